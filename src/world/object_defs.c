/* Defaults of every object definition: the documented values of include/plait/plait.h. */
#include <string.h>

#include <plait/plait.h>

static plait_surface_def default_surface(float thickness)
{
	plait_surface_def surface;
	surface.thickness = thickness;
	surface.friction = 0.1f;
	surface.stickiness = 0.0f;
	surface.bounce = 0.0f;
	surface.collide = true;
	surface.collision_layer = 0;
	return surface;
}

plait_cloth_def plait_default_cloth_def(void)
{
	plait_cloth_def def;
	memset(&def, 0, sizeof def);
	def.density = 0.2f;
	def.stretch_resistance = 20.0f;
	def.compression_resistance = 10.0f;
	def.shear_resistance = 10.0f;
	def.bend_resistance = 0.1f;
	def.rest_length_scale = 1.0f;
	def.drag = 0.05f;
	def.tangential_drag = 0.01f;
	def.lift = 0.05f;
	def.tether_scale = 1.0f;
	def.tether_stiffness = 1.0f;
	def.self_collision_flag = PLAIT_SELF_COLLIDE_FULL_SURFACE;
	def.self_collide_width_scale = 1.0f;
	def.surface = default_surface(0.01f);
	return def;
}

plait_curve_def plait_default_curve_def(void)
{
	plait_curve_def def;
	memset(&def, 0, sizeof def);
	def.mass = 0.01f;
	def.stretch_resistance = 20.0f;
	def.compression_resistance = 10.0f;
	def.bend_resistance = 0.1f;
	def.rest_length_scale = 1.0f;
	def.surface = default_surface(0.01f);
	return def;
}

plait_particles_def plait_default_particles_def(void)
{
	plait_particles_def def;
	memset(&def, 0, sizeof def);
	def.mass = 1.0f;
	def.radius = 0.05f;
	def.surface = default_surface(0.0f);
	def.self_collide = true;
	return def;
}

plait_transform plait_identity_transform(void)
{
	plait_transform t = {{0.0f, 0.0f, 0.0f}, {0.0f, 0.0f, 0.0f}, 1.0f};
	return t;
}

plait_collider_def plait_default_collider_def(void)
{
	plait_collider_def def;
	memset(&def, 0, sizeof def);
	def.shape = PLAIT_SHAPE_PLANE;
	def.normal = (plait_vec3){0.0f, 1.0f, 0.0f};
	def.radius = 0.5f;
	def.b = (plait_vec3){0.0f, 1.0f, 0.0f};
	def.size = (plait_vec3){1.0f, 1.0f, 1.0f};
	def.transform = plait_identity_transform();
	def.surface = default_surface(0.0f);
	return def;
}

/* plait_world_check_intersections: counts crossing cloth triangles with a hierarchy over all of
 * them, built from the current positions. */
#include <math.h>
#include <string.h>

#include "collision/intersect.h"
#include "collision/closest.h"
#include "collision/mesh_shape.h"
#include "core/error.h"
#include "dynamics/contact.h"
#include "world/world.h"

typedef struct check_pass {
	const plait_mesh_shape *shape;
	const plait_sim *sim;
	int triangle;
	int count;
} check_pass;

/* Whether a surface is a colliding mesh or box collider's (its triangles go in the soup). */
static bool collider_surface(const plait_sim *sim, const plait_surface *surface)
{
	const plait_material *m = &sim->materials[surface->material];
	return m->type == PLAIT_OBJECT_COLLIDER && m->collide;
}

/* Whether a triangle of the soup is a collider's (its vertices are the collider's particles). */
static bool collider_triangle(const plait_sim *sim, const int *triangle)
{
	return sim->materials[sim->particles.material[triangle[0]]].type == PLAIT_OBJECT_COLLIDER;
}

static bool share_a_vertex(const int *a, const int *b)
{
	for (int i = 0; i < 3; ++i) {
		for (int j = 0; j < 3; ++j) {
			if (a[i] == b[j]) {
				return true;
			}
		}
	}
	return false;
}

static void visit_pair(int other, void *context)
{
	check_pass *pass = context;
	if (other <= pass->triangle) {
		return; /* each pair once */
	}
	const int *a = pass->shape->triangles[pass->triangle], *b = pass->shape->triangles[other];
	if (share_a_vertex(a, b)) {
		return; /* neighbours touch by construction */
	}
	if (collider_triangle(pass->sim, a) && collider_triangle(pass->sim, b)) {
		return; /* colliders may overlap each other */
	}
	const vec3 *x = pass->shape->positions;
	vec3 t[3] = {x[a[0]], x[a[1]], x[a[2]]}, u[3] = {x[b[0]], x[b[1]], x[b[2]]};
	pass->count += plait_triangles_intersect(t, u);
}

/* Distance from segment a-b to a triangle (zero when it passes through it). */
static float segment_triangle_distance(vec3 a, vec3 b, const vec3 *t)
{
	vec3 n = v3_cross(v3_sub(t[1], t[0]), v3_sub(t[2], t[0]));
	float da = v3_dot(v3_sub(a, t[0]), n), db = v3_dot(v3_sub(b, t[0]), n);
	if ((da <= 0.0f) != (db <= 0.0f)) {
		vec3 crossing = v3_lerp(a, b, da / (da - db));
		int region;
		float w[3];
		vec3 q = plait_closest_point_on_triangle(crossing, t[0], t[1], t[2], &region, w);
		if (v3_length_sq(v3_sub(q, crossing)) <= 1e-12f * v3_length_sq(v3_sub(b, a))) {
			return 0.0f;
		}
	}
	int region;
	float w[3];
	float best = v3_length(v3_sub(plait_closest_point_on_triangle(a, t[0], t[1], t[2], &region, w), a));
	best = plait_minf(best,
	                  v3_length(v3_sub(plait_closest_point_on_triangle(b, t[0], t[1], t[2], &region, w), b)));
	for (int k = 0; k < 3; ++k) {
		float s, u;
		best = plait_minf(best, sqrtf(plait_closest_segments(a, b, t[k], t[(k + 1) % 3], &s, &u)));
	}
	return best;
}

/* Cloth triangles reaching into a sphere or capsule collider by more than the tolerance of
 * plait_count_penetrations (round shapes have no corners or edges of their own to meet cloth:
 * only cloth vertices keep cloth out of them). */
static int triangles_in_round_colliders(const plait_sim *sim, const plait_mesh_shape *soup)
{
	int count = 0;
	for (int k = 0; k < sim->collider_count; ++k) {
		const plait_collider *c = &sim->colliders[k];
		if (!c->collide || (c->shape.type != PLAIT_SHAPE_SPHERE && c->shape.type != PLAIT_SHAPE_CAPSULE)) {
			continue;
		}
		plait_rigid r = plait_rigid_from_transform(c->transform_end);
		for (int t = 0; t < soup->triangle_count; ++t) {
			const int *tri = soup->triangles[t];
			if (collider_triangle(sim, tri)) {
				continue;
			}
			vec3 local[3];
			float radius = 0.0f;
			for (int m = 0; m < 3; ++m) {
				local[m] = plait_rigid_apply_inverse(&r, soup->positions[tri[m]]);
				radius += sim->particles.radius[tri[m]] / 3.0f;
			}
			float distance;
			if (c->shape.type == PLAIT_SHAPE_SPHERE) {
				int region;
				float w[3];
				vec3 q = plait_closest_point_on_triangle(c->shape.center, local[0], local[1], local[2],
				                                         &region, w);
				distance = v3_length(v3_sub(q, c->shape.center));
			} else {
				distance = segment_triangle_distance(c->shape.a, c->shape.b, local);
			}
			float depth = (c->shape.radius - distance) * r.scale;
			count += depth > 1e-4f + 0.01f * radius;
		}
	}
	return count;
}

plait_result plait_world_check_intersections(plait_world_id id, plait_intersection_report *report,
                                             plait_error *error)
{
	plait_world *world = id.world;
	if (world == NULL || report == NULL) {
		return plait_error_set(error, PLAIT_ERROR_INVALID_ARGUMENT, "check needs a world and a report");
	}
	memset(report, 0, sizeof *report);
	report->inside_colliders = plait_count_penetrations(&world->sim);
	/* One soup of every colliding cloth's polygons and every mesh and box collider's triangles,
	 * indexed by particle. */
	const plait_sim *sim = &world->sim;
	int faces = 0, indices = 0, cloth_faces = 0;
	for (int o = 0; o < world->object_count; ++o) {
		const plait_object *object = &world->objects[o];
		if (object->alive && object->type == PLAIT_OBJECT_CLOTH && sim->materials[object->material].collide) {
			faces += object->topology.polygon_count;
			indices += object->topology.polygon_index_count;
		}
	}
	cloth_faces = faces;
	for (int k = 0; k < sim->surface_count; ++k) {
		const plait_surface *surface = &sim->surfaces[k];
		if (collider_surface(sim, surface)) {
			faces += surface->shape->triangle_count;
			indices += 3 * surface->shape->triangle_count;
		}
	}
	if (cloth_faces == 0) {
		return PLAIT_OK;
	}
	const plait_allocator *a = &world->allocator;
	int *sizes = plait_alloc(a, sizeof(int) * (size_t)faces);
	int *soup = plait_alloc(a, sizeof(int) * (size_t)indices);
	int particle_count = world->sim.particles.count;
	vec3 *positions = plait_alloc(a, sizeof(vec3) * (size_t)particle_count);
	if (sizes == NULL || soup == NULL || positions == NULL) {
		plait_free(a, sizes);
		plait_free(a, soup);
		plait_free(a, positions);
		return plait_error_set(error, PLAIT_ERROR_OUT_OF_MEMORY, "out of memory checking intersections");
	}
	int f = 0, k = 0;
	for (int o = 0; o < world->object_count; ++o) {
		const plait_object *object = &world->objects[o];
		if (!object->alive || object->type != PLAIT_OBJECT_CLOTH ||
		    !world->sim.materials[object->material].collide) {
			continue;
		}
		const plait_topology *t = &object->topology;
		for (int p = 0; p < t->polygon_count; ++p) {
			sizes[f++] = t->polygon_sizes[p];
		}
		for (int i = 0; i < t->polygon_index_count; ++i) {
			soup[k++] = object->first_particle + t->polygon_indices[i];
		}
	}
	for (int m = 0; m < sim->surface_count; ++m) {
		const plait_surface *surface = &sim->surfaces[m];
		if (!collider_surface(sim, surface)) {
			continue;
		}
		for (int t = 0; t < surface->shape->triangle_count; ++t) {
			sizes[f++] = 3;
			for (int c = 0; c < 3; ++c) {
				soup[k++] = surface->first + surface->shape->triangles[t][c];
			}
		}
	}
	for (int i = 0; i < particle_count; ++i) {
		positions[i] = world->sim.particles.point[i].x;
	}
	plait_mesh_def mesh = {positions, particle_count, sizes, faces, soup};
	plait_mesh_shape shape;
	plait_result result = plait_mesh_shape_build(&shape, a, &mesh, error);
	plait_free(a, sizes);
	plait_free(a, soup);
	plait_free(a, positions);
	if (result != PLAIT_OK) {
		return result;
	}
	check_pass pass = {&shape, sim, 0, 0};
	for (int t = 0; t < shape.triangle_count; ++t) {
		const int *tri = shape.triangles[t];
		vec3 lower =
		    v3_min(shape.positions[tri[0]], v3_min(shape.positions[tri[1]], shape.positions[tri[2]]));
		vec3 upper =
		    v3_max(shape.positions[tri[0]], v3_max(shape.positions[tri[1]], shape.positions[tri[2]]));
		pass.triangle = t;
		plait_mesh_shape_visit(&shape, lower, upper, true, visit_pair, &pass);
	}
	report->triangle_pairs = pass.count;
	report->triangles_in_colliders = triangles_in_round_colliders(sim, &shape);
	plait_mesh_shape_destroy(&shape, a);
	return PLAIT_OK;
}

/* Analytic checks: each test fails if the physics is wrong. */
#include <criterion/criterion.h>
#include <math.h>
#include <stdlib.h>

#ifndef M_PI
#define M_PI 3.14159265358979323846
#endif

#include "test_support.h"

static plait_world_id make_world(int substeps, float fps)
{
	plait_world_def def = plait_default_world_def();
	def.substeps = substeps;
	def.fps = fps;
	def.air_density = 0.0f;
	plait_error error;
	plait_world_id world = plait_create_world(&def, &error);
	cr_assert(!plait_world_id_is_null(world), "%s", error.message);
	return world;
}

static plait_object_id add_particle(plait_world_id world, plait_vec3 x, plait_vec3 v, float mass,
                                    float radius)
{
	plait_particles_def def = plait_default_particles_def();
	def.positions = &x;
	def.velocities = &v;
	def.count = 1;
	def.mass = mass;
	def.radius = radius;
	plait_error error;
	plait_object_id id = plait_create_particles(world, &def, &error);
	cr_assert(!plait_object_id_is_null(id), "%s", error.message);
	return id;
}

Test(physics, free_fall_matches_the_parabola)
{
	plait_world_id world = make_world(3, 24.0f);
	plait_vec3 x0 = {0.0f, 10.0f, 0.0f}, v0 = {1.0f, 5.0f, -2.0f};
	plait_object_id p = add_particle(world, x0, v0, 1.0f, 0.05f);
	for (int frame = 1; frame <= 48; ++frame) {
		cr_assert(test_step_frames(world, 1));
		plait_vec3 x;
		plait_object_get_positions(p, 0, 1, &x, NULL);
		double t = frame / 24.0;
		double expected_y = 10.0 + 5.0 * t - 0.5 * 9.81 * t * t;
		double expected_x = 1.0 * t, expected_z = -2.0 * t;
		double displacement = fabs(5.0 * t - 0.5 * 9.81 * t * t) + fabs(expected_x) + fabs(expected_z);
		double err = fabs(x.y - expected_y) + fabs(x.x - expected_x) + fabs(x.z - expected_z);
		cr_assert_leq(err, 0.01 * displacement + 1e-5, "frame %d: error %g of displacement %g", frame, err,
		              displacement);
	}
	plait_destroy_world(world);
}

/* A particle on a stiff massless link: period 2 pi sqrt(L / g) at small amplitude. */
Test(physics, pendulum_period)
{
	plait_world_id world = make_world(10, 60.0f);
	float length = 1.0f, amplitude = 0.05f; /* radians */
	plait_vec3 positions[2] = {{0.0f, 0.0f, 0.0f},
	                           {length * sinf(amplitude), -length * cosf(amplitude), 0.0f}};
	plait_curve_def def = plait_default_curve_def();
	def.positions = positions;
	def.vertex_count = 2;
	def.mass = 1.0f;
	def.stretch_resistance = 10000.0f;
	def.compression_resistance = 10000.0f;
	def.bend_resistance = 0.0f;
	def.iterations = 10;
	def.surface.collide = false;
	int pin = 0;
	def.pins = &pin;
	def.pin_count = 1;
	plait_error error;
	plait_object_id curve = plait_create_curve(world, &def, &error);
	cr_assert(!plait_object_id_is_null(curve), "%s", error.message);
	/* Find upward zero crossings of x: the time between the first and the fourth is 3 periods. */
	double crossings[8];
	int found = 0;
	plait_vec3 x[2];
	plait_object_get_positions(curve, 0, 2, x, NULL);
	double previous_x = x[1].x, previous_t = 0.0;
	for (int frame = 1; frame <= 60 * 12 && found < 4; ++frame) {
		cr_assert(test_step_frames(world, 1));
		plait_object_get_positions(curve, 0, 2, x, NULL);
		double t = frame / 60.0;
		if (previous_x < 0.0 && x[1].x >= 0.0) {
			crossings[found++] = previous_t + (t - previous_t) * (-previous_x) / (x[1].x - previous_x);
		}
		previous_x = x[1].x;
		previous_t = t;
	}
	cr_assert_eq(found, 4);
	double period = (crossings[3] - crossings[0]) / 3.0;
	double expected = 2.0 * M_PI * sqrt(length / 9.81);
	cr_assert_leq(fabs(period - expected) / expected, 0.02, "period %g, expected %g", period, expected);
	plait_destroy_world(world);
}

/* Catenary: a chain pinned at both ends hangs as y = a cosh(x / a) + c. */
Test(physics, curve_pinned_at_both_ends_settles_to_a_catenary)
{
	plait_world_id world = make_world(10, 24.0f);
	enum { N = 41 };
	float span = 1.0f, chain_length = 1.4f;
	plait_vec3 positions[N];
	/* Start as a V of the right length so the chain falls into shape. */
	float half = 0.5f * chain_length, drop = sqrtf(half * half - 0.25f * span * span);
	for (int i = 0; i < N; ++i) {
		float s = (float)i / (float)(N - 1);
		float x = -0.5f * span + span * s;
		float y = s <= 0.5f ? -drop * (2.0f * s) : -drop * (2.0f - 2.0f * s);
		positions[i] = (plait_vec3){x, y, 0.0f};
	}
	plait_curve_def def = plait_default_curve_def();
	def.positions = positions;
	def.vertex_count = N;
	def.mass = 0.01f;
	def.stretch_resistance = 10000.0f;
	def.compression_resistance = 0.0f;
	def.bend_resistance = 0.0f;
	def.iterations = 100;
	def.damp = 2.0f;
	def.surface.collide = false;
	int pins[2] = {0, N - 1};
	def.pins = pins;
	def.pin_count = 2;
	plait_error error;
	plait_object_id curve = plait_create_curve(world, &def, &error);
	cr_assert(!plait_object_id_is_null(curve), "%s", error.message);
	cr_assert(test_step_frames(world, 24 * 10));
	plait_vec3 x[N];
	plait_object_get_positions(curve, 0, N, x, NULL);
	/* Solve 2 a sinh(span / (2 a)) = length for a by bisection. */
	double lo = 0.01, hi = 100.0;
	for (int it = 0; it < 200; ++it) {
		double a = 0.5 * (lo + hi);
		if (2.0 * a * sinh(span / (2.0 * a)) > chain_length) {
			lo = a;
		} else {
			hi = a;
		}
	}
	double a = 0.5 * (lo + hi);
	double worst = 0.0;
	for (int i = 0; i < N; ++i) {
		double expected = a * cosh(x[i].x / a) - a * cosh(span / (2.0 * a));
		worst = fmax(worst, fabs(x[i].y - expected));
	}
	cr_assert_leq(worst, 0.02 * span, "max deviation %g of span %g", worst, (double)span);
	plait_destroy_world(world);
}

/* A flat rigid sheet of mass m and area A falling face-down reaches v = m g / (drag rho A). */
Test(physics, terminal_speed_contract_for_drag)
{
	plait_world_def wdef = plait_default_world_def();
	wdef.air_density = 1.2f;
	plait_error error;
	plait_world_id world = plait_create_world(&wdef, &error);
	test_grid grid = test_grid_make(4, 4, 1.0f, 1.0f);
	for (int i = 0; i < grid.vertex_count; ++i) {
		grid.positions[i].y = 100.0f;
	}
	plait_cloth_def def = plait_default_cloth_def();
	def.mesh = test_grid_mesh(&grid);
	def.density = 0.1f;
	def.drag = 0.4f;
	def.lift = 0.0f;
	def.tangential_drag = 0.0f;
	def.stretch_resistance = 1000.0f;
	def.iterations = 20;
	plait_object_id cloth = plait_create_cloth(world, &def, &error);
	cr_assert(!plait_object_id_is_null(cloth), "%s", error.message);
	cr_assert(test_step_frames(world, 24 * 5));
	plait_vec3 v[25];
	plait_object_get_velocities(cloth, 0, 25, v, NULL);
	double mean = 0.0;
	for (int i = 0; i < 25; ++i) {
		mean += v[i].y / 25.0;
	}
	double mass = 0.1 * 1.0, area = 1.0;
	double expected = mass * 9.81 / (0.4 * 1.2 * area);
	cr_assert_leq(fabs(-mean - expected) / expected, 0.05, "terminal speed %g, expected %g", -mean, expected);
	test_grid_free(&grid);
	plait_destroy_world(world);
}

static plait_object_id add_tilted_plane(plait_world_id world, float degrees, float friction)
{
	plait_collider_def def = plait_default_collider_def();
	def.shape = PLAIT_SHAPE_PLANE;
	def.point = (plait_vec3){0.0f, 0.0f, 0.0f};
	float theta = degrees * (float)M_PI / 180.0f;
	def.normal = (plait_vec3){-sinf(theta), cosf(theta), 0.0f}; /* downhill is -x */
	def.surface.friction = friction;
	plait_error error;
	plait_object_id id = plait_create_collider(world, &def, &error);
	cr_assert(!plait_object_id_is_null(id), "%s", error.message);
	return id;
}

/* Friction of a contact is the average of both surfaces; both are mu here. */
static double slide_acceleration(float degrees, float mu, double *moved)
{
	plait_world_id world = make_world(3, 24.0f);
	add_tilted_plane(world, degrees, mu);
	float theta = degrees * (float)M_PI / 180.0f;
	float radius = 0.05f;
	plait_vec3 n = {-sinf(theta), cosf(theta), 0.0f};
	plait_vec3 x0 = {n.x * radius, n.y * radius, 0.0f};
	plait_particles_def def = plait_default_particles_def();
	def.positions = &x0;
	def.count = 1;
	def.radius = radius;
	def.surface.friction = mu;
	plait_object_id p = plait_create_particles(world, &def, NULL);
	/* Settle one frame, then measure along the slope over two seconds. */
	test_step_frames(world, 1);
	plait_vec3 start, end;
	plait_object_get_positions(p, 0, 1, &start, NULL);
	plait_vec3 v_start;
	plait_object_get_velocities(p, 0, 1, &v_start, NULL);
	test_step_frames(world, 48);
	plait_object_get_positions(p, 0, 1, &end, NULL);
	plait_vec3 downhill = {-cosf(theta), -sinf(theta), 0.0f};
	double s = (end.x - start.x) * downhill.x + (end.y - start.y) * downhill.y;
	double v0 = v_start.x * downhill.x + v_start.y * downhill.y;
	*moved = s;
	plait_destroy_world(world);
	double t = 2.0;
	return 2.0 * (s - v0 * t) / (t * t);
}

Test(physics, particle_on_tilted_plane_sticks_below_the_friction_angle)
{
	double moved;
	slide_acceleration(20.0f, 0.5f, &moved); /* tan 20 = 0.36 < 0.5 */
	cr_assert_leq(fabs(moved), 1e-3, "moved %g m", moved);
	slide_acceleration(30.0f, 0.6f, &moved); /* tan 30 = 0.577 < 0.6 */
	cr_assert_leq(fabs(moved), 1e-3, "moved %g m", moved);
}

Test(physics, particle_on_tilted_plane_slides_with_the_coulomb_acceleration)
{
	float cases[][2] = {{30.0f, 0.3f}, {45.0f, 0.5f}, {20.0f, 0.1f}};
	for (int k = 0; k < 3; ++k) {
		double moved;
		double a = slide_acceleration(cases[k][0], cases[k][1], &moved);
		double theta = cases[k][0] * M_PI / 180.0;
		double expected = 9.81 * (sin(theta) - cases[k][1] * cos(theta));
		cr_assert_leq(fabs(a - expected) / expected, 0.10, "theta %g mu %g: a = %g, expected %g",
		              (double)cases[k][0], (double)cases[k][1], a, expected);
	}
}

static void head_on(float bounce, double *momentum_error, double *v1_after, double *v2_after)
{
	plait_world_def wdef = plait_default_world_def();
	wdef.gravity = (plait_vec3){0.0f, 0.0f, 0.0f};
	wdef.air_density = 0.0f;
	plait_world_id world = plait_create_world(&wdef, NULL);
	float m1 = 1.0f, m2 = 3.0f;
	plait_vec3 x1 = {-0.5f, 0.0f, 0.0f}, v1 = {2.0f, 0.0f, 0.0f};
	plait_vec3 x2 = {0.5f, 0.0f, 0.0f}, v2 = {-1.0f, 0.0f, 0.0f};
	plait_particles_def def = plait_default_particles_def();
	def.count = 1;
	def.radius = 0.1f;
	def.surface.bounce = bounce;
	def.surface.friction = 0.0f;
	def.positions = &x1;
	def.velocities = &v1;
	def.mass = m1;
	plait_object_id a = plait_create_particles(world, &def, NULL);
	def.positions = &x2;
	def.velocities = &v2;
	def.mass = m2;
	plait_object_id b = plait_create_particles(world, &def, NULL);
	double before = m1 * 2.0 + m2 * -1.0;
	test_step_frames(world, 24);
	plait_vec3 va, vb;
	plait_object_get_velocities(a, 0, 1, &va, NULL);
	plait_object_get_velocities(b, 0, 1, &vb, NULL);
	double after = m1 * va.x + m2 * vb.x;
	double scale = fabs(m1 * 2.0) + fabs(m2 * 1.0);
	*momentum_error = fabs(after - before) / scale;
	*v1_after = va.x;
	*v2_after = vb.x;
	plait_destroy_world(world);
}

Test(physics, head_on_collision_conserves_momentum_and_bounces_as_asked)
{
	double error, v1, v2;
	/* Elastic: u1 = 2, u2 = -1, m1 = 1, m2 = 3: v1 = -2.5, v2 = 0.5. */
	head_on(1.0f, &error, &v1, &v2);
	cr_assert_leq(error, 1e-5, "momentum error %g", error);
	cr_assert_float_eq(v1, -2.5, 0.025, "v1 = %g", v1);
	cr_assert_float_eq(v2, 0.5, 0.025, "v2 = %g", v2);
	/* Inelastic: both move at the centre-of-mass velocity (2 - 3) / 4 = -0.25. */
	head_on(0.0f, &error, &v1, &v2);
	cr_assert_leq(error, 1e-5, "momentum error %g", error);
	cr_assert_float_eq(v1, -0.25, 0.0025, "v1 = %g", v1);
	cr_assert_float_eq(v2, -0.25, 0.0025, "v2 = %g", v2);
}

/* A particle within the thickness beside a box's side face, driven 10 cm into the box within one
 * substep, ends nearer the top face than the side it came by: it goes back out of the side it
 * began by, not over the edge onto the top (a box's nearest face jumps: contact.c,
 * collide_particle). Out of the top, a cloth vertex in the box arm's elbow ended across the
 * forearm from the rest of its cloth, its triangles wrapped through the bar. */
Test(physics, a_particle_driven_deep_into_a_box_goes_back_out_of_the_face_it_came_by)
{
	plait_world_id world = make_world(4, 60.0f);
	plait_collider_def box = plait_default_collider_def();
	box.shape = PLAIT_SHAPE_BOX;
	box.size = (plait_vec3){1.0f, 0.04f, 1.0f};
	plait_error error;
	cr_assert(!plait_object_id_is_null(plait_create_collider(world, &box, &error)), "%s", error.message);
	const float radius = 0.005f;
	/* 24 m/s is 10 cm in a substep of 1/240 s. */
	plait_object_id particle = add_particle(world, (plait_vec3){-0.5f - 0.98f * radius, 0.015f, 0.0f},
	                                        (plait_vec3){24.0f, 0.0f, 0.0f}, 1.0f, radius);
	cr_assert(test_step_frames(world, 1));
	plait_vec3 x;
	cr_assert_eq(plait_object_get_positions(particle, 0, 1, &x, NULL), PLAIT_OK);
	cr_expect_lt(x.x, -0.5f, "the particle is at x = %g m, y = %g m: not back beside the side face",
	             (double)x.x, (double)x.y);
	cr_expect_lt(x.y, 0.02f, "the particle went over the edge onto the top, to y = %g m", (double)x.y);
	plait_destroy_world(world);
}

/* A particle resting against the underside of a 1 mm box, a rounding inside the thickness, shot
 * up through it within one substep: it began outside the box itself, so it stays on the side
 * it began on (the trapped rule pushes a particle out along the normal where it ends, which
 * past a thin box is the far side). */
Test(physics, a_particle_within_the_thickness_under_a_thin_box_does_not_pass_through_it)
{
	plait_world_id world = make_world(4, 60.0f);
	plait_collider_def box = plait_default_collider_def();
	box.shape = PLAIT_SHAPE_BOX;
	box.size = (plait_vec3){0.6f, 0.001f, 0.6f};
	plait_error error;
	cr_assert(!plait_object_id_is_null(plait_create_collider(world, &box, &error)), "%s", error.message);
	const float radius = 0.01f;
	float starts[2] = {-0.0005f - 0.999f * radius, -0.0005f - 1.001f * radius}; /* inside, outside */
	for (int k = 0; k < 2; ++k) {
		plait_object_id p = add_particle(world, (plait_vec3){0.1f * (float)k, starts[k], 0.0f},
		                                 (plait_vec3){0.0f, 20.0f, 0.0f}, 1.0f, radius);
		(void)p;
	}
	for (int frame = 1; frame <= 30; ++frame) {
		cr_assert(test_step_frames(world, 1));
		for (int k = 0; k < 2; ++k) {
			plait_vec3 x;
			cr_assert_eq(plait_object_get_positions(plait_world_get_object(world, k + 1), 0, 1, &x, NULL),
			             PLAIT_OK);
			cr_assert_lt(x.y, -0.0005f, "frame %d: the particle that began %s the thickness is at y = %g m",
			             frame, k == 0 ? "inside" : "outside", (double)x.y);
		}
	}
	plait_destroy_world(world);
}

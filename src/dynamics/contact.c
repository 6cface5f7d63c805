#include "dynamics/contact.h"

#include <string.h>

#include "collision/ccd.h"
#include "collision/closest.h"
#include "collision/mesh_shape.h"
#include "collision/moving_triangle.h"
#include "collision/particle_hash.h"
#include "collision/static_sweep.h"
#include "dynamics/contact_kernel.h"
#include "dynamics/mesh_contact.h"

static plait_transform lerp_transform(plait_transform a, plait_transform b, float t)
{
	plait_transform r;
	r.translate = v3_lerp(a.translate, b.translate, t);
	r.rotate_deg = v3_lerp(a.rotate_deg, b.rotate_deg, t);
	r.scale = a.scale + (b.scale - a.scale) * t;
	return r;
}

/* Room for a closed mesh collider's clearances (sim.h), unknown for new particles; on failure
 * the collider goes without. */
static void reserve_clearances(plait_sim *sim, plait_collider *c)
{
	int count = sim->particles.count;
	bool wanted = c->shape.type == PLAIT_SHAPE_MESH && c->shape.mesh->closed;
	if (!wanted || c->clear_capacity >= count) {
		return;
	}
	const plait_allocator *a = &sim->allocator;
	int capacity = count + count / 2;
	vec3 *at = plait_alloc(a, sizeof *at * (size_t)capacity);
	float *clearance = plait_alloc(a, sizeof *clearance * (size_t)capacity);
	double *drift = plait_alloc(a, sizeof *drift * (size_t)capacity);
	bool made = at != NULL && clearance != NULL && drift != NULL;
	if (made && c->clear_capacity > 0) {
		memcpy(at, c->clear_at, sizeof *at * (size_t)c->clear_capacity);
		memcpy(clearance, c->clearance, sizeof *clearance * (size_t)c->clear_capacity);
		memcpy(drift, c->clear_drift, sizeof *drift * (size_t)c->clear_capacity);
	}
	int known = made ? c->clear_capacity : 0;
	plait_free(a, c->clear_at);
	plait_free(a, c->clearance);
	plait_free(a, c->clear_drift);
	c->clear_at = NULL;
	c->clearance = NULL;
	c->clear_drift = NULL;
	c->clear_capacity = 0;
	if (!made) {
		plait_free(a, at);
		plait_free(a, clearance);
		plait_free(a, drift);
		return;
	}
	for (int i = known; i < capacity; ++i) {
		clearance[i] = -INFINITY;
		at[i] = v3(0.0f, 0.0f, 0.0f);
		drift[i] = 0.0;
	}
	c->clear_at = at;
	c->clearance = clearance;
	c->clear_drift = drift;
	c->clear_capacity = capacity;
}

void plait_collider_forget_clearances(plait_collider *c)
{
	for (int i = 0; i < c->clear_capacity; ++i) {
		c->clearance[i] = -INFINITY;
	}
}

void plait_colliders_begin_substep(plait_sim *sim, float t0, float t1)
{
	for (int k = 0; k < sim->collider_count; ++k) {
		plait_collider *c = &sim->colliders[k];
		reserve_clearances(sim, c);
		c->rigid_start = plait_rigid_from_transform(lerp_transform(c->transform_start, c->transform_end, t0));
		c->rigid_end = plait_rigid_from_transform(lerp_transform(c->transform_start, c->transform_end, t1));
		if (c->mesh_end != NULL) {
			plait_mesh_shape_deform(c->shape.mesh, c->mesh_start, c->mesh_end, t0, t1);
			c->drift += (double)c->shape.mesh->largest_move;
		}
		/* Its vertices (particles) go where it is at the substep's end; they start from
		 * where the last substep left them. */
		plait_particles *p = &sim->particles;
		for (int v = 0; v < c->count; ++v) {
			vec3 local = c->shape.type == PLAIT_SHAPE_BOX ? plait_shape_box_corner(&c->shape, v)
			                                              : c->shape.mesh->positions[v];
			vec3 x = plait_rigid_apply(&c->rigid_end, local);
			p->pin_start[c->first + v] = x;
			p->pin_end[c->first + v] = x;
		}
	}
}

float plait_combined_friction(float a, float b)
{
	float friction = 0.5f * (a + b);
	return friction > 1.0f ? 1.0f : friction;
}

/* Coulomb friction on a contact: the tangential part of the substep's relative motion is
 * removed entirely while it is within `limit` (friction times the normal push: static), and by
 * `limit` otherwise (sliding). Returns the move to add. */
static vec3 friction_correction(vec3 motion, vec3 normal, float limit, float *rubbed)
{
	vec3 tangential = v3_mul_add(motion, -v3_dot(motion, normal), normal);
	float tangential_length = v3_length(tangential);
	if (!(tangential_length > 0.0f) || !(limit > 0.0f)) {
		return v3(0.0f, 0.0f, 0.0f);
	}
	float removed = tangential_length < limit ? 1.0f : limit / tangential_length;
	*rubbed += removed * tangential_length;
	return v3_scale(tangential, -removed);
}

/* The move that resolves a contact: out along the normal by depth, plus friction up to friction
 * times all the substep's pushes (`pushed` before this one) less what it took (*rubbed). */
static vec3 contact_correction(vec3 normal, float depth, vec3 motion, float friction, float pushed,
                               float *rubbed)
{
	float limit = friction * (depth + pushed) - *rubbed;
	return v3_add(v3_scale(normal, depth), friction_correction(motion, normal, limit, rubbed));
}

/* How far past its contact distance a particle pushed earlier in the substep still rests on a
 * collider, as a share of that distance: the constraint iterations after a push lift a resting
 * particle a hair off (about a micrometre under a 1 cm contact distance) while moving it along. */
#define RESTING_SLACK 0.05f

/* Whether particles of materials a and b collide as a pair. Vertices of one cloth or curve do
 * not collide with each other here: self-collision of meshes works on their triangles. */
static bool materials_pair_up(const plait_material *a, const plait_material *b)
{
	if (!a->collide || !b->collide || a->type == PLAIT_OBJECT_CLOTH || b->type == PLAIT_OBJECT_CLOTH) {
		return false;
	}
	if (a->type == PLAIT_OBJECT_CURVE && b->type == PLAIT_OBJECT_CURVE) {
		return false; /* curves meet through their segments (mesh_contact.c) */
	}
	if (a->object != b->object) {
		return true;
	}
	return a->type == PLAIT_OBJECT_PARTICLES && a->self_collide;
}

bool plait_contacts_begin_substep(plait_sim *sim)
{
	plait_particles *p = &sim->particles;
	sim->pair_contact_count = 0;
	if (!plait_mesh_contacts_prepare(sim, &sim->mesh_contacts_active)) {
		return false;
	}
	if (!plait_mesh_contacts_begin_substep(sim)) {
		return false;
	}

	/* Particle pairs are needed when two colliding curves or particle objects hold particles, or
	 * a particle object collides with itself. (Cloths meet everything through their triangles:
	 * mesh_contact.c.) */
	int colliding_objects = 0, last_object = -1;
	bool self_pairs = false;
	for (int m = 0; m < sim->material_count; ++m) {
		const plait_material *mat = &sim->materials[m];
		if (!mat->collide || mat->type == PLAIT_OBJECT_COLLIDER || mat->type == PLAIT_OBJECT_CLOTH) {
			continue;
		}
		if (mat->object != last_object) {
			++colliding_objects;
			last_object = mat->object;
		}
		self_pairs = self_pairs || (mat->type == PLAIT_OBJECT_PARTICLES && mat->self_collide);
	}
	sim->particle_pairs_active = colliding_objects >= 2 || self_pairs;
	if (!sim->particle_pairs_active) {
		return true;
	}
	if (sim->hash == NULL) {
		sim->hash = plait_alloc_zero(&sim->allocator, 1, sizeof(plait_particle_hash));
		if (sim->hash == NULL) {
			return false;
		}
	}
	if (sim->pair_list_capacity < p->count) {
		plait_free(&sim->allocator, sim->pair_list);
		plait_free(&sim->allocator, sim->pair_lower);
		plait_free(&sim->allocator, sim->pair_upper);
		sim->pair_list = plait_alloc_zero(&sim->allocator, (size_t)p->count, sizeof(int));
		sim->pair_lower = plait_alloc_zero(&sim->allocator, (size_t)p->count, sizeof(vec3));
		sim->pair_upper = plait_alloc_zero(&sim->allocator, (size_t)p->count, sizeof(vec3));
		bool ok = sim->pair_list != NULL && sim->pair_lower != NULL && sim->pair_upper != NULL;
		sim->pair_list_capacity = ok ? p->count : 0;
		if (!ok) {
			return false;
		}
	}
	return true;
}

/* Collider pushes on particle i earlier in this substep, and what their friction took off
 * (sim.h, contact_push and contact_rub). */
static inline float pushed_before(const plait_particles *p, int i)
{
	return (p->flags[i] & PLAIT_PARTICLE_CONTACT) ? p->contact_push[i] : 0.0f;
}

static inline float rubbed_before(const plait_particles *p, int i)
{
	return (p->flags[i] & PLAIT_PARTICLE_CONTACT) ? p->contact_rub[i] : 0.0f;
}

/* Particle i, pushed earlier in the substep and resting on a collider (normal `normal` at its end
 * p1, shape space) without pressing into it now: friction takes what is left of its limit off the
 * substep's tangential motion. Without it the iteration that ends a substep finds a resting
 * particle pushed out already by contact passes and rubs nothing. Returns its end.
 *
 * It counts as touching for the next contact passes (PLAIT_PARTICLE_TOUCHED). Left out, a
 * particle that the constraints had lifted a few micrometres off the surface was not pushed by
 * them in the next substep while its neighbours were: the constraints then carried part of its
 * weight, its pushes (friction's limit) fell short of gravity's share, and a fine sheet on a
 * slope below its friction angle crept down it (30 degrees, friction 0.6, 24 x 24: 16 mm in
 * 2 s; none since, as with contact passes off). */
static vec3 rub_resting(plait_particles *p, int i, vec3 p0, vec3 p1, vec3 normal, float friction)
{
	float rubbed = p->contact_rub[i];
	vec3 moved = v3_add(
	    p1, friction_correction(v3_sub(p1, p0), normal, friction * p->contact_push[i] - rubbed, &rubbed));
	p->contact_rub[i] = rubbed;
	p->flags[i] |= PLAIT_PARTICLE_TOUCHED;
	return moved;
}

/* A collider contact of particle i; its sums of pushes and rubs over the substep become `pushed`
 * and `rubbed`. */
static void record_collider_contact(plait_particles *p, int i, vec3 normal, vec3 surface_velocity,
                                    float bounce, float stickiness, float pushed, float rubbed)
{
	p->contact_push[i] = pushed;
	p->contact_rub[i] = rubbed;
	p->flags[i] |= PLAIT_PARTICLE_CONTACT | PLAIT_PARTICLE_TOUCHED;
	p->contact_normal[i] = normal;
	p->contact_velocity[i] = surface_velocity;
	p->contact_bounce[i] = bounce;
	p->contact_stickiness[i] = stickiness;
}

/* What a particle's pass over a mesh collider gathers, triangle by triangle. */
typedef struct mesh_pass {
	const plait_mesh_shape *mesh;
	const vec3 *start; /* vertices at the substep's start: the mesh's own positions when rigid */
	bool deforming;
	vec3 p0, p1;
	float radius;
	float first_toi;
	int first_triangle;
	float total_depth, deepest;
	vec3 deepest_normal;
	vec3 deepest_motion; /* how far the touched point of the surface moved over the substep */
	bool moved;
	/* A particle pushed earlier in the substep is looked for within rest_radius (its radius and
	 * RESTING_SLACK; the radius otherwise): the nearest surface point it rests on without pressing
	 * in, where friction still acts (rub_resting). */
	float rest_radius, rest_distance;
	vec3 rest_normal, rest_motion;
} mesh_pass;

static vec3 barycentric(const vec3 *positions, const int *tri, const float w[3])
{
	return v3_add(v3_add(v3_scale(positions[tri[0]], w[0]), v3_scale(positions[tri[1]], w[1])),
	              v3_scale(positions[tri[2]], w[2]));
}

static vec3 triangle_normal(vec3 a, vec3 b, vec3 c)
{
	return v3_normalize(v3_cross(v3_sub(b, a), v3_sub(c, a)));
}

/* Deforming meshes: whether a triangle needs the continuous test (see collision/moving_triangle.h).
 * A particle touching it at the start has its contact at t = 0. */
static bool sweep_needed(mesh_pass *pass, int t)
{
	const int *tri = pass->mesh->triangles[t];
	const vec3 *end = pass->mesh->positions;
	vec3 start_corners[3] = {pass->start[tri[0]], pass->start[tri[1]], pass->start[tri[2]]};
	vec3 end_corners[3] = {end[tri[0]], end[tri[1]], end[tri[2]]};
	if (pass->first_toi <= 0.0f ||
	    !plait_moving_triangle_may_touch(pass->p0, pass->p1, start_corners, end_corners, pass->radius)) {
		return false;
	}
	if (plait_moving_triangle_touching_at_start(pass->p0, start_corners, pass->radius)) {
		pass->first_toi = 0.0f;
		pass->first_triangle = t;
		return false;
	}
	return true;
}

/* The earliest time the path comes within the radius of a triangle (continuous test; the
 * triangle's corners move too when the mesh deforms). */
static void visit_sweep(int t, void *context)
{
	mesh_pass *pass = context;
	const int *tri = pass->mesh->triangles[t];
	if (!pass->deforming) {
		/* A rigid mesh stands still in its own space: the cheaper static sweep. */
		float toi;
		const vec3 *x = pass->mesh->positions;
		if (plait_point_path_reaches_triangle(pass->p0, pass->p1, x[tri[0]], x[tri[1]], x[tri[2]],
		                                      pass->radius, &toi) &&
		    toi < pass->first_toi) {
			pass->first_toi = toi;
			pass->first_triangle = t;
		}
		return;
	}
	if (!sweep_needed(pass, t)) {
		return;
	}
	plait_ccd_motion_float m;
	vec3 points[4] = {pass->p0, pass->start[tri[0]], pass->start[tri[1]], pass->start[tri[2]]};
	for (int q = 0; q < 4; ++q) {
		vec3 end = q == 0 ? pass->p1 : pass->mesh->positions[tri[q - 1]];
		m.start[q][0] = points[q].x;
		m.start[q][1] = points[q].y;
		m.start[q][2] = points[q].z;
		m.end[q][0] = end.x;
		m.end[q][1] = end.y;
		m.end[q][2] = end.z;
	}
	float toi;
	float limit = pass->first_toi < 1.0f ? pass->first_toi : 1.0f;
	if (plait_ccd_vertex_face_float(&m, pass->radius, 1e-4f, limit, &toi) && toi < pass->first_toi) {
		pass->first_toi = toi;
		pass->first_triangle = t;
	}
}

static void push_out(mesh_pass *pass, vec3 n, float depth, vec3 surface_motion)
{
	pass->p1 = v3_mul_add(pass->p1, depth, n);
	pass->total_depth += depth;
	if (depth > pass->deepest) {
		pass->deepest = depth;
		pass->deepest_normal = n;
		pass->deepest_motion = surface_motion;
	}
	pass->moved = true;
}

/* Which side of a triangle the path came from: that of p0 against the same surface point at the
 * substep's start (q, face: the point and normal of a rigid mesh, which stands still). Sets
 * *motion to how far that point moved over the substep. */
static vec3 side_normal(const mesh_pass *pass, int t, vec3 q, vec3 face, const float w[3], vec3 *motion)
{
	*motion = v3(0.0f, 0.0f, 0.0f);
	if (pass->deforming) {
		const int *tri = pass->mesh->triangles[t];
		vec3 q_start = barycentric(pass->start, tri, w);
		vec3 face_start = triangle_normal(pass->start[tri[0]], pass->start[tri[1]], pass->start[tri[2]]);
		*motion = v3_sub(q, q_start);
		q = q_start;
		face = v3_length_sq(face_start) > 0.0f ? face_start : face;
	}
	if (pass->mesh->closed) {
		return v3_scale(face, pass->mesh->outward); /* a closed mesh is only ever left outward */
	}
	return v3_dot(v3_sub(pass->p0, q), face) >= 0.0f ? face : v3_neg(face);
}

/* Push the end out of a triangle within the radius, on the side the path came from when the
 * nearest point is inside the face (a thin sheet has two sides). */
static void visit_proximity(int t, void *context)
{
	mesh_pass *pass = context;
	const plait_mesh_shape *mesh = pass->mesh;
	const int *tri = mesh->triangles[t];
	int region;
	float w[3];
	vec3 q = plait_closest_point_on_triangle(pass->p1, mesh->positions[tri[0]], mesh->positions[tri[1]],
	                                         mesh->positions[tri[2]], &region, w);
	vec3 face = mesh->normals[t];
	vec3 n, motion;
	float distance;
	if (region == 0 && v3_length_sq(face) > 0.0f) {
		n = side_normal(pass, t, q, face, w, &motion);
		distance = v3_dot(v3_sub(pass->p1, q), n);
	} else {
		vec3 d = v3_sub(pass->p1, q);
		distance = v3_length(d);
		if (distance >= pass->rest_radius) {
			return;
		}
		vec3 side = side_normal(pass, t, q, face, w, &motion);
		n = distance > 1e-6f * pass->radius ? v3_scale(d, 1.0f / distance) : side;
	}
	if (pass->radius - distance > 0.0f) {
		push_out(pass, n, pass->radius - distance, motion);
	} else if (distance < pass->rest_radius && distance < pass->rest_distance) {
		pass->rest_distance = distance;
		pass->rest_normal = n;
		pass->rest_motion = motion;
	}
}

/* One particle against a mesh collider, in the collider's space (where a rigid mesh stands
 * still and a deforming one moves each vertex on a straight line over the substep). A path
 * shorter than the contact radius, less the longest vertex move, cannot pass through a triangle
 * without ending within the radius of it, so a proximity test at the end suffices; a longer one
 * is swept with the continuous vertex-triangle test (collision/ccd.h), which never misses a
 * contact. Every candidate triangle is visited, however many the path overlaps. Returns true
 * when the particle was moved; *p1 is updated in shape space and *surface_motion receives how
 * far the touched surface point moved over the substep (zero for a rigid mesh). */
static bool collide_point_with_mesh(const plait_mesh_shape *mesh, vec3 p0, vec3 *p1, float radius,
                                    float friction, float *pushed, float *rubbed, bool thorough, bool rests,
                                    bool *rested, vec3 *contact_normal, vec3 *surface_motion,
                                    vec3 *measured_at, float *measured)
{
	*rested = false;
	float rest_radius = rests ? radius * (1.0f + RESTING_SLACK) : radius;
	vec3 grow = {radius, radius, radius}, rest_grow = {rest_radius, rest_radius, rest_radius};
	vec3 lower = v3_sub(v3_min(p0, *p1), rest_grow), upper = v3_add(v3_max(p0, *p1), rest_grow);
	bool deforming = mesh->start_positions != NULL;
	mesh_pass pass = {.mesh = mesh,
	                  .start = deforming ? mesh->start_positions : mesh->positions,
	                  .deforming = deforming,
	                  .p0 = p0,
	                  .p1 = *p1,
	                  .radius = radius,
	                  .first_toi = 2.0f,
	                  .first_triangle = -1,
	                  .rest_radius = rest_radius,
	                  .rest_distance = INFINITY};
	if (v3_length(v3_sub(*p1, p0)) + mesh->largest_move >= radius) {
		/* Fast: the earliest contact along the path, then keep the end on the contact's side. */
		plait_mesh_shape_visit(mesh, lower, upper, true, visit_sweep, &pass);
		if (pass.first_triangle >= 0) {
			int t = pass.first_triangle;
			const int *tri = mesh->triangles[t];
			float toi = pass.first_toi;
			vec3 at = v3_lerp(p0, *p1, toi);
			/* The triangle where it was at the time of contact (for a rigid mesh, where it is). */
			vec3 a = mesh->positions[tri[0]], b = mesh->positions[tri[1]], c = mesh->positions[tri[2]];
			if (deforming) {
				a = v3_lerp(pass.start[tri[0]], a, toi);
				b = v3_lerp(pass.start[tri[1]], b, toi);
				c = v3_lerp(pass.start[tri[2]], c, toi);
			}
			int region;
			float w[3];
			vec3 q = plait_closest_point_on_triangle(at, a, b, c, &region, w);
			vec3 n = v3_sub(at, q);
			float length = v3_length(n);
			/* The touched point moves on with the surface to the end of the substep. */
			vec3 q_end = deforming ? barycentric(mesh->positions, tri, w) : q;
			vec3 motion;
			vec3 side = side_normal(&pass, t, q_end, mesh->normals[t], w, &motion);
			n = length > 1e-6f * radius ? v3_scale(n, 1.0f / length) : side;
			float depth = radius - v3_dot(v3_sub(pass.p1, q_end), n);
			if (depth > 0.0f) {
				push_out(&pass, n, depth, motion);
			}
		}
	}
	if (mesh->closed) {
		/* Trapped check (seed 000 §4.4): whatever side the particle came from, it must end
		 * outside a closed mesh, by the radius. The signed distance settles inside and
		 * outside near edges and corners too. A particle with no triangle's box within its
		 * radius is not touching; it could only be deep inside, which a thorough pass (the
		 * first substep of each frame) looks for. The distance comes first: ending outside,
		 * the particle is pushed only within the radius, where some triangle's box is too, so
		 * the boxes are searched only for one that ends inside. */
		vec3 normal;
		float outside = mesh->outward * plait_mesh_shape_distance(mesh, pass.p1, &normal);
		bool near = pass.moved || thorough || outside >= 0.0f ||
		            plait_mesh_shape_any(mesh, v3_sub(pass.p1, grow), v3_add(pass.p1, grow));
		if (near) {
			*measured_at = pass.p1;
			*measured = outside;
			if (outside < radius) {
				push_out(&pass, v3_scale(normal, mesh->outward), radius - outside, v3(0.0f, 0.0f, 0.0f));
			} else if (outside < rest_radius) {
				pass.rest_distance = outside;
				pass.rest_normal = v3_scale(normal, mesh->outward);
				pass.rest_motion = v3(0.0f, 0.0f, 0.0f);
			}
		}
	} else {
		plait_mesh_shape_visit(mesh, lower, upper, true, visit_proximity, &pass);
	}
	if (!pass.moved) {
		if (pass.rest_distance < rest_radius) {
			/* Resting, as rub_resting: what is left of friction's limit, on the motion relative
			 * to the surface it rests on. Without it a contact pass's push left nothing for the
			 * collision iteration to rub, and cloth slid down a sloped mesh as if without friction
			 * (30 degrees, friction 0.6: 4 m in 2 s). */
			vec3 relative = v3_sub(v3_sub(pass.p1, p0), pass.rest_motion);
			*p1 = v3_add(pass.p1, friction_correction(relative, pass.rest_normal,
			                                          friction * *pushed - *rubbed, rubbed));
			*rested = true;
		}
		return false;
	}
	/* Friction once, against the deepest contact, on the whole normal push, and on the motion
	 * relative to the touched surface: a moving surface carries what rests on it. */
	vec3 relative = v3_sub(v3_sub(pass.p1, p0), pass.deepest_motion);
	float limit = friction * (pass.total_depth + *pushed) - *rubbed;
	*p1 = v3_add(pass.p1, friction_correction(relative, pass.deepest_normal, limit, rubbed));
	*pushed += pass.total_depth;
	*contact_normal = pass.deepest_normal;
	*surface_motion = pass.deepest_motion;
	return true;
}

/* One collider against a range of particles: each particle on its own, so ranges run on
 * any worker with the same result. */
typedef plait_collider_job collider_job;

/* Spheres, the commonest collider, a batch of particles at a time: the arithmetic runs lane by
 * lane over arrays with selects instead of branches, which the compiler turns into vector
 * code, and the contacts are recorded afterwards. It is the general path's arithmetic, operation
 * for operation (sweep and distance in shape.h, contact_correction above), so the two agree to
 * the bit. */
enum { SPHERE_BATCH = 64 };

/* Three coordinates of a lane array, one array each, so that lanes are contiguous. */
typedef struct lanes3 {
	float x[SPHERE_BATCH], y[SPHERE_BATCH], z[SPHERE_BATCH];
} lanes3;

typedef struct sphere_batch {
	int particle[SPHERE_BATCH];
	lanes3 p0, p1; /* the substep's path, shape space */
	float radius[SPHERE_BATCH], friction[SPHERE_BATCH];
	float pushed[SPHERE_BATCH], rubbed[SPHERE_BATCH], rub[SPHERE_BATCH];
	/* Results: whether the lane touches, how deep (no correction when <= 0), the contact
	 * normal and surface point, and the particle's new position (shape space). */
	float touch[SPHERE_BATCH]; /* 1 or 0 */
	float depth[SPHERE_BATCH];
	lanes3 normal, surface, moved;
} sphere_batch;

static inline vec3 lane_get(const lanes3 *lanes, int k)
{
	return (vec3){lanes->x[k], lanes->y[k], lanes->z[k]};
}

static inline void lane_set(lanes3 *lanes, int k, vec3 value)
{
	lanes->x[k] = value.x;
	lanes->y[k] = value.y;
	lanes->z[k] = value.z;
}

PLAIT_VECTOR_CLONES static void solve_sphere_batch(sphere_batch *restrict batch, int count, vec3 centre,
                                                   float sphere_radius)
{
	for (int k = 0; k < count; ++k) {
		vec3 p0 = lane_get(&batch->p0, k), p1 = lane_get(&batch->p1, k);
		float radius = batch->radius[k];
		/* plait_shape_sweep, sphere */
		vec3 motion = v3_sub(p1, p0);
		vec3 m = v3_sub(p0, centre);
		float reach = sphere_radius + radius;
		float c = v3_dot(m, m) - reach * reach;
		float a = v3_dot(motion, motion), b = v3_dot(m, motion);
		float discriminant = b * b - a * c;
		float t_hit = (-b - sqrtf(plait_maxf(discriminant, 0.0f))) / plait_select(a > 0.0f, a, 1.0f);
		/* Conditions combined with & on ints, not && on bools: branch-free, so vectorised. */
		int started_inside = c <= 0.0f;
		int swept = (a > 0.0f) & (b < 0.0f) & (discriminant >= 0.0f) & (t_hit <= 1.0f);
		float toi = plait_select(started_inside, 0.0f, plait_select(t_hit > 0.0f, t_hit, 0.0f));
		/* plait_shape_distance, sphere, at the hit; trapped: at the end instead */
		vec3 hit = v3_lerp(p0, p1, toi);
		vec3 d = v3_sub(hit, centre);
		float length = v3_length(d);
		vec3 normal = v3_select(length > 1e-12f, v3_scale(d, 1.0f / length), v3(0.0f, 1.0f, 0.0f));
		float distance = length - sphere_radius;
		int trapped =
		    plait_select(toi == 0.0f, 1.0f, 0.0f) * plait_select(distance < radius, 1.0f, 0.0f) > 0.5f;
		vec3 d1 = v3_sub(p1, centre);
		float length1 = v3_length(d1);
		vec3 normal1 = v3_select(length1 > 1e-12f, v3_scale(d1, 1.0f / length1), v3(0.0f, 1.0f, 0.0f));
		normal = v3_select(trapped, normal1, normal);
		distance = plait_select(trapped, length1 - sphere_radius, distance);
		hit = v3_select(trapped, p1, hit);
		vec3 surface = v3_mul_add(hit, -distance, normal);
		float depth = radius - v3_dot(v3_sub(p1, surface), normal);
		/* contact_correction and friction_correction */
		float limit = batch->friction[k] * (depth + batch->pushed[k]) - batch->rubbed[k];
		vec3 tangential = v3_mul_add(motion, -v3_dot(motion, normal), normal);
		float tangential_length = v3_length(tangential);
		float removed = plait_select(tangential_length < limit, 1.0f, limit / tangential_length);
		int rubs = (tangential_length > 0.0f) & (limit > 0.0f);
		vec3 rub = v3_select(rubs, v3_scale(tangential, -removed), v3(0.0f, 0.0f, 0.0f));
		batch->rub[k] = plait_select(rubs, removed * tangential_length, 0.0f);
		vec3 correction = v3_add(v3_scale(normal, depth), rub);
		batch->touch[k] = plait_select(started_inside, 1.0f, plait_select(swept, 1.0f, 0.0f));
		batch->depth[k] = depth;
		lane_set(&batch->normal, k, normal);
		lane_set(&batch->surface, k, surface);
		lane_set(&batch->moved, k, v3_add(p1, correction));
	}
}

/* Solves a sphere batch and records its contacts, as the general path does for each particle;
 * returns the contacts that moved a particle. */
static int finish_sphere_batch(collider_job *job, sphere_batch *batch, int count)
{
	plait_sim *sim = job->sim;
	const plait_collider *c = job->c;
	plait_particles *p = &sim->particles;
	const plait_rigid *r0 = &c->rigid_start, *r1 = &c->rigid_end;
	float inverse_h = 1.0f / sim->substep_time;
	solve_sphere_batch(batch, count, c->shape.center, c->shape.radius);
	int contacts = 0;
	for (int k = 0; k < count; ++k) {
		int i = batch->particle[k];
		if (batch->touch[k] == 0.0f || !(batch->depth[k] > 0.0f)) {
			vec3 p0 = lane_get(&batch->p0, k), p1 = lane_get(&batch->p1, k), d = v3_sub(p1, c->shape.center);
			float length = v3_length(d);
			if ((p->flags[i] & PLAIT_PARTICLE_CONTACT) && job->rests && length > 0.0f &&
			    length - c->shape.radius <= batch->radius[k] * (1.0f + RESTING_SLACK)) {
				vec3 moved = rub_resting(p, i, p0, p1, v3_scale(d, 1.0f / length), batch->friction[k]);
				p->point[i].x = job->identity ? moved : plait_rigid_apply(r1, moved);
			}
			if (batch->touch[k] == 0.0f) {
				continue;
			}
		}
		const plait_material *mat = &sim->materials[p->material[i]];
		vec3 surface_velocity = v3(0.0f, 0.0f, 0.0f);
		if (!job->still) {
			vec3 surface = lane_get(&batch->surface, k);
			surface_velocity =
			    v3_scale(v3_sub(plait_rigid_apply(r1, surface), plait_rigid_apply(r0, surface)), inverse_h);
		}
		vec3 normal = lane_get(&batch->normal, k), moved = lane_get(&batch->moved, k);
		vec3 normal_world = job->identity ? normal : plait_rigid_rotate(r1, normal);
		float bounce = 0.5f * (mat->bounce + c->bounce);
		float stickiness = 0.5f * (mat->stickiness + c->stickiness);
		float pushed = pushed_before(p, i), rubbed = rubbed_before(p, i);
		if (batch->depth[k] > 0.0f) {
			p->point[i].x = job->identity ? moved : plait_rigid_apply(r1, moved);
			pushed += batch->depth[k];
			rubbed += batch->rub[k];
			++contacts;
		}
		record_collider_contact(p, i, normal_world, surface_velocity, bounce, stickiness, pushed, rubbed);
	}
	return contacts;
}

/* Whether particle i's path over the substep may reach the collider: inside its world box and
 * its ball (for a round collider most of the box is out of it). */
static inline int path_may_reach(const collider_job *job, vec3 a, vec3 b)
{
	vec3 lower = job->world_lower, upper = job->world_upper;
	/* Bitwise, not logical: one test without a branch each. */
	int in_box = (int)(plait_maxf(a.x, b.x) >= lower.x) & (int)(plait_minf(a.x, b.x) <= upper.x) &
	             (int)(plait_maxf(a.y, b.y) >= lower.y) & (int)(plait_minf(a.y, b.y) <= upper.y) &
	             (int)(plait_maxf(a.z, b.z) >= lower.z) & (int)(plait_minf(a.z, b.z) <= upper.z);
	/* The ball around the path (its midpoint, half its length) must reach the collider's. */
	float reach = job->ball_radius + 0.5f * v3_length(v3_sub(b, a));
	int in_ball = v3_length_sq(v3_sub(v3_scale(v3_add(a, b), 0.5f), job->ball_centre)) <= reach * reach;
	return in_box & in_ball;
}

/* The cull of a bounded collider over particles [begin, begin + count), in a loop without
 * branches (the particles that reach it come in patches the branch predictor cannot learn):
 * into near[], those that take part and may reach it; returns how many. */
enum { CULL_CHUNK = 256 };

PLAIT_VECTOR_CLONES static int cull_particles(const collider_job *restrict job, const plait_particles *p,
                                              int begin, int count, int *restrict near)
{
	int keep[CULL_CHUNK];
	const plait_point *point = p->point + begin;
	const vec3 *x_prev = p->x_prev + begin;
	const uint8_t *flags = p->flags + begin;
	for (int k = 0; k < count; ++k) {
		keep[k] = ((flags[k] & PLAIT_PARTICLE_COLLIDE) != 0) & (point[k].w != 0.0f) &
		          path_may_reach(job, x_prev[k], point[k].x);
	}
	int n = 0;
	for (int k = 0; k < count; ++k) {
		near[n] = begin + k; /* written for every particle, kept for those that reach */
		n += keep[k];
	}
	return n;
}

/* Particle i against the collider: a sphere's particles go into its batch (solved when full),
 * the others are solved here. Returns the contacts that moved it. */
static int collide_particle(collider_job *job, int i, sphere_batch *batch, int *batch_count)
{
	plait_sim *sim = job->sim;
	const plait_collider *c = job->c;
	plait_particles *p = &sim->particles;
	const plait_rigid *r0 = &c->rigid_start, *r1 = &c->rigid_end;
	const plait_material *mat = &sim->materials[p->material[i]];
	/* Everything in the collider's own space: there the collider stands still and the
	 * particle moves along a straight line from p0 to p1. */
	bool identity = job->identity;
	vec3 p0 = identity ? p->x_prev[i] : plait_rigid_apply_inverse(r0, p->x_prev[i]);
	vec3 p1 = identity ? p->point[i].x : plait_rigid_apply_inverse(r1, p->point[i].x);
	float radius = (p->radius[i] + c->thickness) * (1.0f / r1->scale);
	/* A contact pass pushes and counts its push but does not rub (sim.h, contact_push): rubbing at
	 * each pass, with the constraint iterations pushing back between passes, spent friction's
	 * limit on the same few micrometres again and again, and a sheet on a slope just under its
	 * friction angle crept down it. */
	bool again = job->again;
	float friction = again ? 0.0f : plait_combined_friction(mat->friction, c->friction);
	if (batch != NULL) {
		int lane = (*batch_count)++;
		batch->particle[lane] = i;
		lane_set(&batch->p0, lane, p0);
		lane_set(&batch->p1, lane, p1);
		batch->radius[lane] = radius;
		batch->friction[lane] = friction;
		batch->pushed[lane] = pushed_before(p, i);
		batch->rubbed[lane] = rubbed_before(p, i);
		if (*batch_count < SPHERE_BATCH) {
			return 0;
		}
		*batch_count = 0;
		return finish_sphere_batch(job, batch, SPHERE_BATCH);
	}
	float inverse_h = 1.0f / sim->substep_time;
	if (c->shape.type == PLAIT_SHAPE_MESH) {
		/* Pushed earlier in the substep: friction also where it rests within RESTING_SLACK. */
		bool rests = (p->flags[i] & PLAIT_PARTICLE_CONTACT) && job->rests;
		float reach = rests ? radius * (1.0f + RESTING_SLACK) : radius;
		bool cleared = c->clearance != NULL && i < c->clear_capacity && c->shape.mesh->node_count > 0;
		if (cleared) {
			/* Clear of the collider by more than the radius all along the path: nothing to do,
			 * as the tests below would find. The slack is twice what the sweep widens its
			 * reach by for rounding (collision/static_sweep.c: 1e-5 of the radius, the motion,
			 * and the distances from p0 to a corner and between corners), bounded through the
			 * mesh's box, whose coordinates' sizes `extent` bounds. A deforming mesh's surface
			 * has come nearer by at most its drift since (sim.h), this substep's included: its
			 * boxes hold the triangles over the substep, and each point of a triangle is a
			 * mean of its corners, each within that drift of where it was. */
			const plait_bvh_node *root = &c->shape.mesh->nodes[0];
			vec3 at = c->clear_at[i];
			float moved = plait_maxf(v3_length(v3_sub(p0, at)), v3_length(v3_sub(p1, at))) +
			              (float)(c->drift - c->clear_drift[i]);
			float extent = fabsf(root->lower.x) + fabsf(root->lower.y) + fabsf(root->lower.z) +
			               fabsf(root->upper.x) + fabsf(root->upper.y) + fabsf(root->upper.z);
			float scale = radius + 4.0f * moved + fabsf(at.x) + fabsf(at.y) + fabsf(at.z) + 3.0f * extent;
			if (c->clearance[i] - moved > reach * 1.001f + 2e-5f * scale) {
				return 0;
			}
		}
		vec3 normal, motion, measured_at;
		float measured = -INFINITY;
		float pushed = pushed_before(p, i), rubbed = rubbed_before(p, i);
		bool rested;
		bool touched = collide_point_with_mesh(c->shape.mesh, p0, &p1, radius, friction, &pushed, &rubbed,
		                                       sim->substep == 0, rests, &rested, &normal, &motion,
		                                       &measured_at, &measured);
		if (cleared && measured > -INFINITY) {
			c->clear_at[i] = measured_at;
			c->clearance[i] = measured;
			c->clear_drift[i] = c->drift;
		}
		if (rested) {
			/* As rub_resting: its end moved by friction, counted as touching. */
			p->point[i].x = plait_rigid_apply(r1, p1);
			p->contact_rub[i] = rubbed;
			p->flags[i] |= PLAIT_PARTICLE_TOUCHED;
		}
		if (!touched) {
			return 0;
		}
		/* Where the touched surface point was at the substep's start, to where it is. */
		vec3 surface_velocity =
		    v3_scale(v3_sub(plait_rigid_apply(r1, p1), plait_rigid_apply(r0, v3_sub(p1, motion))), inverse_h);
		p->point[i].x = plait_rigid_apply(r1, p1);
		record_collider_contact(p, i, plait_rigid_rotate(r1, normal), surface_velocity,
		                        0.5f * (mat->bounce + c->bounce), 0.5f * (mat->stickiness + c->stickiness),
		                        pushed, rubbed);
		return 1;
	}
	float toi;
	if (!plait_shape_sweep(&c->shape, p0, p1, radius, &toi)) {
		if ((p->flags[i] & PLAIT_PARTICLE_CONTACT) && job->rests) {
			vec3 normal;
			float distance = plait_shape_distance(&c->shape, p1, &normal);
			if (distance <= radius * (1.0f + RESTING_SLACK)) {
				vec3 moved = rub_resting(p, i, p0, p1, normal, friction);
				p->point[i].x = identity ? moved : plait_rigid_apply(r1, moved);
			}
		}
		return 0;
	}
	vec3 hit = v3_lerp(p0, p1, toi);
	vec3 normal;
	float distance = plait_shape_distance(&c->shape, hit, &normal);
	if (toi == 0.0f && distance < radius) {
		/* Started inside the thickened shape. Inside the shape itself (trapped): push out along
		 * the normal at the end position instead, which for the convex shapes here leads
		 * straight out. Only within the thickness (resting on it, a rounding inside): out the
		 * way it came, unless the end lies past the shape on another side (through a thin box),
		 * when it goes back to the side it began on. A box's nearest face jumps: an end inside
		 * the box itself goes back out of the face it began by, not out of the face nearest the
		 * end. (A vertex that the failsafe's zones swung 6 cm into the box arm's forearm from
		 * beside one face went out through the next, across the bar from the rest of its
		 * cloth, and its triangles ended wrapped through the bar: performance.md, session 27.) */
		vec3 end_normal;
		float end_distance = plait_shape_distance(&c->shape, p1, &end_normal);
		bool back_out_of_its_face = c->shape.type == PLAIT_SHAPE_BOX && end_distance < 0.0f;
		if (!(distance > 0.0f) || (v3_dot(end_normal, normal) >= 0.0f && !back_out_of_its_face)) {
			distance = end_distance;
			normal = end_normal;
			hit = p1;
		}
	}
	vec3 surface = v3_mul_add(hit, -distance, normal);
	float depth = radius - v3_dot(v3_sub(p1, surface), normal);
	vec3 surface_velocity = v3(0.0f, 0.0f, 0.0f);
	if (!job->still) {
		vec3 surface_world = plait_rigid_apply(r1, surface);
		surface_velocity = v3_scale(v3_sub(surface_world, plait_rigid_apply(r0, surface)), inverse_h);
	}
	vec3 normal_world = identity ? normal : plait_rigid_rotate(r1, normal);
	float bounce = 0.5f * (mat->bounce + c->bounce);
	float stickiness = 0.5f * (mat->stickiness + c->stickiness);
	if (depth <= 0.0f) {
		/* Touching within the tolerance of the sweep but not inside: still a contact for
		 * restitution and stickiness, no correction. */
		if ((p->flags[i] & PLAIT_PARTICLE_CONTACT) && job->rests) {
			vec3 moved = rub_resting(p, i, p0, p1, normal, friction);
			p->point[i].x = identity ? moved : plait_rigid_apply(r1, moved);
		}
		record_collider_contact(p, i, normal_world, surface_velocity, bounce, stickiness, pushed_before(p, i),
		                        rubbed_before(p, i));
		return 0;
	}
	float pushed = pushed_before(p, i), rubbed = rubbed_before(p, i);
	vec3 correction = contact_correction(normal, depth, v3_sub(p1, p0), friction, pushed, &rubbed);
	p->point[i].x = identity ? v3_add(p1, correction) : plait_rigid_apply(r1, v3_add(p1, correction));
	record_collider_contact(p, i, normal_world, surface_velocity, bounce, stickiness, pushed + depth, rubbed);
	if (c->shape.type == PLAIT_SHAPE_PLANE) {
		p->flags[i] |= PLAIT_PARTICLE_ON_PLANE;
	}
	return 1;
}

static void collide_collider_range(void *context, int begin, int end)
{
	collider_job *job = context;
	plait_particles *p = &job->sim->particles;
	int contacts = 0;
	sphere_batch sphere_lanes;
	sphere_batch *batch = job->c->shape.type == PLAIT_SHAPE_SPHERE ? &sphere_lanes : NULL;
	int batch_count = 0;
	if (job->bounded && job->indices == NULL) {
		int near[CULL_CHUNK];
		plait_collider_bounds bounds = {job->world_lower, job->world_upper, job->ball_centre,
		                                job->ball_radius};
		for (int chunk = begin; chunk < end; chunk += CULL_CHUNK) {
			int size = end - chunk < CULL_CHUNK ? end - chunk : CULL_CHUNK, count = 0, whole = 0;
#if PLAIT_X86_KERNELS
			if (job->sim->simd == PLAIT_SIMD_AVX512) {
				whole = size & ~15;
				count = plait_cull_particles_avx512(p, &bounds, chunk, whole, near);
			} else if (job->sim->simd != PLAIT_SIMD_SCALAR) {
				whole = size & ~7;
				count = plait_cull_particles_avx2(p, &bounds, chunk, whole, near);
			}
#else
			(void)bounds; /* the portable cull reads the job's copy */
#endif
			count += cull_particles(job, p, chunk + whole, size - whole, near + count);
			for (int k = 0; k < count; ++k) {
				contacts += collide_particle(job, near[k], batch, &batch_count);
			}
		}
	} else {
		for (int k = begin; k < end; ++k) {
			int i = job->indices != NULL ? job->indices[k] : k;
			if (!(p->flags[i] & PLAIT_PARTICLE_COLLIDE) || p->point[i].w == 0.0f ||
			    (job->bounded && !path_may_reach(job, p->x_prev[i], p->point[i].x))) {
				continue;
			}
			contacts += collide_particle(job, i, batch, &batch_count);
		}
	}
	if (batch_count > 0) {
		contacts += finish_sphere_batch(job, batch, batch_count);
	}
	atomic_fetch_add_explicit(&job->contacts, contacts, memory_order_relaxed);
}

/* A cloth triangle whose vertices are all outside a sphere or capsule can still reach into it
 * between them, by up to (longest edge)^2 / (6 radius) (the sagitta of its circumcircle): a
 * round shape has no corners or edges of its own to meet the cloth with (mesh and box colliders
 * do: plait_collider.first). Such triangles are pushed out along the normal from the shape's
 * core (centre, axis) to their nearest point, their vertices moved by barycentric weight and
 * inverse mass. Only triangles near the shape whose edges are long enough for that dip to pass
 * their thickness and 0.05 mm are looked at; they are found a chunk at a time in a loop without
 * branches, then pushed one after another, as they share vertices (a push moves vertices away
 * from the shape, so it never brings a triangle of the chunk that was passed over nearer). */
enum { TRIANGLE_CHUNK = 128 };

typedef struct triangle_chunk {
	float x[3][TRIANGLE_CHUNK], y[3][TRIANGLE_CHUNK], z[3][TRIANGLE_CHUNK];
	int keep[TRIANGLE_CHUNK];
} triangle_chunk;

/* Which triangles of the chunk are near the ball and long enough to dip past their reach. */
PLAIT_VECTOR_CLONES static void find_dipping_triangles(triangle_chunk *restrict chunk, int count, vec3 centre,
                                                       float ball_radius, float inverse_six_radius,
                                                       float reach)
{
	for (int k = 0; k < count; ++k) {
		vec3 a = {chunk->x[0][k], chunk->y[0][k], chunk->z[0][k]};
		vec3 b = {chunk->x[1][k], chunk->y[1][k], chunk->z[1][k]};
		vec3 c = {chunk->x[2][k], chunk->y[2][k], chunk->z[2][k]};
		vec3 lower = v3_min(a, v3_min(b, c)), upper = v3_max(a, v3_max(b, c));
		vec3 nearest = v3_min(v3_max(centre, lower), upper);
		int near = v3_length_sq(v3_sub(nearest, centre)) <= ball_radius * ball_radius;
		float longest_sq = plait_maxf(v3_length_sq(v3_sub(b, a)),
		                              plait_maxf(v3_length_sq(v3_sub(c, b)), v3_length_sq(v3_sub(a, c))));
		chunk->keep[k] = near & (longest_sq * inverse_six_radius > reach + 5e-5f);
	}
}

/* Pushes triangle v[] out of the round collider if it reaches into it; returns whether. */
static bool push_triangle_out(const collider_job *job, plait_particles *p, const int *v, float reach)
{
	const plait_collider *c = job->c;
	const plait_rigid *r = &c->rigid_end;
	vec3 local[3];
	for (int m = 0; m < 3; ++m) {
		local[m] = job->identity ? p->point[v[m]].x : plait_rigid_apply_inverse(r, p->point[v[m]].x);
	}
	/* The triangle's point nearest the core, and the core's point nearest it. */
	int region;
	float w[3];
	vec3 core = c->shape.center, q;
	if (c->shape.type == PLAIT_SHAPE_SPHERE) {
		q = plait_closest_point_on_triangle(core, local[0], local[1], local[2], &region, w);
	} else {
		/* Alternating between the axis and the triangle converges for a convex pair. */
		core = c->shape.a;
		for (int iteration = 0; iteration < 8; ++iteration) {
			q = plait_closest_point_on_triangle(core, local[0], local[1], local[2], &region, w);
			core = v3_lerp(c->shape.a, c->shape.b, plait_closest_on_segment(q, c->shape.a, c->shape.b));
		}
		q = plait_closest_point_on_triangle(core, local[0], local[1], local[2], &region, w);
	}
	vec3 d = v3_sub(q, core);
	float distance = v3_length(d);
	float depth = c->shape.radius + reach / r->scale - distance;
	if (depth <= 0.0f || distance <= 1e-12f || w[0] > 0.9999f || w[1] > 0.9999f || w[2] > 0.9999f) {
		return false; /* clear, or at a vertex: the vertex's own contact */
	}
	vec3 normal = v3_scale(d, 1.0f / distance);
	normal = job->identity ? normal : plait_rigid_rotate(r, normal);
	float weighted = 0.0f;
	for (int m = 0; m < 3; ++m) {
		weighted += w[m] * w[m] * p->point[v[m]].w;
	}
	if (weighted <= 0.0f) {
		return false;
	}
	float lambda = depth * r->scale / weighted;
	for (int m = 0; m < 3; ++m) {
		p->point[v[m]].x = v3_mul_add(p->point[v[m]].x, lambda * w[m] * p->point[v[m]].w, normal);
		/* A pass for listed particles reports the others it moved (by adding them). */
		if (job->listed != NULL && job->listed[v[m]] < 0 && p->point[v[m]].w > 0.0f) {
			job->listed[v[m]] = v[m];
			job->grown_indices[(*job->grown_count)++] = v[m];
		}
	}
	return true;
}

static int push_triangles_out_of_round(const collider_job *job)
{
	plait_sim *sim = job->sim;
	const plait_collider *c = job->c;
	plait_particles *p = &sim->particles;
	float inverse_six_radius = 1.0f / (6.0f * c->shape.radius * c->rigid_end.scale);
	triangle_chunk chunk;
	int pushed = 0;
	for (int k = 0; k < sim->surface_count; ++k) {
		const plait_surface *surface = &sim->surfaces[k];
		const plait_material *mat = &sim->materials[surface->material];
		if (mat->type != PLAIT_OBJECT_CLOTH || !mat->collide || mat->collider_flag == PLAIT_COLLIDE_VERTEX) {
			continue;
		}
		const plait_mesh_shape *shape = surface->shape;
		/* A cloth's vertices have its thickness for radius. */
		float reach = mat->thickness + c->thickness;
		for (int first = 0; first < shape->triangle_count; first += TRIANGLE_CHUNK) {
			int count = shape->triangle_count - first < TRIANGLE_CHUNK ? shape->triangle_count - first
			                                                           : TRIANGLE_CHUNK;
			for (int t = 0; t < count; ++t) {
				const int *tri = shape->triangles[first + t];
				for (int m = 0; m < 3; ++m) {
					float unused;
					plait_load_point(&p->point[surface->first + tri[m]], &chunk.x[m][t], &chunk.y[m][t],
					                 &chunk.z[m][t], &unused);
				}
			}
			find_dipping_triangles(&chunk, count, job->ball_centre, job->ball_radius, inverse_six_radius,
			                       reach);
			for (int t = 0; t < count; ++t) {
				if (!chunk.keep[t]) {
					continue;
				}
				const int *tri = shape->triangles[first + t];
				int v[3] = {surface->first + tri[0], surface->first + tri[1], surface->first + tri[2]};
				pushed += push_triangle_out(job, p, v, reach);
			}
		}
	}
	return pushed;
}

#define COLLIDER_GRAIN 1024

/* What a pass of particles against collider c needs of it for the substep. */
static void prepare_collider_job(plait_sim *sim, const plait_collider *c, const int *indices,
                                 collider_job *job)
{
	const plait_rigid *r0 = &c->rigid_start, *r1 = &c->rigid_end;
	/* Cull with the collider's world box over the substep (unbounded for planes), grown by the
	 * thickest particle: most particles never reach the transforms and the sweep. */
	vec3 lower0, upper0;
	bool bounded = plait_shape_bounds(&c->shape, &lower0, &upper0);
	vec3 world_lower = {0}, world_upper = {0};
	if (bounded) {
		float grow = sim->largest_radius + c->thickness;
		world_lower = v3(INFINITY, INFINITY, INFINITY);
		world_upper = v3(-INFINITY, -INFINITY, -INFINITY);
		for (int corner = 0; corner < 8; ++corner) {
			vec3 q = {corner & 1 ? upper0.x : lower0.x, corner & 2 ? upper0.y : lower0.y,
			          corner & 4 ? upper0.z : lower0.z};
			vec3 a = plait_rigid_apply(r0, q), b = plait_rigid_apply(r1, q);
			world_lower = v3_min(world_lower, v3_min(a, b));
			world_upper = v3_max(world_upper, v3_max(a, b));
		}
		world_lower = v3_sub(world_lower, v3(grow, grow, grow));
		world_upper = v3_add(world_upper, v3(grow, grow, grow));
	}
	/* The shape's bounding ball (exact for a sphere) where it is at the substep's middle, grown
	 * by half its centre's travel: it holds the collider over the whole substep. Rotation
	 * about the centre moves nothing out of it. A relative margin keeps rounding from
	 * dropping a grazing contact. (Unbounded shapes are not culled.) */
	vec3 ball_centre = {0};
	float ball_radius = INFINITY;
	if (bounded) {
		vec3 centre =
		    c->shape.type == PLAIT_SHAPE_SPHERE ? c->shape.center : v3_scale(v3_add(lower0, upper0), 0.5f);
		float radius =
		    c->shape.type == PLAIT_SHAPE_SPHERE ? c->shape.radius : 0.5f * v3_length(v3_sub(upper0, lower0));
		vec3 centre0 = plait_rigid_apply(r0, centre), centre1 = plait_rigid_apply(r1, centre);
		ball_centre = v3_scale(v3_add(centre0, centre1), 0.5f);
		ball_radius = radius * plait_maxf(r0->scale, r1->scale) + 0.5f * v3_length(v3_sub(centre1, centre0)) +
		              sim->largest_radius + c->thickness;
		ball_radius = ball_radius * (1.0f + 1e-5f) + 1e-6f;
	}
	bool still = memcmp(r0, r1, sizeof *r0) == 0;
	const plait_rigid *r = r1;
	bool identity = still && r->scale == 1.0f && r->translate.x == 0.0f && r->translate.y == 0.0f &&
	                r->translate.z == 0.0f;
	for (int row = 0; row < 3 && identity; ++row) {
		for (int column = 0; column < 3; ++column) {
			identity = identity && r->rotation.m[row][column] == (row == column ? 1.0f : 0.0f);
		}
	}
	*job =
	    (collider_job){sim,      c,       bounded, world_lower, world_upper, ball_centre, ball_radius, still,
	                   identity, indices, NULL,    NULL,        NULL,        0,           false,       false};
}

/* Particles indices[0, count) (all particles when indices is NULL) against collider c. With
 * listed (plait_collide_listed_with_colliders), the particles a triangle push moves are added to
 * indices, grown_count counting them all. */
/* Which pass over the colliders a collider job belongs to. */
typedef enum collider_pass_kind {
	PASS_FIRST,  /* a collision iteration's pass over the colliders (friction also where resting) */
	PASS_BACK,   /* its pass back over them (an elbow's crease) */
	PASS_AGAIN,  /* a contact pass */
	PASS_LISTED, /* the failsafe's, over listed particles */
} collider_pass_kind;

static int collide_with_collider(plait_sim *sim, const plait_collider *c, int *indices, int count,
                                 int *listed, int *grown_count, collider_pass_kind kind)
{
	plait_particles *p = &sim->particles;
	collider_job job;
	prepare_collider_job(sim, c, indices, &job);
	job.rests = kind == PASS_FIRST;
	job.again = kind == PASS_AGAIN;
	job.listed = listed;
	job.grown_indices = indices;
	job.grown_count = grown_count;
	plait_parallel_for(&sim->parallel, collide_collider_range, &job, 0, indices != NULL ? count : p->count,
	                   COLLIDER_GRAIN);
	int contacts = atomic_load_explicit(&job.contacts, memory_order_relaxed);
	if (job.again) {
		return contacts; /* a contact pass: particles only */
	}
	if (c->shape.type == PLAIT_SHAPE_SPHERE || c->shape.type == PLAIT_SHAPE_CAPSULE) {
		contacts += push_triangles_out_of_round(&job);
	}
	return contacts;
}

/* Earliest t in [0, 1] at which |d0 + t (d1 - d0)| <= distance; false if never. */
static bool sweep_pair(vec3 d0, vec3 d1, float distance, float *toi)
{
	float c = v3_length_sq(d0) - distance * distance;
	if (c <= 0.0f) {
		*toi = 0.0f;
		return true;
	}
	vec3 e = v3_sub(d1, d0);
	float a = v3_length_sq(e);
	float b = v3_dot(d0, e);
	if (a <= 0.0f || b >= 0.0f) {
		return false;
	}
	float discriminant = b * b - a * c;
	if (discriminant < 0.0f) {
		return false;
	}
	float t = (-b - sqrtf(discriminant)) / a;
	if (t > 1.0f) {
		return false;
	}
	*toi = t < 0.0f ? 0.0f : t;
	return true;
}

static int collide_pair(plait_sim *sim, int i, int j)
{
	plait_particles *p = &sim->particles;
	float w_sum = p->point[i].w + p->point[j].w;
	if (w_sum == 0.0f) {
		return 0;
	}
	float distance = p->radius[i] + p->radius[j];
	vec3 d0 = v3_sub(p->x_prev[j], p->x_prev[i]);
	vec3 d1 = v3_sub(p->point[j].x, p->point[i].x);
	float toi;
	if (!sweep_pair(d0, d1, distance, &toi)) {
		return 0;
	}
	vec3 at_contact = v3_lerp(d0, d1, toi);
	vec3 normal = v3_normalize(toi > 0.0f ? at_contact : d1);
	if (v3_length_sq(normal) == 0.0f) {
		normal = v3(0.0f, 1.0f, 0.0f);
	}
	float depth = distance - v3_dot(d1, normal);
	if (depth <= 0.0f) {
		return 0;
	}
	const plait_material *mi = &sim->materials[p->material[i]];
	const plait_material *mj = &sim->materials[p->material[j]];
	float wi = p->point[i].w / w_sum, wj = p->point[j].w / w_sum;
	float rubbed = 0.0f;
	vec3 correction = contact_correction(normal, depth, v3_sub(d1, d0),
	                                     plait_combined_friction(mi->friction, mj->friction), 0.0f, &rubbed);
	p->point[i].x = v3_mul_add(p->point[i].x, -wi, correction);
	p->point[j].x = v3_mul_add(p->point[j].x, wj, correction);

	if (sim->pair_contact_count < sim->pair_contact_capacity) {
		plait_particle_contact *contact = &sim->pair_contacts[sim->pair_contact_count++];
		contact->i = i;
		contact->j = j;
		contact->normal = normal;
		/* v holds the velocity before the constraints until the substep ends. */
		contact->approach_speed = v3_dot(v3_sub(p->v[j], p->v[i]), normal);
		contact->bounce = 0.5f * (mi->bounce + mj->bounce);
	}
	return 1;
}

static bool ensure_pair_contacts(plait_sim *sim)
{
	int wanted = sim->pair_contact_count + sim->particles.count;
	if (sim->pair_contact_capacity >= wanted) {
		return true;
	}
	int capacity = wanted * 2;
	plait_particle_contact *bigger = plait_alloc_grow(&sim->allocator, sim->pair_contacts, sizeof *bigger,
	                                                  sim->pair_contact_count, capacity);
	if (bigger == NULL) {
		return false;
	}
	sim->pair_contacts = bigger;
	sim->pair_contact_capacity = capacity;
	return true;
}

static int collide_particle_pairs(plait_sim *sim)
{
	plait_particles *p = &sim->particles;
	plait_particle_hash *hash = sim->hash;
	/* Whether two particles touch depends only on their relative motion, so the swept boxes
	 * are taken in a frame moving with the particles' mean displacement: a falling cloud then
	 * sweeps small boxes instead of long columns that all overlap. */
	int count = 0;
	double sum_x = 0.0, sum_y = 0.0, sum_z = 0.0;
	for (int i = 0; i < p->count; ++i) {
		if (p->flags[i] & PLAIT_PARTICLE_COLLIDE) {
			sum_x += (double)(p->point[i].x.x - p->x_prev[i].x);
			sum_y += (double)(p->point[i].x.y - p->x_prev[i].y);
			sum_z += (double)(p->point[i].x.z - p->x_prev[i].z);
			++count;
		}
	}
	if (count < 2) {
		return 0;
	}
	vec3 drift = {(float)(sum_x / count), (float)(sum_y / count), (float)(sum_z / count)};
	count = 0;
	float max_radius = 0.0f;
	for (int i = 0; i < p->count; ++i) {
		if (!(p->flags[i] & PLAIT_PARTICLE_COLLIDE)) {
			continue;
		}
		float r = p->radius[i];
		vec3 thickness = {r, r, r};
		vec3 end = v3_sub(p->point[i].x, drift);
		sim->pair_list[count] = i;
		sim->pair_lower[count] = v3_sub(v3_min(p->x_prev[i], end), thickness);
		sim->pair_upper[count] = v3_add(v3_max(p->x_prev[i], end), thickness);
		max_radius = plait_maxf(max_radius, r);
		++count;
	}
	if (count < 2 || !(max_radius > 0.0f)) {
		return 0;
	}
	/* Cells as wide as the largest box: boxes that overlap have their centres in the same or
	 * neighbouring cells. */
	float cell = 2.0f * max_radius;
	for (int k = 0; k < count; ++k) {
		vec3 extent = v3_sub(sim->pair_upper[k], sim->pair_lower[k]);
		cell = plait_maxf(cell, plait_maxf(extent.x, plait_maxf(extent.y, extent.z)));
	}
	if (!plait_particle_hash_build(hash, &sim->allocator, sim->pair_list, sim->pair_lower, sim->pair_upper,
	                               count, cell) ||
	    !ensure_pair_contacts(sim)) {
		return 0;
	}
	int contacts = 0;
	for (int e = 0; e < hash->entry_count; ++e) {
		const plait_hash_entry *a = &hash->entries[e];
		const plait_material *ma = &sim->materials[p->material[a->particle]];
		const vec3 *la = &sim->pair_lower[a->slot], *ua = &sim->pair_upper[a->slot];
		/* The own cell (later entries only), then the 13 cells after it: each pair once. */
		for (int n = -1; n < 13; ++n) {
			plait_hash_cell key = a->cell;
			if (n >= 0) {
				key.x += plait_hash_forward_neighbours[n].x;
				key.y += plait_hash_forward_neighbours[n].y;
				key.z += plait_hash_forward_neighbours[n].z;
			}
			int b = plait_particle_hash_bucket(hash, key);
			int first = n < 0 ? e + 1 : hash->bucket_start[b];
			for (int f = first; f < hash->bucket_start[b + 1]; ++f) {
				const plait_hash_entry *c = &hash->entries[f];
				if (c->cell.x != key.x || c->cell.y != key.y || c->cell.z != key.z) {
					continue;
				}
				const vec3 *lc = &sim->pair_lower[c->slot], *uc = &sim->pair_upper[c->slot];
				if (la->x > uc->x || lc->x > ua->x || la->y > uc->y || lc->y > ua->y || la->z > uc->z ||
				    lc->z > ua->z || !materials_pair_up(ma, &sim->materials[p->material[c->particle]])) {
					continue;
				}
				int i = a->particle < c->particle ? a->particle : c->particle;
				int j = a->particle < c->particle ? c->particle : a->particle;
				contacts += collide_pair(sim, i, j);
				if (sim->pair_contact_count == sim->pair_contact_capacity && !ensure_pair_contacts(sim)) {
					return contacts;
				}
			}
		}
	}
	return contacts;
}

/* How far into a collider's thickness a particle may stay after a collision iteration, as a
 * share of its contact distance, before resolve_creases moves it. */
#define CREASE_SLACK 1e-3f

/* Particle i's violations of its contact distance with the colliders, as half-spaces n.y >= d
 * (world normal n at its position, d its surface plus the contact distance), added to n, d while
 * there is room (CREASE_PLANES); returns how many it violates. */
enum { CREASE_PLANES = 4 };

static int add_violations(const plait_sim *sim, int i, vec3 *n, float *d, int *count)
{
	const plait_particles *p = &sim->particles;
	vec3 x = p->point[i].x;
	int found = 0;
	for (int k = 0; k < sim->collider_count; ++k) {
		const plait_collider *c = &sim->colliders[k];
		if (!c->collide) {
			continue;
		}
		const plait_rigid *r = &c->rigid_end;
		float reach = p->radius[i] + c->thickness;
		vec3 q = plait_rigid_apply_inverse(r, x), normal;
		float depth = reach - plait_shape_distance(&c->shape, q, &normal) * r->scale;
		if (!(depth > CREASE_SLACK * reach)) {
			continue;
		}
		found += 1;
		if (*count < CREASE_PLANES) {
			n[*count] = plait_rigid_rotate(r, normal);
			d[*count] = v3_dot(n[*count], x) + depth;
			*count += 1;
		}
	}
	return found;
}

/* Where colliders meet (an elbow's crease), the pass back over them can push a particle out of
 * one into another, and it ends the iteration inside that one. A particle that touched a collider
 * in the substep and is still inside one after the passes is moved into all the half-spaces that
 * the colliders it has been inside give at their surfaces (projected onto each in turn, a few
 * sweeps), and checked again: a few rounds. Only with two colliding colliders or more. Cloth that
 * slipped on the turning capsules of the arm (contact passes with friction summed over the
 * substep) ended frames with a vertex inside the forearm from frame 101 on without this. */
static void resolve_creases(plait_sim *sim)
{
	int colliders = 0;
	for (int k = 0; k < sim->collider_count; ++k) {
		colliders += sim->colliders[k].collide;
	}
	if (colliders < 2) {
		return;
	}
	plait_particles *p = &sim->particles;
	for (int i = 0; i < p->count; ++i) {
		if (!(p->flags[i] & PLAIT_PARTICLE_CONTACT) || p->point[i].w == 0.0f) {
			continue;
		}
		vec3 n[CREASE_PLANES];
		float d[CREASE_PLANES];
		int count = 0;
		for (int round = 0; round < 3 && add_violations(sim, i, n, d, &count) > 0; ++round) {
			vec3 x = p->point[i].x;
			for (int sweep = 0; sweep < 8; ++sweep) {
				for (int k = 0; k < count; ++k) {
					float short_by = d[k] - v3_dot(n[k], x);
					if (short_by > 0.0f) {
						x = v3_mul_add(x, short_by, n[k]);
					}
				}
			}
			p->point[i].x = x;
		}
	}
}

void plait_collide(plait_sim *sim)
{
	int contacts = 0;
	/* Objects against each other first (particle pairs, then vertices against other objects'
	 * triangles), colliders last: a collider is immovable, so it has the last word and a pile
	 * pressing on the floor cannot push its bottom layer through it. */
	if (sim->particle_pairs_active) {
		contacts += collide_particle_pairs(sim);
	}
	if (sim->mesh_contacts_active) {
		contacts += plait_mesh_contacts_project(sim);
	}
	for (int k = 0; k < sim->collider_count; ++k) {
		if (sim->colliders[k].collide) {
			contacts += collide_with_collider(sim, &sim->colliders[k], NULL, 0, NULL, NULL, PASS_FIRST);
		}
	}
	/* Where colliders meet (an elbow), pushing a particle out of one can push it into another:
	 * back over them in reverse order, so that a particle in the crease settles outside both. */
	for (int k = sim->collider_count - 2; k >= 0; --k) {
		if (sim->colliders[k].collide) {
			(void)collide_with_collider(sim, &sim->colliders[k], NULL, 0, NULL, NULL, PASS_BACK);
		}
	}
	resolve_creases(sim);
	if (sim->mesh_contacts_active) {
		contacts += plait_mesh_contacts_project_on_colliders(sim);
	}
	sim->contacts += contacts;
	sim->contact_particle_count = -1; /* gathered again at the next contact pass */
}

/* The particles that touched a collider since the last gathering (PLAIT_PARTICLE_TOUCHED, which
 * the substep's end leaves set), in index order; false only when out of memory. */
static bool gather_contact_particles(plait_sim *sim)
{
	plait_particles *p = &sim->particles;
	if (sim->contact_particle_capacity < p->count) {
		plait_free(&sim->allocator, sim->contact_particles);
		sim->contact_particles = plait_alloc(&sim->allocator, sizeof(int) * (size_t)p->count);
		sim->contact_particle_capacity = sim->contact_particles != NULL ? p->count : 0;
		if (sim->contact_particles == NULL) {
			return false;
		}
	}
	int count = 0;
	for (int i = 0; i < p->count; ++i) {
		if (p->flags[i] & PLAIT_PARTICLE_TOUCHED) {
			p->flags[i] &= (uint8_t)~PLAIT_PARTICLE_TOUCHED;
			sim->contact_particles[count++] = i;
		}
	}
	sim->contact_particle_count = count;
	return true;
}

void plait_collide_again(plait_sim *sim)
{
	if (sim->mesh_contacts_active) {
		plait_mesh_contacts_project_again(sim);
	}
	if (sim->contact_particle_count < 0 && !gather_contact_particles(sim)) {
		return; /* out of memory: the collision iterations still run */
	}
	int count = sim->contact_particle_count;
	if (count == 0) {
		return;
	}
	for (int k = 0; k < sim->collider_count; ++k) {
		if (sim->colliders[k].collide) {
			(void)collide_with_collider(sim, &sim->colliders[k], sim->contact_particles, count, NULL, NULL,
			                            PASS_AGAIN);
		}
	}
	for (int k = sim->collider_count - 2; k >= 0; --k) {
		if (sim->colliders[k].collide) {
			(void)collide_with_collider(sim, &sim->colliders[k], sim->contact_particles, count, NULL, NULL,
			                            PASS_AGAIN);
		}
	}
}

/* Whether a cloth's triangles are pushed out of round colliders (push_triangles_out_of_round):
 * a pass over triangles, not particles. */
static bool pushes_triangles(const plait_sim *sim)
{
	for (int k = 0; k < sim->surface_count; ++k) {
		const plait_material *mat = &sim->materials[sim->surfaces[k].material];
		if (mat->type == PLAIT_OBJECT_CLOTH && mat->collide && mat->collider_flag != PLAIT_COLLIDE_VERTEX) {
			return true;
		}
	}
	return false;
}

bool plait_collider_pass_begin(plait_sim *sim, plait_collider_pass *pass)
{
	pass->count = 0;
	pass->reverse_count = 0;
	if (sim->particle_pairs_active || sim->mesh_contacts_active) {
		return false;
	}
	bool round = false;
	for (int k = 0; k < sim->collider_count; ++k) {
		const plait_collider *c = &sim->colliders[k];
		if (!c->collide) {
			continue;
		}
		/* A collider with vertices of its own moves them as pins at the next substep's start. */
		if (c->count > 0 || pass->count == PLAIT_PASS_COLLIDERS) {
			return false;
		}
		round = round || c->shape.type == PLAIT_SHAPE_SPHERE || c->shape.type == PLAIT_SHAPE_CAPSULE;
		prepare_collider_job(sim, c, NULL, &pass->jobs[pass->count]);
		pass->jobs[pass->count++].rests = true;
	}
	if (round && pushes_triangles(sim)) {
		return false;
	}
	/* plait_collide's pass back over them: colliders collider_count - 2 down to 0; its contacts
	 * are not counted. */
	for (int j = pass->count - 1; j >= 0; --j) {
		if (pass->jobs[j].c - sim->colliders <= sim->collider_count - 2) {
			pass->reverse[pass->reverse_count] = pass->jobs[j];
			pass->reverse[pass->reverse_count].rests = false;
			atomic_init(&pass->reverse[pass->reverse_count].contacts, 0);
			pass->reverse_count += 1;
		}
	}
	return true;
}

void plait_collider_pass_range(plait_collider_pass *pass, int begin, int end)
{
	for (int j = 0; j < pass->count; ++j) {
		collide_collider_range(&pass->jobs[j], begin, end);
	}
	for (int j = 0; j < pass->reverse_count; ++j) {
		collide_collider_range(&pass->reverse[j], begin, end);
	}
}

#if PLAIT_X86_KERNELS
/* collide_collider_range on the points as columns: the cull reads them there; each particle that
 * may reach the collider goes through the point array (its own entry, as scratch) and back. */
static void collide_collider_range_on_columns(collider_job *job, const plait_columns *columns, int begin,
                                              int end)
{
	plait_particles *p = &job->sim->particles;
	int contacts = 0;
	sphere_batch sphere_lanes;
	sphere_batch *batch = job->c->shape.type == PLAIT_SHAPE_SPHERE ? &sphere_lanes : NULL;
	int near[CULL_CHUNK];
	plait_collider_bounds bounds = {job->world_lower, job->world_upper, job->ball_centre, job->ball_radius};
	for (int chunk = begin; chunk < end; chunk += CULL_CHUNK) {
		int size = end - chunk < CULL_CHUNK ? end - chunk : CULL_CHUNK, whole = size & ~15;
		int count = plait_cull_columns_avx512(p, columns, &bounds, chunk, whole, near);
		for (int i = chunk + whole; i < chunk + size; ++i) {
			p->point[i] = plait_column_point(columns, i);
		}
		count += cull_particles(job, p, chunk + whole, size - whole, near + count);
		int batch_count = 0;
		for (int k = 0; k < count; ++k) {
			int i = near[k];
			p->point[i] = plait_column_point(columns, i);
			contacts += collide_particle(job, i, batch, &batch_count);
		}
		/* Each particle's result is its own, whichever batch it is solved in. */
		if (batch_count > 0) {
			contacts += finish_sphere_batch(job, batch, batch_count);
		}
		for (int k = 0; k < count; ++k) {
			int i = near[k];
			plait_column_set(columns, i, p->point[i].x);
		}
	}
	atomic_fetch_add_explicit(&job->contacts, contacts, memory_order_relaxed);
}
#endif

bool plait_collider_pass_on_columns(const plait_collider_pass *pass)
{
#if PLAIT_X86_KERNELS
	for (int j = 0; j < pass->count; ++j) {
		if (!pass->jobs[j].bounded || pass->jobs[j].indices != NULL) {
			return false;
		}
	}
	for (int j = 0; j < pass->reverse_count; ++j) {
		if (!pass->reverse[j].bounded || pass->reverse[j].indices != NULL) {
			return false;
		}
	}
	return true;
#else
	(void)pass;
	return false;
#endif
}

void plait_collider_pass_range_on_columns(plait_collider_pass *pass, const plait_columns *columns, int begin,
                                          int end)
{
#if PLAIT_X86_KERNELS
	for (int j = 0; j < pass->count; ++j) {
		collide_collider_range_on_columns(&pass->jobs[j], columns, begin, end);
	}
	for (int j = 0; j < pass->reverse_count; ++j) {
		collide_collider_range_on_columns(&pass->reverse[j], columns, begin, end);
	}
#else
	(void)pass;
	(void)columns;
	(void)begin;
	(void)end;
#endif
}

void plait_collider_pass_end(plait_sim *sim, plait_collider_pass *pass)
{
	for (int j = 0; j < pass->count; ++j) {
		sim->contacts += atomic_load_explicit(&pass->jobs[j].contacts, memory_order_relaxed);
	}
	sim->contact_particle_count = -1;
}

int plait_collide_listed_with_colliders(plait_sim *sim, int *indices, int *count, int *listed)
{
	int contacts = 0;
	for (int k = 0; k < sim->collider_count; ++k) {
		if (sim->colliders[k].collide) {
			contacts +=
			    collide_with_collider(sim, &sim->colliders[k], indices, *count, listed, count, PASS_LISTED);
		}
	}
	return contacts;
}

/* Below this approach speed a contact is resting, not bouncing: gravity's pull over two
 * substeps, so resting particles do not jitter. */
float plait_resting_speed(const plait_sim *sim)
{
	return 2.0f * v3_length(sim->settings.gravity) * sim->substep_time + 1e-6f;
}

vec3 plait_respond_to_collider_contact(const plait_particles *p, int i, vec3 v_before, vec3 v,
                                       float resting_speed)
{
	vec3 n = p->contact_normal[i];
	vec3 surface_velocity = p->contact_velocity[i];
	float approach = v3_dot(v3_sub(v_before, surface_velocity), n);
	float normal_speed = v3_dot(v3_sub(v, surface_velocity), n);
	float bounce = p->contact_bounce[i];
	if (bounce > 0.0f && approach < -resting_speed) {
		float target = -bounce * approach;
		if (normal_speed < target) {
			v = v3_mul_add(v, target - normal_speed, n);
		}
	} else if (normal_speed > 0.0f && p->contact_stickiness[i] > 0.0f) {
		v = v3_mul_add(v, -normal_speed * p->contact_stickiness[i], n);
	}
	return v;
}

void plait_contacts_end_substep(plait_sim *sim)
{
	plait_particles *p = &sim->particles;
	float resting_speed = plait_resting_speed(sim);
	for (int c = 0; c < sim->pair_contact_count; ++c) {
		const plait_particle_contact *contact = &sim->pair_contacts[c];
		int i = contact->i, j = contact->j;
		float w_sum = p->point[i].w + p->point[j].w;
		if (w_sum == 0.0f || contact->bounce <= 0.0f || contact->approach_speed >= -resting_speed) {
			continue;
		}
		float normal_speed = v3_dot(v3_sub(p->v[j], p->v[i]), contact->normal);
		float target = -contact->bounce * contact->approach_speed;
		if (normal_speed >= target) {
			continue;
		}
		/* Equal and opposite impulses: momentum is conserved. */
		vec3 impulse = v3_scale(contact->normal, (target - normal_speed) / w_sum);
		p->v[i] = v3_mul_add(p->v[i], -p->point[i].w, impulse);
		p->v[j] = v3_mul_add(p->v[j], p->point[j].w, impulse);
	}
	plait_mesh_contacts_restitute(sim);
}

int plait_count_penetrations(const plait_sim *sim)
{
	const plait_particles *p = &sim->particles;
	int count = 0;
	for (int k = 0; k < sim->collider_count; ++k) {
		const plait_collider *c = &sim->colliders[k];
		if (!c->collide) {
			continue;
		}
		plait_rigid r = plait_rigid_from_transform(c->transform_end);
		vec3 lower, upper;
		bool bounded = plait_shape_bounds(&c->shape, &lower, &upper);
		for (int i = 0; i < p->count; ++i) {
			if (!(p->flags[i] & PLAIT_PARTICLE_COLLIDE) ||
			    sim->materials[p->material[i]].type == PLAIT_OBJECT_COLLIDER) {
				continue; /* colliders' own vertices */
			}
			vec3 q = plait_rigid_apply_inverse(&r, p->point[i].x);
			if (bounded && (q.x < lower.x || q.y < lower.y || q.z < lower.z || q.x > upper.x ||
			                q.y > upper.y || q.z > upper.z)) {
				continue; /* outside the shape's box: not inside the shape */
			}
			vec3 normal;
			float distance = plait_shape_distance(&c->shape, q, &normal) * r.scale;
			if (distance < -(1e-4f + 0.01f * p->radius[i])) {
				++count;
			}
		}
	}
	return count;
}

void plait_contacts_destroy(plait_sim *sim)
{
	plait_mesh_contacts_destroy(sim);
	if (sim->hash != NULL) {
		plait_particle_hash_destroy(sim->hash, &sim->allocator);
		plait_free(&sim->allocator, sim->hash);
		sim->hash = NULL;
	}
}

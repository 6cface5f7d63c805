/* Creating objects: cloth, curves, particles and colliders become particles, materials and
 * constraints of the one simulation (paper §3, §5), and the object accessors.
 *
 * Resistances to material stiffness (scaling relation "link": the resistance is also the number
 * of iterations per frame of that kind, seed 000 §2.4, §9):
 *   cloth stretch, compression, shear: membrane stiffness k = R * 100 N/m. An edge of rest
 *     length L standing for area A_e (each polygon gives 2 A / n to each of its n edges; each
 *     quad A / 2 to each diagonal) gets compliance alpha = L^2 / (k A_e), so a sheet is as stiff
 *     at any resolution;
 *   cloth bend: bending stiffness B = R * 1e-4 N m; a hinge of length |e| between triangles of
 *     area A1, A2 gets alpha = (A1 + A2) / (3 B |e|^2) on its angle (discrete shells);
 *   curve stretch: axial stiffness EA = R * 100 N, alpha = L / EA;
 *   curve bend: bending stiffness EI = R * 1e-4 N m^2, alpha = L^3 / (4 EI) on the distance of
 *     a vertex from the midpoint of its neighbours.
 * Quantities are converted to scene units with space_scale. */
#include <stdio.h>
#include <string.h>

#include "core/error.h"
#include "dynamics/constraints.h"
#include "collision/mesh_shape.h"
#include "dynamics/sim_store.h"
#include "world/bend_pairs.h"
#include "world/tethers.h"
#include "world/world.h"

#define STRETCH_STIFFNESS_PER_RESISTANCE 100.0f /* N/m */
#define BEND_STIFFNESS_PER_RESISTANCE 1e-4f     /* N m */
#define MAX_RESISTANCE 10000.0f

static bool in_range(float value, float low, float high)
{
	return value >= low && value <= high;
}
static bool finite3(plait_vec3 v)
{
	return isfinite(v.x) && isfinite(v.y) && isfinite(v.z);
}

static plait_result check_range(plait_error *error, const char *object, const char *field, float value,
                                float low, float high)
{
	if (!in_range(value, low, high)) {
		return plait_error_set(error, PLAIT_ERROR_INVALID_ARGUMENT, "%s: %s must be in %g..%g, got %g",
		                       object, field, (double)low, (double)high, (double)value);
	}
	return PLAIT_OK;
}

static plait_result check_surface(plait_error *error, const char *object, const plait_surface_def *s)
{
	plait_result r;
	if ((r = check_range(error, object, "thickness", s->thickness, 0.0f, 1e6f)) != PLAIT_OK ||
	    (r = check_range(error, object, "friction", s->friction, 0.0f, 10.0f)) != PLAIT_OK ||
	    (r = check_range(error, object, "stickiness", s->stickiness, 0.0f, 1.0f)) != PLAIT_OK ||
	    (r = check_range(error, object, "bounce", s->bounce, 0.0f, 1.0f)) != PLAIT_OK ||
	    (r = check_range(error, object, "collision_layer", (float)s->collision_layer, 0.0f, 1000.0f)) !=
	        PLAIT_OK) {
		return r;
	}
	return PLAIT_OK;
}

/* The attributes cloth and curves share: resistances, rest length scale, drag, damping and the
 * iteration override. */
static plait_result check_deformable(plait_error *error, const char *label, float stretch, float compression,
                                     float bend, float rest_length_scale, float drag, float damp,
                                     int iterations)
{
	plait_result r;
	if ((r = check_range(error, label, "stretch_resistance", stretch, 0.0f, MAX_RESISTANCE)) != PLAIT_OK ||
	    (r = check_range(error, label, "compression_resistance", compression, 0.0f, MAX_RESISTANCE)) !=
	        PLAIT_OK ||
	    (r = check_range(error, label, "bend_resistance", bend, 0.0f, MAX_RESISTANCE)) != PLAIT_OK ||
	    (r = check_range(error, label, "rest_length_scale", rest_length_scale, 0.01f, 10.0f)) != PLAIT_OK ||
	    (r = check_range(error, label, "drag", drag, 0.0f, 1e6f)) != PLAIT_OK ||
	    (r = check_range(error, label, "damp", damp, 0.0f, 100.0f)) != PLAIT_OK ||
	    (r = check_range(error, label, "iterations", (float)iterations, 0.0f, (float)PLAIT_MAX_IMPORTANCE)) !=
	        PLAIT_OK) {
		return r;
	}
	return PLAIT_OK;
}

static plait_result check_positions(plait_error *error, const char *object, const char *field,
                                    const plait_vec3 *positions, int count)
{
	if (count > 0 && positions == NULL) {
		return plait_error_set(error, PLAIT_ERROR_INVALID_ARGUMENT, "%s: %s is NULL", object, field);
	}
	for (int i = 0; i < count; ++i) {
		if (!finite3(positions[i])) {
			return plait_error_set(error, PLAIT_ERROR_INVALID_MESH, "%s: %s[%d] is not finite", object, field,
			                       i);
		}
	}
	return PLAIT_OK;
}

static plait_result check_pins(plait_error *error, const char *object, const int *pins, int pin_count,
                               int vertex_count)
{
	if (pin_count < 0 || (pin_count > 0 && pins == NULL)) {
		return plait_error_set(error, PLAIT_ERROR_INVALID_ARGUMENT, "%s: pins array is missing", object);
	}
	for (int k = 0; k < pin_count; ++k) {
		if (pins[k] < 0 || pins[k] >= vertex_count) {
			return plait_error_set(error, PLAIT_ERROR_INVALID_ARGUMENT,
			                       "%s: pin %d is vertex %d, outside 0..%d", object, k, pins[k],
			                       vertex_count - 1);
		}
	}
	return PLAIT_OK;
}

static int resistance_importance(float resistance)
{
	float ceiling = ceilf(resistance);
	return ceiling > (float)PLAIT_MAX_IMPORTANCE ? PLAIT_MAX_IMPORTANCE : (int)ceiling;
}

/* Compliance (1/stiffness) of a resistance: 0 turns the constraint off (infinite compliance),
 * the maximum makes it rigid. */
static float stiffness_compliance(float resistance, float per_resistance)
{
	if (resistance >= MAX_RESISTANCE) {
		return 0.0f;
	}
	return resistance > 0.0f ? 1.0f / (resistance * per_resistance) : PLAIT_NO_RESISTANCE;
}

/* Scales a compliance, keeping "no resistance" as it is. */
static float scale_compliance(float compliance, float factor)
{
	return compliance < 0.0f ? PLAIT_NO_RESISTANCE : compliance * factor;
}

static int add_material(plait_sim *sim, int object, plait_object_type type, const plait_surface_def *surface,
                        float damp)
{
	int m = sim->material_count++;
	plait_material *mat = &sim->materials[m];
	memset(mat, 0, sizeof *mat);
	mat->object = object;
	mat->type = type;
	mat->thickness = surface->thickness;
	mat->friction = surface->friction;
	mat->stickiness = surface->stickiness;
	mat->bounce = surface->bounce;
	mat->collide = surface->collide;
	mat->collision_layer = surface->collision_layer;
	mat->self_width_scale = 1.0f;
	mat->damp = damp;
	return m;
}

static void object_label(char *label, size_t size, const char *kind, const char *name)
{
	snprintf(label, size, "%s '%s'", kind, name != NULL && name[0] != '\0' ? name : "(unnamed)");
}

/* Removes an object that failed half-way through creation. */
static void abandon_object(plait_world *world, plait_object *object)
{
	plait_topology_destroy(&object->topology, &world->allocator);
	object->alive = false;
	world->object_count -= 1;
}

static void apply_pins(plait_sim *sim, int first, const int *pins, int pin_count)
{
	for (int k = 0; k < pin_count; ++k) {
		int i = first + pins[k];
		sim->particles.flags[i] |= PLAIT_PARTICLE_PINNED;
		sim->particles.point[i].w = 0.0f;
	}
}

plait_object_id plait_create_cloth(plait_world_id world_id, const plait_cloth_def *def, plait_error *error)
{
	plait_object_id id = {0};
	plait_world *world = world_id.world;
	plait_error_clear(error);
	if (world == NULL || def == NULL) {
		plait_error_set(error, PLAIT_ERROR_INVALID_ARGUMENT, "plait_create_cloth needs a world and a def");
		return id;
	}
	char label[PLAIT_MAX_NAME + 16];
	object_label(label, sizeof label, "cloth", def->name);
	const plait_mesh_def *mesh = &def->mesh;
	if (mesh->vertex_count <= 0 || mesh->face_count <= 0) {
		plait_error_set(error, PLAIT_ERROR_INVALID_MESH, "%s: a cloth needs vertices and faces", label);
		return id;
	}
	if (check_positions(error, label, "positions", mesh->positions, mesh->vertex_count) != PLAIT_OK ||
	    (def->velocities != NULL &&
	     check_positions(error, label, "velocities", def->velocities, mesh->vertex_count) != PLAIT_OK) ||
	    check_range(error, label, "density", def->density, 1e-9f, 1e6f) != PLAIT_OK ||
	    check_deformable(error, label, def->stretch_resistance, def->compression_resistance,
	                     def->bend_resistance, def->rest_length_scale, def->drag, def->damp,
	                     def->iterations) != PLAIT_OK ||
	    check_range(error, label, "shear_resistance", def->shear_resistance, 0.0f, MAX_RESISTANCE) !=
	        PLAIT_OK ||
	    check_range(error, label, "shear_iterations", (float)def->shear_iterations, 0.0f,
	                (float)PLAIT_MAX_IMPORTANCE) != PLAIT_OK ||
	    check_range(error, label, "bend_iterations", (float)def->bend_iterations, 0.0f,
	                (float)PLAIT_MAX_IMPORTANCE) != PLAIT_OK ||
	    check_range(error, label, "tangential_drag", def->tangential_drag, 0.0f, 1e6f) != PLAIT_OK ||
	    check_range(error, label, "lift", def->lift, 0.0f, 1e6f) != PLAIT_OK ||
	    check_range(error, label, "tether_scale", def->tether_scale, 1.0f, 10.0f) != PLAIT_OK ||
	    check_range(error, label, "tether_stiffness", def->tether_stiffness, 0.0f, 1.0f) != PLAIT_OK ||
	    check_range(error, label, "self_collide_width_scale", def->self_collide_width_scale, 0.01f, 100.0f) !=
	        PLAIT_OK ||
	    check_surface(error, label, &def->surface) != PLAIT_OK ||
	    check_pins(error, label, def->pins, def->pin_count, mesh->vertex_count) != PLAIT_OK) {
		return id;
	}
	if (def->self_collision_flag < PLAIT_SELF_COLLIDE_FULL_SURFACE ||
	    def->self_collision_flag > PLAIT_SELF_COLLIDE_VERTEX) {
		plait_error_set(error, PLAIT_ERROR_INVALID_ARGUMENT, "%s: unknown self-collision flag %d", label,
		                (int)def->self_collision_flag);
		return id;
	}
	if (def->collision_flag < PLAIT_COLLIDE_FULL_SURFACE || def->collision_flag > PLAIT_COLLIDE_VERTEX) {
		plait_error_set(error, PLAIT_ERROR_INVALID_ARGUMENT, "%s: unknown collision flag %d", label,
		                (int)def->collision_flag);
		return id;
	}
	if (def->tethers < PLAIT_TETHER_NONE || def->tethers > PLAIT_TETHER_GEODESIC) {
		plait_error_set(error, PLAIT_ERROR_INVALID_ARGUMENT, "%s: unknown tether mode %d", label,
		                (int)def->tethers);
		return id;
	}
	if (def->bend_model < PLAIT_BEND_DIHEDRAL || def->bend_model > PLAIT_BEND_DISTANCE) {
		plait_error_set(error, PLAIT_ERROR_INVALID_ARGUMENT, "%s: unknown bend model %d", label,
		                (int)def->bend_model);
		return id;
	}
	for (int i = 0; def->vertex_masses != NULL && i < mesh->vertex_count; ++i) {
		if (!(def->vertex_masses[i] > 0.0f) || !isfinite(def->vertex_masses[i])) {
			plait_error_set(error, PLAIT_ERROR_INVALID_ARGUMENT, "%s: vertex_masses[%d] must be > 0, got %g",
			                label, i, (double)def->vertex_masses[i]);
			return id;
		}
	}

	plait_object *object = plait_world_new_object(world, PLAIT_OBJECT_CLOTH, def->name, &id);
	if (object == NULL) {
		plait_error_set(error, PLAIT_ERROR_OUT_OF_MEMORY, "%s: out of memory", label);
		return (plait_object_id){0};
	}
	plait_topology *topology = &object->topology;
	if (plait_topology_build(topology, &world->allocator, mesh->vertex_count, mesh->face_sizes,
	                         mesh->face_count, mesh->face_indices, error) != PLAIT_OK) {
		char reason[PLAIT_ERROR_MESSAGE_SIZE];
		snprintf(reason, sizeof reason, "%s", error != NULL ? error->message : "");
		plait_error_set(error, error != NULL ? error->code : PLAIT_ERROR_INVALID_MESH, "%s: %s", label,
		                reason);
		abandon_object(world, object);
		return (plait_object_id){0};
	}

	plait_sim *sim = &world->sim;
	const plait_vec3 *x = mesh->positions;
	int vertex_count = mesh->vertex_count;
	int quad_count = 0;
	for (int f = 0; f < topology->polygon_count; ++f) {
		quad_count += topology->polygon_sizes[f] == 4;
	}
	int bend_count = 0;
	for (int e = 0; e < topology->edge_count; ++e) {
		bend_count += topology->edge_triangle_count[e] == 2;
	}
	plait_allocator *a = &world->allocator;
	bool bend_distance = def->bend_model == PLAIT_BEND_DISTANCE && def->bend_resistance > 0.0f;
	int(*bend_pairs)[2] =
	    bend_distance ? plait_alloc(a, sizeof *bend_pairs * (size_t)(2 * topology->edge_count + 1)) : NULL;
	int bend_pair_count = bend_pairs != NULL ? plait_bend_pairs(topology, x, a, bend_pairs) : 0;
	if (bend_distance) {
		bend_count = 0;
	}
	float *polygon_area = plait_alloc_zero(a, (size_t)topology->polygon_count, sizeof(float));
	float *triangle_area = plait_alloc_zero(a, (size_t)topology->triangle_count, sizeof(float));
	float *vertex_area = plait_alloc_zero(a, (size_t)vertex_count, sizeof(float));
	bool ok = polygon_area && triangle_area && vertex_area &&
	          plait_sim_reserve_particles(sim, vertex_count) && plait_sim_reserve_materials(sim, 1) &&
	          plait_sim_reserve_distance(sim, &sim->stretch, topology->edge_count) &&
	          plait_sim_reserve_distance(sim, &sim->shear, 2 * quad_count) &&
	          plait_sim_reserve_bend(sim, bend_count) &&
	          (!bend_distance || (bend_pairs != NULL && bend_pair_count >= 0)) &&
	          plait_sim_reserve_distance(sim, &sim->bend_distance, bend_pair_count) &&
	          plait_sim_reserve_aero(sim, topology->triangle_count) &&
	          (def->tethers == PLAIT_TETHER_NONE ||
	           plait_sim_reserve_tethers(sim, vertex_count * plait_tethers_per_vertex(def->pin_count)));
	if (!ok) {
		plait_free(a, polygon_area);
		plait_free(a, triangle_area);
		plait_free(a, vertex_area);
		plait_free(a, bend_pairs);
		abandon_object(world, object);
		plait_error_set(error, PLAIT_ERROR_OUT_OF_MEMORY, "%s: out of memory", label);
		return (plait_object_id){0};
	}

	/* Areas: mass and air force are spread by area (seed 003), a third of each triangle. */
	float total_area = 0.0f;
	for (int t = 0; t < topology->triangle_count; ++t) {
		const int *tri = topology->triangles[t];
		float area = 0.5f * v3_length(v3_cross(v3_sub(x[tri[1]], x[tri[0]]), v3_sub(x[tri[2]], x[tri[0]])));
		triangle_area[t] = area;
		polygon_area[topology->triangle_polygon[t]] += area;
		total_area += area;
	}
	/* Each polygon gives an equal share of its area to its corners: a quad's mass does not
	 * depend on which diagonal fanned it (a third per triangle would make one corner of a
	 * quad grid twice as heavy as the opposite one). */
	for (int f = 0; f < topology->polygon_count; ++f) {
		int size = topology->polygon_sizes[f];
		const int *polygon = topology->polygon_indices + topology->polygon_starts[f];
		for (int k = 0; k < size; ++k) {
			vertex_area[polygon[k]] += polygon_area[f] / (float)size;
		}
	}
	float scale = world->def.space_scale;
	float mean_vertex_area = total_area / (float)vertex_count;

	int slot = id.index1 - 1;
	int material = add_material(sim, slot, PLAIT_OBJECT_CLOTH, &def->surface, def->damp);
	plait_material *mat = &sim->materials[material];
	mat->drag = def->drag;
	mat->tangential_drag = def->tangential_drag;
	mat->lift = def->lift;
	mat->self_collide = def->self_collide;
	mat->self_flag = (int)def->self_collision_flag;
	mat->collider_flag = (int)def->collision_flag;
	mat->self_width_scale = def->self_collide_width_scale;
	object->material = material;
	object->first_particle = sim->particles.count;
	object->particle_count = vertex_count;
	uint8_t flags = def->surface.collide ? PLAIT_PARTICLE_COLLIDE : 0;
	for (int i = 0; i < vertex_count; ++i) {
		/* A vertex on no triangle still needs a mass: give it an average vertex's. */
		float area = vertex_area[i] > 0.0f ? vertex_area[i] : mean_vertex_area;
		float mass = def->vertex_masses != NULL ? def->vertex_masses[i] : def->density * area * scale * scale;
		if (!(mass > 0.0f)) {
			mass = 1e-6f;
		}
		vec3 velocity = def->velocities != NULL ? def->velocities[i] : v3(0.0f, 0.0f, 0.0f);
		plait_sim_add_particle(sim, x[i], velocity, mass, def->surface.thickness, material, flags);
	}
	int first = object->first_particle;
	apply_pins(sim, first, def->pins, def->pin_count);

	/* Stretch and compression on polygon edges (and fan diagonals of polygons larger than
	 * quads); shear on both diagonals of each quad (seed 003: separate shear). */
	float stretch_alpha = stiffness_compliance(def->stretch_resistance, STRETCH_STIFFNESS_PER_RESISTANCE);
	float compression_alpha =
	    stiffness_compliance(def->compression_resistance, STRETCH_STIFFNESS_PER_RESISTANCE);
	float shear_alpha = stiffness_compliance(def->shear_resistance, STRETCH_STIFFNESS_PER_RESISTANCE);
	bool has_stretch = def->stretch_resistance > 0.0f || def->compression_resistance > 0.0f;
	for (int e = 0; e < topology->edge_count && has_stretch; ++e) {
		int v0 = topology->edges[e][0], v1 = topology->edges[e][1];
		bool quad_diagonal = false;
		float edge_area = 0.0f;
		int parents = topology->edge_triangle_count[e] < 2 ? topology->edge_triangle_count[e] : 2;
		for (int k = 0; k < parents; ++k) {
			int polygon = topology->triangle_polygon[topology->edge_triangles[e][k]];
			int size = topology->polygon_sizes[polygon];
			quad_diagonal = quad_diagonal || (size == 4 && topology->edge_flags[e] == PLAIT_EDGE_DIAGONAL);
			edge_area += 2.0f * polygon_area[polygon] / (float)size;
		}
		if (quad_diagonal) {
			continue;
		}
		float rest = v3_length(v3_sub(x[v1], x[v0]));
		float ratio = edge_area > 0.0f && rest > 0.0f ? rest * rest / edge_area : 1.0f;
		plait_sim_add_distance(&sim->stretch, first + v0, first + v1, rest * def->rest_length_scale,
		                       scale_compliance(stretch_alpha, ratio),
		                       scale_compliance(compression_alpha, ratio));
	}
	if (def->shear_resistance > 0.0f) {
		for (int f = 0; f < topology->polygon_count; ++f) {
			if (topology->polygon_sizes[f] != 4) {
				continue;
			}
			const int *q = topology->polygon_indices + topology->polygon_starts[f];
			for (int k = 0; k < 2; ++k) {
				int v0 = q[k], v1 = q[k + 2];
				float rest = v3_length(v3_sub(x[v1], x[v0]));
				float edge_area = 0.5f * polygon_area[f];
				float ratio = edge_area > 0.0f && rest > 0.0f ? rest * rest / edge_area : 1.0f;
				plait_sim_add_distance(&sim->shear, first + v0, first + v1, rest * def->rest_length_scale,
				                       scale_compliance(shear_alpha, ratio),
				                       scale_compliance(shear_alpha, ratio));
			}
		}
	}
	if (bend_distance) {
		float bend_alpha = stiffness_compliance(def->bend_resistance, STRETCH_STIFFNESS_PER_RESISTANCE);
		for (int k = 0; k < bend_pair_count; ++k) {
			int v0 = bend_pairs[k][0], v1 = bend_pairs[k][1];
			float rest = v3_length(v3_sub(x[v1], x[v0]));
			plait_sim_add_distance(&sim->bend_distance, first + v0, first + v1, rest * def->rest_length_scale,
			                       bend_alpha, bend_alpha);
		}
	}
	plait_free(a, bend_pairs);
	if (def->bend_resistance > 0.0f && !bend_distance) {
		float bending_stiffness = def->bend_resistance * BEND_STIFFNESS_PER_RESISTANCE / (scale * scale);
		for (int e = 0; e < topology->edge_count; ++e) {
			if (topology->edge_triangle_count[e] != 2) {
				continue;
			}
			int t0 = topology->edge_triangles[e][0], t1 = topology->edge_triangles[e][1];
			/* Hinge (p0, p1) in the order triangle t0 runs along it; wings opposite. */
			const int *a0 = topology->triangles[t0], *a1 = topology->triangles[t1];
			int p0 = -1, p1 = -1, p2 = -1, p3 = -1;
			for (int k = 0; k < 3; ++k) {
				int u = a0[k], v = a0[(k + 1) % 3];
				if ((u == topology->edges[e][0] && v == topology->edges[e][1]) ||
				    (v == topology->edges[e][0] && u == topology->edges[e][1])) {
					p0 = u;
					p1 = v;
					p2 = a0[(k + 2) % 3];
				}
			}
			for (int k = 0; k < 3; ++k) {
				if (a1[k] != p0 && a1[k] != p1) {
					p3 = a1[k];
				}
			}
			float angle;
			if (p2 < 0 || p3 < 0 || !plait_dihedral_angle(x[p0], x[p1], x[p2], x[p3], &angle, NULL)) {
				continue;
			}
			float hinge_sq = v3_length_sq(v3_sub(x[p1], x[p0]));
			float areas = triangle_area[t0] + triangle_area[t1];
			int c = sim->bend.count++;
			sim->bend.quad[c][0] = first + p0;
			sim->bend.quad[c][1] = first + p1;
			sim->bend.quad[c][2] = first + p2;
			sim->bend.quad[c][3] = first + p3;
			sim->bend.rest_angle[c] = angle;
			/* The maximum resistance is rigid, as for every resistance. */
			sim->bend.compliance[c] =
			    def->bend_resistance >= MAX_RESISTANCE ? 0.0f : areas / (3.0f * bending_stiffness * hinge_sq);
			sim->bend.lambda[c] = 0.0f;
		}
	}
	/* Air acts on triangles but mass comes from polygons: triangle t of polygon P lends corner
	 * v the part A_t / S_v of the share A_P / n that v owns in P, where S_v is the area of the
	 * triangles of P touching v; each vertex then feels air on exactly the area it weighs. */
	float *exposure = plait_alloc_zero(a, (size_t)vertex_count, sizeof(float));
	for (int t = 0; t < topology->triangle_count && exposure != NULL; ++t) {
		for (int k = 0; k < 3; ++k) {
			exposure[topology->triangles[t][k]] += triangle_area[t];
		}
	}
	int polygon_start_triangle = 0;
	for (int f = 0; f < topology->polygon_count; ++f) {
		int size = topology->polygon_sizes[f];
		int triangles = size - 2;
		for (int t = polygon_start_triangle; t < polygon_start_triangle + triangles && exposure != NULL;
		     ++t) {
			for (int k = 0; k < 3; ++k) {
				exposure[topology->triangles[t][k]] = 0.0f;
			}
		}
		for (int t = polygon_start_triangle; t < polygon_start_triangle + triangles && exposure != NULL;
		     ++t) {
			for (int k = 0; k < 3; ++k) {
				exposure[topology->triangles[t][k]] += triangle_area[t];
			}
		}
		for (int t = polygon_start_triangle; t < polygon_start_triangle + triangles; ++t) {
			int c = sim->aero.count++;
			for (int k = 0; k < 3; ++k) {
				int v = topology->triangles[t][k];
				float share = polygon_area[f] / (float)size;
				float s_v = exposure != NULL ? exposure[v] : 0.0f;
				sim->aero.triangle[c][k] = first + v;
				sim->aero.weight[c][k] =
				    s_v > 0.0f ? triangle_area[t] * share / s_v : triangle_area[t] / 3.0f;
			}
			sim->aero.material[c] = material;
		}
		polygon_start_triangle += triangles;
	}
	plait_free(a, exposure);
	plait_free(a, polygon_area);
	plait_free(a, triangle_area);
	plait_free(a, vertex_area);
	/* The cloth's surface, for other objects' vertices to collide with. Without memory for it
	 * the cloth still works; its surface is then felt through its vertices only. */
	if (def->surface.collide && plait_sim_reserve_surfaces(sim, 1)) {
		plait_mesh_shape *shape = plait_alloc_zero(a, 1, sizeof *shape);
		if (shape != NULL && plait_mesh_shape_build(shape, a, mesh, NULL) == PLAIT_OK) {
			sim->surfaces[sim->surface_count++] = (plait_surface){slot, material, first, shape};
		} else {
			plait_free(a, shape);
		}
	}
	/* Should the tethers' scratch memory run out, the cloth still works, untethered. */
	(void)plait_build_tethers(sim, topology, x, first, def->pins, def->pin_count, def->tethers,
	                          def->tether_scale, def->tether_stiffness);

	int override = def->iterations;
	object->importance[PLAIT_KIND_STRETCH] =
	    override > 0
	        ? override
	        : resistance_importance(plait_maxf(def->stretch_resistance, def->compression_resistance));
	object->importance[PLAIT_KIND_SHEAR] =
	    def->shear_iterations > 0 ? def->shear_iterations : resistance_importance(def->shear_resistance);
	object->importance[PLAIT_KIND_BEND] =
	    def->bend_iterations > 0 ? def->bend_iterations : resistance_importance(def->bend_resistance);
	object->importance[PLAIT_KIND_TETHER] = 1; /* cheap and decisive: once per substep */
	plait_world_update_kinds(world);
	return id;
}

plait_object_id plait_create_curve(plait_world_id world_id, const plait_curve_def *def, plait_error *error)
{
	plait_object_id id = {0};
	plait_world *world = world_id.world;
	plait_error_clear(error);
	if (world == NULL || def == NULL) {
		plait_error_set(error, PLAIT_ERROR_INVALID_ARGUMENT, "plait_create_curve needs a world and a def");
		return id;
	}
	char label[PLAIT_MAX_NAME + 16];
	object_label(label, sizeof label, "curve", def->name);
	int n = def->vertex_count;
	if (n < 2) {
		plait_error_set(error, PLAIT_ERROR_INVALID_MESH, "%s: a curve needs at least 2 vertices, got %d",
		                label, n);
		return id;
	}
	if (check_positions(error, label, "positions", def->positions, n) != PLAIT_OK ||
	    (def->velocities != NULL &&
	     check_positions(error, label, "velocities", def->velocities, n) != PLAIT_OK) ||
	    check_range(error, label, "mass", def->mass, 1e-12f, 1e9f) != PLAIT_OK ||
	    check_deformable(error, label, def->stretch_resistance, def->compression_resistance,
	                     def->bend_resistance, def->rest_length_scale, def->drag, def->damp,
	                     def->iterations) != PLAIT_OK ||
	    check_surface(error, label, &def->surface) != PLAIT_OK ||
	    check_pins(error, label, def->pins, def->pin_count, n) != PLAIT_OK) {
		return id;
	}
	for (int i = 0; i + 1 < n; ++i) {
		if (v3_length(v3_sub(def->positions[i + 1], def->positions[i])) <= 0.0f) {
			plait_error_set(error, PLAIT_ERROR_INVALID_MESH,
			                "%s: vertices %d and %d coincide (zero-length edge)", label, i, i + 1);
			return id;
		}
	}
	plait_sim *sim = &world->sim;
	plait_object *object = plait_world_new_object(world, PLAIT_OBJECT_CURVE, def->name, &id);
	bool ok = object != NULL && plait_sim_reserve_particles(sim, n) && plait_sim_reserve_materials(sim, 1) &&
	          plait_sim_reserve_distance(sim, &sim->stretch, n - 1) && plait_sim_reserve_rod_bend(sim, n);
	if (!ok) {
		if (object != NULL) {
			abandon_object(world, object);
		}
		plait_error_set(error, PLAIT_ERROR_OUT_OF_MEMORY, "%s: out of memory", label);
		return (plait_object_id){0};
	}
	float scale = world->def.space_scale;
	int material = add_material(sim, id.index1 - 1, PLAIT_OBJECT_CURVE, &def->surface, def->damp);
	plait_material *mat = &sim->materials[material];
	float radius_m = plait_maxf(def->surface.thickness * scale, 1e-3f);
	mat->point_drag = def->drag;
	mat->point_area = PLAIT_PI * radius_m * radius_m;
	object->material = material;
	object->first_particle = sim->particles.count;
	object->particle_count = n;
	uint8_t flags = def->surface.collide ? PLAIT_PARTICLE_COLLIDE : 0;
	for (int i = 0; i < n; ++i) {
		vec3 velocity = def->velocities != NULL ? def->velocities[i] : v3(0.0f, 0.0f, 0.0f);
		plait_sim_add_particle(sim, def->positions[i], velocity, def->mass, def->surface.thickness, material,
		                       flags);
	}
	int first = object->first_particle;
	apply_pins(sim, first, def->pins, def->pin_count);
	mat->self_collide = def->self_collide;
	/* The chain of segments, for collisions with cloths and other curves. Without memory for
	 * it the curve still collides through its vertices. */
	if (def->surface.collide && n >= 2 && plait_sim_reserve_chains(sim, 1)) {
		sim->chains[sim->chain_count++] = (plait_chain){id.index1 - 1, material, first, n};
	}

	const plait_vec3 *x = def->positions;
	if (def->stretch_resistance > 0.0f || def->compression_resistance > 0.0f) {
		/* alpha = L / EA with EA = R * 100 N, converted to scene units by 1 / space_scale. */
		float tension_alpha =
		    stiffness_compliance(def->stretch_resistance, STRETCH_STIFFNESS_PER_RESISTANCE / scale);
		float compression_alpha =
		    stiffness_compliance(def->compression_resistance, STRETCH_STIFFNESS_PER_RESISTANCE / scale);
		for (int i = 0; i + 1 < n; ++i) {
			float rest = v3_length(v3_sub(x[i + 1], x[i]));
			plait_sim_add_distance(&sim->stretch, first + i, first + i + 1, rest * def->rest_length_scale,
			                       scale_compliance(tension_alpha, rest),
			                       scale_compliance(compression_alpha, rest));
		}
	}
	if (def->bend_resistance > 0.0f) {
		float bending = def->bend_resistance * BEND_STIFFNESS_PER_RESISTANCE / (scale * scale * scale);
		for (int i = 1; i + 1 < n; ++i) {
			vec3 mid = v3_scale(v3_add(x[i - 1], x[i + 1]), 0.5f);
			float length = 0.5f * (v3_length(v3_sub(x[i], x[i - 1])) + v3_length(v3_sub(x[i + 1], x[i])));
			int c = sim->rod_bend.count++;
			sim->rod_bend.triple[c][0] = first + i - 1;
			sim->rod_bend.triple[c][1] = first + i;
			sim->rod_bend.triple[c][2] = first + i + 1;
			sim->rod_bend.rest[c] = v3_length(v3_sub(x[i], mid));
			sim->rod_bend.compliance[c] =
			    def->bend_resistance >= MAX_RESISTANCE ? 0.0f : length * length * length / (4.0f * bending);
			sim->rod_bend.lambda[c] = 0.0f;
		}
	}
	int override = def->iterations;
	object->importance[PLAIT_KIND_STRETCH] =
	    override > 0
	        ? override
	        : resistance_importance(plait_maxf(def->stretch_resistance, def->compression_resistance));
	object->importance[PLAIT_KIND_BEND] = resistance_importance(def->bend_resistance);
	plait_world_update_kinds(world);
	return id;
}

plait_object_id plait_create_particles(plait_world_id world_id, const plait_particles_def *def,
                                       plait_error *error)
{
	plait_object_id id = {0};
	plait_world *world = world_id.world;
	plait_error_clear(error);
	if (world == NULL || def == NULL) {
		plait_error_set(error, PLAIT_ERROR_INVALID_ARGUMENT,
		                "plait_create_particles needs a world and a def");
		return id;
	}
	char label[PLAIT_MAX_NAME + 16];
	object_label(label, sizeof label, "particles", def->name);
	int n = def->count;
	if (n < 1) {
		plait_error_set(error, PLAIT_ERROR_INVALID_ARGUMENT, "%s: needs at least one particle, got %d", label,
		                n);
		return id;
	}
	if (check_positions(error, label, "positions", def->positions, n) != PLAIT_OK ||
	    (def->velocities != NULL &&
	     check_positions(error, label, "velocities", def->velocities, n) != PLAIT_OK) ||
	    check_range(error, label, "mass", def->mass, 1e-12f, 1e9f) != PLAIT_OK ||
	    check_range(error, label, "radius", def->radius, 1e-9f, 1e6f) != PLAIT_OK ||
	    check_range(error, label, "drag", def->drag, 0.0f, 1e6f) != PLAIT_OK ||
	    check_range(error, label, "damp", def->damp, 0.0f, 100.0f) != PLAIT_OK ||
	    check_surface(error, label, &def->surface) != PLAIT_OK) {
		return id;
	}
	plait_sim *sim = &world->sim;
	plait_object *object = plait_world_new_object(world, PLAIT_OBJECT_PARTICLES, def->name, &id);
	bool ok = object != NULL && plait_sim_reserve_particles(sim, n) && plait_sim_reserve_materials(sim, 1);
	if (!ok) {
		if (object != NULL) {
			abandon_object(world, object);
		}
		plait_error_set(error, PLAIT_ERROR_OUT_OF_MEMORY, "%s: out of memory", label);
		return (plait_object_id){0};
	}
	float scale = world->def.space_scale;
	float radius = def->radius + def->surface.thickness;
	int material = add_material(sim, id.index1 - 1, PLAIT_OBJECT_PARTICLES, &def->surface, def->damp);
	plait_material *mat = &sim->materials[material];
	mat->self_collide = def->self_collide;
	mat->point_drag = def->drag;
	mat->point_area = PLAIT_PI * (radius * scale) * (radius * scale);
	object->material = material;
	object->first_particle = sim->particles.count;
	object->particle_count = n;
	uint8_t flags = def->surface.collide ? PLAIT_PARTICLE_COLLIDE : 0;
	for (int i = 0; i < n; ++i) {
		vec3 velocity = def->velocities != NULL ? def->velocities[i] : v3(0.0f, 0.0f, 0.0f);
		plait_sim_add_particle(sim, def->positions[i], velocity, def->mass, radius, material, flags);
	}
	plait_world_update_kinds(world);
	return id;
}

static plait_result build_shape(const plait_collider_def *def, const char *label, plait_shape *shape,
                                plait_error *error)
{
	memset(shape, 0, sizeof *shape);
	shape->type = def->shape;
	shape->rotation = m3_identity();
	switch (def->shape) {
	case PLAIT_SHAPE_PLANE: {
		if (!finite3(def->point) || !finite3(def->normal) || v3_length(def->normal) < 1e-12f) {
			return plait_error_set(error, PLAIT_ERROR_INVALID_ARGUMENT,
			                       "%s: a plane needs a finite point and a non-zero normal", label);
		}
		shape->point = def->point;
		shape->normal = v3_normalize(def->normal);
		return PLAIT_OK;
	}
	case PLAIT_SHAPE_SPHERE:
		if (!finite3(def->center) || !(def->radius > 0.0f) || !isfinite(def->radius)) {
			return plait_error_set(error, PLAIT_ERROR_INVALID_ARGUMENT,
			                       "%s: a sphere needs a finite center and radius > 0, got radius %g", label,
			                       (double)def->radius);
		}
		shape->center = def->center;
		shape->radius = def->radius;
		return PLAIT_OK;
	case PLAIT_SHAPE_CAPSULE:
		if (!finite3(def->a) || !finite3(def->b) || !(def->radius > 0.0f) || !isfinite(def->radius)) {
			return plait_error_set(error, PLAIT_ERROR_INVALID_ARGUMENT,
			                       "%s: a capsule needs finite ends a, b and radius > 0, got radius %g",
			                       label, (double)def->radius);
		}
		shape->a = def->a;
		shape->b = def->b;
		shape->radius = def->radius;
		return PLAIT_OK;
	case PLAIT_SHAPE_BOX:
		if (!finite3(def->center) || !finite3(def->rotation_deg) || !(def->size.x > 0.0f) ||
		    !(def->size.y > 0.0f) || !(def->size.z > 0.0f) || !finite3(def->size)) {
			return plait_error_set(
			    error, PLAIT_ERROR_INVALID_ARGUMENT,
			    "%s: a box needs a finite center and rotation and a size > 0 on every axis", label);
		}
		shape->center = def->center;
		shape->half_extents = v3_scale(def->size, 0.5f);
		shape->rotation = m3_from_euler_deg(def->rotation_deg);
		return PLAIT_OK;
	case PLAIT_SHAPE_MESH:
		return PLAIT_OK; /* the mesh is copied and checked when the collider is created */
	}
	return plait_error_set(error, PLAIT_ERROR_INVALID_ARGUMENT, "%s: unknown shape %d", label,
	                       (int)def->shape);
}

static plait_result check_transform(plait_error *error, const char *label, plait_transform t)
{
	if (!finite3(t.translate) || !finite3(t.rotate_deg) || !(t.scale > 0.0f) || !isfinite(t.scale)) {
		return plait_error_set(error, PLAIT_ERROR_INVALID_ARGUMENT,
		                       "%s: transform needs finite translate and rotate and scale > 0", label);
	}
	return PLAIT_OK;
}

/* A mesh or box collider's vertices as pinned particles with a surface of its triangles (see
 * plait_collider.first). Without memory for them the collider still works; cloth then meets
 * it through the cloth's vertices only. */
static void add_collider_surface(plait_world *world, plait_object *object, plait_collider *collider)
{
	plait_sim *sim = &world->sim;
	const plait_shape *shape = &collider->shape;
	const plait_allocator *a = &world->allocator;
	bool box = shape->type == PLAIT_SHAPE_BOX;
	int vertices = box ? 8 : shape->mesh->vertex_count;
	int faces = box ? 6 : shape->mesh->triangle_count, corners = box ? 4 : 3;
	vec3 *positions = plait_alloc(a, sizeof(vec3) * (size_t)vertices);
	int *sizes = plait_alloc(a, sizeof(int) * (size_t)faces);
	int *indices = plait_alloc(a, sizeof(int) * (size_t)(faces * corners));
	plait_mesh_shape *surface = plait_alloc_zero(a, 1, sizeof *surface);
	bool ok = positions != NULL && sizes != NULL && indices != NULL && surface != NULL &&
	          plait_sim_reserve_particles(sim, vertices) && plait_sim_reserve_surfaces(sim, 1);
	if (ok) {
		plait_rigid r = plait_rigid_from_transform(collider->transform_end);
		for (int v = 0; v < vertices; ++v) {
			positions[v] =
			    plait_rigid_apply(&r, box ? plait_shape_box_corner(shape, v) : shape->mesh->positions[v]);
		}
		for (int f = 0; f < faces; ++f) {
			sizes[f] = corners;
			for (int k = 0; k < corners; ++k) {
				indices[f * corners + k] = box ? plait_box_faces[f][k] : shape->mesh->triangles[f][k];
			}
		}
		plait_mesh_def mesh = {positions, vertices, sizes, faces, indices};
		ok = plait_mesh_shape_build(surface, a, &mesh, NULL) == PLAIT_OK;
	}
	if (ok) {
		int first = sim->particles.count;
		for (int v = 0; v < vertices; ++v) {
			/* Massless and pinned: moved only by the collider, never by a contact. */
			(void)plait_sim_add_particle(sim, positions[v], v3(0.0f, 0.0f, 0.0f), 0.0f, collider->thickness,
			                             object->material, PLAIT_PARTICLE_PINNED | PLAIT_PARTICLE_COLLIDE);
		}
		sim->surfaces[sim->surface_count++] =
		    (plait_surface){collider->object, object->material, first, surface};
		object->first_particle = first;
		object->particle_count = vertices;
		collider->first = first;
		collider->count = vertices;
	} else {
		plait_free(a, surface);
	}
	plait_free(a, positions);
	plait_free(a, sizes);
	plait_free(a, indices);
}

plait_object_id plait_create_collider(plait_world_id world_id, const plait_collider_def *def,
                                      plait_error *error)
{
	plait_object_id id = {0};
	plait_world *world = world_id.world;
	plait_error_clear(error);
	if (world == NULL || def == NULL) {
		plait_error_set(error, PLAIT_ERROR_INVALID_ARGUMENT, "plait_create_collider needs a world and a def");
		return id;
	}
	char label[PLAIT_MAX_NAME + 16];
	object_label(label, sizeof label, "collider", def->name);
	plait_shape shape;
	if (build_shape(def, label, &shape, error) != PLAIT_OK ||
	    check_surface(error, label, &def->surface) != PLAIT_OK ||
	    check_transform(error, label, def->transform) != PLAIT_OK) {
		return id;
	}
	if (def->deforming && def->shape != PLAIT_SHAPE_MESH) {
		plait_error_set(error, PLAIT_ERROR_INVALID_ARGUMENT, "%s: only a mesh collider can be deforming",
		                label);
		return id;
	}
	plait_sim *sim = &world->sim;
	if (def->shape == PLAIT_SHAPE_MESH) {
		shape.mesh = plait_alloc_zero(&world->allocator, 1, sizeof *shape.mesh);
		if (shape.mesh == NULL) {
			plait_error_set(error, PLAIT_ERROR_OUT_OF_MEMORY, "%s: out of memory", label);
			return id;
		}
		if (plait_mesh_shape_build(shape.mesh, &world->allocator, &def->mesh, error) != PLAIT_OK) {
			char reason[PLAIT_ERROR_MESSAGE_SIZE];
			snprintf(reason, sizeof reason, "%s", error != NULL ? error->message : "");
			plait_error_set(error, error != NULL ? error->code : PLAIT_ERROR_INVALID_MESH, "%s: %s", label,
			                reason);
			plait_free(&world->allocator, shape.mesh);
			return id;
		}
	}
	/* A deforming mesh starts at rest: the frame's start and end are its own vertices. */
	size_t mesh_bytes = def->deforming ? sizeof(vec3) * (size_t)shape.mesh->vertex_count : 0;
	vec3 *mesh_start = def->deforming ? plait_alloc(&world->allocator, mesh_bytes) : NULL;
	vec3 *mesh_end = def->deforming ? plait_alloc(&world->allocator, mesh_bytes) : NULL;
	plait_object *object = plait_world_new_object(world, PLAIT_OBJECT_COLLIDER, def->name, &id);
	bool ok = object != NULL && plait_sim_reserve_colliders(sim, 1) && plait_sim_reserve_materials(sim, 1) &&
	          (!def->deforming ||
	           (mesh_start != NULL && mesh_end != NULL &&
	            plait_mesh_shape_make_deforming(shape.mesh, &world->allocator, NULL) == PLAIT_OK));
	if (!ok) {
		if (object != NULL) {
			abandon_object(world, object);
		}
		if (shape.mesh != NULL) {
			plait_mesh_shape_destroy(shape.mesh, &world->allocator);
			plait_free(&world->allocator, shape.mesh);
		}
		plait_free(&world->allocator, mesh_start);
		plait_free(&world->allocator, mesh_end);
		plait_error_set(error, PLAIT_ERROR_OUT_OF_MEMORY, "%s: out of memory", label);
		return (plait_object_id){0};
	}
	if (def->deforming) {
		memcpy(mesh_start, shape.mesh->positions, mesh_bytes);
		memcpy(mesh_end, shape.mesh->positions, mesh_bytes);
	}
	object->material = add_material(sim, id.index1 - 1, PLAIT_OBJECT_COLLIDER, &def->surface, 0.0f);
	int k = sim->collider_count++;
	plait_collider *collider = &sim->colliders[k];
	memset(collider, 0, sizeof *collider);
	collider->object = id.index1 - 1;
	collider->shape = shape;
	collider->transform_start = def->transform;
	collider->transform_end = def->transform;
	collider->mesh_start = mesh_start;
	collider->mesh_end = mesh_end;
	collider->thickness = def->surface.thickness;
	collider->friction = def->surface.friction;
	collider->stickiness = def->surface.stickiness;
	collider->bounce = def->surface.bounce;
	collider->collide = def->surface.collide;
	object->collider = k;
	if (collider->collide && (shape.type == PLAIT_SHAPE_MESH || shape.type == PLAIT_SHAPE_BOX)) {
		add_collider_surface(world, object, collider);
	}
	plait_world_update_kinds(world);
	return id;
}

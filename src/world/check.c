/* plait_world_check_intersections: counts crossing cloth triangles with a hierarchy over all of
 * them, built from the current positions. */
#include <string.h>

#include "collision/intersect.h"
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
		if (sim->materials[surface->material].type == PLAIT_OBJECT_COLLIDER &&
		    sim->materials[surface->material].collide) {
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
		if (sim->materials[surface->material].type != PLAIT_OBJECT_COLLIDER ||
		    !sim->materials[surface->material].collide) {
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
	plait_mesh_shape_destroy(&shape, a);
	return PLAIT_OK;
}

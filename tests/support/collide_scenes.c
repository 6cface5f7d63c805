#include "collide_scenes.h"

#include <assert.h>
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

const char *const collide_scene_names[SCENE_COUNT] = {"drape", "thin-box", "pile",
                                                      "twist", "arm",      "hang-self"};

static const float pi = 3.14159265f;

/* A polygon mesh owned by the scene builder. */
typedef struct mesh {
	plait_vec3 *x;
	int vertex_count;
	int *sizes, *indices;
	int face_count;
} mesh;

static mesh mesh_alloc(int vertices, int quads)
{
	mesh m = {malloc(sizeof(plait_vec3) * (size_t)vertices), vertices, malloc(sizeof(int) * (size_t)quads),
	          malloc(sizeof(int) * 4 * (size_t)quads), 0};
	return m;
}

static void mesh_free(mesh *m)
{
	free(m->x);
	free(m->sizes);
	free(m->indices);
	memset(m, 0, sizeof *m);
}

static void add_quad(mesh *m, int a, int b, int c, int d)
{
	m->sizes[m->face_count] = 4;
	int *f = m->indices + 4 * m->face_count++;
	f[0] = a;
	f[1] = b;
	f[2] = c;
	f[3] = d;
}

static plait_mesh_def mesh_def(const mesh *m)
{
	return (plait_mesh_def){m->x, m->vertex_count, m->sizes, m->face_count, m->indices};
}

/* An n x n sheet of side `size` in a horizontal plane at height y, turned by `turn_deg` about
 * the vertical and shifted by (dx, dz). */
static mesh sheet(int n, float size, float y, float turn_deg, float dx, float dz)
{
	mesh m = mesh_alloc(n * n, (n - 1) * (n - 1));
	float c = cosf(turn_deg * pi / 180.0f), s = sinf(turn_deg * pi / 180.0f);
	for (int j = 0; j < n; ++j) {
		for (int i = 0; i < n; ++i) {
			float u = size * ((float)i / (float)(n - 1) - 0.5f),
			      v = size * ((float)j / (float)(n - 1) - 0.5f);
			m.x[j * n + i] = (plait_vec3){c * u - s * v + dx, y, s * u + c * v + dz};
		}
	}
	for (int j = 0; j + 1 < n; ++j) {
		for (int i = 0; i + 1 < n; ++i) {
			int a = j * n + i;
			add_quad(&m, a, a + n, a + n + 1, a + 1);
		}
	}
	return m;
}

/* A tube along x from x0 to x1, `around` vertices round a circle of radius r, `along` rings. */
static mesh tube(int around, int along, float r, float x0, float x1)
{
	mesh m = mesh_alloc(around * along, around * (along - 1));
	for (int j = 0; j < along; ++j) {
		float x = x0 + (x1 - x0) * (float)j / (float)(along - 1);
		for (int i = 0; i < around; ++i) {
			float a = 2.0f * pi * (float)i / (float)around;
			m.x[j * around + i] = (plait_vec3){x, r * cosf(a), r * sinf(a)};
		}
	}
	for (int j = 0; j + 1 < along; ++j) {
		for (int i = 0; i < around; ++i) {
			int next = (i + 1) % around;
			add_quad(&m, j * around + i, j * around + next, (j + 1) * around + next, (j + 1) * around + i);
		}
	}
	return m;
}

/* Appends one face of n vertices (a triangle in a quad slot when n is 3), its vertices after
 * the first in reverse order when `reversed`. */
static void add_face(mesh *m, const int *v, int n, bool reversed)
{
	m->sizes[m->face_count] = n;
	int *f = m->indices + 4 * m->face_count++;
	f[0] = v[0];
	for (int q = 1; q < n; ++q) {
		f[q] = v[reversed ? n - q : q];
	}
}

/* The faces of a closed surface of `rings` rings of `slices` vertices (from vertex 2, ring by
 * ring) between pole vertices 0 and 1: a fan round each pole, quads between rings. Wound
 * counter-clockwise seen from outside when ring 0 runs counter-clockwise seen from pole 0;
 * `reversed` for the other way round. */
static void add_ring_faces(mesh *m, int slices, int rings, bool reversed)
{
	int last = 2 + (rings - 1) * slices;
	for (int i = 0; i < slices; ++i) {
		int next = (i + 1) % slices;
		add_face(m, (int[3]){0, 2 + next, 2 + i}, 3, reversed);
		for (int j = 0; j + 1 < rings; ++j) {
			int a = 2 + j * slices;
			add_face(m, (int[4]){a + i, a + next, a + slices + next, a + slices + i}, 4, reversed);
		}
		add_face(m, (int[3]){1, last + i, last + next}, 3, reversed);
	}
}

/* Triangles stored in quad slots: the index list compacted. */
static void compact_triangles(mesh *m)
{
	int at = 0;
	for (int k = 0; k < m->face_count; ++k) {
		for (int q = 0; q < m->sizes[k]; ++q) {
			m->indices[at++] = m->indices[4 * k + q];
		}
	}
}

/* A capsule round the x axis from x0 to x1, of radius r, as a closed mesh: `slices` vertices
 * round each ring, `cap` rings to each hemisphere's pole, `segments` lengths along the cylinder;
 * every face wound counter-clockwise seen from outside. */
static mesh capsule_mesh(int slices, int cap, int segments, float r, float x0, float x1)
{
	int rings = 2 * cap + segments - 1;
	assert(rings <= 64);
	mesh m = mesh_alloc(2 + rings * slices, slices * (rings + 1));
	float ring_x[64], ring_r[64];
	int count = 0;
	for (int k = 1; k <= cap; ++k) {
		float theta = 0.5f * pi * (float)k / (float)cap;
		ring_x[count] = x0 - r * cosf(theta);
		ring_r[count++] = r * sinf(theta);
	}
	for (int k = 1; k < segments; ++k) {
		ring_x[count] = x0 + (x1 - x0) * (float)k / (float)segments;
		ring_r[count++] = r;
	}
	for (int k = cap; k >= 1; --k) {
		float theta = 0.5f * pi * (float)k / (float)cap;
		ring_x[count] = x1 + r * cosf(theta);
		ring_r[count++] = r * sinf(theta);
	}
	m.x[0] = (plait_vec3){x0 - r, 0.0f, 0.0f};
	m.x[1] = (plait_vec3){x1 + r, 0.0f, 0.0f};
	for (int j = 0; j < rings; ++j) {
		for (int i = 0; i < slices; ++i) {
			float a = 2.0f * pi * (float)i / (float)slices;
			m.x[2 + j * slices + i] = (plait_vec3){ring_x[j], ring_r[j] * cosf(a), ring_r[j] * sinf(a)};
		}
	}
	add_ring_faces(&m, slices, rings, true);
	/* Each face turned to face away from the axis (the winding above is meant to, this makes
	 * sure). */
	for (int k = 0; k < m.face_count; ++k) {
		int *f = m.indices + 4 * k, n = m.sizes[k];
		plait_vec3 a = m.x[f[0]], b = m.x[f[1]], c = m.x[f[2]];
		plait_vec3 u = {b.x - a.x, b.y - a.y, b.z - a.z}, v = {c.x - a.x, c.y - a.y, c.z - a.z};
		plait_vec3 normal = {u.y * v.z - u.z * v.y, u.z * v.x - u.x * v.z, u.x * v.y - u.y * v.x};
		plait_vec3 centre = {0.0f, 0.0f, 0.0f};
		for (int q = 0; q < n; ++q) {
			centre.x += m.x[f[q]].x / (float)n;
			centre.y += m.x[f[q]].y / (float)n;
			centre.z += m.x[f[q]].z / (float)n;
		}
		float axis_x = centre.x < x0 ? x0 : centre.x > x1 ? x1 : centre.x;
		float outward = normal.x * (centre.x - axis_x) + normal.y * centre.y + normal.z * centre.z;
		if (outward < 0.0f) {
			for (int q = 0; q < n / 2; ++q) {
				int t = f[q];
				f[q] = f[n - 1 - q];
				f[n - 1 - q] = t;
			}
		}
	}
	compact_triangles(&m);
	return m;
}

/* A sphere of `slices` x `stacks` (poles as fans of quads with a repeated vertex: triangles). */
static mesh sphere_mesh(int slices, int stacks, float r, plait_vec3 centre)
{
	int vertices = 2 + slices * (stacks - 1);
	mesh m = mesh_alloc(vertices, slices * stacks);
	m.x[0] = (plait_vec3){centre.x, centre.y + r, centre.z};
	m.x[1] = (plait_vec3){centre.x, centre.y - r, centre.z};
	for (int j = 1; j < stacks; ++j) {
		float polar = pi * (float)j / (float)stacks;
		for (int i = 0; i < slices; ++i) {
			float a = 2.0f * pi * (float)i / (float)slices;
			m.x[2 + (j - 1) * slices + i] =
			    (plait_vec3){centre.x + r * sinf(polar) * cosf(a), centre.y + r * cosf(polar),
			                 centre.z + r * sinf(polar) * sinf(a)};
		}
	}
	/* Outward-facing: counter-clockwise seen from outside. */
	add_ring_faces(&m, slices, stacks - 1, false);
	compact_triangles(&m);
	return m;
}

static bool add_cloth(collide_scene *scene, const mesh *m, plait_cloth_def *def, plait_error *error)
{
	def->mesh = mesh_def(m);
	plait_vec3 *shifted = NULL;
	if (scene->options.variant != 0) {
		/* The world copies the mesh: a shifted copy of its positions serves the creation. */
		shifted = malloc(sizeof *shifted * (size_t)m->vertex_count);
		if (shifted == NULL) {
			error->code = PLAIT_ERROR_OUT_OF_MEMORY;
			snprintf(error->message, sizeof error->message, "collide_scene: out of memory");
			return false;
		}
		float k = 1e-3f * (float)scene->options.variant;
		for (int i = 0; i < m->vertex_count; ++i) {
			shifted[i] = (plait_vec3){m->x[i].x + 0.7f * k, m->x[i].y, m->x[i].z + 0.3f * k};
		}
		def->mesh.positions = shifted;
	}
	plait_object_id id = plait_create_cloth(scene->world, def, error);
	free(shifted);
	if (plait_object_id_is_null(id)) {
		return false;
	}
	scene->cloths[scene->cloth_count++] = id;
	return true;
}

/* Keeps a deforming collider's rest vertices (scene->rest), to pose from frame by frame. */
static bool keep_rest(collide_scene *scene, const mesh *m)
{
	size_t size = sizeof(plait_vec3) * (size_t)m->vertex_count;
	scene->rest = malloc(size);
	scene->posed = malloc(size);
	if (scene->rest == NULL || scene->posed == NULL) {
		return false;
	}
	memcpy(scene->rest, m->x, size);
	scene->rest_count = m->vertex_count;
	return true;
}

static bool add_ground(collide_scene *scene, float y, float friction, plait_error *error)
{
	plait_collider_def ground = plait_default_collider_def();
	ground.name = "ground";
	ground.point = (plait_vec3){0.0f, y, 0.0f};
	ground.surface.friction = friction;
	return !plait_object_id_is_null(plait_create_collider(scene->world, &ground, error));
}

static plait_object_id add_sphere(collide_scene *scene, float r, plait_vec3 centre, float friction,
                                  plait_error *error)
{
	plait_collider_def sphere = plait_default_collider_def();
	sphere.name = "sphere";
	sphere.shape = PLAIT_SHAPE_SPHERE;
	sphere.center = centre;
	sphere.radius = r;
	sphere.surface.friction = friction;
	if (!scene->options.mesh_colliders) {
		return plait_create_collider(scene->world, &sphere, error);
	}
	mesh ball = sphere_mesh(40, 40, r, centre);
	sphere.shape = PLAIT_SHAPE_MESH;
	sphere.mesh = mesh_def(&ball);
	sphere.deforming = scene->options.deforming_colliders;
	plait_object_id id = plait_create_collider(scene->world, &sphere, error);
	if (sphere.deforming && !plait_object_id_is_null(id) && !keep_rest(scene, &ball)) {
		id = (plait_object_id){0};
	}
	mesh_free(&ball);
	return id;
}

static bool build(collide_scene *scene, int n, plait_error *error)
{
	plait_cloth_def cloth = plait_default_cloth_def();
	cloth.self_collision_flag = scene->options.self_flag;
	cloth.surface.thickness = 0.01f;
	cloth.surface.friction = 0.3f;
	switch (scene->kind) {
	case SCENE_DRAPE: {
		n = n > 0 ? n : 41;
		scene->frames = 180;
		if (plait_object_id_is_null(add_sphere(scene, 0.5f, (plait_vec3){0, 0, 0}, 0.3f, error)) ||
		    !add_ground(scene, -0.5f, 0.3f, error)) {
			return false;
		}
		cloth.self_collide = true;
		bool ok = true;
		for (int k = 0; k < 2 && ok; ++k) {
			mesh m = sheet(n, 1.6f, 0.6f + 0.15f * (float)k, 17.0f * (float)k, 0.03f * (float)k, 0.0f);
			ok = add_cloth(scene, &m, &cloth, error);
			mesh_free(&m);
		}
		return ok;
	}
	case SCENE_THIN_BOX: {
		n = n > 0 ? n : 32;
		scene->frames = 60;
		plait_collider_def box = plait_default_collider_def();
		box.name = "thin box";
		box.shape = PLAIT_SHAPE_BOX;
		box.center = (plait_vec3){0.0f, 0.0f, 0.0f};
		box.size = (plait_vec3){0.6f, 0.001f, 0.6f};
		box.surface.friction = 0.3f;
		if (plait_object_id_is_null(plait_create_collider(scene->world, &box, error)) ||
		    !add_ground(scene, -0.6f, 0.3f, error)) {
			return false;
		}
		mesh m = sheet(n, 1.0f, 0.3f, 10.0f, 0.0f, 0.0f);
		plait_vec3 *v = malloc(sizeof *v * (size_t)m.vertex_count);
		for (int i = 0; i < m.vertex_count; ++i) {
			v[i] = (plait_vec3){0.0f, -20.0f, 0.0f};
		}
		cloth.velocities = v;
		cloth.self_collide = true;
		bool ok = add_cloth(scene, &m, &cloth, error);
		free(v);
		mesh_free(&m);
		return ok;
	}
	case SCENE_PILE: {
		n = n > 0 ? n : 64;
		scene->frames = 180;
		if (!add_ground(scene, 0.0f, 0.4f, error)) {
			return false;
		}
		cloth.self_collide = true;
		bool ok = true;
		if (scene->options.coarse_floor) {
			mesh m = sheet(3, 1.2f, 0.02f, 0.0f, 0.0f, 0.0f);
			int corners[4] = {0, 2, 6, 8};
			plait_cloth_def floor = cloth;
			floor.pins = corners;
			floor.pin_count = 4;
			ok = add_cloth(scene, &m, &floor, error);
			mesh_free(&m);
		}
		for (int k = 0; k < 4 && ok; ++k) {
			mesh m = sheet(n, 1.0f, 0.1f + 0.15f * (float)k, 23.0f * (float)k, 0.07f * (float)(k % 2),
			               -0.05f * (float)(k / 2));
			ok = add_cloth(scene, &m, &cloth, error);
			mesh_free(&m);
		}
		return ok;
	}
	case SCENE_TWIST: {
		n = n > 0 ? n : 64;
		scene->frames = 600;
		scene->animated = add_sphere(scene, 0.5f, (plait_vec3){0, 0, 0}, 0.8f, error);
		if (plait_object_id_is_null(scene->animated) || !add_ground(scene, -0.5f, 0.3f, error)) {
			return false;
		}
		cloth.self_collide = true;
		cloth.surface.friction = 0.8f;
		mesh m = sheet(n, 1.6f, 0.55f, 0.0f, 0.0f, 0.0f);
		bool ok = add_cloth(scene, &m, &cloth, error);
		mesh_free(&m);
		return ok;
	}
	case SCENE_ARM: {
		n = n > 0 ? n : 40;
		scene->frames = 240;
		float r = 0.06f;
		plait_collider_def upper = plait_default_collider_def();
		upper.name = "upper arm";
		upper.shape = PLAIT_SHAPE_CAPSULE;
		upper.a = (plait_vec3){-0.4f, 0.0f, 0.0f};
		upper.b = (plait_vec3){0.0f, 0.0f, 0.0f};
		upper.radius = r;
		upper.surface.friction = 0.5f;
		plait_collider_def fore = upper;
		fore.name = "forearm";
		fore.a = (plait_vec3){0.0f, 0.0f, 0.0f};
		fore.b = (plait_vec3){0.35f, 0.0f, 0.0f};
		mesh upper_mesh = {0}, fore_mesh = {0};
		if (scene->options.deforming_colliders) {
			/* One closed mesh of the whole arm, rings 1.5 cm apart, bent frame by frame. */
			mesh arm = capsule_mesh(24, 4, 50, r, -0.4f, 0.35f);
			upper.name = "arm";
			upper.shape = PLAIT_SHAPE_MESH;
			upper.mesh = mesh_def(&arm);
			upper.deforming = true;
			scene->animated = plait_create_collider(scene->world, &upper, error);
			bool kept = !plait_object_id_is_null(scene->animated) && keep_rest(scene, &arm);
			mesh_free(&arm);
			if (!kept) {
				return false;
			}
		} else if (scene->options.mesh_colliders) {
			upper_mesh = capsule_mesh(24, 4, 12, r, -0.4f, 0.0f);
			fore_mesh = capsule_mesh(24, 4, 12, r, 0.0f, 0.35f);
			upper.shape = fore.shape = PLAIT_SHAPE_MESH;
			upper.mesh = mesh_def(&upper_mesh);
			fore.mesh = mesh_def(&fore_mesh);
		}
		if (scene->options.box_colliders) {
			/* Square bars 10 cm across: their edges 7.1 cm from the axis, 1.4 cm inside the
			 * sleeve. */
			upper.shape = fore.shape = PLAIT_SHAPE_BOX;
			upper.center = (plait_vec3){-0.2f, 0.0f, 0.0f};
			upper.size = (plait_vec3){0.4f, 0.1f, 0.1f};
			fore.center = (plait_vec3){0.175f, 0.0f, 0.0f};
			fore.size = (plait_vec3){0.35f, 0.1f, 0.1f};
		}
		if (!scene->options.deforming_colliders) {
			bool made = !plait_object_id_is_null(plait_create_collider(scene->world, &upper, error));
			scene->animated = made ? plait_create_collider(scene->world, &fore, error) : (plait_object_id){0};
		}
		mesh_free(&upper_mesh);
		mesh_free(&fore_mesh);
		if (plait_object_id_is_null(scene->animated)) {
			return false;
		}
		mesh m = tube(n, n, r + 0.025f, -0.25f, 0.25f);
		int *pins = malloc(sizeof(int) * (size_t)n);
		for (int i = 0; i < n; ++i) {
			pins[i] = i; /* the ring at the shoulder end */
		}
		cloth.pins = pins;
		cloth.pin_count = n;
		cloth.self_collide = true;
		cloth.surface.thickness = 0.005f;
		bool ok = add_cloth(scene, &m, &cloth, error);
		free(pins);
		mesh_free(&m);
		return ok;
	}
	case SCENE_HANG_SELF: {
		n = n > 0 ? n : 128;
		scene->frames = 300;
		int slices = scene->options.sphere_slices > 0 ? scene->options.sphere_slices : 50;
		float radius = scene->options.sphere_radius > 0.0f ? scene->options.sphere_radius : 0.5f;
		mesh ball = sphere_mesh(slices, slices, radius, (plait_vec3){0.0f, -0.25f - radius, 0.0f});
		plait_collider_def sphere = plait_default_collider_def();
		sphere.name = "sphere mesh";
		sphere.shape = PLAIT_SHAPE_MESH;
		sphere.mesh = mesh_def(&ball);
		sphere.surface.thickness = 0.0f;
		bool ok = !plait_object_id_is_null(plait_create_collider(scene->world, &sphere, error));
		mesh_free(&ball);
		if (!ok) {
			return false;
		}
		mesh m = sheet(n, 2.0f, 0.0f, 0.0f, 0.0f, 0.0f);
		float *masses = malloc(sizeof(float) * (size_t)m.vertex_count);
		for (int i = 0; i < m.vertex_count; ++i) {
			masses[i] = 1.0f;
		}
		int pins[2] = {0, n - 1};
		cloth.vertex_masses = masses;
		cloth.pins = pins;
		cloth.pin_count = 2;
		cloth.self_collide = true;
		if (scene->options.stiff) {
			cloth.stretch_resistance = cloth.compression_resistance = 10000.0f;
			cloth.shear_resistance = cloth.bend_resistance = 10000.0f;
			cloth.bend_model = PLAIT_BEND_DISTANCE;
			int sweeps = scene->options.stiff_substeps > 0 ? scene->options.stiff_substeps : 6;
			cloth.iterations = cloth.shear_iterations = cloth.bend_iterations = sweeps;
			cloth.tethers = PLAIT_TETHER_EUCLIDEAN;
		}
		cloth.surface.thickness = scene->options.thickness_per_edge > 0.0f
		                              ? scene->options.thickness_per_edge * 2.0f / (float)(n - 1)
		                              : 0.004f;
		ok = add_cloth(scene, &m, &cloth, error);
		free(masses);
		mesh_free(&m);
		return ok;
	}
	default:
		return false;
	}
}

bool collide_scene_create(collide_scene *scene, collide_scene_kind kind, int n, const plait_world_def *base,
                          plait_error *error)
{
	collide_scene_options options = collide_scene_default_options();
	return collide_scene_create_with(scene, kind, n, base, &options, error);
}

collide_scene_options collide_scene_default_options(void)
{
	return (collide_scene_options){.self_flag = plait_default_cloth_def().self_collision_flag,
	                               .contact_pass_interval = -1};
}

bool collide_scene_create_with(collide_scene *scene, collide_scene_kind kind, int n,
                               const plait_world_def *base, const collide_scene_options *options,
                               plait_error *error)
{
	memset(scene, 0, sizeof *scene);
	scene->kind = kind;
	scene->options = *options;
	plait_world_def def = base != NULL ? *base : plait_default_world_def();
	if (kind == SCENE_HANG_SELF && options->stiff) {
		def.substeps = options->stiff_substeps > 0 ? options->stiff_substeps : 6;
	}
	def.fps = 60.0f;
	def.air_density = 0.0f;
	if (options->contact_pass_interval >= 0) {
		def.contact_pass_interval = options->contact_pass_interval;
	}
	scene->fps = def.fps;
	scene->world = plait_create_world(&def, error);
	if (plait_world_id_is_null(scene->world)) {
		return false;
	}
	if (!build(scene, n, error)) {
		plait_destroy_world(scene->world);
		free(scene->rest);
		free(scene->posed);
		memset(scene, 0, sizeof *scene);
		return false;
	}
	return true;
}

/* The skinned arm's vertex at rest position x (along the arm's axis, x) with its elbow bent by
 * `angle` radians about z: the axis runs straight to the start of a 20 cm arc round the elbow
 * (x = 0), along the arc, then straight on; each ring keeps its place across the axis, turned
 * with it. The arc's radius (at least 10 cm) is wider than the arm (6 cm), so the bent mesh
 * never passes through itself. */
static plait_vec3 bend_arm(plait_vec3 x, float angle)
{
	const float arc = 0.2f, start = -0.5f * arc;
	if (!(angle > 1e-4f) || x.x <= start) {
		return x;
	}
	float radius = arc / angle;
	float along = x.x - start, phi = along < arc ? along / radius : angle;
	float beyond = along < arc ? 0.0f : along - arc;
	float c = cosf(phi), s = sinf(phi);
	/* The axis point, then the ring's offset: y along the arc's inward normal (-s, c), z as is. */
	float ax = start + radius * s + beyond * c, ay = radius * (1.0f - c) + beyond * s;
	return (plait_vec3){ax - x.y * s, ay + x.y * c, x.z};
}

plait_result collide_scene_step(collide_scene *scene, plait_error *error)
{
	int frame = ++scene->frame; /* the frame being made */
	float t = (float)frame / scene->fps;
	if (scene->kind == SCENE_TWIST) {
		/* Still for a second while the cloth settles, then half a turn per second. */
		float angle = t < 1.0f ? 0.0f : 180.0f * (t - 1.0f);
		plait_result result;
		if (scene->rest != NULL) {
			/* The same turn about the vertical, vertex by vertex (the sphere is at the origin). */
			float c = cosf(angle * pi / 180.0f), s = sinf(angle * pi / 180.0f);
			for (int v = 0; v < scene->rest_count; ++v) {
				plait_vec3 x = scene->rest[v];
				scene->posed[v] = (plait_vec3){c * x.x + s * x.z, x.y, -s * x.x + c * x.z};
			}
			result =
			    plait_collider_set_mesh_positions(scene->animated, scene->posed, scene->rest_count, error);
		} else {
			plait_transform spin = plait_identity_transform();
			spin.rotate_deg = (plait_vec3){0.0f, angle, 0.0f};
			result = plait_collider_set_transform(scene->animated, spin, error);
		}
		if (result != PLAIT_OK) {
			return result;
		}
	}
	if (scene->kind == SCENE_ARM) {
		/* Bends to 110 degrees over 1.5 s after half a second, holds, straightens again. */
		float phase = t < 0.5f   ? 0.0f
		              : t < 2.0f ? (t - 0.5f) / 1.5f
		              : t < 2.5f ? 1.0f
		              : t < 4.0f ? (4.0f - t) / 1.5f
		                         : 0.0f;
		plait_result result;
		if (scene->rest != NULL) {
			for (int v = 0; v < scene->rest_count; ++v) {
				scene->posed[v] = bend_arm(scene->rest[v], 110.0f * phase * pi / 180.0f);
			}
			result =
			    plait_collider_set_mesh_positions(scene->animated, scene->posed, scene->rest_count, error);
		} else {
			plait_transform bend = plait_identity_transform();
			bend.rotate_deg = (plait_vec3){0.0f, 0.0f, 110.0f * phase};
			result = plait_collider_set_transform(scene->animated, bend, error);
		}
		if (result != PLAIT_OK) {
			return result;
		}
	}
	return plait_world_step(scene->world, error);
}

void collide_scene_destroy(collide_scene *scene)
{
	if (!plait_world_id_is_null(scene->world)) {
		plait_destroy_world(scene->world);
	}
	free(scene->rest);
	free(scene->posed);
	memset(scene, 0, sizeof *scene);
}

/* ---- Order of stacked cloths ------------------------------------------------------------- */

/* Where a vertex lies as seen along the scene's lines of sight: a point in a plane and a depth
 * along the line (larger: further out or higher). False outside the region looked at. */
static bool project(const collide_scene *scene, plait_vec3 x, float *u, float *v, float *depth)
{
	if (scene->kind == SCENE_DRAPE) {
		/* Lines from the sphere's centre, over the cap within 50 degrees of the top. */
		float length = sqrtf(x.x * x.x + x.y * x.y + x.z * x.z);
		if (!(x.y > 0.64f * length)) {
			return false;
		}
		*u = x.x / x.y;
		*v = x.z / x.y;
		*depth = length;
		return true;
	}
	*u = x.x;
	*v = x.z;
	*depth = x.y;
	return true;
}

typedef struct flat_triangle {
	float u[3], v[3], depth[3];
} flat_triangle;

/* The depth of the triangle at (u, v), if (u, v) is inside it. */
static bool depth_at(const flat_triangle *t, float u, float v, float *depth)
{
	float d = (t->v[1] - t->v[2]) * (t->u[0] - t->u[2]) + (t->u[2] - t->u[1]) * (t->v[0] - t->v[2]);
	if (fabsf(d) < 1e-12f) {
		return false;
	}
	float a = ((t->v[1] - t->v[2]) * (u - t->u[2]) + (t->u[2] - t->u[1]) * (v - t->v[2])) / d;
	float b = ((t->v[2] - t->v[0]) * (u - t->u[2]) + (t->u[0] - t->u[2]) * (v - t->v[2])) / d;
	float c = 1.0f - a - b;
	if (a < 0.0f || b < 0.0f || c < 0.0f) {
		return false;
	}
	*depth = a * t->depth[0] + b * t->depth[1] + c * t->depth[2];
	return true;
}

#define BINS 48

int collide_scene_order_violations(const collide_scene *scene)
{
	if (scene->kind != SCENE_DRAPE && scene->kind != SCENE_PILE) {
		return 0;
	}
	int violations = 0;
	for (int lower = 0; lower < scene->cloth_count; ++lower) {
		plait_object_id low = scene->cloths[lower];
		int nv = plait_object_get_vertex_count(low);
		int nt = plait_object_get_triangles(low, NULL, 0);
		plait_vec3 *x = malloc(sizeof *x * (size_t)nv);
		int *tri = malloc(sizeof(int) * 3 * (size_t)nt);
		flat_triangle *flat = malloc(sizeof *flat * (size_t)nt);
		bool *valid = calloc((size_t)nt, sizeof(bool));
		plait_object_get_positions(low, 0, nv, x, NULL);
		plait_object_get_triangles(low, tri, nt);
		float lo_u = INFINITY, lo_v = INFINITY, hi_u = -INFINITY, hi_v = -INFINITY;
		for (int t = 0; t < nt; ++t) {
			valid[t] = true;
			for (int k = 0; k < 3; ++k) {
				valid[t] = valid[t] &&
				           project(scene, x[tri[3 * t + k]], &flat[t].u[k], &flat[t].v[k], &flat[t].depth[k]);
			}
			for (int k = 0; k < 3 && valid[t]; ++k) {
				lo_u = fminf(lo_u, flat[t].u[k]);
				hi_u = fmaxf(hi_u, flat[t].u[k]);
				lo_v = fminf(lo_v, flat[t].v[k]);
				hi_v = fmaxf(hi_v, flat[t].v[k]);
			}
		}
		/* Triangles binned over a grid of the plane, so each vertex looks at a few. */
		int *count = calloc(BINS * BINS + 1, sizeof(int));
		float su = BINS / fmaxf(hi_u - lo_u, 1e-6f), sv = BINS / fmaxf(hi_v - lo_v, 1e-6f);
		for (int pass = 0; pass < 2; ++pass) {
			int *list = pass == 1 ? malloc(sizeof(int) * (size_t)(count[BINS * BINS] + 1)) : NULL;
			int *fill = pass == 1 ? calloc(BINS * BINS, sizeof(int)) : NULL;
			for (int t = 0; t < nt; ++t) {
				if (!valid[t]) {
					continue;
				}
				int u0 = (int)((fminf(fminf(flat[t].u[0], flat[t].u[1]), flat[t].u[2]) - lo_u) * su);
				int u1 = (int)((fmaxf(fmaxf(flat[t].u[0], flat[t].u[1]), flat[t].u[2]) - lo_u) * su);
				int v0 = (int)((fminf(fminf(flat[t].v[0], flat[t].v[1]), flat[t].v[2]) - lo_v) * sv);
				int v1 = (int)((fmaxf(fmaxf(flat[t].v[0], flat[t].v[1]), flat[t].v[2]) - lo_v) * sv);
				for (int bu = u0 < 0 ? 0 : u0; bu <= (u1 < BINS ? u1 : BINS - 1); ++bu) {
					for (int bv = v0 < 0 ? 0 : v0; bv <= (v1 < BINS ? v1 : BINS - 1); ++bv) {
						int b = bu * BINS + bv;
						if (pass == 0) {
							count[b] += 1;
						} else {
							list[count[b] + fill[b]++] = t;
						}
					}
				}
			}
			if (pass == 0) {
				/* Prefix sums: count[b] becomes the start of bin b. */
				int total = 0;
				for (int b = 0; b < BINS * BINS; ++b) {
					int c = count[b];
					count[b] = total;
					total += c;
				}
				count[BINS * BINS] = total;
				continue;
			}
			for (int upper = lower + 1; upper < scene->cloth_count; ++upper) {
				plait_object_id up = scene->cloths[upper];
				int nu = plait_object_get_vertex_count(up);
				plait_vec3 *y = malloc(sizeof *y * (size_t)nu);
				plait_object_get_positions(up, 0, nu, y, NULL);
				for (int i = 0; i < nu; ++i) {
					float u, v, depth;
					if (!project(scene, y[i], &u, &v, &depth)) {
						continue;
					}
					int bu = (int)((u - lo_u) * su), bv = (int)((v - lo_v) * sv);
					if (bu < 0 || bv < 0 || bu >= BINS || bv >= BINS) {
						continue;
					}
					int b = bu * BINS + bv;
					int end = b + 1 < BINS * BINS ? count[b + 1] : count[BINS * BINS];
					for (int k = count[b]; k < end; ++k) {
						float under;
						/* Beneath the lower cloth by more than a thickness: out of order. */
						if (depth_at(&flat[list[k]], u, v, &under) && depth < under - 0.01f) {
							++violations;
							break;
						}
					}
				}
				free(y);
			}
			free(list);
			free(fill);
		}
		free(count);
		free(valid);
		free(flat);
		free(tri);
		free(x);
	}
	return violations;
}

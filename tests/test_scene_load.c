/* Valid scenes load with the values they give and the API's defaults for the rest. */
#include "demo_scene.h"
#include "grid.h"
#include "scene.h"
#include "scene_keys.h"

#include <criterion/criterion.h>
#include <dirent.h>
#include <jansson.h>
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#define DATA_DIR PLAIT_SOURCE_DIR "/tests/data"

static void load(const char *json, plait_scene *scene)
{
	plait_tool_error error = {{0}};
	cr_assert(plait_scene_load_string(json, "scene.json", DATA_DIR, scene, &error), "%s", error.message);
}

static void expect_vec3(plait_vec3 v, float x, float y, float z)
{
	cr_expect_float_eq(v.x, x, 1e-6f, "x: %g != %g", v.x, x);
	cr_expect_float_eq(v.y, y, 1e-6f, "y: %g != %g", v.y, y);
	cr_expect_float_eq(v.z, z, 1e-6f, "z: %g != %g", v.z, z);
}

static const char *full_scene =
    "{\n"
    "  \"world\": {\"fps\": 30, \"substeps\": 5, \"max_collision_iterations\": 6, \"gravity\": [0, -10, 0],\n"
    "            \"air_density\": 1.2, \"wind\": {\"speed\": 3, \"direction\": [1, 0, 0], \"noise\": 0.5},\n"
    "            \"space_scale\": 0.01, \"time_scale\": 2, \"seed\": 7, \"untangle\": false},\n"
    "  \"frames\": 48,\n"
    "  \"objects\": [\n"
    "    {\"name\": \"flag\", \"type\": \"cloth\", \"grid\": {\"size\": [2, 1], \"resolution\": [4, 2],\n"
    "     \"center\": [0, 1, 0]}, \"density\": 0.3, \"stretch_resistance\": 80, \"compression_resistance\": "
    "20,\n"
    "     \"shear_resistance\": 15, \"bend_resistance\": 0.5, \"rest_length_scale\": 0.9, \"drag\": 0.1,\n"
    "     \"tangential_drag\": 0.02, \"lift\": 0.2, \"damp\": 0.5, \"friction\": 0.4, \"stickiness\": 0.1,\n"
    "     \"bounce\": 0.2, \"thickness\": 0.02, \"collide\": false, \"pins\": [4, 0, 0],\n"
    "     \"velocities\": [1, 2, 3]},\n"
    "    {\"name\": \"rope\", \"type\": \"curve\", \"positions\": [[0,2,0], [0.1,2,0], [0.2,2,0]],\n"
    "     \"mass\": 0.05, \"bend_resistance\": 2, \"pins\": [0], \"velocities\": [[0,0,0], [0,0,1], "
    "[0,0,2]]},\n"
    "    {\"type\": \"particles\", \"positions\": [[0,3,0], [1,3,0]], \"mass\": 0.5, \"radius\": 0.1,\n"
    "     \"self_collide\": false, \"drag\": 0.3},\n"
    "    {\"name\": \"ball\", \"type\": \"collider\", \"shape\": \"sphere\", \"center\": [0, 0.5, 0],\n"
    "     \"radius\": 0.5, \"damp\": 3, \"keyframes\": [\n"
    "       {\"frame\": 10, \"translate\": [0, 0, 0]},\n"
    "       {\"frame\": 20, \"translate\": [1, 0, 0], \"rotate\": [0, 90, 0], \"scale\": 2}]}\n"
    "  ]\n"
    "}\n";

Test(scene_load, world_values)
{
	plait_scene scene;
	load(full_scene, &scene);
	cr_expect_float_eq(scene.world.fps, 30.0f, 1e-6f);
	cr_expect_eq(scene.world.substeps, 5);
	cr_expect_eq(scene.world.max_collision_iterations, 6);
	expect_vec3(scene.world.gravity, 0, -10, 0);
	cr_expect_float_eq(scene.world.air_density, 1.2f, 1e-6f);
	cr_expect_float_eq(scene.world.wind.speed, 3.0f, 1e-6f);
	expect_vec3(scene.world.wind.direction, 1, 0, 0);
	cr_expect_float_eq(scene.world.wind.noise, 0.5f, 1e-6f);
	cr_expect_float_eq(scene.world.space_scale, 0.01f, 1e-9f);
	cr_expect_float_eq(scene.world.time_scale, 2.0f, 1e-6f);
	cr_expect_eq(scene.world.seed, 7u);
	cr_expect(!scene.world.untangle);
	cr_expect_eq(scene.frames, 48);
	cr_expect_eq(scene.object_count, 4);
	cr_expect_eq(scene.warning_count, 0);
	plait_scene_free(&scene);
}

Test(scene_load, cloth_values)
{
	plait_scene scene;
	load(full_scene, &scene);
	const plait_scene_object *o = &scene.objects[0];
	cr_expect_eq(o->type, PLAIT_OBJECT_CLOTH);
	cr_expect_str_eq(o->name, "flag");
	const plait_cloth_def *c = &o->cloth;
	cr_expect_float_eq(c->density, 0.3f, 1e-6f);
	cr_expect_float_eq(c->stretch_resistance, 80.0f, 1e-6f);
	cr_expect_float_eq(c->compression_resistance, 20.0f, 1e-6f);
	cr_expect_float_eq(c->shear_resistance, 15.0f, 1e-6f);
	cr_expect_float_eq(c->bend_resistance, 0.5f, 1e-6f);
	cr_expect_float_eq(c->rest_length_scale, 0.9f, 1e-6f);
	cr_expect_float_eq(c->drag, 0.1f, 1e-6f);
	cr_expect_float_eq(c->tangential_drag, 0.02f, 1e-6f);
	cr_expect_float_eq(c->lift, 0.2f, 1e-6f);
	cr_expect_float_eq(c->damp, 0.5f, 1e-6f);
	cr_expect_float_eq(c->surface.friction, 0.4f, 1e-6f);
	cr_expect_float_eq(c->surface.stickiness, 0.1f, 1e-6f);
	cr_expect_float_eq(c->surface.bounce, 0.2f, 1e-6f);
	cr_expect_float_eq(c->surface.thickness, 0.02f, 1e-6f);
	cr_expect(!c->surface.collide);
	// Pins are sorted and a repeated vertex is pinned once.
	cr_assert_eq(o->pin_count, 2);
	cr_expect_eq(o->pins[0], 0);
	cr_expect_eq(o->pins[1], 4);
	// One velocity given for all vertices.
	cr_assert_not_null(o->velocities);
	expect_vec3(o->velocities[o->vertex_count - 1], 1, 2, 3);
	plait_scene_free(&scene);
}

Test(scene_load, grid_layout)
{
	plait_scene scene;
	load(full_scene, &scene);
	const plait_scene_object *o = &scene.objects[0];
	// 4x2 quads: 5x3 vertices, vertex (i, j) at j*5+i; size[0] along X, size[1] along Z.
	cr_assert_eq(o->vertex_count, 15);
	cr_assert_eq(o->face_count, 8);
	cr_assert_eq(o->index_count, 32);
	expect_vec3(o->positions[0], -1.0f, 1.0f, -0.5f);
	expect_vec3(o->positions[4], 1.0f, 1.0f, -0.5f);
	expect_vec3(o->positions[1 * 5 + 2], 0.0f, 1.0f, 0.0f);
	expect_vec3(o->positions[14], 1.0f, 1.0f, 0.5f);
	for (int f = 0; f < o->face_count; ++f)
		cr_expect_eq(o->face_sizes[f], 4);
	// Faces wind counter-clockwise seen from +Y (the default normal).
	plait_vec3 a = o->positions[o->face_indices[0]], b = o->positions[o->face_indices[1]],
	           c = o->positions[o->face_indices[2]];
	float ny = (b.z - a.z) * (c.x - a.x) - (b.x - a.x) * (c.z - a.z);
	cr_expect_gt(ny, 0.0f);
	plait_scene_free(&scene);
}

Test(scene_load, grid_with_other_normal)
{
	plait_scene scene;
	load("{\"objects\": [{\"type\": \"cloth\", \"grid\": {\"size\": [2, 1], \"resolution\": [2, 2],"
	     " \"center\": [0, 1, 0], \"normal\": [0, 0, 2]}}]}",
	     &scene);
	const plait_scene_object *o = &scene.objects[0];
	// Every vertex lies in the plane z = 0 through the center, and the faces face +Z.
	for (int i = 0; i < o->vertex_count; ++i)
		cr_expect_float_eq(o->positions[i].z, 0.0f, 1e-6f);
	plait_vec3 a = o->positions[o->face_indices[0]], b = o->positions[o->face_indices[1]],
	           c = o->positions[o->face_indices[2]];
	float nz = (b.x - a.x) * (c.y - a.y) - (b.y - a.y) * (c.x - a.x);
	cr_expect_gt(nz, 0.0f);
	// size[0] still runs along X.
	expect_vec3(o->positions[0], -1.0f, o->positions[0].y, 0.0f);
	plait_scene_free(&scene);
}

Test(scene_load, curve_particles_collider_values)
{
	plait_scene scene;
	load(full_scene, &scene);
	const plait_scene_object *rope = &scene.objects[1];
	cr_expect_eq(rope->type, PLAIT_OBJECT_CURVE);
	cr_expect_eq(rope->vertex_count, 3);
	cr_expect_float_eq(rope->curve.mass, 0.05f, 1e-6f);
	cr_expect_float_eq(rope->curve.bend_resistance, 2.0f, 1e-6f);
	cr_expect_eq(rope->pin_count, 1);
	expect_vec3(rope->velocities[2], 0, 0, 2);

	const plait_scene_object *dots = &scene.objects[2];
	cr_expect_eq(dots->type, PLAIT_OBJECT_PARTICLES);
	cr_expect_str_eq(dots->name, "particles2");
	cr_expect_eq(dots->vertex_count, 2);
	cr_expect_float_eq(dots->particles.mass, 0.5f, 1e-6f);
	cr_expect_float_eq(dots->particles.radius, 0.1f, 1e-6f);
	cr_expect_float_eq(dots->particles.drag, 0.3f, 1e-6f);
	cr_expect(!dots->particles.self_collide);
	cr_expect_null(dots->velocities);

	const plait_scene_object *ball = &scene.objects[3];
	cr_expect_eq(ball->type, PLAIT_OBJECT_COLLIDER);
	cr_expect_eq(ball->collider.shape, PLAIT_SHAPE_SPHERE);
	expect_vec3(ball->collider.center, 0, 0.5f, 0);
	cr_expect_float_eq(ball->collider.radius, 0.5f, 1e-6f);
	cr_expect_eq(ball->keyframe_count, 2);
	plait_scene_free(&scene);
}

Test(scene_load, defaults_come_from_the_api)
{
	plait_scene scene;
	load("{\"objects\": [{\"type\": \"cloth\", \"grid\": {\"size\": [1, 1], \"resolution\": [1, 1]}},"
	     " {\"type\": \"curve\", \"positions\": [[0,0,0], [1,0,0]]},"
	     " {\"type\": \"particles\", \"positions\": [[0,0,0]]},"
	     " {\"type\": \"collider\", \"shape\": \"plane\"}]}",
	     &scene);
	plait_world_def world = plait_default_world_def();
	cr_expect_float_eq(scene.world.fps, world.fps, 0.0f);
	cr_expect_eq(scene.world.substeps, world.substeps);
	cr_expect_eq(scene.world.max_collision_iterations, world.max_collision_iterations);
	expect_vec3(scene.world.gravity, world.gravity.x, world.gravity.y, world.gravity.z);
	cr_expect_float_eq(scene.world.air_density, world.air_density, 0.0f);
	cr_expect_float_eq(scene.world.wind.speed, world.wind.speed, 0.0f);
	cr_expect_float_eq(scene.world.space_scale, world.space_scale, 0.0f);
	cr_expect(scene.world.untangle && world.untangle);
	cr_expect_eq(scene.world.internal_value, world.internal_value);
	cr_expect_eq(scene.frames, PLAIT_SCENE_DEFAULT_FRAMES);
	plait_cloth_def cloth = plait_default_cloth_def();
	cr_expect_float_eq(scene.objects[0].cloth.density, cloth.density, 0.0f);
	cr_expect_float_eq(scene.objects[0].cloth.stretch_resistance, cloth.stretch_resistance, 0.0f);
	cr_expect_float_eq(scene.objects[0].cloth.bend_resistance, cloth.bend_resistance, 0.0f);
	cr_expect_float_eq(scene.objects[0].cloth.lift, cloth.lift, 0.0f);
	cr_expect_float_eq(scene.objects[0].cloth.surface.friction, cloth.surface.friction, 0.0f);
	cr_expect_float_eq(scene.objects[0].cloth.surface.thickness, cloth.surface.thickness, 0.0f);
	cr_expect_eq(scene.objects[0].cloth.surface.collide, cloth.surface.collide);
	cr_expect_eq(scene.objects[0].cloth.bend_model, cloth.bend_model);
	cr_expect_eq(scene.objects[0].cloth.iterations, cloth.iterations);
	cr_expect_eq(scene.objects[0].cloth.shear_iterations, cloth.shear_iterations);
	cr_expect_eq(scene.objects[0].cloth.bend_iterations, cloth.bend_iterations);
	cr_expect_eq(scene.objects[0].cloth.self_collision_flag, cloth.self_collision_flag);
	cr_expect_float_eq(scene.objects[0].cloth.self_collide_width_scale, cloth.self_collide_width_scale, 0.0f);
	cr_expect_eq(scene.objects[0].cloth.surface.collision_layer, cloth.surface.collision_layer);
	plait_curve_def curve = plait_default_curve_def();
	cr_expect_float_eq(scene.objects[1].curve.mass, curve.mass, 0.0f);
	cr_expect_float_eq(scene.objects[1].curve.stretch_resistance, curve.stretch_resistance, 0.0f);
	cr_expect_eq(scene.objects[1].curve.surface.collision_layer, curve.surface.collision_layer);
	plait_particles_def particles = plait_default_particles_def();
	cr_expect_float_eq(scene.objects[2].particles.mass, particles.mass, 0.0f);
	cr_expect_float_eq(scene.objects[2].particles.radius, particles.radius, 0.0f);
	cr_expect_eq(scene.objects[2].particles.self_collide, particles.self_collide);
	cr_expect_eq(scene.objects[2].particles.surface.collision_layer, particles.surface.collision_layer);
	plait_collider_def collider = plait_default_collider_def();
	expect_vec3(scene.objects[3].collider.normal, collider.normal.x, collider.normal.y, collider.normal.z);
	cr_expect_eq(scene.objects[3].collider.surface.collision_layer, collider.surface.collision_layer);
	cr_expect_float_eq(scene.objects[3].collider.transform.scale, 1.0f, 0.0f);
	cr_expect_str_eq(scene.objects[0].name, "cloth0");
	cr_expect_str_eq(scene.objects[3].name, "collider3");
	plait_scene_free(&scene);
}

Test(scene_load, keyframes_interpolate_and_hold)
{
	plait_scene scene;
	load(full_scene, &scene);
	const plait_scene_object *ball = &scene.objects[3];
	plait_transform t = plait_scene_collider_transform(ball, 0);
	expect_vec3(t.translate, 0, 0, 0);
	cr_expect_float_eq(t.scale, 1.0f, 1e-6f);
	// The initial transform is the one at frame 0.
	expect_vec3(ball->collider.transform.translate, 0, 0, 0);
	t = plait_scene_collider_transform(ball, 15);
	expect_vec3(t.translate, 0.5f, 0, 0);
	expect_vec3(t.rotate_deg, 0, 45, 0);
	cr_expect_float_eq(t.scale, 1.5f, 1e-6f);
	t = plait_scene_collider_transform(ball, 20);
	expect_vec3(t.translate, 1, 0, 0);
	t = plait_scene_collider_transform(ball, 100);
	expect_vec3(t.translate, 1, 0, 0);
	cr_expect_float_eq(t.scale, 2.0f, 1e-6f);
	plait_scene_free(&scene);
}

Test(scene_load, mesh_cloth_keeps_quads_and_merges_groups)
{
	plait_scene scene;
	load("{\"objects\": [{\"type\": \"cloth\", \"mesh\": \"two_quads.obj\", \"pins\": [0],"
	     " \"velocities\": [[0,0,0],[0,0,0],[0,0,0],[0,0,0],[0,0,0],[0,0,1]]}]}",
	     &scene);
	const plait_scene_object *o = &scene.objects[0];
	cr_expect_eq(o->vertex_count, 6);
	cr_expect_eq(o->face_count, 2);
	cr_expect_eq(o->face_sizes[0], 4);
	cr_expect_eq(o->face_sizes[1], 4);
	cr_expect_eq(scene.warning_count, 0);
	cr_expect(strstr(o->mesh_path, "tests/data/two_quads.obj") != NULL, "%s", o->mesh_path);
	plait_scene_free(&scene);
}

Test(scene_load, demo_matches_the_example_scene)
{
	json_error_t error;
	json_t *demo = json_loads(plait_demo_scene_json(), 0, &error);
	json_t *file = json_load_file(PLAIT_SOURCE_DIR "/scenes/cloth_on_sphere.json", 0, &error);
	cr_assert_not_null(demo);
	cr_assert_not_null(file, "%s", error.text);
	cr_expect(json_equal(demo, file), "the built-in demo and scenes/cloth_on_sphere.json differ");
	json_decref(demo);
	json_decref(file);
}

Test(scene_load, every_example_scene_loads_and_builds_a_world)
{
	DIR *dir = opendir(PLAIT_SOURCE_DIR "/scenes");
	cr_assert_not_null(dir);
	int count = 0;
	struct dirent *entry;
	while ((entry = readdir(dir)) != NULL) {
		size_t n = strlen(entry->d_name);
		if (n < 5 || strcmp(entry->d_name + n - 5, ".json") != 0)
			continue;
		char path[1024];
		snprintf(path, sizeof path, "%s/scenes/%s", PLAIT_SOURCE_DIR, entry->d_name);
		plait_scene scene;
		plait_tool_error error = {{0}};
		cr_assert(plait_scene_load(path, &scene, &error), "%s", error.message);
		cr_expect_eq(scene.warning_count, 0, "%s has warnings", path);
		plait_world_id world;
		cr_expect(plait_scene_create_world(&scene, &world, &error), "%s", error.message);
		if (!plait_world_id_is_null(world)) {
			cr_expect_eq(plait_world_get_object_count(world), scene.object_count);
			cr_expect(plait_scene_apply_frame(&scene, world, 1, &error), "%s", error.message);
			plait_destroy_world(world);
		}
		plait_scene_free(&scene);
		++count;
	}
	closedir(dir);
	cr_expect_geq(count, 5);
}

// The first cells of a docs table row "| `key` | type | default | unit | range | ...", or false
// for other lines.
#define DOC_CELLS 5
static bool doc_row(const char *line, char cells[DOC_CELLS][96])
{
	if (strncmp(line, "| `", 3) != 0)
		return false;
	const char *p = line + 1;
	for (int c = 0; c < DOC_CELLS; ++c) {
		const char *end = strchr(p, '|');
		if (end == NULL)
			return false;
		while (*p == ' ')
			++p;
		size_t n = (size_t)(end - p);
		while (n > 0 && p[n - 1] == ' ')
			--n;
		if (n >= 96)
			n = 95;
		memcpy(cells[c], p, n);
		cells[c][n] = '\0';
		p = end + 1;
	}
	return true;
}

// Finds the row of key in the table under "<!-- keys: CONTEXT -->".
static bool doc_find(const char *docs, const char *context, const char *key, char cells[DOC_CELLS][96])
{
	char marker[64];
	snprintf(marker, sizeof marker, "<!-- keys: %s -->", context);
	const char *line = strstr(docs, marker);
	if (line == NULL)
		return false;
	char wanted[80];
	snprintf(wanted, sizeof wanted, "`%s`", key);
	for (line = strchr(line, '\n'); line != NULL; line = strchr(line, '\n')) {
		++line;
		if (line[0] == '\n' || line[0] == '\0')
			return false; // end of the table
		if (doc_row(line, cells) && strcmp(cells[0], wanted) == 0)
			return true;
	}
	return false;
}

// Every key the loader accepts has a row in its context's table in docs/scene-format.md, and
// every documented default is the value the loader starts from (plait_default_*_def()).
Test(scene_load, docs_list_every_key_with_the_api_default)
{
	FILE *file = fopen(PLAIT_SOURCE_DIR "/docs/scene-format.md", "rb");
	cr_assert_not_null(file);
	static char docs[200000];
	size_t length = fread(docs, 1, sizeof docs - 1, file);
	fclose(file);
	docs[length] = '\0';

	plait_scene top = {.frames = PLAIT_SCENE_DEFAULT_FRAMES};
	plait_world_def world = plait_default_world_def();
	plait_cloth_def cloth = plait_default_cloth_def();
	plait_grid_def grid = plait_default_grid_def();
	plait_curve_def curve = plait_default_curve_def();
	plait_particles_def particles = plait_default_particles_def();
	plait_collider_def collider = plait_default_collider_def();
	plait_scene_keyframe keyframe = {0, plait_identity_transform()};
	const void *defaults[PLAIT_CONTEXT_COUNT] = {
	    [PLAIT_CONTEXT_TOP] = &top,
	    [PLAIT_CONTEXT_WORLD] = &world,
	    [PLAIT_CONTEXT_WIND] = &world,
	    [PLAIT_CONTEXT_CLOTH] = &cloth,
	    [PLAIT_CONTEXT_GRID] = &grid,
	    [PLAIT_CONTEXT_CURVE] = &curve,
	    [PLAIT_CONTEXT_PARTICLES] = &particles,
	    [PLAIT_CONTEXT_COLLIDER] = &collider,
	    [PLAIT_CONTEXT_KEYFRAME] = &keyframe,
	};
	for (int c = 0; c < PLAIT_CONTEXT_COUNT; ++c) {
		const char *context = plait_scene_context_name((plait_scene_context)c);
		int count;
		const plait_scene_key *keys = plait_scene_keys((plait_scene_context)c, &count);
		for (int i = 0; i < count; ++i) {
			const plait_scene_key *k = &keys[i];
			char cells[DOC_CELLS][96];
			if (!doc_find(docs, context, k->name, cells)) {
				cr_expect_fail("docs/scene-format.md: no row for `%s` in the %s table", k->name, context);
				continue;
			}
			if (k->kind == PLAIT_KEY_SPECIAL || k->offset == PLAIT_KEY_IGNORED)
				continue;
			const char *value = (const char *)defaults[c] + k->offset;
			const char *doc = cells[2];
			switch (k->kind) {
			case PLAIT_KEY_FLOAT: {
				float actual;
				memcpy(&actual, value, sizeof actual);
				char *end;
				double documented = strtod(doc, &end);
				cr_expect(end != doc && *end == '\0', "%s.%s: default \"%s\" is not a number", context,
				          k->name, doc);
				cr_expect(fabs(documented - actual) <= 1e-6 * fabs(documented) + 1e-12,
				          "%s.%s: docs say %s, the library's default is %g", context, k->name, doc, actual);
				break;
			}
			case PLAIT_KEY_INT:
			case PLAIT_KEY_UINT32: {
				int actual;
				memcpy(&actual, value, sizeof actual);
				cr_expect_eq(atoi(doc), actual, "%s.%s: docs say %s, the library's default is %d", context,
				             k->name, doc, actual);
				break;
			}
			case PLAIT_KEY_BOOL: {
				bool actual;
				memcpy(&actual, value, sizeof actual);
				cr_expect_str_eq(doc, actual ? "true" : "false", "%s.%s", context, k->name);
				break;
			}
			case PLAIT_KEY_VEC3: {
				plait_vec3 actual;
				memcpy(&actual, value, sizeof actual);
				float x, y, z;
				cr_expect_eq(sscanf(doc, "[%f, %f, %f]", &x, &y, &z), 3,
				             "%s.%s: default \"%s\" is not [x, y, z]", context, k->name, doc);
				cr_expect(x == actual.x && y == actual.y && z == actual.z,
				          "%s.%s: docs say %s, the library's default is [%g, %g, %g]", context, k->name, doc,
				          actual.x, actual.y, actual.z);
				break;
			}
			case PLAIT_KEY_CHOICE: {
				// Default `"name"`; type string; range the names in enum order, `a`, `b`, ...
				int actual;
				memcpy(&actual, value, sizeof actual);
				cr_assert(actual >= 0 && actual < k->choice_count, "%s.%s: default %d has no name", context,
				          k->name, actual);
				char expected[96];
				snprintf(expected, sizeof expected, "`\"%s\"`", k->choices[actual]);
				cr_expect_str_eq(doc, expected, "%s.%s: docs say %s, the library's default is %s", context,
				                 k->name, doc, expected);
				cr_expect_str_eq(cells[1], "string", "%s.%s: type", context, k->name);
				char names[96] = "";
				for (int v = 0; v < k->choice_count; ++v) {
					size_t used = strlen(names);
					snprintf(names + used, sizeof names - used, "%s`%s`", v > 0 ? ", " : "", k->choices[v]);
				}
				cr_expect_str_eq(cells[4], names, "%s.%s: the values", context, k->name);
				break;
			}
			case PLAIT_KEY_SPECIAL:
				break;
			}
		}
	}
}

Test(scene_load, tethers_are_read_and_checked)
{
	plait_scene scene;
	load("{\"objects\": [{\"type\": \"cloth\", \"grid\": {\"size\": [1, 1], \"resolution\": [4, 4]},"
	     " \"pins\": [0, 4], \"tethers\": \"geodesic\", \"tether_scale\": 1.05}]}",
	     &scene);
	cr_assert_eq(scene.objects[0].cloth.tethers, PLAIT_TETHER_GEODESIC);
	cr_assert_float_eq(scene.objects[0].cloth.tether_scale, 1.05f, 1e-6f);
	plait_world_id world;
	plait_tool_error error;
	cr_assert(plait_scene_create_world(&scene, &world, &error), "%s", error.message);
	plait_destroy_world(world);
	plait_scene_free(&scene);

	plait_scene bad;
	cr_assert_not(plait_scene_load_string("{\"objects\": [{\"type\": \"cloth\", \"grid\": {\"size\": [1, 1], "
	                                      "\"resolution\": [2, 2]}, \"tethers\": \"geodesik\"}]}",
	                                      "scene.json", DATA_DIR, &bad, &error));
	cr_assert(strstr(error.message, "objects[0].tethers") != NULL, "%s", error.message);
	cr_assert(strstr(error.message, "geodesic") != NULL, "%s", error.message);
}

Test(scene_load, self_collide_is_read_for_cloth)
{
	plait_scene scene;
	load("{\"objects\": [{\"type\": \"cloth\", \"grid\": {\"size\": [1, 1], \"resolution\": [2, 2]},"
	     " \"self_collide\": true}]}",
	     &scene);
	cr_assert(scene.objects[0].cloth.self_collide);
	plait_scene_free(&scene);
}

// Collision layers on every kind of object, and the cloth's self-collision settings, reach the
// defs the world is created from.
Test(scene_load, collision_settings_are_read_for_every_object)
{
	plait_scene scene;
	load(
	    "{\"objects\": ["
	    " {\"type\": \"cloth\", \"grid\": {\"size\": [1, 1], \"resolution\": [2, 2]}, \"collision_layer\": 3,"
	    "  \"self_collide\": true, \"self_collision_flag\": \"vertex_face\", \"self_collide_width_scale\": "
	    "2.5},"
	    " {\"type\": \"cloth\", \"grid\": {\"size\": [1, 1], \"resolution\": [2, 2]},"
	    "  \"self_collision_flag\": \"vertex\", \"self_collide_width_scale\": 0.01},"
	    " {\"type\": \"cloth\", \"grid\": {\"size\": [1, 1], \"resolution\": [2, 2]},"
	    "  \"self_collision_flag\": \"full_surface\", \"self_collide_width_scale\": 100, "
	    "\"collision_layer\": 1000},"
	    " {\"type\": \"curve\", \"positions\": [[0,0,0], [1,0,0]], \"collision_layer\": 1},"
	    " {\"type\": \"particles\", \"positions\": [[0,0,0]], \"collision_layer\": 2.0},"
	    " {\"type\": \"collider\", \"shape\": \"plane\", \"collision_layer\": 7}]}",
	    &scene);
	const plait_cloth_def *a = &scene.objects[0].cloth;
	cr_expect_eq(a->surface.collision_layer, 3);
	cr_expect(a->self_collide);
	cr_expect_eq(a->self_collision_flag, PLAIT_SELF_COLLIDE_VERTEX_FACE);
	cr_expect_float_eq(a->self_collide_width_scale, 2.5f, 0.0f);
	const plait_cloth_def *b = &scene.objects[1].cloth;
	cr_expect_eq(b->surface.collision_layer, 0);
	cr_expect_eq(b->self_collision_flag, PLAIT_SELF_COLLIDE_VERTEX);
	cr_expect_float_eq(b->self_collide_width_scale, 0.01f, 0.0f);
	const plait_cloth_def *c = &scene.objects[2].cloth;
	cr_expect_eq(c->surface.collision_layer, 1000);
	cr_expect_eq(c->self_collision_flag, PLAIT_SELF_COLLIDE_FULL_SURFACE);
	cr_expect_float_eq(c->self_collide_width_scale, 100.0f, 0.0f);
	cr_expect_eq(scene.objects[3].curve.surface.collision_layer, 1);
	cr_expect_eq(scene.objects[4].particles.surface.collision_layer, 2);
	cr_expect_eq(scene.objects[5].collider.surface.collision_layer, 7);
	// The library takes what the loader accepts, the ends of the ranges included.
	plait_world_id world;
	plait_tool_error error;
	cr_assert(plait_scene_create_world(&scene, &world, &error), "%s", error.message);
	plait_destroy_world(world);
	plait_scene_free(&scene);
}

// The library checks the ranges; the tool's message names the scene, the object and the key.
Test(scene_load, collision_settings_out_of_range_are_rejected_naming_the_object)
{
	static const struct {
		const char *json;
		const char *message;
	} cases[] = {
	    {"{\"objects\": [{\"type\": \"collider\", \"shape\": \"plane\"}, {\"name\": \"shirt\", \"type\": "
	     "\"cloth\","
	     " \"grid\": {\"size\": [1, 1], \"resolution\": [2, 2]}, \"self_collide_width_scale\": 0}]}",
	     "scene.json: objects[1] (cloth \"shirt\"): the solver rejected it: cloth 'shirt': "
	     "self_collide_width_scale must be in 0.01..100, got 0"},
	    {"{\"objects\": [{\"type\": \"cloth\", \"grid\": {\"size\": [1, 1], \"resolution\": [2, 2]},"
	     " \"self_collide_width_scale\": 101}]}",
	     "scene.json: objects[0] (cloth \"cloth0\"): the solver rejected it: cloth 'cloth0': "
	     "self_collide_width_scale must be in 0.01..100, got 101"},
	    {"{\"objects\": [{\"type\": \"cloth\", \"grid\": {\"size\": [1, 1], \"resolution\": [2, 2]},"
	     " \"collision_layer\": 1001}]}",
	     "scene.json: objects[0] (cloth \"cloth0\"): the solver rejected it: cloth 'cloth0': "
	     "collision_layer must be in 0..1000, got 1001"},
	    {"{\"objects\": [{\"type\": \"curve\", \"name\": \"rope\", \"positions\": [[0,0,0], [1,0,0]],"
	     " \"collision_layer\": -1}]}",
	     "scene.json: objects[0] (curve \"rope\"): the solver rejected it: curve 'rope': "
	     "collision_layer must be in 0..1000, got -1"},
	    {"{\"objects\": [{\"type\": \"particles\", \"positions\": [[0,0,0]], \"collision_layer\": 5000}]}",
	     "scene.json: objects[0] (particles \"particles0\"): the solver rejected it: particles 'particles0': "
	     "collision_layer must be in 0..1000, got 5000"},
	    {"{\"objects\": [{\"type\": \"collider\", \"shape\": \"plane\", \"collision_layer\": -7}]}",
	     "scene.json: objects[0] (collider \"collider0\"): the solver rejected it: collider 'collider0': "
	     "collision_layer must be in 0..1000, got -7"},
	};
	for (size_t i = 0; i < sizeof cases / sizeof cases[0]; ++i) {
		plait_scene scene;
		load(cases[i].json, &scene);
		plait_world_id world;
		plait_tool_error error = {{0}};
		cr_expect_not(plait_scene_create_world(&scene, &world, &error), "%s", cases[i].json);
		cr_expect(plait_world_id_is_null(world));
		cr_expect_str_eq(error.message, cases[i].message);
		plait_scene_free(&scene);
	}
}

Test(scene_load, bend_model_and_iterations_are_read_for_cloth)
{
	plait_scene scene;
	load("{\"objects\": [{\"type\": \"cloth\", \"grid\": {\"size\": [1, 1], \"resolution\": [4, 4]},"
	     " \"pins\": [0, 4], \"bend_model\": \"distance\", \"iterations\": 12, \"shear_iterations\": 7,"
	     " \"bend_iterations\": 1000},"
	     " {\"type\": \"cloth\", \"grid\": {\"size\": [1, 1], \"resolution\": [2, 2]},"
	     " \"bend_model\": \"dihedral\", \"shear_iterations\": 0}]}",
	     &scene);
	const plait_cloth_def *a = &scene.objects[0].cloth;
	cr_expect_eq(a->bend_model, PLAIT_BEND_DISTANCE);
	cr_expect_eq(a->iterations, 12);
	cr_expect_eq(a->shear_iterations, 7);
	cr_expect_eq(a->bend_iterations, 1000);
	const plait_cloth_def *b = &scene.objects[1].cloth;
	cr_expect_eq(b->bend_model, PLAIT_BEND_DIHEDRAL);
	cr_expect_eq(b->shear_iterations, 0);
	cr_expect_eq(b->bend_iterations, 0);
	// The library takes what the loader accepts.
	plait_world_id world;
	plait_tool_error error;
	cr_assert(plait_scene_create_world(&scene, &world, &error), "%s", error.message);
	plait_destroy_world(world);
	plait_scene_free(&scene);
}

/* Every class of scene and mesh error gives a message naming the file, the key path and what
 * was expected. Scenes are loaded from strings named "scene.json" unless a file is the point. */
#include "mesh_io.h"
#include "scene.h"

#include <criterion/criterion.h>
#include <dirent.h>
#include <stdio.h>
#include <string.h>

#define DATA_DIR PLAIT_SOURCE_DIR "/tests/data"

// Loads json (expected to fail) and returns the message in error.
static void expect_failure(const char *json, plait_tool_error *error)
{
	plait_scene scene;
	*error = (plait_tool_error){{0}};
	bool ok = plait_scene_load_string(json, "scene.json", DATA_DIR, &scene, error);
	if (ok)
		plait_scene_free(&scene);
	cr_assert(!ok, "scene loaded but should have failed: %s", json);
	cr_assert(strncmp(error->message, "scene.json", 10) == 0, "message does not start with the file: %s",
	          error->message);
}

static void expect_message(const char *json, const char *message)
{
	plait_tool_error error;
	expect_failure(json, &error);
	cr_expect_str_eq(error.message, message);
}

static void expect_contains(const char *json, const char *part)
{
	plait_tool_error error;
	expect_failure(json, &error);
	cr_expect(strstr(error.message, part) != NULL, "expected \"%s\" in: %s", part, error.message);
}

#define CLOTH_GRID "\"grid\": {\"size\": [1, 1], \"resolution\": [2, 2]}"

Test(scene_errors, unknown_key_suggests_closest)
{
	expect_message(
	    "{\"objects\": [{\"type\": \"collider\", \"shape\": \"plane\"},"
	    " {\"type\": \"cloth\", " CLOTH_GRID ", \"stretch_resistanse\": 5}]}",
	    "scene.json: objects[1].stretch_resistanse: unknown key (did you mean \"stretch_resistance\"?)");
	expect_message(
	    "{\"world\": {\"fsp\": 24}, \"objects\": [{\"type\": \"particles\", \"positions\": [[0,0,0]]}]}",
	    "scene.json: world.fsp: unknown key (did you mean \"fps\"?)");
	expect_message("{\"objets\": []}", "scene.json: objets: unknown key (did you mean \"objects\"?)");
}

Test(scene_errors, unknown_key_without_close_match_lists_valid_keys)
{
	expect_contains(
	    "{\"world\": {\"wind\": {\"xyzzy\": 1}}, \"objects\": [{\"type\": \"particles\", \"positions\": "
	    "[[0,0,0]]}]}",
	    "scene.json: world.wind.xyzzy: unknown key (valid keys here: speed, direction, noise)");
}

Test(scene_errors, number_out_of_range)
{
	expect_message("{\"world\": {\"fps\": -3}, \"objects\": []}",
	               "scene.json: world.fps: expected a number > 0, got -3");
}

Test(scene_errors, out_of_range_values_of_several_keys)
{
	static const struct {
		const char *json;
		const char *message;
	} cases[] = {
	    {"{\"world\": {\"substeps\": 0}, \"objects\": []}",
	     "scene.json: world.substeps: expected an integer from 1 to 1000, got 0"},
	    {"{\"world\": {\"contact_pass_interval\": -3}, \"objects\": []}",
	     "scene.json: world.contact_pass_interval: expected an integer from 0 to 1000, got -3"},
	    {"{\"world\": {\"air_density\": -1.5}, \"objects\": []}",
	     "scene.json: world.air_density: expected a number >= 0, got -1.5"},
	    {"{\"world\": {\"wind\": {\"noise\": 11}}, \"objects\": []}",
	     "scene.json: world.wind.noise: expected a number from 0 to 10, got 11"},
	    {"{\"world\": {\"seed\": -1}, \"objects\": []}",
	     "scene.json: world.seed: expected an integer from 0 to 4294967295, got -1"},
	    {"{\"frames\": 2.5, \"objects\": []}",
	     "scene.json: frames: expected an integer from 0 to 1000000, got 2.5"},
	    {"{\"objects\": [{\"type\": \"cloth\", " CLOTH_GRID ", \"friction\": 11}]}",
	     "scene.json: objects[0].friction: expected a number from 0 to 10, got 11"},
	    {"{\"objects\": [{\"type\": \"cloth\", " CLOTH_GRID ", \"bounce\": 1.5}]}",
	     "scene.json: objects[0].bounce: expected a number from 0 to 1, got 1.5"},
	    {"{\"objects\": [{\"type\": \"cloth\", " CLOTH_GRID ", \"density\": 0}]}",
	     "scene.json: objects[0].density: expected a number > 0 and <= 1000000, got 0"},
	    {"{\"objects\": [{\"type\": \"cloth\", " CLOTH_GRID ", \"rest_length_scale\": 0.001}]}",
	     "scene.json: objects[0].rest_length_scale: expected a number from 0.01 to 10, got 0.001"},
	    {"{\"objects\": [{\"type\": \"cloth\", " CLOTH_GRID ", \"stretch_resistance\": 20000}]}",
	     "scene.json: objects[0].stretch_resistance: expected a number from 0 to 10000, got 20000"},
	    {"{\"objects\": [{\"type\": \"cloth\", " CLOTH_GRID ", \"shear_iterations\": -1}]}",
	     "scene.json: objects[0].shear_iterations: expected an integer from 0 to 1000, got -1"},
	    {"{\"objects\": [{\"type\": \"cloth\", " CLOTH_GRID ", \"bend_iterations\": 1001}]}",
	     "scene.json: objects[0].bend_iterations: expected an integer from 0 to 1000, got 1001"},
	    {"{\"objects\": [{\"type\": \"cloth\", " CLOTH_GRID ", \"shear_iterations\": 2.5}]}",
	     "scene.json: objects[0].shear_iterations: expected an integer from 0 to 1000, got 2.5"},
	    {"{\"objects\": [{\"type\": \"particles\", \"positions\": [[0,0,0]], \"radius\": 0}]}",
	     "scene.json: objects[0].radius: expected a number > 0 and <= 1000000, got 0"},
	    {"{\"objects\": [{\"type\": \"curve\", \"positions\": [[0,0,0],[1,0,0]], \"damp\": 101}]}",
	     "scene.json: objects[0].damp: expected a number from 0 to 100, got 101"},
	    {"{\"objects\": [{\"type\": \"collider\", \"shape\": \"sphere\", \"radius\": -1}]}",
	     "scene.json: objects[0].radius: expected a number > 0, got -1"},
	    {"{\"objects\": [{\"type\": \"cloth\", \"grid\": {\"size\": [1, 1], \"resolution\": [0, 2]}}]}",
	     "scene.json: objects[0].grid.resolution[0]: expected an integer from 1 to 2000, got 0"},
	    {"{\"objects\": [{\"type\": \"cloth\", \"grid\": {\"size\": [1, -2], \"resolution\": [2, 2]}}]}",
	     "scene.json: objects[0].grid.size[1]: expected a number > 0, got -2"},
	};
	for (size_t i = 0; i < sizeof cases / sizeof cases[0]; ++i)
		expect_message(cases[i].json, cases[i].message);
}

Test(scene_errors, number_too_large_for_float)
{
	expect_contains("{\"world\": {\"fps\": 1e39}, \"objects\": []}", "too large for single precision");
}

Test(scene_errors, unknown_type)
{
	expect_message(
	    "{\"objects\": [{\"type\": \"clth\"}]}",
	    "scene.json: objects[0].type: expected one of cloth, curve, particles, collider, got \"clth\"");
}

Test(scene_errors, wrong_value_types)
{
	expect_message("{\"world\": {\"substeps\": \"three\"}, \"objects\": []}",
	               "scene.json: world.substeps: expected an integer from 1 to 1000, got \"three\"");
	expect_message(
	    "{\"world\": {\"gravity\": [0, -9.81]}, \"objects\": []}",
	    "scene.json: world.gravity: expected [x, y, z] (an array of 3 numbers), got an array of 2 items");
	expect_message("{\"world\": {\"gravity\": [0, \"down\", 0]}, \"objects\": []}",
	               "scene.json: world.gravity[1]: expected a number, got \"down\"");
	expect_message("{\"objects\": [{\"type\": \"cloth\", " CLOTH_GRID ", \"collide\": 1}]}",
	               "scene.json: objects[0].collide: expected true or false, got 1");
	expect_message("{\"world\": [], \"objects\": []}",
	               "scene.json: world: expected an object {...}, got an empty array");
	expect_message("[1, 2]",
	               "scene.json: expected an object {...} at the top level, got an array of 2 items");
	expect_contains("{\"objects\": [{\"type\": \"particles\", \"positions\": [[0,0,0], [1,1]]}]}",
	                "scene.json: objects[0].positions[1]: expected [x, y, z]");
}

Test(scene_errors, missing_required_keys)
{
	expect_message("{\"world\": {}}", "scene.json: objects: required key is missing");
	expect_message("{\"objects\": [{\"type\": \"particles\"}]}",
	               "scene.json: objects[0].positions: required key is missing");
	expect_contains("{\"objects\": [{\"name\": \"a\"}]}",
	                "scene.json: objects[0].type: required key is missing (expected one of cloth, curve");
	expect_message("{\"objects\": [{\"type\": \"collider\"}]}",
	               "scene.json: objects[0].shape: required key is missing");
	expect_message("{\"objects\": [{\"type\": \"cloth\", \"grid\": {\"size\": [1, 1]}}]}",
	               "scene.json: objects[0].grid.resolution: required key is missing");
	expect_contains("{\"objects\": [{\"type\": \"cloth\"}]}",
	                "scene.json: objects[0]: a cloth needs either \"mesh\" (a file) or \"grid\"");
	expect_contains("{\"objects\": [{\"type\": \"cloth\", \"mesh\": \"two_quads.obj\", " CLOTH_GRID "}]}",
	                "scene.json: objects[0]: a cloth takes either \"mesh\" or \"grid\", not both");
	expect_message(
	    "{\"objects\": [{\"type\": \"collider\", \"shape\": \"sphere\", \"keyframes\": [{\"translate\": "
	    "[0, 0, 0]}]}]}",
	    "scene.json: objects[0].keyframes[0].frame: required key is missing");
}

Test(scene_errors, json_syntax_error_has_line_and_column)
{
	// The missing comma is noticed at the next key, line 3 column 14.
	plait_tool_error error;
	expect_failure("{\n  \"frames\": 10\n  \"objects\": []\n}\n", &error);
	cr_expect(strncmp(error.message, "scene.json:3:", 13) == 0, "no line in: %s", error.message);
	cr_expect(strstr(error.message, "JSON syntax error") != NULL, "%s", error.message);

	plait_scene scene;
	cr_assert(!plait_scene_load(DATA_DIR "/syntax_error.json", &scene, &error));
	cr_expect(strstr(error.message, "syntax_error.json:4:") != NULL, "%s", error.message);
	cr_expect(strstr(error.message, "JSON syntax error") != NULL, "%s", error.message);
}

Test(scene_errors, duplicate_json_key)
{
	expect_contains("{\"frames\": 1, \"frames\": 2, \"objects\": []}", "duplicate");
}

Test(scene_errors, missing_scene_file)
{
	plait_scene scene;
	plait_tool_error error = {{0}};
	cr_assert(!plait_scene_load(DATA_DIR "/no_such_scene.json", &scene, &error));
	cr_expect(strstr(error.message, "no_such_scene.json: cannot open scene file: No such file") != NULL, "%s",
	          error.message);
}

Test(scene_errors, unknown_shape)
{
	expect_message(
	    "{\"objects\": [{\"type\": \"collider\", \"shape\": \"cube\"}]}",
	    "scene.json: objects[0].shape: expected one of plane, sphere, capsule, box, mesh, got \"cube\"");
}

Test(scene_errors, unknown_bend_model)
{
	expect_message("{\"objects\": [{\"type\": \"cloth\", " CLOTH_GRID ", \"bend_model\": \"springs\"}]}",
	               "scene.json: objects[0].bend_model: expected one of dihedral, distance, got \"springs\"");
	expect_message("{\"objects\": [{\"type\": \"collider\", \"shape\": \"plane\"},"
	               " {\"type\": \"cloth\", " CLOTH_GRID ", \"bend_model\": 1}]}",
	               "scene.json: objects[1].bend_model: expected one of dihedral, distance, got 1");
	// Misspelt keys are suggested their closest valid key, as every other key.
	expect_message("{\"objects\": [{\"type\": \"cloth\", " CLOTH_GRID ", \"bend_modle\": \"distance\"}]}",
	               "scene.json: objects[0].bend_modle: unknown key (did you mean \"bend_model\"?)");
	expect_message(
	    "{\"objects\": [{\"type\": \"cloth\", " CLOTH_GRID ", \"shear_iteration\": 4}]}",
	    "scene.json: objects[0].shear_iteration: unknown key (did you mean \"shear_iterations\"?)");
}

Test(scene_errors, bad_collision_settings)
{
	// self_collision_flag takes the names of plait_self_collision_flag, in its order.
	expect_message(
	    "{\"objects\": [{\"type\": \"cloth\", " CLOTH_GRID ", \"self_collision_flag\": \"faces\"}]}",
	    "scene.json: objects[0].self_collision_flag: expected one of full_surface, vertex_face, vertex, got "
	    "\"faces\"");
	expect_message("{\"objects\": [{\"type\": \"collider\", \"shape\": \"plane\"},"
	               " {\"type\": \"cloth\", " CLOTH_GRID ", \"self_collision_flag\": 2}]}",
	               "scene.json: objects[1].self_collision_flag: expected one of full_surface, vertex_face, "
	               "vertex, got 2");
	expect_message(
	    "{\"objects\": [{\"type\": \"cloth\", " CLOTH_GRID ", \"self_collision_flag\": \"VERTEX\"}]}",
	    "scene.json: objects[0].self_collision_flag: expected one of full_surface, vertex_face, vertex, got "
	    "\"VERTEX\"");
	// Value types; the ranges are the library's (test_scene_load.c, test_cli_run.c).
	expect_message("{\"objects\": [{\"type\": \"cloth\", " CLOTH_GRID
	               ", \"self_collide_width_scale\": \"2\"}]}",
	               "scene.json: objects[0].self_collide_width_scale: expected a number, got \"2\"");
	expect_message("{\"objects\": [{\"type\": \"particles\", \"positions\": [[0,0,0]],"
	               " \"collision_layer\": 1.5}]}",
	               "scene.json: objects[0].collision_layer: expected an integer, got 1.5");
	expect_message(
	    "{\"objects\": [{\"type\": \"collider\", \"shape\": \"plane\", \"collision_layer\": \"top\"}]}",
	    "scene.json: objects[0].collision_layer: expected an integer, got \"top\"");
	expect_message(
	    "{\"objects\": [{\"type\": \"curve\", \"positions\": [[0,0,0],[1,0,0]],"
	    " \"collision_layer\": 3000000000}]}",
	    "scene.json: objects[0].collision_layer: expected an integer, got 3000000000 (too large for "
	    "a 32-bit integer)");
	expect_contains(
	    "{\"objects\": [{\"type\": \"cloth\", " CLOTH_GRID ", \"self_collide_width_scale\": 1e39}]}",
	    "scene.json: objects[0].self_collide_width_scale: expected a number, got 1e+39 (too large "
	    "for single precision)");
	// Misspelt keys are suggested their closest valid key.
	expect_message(
	    "{\"objects\": [{\"type\": \"cloth\", " CLOTH_GRID ", \"self_colision_flag\": \"vertex\"}]}",
	    "scene.json: objects[0].self_colision_flag: unknown key (did you mean \"self_collision_flag\"?)");
	expect_message("{\"objects\": [{\"type\": \"cloth\", " CLOTH_GRID ", \"self_colide_width_scale\": 2}]}",
	               "scene.json: objects[0].self_colide_width_scale: unknown key (did you mean "
	               "\"self_collide_width_scale\"?)");
	expect_message("{\"objects\": [{\"type\": \"collider\", \"shape\": \"plane\", \"colision_layer\": 1}]}",
	               "scene.json: objects[0].colision_layer: unknown key (did you mean \"collision_layer\"?)");
	expect_message(
	    "{\"objects\": [{\"type\": \"particles\", \"positions\": [[0,0,0]], \"collision_layr\": 1}]}",
	    "scene.json: objects[0].collision_layr: unknown key (did you mean \"collision_layer\"?)");
	// Self-collision settings are cloth keys only.
	expect_contains("{\"objects\": [{\"type\": \"particles\", \"positions\": [[0,0,0]],"
	                " \"self_collision_flag\": \"vertex\"}]}",
	                "scene.json: objects[0].self_collision_flag: unknown key (valid keys here: name, type,");
}

Test(scene_errors, mesh_collider_needs_a_mesh_file)
{
	expect_message("{\"objects\": [{\"type\": \"collider\", \"shape\": \"mesh\"}]}",
	               "scene.json: objects[0]: a mesh collider needs \"mesh\": the path of a mesh file");
}

Test(scene_errors, shape_key_of_another_shape)
{
	expect_message(
	    "{\"objects\": [{\"type\": \"collider\", \"shape\": \"plane\", \"radius\": 1}]}",
	    "scene.json: objects[0].radius: not used by a plane collider (a plane takes point, normal)");
	expect_message("{\"objects\": [{\"type\": \"collider\", \"shape\": \"plane\", \"normal\": [0, 0, 0]}]}",
	               "scene.json: objects[0].normal: expected a non-zero direction, got [0, 0, 0]");
	expect_contains("{\"objects\": [{\"type\": \"collider\", \"shape\": \"box\", \"size\": [1, 0, 1]}]}",
	                "scene.json: objects[0].size: expected full extents [x, y, z] all > 0");
}

Test(scene_errors, bad_names)
{
	expect_contains("{\"objects\": [{\"type\": \"particles\", \"name\": \"a b\", \"positions\": [[0,0,0]]}]}",
	                "scene.json: objects[0].name: expected a name of 1 to 63 letters");
	expect_message(
	    "{\"objects\": [{\"type\": \"particles\", \"name\": \"p\", \"positions\": [[0,0,0]]},"
	    " {\"type\": \"particles\", \"name\": \"p\", \"positions\": [[0,0,0]]}]}",
	    "scene.json: objects[1].name: \"p\" is already the name of objects[0]; names must be unique");
}

Test(scene_errors, pins_and_velocities_must_match_vertices)
{
	expect_message(
	    "{\"objects\": [{\"type\": \"curve\", \"positions\": [[0,0,0],[1,0,0]], \"pins\": [0, 2]}]}",
	    "scene.json: objects[0].pins[1]: expected an integer from 0 to 1, got 2");
	expect_message(
	    "{\"objects\": [{\"type\": \"cloth\", " CLOTH_GRID ", \"velocities\": [[0,0,0],[0,0,0]]}]}",
	    "scene.json: objects[0].velocities: expected one [x, y, z] for all vertices or 9 of them (one "
	    "per vertex), got an array of 2 items");
}

Test(scene_errors, keyframes_must_increase)
{
	expect_message("{\"objects\": [{\"type\": \"collider\", \"shape\": \"sphere\", \"keyframes\": ["
	               "{\"frame\": 10}, {\"frame\": 5}]}]}",
	               "scene.json: objects[0].keyframes[1].frame: expected a frame after 10 (keyframes go in "
	               "increasing frame order), got 5");
}

Test(scene_errors, missing_mesh_file)
{
	plait_tool_error error;
	expect_failure("{\"objects\": [{\"type\": \"cloth\", \"mesh\": \"no_such_mesh.obj\"}]}", &error);
	cr_expect(strstr(error.message, "scene.json: objects[0].mesh: ") == error.message, "%s", error.message);
	cr_expect(strstr(error.message, "no_such_mesh.obj: cannot open mesh file: No such file") != NULL, "%s",
	          error.message);
}

Test(scene_errors, bad_index_in_obj)
{
	plait_tool_error error;
	expect_failure("{\"objects\": [{\"type\": \"cloth\", \"mesh\": \"bad_index.obj\"}]}", &error);
	cr_expect(strstr(error.message, "objects[0].mesh: ") != NULL, "%s", error.message);
	cr_expect(strstr(error.message, "bad_index.obj: ") != NULL, "%s", error.message);
	cr_expect(strstr(error.message, "index") != NULL, "%s", error.message);
}

Test(scene_errors, nonfinite_coordinate)
{
	plait_tool_error error;
	expect_failure("{\"objects\": [{\"type\": \"cloth\", \"mesh\": \"nonfinite.obj\"}]}", &error);
	cr_expect(strstr(error.message, "nonfinite.obj: mesh 0 vertex 1 has a non-finite coordinate") != NULL,
	          "%s", error.message);
}

Test(scene_errors, degenerate_faces_are_dropped_with_a_warning)
{
	plait_scene scene;
	plait_tool_error error = {{0}};
	cr_assert(plait_scene_load_string("{\"objects\": [{\"type\": \"cloth\", \"mesh\": \"degenerate.obj\"}]}",
	                                  "scene.json", DATA_DIR, &scene, &error),
	          "%s", error.message);
	cr_expect_eq(scene.objects[0].face_count, 1);
	cr_expect_eq(scene.objects[0].vertex_count, 4);
	cr_assert_geq(scene.warning_count, 1);
	cr_expect(strstr(scene.warnings[0], "scene.json: objects[0].mesh: dropped 2 degenerate faces") != NULL,
	          "%s", scene.warnings[0]);

	plait_soup soup;
	plait_mesh_report report;
	cr_assert(plait_mesh_load(DATA_DIR "/degenerate.obj", &soup, &report, &error), "%s", error.message);
	cr_expect_eq(report.degenerate_faces, 2);
	cr_expect_eq(report.unused_vertices, 1);
	plait_soup_free(&soup);
	plait_scene_free(&scene);
}

Test(scene_errors, empty_mesh_file)
{
	plait_tool_error error;
	expect_failure("{\"objects\": [{\"type\": \"cloth\", \"mesh\": \"empty.obj\"}]}", &error);
	cr_expect(strstr(error.message, "empty.obj: cannot read mesh") != NULL, "%s", error.message);
}

Test(scene_errors, absurd_header_counts_are_refused_before_reading)
{
	const char *path = "/usr/share/assimp/models/invalid/OutOfMemory.off";
	FILE *probe = fopen(path, "rb");
	if (probe == NULL)
		cr_skip_test("%s is not installed", path);
	fclose(probe);
	plait_soup soup;
	plait_mesh_report report;
	plait_tool_error error = {{0}};
	cr_assert(!plait_mesh_load(path, &soup, &report, &error));
	cr_expect(strstr(error.message, "OutOfMemory.off: the OFF header declares") != NULL, "%s", error.message);
}

// assimp's collection of broken files: any outcome but a crash (or a message without the file).
Test(scene_errors, assimp_invalid_models_never_crash, .timeout = 120)
{
	const char *dir_path = "/usr/share/assimp/models/invalid";
	DIR *dir = opendir(dir_path);
	if (dir == NULL)
		cr_skip_test("%s is not installed (package assimp-testmodels)", dir_path);
	int files = 0;
	struct dirent *entry;
	while ((entry = readdir(dir)) != NULL) {
		if (entry->d_name[0] == '.')
			continue;
		char path[1024];
		snprintf(path, sizeof path, "%s/%s", dir_path, entry->d_name);
		plait_soup soup;
		plait_mesh_report report;
		plait_tool_error error = {{0}};
		if (plait_mesh_load(path, &soup, &report, &error)) {
			cr_expect_gt(soup.face_count, 0, "%s", path);
			plait_soup_free(&soup);
		} else {
			cr_expect(strstr(error.message, entry->d_name) != NULL, "message without the file name: %s",
			          error.message);
		}
		++files;
	}
	closedir(dir);
	cr_expect_gt(files, 0);
}

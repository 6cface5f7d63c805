/* `plait check DIR`: a clean run comes out clean in both formats; folders built by hand (or
 * frames edited after the run) give the exact counts of crossing triangles and of vertices
 * inside colliders; bad input gives exit status 2 with a message and leaves nothing behind. */
#include "cli.h"
#include "test_cli.h"

#include <criterion/criterion.h>
#include <dirent.h>
#include <jansson.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/stat.h>
#include <unistd.h>

static const char *clean_scene =
    "{\"world\": {\"fps\": 24, \"substeps\": 2}, \"frames\": 3, \"objects\": [\n"
    " {\"name\": \"sheet\", \"type\": \"cloth\", \"grid\": {\"size\": [1, 1], \"resolution\": [4, 4],\n"
    "  \"center\": [0, 1, 0]}},\n"
    " {\"name\": \"rope\", \"type\": \"curve\", \"positions\": [[2, 1, 0], [2.1, 1, 0], [2.2, 1, 0]], "
    "\"pins\": [0]},\n"
    " {\"name\": \"dots\", \"type\": \"particles\", \"positions\": [[-2, 1, 0], [-2, 1.5, 0]]},\n"
    " {\"name\": \"ball\", \"type\": \"collider\", \"shape\": \"sphere\", \"center\": [5, 1, 0], \"radius\": "
    "0.5,\n"
    "  \"keyframes\": [{\"frame\": 0}, {\"frame\": 3, \"translate\": [0, 0.5, 0]}]},\n"
    " {\"name\": \"rod\", \"type\": \"collider\", \"shape\": \"capsule\", \"a\": [-5, 0.5, 0], \"b\": [-5, "
    "1.5, 0]},\n"
    " {\"name\": \"crate\", \"type\": \"collider\", \"shape\": \"box\", \"center\": [0, 0.5, 5], "
    "\"rotation\": [0, 30, 0]},\n"
    " {\"name\": \"ground\", \"type\": \"collider\", \"shape\": \"plane\"}]}\n";

static char *make_temp_dir(void)
{
	char *dir = strdup("/tmp/plait_check_test_XXXXXX");
	cr_assert_not_null(mkdtemp(dir));
	return dir;
}

static void write_text(const char *dir, const char *name, const char *text)
{
	char path[1024];
	snprintf(path, sizeof path, "%s/%s", dir, name);
	FILE *f = fopen(path, "wb");
	cr_assert_not_null(f, "cannot write %s", path);
	fputs(text, f);
	fclose(f);
}

static bool exists(const char *dir, const char *name)
{
	char path[1024];
	snprintf(path, sizeof path, "%s/%s", dir, name);
	struct stat info;
	return stat(path, &info) == 0;
}

static int count_temporary_files(const char *dir)
{
	DIR *d = opendir(dir);
	cr_assert_not_null(d);
	int count = 0;
	struct dirent *entry;
	while ((entry = readdir(d)) != NULL) {
		size_t n = strlen(entry->d_name);
		count += n > 4 && strcmp(entry->d_name + n - 4, ".tmp") == 0;
	}
	closedir(d);
	return count;
}

/* Runs the scene into DIR/out; returns the output folder (malloc'ed). */
static char *run_scene(const char *dir, const char *scene_json, const char *format)
{
	write_text(dir, "scene.json", scene_json);
	char scene[1024], *out = malloc(1024);
	snprintf(scene, sizeof scene, "%s/scene.json", dir);
	snprintf(out, 1024, "%s/out", dir);
	const char *argv[] = {"plait", "run", scene, "--out", out, "--format", format, "--threads", "1"};
	cli_result r = run_cli(9, argv);
	cr_assert_eq(r.code, 0, "plait run failed: %s", r.err);
	free_result(&r);
	return out;
}

static cli_result check(const char *dir, const char *option, const char *value)
{
	const char *argv[] = {"plait", "check", dir, option, value};
	return run_cli(option != NULL ? 5 : 3, argv);
}

/* Line `frame` of DIR/check.jsonl, parsed. */
static json_t *check_line(const char *dir, int frame)
{
	char path[1024];
	snprintf(path, sizeof path, "%s/check.jsonl", dir);
	char *text = read_file(path, NULL);
	cr_assert_not_null(text, "no %s", path);
	json_t *found = NULL;
	int line = 0;
	for (char *s = strtok(text, "\n"); s != NULL; s = strtok(NULL, "\n"), ++line) {
		if (line == frame) {
			json_error_t error;
			found = json_loads(s, 0, &error);
			cr_assert_not_null(found, "line %d: %s", line, error.text);
		}
	}
	free(text);
	cr_assert_not_null(found, "check.jsonl has no line %d", frame);
	return found;
}

static long long get_int(const json_t *json, const char *key)
{
	const json_t *value = json_object_get(json, key);
	cr_assert(json_is_integer(value), "no integer %s", key);
	return json_integer_value(value);
}

static long long get_entry(const json_t *json, const char *object, const char *key)
{
	const json_t *value = json_object_get(json_object_get(json, object), key);
	return value != NULL ? json_integer_value(value) : 0;
}

Test(cli_check, a_clean_run_is_clean_in_both_formats)
{
	static const char *const formats[] = {"obj", "pc2"};
	for (int f = 0; f < 2; ++f) {
		char *dir = make_temp_dir();
		// A stale manifest from an earlier run is replaced.
		char out_dir[1024];
		snprintf(out_dir, sizeof out_dir, "%s/out", dir);
		mkdir(out_dir, 0777);
		write_text(out_dir, "manifest.json", "{stale");
		char *out = run_scene(dir, clean_scene, formats[f]);
		cli_result r = check(out, NULL, NULL);
		cr_expect_eq(r.code, 0, "%s: stdout: %s stderr: %s", formats[f], r.out, r.err);
		cr_expect(strstr(r.out, "clean") != NULL, "%s", r.out);
		cr_expect(strstr(r.out, "frames 0 to 3, 7 objects") != NULL, "%s", r.out);
		for (int frame = 0; frame <= 3; ++frame) {
			json_t *line = check_line(out, frame);
			cr_expect_eq(get_int(line, "frame"), frame);
			cr_expect_eq(get_int(line, "intersections"), 0);
			cr_expect_eq(get_int(line, "between_objects"), 0);
			cr_expect_eq(get_int(line, "inside_colliders"), 0);
			cr_expect_eq(get_entry(line, "self", "sheet"), 0);
			cr_expect(json_is_integer(json_object_get(json_object_get(line, "self"), "sheet")));
			json_decref(line);
		}
		cr_expect_eq(count_temporary_files(out), 0);
		// The moving ball is recorded where it was at each frame.
		char path[1024];
		snprintf(path, sizeof path, "%s/manifest.json", out);
		json_error_t error;
		json_t *manifest = json_load_file(path, 0, &error);
		cr_assert_not_null(manifest, "%s", error.text);
		json_t *ball = json_array_get(json_object_get(manifest, "objects"), 3);
		cr_expect_str_eq(json_string_value(json_object_get(ball, "shape")), "sphere");
		cr_expect(json_is_true(json_object_get(ball, "closed")));
		json_t *last = json_array_get(json_object_get(ball, "shapes"), 3);
		cr_expect_float_eq(json_number_value(json_array_get(json_object_get(last, "center"), 1)), 1.5, 1e-6);
		json_decref(manifest);
		free_result(&r);
		free(out);
		remove_tree(dir);
		free(dir);
	}
}

static const char *crossing_manifest =
    "{\"plait\": \"0.1.0\", \"manifest\": 1, \"format\": \"obj\", \"first_frame\": 0, \"last_frame\": 1,\n"
    " \"fps\": 24, \"space_scale\": 1, \"objects\": [\n"
    "  {\"name\": \"a\", \"type\": \"cloth\", \"collide\": true, \"vertices\": 4, \"file\": "
    "\"a.%04d.obj\"},\n"
    "  {\"name\": \"b\", \"type\": \"cloth\", \"collide\": true, \"vertices\": 9, \"file\": "
    "\"b.%04d.obj\"}]}\n";

/* A quad in z = 0 (two triangles sharing an edge: they touch, and are not counted). */
static const char *quad_a = "o a\nv 0 0 0\nv 1 0 0\nv 1 1 0\nv 0 1 0\nf 1 2 3 4\n";

/* b: a triangle through a's first triangle, and two of its own crossing each other, far away.
 * In frame 0 (apart) the first is moved away from a, and the third from the second. */
static void write_b(const char *dir, const char *name, bool apart)
{
	float dx = apart ? 10.0f : 0.0f;
	char text[1024];
	snprintf(text, sizeof text,
	         "v %g 0.2 -1\nv %g 0.2 1\nv %g 0.25 1\n"
	         "v 5 0 3\nv 6 0 3\nv 5 1 3\n"
	         "v %g 0.2 2\nv %g 0.2 4\nv %g 0.3 4\n"
	         "f 1 2 3\nf 4 5 6\nf 7/1/1 8/2/2 9/3/3\n",
	         0.7 + dx, 0.7 + dx, 0.8 + dx, 5.2 + dx, 5.2 + dx, 5.3 + dx);
	write_text(dir, name, text);
}

Test(cli_check, crossing_triangles_between_objects_and_within_a_cloth_are_counted)
{
	char *dir = make_temp_dir();
	write_text(dir, "manifest.json", crossing_manifest);
	write_text(dir, "a.0000.obj", quad_a);
	write_text(dir, "a.0001.obj", quad_a);
	write_b(dir, "b.0000.obj", true);
	write_b(dir, "b.0001.obj", false);
	cli_result r = check(dir, NULL, NULL);
	cr_expect_eq(r.code, 1, "stdout: %s stderr: %s", r.out, r.err);
	cr_expect(strstr(r.out, "frame 1: 2 crossing triangle pairs (a/b 1, within b 1)") != NULL, "%s", r.out);
	cr_expect(strstr(r.out, "1 frame with problems, the first at frame 1") != NULL, "%s", r.out);
	json_t *clean = check_line(dir, 0);
	cr_expect_eq(get_int(clean, "intersections"), 0);
	json_decref(clean);
	json_t *line = check_line(dir, 1);
	cr_expect_eq(get_int(line, "intersections"), 2);
	cr_expect_eq(get_int(line, "between_objects"), 1);
	cr_expect_eq(get_entry(line, "self", "a"), 0);
	cr_expect_eq(get_entry(line, "self", "b"), 1);
	cr_expect_eq(get_entry(line, "pairs", "a/b"), 1);
	cr_expect_eq(get_int(line, "inside_colliders"), 0);
	json_decref(line);
	free_result(&r);

	// The same answer with any number of threads, and the lines on stdout with --log -.
	const char *argv[] = {"plait", "check", dir, "--threads", "3", "--log", "-"};
	r = run_cli(7, argv);
	cr_expect_eq(r.code, 1);
	cr_expect(strstr(r.out,
	                 "{\"frame\":1,\"intersections\":2,\"between_objects\":1,\"self\":{\"a\":0,\"b\":1},"
	                 "\"inside_colliders\":0,\"pairs\":{\"a/b\":1},\"inside\":{}}\n") != NULL,
	          "%s", r.out);
	cr_expect(strstr(r.err, "frame 1:") != NULL, "the summary goes to stderr: %s", r.err);
	free_result(&r);
	remove_tree(dir);
	free(dir);
}

static const char *inside_manifest =
    "{\"plait\": \"0.1.0\", \"manifest\": 1, \"format\": \"obj\", \"first_frame\": 0, \"last_frame\": 0,\n"
    " \"objects\": [\n"
    "  {\"name\": \"dots\", \"type\": \"particles\", \"vertices\": 6, \"file\": \"dots.%04d.obj\"},\n"
    "  {\"name\": \"ghost\", \"type\": \"particles\", \"collide\": false, \"vertices\": 1, \"file\": "
    "\"ghost.%04d.obj\"},\n"
    "  {\"name\": \"ball\", \"type\": \"collider\", \"vertices\": 4, \"file\": \"ball.%04d.obj\", \"shape\": "
    "\"sphere\",\n"
    "   \"closed\": true, \"shapes\": [{\"center\": [0, 0.5, 0], \"radius\": 0.5}]},\n"
    "  {\"name\": \"ground\", \"type\": \"collider\", \"vertices\": 4, \"file\": \"ground.%04d.obj\", "
    "\"shape\": \"plane\",\n"
    "   \"closed\": false, \"shapes\": [{\"point\": [0, 0, 0], \"normal\": [0, 1, 0]}]},\n"
    "  {\"name\": \"crate\", \"type\": \"collider\", \"vertices\": 8, \"file\": \"crate.%04d.obj\", "
    "\"shape\": \"mesh\",\n"
    "   \"closed\": true}]}\n";

Test(cli_check, vertices_inside_colliders_are_counted_exactly)
{
	char *dir = make_temp_dir();
	write_text(dir, "manifest.json", inside_manifest);
	// Inside the ball; on its surface; outside everything; below the ground; inside the crate;
	// on the crate's face.
	write_text(dir, "dots.0000.obj", "v 0 0.5 0\nv 0 1 0\nv 3 3 3\nv 0 -0.5 5\nv 5 0.5 0\nv 5.5 0.5 0.2\n");
	write_text(dir, "ghost.0000.obj", "v 0 0.5 0\n");
	// The ball's written surface: a small tetrahedron inside it (the exact shape is in the manifest).
	write_text(dir, "ball.0000.obj",
	           "v 0 0.6 0\nv 0.1 0.4 0\nv -0.1 0.4 0.1\nv -0.1 0.4 -0.1\n"
	           "f 1 2 3\nf 1 3 4\nf 1 4 2\nf 2 4 3\n");
	write_text(dir, "ground.0000.obj", "v -10 0 -10\nv 10 0 -10\nv 10 0 10\nv -10 0 10\nf 1 4 3 2\n");
	// A closed cube from (4.5, 0, -0.5) to (5.5, 1, 0.5), as quads.
	write_text(dir, "crate.0000.obj",
	           "v 4.5 0 -0.5\nv 5.5 0 -0.5\nv 4.5 1 -0.5\nv 5.5 1 -0.5\n"
	           "v 4.5 0 0.5\nv 5.5 0 0.5\nv 4.5 1 0.5\nv 5.5 1 0.5\n"
	           "f 1 5 7 3\nf 2 4 8 6\nf 1 2 6 5\nf 3 7 8 4\nf 1 3 4 2\nf 5 6 8 7\n");
	cli_result r = check(dir, NULL, NULL);
	cr_expect_eq(r.code, 1, "stdout: %s stderr: %s", r.out, r.err);
	cr_expect(strstr(r.out, "3 vertices inside colliders (ball 1, ground 1, crate 1)") != NULL, "%s", r.out);
	json_t *line = check_line(dir, 0);
	cr_expect_eq(get_int(line, "inside_colliders"), 3);
	cr_expect_eq(get_entry(line, "inside", "ball"), 1);
	cr_expect_eq(get_entry(line, "inside", "ground"), 1);
	cr_expect_eq(get_entry(line, "inside", "crate"), 1);
	cr_expect_eq(get_int(line, "intersections"), 0);
	json_decref(line);
	free_result(&r);

	// A tolerance deeper than the ball's centre is deep (0.5 m) counts only what is deeper.
	r = check(dir, "--tolerance", "0.6");
	cr_expect_eq(r.code, 0, "stdout: %s stderr: %s", r.out, r.err);
	free_result(&r);
	remove_tree(dir);
	free(dir);
}

static void patch_float(const char *path, long offset, float value)
{
	FILE *f = fopen(path, "r+b");
	cr_assert_not_null(f);
	unsigned char bytes[4];
	memcpy(bytes, &value, 4); // little endian, as PC2 (the tests run on x86-64)
	cr_assert_eq(fseek(f, offset, SEEK_SET), 0);
	cr_assert_eq(fwrite(bytes, 1, 4, f), 4u);
	fclose(f);
}

Test(cli_check, an_edited_point_cache_frame_is_caught)
{
	char *dir = make_temp_dir();
	char *out = run_scene(dir, clean_scene, "pc2");
	// dots.pc2 holds 2 points a sample; move point 0 of sample 2 into the ball, at (5, 1.25, 0)
	// then (the ball rises from y = 1 to 1.5 over frames 0 to 3).
	char path[1024];
	snprintf(path, sizeof path, "%s/dots.pc2", out);
	long sample = 32 + 2 * 2 * 12;
	patch_float(path, sample + 0, 5.0f);
	patch_float(path, sample + 4, 1.3333f);
	patch_float(path, sample + 8, 0.0f);
	cli_result r = check(out, NULL, NULL);
	cr_expect_eq(r.code, 1, "stdout: %s stderr: %s", r.out, r.err);
	cr_expect(strstr(r.out, "frame 2: 0 crossing triangle pairs, 1 vertex inside colliders (ball 1)") != NULL,
	          "%s", r.out);
	for (int frame = 0; frame <= 3; ++frame) {
		json_t *line = check_line(out, frame);
		cr_expect_eq(get_int(line, "inside_colliders"), frame == 2 ? 1 : 0, "frame %d", frame);
		json_decref(line);
	}
	free_result(&r);
	free(out);
	remove_tree(dir);
	free(dir);
}

Test(cli_check, bad_arguments_and_unreadable_folders_exit_2_with_a_message)
{
	const char *none[] = {"plait", "check"};
	cli_result r = run_cli(2, none);
	cr_expect_eq(r.code, 2);
	cr_expect(strstr(r.err, "which folder?") != NULL, "%s", r.err);
	cr_expect(strstr(r.err, "usage: plait check DIR") != NULL, "%s", r.err);
	free_result(&r);

	const char *unknown[] = {"plait", "check", "/tmp", "--bogus"};
	r = run_cli(4, unknown);
	cr_expect_eq(r.code, 2);
	cr_expect(strstr(r.err, "unknown option '--bogus'") != NULL, "%s", r.err);
	free_result(&r);

	r = check("/tmp/plait_check_no_such_folder", NULL, NULL);
	cr_expect_eq(r.code, 2);
	cr_expect(strstr(r.err, "/tmp/plait_check_no_such_folder: no such folder") != NULL, "%s", r.err);
	free_result(&r);

	char *dir = make_temp_dir();
	r = check(dir, NULL, NULL);
	cr_expect_eq(r.code, 2);
	cr_expect(strstr(r.err, "manifest.json: no manifest") != NULL, "%s", r.err);
	free_result(&r);

	write_text(dir, "manifest.json", "{\"manifest\": 1, \"format\": \"obj\",");
	r = check(dir, NULL, NULL);
	cr_expect_eq(r.code, 2);
	cr_expect(strstr(r.err, "JSON syntax error") != NULL, "%s", r.err);
	free_result(&r);

	write_text(dir, "manifest.json", crossing_manifest);
	r = check(dir, NULL, NULL);
	cr_expect_eq(r.code, 2);
	cr_expect(strstr(r.err, "a.0000.obj: cannot read: No such file or directory") != NULL, "%s", r.err);
	cr_expect_not(exists(dir, "check.jsonl"));
	free_result(&r);

	const char *help[] = {"plait", "check", "--help"};
	r = run_cli(3, help);
	cr_expect_eq(r.code, 0);
	cr_expect(strstr(r.out, "Exit status: 0") != NULL, "%s", r.out);
	free_result(&r);
	remove_tree(dir);
	free(dir);
}

static void truncate_file(const char *dir, const char *name, double keep)
{
	char path[1024];
	snprintf(path, sizeof path, "%s/%s", dir, name);
	struct stat info;
	cr_assert_eq(stat(path, &info), 0, "no %s", path);
	cr_assert_eq(truncate(path, (off_t)(keep * (double)info.st_size)), 0);
}

Test(cli_check, files_cut_short_exit_2_and_leave_nothing_behind)
{
	char *dir = make_temp_dir();
	char *out = run_scene(dir, clean_scene, "obj");
	truncate_file(out, "sheet.0002.obj", 0.5);
	cli_result r = check(out, NULL, NULL);
	cr_expect_eq(r.code, 2, "stdout: %s stderr: %s", r.out, r.err);
	cr_expect(strstr(r.err, "sheet.0002.obj") != NULL, "%s", r.err);
	cr_expect(strstr(r.err, "cut short") != NULL || strstr(r.err, "a vertex needs") != NULL, "%s", r.err);
	cr_expect_not(exists(out, "check.jsonl"));
	cr_expect_eq(count_temporary_files(out), 0);
	free_result(&r);
	free(out);
	remove_tree(dir);
	free(dir);

	dir = make_temp_dir();
	out = run_scene(dir, clean_scene, "pc2");
	truncate_file(out, "sheet.pc2", 0.8);
	r = check(out, NULL, NULL);
	cr_expect_eq(r.code, 2, "stdout: %s stderr: %s", r.out, r.err);
	cr_expect(strstr(r.err, "sheet.pc2") != NULL && strstr(r.err, "cut short") != NULL, "%s", r.err);
	cr_expect_not(exists(out, "check.jsonl"));
	cr_expect_eq(count_temporary_files(out), 0);
	free_result(&r);
	free(out);
	remove_tree(dir);
	free(dir);
}

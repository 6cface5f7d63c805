/* `plait explain`: a scene's settings and the order in which the solver runs its passes. */
#include "cli.h"

#include "scene.h"

#include <jansson.h>
#include <stdlib.h>
#include <string.h>

static void plait_explain_usage(FILE *f)
{
	fprintf(f, "usage: plait explain [SCENE.json] [--json]\n");
}

static void plait_explain_help(FILE *f)
{
	plait_explain_usage(f);
	fprintf(f, "\nPrints the scene's settings and, for each substep of a frame, the kinds of constraint\n"
	           "pass in the order the solver runs them (without a scene: the built-in demo).\n\n"
	           "  --json      print only {\"substeps\":[{\"sequence\":[\"stretch\",...]},...]}\n"
	           "  -h, --help  this help\n");
}

// The kinds of one substep; *names is malloc'ed. Returns the count (0 on failure).
static int plait_explain_sequence(plait_world_id world, int substep, const char ***names)
{
	const char *small[64];
	int count = plait_world_get_schedule(world, substep, small, 64);
	*names = malloc(sizeof(char *) * (size_t)(count > 0 ? count : 1));
	if (*names == NULL || count <= 0)
		return 0;
	if (count <= 64)
		memcpy(*names, small, sizeof(char *) * (size_t)count);
	else
		plait_world_get_schedule(world, substep, *names, count);
	return count;
}

static int plait_explain_json(plait_world_id world, FILE *out)
{
	json_t *substeps = json_array();
	int substep_count = plait_world_get_substep_count(world);
	for (int s = 0; s < substep_count; ++s) {
		const char **names;
		int count = plait_explain_sequence(world, s, &names);
		json_t *sequence = json_array();
		for (int i = 0; i < count; ++i)
			json_array_append_new(sequence, json_string(names[i] != NULL ? names[i] : "?"));
		free(names);
		json_t *item = json_object();
		json_object_set_new(item, "sequence", sequence);
		json_array_append_new(substeps, item);
	}
	json_t *root = json_object();
	json_object_set_new(root, "substeps", substeps);
	char *text = json_dumps(root, JSON_COMPACT | JSON_PRESERVE_ORDER);
	json_decref(root);
	if (text == NULL)
		return PLAIT_EXIT_FAILURE;
	fprintf(out, "%s\n", text);
	free(text);
	return PLAIT_EXIT_OK;
}

// "stretch x7, bend, collision": runs of one kind compressed.
static void plait_explain_print_sequence(FILE *out, const char **names, int count)
{
	for (int i = 0; i < count;) {
		int run = 1;
		while (i + run < count && strcmp(names[i + run], names[i]) == 0)
			++run;
		fprintf(out, "%s%s", i > 0 ? ", " : "", names[i]);
		if (run > 1)
			fprintf(out, " x%d", run);
		i += run;
	}
	fputc('\n', out);
}

static bool plait_same_sequence(const char **a, int na, const char **b, int nb)
{
	if (na != nb)
		return false;
	for (int i = 0; i < na; ++i)
		if (strcmp(a[i], b[i]) != 0)
			return false;
	return true;
}

/* Seed 000 §4.1: cloth resting on a collider stretches where it rests when stretch passes far
 * outnumber collision passes in a substep. Said when a scene has colliders, no contact passes,
 * and a substep with three stretch passes or more per collision pass. */
static void plait_explain_stretch_note(const plait_scene *scene, plait_world_id world,
                                       const plait_world_def *w, int substep_count, FILE *out)
{
	bool colliders = false;
	for (int i = 0; i < scene->object_count; ++i)
		colliders = colliders || scene->objects[i].type == PLAIT_OBJECT_COLLIDER;
	if (!colliders || w->contact_pass_interval > 0)
		return;
	int most = 0;
	for (int s = 0; s < substep_count; ++s) {
		const char **names;
		int count = plait_explain_sequence(world, s, &names), stretch = 0, collision = 0;
		for (int e = 0; e < count; ++e) {
			stretch += strcmp(names[e], "stretch") == 0;
			collision += strcmp(names[e], "collision") == 0;
		}
		free(names);
		if (collision > 0 && stretch / collision > most)
			most = stretch / collision;
	}
	if (most >= 3)
		fprintf(
		    out,
		    "note: up to %d stretch passes per collision pass in a substep: cloth resting on a collider\n"
		    "      stretches where it rests (the stretch passes pull it in, the collision pass pushes it\n"
		    "      out). \"contact_pass_interval\": 1 in the world (the default) adds cheap contact passes\n"
		    "      between them (docs/architecture.md, \"Contact passes\"); more substeps also help.\n",
		    most);
}

static void plait_explain_text(const plait_scene *scene, plait_world_id world, FILE *out)
{
	plait_world_def w = plait_world_get_def(world);
	fprintf(out, "scene %s\n", scene->file);
	fprintf(out, "  %d frames at %g fps, %d substeps per frame, %d collision iterations per frame\n",
	        scene->frames, w.fps, w.substeps, w.max_collision_iterations);
	if (w.contact_pass_interval > 0)
		fprintf(out, "  a contact pass or collision iteration at least every %d stretch iterations\n",
		        w.contact_pass_interval);
	else
		fprintf(out, "  no contact passes (contact_pass_interval 0): collision iterations only\n");
	fprintf(out, "  gravity [%g, %g, %g] m/s^2, air density %g kg/m^3\n", w.gravity.x, w.gravity.y,
	        w.gravity.z, w.air_density);
	if (w.wind.speed > 0.0f)
		fprintf(out, "  wind %g m/s toward [%g, %g, %g], noise %g\n", w.wind.speed, w.wind.direction.x,
		        w.wind.direction.y, w.wind.direction.z, w.wind.noise);
	else
		fprintf(out, "  no wind\n");
	fprintf(out, "  space scale %g m per unit, time scale %g\n", w.space_scale, w.time_scale);
	fprintf(out, "objects\n");
	static const char *const types[] = {"cloth", "curve", "particles", "collider"};
	static const char *const shapes[] = {"plane", "sphere", "capsule", "box", "mesh"};
	for (int i = 0; i < scene->object_count; ++i) {
		const plait_scene_object *o = &scene->objects[i];
		fprintf(out, "  %-16s %-9s ", o->name, types[o->type]);
		if (o->type == PLAIT_OBJECT_COLLIDER && o->sequence.frame_count > 0)
			fprintf(out, "%s%s, deforming over %d frame%s\n", shapes[o->collider.shape],
			        o->keyframe_count > 0 ? ", keyframed" : "", o->sequence.frame_count,
			        o->sequence.frame_count == 1 ? "" : "s");
		else if (o->type == PLAIT_OBJECT_COLLIDER)
			fprintf(out, "%s%s\n", shapes[o->collider.shape], o->keyframe_count > 0 ? ", keyframed" : "");
		else if (o->type == PLAIT_OBJECT_CLOTH)
			fprintf(out, "%d vertices, %d faces, %d pins\n", o->vertex_count, o->face_count, o->pin_count);
		else
			fprintf(out, "%d vertices, %d pins\n", o->vertex_count, o->pin_count);
	}
	int substep_count = plait_world_get_substep_count(world);
	fprintf(out, "schedule: each frame runs %d substep%s, each a sequence of passes in this order\n",
	        substep_count, substep_count == 1 ? "" : "s");
	// Substeps with the same sequence as the one before are folded into one line.
	for (int s = 0; s < substep_count;) {
		const char **names;
		int count = plait_explain_sequence(world, s, &names);
		int last = s;
		while (last + 1 < substep_count) {
			const char **next;
			int next_count = plait_explain_sequence(world, last + 1, &next);
			bool same = plait_same_sequence(names, count, next, next_count);
			free(next);
			if (!same)
				break;
			++last;
		}
		if (last > s)
			fprintf(out, "  substeps %d-%d (%d passes each): ", s + 1, last + 1, count);
		else
			fprintf(out, "  substep %d (%d passes): ", s + 1, count);
		plait_explain_print_sequence(out, names, count);
		free(names);
		s = last + 1;
	}
	plait_explain_stretch_note(scene, world, &w, substep_count, out);
}

int plait_cli_explain(int argc, char **argv, FILE *out, FILE *err)
{
	const char *scene_path = NULL;
	bool as_json = false;
	for (int i = 1; i < argc; ++i) {
		const char *arg = argv[i];
		if (strcmp(arg, "-h") == 0 || strcmp(arg, "--help") == 0) {
			plait_explain_help(out);
			return PLAIT_EXIT_OK;
		} else if (strcmp(arg, "--json") == 0) {
			as_json = true;
		} else if (arg[0] == '-' && arg[1] != '\0') {
			fprintf(err, "plait explain: unknown option '%s'\n", arg);
			plait_explain_usage(err);
			return PLAIT_EXIT_USAGE;
		} else if (scene_path != NULL) {
			fprintf(err, "plait explain: one scene at a time (got '%s' and '%s')\n", scene_path, arg);
			plait_explain_usage(err);
			return PLAIT_EXIT_USAGE;
		} else {
			scene_path = arg;
		}
	}
	plait_tool_error error = {{0}};
	plait_scene scene;
	if (!plait_cli_load_scene(scene_path, &scene, &error)) {
		fprintf(err, "%s\n", error.message);
		return PLAIT_EXIT_FAILURE;
	}
	for (int i = 0; i < scene.warning_count; ++i)
		fprintf(err, "warning: %s\n", scene.warnings[i]);
	plait_world_id world;
	if (!plait_scene_create_world(&scene, &world, &error)) {
		fprintf(err, "%s\n", error.message);
		plait_scene_free(&scene);
		return PLAIT_EXIT_FAILURE;
	}
	int status = PLAIT_EXIT_OK;
	if (as_json)
		status = plait_explain_json(world, out);
	else
		plait_explain_text(&scene, world, out);
	plait_destroy_world(world);
	plait_scene_free(&scene);
	return status;
}

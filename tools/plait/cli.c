#include "cli.h"

#include "demo_scene.h"
#include "scene.h"

#include <string.h>

static void plait_cli_usage(FILE *f)
{
	fprintf(f, "usage: plait run [SCENE.json] [--out DIR] [--frames N] [--format obj|pc2]\n"
	           "       plait check DIR [--log FILE] [--tolerance METRES] [--threads N]\n"
	           "       plait explain [SCENE.json] [--json]\n"
	           "       plait --help | --version\n");
}

static void plait_cli_help(FILE *f)
{
	fprintf(f, "plait %d.%d.%d: cloth, curve and particle dynamics from scene files\n\n", PLAIT_VERSION_MAJOR,
	        PLAIT_VERSION_MINOR, PLAIT_VERSION_PATCH);
	plait_cli_usage(f);
	fprintf(f,
	        "\ncommands:\n"
	        "  run      simulate a scene and write its frames (without a scene: a built-in demo)\n"
	        "  check    count crossing triangles and vertices inside colliders in what run wrote\n"
	        "  explain  print a scene's settings and the solver's schedule of constraint passes\n"
	        "\n`plait run --help`, `plait check --help` and `plait explain --help` describe their options.\n"
	        "Scene files are described in docs/scene-format.md.\n");
}

bool plait_cli_load_scene(const char *path, plait_scene *scene, plait_tool_error *error)
{
	if (path == NULL)
		return plait_scene_load_string(plait_demo_scene_json(), "(built-in demo)", ".", scene, error);
	return plait_scene_load(path, scene, error);
}

const char *plait_cli_option_value(int argc, char **argv, int *i, const char *name, bool *missing)
{
	size_t n = strlen(name);
	const char *arg = argv[*i];
	if (strncmp(arg, name, n) != 0)
		return NULL;
	if (arg[n] == '=')
		return arg + n + 1;
	if (arg[n] != '\0')
		return NULL;
	if (*i + 1 >= argc) {
		*missing = true;
		return NULL;
	}
	*i += 1;
	return argv[*i];
}

int plait_cli_main(int argc, char **argv, FILE *out, FILE *err)
{
	if (argc < 2) {
		plait_cli_usage(err);
		return PLAIT_EXIT_USAGE;
	}
	const char *command = argv[1];
	if (strcmp(command, "--help") == 0 || strcmp(command, "-h") == 0 || strcmp(command, "help") == 0) {
		plait_cli_help(out);
		return PLAIT_EXIT_OK;
	}
	if (strcmp(command, "--version") == 0) {
		fprintf(out, "plait %d.%d.%d\n", PLAIT_VERSION_MAJOR, PLAIT_VERSION_MINOR, PLAIT_VERSION_PATCH);
		return PLAIT_EXIT_OK;
	}
	if (strcmp(command, "run") == 0)
		return plait_cli_run(argc - 1, argv + 1, out, err);
	if (strcmp(command, "check") == 0)
		return plait_cli_check(argc - 1, argv + 1, out, err);
	if (strcmp(command, "explain") == 0)
		return plait_cli_explain(argc - 1, argv + 1, out, err);
	fprintf(err, "plait: unknown command '%s'\n", command);
	plait_cli_usage(err);
	return PLAIT_EXIT_USAGE;
}

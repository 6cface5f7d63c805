#include "files.h"

#include <errno.h>
#include <stdlib.h>
#include <string.h>
#include <sys/stat.h>

bool plait_make_dirs(const char *path, plait_tool_error *error)
{
	char *copy = strdup(path);
	if (copy == NULL)
		return plait_tool_error_set(error, "out of memory");
	size_t length = strlen(copy);
	// Create each prefix ending before a '/', then the whole path.
	for (size_t i = 1; i <= length; ++i) {
		if (copy[i] != '/' && copy[i] != '\0')
			continue;
		char saved = copy[i];
		copy[i] = '\0';
		if (mkdir(copy, 0777) != 0 && errno != EEXIST) {
			int code = errno;
			plait_tool_error_set(error, "%s: cannot create folder: %s", copy, strerror(code));
			free(copy);
			return false;
		}
		copy[i] = saved;
	}
	struct stat info;
	bool is_dir = stat(path, &info) == 0 && S_ISDIR(info.st_mode);
	free(copy);
	if (!is_dir)
		return plait_tool_error_set(error, "%s: exists and is not a folder", path);
	return true;
}

static char *plait_join(const char *dir, const char *prefix, const char *name, const char *suffix)
{
	size_t size = strlen(dir) + strlen(prefix) + strlen(name) + strlen(suffix) + 2;
	char *path = malloc(size);
	if (path != NULL)
		snprintf(path, size, "%s/%s%s%s", dir, prefix, name, suffix);
	return path;
}

bool plait_atomic_open(plait_atomic_file *atomic, const char *dir, const char *name, plait_tool_error *error)
{
	*atomic = (plait_atomic_file){0};
	atomic->temp_path = plait_join(dir, ".", name, ".tmp");
	atomic->final_path = plait_join(dir, "", name, "");
	if (atomic->temp_path == NULL || atomic->final_path == NULL) {
		plait_atomic_abort(atomic);
		return plait_tool_error_set(error, "out of memory");
	}
	atomic->file = fopen(atomic->temp_path, "wb");
	if (atomic->file == NULL) {
		int code = errno;
		plait_tool_error_set(error, "%s: cannot write: %s", atomic->temp_path, strerror(code));
		plait_atomic_abort(atomic);
		return false;
	}
	return true;
}

bool plait_atomic_commit(plait_atomic_file *atomic, plait_tool_error *error)
{
	bool ok = atomic->file != NULL;
	if (ok) {
		ok = fflush(atomic->file) == 0 && ferror(atomic->file) == 0;
		ok = fclose(atomic->file) == 0 && ok;
		atomic->file = NULL;
	}
	if (ok && rename(atomic->temp_path, atomic->final_path) != 0)
		ok = false;
	if (!ok) {
		int code = errno;
		plait_tool_error_set(error, "%s: cannot write: %s", atomic->final_path, strerror(code));
		plait_atomic_abort(atomic);
		return false;
	}
	free(atomic->temp_path);
	free(atomic->final_path);
	*atomic = (plait_atomic_file){0};
	return true;
}

void plait_atomic_abort(plait_atomic_file *atomic)
{
	if (atomic->file != NULL)
		fclose(atomic->file);
	if (atomic->temp_path != NULL)
		remove(atomic->temp_path);
	free(atomic->temp_path);
	free(atomic->final_path);
	*atomic = (plait_atomic_file){0};
}

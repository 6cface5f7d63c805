#include "mesh_sequence.h"

#include <dirent.h>
#include <errno.h>
#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

// Frame numbers go as far as a scene's frames do.
#define PLAIT_SEQUENCE_MAX_FRAME 1000000

void plait_frame_pattern_free(plait_frame_pattern *pattern)
{
	free(pattern->folder);
	free(pattern->prefix);
	free(pattern->suffix);
	*pattern = (plait_frame_pattern){0};
}

static char *plait_join_folder(const char *base_dir, const char *folder, size_t folder_length)
{
	size_t size = strlen(base_dir) + folder_length + 2;
	char *joined = malloc(size);
	if (joined == NULL)
		return NULL;
	if (folder_length > 0 && folder[0] == '/')
		snprintf(joined, size, "%.*s", (int)folder_length, folder);
	else if (folder_length == 0)
		snprintf(joined, size, "%s", base_dir);
	else
		snprintf(joined, size, "%s/%.*s", base_dir, (int)folder_length, folder);
	return joined;
}

bool plait_frame_pattern_parse(const char *base_dir, const char *pattern, plait_frame_pattern *parsed,
                               char *why, size_t why_size)
{
	*parsed = (plait_frame_pattern){0};
	size_t length = strlen(pattern);
	// Literal text before and after the number, with %% turned into %.
	char *before = malloc(length + 1), *after = malloc(length + 1);
	if (before == NULL || after == NULL) {
		free(before);
		free(after);
		snprintf(why, why_size, "out of memory");
		return false;
	}
	size_t before_length = 0, after_length = 0;
	int numbers = 0;
	bool ok = true;
	for (size_t i = 0; i < length && ok; ++i) {
		char c = pattern[i];
		if (c == '%' && pattern[i + 1] == '%') {
			++i;
		} else if (c == '%') {
			size_t j = i + 1;
			bool zero_pad = pattern[j] == '0';
			j += zero_pad;
			int width = 0;
			while (pattern[j] >= '0' && pattern[j] <= '9' && width < 100)
				width = 10 * width + (pattern[j++] - '0');
			if (pattern[j] != 'd' || (zero_pad && (width < 1 || width > 9)) || (!zero_pad && width != 0)) {
				snprintf(why, why_size, "%.*s is not %%d or %%0Nd", (int)(j + 1 - i), pattern + i);
				ok = false;
			} else if (++numbers > 1) {
				snprintf(why, why_size, "more than one frame number");
				ok = false;
			}
			parsed->zero_pad = zero_pad;
			parsed->width = width;
			i = j;
			continue;
		}
		if (numbers == 0)
			before[before_length++] = c;
		else
			after[after_length++] = c;
	}
	before[before_length] = '\0';
	after[after_length] = '\0';
	if (ok && numbers == 0) {
		snprintf(why, why_size, "no frame number");
		ok = false;
	}
	if (ok && strchr(after, '/') != NULL) {
		snprintf(why, why_size, "the frame number is in a folder name, not in the file name");
		ok = false;
	}
	if (ok) {
		char *slash = strrchr(before, '/');
		size_t folder_length = slash == NULL ? 0 : (slash == before ? 1 : (size_t)(slash - before));
		parsed->folder = plait_join_folder(base_dir, before, folder_length);
		parsed->prefix = strdup(slash == NULL ? before : slash + 1);
		parsed->suffix = strdup(after);
		if (parsed->folder == NULL || parsed->prefix == NULL || parsed->suffix == NULL) {
			snprintf(why, why_size, "out of memory");
			ok = false;
		}
	}
	free(before);
	free(after);
	if (!ok)
		plait_frame_pattern_free(parsed);
	return ok;
}

static void plait_frame_name(const plait_frame_pattern *pattern, int frame, char *name, size_t size)
{
	if (pattern->zero_pad)
		snprintf(name, size, "%s%0*d%s", pattern->prefix, pattern->width, frame, pattern->suffix);
	else
		snprintf(name, size, "%s%d%s", pattern->prefix, frame, pattern->suffix);
}

void plait_frame_pattern_path(const plait_frame_pattern *pattern, int frame, char *path, size_t size)
{
	char name[1024];
	plait_frame_name(pattern, frame, name, sizeof name);
	size_t folder_length = strlen(pattern->folder);
	bool slash = folder_length > 0 && pattern->folder[folder_length - 1] == '/';
	snprintf(path, size, "%s%s%s", pattern->folder, slash ? "" : "/", name);
}

// The frame number a file name stands for under the pattern, or -1. Only the name the pattern
// itself would write counts ("arm.7.obj" is not frame 7 of "arm.%04d.obj").
static int plait_frame_of_name(const plait_frame_pattern *pattern, const char *name)
{
	size_t length = strlen(name), prefix = strlen(pattern->prefix), suffix = strlen(pattern->suffix);
	if (length <= prefix + suffix || length - prefix - suffix > 9 ||
	    strncmp(name, pattern->prefix, prefix) != 0 || strcmp(name + length - suffix, pattern->suffix) != 0)
		return -1;
	int frame = 0;
	for (size_t i = prefix; i < length - suffix; ++i) {
		if (name[i] < '0' || name[i] > '9')
			return -1;
		frame = 10 * frame + (name[i] - '0');
	}
	char expected[1024];
	plait_frame_name(pattern, frame, expected, sizeof expected);
	return strcmp(expected, name) == 0 ? frame : -1;
}

static int plait_compare_frames(const void *a, const void *b)
{
	int x = *(const int *)a, y = *(const int *)b;
	return (x > y) - (x < y);
}

// The frame numbers of the pattern's files from 1 up, sorted; *count of them.
static bool plait_find_frames(const plait_frame_pattern *pattern, int **frames, int *count,
                              plait_tool_error *error)
{
	*frames = NULL;
	*count = 0;
	char first[1200];
	plait_frame_pattern_path(pattern, 1, first, sizeof first);
	DIR *dir = opendir(pattern->folder);
	if (dir == NULL)
		return plait_tool_error_set(error, "%s: cannot open its folder: %s", first, strerror(errno));
	int capacity = 0;
	bool ok = true;
	struct dirent *entry;
	while (ok && (entry = readdir(dir)) != NULL) {
		int frame = plait_frame_of_name(pattern, entry->d_name);
		if (frame < 1 || frame > PLAIT_SEQUENCE_MAX_FRAME)
			continue;
		if (*count == capacity) {
			capacity = capacity > 0 ? 2 * capacity : 64;
			int *grown = realloc(*frames, sizeof(int) * (size_t)capacity);
			if (grown == NULL) {
				ok = plait_tool_error_set(error, "%s: out of memory listing the sequence", first);
				break;
			}
			*frames = grown;
		}
		(*frames)[(*count)++] = frame;
	}
	closedir(dir);
	if (!ok) {
		free(*frames);
		*frames = NULL;
		*count = 0;
		return false;
	}
	if (*count > 0)
		qsort(*frames, (size_t)*count, sizeof(int), plait_compare_frames);
	return true;
}

bool plait_mesh_sequence_load(const plait_frame_pattern *pattern, const plait_mesh_layout *layout,
                              plait_mesh_sequence *sequence, plait_tool_error *error)
{
	*sequence = (plait_mesh_sequence){0};
	int *frames, count;
	if (!plait_find_frames(pattern, &frames, &count, error))
		return false;
	char path[1200];
	for (int k = 0; k <= count; ++k) {
		if (k < count && frames[k] == k + 1)
			continue;
		if (k == count && count > 0)
			break;
		// Frame k + 1 is missing, with later ones present (or none at all).
		plait_frame_pattern_path(pattern, k + 1, path, sizeof path);
		if (count == 0)
			plait_tool_error_set(
			    error,
			    "%s: missing: expected a file for every frame from 1 to the sequence's last, "
			    "found none",
			    path);
		else
			plait_tool_error_set(error,
			                     "%s: missing: expected a file for every frame from 1 to the sequence's last "
			                     "(%d)",
			                     path, frames[count - 1]);
		free(frames);
		return false;
	}
	free(frames);
	size_t vertex_count = (size_t)layout->vertex_count;
	if ((size_t)count > SIZE_MAX / sizeof(plait_vec3) / (vertex_count > 0 ? vertex_count : 1))
		return plait_tool_error_set(error, "%s: out of memory for %d frames", layout->path, count);
	sequence->positions = malloc(sizeof(plait_vec3) * vertex_count * (size_t)count);
	if (sequence->positions == NULL)
		return plait_tool_error_set(error, "%s: out of memory for %d frames", layout->path, count);
	sequence->frame_count = count;
	sequence->vertex_count = layout->vertex_count;
	for (int frame = 1; frame <= count; ++frame) {
		plait_frame_pattern_path(pattern, frame, path, sizeof path);
		if (!plait_mesh_load_positions(path, layout, sequence->positions + (size_t)(frame - 1) * vertex_count,
		                               error)) {
			plait_mesh_sequence_free(sequence);
			return false;
		}
	}
	return true;
}

void plait_mesh_sequence_free(plait_mesh_sequence *sequence)
{
	free(sequence->positions);
	*sequence = (plait_mesh_sequence){0};
}

const plait_vec3 *plait_mesh_sequence_frame(const plait_mesh_sequence *sequence, int frame)
{
	int f = frame < 1 ? 1 : (frame > sequence->frame_count ? sequence->frame_count : frame);
	return sequence->positions + (size_t)(f - 1) * (size_t)sequence->vertex_count;
}

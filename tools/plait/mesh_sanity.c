#include "mesh_sanity.h"

#include <ctype.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/stat.h>

#define PLAIT_HEADER_BYTES 4096

// Next whitespace-separated token of text at *at, skipping '#' comments to the end of line.
static const char *plait_next_token(const char *text, size_t *at, size_t *length)
{
	size_t i = *at;
	for (;;) {
		while (text[i] != '\0' && isspace((unsigned char)text[i]))
			++i;
		if (text[i] != '#')
			break;
		while (text[i] != '\0' && text[i] != '\n')
			++i;
	}
	size_t start = i;
	while (text[i] != '\0' && !isspace((unsigned char)text[i]))
		++i;
	*at = i;
	*length = i - start;
	return *length > 0 ? text + start : NULL;
}

static bool plait_parse_count(const char *token, size_t length, double *out)
{
	if (token == NULL || length == 0 || length > 30)
		return false;
	char buffer[32];
	memcpy(buffer, token, length);
	buffer[length] = '\0';
	char *end;
	*out = strtod(buffer, &end);
	return *end == '\0';
}

// OFF: "[ST][C][N][4][n]OFF", then vertex, face and edge counts. ASCII lines are at least
// "0 0 0\n" (6 bytes) per vertex and "3 0 1 2\n" (8 bytes) per face.
static bool plait_check_off(const char *path, const char *text, double file_size, plait_tool_error *error)
{
	size_t at = 0, length;
	const char *keyword = plait_next_token(text, &at, &length);
	if (keyword == NULL || length < 3 || length > 8 || strncmp(keyword + length - 3, "OFF", 3) != 0)
		return true;
	if (strstr(text, "BINARY") != NULL)
		return true;
	double vertices, faces;
	const char *token = plait_next_token(text, &at, &length);
	if (!plait_parse_count(token, length, &vertices))
		return true; // assimp reports malformed headers itself
	token = plait_next_token(text, &at, &length);
	if (!plait_parse_count(token, length, &faces))
		return true;
	if (vertices < 0.0 || faces < 0.0 || vertices * 6.0 + faces * 8.0 > file_size)
		return plait_tool_error_set(
		    error,
		    "%s: the OFF header declares %.0f vertices and %.0f faces, more than a file "
		    "of %.0f bytes can hold",
		    path, vertices, faces, file_size);
	return true;
}

// PLY: "element NAME COUNT" lines before "end_header"; every element takes at least a byte.
static bool plait_check_ply(const char *path, const char *text, double file_size, plait_tool_error *error)
{
	if (strncmp(text, "ply", 3) != 0)
		return true;
	double total = 0.0;
	const char *line = text;
	while (line != NULL && *line != '\0' && strncmp(line, "end_header", 10) != 0) {
		if (strncmp(line, "element ", 8) == 0) {
			// The count is the last word of the line.
			const char *last = line + 8;
			for (const char *p = line + 8; *p != '\0' && *p != '\n'; ++p)
				if (*p == ' ' && p[1] != '\0' && p[1] != '\n' && p[1] != '\r')
					last = p + 1;
			total += strtod(last, NULL);
		}
		line = strchr(line, '\n');
		if (line != NULL)
			++line;
	}
	if (total > file_size)
		return plait_tool_error_set(
		    error,
		    "%s: the PLY header declares %.0f elements, more than a file of %.0f bytes "
		    "can hold",
		    path, total, file_size);
	return true;
}

bool plait_mesh_check_header(const char *path, plait_tool_error *error)
{
	struct stat info;
	if (stat(path, &info) != 0)
		return true; // the caller's open reports it
	FILE *file = fopen(path, "rb");
	if (file == NULL)
		return true;
	char text[PLAIT_HEADER_BYTES + 1];
	size_t length = fread(text, 1, PLAIT_HEADER_BYTES, file);
	fclose(file);
	text[length] = '\0';
	// Binary bytes end the text part early, which only shortens what is checked.
	double size = (double)info.st_size;
	return plait_check_off(path, text, size, error) && plait_check_ply(path, text, size, error);
}

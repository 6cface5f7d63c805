#include "test_cli.h"

#include <criterion/criterion.h>
#include <dirent.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "cli.h"

cli_result run_cli(int argc, const char **argv)
{
	cli_result result = {0};
	size_t out_size = 0, err_size = 0;
	FILE *out = open_memstream(&result.out, &out_size);
	FILE *err = open_memstream(&result.err, &err_size);
	cr_assert(out != NULL && err != NULL);
	result.code = plait_cli_main(argc, (char **)argv, out, err);
	fclose(out);
	fclose(err);
	return result;
}

void free_result(cli_result *result)
{
	free(result->out);
	free(result->err);
}

void remove_tree(const char *path)
{
	DIR *dir = opendir(path);
	if (dir != NULL) {
		struct dirent *entry;
		while ((entry = readdir(dir)) != NULL) {
			if (strcmp(entry->d_name, ".") == 0 || strcmp(entry->d_name, "..") == 0)
				continue;
			char child[1024];
			snprintf(child, sizeof child, "%s/%s", path, entry->d_name);
			remove_tree(child);
		}
		closedir(dir);
	}
	remove(path);
}

char *read_file(const char *path, size_t *size)
{
	FILE *f = fopen(path, "rb");
	if (f == NULL)
		return NULL;
	fseek(f, 0, SEEK_END);
	long n = ftell(f);
	fseek(f, 0, SEEK_SET);
	char *data = malloc((size_t)n + 1);
	size_t got = fread(data, 1, (size_t)n, f);
	fclose(f);
	data[got] = '\0';
	if (size != NULL)
		*size = got;
	return data;
}

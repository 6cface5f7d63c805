/* CCD tests: every query of shared/ccd against its exact ground truth (no miss allowed, extra hits
 * counted), the handcrafted set's extra hits against Tight Inclusion's published counts, and
 * constructed cases for the corners of the problem (grazing, parallel, coplanar, scales, fast
 * motion, thickness).
 *
 * PLAIT_CCD_TEST_STRIDE=n runs every n-th dataset query only (for slow sanitizer builds); the
 * default runs all of them. */
#define _POSIX_C_SOURCE 200809L

#include <criterion/criterion.h>
#include <criterion/logging.h>

#include <dirent.h>
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "collision/ccd.h"

#define CCD_DATA PLAIT_SHARED_DIR "/ccd"
#define TOL PLAIT_CCD_DEFAULT_TOLERANCE

/* Tight Inclusion's false positives on the handcrafted queries (Wang et al. 2021). */
#define TIGHT_INCLUSION_FP_VERTEX_FACE 108
#define TIGHT_INCLUSION_FP_EDGE_EDGE 214

/* ---- dataset loading ---------------------------------------------------------------------- */

typedef struct data_query {
	plait_ccd_motion motion;
	double max_time;
	double minimum_distance;
	/* Exact time of the first contact where the data set gives it, NAN otherwise. */
	double first_contact;
	bool truth;
	/* The expected answer must match exactly (ipc-toolkit's non-conservative checks). */
	bool strict;
} data_query;

typedef struct data_set {
	char name[512];
	bool vertex_face;
	data_query *queries;
	int count, capacity;
} data_set;

typedef struct data_sets {
	data_set *sets;
	int count, capacity;
} data_sets;

static data_set *add_set(data_sets *all, const char *name, bool vertex_face)
{
	if (all->count == all->capacity) {
		all->capacity = all->capacity ? 2 * all->capacity : 16;
		all->sets = realloc(all->sets, (size_t)all->capacity * sizeof(data_set));
	}
	data_set *set = &all->sets[all->count++];
	memset(set, 0, sizeof(*set));
	snprintf(set->name, sizeof(set->name), "%s", name);
	set->vertex_face = vertex_face;
	return set;
}

static data_query *add_query(data_set *set)
{
	if (set->count == set->capacity) {
		set->capacity = set->capacity ? 2 * set->capacity : 1024;
		set->queries = realloc(set->queries, (size_t)set->capacity * sizeof(data_query));
	}
	data_query *q = &set->queries[set->count++];
	memset(q, 0, sizeof(*q));
	q->max_time = 1.0;
	q->first_contact = NAN;
	return q;
}

static void free_sets(data_sets *all)
{
	for (int s = 0; s < all->count; s++)
		free(all->sets[s].queries);
	free(all->sets);
}

/* Parses up to 7 comma-separated numbers; returns how many. */
static int parse_row(const char *line, double value[7])
{
	int fields = 0;
	const char *cursor = line;
	while (fields < 7) {
		char *next;
		value[fields] = strtod(cursor, &next);
		if (next == cursor)
			break;
		fields++;
		cursor = next;
		if (*cursor != ',')
			break;
		cursor++;
	}
	return fields;
}

/* Rows "xn,xd,yn,yd,zn,zd[,truth]", eight per query; each coordinate xn/xd is an exact double. */
static int read_rows(FILE *file, data_set *set)
{
	char line[512];
	int row = 0, read = 0;
	data_query *q = NULL;
	while (fgets(line, sizeof(line), file)) {
		double value[7];
		int fields = line[0] == '#' ? 0 : parse_row(line, value);
		if (fields < 6)
			continue;
		if (row == 0)
			q = add_query(set);
		double *point = row < 4 ? q->motion.start[row] : q->motion.end[row - 4];
		for (int k = 0; k < 3; k++)
			point[k] = value[2 * k] / value[2 * k + 1];
		q->truth = fields == 7 && value[6] != 0.0;
		if (++row == 8) {
			row = 0;
			read++;
		}
	}
	return read;
}

static int read_csv(const char *path, data_set *set)
{
	bool gzipped = strstr(path, ".gz") != NULL;
	FILE *file;
	if (gzipped) {
		char command[1600];
		snprintf(command, sizeof(command), "gzip -dc '%s'", path);
		file = popen(command, "r");
	} else {
		file = fopen(path, "r");
	}
	cr_assert(file, "cannot read %s", path);
	int read = read_rows(file, set);
	if (gzipped)
		cr_assert_eq(pclose(file), 0, "gzip failed on %s", path);
	else
		fclose(file);
	return read;
}

/* A JSON list of booleans gives the truth of the last `count` queries. */
static void read_truth(const char *path, data_set *set, int count)
{
	FILE *file = fopen(path, "r");
	cr_assert(file, "cannot read %s", path);
	int index = set->count - count, c, seen = 0;
	while ((c = fgetc(file)) != EOF) {
		if (c != 't' && c != 'f')
			continue;
		cr_assert_lt(index, set->count, "%s has more entries than queries", path);
		set->queries[index++].truth = c == 't';
		seen++;
		while ((c = fgetc(file)) != EOF && c >= 'a' && c <= 'z')
			;
	}
	fclose(file);
	cr_assert_eq(seen, count, "%s: %d truth values for %d queries", path, seen, count);
}

/* "query_index,toi,kind" rows: the exact first contact of the positives of the last `count`. */
static void read_first_contacts(const char *path, data_set *set, int count)
{
	FILE *file = fopen(path, "r");
	if (!file)
		return;
	char line[256];
	while (fgets(line, sizeof(line), file)) {
		char *end;
		long index = strtol(line, &end, 10);
		if (end == line || *end != ',' || index < 0 || index >= count)
			continue;
		set->queries[set->count - count + index].first_contact = strtod(end + 1, NULL);
	}
	fclose(file);
}

static int compare_names(const void *a, const void *b)
{
	return strcmp(*(char *const *)a, *(char *const *)b);
}

/* Sorted entries of a directory, without hidden ones; names and array malloc'ed. */
static int list_dir(const char *path, char ***names)
{
	*names = NULL;
	DIR *dir = opendir(path);
	if (!dir)
		return 0;
	int count = 0, capacity = 0;
	struct dirent *entry;
	while ((entry = readdir(dir))) {
		if (entry->d_name[0] == '.')
			continue;
		if (count == capacity) {
			capacity = capacity ? 2 * capacity : 16;
			*names = realloc(*names, (size_t)capacity * sizeof(char *));
		}
		(*names)[count++] = strdup(entry->d_name);
	}
	closedir(dir);
	qsort(*names, (size_t)count, sizeof(char *), compare_names);
	return count;
}

static void free_list(char **names, int count)
{
	for (int i = 0; i < count; i++)
		free(names[i]);
	free(names);
}

static bool ends_with(const char *s, const char *suffix)
{
	size_t n = strlen(s), m = strlen(suffix);
	return n >= m && strcmp(s + n - m, suffix) == 0;
}

/* sample-queries/<scene>/<vertex-face|edge-edge>/<file>.csv: one set per kind. */
static void load_handcrafted(data_sets *all)
{
	const char *kinds[2] = {"vertex-face", "edge-edge"};
	char **scenes;
	int scene_count = list_dir(CCD_DATA "/sample-queries", &scenes);
	cr_assert_gt(scene_count, 0, "no scenes in %s/sample-queries", CCD_DATA);
	for (int kind = 0; kind < 2; kind++) {
		data_set *set = add_set(all, "sample-queries", kind == 0);
		for (int s = 0; s < scene_count; s++) {
			char dir[1024];
			snprintf(dir, sizeof(dir), "%s/sample-queries/%s/%s", CCD_DATA, scenes[s], kinds[kind]);
			char **files;
			int file_count = list_dir(dir, &files);
			for (int f = 0; f < file_count; f++) {
				char path[1400];
				snprintf(path, sizeof(path), "%s/%s", dir, files[f]);
				if (ends_with(files[f], ".csv"))
					read_csv(path, set);
			}
			free_list(files, file_count);
		}
	}
	free_list(scenes, scene_count);
}

/* sample-scalable-ccd-data/<scene>/queries/<step><vf|ee>.csv, truth in mma_bool/, and
 * queries_rebuilt/<step><vf|ee>.csv.gz with the truth in the 7th column: one set per file. */
static void load_scalable(data_sets *all)
{
	const char *root = CCD_DATA "/sample-scalable-ccd-data";
	char **scenes;
	int scene_count = list_dir(root, &scenes);
	cr_assert_gt(scene_count, 0, "no scenes in %s", root);
	for (int s = 0; s < scene_count; s++) {
		const char *folders[2] = {"queries", "queries_rebuilt"};
		for (int folder = 0; folder < 2; folder++) {
			char dir[1024];
			snprintf(dir, sizeof(dir), "%s/%s/%s", root, scenes[s], folders[folder]);
			char **files;
			int file_count = list_dir(dir, &files);
			for (int f = 0; f < file_count; f++) {
				if (!ends_with(files[f], ".csv") && !ends_with(files[f], ".csv.gz"))
					continue;
				char stem[256], name[512], path[1400];
				snprintf(stem, sizeof(stem), "%s", files[f]);
				*strstr(stem, ".csv") = '\0';
				snprintf(name, sizeof(name), "%s/%s", scenes[s], stem);
				data_set *set = add_set(all, name, ends_with(stem, "vf"));
				snprintf(path, sizeof(path), "%s/%s", dir, files[f]);
				int read = read_csv(path, set);
				cr_assert_gt(read, 0, "no queries in %s", path);
				if (folder == 0) {
					snprintf(path, sizeof(path), "%s/%s/mma_bool/%s_mma_bool.json", root, scenes[s], stem);
					read_truth(path, set, read);
				}
				snprintf(path, sizeof(path), "%s/%s/roots/%s_toi.csv", root, scenes[s], stem);
				read_first_contacts(path, set, read);
			}
			free_list(files, file_count);
		}
	}
	free_list(scenes, scene_count);
}

static char *read_text(const char *path)
{
	FILE *file = fopen(path, "rb");
	cr_assert(file, "cannot read %s", path);
	fseek(file, 0, SEEK_END);
	long size = ftell(file);
	fseek(file, 0, SEEK_SET);
	char *text = malloc((size_t)size + 1);
	size_t got = fread(text, 1, (size_t)size, file);
	text[got] = '\0';
	fclose(file);
	return text;
}

/* The value text after "key": in an object starting at `object`, or NULL. */
static const char *json_field(const char *object, const char *end, const char *key)
{
	const char *at = strstr(object, key);
	if (!at || (end && at > end))
		return NULL;
	at += strlen(key);
	return at + strspn(at, " :");
}

/* ipc_toolkit_ccd_cases.json: objects with name, kind, points (8 triples), expected, strict, tmax,
 * note. */
static void load_ipc_toolkit(data_sets *all)
{
	char *text = read_text(CCD_DATA "/ipc_toolkit_ccd_cases.json");
	data_set *sets[2] = {add_set(all, "ipc-toolkit", true), add_set(all, "ipc-toolkit", false)};
	const char *object = text;
	while ((object = strstr(object, "\"name\""))) {
		const char *end = strstr(object + 6, "\"name\"");
		bool vertex_face = strncmp(json_field(object, end, "\"kind\""), "\"vf\"", 4) == 0;
		data_query *q = add_query(sets[vertex_face ? 0 : 1]);
		char *cursor = (char *)json_field(object, end, "\"points\"");
		for (int row = 0; row < 8; row++) {
			double *point = row < 4 ? q->motion.start[row] : q->motion.end[row - 4];
			for (int k = 0; k < 3; k++) {
				cursor += strcspn(cursor, "-0123456789");
				point[k] = strtod(cursor, &cursor);
			}
		}
		q->truth = strncmp(json_field(object, end, "\"expected\""), "true", 4) == 0;
		q->strict = strncmp(json_field(object, end, "\"strict\""), "true", 4) == 0;
		q->max_time = strtod(json_field(object, end, "\"tmax\""), NULL);
		/* ipc-toolkit expects a hit in "EE Slow case 1" for every tolerance from 1e-6 up: its
		 * tolerance lets near misses within that distance count (the edges pass 5e-7 apart). Our
		 * tolerance is a time accuracy only, so the case is run with that distance as thickness. */
		const char *note = json_field(object, end, "\"note\"");
		if (note && strncmp(note, "\"run with tolerances 1e-6", 25) == 0)
			q->minimum_distance = 1e-6;
		object += 6;
	}
	free(text);
}

static data_sets load_all(void)
{
	data_sets all = {0};
	load_handcrafted(&all);
	load_scalable(&all);
	load_ipc_toolkit(&all);
	return all;
}

/* ---- running ------------------------------------------------------------------------------ */

typedef struct set_result {
	int queries, positives, false_negatives, false_positives, strict_mismatches;
	/* Hits checked against an exact first-contact time, and those reported after it. */
	int timed, late;
} set_result;

static int test_stride(void)
{
	const char *text = getenv("PLAIT_CCD_TEST_STRIDE");
	int stride = text ? atoi(text) : 1;
	return stride > 0 ? stride : 1;
}

static bool run_query(bool vertex_face, const data_query *q, double *toi)
{
	return vertex_face ? plait_ccd_vertex_face(&q->motion, q->minimum_distance, TOL, q->max_time, toi)
	                   : plait_ccd_edge_edge(&q->motion, q->minimum_distance, TOL, q->max_time, toi);
}

static set_result run_set(const data_set *set, int stride)
{
	set_result r = {0};
	for (int i = 0; i < set->count; i += stride) {
		const data_query *q = &set->queries[i];
		double toi;
		bool hit = run_query(set->vertex_face, q, &toi);
		r.queries++;
		r.positives += q->truth;
		if (q->truth && !hit) {
			r.false_negatives++;
			cr_log_error("%s %s query %d: contact missed", set->name, set->vertex_face ? "vf" : "ee", i);
		}
		r.false_positives += hit && !q->truth;
		r.strict_mismatches += q->strict && hit != q->truth;
		/* Never after the first contact (the exact time is printed to 20 digits). */
		r.timed += hit && !isnan(q->first_contact);
		if (hit && !isnan(q->first_contact) && toi > q->first_contact * (1.0 + 1e-15)) {
			r.late++;
			cr_log_error("%s query %d: toi %.17g after the first contact %.17g", set->name, i, toi,
			             q->first_contact);
		}
	}
	return r;
}

Test(ccd_dataset, no_false_negatives, .timeout = 600)
{
	data_sets all = load_all();
	int stride = test_stride();
	int total = 0;
	for (int s = 0; s < all.count; s++) {
		const data_set *set = &all.sets[s];
		set_result r = run_set(set, stride);
		cr_log_info("set=%s kind=%s queries=%d positives=%d fn=%d fp=%d toi_checked=%d", set->name,
		            set->vertex_face ? "vf" : "ee", r.queries, r.positives, r.false_negatives,
		            r.false_positives, r.timed);
		cr_expect_eq(r.false_negatives, 0, "%s: %d contacts missed", set->name, r.false_negatives);
		cr_expect_eq(r.late, 0, "%s: %d times of impact after the first contact", set->name, r.late);
		cr_expect_eq(r.strict_mismatches, 0, "%s: %d strict cases answered wrongly", set->name,
		             r.strict_mismatches);
		total += r.queries;
	}
	/* The README's counts: 3,085 + 4,194 handcrafted, 193,846 scalable, 419 ipc-toolkit. */
	if (stride == 1)
		cr_expect_eq(total, 3085 + 4194 + 193846 + 419, "expected every query of %s, ran %d", CCD_DATA,
		             total);
	free_sets(&all);
}

Test(ccd_dataset, handcrafted_false_positives_below_tight_inclusion)
{
	data_sets all = {0};
	load_handcrafted(&all);
	for (int s = 0; s < all.count; s++) {
		const data_set *set = &all.sets[s];
		set_result r = run_set(set, 1);
		int limit = set->vertex_face ? TIGHT_INCLUSION_FP_VERTEX_FACE : TIGHT_INCLUSION_FP_EDGE_EDGE;
		cr_log_info("handcrafted %s: %d false positives (Tight Inclusion: %d)",
		            set->vertex_face ? "vf" : "ee", r.false_positives, limit);
		cr_expect_lt(r.false_positives, limit);
		cr_expect_eq(r.false_negatives, 0);
	}
	free_sets(&all);
}

/* ---- constructed cases -------------------------------------------------------------------- */

static void set_point(double point[3], double x, double y, double z)
{
	point[0] = x;
	point[1] = y;
	point[2] = z;
}

/* The unit right triangle (0,0,0), (1,0,0), (0,1,0), at rest, and a vertex moving from a to b. */
static plait_ccd_motion vertex_and_triangle(const double a[3], const double b[3])
{
	plait_ccd_motion m;
	for (int s = 0; s < 2; s++) {
		double(*x)[3] = s == 0 ? m.start : m.end;
		set_point(x[0], s == 0 ? a[0] : b[0], s == 0 ? a[1] : b[1], s == 0 ? a[2] : b[2]);
		set_point(x[1], 0.0, 0.0, 0.0);
		set_point(x[2], 1.0, 0.0, 0.0);
		set_point(x[3], 0.0, 1.0, 0.0);
	}
	return m;
}

/* Every coordinate times scale, plus offset. */
static plait_ccd_motion transformed(plait_ccd_motion m, double scale, double offset)
{
	for (int i = 0; i < 4; i++) {
		for (int k = 0; k < 3; k++) {
			m.start[i][k] = m.start[i][k] * scale + offset;
			m.end[i][k] = m.end[i][k] * scale + offset;
		}
	}
	return m;
}

static bool hit_vertex_face(const plait_ccd_motion *m, double distance, double *toi)
{
	return plait_ccd_vertex_face(m, distance, TOL, 1.0, toi);
}

static bool hit_edge_edge(const plait_ccd_motion *m, double distance, double *toi)
{
	return plait_ccd_edge_edge(m, distance, TOL, 1.0, toi);
}

/* Edge a at rest from a0 to a1; edge b translates by `motion` from b0, b1. */
static plait_ccd_motion two_edges(const double a0[3], const double a1[3], const double b0[3],
                                  const double b1[3], const double motion[3])
{
	plait_ccd_motion m;
	for (int k = 0; k < 3; k++) {
		m.start[0][k] = m.end[0][k] = a0[k];
		m.start[1][k] = m.end[1][k] = a1[k];
		m.start[2][k] = b0[k];
		m.start[3][k] = b1[k];
		m.end[2][k] = b0[k] + motion[k];
		m.end[3][k] = b1[k] + motion[k];
	}
	return m;
}

/* A hit whose first contact is at `contact`: toi at or before it, and within the tolerance. (The
 * callers store the hit first: argument evaluation order would leave toi unread.) */
static void expect_hit_at(bool hit, double toi, double contact)
{
	cr_expect(hit, "missed a contact at t = %g", contact);
	cr_expect_leq(toi, contact, "toi %.17g after the contact at %.17g", toi, contact);
	cr_expect_geq(toi, contact - 2.0 * TOL, "toi %.17g far before the contact at %.17g", toi, contact);
}

Test(ccd_constructed, point_through_triangle)
{
	double a[3] = {0.25, 0.25, 1.0}, b[3] = {0.25, 0.25, -1.0}, toi;
	plait_ccd_motion m = vertex_and_triangle(a, b);
	bool hit = hit_vertex_face(&m, 0.0, &toi);
	expect_hit_at(hit, toi, 0.5);
}

Test(ccd_constructed, clearly_separated)
{
	double a[3] = {3.0, 3.0, 1.0}, b[3] = {3.0, 3.0, -1.0}, toi = -1.0;
	plait_ccd_motion m = vertex_and_triangle(a, b);
	cr_expect_not(hit_vertex_face(&m, 0.0, &toi));
	cr_expect_eq(toi, 1.0, "toi is max_time without a hit");
	double b0[3] = {0, 5, 1}, b1[3] = {1, 5, 1}, a0[3] = {0, 0, 0}, a1[3] = {1, 0, 0},
	       move[3] = {0.0, 1.0, 0.0};
	plait_ccd_motion e = two_edges(a0, a1, b0, b1, move);
	cr_expect_not(hit_edge_edge(&e, 0.0, &toi));
}

Test(ccd_constructed, grazing_contact_on_an_edge)
{
	/* Crosses the plane exactly on the triangle's edge y = 0 at t = 0.5. */
	double a[3] = {0.5, -1.0, 1.0}, b[3] = {0.5, 1.0, -1.0}, toi;
	plait_ccd_motion m = vertex_and_triangle(a, b);
	bool hit = hit_vertex_face(&m, 0.0, &toi);
	expect_hit_at(hit, toi, 0.5);
	/* The same path shifted 1e-9 outside the edge misses. */
	double c[3] = {0.5, -1.0 - 2e-9, 1.0}, d[3] = {0.5, 1.0 - 2e-9, -1.0};
	m = vertex_and_triangle(c, d);
	cr_expect_not(hit_vertex_face(&m, 0.0, &toi), "a 1e-9 near miss counted as contact");
	/* Edge-edge: two crossing edges whose lines meet exactly at an endpoint at t = 0.5. */
	double a0[3] = {0, 0, 0}, a1[3] = {1, 0, 0}, b0[3] = {1, -1, 1}, b1[3] = {1, 1, 1}, move[3] = {0, 0, -2};
	plait_ccd_motion e = two_edges(a0, a1, b0, b1, move);
	hit = hit_edge_edge(&e, 0.0, &toi);
	expect_hit_at(hit, toi, 0.5);
}

Test(ccd_constructed, parallel_edges)
{
	double a0[3] = {0, 0, 0}, a1[3] = {1, 0, 0}, toi;
	/* Overlapping in x, closing in y: they meet along a segment at t = 0.5. */
	double b0[3] = {0.5, 1, 0}, b1[3] = {1.5, 1, 0}, move[3] = {0, -2, 0};
	plait_ccd_motion m = two_edges(a0, a1, b0, b1, move);
	bool hit = hit_edge_edge(&m, 0.0, &toi);
	expect_hit_at(hit, toi, 0.5);
	/* Side by side without overlap in x: no contact. */
	double c0[3] = {1.5, 1, 0}, c1[3] = {2.5, 1, 0};
	m = two_edges(a0, a1, c0, c1, move);
	cr_expect_not(hit_edge_edge(&m, 0.0, &toi));
	/* Parallel and passing 0.1 above each other. */
	double d0[3] = {0.5, 1, 0.1}, d1[3] = {1.5, 1, 0.1};
	m = two_edges(a0, a1, d0, d1, move);
	cr_expect_not(hit_edge_edge(&m, 0.0, &toi));
}

Test(ccd_constructed, coplanar_motion)
{
	/* The vertex slides inside the triangle's plane and enters it through the edge x = 0 at t = 0.5. */
	double a[3] = {-1.0, 0.25, 0.0}, b[3] = {1.0, 0.25, 0.0}, toi;
	plait_ccd_motion m = vertex_and_triangle(a, b);
	bool hit = hit_vertex_face(&m, 0.0, &toi);
	expect_hit_at(hit, toi, 0.5);
	/* In the plane but passing beside the triangle. */
	double c[3] = {-1.0, 2.0, 0.0}, d[3] = {1.0, 2.0, 0.0};
	m = vertex_and_triangle(c, d);
	cr_expect_not(hit_vertex_face(&m, 0.0, &toi));
	/* Two edges sliding in the plane z = 0 until an endpoint touches the other edge at t = 0.5. */
	double a0[3] = {0, 0, 0}, a1[3] = {0, 2, 0}, b0[3] = {1, 1, 0}, b1[3] = {3, 1, 0}, move[3] = {-2, 0, 0};
	plait_ccd_motion e = two_edges(a0, a1, b0, b1, move);
	hit = hit_edge_edge(&e, 0.0, &toi);
	expect_hit_at(hit, toi, 0.5);
}

Test(ccd_constructed, vertex_exactly_on_an_edge)
{
	/* At rest on the triangle's edge from the start: contact at t = 0. */
	double a[3] = {0.5, 0.0, 0.0}, toi = -1.0;
	plait_ccd_motion m = vertex_and_triangle(a, a);
	cr_expect(hit_vertex_face(&m, 0.0, &toi));
	cr_expect_eq(toi, 0.0);
	/* An edge endpoint resting on the other edge's interior. */
	double a0[3] = {0, 0, 0}, a1[3] = {1, 0, 0}, b0[3] = {0.5, 0, 0}, b1[3] = {0.5, 1, 0},
	       still[3] = {0, 0, 0};
	plait_ccd_motion e = two_edges(a0, a1, b0, b1, still);
	cr_expect(hit_edge_edge(&e, 0.0, &toi));
	cr_expect_eq(toi, 0.0);
	/* Sharing a vertex counts as touching at t = 0. */
	double c0[3] = {1, 0, 0}, c1[3] = {1, 1, 0};
	e = two_edges(a0, a1, c0, c1, still);
	cr_expect(hit_edge_edge(&e, 0.0, &toi));
	cr_expect_eq(toi, 0.0);
}

Test(ccd_constructed, tiny_and_huge_scales)
{
	double a[3] = {0.25, 0.25, 1.0}, b[3] = {0.25, 0.25, -1.0}, c[3] = {1.5, 1.5, 1.0},
	       d[3] = {1.5, 1.5, -1.0};
	double scales[3] = {1e-6, 1.0, 1e4}, offsets[3] = {0.0, -3.0, 1e4}, toi;
	for (int i = 0; i < 3; i++) {
		for (int j = 0; j < 3; j++) {
			plait_ccd_motion crossing =
			    transformed(vertex_and_triangle(a, b), scales[i], offsets[j] * scales[i]);
			bool hit = hit_vertex_face(&crossing, 0.0, &toi);
			expect_hit_at(hit, toi, 0.5);
			plait_ccd_motion miss = transformed(vertex_and_triangle(c, d), scales[i], offsets[j] * scales[i]);
			cr_expect_not(hit_vertex_face(&miss, 0.0, &toi), "miss reported at scale %g offset %g", scales[i],
			              offsets[j]);
		}
	}
}

Test(ccd_constructed, fast_point_through_a_thin_triangle)
{
	/* 1000 m/s over a 1/72 s substep: 13.9 m per step, through a 1 cm triangle of zero thickness,
	 * crossing its plane at t = 0.3. */
	double step = 1000.0 / 72.0, size = 0.01;
	double a[3] = {0.25 * size, 0.25 * size, 0.3 * step}, b[3] = {0.25 * size, 0.25 * size, -0.7 * step}, toi;
	plait_ccd_motion m = vertex_and_triangle(a, b);
	for (int i = 1; i <= 3; i++) {
		for (int k = 0; k < 3; k++) {
			m.start[i][k] *= size;
			m.end[i][k] *= size;
		}
	}
	double contact = a[2] / (a[2] - b[2]);
	bool hit = hit_vertex_face(&m, 0.0, &toi);
	expect_hit_at(hit, toi, contact);
	/* The float convenience wrapper agrees and rounds the time down. */
	plait_ccd_motion_float f;
	for (int i = 0; i < 4; i++) {
		for (int k = 0; k < 3; k++) {
			f.start[i][k] = (float)m.start[i][k];
			f.end[i][k] = (float)m.end[i][k];
		}
	}
	float toi_float;
	cr_expect(plait_ccd_vertex_face_float(&f, 0.0f, (float)TOL, 1.0f, &toi_float));
	cr_expect_leq(toi_float, contact + 1e-6, "float toi %g", toi_float);
}

Test(ccd_constructed, minimum_distance)
{
	double d = 0.01, toi;
	/* Gliding over the triangle at height d / 2 (from outside to outside): within d. */
	double a[3] = {-1.0, 0.25, 0.5 * d}, b[3] = {2.0, 0.25, 0.5 * d};
	plait_ccd_motion m = vertex_and_triangle(a, b);
	cr_expect(hit_vertex_face(&m, d, &toi));
	cr_expect_leq(toi, (1.0 - 0.5 * d) / 3.0 + 1e-12, "toi %g after reaching the triangle", toi);
	cr_expect_not(hit_vertex_face(&m, 0.0, &toi), "touching reported at height d / 2");
	/* At height 2 d: no hit. */
	double c[3] = {-1.0, 0.25, 2.0 * d}, e[3] = {2.0, 0.25, 2.0 * d};
	m = vertex_and_triangle(c, e);
	cr_expect_not(hit_vertex_face(&m, d, &toi));
	/* Falling onto the triangle: distance d is reached at t = (1 - d) / 2. */
	double f[3] = {0.25, 0.25, 1.0}, g[3] = {0.25, 0.25, -1.0};
	m = vertex_and_triangle(f, g);
	bool hit = hit_vertex_face(&m, d, &toi);
	expect_hit_at(hit, toi, 0.5 * (1.0 - d));
	/* Edges passing d / 2 apart hit with thickness d, and 2 d apart do not. */
	double a0[3] = {0, 0, 0}, a1[3] = {1, 0, 0}, b0[3] = {0.5, -1, 0.5 * d}, b1[3] = {0.5, 1, 0.5 * d};
	double move[3] = {0, 0, 0}, far0[3] = {0.5, -1, 2.0 * d}, far1[3] = {0.5, 1, 2.0 * d};
	plait_ccd_motion edges = two_edges(a0, a1, b0, b1, move);
	cr_expect(hit_edge_edge(&edges, d, &toi));
	edges = two_edges(a0, a1, far0, far1, move);
	cr_expect_not(hit_edge_edge(&edges, d, &toi));
}

Test(ccd_constructed, max_time_limits_the_interval)
{
	double a[3] = {0.25, 0.25, 1.0}, b[3] = {0.25, 0.25, -1.0}, toi;
	plait_ccd_motion m = vertex_and_triangle(a, b);
	cr_expect_not(plait_ccd_vertex_face(&m, 0.0, TOL, 0.4, &toi));
	cr_expect_eq(toi, 0.4);
	cr_expect(plait_ccd_vertex_face(&m, 0.0, TOL, 0.6, &toi));
	cr_expect_leq(toi, 0.5);
}

Test(ccd_constructed, invalid_input_is_a_hit_at_zero)
{
	double a[3] = {NAN, 0.25, 1.0}, b[3] = {0.25, 0.25, -1.0}, toi = -1.0;
	plait_ccd_motion m = vertex_and_triangle(a, b);
	cr_expect(hit_vertex_face(&m, 0.0, &toi));
	cr_expect_eq(toi, 0.0);
}

/* ---- random motions against a sampled reference ---------------------------------------------- */

static double dot3(const double a[3], const double b[3])
{
	return a[0] * b[0] + a[1] * b[1] + a[2] * b[2];
}

static void sub3(const double a[3], const double b[3], double out[3])
{
	for (int k = 0; k < 3; k++)
		out[k] = a[k] - b[k];
}

static void cross3(const double a[3], const double b[3], double out[3])
{
	out[0] = a[1] * b[2] - a[2] * b[1];
	out[1] = a[2] * b[0] - a[0] * b[2];
	out[2] = a[0] * b[1] - a[1] * b[0];
}

static double point_segment_distance(const double p[3], const double a[3], const double b[3])
{
	double ab[3], ap[3], closest[3];
	sub3(b, a, ab);
	sub3(p, a, ap);
	double length2 = dot3(ab, ab), s = length2 > 0.0 ? dot3(ap, ab) / length2 : 0.0;
	s = s < 0.0 ? 0.0 : s > 1.0 ? 1.0 : s;
	for (int k = 0; k < 3; k++)
		closest[k] = a[k] + s * ab[k] - p[k];
	return sqrt(dot3(closest, closest));
}

/* The distance to the plane if p projects inside the triangle, else to the nearest edge. */
static double point_triangle_distance(const double p[3], const double a[3], const double b[3],
                                      const double c[3])
{
	const double *corner[3] = {a, b, c};
	double ab[3], ac[3], n[3];
	sub3(b, a, ab);
	sub3(c, a, ac);
	cross3(ab, ac, n);
	bool inside = dot3(n, n) > 0.0;
	for (int i = 0; i < 3 && inside; i++) {
		double edge[3], to_p[3], side[3];
		sub3(corner[(i + 1) % 3], corner[i], edge);
		sub3(p, corner[i], to_p);
		cross3(edge, to_p, side);
		inside = dot3(side, n) >= 0.0;
	}
	if (inside) {
		double ap[3];
		sub3(p, a, ap);
		return fabs(dot3(ap, n)) / sqrt(dot3(n, n));
	}
	return fmin(point_segment_distance(p, a, b),
	            fmin(point_segment_distance(p, b, c), point_segment_distance(p, c, a)));
}

/* The closest points of the two lines if both lie on the segments, else an endpoint's distance. */
static double segment_distance(const double a0[3], const double a1[3], const double b0[3], const double b1[3])
{
	double best = fmin(fmin(point_segment_distance(a0, b0, b1), point_segment_distance(a1, b0, b1)),
	                   fmin(point_segment_distance(b0, a0, a1), point_segment_distance(b1, a0, a1)));
	double d1[3], d2[3], r[3];
	sub3(a1, a0, d1);
	sub3(b1, b0, d2);
	sub3(a0, b0, r);
	double a = dot3(d1, d1), e = dot3(d2, d2), b = dot3(d1, d2), c = dot3(d1, r), f = dot3(d2, r);
	double denominator = a * e - b * b;
	if (denominator > 1e-12 * a * e) {
		double s = (b * f - c * e) / denominator, t = (a * f - b * c) / denominator;
		if (s >= 0.0 && s <= 1.0 && t >= 0.0 && t <= 1.0) {
			double gap[3];
			for (int k = 0; k < 3; k++)
				gap[k] = a0[k] + s * d1[k] - b0[k] - t * d2[k];
			best = fmin(best, sqrt(dot3(gap, gap)));
		}
	}
	return best;
}

static double distance_at(const plait_ccd_motion *m, bool vertex_face, double t)
{
	double x[4][3];
	for (int i = 0; i < 4; i++) {
		for (int k = 0; k < 3; k++)
			x[i][k] = m->start[i][k] + t * (m->end[i][k] - m->start[i][k]);
	}
	return vertex_face ? point_triangle_distance(x[0], x[1], x[2], x[3])
	                   : segment_distance(x[0], x[1], x[2], x[3]);
}

/* xorshift64*: a fixed sequence, the same on every machine. */
static double random_unit(unsigned long long *state)
{
	*state ^= *state >> 12;
	*state ^= *state << 25;
	*state ^= *state >> 27;
	return (double)((*state * 2685821657736338717ull) >> 11) * 0x1p-53 * 2.0 - 1.0;
}

Test(ccd_random, thickness_never_missed_by_samples)
{
	unsigned long long state = 0x9e3779b97f4a7c15ull;
	const int samples = 256;
	const double distances[3] = {0.01, 0.05, 0.2};
	int contacts = 0, queries = 0;
	for (int n = 0; n < 3000; n++) {
		plait_ccd_motion m;
		for (int i = 0; i < 4; i++) {
			for (int k = 0; k < 3; k++) {
				m.start[i][k] = random_unit(&state);
				m.end[i][k] = m.start[i][k] + random_unit(&state);
			}
		}
		for (int kind = 0; kind < 2; kind++) {
			bool is_vertex_face = kind == 0;
			double d = distances[n % 3], toi, toi_touch;
			bool hit = is_vertex_face ? hit_vertex_face(&m, d, &toi) : hit_edge_edge(&m, d, &toi);
			bool touch =
			    is_vertex_face ? hit_vertex_face(&m, 0.0, &toi_touch) : hit_edge_edge(&m, 0.0, &toi_touch);
			queries++;
			cr_expect(!touch || hit, "query %d: touching but not within %g", n, d);
			for (int i = 0; i <= samples; i++) {
				double t = (double)i / samples;
				if (distance_at(&m, is_vertex_face, t) <= d * (1.0 - 1e-9)) {
					contacts++;
					cr_expect(hit, "query %d %s: within %g at t = %g but no hit", n,
					          is_vertex_face ? "vf" : "ee", d, t);
					cr_expect_leq(toi, t, "query %d: toi %g after a sampled contact at %g", n, toi, t);
					break;
				}
			}
		}
	}
	cr_log_info("random motions: %d queries, %d with a sampled contact", queries, contacts);
	cr_expect_gt(contacts, queries / 20, "too few contacts to mean anything");
}

#include "world/bend_pairs.h"

#include <stdlib.h>

static int compare_pairs(const void *a, const void *b)
{
	const int *p = a, *q = b;
	return p[0] != q[0] ? (p[0] > q[0]) - (p[0] < q[0]) : (p[1] > q[1]) - (p[1] < q[1]);
}

/* Whether edges e and f have a parent triangle from the same polygon. */
static bool share_polygon(const plait_topology *t, int e, int f)
{
	int ne = t->edge_triangle_count[e] < 2 ? t->edge_triangle_count[e] : 2;
	int nf = t->edge_triangle_count[f] < 2 ? t->edge_triangle_count[f] : 2;
	for (int i = 0; i < ne; ++i) {
		for (int j = 0; j < nf; ++j) {
			if (t->triangle_polygon[t->edge_triangles[e][i]] ==
			    t->triangle_polygon[t->edge_triangles[f][j]]) {
				return true;
			}
		}
	}
	return false;
}

int plait_bend_pairs(const plait_topology *topology, const plait_vec3 *positions,
                     const plait_allocator *allocator, int (*pairs)[2])
{
	int n = topology->vertex_count;
	/* Polygon edges around each vertex, in compressed rows. */
	int *row = plait_alloc_zero(allocator, (size_t)n + 1, sizeof(int));
	int *incident = plait_alloc(allocator, sizeof(int) * (size_t)(2 * topology->edge_count + 1));
	if (row == NULL || incident == NULL) {
		plait_free(allocator, row);
		plait_free(allocator, incident);
		return -1;
	}
	for (int e = 0; e < topology->edge_count; ++e) {
		if (topology->edge_flags[e] & PLAIT_EDGE_POLYGON) {
			row[topology->edges[e][0] + 1] += 1;
			row[topology->edges[e][1] + 1] += 1;
		}
	}
	for (int v = 0; v < n; ++v) {
		row[v + 1] += row[v];
	}
	for (int e = 0; e < topology->edge_count; ++e) {
		if (topology->edge_flags[e] & PLAIT_EDGE_POLYGON) {
			for (int k = 0; k < 2; ++k) {
				int v = topology->edges[e][k];
				incident[row[v]++] = e;
			}
		}
	}
	for (int v = n; v > 0; --v) {
		row[v] = row[v - 1];
	}
	row[0] = 0;

	int count = 0;
	for (int b = 0; b < n; ++b) {
		vec3 xb = positions[b];
		for (int i = row[b]; i < row[b + 1]; ++i) {
			int e = incident[i];
			int a = topology->edges[e][0] == b ? topology->edges[e][1] : topology->edges[e][0];
			vec3 da = v3_sub(positions[a], xb);
			float best = -0.5f; /* straighter than 120 degrees */
			int partner = -1;
			for (int j = row[b]; j < row[b + 1]; ++j) {
				int f = incident[j];
				int c = topology->edges[f][0] == b ? topology->edges[f][1] : topology->edges[f][0];
				if (f == e || share_polygon(topology, e, f)) {
					continue;
				}
				vec3 dc = v3_sub(positions[c], xb);
				float lengths = sqrtf(v3_length_sq(da) * v3_length_sq(dc));
				float cosine = lengths > 0.0f ? v3_dot(da, dc) / lengths : 1.0f;
				if (cosine < best) {
					best = cosine;
					partner = c;
				}
			}
			if (partner >= 0 && partner != a) {
				pairs[count][0] = a < partner ? a : partner;
				pairs[count][1] = a < partner ? partner : a;
				++count;
			}
		}
	}
	qsort(pairs, (size_t)count, sizeof pairs[0], compare_pairs);
	int unique = 0;
	for (int k = 0; k < count; ++k) {
		if (unique == 0 || compare_pairs(pairs[unique - 1], pairs[k]) != 0) {
			pairs[unique][0] = pairs[k][0];
			pairs[unique][1] = pairs[k][1];
			++unique;
		}
	}
	plait_free(allocator, row);
	plait_free(allocator, incident);
	return unique;
}

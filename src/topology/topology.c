#include "topology/topology.h"

#include <stdlib.h>
#include <string.h>

#include "core/error.h"

void plait_topology_destroy(plait_topology *t, const plait_allocator *allocator)
{
	plait_free(allocator, t->polygon_sizes);
	plait_free(allocator, t->polygon_starts);
	plait_free(allocator, t->polygon_indices);
	plait_free(allocator, t->triangles);
	plait_free(allocator, t->triangle_polygon);
	plait_free(allocator, t->triangle_edges);
	plait_free(allocator, t->edges);
	plait_free(allocator, t->edge_flags);
	plait_free(allocator, t->edge_triangles);
	plait_free(allocator, t->edge_triangle_count);
	plait_free(allocator, t->vertex_valence);
	memset(t, 0, sizeof *t);
}

static plait_result validate_faces(int vertex_count, const int *face_sizes, int face_count,
                                   const int *face_indices, int *index_count, int *triangle_count,
                                   plait_error *error)
{
	int indices = 0, triangles = 0;
	for (int f = 0; f < face_count; ++f) {
		int size = face_sizes[f];
		if (size < 3) {
			return plait_error_set(error, PLAIT_ERROR_INVALID_MESH,
			                       "face %d has %d vertices; a face needs at least 3", f, size);
		}
		const int *face = face_indices + indices;
		for (int k = 0; k < size; ++k) {
			if (face[k] < 0 || face[k] >= vertex_count) {
				return plait_error_set(error, PLAIT_ERROR_INVALID_MESH,
				                       "face %d uses vertex index %d, outside 0..%d", f, face[k],
				                       vertex_count - 1);
			}
			for (int m = 0; m < k; ++m) {
				if (face[m] == face[k]) {
					return plait_error_set(error, PLAIT_ERROR_INVALID_MESH,
					                       "face %d is degenerate: it uses vertex %d twice", f, face[k]);
				}
			}
		}
		indices += size;
		triangles += size - 2;
	}
	*index_count = indices;
	*triangle_count = triangles;
	return PLAIT_OK;
}

plait_result plait_topology_build(plait_topology *t, const plait_allocator *allocator, int vertex_count,
                                  const int *face_sizes, int face_count, const int *face_indices,
                                  plait_error *error)
{
	memset(t, 0, sizeof *t);
	if (vertex_count <= 0) {
		return plait_error_set(error, PLAIT_ERROR_INVALID_MESH, "a mesh needs at least one vertex");
	}
	if (face_count < 0 || (face_count > 0 && (face_sizes == NULL || face_indices == NULL))) {
		return plait_error_set(error, PLAIT_ERROR_INVALID_ARGUMENT, "face arrays are missing");
	}
	int index_count = 0, triangle_count = 0;
	plait_result result = validate_faces(vertex_count, face_sizes, face_count, face_indices, &index_count,
	                                     &triangle_count, error);
	if (result != PLAIT_OK) {
		return result;
	}

	t->vertex_count = vertex_count;
	t->polygon_count = face_count;
	t->polygon_index_count = index_count;
	t->triangle_count = triangle_count;
	t->vertex_valence = plait_alloc_zero(allocator, (size_t)vertex_count, sizeof(int));
	bool ok = t->vertex_valence != NULL;
	if (face_count > 0) {
		t->polygon_sizes = plait_alloc_zero(allocator, (size_t)face_count, sizeof(int));
		t->polygon_starts = plait_alloc_zero(allocator, (size_t)face_count, sizeof(int));
		t->polygon_indices = plait_alloc_zero(allocator, (size_t)index_count, sizeof(int));
		t->triangles = plait_alloc_zero(allocator, (size_t)triangle_count, sizeof *t->triangles);
		t->triangle_polygon = plait_alloc_zero(allocator, (size_t)triangle_count, sizeof(int));
		t->triangle_edges = plait_alloc_zero(allocator, (size_t)triangle_count, sizeof *t->triangle_edges);
		ok = ok && t->polygon_sizes && t->polygon_starts && t->polygon_indices && t->triangles &&
		     t->triangle_polygon && t->triangle_edges;
	}
	/* Each triangle edge, sorted by edge to find unique edges and their parents, and whether
	 * it lies on its polygon's border (at triangle * 3 + corner). */
	plait_triangle_edge *records =
	    triangle_count > 0 ? plait_alloc_zero(allocator, (size_t)triangle_count * 3, sizeof *records) : NULL;
	uint8_t *record_flags =
	    triangle_count > 0 ? plait_alloc_zero(allocator, (size_t)triangle_count * 3, sizeof *record_flags)
	                       : NULL;
	if (!ok || (triangle_count > 0 && (records == NULL || record_flags == NULL))) {
		plait_free(allocator, records);
		plait_free(allocator, record_flags);
		plait_topology_destroy(t, allocator);
		return plait_error_set(error, PLAIT_ERROR_OUT_OF_MEMORY, "out of memory building a mesh of %d faces",
		                       face_count);
	}

	/* Fan every polygon from its first vertex; record each triangle edge and whether it lies on
	 * the polygon border (structural) or inside it (a diagonal added by the fan). */
	int start = 0, triangle = 0;
	for (int f = 0; f < face_count; ++f) {
		int size = face_sizes[f];
		const int *face = face_indices + start;
		t->polygon_sizes[f] = size;
		t->polygon_starts[f] = start;
		memcpy(t->polygon_indices + start, face, sizeof(int) * (size_t)size);
		for (int k = 1; k + 1 < size; ++k, ++triangle) {
			int corners[3] = {face[0], face[k], face[k + 1]};
			memcpy(t->triangles[triangle], corners, sizeof corners);
			t->triangle_polygon[triangle] = f;
			for (int c = 0; c < 3; ++c) {
				int u = corners[c], v = corners[(c + 1) % 3];
				/* Corner pairs (0,1) with k == 1, (1,2) always, and (2,0) with k == size-2 are
				 * polygon edges; the rest are fan diagonals. */
				bool polygon_edge = (c == 1) || (c == 0 && k == 1) || (c == 2 && k + 2 == size);
				records[triangle * 3 + c] = (plait_triangle_edge){u < v ? u : v, u < v ? v : u, triangle, c};
				record_flags[triangle * 3 + c] = polygon_edge ? PLAIT_EDGE_POLYGON : PLAIT_EDGE_DIAGONAL;
			}
		}
		start += size;
	}

	int record_count = triangle_count * 3;
	plait_sort_triangle_edges(records, record_count);
	int edge_count = 0;
	for (int i = 0; i < record_count; ++i) {
		if (i == 0 || records[i].low != records[i - 1].low || records[i].high != records[i - 1].high) {
			++edge_count;
		}
	}
	t->edge_count = edge_count;
	if (edge_count > 0) {
		t->edges = plait_alloc_zero(allocator, (size_t)edge_count, sizeof *t->edges);
		t->edge_flags = plait_alloc_zero(allocator, (size_t)edge_count, sizeof *t->edge_flags);
		t->edge_triangles = plait_alloc_zero(allocator, (size_t)edge_count, sizeof *t->edge_triangles);
		t->edge_triangle_count = plait_alloc_zero(allocator, (size_t)edge_count, sizeof(int));
		if (!t->edges || !t->edge_flags || !t->edge_triangles || !t->edge_triangle_count) {
			plait_free(allocator, records);
			plait_free(allocator, record_flags);
			plait_topology_destroy(t, allocator);
			return plait_error_set(error, PLAIT_ERROR_OUT_OF_MEMORY, "out of memory building mesh edges");
		}
	}
	int edge = -1;
	for (int i = 0; i < record_count; ++i) {
		const plait_triangle_edge *r = &records[i];
		if (i == 0 || r->low != records[i - 1].low || r->high != records[i - 1].high) {
			++edge;
			t->edges[edge][0] = r->low;
			t->edges[edge][1] = r->high;
			t->edge_triangles[edge][0] = -1;
			t->edge_triangles[edge][1] = -1;
			t->vertex_valence[r->low] += 1;
			t->vertex_valence[r->high] += 1;
		}
		/* A polygon edge anywhere makes the edge structural. */
		uint8_t flags = record_flags[r->triangle * 3 + r->corner];
		if (flags == PLAIT_EDGE_POLYGON || t->edge_flags[edge] == 0) {
			t->edge_flags[edge] = flags;
		}
		int parents = t->edge_triangle_count[edge]++;
		if (parents < 2) {
			t->edge_triangles[edge][parents] = r->triangle;
		}
		t->triangle_edges[r->triangle][r->corner] = edge;
	}
	plait_free(allocator, records);
	plait_free(allocator, record_flags);
	return PLAIT_OK;
}

int plait_topology_find_edge(const plait_topology *t, int a, int b)
{
	if (a > b) {
		int swap = a;
		a = b;
		b = swap;
	}
	int low = 0, high = t->edge_count - 1;
	while (low <= high) {
		int mid = (low + high) / 2;
		const int *e = t->edges[mid];
		if (e[0] == a && e[1] == b) {
			return mid;
		}
		if (e[0] < a || (e[0] == a && e[1] < b)) {
			low = mid + 1;
		} else {
			high = mid - 1;
		}
	}
	return -1;
}

int plait_topology_border_edge_count(const plait_topology *t)
{
	int count = 0;
	for (int e = 0; e < t->edge_count; ++e) {
		count += t->edge_triangle_count[e] == 1;
	}
	return count;
}

static int compare_triangle_edges(const void *left, const void *right)
{
	const plait_triangle_edge *l = left, *r = right;
	if (l->low != r->low) {
		return l->low < r->low ? -1 : 1;
	}
	if (l->high != r->high) {
		return l->high < r->high ? -1 : 1;
	}
	if (l->triangle != r->triangle) {
		return l->triangle < r->triangle ? -1 : 1;
	}
	return l->corner < r->corner ? -1 : l->corner > r->corner;
}

void plait_sort_triangle_edges(plait_triangle_edge *edges, int count)
{
	if (count > 1) {
		qsort(edges, (size_t)count, sizeof *edges, compare_triangle_edges);
	}
}

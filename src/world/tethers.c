/* Tethers, after Kim, Chentanez and Müller's long-range attachments (seed 004, "Tether
 * Constraints"): each free vertex is tied to the PLAIT_TETHER_ANCHORS pins nearest to it in the
 * rest shape (fewer when the cloth has fewer pins), either in a straight line or along the mesh.
 *
 * Why several pins and not only the nearest: where the nearest pin changes (the line halfway
 * between two pins), neighbouring vertices would be pulled towards different pins, and the
 * edges between them torn apart by the tethers themselves. Hung from two corners, that seam
 * showed as the worst strain of the cloth (0.44 at 10 substeps; 0.14 with both pins).
 *
 * The distance along the mesh is a Dijkstra over the triangle edges and both diagonals of every
 * quad, with up to PLAIT_TETHER_ANCHORS labels (pins) per vertex: it never underestimates the
 * distance on the surface, and overestimates it by at most about 8% on a quad grid (the octile
 * distance), so geodesic tethers are slightly slack, never too tight. */
#include "world/tethers.h"

#include <string.h>

typedef struct heap_item {
	float distance;
	int vertex;
	int pin;
} heap_item;

/* A total order, so that ties are broken the same way on every machine. */
static bool heap_less(heap_item a, heap_item b)
{
	if (a.distance != b.distance) {
		return a.distance < b.distance;
	}
	return a.vertex != b.vertex ? a.vertex < b.vertex : a.pin < b.pin;
}

static void heap_push(heap_item *heap, int *size, heap_item item)
{
	int k = (*size)++;
	while (k > 0) {
		int parent = (k - 1) / 2;
		if (!heap_less(item, heap[parent])) {
			break;
		}
		heap[k] = heap[parent];
		k = parent;
	}
	heap[k] = item;
}

static heap_item heap_pop(heap_item *heap, int *size)
{
	heap_item top = heap[0], last = heap[--*size];
	int k = 0;
	for (;;) {
		int child = 2 * k + 1;
		if (child >= *size) {
			break;
		}
		if (child + 1 < *size && heap_less(heap[child + 1], heap[child])) {
			++child;
		}
		if (!heap_less(heap[child], last)) {
			break;
		}
		heap[k] = heap[child];
		k = child;
	}
	heap[k] = last;
	return top;
}

/* The graph walked for geodesic distances: every edge, plus the second diagonal of each quad
 * (the first is already an edge of its fan). */
static int graph_link_count(const plait_topology *t)
{
	int links = t->edge_count;
	for (int f = 0; f < t->polygon_count; ++f) {
		links += t->polygon_sizes[f] == 4;
	}
	return links;
}

/* Anchors of every vertex: anchor[v * K + k] and distance[v * K + k], k < count[v], nearest
 * first. */
typedef struct anchor_table {
	int *anchor;
	float *distance;
	int *count;
} anchor_table;

enum { K = PLAIT_TETHER_ANCHORS };

static bool has_anchor(const anchor_table *table, int v, int pin)
{
	for (int k = 0; k < table->count[v]; ++k) {
		if (table->anchor[v * K + k] == pin) {
			return true;
		}
	}
	return false;
}

/* Dijkstra with up to K labels per vertex: a vertex is settled once per pin, for its K nearest
 * pins, in order of distance. */
static bool geodesic_anchors(const plait_allocator *a, const plait_topology *t, const vec3 *x,
                             const int *pins, int pin_count, anchor_table *table)
{
	int n = t->vertex_count;
	int links = graph_link_count(t);
	int(*ends)[2] = plait_alloc_zero(a, (size_t)links + 1, sizeof *ends);
	int *start = plait_alloc_zero(a, (size_t)n + 1, sizeof(int));
	int *neighbour = plait_alloc_zero(a, 2 * (size_t)links + 1, sizeof(int));
	int *cursor = plait_alloc_zero(a, (size_t)n, sizeof(int));
	/* Each settled label pushes at most one item per neighbour. */
	size_t heap_capacity = (size_t)K * 2 * (size_t)links + (size_t)pin_count + 1;
	heap_item *heap = plait_alloc_zero(a, heap_capacity, sizeof(heap_item));
	bool ok = ends && start && neighbour && cursor && heap;
	if (ok) {
		/* One pass to list the links: quads are found in order, not searched per link. */
		int link = 0;
		for (int e = 0; e < t->edge_count; ++e, ++link) {
			ends[link][0] = t->edges[e][0];
			ends[link][1] = t->edges[e][1];
		}
		for (int f = 0; f < t->polygon_count; ++f) {
			if (t->polygon_sizes[f] == 4) {
				const int *q = t->polygon_indices + t->polygon_starts[f];
				ends[link][0] = q[1];
				ends[link][1] = q[3];
				++link;
			}
		}
		for (int l = 0; l < links; ++l) {
			start[ends[l][0] + 1] += 1;
			start[ends[l][1] + 1] += 1;
		}
		for (int v = 0; v < n; ++v) {
			start[v + 1] += start[v];
			cursor[v] = start[v];
		}
		for (int l = 0; l < links; ++l) {
			int u = ends[l][0], v = ends[l][1];
			neighbour[cursor[u]++] = v;
			neighbour[cursor[v]++] = u;
		}
		int size = 0;
		for (int k = 0; k < pin_count; ++k) {
			heap_push(heap, &size, (heap_item){0.0f, pins[k], pins[k]});
		}
		while (size > 0) {
			heap_item item = heap_pop(heap, &size);
			int u = item.vertex;
			if (table->count[u] == K || has_anchor(table, u, item.pin)) {
				continue; /* settled K times already, or by this pin */
			}
			int slot = u * K + table->count[u]++;
			table->anchor[slot] = item.pin;
			table->distance[slot] = item.distance;
			for (int k = start[u]; k < start[u + 1]; ++k) {
				int v = neighbour[k];
				if (table->count[v] < K && !has_anchor(table, v, item.pin)) {
					float through = item.distance + v3_length(v3_sub(x[v], x[u]));
					heap_push(heap, &size, (heap_item){through, v, item.pin});
				}
			}
		}
	}
	plait_free(a, ends);
	plait_free(a, start);
	plait_free(a, neighbour);
	plait_free(a, cursor);
	plait_free(a, heap);
	return ok;
}

/* The K pins nearest to each vertex in a straight line. */
static void euclidean_anchors(const vec3 *x, int n, const int *pins, int pin_count, anchor_table *table)
{
	for (int v = 0; v < n; ++v) {
		int *anchor = table->anchor + v * K;
		float *distance = table->distance + v * K;
		int count = 0;
		for (int k = 0; k < pin_count; ++k) {
			float d = v3_length(v3_sub(x[v], x[pins[k]]));
			/* Insertion into the sorted list; equal distances keep the pins' order. */
			int at = count;
			while (at > 0 && d < distance[at - 1]) {
				--at;
			}
			if (at == K) {
				continue;
			}
			for (int m = (count < K ? count : K - 1); m > at; --m) {
				anchor[m] = anchor[m - 1];
				distance[m] = distance[m - 1];
			}
			anchor[at] = pins[k];
			distance[at] = d;
			count += count < K;
		}
		table->count[v] = count;
	}
}

int plait_tethers_per_vertex(int pin_count)
{
	return pin_count < K ? pin_count : K;
}

bool plait_build_tethers(plait_sim *sim, const plait_topology *t, const vec3 *x, int first, const int *pins,
                         int pin_count, plait_tether_mode mode, float scale, float stiffness)
{
	if (mode == PLAIT_TETHER_NONE || pin_count == 0) {
		return true;
	}
	const plait_allocator *a = &sim->allocator;
	int n = t->vertex_count;
	anchor_table table = {plait_alloc_zero(a, (size_t)n * K, sizeof(int)),
	                      plait_alloc_zero(a, (size_t)n * K, sizeof(float)),
	                      plait_alloc_zero(a, (size_t)n, sizeof(int))};
	bool *pinned = plait_alloc_zero(a, (size_t)n, sizeof(bool));
	bool ok = table.anchor && table.distance && table.count && pinned;
	if (ok) {
		for (int k = 0; k < pin_count; ++k) {
			pinned[pins[k]] = true;
		}
		if (mode == PLAIT_TETHER_GEODESIC) {
			ok = geodesic_anchors(a, t, x, pins, pin_count, &table);
		} else {
			euclidean_anchors(x, n, pins, pin_count, &table);
		}
	}
	for (int v = 0; ok && v < n; ++v) {
		/* Vertices cut off from every pin (another piece of the mesh) get no tether. A
		 * vertex's tethers are consecutive, the nearest pin last: the solver projects them in
		 * turn, so the nearest holds exactly after each pass. */
		if (pinned[v]) {
			continue;
		}
		for (int k = table.count[v] - 1; k >= 0; --k) {
			if (!isfinite(table.distance[v * K + k])) {
				continue;
			}
			int c = sim->tether.count++;
			sim->tether.pair[c][0] = first + v;
			sim->tether.pair[c][1] = first + table.anchor[v * K + k];
			sim->tether.length[c] = table.distance[v * K + k] * scale;
			sim->tether.stiffness[c] = stiffness;
		}
	}
	sim->tether.lanes_stale = true;
	plait_free(a, table.anchor);
	plait_free(a, table.distance);
	plait_free(a, table.count);
	plait_free(a, pinned);
	return ok;
}

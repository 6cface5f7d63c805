/* Tethers, after Kim, Chentanez and Müller's long-range attachments (seed 004, "Tether
 * Constraints"): each free vertex is tied to the pin nearest to it in the rest shape, either in
 * a straight line or along the mesh. The distance along the mesh is a multi-source Dijkstra
 * over the triangle edges and both diagonals of every quad: it never underestimates the
 * distance on the surface, and overestimates it by at most about 8% on a quad grid (the
 * octile distance), so geodesic tethers are slightly slack, never too tight. */
#include "world/tethers.h"

#include <string.h>

typedef struct heap_item {
	float distance;
	int vertex;
} heap_item;

static bool heap_less(heap_item a, heap_item b)
{
	return a.distance < b.distance || (a.distance == b.distance && a.vertex < b.vertex);
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

/* Distances along edges from the nearest pin, and which pin, for every vertex. */
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

static bool geodesic_anchors(const plait_allocator *a, const plait_topology *t, const vec3 *x,
                             const int *pins, int pin_count, float *distance, int *anchor)
{
	int n = t->vertex_count;
	int links = graph_link_count(t);
	int(*ends)[2] = plait_alloc_zero(a, (size_t)links + 1, sizeof *ends);
	int *start = plait_alloc_zero(a, (size_t)n + 1, sizeof(int));
	int *neighbour = plait_alloc_zero(a, 2 * (size_t)links + 1, sizeof(int));
	int *cursor = plait_alloc_zero(a, (size_t)n, sizeof(int));
	heap_item *heap = plait_alloc_zero(a, 2 * (size_t)links + (size_t)pin_count + 1, sizeof(heap_item));
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
		for (int v = 0; v < n; ++v) {
			distance[v] = INFINITY;
			anchor[v] = -1;
		}
		for (int k = 0; k < pin_count; ++k) {
			distance[pins[k]] = 0.0f;
			anchor[pins[k]] = pins[k];
			heap_push(heap, &size, (heap_item){0.0f, pins[k]});
		}
		while (size > 0) {
			heap_item item = heap_pop(heap, &size);
			int u = item.vertex;
			if (item.distance > distance[u]) {
				continue; /* a stale entry */
			}
			for (int k = start[u]; k < start[u + 1]; ++k) {
				int v = neighbour[k];
				float through = distance[u] + v3_length(v3_sub(x[v], x[u]));
				if (through < distance[v]) {
					distance[v] = through;
					anchor[v] = anchor[u];
					heap_push(heap, &size, (heap_item){through, v});
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

bool plait_build_tethers(plait_sim *sim, const plait_topology *t, const vec3 *x, int first, const int *pins,
                         int pin_count, plait_tether_mode mode, float scale, float stiffness)
{
	if (mode == PLAIT_TETHER_NONE || pin_count == 0) {
		return true;
	}
	const plait_allocator *a = &sim->allocator;
	int n = t->vertex_count;
	float *distance = plait_alloc_zero(a, (size_t)n, sizeof(float));
	int *anchor = plait_alloc_zero(a, (size_t)n, sizeof(int));
	bool *pinned = plait_alloc_zero(a, (size_t)n, sizeof(bool));
	bool ok = distance && anchor && pinned;
	if (ok) {
		for (int k = 0; k < pin_count; ++k) {
			pinned[pins[k]] = true;
		}
		if (mode == PLAIT_TETHER_GEODESIC) {
			ok = geodesic_anchors(a, t, x, pins, pin_count, distance, anchor);
		} else {
			for (int v = 0; v < n; ++v) {
				distance[v] = INFINITY;
				anchor[v] = -1;
				for (int k = 0; k < pin_count; ++k) {
					float d = v3_length(v3_sub(x[v], x[pins[k]]));
					if (d < distance[v]) {
						distance[v] = d;
						anchor[v] = pins[k];
					}
				}
			}
		}
	}
	for (int v = 0; ok && v < n; ++v) {
		/* Vertices cut off from every pin (another piece of the mesh) get no tether. */
		if (pinned[v] || anchor[v] < 0 || !isfinite(distance[v])) {
			continue;
		}
		int c = sim->tether.count++;
		sim->tether.pair[c][0] = first + v;
		sim->tether.pair[c][1] = first + anchor[v];
		sim->tether.length[c] = distance[v] * scale;
		sim->tether.stiffness[c] = stiffness;
	}
	plait_free(a, distance);
	plait_free(a, anchor);
	plait_free(a, pinned);
	return ok;
}

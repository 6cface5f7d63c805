/* The simplicial complex built from a polygon soup (paper §3), and the bend constraint's
 * dihedral angle and its gradient. */
#include <criterion/criterion.h>
#include <math.h>
#include <string.h>

#include "dynamics/constraints.h"
#include "topology/topology.h"

static const plait_allocator heap = {0};

Test(topology, quad_grid_has_the_expected_simplices)
{
	/* 2 x 1 quads: 6 vertices, 2 quads -> 4 triangles, 7 polygon edges + 2 fan diagonals. */
	int sizes[2] = {4, 4};
	int indices[8] = {0, 1, 4, 3, 1, 2, 5, 4};
	plait_topology t;
	cr_assert_eq(plait_topology_build(&t, &heap, 6, sizes, 2, indices, NULL), PLAIT_OK);
	cr_assert_eq(t.triangle_count, 4);
	cr_assert_eq(t.edge_count, 9);
	int polygon_edges = 0, diagonals = 0;
	for (int e = 0; e < t.edge_count; ++e) {
		cr_assert_lt(t.edges[e][0], t.edges[e][1], "edge vertices are stored in lexicographic order");
		polygon_edges += t.edge_flags[e] == PLAIT_EDGE_POLYGON;
		diagonals += t.edge_flags[e] == PLAIT_EDGE_DIAGONAL;
	}
	cr_assert_eq(polygon_edges, 7);
	cr_assert_eq(diagonals, 2);
	/* The shared edge 1-4 has two parent triangles; the 6 outer edges are borders. */
	int shared = plait_topology_find_edge(&t, 4, 1);
	cr_assert_geq(shared, 0);
	cr_assert_eq(t.edge_triangle_count[shared], 2);
	cr_assert_eq(plait_topology_border_edge_count(&t), 6);
	/* Children of a triangle are its edges. */
	for (int tri = 0; tri < t.triangle_count; ++tri) {
		for (int k = 0; k < 3; ++k) {
			int e = t.triangle_edges[tri][k];
			int a = t.triangles[tri][k], b = t.triangles[tri][(k + 1) % 3];
			cr_assert_eq(e, plait_topology_find_edge(&t, a, b));
		}
	}
	/* Quads are fanned the same way every time: (a,b,c,d) -> (a,b,c), (a,c,d). */
	cr_assert_eq(t.triangles[0][0], 0);
	cr_assert_eq(t.triangles[0][1], 1);
	cr_assert_eq(t.triangles[0][2], 4);
	cr_assert_eq(t.triangles[1][0], 0);
	cr_assert_eq(t.triangles[1][1], 4);
	cr_assert_eq(t.triangles[1][2], 3);
	cr_assert_eq(t.vertex_valence[1], 4); /* edges 0-1, 1-2, 1-4, 1-5 (fan diagonal of quad 2) */
	plait_topology_destroy(&t, &heap);
}

Test(topology, bad_faces_are_rejected_with_a_message)
{
	plait_error error;
	plait_topology t;
	int sizes[1] = {3};
	int out_of_range[3] = {0, 1, 7};
	cr_assert_eq(plait_topology_build(&t, &heap, 3, sizes, 1, out_of_range, &error),
	             PLAIT_ERROR_INVALID_MESH);
	cr_assert(strstr(error.message, "vertex index 7") != NULL, "%s", error.message);
	int repeated[3] = {0, 1, 1};
	cr_assert_eq(plait_topology_build(&t, &heap, 3, sizes, 1, repeated, &error), PLAIT_ERROR_INVALID_MESH);
	cr_assert(strstr(error.message, "degenerate") != NULL, "%s", error.message);
	int two[1] = {2};
	int line[2] = {0, 1};
	cr_assert_eq(plait_topology_build(&t, &heap, 3, two, 1, line, &error), PLAIT_ERROR_INVALID_MESH);
	cr_assert(strstr(error.message, "at least 3") != NULL, "%s", error.message);
}

Test(topology, non_manifold_edges_count_all_parents)
{
	/* Three triangles sharing edge 0-1. */
	int sizes[3] = {3, 3, 3};
	int indices[9] = {0, 1, 2, 1, 0, 3, 0, 1, 4};
	plait_topology t;
	cr_assert_eq(plait_topology_build(&t, &heap, 5, sizes, 3, indices, NULL), PLAIT_OK);
	int e = plait_topology_find_edge(&t, 0, 1);
	cr_assert_eq(t.edge_triangle_count[e], 3);
	plait_topology_destroy(&t, &heap);
}

Test(dihedral, angle_is_signed_and_zero_when_flat)
{
	plait_vec3 p0 = {0, 0, 0}, p1 = {1, 0, 0}, p2 = {0.5f, 1, 0}, p3 = {0.5f, -1, 0};
	float angle;
	cr_assert(plait_dihedral_angle(p0, p1, p2, p3, &angle, NULL));
	cr_assert_float_eq(angle, 0.0f, 1e-6f);
	/* Fold the wing p3 up (+z) and then down: opposite signs, same size. */
	plait_vec3 up = {0.5f, -cosf(0.5f), sinf(0.5f)}, down = {0.5f, -cosf(0.5f), -sinf(0.5f)};
	float a_up, a_down;
	plait_dihedral_angle(p0, p1, p2, up, &a_up, NULL);
	plait_dihedral_angle(p0, p1, p2, down, &a_down, NULL);
	cr_assert_float_eq(fabsf(a_up), 0.5f, 1e-5f);
	cr_assert_float_eq(a_up, -a_down, 1e-6f);
}

Test(dihedral, gradient_matches_finite_differences)
{
	plait_vec3 p[4] = {{0.1f, -0.2f, 0.05f}, {1.0f, 0.1f, -0.1f}, {0.4f, 0.9f, 0.3f}, {0.6f, -0.8f, 0.4f}};
	float angle;
	plait_vec3 g[4];
	cr_assert(plait_dihedral_angle(p[0], p[1], p[2], p[3], &angle, g));
	const float h = 1e-3f;
	for (int k = 0; k < 4; ++k) {
		for (int axis = 0; axis < 3; ++axis) {
			plait_vec3 plus[4], minus[4];
			for (int m = 0; m < 4; ++m) {
				plus[m] = p[m];
				minus[m] = p[m];
			}
			float *a = axis == 0 ? &plus[k].x : axis == 1 ? &plus[k].y : &plus[k].z;
			float *b = axis == 0 ? &minus[k].x : axis == 1 ? &minus[k].y : &minus[k].z;
			*a += h;
			*b -= h;
			float fa, fb;
			plait_dihedral_angle(plus[0], plus[1], plus[2], plus[3], &fa, NULL);
			plait_dihedral_angle(minus[0], minus[1], minus[2], minus[3], &fb, NULL);
			float numeric = (fa - fb) / (2.0f * h);
			float analytic = axis == 0 ? g[k].x : axis == 1 ? g[k].y : g[k].z;
			cr_assert_float_eq(analytic, numeric, 2e-3f, "point %d axis %d: analytic %g numeric %g", k, axis,
			                   (double)analytic, (double)numeric);
		}
	}
}

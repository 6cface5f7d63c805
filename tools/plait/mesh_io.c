#include "mesh_io.h"

#include "grow_array.h"

#include "mesh_sanity.h"

#include <assimp/cimport.h>
#include <assimp/scene.h>
#include <errno.h>
#include <limits.h>
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

// Malformed files can nest nodes without end (or in a cycle); no real scene is this deep.
#define PLAIT_MESH_MAX_NODE_DEPTH 256
// Far beyond any cloth; keeps corrupt counts from making validation crawl.
#define PLAIT_MESH_MAX_VERTICES 50000000

typedef struct plait_mesh_builder {
	const char *path;
	const struct aiScene *scene;
	plait_soup soup;
	int vertex_capacity, face_capacity, index_capacity;
	plait_tool_error *error;
} plait_mesh_builder;

// Row-major 4x4 (assimp's a1..d4) applied to a point.
static plait_vec3 plait_transform_point(const double m[16], double x, double y, double z)
{
	return (plait_vec3){(float)(m[0] * x + m[1] * y + m[2] * z + m[3]),
	                    (float)(m[4] * x + m[5] * y + m[6] * z + m[7]),
	                    (float)(m[8] * x + m[9] * y + m[10] * z + m[11])};
}

static bool plait_add_mesh(plait_mesh_builder *b, unsigned mesh_index, const double m[16],
                           plait_mesh_report *report)
{
	const struct aiMesh *mesh = b->scene->mMeshes[mesh_index];
	if (mesh == NULL || mesh->mNumVertices == 0 || mesh->mVertices == NULL)
		return true;
	if (mesh->mNumVertices > (unsigned)(INT_MAX / 2 - b->soup.vertex_count))
		return plait_tool_error_set(b->error, "%s: mesh %u: too many vertices (%u)", b->path, mesh_index,
		                            mesh->mNumVertices);
	int base = b->soup.vertex_count;
	int vertex_count = base + (int)mesh->mNumVertices;
	if (!plait_grow_array((void **)&b->soup.positions, &b->vertex_capacity, vertex_count, sizeof(plait_vec3)))
		return plait_tool_error_set(b->error, "%s: out of memory", b->path);
	for (unsigned i = 0; i < mesh->mNumVertices; ++i) {
		double x = mesh->mVertices[i].x, y = mesh->mVertices[i].y, z = mesh->mVertices[i].z;
		plait_vec3 p = plait_transform_point(m, x, y, z);
		if (!isfinite(x) || !isfinite(y) || !isfinite(z) || !isfinite(p.x) || !isfinite(p.y) ||
		    !isfinite(p.z))
			return plait_tool_error_set(b->error,
			                            "%s: mesh %u vertex %u has a non-finite coordinate (%g, %g, %g)",
			                            b->path, mesh_index, i, x, y, z);
		b->soup.positions[base + (int)i] = p;
	}
	b->soup.vertex_count = vertex_count;
	if (mesh->mNumFaces > 0 && mesh->mFaces == NULL)
		return plait_tool_error_set(b->error, "%s: mesh %u has %u faces but no face data", b->path,
		                            mesh_index, mesh->mNumFaces);
	for (unsigned f = 0; f < mesh->mNumFaces; ++f) {
		const struct aiFace *face = &mesh->mFaces[f];
		if (face->mNumIndices < 3) {
			report->point_line_faces++;
			continue;
		}
		if (face->mIndices == NULL || face->mNumIndices > (unsigned)(INT_MAX / 4))
			return plait_tool_error_set(b->error, "%s: mesh %u face %u has no valid index list", b->path,
			                            mesh_index, f);
		for (unsigned k = 0; k < face->mNumIndices; ++k) {
			if (face->mIndices[k] >= mesh->mNumVertices)
				return plait_tool_error_set(b->error,
				                            "%s: mesh %u face %u: bad index, vertex %u is out of range (the "
				                            "mesh has %u vertices)",
				                            b->path, mesh_index, f, face->mIndices[k], mesh->mNumVertices);
		}
		int size = (int)face->mNumIndices;
		if (b->soup.index_count > INT_MAX / 2 - size ||
		    !plait_grow_array((void **)&b->soup.face_sizes, &b->face_capacity, b->soup.face_count + 1,
		                      sizeof(int)) ||
		    !plait_grow_array((void **)&b->soup.face_indices, &b->index_capacity, b->soup.index_count + size,
		                      sizeof(int)))
			return plait_tool_error_set(b->error, "%s: out of memory", b->path);
		b->soup.face_sizes[b->soup.face_count++] = size;
		for (int k = 0; k < size; ++k)
			b->soup.face_indices[b->soup.index_count++] = base + (int)face->mIndices[k];
	}
	return true;
}

static bool plait_add_node(plait_mesh_builder *b, const struct aiNode *node, const double parent[16],
                           int depth, plait_mesh_report *report)
{
	if (node == NULL)
		return true;
	if (depth > PLAIT_MESH_MAX_NODE_DEPTH)
		return plait_tool_error_set(b->error, "%s: node hierarchy deeper than %d levels", b->path,
		                            PLAIT_MESH_MAX_NODE_DEPTH);
	const struct aiMatrix4x4 *t = &node->mTransformation;
	double local[16] = {t->a1, t->a2, t->a3, t->a4, t->b1, t->b2, t->b3, t->b4,
	                    t->c1, t->c2, t->c3, t->c4, t->d1, t->d2, t->d3, t->d4};
	double world[16];
	for (int r = 0; r < 4; ++r)
		for (int c = 0; c < 4; ++c)
			world[4 * r + c] = parent[4 * r + 0] * local[0 + c] + parent[4 * r + 1] * local[4 + c] +
			                   parent[4 * r + 2] * local[8 + c] + parent[4 * r + 3] * local[12 + c];
	if (node->mNumMeshes > 0 && node->mMeshes == NULL)
		return plait_tool_error_set(b->error, "%s: node lists %u meshes but no mesh indices", b->path,
		                            node->mNumMeshes);
	for (unsigned i = 0; i < node->mNumMeshes; ++i) {
		if (node->mMeshes[i] >= b->scene->mNumMeshes)
			return plait_tool_error_set(b->error, "%s: bad index: a node uses mesh %u of %u", b->path,
			                            node->mMeshes[i], b->scene->mNumMeshes);
		if (!plait_add_mesh(b, node->mMeshes[i], world, report))
			return false;
	}
	if (node->mNumChildren > 0 && node->mChildren == NULL)
		return true;
	for (unsigned i = 0; i < node->mNumChildren; ++i) {
		if (!plait_add_node(b, node->mChildren[i], world, depth + 1, report))
			return false;
	}
	return true;
}

typedef struct plait_sort_vertex {
	plait_vec3 p;
	int index;
} plait_sort_vertex;

static int plait_compare_vertex(const void *pa, const void *pb)
{
	const plait_sort_vertex *a = pa, *b = pb;
	float da[3] = {a->p.x, a->p.y, a->p.z}, db[3] = {b->p.x, b->p.y, b->p.z};
	for (int i = 0; i < 3; ++i) {
		if (da[i] < db[i])
			return -1;
		if (da[i] > db[i])
			return 1;
	}
	// Ties by index keep the merged vertex the first one in file order (qsort is not stable).
	return (a->index > b->index) - (a->index < b->index);
}

// Merges vertices with identical positions (assimp only joins within one mesh). vertex_of (NULL
// or one per vertex) receives the vertex each one was merged into.
static bool plait_weld(plait_soup *soup, int *unique_count, int *vertex_of)
{
	int n = soup->vertex_count;
	plait_sort_vertex *sorted = malloc(sizeof *sorted * (size_t)(n > 0 ? n : 1));
	int *remap = malloc(sizeof *remap * (size_t)(n > 0 ? n : 1));
	if (sorted == NULL || remap == NULL) {
		free(sorted);
		free(remap);
		return false;
	}
	for (int i = 0; i < n; ++i)
		sorted[i] = (plait_sort_vertex){soup->positions[i], i};
	qsort(sorted, (size_t)n, sizeof *sorted, plait_compare_vertex);
	*unique_count = 0;
	for (int i = 0; i < n;) {
		*unique_count += 1;
		int j = i;
		while (j < n && sorted[j].p.x == sorted[i].p.x && sorted[j].p.y == sorted[i].p.y &&
		       sorted[j].p.z == sorted[i].p.z) {
			remap[sorted[j].index] = sorted[i].index;
			++j;
		}
		i = j;
	}
	for (int k = 0; k < soup->index_count; ++k)
		soup->face_indices[k] = remap[soup->face_indices[k]];
	if (vertex_of != NULL)
		memcpy(vertex_of, remap, sizeof(int) * (size_t)n);
	free(sorted);
	free(remap);
	return true;
}

// Twice the polygon area (Newell) is tiny against its longest edge squared: a needle or a point.
static bool plait_face_is_degenerate(const plait_soup *soup, const int *indices, int size)
{
	for (int i = 0; i < size; ++i)
		for (int j = i + 1; j < size; ++j)
			if (indices[i] == indices[j])
				return true;
	double nx = 0.0, ny = 0.0, nz = 0.0, longest = 0.0;
	for (int i = 0; i < size; ++i) {
		plait_vec3 a = soup->positions[indices[i]], b = soup->positions[indices[(i + 1) % size]];
		nx += ((double)a.y - b.y) * ((double)a.z + b.z);
		ny += ((double)a.z - b.z) * ((double)a.x + b.x);
		nz += ((double)a.x - b.x) * ((double)a.y + b.y);
		double dx = (double)b.x - a.x, dy = (double)b.y - a.y, dz = (double)b.z - a.z;
		double edge = dx * dx + dy * dy + dz * dz;
		longest = edge > longest ? edge : longest;
	}
	double area2 = sqrt(nx * nx + ny * ny + nz * nz);
	return longest == 0.0 || area2 <= 1e-6 * longest;
}

// Drops degenerate faces, then vertices no face uses (merged duplicates are not counted).
// vertex_of (NULL or one per file vertex, as plait_weld left it) is renumbered; -1 = removed.
static bool plait_clean(plait_soup *soup, int unique_count, plait_mesh_report *report, int *vertex_of,
                        int file_vertex_count)
{
	int kept_faces = 0, kept_indices = 0, read = 0;
	for (int f = 0; f < soup->face_count; ++f) {
		int size = soup->face_sizes[f];
		const int *indices = soup->face_indices + read;
		read += size;
		if (plait_face_is_degenerate(soup, indices, size)) {
			report->degenerate_faces++;
			continue;
		}
		memmove(soup->face_indices + kept_indices, indices, sizeof(int) * (size_t)size);
		soup->face_sizes[kept_faces++] = size;
		kept_indices += size;
	}
	soup->face_count = kept_faces;
	soup->index_count = kept_indices;

	int n = soup->vertex_count;
	int *new_index = malloc(sizeof(int) * (size_t)(n > 0 ? n : 1));
	if (new_index == NULL)
		return false;
	for (int i = 0; i < n; ++i)
		new_index[i] = -1;
	for (int k = 0; k < soup->index_count; ++k)
		new_index[soup->face_indices[k]] = 0;
	int used = 0;
	for (int i = 0; i < n; ++i) {
		if (new_index[i] < 0)
			continue;
		new_index[i] = used;
		soup->positions[used++] = soup->positions[i];
	}
	for (int k = 0; k < soup->index_count; ++k)
		soup->face_indices[k] = new_index[soup->face_indices[k]];
	for (int i = 0; vertex_of != NULL && i < file_vertex_count; ++i)
		vertex_of[i] = new_index[vertex_of[i]];
	report->unused_vertices += unique_count - used;
	soup->vertex_count = used;
	free(new_index);
	return true;
}

// Checks indices and coordinates before post-processing, which trusts both.
static bool plait_mesh_validate(const struct aiScene *scene, const char *path, plait_tool_error *error)
{
	for (unsigned m = 0; m < scene->mNumMeshes; ++m) {
		const struct aiMesh *mesh = scene->mMeshes[m];
		if (mesh == NULL)
			continue;
		if (mesh->mNumVertices > PLAIT_MESH_MAX_VERTICES)
			return plait_tool_error_set(error,
			                            "%s: mesh %u has %u vertices, more than the %d a cloth may have",
			                            path, m, mesh->mNumVertices, PLAIT_MESH_MAX_VERTICES);
		for (unsigned i = 0; mesh->mVertices != NULL && i < mesh->mNumVertices; ++i) {
			double x = mesh->mVertices[i].x, y = mesh->mVertices[i].y, z = mesh->mVertices[i].z;
			if (!isfinite(x) || !isfinite(y) || !isfinite(z))
				return plait_tool_error_set(error,
				                            "%s: mesh %u vertex %u has a non-finite coordinate (%g, %g, %g)",
				                            path, m, i, x, y, z);
		}
		for (unsigned f = 0; mesh->mFaces != NULL && f < mesh->mNumFaces; ++f) {
			const struct aiFace *face = &mesh->mFaces[f];
			for (unsigned k = 0; face->mIndices != NULL && k < face->mNumIndices; ++k) {
				if (face->mIndices[k] >= mesh->mNumVertices)
					return plait_tool_error_set(error,
					                            "%s: mesh %u face %u: bad index, vertex %u is out of range "
					                            "(the mesh has %u vertices)",
					                            path, m, f, face->mIndices[k], mesh->mNumVertices);
			}
		}
	}
	return true;
}

// The file's meshes as they are listed (with node transforms), nothing merged or dropped.
static bool plait_mesh_read(const char *path, plait_soup *soup, plait_mesh_report *report,
                            plait_tool_error *error)
{
	*soup = (plait_soup){0};
	*report = (plait_mesh_report){0};
	// Our own open first: assimp's message for a missing file does not say why.
	FILE *probe = fopen(path, "rb");
	if (probe == NULL)
		return plait_tool_error_set(error, "%s: cannot open mesh file: %s", path, strerror(errno));
	fclose(probe);

	if (!plait_mesh_check_header(path, error))
		return false;
	// No post-processing: aiProcess_JoinIdenticalVertices trusts face indices and merges NaN
	// vertices out of sight before they can be reported, and in assimp 5.2 a failing
	// aiApplyPostProcessing crashes. plait_weld joins vertices instead, across meshes too.
	// Triangulation stays off so quads stay quads.
	const struct aiScene *scene = aiImportFile(path, 0);
	if (scene == NULL)
		return plait_tool_error_set(error, "%s: cannot read mesh: %s", path, aiGetErrorString());
	if (scene->mNumMeshes == 0 || scene->mMeshes == NULL) {
		aiReleaseImport(scene);
		return plait_tool_error_set(error, "%s: the file has no meshes", path);
	}
	if (!plait_mesh_validate(scene, path, error)) {
		aiReleaseImport(scene);
		return false;
	}

	plait_mesh_builder b = {.path = path, .scene = scene, .error = error};
	static const double identity[16] = {1, 0, 0, 0, 0, 1, 0, 0, 0, 0, 1, 0, 0, 0, 0, 1};
	bool ok;
	if (scene->mRootNode != NULL) {
		ok = plait_add_node(&b, scene->mRootNode, identity, 0, report);
	} else {
		ok = true;
		for (unsigned m = 0; ok && m < scene->mNumMeshes; ++m)
			ok = plait_add_mesh(&b, m, identity, report);
	}
	report->mesh_count = (int)scene->mNumMeshes;
	aiReleaseImport(scene);
	if (!ok) {
		plait_soup_free(&b.soup);
		return false;
	}
	*soup = b.soup;
	return true;
}

// Merges, drops and removes what plait_mesh_load promises, in place.
static bool plait_mesh_tidy(const char *path, plait_soup *soup, plait_mesh_report *report, int *vertex_of,
                            plait_tool_error *error)
{
	int unique_count = 0, file_vertex_count = soup->vertex_count;
	if (!plait_weld(soup, &unique_count, vertex_of) ||
	    !plait_clean(soup, unique_count, report, vertex_of, file_vertex_count))
		return plait_tool_error_set(error, "%s: out of memory", path);
	if (soup->face_count == 0) {
		if (report->degenerate_faces > 0 || report->point_line_faces > 0)
			return plait_tool_error_set(error, "%s: no usable faces (%d degenerate, %d points or lines)",
			                            path, report->degenerate_faces, report->point_line_faces);
		return plait_tool_error_set(error, "%s: the file has no faces", path);
	}
	return true;
}

bool plait_mesh_load(const char *path, plait_soup *soup, plait_mesh_report *report, plait_tool_error *error)
{
	return plait_mesh_load_layout(path, soup, report, NULL, error);
}

static int *plait_copy_ints(const int *from, int count)
{
	int *copy = malloc(sizeof(int) * (size_t)(count > 0 ? count : 1));
	if (copy != NULL && count > 0)
		memcpy(copy, from, sizeof(int) * (size_t)count);
	return copy;
}

bool plait_mesh_load_layout(const char *path, plait_soup *soup, plait_mesh_report *report,
                            plait_mesh_layout *layout, plait_tool_error *error)
{
	if (layout != NULL)
		*layout = (plait_mesh_layout){0};
	plait_soup read;
	if (!plait_mesh_read(path, &read, report, error))
		return false;
	if (layout != NULL) {
		layout->path = strdup(path);
		layout->file_vertex_count = read.vertex_count;
		layout->file_face_count = read.face_count;
		layout->file_index_count = read.index_count;
		layout->file_face_sizes = plait_copy_ints(read.face_sizes, read.face_count);
		layout->file_face_indices = plait_copy_ints(read.face_indices, read.index_count);
		layout->vertex_of = malloc(sizeof(int) * (size_t)(read.vertex_count > 0 ? read.vertex_count : 1));
		if (layout->path == NULL || layout->file_face_sizes == NULL || layout->file_face_indices == NULL ||
		    layout->vertex_of == NULL) {
			plait_mesh_layout_free(layout);
			plait_soup_free(&read);
			return plait_tool_error_set(error, "%s: out of memory", path);
		}
	}
	if (!plait_mesh_tidy(path, &read, report, layout != NULL ? layout->vertex_of : NULL, error)) {
		if (layout != NULL)
			plait_mesh_layout_free(layout);
		plait_soup_free(&read);
		return false;
	}
	if (layout != NULL) {
		layout->vertex_count = read.vertex_count;
		layout->face_count = read.face_count;
	}
	*soup = read;
	return true;
}

void plait_mesh_layout_free(plait_mesh_layout *layout)
{
	free(layout->path);
	free(layout->file_face_sizes);
	free(layout->file_face_indices);
	free(layout->vertex_of);
	*layout = (plait_mesh_layout){0};
}

static bool plait_same_ints(const int *a, const int *b, int count)
{
	return count == 0 || memcmp(a, b, sizeof(int) * (size_t)count) == 0;
}

static bool plait_same_vec3(plait_vec3 a, plait_vec3 b)
{
	return a.x == b.x && a.y == b.y && a.z == b.z;
}

// Vertices that are one in the layout's mesh must be one here too: at the same position. seen
// holds a zero byte per vertex.
static bool plait_take_positions(const plait_soup *read, const plait_mesh_layout *layout, char *seen,
                                 plait_vec3 *positions)
{
	for (int i = 0; i < read->vertex_count; ++i) {
		int v = layout->vertex_of[i];
		if (v < 0)
			continue;
		if (!seen[v])
			positions[v] = read->positions[i];
		else if (!plait_same_vec3(positions[v], read->positions[i]))
			return false;
		seen[v] = 1;
	}
	return true;
}

bool plait_mesh_load_positions(const char *path, const plait_mesh_layout *layout, plait_vec3 *positions,
                               plait_tool_error *error)
{
	plait_soup read;
	plait_mesh_report report;
	if (!plait_mesh_read(path, &read, &report, error))
		return false;
	char *seen = calloc((size_t)(layout->vertex_count > 0 ? layout->vertex_count : 1), 1);
	if (seen == NULL) {
		plait_soup_free(&read);
		return plait_tool_error_set(error, "%s: out of memory", path);
	}
	bool same_mesh = read.vertex_count == layout->file_vertex_count &&
	                 read.face_count == layout->file_face_count &&
	                 read.index_count == layout->file_index_count &&
	                 plait_same_ints(read.face_sizes, layout->file_face_sizes, read.face_count) &&
	                 plait_same_ints(read.face_indices, layout->file_face_indices, read.index_count) &&
	                 plait_take_positions(&read, layout, seen, positions);
	free(seen);
	if (same_mesh) {
		plait_soup_free(&read);
		return true;
	}
	// Say what differs in the terms of plait_mesh_load: the vertices and faces it would give.
	plait_tool_error tidy_error;
	bool tidy = plait_mesh_tidy(path, &read, &report, NULL, &tidy_error);
	int vertices = tidy ? read.vertex_count : 0, faces = tidy ? read.face_count : 0;
	plait_soup_free(&read);
	if (vertices != layout->vertex_count || faces != layout->face_count)
		return plait_tool_error_set(
		    error, "%s: expected the %d vertices and %d faces of %s, got %d vert%s and %d face%s", path,
		    layout->vertex_count, layout->face_count, layout->path, vertices, vertices == 1 ? "ex" : "ices",
		    faces, faces == 1 ? "" : "s");
	return plait_tool_error_set(error,
	                            "%s: expected the faces of %s over the same vertices, got %d vertices and %d "
	                            "faces joined differently",
	                            path, layout->path, vertices, faces);
}

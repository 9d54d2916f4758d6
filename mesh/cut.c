/*
 * mesh/cut.c -- cutting a mesh open along edges, and extracting a set of
 * faces as a mesh of its own (a panel).
 *
 * Cutting. Corners (half-edge ids, the corner at a half-edge's source) are
 * joined in a union-find across every interior edge that is not cut: the two
 * faces of the edge share both endpoints, so their corners at each endpoint
 * are one vertex. Afterwards each set is one fan of faces around one vertex,
 * and becomes one vertex of the result. The first fan of vertex v (in corner
 * order) keeps index v; further fans become new vertices numbered from
 * vertex_count up, in corner order, so an uncut mesh comes back unchanged.
 * O(F) time (union-find with path halving), 3F + V int32 of scratch.
 * Corner UVs, labels and face order are unchanged; positions and poses are
 * copied to each copy of a vertex.
 *
 * Extraction. Vertices are renumbered in order of first use by the listed
 * faces; the UVs they use are compacted the same way. O(V + F).
 *
 * Failure: PZ_ERR_NOMEM, or PZ_ERR_USAGE for a face id out of range. On
 * failure nothing is allocated and the outputs are NULL.
 *
 * SPDX-License-Identifier: GPL-3.0-or-later
 */
#include "mesh.h"
#include "core/util.h"

#include <stdlib.h>
#include <string.h>

static char *copy_string(const char *text)
{
    if (!text)
        return NULL;
    size_t length = strlen(text) + 1;
    char *copy = malloc(length);
    if (copy)
        memcpy(copy, text, length);
    return copy;
}

/* Gives `target` copies of the label names of `source` (face labels are the caller's). */
static int copy_label_names(const pz_mesh *source, pz_mesh *target)
{
    target->label_count = source->label_count;
    if (!source->label_names)
        return 1;
    target->label_names = calloc((size_t)source->label_count + 1, sizeof(char *));
    if (!target->label_names)
        return 0;
    for (int32_t i = 0; i < source->label_count; ++i)
        if (source->label_names[i] && !(target->label_names[i] = copy_string(source->label_names[i])))
            return 0;
    return 1;
}

/* Copies positions and poses: new vertex i takes original vertex original[i]. */
static int copy_vertex_data(const pz_mesh *source, pz_mesh *target, const int32_t *original)
{
    size_t new_count = (size_t)target->vertex_count, old_count = (size_t)source->vertex_count;
    for (size_t i = 0; i < new_count; ++i)
        memcpy(target->positions + 3 * i, source->positions + 3 * (size_t)original[i], 3 * sizeof(double));
    if (source->pose_count == 0)
        return 1;
    target->poses = malloc((size_t)source->pose_count * new_count * 3 * sizeof(double) + 1);
    if (!target->poses)
        return 0;
    target->pose_count = source->pose_count;
    for (size_t p = 0; p < (size_t)source->pose_count; ++p)
        for (size_t i = 0; i < new_count; ++i)
            memcpy(target->poses + (p * new_count + i) * 3, source->poses + (p * old_count + (size_t)original[i]) * 3,
                   3 * sizeof(double));
    return 1;
}

/* Joins corners across uncut interior edges; returns the new vertex of every corner in corner_vertex. */
static int32_t assign_cut_vertices(const pz_topology *t, const uint8_t *cut, int32_t *parent, int32_t *corner_vertex,
                                   uint8_t *vertex_taken)
{
    for (int32_t h = 0; h < t->halfedge_count; ++h)
        parent[h] = h;
    for (int32_t e = 0; e < t->edge_count; ++e) {
        int32_t h = t->edge_halfedge[2 * e], opposite = t->edge_halfedge[2 * e + 1];
        if (opposite < 0 || cut[e])
            continue;
        /* h runs a -> b and its twin b -> a: corner h (at a) meets next(twin), and vice versa. */
        pz_union_find_join(parent, h, pz_he_next(opposite));
        pz_union_find_join(parent, pz_he_next(h), opposite);
    }
    int32_t next_vertex = t->vertex_count;
    for (int32_t c = 0; c < t->halfedge_count; ++c)
        corner_vertex[c] = -1;
    for (int32_t c = 0; c < t->halfedge_count; ++c) {
        int32_t root = pz_union_find_root(parent, c);
        if (corner_vertex[root] < 0) {
            int32_t v = t->faces[c];
            corner_vertex[root] = vertex_taken[v] ? next_vertex++ : v;
            vertex_taken[v] = 1;
        }
        corner_vertex[c] = corner_vertex[root];
    }
    return next_vertex;
}

/* Every array of a mesh that only depends on faces: corner UVs, UVs, labels. */
static int copy_face_data(const pz_mesh *source, pz_mesh *target)
{
    size_t face_count = (size_t)source->face_count;
    if (source->corner_uvs) {
        target->uv_count = source->uv_count;
        target->uvs = malloc((size_t)source->uv_count * 2 * sizeof(double) + 1);
        target->corner_uvs = malloc(face_count * 3 * sizeof(int32_t) + 1);
        if (!target->uvs || !target->corner_uvs)
            return 0;
        memcpy(target->uvs, source->uvs, (size_t)source->uv_count * 2 * sizeof(double));
        memcpy(target->corner_uvs, source->corner_uvs, face_count * 3 * sizeof(int32_t));
    }
    if (source->face_labels) {
        target->face_labels = malloc(face_count * sizeof(int32_t) + 1);
        if (!target->face_labels)
            return 0;
        memcpy(target->face_labels, source->face_labels, face_count * sizeof(int32_t));
    }
    return copy_label_names(source, target);
}

pz_status pz_mesh_cut(const pz_mesh *mesh, const pz_topology *topology, const uint8_t *cut,
                      pz_mesh **out, int32_t **vertex_map, pz_ctx *ctx)
{
    *out = NULL;
    if (vertex_map)
        *vertex_map = NULL;
    const pz_topology *t = topology;
    int32_t *parent = malloc((size_t)t->halfedge_count * sizeof(int32_t) + 1);
    int32_t *corner_vertex = malloc((size_t)t->halfedge_count * sizeof(int32_t) + 1);
    uint8_t *vertex_taken = calloc((size_t)t->vertex_count + 1, 1);
    int32_t *original = NULL;
    pz_mesh *result = NULL;
    pz_status status = PZ_OK;
    if (!parent || !corner_vertex || !vertex_taken) {
        status = pz_error(ctx, PZ_ERR_NOMEM, "out of memory cutting a mesh of %d faces", (int)t->face_count);
        goto done;
    }
    int32_t new_vertex_count = assign_cut_vertices(t, cut, parent, corner_vertex, vertex_taken);
    if ((status = pz_mesh_create(new_vertex_count, mesh->face_count, &result, ctx)))
        goto done;
    original = malloc((size_t)new_vertex_count * sizeof(int32_t) + 1);
    if (!original) {
        status = pz_error(ctx, PZ_ERR_NOMEM, "out of memory cutting a mesh of %d faces", (int)t->face_count);
        goto done;
    }
    for (int32_t v = 0; v < mesh->vertex_count; ++v)
        original[v] = v;  /* an isolated vertex keeps itself; every used vertex is overwritten below */
    for (int32_t c = 0; c < t->halfedge_count; ++c) {
        result->faces[c] = corner_vertex[c];
        original[corner_vertex[c]] = mesh->faces[c];
    }
    result->unit_scale = mesh->unit_scale;
    if (!copy_vertex_data(mesh, result, original) || !copy_face_data(mesh, result))
        status = pz_error(ctx, PZ_ERR_NOMEM, "out of memory cutting a mesh of %d faces", (int)t->face_count);
done:
    free(parent);
    free(corner_vertex);
    free(vertex_taken);
    if (status) {
        pz_mesh_free(&result);
        free(original);
        return status;
    }
    *out = result;
    if (vertex_map)
        *vertex_map = original;
    else
        free(original);
    return PZ_OK;
}

/* Renumbers the UVs used by the extracted faces in order of first use. */
static int extract_uvs(const pz_mesh *mesh, const int32_t *face_ids, int32_t count, pz_mesh *panel)
{
    int32_t *new_uv = malloc((size_t)mesh->uv_count * sizeof(int32_t) + 1);
    panel->corner_uvs = malloc((size_t)count * 3 * sizeof(int32_t) + 1);
    if (!new_uv || !panel->corner_uvs) {
        free(new_uv);
        return 0;
    }
    for (int32_t i = 0; i < mesh->uv_count; ++i)
        new_uv[i] = -1;
    int32_t used = 0;
    for (int32_t i = 0; i < count; ++i)
        for (int k = 0; k < 3; ++k) {
            int32_t uv = mesh->corner_uvs[3 * face_ids[i] + k];
            if (new_uv[uv] < 0)
                new_uv[uv] = used++;
            panel->corner_uvs[3 * i + k] = new_uv[uv];
        }
    panel->uvs = malloc((size_t)used * 2 * sizeof(double) + 1);
    if (!panel->uvs) {
        free(new_uv);
        return 0;
    }
    panel->uv_count = used;
    for (int32_t uv = 0; uv < mesh->uv_count; ++uv)
        if (new_uv[uv] >= 0)
            memcpy(panel->uvs + 2 * new_uv[uv], mesh->uvs + 2 * uv, 2 * sizeof(double));
    free(new_uv);
    return 1;
}

static int extract_labels(const pz_mesh *mesh, const int32_t *face_ids, int32_t count, pz_mesh *panel)
{
    if (mesh->face_labels) {
        panel->face_labels = malloc((size_t)count * sizeof(int32_t) + 1);
        if (!panel->face_labels)
            return 0;
        for (int32_t i = 0; i < count; ++i)
            panel->face_labels[i] = mesh->face_labels[face_ids[i]];
    }
    return copy_label_names(mesh, panel);
}

/* Panel vertices in order of first use; returns their count, or -1 without memory. */
static int32_t number_panel_vertices(const pz_mesh *mesh, const int32_t *face_ids, int32_t count,
                                     int32_t *new_index, int32_t *original)
{
    for (int32_t v = 0; v < mesh->vertex_count; ++v)
        new_index[v] = -1;
    int32_t used = 0;
    for (int32_t i = 0; i < count; ++i)
        for (int k = 0; k < 3; ++k) {
            int32_t v = mesh->faces[3 * face_ids[i] + k];
            if (new_index[v] < 0) {
                new_index[v] = used;
                original[used++] = v;
            }
        }
    return used;
}

pz_status pz_mesh_extract(const pz_mesh *mesh, const int32_t *face_ids, int32_t count,
                          pz_mesh **out, int32_t **vertex_map, int32_t **face_map, pz_ctx *ctx)
{
    *out = NULL;
    if (vertex_map)
        *vertex_map = NULL;
    if (face_map)
        *face_map = NULL;
    for (int32_t i = 0; i < count; ++i)
        if (face_ids[i] < 0 || face_ids[i] >= mesh->face_count)
            return pz_error(ctx, PZ_ERR_USAGE, "extract: face id %d out of range 0..%d", (int)face_ids[i],
                            (int)mesh->face_count - 1);
    int32_t *new_index = malloc((size_t)mesh->vertex_count * sizeof(int32_t) + 1);
    /* At most 3 * count panel vertices; trimmed once the count is known. */
    size_t bound = (size_t)count * 3 < (size_t)mesh->vertex_count ? (size_t)count * 3 : (size_t)mesh->vertex_count;
    int32_t *original = malloc(bound * sizeof(int32_t) + 1);
    int32_t *faces_taken = face_map ? malloc((size_t)count * sizeof(int32_t) + 1) : NULL;
    pz_mesh *panel = NULL;
    pz_status status = PZ_OK;
    if (!new_index || !original || (face_map && !faces_taken)) {
        status = pz_error(ctx, PZ_ERR_NOMEM, "out of memory extracting %d faces", (int)count);
        goto done;
    }
    int32_t panel_vertex_count = number_panel_vertices(mesh, face_ids, count, new_index, original);
    if ((status = pz_mesh_create(panel_vertex_count, count, &panel, ctx)))
        goto done;
    for (int32_t i = 0; i < count; ++i)
        for (int k = 0; k < 3; ++k)
            panel->faces[3 * i + k] = new_index[mesh->faces[3 * face_ids[i] + k]];
    panel->unit_scale = mesh->unit_scale;
    if (!copy_vertex_data(mesh, panel, original) || (mesh->corner_uvs && !extract_uvs(mesh, face_ids, count, panel)) ||
        !extract_labels(mesh, face_ids, count, panel)) {
        status = pz_error(ctx, PZ_ERR_NOMEM, "out of memory extracting %d faces", (int)count);
        goto done;
    }
    if (faces_taken)
        memcpy(faces_taken, face_ids, (size_t)count * sizeof(int32_t));
done:
    free(new_index);
    if (status) {
        pz_mesh_free(&panel);
        free(original);
        free(faces_taken);
        return status;
    }
    *out = panel;
    if (vertex_map)
        *vertex_map = original;
    else
        free(original);
    if (face_map)
        *face_map = faces_taken;
    return PZ_OK;
}

/*
 * prepare/repair.c -- steps 2 and 3 of the preparation (prepare/prepare.c).
 *
 * Repair: faces with a NaN/Inf corner are dropped; degenerate and duplicate
 * faces dropped (pz_mesh_prepare); faces beyond the first two on an edge
 * dropped; non-manifold vertices split, one copy per fan (corners joined
 * across manifold edges by union-find); faces oriented consistently
 * (pz_mesh_prepare); only the passes a first validation calls for run.
 * Renumbering by pz_mesh_prepare is followed through a temporary extra
 * pose holding each vertex's index (poses are compacted with the
 * vertices), so seams survive it.
 *
 * Fragments: components under 1% of the total area are dropped (--keep all
 * keeps them).
 *
 * SPDX-License-Identifier: GPL-3.0-or-later
 */
#include "prepare/internal.h"

#include <stdlib.h>
#include <string.h>

/* ------------------------------------------------------------------------ */
/* 2. Repair                                                                 */
/* ------------------------------------------------------------------------ */

/*
 * Runs pz_mesh_prepare quietly while following its vertex renumbering: a
 * temporary last pose holds each vertex's old index in x (poses are compacted
 * with the vertices), which then renumbers the seams. *validity gets
 * pz_mesh_prepare's own status (PZ_ERR_INVALID_MESH when problems remain).
 * renumbered (NULL: not wanted) gets the old -> new vertex table (-1:
 * dropped; malloc'd, the caller frees it).
 */
static pz_status prepare_tracked(pz_mesh *mesh, const char *name, unsigned flags, prep_edge_list *seams,
                                 pz_status *validity, int32_t **renumbered, pz_ctx *ctx)
{
    int32_t old_count = mesh->vertex_count;
    double *ids = malloc(3 * (size_t)old_count * sizeof(double) + 1);
    int32_t *new_index = malloc((size_t)old_count * sizeof(int32_t) + 1);
    if (!ids || !new_index) {
        free(ids);
        free(new_index);
        return pz_error(ctx, PZ_ERR_NOMEM, "prepare: out of memory repairing %d vertices", (int)old_count);
    }
    for (int32_t v = 0; v < old_count; ++v) {
        ids[3 * v] = v;
        ids[3 * v + 1] = ids[3 * v + 2] = 0.0;
        new_index[v] = -1;
    }
    pz_status status = pz_mesh_add_pose(mesh, ids, ctx);
    free(ids);
    if (status) {
        free(new_index);
        return status;
    }
    int quiet = ctx->quiet;
    ctx->quiet = 1;
    *validity = pz_mesh_prepare(mesh, name, flags, ctx);
    ctx->quiet = quiet;
    const double *id_pose = mesh->poses + (size_t)(mesh->pose_count - 1) * mesh->vertex_count * 3;
    for (int32_t v = 0; v < mesh->vertex_count; ++v)
        new_index[(int32_t)id_pose[3 * v]] = v;
    if (--mesh->pose_count == 0) {
        free(mesh->poses);
        mesh->poses = NULL;
    }
    int32_t kept = 0;
    for (int32_t e = 0; e < seams->count; ++e) {
        int32_t a = new_index[seams->pairs[2 * e]], b = new_index[seams->pairs[2 * e + 1]];
        if (a >= 0 && b >= 0) {
            seams->pairs[2 * kept] = a;
            seams->pairs[2 * kept + 1] = b;
            ++kept;
        }
    }
    seams->count = kept;
    if (renumbered)
        *renumbered = new_index;
    else
        free(new_index);
    return PZ_OK;
}

static int32_t drop_nonfinite_faces(pz_mesh *mesh, uint8_t *drop)
{
    for (int32_t f = 0; f < mesh->face_count; ++f) {
        drop[f] = 0;
        for (int k = 0; k < 3; ++k) {
            int32_t v = mesh->faces[3 * f + k];
            drop[f] |= !prep_is_finite3(mesh->positions + 3 * (size_t)v);
            for (int32_t p = 0; p < mesh->pose_count; ++p)
                drop[f] |= !prep_is_finite3(mesh->poses + ((size_t)p * mesh->vertex_count + v) * 3);
        }
    }
    return pz_mesh_drop_faces(mesh, drop);
}

/* Drops every face beyond the first two on an edge. */
static pz_status drop_nonmanifold_edge_faces(pz_mesh *mesh, uint8_t *drop, int32_t *dropped, pz_ctx *ctx)
{
    prep_halfedge_key *keys = prep_sorted_halfedges(mesh->faces, mesh->face_count);
    if (!keys)
        return pz_error(ctx, PZ_ERR_NOMEM, "prepare: out of memory checking edges");
    memset(drop, 0, (size_t)mesh->face_count);
    size_t count = 3 * (size_t)mesh->face_count;
    for (size_t begin = 0, end; begin < count; begin = end) {
        end = prep_group_end(keys, count, begin);
        for (size_t i = begin + 2; i < end; ++i)
            drop[pz_he_face(keys[i].halfedge)] = 1;
    }
    free(keys);
    *dropped = pz_mesh_drop_faces(mesh, drop);
    return PZ_OK;
}

/* Marks seam half-edges (binary search of each half-edge in the sorted seam list). */
static int pair_compare(const void *pa, const void *pb)
{
    const int32_t *a = pa, *b = pb;
    return a[0] != b[0] ? (a[0] > b[0]) - (a[0] < b[0]) : (a[1] > b[1]) - (a[1] < b[1]);
}

static void mark_seam_halfedges(const pz_mesh *mesh, prep_edge_list *seams, uint8_t *is_seam)
{
    if (seams->count == 0) { /* qsort and bsearch may not take the NULL of an empty list */
        memset(is_seam, 0, 3 * (size_t)mesh->face_count);
        return;
    }
    qsort(seams->pairs, (size_t)seams->count, 2 * sizeof(int32_t), pair_compare);
    for (int32_t h = 0; h < 3 * mesh->face_count; ++h) {
        int32_t a = mesh->faces[h], b = mesh->faces[pz_he_next(h)];
        int32_t key[2] = {a < b ? a : b, a < b ? b : a};
        is_seam[h] = bsearch(key, seams->pairs, (size_t)seams->count, 2 * sizeof(int32_t), pair_compare) != NULL;
    }
}

/* Gives every fan of a vertex but the first its own copy (corners joined across two-face edges). */
static pz_status split_fans(pz_mesh *mesh, int32_t *corner_parent, int32_t *fan_vertex, int32_t *split,
                            pz_ctx *ctx)
{
    size_t corners = 3 * (size_t)mesh->face_count;
    prep_halfedge_key *keys = prep_sorted_halfedges(mesh->faces, mesh->face_count);
    uint8_t *taken = calloc((size_t)mesh->vertex_count + 1, 1);
    int32_t *source = malloc(corners * sizeof(int32_t) + 1);
    if (!keys || !taken || !source) {
        free(keys);
        free(taken);
        free(source);
        return pz_error(ctx, PZ_ERR_NOMEM, "prepare: out of memory splitting vertices");
    }
    for (size_t c = 0; c < corners; ++c) {
        corner_parent[c] = (int32_t)c;
        fan_vertex[c] = -1;
    }
    for (size_t begin = 0, end; begin < corners; begin = end) {
        end = prep_group_end(keys, corners, begin);
        if (end - begin != 2)
            continue;
        int32_t h1 = keys[begin].halfedge, h2 = keys[begin + 1].halfedge;
        int same_way = mesh->faces[h1] == mesh->faces[h2];
        pz_union_find_join(corner_parent, h1, same_way ? h2 : pz_he_next(h2));
        pz_union_find_join(corner_parent, pz_he_next(h1), same_way ? pz_he_next(h2) : h2);
    }
    free(keys);
    int32_t count = mesh->vertex_count;
    for (size_t c = 0; c < corners; ++c) {
        int32_t root = pz_union_find_root(corner_parent, (int32_t)c), v = mesh->faces[c];
        if (fan_vertex[root] < 0) {
            if (!taken[v]) {
                taken[v] = 1;
                fan_vertex[root] = v;
            } else {
                source[count - mesh->vertex_count] = v;
                fan_vertex[root] = count++;
            }
        }
        mesh->faces[c] = fan_vertex[root];
    }
    free(taken);
    *split = count - mesh->vertex_count;
    pz_status status = PZ_OK;
    if (*split) {
        int32_t n = mesh->vertex_count;
        double *positions = realloc(mesh->positions, 3 * (size_t)count * sizeof(double));
        double *poses = mesh->pose_count ? malloc((size_t)mesh->pose_count * count * 3 * sizeof(double)) : NULL;
        if (positions)
            mesh->positions = positions;
        if (!positions || (mesh->pose_count && !poses)) {
            free(poses);
            free(source);
            return pz_error(ctx, PZ_ERR_NOMEM, "prepare: out of memory splitting vertices");
        }
        for (int32_t i = 0; i < *split; ++i)
            memcpy(positions + 3 * (size_t)(n + i), positions + 3 * (size_t)source[i], 3 * sizeof(double));
        for (size_t p = 0; p < (size_t)mesh->pose_count; ++p) {
            memcpy(poses + p * count * 3, mesh->poses + p * n * 3, (size_t)n * 3 * sizeof(double));
            for (int32_t i = 0; i < *split; ++i)
                memcpy(poses + (p * count + n + i) * 3, mesh->poses + (p * n + source[i]) * 3, 3 * sizeof(double));
        }
        if (poses) {
            free(mesh->poses);
            mesh->poses = poses;
        }
        mesh->vertex_count = count;
    }
    free(source);
    return status;
}

/* Non-manifold edges then vertices; seams are carried by their half-edges. */
static pz_status make_manifold(pz_mesh *mesh, prep_edge_list *seams, pz_prepare_report *report, pz_ctx *ctx)
{
    size_t corners = 3 * (size_t)mesh->face_count;
    uint8_t *flags = malloc(corners + 1);
    int32_t *corner_parent = malloc(corners * sizeof(int32_t) + 1);
    int32_t *fan_vertex = malloc(corners * sizeof(int32_t) + 1);
    pz_status status = PZ_OK;
    if (!flags || !corner_parent || !fan_vertex)
        status = pz_error(ctx, PZ_ERR_NOMEM, "prepare: out of memory repairing %d faces", (int)mesh->face_count);
    if (!status)
        status = drop_nonmanifold_edge_faces(mesh, flags, &report->nonmanifold_edge_faces, ctx);
    if (!status) {
        mark_seam_halfedges(mesh, seams, flags);
        status = split_fans(mesh, corner_parent, fan_vertex, &report->split_vertices, ctx);
    }
    if (!status) {
        seams->count = 0;
        for (int32_t h = 0; h < 3 * mesh->face_count && !status; ++h)
            if (flags[h] && mesh->faces[h] < mesh->faces[pz_he_next(h)] &&
                !prep_edge_list_add(seams, mesh->faces[h], mesh->faces[pz_he_next(h)]))
                status = pz_error(ctx, PZ_ERR_NOMEM, "prepare: out of memory keeping seams");
    }
    free(flags);
    free(corner_parent);
    free(fan_vertex);
    return status;
}

pz_status pz_prepare_make_manifold(pz_mesh *mesh, int32_t *dropped_faces, int32_t *split_vertices, pz_ctx *ctx)
{
    if (dropped_faces)
        *dropped_faces = 0;
    if (split_vertices)
        *split_vertices = 0;
    if (!mesh)
        return pz_error(ctx, PZ_ERR_USAGE, "prepare: no mesh");
    pz_validation found;
    pz_status status = pz_mesh_validate(mesh, &found, ctx);
    if (status)
        return status;
    /* Out-of-range corners or non-finite vertices: pz_mesh_prepare names them. */
    int needed = (found.nonmanifold_edges || found.nonmanifold_vertices) && !found.bad_indices &&
                 !found.nonfinite_coordinates && mesh->face_count > 0;
    pz_validation_clear(&found);
    if (!needed)
        return PZ_OK;
    pz_prepare_report report;
    memset(&report, 0, sizeof report);
    prep_edge_list seams = {0, 0, NULL};
    status = make_manifold(mesh, &seams, &report, ctx);
    free(seams.pairs);
    if (dropped_faces)
        *dropped_faces = report.nonmanifold_edge_faces;
    if (split_vertices)
        *split_vertices = report.split_vertices;
    return status;
}

/* Orients the faces consistently, counting the flips (pz_mesh_prepare swaps corners 1 and 2 of the minority). */
static pz_status orient(pz_mesh *mesh, const char *name, prep_edge_list *seams, pz_prepare_report *report,
                        pz_status *validity, pz_ctx *ctx)
{
    int32_t *old_second = malloc((size_t)mesh->face_count * sizeof(int32_t) + 1);
    if (!old_second)
        return pz_error(ctx, PZ_ERR_NOMEM, "prepare: out of memory orienting faces");
    for (int32_t f = 0; f < mesh->face_count; ++f)
        old_second[f] = mesh->faces[3 * f + 1];
    int32_t faces = mesh->face_count, *new_index = NULL;
    /* it also drops the vertices earlier passes stranded (a fin's tip), renumbering the rest */
    pz_status status = prepare_tracked(mesh, name, PZ_REPAIR_ORIENT, seams, validity, &new_index, ctx);
    report->flipped_faces = 0;
    if (!status && mesh->face_count == faces)
        for (int32_t f = 0; f < faces; ++f)
            report->flipped_faces += mesh->faces[3 * f + 1] != new_index[old_second[f]];
    free(old_second);
    free(new_index);
    return status;
}

/*
 * Runs only the repairs a first validation calls for: a clean 1M-face scan
 * costs that one validation (0.09 s) instead of every pass (0.7 s).
 * Dropping faces can split a vertex's fan, and dropping the third face of
 * an edge can leave the other two disagreeing, so after either the later
 * checks run regardless.
 */
pz_status prep_repair(pz_mesh *mesh, const char *name, prep_edge_list *seams, pz_prepare_report *report, pz_ctx *ctx)
{
    uint8_t *drop = malloc((size_t)mesh->face_count + 1);
    if (!drop)
        return pz_error(ctx, PZ_ERR_NOMEM, "prepare: out of memory repairing %d faces", (int)mesh->face_count);
    report->nonfinite_faces = drop_nonfinite_faces(mesh, drop);
    free(drop);
    pz_validation found;
    pz_status status = pz_mesh_validate(mesh, &found, ctx), validity = PZ_OK;
    if (status)
        return status;
    int dropping = found.bad_indices || found.degenerate_faces || found.duplicate_faces;
    int splitting = dropping || found.nonmanifold_edges || found.nonmanifold_vertices;
    int orienting = splitting || found.inconsistent_edges;
    int32_t faces_before = mesh->face_count, degenerate = found.degenerate_faces;
    unsigned flags = dropping ? PZ_REPAIR_DROP_DEGENERATE | PZ_REPAIR_DROP_DUPLICATES : 0;
    if (dropping || found.unreferenced_vertices || report->nonfinite_faces)
        status = prepare_tracked(mesh, name, flags, seams, &validity, NULL, ctx); /* also drops unused vertices */
    pz_validation_clear(&found);
    int32_t dropped = faces_before - mesh->face_count;
    report->degenerate_faces = degenerate < dropped ? degenerate : dropped;
    report->duplicate_faces = dropped - report->degenerate_faces;
    if (!status && splitting && mesh->face_count > 0)
        status = make_manifold(mesh, seams, report, ctx);
    if (!status && orienting && mesh->face_count > 0) {
        status = orient(mesh, name, seams, report, &validity, ctx);
        if (!status && validity != PZ_OK)
            status = validity; /* still invalid (not orientable): pz_mesh_prepare's message names the problem */
    }
    return status;
}

/* ------------------------------------------------------------------------ */
/* 3. Fragments                                                              */
/* ------------------------------------------------------------------------ */

pz_status prep_drop_fragments(pz_mesh *mesh, const char *name, double fraction, pz_prepare_keep keep,
                              prep_edge_list *seams, pz_prepare_report *report, pz_ctx *ctx)
{
    int32_t *component = malloc((size_t)mesh->face_count * sizeof(int32_t) + 1);
    double *face_area = malloc((size_t)mesh->face_count * sizeof(double) + 1);
    double *area = NULL;
    uint8_t *drop = NULL;
    pz_status status = PZ_OK;
    if (!component || !face_area) {
        status = pz_error(ctx, PZ_ERR_NOMEM, "prepare: out of memory finding components");
        goto done;
    }
    int32_t count = pz_mesh_face_components(mesh, component, ctx);
    if (count < 0) {
        status = (pz_status)count;
        goto done;
    }
    report->components = count;
    area = calloc((size_t)count + 1, sizeof(double));
    drop = malloc((size_t)mesh->face_count + 1);
    if (!area || !drop) {
        status = pz_error(ctx, PZ_ERR_NOMEM, "prepare: out of memory finding components");
        goto done;
    }
    pz_geom_face_areas(mesh, face_area);
    double total = 0.0;
    for (int32_t f = 0; f < mesh->face_count; ++f) {
        area[component[f]] += face_area[f];
        total += face_area[f];
    }
    int32_t largest = 0;
    for (int32_t c = 1; c < count; ++c)
        if (area[c] > area[largest])
            largest = c;
    if (keep == PZ_PREPARE_KEEP_ALL || count <= 1)
        goto done;
    for (int32_t c = 0; c < count; ++c)
        if (c != largest && area[c] < fraction * total)
            ++report->dropped_components;
    for (int32_t f = 0; f < mesh->face_count; ++f)
        drop[f] = component[f] != largest && area[component[f]] < fraction * total;
    if (report->dropped_components) {
        report->dropped_component_faces = pz_mesh_drop_faces(mesh, drop);
        pz_status validity = PZ_OK;
        status = prepare_tracked(mesh, name, 0, seams, &validity, NULL, ctx); /* drops the stranded vertices */
    }
done:
    free(component);
    free(face_area);
    free(area);
    free(drop);
    return status;
}

/*
 * pipeline/mirror_garment.c -- the garment made exactly symmetric before the
 * automatic layout (docs/segment.md, "The symmetrized garment";
 * pietroni2022 Sec. 3, Fig. 3a): when `panelize run` finds a mirror plane
 * (or is given one) on a garment without extra poses, the garment is cut
 * along the plane, one half kept, reflected and welded
 * (pz_prepare_symmetrize), and the field, layout, flattening and garment.obj
 * are those of that garment: mirror pieces are then exact images through an
 * exact vertex map (pipeline/mirror.c). When the run then lays the garment
 * out without the plane (a mirrored layout that costs pieces), or a piece
 * budget's mirrored layout misses the goals, the garment is given back as it
 * was and the run made again as before (pipeline.c, redo_as_loaded), so a
 * run that does not keep the symmetric garment is what it was.
 *
 * SPDX-License-Identifier: GPL-3.0-or-later
 */
#include "pipeline/internal.h"

#include "prepare/prepare.h"

#include <math.h>
#include <stdlib.h>
#include <string.h>

void pl_symmetric_clear(pl_symmetric *sym)
{
    pz_mesh_free(&sym->original);
    free(sym->original_positions_out);
    free(sym->original_seam_vertices);
    pz_symmetry_clear(&sym->symmetry);
    memset(sym, 0, sizeof *sym);
}

/* The welded seams (sketch lines) of the preparation in the symmetric garment's vertices: each seam vertex at
 * the symmetric vertex nearest to it (the original ids kept to give back). */
static pz_status remap_seams(pz_prepare_result *prepared, const int32_t *nearest, int32_t vertex_count,
                             pl_symmetric *sym, pz_ctx *ctx)
{
    if (!prepared || prepared->seam_count == 0)
        return PZ_OK;
    int32_t count = prepared->seam_offsets[prepared->seam_count];
    sym->original_seam_vertices = malloc(((size_t)count + 1) * sizeof(int32_t));
    if (!sym->original_seam_vertices)
        return pz_error(ctx, PZ_ERR_NOMEM, "run: out of memory");
    memcpy(sym->original_seam_vertices, prepared->seam_vertices, (size_t)count * sizeof(int32_t));
    for (int32_t i = 0; i < count; ++i) {
        int32_t v = prepared->seam_vertices[i];
        prepared->seam_vertices[i] = v >= 0 && v < vertex_count ? nearest[v] : v;
    }
    return PZ_OK;
}

/* The plane as pz_run finds it (segment options: AUTO, an axis or the user's plane in the input's units). */
static pz_status detect_plane(const pz_run_options *options, const pz_mesh *mesh, pz_symmetry *out, pz_ctx *ctx)
{
    pz_topology *topology = NULL;
    pz_status status = pz_topology_build(mesh, &topology, ctx);
    double plane[4];
    memcpy(plane, options->segment.symmetry_plane, sizeof plane);
    plane[3] *= mesh->unit_scale;
    if (status == PZ_OK)
        status = pz_symmetry_detect(mesh, topology, options->segment.symmetry, plane, 0, out, ctx);
    pz_topology_free(&topology);
    return status;
}

/* The symmetry of the symmetric garment: the plane and the input's residual figures, the exact maps. */
static pz_status exact_symmetry(const pz_symmetry *found, const pz_symmetrized *s, pz_symmetry *out, pz_ctx *ctx)
{
    *out = *found;
    out->vertex_mirror = NULL, out->vertex_side = NULL, out->face_mirror = NULL;
    out->vertex_count = s->mesh->vertex_count;
    out->face_count = s->mesh->face_count;
    out->vertex_mirror = malloc(((size_t)out->vertex_count + 1) * sizeof(int32_t));
    out->vertex_side = malloc((size_t)out->vertex_count + 1);
    out->face_mirror = malloc(((size_t)out->face_count + 1) * sizeof(int32_t));
    if (!out->vertex_mirror || !out->vertex_side || !out->face_mirror)
        return pz_error(ctx, PZ_ERR_NOMEM, "run: out of memory");
    memcpy(out->vertex_mirror, s->vertex_mirror, (size_t)out->vertex_count * sizeof(int32_t));
    memcpy(out->vertex_side, s->vertex_side, (size_t)out->vertex_count);
    memcpy(out->face_mirror, s->face_mirror, (size_t)out->face_count * sizeof(int32_t));
    return PZ_OK;
}

pz_status pl_symmetrize_garment(const pz_run_options *options, pz_result *result, pl_garment *garment,
                                pl_symmetric *sym, pz_ctx *ctx)
{
    memset(sym, 0, sizeof *sym);
    pz_mesh *mesh = garment->mesh;
    if (options->segment.symmetry == PZ_SYMMETRY_OFF || mesh->pose_count > 0)
        return PZ_OK;
    double start = pz_seconds();
    pz_symmetry found;
    memset(&found, 0, sizeof found);
    pz_ctx quiet;
    pz_ctx_quiet(ctx, &quiet);
    pz_status status = detect_plane(options, mesh, &found, ctx);
    /* Strokes on one side only: the layout is made without the plane (the segmentation says so), and so on the
     * garment as it is. */
    int symmetric = 1;
    if (status == PZ_OK && found.found && options->segment.symmetry == PZ_SYMMETRY_AUTO && !options->mirror_sketch)
        status = pl_sketch_symmetric_on(options, mesh, &found, &symmetric, ctx);
    if (status != PZ_OK || !found.found || !symmetric) {
        pz_symmetry_clear(&found);
        return status;
    }
    pz_symmetrized s;
    status = pz_prepare_symmetrize(mesh, found.normal, found.offset, &s, &quiet);
    if (status != PZ_OK) {
        pz_symmetry_clear(&found);
        if (status != PZ_ERR_DATA)
            return pz_error(ctx, status, "%s", quiet.error);
        /* No sound symmetric garment: the layout mirrors on the garment as it is. */
        pz_note(ctx, "run: symmetry: the garment is laid out as it is (%s)", quiet.error);
        return PZ_OK;
    }
    status = exact_symmetry(&found, &s, &sym->symmetry, ctx);
    double *positions_out = NULL;
    if (status == PZ_OK && !(positions_out = malloc((3 * (size_t)s.mesh->vertex_count + 1) * sizeof(double))))
        status = pz_error(ctx, PZ_ERR_NOMEM, "run: out of memory");
    if (status == PZ_OK)
        status = remap_seams(result->prepared, s.input_nearest, mesh->vertex_count, sym, ctx);
    if (status != PZ_OK) {
        free(positions_out);
        pz_symmetrized_clear(&s);
        pz_symmetry_clear(&found);
        pl_symmetric_clear(sym);
        return status;
    }
    for (size_t i = 0; i < 3 * (size_t)s.mesh->vertex_count; ++i)
        positions_out[i] = s.mesh->positions[i] / s.mesh->unit_scale;
    sym->active = 1;
    sym->original = mesh;
    sym->original_positions_out = result->positions_out;
    sym->original_ids_preserved = garment->ids_preserved;
    sym->deviation_max_mm = s.deviation_max_mm;
    sym->deviation_p95_mm = s.deviation_p95_mm;
    garment->mesh = s.mesh;
    garment->ids_preserved = 0; /* the caller's ids name none of its vertices */
    result->positions_out = positions_out;
    s.mesh = NULL;
    sym->cut_faces = s.cut_faces, sym->snapped_vertices = s.snapped_vertices;
    sym->milliseconds = pz_elapsed_ms(start, pz_seconds());
    pz_symmetrized_clear(&s);
    pz_symmetry_clear(&found);
    return PZ_OK;
}

void pl_symmetric_restore(pl_symmetric *sym, pz_result *result, pl_garment *garment)
{
    if (!sym->active)
        return;
    pz_mesh_free(&garment->mesh);
    garment->mesh = sym->original;
    garment->ids_preserved = sym->original_ids_preserved;
    free(result->positions_out);
    result->positions_out = sym->original_positions_out;
    pz_prepare_result *prepared = result->prepared;
    if (prepared && sym->original_seam_vertices)
        memcpy(prepared->seam_vertices, sym->original_seam_vertices,
               (size_t)prepared->seam_offsets[prepared->seam_count] * sizeof(int32_t));
    sym->original = NULL, sym->original_positions_out = NULL;
    sym->active = 0;
    sym->restored = 1;
}

void pl_symmetric_resettle(const pl_symmetric *sym, pz_mesh *mesh)
{
    if (!sym->active || sym->symmetry.vertex_count != mesh->vertex_count)
        return;
    const pz_symmetry *s = &sym->symmetry;
    for (int32_t v = 0; v < mesh->vertex_count; ++v) {
        int32_t m = s->vertex_mirror[v];
        double *p = mesh->positions + 3 * (size_t)v;
        if (m < v)
            continue;
        double image[3];
        pz_symmetry_reflect_point(s, mesh->positions + 3 * (size_t)m, image);
        for (int d = 0; d < 3; ++d)
            p[d] = 0.5 * (p[d] + image[d]);
        if (m == v) /* on the plane, exactly */
            continue;
        pz_symmetry_reflect_point(s, p, mesh->positions + 3 * (size_t)m);
    }
}

void pl_symmetric_report(const pl_symmetric *sym, pz_result *result, pz_ctx *ctx)
{
    /* Said once the garment is kept (the run's errors, a bad sketch say, come first and alone). */
    if (sym->active && ctx)
        pz_note(ctx, "run: symmetry: laid out on the garment made exactly symmetric about (%.4f, %.4f, %.4f) . p = "
                "%.2f mm: %d faces cut, %d vertices snapped; the input within %.2f mm of it (95 %%: %.2f mm), %d "
                "vertices, %d faces (%.0f ms)", sym->symmetry.normal[0], sym->symmetry.normal[1],
                sym->symmetry.normal[2], sym->symmetry.offset, (int)sym->cut_faces, (int)sym->snapped_vertices,
                sym->deviation_max_mm, sym->deviation_p95_mm, (int)sym->symmetry.vertex_count,
                (int)sym->symmetry.face_count, sym->milliseconds);
    result->symmetrized = sym->active;
    result->symmetrized_max_mm = sym->active ? sym->deviation_max_mm : -1;
    result->symmetrized_p95_mm = sym->active ? sym->deviation_p95_mm : -1;
}

int pl_symmetric_misses_goals(const pz_result *result, const pz_mesh *garment, pz_ctx *ctx)
{
    const pz_pattern *pattern = result->pattern;
    pz_ctx quiet;
    pz_ctx_quiet(ctx, &quiet);
    pz_metrics *metrics = NULL;
    pz_goal_result *panels = calloc((size_t)pattern->panel_count + 1, sizeof *panels);
    int misses = 0;
    if (panels && pz_metrics_compute(pattern, result->uv, 0, &result->options.flatten.fabric, &metrics, &quiet) == PZ_OK &&
        pl_judge_panels(garment, pattern, result->uv, metrics, NULL, &result->options.goals, NULL, panels, &quiet) ==
            PZ_OK)
        for (int32_t p = 0; p < pattern->panel_count; ++p)
            misses += panels[p].failures != 0;
    pz_metrics_free(&metrics);
    free(panels);
    return misses > 0;
}

/*
 * pipeline/sketches.c -- the designer's lines for the automatic layout
 * (docs/run.md, docs/segment.md "Sketches"): the sketches given in memory
 * and in the sketch file, checked against the garment, plus the seams the
 * automatic preparation welded, gathered into one pz_sketch.
 *
 * Apart from pipeline/segmentation.c because it is input handling with no
 * part in the layout's rounds.
 *
 * SPDX-License-Identifier: GPL-3.0-or-later
 */
#include "pipeline/internal.h"

#include <stdlib.h>
#include <string.h>

/* Room for `curves` more curves and `points` more points in a sketch being gathered. */
static int sketch_reserve(pz_sketch *sketch, int32_t curves, int32_t points)
{
    int32_t have_points = sketch->curve_offsets ? sketch->curve_offsets[sketch->curve_count] : 0;
    int32_t *offsets = realloc(sketch->curve_offsets, ((size_t)sketch->curve_count + curves + 1) * sizeof(int32_t));
    if (!offsets)
        return 0;
    if (!sketch->curve_offsets)
        offsets[0] = 0;
    sketch->curve_offsets = offsets;
    double *grown = realloc(sketch->points, ((size_t)have_points + points + 1) * 3 * sizeof(double));
    if (!grown)
        return 0;
    sketch->points = grown;
    return 1;
}

/* Appends every curve of `from` (millimetres). */
static int sketch_append(pz_sketch *sketch, const pz_sketch *from)
{
    if (!from || from->curve_count == 0)
        return 1;
    int32_t points = from->curve_offsets[from->curve_count] - from->curve_offsets[0];
    if (!sketch_reserve(sketch, from->curve_count, points))
        return 0;
    int32_t at = sketch->curve_offsets[sketch->curve_count];
    memcpy(sketch->points + 3 * (size_t)at, from->points + 3 * (size_t)from->curve_offsets[0],
           3 * (size_t)points * sizeof(double));
    for (int32_t c = 0; c < from->curve_count; ++c)
        sketch->curve_offsets[++sketch->curve_count] = at + from->curve_offsets[c + 1] - from->curve_offsets[0];
    return 1;
}

/* Appends the seams the preparation welded, as polylines through the garment's vertices. */
static int sketch_append_welded(pz_sketch *sketch, const pz_prepare_result *prepared, const pz_mesh *mesh)
{
    int32_t welded = prepared && prepared->mesh == NULL ? prepared->seam_count : 0;
    if (welded == 0)
        return 1;
    if (!sketch_reserve(sketch, welded, prepared->seam_offsets[welded]))
        return 0;
    int32_t at = sketch->curve_offsets[sketch->curve_count];
    for (int32_t s = 0; s < welded; ++s) {
        int32_t first = prepared->seam_offsets[s], last = prepared->seam_offsets[s + 1];
        if (last - first < 2)
            continue;
        for (int32_t i = first; i < last; ++i, ++at)
            memcpy(sketch->points + 3 * (size_t)at, mesh->positions + 3 * (size_t)prepared->seam_vertices[i],
                   3 * sizeof(double));
        sketch->curve_offsets[++sketch->curve_count] = at;
    }
    return 1;
}

/* The curves given in memory (`given`, named `name` in messages) checked against the mesh, and those of the file
 * `path` (may be NULL; in the mesh's units) read and checked into *from_file (the caller's). */
static pz_status read_checked(const pz_sketch *given, const char *name, const char *path, const pz_mesh *mesh,
                              pz_sketch **from_file, pz_ctx *ctx)
{
    *from_file = NULL;
    pz_status status = pz_sketch_check(given, mesh, name, ctx);
    if (status == PZ_OK && path) {
        status = pz_sketch_read(path, mesh->unit_scale, from_file, ctx);
        if (status == PZ_OK)
            status = pz_sketch_check(*from_file, mesh, path, ctx);
    }
    return status;
}

pz_status pl_gather_sketch(const pz_run_options *options, const pz_prepare_result *prepared, const pz_mesh *mesh,
                           pz_sketch **out, pz_ctx *ctx)
{
    *out = NULL;
    pz_sketch *from_file = NULL;
    pz_status status = read_checked(options->sketch, "sketch", options->sketch_path, mesh, &from_file, ctx);
    if (status != PZ_OK) {
        pz_sketch_free(&from_file);
        return status;
    }
    pz_sketch *sketch = calloc(1, sizeof *sketch);
    int ok = sketch && sketch_append(sketch, options->sketch) && sketch_append(sketch, from_file) &&
             sketch_append_welded(sketch, prepared, mesh);
    pz_sketch_free(&from_file);
    if (!ok) {
        pz_sketch_free(&sketch);
        return pz_error(ctx, PZ_ERR_NOMEM, "run: out of memory gathering sketches");
    }
    if (sketch->curve_count == 0)
        pz_sketch_free(&sketch);
    *out = sketch;
    return PZ_OK;
}

pz_status pl_sketch_join(const pz_sketch *a, const pz_sketch *b, pz_sketch **out, pz_ctx *ctx)
{
    *out = NULL;
    if ((!a || a->curve_count == 0) && (!b || b->curve_count == 0))
        return PZ_OK;
    pz_sketch *joined = calloc(1, sizeof *joined);
    if (!joined || !sketch_reserve(joined, 0, 0) || !sketch_append(joined, a) || !sketch_append(joined, b)) {
        pz_sketch_free(&joined);
        return pz_error(ctx, PZ_ERR_NOMEM, "run: out of memory joining the sketches");
    }
    *out = joined;
    return PZ_OK;
}

pz_status pl_gather_grain_hints(const pz_run_options *options, const pz_mesh *mesh, pz_sketch **out, pz_ctx *ctx)
{
    *out = NULL;
    pz_sketch *from_file = NULL;
    pz_status status =
        read_checked(options->grain_hints, "grain hints", options->grain_hints_path, mesh, &from_file, ctx);
    if (status == PZ_OK)
        status = pl_sketch_join(options->grain_hints, from_file, out, ctx);
    pz_sketch_free(&from_file);
    /* Each hint is placed by a search over the faces (grain_hints.c), at every flattening: a bound keeps a
     * hostile file's cost in step with the garment's. */
    if (status == PZ_OK && *out && (*out)->curve_count > PL_GRAIN_HINTS_MAX) {
        int32_t count = (*out)->curve_count;
        pz_sketch_free(out);
        status = pz_error(ctx, PZ_ERR_DATA, "%s: %d grain hints, at most %d (a piece takes one)",
                          options->grain_hints_path ? options->grain_hints_path : "grain hints", (int)count,
                          PL_GRAIN_HINTS_MAX);
    }
    return status;
}

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

#include "core/vec.h"

#include <math.h>
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

pz_status pl_designer_sketch(const pz_run_options *options, const pz_mesh *mesh, pz_sketch **out, pz_ctx *ctx)
{
    *out = NULL;
    pz_sketch *from_file = NULL;
    pz_status status = read_checked(options->sketch, "sketch", options->sketch_path, mesh, &from_file, ctx);
    if (status == PZ_OK)
        status = pl_sketch_join(options->sketch, from_file, out, ctx);
    pz_sketch_free(&from_file);
    return status;
}

pz_status pl_gather_sketch(const pz_run_options *options, const pz_prepare_result *prepared, const pz_mesh *mesh,
                           const pz_symmetry *plane, pz_sketch **out, pz_ctx *ctx)
{
    *out = NULL;
    pz_sketch *designer = NULL;
    pz_status status = pl_designer_sketch(options, mesh, &designer, ctx);
    if (status == PZ_OK && designer && options->mirror_sketch && plane && plane->found)
        status = pl_sketch_add_mirrors(designer, plane, pl_sketch_mirror_tolerance(mesh), ctx);
    if (status == PZ_OK)
        status = pz_sketch_check(options->garment_seams, mesh, "garment seams", ctx);
    if (status != PZ_OK) {
        pz_sketch_free(&designer);
        return status;
    }
    pz_sketch *sketch = calloc(1, sizeof *sketch);
    int ok = sketch && sketch_reserve(sketch, 0, 0) && sketch_append(sketch, designer) &&
             sketch_append(sketch, options->garment_seams) && sketch_append_welded(sketch, prepared, mesh);
    pz_sketch_free(&designer);
    if (!ok) {
        pz_sketch_free(&sketch);
        return pz_error(ctx, PZ_ERR_NOMEM, "run: out of memory gathering sketches");
    }
    if (sketch->curve_count == 0)
        pz_sketch_free(&sketch);
    *out = sketch;
    return PZ_OK;
}

/* ---------------------------------------------------------------- symmetry of the strokes */

/* The most points a sketch is sampled at to compare it with its mirror image: the cost stays bounded whatever
 * the file (1000 curves of any length). */
#define MIRROR_SAMPLES_MAX 20000
/* A stroke is its own or another stroke's mirror image when this share of its samples, mirrored, lies within
 * the tolerance of the sketch (the ends of hand-drawn strokes differ). */
#define MIRROR_SHARE 0.9

double pl_sketch_mirror_tolerance(const pz_mesh *mesh)
{
    double lo[3], hi[3];
    pz_mesh_bbox(mesh, lo, hi);
    double diagonal = pz_vec3_distance(lo, hi);
    /* Strokes snapped to vertices by hand or by a script zigzag by up to an edge either side: two edges apart is
     * still the same line on a coarse mesh. */
    double edge_sum = 0;
    for (int32_t f = 0; f < mesh->face_count; ++f)
        for (int k = 0; k < 3; ++k)
            edge_sum += pz_vec3_distance(mesh->positions + 3 * (size_t)mesh->faces[3 * (size_t)f + k],
                                         mesh->positions + 3 * (size_t)mesh->faces[3 * (size_t)f + (k + 1) % 3]);
    double mean_edge = mesh->face_count > 0 ? edge_sum / (3.0 * mesh->face_count) : 0;
    return fmax(fmax(PZ_SKETCH_TOLERANCE_REL * diagonal, 10.0), 2 * mean_edge);
}

typedef struct mirror_sample {
    int64_t cell;   /* the grid cell's key */
    double p[3];
    int32_t curve;
} mirror_sample;

/* The cell's three indices, 21 bits each (unsigned: no overflow), in one key. */
static int64_t cell_key(const double p[3], double cell)
{
    uint64_t key = 0;
    for (int d = 0; d < 3; ++d) {
        double c = floor(p[d] / cell);
        c = fmax(fmin(c, 1e6), -1e6); /* far points share the border cells: a slower search, never a wrong one */
        key = (key << 21) | (uint64_t)((int64_t)c + 1048576); /* 48,576 .. 2,048,576 < 2^21 */
    }
    return (int64_t)key; /* < 2^63 */
}

static int by_cell(const void *a, const void *b)
{
    int64_t x = ((const mirror_sample *)a)->cell, y = ((const mirror_sample *)b)->cell;
    return (x > y) - (x < y);
}

/* The sketch's samples about `step` apart (at most MIRROR_SAMPLES_MAX in all), sorted by cell; NULL when out of
 * memory. */
static mirror_sample *sample_sketch(const pz_sketch *sketch, double tolerance, int32_t *count)
{
    double length = 0;
    int32_t segments = 0;
    for (int32_t c = 0; c < sketch->curve_count; ++c)
        for (int32_t i = sketch->curve_offsets[c]; i + 1 < sketch->curve_offsets[c + 1]; ++i, ++segments)
            length += pz_vec3_distance(sketch->points + 3 * (size_t)i, sketch->points + 3 * (size_t)i + 3);
    double step = fmax(0.5 * tolerance, length / (MIRROR_SAMPLES_MAX - segments - 1 > 0 ? MIRROR_SAMPLES_MAX - segments - 1 : 1));
    size_t capacity = (size_t)(length / step) + (size_t)segments + 2;
    mirror_sample *samples = malloc(capacity * sizeof *samples);
    if (!samples)
        return NULL;
    size_t n = 0;
    for (int32_t c = 0; c < sketch->curve_count; ++c)
        for (int32_t i = sketch->curve_offsets[c]; i + 1 < sketch->curve_offsets[c + 1]; ++i) {
            const double *a = sketch->points + 3 * (size_t)i, *b = a + 3;
            int32_t pieces = (int32_t)fmin(ceil(pz_vec3_distance(a, b) / step), 1e6);
            if (pieces < 1)
                pieces = 1;
            for (int32_t k = 0; k < pieces && n < capacity; ++k, ++n) {
                double t = (double)k / pieces;
                for (int d = 0; d < 3; ++d)
                    samples[n].p[d] = a[d] + t * (b[d] - a[d]);
                samples[n].curve = c;
            }
        }
    for (size_t i = 0; i < n; ++i)
        samples[i].cell = cell_key(samples[i].p, tolerance);
    qsort(samples, n, sizeof *samples, by_cell);
    *count = (int32_t)n;
    return samples;
}

/* 1 when some sample lies within `tolerance` of p (the 27 cells around it). */
static int near_sample(const mirror_sample *samples, int32_t count, const double p[3], double tolerance)
{
    for (int dx = -1; dx <= 1; ++dx)
        for (int dy = -1; dy <= 1; ++dy)
            for (int dz = -1; dz <= 1; ++dz) {
                double q[3] = {p[0] + dx * tolerance, p[1] + dy * tolerance, p[2] + dz * tolerance};
                int64_t key = cell_key(q, tolerance);
                int32_t lo = 0, hi = count;
                while (lo < hi) { /* the first sample of the cell */
                    int32_t mid = lo + (hi - lo) / 2;
                    if (samples[mid].cell < key)
                        lo = mid + 1;
                    else
                        hi = mid;
                }
                for (int32_t i = lo; i < count && samples[i].cell == key; ++i)
                    if (pz_vec3_distance(samples[i].p, p) <= tolerance)
                        return 1;
            }
    return 0;
}

/* Per curve of the sketch: 1 when MIRROR_SHARE of its samples, mirrored, lie near the sketch (mirrored[c]). */
static int curves_mirrored(const pz_sketch *sketch, const pz_symmetry *plane, double tolerance, uint8_t *mirrored)
{
    int32_t count = 0;
    mirror_sample *samples = sample_sketch(sketch, tolerance, &count);
    int32_t *matched = calloc((size_t)sketch->curve_count + 1, sizeof(int32_t));
    int32_t *total = calloc((size_t)sketch->curve_count + 1, sizeof(int32_t));
    if (!samples || !matched || !total) {
        free(samples), free(matched), free(total);
        return 0;
    }
    for (int32_t i = 0; i < count; ++i) {
        double image[3];
        pz_symmetry_reflect_point(plane, samples[i].p, image);
        ++total[samples[i].curve];
        matched[samples[i].curve] += near_sample(samples, count, image, tolerance);
    }
    for (int32_t c = 0; c < sketch->curve_count; ++c)
        mirrored[c] = matched[c] >= MIRROR_SHARE * total[c];
    free(samples), free(matched), free(total);
    return 1;
}

pz_status pl_sketch_symmetric(const pz_sketch *sketch, const pz_symmetry *plane, double tolerance, int *symmetric,
                              pz_ctx *ctx)
{
    *symmetric = 1;
    if (!sketch || sketch->curve_count == 0 || !plane || !plane->found)
        return PZ_OK;
    uint8_t *mirrored = malloc((size_t)sketch->curve_count);
    if (!mirrored || !curves_mirrored(sketch, plane, tolerance, mirrored)) {
        free(mirrored);
        return pz_error(ctx, PZ_ERR_NOMEM, "run: out of memory comparing the sketch with its mirror image");
    }
    for (int32_t c = 0; c < sketch->curve_count; ++c)
        *symmetric &= mirrored[c];
    free(mirrored);
    return PZ_OK;
}

pz_status pl_sketch_symmetric_on(const pz_run_options *options, const pz_mesh *mesh, const pz_symmetry *plane,
                                 int *symmetric, pz_ctx *ctx)
{
    *symmetric = 1;
    pz_sketch *designer = NULL;
    pz_status status = pl_designer_sketch(options, mesh, &designer, ctx);
    if (status == PZ_OK)
        status = pl_sketch_symmetric(designer, plane, pl_sketch_mirror_tolerance(mesh), symmetric, ctx);
    pz_sketch_free(&designer);
    return status;
}

pz_status pl_sketch_add_mirrors(pz_sketch *sketch, const pz_symmetry *plane, double tolerance, pz_ctx *ctx)
{
    int32_t count = sketch->curve_count;
    uint8_t *mirrored = malloc((size_t)count + 1);
    if (!mirrored || !curves_mirrored(sketch, plane, tolerance, mirrored)) {
        free(mirrored);
        return pz_error(ctx, PZ_ERR_NOMEM, "run: out of memory mirroring the sketch");
    }
    int32_t added_curves = 0, added_points = 0;
    for (int32_t c = 0; c < count; ++c)
        if (!mirrored[c])
            ++added_curves, added_points += sketch->curve_offsets[c + 1] - sketch->curve_offsets[c];
    if (added_curves > 0 && !sketch_reserve(sketch, added_curves, added_points)) {
        free(mirrored);
        return pz_error(ctx, PZ_ERR_NOMEM, "run: out of memory mirroring the sketch");
    }
    for (int32_t c = 0; c < count; ++c) {
        if (mirrored[c])
            continue;
        int32_t at = sketch->curve_offsets[sketch->curve_count];
        for (int32_t i = sketch->curve_offsets[c]; i < sketch->curve_offsets[c + 1]; ++i, ++at)
            pz_symmetry_reflect_point(plane, sketch->points + 3 * (size_t)i, sketch->points + 3 * (size_t)at);
        sketch->curve_offsets[++sketch->curve_count] = at;
    }
    free(mirrored);
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

/*
 * field/sketch.c -- sketched curves (docs/field.md, "Sketches"): the JSON
 * reader (pz_sketch_parse, pz_sketch_read) and the snapping of the curves to
 * the mesh for the field's constraints. Polylines are sampled every quarter
 * mean edge; every sample is snapped to the closest point of the mesh
 * through a uniform grid of face bounding boxes (expanding shells of cells
 * until no closer face can exist), and its segment's tangent, projected into
 * the face found, is averaged per face as a 4th power weighted by the sample
 * length (field_sketch_accumulate).
 *
 * Separate from the field's solve (field/crossfield.c) because reading and
 * snapping curves is geometry of its own (a spatial grid, closest points on
 * triangles); it meets the solve only in the face frames of field/internal.h.
 *
 * SPDX-License-Identifier: GPL-3.0-or-later
 */
#include "field/internal.h"
#include "core/vec.h"
#include "core/util.h"

#include <cjson/cJSON.h>
#include <errno.h>
#include <math.h>
#include <stdlib.h>
#include <string.h>

/* ---------------------------------------------------------------- sketches */

void pz_sketch_free(pz_sketch **sketch)
{
    if (!sketch || !*sketch)
        return;
    free((*sketch)->curve_offsets);
    free((*sketch)->points);
    free(*sketch);
    *sketch = NULL;
}

/* Fills the sketch from the parsed JSON; returns an error message or NULL. */
static const char *sketch_from_json(const cJSON *root, double scale, pz_sketch *sketch)
{
    const cJSON *curves = cJSON_IsObject(root) ? cJSON_GetObjectItemCaseSensitive(root, "curves") : NULL;
    if (!cJSON_IsArray(curves))
        return "expected an object with a \"curves\" array";
    int32_t curve_count = cJSON_GetArraySize(curves), point_count = 0;
    const cJSON *curve, *point;
    cJSON_ArrayForEach(curve, curves) {
        if (!cJSON_IsArray(curve) || cJSON_GetArraySize(curve) < 2)
            return "every curve must be an array of at least 2 points";
        point_count += cJSON_GetArraySize(curve);
    }
    sketch->curve_offsets = malloc(((size_t)curve_count + 1) * sizeof *sketch->curve_offsets);
    sketch->points = malloc(((size_t)point_count + 1) * 3 * sizeof *sketch->points);
    if (!sketch->curve_offsets || !sketch->points)
        return "out of memory";
    int32_t c = 0, p = 0;
    sketch->curve_offsets[0] = 0;
    cJSON_ArrayForEach(curve, curves) {
        cJSON_ArrayForEach(point, curve) {
            if (!cJSON_IsArray(point) || cJSON_GetArraySize(point) != 3)
                return "every point must be an array [x, y, z]";
            for (int k = 0; k < 3; ++k) {
                const cJSON *x = cJSON_GetArrayItem(point, k);
                if (!cJSON_IsNumber(x) || !isfinite(x->valuedouble))
                    return "coordinates must be finite numbers";
                sketch->points[3 * (size_t)p + k] = x->valuedouble * scale;
            }
            ++p;
        }
        sketch->curve_offsets[++c] = p;
    }
    sketch->curve_count = curve_count;
    return NULL;
}

pz_status pz_sketch_parse(const char *text, size_t size, const char *name, double scale, pz_sketch **out,
                          pz_ctx *ctx)
{
    *out = NULL;
    cJSON *root = cJSON_ParseWithLength(text, size);
    if (!root)
        return pz_error(ctx, PZ_ERR_DATA, "%s: not valid JSON", name);
    pz_sketch *sketch = calloc(1, sizeof *sketch);
    const char *problem = sketch ? sketch_from_json(root, scale > 0.0 ? scale : 1.0, sketch) : "out of memory";
    cJSON_Delete(root);
    if (problem) {
        pz_sketch_free(&sketch);
        return pz_error(ctx, strcmp(problem, "out of memory") ? PZ_ERR_DATA : PZ_ERR_NOMEM, "%s: %s", name, problem);
    }
    *out = sketch;
    return PZ_OK;
}

pz_status pz_sketch_read(const char *path, double scale, pz_sketch **out, pz_ctx *ctx)
{
    *out = NULL;
    FILE *file = NULL;
    pz_status opened = pz_input_open(path, &file, ctx);
    if (opened != PZ_OK)
        return opened;
    char *text = NULL;
    size_t size = 0, capacity = 0;
    for (;;) {
        if (!pz_grow((void **)&text, &capacity, size + 65536, 1)) {
            free(text);
            fclose(file);
            return pz_error(ctx, PZ_ERR_NOMEM, "%s: out of memory", path);
        }
        size_t got = fread(text + size, 1, capacity - size, file);
        size += got;
        if (got == 0)
            break;
    }
    int failed = ferror(file);
    fclose(file);
    if (failed) {
        free(text);
        return pz_error(ctx, PZ_ERR_OPEN, "%s: read error", path);
    }
    pz_status status = pz_sketch_parse(text, size, path, scale, out, ctx);
    free(text);
    return status;
}

/* ---------------------------------------------------------------- a uniform grid of faces */

typedef struct face_grid {
    double lo[3], cell;
    int32_t dims[3];
    int32_t *offsets;  /* cells + 1 */
    int32_t *faces;
} face_grid;

static void grid_free(face_grid *grid)
{
    free(grid->offsets), free(grid->faces);
}

static int32_t grid_coord(const face_grid *grid, double x, int axis)
{
    double c = floor((x - grid->lo[axis]) / grid->cell);
    if (c < 0.0)
        return 0;
    if (c >= grid->dims[axis])
        return grid->dims[axis] - 1;
    return (int32_t)c;
}

static void face_cell_range(const face_grid *grid, const pz_mesh *mesh, int32_t f, int32_t lo[3], int32_t hi[3])
{
    for (int a = 0; a < 3; ++a) {
        double mn = HUGE_VAL, mx = -HUGE_VAL;
        for (int k = 0; k < 3; ++k) {
            double x = mesh->positions[3 * (size_t)mesh->faces[3 * (size_t)f + k] + a];
            mn = x < mn ? x : mn, mx = x > mx ? x : mx;
        }
        lo[a] = grid_coord(grid, mn, a), hi[a] = grid_coord(grid, mx, a);
    }
}

static size_t cell_index(const face_grid *grid, int32_t x, int32_t y, int32_t z)
{
    return ((size_t)z * grid->dims[1] + y) * grid->dims[0] + x;
}

/* Cells about two mean edges wide (coarser when that would exceed ~8 cells a face). */
static int grid_build(const pz_mesh *mesh, double mean_edge, face_grid *grid)
{
    double hi[3];
    pz_mesh_bbox(mesh, grid->lo, hi);
    grid->cell = mean_edge > 0.0 ? 2.0 * mean_edge : 1.0;
    for (;;) {
        double cells = 1.0;
        for (int a = 0; a < 3; ++a) {
            grid->dims[a] = (int32_t)fmin(floor((hi[a] - grid->lo[a]) / grid->cell) + 1.0, 1e6);
            cells *= grid->dims[a];
        }
        if (cells <= 8.0 * mesh->face_count + 64.0)
            break;
        grid->cell *= 1.5;
    }
    size_t cell_count = (size_t)grid->dims[0] * grid->dims[1] * grid->dims[2];
    grid->offsets = calloc(cell_count + 1, sizeof *grid->offsets);
    if (!grid->offsets)
        return 0;
    size_t total = 0;
    for (int pass = 0; pass < 2; ++pass) {
        for (int32_t f = 0; f < mesh->face_count; ++f) {
            int32_t lo[3], up[3];
            face_cell_range(grid, mesh, f, lo, up);
            for (int32_t z = lo[2]; z <= up[2]; ++z)
                for (int32_t y = lo[1]; y <= up[1]; ++y)
                    for (int32_t x = lo[0]; x <= up[0]; ++x) {
                        size_t c = cell_index(grid, x, y, z);
                        if (pass == 0)
                            ++grid->offsets[c + 1], ++total;
                        else
                            grid->faces[grid->offsets[c]++] = f;
                    }
        }
        if (pass == 0) {
            if (total > INT32_MAX)
                return 0;
            for (size_t c = 0; c < cell_count; ++c)
                grid->offsets[c + 1] += grid->offsets[c];
            grid->faces = malloc((total + 1) * sizeof *grid->faces);
            if (!grid->faces)
                return 0;
        }
    }
    /* The fill pass advanced every offset to the next cell's start: shift back. */
    for (size_t c = cell_count; c > 0; --c)
        grid->offsets[c] = grid->offsets[c - 1];
    grid->offsets[0] = 0;
    return 1;
}

/* Closest point of triangle (a, b, c) to p (Ericson, Real-Time Collision Detection, 5.1.5). */
static void closest_on_triangle(const double *p, const double *a, const double *b, const double *c, double *out)
{
    double ab[3], ac[3], ap[3], bp[3], cp[3];
    pz_vec3_sub(b, a, ab), pz_vec3_sub(c, a, ac), pz_vec3_sub(p, a, ap);
    double d1 = pz_vec3_dot(ab, ap), d2 = pz_vec3_dot(ac, ap);
    if (d1 <= 0.0 && d2 <= 0.0) {
        memcpy(out, a, 3 * sizeof *out);
        return;
    }
    pz_vec3_sub(p, b, bp);
    double d3 = pz_vec3_dot(ab, bp), d4 = pz_vec3_dot(ac, bp);
    if (d3 >= 0.0 && d4 <= d3) {
        memcpy(out, b, 3 * sizeof *out);
        return;
    }
    double vc = d1 * d4 - d3 * d2;
    if (vc <= 0.0 && d1 >= 0.0 && d3 <= 0.0) {
        double v = d1 / (d1 - d3);
        for (int i = 0; i < 3; ++i) out[i] = a[i] + v * ab[i];
        return;
    }
    pz_vec3_sub(p, c, cp);
    double d5 = pz_vec3_dot(ab, cp), d6 = pz_vec3_dot(ac, cp);
    if (d6 >= 0.0 && d5 <= d6) {
        memcpy(out, c, 3 * sizeof *out);
        return;
    }
    double vb = d5 * d2 - d1 * d6;
    if (vb <= 0.0 && d2 >= 0.0 && d6 <= 0.0) {
        double w = d2 / (d2 - d6);
        for (int i = 0; i < 3; ++i) out[i] = a[i] + w * ac[i];
        return;
    }
    double va = d3 * d6 - d5 * d4;
    if (va <= 0.0 && (d4 - d3) >= 0.0 && (d5 - d6) >= 0.0) {
        double w = (d4 - d3) / ((d4 - d3) + (d5 - d6));
        for (int i = 0; i < 3; ++i) out[i] = b[i] + w * (c[i] - b[i]);
        return;
    }
    double denom = 1.0 / (va + vb + vc), v = vb * denom, w = vc * denom;
    for (int i = 0; i < 3; ++i) out[i] = a[i] + ab[i] * v + ac[i] * w;
}

static double face_distance2(const pz_mesh *mesh, int32_t f, const double *p)
{
    const int32_t *face = mesh->faces + 3 * (size_t)f;
    double q[3], d[3];
    closest_on_triangle(p, mesh->positions + 3 * (size_t)face[0], mesh->positions + 3 * (size_t)face[1],
                        mesh->positions + 3 * (size_t)face[2], q);
    pz_vec3_sub(p, q, d);
    return pz_vec3_dot(d, d);
}

/* The face closest to p: shells of cells around p's cell, stopping once the
 * next shell (at least shell * cell away) cannot hold anything closer. */
static int32_t grid_closest_face(const face_grid *grid, const pz_mesh *mesh, const double *p)
{
    int32_t center[3] = {grid_coord(grid, p[0], 0), grid_coord(grid, p[1], 1), grid_coord(grid, p[2], 2)};
    int32_t max_dim = grid->dims[0] > grid->dims[1] ? grid->dims[0] : grid->dims[1];
    max_dim = max_dim > grid->dims[2] ? max_dim : grid->dims[2];
    int32_t best = -1;
    double best_d2 = HUGE_VAL;
    for (int32_t shell = 0; shell <= max_dim; ++shell) {
        for (int32_t z = center[2] - shell; z <= center[2] + shell; ++z) {
            if (z < 0 || z >= grid->dims[2]) continue;
            for (int32_t y = center[1] - shell; y <= center[1] + shell; ++y) {
                if (y < 0 || y >= grid->dims[1]) continue;
                int on_face = abs(z - center[2]) == shell || abs(y - center[1]) == shell;
                for (int32_t x = center[0] - shell; x <= center[0] + shell; x += (on_face ? 1 : 2 * shell)) {
                    if (x >= 0 && x < grid->dims[0]) {
                        size_t c = cell_index(grid, x, y, z);
                        for (int32_t k = grid->offsets[c]; k < grid->offsets[c + 1]; ++k) {
                            double d2 = face_distance2(mesh, grid->faces[k], p);
                            if (d2 < best_d2 || (d2 == best_d2 && grid->faces[k] < best))
                                best_d2 = d2, best = grid->faces[k];
                        }
                    }
                    if (shell == 0)
                        break;
                }
            }
        }
        if (best >= 0 && sqrt(best_d2) <= shell * grid->cell)
            break;
    }
    return best;
}

/* Per-face 4th-power sums of the sketch tangents (re, im: face_count each). */
int field_sketch_accumulate(const pz_mesh *mesh, const field_frames *fr, const pz_sketch *sketch, double mean_edge,
                             double *re, double *im)
{
    face_grid grid = {{0, 0, 0}, 0, {0, 0, 0}, NULL, NULL};
    if (!grid_build(mesh, mean_edge, &grid)) {
        grid_free(&grid);
        return 0;
    }
    double step = 0.25 * (mean_edge > 0.0 ? mean_edge : 1.0);
    for (int32_t c = 0; c < sketch->curve_count; ++c)
        for (int32_t i = sketch->curve_offsets[c]; i + 1 < sketch->curve_offsets[c + 1]; ++i) {
            const double *a = sketch->points + 3 * (size_t)i, *b = a + 3;
            double tangent[3];
            pz_vec3_sub(b, a, tangent);
            double length = pz_vec3_normalize(tangent);
            if (length == 0.0)
                continue;
            double samples = ceil(length / step);
            if (samples > 1e7)
                samples = 1e7;
            for (int32_t k = 0; k < (int32_t)samples; ++k) {
                double t = (k + 0.5) / samples, p[3];
                for (int j = 0; j < 3; ++j)
                    p[j] = a[j] + t * (b[j] - a[j]);
                int32_t f = grid_closest_face(&grid, mesh, p);
                if (f < 0)
                    continue;
                double x = pz_vec3_dot(tangent, fr->e1 + 3 * (size_t)f), y = pz_vec3_dot(tangent, fr->e2 + 3 * (size_t)f);
                double weight = length / samples * hypot(x, y), angle = atan2(y, x);
                re[f] += weight * cos(4.0 * angle);
                im[f] += weight * sin(4.0 * angle);
            }
        }
    grid_free(&grid);
    return 1;
}

/* ---------------------------------------------------------------- the sketch lies on the garment */

/* Mean edge length over the faces' edges (each interior edge counted twice: a scale, not a statistic). */
static double mean_face_edge(const pz_mesh *mesh)
{
    double sum = 0.0;
    for (int32_t f = 0; f < mesh->face_count; ++f)
        for (int k = 0; k < 3; ++k)
            sum += pz_vec3_distance(mesh->positions + 3 * (size_t)mesh->faces[3 * (size_t)f + k],
                                    mesh->positions + 3 * (size_t)mesh->faces[3 * (size_t)f + (k + 1) % 3]);
    return mesh->face_count > 0 ? sum / (3.0 * mesh->face_count) : 0.0;
}

double pz_sketch_tolerance(const pz_mesh *mesh)
{
    double lo[3], hi[3];
    pz_mesh_bbox(mesh, lo, hi);
    return fmax(PZ_SKETCH_TOLERANCE_MM, PZ_SKETCH_TOLERANCE_REL * pz_vec3_distance(lo, hi));
}

pz_status pz_sketch_check(const pz_sketch *sketch, const pz_mesh *mesh, const char *name, pz_ctx *ctx)
{
    if (!sketch || sketch->curve_count == 0)
        return PZ_OK;
    name = name ? name : "sketch";
    double tolerance = pz_sketch_tolerance(mesh), lo[3], hi[3];
    pz_mesh_bbox(mesh, lo, hi);
    face_grid grid = {{0, 0, 0}, 0, {0, 0, 0}, NULL, NULL};
    if (!grid_build(mesh, mean_face_edge(mesh), &grid)) {
        grid_free(&grid);
        return pz_error(ctx, PZ_ERR_NOMEM, "%s: out of memory checking the sketch", name);
    }
    pz_status status = PZ_OK;
    for (int32_t c = 0; c < sketch->curve_count && status == PZ_OK; ++c)
        for (int32_t i = sketch->curve_offsets[c]; i < sketch->curve_offsets[c + 1] && status == PZ_OK; ++i) {
            const double *p = sketch->points + 3 * (size_t)i;
            /* The box first: a point far off costs nothing, and the grid never scans for it. */
            double outside[3];
            for (int k = 0; k < 3; ++k)
                outside[k] = fmax(0.0, fmax(lo[k] - p[k], p[k] - hi[k]));
            double distance = pz_vec3_norm(outside);
            if (distance <= tolerance) {
                int32_t f = grid_closest_face(&grid, mesh, p);
                distance = f >= 0 ? sqrt(face_distance2(mesh, f, p)) : HUGE_VAL;
            }
            if (!(distance <= tolerance))
                status = pz_error(ctx, PZ_ERR_DATA,
                                  "%s: curve %d point %d is %.4g mm from the garment's surface (at most %.1f mm): is "
                                  "the sketch in the garment's units and on this garment?",
                                  name, (int)c, (int)(i - sketch->curve_offsets[c]), distance, tolerance);
        }
    grid_free(&grid);
    return status;
}

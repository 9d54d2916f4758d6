/*
 * tests/param/textile_fixtures.h -- what the two textile test programs
 * (test_textile.c: generated shapes; test_textile_garments.c: the shared
 * real garments) share: a pattern built by hand (one panel = all faces, so
 * the tests do not depend on pz_pattern_build), the flattening call, flipped
 * faces, thread strain, the energy trace of on_iteration, seam lengths and
 * reflection residuals. Defines the programs' context `ctx` (quiet, set up in
 * main).
 *
 * SPDX-License-Identifier: GPL-3.0-or-later
 */
#ifndef PZ_TEST_TEXTILE_FIXTURES_H
#define PZ_TEST_TEXTILE_FIXTURES_H

#include "generate/generate.h"
#include "io/io.h"
#include "param/param.h"
#include "test_meshes.h"

#include <math.h>
#include <stdlib.h>
#include <string.h>

static pz_ctx ctx;

/* A pattern owning `mesh`: one panel per component id given (NULL = all 0). */
static inline pz_pattern *pattern_of(pz_mesh *mesh, const int32_t *face_panel, int32_t panel_count)
{
    pz_pattern *pattern = calloc(1, sizeof *pattern);
    REQUIRE(pattern, "out of memory");
    pattern->mesh = mesh;
    pattern->panel_count = panel_count;
    pattern->vertex_origin = malloc((size_t)mesh->vertex_count * sizeof(int32_t));
    pattern->face_panel = calloc((size_t)mesh->face_count, sizeof(int32_t));
    REQUIRE(pattern->vertex_origin && pattern->face_panel, "out of memory");
    for (int32_t v = 0; v < mesh->vertex_count; ++v)
        pattern->vertex_origin[v] = v;
    if (face_panel)
        memcpy(pattern->face_panel, face_panel, (size_t)mesh->face_count * sizeof(int32_t));
    return pattern;
}

static inline void pattern_release(pz_pattern *pattern)
{
    for (int32_t s = 0; s < pattern->seam_count; ++s) {
        free(pattern->seams[s].side_a);
        free(pattern->seams[s].side_b);
    }
    for (int32_t d = 0; d < pattern->dart_count; ++d) {
        free(pattern->darts[d].leg_a);
        free(pattern->darts[d].leg_b);
    }
    free(pattern->seams);
    free(pattern->darts);
    free(pattern->face_panel);
    free(pattern->vertex_origin);
    pz_mesh_free(&pattern->mesh);
    free(pattern);
}

static inline double *flatten(const pz_pattern *pattern, const pz_textile_options *options, pz_textile_result *result)
{
    double *uv = malloc((size_t)pattern->mesh->vertex_count * 2 * sizeof(double));
    REQUIRE(uv, "out of memory");
    REQUIRE_OK(pz_param_textile(pattern, options, uv, result, &ctx), ctx);
    return uv;
}

static inline double signed_area2(const double *uv, const int32_t *face)
{
    const double *a = uv + 2 * face[0], *b = uv + 2 * face[1], *c = uv + 2 * face[2];
    return 0.5 * ((b[0] - a[0]) * (c[1] - a[1]) - (b[1] - a[1]) * (c[0] - a[0]));
}

static inline int count_flipped(const pz_mesh *mesh, const double *uv)
{
    int flipped = 0;
    for (int32_t f = 0; f < mesh->face_count; ++f)
        flipped += signed_area2(uv, mesh->faces + 3 * f) <= 0;
    return flipped;
}

/* The 3D images of the unit 2D axes on face f: J e_u and J e_v (Eq. 1). */
static inline void tangents(const double *positions, const int32_t *face, const double *uv, double ju[3], double jv[3])
{
    double twice = 2 * signed_area2(uv, face);
    for (int d = 0; d < 3; ++d)
        ju[d] = jv[d] = 0;
    for (int i = 0; i < 3; ++i) {
        int j = (i + 1) % 3, k = (i + 2) % 3;
        double cu = (uv[2 * face[j] + 1] - uv[2 * face[k] + 1]) / twice;
        double cv = (uv[2 * face[k]] - uv[2 * face[j]]) / twice;
        for (int d = 0; d < 3; ++d) {
            ju[d] += cu * positions[3 * face[i] + d];
            jv[d] += cv * positions[3 * face[i] + d];
        }
    }
}

/* Area-weighted RMS of the warp and weft strain (|J_1| - 1, |J_2| - 1) and
 * its maximum, for one set of 3D positions. */
static inline double rms_strain(const pz_mesh *mesh, const double *positions, const double *uv, double *max_strain)
{
    double sum = 0, area_sum = 0;
    *max_strain = 0;
    for (int32_t f = 0; f < mesh->face_count; ++f) {
        const int32_t *face = mesh->faces + 3 * f;
        double ju[3], jv[3];
        tangents(positions, face, uv, ju, jv);
        double su = sqrt(ju[0] * ju[0] + ju[1] * ju[1] + ju[2] * ju[2]) - 1;
        double sv = sqrt(jv[0] * jv[0] + jv[1] * jv[1] + jv[2] * jv[2]) - 1;
        double area = fabs(signed_area2(uv, face));
        sum += area * (su * su + sv * sv) / 2;
        area_sum += area;
        *max_strain = fmax(*max_strain, fmax(fabs(su), fabs(sv)));
    }
    return sqrt(sum / area_sum);
}

/* Energies reported through on_iteration must not increase. */
typedef struct energy_trace {
    int count, increases;
    double last, first;
} energy_trace;

static inline void record_energy(void *user, int iteration, double energy)
{
    energy_trace *trace = user;
    if (iteration == 0)
        trace->first = energy;
    else if (energy > trace->last * (1 + 1e-9))
        ++trace->increases;
    trace->last = energy;
    ++trace->count;
}

/* 20 steps asked and no stop on the tolerance (as bench_param runs them). */
static inline double *twenty_steps(const pz_pattern *pattern, const char *label, pz_textile_result *result)
{
    pz_textile_options options = {.iterations = 20, .tolerance = 1e-300};
    double *uv = flatten(pattern, &options, result);
    printf("%s, 20 steps: energy %.4g -> %.4g, %d iterations, %d bounded, %d damped, %d flipped\n", label,
           result->initial_energy, result->final_energy, result->iterations_run, result->bounded_steps,
           result->damped_steps, count_flipped(pattern->mesh, uv));
    return uv;
}

static inline double polyline_length(const double *uv, const int32_t *ids, int32_t count)
{
    double length = 0;
    for (int32_t i = 1; i < count; ++i)
        length += hypot(uv[2 * ids[i]] - uv[2 * ids[i - 1]], uv[2 * ids[i] + 1] - uv[2 * ids[i - 1] + 1]);
    return length;
}

/* RMS distance after the best-fit reflection of side a onto side b. */
static inline double reflection_residual(const double *uv, const pz_seam *seam)
{
    int32_t n = seam->pair_count;
    double ca[2] = {0, 0}, cb[2] = {0, 0};
    for (int32_t i = 0; i < n; ++i)
        for (int k = 0; k < 2; ++k) {
            ca[k] += uv[2 * seam->side_a[i] + k] / n;
            cb[k] += uv[2 * seam->side_b[i] + k] / n;
        }
    double s00 = 0, s01 = 0, s10 = 0, s11 = 0;
    for (int32_t i = 0; i < n; ++i) {
        double px = uv[2 * seam->side_a[i]] - ca[0], py = uv[2 * seam->side_a[i] + 1] - ca[1];
        double qx = uv[2 * seam->side_b[i]] - cb[0], qy = uv[2 * seam->side_b[i] + 1] - cb[1];
        s00 += qx * px;
        s01 += qx * py;
        s10 += qy * px;
        s11 += qy * py;
    }
    double c = s00 - s11, s = s01 + s10, norm = hypot(c, s);
    c /= norm;
    s /= norm;
    double sum = 0;
    for (int32_t i = 0; i < n; ++i) {
        double px = uv[2 * seam->side_a[i]] - ca[0], py = uv[2 * seam->side_a[i] + 1] - ca[1];
        double qx = uv[2 * seam->side_b[i]] - cb[0], qy = uv[2 * seam->side_b[i] + 1] - cb[1];
        double dx = c * px + s * py - qx, dy = s * px - c * py - qy;
        sum += dx * dx + dy * dy;
    }
    return sqrt(sum / n);
}

#endif

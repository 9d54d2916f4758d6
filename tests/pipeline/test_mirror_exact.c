/*
 * tests/pipeline/test_mirror_exact.c -- the garment made exactly symmetric
 * before the layout (docs/segment.md, "The symmetrized garment"):
 *  - pz_prepare_symmetrize on a nearly symmetric generated bodice (one side
 *    1.5 % wider and rippled): a valid manifold, vertex_mirror a bijection
 *    that is its own inverse, each vertex's mirror at its exact reflection,
 *    plane vertices on the plane, face_mirror an involution, and the input's
 *    distance to it measured (not zero, within the perturbation);
 *  - pz_run on that bodice, also turned about its vertical axis (an oblique
 *    plane): it lays out the symmetric garment, and every mirror pair and
 *    every piece crossed by the plane is exact (outline residual < 0.1 mm),
 *    every one of them counted exact;
 *  - with --symmetry off the garment stays the input's, vertex for vertex.
 *
 * SPDX-License-Identifier: GPL-3.0-or-later
 */
#define _POSIX_C_SOURCE 200809L
#include "generate/generate.h"
#include "pipeline/pipeline.h"
#include "prepare/prepare.h"

#include "test_util.h"

#include <math.h>
#include <stdlib.h>
#include <string.h>

#define WIDER 1.015        /* the +x side this much wider */
#define RIPPLE_MM 2.0      /* and rippled this much along y */

/* The generated bodice (z up, plane x = 0) made nearly symmetric: its +x side wider and rippled, then turned by
 * `degrees` about z (the plane's normal then (cos, sin, 0)). */
static pz_mesh *near_bodice(double degrees)
{
    pz_ctx ctx = {0};
    pz_generate_options options = {.target_faces = 3000};
    pz_mesh *mesh = NULL;
    REQUIRE_OK(pz_generate(PZ_SHAPE_BODICE, &options, &mesh, &ctx), ctx);
    double c = cos(degrees * 3.14159265358979323846 / 180), s = sin(degrees * 3.14159265358979323846 / 180);
    for (int32_t v = 0; v < mesh->vertex_count; ++v) {
        double *p = mesh->positions + 3 * (size_t)v;
        if (p[0] > 0) {
            p[0] *= WIDER;
            p[1] += RIPPLE_MM * sin(p[2] / 40.0) * fmin(1.0, p[0] / 50.0);
        }
        double x = c * p[0] - s * p[1], y = s * p[0] + c * p[1];
        p[0] = x, p[1] = y;
    }
    return mesh;
}

static void test_symmetrize(void)
{
    pz_ctx ctx = {0};
    pz_mesh *mesh = near_bodice(0);
    double normal[3] = {1, 0, 0};
    pz_symmetrized s;
    REQUIRE_OK(pz_prepare_symmetrize(mesh, normal, 0.0, &s, &ctx), ctx);
    const pz_mesh *out = s.mesh;
    pz_validation validation;
    REQUIRE_OK(pz_mesh_validate(out, &validation, &ctx), ctx);
    CHECK(pz_validation_ok(&validation), "the symmetric bodice is not a valid manifold");
    pz_validation_clear(&validation);
    int32_t on_plane = 0, bad_map = 0, far = 0;
    double worst = 0;
    for (int32_t v = 0; v < out->vertex_count; ++v) {
        int32_t m = s.vertex_mirror[v];
        if (m < 0 || m >= out->vertex_count || s.vertex_mirror[m] != v) {
            ++bad_map;
            continue;
        }
        const double *p = out->positions + 3 * (size_t)v, *q = out->positions + 3 * (size_t)m;
        worst = fmax(worst, fabs(p[0] + q[0]) + fabs(p[1] - q[1]) + fabs(p[2] - q[2]));
        on_plane += m == v;
        far += m == v && fabs(p[0]) > 1e-9;
    }
    CHECK(bad_map == 0, "%d vertices without a mirror that maps back", (int)bad_map);
    CHECK(worst < 1e-9, "a vertex and its mirror are %g mm off each other's reflection", worst);
    CHECK(on_plane > 20 && far == 0, "%d vertices on the plane, %d of them off it", (int)on_plane, (int)far);
    int32_t bad_faces = 0;
    for (int32_t f = 0; f < out->face_count; ++f) {
        int32_t g = s.face_mirror[f];
        bad_faces += g < 0 || g >= out->face_count || s.face_mirror[g] != f;
        for (int k = 0; g >= 0 && g < out->face_count && k < 3; ++k) { /* its corners' mirrors are g's corners */
            int32_t m = s.vertex_mirror[out->faces[3 * (size_t)f + k]];
            bad_faces += m != out->faces[3 * (size_t)g] && m != out->faces[3 * (size_t)g + 1] &&
                         m != out->faces[3 * (size_t)g + 2];
        }
    }
    CHECK(bad_faces == 0, "%d faces whose mirror face is not their reflection", (int)bad_faces);
    /* The +x side was 1.5 % wider: up to ~4 mm at the bodice's half width, and rippled by 2 mm. */
    CHECK(s.deviation_max_mm > 0.5 && s.deviation_max_mm < 15, "the input is %g mm from the symmetric bodice",
          s.deviation_max_mm);
    CHECK(s.deviation_p95_mm <= s.deviation_max_mm, "p95 %g above the largest %g", s.deviation_p95_mm,
          s.deviation_max_mm);
    pz_symmetrized_clear(&s);
    pz_mesh_free(&mesh);
}

static void check_exact_run(double degrees)
{
    pz_ctx ctx = {0};
    ctx.quiet = 1;
    pz_mesh *mesh = near_bodice(degrees);
    pz_run_options options;
    pz_run_options_default(&options);
    options.goals.max_strain = 0.06; /* the bodice's mirrored layout is kept at 0.06 (tests/pipeline/test_run.c) */
    pz_result *result = NULL;
    REQUIRE_OK(pz_run(mesh, &options, &result, &ctx), ctx);
    CHECK(result->symmetry.found, "%g degrees: no plane found", degrees);
    CHECK(result->symmetrized && result->symmetry_used, "%g degrees: the symmetric bodice was not laid out (used %d)",
          degrees, result->symmetry_used);
    CHECK(result->garment->vertex_count != mesh->vertex_count, "%g degrees: garment.obj is the input, not the "
          "symmetric bodice", degrees);
    CHECK(result->symmetrized_max_mm > 0 && result->symmetrized_p95_mm >= 0, "%g degrees: deviation %g / %g", degrees,
          result->symmetrized_max_mm, result->symmetrized_p95_mm);
    int32_t mirrored = 0;
    for (int32_t p = 0; result->panel_mirror && p < result->pattern->panel_count; ++p) {
        if (result->panel_mirror[p] < 0)
            continue;
        ++mirrored;
        double residual = result->panel_mirror_residual_mm ? result->panel_mirror_residual_mm[p] : -1;
        CHECK(residual >= 0 && residual < 0.1, "%g degrees: panel %d and its mirror %d differ by %g mm", degrees,
              (int)p, (int)result->panel_mirror[p], residual);
    }
    CHECK(mirrored >= 2, "%g degrees: %d panels with a mirror image", degrees, (int)mirrored);
    CHECK(result->mirror_pieces > 0 && result->exact_mirror_pieces == result->mirror_pieces,
          "%g degrees: %d of %d mirror pieces exact", degrees, (int)result->exact_mirror_pieces,
          (int)result->mirror_pieces);
    CHECK(result->pattern_mirror_max_mm >= 0 && result->pattern_mirror_max_mm < 0.1,
          "%g degrees: pattern residual %g mm", degrees, result->pattern_mirror_max_mm);
    pz_result_free(&result);
    pz_mesh_free(&mesh);
}

static void test_run_exact(void)
{
    check_exact_run(0);
    check_exact_run(20); /* an oblique plane */
}

static void test_symmetry_off(void)
{
    pz_ctx ctx = {0};
    ctx.quiet = 1;
    pz_mesh *mesh = near_bodice(0);
    pz_run_options options;
    pz_run_options_default(&options);
    options.segment.symmetry = PZ_SYMMETRY_OFF;
    pz_result *result = NULL;
    REQUIRE_OK(pz_run(mesh, &options, &result, &ctx), ctx);
    CHECK(!result->symmetrized && result->symmetrized_max_mm == -1, "--symmetry off symmetrized the garment");
    CHECK(result->garment->vertex_count == mesh->vertex_count && result->garment->face_count == mesh->face_count,
          "--symmetry off changed the garment");
    pz_result_free(&result);
    pz_mesh_free(&mesh);
}

int main(void)
{
    test_symmetrize();
    test_run_exact();
    test_symmetry_off();
    return test_finish();
}

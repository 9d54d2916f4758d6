/*
 * tests/param/wirewarp_fixtures.h -- what the two WireWarping test programs
 * (test_wirewarp.c: wires, feature and key curves, bad input;
 * test_wirewarp_symmetry.c: mirror symmetry) share: generated shapes, a
 * pattern built by pz_pattern_build, one warp with its E_len and E_ang
 * measured by pz_metrics_compute, and the printed figures. Defines the
 * programs' context `ctx` (quiet, set up in main).
 *
 * SPDX-License-Identifier: GPL-3.0-or-later
 */
#ifndef PZ_TEST_WIREWARP_FIXTURES_H
#define PZ_TEST_WIREWARP_FIXTURES_H

#include "generate/generate.h"
#include "io/io.h"
#include "param/param.h"
#include "test_meshes.h"

#include <math.h>
#include <stdlib.h>
#include <string.h>

static pz_ctx ctx;

static inline pz_mesh *generate(pz_shape shape, int32_t faces, int open)
{
    pz_generate_options options = {.target_faces = faces, .open = open};
    pz_mesh *mesh = NULL;
    REQUIRE_OK(pz_generate(shape, &options, &mesh, &ctx), ctx);
    return mesh;
}

/* A pattern of a garment mesh with the given panel per face (NULL: one panel). */
static inline pz_pattern *pattern_from(const pz_mesh *garment, const int32_t *face_panel)
{
    int32_t *panels = calloc((size_t)garment->face_count, sizeof(int32_t));
    REQUIRE(panels, "out of memory");
    if (face_panel)
        memcpy(panels, face_panel, (size_t)garment->face_count * sizeof(int32_t));
    pz_pattern *pattern = NULL;
    REQUIRE_OK(pz_pattern_build(garment, panels, NULL, NULL, "test", &pattern, &ctx), ctx);
    free(panels);
    return pattern;
}

typedef struct warp_figures {
    pz_wirewarp_result result;
    double e_len, e_ang;    /* worst over panels, from pz_metrics_compute */
} warp_figures;

static inline warp_figures warp(const pz_pattern *pattern, int scheme, const pz_feature_curves *features, double **uv_out)
{
    warp_figures figures;
    memset(&figures, 0, sizeof figures);
    double *uv = malloc((size_t)pattern->mesh->vertex_count * 2 * sizeof(double));
    REQUIRE(uv, "out of memory");
    pz_wirewarp_options options = {.scheme = scheme};
    REQUIRE_OK(pz_param_wirewarp(pattern, &options, features, uv, &figures.result, &ctx), ctx);
    pz_metrics *metrics = NULL;
    REQUIRE_OK(pz_metrics_compute(pattern, uv, 0, NULL, &metrics, &ctx), ctx);
    for (int32_t p = 0; p < metrics->panel_count; ++p) {
        figures.e_len = fmax(figures.e_len, metrics->panels[p].e_len);
        figures.e_ang = fmax(figures.e_ang, metrics->panels[p].e_ang);
    }
    pz_metrics_free(&metrics);
    if (uv_out)
        *uv_out = uv;
    else
        free(uv);
    return figures;
}

static inline void print_figures(const char *what, const warp_figures *f)
{
    const pz_wirewarp_result *r = &f->result;
    printf("%s: %d patches, %d nodes, %d wire edges, %d iterations, residual %.2g, max wire error %.2g, "
           "E_len %.2g, E_ang %.4g, flipped %d, best effort %d\n",
           what, r->wire_patch_count, r->wire_node_count, r->wire_edge_count, r->iterations, r->constraint_residual,
           r->max_wire_error, f->e_len, f->e_ang, r->flipped_triangles, r->best_effort);
}

#endif

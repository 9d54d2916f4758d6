/*
 * bench/bench_export.c -- speed of the export stage's pieces and writers.
 *
 * A generated bodice of about 50K faces (the benchmark garment) is cut
 * into four panels (quarters around its vertical axis: long, jagged seams,
 * the hard case for the cut-line offset) and flattened with LSCM (not
 * timed). Then, best of REPEAT runs each:
 *   pieces  pz_pieces_build (outlines, allowances, cut lines, notches)
 *   svg     pz_export_write_svg into a temporary file
 *   dxf     pz_export_write_dxf into a temporary file
 * and prints one line:
 *   bench_export faces=... pieces=... sew_points=... cut_points=... notches=...
 *                pieces_ms=... svg_ms=... dxf_ms=... total_ms=... load=...
 * The goal is all formats (with PDF, GLB, marker, HTML by the
 * other writers) under 1 s; load is the 1-minute load average: with 2 cores,
 * figures taken at a load above 1 are not comparable.
 * Usage: bench_export [FACES] [REPEAT] (defaults 50000, 5).
 *
 * SPDX-License-Identifier: GPL-3.0-or-later
 */
#define _POSIX_C_SOURCE 200809L
#include "export/export.h"

#include <float.h>
#include <math.h>
#include <stdio.h>
#include <stdlib.h>

#include "bench_util.h"

static int fail(const char *what, const pz_ctx *ctx)
{
    fprintf(stderr, "bench_export: %s: %s\n", what, ctx->error);
    return 1;
}

/* Quarters around the vertical axis through the centroid. */
static void quarters(const pz_mesh *mesh, int32_t *face_panel)
{
    double up[3], centre[3] = {0, 0, 0};
    pz_mesh_vertical_axis(mesh, up);
    int first = 0, second = fabs(up[1]) > fabs(up[2]) ? 2 : 1;
    for (int32_t v = 0; v < mesh->vertex_count; ++v)
        for (int k = 0; k < 3; ++k)
            centre[k] += mesh->positions[3 * v + k] / mesh->vertex_count;
    for (int32_t f = 0; f < mesh->face_count; ++f) {
        double c[3] = {0, 0, 0};
        for (int k = 0; k < 3; ++k)
            for (int d = 0; d < 3; ++d)
                c[d] += mesh->positions[3 * mesh->faces[3 * f + k] + d] / 3;
        face_panel[f] = (c[first] >= centre[first]) + 2 * (c[second] >= centre[second]);
    }
}

static double time_writer(pz_export_writer writer, const pz_export_inputs *inputs, const char *name, int repeat,
                          pz_ctx *ctx, pz_status *status)
{
    double best = DBL_MAX;
    for (int r = 0; r < repeat && *status == PZ_OK; ++r) {
        FILE *file = tmpfile();
        if (!file) {
            *status = pz_error(ctx, PZ_ERR_CREATE, "%s: no temporary file", name);
            break;
        }
        double start = pz_seconds();
        *status = writer(file, inputs, name, ctx);
        fflush(file);
        best = fmin(best, 1000 * (pz_seconds() - start));
        fclose(file);
    }
    return best;
}

int main(int argc, char **argv)
{
    int32_t faces = argc > 1 ? (int32_t)atol(argv[1]) : 50000;
    int repeat = argc > 2 ? atoi(argv[2]) : 5;
    if (repeat < 1)
        repeat = 1;
    pz_ctx ctx = {0};
    pz_generate_options generate = {.target_faces = faces};
    pz_mesh *garment = NULL;
    pz_pattern *pattern = NULL;
    if (pz_generate(PZ_SHAPE_BODICE, &generate, &garment, &ctx) != PZ_OK)
        return fail("generate", &ctx);
    int32_t *face_panel = malloc((size_t)garment->face_count * sizeof(int32_t));
    if (!face_panel)
        return 1;
    quarters(garment, face_panel);
    pz_status status = pz_pattern_build(garment, face_panel, NULL, NULL, "bodice", &pattern, &ctx);
    free(face_panel);
    if (status != PZ_OK)
        return fail("pattern", &ctx);
    double *uv = malloc(2 * (size_t)pattern->mesh->vertex_count * sizeof(double));
    if (!uv || pz_param_lscm_pattern(pattern, NULL, uv, &ctx) != PZ_OK)
        return fail("flatten", &ctx);

    pz_export_options options;
    pz_export_options_default(&options);
    options.garment_name = "bodice";
    pz_pieces *pieces = NULL;
    double pieces_ms = DBL_MAX;
    for (int r = 0; r < repeat; ++r) {
        pz_pieces_free(&pieces);
        double start = pz_seconds();
        if (pz_pieces_build(pattern, uv, &options, NULL, NULL, &pieces, &ctx) != PZ_OK)
            return fail("pieces", &ctx);
        pieces_ms = fmin(pieces_ms, 1000 * (pz_seconds() - start));
    }
    pz_export_inputs inputs = {.garment = garment, .pattern = pattern, .uv = uv, .pieces = pieces, .options = &options};
    double svg_ms = time_writer(pz_export_write_svg, &inputs, "pattern.svg", repeat, &ctx, &status);
    double dxf_ms = time_writer(pz_export_write_dxf, &inputs, "pattern.dxf", repeat, &ctx, &status);
    if (status != PZ_OK)
        return fail("write", &ctx);
    long sew = 0, cut = 0, notches = 0;
    for (int32_t p = 0; p < pieces->piece_count; ++p) {
        sew += pieces->pieces[p].sew_count;
        cut += pieces->pieces[p].cut_count;
        notches += pieces->pieces[p].notch_count;
    }
    printf("bench_export faces=%d pieces=%d sew_points=%ld cut_points=%ld notches=%ld pieces_ms=%.2f svg_ms=%.2f "
           "dxf_ms=%.2f total_ms=%.2f load=%.2f\n",
           (int)garment->face_count, (int)pieces->piece_count, sew, cut, notches, pieces_ms, svg_ms, dxf_ms,
           pieces_ms + svg_ms + dxf_ms, bench_load_average());
    pz_pieces_free(&pieces);
    free(uv);
    pz_pattern_free(&pattern);
    pz_mesh_free(&garment);
    return 0;
}

/*
 * bench/bench_export.c -- speed of the whole export stage: the pieces, the
 * marker and every pattern file `panelize flatten` and `run` write
 * (pz_export_files: pattern.svg, pattern.dxf, pattern.pdf,
 * pattern-tiled.pdf, marker.svg, garment.glb, report.html).
 *
 * The benchmark pattern: a generated bodice of about 50K faces cut
 * into four panels (quarters around its vertical axis: long, jagged seams,
 * the hard case for the cut-line offset), flattened with LSCM (not timed).
 * Or, with `.obj` arguments, the patterns a `panelize run` or `flatten` wrote
 * (their garment.obj: panels and pattern from its vt), e.g. the 148 panels
 * of the wetsuit. Each step is run REPEAT times and the best is kept:
 *   pieces  pz_pieces_build (outlines, allowances, cut lines, notches)
 *   marker  pz_marker_build (nesting, docs/marker.md)
 *   FILE    the writer of FILE into a temporary file
 * One line per pattern:
 *   bench_export case=... faces=... pieces=... cut_points=... notches=...
 *                pieces_ms=... marker_ms=... <file>_ms=... total_ms=... cpu_ms=... marker_efficiency=...
 *                tiled_pages=... page_area_bound=... load=...
 * total_ms is the sum of the best times (the goal: under 1000 for
 * the 50K-face bodice); cpu_ms the process CPU time of one such round
 * (pieces, marker and every writer once), which a busy machine inflates
 * less than wall time; tiled_pages the pages of pattern-tiled.pdf after its
 * cover, page_area_bound the fewest A4 pages the drawn pieces' cut-line area
 * could fill (packed perfectly, a page advancing 180 x 267 mm past the band
 * it shares); load the 1-minute load average (2 cores: figures
 * taken above 1 are not comparable).
 * Usage: bench_export [FACES [REPEAT]] | bench_export PATTERN.obj... (defaults 50000, 3).
 *
 * SPDX-License-Identifier: GPL-3.0-or-later
 */
#define _POSIX_C_SOURCE 200809L
#include "../tests/export/export_fixtures.h"
#include "export/internal.h"
#include "generate/generate.h"

#include <float.h>
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <time.h>

#include "bench_util.h"

static pz_ctx ctx;

static double cpu_ms(void)
{
    return 1000.0 * (double)clock() / CLOCKS_PER_SEC;
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

/* The generated bodice in quarters, LSCM-flattened. */
static fixture bodice(int32_t faces)
{
    fixture f = {0};
    pz_generate_options generate = {.target_faces = faces};
    REQUIRE_OK(pz_generate(PZ_SHAPE_BODICE, &generate, &f.garment, &ctx), ctx);
    int32_t *face_panel = malloc((size_t)f.garment->face_count * sizeof(int32_t));
    REQUIRE(face_panel, "out of memory");
    quarters(f.garment, face_panel);
    REQUIRE_OK(pz_pattern_build(f.garment, face_panel, NULL, NULL, "bodice", &f.pattern, &ctx), ctx);
    free(face_panel);
    f.uv = malloc(2 * (size_t)f.pattern->mesh->vertex_count * sizeof(double));
    REQUIRE(f.uv, "out of memory");
    REQUIRE_OK(pz_param_lscm_pattern(f.pattern, NULL, f.uv, &ctx), ctx);
    return f;
}

static double time_writer(const pz_export_file *file, const pz_export_inputs *inputs)
{
    FILE *sink = tmpfile();
    REQUIRE(sink, "no temporary file");
    double start = pz_seconds();
    REQUIRE_OK(file->write(sink, inputs, file->name, &ctx), ctx);
    fflush(sink);
    double ms = 1000 * (pz_seconds() - start);
    fclose(sink);
    return ms;
}

/* Times everything of one pattern and prints its line. */
static void bench_pattern(const char *name, const fixture *f, int repeat)
{
    pz_export_options options;
    pz_export_options_default(&options);
    options.garment_name = "bench";
    pz_metrics *metrics = NULL;
    REQUIRE_OK(pz_metrics_compute(f->pattern, f->uv, 0, NULL, &metrics, &ctx), ctx);
    double best[2 + 16], cpu = DBL_MAX;
    for (int i = 0; i < 2 + pz_export_file_count; ++i)
        best[i] = DBL_MAX;
    pz_pieces *pieces = NULL;
    pz_marker *marker = NULL;
    for (int r = 0; r < repeat; ++r) {
        double cpu_start = cpu_ms();
        pz_pieces_free(&pieces);
        pz_marker_free(&marker);
        double start = pz_seconds();
        REQUIRE_OK(pz_pieces_build(f->pattern, f->uv, &options, NULL, NULL, &pieces, &ctx), ctx);
        double built = pz_seconds();
        REQUIRE_OK(pz_marker_build(pieces, &options, &marker, &ctx), ctx);
        best[0] = fmin(best[0], 1000 * (built - start));
        best[1] = fmin(best[1], 1000 * (pz_seconds() - built));
        cJSON *report = cJSON_CreateObject();
        REQUIRE(report, "out of memory");
        cJSON_AddItemToObject(report, "marker", pz_marker_report_json(marker));
        pz_export_inputs inputs = {.garment = f->garment, .pattern = f->pattern, .uv = f->uv, .metrics = metrics,
                                   .pieces = pieces, .marker = marker, .options = &options, .report = report};
        for (int i = 0; i < pz_export_file_count; ++i)
            best[2 + i] = fmin(best[2 + i], time_writer(&pz_export_files[i], &inputs));
        cJSON_Delete(report);
        cpu = fmin(cpu, cpu_ms() - cpu_start);
    }
    long cut = 0, notches = 0;
    for (int32_t p = 0; p < pieces->piece_count; ++p) {
        cut += pieces->pieces[p].cut_count;
        notches += pieces->pieces[p].notch_count;
    }
    double total = 0;
    printf("bench_export case=%s faces=%d pieces=%d cut_points=%ld notches=%ld pieces_ms=%.1f marker_ms=%.1f", name,
           (int)f->pattern->mesh->face_count, (int)pieces->piece_count, cut, notches, best[0], best[1]);
    for (int i = 0; i < 2 + pz_export_file_count; ++i) {
        total += best[i];
        if (i >= 2)
            printf(" %s_ms=%.1f", pz_export_files[i - 2].name, best[i]);
    }
    /* pattern-tiled.pdf's pages (the cover not counted) against the fewest A4 pages the drawn pieces' cut lines
     * could cover packed perfectly: their area over what a page adds (its printable area less a shared band). */
    tiled_layout layout;
    REQUIRE_OK(tiled_layout_build(pieces, "a4", &layout, &ctx), ctx);
    double drawn = 0;
    for (int32_t p = 0; p < pieces->piece_count; ++p)
        drawn += pieces->pieces[p].mirrored ? 0 : pieces->pieces[p].area_mm2;
    printf(" total_ms=%.1f cpu_ms=%.0f marker_efficiency=%.4f tiled_pages=%d page_area_bound=%.0f load=%.2f\n", total,
           cpu, marker->efficiency, (int)layout.page_count,
           ceil(drawn / (layout.step[0] * layout.step[1])), bench_load_average());
    tiled_layout_free(&layout);
    pz_marker_free(&marker);
    pz_pieces_free(&pieces);
    pz_metrics_free(&metrics);
}

int main(int argc, char **argv)
{
    ctx.quiet = 1;
    if (argc > 1 && strstr(argv[1], ".obj")) {
        for (int i = 1; i < argc; ++i) {
            fixture f;
            if (!fixture_from_pattern_obj(&f, argv[i]))
                return 1;
            bench_pattern(argv[i], &f, 3);
            fixture_free(&f);
        }
        return test_finish() == 0 ? 0 : 1;
    }
    int32_t faces = argc > 1 ? (int32_t)atol(argv[1]) : 50000;
    int repeat = argc > 2 && atoi(argv[2]) > 0 ? atoi(argv[2]) : 3;
    fixture f = bodice(faces);
    bench_pattern("bodice-quarters", &f, repeat);
    fixture_free(&f);
    return test_finish() == 0 ? 0 : 1;
}

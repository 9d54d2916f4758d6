/*
 * bench/bench_marker.c -- speed of the marker and of the PDF, GLB and HTML
 * writers (export helper B), and the marker's efficiency.
 *
 *  1. A generated bodice of about 50K faces cut into 8 panels (sectors
 *     around its vertical axis), LSCM-flattened (not timed), pieces built,
 *     then each of marker, marker.svg, pattern.pdf, pattern-tiled.pdf,
 *     garment.glb, report.html timed, written to a temporary file.
 *  2. A marker of 20 pieces: the same bodice cut into 20 panels.
 *  3. When ../shared/data is there: the diffavatar t-shirt's 4 true pieces
 *     (--panels uv) five times over (20 pieces) on 1500 mm: the issue's
 *     marker of 20 pieces (goal: under 5 s), and its efficiency.
 * Or, with `.obj` arguments, the marker of each pattern a `panelize run` or
 * `flatten` wrote (its garment.obj: panels and pattern from its vt), with the
 * default options or `--gap MM` (the figures of docs/marker.md).
 * One line per measurement:
 *   bench_marker case=... step=... ms=... [cpu_ms=... passes=... pieces=... length_mm=... efficiency=... bound=...] load=...
 * Timings are wall clock of one run, and for the marker also its CPU time
 * (cpu_ms: comparable under load, wall clock is not), and bound= the
 * efficiency no nesting of those pieces can pass (marker.efficiency_bound); the load is the
 * 1-minute load average (2 cores: wall clock taken above 1 is inflated).
 * PZ_BENCH_MARKER_SVG=DIR writes every marker as DIR/<case>.svg.
 * Usage: bench_marker [FACES] | bench_marker [--gap MM] PATTERN.obj...
 *
 * SPDX-License-Identifier: GPL-3.0-or-later
 */
#define _POSIX_C_SOURCE 200809L
#include "../tests/export/fixture_export_b.h"
#include "../tests/export/export_fixtures.h"
#include "io/io.h"

#include "bench_util.h"

#include <time.h>

static pz_ctx ctx;

/* pz_marker_build, and the CPU time it took (ms): wall clock is unreliable on a shared machine. */
static pz_marker *build_marker(const pz_pieces *pieces, const pz_export_options *options, double *cpu_ms)
{
    pz_marker *marker = NULL;
    clock_t start = clock();
    REQUIRE_OK(pz_marker_build(pieces, options, &marker, &ctx), ctx);
    *cpu_ms = (double)(clock() - start) * 1000.0 / CLOCKS_PER_SEC;
    return marker;
}

static void print_marker(const char *name, const pz_pieces *pieces, const pz_marker *marker, double cpu_ms)
{
    printf("bench_marker case=%s step=marker ms=%.1f cpu_ms=%.1f passes=%d pieces=%d placements=%d length_mm=%.1f "
           "efficiency=%.4f bound=%.4f load=%.2f\n",
           name, marker->ms, cpu_ms, (int)marker->passes, (int)pieces->piece_count, (int)marker->placement_count,
           marker->length_mm, marker->efficiency, marker->efficiency_bound, bench_load_average());
}

/* With PZ_BENCH_MARKER_SVG=DIR in the environment: DIR/<case>.svg, to look at the marker. */
static void save_svg(const char *name, const pz_pieces *pieces, const pz_marker *marker)
{
    const char *dir = getenv("PZ_BENCH_MARKER_SVG");
    if (!dir)
        return;
    char path[1024];
    snprintf(path, sizeof path, "%s/%s.svg", dir, name);
    for (char *c = path + strlen(dir) + 1; *c; ++c)
        if (*c == '/')
            *c = '_';
    FILE *file = fopen(path, "w");
    REQUIRE(file, "cannot write %s", path);
    pz_export_options options;
    pz_export_options_default(&options);
    pz_export_inputs inputs = {.pieces = pieces, .marker = marker, .options = &options};
    REQUIRE_OK(pz_export_write_marker_svg(file, &inputs, path, &ctx), ctx);
    fclose(file);
}

static void time_writer(const char *name, const char *step, pz_export_writer writer, const pz_export_inputs *inputs)
{
    FILE *sink = tmpfile();
    REQUIRE(sink, "tmpfile");
    double start = pz_seconds();
    REQUIRE_OK(writer(sink, inputs, step, &ctx), ctx);
    fflush(sink);
    double ms = (pz_seconds() - start) * 1000.0;
    long bytes = ftell(sink);
    fclose(sink);
    printf("bench_marker case=%s step=%s ms=%.1f bytes=%ld load=%.2f\n", name, step, ms, bytes,
           bench_load_average());
}

static void bench_bodice(int32_t faces, int32_t panels, int writers)
{
    fixture_pattern fixture;
    fixture_pattern_build(&fixture, faces, panels);
    double start = pz_seconds();
    fixture_pattern_export(&fixture);
    char name[64];
    snprintf(name, sizeof name, "bodice-%dK-%dpanels", (int)(fixture.pattern->mesh->face_count / 1000), (int)panels);
    printf("bench_marker case=%s step=pieces+marker ms=%.1f load=%.2f\n", name, (pz_seconds() - start) * 1000.0,
           bench_load_average());
    double cpu_ms = 0; /* the marker again, alone, for its CPU time (deterministic: the same marker) */
    pz_marker *again = build_marker(fixture.pieces, &fixture.options, &cpu_ms);
    CHECK(again->length_mm == fixture.marker->length_mm, "%s: two builds differ", name);
    pz_marker_free(&again);
    print_marker(name, fixture.pieces, fixture.marker, cpu_ms);
    save_svg(name, fixture.pieces, fixture.marker);
    cJSON *report = cJSON_CreateObject();
    cJSON_AddItemToObject(report, "marker", pz_marker_report_json(fixture.marker));
    pz_export_inputs inputs = fixture.inputs;
    inputs.report = report;
    if (writers) {
        time_writer(name, "marker.svg", pz_export_write_marker_svg, &inputs);
        time_writer(name, "pattern.pdf", pz_export_write_pdf, &inputs);
        time_writer(name, "pattern-tiled.pdf", pz_export_write_pdf_tiled, &inputs);
        time_writer(name, "garment.glb", pz_export_write_glb, &inputs);
        time_writer(name, "report.html", pz_export_write_report_html, &inputs);
    }
    cJSON_Delete(report);
    fixture_pattern_free(&fixture);
}

/* The t-shirt's true pieces, five times: a realistic 20-piece marker. */
static void bench_tshirt(const char *data)
{
    char path[1024];
    snprintf(path, sizeof path, "%s/garments/diffavatar-tshirt.obj", data);
    pz_mesh *mesh = NULL;
    if (pz_mesh_read(path, &mesh, &ctx) != PZ_OK) {
        printf("bench_marker case=tshirt skipped: %s\n", ctx.error);
        return;
    }
    pz_mesh_to_mm(mesh, PZ_UNITS_AUTO, NULL);
    int32_t *face_panel = malloc((size_t)mesh->face_count * sizeof(int32_t)), panel_count = 0;
    uint8_t *extra = NULL;
    pz_pattern *pattern = NULL;
    REQUIRE(face_panel, "out of memory");
    REQUIRE_OK(pz_pattern_panels_from_uv(mesh, face_panel, &panel_count, &extra, &ctx), ctx);
    REQUIRE_OK(pz_pattern_build(mesh, face_panel, extra, NULL, path, &pattern, &ctx), ctx);
    double *uv = malloc((size_t)pattern->mesh->vertex_count * 2 * sizeof(double));
    REQUIRE(uv, "out of memory");
    REQUIRE_OK(pz_param_lscm_pattern(pattern, NULL, uv, &ctx), ctx);
    pz_export_options options;
    pz_export_options_default(&options);
    pz_pieces *pieces = NULL;
    REQUIRE_OK(pz_pieces_build(pattern, uv, &options, NULL, NULL, &pieces, &ctx), ctx);
    /* Five copies of every piece (shallow: the arrays are shared, freed once through `pieces`). */
    int copies = 5;
    pz_pieces many = *pieces;
    many.piece_count = pieces->piece_count * copies;
    many.pieces = malloc((size_t)many.piece_count * sizeof(pz_piece));
    REQUIRE(many.pieces, "out of memory");
    for (int32_t i = 0; i < many.piece_count; ++i) {
        many.pieces[i] = pieces->pieces[i % pieces->piece_count];
        many.pieces[i].mirror_piece = -1, many.pieces[i].mirrored = 0, many.pieces[i].cut_quantity = 1;
    }
    double cpu_ms = 0;
    pz_marker *marker = build_marker(&many, &options, &cpu_ms);
    print_marker("tshirt-x5", &many, marker, cpu_ms);
    save_svg("tshirt-x5", &many, marker);
    pz_marker_free(&marker);
    free(many.pieces);
    pz_pieces_free(&pieces);
    free(uv);
    pz_pattern_free(&pattern);
    free(extra);
    free(face_panel);
    pz_mesh_free(&mesh);
}

/* The pattern a `panelize run` or `flatten` wrote (its garment.obj): pieces with the defaults, their marker. */
static void bench_pattern_obj(const char *path, double gap_mm)
{
    fixture f;
    if (!fixture_from_pattern_obj(&f, path))
        return;
    pz_export_options options;
    pz_export_options_default(&options);
    if (gap_mm >= 0)
        options.gap_mm = gap_mm;
    pz_pieces *pieces = NULL;
    REQUIRE_OK(pz_pieces_build(f.pattern, f.uv, &options, NULL, NULL, &pieces, &ctx), ctx);
    double cpu_ms = 0;
    pz_marker *marker = build_marker(pieces, &options, &cpu_ms);
    char name[256];
    snprintf(name, sizeof name, "%s", path);
    for (char *c = name; *c; ++c)
        if (*c == ' ')
            *c = '_';
    print_marker(name, pieces, marker, cpu_ms);
    save_svg(name, pieces, marker);
    pz_marker_free(&marker);
    pz_pieces_free(&pieces);
    fixture_free(&f);
}

int main(int argc, char **argv)
{
    ctx.quiet = 1;
    double gap_mm = -1;
    if (argc > 2 && strcmp(argv[1], "--gap") == 0) {
        gap_mm = atof(argv[2]);
        argc -= 2, argv += 2;
    }
    if (argc > 1 && strstr(argv[1], ".obj")) {
        for (int i = 1; i < argc; ++i)
            bench_pattern_obj(argv[i], gap_mm);
        return test_finish() == 0 ? 0 : 1;
    }
    int32_t faces = argc > 1 ? (int32_t)atoi(argv[1]) : 50000;
    bench_bodice(faces, 8, 1);
    bench_bodice(faces, 20, 0);
    const char *data = getenv("PZ_SHARED_DATA");
    char fallback[] = "../shared/data";
    if (!data) {
        FILE *probe = fopen("../shared/data/INVENTORY.md", "r");
        if (probe) {
            fclose(probe);
            data = fallback;
        }
    }
    if (data)
        bench_tshirt(data);
    return test_finish() == 0 ? 0 : 1;
}

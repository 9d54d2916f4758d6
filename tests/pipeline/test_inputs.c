/*
 * tests/pipeline/test_inputs.c -- the pipeline's input files and its shelf
 * layout in isolation: the panels, seam and dart readers (ids mapped through
 * panel files; unreferenced vertices refused; every malformed input refused
 * with file and line), joining panel files, the shelf layout (overlapping
 * pieces are moved apart by translations only; separate ones stay) and exact
 * coordinates in garment.obj (read back through pz_mesh_read).
 *
 * The layout and the garment.obj writer are the pipeline's own (its private
 * header); the readers are public (pipeline/pipeline.h).
 *
 * SPDX-License-Identifier: GPL-3.0-or-later
 */
#define _POSIX_C_SOURCE 200809L
#include "io/io.h"
#include "pipeline/internal.h"

#include "test_files.h"

#include <math.h>
#include <stdlib.h>
#include <string.h>

static const char *write_temp(const char *name, const char *text)
{
    static char paths[16][512];
    static int next;
    char *path = paths[next++ % 16];
    test_temp_path(path, 512, name);
    test_write_file(path, text, strlen(text));
    return path;
}

/* ---------------------------------------------------------------- panels file */

static void test_panel_file(void)
{
    pz_ctx ctx = {0};
    int32_t panels[4], count = -1;
    REQUIRE_OK(pz_read_panel_file(write_temp("ok.txt", "0\n1\r\n0\n2\n\n"), 4, panels, &count, &ctx), ctx);
    CHECK(count == 3 && panels[0] == 0 && panels[1] == 1 && panels[2] == 0 && panels[3] == 2, "count %d", count);

    struct { const char *text, *expect; } bad[] = {
        {"0\n1\n0\n", "3 panel ids for a mesh of 4 faces"},
        {"0\n1\n0\n1\n1\n", "line 5: more panel ids"},
        {"0\n2\n0\n2\n", "panel id 1 is unused"},
        {"0\n1\nx\n1\n", "line 3: 'x' is not"},
        {"0\n-1\n0\n1\n", "line 2: '-1' is not"},
        {"0\n1 1\n0\n1\n", "line 2: expected one panel id"},
        {"0\n\n1\n0\n1\n", "line 2: empty line"},
        {"", "empty panels file"},
        {"0\n1\n9\n1\n", "line 3: panel id 9 is not below the face count"},
    };
    for (size_t i = 0; i < sizeof bad / sizeof bad[0]; ++i) {
        const char *path = write_temp("bad.txt", bad[i].text);
        pz_status status = pz_read_panel_file(path, 4, panels, &count, &ctx);
        CHECK(status == PZ_ERR_DATA && strstr(ctx.error, bad[i].expect) && strstr(ctx.error, path),
              "case %zu: %d %s", i, (int)status, ctx.error);
    }
    CHECK(pz_read_panel_file("/nonexistent/panels.txt", 4, panels, &count, &ctx) == PZ_ERR_OPEN, "%s",
          ctx.error);
}

/* ---------------------------------------------------------------- seams and darts */

/* Two panel files of 4 vertices joined; vertex 3 is used by no face. */
static const int32_t offsets[3] = {0, 4, 8};
static const uint8_t vertex_used[8] = {1, 1, 1, 0, 1, 1, 1, 1};

static void test_seams(void)
{
    pz_ctx ctx = {0};
    pz_vertex_space two_files = {2, offsets, vertex_used, 2};
    pz_seam seam;
    REQUIRE_OK(pz_read_seam_file(write_temp("seam.txt", "0\n1\n0 1\n2 3\n"), &two_files, &seam, &ctx), ctx);
    CHECK(seam.pair_count == 2 && seam.panel_a == 0 && seam.panel_b == 1, "pairs %d", (int)seam.pair_count);
    /* side A ids are panel 0's, side B ids panel 1's (its file starts at joined vertex 4). */
    CHECK(seam.side_a[0] == 0 && seam.side_a[1] == 2 && seam.side_b[0] == 5 && seam.side_b[1] == 7,
          "%d %d %d %d", (int)seam.side_a[0], (int)seam.side_a[1], (int)seam.side_b[0], (int)seam.side_b[1]);
    free(seam.side_a);
    free(seam.side_b);

    struct { const char *text, *expect; } bad[] = {
        {"0\n1\n0 1\n2\n", "line 4: expected a vertex pair"},
        {"0\n1\n0 1 2\n", "line 3: expected a vertex pair"},
        {"0\n1\n0 x\n", "line 3: 'x' is not"},
        {"0\n1\n0 4\n", "line 3: vertex 4 is out of range (panel 1's file has 4 vertices)"},
        {"0\n1\n3 1\n", "line 3: vertex 3 is used by no face"},
        {"0\n2\n0 1\n", "line 2: panel id 2 is out of range"},
        {"0\n1\n", "no vertex pairs"},
        {"0\n", "line 2: missing the panel id of side B"},
        {"0 1\n1\n0 1\n", "line 1: expected one number"},
    };
    for (size_t i = 0; i < sizeof bad / sizeof bad[0]; ++i) {
        const char *path = write_temp("bad_seam.txt", bad[i].text);
        pz_status status = pz_read_seam_file(path, &two_files, &seam, &ctx);
        CHECK(status == PZ_ERR_DATA && strstr(ctx.error, bad[i].expect) && strstr(ctx.error, path) &&
                  !seam.side_a && !seam.side_b,
              "case %zu: %d %s", i, (int)status, ctx.error);
    }
    /* One garment file: ids are global, panel ids only range-checked. */
    pz_vertex_space one_file = {1, (const int32_t[]){0, 8}, vertex_used, 2};
    REQUIRE_OK(pz_read_seam_file(write_temp("seam1.txt", "1\n0\n7 0\n"), &one_file, &seam, &ctx), ctx);
    CHECK(seam.side_a[0] == 7 && seam.side_b[0] == 0, "%d %d", (int)seam.side_a[0], (int)seam.side_b[0]);
    free(seam.side_a);
    free(seam.side_b);
}

static void test_darts(void)
{
    pz_ctx ctx = {0};
    pz_vertex_space two_files = {2, offsets, vertex_used, 2};
    pz_dart dart;
    const char *named = write_temp("patch_1_dart_0.txt", "2\n0 1\n");
    REQUIRE_OK(pz_read_dart_file(named, &two_files, &dart, &ctx), ctx);
    CHECK(dart.panel == 1 && dart.tip == 6 && dart.leg_a[0] == 4 && dart.leg_b[0] == 5 && dart.pair_count == 1,
          "panel %d tip %d", (int)dart.panel, (int)dart.tip);
    free(dart.leg_a);
    free(dart.leg_b);

    const char *plain = write_temp("dart.txt", "2\n0 1\n");
    char spec[600];
    snprintf(spec, sizeof spec, "0:%s", plain);
    REQUIRE_OK(pz_read_dart_file(spec, &two_files, &dart, &ctx), ctx);
    CHECK(dart.panel == 0 && dart.tip == 2 && dart.leg_a[0] == 0 && dart.leg_b[0] == 1, "tip %d", (int)dart.tip);
    free(dart.leg_a);
    free(dart.leg_b);

    CHECK(pz_read_dart_file(plain, &two_files, &dart, &ctx) == PZ_ERR_USAGE && strstr(ctx.error, plain),
          "no panel: %s", ctx.error);
    snprintf(spec, sizeof spec, "5:%s", plain);
    CHECK(pz_read_dart_file(spec, &two_files, &dart, &ctx) == PZ_ERR_USAGE, "panel 5: %s", ctx.error);
    const char *far = write_temp("patch_7_dart_0.txt", "2\n0 1\n");
    CHECK(pz_read_dart_file(far, &two_files, &dart, &ctx) == PZ_ERR_DATA && strstr(ctx.error, far), "%s",
          ctx.error);
    const char *odd = write_temp("patch_0_dart_1.txt", "2\n0 1\n1\n");
    CHECK(pz_read_dart_file(odd, &two_files, &dart, &ctx) == PZ_ERR_DATA && strstr(ctx.error, "line 3"), "%s",
          ctx.error);
    /* One garment file: no panel needed. */
    pz_vertex_space one_file = {1, (const int32_t[]){0, 8}, vertex_used, 1};
    REQUIRE_OK(pz_read_dart_file(plain, &one_file, &dart, &ctx), ctx);
    free(dart.leg_a);
    free(dart.leg_b);
}

/* ---------------------------------------------------------------- layout and writers */

/* Two triangles, one panel each, both at the origin: overlapping pieces. */
static pz_pattern *two_piece_pattern(double *uv)
{
    pz_ctx ctx = {0};
    pz_pattern *pattern = calloc(1, sizeof *pattern);
    REQUIRE(pattern != NULL, "out of memory");
    REQUIRE_OK(pz_mesh_create(6, 2, &pattern->mesh, &ctx), ctx);
    static const double positions[18] = {0, 0, 0, 100, 0, 0, 0, 200, 0, 0, 0, 10, 100, 0, 10, 0, 200, 10};
    memcpy(pattern->mesh->positions, positions, sizeof positions);
    for (int32_t c = 0; c < 6; ++c)
        pattern->mesh->faces[c] = c;
    pattern->mesh->unit_scale = 1;
    pattern->panel_count = 2;
    pattern->face_panel = malloc(2 * sizeof(int32_t));
    pattern->vertex_origin = malloc(6 * sizeof(int32_t));
    REQUIRE(pattern->face_panel && pattern->vertex_origin, "out of memory");
    pattern->face_panel[0] = 0;
    pattern->face_panel[1] = 1;
    for (int32_t v = 0; v < 6; ++v) {
        pattern->vertex_origin[v] = v;
        uv[2 * v] = positions[3 * v];
        uv[2 * v + 1] = positions[3 * v + 1];
    }
    return pattern;
}

static void test_layout(void)
{
    pz_ctx ctx = {0};
    double uv[12], before[12];
    pz_pattern *pattern = two_piece_pattern(uv);
    memcpy(before, uv, sizeof uv);
    int moved = 0;
    REQUIRE_OK(pl_pattern_layout(pattern, uv, 20.0, &moved, &ctx), ctx);
    CHECK(moved == 1, "overlapping pieces were not moved");
    for (int piece = 0; piece < 2; ++piece)
        for (int v = 3 * piece + 1; v < 3 * piece + 3; ++v)
            for (int d = 0; d < 2; ++d)
                CHECK(fabs((uv[2 * v + d] - uv[6 * piece + d]) - (before[2 * v + d] - before[6 * piece + d])) < 1e-9,
                      "piece %d changed shape", piece);
    double lo[2][2], hi[2][2];
    for (int piece = 0; piece < 2; ++piece)
        for (int d = 0; d < 2; ++d) {
            lo[piece][d] = fmin(uv[6 * piece + d], fmin(uv[6 * piece + 2 + d], uv[6 * piece + 4 + d]));
            hi[piece][d] = fmax(uv[6 * piece + d], fmax(uv[6 * piece + 2 + d], uv[6 * piece + 4 + d]));
        }
    int apart = lo[1][0] >= hi[0][0] + 20 - 1e-9 || lo[0][0] >= hi[1][0] + 20 - 1e-9 ||
                lo[1][1] >= hi[0][1] + 20 - 1e-9 || lo[0][1] >= hi[1][1] + 20 - 1e-9;
    CHECK(apart, "pieces still within the gap: x %g..%g and %g..%g", lo[0][0], hi[0][0], lo[1][0], hi[1][0]);
    /* Laid out once, they stay. */
    memcpy(before, uv, sizeof uv);
    REQUIRE_OK(pl_pattern_layout(pattern, uv, 20.0, &moved, &ctx), ctx);
    CHECK(moved == 0 && memcmp(before, uv, sizeof uv) == 0, "separate pieces were moved");
    pz_pattern_free(&pattern);
}

static void test_writers(void)
{
    pz_ctx ctx = {0};
    double uv[12];
    pz_pattern *pattern = two_piece_pattern(uv);
    int moved;
    REQUIRE_OK(pl_pattern_layout(pattern, uv, 20.0, &moved, &ctx), ctx);
    /* Coordinates that %.6f would not keep. */
    double positions[18];
    memcpy(positions, pattern->mesh->positions, sizeof positions);
    positions[0] = 1.0950015925056;
    positions[1] = 1.0 / 3.0;
    positions[2] = -2.5e-300;
    char path[512];
    FILE *file = fopen(test_temp_path(path, sizeof path, "garment.obj"), "w");
    REQUIRE(file != NULL, "cannot create %s", path);
    REQUIRE_OK(pl_write_garment_obj(file, pattern->mesh, positions, pattern, uv, &ctx), ctx);
    fclose(file);
    pz_mesh *back = NULL;
    REQUIRE_OK(pz_mesh_read(path, &back, &ctx), ctx);
    CHECK(back->vertex_count == 6 && back->face_count == 2 && memcmp(back->faces, pattern->mesh->faces, 6 * 4) == 0,
          "counts or faces changed");
    CHECK(memcmp(back->positions, positions, sizeof positions) == 0, "positions not exact: %.17g %.17g %.17g",
          back->positions[0], back->positions[1], back->positions[2]);
    int uv_ok = back->corner_uvs != NULL && back->label_count == 2;
    for (int32_t c = 0; uv_ok && c < 6; ++c)
        for (int d = 0; d < 2; ++d)
            uv_ok &= fabs(back->uvs[2 * back->corner_uvs[c] + d] - uv[2 * pattern->mesh->faces[c] + d]) < 1e-6;
    CHECK(uv_ok, "vt of the corners or the panel groups differ");
    CHECK(back->label_names && strcmp(back->label_names[back->face_labels[1]], "panel_1") == 0, "groups");
    pz_mesh_free(&back);

    pz_pattern_free(&pattern);
}

int main(void)
{
    test_temp_dir_create("pz_pipeline_inputs");
    test_panel_file();
    test_seams();
    test_darts();
    test_layout();
    test_writers();
    CHECK(test_temp_dir_remove() == 0, "cannot remove %s", test_temp_dir);
    return test_finish();
}

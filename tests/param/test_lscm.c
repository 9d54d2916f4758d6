/*
 * tests/param/test_lscm.c -- LSCM (pz_param_lscm) and its pattern driver:
 *  - an open cylinder and an open cone (developable) flatten isometrically:
 *    every 2D edge within 1e-6 relative of its 3D length, no flipped face,
 *    min corner at (0, 0), 2D area == 3D area; also a 20,000-face cylinder,
 *    large enough for the nested dissection ordering;
 *  - the warp (+v) follows the grain: with the default grain (+z) the 2D +v
 *    of every cylinder triangle maps to the cylinder axis, and a flat grid
 *    with a grain along +x comes out turned by exactly +90 degrees;
 *  - a closed cylinder (two boundary loops) is refused with PZ_ERR_DATA;
 *  - pz_param_lscm_pattern on a grid cut into two panels by hand: both
 *    pieces isometric and their bounding boxes at least 20 mm apart.
 *
 * SPDX-License-Identifier: GPL-3.0-or-later
 */
#include "generate/generate.h"
#include "param/param.h"
#include "test_meshes.h"

#include <math.h>
#include <stdlib.h>
#include <string.h>

static pz_ctx ctx;

static pz_mesh *generate(pz_shape shape, int32_t faces, int open)
{
    pz_generate_options options = {.target_faces = faces, .open = open};
    pz_mesh *mesh = NULL;
    REQUIRE_OK(pz_generate(shape, &options, &mesh, &ctx), ctx);
    return mesh;
}

static double distance3(const double *a, const double *b)
{
    return sqrt((a[0] - b[0]) * (a[0] - b[0]) + (a[1] - b[1]) * (a[1] - b[1]) + (a[2] - b[2]) * (a[2] - b[2]));
}

static double signed_area2(const double *uv, const int32_t *face)
{
    const double *a = uv + 2 * face[0], *b = uv + 2 * face[1], *c = uv + 2 * face[2];
    return 0.5 * ((b[0] - a[0]) * (c[1] - a[1]) - (b[1] - a[1]) * (c[0] - a[0]));
}

/* Worst relative edge-length error over the faces of one mesh; counts flips. */
static double worst_edge_error(const pz_mesh *mesh, const double *uv, int *flipped)
{
    double worst = 0;
    *flipped = 0;
    for (int32_t f = 0; f < mesh->face_count; ++f) {
        const int32_t *face = mesh->faces + 3 * f;
        if (signed_area2(uv, face) <= 0)
            ++*flipped;
        for (int k = 0; k < 3; ++k) {
            int32_t a = face[k], b = face[(k + 1) % 3];
            double l3 = distance3(mesh->positions + 3 * a, mesh->positions + 3 * b);
            double l2 = hypot(uv[2 * a] - uv[2 * b], uv[2 * a + 1] - uv[2 * b + 1]);
            worst = fmax(worst, fabs(l2 - l3) / l3);
        }
    }
    return worst;
}

static void test_developable(pz_shape shape, int32_t faces)
{
    pz_mesh *mesh = generate(shape, faces, 1);
    double *uv = malloc((size_t)mesh->vertex_count * 2 * sizeof(double));
    REQUIRE(uv, "out of memory");
    REQUIRE_OK(pz_param_lscm(mesh, NULL, uv, &ctx), ctx);
    int flipped;
    double error = worst_edge_error(mesh, uv, &flipped);
    printf("%s (%d faces): lscm worst edge error %.3g\n", pz_shape_name(shape), (int)mesh->face_count, error);
    CHECK(error < 1e-6, "%s: worst edge error %g", pz_shape_name(shape), error);
    CHECK(flipped == 0, "%s: %d flipped faces", pz_shape_name(shape), flipped);
    double lo[2] = {INFINITY, INFINITY}, area_2d = 0;
    for (int32_t v = 0; v < mesh->vertex_count; ++v)
        for (int k = 0; k < 2; ++k)
            lo[k] = fmin(lo[k], uv[2 * v + k]);
    for (int32_t f = 0; f < mesh->face_count; ++f)
        area_2d += signed_area2(uv, mesh->faces + 3 * f);
    double area_3d = pz_geom_total_area(mesh);
    CHECK(fabs(lo[0]) < 1e-9 && fabs(lo[1]) < 1e-9, "min corner (%g, %g)", lo[0], lo[1]);
    CHECK(fabs(area_2d - area_3d) < 1e-9 * area_3d, "2D area %g, 3D area %g", area_2d, area_3d);
    if (shape == PZ_SHAPE_CYLINDER) {
        /* The cylinder's axis is z: +v must map onto +z, i.e. every vertical
         * 3D edge (same x, y) is vertical in 2D with the same sign. */
        double worst_du = 0;
        int vertical = 0, upward = 0;
        for (int32_t f = 0; f < mesh->face_count; ++f)
            for (int k = 0; k < 3; ++k) {
                int32_t a = mesh->faces[3 * f + k], b = mesh->faces[3 * f + (k + 1) % 3];
                const double *pa = mesh->positions + 3 * a, *pb = mesh->positions + 3 * b;
                if (hypot(pa[0] - pb[0], pa[1] - pb[1]) > 1e-9)
                    continue;
                ++vertical;
                worst_du = fmax(worst_du, fabs(uv[2 * a] - uv[2 * b]));
                upward += (uv[2 * b + 1] - uv[2 * a + 1] > 0) == (pb[2] - pa[2] > 0);
            }
        CHECK(vertical > 0 && worst_du < 1e-6, "%d vertical edges, worst horizontal drift %g mm", vertical, worst_du);
        CHECK(upward == vertical, "%d of %d vertical edges point up in 2D", upward, vertical);
    }
    free(uv);
    pz_mesh_free(&mesh);
}

/* A flat grid in z = 0 with the grain along +x: 3D x edges become +v. */
static void test_grain_turns(void)
{
    pz_mesh *mesh = test_grid(12, 7, TEST_GRID_FLAT, 0, &ctx);
    double *uv = malloc((size_t)mesh->vertex_count * 2 * sizeof(double));
    REQUIRE(uv, "out of memory");
    double grain[3] = {1, 0, 0};
    REQUIRE_OK(pz_param_lscm(mesh, grain, uv, &ctx), ctx);
    double worst = 0;
    for (int32_t a = 0; a < mesh->vertex_count; ++a)
        for (int32_t b = 0; b < mesh->vertex_count; ++b) {
            /* 2D difference must be (-(y_b - y_a), x_b - x_a): a +90 degree turn. */
            const double *pa = mesh->positions + 3 * a, *pb = mesh->positions + 3 * b;
            double du = uv[2 * b] - uv[2 * a], dv = uv[2 * b + 1] - uv[2 * a + 1];
            worst = fmax(worst, hypot(du + (pb[1] - pa[1]), dv - (pb[0] - pa[0])));
        }
    CHECK(worst < 1e-6, "grain +x: the grid is not turned by 90 degrees (error %g)", worst);
    free(uv);
    pz_mesh_free(&mesh);
}

static void test_not_a_disk(void)
{
    pz_mesh *mesh = generate(PZ_SHAPE_CYLINDER, 1000, 0);
    double *uv = malloc((size_t)mesh->vertex_count * 2 * sizeof(double));
    REQUIRE(uv, "out of memory");
    pz_status status = pz_param_lscm(mesh, NULL, uv, &ctx);
    CHECK(status == PZ_ERR_DATA, "closed cylinder: status %d", status);
    CHECK(strstr(ctx.error, "disk") != NULL && !strchr(ctx.error, '\n'), "message: %s", ctx.error);
    free(uv);
    pz_mesh_free(&mesh);
}

/* A 20 x 10 grid (10 mm squares) split into a left and a right panel with
 * the middle column of vertices duplicated, as pz_pattern_build would. */
static void test_pattern_layout(void)
{
    const int columns = 20, rows = 10;
    pz_mesh *grid = test_grid(columns, rows, TEST_GRID_FLAT, 0, &ctx);
    pz_pattern pattern;
    memset(&pattern, 0, sizeof pattern);
    int32_t nv = grid->vertex_count, extra = rows + 1;
    REQUIRE_OK(pz_mesh_create(nv + extra, grid->face_count, &pattern.mesh, &ctx), ctx);
    pz_mesh *mesh = pattern.mesh;
    for (int32_t v = 0; v < nv; ++v)
        for (int k = 0; k < 3; ++k)
            mesh->positions[3 * v + k] = 10 * grid->positions[3 * v + k];
    for (int j = 0; j <= rows; ++j)
        memcpy(mesh->positions + 3 * (nv + j), mesh->positions + 3 * (j * (columns + 1) + columns / 2),
               3 * sizeof(double));
    pattern.panel_count = 2;
    pattern.face_panel = malloc((size_t)grid->face_count * sizeof(int32_t));
    REQUIRE(pattern.face_panel, "out of memory");
    for (int32_t f = 0; f < grid->face_count; ++f) {
        int column = (f / 2) % columns;
        pattern.face_panel[f] = column >= columns / 2;
        for (int k = 0; k < 3; ++k) {
            int32_t v = grid->faces[3 * f + k];
            if (column >= columns / 2 && v % (columns + 1) == columns / 2)
                v = nv + v / (columns + 1);
            mesh->faces[3 * f + k] = v;
        }
    }
    double *uv = malloc((size_t)mesh->vertex_count * 2 * sizeof(double));
    REQUIRE(uv, "out of memory");
    REQUIRE_OK(pz_param_lscm_pattern(&pattern, NULL, uv, &ctx), ctx);
    int flipped;
    double error = worst_edge_error(mesh, uv, &flipped);
    CHECK(error < 1e-6 && flipped == 0, "edge error %g, %d flipped", error, flipped);
    double box[2][4] = {{INFINITY, INFINITY, -INFINITY, -INFINITY}, {INFINITY, INFINITY, -INFINITY, -INFINITY}};
    for (int32_t f = 0; f < mesh->face_count; ++f)
        for (int k = 0; k < 3; ++k) {
            const double *q = uv + 2 * mesh->faces[3 * f + k];
            double *b = box[pattern.face_panel[f]];
            b[0] = fmin(b[0], q[0]);
            b[1] = fmin(b[1], q[1]);
            b[2] = fmax(b[2], q[0]);
            b[3] = fmax(b[3], q[1]);
        }
    double gap_u = fmax(box[1][0] - box[0][2], box[0][0] - box[1][2]);
    double gap_v = fmax(box[1][1] - box[0][3], box[0][1] - box[1][3]);
    CHECK(fmax(gap_u, gap_v) >= 20 - 1e-9, "pieces only %g mm apart", fmax(gap_u, gap_v));
    free(uv);
    free(pattern.face_panel);
    pz_mesh_free(&pattern.mesh);
    pz_mesh_free(&grid);
}

int main(void)
{
    pz_ctx_init(&ctx);
    ctx.quiet = 1;
    test_developable(PZ_SHAPE_CYLINDER, 3000);
    test_developable(PZ_SHAPE_CONE, 3000);
    /* 10K unknowns: the nested dissection ordering is tried (param/lscm.c). */
    test_developable(PZ_SHAPE_CYLINDER, 20000);
    test_grain_turns();
    test_not_a_disk();
    test_pattern_layout();
    return test_finish();
}

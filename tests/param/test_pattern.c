/*
 * tests/param/test_pattern.c -- building patterns:
 *  - a generated bodice split front/back: 2 disk panels, 2 side seams whose
 *    sides are copies of the same garment vertices, on the panels' boundaries,
 *    covering every edge between the panels, one on each side (x < 0, x > 0);
 *  - a generated cylinder as one panel (a tube, 2 loops): cut into a disk by
 *    one self-seam running hem to top, about as long as the tube is high;
 *  - a hemisphere split into a cap and a ring (the ring opened by a cut path
 *    that meets the ring seam), an octahedron split at its equator (one
 *    closed seam, first pair repeated, side a along panel a's boundary);
 *  - random panels (nearest of K seeds) on a bodice and a cylinder: disks,
 *    and seams covering every cut edge once;
 *  - a torus panel (genus 1) and a closed one refused as PZ_ERR_DATA naming
 *    the panel; bad panel ids and a panel in two pieces refused;
 *  - panels from UVs: two islands, and a tube with a UV seam inside its only
 *    island (an extra cut that becomes the self-seam); a slit that stops
 *    inside a flat panel becomes a dart (tip with one copy), not a seam;
 *  - explicit correspondences: a seam between two separate pieces, a seam on
 *    a cut replacing the automatic one, a closed dart cut open;
 *  - ../shared/data/garments/diffavatar-tshirt.obj: 4 UV panels, every one a
 *    disk after building; its ground-truth UVs measured as a pattern; the
 *    whole shirt as one panel cut into a disk; the skirt panels of
 *    ../shared/data/seams/ with their explicit seams and darts (skipped
 *    without the data).
 *
 * SPDX-License-Identifier: GPL-3.0-or-later
 */
#include "generate/generate.h"
#include "io/io.h"
#include "param/param.h"
#include "test_meshes.h"

#include <math.h>
#include <stdlib.h>
#include <string.h>
#include <sys/stat.h>

static pz_ctx ctx;

/* Every panel of the pattern is one disk: one component, one boundary loop, chi = 1. */
static int panels_are_disks(const pz_pattern *pattern)
{
    int32_t *ids = malloc((size_t)pattern->mesh->face_count * sizeof(int32_t));
    REQUIRE(ids, "out of memory");
    int ok = 1;
    for (int32_t p = 0; p < pattern->panel_count; ++p) {
        int32_t count = 0;
        for (int32_t f = 0; f < pattern->mesh->face_count; ++f)
            if (pattern->face_panel[f] == p)
                ids[count++] = f;
        pz_mesh *panel = NULL;
        REQUIRE_OK(pz_mesh_extract(pattern->mesh, ids, count, &panel, NULL, NULL, &ctx), ctx);
        pz_topology_summary s = test_summary(panel, &ctx);
        if (s.component_count != 1 || s.boundary_loop_count != 1 || s.euler_characteristic != 1) {
            fprintf(stderr, "panel %d: %d components, %d loops, chi %d\n", (int)p, (int)s.component_count,
                    (int)s.boundary_loop_count, (int)s.euler_characteristic);
            ok = 0;
        }
        pz_mesh_free(&panel);
    }
    free(ids);
    return ok;
}

/* 1 when u-v is a boundary edge of the cut mesh lying in a face of `panel`. */
static int boundary_edge_of(const pz_pattern *pattern, const pz_topology *t, int32_t u, int32_t v, int32_t panel)
{
    for (int32_t h = 0; h < t->halfedge_count; ++h)
        if (t->twin[h] < 0 && pattern->face_panel[pz_he_face(h)] == panel &&
            ((pz_he_from(t, h) == u && pz_he_to(t, h) == v) || (pz_he_from(t, h) == v && pz_he_to(t, h) == u)))
            return 1;
    return 0;
}

/* Checks every seam: sides are copies of the same garment vertices, boundary edges of their panels. Returns edges. */
static int32_t check_seams(const pz_pattern *pattern, const char *what)
{
    pz_topology *t = test_topology(pattern->mesh, &ctx);
    int32_t edges = 0;
    for (int32_t s = 0; s < pattern->seam_count; ++s) {
        const pz_seam *seam = &pattern->seams[s];
        int same = 1, on_boundary = 1, distinct = 1;
        for (int32_t i = 0; i < seam->pair_count; ++i) {
            int32_t a = seam->side_a[i], b = seam->side_b[i];
            same &= pattern->vertex_origin[a] == pattern->vertex_origin[b];
            distinct &= a != b || i == 0 || i == seam->pair_count - 1; /* ends may be shared (a slit's end) */
            if (i + 1 < seam->pair_count) {
                on_boundary &= boundary_edge_of(pattern, t, a, seam->side_a[i + 1], seam->panel_a);
                on_boundary &= boundary_edge_of(pattern, t, b, seam->side_b[i + 1], seam->panel_b);
                ++edges;
            }
        }
        CHECK(same, "%s: seam %d pairs copies of one garment vertex", what, (int)s);
        CHECK(distinct, "%s: seam %d sides are different copies", what, (int)s);
        CHECK(on_boundary, "%s: seam %d sides run along the boundary of panels %d and %d", what, (int)s,
              (int)seam->panel_a, (int)seam->panel_b);
    }
    pz_topology_free(&t);
    return edges;
}

static double side_length(const pz_pattern *pattern, const int32_t *side, int32_t n)
{
    double length = 0;
    for (int32_t i = 0; i + 1 < n; ++i) {
        const double *p = pattern->mesh->positions + 3 * side[i], *q = pattern->mesh->positions + 3 * side[i + 1];
        length += sqrt((p[0] - q[0]) * (p[0] - q[0]) + (p[1] - q[1]) * (p[1] - q[1]) + (p[2] - q[2]) * (p[2] - q[2]));
    }
    return length;
}

static void test_bodice(void)
{
    pz_generate_options options = {.target_faces = 2000};
    pz_mesh *garment = NULL;
    REQUIRE_OK(pz_generate(PZ_SHAPE_BODICE, &options, &garment, &ctx), ctx);
    int32_t *panels = malloc((size_t)garment->face_count * sizeof(int32_t));
    REQUIRE(panels, "out of memory");
    for (int32_t f = 0; f < garment->face_count; ++f) {
        double y = 0;
        for (int k = 0; k < 3; ++k)
            y += garment->positions[3 * garment->faces[3 * f + k] + 1];
        panels[f] = y < 0;
    }
    pz_pattern *pattern = NULL;
    REQUIRE_OK(pz_pattern_build(garment, panels, NULL, NULL, "bodice", &pattern, &ctx), ctx);
    CHECK(pattern->panel_count == 2 && panels_are_disks(pattern), "2 disk panels");
    CHECK(pattern->mesh->face_count == garment->face_count, "faces kept");
    REQUIRE(pattern->seam_count == 2, "2 side seams, got %d", (int)pattern->seam_count);
    int32_t seam_edges = check_seams(pattern, "bodice");
    /* Every garment edge between the panels is in exactly one seam. */
    pz_topology *t = test_topology(garment, &ctx);
    int32_t between = 0;
    for (int32_t e = 0; e < t->edge_count; ++e)
        if (t->edge_halfedge[2 * e + 1] >= 0 &&
            panels[pz_he_face(t->edge_halfedge[2 * e])] != panels[pz_he_face(t->edge_halfedge[2 * e + 1])])
            ++between;
    CHECK(seam_edges == between, "seams cover the %d edges between panels (%d)", (int)between, (int)seam_edges);
    double mean_x[2] = {0, 0};
    for (int32_t s = 0; s < 2; ++s) {
        const pz_seam *seam = &pattern->seams[s];
        CHECK(seam->panel_a == 0 && seam->panel_b == 1, "seam %d joins panels 0 and 1", (int)s);
        double la = side_length(pattern, seam->side_a, seam->pair_count);
        double lb = side_length(pattern, seam->side_b, seam->pair_count);
        CHECK(fabs(la - lb) < 1e-9 && la >= 600 && la < 1000,
              "seam %d: 3D side lengths %g %g (bodice 600 high, seam zig-zags along face edges)", (int)s,
              la, lb);
        for (int32_t i = 0; i < seam->pair_count; ++i)
            mean_x[s] += pattern->mesh->positions[3 * seam->side_a[i]] / seam->pair_count;
    }
    CHECK(mean_x[0] * mean_x[1] < 0, "one seam on each side: mean x %g and %g", mean_x[0], mean_x[1]);
    pz_topology_free(&t);
    pz_pattern_free(&pattern);
    pz_pattern_free(&pattern); /* NULL: no-op */
    free(panels);
    pz_mesh_free(&garment);
}

static void test_tube(void)
{
    pz_generate_options options = {.target_faces = 2000};
    pz_mesh *garment = NULL;
    REQUIRE_OK(pz_generate(PZ_SHAPE_CYLINDER, &options, &garment, &ctx), ctx);
    int32_t *panels = calloc((size_t)garment->face_count, sizeof(int32_t));
    REQUIRE(panels, "out of memory");
    pz_pattern *pattern = NULL;
    REQUIRE_OK(pz_pattern_build(garment, panels, NULL, NULL, "cylinder", &pattern, &ctx), ctx);
    CHECK(pattern->panel_count == 1 && panels_are_disks(pattern), "the tube is cut into a disk");
    REQUIRE(pattern->seam_count == 1, "one self-seam, got %d", (int)pattern->seam_count);
    const pz_seam *seam = &pattern->seams[0];
    CHECK(seam->panel_a == 0 && seam->panel_b == 0, "a self-seam");
    check_seams(pattern, "cylinder");
    double la = side_length(pattern, seam->side_a, seam->pair_count);
    double lb = side_length(pattern, seam->side_b, seam->pair_count);
    CHECK(fabs(la - lb) < 1e-9 && la >= 400 - 1e-9 && la < 440, "shortest path hem to top: %g %g (height 400)", la, lb);
    double z0 = pattern->mesh->positions[3 * seam->side_a[0] + 2];
    double z1 = pattern->mesh->positions[3 * seam->side_a[seam->pair_count - 1] + 2];
    CHECK(fabs(fabs(z1 - z0) - 400) < 1e-6, "runs from one rim to the other: z %g .. %g", z0, z1);
    pz_pattern_free(&pattern);
    free(panels);
    pz_mesh_free(&garment);
}

/* A hemisphere split into a cap (panel 1) and a ring around it (panel 0, an annulus). */
static void test_ring(void)
{
    pz_generate_options options = {.target_faces = 2000};
    pz_mesh *garment = NULL;
    REQUIRE_OK(pz_generate(PZ_SHAPE_HEMISPHERE, &options, &garment, &ctx), ctx);
    double low[3], high[3];
    pz_mesh_bbox(garment, low, high);
    int32_t *panels = malloc((size_t)garment->face_count * sizeof(int32_t));
    REQUIRE(panels, "out of memory");
    for (int32_t f = 0; f < garment->face_count; ++f) {
        double z = 0;
        for (int k = 0; k < 3; ++k)
            z += garment->positions[3 * garment->faces[3 * f + k] + 2] / 3;
        panels[f] = z > low[2] + 0.6 * (high[2] - low[2]);
    }
    pz_pattern *pattern = NULL;
    REQUIRE_OK(pz_pattern_build(garment, panels, NULL, NULL, "hemisphere", &pattern, &ctx), ctx);
    CHECK(pattern->panel_count == 2 && panels_are_disks(pattern), "cap and opened ring are disks");
    REQUIRE(pattern->seam_count == 2, "the ring seam and the ring's self-seam: %d seams", (int)pattern->seam_count);
    check_seams(pattern, "ring");
    int found_ring = 0, found_self = 0;
    for (int32_t s = 0; s < 2; ++s) {
        const pz_seam *seam = &pattern->seams[s];
        const int32_t *origin = pattern->vertex_origin;
        if (seam->panel_a == 0 && seam->panel_b == 1)
            found_ring = origin[seam->side_a[0]] == origin[seam->side_a[seam->pair_count - 1]] &&
                         seam->side_b[0] == seam->side_b[seam->pair_count - 1] &&
                         seam->side_a[0] != seam->side_a[seam->pair_count - 1];
        else if (seam->panel_a == 0 && seam->panel_b == 0)
            found_self = 1;
    }
    CHECK(found_ring, "the ring seam closes on itself: one cap copy, two copies on the opened ring");
    CHECK(found_self, "the ring panel's self-seam");
    pz_pattern_free(&pattern);
    free(panels);
    pz_mesh_free(&garment);
}

/* An octahedron split at its equator: two disks sewn along one closed ring. */
static void test_closed_ring(void)
{
    static const double positions[] = {1, 0, 0, 0, 1, 0, -1, 0, 0, 0, -1, 0, 0, 0, 1, 0, 0, -1};
    static const int32_t faces[] = {0, 1, 4, 1, 2, 4, 2, 3, 4, 3, 0, 4, 1, 0, 5, 2, 1, 5, 3, 2, 5, 0, 3, 5};
    pz_mesh *mesh = test_mesh_from(6, positions, 8, faces, &ctx);
    int32_t panels[8] = {0, 0, 0, 0, 1, 1, 1, 1};
    pz_pattern *pattern = NULL;
    REQUIRE_OK(pz_pattern_build(mesh, panels, NULL, NULL, "octahedron", &pattern, &ctx), ctx);
    CHECK(panels_are_disks(pattern), "two disks");
    REQUIRE(pattern->seam_count == 1, "one ring seam: %d", (int)pattern->seam_count);
    const pz_seam *seam = &pattern->seams[0];
    CHECK(seam->pair_count == 5 && seam->side_a[0] == seam->side_a[4] && seam->side_b[0] == seam->side_b[4],
          "closed: 4 edges, the first pair repeated at the end (%d pairs)", (int)seam->pair_count);
    CHECK(check_seams(pattern, "ring") == 4, "the 4 equator edges");
    pz_topology *t = test_topology(pattern->mesh, &ctx);
    int along = 1; /* panel_a on the left: side a's consecutive pairs are boundary half-edges of panel a, in order */
    for (int i = 0; i < 4; ++i) {
        int found = 0;
        for (int32_t h = 0; h < t->halfedge_count; ++h)
            found |= t->twin[h] < 0 && pz_he_from(t, h) == seam->side_a[i] && pz_he_to(t, h) == seam->side_a[i + 1];
        along &= found;
    }
    CHECK(along, "side a runs along panel a's boundary direction");
    pz_topology_free(&t);
    pz_pattern_free(&pattern);
    pz_mesh_free(&mesh);
}

static int32_t boundary_edge_count(const pz_mesh *mesh)
{
    pz_topology *t = test_topology(mesh, &ctx);
    int32_t count = 0;
    for (int32_t e = 0; e < t->edge_count; ++e)
        count += t->edge_halfedge[2 * e + 1] < 0;
    pz_topology_free(&t);
    return count;
}

/*
 * Random panels (nearest of K random seed faces, by 3D distance) on a bodice
 * and a cylinder: every build either succeeds, with every panel a disk and
 * the seams covering each cut edge exactly once, or refuses a panel in
 * separate pieces (3D distance can split a cell) -- never anything else.
 */
static void test_random_panels(void)
{
    pz_shape shapes[2] = {PZ_SHAPE_BODICE, PZ_SHAPE_CYLINDER};
    srand(11);
    int built = 0;
    for (int trial = 0; trial < 16; ++trial) {
        pz_generate_options options = {.target_faces = 1500};
        pz_mesh *garment = NULL;
        REQUIRE_OK(pz_generate(shapes[trial % 2], &options, &garment, &ctx), ctx);
        int32_t nf = garment->face_count, k_count = 2 + trial % 7, seeds[8];
        int32_t *panels = malloc((size_t)nf * sizeof(int32_t));
        double *centroids = malloc((size_t)nf * 3 * sizeof(double));
        REQUIRE(panels && centroids, "out of memory");
        for (int32_t f = 0; f < nf; ++f)
            for (int c = 0; c < 3; ++c)
                centroids[3 * f + c] = (garment->positions[3 * garment->faces[3 * f] + c] +
                                        garment->positions[3 * garment->faces[3 * f + 1] + c] +
                                        garment->positions[3 * garment->faces[3 * f + 2] + c]) / 3;
        for (int k = 0; k < k_count; ++k)
            seeds[k] = (int32_t)(rand() % nf);
        for (int32_t f = 0; f < nf; ++f) {
            double best = INFINITY;
            for (int k = 0; k < k_count; ++k) {
                const double *a = centroids + 3 * f, *b = centroids + 3 * seeds[k];
                double d = (a[0] - b[0]) * (a[0] - b[0]) + (a[1] - b[1]) * (a[1] - b[1]) + (a[2] - b[2]) * (a[2] - b[2]);
                if (d < best) {
                    best = d;
                    panels[f] = k;
                }
            }
        }
        /* Renumber to 0..K-1 in case a seed lost all its faces to another (equal seeds). */
        int32_t remap[8];
        for (int k = 0; k < 8; ++k)
            remap[k] = -1;
        int32_t used = 0;
        for (int32_t f = 0; f < nf; ++f) {
            if (remap[panels[f]] < 0)
                remap[panels[f]] = used++;
            panels[f] = remap[panels[f]];
        }
        pz_pattern *pattern = NULL;
        pz_status status = pz_pattern_build(garment, panels, NULL, NULL, "random", &pattern, &ctx);
        CHECK(status == PZ_OK || (status == PZ_ERR_DATA && strstr(ctx.error, "separate pieces")),
              "trial %d: status %d: %s", trial, (int)status, ctx.error);
        if (status == PZ_OK) {
            ++built;
            int32_t cut_edges = (boundary_edge_count(pattern->mesh) - boundary_edge_count(garment)) / 2;
            CHECK(panels_are_disks(pattern), "trial %d: %d panels, all disks", trial, (int)used);
            CHECK(check_seams(pattern, "random") == cut_edges, "trial %d: seams cover the %d cut edges once", trial,
                  (int)cut_edges);
        }
        pz_pattern_free(&pattern);
        free(panels);
        free(centroids);
        pz_mesh_free(&garment);
    }
    printf("random panels: %d of 16 splits built (the others have a panel in pieces)\n", built);
    CHECK(built >= 8, "most random splits build: %d of 16", built);
}

static void expect_refused(const pz_mesh *mesh, const int32_t *panels, const char *expected)
{
    pz_pattern *pattern = (pz_pattern *)&ctx;
    pz_status status = pz_pattern_build(mesh, panels, NULL, NULL, "in.obj", &pattern, &ctx);
    CHECK(status == PZ_ERR_DATA && pattern == NULL, "%s: refused (status %d)", expected, (int)status);
    CHECK(strncmp(ctx.error, "in.obj: ", 8) == 0 && strstr(ctx.error, expected) && !strchr(ctx.error, '\n'),
          "message '%s' lacks '%s'", ctx.error, expected);
}

static void test_refusals(void)
{
    pz_mesh *torus = test_grid(8, 6, TEST_GRID_TORUS, 0, &ctx);
    int32_t panels[96] = {0};
    expect_refused(torus, panels, "panel 0 is not a disk and cannot be cut (genus 1");
    pz_mesh_free(&torus);
    pz_mesh *closed = test_tetrahedron(&ctx);
    expect_refused(closed, panels, "panel 0 is not a disk");
    pz_mesh_free(&closed);

    pz_mesh *grid = test_grid(3, 1, TEST_GRID_FLAT, 0, &ctx);
    int32_t gap[6] = {0, 0, 2, 2, 0, 0};
    expect_refused(grid, gap, "panel 1 has no faces");
    int32_t negative[6] = {0, 0, -1, 0, 0, 0};
    expect_refused(grid, negative, "face 2 has panel id -1");
    int32_t split[6] = {0, 0, 1, 1, 0, 0};
    expect_refused(grid, split, "panel 0 is in 2 separate pieces");
    pz_mesh_free(&grid);
}

/* Gives a tube grid (columns x rows) per-corner UVs: (i, j) of the corner, column 0 repeated as column
 * `columns` in the last column of squares, so the edges at angle 0 are a UV seam. */
static void add_tube_uvs(pz_mesh *mesh, int columns, int rows)
{
    mesh->uv_count = (columns + 1) * (rows + 1);
    mesh->uvs = malloc((size_t)mesh->uv_count * 2 * sizeof(double));
    mesh->corner_uvs = malloc((size_t)mesh->face_count * 3 * sizeof(int32_t));
    REQUIRE(mesh->uvs && mesh->corner_uvs, "out of memory");
    for (int j = 0; j <= rows; ++j)
        for (int i = 0; i <= columns; ++i) {
            mesh->uvs[2 * (j * (columns + 1) + i)] = i;
            mesh->uvs[2 * (j * (columns + 1) + i) + 1] = j;
        }
    for (int32_t f = 0; f < mesh->face_count; ++f) {
        int square = f / 2, i = square % columns;
        for (int k = 0; k < 3; ++k) {
            int32_t v = mesh->faces[3 * f + k];
            int vi = v % columns, vj = v / columns;
            if (i == columns - 1 && vi == 0)
                vi = columns;
            mesh->corner_uvs[3 * f + k] = vj * (columns + 1) + vi;
        }
    }
}

static void test_panels_from_uv(void)
{
    const int columns = 8, rows = 3;
    pz_mesh *tube = test_grid(columns, rows, TEST_GRID_TUBE, 0, &ctx);
    int32_t face_panel[48], panel_count = -1;
    uint8_t *extra = (uint8_t *)&ctx;
    CHECK(pz_pattern_panels_from_uv(tube, face_panel, &panel_count, &extra, &ctx) == PZ_ERR_DATA && extra == NULL,
          "no UVs: refused");
    add_tube_uvs(tube, columns, rows);
    REQUIRE_OK(pz_pattern_panels_from_uv(tube, face_panel, &panel_count, &extra, &ctx), ctx);
    CHECK(panel_count == 1, "one island: %d", (int)panel_count);
    pz_topology *t = test_topology(tube, &ctx);
    int32_t cut_count = 0, cuts_ok = 1;
    for (int32_t e = 0; e < t->edge_count; ++e)
        if (extra[e]) {
            ++cut_count;
            int32_t h = t->edge_halfedge[2 * e];
            cuts_ok &= pz_he_from(t, h) % columns == 0 && pz_he_to(t, h) % columns == 0;
        }
    CHECK(cut_count == rows && cuts_ok, "the UV seam inside the island is %d extra cuts at angle 0", (int)cut_count);
    pz_pattern *pattern = NULL;
    REQUIRE_OK(pz_pattern_build(tube, face_panel, extra, NULL, "tube", &pattern, &ctx), ctx);
    CHECK(panels_are_disks(pattern) && pattern->seam_count == 1 && pattern->seams[0].pair_count == rows + 1,
          "the UV seam opens the tube: %d seams", (int)pattern->seam_count);
    check_seams(pattern, "uv tube");
    pz_pattern_free(&pattern);
    free(extra);
    pz_topology_free(&t);

    /* Two islands: give the right half (columns 4..7) UV indices of its own. */
    int32_t uv_base = tube->uv_count;
    double *bigger = realloc(tube->uvs, (size_t)uv_base * 4 * sizeof(double));
    REQUIRE(bigger, "out of memory");
    tube->uvs = bigger;
    memcpy(tube->uvs + 2 * uv_base, tube->uvs, (size_t)uv_base * 2 * sizeof(double));
    tube->uv_count = 2 * uv_base;
    for (int32_t f = 0; f < tube->face_count; ++f)
        if ((f / 2) % columns >= 4)
            for (int k = 0; k < 3; ++k) {
                tube->corner_uvs[3 * f + k] += uv_base;
                tube->uvs[2 * tube->corner_uvs[3 * f + k]] += 100; /* not equal by value either */
            }
    REQUIRE_OK(pz_pattern_panels_from_uv(tube, face_panel, &panel_count, &extra, &ctx), ctx);
    int halves = 1;
    for (int32_t f = 0; f < tube->face_count; ++f)
        halves &= face_panel[f] == ((f / 2) % columns >= 4);
    CHECK(panel_count == 2 && halves, "two islands, numbered in face order: %d", (int)panel_count);
    REQUIRE_OK(pz_pattern_build(tube, face_panel, extra, NULL, "tube", &pattern, &ctx), ctx);
    CHECK(panels_are_disks(pattern) && pattern->seam_count == 2, "two halves, two seams: %d", (int)pattern->seam_count);
    pz_pattern_free(&pattern);
    free(extra);
    pz_mesh_free(&tube);
}

/*
 * A slit cut into a flat 6 x 6 grid from the boundary at (3, 0) up to the
 * interior vertex (3, 3) is a dart, not a seam: tip (3, 3) with one copy,
 * legs from the open end towards the tip, two copies of each leg vertex.
 */
static void test_slit_is_dart(void)
{
    const int columns = 6, rows = 6, vertex_columns = columns + 1;
    pz_mesh *grid = test_grid(columns, rows, TEST_GRID_FLAT, 0, &ctx);
    pz_topology *t = test_topology(grid, &ctx);
    uint8_t *slit = calloc((size_t)t->edge_count, 1);
    int32_t *face_panel = calloc((size_t)grid->face_count, sizeof(int32_t));
    REQUIRE(slit && face_panel, "out of memory");
    for (int32_t e = 0; e < t->edge_count; ++e) {
        int32_t h = t->edge_halfedge[2 * e], u = pz_he_from(t, h), v = pz_he_to(t, h);
        int vertical = u % vertex_columns == 3 && v % vertex_columns == 3;
        slit[e] = vertical && u / vertex_columns <= 3 && v / vertex_columns <= 3;
    }
    pz_pattern *pattern = NULL;
    REQUIRE_OK(pz_pattern_build(grid, face_panel, slit, NULL, "slit", &pattern, &ctx), ctx);
    CHECK(panels_are_disks(pattern), "slit grid: one disk");
    CHECK(pattern->seam_count == 0 && pattern->dart_count == 1, "slit: %d seams, %d darts (want 0, 1)",
          (int)pattern->seam_count, (int)pattern->dart_count);
    if (pattern->dart_count == 1) {
        const pz_dart *dart = &pattern->darts[0];
        const int32_t *origin = pattern->vertex_origin;
        CHECK(dart->panel == 0 && dart->pair_count == 3 && origin[dart->tip] == 3 * vertex_columns + 3,
              "dart: panel %d, %d pairs, tip at garment vertex %d", (int)dart->panel, (int)dart->pair_count,
              (int)origin[dart->tip]);
        int legs_ok = 1;
        for (int32_t i = 0; i < dart->pair_count && i < 3; ++i)
            legs_ok &= origin[dart->leg_a[i]] == i * vertex_columns + 3 &&
                       origin[dart->leg_b[i]] == origin[dart->leg_a[i]] &&
                       dart->leg_a[i] != dart->leg_b[i];
        CHECK(legs_ok, "dart legs: two copies of (3, 0), (3, 1), (3, 2), from the open end");
        int32_t tip_copies = 0;
        for (int32_t v = 0; v < pattern->mesh->vertex_count; ++v)
            tip_copies += origin[v] == 3 * vertex_columns + 3;
        CHECK(tip_copies == 1, "the tip has one copy: %d", (int)tip_copies);
    }
    pz_pattern_free(&pattern);
    free(slit);
    free(face_panel);
    pz_topology_free(&t);
    pz_mesh_free(&grid);
}

/* Two unit-square grids side by side (2 x 2 squares each), separate: pieces 0 (x 0..2) and 1 (x 3..5). */
static pz_mesh *two_pieces(void)
{
    pz_mesh *one = test_grid(2, 2, TEST_GRID_FLAT, 0, &ctx);
    pz_mesh *both = NULL;
    REQUIRE_OK(pz_mesh_create(2 * one->vertex_count, 2 * one->face_count, &both, &ctx), ctx);
    for (int piece = 0; piece < 2; ++piece) {
        for (int32_t v = 0; v < one->vertex_count; ++v)
            for (int k = 0; k < 3; ++k)
                both->positions[3 * (piece * one->vertex_count + v) + k] =
                    one->positions[3 * v + k] + (k == 0 ? 3.0 * piece : 0.0);
        for (int32_t c = 0; c < 3 * one->face_count; ++c)
            both->faces[3 * piece * one->face_count + c] = one->faces[c] + piece * one->vertex_count;
    }
    pz_mesh_free(&one);
    return both;
}

static void test_explicit(void)
{
    /* Piece 0's right column (x = 2: vertices 2, 5, 8) sewn to piece 1's left column (9, 12, 15). */
    pz_mesh *mesh = two_pieces();
    int32_t panels[16];
    for (int f = 0; f < 16; ++f)
        panels[f] = f >= 8;
    int32_t side_a[3] = {2, 5, 8}, side_b[3] = {9, 12, 15};
    pz_seam given = {.pair_count = 3, .side_a = side_a, .side_b = side_b};
    pz_correspondences correspondences = {.seam_count = 1, .seams = &given};
    pz_pattern *pattern = NULL;
    REQUIRE_OK(pz_pattern_build(mesh, panels, NULL, &correspondences, "pieces", &pattern, &ctx), ctx);
    REQUIRE(pattern->seam_count == 1, "one explicit seam: %d", (int)pattern->seam_count);
    const pz_seam *seam = &pattern->seams[0];
    int mapped = seam->panel_a == 0 && seam->panel_b == 1;
    for (int i = 0; i < 3; ++i)
        mapped &= pattern->vertex_origin[seam->side_a[i]] == side_a[i] &&
                  pattern->vertex_origin[seam->side_b[i]] == side_b[i];
    CHECK(mapped, "pairs mapped onto the pieces' copies");
    /* An interior vertex (4, the centre of piece 0) is not on a boundary. */
    side_a[1] = 4;
    pz_pattern_free(&pattern);
    pattern = (pz_pattern *)&ctx;
    CHECK(pz_pattern_build(mesh, panels, NULL, &correspondences, "pieces", &pattern, &ctx) == PZ_ERR_DATA &&
              pattern == NULL && strstr(ctx.error, "vertex 4"),
          "interior vertex refused: %s", ctx.error);
    side_a[1] = 99;
    CHECK(pz_pattern_build(mesh, panels, NULL, &correspondences, "pieces", &pattern, &ctx) == PZ_ERR_DATA &&
              strstr(ctx.error, "out of range"),
          "vertex out of range refused: %s", ctx.error);
    pz_mesh_free(&mesh);

    /* A closed dart in a 4 x 4 grid: legs up the middle column from the hem (2) to the tip (12). */
    mesh = test_grid(4, 4, TEST_GRID_FLAT, 0, &ctx);
    int32_t grid_panels[32] = {0}, legs[2] = {2, 7};
    pz_dart dart = {.tip = 12, .pair_count = 2, .leg_a = legs, .leg_b = legs};
    pz_correspondences with_dart = {.dart_count = 1, .darts = &dart};
    REQUIRE_OK(pz_pattern_build(mesh, grid_panels, NULL, &with_dart, "darted", &pattern, &ctx), ctx);
    CHECK(panels_are_disks(pattern) && pattern->dart_count == 1 && pattern->seam_count == 0,
          "a slit dart: still a disk, %d seams", (int)pattern->seam_count);
    const pz_dart *d = &pattern->darts[0];
    int opened = pattern->vertex_origin[d->tip] == 12 && d->pair_count == 2;
    for (int i = 0; i < 2; ++i)
        opened &= d->leg_a[i] != d->leg_b[i] && pattern->vertex_origin[d->leg_a[i]] == legs[i] &&
                  pattern->vertex_origin[d->leg_b[i]] == legs[i];
    CHECK(opened, "dart legs are two copies of each leg vertex, the tip one");
    CHECK(pattern->mesh->vertex_count == mesh->vertex_count + 2, "two vertices more: %d",
          (int)pattern->mesh->vertex_count);
    pz_pattern_free(&pattern);

    /* An explicit seam on a cut replaces the automatic one: split the grid at x = 2. */
    for (int f = 0; f < 32; ++f)
        grid_panels[f] = (f / 2) % 4 >= 2;
    REQUIRE_OK(pz_pattern_build(mesh, grid_panels, NULL, NULL, "split", &pattern, &ctx), ctx);
    CHECK(pattern->seam_count == 1 && pattern->seams[0].pair_count == 5, "automatic: one seam of 5 pairs");
    pz_pattern_free(&pattern);
    int32_t chain[3] = {7, 12, 17}; /* the middle part of the column x = 2 */
    pz_seam on_cut = {.pair_count = 3, .side_a = chain, .side_b = chain};
    pz_correspondences explicit_seam = {.seam_count = 1, .seams = &on_cut};
    REQUIRE_OK(pz_pattern_build(mesh, grid_panels, NULL, &explicit_seam, "split", &pattern, &ctx), ctx);
    CHECK(pattern->seam_count == 3, "explicit seam + the two automatic pieces left over: %d", (int)pattern->seam_count);
    CHECK(pattern->seams[0].pair_count == 3 && pattern->seams[0].panel_a != pattern->seams[0].panel_b,
          "the explicit seam comes first, between the two panels");
    int32_t edges = check_seams(pattern, "explicit on cut");
    CHECK(edges == 4, "4 cut edges covered once: %d", (int)edges);
    pz_pattern_free(&pattern);
    pz_seam twice[2] = {on_cut, {.pair_count = 2, .side_a = chain + 1, .side_b = chain + 1}};
    pz_correspondences overlapping = {.seam_count = 2, .seams = twice};
    pattern = (pz_pattern *)&ctx;
    CHECK(pz_pattern_build(mesh, grid_panels, NULL, &overlapping, "split", &pattern, &ctx) == PZ_ERR_DATA &&
              pattern == NULL && strstr(ctx.error, "seam 1: edge 12-17 is already in another seam"),
          "overlapping explicit seams refused: %s", ctx.error);
    int32_t off_cut[2] = {6, 11};
    pz_seam not_cut = {.pair_count = 2, .side_a = off_cut, .side_b = off_cut};
    explicit_seam.seams = &not_cut;
    CHECK(pz_pattern_build(mesh, grid_panels, NULL, &explicit_seam, "split", &pattern, &ctx) == PZ_ERR_DATA &&
              strstr(ctx.error, "not joined by a cut edge"),
          "a seam off the cut is refused: %s", ctx.error);
    pz_mesh_free(&mesh);
}

static void test_correspondences_clear(void)
{
    pz_correspondences c = {0};
    c.seam_count = 1;
    c.seams = calloc(1, sizeof(pz_seam));
    REQUIRE(c.seams, "out of memory");
    c.seams[0].side_a = malloc(4 * sizeof(int32_t));
    c.seams[0].side_b = malloc(4 * sizeof(int32_t));
    c.dart_count = 1;
    c.darts = calloc(1, sizeof(pz_dart));
    REQUIRE(c.darts, "out of memory");
    c.darts[0].leg_a = malloc(4 * sizeof(int32_t));
    pz_correspondences_clear(&c);
    CHECK(c.seam_count == 0 && c.seams == NULL && c.dart_count == 0 && c.darts == NULL, "cleared");
    pz_correspondences_clear(&c);
    pz_correspondences_clear(NULL);
}

/*
 * The shirt's own UVs are its real sewing pattern: measured against the 3D
 * shirt (scaled to equal total area), strains stay near the spread
 * INVENTORY.md gives for edge ratios (0.89 - 1.03), no triangle is flipped,
 * and the seams' sides have nearly the same length (most exactly).
 */
static void measure_ground_truth(const pz_mesh *mesh, const pz_pattern *pattern)
{
    int32_t nv = pattern->mesh->vertex_count;
    double *uv = calloc((size_t)nv * 2, sizeof(double));
    REQUIRE(uv, "out of memory");
    int consistent = 1;
    double area_2d = 0;
    for (int32_t c = 0; c < 3 * mesh->face_count; ++c) {
        int32_t v = pattern->mesh->faces[c];
        const double *t = mesh->uvs + 2 * mesh->corner_uvs[c];
        if ((uv[2 * v] != 0 || uv[2 * v + 1] != 0) && (uv[2 * v] != t[0] || uv[2 * v + 1] != t[1]))
            consistent = 0;
        uv[2 * v] = t[0];
        uv[2 * v + 1] = t[1];
    }
    CHECK(consistent, "every cut-mesh vertex has one UV (all UV seams were cut)");
    for (int32_t f = 0; f < mesh->face_count; ++f) {
        const int32_t *c = pattern->mesh->faces + 3 * f;
        const double *a = uv + 2 * c[0], *b = uv + 2 * c[1], *d = uv + 2 * c[2];
        area_2d += fabs((b[0] - a[0]) * (d[1] - a[1]) - (b[1] - a[1]) * (d[0] - a[0])) / 2;
    }
    double scale = sqrt(pz_geom_total_area(mesh) / area_2d);
    for (int32_t i = 0; i < 2 * nv; ++i)
        uv[i] *= scale;
    pz_metrics *m = NULL;
    REQUIRE_OK(pz_metrics_compute(pattern, uv, 0, NULL, &m, &ctx), ctx);
    double worst_p95 = 0;
    for (int32_t p = 0; p < m->panel_count; ++p)
        worst_p95 = fmax(worst_p95, fmax(m->panels[p].strain_warp.p95, m->panels[p].strain_weft.p95));
    printf("tshirt ground truth: max |strain| %.3f, worst p95 %.3f, max seam mismatch %.4f, injective %d\n",
           m->max_abs_strain, worst_p95, m->max_seam_mismatch_rel, m->injective);
    CHECK(worst_p95 < 0.15, "ground-truth pattern: p95 strain %g", worst_p95);
    /* The sleeve caps are about 10 % shorter than the armholes in this pattern (ease); the
     * underarm self-seams and the shoulder and side seams are exact mirror images. */
    int32_t mirrored = 0;
    for (int32_t s = 0; s < m->seam_count; ++s)
        mirrored += m->seams[s].reflection_residual_mm < 0.5 && m->seams[s].mismatch_rel < 1e-3;
    CHECK(m->max_seam_mismatch_rel < 0.12, "ground-truth seams nearly match: %g", m->max_seam_mismatch_rel);
    CHECK(mirrored >= 6, "ground-truth: %d seams are exact mirrors (residual < 0.5 mm)", (int)mirrored);
    int32_t flipped = 0;
    for (int32_t p = 0; p < m->panel_count; ++p)
        flipped += m->panels[p].flipped_triangles;
    CHECK(flipped == 0, "ground-truth pattern: %d flipped triangles", (int)flipped);
    pz_metrics_free(&m);
    free(uv);
}

static void test_shared_tshirt(void)
{
    const char *dir = test_shared_data();
    char path[4096];
    struct stat info;
    if (!dir)
        return;
    snprintf(path, sizeof path, "%s/garments/diffavatar-tshirt.obj", dir);
    if (stat(path, &info) != 0) {
        char why[4200];
        snprintf(why, sizeof why, "%s missing", path);
        test_skip_part(why);
        return;
    }
    pz_mesh *mesh = NULL;
    REQUIRE_OK(pz_mesh_read(path, &mesh, &ctx), ctx);
    pz_mesh_to_mm(mesh, PZ_UNITS_AUTO, NULL);
    int32_t *panels = malloc((size_t)mesh->face_count * sizeof(int32_t)), panel_count = 0;
    uint8_t *extra = NULL;
    REQUIRE(panels, "out of memory");
    REQUIRE_OK(pz_pattern_panels_from_uv(mesh, panels, &panel_count, &extra, &ctx), ctx);
    CHECK(panel_count == 4, "tshirt: 4 UV panels, got %d", (int)panel_count);
    pz_pattern *pattern = NULL;
    REQUIRE_OK(pz_pattern_build(mesh, panels, extra, NULL, path, &pattern, &ctx), ctx);
    CHECK(panels_are_disks(pattern), "tshirt: every panel a disk");
    CHECK(pattern->seam_count >= 4, "tshirt: %d seams", (int)pattern->seam_count);
    check_seams(pattern, "tshirt");
    printf("tshirt: %d panels, %d seams, %d -> %d vertices\n", (int)pattern->panel_count, (int)pattern->seam_count,
           (int)mesh->vertex_count, (int)pattern->mesh->vertex_count);
    measure_ground_truth(mesh, pattern);
    pz_pattern_free(&pattern);

    /* The whole shirt as one panel: 4 loops (hem, neck, two sleeves) joined by 3 cut paths. */
    memset(panels, 0, (size_t)mesh->face_count * sizeof(int32_t));
    REQUIRE_OK(pz_pattern_build(mesh, panels, NULL, NULL, path, &pattern, &ctx), ctx);
    CHECK(pattern->panel_count == 1 && panels_are_disks(pattern), "tshirt as one panel: cut into a disk");
    CHECK(pattern->seam_count >= 3, "tshirt as one panel: %d self-seams", (int)pattern->seam_count);
    check_seams(pattern, "tshirt one panel");
    pz_pattern_free(&pattern);
    free(extra);
    free(panels);
    pz_mesh_free(&mesh);
}

/* Reads "A\nB\n" then pairs (a seam file) or "tip\n" then pairs (a dart file); returns the pair count. */
static int32_t read_pairs(const char *path, int header_count, int32_t *header, int32_t *first, int32_t *second,
                          int32_t capacity)
{
    FILE *file = fopen(path, "r");
    REQUIRE(file, "cannot open %s", path);
    for (int i = 0; i < header_count; ++i)
        REQUIRE(fscanf(file, "%d", &header[i]) == 1, "%s: header", path);
    int32_t count = 0;
    while (count < capacity && fscanf(file, "%d %d", &first[count], &second[count]) == 2)
        ++count;
    fclose(file);
    return count;
}

/*
 * The two skirt panels of ../shared/data/seams/ as one garment (panel K's
 * vertices offset by the vertex count before it) with their two seams and
 * four darts given explicitly: the seams map onto the right pieces with equal
 * 3D side lengths, the darts onto one panel each.
 */
static void test_shared_skirt(void)
{
    const char *dir = test_shared_data();
    char path[4096];
    struct stat info;
    if (!dir)
        return;
    snprintf(path, sizeof path, "%s/seams/skirt_0.obj", dir);
    if (stat(path, &info) != 0) {
        char why[4200];
        snprintf(why, sizeof why, "%s missing", path);
        test_skip_part(why);
        return;
    }
    pz_mesh *pieces[2] = {NULL, NULL};
    for (int k = 0; k < 2; ++k) {
        snprintf(path, sizeof path, "%s/seams/skirt_%d.obj", dir, k);
        REQUIRE_OK(pz_mesh_read(path, &pieces[k], &ctx), ctx);
    }
    int32_t offset[2] = {0, pieces[0]->vertex_count};
    pz_mesh *garment = NULL;
    REQUIRE_OK(pz_mesh_create(pieces[0]->vertex_count + pieces[1]->vertex_count,
                              pieces[0]->face_count + pieces[1]->face_count, &garment, &ctx), ctx);
    int32_t *panels = malloc((size_t)garment->face_count * sizeof(int32_t));
    REQUIRE(panels, "out of memory");
    for (int k = 0, face_base = 0; k < 2; face_base += pieces[k]->face_count, ++k) {
        memcpy(garment->positions + 3 * offset[k], pieces[k]->positions,
               (size_t)pieces[k]->vertex_count * 3 * sizeof(double));
        for (int32_t c = 0; c < 3 * pieces[k]->face_count; ++c)
            garment->faces[3 * face_base + c] = pieces[k]->faces[c] + offset[k];
        for (int32_t f = 0; f < pieces[k]->face_count; ++f)
            panels[face_base + f] = k;
    }
    pz_mesh_to_mm(garment, PZ_UNITS_AUTO, NULL);
    pz_seam seams[2];
    pz_dart darts[4];
    int32_t buffer[6][2][64];
    for (int s = 0; s < 2; ++s) {
        int32_t ends[2];
        snprintf(path, sizeof path, "%s/seams/seam%d.txt", dir, s);
        seams[s].pair_count = read_pairs(path, 2, ends, buffer[s][0], buffer[s][1], 64);
        for (int32_t i = 0; i < seams[s].pair_count; ++i) {
            buffer[s][0][i] += offset[ends[0]];
            buffer[s][1][i] += offset[ends[1]];
        }
        seams[s].side_a = buffer[s][0];
        seams[s].side_b = buffer[s][1];
    }
    for (int d = 0; d < 4; ++d) {
        int k = d / 2;
        snprintf(path, sizeof path, "%s/seams/patch_%d_dart_%d.txt", dir, k, d % 2);
        darts[d].pair_count = read_pairs(path, 1, &darts[d].tip, buffer[2 + d][0], buffer[2 + d][1], 64);
        darts[d].tip += offset[k];
        for (int32_t i = 0; i < darts[d].pair_count; ++i) {
            buffer[2 + d][0][i] += offset[k];
            buffer[2 + d][1][i] += offset[k];
        }
        darts[d].leg_a = buffer[2 + d][0];
        darts[d].leg_b = buffer[2 + d][1];
    }
    pz_correspondences given = {.seam_count = 2, .seams = seams, .dart_count = 4, .darts = darts};
    pz_pattern *pattern = NULL;
    REQUIRE_OK(pz_pattern_build(garment, panels, NULL, &given, "skirt", &pattern, &ctx), ctx);
    CHECK(pattern->panel_count == 2 && panels_are_disks(pattern), "skirt: two disk panels");
    CHECK(pattern->seam_count == 2 && pattern->dart_count == 4, "skirt: %d seams, %d darts (no cut: pieces apart)",
          (int)pattern->seam_count, (int)pattern->dart_count);
    for (int s = 0; s < pattern->seam_count; ++s) {
        const pz_seam *seam = &pattern->seams[s];
        double la = side_length(pattern, seam->side_a, seam->pair_count);
        double lb = side_length(pattern, seam->side_b, seam->pair_count);
        CHECK(seam->panel_a == 0 && seam->panel_b == 1 && fabs(la - lb) < 1e-9 * la && la > 0,
              "skirt seam %d: panels %d-%d, 3D sides %g %g", s, (int)seam->panel_a, (int)seam->panel_b, la, lb);
    }
    for (int d = 0; d < pattern->dart_count; ++d)
        CHECK(pattern->darts[d].panel == d / 2 && pattern->vertex_origin[pattern->darts[d].tip] == darts[d].tip,
              "skirt dart %d on panel %d", d, (int)pattern->darts[d].panel);
    pz_pattern_free(&pattern);
    free(panels);
    pz_mesh_free(&garment);
    pz_mesh_free(&pieces[0]);
    pz_mesh_free(&pieces[1]);
}

int main(void)
{
    pz_ctx_init(&ctx);
    ctx.quiet = 1;
    test_bodice();
    test_tube();
    test_ring();
    test_closed_ring();
    test_random_panels();
    test_refusals();
    test_panels_from_uv();
    test_explicit();
    test_correspondences_clear();
    test_slit_is_dart();
    test_shared_tshirt();
    test_shared_skirt();
    if (!test_shared_data())
        test_skip_part("the T-shirt and the skirt's panels (no ../shared/data)");
    return test_finish();
}

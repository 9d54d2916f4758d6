/*
 * tests/segment/test_truing.c -- seam truing (segment/truing.c).
 *
 *  - a staircase cut along a flat grid becomes nearly the straight line it
 *    approximates: its vertices move onto the line (RMS distance down by a
 *    factor of 3 or more), its mean turn falls below 15 degrees, everything
 *    stays in the plane, no face flips or collapses, the ends on the border
 *    stay, connectivity is untouched; a staircase of square steps (which
 *    runs round two sides of triangles) improves less but collapses nothing;
 *  - a pose that is an affine image of the rest pose stays exactly that
 *    image after truing (the poses follow barycentrically);
 *  - on a cylinder the moved vertices stay on the surface;
 *  - an L-shaped seam keeps its corner where it was;
 *  - bad arguments: PZ_ERR_USAGE.
 *
 * SPDX-License-Identifier: GPL-3.0-or-later
 */
#include "segment/segment.h"

#include <math.h>

#include "test_meshes.h"
#include "test_util.h"

static pz_ctx ctx;

/* The edge between grid vertices a and b, or -1. */
static int32_t edge_between(const pz_topology *t, int32_t a, int32_t b)
{
    for (int32_t e = 0; e < t->edge_count; ++e) {
        int32_t h = t->edge_halfedge[2 * e];
        int32_t x = pz_he_from(t, h), y = pz_he_to(t, h);
        if ((x == a && y == b) || (x == b && y == a))
            return e;
    }
    return -1;
}

/* Cuts the path along grid edges that follows the line y = y0 + slope x (grid units, 0 <= slope <= 1)
 * from x = 0 to x = columns: horizontal edges, and the rising diagonals where the line climbs a row (the
 * path a field-aligned trace leaves after its own smoothing: never two sides of one triangle); writes its
 * vertices into path and returns their count. */
static int32_t staircase(const pz_topology *t, int columns, double y0, double slope, uint8_t *cut, int32_t *path)
{
    int vertex_columns = columns + 1, j = (int)lround(y0), count = 0;
    path[count++] = j * vertex_columns;
    for (int i = 0; i < columns; ++i) {
        int up = y0 + slope * (i + 1) > j + 0.5;
        int32_t e = edge_between(t, j * vertex_columns + i, (j + up) * vertex_columns + i + 1);
        REQUIRE(e >= 0, "no edge");
        cut[e] = 1;
        j += up;
        path[count++] = j * vertex_columns + i + 1;
    }
    return count;
}

/* The same line by horizontal and vertical edges only: every step runs round two sides of a triangle,
 * whose three corners cannot all move onto the line (the safety must keep that triangle alive). */
static int32_t square_staircase(const pz_topology *t, int columns, double y0, double slope, uint8_t *cut,
                                int32_t *path)
{
    int vertex_columns = columns + 1, i = 0, j = (int)lround(y0), count = 0;
    path[count++] = j * vertex_columns;
    while (i < columns) {
        int up = y0 + slope * (i + 0.5) > j + 0.5;
        int32_t next = up ? (j + 1) * vertex_columns + i : j * vertex_columns + i + 1;
        int32_t e = edge_between(t, path[count - 1], next);
        REQUIRE(e >= 0, "no edge");
        cut[e] = 1;
        j += up;
        i += !up;
        path[count++] = next;
    }
    return count;
}

static double distance_to_line(const double *p, double y0, double slope, double cell)
{
    /* the line y = cell * y0 + slope x in millimetres */
    return fabs(p[1] - cell * y0 - slope * p[0]) / sqrt(1 + slope * slope);
}

static void test_flat_staircase(int square)
{
    const int columns = 30, rows = 30;
    const double cell = 10, y0 = 6, slope = 0.4;
    pz_mesh *mesh = test_grid(columns, rows, TEST_GRID_FLAT, 0, &ctx);
    for (int32_t i = 0; i < 3 * mesh->vertex_count; ++i)
        mesh->positions[i] *= cell;
    mesh->unit_scale = 1;
    /* A pose that is an affine image of the rest pose. */
    mesh->pose_count = 1;
    mesh->poses = malloc((size_t)mesh->vertex_count * 3 * sizeof(double));
    REQUIRE(mesh->poses, "out of memory");
    for (int32_t v = 0; v < mesh->vertex_count; ++v) {
        const double *p = mesh->positions + 3 * v;
        double *q = mesh->poses + 3 * v;
        q[0] = 2 * p[0] + 0.3 * p[1] + 5;
        q[1] = p[1] - 7;
        q[2] = 0.1 * p[0];
    }
    pz_topology *topology = test_topology(mesh, &ctx);
    uint8_t *cut = calloc((size_t)topology->edge_count, 1);
    int32_t *path = malloc((size_t)mesh->vertex_count * sizeof(int32_t));
    int32_t *faces_before = malloc((size_t)mesh->face_count * 3 * sizeof(int32_t));
    double *rest = malloc((size_t)mesh->vertex_count * 3 * sizeof(double));
    REQUIRE(cut && path && faces_before && rest, "out of memory");
    int32_t n = square ? square_staircase(topology, columns, y0, slope, cut, path)
                       : staircase(topology, columns, y0, slope, cut, path);
    memcpy(faces_before, mesh->faces, (size_t)mesh->face_count * 3 * sizeof(int32_t));
    memcpy(rest, mesh->positions, (size_t)mesh->vertex_count * 3 * sizeof(double));
    double before = 0;
    for (int32_t i = 0; i < n; ++i)
        before += pow(distance_to_line(mesh->positions + 3 * path[i], y0, slope, cell), 2);
    before = sqrt(before / n);

    pz_truing_result result;
    REQUIRE_OK(pz_segment_true_seams(mesh, topology, cut, NULL, &result, &ctx), ctx);
    double after = 0, worst_z = 0;
    for (int32_t i = 0; i < n; ++i)
        after += pow(distance_to_line(mesh->positions + 3 * path[i], y0, slope, cell), 2);
    after = sqrt(after / n);
    for (int32_t v = 0; v < mesh->vertex_count; ++v)
        worst_z = fmax(worst_z, fabs(mesh->positions[3 * v + 2]));
    printf("flat %s: %d vertices, RMS distance to the line %.2f -> %.2f mm, mean turn %.1f -> %.1f deg, "
           "%d moved, %d relaxed, at most %.2f mm\n",
           square ? "square staircase" : "staircase", (int)n, before, after, result.mean_turn_before_deg, result.mean_turn_after_deg,
           (int)result.moved_vertices, (int)result.relaxed_vertices, result.max_move_mm);
    /* The square staircase cannot straighten where its triangles would collapse: less is asked. */
    CHECK(after < before / (square ? 1.5 : 3), "RMS distance to the line %.2f -> %.2f mm", before, after);
    CHECK(result.mean_turn_before_deg > 30 && result.mean_turn_after_deg < (square ? 40 : 15),
          "mean turn %.1f -> %.1f degrees", result.mean_turn_before_deg, result.mean_turn_after_deg);
    CHECK(result.max_move_mm <= 0.5 * cell + 1e-9, "a vertex moved %.2f mm", result.max_move_mm);
    CHECK(worst_z < 1e-9, "a vertex left the plane by %g", worst_z);
    CHECK(memcmp(faces_before, mesh->faces, (size_t)mesh->face_count * 3 * sizeof(int32_t)) == 0,
          "the faces changed");
    for (int end = 0; end < 2; ++end) {
        int32_t v = path[end ? n - 1 : 0];
        CHECK(memcmp(rest + 3 * v, mesh->positions + 3 * v, 3 * sizeof(double)) == 0, "border end %d moved", (int)v);
    }
    int32_t bad_faces = 0;
    for (int32_t f = 0; f < mesh->face_count; ++f) {
        const int32_t *face = mesh->faces + 3 * f;
        const double *a = mesh->positions + 3 * face[0], *b = mesh->positions + 3 * face[1],
                     *c = mesh->positions + 3 * face[2];
        double area = ((b[0] - a[0]) * (c[1] - a[1]) - (b[1] - a[1]) * (c[0] - a[0])) / 2;
        bad_faces += !(area > 0.2 * cell * cell / 2);
    }
    CHECK(bad_faces == 0, "%d faces flipped or collapsed below a fifth of their area", (int)bad_faces);
    double pose_error = 0;
    for (int32_t v = 0; v < mesh->vertex_count; ++v) {
        const double *p = mesh->positions + 3 * v, *q = mesh->poses + 3 * v;
        double expected[3] = {2 * p[0] + 0.3 * p[1] + 5, p[1] - 7, 0.1 * p[0]};
        for (int d = 0; d < 3; ++d)
            pose_error = fmax(pose_error, fabs(q[d] - expected[d]));
    }
    CHECK(pose_error < 1e-9, "the pose is off its affine image by %g mm", pose_error);
    free(rest);
    free(faces_before);
    free(path);
    free(cut);
    pz_topology_free(&topology);
    pz_mesh_free(&mesh);
}

static void test_cylinder(void)
{
    const int columns = 48, rows = 30;
    const double radius = 100, height = 10;
    pz_mesh *mesh = test_grid(columns, rows, TEST_GRID_TUBE, 0, &ctx);
    for (int32_t v = 0; v < mesh->vertex_count; ++v) {
        mesh->positions[3 * v] *= radius;
        mesh->positions[3 * v + 1] *= radius;
        mesh->positions[3 * v + 2] *= height;
    }
    mesh->unit_scale = 1;
    pz_topology *topology = test_topology(mesh, &ctx);
    uint8_t *cut = calloc((size_t)topology->edge_count, 1);
    REQUIRE(cut, "out of memory");
    /* A helix on edges: up one row, straight or along the diagonal one column over, every other row. */
    int i = 0;
    for (int j = 0; j < rows; ++j) {
        int over = j % 2;
        int32_t a = j * columns + i % columns, b = (j + 1) * columns + (i + over) % columns;
        cut[edge_between(topology, a, b)] = 1;
        i += over;
    }
    pz_truing_result result;
    REQUIRE_OK(pz_segment_true_seams(mesh, topology, cut, NULL, &result, &ctx), ctx);
    double inner = radius * cos(3.14159265358979323846 / columns), worst = 0;
    for (int32_t v = 0; v < mesh->vertex_count; ++v) {
        const double *p = mesh->positions + 3 * v;
        double r = sqrt(p[0] * p[0] + p[1] * p[1]);
        worst = fmax(worst, fmax(r - radius, inner - r));
    }
    printf("cylinder: %d moved, mean turn %.1f -> %.1f degrees, worst distance off the surface band %.2g mm\n",
           (int)result.moved_vertices, result.mean_turn_before_deg, result.mean_turn_after_deg, worst);
    CHECK(result.moved_vertices > 0, "nothing moved");
    CHECK(worst < 1e-9, "a vertex left the cylinder's triangles by %g mm", worst);
    CHECK(result.mean_turn_after_deg < result.mean_turn_before_deg / 2, "mean turn %.1f -> %.1f degrees",
          result.mean_turn_before_deg, result.mean_turn_after_deg);
    free(cut);
    pz_topology_free(&topology);
    pz_mesh_free(&mesh);
}

static void test_corner_stays(void)
{
    const int columns = 20, rows = 20;
    pz_mesh *mesh = test_grid(columns, rows, TEST_GRID_FLAT, 0, &ctx);
    mesh->unit_scale = 1;
    pz_topology *topology = test_topology(mesh, &ctx);
    uint8_t *cut = calloc((size_t)topology->edge_count, 1);
    REQUIRE(cut, "out of memory");
    int vc = columns + 1;
    /* From the left border along row 10 to column 10, then up column 10 to the top border. */
    for (int i = 0; i < 10; ++i)
        cut[edge_between(topology, 10 * vc + i, 10 * vc + i + 1)] = 1;
    for (int j = 10; j < rows; ++j)
        cut[edge_between(topology, j * vc + 10, (j + 1) * vc + 10)] = 1;
    double corner[3];
    memcpy(corner, mesh->positions + 3 * (10 * vc + 10), sizeof corner);
    pz_truing_result result;
    REQUIRE_OK(pz_segment_true_seams(mesh, topology, cut, NULL, &result, &ctx), ctx);
    CHECK(memcmp(corner, mesh->positions + 3 * (10 * vc + 10), sizeof corner) == 0, "the corner moved");
    /* Straight runs are already smooth: nothing should move far. */
    CHECK(result.max_move_mm < 0.05, "a vertex of a straight seam moved %.3f", result.max_move_mm);
    free(cut);
    pz_topology_free(&topology);
    pz_mesh_free(&mesh);
}

static void test_bad_arguments(void)
{
    pz_mesh *mesh = test_grid(2, 2, TEST_GRID_FLAT, 0, &ctx);
    pz_topology *topology = test_topology(mesh, &ctx);
    CHECK(pz_segment_true_seams(NULL, topology, (const uint8_t *)"", NULL, NULL, &ctx) == PZ_ERR_USAGE, "no mesh");
    CHECK(pz_segment_true_seams(mesh, topology, NULL, NULL, NULL, &ctx) == PZ_ERR_USAGE, "no cuts");
    pz_topology_free(&topology);
    pz_mesh_free(&mesh);
}

int main(void)
{
    pz_ctx_init(&ctx);
    test_flat_staircase(0);
    test_flat_staircase(1);
    test_cylinder();
    test_corner_stays();
    test_bad_arguments();
    return test_finish();
}

/*
 * tests/mesh/test_mesh.c -- the mesh object itself (mesh/mesh.c): copies,
 * poses, units and the vertical axis.
 *
 * SPDX-License-Identifier: GPL-3.0-or-later
 */
#include "test_meshes.h"

static pz_ctx ctx;

/* A box-shaped grid scaled to the given extents. */
static pz_mesh *box_grid(double size_x, double size_y, double size_z)
{
    pz_mesh *mesh = test_grid(4, 4, TEST_GRID_FLAT, 0, &ctx);
    for (int32_t v = 0; v < mesh->vertex_count; ++v) {
        double *p = mesh->positions + 3 * v;
        double u = p[0] / 4.0, w = p[1] / 4.0;
        p[0] = u * size_x;
        p[1] = w * size_y;
        p[2] = (u + w) * 0.5 * size_z; /* a slanted sheet spanning all three extents */
    }
    return mesh;
}

static void test_units(void)
{
    static const struct {
        double extent;          /* largest extent in file units */
        pz_units expected;
        int plausible;
    } cases[] = {
        {1.2, PZ_UNITS_M, 1},     /* a 1.2 m garment in metres */
        {60.0, PZ_UNITS_CM, 1},   /* a 60 cm skirt in centimetres */
        {600.0, PZ_UNITS_MM, 1},  /* a 600 mm bodice in millimetres */
        {0.3, PZ_UNITS_M, 1},     /* a 30 cm sleeve piece in metres */
        {9.3, PZ_UNITS_CM, 0},    /* fits nothing: 93 mm in cm, 9.3 m in m */
    };
    for (size_t i = 0; i < sizeof cases / sizeof cases[0]; ++i) {
        pz_mesh *mesh = box_grid(cases[i].extent, cases[i].extent / 2, cases[i].extent / 3);
        pz_units guess = pz_mesh_guess_units(mesh);
        CHECK(guess == cases[i].expected, "extent %g: guessed %s", cases[i].extent, pz_units_str(guess));
        CHECK(pz_mesh_units_plausible(mesh, PZ_UNITS_AUTO) == cases[i].plausible, "extent %g: plausible",
              cases[i].extent);
        pz_units used = PZ_UNITS_AUTO;
        pz_mesh_to_mm(mesh, PZ_UNITS_AUTO, &used);
        double lo[3], hi[3];
        pz_mesh_bbox(mesh, lo, hi);
        CHECK(fabs((hi[0] - lo[0]) - cases[i].extent * pz_units_to_mm(used)) < 1e-9 * cases[i].extent * 1000,
              "extent %g scaled to mm", cases[i].extent);
        CHECK(mesh->unit_scale == pz_units_to_mm(used), "unit_scale records the scale");
        pz_mesh_free(&mesh);
    }
    pz_units parsed;
    CHECK(pz_units_parse("cm", &parsed, &ctx) == PZ_OK && parsed == PZ_UNITS_CM, "parse cm");
    CHECK(pz_units_parse("inch", &parsed, &ctx) == PZ_ERR_USAGE && strstr(ctx.error, "inch"), "refuse inch");
}

static void test_vertical_axis(void)
{
    double axis[3];
    pz_mesh *z_up = box_grid(300, 200, 600);
    pz_mesh_vertical_axis(z_up, axis);
    CHECK(axis[0] == 0 && axis[1] == 0 && axis[2] == 1, "taller along z: z is up");
    pz_mesh *y_up = box_grid(700, 600, 250); /* a t-shirt with spread sleeves, y up */
    pz_mesh_vertical_axis(y_up, axis);
    CHECK(axis[0] == 0 && axis[1] == 1 && axis[2] == 0, "taller along y than z: y is up, x never");
    pz_mesh_free(&z_up);
    pz_mesh_free(&y_up);
}

static void test_copy_and_poses(void)
{
    pz_mesh *mesh = test_grid(3, 2, TEST_GRID_FLAT, 0, &ctx);
    double *moved = malloc((size_t)mesh->vertex_count * 3 * sizeof(double));
    REQUIRE(moved, "out of memory");
    for (int32_t i = 0; i < 3 * mesh->vertex_count; ++i)
        moved[i] = mesh->positions[i] + 1.0;
    REQUIRE_OK(pz_mesh_add_pose(mesh, moved, &ctx), ctx);
    REQUIRE_OK(pz_mesh_add_pose(mesh, mesh->positions, &ctx), ctx);
    CHECK(mesh->pose_count == 2, "two poses");
    CHECK(mesh->poses[0] == moved[0] && mesh->poses[3 * mesh->vertex_count] == mesh->positions[0], "pose order");
    mesh->face_labels = calloc((size_t)mesh->face_count, sizeof(int32_t));
    mesh->label_names = calloc(1, sizeof(char *));
    REQUIRE(mesh->face_labels && mesh->label_names, "out of memory");
    mesh->label_count = 1;
    mesh->label_names[0] = test_strdup("front");
    pz_mesh *copy = NULL;
    REQUIRE_OK(pz_mesh_copy(mesh, &copy, &ctx), ctx);
    CHECK(copy->positions != mesh->positions && copy->poses != mesh->poses, "deep copy");
    CHECK(memcmp(copy->poses, mesh->poses, (size_t)2 * 3 * mesh->vertex_count * sizeof(double)) == 0, "poses copied");
    CHECK(strcmp(copy->label_names[0], "front") == 0 && copy->label_names[0] != mesh->label_names[0], "names copied");
    pz_mesh_to_mm(copy, PZ_UNITS_CM, NULL);
    CHECK(copy->poses[0] == 10.0 * mesh->poses[0], "poses scale with the rest pose");
    pz_mesh_free(&copy);
    pz_mesh_free(&mesh);
    CHECK(mesh == NULL, "free sets the pointer to NULL");
    pz_mesh_free(&mesh); /* freeing NULL is fine */
    free(moved);
}

int main(void)
{
    pz_ctx_init(&ctx);
    ctx.quiet = 1;
    test_units();
    test_vertical_axis();
    test_copy_and_poses();
    return test_finish();
}

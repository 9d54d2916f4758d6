/*
 * tests/mesh/test_validate.c -- every validation problem on a small mesh
 * that has exactly that problem (and no other), the repairs of
 * pz_mesh_prepare fixing what they claim and refusing what they cannot, and
 * pz_mesh_drop_unreferenced renumbering faces and poses.
 *
 * SPDX-License-Identifier: GPL-3.0-or-later
 */
#include "test_meshes.h"

#include <math.h>
#include <string.h>

static pz_ctx ctx;

/* Validation counts, in the struct's order, and the expected first line. */
typedef struct expected {
    int32_t nonfinite, bad, degenerate, duplicate, nonmanifold_edges, nonmanifold_vertices, inconsistent,
        unreferenced;
    const char *first_line;  /* a substring of problems[0], or NULL when nothing is expected */
} expected;

static void check_validation(const pz_mesh *mesh, const char *name, expected want)
{
    pz_validation v;
    REQUIRE_OK(pz_mesh_validate(mesh, &v, &ctx), ctx);
    CHECK(v.nonfinite_coordinates == want.nonfinite, "%s: non-finite %d", name, (int)v.nonfinite_coordinates);
    CHECK(v.bad_indices == want.bad, "%s: bad indices %d", name, (int)v.bad_indices);
    CHECK(v.degenerate_faces == want.degenerate, "%s: degenerate %d", name, (int)v.degenerate_faces);
    CHECK(v.duplicate_faces == want.duplicate, "%s: duplicates %d", name, (int)v.duplicate_faces);
    CHECK(v.nonmanifold_edges == want.nonmanifold_edges, "%s: non-manifold edges %d", name, (int)v.nonmanifold_edges);
    CHECK(v.nonmanifold_vertices == want.nonmanifold_vertices, "%s: non-manifold vertices %d", name,
          (int)v.nonmanifold_vertices);
    CHECK(v.inconsistent_edges == want.inconsistent, "%s: inconsistent %d", name, (int)v.inconsistent_edges);
    CHECK(v.unreferenced_vertices == want.unreferenced, "%s: unreferenced %d", name, (int)v.unreferenced_vertices);
    int kinds = (want.nonfinite > 0) + (want.bad > 0) + (want.degenerate > 0) + (want.duplicate > 0) +
                (want.nonmanifold_edges > 0) + (want.nonmanifold_vertices > 0) + (want.inconsistent > 0) +
                (want.unreferenced > 0);
    CHECK(v.problem_count == kinds, "%s: %d problem lines, expected %d", name, (int)v.problem_count, kinds);
    if (want.first_line && v.problem_count > 0)
        CHECK(strstr(v.problems[0], want.first_line) != NULL, "%s: first line '%s' lacks '%s'", name, v.problems[0],
              want.first_line);
    for (int32_t i = 0; i < v.problem_count; ++i)
        CHECK(strchr(v.problems[i], '\n') == NULL, "%s: problem line %d is one line", name, (int)i);
    int only_unreferenced = kinds == (want.unreferenced > 0);
    CHECK(pz_validation_ok(&v) == only_unreferenced, "%s: pz_validation_ok", name);
    pz_validation_clear(&v);
    CHECK(v.problems == NULL && v.problem_count == 0, "%s: clear zeroes", name);
}

static const double five[] = {0, 0, 0, 1, 0, 0, 0, 1, 0, -1, 0, 0, 0, -1, 0};

static void test_each_problem(void)
{
    pz_mesh *mesh = test_grid(3, 2, TEST_GRID_FLAT, 0, &ctx);
    check_validation(mesh, "clean grid", (expected){0, 0, 0, 0, 0, 0, 0, 0, NULL});
    pz_mesh_free(&mesh);

    static const int32_t bowtie[] = {0, 1, 2, 0, 3, 4};
    mesh = test_mesh_from(5, five, 2, bowtie, &ctx);
    check_validation(mesh, "bow-tie", (expected){0, 0, 0, 0, 0, 1, 0, 0, "1 non-manifold vertex,"});
    pz_mesh_free(&mesh);

    /* Three fins on the edge 0-1 (off the plane, so none is degenerate). */
    static const double fins[] = {0, 0, 0, 1, 0, 0, 0, 1, 0, 0, 0, 1, 0, -1, 1};
    static const int32_t three_on_edge[] = {0, 1, 2, 1, 0, 3, 0, 1, 4};
    mesh = test_mesh_from(5, fins, 3, three_on_edge, &ctx);
    check_validation(mesh, "three faces on one edge",
                     (expected){0, 0, 0, 0, 1, 0, 0, 0, "1 non-manifold edge, with more than two faces (first: vertices 0-1)"});
    pz_mesh_free(&mesh);

    /* Flip face 1 of a 3 x 2 grid (the upper triangle of the corner cell):
     * its two interior edges now run the same way as their neighbours'. */
    mesh = test_grid(3, 2, TEST_GRID_FLAT, 0, &ctx);
    int32_t swap = mesh->faces[3 * 1 + 1];
    mesh->faces[3 * 1 + 1] = mesh->faces[3 * 1 + 2];
    mesh->faces[3 * 1 + 2] = swap;
    check_validation(mesh, "flipped face", (expected){0, 0, 0, 0, 0, 0, 2, 0, "2 inconsistently oriented edges"});
    pz_mesh_free(&mesh);

    /* A copy of face 3, rotated, and a reversed copy of face 7. */
    mesh = test_grid(3, 2, TEST_GRID_FLAT, 2, &ctx);
    int32_t copies[6] = {mesh->faces[10], mesh->faces[11], mesh->faces[9], mesh->faces[21], mesh->faces[23],
                         mesh->faces[22]};
    memcpy(mesh->faces + 3 * 12, copies, sizeof copies);
    check_validation(mesh, "duplicate faces", (expected){0, 0, 0, 2, 0, 0, 0, 0, "(first: face 12 repeats face 3)"});
    pz_mesh_free(&mesh);

    /* Face (1 0 3) with 3 on the line through 0 and 1: zero area. */
    static const double collinear[] = {0, 0, 0, 1, 0, 0, 0, 1, 0, 2, 0, 0};
    static const int32_t sliver[] = {0, 1, 2, 1, 0, 3};
    mesh = test_mesh_from(4, collinear, 2, sliver, &ctx);
    check_validation(mesh, "zero-area face", (expected){0, 0, 1, 0, 0, 0, 0, 0, "1 degenerate (zero-area) face (first: face 1)"});
    /* The threshold is relative: the same shape in metres or microns is just as degenerate or not. */
    for (int32_t i = 0; i < 12; ++i)
        mesh->positions[i] *= 1e-6;
    check_validation(mesh, "zero-area face, scaled", (expected){0, 0, 1, 0, 0, 0, 0, 0, NULL});
    mesh->positions[3 * 3 + 1] = 1e-9;  /* lift vertex 3 by 1/1000 of the size: a real, thin face */
    check_validation(mesh, "thin face", (expected){0, 0, 0, 0, 0, 0, 0, 0, NULL});
    pz_mesh_free(&mesh);

    static const int32_t triangle[] = {0, 1, 2};
    mesh = test_mesh_from(3, five, 1, triangle, &ctx);
    mesh->positions[4] = NAN;
    check_validation(mesh, "NaN coordinate", (expected){1, 0, 0, 0, 0, 0, 0, 0, "(first: vertex 1)"});
    mesh->positions[4] = 0;
    double pose[9] = {0, 0, 0, 1, 0, 0, 0, 1, INFINITY};
    REQUIRE_OK(pz_mesh_add_pose(mesh, pose, &ctx), ctx);
    check_validation(mesh, "infinite pose coordinate", (expected){1, 0, 0, 0, 0, 0, 0, 0, "(first: vertex 2)"});
    pz_mesh_free(&mesh);

    mesh = test_mesh_from(5, five, 1, triangle, &ctx);
    check_validation(mesh, "unreferenced vertices", (expected){0, 0, 0, 0, 0, 0, 0, 2, "2 unreferenced vertices (first: vertex 3)"});
    pz_mesh_free(&mesh);

    static const int32_t out_of_range[] = {0, 1, 2, 0, 2, 9};
    mesh = test_mesh_from(3, five, 2, out_of_range, &ctx);
    check_validation(mesh, "index out of range", (expected){0, 1, 0, 0, 0, 0, 0, 0, "(first: face 1)"});
    pz_mesh_free(&mesh);

    /* A repeated index is a bad index and a zero-area face at once. */
    static const int32_t repeated[] = {0, 1, 2, 2, 1, 1};
    mesh = test_mesh_from(3, five, 2, repeated, &ctx);
    check_validation(mesh, "repeated index", (expected){0, 1, 1, 0, 0, 0, 0, 0, "1 bad face index"});
    pz_mesh_free(&mesh);
}

static void test_moebius_band(void)
{
    pz_mesh *mesh = test_moebius(&ctx);
    check_validation(mesh, "Moebius band", (expected){0, 0, 0, 0, 0, 0, 1, 0, "1 inconsistently oriented edge"});
    CHECK(pz_mesh_prepare(mesh, "band.obj", PZ_REPAIR_ORIENT, &ctx) == PZ_ERR_INVALID_MESH,
          "a non-orientable band cannot be oriented");
    CHECK(strstr(ctx.error, "band.obj: invalid mesh: ") == ctx.error && strstr(ctx.error, "inconsistently"),
          "message: %s", ctx.error);
    pz_mesh_free(&mesh);
}

static int grid_is_valid(const pz_mesh *mesh)
{
    pz_validation v;
    REQUIRE_OK(pz_mesh_validate(mesh, &v, &ctx), ctx);
    int ok = pz_validation_ok(&v) && v.unreferenced_vertices == 0;
    pz_validation_clear(&v);
    return ok;
}

static void test_repairs(void)
{
    /* Orientation: a minority of flipped faces are flipped back. */
    pz_mesh *mesh = test_grid(3, 2, TEST_GRID_FLAT, 0, &ctx);
    int32_t original[36];
    memcpy(original, mesh->faces, sizeof original);
    for (int f = 2; f <= 5; f += 3) {
        int32_t swap = mesh->faces[3 * f + 1];
        mesh->faces[3 * f + 1] = mesh->faces[3 * f + 2];
        mesh->faces[3 * f + 2] = swap;
    }
    CHECK(pz_mesh_prepare(mesh, "flipped.obj", PZ_REPAIR_NONE, &ctx) == PZ_ERR_INVALID_MESH, "refused unrepaired");
    CHECK(strstr(ctx.error, "flipped.obj") && strstr(ctx.error, "inconsistently"), "message: %s", ctx.error);
    CHECK(pz_mesh_prepare(mesh, "flipped.obj", PZ_REPAIR_ORIENT, &ctx) == PZ_OK, "oriented: %s", ctx.error);
    CHECK(memcmp(mesh->faces, original, sizeof original) == 0, "orientation restored to the majority's");
    pz_mesh_free(&mesh);

    /* A whole component upside down is flipped too (its majority is its own). */
    mesh = test_grid(2, 1, TEST_GRID_FLAT, 0, &ctx);
    for (int f = 0; f < 4; ++f)
        if (f != 1) {
            int32_t swap = mesh->faces[3 * f + 1];
            mesh->faces[3 * f + 1] = mesh->faces[3 * f + 2];
            mesh->faces[3 * f + 2] = swap;
        }
    CHECK(pz_mesh_prepare(mesh, "strip.obj", PZ_REPAIR_ORIENT, &ctx) == PZ_OK, "%s", ctx.error);
    CHECK(grid_is_valid(mesh), "strip oriented");
    CHECK(mesh->faces[3 * 1 + 1] != 4 || mesh->faces[3 * 1 + 2] != 3, "the lone face followed the majority");
    pz_mesh_free(&mesh);

    /* Duplicates dropped, labels and corner UVs following their faces. */
    mesh = test_grid(3, 2, TEST_GRID_FLAT, 2, &ctx);
    memcpy(mesh->faces + 36, mesh->faces + 9, 3 * sizeof(int32_t));
    memcpy(mesh->faces + 39, mesh->faces + 21, 3 * sizeof(int32_t));
    mesh->face_labels = calloc(14, sizeof(int32_t));
    mesh->corner_uvs = calloc(42, sizeof(int32_t));
    REQUIRE(mesh->face_labels && mesh->corner_uvs, "out of memory");
    mesh->label_count = 14;
    mesh->uv_count = 42;
    mesh->uvs = calloc(84, sizeof(double));
    REQUIRE(mesh->uvs, "out of memory");
    for (int f = 0; f < 14; ++f) {
        mesh->face_labels[f] = f;
        for (int k = 0; k < 3; ++k)
            mesh->corner_uvs[3 * f + k] = 3 * f + k;
    }
    CHECK(pz_mesh_prepare(mesh, "dup.obj", PZ_REPAIR_DROP_DEGENERATE, &ctx) == PZ_ERR_INVALID_MESH,
          "duplicates not dropped by the degenerate repair");
    CHECK(strstr(ctx.error, "duplicate"), "message: %s", ctx.error);
    CHECK(pz_mesh_prepare(mesh, "dup.obj", PZ_REPAIR_DROP_DUPLICATES, &ctx) == PZ_OK, "%s", ctx.error);
    CHECK(mesh->face_count == 12, "face count after dropping duplicates: %d", (int)mesh->face_count);
    CHECK(mesh->face_labels[11] == 11 && mesh->corner_uvs[35] == 35, "labels and UVs kept with their faces");
    CHECK(grid_is_valid(mesh), "valid after dropping duplicates");
    pz_mesh_free(&mesh);

    /* Zero-area face dropped; the vertex only it used goes too. */
    static const double collinear[] = {0, 0, 0, 1, 0, 0, 0, 1, 0, 2, 0, 0};
    static const int32_t sliver[] = {1, 0, 3, 0, 1, 2};
    mesh = test_mesh_from(4, collinear, 2, sliver, &ctx);
    CHECK(pz_mesh_prepare(mesh, "sliver.obj", PZ_REPAIR_NONE, &ctx) == PZ_ERR_INVALID_MESH, "sliver refused");
    CHECK(strstr(ctx.error, "sliver.obj: invalid mesh: 1 degenerate") == ctx.error, "message: %s", ctx.error);
    CHECK(pz_mesh_prepare(mesh, "sliver.obj", PZ_REPAIR_DROP_DEGENERATE, &ctx) == PZ_OK, "%s", ctx.error);
    CHECK(mesh->face_count == 1 && mesh->vertex_count == 3, "one face, three vertices left: %d %d",
          (int)mesh->face_count, (int)mesh->vertex_count);
    CHECK(mesh->faces[0] == 0 && mesh->faces[1] == 1 && mesh->faces[2] == 2, "remaining face kept");
    pz_mesh_free(&mesh);

    /* Several kinds at once: the message names the first and counts the rest. */
    static const int32_t messy[] = {0, 1, 2, 0, 3, 4, 2, 1, 1};
    mesh = test_mesh_from(5, five, 3, messy, &ctx);
    mesh->positions[14] = NAN;
    CHECK(pz_mesh_prepare(mesh, "messy.ply", PZ_REPAIR_NONE, &ctx) == PZ_ERR_INVALID_MESH, "messy refused");
    CHECK(strstr(ctx.error, "messy.ply: invalid mesh: 1 vertex with non-finite") == ctx.error &&
              strstr(ctx.error, "; 3 more kinds of problem") && strstr(ctx.error, "panelize info messy.ply"),
          "message: %s", ctx.error);
    CHECK(strchr(ctx.error, '\n') == NULL, "one line");
    pz_mesh_free(&mesh);

    /* A clean mesh with a stray vertex passes, minus the vertex. */
    mesh = test_mesh_from(5, five, 1, messy, &ctx);
    CHECK(pz_mesh_prepare(mesh, "stray.obj", PZ_REPAIR_NONE, &ctx) == PZ_OK, "%s", ctx.error);
    CHECK(mesh->vertex_count == 3, "stray vertices dropped");
    pz_mesh_free(&mesh);
}

static void test_drop_unreferenced(void)
{
    /* Vertices 0 and 3 unused: 1 2 4 become 0 1 2, in the rest pose and both poses. */
    static const double positions[] = {0, 0, 0, 1, 0, 0, 0, 1, 0, 9, 9, 9, 1, 1, 0};
    static const int32_t faces[] = {1, 4, 2};
    pz_mesh *mesh = test_mesh_from(5, positions, 1, faces, &ctx);
    double pose[15];
    for (int p = 0; p < 2; ++p) {
        for (int i = 0; i < 15; ++i)
            pose[i] = positions[i] + 10.0 * (p + 1);
        REQUIRE_OK(pz_mesh_add_pose(mesh, pose, &ctx), ctx);
    }
    int32_t removed = -1;
    CHECK(pz_mesh_drop_unreferenced(mesh, &removed, &ctx) == PZ_OK, "%s", ctx.error);
    CHECK(removed == 2 && mesh->vertex_count == 3, "removed %d, %d left", (int)removed, (int)mesh->vertex_count);
    CHECK(mesh->faces[0] == 0 && mesh->faces[1] == 2 && mesh->faces[2] == 1, "faces renumbered");
    static const int32_t kept[] = {1, 2, 4};
    int positions_ok = 1, poses_ok = 1;
    for (int v = 0; v < 3; ++v)
        for (int k = 0; k < 3; ++k) {
            positions_ok &= mesh->positions[3 * v + k] == positions[3 * kept[v] + k];
            for (int p = 0; p < 2; ++p)
                poses_ok &= mesh->poses[(p * 3 + v) * 3 + k] == positions[3 * kept[v] + k] + 10.0 * (p + 1);
        }
    CHECK(positions_ok, "rest positions compacted");
    CHECK(poses_ok, "poses compacted with the new vertex count");
    CHECK(pz_mesh_drop_unreferenced(mesh, NULL, &ctx) == PZ_OK && mesh->vertex_count == 3, "idempotent");
    pz_mesh_free(&mesh);
}

/* Random small meshes (indices may repeat or fall out of range): validation
 * never fails to run, a mesh it passes always gets a topology, and after all
 * repairs pz_mesh_prepare either refuses or hands over a mesh that builds. */
static void test_random_meshes(void)
{
    uint32_t state = 12345;
    int passed = 0, built = 0, prepared = 0, prepared_built = 0;
    for (int trial = 0; trial < 3000; ++trial) {
        int32_t vertex_count = 4 + trial % 5, face_count = 1 + trial % 9;
        pz_mesh *mesh = NULL;
        REQUIRE_OK(pz_mesh_create(vertex_count, face_count, &mesh, &ctx), ctx);
        for (int32_t i = 0; i < 3 * vertex_count; ++i) {
            state = state * 1664525u + 1013904223u;
            mesh->positions[i] = (double)(state >> 8) / (double)(1u << 24);
        }
        for (int32_t c = 0; c < 3 * face_count; ++c) {
            state = state * 1664525u + 1013904223u;
            int32_t pick = (int32_t)((state >> 16) % (uint32_t)(vertex_count + (trial % 7 == 0)));
            mesh->faces[c] = pick;
        }
        pz_validation v;
        REQUIRE_OK(pz_mesh_validate(mesh, &v, &ctx), ctx);
        pz_topology *topology = NULL;
        if (pz_validation_ok(&v)) {
            ++passed;
            built += pz_topology_build(mesh, &topology, &ctx) == PZ_OK;
            pz_topology_free(&topology);
        }
        pz_validation_clear(&v);
        if (pz_mesh_prepare(mesh, "random", PZ_REPAIR_DROP_DEGENERATE | PZ_REPAIR_DROP_DUPLICATES | PZ_REPAIR_ORIENT,
                            &ctx) == PZ_OK) {
            ++prepared;
            prepared_built += pz_topology_build(mesh, &topology, &ctx) == PZ_OK;
            pz_topology_free(&topology);
        } else {
            CHECK(strstr(ctx.error, "random: invalid mesh: ") == ctx.error, "refusal message: %s", ctx.error);
        }
        pz_mesh_free(&mesh);
    }
    CHECK(passed > 100 && built == passed, "valid random meshes %d, with a topology %d", passed, built);
    CHECK(prepared > passed && prepared_built == prepared, "repaired random meshes %d, with a topology %d", prepared,
          prepared_built);
}

int main(void)
{
    pz_ctx_init(&ctx);
    ctx.quiet = 1;
    test_each_problem();
    test_moebius_band();
    test_repairs();
    test_drop_unreferenced();
    test_random_meshes();
    pz_mesh *empty = NULL;
    REQUIRE_OK(pz_mesh_create(0, 0, &empty, &ctx), ctx);
    check_validation(empty, "empty mesh", (expected){0, 0, 0, 0, 0, 0, 0, 0, NULL});
    pz_mesh_free(&empty);
    return test_finish();
}

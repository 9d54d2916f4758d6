/*
 * tests/test_meshes.h -- small meshes and reader checks shared by the C tests
 * (it includes mesh/mesh.h and test_util.h).
 *
 *  - test_mesh_from: a mesh from literal position and face arrays;
 *  - test_grid: a grid of unit squares, flat, rolled into a tube or a torus;
 *  - test_tetrahedron, test_moebius: a closed and a non-orientable surface;
 *  - test_topology, test_summary: connectivity of a mesh that must have one;
 *  - test_face_is: one face's corners;
 *  - test_read_ok, test_read_fails: a memory reader (pz_obj_read_memory
 *    and alike) that must accept or refuse its input, refusals checked for
 *    the error contract (PZ_ERR_DATA, *out NULL, one line "NAME: ...").
 * Builders stop the test (REQUIRE) when the library refuses them.
 *
 * SPDX-License-Identifier: GPL-3.0-or-later
 */
#ifndef PZ_TEST_MESHES_H
#define PZ_TEST_MESHES_H

#include "mesh/mesh.h"
#include "test_util.h"

#include <math.h>
#include <string.h>

#define TEST_PI 3.14159265358979323846

/* A mesh of vertex_count positions (x y z each) and face_count faces (three indices each). */
static inline pz_mesh *test_mesh_from(int32_t vertex_count, const double *positions, int32_t face_count,
                                      const int32_t *faces, pz_ctx *ctx)
{
    pz_mesh *mesh = NULL;
    REQUIRE_OK(pz_mesh_create(vertex_count, face_count, &mesh, ctx), *ctx);
    memcpy(mesh->positions, positions, (size_t)vertex_count * 3 * sizeof(double));
    memcpy(mesh->faces, faces, (size_t)face_count * 3 * sizeof(int32_t));
    return mesh;
}

typedef enum test_grid_shape {
    TEST_GRID_FLAT,  /* in the z = 0 plane, vertex (i, j) at (i, j, 0) */
    TEST_GRID_TUBE,  /* the last column joined to the first, rolled round z: (cos u, sin u, j), outward normals */
    TEST_GRID_TORUS, /* rows joined too: radii 3 and 1 */
} test_grid_shape;

/*
 * A grid of columns x rows squares, each split along its rising diagonal into
 * (a b d) and (a d c), counter-clockwise seen from +z (from outside when
 * rolled). Vertex (i, j) is j * vertex_columns + i, with vertex_columns =
 * columns + 1 when flat and columns when wrapped; faces run row by row, two a
 * square. extra_faces more faces (all 0 0 0) follow, for the caller to fill.
 */
static inline pz_mesh *test_grid(int columns, int rows, test_grid_shape shape, int extra_faces, pz_ctx *ctx)
{
    int wrap_columns = shape != TEST_GRID_FLAT, wrap_rows = shape == TEST_GRID_TORUS;
    int vertex_columns = wrap_columns ? columns : columns + 1;
    int vertex_rows = wrap_rows ? rows : rows + 1;
    pz_mesh *mesh = NULL;
    REQUIRE_OK(pz_mesh_create(vertex_columns * vertex_rows, 2 * columns * rows + extra_faces, &mesh, ctx), *ctx);
    for (int j = 0; j < vertex_rows; ++j)
        for (int i = 0; i < vertex_columns; ++i) {
            double *p = mesh->positions + 3 * (j * vertex_columns + i);
            double u = 2 * TEST_PI * i / columns, v = 2 * TEST_PI * j / rows;
            if (shape == TEST_GRID_TORUS) {
                p[0] = (3 + cos(v)) * cos(u);
                p[1] = (3 + cos(v)) * sin(u);
                p[2] = sin(v);
            } else if (shape == TEST_GRID_TUBE) {
                p[0] = cos(u);
                p[1] = sin(u);
                p[2] = j;
            } else {
                p[0] = i;
                p[1] = j;
                p[2] = 0;
            }
        }
    int32_t *face = mesh->faces;
    for (int j = 0; j < rows; ++j)
        for (int i = 0; i < columns; ++i) {
            int32_t a = j * vertex_columns + i;
            int32_t b = j * vertex_columns + (i + 1) % vertex_columns;
            int32_t c = ((j + 1) % vertex_rows) * vertex_columns + i;
            int32_t d = ((j + 1) % vertex_rows) * vertex_columns + (i + 1) % vertex_columns;
            int32_t quad[6] = {a, b, d, a, d, c};
            memcpy(face, quad, sizeof quad);
            face += 6;
        }
    return mesh;
}

/* The regular tetrahedron on alternate corners of the cube [-1, 1]^3, faces outward. */
static inline pz_mesh *test_tetrahedron(pz_ctx *ctx)
{
    static const double positions[] = {1, 1, 1, 1, -1, -1, -1, 1, -1, -1, -1, 1};
    static const int32_t faces[] = {0, 1, 2, 0, 3, 1, 0, 2, 3, 1, 3, 2};
    return test_mesh_from(4, positions, 4, faces, ctx);
}

/* A Moebius band: 6 quads (12 faces, 12 vertices) round z, the last joining with a half twist. */
static inline pz_mesh *test_moebius(pz_ctx *ctx)
{
    double positions[12 * 3];
    int32_t faces[12 * 3];
    for (int i = 0; i < 6; ++i) {
        double t = 2 * TEST_PI * i / 6;
        for (int side = 0; side < 2; ++side) {
            double w = side ? 0.3 : -0.3;
            double *p = positions + 3 * (2 * i + side);
            p[0] = (2 + w * cos(t / 2)) * cos(t);
            p[1] = (2 + w * cos(t / 2)) * sin(t);
            p[2] = w * sin(t / 2);
        }
        int32_t a0 = 2 * i, a1 = 2 * i + 1;
        int32_t b0 = i < 5 ? 2 * (i + 1) : 1, b1 = i < 5 ? 2 * (i + 1) + 1 : 0;
        int32_t quad[6] = {a0, b0, b1, a0, b1, a1};
        memcpy(faces + 6 * i, quad, sizeof quad);
    }
    return test_mesh_from(12, positions, 12, faces, ctx);
}

/* The connectivity of a mesh that must have one (free it with pz_topology_free). */
static inline pz_topology *test_topology(const pz_mesh *mesh, pz_ctx *ctx)
{
    pz_topology *topology = NULL;
    REQUIRE_OK(pz_topology_build(mesh, &topology, ctx), *ctx);
    return topology;
}

/* Counts, Euler characteristic, genus and loops of a mesh that must have a topology. */
static inline pz_topology_summary test_summary(const pz_mesh *mesh, pz_ctx *ctx)
{
    pz_topology *topology = test_topology(mesh, ctx);
    pz_topology_summary summary = {0};
    REQUIRE_OK(pz_topology_summarize(topology, &summary, ctx), *ctx);
    pz_topology_free(&topology);
    return summary;
}

/* Face f has the corners a b c, in that order. */
static inline int test_face_is(const pz_mesh *mesh, int32_t f, int32_t a, int32_t b, int32_t c)
{
    const int32_t *corners = mesh->faces + 3 * f;
    return corners[0] == a && corners[1] == b && corners[2] == c;
}

/* A reader from memory: pz_obj_read_memory, pz_off_read_memory (or an adapter). */
typedef pz_status (*test_reader)(const char *data, size_t size, const char *name, pz_mesh **out, pz_ctx *ctx);

/* Reads data (size bytes, named `name`) that must parse; `what` labels the failure. NULL when it did not. */
static inline pz_mesh *test_read_ok(test_reader read, const char *data, size_t size, const char *name,
                                    const char *what)
{
    pz_ctx ctx;
    pz_ctx_init(&ctx);
    pz_mesh *mesh = NULL;
    pz_status status = read(data, size, name, &mesh, &ctx);
    CHECK(status == PZ_OK, "%s: read failed: %s", what, ctx.error);
    return mesh;
}

/* Reads data that must be refused as PZ_ERR_DATA with *out reset to NULL and
 * a one-line message "NAME: ..." containing `expected`. */
static inline void test_read_fails(test_reader read, const char *data, size_t size, const char *name,
                                   const char *expected)
{
    pz_ctx ctx;
    pz_ctx_init(&ctx);
    pz_mesh *mesh = (pz_mesh *)&ctx; /* must be reset to NULL */
    pz_status status = read(data, size, name, &mesh, &ctx);
    size_t name_length = strlen(name);
    CHECK(status == PZ_ERR_DATA, "expected PZ_ERR_DATA for %s, got %d", expected, (int)status);
    CHECK(mesh == NULL, "*out not NULL after failure");
    CHECK(strncmp(ctx.error, name, name_length) == 0 && strncmp(ctx.error + name_length, ": ", 2) == 0,
          "message does not start with '%s: ': %s", name, ctx.error);
    CHECK(strstr(ctx.error, expected) != NULL, "message '%s' lacks '%s'", ctx.error, expected);
    CHECK(strchr(ctx.error, '\n') == NULL, "message is not one line: %s", ctx.error);
}

#endif

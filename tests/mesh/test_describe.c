/*
 * tests/mesh/test_describe.c -- pz_mesh_describe on meshes whose figures are
 * known: a generated bodice (a tube: one component, two boundary loops,
 * Euler characteristic 0, genus 0, loop lengths adding up to the girths), a
 * closed tetrahedron (chi 2, no loops), and an invalid mesh with a fin, which
 * is still described (edges and components counted, loops and genus unknown).
 *
 * SPDX-License-Identifier: GPL-3.0-or-later
 */
#include "generate/generate.h"
#include "mesh/mesh.h"

#include "test_util.h"

#include <math.h>
#include <string.h>

static void test_bodice(void)
{
    pz_ctx ctx = {0};
    pz_generate_options options = {.target_faces = 2000};
    pz_mesh *mesh = NULL;
    REQUIRE_OK(pz_generate(PZ_SHAPE_BODICE, &options, &mesh, &ctx), ctx);
    pz_mesh_description d;
    REQUIRE_OK(pz_mesh_describe(mesh, &d, &ctx), ctx);
    CHECK(d.manifold && d.component_count == 1 && d.boundary_loop_count == 2 && d.euler_characteristic == 0 &&
              d.genus == 0,
          "bodice: manifold %d, %d components, %d loops, chi %d, genus %d", d.manifold, (int)d.component_count,
          (int)d.boundary_loop_count, (int)d.euler_characteristic, (int)d.genus);
    /* V - E + F = 0 for a tube, so the edges follow from the counts. */
    CHECK(d.edge_count == mesh->vertex_count + mesh->face_count, "edges %d", (int)d.edge_count);
    int32_t loop_vertices = 0;
    for (int32_t i = 0; i < d.boundary_loop_count; ++i) {
        loop_vertices += d.loop_vertex_counts[i];
        CHECK(d.loop_lengths[i] > 500 && d.loop_lengths[i] < 1500, "loop %d: %g mm is no girth", (int)i,
              d.loop_lengths[i]);
    }
    int32_t boundary = 0;
    pz_topology *topology = NULL;
    REQUIRE_OK(pz_topology_build(mesh, &topology, &ctx), ctx);
    for (int32_t v = 0; v < mesh->vertex_count; ++v)
        boundary += topology->vertex_on_boundary[v];
    pz_topology_free(&topology);
    CHECK(loop_vertices == boundary, "loops hold %d vertices, the boundary %d", (int)loop_vertices, (int)boundary);
    CHECK(d.area_known && fabs(d.area_mm2 - pz_geom_total_area(mesh)) < 1e-6, "area %g", d.area_mm2);
    pz_mesh_description_clear(&d);
    CHECK(d.loop_lengths == NULL && d.validation.problems == NULL, "clear left pointers");
    pz_mesh_free(&mesh);
}

static pz_mesh *mesh_of(int32_t vertices, const double *positions, int32_t faces, const int32_t *corners)
{
    pz_ctx ctx = {0};
    pz_mesh *mesh = NULL;
    REQUIRE_OK(pz_mesh_create(vertices, faces, &mesh, &ctx), ctx);
    memcpy(mesh->positions, positions, 3 * (size_t)vertices * sizeof(double));
    memcpy(mesh->faces, corners, 3 * (size_t)faces * sizeof(int32_t));
    return mesh;
}

static void test_closed_and_invalid(void)
{
    pz_ctx ctx = {0};
    static const double corners4[12] = {0, 0, 0, 100, 0, 0, 0, 100, 0, 0, 0, 100};
    static const int32_t tetra[12] = {0, 2, 1, 0, 1, 3, 1, 2, 3, 2, 0, 3};
    pz_mesh *mesh = mesh_of(4, corners4, 4, tetra);
    pz_mesh_description d;
    REQUIRE_OK(pz_mesh_describe(mesh, &d, &ctx), ctx);
    CHECK(d.manifold && d.euler_characteristic == 2 && d.boundary_loop_count == 0 && d.edge_count == 6 &&
              d.genus == 0,
          "tetrahedron: chi %d, loops %d, edges %d, genus %d", (int)d.euler_characteristic,
          (int)d.boundary_loop_count, (int)d.edge_count, (int)d.genus);
    pz_mesh_description_clear(&d);
    pz_mesh_free(&mesh);

    /* Three faces on one edge: not a manifold, still described. */
    static const double corners5[15] = {0, 0, 0, 100, 0, 0, 0, 100, 0, 0, -100, 0, 0, 0, 100};
    static const int32_t fin[9] = {0, 1, 2, 1, 0, 3, 0, 1, 4};
    mesh = mesh_of(5, corners5, 3, fin);
    REQUIRE_OK(pz_mesh_describe(mesh, &d, &ctx), ctx);
    CHECK(!d.manifold && d.validation.nonmanifold_edges == 1, "a fin: manifold %d, %d non-manifold edges", d.manifold,
          (int)d.validation.nonmanifold_edges);
    /* 5 vertices, 7 distinct edges, 3 faces: chi 1; one component; loops and genus unknown. */
    CHECK(d.edge_count == 7 && d.component_count == 1 && d.euler_characteristic == 1 &&
              d.boundary_loop_count == -1 && d.genus == -1 && d.area_known,
          "a fin: %d edges, %d components, chi %d, loops %d, genus %d", (int)d.edge_count, (int)d.component_count,
          (int)d.euler_characteristic, (int)d.boundary_loop_count, (int)d.genus);
    pz_mesh_description_clear(&d);
    pz_mesh_free(&mesh);
}

int main(void)
{
    test_bodice();
    test_closed_and_invalid();
    return test_finish();
}

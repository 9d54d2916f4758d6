/*
 * tests/mesh/test_topology.c -- connectivity on hand-built meshes with known
 * answers: counts, Euler characteristic, genus, boundary loops (order and
 * direction), ordered one-rings, components, and refusal of meshes that are
 * not oriented manifolds.
 *
 * SPDX-License-Identifier: GPL-3.0-or-later
 */
#include "io/io.h"
#include "test_meshes.h"

#include <string.h>

static pz_ctx ctx;

/* Every half-edge's twin runs the other way and points back; edges cover half-edges once. */
static void check_invariants(const pz_topology *t, const char *name)
{
    int bad_twin = 0, bad_edge = 0;
    for (int32_t h = 0; h < t->halfedge_count; ++h) {
        int32_t o = t->twin[h];
        if (o >= 0 && (t->twin[o] != h || pz_he_from(t, o) != pz_he_to(t, h) || pz_he_to(t, o) != pz_he_from(t, h)))
            ++bad_twin;
        int32_t e = t->halfedge_edge[h];
        if (e < 0 || e >= t->edge_count || (t->edge_halfedge[2 * e] != h && t->edge_halfedge[2 * e + 1] != h))
            ++bad_edge;
    }
    CHECK(bad_twin == 0, "%s: %d half-edges with a wrong twin", name, bad_twin);
    CHECK(bad_edge == 0, "%s: %d half-edges with a wrong edge", name, bad_edge);
    int bad_vertex = 0;
    for (int32_t v = 0; v < t->vertex_count; ++v)
        bad_vertex += t->vertex_halfedge[v] >= 0 && pz_he_from(t, t->vertex_halfedge[v]) != v;
    CHECK(bad_vertex == 0, "%s: %d vertex half-edges do not leave their vertex", name, bad_vertex);
}

static void test_counts(void)
{
    static const double tri_positions[] = {0, 0, 0, 1, 0, 0, 0, 1, 0};
    static const int32_t tri_faces[] = {0, 1, 2};
    struct {
        const char *name;
        pz_mesh *mesh;
        int32_t v, e, f, components, loops, chi, genus;
    } cases[] = {
        {"triangle", test_mesh_from(3, tri_positions, 1, tri_faces, &ctx), 3, 3, 1, 1, 1, 1, 0},
        {"quad strip", test_grid(3, 1, TEST_GRID_FLAT, 0, &ctx), 8, 13, 6, 1, 1, 1, 0},
        {"tetrahedron", test_tetrahedron(&ctx), 4, 6, 4, 1, 0, 2, 0},
        {"torus", test_grid(6, 4, TEST_GRID_TORUS, 0, &ctx), 24, 72, 48, 1, 0, 0, 1},
        {"tube", test_grid(8, 2, TEST_GRID_TUBE, 0, &ctx), 24, 56, 32, 1, 2, 0, 0},
    };
    for (size_t i = 0; i < sizeof cases / sizeof cases[0]; ++i) {
        pz_topology *topology = test_topology(cases[i].mesh, &ctx);
        check_invariants(topology, cases[i].name);
        pz_topology_free(&topology);
        pz_topology_summary s = test_summary(cases[i].mesh, &ctx);
        CHECK(s.vertex_count == cases[i].v, "%s: V %d", cases[i].name, (int)s.vertex_count);
        CHECK(s.edge_count == cases[i].e, "%s: E %d", cases[i].name, (int)s.edge_count);
        CHECK(s.face_count == cases[i].f, "%s: F %d", cases[i].name, (int)s.face_count);
        CHECK(s.component_count == cases[i].components, "%s: components %d", cases[i].name, (int)s.component_count);
        CHECK(s.boundary_loop_count == cases[i].loops, "%s: loops %d", cases[i].name, (int)s.boundary_loop_count);
        CHECK(s.euler_characteristic == cases[i].chi, "%s: chi %d", cases[i].name, (int)s.euler_characteristic);
        CHECK(s.genus == cases[i].genus, "%s: genus %d", cases[i].name, (int)s.genus);
        pz_mesh_free(&cases[i].mesh);
    }
}

/* Two tetrahedra and a triangle, plus an unreferenced vertex: 3 components, chi 2+2+1. */
static void test_components(void)
{
    static const double positions[] = {1, 1, 1, 1, -1, -1, -1, 1, -1, -1, -1, 1,
                                       11, 1, 1, 11, -1, -1, 9, 1, -1, 9, -1, 1,
                                       20, 0, 0, 21, 0, 0, 20, 1, 0, 50, 50, 50};
    static const int32_t faces[] = {0, 1, 2, 8, 9, 10, 0, 3, 1, 4, 5, 6, 0, 2, 3,
                                    4, 7, 5, 1, 3, 2, 4, 6, 7, 5, 7, 6};
    pz_mesh *mesh = test_mesh_from(12, positions, 9, faces, &ctx);
    pz_topology *topology = test_topology(mesh, &ctx);
    int32_t component[9];
    int32_t count = pz_topology_components(topology, component, &ctx);
    CHECK(count == 3, "components %d", (int)count);
    static const int32_t expected[9] = {0, 1, 0, 2, 0, 2, 0, 2, 2};
    CHECK(memcmp(component, expected, sizeof expected) == 0, "components numbered in order of first face");
    pz_topology_summary s;
    CHECK(pz_topology_summarize(topology, &s, &ctx) == PZ_OK, "%s", ctx.error);
    CHECK(s.vertex_count == 11, "referenced vertices %d", (int)s.vertex_count);
    CHECK(s.euler_characteristic == 5, "chi %d", (int)s.euler_characteristic);
    CHECK(s.genus == 0 && s.boundary_loop_count == 1, "genus %d loops %d", (int)s.genus, (int)s.boundary_loop_count);
    CHECK(topology->vertex_halfedge[11] == -1, "isolated vertex has no half-edge");
    CHECK(pz_topology_vertex_ring(topology, 11, NULL, 0) == 0, "isolated vertex has an empty ring");
    pz_topology_free(&topology);
    int32_t raw_component[9];
    CHECK(pz_mesh_face_components(mesh, raw_component, &ctx) == 3, "components without connectivity");
    CHECK(memcmp(raw_component, expected, sizeof expected) == 0, "same numbering without connectivity");
    /* An out-of-range corner (an invalid mesh) is skipped, not followed. */
    mesh->faces[3 * 1 + 0] = 1000;
    CHECK(pz_mesh_face_components(mesh, raw_component, &ctx) == 3, "an out-of-range corner is skipped");
    mesh->faces[3 * 1 + 0] = mesh->faces[3 * 1 + 1] = mesh->faces[3 * 1 + 2] = -5;
    CHECK(pz_mesh_face_components(mesh, raw_component, &ctx) == 2 && raw_component[1] == -1,
          "a face with no corner in range gets component -1 and the lone triangle's component is gone");
    pz_mesh_free(&mesh);
}

static void check_loop(const pz_loops *loops, int32_t index, const int32_t *expected, int32_t count, const char *name)
{
    int32_t begin = loops->loop_offsets[index], length = loops->loop_offsets[index + 1] - begin;
    CHECK(length == count, "%s: loop %d has %d vertices, expected %d", name, (int)index, (int)length, (int)count);
    if (length == count)
        CHECK(memcmp(loops->loop_vertices + begin, expected, (size_t)count * sizeof(int32_t)) == 0,
              "%s: loop %d vertex order", name, (int)index);
}

static void test_boundary_loops(void)
{
    /* Quad strip 2 x 1: bottom 0 1 2, top 3 4 5; counter-clockwise seen from +z,
     * starting at the first boundary half-edge 0 -> 1. */
    pz_mesh *strip = test_grid(2, 1, TEST_GRID_FLAT, 0, &ctx);
    pz_topology *topology = test_topology(strip, &ctx);
    pz_loops *loops = NULL;
    REQUIRE_OK(pz_topology_boundary_loops(topology, &loops, &ctx), ctx);
    CHECK(loops->loop_count == 1, "strip: %d loops", (int)loops->loop_count);
    static const int32_t strip_loop[] = {0, 1, 2, 5, 4, 3};
    check_loop(loops, 0, strip_loop, 6, "strip");
    pz_loops_free(&loops);
    CHECK(loops == NULL, "pz_loops_free clears the pointer");
    pz_topology_free(&topology);
    CHECK(topology == NULL, "pz_topology_free clears the pointer");
    pz_mesh_free(&strip);

    /* Tube of 4 columns, 1 row: the bottom runs with increasing angle, the top
     * the other way (surface on the left of each). */
    pz_mesh *tube = test_grid(4, 1, TEST_GRID_TUBE, 0, &ctx);
    topology = test_topology(tube, &ctx);
    REQUIRE_OK(pz_topology_boundary_loops(topology, &loops, &ctx), ctx);
    CHECK(loops->loop_count == 2, "tube: %d loops", (int)loops->loop_count);
    static const int32_t bottom[] = {0, 1, 2, 3}, top[] = {5, 4, 7, 6};
    check_loop(loops, 0, bottom, 4, "tube bottom");
    check_loop(loops, 1, top, 4, "tube top");
    for (int32_t v = 0; v < 8; ++v)
        CHECK(topology->vertex_on_boundary[v] == 1, "tube vertex %d on the boundary", (int)v);
    pz_loops_free(&loops);
    pz_topology_free(&topology);
    pz_mesh_free(&tube);

    pz_mesh *closed = test_tetrahedron(&ctx);
    topology = test_topology(closed, &ctx);
    REQUIRE_OK(pz_topology_boundary_loops(topology, &loops, &ctx), ctx);
    CHECK(loops->loop_count == 0 && loops->loop_offsets[0] == 0, "a closed mesh has no boundary loop");
    pz_loops_free(&loops);
    pz_topology_free(&topology);
    pz_mesh_free(&closed);
}

/* ring must be a rotation of expected (an interior ring has no distinguished start). */
static int is_rotation(const int32_t *ring, const int32_t *expected, int32_t count)
{
    for (int32_t shift = 0; shift < count; ++shift) {
        int32_t k = 0;
        while (k < count && ring[k] == expected[(k + shift) % count])
            ++k;
        if (k == count)
            return 1;
    }
    return 0;
}

static void test_vertex_ring(void)
{
    /* 2 x 2 grid, vertex (i, j) = 3j + i; diagonals rise, so the centre 4 has
     * the six neighbours 5 8 7 3 0 1 counter-clockwise. */
    pz_mesh *mesh = test_grid(2, 2, TEST_GRID_FLAT, 0, &ctx);
    pz_topology *topology = test_topology(mesh, &ctx);
    int32_t ring[16];
    int32_t count = pz_topology_vertex_ring(topology, 4, ring, 16);
    static const int32_t centre[] = {5, 8, 7, 3, 0, 1};
    CHECK(count == 6, "centre ring size %d", (int)count);
    CHECK(count == 6 && is_rotation(ring, centre, 6), "centre ring is counter-clockwise");
    CHECK(topology->vertex_on_boundary[4] == 0, "centre is interior");
    /* Bottom middle vertex 1: from boundary neighbour 2 round to boundary neighbour 0. */
    count = pz_topology_vertex_ring(topology, 1, ring, 16);
    static const int32_t bottom[] = {2, 5, 4, 0};
    CHECK(count == 4 && memcmp(ring, bottom, sizeof bottom) == 0, "boundary ring %d: %d %d %d %d", (int)count,
          (int)ring[0], (int)ring[1], (int)ring[2], (int)ring[3]);
    CHECK(topology->vertex_on_boundary[1] == 1, "vertex 1 on the boundary");
    CHECK(pz_he_to(topology, topology->vertex_halfedge[1]) == 2 && topology->twin[topology->vertex_halfedge[1]] < 0,
          "boundary vertex_halfedge is the outgoing boundary half-edge");
    /* Sizing with capacity 0, then a short buffer is not overrun. */
    CHECK(pz_topology_vertex_ring(topology, 4, NULL, 0) == 6, "capacity 0 sizes the ring");
    int32_t short_ring[3] = {-7, -7, -7};
    CHECK(pz_topology_vertex_ring(topology, 4, short_ring, 2) == 6 && short_ring[2] == -7, "capacity respected");
    /* Corner vertex 0 has the two faces (0 1 4) and (0 4 3). */
    count = pz_topology_vertex_ring(topology, 0, ring, 16);
    static const int32_t corner[] = {1, 4, 3};
    CHECK(count == 3 && memcmp(ring, corner, sizeof corner) == 0, "corner ring");
    pz_topology_free(&topology);
    pz_mesh_free(&mesh);
}

static void expect_refused(pz_mesh *mesh, const char *name, const char *word)
{
    pz_topology dummy, *topology = &dummy;  /* must be reset to NULL */
    ctx.error[0] = 0;
    pz_status status = pz_topology_build(mesh, &topology, &ctx);
    CHECK(status == PZ_ERR_INVALID_MESH, "%s: status %d", name, (int)status);
    CHECK(topology == NULL, "%s: output left NULL", name);
    CHECK(strstr(ctx.error, word) != NULL, "%s: message '%s' lacks '%s'", name, ctx.error, word);
    CHECK(strchr(ctx.error, '\n') == NULL, "%s: one-line message", name);
    pz_mesh_free(&mesh);
}

static void test_refusals(void)
{
    static const double five[] = {0, 0, 0, 1, 0, 0, 0, 1, 0, -1, 0, 0, 0, -1, 0};
    static const int32_t bowtie[] = {0, 1, 2, 0, 3, 4};
    expect_refused(test_mesh_from(5, five, 2, bowtie, &ctx), "bow-tie", "vertex 0");
    static const int32_t three_on_edge[] = {0, 1, 2, 1, 0, 3, 0, 1, 4};
    expect_refused(test_mesh_from(5, five, 3, three_on_edge, &ctx), "three faces on an edge", "edge 0-1");
    static const int32_t flipped[] = {0, 1, 2, 0, 1, 3};
    expect_refused(test_mesh_from(5, five, 2, flipped, &ctx), "flipped face", "edge 0-1");
    static const int32_t out_of_range[] = {0, 1, 7};
    expect_refused(test_mesh_from(5, five, 1, out_of_range, &ctx), "index out of range", "face 0");
    static const int32_t repeated[] = {0, 1, 1};
    expect_refused(test_mesh_from(5, five, 1, repeated, &ctx), "repeated index", "face 0");
    expect_refused(test_moebius(&ctx), "Moebius band", "same way");
}

/* Real garments (INVENTORY.md gives their boundary loop counts): valid, one
 * component, genus 0, the stated loops, and a consistent half-edge structure. */
static void test_real_meshes(void)
{
    const char *dir = test_shared_data();
    if (!dir) {
        test_skip_part("the real meshes: PZ_SHARED_DATA is not set");
        return;
    }
    static const struct {
        const char *file;
        int32_t loops;
    } meshes[] = {
        {"garments/diffavatar-tshirt.obj", 4}, {"garments/parafashion-leggings.ply", 3},
        {"garments/parafashion-wetsuit.obj", 5}, {"garments/shirtfront-panel.obj", 1},
        {"surfaces/camelhead.off", 1},
    };
    for (size_t i = 0; i < sizeof meshes / sizeof meshes[0]; ++i) {
        char path[4096];
        snprintf(path, sizeof path, "%s/%s", dir, meshes[i].file);
        pz_mesh *mesh = NULL;
        if (pz_mesh_read(path, &mesh, &ctx) != PZ_OK) {
            CHECK(0, "cannot read the shared %s: %s", meshes[i].file, ctx.error);
            continue;
        }
        CHECK(pz_mesh_prepare(mesh, path, PZ_REPAIR_NONE, &ctx) == PZ_OK, "%s", ctx.error);
        pz_topology *topology = NULL;
        CHECK(pz_topology_build(mesh, &topology, &ctx) == PZ_OK, "%s: %s", meshes[i].file, ctx.error);
        if (topology) {
            check_invariants(topology, meshes[i].file);
            pz_topology_summary s;
            CHECK(pz_topology_summarize(topology, &s, &ctx) == PZ_OK, "%s", ctx.error);
            CHECK(s.boundary_loop_count == meshes[i].loops && s.component_count == 1 && s.genus == 0,
                  "%s: loops %d components %d genus %d", meshes[i].file, (int)s.boundary_loop_count,
                  (int)s.component_count, (int)s.genus);
            /* Every interior vertex's ring closes; every boundary ring has one more entry than faces. */
            int32_t ring[64], bad_rings = 0;
            for (int32_t v = 0; v < topology->vertex_count; ++v) {
                int32_t count = pz_topology_vertex_ring(topology, v, ring, 64);
                int32_t first = count > 0 && count <= 64 ? ring[0] : -1;
                bad_rings += count < 2 || (topology->vertex_on_boundary[v] && first != pz_he_to(topology, topology->vertex_halfedge[v]));
            }
            CHECK(bad_rings == 0, "%s: %d bad rings", meshes[i].file, (int)bad_rings);
        }
        pz_topology_free(&topology);
        pz_mesh_free(&mesh);
    }
}

int main(void)
{
    pz_ctx_init(&ctx);
    ctx.quiet = 1;
    test_counts();
    test_components();
    test_boundary_loops();
    test_vertex_ring();
    test_refusals();
    test_real_meshes();
    pz_mesh *empty = NULL;
    REQUIRE_OK(pz_mesh_create(0, 0, &empty, &ctx), ctx);
    pz_topology_summary s = test_summary(empty, &ctx);
    CHECK(s.vertex_count == 0 && s.edge_count == 0 && s.component_count == 0 && s.genus == 0, "empty mesh");
    pz_mesh_free(&empty);
    return test_finish();
}

/*
 * tests/trace/test_symmetry.c -- the mirror plane and mirrored paths
 * (segment/symmetry.c):
 *  - the generated bodice is symmetric about x = 0: AUTO finds x with
 *    residual_rel < 1e-3, the plane through x = 0; the vertex map is an
 *    involution that swaps the sides; y is rejected (its residual is above
 *    the tolerance) but used, residual reported, when asked for;
 *  - the bodice stretched on one side has no plane (AUTO: found = 0); OFF
 *    finds nothing;
 *  - the mirror of every candidate path is a valid path of the same kind
 *    and length, border paths still ENTER to EXIT, and mirroring twice gives
 *    the original vertices back.
 *
 * SPDX-License-Identifier: GPL-3.0-or-later
 */
#include "field/field.h"
#include "generate/generate.h"
#include "segment/segment.h"
#include "test_meshes.h"
#include "trace_fixtures.h"

#include <math.h>
#include <stdio.h>

static pz_ctx ctx;

static pz_mesh *bodice(void)
{
    pz_generate_options options = {7000, 0, 0};
    pz_mesh *mesh = NULL;
    REQUIRE_OK(pz_generate(PZ_SHAPE_BODICE, &options, &mesh, &ctx), ctx);
    return mesh;
}

static void test_detect_bodice(const pz_mesh *mesh, const pz_topology *topology)
{
    pz_symmetry s;
    REQUIRE_OK(pz_symmetry_detect(mesh, topology, PZ_SYMMETRY_AUTO, NULL, 0.0, &s, &ctx), ctx);
    printf("bodice: axis %d, offset %g, residual %g mm (rel %g)\n", s.axis, s.offset, s.residual_mm, s.residual_rel);
    REQUIRE(s.found && s.axis == 0 && s.residual_rel < 1e-3 && fabs(s.offset) < 1.0 && s.normal[0] == 1.0,
            "bodice plane: found %d axis %d offset %g residual_rel %g", s.found, s.axis, s.offset, s.residual_rel);
    REQUIRE(s.vertex_count == mesh->vertex_count && s.vertex_mirror && s.vertex_side, "arrays");
    int not_involution = 0, bad_side = 0, sides[3] = {0, 0, 0};
    for (int32_t v = 0; v < mesh->vertex_count; ++v) {
        int32_t m = s.vertex_mirror[v];
        if (m < 0 || s.vertex_mirror[m] != v) {
            ++not_involution;
            continue;
        }
        ++sides[s.vertex_side[v]];
        bad_side += s.vertex_side[v] + s.vertex_side[m] != 2;
        bad_side += (s.vertex_side[v] == 1) != (fabs(mesh->positions[3 * v]) < 10.0);
    }
    CHECK(not_involution == 0 && bad_side == 0, "%d vertices not mapped back, %d with wrong sides", not_involution,
          bad_side);
    CHECK(sides[0] == sides[2] && sides[1] > 0, "sides %d / %d / %d", sides[0], sides[1], sides[2]);
    pz_symmetry_clear(&s);
    CHECK(s.vertex_mirror == NULL && s.found == 0, "clear");

    REQUIRE_OK(pz_symmetry_detect(mesh, topology, PZ_SYMMETRY_Y, NULL, 0.0, &s, &ctx), ctx);
    printf("bodice forced y: residual rel %g\n", s.residual_rel);
    CHECK(s.found && s.axis == 1 && s.residual_rel > 0.005, "forced y: found %d axis %d residual_rel %g", s.found,
          s.axis, s.residual_rel);
    pz_symmetry_clear(&s);
    REQUIRE_OK(pz_symmetry_detect(mesh, topology, PZ_SYMMETRY_OFF, NULL, 0.0, &s, &ctx), ctx);
    CHECK(!s.found && s.axis == -1 && !s.vertex_mirror, "off");
    pz_symmetry_clear(&s);
}

static void test_asymmetric(void)
{
    pz_mesh *mesh = bodice();
    for (int32_t v = 0; v < mesh->vertex_count; ++v) /* the +x side 50 % wider: no mirror plane left */
        if (mesh->positions[3 * v] > 0)
            mesh->positions[3 * v] *= 1.5;
    pz_topology *topology = test_topology(mesh, &ctx);
    pz_symmetry s;
    REQUIRE_OK(pz_symmetry_detect(mesh, topology, PZ_SYMMETRY_AUTO, NULL, 0.0, &s, &ctx), ctx);
    printf("stretched bodice: found %d, best residual rel %g\n", s.found, s.residual_rel);
    CHECK(!s.found && s.axis == -1 && s.residual_rel > 0.005 && !s.vertex_mirror, "stretched: found %d rel %g",
          s.found, s.residual_rel);
    pz_symmetry_clear(&s);
    pz_topology_free(&topology);
    pz_mesh_free(&mesh);
}

static int path_ok(const pz_topology *topology, const pz_trace_graph *graph, const pz_trace_path *p)
{
    char *seen = calloc((size_t)topology->vertex_count, 1);
    REQUIRE(seen, "out of memory");
    int ok = p->vertex_count >= 2;
    for (int32_t i = 0; i < p->vertex_count && ok; ++i) {
        ok = !seen[p->vertices[i]] && p->arms[i] < 4;
        seen[p->vertices[i]] = 1;
        if (ok && (i + 1 < p->vertex_count || p->closed))
            ok = test_share_edge(topology, p->vertices[i], p->vertices[(i + 1) % p->vertex_count]);
    }
    free(seen);
    if (ok && p->kind == PZ_TRACE_BORDER) {
        int32_t n = p->vertex_count - 1;
        ok = graph->node_kind[4 * p->vertices[0] + p->arms[0]] == PZ_TRACE_NODE_ENTER &&
             graph->node_kind[4 * p->vertices[n] + p->arms[n]] == PZ_TRACE_NODE_EXIT;
    }
    return ok;
}

static void test_mirror_paths(const pz_mesh *mesh, const pz_topology *topology)
{
    pz_field *field = NULL;
    pz_trace_graph *graph = NULL;
    pz_trace_paths *paths = NULL;
    REQUIRE_OK(pz_field_compute(mesh, topology, NULL, &field, &ctx), ctx);
    REQUIRE_OK(pz_trace_graph_build(mesh, topology, field->directions, NULL, &graph, &ctx), ctx);
    REQUIRE_OK(pz_trace_candidates(graph, mesh, topology, NULL, &paths, &ctx), ctx);
    pz_symmetry s;
    REQUIRE_OK(pz_symmetry_detect(mesh, topology, PZ_SYMMETRY_AUTO, NULL, 0.0, &s, &ctx), ctx);
    REQUIRE(s.found, "no plane");
    int bad = 0, not_back = 0;
    for (int32_t i = 0; i < paths->path_count; ++i) {
        const pz_trace_path *p = &paths->paths[i];
        pz_trace_path m, back;
        REQUIRE_OK(pz_symmetry_mirror_path(&s, graph, mesh, topology, p, &m, &ctx), ctx);
        int ok = m.kind == p->kind && m.closed == p->closed && path_ok(topology, graph, &m) &&
                 fabs(m.length_mm - p->length_mm) < 1e-3 * p->length_mm;
        CHECK(ok, "mirror of path %d (kind %d, %d vertices, %g mm): kind %d, %d vertices, %g mm", (int)i, p->kind,
              (int)p->vertex_count, p->length_mm, m.kind, (int)m.vertex_count, m.length_mm);
        bad += !ok;
        REQUIRE_OK(pz_symmetry_mirror_path(&s, graph, mesh, topology, &m, &back, &ctx), ctx);
        not_back += back.vertex_count != p->vertex_count ||
                    memcmp(back.vertices, p->vertices, (size_t)p->vertex_count * sizeof(int32_t)) != 0;
        pz_trace_path_clear(&back);
        pz_trace_path_clear(&m);
    }
    printf("mirrored %d paths: %d bad, %d not mirrored back exactly\n", (int)paths->path_count, bad, not_back);
    CHECK(paths->path_count > 10 && not_back == 0, "%d paths, %d not mirrored back", (int)paths->path_count, not_back);
    pz_symmetry none = {0};
    pz_trace_path m;
    CHECK(pz_symmetry_mirror_path(&none, graph, mesh, topology, &paths->paths[0], &m, &ctx) == PZ_ERR_USAGE,
          "mirror without a plane accepted");
    pz_symmetry_clear(&s);
    pz_trace_paths_free(&paths);
    pz_trace_graph_free(&graph);
    pz_field_free(&field);
}

int main(void)
{
    pz_ctx_init(&ctx);
    ctx.quiet = 1;
    pz_mesh *mesh = bodice();
    pz_topology *topology = test_topology(mesh, &ctx);
    test_detect_bodice(mesh, topology);
    test_mirror_paths(mesh, topology);
    pz_topology_free(&topology);
    pz_mesh_free(&mesh);
    test_asymmetric();
    return test_finish();
}

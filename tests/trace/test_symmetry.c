/*
 * tests/trace/test_symmetry.c -- the mirror plane and mirrored paths
 * (segment/symmetry.c):
 *  - the generated bodice is symmetric about x = 0: AUTO finds x with
 *    residual_rel < 1e-3, the plane through x = 0; the vertex map is an
 *    involution that swaps the sides; y is rejected (its residual is above
 *    the tolerance) but used, residual reported, when asked for;
 *  - the bodice stretched on one side has no plane (AUTO: found = 0); OFF
 *    finds nothing;
 *  - in any orientation (docs/segment.md, "Symmetry"): the bodice turned by
 *    an arbitrary rotation and moved gets its plane, the normal within 1
 *    degree of the true one's image, the offset within 1 mm; with every
 *    vertex moved by up to 0.5 % of the diagonal (deterministic noise) it is
 *    still symmetric (residual within the 1.5 % tolerance) and its plane
 *    within 2 degrees; one side 60 % wider and the whole tapered upwards
 *    makes it asymmetric (above 1.5 %; a local bulge, 0.25-0.4 diagonals
 *    wide and 5-10 % deep, measured 1.36-1.51 %: the 90th percentile forgives
 *    what concerns about a tenth of the surface); a given plane (PZ_SYMMETRY_
 *    PLANE) is used as given, x with its offset fitted; the shared
 *    parafashion shirt (open front, sides differing) has none and the shared
 *    T-shirt one, along x, when ../shared/data is there;
 *  - the mirror of every candidate path is a valid path of the same kind
 *    and length, border paths still ENTER to EXIT, and mirroring twice gives
 *    the original vertices back.
 *
 * SPDX-License-Identifier: GPL-3.0-or-later
 */
#include "field/field.h"
#include "generate/generate.h"
#include "segment/segment.h"
#include "io/io.h"
#include "test_meshes.h"
#include "trace_fixtures.h"

#include <math.h>
#include <stdio.h>
#include <string.h>

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

/* The bodice turned by a fixed arbitrary rotation and moved; *true_normal: the image of the plane's normal (x). */
static pz_mesh *turned_bodice(double true_normal[3])
{
    pz_mesh *mesh = bodice();
    double a = 0.7, b = -0.4, c = 1.1; /* radians about z, x, y */
    double rz[3][3] = {{cos(a), -sin(a), 0}, {sin(a), cos(a), 0}, {0, 0, 1}};
    double rx[3][3] = {{1, 0, 0}, {0, cos(b), -sin(b)}, {0, sin(b), cos(b)}};
    double ry[3][3] = {{cos(c), 0, sin(c)}, {0, 1, 0}, {-sin(c), 0, cos(c)}};
    double m[3][3], r[3][3];
    for (int i = 0; i < 3; ++i)
        for (int j = 0; j < 3; ++j) {
            m[i][j] = 0;
            for (int k = 0; k < 3; ++k)
                m[i][j] += rx[i][k] * rz[k][j];
        }
    for (int i = 0; i < 3; ++i)
        for (int j = 0; j < 3; ++j) {
            r[i][j] = 0;
            for (int k = 0; k < 3; ++k)
                r[i][j] += ry[i][k] * m[k][j];
        }
    for (int32_t v = 0; v < mesh->vertex_count; ++v) {
        double *p = mesh->positions + 3 * v, q[3];
        for (int i = 0; i < 3; ++i)
            q[i] = r[i][0] * p[0] + r[i][1] * p[1] + r[i][2] * p[2] + 100.0 * (i + 1);
        memcpy(p, q, sizeof q);
    }
    for (int i = 0; i < 3; ++i)
        true_normal[i] = r[i][0];
    return mesh;
}

static double angle_deg(const double a[3], const double b[3])
{
    double dot = fabs(a[0] * b[0] + a[1] * b[1] + a[2] * b[2]);
    return acos(fmin(1.0, dot)) * 180 / 3.14159265358979323846;
}

static double diagonal(const pz_mesh *mesh)
{
    double lo[3], hi[3];
    pz_mesh_bbox(mesh, lo, hi);
    return sqrt((hi[0] - lo[0]) * (hi[0] - lo[0]) + (hi[1] - lo[1]) * (hi[1] - lo[1]) + (hi[2] - lo[2]) * (hi[2] - lo[2]));
}

static void test_any_orientation(void)
{
    double normal[3];
    pz_mesh *mesh = turned_bodice(normal);
    pz_topology *topology = test_topology(mesh, &ctx);
    pz_symmetry s;
    REQUIRE_OK(pz_symmetry_detect(mesh, topology, PZ_SYMMETRY_AUTO, NULL, 0.0, &s, &ctx), ctx);
    /* The plane x = 0 went through the rotation and the move (100, 200, 300) with the mesh. */
    double offset = normal[0] * 100 + normal[1] * 200 + normal[2] * 300;
    double sign = s.normal[0] * normal[0] + s.normal[1] * normal[1] + s.normal[2] * normal[2] < 0 ? -1 : 1;
    printf("turned bodice: normal (%.5f %.5f %.5f), true (%.5f %.5f %.5f): %.4f degrees; offset %.3f (true %.3f); "
           "residual %.3g mm\n", s.normal[0], s.normal[1], s.normal[2], normal[0], normal[1], normal[2],
           angle_deg(s.normal, normal), s.offset, offset, s.residual_mm);
    CHECK(s.found && angle_deg(s.normal, normal) < 1.0 && fabs(sign * s.offset - offset) < 1.0 && s.axis == -1,
          "turned bodice: found %d, normal %.3f degrees off, offset %g against %g, axis %d", s.found,
          angle_deg(s.normal, normal), sign * s.offset, offset, s.axis);
    int involution = 0;
    for (int32_t v = 0; s.vertex_mirror && v < mesh->vertex_count; ++v)
        involution += s.vertex_mirror[v] >= 0 && s.vertex_mirror[s.vertex_mirror[v]] == v;
    CHECK(involution == mesh->vertex_count, "turned bodice: %d of %d vertices mapped back", involution,
          (int)mesh->vertex_count);
    pz_symmetry_clear(&s);

    /* Noise: every vertex moved by up to 0.5 % of the diagonal, along each axis (a fixed linear congruence). */
    double amplitude = 0.005 * diagonal(mesh);
    uint32_t state = 12345;
    for (int32_t v = 0; v < 3 * mesh->vertex_count; ++v) {
        state = state * 1664525u + 1013904223u;
        mesh->positions[v] += amplitude * (2.0 * (state >> 8) / 16777216.0 - 1.0) / sqrt(3.0);
    }
    REQUIRE_OK(pz_symmetry_detect(mesh, topology, PZ_SYMMETRY_AUTO, NULL, 0.0, &s, &ctx), ctx);
    printf("noisy turned bodice (0.5 %% of the diagonal): found %d, %.3f degrees off, residual %.3f %% of the "
           "diagonal\n", s.found, angle_deg(s.normal, normal), 100 * s.residual_rel);
    CHECK(s.found && s.residual_rel < 0.015 && angle_deg(s.normal, normal) < 2.0,
          "noisy bodice: found %d, residual %.4f, normal %.2f degrees off", s.found, s.residual_rel,
          angle_deg(s.normal, normal));
    pz_symmetry_clear(&s);
    pz_topology_free(&topology);
    pz_mesh_free(&mesh);
}

/*
 * No plane left: the +x half of the bodice 60 % wider, and the whole tapered
 * upwards (60 % fuller at the top than at the bottom), so that neither the
 * left-right plane nor the bodice's near top-bottom one (bust and hip alike:
 * 1.1-1.6 % with only one side changed) survives.
 */
static void test_bulge(void)
{
    pz_mesh *mesh = bodice();
    double lo[3], hi[3];
    pz_mesh_bbox(mesh, lo, hi);
    double middle_z = 0.5 * (lo[2] + hi[2]);
    for (int32_t v = 0; v < mesh->vertex_count; ++v) {
        double *p = mesh->positions + 3 * v, taper = 1 + 0.6 * (p[1] - lo[1]) / (hi[1] - lo[1]);
        p[0] *= (p[0] > 0 ? 1.6 : 1.0) * taper;
        p[2] = middle_z + taper * (p[2] - middle_z);
    }
    pz_topology *topology = test_topology(mesh, &ctx);
    pz_symmetry s;
    REQUIRE_OK(pz_symmetry_detect(mesh, topology, PZ_SYMMETRY_AUTO, NULL, 0.0, &s, &ctx), ctx);
    printf("lopsided tapered bodice: found %d, best residual %.2f %% of the diagonal, normal (%.3f %.3f %.3f)\n", s.found, 100 * s.residual_rel, s.normal[0], s.normal[1], s.normal[2]);
    CHECK(!s.found && s.residual_rel > 0.015 && !s.vertex_mirror, "lopsided bodice: found %d residual %.4f", s.found,
          s.residual_rel);
    pz_symmetry_clear(&s);

    /* A given plane is used as given, whatever its residual; an axis gets its offset fitted. */
    double plane[4] = {0, 0, 2, 20}; /* z = 10: the normal need not be unit */
    REQUIRE_OK(pz_symmetry_detect(mesh, topology, PZ_SYMMETRY_PLANE, plane, 0.0, &s, &ctx), ctx);
    CHECK(s.found && s.normal[2] == 1 && fabs(s.offset - 10) < 1e-12 && s.axis == 2 && s.vertex_mirror,
          "given plane: found %d normal (%g %g %g) offset %g axis %d", s.found, s.normal[0], s.normal[1], s.normal[2],
          s.offset, s.axis);
    pz_symmetry_clear(&s);
    double zero[4] = {0, 0, 0, 1};
    CHECK(pz_symmetry_detect(mesh, topology, PZ_SYMMETRY_PLANE, zero, 0.0, &s, &ctx) == PZ_ERR_USAGE &&
              pz_symmetry_detect(mesh, topology, PZ_SYMMETRY_PLANE, NULL, 0.0, &s, &ctx) == PZ_ERR_USAGE,
          "a zero or missing plane accepted");
    pz_symmetry_clear(&s);
    pz_topology_free(&topology);
    pz_mesh_free(&mesh);
}

/* The shared garments: the T-shirt has its plane along x, the parafashion shirt (its front open) none. */
static void test_shared(void)
{
    const char *data = test_shared_data();
    if (!data) {
        test_skip_part("shared garments (no ../shared/data)");
        return;
    }
    const char *names[] = {"diffavatar-tshirt.obj", "parafashion-shirt.obj"};
    for (int i = 0; i < 2; ++i) {
        char path[4096];
        snprintf(path, sizeof path, "%s/garments/%s", data, names[i]);
        pz_mesh *mesh = NULL;
        REQUIRE_OK(pz_mesh_read(path, &mesh, &ctx), ctx);
        pz_mesh_to_mm(mesh, PZ_UNITS_AUTO, NULL);
        REQUIRE_OK(pz_mesh_prepare(mesh, path, PZ_REPAIR_NONE, &ctx), ctx);
        pz_topology *topology = test_topology(mesh, &ctx);
        pz_symmetry s;
        double start = pz_seconds();
        REQUIRE_OK(pz_symmetry_detect(mesh, topology, PZ_SYMMETRY_AUTO, NULL, 0.0, &s, &ctx), ctx);
        printf("%s: found %d, normal (%.4f %.4f %.4f), residual %.2f %% of the diagonal, %.0f ms\n", names[i], s.found,
               s.normal[0], s.normal[1], s.normal[2], 100 * s.residual_rel, 1e3 * (pz_seconds() - start));
        if (i == 0)
            CHECK(s.found && s.axis == 0 && s.residual_rel < 0.015, "T-shirt: found %d axis %d residual %.4f", s.found,
                  s.axis, s.residual_rel);
        else
            CHECK(!s.found && s.residual_rel > 0.02, "shirt: found %d residual %.4f", s.found, s.residual_rel);
        pz_symmetry_clear(&s);
        pz_topology_free(&topology);
        pz_mesh_free(&mesh);
    }
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
    test_any_orientation();
    test_bulge();
    test_shared();
    return test_finish();
}

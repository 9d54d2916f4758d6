/*
 * tests/trace/test_trace.c -- the tracing graph and its paths on shapes whose
 * answer is known:
 *  - cylinder (axis z, radius 150, height 400): the vertex crosses follow the
 *    axis and the circumference, boundary nodes are ENTER/EXIT/ALONG, links
 *    join neighbours with positive weights; loops go round at one height
 *    (length about the circumference), border paths run along a ruling from
 *    one rim to the other;
 *  - every candidate on every shape is a valid path (consecutive vertices
 *    share an edge, no vertex twice, ENTER start and EXIT end for border
 *    paths, loops off the boundary), and the candidates do not depend on the
 *    thread count;
 *  - the M4 distance: 0 on a path's axis nodes, a parallel loop nearer than a
 *    crossing ruling; tangential meetings;
 *  - a flat rectangle: no ENTER node at the corners, one ENTER and one EXIT
 *    elsewhere on the border; no loops, border paths straight from side to
 *    side (none from a corner running beside the border);
 *    a tetrahedron with an unused vertex: no paths, no crash;
 *  - the bodice (a useful number of candidates), a closed torus (loops only),
 *    sketch snapping and its errors, paths through given vertices (returns
 *    cut out, gaps closed), option errors;
 *  - the shared parafashion skirt when ../shared/data is there: valid
 *    candidates, no detour left by smoothing, thread-count independent.
 *
 * SPDX-License-Identifier: GPL-3.0-or-later
 */
#include "field/field.h"
#include "generate/generate.h"
#include "io/io.h"
#include "trace/trace.h"
#include "test_meshes.h"
#include "trace_fixtures.h"

#include <math.h>
#include <stdio.h>

static pz_ctx ctx;

typedef struct fixture {
    pz_mesh *mesh;
    pz_topology *topology;
    pz_field *field;
    pz_trace_graph *graph;
} fixture;

static fixture fixture_of(pz_mesh *mesh)
{
    fixture f = {mesh, NULL, NULL, NULL};
    f.topology = test_topology(mesh, &ctx);
    REQUIRE_OK(pz_field_compute(mesh, f.topology, NULL, &f.field, &ctx), ctx);
    REQUIRE_OK(pz_trace_graph_build(mesh, f.topology, f.field->directions, NULL, &f.graph, &ctx), ctx);
    return f;
}

static fixture generated(pz_shape shape, int32_t faces)
{
    pz_generate_options options = {faces, 0, 0};
    pz_mesh *mesh = NULL;
    REQUIRE_OK(pz_generate(shape, &options, &mesh, &ctx), ctx);
    return fixture_of(mesh);
}

static void fixture_free(fixture *f)
{
    pz_trace_graph_free(&f->graph);
    pz_field_free(&f->field);
    pz_topology_free(&f->topology);
    pz_mesh_free(&f->mesh);
}

static pz_trace_paths *candidates(const fixture *f, const pz_trace_candidate_options *options)
{
    pz_trace_paths *paths = NULL;
    REQUIRE_OK(pz_trace_candidates(f->graph, f->mesh, f->topology, options, &paths, &ctx), ctx);
    return paths;
}

static double distance(const pz_mesh *mesh, int32_t a, int32_t b)
{
    const double *p = mesh->positions + 3 * a, *q = mesh->positions + 3 * b;
    return sqrt((p[0] - q[0]) * (p[0] - q[0]) + (p[1] - q[1]) * (p[1] - q[1]) + (p[2] - q[2]) * (p[2] - q[2]));
}

/* Every promise a path makes; returns 1 when all hold (failures are CHECKed). */
static int path_valid(const fixture *f, const pz_trace_path *path, const char *what, int index)
{
    int ok = 1;
    char *seen = calloc((size_t)f->mesh->vertex_count, 1);
    REQUIRE(seen, "out of memory");
    double length = 0.0;
    for (int32_t i = 0; i < path->vertex_count && ok; ++i) {
        int32_t v = path->vertices[i];
        ok = v >= 0 && v < f->mesh->vertex_count && path->arms[i] < 4 && !seen[v];
        CHECK(ok, "%s %d: vertex %d (position %d) out of range, repeated or bad arm %d", what, index, (int)v, (int)i,
              path->arms[i]);
        if (!ok)
            break;
        seen[v] = 1;
        int last = i + 1 == path->vertex_count;
        if (last && !path->closed)
            break;
        int32_t next = path->vertices[last ? 0 : i + 1];
        ok = test_share_edge(f->topology, v, next);
        CHECK(ok, "%s %d: vertices %d and %d share no edge", what, index, (int)v, (int)next);
        length += distance(f->mesh, v, next);
    }
    free(seen);
    if (ok) {
        ok = fabs(length - path->length_mm) < 1e-6 * (1.0 + length) && path->cost >= path->length_mm * (1 - 1e-9);
        CHECK(ok, "%s %d: length %g (stored %g), cost %g", what, index, length, path->length_mm, path->cost);
    }
    if (ok && path->kind == PZ_TRACE_BORDER) {
        uint8_t first = f->graph->node_kind[4 * path->vertices[0] + path->arms[0]];
        int32_t n = path->vertex_count - 1;
        uint8_t end = f->graph->node_kind[4 * path->vertices[n] + path->arms[n]];
        ok = !path->closed && first == PZ_TRACE_NODE_ENTER && end == PZ_TRACE_NODE_EXIT;
        CHECK(ok, "%s %d: border path from kind %d to kind %d", what, index, first, end);
        for (int32_t i = 1; i < n && ok; ++i) {
            ok = !f->topology->vertex_on_boundary[path->vertices[i]];
            CHECK(ok, "%s %d: border path touches the boundary inside (position %d)", what, index, (int)i);
        }
    }
    if (ok && path->kind == PZ_TRACE_LOOP) {
        ok = path->closed && path->vertex_count >= 6;
        CHECK(ok, "%s %d: loop closed %d with %d vertices", what, index, path->closed, (int)path->vertex_count);
        for (int32_t i = 0; i < path->vertex_count && ok; ++i) {
            ok = !f->topology->vertex_on_boundary[path->vertices[i]];
            CHECK(ok, "%s %d: loop on the boundary at position %d", what, index, (int)i);
        }
    }
    return ok;
}

static int all_valid(const fixture *f, const pz_trace_paths *paths, const char *what)
{
    int ok = 1;
    for (int32_t i = 0; i < paths->path_count; ++i)
        ok &= path_valid(f, &paths->paths[i], what, (int)i);
    return ok;
}

static int count_kind(const pz_trace_paths *paths, pz_trace_path_kind kind)
{
    int count = 0;
    for (int32_t i = 0; i < paths->path_count; ++i)
        count += paths->paths[i].kind == kind;
    return count;
}

/* ---------------------------------------------------------------- graph */

static void test_graph_cylinder(const fixture *f)
{
    const pz_trace_graph *g = f->graph;
    CHECK(g->node_count == 4 * f->mesh->vertex_count, "node count %d", (int)g->node_count);
    int bad_links = 0, links = g->link_offsets[g->node_count];
    for (int32_t n = 0; n < g->node_count; ++n)
        for (int32_t l = g->link_offsets[n]; l < g->link_offsets[n + 1]; ++l) {
            int32_t t = g->link_targets[l];
            bad_links += t < 0 || t >= g->node_count || !(g->link_weights[l] > 0.0) ||
                         !test_share_edge(f->topology, n / 4, t / 4);
        }
    CHECK(bad_links == 0, "%d of %d links bad", bad_links, links);
    /* 45 degrees: every directed edge follows one arm (two on an exact tie). */
    CHECK(links >= 2 * f->topology->edge_count && links <= 2 * 2 * f->topology->edge_count, "%d links for %d edges",
          links, (int)f->topology->edge_count);
    double worst_interior = 0.0;
    int bad_kinds = 0;
    for (int32_t v = 0; v < f->mesh->vertex_count; ++v) {
        double arm[3];
        pz_trace_arm_direction(g, v, 0, arm);
        /* On the cylinder the cross follows the axis (z) and the circumference: |arm.z| is 0 or 1. */
        double off = fmin(fabs(arm[2]), 1.0 - fabs(arm[2]));
        if (!f->topology->vertex_on_boundary[v]) {
            worst_interior = fmax(worst_interior, off);
            bad_kinds += g->node_kind[4 * v] != PZ_TRACE_NODE_INTERIOR;
            continue;
        }
        /* Boundary: two arms along the rim, one into the surface (towards the other rim), one out. */
        int kinds[4] = {0, 0, 0, 0};
        for (int k = 0; k < 4; ++k) {
            double d[3];
            pz_trace_arm_direction(g, v, k, d);
            double inward = f->mesh->positions[3 * v + 2] < 200.0 ? d[2] : -d[2];
            int kind = g->node_kind[4 * v + k];
            ++kinds[kind];
            bad_kinds += (kind == PZ_TRACE_NODE_ENTER && inward < 0.98) || (kind == PZ_TRACE_NODE_EXIT && inward > -0.98) ||
                         (kind == PZ_TRACE_NODE_ALONG && fabs(d[2]) > 0.02);
        }
        bad_kinds += kinds[PZ_TRACE_NODE_ENTER] != 1 || kinds[PZ_TRACE_NODE_EXIT] != 1 || kinds[PZ_TRACE_NODE_ALONG] != 2;
    }
    CHECK(worst_interior < sin(2.0 * TEST_PI / 180), "interior cross off the axis by %g", worst_interior);
    CHECK(bad_kinds == 0, "%d vertices with wrong node kinds or boundary arms", bad_kinds);
    CHECK(fabs(g->match_angle_deg - 45.0) < 1e-12 && g->drift_weight > 0, "defaults %g %g", g->match_angle_deg,
          g->drift_weight);
}

static void test_graph_options(const fixture *f)
{
    pz_trace_graph *graph = NULL;
    pz_trace_graph_options bad = {120.0, 0.0};
    CHECK(pz_trace_graph_build(f->mesh, f->topology, f->field->directions, &bad, &graph, &ctx) == PZ_ERR_USAGE &&
              !graph && strstr(ctx.error, "match angle"),
          "match angle 120 accepted: %s", ctx.error);
    bad = (pz_trace_graph_options){0.0, -1.0};
    CHECK(pz_trace_graph_build(f->mesh, f->topology, f->field->directions, &bad, &graph, &ctx) == PZ_ERR_USAGE &&
              !graph,
          "negative drift weight accepted");
    pz_trace_candidate_options negative = {.border_sources = -1};
    pz_trace_paths *paths = NULL;
    CHECK(pz_trace_candidates(f->graph, f->mesh, f->topology, &negative, &paths, &ctx) == PZ_ERR_USAGE && !paths,
          "negative source count accepted");
    /* Cancelled: no paths, the status says so (the tracing tasks not started are skipped). */
    volatile int stop = 1;
    pz_ctx cancelled;
    pz_ctx_quiet(&ctx, &cancelled);
    cancelled.cancel = &stop;
    CHECK(pz_trace_candidates(f->graph, f->mesh, f->topology, NULL, &paths, &cancelled) == PZ_ERR_CANCELLED &&
              !paths && strstr(cancelled.error, "cancelled"),
          "cancelled tracing: %s", cancelled.error);
}

/* ---------------------------------------------------------------- candidates */

static void test_cylinder_candidates(const fixture *f, const pz_trace_paths *paths)
{
    REQUIRE(all_valid(f, paths, "cylinder"), "invalid cylinder path");
    int loops = count_kind(paths, PZ_TRACE_LOOP), borders = count_kind(paths, PZ_TRACE_BORDER);
    printf("cylinder: %d loops, %d border paths\n", loops, borders);
    CHECK(loops >= 5 && borders >= 10, "%d loops, %d border paths", loops, borders);
    double circumference = 2 * TEST_PI * 150.0, edge = f->graph->mean_edge_length;
    for (int32_t i = 0; i < paths->path_count; ++i) {
        const pz_trace_path *p = &paths->paths[i];
        double zmin = 1e9, zmax = -1e9, amin = 1e9, amax = -1e9;
        for (int32_t k = 0; k < p->vertex_count; ++k) {
            const double *q = f->mesh->positions + 3 * p->vertices[k];
            zmin = fmin(zmin, q[2]), zmax = fmax(zmax, q[2]);
            double angle = atan2(q[1], q[0]) * 150.0; /* arc length round the axis */
            amin = fmin(amin, angle), amax = fmax(amax, angle);
        }
        if (p->kind == PZ_TRACE_LOOP) {
            CHECK(zmax - zmin < 1.01 * edge && fabs(p->length_mm - circumference) < 0.03 * circumference,
                  "loop %d: heights %g..%g, length %g", (int)i, zmin, zmax, p->length_mm);
        } else {
            /* A ruling: rim to rim (0 to 400), at one angle (the seam of atan2 at -pi makes amax-amin large). */
            double spread = amax - amin;
            if (spread > circumference / 2)
                spread = circumference - spread;
            CHECK(zmin < 1e-6 && zmax > 400 - 1e-6 && (spread < 1.01 * edge || spread > circumference - 1.01 * edge) &&
                      fabs(p->length_mm - 400.0) < 0.03 * 400.0,
                  "border path %d: heights %g..%g, spread %g mm, length %g", (int)i, zmin, zmax, spread,
                  p->length_mm);
        }
    }
}

static int paths_equal(const pz_trace_paths *a, const pz_trace_paths *b)
{
    if (a->path_count != b->path_count)
        return 0;
    for (int32_t i = 0; i < a->path_count; ++i) {
        const pz_trace_path *p = &a->paths[i], *q = &b->paths[i];
        if (p->kind != q->kind || p->vertex_count != q->vertex_count || p->cost != q->cost ||
            memcmp(p->vertices, q->vertices, (size_t)p->vertex_count * sizeof(int32_t)) ||
            memcmp(p->arms, q->arms, (size_t)p->vertex_count))
            return 0;
    }
    return 1;
}

static void test_deterministic(const fixture *f, const char *what)
{
    pz_trace_candidate_options one = {.threads = 1}, two = {.threads = 2};
    pz_trace_paths *a = candidates(f, &one), *b = candidates(f, &two);
    CHECK(paths_equal(a, b), "%s: candidates differ between 1 and 2 threads (%d vs %d paths)", what,
          (int)a->path_count, (int)b->path_count);
    pz_trace_paths_free(&a);
    pz_trace_paths_free(&b);
}

/* The loop and the border path nearest to height z / angle 0. */
static const pz_trace_path *pick(const fixture *f, const pz_trace_paths *paths, pz_trace_path_kind kind,
                                 const pz_trace_path *unlike)
{
    for (int32_t i = 0; i < paths->path_count; ++i) {
        const pz_trace_path *p = &paths->paths[i];
        if (p->kind != kind || p == unlike)
            continue;
        if (unlike) { /* a different height: share no vertex */
            int shared = 0;
            for (int32_t k = 0; k < p->vertex_count && !shared; ++k)
                for (int32_t j = 0; j < unlike->vertex_count && !shared; ++j)
                    shared = p->vertices[k] == unlike->vertices[j];
            if (shared)
                continue;
        }
        (void)f;
        return p;
    }
    return NULL;
}

static void test_distance_and_tangency(const fixture *f, const pz_trace_paths *paths)
{
    const pz_trace_path *loop = pick(f, paths, PZ_TRACE_LOOP, NULL);
    const pz_trace_path *other = pick(f, paths, PZ_TRACE_LOOP, loop);
    const pz_trace_path *ruling = pick(f, paths, PZ_TRACE_BORDER, NULL);
    REQUIRE(loop && other && ruling, "need two loops and a ruling");
    double *dist = malloc((size_t)f->graph->node_count * sizeof(double));
    REQUIRE(dist, "out of memory");
    REQUIRE_OK(pz_trace_distance(f->graph, loop, 1, 0, dist, &ctx), ctx);
    int zero = 1;
    for (int32_t k = 0; k < loop->vertex_count; ++k)
        zero &= dist[4 * loop->vertices[k] + loop->arms[k]] == 0.0 &&
                dist[4 * loop->vertices[k] + (loop->arms[k] + 2) % 4] == 0.0;
    CHECK(zero && pz_trace_path_mean_distance(loop, dist) == 0.0, "distance not 0 on the path's axis nodes");
    double parallel = pz_trace_path_mean_distance(other, dist), crossing = pz_trace_path_mean_distance(ruling, dist);
    printf("distance from a loop: parallel loop %g, crossing ruling %g\n", parallel, crossing);
    CHECK(parallel > 0.0 && parallel < crossing, "parallel %g not nearer than crossing %g", parallel, crossing);
    REQUIRE_OK(pz_trace_distance(f->graph, NULL, 0, 1, dist, &ctx), ctx);
    int along_zero = 1, finite = 0;
    for (int32_t n = 0; n < f->graph->node_count; ++n) {
        if (f->graph->node_kind[n] == PZ_TRACE_NODE_ALONG)
            along_zero &= dist[n] == 0.0;
        finite += isfinite(dist[n]);
    }
    CHECK(along_zero && finite > f->graph->node_count / 4, "from the boundary: ALONG nodes 0 %d, %d finite", along_zero,
          finite);
    /* Paths added to a distance: the full computation's result, bit for bit. */
    pz_trace_path three[3] = {*loop, *other, *ruling};
    double *added = malloc((size_t)f->graph->node_count * sizeof(double));
    REQUIRE(added, "out of memory");
    REQUIRE_OK(pz_trace_distance(f->graph, three, 3, 1, dist, &ctx), ctx);
    REQUIRE_OK(pz_trace_distance(f->graph, three, 1, 1, added, &ctx), ctx);
    REQUIRE_OK(pz_trace_distance_add(f->graph, three + 1, 1, added, &ctx), ctx);
    REQUIRE_OK(pz_trace_distance_add(f->graph, three + 2, 1, added, &ctx), ctx);
    CHECK(memcmp(dist, added, (size_t)f->graph->node_count * sizeof(double)) == 0,
          "distance with paths added one by one differs from the distance of all three");
    free(added);
    free(dist);

    int32_t n = f->mesh->vertex_count;
    CHECK(!pz_trace_paths_tangential(loop, ruling, n), "a loop and a ruling cross orthogonally");
    CHECK(!pz_trace_paths_tangential(loop, other, n), "two disjoint loops do not meet");
    CHECK(pz_trace_paths_tangential(loop, loop, n), "a loop runs along itself");
    /* The same ruling walked backwards (arms turned by 180 degrees): same axis, tangential. */
    pz_trace_path reversed;
    REQUIRE_OK(pz_trace_path_copy(ruling, &reversed, &ctx), ctx);
    for (int32_t k = 0; k < ruling->vertex_count; ++k) {
        int32_t j = ruling->vertex_count - 1 - k;
        reversed.vertices[k] = ruling->vertices[j], reversed.arms[k] = (uint8_t)((ruling->arms[j] + 2) % 4);
    }
    CHECK(pz_trace_paths_tangential(ruling, &reversed, n), "a ruling and itself reversed are tangential");
    /* Only its two ends shared with another path ending there: ignored. */
    pz_trace_path ends = reversed;
    ends.vertex_count = 1;
    ends.vertices = reversed.vertices + ruling->vertex_count - 1;
    ends.arms = reversed.arms + ruling->vertex_count - 1;
    CHECK(!pz_trace_paths_tangential(ruling, &ends, n), "meeting at both ends counted as tangential");
    pz_trace_path_clear(&reversed);
    CHECK(reversed.vertices == NULL && reversed.vertex_count == 0, "clear did not zero the path");
}

static void test_snap(const fixture *f)
{
    double points[24 * 3];
    for (int i = 0; i < 24; ++i) {
        double t = 2 * TEST_PI * i / 24;
        points[3 * i] = 152 * cos(t), points[3 * i + 1] = 152 * sin(t), points[3 * i + 2] = 201;
    }
    pz_trace_path path;
    REQUIRE_OK(pz_trace_snap_polyline(f->graph, f->mesh, f->topology, points, 24, 1, 0.0, "ring", &path, &ctx), ctx);
    CHECK(path.kind == PZ_TRACE_SKETCH && path.closed && path_valid(f, &path, "snapped ring", 0), "snapped ring");
    double zmin = 1e9, zmax = -1e9;
    int along_circumference = 1;
    for (int32_t k = 0; k < path.vertex_count; ++k) {
        zmin = fmin(zmin, f->mesh->positions[3 * path.vertices[k] + 2]);
        zmax = fmax(zmax, f->mesh->positions[3 * path.vertices[k] + 2]);
        double arm[3];
        pz_trace_arm_direction(f->graph, path.vertices[k], path.arms[k], arm);
        along_circumference &= fabs(arm[2]) < 0.1;
    }
    CHECK(zmax - zmin < 2.01 * f->graph->mean_edge_length && along_circumference,
          "snapped ring spans heights %g..%g; arms along the circumference %d", zmin, zmax, along_circumference);
    pz_trace_path_clear(&path);
    points[3 * 5] = 1000.0;
    CHECK(pz_trace_snap_polyline(f->graph, f->mesh, f->topology, points, 24, 1, 0.0, "ring", &path, &ctx) ==
                  PZ_ERR_DATA &&
              strstr(ctx.error, "ring: point 5") && path.vertices == NULL,
          "a far point: %s", ctx.error);
}

/* A route that comes back to a vertex: the stretch in between is cut out, gaps are closed. */
static void test_path_through(const fixture *f)
{
    /* Cylinder grid: consecutive vertex indices are neighbours round a row; rows are far apart in index. */
    int32_t columns = 0;
    while (columns < f->mesh->vertex_count && fabs(f->mesh->positions[3 * columns + 2] -
                                                   f->mesh->positions[2]) < 1e-9)
        ++columns;
    REQUIRE(columns > 8, "cylinder rows: %d", (int)columns);
    int32_t back[] = {3 * columns + 1, 3 * columns + 6, 6 * columns + 6, 3 * columns + 6, 3 * columns + 9};
    pz_trace_path path;
    REQUIRE_OK(pz_trace_path_through(f->graph, f->mesh, f->topology, back, 5, 0, &path, &ctx), ctx);
    int visits_far = 0;
    for (int32_t k = 0; k < path.vertex_count; ++k)
        visits_far += path.vertices[k] == 6 * columns + 6;
    CHECK(path_valid(f, &path, "through", 0) && !visits_far && path.vertices[0] == back[0] &&
              path.vertices[path.vertex_count - 1] == back[4],
          "route back and forth: %d vertices, far vertex kept %d", (int)path.vertex_count, visits_far);
    pz_trace_path_clear(&path);
    int32_t ring[] = {3 * columns, 3 * columns + columns / 3, 3 * columns + 2 * columns / 3, 3 * columns};
    REQUIRE_OK(pz_trace_path_through(f->graph, f->mesh, f->topology, ring, 4, 1, &path, &ctx), ctx);
    CHECK(path.closed && path.vertex_count == columns && path_valid(f, &path, "closed through", 0),
          "closed row: %d of %d vertices", (int)path.vertex_count, (int)columns);
    pz_trace_path_clear(&path);
    int32_t bad[] = {0, f->mesh->vertex_count};
    CHECK(pz_trace_path_through(f->graph, f->mesh, f->topology, bad, 2, 0, &path, &ctx) == PZ_ERR_DATA,
          "vertex out of range accepted");
}

static void test_cylinder(void)
{
    fixture f = generated(PZ_SHAPE_CYLINDER, 4000);
    test_graph_cylinder(&f);
    test_graph_options(&f);
    pz_trace_paths *paths = candidates(&f, NULL);
    test_cylinder_candidates(&f, paths);
    test_distance_and_tangency(&f, paths);
    pz_trace_paths_free(&paths);
    test_deterministic(&f, "cylinder");
    test_snap(&f);
    test_path_through(&f);
    fixture_free(&f);
}

static void test_bodice(void)
{
    fixture f = generated(PZ_SHAPE_BODICE, 7000);
    double start = pz_seconds();
    pz_trace_paths *paths = candidates(&f, NULL);
    double ms = 1e3 * (pz_seconds() - start);
    int loops = count_kind(paths, PZ_TRACE_LOOP), borders = count_kind(paths, PZ_TRACE_BORDER);
    printf("bodice %d faces: %d loops, %d border paths (%.0f ms, not a test figure)\n", (int)f.mesh->face_count,
           loops, borders, ms);
    CHECK(all_valid(&f, paths, "bodice"), "invalid bodice path");
    CHECK(loops >= 5 && borders >= 10 && paths->path_count <= 200, "%d loops, %d border paths", loops, borders);
    pz_trace_candidate_options only_loops = {.border = -1};
    pz_trace_paths *loop_paths = candidates(&f, &only_loops);
    CHECK(count_kind(loop_paths, PZ_TRACE_BORDER) == 0 && loop_paths->path_count > 0, "border = -1");
    pz_trace_paths_free(&loop_paths);
    pz_trace_paths_free(&paths);
    test_deterministic(&f, "bodice");
    fixture_free(&f);
}

static void test_torus(void)
{
    fixture f = fixture_of(test_grid(48, 16, TEST_GRID_TORUS, 0, &ctx));
    pz_trace_paths *paths = candidates(&f, NULL);
    int loops = count_kind(paths, PZ_TRACE_LOOP);
    printf("torus: %d loops of %d paths\n", loops, (int)paths->path_count);
    CHECK(loops > 0 && loops == paths->path_count, "closed surface: %d loops of %d paths", loops,
          (int)paths->path_count);
    CHECK(all_valid(&f, paths, "torus"), "invalid torus path");
    pz_trace_paths_free(&paths);
    fixture_free(&f);
}

/* A flat rectangle (a disk): no loops; border paths are straight grid lines from one side to the opposite one. */
static void test_flat(void)
{
    fixture f = fixture_of(test_grid(24, 12, TEST_GRID_FLAT, 0, &ctx));
    int corners_ok = 0, sides_ok = 0, boundary = 0;
    for (int32_t v = 0; v < f.mesh->vertex_count; ++v) {
        if (!f.topology->vertex_on_boundary[v])
            continue;
        int enter = 0, exit = 0;
        for (int k = 0; k < 4; ++k)
            enter += f.graph->node_kind[4 * v + k] == PZ_TRACE_NODE_ENTER,
                exit += f.graph->node_kind[4 * v + k] == PZ_TRACE_NODE_EXIT;
        double x = f.mesh->positions[3 * v], y = f.mesh->positions[3 * v + 1];
        int corner = (x == 0 || x == 24) && (y == 0 || y == 12);
        ++boundary;
        corners_ok += corner && enter == 0 && exit == 2;
        sides_ok += !corner && enter == 1 && exit == 1;
    }
    CHECK(corners_ok == 4 && sides_ok == boundary - 4, "flat: %d of 4 corners without ENTER, %d of %d sides with one",
          corners_ok, sides_ok, boundary - 4);
    pz_trace_paths *paths = candidates(&f, NULL);
    int straight = 0;
    for (int32_t i = 0; i < paths->path_count; ++i) {
        const pz_trace_path *p = &paths->paths[i];
        const double *first = f.mesh->positions + 3 * p->vertices[0];
        int same_x = 1, same_y = 1;
        for (int32_t k = 1; k < p->vertex_count; ++k) {
            same_x &= f.mesh->positions[3 * p->vertices[k]] == first[0];
            same_y &= f.mesh->positions[3 * p->vertices[k] + 1] == first[1];
        }
        int is_straight = (same_x && p->vertex_count == 13) || (same_y && p->vertex_count == 25);
        straight += is_straight;
    }
    printf("flat grid: %d border paths, %d straight side to side\n", (int)paths->path_count, straight);
    CHECK(all_valid(&f, paths, "flat") && count_kind(paths, PZ_TRACE_LOOP) == 0 && paths->path_count >= 10 &&
              straight == paths->path_count,
          "flat: %d paths, %d straight, %d loops", (int)paths->path_count, straight, count_kind(paths, PZ_TRACE_LOOP));
    pz_trace_paths_free(&paths);
    fixture_free(&f);
}

/* Degenerate inputs: a tetrahedron (too small for any loop) with an unused vertex: no paths, no crash. */
static void test_tiny(void)
{
    static const double positions[] = {1, 1, 1, 1, -1, -1, -1, 1, -1, -1, -1, 1, 5, 5, 5};
    static const int32_t faces[] = {0, 1, 2, 0, 3, 1, 0, 2, 3, 1, 3, 2};
    fixture f = fixture_of(test_mesh_from(5, positions, 4, faces, &ctx));
    pz_trace_paths *paths = candidates(&f, NULL);
    CHECK(paths->path_count == 0, "tetrahedron: %d paths", (int)paths->path_count);
    CHECK(f.graph->link_offsets[4 * 4 + 4] == f.graph->link_offsets[4 * 4], "the unused vertex has links");
    double *dist = malloc((size_t)f.graph->node_count * sizeof(double));
    REQUIRE(dist, "out of memory");
    REQUIRE_OK(pz_trace_distance(f.graph, NULL, 0, 1, dist, &ctx), ctx);
    CHECK(isinf(dist[0]) && isinf(dist[16]), "no sources: every node unreachable");
    free(dist);
    pz_trace_paths_free(&paths);
    fixture_free(&f);
}

/* 1 when no path still goes round a triangle (a-b-c with a-c an edge) where smoothing may cut it. */
static int no_detours(const fixture *f, const pz_trace_paths *paths)
{
    int detours = 0;
    for (int32_t i = 0; i < paths->path_count; ++i) {
        const pz_trace_path *p = &paths->paths[i];
        int32_t n = p->vertex_count;
        if (p->closed && n <= 6)
            continue;
        for (int32_t k = p->closed ? 0 : 1; k < (p->closed ? n : n - 1); ++k) {
            int32_t a = p->vertices[(k + n - 1) % n], c = p->vertices[(k + 1) % n];
            detours += test_share_edge(f->topology, a, c) &&
                       !(f->topology->vertex_on_boundary[a] && f->topology->vertex_on_boundary[c]);
        }
    }
    CHECK(detours == 0, "%d detours left", detours);
    return detours == 0;
}

/* A real garment (skipped without ../shared/data): valid, smoothed, deterministic candidates. */
static void test_shared_skirt(void)
{
    const char *dir = test_shared_data();
    if (!dir) {
        test_skip_part("shared skirt (no ../shared/data)");
        return;
    }
    char path[4096];
    snprintf(path, sizeof path, "%s/garments/parafashion-skirt.obj", dir);
    pz_mesh *mesh = NULL;
    REQUIRE_OK(pz_mesh_read(path, &mesh, &ctx), ctx);
    pz_mesh_to_mm(mesh, PZ_UNITS_AUTO, NULL);
    REQUIRE_OK(pz_mesh_prepare(mesh, path, PZ_REPAIR_DROP_DEGENERATE | PZ_REPAIR_DROP_DUPLICATES | PZ_REPAIR_ORIENT,
                               &ctx),
               ctx);
    fixture f = fixture_of(mesh);
    pz_trace_paths *smoothed = candidates(&f, NULL);
    pz_trace_candidate_options raw_options = {.smooth = -1};
    pz_trace_paths *raw = candidates(&f, &raw_options);
    double smoothed_length = 0, raw_length = 0;
    for (int32_t i = 0; i < smoothed->path_count; ++i)
        smoothed_length += smoothed->paths[i].length_mm / smoothed->path_count;
    for (int32_t i = 0; i < raw->path_count; ++i)
        raw_length += raw->paths[i].length_mm / raw->path_count;
    printf("skirt: %d candidates, mean length %.1f mm smoothed, %.1f raw\n", (int)smoothed->path_count,
           smoothed_length, raw_length);
    CHECK(all_valid(&f, smoothed, "skirt") && all_valid(&f, raw, "raw skirt"), "invalid skirt path");
    CHECK(no_detours(&f, smoothed), "skirt: smoothing left detours");
    CHECK(smoothed->path_count >= 50 && count_kind(smoothed, PZ_TRACE_LOOP) > 0, "skirt: %d candidates",
          (int)smoothed->path_count);
    pz_trace_paths_free(&smoothed);
    pz_trace_paths_free(&raw);
    test_deterministic(&f, "skirt");
    fixture_free(&f);
}

int main(void)
{
    pz_ctx_init(&ctx);
    ctx.quiet = 1;
    test_cylinder();
    test_bodice();
    test_torus();
    test_flat();
    test_tiny();
    test_shared_skirt();
    return test_finish();
}

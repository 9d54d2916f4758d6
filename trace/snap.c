/*
 * trace/snap.c -- paths through given vertices: a sketched polyline snapped
 * to mesh edges (pz_trace_snap_polyline) and the general vertex-sequence to
 * path step it and the mirror of a path share (pz_trace_path_through).
 *
 * Gaps between consecutive vertices are closed by A* over the mesh edges
 * (3D edge lengths, the straight-line distance as heuristic), which touches
 * only the region between the two vertices. Each point of a polyline goes to
 * its nearest vertex by a linear scan (O(points x vertices): sketches have a
 * few hundred points). The distance to the nearest vertex stands for the
 * distance to the mesh; it overestimates by at most about one edge, well
 * inside the default tolerance of five mean edges.
 *
 * SPDX-License-Identifier: GPL-3.0-or-later
 */
#include "trace/trace.h"
#include "core/vec.h"
#include "trace/internal.h"

#include <math.h>
#include <stdlib.h>
#include <string.h>

/* Scratch for A* between vertices and for building one path. */
typedef struct walker {
    const pz_mesh *mesh;
    const pz_topology *topology;
    double *dist;        /* vertex_count, INFINITY when unreached */
    int32_t *pred;       /* vertex_count */
    int32_t *touched;    /* vertices whose dist is finite */
    size_t touched_count;
    int32_t *position;   /* vertex_count: index in the path being built, -1 when not in it */
    int32_t *route;      /* vertex_count: one A* route, target first */
    pz_heap heap;
    int32_t *sequence;   /* the path being built */
    int32_t length, capacity;
} walker;

static void walker_free(walker *w)
{
    free(w->dist), free(w->pred), free(w->touched), free(w->position), free(w->route), free(w->sequence);
    pz_heap_free(&w->heap);
}

static int walker_init(walker *w, const pz_mesh *mesh, const pz_topology *topology)
{
    memset(w, 0, sizeof *w);
    w->mesh = mesh, w->topology = topology;
    size_t count = (size_t)mesh->vertex_count + 1;
    w->dist = malloc(count * sizeof(double));
    w->pred = malloc(count * sizeof(int32_t));
    w->touched = malloc(count * sizeof(int32_t));
    w->position = malloc(count * sizeof(int32_t));
    w->route = malloc(count * sizeof(int32_t));
    w->capacity = 64;
    w->sequence = malloc((size_t)w->capacity * sizeof(int32_t));
    if (!w->dist || !w->pred || !w->touched || !w->position || !w->route || !w->sequence)
        return 0;
    for (size_t v = 0; v < count; ++v)
        w->dist[v] = INFINITY, w->position[v] = -1;
    return 1;
}

static double vertex_distance(const pz_mesh *mesh, int32_t a, int32_t b)
{
    double d[3];
    pz_vec3_sub(mesh->positions + 3 * (size_t)a, mesh->positions + 3 * (size_t)b, d);
    return sqrt(pz_vec3_dot(d, d));
}

/*
 * A* from `from` to `to` over mesh edges. Writes the route (to first, from
 * last) into w->route and returns its vertex count; 0 when `to` cannot be
 * reached; -1 when out of memory.
 */
static int32_t shortest_route(walker *w, int32_t from, int32_t to)
{
    for (size_t i = 0; i < w->touched_count; ++i)
        w->dist[w->touched[i]] = INFINITY;
    w->touched_count = 0, w->heap.count = 0;
    w->dist[from] = 0.0, w->pred[from] = -1, w->touched[w->touched_count++] = from;
    if (!pz_heap_push(&w->heap, vertex_distance(w->mesh, from, to), from))
        return -1;
    int32_t ring[256];
    double key;
    int32_t u;
    int found = 0;
    while (pz_heap_pop(&w->heap, &key, &u)) {
        if (key > w->dist[u] + vertex_distance(w->mesh, u, to) + 1e-9)
            continue; /* stale */
        if (u == to) {
            found = 1;
            break;
        }
        int32_t count = pz_topology_vertex_ring(w->topology, u, ring, 256);
        for (int32_t i = 0; i < count && i < 256; ++i) {
            int32_t t = ring[i];
            double nd = w->dist[u] + vertex_distance(w->mesh, u, t);
            if (!(nd < w->dist[t]))
                continue;
            if (w->dist[t] == INFINITY)
                w->touched[w->touched_count++] = t;
            w->dist[t] = nd, w->pred[t] = u;
            if (!pz_heap_push(&w->heap, nd + vertex_distance(w->mesh, t, to), t))
                return -1;
        }
    }
    if (!found)
        return 0;
    int32_t count = 0;
    for (int32_t v = to; v >= 0; v = w->pred[v])
        w->route[count++] = v;
    return count;
}

/* Appends v to the sequence; when v is already in it, cuts the sequence back to v's first visit. */
static int sequence_append(walker *w, int32_t v)
{
    int32_t at = w->position[v];
    if (at >= 0) {
        for (int32_t i = at + 1; i < w->length; ++i)
            w->position[w->sequence[i]] = -1;
        w->length = at + 1;
        return 1;
    }
    if (w->length == w->capacity) {
        int32_t *grown = realloc(w->sequence, 2 * (size_t)w->capacity * sizeof(int32_t));
        if (!grown)
            return 0;
        w->sequence = grown, w->capacity *= 2;
    }
    w->position[v] = w->length;
    w->sequence[w->length++] = v;
    return 1;
}

/*
 * Walks from the sequence's last vertex to v along the shortest route,
 * appending the route's vertices (v itself only when include_target).
 * Returns PZ_OK, PZ_ERR_DATA (unreachable) or PZ_ERR_NOMEM.
 */
static pz_status walk_to(walker *w, int32_t v, int include_target, pz_ctx *ctx)
{
    int32_t last = w->sequence[w->length - 1];
    int32_t count = shortest_route(w, last, v);
    if (count < 0)
        return pz_error(ctx, PZ_ERR_NOMEM, "trace: out of memory joining vertices %d and %d", (int)last, (int)v);
    if (count == 0)
        return pz_error(ctx, PZ_ERR_DATA, "trace: vertices %d and %d lie in different components", (int)last, (int)v);
    for (int32_t i = count - 2; i >= (include_target ? 0 : 1); --i)
        if (!sequence_append(w, w->route[i]))
            return pz_error(ctx, PZ_ERR_NOMEM, "trace: out of memory for a path");
    return PZ_OK;
}

/* Arms along the tangent, then length and cost, of a finished path. */
static void path_arms_and_cost(const pz_trace_graph *graph, const pz_mesh *mesh, pz_trace_path *path)
{
    int32_t count = path->vertex_count;
    for (int32_t i = 0; i < count; ++i) {
        int32_t before = i > 0 ? i - 1 : path->closed ? count - 1 : 0;
        int32_t after = i + 1 < count ? i + 1 : path->closed ? 0 : count - 1;
        double tangent[3];
        pz_vec3_sub(mesh->positions + 3 * (size_t)path->vertices[after], mesh->positions + 3 * (size_t)path->vertices[before],
             tangent);
        path->arms[i] = (uint8_t)pz_trace_closest_arm(graph, path->vertices[i], tangent);
    }
    trace_path_measure(graph, mesh, path);
}

/* Fills *out from the walker's sequence. */
static pz_status path_from_sequence(const pz_trace_graph *graph, const walker *w, int closed, pz_trace_path *out,
                                    pz_ctx *ctx)
{
    memset(out, 0, sizeof *out);
    out->kind = PZ_TRACE_SKETCH;
    out->closed = closed && w->length >= 3;
    out->vertex_count = w->length;
    out->vertices = malloc(((size_t)w->length + 1) * sizeof(int32_t));
    out->arms = malloc((size_t)w->length + 1);
    if (!out->vertices || !out->arms) {
        pz_trace_path_clear(out);
        return pz_error(ctx, PZ_ERR_NOMEM, "trace: out of memory for a path of %d vertices", (int)w->length);
    }
    memcpy(out->vertices, w->sequence, (size_t)w->length * sizeof(int32_t));
    path_arms_and_cost(graph, w->mesh, out);
    return PZ_OK;
}

static pz_status walk_sequence(walker *w, const int32_t *vertices, int32_t count, int closed, pz_ctx *ctx)
{
    int32_t vertex_count = w->mesh->vertex_count;
    for (int32_t i = 0; i < count; ++i)
        if (vertices[i] < 0 || vertices[i] >= vertex_count || w->topology->vertex_halfedge[vertices[i]] < 0)
            return pz_error(ctx, PZ_ERR_DATA, "trace: path vertex %d (position %d) is not a mesh vertex in use",
                            (int)vertices[i], (int)i);
    /* A closed input that ends where it starts would collapse onto its first vertex: drop the repeat. */
    while (closed && count > 1 && vertices[count - 1] == vertices[0])
        --count;
    if (count > 0 && !sequence_append(w, vertices[0]))
        return pz_error(ctx, PZ_ERR_NOMEM, "trace: out of memory for a path");
    for (int32_t i = 1; i < count; ++i) {
        if (vertices[i] == w->sequence[w->length - 1])
            continue;
        pz_status status = walk_to(w, vertices[i], 1, ctx);
        if (status)
            return status;
    }
    if (closed && w->length >= 3)
        return walk_to(w, w->sequence[0], 0, ctx);
    return PZ_OK;
}

pz_status pz_trace_path_through(const pz_trace_graph *graph, const pz_mesh *mesh, const pz_topology *topology,
                                const int32_t *vertices, int32_t count, int closed, pz_trace_path *out,
                                pz_ctx *ctx)
{
    memset(out, 0, sizeof *out);
    walker w;
    pz_status status = PZ_OK;
    if (!walker_init(&w, mesh, topology))
        status = pz_error(ctx, PZ_ERR_NOMEM, "trace: out of memory for a path on %d vertices", (int)mesh->vertex_count);
    if (!status)
        status = walk_sequence(&w, vertices, count, closed, ctx);
    if (!status)
        status = path_from_sequence(graph, &w, closed, out, ctx);
    walker_free(&w);
    return status;
}

/* The vertex in use nearest to p, and its distance. */
static int32_t nearest_vertex(const pz_mesh *mesh, const pz_topology *topology, const double *p, double *distance)
{
    int32_t best = -1;
    double best_d2 = INFINITY;
    for (int32_t v = 0; v < mesh->vertex_count; ++v) {
        if (topology->vertex_halfedge[v] < 0)
            continue;
        double d[3];
        pz_vec3_sub(mesh->positions + 3 * (size_t)v, p, d);
        double d2 = pz_vec3_dot(d, d);
        if (d2 < best_d2)
            best_d2 = d2, best = v;
    }
    *distance = sqrt(best_d2);
    return best;
}

pz_status pz_trace_snap_polyline(const pz_trace_graph *graph, const pz_mesh *mesh, const pz_topology *topology,
                                 const double *points, int32_t point_count, int closed, double tolerance_mm,
                                 const char *name, pz_trace_path *out, pz_ctx *ctx)
{
    memset(out, 0, sizeof *out);
    if (!name)
        name = "sketch";
    if (point_count < 1)
        return pz_error(ctx, PZ_ERR_DATA, "%s: a curve without points", name);
    double tolerance = tolerance_mm > 0.0 ? tolerance_mm : 5.0 * graph->mean_edge_length;
    int32_t *snapped = malloc((size_t)point_count * sizeof(int32_t));
    if (!snapped)
        return pz_error(ctx, PZ_ERR_NOMEM, "%s: out of memory snapping %d points", name, (int)point_count);
    for (int32_t i = 0; i < point_count; ++i) {
        double distance;
        snapped[i] = nearest_vertex(mesh, topology, points + 3 * (size_t)i, &distance);
        if (snapped[i] < 0 || !(distance <= tolerance)) {
            free(snapped);
            return pz_error(ctx, PZ_ERR_DATA, "%s: point %d (%g, %g, %g) lies %.3g mm from the mesh (tolerance %.3g mm)",
                            name, (int)i, points[3 * (size_t)i], points[3 * (size_t)i + 1], points[3 * (size_t)i + 2],
                            distance, tolerance);
        }
    }
    pz_status status = pz_trace_path_through(graph, mesh, topology, snapped, point_count, closed, out, ctx);
    free(snapped);
    return status;
}

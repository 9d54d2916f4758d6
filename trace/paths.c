/*
 * trace/paths.c -- candidate paths on the tracing graph (pietroni2022
 * Sec. 4.2, "Path classification" and "Path insertion"), the M4 distance
 * and the tangential test.
 *
 * Candidates:
 *  - Sources are subsampled uniformly by farthest-point sampling (3D
 *    distance; the first source is the candidate nearest the candidates'
 *    centroid, ties to the lowest index): interior vertices for loops (arms
 *    0 and 1 of each: arms 2 and 3 give the same loops reversed), boundary
 *    vertices with an ENTER node for border paths (each of their ENTER
 *    nodes; convex corners have none).
 *  - A loop is the shortest cycle through its source node: the search starts
 *    by relaxing the source's out-links with the source itself unreached, and
 *    ends when the source is popped. A link closing the cycle is taken only
 *    after TRACE_MIN_LOOP_EDGES edges, so a loop is never trivially short.
 *    Loops stay off the boundary (boundary nodes are never entered): a loop
 *    along the border would cut nothing.
 *  - A border path is the shortest path from an ENTER node to the first EXIT
 *    node popped, at least TRACE_MIN_BORDER_EDGES edges away. Other boundary
 *    nodes are entered but not expanded: a border path touches the boundary
 *    at its two ends only (no strips along the border, Fig. 9).
 *  - Both searches stop beyond max_length * (1 + drift_weight / 2) of cost
 *    (a path drifting on average half-way to the match angle). Paths longer than
 *    max_length or visiting a vertex twice (on two arms) are dropped; the
 *    others are smoothed (smooth_path below), measured again (length, cost),
 *    deduplicated by vertex set and sorted.
 *  - Sources are searched in parallel (OpenMP, one scratch set per thread);
 *    each source writes its own slot and the slots are gathered in source
 *    order, so the output does not depend on the thread count.
 *
 * SPDX-License-Identifier: GPL-3.0-or-later
 */
#include "trace/trace.h"
#include "core/vec.h"
#include "trace/internal.h"

#include <math.h>
#include <omp.h>
#include <stdlib.h>
#include <string.h>

#define TRACE_DEFAULT_BORDER_SOURCES 64
#define TRACE_DEFAULT_INTERIOR_SOURCES 64
#define TRACE_DEFAULT_MAX_LENGTH_FACTOR 3.0
#define TRACE_MIN_LOOP_EDGES 6
#define TRACE_MIN_BORDER_EDGES 2

/* ---------------------------------------------------------------- path lifecycle */

void pz_trace_path_clear(pz_trace_path *path)
{
    if (!path)
        return;
    free(path->vertices), free(path->arms);
    memset(path, 0, sizeof *path);
}

pz_status pz_trace_path_copy(const pz_trace_path *path, pz_trace_path *out, pz_ctx *ctx)
{
    *out = *path;
    size_t count = (size_t)path->vertex_count;
    out->vertices = malloc((count + 1) * sizeof(int32_t));
    out->arms = malloc(count + 1);
    if (!out->vertices || !out->arms) {
        pz_trace_path_clear(out);
        return pz_error(ctx, PZ_ERR_NOMEM, "trace: out of memory copying a path of %d vertices", (int)count);
    }
    if (count) {
        memcpy(out->vertices, path->vertices, count * sizeof(int32_t));
        memcpy(out->arms, path->arms, count);
    }
    return PZ_OK;
}

void pz_trace_paths_free(pz_trace_paths **paths)
{
    if (!paths || !*paths)
        return;
    for (int32_t i = 0; i < (*paths)->path_count; ++i)
        pz_trace_path_clear(&(*paths)->paths[i]);
    free((*paths)->paths);
    free(*paths);
    *paths = NULL;
}

/* ---------------------------------------------------------------- search scratch */

/* One thread's search state over the graph's nodes; only touched entries are reset between searches. */
typedef struct search_scratch {
    double *dist;      /* node_count, INFINITY when unreached */
    int32_t *pred;     /* node_count */
    int32_t *hops;     /* node_count: edges on the best path so far */
    int32_t *touched;  /* nodes whose dist is finite */
    size_t touched_count;
    int32_t *chain;    /* node_count: the path found, source first */
    uint32_t *seen;    /* vertex_count: stamp of the last path that visited the vertex */
    uint32_t stamp;
    size_t seen_count;
    pz_heap heap;
} search_scratch;

static void scratch_free(search_scratch *s)
{
    free(s->dist), free(s->pred), free(s->hops), free(s->touched), free(s->chain), free(s->seen);
    pz_heap_free(&s->heap);
    memset(s, 0, sizeof *s);
}

static int scratch_init(search_scratch *s, const pz_trace_graph *graph)
{
    memset(s, 0, sizeof *s);
    size_t nodes = (size_t)graph->node_count + 1;
    s->dist = malloc(nodes * sizeof(double));
    s->pred = malloc(nodes * sizeof(int32_t));
    s->hops = malloc(nodes * sizeof(int32_t));
    s->touched = malloc(nodes * sizeof(int32_t));
    s->chain = malloc(nodes * sizeof(int32_t));
    s->seen_count = (size_t)graph->vertex_count + 1;
    s->seen = calloc(s->seen_count, sizeof(uint32_t));
    if (!s->dist || !s->pred || !s->hops || !s->touched || !s->chain || !s->seen) {
        scratch_free(s);
        return 0;
    }
    for (size_t i = 0; i < nodes; ++i)
        s->dist[i] = INFINITY;
    return 1;
}

static void scratch_reset(search_scratch *s)
{
    for (size_t i = 0; i < s->touched_count; ++i)
        s->dist[s->touched[i]] = INFINITY;
    s->touched_count = 0;
    s->heap.count = 0;
}

/* Records a better distance to `node` through `from`; returns 0 when out of memory. */
static int relax(search_scratch *s, int32_t node, int32_t from, double dist, int32_t hops)
{
    if (!(dist < s->dist[node]))
        return 1;
    if (s->dist[node] == INFINITY)
        s->touched[s->touched_count++] = node;
    s->dist[node] = dist, s->pred[node] = from, s->hops[node] = hops;
    return pz_heap_push(&s->heap, dist, node);
}

/*
 * Shortest cycle through `source`. Returns the number of nodes written to
 * s->chain (source first, closing link implied), 0 when none within max_cost,
 * -1 when out of memory.
 */
static int32_t search_loop(const pz_trace_graph *graph, int32_t source, double max_cost, search_scratch *s)
{
    scratch_reset(s);
    const uint8_t *kind = graph->node_kind;
    for (int32_t l = graph->link_offsets[source]; l < graph->link_offsets[source + 1]; ++l)
        if (kind[graph->link_targets[l]] == PZ_TRACE_NODE_INTERIOR &&
            !relax(s, graph->link_targets[l], source, graph->link_weights[l], 1))
            return -1;
    double d;
    int32_t u;
    while (pz_heap_pop(&s->heap, &d, &u)) {
        if (d > s->dist[u])
            continue;
        if (d > max_cost)
            return 0;
        if (u == source)
            break;
        for (int32_t l = graph->link_offsets[u]; l < graph->link_offsets[u + 1]; ++l) {
            int32_t t = graph->link_targets[l];
            if (kind[t] != PZ_TRACE_NODE_INTERIOR || (t == source && s->hops[u] + 1 < TRACE_MIN_LOOP_EDGES))
                continue;
            if (!relax(s, t, u, d + graph->link_weights[l], s->hops[u] + 1))
                return -1;
        }
    }
    if (s->dist[source] == INFINITY)
        return 0;
    int32_t count = s->hops[source];
    s->chain[0] = source;
    for (int32_t i = count - 1, n = s->pred[source]; i >= 1; --i, n = s->pred[n])
        s->chain[i] = n;
    return count;
}

/* Shortest path from an ENTER node to the nearest EXIT node. Same returns as search_loop. */
static int32_t search_border(const pz_trace_graph *graph, int32_t source, double max_cost, search_scratch *s)
{
    scratch_reset(s);
    const uint8_t *kind = graph->node_kind;
    if (!relax(s, source, -1, 0.0, 0))
        return -1;
    double d;
    int32_t u, target = -1;
    while (pz_heap_pop(&s->heap, &d, &u)) {
        if (d > s->dist[u])
            continue;
        if (d > max_cost)
            break;
        if (u != source && kind[u] != PZ_TRACE_NODE_INTERIOR) {
            if (kind[u] == PZ_TRACE_NODE_EXIT && s->hops[u] >= TRACE_MIN_BORDER_EDGES) {
                target = u;
                break;
            }
            continue;
        }
        for (int32_t l = graph->link_offsets[u]; l < graph->link_offsets[u + 1]; ++l)
            if (!relax(s, graph->link_targets[l], u, d + graph->link_weights[l], s->hops[u] + 1))
                return -1;
    }
    if (target < 0)
        return 0;
    int32_t count = s->hops[target] + 1;
    for (int32_t i = count - 1, n = target; i >= 0; --i, n = s->pred[n])
        s->chain[i] = n;
    return count;
}

/* ---------------------------------------------------------------- paths from node chains */

/* 1 when no vertex of the chain repeats (a path touching a vertex twice crosses itself). */
static int chain_simple(const int32_t *chain, int32_t count, search_scratch *s)
{
    if (++s->stamp == 0) { /* wrapped: old stamps could collide, start over */
        memset(s->seen, 0, s->seen_count * sizeof(uint32_t));
        s->stamp = 1;
    }
    for (int32_t i = 0; i < count; ++i) {
        int32_t v = chain[i] / 4;
        if (s->seen[v] == s->stamp)
            return 0;
        s->seen[v] = s->stamp;
    }
    return 1;
}

/* Fills *path's vertices and arms from s->chain (not measured); returns 0 when out of memory. */
static int path_from_chain(const search_scratch *s, int32_t count, pz_trace_path_kind kind, pz_trace_path *path)
{
    memset(path, 0, sizeof *path);
    path->vertices = malloc((size_t)count * sizeof(int32_t));
    path->arms = malloc((size_t)count);
    if (!path->vertices || !path->arms) {
        pz_trace_path_clear(path);
        return 0;
    }
    for (int32_t i = 0; i < count; ++i)
        path->vertices[i] = s->chain[i] / 4, path->arms[i] = (uint8_t)(s->chain[i] % 4);
    path->kind = kind;
    path->closed = kind == PZ_TRACE_LOOP;
    path->vertex_count = count;
    return 1;
}

/* ---------------------------------------------------------------- measuring and smoothing */

static double step_length(const pz_mesh *mesh, int32_t a, int32_t b)
{
    double d[3];
    pz_vec3_sub(mesh->positions + 3 * (size_t)b, mesh->positions + 3 * (size_t)a, d);
    return sqrt(pz_vec3_dot(d, d));
}

void trace_path_measure(const pz_trace_graph *graph, const pz_mesh *mesh, pz_trace_path *path)
{
    int32_t count = path->vertex_count;
    path->length_mm = path->cost = 0.0;
    for (int32_t i = 0; i + 1 < count + (path->closed ? 1 : 0); ++i) {
        int32_t v = path->vertices[i], next = path->vertices[(i + 1) % count], node = 4 * v + path->arms[i];
        double length = step_length(mesh, v, next), weight = length * (1.0 + graph->drift_weight);
        for (int32_t l = graph->link_offsets[node]; l < graph->link_offsets[node + 1]; ++l)
            if (graph->link_targets[l] / 4 == next)
                weight = graph->link_weights[l];
        path->length_mm += length;
        path->cost += weight;
    }
}

static int neighbors(const pz_trace_graph *graph, int32_t a, int32_t b)
{
    for (int32_t i = graph->neighbor_offsets[a]; i < graph->neighbor_offsets[a + 1]; ++i)
        if (graph->neighbor_vertices[i] == b)
            return 1;
    return 0;
}

/*
 * Smoothing on the edge graph: drops detours. The drift penalty makes two
 * edges along the arms cheaper than the third edge of their triangle, so a
 * shortest path staircases; where a path goes a-b-c round a triangle (a and
 * c share an edge) b is dropped, which is shorter and follows the path's
 * mean direction. Repeated until no detour is left. Kept: the ends of open
 * paths, a loop's minimum size, and border paths never get an edge joining
 * two boundary vertices. Cheap: O(length^2) worst case, one pass in practice.
 * The paper's geometric smoothing moves paths off the edges, which this
 * stage does not do (docs/trace.md).
 */
static void smooth_path(const pz_trace_graph *graph, const uint8_t *on_boundary, pz_trace_path *path)
{
    int32_t minimum = path->closed ? TRACE_MIN_LOOP_EDGES : 2;
    int changed = 1;
    while (changed) {
        changed = 0;
        int32_t n = path->vertex_count;
        for (int32_t i = path->closed ? 0 : 1; i < (path->closed ? n : n - 1) && n > minimum; ++i) {
            int32_t a = path->vertices[(i + n - 1) % n], c = path->vertices[(i + 1) % n];
            if ((on_boundary[a] && on_boundary[c]) || !neighbors(graph, a, c))
                continue;
            memmove(path->vertices + i, path->vertices + i + 1, (size_t)(n - i - 1) * sizeof(int32_t));
            memmove(path->arms + i, path->arms + i + 1, (size_t)(n - i - 1));
            --n, --i, changed = 1;
        }
        path->vertex_count = n;
    }
}

/* ---------------------------------------------------------------- sources */

/*
 * Farthest-point sampling of up to `wanted` of the candidate vertices
 * (3D distance), first the one nearest the candidates' centroid. Writes the
 * chosen vertices to chosen[] and returns their count. O(count * wanted).
 */
static int32_t farthest_points(const pz_mesh *mesh, const int32_t *candidates, int32_t count, int32_t wanted,
                               int32_t *chosen, double *gap)
{
    if (count == 0 || wanted <= 0)
        return 0;
    double centroid[3] = {0, 0, 0};
    for (int32_t i = 0; i < count; ++i)
        for (int k = 0; k < 3; ++k)
            centroid[k] += mesh->positions[3 * (size_t)candidates[i] + k] / count;
    for (int32_t i = 0; i < count; ++i) {
        double d[3];
        pz_vec3_sub(mesh->positions + 3 * (size_t)candidates[i], centroid, d);
        gap[i] = -pz_vec3_dot(d, d); /* first pick: the largest -distance = the nearest to the centroid */
    }
    int32_t chosen_count = 0;
    while (chosen_count < wanted && chosen_count < count) {
        int32_t best = 0;
        for (int32_t i = 1; i < count; ++i)
            if (gap[i] > gap[best])
                best = i;
        if (chosen_count > 0 && gap[best] <= 0.0)
            break; /* every candidate already chosen */
        chosen[chosen_count++] = candidates[best];
        const double *p = mesh->positions + 3 * (size_t)candidates[best];
        for (int32_t i = 0; i < count; ++i) {
            double d[3];
            pz_vec3_sub(mesh->positions + 3 * (size_t)candidates[i], p, d);
            double d2 = pz_vec3_dot(d, d);
            if (chosen_count == 1 || d2 < gap[i])
                gap[i] = d2;
        }
    }
    return chosen_count;
}

static int enter_nodes(const pz_trace_graph *graph, int32_t v)
{
    int count = 0;
    for (int k = 0; k < 4; ++k)
        count += graph->node_kind[4 * v + k] == PZ_TRACE_NODE_ENTER;
    return count;
}

typedef struct search_task {
    int32_t node;
    pz_trace_path_kind kind;
} search_task;

/* The searches to run: two loop nodes per interior source, the ENTER nodes (one, two at a concave corner) of
 * every border source; boundary vertices without an ENTER node (convex corners) are no sources. */
static int32_t plan_tasks(const pz_trace_graph *graph, const pz_mesh *mesh, const pz_topology *topology,
                          int32_t interior_wanted, int32_t border_wanted, search_task *tasks, int32_t *scratch,
                          double *gap)
{
    int32_t task_count = 0;
    for (int pass = 0; pass < 2; ++pass) {
        int border = pass == 1;
        int32_t wanted = border ? border_wanted : interior_wanted, count = 0;
        if (wanted <= 0)
            continue;
        for (int32_t v = 0; v < mesh->vertex_count; ++v)
            if (topology->vertex_halfedge[v] >= 0 && !!topology->vertex_on_boundary[v] == border &&
                (!border || enter_nodes(graph, v) > 0))
                scratch[count++] = v;
        int32_t *chosen = scratch + count;
        int32_t chosen_count = farthest_points(mesh, scratch, count, wanted, chosen, gap);
        for (int32_t i = 0; i < chosen_count; ++i) {
            int32_t v = chosen[i];
            if (border) {
                for (int k = 0; k < 4; ++k)
                    if (graph->node_kind[4 * v + k] == PZ_TRACE_NODE_ENTER)
                        tasks[task_count++] = (search_task){4 * v + k, PZ_TRACE_BORDER};
            } else {
                tasks[task_count++] = (search_task){4 * v + 0, PZ_TRACE_LOOP};
                tasks[task_count++] = (search_task){4 * v + 1, PZ_TRACE_LOOP};
            }
        }
    }
    return task_count;
}

/* ---------------------------------------------------------------- candidates */

typedef struct candidate_settings {
    int32_t interior_sources, border_sources;
    double max_length, max_cost;
    int threads, smooth;
} candidate_settings;

static pz_status candidate_settings_resolve(const pz_trace_graph *graph, const pz_mesh *mesh,
                                            const pz_trace_candidate_options *options, candidate_settings *out,
                                            pz_ctx *ctx)
{
    pz_trace_candidate_options o = {0};
    if (options)
        o = *options;
    if (o.border_sources < 0 || o.interior_sources < 0 || o.max_length_factor < 0 || o.threads < 0 ||
        !(o.max_length_factor < 1e6))
        return pz_error(ctx, PZ_ERR_USAGE, "trace: negative candidate option (sources %d/%d, length factor %g, "
                        "threads %d)", (int)o.interior_sources, (int)o.border_sources, o.max_length_factor,
                        o.threads);
    double lo[3], hi[3], d[3];
    pz_mesh_bbox(mesh, lo, hi);
    pz_vec3_sub(hi, lo, d);
    out->interior_sources = o.loops < 0 ? 0 : o.interior_sources ? o.interior_sources : TRACE_DEFAULT_INTERIOR_SOURCES;
    out->border_sources = o.border < 0 ? 0 : o.border_sources ? o.border_sources : TRACE_DEFAULT_BORDER_SOURCES;
    out->max_length = (o.max_length_factor ? o.max_length_factor : TRACE_DEFAULT_MAX_LENGTH_FACTOR) * sqrt(pz_vec3_dot(d, d));
    /* Candidates on the shared garments have cost / length <= 1.64 (drift weight 2): a search may stop at 2x. */
    out->max_cost = out->max_length * (1.0 + 0.5 * graph->drift_weight);
    out->threads = o.threads ? o.threads : omp_get_max_threads();
    out->smooth = o.smooth >= 0;
    return PZ_OK;
}

/* Runs one search and keeps its path in *slot (vertex_count 0: none). Returns 0 when out of memory. */
static int run_task(const pz_trace_graph *graph, const pz_mesh *mesh, const pz_topology *topology,
                    const search_task *task, const candidate_settings *settings, search_scratch *s,
                    pz_trace_path *slot)
{
    memset(slot, 0, sizeof *slot);
    int32_t count = task->kind == PZ_TRACE_LOOP ? search_loop(graph, task->node, settings->max_cost, s)
                                                 : search_border(graph, task->node, settings->max_cost, s);
    if (count < 0)
        return 0;
    if (count == 0 || !chain_simple(s->chain, count, s))
        return 1;
    if (!path_from_chain(s, count, task->kind, slot))
        return 0;
    if (settings->smooth)
        smooth_path(graph, topology->vertex_on_boundary, slot);
    trace_path_measure(graph, mesh, slot);
    if (slot->length_mm > settings->max_length)
        pz_trace_path_clear(slot);
    return 1;
}

/* Runs every task in parallel, each into its own slot. Returns 0 when out of memory. Once the context is
 * cancelled the tasks not started are skipped (the flag is only read here; the caller says cancelled). */
static int run_tasks(const pz_trace_graph *graph, const pz_mesh *mesh, const pz_topology *topology,
                     const search_task *tasks, int32_t task_count, const candidate_settings *settings,
                     pz_trace_path *slots, const pz_ctx *ctx)
{
    int failed = 0;
#pragma omp parallel num_threads(settings->threads)
    {
        search_scratch s;
        int ok = scratch_init(&s, graph);
        if (!ok) {
#pragma omp atomic write
            failed = 1;
        }
#pragma omp for schedule(dynamic, 1)
        for (int32_t i = 0; i < task_count; ++i) {
            if (pz_cancelled(ctx))
                continue;
            if (ok && !run_task(graph, mesh, topology, &tasks[i], settings, &s, &slots[i])) {
#pragma omp atomic write
                failed = 1;
            }
        }
        scratch_free(&s);
    }
    return !failed;
}

static int compare_int32(const void *a, const void *b)
{
    int32_t x = *(const int32_t *)a, y = *(const int32_t *)b;
    return (x > y) - (x < y);
}

typedef struct ranked_path {
    pz_trace_path *path;
    int32_t order;     /* slot index: the last tie-breaker */
} ranked_path;

static int compare_ranked(const void *a, const void *b)
{
    const ranked_path *x = a, *y = b;
    if (x->path->cost != y->path->cost)
        return x->path->cost < y->path->cost ? -1 : 1;
    if (x->path->vertices[0] != y->path->vertices[0])
        return x->path->vertices[0] < y->path->vertices[0] ? -1 : 1;
    return (x->order > y->order) - (x->order < y->order);
}

/* 1 when paths a and b visit the same vertex set. */
static int same_vertex_set(const pz_trace_path *a, const pz_trace_path *b, int32_t *sorted_a, int32_t *sorted_b)
{
    if (a->vertex_count != b->vertex_count)
        return 0;
    size_t count = (size_t)a->vertex_count;
    memcpy(sorted_a, a->vertices, count * sizeof(int32_t));
    memcpy(sorted_b, b->vertices, count * sizeof(int32_t));
    qsort(sorted_a, count, sizeof(int32_t), compare_int32);
    qsort(sorted_b, count, sizeof(int32_t), compare_int32);
    return memcmp(sorted_a, sorted_b, count * sizeof(int32_t)) == 0;
}

/*
 * Moves the found paths out of the slots into *out, sorted by cost then first
 * vertex, dropping any path with the vertex set of a cheaper one. Duplicates
 * are first screened by vertex count and vertex sum. Returns 0 when out of memory.
 */
static int gather(pz_trace_path *slots, int32_t slot_count, int32_t vertex_count, pz_trace_paths *out)
{
    ranked_path *ranked = malloc(((size_t)slot_count + 1) * sizeof *ranked);
    int64_t *sums = malloc(((size_t)slot_count + 1) * sizeof *sums);
    int32_t *sorted_a = malloc(((size_t)vertex_count + 1) * sizeof(int32_t));
    int32_t *sorted_b = malloc(((size_t)vertex_count + 1) * sizeof(int32_t));
    out->paths = malloc(((size_t)slot_count + 1) * sizeof *out->paths);
    if (!ranked || !sums || !sorted_a || !sorted_b || !out->paths) {
        free(ranked), free(sums), free(sorted_a), free(sorted_b);
        return 0;
    }
    int32_t count = 0;
    for (int32_t i = 0; i < slot_count; ++i)
        if (slots[i].vertex_count > 0)
            ranked[count] = (ranked_path){&slots[i], i}, ++count;
    qsort(ranked, (size_t)count, sizeof *ranked, compare_ranked);
    out->path_count = 0;
    for (int32_t i = 0; i < count; ++i) {
        pz_trace_path *path = ranked[i].path;
        int64_t sum = 0;
        for (int32_t k = 0; k < path->vertex_count; ++k)
            sum += path->vertices[k];
        int duplicate = 0;
        for (int32_t j = 0; j < out->path_count && !duplicate; ++j)
            duplicate = sums[j] == sum && same_vertex_set(&out->paths[j], path, sorted_a, sorted_b);
        if (duplicate) {
            pz_trace_path_clear(path);
            continue;
        }
        sums[out->path_count] = sum;
        out->paths[out->path_count++] = *path;
        memset(path, 0, sizeof *path);
    }
    free(ranked), free(sums), free(sorted_a), free(sorted_b);
    return 1;
}

pz_status pz_trace_candidates(const pz_trace_graph *graph, const pz_mesh *mesh, const pz_topology *topology,
                              const pz_trace_candidate_options *options, pz_trace_paths **out, pz_ctx *ctx)
{
    *out = NULL;
    candidate_settings settings;
    pz_status status = candidate_settings_resolve(graph, mesh, options, &settings, ctx);
    if (status)
        return status;
    size_t task_capacity = 2 * (size_t)settings.interior_sources + 4 * (size_t)settings.border_sources + 1;
    size_t vertex_capacity = 2 * (size_t)mesh->vertex_count + 1;
    search_task *tasks = malloc(task_capacity * sizeof *tasks);
    int32_t *vertex_scratch = malloc(vertex_capacity * sizeof(int32_t));
    double *gap = malloc(vertex_capacity * sizeof(double));
    pz_trace_path *slots = calloc(task_capacity, sizeof *slots);
    pz_trace_paths *paths = calloc(1, sizeof *paths);
    int ok = tasks && vertex_scratch && gap && slots && paths;
    int32_t task_count = 0;
    if (ok) {
        task_count = plan_tasks(graph, mesh, topology, settings.interior_sources, settings.border_sources, tasks,
                                vertex_scratch, gap);
        ok = run_tasks(graph, mesh, topology, tasks, task_count, &settings, slots, ctx);
        if (ok && (status = pz_check_cancel(ctx, "trace")) != PZ_OK)
            ok = 0;
        ok = ok && gather(slots, task_count, mesh->vertex_count, paths);
    }
    for (int32_t i = 0; slots && i < task_count; ++i)
        pz_trace_path_clear(&slots[i]);
    free(tasks), free(vertex_scratch), free(gap), free(slots);
    if (!ok) {
        pz_trace_paths_free(&paths);
        if (status == PZ_ERR_CANCELLED)
            return status;
        return pz_error(ctx, PZ_ERR_NOMEM, "trace: out of memory tracing candidates on %d vertices",
                        (int)mesh->vertex_count);
    }
    *out = paths;
    return PZ_OK;
}

/* ---------------------------------------------------------------- distance */

/* Sets the axis nodes of the paths to distance 0 and queues them. Returns 0 when out of memory. */
static int seed_paths(const pz_trace_path *paths, int32_t path_count, double *distance, pz_heap *heap)
{
    for (int32_t p = 0; p < path_count; ++p)
        for (int32_t i = 0; i < paths[p].vertex_count; ++i)
            for (int side = 0; side < 4; side += 2) { /* the path's arm and the opposite one: its axis */
                int32_t node = 4 * paths[p].vertices[i] + (paths[p].arms[i] + side) % 4;
                if (distance[node] > 0.0 && (distance[node] = 0.0, !pz_heap_push(heap, 0.0, node)))
                    return 0;
            }
    return 1;
}

/* Dijkstra over the 4-sheeted covering from the queued nodes, lowering distance[]. Returns 0 when out of memory. */
static int spread(const pz_trace_graph *graph, double *distance, pz_heap *heap)
{
    double d;
    int32_t u;
    while (pz_heap_pop(heap, &d, &u)) {
        if (d > distance[u])
            continue;
        int32_t v = u / 4, arm = u % 4;
        for (int32_t i = graph->neighbor_offsets[v]; i < graph->neighbor_offsets[v + 1]; ++i) {
            int32_t t = 4 * graph->neighbor_vertices[i] + (arm + graph->neighbor_shift[i]) % 4;
            double nd = d + graph->neighbor_lengths[i];
            if (nd < distance[t] && (distance[t] = nd, !pz_heap_push(heap, nd, t)))
                return 0;
        }
    }
    return 1;
}

static pz_status distance_nomem(const pz_trace_graph *graph, pz_ctx *ctx)
{
    return pz_error(ctx, PZ_ERR_NOMEM, "trace: out of memory for the distance over %d nodes", (int)graph->node_count);
}

pz_status pz_trace_distance(const pz_trace_graph *graph, const pz_trace_path *paths, int32_t path_count,
                            int from_boundary, double *distance, pz_ctx *ctx)
{
    for (int32_t n = 0; n < graph->node_count; ++n)
        distance[n] = INFINITY;
    pz_heap heap = {0};
    int ok = seed_paths(paths, path_count, distance, &heap);
    for (int32_t n = 0; n < graph->node_count && ok && from_boundary; ++n)
        if (graph->node_kind[n] == PZ_TRACE_NODE_ALONG && distance[n] > 0.0)
            distance[n] = 0.0, ok = pz_heap_push(&heap, 0.0, n);
    ok = ok && spread(graph, distance, &heap);
    pz_heap_free(&heap);
    return ok ? PZ_OK : distance_nomem(graph, ctx);
}

/*
 * Only the nodes the new paths bring nearer are visited. The result is the
 * full computation's, bit for bit: a node's distance is the least, over the
 * paths to it from any source, of the edge lengths added in order from the
 * source; rounding is monotone, so Dijkstra finds that least value whatever
 * the sources queued, and the sources of a call and of the earlier ones
 * reach a node by different paths, so their minima simply combine.
 */
pz_status pz_trace_distance_add(const pz_trace_graph *graph, const pz_trace_path *paths, int32_t path_count,
                                double *distance, pz_ctx *ctx)
{
    pz_heap heap = {0};
    int ok = seed_paths(paths, path_count, distance, &heap) && spread(graph, distance, &heap);
    pz_heap_free(&heap);
    return ok ? PZ_OK : distance_nomem(graph, ctx);
}

double pz_trace_path_mean_distance(const pz_trace_path *path, const double *distance)
{
    if (path->vertex_count == 0)
        return 0.0;
    double sum = 0.0;
    for (int32_t i = 0; i < path->vertex_count; ++i)
        sum += distance[4 * path->vertices[i] + path->arms[i]];
    return sum / path->vertex_count;
}

/* ---------------------------------------------------------------- tangential meetings */

/* 1 when position i is an end of an open path. */
static int open_end(const pz_trace_path *path, int32_t i)
{
    return !path->closed && (i == 0 || i == path->vertex_count - 1);
}

/* 1 when a meeting at a's position i and b's position j is tangential (same axis, not two ends). */
static int meets_tangentially(const pz_trace_path *a, int32_t i, const pz_trace_path *b, int32_t j)
{
    return (a->arms[i] % 2) == (b->arms[j] % 2) && !(open_end(a, i) && open_end(b, j));
}

int pz_trace_paths_tangential(const pz_trace_path *a, const pz_trace_path *b, int32_t vertex_count)
{
    int32_t *position = malloc(((size_t)vertex_count + 1) * sizeof(int32_t));
    int tangential = 0;
    if (!position) { /* no scratch: the quadratic scan gives the same answer */
        for (int32_t i = 0; i < a->vertex_count && !tangential; ++i)
            for (int32_t j = 0; j < b->vertex_count && !tangential; ++j)
                tangential = a->vertices[i] == b->vertices[j] && meets_tangentially(a, i, b, j);
        return tangential;
    }
    for (int32_t i = 0; i < b->vertex_count; ++i)
        position[b->vertices[i]] = -1;
    for (int32_t i = 0; i < a->vertex_count; ++i)
        position[a->vertices[i]] = i;
    for (int32_t j = 0; j < b->vertex_count && !tangential; ++j) {
        int32_t i = position[b->vertices[j]];
        tangential = i >= 0 && meets_tangentially(a, i, b, j);
    }
    free(position);
    return tangential;
}

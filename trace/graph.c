/*
 * trace/graph.c -- the tracing graph of pietroni2022 Sec. 4.2 (Fig. 5),
 * after Pietroni et al. 2016/2021: four nodes per vertex, one per arm of the
 * vertex's cross, linked along the mesh edges that follow an arm.
 *
 * Algorithm:
 *  1. Vertex normals: area-weighted sums of the face normals.
 *  2. Vertex crosses. Each vertex averages its faces' crosses in a tangent
 *     frame (e1 = its first edge projected, e2 = n x e1): each face arm is
 *     rotated from the face plane to the vertex plane (the smallest rotation
 *     taking the face normal to the vertex normal), its angle theta taken in
 *     the frame and exp(4i theta) summed, weighted by the corner angle; arm 0
 *     has angle arg(sum) / 4, which does not depend on which of the four arms
 *     each face stored. When the sum cancels (a singular vertex) the face
 *     with the largest corner angle decides. Boundary vertices too: the field
 *     is aligned to the boundary, so on a smooth boundary one arm runs along
 *     it, and at a corner the cross follows the two edges.
 *     Boundary node kinds (Fig. 9): with phi the arm's angle from the
 *     outgoing boundary edge (counter-clockwise, into the surface) and the
 *     surface's sector [0, sector], an arm within 45 degrees of either
 *     boundary edge is ALONG, one inside the sector ENTER, one outside EXIT.
 *     A smooth boundary vertex gets one ENTER, one EXIT and two ALONG nodes;
 *     a convex corner of 90 degrees no ENTER (a path from it would run
 *     diagonally into the corner's neighbourhood and then beside the
 *     boundary: the thin strip of Fig. 9).
 *  3. The covering (the M4 stratification used by pz_trace_distance): for
 *     every vertex its ordered one-ring, and for each neighbour w the shift
 *     s such that arm k of v, carried to w by the smallest rotation between
 *     the normals, is closest to arm (k + s) % 4 of w.
 *  4. Links. For each directed edge v->w: the edge, projected on v's
 *     tangent plane, follows arm k of v when the angle between them is at
 *     most the match angle (45 degrees: every edge follows exactly one arm,
 *     two on a tie). The link goes to arm (k + s) % 4 of w. Weight:
 *         length * (1 + drift_weight * (a_v^2 + a_w^2) / 2),
 *     a_v, a_w = the angle between the edge and the arm at each end divided
 *     by the match angle (so 0 for an edge on the arms, about 1 at the
 *     limit). drift_weight defaults to 2: an edge at the match angle costs 3x
 *     its length, one half-way 1.5x.
 *
 * Memory: about 6 links per vertex (12 bytes each) and 6 covering entries
 * per vertex (13 bytes each), 7 doubles and 5 bytes per vertex, and a
 * temporary link list while building.
 * Fails only on bad options or allocation failure. O(V + E), single pass.
 *
 * SPDX-License-Identifier: GPL-3.0-or-later
 */
#include "trace/trace.h"
#include "field/field.h"
#include "core/util.h"
#include "core/vec.h"

#include <math.h>
#include <stdlib.h>
#include <string.h>

#define TRACE_DEFAULT_MATCH_DEG 45.0
#define TRACE_DEFAULT_DRIFT_WEIGHT 2.0
#define TRACE_ALONG_MARGIN_DEG 45.0

void pz_trace_graph_free(pz_trace_graph **graph)
{
    if (!graph || !*graph)
        return;
    pz_trace_graph *g = *graph;
    free(g->vertex_normals), free(g->vertex_arms), free(g->node_kind);
    free(g->link_offsets), free(g->link_targets), free(g->link_weights);
    free(g->neighbor_offsets), free(g->neighbor_vertices), free(g->neighbor_shift), free(g->neighbor_lengths);
    free(g);
    *graph = NULL;
}

pz_status pz_trace_graph_copy(const pz_trace_graph *graph, pz_trace_graph **out, pz_ctx *ctx)
{
    *out = NULL;
    pz_trace_graph *g = calloc(1, sizeof *g);
    if (!g)
        return pz_error(ctx, PZ_ERR_NOMEM, "trace: out of memory copying a graph");
    *g = *graph;
    size_t vertices = (size_t)graph->vertex_count, nodes = (size_t)graph->node_count;
    size_t links = (size_t)graph->link_offsets[graph->node_count];
    size_t neighbors = (size_t)graph->neighbor_offsets[graph->vertex_count];
    int failed = 0;
    g->vertex_normals = pz_copy_array(graph->vertex_normals, 3 * vertices, sizeof(double), &failed);
    g->vertex_arms = pz_copy_array(graph->vertex_arms, 3 * vertices, sizeof(double), &failed);
    g->node_kind = pz_copy_array(graph->node_kind, nodes, 1, &failed);
    g->link_offsets = pz_copy_array(graph->link_offsets, nodes + 1, sizeof(int32_t), &failed);
    g->link_targets = pz_copy_array(graph->link_targets, links, sizeof(int32_t), &failed);
    g->link_weights = pz_copy_array(graph->link_weights, links, sizeof(double), &failed);
    g->neighbor_offsets = pz_copy_array(graph->neighbor_offsets, vertices + 1, sizeof(int32_t), &failed);
    g->neighbor_vertices = pz_copy_array(graph->neighbor_vertices, neighbors, sizeof(int32_t), &failed);
    g->neighbor_shift = pz_copy_array(graph->neighbor_shift, neighbors, 1, &failed);
    g->neighbor_lengths = pz_copy_array(graph->neighbor_lengths, neighbors, sizeof(double), &failed);
    if (failed) {
        pz_trace_graph_free(&g);
        return pz_error(ctx, PZ_ERR_NOMEM, "trace: out of memory copying a graph");
    }
    *out = g;
    return PZ_OK;
}

/*
 * Rotates v by the smallest rotation taking unit normal `from` to unit normal
 * `to` (Rodrigues with axis from x to). Opposite normals: v projected on the
 * `to` plane instead.
 */
static void rotate_between(const double *v, const double *from, const double *to, double *out)
{
    double c = pz_vec3_dot(from, to);
    if (c < -0.999) {
        double along = pz_vec3_dot(v, to);
        for (int i = 0; i < 3; ++i)
            out[i] = v[i] - along * to[i];
        return;
    }
    double k[3], kv[3];
    pz_vec3_cross(from, to, k);
    pz_vec3_cross(k, v, kv);
    double kdot = pz_vec3_dot(k, v) / (1.0 + c);
    for (int i = 0; i < 3; ++i)
        out[i] = c * v[i] + kv[i] + kdot * k[i];
}

/* v projected on the plane of unit normal n, normalised (zero stays zero). */
static void tangent_unit(const double *v, const double *n, double *out)
{
    double along = pz_vec3_dot(v, n);
    for (int i = 0; i < 3; ++i)
        out[i] = v[i] - along * n[i];
    pz_vec3_normalize(out);
}

void pz_trace_arm_direction(const pz_trace_graph *graph, int32_t vertex, int arm, double out[3])
{
    const double *a0 = graph->vertex_arms + 3 * (size_t)vertex, *n = graph->vertex_normals + 3 * (size_t)vertex;
    double a1[3];
    pz_vec3_cross(n, a0, a1);
    static const double cosines[4] = {1, 0, -1, 0}, sines[4] = {0, 1, 0, -1};
    int k = ((arm % 4) + 4) % 4;
    for (int i = 0; i < 3; ++i)
        out[i] = cosines[k] * a0[i] + sines[k] * a1[i];
}

int pz_trace_closest_arm(const pz_trace_graph *graph, int32_t vertex, const double direction[3])
{
    const double *a0 = graph->vertex_arms + 3 * (size_t)vertex, *n = graph->vertex_normals + 3 * (size_t)vertex;
    double a1[3];
    pz_vec3_cross(n, a0, a1);
    double x = pz_vec3_dot(direction, a0), y = pz_vec3_dot(direction, a1);
    if (fabs(x) >= fabs(y))
        return x >= 0.0 ? 0 : 2;
    return y >= 0.0 ? 1 : 3;
}

static void vertex_normals(const pz_mesh *mesh, double *normals)
{
    memset(normals, 0, (size_t)mesh->vertex_count * 3 * sizeof(double));
    for (int32_t f = 0; f < mesh->face_count; ++f) {
        const int32_t *face = mesh->faces + 3 * (size_t)f;
        double a[3], b[3], n[3]; /* |n| = twice the area: area weighting for free */
        pz_vec3_sub(mesh->positions + 3 * (size_t)face[1], mesh->positions + 3 * (size_t)face[0], a);
        pz_vec3_sub(mesh->positions + 3 * (size_t)face[2], mesh->positions + 3 * (size_t)face[0], b);
        pz_vec3_cross(a, b, n);
        for (int k = 0; k < 3; ++k)
            for (int i = 0; i < 3; ++i)
                normals[3 * (size_t)face[k] + i] += n[i];
    }
    for (int32_t v = 0; v < mesh->vertex_count; ++v)
        pz_vec3_normalize(normals + 3 * (size_t)v);
}

/* Every vertex: the angle-weighted 4-RoSy average of the incident faces' arms. */
static int average_arms(const pz_mesh *mesh, const pz_topology *topology, const double *face_arms,
                        const double *corner_angles, pz_trace_graph *graph)
{
    int32_t vertex_count = mesh->vertex_count;
    double *sums = calloc((size_t)vertex_count * 4 + 1, sizeof(double)); /* re, im, best weight, best angle */
    double *frames = malloc(((size_t)vertex_count * 3 + 1) * sizeof(double)); /* e1 per vertex */
    if (!sums || !frames) {
        free(sums), free(frames);
        return 0;
    }
    for (int32_t v = 0; v < vertex_count; ++v) {
        double *e1 = frames + 3 * (size_t)v;
        int32_t h = topology->vertex_halfedge[v];
        e1[0] = e1[1] = e1[2] = 0.0;
        if (h < 0)
            continue;
        double d[3];
        pz_vec3_sub(mesh->positions + 3 * (size_t)pz_he_to(topology, h), mesh->positions + 3 * (size_t)v, d);
        tangent_unit(d, graph->vertex_normals + 3 * (size_t)v, e1);
    }
    for (int32_t f = 0; f < mesh->face_count; ++f) {
        double fn[3], a[3], b[3];
        const int32_t *face = mesh->faces + 3 * (size_t)f;
        pz_vec3_sub(mesh->positions + 3 * (size_t)face[1], mesh->positions + 3 * (size_t)face[0], a);
        pz_vec3_sub(mesh->positions + 3 * (size_t)face[2], mesh->positions + 3 * (size_t)face[0], b);
        pz_vec3_cross(a, b, fn);
        pz_vec3_normalize(fn);
        for (int k = 0; k < 3; ++k) {
            int32_t v = face[k];
            const double *n = graph->vertex_normals + 3 * (size_t)v, *e1 = frames + 3 * (size_t)v;
            double e2[3], d[3];
            pz_vec3_cross(n, e1, e2);
            rotate_between(face_arms + 3 * (size_t)f, fn, n, d);
            double theta = atan2(pz_vec3_dot(d, e2), pz_vec3_dot(d, e1)), weight = corner_angles[3 * (size_t)f + k];
            double *s = sums + 4 * (size_t)v;
            s[0] += weight * cos(4.0 * theta), s[1] += weight * sin(4.0 * theta);
            if (weight > s[2])
                s[2] = weight, s[3] = theta;
        }
    }
    for (int32_t v = 0; v < vertex_count; ++v) {
        if (topology->vertex_halfedge[v] < 0)
            continue;
        const double *s = sums + 4 * (size_t)v, *n = graph->vertex_normals + 3 * (size_t)v;
        const double *e1 = frames + 3 * (size_t)v;
        double theta = hypot(s[0], s[1]) > 1e-9 * s[2] ? 0.25 * atan2(s[1], s[0]) : s[3];
        double e2[3], *arm = graph->vertex_arms + 3 * (size_t)v;
        pz_vec3_cross(n, e1, e2);
        for (int i = 0; i < 3; ++i)
            arm[i] = cos(theta) * e1[i] + sin(theta) * e2[i];
    }
    free(sums), free(frames);
    return 1;
}

/*
 * The kind of arm k at boundary vertex v: phi, its angle counter-clockwise
 * from the outgoing boundary edge in v's tangent plane, against the
 * surface's sector [0, sector] (sector: the angle of the reversed incoming
 * edge). Within TRACE_ALONG_MARGIN of either edge: ALONG; inside the
 * sector: ENTER; outside: EXIT.
 */
static uint8_t boundary_kind(double phi, double sector)
{
    double margin = TRACE_ALONG_MARGIN_DEG * PZ_PI / 180.0;
    if (phi < margin || phi > 2.0 * PZ_PI - margin || fabs(phi - sector) < margin)
        return PZ_TRACE_NODE_ALONG;
    return phi < sector ? PZ_TRACE_NODE_ENTER : PZ_TRACE_NODE_EXIT;
}

/* Angle of d in the frame (x, n x x), in [0, 2 pi). */
static double frame_angle(const double *d, const double *x, const double *n)
{
    double y[3];
    pz_vec3_cross(n, x, y);
    double angle = atan2(pz_vec3_dot(d, y), pz_vec3_dot(d, x));
    return angle < 0.0 ? angle + 2.0 * PZ_PI : angle;
}

/* Node kinds: INTERIOR off the boundary; ENTER, EXIT or ALONG (boundary_kind) on it. */
static int node_kinds(const pz_mesh *mesh, const pz_topology *topology, pz_trace_graph *graph)
{
    memset(graph->node_kind, PZ_TRACE_NODE_INTERIOR, (size_t)graph->node_count);
    double *edges = calloc((size_t)graph->vertex_count * 6 + 1, sizeof(double)); /* outgoing, incoming */
    if (!edges)
        return 0;
    for (int32_t h = 0; h < topology->halfedge_count; ++h) {
        if (topology->twin[h] >= 0)
            continue;
        int32_t a = pz_he_from(topology, h), b = pz_he_to(topology, h);
        pz_vec3_sub(mesh->positions + 3 * (size_t)b, mesh->positions + 3 * (size_t)a, edges + 6 * (size_t)a);
        pz_vec3_sub(mesh->positions + 3 * (size_t)b, mesh->positions + 3 * (size_t)a, edges + 6 * (size_t)b + 3);
    }
    for (int32_t v = 0; v < graph->vertex_count; ++v) {
        if (!topology->vertex_on_boundary[v])
            continue;
        const double *n = graph->vertex_normals + 3 * (size_t)v, *in = edges + 6 * (size_t)v + 3;
        double x[3], back[3] = {-in[0], -in[1], -in[2]};
        tangent_unit(edges + 6 * (size_t)v, n, x);
        double sector = frame_angle(back, x, n);
        for (int k = 0; k < 4; ++k) {
            double arm[3];
            pz_trace_arm_direction(graph, v, k, arm);
            graph->node_kind[4 * (size_t)v + k] = boundary_kind(frame_angle(arm, x, n), sector);
        }
    }
    free(edges);
    return 1;
}

typedef struct link_list {
    int32_t *from, *to;
    double *weight;
    size_t count, capacity;
} link_list;

static int link_push(link_list *list, int32_t from, int32_t to, double weight)
{
    if (list->count == list->capacity) {
        size_t capacity = list->capacity ? 2 * list->capacity : 1024;
        int32_t *f = realloc(list->from, capacity * sizeof *f);
        if (f)
            list->from = f;
        int32_t *t = realloc(list->to, capacity * sizeof *t);
        if (t)
            list->to = t;
        double *w = realloc(list->weight, capacity * sizeof *w);
        if (w)
            list->weight = w;
        if (!f || !t || !w)
            return 0;
        list->capacity = capacity;
    }
    list->from[list->count] = from, list->to[list->count] = to, list->weight[list->count] = weight;
    ++list->count;
    return 1;
}

/* The links leaving vertex v along the edge to w; arm k of v is arm (k + shift) % 4 of w. */
static int edge_links(const pz_mesh *mesh, pz_trace_graph *graph, int32_t v, int32_t w, int shift, link_list *list)
{
    const double *nv = graph->vertex_normals + 3 * (size_t)v, *nw = graph->vertex_normals + 3 * (size_t)w;
    double edge[3], at_v[3], at_w[3];
    pz_vec3_sub(mesh->positions + 3 * (size_t)w, mesh->positions + 3 * (size_t)v, edge);
    double length = sqrt(pz_vec3_dot(edge, edge));
    tangent_unit(edge, nv, at_v);
    tangent_unit(edge, nw, at_w);
    double match = graph->match_angle_deg * PZ_PI / 180.0;
    for (int k = 0; k < 4; ++k) {
        double arm[3], arm_w[3];
        pz_trace_arm_direction(graph, v, k, arm);
        double angle_v = acos(fmax(-1.0, fmin(1.0, pz_vec3_dot(arm, at_v))));
        if (angle_v > match + 1e-12)
            continue;
        int kw = (k + shift) % 4;
        pz_trace_arm_direction(graph, w, kw, arm_w);
        double angle_w = acos(fmax(-1.0, fmin(1.0, pz_vec3_dot(arm_w, at_w))));
        double drift = 0.5 * ((angle_v / match) * (angle_v / match) + (angle_w / match) * (angle_w / match));
        double weight = length * (1.0 + graph->drift_weight * drift);
        if (!(weight > 0.0))
            weight = 1e-12; /* a zero-length edge: keep weights positive as promised */
        if (!link_push(list, 4 * v + k, 4 * w + kw, weight))
            return 0;
    }
    return 1;
}

/* The arm of w closest to arm 0 of v carried to w by the smallest rotation between their normals. */
static int arm_shift(const pz_trace_graph *graph, int32_t v, int32_t w)
{
    double carried[3];
    rotate_between(graph->vertex_arms + 3 * (size_t)v, graph->vertex_normals + 3 * (size_t)v,
                   graph->vertex_normals + 3 * (size_t)w, carried);
    return pz_trace_closest_arm(graph, w, carried);
}

/* The covering: every vertex's one-ring (ordered) with the arm shift to each neighbour. */
static int build_neighbors(const pz_mesh *mesh, const pz_topology *topology, pz_trace_graph *graph)
{
    int32_t vertex_count = graph->vertex_count;
    graph->neighbor_offsets = malloc(((size_t)vertex_count + 1) * sizeof(int32_t));
    if (!graph->neighbor_offsets)
        return 0;
    graph->neighbor_offsets[0] = 0;
    for (int32_t v = 0; v < vertex_count; ++v)
        graph->neighbor_offsets[v + 1] = graph->neighbor_offsets[v] + pz_topology_vertex_ring(topology, v, NULL, 0);
    size_t total = (size_t)graph->neighbor_offsets[vertex_count];
    graph->neighbor_vertices = malloc((total + 1) * sizeof(int32_t));
    graph->neighbor_shift = malloc(total + 1);
    graph->neighbor_lengths = malloc((total + 1) * sizeof(double));
    if (!graph->neighbor_vertices || !graph->neighbor_shift || !graph->neighbor_lengths)
        return 0;
    for (int32_t v = 0; v < vertex_count; ++v) {
        int32_t first = graph->neighbor_offsets[v], count = graph->neighbor_offsets[v + 1] - first;
        pz_topology_vertex_ring(topology, v, graph->neighbor_vertices + first, count);
        for (int32_t i = first; i < first + count; ++i) {
            int32_t w = graph->neighbor_vertices[i];
            double d[3];
            pz_vec3_sub(mesh->positions + 3 * (size_t)w, mesh->positions + 3 * (size_t)v, d);
            graph->neighbor_shift[i] = (uint8_t)arm_shift(graph, v, w);
            graph->neighbor_lengths[i] = sqrt(pz_vec3_dot(d, d));
        }
    }
    return 1;
}

/* Counting sort of the link list by source node into CSR; links keep their order within a node. */
static int links_to_csr(const link_list *list, pz_trace_graph *graph)
{
    size_t count = list->count;
    graph->link_offsets = calloc((size_t)graph->node_count + 1, sizeof(int32_t));
    graph->link_targets = malloc((count + 1) * sizeof(int32_t));
    graph->link_weights = malloc((count + 1) * sizeof(double));
    int32_t *cursor = malloc(((size_t)graph->node_count + 1) * sizeof(int32_t));
    if (!graph->link_offsets || !graph->link_targets || !graph->link_weights || !cursor) {
        free(cursor);
        return 0;
    }
    for (size_t i = 0; i < count; ++i)
        ++graph->link_offsets[list->from[i] + 1];
    for (int32_t n = 0; n < graph->node_count; ++n)
        graph->link_offsets[n + 1] += graph->link_offsets[n];
    memcpy(cursor, graph->link_offsets, (size_t)graph->node_count * sizeof(int32_t));
    for (size_t i = 0; i < count; ++i) {
        int32_t slot = cursor[list->from[i]]++;
        graph->link_targets[slot] = list->to[i];
        graph->link_weights[slot] = list->weight[i];
    }
    free(cursor);
    return 1;
}

static int build_links(const pz_mesh *mesh, pz_trace_graph *graph)
{
    link_list list = {0};
    int ok = 1;
    for (int32_t v = 0; v < graph->vertex_count && ok; ++v)
        for (int32_t i = graph->neighbor_offsets[v]; i < graph->neighbor_offsets[v + 1] && ok; ++i)
            ok = edge_links(mesh, graph, v, graph->neighbor_vertices[i], graph->neighbor_shift[i], &list);
    ok = ok && links_to_csr(&list, graph);
    free(list.from), free(list.to), free(list.weight);
    return ok;
}

static pz_status check_options(const pz_trace_graph_options *options, double *match_deg, double *drift_weight,
                               pz_ctx *ctx)
{
    *match_deg = TRACE_DEFAULT_MATCH_DEG, *drift_weight = TRACE_DEFAULT_DRIFT_WEIGHT;
    if (!options)
        return PZ_OK;
    if (options->match_angle_deg != 0.0)
        *match_deg = options->match_angle_deg;
    if (options->drift_weight != 0.0)
        *drift_weight = options->drift_weight;
    if (!(*match_deg > 0.0 && *match_deg <= 90.0))
        return pz_error(ctx, PZ_ERR_USAGE, "trace: match angle %g degrees outside (0, 90]", *match_deg);
    if (!(*drift_weight >= 0.0 && *drift_weight < 1e6))
        return pz_error(ctx, PZ_ERR_USAGE, "trace: drift weight %g outside [0, 1e6)", *drift_weight);
    return PZ_OK;
}

pz_status pz_trace_graph_build(const pz_mesh *mesh, const pz_topology *topology, const double *face_arms,
                               const pz_trace_graph_options *options, pz_trace_graph **out, pz_ctx *ctx)
{
    *out = NULL;
    double match_deg, drift_weight;
    pz_status status = check_options(options, &match_deg, &drift_weight, ctx);
    if (status)
        return status;
    size_t vertex_count = (size_t)mesh->vertex_count;
    pz_trace_graph *graph = calloc(1, sizeof *graph);
    double *corner_angles = malloc(((size_t)mesh->face_count * 3 + 1) * sizeof(double));
    if (graph) {
        graph->vertex_count = mesh->vertex_count;
        graph->node_count = 4 * mesh->vertex_count;
        graph->match_angle_deg = match_deg, graph->drift_weight = drift_weight;
        graph->vertex_normals = malloc((vertex_count * 3 + 1) * sizeof(double));
        graph->vertex_arms = calloc(vertex_count * 3 + 1, sizeof(double));
        graph->node_kind = malloc(vertex_count * 4 + 1);
    }
    if (!graph || !corner_angles || !graph->vertex_normals || !graph->vertex_arms || !graph->node_kind) {
        free(corner_angles);
        pz_trace_graph_free(&graph);
        return pz_error(ctx, PZ_ERR_NOMEM, "trace: out of memory for the graph of %d vertices", (int)vertex_count);
    }
    graph->mean_edge_length = pz_field_mean_edge_length(mesh, topology);
    pz_geom_corner_angles(mesh, corner_angles);
    vertex_normals(mesh, graph->vertex_normals);
    int ok = average_arms(mesh, topology, face_arms, corner_angles, graph);
    free(corner_angles);
    ok = ok && node_kinds(mesh, topology, graph);
    if (!ok || !build_neighbors(mesh, topology, graph) || !build_links(mesh, graph)) {
        pz_trace_graph_free(&graph);
        return pz_error(ctx, PZ_ERR_NOMEM, "trace: out of memory for the links of %d vertices", (int)vertex_count);
    }
    *out = graph;
    return PZ_OK;
}

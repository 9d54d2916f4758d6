/*
 * mesh/topology.c -- half-edge connectivity in corner layout, one-rings,
 * boundary loops, connected components and the topological summary.
 *
 * Algorithm. Half-edge h = 3f + k runs from corner k of face f to corner
 * k+1, so next/prev/face are arithmetic and only the twins must be found.
 * The outgoing half-edges are bucketed by their source vertex (a counting
 * sort: one pass counts, a prefix sum places, one pass fills), which costs
 * O(F) time and (V + 1 + 3F) int32 of scratch. The twin of a -> b is the one
 * half-edge b -> a in b's bucket; a bucket holds about six entries on a
 * garment mesh, so the scans are short.
 *
 * Failure. The build refuses, with PZ_ERR_INVALID_MESH and a one-line
 * message naming the first offending element, a mesh with an index out of
 * range or repeated in a face, an edge carried by more than two faces or by
 * two faces running it the same way (inconsistent orientation), or a vertex
 * whose faces form more than one fan (detected by walking around every
 * vertex and comparing the faces reached with the faces incident).
 * pz_mesh_validate reports all of these with counts; run it first for a
 * diagnosis. Allocation failures return PZ_ERR_NOMEM. Memory kept:
 * twin, halfedge_edge (3F each), edge_halfedge (2E), vertex_halfedge (V),
 * vertex_on_boundary (V bytes): about 38 bytes per face.
 *
 * SPDX-License-Identifier: GPL-3.0-or-later
 */
#include "mesh.h"
#include "core/util.h"

#include <stdlib.h>
#include <string.h>

void pz_topology_free(pz_topology **topology)
{
    if (!topology || !*topology)
        return;
    pz_topology *t = *topology;
    free(t->twin);
    free(t->halfedge_edge);
    free(t->edge_halfedge);
    free(t->vertex_halfedge);
    free(t->vertex_on_boundary);
    free(t);
    *topology = NULL;
}

/* Outgoing half-edges bucketed by source vertex (compressed rows). */
typedef struct outgoing_star {
    int32_t *offsets;    /* vertex_count + 1 */
    int32_t *halfedges;  /* halfedge_count, grouped by source vertex, increasing id in a group */
    int32_t *targets;    /* halfedge_count: the target vertex of halfedges[i], so that scans stay in one cache line */
} outgoing_star;

static void outgoing_star_free(outgoing_star *star)
{
    free(star->offsets);
    free(star->halfedges);
    free(star->targets);
    star->offsets = star->halfedges = star->targets = NULL;
}

static pz_status outgoing_star_build(const pz_mesh *mesh, outgoing_star *star, pz_ctx *ctx)
{
    int32_t vertex_count = mesh->vertex_count, halfedge_count = 3 * mesh->face_count;
    star->offsets = calloc((size_t)vertex_count + 2, sizeof(int32_t));
    star->halfedges = malloc((size_t)halfedge_count * sizeof(int32_t) + 1);
    star->targets = malloc((size_t)halfedge_count * sizeof(int32_t) + 1);
    if (!star->offsets || !star->halfedges || !star->targets) {
        outgoing_star_free(star);
        return pz_error(ctx, PZ_ERR_NOMEM, "out of memory for the connectivity of %d faces",
                        (int)mesh->face_count);
    }
    /* Count into offsets[v + 2], prefix-sum into offsets[v + 1], then fill
     * with offsets[v + 1] as the write cursor: it ends at the start of v + 1. */
    for (int32_t h = 0; h < halfedge_count; ++h)
        ++star->offsets[mesh->faces[h] + 2];
    for (int32_t v = 0; v < vertex_count; ++v)
        star->offsets[v + 2] += star->offsets[v + 1];
    for (int32_t h = 0; h < halfedge_count; ++h) {
        int32_t slot = star->offsets[mesh->faces[h] + 1]++;
        star->halfedges[slot] = h;
        star->targets[slot] = mesh->faces[pz_he_next(h)];
    }
    return PZ_OK;
}

static pz_status check_face_indices(const pz_mesh *mesh, pz_ctx *ctx)
{
    for (int32_t f = 0; f < mesh->face_count; ++f) {
        const int32_t *corner = mesh->faces + 3 * f;
        for (int k = 0; k < 3; ++k)
            if (corner[k] < 0 || corner[k] >= mesh->vertex_count)
                return pz_error(ctx, PZ_ERR_INVALID_MESH, "topology: face %d uses vertex %d, out of range 0..%d",
                                (int)f, (int)corner[k], (int)mesh->vertex_count - 1);
        if (corner[0] == corner[1] || corner[1] == corner[2] || corner[2] == corner[0])
            return pz_error(ctx, PZ_ERR_INVALID_MESH, "topology: face %d repeats a vertex (%d %d %d)",
                            (int)f, (int)corner[0], (int)corner[1], (int)corner[2]);
    }
    return PZ_OK;
}

/* Pairs every half-edge a -> b with the single b -> a, refusing an edge that
 * is used twice in one direction or whose reverse appears twice. */
static pz_status find_twins(const pz_mesh *mesh, const outgoing_star *star, int32_t *twin, pz_ctx *ctx)
{
    const int32_t *faces = mesh->faces;
    int32_t halfedge_count = 3 * mesh->face_count;
    for (int32_t h = 0; h < halfedge_count; ++h) {
        int32_t from = faces[h], to = faces[pz_he_next(h)];
        int32_t found = -1, reverse_count = 0, same_count = 0;
        for (int32_t i = star->offsets[to]; i < star->offsets[to + 1]; ++i)
            if (star->targets[i] == from) {
                found = star->halfedges[i];
                ++reverse_count;
            }
        for (int32_t i = star->offsets[from]; i < star->offsets[from + 1]; ++i)
            same_count += star->targets[i] == to;
        if (reverse_count > 1 || same_count > 1)
            return pz_error(ctx, PZ_ERR_INVALID_MESH,
                            "topology: edge %d-%d has more than two faces or two faces running it the same way "
                            "(not an oriented manifold; see pz_mesh_validate)",
                            (int)(from < to ? from : to), (int)(from < to ? to : from));
        twin[h] = found;
    }
    return PZ_OK;
}

/* Numbers the undirected edges in half-edge order: an edge is born at its
 * boundary half-edge or at the lower-numbered of its two half-edges. */
static pz_status number_edges(pz_topology *t, pz_ctx *ctx)
{
    int32_t edge_count = 0;
    for (int32_t h = 0; h < t->halfedge_count; ++h)
        edge_count += t->twin[h] < 0 || h < t->twin[h];
    t->edge_count = edge_count;
    t->edge_halfedge = malloc((size_t)edge_count * 2 * sizeof(int32_t) + 1);
    if (!t->edge_halfedge)
        return pz_error(ctx, PZ_ERR_NOMEM, "out of memory for %d edges", (int)edge_count);
    int32_t edge = 0;
    for (int32_t h = 0; h < t->halfedge_count; ++h) {
        int32_t opposite = t->twin[h];
        if (opposite >= 0 && opposite < h)
            continue;
        t->edge_halfedge[2 * edge] = h;
        t->edge_halfedge[2 * edge + 1] = opposite;
        t->halfedge_edge[h] = edge;
        if (opposite >= 0)
            t->halfedge_edge[opposite] = edge;
        ++edge;
    }
    return PZ_OK;
}

/* The next outgoing half-edge of from(h) counter-clockwise, or -1 at the boundary. */
static int32_t rotate_ccw(const pz_topology *t, int32_t h)
{
    return t->twin[pz_he_prev(h)];
}

/* Chooses vertex_halfedge (a boundary half-edge when there is one, so that
 * counter-clockwise walks start at the boundary) and checks that walking
 * around each vertex reaches all of its faces: otherwise they form several
 * fans joined only at the vertex. */
static pz_status assign_vertex_halfedges(pz_topology *t, const outgoing_star *star, pz_ctx *ctx)
{
    for (int32_t v = 0; v < t->vertex_count; ++v)
        t->vertex_halfedge[v] = -1;
    for (int32_t h = 0; h < t->halfedge_count; ++h) {
        int32_t v = t->faces[h], chosen = t->vertex_halfedge[v];
        if (chosen < 0 || (t->twin[h] < 0 && t->twin[chosen] >= 0))
            t->vertex_halfedge[v] = h;
    }
    for (int32_t v = 0; v < t->vertex_count; ++v) {
        int32_t start = t->vertex_halfedge[v];
        int32_t incident = star->offsets[v + 1] - star->offsets[v];
        t->vertex_on_boundary[v] = start >= 0 && t->twin[start] < 0;
        if (start < 0)
            continue;
        int32_t reached = 0, h = start;
        do {
            ++reached;
            h = rotate_ccw(t, h);
        } while (h >= 0 && h != start && reached <= incident);
        if (reached != incident)
            return pz_error(ctx, PZ_ERR_INVALID_MESH,
                            "topology: the faces around vertex %d form more than one fan "
                            "(non-manifold vertex; see pz_mesh_validate)", (int)v);
    }
    return PZ_OK;
}

pz_status pz_topology_build(const pz_mesh *mesh, pz_topology **out, pz_ctx *ctx)
{
    *out = NULL;
    pz_status status = check_face_indices(mesh, ctx);
    if (status)
        return status;
    pz_topology *t = calloc(1, sizeof *t);
    if (!t)
        return pz_error(ctx, PZ_ERR_NOMEM, "out of memory");
    t->vertex_count = mesh->vertex_count;
    t->face_count = mesh->face_count;
    t->halfedge_count = 3 * mesh->face_count;
    t->faces = mesh->faces;
    size_t halfedge_bytes = (size_t)t->halfedge_count * sizeof(int32_t) + 1;
    t->twin = malloc(halfedge_bytes);
    t->halfedge_edge = malloc(halfedge_bytes);
    t->vertex_halfedge = malloc((size_t)t->vertex_count * sizeof(int32_t) + 1);
    t->vertex_on_boundary = malloc((size_t)t->vertex_count + 1);
    if (!t->twin || !t->halfedge_edge || !t->vertex_halfedge || !t->vertex_on_boundary) {
        pz_topology_free(&t);
        return pz_error(ctx, PZ_ERR_NOMEM, "out of memory for the connectivity of %d faces", (int)mesh->face_count);
    }
    outgoing_star star = {0};
    status = outgoing_star_build(mesh, &star, ctx);
    if (!status)
        status = find_twins(mesh, &star, t->twin, ctx);
    if (!status)
        status = number_edges(t, ctx);
    if (!status)
        status = assign_vertex_halfedges(t, &star, ctx);
    outgoing_star_free(&star);
    if (status) {
        pz_topology_free(&t);
        return status;
    }
    *out = t;
    return PZ_OK;
}

int32_t pz_topology_vertex_ring(const pz_topology *topology, int32_t v, int32_t *ring, int32_t capacity)
{
    int32_t start = topology->vertex_halfedge[v];
    if (start < 0)
        return 0;
    int32_t count = 0, h = start, last = start;
    do {
        if (count < capacity)
            ring[count] = pz_he_to(topology, h);
        ++count;
        last = h;
        h = rotate_ccw(topology, h);
    } while (h >= 0 && h != start);
    if (h < 0) {
        /* Open fan: the last face's far corner is the other boundary neighbour. */
        if (count < capacity)
            ring[count] = topology->faces[pz_he_prev(last)];
        ++count;
    }
    return count;
}

void pz_loops_free(pz_loops **loops)
{
    if (!loops || !*loops)
        return;
    free((*loops)->loop_offsets);
    free((*loops)->loop_vertices);
    free(*loops);
    *loops = NULL;
}

/* A boundary loop follows boundary half-edges: after a -> b comes b's
 * outgoing boundary half-edge, which is vertex_halfedge[b] by construction.
 * Loops start at their lowest-numbered boundary half-edge, in that order. */
pz_status pz_topology_boundary_loops(const pz_topology *topology, pz_loops **out, pz_ctx *ctx)
{
    *out = NULL;
    const pz_topology *t = topology;
    int32_t boundary_count = 0;
    for (int32_t h = 0; h < t->halfedge_count; ++h)
        boundary_count += t->twin[h] < 0;
    pz_loops *loops = calloc(1, sizeof *loops);
    uint8_t *visited = calloc((size_t)t->vertex_count + 1, 1);
    if (loops) {
        /* A loop has at least three half-edges, which bounds the loop count. */
        loops->loop_offsets = malloc(((size_t)boundary_count / 3 + 2) * sizeof(int32_t));
        loops->loop_vertices = malloc((size_t)boundary_count * sizeof(int32_t) + 1);
    }
    if (!loops || !visited || !loops->loop_offsets || !loops->loop_vertices) {
        free(visited);
        pz_loops_free(&loops);
        return pz_error(ctx, PZ_ERR_NOMEM, "out of memory for %d boundary edges", (int)boundary_count);
    }
    int32_t written = 0;
    loops->loop_offsets[0] = 0;
    for (int32_t start = 0; start < t->halfedge_count; ++start) {
        if (t->twin[start] >= 0 || visited[t->faces[start]])
            continue;
        int32_t h = start;
        while (h >= 0 && !visited[t->faces[h]] && written < boundary_count) {
            visited[t->faces[h]] = 1;
            loops->loop_vertices[written++] = t->faces[h];
            h = t->vertex_halfedge[pz_he_to(t, h)];
        }
        loops->loop_offsets[++loops->loop_count] = written;
    }
    free(visited);
    *out = loops;
    return PZ_OK;
}

/* Union-find over vertices (the three corners of a face are joined), so
 * faces touching at a single vertex share a component. Components are
 * numbered in order of their first face. */
/*
 * Faces sharing a vertex are one component: union-find over the corners of
 * every face, O(F alpha(V)). Corners out of range are skipped, so this works
 * on meshes that failed validation too; a face with no corner in range gets
 * component -1.
 */
static int32_t face_components(const int32_t *faces, int32_t face_count, int32_t vertex_count,
                               int32_t *face_component, pz_ctx *ctx)
{
    int32_t *parent = malloc((size_t)vertex_count * sizeof(int32_t) + 1);
    int32_t *label = malloc((size_t)vertex_count * sizeof(int32_t) + 1);
    if (!parent || !label) {
        free(parent);
        free(label);
        return pz_error(ctx, PZ_ERR_NOMEM, "out of memory for the components of %d vertices", (int)vertex_count);
    }
    for (int32_t v = 0; v < vertex_count; ++v) {
        parent[v] = v;
        label[v] = -1;
    }
    for (int32_t f = 0; f < face_count; ++f) {
        int32_t first = -1;
        for (int k = 0; k < 3; ++k) {
            int32_t v = faces[3 * f + k];
            if (v < 0 || v >= vertex_count)
                continue;
            if (first < 0)
                first = v;
            else
                pz_union_find_join(parent, first, v);
        }
    }
    int32_t component_count = 0;
    for (int32_t f = 0; f < face_count; ++f) {
        int32_t root = -1;
        for (int k = 0; k < 3 && root < 0; ++k) {
            int32_t v = faces[3 * f + k];
            if (v >= 0 && v < vertex_count)
                root = pz_union_find_root(parent, v);
        }
        if (root >= 0 && label[root] < 0)
            label[root] = component_count++;
        if (face_component)
            face_component[f] = root >= 0 ? label[root] : -1;
    }
    free(parent);
    free(label);
    return component_count;
}

int32_t pz_topology_components(const pz_topology *topology, int32_t *face_component, pz_ctx *ctx)
{
    return face_components(topology->faces, topology->face_count, topology->vertex_count, face_component, ctx);
}

int32_t pz_mesh_face_components(const pz_mesh *mesh, int32_t *face_component, pz_ctx *ctx)
{
    return face_components(mesh->faces, mesh->face_count, mesh->vertex_count, face_component, ctx);
}

/* chi = V - E + F is additive over components and so is the boundary loop
 * count, so the total genus sum_c (2 - chi_c - b_c) / 2 is
 * (2 C - chi - B) / 2 without per-component bookkeeping. */
pz_status pz_topology_summarize(const pz_topology *topology, pz_topology_summary *out, pz_ctx *ctx)
{
    memset(out, 0, sizeof *out);
    const pz_topology *t = topology;
    int32_t referenced = 0;
    for (int32_t v = 0; v < t->vertex_count; ++v)
        referenced += t->vertex_halfedge[v] >= 0;
    int32_t *face_component = malloc((size_t)t->face_count * sizeof(int32_t) + 1);
    if (!face_component)
        return pz_error(ctx, PZ_ERR_NOMEM, "out of memory for the components of %d faces", (int)t->face_count);
    int32_t component_count = pz_topology_components(t, face_component, ctx);
    free(face_component);
    if (component_count < 0)
        return (pz_status)component_count;
    pz_loops *loops = NULL;
    pz_status status = pz_topology_boundary_loops(t, &loops, ctx);
    if (status)
        return status;
    out->vertex_count = referenced;
    out->edge_count = t->edge_count;
    out->face_count = t->face_count;
    out->component_count = component_count;
    out->boundary_loop_count = loops->loop_count;
    out->euler_characteristic = referenced - t->edge_count + t->face_count;
    out->genus = (2 * component_count - out->euler_characteristic - loops->loop_count) / 2;
    pz_loops_free(&loops);
    return PZ_OK;
}

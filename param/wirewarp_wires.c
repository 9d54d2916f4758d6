/*
 * param/wirewarp_wires.c -- WireWarping's set-up: the wires (panel
 * boundaries and feature curves), the wire-patches they cut each panel into
 * and the wire-nodes of those patches (Sec. 2, Defs. 4-5); and the snapping
 * of feature polylines to mesh edges (pz_feature_curves_snap). The method:
 * param/wirewarp.c; the file map: param/wirewarp_internal.h.
 *
 * SPDX-License-Identifier: GPL-3.0-or-later
 */
#include "param/wirewarp_internal.h"

#include <stdlib.h>
#include <string.h>

/* ------------------------------------------------------------------------ */
/* Edge lookup                                                               */
/* ------------------------------------------------------------------------ */


static int64_t pair_key(int32_t a, int32_t b)
{
    if (a > b) {
        int32_t t = a;
        a = b;
        b = t;
    }
    return ((int64_t)a << 32) | (uint32_t)b;
}

static int edge_key_compare(const void *x, const void *y)
{
    int64_t a = ((const ww_edge_key *)x)->key, b = ((const ww_edge_key *)y)->key;
    return (a > b) - (a < b);
}

/* Sorted (vertex pair -> edge) keys of a topology; NULL when out of memory. */
ww_edge_key *ww_edge_keys(const pz_topology *t)
{
    ww_edge_key *keys = malloc((size_t)(t->edge_count + 1) * sizeof *keys);
    if (!keys)
        return NULL;
    for (int32_t e = 0; e < t->edge_count; ++e) {
        int32_t h = t->edge_halfedge[2 * e];
        keys[e].key = pair_key(pz_he_from(t, h), pz_he_to(t, h));
        keys[e].edge = e;
    }
    qsort(keys, (size_t)t->edge_count, sizeof *keys, edge_key_compare);
    return keys;
}

int32_t ww_find_edge(const ww_edge_key *keys, int32_t count, int32_t a, int32_t b)
{
    int64_t key = pair_key(a, b);
    int32_t lo = 0, hi = count - 1;
    while (lo <= hi) {
        int32_t mid = lo + (hi - lo) / 2;
        if (keys[mid].key == key)
            return keys[mid].edge;
        if (keys[mid].key < key)
            lo = mid + 1;
        else
            hi = mid - 1;
    }
    return -1;
}


/* A max-heap of (key, id) entries: the progressive scheme's patches, the snapper's Dijkstra. */

static int heap_above(const ww_heap_entry *x, const ww_heap_entry *y)
{
    return x->key > y->key || (x->key == y->key && x->patch < y->patch);
}

int ww_heap_push(ww_heap_entry **heap, size_t *capacity, int32_t *size, double key, int32_t patch)
{
    if (!pz_grow((void **)heap, capacity, (size_t)*size + 1, sizeof **heap))
        return 0;
    ww_heap_entry *h = *heap;
    int32_t i = (*size)++;
    h[i].key = key;
    h[i].patch = patch;
    while (i > 0 && heap_above(&h[i], &h[(i - 1) / 2])) {
        ww_heap_entry t = h[i];
        h[i] = h[(i - 1) / 2];
        h[(i - 1) / 2] = t;
        i = (i - 1) / 2;
    }
    return 1;
}

ww_heap_entry ww_heap_pop(ww_heap_entry *h, int32_t *size)
{
    ww_heap_entry top = h[0];
    h[0] = h[--(*size)];
    for (int32_t i = 0;;) {
        int32_t l = 2 * i + 1, r = l + 1, best = i;
        if (l < *size && heap_above(&h[l], &h[best]))
            best = l;
        if (r < *size && heap_above(&h[r], &h[best]))
            best = r;
        if (best == i)
            break;
        ww_heap_entry t = h[i];
        h[i] = h[best];
        h[best] = t;
        i = best;
    }
    return top;
}

/* ------------------------------------------------------------------------ */
/* Wires, wire-patches, wire-nodes (Sec. 2)                                  */
/* ------------------------------------------------------------------------ */


void ww_wires_free(ww_wires *w)
{
    pz_topology_free(&w->topo);
    free(w->keys);
    free(w->wire_edge);
    free(w->key_vertex);
    free(w->key_turn);
    free(w->key_side);
    free(w->patch_panel);
    free(w->patch_offsets);
    free(w->patch_perimeter);
    free(w->node_host);
    free(w->node_patch);
    free(w->alpha);
    free(w->length);
    free(w->host_offsets);
    free(w->host_nodes);
    memset(w, 0, sizeof *w);
}

/* Marks boundary and feature edges; checks the curves follow mesh edges. */
static pz_status mark_wires(const pz_pattern *pattern, const pz_feature_curves *features, ww_wires *w,
                            uint8_t *cut, pz_ctx *ctx)
{
    const pz_topology *t = w->topo;
    int32_t nv = pattern->mesh->vertex_count;
    for (int32_t e = 0; e < t->edge_count; ++e)
        w->wire_edge[e] = t->edge_halfedge[2 * e + 1] < 0;
    if (features && features->curve_count > 0 && !features->curves)
        return pz_error(ctx, PZ_ERR_USAGE, "wirewarp: %d feature curves but no array", features->curve_count);
    for (int32_t c = 0; features && c < features->curve_count; ++c) {
        const pz_feature_curve *curve = &features->curves[c];
        if (curve->vertex_count < 2 || !curve->vertices)
            return pz_error(ctx, PZ_ERR_DATA, "wirewarp: feature curve %d has fewer than 2 vertices", c);
        for (int32_t i = 0; i < curve->vertex_count; ++i) {
            int32_t v = curve->vertices[i];
            if (v < 0 || v >= nv)
                return pz_error(ctx, PZ_ERR_DATA, "wirewarp: feature curve %d: vertex %d is not on the mesh (%d vertices)",
                                c, v, nv);
            if (curve->kind == PZ_FEATURE_KEY)
                w->key_vertex[v] = 1;
            if (curve->kind == PZ_FEATURE_KEY && curve->turning && i > 0 && i + 1 < curve->vertex_count) {
                w->key_turn[v] = curve->turning[i];
                w->key_side[2 * v] = curve->vertices[i - 1];
                w->key_side[2 * v + 1] = curve->vertices[i + 1];
            }
            if (i == 0 || curve->vertices[i - 1] == v)
                continue;
            int32_t e = ww_find_edge(w->keys, t->edge_count, curve->vertices[i - 1], v);
            if (e < 0)
                return pz_error(ctx, PZ_ERR_DATA,
                                "wirewarp: feature curve %d: vertices %d and %d share no mesh edge (snap it first)", c,
                                curve->vertices[i - 1], v);
            if (!w->wire_edge[e])
                cut[e] = 1;
            w->wire_edge[e] = 1;
        }
    }
    return PZ_OK;
}

/* Nodes of the split mesh's loops, one loop per patch; CSR of nodes per host. */
static pz_status collect_nodes(const pz_pattern *pattern, const pz_mesh *split, const int32_t *host,
                               const pz_loops *loops, const int32_t *face_patch, const int32_t *vertex_face,
                               ww_wires *w, pz_ctx *ctx)
{
    int32_t m = w->patch_count, nv = pattern->mesh->vertex_count;
    int32_t *loop_of_patch = malloc((size_t)m * sizeof(int32_t) + 1);
    double *angles = malloc((size_t)split->face_count * 3 * sizeof(double) + 1);
    double *vertex_alpha = calloc((size_t)split->vertex_count + 1, sizeof(double));
    int32_t total = loops->loop_offsets[loops->loop_count];
    w->node_count = total;
    w->patch_panel = malloc((size_t)m * sizeof(int32_t) + 1);
    w->patch_offsets = malloc((size_t)(m + 1) * sizeof(int32_t));
    w->patch_perimeter = calloc((size_t)m + 1, sizeof(double));
    w->node_host = malloc((size_t)total * sizeof(int32_t) + 1);
    w->node_patch = malloc((size_t)total * sizeof(int32_t) + 1);
    w->alpha = malloc((size_t)total * sizeof(double) + 1);
    w->length = malloc((size_t)total * sizeof(double) + 1);
    w->host_offsets = calloc((size_t)nv + 1, sizeof(int32_t));
    w->host_nodes = malloc((size_t)total * sizeof(int32_t) + 1);
    pz_status status = PZ_OK;
    if (!loop_of_patch || !angles || !vertex_alpha || !w->patch_panel || !w->patch_offsets || !w->patch_perimeter ||
        !w->node_host || !w->node_patch || !w->alpha || !w->length || !w->host_offsets || !w->host_nodes) {
        status = pz_error(ctx, PZ_ERR_NOMEM, "wirewarp: out of memory for %d wire-nodes", (int)total);
        goto done;
    }
    for (int32_t p = 0; p < m; ++p)
        loop_of_patch[p] = -1;
    for (int32_t l = 0; l < loops->loop_count; ++l) {
        int32_t p = face_patch[vertex_face[loops->loop_vertices[loops->loop_offsets[l]]]];
        if (loop_of_patch[p] >= 0) {
            status = pz_error(ctx, PZ_ERR_DATA,
                              "wirewarp: a wire-patch of panel %d has several boundary loops (a closed feature curve "
                              "inside the panel?): join the curve to the panel boundary",
                              pattern->face_panel[vertex_face[loops->loop_vertices[loops->loop_offsets[l]]]]);
            goto done;
        }
        loop_of_patch[p] = l;
    }
    pz_geom_corner_angles(split, angles);
    for (int32_t c = 0; c < 3 * split->face_count; ++c)
        vertex_alpha[split->faces[c]] += angles[c];
    w->patch_offsets[0] = 0;
    for (int32_t p = 0, node = 0; p < m; ++p) {
        int32_t l = loop_of_patch[p];
        if (l < 0) {
            status = pz_error(ctx, PZ_ERR_DATA, "wirewarp: a wire-patch has no boundary (closed surface)");
            goto done;
        }
        const int32_t *loop = loops->loop_vertices + loops->loop_offsets[l];
        int32_t n = loops->loop_offsets[l + 1] - loops->loop_offsets[l];
        w->patch_panel[p] = pattern->face_panel[vertex_face[loop[0]]];
        for (int32_t b = 0; b < n; ++b, ++node) {
            w->node_host[node] = host[loop[b]];
            w->node_patch[node] = p;
            w->alpha[node] = vertex_alpha[loop[b]];
            w->length[node] = ww_distance3(pattern->mesh->positions + 3 * host[loop[b]],
                                        pattern->mesh->positions + 3 * host[loop[(b + 1) % n]]);
            w->patch_perimeter[p] += w->length[node];
            ++w->host_offsets[w->node_host[node] + 1];
        }
        w->patch_offsets[p + 1] = node;
    }
    for (int32_t v = 0; v < nv; ++v)
        w->host_offsets[v + 1] += w->host_offsets[v];
    {
        int32_t *cursor = malloc((size_t)nv * sizeof(int32_t) + 1);
        if (!cursor) {
            status = pz_error(ctx, PZ_ERR_NOMEM, "wirewarp: out of memory");
            goto done;
        }
        memcpy(cursor, w->host_offsets, (size_t)nv * sizeof(int32_t));
        for (int32_t node = 0; node < total; ++node)
            w->host_nodes[cursor[w->node_host[node]]++] = node;
        free(cursor);
    }
done:
    free(loop_of_patch);
    free(angles);
    free(vertex_alpha);
    return status;
}

/* Builds wires, wire-patches and wire-nodes of the whole pattern. */
pz_status ww_wires_build(const pz_pattern *pattern, const pz_feature_curves *features, ww_wires *w, pz_ctx *ctx)
{
    memset(w, 0, sizeof *w);
    pz_status status = pz_topology_build(pattern->mesh, &w->topo, ctx);
    if (status)
        return status;
    const pz_topology *t = w->topo;
    uint8_t *cut = calloc((size_t)t->edge_count + 1, 1);
    w->keys = ww_edge_keys(t);
    w->wire_edge = calloc((size_t)t->edge_count + 1, 1);
    w->key_vertex = calloc((size_t)pattern->mesh->vertex_count + 1, 1);
    w->key_turn = malloc((size_t)pattern->mesh->vertex_count * sizeof(double) + 1);
    w->key_side = malloc((size_t)pattern->mesh->vertex_count * 2 * sizeof(int32_t) + 1);
    pz_mesh *split = NULL;
    pz_topology *split_topo = NULL;
    pz_loops *loops = NULL;
    int32_t *host = NULL, *face_patch = NULL, *vertex_face = NULL;
    if (!cut || !w->keys || !w->wire_edge || !w->key_vertex || !w->key_turn || !w->key_side) {
        status = pz_error(ctx, PZ_ERR_NOMEM, "wirewarp: out of memory");
        goto done;
    }
    for (int32_t v = 0; v < pattern->mesh->vertex_count; ++v)
        w->key_turn[v] = NAN;
    if ((status = mark_wires(pattern, features, w, cut, ctx)))
        goto done;
    if ((status = pz_mesh_cut(pattern->mesh, t, cut, &split, &host, ctx)))
        goto done;
    if ((status = pz_topology_build(split, &split_topo, ctx)) ||
        (status = pz_topology_boundary_loops(split_topo, &loops, ctx)))
        goto done;
    face_patch = malloc((size_t)split->face_count * sizeof(int32_t) + 1);
    vertex_face = malloc((size_t)split->vertex_count * sizeof(int32_t) + 1);
    if (!face_patch || !vertex_face) {
        status = pz_error(ctx, PZ_ERR_NOMEM, "wirewarp: out of memory");
        goto done;
    }
    int32_t count = pz_topology_components(split_topo, face_patch, ctx);
    if (count < 0) {
        status = (pz_status)count;
        goto done;
    }
    w->patch_count = count;
    for (int32_t v = 0; v < split->vertex_count; ++v)
        vertex_face[v] = split_topo->vertex_halfedge[v] >= 0 ? pz_he_face(split_topo->vertex_halfedge[v]) : 0;
    status = collect_nodes(pattern, split, host, loops, face_patch, vertex_face, w, ctx);
done:
    free(cut);
    free(host);
    free(face_patch);
    free(vertex_face);
    pz_loops_free(&loops);
    pz_topology_free(&split_topo);
    pz_mesh_free(&split);
    if (status)
        ww_wires_free(w);
    return status;
}


/* ------------------------------------------------------------------------ */
/* Feature curves: snapping polylines to mesh edges                          */
/* ------------------------------------------------------------------------ */

void pz_feature_curves_free(pz_feature_curves **curves)
{
    if (!curves || !*curves)
        return;
    for (int32_t c = 0; c < (*curves)->curve_count; ++c) {
        free((*curves)->curves[c].vertices);
        free((*curves)->curves[c].turning);
    }
    free((*curves)->curves);
    free(*curves);
    *curves = NULL;
}

typedef struct ww_snapper {
    const pz_mesh *mesh;
    const pz_topology *t;
    int32_t *by_x;        /* vertices sorted by x */
    int32_t *adj_offsets, *adj;  /* vertex neighbours (CSR) */
    double *dist;         /* Dijkstra distances, INFINITY between queries */
    int32_t *parent;
    int32_t *touched;
    size_t touched_cap;
    ww_heap_entry *heap;  /* min-heap through negated keys */
    size_t heap_cap;
} ww_snapper;

typedef struct ww_keyed_vertex {
    double x;
    int32_t vertex;
} ww_keyed_vertex;

/* By x, then by id (deterministic); a key copy instead of a global, so snapping is reentrant. */
static int by_x_compare(const void *p, const void *q)
{
    const ww_keyed_vertex *a = p, *b = q;
    if (a->x != b->x)
        return (a->x > b->x) - (a->x < b->x);
    return (a->vertex > b->vertex) - (a->vertex < b->vertex);
}

/* Nearest vertex to q: binary search on x, then scan outward while |dx| can still win. */
static int32_t nearest_vertex(const ww_snapper *s, const double *q, double *distance)
{
    int32_t n = s->mesh->vertex_count, lo = 0, hi = n;
    const double *pos = s->mesh->positions;
    while (lo < hi) {
        int32_t mid = lo + (hi - lo) / 2;
        if (pos[3 * s->by_x[mid]] < q[0])
            lo = mid + 1;
        else
            hi = mid;
    }
    int32_t best = -1;
    double best_d = INFINITY;
    for (int32_t i = lo; i < n && pos[3 * s->by_x[i]] - q[0] < best_d; ++i) {
        double d = ww_distance3(pos + 3 * s->by_x[i], q);
        if (d < best_d) {
            best_d = d;
            best = s->by_x[i];
        }
    }
    for (int32_t i = lo - 1; i >= 0 && q[0] - pos[3 * s->by_x[i]] < best_d; --i) {
        double d = ww_distance3(pos + 3 * s->by_x[i], q);
        if (d < best_d) {
            best_d = d;
            best = s->by_x[i];
        }
    }
    *distance = best_d;
    return best;
}

/* Shortest edge path from a to b (Dijkstra, stops at b); appended after a. Returns 0 when unreachable or OOM. */
static int shortest_path(ww_snapper *s, int32_t a, int32_t b, int32_t **path, size_t *cap, int32_t *count)
{
    const double *pos = s->mesh->positions;
    int32_t size = 0, touched = 0, found = 0, ok = 1;
    s->dist[a] = 0;
    s->parent[a] = -1;
    if (!pz_grow((void **)&s->touched, &s->touched_cap, 1, sizeof(int32_t)))
        return 0;
    s->touched[touched++] = a;
    ok = ww_heap_push(&s->heap, &s->heap_cap, &size, -0.0, a);
    while (ok && size > 0) {
        ww_heap_entry top = ww_heap_pop(s->heap, &size);
        int32_t v = top.patch;
        if (-top.key > s->dist[v])
            continue;
        if (v == b) {
            found = 1;
            break;
        }
        for (int32_t k = s->adj_offsets[v]; k < s->adj_offsets[v + 1]; ++k) {
            int32_t u = s->adj[k];
            double d = s->dist[v] + ww_distance3(pos + 3 * v, pos + 3 * u);
            if (d < s->dist[u]) {
                if (isinf(s->dist[u])) {
                    if (!pz_grow((void **)&s->touched, &s->touched_cap, (size_t)touched + 1, sizeof(int32_t))) {
                        ok = 0;
                        break;
                    }
                    s->touched[touched++] = u;
                }
                s->dist[u] = d;
                s->parent[u] = v;
                if (!ww_heap_push(&s->heap, &s->heap_cap, &size, -d, u))
                    ok = 0;
            }
        }
    }
    if (found) {
        int32_t length = 0;
        for (int32_t v = b; v != a; v = s->parent[v])
            ++length;
        if (!pz_grow((void **)path, cap, (size_t)*count + length, sizeof(int32_t)))
            ok = 0;
        else {
            int32_t i = *count + length - 1;
            for (int32_t v = b; v != a; v = s->parent[v])
                (*path)[i--] = v;
            *count += length;
        }
    }
    for (int32_t i = 0; i < touched; ++i)
        s->dist[s->touched[i]] = INFINITY;
    return ok && found;
}

static void snapper_free(ww_snapper *s)
{
    free(s->by_x);
    free(s->adj_offsets);
    free(s->adj);
    free(s->dist);
    free(s->parent);
    free(s->touched);
    free(s->heap);
}

static int snapper_init(ww_snapper *s, const pz_mesh *mesh, const pz_topology *t)
{
    int32_t nv = mesh->vertex_count, ne = t->edge_count;
    memset(s, 0, sizeof *s);
    s->mesh = mesh;
    s->t = t;
    s->by_x = malloc((size_t)nv * sizeof(int32_t) + 1);
    s->adj_offsets = calloc((size_t)nv + 1, sizeof(int32_t));
    s->adj = malloc((size_t)ne * 2 * sizeof(int32_t) + 1);
    s->dist = malloc((size_t)nv * sizeof(double) + 1);
    s->parent = malloc((size_t)nv * sizeof(int32_t) + 1);
    int32_t *fill = malloc((size_t)nv * sizeof(int32_t) + 1);
    if (!s->by_x || !s->adj_offsets || !s->adj || !s->dist || !s->parent || !fill) {
        free(fill);
        return 0;
    }
    ww_keyed_vertex *keyed = malloc((size_t)nv * sizeof *keyed + 1);
    if (!keyed) {
        free(fill);
        return 0;
    }
    for (int32_t v = 0; v < nv; ++v) {
        keyed[v].x = mesh->positions[3 * v];
        keyed[v].vertex = v;
        s->dist[v] = INFINITY;
    }
    qsort(keyed, (size_t)nv, sizeof *keyed, by_x_compare);
    for (int32_t v = 0; v < nv; ++v)
        s->by_x[v] = keyed[v].vertex;
    free(keyed);
    for (int32_t e = 0; e < ne; ++e) {
        int32_t h = t->edge_halfedge[2 * e];
        ++s->adj_offsets[pz_he_from(t, h) + 1];
        ++s->adj_offsets[pz_he_to(t, h) + 1];
    }
    for (int32_t v = 0; v < nv; ++v)
        s->adj_offsets[v + 1] += s->adj_offsets[v];
    memcpy(fill, s->adj_offsets, (size_t)nv * sizeof(int32_t));
    for (int32_t e = 0; e < ne; ++e) {
        int32_t h = t->edge_halfedge[2 * e], a = pz_he_from(t, h), b = pz_he_to(t, h);
        s->adj[fill[a]++] = b;
        s->adj[fill[b]++] = a;
    }
    free(fill);
    return 1;
}

/* The panel of vertex v (through one of its faces), -1 for an isolated vertex. */
static int32_t vertex_panel(const pz_pattern *pattern, const pz_topology *t, int32_t v)
{
    return t->vertex_halfedge[v] >= 0 ? pattern->face_panel[pz_he_face(t->vertex_halfedge[v])] : -1;
}

static pz_status snap_one(const pz_pattern *pattern, ww_snapper *s, const pz_feature_polyline *line, int32_t c,
                          double tolerance, pz_feature_curve *curve, pz_ctx *ctx)
{
    size_t cap = 0;
    int32_t count = 0, previous = -1;
    curve->kind = line->kind;
    if (line->point_count < 2 || !line->points)
        return pz_error(ctx, PZ_ERR_DATA, "features: curve %d has fewer than 2 points", c);
    for (int32_t i = 0; i < line->point_count; ++i) {
        double d;
        int32_t v = nearest_vertex(s, line->points + 3 * i, &d);
        if (v < 0 || !(d <= tolerance)) {
            free(curve->vertices);
            curve->vertices = NULL;
            return pz_error(ctx, PZ_ERR_DATA,
                            "features: curve %d point %d is %.3g mm from the nearest mesh vertex (tolerance %.3g mm): "
                            "not on the mesh",
                            c, i, d, tolerance);
        }
        if (v == previous)
            continue;
        int ok;
        if (previous < 0) {
            ok = pz_grow((void **)&curve->vertices, &cap, 1, sizeof(int32_t));
            if (ok)
                curve->vertices[count++] = v;
        } else {
            int32_t pa = vertex_panel(pattern, s->t, previous), pb = vertex_panel(pattern, s->t, v);
            if (pa != pb) {
                free(curve->vertices);
                curve->vertices = NULL;
                return pz_error(ctx, PZ_ERR_DATA,
                                "features: curve %d runs across panels %d and %d (points %d-%d): split it per panel", c,
                                pa, pb, i - 1, i);
            }
            ok = shortest_path(s, previous, v, &curve->vertices, &cap, &count);
        }
        if (!ok) {
            free(curve->vertices);
            curve->vertices = NULL;
            return pz_error(ctx, PZ_ERR_DATA, "features: curve %d: no edge path to point %d (out of memory?)", c, i);
        }
        previous = v;
    }
    curve->vertex_count = count;
    if (count < 2) {
        free(curve->vertices);
        curve->vertices = NULL;
        return pz_error(ctx, PZ_ERR_DATA, "features: curve %d snaps to a single vertex", c);
    }
    return PZ_OK;
}

/* Both snapping entry points: strict (the first bad curve fails the call) or lenient (it is skipped). */
static pz_status snap_curves(const pz_pattern *pattern, const pz_feature_polyline *polylines, int32_t polyline_count,
                             double tolerance_mm, pz_feature_curves **out, int lenient, uint8_t *skipped,
                             void (*on_skip)(void *user, int32_t curve, const char *problem), void *user,
                             pz_ctx *ctx)
{
    *out = NULL;
    if (!pattern || !pattern->mesh || (polyline_count > 0 && !polylines) || polyline_count < 0)
        return pz_error(ctx, PZ_ERR_USAGE, "features: no pattern or no curves");
    const pz_mesh *mesh = pattern->mesh;
    pz_topology *t = NULL;
    pz_status status = pz_topology_build(mesh, &t, ctx);
    if (status)
        return status;
    if (!(tolerance_mm > 0)) {
        double sum = 0;
        for (int32_t e = 0; e < t->edge_count; ++e) {
            int32_t h = t->edge_halfedge[2 * e];
            sum += ww_distance3(mesh->positions + 3 * pz_he_from(t, h), mesh->positions + 3 * pz_he_to(t, h));
        }
        tolerance_mm = t->edge_count ? 2 * sum / t->edge_count : 0;
    }
    ww_snapper s;
    pz_feature_curves *curves = calloc(1, sizeof *curves);
    if (curves)
        curves->curves = calloc((size_t)polyline_count + 1, sizeof(pz_feature_curve));
    if (!snapper_init(&s, mesh, t) || !curves || !curves->curves) {
        status = pz_error(ctx, PZ_ERR_NOMEM, "features: out of memory");
        goto done;
    }
    for (int32_t c = 0; c < polyline_count; ++c) {
        pz_feature_curve *curve = &curves->curves[curves->curve_count];
        status = snap_one(pattern, &s, &polylines[c], c, tolerance_mm, curve, ctx);
        if (skipped)
            skipped[c] = status == PZ_ERR_DATA && lenient;
        if (status == PZ_ERR_DATA && lenient) {
            /* snap_one freed the curve's vertices; the slot is reused by the next curve */
            memset(curve, 0, sizeof *curve);
            if (on_skip)
                on_skip(user, c, strncmp(ctx->error, "features: ", 10) == 0 ? ctx->error + 10 : ctx->error);
            ctx->error[0] = 0;
            status = PZ_OK;
            continue;
        }
        if (status)
            goto done;
        ++curves->curve_count;
    }
    *out = curves;
    curves = NULL;
done:
    pz_feature_curves_free(&curves);
    snapper_free(&s);
    pz_topology_free(&t);
    return status;
}

pz_status pz_feature_curves_snap(const pz_pattern *pattern, const pz_feature_polyline *polylines,
                                 int32_t polyline_count, double tolerance_mm, pz_feature_curves **out, pz_ctx *ctx)
{
    return snap_curves(pattern, polylines, polyline_count, tolerance_mm, out, 0, NULL, NULL, NULL, ctx);
}

pz_status pz_feature_curves_snap_lenient(const pz_pattern *pattern, const pz_feature_polyline *polylines,
                                         int32_t polyline_count, double tolerance_mm, pz_feature_curves **out,
                                         uint8_t *skipped,
                                         void (*on_skip)(void *user, int32_t curve, const char *problem),
                                         void *user, pz_ctx *ctx)
{
    return snap_curves(pattern, polylines, polyline_count, tolerance_mm, out, 1, skipped, on_skip, user, ctx);
}


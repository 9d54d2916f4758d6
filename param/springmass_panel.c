/*
 * param/springmass_panel.c -- the spring-mass back-end's set-up of one panel (edges, rest
 * lengths, heights, areas, adjacency, boundary distances), its indexed heap
 * and its energies (wang2002 Eqs. 1-6, mccartney2005 Eq. 9). The method:
 * param/springmass.c; the file map: param/springmass_internal.h.
 *
 * SPDX-License-Identifier: GPL-3.0-or-later
 */
#include "param/springmass_internal.h"

#include <stdlib.h>
#include <string.h>

/* ------------------------------------------------------------------------ */
/* Indexed max-heap over ids with external keys                              */
/* ------------------------------------------------------------------------ */

int sm_heap_init(sm_heap *h, int32_t capacity, const double *key)
{
    h->count = 0;
    h->key = key;
    h->items = malloc((size_t)capacity * sizeof(int32_t) + 1);
    h->where = malloc((size_t)capacity * sizeof(int32_t) + 1);
    if (!h->items || !h->where)
        return 0;
    for (int32_t i = 0; i < capacity; ++i)
        h->where[i] = -1;
    return 1;
}

void sm_heap_free(sm_heap *h)
{
    free(h->items);
    free(h->where);
    h->items = h->where = NULL;
}

static void heap_swap(sm_heap *h, int32_t a, int32_t b)
{
    int32_t ia = h->items[a], ib = h->items[b];
    h->items[a] = ib;
    h->items[b] = ia;
    h->where[ib] = a;
    h->where[ia] = b;
}

static void heap_up(sm_heap *h, int32_t i)
{
    while (i > 0) {
        int32_t parent = (i - 1) / 2;
        if (h->key[h->items[parent]] >= h->key[h->items[i]])
            break;
        heap_swap(h, i, parent);
        i = parent;
    }
}

static void heap_down(sm_heap *h, int32_t i)
{
    for (;;) {
        int32_t left = 2 * i + 1, right = left + 1, best = i;
        if (left < h->count && h->key[h->items[left]] > h->key[h->items[best]])
            best = left;
        if (right < h->count && h->key[h->items[right]] > h->key[h->items[best]])
            best = right;
        if (best == i)
            return;
        heap_swap(h, i, best);
        i = best;
    }
}

/* Inserts id, or restores the order after its key changed. */
void sm_heap_update(sm_heap *h, int32_t id)
{
    int32_t i = h->where[id];
    if (i < 0) {
        i = h->count++;
        h->items[i] = id;
        h->where[id] = i;
    }
    heap_up(h, i);
    heap_down(h, h->where[id]);
}

int32_t sm_heap_pop(sm_heap *h)
{
    int32_t top = h->items[0];
    heap_swap(h, 0, --h->count);
    h->where[top] = -1;
    if (h->count)
        heap_down(h, 0);
    return top;
}


void sm_panel_free(sm_panel *p)
{
    free(p->pinned);
    free(p->loop);
    free(p->loop_position);
    pz_topology_free(&p->topology);
    free(p->edge_vertices);
    free(p->rest);
    free(p->vertex_edge_offsets);
    free(p->vertex_edges);
    free(p->vertex_face_offsets);
    free(p->vertex_faces);
    free(p->height);
    free(p->area3d);
    free(p->boundary_distance);
    free(p->medial);
    free(p->edge_active);
    free(p->face_placed);
    free(p->vertex_placed);
    free(p->placed_order);
    free(p->energy);
    free(p->delta);
    sm_heap_free(&p->node_heap);
}

/* CSR adjacency: for each of `count` items, its `arity` vertices. */
static int build_csr(int32_t nv, const int32_t *items, int32_t count, int arity, int32_t **offsets_out,
                     int32_t **list_out)
{
    int32_t *offsets = calloc((size_t)nv + 1, sizeof(int32_t));
    int32_t *list = malloc((size_t)count * (size_t)arity * sizeof(int32_t) + 1);
    int32_t *fill = malloc((size_t)nv * sizeof(int32_t) + 1);
    if (!offsets || !list || !fill) {
        free(offsets);
        free(list);
        free(fill);
        return 0;
    }
    for (int32_t i = 0; i < count * arity; ++i)
        ++offsets[items[i] + 1];
    for (int32_t v = 0; v < nv; ++v)
        offsets[v + 1] += offsets[v];
    memcpy(fill, offsets, (size_t)nv * sizeof(int32_t));
    for (int32_t i = 0; i < count * arity; ++i)
        list[fill[items[i]]++] = i / arity;
    free(fill);
    *offsets_out = offsets;
    *list_out = list;
    return 1;
}

/* Multi-source Dijkstra from the boundary over edges (lengths in mm). */
static int boundary_distances(sm_panel *p)
{
    double *key = malloc((size_t)p->nv * sizeof(double) + 1);
    sm_heap heap = {0};
    if (!key || !sm_heap_init(&heap, p->nv, key)) {
        free(key);
        sm_heap_free(&heap);
        return 0;
    }
    for (int32_t v = 0; v < p->nv; ++v) {
        p->boundary_distance[v] = p->topology->vertex_on_boundary[v] ? 0 : HUGE_VAL;
        key[v] = -p->boundary_distance[v];
        if (p->topology->vertex_on_boundary[v])
            sm_heap_update(&heap, v);
    }
    while (heap.count) {
        int32_t v = sm_heap_pop(&heap);
        for (int32_t i = p->vertex_edge_offsets[v]; i < p->vertex_edge_offsets[v + 1]; ++i) {
            int32_t e = p->vertex_edges[i];
            int32_t w = p->edge_vertices[2 * e] == v ? p->edge_vertices[2 * e + 1] : p->edge_vertices[2 * e];
            double d = p->boundary_distance[v] + p->rest[e];
            if (d < p->boundary_distance[w]) {
                p->boundary_distance[w] = d;
                key[w] = -d;
                sm_heap_update(&heap, w);
            }
        }
    }
    sm_heap_free(&heap);
    free(key);
    return 1;
}

pz_status sm_panel_init(sm_panel *p, const pz_mesh *mesh, const sm_settings *settings, double *uv,
                            pz_ctx *ctx)
{
    memset(p, 0, sizeof *p);
    p->mesh = mesh;
    p->settings = settings;
    p->ctx = ctx;
    p->uv = uv;
    p->omega = 1;
    pz_status status = pz_topology_build(mesh, &p->topology, ctx);
    if (status)
        return status;
    p->nv = mesh->vertex_count;
    p->nf = mesh->face_count;
    p->ne = p->topology->edge_count;
    size_t nv = (size_t)p->nv, nf = (size_t)p->nf, ne = (size_t)p->ne;
    p->edge_vertices = malloc(ne * 2 * sizeof(int32_t) + 1);
    p->rest = malloc(ne * sizeof(double) + 1);
    p->height = malloc(nf * 3 * sizeof(double) + 1);
    p->area3d = malloc(nf * sizeof(double) + 1);
    p->boundary_distance = malloc(nv * sizeof(double) + 1);
    p->medial = malloc(nf * sizeof(double) + 1);
    p->edge_active = calloc(ne + 1, 1);
    p->face_placed = calloc(nf + 1, 1);
    p->vertex_placed = calloc(nv + 1, 1);
    p->placed_order = malloc(nv * sizeof(int32_t) + 1);
    p->energy = calloc(nv + 1, sizeof(double));
    p->delta = malloc(nv * sizeof(double) + 1);
    if (!p->edge_vertices || !p->rest || !p->height || !p->area3d || !p->boundary_distance || !p->medial ||
        !p->edge_active || !p->face_placed || !p->vertex_placed || !p->placed_order || !p->energy || !p->delta)
        return pz_error(ctx, PZ_ERR_NOMEM, "springmass: out of memory");
    const double *x = mesh->positions;
    double total = 0;
    for (int32_t e = 0; e < p->ne; ++e) {
        int32_t h = p->topology->edge_halfedge[2 * e];
        p->edge_vertices[2 * e] = pz_he_from(p->topology, h);
        p->edge_vertices[2 * e + 1] = pz_he_to(p->topology, h);
        p->rest[e] = dist3d(x + 3 * p->edge_vertices[2 * e], x + 3 * p->edge_vertices[2 * e + 1]);
        total += p->rest[e];
    }
    p->mean_edge = p->ne ? total / p->ne : 1;
    for (int32_t v = 0; v < p->nv; ++v)
        p->delta[v] = 0.05 * p->mean_edge;
    for (int32_t f = 0; f < p->nf; ++f) {
        const int32_t *c = mesh->faces + 3 * f;
        const double *a = x + 3 * c[0], *b = x + 3 * c[1], *d = x + 3 * c[2];
        double e1[3] = {b[0] - a[0], b[1] - a[1], b[2] - a[2]}, e2[3] = {d[0] - a[0], d[1] - a[1], d[2] - a[2]};
        double n[3] = {e1[1] * e2[2] - e1[2] * e2[1], e1[2] * e2[0] - e1[0] * e2[2], e1[0] * e2[1] - e1[1] * e2[0]};
        double twice = sqrt(n[0] * n[0] + n[1] * n[1] + n[2] * n[2]);
        p->area3d[f] = twice / 2;
        for (int k = 0; k < 3; ++k) {
            double opposite = dist3d(x + 3 * c[(k + 1) % 3], x + 3 * c[(k + 2) % 3]);
            p->height[3 * f + k] = opposite > 0 ? twice / opposite : 0;
        }
    }
    if (!build_csr(p->nv, p->edge_vertices, p->ne, 2, &p->vertex_edge_offsets, &p->vertex_edges) ||
        !build_csr(p->nv, mesh->faces, p->nf, 3, &p->vertex_face_offsets, &p->vertex_faces) ||
        !boundary_distances(p))
        return pz_error(ctx, PZ_ERR_NOMEM, "springmass: out of memory");
    for (int32_t f = 0; f < p->nf; ++f) {
        const int32_t *c = mesh->faces + 3 * f;
        p->medial[f] = (p->boundary_distance[c[0]] + p->boundary_distance[c[1]] + p->boundary_distance[c[2]]) / 3;
    }
    if (settings->heap && !sm_heap_init(&p->node_heap, p->nv, p->energy))
        return pz_error(ctx, PZ_ERR_NOMEM, "springmass: out of memory");
    return PZ_OK;
}

/* ------------------------------------------------------------------------ */
/* Energies                                                                  */
/* ------------------------------------------------------------------------ */

int32_t sm_edge_other(const sm_panel *p, int32_t e, int32_t v)
{
    return p->edge_vertices[2 * e] == v ? p->edge_vertices[2 * e + 1] : p->edge_vertices[2 * e];
}

/* mccartney2005 Eqs. 5-9 of face f with its current 2D corners; flipped faces add a barrier. */
static double face_orthotropic(const sm_panel *p, int32_t f)
{
    const int32_t *c = p->mesh->faces + 3 * f;
    double p3[3][3], p2[3][2], warp, weft, shear_deg;
    for (int k = 0; k < 3; ++k) {
        memcpy(p3[k], p->mesh->positions + 3 * c[k], sizeof p3[k]);
        memcpy(p2[k], p->uv + 2 * c[k], sizeof p2[k]);
    }
    double det = (p2[1][0] - p2[0][0]) * (p2[2][1] - p2[0][1]) - (p2[2][0] - p2[0][0]) * (p2[1][1] - p2[0][1]);
    const pz_fabric *fabric = &p->settings->fabric;
    if (det <= 0)
        return 10 * p->area3d[f] * (fabric->k_su + fabric->k_sv) * (1 - det / (2 * p->area3d[f] + 1e-300));
    pz_metrics_triangle_strain((const double(*)[3])p3, (const double(*)[2])p2, &warp, &weft, &shear_deg);
    double phi = shear_deg * SM_PI / 180;
    return 0.25 * det * (fabric->k_su * weft * weft + fabric->k_sv * warp * warp + fabric->k_r * phi * phi);
}

/* The node's energy: Eq. 1 over its active springs, or its placed faces' orthotropic energy. */
double sm_node_energy(sm_panel *p, int32_t v)
{
    double sum = 0;
    ++p->evaluations;
    if (p->settings->orthotropic) {
        for (int32_t i = p->vertex_face_offsets[v]; i < p->vertex_face_offsets[v + 1]; ++i)
            if (p->face_placed[p->vertex_faces[i]])
                sum += face_orthotropic(p, p->vertex_faces[i]);
        return sum;
    }
    for (int32_t i = p->vertex_edge_offsets[v]; i < p->vertex_edge_offsets[v + 1]; ++i) {
        int32_t e = p->vertex_edges[i];
        if (!p->edge_active[e])
            continue;
        double stretch = dist2d(p->uv + 2 * v, p->uv + 2 * sm_edge_other(p, e, v)) - p->rest[e];
        sum += 0.5 * SM_SPRING_C * stretch * stretch;
    }
    return sum;
}

/* E(Phi), Eq. 3 (orthotropic: the sum over placed faces). */
double sm_total_energy(sm_panel *p)
{
    double sum = 0;
    if (p->settings->orthotropic) {
        for (int32_t f = 0; f < p->nf; ++f)
            if (p->face_placed[f])
                sum += face_orthotropic(p, f);
        return sum;
    }
    for (int32_t e = 0; e < p->ne; ++e)
        if (p->edge_active[e]) {
            double stretch =
                dist2d(p->uv + 2 * p->edge_vertices[2 * e], p->uv + 2 * p->edge_vertices[2 * e + 1]) - p->rest[e];
            sum += SM_SPRING_C * stretch * stretch; /* both ends' Eq. 1 */
        }
    return sum;
}

/* wang2002 Eq. 4 (per triangle) and Eq. 6 (per edge). */
void sm_accuracy(const sm_panel *p, double *e_area, double *e_shape)
{
    double area_error = 0, area_sum = 0, length_error = 0, length_sum = 0;
    for (int32_t f = 0; f < p->nf; ++f) {
        const int32_t *c = p->mesh->faces + 3 * f;
        const double *a = p->uv + 2 * c[0], *b = p->uv + 2 * c[1], *d = p->uv + 2 * c[2];
        double area2 = 0.5 * fabs((b[0] - a[0]) * (d[1] - a[1]) - (d[0] - a[0]) * (b[1] - a[1]));
        area_error += fabs(p->area3d[f] - area2);
        area_sum += p->area3d[f];
    }
    for (int32_t e = 0; e < p->ne; ++e) {
        double l2 = dist2d(p->uv + 2 * p->edge_vertices[2 * e], p->uv + 2 * p->edge_vertices[2 * e + 1]);
        length_error += fabs(p->rest[e] - l2);
        length_sum += p->rest[e];
    }
    *e_area = area_sum > 0 ? area_error / area_sum : 0;
    *e_shape = length_sum > 0 ? length_error / length_sum : 0;
}


/*
 * param/springmass.c -- spring-mass flattening with strain-energy relaxation
 * (wang2002 "Surface flattening based on energy model", mccartney2005
 * "orthotropic pattern flattening", IISERM "heap accelerated flattening").
 *
 * Every panel (a disk of the cut mesh) is flattened on its own:
 *
 * Seed. A multi-source Dijkstra from the boundary vertices over the edges
 * gives each vertex its distance to the boundary; a face's medial distance is
 * the mean over its corners (mccartney2005 Sec. 6). The face farthest from the
 * boundary is laid down undistorted, turned so that the 3D grain projected
 * onto it becomes +v (the warp; mccartney2005 Sec. 8).
 *
 * Phase one (wang2002 Sec. 6.1, mccartney2005 Sec. 6). Faces that share an
 * edge with a flattened face wait in a max-heap keyed by medial distance, so
 * the flattening grows from the middle outward. A face with one unplaced
 * corner is unconstrained: the corner goes to the intersection of the two
 * circles with the 3D edge lengths as radii, on the side that keeps the face
 * counter-clockwise. A face whose three corners are placed is constrained:
 * its springs join the system, the corner with the highest energy is moved
 * to its energy minimum (repeated node relaxations), then energy is released:
 *   full  (wang2002 InitFlatten): sweeps over every placed node until the
 *         energy varies less than energy_variation or 50 sweeps;
 *   heap  (IISERM Sec. 3): node energies live in an indexed max-heap and only
 *         the nodes on one path from the root down the larger children
 *         (single path, Sec. 3.1), or on up to heap_paths paths whose number
 *         grows as 2^(level-2) (multi-path, Sec. 3.2, Eq. 5), are relaxed.
 *
 * Phase two (wang2002 Sec. 5-6.2): for the isotropic springs, first a global
 * release (local-global iterations with one CHOLMOD factorization of the
 * spring Laplacian; see global_release: node sweeps alone stop far from the
 * minimum on large panels), then sweeps over all nodes until E_S (Eq. 4)
 * and E_C (Eq. 6) are both below the accuracy, or the energy (Eq. 3) varies
 * less than energy_variation, or max_iterations sweeps; a diverging sweep
 * is undone (see DIVERGENCE_RISE). A panel that ends folded or with its
 * outline crossing itself is flattened again, with 8 heap paths, then from
 * its LSCM (see RETRY_PATHS).
 *
 * Seam matching (not in the papers, see sm_link): the facing segments of
 * every seam and dart get the mean of their two 2D lengths; each panel's
 * outline is refitted to those lengths exactly in angle space (wang2008
 * Eqs. 2-8 for one loop, fit_loop) and its interior released again with the
 * outline pinned. Faces still flipped at the end are untangled
 * geometrically (pz_param_untangle, wirewarp.c), a matched outline kept.
 *
 * Node relaxation, isotropic. The force of Eq. 2 (C = 0.5) moves the node as
 * Eqs. 11-13 with the node starting at rest: dq = dt^2 / (2 m_i) f_i. The
 * paper drops damping, so a persistent velocity would oscillate forever; and
 * it calls rho and C scale factors: we fix the scale so that dt^2 / (2 m_i) =
 * 1 / sum_j C, the largest step for which the move cannot raise the node's
 * energy (the springs' Hessian is bounded by sum_j C); phase two
 * over-relaxes it by PHASE_TWO_OMEGA (SOR, see there). Then the overlap
 * penalty of Eqs. 14-15: for every opposite edge whose distance h_j to the
 * node has fallen below PENALTY_FRACTION of the 3D distance h_j*, the node is
 * pushed away from the edge by the shortfall. (The paper's threshold h_j* on
 * its own would fight the springs wherever a triangle is slightly
 * compressed; the fraction keeps it to triangles heading for a flip.)
 *
 * Node relaxation, orthotropic: the energy is mccartney2005 Eqs. 5-9 over
 * the node's triangles, 0.5 A (K_su (S_u - 1)^2 + K_sv (S_v - 1)^2 + K_r
 * phi^2) with u the weft, v the warp of the pattern plane, and the move is
 * ISERM's (IISERM Sec. 2, Fig. 3): four trial moves of +-delta along u and v,
 * the best one kept when it lowers the energy; each node's delta grows by 1.5
 * after a success and halves after a failure. A flipped triangle adds a
 * barrier so that moves which unflip it are taken.
 *
 * Energy map (wang2002 Sec. 6.3): the energy of each vertex (Eq. 1, or a
 * third of its triangles' orthotropic energy); Eq. 16 interpolates it
 * linearly inside triangles (energy.svg draws the value at the centroid).
 * The suggested cutting line is the crest line through the maximum: from the
 * maximum down to the boundary and from it inward, each step to the
 * neighbour (closer to / farther from the boundary) with the highest energy,
 * i.e. the slowest descent; inward it stops at a local maximum of boundary
 * distance or when the energy falls below a tenth of the maximum.
 *
 * Trial cut (mccartney2005 Sec. 4, 7): the panel is cut along that line
 * (pz_mesh_cut) and flattened again; the two sides of the cut, walked along
 * the boundary from one mouth through the tip to the other, enclose a
 * polygon whose signed area is negative when the sides splay apart (a gap:
 * dart) and positive when they overlap (a gusset), since the boundary walks
 * with the material on its left.
 *
 * Cost: phase one heap O(F log F) plus the paths; full O(F * n * sweeps);
 * phase two one sparse factorization plus O(n) per global iteration (two
 * triangular solves) and per sweep; seam matching O(outline) per Newton step
 * and one more release per linked panel. Memory O(n + F) plus the factor,
 * for all panels at once (matching needs them all). Failure: PZ_ERR_NOMEM;
 * PZ_ERR_DATA when a panel cannot be reached from its seed through edges.
 *
 * SPDX-License-Identifier: GPL-3.0-or-later
 */
#include "param/internal.h"

#include <math.h>
#include <stdlib.h>
#include <string.h>


#define SM_PI 3.14159265358979323846
#define SM_SPRING_C 0.5          /* wang2002 Sec. 5: C = 0.5 */
#define PENALTY_FRACTION 0.2     /* Eq. 14 applies when h_j < this * h_j* */
#define CONSTRAINED_STEPS 20     /* node minimization of a constrained corner */
#define CREST_STOP_FRACTION 0.1  /* the cutting line ends below this fraction of the maximum energy */

/* ------------------------------------------------------------------------ */
/* Indexed max-heap over ids with external keys                              */
/* ------------------------------------------------------------------------ */

typedef struct sm_heap {
    int32_t count;
    int32_t *items;     /* heap order */
    int32_t *where;     /* id -> index in items, -1 when absent */
    const double *key;  /* id -> key */
} sm_heap;

static int heap_init(sm_heap *h, int32_t capacity, const double *key)
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

static void heap_free(sm_heap *h)
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
static void heap_update(sm_heap *h, int32_t id)
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

static int32_t heap_pop(sm_heap *h)
{
    int32_t top = h->items[0];
    heap_swap(h, 0, --h->count);
    h->where[top] = -1;
    if (h->count)
        heap_down(h, 0);
    return top;
}

/* ------------------------------------------------------------------------ */
/* One panel                                                                 */
/* ------------------------------------------------------------------------ */

typedef struct sm_settings {
    int heap;               /* 1 heap release, 0 full */
    int paths;              /* 1 single path, >= 2 multi-path cap */
    int orthotropic;
    pz_fabric fabric;
    double grain[3];
    int max_iterations, phase_one_iterations;
    double accuracy, energy_variation;
    int local_only;         /* phase two without the global release */
    int independent;        /* no seam matching */
} sm_settings;

/* Over-relaxation of the isotropic move in the whole-system sweeps of phase
 * two: plain Gauss-Seidel moves (omega = 1) spread a long-wavelength error by
 * one ring per sweep and the energy-variation rule then stops early, far
 * from the minimum; SOR with omega < 2 converges to the same minimum. */
#define PHASE_TWO_OMEGA 1.7

typedef struct sm_panel {
    const pz_mesh *mesh;
    pz_topology *topology;
    const sm_settings *settings;
    int32_t nv, nf, ne;
    int32_t *edge_vertices;    /* ne x 2 */
    double *rest;              /* ne: 3D edge lengths d_j */
    int32_t *vertex_edge_offsets, *vertex_edges;  /* CSR vertex -> edges */
    int32_t *vertex_face_offsets, *vertex_faces;  /* CSR vertex -> faces */
    double *height;            /* nf x 3: 3D distance of corner k to its opposite edge (h_j*) */
    double *area3d;            /* nf */
    double *boundary_distance; /* nv */
    double *medial;            /* nf */
    uint8_t *edge_active, *face_placed, *vertex_placed;
    int32_t *placed_order, placed_count;
    double *uv;                /* nv x 2 */
    double *energy;            /* nv: node energy (relaxation key) */
    double *delta;             /* nv: orthotropic trial step */
    double mean_edge;
    uint8_t *pinned;           /* nv or NULL: vertices the releases keep in place (a matched outline) */
    int32_t *loop, loop_count; /* the boundary loop (seam matching), local vertices in order */
    int32_t *loop_position;    /* nv: index in loop, -1 inside */
    sm_heap node_heap;         /* heap release only */
    double omega;              /* isotropic move scale: 1, or PHASE_TWO_OMEGA in phase two */
    long long relaxations, evaluations;
} sm_panel;

/* sqrt of the squares, not hypot: pattern coordinates are far from overflow, and glibc's hypot was a
 * quarter of the 20K-face run's time (perf) */
static double norm2d(double x, double y) { return sqrt(x * x + y * y); }

static double dist2d(const double *a, const double *b) { return norm2d(a[0] - b[0], a[1] - b[1]); }

static double dist3d(const double *a, const double *b)
{
    double d[3] = {a[0] - b[0], a[1] - b[1], a[2] - b[2]};
    return sqrt(d[0] * d[0] + d[1] * d[1] + d[2] * d[2]);
}

static void panel_free(sm_panel *p)
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
    heap_free(&p->node_heap);
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
    if (!key || !heap_init(&heap, p->nv, key)) {
        free(key);
        heap_free(&heap);
        return 0;
    }
    for (int32_t v = 0; v < p->nv; ++v) {
        p->boundary_distance[v] = p->topology->vertex_on_boundary[v] ? 0 : HUGE_VAL;
        key[v] = -p->boundary_distance[v];
        if (p->topology->vertex_on_boundary[v])
            heap_update(&heap, v);
    }
    while (heap.count) {
        int32_t v = heap_pop(&heap);
        for (int32_t i = p->vertex_edge_offsets[v]; i < p->vertex_edge_offsets[v + 1]; ++i) {
            int32_t e = p->vertex_edges[i];
            int32_t w = p->edge_vertices[2 * e] == v ? p->edge_vertices[2 * e + 1] : p->edge_vertices[2 * e];
            double d = p->boundary_distance[v] + p->rest[e];
            if (d < p->boundary_distance[w]) {
                p->boundary_distance[w] = d;
                key[w] = -d;
                heap_update(&heap, w);
            }
        }
    }
    heap_free(&heap);
    free(key);
    return 1;
}

static pz_status panel_init(sm_panel *p, const pz_mesh *mesh, const sm_settings *settings, double *uv,
                            pz_ctx *ctx)
{
    memset(p, 0, sizeof *p);
    p->mesh = mesh;
    p->settings = settings;
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
    if (settings->heap && !heap_init(&p->node_heap, p->nv, p->energy))
        return pz_error(ctx, PZ_ERR_NOMEM, "springmass: out of memory");
    return PZ_OK;
}

/* ------------------------------------------------------------------------ */
/* Energies                                                                  */
/* ------------------------------------------------------------------------ */

static int32_t edge_other(const sm_panel *p, int32_t e, int32_t v)
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
static double node_energy(sm_panel *p, int32_t v)
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
        double stretch = dist2d(p->uv + 2 * v, p->uv + 2 * edge_other(p, e, v)) - p->rest[e];
        sum += 0.5 * SM_SPRING_C * stretch * stretch;
    }
    return sum;
}

/* E(Phi), Eq. 3 (orthotropic: the sum over placed faces). */
static double total_energy(sm_panel *p)
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
static void accuracy(const sm_panel *p, double *e_area, double *e_shape)
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

/* ------------------------------------------------------------------------ */
/* Node relaxation                                                           */
/* ------------------------------------------------------------------------ */

/* Eqs. 14-15: pushes v away from every opposite edge it has come too close to. */
static void overlap_penalty(sm_panel *p, int32_t v)
{
    double *q = p->uv + 2 * v, push[2] = {0, 0};
    for (int32_t i = p->vertex_face_offsets[v]; i < p->vertex_face_offsets[v + 1]; ++i) {
        int32_t f = p->vertex_faces[i];
        if (!p->face_placed[f])
            continue;
        const int32_t *c = p->mesh->faces + 3 * f;
        int k = c[0] == v ? 0 : c[1] == v ? 1 : 2;
        const double *a = p->uv + 2 * c[(k + 1) % 3], *b = p->uv + 2 * c[(k + 2) % 3];
        double ex = b[0] - a[0], ey = b[1] - a[1], length = norm2d(ex, ey);
        if (length <= 0)
            continue;
        double h = (ex * (q[1] - a[1]) - ey * (q[0] - a[0])) / length; /* > 0: v on the face's side */
        double wanted = PENALTY_FRACTION * p->height[3 * f + k];
        if (h < wanted) {
            push[0] += (wanted - h) * -ey / length;
            push[1] += (wanted - h) * ex / length;
        }
    }
    q[0] += push[0];
    q[1] += push[1];
}

/* Eq. 2 force, moved by dq = f / sum C (Eqs. 11-13 from rest, see the header). */
static void relax_isotropic(sm_panel *p, int32_t v)
{
    double force[2] = {0, 0}, stiffness = 0, *q = p->uv + 2 * v;
    for (int32_t i = p->vertex_edge_offsets[v]; i < p->vertex_edge_offsets[v + 1]; ++i) {
        int32_t e = p->vertex_edges[i];
        if (!p->edge_active[e])
            continue;
        const double *w = p->uv + 2 * edge_other(p, e, v);
        double dx = w[0] - q[0], dy = w[1] - q[1], length = norm2d(dx, dy);
        stiffness += SM_SPRING_C;
        if (length <= 0)
            continue;
        double magnitude = SM_SPRING_C * (length - p->rest[e]) / length;
        force[0] += magnitude * dx;
        force[1] += magnitude * dy;
    }
    if (stiffness > 0) {
        q[0] += p->omega * force[0] / stiffness;
        q[1] += p->omega * force[1] / stiffness;
    }
}

/* ISERM's four orthogonal trial moves (IISERM Fig. 3) with an adaptive step. */
static void relax_orthotropic(sm_panel *p, int32_t v)
{
    double *q = p->uv + 2 * v, start[2] = {q[0], q[1]};
    double best = node_energy(p, v), best_q[2] = {q[0], q[1]};
    static const double directions[4][2] = {{1, 0}, {-1, 0}, {0, 1}, {0, -1}};
    for (int d = 0; d < 4; ++d) {
        q[0] = start[0] + p->delta[v] * directions[d][0];
        q[1] = start[1] + p->delta[v] * directions[d][1];
        double trial = node_energy(p, v);
        if (trial < best) {
            best = trial;
            best_q[0] = q[0];
            best_q[1] = q[1];
        }
    }
    int moved = best_q[0] != start[0] || best_q[1] != start[1];
    q[0] = best_q[0];
    q[1] = best_q[1];
    p->delta[v] = moved ? fmin(p->delta[v] * 1.5, 0.5 * p->mean_edge) : fmax(p->delta[v] * 0.5, 1e-9 * p->mean_edge);
}

static void relax_node(sm_panel *p, int32_t v)
{
    ++p->relaxations;
    if (p->settings->orthotropic)
        relax_orthotropic(p, v);
    else
        relax_isotropic(p, v);
    overlap_penalty(p, v);
}

/* Heap mode: recompute the energies a move of v changed (v and its placed neighbours). */
static void refresh_around(sm_panel *p, int32_t v)
{
    if (!p->settings->heap)
        return;
    p->energy[v] = node_energy(p, v);
    heap_update(&p->node_heap, v);
    for (int32_t i = p->vertex_edge_offsets[v]; i < p->vertex_edge_offsets[v + 1]; ++i) {
        int32_t w = edge_other(p, p->vertex_edges[i], v);
        if (p->vertex_placed[w]) {
            p->energy[w] = node_energy(p, w);
            heap_update(&p->node_heap, w);
        }
    }
}

/* One Gauss-Seidel sweep over the placed nodes, in placement order. */
static void sweep(sm_panel *p)
{
    for (int32_t i = 0; i < p->placed_count; ++i)
        if (!p->pinned || !p->pinned[p->placed_order[i]])
            relax_node(p, p->placed_order[i]);
}

/* A whole-system sweep that raises the energy by more than this fraction
 * diverges: the overlap penalty of Eqs. 14-15 is not part of the energy, and
 * on a badly tangled phase-one result (a face scan: the paper's Fig. 14
 * case) penalty pushes and SOR feed each other until the coordinates
 * overflow. Phase two then restores the positions before that sweep, drops
 * to plain Gauss-Seidel (omega = 1), and stops if it rises again. */
#define DIVERGENCE_RISE 0.01

/* wang2002 EnergyRelease with the energy-variation and iteration rules (and,
 * in phase two (backup != NULL), the accuracy rule and the divergence guard);
 * returns the stop reason. backup: nv x 2 scratch or NULL. */
static int energy_release(sm_panel *p, int max_sweeps, double *backup, int *sweeps_run)
{
    const double target = p->pinned ? 0 : p->settings->accuracy; /* a matched outline: release it fully */
    double previous = total_energy(p);
    size_t bytes = (size_t)p->nv * 2 * sizeof(double);
    int stop = PZ_SPRINGMASS_STOP_ITERATIONS, run = 0;
    for (;;) {
        if (backup) {
            double e_area, e_shape;
            accuracy(p, &e_area, &e_shape);
            if (e_area <= target && e_shape <= target) {
                stop = PZ_SPRINGMASS_STOP_ACCURACY;
                break;
            }
        }
        if (run >= max_sweeps)
            break;
        if (backup)
            memcpy(backup, p->uv, bytes);
        sweep(p);
        ++run;
        double current = total_energy(p);
        if (backup && !(current <= previous * (1 + DIVERGENCE_RISE))) {
            memcpy(p->uv, backup, bytes);
            if (p->omega > 1) {
                p->omega = 1;
                continue;
            }
            stop = PZ_SPRINGMASS_STOP_VARIATION; /* the energy no longer falls */
            break;
        }
        if (previous <= 0 || fabs(current - previous) <= p->settings->energy_variation * previous) {
            stop = PZ_SPRINGMASS_STOP_VARIATION;
            break;
        }
        previous = current;
    }
    if (sweeps_run)
        *sweeps_run = run;
    return stop;
}

/* ------------------------------------------------------------------------ */
/* Global release (phase two, isotropic)                                     */
/* ------------------------------------------------------------------------ */

/* Node sweeps remove a long-wavelength strain one ring per sweep, so on large
 * panels the energy-variation rule stops them far from the minimum. The
 * spring energy sum C/2 (|x_a - x_b| - d_e)^2 is also min over unit vectors
 * r_e of sum C/2 |x_a - x_b - d_e r_e|^2, which local-global iterations
 * minimize (the "fast mass-spring" / projective scheme): r_e = the current
 * edge direction (local), then the positions from one linear solve with the
 * spring Laplacian (global), factored once by CHOLMOD. Each iteration cannot
 * raise the energy; a tiny proximal term GLOBAL_PROXIMAL |x - x_old|^2 fixes
 * the translation. A step that would flip more faces (the spring energy has
 * no barrier; the node sweeps after it keep the overlap penalty) or raise the
 * energy is halved up to GLOBAL_HALVINGS times, then undone, ending the
 * release. */
#define GLOBAL_MAX_ITERATIONS 200
#define GLOBAL_PROXIMAL 1e-8
#define GLOBAL_STOP 1e-5 /* relative energy decrease per iteration that ends the release */
#define GLOBAL_HALVINGS 4 /* a step that flips faces is shortened up to 4 times before the release ends */
#define GLOBAL_PIN 1e8    /* the proximal weight of a pinned vertex (the steps then keep it exactly) */

static double proximal_weight(const sm_panel *p, int32_t v)
{
    return p->pinned && p->pinned[v] ? GLOBAL_PIN : GLOBAL_PROXIMAL;
}

static int32_t flipped_faces(const sm_panel *p)
{
    int32_t count = 0;
    for (int32_t f = 0; f < p->nf; ++f) {
        const int32_t *c = p->mesh->faces + 3 * f;
        const double *a = p->uv + 2 * c[0], *b = p->uv + 2 * c[1], *d = p->uv + 2 * c[2];
        count += (b[0] - a[0]) * (d[1] - a[1]) - (d[0] - a[0]) * (b[1] - a[1]) <= 0;
    }
    return count;
}

/* The spring Laplacian C L + the proximal weights (proximal_weight), lower triangle. */
static cholmod_sparse *spring_laplacian(const sm_panel *p, cholmod_common *cc)
{
    size_t n = (size_t)p->nv;
    cholmod_triplet *t = cholmod_allocate_triplet(n, n, n + (size_t)p->ne, -1, CHOLMOD_REAL, cc);
    if (!t)
        return NULL;
    int32_t *ti = t->i, *tj = t->j;
    double *tx = t->x;
    for (int32_t v = 0; v < p->nv; ++v) {
        ti[v] = tj[v] = v;
        tx[v] = proximal_weight(p, v);
    }
    size_t at = n;
    for (int32_t e = 0; e < p->ne; ++e) {
        int32_t a = p->edge_vertices[2 * e], b = p->edge_vertices[2 * e + 1];
        tx[a] += SM_SPRING_C;
        tx[b] += SM_SPRING_C;
        ti[at] = a > b ? a : b;
        tj[at] = a > b ? b : a;
        tx[at++] = -SM_SPRING_C;
    }
    t->nnz = at;
    cholmod_sparse *matrix = cholmod_triplet_to_sparse(t, at, cc);
    cholmod_free_triplet(&t, cc);
    return matrix;
}

/* Right-hand side of the global step: sum_e C d_e r_e (local step) plus the proximal pull (pins too). */
static void global_rhs(const sm_panel *p, double *b)
{
    int32_t n = p->nv;
    for (int32_t v = 0; v < n; ++v) {
        b[v] = proximal_weight(p, v) * p->uv[2 * v];
        b[n + v] = proximal_weight(p, v) * p->uv[2 * v + 1];
    }
    for (int32_t e = 0; e < p->ne; ++e) {
        int32_t a = p->edge_vertices[2 * e], c = p->edge_vertices[2 * e + 1];
        double dx = p->uv[2 * a] - p->uv[2 * c], dy = p->uv[2 * a + 1] - p->uv[2 * c + 1], length = norm2d(dx, dy);
        if (length <= 0)
            continue;
        double scale = SM_SPRING_C * p->rest[e] / length;
        b[a] += scale * dx;
        b[n + a] += scale * dy;
        b[c] -= scale * dx;
        b[n + c] -= scale * dy;
    }
}

/* wang2002's accuracy rule: E_S and E_C both within the permissible accuracy. */
static int accurate(const sm_panel *p)
{
    double e_area, e_shape;
    accuracy(p, &e_area, &e_shape);
    return e_area <= p->settings->accuracy && e_shape <= p->settings->accuracy;
}

/* Runs the global release until the accuracy rule holds, the energy settles or
 * GLOBAL_MAX_ITERATIONS; returns the iterations kept (0 when the factorization fails). */
static int global_release(sm_panel *p, pz_ctx *ctx, pz_status *status)
{
    cholmod_common cc;
    cholmod_start(&cc);
    cc.print = 0;
    cc.supernodal = CHOLMOD_SIMPLICIAL; /* the supernodal BLAS calls cost more on these small 2D meshes (perf) */
    int32_t n = p->nv, kept = 0;
    cholmod_sparse *matrix = spring_laplacian(p, &cc);
    cholmod_factor *factor = matrix ? cholmod_analyze(matrix, &cc) : NULL;
    cholmod_dense *rhs = cholmod_zeros((size_t)n, 2, CHOLMOD_REAL, &cc);
    double *previous_uv = malloc((size_t)n * 2 * sizeof(double) + 1);
    *status = PZ_OK;
    if (!matrix || !factor || !rhs || !previous_uv) {
        if (cc.status == CHOLMOD_OUT_OF_MEMORY || !previous_uv)
            *status = pz_error(ctx, PZ_ERR_NOMEM, "springmass: out of memory for the global release");
        goto done;
    }
    if (!cholmod_factorize(matrix, factor, &cc) || cc.status != CHOLMOD_OK)
        goto done; /* not definite (cannot happen for a connected panel): the node sweeps alone */
    double energy = total_energy(p);
    int32_t flipped = flipped_faces(p);
    while (kept < GLOBAL_MAX_ITERATIONS && energy > 0 && (p->pinned || !accurate(p))) {
        memcpy(previous_uv, p->uv, (size_t)n * 2 * sizeof(double));
        global_rhs(p, rhs->x);
        cholmod_dense *x = cholmod_solve(CHOLMOD_A, factor, rhs, &cc);
        if (!x)
            break;
        /* the full step, else shorter ones toward it (GLOBAL_HALVINGS) */
        const double *s = x->x;
        double current = HUGE_VAL, t = 1;
        int accepted = 0;
        for (int halving = 0; halving <= GLOBAL_HALVINGS && !accepted; ++halving, t /= 2) {
            for (int32_t v = 0; v < n; ++v) {
                if (p->pinned && p->pinned[v])
                    continue; /* exactly where the outline was fitted, not 1e-8 off */
                p->uv[2 * v] = previous_uv[2 * v] + t * (s[v] - previous_uv[2 * v]);
                p->uv[2 * v + 1] = previous_uv[2 * v + 1] + t * (s[n + v] - previous_uv[2 * v + 1]);
            }
            current = total_energy(p);
            accepted = current <= energy && flipped_faces(p) <= flipped;
        }
        cholmod_free_dense(&x, &cc);
        if (!accepted) {
            memcpy(p->uv, previous_uv, (size_t)n * 2 * sizeof(double));
            break;
        }
        ++kept;
        int settled = energy - current <= GLOBAL_STOP * energy;
        energy = current;
        if (settled)
            break;
    }
done:
    free(previous_uv);
    cholmod_free_dense(&rhs, &cc);
    cholmod_free_factor(&factor, &cc);
    cholmod_free_sparse(&matrix, &cc);
    cholmod_finish(&cc);
    return kept;
}

/* IISERM Sec. 3: relax the nodes on the paths from the heap root down the larger children. */
static void heap_release(sm_panel *p)
{
    enum { MAX_WIDTH = 256 };
    int32_t frontier[MAX_WIDTH], next[2 * MAX_WIDTH], chosen[64 * MAX_WIDTH];
    int32_t frontier_count = 0, chosen_count = 0, cap = p->settings->paths;
    if (p->node_heap.count == 0)
        return;
    frontier[frontier_count++] = 0;
    chosen[chosen_count++] = p->node_heap.items[0];
    for (int level = 2; frontier_count > 0; ++level) {
        int32_t width = cap <= 1 ? 1 : level <= 3 ? 2 : (level - 2 < 20 ? 1 << (level - 2) : MAX_WIDTH);
        if (cap > 1 && width > cap)
            width = cap;
        if (width > MAX_WIDTH)
            width = MAX_WIDTH;
        int32_t next_count = 0;
        for (int32_t i = 0; i < frontier_count; ++i)
            for (int32_t child = 2 * frontier[i] + 1; child <= 2 * frontier[i] + 2; ++child)
                if (child < p->node_heap.count)
                    next[next_count++] = child;
        /* keep the `width` children of the largest energies (partial selection sort: width is small) */
        frontier_count = 0;
        for (int32_t k = 0; k < next_count && frontier_count < width; ++k) {
            int32_t best = k;
            for (int32_t j = k + 1; j < next_count; ++j)
                if (p->energy[p->node_heap.items[next[j]]] > p->energy[p->node_heap.items[next[best]]])
                    best = j;
            int32_t t = next[k];
            next[k] = next[best];
            next[best] = t;
            frontier[frontier_count++] = next[k];
            if (chosen_count < 64 * MAX_WIDTH)
                chosen[chosen_count++] = p->node_heap.items[next[k]];
        }
    }
    for (int32_t i = 0; i < chosen_count; ++i)
        relax_node(p, chosen[i]);
    for (int32_t i = 0; i < chosen_count; ++i)
        refresh_around(p, chosen[i]);
}

/* ------------------------------------------------------------------------ */
/* Phase one                                                                 */
/* ------------------------------------------------------------------------ */

static void place_vertex(sm_panel *p, int32_t v)
{
    if (p->vertex_placed[v])
        return;
    p->vertex_placed[v] = 1;
    p->placed_order[p->placed_count++] = v;
}

/* Marks face f flattened: its springs join the system. */
static void activate_face(sm_panel *p, int32_t f)
{
    p->face_placed[f] = 1;
    for (int k = 0; k < 3; ++k)
        p->edge_active[p->topology->halfedge_edge[3 * f + k]] = 1;
}

/* The seed face laid down undistorted with the projected grain along +v. */
static void lay_seed(sm_panel *p, int32_t f)
{
    const int32_t *c = p->mesh->faces + 3 * f;
    const double *x = p->mesh->positions, *a = x + 3 * c[0], *b = x + 3 * c[1], *d = x + 3 * c[2];
    double e1[3] = {b[0] - a[0], b[1] - a[1], b[2] - a[2]}, e2[3] = {d[0] - a[0], d[1] - a[1], d[2] - a[2]};
    double n[3] = {e1[1] * e2[2] - e1[2] * e2[1], e1[2] * e2[0] - e1[0] * e2[2], e1[0] * e2[1] - e1[1] * e2[0]};
    double nl = sqrt(n[0] * n[0] + n[1] * n[1] + n[2] * n[2]);
    for (int k = 0; k < 3; ++k)
        n[k] /= nl;
    const double *g = p->settings->grain;
    double gn = g[0] * n[0] + g[1] * n[1] + g[2] * n[2];
    double bv[3] = {g[0] - gn * n[0], g[1] - gn * n[1], g[2] - gn * n[2]};
    double bl = sqrt(bv[0] * bv[0] + bv[1] * bv[1] + bv[2] * bv[2]);
    if (bl < 1e-9) { /* grain along the normal: any in-plane direction */
        memcpy(bv, e1, sizeof bv);
        bl = sqrt(bv[0] * bv[0] + bv[1] * bv[1] + bv[2] * bv[2]);
    }
    for (int k = 0; k < 3; ++k)
        bv[k] /= bl;
    /* b_u = b_v x n, so that (b_u, b_v, n) is right-handed and the face stays counter-clockwise */
    double bu[3] = {bv[1] * n[2] - bv[2] * n[1], bv[2] * n[0] - bv[0] * n[2], bv[0] * n[1] - bv[1] * n[0]};
    for (int k = 0; k < 3; ++k) {
        const double *q = x + 3 * c[k];
        double r[3] = {q[0] - a[0], q[1] - a[1], q[2] - a[2]};
        p->uv[2 * c[k]] = r[0] * bu[0] + r[1] * bu[1] + r[2] * bu[2];
        p->uv[2 * c[k] + 1] = r[0] * bv[0] + r[1] * bv[1] + r[2] * bv[2];
        place_vertex(p, c[k]);
    }
    activate_face(p, f);
}

/* Unconstrained placement: corner k of f at the circles' intersection left of the other two. */
static void place_by_circles(sm_panel *p, int32_t f, int k)
{
    const int32_t *c = p->mesh->faces + 3 * f;
    int32_t v1 = c[(k + 1) % 3], v2 = c[(k + 2) % 3], v3 = c[k];
    const double *x = p->mesh->positions, *p1 = p->uv + 2 * v1, *p2 = p->uv + 2 * v2;
    double r1 = dist3d(x + 3 * v1, x + 3 * v3), r2 = dist3d(x + 3 * v2, x + 3 * v3);
    double ex = p2[0] - p1[0], ey = p2[1] - p1[1], d = norm2d(ex, ey);
    double *q = p->uv + 2 * v3;
    if (d <= 0) {
        q[0] = p1[0] + r1;
        q[1] = p1[1];
    } else {
        ex /= d;
        ey /= d;
        double along = (r1 * r1 - r2 * r2 + d * d) / (2 * d), across2 = r1 * r1 - along * along;
        double across = across2 > 0 ? sqrt(across2) : 0;
        /* (v1, v2, v3) is counter-clockwise: v3 lies left of v1 -> v2 */
        q[0] = p1[0] + along * ex - across * ey;
        q[1] = p1[1] + along * ey + across * ex;
    }
    place_vertex(p, v3);
}

static void push_neighbours(sm_panel *p, sm_heap *faces, int32_t f)
{
    for (int k = 0; k < 3; ++k) {
        int32_t twin = p->topology->twin[3 * f + k];
        if (twin >= 0 && !p->face_placed[pz_he_face(twin)])
            heap_update(faces, pz_he_face(twin));
    }
}

static void flatten_face(sm_panel *p, int32_t f)
{
    const int32_t *c = p->mesh->faces + 3 * f;
    int unplaced = -1;
    for (int k = 0; k < 3; ++k)
        if (!p->vertex_placed[c[k]])
            unplaced = k;
    if (unplaced >= 0) {
        place_by_circles(p, f, unplaced);
        activate_face(p, f);
        for (int k = 0; k < 3; ++k)
            refresh_around(p, c[k]);
        return;
    }
    /* constrained: move the corner with the highest energy to its minimum, then release */
    activate_face(p, f);
    int32_t worst = c[0];
    double worst_energy = -1;
    for (int k = 0; k < 3; ++k) {
        double e = node_energy(p, c[k]);
        if (e > worst_energy) {
            worst_energy = e;
            worst = c[k];
        }
    }
    for (int step = 0; step < CONSTRAINED_STEPS; ++step) {
        relax_node(p, worst);
        double e = node_energy(p, worst);
        int settled = e >= worst_energy * (1 - 1e-6);
        worst_energy = e;
        if (settled)
            break;
    }
    for (int k = 0; k < 3; ++k)
        refresh_around(p, c[k]);
    if (p->settings->heap)
        heap_release(p);
    else
        energy_release(p, p->settings->phase_one_iterations, NULL, NULL);
}

static pz_status phase_one(sm_panel *p, pz_ctx *ctx)
{
    int32_t seed = 0;
    for (int32_t f = 1; f < p->nf; ++f)
        if (p->medial[f] > p->medial[seed])
            seed = f;
    sm_heap faces = {0};
    if (!heap_init(&faces, p->nf, p->medial)) {
        heap_free(&faces);
        return pz_error(ctx, PZ_ERR_NOMEM, "springmass: out of memory");
    }
    lay_seed(p, seed);
    for (int k = 0; k < 3; ++k)
        refresh_around(p, p->mesh->faces[3 * seed + k]);
    push_neighbours(p, &faces, seed);
    int32_t flattened = 1;
    while (faces.count) {
        int32_t f = heap_pop(&faces);
        flatten_face(p, f);
        push_neighbours(p, &faces, f);
        ++flattened;
    }
    heap_free(&faces);
    if (flattened != p->nf || p->placed_count != p->nv)
        return pz_error(ctx, PZ_ERR_DATA, "springmass: a panel of %d faces is not edge-connected (%d reached from its seed)",
                        (int)p->nf, (int)flattened);
    return PZ_OK;
}

/* ------------------------------------------------------------------------ */
/* Energy map and cutting line                                               */
/* ------------------------------------------------------------------------ */

/* Per-vertex energy for the map: Eq. 1, or a third of the adjacent faces' energy. */
static void energy_map(sm_panel *p, double *out)
{
    for (int32_t v = 0; v < p->nv; ++v) {
        double e = node_energy(p, v);
        out[v] = p->settings->orthotropic ? e / 3 : e;
    }
}

/* The crest line (see the header); writes up to nv vertices, returns the count. */
static int32_t crest_line(const sm_panel *p, const double *map, int32_t *line)
{
    int32_t top = 0;
    for (int32_t v = 1; v < p->nv; ++v)
        if (map[v] > map[top])
            top = v;
    /* toward the boundary: strictly decreasing distance, highest energy first */
    int32_t count = 0, v = top;
    line[count++] = v;
    while (p->boundary_distance[v] > 0) {
        int32_t best = -1;
        for (int32_t i = p->vertex_edge_offsets[v]; i < p->vertex_edge_offsets[v + 1]; ++i) {
            int32_t w = edge_other(p, p->vertex_edges[i], v);
            if (p->boundary_distance[w] < p->boundary_distance[v] && (best < 0 || map[w] > map[best]))
                best = w;
        }
        if (best < 0)
            break;
        line[count++] = v = best;
    }
    for (int32_t i = 0; i < count / 2; ++i) { /* boundary first */
        int32_t t = line[i];
        line[i] = line[count - 1 - i];
        line[count - 1 - i] = t;
    }
    /* inward: strictly increasing distance while the energy stays up */
    v = top;
    for (;;) {
        int32_t best = -1;
        for (int32_t i = p->vertex_edge_offsets[v]; i < p->vertex_edge_offsets[v + 1]; ++i) {
            int32_t w = edge_other(p, p->vertex_edges[i], v);
            if (p->boundary_distance[w] > p->boundary_distance[v] && (best < 0 || map[w] > map[best]))
                best = w;
        }
        if (best < 0 || map[best] < CREST_STOP_FRACTION * map[top] || count >= p->nv)
            break;
        line[count++] = v = best;
    }
    return count;
}

/* ------------------------------------------------------------------------ */
/* Driver                                                                    */
/* ------------------------------------------------------------------------ */

typedef struct sm_outcome {
    int stop, iterations;
    double phase_one_energy, final_energy, e_area, e_shape;
    double phase_one_ms, phase_two_ms;
    long long relaxations, phase_one_relaxations, evaluations;
    int global_iterations;
} sm_outcome;

/* Phase two (wang2002 Sec. 5-6.2): the global release (isotropic), then the node sweeps. Also releases a
 * matched panel's interior against its pinned outline. */
static pz_status panel_release(sm_panel *p, sm_outcome *outcome, pz_ctx *ctx)
{
    pz_status status = PZ_OK;
    if (!p->settings->orthotropic && !p->settings->local_only) {
        outcome->global_iterations += global_release(p, ctx, &status);
        if (status)
            return status;
    }
    p->omega = PHASE_TWO_OMEGA;
    double *backup = malloc((size_t)p->nv * 2 * sizeof(double) + 1);
    if (!backup)
        return pz_error(ctx, PZ_ERR_NOMEM, "springmass: out of memory");
    int sweeps = 0;
    outcome->stop = energy_release(p, p->settings->max_iterations, backup, &sweeps);
    outcome->iterations += sweeps;
    free(backup);
    return PZ_OK;
}

/* Phase one and phase two of one disk mesh into uv (nv x 2), the state kept in p for seam matching and
 * panel_finish. */
static pz_status panel_flatten(sm_panel *p, const pz_mesh *mesh, const sm_settings *settings, double *uv,
                               sm_outcome *outcome, pz_ctx *ctx)
{
    double start = pz_seconds();
    pz_status status = panel_init(p, mesh, settings, uv, ctx);
    if (!status)
        status = phase_one(p, ctx);
    if (status)
        return status;
    outcome->phase_one_ms = 1e3 * (pz_seconds() - start);
    outcome->phase_one_relaxations = p->relaxations;
    outcome->phase_one_energy = total_energy(p);
    start = pz_seconds();
    status = panel_release(p, outcome, ctx);
    outcome->phase_two_ms = 1e3 * (pz_seconds() - start);
    return status;
}

/* The panel's last steps: folds untangled, its figures, energy map and cutting line (map and line may be
 * NULL). */
static pz_status panel_finish(sm_panel *p, sm_outcome *outcome, double *map, int32_t *line, int32_t *line_count,
                              pz_ctx *ctx)
{
    /* folds left by phase one (the shared mannequin: 76 faces, 35 after this): the
     * springs have no barrier, so unflip them geometrically (no flip added; a matched outline stays) */
    if (flipped_faces(p) > 0 && pz_param_untangle(p->mesh, p->pinned, p->uv) < 0)
        return pz_error(ctx, PZ_ERR_NOMEM, "springmass: out of memory");
    outcome->final_energy = total_energy(p);
    accuracy(p, &outcome->e_area, &outcome->e_shape);
    if (map)
        energy_map(p, map);
    if (map && line)
        *line_count = crest_line(p, map, line);
    outcome->relaxations = p->relaxations;
    outcome->evaluations = p->evaluations;
    return PZ_OK;
}

/* Flattens one disk mesh on its own into uv (nv x 2): the trial cut's re-flattening. */
static pz_status flatten_disk(const pz_mesh *mesh, const sm_settings *settings, double *uv, sm_outcome *outcome,
                              pz_ctx *ctx)
{
    sm_panel p;
    pz_status status = panel_flatten(&p, mesh, settings, uv, outcome, ctx);
    if (!status)
        status = panel_finish(&p, outcome, NULL, NULL, NULL, ctx);
    panel_free(&p);
    return status;
}

/* ------------------------------------------------------------------------ */
/* Seam matching                                                             */
/* ------------------------------------------------------------------------ */

/*
 * Sewing needs the two sides of a seam (the two legs of a dart) to have the
 * same length. Flattened alone, each panel's springs give its outline their
 * own compromise, and the sides of a seam came out up to 13 % apart on the
 * shared garments (docs/springmass.md). So every pair of facing segments
 * (a_i a_i+1 on one side, b_i b_i+1 on the other, as the pattern pairs
 * them; a dart's legs out to the tip) is a link, and after phase two both
 * segments get the mean of their 2D lengths. Each panel's outline is then
 * refitted with those edge lengths exactly (fit_loop: wang2008's
 * length-preserving boundary, Eqs. 2-8 for one loop, the target angles
 * being the outline's own turning angles, so it moves as little as the new
 * lengths allow), and its interior is released again with the outline
 * pinned. Matching segment by segment keeps facing notches together; only
 * lengths are shared, each panel keeps its own shape. A penalty coupling in
 * the releases was tried first: with stiff links the local-global release
 * converged slowly and panels held by the flip guard kept their partners
 * from matching (0.1-1.1 % left on the shared garments, energy up 30-150 %).
 */
typedef struct sm_link {
    int32_t curve;            /* seam s, or seam_count + dart d */
    int32_t panel[2];         /* side a's and side b's panel */
    int32_t end[2][2];        /* each side's segment: two local vertices of its panel */
    double rest;              /* mean 3D length of the two segments */
} sm_link;

#define FIT_ITERATIONS 50     /* optimality steps of fit_loop (Newton stops in under 10 on the tests) */
#define FIT_FEASIBLE 1e-13    /* scaled closure residual the feasibility steps aim for */
#define FIT_ACCEPT 1e-9       /* an outline left with a larger residual is not matched */

/* Appends the links of one seam (tip < 0) or dart: facing segments (a[i], a[i+1]) / (b[i], b[i+1]) and, for
 * a dart, (a[n-1], tip) / (b[n-1], tip). owner/local: pattern vertex -> panel and local vertex. */
static void add_links(sm_link *links, int32_t *count, const pz_mesh *mesh, const int32_t *owner,
                      const int32_t *local, int32_t curve, const int32_t *a, const int32_t *b, int32_t n,
                      int32_t tip)
{
    for (int32_t i = 0; i + 1 < n || (tip >= 0 && i < n); ++i) {
        int32_t ends[2][2] = {{a[i], i + 1 < n ? a[i + 1] : tip}, {b[i], i + 1 < n ? b[i + 1] : tip}};
        sm_link *l = &links[*count];
        int usable = 1;
        for (int side = 0; side < 2; ++side) {
            usable &= ends[side][0] != ends[side][1] && owner[ends[side][0]] == owner[ends[side][1]];
            l->panel[side] = owner[ends[side][0]];
            l->end[side][0] = local[ends[side][0]];
            l->end[side][1] = local[ends[side][1]];
        }
        if (!usable)
            continue;
        l->curve = curve;
        l->rest = (dist3d(mesh->positions + 3 * ends[0][0], mesh->positions + 3 * ends[0][1]) +
                   dist3d(mesh->positions + 3 * ends[1][0], mesh->positions + 3 * ends[1][1])) / 2;
        ++*count;
    }
}

/* The links of every seam and dart; vertex_maps[k]: panel k's local -> pattern vertex. -1 when out of
 * memory, else the count. */
static int32_t build_links(const pz_pattern *pattern, int32_t *const *vertex_maps, const sm_panel *panels,
                           sm_link **out)
{
    int32_t nv = pattern->mesh->vertex_count, count = 0;
    size_t capacity = 0;
    for (int32_t s = 0; s < pattern->seam_count; ++s)
        capacity += (size_t)pattern->seams[s].pair_count;
    for (int32_t d = 0; d < pattern->dart_count; ++d)
        capacity += (size_t)pattern->darts[d].pair_count;
    int32_t *owner = malloc((size_t)nv * sizeof(int32_t) + 1), *local = malloc((size_t)nv * sizeof(int32_t) + 1);
    sm_link *links = malloc(capacity * sizeof(sm_link) + 1);
    if (!owner || !local || !links) {
        free(owner);
        free(local);
        free(links);
        return -1;
    }
    for (int32_t k = 0; k < pattern->panel_count; ++k)
        for (int32_t v = 0; v < panels[k].nv; ++v) {
            owner[vertex_maps[k][v]] = k;
            local[vertex_maps[k][v]] = v;
        }
    for (int32_t s = 0; s < pattern->seam_count; ++s)
        add_links(links, &count, pattern->mesh, owner, local, s, pattern->seams[s].side_a, pattern->seams[s].side_b,
                  pattern->seams[s].pair_count, -1);
    for (int32_t d = 0; d < pattern->dart_count; ++d)
        add_links(links, &count, pattern->mesh, owner, local, pattern->seam_count + d, pattern->darts[d].leg_a,
                  pattern->darts[d].leg_b, pattern->darts[d].pair_count, pattern->darts[d].tip);
    free(owner);
    free(local);
    *out = links;
    return count;
}

/* The panel's boundary loop and each vertex's place in it; 0 when out of memory (a panel with several loops
 * gets loop_count 0: not matched). */
static int panel_loop(sm_panel *p, pz_ctx *ctx)
{
    pz_loops *loops = NULL;
    if (pz_topology_boundary_loops(p->topology, &loops, ctx))
        return 0;
    p->loop_position = malloc((size_t)p->nv * sizeof(int32_t) + 1);
    p->loop = malloc((size_t)loops->loop_offsets[loops->loop_count] * sizeof(int32_t) + 1);
    if (!p->loop_position || !p->loop) {
        pz_loops_free(&loops);
        return 0;
    }
    for (int32_t v = 0; v < p->nv; ++v)
        p->loop_position[v] = -1;
    if (loops->loop_count == 1) {
        p->loop_count = loops->loop_offsets[1];
        memcpy(p->loop, loops->loop_vertices, (size_t)p->loop_count * sizeof(int32_t));
        for (int32_t i = 0; i < p->loop_count; ++i)
            p->loop_position[p->loop[i]] = i;
    }
    pz_loops_free(&loops);
    return 1;
}

/* The shorter run of loop edges between local vertices a and b: edges first .. first + count - 1 (mod n);
 * 0 when either is not on the loop. */
static int loop_path(const sm_panel *p, int32_t a, int32_t b, int32_t *first, int32_t *count)
{
    int32_t n = p->loop_count, i = p->loop_position[a], j = p->loop_position[b];
    if (i < 0 || j < 0 || i == j)
        return 0;
    int32_t forward = ((j - i) % n + n) % n;
    *first = forward <= n - forward ? i : j;
    *count = forward <= n - forward ? forward : n - forward;
    return 1;
}

static double loop_edge(const sm_panel *p, const double *uv, int32_t i)
{
    return dist2d(uv + 2 * p->loop[i], uv + 2 * p->loop[(i + 1) % p->loop_count]);
}

static double path_length(const sm_panel *p, int32_t first, int32_t count)
{
    double sum = 0;
    for (int32_t k = 0; k < count; ++k)
        sum += loop_edge(p, p->uv, (first + k) % p->loop_count);
    return sum;
}

/* Solves the 3 x 3 symmetric positive system a x = b (Cholesky); 0 when not definite. */
static int solve3(double a[3][3], const double b[3], double x[3])
{
    double l[3][3] = {{0}};
    for (int i = 0; i < 3; ++i)
        for (int j = 0; j <= i; ++j) {
            double sum = a[i][j];
            for (int k = 0; k < j; ++k)
                sum -= l[i][k] * l[j][k];
            if (i == j) {
                if (!(sum > 0))
                    return 0;
                l[i][i] = sqrt(sum);
            } else {
                l[i][j] = sum / l[j][j];
            }
        }
    double y[3];
    for (int i = 0; i < 3; ++i) {
        y[i] = b[i];
        for (int k = 0; k < i; ++k)
            y[i] -= l[i][k] * y[k];
        y[i] /= l[i][i];
    }
    for (int i = 2; i >= 0; --i) {
        x[i] = y[i];
        for (int k = i + 1; k < 3; ++k)
            x[i] -= l[k][i] * x[k];
        x[i] /= l[i][i];
    }
    return 1;
}

/*
 * Edge directions phi (phi_0 fixed, phi_i = phi_{i-1} + tau_i), the constraint
 * residuals g (turning, closure x and y over the perimeter L) and the suffix
 * sums of l sin phi and l cos phi that make the Jacobian (wang2008 Eqs. 17-19).
 */
static void fit_evaluate(int32_t n, const double *length, double perimeter, double total, double phi0,
                         const double *tau, double *phi, double *suffix_sin, double *suffix_cos, double g[3])
{
    double turning = tau[0];
    phi[0] = phi0;
    for (int32_t i = 1; i < n; ++i) {
        phi[i] = phi[i - 1] + tau[i];
        turning += tau[i];
    }
    double s = 0, c = 0;
    for (int32_t i = n - 1; i >= 0; --i) {
        s += length[i] * sin(phi[i]) / perimeter;
        c += length[i] * cos(phi[i]) / perimeter;
        suffix_sin[i] = s;
        suffix_cos[i] = c;
    }
    g[0] = turning - total;
    g[1] = c;
    g[2] = s;
}

/*
 * Refits the panel's outline to the edge lengths `length` (loop edge i from
 * loop[i] to loop[i+1]): the closed polygon whose turning angles tau are
 * nearest, in least squares, to the outline's current ones tau0 (wang2008
 * Eq. 2 for one loop: sum tau = the current total turning, the loop closes).
 * Sequential linearly constrained steps (Eqs. 5-7, J J^T is 3 x 3), then
 * feasibility steps; the new outline is laid from loop[0] along edge 0's
 * direction and moved rigidly onto the old one (least squares). Writes out
 * (loop_count x 2); returns the scaled residual (HUGE_VAL when it failed).
 * scratch: 6 x loop_count doubles.
 */
static double fit_loop(const sm_panel *p, const double *length, double *out, double *scratch)
{
    int32_t n = p->loop_count;
    double *tau0 = scratch, *tau = tau0 + n, *phi = tau + n, *ss = phi + n, *sc = ss + n, *delta = sc + n;
    double perimeter = 0, turning = 0;
    for (int32_t i = 0; i < n; ++i) {
        const double *a = p->uv + 2 * p->loop[(i + n - 1) % n], *b = p->uv + 2 * p->loop[i],
                     *c = p->uv + 2 * p->loop[(i + 1) % n];
        double d1[2] = {b[0] - a[0], b[1] - a[1]}, d2[2] = {c[0] - b[0], c[1] - b[1]};
        tau0[i] = tau[i] = atan2(d1[0] * d2[1] - d1[1] * d2[0], d1[0] * d2[0] + d1[1] * d2[1]);
        turning += tau0[i];
        perimeter += length[i];
    }
    const double *b0 = p->uv + 2 * p->loop[0], *b1 = p->uv + 2 * p->loop[1 % n];
    double phi0 = atan2(b1[1] - b0[1], b1[0] - b0[0]), total = 2 * SM_PI * nearbyint(turning / (2 * SM_PI)), g[3];
    if (n < 3 || !(perimeter > 0))
        return HUGE_VAL;
    for (int iteration = 0, feasibility = 0; iteration < FIT_ITERATIONS + 20; ++iteration) {
        fit_evaluate(n, length, perimeter, total, phi0, tau, phi, ss, sc, g);
        if (feasibility && fmax(fabs(g[0]), fmax(fabs(g[1]), fabs(g[2]))) < FIT_FEASIBLE)
            break;
        /* J: row 0 all ones; rows 1, 2 at column j >= 1: -suffix_sin[j], suffix_cos[j] (column 0: 0, 0) */
        double jj[3][3] = {{0}}, rhs[3] = {g[0], g[1], g[2]}, mu[3], step2 = 0;
        for (int32_t j = 0; j < n; ++j) {
            double col[3] = {1, j ? -ss[j] : 0, j ? sc[j] : 0}, r = feasibility ? 0 : tau0[j] - tau[j];
            for (int a = 0; a < 3; ++a) {
                rhs[a] += col[a] * r;
                for (int b = 0; b < 3; ++b)
                    jj[a][b] += col[a] * col[b];
            }
        }
        for (int a = 0; a < 3; ++a)
            jj[a][a] += 1e-14 * n;
        if (!solve3(jj, rhs, mu))
            return HUGE_VAL;
        for (int32_t j = 0; j < n; ++j) {
            double col[3] = {1, j ? -ss[j] : 0, j ? sc[j] : 0};
            delta[j] = (feasibility ? 0 : tau0[j] - tau[j]) - col[0] * mu[0] - col[1] * mu[1] - col[2] * mu[2];
            step2 += delta[j] * delta[j];
        }
        for (int32_t j = 0; j < n; ++j)
            tau[j] += delta[j];
        if (feasibility)
            ++feasibility;
        else if (step2 / n < 1e-24 || iteration + 1 >= FIT_ITERATIONS)
            feasibility = 1;
    }
    fit_evaluate(n, length, perimeter, total, phi0, tau, phi, ss, sc, g);
    double residual = fmax(fabs(g[0]), fmax(fabs(g[1]), fabs(g[2])));
    if (!(residual <= FIT_ACCEPT))
        return HUGE_VAL;
    /* lay it out (Eq. 8), then the rigid motion onto the old outline */
    double old_centre[2] = {0, 0}, new_centre[2] = {0, 0}, dot = 0, cross = 0;
    out[0] = out[1] = 0;
    for (int32_t i = 0; i + 1 < n; ++i) {
        out[2 * (i + 1)] = out[2 * i] + length[i] * cos(phi[i]);
        out[2 * (i + 1) + 1] = out[2 * i + 1] + length[i] * sin(phi[i]);
    }
    for (int32_t i = 0; i < n; ++i)
        for (int k = 0; k < 2; ++k) {
            old_centre[k] += p->uv[2 * p->loop[i] + k] / n;
            new_centre[k] += out[2 * i + k] / n;
        }
    for (int32_t i = 0; i < n; ++i) {
        double x = out[2 * i] - new_centre[0], y = out[2 * i + 1] - new_centre[1];
        double u = p->uv[2 * p->loop[i]] - old_centre[0], v = p->uv[2 * p->loop[i] + 1] - old_centre[1];
        dot += x * u + y * v;
        cross += x * v - y * u;
    }
    double angle = atan2(cross, dot), c = cos(angle), s = sin(angle);
    for (int32_t i = 0; i < n; ++i) {
        double x = out[2 * i] - new_centre[0], y = out[2 * i + 1] - new_centre[1];
        out[2 * i] = old_centre[0] + c * x - s * y;
        out[2 * i + 1] = old_centre[1] + s * x + c * y;
    }
    return residual;
}

/* Every link's mean length onto both its sides (scaling the loop edges of each side's run); marks the
 * panels that have a link. targets[k]: panel k's loop edge lengths, preset to the current ones. */
static void link_targets(const sm_panel *panels, const sm_link *links, int32_t link_count, double **targets,
                         uint8_t *linked)
{
    for (int32_t i = 0; i < link_count; ++i) {
        const sm_link *l = &links[i];
        int32_t first[2], count[2];
        double length[2];
        int usable = 1;
        for (int side = 0; side < 2 && usable; ++side) {
            const sm_panel *p = &panels[l->panel[side]];
            usable = p->loop_count > 0 && loop_path(p, l->end[side][0], l->end[side][1], &first[side], &count[side]);
            length[side] = usable ? path_length(p, first[side], count[side]) : 0;
            usable &= length[side] > 0;
        }
        if (!usable)
            continue;
        double mean = (length[0] + length[1]) / 2;
        for (int side = 0; side < 2; ++side) {
            const sm_panel *p = &panels[l->panel[side]];
            for (int32_t k = 0; k < count[side]; ++k) {
                int32_t e = (first[side] + k) % p->loop_count;
                targets[l->panel[side]][e] = loop_edge(p, p->uv, e) * mean / length[side];
            }
            linked[l->panel[side]] = 1;
        }
    }
}

/* Faces still flipped after untangling a copy of the panel with `fixed` vertices kept; -1 when out of memory.
 * copy: nv x 2 scratch. */
static int32_t flips_left(sm_panel *p, const uint8_t *fixed, double *copy)
{
    double *uv = p->uv;
    memcpy(copy, uv, (size_t)p->nv * 2 * sizeof(double));
    p->uv = copy;
    int32_t flipped = flipped_faces(p);
    if (flipped > 0)
        flipped = pz_param_untangle(p->mesh, fixed, copy) < 0 ? -1 : flipped_faces(p);
    p->uv = uv;
    return flipped;
}

/* Refits one linked panel's outline to its targets, pins it and releases the interior again. Returns 1 when
 * matched; 0 (the panel as it was) when the outline could not be refitted or when the matched panel would
 * keep more flipped faces than the unmatched one (a fold the pinned outline does not let go, e.g. an ear
 * triangle turned over by the refit). */
static int match_panel(sm_panel *p, const double *target, sm_outcome *outcome, double *scratch, pz_ctx *ctx,
                       pz_status *status)
{
    double *fitted = scratch + 6 * (size_t)p->loop_count;
    size_t bytes = (size_t)p->nv * 2 * sizeof(double);
    double *before = malloc(bytes + 1), *copy = malloc(bytes + 1);
    sm_outcome unmatched = *outcome;
    int matched = 0;
    p->pinned = calloc((size_t)p->nv + 1, 1);
    *status = PZ_OK;
    if (!before || !copy || !p->pinned) {
        *status = pz_error(ctx, PZ_ERR_NOMEM, "springmass: out of memory");
        goto done;
    }
    if (fit_loop(p, target, fitted, scratch) == HUGE_VAL)
        goto done;
    memcpy(before, p->uv, bytes);
    int32_t alone = flips_left(p, NULL, copy);
    for (int32_t i = 0; i < p->loop_count; ++i) {
        p->uv[2 * p->loop[i]] = fitted[2 * i];
        p->uv[2 * p->loop[i] + 1] = fitted[2 * i + 1];
        p->pinned[p->loop[i]] = 1;
    }
    if ((*status = panel_release(p, outcome, ctx)))
        goto done;
    int32_t together = flips_left(p, p->pinned, copy);
    if (alone < 0 || together < 0)
        *status = pz_error(ctx, PZ_ERR_NOMEM, "springmass: out of memory");
    matched = !*status && together <= alone;
    if (!matched) {
        memcpy(p->uv, before, bytes);
        int work = outcome->global_iterations;
        *outcome = unmatched;
        outcome->global_iterations = work; /* the work was done all the same */
    }
done:
    free(before);
    free(copy);
    if (!matched) {
        free(p->pinned);
        p->pinned = NULL;
    }
    return matched;
}

/* Seam matching of all panels (see sm_link); counts the panels it could not refit. */
static pz_status match_seams(sm_panel *panels, int32_t panel_count, const sm_link *links, int32_t link_count,
                             sm_outcome *outcomes, int32_t *unmatched, pz_ctx *ctx)
{
    double **targets = calloc((size_t)panel_count + 1, sizeof(double *));
    uint8_t *linked = calloc((size_t)panel_count + 1, 1);
    double *scratch = NULL;
    pz_status status = PZ_OK;
    size_t most = 0;
    if (!targets || !linked)
        status = pz_error(ctx, PZ_ERR_NOMEM, "springmass: out of memory");
    for (int32_t k = 0; k < panel_count && !status; ++k) {
        sm_panel *p = &panels[k];
        if (!(targets[k] = malloc((size_t)p->loop_count * sizeof(double) + 1))) {
            status = pz_error(ctx, PZ_ERR_NOMEM, "springmass: out of memory");
            break;
        }
        for (int32_t i = 0; i < p->loop_count; ++i)
            targets[k][i] = loop_edge(p, p->uv, i);
        most = (size_t)p->loop_count > most ? (size_t)p->loop_count : most;
    }
    if (!status && !(scratch = malloc(most * 8 * sizeof(double) + 1)))
        status = pz_error(ctx, PZ_ERR_NOMEM, "springmass: out of memory");
    if (!status)
        link_targets(panels, links, link_count, targets, linked);
    for (int32_t k = 0; k < panel_count && !status; ++k) {
        if (!linked[k])
            continue;
        double start = pz_seconds();
        *unmatched += !match_panel(&panels[k], targets[k], &outcomes[k], scratch, ctx, &status);
        outcomes[k].phase_two_ms += 1e3 * (pz_seconds() - start);
    }
    for (int32_t k = 0; targets && k < panel_count; ++k)
        free(targets[k]);
    free(targets);
    free(linked);
    free(scratch);
    return status;
}

/* Worst |side a - side b| / 3D length over the seams and darts (sums over their links, lengths along the
 * outline between each link's ends, straight when its panel has no loop). curve_count: seams + darts. */
static double worst_mismatch(const sm_panel *panels, const sm_link *links, int32_t link_count, int32_t curve_count)
{
    double *sums = calloc((size_t)curve_count * 3 + 1, sizeof(double)), worst = 0;
    if (!sums)
        return NAN;
    for (int32_t i = 0; i < link_count; ++i) {
        const sm_link *l = &links[i];
        for (int side = 0; side < 2; ++side) {
            const sm_panel *p = &panels[l->panel[side]];
            int32_t first, count;
            sums[3 * l->curve + side] += p->loop_count > 0 && loop_path(p, l->end[side][0], l->end[side][1], &first, &count)
                                             ? path_length(p, first, count)
                                             : dist2d(p->uv + 2 * l->end[side][0], p->uv + 2 * l->end[side][1]);
        }
        sums[3 * l->curve + 2] += l->rest;
    }
    for (int32_t c = 0; c < curve_count; ++c)
        if (sums[3 * c + 2] > 0)
            worst = fmax(worst, fabs(sums[3 * c] - sums[3 * c + 1]) / sums[3 * c + 2]);
    free(sums);
    return worst;
}

/* Signed area between the two sides of the cut (> 0: they splay apart). */
static double cut_opening(const pz_mesh *cut, const int32_t *cut_origin, const double *uv, const int32_t *line,
                          int32_t line_count, pz_ctx *ctx, pz_status *status)
{
    pz_topology *topology = NULL;
    pz_loops *loops = NULL;
    double opening = 0;
    *status = pz_topology_build(cut, &topology, ctx);
    if (!*status)
        *status = pz_topology_boundary_loops(topology, &loops, ctx);
    if (*status) {
        pz_topology_free(&topology);
        return 0;
    }
    int32_t tip = line[line_count - 1], reach = line_count - 1;
    for (int32_t l = 0; l < loops->loop_count; ++l) {
        const int32_t *loop = loops->loop_vertices + loops->loop_offsets[l];
        int32_t n = loops->loop_offsets[l + 1] - loops->loop_offsets[l];
        for (int32_t i = 0; i < n; ++i) {
            if (cut_origin[loop[i]] != tip || n < 2 * reach + 1)
                continue;
            int ok = 1;
            double twice = 0;
            for (int32_t j = -reach; j < reach; ++j) {
                int32_t a = loop[((i + j) % n + n) % n], b = loop[((i + j + 1) % n + n) % n];
                int32_t k = j < 0 ? -j : j;
                ok &= cut_origin[a] == line[line_count - 1 - k];
                twice += uv[2 * a] * uv[2 * b + 1] - uv[2 * b] * uv[2 * a + 1];
            }
            int32_t first = loop[((i - reach) % n + n) % n], last = loop[(i + reach) % n];
            ok &= cut_origin[last] == line[0];
            twice += uv[2 * last] * uv[2 * first + 1] - uv[2 * first] * uv[2 * last + 1];
            if (ok)
                opening = -twice / 2; /* the boundary keeps the material on its left: a gap is clockwise */
        }
    }
    pz_loops_free(&loops);
    pz_topology_free(&topology);
    return opening;
}

/*
 * An opening (gap or overlap) of at most this fraction of the panel's area is
 * no seam at all (PZ_SEAM_KIND_NONE): on a 300 mm panel, a dart half its
 * width long whose mouth is 1.2 mm wide, below what a cutter or a sewer can
 * place. Measured: 3 of the 10 panels of the 3K generated bodice (`run`)
 * open by 0.03-0.09% (4.9 mm^2 on a 15,300 mm^2 panel): none; the others by
 * 0.11-4.8%; a 25-degree spherical cap opens by 0.48%, the saddle test's
 * disk by 0.37%, an 8-degree cap by 0.014%.
 */
#define SM_CUT_NONE_FRACTION 1e-3

/* Cuts the panel along its line, flattens it again and classifies the cut. */
static pz_status trial_cut(const pz_mesh *panel_mesh, const sm_settings *settings, const int32_t *line,
                           int32_t line_count, pz_springmass_panel *out, pz_ctx *ctx)
{
    pz_topology *topology = NULL;
    pz_mesh *cut = NULL;
    int32_t *origin = NULL;
    uint8_t *flags = NULL;
    double *uv = NULL;
    pz_status status = pz_topology_build(panel_mesh, &topology, ctx);
    if (status)
        return status;
    flags = calloc((size_t)topology->edge_count + 1, 1);
    if (!flags) {
        status = pz_error(ctx, PZ_ERR_NOMEM, "springmass: out of memory");
        goto done;
    }
    for (int32_t i = 0; i + 1 < line_count; ++i) {
        int32_t h = topology->vertex_halfedge[line[i]], start = h;
        /* walk the outgoing half-edges of line[i] to find the edge to line[i + 1] */
        do {
            if (pz_he_to(topology, h) == line[i + 1] || pz_he_from(topology, pz_he_prev(h)) == line[i + 1]) {
                int32_t e = pz_he_to(topology, h) == line[i + 1] ? topology->halfedge_edge[h]
                                                                  : topology->halfedge_edge[pz_he_prev(h)];
                flags[e] = 1;
                break;
            }
            int32_t twin = topology->twin[pz_he_prev(h)];
            h = twin;
        } while (h >= 0 && h != start);
    }
    status = pz_mesh_cut(panel_mesh, topology, flags, &cut, &origin, ctx);
    if (status)
        goto done;
    uv = malloc((size_t)cut->vertex_count * 2 * sizeof(double) + 1);
    if (!uv) {
        status = pz_error(ctx, PZ_ERR_NOMEM, "springmass: out of memory");
        goto done;
    }
    sm_outcome outcome = {0};
    status = flatten_disk(cut, settings, uv, &outcome, ctx);
    if (status)
        goto done;
    out->cut_energy = outcome.final_energy;
    out->cut_opening_mm2 = cut_opening(cut, origin, uv, line, line_count, ctx, &status);
    double area = pz_geom_total_area(panel_mesh);
    out->cut_kind = fabs(out->cut_opening_mm2) <= SM_CUT_NONE_FRACTION * area ? PZ_SEAM_KIND_NONE
                    : out->cut_opening_mm2 > 0               ? PZ_SEAM_KIND_DART
                                                             : PZ_SEAM_KIND_GUSSET;
done:
    free(uv);
    free(flags);
    free(origin);
    pz_mesh_free(&cut);
    pz_topology_free(&topology);
    return status;
}

void pz_springmass_result_clear(pz_springmass_result *result)
{
    if (!result)
        return;
    free(result->vertex_energy);
    for (int32_t i = 0; i < result->panel_count && result->panels; ++i)
        free(result->panels[i].cut_vertices);
    free(result->panels);
    memset(result, 0, sizeof *result);
}

static void settings_from(const pz_springmass_options *options, sm_settings *s)
{
    pz_springmass_options zero = {0};
    if (!options)
        options = &zero;
    memset(s, 0, sizeof *s);
    s->heap = options->relax == 0;
    s->paths = options->heap_paths > 1 ? options->heap_paths : 1;
    s->orthotropic = options->orthotropic;
    s->fabric.k_su = options->fabric.k_su > 0 ? options->fabric.k_su : 0.946;
    s->fabric.k_sv = options->fabric.k_sv > 0 ? options->fabric.k_sv : 0.548;
    s->fabric.k_r = options->fabric.k_r > 0 ? options->fabric.k_r : 0.159;
    double z[3] = {0, 0, 1};
    memcpy(s->grain, options->grain_given ? options->grain : z, sizeof s->grain);
    s->max_iterations = options->max_iterations > 0 ? options->max_iterations : 1000;
    s->phase_one_iterations = options->phase_one_iterations > 0 ? options->phase_one_iterations : 50;
    s->accuracy = options->accuracy > 0 ? options->accuracy : 0.01;
    s->energy_variation = options->energy_variation > 0 ? options->energy_variation : 0.0005;
    s->local_only = options->local_release_only;
    s->independent = options->independent_panels;
}

/* One panel of the pattern: its own mesh and buffers, kept until every panel is flattened (seam matching). */
typedef struct sm_piece {
    pz_mesh *mesh;
    int32_t *vertex_map;       /* local -> pattern vertex */
    double *uv, *map;
    int32_t *line, line_count;
    sm_settings retry;         /* the settings of a retry (its panel points to them) */
} sm_piece;

static void pieces_free(sm_piece *pieces, sm_panel *panels, int32_t count)
{
    for (int32_t k = 0; pieces && k < count; ++k) {
        if (panels)
            panel_free(&panels[k]);
        pz_mesh_free(&pieces[k].mesh);
        free(pieces[k].vertex_map);
        free(pieces[k].uv);
        free(pieces[k].map);
        free(pieces[k].line);
    }
    free(pieces);
    free(panels);
}

/* Flipped faces plus crossings of the outline; -1 when out of memory. */
static int32_t panel_defects(const sm_panel *p)
{
    int32_t *edges = malloc((size_t)p->loop_count * 2 * sizeof(int32_t) + 1);
    if (!edges)
        return -1;
    for (int32_t i = 0; i < p->loop_count; ++i) {
        edges[2 * i] = p->loop[i];
        edges[2 * i + 1] = p->loop[(i + 1) % p->loop_count];
    }
    int32_t crossings = pz_metrics_outline_crossings(edges, p->loop_count, p->uv);
    free(edges);
    return crossings < 0 ? -1 : crossings + flipped_faces(p);
}

/*
 * Second tries for a panel that ends phase two folded (flipped faces) or with
 * its outline crossing itself. Heap relaxation relaxes a few nodes per
 * triangle, and once in a while its phase one leaves a basin the releases
 * cannot leave: the generated bodice's back came out with a crossing
 * outline, energy 823 where full relaxation and 8 heap paths give 341. Such
 * a panel is flattened again with RETRY_PATHS heap paths (IISERM's
 * multi-path); if that is still folded (phase one itself tangles on the
 * shared head scans, one panel each), phase two starts from the panel's LSCM
 * instead of phase one (our addition, not the papers'). The best of the tries
 * is kept: fewer defects, else less energy. The cost is paid only there.
 */
#define RETRY_PATHS 8

/* Phase two from the panel's LSCM (area-scaled, grain along +v) instead of phase one. */
static pz_status panel_from_lscm(sm_panel *p, const pz_mesh *mesh, const sm_settings *settings, double *uv,
                                 sm_outcome *outcome, pz_ctx *ctx)
{
    double start = pz_seconds();
    pz_status status = panel_init(p, mesh, settings, uv, ctx);
    if (!status)
        status = pz_param_lscm(mesh, settings->grain, uv, ctx);
    if (status)
        return status;
    for (int32_t f = 0; f < p->nf; ++f)
        activate_face(p, f);
    for (int32_t v = 0; v < p->nv; ++v)
        place_vertex(p, v);
    outcome->phase_one_ms = 1e3 * (pz_seconds() - start);
    outcome->phase_one_energy = total_energy(p);
    start = pz_seconds();
    status = panel_release(p, outcome, ctx);
    outcome->phase_two_ms = 1e3 * (pz_seconds() - start);
    return status;
}

/* Panel k flattened again (with_lscm 0: RETRY_PATHS heap paths, 1: from LSCM); kept when better, updating
 * *defects. */
static pz_status retry_piece(sm_piece *piece, sm_panel *panel, sm_outcome *outcome, int with_lscm, int32_t *defects,
                             pz_ctx *ctx)
{
    sm_panel second;
    sm_outcome second_outcome = {0};
    size_t bytes = (size_t)panel->nv * 2 * sizeof(double);
    double *uv = malloc(bytes + 1);
    piece->retry = *panel->settings;
    piece->retry.paths = with_lscm ? piece->retry.paths : RETRY_PATHS;
    memset(&second, 0, sizeof second);
    pz_status status = !uv ? pz_error(ctx, PZ_ERR_NOMEM, "springmass: out of memory")
                       : with_lscm ? panel_from_lscm(&second, piece->mesh, &piece->retry, uv, &second_outcome, ctx)
                                   : panel_flatten(&second, piece->mesh, &piece->retry, uv, &second_outcome, ctx);
    if (!status && !panel_loop(&second, ctx))
        status = pz_error(ctx, PZ_ERR_NOMEM, "springmass: out of memory");
    int32_t second_defects = status ? -1 : panel_defects(&second);
    if (!status && second_defects < 0)
        status = pz_error(ctx, PZ_ERR_NOMEM, "springmass: out of memory");
    if (!status && (second_defects < *defects ||
                    (second_defects == *defects && total_energy(&second) < total_energy(panel)))) {
        long long work = panel->relaxations;
        double ms = outcome->phase_one_ms + outcome->phase_two_ms;
        panel_free(panel);
        *panel = second;
        memcpy(piece->uv, uv, bytes);
        panel->uv = piece->uv;
        panel->relaxations += work; /* every try counts */
        *outcome = second_outcome;
        outcome->phase_one_ms += ms;
        *defects = second_defects;
    } else {
        panel_free(&second);
    }
    free(uv);
    return status;
}

/* Extracts panel k and runs its phase one and two (and second tries when it ends folded). */
static pz_status start_piece(const pz_pattern *pattern, const int32_t *faces, int32_t face_count, int32_t k,
                             const sm_settings *settings, sm_piece *piece, sm_panel *panel, sm_outcome *outcome,
                             int32_t *retried, pz_ctx *ctx)
{
    if (face_count == 0)
        return pz_error(ctx, PZ_ERR_DATA, "springmass: panel %d has no faces", (int)k);
    pz_status status = pz_mesh_extract(pattern->mesh, faces, face_count, &piece->mesh, &piece->vertex_map, NULL, ctx);
    if (status)
        return status;
    size_t nv = (size_t)piece->mesh->vertex_count;
    piece->uv = malloc(nv * 2 * sizeof(double) + 1);
    piece->map = malloc(nv * sizeof(double) + 1);
    piece->line = malloc(nv * sizeof(int32_t) + 1);
    if (!piece->uv || !piece->map || !piece->line)
        return pz_error(ctx, PZ_ERR_NOMEM, "springmass: out of memory");
    if ((status = panel_flatten(panel, piece->mesh, settings, piece->uv, outcome, ctx)))
        return status;
    if (!panel_loop(panel, ctx))
        return pz_error(ctx, PZ_ERR_NOMEM, "springmass: out of memory");
    int32_t defects = panel_defects(panel);
    if (defects < 0)
        return pz_error(ctx, PZ_ERR_NOMEM, "springmass: out of memory");
    *retried += defects > 0;
    if (defects > 0 && settings->heap && settings->paths < RETRY_PATHS)
        status = retry_piece(piece, panel, outcome, 0, &defects, ctx);
    if (!status && defects > 0)
        status = retry_piece(piece, panel, outcome, 1, &defects, ctx);
    return status;
}

/* Writes panel k's coordinates back and fills its record (trial cut when asked). */
static pz_status record_piece(const sm_piece *piece, const sm_outcome *outcome, int32_t panel,
                              const sm_settings *settings, int do_trial_cut, double *uv, pz_springmass_result *result,
                              pz_ctx *ctx)
{
    int32_t nv = piece->mesh->vertex_count;
    for (int32_t v = 0; v < nv; ++v) {
        uv[2 * piece->vertex_map[v]] = piece->uv[2 * v];
        uv[2 * piece->vertex_map[v] + 1] = piece->uv[2 * v + 1];
    }
    if (!result)
        return PZ_OK;
    pz_springmass_panel *record = &result->panels[panel];
    record->panel = panel;
    record->stop = outcome->stop;
    record->iterations = outcome->iterations;
    record->global_iterations = outcome->global_iterations;
    record->phase_one_energy = outcome->phase_one_energy;
    record->final_energy = outcome->final_energy;
    record->e_area = outcome->e_area;
    record->e_shape = outcome->e_shape;
    int32_t top = 0;
    for (int32_t v = 0; v < nv; ++v) {
        result->vertex_energy[piece->vertex_map[v]] = piece->map[v];
        if (piece->map[v] > piece->map[top])
            top = v;
    }
    record->max_energy_vertex = piece->vertex_map[top];
    pz_status status = PZ_OK;
    if (do_trial_cut && piece->line_count >= 2)
        status = trial_cut(piece->mesh, settings, piece->line, piece->line_count, record, ctx);
    record->cut_vertices = malloc((size_t)piece->line_count * sizeof(int32_t) + 1);
    if (!record->cut_vertices)
        return status ? status : pz_error(ctx, PZ_ERR_NOMEM, "springmass: out of memory");
    for (int32_t i = 0; i < piece->line_count; ++i)
        record->cut_vertices[i] = piece->vertex_map[piece->line[i]];
    record->cut_vertex_count = piece->line_count;
    result->phase_one_energy += outcome->phase_one_energy;
    result->final_energy += outcome->final_energy;
    result->node_relaxations += outcome->relaxations;
    result->phase_one_relaxations += outcome->phase_one_relaxations;
    result->energy_evaluations += outcome->evaluations;
    result->phase_one_ms += outcome->phase_one_ms;
    result->phase_two_ms += outcome->phase_two_ms;
    result->global_iterations += outcome->global_iterations;
    return status;
}

/* Seam matching (unless settings->independent), then the seams' mismatch into result (may be NULL). */
static pz_status match_pieces(const pz_pattern *pattern, const sm_settings *settings, const sm_piece *pieces,
                              sm_panel *panels, sm_outcome *outcomes, pz_springmass_result *result, pz_ctx *ctx)
{
    int32_t np = pattern->panel_count, unmatched = 0;
    int32_t **maps = malloc((size_t)np * sizeof(int32_t *) + 1);
    sm_link *links = NULL;
    int32_t count = maps ? 0 : -1;
    for (int32_t k = 0; count == 0 && k < np; ++k)
        maps[k] = pieces[k].vertex_map;
    if (count == 0)
        count = build_links(pattern, maps, panels, &links);
    free(maps);
    pz_status status = count < 0 ? pz_error(ctx, PZ_ERR_NOMEM, "springmass: out of memory") : PZ_OK;
    if (!status && count > 0 && !settings->independent)
        status = match_seams(panels, np, links, count, outcomes, &unmatched, ctx);
    if (!status && result) {
        result->matched_pairs = settings->independent ? 0 : count;
        result->unmatched_panels = unmatched;
        result->max_seam_mismatch =
            count > 0 ? worst_mismatch(panels, links, count, pattern->seam_count + pattern->dart_count) : 0;
    }
    free(links);
    return status;
}

pz_status pz_param_springmass(const pz_pattern *pattern, const pz_springmass_options *options, double *uv,
                              pz_springmass_result *result, pz_ctx *ctx)
{
    sm_settings settings;
    settings_from(options, &settings);
    if (result)
        memset(result, 0, sizeof *result);
    int32_t np = pattern->panel_count, *offsets = NULL, *order = NULL, retried = 0;
    pz_status status = pz_param_panel_faces(pattern, &offsets, &order, ctx);
    sm_piece *pieces = status ? NULL : calloc((size_t)np + 1, sizeof *pieces);
    sm_panel *panels = status ? NULL : calloc((size_t)np + 1, sizeof *panels);
    sm_outcome *outcomes = status ? NULL : calloc((size_t)np + 1, sizeof *outcomes);
    if (!status && (!pieces || !panels || !outcomes))
        status = pz_error(ctx, PZ_ERR_NOMEM, "springmass: out of memory");
    if (!status && result) {
        result->vertex_count = pattern->mesh->vertex_count;
        result->panel_count = np;
        result->vertex_energy = calloc((size_t)pattern->mesh->vertex_count + 1, sizeof(double));
        result->panels = calloc((size_t)np + 1, sizeof(pz_springmass_panel));
        if (!result->vertex_energy || !result->panels)
            status = pz_error(ctx, PZ_ERR_NOMEM, "springmass: out of memory");
    }
    for (int32_t k = 0; k < np && !status; ++k)
        status = start_piece(pattern, order + offsets[k], offsets[k + 1] - offsets[k], k, &settings, &pieces[k],
                             &panels[k], &outcomes[k], &retried, ctx);
    if (!status)
        status = match_pieces(pattern, &settings, pieces, panels, outcomes, result, ctx);
    for (int32_t k = 0; k < np && !status; ++k)
        status = panel_finish(&panels[k], &outcomes[k], pieces[k].map, pieces[k].line, &pieces[k].line_count, ctx);
    int do_trial_cut = options && options->trial_cut;
    for (int32_t k = 0; k < np && !status; ++k)
        status = record_piece(&pieces[k], &outcomes[k], k, &settings, do_trial_cut, uv, result, ctx);
    if (result)
        result->retried_panels = retried;
    pieces_free(pieces, panels, np);
    free(outcomes);
    free(order);
    free(offsets);
    if (status && result)
        pz_springmass_result_clear(result);
    return status;
}

/* ------------------------------------------------------------------------ */
/* energy.svg                                                                */
/* ------------------------------------------------------------------------ */

/* Blue (low) to red (high) through green and yellow. */
static void energy_colour(double t, int rgb[3])
{
    t = t < 0 ? 0 : t > 1 ? 1 : t;
    double r = t < 0.5 ? 0 : t < 0.75 ? (t - 0.5) * 4 : 1;
    double g = t < 0.25 ? t * 4 : t < 0.75 ? 1 : (1 - t) * 4;
    double b = t < 0.25 ? 1 : t < 0.5 ? (0.5 - t) * 4 : 0;
    rgb[0] = (int)(255 * r + 0.5);
    rgb[1] = (int)(255 * g + 0.5);
    rgb[2] = (int)(255 * b + 0.5);
}

pz_status pz_springmass_write_energy_svg(const pz_pattern *pattern, const double *uv,
                                         const pz_springmass_result *result, const char *path, pz_ctx *ctx)
{
    const pz_mesh *mesh = pattern->mesh;
    int32_t np = pattern->panel_count;
    double *box = malloc((size_t)np * 4 * sizeof(double) + 1), *shift = malloc((size_t)np * 2 * sizeof(double) + 1);
    if (!box || !shift) {
        free(box);
        free(shift);
        return pz_error(ctx, PZ_ERR_NOMEM, "%s: out of memory", path);
    }
    for (int32_t p = 0; p < np; ++p) {
        box[4 * p] = box[4 * p + 1] = HUGE_VAL;
        box[4 * p + 2] = box[4 * p + 3] = -HUGE_VAL;
    }
    for (int32_t f = 0; f < mesh->face_count; ++f)
        for (int k = 0; k < 3; ++k) {
            const double *q = uv + 2 * mesh->faces[3 * f + k];
            double *b = box + 4 * pattern->face_panel[f];
            b[0] = fmin(b[0], q[0]);
            b[1] = fmin(b[1], q[1]);
            b[2] = fmax(b[2], q[0]);
            b[3] = fmax(b[3], q[1]);
        }
    /* panels side by side, 20 mm apart; SVG y runs down, so v is negated */
    double x = 10, height = 0;
    for (int32_t p = 0; p < np; ++p) {
        shift[2 * p] = x - box[4 * p];
        shift[2 * p + 1] = 10 + box[4 * p + 3];
        x += box[4 * p + 2] - box[4 * p] + 20;
        height = fmax(height, box[4 * p + 3] - box[4 * p + 1]);
    }
    double top = 0;
    for (int32_t v = 0; result && v < result->vertex_count; ++v)
        top = fmax(top, result->vertex_energy[v]);
    pz_output out;
    pz_status status = pz_output_open(&out, path, "w", ctx);
    if (status) {
        free(box);
        free(shift);
        return status;
    }
    FILE *file = out.file;
    fprintf(file,
            "<?xml version=\"1.0\" encoding=\"UTF-8\"?>\n<svg xmlns=\"http://www.w3.org/2000/svg\" "
            "width=\"%.3fmm\" height=\"%.3fmm\" viewBox=\"0 0 %.3f %.3f\">\n",
            x - 10, height + 20, x - 10, height + 20);
    fprintf(file, "<!-- spring-mass energy map (wang2002 Sec. 6.3): blue low, red high; max %.6g -->\n", top);
    for (int32_t f = 0; f < mesh->face_count; ++f) {
        const int32_t *c = mesh->faces + 3 * f;
        const double *s = shift + 2 * pattern->face_panel[f];
        double mean = 0;
        for (int k = 0; k < 3 && result; ++k)
            mean += result->vertex_energy[c[k]] / 3;
        int rgb[3];
        energy_colour(top > 0 ? mean / top : 0, rgb);
        fprintf(file, "<polygon fill=\"#%02x%02x%02x\" stroke=\"none\" points=\"", rgb[0], rgb[1], rgb[2]);
        for (int k = 0; k < 3; ++k)
            fprintf(file, "%.3f,%.3f ", uv[2 * c[k]] + s[0], s[1] - uv[2 * c[k] + 1]);
        fprintf(file, "\"/>\n");
    }
    for (int32_t p = 0; result && p < result->panel_count; ++p) {
        const pz_springmass_panel *record = &result->panels[p];
        const double *s = shift + 2 * p;
        fprintf(file, "<polyline fill=\"none\" stroke=\"black\" stroke-width=\"1\" points=\"");
        for (int32_t i = 0; i < record->cut_vertex_count; ++i) {
            const double *q = uv + 2 * record->cut_vertices[i];
            fprintf(file, "%.3f,%.3f ", q[0] + s[0], s[1] - q[1]);
        }
        fprintf(file, "\"/>\n");
    }
    fprintf(file, "</svg>\n");
    free(box);
    free(shift);
    return pz_output_commit(&out, ctx);
}

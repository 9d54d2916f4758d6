/*
 * param/springmass_release.c -- the spring-mass back-end's solve for one panel:
 * node relaxation and energy release, the global release (CHOLMOD), phase
 * one (triangles laid from the seed) and phase two. The method:
 * param/springmass.c.
 *
 * SPDX-License-Identifier: GPL-3.0-or-later
 */
#include "param/springmass_internal.h"

#include <stdlib.h>
#include <string.h>

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
        const double *w = p->uv + 2 * sm_edge_other(p, e, v);
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
    double best = sm_node_energy(p, v), best_q[2] = {q[0], q[1]};
    static const double directions[4][2] = {{1, 0}, {-1, 0}, {0, 1}, {0, -1}};
    for (int d = 0; d < 4; ++d) {
        q[0] = start[0] + p->delta[v] * directions[d][0];
        q[1] = start[1] + p->delta[v] * directions[d][1];
        double trial = sm_node_energy(p, v);
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
    p->energy[v] = sm_node_energy(p, v);
    sm_heap_update(&p->node_heap, v);
    for (int32_t i = p->vertex_edge_offsets[v]; i < p->vertex_edge_offsets[v + 1]; ++i) {
        int32_t w = sm_edge_other(p, p->vertex_edges[i], v);
        if (p->vertex_placed[w]) {
            p->energy[w] = sm_node_energy(p, w);
            sm_heap_update(&p->node_heap, w);
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
    double previous = sm_total_energy(p);
    size_t bytes = (size_t)p->nv * 2 * sizeof(double);
    int stop = PZ_SPRINGMASS_STOP_ITERATIONS, run = 0;
    for (;;) {
        if (backup) {
            double e_area, e_shape;
            sm_accuracy(p, &e_area, &e_shape);
            if (e_area <= target && e_shape <= target) {
                stop = PZ_SPRINGMASS_STOP_ACCURACY;
                break;
            }
        }
        if (run >= max_sweeps || pz_cancelled(p->ctx))
            break;
        if (backup)
            memcpy(backup, p->uv, bytes);
        sweep(p);
        ++run;
        double current = sm_total_energy(p);
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

int32_t sm_flipped_faces(const sm_panel *p)
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
    sm_accuracy(p, &e_area, &e_shape);
    return e_area <= p->settings->accuracy && e_shape <= p->settings->accuracy;
}

/* The spring system's CHOLMOD workspace, started on first use. */
static cholmod_common *spring_common(sm_spring *spring)
{
    if (!spring->started) {
        cholmod_start(&spring->common);
        spring->common.print = 0;
        /* the supernodal BLAS calls cost more on these small 2D meshes (perf) */
        spring->common.supernodal = CHOLMOD_SIMPLICIAL;
        spring->started = 1;
    }
    return &spring->common;
}

void sm_spring_free(sm_spring *spring)
{
    if (spring->started) {
        cholmod_free_factor(&spring->symbolic, &spring->common);
        cholmod_finish(&spring->common);
    }
    memset(spring, 0, sizeof *spring);
}

/* A factor ready for the spring Laplacian's numeric factorization: a copy of
 * the piece's symbolic analysis, made on first use (the pattern is the
 * piece's edges, whatever the pins and weights). NULL when out of memory. */
static cholmod_factor *spring_factor(sm_spring *spring, cholmod_sparse *matrix)
{
    if (!spring->symbolic && !(spring->symbolic = cholmod_analyze(matrix, &spring->common)))
        return NULL;
    return cholmod_copy_factor(spring->symbolic, &spring->common);
}

/* Runs the global release until the accuracy rule holds, the energy settles or
 * GLOBAL_MAX_ITERATIONS; returns the iterations kept (0 when the factorization fails). */
static int global_release(sm_panel *p, pz_ctx *ctx, pz_status *status)
{
    sm_spring own;
    memset(&own, 0, sizeof own);
    sm_spring *spring = p->spring ? p->spring : &own;
    cholmod_common *cc = spring_common(spring);
    int32_t n = p->nv, kept = 0;
    cholmod_sparse *matrix = spring_laplacian(p, cc);
    cholmod_factor *factor = matrix ? spring_factor(spring, matrix) : NULL;
    cholmod_dense *rhs = cholmod_zeros((size_t)n, 2, CHOLMOD_REAL, cc);
    double *previous_uv = malloc((size_t)n * 2 * sizeof(double) + 1);
    *status = PZ_OK;
    if (!matrix || !factor || !rhs || !previous_uv) {
        if (cc->status == CHOLMOD_OUT_OF_MEMORY || !previous_uv)
            *status = pz_error(ctx, PZ_ERR_NOMEM, "springmass: out of memory for the global release");
        goto done;
    }
    if (!cholmod_factorize(matrix, factor, cc) || cc->status != CHOLMOD_OK)
        goto done; /* not definite (cannot happen for a connected panel): the node sweeps alone */
    double energy = sm_total_energy(p);
    int32_t flipped = sm_flipped_faces(p);
    while (kept < GLOBAL_MAX_ITERATIONS && energy > 0 && (p->pinned || !accurate(p)) && !pz_cancelled(ctx)) {
        memcpy(previous_uv, p->uv, (size_t)n * 2 * sizeof(double));
        global_rhs(p, rhs->x);
        cholmod_dense *x = cholmod_solve(CHOLMOD_A, factor, rhs, cc);
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
            current = sm_total_energy(p);
            accepted = current <= energy && sm_flipped_faces(p) <= flipped;
        }
        cholmod_free_dense(&x, cc);
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
    cholmod_free_dense(&rhs, cc);
    cholmod_free_factor(&factor, cc);
    cholmod_free_sparse(&matrix, cc);
    if (spring == &own)
        sm_spring_free(&own);
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

void sm_place_vertex(sm_panel *p, int32_t v)
{
    if (p->vertex_placed[v])
        return;
    p->vertex_placed[v] = 1;
    p->placed_order[p->placed_count++] = v;
}

/* Marks face f flattened: its springs join the system. */
void sm_activate_face(sm_panel *p, int32_t f)
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
        sm_place_vertex(p, c[k]);
    }
    sm_activate_face(p, f);
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
    sm_place_vertex(p, v3);
}

static void push_neighbours(sm_panel *p, sm_heap *faces, int32_t f)
{
    for (int k = 0; k < 3; ++k) {
        int32_t twin = p->topology->twin[3 * f + k];
        if (twin >= 0 && !p->face_placed[pz_he_face(twin)])
            sm_heap_update(faces, pz_he_face(twin));
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
        sm_activate_face(p, f);
        for (int k = 0; k < 3; ++k)
            refresh_around(p, c[k]);
        return;
    }
    /* constrained: move the corner with the highest energy to its minimum, then release */
    sm_activate_face(p, f);
    int32_t worst = c[0];
    double worst_energy = -1;
    for (int k = 0; k < 3; ++k) {
        double e = sm_node_energy(p, c[k]);
        if (e > worst_energy) {
            worst_energy = e;
            worst = c[k];
        }
    }
    for (int step = 0; step < CONSTRAINED_STEPS; ++step) {
        relax_node(p, worst);
        double e = sm_node_energy(p, worst);
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
    if (!sm_heap_init(&faces, p->nf, p->medial)) {
        sm_heap_free(&faces);
        return pz_error(ctx, PZ_ERR_NOMEM, "springmass: out of memory");
    }
    lay_seed(p, seed);
    for (int k = 0; k < 3; ++k)
        refresh_around(p, p->mesh->faces[3 * seed + k]);
    push_neighbours(p, &faces, seed);
    int32_t flattened = 1;
    while (faces.count) {
        if ((flattened & 255) == 0 && pz_cancelled(ctx))
            break;
        int32_t f = sm_heap_pop(&faces);
        flatten_face(p, f);
        push_neighbours(p, &faces, f);
        ++flattened;
    }
    sm_heap_free(&faces);
    if (pz_cancelled(ctx))
        return pz_check_cancel(ctx, "springmass");
    if (flattened != p->nf || p->placed_count != p->nv)
        return pz_error(ctx, PZ_ERR_DATA, "springmass: a panel of %d faces is not edge-connected (%d reached from its seed)",
                        (int)p->nf, (int)flattened);
    return PZ_OK;
}


/* ------------------------------------------------------------------------ */
/* Driver                                                                    */
/* ------------------------------------------------------------------------ */


/* Phase two (wang2002 Sec. 5-6.2): the global release (isotropic), then the node sweeps. Also releases a
 * matched panel's interior against its pinned outline. */
pz_status sm_panel_release(sm_panel *p, sm_outcome *outcome, pz_ctx *ctx)
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
    return pz_check_cancel(ctx, "springmass");
}

/* Phase one and phase two of one disk mesh into uv (nv x 2), the state kept in p for seam matching and
 * panel_finish. */
pz_status sm_panel_flatten(sm_panel *p, const pz_mesh *mesh, const sm_settings *settings, double *uv,
                           sm_spring *spring, sm_outcome *outcome, pz_ctx *ctx)
{
    double start = pz_seconds();
    pz_status status = sm_panel_init(p, mesh, settings, uv, ctx);
    p->spring = spring;
    if (!status)
        status = phase_one(p, ctx);
    if (status)
        return status;
    outcome->phase_one_ms = 1e3 * (pz_seconds() - start);
    outcome->phase_one_relaxations = p->relaxations;
    outcome->phase_one_energy = sm_total_energy(p);
    start = pz_seconds();
    status = sm_panel_release(p, outcome, ctx);
    outcome->phase_two_ms = 1e3 * (pz_seconds() - start);
    return status;
}

/* The panel's last steps: folds untangled, its figures, energy map and cutting line (map and line may be
 * NULL). */
pz_status sm_panel_finish(sm_panel *p, sm_outcome *outcome, double *map, int32_t *line, int32_t *line_count,
                              pz_ctx *ctx)
{
    /* folds left by phase one (the shared mannequin: 76 faces, 35 after this): the
     * springs have no barrier, so unflip them geometrically (no flip added; a matched outline stays) */
    if (sm_flipped_faces(p) > 0 && pz_param_untangle(p->mesh, p->pinned, p->uv) < 0)
        return pz_error(ctx, PZ_ERR_NOMEM, "springmass: out of memory");
    /* slivers: edge lengths leave their apexes free (issue 17: strain 31,772); the pinned outline stays */
    if (pz_param_fit_slivers(p->mesh, p->pinned, p->uv) < 0)
        return pz_error(ctx, PZ_ERR_NOMEM, "springmass: out of memory");
    outcome->final_energy = sm_total_energy(p);
    sm_accuracy(p, &outcome->e_area, &outcome->e_shape);
    if (map)
        sm_energy_map(p, map);
    if (map && line)
        *line_count = sm_crest_line(p, map, line);
    outcome->relaxations = p->relaxations;
    outcome->evaluations = p->evaluations;
    return PZ_OK;
}

/* Flattens one disk mesh on its own into uv (nv x 2): the trial cut's re-flattening. */
pz_status sm_flatten_disk(const pz_mesh *mesh, const sm_settings *settings, double *uv, sm_outcome *outcome,
                              pz_ctx *ctx)
{
    sm_panel p;
    pz_status status = sm_panel_flatten(&p, mesh, settings, uv, NULL, outcome, ctx);
    if (!status)
        status = sm_panel_finish(&p, outcome, NULL, NULL, NULL, ctx);
    sm_panel_free(&p);
    return status;
}


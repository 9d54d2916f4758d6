/*
 * param/wirewarp_angles.c -- WireWarping's angle space (Eqs. 2-9, 13-24):
 * the wire-nodes' 2D angles closest to their surface angles under the
 * closure and compatibility constraints, by sequential linearly constrained
 * steps with J J^T factored by CHOLMOD (analyzed once per system, refactored
 * each step); the global and progressive schemes; key curves and their
 * relaxation. The method: param/wirewarp.c.
 *
 * SPDX-License-Identifier: GPL-3.0-or-later
 */
#include "param/wirewarp_internal.h"

#include <stdlib.h>
#include <string.h>

#define WW_EPS 1e-12               /* diagonal regularization of J J^T (rows are O(1)) */
#define WW_FEASIBLE 1e-12          /* scaled residual below which the constraints hold */
#define WW_KEY_WEIGHT 1e6          /* weight of a relaxed key angle's target against 1 for a free angle */
#define WW_RELAXED_ANGLE 1e-6      /* rad: a key curve whose angles moved more than this was relaxed */

/* ------------------------------------------------------------------------ */
/* Angle-space optimization (Eqs. 2-9, 13-24)                                */
/* ------------------------------------------------------------------------ */

typedef struct ww_angles {
    const ww_wires *w;
    const pz_mesh *mesh;
    double *theta;        /* per node */
    uint8_t *locked;      /* per node: angle fixed (key curve, Eq. 9, or already warped) */
    int32_t *column;      /* per node: column in the current system, -1 (scratch, kept -1) */
    int32_t *host_row;    /* per pattern vertex: compatibility row, -1 (scratch, kept -1) */
    uint8_t *in_set;      /* per patch: in the current system (scratch, kept 0) */
    double *phi, *suffix_sin, *suffix_cos;  /* per node */
    /* Relaxed key curves (relax_keys): their nodes are free but pulled to their fixed value (target) with
     * weight WW_KEY_WEIGHT; the columns of J are scaled by 1/sqrt(weight) (scale), see system_step. */
    double *target;       /* per node: alpha, or the key value for a relaxed key node */
    double *scale;        /* per node: 1, or 1/sqrt(WW_KEY_WEIGHT) for a relaxed key node */
    uint8_t *soft;        /* per node: a relaxed key node */
    int max_iterations;
    cholmod_common *cc;
    /* outcomes */
    int iterations;
    int32_t constraint_count;
    double residual;
} ww_angles;

/* Constraint residuals g and the Jacobian values of the patches in `set`. */
static void evaluate(ww_angles *a, const int32_t *set, int32_t set_count, int32_t host_row_count,
                     const int32_t *row_host, double *g, cholmod_sparse *J)
{
    const ww_wires *w = a->w;
    double *values = J ? J->x : NULL;
    const int32_t *colp = J ? J->p : NULL;
    for (int32_t k = 0; k < set_count; ++k) {
        int32_t p = set[k], first = w->patch_offsets[p], n = w->patch_offsets[p + 1] - first;
        double L = w->patch_perimeter[p], phi = 0, sum_theta = 0, cx = 0, cy = 0;
        for (int32_t b = 0; b < n; ++b) {
            phi = remainder(phi + WW_PI - a->theta[first + b], 2 * WW_PI);
            a->phi[first + b] = phi;
            sum_theta += a->theta[first + b];
        }
        double s = 0, c = 0;
        for (int32_t b = n - 1; b >= 0; --b) {
            double l = w->length[first + b] / L;
            s += l * sin(a->phi[first + b]);
            c += l * cos(a->phi[first + b]);
            a->suffix_sin[first + b] = s;
            a->suffix_cos[first + b] = c;
        }
        cx = c;
        cy = s;
        g[3 * k] = (n - 2) * WW_PI - sum_theta;
        g[3 * k + 1] = cx;
        g[3 * k + 2] = cy;
        if (!values)
            continue;
        for (int32_t b = 0; b < n; ++b) {
            int32_t col = a->column[first + b];
            if (col < 0)
                continue;
            double *x = values + colp[col];  /* rows 3k, 3k+1, 3k+2 come first in the column (Eqs. 17-19) */
            double s = a->scale[first + b];  /* the weighted objective's column scaling (system_step) */
            x[0] = -s;
            x[1] = s * a->suffix_sin[first + b];
            x[2] = -s * a->suffix_cos[first + b];
            if (colp[col + 1] - colp[col] == 4)
                x[3] = -s;     /* Eq. 16 */
        }
    }
    for (int32_t r = 0; r < host_row_count; ++r) {
        int32_t h = row_host[r];
        double sum = 0;
        for (int32_t i = w->host_offsets[h]; i < w->host_offsets[h + 1]; ++i)
            sum += a->theta[w->host_nodes[i]];
        g[3 * set_count + r] = 2 * WW_PI - sum;
    }
}

static double max_abs(const double *x, int32_t n)
{
    double m = 0;
    for (int32_t i = 0; i < n; ++i)
        m = fmax(m, fabs(x[i]));
    return m;
}

/* One constrained system: the free nodes (columns) and constraints (rows) of a set of patches. */
typedef struct ww_system {
    const int32_t *set;
    int32_t set_count;
    int32_t ncol, host_rows, nrow;
    int32_t *col_node;    /* column -> node */
    int32_t *row_host;    /* compatibility row -> host vertex */
    cholmod_sparse *J;    /* nrow x ncol, pattern fixed, values from evaluate() */
} ww_system;

/* Frees a system and resets the scratch marks it set. */
static void system_release(ww_angles *a, ww_system *sys)
{
    for (int32_t k = 0; k < sys->set_count; ++k)
        a->in_set[sys->set[k]] = 0;
    for (int32_t c = 0; c < sys->ncol; ++c)
        a->column[sys->col_node[c]] = -1;
    for (int32_t r = 0; r < sys->host_rows; ++r)
        a->host_row[sys->row_host[r]] = -1;
    cholmod_free_sparse(&sys->J, a->cc);
    free(sys->col_node);
    free(sys->row_host);
}

/* A compatibility row for interior host h when all its unlocked nodes lie in the set. */
static int wants_host_row(const ww_angles *a, int32_t h)
{
    const ww_wires *w = a->w;
    if (w->topo->vertex_on_boundary[h] || a->host_row[h] >= 0)
        return 0;
    for (int32_t j = w->host_offsets[h]; j < w->host_offsets[h + 1]; ++j) {
        int32_t q = w->host_nodes[j];
        if (!a->locked[q] && !a->in_set[w->node_patch[q]])
            return 0;
    }
    return 1;
}

/*
 * Columns, rows and the pattern of J: per column the 3 rows of its patch
 * (turning, closure x, closure y: Eq. 17), then its host's row (Eq. 16).
 */
static pz_status system_build(ww_angles *a, const int32_t *set, int32_t set_count, ww_system *sys, pz_ctx *ctx)
{
    const ww_wires *w = a->w;
    size_t col_cap = 0, row_cap = 0, nnz = 0;
    memset(sys, 0, sizeof *sys);
    sys->set = set;
    sys->set_count = set_count;
    for (int32_t k = 0; k < set_count; ++k)
        a->in_set[set[k]] = 1;
    for (int32_t k = 0; k < set_count; ++k)
        for (int32_t i = w->patch_offsets[set[k]]; i < w->patch_offsets[set[k] + 1]; ++i) {
            if (a->locked[i])
                continue;
            if (!pz_grow((void **)&sys->col_node, &col_cap, (size_t)sys->ncol + 1, sizeof(int32_t)))
                return pz_error(ctx, PZ_ERR_NOMEM, "wirewarp: out of memory");
            a->column[i] = sys->ncol;
            sys->col_node[sys->ncol++] = i;
            int32_t h = w->node_host[i];
            if (!wants_host_row(a, h))
                continue;
            if (!pz_grow((void **)&sys->row_host, &row_cap, (size_t)sys->host_rows + 1, sizeof(int32_t)))
                return pz_error(ctx, PZ_ERR_NOMEM, "wirewarp: out of memory");
            a->host_row[h] = sys->host_rows;
            sys->row_host[sys->host_rows++] = h;
        }
    sys->nrow = 3 * set_count + sys->host_rows;
    for (int32_t c = 0; c < sys->ncol; ++c)
        nnz += 3 + (a->host_row[w->node_host[sys->col_node[c]]] >= 0);
    sys->J = cholmod_allocate_sparse((size_t)sys->nrow, (size_t)sys->ncol, nnz + 1, 1, 1, 0, CHOLMOD_REAL, a->cc);
    if (!sys->J)
        return pz_error(ctx, PZ_ERR_NOMEM, "wirewarp: out of memory for %d constraints", (int)sys->nrow);
    int32_t *colp = sys->J->p, *rowi = sys->J->i, at = 0;
    for (int32_t c = 0, k = 0; c < sys->ncol; ++c) {
        int32_t node = sys->col_node[c];
        while (set[k] != w->node_patch[node])
            ++k; /* columns were created patch by patch in set order */
        colp[c] = at;
        rowi[at++] = 3 * k;
        rowi[at++] = 3 * k + 1;
        rowi[at++] = 3 * k + 2;
        int32_t hr = a->host_row[w->node_host[node]];
        if (hr >= 0)
            rowi[at++] = 3 * set_count + hr;
    }
    colp[sys->ncol] = at;
    return PZ_OK;
}

/*
 * One step from the residuals g: (J J^T + eps I) mu = J r + g, theta += r -
 * J^T mu, with r = target - theta (optimality) or 0 (feasibility). Returns the
 * squared step length, or -1 when CHOLMOD fails.
 * Weighted objective sum w (theta - target)^2 / 2 (relaxed key nodes): with
 * S = diag(1/sqrt(w)) and Js = J S (the values evaluate() wrote), the step is
 * (Js Js^T + eps I) mu = Js S^-1 r + g, delta = r - S Js^T mu; w = 1 gives
 * back Eqs. 23-24.
 */
static double system_step(ww_angles *a, const ww_system *sys, cholmod_factor *factor, const double *g,
                          int feasibility, double *r, cholmod_dense *rhs)
{
    double beta[2] = {WW_EPS, 0};
    if (!cholmod_factorize_p(sys->J, beta, NULL, 0, factor, a->cc) || a->cc->status < CHOLMOD_OK)
        return -1;
    const int32_t *colp = sys->J->p, *rowi = sys->J->i;
    const double *x = sys->J->x;
    double *b = rhs->x;
    memcpy(b, g, (size_t)sys->nrow * sizeof(double));
    for (int32_t c = 0; c < sys->ncol; ++c) {
        int32_t node = sys->col_node[c];
        r[c] = feasibility ? 0 : a->target[node] - a->theta[node];
        for (int32_t e = colp[c]; e < colp[c + 1]; ++e)
            b[rowi[e]] += x[e] * r[c] / a->scale[node];
    }
    cholmod_dense *mu = cholmod_solve(CHOLMOD_A, factor, rhs, a->cc);
    if (!mu)
        return -1;
    const double *m = mu->x;
    double step2 = 0;
    for (int32_t c = 0; c < sys->ncol; ++c) {
        double dot = 0;
        for (int32_t e = colp[c]; e < colp[c + 1]; ++e)
            dot += x[e] * m[rowi[e]];
        double d = r[c] - a->scale[sys->col_node[c]] * dot;
        a->theta[sys->col_node[c]] += d;
        step2 += d * d;
    }
    cholmod_free_dense(&mu, a->cc);
    return step2;
}

/*
 * Solves for the unlocked angles of the patches in `set` (Eq. 13 restricted
 * to them): optimality steps until the mean squared step is below 1e-16 (or
 * the iteration cap), then at most 20 feasibility steps until every scaled
 * residual is below WW_FEASIBLE. The factorization is analyzed once.
 */
static pz_status solve_set(ww_angles *a, const int32_t *set, int32_t set_count, pz_ctx *ctx)
{
    ww_system sys;
    pz_status status = system_build(a, set, set_count, &sys, ctx);
    cholmod_factor *factor = NULL;
    cholmod_dense *rhs = NULL;
    double *g = NULL, *r = NULL;
    if (status)
        goto done;
    a->constraint_count += sys.nrow;
    rhs = cholmod_zeros((size_t)sys.nrow, 1, CHOLMOD_REAL, a->cc);
    g = malloc((size_t)sys.nrow * sizeof(double) + 1);
    r = malloc((size_t)sys.ncol * sizeof(double) + 1);
    if (sys.ncol > 0 && rhs)
        factor = cholmod_analyze(sys.J, a->cc);
    if (!rhs || !g || !r || (sys.ncol > 0 && !factor)) {
        status = pz_error(ctx, PZ_ERR_NOMEM, "wirewarp: out of memory for %d constraints", (int)sys.nrow);
        goto done;
    }
    int feasibility = 0;
    for (int iter = 0; iter < a->max_iterations + 20; ++iter) {
        evaluate(a, set, set_count, sys.host_rows, sys.row_host, g, sys.J);
        if (sys.ncol == 0 || (feasibility && max_abs(g, sys.nrow) < WW_FEASIBLE) || feasibility > 20)
            break;
        double step2 = system_step(a, &sys, factor, g, feasibility, r, rhs);
        if (step2 < 0) {
            status = pz_error(ctx, PZ_ERR_INTERNAL, "wirewarp: CHOLMOD failed on %d constraints (status %d)",
                              (int)sys.nrow, a->cc->status);
            goto done;
        }
        ++a->iterations;
        if (feasibility)
            ++feasibility;
        else if (step2 / sys.ncol < 1e-16 || iter + 1 >= a->max_iterations)
            feasibility = 1; /* optimum reached (Algorithm 1's test, tighter): now polish the constraints */
    }
    for (int32_t c = 0; c < sys.ncol; ++c)
        if (!isfinite(a->theta[sys.col_node[c]]))
            a->residual = INFINITY;
    evaluate(a, set, set_count, sys.host_rows, sys.row_host, g, NULL);
    a->residual = fmax(a->residual, max_abs(g, sys.nrow));
done:
    cholmod_free_factor(&factor, a->cc);
    cholmod_free_dense(&rhs, a->cc);
    free(g);
    free(r);
    system_release(a, &sys);
    return status;
}

/*
 * Fixes key node q at `value`: locked (the paper), or, when its host is in
 * relax_host, a least-squares target of weight WW_KEY_WEIGHT (relax_keys).
 */
static void fix_key_node(ww_angles *a, int32_t q, double value, const uint8_t *relax_host)
{
    a->theta[q] = value;
    if (relax_host && relax_host[a->w->node_host[q]]) {
        a->target[q] = value;
        a->scale[q] = 1 / sqrt(WW_KEY_WEIGHT);
        a->soft[q] = 1;
    } else {
        a->locked[q] = 1;
    }
}

/*
 * A user-given 2D shape at interior host h (pz_feature_curve.turning): the
 * node whose patch lies left of the curve (its loop, material on the left,
 * runs prev -> h -> next) gets pi - turn, the one on the right pi + turn;
 * they sum to 2 pi (Eq. 13). Returns 0 (Eq. 1 is used) unless h has exactly
 * these two nodes.
 */
static int lock_given_turn(ww_angles *a, int32_t h, const uint8_t *relax_host)
{
    const ww_wires *w = a->w;
    if (isnan(w->key_turn[h]) || w->topo->vertex_on_boundary[h] || w->host_offsets[h + 1] - w->host_offsets[h] != 2)
        return 0;
    double theta[2];
    for (int j = 0; j < 2; ++j) {
        int32_t q = w->host_nodes[w->host_offsets[h] + j], p = w->node_patch[q];
        int32_t first = w->patch_offsets[p], n = w->patch_offsets[p + 1] - first, b = q - first;
        int32_t before = w->node_host[first + (b + n - 1) % n], after = w->node_host[first + (b + 1) % n];
        if (before == w->key_side[2 * h] && after == w->key_side[2 * h + 1])
            theta[j] = WW_PI - w->key_turn[h];
        else if (before == w->key_side[2 * h + 1] && after == w->key_side[2 * h])
            theta[j] = WW_PI + w->key_turn[h];
        else
            return 0;
    }
    for (int j = 0; j < 2; ++j)
        fix_key_node(a, w->host_nodes[w->host_offsets[h] + j], theta[j], relax_host);
    return 1;
}

/* Key-curve nodes: the user's turning angles where given, else Eq. 1 (the 3D
 * angle, scaled to 2 pi at interior vertices). Nodes of hosts in relax_host
 * (may be NULL) become weighted targets instead of locks. Returns the nodes locked. */
static int32_t lock_key_angles(ww_angles *a, const uint8_t *relax_host)
{
    const ww_wires *w = a->w;
    int32_t count = 0;
    for (int32_t h = 0; h < w->topo->vertex_count; ++h) {
        if (!w->key_vertex[h] || w->host_offsets[h] == w->host_offsets[h + 1])
            continue;
        int relaxed = relax_host && relax_host[h];
        if (lock_given_turn(a, h, relax_host)) {
            count += relaxed ? 0 : 2;
            continue;
        }
        double sum = 0;
        for (int32_t j = w->host_offsets[h]; j < w->host_offsets[h + 1]; ++j)
            sum += w->alpha[w->host_nodes[j]];
        for (int32_t j = w->host_offsets[h]; j < w->host_offsets[h + 1]; ++j) {
            int32_t q = w->host_nodes[j];
            fix_key_node(a, q, w->topo->vertex_on_boundary[h] ? w->alpha[q] : 2 * WW_PI * w->alpha[q] / sum,
                         relax_host);
            count += !relaxed;
        }
    }
    return count;
}

/* ----- progressive scheme: a max-heap of patches keyed by Eq. 10 ----- */

static double shape_evidence(const ww_angles *a, int32_t p)
{
    const ww_wires *w = a->w;
    int32_t known = 0, n = w->patch_offsets[p + 1] - w->patch_offsets[p];
    for (int32_t i = w->patch_offsets[p]; i < w->patch_offsets[p + 1]; ++i)
        known += a->locked[i] || a->soft[i];  /* a relaxed key angle is still shape evidence */
    return (double)known / n;
}

/* Eq. 9 at host h: the one node whose angle is unknown gets 2 pi minus the others. Returns its patch or -1. */
static int32_t lock_compatible(ww_angles *a, int32_t h)
{
    const ww_wires *w = a->w;
    if (w->topo->vertex_on_boundary[h])
        return -1;
    int32_t unknown = -1, unknown_count = 0;
    double sum = 0;
    for (int32_t j = w->host_offsets[h]; j < w->host_offsets[h + 1]; ++j) {
        int32_t q = w->host_nodes[j];
        if (a->locked[q])
            sum += a->theta[q];
        else {
            unknown = q;
            ++unknown_count;
        }
    }
    if (unknown_count != 1)
        return -1;
    a->theta[unknown] = 2 * WW_PI - sum;
    a->locked[unknown] = 1;
    return w->node_patch[unknown];
}

static pz_status progressive(ww_angles *a, int32_t *locked_count, pz_ctx *ctx)
{
    const ww_wires *w = a->w;
    int32_t m = w->patch_count, size = 0;
    size_t capacity = 0;
    ww_heap_entry *heap = NULL;
    uint8_t *done = calloc((size_t)m + 1, 1);
    double *key = malloc((size_t)m * sizeof(double) + 1);
    pz_status status = PZ_OK;
    if (!done || !key)
        goto nomem;
    for (int32_t h = 0; h < w->topo->vertex_count; ++h)
        *locked_count += lock_compatible(a, h) >= 0;
    for (int32_t p = 0; p < m; ++p)
        if (!ww_heap_push(&heap, &capacity, &size, key[p] = shape_evidence(a, p), p))
            goto nomem;
    while (size > 0) {
        ww_heap_entry top = ww_heap_pop(heap, &size);
        if (done[top.patch] || top.key != key[top.patch])
            continue; /* stale entry: the patch was re-keyed */
        int32_t p = top.patch;
        if ((status = solve_set(a, &p, 1, ctx)))
            break;
        done[p] = 1;
        for (int32_t i = w->patch_offsets[p]; i < w->patch_offsets[p + 1]; ++i)
            a->locked[i] = 1;
        for (int32_t i = w->patch_offsets[p]; i < w->patch_offsets[p + 1]; ++i) {
            int32_t h = w->node_host[i];
            int32_t q = lock_compatible(a, h);
            *locked_count += q >= 0;
            for (int32_t j = w->host_offsets[h]; j < w->host_offsets[h + 1]; ++j) {
                int32_t r = w->node_patch[w->host_nodes[j]];
                if (done[r])
                    continue;
                double k = shape_evidence(a, r);
                if (k != key[r] && !ww_heap_push(&heap, &capacity, &size, key[r] = k, r))
                    goto nomem;
            }
        }
    }
    free(heap);
    free(done);
    free(key);
    return status;
nomem:
    free(heap);
    free(done);
    free(key);
    return pz_error(ctx, PZ_ERR_NOMEM, "wirewarp: out of memory");
}



/*
 * The start: alpha shifted evenly over each patch's free nodes so the loop
 * turns by exactly 2 pi (the minimizer under the first constraint of Eq. 2
 * alone). The paper starts at theta = alpha; on a patch bounded by a
 * geodesic (alpha = pi everywhere, a hemisphere's equator) that start is a
 * straight line, where the closure Jacobian loses rank and the iteration can
 * wander into a self-crossing loop; this start is the regular polygon there.
 * A patch whose free nodes are all relaxed key nodes shifts those.
 */
static void start_on_turning(const ww_wires *w, const uint8_t *locked, const uint8_t *soft, double *theta)
{
    for (int32_t p = 0; p < w->patch_count; ++p) {
        int32_t first = w->patch_offsets[p], n = w->patch_offsets[p + 1] - first, free_count = 0, soft_count = 0;
        double deficit = (n - 2) * WW_PI;
        for (int32_t i = first; i < first + n; ++i) {
            deficit -= theta[i];
            free_count += !locked[i] && !soft[i];
            soft_count += !locked[i] && soft[i];
        }
        int use_soft = free_count == 0;
        int32_t count = use_soft ? soft_count : free_count;
        for (int32_t i = first; count > 0 && i < first + n; ++i)
            if (!locked[i] && (soft[i] != 0) == use_soft)
                theta[i] += deficit / count;
    }
}

/* One solve of all the angles from scratch; key nodes of hosts in relax_host (may be NULL) are targets. */
static pz_status angles_pass(ww_angles *a, const pz_wirewarp_options *options, const uint8_t *relax_host,
                             int32_t *all, int32_t *locked_count, pz_ctx *ctx)
{
    const ww_wires *w = a->w;
    for (int32_t i = 0; i < w->node_count; ++i) {
        a->theta[i] = a->target[i] = w->alpha[i];  /* the paper's start: theta = alpha */
        a->scale[i] = 1;
        a->soft[i] = a->locked[i] = 0;
    }
    a->residual = 0;
    a->constraint_count = 0;
    *locked_count = lock_key_angles(a, relax_host);
    start_on_turning(w, a->locked, a->soft, a->theta);
    if (options && options->scheme == 1)
        return progressive(a, locked_count, ctx);
    for (int32_t p = 0; p < w->patch_count; ++p)
        all[p] = p;
    return solve_set(a, all, w->patch_count, ctx);
}

/* Per feature curve, the largest change of its relaxed key angles from their fixed values (0: none). */
static void key_curve_changes(const ww_angles *a, const pz_feature_curves *features, double *change)
{
    const ww_wires *w = a->w;
    for (int32_t c = 0; c < features->curve_count; ++c) {
        const pz_feature_curve *curve = &features->curves[c];
        change[c] = 0;
        for (int32_t i = 0; curve->kind == PZ_FEATURE_KEY && i < curve->vertex_count; ++i) {
            int32_t h = curve->vertices[i];
            for (int32_t j = w->host_offsets[h]; j < w->host_offsets[h + 1]; ++j) {
                int32_t q = w->host_nodes[j];
                if (a->soft[q])
                    change[c] = fmax(change[c], fabs(a->theta[q] - a->target[q]));
            }
        }
    }
}

/* The relaxed curves of `change` into the result, as indices of the caller's curves (origin, may be NULL). */
static void record_relaxed(const pz_feature_curves *features, const int32_t *origin, const double *change,
                           pz_wirewarp_result *r)
{
    r->relaxed_key_curve_count = 0;
    r->relaxed_key_angle = 0;
    for (int32_t c = 0; c < features->curve_count; ++c) {
        if (!(change[c] > WW_RELAXED_ANGLE))
            continue;
        if (r->relaxed_key_curve_count < PZ_WIREWARP_RELAXED_MAX)
            r->relaxed_key_curves[r->relaxed_key_curve_count] = origin ? origin[c] : c;
        ++r->relaxed_key_curve_count;
        r->relaxed_key_angle = fmax(r->relaxed_key_angle, change[c]);
    }
}

/*
 * Over-constraining key curves (paper Figs. 13-14: the patches cannot close
 * with all key angles fixed). The paper's advice is to release the key
 * curves that conflict into accessory ones; done automatically here in the
 * least-squares sense: (1) every key angle becomes a target of weight
 * WW_KEY_WEIGHT (free angles weigh 1), so the misclosure is spread over the
 * key angles that must give, evenly where they all weigh the same (a whole
 * boundary given as a key curve), and every wire keeps its length; (2) the
 * key curves that did not move (by WW_RELAXED_ANGLE, or by a thousandth of
 * the largest move) are fixed again and the rest solved once more, kept
 * when it closes as well as (1). Without
 * this, the locked loop was drawn open and its closing edge took the whole
 * gap (55 times its length on a 2K quarter-sphere).
 */
static pz_status relax_keys(ww_angles *a, const pz_wirewarp_options *options, const pz_feature_curves *features,
                            const int32_t *origin, int32_t *all, pz_wirewarp_result *r, pz_ctx *ctx)
{
    const ww_wires *w = a->w;
    int32_t nv = w->topo->vertex_count, nn = w->node_count, count = features->curve_count;
    uint8_t *relax_host = malloc((size_t)nv + 1);
    double *change = malloc((size_t)count * sizeof(double) + 1);
    double *kept = malloc((size_t)nn * sizeof(double) + 1);
    pz_status status = PZ_OK;
    if (!relax_host || !change || !kept) {
        status = pz_error(ctx, PZ_ERR_NOMEM, "wirewarp: out of memory");
        goto done;
    }
    memcpy(relax_host, w->key_vertex, (size_t)nv);
    if ((status = angles_pass(a, options, relax_host, all, &r->locked_count, ctx)))
        goto done;
    key_curve_changes(a, features, change);
    record_relaxed(features, origin, change, r);
    memcpy(kept, a->theta, (size_t)nn * sizeof(double));
    double kept_residual = a->residual;
    int32_t kept_locked = r->locked_count, kept_constraints = a->constraint_count, fixed_again = 0;
    /* A curve that only gave a thousandth of what the conflicting ones gave is fixed again too: with a
     * large misclosure, the 1/weight share a compatible curve takes can exceed WW_RELAXED_ANGLE. */
    double moved = WW_RELAXED_ANGLE;
    for (int32_t c = 0; c < count; ++c)
        moved = fmax(moved, 1e-3 * change[c]);
    memset(relax_host, 0, (size_t)nv);
    for (int32_t c = 0; c < count; ++c) {
        const pz_feature_curve *curve = &features->curves[c];
        if (curve->kind != PZ_FEATURE_KEY)
            continue;
        fixed_again += !(change[c] > moved);
        for (int32_t i = 0; change[c] > moved && i < curve->vertex_count; ++i)
            relax_host[curve->vertices[i]] = 1;
    }
    if (fixed_again == 0 || r->relaxed_key_curve_count == 0)
        goto done;
    if ((status = angles_pass(a, options, relax_host, all, &r->locked_count, ctx)))
        goto done;
    if (a->residual <= fmax(WW_BEST_EFFORT, kept_residual)) {
        key_curve_changes(a, features, change);
        record_relaxed(features, origin, change, r);
    } else { /* fixing them again reopened a patch: keep (1) */
        memcpy(a->theta, kept, (size_t)nn * sizeof(double));
        a->residual = kept_residual;
        a->constraint_count = kept_constraints;
        r->locked_count = kept_locked;
    }
done:
    free(relax_host);
    free(change);
    free(kept);
    return status;
}

pz_status ww_warp_angles(const pz_pattern *pattern, const ww_wires *w, const pz_wirewarp_options *options,
                             const pz_feature_curves *features, const int32_t *origin, double *theta,
                             pz_wirewarp_result *r, pz_ctx *ctx)
{
    int32_t nn = w->node_count, m = w->patch_count;
    ww_angles a = {.w = w, .mesh = pattern->mesh, .theta = theta,
                   .max_iterations = options && options->max_iterations > 0 ? options->max_iterations : 100};
    a.locked = calloc((size_t)nn + 1, 1);
    a.column = malloc((size_t)nn * sizeof(int32_t) + 1);
    a.host_row = malloc((size_t)pattern->mesh->vertex_count * sizeof(int32_t) + 1);
    a.in_set = calloc((size_t)m + 1, 1);
    a.phi = malloc((size_t)nn * sizeof(double) + 1);
    a.suffix_sin = malloc((size_t)nn * sizeof(double) + 1);
    a.suffix_cos = malloc((size_t)nn * sizeof(double) + 1);
    a.target = malloc((size_t)nn * sizeof(double) + 1);
    a.scale = malloc((size_t)nn * sizeof(double) + 1);
    a.soft = calloc((size_t)nn + 1, 1);
    int32_t *all = malloc((size_t)m * sizeof(int32_t) + 1);
    cholmod_common cc;
    cholmod_start(&cc);
    cc.supernodal = CHOLMOD_SIMPLICIAL;
    cc.print = 0; /* failures are reported through ctx or result->best_effort */
    a.cc = &cc;
    pz_status status = PZ_OK;
    if (!a.locked || !a.column || !a.host_row || !a.in_set || !a.phi || !a.suffix_sin || !a.suffix_cos || !a.target ||
        !a.scale || !a.soft || !all) {
        status = pz_error(ctx, PZ_ERR_NOMEM, "wirewarp: out of memory for %d wire-nodes", (int)nn);
        goto done;
    }
    for (int32_t i = 0; i < nn; ++i)
        a.column[i] = -1;
    for (int32_t v = 0; v < pattern->mesh->vertex_count; ++v)
        a.host_row[v] = -1;
    if ((status = angles_pass(&a, options, NULL, all, &r->locked_count, ctx)))
        goto done;
    int any_key = 0;
    for (int32_t c = 0; features && c < features->curve_count; ++c)
        any_key |= features->curves[c].kind == PZ_FEATURE_KEY;
    if (!(a.residual <= WW_BEST_EFFORT) && any_key)
        status = relax_keys(&a, options, features, origin, all, r, ctx);
    r->iterations = a.iterations;
    r->constraint_count = a.constraint_count;
    r->constraint_residual = a.residual;
    r->best_effort = !(a.residual <= WW_BEST_EFFORT) || r->relaxed_key_curve_count > 0;
    if (r->best_effort)
        for (int32_t i = 0; i < nn; ++i)
            if (!isfinite(theta[i]))
                theta[i] = w->alpha[i];
done:
    cholmod_finish(&cc);
    free(a.locked);
    free(a.column);
    free(a.host_row);
    free(a.in_set);
    free(a.phi);
    free(a.suffix_sin);
    free(a.suffix_cos);
    free(a.target);
    free(a.scale);
    free(a.soft);
    free(all);
    return status;
}


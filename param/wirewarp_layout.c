/*
 * param/wirewarp_layout.c -- WireWarping in the plane: the wires walked out
 * patch by patch from their angles (Sec. 3.3), the interior vertices by the
 * Laplacian-like system of Eq. 11 with the wires fixed (CHOLMOD; its
 * symbolic analysis kept in a ww_interior for the next solve with the same
 * wires) or the relaxed Gauss-Seidel of Eq. 12, the wire length figures,
 * the turn that puts the grain along +v, and the untangling of flipped
 * faces (pz_param_untangle, also used by the spring-mass back-end). The
 * method: param/wirewarp.c.
 *
 * SPDX-License-Identifier: GPL-3.0-or-later
 */
#include "param/wirewarp_internal.h"

#include <stdlib.h>
#include <string.h>

/* ------------------------------------------------------------------------ */
/* Layout of the wires (Sec. 3.3) and of the interior (Eq. 11)               */
/* ------------------------------------------------------------------------ */

/*
 * Where the walk puts the node after node i of a patch (first: its first
 * node, n nodes): from the edge prev -> i, turned by pi - theta_i, at the 3D
 * length of edge i (Eq. 8).
 */
static void walk_step(const ww_wires *w, const double *theta, int32_t first, int32_t n, int32_t i, const double *uv,
                      double out[2])
{
    const int32_t *host = w->node_host + first;
    int32_t prev = (i + n - 1) % n;
    const double *pi = uv + 2 * host[i], *pp = uv + 2 * host[prev];
    double dx = pi[0] - pp[0], dy = pi[1] - pp[1], norm = hypot(dx, dy);
    double turn = WW_PI - theta[first + i], c = cos(turn), sn = sin(turn);
    double l = w->length[first + i] / (norm > 0 ? norm : 1);
    out[0] = pi[0] + l * (c * dx - sn * dy);
    out[1] = pi[1] + l * (sn * dx + c * dy);
}

/*
 * Walks patch p from a pair of consecutive placed nodes, placing the rest by
 * Eq. 8. A run of newly placed nodes ends at a node placed before; when the
 * angles do not close the loop exactly (a best-effort residual), the walk
 * misses that node by a gap, which is spread over the run in proportion to
 * arc length instead of being left to the closing edge (which stretched to
 * 55 times its length on an over-constrained quarter-sphere). With the
 * constraints met the gap is round-off.
 */
static int walk_patch(const ww_wires *w, const double *theta, int32_t p, uint8_t *placed, double *uv, int32_t *run)
{
    int32_t first = w->patch_offsets[p], n = w->patch_offsets[p + 1] - first, s = -1, run_count = 0;
    const int32_t *host = w->node_host + first;
    for (int32_t b = 0; b < n && s < 0; ++b)
        if (placed[host[b]] && placed[host[(b + 1) % n]] && host[b] != host[(b + 1) % n])
            s = (b + 1) % n;
    if (s < 0)
        return 0;
    double arc = 0;
    for (int32_t k = 0; k < n - 1; ++k) {
        int32_t i = (s + k) % n, next = (i + 1) % n;
        double at[2];
        walk_step(w, theta, first, n, i, uv, at);
        arc += w->length[first + i];
        if (!placed[host[next]]) {
            uv[2 * host[next]] = at[0];
            uv[2 * host[next] + 1] = at[1];
            placed[host[next]] = 1;
            run[run_count++] = next;
            continue;
        }
        /* next was placed before: spread the miss over the run that leads to it */
        double gap[2] = {at[0] - uv[2 * host[next]], at[1] - uv[2 * host[next] + 1]}, along = 0;
        for (int32_t j = 0; j < run_count && arc > 0; ++j) {
            int32_t q = run[j];
            along += w->length[first + (q + n - 1) % n];
            uv[2 * host[q]] -= gap[0] * along / arc;
            uv[2 * host[q] + 1] -= gap[1] * along / arc;
        }
        run_count = 0;
        arc = 0;
    }
    return 1;
}

/* Places every wire-node's host vertex, patches in propagation order. */
pz_status ww_layout_wires(const ww_wires *w, const double *theta, uint8_t *placed, double *uv, pz_ctx *ctx)
{
    int32_t m = w->patch_count, ne = w->topo->edge_count;
    int32_t *edge_patch = malloc((size_t)ne * 2 * sizeof(int32_t) + 1);
    int32_t *queue = malloc((size_t)m * sizeof(int32_t) + 1);
    int32_t *run = malloc((size_t)w->node_count * sizeof(int32_t) + 1);
    uint8_t *seen = calloc((size_t)m + 1, 1);
    pz_status status = PZ_OK;
    if (!edge_patch || !queue || !run || !seen) {
        status = pz_error(ctx, PZ_ERR_NOMEM, "wirewarp: out of memory");
        goto done;
    }
    for (int32_t e = 0; e < 2 * ne; ++e)
        edge_patch[e] = -1;
    for (int32_t p = 0; p < m; ++p) {
        int32_t first = w->patch_offsets[p], n = w->patch_offsets[p + 1] - first;
        for (int32_t b = 0; b < n; ++b) {
            int32_t e = ww_find_edge(w->keys, ne, w->node_host[first + b], w->node_host[first + (b + 1) % n]);
            if (e >= 0)
                edge_patch[2 * e + (edge_patch[2 * e] >= 0)] = p;
        }
    }
    for (int32_t seed = 0; seed < m; ++seed) {
        if (seen[seed])
            continue;
        /* The first patch of a panel: fix two neighbouring nodes at their distance. */
        int32_t first = w->patch_offsets[seed], head = 0, tail = 0;
        int32_t a = w->node_host[first], b = w->node_host[first + 1];
        uv[2 * a] = uv[2 * a + 1] = 0;
        uv[2 * b] = w->length[first];
        uv[2 * b + 1] = 0;
        placed[a] = placed[b] = 1;
        seen[seed] = 1;
        queue[tail++] = seed;
        while (head < tail) {
            int32_t p = queue[head++];
            if (!walk_patch(w, theta, p, placed, uv, run)) {
                status = pz_error(ctx, PZ_ERR_INTERNAL, "wirewarp: wire-patch %d could not be placed", p);
                goto done;
            }
            int32_t f0 = w->patch_offsets[p], n = w->patch_offsets[p + 1] - f0;
            for (int32_t k = 0; k < n; ++k) {
                int32_t e = ww_find_edge(w->keys, ne, w->node_host[f0 + k], w->node_host[f0 + (k + 1) % n]);
                for (int s = 0; e >= 0 && s < 2; ++s) {
                    int32_t r = edge_patch[2 * e + s];
                    if (r >= 0 && !seen[r]) {
                        seen[r] = 1;
                        queue[tail++] = r;
                    }
                }
            }
        }
    }
done:
    free(edge_patch);
    free(queue);
    free(run);
    free(seen);
    return status;
}

/* Eq. 12: relaxed Gauss-Seidel with 1/length weights (the fallback). */
static void gauss_seidel(const pz_mesh *mesh, const pz_topology *t, const uint8_t *placed, double *uv)
{
    int32_t nv = mesh->vertex_count;
    double cx = 0, cy = 0;
    int32_t count = 0;
    for (int32_t v = 0; v < nv; ++v)
        if (placed[v]) {
            cx += uv[2 * v];
            cy += uv[2 * v + 1];
            ++count;
        }
    for (int32_t v = 0; v < nv; ++v)
        if (!placed[v]) {
            uv[2 * v] = count ? cx / count : 0;
            uv[2 * v + 1] = count ? cy / count : 0;
        }
    int32_t ring_cap = 64, *ring = malloc((size_t)ring_cap * sizeof(int32_t));
    if (!ring)
        return;
    for (int iter = 0; iter < 10000; ++iter) {
        double moved = 0;
        for (int32_t v = 0; v < nv; ++v) {
            if (placed[v])
                continue;
            int32_t n = pz_topology_vertex_ring(t, v, ring, ring_cap);
            if (n > ring_cap) {
                int32_t *bigger = realloc(ring, (size_t)n * sizeof(int32_t));
                if (!bigger)
                    break;
                ring = bigger;
                ring_cap = n;
                n = pz_topology_vertex_ring(t, v, ring, ring_cap);
            }
            double sw = 0, sx = 0, sy = 0;
            for (int32_t k = 0; k < n; ++k) {
                double wk = 1 / fmax(ww_distance3(mesh->positions + 3 * v, mesh->positions + 3 * ring[k]), 1e-300);
                sw += wk;
                sx += wk * uv[2 * ring[k]];
                sy += wk * uv[2 * ring[k] + 1];
            }
            if (sw <= 0)
                continue;
            double dx = 1.5 * (sx / sw - uv[2 * v]), dy = 1.5 * (sy / sw - uv[2 * v + 1]);
            uv[2 * v] += dx;
            uv[2 * v + 1] += dy;
            moved = fmax(moved, hypot(dx, dy));
        }
        if (moved < 1e-5)
            break;
    }
    free(ring);
}

/* The interior's CHOLMOD workspace, started on first use. */
static cholmod_common *interior_common(ww_interior *interior)
{
    if (!interior->started) {
        cholmod_start(&interior->common);
        interior->common.supernodal = CHOLMOD_SIMPLICIAL;
        interior->common.print = 0; /* a failed factorization falls back to Gauss-Seidel (Eq. 12) */
        interior->started = 1;
    }
    return &interior->common;
}

void ww_interior_free(ww_interior *interior)
{
    if (interior->started) {
        cholmod_free_factor(&interior->symbolic, &interior->common);
        cholmod_finish(&interior->common);
    }
    free(interior->placed);
    memset(interior, 0, sizeof *interior);
}

/* A factor of the interior matrix ready for its numeric factorization: a copy
 * of the kept symbolic analysis when it was made for the same wires, else a
 * new analysis, kept. NULL when out of memory (common->status). */
static cholmod_factor *interior_factor(ww_interior *interior, cholmod_sparse *matrix, const uint8_t *placed,
                                       int32_t vertex_count)
{
    cholmod_common *cc = &interior->common;
    if (!interior->symbolic || !interior->placed || interior->vertex_count != vertex_count ||
        memcmp(interior->placed, placed, (size_t)vertex_count)) {
        cholmod_free_factor(&interior->symbolic, cc);
        free(interior->placed);
        interior->placed = malloc((size_t)vertex_count + 1);
        interior->vertex_count = vertex_count;
        if (interior->placed)
            memcpy(interior->placed, placed, (size_t)vertex_count);
        interior->symbolic = cholmod_analyze(matrix, cc);
        if (!interior->symbolic)
            return NULL;
    }
    return cholmod_copy_factor(interior->symbolic, cc);
}

/*
 * Interior vertices: sum_j w_ij (x_i - x_j) = 0 with the wires fixed (Eq. 11), one CHOLMOD solve.
 * mode: options->interior (0 cotangent weights, 1 the paper's 1/length weights, 2 the paper's relaxed
 * Gauss-Seidel, Eq. 12, which is otherwise the fallback when the factorization fails).
 */
pz_status ww_layout_interior(const pz_mesh *mesh, const pz_topology *t, int mode, const uint8_t *placed, double *uv,
                             int *fallback, ww_interior *interior, pz_ctx *ctx)
{
    int paper_weights = mode >= 1;
    int32_t nv = mesh->vertex_count, ne = t->edge_count, n = 0;
    int32_t *index = malloc((size_t)nv * sizeof(int32_t) + 1);
    double *weight = malloc((size_t)ne * sizeof(double) + 1);
    if (!index || !weight) {
        free(index);
        free(weight);
        return pz_error(ctx, PZ_ERR_NOMEM, "wirewarp: out of memory");
    }
    for (int32_t v = 0; v < nv; ++v)
        index[v] = placed[v] ? -1 : n++;
    if (n == 0 || mode == 2) {
        if (n > 0) {
            *fallback = 1;
            gauss_seidel(mesh, t, placed, uv);
        }
        free(index);
        free(weight);
        return PZ_OK;
    }
    if (paper_weights)
        for (int32_t e = 0; e < ne; ++e) {
            int32_t h = t->edge_halfedge[2 * e];
            weight[e] = 1 / fmax(ww_distance3(mesh->positions + 3 * pz_he_from(t, h), mesh->positions + 3 * pz_he_to(t, h)),
                                 1e-300);
        }
    else
        pz_geom_cotan_weights(mesh, t, weight);
    cholmod_common *cc = interior_common(interior);
    cholmod_triplet *triplet = cholmod_allocate_triplet((size_t)n, (size_t)n, (size_t)(n + ne), -1, CHOLMOD_REAL, cc);
    cholmod_dense *rhs = cholmod_zeros((size_t)n, 2, CHOLMOD_REAL, cc);
    cholmod_sparse *matrix = NULL;
    cholmod_factor *factor = NULL;
    cholmod_dense *x = NULL;
    pz_status status = PZ_OK;
    if (!triplet || !rhs) {
        status = pz_error(ctx, PZ_ERR_NOMEM, "wirewarp: out of memory for %d interior vertices", (int)n);
        goto done;
    }
    int32_t *ti = triplet->i, *tj = triplet->j;
    double *tx = triplet->x, *b = rhs->x;
    size_t at = 0;
    for (int32_t v = 0; v < nv; ++v)
        if (index[v] >= 0) {
            ti[at] = tj[at] = index[v];
            tx[at++] = 0;
        }
    double *diag = tx;  /* the first n entries are the diagonal, in index order */
    for (int32_t e = 0; e < ne; ++e) {
        int32_t h = t->edge_halfedge[2 * e], a = pz_he_from(t, h), c = pz_he_to(t, h);
        int32_t ia = index[a], ic = index[c];
        double we = weight[e];
        if (ia >= 0)
            diag[ia] += we;
        if (ic >= 0)
            diag[ic] += we;
        if (ia >= 0 && ic >= 0) {
            ti[at] = ia > ic ? ia : ic;
            tj[at] = ia > ic ? ic : ia;
            tx[at++] = -we;
        } else if (ia >= 0 || ic >= 0) {
            int32_t free_row = ia >= 0 ? ia : ic, fixed = ia >= 0 ? c : a;
            b[free_row] += we * uv[2 * fixed];
            b[n + free_row] += we * uv[2 * fixed + 1];
        }
    }
    triplet->nnz = at;
    matrix = cholmod_triplet_to_sparse(triplet, at, cc);
    if (matrix)
        factor = interior_factor(interior, matrix, placed, nv);
    if (factor)
        cholmod_factorize(matrix, factor, cc);
    if (factor && cc->status == CHOLMOD_OK)
        x = cholmod_solve(CHOLMOD_A, factor, rhs, cc);
    if (x && cc->status == CHOLMOD_OK) {
        const double *s = x->x;
        for (int32_t v = 0; v < nv; ++v)
            if (index[v] >= 0) {
                uv[2 * v] = s[index[v]];
                uv[2 * v + 1] = s[n + index[v]];
            }
    } else if (cc->status == CHOLMOD_OUT_OF_MEMORY) {
        status = pz_error(ctx, PZ_ERR_NOMEM, "wirewarp: out of memory in the interior solve");
    } else {
        *fallback = 1;  /* not positive definite (degenerate faces): the paper's iteration */
        gauss_seidel(mesh, t, placed, uv);
    }
done:
    cholmod_free_dense(&x, cc);
    cholmod_free_factor(&factor, cc);
    cholmod_free_sparse(&matrix, cc);
    cholmod_free_dense(&rhs, cc);
    cholmod_free_triplet(&triplet, cc);
    free(index);
    free(weight);
    return status;
}

/* Eq. 26 over the wire edges, and the worst relative error. */
void ww_wire_length_error(const pz_mesh *mesh, const ww_wires *w, const double *uv, pz_wirewarp_result *r)
{
    const pz_topology *t = w->topo;
    double sum = 0, worst = 0;
    int32_t count = 0;
    for (int32_t e = 0; e < t->edge_count; ++e) {
        if (!w->wire_edge[e])
            continue;
        int32_t h = t->edge_halfedge[2 * e], a = pz_he_from(t, h), b = pz_he_to(t, h);
        double l3 = ww_distance3(mesh->positions + 3 * a, mesh->positions + 3 * b);
        double l2 = hypot(uv[2 * a] - uv[2 * b], uv[2 * a + 1] - uv[2 * b + 1]);
        double error = l3 > 0 ? fabs(l2 - l3) / l3 : fabs(l2);
        sum += error;
        worst = fmax(worst, error);
        ++count;
    }
    r->wire_edge_count = count;
    r->e_len_wires = count ? sum / count : 0;
    r->max_wire_error = worst;
}



/*
 * Turns every piece about its centroid so that the 3D grain axis, projected
 * onto the faces and mapped into the plane, runs along +v on average
 * (area-weighted), as pz_param_lscm does: the warp/weft strains and the
 * orthotropic energy of the metrics are measured along u and v.
 */
pz_status ww_orient_to_grain(const pz_pattern *pattern, const double grain[3], double *uv, pz_ctx *ctx)
{
    const pz_mesh *mesh = pattern->mesh;
    int32_t np = pattern->panel_count;
    double *sums = calloc((size_t)np * 5 + 1, sizeof(double)); /* grain image x y, centroid x y, count */
    uint8_t *seen = calloc((size_t)mesh->vertex_count + 1, 1);
    if (!sums || !seen) {
        free(sums);
        free(seen);
        return pz_error(ctx, PZ_ERR_NOMEM, "wirewarp: out of memory");
    }
    for (int32_t f = 0; f < mesh->face_count; ++f) {
        const int32_t *c = mesh->faces + 3 * f;
        double *s = sums + 5 * pattern->face_panel[f];
        const double *p0 = mesh->positions + 3 * c[0], *p1 = mesh->positions + 3 * c[1], *p2 = mesh->positions + 3 * c[2];
        double e1[3] = {p1[0] - p0[0], p1[1] - p0[1], p1[2] - p0[2]}, e2[3] = {p2[0] - p0[0], p2[1] - p0[1], p2[2] - p0[2]};
        double a11 = e1[0] * e1[0] + e1[1] * e1[1] + e1[2] * e1[2], a22 = e2[0] * e2[0] + e2[1] * e2[1] + e2[2] * e2[2];
        double a12 = e1[0] * e2[0] + e1[1] * e2[1] + e1[2] * e2[2];
        double g1 = grain[0] * e1[0] + grain[1] * e1[1] + grain[2] * e1[2];
        double g2 = grain[0] * e2[0] + grain[1] * e2[1] + grain[2] * e2[2];
        double det = a11 * a22 - a12 * a12;
        if (!(det > 0))
            continue;
        /* The grain's tangential part as a e1 + b e2; its 2D image a q1 + b q2, weighted by area. */
        double a = (a22 * g1 - a12 * g2) / det, b = (a11 * g2 - a12 * g1) / det, area = 0.5 * sqrt(det);
        for (int k = 0; k < 2; ++k)
            s[k] += area * (a * (uv[2 * c[1] + k] - uv[2 * c[0] + k]) + b * (uv[2 * c[2] + k] - uv[2 * c[0] + k]));
        for (int k = 0; k < 3; ++k)
            if (!seen[c[k]]) {
                seen[c[k]] = 1;
                s[2] += uv[2 * c[k]];
                s[3] += uv[2 * c[k] + 1];
                s[4] += 1;
            }
    }
    for (int32_t p = 0; p < np; ++p) {
        double *s = sums + 5 * p;
        if (hypot(s[0], s[1]) > 0 && s[4] > 0) {
            double turn = WW_PI / 2 - atan2(s[1], s[0]);
            s[0] = cos(turn);
            s[1] = sin(turn);
            s[2] /= s[4];
            s[3] /= s[4];
        } else {
            s[0] = 1;
            s[1] = s[2] = s[3] = 0;
        }
    }
    memset(seen, 0, (size_t)mesh->vertex_count);
    for (int32_t f = 0; f < mesh->face_count; ++f)
        for (int k = 0; k < 3; ++k) {
            int32_t v = mesh->faces[3 * f + k];
            if (seen[v])
                continue;
            seen[v] = 1;
            const double *s = sums + 5 * pattern->face_panel[f];
            double x = uv[2 * v] - s[2], y = uv[2 * v + 1] - s[3];
            uv[2 * v] = s[2] + s[0] * x - s[1] * y;
            uv[2 * v + 1] = s[3] + s[1] * x + s[0] * y;
        }
    free(sums);
    free(seen);
    return PZ_OK;
}


/* ------------------------------------------------------------------------ */
/* Untangling the interior                                                   */
/* ------------------------------------------------------------------------ */

/*
 * Why faces flip even with the positive 1/length weights: Tutte's guarantee
 * needs a convex boundary, and a dangling feature curve's tip is a reflex
 * corner of its wire-patch (inner angle 2 pi). On a positively curved panel
 * the wires keep their 3D lengths, the interior is compressed, and the
 * vertex that continues the curve past the tip is pulled back across it
 * (quarter-sphere, meridian from the pole to latitude 45: the 2 faces
 * between the tip and that vertex). The repair moves only interior (non-wire)
 * vertices, so E_len is untouched: a vertex of a flipped face goes to the
 * centroid of the kernel of its star (the points from which every one of its
 * faces is counter-clockwise), which unflips all its faces without flipping
 * any other. Rounds repeat while they help; a vertex whose kernel is empty
 * waits for its neighbours to move.
 */
#define UNTANGLE_ROUNDS 50
#define KERNEL_MAX 64      /* polygon vertices kept while clipping; a star has a handful of faces */

double ww_face_det(const pz_mesh *mesh, const double *uv, int32_t f)
{
    const int32_t *c = mesh->faces + 3 * f;
    const double *a = uv + 2 * c[0], *b = uv + 2 * c[1], *d = uv + 2 * c[2];
    return (b[0] - a[0]) * (d[1] - a[1]) - (d[0] - a[0]) * (b[1] - a[1]);
}

/* Clips the convex polygon poly (n points) to the half-plane left of a -> b; returns the new count. */
static int clip_left(double (*poly)[2], int n, const double *a, const double *b)
{
    double out[KERNEL_MAX][2];
    int m = 0;
    for (int i = 0; i < n; ++i) {
        const double *p = poly[i], *q = poly[(i + 1) % n];
        double sp = (b[0] - a[0]) * (p[1] - a[1]) - (b[1] - a[1]) * (p[0] - a[0]);
        double sq = (b[0] - a[0]) * (q[1] - a[1]) - (b[1] - a[1]) * (q[0] - a[0]);
        if (sp >= 0 && m < KERNEL_MAX) {
            out[m][0] = p[0];
            out[m++][1] = p[1];
        }
        if ((sp >= 0) != (sq >= 0) && m < KERNEL_MAX) {
            double t = sp / (sp - sq);
            out[m][0] = p[0] + t * (q[0] - p[0]);
            out[m++][1] = p[1] + t * (q[1] - p[1]);
        }
    }
    memcpy(poly, out, (size_t)m * sizeof out[0]);
    return m;
}

/* Moves v to the centroid of its star's kernel; 0 when the kernel is empty. */
static int move_into_kernel(const pz_mesh *mesh, const int32_t *star, int32_t count, int32_t v, double *uv)
{
    double poly[KERNEL_MAX][2], lo[2] = {HUGE_VAL, HUGE_VAL}, hi[2] = {-HUGE_VAL, -HUGE_VAL};
    for (int32_t i = 0; i < count; ++i)
        for (int k = 0; k < 3; ++k)
            for (int d = 0; d < 2; ++d) {
                lo[d] = fmin(lo[d], uv[2 * mesh->faces[3 * star[i] + k] + d]);
                hi[d] = fmax(hi[d], uv[2 * mesh->faces[3 * star[i] + k] + d]);
            }
    double box[4][2] = {{lo[0], lo[1]}, {hi[0], lo[1]}, {hi[0], hi[1]}, {lo[0], hi[1]}};
    memcpy(poly, box, sizeof box);
    int n = 4;
    for (int32_t i = 0; i < count && n >= 3; ++i) {
        const int32_t *c = mesh->faces + 3 * star[i];
        int k = c[0] == v ? 0 : c[1] == v ? 1 : 2;
        n = clip_left(poly, n, uv + 2 * c[(k + 1) % 3], uv + 2 * c[(k + 2) % 3]);
    }
    double twice = 0, cx = 0, cy = 0;
    for (int i = 0; i < n; ++i) {
        const double *p = poly[i], *q = poly[(i + 1) % n];
        double cross = p[0] * q[1] - q[0] * p[1];
        twice += cross;
        cx += (p[0] + q[0]) * cross;
        cy += (p[1] + q[1]) * cross;
    }
    if (n < 3 || !(twice > 1e-12 * (hi[0] - lo[0]) * (hi[1] - lo[1])))
        return 0;
    double old[2] = {uv[2 * v], uv[2 * v + 1]};
    uv[2 * v] = cx / (3 * twice);
    uv[2 * v + 1] = cy / (3 * twice);
    for (int32_t i = 0; i < count; ++i)
        if (!(ww_face_det(mesh, uv, star[i]) > 0)) { /* round-off at a sliver kernel: keep the old place */
            uv[2 * v] = old[0];
            uv[2 * v + 1] = old[1];
            return 0;
        }
    return 1;
}

/* Unflips faces by moving their vertices that are not `fixed` (NULL: none is; see above); returns the
 * vertex moves or -1 (no memory). Also used by springmass.c. */
int32_t pz_param_untangle(const pz_mesh *mesh, const uint8_t *fixed, double *uv)
{
    int32_t nv = mesh->vertex_count, nf = mesh->face_count, moves = 0;
    int32_t *offsets = calloc((size_t)nv + 2, sizeof(int32_t)), *star = malloc((size_t)nf * 3 * sizeof(int32_t) + 1);
    uint8_t *wanted = malloc((size_t)nv + 1);
    if (!offsets || !star || !wanted) {
        free(offsets);
        free(star);
        free(wanted);
        return -1;
    }
    for (int32_t c = 0; c < 3 * nf; ++c)
        ++offsets[mesh->faces[c] + 2];
    for (int32_t v = 0; v < nv; ++v)
        offsets[v + 2] += offsets[v + 1];
    for (int32_t c = 0; c < 3 * nf; ++c)
        star[offsets[mesh->faces[c] + 1]++] = c / 3;
    /* offsets[v] .. offsets[v + 1] are now v's faces */
    for (int round = 0; round < UNTANGLE_ROUNDS; ++round) {
        memset(wanted, 0, (size_t)nv);
        int32_t flipped = 0, moved = 0;
        for (int32_t f = 0; f < nf; ++f)
            if (!(ww_face_det(mesh, uv, f) > 0)) {
                ++flipped;
                for (int k = 0; k < 3; ++k)
                    wanted[mesh->faces[3 * f + k]] = !fixed || !fixed[mesh->faces[3 * f + k]];
            }
        for (int32_t v = 0; v < nv; ++v)
            if (wanted[v])
                moved += move_into_kernel(mesh, star + offsets[v], offsets[v + 1] - offsets[v], v, uv);
        moves += moved;
        if (!flipped || !moved)
            break;
    }
    free(offsets);
    free(star);
    free(wanted);
    return moves;
}

/*
 * param/lscm.c -- least squares conformal maps (Levy et al. 2002), grain
 * orientation and the side-by-side layout of pattern pieces.
 *
 * LSCM. In each triangle's own orthonormal frame (x along the first edge, y
 * in the plane, so the triangle is counter-clockwise) the gradients of the
 * hat functions are grad(phi_i) = rot90(p_k - p_j) / (2 A) for (i, j, k)
 * cyclic. A map (u, v) is conformal on the triangle when grad(v) is grad(u)
 * turned by +90 degrees (Cauchy-Riemann: v_x = -u_y, v_y = u_x), so the
 * conformal energy (Levy 2002, Eq. 5; the same quadratic form as Dirichlet
 * energy minus signed area) is
 *     E_C = sum_t A_t ( (v_x + u_y)^2 + (v_y - u_x)^2 ),
 * two residual rows of six unknowns per triangle. Its null space is the
 * similarities (4 dimensions), so two boundary vertices far apart are pinned
 * to (0, 0) and (d, 0), d their 3D distance (Levy's choice). The normal
 * equations of the remaining 2 (n - 2) unknowns (u and v interleaved) are
 * SPD and are solved with one CHOLMOD factorization (supernodal from about
 * 20K faces, pz_param_factorize).
 *
 * Grain (pietroni2022 Sec. 4.3, "Grain alignment"): per triangle the 3D
 * grain axis is projected onto the triangle plane and carried into 2D by the
 * triangle's affine map F = Q P^-1 (P: 3D edge vectors in the local frame,
 * Q: 2D edge vectors); the unit 2D directions, weighted by 3D area times the
 * projected length, are summed and the piece is rotated so that the sum
 * points along +v (the warp; docs/param.md). When the weighted sum is below
 * 1e-3 of the area (grain nearly normal to the whole piece, or projections
 * cancelling out) the orientation is left as it is.
 *
 * Then the piece is scaled so its 2D area equals its 3D area (a conformal
 * map's scale is arbitrary) and moved so its min corner is (0, 0).
 *
 * Layout: pieces are placed on shelves (rows) left to right with a 20 mm gap,
 * a new row when the row is wider than max(widest piece, 1.5 sqrt(sum of
 * box areas)), so the whole pattern is viewable and no two boxes overlap.
 *
 * Cost: O(F) assembly, one sparse Cholesky of a 2V system; memory about
 * 36 triplets per face transiently. Failure modes: a mesh that is not one
 * disk (PZ_ERR_DATA), a numerically singular system (PZ_ERR_INTERNAL),
 * out of memory (PZ_ERR_NOMEM).
 *
 * SPDX-License-Identifier: GPL-3.0-or-later
 */
#include "param/internal.h"

#include <math.h>
#include <stdlib.h>
#include <string.h>
#include <omp.h>

#define LSCM_GAP_MM 20.0
#define LSCM_HALF_PI 1.57079632679489661923

/* Local frame of face f (positions pos): the 2D coordinates of corners 1 and 2
 * (corner 0 at the origin), written to local[0..2] = x1, x2, y2, and the frame
 * axes e1, e2 (each 3). Returns the area (0 for a degenerate face). */
double pz_param_face_frame(const double *pos, const int32_t *face, double local[3], double e1[3], double e2[3])
{
    const double *a = pos + 3 * face[0], *b = pos + 3 * face[1], *c = pos + 3 * face[2];
    double ab[3] = {b[0] - a[0], b[1] - a[1], b[2] - a[2]};
    double ac[3] = {c[0] - a[0], c[1] - a[1], c[2] - a[2]};
    double n[3] = {ab[1] * ac[2] - ab[2] * ac[1], ab[2] * ac[0] - ab[0] * ac[2], ab[0] * ac[1] - ab[1] * ac[0]};
    double len_ab = sqrt(ab[0] * ab[0] + ab[1] * ab[1] + ab[2] * ab[2]);
    double len_n = sqrt(n[0] * n[0] + n[1] * n[1] + n[2] * n[2]);
    if (len_ab <= 0 || len_n <= 0) {
        local[0] = local[1] = local[2] = 0;
        for (int k = 0; k < 3; ++k)
            e1[k] = e2[k] = 0;
        return 0;
    }
    for (int k = 0; k < 3; ++k) {
        e1[k] = ab[k] / len_ab;
        n[k] /= len_n;
    }
    e2[0] = n[1] * e1[2] - n[2] * e1[1];
    e2[1] = n[2] * e1[0] - n[0] * e1[2];
    e2[2] = n[0] * e1[1] - n[1] * e1[0];
    local[0] = len_ab;
    local[1] = ac[0] * e1[0] + ac[1] * e1[1] + ac[2] * e1[2];
    local[2] = ac[0] * e2[0] + ac[1] * e2[1] + ac[2] * e2[2];
    return 0.5 * len_n;
}

/*
 * The rotation angle (radians, counter-clockwise) that turns the area-weighted
 * projected grain of the given faces onto +v; 0 when the grain is nearly
 * normal to all of them (see the header). mesh: 3D positions and faces.
 */
double pz_param_grain_angle(const pz_mesh *mesh, const int32_t *face_ids, int32_t face_count, const double grain[3],
                            double turn, const double *uv)
{
    double glen = sqrt(grain[0] * grain[0] + grain[1] * grain[1] + grain[2] * grain[2]);
    if (glen <= 0)
        return 0;
    double g[3] = {grain[0] / glen, grain[1] / glen, grain[2] / glen};
    double sum[2] = {0, 0}, area_sum = 0;
    for (int32_t i = 0; i < face_count; ++i) {
        const int32_t *face = mesh->faces + 3 * (face_ids ? face_ids[i] : i);
        double local[3], e1[3], e2[3];
        double area = pz_param_face_frame(mesh->positions, face, local, e1, e2);
        if (area <= 0)
            continue;
        area_sum += area;
        /* The grain in the frame: its projection onto the plane is (a, b). */
        double a = g[0] * e1[0] + g[1] * e1[1] + g[2] * e1[2];
        double b = g[0] * e2[0] + g[1] * e2[1] + g[2] * e2[2];
        pz_param_turn_in_frame(turn, &a, &b);
        double projected = sqrt(a * a + b * b);
        if (projected < 1e-9)
            continue;
        /* F = Q P^-1 with P = [(x1, 0) (x2, y2)], Q the 2D edge vectors. */
        const double *q0 = uv + 2 * face[0], *q1 = uv + 2 * face[1], *q2 = uv + 2 * face[2];
        double q1x = q1[0] - q0[0], q1y = q1[1] - q0[1], q2x = q2[0] - q0[0], q2y = q2[1] - q0[1];
        /* P^-1 (a, b): solve x1 s + x2 t = a, y2 t = b. */
        double t = b / local[2];
        double s = (a - local[1] * t) / local[0];
        double dx = q1x * s + q2x * t, dy = q1y * s + q2y * t;
        double dlen = sqrt(dx * dx + dy * dy);
        if (!(dlen > 0))
            continue;
        sum[0] += area * projected * dx / dlen;
        sum[1] += area * projected * dy / dlen;
    }
    if (!(sqrt(sum[0] * sum[0] + sum[1] * sum[1]) > 1e-3 * area_sum))
        return 0;
    return LSCM_HALF_PI - atan2(sum[1], sum[0]);
}

/* Rotates the uv of the listed vertices by `angle` about their centroid. */
void pz_param_rotate_vertices(const int32_t *vertex_ids, int32_t vertex_count, double angle, double *uv)
{
    if (angle == 0 || vertex_count == 0)
        return;
    double cu = 0, cv = 0;
    for (int32_t i = 0; i < vertex_count; ++i) {
        cu += uv[2 * vertex_ids[i]];
        cv += uv[2 * vertex_ids[i] + 1];
    }
    cu /= vertex_count;
    cv /= vertex_count;
    double c = cos(angle), s = sin(angle);
    for (int32_t i = 0; i < vertex_count; ++i) {
        double *p = uv + 2 * vertex_ids[i];
        double x = p[0] - cu, y = p[1] - cv;
        p[0] = cu + c * x - s * y;
        p[1] = cv + s * x + c * y;
    }
}

/* ------------------------------------------------------------------------ */
/* Fill-reducing ordering                                                    */
/* ------------------------------------------------------------------------ */

/* A part of at most this many unknowns is not split further (its natural
 * order costs little fill). */
#define ND_LEAF 16

typedef struct nd_work {
    const int32_t *start, *adjacent;  /* full adjacency (both triangles), CSR */
    const double *coords;             /* n x 3 */
    int32_t *mark;                    /* n: the call that marked the vertex (its upper half) */
    double *key;                      /* n: position along the current split axis */
    int32_t calls;
    int32_t *perm;
    int32_t filled;
    int32_t *best_ids;                /* n, or NULL: scratch keeping the best split of a part so far */
} nd_work;

/* Reorders ids so that ids[0..k) have keys <= those of ids[k..m) (Hoare selection). */
static void nd_select(const double *key, int32_t *ids, int32_t m, int32_t k)
{
    int32_t lo = 0, hi = m - 1;
    while (lo < hi) {
        double pivot = key[ids[(lo + hi) / 2]];
        int32_t i = lo, j = hi;
        while (i <= j) {
            while (key[ids[i]] < pivot)
                ++i;
            while (key[ids[j]] > pivot)
                --j;
            if (i <= j) {
                int32_t t = ids[i];
                ids[i++] = ids[j];
                ids[j--] = t;
            }
        }
        if (k <= j)
            hi = j;
        else if (k >= i)
            lo = i;
        else
            return;
    }
}

/* Splits ids at the median along coordinate `axis` (ids[0..m/2) below) and
 * moves the separator -- the vertices of the lower half that touch the upper
 * half -- to the end of the lower half. Returns where the separator starts. */
static int32_t nd_split(nd_work *w, int32_t *ids, int32_t m, int axis)
{
    for (int32_t i = 0; i < m; ++i)
        w->key[ids[i]] = w->coords[3 * ids[i] + axis];
    int32_t half = m / 2;
    nd_select(w->key, ids, m, half);
    int32_t token = ++w->calls;
    for (int32_t i = half; i < m; ++i)
        w->mark[ids[i]] = token;
    int32_t inner = half;
    for (int32_t i = half - 1; i >= 0; --i) {
        int32_t v = ids[i], touches = 0;
        for (int32_t e = w->start[v]; e < w->start[v + 1] && !touches; ++e)
            touches = w->mark[w->adjacent[e]] == token;
        if (touches) {
            ids[i] = ids[--inner];
            ids[inner] = v;
        }
    }
    return inner;
}

/* Orders ids: the half below the median, the half above, then the separator,
 * each half recursively. The split is across whichever coordinate axis gives
 * the smallest separator among those along which the part extends at least
 * a third as far as along its longest (the longest alone cut a face scan's
 * relief along its depth: 2x larger separators, 2.7x the flops of AMD). */
static void nd_order(nd_work *w, int32_t *ids, int32_t m, int depth)
{
    if (m <= ND_LEAF || depth > 60) {
        for (int32_t i = 0; i < m; ++i)
            w->perm[w->filled++] = ids[i];
        return;
    }
    double lo[3] = {INFINITY, INFINITY, INFINITY}, hi[3] = {-INFINITY, -INFINITY, -INFINITY};
    for (int32_t i = 0; i < m; ++i)
        for (int k = 0; k < 3; ++k) {
            lo[k] = fmin(lo[k], w->coords[3 * ids[i] + k]);
            hi[k] = fmax(hi[k], w->coords[3 * ids[i] + k]);
        }
    double longest = fmax(hi[0] - lo[0], fmax(hi[1] - lo[1], hi[2] - lo[2]));
    int best_axis = -1, last_axis = -1;
    int32_t best_size = m + 1, inner = 0, best_inner = 0;
    for (int axis = 0; axis < 3; ++axis) {
        if (hi[axis] - lo[axis] < longest / 3)
            continue;
        inner = nd_split(w, ids, m, axis);
        last_axis = axis;
        if (m / 2 - inner < best_size) {
            best_size = m / 2 - inner;
            best_axis = axis, best_inner = inner;
            if (w->best_ids) /* kept: a later, worse split need not be redone */
                memcpy(w->best_ids, ids, (size_t)m * sizeof *ids);
        }
    }
    if (best_axis != last_axis) {
        if (w->best_ids)
            memcpy(ids, w->best_ids, (size_t)m * sizeof *ids), inner = best_inner;
        else
            inner = nd_split(w, ids, m, best_axis);
    }
    int32_t half = m / 2;
    nd_order(w, ids, inner, depth + 1);
    nd_order(w, ids + half, m - half, depth + 1);
    for (int32_t i = inner; i < half; ++i)
        w->perm[w->filled++] = ids[i];
}

/*
 * A nested dissection ordering of a symmetric n x n pattern (CHOLMOD's
 * upper or lower CSC: colp, rows) whose unknowns sit at 3D points coords
 * (n x 3): recursive median splits across a coordinate axis (nd_order)
 * with the vertex separator ordered last. On the 100K-vertex hemisphere
 * this gives 4.8M factor entries and 0.91 GFlop against AMD's 5.4M and 1.42
 * (METIS: 4.4M, 0.75) in 50 ms against METIS's 400 (docs/param.md). perm:
 * n, written (perm[k] = the unknown eliminated k-th). Returns 0 when out of
 * memory.
 */
static int nested_dissection(const int *colp, const int *rows, int32_t n, const double *coords, int32_t *perm)
{
    int32_t *start = calloc((size_t)n + 2, sizeof(int32_t));
    int32_t *ids = malloc(((size_t)n + 1) * sizeof(int32_t));
    int32_t *mark = malloc(((size_t)n + 1) * sizeof(int32_t));
    double *key = malloc(((size_t)n + 1) * sizeof(double));
    int32_t *adjacent = NULL;
    int ok = start && ids && mark && key;
    if (ok) {
        for (int32_t j = 0; j < n; ++j)
            for (int e = colp[j]; e < colp[j + 1]; ++e)
                if (rows[e] != j) {
                    ++start[rows[e] + 2];
                    ++start[j + 2];
                }
        for (int32_t v = 0; v < n; ++v)
            start[v + 2] += start[v + 1];
        ok = (adjacent = malloc(((size_t)start[n + 1] + 1) * sizeof(int32_t))) != NULL;
    }
    if (ok) {
        for (int32_t j = 0; j < n; ++j)
            for (int e = colp[j]; e < colp[j + 1]; ++e)
                if (rows[e] != j) {
                    adjacent[start[rows[e] + 1]++] = j;
                    adjacent[start[j + 1]++] = rows[e];
                }
        for (int32_t v = 0; v < n; ++v) {
            ids[v] = v;
            mark[v] = 0;
        }
        int32_t *best_ids = malloc(((size_t)n + 1) * sizeof(int32_t)); /* NULL: splits are redone instead */
        nd_work w = {start, adjacent, coords, mark, key, 0, perm, 0, best_ids};
        nd_order(&w, ids, n, 0);
        free(best_ids);
    }
    free(start);
    free(ids);
    free(mark);
    free(key);
    free(adjacent);
    return ok;
}

/*
 * CHOLMOD's symbolic analysis of a symmetric matrix whose unknown k sits at
 * the 3D point positions[3 * vertex_of[k]]: from ND_MIN_UNKNOWNS unknowns on,
 * the better (CHOLMOD's pick) of nested_dissection and AMD -- nested
 * dissection wins on smooth meshes (hemisphere, 100K unknowns: 0.91 against
 * 1.42 GFlop), AMD on some irregular ones (the face scan: 0.04 against 0.09)
 * -- (and METIS too for a `refactorized` matrix below PZ_METIS_MAX_UNKNOWNS)
 * else, or when vertex_of is NULL or memory is short, CHOLMOD's default
 * (AMD, METIS when that fills badly: its analysis alone took 1.2-1.7 s at
 * 200K faces). Returns the symbolic factor or NULL (common->status says
 * why). Shared with the textile set-up (param/textile_setup.c).
 */
#define ND_MIN_UNKNOWNS 8000
/* cholmod_analyze_p trying the orderings listed (CHOLMOD keeps the one that fills least); perm: the
 * CHOLMOD_GIVEN one, when listed. */
static cholmod_factor *analyze_with(cholmod_sparse *matrix, int32_t *perm, const int *orderings, int count,
                                    cholmod_common *common)
{
    int nmethods = common->nmethods, saved[3];
    for (int m = 0; m < count; ++m) {
        saved[m] = common->method[m].ordering;
        common->method[m].ordering = orderings[m];
    }
    common->nmethods = count;
    cholmod_factor *factor = cholmod_analyze_p(matrix, perm, NULL, 0, common);
    common->nmethods = nmethods;
    for (int m = 0; m < count; ++m)
        common->method[m].ordering = saved[m];
    return factor;
}

cholmod_factor *pz_param_analyze(cholmod_sparse *matrix, const double *positions, const int32_t *vertex_of,
                                 int refactorized, cholmod_common *common)
{
    size_t n = matrix->ncol;
    /* METIS for a matrix factorized many times: on the textile's systems it filled 10-17 % less than
     * the better of nested_dissection and AMD, with 21-46 % fewer flops (camelhead.off: 35 -> 19
     * MFlop), but through CHOLMOD it costs two to four of those factorizations (40-80 ms at 11-17K
     * unknowns), and at 100K unknowns it added 0.8 s to the start-up (docs/param.md, "Speed against
     * libigl"). */
    int metis = refactorized && n < PZ_METIS_MAX_UNKNOWNS;
    double *coords = NULL;
    int32_t *perm = NULL;
    if (vertex_of && n >= ND_MIN_UNKNOWNS) {
        coords = malloc(n * 3 * sizeof(double));
        perm = malloc(n * sizeof(int32_t));
    }
    int dissected = 0;
    cholmod_factor *factor = NULL;
    if (coords && perm) {
        for (size_t k = 0; k < n; ++k)
            memcpy(coords + 3 * k, positions + 3 * (size_t)vertex_of[k], 3 * sizeof(double));
        dissected = nested_dissection(matrix->p, matrix->i, (int32_t)n, coords, perm);
        if (dissected) {
            /* AMD wins on some irregular meshes. */
            static const int orderings[3] = {CHOLMOD_GIVEN, CHOLMOD_AMD, CHOLMOD_METIS};
            factor = analyze_with(matrix, perm, orderings, metis ? 3 : 2, common);
        }
    }
    free(coords);
    free(perm);
    if (dissected)
        return factor;
    if (metis) {
        static const int orderings[2] = {CHOLMOD_AMD, CHOLMOD_METIS};
        return analyze_with(matrix, NULL, orderings, 2, common);
    }
    return cholmod_analyze(matrix, common);
}

cholmod_factor *pz_param_analyze_ranked(cholmod_sparse *matrix, const int32_t *vertex_of, const int32_t *vertex_rank,
                                        cholmod_common *common)
{
    size_t n = matrix->ncol;
    int32_t *perm = malloc(n * sizeof(int32_t) + 1);
    int32_t *count = calloc(n + 2, sizeof(int32_t));
    cholmod_factor *factor = NULL;
    if (perm && count) {
        /* Counting sort by rank (ranks below n; none: n, last). */
        for (size_t k = 0; k < n; ++k) {
            int32_t r = vertex_rank[vertex_of[k]];
            ++count[(r >= 0 && (size_t)r < n ? (size_t)r : n) + 1];
        }
        for (size_t r = 0; r <= n; ++r)
            count[r + 1] += count[r];
        for (size_t k = 0; k < n; ++k) {
            int32_t r = vertex_rank[vertex_of[k]];
            perm[count[r >= 0 && (size_t)r < n ? (size_t)r : n]++] = (int32_t)k;
        }
        static const int given[1] = {CHOLMOD_GIVEN};
        factor = analyze_with(matrix, perm, given, 1, common);
    } else {
        common->status = CHOLMOD_OUT_OF_MEMORY;
    }
    free(perm);
    free(count);
    return factor;
}

/*
 * cholmod_factorize with no OpenMP team. CHOLMOD 3 (SuiteSparse 5.12) opens
 * its supernodal factorization's parallel regions with a fixed
 * num_threads(CHOLMOD_OMP_NUM_THREADS), 4, once or several times per
 * supernode: hundreds of small regions per factorization. Those regions only
 * clear and scatter memory (the flops are in the BLAS, reference BLAS being
 * single-threaded), so a team saves little, and after every region libgomp's
 * worker threads spin (its default active wait, GOMP_SPINCOUNT 300,000) while
 * the calling thread goes on alone: on the 2-core machine with an idle
 * 15-minute load average (libgomp's dynamic teams then allow 2 threads), a
 * 20K-face textile iteration took 350 ms of CPU instead of 13 and a 3K-face
 * initialization 170 ms instead of 16, and on a busy machine the spinners
 * take the core the caller needs (docs/param.md, "Speed"). So the calling
 * thread's max-active-levels ICV is 0 for the call (every region inside runs
 * as a team of one; the ICV belongs to the calling task's data environment,
 * so nothing else in the process is affected) and restored afterwards. The
 * factor does not depend on the team size. Shared with the textile global step (param/textile_global.c).
 * Returns cholmod_factorize's result (common->status says why it failed).
 */
int pz_param_factorize(cholmod_sparse *matrix, cholmod_factor *factor, cholmod_common *common)
{
    int levels = omp_get_max_active_levels();
    omp_set_max_active_levels(0);
    int ok = cholmod_factorize(matrix, factor, common);
    omp_set_max_active_levels(levels);
    return ok;
}

/* ------------------------------------------------------------------------ */
/* LSCM of one disk                                                          */
/* ------------------------------------------------------------------------ */

static pz_status check_disk(const pz_mesh *disk, pz_topology **topology, pz_ctx *ctx)
{
    pz_status status = pz_topology_build(disk, topology, ctx);
    if (status)
        return status;
    pz_topology_summary summary;
    if ((status = pz_topology_summarize(*topology, &summary, ctx)))
        return status;
    if (summary.component_count != 1 || summary.boundary_loop_count != 1 || summary.genus != 0)
        return pz_error(ctx, PZ_ERR_DATA,
                        "lscm: the mesh is not one disk (%d components, %d boundary loops, genus %d)",
                        summary.component_count, summary.boundary_loop_count, summary.genus);
    return PZ_OK;
}

/* Two boundary vertices far apart: the farthest from the first boundary
 * vertex, then the farthest from that one (two sweeps over the loop). */
static pz_status pick_pins(const pz_mesh *disk, const pz_topology *topology, int32_t pins[2], pz_ctx *ctx)
{
    pz_loops *loops = NULL;
    pz_status status = pz_topology_boundary_loops(topology, &loops, ctx);
    if (status)
        return status;
    const int32_t *loop = loops->loop_vertices;
    int32_t count = loops->loop_offsets[1];
    int32_t a = loop[0], b = loop[0];
    for (int sweep = 0; sweep < 2; ++sweep) {
        double best = -1;
        const double *from = disk->positions + 3 * a;
        for (int32_t i = 0; i < count; ++i) {
            const double *p = disk->positions + 3 * loop[i];
            double d = (p[0] - from[0]) * (p[0] - from[0]) + (p[1] - from[1]) * (p[1] - from[1]) +
                       (p[2] - from[2]) * (p[2] - from[2]);
            if (d > best) {
                best = d;
                b = loop[i];
            }
        }
        if (sweep == 0) {
            a = b;
        }
    }
    pz_loops_free(&loops);
    if (a == b)
        return pz_error(ctx, PZ_ERR_DATA, "lscm: the boundary has a single point");
    pins[0] = a;
    pins[1] = b;
    return PZ_OK;
}

/* Assembles and solves the pinned normal equations; writes uv of every
 * referenced vertex (unreferenced ones get 0). */
static pz_status lscm_solve(const pz_mesh *disk, const int32_t pins[2], double *uv, int32_t *vertex_rank,
                            pz_ctx *ctx)
{
    int32_t nv = disk->vertex_count, nf = disk->face_count;
    int32_t *unknown = malloc((size_t)nv * sizeof(int32_t));
    if (!unknown)
        return pz_error(ctx, PZ_ERR_NOMEM, "lscm: out of memory");
    for (int32_t v = 0; v < nv; ++v)
        unknown[v] = -1;
    for (int32_t i = 0; i < 3 * nf; ++i)
        unknown[disk->faces[i]] = 0;
    int32_t free_count = 0;
    for (int32_t v = 0; v < nv; ++v)
        if (unknown[v] == 0 && v != pins[0] && v != pins[1])
            unknown[v] = free_count++;
        else if (v == pins[0] || v == pins[1])
            unknown[v] = -2;
    const double *pa = disk->positions + 3 * pins[0], *pb = disk->positions + 3 * pins[1];
    double distance = sqrt((pa[0] - pb[0]) * (pa[0] - pb[0]) + (pa[1] - pb[1]) * (pa[1] - pb[1]) +
                           (pa[2] - pb[2]) * (pa[2] - pb[2]));
    memset(uv, 0, (size_t)nv * 2 * sizeof(double));
    uv[2 * pins[1]] = distance;

    cholmod_common common;
    cholmod_start(&common);
    common.supernodal = CHOLMOD_AUTO; /* supernodal from about 20K faces: docs/param.md, "Speed" */
    size_t n = (size_t)free_count;
    /* Lower triangle (stype -1) of the Hermitian matrix: 6 entries per face at most. */
    cholmod_triplet *triplet = cholmod_allocate_triplet(n, n, (size_t)nf * 6, -1, CHOLMOD_COMPLEX, &common);
    cholmod_dense *rhs = cholmod_zeros(n, 1, CHOLMOD_COMPLEX, &common);
    cholmod_sparse *matrix = NULL;
    cholmod_factor *factor = NULL;
    cholmod_dense *solution = NULL;
    pz_status status = PZ_OK;
    if (!triplet || !rhs) {
        status = pz_error(ctx, PZ_ERR_NOMEM, "lscm: out of memory");
        goto done;
    }
    int *ti = triplet->i, *tj = triplet->j;
    double *tx = triplet->x, *b = rhs->x;
    for (int32_t f = 0; f < nf; ++f) {
        const int32_t *face = disk->faces + 3 * f;
        double local[3], e1[3], e2[3];
        double area = pz_param_face_frame(disk->positions, face, local, e1, e2);
        if (area <= 0)
            continue;
        double p[3][2] = {{0, 0}, {local[0], 0}, {local[1], local[2]}};
        /* W_i = sqrt(A) (d phi_i/dx + i d phi_i/dy): sum_i W_i z_i = 2 sqrt(A) dz/d(conj w). */
        double w_re[3], w_im[3], root = sqrt(area);
        for (int i = 0; i < 3; ++i) {
            int j = (i + 1) % 3, k = (i + 2) % 3;
            w_re[i] = -root * (p[k][1] - p[j][1]) / (2 * area);
            w_im[i] = root * (p[k][0] - p[j][0]) / (2 * area);
        }
        for (int r = 0; r < 3; ++r) {
            int32_t row = unknown[face[r]];
            if (row < 0)
                continue;
            for (int c = 0; c < 3; ++c) {
                /* H_rc = conj(W_r) W_c */
                double re = w_re[r] * w_re[c] + w_im[r] * w_im[c], im = w_re[r] * w_im[c] - w_im[r] * w_re[c];
                int32_t col = unknown[face[c]];
                if (col < 0) { /* pinned: b_r -= H_rc z_c */
                    double zr = uv[2 * face[c]], zi = uv[2 * face[c] + 1];
                    b[2 * row] -= re * zr - im * zi;
                    b[2 * row + 1] -= re * zi + im * zr;
                } else if (row >= col) {
                    size_t t = triplet->nnz++;
                    ti[t] = row;
                    tj[t] = col;
                    tx[2 * t] = re;
                    tx[2 * t + 1] = im;
                }
            }
        }
    }
    matrix = cholmod_triplet_to_sparse(triplet, 0, &common);
    if (!matrix) {
        status = pz_error(ctx, PZ_ERR_NOMEM, "lscm: out of memory");
        goto done;
    }
    int32_t *vertex_of = malloc(n * sizeof(int32_t) + 1); /* NULL: CHOLMOD's default ordering */
    for (int32_t v = 0; vertex_of && v < nv; ++v)
        if (unknown[v] >= 0)
            vertex_of[unknown[v]] = v;
    factor = pz_param_analyze(matrix, disk->positions, vertex_of, 0, &common);
    if (vertex_rank && factor && vertex_of && n >= PZ_METIS_MAX_UNKNOWNS) {
        const int *perm = factor->Perm; /* perm[k]: the unknown eliminated k-th */
        for (size_t k = 0; k < n; ++k)
            vertex_rank[vertex_of[perm[k]]] = (int32_t)k;
    }
    free(vertex_of);
    if (factor)
        pz_param_factorize(matrix, factor, &common);
    if (!factor || common.status != CHOLMOD_OK) {
        status = common.status == CHOLMOD_OUT_OF_MEMORY ? pz_error(ctx, PZ_ERR_NOMEM, "lscm: out of memory")
                                                        : pz_error(ctx, PZ_ERR_INTERNAL,
                                                                   "lscm: the system is singular (degenerate triangles?)");
        goto done;
    }
    solution = cholmod_solve(CHOLMOD_A, factor, rhs, &common);
    if (!solution) {
        status = pz_error(ctx, PZ_ERR_INTERNAL, "lscm: the solve failed");
        goto done;
    }
    const double *x = solution->x;
    for (int32_t v = 0; v < nv; ++v)
        if (unknown[v] >= 0) {
            uv[2 * v] = x[2 * unknown[v]];
            uv[2 * v + 1] = x[2 * unknown[v] + 1];
            if (!isfinite(uv[2 * v]) || !isfinite(uv[2 * v + 1])) {
                status = pz_error(ctx, PZ_ERR_INTERNAL, "lscm: the solve is not finite");
                goto done;
            }
        }
done:
    cholmod_free_dense(&solution, &common);
    cholmod_free_factor(&factor, &common);
    cholmod_free_sparse(&matrix, &common);
    cholmod_free_dense(&rhs, &common);
    cholmod_free_triplet(&triplet, &common);
    cholmod_finish(&common);
    free(unknown);
    return status;
}

/* Scales to the 3D area (about the origin) and moves the min corner to (0, 0).
 * Reflects first if the map came out clockwise (cannot happen for a valid disk,
 * kept as a guard so the output is always counter-clockwise). */
static void normalize_piece(const pz_mesh *disk, double *uv)
{
    double area_3d = 0, area_2d = 0;
    for (int32_t f = 0; f < disk->face_count; ++f) {
        const int32_t *face = disk->faces + 3 * f;
        double local[3], e1[3], e2[3];
        area_3d += pz_param_face_frame(disk->positions, face, local, e1, e2);
        const double *a = uv + 2 * face[0], *b = uv + 2 * face[1], *c = uv + 2 * face[2];
        area_2d += 0.5 * ((b[0] - a[0]) * (c[1] - a[1]) - (b[1] - a[1]) * (c[0] - a[0]));
    }
    double scale = area_2d != 0 ? sqrt(area_3d / fabs(area_2d)) : 1;
    double flip = area_2d < 0 ? -1 : 1;
    double lo[2] = {INFINITY, INFINITY};
    for (int32_t v = 0; v < disk->vertex_count; ++v) {
        uv[2 * v] *= scale * flip;
        uv[2 * v + 1] *= scale;
    }
    for (int32_t i = 0; i < 3 * disk->face_count; ++i)
        for (int k = 0; k < 2; ++k)
            if (uv[2 * disk->faces[i] + k] < lo[k])
                lo[k] = uv[2 * disk->faces[i] + k];
    for (int32_t v = 0; v < disk->vertex_count; ++v) {
        uv[2 * v] -= lo[0];
        uv[2 * v + 1] -= lo[1];
    }
}

/* pz_param_lscm, and into vertex_rank (nv, may be NULL, left as it is for small systems) the elimination order of
 * its factorization when the system had at least PZ_METIS_MAX_UNKNOWNS unknowns. */
static pz_status lscm_disk(const pz_mesh *disk, const double grain[3], double *uv, int32_t *vertex_rank, pz_ctx *ctx)
{
    static const double up[3] = {0, 0, 1};
    if (!disk || !uv)
        return pz_error(ctx, PZ_ERR_USAGE, "lscm: no mesh or no output");
    pz_topology *topology = NULL;
    pz_status status = check_disk(disk, &topology, ctx);
    int32_t pins[2];
    if (!status)
        status = pick_pins(disk, topology, pins, ctx);
    pz_topology_free(&topology);
    if (!status)
        status = lscm_solve(disk, pins, uv, vertex_rank, ctx);
    if (status)
        return status;
    normalize_piece(disk, uv);
    double angle = pz_param_grain_angle(disk, NULL, disk->face_count, grain ? grain : up, 0, uv);
    if (angle != 0) {
        double c = cos(angle), s = sin(angle);
        for (int32_t v = 0; v < disk->vertex_count; ++v) {
            double x = uv[2 * v], y = uv[2 * v + 1];
            uv[2 * v] = c * x - s * y;
            uv[2 * v + 1] = s * x + c * y;
        }
        /* Rotation keeps the area: only move the min corner back to (0, 0). */
        normalize_piece(disk, uv);
    }
    return PZ_OK;
}

pz_status pz_param_lscm(const pz_mesh *disk, const double grain[3], double *uv, pz_ctx *ctx)
{
    return lscm_disk(disk, grain, uv, NULL, ctx);
}

/* ------------------------------------------------------------------------ */
/* Panels of a pattern                                                       */
/* ------------------------------------------------------------------------ */

/* Faces bucketed by panel: faces of panel p are order[offsets[p] .. offsets[p+1]-1]. */
pz_status pz_param_panel_faces(const pz_pattern *pattern, int32_t **offsets, int32_t **order, pz_ctx *ctx)
{
    int32_t nf = pattern->mesh->face_count, np = pattern->panel_count;
    *offsets = calloc((size_t)np + 1, sizeof(int32_t));
    *order = malloc((size_t)(nf ? nf : 1) * sizeof(int32_t));
    if (!*offsets || !*order) {
        free(*offsets);
        free(*order);
        *offsets = *order = NULL;
        return pz_error(ctx, PZ_ERR_NOMEM, "pattern: out of memory");
    }
    for (int32_t f = 0; f < nf; ++f) {
        int32_t p = pattern->face_panel[f];
        if (p < 0 || p >= np) {
            free(*offsets);
            free(*order);
            *offsets = *order = NULL;
            return pz_error(ctx, PZ_ERR_DATA, "pattern: face %d has panel %d out of range", f, p);
        }
        ++(*offsets)[p + 1];
    }
    for (int32_t p = 0; p < np; ++p)
        (*offsets)[p + 1] += (*offsets)[p];
    int32_t *fill = malloc((size_t)np * sizeof(int32_t) + 1);
    if (!fill) {
        free(*offsets);
        free(*order);
        *offsets = *order = NULL;
        return pz_error(ctx, PZ_ERR_NOMEM, "pattern: out of memory");
    }
    memcpy(fill, *offsets, (size_t)np * sizeof(int32_t));
    for (int32_t f = 0; f < nf; ++f)
        (*order)[fill[pattern->face_panel[f]]++] = f;
    free(fill);
    return PZ_OK;
}

pz_status pz_param_turn_to_panel_grain(const pz_pattern *pattern, const double grain[3], const double *panel_turn,
                                       double *uv, pz_ctx *ctx)
{
    if (!panel_turn)
        return PZ_OK;
    int32_t *offsets = NULL, *order = NULL;
    pz_status status = pz_param_panel_faces(pattern, &offsets, &order, ctx);
    if (status)
        return status;
    const pz_mesh *mesh = pattern->mesh;
    int32_t *vertices = malloc(((size_t)mesh->vertex_count + 1) * sizeof(int32_t));
    uint8_t *seen = calloc((size_t)mesh->vertex_count + 1, 1);
    if (!vertices || !seen)
        status = pz_error(ctx, PZ_ERR_NOMEM, "pattern: out of memory turning pieces to their grain");
    for (int32_t p = 0; status == PZ_OK && p < pattern->panel_count; ++p) {
        if (panel_turn[p] == 0 || !isfinite(panel_turn[p]))
            continue;
        const int32_t *faces = order + offsets[p];
        int32_t face_count = offsets[p + 1] - offsets[p], vertex_count = 0;
        for (int32_t i = 0; i < face_count; ++i)
            for (int k = 0; k < 3; ++k) {
                int32_t v = mesh->faces[3 * (size_t)faces[i] + k];
                if (!seen[v])
                    seen[v] = 1, vertices[vertex_count++] = v;
            }
        pz_param_rotate_vertices(vertices, vertex_count,
                                 pz_param_grain_angle(mesh, faces, face_count, grain, panel_turn[p], uv), uv);
        for (int32_t i = 0; i < vertex_count; ++i)
            seen[vertices[i]] = 0;
    }
    free(vertices);
    free(seen);
    free(offsets);
    free(order);
    return status;
}

/* Places the pieces on shelves with a 20 mm gap (see the header). */
void pz_param_layout(const pz_pattern *pattern, const int32_t *offsets, const int32_t *order, double *uv)
{
    const pz_mesh *mesh = pattern->mesh;
    int32_t np = pattern->panel_count;
    double *box = malloc((size_t)(np ? np : 1) * 4 * sizeof(double));
    uint8_t *moved = calloc((size_t)mesh->vertex_count + 1, 1);
    if (!box || !moved) { /* layout is cosmetic: leave the pieces where they are */
        free(box);
        free(moved);
        return;
    }
    double box_area = 0, widest = 0;
    for (int32_t p = 0; p < np; ++p) {
        double *b = box + 4 * p;
        b[0] = b[1] = INFINITY;
        b[2] = b[3] = -INFINITY;
        for (int32_t i = 3 * offsets[p]; i < 3 * offsets[p + 1]; ++i) {
            const double *q = uv + 2 * mesh->faces[3 * order[i / 3] + i % 3];
            b[0] = fmin(b[0], q[0]);
            b[1] = fmin(b[1], q[1]);
            b[2] = fmax(b[2], q[0]);
            b[3] = fmax(b[3], q[1]);
        }
        if (offsets[p + 1] == offsets[p])
            b[0] = b[1] = b[2] = b[3] = 0;
        box_area += (b[2] - b[0] + LSCM_GAP_MM) * (b[3] - b[1] + LSCM_GAP_MM);
        widest = fmax(widest, b[2] - b[0]);
    }
    double row_limit = fmax(widest, 1.5 * sqrt(box_area));
    double x = 0, y = 0, row_height = 0;
    for (int32_t p = 0; p < np; ++p) {
        const double *b = box + 4 * p;
        double width = b[2] - b[0], height = b[3] - b[1];
        if (x > 0 && x + width > row_limit) {
            x = 0;
            y += row_height + LSCM_GAP_MM;
            row_height = 0;
        }
        double du = x - b[0], dv = y - b[1];
        for (int32_t i = 3 * offsets[p]; i < 3 * offsets[p + 1]; ++i) {
            int32_t v = mesh->faces[3 * order[i / 3] + i % 3];
            if (moved[v])
                continue;
            moved[v] = 1;
            uv[2 * v] += du;
            uv[2 * v + 1] += dv;
        }
        x += width + LSCM_GAP_MM;
        row_height = fmax(row_height, height);
    }
    free(box);
    free(moved);
}

/* LSCM of one panel written back into the pattern's uv. */
static pz_status lscm_panel(const pz_pattern *pattern, int32_t panel, const int32_t *face_ids, int32_t count,
                            const double grain[3], double *uv, int32_t *vertex_rank, pz_ctx *ctx)
{
    pz_mesh *piece = NULL;
    int32_t *vertex_map = NULL, *piece_rank = NULL;
    double *piece_uv = NULL;
    pz_status status = pz_mesh_extract(pattern->mesh, face_ids, count, &piece, &vertex_map, NULL, ctx);
    if (!status && !(piece_uv = malloc((size_t)piece->vertex_count * 2 * sizeof(double))))
        status = pz_error(ctx, PZ_ERR_NOMEM, "lscm: out of memory");
    if (!status && vertex_rank && !(piece_rank = malloc((size_t)piece->vertex_count * sizeof(int32_t))))
        status = pz_error(ctx, PZ_ERR_NOMEM, "lscm: out of memory");
    for (int32_t v = 0; piece_rank && v < piece->vertex_count; ++v)
        piece_rank[v] = -1;
    if (!status) {
        status = lscm_disk(piece, grain, piece_uv, piece_rank, ctx);
        if (status) {
            /* Say which panel: the message from pz_param_lscm is generic. */
            char inner[sizeof ctx->error];
            memcpy(inner, ctx->error, sizeof inner);
            pz_error(ctx, status, "panel %d: %s", panel, inner);
        }
    }
    if (!status)
        for (int32_t v = 0; v < piece->vertex_count; ++v) {
            uv[2 * vertex_map[v]] = piece_uv[2 * v];
            uv[2 * vertex_map[v] + 1] = piece_uv[2 * v + 1];
            if (piece_rank)
                vertex_rank[vertex_map[v]] = piece_rank[v];
        }
    free(piece_rank);
    free(piece_uv);
    free(vertex_map);
    pz_mesh_free(&piece);
    return status;
}

pz_status pz_param_lscm_pattern(const pz_pattern *pattern, const double grain[3], double *uv, pz_ctx *ctx)
{
    return pz_param_lscm_pattern_ranked(pattern, grain, uv, NULL, ctx);
}

pz_status pz_param_lscm_pattern_ranked(const pz_pattern *pattern, const double grain[3], double *uv,
                                       int32_t *vertex_rank, pz_ctx *ctx)
{
    if (!pattern || !pattern->mesh || !uv)
        return pz_error(ctx, PZ_ERR_USAGE, "lscm: no pattern or no output");
    for (int32_t v = 0; vertex_rank && v < pattern->mesh->vertex_count; ++v)
        vertex_rank[v] = -1;
    int32_t *offsets = NULL, *order = NULL;
    pz_status status = pz_param_panel_faces(pattern, &offsets, &order, ctx);
    if (status)
        return status;
    memset(uv, 0, (size_t)pattern->mesh->vertex_count * 2 * sizeof(double));
    /* Panels are independent; each thread reports into its own context and
     * the first failing panel (lowest id) is the one reported. */
    int32_t failed_panel = pattern->panel_count;
    pz_status failed_status = PZ_OK;
    char failed_message[sizeof ctx->error] = "";
#pragma omp parallel for schedule(dynamic, 1) if (pattern->panel_count > 1 && pattern->mesh->face_count >= 8192)
    for (int32_t p = 0; p < pattern->panel_count; ++p) {
        pz_ctx local = *ctx;
        pz_status st =
            lscm_panel(pattern, p, order + offsets[p], offsets[p + 1] - offsets[p], grain, uv, vertex_rank, &local);
        if (st) {
#pragma omp critical(pz_lscm_failure)
            if (p < failed_panel) {
                failed_panel = p;
                failed_status = st;
                memcpy(failed_message, local.error, sizeof failed_message);
            }
        }
    }
    if (failed_status) {
        pz_error(ctx, failed_status, "%s", failed_message);
    } else {
        pz_param_layout(pattern, offsets, order, uv);
    }
    free(offsets);
    free(order);
    return failed_status;
}

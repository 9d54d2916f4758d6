/*
 * param/wirewarp.c -- WireWarping (C.C.L. Wang, "WireWarping: A fast surface
 * flattening approach with length-preserved feature curves", CAD 40, 2008).
 *
 * Wires are every panel's boundary (seams, darts already cut open by the
 * pattern) plus the user's feature curves. Cutting the pattern mesh along
 * the feature curves (pz_mesh_cut) splits each panel into wire-patches
 * (Sec. 2, Def. 4); every boundary vertex of that split mesh is a wire-node
 * (Def. 5), its host vertex is the pattern vertex it copies, its surface
 * angle alpha is the sum of the patch's corner angles there. Each wire-patch
 * must be a disk (one boundary loop).
 *
 * Angles. A wire-patch's boundary is drawn in the plane from its 2D angles
 * theta: edge b leaves node b in direction phi_b = phi_{b-1} + pi - theta_b
 * (Eq. 3) with its exact 3D length l_b (Eq. 8), so every wire edge keeps its
 * length by construction; the loop must turn by 2 pi and close (Eq. 2):
 *     (n - 2) pi - sum theta = 0,  sum l cos phi = 0,  sum l sin phi = 0,
 * and at every interior host vertex the angles of its wire-nodes sum to
 * 2 pi (Eq. 13, compatibility). We minimize sum (theta - alpha)^2 / 2 under
 * these constraints by sequential linearly constrained programming (Eq. 5,
 * Eqs. 15-24): with J the constraint Jacobian over the free angles (Eqs.
 * 16-19, suffix sums of l sin phi and l cos phi), g the residuals and
 * r = alpha - theta, each step solves
 *     (J J^T + eps I) mu = J r + g,   delta = r - J^T mu        (Eqs. 23-24)
 * whose fixed points are the KKT points; then a few minimum-norm feasibility
 * steps (delta = -J^T (J J^T + eps I)^-1 g) drive the closure residual to
 * round-off. J J^T + eps I is factored by CHOLMOD (simplicial, analyzed
 * once, refactored each step); eps = 1e-12 keeps it definite when the
 * system is rank deficient (a patch whose angles are all locked, key curves
 * that over-constrain it: paper Figs. 13-14), where the result is the
 * least-squares best effort and result->best_effort is set. Closure rows are
 * divided by the patch perimeter so all rows are O(1).
 *  - Global scheme (Sec. 4): one system over all wire-patches, 3m + r rows.
 *  - Progressive scheme (Sec. 3.2, Algorithm 2): patches one at a time from
 *    a max-heap keyed by the shape-evidence factor n'/n (Eq. 10); after a
 *    patch is warped, a node whose host's other nodes are all known is
 *    locked by Eq. 9. Several unknown nodes of one interior host inside the
 *    same patch (a dangling curve's slit) get a compatibility row instead.
 * Key feature curves lock their nodes' angles by Eq. 1, or by the user's
 * turning angles (pz_feature_curve.turning: pi -+ turn on the left/right
 * side, the paper's "users can specify the shape ... by assigning theta").
 * The iteration starts
 * from alpha shifted to satisfy each patch's turning constraint (see
 * start_on_turning) rather than the paper's theta = alpha.
 *
 * Layout (Sec. 3.3): patches are ordered by propagation over shared wire
 * edges; a patch with two consecutive placed nodes places the following
 * free nodes by Eq. 8, turning by pi - theta at each node.
 *
 * Interior vertices: the Laplacian-like system of Eq. 11 with the wires
 * fixed, solved directly with CHOLMOD. Default weights are the cotangent
 * weights (linear precision: a developable panel comes out isometric, which
 * the paper's 1/length weights do not give); options->interior = 1 uses the
 * paper's. Relaxed Gauss-Seidel (Eq. 12, tau = 1.5) is the fallback when the
 * factorization fails. Injectivity is measured with pz_metrics_compute; when
 * the cotangent solve flips faces, the 1/length weights (positive, so every
 * interior vertex is a convex combination of its neighbours) are tried and
 * kept if they flip fewer; faces still flipped are untangled by moving
 * interior vertices into the kernel of their star (pz_param_untangle), and
 * a dangling curve whose tip still folds gives up tip edges, flagged best
 * effort (trim_dangling_ends). Each piece is finally turned so that the grain
 * (default +z) runs along +v, and the pieces are laid side by side.
 *
 * Memory O(V + F). Time: O(F log F) to build the wires (sorting edges,
 * cutting); per Newton step a sparse factorization of the (3m + r) matrix
 * J J^T, whose entries are O(wire-nodes); one sparse solve for the interior.
 * Failure modes: PZ_ERR_DATA for a wire-patch that is not a disk (a closed
 * feature curve inside a panel) or a feature curve that does not follow
 * mesh edges; PZ_ERR_NOMEM; numerically impossible constraints are not
 * errors but a best-effort result.
 *
 * SPDX-License-Identifier: GPL-3.0-or-later
 */
#include "param/internal.h"
#include "core/util.h"

#include <math.h>
#include <stdlib.h>
#include <string.h>

#define WW_PI 3.14159265358979323846
#define WW_EPS 1e-12               /* diagonal regularization of J J^T (rows are O(1)) */
#define WW_FEASIBLE 1e-12          /* scaled residual below which the constraints hold */
#define WW_BEST_EFFORT 1e-9        /* scaled residual above which the result is flagged */
#define WW_KEY_WEIGHT 1e6          /* weight of a relaxed key angle's target against 1 for a free angle */
#define WW_RELAXED_ANGLE 1e-6      /* rad: a key curve whose angles moved more than this was relaxed */

/* ------------------------------------------------------------------------ */
/* Edge lookup                                                               */
/* ------------------------------------------------------------------------ */

typedef struct ww_edge_key {
    int64_t key;
    int32_t edge;
} ww_edge_key;

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
static ww_edge_key *edge_keys(const pz_topology *t)
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

static int32_t find_edge(const ww_edge_key *keys, int32_t count, int32_t a, int32_t b)
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

static double distance3(const double *a, const double *b)
{
    return sqrt((a[0] - b[0]) * (a[0] - b[0]) + (a[1] - b[1]) * (a[1] - b[1]) + (a[2] - b[2]) * (a[2] - b[2]));
}

/* ------------------------------------------------------------------------ */
/* Wires, wire-patches, wire-nodes (Sec. 2)                                  */
/* ------------------------------------------------------------------------ */

typedef struct ww_wires {
    pz_topology *topo;           /* of pattern->mesh */
    ww_edge_key *keys;
    uint8_t *wire_edge;          /* per edge: on a boundary or a feature curve */
    uint8_t *key_vertex;         /* per pattern vertex: on a key curve */
    double *key_turn;            /* per pattern vertex: the user's turning angle there, NAN when not given */
    int32_t *key_side;           /* per pattern vertex: the curve's previous and next vertex (x2), for key_turn */
    int32_t patch_count;
    int32_t *patch_panel;
    int32_t *patch_offsets;      /* nodes of patch p: patch_offsets[p] .. [p+1]-1, anticlockwise */
    double *patch_perimeter;
    int32_t node_count;
    int32_t *node_host;          /* pattern vertex */
    int32_t *node_patch;
    double *alpha;               /* surface angle (Def. 5) */
    double *length;              /* 3D length of the edge node -> next node */
    int32_t *host_offsets;       /* pattern vertex -> its nodes (CSR) */
    int32_t *host_nodes;
} ww_wires;

static void wires_free(ww_wires *w)
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
            int32_t e = find_edge(w->keys, t->edge_count, curve->vertices[i - 1], v);
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
            w->length[node] = distance3(pattern->mesh->positions + 3 * host[loop[b]],
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
static pz_status wires_build(const pz_pattern *pattern, const pz_feature_curves *features, ww_wires *w, pz_ctx *ctx)
{
    memset(w, 0, sizeof *w);
    pz_status status = pz_topology_build(pattern->mesh, &w->topo, ctx);
    if (status)
        return status;
    const pz_topology *t = w->topo;
    uint8_t *cut = calloc((size_t)t->edge_count + 1, 1);
    w->keys = edge_keys(t);
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
        wires_free(w);
    return status;
}

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

typedef struct ww_heap_entry {
    double key;
    int32_t patch;
} ww_heap_entry;

static int heap_above(const ww_heap_entry *x, const ww_heap_entry *y)
{
    return x->key > y->key || (x->key == y->key && x->patch < y->patch);
}

static int heap_push(ww_heap_entry **heap, size_t *capacity, int32_t *size, double key, int32_t patch)
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

static ww_heap_entry heap_pop(ww_heap_entry *h, int32_t *size)
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
        if (!heap_push(&heap, &capacity, &size, key[p] = shape_evidence(a, p), p))
            goto nomem;
    while (size > 0) {
        ww_heap_entry top = heap_pop(heap, &size);
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
                if (k != key[r] && !heap_push(&heap, &capacity, &size, key[r] = k, r))
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
static pz_status layout_wires(const ww_wires *w, const double *theta, uint8_t *placed, double *uv, pz_ctx *ctx)
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
            int32_t e = find_edge(w->keys, ne, w->node_host[first + b], w->node_host[first + (b + 1) % n]);
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
                int32_t e = find_edge(w->keys, ne, w->node_host[f0 + k], w->node_host[f0 + (k + 1) % n]);
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
                double wk = 1 / fmax(distance3(mesh->positions + 3 * v, mesh->positions + 3 * ring[k]), 1e-300);
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

/*
 * Interior vertices: sum_j w_ij (x_i - x_j) = 0 with the wires fixed (Eq. 11), one CHOLMOD solve.
 * mode: options->interior (0 cotangent weights, 1 the paper's 1/length weights, 2 the paper's relaxed
 * Gauss-Seidel, Eq. 12, which is otherwise the fallback when the factorization fails).
 */
static pz_status layout_interior(const pz_mesh *mesh, const pz_topology *t, int mode, const uint8_t *placed,
                                 double *uv, int *fallback, pz_ctx *ctx)
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
            weight[e] = 1 / fmax(distance3(mesh->positions + 3 * pz_he_from(t, h), mesh->positions + 3 * pz_he_to(t, h)),
                                 1e-300);
        }
    else
        pz_geom_cotan_weights(mesh, t, weight);
    cholmod_common cc;
    cholmod_start(&cc);
    cc.supernodal = CHOLMOD_SIMPLICIAL;
    cc.print = 0; /* a failed factorization falls back to Gauss-Seidel (Eq. 12) */
    cholmod_triplet *triplet = cholmod_allocate_triplet((size_t)n, (size_t)n, (size_t)(n + ne), -1, CHOLMOD_REAL, &cc);
    cholmod_dense *rhs = cholmod_zeros((size_t)n, 2, CHOLMOD_REAL, &cc);
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
    matrix = cholmod_triplet_to_sparse(triplet, at, &cc);
    if (matrix)
        factor = cholmod_analyze(matrix, &cc);
    if (factor)
        cholmod_factorize(matrix, factor, &cc);
    if (factor && cc.status == CHOLMOD_OK)
        x = cholmod_solve(CHOLMOD_A, factor, rhs, &cc);
    if (x && cc.status == CHOLMOD_OK) {
        const double *s = x->x;
        for (int32_t v = 0; v < nv; ++v)
            if (index[v] >= 0) {
                uv[2 * v] = s[index[v]];
                uv[2 * v + 1] = s[n + index[v]];
            }
    } else if (cc.status == CHOLMOD_OUT_OF_MEMORY) {
        status = pz_error(ctx, PZ_ERR_NOMEM, "wirewarp: out of memory in the interior solve");
    } else {
        *fallback = 1;  /* not positive definite (degenerate faces): the paper's iteration */
        gauss_seidel(mesh, t, placed, uv);
    }
done:
    cholmod_free_dense(&x, &cc);
    cholmod_free_factor(&factor, &cc);
    cholmod_free_sparse(&matrix, &cc);
    cholmod_free_dense(&rhs, &cc);
    cholmod_free_triplet(&triplet, &cc);
    cholmod_finish(&cc);
    free(index);
    free(weight);
    return status;
}

/* Eq. 26 over the wire edges, and the worst relative error. */
static void wire_length_error(const pz_mesh *mesh, const ww_wires *w, const double *uv, pz_wirewarp_result *r)
{
    const pz_topology *t = w->topo;
    double sum = 0, worst = 0;
    int32_t count = 0;
    for (int32_t e = 0; e < t->edge_count; ++e) {
        if (!w->wire_edge[e])
            continue;
        int32_t h = t->edge_halfedge[2 * e], a = pz_he_from(t, h), b = pz_he_to(t, h);
        double l3 = distance3(mesh->positions + 3 * a, mesh->positions + 3 * b);
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

/* ------------------------------------------------------------------------ */
/* Entry point                                                               */
/* ------------------------------------------------------------------------ */

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

static pz_status warp_angles(const pz_pattern *pattern, const ww_wires *w, const pz_wirewarp_options *options,
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

static pz_status check_pattern(const pz_pattern *pattern, double *uv, pz_ctx *ctx)
{
    if (!pattern || !pattern->mesh || !pattern->face_panel || !uv)
        return pz_error(ctx, PZ_ERR_USAGE, "wirewarp: no pattern or no output");
    for (int32_t f = 0; f < pattern->mesh->face_count; ++f)
        if (pattern->face_panel[f] < 0 || pattern->face_panel[f] >= pattern->panel_count)
            return pz_error(ctx, PZ_ERR_DATA, "wirewarp: face %d has panel %d out of range", f, pattern->face_panel[f]);
    return PZ_OK;
}

/*
 * Turns every piece about its centroid so that the 3D grain axis, projected
 * onto the faces and mapped into the plane, runs along +v on average
 * (area-weighted), as pz_param_lscm does: the warp/weft strains and the
 * orthotropic energy of the metrics are measured along u and v.
 */
static pz_status orient_to_grain(const pz_pattern *pattern, const double grain[3], double *uv, pz_ctx *ctx)
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

/* Injectivity of the result (pz_metrics_compute): flipped faces and boundary crossings. */
static pz_status measure_injectivity(const pz_pattern *pattern, const double *uv, pz_wirewarp_result *r, pz_ctx *ctx)
{
    pz_metrics *metrics = NULL;
    pz_status status = pz_metrics_compute(pattern, uv, 0, NULL, &metrics, ctx);
    if (status)
        return status;
    r->injective = metrics->injective;
    r->flipped_triangles = 0;
    for (int32_t p = 0; p < metrics->panel_count; ++p)
        r->flipped_triangles += metrics->panels[p].flipped_triangles;
    pz_metrics_free(&metrics);
    return PZ_OK;
}

/*
 * Cotangent weights can be negative, and on a far-from-developable patch
 * (whose warped boundary encloses much less area than the surface) they can
 * fold the interior. The paper's positive 1/length weights make every
 * interior vertex a convex combination of its neighbours (Tutte: injective
 * inside a convex boundary), so they are tried and kept when they flip fewer
 * faces. The wires are not moved, so E_len is unchanged.
 */
static pz_status retry_inverse_length(const pz_pattern *pattern, const ww_wires *w, const uint8_t *placed, double *uv,
                                      pz_wirewarp_result *r, pz_ctx *ctx)
{
    size_t bytes = (size_t)pattern->mesh->vertex_count * 2 * sizeof(double);
    double *cotangent = malloc(bytes + 1);
    if (!cotangent)
        return pz_error(ctx, PZ_ERR_NOMEM, "wirewarp: out of memory");
    memcpy(cotangent, uv, bytes);
    pz_wirewarp_result first = *r;
    double start = pz_seconds();
    pz_status status = layout_interior(pattern->mesh, w->topo, 1, placed, uv, &r->interior_fallback, ctx);
    if (!status)
        status = measure_injectivity(pattern, uv, r, ctx);
    r->interior_ms += 1e3 * (pz_seconds() - start);
    if (!status && r->flipped_triangles < first.flipped_triangles) {
        r->interior_inverse_length = 1;
    } else if (!status) {
        double ms = r->interior_ms;
        *r = first;
        r->interior_ms = ms;
        memcpy(uv, cotangent, bytes);
    }
    free(cotangent);
    return status;
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

static double face_det(const pz_mesh *mesh, const double *uv, int32_t f)
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
        if (!(face_det(mesh, uv, star[i]) > 0)) { /* round-off at a sliver kernel: keep the old place */
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
            if (!(face_det(mesh, uv, f) > 0)) {
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

/* The untangling step of pz_param_wirewarp: repair, then measure again. */
static pz_status untangle(const pz_pattern *pattern, const uint8_t *placed, double *uv, pz_wirewarp_result *r,
                          pz_ctx *ctx)
{
    int32_t moves = pz_param_untangle(pattern->mesh, placed, uv);
    if (moves < 0)
        return pz_error(ctx, PZ_ERR_NOMEM, "wirewarp: out of memory while untangling");
    r->untangled_vertices = moves;
    pz_status status = moves ? measure_injectivity(pattern, uv, r, ctx) : PZ_OK;
    if (!status && r->flipped_triangles > 0)
        r->best_effort = 1; /* folded: no injective layout of the interior was found with these wires */
    return status;
}

/* One WireWarping of the pattern; origin (may be NULL) maps features' indices to the caller's (trimming). */
static pz_status wirewarp_once(const pz_pattern *pattern, const pz_wirewarp_options *options,
                               const pz_feature_curves *features, const int32_t *origin, double *uv,
                               pz_wirewarp_result *r, pz_ctx *ctx)
{
    memset(r, 0, sizeof *r);
    pz_status status = check_pattern(pattern, uv, ctx);
    if (status)
        return status;
    const pz_mesh *mesh = pattern->mesh;
    double start = pz_seconds();
    ww_wires w;
    if ((status = wires_build(pattern, features, &w, ctx)))
        return status;
    r->wire_patch_count = w.patch_count;
    r->wire_node_count = w.node_count;
    double *theta = malloc((size_t)w.node_count * sizeof(double) + 1);
    uint8_t *placed = calloc((size_t)mesh->vertex_count + 1, 1);
    int32_t *offsets = NULL, *order = NULL;
    if (!theta || !placed) {
        status = pz_error(ctx, PZ_ERR_NOMEM, "wirewarp: out of memory");
        goto done;
    }
    memset(uv, 0, (size_t)mesh->vertex_count * 2 * sizeof(double));
    if ((status = warp_angles(pattern, &w, options, features, origin, theta, r, ctx)))
        goto done;
    double angles_done = pz_seconds();
    r->angle_ms = 1e3 * (angles_done - start);
    if ((status = layout_wires(&w, theta, placed, uv, ctx)))
        goto done;
    double wires_done = pz_seconds();
    r->layout_ms = 1e3 * (wires_done - angles_done);
    int interior = options ? options->interior : 0;
    r->interior_inverse_length = interior >= 1;  /* Eq. 12 iterates with the same 1/length weights */
    if ((status = layout_interior(mesh, w.topo, interior, placed, uv, &r->interior_fallback, ctx)))
        goto done;
    r->interior_ms = 1e3 * (pz_seconds() - wires_done);
    double up[3] = {0, 0, 1};
    if ((status = orient_to_grain(pattern, options && options->grain_given ? options->grain : up, uv, ctx)))
        goto done;
    if ((status = pz_param_panel_faces(pattern, &offsets, &order, ctx)))
        goto done;
    pz_param_layout(pattern, offsets, order, uv);
    wire_length_error(mesh, &w, uv, r);
    if ((status = measure_injectivity(pattern, uv, r, ctx)))
        goto done;
    if (!r->injective && !r->interior_inverse_length)
        status = retry_inverse_length(pattern, &w, placed, uv, r, ctx);
    if (!status && r->flipped_triangles > 0)
        status = untangle(pattern, placed, uv, r, ctx);
done:
    free(offsets);
    free(order);
    free(theta);
    free(placed);
    wires_free(&w);
    return status;
}

/*
 * Graceful degradation for dangling curves. When faces stay flipped next to
 * the free end (tip) of a feature curve that stops inside its panel, the
 * interior cannot follow the rigid wire there (see pz_param_untangle): the
 * tip's last edge is given up (the vertex becomes interior again) and the
 * panel warped again, until no face flips or no tip near a flip is left.
 * The shortened curves still keep their lengths exactly; the dropped edges
 * are counted in result->trimmed_feature_edges and best_effort is set.
 */
#define TRIM_ROUNDS 200

/* Marks the vertices of flipped faces and of the faces touching them. */
static void mark_near_flips(const pz_mesh *mesh, const double *uv, uint8_t *near)
{
    memset(near, 0, (size_t)mesh->vertex_count);
    for (int32_t f = 0; f < mesh->face_count; ++f)
        if (!(face_det(mesh, uv, f) > 0))
            for (int k = 0; k < 3; ++k)
                near[mesh->faces[3 * f + k]] = 1;
    for (int32_t f = 0; f < mesh->face_count; ++f) {
        const int32_t *c = mesh->faces + 3 * f;
        if ((near[c[0]] | near[c[1]] | near[c[2]]) & 1)
            near[c[0]] |= 2, near[c[1]] |= 2, near[c[2]] |= 2;
    }
}

/* Drops the dangling ends of `curves` that lie near a flip; returns the edges dropped. A curve left
 * with one vertex is removed; origin (curve -> the caller's index) follows. */
static int32_t trim_dangling_ends(const pz_mesh *mesh, const uint8_t *on_boundary, const uint8_t *near,
                                  int32_t *uses, pz_feature_curves *curves, int32_t *origin)
{
    int32_t dropped = 0;
    memset(uses, 0, (size_t)mesh->vertex_count * sizeof(int32_t));
    for (int32_t c = 0; c < curves->curve_count; ++c)
        for (int32_t i = 0; i < curves->curves[c].vertex_count; ++i)
            ++uses[curves->curves[c].vertices[i]];
    for (int32_t c = 0; c < curves->curve_count; ++c) {
        pz_feature_curve *curve = &curves->curves[c];
        for (int end = 0; end < 2 && curve->vertex_count >= 2; ++end) {
            int32_t at = end ? curve->vertex_count - 1 : 0, tip = curve->vertices[at];
            if (on_boundary[tip] || uses[tip] != 1 || !near[tip])
                continue;
            if (end == 0) {
                memmove(curve->vertices, curve->vertices + 1, (size_t)(curve->vertex_count - 1) * sizeof(int32_t));
                if (curve->turning)
                    memmove(curve->turning, curve->turning + 1, (size_t)(curve->vertex_count - 1) * sizeof(double));
            }
            --curve->vertex_count;
            ++dropped;
        }
    }
    int32_t kept = 0;
    for (int32_t c = 0; c < curves->curve_count; ++c) {
        if (curves->curves[c].vertex_count >= 2) {
            origin[kept] = origin[c];
            curves->curves[kept++] = curves->curves[c];
        } else {
            free(curves->curves[c].vertices);
            free(curves->curves[c].turning);
        }
    }
    curves->curve_count = kept;
    return dropped;
}

static pz_feature_curves *copy_curves(const pz_feature_curves *from)
{
    pz_feature_curves *to = calloc(1, sizeof *to);
    if (!to || !(to->curves = calloc((size_t)from->curve_count + 1, sizeof *to->curves))) {
        free(to);
        return NULL;
    }
    for (int32_t c = 0; c < from->curve_count; ++c, ++to->curve_count) {
        const pz_feature_curve *src = &from->curves[c];
        pz_feature_curve *dst = &to->curves[c];
        *dst = *src;
        dst->vertices = malloc((size_t)src->vertex_count * sizeof(int32_t) + 1);
        dst->turning = src->turning ? malloc((size_t)src->vertex_count * sizeof(double) + 1) : NULL;
        if (!dst->vertices || (src->turning && !dst->turning)) {
            ++to->curve_count; /* so that this curve's arrays are freed too */
            pz_feature_curves_free(&to);
            return NULL;
        }
        memcpy(dst->vertices, src->vertices, (size_t)src->vertex_count * sizeof(int32_t));
        if (src->turning)
            memcpy(dst->turning, src->turning, (size_t)src->vertex_count * sizeof(double));
    }
    return to;
}

pz_status pz_param_wirewarp(const pz_pattern *pattern, const pz_wirewarp_options *options,
                            const pz_feature_curves *features, double *uv, pz_wirewarp_result *result, pz_ctx *ctx)
{
    pz_wirewarp_result local;
    pz_wirewarp_result *r = result ? result : &local;
    pz_status status = wirewarp_once(pattern, options, features, NULL, uv, r, ctx);
    if (status || r->flipped_triangles == 0 || !features || features->curve_count == 0)
        return status;
    const pz_mesh *mesh = pattern->mesh;
    pz_topology *topology = NULL;
    pz_feature_curves *trimmed = copy_curves(features);
    uint8_t *near = malloc((size_t)mesh->vertex_count + 1);
    int32_t *uses = malloc((size_t)mesh->vertex_count * sizeof(int32_t) + 1);
    int32_t *origin = malloc((size_t)features->curve_count * sizeof(int32_t) + 1);
    if (!trimmed || !near || !uses || !origin) {
        status = pz_error(ctx, PZ_ERR_NOMEM, "wirewarp: out of memory");
        goto done;
    }
    if ((status = pz_topology_build(mesh, &topology, ctx)))
        goto done;
    for (int32_t c = 0; c < features->curve_count; ++c)
        origin[c] = c;
    int32_t total = 0;
    for (int round = 0; round < TRIM_ROUNDS && r->flipped_triangles > 0; ++round) {
        mark_near_flips(mesh, uv, near);
        int32_t dropped = trim_dangling_ends(mesh, topology->vertex_on_boundary, near, uses, trimmed, origin);
        if (!dropped)
            break;
        total += dropped;
        if ((status = wirewarp_once(pattern, options, trimmed, origin, uv, r, ctx)))
            goto done;
    }
    r->trimmed_feature_edges = total;
    r->best_effort |= total > 0;
done:
    pz_topology_free(&topology);
    pz_feature_curves_free(&trimmed);
    free(near);
    free(uses);
    free(origin);
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
        double d = distance3(pos + 3 * s->by_x[i], q);
        if (d < best_d) {
            best_d = d;
            best = s->by_x[i];
        }
    }
    for (int32_t i = lo - 1; i >= 0 && q[0] - pos[3 * s->by_x[i]] < best_d; --i) {
        double d = distance3(pos + 3 * s->by_x[i], q);
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
    ok = heap_push(&s->heap, &s->heap_cap, &size, -0.0, a);
    while (ok && size > 0) {
        ww_heap_entry top = heap_pop(s->heap, &size);
        int32_t v = top.patch;
        if (-top.key > s->dist[v])
            continue;
        if (v == b) {
            found = 1;
            break;
        }
        for (int32_t k = s->adj_offsets[v]; k < s->adj_offsets[v + 1]; ++k) {
            int32_t u = s->adj[k];
            double d = s->dist[v] + distance3(pos + 3 * v, pos + 3 * u);
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
                if (!heap_push(&s->heap, &s->heap_cap, &size, -d, u))
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
            sum += distance3(mesh->positions + 3 * pz_he_from(t, h), mesh->positions + 3 * pz_he_to(t, h));
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

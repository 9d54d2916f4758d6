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
 * Set-up and solve (pz_wirewarp_setup, pz_wirewarp_solve): the wires,
 * wire-patches and wire-nodes depend only on the pattern and the feature
 * curves and are built once; a solve (any options) warps the angles, lays
 * out the wires and the interior, whose CHOLMOD symbolic analysis is kept
 * for the next interior solve with the same wires (the 1/length retry, the
 * next solve). Trimming dangling ends changes the wires, so each trimming
 * round builds its own. Files: param/wirewarp_internal.h.
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
#include "param/wirewarp_internal.h"

#include <stdlib.h>
#include <string.h>

static pz_status check_pattern(const pz_pattern *pattern, const double *uv, pz_ctx *ctx)
{
    if (!pattern || !pattern->mesh || !pattern->face_panel || !uv)
        return pz_error(ctx, PZ_ERR_USAGE, "wirewarp: no pattern or no output");
    for (int32_t f = 0; f < pattern->mesh->face_count; ++f)
        if (pattern->face_panel[f] < 0 || pattern->face_panel[f] >= pattern->panel_count)
            return pz_error(ctx, PZ_ERR_DATA, "wirewarp: face %d has panel %d out of range", f, pattern->face_panel[f]);
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
                                      ww_interior *interior, pz_wirewarp_result *r, pz_ctx *ctx)
{
    size_t bytes = (size_t)pattern->mesh->vertex_count * 2 * sizeof(double);
    double *cotangent = malloc(bytes + 1);
    if (!cotangent)
        return pz_error(ctx, PZ_ERR_NOMEM, "wirewarp: out of memory");
    memcpy(cotangent, uv, bytes);
    pz_wirewarp_result first = *r;
    double start = pz_seconds();
    pz_status status = ww_layout_interior(pattern->mesh, w->topo, 1, placed, uv, &r->interior_fallback, interior, ctx);
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

/* One WireWarping of the pattern with its wires w (built in wires_ms) and the interior's kept analysis;
 * origin (may be NULL) maps features' indices to the caller's (trimming). */
static pz_status wirewarp_once(const pz_pattern *pattern, const pz_wirewarp_options *options, const ww_wires *w,
                               double wires_ms, ww_interior *interior, const pz_feature_curves *features,
                               const int32_t *origin, double *uv, pz_wirewarp_result *r, pz_ctx *ctx)
{
    memset(r, 0, sizeof *r);
    pz_status status = check_pattern(pattern, uv, ctx);
    if (status)
        return status;
    const pz_mesh *mesh = pattern->mesh;
    double start = pz_seconds();
    r->wire_patch_count = w->patch_count;
    r->wire_node_count = w->node_count;
    double *theta = malloc((size_t)w->node_count * sizeof(double) + 1);
    uint8_t *placed = calloc((size_t)mesh->vertex_count + 1, 1);
    int32_t *offsets = NULL, *order = NULL;
    if (!theta || !placed) {
        status = pz_error(ctx, PZ_ERR_NOMEM, "wirewarp: out of memory");
        goto done;
    }
    memset(uv, 0, (size_t)mesh->vertex_count * 2 * sizeof(double));
    if ((status = ww_warp_angles(pattern, w, options, features, origin, theta, r, ctx)))
        goto done;
    double angles_done = pz_seconds();
    r->angle_ms = wires_ms + 1e3 * (angles_done - start);
    if ((status = pz_check_cancel(ctx, "wirewarp")) || (status = ww_layout_wires(w, theta, placed, uv, ctx)))
        goto done;
    double wires_done = pz_seconds();
    r->layout_ms = 1e3 * (wires_done - angles_done);
    int mode = options ? options->interior : 0;
    r->interior_inverse_length = mode >= 1;  /* Eq. 12 iterates with the same 1/length weights */
    if ((status = ww_layout_interior(mesh, w->topo, mode, placed, uv, &r->interior_fallback, interior, ctx)))
        goto done;
    r->interior_ms = 1e3 * (pz_seconds() - wires_done);
    double up[3] = {0, 0, 1};
    if ((status = ww_orient_to_grain(pattern, options && options->grain_given ? options->grain : up, uv, ctx)))
        goto done;
    if ((status = pz_param_panel_faces(pattern, &offsets, &order, ctx)))
        goto done;
    pz_param_layout(pattern, offsets, order, uv);
    ww_wire_length_error(mesh, w, uv, r);
    if ((status = measure_injectivity(pattern, uv, r, ctx)))
        goto done;
    if (!r->injective && !r->interior_inverse_length)
        status = retry_inverse_length(pattern, w, placed, uv, interior, r, ctx);
    if (!status && r->flipped_triangles > 0)
        status = untangle(pattern, placed, uv, r, ctx);
done:
    free(offsets);
    free(order);
    free(theta);
    free(placed);
    return status;
}

/* wirewarp_once with the wires of `features` built for it (a trimming round). */
static pz_status wirewarp_trimmed(const pz_pattern *pattern, const pz_wirewarp_options *options,
                                  const pz_feature_curves *features, const int32_t *origin, double *uv,
                                  pz_wirewarp_result *r, pz_ctx *ctx)
{
    ww_wires w;
    ww_interior interior;
    memset(&interior, 0, sizeof interior);
    double start = pz_seconds();
    pz_status status = ww_wires_build(pattern, features, &w, ctx);
    if (!status)
        status = wirewarp_once(pattern, options, &w, 1e3 * (pz_seconds() - start), &interior, features, origin, uv,
                               r, ctx);
    ww_wires_free(&w);
    ww_interior_free(&interior);
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
        if (!(ww_face_det(mesh, uv, f) > 0))
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

/* The solver of param.h: the set-up (pattern, feature curves, wires) and the interior's kept analysis. */
struct pz_wirewarp_solver {
    const pz_pattern *pattern;
    pz_feature_curves *features;     /* a copy, NULL without feature curves */
    ww_wires wires;
    double wires_ms;                 /* counted into the first round's angle_ms, as before the split */
    ww_interior interior;
};

void pz_wirewarp_solver_free(pz_wirewarp_solver **solver)
{
    if (!solver || !*solver)
        return;
    ww_wires_free(&(*solver)->wires);
    ww_interior_free(&(*solver)->interior);
    pz_feature_curves_free(&(*solver)->features);
    free(*solver);
    *solver = NULL;
}

pz_status pz_wirewarp_setup(const pz_pattern *pattern, const pz_feature_curves *features, pz_wirewarp_solver **out,
                            pz_ctx *ctx)
{
    if (!out)
        return pz_error(ctx, PZ_ERR_USAGE, "wirewarp: no solver to set up");
    *out = NULL;
    static const double no_uv[2];
    pz_status status = check_pattern(pattern, no_uv, ctx); /* the uv is the solve's */
    if (status)
        return status;
    pz_wirewarp_solver *solver = calloc(1, sizeof *solver);
    if (!solver)
        return pz_error(ctx, PZ_ERR_NOMEM, "wirewarp: out of memory");
    solver->pattern = pattern;
    double start = pz_seconds();
    status = ww_wires_build(pattern, features, &solver->wires, ctx);
    if (!status && features && features->curve_count > 0 && !(solver->features = copy_curves(features)))
        status = pz_error(ctx, PZ_ERR_NOMEM, "wirewarp: out of memory");
    if (status) {
        pz_wirewarp_solver_free(&solver);
        return status;
    }
    solver->wires_ms = 1e3 * (pz_seconds() - start);
    *out = solver;
    return PZ_OK;
}

pz_status pz_wirewarp_solve(pz_wirewarp_solver *solver, const pz_wirewarp_options *options, double *uv,
                            pz_wirewarp_result *result, pz_ctx *ctx)
{
    if (!solver)
        return pz_error(ctx, PZ_ERR_USAGE, "wirewarp: no solver");
    pz_wirewarp_result local;
    pz_wirewarp_result *r = result ? result : &local;
    const pz_pattern *pattern = solver->pattern;
    const pz_feature_curves *features = solver->features;
    pz_status status = wirewarp_once(pattern, options, &solver->wires, solver->wires_ms, &solver->interior, features,
                                     NULL, uv, r, ctx);
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
        if ((status = pz_check_cancel(ctx, "wirewarp")))
            goto done;
        mark_near_flips(mesh, uv, near);
        int32_t dropped = trim_dangling_ends(mesh, topology->vertex_on_boundary, near, uses, trimmed, origin);
        if (!dropped)
            break;
        total += dropped;
        if ((status = wirewarp_trimmed(pattern, options, trimmed, origin, uv, r, ctx)))
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

pz_status pz_param_wirewarp(const pz_pattern *pattern, const pz_wirewarp_options *options,
                            const pz_feature_curves *features, double *uv, pz_wirewarp_result *result, pz_ctx *ctx)
{
    if (result)
        memset(result, 0, sizeof *result);
    if (!uv)
        return check_pattern(pattern, uv, ctx);
    pz_wirewarp_solver *solver = NULL;
    pz_status status = pz_wirewarp_setup(pattern, features, &solver, ctx);
    if (!status)
        status = pz_wirewarp_solve(solver, options, uv, result, ctx);
    pz_wirewarp_solver_free(&solver);
    return status;
}

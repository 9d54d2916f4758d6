/*
 * param/springmass_match.c -- seam matching of the spring-mass back-end: the
 * facing segments of every seam and dart get equal lengths, each outline is
 * refitted to them exactly in angle space and the interior released again.
 * The method: param/springmass.c.
 *
 * SPDX-License-Identifier: GPL-3.0-or-later
 */
#include "param/springmass_internal.h"

#include <stdlib.h>
#include <string.h>

/* ------------------------------------------------------------------------ */
/* Seam matching                                                             */
/* ------------------------------------------------------------------------ */


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
int32_t sm_build_links(const pz_pattern *pattern, int32_t *const *vertex_maps, const sm_panel *panels,
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
int sm_panel_loop(sm_panel *p, pz_ctx *ctx)
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
    int32_t flipped = sm_flipped_faces(p);
    if (flipped > 0)
        flipped = pz_param_untangle(p->mesh, fixed, copy) < 0 ? -1 : sm_flipped_faces(p);
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
    if ((*status = sm_panel_release(p, outcome, ctx)))
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
pz_status sm_match_seams(sm_panel *panels, int32_t panel_count, const sm_link *links, int32_t link_count,
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
double sm_worst_mismatch(const sm_panel *panels, const sm_link *links, int32_t link_count, int32_t curve_count)
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

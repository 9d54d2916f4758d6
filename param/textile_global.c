/*
 * param/textile_global.c -- the global step of the textile parameterization:
 * each panel's two coordinate systems assembled from the local step's
 * shares, factorized when needed (numerically only: the symbolic analysis
 * is the set-up's) and solved by preconditioned conjugate gradients or
 * directly; and the projection that keeps a step from turning
 * the panels. The design: param/textile_internal.h.
 *
 * SPDX-License-Identifier: GPL-3.0-or-later
 */
#include "param/textile_internal.h"

#include <math.h>
#include <omp.h>
#include <string.h>

/* ------------------------------------------------------------------------ */
/* Global step                                                               */
/* ------------------------------------------------------------------------ */

/* y = A x for the upper-stored symmetric matrix. */
static void symmetric_product(const cholmod_sparse *matrix, const double *x, double *y)
{
    const int *colp = matrix->p, *rows = matrix->i;
    const double *values = matrix->x;
    size_t n = matrix->ncol;
    memset(y, 0, n * sizeof(double));
    for (size_t j = 0; j < n; ++j) {
        double xj = x[j], sum = 0;
        int end = colp[j + 1] - 1; /* the diagonal */
        for (int e = colp[j]; e < end; ++e) {
            y[rows[e]] += values[e] * xj;
            sum += values[e] * x[rows[e]];
        }
        y[j] += sum + values[end] * xj;
    }
}

/* z = A^-1 g with the coordinate's current preconditioner, g = its
 * textile_grain_gradient, for textile_project_grain_turn (the residual vector is free
 * outside pcg_solve). */
static int grain_response(const panel_system *system, coordinate_solver *solver, cholmod_factor *factor)
{
    memcpy(solver->residual->x, solver->grain_gradient, (size_t)system->vertex_count * sizeof(double));
    if (!cholmod_solve2(CHOLMOD_A, factor, solver->residual, NULL, &solver->solution, NULL, &solver->work_y,
                        &solver->work_e, &solver->common))
        return solver->common.status ? solver->common.status : -1;
    memcpy(solver->grain_response, solver->solution->x, (size_t)system->vertex_count * sizeof(double));
    solver->response_ready = 1;
    return CHOLMOD_OK;
}

/*
 * The global step's solve: conjugate gradients preconditioned with the
 * factor of an earlier iteration's matrix, from the current coordinates,
 * until r^T M^-1 r (the preconditioner's estimate of twice what the
 * quadratic can still decrease) fell to PCG_REDUCTION of its start or below
 * PCG_MODEL_TOLERANCE of x^T A x, at most max_steps / 2 steps. The matrix
 * changes only through the stretch terms, and on a distorted mesh mostly on
 * the few faces far from their 3D size: M^-1 A is then the identity plus a
 * few outlying eigenvalues, which conjugate gradients remove in a few steps
 * (one steepest-descent step could not: measured on camelhead, docs/param.md
 * "Speed against libigl"). Every step lowers the quadratic (A is SPD), so a
 * step is never rejected; the Euclidean residual is no measure of that (it
 * rose by 1.4-330x on steps that lowered the quadratic, on camelhead, when
 * the old test rejected them). Nothing is done when the residual is already
 * below PCG_TOLERANCE of the right-hand side. The factor is refreshed for
 * the next iteration when this solve needed more than a quarter of what one
 * factorization costs in steps (max_steps, from flop counts: about 7 at 1K
 * vertices, 65 at 100K, clamped to 4..60): it has gone stale. Returns 0 only
 * when the preconditioner is unusable (not positive on r: solve_coordinate
 * then factorizes and solves directly).
 */
#define PCG_TOLERANCE 1e-8
#define PCG_REDUCTION 1e-1
#define ONE_STEP_REDUCTION 1e-2 /* the one-step rules' residual reduction (the old rule) */
#define PCG_EXACT_SLACK 0.2
/* demand_exact_solves (a stalled line search, textile_solve.c): the next solve runs to this
 * reduction, with up to one factorization's worth of steps, instead of factorizing both coordinates
 * (on the 20K hemisphere the retry's two factorizations were a fifth of the iterations' time; the
 * fresh factor from the last refactorization converges in a few steps). */
#define PCG_EXACT_REDUCTION 1e-12
#define ONE_STEP_MIN_VERTICES 50000
#define PCG_MODEL_TOLERANCE 1e-9
/* The start of a preconditioned solve: the iterate (uv's column k) gathered into `current`, the
 * residual r = b - A x into `residual`, its squared norm and x^T A x. Returns 1 when the residual is
 * already below PCG_TOLERANCE of the right-hand side (nothing to do). */
static int start_residual(const panel_system *system, coordinate_solver *solver, int k, const double *uv,
                          double *r_norm, double *scale)
{
    int32_t n = system->vertex_count;
    double *b = solver->rhs->x, *r = solver->residual->x, *ap = solver->product, *x = solver->current;
    for (int32_t l = 0; l < n; ++l)
        x[l] = uv[2 * system->vertices[l] + k];
    symmetric_product(solver->matrix, x, ap);
    double b_norm = 0;
    *r_norm = *scale = 0;
    for (int32_t l = 0; l < n; ++l) {
        r[l] = b[l] - ap[l];
        b_norm += b[l] * b[l];
        *r_norm += r[l] * r[l];
        *scale += x[l] * ap[l];
    }
    return *r_norm <= PCG_TOLERANCE * PCG_TOLERANCE * fmax(b_norm, 1e-300);
}

/* After one step on a large panel: the old rule, steps to ONE_STEP_REDUCTION at the rate this step cut the
 * residual (r, of squared norm r_norm before it) over half a factorization's cost. Used only to decide
 * when to refactorize, which on the smooth 200K hemisphere it does once in 20 iterations. */
static int one_step_stale(const double *r, int32_t n, double r_norm, int max_steps)
{
    double new_norm = 0;
    for (int32_t l = 0; l < n; ++l)
        new_norm += r[l] * r[l];
    return !(new_norm < r_norm) || 2 * log(ONE_STEP_REDUCTION) / log(new_norm / r_norm) > max_steps / 2;
}

static int pcg_solve(const panel_system *system, coordinate_solver *solver, cholmod_factor *factor, int k, double *uv)
{
    int32_t n = system->vertex_count;
    double *r = solver->residual->x, *ap = solver->product, *p = solver->direction, *x = solver->current;
    double r_norm, scale;
    if (start_residual(system, solver, k, uv, &r_norm, &scale))
        return 1;
    /* Panels of ONE_STEP_MIN_VERTICES take one step, as before: on the 200K hemisphere checking it cost
     * as many solves again for no lower energy (docs/param.md, "Speed against libigl"). */
    int budget = n >= ONE_STEP_MIN_VERTICES ? 1 : solver->max_steps / 2 > 1 ? solver->max_steps / 2 : 1;
    int exact = solver->exact;
    double reduction = exact ? PCG_EXACT_REDUCTION : PCG_REDUCTION;
    solver->exact = 0;
    if (exact)
        budget = solver->max_steps;
    int steps = 0;
    double rz = 0, rz_start = 0;
    for (;;) {
        ++solver->pcg_solves;
        if (!cholmod_solve2(CHOLMOD_A, factor, solver->residual, NULL, &solver->solution, NULL, &solver->work_y,
                            &solver->work_e, &solver->common))
            return 0;
        const double *z = solver->solution->x;
        double rz_new = 0;
        for (int32_t l = 0; l < n; ++l)
            rz_new += r[l] * z[l];
        if (steps == 0) {
            if (!(rz_new > 0))
                return 0;
            rz_start = rz_new;
        }
        if (rz_new <= PCG_MODEL_TOLERANCE * scale || rz_new <= reduction * rz_start || steps == budget)
            break;
        double beta = steps == 0 ? 0 : rz_new / rz; /* p's old contents are garbage at step 0 (0 * NaN) */
        for (int32_t l = 0; l < n; ++l)
            p[l] = steps == 0 ? z[l] : z[l] + beta * p[l];
        rz = rz_new;
        symmetric_product(solver->matrix, p, ap);
        double pap = 0;
        for (int32_t l = 0; l < n; ++l)
            pap += p[l] * ap[l];
        if (!(pap > 0))
            break;
        double alpha = rz / pap;
        for (int32_t l = 0; l < n; ++l) {
            x[l] += alpha * p[l];
            r[l] -= alpha * ap[l];
        }
        /* alpha is z^T M z / z^T A z: near 1, M is A along the step and it
         * was nearly exact; checking that would cost another solve. */
        if (++steps == budget || (steps == 1 && !exact && fabs(alpha - 1) <= PCG_EXACT_SLACK))
            break;
    }
    /* An exact solve that used its whole budget: the factor has gone stale. */
    if (exact ? steps == budget
              : budget > 1 ? 4 * steps > solver->max_steps : one_step_stale(r, n, r_norm, solver->max_steps))
        solver->refactor = 1;
    for (int32_t l = 0; l < n; ++l)
        uv[2 * system->vertices[l] + k] = x[l];
    return 1;
}

/*
 * With a strain goal (panelize run, the segmentation's evaluations): the
 * solve of the revision before issue 17, one preconditioned step, rejected
 * (0: solve_coordinate factorizes and solves directly, backing off from PCG
 * 1, 2, 4, ... 16 times on repeated failures) when the Euclidean residual
 * did not fall, the factor refreshed when at this step's rate a 1e-2
 * reduction would take more than half a factorization. That test is wrong
 * as a test of the step (pcg_solve says why), but with a strain goal the
 * reweighting changes the matrix by up to 4x per face and iteration, and the
 * exact solves the rejections bring are what those runs were tuned with:
 * conjugate gradients there ended the 1,200-face hemisphere at strain 0.158
 * against a goal of 0.01 (under 0.1 before) and changed the segmentation of
 * the test garments (docs/param.md, "Speed against libigl").
 */
static int one_step_solve(const panel_system *system, coordinate_solver *solver, cholmod_factor *factor, int k,
                          double *uv)
{
    int32_t n = system->vertex_count;
    double *r = solver->residual->x, *ap = solver->product, *current = solver->current;
    double r_norm, scale;
    if (start_residual(system, solver, k, uv, &r_norm, &scale))
        return 1;
    if (!cholmod_solve2(CHOLMOD_A, factor, solver->residual, NULL, &solver->solution, NULL, &solver->work_y,
                        &solver->work_e, &solver->common))
        return 0;
    const double *z = solver->solution->x;
    double rz = 0;
    for (int32_t l = 0; l < n; ++l)
        rz += r[l] * z[l];
    /* r^T M^-1 r estimates what the quadratic can still decrease; x^T A x
     * is its scale (the size of the targets). */
    if (rz <= PCG_MODEL_TOLERANCE * scale)
        return 1;
    symmetric_product(solver->matrix, z, ap);
    double zaz = 0;
    for (int32_t l = 0; l < n; ++l)
        zaz += z[l] * ap[l];
    if (!(zaz > 0))
        return 0;
    double alpha = rz / zaz, new_norm = 0;
    for (int32_t l = 0; l < n; ++l) {
        double residual = r[l] - alpha * ap[l];
        new_norm += residual * residual;
    }
    if (!(new_norm < r_norm))
        return 0;
    /* Steps to ONE_STEP_REDUCTION at this rate (squared norms). */
    if (2 * log(ONE_STEP_REDUCTION) / log(new_norm / r_norm) > solver->max_steps / 2)
        solver->refactor = 1;
    for (int32_t l = 0; l < n; ++l)
        uv[2 * system->vertices[l] + k] = current[l] + alpha * z[l];
    ++solver->pcg_solves;
    return 1;
}

/* Assembles coordinate k's system of one panel from the local step's face
 * shares, the seam segments and the seam and dart pulls at uv. */
static void assemble_coordinate(const textile_state *state, int32_t panel, int k, const double *uv)
{
    const pz_mesh *mesh = state->pattern->mesh;
    panel_system *system = &state->panels[panel];
    coordinate_solver *solver = &system->solver[k];
    cholmod_sparse *matrix = solver->matrix;
    double *values = matrix->x, *rhs = solver->rhs->x;
    const int *colp = matrix->p;
    int32_t n = system->vertex_count;
    memset(values, 0, (size_t)colp[n] * sizeof(double));
    memset(rhs, 0, (size_t)n * sizeof(double));
    const int32_t *faces = state->order + state->offsets[panel];
    int32_t count = state->offsets[panel + 1] - state->offsets[panel];
    for (int32_t i = 0; i < count; ++i) {
        int32_t f = faces[i];
        const int32_t *face = mesh->faces + 3 * f;
        const face_terms *terms = &state->terms[f];
        const int32_t *slot = system->slots + 6 * i;
        for (int e = 0; e < 6; ++e)
            values[slot[e]] += terms->value[k][e];
        for (int a = 0; a < 3; ++a)
            rhs[state->vertex_local[face[a]]] += terms->rhs[k][a];
    }
    for (int32_t i = 0; i < system->segment_count; ++i) {
        int32_t g = system->segment_ids[i];
        const int32_t *ends = state->segment_ends + 2 * g;
        int32_t a = state->vertex_local[ends[0]], b = state->vertex_local[ends[1]];
        if (a == b || (state->seams_open && g < state->seam_segment_end))
            continue;
        double w = state->segment_weight[g], t = w * state->segment_target[2 * g + k];
        values[system->segment_slots[i]] -= w;
        values[colp[a + 1] - 1] += w;
        values[colp[b + 1] - 1] += w;
        rhs[b] += t;
        rhs[a] -= t;
    }
    double reg = state->regularization;
    for (int32_t l = 0; l < n; ++l) {
        int32_t v = system->vertices[l];
        values[colp[l + 1] - 1] += state->pull_weight[v] + reg; /* the diagonal ends each upper column */
        rhs[l] += state->pull_target[2 * v + k] + reg * uv[2 * v + k];
    }
    if (state->project_grain)
        textile_grain_gradient(state, panel, k, uv, solver->grain_gradient);
}

/*
 * Factorizes coordinate k's matrix when this iteration needs it: the first
 * time (u only: v borrows u's factor until it needs its own), when the
 * factor went stale or a PCG step failed (pcg_solve), and during the
 * back-off after failures. Returns a CHOLMOD status.
 */
static int factorize_when_needed(panel_system *system, int k)
{
    coordinate_solver *solver = &system->solver[k];
    int needed = solver->direct_runs > 0 || solver->refactor || (!solver->factored && !solver->borrowing);
    if (!needed)
        return CHOLMOD_OK;
    if (solver->direct_runs > 0)
        --solver->direct_runs;
    pz_param_factorize(solver->matrix, solver->factor, &solver->common);
    if (solver->common.status != CHOLMOD_OK)
        return solver->common.status ? solver->common.status : -1;
    solver->factored = solver->fresh = 1;
    ++solver->factorizations;
    solver->refactor = solver->borrowing = 0;
    solver->response_ready = 0;
    if (k == 0 && system->solver[1].borrowing)
        system->solver[1].response_ready = 0;
    return CHOLMOD_OK;
}

/*
 * Solves coordinate k of one panel and writes it into uv: directly with a
 * factor made this iteration, otherwise preconditioned (pcg_solve; with a
 * strain goal one_step_solve). A solve that fails leaves uv alone and marks the coordinate
 * `failed` (textile_global_step then factorizes and solves it directly), and asks
 * for factorizations in the next iterations too: 1, 2, 4, ... 16 in a row
 * on repeated failures (large, uneven distortion: the face scan), so a
 * useless PCG costs at most about what it meant to save. Factors are only
 * read here, so v can borrow u's while both are solved in parallel.
 * Returns a CHOLMOD status.
 */
static int solve_coordinate(const textile_state *state, int32_t panel, int k, double *uv)
{
    panel_system *system = &state->panels[panel];
    coordinate_solver *solver = &system->solver[k];
    cholmod_factor *factor = solver->borrowing ? system->solver[0].factor : solver->factor;
    if (solver->fresh) {
        solver->fresh = solver->exact = 0; /* a direct solve is exact */
        if (!cholmod_solve2(CHOLMOD_A, factor, solver->rhs, NULL, &solver->solution, NULL, &solver->work_y,
                            &solver->work_e, &solver->common))
            return solver->common.status ? solver->common.status : -1;
        const double *x = solver->solution->x;
        for (int32_t l = 0; l < system->vertex_count; ++l)
            uv[2 * system->vertices[l] + k] = x[l];
    } else if (state->strain_limit > 0 ? one_step_solve(system, solver, factor, k, uv)
                                       : pcg_solve(system, solver, factor, k, uv)) {
        solver->backoff = 1;
    } else {
        solver->failed = 1;
        ++solver->failed_steps;
        solver->direct_runs = solver->backoff;
        solver->backoff = solver->backoff < 16 ? 2 * solver->backoff : 16;
        return CHOLMOD_OK;
    }
    if (state->project_grain && !solver->response_ready)
        return grain_response(system, solver, factor);
    return CHOLMOD_OK;
}

/* Records the first failing panel of a parallel phase. */
static void note_failure(int status, int32_t panel, int *failed_status, int32_t *failed_panel)
{
    if (status == CHOLMOD_OK)
        return;
#pragma omp critical(pz_textile_failure)
    if (*failed_panel < 0 || panel < *failed_panel) {
        *failed_panel = panel;
        *failed_status = status;
    }
}

/*
 * The global step in three parallel phases over the 2 x panels coordinate
 * systems: assembly, the factorizations this iteration needs, the solves.
 * The local step is complete before any coordinate is overwritten, each
 * task writes only its own panel's coordinate, and no factor changes while
 * the solves read them: no races, and the same result for any thread count.
 */
pz_status textile_global_step(textile_state *state, double *uv, pz_ctx *ctx)
{
    int32_t tasks = 2 * state->pattern->panel_count;
    int failed_status = CHOLMOD_OK;
    int32_t failed_panel = -1;
#pragma omp parallel for schedule(dynamic, 1) num_threads(state->threads) if (state->parallel)
    for (int32_t task = 0; task < tasks; ++task)
        assemble_coordinate(state, task / 2, task % 2, uv);
#pragma omp parallel for schedule(dynamic, 1) num_threads(state->threads) if (state->parallel)
    for (int32_t task = 0; task < tasks; ++task)
        note_failure(factorize_when_needed(&state->panels[task / 2], task % 2), task / 2, &failed_status,
                     &failed_panel);
    int retry = 0;
    if (failed_panel < 0) {
#pragma omp parallel for schedule(dynamic, 1) num_threads(state->threads) if (state->parallel) reduction(| : retry)
        for (int32_t task = 0; task < tasks; ++task) {
            note_failure(solve_coordinate(state, task / 2, task % 2, uv), task / 2, &failed_status, &failed_panel);
            retry |= state->panels[task / 2].solver[task % 2].failed;
        }
    }
    /* PCG steps that failed: factorize and solve directly, after every
     * solve that might read the factor is done. */
    if (retry && failed_panel < 0) {
#pragma omp parallel for schedule(dynamic, 1) num_threads(state->threads) if (state->parallel)
        for (int32_t task = 0; task < tasks; ++task) {
            panel_system *system = &state->panels[task / 2];
            if (!system->solver[task % 2].failed)
                continue;
            system->solver[task % 2].failed = 0;
            int st = factorize_when_needed(system, task % 2);
            note_failure(st ? st : solve_coordinate(state, task / 2, task % 2, uv), task / 2, &failed_status,
                         &failed_panel);
        }
    }
    if (failed_panel < 0)
        return PZ_OK;
    if (failed_status == CHOLMOD_OUT_OF_MEMORY)
        return pz_error(ctx, PZ_ERR_NOMEM, "textile: panel %d: out of memory", failed_panel);
    return pz_error(ctx, PZ_ERR_INTERNAL, "textile: panel %d: the global step failed (CHOLMOD status %d)", failed_panel,
                    failed_status);
}

/*
 * Grain-constrained steps (docs/param.md). Eq. 10 is not invariant under
 * rotation, so the global step turns each panel a little towards the
 * rotation its stretch terms prefer, and textile_align_grain turns it back: near
 * convergence that raised the energy of every full step (the fixed point of
 * step-then-align is not a minimum of Eq. 10 among aligned patterns) and the
 * iteration stalled in backtracking. So the step d = new - old of each panel
 * is replaced by the minimizer of the global step's quadratic under the
 * linearized constraint g . d = 0 (g: the gradient of the panel's grain angle,
 * textile_grain_gradient, both coordinates): d - (g . d / g . z) z with z = A^-1 g,
 * taken from the last factorization (a stale z only makes the projected step
 * a little less than optimal; g . d = 0 holds exactly). The step then turns
 * the panel only to second order, and the iteration's fixed points are the
 * stationary points of Eq. 10 among aligned patterns.
 */
void textile_project_grain_turn(const textile_state *state, const double *previous, double *uv)
{
#pragma omp parallel for schedule(dynamic, 1) num_threads(state->threads) if (state->across_panels)
    for (int32_t p = 0; p < state->pattern->panel_count; ++p) {
        const panel_system *system = &state->panels[p];
        double turn = 0, response = 0;
        for (int k = 0; k < 2; ++k)
            for (int32_t l = 0; l < system->vertex_count; ++l) {
                size_t i = 2 * (size_t)system->vertices[l] + k;
                turn += system->solver[k].grain_gradient[l] * (uv[i] - previous[i]);
                response += system->solver[k].grain_gradient[l] * system->solver[k].grain_response[l];
            }
        if (!(response > 0))
            continue;
        for (int k = 0; k < 2; ++k)
            for (int32_t l = 0; l < system->vertex_count; ++l)
                uv[2 * (size_t)system->vertices[l] + k] -= turn / response * system->solver[k].grain_response[l];
    }
}

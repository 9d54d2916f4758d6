/*
 * param/textile_solve.c -- the iterations of the textile parameterization
 * (pz_textile_solve): evaluation, the monotone line search, the strain
 * goal's reweighting and demotion rounds, the driver; and pz_param_textile,
 * set-up then solve. The design: param/textile_internal.h.
 *
 * SPDX-License-Identifier: GPL-3.0-or-later
 */
#include "param/textile_internal.h"

#include <math.h>
#include <omp.h>
#include <stdlib.h>
#include <string.h>

/* ------------------------------------------------------------------------ */
/* Monotone steps                                                            */
/* ------------------------------------------------------------------------ */

/* A step goes at most this fraction of the way to the first face that would
 * flip (flip_free_step): a face nearly collapsed has a huge stretch term. */
#define FLIP_MARGIN 0.8
/* Halvings of a panel's step before the whole step is given up. */
#define MAX_STEP_HALVINGS 5
/* Relative slack on "the energy did not increase" (rounding of the sums). */
#define ENERGY_SLACK 1e-10

/* Grain alignment and local step at uv: E_textile (Eq. 10) of uv as it will
 * be returned, and the terms of the next global step. */
static double evaluate(textile_state *state, double *uv)
{
    textile_align_grain(state, uv);
    return textile_local_step(state, uv);
}

/* Per panel: its energy (faces + seam and dart pulls on its vertices) and
 * its defects: collapsed or mirrored faces, from the last evaluation, plus
 * crossings of its outline at uv. */
static void panel_figures(const textile_state *state, const double *uv, double *energy, int32_t *flipped)
{
    const pz_pattern *pattern = state->pattern;
#pragma omp parallel for schedule(dynamic, 1) num_threads(state->threads) if (state->across_panels)
    for (int32_t p = 0; p < pattern->panel_count; ++p) {
        int32_t first = state->offsets[p], faces = state->offsets[p + 1] - first;
        double block_energy[SUM_BLOCKS], sum = state->panel_pull[p];
        int32_t count = 0;
#pragma omp parallel for schedule(static) reduction(+ : count) num_threads(state->threads) if (state->within_panel)
        for (int block = 0; block < SUM_BLOCKS; ++block) {
            double block_sum = 0;
            for (int32_t i = block_start(first, faces, block); i < block_start(first, faces, block + 1); ++i) {
                block_sum += state->face_energy[state->order[i]];
                count += state->face_flipped[state->order[i]];
            }
            block_energy[block] = block_sum;
        }
        for (int block = 0; block < SUM_BLOCKS; ++block)
            sum += block_energy[block];
        energy[p] = sum;
        /* Outline crossings count as defects like flipped faces: the line search never adds one
         * (a dart closing past zero, a boundary folding over itself cannot be cut). */
        int32_t outline = state->outline_offsets[p], edges = state->outline_offsets[p + 1] - outline;
        int32_t crossings = pz_metrics_outline_crossings(state->outline_edges + 2 * (size_t)outline, edges, uv);
        flipped[p] = count + (crossings > 0 ? crossings : 0);
    }
}

/* Per-panel bookkeeping of the line search (panel_count each). */
typedef struct step_control {
    double *previous_uv, *full_uv;  /* vertex_count x 2: the accepted iterate, the global step's result */
    double *step;                   /* per panel: fraction of the global step taken */
    double *energy, *trial_energy;  /* per panel, accepted and trial */
    int32_t *flipped, *trial_flipped, *allowed_flipped; /* allowed: as many as the start had */
    double *vertex_step;            /* vertex_count: a vertex's own factor on top of its panel's step */
    uint8_t *near;                  /* vertex_count, scratch of damp_crossings: 0 outside its rings */
} step_control;

static void step_control_free(step_control *control)
{
    free(control->previous_uv);
    free(control->full_uv);
    free(control->step);
    free(control->energy);
    free(control->trial_energy);
    free(control->flipped);
    free(control->trial_flipped);
    free(control->allowed_flipped);
    free(control->vertex_step);
    free(control->near);
}

static int step_control_init(step_control *control, const pz_pattern *pattern)
{
    size_t nv = (size_t)pattern->mesh->vertex_count, np = (size_t)pattern->panel_count;
    control->previous_uv = malloc(nv * 2 * sizeof(double) + 1);
    control->full_uv = malloc(nv * 2 * sizeof(double) + 1);
    control->step = malloc(np * sizeof(double) + 1);
    control->energy = malloc(np * sizeof(double) + 1);
    control->trial_energy = malloc(np * sizeof(double) + 1);
    control->flipped = malloc(np * sizeof(int32_t) + 1);
    control->trial_flipped = malloc(np * sizeof(int32_t) + 1);
    control->allowed_flipped = malloc(np * sizeof(int32_t) + 1);
    control->vertex_step = malloc(nv * sizeof(double) + 1);
    control->near = calloc(nv + 1, 1);
    return control->previous_uv && control->full_uv && control->step && control->energy && control->trial_energy &&
           control->flipped && control->trial_flipped && control->allowed_flipped && control->vertex_step &&
           control->near;
}

/* uv = previous + step[p] vertex_step[v] (full - previous) on every vertex v of every panel p. */
static void blend(const textile_state *state, const step_control *control, double *uv)
{
    const pz_pattern *pattern = state->pattern;
#pragma omp parallel for schedule(dynamic, 1) num_threads(state->threads) if (state->across_panels)
    for (int32_t p = 0; p < pattern->panel_count; ++p) {
        const panel_system *system = &state->panels[p];
        double t = control->step[p];
#pragma omp parallel for schedule(static) num_threads(state->threads) if (state->within_panel)
        for (int32_t l = 0; l < system->vertex_count; ++l)
            for (int k = 0; k < 2; ++k) {
                int32_t v = system->vertices[l];
                size_t i = 2 * (size_t)v + k;
                uv[i] = control->previous_uv[i] + t * control->vertex_step[v] *
                                                      (control->full_uv[i] - control->previous_uv[i]);
            }
    }
}

/*
 * The largest t > 0 such that no face of `panel` with positive area at
 * `from` reaches zero area on from + t (to - from) (INFINITY when none does
 * for any t): twice
 * the signed area is a quadratic in t, c0 + c1 t + c2 t^2, and t is its
 * smallest positive root over the faces (Smith and Schaefer 2015, Sec. 4.1,
 * bound the step of their line search the same way).
 */
static double flip_free_step(const textile_state *state, int32_t panel, const double *from, const double *to)
{
    const pz_mesh *mesh = state->pattern->mesh;
    double best = INFINITY;
#pragma omp parallel for schedule(static) reduction(min : best) num_threads(state->threads) if (state->within_panel)
    for (int32_t i = state->offsets[panel]; i < state->offsets[panel + 1]; ++i) {
        const int32_t *face = mesh->faces + 3 * state->order[i];
        double e[2][2], d[2][2]; /* edges 0->1 and 0->2 at `from`, and their change */
        for (int j = 0; j < 2; ++j)
            for (int k = 0; k < 2; ++k) {
                e[j][k] = from[2 * face[j + 1] + k] - from[2 * face[0] + k];
                d[j][k] = to[2 * face[j + 1] + k] - to[2 * face[0] + k] - e[j][k];
            }
        double c0 = e[0][0] * e[1][1] - e[0][1] * e[1][0];
        if (!(c0 > 0))
            continue;
        double c1 = e[0][0] * d[1][1] - e[0][1] * d[1][0] + d[0][0] * e[1][1] - d[0][1] * e[1][0];
        double c2 = d[0][0] * d[1][1] - d[0][1] * d[1][0];
        double root = INFINITY;
        if (c2 == 0) {
            if (c1 < 0)
                root = -c0 / c1;
        } else {
            double discriminant = c1 * c1 - 4 * c2 * c0;
            if (discriminant >= 0) {
                /* The two roots without cancellation: q / c2 and c0 / q. */
                double q = -0.5 * (c1 + copysign(sqrt(discriminant), c1));
                double r1 = q / c2, r2 = q != 0 ? c0 / q : INFINITY;
                root = r1 > 0 ? r1 : INFINITY;
                if (r2 > 0 && r2 < root)
                    root = r2;
            }
        }
        if (root < best)
            best = root;
    }
    return best;
}

/* Rings of faces around an outline crossing over which a vertex's own step
 * ramps back from 0 to 1 (damp_crossings). Measured on the jumpsuit front
 * (3 poses): 1 ring ended at energy 1288 after 20 steps, 3 rings 1292, 6
 * rings 1185, 10 rings 1280 (the trajectories differ; 6 kept). */
#define CROSSING_RINGS 6

/*
 * When panel p's trial iterate uv lowered its energy but made its outline
 * meet itself: the vertices of the meeting outline edges keep their
 * previous positions (own step 0) and those k rings of faces away take
 * k / (CROSSING_RINGS + 1) of the step, so the next trial holds back only
 * where the outline closes up instead of the whole panel. The steps of one
 * line search only shrink (a vertex frozen once stays frozen until the next
 * global step). Why: two parts of the jumpsuit front's outline lie about
 * 1.5 mm apart in 3D (vertices 172-173 and 1164-1167) and the flattening
 * closes that gap; halving the whole panel's step, as for an energy rise,
 * left every later step a backtracked fraction and the iteration stalled
 * after 7-8 steps. Returns 1 when the panel has a crossing (and its steps
 * were shortened), 0 when it has none (its defects are faces).
 */
static int damp_crossings(const textile_state *state, step_control *control, int32_t p, const double *uv)
{
    const pz_mesh *mesh = state->pattern->mesh;
    const panel_system *system = &state->panels[p];
    int32_t outline = state->outline_offsets[p], edges = state->outline_offsets[p + 1] - outline;
    uint8_t *near = control->near;
    int32_t crossings =
        pz_metrics_outline_crossings_marked(state->outline_edges + 2 * (size_t)outline, edges, uv, near);
    if (crossings > 0) {
        int32_t first = state->offsets[p], faces = state->offsets[p + 1] - first;
        for (int ring = 1; ring <= CROSSING_RINGS; ++ring)
            for (int32_t i = first; i < first + faces; ++i) {
                const int32_t *corner = mesh->faces + 3 * (size_t)state->order[i];
                if (near[corner[0]] == ring || near[corner[1]] == ring || near[corner[2]] == ring)
                    for (int c = 0; c < 3; ++c)
                        if (!near[corner[c]])
                            near[corner[c]] = (uint8_t)(ring + 1);
            }
    }
    for (int32_t l = 0; l < system->vertex_count; ++l) {
        int32_t v = system->vertices[l];
        if (near[v] && crossings > 0)
            control->vertex_step[v] = fmin(control->vertex_step[v], (near[v] - 1) / (CROSSING_RINGS + 1.0));
        near[v] = 0;
    }
    return crossings > 0;
}

/*
 * Backtracking after a global step (uv holds its result; control->previous_uv
 * the accepted iterate, of energy `energy`, already evaluated into
 * control->energy / flipped). The step is accepted when the total energy did
 * not increase and no panel has more collapsed or mirrored faces than the
 * start had; otherwise the panels that got worse (energy up or new flips; all
 * panels when none did alone, since seams couple them) take half their step,
 * and so on MAX_STEP_HALVINGS times, after which the previous iterate is
 * restored. Returns the energy of the iterate left in uv (evaluated, so the
 * local-step terms belong to it, except after a stall, which ends the
 * iteration); *damped is set when the step was shortened, *stalled when it
 * was given up.
 */
static double line_search(textile_state *state, step_control *control, double energy, double tolerance, double *uv,
                          int *bounded, int *damped, int *stalled)
{
    const pz_pattern *pattern = state->pattern;
    size_t bytes = (size_t)pattern->mesh->vertex_count * 2 * sizeof(double);
    int32_t np = pattern->panel_count;
    memcpy(control->full_uv, uv, bytes);
    for (int32_t v = 0; v < pattern->mesh->vertex_count; ++v)
        control->vertex_step[v] = 1;
    *bounded = 0;
    for (int32_t p = 0; p < np; ++p) {
        double step = FLIP_MARGIN * flip_free_step(state, p, control->previous_uv, control->full_uv);
        /* A bound below the shortest backtracked step (a face nearly
         * collapsed and squeezed further by any step) would freeze the
         * panel: the backtracking alone decides then, as it did before. */
        control->step[p] = step < 1 && step >= 1.0 / (1 << MAX_STEP_HALVINGS) ? step : 1;
        *bounded |= control->step[p] < 1;
    }
    if (*bounded)
        blend(state, control, uv);
    *damped = *stalled = 0;
    for (int halving = 0;; ++halving) {
        double trial = evaluate(state, uv);
        panel_figures(state, uv, control->trial_energy, control->trial_flipped);
        int new_flips = 0;
        for (int32_t p = 0; p < np; ++p)
            new_flips |= control->trial_flipped[p] > control->allowed_flipped[p];
        if (isfinite(trial) && trial <= energy * (1 + ENERGY_SLACK) && !new_flips) {
            memcpy(control->energy, control->trial_energy, (size_t)np * sizeof(double));
            memcpy(control->flipped, control->trial_flipped, (size_t)np * sizeof(int32_t));
            return trial;
        }
        /* A full step that changes the energy by no more than the stopping
         * tolerance means the iteration has converged: halving it would only
         * chase rounding (each halving costs a local step). */
        int converged = halving == 0 && !new_flips && isfinite(trial) && trial - energy <= tolerance * energy;
        *damped = !converged;
        if (converged || halving == MAX_STEP_HALVINGS) {
            memcpy(uv, control->previous_uv, bytes); /* aligned already; the iteration stops */
            *stalled = 1;
            return energy;
        }
        int blamed = 0;
        for (int32_t p = 0; p < np; ++p) {
            int more_defects = control->trial_flipped[p] > control->allowed_flipped[p];
            int higher = !(control->trial_energy[p] <= control->energy[p] + ENERGY_SLACK * energy);
            if (more_defects && !higher && damp_crossings(state, control, p, uv)) {
                blamed = 1;
                continue;
            }
            if ((more_defects || higher) && control->step[p] > 0) {
                control->step[p] *= 0.5;
                blamed = 1;
            }
        }
        if (!blamed)
            for (int32_t p = 0; p < np; ++p)
                control->step[p] *= 0.5;
        blend(state, control, uv);
    }
}

/* ------------------------------------------------------------------------ */
/* Driver                                                                    */
/* ------------------------------------------------------------------------ */

/* With a strain goal, iterations with the seams open before they are sewn:
 * the panels first reach their own flat shapes, as in the segmentation's
 * evaluations (5 iterations there too). Sewn at once, the seams' equal
 * lengths were taken from the LSCM start, which can be far off (a panel
 * with a long dart: strain 1.46 at the start), and held every neighbour to
 * that panel's distorted boundary: on one shirt-front layout the joint
 * flattening ended at strain 0.30 against 0.048 with this warm-up.
 * Without a goal the seams are opened too, until the open iteration stops
 * on its own (open_seams_start). */
#define WARMUP_ITERATIONS 5
/* open_seams_start's stop: the energy changed by at most this fraction in a
 * step (or the caller's tolerance, when looser). Measured with
 * bench/bench_truth on 9 garments: 1e-2, 1e-3 and 1e-4 give the same
 * distances to the true pieces within 2 % of each other; 1e-3 took 10 open
 * steps on the T-shirt where the default tolerance (1e-6) takes all 20. */
#define WARMUP_TOLERANCE 1e-3

/* Rounds of demote_terms after the first run of iterations. */
#define MAX_DEMOTION_ROUNDS 2
/* A face's stretch weight grows once its strain passes this fraction of the
 * strain goal (update_strain_weights). */
#define STRAIN_WEIGHT_ONSET 0.8
/* Bounds of one update's growth factor and of the accumulated multiplier. */
#define STRAIN_WEIGHT_STEP_MAX 4.0
#define STRAIN_WEIGHT_MAX 1000.0

/*
 * The strain goal as iteratively reweighted least squares: Eq. 5 sums
 * squared strains, so a few faces can keep a strain well above the goal
 * while the sum is small (the worst face of a panel, not its mean, decides
 * whether it meets the goal). Every face whose strain passed
 * STRAIN_WEIGHT_ONSET x the goal at the last accepted iterate has its
 * stretch weight multiplied by (strain / onset)^2 (at most
 * STRAIN_WEIGHT_STEP_MAX per update, STRAIN_WEIGHT_MAX in all). The
 * multipliers only grow, like the penalty of a constraint, so a face pulled
 * under the goal stays there. Returns the number of faces changed.
 */
static int32_t update_strain_weights(textile_state *state)
{
    int32_t nf = state->pattern->mesh->face_count, changed = 0;
    double onset = STRAIN_WEIGHT_ONSET * state->strain_limit;
    for (int32_t f = 0; f < nf; ++f) {
        double strain = state->face_strain[f];
        if (!(strain > onset) || state->face_flipped[f] || state->stretch_boost[f] >= STRAIN_WEIGHT_MAX)
            continue;
        double factor = fmin(STRAIN_WEIGHT_STEP_MAX, (strain / onset) * (strain / onset));
        state->stretch_boost[f] = fmin(STRAIN_WEIGHT_MAX, state->stretch_boost[f] * factor);
        ++changed;
    }
    return changed;
}

/* With a strain goal, the seams' and darts' sides should be this close in
 * length (relative to the 3D length): issue 5's 0.5 %. */
#define SEAM_MISMATCH_GOAL 0.005

/*
 * The length goal the same way as the strain goal (update_strain_weights):
 * the facing segments of a seam or dart whose sides differ by more than
 * STRAIN_WEIGHT_ONSET x SEAM_MISMATCH_GOAL get heavier, at most
 * STRAIN_WEIGHT_MAX times their start. The strain reweighting stiffens faces
 * along seams, and a stiffer fabric resists equal lengths more: both goals
 * have to grow together. Returns the number of curves changed.
 */
static int32_t update_length_weights(textile_state *state)
{
    const pz_pattern *pattern = state->pattern;
    int32_t curves = pattern->seam_count + pattern->dart_count, changed = 0;
    double onset = STRAIN_WEIGHT_ONSET * SEAM_MISMATCH_GOAL;
    for (int32_t c = 0; c < curves; ++c) {
        double mismatch = state->curve_mismatch[c];
        int is_seam = c < pattern->seam_count;
        int32_t base = is_seam ? state->seam_segment_base[c] : state->dart_segment_base[c - pattern->seam_count];
        if (base < 0 || !(mismatch > onset))
            continue;
        int32_t pairs = is_seam ? pattern->seams[c].pair_count - 1 : pattern->darts[c - pattern->seam_count].pair_count;
        double start = (is_seam ? state->w_seam : state->w_dart) * SEGMENT_LENGTH_STIFFNESS;
        double factor = fmin(STRAIN_WEIGHT_STEP_MAX, (mismatch / onset) * (mismatch / onset));
        if (state->segment_weight[base] >= STRAIN_WEIGHT_MAX * start)
            continue;
        for (int32_t g = base; g < base + 2 * pairs; ++g)
            state->segment_weight[g] = fmin(STRAIN_WEIGHT_MAX * start, state->segment_weight[g] * factor);
        ++changed;
    }
    return changed;
}

/*
 * After a run of iterations with a strain goal: the panels whose worst face
 * still breaks it lose their reflection terms (mirror seams become
 * length-only, darts keep their equal legs without the axis symmetry of
 * Eq. 9). Sewing needs equal lengths, the goal needs the strain; mirror
 * images are the paper's "ideally" (Sec. 3) and give way. Returns how many
 * seams and darts were demoted (counted into result->length_only_seams and
 * result->length_only_darts).
 */
static int32_t demote_terms(textile_state *state, pz_textile_result *result)
{
    const pz_pattern *pattern = state->pattern;
    int32_t np = pattern->panel_count, demoted = 0;
    uint8_t *over = calloc((size_t)np + 1, 1);
    if (!over)
        return 0;
    for (int32_t f = 0; f < pattern->mesh->face_count; ++f)
        if (state->face_strain[f] > state->strain_limit)
            over[pattern->face_panel[f]] = 1;
    for (int32_t s = 0; s < pattern->seam_count; ++s) {
        const pz_seam *seam = &pattern->seams[s];
        if (state->seam_length_only[s] || seam->pair_count < 2)
            continue;
        if (over[state->vertex_panel[seam->side_a[0]]] || over[state->vertex_panel[seam->side_b[0]]]) {
            state->seam_length_only[s] = 1;
            ++result->length_only_seams;
            ++demoted;
        }
    }
    for (int32_t d = 0; d < pattern->dart_count; ++d) {
        const pz_dart *dart = &pattern->darts[d];
        if (state->dart_length_only[d] || dart->pair_count < 1 || !over[state->vertex_panel[dart->tip]])
            continue;
        state->dart_length_only[d] = 1;
        ++result->length_only_darts;
        ++demoted;
    }
    free(over);
    return demoted;
}

/* The next global step solves exactly: without a strain goal by conjugate
 * gradients to PCG_EXACT_REDUCTION (pcg_solve; a factorization only when
 * that takes more than one factorization's worth of steps); with one, the
 * one-step solve's way: every coordinate's own matrix factorized and solved
 * directly (v stops borrowing u's factor). */
static void demand_exact_solves(textile_state *state)
{
    for (int32_t p = 0; p < state->pattern->panel_count; ++p)
        for (int k = 0; k < 2; ++k) {
            if (state->strain_limit <= 0) {
                state->panels[p].solver[k].exact = 1;
                continue;
            }
            state->panels[p].solver[k].refactor = 1;
            state->panels[p].solver[k].borrowing = 0;
        }
}

/*
 * Up to `iterations` local/global steps from uv (of energy *energy, already
 * evaluated into control), each followed by the line search; with a strain
 * goal the stretch weights are updated after every accepted step (and the
 * iterate re-evaluated under them, so the line search always compares
 * energies of one function). Stops on the tolerance only in a step that
 * changed no weight. PZ_ERR_CANCELLED (uv the last accepted iterate) when
 * the caller asks to stop between two steps.
 */
static pz_status iterate(pz_textile_solver *solver, step_control *control, int iterations, double *uv,
                         double *energy, pz_textile_result *outcome, pz_ctx *ctx)
{
    textile_state *state = &solver->state;
    const pz_pattern *pattern = state->pattern;
    double tolerance = solver->tolerance;
    int exact_retried = 0;
    for (int it = 0; it < iterations; ++it) {
        pz_status status = pz_check_cancel(ctx, "textile");
        if (status)
            return status;
        double previous = *energy;
        memcpy(control->previous_uv, uv, (size_t)pattern->mesh->vertex_count * 2 * sizeof(double));
        status = textile_global_step(state, uv, ctx);
        if (status)
            return status;
        if (state->project_grain)
            textile_project_grain_turn(state, control->previous_uv, uv);
        int bounded, damped, stalled;
        *energy = line_search(state, control, previous, tolerance, uv, &bounded, &damped, &stalled);
        outcome->bounded_steps += bounded;
        outcome->damped_steps += damped;
        ++outcome->iterations_run;
        if (solver->on_iteration)
            solver->on_iteration(solver->user, outcome->iterations_run, *energy);
        int reweighted = 0;
        if (state->strain_limit > 0 && !stalled && update_strain_weights(state) + update_length_weights(state) > 0) {
            *energy = evaluate(state, uv);
            panel_figures(state, uv, control->energy, control->flipped);
            reweighted = 1;
        }
        /* From the first backtracked step on, steps keep the grain
         * (project_grain_turn). A step that no fraction of could lower the
         * energy is retried once with that and with exact solves (fresh
         * factors, v's own) before the iteration gives up. */
        if (damped)
            state->project_grain = 1;
        if (stalled && damped && !exact_retried) {
            exact_retried = 1;
            demand_exact_solves(state);
            *energy = evaluate(state, uv);
            panel_figures(state, uv, control->energy, control->flipped);
            continue;
        }
        if (stalled || (!reweighted && fabs(*energy - previous) <= tolerance * previous)) {
            outcome->converged = 1;
            break;
        }
    }
    return PZ_OK;
}

/*
 * Without a strain goal: the start the sewn iteration begins from. The seam
 * terms are local/global targets taken from the current iterate, and the
 * equal-length term is stiff (SEGMENT_LENGTH_STIFFNESS): sewn from the LSCM
 * start, they hold every seam's segments near the start's lengths and
 * directions, and 20 steps leave the panels close to LSCM's shapes where
 * those are far from the 3D ones (a loosely draped, gathered skirt: 2.6x
 * libigl ARAP's distance to the true pieces; docs/flatten.md, "Against
 * real sewing patterns"). So the panels first find their own flat shapes
 * with the seams open (darts kept), up to `iterations` steps or until a
 * step changes the energy by less than WARMUP_TOLERANCE, and are sewn from
 * there; the mirror
 * test then sees those shapes. The warm-up is part of the start: its steps
 * are not reported (iterations_run, on_iteration) and it is kept only when
 * it lowers Eq. 10 with the seams sewn, so the energies reported still never
 * increase and the result's is never above the LSCM start's.
 */
static pz_status open_seams_start(pz_textile_solver *solver, step_control *control, double *uv, double *energy,
                                  pz_textile_result *outcome, pz_ctx *ctx)
{
    textile_state *state = &solver->state;
    const pz_pattern *pattern = state->pattern;
    size_t bytes = (size_t)pattern->mesh->vertex_count * 2 * sizeof(double);
    double *lscm_uv = malloc(bytes);
    if (!lscm_uv)
        return pz_error(ctx, PZ_ERR_NOMEM, "textile: out of memory");
    memcpy(lscm_uv, uv, bytes);
    int32_t lscm_length_only = outcome->length_only_seams;
    void (*on_iteration)(void *, int, double) = solver->on_iteration;
    pz_textile_result open_outcome = *outcome;
    double open_energy;
    state->seams_open = 1;
    open_energy = evaluate(state, uv);
    panel_figures(state, uv, control->energy, control->flipped);
    double tolerance = solver->tolerance;
    solver->tolerance = fmax(tolerance, WARMUP_TOLERANCE);
    solver->on_iteration = NULL;
    pz_status status = iterate(solver, control, solver->iterations, uv, &open_energy, &open_outcome, ctx);
    solver->on_iteration = on_iteration;
    solver->tolerance = tolerance;
    state->seams_open = 0;
    if (!status) {
        outcome->length_only_seams = textile_classify_seams(state, uv);
        double sewn = evaluate(state, uv);
        if (sewn < *energy) {
            *energy = sewn;
        } else { /* the LSCM start was better sewn: back to it */
            memcpy(uv, lscm_uv, bytes);
            outcome->length_only_seams = lscm_length_only;
            textile_classify_seams(state, uv);
            *energy = evaluate(state, uv);
        }
        panel_figures(state, uv, control->energy, control->flipped);
    }
    free(lscm_uv);
    return status;
}

/* The iterations of one solve from the LSCM start already in uv: the warm-up
 * with the seams open (strain goal; without one open_seams_start), round 0,
 * and the demotion rounds. */
static pz_status run_rounds(pz_textile_solver *solver, step_control *control, double *uv, pz_textile_result *outcome,
                            pz_ctx *ctx)
{
    textile_state *state = &solver->state;
    const pz_pattern *pattern = state->pattern;
    /* With a strain goal the seams are sewn after a warm-up (docs/param.md, "The strain goal"). */
    state->seams_open = state->strain_limit > 0 && pattern->seam_count > 0 && state->w_seam > 0;
    double energy = evaluate(state, uv);
    panel_figures(state, uv, control->energy, control->flipped);
    memcpy(control->allowed_flipped, control->flipped, (size_t)pattern->panel_count * sizeof(int32_t));
    outcome->initial_energy = energy;
    if (solver->on_iteration)
        solver->on_iteration(solver->user, 0, energy);
    pz_status status = PZ_OK;
    if (state->strain_limit <= 0 && pattern->seam_count > 0 && state->w_seam > 0)
        status = open_seams_start(solver, control, uv, &energy, outcome, ctx);
    if (state->seams_open) {
        status = iterate(solver, control, WARMUP_ITERATIONS, uv, &energy, outcome, ctx);
        state->seams_open = 0;
        if (!status)
            outcome->length_only_seams = textile_classify_seams(state, uv);
        energy = evaluate(state, uv);
        panel_figures(state, uv, control->energy, control->flipped);
    }
    /* Round 0 is the paper's iteration; with a strain goal, later rounds
     * follow only when some panel still breaks it and demote_terms freed
     * that panel of a symmetry term (docs/param.md, "The strain goal"). */
    int rounds = state->strain_limit > 0 ? 1 + MAX_DEMOTION_ROUNDS : 1;
    for (int round = 0; round < rounds && !status; ++round) {
        if (round > 0) {
            int32_t demoted = demote_terms(state, outcome);
            if (demoted == 0)
                break;
            energy = evaluate(state, uv);
            panel_figures(state, uv, control->energy, control->flipped);
        }
        status = iterate(solver, control, solver->iterations, uv, &energy, outcome, ctx);
    }
    outcome->final_energy = energy;
    return status;
}

pz_status pz_textile_solve(pz_textile_solver *solver, double *uv, pz_textile_result *result, pz_ctx *ctx)
{
    if (!solver || !uv)
        return pz_error(ctx, PZ_ERR_USAGE, "textile: no solver or no output");
    textile_state *state = &solver->state;
    const pz_pattern *pattern = state->pattern;
    pz_textile_result outcome;
    memset(&outcome, 0, sizeof outcome);
    outcome.init_ms = solver->setup_ms;
    pz_status status = textile_state_begin(state, ctx);
    if (status)
        return status;
    step_control control;
    memset(&control, 0, sizeof control);
    if (!step_control_init(&control, pattern)) {
        step_control_free(&control);
        textile_state_end(state);
        return pz_error(ctx, PZ_ERR_NOMEM, "textile: out of memory");
    }
    double solve_start = pz_seconds();
    memcpy(uv, solver->start_uv, (size_t)pattern->mesh->vertex_count * 2 * sizeof(double));
    outcome.length_only_seams = textile_classify_seams(state, uv);
    status = run_rounds(solver, &control, uv, &outcome, ctx);
    for (int32_t p = 0; p < pattern->panel_count; ++p)
        for (int k = 0; k < 2; ++k) {
            outcome.factorizations += state->panels[p].solver[k].factorizations;
            outcome.failed_steps += state->panels[p].solver[k].failed_steps;
            outcome.pcg_solves += state->panels[p].solver[k].pcg_solves;
        }
    step_control_free(&control);
    textile_state_end(state);
    if (status)
        return status;
    outcome.solve_ms = 1e3 * (pz_seconds() - solve_start);
    outcome.iteration_ms = outcome.iterations_run ? outcome.solve_ms / outcome.iterations_run : 0;
    pz_param_layout(pattern, state->offsets, state->order, uv);
    if (result)
        *result = outcome;
    return PZ_OK;
}

pz_status pz_param_textile(const pz_pattern *pattern, const pz_textile_options *options, double *uv,
                           pz_textile_result *result, pz_ctx *ctx)
{
    if (!pattern || !pattern->mesh || !uv)
        return pz_error(ctx, PZ_ERR_USAGE, "textile: no pattern or no output");
    pz_textile_solver *solver = NULL;
    pz_status status = pz_textile_setup(pattern, options, &solver, ctx);
    if (!status)
        status = pz_textile_solve(solver, uv, result, ctx);
    pz_textile_solver_free(&solver);
    return status;
}

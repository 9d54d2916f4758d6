/*
 * param/textile.c -- the anisotropic textile parameterization of
 * pietroni2022 Sec. 4.3, a local/global iteration over all panels at once.
 *
 * Start: LSCM per panel, oriented so the projected grain runs along +v
 * (param/lscm.c). Then, each iteration:
 *
 *  1. Grain alignment: every panel is turned rigidly about its centroid so
 *     the area-weighted projected 3D grain follows +v (the warp; Sec. 4.3
 *     "Grain alignment": not part of the energy, re-imposed every step).
 *  2. Local step, per triangle, from the current 2D triangle ABC and the 3D
 *     triangle A'B'C' (in its own orthonormal frame), for the rest pose and,
 *     with use_poses, every pose, the results averaged (Sec. 4.3, last
 *     paragraph: only right-hand sides depend on the 3D shape; the energy
 *     is then the mean of the poses' energies, whose step that is):
 *       - stretch (Eqs. 2-5): the barycentric differences of G_u = G + (1,0)
 *         and G are the u-derivatives of the hat functions on ABC,
 *         c_u = d(alpha, beta, gamma)/du, likewise c_v; s_u = |sum c_u,i X'_i|
 *         and s_v are the 3D lengths of the images of the unit grain vectors.
 *         Residuals s_u - c_u . u and s_v - c_v . v, each row weighted by
 *         s_k and a shear term added so the global step's slope is that of
 *         Eq. 10 (face_system: "consistent stretch steps").
 *       - rigidity (Eq. 6): R = the best rotation of A'B'C' onto ABC
 *         (2x2 Procrustes in closed form), edge targets R (X'_j - X'_i).
 *     Seams (Eqs. 7-8): the best-fit reflection M (Procrustes with det = -1,
 *     plus translation) of side a onto side b; targets (M p + q)/2 and
 *     (p + M^-1 q)/2. A seam whose sides cannot be mirror images (a collar
 *     band on a neckline: classify_seams, at the start) gets equal lengths
 *     of facing segments instead (seam_length_targets). Darts (Eq. 9): the axis through the tip that best fits
 *     the leg midpoints (principal direction), targets the averages of each
 *     leg point with its mirrored partner.
 *  3. Global step: minimize Eq. 10 with those coefficients and targets fixed.
 *     No term couples u with v (the stretch rows involve one coordinate, the
 *     edge targets are per coordinate), so each panel gives two independent
 *     n x n SPD systems. They share one sparsity pattern (the panel's vertex
 *     adjacency) but not their values (c_u != c_v), so each has its own
 *     matrix and factor; CHOLMOD's symbolic analysis is done once per panel
 *     at setup and copied. The matrix changes every iteration (c depends on
 *     the 2D triangles), but slowly: each system takes one step of conjugate
 *     gradients preconditioned with the factor of an earlier iteration's
 *     matrix, refactorized (numerically only) when that factor has gone
 *     stale (pcg_solve). Panels are independent given the seam targets, so
 *     the 2 x panels systems are solved in parallel (OpenMP). Once a step
 *     has needed backtracking, the step is projected so it does not turn the
 *     panels (project_grain_turn: step 1 would turn them back).
 *
 * Scales (where the paper is silent; docs/param.md): the stretch residual is
 * dimensionless, so each triangle's stretch term is weighted by its 3D area,
 * which makes it comparable to the edge (mm^2) rigidity term and independent
 * of the mesh resolution and the units. A panel's energy is invariant under
 * translation, so 1e-8 * max(1, w_stretch + w_rigid) times the squared
 * distance of every vertex to its current position is added: it fixes the
 * null space without measurably biasing the solution.
 *
 * Monotone steps (line_search): the local/global step is not a descent step
 * for Eq. 10 (the stretch rows are linearized around the old 2D triangles:
 * a triangle squeezed to 1/7 of its 3D length is asked to grow 7x in one
 * step, and with its neighbours it overshoots; seams and ARAP alone would be
 * a proper majorization). Seen on the diffavatar shirt: the energy went
 * 640K -> 31K -> 19M at the last step, strain 174, flipped faces. So every
 * global step is first shortened, per panel, to 0.8 of the way to the first
 * face that would flip (flip_free_step), then aligned and evaluated; it is
 * kept when the total energy did not increase and no panel has more
 * collapsed or mirrored faces or outline crossings than the LSCM start had;
 * otherwise a panel whose energy fell but whose outline now meets itself
 * holds back only around the contact (damp_crossings), and the panels that
 * got worse take half their step (all panels when none did on its own:
 * seams couple them), at most MAX_STEP_HALVINGS times, after which the
 * previous iterate is kept and the iteration stops. The returned energy is
 * therefore never above the start's, and the energies reported through
 * options->on_iteration never increase.
 *
 * Stopping: after `iterations` global steps (20), when the energy changed by
 * no more than `tolerance` (1e-6) relative to the previous iterate, or when
 * no fraction of the step lowers it. The side-by-side layout (lscm.c)
 * follows.
 *
 * Cost per iteration: O(F) for the local step and the assembly (a scatter
 * of each face's precomputed share into precomputed CSC slots, no
 * allocation), plus one preconditioned step per coordinate (two triangular
 * solves, two products) and an occasional numeric factorization. Memory:
 * per face 3 doubles per pose (the 3D frame coordinates), 2 (the grain in
 * the frame), the local-step output (18 doubles) and 6 matrix slots; per
 * panel two CSC matrices and one or two factors (v borrows u's on large
 * panels). Failure modes: PZ_ERR_DATA (a panel that is not a disk, a seam
 * vertex out of range), PZ_ERR_NOMEM, PZ_ERR_INTERNAL (CHOLMOD reports a
 * matrix that is not positive definite: should not happen since the
 * regularized system is SPD).
 *
 * SPDX-License-Identifier: GPL-3.0-or-later
 */
#define _DEFAULT_SOURCE /* getloadavg, sysconf */
#include "param.h"

#include <cholmod.h>
#include <math.h>
#include <omp.h>
#include <stdlib.h>
#include <string.h>
#include <unistd.h>

/* Bounds of a factorization's cost in PCG steps (see pcg_solve). */
#define PCG_MIN_STEPS 4
#define PCG_MAX_STEPS 60
/* From this cost on, v starts with u's factor as its preconditioner instead
 * of its own (factorize_when_needed): at 200K faces (60) that saved one
 * 0.3 s factorization for energies 2e-4 higher after 20 steps; below, the
 * saving is small and the trajectories of the test meshes changed more. */
#define BORROW_MIN_STEPS 40
#define FACTOR_FLOP_COST 2.0

/* Threads pay only when every parallel region has milliseconds of work:
 * OpenMP's fork/join, and on a loaded machine threads descheduled while the
 * others spin at a barrier, cost more than they save below that. Measured on
 * the 2-core machine at load 3-4, 20K faces: 19 ms per iteration on one
 * thread, 113 ms on two (2x slower even at load 0.3 with active waiting).
 * So by default only patterns of PARALLEL_MIN_FACES faces run threaded; an
 * explicit options->threads >= 2 lowers that to PARALLEL_MIN_FACES_ASKED. */
#define PARALLEL_MIN_FACES 100000
#define PARALLEL_MIN_FACES_ASKED 8192

/* Sums over faces or vertices must not depend on the thread count (the same
 * pattern byte for byte, issue 5; the energies steer the line search): a
 * range is cut into SUM_BLOCKS fixed blocks, each summed in order by one
 * thread, and the block sums are added in block order. An OpenMP reduction
 * would add per-thread partial sums, which round differently per count. */
#define SUM_BLOCKS 64

/* First index of block `block` of [first, first + count). */
static int32_t block_start(int32_t first, int32_t count, int block)
{
    return first + (int32_t)((int64_t)count * block / SUM_BLOCKS);
}

/* Shared with param/lscm.c (see there). */
double pz_param_face_frame(const double *pos, const int32_t *face, double local[3], double e1[3], double e2[3]);
pz_status pz_param_panel_faces(const pz_pattern *pattern, int32_t **offsets, int32_t **order, pz_ctx *ctx);
void pz_param_layout(const pz_pattern *pattern, const int32_t *offsets, const int32_t *order, double *uv);
cholmod_factor *pz_param_analyze(cholmod_sparse *matrix, const double *positions, const int32_t *vertex_of,
                                 cholmod_common *common);
int pz_param_factorize(cholmod_sparse *matrix, cholmod_factor *factor, cholmod_common *common);

/* One n x n SPD system of one panel and one coordinate, with its own CHOLMOD
 * workspace (CHOLMOD commons are not shared between threads). */
typedef struct coordinate_solver {
    int started;
    cholmod_common common;
    cholmod_sparse *matrix;   /* upper triangle, fixed pattern */
    cholmod_factor *factor;   /* symbolic once, numeric every iteration */
    cholmod_dense *rhs, *solution, *work_y, *work_e;
    cholmod_dense *residual;  /* PCG: r, the right-hand side of the preconditioner solve */
    double *product, *current; /* PCG: A x or A z, and the iterate */
    int factored;             /* the factor holds some earlier matrix's numbers */
    int borrowing;            /* v only: preconditions with u's factor (until it needs its own) */
    int fresh;                /* the factor was made from this iteration's matrix: solve directly */
    int failed;               /* this iteration's PCG step failed (global_step solves it directly) */
    int refactor;             /* 1: factorize before the next solve */
    int direct_runs;          /* after PCG failed: factorize and solve directly this many more times */
    int backoff;              /* the next such pause (doubles on repeated failures) */
    int max_steps;            /* what one factorization costs in PCG steps (flop counts, pcg_solve) */
    double *grain_gradient;   /* the panel's grain_gradient for this coordinate at the last assembly */
    double *grain_response;   /* A^-1 of it (grain_response), computed once per factorization */
    int response_ready;       /* grain_response belongs to the current factor */
} coordinate_solver;

typedef struct panel_system {
    int32_t vertex_count;
    int32_t *vertices;        /* local -> cut-mesh vertex */
    int32_t *slots;           /* per panel face: 6 value slots: (0,0) (1,1) (2,2) (0,1) (0,2) (1,2) */
    int32_t segment_count;    /* length-only seam segments in this panel */
    int32_t *segment_ids;     /* their indices in textile_state's segment arrays */
    int32_t *segment_slots;   /* their off-diagonal value slot */
    coordinate_solver solver[2];
} panel_system;

/* The local step's output for one face: its share of the global step's
 * system for coordinate k (face_system), so the assembly is a scatter. */
typedef struct face_terms {
    double value[2][6];       /* matrix entries (0,0) (1,1) (2,2) (0,1) (0,2) (1,2) of its corners */
    double rhs[2][3];         /* right-hand side at its corners */
} face_terms;

typedef struct textile_state {
    const pz_pattern *pattern;
    double w_stretch, w_rigid, w_dart, w_seam, regularization;
    double grain[3];
    int threads;
    int parallel;             /* 1: big enough for threads to pay (PARALLEL_MIN_FACES*) */
    int across_panels;        /* parallel and several panels: per-panel loops are split across threads */
    int within_panel;         /* parallel and one panel: per-panel loops split their own faces or vertices */
    int32_t pose_total;       /* 1 + poses used */
    double *frames;           /* face_count x pose_total x 3: x1, x2, y2 of the 3D triangle's frame */
    double *areas;            /* face_count: rest 3D area */
    double *grain_local;      /* face_count x 2: the grain projected onto the rest face, in its frame */
    face_terms *terms;        /* face_count */
    double *face_energy;      /* face_count: the face's terms of Eq. 10 at the last evaluated uv */
    uint8_t *face_flipped;    /* face_count: 1 when its 2D triangle is collapsed or mirrored */
    int32_t *vertex_panel;    /* vertex_count */
    double *panel_pull;       /* panel_count: seam and dart energy of the panel's vertices */
    double *grain_norm;       /* panel_count: |S| of panel_grain_angle at the last evaluation */
    int project_grain;        /* 1: project_grain_turn after every global step */
    int32_t *vertex_local;    /* vertex_count: index within its panel */
    double *pull_weight;      /* vertex_count: summed seam/dart weights */
    double *pull_target;      /* vertex_count x 2: weighted sums of seam/dart targets */
    int32_t *offsets, *order; /* faces bucketed by panel */
    int32_t *outline_offsets; /* panel_count + 1: each panel's outline edges in outline_edges */
    int32_t *outline_edges;   /* 2 vertex ids per outline (boundary) edge of the cut mesh */
    panel_system *panels;
    /* Equal lengths of facing segments, on every seam and dart (build_segments);
     * seams that cannot be mirror images (classify_seams, demote_seams) keep
     * only this term, the others also get the reflection of Eqs. 7-8. */
    double mirror_tolerance;
    uint8_t *seam_length_only;   /* seam_count: 1 = no reflection term */
    int32_t *seam_segment_base;  /* seam_count: first segment of the seam, -1 when it has none */
    int32_t *dart_segment_base;  /* dart_count: first segment of the dart, -1 when it has none */
    uint8_t *dart_length_only;   /* dart_count: 1 = no axis symmetry term (demote_terms) */
    int32_t segment_count;       /* 2 per facing pair: side a (or leg a), then side b */
    int32_t *segment_ends;       /* segment_count x 2: cut-mesh vertices (from, to) */
    double *segment_target;      /* segment_count x 2: the local step's target for to - from */
    double *segment_weight;      /* segment_count */
    int32_t seam_segment_end;    /* the seams' segments come first: 0 .. seam_segment_end - 1 */
    /* 1 while the panels find their own flat shapes before the seams are
     * sewn (the strain goal's warm-up: seam terms left out, darts kept). */
    int seams_open;
    /* Strain goal (options->strain_limit; 0 = none): per face, the stretch
     * weight's multiplier (update_strain_weights) and the face's worst
     * |warp| or |weft| strain at the last evaluation. */
    double strain_limit;
    double *stretch_boost;       /* face_count, or NULL without a strain goal */
    double *face_strain;         /* face_count */
    /* With a strain goal the lengths are a goal too (SEAM_MISMATCH_GOAL):
     * per seam, then per dart, the relative mismatch of the two sides' 2D
     * lengths at the last evaluation, over the 3D length of side a. */
    double *curve_length_3d;     /* seam_count + dart_count */
    double *curve_mismatch;      /* seam_count + dart_count */
} textile_state;

/* ------------------------------------------------------------------------ */
/* Setup                                                                     */
/* ------------------------------------------------------------------------ */

static void solver_free(coordinate_solver *solver)
{
    if (!solver->started)
        return;
    cholmod_free_dense(&solver->work_e, &solver->common);
    cholmod_free_dense(&solver->work_y, &solver->common);
    cholmod_free_dense(&solver->solution, &solver->common);
    cholmod_free_dense(&solver->rhs, &solver->common);
    cholmod_free_dense(&solver->residual, &solver->common);
    free(solver->product);
    free(solver->current);
    free(solver->grain_gradient);
    free(solver->grain_response);
    cholmod_free_factor(&solver->factor, &solver->common);
    cholmod_free_sparse(&solver->matrix, &solver->common);
    cholmod_finish(&solver->common);
    solver->started = 0;
}

static void state_free(textile_state *state)
{
    if (state->panels)
        for (int32_t p = 0; p < state->pattern->panel_count; ++p) {
            solver_free(&state->panels[p].solver[0]);
            solver_free(&state->panels[p].solver[1]);
            free(state->panels[p].vertices);
            free(state->panels[p].slots);
            free(state->panels[p].segment_ids);
            free(state->panels[p].segment_slots);
        }
    free(state->panels);
    free(state->frames);
    free(state->areas);
    free(state->grain_local);
    free(state->terms);
    free(state->face_energy);
    free(state->face_flipped);
    free(state->vertex_panel);
    free(state->panel_pull);
    free(state->grain_norm);
    free(state->vertex_local);
    free(state->pull_weight);
    free(state->pull_target);
    free(state->offsets);
    free(state->order);
    free(state->outline_offsets);
    free(state->outline_edges);
    free(state->seam_length_only);
    free(state->seam_segment_base);
    free(state->dart_segment_base);
    free(state->dart_length_only);
    free(state->stretch_boost);
    free(state->face_strain);
    free(state->curve_length_3d);
    free(state->curve_mismatch);
    free(state->segment_ends);
    free(state->segment_target);
    free(state->segment_weight);
}

/* Index of entry (row, col), row <= col, in the sorted upper CSC matrix. */
static int32_t find_slot(const cholmod_sparse *matrix, int32_t row, int32_t col)
{
    const int *colp = matrix->p, *rows = matrix->i;
    int lo = colp[col], hi = colp[col + 1] - 1;
    while (lo < hi) {
        int mid = (lo + hi) / 2;
        if (rows[mid] < row)
            lo = mid + 1;
        else
            hi = mid;
    }
    return lo;
}

/* The length-only seam segments of one panel (both ends are in it: a seam
 * side lies in one panel). 0 when out of memory. */
static int panel_segments(const textile_state *state, panel_system *system, int32_t panel)
{
    int32_t count = 0;
    for (int32_t g = 0; g < state->segment_count; ++g)
        count += state->vertex_panel[state->segment_ends[2 * g]] == panel;
    system->segment_count = count;
    system->segment_ids = malloc((size_t)count * sizeof(int32_t) + 1);
    system->segment_slots = malloc((size_t)count * sizeof(int32_t) + 1);
    if (!system->segment_ids || !system->segment_slots)
        return 0;
    count = 0;
    for (int32_t g = 0; g < state->segment_count; ++g)
        if (state->vertex_panel[state->segment_ends[2 * g]] == panel)
            system->segment_ids[count++] = g;
    return 1;
}

/* Builds one panel's vertex list, sparsity pattern, slots, and the symbolic
 * factorization shared by its u and v systems. 0 on success, else a status
 * (message in *message). */
static pz_status panel_setup(textile_state *state, int32_t panel, char *message, size_t message_size)
{
    const pz_mesh *mesh = state->pattern->mesh;
    panel_system *system = &state->panels[panel];
    const int32_t *faces = state->order + state->offsets[panel];
    int32_t count = state->offsets[panel + 1] - state->offsets[panel];
    system->vertices = malloc((size_t)3 * count * sizeof(int32_t) + 1);
    system->slots = malloc((size_t)6 * count * sizeof(int32_t) + 1);
    if (!system->vertices || !system->slots) {
        snprintf(message, message_size, "textile: out of memory");
        return PZ_ERR_NOMEM;
    }
    /* Vertices in order of first use: vertex_local doubles as the "seen" mark
     * (every vertex belongs to one panel, so the panels write disjoint entries). */
    int32_t n = 0;
    for (int32_t i = 0; i < 3 * count; ++i) {
        int32_t v = mesh->faces[3 * faces[i / 3] + i % 3];
        if (state->vertex_local[v] < 0) {
            state->vertex_local[v] = n;
            system->vertices[n++] = v;
        }
    }
    system->vertex_count = n;
    if (!panel_segments(state, system, panel)) {
        snprintf(message, message_size, "textile: out of memory");
        return PZ_ERR_NOMEM;
    }
    for (int k = 0; k < 2; ++k) {
        cholmod_start(&system->solver[k].common);
        system->solver[k].started = 1;
        system->solver[k].common.supernodal = CHOLMOD_AUTO; /* as in lscm.c */
    }
    coordinate_solver *su = &system->solver[0], *sv = &system->solver[1];
    cholmod_triplet *triplet = cholmod_allocate_triplet(n, n, (size_t)6 * count + system->segment_count, 1,
                                                        CHOLMOD_REAL, &su->common);
    if (!triplet) {
        snprintf(message, message_size, "textile: out of memory");
        return PZ_ERR_NOMEM;
    }
    static const int pair[6][2] = {{0, 0}, {1, 1}, {2, 2}, {0, 1}, {0, 2}, {1, 2}};
    int *ti = triplet->i, *tj = triplet->j;
    double *tx = triplet->x;
    for (int32_t f = 0; f < count; ++f) {
        const int32_t *face = mesh->faces + 3 * faces[f];
        for (int e = 0; e < 6; ++e) {
            int32_t a = state->vertex_local[face[pair[e][0]]], b = state->vertex_local[face[pair[e][1]]];
            ti[triplet->nnz] = a < b ? a : b;
            tj[triplet->nnz] = a < b ? b : a;
            tx[triplet->nnz++] = 1;
        }
    }
    for (int32_t i = 0; i < system->segment_count; ++i) {
        const int32_t *ends = state->segment_ends + 2 * system->segment_ids[i];
        int32_t a = state->vertex_local[ends[0]], b = state->vertex_local[ends[1]];
        ti[triplet->nnz] = a < b ? a : b;
        tj[triplet->nnz] = a < b ? b : a;
        tx[triplet->nnz++] = 1;
    }
    su->matrix = cholmod_triplet_to_sparse(triplet, 0, &su->common);
    cholmod_free_triplet(&triplet, &su->common);
    if (su->matrix) {
        for (int32_t f = 0; f < count; ++f) {
            const int32_t *face = mesh->faces + 3 * faces[f];
            for (int e = 0; e < 6; ++e) {
                int32_t a = state->vertex_local[face[pair[e][0]]], b = state->vertex_local[face[pair[e][1]]];
                system->slots[6 * f + e] = find_slot(su->matrix, a < b ? a : b, a < b ? b : a);
            }
        }
        for (int32_t i = 0; i < system->segment_count; ++i) {
            const int32_t *ends = state->segment_ends + 2 * system->segment_ids[i];
            int32_t a = state->vertex_local[ends[0]], b = state->vertex_local[ends[1]];
            system->segment_slots[i] = find_slot(su->matrix, a < b ? a : b, a < b ? b : a);
        }
        su->factor = pz_param_analyze(su->matrix, mesh->positions, system->vertices, &su->common);
        /* The factorization costs `ratio` PCG steps: CHOLMOD's flop count for
         * the factor against two triangular solves and a product, times
         * FACTOR_FLOP_COST (the flops underestimate it below ~50K unknowns:
         * measured 16 steps against a count of 6 at 1K unknowns, 40 against
         * 16 at 10K, 32 against 42 at 100K). Deterministic, unlike timing. */
        double step = 4 * su->common.lnz + 4.0 * ((int *)su->matrix->p)[n];
        double ratio = step > 0 ? FACTOR_FLOP_COST * su->common.fl / step : 0;
        int max_steps = ratio < PCG_MIN_STEPS ? PCG_MIN_STEPS : ratio > PCG_MAX_STEPS ? PCG_MAX_STEPS : (int)ratio;
        su->max_steps = sv->max_steps = max_steps;
        sv->matrix = cholmod_copy_sparse(su->matrix, &sv->common);
    }
    if (su->factor && sv->matrix)
        sv->factor = cholmod_copy_factor(su->factor, &sv->common);
    int allocated = sv->factor != NULL;
    for (int k = 0; k < 2 && allocated; ++k) {
        coordinate_solver *s = &system->solver[k];
        s->backoff = 1;
        s->borrowing = k == 1 && s->max_steps >= BORROW_MIN_STEPS;
        s->rhs = cholmod_zeros(n, 1, CHOLMOD_REAL, &s->common);
        s->residual = cholmod_zeros(n, 1, CHOLMOD_REAL, &s->common);
        s->product = malloc((size_t)n * sizeof(double) + 1);
        s->current = malloc((size_t)n * sizeof(double) + 1);
        s->grain_gradient = malloc((size_t)n * sizeof(double) + 1);
        s->grain_response = calloc((size_t)n + 1, sizeof(double));
        allocated = s->rhs && s->residual && s->product && s->current && s->grain_gradient && s->grain_response;
    }
    if (!allocated) {
        snprintf(message, message_size, "textile: panel %d: out of memory in the symbolic analysis", panel);
        return PZ_ERR_NOMEM;
    }
    return PZ_OK;
}

static double dot3(const double a[3], const double b[3])
{
    return a[0] * b[0] + a[1] * b[1] + a[2] * b[2];
}

/* The 3D frame coordinates of every face in every pose used, and rest areas. */
static void compute_frames(textile_state *state)
{
    const pz_mesh *mesh = state->pattern->mesh;
    int32_t poses = state->pose_total;
#pragma omp parallel for schedule(static) num_threads(state->threads) if (state->parallel)
    for (int32_t f = 0; f < mesh->face_count; ++f) {
        double e1[3], e2[3];
        for (int32_t p = 0; p < poses; ++p) {
            const double *pos = p == 0 ? mesh->positions : mesh->poses + (size_t)(p - 1) * mesh->vertex_count * 3;
            double area = pz_param_face_frame(pos, mesh->faces + 3 * f, state->frames + ((size_t)f * poses + p) * 3,
                                              e1, e2);
            if (p == 0) {
                state->areas[f] = area;
                state->grain_local[2 * f] = dot3(state->grain, e1);
                state->grain_local[2 * f + 1] = dot3(state->grain, e2);
            }
        }
    }
}

/* Every vertex in one panel only (the panels' systems index their own
 * vertices and are built in parallel) and no panel empty. */
static pz_status check_panels(const pz_pattern *pattern, pz_ctx *ctx)
{
    const pz_mesh *mesh = pattern->mesh;
    int32_t *vertex_panel = malloc((size_t)mesh->vertex_count * sizeof(int32_t) + 1);
    int32_t *panel_faces = calloc((size_t)pattern->panel_count + 1, sizeof(int32_t));
    pz_status status = PZ_OK;
    if (!vertex_panel || !panel_faces)
        status = pz_error(ctx, PZ_ERR_NOMEM, "textile: out of memory");
    for (int32_t v = 0; !status && v < mesh->vertex_count; ++v)
        vertex_panel[v] = -1;
    for (int32_t i = 0; !status && i < 3 * mesh->face_count; ++i) {
        int32_t v = mesh->faces[i], panel = pattern->face_panel[i / 3];
        if (panel < 0 || panel >= pattern->panel_count || v < 0 || v >= mesh->vertex_count) {
            status = pz_error(ctx, PZ_ERR_DATA, "textile: face %d: panel or vertex out of range", i / 3);
        } else if (vertex_panel[v] >= 0 && vertex_panel[v] != panel) {
            status = pz_error(ctx, PZ_ERR_DATA, "textile: vertex %d is in panels %d and %d (the mesh is not cut)", v,
                              vertex_panel[v], panel);
        } else {
            vertex_panel[v] = panel;
            panel_faces[panel] += i % 3 == 0;
        }
    }
    for (int32_t p = 0; !status && p < pattern->panel_count; ++p)
        if (panel_faces[p] == 0)
            status = pz_error(ctx, PZ_ERR_DATA, "textile: panel %d has no faces", p);
    free(vertex_panel);
    free(panel_faces);
    return status;
}

static pz_status check_correspondences(const pz_pattern *pattern, pz_ctx *ctx)
{
    int32_t nv = pattern->mesh->vertex_count;
    for (int32_t s = 0; s < pattern->seam_count; ++s) {
        const pz_seam *seam = &pattern->seams[s];
        for (int32_t i = 0; i < seam->pair_count; ++i)
            if (seam->side_a[i] < 0 || seam->side_a[i] >= nv || seam->side_b[i] < 0 || seam->side_b[i] >= nv)
                return pz_error(ctx, PZ_ERR_DATA, "textile: seam %d: vertex out of range", s);
    }
    for (int32_t d = 0; d < pattern->dart_count; ++d) {
        const pz_dart *dart = &pattern->darts[d];
        if (dart->tip < 0 || dart->tip >= nv)
            return pz_error(ctx, PZ_ERR_DATA, "textile: dart %d: tip out of range", d);
        for (int32_t i = 0; i < dart->pair_count; ++i)
            if (dart->leg_a[i] < 0 || dart->leg_a[i] >= nv || dart->leg_b[i] < 0 || dart->leg_b[i] >= nv)
                return pz_error(ctx, PZ_ERR_DATA, "textile: dart %d: vertex out of range", d);
    }
    return PZ_OK;
}

/* The best-fit reflection x -> R x + t, R = [[c, s], [s, -c]] (symmetric,
 * det -1), of side a onto side b (Eqs. 7-8): centroids, then the R
 * maximizing c (S00 - S11) + s (S01 + S10), S = sum (q - cb)(p - ca)^T. */
static void fit_reflection(const pz_seam *seam, const double *uv, double *c_out, double *s_out, double t[2])
{
    int32_t n = seam->pair_count;
    double ca[2] = {0, 0}, cb[2] = {0, 0};
    for (int32_t i = 0; i < n; ++i)
        for (int k = 0; k < 2; ++k) {
            ca[k] += uv[2 * seam->side_a[i] + k] / n;
            cb[k] += uv[2 * seam->side_b[i] + k] / n;
        }
    double s00 = 0, s01 = 0, s10 = 0, s11 = 0;
    for (int32_t i = 0; i < n; ++i) {
        double px = uv[2 * seam->side_a[i]] - ca[0], py = uv[2 * seam->side_a[i] + 1] - ca[1];
        double qx = uv[2 * seam->side_b[i]] - cb[0], qy = uv[2 * seam->side_b[i] + 1] - cb[1];
        s00 += qx * px;
        s01 += qx * py;
        s10 += qy * px;
        s11 += qy * py;
    }
    double c = s00 - s11, s = s01 + s10, norm = sqrt(c * c + s * s);
    if (norm > 0) {
        c /= norm;
        s /= norm;
    } else {
        c = 1;
        s = 0;
    }
    *c_out = c;
    *s_out = s;
    t[0] = cb[0] - (c * ca[0] + s * ca[1]);
    t[1] = cb[1] - (s * ca[0] - c * ca[1]);
}

/* RMS distance of side b to side a after the best-fit reflection, over the
 * 3D length of side a; 0 for a seam of fewer than 2 pairs. */
static double relative_reflection_residual(const pz_mesh *mesh, const pz_seam *seam, const double *uv)
{
    int32_t n = seam->pair_count;
    if (n < 2)
        return 0;
    double c, s, t[2], sum = 0, length = 0;
    fit_reflection(seam, uv, &c, &s, t);
    for (int32_t i = 0; i < n; ++i) {
        const double *p = uv + 2 * seam->side_a[i], *q = uv + 2 * seam->side_b[i];
        double dx = c * p[0] + s * p[1] + t[0] - q[0], dy = s * p[0] - c * p[1] + t[1] - q[1];
        sum += dx * dx + dy * dy;
        if (i > 0) {
            const double *x = mesh->positions + 3 * seam->side_a[i - 1], *y = mesh->positions + 3 * seam->side_a[i];
            double d[3] = {x[0] - y[0], x[1] - y[1], x[2] - y[2]};
            length += sqrt(dot3(d, d));
        }
    }
    return length > 0 ? sqrt(sum / n) / length : 0;
}

/*
 * Weight of one pair of facing segments, relative to w_seam (w_dart for a
 * dart). A pair's term is w (|e_a| - |e_b|)^2 / 2 in mm^2, like a face's
 * stretch term w_stretch * area * strain^2: a mismatch d over a segment of
 * length h strains the band of faces along it by about d / h, which costs the
 * stretch term about w_stretch h^2 (d / h)^2 = w_stretch d^2, whatever the
 * resolution. At 100 the seams hold their equal lengths 100x more firmly than
 * the fabric resists the strain that takes: measured on the shared garments
 * (docs/param.md), every seam's sides within 0.4 % of each other, against
 * 2-5 % with the reflection term alone.
 */
#define SEGMENT_LENGTH_STIFFNESS 100.0

/* Appends the facing segments (a[i], a[i+1]) / (b[i], b[i+1]), i < n - 1,
 * and, when tip >= 0, (a[n-1], tip) / (b[n-1], tip); returns the first index. */
static int32_t add_segments(textile_state *state, const int32_t *a, const int32_t *b, int32_t n, int32_t tip,
                            double weight)
{
    int32_t base = state->segment_count;
    for (int32_t i = 0; i < n; ++i) {
        if (i + 1 >= n && tip < 0)
            break;
        int32_t next_a = i + 1 < n ? a[i + 1] : tip, next_b = i + 1 < n ? b[i + 1] : tip;
        int32_t *ends = state->segment_ends + 2 * (size_t)state->segment_count;
        ends[0] = a[i];
        ends[1] = next_a;
        ends[2] = b[i];
        ends[3] = next_b;
        state->segment_weight[state->segment_count] = weight;
        state->segment_weight[state->segment_count + 1] = weight;
        state->segment_count += 2;
    }
    return base;
}

/*
 * The facing segments of every seam (2 sides) and dart (2 legs, out to the
 * tip): each pair is held to equal lengths (seam_length_targets), which is
 * what sewing needs whatever the 2D shapes. 0 when out of memory.
 */
static int build_segments(textile_state *state)
{
    const pz_pattern *pattern = state->pattern;
    int32_t ns = pattern->seam_count, nd = pattern->dart_count;
    size_t pairs = 0;
    for (int32_t s = 0; s < ns; ++s)
        pairs += pattern->seams[s].pair_count > 1 ? (size_t)pattern->seams[s].pair_count - 1 : 0;
    for (int32_t d = 0; d < nd; ++d)
        pairs += (size_t)pattern->darts[d].pair_count;
    state->seam_segment_base = malloc(((size_t)ns + 1) * sizeof(int32_t));
    state->dart_segment_base = malloc(((size_t)nd + 1) * sizeof(int32_t));
    state->dart_length_only = calloc((size_t)nd + 1, 1);
    state->segment_ends = malloc(pairs * 4 * sizeof(int32_t) + 1);
    state->segment_target = calloc(pairs * 4 + 1, sizeof(double));
    state->segment_weight = malloc(pairs * 2 * sizeof(double) + 1);
    if (!state->seam_segment_base || !state->dart_segment_base || !state->dart_length_only || !state->segment_ends || !state->segment_target ||
        !state->segment_weight)
        return 0;
    state->segment_count = 0;
    for (int32_t s = 0; s < ns; ++s) {
        const pz_seam *seam = &pattern->seams[s];
        int usable = seam->pair_count >= 2 && state->w_seam > 0;
        state->seam_segment_base[s] =
            usable ? add_segments(state, seam->side_a, seam->side_b, seam->pair_count, -1,
                                  state->w_seam * SEGMENT_LENGTH_STIFFNESS)
                   : -1;
    }
    state->seam_segment_end = state->segment_count;
    for (int32_t d = 0; d < nd; ++d) {
        const pz_dart *dart = &pattern->darts[d];
        int usable = dart->pair_count >= 1 && state->w_dart > 0;
        state->dart_segment_base[d] =
            usable ? add_segments(state, dart->leg_a, dart->leg_b, dart->pair_count, dart->tip,
                                  state->w_dart * SEGMENT_LENGTH_STIFFNESS)
                   : -1;
    }
    return 1;
}

/*
 * Which seams can be mirror images (docs/param.md, "Seams that cannot be
 * mirror images"). At the LSCM start every panel has its own natural flat
 * shape; a seam whose sides are then further from mirror images than
 * mirror_tolerance (relative_reflection_residual) keeps only its equal
 * lengths: mirror seams (skirt side seams, a sleeve's underarm) measure
 * 0.2-3.6 % on the test garments, a collar band on a neckline 25 %, sleeve
 * caps in armholes 8-10 %, and forcing the latter into reflections takes
 * strains of that order. Returns the number of length-only seams, -1 when
 * out of memory.
 */
static int32_t classify_seams(textile_state *state, const double *uv)
{
    const pz_pattern *pattern = state->pattern;
    int32_t ns = pattern->seam_count, length_only = 0;
    if (!state->seam_length_only && !(state->seam_length_only = calloc((size_t)ns + 1, 1)))
        return -1;
    for (int32_t s = 0; s < ns; ++s) {
        const pz_seam *seam = &pattern->seams[s];
        state->seam_length_only[s] = 0;
        if (seam->pair_count < 2 || state->w_seam <= 0 ||
            !(relative_reflection_residual(pattern->mesh, seam, uv) > state->mirror_tolerance))
            continue;
        state->seam_length_only[s] = 1;
        ++length_only;
    }
    return length_only;
}

/* The outline edges of every panel (boundary half-edges of the cut mesh), for the crossing test. */
static pz_status build_outlines(textile_state *state, pz_ctx *ctx)
{
    const pz_pattern *pattern = state->pattern;
    pz_topology *topology = NULL;
    pz_status status = pz_topology_build(pattern->mesh, &topology, ctx);
    if (status)
        return status;
    int32_t np = pattern->panel_count;
    state->outline_offsets = calloc((size_t)np + 2, sizeof(int32_t));
    int32_t boundary = 0;
    for (int32_t h = 0; h < topology->halfedge_count; ++h)
        boundary += topology->twin[h] < 0;
    state->outline_edges = malloc((size_t)boundary * 2 * sizeof(int32_t) + 1);
    if (!state->outline_offsets || !state->outline_edges) {
        pz_topology_free(&topology);
        return pz_error(ctx, PZ_ERR_NOMEM, "textile: out of memory");
    }
    for (int32_t h = 0; h < topology->halfedge_count; ++h)
        if (topology->twin[h] < 0)
            ++state->outline_offsets[pattern->face_panel[pz_he_face(h)] + 2];
    for (int32_t p = 0; p < np; ++p)
        state->outline_offsets[p + 2] += state->outline_offsets[p + 1];
    for (int32_t h = 0; h < topology->halfedge_count; ++h) {
        if (topology->twin[h] >= 0)
            continue;
        int32_t slot = state->outline_offsets[pattern->face_panel[pz_he_face(h)] + 1]++;
        state->outline_edges[2 * slot] = pz_he_from(topology, h);
        state->outline_edges[2 * slot + 1] = pz_he_to(topology, h);
    }
    pz_topology_free(&topology);
    return PZ_OK;
}

/* 3D length of side a of every seam and leg a of every dart (to the tip). */
static int curve_lengths(textile_state *state)
{
    const pz_pattern *pattern = state->pattern;
    int32_t curves = pattern->seam_count + pattern->dart_count;
    state->curve_length_3d = calloc((size_t)curves + 1, sizeof(double));
    state->curve_mismatch = calloc((size_t)curves + 1, sizeof(double));
    if (!state->curve_length_3d || !state->curve_mismatch)
        return 0;
    const double *pos = pattern->mesh->positions;
    for (int32_t c = 0; c < curves; ++c) {
        int32_t base = c < pattern->seam_count ? state->seam_segment_base[c]
                                               : state->dart_segment_base[c - pattern->seam_count];
        int32_t pairs = c < pattern->seam_count ? pattern->seams[c].pair_count - 1
                                                : pattern->darts[c - pattern->seam_count].pair_count;
        for (int32_t g = base; base >= 0 && g < base + 2 * pairs; g += 2) {
            const double *x = pos + 3 * state->segment_ends[2 * g], *y = pos + 3 * state->segment_ends[2 * g + 1];
            double d[3] = {x[0] - y[0], x[1] - y[1], x[2] - y[2]};
            state->curve_length_3d[c] += sqrt(dot3(d, d));
        }
    }
    return 1;
}

static pz_status state_setup(textile_state *state, const double *uv, int32_t *length_only, pz_ctx *ctx)
{
    const pz_pattern *pattern = state->pattern;
    const pz_mesh *mesh = pattern->mesh;
    size_t nv = (size_t)mesh->vertex_count, nf = (size_t)mesh->face_count;
    state->frames = malloc(nf * state->pose_total * 3 * sizeof(double) + 1);
    state->areas = malloc(nf * sizeof(double) + 1);
    state->grain_local = malloc(nf * 2 * sizeof(double) + 1);
    state->terms = malloc(nf * sizeof(face_terms) + 1);
    state->vertex_local = malloc(nv * sizeof(int32_t) + 1);
    state->pull_weight = malloc(nv * sizeof(double) + 1);
    state->pull_target = malloc(nv * 2 * sizeof(double) + 1);
    state->panels = calloc((size_t)pattern->panel_count + 1, sizeof(panel_system));
    state->face_energy = malloc(nf * sizeof(double) + 1);
    state->face_flipped = malloc(nf + 1);
    state->vertex_panel = malloc(nv * sizeof(int32_t) + 1);
    state->panel_pull = malloc((size_t)pattern->panel_count * sizeof(double) + 1);
    state->grain_norm = calloc((size_t)pattern->panel_count + 1, sizeof(double));
    if (!state->frames || !state->areas || !state->grain_local || !state->terms || !state->vertex_local || !state->pull_weight ||
        !state->pull_target || !state->panels || !state->face_energy || !state->face_flipped || !state->vertex_panel ||
        !state->panel_pull || !state->grain_norm)
        return pz_error(ctx, PZ_ERR_NOMEM, "textile: out of memory");
    for (size_t v = 0; v < nv; ++v)
        state->vertex_local[v] = -1;
    for (size_t i = 0; i < 3 * nf; ++i) /* check_panels: every vertex is in one panel */
        state->vertex_panel[mesh->faces[i]] = pattern->face_panel[i / 3];
    if (!build_segments(state) || (*length_only = classify_seams(state, uv)) < 0)
        return pz_error(ctx, PZ_ERR_NOMEM, "textile: out of memory");
    pz_status outlined = build_outlines(state, ctx);
    if (outlined)
        return outlined;
    if (state->strain_limit > 0) {
        state->stretch_boost = malloc(nf * sizeof(double) + 1);
        state->face_strain = calloc(nf + 1, sizeof(double));
        if (!state->stretch_boost || !state->face_strain)
            return pz_error(ctx, PZ_ERR_NOMEM, "textile: out of memory");
        for (size_t f = 0; f < nf; ++f)
            state->stretch_boost[f] = 1;
        if (!curve_lengths(state))
            return pz_error(ctx, PZ_ERR_NOMEM, "textile: out of memory");
    }
    compute_frames(state);
    pz_status failed = PZ_OK;
    int32_t failed_panel = -1;
    char message[sizeof ctx->error] = "";
#pragma omp parallel for schedule(dynamic, 1) num_threads(state->threads) if (state->parallel)
    for (int32_t p = 0; p < pattern->panel_count; ++p) {
        char local_message[sizeof ctx->error];
        pz_status st = panel_setup(state, p, local_message, sizeof local_message);
        if (st) {
#pragma omp critical(pz_textile_failure)
            if (!failed || p < failed_panel) { /* the lowest panel, whatever the timing */
                failed = st;
                failed_panel = p;
                memcpy(message, local_message, sizeof message);
            }
        }
    }
    if (failed)
        return pz_error(ctx, failed, "%s", message);
    return PZ_OK;
}

/* ------------------------------------------------------------------------ */
/* Local step                                                                */
/* ------------------------------------------------------------------------ */

/*
 * Face f's share of coordinate k's system in the global step: the rigid
 * edge targets t (Eq. 6) and the stretch term (docs/param.md, "Consistent
 * stretch steps"). Eq. 10 evaluates w A (s_k - 1)^2, and with the other
 * coordinate fixed s_k of the new triangle is exactly s_k / a, a = c_k .
 * x_new (c_k: the old triangle's hat gradients), so the face's term is
 * w A (s_k / a - 1)^2. The paper's row w A (s_k - a)^2 has the right
 * minimizer (a = s_k) but its slope at a = 1 is 1 / s_k of the true one, so
 * the local/global map stops where the weighted slopes balance, not at a
 * stationary point of Eq. 10: near that fixed point every full step raised
 * the energy and was backtracked. Weighting the row by s_k makes the slopes
 * equal (the minimizer stays a = s_k). The other coordinate's term depends
 * on coordinate k through the shear, d s_o = -(J_1 . J_2 / s_o) dT_ko (T: the
 * new triangle in the old one's frame, T_ko = c_o . x_k,new): `cross` is its
 * slope, `cross_weight` its Gauss-Newton curvature w A (J_1 . J_2 / s_o)^2
 * along c_o (without it the force, scaled up by the strain goal's weights,
 * threw steps far off: most steps were backtracked on the shared garments).
 * Far from the goal (s_k outside [1/STRETCH_STEP_RANGE, STRETCH_STEP_RANGE];
 * the LSCM start of the face scan has faces squeezed 1000x) the row asks for
 * at most that factor per step (a trust region) and the shear terms are
 * left out.
 */
#define STRETCH_STEP_RANGE 2.0

/* Per coordinate k, over the poses used: the mean of s_k, of s_k^2, of
 * (s_k - 1) J_1 . J_2 / s_k (the shear slope) and of (J_1 . J_2 / s_k)^2. */
typedef struct stretch_figures {
    double s[2], second[2], slope[2], curvature[2];
} stretch_figures;

static void face_system(const double c[2][3], const stretch_figures *figures, const double t[3][2],
                        double stretch_weight, double w_rigid, int k, face_terms *terms)
{
    static const int pair[6][2] = {{0, 0}, {1, 1}, {2, 2}, {0, 1}, {0, 2}, {1, 2}};
    int o = 1 - k;
    const double *s = figures->s;
    double low = 1 / STRETCH_STEP_RANGE;
    double clamped = s[k] > STRETCH_STEP_RANGE ? STRETCH_STEP_RANGE : s[k] < low ? low : s[k];
    int near = clamped == s[k] && s[o] <= STRETCH_STEP_RANGE && s[o] >= low;
    double row_weight = stretch_weight * clamped;
    /* With poses the row's slope is the mean of the poses' slopes:
     * sum_p s_p (s_p - 1) = P s (s + var / s - 1); var = 0 for one pose. */
    double target = near ? s[k] + (figures->second[k] - s[k] * s[k]) / s[k] : clamped;
    double cross = near ? stretch_weight * figures->slope[o] : 0;
    double cross_weight = near ? stretch_weight * figures->curvature[o] : 0;
    for (int e = 0; e < 6; ++e) {
        int a = pair[e][0], b = pair[e][1];
        terms->value[k][e] = row_weight * c[k][a] * c[k][b] + cross_weight * c[o][a] * c[o][b] +
                             (a == b ? 2 * w_rigid : -w_rigid);
    }
    for (int a = 0; a < 3; ++a)
        terms->rhs[k][a] = row_weight * target * c[k][a] + cross * c[o][a];
    for (int e = 0; e < 3; ++e) {
        terms->rhs[k][(e + 1) % 3] += w_rigid * t[e][k];
        terms->rhs[k][e] -= w_rigid * t[e][k];
    }
}

/* Stretch coefficients and targets, rigid edge targets of face f, and from
 * them its share of the global step (face_system); returns its energy at
 * the current uv. */
static double local_face(const textile_state *state, int32_t f, const double *uv)
{
    const int32_t *face = state->pattern->mesh->faces + 3 * f;
    double q[3][2], c[2][3];
    for (int i = 0; i < 3; ++i) {
        q[i][0] = uv[2 * face[i]];
        q[i][1] = uv[2 * face[i] + 1];
    }
    double twice_area = (q[1][0] - q[0][0]) * (q[2][1] - q[0][1]) - (q[1][1] - q[0][1]) * (q[2][0] - q[0][0]);
    double area_3d = state->areas[f];
    /* A collapsed 2D triangle has no barycentric gradients, and a flipped
     * one would be held mirrored by its stretch rows (c . u = 1 whatever the
     * orientation): their stretch rows are dropped for this iteration and the
     * rotation-only rigidity term alone turns them back. */
    int stretch = twice_area > 1e-12 * area_3d && area_3d > 0;
    for (int i = 0; i < 3; ++i) {
        int j = (i + 1) % 3, k = (i + 2) % 3;
        c[0][i] = stretch ? (q[j][1] - q[k][1]) / twice_area : 0;
        c[1][i] = stretch ? (q[k][0] - q[j][0]) / twice_area : 0;
    }
    double qe[3][2];
    for (int e = 0; e < 3; ++e) {
        int j = (e + 1) % 3;
        qe[e][0] = q[j][0] - q[e][0];
        qe[e][1] = q[j][1] - q[e][1];
    }
    double image[2] = {0, 0}; /* c_k . q: 1 up to rounding (c_k are the hat functions' k-derivatives) */
    for (int k = 0; k < 2; ++k)
        for (int i = 0; i < 3; ++i)
            image[k] += c[k][i] * q[i][k];
    stretch_figures figures = {{0, 0}, {0, 0}, {0, 0}, {0, 0}};
    double t[3][2] = {{0, 0}, {0, 0}, {0, 0}}, stretch_sum[2] = {0, 0}, rigid_sum = 0;
    int32_t poses = state->pose_total;
    for (int32_t p = 0; p < poses; ++p) {
        const double *frame = state->frames + ((size_t)f * poses + p) * 3;
        double P[3][2] = {{0, 0}, {frame[0], 0}, {frame[1], frame[2]}};
        double thread[2][2], length[2]; /* J_k in the 3D frame, |J_k| */
        for (int k = 0; k < 2; ++k) {
            thread[k][0] = thread[k][1] = 0;
            for (int i = 0; i < 3; ++i) {
                thread[k][0] += c[k][i] * P[i][0];
                thread[k][1] += c[k][i] * P[i][1];
            }
            length[k] = sqrt(thread[k][0] * thread[k][0] + thread[k][1] * thread[k][1]);
        }
        double threads_dot = thread[0][0] * thread[1][0] + thread[0][1] * thread[1][1];
        for (int k = 0; k < 2; ++k) {
            double shear = length[k] > 0 ? threads_dot / length[k] : 0;
            figures.s[k] += length[k];
            figures.second[k] += length[k] * length[k];
            figures.slope[k] += (length[k] - 1) * shear;
            figures.curvature[k] += shear * shear;
            stretch_sum[k] += (length[k] - image[k]) * (length[k] - image[k]);
        }
        double pe[3][2], s00 = 0, s01 = 0, s10 = 0, s11 = 0;
        for (int e = 0; e < 3; ++e) {
            int j = (e + 1) % 3;
            pe[e][0] = P[j][0] - P[e][0];
            pe[e][1] = P[j][1] - P[e][1];
            s00 += qe[e][0] * pe[e][0];
            s01 += qe[e][0] * pe[e][1];
            s10 += qe[e][1] * pe[e][0];
            s11 += qe[e][1] * pe[e][1];
        }
        /* The rotation maximizing tr(R^T S), S = sum q_e p_e^T. */
        double cs = s00 + s11, sn = s10 - s01, norm = sqrt(cs * cs + sn * sn);
        if (norm > 0) {
            cs /= norm;
            sn /= norm;
        } else {
            cs = 1;
            sn = 0;
        }
        for (int e = 0; e < 3; ++e) {
            double target[2] = {cs * pe[e][0] - sn * pe[e][1], sn * pe[e][0] + cs * pe[e][1]};
            for (int k = 0; k < 2; ++k) {
                t[e][k] += target[k];
                rigid_sum += (qe[e][k] - target[k]) * (qe[e][k] - target[k]);
            }
        }
    }
    double energy = 0, stretch_weight = state->w_stretch * area_3d * (state->stretch_boost ? state->stretch_boost[f] : 1);
    double worst_strain = 0;
    for (int k = 0; k < 2; ++k) {
        figures.s[k] /= poses;
        figures.second[k] /= poses;
        figures.slope[k] /= poses;
        figures.curvature[k] /= poses;
        if (stretch) {
            energy += stretch_weight * stretch_sum[k] / poses;
            /* s_k - 1 is the strain |J_k| - 1 of docs/metrics.md (the mean over poses). */
            worst_strain = fmax(worst_strain, fabs(figures.s[k] - 1));
        }
        for (int e = 0; e < 3; ++e)
            t[e][k] /= poses;
    }
    if (state->face_strain)
        state->face_strain[f] = worst_strain;
    energy += state->w_rigid * rigid_sum / poses;
    for (int k = 0; k < 2; ++k)
        face_system(c, &figures, t, stretch_weight, state->w_rigid, k, &state->terms[f]);
    state->face_energy[f] = energy;
    state->face_flipped[f] = !(twice_area > 0);
    return energy;
}

/* Adds weight * |x - target|^2 for one vertex; returns the energy. */
static double pull(textile_state *state, int32_t v, double weight, const double target[2], const double *uv)
{
    state->pull_weight[v] += weight;
    state->pull_target[2 * v] += weight * target[0];
    state->pull_target[2 * v + 1] += weight * target[1];
    double du = uv[2 * v] - target[0], dv = uv[2 * v + 1] - target[1];
    state->panel_pull[state->vertex_panel[v]] += weight * (du * du + dv * dv);
    return weight * (du * du + dv * dv);
}

/* Eqs. 7-8: best-fit reflection M of side a onto side b (fit_reflection),
 * midpoint targets for both sides. */
static double seam_targets(textile_state *state, const pz_seam *seam, const double *uv)
{
    int32_t n = seam->pair_count;
    if (n < 2 || state->w_seam <= 0)
        return 0;
    double c, s, t[2];
    fit_reflection(seam, uv, &c, &s, t);
    double energy = 0;
    for (int32_t i = 0; i < n; ++i) {
        const double *p = uv + 2 * seam->side_a[i], *q = uv + 2 * seam->side_b[i];
        double mp[2] = {c * p[0] + s * p[1] + t[0], s * p[0] - c * p[1] + t[1]};
        double qt[2] = {q[0] - t[0], q[1] - t[1]};
        double mq[2] = {c * qt[0] + s * qt[1], s * qt[0] - c * qt[1]}; /* M^-1 q = R (q - t) */
        double target_a[2] = {(p[0] + mq[0]) / 2, (p[1] + mq[1]) / 2};
        double target_b[2] = {(q[0] + mp[0]) / 2, (q[1] + mp[1]) / 2};
        energy += pull(state, seam->side_a[i], state->w_seam, target_a, uv);
        energy += pull(state, seam->side_b[i], state->w_seam, target_b, uv);
    }
    return energy;
}

/*
 * Equal lengths of facing segments (build_segments), pairs g = first,
 * first + 2, ...: for e_a = a_{i+1} - a_i and e_b = b_{i+1} - b_i the targets
 * keep each segment's direction and give both the mean length
 * L = (|e_a| + |e_b|) / 2. Those are the minimizers of |e_a - L d_a|^2 +
 * |e_b - L d_b|^2 over unit d_a, d_b and L, so the term is
 * w (|e_a| - |e_b|)^2 / 2 and the local/global step stays a majorization,
 * like Procrustes for the rigidity term. Matching segment by segment (not
 * only the totals) keeps facing notches together.
 */
static double segment_length_targets(textile_state *state, int32_t first, int32_t pairs, const double *uv,
                                     double side_length[2])
{
    double energy = 0;
    side_length[0] = side_length[1] = 0;
    for (int32_t g = first; g < first + 2 * pairs; g += 2) {
        double w = state->segment_weight[g];
        double length[2], e[2][2];
        for (int side = 0; side < 2; ++side) {
            const int32_t *ends = state->segment_ends + 2 * (g + side);
            e[side][0] = uv[2 * ends[1]] - uv[2 * ends[0]];
            e[side][1] = uv[2 * ends[1] + 1] - uv[2 * ends[0] + 1];
            length[side] = sqrt(e[side][0] * e[side][0] + e[side][1] * e[side][1]);
        }
        double mean = (length[0] + length[1]) / 2;
        side_length[0] += length[0];
        side_length[1] += length[1];
        for (int side = 0; side < 2; ++side) {
            const int32_t *ends = state->segment_ends + 2 * (g + side);
            double *target = state->segment_target + 2 * (g + side);
            double dx = length[side] > 0 ? e[side][0] / length[side] : 1;
            double dy = length[side] > 0 ? e[side][1] / length[side] : 0;
            double scale = ends[0] == ends[1] ? 0 : mean; /* a repeated vertex: no segment (global step skips it) */
            target[0] = scale * dx;
            target[1] = scale * dy;
            double rx = e[side][0] - target[0], ry = e[side][1] - target[1];
            double term = w * (rx * rx + ry * ry);
            state->panel_pull[state->vertex_panel[ends[0]]] += term;
            energy += term;
        }
    }
    return energy;
}

/* Eq. 9: axis through the tip fitting the leg midpoints; targets average each
 * leg point with its partner mirrored about that axis. */
static double dart_targets(textile_state *state, const pz_dart *dart, const double *uv)
{
    int32_t n = dart->pair_count;
    if (n < 1 || state->w_dart <= 0)
        return 0;
    const double *tip = uv + 2 * dart->tip;
    double c00 = 0, c01 = 0, c11 = 0;
    for (int32_t i = 0; i < n; ++i) {
        const double *p = uv + 2 * dart->leg_a[i], *q = uv + 2 * dart->leg_b[i];
        double rx = (p[0] + q[0]) / 2 - tip[0], ry = (p[1] + q[1]) / 2 - tip[1];
        c00 += rx * rx;
        c01 += rx * ry;
        c11 += ry * ry;
    }
    if (c00 + c11 <= 0)
        return 0;
    double angle = 0.5 * atan2(2 * c01, c00 - c11); /* principal direction */
    double dx = cos(angle), dy = sin(angle);
    double m00 = 2 * dx * dx - 1, m01 = 2 * dx * dy, m11 = 2 * dy * dy - 1;
    double energy = 0;
    for (int32_t i = 0; i < n; ++i) {
        const double *p = uv + 2 * dart->leg_a[i], *q = uv + 2 * dart->leg_b[i];
        double px = p[0] - tip[0], py = p[1] - tip[1], qx = q[0] - tip[0], qy = q[1] - tip[1];
        double mirrored_p[2] = {tip[0] + m00 * px + m01 * py, tip[1] + m01 * px + m11 * py};
        double mirrored_q[2] = {tip[0] + m00 * qx + m01 * qy, tip[1] + m01 * qx + m11 * qy};
        double target_a[2] = {(p[0] + mirrored_q[0]) / 2, (p[1] + mirrored_q[1]) / 2};
        double target_b[2] = {(q[0] + mirrored_p[0]) / 2, (q[1] + mirrored_p[1]) / 2};
        energy += pull(state, dart->leg_a[i], state->w_dart, target_a, uv);
        energy += pull(state, dart->leg_b[i], state->w_dart, target_b, uv);
    }
    return energy;
}

static void record_mismatch(textile_state *state, int32_t curve, const double sides[2])
{
    if (state->curve_mismatch && state->curve_length_3d[curve] > 0)
        state->curve_mismatch[curve] = fabs(sides[0] - sides[1]) / state->curve_length_3d[curve];
}

/* The whole local step; returns E_textile (Eq. 10) at the current uv. */
static double local_step(textile_state *state, const double *uv)
{
    const pz_pattern *pattern = state->pattern;
    int32_t nf = pattern->mesh->face_count;
    double block_energy[SUM_BLOCKS], energy = 0;
#pragma omp parallel for schedule(static) num_threads(state->threads) if (state->parallel)
    for (int block = 0; block < SUM_BLOCKS; ++block) {
        double sum = 0;
        for (int32_t f = block_start(0, nf, block); f < block_start(0, nf, block + 1); ++f)
            sum += local_face(state, f, uv);
        block_energy[block] = sum;
    }
    for (int block = 0; block < SUM_BLOCKS; ++block)
        energy += block_energy[block];
    /* Seams and darts touch few vertices: serial. */
    memset(state->pull_weight, 0, (size_t)pattern->mesh->vertex_count * sizeof(double));
    memset(state->pull_target, 0, (size_t)pattern->mesh->vertex_count * 2 * sizeof(double));
    memset(state->panel_pull, 0, (size_t)pattern->panel_count * sizeof(double));
    double sides[2];
    for (int32_t s = 0; s < pattern->seam_count && !state->seams_open; ++s) {
        const pz_seam *seam = &pattern->seams[s];
        if (state->seam_segment_base[s] >= 0) {
            energy += segment_length_targets(state, state->seam_segment_base[s], seam->pair_count - 1, uv, sides);
            record_mismatch(state, s, sides);
        }
        if (!state->seam_length_only[s])
            energy += seam_targets(state, seam, uv);
    }
    for (int32_t d = 0; d < pattern->dart_count; ++d) {
        const pz_dart *dart = &pattern->darts[d];
        if (state->dart_segment_base[d] >= 0) {
            energy += segment_length_targets(state, state->dart_segment_base[d], dart->pair_count, uv, sides);
            record_mismatch(state, pattern->seam_count + d, sides);
        }
        if (!state->dart_length_only[d])
            energy += dart_targets(state, dart, uv);
    }
    return energy;
}

/*
 * The angle that turns panel p's area-weighted projected grain onto +v: the
 * computation of pz_param_grain_angle (lscm.c) with the rest frames and the
 * grain in each frame precomputed at setup. *norm: the length of the
 * weighted sum (0 when the angle is left at 0).
 */
static double panel_grain_angle(const textile_state *state, int32_t panel, const double *uv, double *norm)
{
    const pz_mesh *mesh = state->pattern->mesh;
    double glen = sqrt(dot3(state->grain, state->grain));
    int32_t first = state->offsets[panel], count = state->offsets[panel + 1] - first;
    double block_sums[SUM_BLOCKS][3]; /* sum_u, sum_v, area_sum */
#pragma omp parallel for schedule(static) num_threads(state->threads) if (state->within_panel)
    for (int block = 0; block < SUM_BLOCKS; ++block) {
        double sum_u = 0, sum_v = 0, area_sum = 0;
        for (int32_t i = block_start(first, count, block); i < block_start(first, count, block + 1); ++i) {
            int32_t f = state->order[i];
            const int32_t *face = mesh->faces + 3 * f;
            const double *frame = state->frames + (size_t)f * state->pose_total * 3;
            double area = state->areas[f];
            if (area <= 0)
                continue;
            area_sum += area;
            double a = state->grain_local[2 * f] / glen, b = state->grain_local[2 * f + 1] / glen;
            double projected = sqrt(a * a + b * b);
            if (projected < 1e-9)
                continue;
            const double *q0 = uv + 2 * face[0], *q1 = uv + 2 * face[1], *q2 = uv + 2 * face[2];
            double t = b / frame[2];
            double s = (a - frame[1] * t) / frame[0];
            double dx = (q1[0] - q0[0]) * s + (q2[0] - q0[0]) * t, dy = (q1[1] - q0[1]) * s + (q2[1] - q0[1]) * t;
            double dlen = sqrt(dx * dx + dy * dy);
            if (!(dlen > 0))
                continue;
            sum_u += area * projected * dx / dlen;
            sum_v += area * projected * dy / dlen;
        }
        block_sums[block][0] = sum_u;
        block_sums[block][1] = sum_v;
        block_sums[block][2] = area_sum;
    }
    double sum_u = 0, sum_v = 0, area_sum = 0;
    for (int block = 0; block < SUM_BLOCKS; ++block) {
        sum_u += block_sums[block][0];
        sum_v += block_sums[block][1];
        area_sum += block_sums[block][2];
    }
    *norm = sqrt(sum_u * sum_u + sum_v * sum_v);
    if (!(*norm > 1e-3 * area_sum)) {
        *norm = 0;
        return 0;
    }
    return 1.57079632679489661923 - atan2(sum_v, sum_u);
}

/* pz_param_rotate_vertices (lscm.c) for one panel, split across threads when
 * the pattern is one big panel. */
static void rotate_panel(const textile_state *state, int32_t panel, double angle, double *uv)
{
    const panel_system *system = &state->panels[panel];
    int32_t n = system->vertex_count;
    if (angle == 0 || n == 0)
        return;
    double block_sums[SUM_BLOCKS][2], cu = 0, cv = 0;
#pragma omp parallel for schedule(static) num_threads(state->threads) if (state->within_panel)
    for (int block = 0; block < SUM_BLOCKS; ++block) {
        double sum_u = 0, sum_v = 0;
        for (int32_t l = block_start(0, n, block); l < block_start(0, n, block + 1); ++l) {
            sum_u += uv[2 * system->vertices[l]];
            sum_v += uv[2 * system->vertices[l] + 1];
        }
        block_sums[block][0] = sum_u;
        block_sums[block][1] = sum_v;
    }
    for (int block = 0; block < SUM_BLOCKS; ++block) {
        cu += block_sums[block][0];
        cv += block_sums[block][1];
    }
    cu /= n;
    cv /= n;
    double c = cos(angle), s = sin(angle);
#pragma omp parallel for schedule(static) num_threads(state->threads) if (state->within_panel)
    for (int32_t l = 0; l < n; ++l) {
        double *p = uv + 2 * system->vertices[l];
        double x = p[0] - cu, y = p[1] - cv;
        p[0] = cu + c * x - s * y;
        p[1] = cv + s * x + c * y;
    }
}

/* Step 1: rigid rotation of every panel so its warp follows the grain. */
static void align_grain(textile_state *state, double *uv)
{
    const pz_pattern *pattern = state->pattern;
#pragma omp parallel for schedule(dynamic, 1) num_threads(state->threads) if (state->across_panels)
    for (int32_t p = 0; p < pattern->panel_count; ++p)
        rotate_panel(state, p, panel_grain_angle(state, p, uv, &state->grain_norm[p]), uv);
}

/*
 * The gradient of panel p's grain angle (panel_grain_angle: theta = pi/2 -
 * atan2(S_v, S_u), S the weighted sum of the faces' unit 2D grain directions
 * d / |d|) with respect to coordinate k of its vertices, at an aligned uv (S
 * along +v, so d theta = dS_u / |S|): per face w (e_u - dhat_u dhat)_k / |d|
 * times d's coefficient of each corner. gradient: the panel's vertex_count,
 * written.
 */
static void grain_gradient(const textile_state *state, int32_t panel, int k, const double *uv, double *gradient)
{
    const pz_mesh *mesh = state->pattern->mesh;
    memset(gradient, 0, (size_t)state->panels[panel].vertex_count * sizeof(double));
    double glen = sqrt(dot3(state->grain, state->grain)), norm = state->grain_norm[panel];
    if (!(norm > 0))
        return;
    for (int32_t i = state->offsets[panel]; i < state->offsets[panel + 1]; ++i) {
        int32_t f = state->order[i];
        const int32_t *face = mesh->faces + 3 * f;
        const double *frame = state->frames + (size_t)f * state->pose_total * 3;
        double a = state->grain_local[2 * f] / glen, b = state->grain_local[2 * f + 1] / glen;
        double projected = sqrt(a * a + b * b);
        if (state->areas[f] <= 0 || projected < 1e-9)
            continue;
        /* As in panel_grain_angle: d = (q1 - q0) s + (q2 - q0) t. */
        double t = b / frame[2], s = (a - frame[1] * t) / frame[0];
        const double *q0 = uv + 2 * face[0], *q1 = uv + 2 * face[1], *q2 = uv + 2 * face[2];
        double dx = (q1[0] - q0[0]) * s + (q2[0] - q0[0]) * t, dy = (q1[1] - q0[1]) * s + (q2[1] - q0[1]) * t;
        double dlen = sqrt(dx * dx + dy * dy);
        if (!(dlen > 0))
            continue;
        double ux = dx / dlen, uy = dy / dlen;
        double g = state->areas[f] * projected * ((k == 0 ? 1 : 0) - ux * (k == 0 ? ux : uy)) / (dlen * norm);
        gradient[state->vertex_local[face[1]]] += g * s;
        gradient[state->vertex_local[face[2]]] += g * t;
        gradient[state->vertex_local[face[0]]] -= g * (s + t);
    }
}

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
 * grain_gradient, for project_grain_turn (the residual vector is free
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
 * The global step's solve: one step of conjugate gradients preconditioned
 * with the factor of an earlier iteration's matrix, from the current
 * coordinates (x + alpha z, z = M^-1 (b - A x), alpha minimizing the
 * quadratic along z). The matrix changes only through the stretch terms, so
 * the old factor is nearly A^-1 and one step takes most of the way; the
 * global step need not be exact (the next local step changes the matrix
 * again, and the line search checks every step): measured, one step per
 * iteration reached the same energies as solving to 1e-2 (2-4 steps) in
 * the same number of iterations (docs/param.md, "Speed"). Nothing is done
 * when the residual is already below PCG_TOLERANCE of the right-hand side
 * or r^T M^-1 r below PCG_MODEL_TOLERANCE of x^T A x. The factor is
 * refreshed for the next iteration when, at the rate of this step, reducing
 * the residual by PCG_REDUCTION would take more than half of what one
 * factorization costs in steps (max_steps, from flop counts: about 7 at 1K
 * vertices, 65 at 100K, clamped to 4..60): it has gone stale. A step that
 * does not lower the residual returns 0 (uv untouched; solve_coordinate
 * factorizes and solves directly, and when that keeps happening -- large,
 * uneven distortion: the face scan -- backs off from PCG exponentially, 1,
 * 2, 4, ... direct solves before the next try).
 */
#define PCG_TOLERANCE 1e-8
#define PCG_REDUCTION 1e-2
#define PCG_MODEL_TOLERANCE 1e-9
static int pcg_solve(const panel_system *system, coordinate_solver *solver, cholmod_factor *factor, int k, double *uv)
{
    int32_t n = system->vertex_count;
    double *b = solver->rhs->x, *r = solver->residual->x, *ap = solver->product;
    /* The iterate lives in uv's column k; gather it into `current`. */
    double *current = solver->current;
    for (int32_t l = 0; l < n; ++l)
        current[l] = uv[2 * system->vertices[l] + k];
    symmetric_product(solver->matrix, current, ap);
    double b_norm = 0, r_norm = 0, scale = 0;
    for (int32_t l = 0; l < n; ++l) {
        r[l] = b[l] - ap[l];
        b_norm += b[l] * b[l];
        r_norm += r[l] * r[l];
        scale += current[l] * ap[l];
    }
    if (r_norm <= PCG_TOLERANCE * PCG_TOLERANCE * fmax(b_norm, 1e-300))
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
    /* Steps to PCG_REDUCTION at this rate (squared norms). */
    if (2 * log(PCG_REDUCTION) / log(new_norm / r_norm) > solver->max_steps / 2)
        solver->refactor = 1;
    for (int32_t l = 0; l < n; ++l)
        uv[2 * system->vertices[l] + k] = current[l] + alpha * z[l];
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
        grain_gradient(state, panel, k, uv, solver->grain_gradient);
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
    solver->refactor = solver->borrowing = 0;
    solver->response_ready = 0;
    if (k == 0 && system->solver[1].borrowing)
        system->solver[1].response_ready = 0;
    return CHOLMOD_OK;
}

/*
 * Solves coordinate k of one panel and writes it into uv: directly with a
 * factor made this iteration, otherwise one preconditioned step
 * (pcg_solve). A step that fails leaves uv alone and marks the coordinate
 * `failed` (global_step then factorizes and solves it directly), and asks
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
        solver->fresh = 0;
        if (!cholmod_solve2(CHOLMOD_A, factor, solver->rhs, NULL, &solver->solution, NULL, &solver->work_y,
                            &solver->work_e, &solver->common))
            return solver->common.status ? solver->common.status : -1;
        const double *x = solver->solution->x;
        for (int32_t l = 0; l < system->vertex_count; ++l)
            uv[2 * system->vertices[l] + k] = x[l];
    } else if (pcg_solve(system, solver, factor, k, uv)) {
        solver->backoff = 1;
    } else {
        solver->failed = 1;
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
static pz_status global_step(textile_state *state, double *uv, pz_ctx *ctx)
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
 * rotation its stretch terms prefer, and align_grain turns it back: near
 * convergence that raised the energy of every full step (the fixed point of
 * step-then-align is not a minimum of Eq. 10 among aligned patterns) and the
 * iteration stalled in backtracking. So the step d = new - old of each panel
 * is replaced by the minimizer of the global step's quadratic under the
 * linearized constraint g . d = 0 (g: the gradient of the panel's grain angle,
 * grain_gradient, both coordinates): d - (g . d / g . z) z with z = A^-1 g,
 * taken from the last factorization (a stale z only makes the projected step
 * a little less than optimal; g . d = 0 holds exactly). The step then turns
 * the panel only to second order, and the iteration's fixed points are the
 * stationary points of Eq. 10 among aligned patterns.
 */
static void project_grain_turn(const textile_state *state, const double *previous, double *uv)
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
    align_grain(state, uv);
    return local_step(state, uv);
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
 * flattening ended at strain 0.30 against 0.048 with this warm-up. */
#define WARMUP_ITERATIONS 5

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

/* The next global step factorizes every coordinate's own matrix and solves
 * it directly (v stops borrowing u's factor). */
static void demand_exact_solves(textile_state *state)
{
    for (int32_t p = 0; p < state->pattern->panel_count; ++p)
        for (int k = 0; k < 2; ++k) {
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
 * changed no weight.
 */
static pz_status iterate(textile_state *state, step_control *control, const pz_textile_options *options,
                         int iterations, double tolerance, double *uv, double *energy, pz_textile_result *outcome,
                         pz_ctx *ctx)
{
    const pz_pattern *pattern = state->pattern;
    int exact_retried = 0;
    for (int it = 0; it < iterations; ++it) {
        double previous = *energy;
        memcpy(control->previous_uv, uv, (size_t)pattern->mesh->vertex_count * 2 * sizeof(double));
        pz_status status = global_step(state, uv, ctx);
        if (status)
            return status;
        if (state->project_grain)
            project_grain_turn(state, control->previous_uv, uv);
        int bounded, damped, stalled;
        *energy = line_search(state, control, previous, tolerance, uv, &bounded, &damped, &stalled);
        outcome->bounded_steps += bounded;
        outcome->damped_steps += damped;
        ++outcome->iterations_run;
        if (options && options->on_iteration)
            options->on_iteration(options->user, outcome->iterations_run, *energy);
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
 * The team size when the caller leaves it to us (options->threads == 0):
 * OpenMP's maximum, but one thread when the machine has no core to spare.
 * libgomp's default wait is active, so a thread descheduled by other work
 * leaves its partner spinning at every barrier: at 200K faces and load 3.4
 * on 2 cores, 66-184 ms per iteration with two threads against 79-109 ms
 * with one (docs/param.md, "Threads"). "No core to spare": the 1-minute load
 * average, less the one thread this process runs itself, leaves less than
 * one more core. The result does not depend on the team size (SUM_BLOCKS),
 * so this only changes the time.
 */
static int default_threads(void)
{
    int threads = omp_get_max_threads();
    long cores = sysconf(_SC_NPROCESSORS_ONLN);
    double load[1];
    if (threads > 1 && cores > 0 && getloadavg(load, 1) == 1) {
        double spare = (double)cores - fmax(load[0] - 1.0, 0.0);
        if (spare < (double)threads)
            threads = spare >= 2.0 ? (int)spare : 1;
    }
    return threads;
}

static void read_options(textile_state *state, const pz_textile_options *options, int *iterations, double *tolerance)
{
    pz_textile_options defaults;
    memset(&defaults, 0, sizeof defaults);
    if (!options)
        options = &defaults;
    *iterations = options->iterations > 0 ? options->iterations : 20;
    *tolerance = options->tolerance > 0 ? options->tolerance : 1e-6;
    if (options->weights_given) {
        state->w_stretch = options->weight_stretch;
        state->w_rigid = options->weight_rigid;
        state->w_dart = options->weight_dart;
        state->w_seam = options->weight_seam;
    } else {
        state->w_stretch = 5;
        state->w_rigid = 1;
        state->w_dart = 5;
        state->w_seam = 5;
    }
    double up[3] = {0, 0, 1};
    memcpy(state->grain, options->grain_given ? options->grain : up, sizeof state->grain);
    state->threads = options->threads > 0 ? options->threads : default_threads();
    state->parallel = state->threads > 1 && state->pattern->mesh->face_count >=
                                                (options->threads > 0 ? PARALLEL_MIN_FACES_ASKED : PARALLEL_MIN_FACES);
    /* A parallel loop over one panel leaves every thread but one spinning at
     * the barrier (on a busy machine, descheduled: 5x slower iterations were
     * measured), so one-panel patterns split the work inside the panel. */
    state->across_panels = state->parallel && state->pattern->panel_count > 1;
    state->within_panel = state->parallel && state->pattern->panel_count == 1;
    state->pose_total = 1 + (options->use_poses ? state->pattern->mesh->pose_count : 0);
    state->regularization = 1e-8 * fmax(1.0, state->w_stretch + state->w_rigid);
    state->mirror_tolerance = options->seam_mirror_tolerance > 0 ? options->seam_mirror_tolerance : 0.05;
    state->strain_limit = options->strain_limit > 0 ? options->strain_limit : 0;
}

pz_status pz_param_textile(const pz_pattern *pattern, const pz_textile_options *options, double *uv,
                           pz_textile_result *result, pz_ctx *ctx)
{
    if (!pattern || !pattern->mesh || !uv)
        return pz_error(ctx, PZ_ERR_USAGE, "textile: no pattern or no output");
    textile_state state;
    memset(&state, 0, sizeof state);
    state.pattern = pattern;
    int iterations;
    double tolerance;
    read_options(&state, options, &iterations, &tolerance);
    if (state.w_stretch < 0 || state.w_rigid < 0 || state.w_dart < 0 || state.w_seam < 0)
        return pz_error(ctx, PZ_ERR_USAGE, "textile: weights must not be negative");
    pz_textile_result outcome;
    memset(&outcome, 0, sizeof outcome);
    double start = pz_seconds();
    pz_status status = check_panels(pattern, ctx);
    if (!status)
        status = check_correspondences(pattern, ctx);
    if (!status)
        status = pz_param_lscm_pattern(pattern, state.grain, uv, ctx);
    if (!status)
        status = pz_param_panel_faces(pattern, &state.offsets, &state.order, ctx);
    if (!status)
        status = state_setup(&state, uv, &outcome.length_only_seams, ctx);
    if (status) {
        state_free(&state);
        return status;
    }
    step_control control;
    memset(&control, 0, sizeof control);
    if (!step_control_init(&control, pattern)) {
        step_control_free(&control);
        state_free(&state);
        return pz_error(ctx, PZ_ERR_NOMEM, "textile: out of memory");
    }
    double solve_start = pz_seconds();
    outcome.init_ms = 1e3 * (solve_start - start);
    /* With a strain goal the seams are sewn after a warm-up (docs/param.md, "The strain goal"). */
    state.seams_open = state.strain_limit > 0 && pattern->seam_count > 0 && state.w_seam > 0;
    double energy = evaluate(&state, uv);
    panel_figures(&state, uv, control.energy, control.flipped);
    memcpy(control.allowed_flipped, control.flipped, (size_t)pattern->panel_count * sizeof(int32_t));
    outcome.initial_energy = energy;
    if (options && options->on_iteration)
        options->on_iteration(options->user, 0, energy);
    if (state.seams_open) {
        status = iterate(&state, &control, options, WARMUP_ITERATIONS, tolerance, uv, &energy, &outcome, ctx);
        state.seams_open = 0;
        if (!status && (outcome.length_only_seams = classify_seams(&state, uv)) < 0)
            status = pz_error(ctx, PZ_ERR_NOMEM, "textile: out of memory");
        energy = evaluate(&state, uv);
        panel_figures(&state, uv, control.energy, control.flipped);
    }
    /* Round 0 is the paper's iteration; with a strain goal, later rounds
     * follow only when some panel still breaks it and demote_terms freed
     * that panel of a symmetry term (docs/param.md, "The strain goal"). */
    int rounds = state.strain_limit > 0 ? 1 + MAX_DEMOTION_ROUNDS : 1;
    for (int round = 0; round < rounds && !status; ++round) {
        if (round > 0) {
            int32_t demoted = demote_terms(&state, &outcome);
            if (demoted == 0)
                break;
            energy = evaluate(&state, uv);
            panel_figures(&state, uv, control.energy, control.flipped);
        }
        status = iterate(&state, &control, options, iterations, tolerance, uv, &energy, &outcome, ctx);
    }
    if (status) {
        step_control_free(&control);
        state_free(&state);
        return status;
    }
    outcome.final_energy = energy;
    step_control_free(&control);
    double end = pz_seconds();
    outcome.solve_ms = 1e3 * (end - solve_start);
    outcome.iteration_ms = outcome.iterations_run ? outcome.solve_ms / outcome.iterations_run : 0;
    pz_param_layout(pattern, state.offsets, state.order, uv);
    state_free(&state);
    if (result)
        *result = outcome;
    return PZ_OK;
}

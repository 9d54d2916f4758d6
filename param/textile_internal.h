/*
 * param/textile_internal.h -- the parts of the textile parameterization
 * (pz_param_textile, pz_textile_setup / pz_textile_solve) and what they share.
 *
 * The anisotropic textile parameterization of pietroni2022 Sec. 4.3, a
 * local/global iteration over all panels at once.
 *
 * Start: LSCM per panel, oriented so the projected grain runs along +v
 * (param/lscm.c); a pattern with seams first iterates with them open, so
 * the panels reach their own flat shapes before they are sewn (textile_solve.c:
 * the strain goal's warm-up, open_seams_start without one). Then, each
 * iteration:
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
 *     the 2D triangles), but slowly: each system is solved by conjugate
 *     gradients preconditioned with the factor of an earlier iteration's
 *     matrix (a few steps; one on panels of 50K vertices and, with a strain
 *     goal, the one-step solve of before issue 17), refactorized
 *     (numerically only) when that factor has gone stale (pcg_solve,
 *     one_step_solve). Panels are independent given the seam targets, so
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
 * allocation), plus a few preconditioned steps per coordinate (each two
 * triangular solves and a product) and an occasional numeric factorization. Memory:
 * per face 3 doubles per pose (the 3D frame coordinates), 2 (the grain in
 * the frame), the local-step output (18 doubles) and 6 matrix slots; per
 * panel two CSC matrices and one or two factors (v borrows u's on large
 * panels). Failure modes: PZ_ERR_DATA (a panel that is not a disk, a seam
 * vertex out of range), PZ_ERR_NOMEM, PZ_ERR_INTERNAL (CHOLMOD reports a
 * matrix that is not positive definite: should not happen since the
 * regularized system is SPD).
 *
 * Files:
 *   textile_setup.c   checks, the LSCM start, the 3D frames, seam segments
 *                     and outlines, each panel's sparsity pattern and
 *                     CHOLMOD's symbolic analysis (pz_textile_setup)
 *   textile_local.c   the local step (stretch, rigidity, seam, dart targets)
 *                     and the grain alignment
 *   textile_global.c  the global step: assembly, factorizations, solves
 *   textile_solve.c   the line search, the strain goal's reweighting, the
 *                     iterations (pz_textile_solve) and pz_param_textile
 *
 * Set-up and solve. Everything that depends only on the pattern and the
 * options is made once by pz_textile_setup and never written afterwards:
 * the LSCM start, frames, areas, the faces and vertices of each panel, the
 * seam segments, outlines, the CSC pattern of every panel's two systems and
 * their symbolic analysis (the fill-reducing ordering and the factor's
 * structure, which depend on the sparsity pattern only: from 8,000 unknowns
 * on also on the vertex positions, fixed too). pz_textile_solve allocates
 * the rest (the local step's output, weights the strain goal changes, the numeric
 * factors, copied from the symbolic analysis) and frees it when done, so a
 * kept solver holds only its set-up and every solve starts from the same
 * state: the same uv, byte for byte, as a fresh pz_param_textile.
 *
 * SPDX-License-Identifier: GPL-3.0-or-later
 */
#ifndef PZ_PARAM_TEXTILE_INTERNAL_H
#define PZ_PARAM_TEXTILE_INTERNAL_H

#include "param/internal.h"

/* Bounds of a factorization's cost in PCG steps (see pcg_solve). */
#define PCG_MIN_STEPS 4
#define PCG_MAX_STEPS 60
/* From this cost on, v starts with u's factor as its preconditioner instead
 * of its own (factorize_when_needed): at 200K faces (60) that saved one
 * 0.3 s factorization for energies 2e-4 higher after 20 steps; below, the
 * saving is small and the trajectories of the test meshes changed more. */
#define BORROW_MIN_STEPS 40
#define FACTOR_FLOP_COST 2.0
/* Panels below this many faces get simplicial factors (textile_setup.c). */
#define SIMPLICIAL_MAX_FACES 100000

/* Threads pay only when every parallel region has milliseconds of work:
 * OpenMP's fork/join, and on a loaded machine threads descheduled while the
 * others spin at a barrier, cost more than they save below that. Measured on
 * the 2-core machine at load 3-4, 20K faces: 19 ms per iteration on one
 * thread, 113 ms on two (2x slower even at load 0.3 with active waiting);
 * asked for explicitly, 75 ms against 10 ms at load 5 (issue 17). So only
 * patterns of PARALLEL_MIN_FACES faces run threaded, and only on the cores
 * the load average leaves free, whatever options->threads asks. */
#define PARALLEL_MIN_FACES 100000

/* Sums over faces or vertices must not depend on the thread count (the same
 * pattern byte for byte, issue 5; the energies steer the line search): a
 * range is cut into SUM_BLOCKS fixed blocks, each summed in order by one
 * thread, and the block sums are added in block order. An OpenMP reduction
 * would add per-thread partial sums, which round differently per count. */
#define SUM_BLOCKS 64

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

/* First index of block `block` of [first, first + count). */
static inline int32_t block_start(int32_t first, int32_t count, int block)
{
    return first + (int32_t)((int64_t)count * block / SUM_BLOCKS);
}

static inline double dot3(const double a[3], const double b[3])
{
    return a[0] * b[0] + a[1] * b[1] + a[2] * b[2];
}

/* One n x n SPD system of one panel and one coordinate, with its own CHOLMOD
 * workspace (CHOLMOD commons are not shared between threads). Set-up: the
 * common, the matrix (its pattern; the values are assembled every
 * iteration) and max_steps. Everything else belongs to one solve
 * (solver_begin, solver_end). */
typedef struct coordinate_solver {
    int started;
    cholmod_common common;
    cholmod_sparse *matrix;   /* upper triangle, fixed pattern */
    int max_steps;            /* what one factorization costs in PCG steps (flop counts, pcg_solve) */
    /* One solve: */
    cholmod_factor *factor;   /* a copy of the panel's symbolic analysis, numeric from its first factorization */
    cholmod_dense *rhs, *solution, *work_y, *work_e;
    cholmod_dense *residual;  /* PCG: r, the right-hand side of the preconditioner solve */
    double *product, *current; /* PCG: A x or A p, and the iterate */
    double *direction;        /* PCG: the search direction p */
    int factored;             /* the factor holds some earlier matrix's numbers */
    int borrowing;            /* v only: preconditions with u's factor (until it needs its own) */
    int fresh;                /* the factor was made from this iteration's matrix: solve directly */
    int failed;               /* this iteration's PCG step failed (global_step solves it directly) */
    int refactor;             /* 1: factorize before the next solve */
    int exact;                /* 1: the next preconditioned solve runs to PCG_EXACT_REDUCTION (demand_exact_solves) */
    int direct_runs;          /* after PCG failed: factorize and solve directly this many more times */
    int backoff;              /* the next such pause (doubles on repeated failures) */
    double *grain_gradient;   /* the panel's grain_gradient for this coordinate at the last assembly */
    double *grain_response;   /* A^-1 of it (grain_response), computed once per factorization */
    int response_ready;       /* grain_response belongs to the current factor */
    int32_t factorizations;   /* numeric factorizations in this solve (pz_textile_result) */
    int32_t failed_steps;     /* PCG solves that failed in this solve */
    int32_t pcg_solves;       /* preconditioner solves of PCG in this solve */
} coordinate_solver;

typedef struct panel_system {
    int32_t vertex_count;
    int32_t *vertices;        /* local -> cut-mesh vertex */
    int32_t *slots;           /* per panel face: 6 value slots: (0,0) (1,1) (2,2) (0,1) (0,2) (1,2) */
    int32_t segment_count;    /* length-only seam segments in this panel */
    int32_t *segment_ids;     /* their indices in textile_state's segment arrays */
    int32_t *segment_slots;   /* their off-diagonal value slot */
    cholmod_factor *symbolic; /* the symbolic analysis of the pattern both coordinates share (set-up) */
    coordinate_solver solver[2];
} panel_system;

/* The local step's output for one face: its share of the global step's
 * system for coordinate k (face_system), so the assembly is a scatter. */
typedef struct face_terms {
    double value[2][6];       /* matrix entries (0,0) (1,1) (2,2) (0,1) (0,2) (1,2) of its corners */
    double rhs[2][3];         /* right-hand side at its corners */
} face_terms;

/* The iteration's state. The first group is the set-up (textile_setup.c,
 * read-only afterwards); the second is allocated by state_begin and freed by
 * state_end for each solve. */
typedef struct textile_state {
    /* Set-up. */
    const pz_pattern *pattern;
    double w_stretch, w_rigid, w_dart, w_seam, regularization;
    double grain[3];
    const double *panel_grain_turn; /* pz_textile_options.panel_grain_turn: read by the set-up only (compute_frames) */
    int brief;                /* few iterations (an evaluation's): the systems are ordered by AMD alone (panel_setup) */
    int threads;
    int parallel;             /* 1: big enough for threads to pay (PARALLEL_MIN_FACES*) */
    int across_panels;        /* parallel and several panels: per-panel loops are split across threads */
    int within_panel;         /* parallel and one panel: per-panel loops split their own faces or vertices */
    int32_t pose_total;       /* 1 + poses used */
    double *frames;           /* face_count x pose_total x 3: x1, x2, y2 of the 3D triangle's frame */
    double *areas;            /* face_count: rest 3D area */
    double *grain_local;      /* face_count x 2: the grain projected onto the rest face, in its frame */
    int32_t *vertex_panel;    /* vertex_count */
    int32_t *vertex_rank;     /* vertex_count or NULL: the elimination order of the LSCM start's factorization of
                               * panels of PZ_METIS_MAX_UNKNOWNS unknowns or more (-1 elsewhere), which their
                               * systems reuse instead of searching orderings again (pz_param_analyze_ranked);
                               * freed once they are analyzed */
    int32_t *vertex_local;    /* vertex_count: index within its panel */
    int32_t *offsets, *order; /* faces bucketed by panel */
    int32_t *outline_offsets; /* panel_count + 1: each panel's outline edges in outline_edges */
    int32_t *outline_edges;   /* 2 vertex ids per outline (boundary) edge of the cut mesh */
    panel_system *panels;
    /* Equal lengths of facing segments, on every seam and dart (build_segments);
     * seams that cannot be mirror images (classify_seams, demote_terms) keep
     * only this term, the others also get the reflection of Eqs. 7-8. */
    double mirror_tolerance;
    int32_t *seam_segment_base;  /* seam_count: first segment of the seam, -1 when it has none */
    int32_t *dart_segment_base;  /* dart_count: first segment of the dart, -1 when it has none */
    int32_t segment_count;       /* 2 per facing pair: side a (or leg a), then side b */
    int32_t *segment_ends;       /* segment_count x 2: cut-mesh vertices (from, to) */
    double *segment_weight_start; /* segment_count: each segment's weight when a solve starts */
    int32_t seam_segment_end;    /* the seams' segments come first: 0 .. seam_segment_end - 1 */
    /* Strain goal (options->strain_limit; 0 = none). With it the lengths are
     * a goal too (SEAM_MISMATCH_GOAL): per seam, then per dart, the 3D
     * length of side a. */
    double strain_limit;
    double *curve_length_3d;     /* seam_count + dart_count, or NULL without a strain goal */

    /* One solve. */
    face_terms *terms;        /* face_count */
    double *face_energy;      /* face_count: the face's terms of Eq. 10 at the last evaluated uv */
    uint8_t *face_flipped;    /* face_count: 1 when its 2D triangle is collapsed or mirrored */
    double *panel_pull;       /* panel_count: seam and dart energy of the panel's vertices */
    double *grain_norm;       /* panel_count: |S| of panel_grain_angle at the last evaluation */
    int project_grain;        /* 1: project_grain_turn after every global step */
    double *pull_weight;      /* vertex_count: summed seam/dart weights */
    double *pull_target;      /* vertex_count x 2: weighted sums of seam/dart targets */
    uint8_t *seam_length_only;   /* seam_count: 1 = no reflection term */
    uint8_t *dart_length_only;   /* dart_count: 1 = no axis symmetry term (demote_terms) */
    double *segment_target;      /* segment_count x 2: the local step's target for to - from */
    double *segment_weight;      /* segment_count */
    /* 1 while the panels find their own flat shapes before the seams are
     * sewn (the strain goal's warm-up: seam terms left out, darts kept). */
    int seams_open;
    /* With a strain goal: per face, the stretch weight's multiplier
     * (update_strain_weights) and the face's worst |warp| or |weft| strain
     * at the last evaluation; per seam, then per dart, the relative mismatch
     * of the two sides' 2D lengths at the last evaluation, over
     * curve_length_3d. NULL without a strain goal. */
    double *stretch_boost;       /* face_count */
    double *face_strain;         /* face_count */
    double *curve_mismatch;      /* seam_count + dart_count */
} textile_state;

/* The solver of param.h: the set-up state, the LSCM start and the options a solve reads. */
struct pz_textile_solver {
    textile_state state;
    double *start_uv;         /* vertex_count x 2: the LSCM start (pz_param_lscm_pattern) */
    int iterations;
    double tolerance;
    void (*on_iteration)(void *user, int iteration, double energy);
    void *user;
    double setup_ms;          /* reported as pz_textile_result.init_ms */
};

/* textile_setup.c */
void textile_state_free(textile_state *state);
pz_status textile_state_begin(textile_state *state, pz_ctx *ctx);
void textile_state_end(textile_state *state);
int32_t textile_classify_seams(textile_state *state, const double *uv);
void textile_fit_reflection(const pz_seam *seam, const double *uv, double *c_out, double *s_out, double t[2]);

/* textile_local.c */
double textile_local_step(textile_state *state, const double *uv);
void textile_align_grain(textile_state *state, double *uv);
void textile_grain_gradient(const textile_state *state, int32_t panel, int k, const double *uv, double *gradient);

/* textile_global.c */
pz_status textile_global_step(textile_state *state, double *uv, pz_ctx *ctx);
void textile_project_grain_turn(const textile_state *state, const double *previous, double *uv);

#endif /* PZ_PARAM_TEXTILE_INTERNAL_H */

/*
 * param/param.h -- the public face of panelize's flattening stage.
 *
 * A garment with given panels becomes a *pattern*: the mesh is cut along
 * every seam (and along a cut path inside each panel that is not a disk), so
 * each panel is one disk-shaped component of the cut mesh; seams and darts
 * are lists of facing vertex pairs of that cut mesh. Flattening computes a 2D
 * position (mm) for every vertex of the cut mesh; metrics measure how the
 * flat pieces fit the 3D garment.
 *
 *   pz_pattern_build   panels + seams/darts  -> pz_pattern (cut mesh, seams)
 *   pz_param_lscm      one disk              -> initial UVs (Levy 2002)
 *   pz_param_textile   a whole pattern       -> UVs (pietroni2022 Sec. 4.3);
 *                      also as pz_textile_setup then pz_textile_solve
 *   pz_metrics_compute a pattern + UVs       -> per-triangle/panel/seam figures
 *
 * Conventions are those of mesh/mesh.h (status, ctx last, ownership).
 * Design notes: docs/param.md (flattening), docs/pattern.md (panels, seams,
 * darts and their file format), docs/metrics.md (every metric).
 *
 * SPDX-License-Identifier: GPL-3.0-or-later
 */
#ifndef PZ_PARAM_H
#define PZ_PARAM_H

#include "mesh/mesh.h"

#ifdef __cplusplus
extern "C" {
#endif

/* ------------------------------------------------------------------------ */
/* Patterns: panels, seams, darts                                            */
/* ------------------------------------------------------------------------ */

/**
 * Two boundary polylines of the cut mesh that are sewn together. side_a[i]
 * and side_b[i] are copies of the same garment vertex (same 3D position), in
 * order along the seam. A seam between a panel and itself (the cut that
 * opens a tube) has panel_a == panel_b.
 */
typedef struct pz_seam {
    int32_t panel_a, panel_b;
    int32_t pair_count;
    int32_t *side_a;   /* pair_count vertices of the cut mesh */
    int32_t *side_b;   /* pair_count vertices of the cut mesh */
} pz_seam;

/**
 * A dart: two legs of one panel that meet at the tip. leg_a[i] and leg_b[i]
 * face each other (they are sewn together); the tip is shared by both legs.
 */
typedef struct pz_dart {
    int32_t panel;
    int32_t tip;       /* vertex of the cut mesh */
    int32_t pair_count;
    int32_t *leg_a;    /* pair_count vertices of the cut mesh */
    int32_t *leg_b;
} pz_dart;

/**
 * A garment cut into panels. Owns everything; free with pz_pattern_free.
 * `mesh` is the cut mesh: its faces are the garment's faces in the same
 * order, its vertices copies of garment vertices (vertex_origin), with the
 * garment's poses carried along. Every panel is one connected disk of it.
 */
typedef struct pz_pattern {
    pz_mesh *mesh;             /* the cut mesh (owned) */
    int32_t *vertex_origin;    /* mesh->vertex_count: the garment vertex of each cut-mesh vertex */
    int32_t panel_count;
    int32_t *face_panel;       /* mesh->face_count: panel id 0..panel_count-1 */
    int32_t seam_count;
    pz_seam *seams;
    int32_t dart_count;
    pz_dart *darts;
} pz_pattern;

void pz_pattern_free(pz_pattern **pattern);

/**
 * Explicit correspondences given by the user (the format of
 * ../shared/data/seams/, docs/pattern.md): vertex indices refer to the
 * *garment* mesh; pz_pattern_build maps them onto the cut mesh.
 */
typedef struct pz_correspondences {
    int32_t seam_count;
    pz_seam *seams;    /* side_a/side_b: garment vertices; panel ids ignored (derived) */
    int32_t dart_count;
    pz_dart *darts;    /* tip/legs: garment vertices; panel ignored (derived) */
} pz_correspondences;

void pz_correspondences_clear(pz_correspondences *correspondences);

/**
 * Builds a pattern from a valid garment mesh and a panel id per face:
 *  - edges between faces of different panels are cut, and so are the edges
 *    in `extra_cuts` (edge flags over pz_topology_build(garment) edges, may be
 *    NULL): `--panels uv` passes the UV seams inside an island here;
 *  - a panel that is not a disk is cut into one: for each extra boundary loop
 *    the shortest edge path (Dijkstra, lengths in mm) joining it to another
 *    loop becomes a self-seam; a closed panel (no boundary) or one of genus >
 *    0 is PZ_ERR_DATA naming the panel;
 *  - seams are found automatically: maximal chains of cut edges between the
 *    same two panels (or a panel and itself), oriented and paired vertex by
 *    vertex; a self-chain that ends inside its panel (a slit, one copy at
 *    its tip: the darts of a UV pattern) becomes a pz_dart instead;
 *    `explicit` (may be NULL) adds or replaces correspondences
 *    (garment vertex ids; a seam whose vertices are not on a cut is
 *    PZ_ERR_DATA).
 * `path` names the input in error messages. Panel ids must be 0..K-1 with
 * every id used (PZ_ERR_DATA otherwise).
 */
pz_status pz_pattern_build(const pz_mesh *garment, const int32_t *face_panel, const uint8_t *extra_cuts,
                           const pz_correspondences *explicit_correspondences, const char *path,
                           pz_pattern **out, pz_ctx *ctx);

/**
 * Panels from the mesh's own UVs (`--panels uv`): each UV island (faces
 * connected through edges whose two sides share UV indices) is a panel, and
 * every edge whose two sides have different UV indices is a cut, also inside
 * an island. Writes face_panel (face_count, caller's buffer), *panel_count,
 * and *extra_cuts (edge flags over pz_topology_build(mesh) edges; caller
 * frees). PZ_ERR_DATA when the mesh has no UVs.
 */
pz_status pz_pattern_panels_from_uv(const pz_mesh *mesh, int32_t *face_panel, int32_t *panel_count,
                                    uint8_t **extra_cuts, pz_ctx *ctx);

/* ------------------------------------------------------------------------ */
/* Flattening                                                                */
/* ------------------------------------------------------------------------ */

/**
 * Least squares conformal map (Levy et al. 2002) of one disk-topology mesh,
 * solved with CHOLMOD, then rotated so that the projected 3D `grain` axis
 * (NULL = +z) runs along +v and scaled so that the 2D area equals the 3D
 * area. uv: vertex_count x 2, written. PZ_ERR_DATA for a mesh that is not a
 * single disk.
 */
pz_status pz_param_lscm(const pz_mesh *disk, const double grain[3], double *uv, pz_ctx *ctx);

/** Textile parameterization options. Zero-initialized = defaults. */
typedef struct pz_textile_options {
    int iterations;           /* 0 = 20 */
    double tolerance;         /* relative energy change that stops early; 0 = 1e-6 */
    int weights_given;        /* 1: use the weights below; 0 = defaults (5, 1, 5, 5) */
    double weight_stretch;    /* omega_stretch, Eq. 5 */
    double weight_rigid;      /* omega_rigid, Eq. 6 */
    double weight_dart;       /* omega_dart, Eq. 9 */
    double weight_seam;       /* omega_seam, Eq. 8 */
    int grain_given;          /* 1: use `grain`; 0 = +z (the garment's vertical) */
    double grain[3];          /* 3D warp axis */
    int use_poses;            /* 1: average the right-hand sides over the rest pose and every pose */
    int threads;              /* OpenMP threads; 0 = default */
    /* Called (may be NULL) with the energy (Eq. 10) of the start (iteration 0)
     * and of every accepted iterate: non-increasing (docs/param.md). */
    void (*on_iteration)(void *user, int iteration, double energy);
    void *user;
    /* A seam whose two sides, after the LSCM start, are further from mirror
     * images than this (RMS residual of the best-fit reflection over the
     * seam's 3D length) cannot be sewn as a mirror seam (a collar band on a
     * neckline, a sleeve cap in an armhole): it is held to equal length only,
     * segment by segment. 0 = 0.05; a huge value keeps every seam a mirror
     * seam (the paper's Eq. 8 everywhere). docs/param.md. */
    double seam_mirror_tolerance;
    /* The strain goal S (0 = none): every face's |warp| and |weft| strain
     * should stay within +-S. Faces near it get heavier stretch weights
     * (reweighted least squares), and when a panel still breaks it after the
     * iterations, the reflection terms of its seams and darts give way to
     * equal lengths only and the iterations run again (at most twice).
     * docs/param.md, "The strain goal". `panelize run` passes --max-strain. */
    double strain_limit;
    /* Each panel's warp turned from `grain` (pattern->panel_count angles in radians, borrowed for the set-up;
     * 0: along the grain), or NULL: the designer's grain hints for regions (pietroni2022 Sec. 4.3, "Grain
     * alignment": a bias cut favours another axis in specific regions; docs/param.md, "Grain hints"). Each
     * face's desired warp is the grain projected on it, turned by its panel's angle about the face normal (so
     * a 45-degree bias stays 45 degrees to the grain all round a curved piece). */
    const double *panel_grain_turn;
} pz_textile_options;

/** Outcomes that are not errors. */
typedef struct pz_textile_result {
    int iterations_run;
    double initial_energy;
    double final_energy;
    int converged;            /* 1: stopped on the tolerance, 0: on the iteration cap */
    double init_ms;           /* LSCM initialization */
    double solve_ms;          /* all iterations */
    double iteration_ms;      /* mean per iteration */
    int bounded_steps;        /* global steps shortened before any evaluation so no face flips on the way (docs/param.md) */
    int damped_steps;         /* global steps shortened (backtracked) to keep the energy from rising or faces from flipping */
    int32_t length_only_seams; /* seams held to equal length only (seam_mirror_tolerance, strain_limit) */
    int32_t length_only_darts; /* darts held to equal legs without axis symmetry (strain_limit) */
    int32_t factorizations;   /* numeric factorizations of the global step's systems (docs/param.md, "Speed") */
    int32_t failed_steps;     /* preconditioned solves that could not start (solved directly instead) */
    int32_t pcg_solves;       /* triangular solves with an earlier factor (preconditioned conjugate gradients) */
} pz_textile_result;

/**
 * The anisotropic textile parameterization of pietroni2022 Sec. 4.3: local /
 * global iterations of warp and weft stretch (Eqs. 1-5), ARAP rigidity with
 * per-triangle Procrustes (Eq. 6), seam reflection symmetry (Eqs. 7-8), dart
 * symmetry (Eq. 9) and grain alignment, from an LSCM start. All panels are
 * iterated jointly so seam partners see each other's latest positions.
 * uv: pattern->mesh->vertex_count x 2, written (mm). result may be NULL.
 */
pz_status pz_param_textile(const pz_pattern *pattern, const pz_textile_options *options, double *uv,
                           pz_textile_result *result, pz_ctx *ctx);

/**
 * The textile parameterization in two parts, set-up then solve (as libigl's
 * arap_precomputation then arap_solve): pz_param_textile is exactly
 * pz_textile_setup, pz_textile_solve, pz_textile_solver_free.
 *
 * The set-up holds everything that depends only on the pattern and the
 * options: the checks, the LSCM start, each face's 3D frames, the seam
 * segments and outlines, and per panel the sparsity pattern of its two
 * coordinate systems with CHOLMOD's symbolic analysis (the fill-reducing
 * ordering). A solve runs the iterations from the LSCM start, making only
 * numeric factorizations (copies of the set-up's analysis), and gives the
 * same uv and result, byte for byte, every time: a caller that flattens the
 * same pattern again (the segmentation evaluating a panel it has seen)
 * keeps the solver and pays the iterations only. docs/param.md, "Set-up and
 * solve".
 */
typedef struct pz_textile_solver pz_textile_solver;

/**
 * Sets up the textile parameterization of `pattern` with `options` (NULL =
 * defaults; copied, including on_iteration and user, which later solves
 * call). The solver keeps a pointer to `pattern`, which must stay unchanged
 * and outlive it. *out: the caller's, freed with pz_textile_solver_free
 * (NULL on error). Errors as pz_param_textile's set-up: PZ_ERR_USAGE
 * (negative weights), PZ_ERR_DATA (a panel that is not a disk, a seam vertex
 * out of range), PZ_ERR_NOMEM, PZ_ERR_CANCELLED (after the LSCM start).
 */
pz_status pz_textile_setup(const pz_pattern *pattern, const pz_textile_options *options, pz_textile_solver **out,
                           pz_ctx *ctx);

/**
 * One textile solve with a set-up solver: uv (pattern->mesh->vertex_count x
 * 2, written, mm) and result (may be NULL; written on success) as
 * pz_param_textile gives them; result->init_ms is the set-up's time. The
 * memory of the solve is freed before returning: between solves the solver
 * holds its set-up only. PZ_ERR_CANCELLED between two iterations when
 * ctx->cancel is set (uv then holds the last accepted iterate, not laid
 * out). One solver serves one thread at a time; separate solvers may solve
 * in parallel.
 */
pz_status pz_textile_solve(pz_textile_solver *solver, double *uv, pz_textile_result *result, pz_ctx *ctx);

/** Frees the solver and sets *solver to NULL (accepts NULL and *solver == NULL). */
void pz_textile_solver_free(pz_textile_solver **solver);

/**
 * Turns each panel p of a flattening (uv: pattern->mesh->vertex_count x 2) with panel_turn[p] != 0 about its
 * centroid so that its desired warp (the 3D `grain` projected on each face and turned by panel_turn[p] about
 * the face normal, area-weighted) runs along +v. For the back-ends without a grain term of their own (LSCM,
 * WireWarping, spring-mass) when panels carry grain hints (pz_textile_options.panel_grain_turn is the
 * textile's). panel_turn NULL: nothing to do. PZ_ERR_NOMEM.
 */
pz_status pz_param_turn_to_panel_grain(const pz_pattern *pattern, const double grain[3], const double *panel_turn,
                                       double *uv, pz_ctx *ctx);

/** LSCM only, panel by panel (the `--backend lscm` path), grain-oriented. */
pz_status pz_param_lscm_pattern(const pz_pattern *pattern, const double grain[3], double *uv, pz_ctx *ctx);

/* ------------------------------------------------------------------------ */
/* WireWarping (wang2008): length-exact seams; docs/wirewarp.md              */
/* ------------------------------------------------------------------------ */

typedef enum pz_feature_kind {
    PZ_FEATURE_ACCESSORY = 0,  /* length kept, 2D shape optimized */
    PZ_FEATURE_KEY = 1         /* length kept, 2D angles fixed by Eq. 1 */
} pz_feature_kind;

/** A feature curve on the cut mesh: consecutive vertices share a mesh edge. */
typedef struct pz_feature_curve {
    pz_feature_kind kind;
    int32_t vertex_count;
    int32_t *vertices;         /* cut-mesh vertices (pattern->mesh) */
    double *turning;           /* key curves, optional (NULL: Eq. 1 keeps the 3D shape): the user's 2D shape,
                                  vertex_count signed turning angles (radians, > 0 = turning left in the
                                  pattern plane); used at vertices inside the panel with a curve vertex on
                                  each side, ignored at the ends and on the boundary (Eq. 1 there). Owned:
                                  freed by pz_feature_curves_free */
} pz_feature_curve;

typedef struct pz_feature_curves {
    int32_t curve_count;
    pz_feature_curve *curves;
} pz_feature_curves;

void pz_feature_curves_free(pz_feature_curves **curves);

/** A 3D polyline as read from a features file (points: point_count x 3, mm). */
typedef struct pz_feature_polyline {
    pz_feature_kind kind;
    int32_t point_count;
    const double *points;
} pz_feature_polyline;

/**
 * Snaps polylines to mesh edges: every point goes to its nearest cut-mesh
 * vertex, consecutive vertices are joined by the shortest edge path (Dijkstra,
 * 3D lengths) inside one panel. tolerance_mm: farthest a point may lie from
 * its vertex (0 = twice the mean edge length). PZ_ERR_DATA naming the curve
 * and point for a point off the mesh or a curve crossing panels.
 */
pz_status pz_feature_curves_snap(const pz_pattern *pattern, const pz_feature_polyline *polylines,
                                 int32_t polyline_count, double tolerance_mm, pz_feature_curves **out,
                                 pz_ctx *ctx);

/**
 * pz_feature_curves_snap, but a polyline that cannot be snapped (a point off the mesh, a curve across
 * panels, a curve that snaps to one vertex) is left out instead of failing the call: *out holds the
 * others in order (possibly none); skipped (polyline_count flags, may be NULL) gets 1 for each one
 * left out, and on_skip (may be NULL) is called with its index and the one-line problem. Only usage
 * and out-of-memory errors fail (then *out = NULL). *out is freed with pz_feature_curves_free.
 */
pz_status pz_feature_curves_snap_lenient(const pz_pattern *pattern, const pz_feature_polyline *polylines,
                                         int32_t polyline_count, double tolerance_mm, pz_feature_curves **out,
                                         uint8_t *skipped,
                                         void (*on_skip)(void *user, int32_t curve, const char *problem),
                                         void *user, pz_ctx *ctx);

typedef struct pz_wirewarp_options {
    int scheme;              /* 0 global (Sec. 4, default), 1 progressive (Sec. 3) */
    int interior;            /* 0 cotangent Laplacian (default), 1 the paper's 1/length weights (Eq. 11),
                                2 those solved by the paper's relaxed Gauss-Seidel (Eq. 12; else the fallback) */
    int max_iterations;      /* Newton iterations per solve; 0 = 100 */
    int grain_given;         /* 1: use `grain`; 0 = +z. Each piece is turned so the grain runs along +v */
    double grain[3];
} pz_wirewarp_options;

#define PZ_WIREWARP_RELAXED_MAX 16  /* relaxed key curves listed by index in pz_wirewarp_result */

typedef struct pz_wirewarp_result {
    int32_t wire_patch_count, wire_node_count, wire_edge_count;
    int32_t locked_count;        /* wire-nodes with angles fixed by key curves (Eq. 1) or Eq. 9 */
    int32_t constraint_count;    /* 3m + r of the global system (progressive: summed over patches) */
    int iterations;              /* Newton iterations (summed over patches for progressive) */
    double constraint_residual;  /* worst closure (relative to perimeter) or angle-sum (rad) residual */
    double e_len_wires;          /* Eq. 26 over every wire edge (boundaries and feature curves) */
    double max_wire_error;       /* worst relative wire-edge length error */
    int best_effort;             /* 1: the constraints could not all be met (incompatible keys, Figs. 13-14) */
    int interior_fallback;       /* 1: Gauss-Seidel (Eq. 12) replaced the direct solve */
    int interior_inverse_length; /* 1: the interior uses Eq. 11's 1/length weights (asked, or the
                                    cotangent solve flipped faces and these flipped fewer) */
    int injective;               /* pz_metrics_compute: no flipped face, no boundary crossing */
    int32_t flipped_triangles;   /* after the untangling; > 0 also sets best_effort */
    double angle_ms, layout_ms, interior_ms;
    int32_t untangled_vertices;  /* interior vertex moves that unflipped faces (wires never move) */
    int32_t trimmed_feature_edges; /* edges given up at the free ends of dangling feature curves because the
                                    interior folded there (best_effort is then set; docs/wirewarp.md) */
    int32_t relaxed_key_curve_count; /* key curves whose angles were relaxed: with them all fixed the wire-patches
                                    could not close (incompatible keys, Figs. 13-14), so their Eq. 1 angles became
                                    least-squares targets; wire lengths stay exact; best_effort is then set */
    int32_t relaxed_key_curves[PZ_WIREWARP_RELAXED_MAX]; /* the first of them: indices into `features` */
    double relaxed_key_angle;    /* largest change of a relaxed key curve's angle from its fixed value (rad) */
} pz_wirewarp_result;

/**
 * WireWarping of every panel: wires are the panel boundaries plus `features`
 * (may be NULL); wire-patches are warped in angle space so that every wire
 * edge keeps its 3D length, then interior vertices solve a Laplacian with
 * the wires fixed. uv: pattern->mesh->vertex_count x 2, written (mm).
 * options and result may be NULL. A best-effort result (result->best_effort)
 * is still PZ_OK; structural problems (a wire-patch that is not a disk, a
 * feature curve whose consecutive vertices share no edge) are PZ_ERR_DATA.
 */
pz_status pz_param_wirewarp(const pz_pattern *pattern, const pz_wirewarp_options *options,
                            const pz_feature_curves *features, double *uv, pz_wirewarp_result *result,
                            pz_ctx *ctx);

/**
 * WireWarping in two parts: pz_param_wirewarp is exactly pz_wirewarp_setup,
 * pz_wirewarp_solve, pz_wirewarp_solver_free. The set-up builds the wires,
 * wire-patches and wire-nodes of the pattern and `features` (which depend on
 * nothing else); each solve takes its own options (scheme, interior weights,
 * iterations, grain) and keeps the interior system's CHOLMOD symbolic
 * analysis for the next interior solve with the same wires. Solving twice
 * with the same options gives the same uv.
 */
typedef struct pz_wirewarp_solver pz_wirewarp_solver;

/**
 * Sets up WireWarping of `pattern` along `features` (may be NULL; copied).
 * The solver keeps a pointer to `pattern`, which must stay unchanged and
 * outlive it. *out: the caller's, freed with pz_wirewarp_solver_free (NULL
 * on error). Errors as pz_param_wirewarp's structural ones (PZ_ERR_DATA for
 * a wire-patch that is not a disk or a curve off the mesh edges).
 */
pz_status pz_wirewarp_setup(const pz_pattern *pattern, const pz_feature_curves *features, pz_wirewarp_solver **out,
                            pz_ctx *ctx);

/**
 * One WireWarping with a set-up solver: uv and result (may be NULL) as
 * pz_param_wirewarp gives them with these options (may be NULL). Trimming
 * dangling curve ends (docs/wirewarp.md) builds the trimmed wires for that
 * solve only. PZ_ERR_CANCELLED between steps when ctx->cancel is set. One
 * solver serves one thread at a time.
 */
pz_status pz_wirewarp_solve(pz_wirewarp_solver *solver, const pz_wirewarp_options *options, double *uv,
                            pz_wirewarp_result *result, pz_ctx *ctx);

/** Frees the solver and sets *solver to NULL (accepts NULL and *solver == NULL). */
void pz_wirewarp_solver_free(pz_wirewarp_solver **solver);

/* ------------------------------------------------------------------------ */
/* Metrics                                                                   */
/* ------------------------------------------------------------------------ */

/** max, 95th percentile and area-weighted mean of a per-triangle quantity. */
typedef struct pz_stat {
    double max, p95, mean;
} pz_stat;

/** Fabric constants of mccartney2005 (Eqs. 8-9). Zero = the paper's. */
typedef struct pz_fabric {
    double k_su;   /* tensile stiffness along u (the weft, mccartney2005's K_su), N/mm; default 0.946 */
    double k_sv;   /* tensile stiffness along v (the warp, K_sv), N/mm; default 0.548 */
    double k_r;    /* shear stiffness, N/mm/rad; default 0.159 */
} pz_fabric;

/** The paper's constants (mccartney2005's woven cotton): the one place they are defined. */
pz_fabric pz_fabric_default(void);

typedef struct pz_panel_metrics {
    int32_t panel;
    int32_t face_count;
    double area_3d_mm2, area_2d_mm2;
    pz_stat strain_warp;      /* |J_1| - 1 (J: pattern -> garment); signed values, max of |.| */
    pz_stat strain_weft;      /* |J_2| - 1 */
    pz_stat shear_deg;        /* angle between warp and weft threads in 3D minus 90 */
    double orthotropic_energy;  /* mccartney2005 Eq. 9, summed, N*mm */
    double arap_energy;       /* sum over triangles of area * ||J - R||_F^2 */
    double e_len;             /* wang2008 Eq. 26 over the panel's boundary edges */
    double e_ang;             /* wang2008 Eq. 27 */
    double e_area;            /* wang2002 Eq. 4 (area accuracy summed per triangle; docs/metrics.md) */
    double e_shape;           /* wang2002 Eq. 6 */
    int32_t flipped_triangles;
    int32_t boundary_self_intersections;
} pz_panel_metrics;

typedef struct pz_seam_metrics {
    int32_t seam;
    int32_t panel_a, panel_b;
    double length_3d_mm, length_a_mm, length_b_mm;
    double mismatch_rel;           /* |length_a - length_b| / length_3d */
    double reflection_residual_mm; /* RMS distance after the best-fit reflection of side a onto side b */
} pz_seam_metrics;

typedef struct pz_dart_metrics {
    int32_t dart;
    double leg_a_mm, leg_b_mm;
    double mismatch_rel;
    double symmetry_residual_mm;   /* RMS distance of leg b to leg a mirrored about the best axis through the tip */
    double intake_mm;              /* the fabric it takes in: the distance between the legs' ends at its mouth (the
                                      ends farther from the tip) in the pattern */
} pz_dart_metrics;

typedef struct pz_metrics {
    int32_t face_count;
    double *strain_warp;      /* face_count */
    double *strain_weft;      /* face_count */
    double *shear_deg;        /* face_count */
    int32_t panel_count;
    pz_panel_metrics *panels;
    int32_t seam_count;
    pz_seam_metrics *seams;
    int32_t dart_count;
    pz_dart_metrics *darts;
    double max_abs_strain;    /* over all panels and poses measured */
    double max_seam_mismatch_rel;
    int injective;            /* no flipped triangle and no boundary self-intersection */
} pz_metrics;

/**
 * Measures a flattened pattern against the rest pose (or, with pose >= 1,
 * against extra pose pose-1). uv: pattern->mesh->vertex_count x 2. fabric
 * may be NULL (defaults). Boundary self-intersections are found with a
 * sweep over segment bounding boxes, O(n log n). Caller frees *out.
 */
pz_status pz_metrics_compute(const pz_pattern *pattern, const double *uv, int pose, const pz_fabric *fabric,
                             pz_metrics **out, pz_ctx *ctx);
void pz_metrics_free(pz_metrics **metrics);

/**
 * Pairs of outline edges that meet (cross, touch or overlap) without sharing a
 * vertex: the boundary self-intersections of pz_metrics_compute for one set of
 * edges. edges: count x 2 vertex ids into uv (vertex_count x 2). A uniform
 * grid of about one cell per edge: O(n + b), b the pairs of edges whose
 * bounding boxes share a cell (docs/metrics.md). Returns -1 when out of memory.
 */
int32_t pz_metrics_outline_crossings(const int32_t *edges, int32_t count, const double *uv);
/**
 * pz_metrics_outline_crossings that also sets marked[v] = 1 for both end
 * vertices of every edge in a meeting pair (marked: caller-owned, one byte
 * per vertex of uv, not cleared here; NULL: count only).
 */
int32_t pz_metrics_outline_crossings_marked(const int32_t *edges, int32_t count, const double *uv, uint8_t *marked);

/**
 * Per-triangle strain of one triangle: p3[3][3] garment positions, p2[3][2]
 * pattern positions. Writes warp and weft strain (|J_1| - 1, |J_2| - 1) and
 * shear in degrees; the building block the tests check by hand.
 */
void pz_metrics_triangle_strain(const double p3[3][3], const double p2[3][2], double *strain_warp,
                                double *strain_weft, double *shear_deg);

/* ------------------------------------------------------------------------ */
/* Spring-mass (wang2002, mccartney2005, IISERM; docs/springmass.md)         */
/* ------------------------------------------------------------------------ */

/** Spring-mass options. Zero-initialized = defaults. */
typedef struct pz_springmass_options {
    int relax;               /* phase-one release: 0 heap (IISERM, default), 1 full (wang2002 InitFlatten) */
    int heap_paths;          /* heap: 0 or 1 = single path; k >= 2 = multi-path, 2^(level-2) paths capped at k */
    int orthotropic;         /* 1: mccartney2005 warp/weft/shear energy (fabric) instead of isotropic springs */
    pz_fabric fabric;        /* zero = the paper's constants */
    int grain_given;         /* 1: use `grain`; 0 = +z */
    double grain[3];         /* 3D warp axis; the seed triangle's warp (+v) follows it */
    int max_iterations;      /* phase two cap N; 0 = 1000 (wang2002 Sec. 6.2) */
    int phase_one_iterations; /* full release cap after each triangle; 0 = 50 (wang2002 InitFlatten) */
    double accuracy;         /* E_S and E_C target of phase two; 0 = 0.01 */
    double energy_variation; /* relative energy change that stops a release; 0 = 0.0005 */
    int trial_cut;           /* 1: cut each panel along its suggested line, re-flatten, classify dart/gusset */
    int local_release_only;  /* 1: phase two is only the paper's node sweeps; 0 (default): isotropic phase two
                                starts with a global (local-global, CHOLMOD) release, docs/springmass.md */
    int independent_panels;  /* 1: every panel flattened alone (the papers); 0 (default): after phase two the
                                facing segments of every seam and dart get equal lengths, their mean, exactly
                                (seam matching, docs/springmass.md) */
} pz_springmass_options;

typedef enum pz_springmass_stop {
    PZ_SPRINGMASS_STOP_ACCURACY = 1,   /* E_S and E_C below the accuracy */
    PZ_SPRINGMASS_STOP_VARIATION = 2,  /* energy changed less than energy_variation */
    PZ_SPRINGMASS_STOP_ITERATIONS = 3  /* max_iterations reached */
} pz_springmass_stop;

typedef enum pz_seam_kind {
    PZ_SEAM_KIND_NONE = 0,     /* sides neither splay nor overlap measurably (|opening| <= 0.1% of the area) */
    PZ_SEAM_KIND_DART = 1,     /* sides splay apart (elliptic: close with a dart) */
    PZ_SEAM_KIND_GUSSET = 2    /* sides overlap (hyperbolic: insert a gusset) */
} pz_seam_kind;

/** Per panel: the suggested cutting line and what happens when it is cut. */
typedef struct pz_springmass_panel {
    int32_t panel;
    int stop;                   /* pz_springmass_stop of phase two */
    int iterations;             /* phase-two sweeps */
    int global_iterations;      /* phase-two global release iterations (0: orthotropic or local_release_only) */
    double phase_one_energy;    /* E(Phi) (Eq. 3) after phase one */
    double final_energy;        /* E(Phi) at the end */
    double e_area, e_shape;     /* wang2002 Eqs. 4 and 6 at the end */
    int32_t max_energy_vertex;  /* cut-mesh vertex of the highest energy */
    int32_t cut_vertex_count;
    int32_t *cut_vertices;      /* crest line (Sec. 6.3): cut-mesh vertices from the boundary inward (owned) */
    pz_seam_kind cut_kind;      /* trial_cut only */
    double cut_opening_mm2;     /* trial_cut: area between the cut's sides, > 0 gap (dart), < 0 overlap (gusset) */
    double cut_energy;          /* trial_cut: final energy of the panel cut open */
} pz_springmass_panel;

typedef struct pz_springmass_result {
    int32_t vertex_count;
    double *vertex_energy;      /* vertex_count (cut mesh): the energy map (owned) */
    int32_t panel_count;
    pz_springmass_panel *panels; /* owned */
    double phase_one_energy, final_energy;  /* sums over panels */
    long long node_relaxations;      /* node moves, all phases: a deterministic work counter */
    long long phase_one_relaxations; /* of which during phase one */
    long long energy_evaluations;    /* node energy evaluations */
    double phase_one_ms, phase_two_ms;
    long long global_iterations;     /* local-global iterations of phase two's global release (each one
                                        touches every spring and solves once with the factored Laplacian) */
    int32_t matched_pairs;           /* facing segment pairs of seams and darts given equal lengths */
    int32_t unmatched_panels;        /* panels whose outline could not be refitted (left as phase two made them) */
    int32_t retried_panels;          /* panels flattened again because they ended folded or with a crossing
                                        outline: 8 heap paths, then from LSCM (docs/springmass.md) */
    double max_seam_mismatch;        /* worst |side a - side b| / 3D length over the seams and darts, at the
                                        end (also with independent_panels) */
} pz_springmass_result;

/**
 * Spring-mass flattening of every panel: phase one lays each panel's
 * triangles one by one from its seed (largest medial distance), releasing
 * energy after each constrained triangle (heap or full); phase two releases
 * the panel until the stopping rules of wang2002 Sec. 5. Then (unless
 * options->independent_panels) the facing segments of every seam and dart
 * get their mean length exactly: each outline is refitted in angle space and
 * the interior released again with it fixed.
 * uv: pattern->mesh->vertex_count x 2, written (mm). result may be NULL;
 * otherwise it is filled and must be released with pz_springmass_result_clear.
 */
pz_status pz_param_springmass(const pz_pattern *pattern, const pz_springmass_options *options, double *uv,
                              pz_springmass_result *result, pz_ctx *ctx);
void pz_springmass_result_clear(pz_springmass_result *result);

/** energy.svg: the flattened panels coloured by vertex energy, with the cutting lines. Atomic. */
pz_status pz_springmass_write_energy_svg(const pz_pattern *pattern, const double *uv,
                                         const pz_springmass_result *result, const char *path, pz_ctx *ctx);

#ifdef __cplusplus
}
#endif

#endif /* PZ_PARAM_H */

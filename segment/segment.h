/*
 * segment/segment.h -- the segmentation stage: from a garment, its
 * cross-field and the tracing graph to a patch layout whose every panel
 * meets the goals (pietroni2022 Sec. 3.1 and 4.2).
 *
 *   pz_symmetry_detect   a mirror plane of the garment and the vertex mirror map
 *   pz_segment_goals     does one panel (a set of faces) meet the goals?
 *   pz_segment           the whole layout: candidates, greedy insertion,
 *                        recursion into failing panels, removal in reverse
 *                        order, darts, symmetry, sketches
 *
 * A layout is a set of cut edges (flags over pz_topology_build(mesh)
 * edges). Panels are the connected components of faces across uncut edges.
 * A cut chain that ends inside a panel (one end on no other cut and not on
 * the boundary) is a dart slit: its free end is the tip. pz_pattern_build
 * (param/param.h) takes the result as face_panel + extra_cuts (the cut edges
 * that have the same panel on both sides: dart slits) and finds the seams and
 * darts itself.
 *
 * Goals of a panel (pietroni2022 Sec. 3.1; docs/segment.md gives the details):
 *  - it is a topological disk (darts' slits are part of its boundary);
 *  - it has at most max_corners corners (vertices of its outline where the
 *    neighbouring panel changes, plus sharp turns of the outline);
 *    the outline is taken with its darts closed: a dart adds no corner;
 *  - its flattening (LSCM start + a few textile iterations, grain given) is
 *    injective and every triangle's warp and weft strain lies within
 *    +-max_strain;
 *  - piece shapes: at least min_piece_width_mm wide and min_piece_area of
 *    the garment's area unless the input makes it so, at most
 *    max_piece_width_mm across the grain, every dart taking in at least
 *    min_dart_intake_mm (a split never answers a shape goal: pieces left
 *    under one are merged into a neighbour at the end, even over S).
 *
 * Conventions of mesh/mesh.h. Deterministic: the result never depends on
 * the thread count or timing.
 *
 * SPDX-License-Identifier: GPL-3.0-or-later
 */
#ifndef PZ_SEGMENT_H
#define PZ_SEGMENT_H

#include "field/field.h"
#include "mesh/mesh.h"
#include "trace/trace.h"

#ifdef __cplusplus
extern "C" {
#endif

/* ------------------------------------------------------------------------ */
/* Symmetry                                                                  */
/* ------------------------------------------------------------------------ */

typedef enum pz_symmetry_mode {
    PZ_SYMMETRY_AUTO = 0,  /* detect a plane in any orientation; used when its residual is within the tolerance */
    PZ_SYMMETRY_OFF = 1,
    PZ_SYMMETRY_X = 2,     /* a plane x = c (normal along x), c fitted */
    PZ_SYMMETRY_Y = 3,
    PZ_SYMMETRY_Z = 4,
    PZ_SYMMETRY_PLANE = 5  /* the plane given (pz_symmetry_detect's plane, pz_segment_options.symmetry_plane) */
} pz_symmetry_mode;

typedef struct pz_symmetry {
    int found;                 /* 1: a plane is in use */
    int axis;                  /* 0, 1, 2: the normal is that coordinate axis; -1 an oblique plane, or none */
    double normal[3], offset;  /* plane: dot(normal, p) = offset (normal unit) */
    /* How far the garment is from its mirror image: every vertex in use mirrored through the plane,
     * its distance to the surface (the closest point on the faces around its nearest vertex), and each
     * border vertex's distance to the border. */
    double residual_mm;        /* the larger 90th percentile of the two (robust: a draped garment is only
                                  nearly symmetric, and its meshing is not symmetric at all) */
    double residual_rel;       /* residual_mm / bounding-box diagonal: AUTO's acceptance figure */
    double rms_mm;             /* their RMS */
    int32_t vertex_count;
    int32_t *vertex_mirror;    /* vertex_count: the vertex nearest to each vertex's mirror image (-1 none) */
    uint8_t *vertex_side;      /* vertex_count: 0 on the negative side, 1 on the plane (within tolerance), 2 positive */
    int32_t face_count;
    int32_t *face_mirror;      /* face_count: the face holding the point closest to each face's mirrored
                                  centroid (-1 none) */
} pz_symmetry;

/**
 * Finds the mirror plane (docs/segment.md, "Symmetry").
 * PZ_SYMMETRY_AUTO: candidate normals are the x, y and z axes and the
 * principal axes of the area-weighted vertices (with more directions in the
 * plane of two nearly equal principal axes), each plane through the area
 * centroid refined by an ICP-like fit (mirror, match the closest surface
 * points, refit the plane to the nearest 80 % of the pairs); the plane of
 * smallest residual (residual_mm: 90th percentiles of the mirrored vertices'
 * distances to the surface and of the border's to the border) wins, snapped to a coordinate axis within 1 degree when that
 * fits as well, and is used (found = 1) when residual_rel is below
 * tolerance_rel (0 = 0.015); otherwise found = 0 with the best residual kept.
 * PZ_SYMMETRY_X/Y/Z: the plane normal to that axis, its offset fitted, used
 * whatever its residual. PZ_SYMMETRY_PLANE: `plane` (nx, ny, nz, d: the plane
 * n . p = d, n need not be unit) as given, used whatever its residual
 * (PZ_ERR_USAGE when n is zero or not finite). PZ_OFF: found = 0.
 * plane may be NULL except with PZ_SYMMETRY_PLANE. Closest points through a
 * uniform vertex grid; the fits use at most 2000 vertices: O(V + F) expected.
 * Caller frees with pz_symmetry_clear.
 */
pz_status pz_symmetry_detect(const pz_mesh *mesh, const pz_topology *topology, pz_symmetry_mode mode,
                             const double plane[4], double tolerance_rel, pz_symmetry *out, pz_ctx *ctx);
void pz_symmetry_clear(pz_symmetry *symmetry);
/** Copies a symmetry (its arrays too) into *out; PZ_ERR_NOMEM. Free *out with pz_symmetry_clear. */
pz_status pz_symmetry_copy(const pz_symmetry *symmetry, pz_symmetry *out, pz_ctx *ctx);
/** p mirrored through the plane into out (may alias p). */
void pz_symmetry_reflect_point(const pz_symmetry *symmetry, const double p[3], double out[3]);
/** A direction mirrored through the plane (its normal component negated) into out (may alias d). */
void pz_symmetry_reflect_direction(const pz_symmetry *symmetry, const double d[3], double out[3]);

/**
 * The mirror image of a path through vertex_mirror: every vertex mirrored,
 * gaps between mirrored neighbours that share no edge closed by the shortest
 * edge path, arms mirrored through the graph (the arm closest to the
 * reflected direction). PZ_ERR_DATA when a vertex has no mirror.
 */
pz_status pz_symmetry_mirror_path(const pz_symmetry *symmetry, const pz_trace_graph *graph, const pz_mesh *mesh,
                                  const pz_topology *topology, const pz_trace_path *path, pz_trace_path *out,
                                  pz_ctx *ctx);

/* ------------------------------------------------------------------------ */
/* Goals                                                                     */
/* ------------------------------------------------------------------------ */

/** Why a panel misses its goals (bit set). */
enum pz_goal_failure {
    PZ_GOAL_NOT_DISK = 1u << 0,
    PZ_GOAL_CORNERS = 1u << 1,
    PZ_GOAL_STRAIN = 1u << 2,
    PZ_GOAL_NOT_INJECTIVE = 1u << 3,
    PZ_GOAL_VETOED = 1u << 4,    /* the caller's final flattening rejected this panel (pz_segment_options.vetoed) */
    PZ_GOAL_SEAM_MISMATCH = 1u << 5, /* a seam's or dart's two sides differ by more than max_seam_mismatch */
    PZ_GOAL_NARROW = 1u << 6,        /* narrower than min_piece_width_mm, and not because the input is narrow there */
    PZ_GOAL_SMALL = 1u << 7,         /* under min_piece_area of the garment's area, and not a whole component */
    PZ_GOAL_FABRIC_WIDTH = 1u << 8,  /* wider across the grain than max_piece_width_mm (the fabric's width) */
    PZ_GOAL_DART_INTAKE = 1u << 9    /* a dart takes in less than min_dart_intake_mm at its mouth */
};

/* The failures a split can mend: the layout splits a panel that has one of these (docs/segment.md). */
#define PZ_GOAL_SPLIT_MENDS                                                                                     \
    (PZ_GOAL_NOT_DISK | PZ_GOAL_CORNERS | PZ_GOAL_STRAIN | PZ_GOAL_NOT_INJECTIVE | PZ_GOAL_VETOED |             \
     PZ_GOAL_FABRIC_WIDTH)
/* The piece-shape failures a split can only make worse: a split that would cause one is rejected, and a
 * panel that has one is reported, never split further (a sliver is never the answer to a strain goal). */
#define PZ_GOAL_SHAPE (PZ_GOAL_NARROW | PZ_GOAL_SMALL)

/**
 * The goals every panel is judged by (pietroni2022 Sec. 3.1, plus the seam
 * lengths the pattern promises). pz_goal_options_default is the one place the
 * defaults are defined.
 */
typedef struct pz_goal_options {
    int32_t max_corners;         /* C; default 8 (0 = the default) */
    double max_strain;           /* S: |strain| bound on every triangle (>= 0); default 0.05 */
    double grain[3];             /* the warp axis in 3D (unit); default +z */
    int textile_iterations;      /* an evaluation's flattening; 0 = the default of docs/segment.md;
                                    < 0: shape only (disk and corners), no flattening */
    double max_seam_mismatch;    /* relative length difference of a seam's or dart's two sides; default 0.005;
                                    judged on the final pattern (an evaluation has no partner panels) */
    /* Piece shapes (docs/segment.md, "Piece shapes"); 0 = not judged. */
    double min_piece_width_mm;   /* no piece narrower (twice its largest inscribed distance); default 40 */
    double min_piece_area;       /* no piece smaller, as a share of the garment's area; default 0.01 */
    double max_piece_width_mm;   /* no piece wider across the grain (the fabric's usable width); default 0:
                                    panelize run sets it from the fabric width less twice the allowance */
    double min_dart_intake_mm;   /* every dart opens at least this much at its mouth; default 6 */
} pz_goal_options;

/** C = 8, S = 0.05, seam mismatch 0.5 %, grain +z, pieces 40 mm wide and 1 % of the area, darts 6 mm. */
void pz_goal_options_default(pz_goal_options *goals);

/** One panel's figures and the goals it misses. */
typedef struct pz_goal_result {
    unsigned failures;           /* enum pz_goal_failure bits; 0 = goals met (pz_goal_judge) */
    int disk;                    /* 1: the panel, opened along its own slits, is a topological disk */
    int32_t corners;
    int32_t boundary_loops;
    double max_abs_strain;       /* worst |warp| or |weft| strain over the panel's triangles (-1: not flattened) */
    int32_t flipped_triangles;
    int32_t boundary_self_intersections;
    double max_seam_mismatch;    /* worst relative mismatch of the panel's seams and darts (-1: not measured) */
    int32_t darts;               /* dart slits of the panel (a slit with a tip inside) */
    double min_dart_opening_deg; /* smallest opening angle at a dart tip in the flattening, -1 none or not flattened */
    /* Piece shape (docs/segment.md, "Piece shapes"): not judged when -1 (not measured); an area share of 0
     * neither (no real panel has none). */
    double area_share;           /* the panel's area / the garment's */
    double min_width_mm;         /* twice the largest distance from the outline inside the panel */
    int width_forced;            /* 1: narrow because the input is (a whole component, or measured from its
                                    seams alone it is at least min_piece_width_mm wide): not judged narrow */
    int area_forced;             /* 1: a whole component of the garment: not judged small */
    double across_grain_mm;      /* the flattened piece's extent across the grain (-1 not flattened) */
    double min_dart_intake_mm;   /* the smallest opening of a dart at its mouth in the flattening (-1 none) */
} pz_goal_result;

/**
 * The one goal judge: the failure bits of a panel's figures under `goals`
 * (PZ_GOAL_VETOED is kept from figures->failures; every other bit is judged
 * again). A figure not measured (strain or seam mismatch -1) is not judged.
 * The segmentation's evaluations and the final verdict of panelize run both
 * call it, so a goal added here counts everywhere.
 */
unsigned pz_goal_judge(const pz_goal_options *goals, const pz_goal_result *figures);

/**
 * Evaluates one panel: the faces face_ids[0..count-1] of `mesh` (a valid
 * garment with topology), `edge_cut` the layout's cut edges (the corners
 * depend on which neighbour lies across each outline edge; the panel's own
 * slits are cut). Flattens only when the panel is a disk with at most
 * max_corners corners (otherwise max_abs_strain = -1: the panel must be split
 * anyway). Thread-safe (call it from several threads at once).
 */
pz_status pz_segment_goals(const pz_mesh *mesh, const pz_topology *topology, const uint8_t *edge_cut,
                           const int32_t *face_ids, int32_t count, const pz_goal_options *options,
                           pz_goal_result *out, pz_ctx *ctx);

/**
 * The width of a piece (docs/segment.md, "Piece shapes"): twice the largest
 * distance from its outline inside it, propagated over the edges of the
 * triangles `faces` (face_count x 3 ids below vertex_count) with the straight
 * distance to the outline vertex each vertex is reached from. points:
 * vertex_count x dim (2: a flattened piece, 3: a panel on the garment);
 * source[v] = 1 for the outline's vertices. *width = INFINITY when no vertex
 * is a source (a closed surface). O(E log V). Errors: PZ_ERR_USAGE, PZ_ERR_NOMEM.
 */
pz_status pz_piece_width(int32_t vertex_count, const double *points, int dim, int32_t face_count,
                         const int32_t *faces, const uint8_t *source, double *width, pz_ctx *ctx);

/** "not a disk, 11 corners > 8, strain 0.071 > 0.05, 3 flipped triangles, seam mismatch 0.8% > 0.5%" into buf
 * (goals met: "ok"). */
void pz_goal_describe(const pz_goal_result *result, const pz_goal_options *options, char *buf, size_t size);

/* ------------------------------------------------------------------------ */
/* The layout                                                                */
/* ------------------------------------------------------------------------ */

/** Evaluations shared by several pz_segment calls (pz_segment_cache_create, below). */
typedef struct pz_segment_cache pz_segment_cache;

typedef struct pz_segment_options {
    int32_t max_corners;         /* C; 0 = 8 */
    double max_strain;           /* S (>= 0; pz_segment_options_default sets 0.05) */
    /* The piece-shape goals of pz_goal_options (0: not judged; pz_segment_options_default sets the goals'
     * defaults): a split that would cut a piece narrower or smaller is never made. */
    double min_piece_width_mm, min_piece_area, max_piece_width_mm, min_dart_intake_mm;
    pz_symmetry_mode symmetry;   /* default AUTO */
    double symmetry_plane[4];    /* PZ_SYMMETRY_PLANE: nx, ny, nz, d (n . p = d, millimetres) */
    int darts;                   /* 1: insert darts (default), 0: none */
    double grain[3];             /* 3D warp axis (unit); pz_segment_options_default: +z */
    const pz_sketch *sketch;     /* curves that become seams never removed, or NULL */
    int32_t max_candidates;      /* candidate paths sampled per level; 0 = default */
    int32_t max_depth;           /* recursion levels into failing panels; 0 = default */
    int threads;                 /* OpenMP threads; 0 = default. The result does not depend on it. */
    pz_trace_graph_options graph;
    /* The tracing graph of this mesh and field, built with `graph` (pz_trace_graph_build), to use instead of
     * building it again (borrowed, read only: the pipeline builds it once per field and shares it between
     * its layouts and runs, docs/run.md "Reuse between runs"), or NULL: built here. */
    const pz_trace_graph *prebuilt_graph;
    /* Panels known to fail (may be NULL): pz_segment_face_set_key of face sets that a previous
     * layout's final flattening (all panels jointly, seams coupled) found failing while their own
     * evaluation passed. A panel with one of these face sets fails with PZ_GOAL_VETOED, so the
     * layout splits it (or does not merge into it) this time. docs/run.md, "The final verdict". */
    const uint64_t *vetoed;
    int32_t vetoed_count;
    /* Evaluations shared with earlier calls on the same mesh, goals and grain (may be NULL: a private
     * cache). The caller keeps it alive during the call. */
    pz_segment_cache *cache;
    /* 0 .. 0.9: a panel passes only when its evaluated strain is at most (1 - strain_margin) S (its
     * flattening still aims at S). 0 by default; panelize run raises it in its verdict rounds, where
     * the joint flattening showed the evaluations too optimistic for this garment. */
    double strain_margin;
    /* Edges cut from the start and never removed (flags over the topology's edges, may be NULL), like
     * sketches: every panel of a layout that has these cuts is a union of this layout's panels, so this
     * layout has at least as many. panelize run passes the final cuts of its looser goals here
     * (docs/segment.md, "Monotone panel counts"). */
    const uint8_t *seed_cuts;
    /* The piece budget (0: none): at most this many panels (mirror pairs count as two), with the least
     * strain. The layout is made as usual but for the seams beyond the garment's structure once the budget
     * is reached, then merged down one seam segment at a time, each time the removal that leaves the least
     * worst strain among those that keep every panel a disk flattening injectively; corners and S no
     * longer stop a merge (result->budget_met: reached; docs/segment.md, "A piece budget and the
     * trade-off"). */
    int32_t max_pieces;
    /* 1: stop as soon as the layout shows S out of reach with sound pieces: a panel over S already under a
     * piece-shape goal (a split only makes it thinner), or panels over S once the insertion is done (removal
     * and darts never mend them). The layout so far is returned, goals_met 0 and stopped_unsound 1, without
     * removal or darts. panelize run's probe of an S its outlook doubts (docs/run.md, "Impossible goals"). */
    int stop_when_unsound;
    /* Progress (may be NULL): stage name ("candidates", "insert", "remove", "darts", "budget"), called after
     * each insertion, removal, dart and budget merge with the current panel count and the worst strain among the
     * current panels that have been flattened (0 when none has). The context's progress callback
     * (pz_ctx.progress) is called at the same steps, with the fraction done. */
    void (*on_progress)(void *user, const char *stage, int32_t panel_count, double worst_strain);
    void *user;
} pz_segment_options;

void pz_segment_options_default(pz_segment_options *options);

/**
 * Panel evaluations kept across pz_segment calls (pz_segment_options.cache): a
 * panel is judged by its faces and the neighbours across its outline, so a
 * second layout of the same mesh with the same goals (panelize run's verdict
 * rounds) flattens only the panels the first never met. Create with
 * pz_segment_cache_create (NULL when out of memory), free with
 * pz_segment_cache_free (accepts NULL). Not thread-safe across calls.
 */
pz_segment_cache *pz_segment_cache_create(void);
void pz_segment_cache_free(pz_segment_cache **cache);

/** The key of a panel's face set for pz_segment_options.vetoed: faces[0..count-1] in increasing order. */
uint64_t pz_segment_face_set_key(const int32_t *faces, int32_t count);

/** A seam path of the final layout, for layout.obj and the report. */
typedef enum pz_layout_curve_kind {
    PZ_LAYOUT_SEAM = 0,          /* separates two panels (or a panel and itself) */
    PZ_LAYOUT_DART = 1,          /* a dart slit, tip at vertices[0] */
    PZ_LAYOUT_SKETCH = 2         /* a sketched seam (kept whatever the goals) */
} pz_layout_curve_kind;

typedef struct pz_layout_curve {
    pz_layout_curve_kind kind;   /* a sketched curve that ends inside a panel is a PZ_LAYOUT_DART */
    int sketched;                /* 1: from a sketch (never removed), whatever its kind */
    int closed;
    int32_t vertex_count;
    int32_t *vertices;           /* garment vertices along cut edges */
} pz_layout_curve;

typedef struct pz_segment_panel {
    int32_t face_count;
    int32_t corners;
    int32_t darts;
    int32_t mirror_panel;        /* the panel that is its mirror image, itself when it straddles the plane, -1 */
    int copy;                    /* 1: the mirror image of mirror_panel on the half the layout was not made on:
                                    one pattern piece with it (its goals and corners are the pair's) */
    pz_goal_result goals;        /* at the final layout */
} pz_segment_panel;

typedef struct pz_segment_result {
    int32_t face_count, edge_count;
    int32_t *face_panel;         /* face_count: 0 .. panel_count-1, numbered in order of first face */
    int32_t panel_count;
    uint8_t *edge_cut;           /* edge_count: 1 = cut (seam or dart slit) */
    uint8_t *extra_cuts;         /* edge_count: cut edges with the same panel on both sides (dart slits):
                                    the extra_cuts argument of pz_pattern_build */
    pz_segment_panel *panels;    /* panel_count */
    int32_t curve_count;
    pz_layout_curve *curves;     /* the layout split at junctions */
    int32_t dart_count;
    int goals_met;               /* every panel meets its goals */
    int stopped_unsound;         /* options.stop_when_unsound stopped the layout (S out of reach with sound pieces) */
    char reasons[512];           /* when not: "panel 3: strain 0.071 > 0.05; ..." (truncated) */
    pz_symmetry symmetry;        /* the plane used (found = 0: none) */
    double symmetry_residual_mm; /* RMS distance between the layout's cut edges and their mirror images */
    int32_t max_pieces;          /* options.max_pieces (0: no budget) */
    int budget_met;              /* 1 when the panels are at most max_pieces (1 without a budget) */
    int32_t budget_merges;       /* seam segments removed to meet the budget */
    int32_t budget_unmirrored;   /* of them, removed without their mirror image (no mirrored merge was left):
                                    the layout is then no longer symmetric (docs/segment.md) */
    /* Counters and timings. */
    int32_t candidate_count, inserted_count, removed_count, evaluation_count;
    int32_t merged_slivers;      /* seams removed at the end to merge a piece under the shape goals into a
                                    neighbour (that may then miss S: a sliver is never the answer to S) */
    double graph_ms, candidates_ms, insert_ms, remove_ms, darts_ms, budget_ms, total_ms;
} pz_segment_result;

/**
 * Builds the layout of a valid garment (millimetres) guided by its
 * cross-field (field->directions). The run always ends: when the goals cannot
 * be met (S = 0 on a sphere, a budget exhausted), the best layout found is
 * returned with goals_met = 0 and the reasons, still PZ_OK. A closed surface
 * gets loops; several components are segmented each on its own. With a
 * plane (found by PZ_SYMMETRY_AUTO within its tolerance, or given) the
 * layout is made on one half and mirrored (docs/segment.md, "Symmetry"):
 * the plane cut first and removed last, candidates traced on half 0, mirror
 * pairs judged as one piece (pz_segment_panel.copy). pz_segment uses the
 * plane whenever it has one; panelize run also makes the layout without it
 * and keeps the one with fewer panels.
 * Progress goes to ctx->progress (stage "segment", a fraction of the call
 * that never decreases) as well as to options->on_progress; ctx->cancel is
 * checked between steps (each insertion, removal, dart, panel evaluation),
 * so a cancelled call returns within about one step.
 * Caller frees *out with pz_segment_result_free.
 * Errors: PZ_ERR_USAGE (bad options), PZ_ERR_DATA (a sketch point off the
 * mesh), PZ_ERR_NOMEM, PZ_ERR_INTERNAL, PZ_ERR_CANCELLED (*out stays NULL,
 * nothing leaks, and a shared options->cache keeps only finished
 * evaluations).
 */
pz_status pz_segment(const pz_mesh *mesh, const pz_topology *topology, const pz_field *field,
                     const pz_segment_options *options, pz_segment_result **out, pz_ctx *ctx);
void pz_segment_result_free(pz_segment_result **result);

/** The merge sequence of a layout (pz_segment_merge_sequence): the trade-off between pieces and strain. */
#define PZ_TRADEOFF_STEPS 64
typedef struct pz_segment_tradeoff {
    int32_t count;                            /* steps recorded; [0] is the layout as given */
    int32_t pieces[PZ_TRADEOFF_STEPS];        /* panels after each step (decreasing) */
    double worst_strain[PZ_TRADEOFF_STEPS];   /* the worst strain of the segmentation's evaluations there */
    double ms;                                /* the time it took */
} pz_segment_tradeoff;

/**
 * The trade-off curve of a layout (docs/segment.md, "A piece budget and the trade-off"): from the layout
 * of `edge_cut` (flags over the topology's edges, e.g. a pz_segment_result's), merges panels one seam
 * segment at a time as the piece budget does (the merge leaving the least worst strain; corners no longer
 * count), recording the panel count and the worst strain after each, until one panel is left, no merge
 * keeps every panel a disk flattening injectively, or the worst strain exceeds stop_strain. Uses the
 * options' goals (S, grain, poses through the mesh), symmetry and threads; options->seed_cuts are never
 * removed (pass the sketched seams). The mesh is not changed. Errors: PZ_ERR_USAGE, PZ_ERR_NOMEM,
 * PZ_ERR_CANCELLED.
 */
pz_status pz_segment_merge_sequence(const pz_mesh *mesh, const pz_topology *topology,
                                    const pz_segment_options *options, const uint8_t *edge_cut, double stop_strain,
                                    pz_segment_tradeoff *out, pz_ctx *ctx);

/* ------------------------------------------------------------------------ */
/* Seam truing                                                               */
/* ------------------------------------------------------------------------ */

typedef struct pz_truing_options {
    int passes;                  /* Taubin lambda/mu passes along each chain; 0 = 20 */
    double max_move_rel;         /* a vertex moves at most this times its shortest edge; 0 = 0.5 */
    double corner_deg;           /* chain vertices turning more than this over 3 edges each way stay; 0 = 50 (as the corners of docs/segment.md) */
} pz_truing_options;

typedef struct pz_truing_result {
    int32_t chain_count;         /* chains of cut edges between nodes (or closed loops) */
    int32_t moved_vertices;      /* chain vertices moved onto the smoothed seams */
    int32_t relaxed_vertices;    /* their neighbours moved to keep the triangles well shaped */
    double mean_turn_before_deg; /* mean turning angle between consecutive cut edges, before and after */
    double mean_turn_after_deg;
    double max_move_mm;          /* the largest displacement of a vertex */
} pz_truing_result;

/**
 * Seam truing (docs/segment.md, "Truing"): moves the vertices of every chain of
 * cut edges (edge_cut over `topology` edges) onto a smoothed copy of the chain,
 * projected onto the original surface, and relaxes their neighbours; chain
 * ends, border vertices and corners stay. Connectivity and face order are
 * unchanged; mesh->positions and every pose in mesh->poses are updated in
 * place (poses by the barycentric position of each moved vertex on the
 * original surface). result may be NULL. Errors: PZ_ERR_USAGE, PZ_ERR_NOMEM
 * (the mesh is then left partly moved: callers keep a copy if they need one).
 */
pz_status pz_segment_true_seams(pz_mesh *mesh, const pz_topology *topology, const uint8_t *edge_cut,
                                const pz_truing_options *options, pz_truing_result *result, pz_ctx *ctx);

#ifdef __cplusplus
}
#endif

#endif /* PZ_SEGMENT_H */

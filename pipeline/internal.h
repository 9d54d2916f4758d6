/*
 * pipeline/internal.h -- what the files of pipeline/ share (not public).
 *
 *   inputs.c       panel, seam, dart and feature-curve files; joining panel files
 *   load.c         the load stage: the caller's mesh copied, in millimetres,
 *                  prepared (pz_run), repaired and validated
 *   panels.c       the user's panels (groups, labels, uv, per-face ids) and
 *                  their seams and darts mapped onto the prepared garment
 *   segmentation.c the automatic layout with its verdict rounds and the
 *                  looser goal settings that keep panel counts monotone
 *   sketches.c     the designer's lines gathered for it (pl_gather_sketch), their
 *                  symmetry about the plane, their mirror images (mirror_sketch)
 *   run_cache.c    the plane, field and graphs kept for the next run (pz_run_cache)
 *   flatten.c      the chosen back-end, the pieces laid out, metrics
 *   verdict.c      the final verdict on every panel (pz_goal_judge) and the
 *                  pattern's mirror symmetry
 *   mirror.c       exact mirror pieces: pairs and pieces crossed by the plane
 *   mirror_pairing.c  their outlines paired (mirror_internal.h), the residual
 *   mirror_garment.c  the garment made exactly symmetric before the layout
 *   tradeoff.c     the outlook on S before the segmentation, the trade-off curve after the verdict
 *   pipeline.c     pz_run, pz_flatten, pz_result_free: the stages in order
 *   names.c        the pieces' names from their place on the garment
 *   report.c       report.json (pz_result_report)
 *   write.c        pz_result_write: every file, all or nothing (the deferred marker
 *                  and trade-off made beside the files that need neither)
 *
 * SPDX-License-Identifier: GPL-3.0-or-later
 */
#ifndef PZ_PIPELINE_INTERNAL_H
#define PZ_PIPELINE_INTERNAL_H

#include "pipeline/pipeline.h"

/* Space between pieces when a back-end's pieces overlap and are laid out again (mm). */
#define PL_LAYOUT_GAP_MM 20.0

/** The base name of a path without its extension (malloc'd; NULL when out of memory). */
char *pl_base_name(const char *path);

/**
 * Progress: reports `stage` at `from` of the whole, then maps the stage's own
 * 0..1 reports into from .. to (pz_progress_range).
 */
void pl_stage(pz_ctx *ctx, const char *stage, double from, double to, const char *message);

/** "run" or "flatten": the first word of the pipeline's messages. */
const char *pl_who(const pz_result *result);

/* ---------------------------------------------------------------- inputs.c */

/** Feature curves read from a features file (points in mm). */
typedef struct pl_feature_file {
    int32_t curve_count;
    pz_feature_polyline *polylines;   /* curve_count; points point into `points` */
    double *points;                   /* every curve's points, x 3 */
} pl_feature_file;

/**
 * A features file: JSON {"curves":[{"kind":"key"|"accessory","points":
 * [[x,y,z],...]}]} with at least one curve of at least two points, in the
 * input's units; mm_per_unit converts to millimetres like the mesh.
 * PZ_ERR_OPEN when unreadable; PZ_ERR_DATA naming the file and the line (not
 * JSON) or the curve and point (wrong shape) otherwise.
 */
pz_status pl_read_features(const char *path, double mm_per_unit, pl_feature_file *out, pz_ctx *ctx);
void pl_feature_file_clear(pl_feature_file *features);

/* ---------------------------------------------------------------- load.c */

/** The caller's mesh as the pipeline works on it, and how its ids map onto it. */
typedef struct pl_garment {
    pz_mesh *mesh;                /* prepared, millimetres (moved into the result at the end) */
    int32_t raw_vertex_count, raw_face_count;
    int32_t *raw_to_garment;      /* raw_vertex_count: the prepared vertex, or -1 when no face used it */
    int ids_preserved;            /* only unreferenced vertices were dropped: the caller's ids map exactly */
} pl_garment;

/**
 * The load stage: copies `input`, converts it to millimetres
 * (options->units), runs the automatic preparation when `prepare` is set
 * (its report goes to result->prepared), applies options->repair_flags and
 * validates (PZ_ERR_INVALID_MESH naming options->name). Fills
 * result->positions_out, units, units_guessed, grain and grain_source.
 */
pz_status pl_load(const pz_mesh *input, const pz_run_options *options, int prepare, pz_result *result,
                  pl_garment *garment, pz_ctx *ctx);
void pl_garment_clear(pl_garment *garment);

/* ---------------------------------------------------------------- mirror_garment.c */

/** The garment made exactly symmetric before the automatic layout, and what gives it back. */
typedef struct pl_symmetric {
    int active;                      /* 1: the garment being laid out is the symmetric one */
    int restored;                    /* 1: it was given back (the layout did not use the plane) */
    pz_symmetry symmetry;            /* the plane, the input's residual, the exact maps of the symmetric garment */
    double deviation_max_mm, deviation_p95_mm;  /* the input's vertices' distance to it */
    int32_t cut_faces, snapped_vertices;         /* what the symmetrization did, and its time */
    double milliseconds;
    pz_mesh *original;               /* the garment as loaded (while active) */
    double *original_positions_out;
    int original_ids_preserved;
    int32_t *original_seam_vertices; /* the preparation's welded seams in the garment's own ids */
} pl_symmetric;

/**
 * With a plane found or given (options->segment.symmetry not off) on a garment
 * without poses: garment->mesh replaced by the exactly symmetric garment,
 * result->positions_out by its positions and the preparation's welded seams
 * mapped onto it; sym keeps what pl_symmetric_restore gives back. Otherwise
 * sym->active 0 and nothing changes. Errors: PZ_ERR_NOMEM.
 */
pz_status pl_symmetrize_garment(const pz_run_options *options, pz_result *result, pl_garment *garment,
                                pl_symmetric *sym, pz_ctx *ctx);
/** The garment, positions_out and welded seams as loaded (sym->restored set); nothing when not active. */
void pl_symmetric_restore(pl_symmetric *sym, pz_result *result, pl_garment *garment);
/** Vertices moved along the surface (seam truing) made symmetric again: each pair averaged through the plane. */
void pl_symmetric_resettle(const pl_symmetric *sym, pz_mesh *mesh);
/** The symmetrization's figures in result (symmetrized, its deviation; -1 when the garment is the input's), and
 * a note saying what it did when the garment laid out is the symmetric one (ctx NULL: no note). */
void pl_symmetric_report(const pl_symmetric *sym, pz_result *result, pz_ctx *ctx);
void pl_symmetric_clear(pl_symmetric *sym);
/** 1 when a panel of result's flattening (pattern, uv) misses a goal of the run (pl_judge_panels, rest pose). */
int pl_symmetric_misses_goals(const pz_result *result, const pz_mesh *garment, pz_ctx *ctx);

/* ---------------------------------------------------------------- panels.c */

/** Panels chosen for one flattening: per-face ids, names, extra cuts (all owned). */
typedef struct pl_panel_choice {
    const char *source;           /* "segmentation", "file", "uv", "files", "groups", "components" (static) */
    int32_t *face_panel;          /* face_count */
    int32_t panel_count;
    uint8_t *extra_cuts;          /* flags over pz_topology_build(garment)'s edges, or NULL */
    char **names;                 /* panel_count entries (may be NULL), or NULL */
} pl_panel_choice;

void pl_panel_choice_clear(pl_panel_choice *choice);
void pl_panel_choice_drop_names(pl_panel_choice *choice);

/** The user's panels (panels NULL: groups) on the loaded garment. */
pz_status pl_user_panels(const pz_panels *panels, const pl_garment *garment, const pz_result *result,
                         pl_panel_choice *choice, pz_ctx *ctx);

/** The user's seams and darts in the loaded garment's vertex ids (*out cleared with pz_correspondences_clear). */
pz_status pl_user_correspondences(const pz_panels *panels, const pl_garment *garment, int32_t panel_count,
                                  pz_correspondences *out, pz_ctx *ctx);

/* ---------------------------------------------------------------- segmentation.c */

/**
 * The user's sketches (options->sketch in memory, then options->sketch_path; with options->mirror_sketch and
 * a `plane` (may be NULL), each stroke's mirror image too), options->garment_seams, and the seams `prepared`
 * welded (a designer's seams survive the weld), in one sketch in the garment's millimetres; *out NULL when
 * there is none, else the caller frees it (pz_sketch_free). A sketch off the surface is a data error naming it.
 */
pz_status pl_gather_sketch(const pz_run_options *options, const pz_prepare_result *prepared, const pz_mesh *mesh,
                           const pz_symmetry *plane, pz_sketch **out, pz_ctx *ctx);

/**
 * The designer's strokes alone (options->sketch, then options->sketch_path), checked against the mesh;
 * *out NULL when there are none, else the caller's (pz_sketch_free).
 */
pz_status pl_designer_sketch(const pz_run_options *options, const pz_mesh *mesh, pz_sketch **out, pz_ctx *ctx);

/** How far a stroke's mirror image may lie from a stroke and still count as it: 2 % of the mesh's diagonal, at
 * least 10 mm (a stroke drawn by hand on each side) and two mean edge lengths (strokes through vertices). */
double pl_sketch_mirror_tolerance(const pz_mesh *mesh);

/**
 * *symmetric = 1 when every curve of `sketch` (may be NULL) mirrored through `plane` lies, for 90 % of its
 * length, within `tolerance` of the sketch (its own image on the plane, or another stroke); 1 without a sketch
 * or a plane. Bounded: at most about 20,000 samples whatever the sketch. PZ_ERR_NOMEM.
 */
pz_status pl_sketch_symmetric(const pz_sketch *sketch, const pz_symmetry *plane, double tolerance, int *symmetric,
                              pz_ctx *ctx);

/** The same for the designer's sketch of a run (pl_designer_sketch) with pl_sketch_mirror_tolerance. */
pz_status pl_sketch_symmetric_on(const pz_run_options *options, const pz_mesh *mesh, const pz_symmetry *plane,
                                 int *symmetric, pz_ctx *ctx);

/** Appends the mirror image through `plane` of every curve of `sketch` that has none (the test above). */
pz_status pl_sketch_add_mirrors(pz_sketch *sketch, const pz_symmetry *plane, double tolerance, pz_ctx *ctx);

/** 1 when nothing pz_run deferred is left for pz_result_complete to make (options.defer_extras). */
int pl_result_completed(const pz_result *result);

/* ---------------------------------------------------------------- run_cache.c */

/** The mirror plane found before the field and the cross-field (with its mirrored version): what a run
 * leaves for the next run of the same garment, sketch and options (pz_run_cache). */
typedef struct pl_plane_and_field {
    pz_symmetry symmetry;     /* the plane (found or given) with its maps; found = 0 without one */
    int plane;                /* 1: the layouts may use it (found, and not refused for a one-sided sketch) */
    int sketch_asymmetric;    /* found and refused: the designer's sketch is not symmetric about it */
    pz_field *field;          /* the cross-field of the garment */
    pz_field *mirror_field;   /* the field symmetrized about the plane, or NULL */
    pz_trace_graph *graph;    /* the tracing graph of `field` (the segmentation's graph options) */
    pz_trace_graph *mirror_graph; /* of `mirror_field`, or NULL */
    double field_ms;          /* what computing them took */
} pl_plane_and_field;

void pl_plane_and_field_clear(pl_plane_and_field *value);

/** *key: a hash of everything the plane and field depend on (the garment's positions, faces and poses, the
 * field's and symmetry's options, the designer's sketch, the garment's and welded seams, the grain hints,
 * a given plane's maps). Reads the sketch file again (its errors are the run's). */
pz_status pl_plane_and_field_key(const pz_run_options *options, const pz_prepare_result *prepared,
                                 const pz_sketch *grain_hints, const pz_symmetry *given_plane, const pz_mesh *garment,
                                 uint64_t *key, pz_ctx *ctx);
/** A copy of the entry of `key` into *out (cleared first by the caller) and *found = 1; *found = 0 when the cache
 * (may be NULL) has none. PZ_ERR_NOMEM. */
pz_status pl_run_cache_find(pz_run_cache *cache, uint64_t key, pl_plane_and_field *out, int *found, pz_ctx *ctx);
/** A copy of `value` kept under `key` (the older of the two entries replaced); nothing without a cache. */
pz_status pl_run_cache_keep(pz_run_cache *cache, uint64_t key, const pl_plane_and_field *value, pz_ctx *ctx);

/** The automatic layout's state across verdict rounds (opaque). */
typedef struct pl_segmenter pl_segmenter;

pz_status pl_segmenter_create(const pz_run_options *options, const pz_prepare_result *prepared, const double grain[3],
                              pl_segmenter **out, pz_ctx *ctx);
void pl_segmenter_free(pl_segmenter **segmenter);

/**
 * The automatic panels of `garment` (its vertices may move along the surface:
 * seam truing). Called again after pl_segmenter_accept said no, it makes the
 * layout again with the rejected panels vetoed.
 */
pz_status pl_segmenter_choose(pl_segmenter *segmenter, pz_mesh *garment, pl_panel_choice *choice, pz_ctx *ctx);

/** The verdict round: 1 accepts the flattening (uv) of the panels last chosen, 0 asks for a new layout. */
int pl_segmenter_accept(pl_segmenter *segmenter, const pz_pattern *pattern, const double *uv, pz_ctx *ctx);
/* The strain goal the flattening aims at: the run's S, or the looser S whose layout was written because the
 * run's could not be met with sound pieces (pipeline/segmentation.c, write_sound_instead). */
double pl_segmenter_flatten_strain(const pl_segmenter *segmenter, double run_strain);

/** The mirror pieces of the panels last chosen made exact in uv (pl_exact_mirror_pieces), when the layout used a
 * plane. */
pz_status pl_segmenter_exact_mirrors(pl_segmenter *segmenter, const pz_pattern *pattern, double *uv, pz_ctx *ctx);

/** Moves what the run reports (segmentation, field, truing, rounds, ladder) into the result. */
void pl_segmenter_report(pl_segmenter *segmenter, pz_result *result);
/** The plane to use, with its maps (the symmetric garment's exact ones), instead of detecting one; `symmetry`
 * stays the caller's and must outlive the segmenter's first choice. */
void pl_segmenter_give_plane(pl_segmenter *segmenter, const pz_symmetry *symmetry);
/** The strain outlook (can S be met?) of `from`, taken already: not measured nor said again. */
void pl_segmenter_take_outlook(pl_segmenter *segmenter, const pl_segmenter *from);
/** The grain hints (millimetres; borrowed, must outlive the segmenter): the field aligns to them too. */
void pl_segmenter_give_grain_hints(pl_segmenter *segmenter, const pz_sketch *hints);
/** The layout last chosen (the segmenter's), or NULL. */
const pz_segment_result *pl_segmenter_layout(const pl_segmenter *segmenter);
/** 1 when the layout last chosen was made with the plane (mirrored). */
int pl_segmenter_plane_used(const pl_segmenter *segmenter);
/* 1 when the run's S was out of reach and a looser setting's layout is written (issue 15). */
int pl_segmenter_wrote_looser(const pl_segmenter *segmenter);

/* ---------------------------------------------------------------- flatten.c */

/**
 * Flattens every panel of `pattern` with the back-end of options->flatten
 * (grain: result->grain; panel_turn: each panel's grain turn from the
 * hints, pattern->panel_count radians, or NULL), strain goal
 * strain_limit (0: none), writing uv (2 per pattern vertex, zeroed by the
 * caller) and result->backend.
 */
pz_status pl_flatten_pattern(const pz_run_options *options, const pz_pattern *pattern, double mm_per_unit,
                             const double grain[3], const double *panel_turn, double strain_limit, double *uv,
                             pz_backend_outcome *outcome, pz_ctx *ctx);

/* ---------------------------------------------------------------- grain hints (sketches.c, grain_hints.c) */

/* The most grain hints a run takes: a piece is turned by one; each is placed by a search over the faces. */
#define PL_GRAIN_HINTS_MAX 200

/**
 * The grain hints of the options (options->grain_hints, millimetres, and the
 * curves of options->grain_hints_path in the mesh's units), each within
 * pz_sketch_tolerance of `mesh`, into *out (NULL when there are none; the
 * caller's, pz_sketch_free). PZ_ERR_OPEN, PZ_ERR_DATA naming the file and the
 * curve (or more than PL_GRAIN_HINTS_MAX hints), PZ_ERR_NOMEM.
 */
pz_status pl_gather_grain_hints(const pz_run_options *options, const pz_mesh *mesh, pz_sketch **out, pz_ctx *ctx);
/** The curves of a then b (either may be NULL) into *out (NULL when both are; the caller's). PZ_ERR_NOMEM. */
pz_status pl_sketch_join(const pz_sketch *a, const pz_sketch *b, pz_sketch **out, pz_ctx *ctx);
/**
 * Each panel's grain turn from the grain hints (docs/run.md, "Grain hints"):
 * a hint is given to the panel of the face nearest its middle point, and its
 * turn is the angle, on that face and about its normal, from the projected
 * global `grain` to the hint's chord (first point to last); several in one
 * panel are averaged (strokes either way along a line agree); a mirror pair's
 * partner without a hint takes the mirrored turn (segment: the layout, or
 * NULL). *panel_turn: pattern->panel_count radians (0: no hint; the caller's,
 * free), NULL when `hints` is NULL. *hinted: the panels turned. PZ_ERR_NOMEM.
 */
pz_status pl_panel_grain(const pz_pattern *pattern, const double grain[3], const pz_sketch *hints,
                         const pz_segment_result *segment, double **panel_turn, int32_t *hinted, pz_ctx *ctx);

/**
 * The flattening the segmentation's verdict judges a looser goal setting
 * with: the run's own back-end when it is textile or lscm, textile otherwise.
 */
pz_status pl_flatten_for_verdict(const pz_run_options *options, const pz_pattern *pattern, const double grain[3],
                                 const double *panel_turn, double strain_limit, double *uv, pz_ctx *ctx);

/** One warning line per thing a user should know about a best-effort WireWarping. */
void pl_warn_wirewarp(const pz_run_options *options, const pz_backend_outcome *outcome, pz_ctx *ctx);

void pl_backend_outcome_clear(pz_backend_outcome *outcome);

/**
 * When the bounding boxes of two panels overlap, translates every panel into
 * rows (shelves, tallest first) with gap_mm between pieces; a layout without
 * overlaps is kept as the back-end made it. uv changed in place; sets *moved.
 */
pz_status pl_pattern_layout(const pz_pattern *pattern, double *uv, double gap_mm, int *moved, pz_ctx *ctx);

/** metrics[0] on the rest pose, metrics[p] on extra pose p (count = 1 + poses). */
pz_status pl_measure(const pz_pattern *pattern, const double *uv, const pz_fabric *fabric, pz_metrics **metrics,
                     int count, pz_ctx *ctx);

/** Each panel's worst |warp| or |weft| strain over the extra poses; NULL when out of memory (caller frees). */
double *pl_strain_of_poses(const pz_pattern *pattern, const double *uv, const pz_fabric *fabric, pz_ctx *ctx);

/* ---------------------------------------------------------------- verdict.c */

/**
 * Judges every panel of `pattern` against `goals` with the one goal judge:
 * disk, corners, area share and whether the input forces a narrow or small
 * piece on the garment's cut outline; strain and injectivity on the
 * flattening (metrics: the rest pose; pose_strain, may be NULL: each panel's
 * worst strain over the extra poses); seam and dart length mismatch and dart
 * intakes from the metrics; the piece's width and its extent across the grain
 * on the pattern (uv). panels (pattern->panel_count) receives each panel's
 * figures and failure bits. segment (may be NULL): the layout, when its
 * panels are the pattern's: a mirror pair is one pattern piece, so the copy
 * of a pair (pz_segment_panel.copy) takes its partner's corners.
 */
pz_status pl_judge_panels(const pz_mesh *garment, const pz_pattern *pattern, const double *uv,
                          const pz_metrics *metrics, const double *pose_strain, const pz_goal_options *goals,
                          const pz_segment_result *segment,
                          pz_goal_result *panels, pz_ctx *ctx);

/** The final verdict of a result (goals met, reasons, one note when missed) from its metrics. */
pz_status pl_final_verdict(pz_result *result, int layout_reachable, pz_ctx *ctx);

/**
 * Names the segmentation's pieces after their place on the garment (front_left, back, sleeve_right, collar,
 * ...: docs/run.md, "Piece names") into result->panel_names; mirror partners (result->panel_mirror) get the
 * same name with the other side. Nothing to do when the panels have names (the user's groups or files).
 */
pz_status pl_name_pieces(pz_result *result, pz_ctx *ctx);

/* ---------------------------------------------------------------- tradeoff.c */

/**
 * The outlook on S (docs/run.md, "Can S be met?"), taken on the prepared garment before the field and the
 * segmentation: the poses' spread and the strain of sample pieces of the smallest sound size; one note
 * naming an S that would work when they exceed S. PZ_ERR_NOMEM, PZ_ERR_CANCELLED.
 */
pz_status pl_strain_outlook(const pz_mesh *garment, const pz_run_options *options, const double grain[3],
                            pz_strain_outlook *out, pz_ctx *ctx);

/**
 * The trade-off (docs/run.md): result->tradeoff from the final layout (result->segment on result->garment),
 * merged down until the worst strain passes the grid's loosest goal. Left unmeasured (count 0) when it
 * cannot be made; PZ_ERR_NOMEM, PZ_ERR_CANCELLED.
 */
pz_status pl_measure_tradeoff(pz_result *result, pz_ctx *ctx);

/** The flattened pieces' own mirror symmetry (result->pattern_mirror_*), when the layout found a plane. */
void pl_measure_pattern_symmetry(pz_result *result, pz_ctx *ctx);

/* ---------------------------------------------------------------- mirror.c */

/**
 * Makes the mirror pieces of a layout made with a plane exact in uv (docs/segment.md, "Exact mirror pieces"):
 * each pair (a panel and its copy, pz_segment_panel.copy) and each panel crossed by the plane (its own mirror
 * panel), unless that pushes a panel past the strain goal max_strain. *pieces: the pairs and self-mirrored
 * panels, *exact: those made exact. Nothing without a plane or when the pattern's panels are not the layout's.
 * PZ_ERR_NOMEM.
 */
pz_status pl_exact_mirror_pieces(const pz_pattern *pattern, const pz_segment_result *segment, double max_strain,
                                 double *uv, int32_t *exact, int32_t *pieces, pz_ctx *ctx);

/**
 * The residual of the mirror pieces (mm): every outline vertex of a piece against its partner's outline
 * reflected (the best 2D reflection through the anchors), both ways; RMS and largest over all pairs and pieces
 * crossed by the plane; -1 when there is none. panel_largest (panel count, may be NULL): each panel's pair's
 * largest (-1: not in one). PZ_ERR_NOMEM.
 */
pz_status pl_mirror_residual(const pz_pattern *pattern, const double *uv, const pz_segment_result *segment,
                             double *rms, double *largest, double *panel_largest, pz_ctx *ctx);

/** The garment's faces bucketed by pattern panel (CSR); 0 when out of memory. The caller frees both. */
int pl_faces_by_panel(const pz_pattern *pattern, int32_t **offsets, int32_t **order);

/* ---------------------------------------------------------------- report.c, write.c */

/** layout.obj: the layout curves on the garment, in the input's units. */
pz_status pl_write_layout_obj(const pz_result *result, FILE *file, pz_ctx *ctx);

/* ---------------------------------------------------------------- folder.c */

/** An output folder being written: the hidden folder beside it, swapped in on commit. */
typedef struct pl_folder {
    char *target, *parent, *name;   /* the folder asked for, its parent and its last component */
    char *hidden;                   /* PARENT/.NAME.tmp-PID: where the files are written */
    int lock_fd;                    /* the parent, locked while this writer works (-1: no lock) */
    int committed;
} pl_folder;

/** Checks the folder (pz_output_folder_check), takes the parent's lock, clears dead runs' leftovers, makes the hidden folder. */
pz_status pl_folder_begin(const char *folder, pl_folder *out, pz_ctx *ctx);
/** Writes the marker (the files' names) last, syncs, and swaps the hidden folder in for the target. */
pz_status pl_folder_commit(pl_folder *folder, const char *const *files, int file_count, pz_ctx *ctx);
/** Removes the hidden folder unless committed, releases the lock, frees. */
void pl_folder_end(pl_folder *folder);

/** garment.obj: `v` = positions_out, `vt` = uv, the garment's faces with `g panel_K` groups. */
pz_status pl_write_garment_obj(FILE *file, const pz_mesh *garment, const double *positions,
                               const pz_pattern *pattern, const double *uv, pz_ctx *ctx);

#endif /* PZ_PIPELINE_INTERNAL_H */

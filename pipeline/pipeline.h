/*
 * pipeline/pipeline.h -- the whole of panelize as one library call.
 *
 *   pz_run:     garment in, sewable pattern out (load -> prepare -> field ->
 *               segment -> param -> export), every panel judged by one goal
 *               judge (segment/segment.h, pz_goal_judge).
 *   pz_flatten: the user's own panels flattened (no segmentation).
 *   pz_result_write: the files of a result, into a folder, all or nothing.
 *
 * Nothing here touches the file system but pz_result_write (and the
 * option files the options name: sketches, allowances, feature curves). The
 * command line (cli/), the Python package and the batch runner are callers
 * of these functions; docs/architecture.md shows how the stages connect.
 *
 *   pz_run_options options;
 *   pz_run_options_default(&options);
 *   options.goals.max_strain = 0.03;
 *   pz_result *result = NULL;
 *   if (pz_run(mesh, &options, &result, &ctx) == PZ_OK) {
 *       printf("%d panels, goals %s\n", result->pattern->panel_count,
 *              result->verdict.goals_met ? "met" : "not met");
 *       pz_result_write(result, "out", PZ_OUTPUT_ALL, &ctx);
 *   }
 *   pz_result_free(&result);
 *
 * Ownership: the mesh passed in stays the caller's and is not changed (the
 * pipeline works on its own copy); a result is the caller's and is freed
 * with pz_result_free; every pointer inside a result belongs to the result.
 * Progress and cancellation go through the context (core/core.h).
 *
 * SPDX-License-Identifier: GPL-3.0-or-later
 */
#ifndef PZ_PIPELINE_H
#define PZ_PIPELINE_H

#include "core/core.h"
#include "export/export.h"
#include "field/field.h"
#include "mesh/mesh.h"
#include "param/param.h"
#include "prepare/prepare.h"
#include "segment/segment.h"

#include <cjson/cJSON.h>

#ifdef __cplusplus
extern "C" {
#endif

/* ------------------------------------------------------------------------ */
/* Options                                                                   */
/* ------------------------------------------------------------------------ */

/** The back-end that flattens the panels (param/param.h). */
typedef enum pz_backend {
    PZ_BACKEND_TEXTILE = 0,    /* anisotropic textile energy, pietroni2022 Sec. 4.3 (default) */
    PZ_BACKEND_LSCM,           /* least-squares conformal maps (Levy 2002) */
    PZ_BACKEND_WIREWARP,       /* WireWarping, wang2008: every seam keeps its 3D length */
    PZ_BACKEND_SPRINGMASS,     /* spring-mass with heap relaxation, wang2002 + IISERM */
    PZ_BACKEND_COUNT
} pz_backend;

/** "textile", "lscm", "wirewarp", "springmass". */
const char *pz_backend_name(pz_backend backend);
/** The back-end of a name; PZ_BACKEND_COUNT when there is none. */
pz_backend pz_backend_parse(const char *name);

/** How the panels are flattened (the param stage as the pipeline drives it). */
typedef struct pz_flatten_options {
    pz_backend backend;          /* default PZ_BACKEND_TEXTILE */
    int iterations;              /* textile iterations, 1..PZ_MAX_ITERATIONS; default 20 */
    double weights[4];           /* textile weights: stretch, rigidity, dart, seam; default 5, 1, 5, 5 */
    pz_fabric fabric;            /* pz_fabric_default: the metrics' fabric and textile's constants */
    int fabric_given;            /* 1: springmass uses the orthotropic (warp, weft, shear) energy */
    int grain_given;             /* 0 (default): the garment's vertical axis (pz_mesh_vertical_axis) */
    double grain[3];             /* the warp direction in 3D when grain_given */
    int progressive;             /* wirewarp: 1 = the progressive scheme, 0 = global (default) */
    int relax_full;              /* springmass: 1 = relax every node, 0 = heap (default) */
    const char *features_path;   /* wirewarp: feature curves file (docs/wirewarp.md), or NULL */
} pz_flatten_options;

void pz_flatten_options_default(pz_flatten_options *options);

/* ------------------------------------------------------------------------ */
/* The user's own panels (pz_flatten, and pz_run with panels given)          */
/* ------------------------------------------------------------------------ */

typedef enum pz_panels_source {
    PZ_PANELS_GROUPS = 0,      /* one panel per connected piece of each label (OBJ group); the default */
    PZ_PANELS_LABELS,          /* one panel per label exactly (panel files joined with pz_mesh_join) */
    PZ_PANELS_UV,              /* the mesh's UV islands, cut along its UV seams */
    PZ_PANELS_FACES            /* face_panel below */
} pz_panels_source;

/**
 * Panels and their seams and darts, in the ids of the mesh given to
 * pz_flatten / pz_run (before any repair). Borrowed by the call.
 */
typedef struct pz_panels {
    pz_panels_source source;
    const int32_t *face_panel;          /* PZ_PANELS_FACES: one id per face, 0 .. panel_count - 1, each used */
    int32_t panel_count;
    const char *face_panel_name;        /* where face_panel came from, for messages (may be NULL) */
    const pz_seam *seams;               /* seams: vertex pairs of two panels (may be NULL) */
    int32_t seam_count;
    const pz_dart *darts;               /* darts: tip and facing leg vertices (may be NULL) */
    int32_t dart_count;
    const char *correspondence_name;    /* the first seam or dart file, for messages (may be NULL) */
} pz_panels;

/** Every option of the pipeline, one nested block per stage. */
/**
 * What one run leaves for the next run of the same garment (docs/run.md, "Reuse between runs"): the mirror
 * plane and the cross-field (with its mirrored version), found again only when something they depend on
 * changed (the garment, its poses, the sketch, the grain hints, the field's or symmetry's options), so a
 * run that changes S, C, darts, the piece budget or the fabric reuses them. Holds at most two garments'
 * (a symmetric garment's and the garment as loaded). One run at a time per cache; the caller frees it.
 * pz_run keeps one of its own for its consolidation trial when the options give none.
 */
typedef struct pz_run_cache pz_run_cache;
/** A new, empty cache (NULL when out of memory). */
pz_run_cache *pz_run_cache_create(void);
void pz_run_cache_free(pz_run_cache **cache);
/** How often runs found what they needed in the cache and how often they computed it (both 0 for NULL). */
void pz_run_cache_counts(const pz_run_cache *cache, int64_t *hits, int64_t *misses);

typedef struct pz_run_options {
    /* load: the mesh as read, in its file's units */
    pz_units units;                  /* the mesh's units; PZ_UNITS_AUTO (default) guesses */
    unsigned repair_flags;           /* pz_repair_flags applied before validation; default none */
    const char *name;                /* the garment's file or name, for messages and piece labels; may be NULL */
    const pz_panels *panels;         /* pz_run: the user's panels instead of the segmentation (NULL: segment) */
    const char *const *input_files;  /* the files the mesh was read from, for the report (NULL: name) */
    int32_t input_file_count;
    /* prepare (pz_run only): weld, repair, remesh when the mesh needs it */
    int prepare;                     /* 1 (default): pz_prepare_auto; 0: the mesh as given */
    pz_prepare_options prepare_options;
    /* field */
    pz_field_options field;          /* sketch and poses are set by the run */
    /* segment */
    pz_goal_options goals;           /* S, C, seam mismatch: pz_goal_options_default (its grain is set by the run) */
    pz_segment_options segment;      /* symmetry, darts, candidates, threads (its goals come from `goals`);
                                        segment.symmetry_plane (PZ_SYMMETRY_PLANE) in the input's units, like a
                                        sketch file: pz_run scales its offset with the mesh */
    const char *sketch_path;         /* seams the user drew: {"curves": [[[x,y,z], ...]]} in the mesh's units */
    const pz_sketch *sketch;         /* or the same in memory (millimetres); both may be given */
    const pz_sketch *garment_seams;  /* the garment's own seams (millimetres; may be NULL), kept as seams like the
                                        sketch but not the designer's: no part in its symmetry (the studio passes
                                        the seams its one preparation welded) */
    pz_run_cache *cache;             /* what this run may reuse from the last run of the same garment and keeps
                                        for the next (the plane and the cross-field), or NULL (docs/run.md,
                                        "Reuse between runs"); one run at a time per cache */
    int defer_extras;                /* 1: pz_run leaves the trade-off curve and the marker (the pieces nested on
                                        the fabric; with the trade-off a fifth of a short run) to
                                        pz_result_complete, which pz_result_write calls: for callers that look at
                                        a result before they write it (the studio); 0 (default) */
    int mirror_sketch;               /* 1: each stroke is also drawn mirrored about the garment's plane, when one
                                        is found, so the pattern stays symmetric; 0 (default): a sketch that is
                                        not symmetric lays the garment out without the plane (docs/run.md) */
    const char *grain_hints_path;    /* grain hints: {"curves": [[[x,y,z], ...]]} in the mesh's units, each a short
                                        stroke along which the warp runs in the piece it lies on (docs/run.md) */
    const pz_sketch *grain_hints;    /* or the same in memory (millimetres); both may be given */
    int truing;                      /* 1 (default): seams traced along mesh edges are smoothed on the surface */
    int consolidate;                 /* 1 (default): a layout that met its goals is made again with one piece fewer
                                        and kept when that meets them too (docs/run.md, "Consolidation") */
    /* param */
    pz_flatten_options flatten;
    /* export */
    pz_export_options output;        /* allowances, notches, paper, marker, names */
    const char *allowances_path;     /* per-seam allowances file (docs/export.md), or NULL */
} pz_run_options;

/** The defaults of every stage (each defined once, in its stage's own _default function). */
void pz_run_options_default(pz_run_options *options);

/* ------------------------------------------------------------------------ */
/* The options a person sets, checked once for every front end              */
/* ------------------------------------------------------------------------ */

#define PZ_MAX_ITERATIONS 10000        /* the textile back-end's iterations: 1 .. this */

/** How a message spells an option: "--max-strain" (the command line) or "max_strain" (a keyword argument). */
typedef enum pz_option_style {
    PZ_OPTION_FLAG = 0,
    PZ_OPTION_KEYWORD
} pz_option_style;

/**
 * The ranges of the options a person sets (the command line and the Python
 * package both call this after filling *options from pz_run_options_default
 * and the user's values): the goals (max-corners 1..1000, max-strain 0..10,
 * max-seam-mismatch 0..1, min-piece-width 0..1000 mm, min-piece-area 0..0.5,
 * min-dart-intake 0..1000 mm), the back-end (iterations 1..PZ_MAX_ITERATIONS,
 * weights >= 0, fabric > 0, grain not zero), the pattern files
 * (seam- and hem-allowance 0..100 mm, notch-spacing 1..10000 mm,
 * fabric-width 10..10000 mm, gap 0..1000 mm, paper a4 or letter, size 1..31
 * characters) and a symmetry plane's normal. PZ_ERR_USAGE
 * "COMMAND: OPTION: problem" naming the first option out of range.
 */
pz_status pz_run_options_check(const pz_run_options *options, const char *command, pz_option_style style,
                               pz_ctx *ctx);

/**
 * The field's options as a person sets them (scales 1..PZ_FIELD_MAX_SCALES,
 * smoothness finite and positive): front ends fill PZ_FIELD_DEFAULT_SCALES
 * and PZ_FIELD_DEFAULT_SMOOTHNESS first, so a given 0 is refused. As above.
 */
pz_status pz_field_options_check(const pz_field_options *options, const char *command, pz_option_style style,
                                 pz_ctx *ctx);

/** The preparation's options (edge >= 0 mm, not with faces; faces >= 0; weld finite). As above. */
pz_status pz_prepare_options_check(const pz_prepare_options *options, const char *command, pz_option_style style,
                                   pz_ctx *ctx);

/* ------------------------------------------------------------------------ */
/* The result                                                                */
/* ------------------------------------------------------------------------ */

/** The verdict on the final pattern, judged by pz_goal_judge on every panel. */
typedef struct pz_verdict {
    int judged;                      /* 1: goals were judged (pz_run); 0: pz_flatten (no goals) */
    int goals_met;
    int reachable;                   /* 0: the layout itself could not meet the goals (best effort) */
    int32_t failing_panels;
    int32_t over_strain_panels;      /* of them, over S */
    double worst_strain;             /* worst |warp| or |weft| strain over every panel and pose */
    double worst_seam_mismatch;      /* worst relative seam or dart length mismatch */
    double area_over_strain;         /* share of the garment's area whose warp or weft strain exceeds S in some
                                        pose (0..1) */
    pz_goal_result *panels;          /* panel_count: each panel's figures and failure bits */
    char reasons[1024];              /* when not met: a summary, then the failing panels */
} pz_verdict;

/**
 * The outlook on the strain goal, taken before the segmentation (pz_run; docs/run.md, "Can S be met?"):
 * estimates of the least strain any layout of sound pieces can reach.
 */
typedef struct pz_strain_outlook {
    int measured;                    /* 0: not taken (given panels) */
    double pose_spread;              /* the poses' own spread: the area-weighted 99th percentile over triangles of
                                        the least warp/weft strain any one pattern triangle leaves in some pose
                                        (0 without extra poses) */
    double piece_strain;             /* the 90th percentile of the worst strain of sample pieces (geodesic disks of
                                        piece_area_mm2, flattened as the segmentation flattens a panel) */
    double piece_area_mm2;           /* 1 % of the garment's area, or its area over --max-pieces when larger */
    int32_t samples;                 /* sample pieces flattened */
    double suggested_strain;         /* an S these estimates allow (rounded up to 0.01), at least the run's S */
    int reachable;                   /* 1: neither estimate exceeds S */
    double ms;
} pz_strain_outlook;

/** The trade-off grid: the strain goals report.json's "tradeoff" gives the piece counts of. */
#define PZ_TRADEOFF_GRID_COUNT 7
extern const double pz_tradeoff_grid[PZ_TRADEOFF_GRID_COUNT];

/**
 * The pieces the strain goal s needs, from a run's trade-off sequence (result->tradeoff): the fewest panels
 * of its steps whose worst strain is within s; -1 when none is (not measured that strictly).
 */
int32_t pz_tradeoff_pieces(const pz_segment_tradeoff *tradeoff, double s);

/** Timings of one call, milliseconds. */
typedef struct pz_timings {
    double read;                     /* set by the caller that read the files (the CLI) */
    double prepare, field, segment;  /* pz_run: the automatic preparation, the cross-field, the layout */
    double looser_goals;             /* of segment: the looser goal settings laid out first */
    double panels;                   /* choosing the panels (the segmentation, for pz_run), all rounds */
    double pattern;                  /* choosing the panels and cutting the garment, all rounds */
    double flatten;                  /* the back-end and the verdict rounds' judging, layout */
    double metrics, pieces, write, total;
} pz_timings;

/** A feature curve left out of the flattening (not on the mesh, across panels, ...). */
typedef struct pz_skipped_feature {
    int32_t curve;                         /* its index in the features file */
    char problem[256];
} pz_skipped_feature;

/** What the back-end reports of its own run (report.json's backend_result). */
typedef struct pz_backend_outcome {
    pz_textile_result textile;             /* textile only */
    pz_wirewarp_result wirewarp;           /* wirewarp only; relaxed_key_curves are indices in the features file */
    pz_springmass_result springmass;       /* springmass only */
    int32_t feature_count;                 /* wirewarp: feature curves used */
    int32_t skipped_count;                 /* wirewarp: feature curves left out */
    pz_skipped_feature *skipped;
    double ms;                             /* the back-end's own run */
} pz_backend_outcome;

/**
 * Everything the pattern files are made from, in memory. Every pointer is
 * owned by the result (pz_result_free). Lengths in millimetres.
 */
typedef struct pz_result {
    int from_run;                    /* 1: pz_run (segmentation or given panels with goals); 0: pz_flatten */
    pz_run_options options;          /* the options used (string pointers borrowed from the caller's) */
    /* the garment */
    pz_mesh *garment;                /* as flattened: prepared, repaired, seams trued (mm) */
    double *positions_out;           /* garment->vertex_count x 3 in the input's units (garment.obj's v) */
    pz_units units;                  /* the input's units */
    int units_guessed;
    double grain[3];                 /* the warp direction used */
    double pose_edge_change_median;  /* extra poses: the relative change of the edge lengths against the rest */
    double pose_edge_change_p95;     /* pose, median and 95th percentile over every edge and pose (0 without) */
    const char *grain_source;        /* "given", "vertical axis (y)", "vertical axis (z)" (static) */
    int32_t grain_hint_count;        /* the grain hints given (docs/run.md, "Grain hints") */
    double *panel_grain_turn;        /* pattern->panel_count radians: a panel's warp turned from `grain` about the
                                        surface normal by its hints (0: none); NULL without hints. The result's */
    int32_t grain_hinted_panels;     /* panels with an axis of their own */
    /* the panels and the pattern */
    const char *panels_source;       /* "segmentation", "file", "uv", "files", "groups", "components" (static) */
    pz_pattern *pattern;             /* the cut garment: panels, seams, darts (param/param.h) */
    double *uv;                      /* pattern->mesh->vertex_count x 2: the pieces laid out side by side */
    int layout_moved;                /* 1: the pieces were moved apart after flattening */
    char **panel_names;              /* pattern->panel_count entries (may be NULL), or NULL */
    int32_t *panel_mirror;           /* pattern->panel_count: the mirror-image panel (itself, -1 none), or NULL */
    pz_backend_outcome backend;
    /* metrics and verdict */
    pz_metrics **metrics;            /* metrics_count: the rest pose, then every extra pose */
    int metrics_count;
    pz_verdict verdict;
    /* the layout on the 3D garment: seams and darts as polylines of garment vertices */
    int32_t layout_curve_count;
    int32_t *layout_offsets;         /* layout_curve_count + 1 */
    int32_t *layout_vertices;        /* curve i: layout_vertices[layout_offsets[i] .. layout_offsets[i+1]-1] */
    uint8_t *layout_is_dart;         /* layout_curve_count: 1 for a dart (tip first, then leg a) */
    /* pz_run only (NULL otherwise) */
    pz_segment_result *segment;      /* the automatic layout: symmetry, panels, darts, counts */
    pz_prepare_result *prepared;     /* the automatic preparation's report (its mesh moved to `garment`) */
    pz_truing_result truing;
    int truing_dropped;              /* 1: the trued seams missed the goals and the layout was flattened untrued */
    int32_t field_singularities;
    int32_t verdict_rounds;          /* layouts made again because the joint flattening rejected panels */
    int32_t vetoed_panels;
    int32_t looser_settings;         /* looser goal settings laid out first (monotone panel counts) */
    int32_t looser_most_panels;
    int looser_seeded;
    double looser_reachable_strain;  /* the strictest S among them whose layout met every goal (at the run's C); <= 0: none */
    int32_t looser_reachable_panels; /* that layout's panels */
    double looser_written_strain;    /* > 0: the run's S was out of reach with sound pieces, and the layout of this
                                        looser S (the reachable one) is the one written (docs/run.md) */
    int looser_direct;               /* 1: the run's S was shown out of reach (the outlook, then a layout that stopped
                                        with looser_probe_panels panels) and the looser settings were laid out each
                                        on its own from the outlook's suggestion up (docs/run.md, "Impossible goals") */
    int32_t looser_probe_panels;
    int32_t consolidated_from;       /* > 0: the layout first made had this many pieces; the run made it again with
                                        a budget of one fewer, and that pattern met every goal (docs/run.md,
                                        "Consolidation") */
    pz_strain_outlook outlook;       /* can S be met: taken before the segmentation */
    int tradeoff_measured;           /* 1: pl_measure_tradeoff ran (or deferred extras were completed) */
    pz_segment_tradeoff tradeoff;    /* the final layout's merge sequence (count 0: not measured): the pieces each
                                        strain goal needs (pz_tradeoff_pieces; docs/run.md, "The trade-off") */
    double pattern_mirror_rms_mm;    /* mirror symmetry of the flattened pieces; -1 when not measured */
    double pattern_mirror_max_mm;
    /* The mirror plane (docs/segment.md, "Symmetry"): found or given before the field (its figures only: the
     * maps are NULL; the layout's own copy is segment->symmetry), whether the layout used it, and the panel
     * counts of the first layouts with and without it (-1: not made). */
    pz_symmetry symmetry;
    int symmetry_used;
    int symmetrized;                 /* 1: laid out on the garment made exactly symmetric (garment.obj is it) */
    double symmetrized_max_mm;       /* the input's vertices' distance to it: largest, 95th percentile (-1) */
    double symmetrized_p95_mm;
    int symmetry_rejected;           /* the joint flattening rejected the mirrored layout: made without the plane */
    int field_reused;                /* 1: the plane and cross-field came from options.cache (a run before) */
    int symmetry_sketch_asymmetric;  /* the plane was found and not used: the designer's sketch is not symmetric
                                        about it (options.mirror_sketch mirrors it) */
    int32_t pieces_with_symmetry, pieces_without_symmetry;
    int32_t mirror_pieces;           /* mirror pairs and panels crossed by the plane in the final layout */
    int32_t exact_mirror_pieces;     /* those made exact mirror images (docs/segment.md, "Exact mirror pieces") */
    double *panel_mirror_residual_mm; /* pattern->panel_count: the largest outline residual of each panel's mirror
                                         pair (or of itself, crossed by the plane), -1 none; or NULL */
    /* export */
    char *garment_name;              /* the name on the pieces (options.output.garment_name points here when the
                                        options named none: the input's base name) */
    double *seam_allowances;         /* pattern->seam_count, from allowances_path, or NULL */
    pz_pieces *pieces;               /* sew and cut lines, notches, labels */
    pz_marker *marker;               /* the pieces nested on the fabric */
    pz_timings timings;
} pz_result;

/**
 * The automatic pipeline: `garment` as read (in its file's units,
 * options->units says which; extra poses attached), options from
 * pz_run_options_default (NULL: the defaults). With options->panels set the
 * user's panels replace the segmentation (and preparation), and the goals
 * are still judged. On success *out is a new result; PZ_ERR_CANCELLED when
 * ctx->cancel was set; other errors as the stages report them, *out NULL.
 */
pz_status pz_run(const pz_mesh *garment, const pz_run_options *options, pz_result **out, pz_ctx *ctx);

/**
 * Flattens the user's panels (`panels` NULL: PZ_PANELS_GROUPS; options->panels
 * is not used): no preparation, no segmentation, no goal verdict
 * (result->verdict.judged is 0). Ownership as pz_run; the goals are not used.
 */
pz_status pz_flatten(const pz_mesh *garment, const pz_panels *panels, const pz_run_options *options,
                     pz_result **out, pz_ctx *ctx);

/** Frees a result and everything in it; accepts NULL and *result == NULL; sets *result = NULL. */
void pz_result_free(pz_result **result);

/* ------------------------------------------------------------------------ */
/* Files                                                                     */
/* ------------------------------------------------------------------------ */

/** The files pz_result_write can write (a bit set). */
typedef enum pz_output_file {
    PZ_OUTPUT_GARMENT_OBJ = 1u << 0,   /* garment.obj: the garment with the pattern as vt */
    PZ_OUTPUT_SVG = 1u << 1,           /* pattern.svg */
    PZ_OUTPUT_PDF = 1u << 2,           /* pattern.pdf (one 1:1 sheet) */
    PZ_OUTPUT_TILED_PDF = 1u << 3,     /* pattern-tiled.pdf (A4/Letter pages) */
    PZ_OUTPUT_DXF = 1u << 4,           /* pattern.dxf (AAMA/ASTM) */
    PZ_OUTPUT_MARKER = 1u << 5,        /* marker.svg */
    PZ_OUTPUT_GLB = 1u << 6,           /* garment.glb */
    PZ_OUTPUT_REPORT_JSON = 1u << 7,   /* report.json */
    PZ_OUTPUT_REPORT_HTML = 1u << 8,   /* report.html */
    PZ_OUTPUT_LAYOUT_OBJ = 1u << 9,    /* layout.obj (pz_run only) */
    PZ_OUTPUT_ENERGY_SVG = 1u << 10,   /* energy.svg (springmass only) */
    PZ_OUTPUT_ALL = 0x7ffu             /* every file that applies to the result */
} pz_output_file;

/**
 * Parses a comma-separated list of output names ("svg,dxf,json"; the names
 * are obj, svg, pdf, tiled, dxf, marker, glb, json, html, layout, energy,
 * all) into *outputs. PZ_ERR_USAGE naming the unknown word.
 */
pz_status pz_outputs_parse(const char *list, unsigned *outputs, pz_ctx *ctx);

/**
 * What pz_run deferred (pz_run_options.defer_extras) made now: the trade-off curve (result->tradeoff) and
 * the marker (result->marker, docs/marker.md); each at most once, PZ_OK at once when both are there (or do
 * not apply). Not safe to call on one result from two threads at once (the caller locks).
 */
pz_status pz_result_complete(pz_result *result, pz_ctx *ctx);

/**
 * Writes the chosen files of a result into `folder` as one unit: the files
 * are written and synced into a hidden folder beside it, with the marker
 * `.panelize` last, which then replaces `folder` whole (created when missing;
 * an earlier panelize output is exchanged atomically and its files removed;
 * a folder of other files is refused, see pz_output_folder_check). On failure
 * or cancellation the earlier folder is left as it was and nothing new stays
 * behind; writers into one parent take turns. What pz_run deferred is made first (pz_result_complete).
 * Files that do not apply (layout.obj of pz_flatten, energy.svg of
 * another back-end) are skipped. *report_text (may be NULL) receives
 * report.json's text (malloc'd, the caller frees) when it was written.
 */
pz_status pz_result_write(pz_result *result, const char *folder, unsigned outputs, char **report_text,
                          pz_ctx *ctx);

/**
 * Whether `folder` can receive a result, before any work: it is missing (its
 * nearest existing ancestor a writable directory), empty, or an earlier
 * panelize output (it holds the marker `.panelize`). A file, a folder of
 * someone else's files or a read-only place is PZ_ERR_CREATE naming it.
 */
pz_status pz_output_folder_check(const char *folder, pz_ctx *ctx);

/** report.json's content as a cJSON tree (the caller deletes it); NULL when out of memory. */
cJSON *pz_result_report(const pz_result *result);

/* ------------------------------------------------------------------------ */
/* Input files besides the mesh (docs/flatten.md)                            */
/* ------------------------------------------------------------------------ */

/**
 * A panels file: one integer panel id per line, one line per face (blank
 * lines at the end are ignored). Ids must be 0..K-1 with every id used.
 * Writes face_count ids to face_panel and K to *panel_count. PZ_ERR_OPEN when
 * unreadable, PZ_ERR_DATA naming the file and line otherwise.
 */
pz_status pz_read_panel_file(const char *path, int32_t face_count, int32_t *face_panel, int32_t *panel_count,
                             pz_ctx *ctx);

/**
 * How the vertex ids of seam and dart files map to the mesh's vertices: with
 * one mesh file, ids are that file's; with several panel files joined,
 * panel K's ids are local to its file, which starts at vertex
 * file_vertex_offset[K] of the joined mesh.
 */
typedef struct pz_vertex_space {
    int32_t file_count;
    const int32_t *file_vertex_offset;  /* file_count + 1 */
    const uint8_t *vertex_used;         /* file_vertex_offset[file_count]: 1 when a face uses the vertex
                                           (may be NULL: not checked) */
    int32_t panel_count;                /* panel ids in the files must be below this */
} pz_vertex_space;

/**
 * A seam file: line 1 panel of side A, line 2 panel of side B, then `a b`
 * vertex pairs (a on panel A, b on panel B). Fills `seam` with the joined
 * mesh's vertex ids (side_a/side_b malloc'd, freed by
 * pz_correspondences_clear or by the caller). PZ_ERR_DATA names the file and line.
 */
pz_status pz_read_seam_file(const char *path, const pz_vertex_space *space, pz_seam *seam, pz_ctx *ctx);

/**
 * A dart given as `FILE` or `K:FILE`: line 1 the tip vertex, then `p q`
 * pairs facing each other on the two legs. The panel K comes from the `K:`
 * prefix or from a file name `patch_K_dart_J...`; with several panel files
 * it is required (PZ_ERR_USAGE when it cannot be told).
 */
pz_status pz_read_dart_file(const char *spec, const pz_vertex_space *space, pz_dart *dart, pz_ctx *ctx);

/**
 * Every seam file (pz_read_seam_file) and dart spec (pz_read_dart_file) in
 * order into *out (emptied first; its arrays the caller's, freed with
 * pz_correspondences_clear also on failure). The first failure stops and is
 * returned.
 */
pz_status pz_read_correspondences(const char *const *seam_paths, int seam_count, const char *const *dart_specs,
                                  int dart_count, const pz_vertex_space *space, pz_correspondences *out,
                                  pz_ctx *ctx);

/**
 * Points the panels' seams and darts at what pz_read_correspondences read
 * (still owned by `read`), named after `name` (the first file) in messages.
 */
void pz_panels_use_correspondences(pz_panels *panels, const pz_correspondences *read, const char *name);

/** Sets used[v] = 1 for every vertex a face of `mesh` names (used: vertex_count bytes, zeroed by the caller). */
void pz_mesh_mark_used_vertices(const pz_mesh *mesh, uint8_t *used);

/**
 * Joins meshes one after another without welding: label K = part K (named
 * after names[K]'s base name), so PZ_PANELS_LABELS makes part K panel K.
 * vertex_offset (count + 1) receives where each part's vertices start.
 */
pz_status pz_mesh_join(pz_mesh *const *parts, const char *const *names, int32_t count, pz_mesh **out,
                       int32_t *vertex_offset, pz_ctx *ctx);

#ifdef __cplusplus
}
#endif

#endif /* PZ_PIPELINE_H */

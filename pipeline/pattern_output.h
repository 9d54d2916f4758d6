/*
 * pipeline/pattern_output.h -- what `panelize flatten` reads besides the mesh
 * (panel files, seam and dart files) and what it writes (garment.obj with the
 * pattern as vt, pattern.svg, report.json). Shared by cmd_flatten.c and
 * pattern_output.c only; the formats are described in docs/flatten.md.
 *
 * SPDX-License-Identifier: GPL-3.0-or-later
 */
#ifndef PZ_PATTERN_OUTPUT_H
#define PZ_PATTERN_OUTPUT_H

#include "export/export.h"
#include "param/param.h"
#include "pipeline/cli.h"

/* ---------------------------------------------------------------- readers */

/**
 * A panels file: one integer panel id per line, one line per face (blank
 * lines at the end are ignored). Ids must be 0..K-1 with every id used.
 * Writes face_count ids to face_panel and K to *panel_count. PZ_ERR_OPEN when
 * unreadable, PZ_ERR_DATA naming the file and line otherwise.
 */
pz_status pz_flatten_read_panel_file(const char *path, int32_t face_count, int32_t *face_panel,
                                     int32_t *panel_count, pz_ctx *ctx);

/**
 * How the vertex ids of seam and dart files map to garment vertices. With one
 * input file (file_count 1) ids are the file's vertex ids; with several
 * panel files, ids are local to panel K's file, which starts at raw vertex
 * file_vertex_offset[K] of the concatenation. raw_to_garment maps raw ids to
 * the prepared garment's vertices (-1: dropped as unreferenced).
 */
typedef struct pz_vertex_space {
    int32_t file_count;
    const int32_t *file_vertex_offset;  /* file_count + 1 */
    const int32_t *raw_to_garment;      /* file_vertex_offset[file_count] */
    int32_t panel_count;                /* panel ids in the files must be below this */
} pz_vertex_space;

/**
 * A seam file: line 1 panel of side A, line 2 panel of side B, then `a b`
 * vertex pairs (a on panel A, b on panel B). Fills `seam` with garment
 * vertex ids (caller frees side_a/side_b, also through
 * pz_correspondences_clear). PZ_ERR_DATA names the file and line.
 */
pz_status pz_flatten_read_seam(const char *path, const pz_vertex_space *space, pz_seam *seam, pz_ctx *ctx);

/**
 * A dart given as `FILE` or `K:FILE`: line 1 the tip vertex, then `p q`
 * pairs facing each other on the two legs. The panel K comes from the `K:`
 * prefix or from a file name `patch_K_dart_J...`; with several panel files
 * it is required (PZ_ERR_USAGE when it cannot be told).
 */
pz_status pz_flatten_read_dart(const char *spec, const pz_vertex_space *space, pz_dart *dart, pz_ctx *ctx);

/** Feature curves read from a --features file (points in mm). */
typedef struct pz_feature_file {
    int32_t curve_count;
    pz_feature_polyline *polylines;   /* curve_count; points point into `points` */
    double *points;                   /* every curve's points, x 3 */
} pz_feature_file;

/**
 * A features file: JSON {"curves":[{"kind":"key"|"accessory","points":
 * [[x,y,z],...]}]} with at least one curve of at least two points, in the
 * input's units; mm_per_unit converts to millimetres like the mesh.
 * PZ_ERR_OPEN when unreadable; PZ_ERR_DATA naming the file and the line (not
 * JSON) or the curve and point (wrong shape) otherwise.
 */
pz_status pz_flatten_read_features(const char *path, double mm_per_unit, pz_feature_file *out, pz_ctx *ctx);
void pz_feature_file_clear(pz_feature_file *features);

/* ---------------------------------------------------------------- layout and writers */

/**
 * When the bounding boxes of two panels overlap, translates every panel into
 * rows (shelves, tallest first, rows about as wide as the whole layout is
 * tall) with gap_mm between pieces; a layout without overlaps is kept as the
 * back-end made it. uv is pattern->mesh->vertex_count x 2, changed in place.
 * Sets *moved.
 */
pz_status pz_pattern_layout(const pz_pattern *pattern, double *uv, double gap_mm, int *moved, pz_ctx *ctx);

/**
 * garment.obj: `v` = positions (garment vertex_count x 3, written as given),
 * `vt` = uv of every cut-mesh vertex, faces = the garment's faces in order
 * with the vt of the cut-mesh corner, `g panel_K` whenever the panel changes.
 */
pz_status pz_pattern_write_obj(FILE *file, const pz_mesh *garment, const double *positions,
                               const pz_pattern *pattern, const double *uv, pz_ctx *ctx);

/**
 * pattern.svg at 1:1 in millimetres: one <g id="panel_K"> per panel with its
 * triangle edges (light), outline (closed boundary loops), grainline arrow
 * along +v through the piece's centroid and the piece name. panel_names
 * (panel_count, entries may be NULL) are shown next to "panel_K".
 */
pz_status pz_pattern_write_svg(FILE *file, const pz_pattern *pattern, const double *uv,
                               const char *const *panel_names, pz_ctx *ctx);

/** A --features curve left out of the flattening (not on the mesh, across panels, ...): index in the file, why. */
typedef struct pz_skipped_feature {
    int32_t curve;
    char problem[256];
} pz_skipped_feature;

/** Everything report.json says besides the metrics. */
typedef struct pz_flatten_report {
    const char *const *input_paths;
    int input_count;
    int32_t vertices, faces, poses;
    const char *units;            /* the input's units ("mm", "cm", "m") */
    int units_guessed;
    const char *panels_source;    /* "file", "uv", "files", "groups", "components" */
    const char *backend;          /* "textile", "lscm", "wirewarp" or "springmass" */
    int iterations;
    double weights[4];            /* stretch, rigid, dart, seam */
    pz_fabric fabric;             /* the constants used */
    double grain[3];
    const char *grain_source;     /* "given", "vertical axis (y)", "vertical axis (z)" */
    const pz_textile_result *textile;  /* textile only, else NULL */
    const pz_wirewarp_result *wirewarp;  /* wirewarp only, else NULL */
    int progressive;              /* wirewarp: --scheme progressive */
    int32_t feature_count;        /* wirewarp: curves from --features that were used */
    const pz_skipped_feature *skipped_features;  /* wirewarp: the curves left out, skipped_feature_count */
    int32_t skipped_feature_count;
    const pz_springmass_result *springmass;  /* springmass only, else NULL */
    int relax_full;               /* springmass: --relax full */
    int orthotropic;              /* springmass: --fabric given */
    double backend_ms;            /* the back-end's own run, before layout */
    const double *uv;             /* the pattern (cutting lines' 2D points) */
    int layout_moved;
    double timings_ms[6];         /* read, pattern, flatten, metrics, write, total */
    const pz_pattern *pattern;
    const pz_metrics *const *metrics;  /* metrics_count: rest pose first, then each extra pose */
    int metrics_count;
    const char *const *panel_names;
} pz_flatten_report;

/** Builds report.json (docs/flatten.md); NULL when out of memory. */
cJSON *pz_flatten_report_json(const pz_flatten_report *report);

/* ---------------------------------------------------------------- the shared command */

/** An extra file a command adds to flatten's outputs (layout.obj for run). */
typedef struct pz_flatten_extra_file {
    const char *name;
    pz_status (*write)(void *user, FILE *file, const pz_pattern *pattern, pz_ctx *ctx);
} pz_flatten_extra_file;

/**
 * What `panelize run` changes in the flatten command (cmd_run.c): where the
 * panels come from when --panels is not given (the automatic layout), what
 * report.json gains, which extra files are written. Every pointer may be
 * NULL/0; `flatten` itself passes no extension.
 */
typedef struct pz_flatten_extension {
    void *user;
    /* Called on the freshly read garment (mm, not yet validated): may replace *mesh by a prepared one
     * (run --prepare auto); sets *changed when it did, so vertex ids of the input no longer apply. */
    pz_status (*prepare_mesh)(void *user, pz_mesh **mesh, int *changed, pz_ctx *ctx);
    /* Panels for a garment without --panels: face_panel (face_count, malloc'd, the caller frees),
     * *panel_count, *extra_cuts (edge flags over pz_topology_build(garment), malloc'd or NULL). */
    /* May move vertices along the surface (seam truing: connectivity, face order and units unchanged);
     * called again after accept_pattern said no, on the garment as the previous call left it. */
    pz_status (*choose_panels)(void *user, pz_mesh *garment, int32_t **face_panel, int32_t *panel_count,
                               uint8_t **extra_cuts, pz_ctx *ctx);
    const char *panels_source;           /* report's panels.source for choose_panels ("segmentation") */
    /* Called after each flattening of the panels choose_panels gave, with its pattern points (uv, 2 per
     * pattern vertex, borrowed) and rest-pose metrics: 1 accepts the pattern; 0 asks for choose_panels
     * again (the extension remembers why and bounds the rounds). */
    int (*accept_pattern)(void *user, const pz_pattern *pattern, const double *uv, const pz_metrics *metrics);
    double strain_limit;                 /* the textile back-end's strain goal (run: --max-strain), 0 = none */
    /* Called once the pattern exists, before any export: the mirror panel of each panel (may return NULL)
     * and the layout curves as garment vertex polylines for garment.glb (may leave them empty). */
    const int32_t *(*panel_mirror)(void *user, const pz_pattern *pattern);
    void (*layout_curves)(void *user, const pz_pattern *pattern, const int32_t **vertices, const int32_t **offsets,
                          int32_t *count);
    /* Adds the command's own keys to report.json (root) and to the text summary; uv are the final
     * pattern points (2 per pattern vertex, pieces laid out side by side, borrowed). */
    int (*extend_report)(void *user, cJSON *root, const pz_mesh *garment, const pz_pattern *pattern,
                         const double *uv, const pz_metrics *metrics);
    void (*print_summary)(void *user);
    int32_t extra_file_count;
    const pz_flatten_extra_file *extra_files;
} pz_flatten_extension;

/**
 * The flatten pipeline shared by `flatten` and `run`: read, panels, pattern,
 * back-end, metrics, pieces and marker, all files written all-or-nothing.
 * extension may be NULL (plain `flatten`).
 */
pz_status pz_flatten_execute(const pz_cli_args *args, const pz_flatten_extension *extension, pz_ctx *ctx);

/**
 * The flattening `flatten` would make of pattern with the options in args (--backend textile or lscm;
 * wirewarp and springmass are replaced by textile), grain from --grain or garment's vertical axis,
 * textile strain goal strain_limit (0 = none): for `run`, which judges looser goal settings on their own
 * patterns. Writes uv (2 per pattern vertex, the caller's; NULL: only *fabric) and *fabric (--fabric or
 * the defaults, may be NULL).
 */
pz_status pz_flatten_pattern_like_cli(const pz_cli_args *args, const pz_mesh *garment, const pz_pattern *pattern,
                                      double strain_limit, double *uv, pz_fabric *fabric, pz_ctx *ctx);

#endif /* PZ_PATTERN_OUTPUT_H */

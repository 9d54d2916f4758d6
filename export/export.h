/*
 * export/export.h -- the export stage: a flattened pattern becomes files for
 * the cutting table (pieces with sew and cut lines, notches, grainlines,
 * darts), for CAD tools (DXF-AAMA), printers (PDF, tiled PDF), viewers (GLB)
 * and people (report.html), plus a marker (the pieces nested on the fabric).
 *
 *   pz_pieces_build        pattern + uv -> pieces (outline, allowance, notches, ...)
 *   pz_marker_build        pieces -> placement on a fabric of a given width
 *   pz_export_write_*      one writer per file, each to an open FILE *
 *   pz_export_files[]      the table of the files `flatten` and `run` write
 *
 * Writers take an open stream: the command opens every file through
 * pz_output_open (a temporary) and renames all of them only when all are
 * complete (all or nothing), so a writer never creates files itself.
 * All lengths are millimetres in the pattern plane (x = u, y = v; v is the
 * warp). Docs: docs/export.md (pieces, allowance, notches, formats),
 * docs/marker.md (nesting).
 *
 * SPDX-License-Identifier: GPL-3.0-or-later
 */
#ifndef PZ_EXPORT_H
#define PZ_EXPORT_H

#include "param/param.h"

#include <cjson/cJSON.h>
#include <stdio.h>

#ifdef __cplusplus
extern "C" {
#endif

/* ------------------------------------------------------------------------ */
/* Pieces                                                                    */
/* ------------------------------------------------------------------------ */

/** A notch: a short cut into the allowance, perpendicular to the sew line. */
typedef struct pz_notch {
    double position[2];          /* on the sew line */
    double direction[2];         /* unit, pointing outward (into the allowance) */
    double arc_mm;               /* arc length from the seam's start along this piece's side */
    int32_t seam;                /* pattern seam index, or -1 for a dart notch */
    int32_t dart;                /* pattern dart index, or -1 */
    char label[16];              /* "A1": the same on both partners of a seam */
    double cut_point[2];         /* where the ray from position along direction meets the cut line */
    double depth_mm;             /* notch length, drawn from cut_point inward (-direction):
                                    min(notch_depth_mm, the local allowance) */
} pz_notch;

/** An internal line drawn on a piece (dart legs, the dart's fold line). */
typedef struct pz_piece_line {
    int32_t point_count;
    double *points;              /* point_count x 2 */
} pz_piece_line;

/** One pattern piece (one panel). Owned by pz_pieces. */
typedef struct pz_piece {
    int32_t panel;
    char name[48];               /* "panel_K" or the given name */
    int32_t cut_quantity;        /* 1, or 2 ("Cut 2 mirrored") for the first piece of a mirrored pair */
    int32_t mirror_piece;        /* index of the piece that is its mirror image (-1 none) */
    int mirrored;                /* 1: the second of a mirrored pair: its partner carries "Cut 2 mirrored",
                                    so SVG/PDF/DXF/marker do not draw it on its own */
    int32_t sew_count;
    double *sew;                 /* sew_count x 2: the sew line, closed, counter-clockwise (outer loop) */
    int32_t *sew_vertex;         /* sew_count: the cut-mesh vertex of each sew point */
    double *sew_allowance;       /* sew_count: allowance of the edge sew[i] -> sew[i+1] (seam or hem) */
    int32_t cut_count;
    double *cut;                 /* cut_count x 2: the cut line, closed, counter-clockwise */
    int32_t notch_count;
    pz_notch *notches;
    int32_t line_count;
    pz_piece_line *lines;        /* dart legs and fold lines */
    double grain[2][2];          /* grainline arrow: tail, head (along +v) */
    int on_fold;                 /* 1: drawn as its half, to be cut on the fold (pz_export_options.fold) */
    double fold[2][2];           /* on_fold: the fold line's ends (the edge of the half without allowance) */
    double bbox_min[2], bbox_max[2]; /* of the cut line */
    double area_mm2;             /* area inside the cut line */
    double sew_area_mm2;         /* area inside the sew line */
} pz_piece;

typedef struct pz_pieces {
    int32_t piece_count;
    pz_piece *pieces;
    char garment_name[64];
    char size_name[32];
} pz_pieces;

/**
 * Before any work: whether a garment of `area_mm2` could be tiled at all on
 * `paper` ("a4", "letter" or NULL = a4). Every piece lies on the tiled sheet,
 * and flattening keeps a piece's area within its strain, so a garment of more
 * than twice the area of the most tiles pattern-tiled.pdf prints (20,000) is
 * PZ_ERR_DATA naming `name` and its area at once, rather than after the whole
 * computation (a garment read in the wrong units: 90 m tall).
 */
pz_status pz_export_check_tiled_area(double area_mm2, const char *paper, const char *name, pz_ctx *ctx);

/** Export options. pz_export_options_default fills the defaults. */
typedef struct pz_export_options {
    double seam_allowance_mm;    /* default 10 */
    double hem_allowance_mm;     /* open edges (not on a seam); < 0 (the default, -1) = seam_allowance_mm */
    const double *seam_allowances_mm; /* pattern->seam_count (may be NULL): per-seam allowance, < 0 = default
                                         (from --allowances FILE, pz_export_read_allowances) */
    double notch_spacing_mm;     /* default 100 */
    double notch_depth_mm;       /* default 5 (never deeper than the allowance) */
    const char *paper;           /* "a4" (default) or "letter" */
    int dxf_strict;              /* 1: no TABLES section, 7-bit ASCII only */
    double fabric_width_mm;      /* marker width; default 1500 */
    double gap_mm;               /* marker gap between pieces; default 5 */
    const char *garment_name;    /* default: the input's base name */
    const char *size_name;       /* default "base" */
    int fold;                    /* 1: a piece that is its own mirror image (panel_mirror[p] == p, symmetric within
                                    0.25 mm) is drawn as its half, cut on the fold (docs/export.md); default 0 */
} pz_export_options;

void pz_export_options_default(pz_export_options *options);

/** The cut instruction printed on a piece: "Cut 2 mirrored", "Cut 1 on fold" or "Cut 1" (static text). */
const char *pz_piece_cut_text(const pz_piece *piece);

/**
 * Reads a per-seam allowance file (--allowances FILE, format in
 * docs/export.md: one `PANEL_A PANEL_B MM` line per seam, `#` comments) into
 * *out (pattern->seam_count values, -1 where the file says nothing; caller
 * frees). PZ_ERR_OPEN when unreadable, PZ_ERR_DATA naming the file and line
 * (bad numbers, a panel pair with no seam, a negative allowance).
 */
pz_status pz_export_read_allowances(const char *path, const pz_pattern *pattern, double **out, pz_ctx *ctx);

/**
 * Builds every piece of a flattened pattern: sew line = the panel's outer
 * boundary in uv (the slits of darts included as their legs), cut line =
 * sew line offset outward by each edge's allowance (mitred corners, acute
 * corners cut off, never self-intersecting), notches at both ends of every
 * seam side and every notch_spacing_mm along it at equal arc length on both
 * partners, dart legs and tips as internal lines with notches, grainline,
 * areas. panel_mirror (panel_count, may be NULL): the mirror panel of each
 * panel (pz_segment_panel.mirror_panel): when two pieces are mirror images
 * in 2D as well (within 1 mm RMS), the first gets cut_quantity 2 and the
 * second mirrored = 1, and every seam reaching that hidden second piece
 * takes the labels of its mirror twin on the drawn side (so the mirrored
 * cut's notches match its partner's; docs/export.md). panel_names
 * (may be NULL, entries may be NULL). Caller frees with pz_pieces_free.
 * Piece i is panel i. The cut line closes every dart's V by the line across
 * its mouth (a folded dart: never cut into). Notches: cut_point and depth_mm
 * say where to draw them (from the cut line inward). Details and choices:
 * docs/export.md. PZ_ERR_USAGE for a negative allowance or depth or a
 * spacing <= 0, PZ_ERR_DATA for a panel without boundary or with fewer than
 * 3 distinct outline points, PZ_ERR_NOMEM; *out stays NULL on failure.
 */
pz_status pz_pieces_build(const pz_pattern *pattern, const double *uv, const pz_export_options *options,
                          const int32_t *panel_mirror, const char *const *panel_names, pz_pieces **out,
                          pz_ctx *ctx);
void pz_pieces_free(pz_pieces **pieces);

/**
 * One sheet for the drawn pieces (mirrored == 0), laid out in rows by their
 * cut-line boxes, tallest first, gap_mm apart and from the edges, below a
 * band of reserve_top_mm left free at the top (title, 10 cm scale box).
 * offsets (piece_count x 2, written): piece point (x, y) goes to (x +
 * offsets[2i], y + offsets[2i+1]) on the sheet, y up, inside [0, size[0]] x
 * [0, size[1]] (size written, mm). Mirrored pieces get offset 0. Writers that
 * draw y down use size[1] - y. Deterministic.
 */
void pz_pieces_sheet_layout(const pz_pieces *pieces, double gap_mm, double reserve_top_mm, double *offsets,
                            double size[2]);

/* ------------------------------------------------------------------------ */
/* Marker                                                                    */
/* ------------------------------------------------------------------------ */

typedef struct pz_marker_placement {
    int32_t piece;
    int32_t copy;                /* 0, or 1 for the second cut of a quantity-2 piece (drawn mirrored) */
    int rotation_deg;            /* 0 or 180 only: the grain stays true */
    int mirrored;                /* 1: placed mirrored (the second of a pair) */
    double offset[2];            /* translation applied after rotation / mirroring */
} pz_marker_placement;

typedef struct pz_marker {
    int32_t placement_count;
    pz_marker_placement *placements;
    double fabric_width_mm;
    double length_mm;            /* used length of the fabric */
    double efficiency;           /* sum of piece areas (cut lines) / (width x length) */
    double shortest_possible_mm; /* no marker of the placed pieces is shorter: the tallest piece (the grain keeps
                                  * them upright) or their area over the width, whichever is longer */
    double efficiency_bound;     /* the efficiency of a marker that short: what no nesting can pass */
    int32_t passes;              /* greedy placement passes the search ran (docs/marker.md) */
    double ms;                   /* time to build */
    int32_t unplaced_count;      /* pieces wider than the fabric in both turns: not in the marker */
    int32_t *unplaced;           /* unplaced_count piece indices */
} pz_marker;

/**
 * Nests every piece (each copy of its cut quantity) on a fabric of
 * fabric_width_mm along x, growing along y, rotations 0 or 180 degrees
 * only, the two copies of a Cut-2 piece side by side as a pair or each on its own, gap_mm between pieces (method in
 * docs/marker.md). A piece wider than the fabric (its cut line's width, the
 * same at 0 and 180 degrees) cannot be cut from it with the grain kept: it is
 * left out and listed in unplaced (the rest is still nested; the caller
 * warns). PZ_ERR_DATA for a non-finite cut-line coordinate, PZ_ERR_USAGE for
 * a fabric width that is not finite, PZ_ERR_NOMEM. Deterministic. Caller
 * frees with pz_marker_free.
 */
pz_status pz_marker_build(const pz_pieces *pieces, const pz_export_options *options, pz_marker **out, pz_ctx *ctx);
void pz_marker_free(pz_marker **marker);

/**
 * Places point_count points of `piece` (its cut or sew line, grainline, ...)
 * as `placement` does: x -> -x when mirrored, then a turn by rotation_deg
 * about the origin, then + offset. out: point_count x 2 (may be `points`).
 */
void pz_marker_place_points(const pz_piece *piece, const pz_marker_placement *placement, const double *points,
                            int32_t point_count, double *out);

/* ------------------------------------------------------------------------ */
/* Files                                                                     */
/* ------------------------------------------------------------------------ */

/** Everything a writer may need. Pointers are borrowed. */
typedef struct pz_export_inputs {
    const pz_mesh *garment;          /* the prepared garment (mm) */
    const double *positions;         /* garment vertex positions as given (for garment.obj) */
    const pz_pattern *pattern;
    const double *uv;                /* pattern->mesh->vertex_count x 2 */
    const pz_metrics *metrics;       /* rest pose */
    const pz_pieces *pieces;
    const pz_marker *marker;         /* may be NULL (then marker.svg is skipped) */
    const pz_export_options *options;
    const char *const *panel_names;  /* may be NULL */
    const cJSON *report;             /* report.json's content (report.html shows it) */
    const int32_t *layout_vertices;  /* may be NULL: seam polylines on the garment (garment vertex ids) ... */
    const int32_t *layout_offsets;   /* ... curve i = layout_vertices garment ids [offsets[i], offsets[i+1]) */
    int32_t layout_curve_count;
} pz_export_inputs;

typedef pz_status (*pz_export_writer)(FILE *file, const pz_export_inputs *inputs, const char *name, pz_ctx *ctx);

/** One file of the export: its name in the output directory and its writer. */
typedef struct pz_export_file {
    const char *name;                /* "pattern.svg" */
    pz_export_writer write;
    int binary;                      /* 1: open "wb" */
} pz_export_file;

/** The pattern files (not garment.obj or report.json, which the commands write). */
extern const pz_export_file pz_export_files[];
extern const int pz_export_file_count;

pz_status pz_export_write_svg(FILE *file, const pz_export_inputs *inputs, const char *name, pz_ctx *ctx);
pz_status pz_export_write_dxf(FILE *file, const pz_export_inputs *inputs, const char *name, pz_ctx *ctx);
pz_status pz_export_write_pdf(FILE *file, const pz_export_inputs *inputs, const char *name, pz_ctx *ctx);
pz_status pz_export_write_pdf_tiled(FILE *file, const pz_export_inputs *inputs, const char *name, pz_ctx *ctx);
pz_status pz_export_write_glb(FILE *file, const pz_export_inputs *inputs, const char *name, pz_ctx *ctx);
pz_status pz_export_write_marker_svg(FILE *file, const pz_export_inputs *inputs, const char *name, pz_ctx *ctx);
pz_status pz_export_write_report_html(FILE *file, const pz_export_inputs *inputs, const char *name, pz_ctx *ctx);

/** report.json's "marker" object {length_mm, efficiency, fabric_width_mm, pieces, ms}; NULL when out of memory. */
cJSON *pz_marker_report_json(const pz_marker *marker);

#ifdef __cplusplus
}
#endif

#endif /* PZ_EXPORT_H */

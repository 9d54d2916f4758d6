/*
 * export/notches.h -- private to export/: the steps of pz_pieces_build that
 * live in export/notches.c (seam and dart notches, dart lines).
 *
 * SPDX-License-Identifier: GPL-3.0-or-later
 */
#ifndef PZ_EXPORT_NOTCHES_H
#define PZ_EXPORT_NOTCHES_H

#include "export/export.h"

/* Where each cut-mesh vertex sits on its piece's sew line: loop_piece[v] (-1 off the outline), loop_index[v]. */
typedef struct pz_outline_map {
    const int32_t *loop_piece;
    const int32_t *loop_index;
} pz_outline_map;

/* A dart's mouth wider than this many allowances is cut out, not folded (docs/export.md). */
#define PZ_DART_FOLD_LIMIT 4.0

/* The outline position (loop index) of a dart's two mouth ends, -1 when the dart does not reach the outline. */
typedef struct pz_dart_mouth {
    int32_t piece;
    int32_t index_a, index_b;   /* sew indices: the outline runs index_a -> ... tip ... -> index_b */
    int folded;                 /* 1: the cut line closes the V across the mouth; 0: it follows the legs */
} pz_dart_mouth;

/* Finds the mouth of every dart (mouths: pattern->dart_count); needs the allowances assigned. */
void pz_pieces_find_dart_mouths(const pz_pattern *pattern, const pz_pieces *pieces, const pz_outline_map *map,
                                pz_dart_mouth *mouths);

/* The label of letter group `seam` (a seam's, or a mirror twin pair's: notches.c), notch `index` (0-based):
 * "A1", ..., "Z9", "AA1". */
void pz_notch_label(int32_t seam, int32_t index, char label[16]);

/*
 * Adds every seam's and dart's notches and every dart's internal lines to the
 * pieces. Needs the mirrored pairs found (mirror_piece, mirrored): a seam on
 * a hidden piece shares its label with its mirror twin on the drawn partner.
 * panel_mirror: as pz_pieces_build's (may be NULL).
 */
pz_status pz_pieces_add_notches(pz_pieces *pieces, const pz_pattern *pattern, const double *uv,
                                const pz_outline_map *map, const pz_dart_mouth *mouths, const int32_t *panel_mirror,
                                const pz_export_options *options, pz_ctx *ctx);

/* The sew edge joining outline vertices a and b (consecutive on one piece's outline), or -1. */
int32_t pz_outline_edge(const pz_pieces *pieces, const pz_outline_map *map, int32_t a, int32_t b);

/* Room for a drawn notch label: the labels of the notches at one place, "X5 I1". */
#define PZ_NOTCH_LABELS_MAX 48

/*
 * The notches as drawn: notches at the same place (the ends of two seams at a
 * corner, made from one sew vertex) are drawn once, with their labels joined
 * ("X5 I1") on the first of them; the others get "" and are not drawn.
 * labels: piece->notch_count. 0 when out of memory.
 */
int pz_piece_notch_labels(const pz_piece *piece, char (*labels)[PZ_NOTCH_LABELS_MAX]);

/* Outward unit normal of sew edge i (sew[i] -> sew[i+1]) of a piece. */
void pz_piece_edge_normal(const pz_piece *piece, int32_t i, double normal[2]);

#endif /* PZ_EXPORT_NOTCHES_H */

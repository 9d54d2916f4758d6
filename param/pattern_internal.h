/*
 * param/pattern_internal.h -- the state of one pz_pattern_build call, shared
 * by param/pattern.c (panel ids, cut flags, cutting every panel into a disk,
 * the entry points) and param/pattern_seams.c (seams and darts from the cut
 * edges, explicit correspondences mapped to the cut mesh). Not part of the
 * public interface; docs/pattern.md describes the algorithm.
 *
 * SPDX-License-Identifier: GPL-3.0-or-later
 */
#ifndef PZ_PARAM_PATTERN_INTERNAL_H
#define PZ_PARAM_PATTERN_INTERNAL_H

#include "param/param.h"

/* Everything pz_pattern_build makes on its way; builder_free (pattern.c) frees what is still held. */
typedef struct pattern_builder {
    const pz_mesh *garment;
    const int32_t *face_panel;
    const char *path;
    int32_t panel_count;
    pz_topology *topology;      /* of the garment */
    uint8_t *cut;               /* garment edge flags */
    uint8_t *explicit_edge;     /* garment edges taken by explicit seams or darts */
    int32_t *vertex_edge_offsets; /* garment vertex -> its edges (CSR, every edge) */
    int32_t *vertex_edges;
    /* after the final cut */
    pz_mesh *cut_mesh;
    int32_t *vertex_origin;
    pz_topology *cut_topology;
    int32_t *vertex_panel;      /* cut-mesh vertex -> panel (-1: unused) */
    int32_t *copy_offsets;      /* garment vertex -> its copies (CSR) */
    int32_t *copies;
    pz_seam *seams;
    int32_t seam_count;
    size_t seam_capacity;
    pz_dart *darts;
    int32_t dart_count;
    size_t dart_capacity;
} pattern_builder;

/* PZ_ERR_NOMEM naming the pattern's path. */
pz_status pattern_no_memory(pattern_builder *b, pz_ctx *ctx);
/* The garment edge between vertices u and v, or -1. */
int32_t pattern_find_edge(const pattern_builder *b, int32_t u, int32_t v);

/* pattern_seams.c, run after the final cut (b->cut_mesh, cut_topology, vertex_panel set): */
/* Garment vertex -> its copies on the cut mesh (copy_offsets, copies). */
pz_status pattern_index_copies(pattern_builder *b, pz_ctx *ctx);
/* Step 6: the given seams and darts (garment vertex ids) as copies; their edges leave the automatic seams. */
pz_status pattern_map_explicit(pattern_builder *b, const pz_correspondences *given, pz_ctx *ctx);
/* Step 5: seams (and slit darts) from the chains of cut edges not taken by explicit ones. */
pz_status pattern_find_automatic_seams(pattern_builder *b, pz_ctx *ctx);

#endif

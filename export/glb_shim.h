/*
 * export/glb_shim.h -- private to export/: the GLB writer for a coloured,
 * textured garment with seam lines (garment.glb, export/glb.c), behind plain
 * C. The function lives in export/glb_shim.cpp (tinygltf stays in that one
 * C++ file of export); only C types cross this header.
 *
 * SPDX-License-Identifier: GPL-3.0-or-later
 */
#ifndef PZ_EXPORT_GLB_SHIM_H
#define PZ_EXPORT_GLB_SHIM_H

#include "mesh/mesh.h"

#include <stdint.h>
#include <stdio.h>

#ifdef __cplusplus
extern "C" {
#endif

/** A garment to write as GLB. Arrays are borrowed. */
typedef struct pz_glb_garment {
    int32_t vertex_count;
    const double *positions;      /* vertex_count x 3 (mm) */
    const int32_t *vertex_group;  /* vertex_count: colour index of each vertex, >= 0 (0-11: the palette of
                                     pz_glb_label_color, io/io.h; above: hues a golden angle apart) */
    const double *texcoords;      /* vertex_count x 2, panelize's convention (v up; flipped for glTF), or NULL */
    int32_t face_count;
    const int32_t *faces;         /* face_count x 3 */
    int32_t line_point_count;
    const double *line_points;    /* line_point_count x 3: the seams' vertices (mm, written in metres) */
    int32_t line_index_count;     /* even: pairs of line_points indices, one segment each */
    const int32_t *line_indices;
    const char *name;             /* mesh and node name */
} pz_glb_garment;

/**
 * Writes `garment` as GLB to an open stream: one mesh with a TRIANGLES
 * primitive (POSITION in metres, glTF's unit: the millimetres given x 0.001,
 * with min/max; NORMAL (area-weighted), COLOR_0 = the colour of vertex_group,
 * stored linear,
 * TEXCOORD_0 when given) under a white double-sided material, and a LINES
 * primitive for the seams (when line_index_count > 0) under a dark one.
 * `what` names the output in messages. Errors: PZ_ERR_INVALID_MESH for
 * indices out of range or non-finite coordinates, PZ_ERR_CREATE when the
 * stream fails, PZ_ERR_NOMEM.
 */
pz_status pz_glb_write_garment(const pz_glb_garment *garment, FILE *file, const char *what, pz_ctx *ctx);

#ifdef __cplusplus
}
#endif

#endif /* PZ_EXPORT_GLB_SHIM_H */

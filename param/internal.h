/*
 * param/internal.h -- what the flattening back-ends share and the library's
 * users do not see: the local frame of a face, faces grouped by panel, the
 * side-by-side layout of pieces, CHOLMOD's symbolic analysis with our
 * fill-reducing ordering and its numeric factorization without an OpenMP
 * team (all in param/lscm.c), and the geometric untangling of flipped faces
 * (param/wirewarp_layout.c). Included by the .c files of param/ only; never by another
 * stage (their interface is param/param.h).
 *
 * Each back-end that spans several files has its own private header on top
 * of this one: param/textile_internal.h, param/wirewarp_internal.h,
 * param/springmass_internal.h.
 *
 * SPDX-License-Identifier: GPL-3.0-or-later
 */
#ifndef PZ_PARAM_INTERNAL_H
#define PZ_PARAM_INTERNAL_H

#include "param/param.h"

#include <math.h>

#include <cholmod.h>

/* Local frame of face `face` (3 vertex ids into pos, n x 3): the 2D coordinates
 * of corners 1 and 2 (corner 0 at the origin), written to local[0..2] = x1,
 * x2, y2, and the frame axes e1, e2 (each 3). Returns the area (0 for a
 * degenerate face). */
double pz_param_face_frame(const double *pos, const int32_t *face, double local[3], double e1[3], double e2[3]);

/* The rotation angle (radians, counter-clockwise) that turns the
 * area-weighted projected grain of the given faces (face_ids may be NULL: the
 * first face_count faces), each turned by `turn` about its face normal (0:
 * the projected grain itself), onto +v; 0 when the grain is nearly normal to
 * all of them. */
double pz_param_grain_angle(const pz_mesh *mesh, const int32_t *face_ids, int32_t face_count, const double grain[3],
                            double turn, const double *uv);

/* (a, b), a direction in a face's frame (e1, e2) (pz_param_face_frame: (e1, e2, n) right-handed), turned by
 * `turn` radians about the face normal: a grain hint's turn of the warp (pz_textile_options.panel_grain_turn). */
static inline void pz_param_turn_in_frame(double turn, double *a, double *b)
{
    if (turn == 0 || !isfinite(turn))
        return;
    double c = cos(turn), s = sin(turn), turned = c * *a - s * *b;
    *b = s * *a + c * *b;
    *a = turned;
}

/* Rotates the uv of the listed vertices by `angle` about their centroid. */
void pz_param_rotate_vertices(const int32_t *vertex_ids, int32_t vertex_count, double angle, double *uv);

/* Faces bucketed by panel: faces of panel p are (*order)[(*offsets)[p] ..
 * (*offsets)[p+1] - 1]. Both arrays are the caller's to free. */
pz_status pz_param_panel_faces(const pz_pattern *pattern, int32_t **offsets, int32_t **order, pz_ctx *ctx);

/* Places the pieces on shelves with a 20 mm gap (param/lscm.c's header). */
void pz_param_layout(const pz_pattern *pattern, const int32_t *offsets, const int32_t *order, double *uv);

/* CHOLMOD's symbolic analysis of a symmetric matrix whose unknown k sits at
 * positions[3 * vertex_of[k]] (vertex_of may be NULL: CHOLMOD's default
 * ordering): nested dissection or AMD, whichever fills less, from 8000
 * unknowns on. `refactorized`: the matrix will be factorized many times (the
 * textile's), so below PZ_METIS_MAX_UNKNOWNS METIS is tried too (a slower
 * ordering that pays back over the factorizations and solves). The ordering
 * depends on the sparsity pattern and, from 8000 unknowns on, the positions:
 * a factor analyzed once serves every matrix of that pattern. Returns the
 * symbolic factor or NULL (common->status says why). */
#define PZ_METIS_MAX_UNKNOWNS 50000
cholmod_factor *pz_param_analyze(cholmod_sparse *matrix, const double *positions, const int32_t *vertex_of,
                                 int refactorized, cholmod_common *common);

/* The symbolic analysis of a matrix whose unknown k is vertex vertex_of[k], in the order `vertex_rank` gives
 * (vertex_rank[v]: when v was eliminated in an earlier factorization of the same mesh's adjacency, the LSCM
 * start's; unknowns whose vertex has no rank, e.g. its pins, last): no ordering searched again. NULL when out of
 * memory (common->status). */
cholmod_factor *pz_param_analyze_ranked(cholmod_sparse *matrix, const int32_t *vertex_of, const int32_t *vertex_rank,
                                        cholmod_common *common);

/* pz_param_lscm_pattern, and for every panel whose LSCM system had at least PZ_METIS_MAX_UNKNOWNS unknowns, the
 * elimination order its factorization used, per pattern vertex, into vertex_rank (nv; may be NULL; -1 for the
 * others and for the pins): what pz_param_analyze_ranked reuses. */
pz_status pz_param_lscm_pattern_ranked(const pz_pattern *pattern, const double grain[3], double *uv,
                                       int32_t *vertex_rank, pz_ctx *ctx);

/* cholmod_factorize with no OpenMP team (param/lscm.c says why). */
int pz_param_factorize(cholmod_sparse *matrix, cholmod_factor *factor, cholmod_common *common);

/* Moves interior vertices of flipped faces into the kernel of their star
 * (vertices with fixed[v] set never move; fixed may be NULL). Returns the
 * moves made, -1 when out of memory. */
int32_t pz_param_untangle(const pz_mesh *mesh, const uint8_t *fixed, double *uv);

/* Puts the apex of every sliver face (3D height under 5e-2 of its longest
 * edge) where the 3D triangle puts it over its flattened longest edge,
 * unless the apex is fixed (may be NULL) or a face around it would flip
 * (param/slivers.c says why). Returns the apexes moved, -1 out of memory. */
int32_t pz_param_fit_slivers(const pz_mesh *mesh, const uint8_t *fixed, double *uv);

#endif /* PZ_PARAM_INTERNAL_H */

/*
 * prepare/cgal_shim.h -- the three CGAL operations prepare/ needs, behind
 * plain C: edge-collapse decimation, isotropic remeshing and closest-point
 * queries. Only C types cross this header; prepare/cgal_shim.cpp is the one
 * C++ file that includes CGAL, and it catches every exception at the
 * boundary (a pz_status and a one-line message come back instead).
 *
 * SPDX-License-Identifier: GPL-3.0-or-later
 */
#ifndef PZ_CGAL_SHIM_H
#define PZ_CGAL_SHIM_H

#include "mesh/mesh.h"

#ifdef __cplusplus
extern "C" {
#endif

/**
 * A bare triangle surface with a set of constrained edges (the welded seams
 * to keep). Arrays are malloc'd; pz_cgal_surface_clear frees them.
 * The input of decimate and remesh must be edge-manifold and consistently
 * oriented (prepare/repair.c repairs it first).
 */
typedef struct pz_cgal_surface {
    int32_t vertex_count, face_count, edge_count;
    double *positions;   /* vertex_count x 3 */
    int32_t *faces;      /* face_count x 3 */
    int32_t *edges;      /* edge_count x 2 vertex pairs: constrained (seam) edges */
    int32_t locked_count;
    int32_t *locked;     /* input only: vertices remeshing must keep (corners); may be NULL */
} pz_cgal_surface;

void pz_cgal_surface_clear(pz_cgal_surface *surface);

/**
 * Edge-collapse simplification (CGAL Surface_mesh_simplification) down to
 * about target_faces faces: shortest edge first, midpoint placement.
 * Constrained edges and boundary edges are never collapsed, and their
 * vertices never move, so the seams and the outline keep their exact shape.
 * *out receives the result (constrained edges renumbered).
 */
pz_status pz_cgal_decimate(const pz_cgal_surface *in, int32_t target_faces, pz_cgal_surface *out, pz_ctx *ctx);

/**
 * Isotropic remeshing (CGAL PMP isotropic_remeshing, Botsch & Kobbelt 2004:
 * split long edges, collapse short ones, flip towards valence 6, tangential
 * relaxation) to target_edge, `iterations` rounds. Boundary and constrained
 * edges may be split and collapsed but only along themselves, and the locked
 * vertices stay: the outline, its corners and the seams stay where they are.
 * *out receives the result.
 */
pz_status pz_cgal_remesh(const pz_cgal_surface *in, double target_edge, int iterations, pz_cgal_surface *out,
                         pz_ctx *ctx);

/**
 * For each of query_count points (query_count x 3), the closest point on the
 * triangles (faces x 3 into positions) and the face it lies on, through an
 * AABB tree: O((F + Q) log F). closest: query_count x 3, face: query_count.
 * Uses up to 8 threads for many queries (and two trees, built in parallel,
 * above 200K triangles); the answers do not depend on the thread count.
 */
pz_status pz_cgal_closest_points(const double *positions, int32_t vertex_count, const int32_t *faces,
                                 int32_t face_count, const double *queries, int32_t query_count, double *closest,
                                 int32_t *face, pz_ctx *ctx);

#ifdef __cplusplus
}
#endif

#endif

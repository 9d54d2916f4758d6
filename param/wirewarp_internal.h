/*
 * param/wirewarp_internal.h -- the parts of WireWarping (pz_param_wirewarp,
 * pz_wirewarp_setup / pz_wirewarp_solve; the method: param/wirewarp.c) and
 * what they share.
 *
 * Files:
 *   wirewarp_wires.c   set-up: edge lookup, the wires, wire-patches and
 *                      wire-nodes of a pattern and its feature curves, and
 *                      the snapping of feature polylines to mesh edges
 *   wirewarp_angles.c  solve, angle space: the constrained optimization of
 *                      the wire-nodes' angles (global and progressive)
 *   wirewarp_layout.c  solve, the plane: the wires walked out, the interior
 *                      (CHOLMOD, its symbolic analysis kept: ww_interior),
 *                      the grain orientation and the untangling
 *   wirewarp.c         the driver, the report figures, the dangling-end
 *                      trimming, pz_param_wirewarp and the solver API
 *
 * SPDX-License-Identifier: GPL-3.0-or-later
 */
#ifndef PZ_PARAM_WIREWARP_INTERNAL_H
#define PZ_PARAM_WIREWARP_INTERNAL_H

#include "param/internal.h"
#include "core/util.h"

#include <math.h>

#define WW_PI 3.14159265358979323846
#define WW_BEST_EFFORT 1e-9        /* scaled residual above which the result is flagged */

static inline double ww_distance3(const double *a, const double *b)
{
    return sqrt((a[0] - b[0]) * (a[0] - b[0]) + (a[1] - b[1]) * (a[1] - b[1]) + (a[2] - b[2]) * (a[2] - b[2]));
}

/* Sorted (vertex pair -> edge) keys of a topology, for ww_find_edge. */
typedef struct ww_edge_key {
    int64_t key;
    int32_t edge;
} ww_edge_key;

/* The keys of t's edges (caller frees); NULL when out of memory. */
ww_edge_key *ww_edge_keys(const pz_topology *t);
/* The edge joining a and b, -1 when there is none. */
int32_t ww_find_edge(const ww_edge_key *keys, int32_t count, int32_t a, int32_t b);

/* A max-heap entry (larger key first, then smaller id): the progressive
 * scheme's patches, the snapper's Dijkstra (negated distances). */
typedef struct ww_heap_entry {
    double key;
    int32_t patch;
} ww_heap_entry;

/* Pushes (key, patch) onto the heap of *size entries (grown as needed); 0 when out of memory. */
int ww_heap_push(ww_heap_entry **heap, size_t *capacity, int32_t *size, double key, int32_t patch);
/* Removes and returns the top entry (*size > 0). */
ww_heap_entry ww_heap_pop(ww_heap_entry *h, int32_t *size);

/* Wires, wire-patches, wire-nodes (Sec. 2) of a pattern and its feature curves. */
typedef struct ww_wires {
    pz_topology *topo;           /* of pattern->mesh */
    ww_edge_key *keys;
    uint8_t *wire_edge;          /* per edge: on a boundary or a feature curve */
    uint8_t *key_vertex;         /* per pattern vertex: on a key curve */
    double *key_turn;            /* per pattern vertex: the user's turning angle there, NAN when not given */
    int32_t *key_side;           /* per pattern vertex: the curve's previous and next vertex (x2), for key_turn */
    int32_t patch_count;
    int32_t *patch_panel;
    int32_t *patch_offsets;      /* nodes of patch p: patch_offsets[p] .. [p+1]-1, anticlockwise */
    double *patch_perimeter;
    int32_t node_count;
    int32_t *node_host;          /* pattern vertex */
    int32_t *node_patch;
    double *alpha;               /* surface angle (Def. 5) */
    double *length;              /* 3D length of the edge node -> next node */
    int32_t *host_offsets;       /* pattern vertex -> its nodes (CSR) */
    int32_t *host_nodes;
} ww_wires;

/* wirewarp_wires.c: builds *w (freed with ww_wires_free, also after an error). */
pz_status ww_wires_build(const pz_pattern *pattern, const pz_feature_curves *features, ww_wires *w, pz_ctx *ctx);
void ww_wires_free(ww_wires *w);

/* wirewarp_angles.c: the wire-nodes' 2D angles theta (node_count), the angle figures into r; origin (may
 * be NULL) maps the features' indices to the caller's. */
pz_status ww_warp_angles(const pz_pattern *pattern, const ww_wires *w, const pz_wirewarp_options *options,
                         const pz_feature_curves *features, const int32_t *origin, double *theta,
                         pz_wirewarp_result *r, pz_ctx *ctx);

/*
 * The interior system's symbolic analysis, kept between interior solves: its
 * sparsity pattern depends only on the mesh and on which vertices are wires
 * (placed), so the cotangent solve, the 1/length retry and every later solve
 * of a kept solver share one analysis; each factorizes a copy of it. Zero it
 * to start; ww_interior_free releases it.
 */
typedef struct ww_interior {
    int started;
    cholmod_common common;       /* simplicial, quiet */
    cholmod_factor *symbolic;    /* NULL: none yet */
    uint8_t *placed;             /* vertex_count: the wires the analysis belongs to */
    int32_t vertex_count;
} ww_interior;

void ww_interior_free(ww_interior *interior);

/* wirewarp_layout.c */
pz_status ww_layout_wires(const ww_wires *w, const double *theta, uint8_t *placed, double *uv, pz_ctx *ctx);
pz_status ww_layout_interior(const pz_mesh *mesh, const pz_topology *t, int mode, const uint8_t *placed, double *uv,
                             int *fallback, ww_interior *interior, pz_ctx *ctx);
void ww_wire_length_error(const pz_mesh *mesh, const ww_wires *w, const double *uv, pz_wirewarp_result *r);
pz_status ww_orient_to_grain(const pz_pattern *pattern, const double grain[3], double *uv, pz_ctx *ctx);
/* Twice the signed area of face f at uv. */
double ww_face_det(const pz_mesh *mesh, const double *uv, int32_t f);

#endif /* PZ_PARAM_WIREWARP_INTERNAL_H */

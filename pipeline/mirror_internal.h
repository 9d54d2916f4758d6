/*
 * pipeline/mirror_internal.h -- what the two files of the exact mirror pieces
 * share (docs/segment.md, "Exact mirror pieces"): pipeline/mirror_pairing.c
 * pairs two outlines (anchors, corners, the 2D reflection through them) and
 * measures the residual; pipeline/mirror.c makes the pieces exact. Not part of
 * the public interface.
 *
 * SPDX-License-Identifier: GPL-3.0-or-later
 */
#ifndef PZ_PIPELINE_MIRROR_INTERNAL_H
#define PZ_PIPELINE_MIRROR_INTERNAL_H

#include "pipeline/internal.h"

/* An outline vertex turning more is a corner: both outlines must have it as an anchor. */
#define PL_MIRROR_CORNER_DEG 40.0

/* The longest boundary loop of each panel of the cut mesh (cut-mesh vertices in loop order). */
typedef struct outlines {
    pz_loops *loops;
    int32_t *panel_loop;    /* panel_count: the loop of each panel, -1 */
} outlines;

typedef struct anchor {
    int32_t a, b;    /* positions in the piece's outline and in the partner's */
} anchor;

/* x -> M x + t, M a reflection matrix (det -1). */
typedef struct mirror2 {
    double m[2][2], t[2];
} mirror2;

/* Panel p's outline A, its partner q's outline B (the same for a panel crossed by the plane), the anchors between
 * them and the reflection through the anchors. */
typedef struct pairing {
    const int32_t *A, *B;
    int32_t na, nb;
    anchor *anchors;     /* room for na + nb */
    int32_t count;       /* 0: no pairing */
    mirror2 r;
    int involution;      /* 1: A == B */
} pairing;

/* The longest boundary loop of each panel of the cut mesh (topology: the cut mesh's); 0 when out of memory. */
int pl_outlines_build(const pz_pattern *pattern, const pz_topology *topology, outlines *o, pz_ctx *ctx);
void pl_outlines_free(outlines *o);

/* x -> M x + t, and back (M is its own inverse: y -> M (y - t)). */
void pl_mirror2_apply(const mirror2 *r, const double *x, double *out);
void pl_mirror2_back(const mirror2 *r, const double *y, double *out);

/* The turn (degrees) of loop L (n vertices) at position i, from uv. */
double pl_turn_deg(const int32_t *L, int32_t n, int32_t i, const double *uv);

/*
 * Pairs panel p's outline with panel q's (q == p: crossed by the plane): anchors, corners, the reflection, from
 * uv. mirror: the garment's vertex_mirror. position_a, position_b: 2 x garment vertex count each, all -1 (left
 * so). 0 when out of memory; pr->count 0 when the outlines cannot be paired. Free with pl_pairing_free.
 */
int pl_pairing_make(const pz_pattern *pattern, const outlines *o, const int32_t *mirror, int32_t p, int32_t q,
                    int32_t *position_a, int32_t *position_b, const double *uv, pairing *pr);
void pl_pairing_free(pairing *pr);

#endif

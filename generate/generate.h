/*
 * generate/generate.h -- synthetic garments and surfaces (docs/generate.md):
 * the default input of `panelize generate` and the fixtures of the tests
 * and benchmarks, in millimetres at human scale. Conventions as in
 * mesh/mesh.h.
 *
 * SPDX-License-Identifier: GPL-3.0-or-later
 */
#ifndef PZ_GENERATE_H
#define PZ_GENERATE_H

#include <stdint.h>

#include "mesh/mesh.h"

#ifdef __cplusplus
extern "C" {
#endif

typedef enum pz_shape {
    PZ_SHAPE_UNKNOWN = 0,
    PZ_SHAPE_BODICE,          /* sleeveless torso tube: bust, waist, hip; two boundary loops */
    PZ_SHAPE_SKIRT,           /* flared skirt shaped at the hip; two boundary loops */
    PZ_SHAPE_SLEEVE,          /* bent tube; two boundary loops */
    PZ_SHAPE_HEMISPHERE,      /* one boundary loop, positive curvature */
    PZ_SHAPE_QUARTER_SPHERE,  /* one boundary loop, positive curvature */
    PZ_SHAPE_SADDLE,          /* one boundary loop, negative curvature */
    PZ_SHAPE_CYLINDER,        /* developable; two loops, or one with `open` */
    PZ_SHAPE_CONE             /* developable (truncated); two loops, or one with `open` */
} pz_shape;

/** Parses a shape name ("bodice", "quarter-sphere", ...); PZ_SHAPE_UNKNOWN otherwise. */
pz_shape pz_shape_parse(const char *name);
const char *pz_shape_name(pz_shape shape);

typedef struct pz_generate_options {
    int32_t target_faces;  /* approximate face count; 0 = 20000. 500 .. 1,000,000 keep well-shaped faces */
    int32_t pose_count;    /* extra deformed poses (bending, twisting, breathing); 0 = none */
    int open;              /* cylinder/cone: cut along a ruling into a disk */
} pz_generate_options;

/**
 * Generates a shape in millimetres at human scale, counter-clockwise faces
 * with normals pointing outward (away from the body), manifold and well shaped.
 * Extra poses share the connectivity. Caller frees *out.
 */
pz_status pz_generate(pz_shape shape, const pz_generate_options *options, pz_mesh **out, pz_ctx *ctx);

#ifdef __cplusplus
}
#endif

#endif /* PZ_GENERATE_H */

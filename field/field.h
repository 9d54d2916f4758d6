/*
 * field/field.h -- the field stage: multi-scale principal curvature and the
 * curvature-aligned 4-RoSy cross-field that guides the seams.
 *
 * pietroni2022 Sec. 4.1: principal curvature directions at several scales
 * (after Panozzo et al. 2010) give per-face target directions and an
 * anisotropy weight; a globally smooth cross-field (one sparse solve) is
 * softly aligned to them where the anisotropy is high, and hard-aligned to
 * the boundary edges and to the curves the user sketched. Extra poses add
 * their own curvature, averaged per face in the rest shape. The method and
 * its choices are in docs/field.md and in the header comments of
 * field/curvature.c and field/crossfield.c.
 *
 * Conventions of mesh/mesh.h: fallible calls take pz_ctx last and return a
 * pz_status, allocating calls take `T **out` freed by the matching
 * pz_*_free(&p) (NULL accepted). Directions are unit 3D vectors in the plane
 * of their face; a cross is given by one arm, the others being that arm
 * turned by 90, 180 and 270 degrees about the face normal.
 *
 * SPDX-License-Identifier: GPL-3.0-or-later
 */
#ifndef PZ_FIELD_H
#define PZ_FIELD_H

#include "mesh/mesh.h"

#ifdef __cplusplus
extern "C" {
#endif

/* ------------------------------------------------------------------------ */
/* Curvature                                                                 */
/* ------------------------------------------------------------------------ */

/** Default number of scales (radius 1x, 2x, 4x the mean edge length). */
#define PZ_FIELD_DEFAULT_SCALES 3
/** Largest number of scales accepted (radius up to 2^7 mean edges). */
#define PZ_FIELD_MAX_SCALES 8

/** Per-face principal curvature, combined over the scales. */
typedef struct pz_curvature {
    int32_t face_count;
    int32_t scale_count;
    double *directions;   /* face_count x 3: unit direction of the larger |curvature|, in the face plane */
    double *k_max;        /* face_count: the curvature of larger magnitude (1/mm, mean over scales) */
    double *k_min;        /* face_count: the other principal curvature (1/mm, mean over scales) */
    double *anisotropy;   /* face_count in [0, 1]: (|k1|-|k2|)/(|k1|+|k2|+eps) times the agreement of the scales */
} pz_curvature;

/**
 * Principal curvature of the surface given by `positions` (vertex_count x 3;
 * NULL = the rest pose) with the connectivity of `mesh`/`topology`, at
 * `scale_count` scales (0 = PZ_FIELD_DEFAULT_SCALES; 1 .. PZ_FIELD_MAX_SCALES):
 * a quadric fitted at every vertex over the vertices within radius
 * 2^s * mean edge length (at least the one-ring), averaged to faces as
 * tensors, and the scales combined by the 90-degree-invariant average of the
 * directions weighted by anisotropy. O(V * neighbourhood size), OpenMP.
 * Errors: PZ_ERR_USAGE (bad scale count), PZ_ERR_NOMEM.
 */
pz_status pz_curvature_compute(const pz_mesh *mesh, const pz_topology *topology, const double *positions,
                               int32_t scale_count, pz_curvature **out, pz_ctx *ctx);
void pz_curvature_free(pz_curvature **curvature);

/** Mean edge length of the rest pose (0 for a mesh without faces). */
double pz_field_mean_edge_length(const pz_mesh *mesh, const pz_topology *topology);

/* ------------------------------------------------------------------------ */
/* Sketches                                                                  */
/* ------------------------------------------------------------------------ */

/** 3D polylines drawn by the user (in millimetres once scaled). */
typedef struct pz_sketch {
    int32_t curve_count;
    int32_t *curve_offsets;  /* curve_count + 1: curve i has points curve_offsets[i] .. curve_offsets[i+1]-1 */
    double *points;          /* curve_offsets[curve_count] x 3 */
} pz_sketch;

/**
 * Parses `{"curves": [[[x,y,z], ...], ...]}` (each curve at least 2 finite
 * points) from memory; `name` names the source in messages. Coordinates are
 * multiplied by `scale` (pass mesh->unit_scale so a sketch in the mesh file's
 * units lands on the millimetre mesh). Malformed input, anything but white
 * space after the JSON value, or more than PZ_SKETCH_MAX_CURVES curves:
 * PZ_ERR_DATA.
 */
pz_status pz_sketch_parse(const char *text, size_t size, const char *name, double scale, pz_sketch **out,
                          pz_ctx *ctx);
/** The same from a file: PZ_ERR_OPEN when it cannot be read, PZ_ERR_DATA when malformed. */
pz_status pz_sketch_read(const char *path, double scale, pz_sketch **out, pz_ctx *ctx);
void pz_sketch_free(pz_sketch **sketch);

/* The most curves a sketch may hold: each becomes a seam of its own (a garment has tens), and each is
 * snapped to the mesh by a shortest-path search; 20,000 curves fit in a 2 MB file. */
#define PZ_SKETCH_MAX_CURVES 1000

/* How far a sketch point may lie from the surface: 2 % of the bounding-box diagonal, at least 10 mm
 * (a curve drawn on a slightly different version of the garment, a prepared or remeshed one, still fits). */
#define PZ_SKETCH_TOLERANCE_REL 0.02
#define PZ_SKETCH_TOLERANCE_MM 10.0

/** The tolerance above for this mesh (mm). */
double pz_sketch_tolerance(const pz_mesh *mesh);

/**
 * Every point of the sketch lies within pz_sketch_tolerance of the mesh's
 * surface; otherwise PZ_ERR_DATA naming `name`, the curve, the point and the
 * distance (a sketch in other units, or drawn on another garment). Far points
 * are refused from the bounding box alone: O(points + F).
 * pz_field_compute checks its sketch this way too.
 */
pz_status pz_sketch_check(const pz_sketch *sketch, const pz_mesh *mesh, const char *name, pz_ctx *ctx);

/* ------------------------------------------------------------------------ */
/* The cross-field                                                           */
/* ------------------------------------------------------------------------ */

/** Default weight of smoothness against curvature alignment (--smoothness). */
#define PZ_FIELD_DEFAULT_SMOOTHNESS 4.0

typedef struct pz_field_options {
    int32_t scale_count;      /* curvature scales; 0 = PZ_FIELD_DEFAULT_SCALES */
    double smoothness;        /* weight of the smoothness term (> 0); 0 = PZ_FIELD_DEFAULT_SMOOTHNESS */
    const pz_sketch *sketch;  /* curves to align to (hard), or NULL */
    int use_poses;            /* 1: add the curvature of every mesh->poses (the CLI always does) */
} pz_field_options;

/** The defaults: every field zero, which means the defaults named above (defined once, in crossfield.c). */
void pz_field_options_default(pz_field_options *options);

/** What a face's cross is held to. */
enum pz_field_constraint {
    PZ_FIELD_FREE = 0,        /* smooth + soft curvature alignment */
    PZ_FIELD_BOUNDARY = 1,    /* one arm along its (longest) boundary edge */
    PZ_FIELD_SKETCH = 2       /* one arm along the sketched curve crossing it */
};

typedef struct pz_field {
    int32_t face_count;
    double *directions;          /* face_count x 3: one unit arm of each face's cross */
    double *normals;             /* face_count x 3: unit face normals (rest pose) */
    double *curvature_directions;/* face_count x 3: the combined curvature target (poses included) */
    double *anisotropy;          /* face_count: combined anisotropy (mean over poses) */
    uint8_t *constraint;         /* face_count: enum pz_field_constraint */
    double *constraint_directions; /* face_count x 3: the prescribed arm of constrained faces (0 elsewhere) */
    int32_t boundary_face_count, sketch_face_count;

    int32_t singularity_count;
    int32_t *singular_vertices;  /* singularity_count interior vertices, increasing */
    double *singular_indices;    /* singularity_count: index in turns, +-0.25 (rarely +-0.5 ...) */
    double index_sum;            /* sum of all singularity indices */

    double curvature_alignment_deg; /* mean cross angle to the curvature target, weighted by anisotropy * area */
    double boundary_alignment_deg;  /* mean cross angle to the boundary edge over boundary faces (-1: none) */
    double sketch_alignment_deg;    /* mean cross angle to the sketch tangent over sketched faces (-1: none) */

    double curvature_ms, sketch_ms, solve_ms, singularity_ms; /* timings of the steps */
    double mean_edge_length;
} pz_field;

/**
 * Computes the cross-field of a valid mesh (topology built from it): curvature
 * of the rest pose (and of every pose with use_poses), sketch snapping,
 * boundary and sketch constraints, one CHOLMOD solve, normalisation, then the
 * singularities and the alignment figures. A mesh without boundary, sketch or
 * anisotropic curvature has no preferred direction; the field is then seeded
 * by one face aligned with its first edge.
 * Errors: PZ_ERR_USAGE (bad options), PZ_ERR_NOMEM, PZ_ERR_INTERNAL (failed
 * factorisation), PZ_ERR_CANCELLED (ctx->cancel set; checked between steps,
 * not inside the one CHOLMOD factorisation).
 */
pz_status pz_field_compute(const pz_mesh *mesh, const pz_topology *topology, const pz_field_options *options,
                           pz_field **out, pz_ctx *ctx);
void pz_field_free(pz_field **field);
/** A deep copy of a field into *out (the caller frees it with pz_field_free); PZ_ERR_NOMEM. */
pz_status pz_field_copy(const pz_field *field, pz_field **out, pz_ctx *ctx);

/**
 * The mirror-symmetric version of a field (docs/field.md, "Symmetry"), into
 * a new field *out: every free face's cross averaged with the cross of its
 * mirror face (mirror_faces[f], -1 none: the face holding the mirror image
 * of face f) reflected through the plane of unit normal `normal`, so the
 * field is (nearly) its own mirror image and paths traced on one half mirror
 * those on the other; constrained faces (border, sketch) keep their crosses.
 * Singularities and alignment figures are recomputed. O(F). Errors:
 * PZ_ERR_USAGE (a field of another mesh), PZ_ERR_NOMEM.
 */
pz_status pz_field_mirrored(const pz_mesh *mesh, const pz_topology *topology, const pz_field *field,
                            const int32_t *mirror_faces, const double normal[3], pz_field **out, pz_ctx *ctx);

/**
 * Angle in degrees (0 .. 45) between the cross with arm `arm` and the line of
 * `direction`, both in the plane with unit normal `normal` (direction is
 * projected first). 0 when direction has no tangential part.
 */
double pz_field_cross_angle_deg(const double arm[3], const double direction[3], const double normal[3]);

/* ------------------------------------------------------------------------ */
/* Output                                                                    */
/* ------------------------------------------------------------------------ */

/**
 * Writes the field as line segments (two per face through the centroid, each
 * `arm_length` mm long; 0 = 0.8 mean edge) and the singular vertices as
 * points, to an open stream: OBJ (`v`, `l`, `p` elements, groups `cross` and
 * `singularities`) or binary glTF (one mesh with a LINES primitive and, when
 * there are singularities, a POINTS primitive). The caller opens and commits
 * the file (pz_output_open) so several outputs can be all-or-nothing.
 * Errors: PZ_ERR_CREATE on a write error (`name` in the message), PZ_ERR_NOMEM.
 */
pz_status pz_field_write_obj(const pz_mesh *mesh, const pz_field *field, double arm_length, FILE *file,
                             const char *name, pz_ctx *ctx);
pz_status pz_field_write_glb(const pz_mesh *mesh, const pz_field *field, double arm_length, FILE *file,
                             const char *name, pz_ctx *ctx);

#ifdef __cplusplus
}
#endif

#endif /* PZ_FIELD_H */

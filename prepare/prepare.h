/*
 * prepare/prepare.h -- scan-ready input (docs/prepare.md): weld, repair,
 * drop fragments, decimate huge inputs, remesh isotropically, carry the
 * poses and labels over and measure the Hausdorff distance to the input;
 * the automatic mode of `panelize run --prepare auto`; the welded seams as
 * a sketch file. Conventions as in mesh/mesh.h; lengths in mm.
 *
 * SPDX-License-Identifier: GPL-3.0-or-later
 */
#ifndef PZ_PREPARE_H
#define PZ_PREPARE_H

#include <stdint.h>

#include "mesh/mesh.h"

#ifdef __cplusplus
extern "C" {
#endif

/** What to do with the connected components left after repair. */
typedef enum pz_prepare_keep {
    PZ_PREPARE_KEEP_LARGEST = 0,  /* drop fragments under fragment_fraction of the area (default) */
    PZ_PREPARE_KEEP_ALL           /* keep every component as a garment part */
} pz_prepare_keep;

/** Options of pz_prepare. Zero = defaults. Lengths in mm (the mesh is in mm). */
typedef struct pz_prepare_options {
    double weld_distance;      /* weld vertices closer than this; 0 = 0.01 mm; < 0 = no welding */
    double target_edge;        /* remeshing edge length; 0 = from target_faces */
    int32_t target_faces;      /* faces wanted when target_edge is 0; 0 = 20000 (automatic: the most
                                  faces kept as they are, and the count above them; 0 = 10000) */
    pz_prepare_keep keep;
    double fragment_fraction;  /* 0 = 0.01 (1% of the total area) */
    int iterations;            /* remeshing rounds; 0 = 5 */
    int automatic;             /* 1: decimate and remesh only when the mesh needs it (pz_prepare_auto) */
    int no_remesh;             /* 1: never decimate or remesh (weld and repair only) */
    const char *name;          /* the input's name for messages; NULL = "mesh" */
} pz_prepare_options;

/** The defaults: every field zero, which means the defaults named above (defined once, in prepare/). */
void pz_prepare_options_default(pz_prepare_options *options);

/** The steps, in the order they run (pz_prepare_report.steps). */
typedef enum pz_prepare_step_id {
    PZ_PREPARE_WELD = 0, PZ_PREPARE_REPAIR, PZ_PREPARE_FRAGMENTS, PZ_PREPARE_DECIMATE,
    PZ_PREPARE_REMESH, PZ_PREPARE_POSES, PZ_PREPARE_HAUSDORFF, PZ_PREPARE_STEP_COUNT
} pz_prepare_step_id;

typedef struct pz_prepare_step {
    const char *name;    /* "weld", "repair", "fragments", "decimate", "remesh", "poses", "hausdorff" */
    int ran;             /* 1 when the step changed or measured something */
    char detail[256];    /* one line: the counts, or why the step did not run */
    double seconds;
} pz_prepare_step;

/** Counts and figures of one preparation. */
typedef struct pz_prepare_report {
    pz_prepare_step steps[PZ_PREPARE_STEP_COUNT];
    int32_t input_vertices, input_faces;
    int32_t welded_vertices;         /* vertices merged into another by welding */
    int32_t seam_edges;              /* welded edges (between two formerly separate faces) */
    int32_t nonfinite_faces;         /* faces dropped for a NaN/Inf corner */
    int32_t degenerate_faces, duplicate_faces;
    int32_t nonmanifold_edge_faces;  /* faces dropped beyond the first two on an edge */
    int32_t split_vertices;          /* copies made to split non-manifold vertices */
    int32_t flipped_faces;
    int32_t components, dropped_components, dropped_component_faces;
    int32_t decimated_faces;         /* faces after decimation; 0 when it did not run */
    double target_edge;              /* mm; 0 when remeshing did not run */
    int32_t output_vertices, output_faces;
    double bbox_diagonal;            /* of the repaired rest input, mm */
    double hausdorff;                /* symmetric sampled Hausdorff distance, rest pose, mm (0 when unchanged) */
    double hausdorff_bound;          /* 0.005 x bbox_diagonal */
    double pose_hausdorff_max;       /* largest over the extra poses (each against its own input pose) */
    int within_bound;                /* 1 when every Hausdorff distance is under the bound */
    double min_angle_over_20_fraction; /* fraction of output faces whose smallest angle exceeds 20 degrees */
} pz_prepare_report;

/** A prepared mesh, its seams as polylines of its vertices, and the report. */
typedef struct pz_prepare_result {
    pz_mesh *mesh;            /* manifold, oriented; poses and labels carried over, UVs dropped when remeshed */
    int32_t seam_count;
    int32_t *seam_offsets;    /* seam_count + 1 */
    int32_t *seam_vertices;   /* polyline i: seam_vertices[seam_offsets[i] .. seam_offsets[i+1]-1] (closed: last == first) */
    pz_prepare_report report;
} pz_prepare_result;

/**
 * Makes a scan or an export ready for the field, tracing and flattening:
 * weld, repair, drop fragments, decimate huge inputs, remesh isotropically
 * (boundaries and welded seams kept), carry the poses over and measure the
 * Hausdorff distance to the repaired input. `mesh` (in mm) is not changed.
 * Errors: PZ_ERR_INVALID_MESH when nothing is left after repair or a
 * component is not orientable; PZ_ERR_USAGE for a target edge too long for
 * the garment. Notes each step through pz_note. On success *out is a new
 * result the caller owns (pz_prepare_result_free); on failure *out is NULL.
 */
pz_status pz_prepare(const pz_mesh *mesh, const pz_prepare_options *options, pz_prepare_result **out, pz_ctx *ctx);

/**
 * pz_prepare with options->automatic set: what `panelize run --prepare auto`
 * calls. Weld, repair and fragments always run; then a mesh over 10000 faces
 * (options->target_faces when set) is remeshed to that count, one with under
 * 95% of its faces free of angles under 20 degrees is remeshed at its own
 * face count. A remesh that moves the shape beyond the Hausdorff bound is
 * tried again at twice the faces (up to 40000, below the input's count), then
 * once at the input's count for a badly shaped input; when none fits the
 * bound it is undone (the repaired input kept). The remesh step's detail says
 * why it ran, or why not (docs/prepare.md). Ownership as pz_prepare.
 */
pz_status pz_prepare_auto(const pz_mesh *mesh, const pz_prepare_options *options, pz_prepare_result **out,
                          pz_ctx *ctx);

/**
 * The repairs of the preparation that keep the faces and the existing
 * vertex ids (what `flatten --repair` adds to pz_mesh_prepare's): faces
 * beyond the first two on an edge dropped, non-manifold vertices split, one
 * copy per fan of faces, the copies appended after the existing vertices
 * (with their poses). Runs only when pz_mesh_validate finds non-manifold
 * edges or vertices and nothing it cannot work on (corners out of range,
 * non-finite coordinates: pz_mesh_prepare reports those). Corner UVs and
 * face labels stay with their faces. *dropped_faces and *split_vertices
 * (may be NULL) get the counts. Errors: PZ_ERR_NOMEM.
 */
pz_status pz_prepare_make_manifold(pz_mesh *mesh, int32_t *dropped_faces, int32_t *split_vertices, pz_ctx *ctx);

/** An exactly mirror-symmetric garment (pz_prepare_symmetrize). */
typedef struct pz_symmetrized {
    pz_mesh *mesh;            /* the kept half (its vertices first), then its reflection; no UVs or poses */
    int32_t *vertex_mirror;   /* mesh->vertex_count: the vertex at each vertex's exact reflection (itself on the
                                 plane); a bijection, its own inverse */
    int32_t *face_mirror;     /* mesh->face_count: face f's reflection (f + half the faces, and back) */
    uint8_t *vertex_side;     /* mesh->vertex_count: 0 the kept (negative) side, 1 on the plane, 2 the reflection */
    int32_t snapped_vertices; /* input vertices put onto the plane (within a tenth of the mean edge length of it) */
    int32_t cut_faces;        /* input faces the plane crossed */
    double deviation_max_mm;  /* the input's vertices' distance to the symmetric surface: largest */
    double deviation_p95_mm;  /* and 95th percentile */
    int32_t *input_nearest;   /* input vertex count: the symmetric vertex nearest each input vertex */
} pz_symmetrized;

/**
 * The garment made exactly symmetric about the plane normal . p = offset
 * (pietroni2022 Sec. 3): the faces the plane crosses cut, vertices near it
 * snapped onto it, the negative half kept, reflected and welded along the
 * plane (docs/segment.md, "The symmetrized garment"). `mesh` (a valid
 * manifold, mm, its poses ignored) is not changed; labels follow the faces.
 * PZ_ERR_DATA when nothing lies on the negative side or the result is not a
 * valid manifold (the garment meets the plane along a fold); PZ_ERR_USAGE for
 * a zero normal. On success *out owns its arrays (pz_symmetrized_clear); on
 * failure it is zeroed.
 */
pz_status pz_prepare_symmetrize(const pz_mesh *mesh, const double normal[3], double offset, pz_symmetrized *out,
                                pz_ctx *ctx);
void pz_symmetrized_clear(pz_symmetrized *symmetrized);

/** Frees the result, its mesh and seams, and sets *result to NULL (NULL or *result NULL: nothing). */
void pz_prepare_result_free(pz_prepare_result **result);

/** Writes the seams as a sketch file {"curves": [[[x,y,z], ...], ...]} (mm), atomically; result stays the caller's. */
pz_status pz_prepare_write_seams(const pz_prepare_result *result, const char *path, pz_ctx *ctx);

#ifdef __cplusplus
}
#endif

#endif /* PZ_PREPARE_H */

/*
 * mesh/mesh.h -- the public face of panelize's mesh core.
 *
 * Everything later stages stand on: the triangle mesh with its optional UVs,
 * labels and poses, its units, validation and repair, connectivity
 * (half-edges in a corner layout), geometry, and cutting and extraction.
 * Files are read and written by io/io.h, scans made ready by
 * prepare/prepare.h, synthetic garments built by generate/generate.h; the
 * context and status codes are core/core.h's.
 *
 * Conventions (see docs/mesh.md):
 *  - Shapes are written in libigl's notation: `nv x 3` means nv rows of 3,
 *    row-major, contiguous.
 *  - Every function that can fail takes a `pz_ctx *` last and returns a
 *    pz_status. On failure it writes a one-line message into the context,
 *    leaves every `T **out` at NULL and leaks nothing.
 *  - A function that allocates takes `T **out`; the caller owns the result and
 *    frees it with the matching `pz_*_free(&p)`, which accepts NULL and sets
 *    the pointer to NULL.
 *  - Indices are int32_t (a mesh has fewer than 2^31 elements).
 *  - Lengths are millimetres once a mesh has been through pz_mesh_to_mm();
 *    readers return the file's own units.
 *
 * SPDX-License-Identifier: GPL-3.0-or-later
 */
#ifndef PZ_MESH_H
#define PZ_MESH_H

#include <stddef.h>
#include <stdint.h>
#include <stdio.h>

#include "core/core.h"

#ifdef __cplusplus
extern "C" {
#endif

/* ------------------------------------------------------------------------ */
/* The mesh                                                                  */
/* ------------------------------------------------------------------------ */

/**
 * A triangle mesh. All arrays are owned by the mesh and freed by pz_mesh_free.
 *
 * UVs are indexed per corner, as in OBJ: corner k of face f has the UV
 * uvs[2*corner_uvs[3*f+k] .. +1]. This keeps UV seams (two corners of one
 * vertex with different UV indices) exactly, which `--panels uv` relies on.
 *
 * Labels are per face (OBJ `g`/`o` groups, glTF primitives or panels); label
 * L's name is label_names[L] (may be NULL for unnamed labels).
 *
 * Extra poses share the connectivity: pose p's positions are
 * poses[(p * vertex_count + v) * 3 .. +2]. The rest pose is `positions`.
 */
typedef struct pz_mesh {
    int32_t vertex_count;
    int32_t face_count;
    double *positions;      /* vertex_count x 3 */
    int32_t *faces;         /* face_count x 3, counter-clockwise seen from the normal side */

    int32_t uv_count;       /* 0 when the mesh has no UVs */
    double *uvs;            /* uv_count x 2, or NULL */
    int32_t *corner_uvs;    /* face_count x 3 indices into uvs, or NULL */

    int32_t *face_labels;   /* face_count, or NULL */
    int32_t label_count;    /* number of distinct labels: 0 .. label_count-1 */
    char **label_names;     /* label_count strings (entries may be NULL), or NULL */

    int32_t pose_count;     /* extra poses, 0 when there are none */
    double *poses;          /* pose_count x vertex_count x 3, or NULL */

    double unit_scale;      /* millimetres per file unit applied so far (1 after pz_mesh_to_mm with mm) */
} pz_mesh;

/** Allocates a mesh with room for the given counts (arrays zeroed; no UVs, labels or poses). */
pz_status pz_mesh_create(int32_t vertex_count, int32_t face_count, pz_mesh **out, pz_ctx *ctx);

/** Frees a mesh and everything it owns; accepts NULL and *mesh == NULL; sets *mesh = NULL. */
void pz_mesh_free(pz_mesh **mesh);

/** Deep copy. */
pz_status pz_mesh_copy(const pz_mesh *mesh, pz_mesh **out, pz_ctx *ctx);

/** Axis-aligned bounding box of the rest pose: bbox_min[3], bbox_max[3]. Zeros for an empty mesh. */
void pz_mesh_bbox(const pz_mesh *mesh, double bbox_min[3], double bbox_max[3]);

/**
 * The garment's vertical (its "up", the default grain axis): +y or +z,
 * whichever the rest pose's bounding box is taller along. Tools disagree on
 * the up axis (glTF, CLO3D and Blender's OBJ export use y, scanners and CAD
 * often z), and no common tool uses x; a garment is taller than it is deep,
 * while arms spread sideways make x unreliable. Writes a unit vector.
 */
void pz_mesh_vertical_axis(const pz_mesh *mesh, double axis[3]);

/** Length units a file may be in. */
typedef enum pz_units {
    PZ_UNITS_AUTO = 0,
    PZ_UNITS_MM,
    PZ_UNITS_CM,
    PZ_UNITS_M
} pz_units;

/** "mm", "cm", "m" ("auto" for PZ_UNITS_AUTO). */
const char *pz_units_str(pz_units units);
/** Parses "mm", "cm", "m", "auto"; returns PZ_ERR_USAGE otherwise. */
pz_status pz_units_parse(const char *text, pz_units *out, pz_ctx *ctx);
/** Millimetres per unit: 1, 10, 1000. */
double pz_units_to_mm(pz_units units);

/**
 * Guesses the units from the bounding box: a garment is 0.2 - 2 m in its
 * largest extent. Returns the unit in which the largest extent falls closest
 * to that range (see docs/mesh.md for the exact rule). An empty mesh is mm.
 */
pz_units pz_mesh_guess_units(const pz_mesh *mesh);

/**
 * 1 when the mesh's largest extent, read in `units`, lies in a human's
 * 200 - 3000 mm (PZ_MESH_HUMAN_MIN_MM .. PZ_MESH_HUMAN_MAX_MM). A guess that
 * is not plausible is refused by pz_mesh_check_units: the mesh is either not
 * a garment or in a unit panelize cannot tell (give --units).
 */
int pz_mesh_units_plausible(const pz_mesh *mesh, pz_units units);

#define PZ_MESH_HUMAN_MIN_MM 200.0
#define PZ_MESH_HUMAN_MAX_MM 3000.0

/**
 * After pz_mesh_to_mm: whether the mesh, now in millimetres, has a garment's
 * size (largest extent 0.2 - 3 m). When not and the units were `guessed`,
 * PZ_ERR_DATA naming `name`, the reading and its size, asking for --units (a
 * 90 m or a 9 mm garment is a wrong guess, not a garment to cut); when not
 * and the units were given, a warning note and PZ_OK (the user said so).
 */
pz_status pz_mesh_check_units(const pz_mesh *mesh, pz_units used, int guessed, const char *name, pz_ctx *ctx);

/**
 * Scales the positions and every pose to millimetres. `units` AUTO means
 * guess. Writes the units used to *used (may be NULL). UVs are not scaled.
 */
void pz_mesh_to_mm(pz_mesh *mesh, pz_units units, pz_units *used);

/**
 * The most extra poses a mesh may carry (glTF morph targets and pose files
 * together). Every pose is flattened and measured with the rest: a file of
 * 1.7 MB can declare 100,000 morph targets, whose work would have no bound.
 */
#define PZ_MESH_MAX_POSES 256

/**
 * Adds one pose (vertex_count x 3 positions, copied) to the mesh; more than
 * PZ_MESH_MAX_POSES is PZ_ERR_DATA.
 */
pz_status pz_mesh_add_pose(pz_mesh *mesh, const double *positions, pz_ctx *ctx);

/* ------------------------------------------------------------------------ */
/* Validation                                                                */
/* ------------------------------------------------------------------------ */

/** Counts of every problem validation looks for. */
typedef struct pz_validation {
    int32_t nonfinite_coordinates;   /* vertices with a NaN or infinite coordinate (any pose) */
    int32_t bad_indices;             /* face corners out of range or repeated in one face */
    int32_t degenerate_faces;        /* zero-area faces (two equal corners or collinear: area <= eps * diag^2) */
    int32_t duplicate_faces;         /* faces with the same vertex set as an earlier face */
    int32_t nonmanifold_edges;       /* edges with more than two incident faces */
    int32_t nonmanifold_vertices;    /* vertices whose incident faces form more than one fan */
    int32_t inconsistent_edges;      /* interior edges whose two faces traverse them the same way */
    int32_t unreferenced_vertices;   /* vertices no face uses */
    int32_t problem_count;           /* number of strings in problems */
    char **problems;                 /* one line per kind of problem found, e.g.
                                        "3 non-manifold edges (first: vertices 10-11)";
                                        unreferenced vertices are listed too */
} pz_validation;

/**
 * Checks a mesh for every problem above. O(F log F). Returns PZ_OK when the
 * checks ran (whatever they found); *out is filled and must be released with
 * pz_validation_clear. Use pz_validation_ok to ask whether the mesh is valid.
 */
pz_status pz_mesh_validate(const pz_mesh *mesh, pz_validation *out, pz_ctx *ctx);

/** 1 when nothing but unreferenced vertices was found. */
int pz_validation_ok(const pz_validation *validation);

/** Frees the problem strings and zeroes the struct. */
void pz_validation_clear(pz_validation *validation);

/** Repairs a command can ask for before refusing a mesh (documented in docs/mesh.md). */
typedef enum pz_repair_flags {
    PZ_REPAIR_NONE = 0,
    PZ_REPAIR_DROP_DEGENERATE = 1 << 0,  /* remove zero-area faces */
    PZ_REPAIR_DROP_DUPLICATES = 1 << 1,  /* remove repeated faces */
    PZ_REPAIR_ORIENT = 1 << 2            /* flip faces to a consistent orientation per component */
} pz_repair_flags;

/**
 * Drops unreferenced vertices (always; the note says how many), applies the
 * requested repairs in place, then validates. Returns PZ_ERR_INVALID_MESH with
 * a one-line message naming `path` and the first remaining problem when the
 * mesh is still not valid. Reports what it did through pz_note.
 */
pz_status pz_mesh_prepare(pz_mesh *mesh, const char *path, unsigned repair_flags, pz_ctx *ctx);

/**
 * pz_mesh_prepare for a caller that must print one error line and nothing
 * else when it fails: a copy is prepared quietly first; only when that
 * succeeds is the preparation repeated aloud (it is deterministic) or, in a
 * quiet context, the prepared copy put in place of *mesh. On failure *mesh
 * is unchanged.
 */
pz_status pz_mesh_prepare_quietly_first(pz_mesh **mesh, const char *name, unsigned repair_flags, pz_ctx *ctx);

/**
 * Removes the faces with drop[f] != 0 in place, keeping the order of the
 * others with their corner UVs and labels. Vertices stay (drop them with
 * pz_mesh_drop_unreferenced). Returns the number of faces removed.
 */
int32_t pz_mesh_drop_faces(pz_mesh *mesh, const uint8_t *drop);

/** Removes vertices that no face references, renumbering faces. Writes the count removed to *removed (may be NULL). */
pz_status pz_mesh_drop_unreferenced(pz_mesh *mesh, int32_t *removed, pz_ctx *ctx);

/* ------------------------------------------------------------------------ */
/* Connectivity                                                              */
/* ------------------------------------------------------------------------ */

/**
 * Half-edges in corner layout (docs/mesh.md): half-edge h = 3*f + k belongs to
 * face f and runs from faces[3f+k] to faces[3f+(k+1)%3]. next(h) and prev(h)
 * are arithmetic (pz_he_next, pz_he_prev); twin[h] is the opposite half-edge or
 * -1 on the boundary. Each undirected edge e has edge_halfedge[2e] (always
 * valid) and edge_halfedge[2e+1] (-1 on the boundary). vertex_halfedge[v] is an
 * outgoing half-edge of v; for a boundary vertex it is the one whose
 * prev-around-the-vertex is missing, so ordered one-ring walks start at the
 * boundary. Built in O(F log F) (sort of directed edges).
 * Requires an edge-manifold, consistently oriented mesh with no vertex fans
 * split (pz_mesh_validate ok).
 */
typedef struct pz_topology {
    int32_t vertex_count;
    int32_t face_count;
    int32_t edge_count;
    int32_t halfedge_count;    /* 3 * face_count */
    const int32_t *faces;      /* borrowed from the mesh: face_count x 3 */
    int32_t *twin;             /* halfedge_count */
    int32_t *halfedge_edge;    /* halfedge_count: the undirected edge of a half-edge */
    int32_t *edge_halfedge;    /* edge_count x 2 */
    int32_t *vertex_halfedge;  /* vertex_count: outgoing half-edge, -1 for an isolated vertex */
    uint8_t *vertex_on_boundary; /* vertex_count: 1 on the boundary */
} pz_topology;

static inline int32_t pz_he_face(int32_t h) { return h / 3; }
static inline int32_t pz_he_next(int32_t h) { return h - h % 3 + (h % 3 + 1) % 3; }
static inline int32_t pz_he_prev(int32_t h) { return h - h % 3 + (h % 3 + 2) % 3; }
static inline int32_t pz_he_from(const pz_topology *t, int32_t h) { return t->faces[h]; }
static inline int32_t pz_he_to(const pz_topology *t, int32_t h) { return t->faces[pz_he_next(h)]; }

/** Builds connectivity. The topology borrows mesh->faces: keep the mesh alive and unchanged. */
pz_status pz_topology_build(const pz_mesh *mesh, pz_topology **out, pz_ctx *ctx);
void pz_topology_free(pz_topology **topology);

/**
 * Ordered one-ring of v: the neighbour vertices counter-clockwise around the
 * normal. For a boundary vertex the list starts and ends at the two boundary
 * neighbours. Writes up to `capacity` indices to `ring` and returns the full
 * count (call with capacity 0 to size). Isolated vertex: 0.
 */
int32_t pz_topology_vertex_ring(const pz_topology *topology, int32_t v, int32_t *ring, int32_t capacity);

/**
 * Boundary loops: loop_count loops; loop i has the vertices
 * loop_vertices[loop_offsets[i] .. loop_offsets[i+1]-1] in order, walking with
 * the surface on the left (the direction of the boundary half-edges).
 */
typedef struct pz_loops {
    int32_t loop_count;
    int32_t *loop_offsets;   /* loop_count + 1 */
    int32_t *loop_vertices;  /* loop_offsets[loop_count] */
} pz_loops;

pz_status pz_topology_boundary_loops(const pz_topology *topology, pz_loops **out, pz_ctx *ctx);
void pz_loops_free(pz_loops **loops);

/**
 * Connected components over faces (faces sharing an edge or a vertex are
 * connected). face_component: face_count, written by the caller's buffer.
 * Returns the component count (>= 0), or a negative pz_status.
 */
int32_t pz_topology_components(const pz_topology *topology, int32_t *face_component, pz_ctx *ctx);

/**
 * The same on any mesh, without connectivity (so also on one that failed
 * validation): corners with an out-of-range index are skipped, and a face
 * with none in range gets component -1. face_component may be NULL.
 */
int32_t pz_mesh_face_components(const pz_mesh *mesh, int32_t *face_component, pz_ctx *ctx);

/** Topological summary of a mesh. */
typedef struct pz_topology_summary {
    int32_t vertex_count, edge_count, face_count;
    int32_t component_count;
    int32_t boundary_loop_count;
    int32_t euler_characteristic;   /* V - E + F over referenced vertices */
    int32_t genus;                  /* total genus: sum over components of (2 - chi_c - b_c) / 2 */
} pz_topology_summary;

pz_status pz_topology_summarize(const pz_topology *topology, pz_topology_summary *out, pz_ctx *ctx);

/** What a mesh is, valid or not (`panelize info`): counts that are not known are -1. */
typedef struct pz_mesh_description {
    pz_validation validation;
    int manifold;                    /* pz_validation_ok */
    int32_t edge_count;
    int32_t component_count;
    int32_t euler_characteristic;
    int32_t genus;                   /* -1 when the mesh is not a valid manifold */
    int32_t boundary_loop_count;     /* -1 when the mesh is not a valid manifold */
    int32_t *loop_vertex_counts;     /* boundary_loop_count, or NULL */
    double *loop_lengths;            /* boundary_loop_count, mm, or NULL */
    int area_known;                  /* 0 when faces have out-of-range indices */
    double area_mm2;
    double bbox_min[3], bbox_max[3];
    double validate_ms, topology_ms;
} pz_mesh_description;

/**
 * Describes any mesh that parses: validation, then the half-edge topology
 * (components, boundary loops and their lengths, Euler characteristic, genus)
 * when the mesh is a valid manifold, or the counts that need no
 * manifoldness (components, edges, Euler characteristic) when it is not;
 * area and bounding box. O(F log F). Free with pz_mesh_description_clear.
 */
pz_status pz_mesh_describe(const pz_mesh *mesh, pz_mesh_description *out, pz_ctx *ctx);
void pz_mesh_description_clear(pz_mesh_description *description);

/* ------------------------------------------------------------------------ */
/* Geometry (rest pose unless a positions array is passed)                   */
/* ------------------------------------------------------------------------ */

/** Face areas: face_count. */
void pz_geom_face_areas(const pz_mesh *mesh, double *areas);
/** Unit face normals: face_count x 3 (zero vector for a degenerate face). */
void pz_geom_face_normals(const pz_mesh *mesh, double *normals);
/** Total area. */
double pz_geom_total_area(const pz_mesh *mesh);
/**
 * Area-weighted vertex normals: vertex_count x 3, the sum of the (p1 - p0) x
 * (p2 - p0) of the faces around each vertex, scaled to unit length; (0,0,1)
 * where that sum vanishes (an isolated vertex, a degenerate fan). The GLB
 * writers store them as NORMAL.
 */
void pz_geom_vertex_normals(const pz_mesh *mesh, double *normals);
/** Corner angles in radians: face_count x 3, angle at corner k of face f. */
void pz_geom_corner_angles(const pz_mesh *mesh, double *angles);
/**
 * Cotangent weights per edge: edge_count, w_e = (cot a + cot b) / 2 over the
 * one or two angles opposite the edge.
 */
void pz_geom_cotan_weights(const pz_mesh *mesh, const pz_topology *topology, double *weights);
/**
 * Angle defect per vertex (discrete Gaussian curvature times area):
 * 2 pi - sum of angles for interior vertices, pi - sum for boundary vertices.
 */
void pz_geom_angle_defect(const pz_mesh *mesh, const pz_topology *topology, double *defect);
/**
 * Developability error per vertex (wang2008, Eq. 25): |sum of angles - 2 pi|
 * for interior vertices, 0 for boundary vertices.
 */
void pz_geom_developability(const pz_mesh *mesh, const pz_topology *topology, double *e_dev);
/**
 * The point of triangle (a, b, c) closest to p, as barycentric coordinates
 * bary[0..2] (non-negative, summing to 1): Ericson, Real-Time Collision
 * Detection, 5.1.5. A degenerate triangle gives one of its closest points.
 */
void pz_geom_closest_on_triangle(const double *p, const double *a, const double *b, const double *c, double bary[3]);

/* ------------------------------------------------------------------------ */
/* Cutting                                                                   */
/* ------------------------------------------------------------------------ */

/**
 * Splits the mesh along the edges with cut[e] != 0 (edge_count flags from
 * `topology`), duplicating the vertices on the cuts so that faces on the two
 * sides of a cut edge no longer share it. A vertex gets one copy per fan of
 * faces left connected around it. UVs, labels and poses are carried over.
 * *vertex_map (new vertex count) gives the original vertex of every new
 * vertex; faces keep their order. Caller frees *out (pz_mesh_free) and
 * *vertex_map (free). vertex_map may be NULL.
 */
pz_status pz_mesh_cut(const pz_mesh *mesh, const pz_topology *topology, const uint8_t *cut,
                      pz_mesh **out, int32_t **vertex_map, pz_ctx *ctx);

/**
 * Extracts the faces face_ids[0..count-1] as their own mesh (a panel), in that
 * order, with only the vertices they use (in order of first use). UVs, labels
 * and poses are carried over. *vertex_map (panel vertex count) maps panel
 * vertices to original vertices; *face_map (count) maps panel faces to
 * original faces. Either map pointer may be NULL; the caller frees both.
 */
pz_status pz_mesh_extract(const pz_mesh *mesh, const int32_t *face_ids, int32_t count,
                          pz_mesh **out, int32_t **vertex_map, int32_t **face_map, pz_ctx *ctx);

#ifdef __cplusplus
}
#endif

#endif /* PZ_MESH_H */

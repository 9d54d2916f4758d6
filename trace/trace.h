/*
 * trace/trace.h -- the tracing stage: field-aligned paths on the garment that
 * become candidate seams (pietroni2022 Sec. 4.2, after Pietroni et al. 2016,
 * 2021 and Nuvoli et al. 2019).
 *
 *   pz_trace_graph_build      mesh + per-face cross-field -> tracing graph
 *   pz_trace_candidates       graph -> loops and border-to-border paths
 *   pz_trace_distance         graph + paths already in -> per-node distance
 *                             (the M4 stratification: a path occupies the
 *                             nodes of its own axis only, so a path crossing
 *                             it orthogonally is far, a parallel one near)
 *   pz_trace_distance_add     that distance lowered by paths inserted since
 *   pz_trace_paths_tangential two paths meet other than orthogonally?
 *   pz_trace_snap_polyline    a sketched 3D polyline -> a path on mesh edges
 *
 * The tracing graph has four nodes per vertex, node = 4 * vertex + arm, arm k
 * being the vertex's cross arm 0 turned by k * 90 degrees about the vertex
 * normal (arms 0 and 2 form one *axis*, 1 and 3 the other). A link runs
 * from node (v, k) to node (w, k') for a mesh edge v-w whose direction is
 * within the matching angle of arm k at v, k' being the arm of w closest to
 * arm k transported to w. Its weight is the edge length times a penalty that
 * grows with the drift of the edge from the arms at both ends.
 *
 * Paths stay on mesh edges (the mesh is never split); they are smoothed on
 * the edge graph (docs/trace.md says how). A path is a vertex sequence in
 * which consecutive vertices share a mesh edge; each vertex carries the arm
 * the path travels along there.
 *
 * Conventions of mesh/mesh.h: fallible calls take pz_ctx last and return a
 * pz_status; allocating calls take `T **out` freed by the matching
 * pz_*_free(&p) (NULL accepted). Everything is deterministic (no dependence
 * on thread timing).
 *
 * SPDX-License-Identifier: GPL-3.0-or-later
 */
#ifndef PZ_TRACE_H
#define PZ_TRACE_H

#include "mesh/mesh.h"

#ifdef __cplusplus
extern "C" {
#endif

/** What a boundary node's arm does at the border (pietroni2022 Fig. 9). */
enum pz_trace_node_kind {
    PZ_TRACE_NODE_INTERIOR = 0,  /* the vertex is not on the boundary */
    PZ_TRACE_NODE_ENTER = 1,     /* boundary vertex, the arm points into the surface */
    PZ_TRACE_NODE_EXIT = 2,      /* boundary vertex, the arm points out of the surface */
    PZ_TRACE_NODE_ALONG = 3      /* boundary vertex, the arm runs along the boundary */
};

/** The tracing graph. Links in CSR form over nodes 0 .. 4 * vertex_count - 1. */
typedef struct pz_trace_graph {
    int32_t vertex_count;
    int32_t node_count;          /* 4 * vertex_count */
    double *vertex_normals;      /* vertex_count x 3 (unit, area-weighted) */
    double *vertex_arms;         /* vertex_count x 3: arm 0 of each vertex's cross (unit, tangent) */
    uint8_t *node_kind;          /* node_count: enum pz_trace_node_kind */
    int32_t *link_offsets;       /* node_count + 1 */
    int32_t *link_targets;       /* link_offsets[node_count]: target node */
    double *link_weights;        /* link_offsets[node_count]: > 0 */
    /* The 4-sheeted covering (the M4 stratification of pz_trace_distance): every mesh edge v-w in both
     * directions, and the arm of w that arm k of v becomes there: (k + neighbor_shift) % 4. */
    int32_t *neighbor_offsets;   /* vertex_count + 1 */
    int32_t *neighbor_vertices;  /* neighbor_offsets[vertex_count] */
    uint8_t *neighbor_shift;     /* neighbor_offsets[vertex_count]: 0..3 */
    double *neighbor_lengths;    /* neighbor_offsets[vertex_count]: the edge's 3D length */
    double mean_edge_length;
    double match_angle_deg;      /* the options actually used (defaults filled in) */
    double drift_weight;
} pz_trace_graph;

/** Graph options. Zero-initialized = defaults. */
typedef struct pz_trace_graph_options {
    double match_angle_deg;      /* largest angle between an edge and the arm it follows; 0 = 45 */
    double drift_weight;         /* weight of the drift penalty; 0 = the default of docs/trace.md */
} pz_trace_graph_options;

/**
 * Builds the tracing graph of a valid mesh from a per-face cross (one unit arm
 * per face, face_count x 3, e.g. pz_field.directions): the cross is carried
 * to vertices by the 90-degree-invariant average of the incident faces' arms
 * (angle-weighted). A boundary node is ENTER when its arm points into the
 * surface, EXIT when out, ALONG within 45 degrees of a boundary edge
 * (docs/trace.md; a convex corner has no ENTER node).
 * options may be NULL. Errors: PZ_ERR_USAGE (bad options), PZ_ERR_NOMEM.
 */
pz_status pz_trace_graph_build(const pz_mesh *mesh, const pz_topology *topology, const double *face_arms,
                               const pz_trace_graph_options *options, pz_trace_graph **out, pz_ctx *ctx);
void pz_trace_graph_free(pz_trace_graph **graph);
/** A deep copy of a graph into *out (the caller frees it with pz_trace_graph_free); PZ_ERR_NOMEM. */
pz_status pz_trace_graph_copy(const pz_trace_graph *graph, pz_trace_graph **out, pz_ctx *ctx);

/** Arm `arm` (0..3, taken mod 4) of a vertex's cross as a unit 3D vector (zero for an isolated vertex). */
void pz_trace_arm_direction(const pz_trace_graph *graph, int32_t vertex, int arm, double out[3]);

/** The arm (0..3) of the vertex's cross closest to `direction` (projected on the vertex's tangent plane). */
int pz_trace_closest_arm(const pz_trace_graph *graph, int32_t vertex, const double direction[3]);

typedef enum pz_trace_path_kind {
    PZ_TRACE_LOOP = 0,       /* closed: the last vertex links back to the first */
    PZ_TRACE_BORDER = 1,     /* from an entering boundary node to an exiting one */
    PZ_TRACE_SKETCH = 2      /* snapped from a user sketch; open or closed (`closed`) */
} pz_trace_path_kind;

/** One path on mesh edges. */
typedef struct pz_trace_path {
    pz_trace_path_kind kind;
    int closed;                /* 1: vertices[count-1] and vertices[0] share an edge that belongs to the path */
    int32_t vertex_count;
    int32_t *vertices;         /* mesh vertices; consecutive ones share an edge; no vertex twice */
    uint8_t *arms;             /* vertex_count: the arm (0..3) the path travels along at each vertex */
    double length_mm;          /* 3D length (closing edge included when closed) */
    double cost;               /* sum of the link weights (length times drift penalty); a step with no graph
                                  link (sketches, mirrored gaps) costs its length times 1 + drift_weight */
} pz_trace_path;

/** A list of paths. Owns every path's arrays. */
typedef struct pz_trace_paths {
    int32_t path_count;
    pz_trace_path *paths;
} pz_trace_paths;

void pz_trace_paths_free(pz_trace_paths **paths);

/** Candidate sampling options. Zero-initialized = defaults. */
typedef struct pz_trace_candidate_options {
    int32_t border_sources;    /* entering boundary nodes used as sources, subsampled uniformly along the
                                  boundary; 0 = default (docs/trace.md) */
    int32_t interior_sources;  /* interior vertices used as loop sources (both axes each), subsampled
                                  uniformly over the area; 0 = default */
    int loops;                 /* 1 or 0 (default): trace loops; -1: none */
    int border;                /* 1 or 0 (default): trace border-to-border paths; -1: none */
    double max_length_factor;  /* drop paths longer than this times the bounding-box diagonal; 0 = 3 */
    int threads;               /* OpenMP threads; 0 = default. The result does not depend on it. */
    int smooth;                /* 1 (default when 0): drop detours round a triangle (docs/trace.md); -1: keep
                                  the paths as the search found them */
} pz_trace_candidate_options;

/**
 * Samples candidate paths: loops (shortest cycle through an interior source
 * node back to itself) and border-to-border paths (shortest path from an
 * entering boundary source node to any exiting boundary node), each
 * smoothed; duplicates (same vertex set) dropped; sorted by cost then by
 * first vertex, so the order is deterministic. A closed mesh gets loops only,
 * a mesh without interior vertices border paths only. options may be NULL.
 * Returns PZ_OK with zero paths when none can be traced. With ctx->cancel
 * set, the tracing tasks not yet started are skipped and PZ_ERR_CANCELLED
 * is returned (*out NULL).
 */
pz_status pz_trace_candidates(const pz_trace_graph *graph, const pz_mesh *mesh, const pz_topology *topology,
                              const pz_trace_candidate_options *options, pz_trace_paths **out, pz_ctx *ctx);

/**
 * Multi-source Dijkstra from the nodes the given paths occupy (each path
 * vertex: its arm and the opposite arm, same axis), plus, when
 * `from_boundary` is set, the boundary nodes running along the border. It
 * runs on the 4-sheeted covering (neighbor_* above), not on the aligned
 * links: node (v, k) reaches (w, k + shift) over every edge v-w, at the edge's
 * length. So the distance spreads sideways within a path's own axis (a
 * parallel path is near) while the other axis is reached only round a
 * singularity (a path crossing orthogonally is far, INFINITY without one).
 * distance: node_count, written (mm; INFINITY if unreachable).
 * paths may be NULL with path_count 0.
 */
pz_status pz_trace_distance(const pz_trace_graph *graph, const pz_trace_path *paths, int32_t path_count,
                            int from_boundary, double *distance, pz_ctx *ctx);

/**
 * Lowers a distance from pz_trace_distance by more paths: the result is, bit
 * for bit, pz_trace_distance over the earlier paths and these together (same
 * from_boundary), at the cost of the nodes that come nearer. distance:
 * node_count, updated in place.
 */
pz_status pz_trace_distance_add(const pz_trace_graph *graph, const pz_trace_path *paths, int32_t path_count,
                                double *distance, pz_ctx *ctx);

/** Mean of distance[] over the path's nodes (vertex, arm): the farthest-first key of path insertion. */
double pz_trace_path_mean_distance(const pz_trace_path *path, const double *distance);

/**
 * 1 when paths a and b share a vertex at which they travel along the same
 * axis (a tangential meeting, pietroni2022 Sec. 4.2), 0 when they only cross
 * orthogonally or do not meet. A shared vertex that is an end of both
 * (open) paths is ignored: two border paths ending at one boundary vertex.
 * `vertex_count` (the mesh's) sizes a scratch buffer; O(length).
 */
int pz_trace_paths_tangential(const pz_trace_path *a, const pz_trace_path *b, int32_t vertex_count);

/**
 * Snaps a 3D polyline (points: point_count x 3, mm) to mesh edges: each
 * point goes to its nearest vertex, consecutive vertices are joined by the
 * shortest edge path. closed: the polyline returns to its first point.
 * Arms are the graph's arm closest to the path's tangent. tolerance_mm:
 * farthest a point may lie from the mesh (0 = 5 mean edges); beyond it
 * PZ_ERR_DATA naming `name` and the point. Result kind PZ_TRACE_SKETCH.
 */
pz_status pz_trace_snap_polyline(const pz_trace_graph *graph, const pz_mesh *mesh, const pz_topology *topology,
                                 const double *points, int32_t point_count, int closed, double tolerance_mm,
                                 const char *name, pz_trace_path *out, pz_ctx *ctx);

/**
 * A path through the given mesh vertices in order (vertices: count, each in
 * range): consecutive vertices that share no edge are joined by the shortest
 * edge path (3D length), consecutive repeats are dropped, and when a vertex
 * comes back the stretch since its first visit is cut out, so no vertex
 * appears twice. closed: the last vertex is joined back to the first (a
 * closed result with fewer than 3 vertices becomes open). Arms: the graph's
 * arm closest to the path's tangent. Kind PZ_TRACE_SKETCH; length_mm and cost
 * (link weights where the graph has the link, else length times
 * 1 + drift_weight) are filled. *out is overwritten (not freed first).
 * Errors: PZ_ERR_DATA (a vertex out of range, or two vertices in different
 * components), PZ_ERR_NOMEM. Used by pz_trace_snap_polyline and
 * pz_symmetry_mirror_path.
 */
pz_status pz_trace_path_through(const pz_trace_graph *graph, const pz_mesh *mesh, const pz_topology *topology,
                                const int32_t *vertices, int32_t count, int closed, pz_trace_path *out,
                                pz_ctx *ctx);

/** Frees one path's arrays and zeroes it. */
void pz_trace_path_clear(pz_trace_path *path);

/** Deep copy of a path into *out (arrays allocated). PZ_ERR_NOMEM. */
pz_status pz_trace_path_copy(const pz_trace_path *path, pz_trace_path *out, pz_ctx *ctx);

#ifdef __cplusplus
}
#endif

#endif /* PZ_TRACE_H */

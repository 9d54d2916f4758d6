/*
 * segment/internal.h -- the layout state shared by segment/layout.c (set-up,
 * stages, result), segment/labels.c (the panels of the current cuts),
 * segment/evaluate.c (their goals, the evaluation cache, progress),
 * segment/insert.c (path insertion), segment/fallback.c (the cut through a
 * panel's worst vertex), segment/mirror.c (the layout on one half of a
 * symmetric garment) and segment/removal.c (segments, removal, darts).
 * Not part of the public interface.
 *
 * SPDX-License-Identifier: GPL-3.0-or-later
 */
#ifndef PZ_SEGMENT_INTERNAL_H
#define PZ_SEGMENT_INTERNAL_H

#include "segment/segment.h"

/* Why an inserted path is never removed (seg_path.sketch, seg_segment.sketch: bits). */
#define SEG_SKETCH 1   /* a sketched curve */
#define SEG_SEEDED 2   /* options->seed_cuts (its path is empty: the edges are given, not traced) */

/* One inserted path: its copy and whether it is never removed (SEG_SKETCH | SEG_SEEDED bits, 0: removable). */
typedef struct seg_path {
    pz_trace_path path;
    int sketch;
} seg_path;

/* One cached evaluation: key 0 = empty slot. */
typedef struct seg_cache_entry {
    uint64_t key;
    pz_goal_result goals;     /* as evaluated, before any veto */
} seg_cache_entry;

/* The evaluation cache (open addressing, power-of-two capacity); pz_segment_cache to the public. */
struct pz_segment_cache {
    seg_cache_entry *entries;
    int32_t capacity, count;
};

/* A maximal chain of cut edges between nodes (vertices whose cut degree is not 2, or on the border). */
typedef struct seg_segment {
    int32_t edge_count;
    int32_t *edges;        /* edge_count, in walking order */
    int32_t *vertices;     /* edge_count + 1 (closed: last == first) */
    int closed;
    int32_t owner;         /* the latest inserted path that cut one of its edges (insertion order), -1 unknown */
    int sketch;            /* SEG_SKETCH | SEG_SEEDED bits of its edges' paths: never removed when non-zero */
} seg_segment;

typedef struct seg_segments {
    int32_t count;
    seg_segment *items;
} seg_segments;

/* The garment's axes for the pattern maker's preferences (segment/preference.c). */
typedef struct seg_frame {
    double up[3];            /* the garment's vertical (pz_mesh_vertical_axis) */
    double side[3];          /* horizontal, left to right: the symmetry plane's normal, else the area's widest spread */
    double front[3];         /* up x side */
    double centre[3];        /* the area centroid (moved onto the symmetry plane when one is in use) */
    double diagonal;         /* of the bounding box */
    double total_area;
    double mean_radius;      /* area-weighted mean distance of the faces from the vertical axis through centre */
    int torso;               /* 1: 2 pi mean_radius exceeds the height: a body round the axis, whose bands split */
    double *face_area;       /* face_count */
} seg_frame;

typedef struct seg_layout {
    const pz_mesh *mesh;
    const pz_topology *topology;
    const pz_field *field;
    const pz_segment_options *options;
    pz_goal_options goals;
    double accept_strain;    /* (1 - options->strain_margin) * goals.max_strain */
    int threads;
    int32_t max_candidates, max_depth;
    pz_trace_graph *graph;
    int graph_borrowed;      /* 1: graph is options->prebuilt_graph, not this layout's to free */
    pz_symmetry symmetry;
    /* With a mirror plane (segment/mirror.c): the side of each face (0: the half the layout is made on,
     * 1: its mirror image) and the edges between the halves, cut first and removed last (NULL without). */
    uint8_t *face_half;
    uint8_t *edge_plane;
    /* Each panel's mirror panel as of labelling `mirror->labelling` (segment/mirror.c, computed when asked). */
    struct seg_panel_mirrors *mirrors;
    /* Vertex -> incident edges (CSR), for edge lookups and cut degrees. */
    int32_t *vertex_edge_offsets, *vertex_edges;
    uint8_t *edge_cut;
    int32_t *edge_owner;   /* edge_count: the inserted path that first cut it, -1 */
    seg_path *paths;
    int32_t path_count, path_capacity;
    /* Panels of the current cut flags (labels_valid = 0 once a flag changes: seg_label_panels relabels,
     * only around the edges whose flag differs from labelled_cut once `labelled`). */
    int labels_valid, labelled;
    int64_t labelling;       /* counts the labellings (seg_label_panels) */
    uint8_t *labelled_cut;   /* edge_count: edge_cut as of the last labelling */
    int32_t *label_stack, *label_region, *label_spare; /* relabelling scratch (face_count; stack max(F, E)) */
    int32_t *face_panel;
    int32_t panel_count;
    int32_t *panel_offsets;  /* panel_count + 1 */
    int32_t *panel_faces;    /* face_count, each panel's faces increasing */
    pz_goal_result *panel_goals;
    uint8_t *panel_evaluated;
    struct seg_shape *panel_shape;   /* per panel, set with its evaluation (seg_panel_shape) */
    seg_frame frame;
    pz_segment_cache *cache;     /* options->cache, or own_cache */
    pz_segment_cache own_cache;
    struct seg_goal_scratch **goal_scratch; /* threads: evaluation scratch, created when first needed */
    int32_t evaluation_count;
    int32_t removed_early;    /* segments removed during the insertion (before weak candidates) */
    int stopped_unsound;      /* options->stop_when_unsound: S shown out of reach with sound pieces (insert.c) */
    int64_t evaluated_faces;  /* faces over all evaluations: the work budget's measure */
    double mean_edge;
    /* ctx->progress: the fraction reported last, and where the current part of the run ends (seg_progress). */
    double progress, progress_limit;
} seg_layout;

/* layout.c */
int32_t seg_edge_between(const seg_layout *layout, int32_t a, int32_t b);
int32_t seg_cut_degree(const seg_layout *layout, int32_t v);

/* labels.c: relabels the panels after cut flags changed (nothing to do while labels_valid). */
pz_status seg_label_panels(seg_layout *layout, pz_ctx *ctx);

/* evaluate.c */
/* Evaluates the panels with want[p] set (all when want is NULL), from the cache when it can.
 * PZ_ERR_CANCELLED when ctx's cancel flag is set before or during the evaluations (nothing cancelled is
 * cached). */
pz_status seg_evaluate_panels(seg_layout *layout, const uint8_t *want, pz_ctx *ctx);
/* Reports a step of `stage` through options->on_progress and ctx->progress (stage "segment"). */
void seg_progress(seg_layout *layout, const char *stage, pz_ctx *ctx);
/* Starts the part of the run that ends at `limit` (0..1) of the whole, for ctx->progress. */
void seg_progress_part(seg_layout *layout, double limit, const char *stage, pz_ctx *ctx);

/* insert.c */
/* Inserts a path (copied): cuts its edges, owned by it; sketch: SEG_SKETCH | SEG_SEEDED bits (0: removable). */
pz_status seg_add_path(seg_layout *layout, const pz_trace_path *path, int sketch, pz_ctx *ctx);
/* Candidates traced on the submesh of faces[0..count-1] (`sources` border and interior sources), mapped back to
 * the garment's vertices and graph arms; *out NULL when the faces have no topology of their own. */
pz_status seg_trace_faces(seg_layout *layout, const int32_t *faces, int32_t count, int32_t sources,
                          pz_trace_paths **out, pz_ctx *ctx);
pz_status seg_insert_sketches(seg_layout *layout, pz_ctx *ctx);
/* options->seed_cuts: cut from the start, owned by one empty path marked SEG_SEEDED (never removed). */
pz_status seg_insert_seeds(seg_layout *layout, pz_ctx *ctx);
/* Candidates, greedy insertion, recursion into failing panels, then the fallback cuts. */
pz_status seg_insert_all(seg_layout *layout, pz_segment_result *result, pz_ctx *ctx);
/* The graph arm of vertex v closest to direction d (tangent or not). */
uint8_t seg_closest_arm(const pz_trace_graph *graph, int32_t v, const double d[3]);
/* Inserts a path and, with a symmetry plane, its mirror image when it has one. */
pz_status seg_insert_with_mirror(seg_layout *layout, const pz_trace_path *path, pz_ctx *ctx);
/* 1 when panel p lies on the mirrored (positive) side of the plane: its mirror panel gets the cuts. */
int seg_panel_mirrored_side(const seg_layout *layout, int32_t p);

/* goals.c: pz_segment_goals with reusable scratch (seg_goal_scratch_new(face_count); one per thread) and,
 * when face_panel is given (the layout's labels; face_ids must be one whole panel of them), the
 * neighbours' labels read from it rather than flood-filled. The same results, at O(panel) cost. */
typedef struct seg_goal_scratch seg_goal_scratch;
seg_goal_scratch *seg_goal_scratch_new(int32_t face_count);
void seg_goal_scratch_free(seg_goal_scratch *scratch);
pz_status seg_goals(const pz_mesh *mesh, const pz_topology *topology, const uint8_t *edge_cut,
                    const int32_t *face_panel, const int32_t *face_ids, int32_t count, const pz_goal_options *options,
                    seg_goal_scratch *scratch, pz_goal_result *out, pz_ctx *ctx);

/* fallback.c */
#define SEG_FALLBACK_ROUNDS 16
#define SEG_FALLBACK_MAX_CUTS 256
pz_status seg_fallback_cuts(seg_layout *layout, int32_t *inserted, pz_ctx *ctx);

/* mirror.c: the layout made on one half of a mirror-symmetric garment (docs/segment.md, "Symmetry"). */
/* Splits the garment along the plane (face_half, edge_plane) and cuts the edges between the halves as
 * removable paths; nothing without a plane. */
pz_status seg_plane_cut(seg_layout *layout, pz_ctx *ctx);
/* Frees what seg_plane_cut made. */
void seg_mirror_free(seg_layout *layout);
/* Candidates traced on half 0 only (sources: border and interior sources). */
pz_status seg_trace_half(seg_layout *layout, int32_t sources, pz_trace_paths **out, pz_ctx *ctx);
/* 1 when every edge of the path touches a face of `half` (always without halves): a path traced on one half,
 * or its mirror image, that strays into the other would cross the paths there. */
int seg_path_in_half(const seg_layout *layout, const pz_trace_path *path, uint8_t half);
/* The goals panel p fails (its goals evaluated). With halves, a mirror pair across them is one pattern piece: both
 * panels get the failures of both, but for the copy's (half 1) corners, which are its partner's (docs/segment.md,
 * "Symmetry"); their goals must both be evaluated. */
unsigned seg_panel_failures(const seg_layout *layout, int32_t p);
/* The mirror partner of panel p across the halves (-1: none, or p straddles the plane). */
int32_t seg_panel_partner(const seg_layout *layout, int32_t p);
/* Panel p's goals as a pattern piece: its own figures, the pair's failures (seg_panel_failures) and, on half 1, its
 * partner's corners. Returns 1 when p is the copy (on half 1) of its partner. */
int seg_pair_goals(const seg_layout *layout, int32_t p, pz_goal_result *goals);
/* The mirror panel of every panel (-1 none; itself when it straddles the plane): by the faces' mirror faces. */
pz_status seg_mirror_panels(const seg_layout *layout, int32_t *mirror_panel, pz_ctx *ctx);

/* preference.c: the pattern maker's preferences (docs/segment.md, "Where seams go"). */
pz_status seg_frame_init(seg_layout *layout, pz_ctx *ctx);
void seg_frame_clear(seg_frame *frame);
/* What makes a set of faces a band round the body: its area (mm^2) and, for the large ones, how far it wraps
 * round the vertical axis through the frame's centre (degrees), its length round that axis and its height. */
typedef struct seg_shape {
    double area, wrap_deg, girth, height;
} seg_shape;
void seg_faces_shape(const seg_layout *layout, const int32_t *faces, int32_t count, seg_shape *out);
/* 1 for a large set of faces wrapped round the body, longer round it than high (a tube or C round the torso or
 * the hips; not a collar, a cuff, a sleeve or a leg): the layout splits it. */
int seg_shape_is_band(const seg_layout *layout, const seg_shape *shape);
/* Panel p's shape into panel_shape[p] (seg_evaluate_panels calls it), and the test on it. */
void seg_panel_shape(seg_layout *layout, int32_t p);
int seg_panel_is_band(const seg_layout *layout, int32_t p);
/* A candidate's preference, its parts and the score they make (0..1). */
typedef struct seg_preference {
    double vertical;     /* length-weighted mean |tangent . up| */
    double silhouette;   /* length-weighted mean of max(0, 1 - 2 |normal . front|): faces sideways, up or down */
    double centre;       /* length-weighted: on the mid-plane and running in it */
    double widening;     /* loops: the mean girth of the wider side (both sides round the body) over the length */
    double junction;     /* loops: the surface beyond is wider than the loop (0..1, from widening) */
    double alignment;    /* length / cost: 1 on the field's arms */
    int encircles;       /* loops: winds round the vertical axis (round the body, not a limb) */
    int narrow_side;     /* loops round a limb: the limb's side (0: left of the loop's direction) */
    double score;        /* loops: max(junction, silhouette, centre); border paths max(silhouette, centre,
                            vertical / 2) */
} seg_preference;
typedef struct seg_girth_scratch seg_girth_scratch;
seg_girth_scratch *seg_girth_scratch_new(const seg_layout *layout);
void seg_girth_scratch_free(seg_girth_scratch *scratch);
pz_status seg_preference_measure(const seg_layout *layout, const pz_trace_path *path, seg_girth_scratch *scratch,
                                 seg_preference *out, pz_ctx *ctx);
/* One junction per limb: a loop round a limb whose limb side lies inside another junction loop's, with a
 * junction score no higher, loses its junction score (the limb meets the body at the other). */
pz_status seg_junctions_outermost(const seg_layout *layout, const pz_trace_path *const *loops, seg_preference **prefs,
                                  int32_t count, pz_ctx *ctx);

/* removal.c */
pz_status seg_segments_build(const seg_layout *layout, seg_segments *out, pz_ctx *ctx);
void seg_segments_clear(seg_segments *segments);
pz_status seg_remove_pass(seg_layout *layout, int32_t *removed, pz_ctx *ctx);
pz_status seg_dart_pass(seg_layout *layout, int32_t *darts, pz_ctx *ctx);
/* Merges every panel that misses a piece-shape goal (PZ_GOAL_SHAPE) into a neighbour, even when the merged
 * panel then misses the strain goal (docs/segment.md, "Piece shapes"); *merged: the seams removed. */
pz_status seg_merge_slivers(seg_layout *layout, int32_t *merged, pz_ctx *ctx);

/* A set of edges changed together (a segment or part of it, plus its mirror image). */
typedef struct seg_edge_set {
    int32_t count;
    int32_t *edges;
} seg_edge_set;
/*
 * The mirror image of each segment of one seg_segments (built on it; the segments outlive the map): the
 * segment the mirror images of its vertices touch most (removal.c). Without a plane the map is empty and
 * every segment has no mirror. claimed[i] = 1 for a segment of half 1 that is the image of one of half 0:
 * it goes with that one and is not tried on its own.
 */
typedef struct seg_mirror_map {
    const seg_segments *segments;
    int32_t *edge_segment;   /* edge_count: the segment of each cut edge (-1 uncut) */
    int32_t *votes;          /* segment count: zero between calls */
    int32_t *touched;        /* segment count: the segments voted for in one call */
    int32_t *mirror;         /* segment count: the mirror segment, -2 not yet known */
    uint8_t *claimed;        /* segment count (NULL without a plane) */
} seg_mirror_map;
/* 0 when out of memory (nothing to free then). */
int seg_mirror_map_build(const seg_layout *layout, const seg_segments *segments, seg_mirror_map *map);
void seg_mirror_map_free(seg_mirror_map *map);
/* edges[0..n-1] (segment `index` of the map's segments, or a part of it from one end) and, with symmetry, their
 * mirror image's edges that are cut and not sketched. 0: out of memory. The caller frees out->edges. */
int seg_edge_set_make(const seg_layout *layout, seg_mirror_map *map, int32_t index, const int32_t *edges, int32_t n,
                      seg_edge_set *out);
/* Sets the set's cut flags to `cut` (labels become invalid). */
void seg_edge_set_apply(seg_layout *layout, const seg_edge_set *set, uint8_t cut);
/* 1 when, with the set uncut, some inner vertex keeps exactly one cut edge (a stub). */
int seg_leaves_stub(seg_layout *layout, const seg_edge_set *set);
/* 1 when every edge of the segment is cut. */
int seg_all_cut(const seg_layout *layout, const seg_segment *s);

/* budget.c (docs/segment.md, "A piece budget and the trade-off"): merges panels down to options->max_pieces;
 * the merge sequence from the current layout (out->count steps, [0] the layout as it is) until one panel is
 * left, no merge is valid or the worst strain exceeds stop_strain. Both lift the corner bound. */
pz_status seg_budget_merge(seg_layout *layout, pz_segment_result *result, pz_ctx *ctx);
pz_status seg_merge_sequence(seg_layout *layout, double stop_strain, pz_segment_tradeoff *out, pz_ctx *ctx);

#endif

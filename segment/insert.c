/*
 * segment/insert.c -- the insertion half of the automatic layout
 * (pietroni2022 Sec. 4.2; docs/segment.md, "Insertion"): sketches are snapped
 * and inserted first, then seeded cuts. Then, while some panel fails and the
 * budget lasts, among the candidates that cut an uncut edge inside a failing
 * panel and meet no inserted path tangentially, the one farthest from the
 * inserted paths (mean M4 distance, border included) is inserted, with its
 * mirror image when a symmetry plane is in use. When no candidate helps,
 * candidates are traced again on each failing panel's own submesh (one level
 * of recursion per round, at most max_depth rounds); panels that still fail
 * get a cut through their worst vertex (segment/fallback.c).
 *
 * Separate from segment/layout.c (set-up, removal rounds, result) because
 * insertion is one stage with its own data (candidates and their mirror
 * images, the distance field of the inserted paths); it reaches the layout
 * only through segment/internal.h. Cancellation (pz_ctx.cancel) is checked
 * before every insertion round and every failing panel's recursion.
 *
 * SPDX-License-Identifier: GPL-3.0-or-later
 */
#include "segment/internal.h"
#include "core/heap.h"
#include "core/vec.h"

#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

/* Insertions per level at most: a guarantee that the run ends. */
#define MAX_INSERTIONS_PER_LEVEL 64
/* The insertion key is weight x min(distance, far enough), weight = (1 - PREFERENCE_WEIGHT +
 * PREFERENCE_WEIGHT x preference) x (1 + alignment) / 2 (docs/segment.md, "Where seams go"). Far enough:
 * FAR_ENOUGH_WIDTHS times the minimum piece width, at least FAR_ENOUGH_MM (a seam whose mean distance from
 * another is that far keeps the strip between them wider than a sliver where the two waver together), or
 * FAR_ENOUGH_REL of the bounding-box diagonal on a small model. */
#define FAR_ENOUGH_MM 60.0
#define FAR_ENOUGH_WIDTHS 2.5
#define FAR_ENOUGH_REL 0.1
#define PREFERENCE_WEIGHT 0.75
/* A candidate preferred less than this is a seam of last resort: a removal pass comes first. */
#define WEAK_PREFERENCE 0.5
/* A band is split by a path at least this upright (mean |tangent . up|): one across it leaves two bands. */
#define UPRIGHT 0.5
/* A sketch end this near the border or a seam (share of the bounding-box diagonal) is carried on to it:
 * the tolerance within which seamscore.py takes a seam for the designer's. A curve longer than
 * SKETCH_SEAM_LENGTH of the diagonal is a seam (a dart is a fraction of its piece): both its ends reach the
 * nearest border or seam. */
#define SKETCH_REACH 0.03
#define SKETCH_SEAM_LENGTH 0.25

static pz_status nomem(pz_ctx *ctx)
{
    return pz_error(ctx, PZ_ERR_NOMEM, "segment: out of memory");
}

/* A panel the insertion splits: 1 when it misses a goal a split mends (PZ_GOAL_SPLIT_MENDS: not the piece
 * shapes), 2 when it is only a band round the body (segment/preference.c), 0 otherwise. */
static int needs_split(const seg_layout *layout, int32_t p)
{
    return (seg_panel_failures(layout, p) & PZ_GOAL_SPLIT_MENDS) ? 1 : seg_panel_is_band(layout, p) ? 2 : 0;
}

static int32_t failing_panels(const seg_layout *layout)
{
    int32_t failing = 0;
    for (int32_t p = 0; p < layout->panel_count; ++p)
        failing += needs_split(layout, p) != 0;
    return failing;
}

/* Panels that miss a goal a split mends (bands alone get no fallback cut: it would not be a seam a pattern
 * maker draws). */
static int32_t goal_failing_panels(const seg_layout *layout)
{
    int32_t failing = 0;
    for (int32_t p = 0; p < layout->panel_count; ++p)
        failing += (seg_panel_failures(layout, p) & PZ_GOAL_SPLIT_MENDS) != 0;
    return failing;
}

/* options->stop_when_unsound: 1 (and the layout marked stopped) when a panel over S is already under a piece-shape
 * goal or under twice the least piece area (any split of it leaves a piece under that area), or, once the insertion
 * is done (done = 1), when any panel is over S: no split mends the first with sound pieces, and the removal and
 * darts never mend the second. */
static int stop_unsound(seg_layout *layout, int done)
{
    if (!layout->options->stop_when_unsound)
        return 0;
    for (int32_t p = 0; p < layout->panel_count && !layout->stopped_unsound; ++p) {
        unsigned failures = seg_panel_failures(layout, p);
        double share = layout->panel_goals[p].area_share;
        int unsplittable = (failures & PZ_GOAL_SHAPE) || (share > 0 && share < 2 * layout->goals.min_piece_area);
        layout->stopped_unsound = (failures & PZ_GOAL_STRAIN) && (done || unsplittable);
    }
    return layout->stopped_unsound;
}

/* ---------------------------------------------------------------- paths */

static pz_status add_path(seg_layout *layout, const pz_trace_path *path, int sketch, pz_ctx *ctx)
{
    if (layout->path_count == layout->path_capacity) {
        int32_t capacity = layout->path_capacity ? 2 * layout->path_capacity : 16;
        seg_path *grown = realloc(layout->paths, (size_t)capacity * sizeof(seg_path));
        if (!grown)
            return nomem(ctx);
        layout->paths = grown;
        layout->path_capacity = capacity;
    }
    seg_path *slot = layout->paths + layout->path_count;
    memset(slot, 0, sizeof *slot);
    pz_status status = pz_trace_path_copy(path, &slot->path, ctx);
    if (status)
        return status;
    slot->sketch = sketch;
    int32_t index = layout->path_count++;
    int32_t n = path->vertex_count, edges = path->closed ? n : n - 1;
    for (int32_t i = 0; i < edges; ++i) {
        int32_t e = seg_edge_between(layout, path->vertices[i], path->vertices[(i + 1) % n]);
        if (e < 0 || layout->edge_cut[e])
            continue;
        layout->edge_cut[e] = 1;
        layout->labels_valid = 0;
        layout->edge_owner[e] = index;
    }
    return PZ_OK;
}

pz_status seg_add_path(seg_layout *layout, const pz_trace_path *path, int sketch, pz_ctx *ctx)
{
    return add_path(layout, path, sketch, ctx);
}

/*
 * 1 when the path has an uncut interior edge inside a panel to split: one that misses a goal, or, for a path
 * running up and down (`upright`: a horizontal cut across a band leaves two bands), a band.
 */
static int splits_failing(const seg_layout *layout, const pz_trace_path *path, int upright)
{
    const pz_topology *t = layout->topology;
    int32_t n = path->vertex_count, edges = path->closed ? n : n - 1;
    for (int32_t i = 0; i < edges; ++i) {
        int32_t e = seg_edge_between(layout, path->vertices[i], path->vertices[(i + 1) % n]);
        if (e < 0 || layout->edge_cut[e] || t->edge_halfedge[2 * e + 1] < 0)
            continue;
        int why = needs_split(layout, layout->face_panel[pz_he_face(t->edge_halfedge[2 * e])]);
        if (why == 1 || (why == 2 && upright))
            return 1;
    }
    return 0;
}

static int tangential_to_inserted(const seg_layout *layout, const pz_trace_path *path)
{
    for (int32_t i = 0; i < layout->path_count; ++i)
        if (pz_trace_paths_tangential(path, &layout->paths[i].path, layout->mesh->vertex_count))
            return 1;
    return 0;
}

/* Mean signed distance of points (vertex ids) to the plane; 0 without one. */
static double plane_side(const seg_layout *layout, const int32_t *vertices, int32_t n)
{
    const pz_symmetry *s = &layout->symmetry;
    if (!s->found || n <= 0)
        return 0;
    double side = 0;
    for (int32_t j = 0; j < n; ++j) {
        const double *p = layout->mesh->positions + 3 * vertices[j];
        side += pz_vec3_dot(s->normal, p) - s->offset;
    }
    return side / n;
}

/* Paths and panels farther than this (mean edges) on the positive side are left to their mirror images. */
#define MIRRORED_SIDE_EDGES 2.0

int seg_panel_mirrored_side(const seg_layout *layout, int32_t p)
{
    const int32_t *faces = layout->panel_faces + layout->panel_offsets[p];
    int32_t count = layout->panel_offsets[p + 1] - layout->panel_offsets[p];
    if (!layout->symmetry.found)
        return 0;
    double side = 0;
    for (int32_t i = 0; i < count; ++i)
        side += plane_side(layout, layout->topology->faces + 3 * faces[i], 3);
    return side / count > MIRRORED_SIDE_EDGES * layout->mean_edge;
}

pz_status seg_insert_with_mirror(seg_layout *layout, const pz_trace_path *path, pz_ctx *ctx)
{
    pz_status status = add_path(layout, path, 0, ctx);
    if (status || !layout->symmetry.found)
        return status;
    pz_trace_path mirror;
    memset(&mirror, 0, sizeof mirror);
    pz_ctx local;
    pz_ctx_quiet(ctx, &local);
    if (pz_symmetry_mirror_path(&layout->symmetry, layout->graph, layout->mesh, layout->topology, path, &mirror,
                                &local) == PZ_OK)
        status = add_path(layout, &mirror, 0, ctx);
    pz_trace_path_clear(&mirror);
    return status;
}

/* A candidate and its mirror image (mirror.vertex_count 0: none, or the candidate is its own mirror). */
typedef struct seg_candidate {
    pz_trace_path path;
    pz_trace_path mirror;
    int usable;
    seg_preference preference;  /* of path (its mirror image scores alike) */
    double weight;              /* the insertion key's factor: (1 - w0 + w0 score) x alignment */
} seg_candidate;

static void candidates_clear(seg_candidate *candidates, int32_t count)
{
    for (int32_t i = 0; i < count; ++i) {
        pz_trace_path_clear(&candidates[i].path);
        pz_trace_path_clear(&candidates[i].mirror);
    }
    free(candidates);
}

/* Share of a's vertices that b passes too. */
static double shared_fraction(const pz_trace_path *a, const pz_trace_path *b, uint8_t *mark)
{
    for (int32_t i = 0; i < b->vertex_count; ++i)
        mark[b->vertices[i]] = 1;
    int32_t shared = 0;
    for (int32_t i = 0; i < a->vertex_count; ++i)
        shared += mark[a->vertices[i]];
    for (int32_t i = 0; i < b->vertex_count; ++i)
        mark[b->vertices[i]] = 0;
    return a->vertex_count ? (double)shared / a->vertex_count : 0;
}

/*
 * Takes the traced paths into candidates. With a symmetry plane a path is
 * kept when its mean vertex lies on the negative side or on the plane (the
 * sources of one side), and is paired with its mirror image; a path that is
 * (nearly: 80% of its vertices) its own mirror image stays alone; a path
 * that meets its mirror image tangentially otherwise would leave slivers
 * and is dropped.
 */
static pz_status make_candidates(seg_layout *layout, pz_trace_paths *traced, seg_candidate **out, int32_t *count,
                                 pz_ctx *ctx)
{
    *out = NULL;
    *count = 0;
    int32_t n = traced ? traced->path_count : 0;
    seg_candidate *candidates = calloc((size_t)n + 1, sizeof(seg_candidate));
    uint8_t *mark = calloc((size_t)layout->mesh->vertex_count + 1, 1);
    if (!candidates || !mark) {
        free(candidates);
        free(mark);
        return nomem(ctx);
    }
    const pz_symmetry *s = &layout->symmetry;
    seg_girth_scratch *girth = seg_girth_scratch_new(layout);
    if (!girth) {
        free(candidates);
        free(mark);
        return nomem(ctx);
    }
    int32_t kept = 0;
    pz_status status = PZ_OK;
    for (int32_t i = 0; i < n && !status; ++i) {
        pz_trace_path *path = &traced->paths[i];
        if (plane_side(layout, path->vertices, path->vertex_count) > MIRRORED_SIDE_EDGES * layout->mean_edge)
            continue;
        seg_candidate *c = candidates + kept;
        c->path = *path; /* moved: the traced list gives up its arrays */
        memset(path, 0, sizeof *path);
        c->usable = 1;
        if (s->found) {
            pz_ctx local;
            pz_ctx_quiet(ctx, &local);
            if (pz_symmetry_mirror_path(s, layout->graph, layout->mesh, layout->topology, &c->path, &c->mirror,
                                        &local) != PZ_OK) {
                memset(&c->mirror, 0, sizeof c->mirror);
                c->usable = 0;
            } else if (!seg_path_in_half(layout, &c->path, 0) || !seg_path_in_half(layout, &c->mirror, 1)) {
                c->usable = 0; /* with halves, each path stays in its own (segment/mirror.c) */
            } else if (shared_fraction(&c->path, &c->mirror, mark) >= 0.8) {
                pz_trace_path_clear(&c->mirror);
            } else if (pz_trace_paths_tangential(&c->path, &c->mirror, layout->mesh->vertex_count)) {
                c->usable = 0;
            }
        }
        status = seg_preference_measure(layout, &c->path, girth, &c->preference, ctx);
        ++kept;
    }
    /* One junction per limb, then the insertion key's weights. */
    const pz_trace_path **loops = malloc(((size_t)kept + 1) * sizeof *loops);
    seg_preference **prefs = malloc(((size_t)kept + 1) * sizeof *prefs);
    if (!status && (!loops || !prefs))
        status = nomem(ctx);
    for (int32_t i = 0; !status && i < kept; ++i)
        loops[i] = &candidates[i].path, prefs[i] = &candidates[i].preference;
    if (!status)
        status = seg_junctions_outermost(layout, loops, prefs, kept, ctx);
    free(loops);
    free(prefs);
    for (int32_t i = 0; !status && i < kept; ++i)
        candidates[i].weight = (1 - PREFERENCE_WEIGHT + PREFERENCE_WEIGHT * candidates[i].preference.score) *
                               (0.5 + 0.5 * candidates[i].preference.alignment);
    free(mark);
    seg_girth_scratch_free(girth);
    *out = candidates;
    *count = kept;
    if (status) {
        candidates_clear(candidates, kept);
        *out = NULL;
        *count = 0;
    }
    return status;
}

/* 1 when the panels to split all fail on their corners and nothing else a split mends. */
static int corners_only(const seg_layout *layout)
{
    int any = 0;
    for (int32_t p = 0; p < layout->panel_count; ++p) {
        unsigned failures = seg_panel_failures(layout, p) & PZ_GOAL_SPLIT_MENDS;
        if (failures & ~(unsigned)PZ_GOAL_CORNERS)
            return 0;
        any |= failures != 0;
    }
    return any;
}

/* 1 when a piece budget is set, the panels are at least that many and every one is a disk. */
static int budget_reached(const seg_layout *layout)
{
    int32_t budget = layout->options->max_pieces;
    if (budget <= 0 || layout->panel_count < budget)
        return 0;
    for (int32_t p = 0; p < layout->panel_count; ++p)
        if (layout->panel_goals[p].failures & PZ_GOAL_NOT_DISK)
            return 0;
    return 1;
}

/* 1 when candidate c (or its mirror image) splits a panel to split. */
static int helps(const seg_layout *layout, const seg_candidate *c)
{
    int upright = c->preference.vertical >= UPRIGHT;
    return splits_failing(layout, &c->path, upright) ||
           (c->mirror.vertex_count && splits_failing(layout, &c->mirror, upright));
}

/* 1 when some usable candidate helps: otherwise no distance is needed. */
static int any_helpful(const seg_layout *layout, const seg_candidate *candidates, int32_t count)
{
    for (int32_t i = 0; i < count; ++i)
        if (candidates[i].usable && helps(layout, candidates + i))
            return 1;
    return 0;
}

/*
 * Greedy insertion over one pool of candidates (pietroni2022 Sec. 4.2):
 * farthest first among those that split a failing panel and meet no
 * inserted path tangentially. Returns the number inserted in *inserted.
 */
static pz_status insert_greedy(seg_layout *layout, seg_candidate *candidates, int32_t count, int32_t *inserted,
                               pz_ctx *ctx)
{
    *inserted = 0;
    double *distance = malloc((size_t)layout->graph->node_count * sizeof(double) + 1);
    pz_trace_path *in_paths = NULL;
    if (!distance)
        return nomem(ctx);
    pz_status status = PZ_OK;
    /* The distance covers paths[0 .. measured - 1]; each round adds the paths inserted since (-1: none yet). */
    int32_t measured = -1;
    /* Farther than this from every inserted path, a candidate is as good as any other: its preference decides. */
    double far_enough = fmin(fmax(FAR_ENOUGH_MM, FAR_ENOUGH_WIDTHS * layout->goals.min_piece_width_mm),
                             FAR_ENOUGH_REL * layout->frame.diagonal);
    /* Nearer than the minimum piece width (on average) to the paths in, a candidate leaves a sliver. */
    double too_near = layout->goals.min_piece_width_mm;
    int tidied = 0; /* 1: the removal pass before the first weak candidate ran */
    for (int round = 0; round < MAX_INSERTIONS_PER_LEVEL && !status; ++round) {
        if ((status = pz_check_cancel(ctx, "segment")) || (status = seg_evaluate_panels(layout, NULL, ctx)))
            break;
        if (!failing_panels(layout) || stop_unsound(layout, 0) || !any_helpful(layout, candidates, count))
            break;
        free(in_paths);
        in_paths = malloc(((size_t)layout->path_count + 1) * sizeof(pz_trace_path));
        if (!in_paths) {
            status = nomem(ctx);
            break;
        }
        for (int32_t i = 0; i < layout->path_count; ++i)
            in_paths[i] = layout->paths[i].path;
        status = measured < 0 ? pz_trace_distance(layout->graph, in_paths, layout->path_count, 1, distance, ctx)
                              : pz_trace_distance_add(layout->graph, in_paths + measured, layout->path_count - measured,
                                                      distance, ctx);
        measured = layout->path_count;
        if (status)
            break;
        /* Seams a pattern maker draws first (preference >= WEAK_PREFERENCE), by weight x min(distance, far
         * enough); when none helps, the paper's farthest first among the others. */
        int32_t best = -1;
        int best_strong = 0;
        double best_key = -1, best_distance = -1;
        for (int32_t i = 0; i < count; ++i) {
            seg_candidate *c = candidates + i;
            if (!c->usable)
                continue;
            if (!helps(layout, c))
                continue;
            double d = pz_trace_path_mean_distance(&c->path, distance);
            if (d < too_near)
                continue; /* the strip between it and an inserted path would be a sliver */
            int strong = c->preference.score >= WEAK_PREFERENCE;
            double key = c->weight * fmin(d, strong ? far_enough : layout->frame.diagonal);
            if (strong < best_strong || (strong == best_strong && !(key > best_key || (key == best_key && d > best_distance))))
                continue;
            if (tangential_to_inserted(layout, &c->path) ||
                (c->mirror.vertex_count && tangential_to_inserted(layout, &c->mirror))) {
                c->usable = 0; /* inserted paths only grow: it stays tangential */
                continue;
            }
            best = i;
            best_strong = strong;
            best_key = key;
            best_distance = d;
        }
        if (best < 0)
            break;
        /* With a piece budget, the seams beyond the garment's own structure stop at the budget once every
         * panel is a disk: the budget merges down, and strain is what it trades. */
        if (!best_strong && budget_reached(layout))
            break;
        /* Before the first seam a pattern maker would not draw, when panels fail on corners alone, the
         * redundant cuts go (small pieces left between parallel seams, their junctions): they can be why a
         * large panel has too many corners. Once: a pass costs a trial per segment. */
        if (candidates[best].preference.score < WEAK_PREFERENCE && !tidied && corners_only(layout)) {
            int32_t removed = 0;
            tidied = 1;
            status = seg_remove_pass(layout, &removed, ctx);
            layout->removed_early += removed;
            if (!status && removed == 0)
                status = seg_evaluate_panels(layout, NULL, ctx);
            if (status)
                break;
            if (removed > 0)
                continue;
        }
        candidates[best].usable = 0;
        status = add_path(layout, &candidates[best].path, 0, ctx);
        if (!status && candidates[best].mirror.vertex_count)
            status = add_path(layout, &candidates[best].mirror, 0, ctx);
        if (!status)
            status = seg_label_panels(layout, ctx);
        ++*inserted;
        if (!status && (status = seg_evaluate_panels(layout, NULL, ctx)) == PZ_OK)
            seg_progress(layout, "insert", ctx);
    }
    free(in_paths);
    free(distance);
    return status;
}

uint8_t seg_closest_arm(const pz_trace_graph *graph, int32_t v, const double d[3])
{
    const double *n = graph->vertex_normals + 3 * v, *a = graph->vertex_arms + 3 * v;
    double b[3];
    pz_vec3_cross(n, a, b);
    double along = pz_vec3_dot(d, a), across = pz_vec3_dot(d, b);
    if (fabs(along) >= fabs(across))
        return along >= 0 ? 0 : 2;
    return across >= 0 ? 1 : 3;
}

/* Arm k of vertex v of a graph as a 3D direction. */
static void arm_direction(const pz_trace_graph *graph, int32_t v, int k, double d[3])
{
    const double *n = graph->vertex_normals + 3 * v, *a = graph->vertex_arms + 3 * v;
    double b[3];
    pz_vec3_cross(n, a, b);
    double ca = k == 0 ? 1 : k == 2 ? -1 : 0, cb = k == 1 ? 1 : k == 3 ? -1 : 0;
    for (int i = 0; i < 3; ++i)
        d[i] = ca * a[i] + cb * b[i];
}

pz_status seg_trace_faces(seg_layout *layout, const int32_t *faces, int32_t count, int32_t sources, pz_trace_paths **out,
                          pz_ctx *ctx)
{
    *out = NULL;
    pz_mesh *sub = NULL;
    int32_t *vertex_map = NULL, *face_map = NULL;
    pz_topology *topology = NULL;
    pz_trace_graph *graph = NULL;
    double *arms = NULL;
    pz_ctx local;
    pz_ctx_quiet(ctx, &local); /* failures only mean no candidates; a cancel is seen by the next check */
    pz_status status = pz_mesh_extract(layout->mesh, faces, count, &sub, &vertex_map, &face_map, ctx);
    if (status)
        return status;
    /* A panel pinched at a vertex has no topology: it gets no candidates of its own. */
    if (pz_topology_build(sub, &topology, &local) == PZ_OK) {
        arms = malloc((size_t)count * 3 * sizeof(double));
        if (!arms)
            status = nomem(ctx);
        for (int32_t f = 0; arms && f < count; ++f)
            memcpy(arms + 3 * f, layout->field->directions + 3 * face_map[f], 3 * sizeof(double));
        pz_trace_candidate_options options = {0};
        options.border_sources = sources;
        options.interior_sources = sources;
        options.threads = layout->threads;
        if (!status && pz_trace_graph_build(sub, topology, arms, &layout->options->graph, &graph, &local) == PZ_OK &&
            pz_trace_candidates(graph, sub, topology, &options, out, &local) == PZ_OK) {
            for (int32_t i = 0; i < (*out)->path_count; ++i) {
                pz_trace_path *path = &(*out)->paths[i];
                for (int32_t j = 0; j < path->vertex_count; ++j) {
                    double d[3];
                    arm_direction(graph, path->vertices[j], path->arms[j], d);
                    path->vertices[j] = vertex_map[path->vertices[j]];
                    path->arms[j] = seg_closest_arm(layout->graph, path->vertices[j], d);
                }
            }
        }
    }
    pz_trace_graph_free(&graph);
    free(arms);
    pz_topology_free(&topology);
    free(vertex_map);
    free(face_map);
    pz_mesh_free(&sub);
    return status;
}

/* Candidates traced on panel p's own submesh, mapped back to the garment (vertices and arms). */
static pz_status panel_candidates(seg_layout *layout, int32_t p, pz_trace_paths **out, pz_ctx *ctx)
{
    int32_t sources = layout->max_candidates / 4 > 4 ? layout->max_candidates / 4 : 4;
    return seg_trace_faces(layout, layout->panel_faces + layout->panel_offsets[p],
                           layout->panel_offsets[p + 1] - layout->panel_offsets[p], sources, out, ctx);
}

/* One recursion level: candidates on every failing panel's submesh, inserted greedily. */
static pz_status recurse_failing(seg_layout *layout, int32_t *inserted, pz_ctx *ctx)
{
    *inserted = 0;
    int32_t panels = layout->panel_count;
    pz_trace_paths *pooled = calloc(1, sizeof *pooled);
    if (!pooled)
        return nomem(ctx);
    pz_status status = PZ_OK;
    for (int32_t p = 0; p < panels && !status; ++p) {
        if (!needs_split(layout, p))
            continue;
        if ((status = pz_check_cancel(ctx, "segment")))
            break;
        pz_trace_paths *paths = NULL;
        status = panel_candidates(layout, p, &paths, ctx);
        if (status || !paths)
            continue;
        pz_trace_path *grown = realloc(pooled->paths, ((size_t)pooled->path_count + paths->path_count + 1) *
                                                          sizeof(pz_trace_path));
        if (!grown) {
            status = nomem(ctx);
        } else {
            pooled->paths = grown;
            memcpy(grown + pooled->path_count, paths->paths, (size_t)paths->path_count * sizeof(pz_trace_path));
            pooled->path_count += paths->path_count;
            paths->path_count = 0; /* moved */
        }
        pz_trace_paths_free(&paths);
    }
    seg_candidate *candidates = NULL;
    int32_t count = 0;
    if (!status)
        status = make_candidates(layout, pooled, &candidates, &count, ctx);
    if (!status)
        status = insert_greedy(layout, candidates, count, inserted, ctx);
    candidates_clear(candidates, count);
    pz_trace_paths_free(&pooled);
    return status;
}

/* ---------------------------------------------------------------- stages */

/*
 * The vertex nearest to v (shortest edge path, 3D lengths) that is on the border or on a cut edge, within
 * `reach`; -1 when none is. A bounded Dijkstra over the layout's vertex edges (scratch: vertex_count
 * distances at INFINITY, left so).
 */
static int32_t nearest_seam_or_border(const seg_layout *layout, int32_t v, double reach, double *distance,
                                      pz_heap *heap, int32_t *touched)
{
    const pz_topology *t = layout->topology;
    int32_t count = 0, found = -1;
    heap->count = 0;
    distance[v] = 0;
    touched[count++] = v;
    if (!pz_heap_push(heap, 0, v))
        return -1;
    double d;
    int32_t u;
    while (found < 0 && pz_heap_pop(heap, &d, &u)) {
        if (d > distance[u] || d > reach)
            continue;
        if (u != v && (t->vertex_on_boundary[u] || seg_cut_degree(layout, u) > 0)) {
            found = u;
            break;
        }
        for (int32_t i = layout->vertex_edge_offsets[u]; i < layout->vertex_edge_offsets[u + 1]; ++i) {
            int32_t e = layout->vertex_edges[i], h = t->edge_halfedge[2 * e];
            int32_t w = pz_he_from(t, h) == u ? pz_he_to(t, h) : pz_he_from(t, h);
            double step = d + pz_vec3_distance(layout->mesh->positions + 3 * u, layout->mesh->positions + 3 * w);
            if (step < distance[w] && step <= reach) {
                if (distance[w] == INFINITY)
                    touched[count++] = w;
                distance[w] = step;
                if (!pz_heap_push(heap, step, w))
                    break;
            }
        }
    }
    for (int32_t i = 0; i < count; ++i)
        distance[touched[i]] = INFINITY;
    return found;
}

/*
 * A sketched curve's open ends that stop short of the border or of a seam already cut (an earlier sketch)
 * by less than SKETCH_REACH of the bounding-box diagonal are carried on to it: a designer's line drawn from
 * the hem to the neckline means a seam from the hem to the neckline, not a slit that stops 2 cm short of
 * both (which left the panel a slit to be cut round: 7 pieces became 12 on the DiffAvatar T-shirt). An
 * end farther from both stays where it is: a dart's tip. *path is replaced when an end moved.
 */
static pz_status reach_seams(seg_layout *layout, pz_trace_path *path, pz_ctx *ctx)
{
    int32_t n = path->vertex_count;
    if (path->closed || n < 2)
        return PZ_OK;
    int32_t vertex_count = layout->mesh->vertex_count;
    double *distance = malloc((size_t)vertex_count * sizeof(double) + 1);
    int32_t *touched = malloc((size_t)vertex_count * sizeof(int32_t) + 1);
    int32_t *vertices = malloc(((size_t)n + 2) * sizeof(int32_t));
    pz_heap heap = {0};
    pz_status status = PZ_OK;
    if (!distance || !touched || !vertices)
        status = nomem(ctx);
    int32_t ends[2] = {-1, -1};
    /* A long curve is a seam whatever the gap; a short one may be a dart, whose tip stays inside. */
    double reach = path->length_mm > SKETCH_SEAM_LENGTH * layout->frame.diagonal ? INFINITY
                                                                                  : SKETCH_REACH * layout->frame.diagonal;
    for (int32_t i = 0; !status && i < vertex_count; ++i)
        distance[i] = INFINITY;
    for (int k = 0; !status && k < 2; ++k) {
        int32_t end = path->vertices[k ? n - 1 : 0];
        if (!layout->topology->vertex_on_boundary[end] && seg_cut_degree(layout, end) == 0)
            ends[k] = nearest_seam_or_border(layout, end, reach, distance, &heap, touched);
        /* Not back to where the curve starts (a short dart drawn from the hem stays a dart). */
        const double *other = layout->mesh->positions + 3 * path->vertices[k ? 0 : n - 1];
        if (ends[k] >= 0 && pz_vec3_distance(layout->mesh->positions + 3 * ends[k], other) < 0.5 * path->length_mm)
            ends[k] = -1;
    }
    if (!status && (ends[0] >= 0 || ends[1] >= 0)) {
        int32_t count = 0;
        if (ends[0] >= 0)
            vertices[count++] = ends[0];
        memcpy(vertices + count, path->vertices, (size_t)n * sizeof(int32_t));
        count += n;
        if (ends[1] >= 0)
            vertices[count++] = ends[1];
        pz_trace_path reached;
        memset(&reached, 0, sizeof reached);
        pz_ctx local;
        pz_ctx_quiet(ctx, &local);
        if (pz_trace_path_through(layout->graph, layout->mesh, layout->topology, vertices, count, 0, &reached,
                                  &local) == PZ_OK) {
            pz_trace_path_clear(path);
            *path = reached;
        }
    }
    free(distance);
    free(touched);
    free(vertices);
    pz_heap_free(&heap);
    return status;
}

pz_status seg_insert_sketches(seg_layout *layout, pz_ctx *ctx)
{
    const pz_sketch *sketch = layout->options->sketch;
    if (!sketch)
        return PZ_OK;
    for (int32_t i = 0; i < sketch->curve_count; ++i) {
        int32_t first = sketch->curve_offsets[i], n = sketch->curve_offsets[i + 1] - first;
        const double *points = sketch->points + 3 * first;
        const double *last = points + 3 * (n - 1);
        /* A curve whose ends coincide is closed. */
        int closed = n > 2 && fabs(points[0] - last[0]) + fabs(points[1] - last[1]) + fabs(points[2] - last[2]) <
                                  1e-9 * (1 + fabs(points[0]));
        char name[32];
        snprintf(name, sizeof name, "sketch curve %d", (int)i);
        pz_trace_path path;
        memset(&path, 0, sizeof path);
        pz_status status = pz_trace_snap_polyline(layout->graph, layout->mesh, layout->topology, points,
                                                  closed ? n - 1 : n, closed, 0, name, &path, ctx);
        if (!status)
            status = reach_seams(layout, &path, ctx);
        if (!status)
            status = add_path(layout, &path, SEG_SKETCH, ctx);
        pz_trace_path_clear(&path);
        if (status)
            return status;
    }
    return PZ_OK;
}

/* options->seed_cuts: cut from the start, owned by one empty path marked SEG_SEEDED (never removed). */
pz_status seg_insert_seeds(seg_layout *layout, pz_ctx *ctx)
{
    const uint8_t *seeds = layout->options->seed_cuts;
    if (!seeds)
        return PZ_OK;
    pz_trace_path empty;
    memset(&empty, 0, sizeof empty);
    pz_status status = add_path(layout, &empty, SEG_SEEDED, ctx);
    if (status)
        return status;
    int32_t index = layout->path_count - 1;
    for (int32_t e = 0; e < layout->topology->edge_count; ++e) {
        if (!seeds[e] || layout->edge_cut[e])
            continue;
        layout->edge_cut[e] = 1;
        layout->edge_owner[e] = index;
        layout->labels_valid = 0;
    }
    return PZ_OK;
}

pz_status seg_insert_all(seg_layout *layout, pz_segment_result *result, pz_ctx *ctx)
{
    double start = pz_seconds();
    pz_trace_candidate_options options = {0};
    options.border_sources = layout->max_candidates / 2;
    options.interior_sources = layout->max_candidates / 2;
    options.threads = layout->threads;
    pz_trace_paths *traced = NULL;
    /* With a mirror plane the candidates come from one half (segment/mirror.c), mirrored when inserted: half the
     * sources on half the surface, the whole garment's density (twice as many made twice the panels to remove). */
    pz_status status = layout->face_half ? seg_trace_half(layout, layout->max_candidates / 4, &traced, ctx)
                                         : pz_trace_candidates(layout->graph, layout->mesh, layout->topology, &options,
                                                               &traced, ctx);
    seg_candidate *candidates = NULL;
    int32_t count = 0;
    if (!status)
        status = make_candidates(layout, traced, &candidates, &count, ctx);
    pz_trace_paths_free(&traced);
    result->candidate_count = count;
    result->candidates_ms = 1e3 * (pz_seconds() - start);
    start = pz_seconds();
    if (!status)
        seg_progress(layout, "candidates", ctx);
    int32_t inserted = 0;
    if (!status)
        status = insert_greedy(layout, candidates, count, &inserted, ctx);
    candidates_clear(candidates, count);
    for (int32_t depth = 0; !status && depth < layout->max_depth && failing_panels(layout) && !budget_reached(layout) &&
                            !layout->stopped_unsound;
         ++depth) {
        int32_t more = 0;
        status = recurse_failing(layout, &more, ctx);
        if (!more)
            break;
    }
    if (!status && !layout->stopped_unsound && goal_failing_panels(layout) && !budget_reached(layout))
        status = seg_fallback_cuts(layout, &inserted, ctx);
    if (!status && layout->options->stop_when_unsound && !(status = seg_label_panels(layout, ctx)) &&
        !(status = seg_evaluate_panels(layout, NULL, ctx)))
        stop_unsound(layout, 1);
    result->insert_ms = 1e3 * (pz_seconds() - start);
    return status;
}

/*
 * pipeline/tradeoff.c -- pieces against strain (docs/run.md, "Can S be met?" and "The trade-off"):
 *
 *  - the outlook, before the segmentation: estimates of the least strain any layout of sound pieces can
 *    reach, from the poses' own spread and from flattening sample pieces of the smallest sound size; when
 *    they exceed S, one line says so and names an S that would work;
 *  - the trade-off, after the final verdict: the final layout merged down as the piece budget merges
 *    (pz_segment_merge_sequence), each step's panel count and worst strain, from which report.json gives
 *    the pieces each strain goal of the grid needs.
 *
 * SPDX-License-Identifier: GPL-3.0-or-later
 */
#include "pipeline/internal.h"
#include "core/heap.h"
#include "core/vec.h"

#include <math.h>
#include <stdlib.h>
#include <string.h>

const double pz_tradeoff_grid[PZ_TRADEOFF_GRID_COUNT] = {0.03, 0.04, 0.05, 0.07, 0.10, 0.15, 0.20};

/* The merge sequence stops once the worst strain passes the grid's loosest goal. */
#define TRADEOFF_STOP_STRAIN 0.20

/* Sample pieces of the outlook, their size (share of the garment's area) and the percentiles used. */
#define OUTLOOK_SAMPLES 24
#define OUTLOOK_PIECE_SHARE 0.01
#define OUTLOOK_PIECE_QUANTILE 0.90
#define OUTLOOK_POSE_QUANTILE 0.99
/* Directions tried for a triangle's warp (and the weft at right angles) in the pose spread. */
#define OUTLOOK_DIRECTIONS 18

int32_t pz_tradeoff_pieces(const pz_segment_tradeoff *tradeoff, double s)
{
    int32_t pieces = -1;
    for (int32_t i = 0; tradeoff && i < tradeoff->count; ++i)
        if (tradeoff->worst_strain[i] <= s && (pieces < 0 || tradeoff->pieces[i] < pieces))
            pieces = tradeoff->pieces[i];
    return pieces;
}

/* ---------------------------------------------------------------- the trade-off */

/* The edge joining vertices a and b (-1 none): the half-edges round a, both ways from a border. */
static int32_t edge_between(const pz_topology *t, int32_t a, int32_t b)
{
    int32_t first = t->vertex_halfedge[a];
    for (int32_t h = first, guard = 0; h >= 0 && guard < 1 << 16; ++guard) {
        if (pz_he_to(t, h) == b)
            return t->halfedge_edge[h];
        if (pz_he_from(t, pz_he_prev(h)) == b)
            return t->halfedge_edge[pz_he_prev(h)];
        int32_t twin = t->twin[pz_he_prev(h)];
        h = twin;
        if (h == first)
            break;
    }
    for (int32_t h = t->twin[first], guard = 0; h >= 0 && guard < 1 << 16; ++guard) {
        h = pz_he_next(h); /* out of a again, the other way round */
        if (pz_he_to(t, h) == b)
            return t->halfedge_edge[h];
        h = t->twin[h];
    }
    return -1;
}

pz_status pl_measure_tradeoff(pz_result *result, pz_ctx *ctx)
{
    const pz_segment_result *segment = result->segment;
    if (!segment || !result->garment || segment->edge_count <= 0)
        return PZ_OK;
    pz_topology *topology = NULL;
    pz_ctx quiet;
    pz_ctx_quiet(ctx, &quiet);
    if (pz_topology_build(result->garment, &topology, &quiet) != PZ_OK || topology->edge_count != segment->edge_count) {
        pz_topology_free(&topology);
        return PZ_OK; /* not measured: the report says so */
    }
    /* The designer's seams stay: the sketched curves' edges are seeds, never merged away. */
    uint8_t *keep = calloc((size_t)topology->edge_count + 1, 1);
    if (!keep) {
        pz_topology_free(&topology);
        return pz_error(ctx, PZ_ERR_NOMEM, "run: out of memory measuring the trade-off");
    }
    const pz_mesh *mesh = result->garment;
    for (int32_t c = 0; c < segment->curve_count; ++c) {
        const pz_layout_curve *curve = segment->curves + c;
        int32_t n = curve->vertex_count, edges = curve->closed ? n : n - 1;
        for (int32_t i = 0; curve->sketched && i < edges; ++i) {
            int32_t e = edge_between(topology, curve->vertices[i], curve->vertices[(i + 1) % n]);
            if (e >= 0)
                keep[e] = 1;
        }
    }
    pz_segment_options options = result->options.segment;
    options.max_strain = result->options.goals.max_strain;
    options.max_corners = result->options.goals.max_corners;
    memcpy(options.grain, result->grain, sizeof options.grain);
    options.sketch = NULL;
    options.seed_cuts = keep;
    options.vetoed = NULL;
    options.vetoed_count = 0;
    options.cache = NULL;
    options.on_progress = NULL;
    options.max_pieces = 0;
    options.strain_margin = 0;
    /* The merges keep the run's mirror pairs: its plane when the layout used it, none otherwise. */
    options.symmetry = result->symmetry_used ? PZ_SYMMETRY_PLANE : PZ_SYMMETRY_OFF;
    memcpy(options.symmetry_plane, result->symmetry.normal, sizeof result->symmetry.normal);
    options.symmetry_plane[3] = result->symmetry.offset;
    pl_stage(ctx, "export", 0.9, 0.92, "trade-off");
    pz_status status = pz_segment_merge_sequence(mesh, topology, &options, segment->edge_cut, TRADEOFF_STOP_STRAIN,
                                                 &result->tradeoff, &quiet);
    free(keep);
    pz_topology_free(&topology);
    if (status == PZ_ERR_CANCELLED)
        return pz_error(ctx, status, "run: cancelled");
    if (status == PZ_ERR_NOMEM)
        return pz_error(ctx, status, "run: out of memory measuring the trade-off");
    if (status != PZ_OK)
        memset(&result->tradeoff, 0, sizeof result->tradeoff); /* not measured */
    /* The layout itself was flattened for good: its worst strain is the final pattern's, not an estimate. */
    if (result->tradeoff.count > 0 && result->verdict.judged)
        result->tradeoff.worst_strain[0] = result->verdict.worst_strain;
    return PZ_OK;
}

/* ---------------------------------------------------------------- the outlook: poses */

/* The least, over a triangle's warp directions, of the larger spread of warp and weft over the poses. */
static double triangle_pose_spread(const pz_mesh *mesh, int32_t f)
{
    const int32_t *v = mesh->faces + 3 * f;
    const double *p0 = mesh->positions + 3 * v[0];
    double e1[3], e2[3], u[3], n[3], w[3];
    pz_vec3_sub(mesh->positions + 3 * v[1], p0, e1);
    pz_vec3_sub(mesh->positions + 3 * v[2], p0, e2);
    pz_vec3_cross(e1, e2, n);
    double l1 = pz_vec3_norm(e1), area2 = pz_vec3_norm(n);
    if (!(l1 > 0) || !(area2 > 1e-12 * l1 * l1))
        return 0;
    for (int k = 0; k < 3; ++k)
        u[k] = e1[k] / l1;
    pz_vec3_cross(n, u, w);
    pz_vec3_normalize(w);
    /* Rest 2D coordinates of the edges: E = [[e1.u, e2.u], [0, e2.w]]; F_pose = [e1' e2'] E^-1. */
    double a = l1, b = pz_vec3_dot(e2, u), d = pz_vec3_dot(e2, w);
    if (!(fabs(d) > 0))
        return 0;
    double best = INFINITY;
    for (int k = 0; k < OUTLOOK_DIRECTIONS; ++k) {
        double theta = PZ_PI * k / OUTLOOK_DIRECTIONS, worst = 0;
        for (int across = 0; across < 2; ++across) {
            double x = across ? -sin(theta) : cos(theta), y = across ? cos(theta) : sin(theta);
            /* E^-1 (x, y): the combination of e1 and e2 that is this rest direction. */
            double c2 = y / d, c1 = (x - b * c2) / a;
            double lo = INFINITY, hi = 0;
            for (int pose = -1; pose < mesh->pose_count; ++pose) {
                const double *positions = pose < 0 ? mesh->positions : mesh->poses + 3 * (size_t)mesh->vertex_count * pose;
                const double *q0 = positions + 3 * v[0], *q1 = positions + 3 * v[1], *q2 = positions + 3 * v[2];
                double s[3];
                for (int j = 0; j < 3; ++j)
                    s[j] = c1 * (q1[j] - q0[j]) + c2 * (q2[j] - q0[j]);
                double stretch = pz_vec3_norm(s);
                lo = fmin(lo, stretch), hi = fmax(hi, stretch);
            }
            /* One pattern length for all poses: the best leaves (hi - lo) / (hi + lo) in the worst pose. */
            worst = fmax(worst, hi + lo > 0 ? (hi - lo) / (hi + lo) : 0);
        }
        best = fmin(best, worst);
    }
    return best;
}

typedef struct weighted {
    double value, weight;
} weighted;

static int compare_weighted(const void *l, const void *r)
{
    double a = ((const weighted *)l)->value, b = ((const weighted *)r)->value;
    return (a > b) - (a < b);
}

/* The weighted q-quantile (sorts the items). */
static double weighted_quantile(weighted *items, int32_t count, double q)
{
    if (count <= 0)
        return 0;
    qsort(items, (size_t)count, sizeof *items, compare_weighted);
    double total = 0, sum = 0;
    for (int32_t i = 0; i < count; ++i)
        total += items[i].weight;
    for (int32_t i = 0; i < count; ++i) {
        sum += items[i].weight;
        if (sum >= q * total)
            return items[i].value;
    }
    return items[count - 1].value;
}

static double pose_spread(const pz_mesh *mesh, const double *areas)
{
    if (mesh->pose_count <= 0 || !mesh->poses)
        return 0;
    weighted *items = malloc((size_t)mesh->face_count * sizeof *items + 1);
    if (!items)
        return -1;
    for (int32_t f = 0; f < mesh->face_count; ++f)
        items[f] = (weighted){triangle_pose_spread(mesh, f), areas[f]};
    double spread = weighted_quantile(items, mesh->face_count, OUTLOOK_POSE_QUANTILE);
    free(items);
    return spread;
}

/* ---------------------------------------------------------------- the outlook: sample pieces */

/* Farthest-point samples over the vertices (3D distance), from the vertex nearest the centroid. */
static int32_t sample_vertices(const pz_mesh *mesh, int32_t *samples, int32_t wanted)
{
    int32_t n = mesh->vertex_count;
    double *nearest = malloc((size_t)n * sizeof(double) + 1), centre[3] = {0, 0, 0};
    if (!nearest || n <= 0) {
        free(nearest);
        return 0;
    }
    for (int32_t v = 0; v < n; ++v)
        for (int k = 0; k < 3; ++k)
            centre[k] += mesh->positions[3 * v + k] / n;
    int32_t next = 0, count = 0;
    for (int32_t v = 0; v < n; ++v) {
        nearest[v] = pz_vec3_distance(mesh->positions + 3 * v, centre);
        if (nearest[v] < nearest[next])
            next = v;
    }
    for (int32_t v = 0; v < n; ++v)
        nearest[v] = INFINITY;
    while (count < wanted && count < n) {
        samples[count++] = next;
        int32_t farthest = 0;
        for (int32_t v = 0; v < n; ++v) {
            nearest[v] = fmin(nearest[v], pz_vec3_distance(mesh->positions + 3 * v, mesh->positions + 3 * next));
            if (nearest[v] > nearest[farthest])
                farthest = v;
        }
        if (!(nearest[farthest] > 0))
            break;
        next = farthest;
    }
    free(nearest);
    return count;
}

typedef struct piece_scratch {
    double *distance;            /* vertex_count, INFINITY */
    int32_t *settled_order;      /* vertices settled, to reset */
    int32_t *vertex_faces;       /* CSR: faces of each vertex */
    int32_t *vertex_face_offsets;
    uint8_t *face_taken;
    int32_t *faces;
    pz_heap heap;
} piece_scratch;

/*
 * A geodesic disk round vertex `centre` (Dijkstra over edges) grown until its faces (all three vertices
 * reached) cover `area`: into s->faces, *count.
 */
static void grow_piece(const pz_mesh *mesh, const pz_topology *topology, const double *areas, int32_t centre,
                       double area, piece_scratch *s, int32_t *count)
{
    int32_t settled = 0;
    double covered = 0;
    *count = 0;
    s->heap.count = 0;
    s->distance[centre] = 0;
    s->settled_order[settled++] = centre;
    pz_heap_push(&s->heap, 0, centre);
    double d;
    int32_t v;
    while (covered < area && pz_heap_pop(&s->heap, &d, &v)) {
        if (d > s->distance[v])
            continue;
        for (int32_t i = s->vertex_face_offsets[v]; i < s->vertex_face_offsets[v + 1]; ++i) {
            int32_t f = s->vertex_faces[i];
            const int32_t *fv = mesh->faces + 3 * f;
            if (s->face_taken[f])
                continue;
            int reached = 1;
            for (int k = 0; k < 3; ++k)
                reached &= s->distance[fv[k]] <= d;
            if (reached) {
                s->face_taken[f] = 1;
                s->faces[(*count)++] = f;
                covered += areas[f];
            }
            for (int k = 0; k < 3; ++k) {
                double step = d + pz_vec3_distance(mesh->positions + 3 * v, mesh->positions + 3 * fv[k]);
                if (step < s->distance[fv[k]]) {
                    if (s->distance[fv[k]] == INFINITY)
                        s->settled_order[settled++] = fv[k];
                    s->distance[fv[k]] = step;
                    if (!pz_heap_push(&s->heap, step, fv[k]))
                        covered = area; /* out of memory: the piece so far */
                }
            }
        }
    }
    (void)topology;
    for (int32_t i = 0; i < settled; ++i)
        s->distance[s->settled_order[i]] = INFINITY;
    for (int32_t i = 0; i < *count; ++i)
        s->face_taken[s->faces[i]] = 0;
}

static void piece_scratch_free(piece_scratch *s)
{
    free(s->distance), free(s->settled_order), free(s->vertex_faces), free(s->vertex_face_offsets);
    free(s->face_taken), free(s->faces);
    pz_heap_free(&s->heap);
}

static int piece_scratch_init(const pz_mesh *mesh, piece_scratch *s)
{
    memset(s, 0, sizeof *s);
    size_t v = (size_t)mesh->vertex_count, f = (size_t)mesh->face_count;
    s->distance = malloc((v + 1) * sizeof(double));
    s->settled_order = malloc((v + 1) * sizeof(int32_t));
    s->vertex_faces = malloc((3 * f + 1) * sizeof(int32_t));
    s->vertex_face_offsets = calloc(v + 2, sizeof(int32_t));
    s->face_taken = calloc(f + 1, 1);
    s->faces = malloc((f + 1) * sizeof(int32_t));
    if (!s->distance || !s->settled_order || !s->vertex_faces || !s->vertex_face_offsets || !s->face_taken ||
        !s->faces)
        return 0;
    for (size_t i = 0; i < v; ++i)
        s->distance[i] = INFINITY;
    for (size_t i = 0; i < 3 * f; ++i)
        ++s->vertex_face_offsets[mesh->faces[i] + 1];
    for (size_t i = 0; i < v; ++i)
        s->vertex_face_offsets[i + 1] += s->vertex_face_offsets[i];
    int32_t *fill = calloc(v + 1, sizeof(int32_t));
    if (!fill)
        return 0;
    for (size_t i = 0; i < 3 * f; ++i) {
        int32_t vertex = mesh->faces[i];
        s->vertex_faces[s->vertex_face_offsets[vertex] + fill[vertex]++] = (int32_t)(i / 3);
    }
    free(fill);
    return 1;
}

/* The piece strain: the OUTLOOK_PIECE_QUANTILE of sample pieces' worst strain (-1: none flattened). */
static pz_status piece_strain(const pz_mesh *mesh, const pz_topology *topology, const double *areas,
                              const pz_goal_options *goals, double area, pz_strain_outlook *out, pz_ctx *ctx)
{
    int32_t samples[OUTLOOK_SAMPLES];
    int32_t wanted = sample_vertices(mesh, samples, OUTLOOK_SAMPLES);
    piece_scratch scratch;
    memset(&scratch, 0, sizeof scratch);
    uint8_t *no_cuts = calloc((size_t)topology->edge_count + 1, 1);
    weighted strains[OUTLOOK_SAMPLES];
    pz_status status = no_cuts && piece_scratch_init(mesh, &scratch) ? PZ_OK : PZ_ERR_NOMEM;
    int32_t flattened = 0;
    for (int32_t i = 0; i < wanted && status == PZ_OK; ++i) {
        if ((status = pz_check_cancel(ctx, "run")) != PZ_OK)
            break;
        int32_t count = 0;
        grow_piece(mesh, topology, areas, samples[i], area, &scratch, &count);
        pz_goal_result figures;
        pz_ctx quiet;
        pz_ctx_quiet(ctx, &quiet);
        /* A disk grown that large (with a budget) can close round a limb or fold over in its flattening: no
         * piece would be cut so, and its strain says nothing of S (the DiffAvatar shirt at --max-pieces 5
         * reported S = 7.69, the T-shirt at 5 pieces 87.5). Only pieces that flatten as pieces count. */
        if (count > 0 && pz_segment_goals(mesh, topology, no_cuts, scratch.faces, count, goals, &figures, &quiet) == PZ_OK &&
            figures.disk && figures.flipped_triangles == 0 && figures.boundary_self_intersections == 0 &&
            figures.max_abs_strain >= 0)
            strains[flattened++] = (weighted){figures.max_abs_strain, 1};
    }
    out->samples = flattened;
    out->piece_strain = flattened ? weighted_quantile(strains, flattened, OUTLOOK_PIECE_QUANTILE) : -1;
    free(no_cuts);
    piece_scratch_free(&scratch);
    return status;
}

/* ---------------------------------------------------------------- the outlook */

pz_status pl_strain_outlook(const pz_mesh *mesh, const pz_run_options *options, const double grain[3],
                            pz_strain_outlook *out, pz_ctx *ctx)
{
    memset(out, 0, sizeof *out);
    double start = pz_seconds();
    pz_topology *topology = NULL;
    double *areas = malloc((size_t)mesh->face_count * sizeof(double) + 1);
    pz_status status = areas ? pz_topology_build(mesh, &topology, ctx) : PZ_ERR_NOMEM;
    if (status == PZ_OK) {
        pz_geom_face_areas(mesh, areas);
        double total = 0;
        for (int32_t f = 0; f < mesh->face_count; ++f)
            total += areas[f];
        /* The smallest sound piece: 1 % of the area, with a budget too. A geodesic disk of the budget's
         * average piece is no piece a layout cuts (it closes round limbs and folds over: the DiffAvatar shirt at
         * --max-pieces 8 was told "S = 1.32 would work", and its layout met 0.05 with 6 pieces): a warning
         * from it was false. The budget trades strain for pieces anyway (docs/run.md, "Can S be met?"). */
        double area = OUTLOOK_PIECE_SHARE * total;
        out->piece_area_mm2 = area;
        out->pose_spread = pose_spread(mesh, areas);
        pz_goal_options goals = options->goals;
        goals.max_corners = 100000; /* a sample piece is judged on its flattening only */
        memcpy(goals.grain, grain, sizeof goals.grain);
        status = out->pose_spread < 0 ? PZ_ERR_NOMEM : piece_strain(mesh, topology, areas, &goals, area, out, ctx);
    }
    free(areas);
    pz_topology_free(&topology);
    if (status == PZ_ERR_CANCELLED)
        return pz_error(ctx, status, "run: cancelled");
    if (status != PZ_OK)
        return pz_error(ctx, PZ_ERR_NOMEM, "run: out of memory estimating the strain");
    double s = options->goals.max_strain, needed = fmax(out->pose_spread, out->piece_strain);
    out->measured = 1;
    out->reachable = !(needed > s);
    out->suggested_strain = out->reachable ? s : ceil(needed * 100 - 1e-9) / 100;
    out->ms = pz_elapsed_ms(start, pz_seconds());
    if (!out->reachable) {
        char why[160];
        if (out->pose_spread > s)
            snprintf(why, sizeof why, "the poses differ by up to %.3g (warp or weft) on 1 %% of the area",
                     out->pose_spread);
        else
            snprintf(why, sizeof why, "pieces of %.0f cm2 flatten with up to %.3g strain on a tenth of the garment",
                     out->piece_area_mm2 / 100, out->piece_strain);
        pz_note(ctx, "run: S = %g cannot be met with sound pieces: %s; S = %.2f would work", s, why,
                out->suggested_strain);
    }
    return PZ_OK;
}

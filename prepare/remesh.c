/*
 * prepare/remesh.c -- steps 4 and 5 of the preparation (prepare/prepare.c):
 * the edge to remesh to, decimation when the mesh is far too fine
 * (prepare/decimate.c, then CGAL edge collapse), the corners remeshing must
 * keep, and CGAL's isotropic remeshing (Botsch & Kobbelt 2004,
 * prepare/cgal_shim.cpp).
 *
 * The target edge L gives ~20K faces by default: the equilateral edge
 * F = A / (sqrt(3)/4 L^2)  =>  L = sqrt(4 A / (sqrt(3) F)), lengthened by
 * sqrt(1.19) (CGAL's mean edge is shorter than its target), corrected by up
 * to two more passes when the count misses by over 10%. Outline and seams
 * constrained; their corners (turns measured at the scale of the edge) and
 * crease vertices locked.
 *
 * SPDX-License-Identifier: GPL-3.0-or-later
 */
#include "prepare/internal.h"

#include <math.h>
#include <stdlib.h>
#include <string.h>

/* A target edge giving fewer faces than this is longer than the garment allows. */
#define MIN_EXPECTED_FACES 100
#define MAX_EXPECTED_FACES 10000000.0
/* Decimate first when the input has more than DECIMATE_ABOVE x the faces wanted, down to DECIMATE_TO x. */
#define DECIMATE_ABOVE 4
#define DECIMATE_TO 2
#define SQRT3 1.7320508075688772
/* Remesh a second time when the face count misses the one asked for by more than this fraction. */
#define REMESH_FACE_TOLERANCE 0.1
#define REMESH_CORRECTIONS 2
/*
 * CGAL splits edges over 4/3 L and collapses those under 4/5 L, so its edges
 * end up shorter than L on average: remeshing to the equilateral edge of N
 * faces gave 1.19 N (median over the 15 shared garments and surfaces at
 * 2000, 5000 and 20000 faces; 1.05-1.50). The first pass therefore aims at
 * an edge sqrt(1.19) longer, which lands within REMESH_FACE_TOLERANCE
 * mostly, and saves the corrected pass (half of the remeshing time).
 */
#define REMESH_EDGE_SHRINK 1.19
/* An outline vertex farther than this fraction of the Hausdorff bound from its chord at the remeshing scale is kept. */
#define OUTLINE_TOLERANCE 0.25

/* ------------------------------------------------------------------------ */
/* Corners                                                                   */
/* ------------------------------------------------------------------------ */

static void add_line_end(int32_t *degree, int32_t *neighbour, int32_t a, int32_t b)
{
    if (degree[a] < 0) /* on a crease: locked anyway */
        return;
    if (degree[a] < 2)
        neighbour[2 * a + degree[a]] = b;
    ++degree[a];
}

static void add_line_edge(int32_t *degree, int32_t *neighbour, int32_t a, int32_t b)
{
    add_line_end(degree, neighbour, a, b);
    add_line_end(degree, neighbour, b, a);
}

/* Cosine of the angle between the normals of the faces of half-edges g and h. */
static double normal_cos(const pz_cgal_surface *surface, int32_t g, int32_t h)
{
    double n[2][3];
    int32_t faces[2] = {pz_he_face(g), pz_he_face(h)};
    for (int i = 0; i < 2; ++i) {
        const int32_t *c = surface->faces + 3 * (size_t)faces[i];
        prep_face_normal(surface->positions + 3 * (size_t)c[0], surface->positions + 3 * (size_t)c[1],
                         surface->positions + 3 * (size_t)c[2], n[i]);
    }
    double dot = n[0][0] * n[1][0] + n[0][1] * n[1][1] + n[0][2] * n[1][2];
    double lengths = sqrt((n[0][0] * n[0][0] + n[0][1] * n[0][1] + n[0][2] * n[0][2]) *
                          (n[1][0] * n[1][0] + n[1][1] * n[1][1] + n[1][2] * n[1][2]));
    return lengths > 0.0 ? dot / lengths : 1.0;
}

/* The next vertex along a line after `at`, coming from `previous` (at has degree 2). */
static int32_t line_next(const int32_t *neighbour, int32_t previous, int32_t at)
{
    return neighbour[2 * at] == previous ? neighbour[2 * at + 1] : neighbour[2 * at];
}

/*
 * The shape of a line at v (degree 2) at the scale of the remeshing: the
 * cosine of its turn between the points `reach` away along the line on
 * either side (or its ends), and v's distance from the chord between those
 * two points. A jagged line (a seam following mesh edges, a noisy outline)
 * turns at every vertex, but not at the scale of the remeshing; the chord
 * distance is what removing v (and its neighbours within reach) would move
 * the line by.
 */
static void line_shape(const pz_cgal_surface *s, const int32_t *degree, const int32_t *neighbour, int32_t v,
                       double reach, double *cosine, double *deviation)
{
    const double *p = s->positions + 3 * (size_t)v;
    const double *ends[2];
    for (int side = 0; side < 2; ++side) {
        int32_t previous = v, at = neighbour[2 * v + side];
        for (int32_t steps = 0; steps < s->vertex_count && at != v && degree[at] == 2 &&
                                prep_squared_distance3(p, s->positions + 3 * (size_t)at) < reach * reach;
             ++steps) {
            int32_t next = line_next(neighbour, previous, at);
            previous = at;
            at = next;
        }
        ends[side] = s->positions + 3 * (size_t)at;
    }
    double in[3], out[3], chord[3], dot = 0.0, in_length = 0.0, out_length = 0.0, chord_length = 0.0, along = 0.0;
    for (int k = 0; k < 3; ++k) {
        in[k] = p[k] - ends[0][k];
        out[k] = ends[1][k] - p[k];
        chord[k] = ends[1][k] - ends[0][k];
        dot += in[k] * out[k];
        in_length += in[k] * in[k];
        out_length += out[k] * out[k];
        chord_length += chord[k] * chord[k];
        along += in[k] * chord[k];
    }
    double lengths = sqrt(in_length * out_length);
    *cosine = lengths > 0.0 ? dot / lengths : 1.0;
    double t = chord_length > 0.0 ? fmin(1.0, fmax(0.0, along / chord_length)) : 0.0;
    *deviation = 0.0;
    for (int k = 0; k < 3; ++k)
        *deviation += (in[k] - t * chord[k]) * (in[k] - t * chord[k]);
    *deviation = sqrt(*deviation);
}

/* Whether v ranks first (lowest `rank`) among the line vertices closer than `reach` (the lower index on a tie). */
static int sharpest_around(const pz_cgal_surface *s, const int32_t *degree, const int32_t *neighbour,
                           const double *rank, int32_t v, double reach)
{
    const double *p = s->positions + 3 * (size_t)v;
    for (int side = 0; side < 2; ++side) {
        int32_t previous = v, at = neighbour[2 * v + side];
        for (int32_t steps = 0; steps < s->vertex_count && at != v && degree[at] == 2 &&
                                prep_squared_distance3(p, s->positions + 3 * (size_t)at) < reach * reach;
             ++steps) {
            if (rank[at] < rank[v] || (rank[at] == rank[v] && at < v))
                return 0;
            int32_t next = line_next(neighbour, previous, at);
            previous = at;
            at = next;
        }
    }
    return 1;
}

/* Joins the two ends of a crease edge in the union-find `crease` (-1: not on a crease). */
static void join_crease(int32_t *crease, int32_t a, int32_t b)
{
    if (crease[a] < 0)
        crease[a] = a;
    if (crease[b] < 0)
        crease[b] = b;
    pz_union_find_join(crease, a, b);
}

/*
 * Marks (degree -1) the vertices of every connected set of crease edges,
 * except a set that touches the outline or a seam (on_line) and spans less
 * than `edge` (its bounding-box diagonal). Thinning keeps every line vertex,
 * so a strip of the input's fine faces stays beside the lines, and on a
 * scan such a fold is noise: with +-0.4 mm noise, 1.2 mm edges fold by over
 * CREASE_DEGREES here and there, and locking them kept that strip (a
 * 1M-face unwelded bodice to 20000 faces: 95.8% well shaped, 676 of the 833
 * bad faces on the seam; 99.7% without them). Small folds away from the
 * lines are kept: ignoring them too smoothed the shared face scan's
 * features away (10000 faces: 2.66 mm from the input instead of 1.48).
 */
static void lock_long_creases(const pz_cgal_surface *surface, int32_t *crease, const uint8_t *on_line, double edge,
                              int32_t *degree)
{
    int32_t n = surface->vertex_count;
    double *box = malloc(6 * (size_t)n * sizeof(double) + 1); /* per root: lo xyz, hi xyz */
    uint8_t *touches = calloc((size_t)n + 1, 1);              /* per root: a vertex of the set is on a line */
    for (int32_t v = 0; v < n; ++v)
        if (crease[v] >= 0)
            crease[v] = pz_union_find_root(crease, v);
    for (int32_t v = 0; touches && v < n; ++v)
        if (crease[v] >= 0 && on_line[v])
            touches[crease[v]] = 1;
    for (int32_t v = 0; box && v < n; ++v)
        if (crease[v] == v)
            for (int k = 0; k < 3; ++k)
                box[6 * (size_t)v + k] = box[6 * (size_t)v + 3 + k] = surface->positions[3 * (size_t)v + k];
    for (int32_t v = 0; box && v < n; ++v)
        for (int k = 0; k < 3 && crease[v] >= 0; ++k) {
            double *root = box + 6 * (size_t)crease[v], x = surface->positions[3 * (size_t)v + k];
            root[k] = fmin(root[k], x);
            root[3 + k] = fmax(root[3 + k], x);
        }
    for (int32_t v = 0; v < n; ++v) {
        if (crease[v] < 0)
            continue;
        const double *root = box ? box + 6 * (size_t)crease[v] : NULL;
        /* out of memory for the boxes: every crease is kept, the safe side */
        if (!root || !touches || !touches[crease[v]] || prep_squared_distance3(root, root + 3) >= edge * edge)
            degree[v] = -1;
    }
    free(box);
    free(touches);
}

/*
 * Vertices remeshing must keep. Corners of the lines it keeps (outline and
 * seams): ends, junctions (a seam meeting the outline or another seam), and
 * turns sharper than CORNER_DEGREES; collapsing one would cut the corner
 * off the garment. Turns are measured at the scale of half the remeshing
 * edge, and only one vertex per reach is locked (the sharpest): a line that
 * is jagged at the input's scale (a seam following mesh edges, a scanned
 * hem with noise) turns at every vertex, and locking all of them keeps its
 * tiny edges and slivers beside them (a 1M-face bodice with +-0.4 mm noise,
 * every outline turn locked: 97.0% of the faces well shaped, every bad one
 * on the outline). On the outline a vertex is also kept when it lies more
 * than `tolerance` from the chord between the points half an edge away (a
 * tight curve of the hem, which a turn at that scale can miss: remeshing
 * cut 7 mm off the side of a noisy bodice's hem, bound 3.7 mm), and the one
 * kept within a reach is the farthest from its chord, so the outline
 * remeshing leaves stays near the input's. And the vertices of creases
 * (faces folding by more than CREASE_DEGREES: a collar fold, a pressed
 * pleat) whose connected crease edges span at least an edge L
 * (lock_long_creases): tangential relaxation would round them off, by up to
 * half an edge.
 */
#define CORNER_DEGREES 30.0
#define CREASE_DEGREES 60.0
static pz_status find_corners(pz_cgal_surface *surface, double edge, double tolerance, pz_ctx *ctx)
{
    int32_t n = surface->vertex_count;
    int32_t *degree = calloc((size_t)n + 1, sizeof(int32_t));
    int32_t *neighbour = malloc(2 * (size_t)n * sizeof(int32_t) + 1);
    double *rank = malloc((size_t)n * sizeof(double) + 1);
    uint8_t *on_outline = calloc((size_t)n + 1, 1), *on_line = malloc((size_t)n + 1),
            *candidate = calloc((size_t)n + 1, 1);
    int32_t *crease = malloc((size_t)n * sizeof(int32_t) + 1);
    prep_halfedge_key *keys = prep_sorted_halfedges(surface->faces, surface->face_count);
    surface->locked = malloc((size_t)n * sizeof(int32_t) + 1);
    surface->locked_count = 0;
    pz_status status = PZ_OK;
    if (crease)
        memset(crease, 0xff, (size_t)n * sizeof(int32_t));
    if (!degree || !neighbour || !rank || !on_outline || !on_line || !candidate || !crease || !keys ||
        !surface->locked) {
        status = pz_error(ctx, PZ_ERR_NOMEM, "prepare: out of memory finding corners");
        goto done;
    }
    size_t count = 3 * (size_t)surface->face_count;
    double crease_cos = cos(CREASE_DEGREES * 3.14159265358979323846 / 180.0);
    for (size_t begin = 0, end; begin < count; begin = end) {
        end = prep_group_end(keys, count, begin);
        if (end == begin + 1) {
            add_line_edge(degree, neighbour, keys[begin].lo, keys[begin].hi);
            on_outline[keys[begin].lo] = on_outline[keys[begin].hi] = 1;
        }
        else if (end == begin + 2 && normal_cos(surface, keys[begin].halfedge, keys[begin + 1].halfedge) < crease_cos)
            join_crease(crease, keys[begin].lo, keys[begin].hi);
    }
    memcpy(on_line, on_outline, (size_t)n);
    for (int32_t e = 0; e < 2 * surface->edge_count; ++e)
        on_line[surface->edges[e]] = 1;
    lock_long_creases(surface, crease, on_line, edge, degree);
    for (int32_t e = 0; e < surface->edge_count; ++e)
        add_line_edge(degree, neighbour, surface->edges[2 * e], surface->edges[2 * e + 1]);
    double cos_limit = cos(CORNER_DEGREES * 3.14159265358979323846 / 180.0), reach = 0.5 * edge;
    for (int32_t v = 0; v < n; ++v) {
        rank[v] = 1.0;
        if (degree[v] != 2)
            continue;
        double cosine = 1.0, deviation = 0.0;
        line_shape(surface, degree, neighbour, v, reach, &cosine, &deviation);
        candidate[v] = cosine < cos_limit || (on_outline[v] && deviation > tolerance);
        rank[v] = on_outline[v] ? -deviation : cosine; /* lines are all outline or all seam */
    }
    for (int32_t v = 0; v < n; ++v) {
        int corner = degree[v] != 0 && degree[v] != 2; /* ends, junctions and creases (-1) */
        if (degree[v] == 2)
            corner = candidate[v] && sharpest_around(surface, degree, neighbour, rank, v, reach);
        if (corner)
            surface->locked[surface->locked_count++] = v;
    }
done:
    free(degree);
    free(neighbour);
    free(rank);
    free(on_outline);
    free(on_line);
    free(candidate);
    free(crease);
    free(keys);
    return status;
}

/* ------------------------------------------------------------------------ */
/* Remeshing                                                                 */
/* ------------------------------------------------------------------------ */

static pz_cgal_surface surface_view(const pz_mesh *mesh, const prep_edge_list *seams)
{
    pz_cgal_surface view = {mesh->vertex_count, mesh->face_count, seams->count, mesh->positions, mesh->faces,
                            seams->pairs, 0, NULL};
    return view;
}

/* The edge length to remesh to; PZ_ERR_USAGE when it would give too few or too many faces. */
static pz_status choose_edge(const pz_mesh *work, const char *name, const prep_plan *plan, double *edge,
                             double *expected_faces, pz_ctx *ctx)
{
    double area = pz_geom_total_area(work);
    *edge = plan->target_edge > 0.0 ? plan->target_edge : sqrt(4.0 * area / (SQRT3 * plan->target_faces));
    *expected_faces = 4.0 * area / (SQRT3 * *edge * *edge);
    double longest = sqrt(4.0 * area / (SQRT3 * MIN_EXPECTED_FACES));
    if (*expected_faces < MIN_EXPECTED_FACES)
        return pz_error(ctx, PZ_ERR_USAGE,
                        "%s: target edge %g mm is too long for this garment (area %.0f mm^2: about %.0f faces; at "
                        "most %.1f mm)", name, *edge, area, *expected_faces, longest);
    if (*expected_faces > MAX_EXPECTED_FACES)
        return pz_error(ctx, PZ_ERR_USAGE, "%s: target edge %g mm is too short (about %.0f faces)", name, *edge,
                        *expected_faces);
    if (plan->target_edge <= 0.0) /* asked for faces: aim where CGAL lands on them */
        *edge *= sqrt(REMESH_EDGE_SHRINK);
    return PZ_OK;
}

/*
 * Remeshing again when the face count misses `expected` by more than
 * REMESH_FACE_TOLERANCE (faces asked for, not an edge). The count is a
 * steep, uneven function of the edge: CGAL leaves edges between 4/5 and 4/3
 * of the target alone, so from a mesh a little finer than wanted nothing
 * changes until the target passes 5/4 of its edges, then a lot does (a
 * 16K-face bodice: 15892 faces at 11 mm, 13766 at 11.84, 10622 at 12.5).
 * So the edge is first scaled as if faces went as 1 / edge^2, then, once
 * one pass gave too many faces and one too few, taken by the secant
 * through the two in log-log; the pass closest to `expected` is kept.
 * *remeshed holds the first pass on entry and the kept one on return.
 */
static pz_status correct_face_count(const pz_cgal_surface *source, double expected, int iterations, double *edge,
                                    pz_cgal_surface *remeshed, int *passes, pz_ctx *ctx)
{
    double over_edge = 0.0, over_miss = 0.0, under_edge = 0.0, under_miss = 0.0, kept_edge = *edge;
    pz_cgal_surface trial = {0};
    pz_status status = PZ_OK;
    double miss = remeshed->face_count / expected;
    for (int pass = 1; pass <= REMESH_CORRECTIONS && fabs(miss - 1.0) > REMESH_FACE_TOLERANCE; ++pass) {
        if (miss > 1.0)
            over_edge = *edge, over_miss = miss;
        else
            under_edge = *edge, under_miss = miss;
        if (over_edge > 0.0 && under_edge > 0.0 && under_miss > 0.0) /* log miss linear in log edge between them */
            *edge = exp(log(over_edge) + log(under_edge / over_edge) * log(over_miss) / log(over_miss / under_miss));
        else
            *edge *= sqrt(fmax(miss, 0.25));
        if ((status = pz_cgal_remesh(source, *edge, iterations, &trial, ctx)))
            break;
        ++*passes;
        double trial_miss = trial.face_count / expected;
        if (fabs(log(trial_miss)) < fabs(log(remeshed->face_count / expected))) {
            pz_cgal_surface swap = *remeshed;
            *remeshed = trial;
            trial = swap;
            kept_edge = *edge;
        }
        pz_cgal_surface_clear(&trial);
        miss = trial_miss;
    }
    *edge = kept_edge;
    return status;
}

/* Steps 4-5: *out gets the remeshed mesh (positions, faces), *remeshed the surface with its seams. */
pz_status prep_decimate_and_remesh(const pz_mesh *work, const prep_edge_list *seams, const char *name,
                                   const prep_plan *plan, const char *why, pz_mesh **out,
                                   pz_cgal_surface *remeshed, prep_step_state *state, pz_ctx *ctx)
{
    pz_prepare_report *report = state->report;
    double edge = 0.0, expected = 0.0;
    pz_status status = choose_edge(work, name, plan, &edge, &expected, ctx);
    if (status)
        return status;
    pz_cgal_surface source = surface_view(work, seams), thinned = {0}, decimated = {0};
    double started = pz_seconds();
    if (work->face_count > DECIMATE_ABOVE * expected) {
        int32_t wanted = (int32_t)(DECIMATE_TO * expected);
        if ((status = prep_thin_out(&source, wanted, edge / sqrt(REMESH_EDGE_SHRINK), &thinned, ctx)))
            return status;
        source = thinned;
        int32_t thin_faces = thinned.face_count;
        if (thinned.face_count > 1.5 * wanted) {
            status = pz_cgal_decimate(&thinned, wanted, &decimated, ctx);
            pz_cgal_surface_clear(&thinned);
            if (status)
                return status;
            source = decimated;
        }
        report->decimated_faces = source.face_count;
        if (source.face_count == thin_faces)
            prep_step_done(state, PZ_PREPARE_DECIMATE, 1, started, "%d -> %d faces (thinning)", (int)work->face_count,
                           thin_faces);
        else
            prep_step_done(state, PZ_PREPARE_DECIMATE, 1, started, "%d -> %d faces (thinning) -> %d (edge collapse)",
                           (int)work->face_count, thin_faces, (int)source.face_count);
    } else {
        prep_step_done(state, PZ_PREPARE_DECIMATE, 0, started, "not needed: %d faces, at most %.0f wanted",
                       (int)work->face_count, DECIMATE_ABOVE * expected);
    }
    if ((status = pz_check_cancel(ctx, name))) {
        pz_cgal_surface_clear(&thinned);
        pz_cgal_surface_clear(&decimated);
        return status;
    }
    started = pz_seconds();
    status = find_corners(&source, edge, OUTLINE_TOLERANCE * report->hausdorff_bound, ctx);
    if (!status)
        status = pz_cgal_remesh(&source, edge, plan->iterations, remeshed, ctx);
    int passes = 1;
    if (!status && plan->target_edge <= 0.0)
        status = correct_face_count(&source, expected, plan->iterations, &edge, remeshed, &passes, ctx);
    free(source.locked);
    source.locked = NULL;
    pz_cgal_surface_clear(&thinned);
    pz_cgal_surface_clear(&decimated);
    if (status)
        return status;
    if ((status = pz_mesh_create(remeshed->vertex_count, remeshed->face_count, out, ctx)))
        return status;
    memcpy((*out)->positions, remeshed->positions, 3 * (size_t)remeshed->vertex_count * sizeof(double));
    memcpy((*out)->faces, remeshed->faces, 3 * (size_t)remeshed->face_count * sizeof(int32_t));
    report->target_edge = edge;
    prep_step_done(state, PZ_PREPARE_REMESH, 1, started, "edge %.2f mm, %d iterations, %d pass%s: %d faces%s%s", edge,
                   plan->iterations, passes, passes > 1 ? "es" : "", (int)remeshed->face_count, *why ? "; " : "", why);
    return PZ_OK;
}

/*
 * segment/preference.c -- where a pattern maker puts seams (docs/segment.md,
 * "Where seams go"): the garment's frame (its up, side and front axes and its
 * centre), the preference of each candidate path for the greedy insertion
 * (segment/insert.c), and whether a panel is a band wrapped round the body.
 *
 * A candidate's preference (0..1) is the largest of what makes a seam one a
 * pattern maker recognises:
 *  - silhouette: the path runs where the surface faces sideways, up or down,
 *    never to the front or the back (|normal . front| small): side seams,
 *    shoulder seams, the top and the underside of a sleeve: the seams
 *    between a front and a back piece;
 *  - centre: the path runs in the body's mid-plane (the symmetry plane when
 *    one is in use): centre front and centre back;
 *  - junction (loops): the loop is where a tube meets the body: the surface
 *    beyond it on one side (a loop round a limb: armhole, leg) or on both
 *    sides (a loop round the body: a waist) is wider than the loop itself;
 *  - half the verticality for border paths: a vertical seam that is neither
 *    (a princess line) beats a horizontal one.
 * A band round the torso is none of these: it faces front and back, lies off
 * the mid-plane and, round a straight body, is no narrower than its
 * neighbourhood.
 *
 * SPDX-License-Identifier: GPL-3.0-or-later
 */
#include "segment/internal.h"
#include "core/heap.h"
#include "core/vec.h"

#include <math.h>
#include <stdlib.h>
#include <string.h>

/* A panel wrapping further than this round the vertical axis through the centre is a band ... */
#define BAND_WRAP_DEG 240.0
/* ... when it holds more than this share of the garment's area (smaller ones are collars, cuffs and
 * waistbands, which pattern makers do cut as bands) and its length round the axis exceeds its height, on a
 * garment whose body round that axis is a torso (wider round than high: not a lone sleeve or leg, which is
 * cut in one piece). */
#define BAND_AREA_SHARE 0.10
/* Faces nearer the vertical axis than this share of the mean radius have no reliable angle round it. */
#define WRAP_MIN_RADIUS 0.3
#define WRAP_BINS 36
/* A bin of the wrap counts as covered when it holds this share of the panel's area. */
#define WRAP_BIN_SHARE 0.002
/* "On the centre line": within this share of the bounding-box diagonal of the mid-plane. */
#define CENTRE_TOLERANCE 0.03
/* Junctions. Round a limb, the girth of the wider side over the narrower's: a loop at the root of a limb
 * (the body beyond, the limb's tube on this side) scores 1 from JUNCTION_FULL on, 0 up to JUNCTION_NONE
 * (a straight tube: 1). Round the body, the narrower side's girth over the loop's length: both sides
 * must widen (a waist), 0 up to WAIST_NONE, 1 from WAIST_FULL. */
#define JUNCTION_NONE 1.15
#define JUNCTION_FULL 1.45
#define WAIST_NONE 1.05
#define WAIST_FULL 1.3
/* The limb side of a junction keeps at least this share of the loop's length as its girth (a tube). */
#define TUBE_MIN 0.6
/* A side of a loop that ends at a border nearer than this share of the radius is a stub (no girth). */
#define STUB_REACH 0.75
/* A centre seam is optional in most garments (fronts and backs are cut on the fold): it ranks below the
 * seams every garment has (silhouette, junctions: up to 1) and above a vertical line that is neither. */
#define CENTRE_RANK 0.7

static pz_status nomem(pz_ctx *ctx)
{
    return pz_error(ctx, PZ_ERR_NOMEM, "segment: out of memory");
}

/* ---------------------------------------------------------------- the frame */

static void face_centroid(const pz_mesh *mesh, int32_t f, double out[3])
{
    const int32_t *v = mesh->faces + 3 * f;
    for (int k = 0; k < 3; ++k)
        out[k] = (mesh->positions[3 * v[0] + k] + mesh->positions[3 * v[1] + k] + mesh->positions[3 * v[2] + k]) / 3;
}

/* p - centre with its vertical part removed. */
static void horizontal_offset(const seg_frame *frame, const double p[3], double out[3])
{
    double d[3] = {p[0] - frame->centre[0], p[1] - frame->centre[1], p[2] - frame->centre[2]};
    double h = pz_vec3_dot(d, frame->up);
    for (int k = 0; k < 3; ++k)
        out[k] = d[k] - h * frame->up[k];
}

/* side: the horizontal direction of the largest spread of the area (left to right on a body with its arms or
 * legs side by side), or the symmetry plane's normal when one is in use. */
static void choose_side(const seg_layout *layout, seg_frame *frame)
{
    double a[3] = {1, 0, 0}, b[3];
    if (fabs(frame->up[0]) > 0.9)
        a[0] = 0, a[1] = 1;
    double h = pz_vec3_dot(a, frame->up);
    for (int k = 0; k < 3; ++k)
        a[k] -= h * frame->up[k];
    pz_vec3_normalize(a);
    pz_vec3_cross(frame->up, a, b);
    if (layout->symmetry.found) {
        double n[3] = {layout->symmetry.normal[0], layout->symmetry.normal[1], layout->symmetry.normal[2]};
        double along = pz_vec3_dot(n, frame->up);
        for (int k = 0; k < 3; ++k)
            n[k] -= along * frame->up[k];
        if (pz_vec3_norm(n) > 0.5) {
            pz_vec3_normalize(n);
            memcpy(frame->side, n, sizeof frame->side);
            return;
        }
    }
    /* The 2 x 2 covariance in the basis (a, b), area-weighted. */
    double saa = 0, sab = 0, sbb = 0;
    for (int32_t f = 0; f < layout->mesh->face_count; ++f) {
        double c[3], q[3];
        face_centroid(layout->mesh, f, c);
        horizontal_offset(frame, c, q);
        double x = pz_vec3_dot(q, a), y = pz_vec3_dot(q, b), w = frame->face_area[f];
        saa += w * x * x, sab += w * x * y, sbb += w * y * y;
    }
    double angle = 0.5 * atan2(2 * sab, saa - sbb); /* the major axis */
    for (int k = 0; k < 3; ++k)
        frame->side[k] = cos(angle) * a[k] + sin(angle) * b[k];
    pz_vec3_normalize(frame->side);
}

pz_status seg_frame_init(seg_layout *layout, pz_ctx *ctx)
{
    seg_frame *frame = &layout->frame;
    const pz_mesh *mesh = layout->mesh;
    frame->face_area = malloc((size_t)mesh->face_count * sizeof(double) + 1);
    if (!frame->face_area)
        return nomem(ctx);
    pz_geom_face_areas(mesh, frame->face_area);
    pz_mesh_vertical_axis(mesh, frame->up);
    double lo[3], hi[3];
    pz_mesh_bbox(mesh, lo, hi);
    frame->diagonal = sqrt((hi[0] - lo[0]) * (hi[0] - lo[0]) + (hi[1] - lo[1]) * (hi[1] - lo[1]) +
                           (hi[2] - lo[2]) * (hi[2] - lo[2]));
    frame->total_area = 0;
    memset(frame->centre, 0, sizeof frame->centre);
    for (int32_t f = 0; f < mesh->face_count; ++f) {
        double c[3];
        face_centroid(mesh, f, c);
        for (int k = 0; k < 3; ++k)
            frame->centre[k] += frame->face_area[f] * c[k];
        frame->total_area += frame->face_area[f];
    }
    for (int k = 0; k < 3 && frame->total_area > 0; ++k)
        frame->centre[k] /= frame->total_area;
    if (layout->symmetry.found) {
        /* The mid-plane is the symmetry plane: the centre moves onto it. */
        double off = pz_vec3_dot(layout->symmetry.normal, frame->centre) - layout->symmetry.offset;
        for (int k = 0; k < 3; ++k)
            frame->centre[k] -= off * layout->symmetry.normal[k];
    }
    choose_side(layout, frame);
    pz_vec3_cross(frame->up, frame->side, frame->front);
    pz_vec3_normalize(frame->front);
    double radius = 0;
    for (int32_t f = 0; f < mesh->face_count; ++f) {
        double c[3], q[3];
        face_centroid(mesh, f, c);
        horizontal_offset(frame, c, q);
        radius += frame->face_area[f] * pz_vec3_norm(q);
    }
    frame->mean_radius = frame->total_area > 0 ? radius / frame->total_area : 0;
    /* A body round the vertical axis wider round than high (a torso, hips): a lone sleeve or leg is not one. */
    frame->torso = 2 * PZ_PI * frame->mean_radius > fabs(pz_vec3_dot(hi, frame->up) - pz_vec3_dot(lo, frame->up));
    return PZ_OK;
}

void seg_frame_clear(seg_frame *frame)
{
    free(frame->face_area);
    frame->face_area = NULL;
}

/* ---------------------------------------------------------------- bands */

/* How far (degrees) the faces wrap round the vertical axis through the centre, and their mean radius. */
static double wrap_degrees(const seg_layout *layout, const int32_t *faces, int32_t count, double area,
                           double *mean_radius)
{
    const seg_frame *frame = &layout->frame;
    double bins[WRAP_BINS] = {0}, radius = 0;
    for (int32_t i = 0; i < count; ++i) {
        double c[3], q[3];
        face_centroid(layout->mesh, faces[i], c);
        horizontal_offset(frame, c, q);
        double r = pz_vec3_norm(q), w = frame->face_area[faces[i]];
        radius += w * r;
        if (r < WRAP_MIN_RADIUS * frame->mean_radius)
            continue;
        double angle = atan2(pz_vec3_dot(q, frame->front), pz_vec3_dot(q, frame->side));
        int bin = (int)floor((angle + PZ_PI) / (2 * PZ_PI) * WRAP_BINS);
        bins[bin < 0 ? 0 : bin >= WRAP_BINS ? WRAP_BINS - 1 : bin] += w;
    }
    *mean_radius = area > 0 ? radius / area : 0;
    /* The longest run of uncovered bins, round the circle. */
    int longest = 0, run = 0;
    for (int i = 0; i < 2 * WRAP_BINS; ++i) {
        run = bins[i % WRAP_BINS] <= WRAP_BIN_SHARE * area ? run + 1 : 0;
        longest = run > longest ? run : longest;
    }
    if (longest > WRAP_BINS)
        longest = WRAP_BINS;
    return 360.0 * (WRAP_BINS - longest) / WRAP_BINS;
}

void seg_faces_shape(const seg_layout *layout, const int32_t *faces, int32_t count, seg_shape *out)
{
    memset(out, 0, sizeof *out);
    double low = INFINITY, high = -INFINITY;
    for (int32_t i = 0; i < count; ++i)
        out->area += layout->frame.face_area[faces[i]];
    if (!(out->area > BAND_AREA_SHARE * layout->frame.total_area))
        return; /* too small to be a band: the rest is not needed */
    for (int32_t i = 0; i < count; ++i) {
        double c[3];
        face_centroid(layout->mesh, faces[i], c);
        double h = pz_vec3_dot(c, layout->frame.up);
        low = fmin(low, h), high = fmax(high, h);
    }
    double radius = 0;
    out->wrap_deg = wrap_degrees(layout, faces, count, out->area, &radius);
    out->girth = 2 * PZ_PI * radius * out->wrap_deg / 360;
    out->height = high - low;
}

int seg_shape_is_band(const seg_layout *layout, const seg_shape *shape)
{
    return layout->frame.torso && shape->wrap_deg > BAND_WRAP_DEG && shape->area > BAND_AREA_SHARE * layout->frame.total_area &&
           shape->girth > shape->height;
}

int seg_panel_is_band(const seg_layout *layout, int32_t p)
{
    return seg_shape_is_band(layout, layout->panel_shape + p);
}

void seg_panel_shape(seg_layout *layout, int32_t p)
{
    seg_faces_shape(layout, layout->panel_faces + layout->panel_offsets[p],
                    layout->panel_offsets[p + 1] - layout->panel_offsets[p], layout->panel_shape + p);
}

/* ---------------------------------------------------------------- junctions */

struct seg_girth_scratch {
    double *distance;      /* face_count, INFINITY when not reached */
    int8_t *side;          /* face_count */
    uint8_t *blocked;      /* edge_count: the loop's edges */
    int32_t *touched;      /* faces reached, to reset */
    int32_t *order;        /* faces settled, nearest first */
    pz_heap heap;
};

seg_girth_scratch *seg_girth_scratch_new(const seg_layout *layout)
{
    seg_girth_scratch *s = calloc(1, sizeof *s);
    int32_t faces = layout->topology->face_count, edges = layout->topology->edge_count;
    if (!s)
        return NULL;
    s->distance = malloc(((size_t)faces + 1) * sizeof(double));
    s->side = malloc((size_t)faces + 1);
    s->blocked = calloc((size_t)edges + 1, 1);
    s->touched = malloc(((size_t)faces + 1) * sizeof(int32_t));
    s->order = malloc(((size_t)faces + 1) * sizeof(int32_t));
    if (!s->distance || !s->side || !s->blocked || !s->touched || !s->order) {
        seg_girth_scratch_free(s);
        return NULL;
    }
    for (int32_t f = 0; f < faces; ++f)
        s->distance[f] = INFINITY;
    return s;
}

void seg_girth_scratch_free(seg_girth_scratch *scratch)
{
    if (!scratch)
        return;
    free(scratch->distance);
    free(scratch->side);
    free(scratch->blocked);
    free(scratch->touched);
    free(scratch->order);
    pz_heap_free(&scratch->heap);
    free(scratch);
}

static int reach(seg_girth_scratch *s, int32_t *touched_count, int32_t f, double d, int side)
{
    if (!(d < s->distance[f]))
        return 1;
    if (s->distance[f] == INFINITY)
        s->touched[(*touched_count)++] = f;
    s->distance[f] = d;
    s->side[f] = (int8_t)side;
    return pz_heap_push(&s->heap, d, f);
}

/*
 * The mean girth of the surface on each side of a closed loop within `radius` of it (over faces, distances
 * between face centroids, never across the loop): the area reached on that side over the farthest distance
 * reached there (radius, or less where the side ends at a border first). girth[0] is the side on the left of
 * the loop's direction. 0 when out of memory.
 */
static int loop_girths(const seg_layout *layout, const pz_trace_path *loop, double radius, seg_girth_scratch *s,
                       double girth[2])
{
    const pz_topology *t = layout->topology;
    const pz_mesh *mesh = layout->mesh;
    int32_t n = loop->vertex_count, touched = 0;
    double area[2] = {0, 0}, farthest[2] = {0, 0};
    int ok = 1;
    for (int32_t i = 0; i < n; ++i) {
        int32_t e = seg_edge_between(layout, loop->vertices[i], loop->vertices[(i + 1) % n]);
        if (e >= 0)
            s->blocked[e] = 1;
    }
    s->heap.count = 0;
    for (int32_t i = 0; i < n && ok; ++i) {
        int32_t e = seg_edge_between(layout, loop->vertices[i], loop->vertices[(i + 1) % n]);
        if (e < 0)
            continue;
        const double *a = mesh->positions + 3 * loop->vertices[i], *b = mesh->positions + 3 * loop->vertices[(i + 1) % n];
        double mid[3] = {0.5 * (a[0] + b[0]), 0.5 * (a[1] + b[1]), 0.5 * (a[2] + b[2])};
        for (int k = 0; k < 2 && ok; ++k) {
            int32_t h = t->edge_halfedge[2 * e + k];
            if (h < 0)
                continue;
            /* The half-edge running along the loop's direction has the left side's face. */
            int side = pz_he_from(t, h) == loop->vertices[i] ? 0 : 1;
            double c[3];
            face_centroid(mesh, pz_he_face(h), c);
            ok = reach(s, &touched, pz_he_face(h), pz_vec3_distance(c, mid), side);
        }
    }
    /* Faces in the order of their distance: the distances of each side's faces, to split them in halves after. */
    double d;
    int32_t f, popped = 0;
    while (ok && pz_heap_pop(&s->heap, &d, &f)) {
        if (d > s->distance[f] || d > radius)
            continue;
        s->order[popped++] = f;
        farthest[s->side[f]] = fmax(farthest[s->side[f]], d);
        double c[3];
        face_centroid(mesh, f, c);
        for (int k = 0; k < 3 && ok; ++k) {
            int32_t g = t->twin[3 * f + k];
            if (g < 0 || s->blocked[t->halfedge_edge[3 * f + k]])
                continue;
            double cg[3];
            face_centroid(mesh, pz_he_face(g), cg);
            ok = reach(s, &touched, pz_he_face(g), d + pz_vec3_distance(c, cg), s->side[f]);
        }
    }
    /* The girth at the outer half of each side's reach: its area there over the half's width (a straight tube:
     * the loop's length; beyond a loop round a hole in a plane: length + 3 pi r / 2 at r = radius). */
    for (int32_t i = 0; i < popped; ++i) {
        int32_t g = s->order[i], side = s->side[g];
        if (s->distance[g] >= 0.5 * farthest[side])
            area[side] += layout->frame.face_area[g];
    }
    for (int32_t i = 0; i < touched; ++i)
        s->distance[s->touched[i]] = INFINITY;
    for (int32_t i = 0; i < n; ++i) {
        int32_t e = seg_edge_between(layout, loop->vertices[i], loop->vertices[(i + 1) % n]);
        if (e >= 0)
            s->blocked[e] = 0;
    }
    /* A side that ends at a border before the radius is a stub of the tube: its band is too narrow to tell a
     * girth (the last row of faces is cut by the border), and a stub neither widens nor narrows. */
    for (int k = 0; k < 2; ++k)
        girth[k] = farthest[k] < STUB_REACH * radius ? -1 : area[k] / fmax(0.5 * farthest[k], layout->mean_edge);
    return ok;
}

/* A closed path's length without its staircase: the mean over the phases of the polygon through every
 * LENGTH_STRIDE-th vertex (a path on mesh edges at an angle to them is 10-20 % longer than the curve it follows). */
#define LENGTH_STRIDE 4
static double smooth_loop_length(const seg_layout *layout, const pz_trace_path *loop)
{
    int32_t n = loop->vertex_count;
    if (n < 3 * LENGTH_STRIDE)
        return loop->length_mm;
    double sum = 0;
    for (int32_t i = 0; i < n; ++i)
        sum += pz_vec3_distance(layout->mesh->positions + 3 * loop->vertices[i],
                                layout->mesh->positions + 3 * loop->vertices[(i + LENGTH_STRIDE) % n]);
    return sum / LENGTH_STRIDE;
}

/* The number of turns a loop makes round the vertical axis through the centre. */
static double winding(const seg_layout *layout, const pz_trace_path *loop)
{
    double turn = 0, prev[3];
    int32_t n = loop->vertex_count;
    horizontal_offset(&layout->frame, layout->mesh->positions + 3 * loop->vertices[n - 1], prev);
    for (int32_t i = 0; i < n; ++i) {
        double q[3], cross[3];
        horizontal_offset(&layout->frame, layout->mesh->positions + 3 * loop->vertices[i], q);
        pz_vec3_cross(prev, q, cross);
        turn += atan2(pz_vec3_dot(cross, layout->frame.up), pz_vec3_dot(prev, q));
        memcpy(prev, q, sizeof prev);
    }
    return turn / (2 * PZ_PI);
}

static double ramp(double x, double lo, double hi)
{
    return x <= lo ? 0 : x >= hi ? 1 : (x - lo) / (hi - lo);
}

/* ---------------------------------------------------------------- a candidate's preference */

pz_status seg_preference_measure(const seg_layout *layout, const pz_trace_path *path, seg_girth_scratch *scratch,
                                 seg_preference *out, pz_ctx *ctx)
{
    memset(out, 0, sizeof *out);
    const seg_frame *frame = &layout->frame;
    const double *normals = layout->graph->vertex_normals;
    int32_t n = path->vertex_count, edges = path->closed ? n : n - 1;
    double length = 0, vertical = 0, silhouette = 0, centre = 0;
    double tolerance = CENTRE_TOLERANCE * frame->diagonal;
    for (int32_t i = 0; i < edges; ++i) {
        int32_t a = path->vertices[i], b = path->vertices[(i + 1) % n];
        const double *pa = layout->mesh->positions + 3 * a, *pb = layout->mesh->positions + 3 * b;
        double t[3] = {pb[0] - pa[0], pb[1] - pa[1], pb[2] - pa[2]};
        double l = pz_vec3_norm(t);
        if (!(l > 0))
            continue;
        for (int k = 0; k < 3; ++k)
            t[k] /= l;
        double normal[3] = {normals[3 * a] + normals[3 * b], normals[3 * a + 1] + normals[3 * b + 1],
                            normals[3 * a + 2] + normals[3 * b + 2]};
        pz_vec3_normalize(normal);
        double mid[3] = {0.5 * (pa[0] + pb[0]) - frame->centre[0], 0.5 * (pa[1] + pb[1]) - frame->centre[1],
                         0.5 * (pa[2] + pb[2]) - frame->centre[2]};
        length += l;
        vertical += l * fabs(pz_vec3_dot(t, frame->up));
        silhouette += l * fmax(0, 1 - 2 * fabs(pz_vec3_dot(normal, frame->front)));
        /* On the mid-plane and running in it (a loop crossing the plane scores only its crossing edges). */
        centre += l * fmax(0, 1 - fabs(pz_vec3_dot(mid, frame->side)) / tolerance) *
                  (1 - fabs(pz_vec3_dot(t, frame->side)));
    }
    if (!(length > 0))
        return PZ_OK;
    out->vertical = vertical / length;
    out->silhouette = silhouette / length;
    out->centre = centre / length;
    out->alignment = path->cost > 0 ? fmin(1, path->length_mm / path->cost) : 1;
    if (path->closed && n >= 3) {
        double girth[2];
        double radius = fmin(fmax(path->length_mm / (2 * PZ_PI), 2 * layout->mean_edge), 0.25 * frame->diagonal);
        if (!loop_girths(layout, path, radius, scratch, girth))
            return nomem(ctx);
        out->encircles = fabs(winding(layout, path)) > 0.5;
        double length = smooth_loop_length(layout, path);
        for (int k = 0; k < 2; ++k)
            girth[k] = girth[k] < 0 ? length : girth[k];
        if (out->encircles) {
            /* Round the body, both sides must widen: a waist. */
            out->widening = fmin(girth[0], girth[1]) / length;
            out->junction = ramp(out->widening, WAIST_NONE, WAIST_FULL);
        } else {
            /* Round a limb: the body beyond is wider than the limb's tube on this side, and the limb is a tube
             * (its girth near the loop's length; a loop that cuts off a cap narrowing fast is no junction). */
            double narrow = fmin(girth[0], girth[1]);
            out->narrow_side = girth[0] <= girth[1] ? 0 : 1;
            out->widening = fmax(girth[0], girth[1]) / fmax(narrow, layout->mean_edge);
            out->junction = narrow >= TUBE_MIN * length ? ramp(out->widening, JUNCTION_NONE, JUNCTION_FULL) : 0;
        }
        out->score = fmax(out->junction, fmax(out->silhouette, CENTRE_RANK * out->centre));
    } else {
        out->score = fmax(0.5 * out->vertical, fmax(out->silhouette, CENTRE_RANK * out->centre));
    }
    return PZ_OK;
}

/* ---------------------------------------------------------------- one junction per limb */

/*
 * The faces on one side of a closed loop (0: the left of its direction), flooded across every edge but the
 * loop's, into `mark` (face_count bits); the side's area into *area. 0 when out of memory.
 */
static int flood_side(const seg_layout *layout, const pz_trace_path *loop, int side, uint8_t *mark, double *area,
                      int32_t *stack, uint8_t *blocked)
{
    const pz_topology *t = layout->topology;
    int32_t n = loop->vertex_count, top = 0;
    *area = 0;
    for (int32_t i = 0; i < n; ++i) {
        int32_t e = seg_edge_between(layout, loop->vertices[i], loop->vertices[(i + 1) % n]);
        if (e >= 0)
            blocked[e] = 1;
    }
    for (int32_t i = 0; i < n; ++i) {
        int32_t e = seg_edge_between(layout, loop->vertices[i], loop->vertices[(i + 1) % n]);
        for (int k = 0; e >= 0 && k < 2; ++k) {
            int32_t h = t->edge_halfedge[2 * e + k];
            if (h < 0 || (pz_he_from(t, h) == loop->vertices[i] ? 0 : 1) != side)
                continue;
            int32_t f = pz_he_face(h);
            if (!(mark[f >> 3] & (1u << (f & 7))))
                mark[f >> 3] |= (uint8_t)(1u << (f & 7)), stack[top++] = f;
        }
    }
    while (top > 0) {
        int32_t f = stack[--top];
        *area += layout->frame.face_area[f];
        for (int k = 0; k < 3; ++k) {
            int32_t g = t->twin[3 * f + k];
            if (g < 0 || blocked[t->halfedge_edge[3 * f + k]])
                continue;
            int32_t next = pz_he_face(g);
            if (!(mark[next >> 3] & (1u << (next & 7))))
                mark[next >> 3] |= (uint8_t)(1u << (next & 7)), stack[top++] = next;
        }
    }
    for (int32_t i = 0; i < n; ++i) {
        int32_t e = seg_edge_between(layout, loop->vertices[i], loop->vertices[(i + 1) % n]);
        if (e >= 0)
            blocked[e] = 0;
    }
    return 1;
}

pz_status seg_junctions_outermost(const seg_layout *layout, const pz_trace_path *const *loops, seg_preference **prefs,
                                  int32_t count, pz_ctx *ctx)
{
    int32_t limbs = 0, faces = layout->topology->face_count;
    int32_t *which = malloc(((size_t)count + 1) * sizeof(int32_t));
    if (!which)
        return nomem(ctx);
    for (int32_t i = 0; i < count; ++i)
        if (loops[i]->closed && prefs[i]->junction > 0 && !prefs[i]->encircles)
            which[limbs++] = i;
    size_t bytes = ((size_t)faces + 7) / 8;
    uint8_t *marks = calloc((size_t)limbs * bytes + 1, 1);
    double *areas = malloc(((size_t)limbs + 1) * sizeof(double));
    int32_t *stack = malloc(((size_t)faces + 1) * sizeof(int32_t));
    uint8_t *blocked = calloc((size_t)layout->topology->edge_count + 1, 1);
    pz_status status = marks && areas && stack && blocked ? PZ_OK : nomem(ctx);
    for (int32_t a = 0; a < limbs && !status; ++a)
        flood_side(layout, loops[which[a]], prefs[which[a]]->narrow_side, marks + a * bytes, areas + a, stack, blocked);
    /* A junction whose limb side lies inside another's (nearer the limb's free end), no stronger than it, is no
     * junction: a limb meets the body once (the armhole, not round the elbow; the top of the leg, not the knee). */
    const pz_topology *t = layout->topology;
    for (int32_t b = 0; b < limbs && !status; ++b) {
        const pz_trace_path *loop = loops[which[b]];
        int32_t e = seg_edge_between(layout, loop->vertices[0], loop->vertices[1]), f = -1;
        for (int k = 0; e >= 0 && k < 2 && f < 0; ++k) {
            int32_t h = t->edge_halfedge[2 * e + k];
            if (h >= 0 && (pz_he_from(t, h) == loop->vertices[0] ? 0 : 1) == prefs[which[b]]->narrow_side)
                f = pz_he_face(h);
        }
        for (int32_t a = 0; a < limbs && f >= 0; ++a) {
            if (a == b || !(areas[a] > areas[b]) || prefs[which[a]]->junction < prefs[which[b]]->junction ||
                !(marks[a * bytes + (f >> 3)] & (1u << (f & 7))))
                continue;
            seg_preference *p = prefs[which[b]];
            p->junction = 0;
            p->score = fmax(p->silhouette, CENTRE_RANK * p->centre);
            break;
        }
    }
    free(which);
    free(marks);
    free(areas);
    free(stack);
    free(blocked);
    return status;
}

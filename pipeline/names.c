/*
 * pipeline/names.c -- pattern pieces named after their place on the garment
 * (docs/run.md, "Piece names"): front, back, side, sleeve, leg, yoke, collar
 * or waistband, with the wearer's left or right, and the mirror partner of a
 * "Cut 2" pair named the same with the other side (front_left, front_right).
 *
 * The garment's frame: up is the grain's vertical; the left-right axis is the
 * mirror plane's normal when the layout found one, else the horizontal
 * direction along which the garment spreads most (a body is wider than it is
 * deep); front is the remaining horizontal direction, signed by the neckline
 * (the top opening dips lowest at the front) when the top opening dips, else
 * by the convention of the usual exports (y up: the body faces +z; z up: it
 * faces -y; both make the wearer's left +x). The wearer's left is up x front.
 *
 * The openings (boundary loops) tell the garment's parts: the highest one is
 * the top (neck or waist); low ones off the centre that come in a left and
 * right pair are leg openings; a low one on the centre is the hem; other ones
 * off the centre are arm openings (cuffs or armholes). Every face belongs to
 * the opening nearest to it along the surface (a multi-source Dijkstra over
 * the mesh's edges), and a panel to the opening most of its area belongs to.
 *
 * Cost: O(E log V) for the distances, O(F) for the rest.
 *
 * SPDX-License-Identifier: GPL-3.0-or-later
 */
#define _POSIX_C_SOURCE 200809L
#include "pipeline/internal.h"

#include "core/heap.h"
#include "core/vec.h"

#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

/* A panel is "on the side" when its centre lies this much closer to the centre front-back than to the
 * centre left-right (in units of its lateral offset). */
#define SIDE_RATIO 0.35
/* A panel straddles the centre when it reaches this share of the garment's half-width past it on both sides. */
#define STRADDLE_SHARE 0.1
/* A panel goes round the body when it reaches this share of the garment's half-depth to the front and back. */
#define WRAP_SHARE 0.5
/* An opening is off the centre when its centroid lies farther than this share of the half-width. */
#define OFF_CENTRE_SHARE 0.25
/* A band at the top opening: at most this share of the area and of the height. */
#define BAND_AREA_SHARE 0.06
#define BAND_HEIGHT_SHARE 0.15
/* A yoke: in the top YOKE_TOP_SHARE of the height, at most YOKE_HEIGHT_SHARE tall, across the centre. */
#define YOKE_TOP_SHARE 0.3
#define YOKE_HEIGHT_SHARE 0.25
/* The top opening dips (a neckline) when its height range exceeds this share of its width. */
#define NECK_DIP_SHARE 0.15

typedef enum loop_kind { LOOP_OTHER = 0, LOOP_TOP, LOOP_HEM, LOOP_ARM, LOOP_LEG } loop_kind;

typedef struct frame {
    double centre[3], up[3], left[3], front[3];
    double height_lo, height_hi, half_width, half_depth;
} frame;

typedef struct opening {
    double centroid[3], perimeter, height_lo, height_hi, half_width;
    loop_kind kind;
} opening;

typedef struct panel_place {
    double area, centroid[3];
    double height_lo, height_hi, lateral_lo, lateral_hi, ahead_lo, ahead_hi;
    int32_t opening;        /* the opening most of its area is nearest to, -1 none */
    int touches_top;        /* one of its faces has a vertex on the top opening */
} panel_place;

static double triangle_area(const pz_mesh *mesh, int32_t face)
{
    const int32_t *v = mesh->faces + 3 * face;
    double ab[3], ac[3], n[3];
    pz_vec3_sub(mesh->positions + 3 * v[1], mesh->positions + 3 * v[0], ab);
    pz_vec3_sub(mesh->positions + 3 * v[2], mesh->positions + 3 * v[0], ac);
    pz_vec3_cross(ab, ac, n);
    return 0.5 * pz_vec3_norm(n);
}

static double along(const frame *f, const double axis[3], const double *p)
{
    double d[3];
    pz_vec3_sub(p, f->centre, d);
    return pz_vec3_dot(axis, d);
}

static void horizontal(const double up[3], const double v[3], double out[3])
{
    double h = pz_vec3_dot(up, v);
    for (int k = 0; k < 3; ++k)
        out[k] = v[k] - h * up[k];
}

static int normalize(double v[3])
{
    double n = pz_vec3_norm(v);
    if (!(n > 1e-9))
        return 0;
    for (int k = 0; k < 3; ++k)
        v[k] /= n;
    return 1;
}

/* The horizontal direction along which the vertices spread most (2 x 2 covariance in the horizontal plane). */
static void widest_horizontal(const pz_mesh *mesh, const frame *f, const double e1[3], const double e2[3],
                              double out[3])
{
    double a = 0, b = 0, c = 0;
    for (int32_t v = 0; v < mesh->vertex_count; ++v) {
        double x = along(f, e1, mesh->positions + 3 * v), y = along(f, e2, mesh->positions + 3 * v);
        a += x * x, b += x * y, c += y * y;
    }
    double angle = 0.5 * atan2(2 * b, a - c);  /* the major axis of the covariance */
    for (int k = 0; k < 3; ++k)
        out[k] = cos(angle) * e1[k] + sin(angle) * e2[k];
}

/* Up, centre, the left-right axis (unsigned) and the heights of the garment. */
static void frame_axes(const pz_result *result, frame *f)
{
    const pz_mesh *mesh = result->garment;
    memcpy(f->up, result->grain, sizeof f->up);
    if (!normalize(f->up))
        f->up[0] = f->up[1] = 0, f->up[2] = 1;
    double area = 0;
    memset(f->centre, 0, sizeof f->centre);
    f->height_lo = INFINITY, f->height_hi = -INFINITY;
    for (int32_t i = 0; i < mesh->face_count; ++i) {
        const int32_t *v = mesh->faces + 3 * i;
        double a = triangle_area(mesh, i);
        for (int c = 0; c < 3; ++c)
            for (int k = 0; k < 3; ++k)
                f->centre[k] += a * mesh->positions[3 * v[c] + k] / 3;
        area += a;
    }
    for (int k = 0; k < 3 && area > 0; ++k)
        f->centre[k] /= area;
    for (int32_t v = 0; v < mesh->vertex_count; ++v) {
        double h = pz_vec3_dot(f->up, mesh->positions + 3 * v);
        f->height_lo = fmin(f->height_lo, h), f->height_hi = fmax(f->height_hi, h);
    }
    const pz_segment_result *segment = result->segment;
    double axis[3] = {0, 0, 0};
    if (segment && segment->symmetry.found)
        horizontal(f->up, segment->symmetry.normal, axis);
    if (!(pz_vec3_norm(axis) > 0.5)) {
        double seed[3] = {1, 0, 0}, e1[3], e2[3];
        if (fabs(f->up[0]) > 0.9)
            seed[0] = 0, seed[1] = 1;
        horizontal(f->up, seed, e1);
        normalize(e1);
        pz_vec3_cross(f->up, e1, e2);
        widest_horizontal(mesh, f, e1, e2, axis);
    }
    normalize(axis);
    memcpy(f->left, axis, sizeof f->left);
    pz_vec3_cross(f->up, f->left, f->front);  /* unsigned until sign_front */
    f->half_width = 0;
    for (int32_t v = 0; v < mesh->vertex_count; ++v)
        f->half_width = fmax(f->half_width, fabs(along(f, f->left, mesh->positions + 3 * v)));
}



/* The openings' shapes and kinds: the highest on the centre is the top; below mid-height, a left and right
 * pair off the centre are legs and the largest on the centre is the hem; above it, off the centre, arms. */
static void classify_openings(const pz_mesh *mesh, const pz_loops *loops, const frame *f, opening *openings)
{
    double mid = 0.5 * (f->height_lo + f->height_hi), highest = -INFINITY;
    int32_t top = -1;
    for (int32_t l = 0; l < loops->loop_count; ++l) {
        opening *o = &openings[l];
        memset(o, 0, sizeof *o);
        o->height_lo = INFINITY, o->height_hi = -INFINITY;
        int32_t first = loops->loop_offsets[l], n = loops->loop_offsets[l + 1] - first;
        for (int32_t i = 0; i < n; ++i) {
            const double *p = mesh->positions + 3 * loops->loop_vertices[first + i];
            o->perimeter += pz_vec3_distance(p, mesh->positions + 3 * loops->loop_vertices[first + (i + 1) % n]);
            for (int k = 0; k < 3; ++k)
                o->centroid[k] += p[k] / n;
            double h = pz_vec3_dot(f->up, p);
            o->height_lo = fmin(o->height_lo, h), o->height_hi = fmax(o->height_hi, h);
        }
        for (int32_t i = 0; i < n; ++i) {
            double d[3];
            pz_vec3_sub(mesh->positions + 3 * loops->loop_vertices[first + i], o->centroid, d);
            o->half_width = fmax(o->half_width, fabs(pz_vec3_dot(f->left, d)));
        }
    }
    /* The top: the highest opening on the centre (raised arms put cuffs higher than the neck), else the
     * highest of all. */
    for (int pass = 0; pass < 2 && top < 0; ++pass)
        for (int32_t l = 0; l < loops->loop_count; ++l) {
            int off_centre = fabs(along(f, f->left, openings[l].centroid)) > OFF_CENTRE_SHARE * f->half_width;
            if ((pass == 1 || !off_centre) && pz_vec3_dot(f->up, openings[l].centroid) > highest)
                highest = pz_vec3_dot(f->up, openings[l].centroid), top = l;
        }
    int32_t legs_left = 0, legs_right = 0, hem = -1;
    for (int32_t l = 0; l < loops->loop_count; ++l) {
        opening *o = &openings[l];
        double lateral = along(f, f->left, o->centroid);
        int off_centre = fabs(lateral) > OFF_CENTRE_SHARE * f->half_width, low = pz_vec3_dot(f->up, o->centroid) < mid;
        o->kind = LOOP_OTHER;
        if (l == top)
            o->kind = LOOP_TOP;
        else if (low && off_centre) {
            o->kind = LOOP_LEG;
            legs_left += lateral > 0, legs_right += lateral <= 0;
        } else if (low && (hem < 0 || o->perimeter > openings[hem].perimeter))
            hem = l;
        else if (!low && off_centre)
            o->kind = LOOP_ARM;
    }
    if (hem >= 0)
        openings[hem].kind = LOOP_HEM;
    /* Legs come in a left and right pair; a lone low opening off the centre is no leg. */
    for (int32_t l = 0; l < loops->loop_count && (legs_left == 0 || legs_right == 0); ++l)
        if (openings[l].kind == LOOP_LEG)
            openings[l].kind = LOOP_OTHER;
}

/* The front's sign, then the wearer's left (up x front). A top opening that dips (a neckline) dips lowest at
 * the front; otherwise the exports' convention: the wearer's left is +x, so front = x cross up. */
static void sign_front(const pz_mesh *mesh, const pz_loops *loops, const opening *openings, frame *f)
{
    double convention[3], x[3] = {1, 0, 0};
    pz_vec3_cross(x, f->up, convention);
    double sign = pz_vec3_dot(convention, f->front) < 0 ? -1 : 1;
    for (int32_t l = 0; l < loops->loop_count; ++l) {
        const opening *o = &openings[l];
        if (o->kind != LOOP_TOP || !(o->height_hi - o->height_lo > NECK_DIP_SHARE * 2 * o->half_width))
            continue;
        int32_t lowest = loops->loop_vertices[loops->loop_offsets[l]];
        for (int32_t i = loops->loop_offsets[l]; i < loops->loop_offsets[l + 1]; ++i)
            if (pz_vec3_dot(f->up, mesh->positions + 3 * loops->loop_vertices[i]) <
                pz_vec3_dot(f->up, mesh->positions + 3 * lowest))
                lowest = loops->loop_vertices[i];
        double d[3];
        pz_vec3_sub(mesh->positions + 3 * lowest, o->centroid, d);
        double ahead = pz_vec3_dot(f->front, d);
        if (fabs(ahead) > 0.25 * o->half_width)
            sign = ahead < 0 ? -1 : 1;
    }
    for (int k = 0; k < 3; ++k)
        f->front[k] *= sign;
    pz_vec3_cross(f->up, f->front, f->left);
    f->half_depth = 0;
    for (int32_t v = 0; v < mesh->vertex_count; ++v)
        f->half_depth = fmax(f->half_depth, fabs(along(f, f->front, mesh->positions + 3 * v)));
}

/* The opening nearest to each vertex along the mesh's edges (-1: none reachable), into nearest. */
static pz_status nearest_openings(const pz_mesh *mesh, const pz_topology *topology, const pz_loops *loops,
                                  int32_t *nearest, pz_ctx *ctx)
{
    int32_t n = mesh->vertex_count;
    int32_t *offsets = calloc((size_t)n + 2, sizeof(int32_t));
    int32_t *adjacent = malloc((size_t)2 * topology->edge_count * sizeof(int32_t) + 1);
    double *reach = malloc((size_t)n * sizeof(double) + 1);
    pz_heap heap;
    memset(&heap, 0, sizeof heap);
    int ok = offsets && adjacent && reach;
    for (int32_t e = 0; ok && e < topology->edge_count; ++e) {
        int32_t h = topology->edge_halfedge[2 * e];
        ++offsets[pz_he_from(topology, h) + 2], ++offsets[pz_he_to(topology, h) + 2];
    }
    for (int32_t v = 0; ok && v < n; ++v)
        offsets[v + 2] += offsets[v + 1];
    for (int32_t e = 0; ok && e < topology->edge_count; ++e) {
        int32_t h = topology->edge_halfedge[2 * e], a = pz_he_from(topology, h), b = pz_he_to(topology, h);
        adjacent[offsets[a + 1]++] = b, adjacent[offsets[b + 1]++] = a;
    }
    for (int32_t v = 0; ok && v < n; ++v)
        reach[v] = INFINITY, nearest[v] = -1;
    for (int32_t l = 0; ok && l < loops->loop_count; ++l)
        for (int32_t i = loops->loop_offsets[l]; ok && i < loops->loop_offsets[l + 1]; ++i) {
            int32_t v = loops->loop_vertices[i];
            reach[v] = 0, nearest[v] = l;
            ok = pz_heap_push(&heap, 0, v);
        }
    double key;
    int32_t v;
    while (ok && pz_heap_pop(&heap, &key, &v)) {
        if (key > reach[v])
            continue;
        for (int32_t i = offsets[v]; ok && i < offsets[v + 1]; ++i) {
            int32_t w = adjacent[i];
            double d = key + pz_vec3_distance(mesh->positions + 3 * v, mesh->positions + 3 * w);
            if (d < reach[w]) {
                reach[w] = d, nearest[w] = nearest[v];
                ok = pz_heap_push(&heap, d, w);
            }
        }
    }
    pz_heap_free(&heap);
    free(offsets);
    free(adjacent);
    free(reach);
    return ok ? PZ_OK : pz_error(ctx, PZ_ERR_NOMEM, "run: out of memory naming the pieces");
}

/* Each panel's area, centroid, extents, whether it reaches the top opening, and the opening most of its area
 * is nearest to. on_loop: the boundary loop of each vertex (-1 inside). */
static pz_status place_panels(const pz_result *result, const frame *f, const int32_t *nearest, const int32_t *on_loop,
                              int32_t loop_count, const opening *openings, panel_place *places, pz_ctx *ctx)
{
    const pz_mesh *mesh = result->garment;
    const pz_pattern *pattern = result->pattern;
    int32_t panels = pattern->panel_count;
    double *votes = calloc((size_t)panels * (loop_count + 1) + 1, sizeof(double));
    if (!votes)
        return pz_error(ctx, PZ_ERR_NOMEM, "run: out of memory naming the pieces");
    for (int32_t p = 0; p < panels; ++p) {
        memset(&places[p], 0, sizeof places[p]);
        places[p].height_lo = places[p].lateral_lo = places[p].ahead_lo = INFINITY;
        places[p].height_hi = places[p].lateral_hi = places[p].ahead_hi = -INFINITY;
    }
    for (int32_t i = 0; i < mesh->face_count; ++i) {
        int32_t p = pattern->face_panel[i];
        panel_place *place = &places[p];
        double a = triangle_area(mesh, i);
        place->area += a;
        for (int c = 0; c < 3; ++c) {
            int32_t v = mesh->faces[3 * i + c];
            const double *x = mesh->positions + 3 * v;
            for (int k = 0; k < 3; ++k)
                place->centroid[k] += a * x[k] / 3;
            double h = pz_vec3_dot(f->up, x), lateral = along(f, f->left, x);
            place->height_lo = fmin(place->height_lo, h), place->height_hi = fmax(place->height_hi, h);
            place->lateral_lo = fmin(place->lateral_lo, lateral), place->lateral_hi = fmax(place->lateral_hi, lateral);
            double ahead = along(f, f->front, x);
            place->ahead_lo = fmin(place->ahead_lo, ahead), place->ahead_hi = fmax(place->ahead_hi, ahead);
            if (nearest[v] >= 0)
                votes[(size_t)p * (loop_count + 1) + nearest[v]] += a;
            place->touches_top |= on_loop[v] >= 0 && openings[on_loop[v]].kind == LOOP_TOP;
        }
    }
    for (int32_t p = 0; p < panels; ++p) {
        panel_place *place = &places[p];
        for (int k = 0; k < 3 && place->area > 0; ++k)
            place->centroid[k] /= place->area;
        place->opening = -1;
        double most = 0;
        for (int32_t l = 0; l < loop_count; ++l)
            if (votes[(size_t)p * (loop_count + 1) + l] > most)
                most = votes[(size_t)p * (loop_count + 1) + l], place->opening = l;
    }
    free(votes);
    return PZ_OK;
}

/* One piece's name before numbering: its stem ("front", "sleeve_back", ...) and side (+1 the wearer's
 * left, -1 right, 0 none: it straddles the centre). */
typedef struct piece_name {
    char stem[32];
    int side;
    double height;          /* its centroid's, to number equal names from the top */
} piece_name;

/* What the garment as a whole tells the names. */
typedef struct garment_parts {
    double total_area, torso_half_width;
    int has_arms;
    int32_t *limb_panels;   /* per opening: the panels that belong to it as a limb */
    double *limb_centre;    /* per opening: 3, the area centroid of those panels */
} garment_parts;

static int sign_of(double x)
{
    return x > 0 ? 1 : -1;
}

/* A limb panel: sleeve or leg, front or back when its limb has several panels, on its opening's side. */
static int limb_name(const frame *f, const opening *o, const panel_place *place, const garment_parts *parts,
                     int32_t opening_index, piece_name *name)
{
    double lateral = along(f, f->left, place->centroid);
    if (o->kind == LOOP_LEG)
        snprintf(name->stem, sizeof name->stem, "leg");
    else if (o->kind == LOOP_ARM && fabs(lateral) > parts->torso_half_width)
        snprintf(name->stem, sizeof name->stem, "sleeve");
    else
        return 0;
    if (parts->limb_panels[opening_index] > 1) {
        /* Its front or back half: ahead of the limb's own centre or behind it (a leg in a stride leans). */
        double d[3];
        pz_vec3_sub(place->centroid, parts->limb_centre + 3 * opening_index, d);
        size_t used = strlen(name->stem);
        snprintf(name->stem + used, sizeof name->stem - used, "%s", pz_vec3_dot(f->front, d) > 0 ? "_front" : "_back");
    }
    name->side = sign_of(along(f, f->left, o->centroid));
    return 1;
}

/* The name of panel p from its place (mirror: the pattern's mirror partners, may be NULL). */
static void name_panel(const frame *f, const opening *openings, const panel_place *place, const garment_parts *parts,
                       int own_mirror, piece_name *name)
{
    double height = f->height_hi - f->height_lo, lateral = along(f, f->left, place->centroid);
    double ahead = along(f, f->front, place->centroid);
    int straddles = own_mirror || (place->lateral_lo < -STRADDLE_SHARE * f->half_width &&
                                   place->lateral_hi > STRADDLE_SHARE * f->half_width);
    name->height = pz_vec3_dot(f->up, place->centroid);
    name->side = straddles ? 0 : sign_of(lateral);
    if (place->opening >= 0 && limb_name(f, &openings[place->opening], place, parts, place->opening, name))
        return;
    if (place->touches_top && place->area < BAND_AREA_SHARE * parts->total_area &&
        place->height_hi - place->height_lo < BAND_HEIGHT_SHARE * height) {
        snprintf(name->stem, sizeof name->stem, "%s", parts->has_arms ? "collar" : "waistband");
        return;
    }
    if (straddles && name->height > f->height_hi - YOKE_TOP_SHARE * height &&
        place->height_hi - place->height_lo < YOKE_HEIGHT_SHARE * height) {
        snprintf(name->stem, sizeof name->stem, "yoke%s", fabs(ahead) < STRADDLE_SHARE * f->half_width ? ""
                                                           : ahead > 0 ? "_front" : "_back");
        return;
    }
    /* Round the body: across the centre both ways (a band or a tube, front and back in one). */
    if (straddles && place->ahead_lo < -WRAP_SHARE * f->half_depth && place->ahead_hi > WRAP_SHARE * f->half_depth)
        snprintf(name->stem, sizeof name->stem, "body");
    else if (!straddles && fabs(ahead) < SIDE_RATIO * fabs(lateral))
        snprintf(name->stem, sizeof name->stem, "side");
    else
        snprintf(name->stem, sizeof name->stem, "%s", ahead > 0 ? "front" : "back");
}

/* A mirror partner takes its partner's stem and the other side. */
static void pair_partners(const int32_t *mirror, int32_t panels, piece_name *names)
{
    for (int32_t p = 0; mirror && p < panels; ++p) {
        int32_t q = mirror[p];
        if (q <= p || q >= panels)
            continue;
        if (names[p].side == 0)
            names[p].side = names[q].side ? -names[q].side : 1;
        memcpy(names[q].stem, names[p].stem, sizeof names[q].stem);
        names[q].side = -names[p].side;
    }
}

static void write_name(const piece_name *name, int number, char *out, size_t size)
{
    int written = snprintf(out, size, "%s%s", name->stem, name->side > 0 ? "_left" : name->side < 0 ? "_right" : "");
    if (number > 0 && written > 0 && (size_t)written < size)
        snprintf(out + written, size - (size_t)written, "_%d", number);
}

/* The piece a partner's name follows: its mirror partner when that comes first, else itself. */
static int32_t primary(const int32_t *mirror, int32_t p)
{
    return mirror && mirror[p] >= 0 && mirror[p] < p ? mirror[p] : p;
}

/* Pieces of one name numbered from the top (1, 2, ...; a partner takes its primary's number): `same`
 * says which primaries share a number sequence with p. by_side: within a stem and side, else a stem. */
static void number_from_top(const int32_t *mirror, int32_t panels, const piece_name *names, int by_side, int *number)
{
    for (int32_t p = 0; p < panels; ++p) {
        if (primary(mirror, p) != p)
            continue;
        int32_t rank = 1, group = 0;
        for (int32_t q = 0; q < panels; ++q) {
            if (primary(mirror, q) != q || strcmp(names[q].stem, names[p].stem) != 0 ||
                (by_side && names[q].side != names[p].side))
                continue;
            ++group;
            rank += q != p && (names[q].height > names[p].height || (names[q].height == names[p].height && q < p));
        }
        number[p] = group > 1 ? (int)rank : 0;
    }
    for (int32_t p = 0; p < panels; ++p)
        number[p] = number[primary(mirror, p)];
}

static int compare_strings(const void *l, const void *r)
{
    return strcmp(*(char *const *)l, *(char *const *)r);
}

/* 1 when two of the names are equal (sorted copy of the pointers: O(P log P)). */
static int repeats(char **names, int32_t panels, char **sorted)
{
    memcpy(sorted, names, (size_t)panels * sizeof(char *));
    qsort(sorted, (size_t)panels, sizeof(char *), compare_strings);
    for (int32_t p = 1; p < panels; ++p)
        if (strcmp(sorted[p - 1], sorted[p]) == 0)
            return 1;
    return 0;
}

/* The final names into out: equal names numbered from the top within their stem and side; should a
 * partner's name then meet another piece's, every piece of a stem is numbered in one sequence. */
static pz_status number_names(const int32_t *mirror, int32_t panels, const piece_name *names, char **out, pz_ctx *ctx)
{
    int *number = calloc((size_t)panels + 1, sizeof(int));
    char **sorted = malloc((size_t)panels * sizeof(char *) + 1);
    pz_status status = number && sorted ? PZ_OK : pz_error(ctx, PZ_ERR_NOMEM, "run: out of memory naming the pieces");
    for (int by_side = 1; by_side >= 0 && status == PZ_OK; --by_side) {
        number_from_top(mirror, panels, names, by_side, number);
        for (int32_t p = 0; p < panels && status == PZ_OK; ++p) {
            char text[48];
            write_name(&names[p], number[p], text, sizeof text);
            free(out[p]);
            if (!(out[p] = strdup(text)))
                status = pz_error(ctx, PZ_ERR_NOMEM, "run: out of memory naming the pieces");
        }
        if (status == PZ_OK && !repeats(out, panels, sorted))
            break;
    }
    free(number);
    free(sorted);
    return status;
}

/* Every name of the pieces (names[panel_count], filled) from the garment's frame and openings. */
static pz_status name_all(const pz_result *result, const pz_topology *topology, const pz_loops *loops, char **out,
                          pz_ctx *ctx)
{
    const pz_mesh *mesh = result->garment;
    int32_t panels = result->pattern->panel_count, count = loops->loop_count;
    frame f;
    frame_axes(result, &f);
    opening *openings = calloc((size_t)count + 1, sizeof *openings);
    int32_t *nearest = malloc((size_t)mesh->vertex_count * sizeof(int32_t) + 1);
    int32_t *on_loop = malloc((size_t)mesh->vertex_count * sizeof(int32_t) + 1);
    panel_place *places = calloc((size_t)panels + 1, sizeof *places);
    piece_name *names = calloc((size_t)panels + 1, sizeof *names);
    garment_parts parts = {0, 0, 0, calloc((size_t)count + 1, sizeof(int32_t)),
                           calloc(3 * (size_t)count + 1, sizeof(double))};
    double *limb_area = calloc((size_t)count + 1, sizeof(double));
    pz_status status = openings && nearest && on_loop && places && names && parts.limb_panels && parts.limb_centre &&
                               limb_area
                           ? PZ_OK
                           : pz_error(ctx, PZ_ERR_NOMEM, "run: out of memory naming the pieces");
    if (status == PZ_OK) {
        memset(on_loop, 0xff, (size_t)mesh->vertex_count * sizeof(int32_t));
        for (int32_t l = 0; l < count; ++l)
            for (int32_t i = loops->loop_offsets[l]; i < loops->loop_offsets[l + 1]; ++i)
                on_loop[loops->loop_vertices[i]] = l;
        classify_openings(mesh, loops, &f, openings);
        sign_front(mesh, loops, openings, &f);
        status = nearest_openings(mesh, topology, loops, nearest, ctx);
    }
    if (status == PZ_OK)
        status = place_panels(result, &f, nearest, on_loop, count, openings, places, ctx);
    if (status == PZ_OK) {
        int32_t hem = -1, top = -1;
        for (int32_t l = 0; l < count; ++l) {
            parts.has_arms |= openings[l].kind == LOOP_ARM;
            hem = openings[l].kind == LOOP_HEM ? l : hem;
            top = openings[l].kind == LOOP_TOP ? l : top;
        }
        parts.torso_half_width = hem >= 0 ? openings[hem].half_width : top >= 0 ? openings[top].half_width : f.half_width;
        for (int32_t p = 0; p < panels; ++p) {
            parts.total_area += places[p].area;
            int32_t o = places[p].opening;
            if (o >= 0 && (openings[o].kind == LOOP_LEG ||
                           (openings[o].kind == LOOP_ARM &&
                            fabs(along(&f, f.left, places[p].centroid)) > parts.torso_half_width))) {
                ++parts.limb_panels[o];
                limb_area[o] += places[p].area;
                for (int k = 0; k < 3; ++k)
                    parts.limb_centre[3 * o + k] += places[p].area * places[p].centroid[k];
            }
        }
        for (int32_t o = 0; o < count; ++o)
            for (int k = 0; k < 3 && limb_area[o] > 0; ++k)
                parts.limb_centre[3 * o + k] /= limb_area[o];
        const int32_t *mirror = result->panel_mirror;
        for (int32_t p = 0; p < panels; ++p)
            name_panel(&f, openings, &places[p], &parts, mirror && mirror[p] == p, &names[p]);
        pair_partners(mirror, panels, names);
        status = number_names(mirror, panels, names, out, ctx);
    }
    free(openings);
    free(nearest);
    free(on_loop);
    free(places);
    free(names);
    free(parts.limb_panels);
    free(parts.limb_centre);
    free(limb_area);
    return status;
}

pz_status pl_name_pieces(pz_result *result, pz_ctx *ctx)
{
    if (result->panel_names)
        return PZ_OK;  /* the user's (groups, labels, panel files) */
    int32_t panels = result->pattern->panel_count;
    pz_topology *topology = NULL;
    pz_loops *loops = NULL;
    char **names = calloc((size_t)panels + 1, sizeof(char *));
    pz_status status = names ? pz_topology_build(result->garment, &topology, ctx)
                             : pz_error(ctx, PZ_ERR_NOMEM, "run: out of memory naming the pieces");
    if (status == PZ_OK)
        status = pz_topology_boundary_loops(topology, &loops, ctx);
    if (status == PZ_OK)
        status = name_all(result, topology, loops, names, ctx);
    pz_loops_free(&loops);
    pz_topology_free(&topology);
    if (status != PZ_OK) {
        for (int32_t p = 0; names && p < panels; ++p)
            free(names[p]);
        free(names);
        return status;
    }
    result->panel_names = names;
    return PZ_OK;
}

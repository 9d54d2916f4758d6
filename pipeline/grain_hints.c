/*
 * pipeline/grain_hints.c -- the designer's grain hints given to the pieces
 * (docs/run.md, "Grain hints"; pietroni2022 Sec. 4.3, "Grain alignment": "in
 * some cases, the tailor may perform a bias cut instead, favoring another
 * alignment axis in specific regions").
 *
 * A hint is a short stroke drawn on the garment: the warp runs along it in the
 * piece it lies on. The region a hint governs is that piece (the panel of the
 * face nearest the stroke's middle): a piece is cut from one grain, so a hint
 * turns the whole piece, and the textile flattening aligns the piece's warp
 * with the hint's axis as it aligns every other piece with the global grain
 * (param: pz_textile_options.panel_grain). The field honours the strokes too
 * (pipeline/segmentation.c joins them to the field's sketch: one arm of the
 * cross along each), so the seams near a hint follow its grain and not the
 * global one.
 *
 * SPDX-License-Identifier: GPL-3.0-or-later
 */
#include "pipeline/internal.h"
#include "core/vec.h"

#include <math.h>
#include <stdlib.h>
#include <string.h>

/* Length of the step from point i to point i + 1 of the hints' points. */
static double step_length(const double *points, int32_t i)
{
    double d[3] = {points[3 * i + 3] - points[3 * i], points[3 * i + 4] - points[3 * i + 1],
                   points[3 * i + 5] - points[3 * i + 2]};
    return sqrt(d[0] * d[0] + d[1] * d[1] + d[2] * d[2]);
}

/* The point halfway along curve c (by length) into mid, and its chord (last point - first) into chord. */
static void hint_middle_and_chord(const pz_sketch *hints, int32_t c, double mid[3], double chord[3])
{
    const double *points = hints->points;
    int32_t first = hints->curve_offsets[c], last = hints->curve_offsets[c + 1] - 1;
    double length = 0;
    for (int32_t i = first; i < last; ++i)
        length += step_length(points, i);
    memcpy(mid, points + 3 * (size_t)first, 3 * sizeof(double));
    double walked = 0;
    for (int32_t i = first; i < last; ++i) {
        double step = step_length(points, i);
        if (step > 0 && walked + step >= length / 2) {
            double t = (length / 2 - walked) / step;
            for (int k = 0; k < 3; ++k)
                mid[k] = points[3 * i + k] + t * (points[3 * i + 3 + k] - points[3 * i + k]);
            break;
        }
        walked += step;
    }
    for (int k = 0; k < 3; ++k)
        chord[k] = points[3 * last + k] - points[3 * first + k];
}

/* The face of `mesh` whose centroid is nearest `point` (-1: no face). */
static int32_t nearest_face(const pz_mesh *mesh, const double point[3])
{
    int32_t best = -1;
    double best_distance = INFINITY;
    for (int32_t f = 0; f < mesh->face_count; ++f) {
        const int32_t *v = mesh->faces + 3 * (size_t)f;
        double distance = 0;
        for (int k = 0; k < 3; ++k) {
            double centroid = (mesh->positions[3 * v[0] + k] + mesh->positions[3 * v[1] + k] +
                               mesh->positions[3 * v[2] + k]) / 3;
            distance += (centroid - point[k]) * (centroid - point[k]);
        }
        if (distance < best_distance)
            best_distance = distance, best = f;
    }
    return best;
}

/* The angle (radians, about the face normal) from the projection of `grain` on face f to the projection of
 * `axis`; 0 when either is nearly normal to the face. */
static double turn_on_face(const pz_mesh *mesh, int32_t f, const double grain[3], const double axis[3])
{
    const int32_t *v = mesh->faces + 3 * (size_t)f;
    const double *p0 = mesh->positions + 3 * (size_t)v[0];
    double ab[3], ac[3], n[3], g[3], h[3], cross[3];
    pz_vec3_sub(mesh->positions + 3 * (size_t)v[1], p0, ab);
    pz_vec3_sub(mesh->positions + 3 * (size_t)v[2], p0, ac);
    pz_vec3_cross(ab, ac, n);
    double length = pz_vec3_norm(n);
    if (!(length > 0))
        return 0;
    double gn = 0, hn = 0;
    for (int k = 0; k < 3; ++k)
        n[k] /= length, gn += grain[k] * n[k], hn += axis[k] * n[k];
    for (int k = 0; k < 3; ++k) /* both projected on the face */
        g[k] = grain[k] - gn * n[k], h[k] = axis[k] - hn * n[k];
    pz_vec3_cross(g, h, cross);
    double sine = pz_vec3_dot(cross, n), cosine = pz_vec3_dot(g, h);
    return sine == 0 && cosine == 0 ? 0 : atan2(sine, cosine);
}

pz_status pl_panel_grain(const pz_pattern *pattern, const double grain[3], const pz_sketch *hints,
                         const pz_segment_result *segment, double **panel_turn, int32_t *hinted, pz_ctx *ctx)
{
    *panel_turn = NULL;
    *hinted = 0;
    if (!hints || hints->curve_count == 0)
        return PZ_OK;
    int32_t panels = pattern->panel_count;
    double *turn = calloc((size_t)panels + 1, sizeof(double));
    double *sum = calloc(2 * (size_t)panels + 2, sizeof(double)); /* per panel: the hints' unit turns, summed */
    double *first = calloc((size_t)panels + 1, sizeof(double));
    uint8_t *seen = calloc((size_t)panels + 1, 1);
    if (!turn || !sum || !first || !seen) {
        free(turn), free(sum), free(first), free(seen);
        return pz_error(ctx, PZ_ERR_NOMEM, "run: out of memory placing the grain hints");
    }
    for (int32_t c = 0; c < hints->curve_count; ++c) {
        double mid[3], chord[3];
        hint_middle_and_chord(hints, c, mid, chord);
        int32_t face = nearest_face(pattern->mesh, mid);
        if (face < 0 || !(chord[0] * chord[0] + chord[1] * chord[1] + chord[2] * chord[2] > 0))
            continue;
        int32_t p = pattern->face_panel[face];
        double angle = turn_on_face(pattern->mesh, face, grain, chord);
        /* A grain line has no direction: strokes drawn either way along it agree with the panel's first. */
        if (seen[p] && cos(angle - first[p]) < 0)
            angle += angle > 0 ? -PZ_PI : PZ_PI;
        if (!seen[p])
            seen[p] = 1, first[p] = angle;
        sum[2 * p] += cos(angle);
        sum[2 * p + 1] += sin(angle);
    }
    for (int32_t p = 0; p < panels; ++p)
        if (seen[p])
            turn[p] = atan2(sum[2 * p + 1], sum[2 * p]);
    /* A mirror pair is one piece cut twice: the partner without a hint of its own takes the mirrored turn. */
    int mirrored = segment && segment->symmetry.found && segment->panel_count == panels;
    for (int32_t p = 0; mirrored && p < panels; ++p) {
        int32_t q = segment->panels[p].mirror_panel;
        if (seen[p] && q >= 0 && q < panels && q != p && !seen[q])
            turn[q] = -turn[p], seen[q] = 2;
    }
    for (int32_t p = 0; p < panels; ++p)
        *hinted += seen[p] != 0;
    free(sum), free(first), free(seen);
    *panel_turn = turn;
    return PZ_OK;
}

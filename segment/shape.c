/*
 * segment/shape.c -- the width of a piece (docs/segment.md, "Piece shapes"):
 * twice the largest distance from its outline inside it, the diameter of the
 * largest circle it holds. A sliver (a band a few millimetres wide) has a
 * small one however long it is; a piece with a narrow tail keeps the width
 * of its body (the corner goal limits such tails).
 *
 * A multi-source Dijkstra from the outline over the mesh's edges finds each
 * vertex's nearest outline vertex along edge paths; the vertex's distance is
 * then the straight one to that outline vertex, not the length of the edge
 * path (which overestimates by up to 8-15 % on a regular triangulation: a
 * 35 mm band would pass a 40 mm goal). Near the medial axis the nearest along
 * edges can be the wrong side's, so sweeps follow in which each vertex takes a
 * neighbour's outline vertex when that one is nearer, while one changes. The
 * width is never below the distance to the nearest outline vertex and was
 * within 3.1 % above the brute-force one on the flattened pieces of
 * tests/pipeline/test_run.c (the test allows 5 %). Propagating the straight
 * distances alone (each vertex relaxed from its neighbours' sources, no
 * sweeps) was 30 % over on a coarse piece a few triangles across. On a curved
 * panel the straight distance is a chord, shorter than the distance along the
 * surface by under 1 % for a band of 40 mm on a curvature radius of 150 mm.
 *
 * The faces' centroids count too, each at its straight distance to the
 * nearest outline vertex of its corners and their neighbours: a strip one
 * triangle wide has every vertex on its outline and the width of its
 * triangles, and a coarse piece has its widest point inside a triangle.
 *
 * Cost: O(E log V) for E edges and V vertices of the piece (and O(E) per
 * sweep, at most REFINE_SWEEPS).
 *
 * SPDX-License-Identifier: GPL-3.0-or-later
 */
#include "segment/segment.h"

#include "core/heap.h"

#include <math.h>
#include <stdlib.h>
#include <string.h>

/* At most this many sweeps in which each vertex takes a neighbour's outline vertex when that one is nearer. */
#define REFINE_SWEEPS 16

static double distance(const double *points, int dim, int32_t a, int32_t b)
{
    double sum = 0;
    for (int k = 0; k < dim; ++k) {
        double d = points[(size_t)dim * a + k] - points[(size_t)dim * b + k];
        sum += d * d;
    }
    return sqrt(sum);
}

/* The vertices next to each vertex across the faces' edges (CSR; an inner edge is listed twice). */
static int neighbours(int32_t vertex_count, int32_t face_count, const int32_t *faces, int32_t **offsets_out,
                      int32_t **adjacent_out)
{
    int32_t *offsets = calloc((size_t)vertex_count + 2, sizeof(int32_t));
    int32_t *adjacent = malloc((size_t)6 * face_count * sizeof(int32_t) + 1);
    if (!offsets || !adjacent) {
        free(offsets);
        free(adjacent);
        return 0;
    }
    for (int32_t c = 0; c < 3 * face_count; ++c)
        offsets[faces[c] + 2] += 2;  /* each corner's vertex has 2 neighbours in its face */
    for (int32_t v = 0; v < vertex_count; ++v)
        offsets[v + 2] += offsets[v + 1];
    for (int32_t f = 0; f < face_count; ++f)
        for (int k = 0; k < 3; ++k) {
            int32_t v = faces[3 * f + k];
            adjacent[offsets[v + 1]++] = faces[3 * f + (k + 1) % 3];
            adjacent[offsets[v + 1]++] = faces[3 * f + (k + 2) % 3];
        }
    *offsets_out = offsets;
    *adjacent_out = adjacent;
    return 1;
}

pz_status pz_piece_width(int32_t vertex_count, const double *points, int dim, int32_t face_count,
                         const int32_t *faces, const uint8_t *source, double *width, pz_ctx *ctx)
{
    if (!points || !faces || !source || !width || (dim != 2 && dim != 3) || vertex_count < 0 || face_count < 0)
        return pz_error(ctx, PZ_ERR_USAGE, "piece width: no points, faces or sources");
    *width = INFINITY;
    int32_t *offsets = NULL, *adjacent = NULL;
    double *reach = malloc((size_t)vertex_count * sizeof(double) + 1);
    int32_t *nearest = malloc((size_t)vertex_count * sizeof(int32_t) + 1);
    pz_heap heap;
    memset(&heap, 0, sizeof heap);
    int ok = reach && nearest && neighbours(vertex_count, face_count, faces, &offsets, &adjacent);
    int32_t sources = 0;
    for (int32_t v = 0; ok && v < vertex_count; ++v) {
        reach[v] = source[v] ? 0 : INFINITY;
        nearest[v] = source[v] ? v : -1;
        if (source[v])
            ok = pz_heap_push(&heap, 0, v), ++sources;
    }
    /* A plain multi-source Dijkstra over edge lengths (path[] the graph distance); each vertex keeps the
     * source it was reached from, and its reach is the straight distance to that source. */
    double *path = ok ? malloc((size_t)vertex_count * sizeof(double) + 1) : NULL;
    ok = ok && path;
    for (int32_t u = 0; ok && u < vertex_count; ++u)
        path[u] = reach[u];
    double farthest = 0;
    double key;
    int32_t v;
    while (ok && pz_heap_pop(&heap, &key, &v)) {
        if (key > path[v])
            continue;
        for (int32_t i = offsets[v]; i < offsets[v + 1] && ok; ++i) {
            int32_t w = adjacent[i];
            double d = key + distance(points, dim, v, w);
            if (d < path[w]) {
                path[w] = d;
                nearest[w] = nearest[v];
                reach[w] = distance(points, dim, w, nearest[v]);
                ok = pz_heap_push(&heap, d, w);
            }
        }
    }
    free(path);
    /* Each vertex then tries its neighbours' outline vertices, sweep after sweep while one changes: the
     * nearest along edges is not always the nearest (at the medial axis a path's detour picks the other side). */
    for (int sweep = 0, changed = 1; ok && changed && sweep < REFINE_SWEEPS; ++sweep) {
        changed = 0;
        for (int32_t u = 0; u < vertex_count; ++u)
            for (int32_t i = offsets[u]; i < offsets[u + 1]; ++i) {
                int32_t s = nearest[adjacent[i]];
                double d = s >= 0 ? distance(points, dim, u, s) : INFINITY;
                if (d < reach[u])
                    reach[u] = d, nearest[u] = s, changed = 1;
            }
    }
    for (int32_t u = 0; ok && u < vertex_count; ++u)
        if (isfinite(reach[u]))
            farthest = fmax(farthest, reach[u]);
    /* The faces' centroids too: a strip one triangle wide has every vertex on its outline, but not zero width. */
    for (int32_t f = 0; ok && sources > 0 && f < face_count; ++f) {
        double centroid[3] = {0, 0, 0}, nearest_reach = INFINITY;
        for (int k = 0; k < 3; ++k)
            for (int d = 0; d < dim; ++d)
                centroid[d] += points[(size_t)dim * faces[3 * f + k] + d] / 3;
        /* Its corners' outline vertices and their neighbours': the centroid's nearest is among them. */
        for (int k = 0; k < 3; ++k)
            for (int32_t i = offsets[faces[3 * f + k]] - 1; i < offsets[faces[3 * f + k] + 1]; ++i) {
                int32_t s = nearest[i < offsets[faces[3 * f + k]] ? faces[3 * f + k] : adjacent[i]];
                if (s < 0)
                    continue;
                double sum = 0;
                for (int d = 0; d < dim; ++d)
                    sum += (centroid[d] - points[(size_t)dim * s + d]) * (centroid[d] - points[(size_t)dim * s + d]);
                nearest_reach = fmin(nearest_reach, sqrt(sum));
            }
        if (isfinite(nearest_reach))
            farthest = fmax(farthest, nearest_reach);
    }
    pz_heap_free(&heap);
    free(reach);
    free(nearest);
    free(offsets);
    free(adjacent);
    if (!ok)
        return pz_error(ctx, PZ_ERR_NOMEM, "piece width: out of memory");
    if (sources > 0)
        *width = 2 * farthest;
    return PZ_OK;
}

/*
 * param/slivers.c -- sliver triangles given their 3D shape after a
 * flattening that only sees edge lengths (spring-mass).
 *
 * A sliver's apex (the corner opposite its longest edge) sits a height h
 * above that edge with h a tiny fraction of its length L. Edge lengths fix h
 * only to second order (|am| + |mb| - |ab| is about 2 h^2 / L), so a spring
 * system whose edges are strained by e relative moves the apex by about
 * e L: with e = 1e-4, L = 10 mm and h = 0.5 um the sliver came out 5x its
 * height (strain 4.2; 31,772 on a real panel, issue 17) although every
 * spring was within 1e-4 of its length. The apex is therefore put where the
 * 3D triangle puts it, copied rigidly onto the sliver's flattened longest
 * edge and scaled to it: the sliver's strain becomes that of its longest
 * edge. The apex moves by about e L, far below the size of its other faces,
 * so the move is kept only when no face around the apex flips.
 *
 * SPDX-License-Identifier: GPL-3.0-or-later
 */
#include "param/internal.h"

#include <math.h>
#include <stdlib.h>
#include <string.h>

/* 3D height over longest edge below which a face is a sliver. */
#define SLIVER_HEIGHT 5e-2

static double twice_signed_area(const double *uv, const int32_t *face)
{
    const double *a = uv + 2 * face[0], *b = uv + 2 * face[1], *c = uv + 2 * face[2];
    return (b[0] - a[0]) * (c[1] - a[1]) - (b[1] - a[1]) * (c[0] - a[0]);
}

/* The apex's position for face f (its corner `apex` opposite edge apex+1 -> apex+2) from its 3D shape. */
static void apex_from_3d(const pz_mesh *mesh, const int32_t *face, int apex, double orientation, const double *uv,
                         double out[2])
{
    int32_t m = face[apex], a = face[(apex + 1) % 3], b = face[(apex + 2) % 3];
    const double *pa = mesh->positions + 3 * a, *pb = mesh->positions + 3 * b, *pm = mesh->positions + 3 * m;
    double base[3], to_apex[3];
    for (int k = 0; k < 3; ++k) {
        base[k] = pb[k] - pa[k];
        to_apex[k] = pm[k] - pa[k];
    }
    double length2 = base[0] * base[0] + base[1] * base[1] + base[2] * base[2];
    double along = (to_apex[0] * base[0] + to_apex[1] * base[1] + to_apex[2] * base[2]) / length2;
    double off[3], height2 = 0;
    for (int k = 0; k < 3; ++k) {
        off[k] = to_apex[k] - along * base[k];
        height2 += off[k] * off[k];
    }
    double across = sqrt(height2 / length2); /* height over the base length */
    const double *qa = uv + 2 * a, *qb = uv + 2 * b;
    double dx = qb[0] - qa[0], dy = qb[1] - qa[1];
    /* Face (m, a, b) counter-clockwise (orientation > 0) has m to the left of a -> b. */
    double side = orientation > 0 ? 1 : -1;
    out[0] = qa[0] + along * dx - side * across * dy;
    out[1] = qa[1] + along * dy + side * across * dx;
}

int32_t pz_param_fit_slivers(const pz_mesh *mesh, const uint8_t *fixed, double *uv)
{
    int32_t nf = mesh->face_count, moved = 0;
    double orientation = 0;
    for (int32_t f = 0; f < nf; ++f)
        orientation += twice_signed_area(uv, mesh->faces + 3 * f);
    int32_t *first = malloc(((size_t)mesh->vertex_count + 1) * sizeof(int32_t));
    int32_t *next = malloc(3 * (size_t)nf * sizeof(int32_t) + 1);
    if (!first || !next) {
        free(first);
        free(next);
        return -1;
    }
    /* Corner lists per vertex, to check the faces around a moved apex. */
    for (int32_t v = 0; v < mesh->vertex_count; ++v)
        first[v] = -1;
    for (int32_t c = 3 * nf - 1; c >= 0; --c) {
        next[c] = first[mesh->faces[c]];
        first[mesh->faces[c]] = c;
    }
    for (int32_t f = 0; f < nf; ++f) {
        const int32_t *face = mesh->faces + 3 * f;
        double length2[3], longest = 0;
        int apex = 0;
        for (int e = 0; e < 3; ++e) { /* edge opposite corner e */
            const double *p = mesh->positions + 3 * face[(e + 1) % 3], *q = mesh->positions + 3 * face[(e + 2) % 3];
            length2[e] = (q[0] - p[0]) * (q[0] - p[0]) + (q[1] - p[1]) * (q[1] - p[1]) + (q[2] - p[2]) * (q[2] - p[2]);
            if (length2[e] > longest) {
                longest = length2[e];
                apex = e;
            }
        }
        double frame[3], e1[3], e2[3];
        double area = pz_param_face_frame(mesh->positions, face, frame, e1, e2);
        int32_t m = face[apex];
        if (!(longest > 0) || !(2 * area < SLIVER_HEIGHT * longest) || (fixed && fixed[m]))
            continue;
        double old[2] = {uv[2 * m], uv[2 * m + 1]}, target[2];
        apex_from_3d(mesh, face, apex, orientation, uv, target);
        uv[2 * m] = target[0];
        uv[2 * m + 1] = target[1];
        int flips = 0;
        for (int32_t c = first[m]; c >= 0 && !flips; c = next[c])
            flips = !(twice_signed_area(uv, mesh->faces + 3 * (c / 3)) * orientation > 0);
        if (flips) {
            uv[2 * m] = old[0];
            uv[2 * m + 1] = old[1];
        } else {
            ++moved;
        }
    }
    free(first);
    free(next);
    return moved;
}

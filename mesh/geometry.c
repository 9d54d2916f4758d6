/*
 * mesh/geometry.c -- per-face and per-vertex quantities of the rest pose:
 * areas, face and vertex normals, corner angles, cotangent weights, angle
 * defect and the developability error.
 *
 * Robustness. Corner angles are atan2(|u x w|, u . w), accurate for angles
 * near 0 and pi where acos(u . w / (|u||w|)) loses half its digits (and can
 * be fed a ratio slightly above 1). A cotangent is (u . w) / |u x w|; a
 * degenerate face (|u x w| = 0) contributes 0 to a cotangent weight rather
 * than an infinity, and has a zero normal.
 *
 * Curvature. The angle defect is 2 pi - sum of the angles at an interior
 * vertex (pi - sum at a boundary vertex): the discrete Gaussian curvature
 * integrated over the vertex's area, whose sum over a closed surface is
 * 2 pi chi (Gauss-Bonnet). The developability error of wang2008 (Eq. 25) is
 * |sum - 2 pi| at interior vertices and 0 on the boundary, where a fan of
 * faces can always be flattened. Isolated vertices get 0 in both.
 *
 * Nothing here allocates or fails; preconditions: faces index valid
 * vertices, and the topology (where taken) was built from this mesh.
 *
 * SPDX-License-Identifier: GPL-3.0-or-later
 */
#include "mesh/mesh.h"

#include "core/vec.h"

#include <math.h>
#include <string.h>

/* Twice-area vector of face f: (p1 - p0) x (p2 - p0). */
static void face_cross(const pz_mesh *mesh, int32_t f, double *out)
{
    const int32_t *corner = mesh->faces + 3 * f;
    double u[3], w[3];
    pz_vec3_sub(mesh->positions + 3 * corner[1], mesh->positions + 3 * corner[0], u);
    pz_vec3_sub(mesh->positions + 3 * corner[2], mesh->positions + 3 * corner[0], w);
    pz_vec3_cross(u, w, out);
}

/* The edge vectors leaving corner k of face f, towards corners k+1 and k+2. */
static void corner_edges(const pz_mesh *mesh, int32_t f, int k, double *u, double *w)
{
    const int32_t *corner = mesh->faces + 3 * f;
    const double *origin = mesh->positions + 3 * corner[k];
    pz_vec3_sub(mesh->positions + 3 * corner[(k + 1) % 3], origin, u);
    pz_vec3_sub(mesh->positions + 3 * corner[(k + 2) % 3], origin, w);
}

static double corner_angle(const pz_mesh *mesh, int32_t f, int k)
{
    double u[3], w[3], c[3];
    corner_edges(mesh, f, k, u, w);
    pz_vec3_cross(u, w, c);
    return atan2(pz_vec3_norm(c), pz_vec3_dot(u, w));
}

static double corner_cotangent(const pz_mesh *mesh, int32_t f, int k)
{
    double u[3], w[3], c[3];
    corner_edges(mesh, f, k, u, w);
    pz_vec3_cross(u, w, c);
    double sine_term = pz_vec3_norm(c);
    return sine_term > 0.0 ? pz_vec3_dot(u, w) / sine_term : 0.0;
}

void pz_geom_face_areas(const pz_mesh *mesh, double *areas)
{
    for (int32_t f = 0; f < mesh->face_count; ++f) {
        double c[3];
        face_cross(mesh, f, c);
        areas[f] = 0.5 * pz_vec3_norm(c);
    }
}

void pz_geom_face_normals(const pz_mesh *mesh, double *normals)
{
    for (int32_t f = 0; f < mesh->face_count; ++f) {
        double c[3];
        face_cross(mesh, f, c);
        double length = pz_vec3_norm(c);
        for (int k = 0; k < 3; ++k)
            normals[3 * f + k] = length > 0.0 ? c[k] / length : 0.0;
    }
}

void pz_geom_vertex_normals(const pz_mesh *mesh, double *normals)
{
    memset(normals, 0, 3 * (size_t)mesh->vertex_count * sizeof *normals);
    for (int32_t f = 0; f < mesh->face_count; ++f) {
        double c[3];
        face_cross(mesh, f, c);
        for (int k = 0; k < 3; ++k)
            for (int d = 0; d < 3; ++d)
                normals[3 * (size_t)mesh->faces[3 * f + k] + d] += c[d];
    }
    for (int32_t v = 0; v < mesh->vertex_count; ++v) {
        double *n = normals + 3 * (size_t)v;
        double length = pz_vec3_norm(n);
        if (length > 0.0 && isfinite(length)) {
            n[0] /= length, n[1] /= length, n[2] /= length;
        } else {
            n[0] = n[1] = 0.0, n[2] = 1.0;
        }
    }
}

double pz_geom_total_area(const pz_mesh *mesh)
{
    double total = 0.0;
    for (int32_t f = 0; f < mesh->face_count; ++f) {
        double c[3];
        face_cross(mesh, f, c);
        total += 0.5 * pz_vec3_norm(c);
    }
    return total;
}

void pz_geom_corner_angles(const pz_mesh *mesh, double *angles)
{
    for (int32_t f = 0; f < mesh->face_count; ++f)
        for (int k = 0; k < 3; ++k)
            angles[3 * f + k] = corner_angle(mesh, f, k);
}

/* Half-edge h = 3f + k runs corner k -> k+1; the angle opposite it is at corner k+2. */
void pz_geom_cotan_weights(const pz_mesh *mesh, const pz_topology *topology, double *weights)
{
    memset(weights, 0, (size_t)topology->edge_count * sizeof *weights);
    for (int32_t h = 0; h < topology->halfedge_count; ++h)
        weights[topology->halfedge_edge[h]] += 0.5 * corner_cotangent(mesh, pz_he_face(h), (h % 3 + 2) % 3);
}

/* Sum of the corner angles at each vertex. */
static void angle_sums(const pz_mesh *mesh, double *sums)
{
    memset(sums, 0, (size_t)mesh->vertex_count * sizeof *sums);
    for (int32_t f = 0; f < mesh->face_count; ++f)
        for (int k = 0; k < 3; ++k)
            sums[mesh->faces[3 * f + k]] += corner_angle(mesh, f, k);
}

void pz_geom_angle_defect(const pz_mesh *mesh, const pz_topology *topology, double *defect)
{
    angle_sums(mesh, defect);
    for (int32_t v = 0; v < mesh->vertex_count; ++v) {
        if (topology->vertex_halfedge[v] < 0)
            defect[v] = 0.0;
        else
            defect[v] = (topology->vertex_on_boundary[v] ? PZ_PI : 2.0 * PZ_PI) - defect[v];
    }
}

void pz_geom_developability(const pz_mesh *mesh, const pz_topology *topology, double *e_dev)
{
    angle_sums(mesh, e_dev);
    for (int32_t v = 0; v < mesh->vertex_count; ++v) {
        if (topology->vertex_halfedge[v] < 0 || topology->vertex_on_boundary[v])
            e_dev[v] = 0.0;
        else
            e_dev[v] = fabs(e_dev[v] - 2.0 * PZ_PI);
    }
}

void pz_geom_closest_on_triangle(const double *p, const double *a, const double *b, const double *c, double bary[3])
{
    double ab[3], ac[3], ap[3];
    pz_vec3_sub(b, a, ab);
    pz_vec3_sub(c, a, ac);
    pz_vec3_sub(p, a, ap);
    double d1 = pz_vec3_dot(ab, ap), d2 = pz_vec3_dot(ac, ap);
    if (d1 <= 0 && d2 <= 0) {
        bary[0] = 1, bary[1] = 0, bary[2] = 0;
        return;
    }
    double bp[3];
    pz_vec3_sub(p, b, bp);
    double d3 = pz_vec3_dot(ab, bp), d4 = pz_vec3_dot(ac, bp);
    if (d3 >= 0 && d4 <= d3) {
        bary[0] = 0, bary[1] = 1, bary[2] = 0;
        return;
    }
    double vc = d1 * d4 - d3 * d2;
    if (vc <= 0 && d1 >= 0 && d3 <= 0) {
        double w = d1 / (d1 - d3);
        bary[0] = 1 - w, bary[1] = w, bary[2] = 0;
        return;
    }
    double cp[3];
    pz_vec3_sub(p, c, cp);
    double d5 = pz_vec3_dot(ab, cp), d6 = pz_vec3_dot(ac, cp);
    if (d6 >= 0 && d5 <= d6) {
        bary[0] = 0, bary[1] = 0, bary[2] = 1;
        return;
    }
    double vb = d5 * d2 - d1 * d6;
    if (vb <= 0 && d2 >= 0 && d6 <= 0) {
        double w = d2 / (d2 - d6);
        bary[0] = 1 - w, bary[1] = 0, bary[2] = w;
        return;
    }
    double va = d3 * d6 - d5 * d4;
    if (va <= 0 && (d4 - d3) >= 0 && (d5 - d6) >= 0) {
        double w = (d4 - d3) / ((d4 - d3) + (d5 - d6));
        bary[0] = 0, bary[1] = 1 - w, bary[2] = w;
        return;
    }
    double denom = 1 / (va + vb + vc);
    bary[1] = vb * denom;
    bary[2] = vc * denom;
    bary[0] = 1 - bary[1] - bary[2];
}

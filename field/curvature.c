/*
 * field/curvature.c -- multi-scale principal curvature per face.
 *
 * pietroni2022 Sec. 4.1 initialises the cross-field with the principal
 * curvature directions "at a low scale" from Panozzo et al. 2010 (efficient
 * multi-scale curvature estimation) and weighs them by their anisotropy
 * (as Bommes et al. 2009 do). This file does the following, per scale s of
 * `scale_count` (radius r_s = 2^s * mean edge length: 1x, 2x, 4x by default):
 *
 *  1. At every vertex: a frame (t1, t2, n) from the area-weighted normal; the
 *     vertices within Euclidean distance r_max of it, collected by a
 *     breadth-first walk over the edges that stops at r_max (so the
 *     neighbourhood is connected on the surface, a cheap stand-in for a
 *     geodesic disk); always at least the one-ring.
 *  2. For each scale, a least-squares quadric z = a x^2 + b xy + c y^2 + d x
 *     + e y over the neighbours within r_s (the height function of Panozzo
 *     2010, Sec. 3; 3 unknowns when fewer than 6 neighbours), coordinates
 *     divided by r_s for conditioning. The shape operator at the vertex is
 *     [[2a, b], [b, 2c]] in (t1, t2) (the slope terms d, e only absorb the
 *     normal's error), stored as a 3D symmetric tensor.
 *  3. Per face: the mean of its three vertex tensors, restricted to the face
 *     plane; its eigenvalues are the principal curvatures k1, k2 (|k1| >=
 *     |k2|) and the eigenvector of k1 the direction. Anisotropy
 *     (|k1| - |k2|) / (|k1| + |k2| + eps), eps = 0.5 / sqrt(surface area)
 *     (rotation invariant), so flat and umbilic regions get ~0.
 *  4. The scales are combined with the 90-degree-invariant average: the
 *     direction angle phi_s in the face frame as the complex number
 *     a_s exp(4 i phi_s), summed; the direction is arg / 4 and the anisotropy
 *     |sum| / S. Scales that disagree (noise, wrinkles at the fine scale)
 *     cancel, which lowers the confidence there: the coarse scales are the
 *     defence against noise.
 *
 * Cost: O(V * N) with N the vertices within the largest radius (~100 at 4
 * mean edges), in parallel over vertices with OpenMP (per-thread walk
 * buffers of 2 V int32). Memory: V x S x 6 doubles of tensors plus the
 * vertex adjacency. Failure: PZ_ERR_USAGE for a scale count outside
 * 1 .. PZ_FIELD_MAX_SCALES, PZ_ERR_NOMEM; nothing leaks, *out stays NULL.
 *
 * SPDX-License-Identifier: GPL-3.0-or-later
 */
#include "field/field.h"
#include "core/vec.h"

#include <math.h>
#include <omp.h>
#include <stdlib.h>
#include <string.h>



/* Any unit vector orthogonal to the unit vector n. */
static void orthogonal3(const double *n, double *out)
{
    double axis[3] = {0.0, 0.0, 0.0};
    axis[fabs(n[0]) < fabs(n[1]) ? (fabs(n[0]) < fabs(n[2]) ? 0 : 2) : (fabs(n[1]) < fabs(n[2]) ? 1 : 2)] = 1.0;
    pz_vec3_cross(n, axis, out);
    pz_vec3_normalize(out);
}

double pz_field_mean_edge_length(const pz_mesh *mesh, const pz_topology *topology)
{
    if (topology->edge_count == 0)
        return 0.0;
    double total = 0.0;
    for (int32_t e = 0; e < topology->edge_count; ++e) {
        int32_t h = topology->edge_halfedge[2 * e];
        double d[3];
        pz_vec3_sub(mesh->positions + 3 * (size_t)pz_he_from(topology, h), mesh->positions + 3 * (size_t)pz_he_to(topology, h), d);
        total += sqrt(pz_vec3_dot(d, d));
    }
    return total / topology->edge_count;
}

/* ---------------------------------------------------------------- vertex adjacency (CSR) */

typedef struct adjacency {
    int32_t *offsets;    /* vertex_count + 1 */
    int32_t *neighbours; /* offsets[vertex_count] */
} adjacency;

/* Each half-edge gives from -> to; a boundary half-edge (no twin) also gives
 * to -> from, so every undirected edge appears once in each endpoint's list. */
static int adjacency_build(const pz_topology *topology, adjacency *adj)
{
    int32_t n = topology->vertex_count;
    adj->offsets = calloc((size_t)n + 1, sizeof *adj->offsets);
    adj->neighbours = malloc(((size_t)topology->halfedge_count * 2 + 1) * sizeof *adj->neighbours);
    if (!adj->offsets || !adj->neighbours)
        return 0;
    for (int32_t h = 0; h < topology->halfedge_count; ++h) {
        ++adj->offsets[pz_he_from(topology, h) + 1];
        if (topology->twin[h] < 0)
            ++adj->offsets[pz_he_to(topology, h) + 1];
    }
    for (int32_t v = 0; v < n; ++v)
        adj->offsets[v + 1] += adj->offsets[v];
    int32_t *fill = malloc(((size_t)n + 1) * sizeof *fill);
    if (!fill)
        return 0;
    memcpy(fill, adj->offsets, (size_t)n * sizeof *fill);
    for (int32_t h = 0; h < topology->halfedge_count; ++h) {
        int32_t a = pz_he_from(topology, h), b = pz_he_to(topology, h);
        adj->neighbours[fill[a]++] = b;
        if (topology->twin[h] < 0)
            adj->neighbours[fill[b]++] = a;
    }
    free(fill);
    return 1;
}

static void adjacency_free(adjacency *adj)
{
    free(adj->offsets);
    free(adj->neighbours);
}

/* ---------------------------------------------------------------- the quadric fit */

/* Solves the n x n system a x = b (n <= 5) by Gaussian elimination with
 * partial pivoting; returns 0 when a pivot falls below tol. */
static int solve_small(double a[5][5], double *b, int n, double tol)
{
    for (int col = 0; col < n; ++col) {
        int pivot = col;
        for (int r = col + 1; r < n; ++r)
            if (fabs(a[r][col]) > fabs(a[pivot][col]))
                pivot = r;
        if (fabs(a[pivot][col]) <= tol)
            return 0;
        if (pivot != col) {
            for (int k = 0; k < n; ++k) {
                double t = a[col][k]; a[col][k] = a[pivot][k]; a[pivot][k] = t;
            }
            double t = b[col]; b[col] = b[pivot]; b[pivot] = t;
        }
        for (int r = col + 1; r < n; ++r) {
            double factor = a[r][col] / a[col][col];
            for (int k = col; k < n; ++k)
                a[r][k] -= factor * a[col][k];
            b[r] -= factor * b[col];
        }
    }
    for (int r = n - 1; r >= 0; --r) {
        for (int k = r + 1; k < n; ++k)
            b[r] -= a[r][k] * b[k];
        b[r] /= a[r][r];
    }
    return 1;
}

/* A vertex's frame and its neighbourhood in that frame (coordinates and distances). */
typedef struct local_patch {
    double t1[3], t2[3], n[3];
    int32_t count;       /* neighbours */
    int32_t ring_count;  /* the first ring_count neighbours are the one-ring */
    double *xyz;         /* count x 3, in (t1, t2, n) */
    double *distance;    /* count */
} local_patch;

/* Fits the quadric over the neighbours within `radius` (and the one-ring);
 * writes the shape operator as a 3D tensor (xx, xy, xz, yy, yz, zz). */
static void fit_scale(const local_patch *patch, double radius, double tensor[6])
{
    double a[5][5] = {{0}}, b[5] = {0};
    int used = 0;
    double inv = 1.0 / radius;
    for (int32_t i = 0; i < patch->count; ++i) {
        if (i >= patch->ring_count && patch->distance[i] >= radius)
            continue;
        double x = patch->xyz[3 * i] * inv, y = patch->xyz[3 * i + 1] * inv, z = patch->xyz[3 * i + 2] * inv;
        double phi[5] = {x * x, x * y, y * y, x, y};
        for (int r = 0; r < 5; ++r) {
            for (int c = 0; c < 5; ++c)
                a[r][c] += phi[r] * phi[c];
            b[r] += phi[r] * z;
        }
        ++used;
    }
    memset(tensor, 0, 6 * sizeof *tensor);
    int unknowns = used >= 6 ? 5 : 3;
    if (used < 3)
        return;
    double a_copy[5][5], b_copy[5];
    memcpy(a_copy, a, sizeof a);
    memcpy(b_copy, b, sizeof b);
    if (!solve_small(a_copy, b_copy, unknowns, 1e-12 * (a[0][0] + 1e-300))) {
        /* Too few independent directions for the slopes: the pure quadric. */
        if (unknowns == 3 || !solve_small(a, b, 3, 1e-12 * (a[0][0] + 1e-300)))
            return;
        memcpy(b_copy, b, sizeof b);
    }
    /* Back to 1/mm: z/r = a (x/r)^2 -> z = (a/r) x^2. */
    double h11 = 2.0 * b_copy[0] * inv, h12 = b_copy[1] * inv, h22 = 2.0 * b_copy[2] * inv;
    const double *t1 = patch->t1, *t2 = patch->t2;
    double m[3][3];
    for (int r = 0; r < 3; ++r)
        for (int c = 0; c < 3; ++c)
            m[r][c] = h11 * t1[r] * t1[c] + h12 * (t1[r] * t2[c] + t2[r] * t1[c]) + h22 * t2[r] * t2[c];
    tensor[0] = m[0][0], tensor[1] = m[0][1], tensor[2] = m[0][2];
    tensor[3] = m[1][1], tensor[4] = m[1][2], tensor[5] = m[2][2];
}

/* Area-weighted vertex normals (unnormalised sums of face cross products, then normalised). */
static void vertex_normals(const pz_mesh *mesh, const double *positions, double *normals)
{
    memset(normals, 0, (size_t)mesh->vertex_count * 3 * sizeof *normals);
    for (int32_t f = 0; f < mesh->face_count; ++f) {
        const int32_t *face = mesh->faces + 3 * (size_t)f;
        double e1[3], e2[3], n[3];
        pz_vec3_sub(positions + 3 * (size_t)face[1], positions + 3 * (size_t)face[0], e1);
        pz_vec3_sub(positions + 3 * (size_t)face[2], positions + 3 * (size_t)face[0], e2);
        pz_vec3_cross(e1, e2, n);
        for (int k = 0; k < 3; ++k)
            for (int c = 0; c < 3; ++c)
                normals[3 * (size_t)face[k] + c] += n[c];
    }
    for (int32_t v = 0; v < mesh->vertex_count; ++v)
        pz_vec3_normalize(normals + 3 * (size_t)v);
}

/* Collects the neighbourhood of v: breadth-first over edges, keeping the
 * vertices closer than max_radius (the one-ring always). `stamp` marks
 * visited vertices with v (so it never needs clearing); `queue` holds V. */
static void gather_patch(const adjacency *adj, const double *positions, int32_t v, double max_radius,
                         int32_t *stamp, int32_t *queue, local_patch *patch)
{
    const double *center = positions + 3 * (size_t)v;
    int32_t head = 0, tail = 0;
    stamp[v] = v;
    queue[tail++] = v;
    patch->ring_count = adj->offsets[v + 1] - adj->offsets[v];
    while (head < tail) {
        int32_t u = queue[head++];
        for (int32_t k = adj->offsets[u]; k < adj->offsets[u + 1]; ++k) {
            int32_t w = adj->neighbours[k];
            if (stamp[w] == v)
                continue;
            stamp[w] = v;
            double d[3];
            pz_vec3_sub(positions + 3 * (size_t)w, center, d);
            double distance = sqrt(pz_vec3_dot(d, d));
            if (u != v && distance >= max_radius)
                continue;
            int32_t i = tail - 1;
            queue[tail++] = w;
            patch->xyz[3 * i] = pz_vec3_dot(d, patch->t1);
            patch->xyz[3 * i + 1] = pz_vec3_dot(d, patch->t2);
            patch->xyz[3 * i + 2] = pz_vec3_dot(d, patch->n);
            patch->distance[i] = distance;
        }
    }
    patch->count = tail - 1;
}

/* ---------------------------------------------------------------- per-vertex tensors */

/* tensors: V x S x 6. Returns 0 when out of memory. */
static int vertex_tensors(const pz_mesh *mesh, const adjacency *adj, const double *positions, double base_radius,
                          int32_t scale_count, double *tensors)
{
    int32_t n = mesh->vertex_count;
    double *normals = malloc(((size_t)n + 1) * 3 * sizeof *normals);
    int thread_count = omp_get_max_threads();
    int32_t *buffers = malloc(((size_t)thread_count * 2 * (size_t)n + 1) * sizeof *buffers);
    double *patch_buffers = malloc(((size_t)thread_count * 4 * (size_t)n + 1) * sizeof *patch_buffers);
    if (!normals || !buffers || !patch_buffers) {
        free(normals), free(buffers), free(patch_buffers);
        return 0;
    }
    vertex_normals(mesh, positions, normals);
    double max_radius = base_radius * (double)(1 << (scale_count - 1));
#pragma omp parallel num_threads(thread_count)
    {
        int t = omp_get_thread_num();
        int32_t *stamp = buffers + (size_t)t * 2 * n, *queue = stamp + n;
        for (int32_t v = 0; v < n; ++v)
            stamp[v] = -1;
        local_patch patch;
        patch.xyz = patch_buffers + (size_t)t * 4 * n;
        patch.distance = patch.xyz + 3 * (size_t)n;
#pragma omp for schedule(dynamic, 256)
        for (int32_t v = 0; v < n; ++v) {
            memcpy(patch.n, normals + 3 * (size_t)v, sizeof patch.n);
            double *out = tensors + (size_t)v * scale_count * 6;
            if (pz_vec3_dot(patch.n, patch.n) == 0.0) {
                memset(out, 0, (size_t)scale_count * 6 * sizeof *out);
                continue;
            }
            orthogonal3(patch.n, patch.t1);
            pz_vec3_cross(patch.n, patch.t1, patch.t2);
            gather_patch(adj, positions, v, max_radius, stamp, queue, &patch);
            for (int32_t s = 0; s < scale_count; ++s)
                fit_scale(&patch, base_radius * (double)(1 << s), out + 6 * s);
        }
    }
    free(normals), free(buffers), free(patch_buffers);
    return 1;
}

/* ---------------------------------------------------------------- per-face combination */

/* Face frame: e1 along the first edge, e2 = n x e1. Returns 0 for a degenerate face. */
static int face_frame(const double *positions, const int32_t *face, double e1[3], double e2[3], double n[3])
{
    double b[3];
    pz_vec3_sub(positions + 3 * (size_t)face[1], positions + 3 * (size_t)face[0], e1);
    pz_vec3_sub(positions + 3 * (size_t)face[2], positions + 3 * (size_t)face[0], b);
    pz_vec3_cross(e1, b, n);
    if (pz_vec3_normalize(n) == 0.0 || pz_vec3_normalize(e1) == 0.0)
        return 0;
    pz_vec3_cross(n, e1, e2);
    return 1;
}

/* t^T T u for a packed symmetric tensor. */
static double tensor_form(const double *t, const double *a, const double *b)
{
    double ta[3] = {t[0] * a[0] + t[1] * a[1] + t[2] * a[2], t[1] * a[0] + t[3] * a[1] + t[4] * a[2],
                    t[2] * a[0] + t[4] * a[1] + t[5] * a[2]};
    return pz_vec3_dot(ta, b);
}

static void combine_face(const pz_mesh *mesh, const double *positions, const double *tensors, int32_t scale_count,
                         double eps, int32_t f, pz_curvature *c)
{
    const int32_t *face = mesh->faces + 3 * (size_t)f;
    double e1[3], e2[3], n[3];
    double *direction = c->directions + 3 * (size_t)f;
    c->k_max[f] = c->k_min[f] = c->anisotropy[f] = 0.0;
    if (!face_frame(positions, face, e1, e2, n)) {
        direction[0] = direction[1] = direction[2] = 0.0;
        return;
    }
    double sum_re = 0.0, sum_im = 0.0, k_big = 0.0, k_small = 0.0;
    for (int32_t s = 0; s < scale_count; ++s) {
        double t[6] = {0};
        for (int k = 0; k < 3; ++k)
            for (int i = 0; i < 6; ++i)
                t[i] += tensors[((size_t)face[k] * scale_count + s) * 6 + i] / 3.0;
        double p = tensor_form(t, e1, e1), q = tensor_form(t, e1, e2), r = tensor_form(t, e2, e2);
        double mean = 0.5 * (p + r), radius = sqrt(0.25 * (p - r) * (p - r) + q * q);
        double lambda_hi = mean + radius, lambda_lo = mean - radius;
        double phi = 0.5 * atan2(2.0 * q, p - r);  /* direction of lambda_hi */
        double k1 = lambda_hi, k2 = lambda_lo;
        if (fabs(lambda_lo) > fabs(lambda_hi)) {
            k1 = lambda_lo, k2 = lambda_hi;
            phi += 0.5 * PZ_PI;
        }
        double a = (fabs(k1) - fabs(k2)) / (fabs(k1) + fabs(k2) + eps);
        sum_re += a * cos(4.0 * phi), sum_im += a * sin(4.0 * phi);
        k_big += k1 / scale_count, k_small += k2 / scale_count;
        if (s == 0) {
            /* The finest scale says which of the two cross arms carries k1. */
            for (int i = 0; i < 3; ++i)
                direction[i] = cos(phi) * e1[i] + sin(phi) * e2[i];
        }
    }
    double theta = 0.25 * atan2(sum_im, sum_re);
    /* Of the four arms of the combined cross, keep the one nearest the finest k1 direction. */
    double arm[3], best[3], best_dot = -1.0;
    for (int k = 0; k < 4; ++k) {
        double angle = theta + 0.5 * PZ_PI * k;
        for (int i = 0; i < 3; ++i)
            arm[i] = cos(angle) * e1[i] + sin(angle) * e2[i];
        double d = pz_vec3_dot(arm, direction);
        if (d > best_dot)
            best_dot = d, memcpy(best, arm, sizeof best);
    }
    memcpy(direction, best, sizeof best);
    c->anisotropy[f] = sqrt(sum_re * sum_re + sum_im * sum_im) / scale_count;
    c->k_max[f] = k_big, c->k_min[f] = k_small;
}

/* ---------------------------------------------------------------- public */

void pz_curvature_free(pz_curvature **curvature)
{
    if (!curvature || !*curvature)
        return;
    free((*curvature)->directions);
    free((*curvature)->k_max);
    free((*curvature)->k_min);
    free((*curvature)->anisotropy);
    free(*curvature);
    *curvature = NULL;
}

/* Square root of the surface area: a size that, unlike a bounding box, does not change with rotation. */
static double surface_size(const pz_mesh *mesh, const double *positions)
{
    double area = 0.0;
    for (int32_t f = 0; f < mesh->face_count; ++f) {
        const int32_t *face = mesh->faces + 3 * (size_t)f;
        double a[3], b[3], n[3];
        pz_vec3_sub(positions + 3 * (size_t)face[1], positions + 3 * (size_t)face[0], a);
        pz_vec3_sub(positions + 3 * (size_t)face[2], positions + 3 * (size_t)face[0], b);
        pz_vec3_cross(a, b, n);
        area += 0.5 * sqrt(pz_vec3_dot(n, n));
    }
    return sqrt(area);
}

pz_status pz_curvature_compute(const pz_mesh *mesh, const pz_topology *topology, const double *positions,
                               int32_t scale_count, pz_curvature **out, pz_ctx *ctx)
{
    *out = NULL;
    if (scale_count == 0)
        scale_count = PZ_FIELD_DEFAULT_SCALES;
    if (scale_count < 1 || scale_count > PZ_FIELD_MAX_SCALES)
        return pz_error(ctx, PZ_ERR_USAGE, "curvature: %d scales is outside 1 .. %d", (int)scale_count,
                        PZ_FIELD_MAX_SCALES);
    if (!positions)
        positions = mesh->positions;
    pz_curvature *c = calloc(1, sizeof *c);
    adjacency adj = {NULL, NULL};
    double *tensors = NULL;
    size_t f_count = (size_t)mesh->face_count + 1;
    if (c) {
        c->face_count = mesh->face_count;
        c->scale_count = scale_count;
        c->directions = malloc(f_count * 3 * sizeof *c->directions);
        c->k_max = malloc(f_count * sizeof *c->k_max);
        c->k_min = malloc(f_count * sizeof *c->k_min);
        c->anisotropy = malloc(f_count * sizeof *c->anisotropy);
        tensors = malloc(((size_t)mesh->vertex_count * scale_count * 6 + 1) * sizeof *tensors);
    }
    if (!c || !c->directions || !c->k_max || !c->k_min || !c->anisotropy || !tensors ||
        !adjacency_build(topology, &adj) ||
        !vertex_tensors(mesh, &adj, positions, pz_field_mean_edge_length(mesh, topology), scale_count, tensors)) {
        pz_curvature_free(&c);
        adjacency_free(&adj);
        free(tensors);
        return pz_error(ctx, PZ_ERR_NOMEM, "curvature: out of memory for %d faces", (int)mesh->face_count);
    }
    double size = surface_size(mesh, positions);
    double eps = size > 0.0 ? 0.5 / size : 1e-12;
#pragma omp parallel for schedule(static)
    for (int32_t f = 0; f < mesh->face_count; ++f)
        combine_face(mesh, positions, tensors, scale_count, eps, f, c);
    adjacency_free(&adj);
    free(tensors);
    *out = c;
    return PZ_OK;
}

/*
 * field/crossfield.c -- the smooth, curvature-aligned 4-RoSy cross-field
 * (pietroni2022 Sec. 4.1) and its singularities. Sketched curves are read
 * and snapped to faces in field/sketch.c (sharing the face frames through
 * field/internal.h); the field's files are written by field/writers.c.
 *
 * Representation: every face f has a frame (e1 along its first edge,
 * e2 = n x e1); a cross whose arm makes angle theta with e1 is the complex
 * number u_f = exp(4 i theta), which is the same for all four arms (the
 * "4th power" representation of Knoeppel et al. 2013 / Diamanti et al. 2014).
 * Across an interior edge with vector v, the Levi-Civita transport from f to
 * g (unfolding g onto f about the edge) turns angles by alpha_g - alpha_f,
 * alpha being the angle of v in each frame, so crosses compare through
 * rho_fg = exp(4 i (alpha_g - alpha_f)).
 *
 * Energy (one linear least-squares problem, normalised afterwards):
 *     E(u) = W sum_edges |u_g - rho_fg u_f|^2
 *          + sum_faces a_f (A_f / mean A) |u_f - c_f|^2
 * with W = --smoothness, c_f the curvature target exp(4 i phi_f) and a_f its
 * anisotropy (rest pose and every pose combined, see below), as Panozzo et
 * al. 2012 / Diamanti 2014 add soft alignment to a globally smooth field.
 * Hard constraints fix u_f for boundary faces (one arm along the longest
 * boundary edge of the face, so traced seams meet the boundary at right
 * angles) and for faces a sketched curve crosses (one arm along the curve);
 * sketches win over the boundary. Hard-constrained faces are eliminated: the
 * unknowns are the free faces only. The normal equations H u = b form a
 * Hermitian positive definite n x n system (H_ff = W deg_f + weight_f,
 * H_gf = -W rho_fg), factorised once by CHOLMOD as a complex LDL^H
 * (simplicial, AMD ordering). The same system written as a real symmetric
 * 2n x 2n one (x, y interleaved) gives the same field but has four times the
 * factor entries and took 4x longer (2.8 s against 0.7 s at 100K faces), so
 * the complex form is used. A connected component
 * with no constraint and no anisotropy at all has no preferred direction;
 * its first face is then fixed along its first edge (a seed).
 *
 * Poses (Sec. 4.1, last paragraph): each pose gets its own multi-scale
 * curvature; the pose direction of a face is carried to the rest face by the
 * affine map between the two triangles, and the targets are combined with the
 * 90-degree-invariant average sum_p a_p c_p (direction = arg / 4), the
 * anisotropy being the mean over the poses. One joint smoothing follows.
 *
 * Sketches: polylines sampled every quarter mean edge; every sample is
 * snapped to the closest point of the mesh through a uniform grid of face
 * bounding boxes (expanding shells of cells until no closer face can exist),
 * and its segment's tangent, projected into the face found, is averaged per
 * face as a 4th power weighted by the sample length.
 *
 * Singularities: around an interior vertex v the faces are visited in order;
 * each step f -> g adds delta = arg(u_g / (rho_fg u_f)) in (-pi, pi]. With
 * the angle defect K_v (the holonomy of the frames around v) the index is
 * (sum delta / 4 + K_v) / (2 pi), a multiple of 1/4; nonzero indices are the
 * singularities. Summed over a closed surface the delta terms cancel (each
 * edge is crossed once each way) and sum K_v = 2 pi chi (Gauss-Bonnet), so
 * the indices add up to the Euler characteristic exactly.
 *
 * Cost: O(F) assembly, the sparse factorisation (O(F^1.5)-ish fill for
 * surface meshes), O(F) singularities. Memory: ~10 doubles per face plus the
 * factor. Failure: PZ_ERR_USAGE (options), PZ_ERR_NOMEM, PZ_ERR_INTERNAL
 * (CHOLMOD failed), PZ_ERR_CANCELLED (pz_ctx.cancel, checked between the
 * steps: per pose, assembly, analysis, factorisation, solve, singularities);
 * nothing leaks and *out stays NULL.
 *
 * SPDX-License-Identifier: GPL-3.0-or-later
 */
#include "field/internal.h"
#include "core/vec.h"
#include "core/util.h"

#include <cholmod.h>
#include <math.h>
#include <stdlib.h>
#include <string.h>

double pz_field_cross_angle_deg(const double arm[3], const double direction[3], const double normal[3])
{
    double d[3];
    double along = pz_vec3_dot(direction, normal);
    for (int i = 0; i < 3; ++i)
        d[i] = direction[i] - along * normal[i];
    if (pz_vec3_normalize(d) == 0.0)
        return 0.0;
    double other[3];
    pz_vec3_cross(normal, arm, other);
    double angle = atan2(fabs(pz_vec3_dot(d, other)), fabs(pz_vec3_dot(d, arm))); /* 0 .. pi/2 */
    if (angle > 0.25 * PZ_PI)
        angle = 0.5 * PZ_PI - angle;
    return angle * 180.0 / PZ_PI;
}

/* ---------------------------------------------------------------- face frames */

static void frames_free(field_frames *fr)
{
    free(fr->e1), free(fr->e2), free(fr->n), free(fr->area);
    memset(fr, 0, sizeof *fr);
}

static int frames_build(const pz_mesh *mesh, field_frames *fr)
{
    size_t count = (size_t)mesh->face_count + 1;
    fr->e1 = malloc(count * 3 * sizeof(double));
    fr->e2 = malloc(count * 3 * sizeof(double));
    fr->n = malloc(count * 3 * sizeof(double));
    fr->area = malloc(count * sizeof(double));
    if (!fr->e1 || !fr->e2 || !fr->n || !fr->area)
        return 0;
    double total = 0.0;
    for (int32_t f = 0; f < mesh->face_count; ++f) {
        const int32_t *face = mesh->faces + 3 * (size_t)f;
        double *e1 = fr->e1 + 3 * (size_t)f, *e2 = fr->e2 + 3 * (size_t)f, *n = fr->n + 3 * (size_t)f, b[3];
        pz_vec3_sub(mesh->positions + 3 * (size_t)face[1], mesh->positions + 3 * (size_t)face[0], e1);
        pz_vec3_sub(mesh->positions + 3 * (size_t)face[2], mesh->positions + 3 * (size_t)face[0], b);
        pz_vec3_cross(e1, b, n);
        fr->area[f] = 0.5 * pz_vec3_normalize(n);
        pz_vec3_normalize(e1);
        pz_vec3_cross(n, e1, e2);
        total += fr->area[f];
    }
    fr->mean_area = mesh->face_count ? total / mesh->face_count : 1.0;
    if (!(fr->mean_area > 0.0))
        fr->mean_area = 1.0;
    return 1;
}

/* Angle of a 3D vector in face f's frame. */
static double frame_angle(const field_frames *fr, int32_t f, const double *v)
{
    return atan2(pz_vec3_dot(v, fr->e2 + 3 * (size_t)f), pz_vec3_dot(v, fr->e1 + 3 * (size_t)f));
}

static void frame_direction(const field_frames *fr, int32_t f, double angle, double *out)
{
    const double *e1 = fr->e1 + 3 * (size_t)f, *e2 = fr->e2 + 3 * (size_t)f;
    for (int i = 0; i < 3; ++i)
        out[i] = cos(angle) * e1[i] + sin(angle) * e2[i];
}

/* 4 (alpha_g - alpha_f) for the edge of half-edge h (face f) and its twin (face g). */
static double transport_angle(const pz_mesh *mesh, const pz_topology *topology, const field_frames *fr, int32_t h)
{
    int32_t t = topology->twin[h];
    double v[3];
    pz_vec3_sub(mesh->positions + 3 * (size_t)pz_he_to(topology, h), mesh->positions + 3 * (size_t)pz_he_from(topology, h), v);
    return 4.0 * (frame_angle(fr, pz_he_face(t), v) - frame_angle(fr, pz_he_face(h), v));
}

/* ---------------------------------------------------------------- curvature targets */

/* Carries a direction of pose face f to the rest face by the affine map between the triangles. */
static double pose_to_rest_angle(const pz_mesh *mesh, const field_frames *fr, const double *pose, int32_t f,
                                 const double *direction)
{
    const int32_t *face = mesh->faces + 3 * (size_t)f;
    double a[3], b[3];
    pz_vec3_sub(pose + 3 * (size_t)face[1], pose + 3 * (size_t)face[0], a);
    pz_vec3_sub(pose + 3 * (size_t)face[2], pose + 3 * (size_t)face[0], b);
    double aa = pz_vec3_dot(a, a), ab = pz_vec3_dot(a, b), bb = pz_vec3_dot(b, b), ad = pz_vec3_dot(a, direction), bd = pz_vec3_dot(b, direction);
    double det = aa * bb - ab * ab;
    if (!(fabs(det) > 0.0))
        return frame_angle(fr, f, direction);
    double alpha = (bb * ad - ab * bd) / det, beta = (aa * bd - ab * ad) / det, rest[3], ra[3], rb[3];
    pz_vec3_sub(mesh->positions + 3 * (size_t)face[1], mesh->positions + 3 * (size_t)face[0], ra);
    pz_vec3_sub(mesh->positions + 3 * (size_t)face[2], mesh->positions + 3 * (size_t)face[0], rb);
    for (int i = 0; i < 3; ++i)
        rest[i] = alpha * ra[i] + beta * rb[i];
    return frame_angle(fr, f, rest);
}

/* Combined curvature target per face: c = (re, im) unit, weight = mean anisotropy. */
static pz_status curvature_targets(const pz_mesh *mesh, const pz_topology *topology, const field_frames *fr,
                                   const pz_field_options *options, double *re, double *im, pz_field *field,
                                   pz_ctx *ctx)
{
    int32_t pose_total = 1 + (options->use_poses ? mesh->pose_count : 0);
    memset(re, 0, (size_t)mesh->face_count * sizeof *re);
    memset(im, 0, (size_t)mesh->face_count * sizeof *im);
    memset(field->anisotropy, 0, (size_t)mesh->face_count * sizeof *field->anisotropy);
    for (int32_t p = 0; p < pose_total; ++p) {
        const double *positions = p == 0 ? mesh->positions : mesh->poses + (size_t)(p - 1) * mesh->vertex_count * 3;
        pz_curvature *curvature = NULL;
        pz_status status = pz_check_cancel(ctx, "field");
        if (!status)
            status = pz_curvature_compute(mesh, topology, positions, options->scale_count, &curvature, ctx);
        if (status)
            return status;
        for (int32_t f = 0; f < mesh->face_count; ++f) {
            const double *d = curvature->directions + 3 * (size_t)f;
            double angle = p == 0 ? frame_angle(fr, f, d) : pose_to_rest_angle(mesh, fr, positions, f, d);
            double a = curvature->anisotropy[f];
            re[f] += a * cos(4.0 * angle), im[f] += a * sin(4.0 * angle);
            field->anisotropy[f] += a / pose_total;
        }
        pz_curvature_free(&curvature);
    }
    for (int32_t f = 0; f < mesh->face_count; ++f) {
        double angle = 0.25 * atan2(im[f], re[f]);
        frame_direction(fr, f, angle, field->curvature_directions + 3 * (size_t)f);
        re[f] = cos(4.0 * angle), im[f] = sin(4.0 * angle);
    }
    return PZ_OK;
}

/* ---------------------------------------------------------------- constraints */

/* Boundary faces: one arm along the longest boundary edge (unless sketched). Returns 0 when out of memory. */
static int boundary_constraints(const pz_mesh *mesh, const pz_topology *topology, pz_field *field)
{
    double *best_length = calloc((size_t)mesh->face_count + 1, sizeof *best_length);
    if (!best_length)
        return 0;
    for (int32_t h = 0; h < topology->halfedge_count; ++h) {
        int32_t f = pz_he_face(h);
        if (topology->twin[h] >= 0 || field->constraint[f] == PZ_FIELD_SKETCH)
            continue;
        double v[3];
        pz_vec3_sub(mesh->positions + 3 * (size_t)pz_he_to(topology, h), mesh->positions + 3 * (size_t)pz_he_from(topology, h), v);
        double length = pz_vec3_normalize(v);
        if (length <= best_length[f])
            continue;
        best_length[f] = length;
        field->constraint[f] = PZ_FIELD_BOUNDARY;
        memcpy(field->constraint_directions + 3 * (size_t)f, v, sizeof v);
    }
    free(best_length);
    return 1;
}

/* Components (over interior edges) without a constrained face or any anisotropy get one seed face. */
static int seed_free_components(const pz_mesh *mesh, const pz_topology *topology, const field_frames *fr,
                                pz_field *field)
{
    int32_t n = mesh->face_count;
    int32_t *parent = malloc(((size_t)n + 1) * sizeof *parent);
    uint8_t *anchored = calloc((size_t)n + 1, 1);
    if (!parent || !anchored) {
        free(parent), free(anchored);
        return 0;
    }
    for (int32_t f = 0; f < n; ++f)
        parent[f] = f;
    for (int32_t h = 0; h < topology->halfedge_count; ++h)
        if (topology->twin[h] > h)
            pz_union_find_join(parent, pz_he_face(h), pz_he_face(topology->twin[h]));
    for (int32_t f = 0; f < n; ++f)
        if (field->constraint[f] != PZ_FIELD_FREE || field->anisotropy[f] > 1e-6)
            anchored[pz_union_find_root(parent, f)] = 1;
    for (int32_t f = 0; f < n; ++f)
        if (parent[f] == f && !anchored[f]) {
            field->constraint[f] = PZ_FIELD_BOUNDARY; /* a seed behaves as a fixed face */
            memcpy(field->constraint_directions + 3 * (size_t)f, fr->e1 + 3 * (size_t)f, 3 * sizeof(double));
        }
    free(parent), free(anchored);
    return 1;
}

/* ---------------------------------------------------------------- the solve */

typedef struct solve_input {
    const pz_mesh *mesh;
    const pz_topology *topology;
    const field_frames *fr;
    double smoothness;
    const double *target_re, *target_im;  /* curvature targets */
    const double *align_weight;           /* face_count: a_f A_f / mean A */
    double *u_re, *u_im;                  /* in: values of the fixed faces; out: all faces */
    const uint8_t *fixed;
} solve_input;

/* Appends one complex entry (re, im) to a CHOLMOD_COMPLEX triplet matrix. */
static void triplet_add(cholmod_triplet *t, int32_t row, int32_t col, double re, double im)
{
    int32_t *ri = t->i, *ci = t->j;
    double *x = t->x;
    ri[t->nnz] = row, ci[t->nnz] = col;
    x[2 * t->nnz] = re, x[2 * t->nnz + 1] = im;
    ++t->nnz;
}

/*
 * Adds W |u_g - rho u_f|^2 for one interior edge (f, g): H_ff += W, H_gg += W,
 * H_gf = -W rho (lower triangle: the entry below the diagonal, conjugated
 * when g comes first); a fixed neighbour moves to the right-hand side,
 * b_f += W conj(rho) u_g or b_g += W rho u_f.
 */
static void assemble_edge(const solve_input *in, const int32_t *index, int32_t f, int32_t g, double rho,
                          cholmod_triplet *t, double *rhs)
{
    double w = in->smoothness, c = cos(rho), s = sin(rho);
    int32_t kf = index[f], kg = index[g];
    if (kf >= 0)
        triplet_add(t, kf, kf, w, 0.0);
    if (kg >= 0)
        triplet_add(t, kg, kg, w, 0.0);
    if (kf >= 0 && kg >= 0) {
        if (kg > kf)
            triplet_add(t, kg, kf, -w * c, -w * s);
        else
            triplet_add(t, kf, kg, -w * c, w * s);
    } else if (kf >= 0) {
        double x = in->u_re[g], y = in->u_im[g];
        rhs[2 * kf] += w * (c * x + s * y);
        rhs[2 * kf + 1] += w * (c * y - s * x);
    } else if (kg >= 0) {
        double x = in->u_re[f], y = in->u_im[f];
        rhs[2 * kg] += w * (c * x - s * y);
        rhs[2 * kg + 1] += w * (s * x + c * y);
    }
}

static pz_status solve_field(const solve_input *in, pz_ctx *ctx)
{
    const pz_mesh *mesh = in->mesh;
    int32_t n = mesh->face_count, free_count = 0;
    int32_t *index = malloc(((size_t)n + 1) * sizeof *index);
    if (!index)
        return pz_error(ctx, PZ_ERR_NOMEM, "field: out of memory");
    for (int32_t f = 0; f < n; ++f)
        index[f] = in->fixed[f] ? -1 : free_count++;
    if (free_count == 0) {
        free(index);
        return PZ_OK;
    }
    cholmod_common common;
    cholmod_start(&common);
    common.supernodal = CHOLMOD_SIMPLICIAL; /* reference BLAS: supernodal gained only 15-18 % (docs/field.md) */
    size_t size = (size_t)free_count;
    size_t max_entries = (size_t)n + 3 * (size_t)in->topology->edge_count + 2;
    cholmod_triplet *triplets = cholmod_allocate_triplet(size, size, max_entries, -1, CHOLMOD_COMPLEX, &common);
    cholmod_dense *rhs = cholmod_zeros(size, 1, CHOLMOD_COMPLEX, &common);
    cholmod_sparse *matrix = NULL;
    cholmod_factor *factor = NULL;
    cholmod_dense *solution = NULL;
    pz_status status = PZ_OK;
    if (!triplets || !rhs) {
        status = pz_error(ctx, PZ_ERR_NOMEM, "field: out of memory for the system of %d faces", (int)free_count);
        goto done;
    }
    double *b = rhs->x;
    for (int32_t f = 0; f < n; ++f) {
        int32_t k = index[f];
        if (k < 0)
            continue;
        /* Alignment plus a tiny ridge so that a nearly isotropic region stays well posed. */
        double a = in->align_weight[f];
        triplet_add(triplets, k, k, a + 1e-10 * in->smoothness, 0.0);
        b[2 * k] += a * in->target_re[f];
        b[2 * k + 1] += a * in->target_im[f];
    }
    for (int32_t h = 0; h < in->topology->halfedge_count; ++h) {
        int32_t t = in->topology->twin[h];
        if (t > h)
            assemble_edge(in, index, pz_he_face(h), pz_he_face(t), transport_angle(mesh, in->topology, in->fr, h),
                          triplets, b);
    }
    if ((status = pz_check_cancel(ctx, "field")))
        goto done;
    matrix = cholmod_triplet_to_sparse(triplets, triplets->nnz, &common);
    if (matrix)
        factor = cholmod_analyze(matrix, &common);
    if (factor && (status = pz_check_cancel(ctx, "field")))
        goto done;
    if (factor)
        cholmod_factorize(matrix, factor, &common);
    if (!matrix || !factor || common.status != CHOLMOD_OK || factor->minor < factor->n) {
        status = common.status == CHOLMOD_OUT_OF_MEMORY
                     ? pz_error(ctx, PZ_ERR_NOMEM, "field: out of memory factorising %zu unknowns", size)
                     : pz_error(ctx, PZ_ERR_INTERNAL, "field: factorisation failed (CHOLMOD status %d)", common.status);
        goto done;
    }
    if ((status = pz_check_cancel(ctx, "field")))
        goto done;
    solution = cholmod_solve(CHOLMOD_A, factor, rhs, &common);
    if (!solution || common.status != CHOLMOD_OK) {
        status = pz_error(ctx, PZ_ERR_INTERNAL, "field: solve failed (CHOLMOD status %d)", common.status);
        goto done;
    }
    const double *x = solution->x;
    for (int32_t f = 0; f < n; ++f)
        if (index[f] >= 0)
            in->u_re[f] = x[2 * index[f]], in->u_im[f] = x[2 * index[f] + 1];
done:
    cholmod_free_dense(&solution, &common);
    cholmod_free_factor(&factor, &common);
    cholmod_free_sparse(&matrix, &common);
    cholmod_free_dense(&rhs, &common);
    cholmod_free_triplet(&triplets, &common);
    cholmod_finish(&common);
    free(index);
    return status;
}

/* ---------------------------------------------------------------- singularities */

static double wrap_angle(double a)
{
    a = fmod(a, 2.0 * PZ_PI);
    if (a > PZ_PI) a -= 2.0 * PZ_PI;
    if (a <= -PZ_PI) a += 2.0 * PZ_PI;
    return a;
}

static pz_status find_singularities(const pz_mesh *mesh, const pz_topology *topology, const field_frames *fr,
                                    const double *u_re, const double *u_im, pz_field *field, pz_ctx *ctx)
{
    double *defect = malloc(((size_t)mesh->vertex_count + 1) * sizeof *defect);
    size_t capacity = 0;
    if (!defect)
        return pz_error(ctx, PZ_ERR_NOMEM, "field: out of memory");
    pz_geom_angle_defect(mesh, topology, defect);
    field->index_sum = 0.0;
    for (int32_t v = 0; v < mesh->vertex_count; ++v) {
        int32_t h0 = topology->vertex_halfedge[v];
        if (h0 < 0 || topology->vertex_on_boundary[v])
            continue;
        double turn = 0.0;
        int32_t h = h0;
        do {
            int32_t p = pz_he_prev(h), t = topology->twin[p];
            int32_t f = pz_he_face(p), g = pz_he_face(t);
            double rho = transport_angle(mesh, topology, fr, p);
            double arg_f = atan2(u_im[f], u_re[f]), arg_g = atan2(u_im[g], u_re[g]);
            turn += wrap_angle(arg_g - arg_f - rho);
            h = t;
        } while (h != h0);
        double index = (turn / 4.0 + defect[v]) / (2.0 * PZ_PI);
        double quarters = round(index * 4.0);
        if (quarters == 0.0)
            continue;
        size_t old_capacity = capacity;
        if (!pz_grow((void **)&field->singular_vertices, &capacity, (size_t)field->singularity_count + 1,
                     sizeof *field->singular_vertices)) {
            free(defect);
            return pz_error(ctx, PZ_ERR_NOMEM, "field: out of memory");
        }
        if (capacity != old_capacity) {
            double *grown = realloc(field->singular_indices, capacity * sizeof *grown);
            if (!grown) {
                free(defect);
                return pz_error(ctx, PZ_ERR_NOMEM, "field: out of memory");
            }
            field->singular_indices = grown;
        }
        field->singular_vertices[field->singularity_count] = v;
        field->singular_indices[field->singularity_count++] = quarters / 4.0;
        field->index_sum += quarters / 4.0;
    }
    free(defect);
    return PZ_OK;
}

/* ---------------------------------------------------------------- figures */

static void alignment_figures(const pz_mesh *mesh, const pz_topology *topology, pz_field *field)
{
    double sum = 0.0, weight = 0.0;
    double *areas = malloc(((size_t)mesh->face_count + 1) * sizeof *areas);
    if (areas)
        pz_geom_face_areas(mesh, areas);
    for (int32_t f = 0; f < mesh->face_count; ++f) {
        double w = field->anisotropy[f] * (areas ? areas[f] : 1.0);
        sum += w * pz_field_cross_angle_deg(field->directions + 3 * (size_t)f,
                                            field->curvature_directions + 3 * (size_t)f, field->normals + 3 * (size_t)f);
        weight += w;
    }
    free(areas);
    field->curvature_alignment_deg = weight > 0.0 ? sum / weight : 0.0;
    /* Boundary: the longest boundary edge of every face that has one, sketched or not. */
    double b_sum = 0.0;
    int32_t b_count = 0;
    for (int32_t h = 0; h < topology->halfedge_count; ++h) {
        if (topology->twin[h] >= 0)
            continue;
        int32_t f = pz_he_face(h), longest = h;
        for (int k = 0; k < 3; ++k) {
            int32_t other = 3 * f + k;
            double a[3], b[3];
            pz_vec3_sub(mesh->positions + 3 * (size_t)pz_he_to(topology, other), mesh->positions + 3 * (size_t)pz_he_from(topology, other), a);
            pz_vec3_sub(mesh->positions + 3 * (size_t)pz_he_to(topology, longest), mesh->positions + 3 * (size_t)pz_he_from(topology, longest), b);
            if (topology->twin[other] < 0 && (pz_vec3_dot(a, a) > pz_vec3_dot(b, b) || (pz_vec3_dot(a, a) == pz_vec3_dot(b, b) && other < longest)))
                longest = other;
        }
        if (longest != h)
            continue;
        double v[3];
        pz_vec3_sub(mesh->positions + 3 * (size_t)pz_he_to(topology, h), mesh->positions + 3 * (size_t)pz_he_from(topology, h), v);
        b_sum += pz_field_cross_angle_deg(field->directions + 3 * (size_t)f, v, field->normals + 3 * (size_t)f);
        ++b_count;
    }
    field->boundary_alignment_deg = b_count ? b_sum / b_count : -1.0;
    double s_sum = 0.0;
    int32_t s_count = 0;
    for (int32_t f = 0; f < mesh->face_count; ++f)
        if (field->constraint[f] == PZ_FIELD_SKETCH) {
            s_sum += pz_field_cross_angle_deg(field->directions + 3 * (size_t)f,
                                              field->constraint_directions + 3 * (size_t)f, field->normals + 3 * (size_t)f);
            ++s_count;
        }
    field->sketch_alignment_deg = s_count ? s_sum / s_count : -1.0;
}

/* ---------------------------------------------------------------- public */

void pz_field_free(pz_field **field)
{
    if (!field || !*field)
        return;
    pz_field *f = *field;
    free(f->directions), free(f->normals), free(f->curvature_directions), free(f->anisotropy);
    free(f->constraint), free(f->constraint_directions), free(f->singular_vertices), free(f->singular_indices);
    free(f);
    *field = NULL;
}

static pz_field *field_allocate(int32_t face_count)
{
    pz_field *field = calloc(1, sizeof *field);
    if (!field)
        return NULL;
    size_t n = (size_t)face_count + 1;
    field->face_count = face_count;
    field->directions = calloc(n * 3, sizeof(double));
    field->normals = calloc(n * 3, sizeof(double));
    field->curvature_directions = calloc(n * 3, sizeof(double));
    field->anisotropy = calloc(n, sizeof(double));
    field->constraint = calloc(n, 1);
    field->constraint_directions = calloc(n * 3, sizeof(double));
    if (!field->directions || !field->normals || !field->curvature_directions || !field->anisotropy ||
        !field->constraint || !field->constraint_directions)
        pz_field_free(&field);
    return field;
}

pz_status pz_field_copy(const pz_field *field, pz_field **out, pz_ctx *ctx)
{
    *out = NULL;
    if (!field)
        return pz_error(ctx, PZ_ERR_USAGE, "field: nothing to copy");
    pz_field *copy = field_allocate(field->face_count);
    size_t n = (size_t)field->face_count, singular = (size_t)field->singularity_count;
    if (copy) {
        double *directions = copy->directions, *normals = copy->normals, *curvature = copy->curvature_directions;
        double *anisotropy = copy->anisotropy, *constraint_directions = copy->constraint_directions;
        uint8_t *constraint = copy->constraint;
        *copy = *field; /* the figures; the arrays are this copy's own */
        copy->directions = directions, copy->normals = normals, copy->curvature_directions = curvature;
        copy->anisotropy = anisotropy, copy->constraint = constraint, copy->constraint_directions = constraint_directions;
        copy->singular_vertices = malloc(singular * sizeof(int32_t) + 1);
        copy->singular_indices = malloc(singular * sizeof(double) + 1);
        if (!copy->singular_vertices || !copy->singular_indices)
            pz_field_free(&copy);
    }
    if (!copy)
        return pz_error(ctx, PZ_ERR_NOMEM, "field: out of memory copying a field of %d faces", (int)n);
    memcpy(copy->directions, field->directions, 3 * n * sizeof(double));
    memcpy(copy->normals, field->normals, 3 * n * sizeof(double));
    memcpy(copy->curvature_directions, field->curvature_directions, 3 * n * sizeof(double));
    memcpy(copy->anisotropy, field->anisotropy, n * sizeof(double));
    memcpy(copy->constraint, field->constraint, n);
    memcpy(copy->constraint_directions, field->constraint_directions, 3 * n * sizeof(double));
    if (singular > 0) {
        memcpy(copy->singular_vertices, field->singular_vertices, singular * sizeof(int32_t));
        memcpy(copy->singular_indices, field->singular_indices, singular * sizeof(double));
    }
    *out = copy;
    return PZ_OK;
}

/* Sketch constraints into field->constraint / constraint_directions. */
static pz_status apply_sketch(const pz_mesh *mesh, const field_frames *fr, const pz_sketch *sketch, pz_field *field,
                              pz_ctx *ctx)
{
    /* A point far off the surface would snap nowhere sensible (and each sample would scan the grid). */
    pz_status checked = pz_sketch_check(sketch, mesh, "field: sketch", ctx);
    if (checked != PZ_OK)
        return checked;
    double *re = calloc((size_t)mesh->face_count + 1, sizeof *re);
    double *im = calloc((size_t)mesh->face_count + 1, sizeof *im);
    if (!re || !im || !field_sketch_accumulate(mesh, fr, sketch, field->mean_edge_length, re, im)) {
        free(re), free(im);
        return pz_error(ctx, PZ_ERR_NOMEM, "field: out of memory snapping the sketch");
    }
    for (int32_t f = 0; f < mesh->face_count; ++f) {
        if (!(hypot(re[f], im[f]) > 1e-12 * field->mean_edge_length))
            continue;
        field->constraint[f] = PZ_FIELD_SKETCH;
        frame_direction(fr, f, 0.25 * atan2(im[f], re[f]), field->constraint_directions + 3 * (size_t)f);
        ++field->sketch_face_count;
    }
    free(re), free(im);
    return PZ_OK;
}

/* Values of the fixed faces, and the alignment weight of every face. */
static void prepare_unknowns(const pz_mesh *mesh, const field_frames *fr, const pz_field *field, double *u_re,
                             double *u_im, double *align_weight)
{
    for (int32_t f = 0; f < mesh->face_count; ++f) {
        double angle = frame_angle(fr, f, field->constraint_directions + 3 * (size_t)f);
        int fixed = field->constraint[f] != PZ_FIELD_FREE;
        u_re[f] = fixed ? cos(4.0 * angle) : 0.0;
        u_im[f] = fixed ? sin(4.0 * angle) : 0.0;
        align_weight[f] = field->anisotropy[f] * fr->area[f] / fr->mean_area;
    }
}

pz_status pz_field_compute(const pz_mesh *mesh, const pz_topology *topology, const pz_field_options *options,
                           pz_field **out, pz_ctx *ctx)
{
    *out = NULL;
    pz_field_options opts;
    if (options)
        opts = *options;
    else
        pz_field_options_default(&opts);
    if (opts.smoothness == 0.0)
        opts.smoothness = PZ_FIELD_DEFAULT_SMOOTHNESS;
    if (!(opts.smoothness > 0.0) || !isfinite(opts.smoothness))
        return pz_error(ctx, PZ_ERR_USAGE, "field: smoothness must be a positive number");
    if (opts.scale_count < 0 || opts.scale_count > PZ_FIELD_MAX_SCALES)
        return pz_error(ctx, PZ_ERR_USAGE, "field: %d scales is outside 1 .. %d", (int)opts.scale_count,
                        PZ_FIELD_MAX_SCALES);
    int32_t n = mesh->face_count;
    pz_field *field = field_allocate(n);
    field_frames fr = {NULL, NULL, NULL, NULL, 0.0};
    double *target_re = malloc(((size_t)n + 1) * sizeof(double)), *target_im = malloc(((size_t)n + 1) * sizeof(double));
    double *u_re = malloc(((size_t)n + 1) * sizeof(double)), *u_im = malloc(((size_t)n + 1) * sizeof(double));
    double *align_weight = malloc(((size_t)n + 1) * sizeof(double));
    pz_status status = pz_check_cancel(ctx, "field");
    if (status)
        goto done;
    if (!field || !frames_build(mesh, &fr) || !target_re || !target_im || !u_re || !u_im || !align_weight) {
        status = pz_error(ctx, PZ_ERR_NOMEM, "field: out of memory for %d faces", (int)n);
        goto done;
    }
    memcpy(field->normals, fr.n, (size_t)n * 3 * sizeof(double));
    field->mean_edge_length = pz_field_mean_edge_length(mesh, topology);

    double start = pz_seconds();
    if ((status = curvature_targets(mesh, topology, &fr, &opts, target_re, target_im, field, ctx)))
        goto done;
    double curvature_end = pz_seconds();
    if ((status = pz_check_cancel(ctx, "field")))
        goto done;
    if (opts.sketch && (status = apply_sketch(mesh, &fr, opts.sketch, field, ctx)))
        goto done;
    double sketch_end = pz_seconds();
    if (!boundary_constraints(mesh, topology, field)) {
        status = pz_error(ctx, PZ_ERR_NOMEM, "field: out of memory");
        goto done;
    }
    for (int32_t f = 0; f < n; ++f)
        field->boundary_face_count += field->constraint[f] == PZ_FIELD_BOUNDARY;
    if (!seed_free_components(mesh, topology, &fr, field)) {
        status = pz_error(ctx, PZ_ERR_NOMEM, "field: out of memory");
        goto done;
    }
    prepare_unknowns(mesh, &fr, field, u_re, u_im, align_weight);
    solve_input input = {mesh, topology, &fr, opts.smoothness, target_re, target_im, align_weight, u_re, u_im,
                         field->constraint};
    if ((status = solve_field(&input, ctx)))
        goto done;
    for (int32_t f = 0; f < n; ++f)
        frame_direction(&fr, f, 0.25 * atan2(u_im[f], u_re[f]), field->directions + 3 * (size_t)f);
    double solve_end = pz_seconds();
    if ((status = pz_check_cancel(ctx, "field")))
        goto done;
    if ((status = find_singularities(mesh, topology, &fr, u_re, u_im, field, ctx)))
        goto done;
    alignment_figures(mesh, topology, field);
    double end = pz_seconds();
    field->curvature_ms = 1e3 * (curvature_end - start);
    field->sketch_ms = 1e3 * (sketch_end - curvature_end);
    field->solve_ms = 1e3 * (solve_end - sketch_end);
    field->singularity_ms = 1e3 * (end - solve_end);
done:
    frames_free(&fr);
    free(target_re), free(target_im), free(u_re), free(u_im), free(align_weight);
    if (status)
        pz_field_free(&field);
    *out = field;
    return status;
}

void pz_field_options_default(pz_field_options *options)
{
    memset(options, 0, sizeof *options);
}

/* ---------------------------------------------------------------- symmetry */

/*
 * Each free face's cross (u, its 4th power in the face's frame, from its arm)
 * averaged with the cross of its mirror face reflected through the plane and
 * turned into the face's frame (the reflection of an arm is an arm of the
 * reflected cross, so one arm is enough). Constrained faces keep their
 * crosses: the border is its own mirror image already, a sketch is the
 * user's. Every face is averaged from the input crosses, so the result does
 * not depend on the face order, and a face and its mirror face get mirror
 * images of each other when each is the other's mirror face.
 */
static void mirror_average(const field_frames *fr, const pz_field *in, const int32_t *mirror_faces,
                           const double normal[3], double *u_re, double *u_im)
{
    int32_t n = in->face_count;
    for (int32_t f = 0; f < n; ++f) {
        double angle = 4 * frame_angle(fr, f, in->directions + 3 * (size_t)f);
        u_re[f] = cos(angle), u_im[f] = sin(angle);
    }
    for (int32_t f = 0; f < n; ++f) {
        int32_t g = mirror_faces[f];
        if (g < 0 || g >= n || g == f || in->constraint[f] != PZ_FIELD_FREE)
            continue;
        const double *arm = in->directions + 3 * (size_t)g;
        double reflected[3], t = pz_vec3_dot(arm, normal);
        for (int k = 0; k < 3; ++k)
            reflected[k] = arm[k] - 2 * t * normal[k];
        double own = 4 * frame_angle(fr, f, in->directions + 3 * (size_t)f), image = 4 * frame_angle(fr, f, reflected);
        double re = cos(own) + cos(image), im = sin(own) + sin(image);
        if (hypot(re, im) > 1e-9) /* opposite crosses (45 degrees apart) average to nothing: keep the face's own */
            u_re[f] = re, u_im[f] = im;
    }
}

static int field_copy_arrays(const pz_field *from, pz_field *to)
{
    size_t n = (size_t)from->face_count;
    if (!to)
        return 0;
    memcpy(to->normals, from->normals, 3 * n * sizeof(double));
    memcpy(to->curvature_directions, from->curvature_directions, 3 * n * sizeof(double));
    memcpy(to->anisotropy, from->anisotropy, n * sizeof(double));
    memcpy(to->constraint, from->constraint, n);
    memcpy(to->constraint_directions, from->constraint_directions, 3 * n * sizeof(double));
    to->boundary_face_count = from->boundary_face_count, to->sketch_face_count = from->sketch_face_count;
    to->mean_edge_length = from->mean_edge_length;
    to->curvature_ms = from->curvature_ms, to->sketch_ms = from->sketch_ms, to->solve_ms = from->solve_ms;
    return 1;
}

pz_status pz_field_mirrored(const pz_mesh *mesh, const pz_topology *topology, const pz_field *field,
                            const int32_t *mirror_faces, const double normal[3], pz_field **out, pz_ctx *ctx)
{
    *out = NULL;
    if (!field || field->face_count != mesh->face_count || !mirror_faces)
        return pz_error(ctx, PZ_ERR_USAGE, "field: no field of this mesh or no mirror faces to symmetrize with");
    int32_t n = mesh->face_count;
    pz_field *mirrored = field_allocate(n);
    field_frames fr = {NULL, NULL, NULL, NULL, 0.0};
    double *u_re = malloc(((size_t)n + 1) * sizeof(double)), *u_im = malloc(((size_t)n + 1) * sizeof(double));
    pz_status status = PZ_OK;
    double start = pz_seconds();
    if (!field_copy_arrays(field, mirrored) || !frames_build(mesh, &fr) || !u_re || !u_im)
        status = pz_error(ctx, PZ_ERR_NOMEM, "field: out of memory for %d faces", (int)n);
    if (!status) {
        mirror_average(&fr, field, mirror_faces, normal, u_re, u_im);
        for (int32_t f = 0; f < n; ++f)
            frame_direction(&fr, f, 0.25 * atan2(u_im[f], u_re[f]), mirrored->directions + 3 * (size_t)f);
        status = find_singularities(mesh, topology, &fr, u_re, u_im, mirrored, ctx);
    }
    if (!status) {
        alignment_figures(mesh, topology, mirrored);
        mirrored->singularity_ms = 1e3 * (pz_seconds() - start);
    }
    frames_free(&fr);
    free(u_re), free(u_im);
    if (status)
        pz_field_free(&mirrored);
    *out = mirrored;
    return status;
}

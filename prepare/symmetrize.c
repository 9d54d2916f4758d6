/*
 * prepare/symmetrize.c -- an exactly mirror-symmetric garment from a nearly
 * symmetric one, as pietroni2022 does before its layout (Sec. 3, Fig. 3a):
 * split along the plane, keep one half, reflect it, weld along the plane
 * (docs/segment.md, "Symmetry", "The symmetrized garment").
 *
 *  1. every vertex's signed distance to the plane; a vertex within a tenth
 *     of the mean edge length of it is snapped onto it (a cut that close
 *     would leave sliver triangles);
 *  2. each face on the negative side is kept, each face the plane crosses
 *     clipped to its negative part (one cut point per crossed edge, shared
 *     by the two faces of the edge, projected onto the plane), the clipped
 *     polygon fanned into triangles; faces lying in the plane are dropped;
 *  3. the kept half reflected (faces reversed to keep their orientation);
 *     its vertices on the plane are shared by both halves (the weld), so
 *     vertex i and vertex_mirror[i] are exact reflections and the vertex and
 *     face maps are bijections by construction. A plane vertex on no plane
 *     edge (the surface only touches the plane there) gets its own mirror
 *     copy: sharing it would pinch two sheets at one point.
 *
 * The result must be a valid manifold (a half folding onto the plane along
 * an edge would give that edge four faces): otherwise PZ_ERR_DATA, and the
 * caller goes on with the garment as it is.
 *
 * SPDX-License-Identifier: GPL-3.0-or-later
 */
#define _POSIX_C_SOURCE 200809L
#include "prepare/internal.h"
#include "prepare/cgal_shim.h"

#include <math.h>
#include <stdlib.h>
#include <string.h>

/* A vertex this close to the plane (as a fraction of the mean edge length) is put on it: a cut closer to a vertex
 * would leave a sliver triangle, and a larger snap moves more of the input. The layouts made on the result are
 * sensitive to it (docs/segment.md, "The symmetrized garment", measured at 0.05, 0.1, 0.2 and a third). */
#define SNAP_FRACTION 0.1

void pz_symmetrized_clear(pz_symmetrized *symmetrized)
{
    if (!symmetrized)
        return;
    pz_mesh_free(&symmetrized->mesh);
    free(symmetrized->vertex_mirror);
    free(symmetrized->face_mirror);
    free(symmetrized->vertex_side);
    free(symmetrized->input_nearest);
    memset(symmetrized, 0, sizeof *symmetrized);
}

/* The work of one symmetrization: the input's signed distances, its edges' cut points, the kept half. */
typedef struct halving {
    const pz_mesh *input;
    const pz_topology *topology;
    double normal[3], offset;
    double *distance;        /* input vertex count: signed distance, 0 on (or snapped onto) the plane */
    int32_t *vertex_new;     /* input vertex -> kept-half vertex, -1 */
    int32_t *edge_cut;       /* input edge -> kept-half vertex of its cut point, -1 */
    double *positions;       /* kept-half vertices x 3 */
    int32_t vertex_count, vertex_capacity;
    int32_t *faces;          /* kept-half faces x 3 */
    int32_t *face_origin;    /* the input face each kept face comes from */
    int32_t face_count, face_capacity;
} halving;

static void halving_free(halving *h)
{
    free(h->distance), free(h->vertex_new), free(h->edge_cut), free(h->positions), free(h->faces);
    free(h->face_origin);
}

static void project_onto_plane(const halving *h, double p[3])
{
    double s = p[0] * h->normal[0] + p[1] * h->normal[1] + p[2] * h->normal[2] - h->offset;
    for (int d = 0; d < 3; ++d)
        p[d] -= s * h->normal[d];
}

/* A new kept-half vertex at p; -1 when out of memory. */
static int32_t add_vertex(halving *h, const double p[3])
{
    if (h->vertex_count == h->vertex_capacity) {
        int32_t capacity = 2 * h->vertex_capacity + 16;
        double *grown = realloc(h->positions, 3 * (size_t)capacity * sizeof(double));
        if (!grown)
            return -1;
        h->positions = grown, h->vertex_capacity = capacity;
    }
    memcpy(h->positions + 3 * (size_t)h->vertex_count, p, 3 * sizeof(double));
    return h->vertex_count++;
}

static int add_face(halving *h, int32_t a, int32_t b, int32_t c, int32_t origin)
{
    if (h->face_count == h->face_capacity) {
        int32_t capacity = 2 * h->face_capacity + 16;
        int32_t *faces = realloc(h->faces, 3 * (size_t)capacity * sizeof(int32_t));
        if (faces)
            h->faces = faces;
        int32_t *origins = realloc(h->face_origin, (size_t)capacity * sizeof(int32_t));
        if (origins)
            h->face_origin = origins;
        if (!faces || !origins)
            return 0;
        h->face_capacity = capacity;
    }
    int32_t *face = h->faces + 3 * (size_t)h->face_count;
    face[0] = a, face[1] = b, face[2] = c;
    h->face_origin[h->face_count++] = origin;
    return 1;
}

/* The kept-half vertex of input vertex v (on the negative side or the plane), made on first use. */
static int32_t kept_vertex(halving *h, int32_t v)
{
    if (h->vertex_new[v] < 0) {
        double p[3];
        memcpy(p, h->input->positions + 3 * (size_t)v, sizeof p);
        if (h->distance[v] == 0)
            project_onto_plane(h, p);
        h->vertex_new[v] = add_vertex(h, p);
    }
    return h->vertex_new[v];
}

/* The cut point of the edge of half-edge e (a strictly negative, b strictly positive or the reverse). */
static int32_t cut_vertex(halving *h, int32_t e)
{
    int32_t edge = h->topology->halfedge_edge[e];
    if (h->edge_cut[edge] < 0) {
        int32_t a = pz_he_from(h->topology, e), b = pz_he_to(h->topology, e);
        if (a > b) { /* the same point whichever face asks first */
            int32_t swap = a;
            a = b, b = swap;
        }
        double t = h->distance[a] / (h->distance[a] - h->distance[b]), p[3];
        for (int d = 0; d < 3; ++d)
            p[d] = h->input->positions[3 * (size_t)a + d] +
                   t * (h->input->positions[3 * (size_t)b + d] - h->input->positions[3 * (size_t)a + d]);
        project_onto_plane(h, p);
        h->edge_cut[edge] = add_vertex(h, p);
    }
    return h->edge_cut[edge];
}

static double squared_distance(const halving *h, int32_t a, int32_t b)
{
    double sum = 0;
    for (int d = 0; d < 3; ++d) {
        double x = h->positions[3 * (size_t)a + d] - h->positions[3 * (size_t)b + d];
        sum += x * x;
    }
    return sum;
}

/* Face f clipped to the negative side (Sutherland-Hodgman on one plane), fanned into triangles. */
static int clip_face(halving *h, int32_t f)
{
    int32_t polygon[4], n = 0;
    for (int k = 0; k < 3; ++k) {
        int32_t e = 3 * f + k, a = pz_he_from(h->topology, e), b = pz_he_to(h->topology, e);
        double sa = h->distance[a], sb = h->distance[b];
        if (sa <= 0) {
            int32_t v = kept_vertex(h, a);
            if (v < 0)
                return 0;
            polygon[n++] = v;
        }
        if ((sa < 0 && sb > 0) || (sa > 0 && sb < 0)) {
            int32_t v = cut_vertex(h, e);
            if (v < 0)
                return 0;
            polygon[n++] = v;
        }
    }
    if (n == 3)
        return add_face(h, polygon[0], polygon[1], polygon[2], f);
    if (n < 3) /* only an edge or a corner touches the negative side */
        return 1;
    /* A quad: the shorter diagonal. */
    int first = squared_distance(h, polygon[0], polygon[2]) <= squared_distance(h, polygon[1], polygon[3]) ? 0 : 1;
    return add_face(h, polygon[first], polygon[first + 1], polygon[(first + 2) % 4], f) &&
           add_face(h, polygon[first], polygon[(first + 2) % 4], polygon[(first + 3) % 4], f);
}

/* Signed distances, snapped within SNAP_FRACTION of the mean edge length. */
static void signed_distances(halving *h, int32_t *snapped)
{
    const pz_mesh *mesh = h->input;
    double length = 0;
    int32_t edges = 0;
    for (int32_t e = 0; e < h->topology->edge_count; ++e) {
        int32_t he = h->topology->edge_halfedge[2 * e];
        const double *a = mesh->positions + 3 * (size_t)pz_he_from(h->topology, he);
        const double *b = mesh->positions + 3 * (size_t)pz_he_to(h->topology, he);
        length += sqrt((a[0] - b[0]) * (a[0] - b[0]) + (a[1] - b[1]) * (a[1] - b[1]) + (a[2] - b[2]) * (a[2] - b[2]));
        ++edges;
    }
    double snap = edges > 0 ? SNAP_FRACTION * length / edges : 0;
    *snapped = 0;
    for (int32_t v = 0; v < mesh->vertex_count; ++v) {
        const double *p = mesh->positions + 3 * (size_t)v;
        double s = p[0] * h->normal[0] + p[1] * h->normal[1] + p[2] * h->normal[2] - h->offset;
        if (fabs(s) <= snap) {
            *snapped += s != 0;
            s = 0;
        }
        h->distance[v] = s;
    }
}

/*
 * The whole garment from the kept half: its vertices, then the mirror copies
 * of those off the plane (and of plane vertices on no plane edge); its faces,
 * then their reflections, reversed.
 */
static pz_status reflect_half(const halving *h, pz_symmetrized *out, pz_ctx *ctx)
{
    int32_t n = h->vertex_count, faces = h->face_count;
    uint8_t *on_plane_edge = calloc((size_t)n + 1, 1);
    int32_t *mirror = malloc(((size_t)n + 1) * sizeof(int32_t));
    if (!on_plane_edge || !mirror) {
        free(on_plane_edge), free(mirror);
        return pz_error(ctx, PZ_ERR_NOMEM, "symmetrize: out of memory");
    }
    /* A kept vertex is on the plane when it is a cut point or a plane (snapped) input vertex. */
    uint8_t *plane = calloc((size_t)n + 1, 1);
    if (!plane) {
        free(on_plane_edge), free(mirror);
        return pz_error(ctx, PZ_ERR_NOMEM, "symmetrize: out of memory");
    }
    for (int32_t v = 0; v < h->input->vertex_count; ++v)
        if (h->vertex_new[v] >= 0 && h->distance[v] == 0)
            plane[h->vertex_new[v]] = 1;
    for (int32_t e = 0; e < h->topology->edge_count; ++e)
        if (h->edge_cut[e] >= 0)
            plane[h->edge_cut[e]] = 1;
    for (int32_t f = 0; f < faces; ++f)
        for (int k = 0; k < 3; ++k) {
            int32_t a = h->faces[3 * (size_t)f + k], b = h->faces[3 * (size_t)f + (k + 1) % 3];
            if (plane[a] && plane[b])
                on_plane_edge[a] = on_plane_edge[b] = 1;
        }
    int32_t total = n;
    for (int32_t v = 0; v < n; ++v)
        mirror[v] = plane[v] && on_plane_edge[v] ? v : total++;
    pz_status status = pz_mesh_create(total, 2 * faces, &out->mesh, ctx);
    if (status == PZ_OK) {
        out->vertex_mirror = malloc(((size_t)total + 1) * sizeof(int32_t));
        out->face_mirror = malloc((2 * (size_t)faces + 1) * sizeof(int32_t));
        out->vertex_side = malloc((size_t)total + 1);
        if (!out->vertex_mirror || !out->face_mirror || !out->vertex_side)
            status = pz_error(ctx, PZ_ERR_NOMEM, "symmetrize: out of memory");
    }
    if (status == PZ_OK) {
        pz_mesh *mesh = out->mesh;
        memcpy(mesh->positions, h->positions, 3 * (size_t)n * sizeof(double));
        for (int32_t v = 0; v < n; ++v) {
            int32_t m = mirror[v];
            out->vertex_mirror[v] = m, out->vertex_mirror[m] = v;
            out->vertex_side[v] = m == v ? 1 : 0;
            if (m == v)
                continue;
            out->vertex_side[m] = 2;
            const double *p = h->positions + 3 * (size_t)v;
            double s = p[0] * h->normal[0] + p[1] * h->normal[1] + p[2] * h->normal[2] - h->offset;
            for (int d = 0; d < 3; ++d)
                mesh->positions[3 * (size_t)m + d] = p[d] - 2 * s * h->normal[d];
        }
        for (int32_t f = 0; f < faces; ++f) {
            const int32_t *face = h->faces + 3 * (size_t)f;
            memcpy(mesh->faces + 3 * (size_t)f, face, 3 * sizeof(int32_t));
            int32_t *image = mesh->faces + 3 * ((size_t)f + faces);
            image[0] = mirror[face[0]], image[1] = mirror[face[2]], image[2] = mirror[face[1]];
            out->face_mirror[f] = f + faces, out->face_mirror[f + faces] = f;
        }
    }
    free(plane), free(on_plane_edge), free(mirror);
    return status;
}

/* Face labels follow the faces (a reflected face takes its original's label). */
static pz_status carry_labels(const halving *h, pz_mesh *mesh, pz_ctx *ctx)
{
    const pz_mesh *input = h->input;
    if (!input->face_labels)
        return PZ_OK;
    mesh->face_labels = malloc(((size_t)mesh->face_count + 1) * sizeof(int32_t));
    if (input->label_count > 0 && input->label_names)
        mesh->label_names = calloc((size_t)input->label_count, sizeof(char *));
    if (!mesh->face_labels || (input->label_count > 0 && input->label_names && !mesh->label_names))
        return pz_error(ctx, PZ_ERR_NOMEM, "symmetrize: out of memory");
    mesh->label_count = input->label_count;
    for (int32_t l = 0; mesh->label_names && l < input->label_count; ++l)
        if (input->label_names[l] && !(mesh->label_names[l] = strdup(input->label_names[l])))
            return pz_error(ctx, PZ_ERR_NOMEM, "symmetrize: out of memory");
    for (int32_t f = 0; f < h->face_count; ++f)
        mesh->face_labels[f] = mesh->face_labels[f + h->face_count] = input->face_labels[h->face_origin[f]];
    return PZ_OK;
}

static int compare_double(const void *a, const void *b)
{
    double x = *(const double *)a, y = *(const double *)b;
    return (x > y) - (x < y);
}

/* How far the input moved: each input vertex's distance to the symmetric surface, the largest and the 95th
 * percentile. */
static pz_status measure_deviation(const pz_mesh *input, pz_symmetrized *out, pz_ctx *ctx)
{
    int32_t n = input->vertex_count;
    double *closest = malloc((3 * (size_t)n + 1) * sizeof(double));
    double *distance = malloc(((size_t)n + 1) * sizeof(double));
    int32_t *face = malloc(((size_t)n + 1) * sizeof(int32_t));
    out->input_nearest = malloc(((size_t)n + 1) * sizeof(int32_t));
    pz_status status = closest && distance && face && out->input_nearest ? PZ_OK : pz_error(ctx, PZ_ERR_NOMEM, "symmetrize: out of memory");
    if (status == PZ_OK)
        status = pz_cgal_closest_points(out->mesh->positions, out->mesh->vertex_count, out->mesh->faces,
                                        out->mesh->face_count, input->positions, n, closest, face, ctx);
    if (status == PZ_OK && n > 0) {
        for (int32_t v = 0; v < n; ++v) {
            distance[v] = prep_distance3(input->positions + 3 * (size_t)v, closest + 3 * (size_t)v);
            const int32_t *corner = out->mesh->faces + 3 * (size_t)(face[v] >= 0 ? face[v] : 0);
            double best = INFINITY;
            for (int k = 0; k < 3; ++k) {
                double d = prep_distance3(closest + 3 * (size_t)v, out->mesh->positions + 3 * (size_t)corner[k]);
                if (d < best)
                    best = d, out->input_nearest[v] = corner[k];
            }
        }
        qsort(distance, (size_t)n, sizeof(double), compare_double);
        out->deviation_max_mm = distance[n - 1];
        out->deviation_p95_mm = distance[(size_t)(0.95 * (double)(n - 1))];
    }
    free(closest), free(distance), free(face);
    return status;
}

pz_status pz_prepare_symmetrize(const pz_mesh *mesh, const double normal[3], double offset, pz_symmetrized *out,
                                pz_ctx *ctx)
{
    memset(out, 0, sizeof *out);
    double length = sqrt(normal[0] * normal[0] + normal[1] * normal[1] + normal[2] * normal[2]);
    if (!(length > 0) || !isfinite(offset))
        return pz_error(ctx, PZ_ERR_USAGE, "symmetrize: the plane's normal is zero or not finite");
    pz_topology *topology = NULL;
    pz_status status = pz_topology_build(mesh, &topology, ctx);
    if (status != PZ_OK)
        return status;
    halving h;
    memset(&h, 0, sizeof h);
    h.input = mesh, h.topology = topology;
    for (int d = 0; d < 3; ++d)
        h.normal[d] = normal[d] / length;
    h.offset = offset / length;
    h.distance = malloc(((size_t)mesh->vertex_count + 1) * sizeof(double));
    h.vertex_new = malloc(((size_t)mesh->vertex_count + 1) * sizeof(int32_t));
    h.edge_cut = malloc(((size_t)topology->edge_count + 1) * sizeof(int32_t));
    if (!h.distance || !h.vertex_new || !h.edge_cut)
        status = pz_error(ctx, PZ_ERR_NOMEM, "symmetrize: out of memory");
    if (status == PZ_OK) {
        for (int32_t v = 0; v < mesh->vertex_count; ++v)
            h.vertex_new[v] = -1;
        for (int32_t e = 0; e < topology->edge_count; ++e)
            h.edge_cut[e] = -1;
        signed_distances(&h, &out->snapped_vertices);
        for (int32_t f = 0; status == PZ_OK && f < mesh->face_count; ++f) {
            const int32_t *face = mesh->faces + 3 * (size_t)f;
            double lo = fmin(h.distance[face[0]], fmin(h.distance[face[1]], h.distance[face[2]]));
            double hi = fmax(h.distance[face[0]], fmax(h.distance[face[1]], h.distance[face[2]]));
            if (!(lo < 0)) /* on the positive side, or lying in the plane */
                continue;
            out->cut_faces += hi > 0;
            if (!clip_face(&h, f))
                status = pz_error(ctx, PZ_ERR_NOMEM, "symmetrize: out of memory");
        }
    }
    if (status == PZ_OK && h.face_count == 0)
        status = pz_error(ctx, PZ_ERR_DATA, "symmetrize: no face on the kept side of the plane");
    if (status == PZ_OK)
        status = reflect_half(&h, out, ctx);
    if (status == PZ_OK)
        status = carry_labels(&h, out->mesh, ctx);
    if (status == PZ_OK) {
        out->mesh->unit_scale = mesh->unit_scale;
        pz_validation validation;
        status = pz_mesh_validate(out->mesh, &validation, ctx);
        if (status == PZ_OK && !pz_validation_ok(&validation))
            status = pz_error(ctx, PZ_ERR_DATA, "symmetrize: the symmetric garment is not a valid manifold (the "
                              "garment meets the plane along a fold)");
        pz_validation_clear(&validation);
    }
    if (status == PZ_OK)
        status = measure_deviation(mesh, out, ctx);
    halving_free(&h);
    pz_topology_free(&topology);
    if (status != PZ_OK)
        pz_symmetrized_clear(out);
    return status;
}

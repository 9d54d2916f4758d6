/*
 * tests/mesh/test_geometry.c -- areas, normals, angles, cotangent weights,
 * angle defect and developability on meshes with known answers: a unit right
 * triangle, a flat grid (zero defect inside, Laplacian linear precision), a
 * tetrahedron and a cube (Gauss-Bonnet: total defect 4 pi; a cube corner
 * pi / 2), and a needle triangle where acos would lose the angle. Vertex
 * normals: +z on a flat grid, radial on the regular tetrahedron, weighted by
 * area at a cube corner (two triangles of a side count twice), flipped with
 * the faces, (0, 0, 1) at an isolated vertex.
 *
 * SPDX-License-Identifier: GPL-3.0-or-later
 */
#include "io/io.h"
#include "test_meshes.h"

#include <math.h>
#include <string.h>

static pz_ctx ctx;

static const double PI = TEST_PI;

static int near(double a, double b, double tolerance) { return fabs(a - b) <= tolerance; }

static void test_right_triangle(void)
{
    static const double positions[] = {0, 0, 0, 1, 0, 0, 0, 1, 0};
    static const int32_t faces[] = {0, 1, 2};
    pz_mesh *mesh = test_mesh_from(3, positions, 1, faces, &ctx);
    double area, normal[3], angles[3];
    pz_geom_face_areas(mesh, &area);
    pz_geom_face_normals(mesh, normal);
    pz_geom_corner_angles(mesh, angles);
    CHECK(near(area, 0.5, 1e-15), "area %g", area);
    CHECK(near(pz_geom_total_area(mesh), 0.5, 1e-15), "total area");
    CHECK(normal[0] == 0 && normal[1] == 0 && near(normal[2], 1, 1e-15), "normal +z");
    CHECK(near(angles[0], PI / 2, 1e-15) && near(angles[1], PI / 4, 1e-15) && near(angles[2], PI / 4, 1e-15),
          "angles %g %g %g", angles[0], angles[1], angles[2]);
    pz_topology *topology = test_topology(mesh, &ctx);
    double defect[3], e_dev[3], weights[3];
    pz_geom_angle_defect(mesh, topology, defect);
    pz_geom_developability(mesh, topology, e_dev);
    CHECK(near(defect[0], PI / 2, 1e-15) && near(defect[1], 3 * PI / 4, 1e-15), "boundary defect pi - angle");
    CHECK(e_dev[0] == 0 && e_dev[1] == 0 && e_dev[2] == 0, "no developability error on the boundary");
    /* Edge 1-2 faces the right angle (cot 0), edges 0-1 and 2-0 a 45 degree one (cot 1). */
    pz_geom_cotan_weights(mesh, topology, weights);
    CHECK(near(weights[topology->halfedge_edge[1]], 0.0, 1e-15), "weight opposite the right angle");
    CHECK(near(weights[topology->halfedge_edge[0]], 0.5, 1e-15) && near(weights[topology->halfedge_edge[2]], 0.5, 1e-15),
          "weights opposite 45 degrees");
    pz_topology_free(&topology);

    /* Reversing the face reverses the normal; a degenerate face has a zero one. */
    mesh->faces[1] = 2;
    mesh->faces[2] = 1;
    pz_geom_face_normals(mesh, normal);
    CHECK(near(normal[2], -1, 1e-15), "reversed normal");
    mesh->positions[7] = 0;  /* vertex 2 onto the x axis */
    pz_geom_face_normals(mesh, normal);
    pz_geom_face_areas(mesh, &area);
    CHECK(normal[0] == 0 && normal[1] == 0 && normal[2] == 0 && area == 0, "degenerate face: zero normal and area");
    pz_mesh_free(&mesh);
}

/* A needle: the angle at vertex 0 is 1e-10 rad; atan2 keeps it, acos of the
 * cosine (1 - 5e-21, which rounds to 1) would return 0. */
static void test_needle(void)
{
    double positions[] = {0, 0, 0, 1, 0, 0, 1, 1e-10, 0};
    static const int32_t faces[] = {0, 1, 2};
    pz_mesh *mesh = test_mesh_from(3, positions, 1, faces, &ctx);
    double angles[3];
    pz_geom_corner_angles(mesh, angles);
    CHECK(near(angles[0], 1e-10, 1e-20), "needle angle %.17g", angles[0]);
    CHECK(near(angles[0] + angles[1] + angles[2], PI, 1e-14), "angles sum to pi");
    pz_mesh_free(&mesh);
}

static void test_flat_grid(void)
{
    pz_mesh *mesh = test_grid(4, 3, TEST_GRID_FLAT, 0, &ctx);
    pz_topology *topology = test_topology(mesh, &ctx);
    double defect[20], e_dev[20], *weights = malloc((size_t)topology->edge_count * sizeof(double));
    REQUIRE(weights, "out of memory");
    pz_geom_angle_defect(mesh, topology, defect);
    pz_geom_developability(mesh, topology, e_dev);
    double total = 0, worst_interior = 0, worst_e_dev = 0;
    for (int v = 0; v < 20; ++v) {
        total += defect[v];
        if (!topology->vertex_on_boundary[v])
            worst_interior = fmax(worst_interior, fabs(defect[v]));
        worst_e_dev = fmax(worst_e_dev, e_dev[v]);
    }
    CHECK(worst_interior < 1e-14, "interior defect %g", worst_interior);
    CHECK(worst_e_dev < 1e-14, "developability error of a plane %g", worst_e_dev);
    CHECK(near(defect[0], PI / 2, 1e-14) && near(defect[4], PI / 2, 1e-14), "corner defects");
    CHECK(near(defect[1], 0, 1e-14), "straight boundary: no defect");
    CHECK(near(total, 2 * PI, 1e-13), "Gauss-Bonnet for a disk: %g", total);
    CHECK(near(pz_geom_total_area(mesh), 12, 1e-13), "area 4 x 3");

    /* Diagonals face right angles (weight 0); inner axis edges two 45 degree
     * angles (weight 1); boundary axis edges one (weight 1/2). */
    pz_geom_cotan_weights(mesh, topology, weights);
    int wrong = 0;
    for (int32_t e = 0; e < topology->edge_count; ++e) {
        int32_t h = topology->edge_halfedge[2 * e];
        const double *p = mesh->positions + 3 * pz_he_from(topology, h), *q = mesh->positions + 3 * pz_he_to(topology, h);
        int diagonal = p[0] != q[0] && p[1] != q[1];
        double want = diagonal ? 0.0 : topology->edge_halfedge[2 * e + 1] < 0 ? 0.5 : 1.0;
        wrong += !near(weights[e], want, 1e-14);
    }
    CHECK(wrong == 0, "%d cotan weights off", wrong);
    /* Linear precision: at an interior vertex sum_e w_e (x_j - x_i) = 0. */
    double worst_residual = 0;
    for (int32_t v = 0; v < 20; ++v) {
        if (topology->vertex_on_boundary[v])
            continue;
        double residual[2] = {0, 0};
        for (int32_t h = 0; h < topology->halfedge_count; ++h)
            if (pz_he_from(topology, h) == v) {
                const double *p = mesh->positions + 3 * v, *q = mesh->positions + 3 * pz_he_to(topology, h);
                for (int k = 0; k < 2; ++k)
                    residual[k] += weights[topology->halfedge_edge[h]] * (q[k] - p[k]);
            }
        worst_residual = fmax(worst_residual, hypot(residual[0], residual[1]));
    }
    CHECK(worst_residual < 1e-13, "cotan Laplacian of a linear function %g", worst_residual);
    free(weights);
    pz_topology_free(&topology);
    pz_mesh_free(&mesh);
}

static void test_closed_surfaces(void)
{
    pz_mesh *mesh = test_tetrahedron(&ctx);
    const double *tetra_positions = mesh->positions;
    pz_topology *topology = test_topology(mesh, &ctx);
    double defect[8], e_dev[8], normals[12 * 3];
    pz_geom_angle_defect(mesh, topology, defect);
    double total = defect[0] + defect[1] + defect[2] + defect[3];
    CHECK(near(total, 4 * PI, 1e-13), "tetrahedron: total defect %g = 4 pi", total);
    CHECK(near(defect[0], PI, 1e-14), "regular tetrahedron vertex defect pi");
    pz_geom_face_normals(mesh, normals);
    int outward = 1;
    for (int f = 0; f < 4; ++f) {
        const int32_t *c = mesh->faces + 3 * f;
        double centroid_dot = 0;
        for (int k = 0; k < 3; ++k)
            centroid_dot += normals[3 * f + k] * (tetra_positions[3 * c[0] + k] + tetra_positions[3 * c[1] + k] +
                                                  tetra_positions[3 * c[2] + k]);
        outward &= centroid_dot > 0;
    }
    CHECK(outward, "counter-clockwise faces have outward normals");
    pz_topology_free(&topology);
    pz_mesh_free(&mesh);

    /* Unit cube: three right angles meet at each corner, defect pi / 2 each. */
    static const double cube_positions[] = {0, 0, 0, 1, 0, 0, 1, 1, 0, 0, 1, 0, 0, 0, 1, 1, 0, 1, 1, 1, 1, 0, 1, 1};
    static const int32_t cube_faces[] = {0, 2, 1, 0, 3, 2, 4, 5, 6, 4, 6, 7, 0, 1, 5, 0, 5, 4,
                                         1, 2, 6, 1, 6, 5, 2, 3, 7, 2, 7, 6, 3, 0, 4, 3, 4, 7};
    mesh = test_mesh_from(8, cube_positions, 12, cube_faces, &ctx);
    topology = test_topology(mesh, &ctx);
    pz_geom_angle_defect(mesh, topology, defect);
    pz_geom_developability(mesh, topology, e_dev);
    int corners_ok = 1;
    total = 0;
    for (int v = 0; v < 8; ++v) {
        corners_ok &= near(defect[v], PI / 2, 1e-14) && near(e_dev[v], PI / 2, 1e-14);
        total += defect[v];
    }
    CHECK(corners_ok, "cube corner defect and developability error pi / 2");
    CHECK(near(total, 4 * PI, 1e-13), "cube: total defect 4 pi");
    CHECK(near(pz_geom_total_area(mesh), 6, 1e-14), "cube area 6");
    pz_topology_free(&topology);
    pz_mesh_free(&mesh);
}

static void test_vertex_normals(void)
{
    /* Flat grid: +z everywhere, exactly. */
    pz_mesh *mesh = test_grid(4, 3, TEST_GRID_FLAT, 0, &ctx);
    double normals[20 * 3];
    pz_geom_vertex_normals(mesh, normals);
    int flat = 1;
    for (int v = 0; v < 20; ++v)
        flat &= normals[3 * v] == 0 && normals[3 * v + 1] == 0 && normals[3 * v + 2] == 1;
    CHECK(flat, "flat grid: every vertex normal is +z");
    pz_mesh_free(&mesh);

    /* Regular tetrahedron: by symmetry each vertex normal points away from the centre, at the vertex. */
    mesh = test_tetrahedron(&ctx);
    pz_geom_vertex_normals(mesh, normals);
    double worst = 0;
    for (int v = 0; v < 4; ++v)
        for (int k = 0; k < 3; ++k)
            worst = fmax(worst, fabs(normals[3 * v + k] - mesh->positions[3 * v + k] / sqrt(3.0)));
    CHECK(worst < 1e-15, "tetrahedron: vertex normals radial (off by %g)", worst);
    /* Reversed faces reverse the normals. */
    for (int f = 0; f < 4; ++f) {
        int32_t swap = mesh->faces[3 * f + 1];
        mesh->faces[3 * f + 1] = mesh->faces[3 * f + 2];
        mesh->faces[3 * f + 2] = swap;
    }
    double reversed[4 * 3];
    pz_geom_vertex_normals(mesh, reversed);
    worst = 0;
    for (int i = 0; i < 12; ++i)
        worst = fmax(worst, fabs(reversed[i] + normals[i]));
    CHECK(worst < 1e-15, "reversed faces: reversed normals (off by %g)", worst);
    pz_mesh_free(&mesh);

    /* Unit cube corner 0: both bottom (-z) and both front (-y) triangles use it, one left (-x) triangle:
     * the area-weighted sum is (-1, -2, -2), its direction (-1, -2, -2) / 3. Vertex 8 is used by no face. */
    static const double cube_positions[] = {0, 0, 0, 1, 0, 0, 1, 1, 0, 0, 1, 0, 0, 0, 1,
                                            1, 0, 1, 1, 1, 1, 0, 1, 1, 5, 5, 5};
    static const int32_t cube_faces[] = {0, 2, 1, 0, 3, 2, 4, 5, 6, 4, 6, 7, 0, 1, 5, 0, 5, 4,
                                         1, 2, 6, 1, 6, 5, 2, 3, 7, 2, 7, 6, 3, 0, 4, 3, 4, 7};
    mesh = test_mesh_from(9, cube_positions, 12, cube_faces, &ctx);
    pz_geom_vertex_normals(mesh, normals);
    CHECK(near(normals[0], -1.0 / 3, 1e-15) && near(normals[1], -2.0 / 3, 1e-15) && near(normals[2], -2.0 / 3, 1e-15),
          "cube corner normal (%g %g %g), want (-1 -2 -2) / 3", normals[0], normals[1], normals[2]);
    CHECK(normals[24] == 0 && normals[25] == 0 && normals[26] == 1, "isolated vertex: (0, 0, 1)");
    worst = 0;
    for (int v = 0; v < 9; ++v)
        worst = fmax(worst, fabs(hypot(hypot(normals[3 * v], normals[3 * v + 1]), normals[3 * v + 2]) - 1));
    CHECK(worst < 1e-15, "unit length (off by %g)", worst);
    pz_mesh_free(&mesh);
}

/* Gauss-Bonnet on real disks (INVENTORY.md: one boundary loop): the defects
 * sum to 2 pi; a hemisphere is curved (some developability error), and its
 * area is 2 pi r^2 within the chordal loss. */
static void test_real_meshes(void)
{
    const char *dir = test_shared_data();
    if (!dir) {
        test_skip_part("the real meshes: PZ_SHARED_DATA is not set");
        return;
    }
    static const char *const files[] = {"surfaces/hemisphere.obj", "surfaces/face-scan.obj", "seams/skirt_0.obj"};
    for (size_t i = 0; i < sizeof files / sizeof files[0]; ++i) {
        char path[4096];
        snprintf(path, sizeof path, "%s/%s", dir, files[i]);
        pz_mesh *mesh = NULL;
        pz_topology *topology = NULL;
        if (pz_mesh_read(path, &mesh, &ctx) != PZ_OK || pz_mesh_prepare(mesh, path, 0, &ctx) != PZ_OK ||
            pz_topology_build(mesh, &topology, &ctx) != PZ_OK) {
            CHECK(0, "%s: %s", files[i], ctx.error);
            pz_mesh_free(&mesh);
            continue;
        }
        double *defect = malloc((size_t)mesh->vertex_count * sizeof(double));
        double *e_dev = malloc((size_t)mesh->vertex_count * sizeof(double));
        REQUIRE(defect && e_dev, "out of memory");
        pz_geom_angle_defect(mesh, topology, defect);
        pz_geom_developability(mesh, topology, e_dev);
        double total = 0, largest_e_dev = 0;
        for (int32_t v = 0; v < mesh->vertex_count; ++v) {
            total += defect[v];
            largest_e_dev = fmax(largest_e_dev, e_dev[v]);
        }
        CHECK(near(total, 2 * PI, 1e-9), "%s: total defect %.12g, expected 2 pi", files[i], total);
        if (i == 0) {
            /* The file's hemisphere is centred on the origin (tilted, so no
             * bounding-box guess): its radius is the vertices' distance. */
            double radius = 0, nearest = INFINITY, area = pz_geom_total_area(mesh);
            for (int32_t v = 0; v < mesh->vertex_count; ++v) {
                const double *p = mesh->positions + 3 * v;
                radius = fmax(radius, sqrt(p[0] * p[0] + p[1] * p[1] + p[2] * p[2]));
                nearest = fmin(nearest, sqrt(p[0] * p[0] + p[1] * p[1] + p[2] * p[2]));
            }
            CHECK(nearest > 0.99 * radius, "hemisphere vertices on a sphere: %g .. %g", nearest, radius);
            CHECK(area < 2 * PI * radius * radius && area > 0.98 * 2 * PI * radius * radius,
                  "hemisphere area %g vs 2 pi r^2 = %g", area, 2 * PI * radius * radius);
            CHECK(largest_e_dev > 1e-4, "a sphere is not developable (largest E_dev %g)", largest_e_dev);
        }
        free(defect);
        free(e_dev);
        pz_topology_free(&topology);
        pz_mesh_free(&mesh);
    }
}

int main(void)
{
    pz_ctx_init(&ctx);
    ctx.quiet = 1;
    test_right_triangle();
    test_needle();
    test_flat_grid();
    test_closed_surfaces();
    test_vertex_normals();
    test_real_meshes();
    return test_finish();
}

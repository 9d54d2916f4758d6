/*
 * tests/field/test_field.c -- the cross-field on shapes whose answer is known:
 * a cylinder (axis and circumference within 1 degree, no singularities), the
 * bodice (boundary faces hold an arm along the boundary within 2 degrees; a
 * sketched diagonal on the front is followed within 2 degrees), invariance
 * under a rigid rotation and stability under vertex noise of 0.5 % of the
 * mean edge (mean angle change printed), extra poses changing the field near
 * a bend only (a local elbow bend, and pz_generate's bent pose), and the
 * sketch parser's errors. Singularities: the reported ones must be exactly
 * the vertices whose index, measured here from the arms and the geometry
 * alone, is not zero (bodice and closed surfaces); a torus of revolution has
 * none, an ellipsoid a half turn at each of its four umbilics (computed from
 * its semi-axes; with noise, extra pairs that cancel), a sphere (no
 * preferred direction at all) only positive ones, at most 8.
 *
 * SPDX-License-Identifier: GPL-3.0-or-later
 */
#include "field/field.h"
#include "core/vec.h"
#include "test_meshes.h"
#include "generate/generate.h"

#include <stdio.h>

static pz_ctx ctx;

static pz_mesh *generate(pz_shape shape, int32_t faces, int32_t poses)
{
    pz_generate_options options = {faces, poses, 0};
    pz_mesh *mesh = NULL;
    REQUIRE_OK(pz_generate(shape, &options, &mesh, &ctx), ctx);
    return mesh;
}

static pz_field *field_of(const pz_mesh *mesh, const pz_field_options *options)
{
    pz_topology *topology = test_topology(mesh, &ctx);
    pz_field *field = NULL;
    REQUIRE_OK(pz_field_compute(mesh, topology, options, &field, &ctx), ctx);
    pz_topology_free(&topology);
    return field;
}

/* Mean (and max) cross angle between two fields on the same faces. */
static double mean_field_change(const pz_field *a, const pz_field *b, double *max_change)
{
    double sum = 0.0, worst = 0.0;
    for (int32_t f = 0; f < a->face_count; ++f) {
        double angle = pz_field_cross_angle_deg(b->directions + 3 * f, a->directions + 3 * f, b->normals + 3 * f);
        sum += angle;
        worst = angle > worst ? angle : worst;
    }
    if (max_change)
        *max_change = worst;
    return sum / a->face_count;
}

static double mean_edge(const pz_mesh *mesh)
{
    pz_topology *topology = test_topology(mesh, &ctx);
    double length = pz_field_mean_edge_length(mesh, topology);
    pz_topology_free(&topology);
    return length;
}

/* ---------------------------------------------------------------- singularities, measured here */

/*
 * The index of the cross at interior vertex v, measured here without the
 * library's frames: walking the faces round v counter-clockwise, the arm's
 * angle to each shared edge (about each face's own normal) is kept by the
 * transport across that edge, so the cross turns by the change of that angle
 * taken to the nearest quarter turn; the turns plus the angle defect, over
 * 2 pi, give the index.
 */
static double index_at(const pz_mesh *mesh, const pz_topology *topology, const pz_field *field, int32_t v)
{
    int32_t h0 = topology->vertex_halfedge[v], h = h0;
    double turn = 0.0, corner_sum = 0.0;
    do {
        int32_t into_v = pz_he_prev(h), twin = topology->twin[into_v];
        int32_t f = pz_he_face(h), g = pz_he_face(twin), w = pz_he_from(topology, into_v);
        const double *p_v = mesh->positions + 3 * v;
        double edge[3], out_edge[3], angle_in[2];
        pz_vec3_sub(mesh->positions + 3 * w, p_v, edge);
        pz_vec3_sub(mesh->positions + 3 * pz_he_to(topology, h), p_v, out_edge);
        corner_sum += acos(pz_vec3_dot(edge, out_edge) / (pz_vec3_norm(edge) * pz_vec3_norm(out_edge)));
        const int32_t across[2] = {f, g};
        for (int k = 0; k < 2; ++k) {
            const int32_t *corners = mesh->faces + 3 * across[k];
            double side_a[3], side_b[3], normal[3], turned[3];
            pz_vec3_sub(mesh->positions + 3 * corners[1], mesh->positions + 3 * corners[0], side_a);
            pz_vec3_sub(mesh->positions + 3 * corners[2], mesh->positions + 3 * corners[0], side_b);
            pz_vec3_cross(side_a, side_b, normal);
            pz_vec3_normalize(normal);
            const double *arm = field->directions + 3 * across[k];
            pz_vec3_cross(edge, arm, turned);
            angle_in[k] = atan2(pz_vec3_dot(normal, turned), pz_vec3_dot(edge, arm));
        }
        double step = angle_in[1] - angle_in[0];
        turn += step - TEST_PI / 2.0 * round(step / (TEST_PI / 2.0));
        h = twin;
    } while (h != h0);
    return (turn + 2.0 * TEST_PI - corner_sum) / (2.0 * TEST_PI);
}

/*
 * The field's singularities must be exactly the interior vertices whose index
 * (measured by index_at) is not zero, with that index.
 */
static void check_singularities_measured(const pz_mesh *mesh, const pz_field *field, const char *name)
{
    pz_topology *topology = test_topology(mesh, &ctx);
    int32_t found = 0, wrong = 0, listed = 0, not_quarter = 0;
    for (int32_t v = 0; v < mesh->vertex_count; ++v) {
        if (topology->vertex_halfedge[v] < 0 || topology->vertex_on_boundary[v])
            continue;
        double measured = index_at(mesh, topology, field, v);
        double quarters = round(4.0 * measured);
        not_quarter += fabs(4.0 * measured - quarters) > 1e-6;
        while (listed < field->singularity_count && field->singular_vertices[listed] < v)
            ++wrong, ++listed; /* listed, but not singular here */
        int is_listed = listed < field->singularity_count && field->singular_vertices[listed] == v;
        double reported = is_listed ? field->singular_indices[listed++] : 0.0;
        found += quarters != 0.0;
        if (fabs(reported - quarters / 4.0) > 1e-12) {
            if (++wrong <= 5)
                fprintf(stderr, "%s: vertex %d has index %g, the field reports %g\n", name, (int)v, quarters / 4.0,
                        reported);
        }
    }
    wrong += field->singularity_count - listed;
    CHECK(not_quarter == 0, "%s: %d vertices have an index that is no multiple of 1/4", name, (int)not_quarter);
    CHECK(wrong == 0 && found == field->singularity_count,
          "%s: %d singularities measured, %d reported, %d vertices disagree", name, (int)found,
          (int)field->singularity_count, (int)wrong);
    pz_topology_free(&topology);
}

/* ---------------------------------------------------------------- cylinder */

static void test_cylinder(void)
{
    pz_mesh *mesh = generate(PZ_SHAPE_CYLINDER, 6000, 0);
    pz_field *field = field_of(mesh, NULL);
    const double axis[3] = {0.0, 0.0, 1.0};
    double worst = 0.0;
    for (int32_t f = 0; f < mesh->face_count; ++f) {
        double angle = pz_field_cross_angle_deg(field->directions + 3 * f, axis, field->normals + 3 * f);
        worst = angle > worst ? angle : worst;
    }
    CHECK(worst < 1.0, "cylinder: the field leaves the axis by up to %.3f degrees", worst);
    CHECK(field->singularity_count == 0, "cylinder: %d singularities", (int)field->singularity_count);
    CHECK(field->curvature_alignment_deg < 1.0, "cylinder: curvature alignment %.3f", field->curvature_alignment_deg);
    /* The curvature itself: k_max ~ 1/150 round the circumference. */
    pz_topology *topology = test_topology(mesh, &ctx);
    pz_curvature *curvature = NULL;
    REQUIRE_OK(pz_curvature_compute(mesh, topology, NULL, 0, &curvature, &ctx), ctx);
    double k_sum = 0.0, a_sum = 0.0;
    for (int32_t f = 0; f < mesh->face_count; ++f)
        k_sum += fabs(curvature->k_max[f]), a_sum += curvature->anisotropy[f];
    double k_mean = k_sum / mesh->face_count, a_mean = a_sum / mesh->face_count;
    CHECK(fabs(k_mean * 150.0 - 1.0) < 0.05, "cylinder radius 150: mean |k_max| %.5f", k_mean);
    CHECK(a_mean > 0.8, "cylinder: mean anisotropy %.3f should be near 1", a_mean);
    pz_curvature_free(&curvature);
    pz_topology_free(&topology);
    pz_field_free(&field);
    pz_mesh_free(&mesh);
}

/* ---------------------------------------------------------------- bodice: boundary */

static void test_bodice_boundary(void)
{
    pz_mesh *mesh = generate(PZ_SHAPE_BODICE, 8000, 0);
    pz_topology *topology = test_topology(mesh, &ctx);
    pz_field *field = field_of(mesh, NULL);
    double worst = 0.0;
    int32_t boundary_faces = 0;
    for (int32_t f = 0; f < mesh->face_count; ++f) {
        double best = 90.0;
        for (int k = 0; k < 3; ++k) {
            int32_t h = 3 * f + k;
            if (topology->twin[h] >= 0)
                continue;
            double edge[3];
            for (int i = 0; i < 3; ++i)
                edge[i] = mesh->positions[3 * pz_he_to(topology, h) + i] - mesh->positions[3 * pz_he_from(topology, h) + i];
            double angle = pz_field_cross_angle_deg(field->directions + 3 * f, edge, field->normals + 3 * f);
            best = angle < best ? angle : best;
        }
        if (best < 90.0) {
            ++boundary_faces;
            worst = best > worst ? best : worst;
        }
    }
    CHECK(boundary_faces > 50, "bodice: only %d boundary faces", (int)boundary_faces);
    CHECK(worst < 2.0, "bodice: a boundary face's cross is %.3f degrees off its boundary edge", worst);
    CHECK(field->boundary_alignment_deg >= 0.0 && field->boundary_alignment_deg < 2.0,
          "bodice: boundary_alignment_deg %.3f", field->boundary_alignment_deg);
    printf("bodice: %d singularities, curvature alignment %.2f deg\n", (int)field->singularity_count,
           field->curvature_alignment_deg);
    check_singularities_measured(mesh, field, "bodice");
    pz_field_free(&field);
    pz_topology_free(&topology);
    pz_mesh_free(&mesh);
}

/* ---------------------------------------------------------------- bodice: sketch */

/* The first hit of the ray from `origin` along +y with the mesh (Moeller-Trumbore); 0 when none. */
static int ray_hit_y(const pz_mesh *mesh, const double origin[3], double hit[3], int32_t *hit_face)
{
    double best = HUGE_VAL;
    for (int32_t f = 0; f < mesh->face_count; ++f) {
        const double *a = mesh->positions + 3 * mesh->faces[3 * f], *b = mesh->positions + 3 * mesh->faces[3 * f + 1],
                     *c = mesh->positions + 3 * mesh->faces[3 * f + 2];
        double e1[3], e2[3], s[3];
        for (int i = 0; i < 3; ++i)
            e1[i] = b[i] - a[i], e2[i] = c[i] - a[i], s[i] = origin[i] - a[i];
        /* direction (0, 1, 0): p = d x e2, det = e1 . p */
        double p[3] = {e2[2], 0.0, -e2[0]};
        double det = e1[0] * p[0] + e1[2] * p[2];
        if (fabs(det) < 1e-12)
            continue;
        double u = (s[0] * p[0] + s[2] * p[2]) / det;
        double q[3] = {s[1] * e1[2] - s[2] * e1[1], s[2] * e1[0] - s[0] * e1[2], s[0] * e1[1] - s[1] * e1[0]};
        double v = q[1] / det;
        double t = (e2[0] * q[0] + e2[1] * q[1] + e2[2] * q[2]) / det;
        if (u < 0.0 || v < 0.0 || u + v > 1.0 || t <= 0.0 || t >= best)
            continue;
        best = t;
        *hit_face = f;
    }
    if (best == HUGE_VAL)
        return 0;
    hit[0] = origin[0], hit[1] = origin[1] + best, hit[2] = origin[2];
    return 1;
}

static void test_bodice_sketch(void)
{
    pz_mesh *mesh = generate(PZ_SHAPE_BODICE, 8000, 0);
    /* A diagonal on the front (-y side), from low left to high right, projected onto the surface. */
    enum { POINTS = 60 };
    double points[POINTS][3];
    int32_t faces[POINTS];
    char *json = malloc(POINTS * 100 + 64);
    REQUIRE(json, "out of memory");
    size_t length = (size_t)sprintf(json, "{\"curves\": [[");
    for (int k = 0; k < POINTS; ++k) {
        double t = k / (POINTS - 1.0);
        double origin[3] = {-90.0 + 180.0 * t, -1000.0, 180.0 + 220.0 * t};
        REQUIRE(ray_hit_y(mesh, origin, points[k], &faces[k]), "the ray at x=%g z=%g misses the bodice", origin[0],
                origin[2]);
        length += (size_t)sprintf(json + length, "%s[%.9g, %.9g, %.9g]", k ? ", " : "", points[k][0], points[k][1],
                                  points[k][2]);
    }
    sprintf(json + length, "]]}");
    pz_sketch *sketch = NULL;
    REQUIRE_OK(pz_sketch_parse(json, strlen(json), "diagonal.json", 1.0, &sketch, &ctx), ctx);
    free(json);
    CHECK(sketch->curve_count == 1 && sketch->curve_offsets[1] == POINTS, "sketch parsed to %d curves",
          (int)sketch->curve_count);
    pz_field_options options = {0, 0.0, sketch, 0};
    pz_field *field = field_of(mesh, &options);
    CHECK(field->sketch_face_count > 20, "only %d faces sketched", (int)field->sketch_face_count);
    CHECK(field->sketch_alignment_deg >= 0.0 && field->sketch_alignment_deg < 2.0, "sketch_alignment_deg %.3f",
          field->sketch_alignment_deg);
    /* Independently: at every segment's midpoint the field follows the segment. */
    double worst = 0.0;
    for (int k = 0; k + 1 < POINTS; ++k) {
        double mid[3], segment[3], hit[3];
        int32_t f = -1;
        for (int i = 0; i < 3; ++i)
            mid[i] = 0.5 * (points[k][i] + points[k + 1][i]), segment[i] = points[k + 1][i] - points[k][i];
        double origin[3] = {mid[0], -1000.0, mid[2]};
        if (!ray_hit_y(mesh, origin, hit, &f))
            continue;
        double angle = pz_field_cross_angle_deg(field->directions + 3 * f, segment, field->normals + 3 * f);
        worst = angle > worst ? angle : worst;
    }
    CHECK(worst < 2.0, "the sketched faces are up to %.3f degrees off the curve", worst);
    printf("sketch: %d faces constrained, worst angle to the curve %.3f deg\n", (int)field->sketch_face_count, worst);
    pz_field_free(&field);
    pz_sketch_free(&sketch);
    pz_mesh_free(&mesh);
}

static void test_sketch_errors(void)
{
    const char *bad[] = {
        "not json", "{\"curves\": 3}", "{\"lines\": []}", "[1, 2]", "{\"curves\": [[[0, 0, 0]]]}",
        "{\"curves\": [[[0, 0], [1, 1, 1]]]}", "{\"curves\": [[[0, 0, \"x\"], [1, 1, 1]]]}", "{\"curves\": [5]}",
    };
    for (size_t i = 0; i < sizeof bad / sizeof *bad; ++i) {
        pz_sketch *sketch = NULL;
        pz_status status = pz_sketch_parse(bad[i], strlen(bad[i]), "bad.json", 1.0, &sketch, &ctx);
        CHECK(status == PZ_ERR_DATA && !sketch, "'%s' should be PZ_ERR_DATA, got %d", bad[i], (int)status);
        CHECK(strstr(ctx.error, "bad.json") && !strchr(ctx.error, '\n'), "message '%s' should name the file",
              ctx.error);
    }
    pz_sketch *sketch = NULL;
    CHECK(pz_sketch_read("/nonexistent/sketch.json", 1.0, &sketch, &ctx) == PZ_ERR_OPEN && !sketch,
          "a missing sketch file is PZ_ERR_OPEN");
    const char *scaled = "{\"curves\": [[[1, 2, 3], [4, 5, 6]], [[0, 0, 0], [1, 0, 0], [2, 0, 0]]]}";
    REQUIRE_OK(pz_sketch_parse(scaled, strlen(scaled), "cm.json", 10.0, &sketch, &ctx), ctx);
    CHECK(sketch->curve_count == 2 && sketch->curve_offsets[2] == 5, "two curves of 2 and 3 points");
    CHECK(sketch->points[5] == 60.0, "points are scaled to millimetres");
    pz_sketch_free(&sketch);
    pz_sketch_free(&sketch); /* NULL is fine */
}

/* ---------------------------------------------------------------- invariance and noise */

static void rotate(pz_mesh *mesh, const double r[3][3])
{
    for (int32_t v = 0; v < mesh->vertex_count; ++v) {
        double *p = mesh->positions + 3 * v, q[3];
        for (int i = 0; i < 3; ++i)
            q[i] = r[i][0] * p[0] + r[i][1] * p[1] + r[i][2] * p[2];
        memcpy(p, q, sizeof q);
    }
}

static void test_rotation_and_noise(void)
{
    pz_mesh *mesh = generate(PZ_SHAPE_BODICE, 8000, 0);
    pz_field *reference = field_of(mesh, NULL);
    /* Rotation by 40 degrees about (1, 2, 2)/3 (Rodrigues). */
    double axis[3] = {1.0 / 3.0, 2.0 / 3.0, 2.0 / 3.0}, angle = 40.0 * TEST_PI / 180.0, c = cos(angle), s = sin(angle);
    double r[3][3];
    for (int i = 0; i < 3; ++i)
        for (int j = 0; j < 3; ++j)
            r[i][j] = (i == j ? c : 0.0) + (1.0 - c) * axis[i] * axis[j];
    r[0][1] -= s * axis[2], r[0][2] += s * axis[1], r[1][0] += s * axis[2];
    r[1][2] -= s * axis[0], r[2][0] -= s * axis[1], r[2][1] += s * axis[0];
    pz_mesh *rotated = NULL;
    REQUIRE_OK(pz_mesh_copy(mesh, &rotated, &ctx), ctx);
    rotate(rotated, r);
    pz_field *turned = field_of(rotated, NULL);
    double worst = 0.0;
    for (int32_t f = 0; f < mesh->face_count; ++f) {
        double d[3];
        const double *a = reference->directions + 3 * f;
        for (int i = 0; i < 3; ++i)
            d[i] = r[i][0] * a[0] + r[i][1] * a[1] + r[i][2] * a[2];
        double change = pz_field_cross_angle_deg(turned->directions + 3 * f, d, turned->normals + 3 * f);
        worst = change > worst ? change : worst;
    }
    CHECK(worst < 0.01, "rotating the mesh changes the field by up to %.5f degrees", worst);
    CHECK(turned->singularity_count == reference->singularity_count, "rotation changes the singularities: %d vs %d",
          (int)turned->singularity_count, (int)reference->singularity_count);

    /* Noise: every vertex moved by 0.5 % of the mean edge in a pseudo-random direction. */
    pz_mesh *noisy = NULL;
    REQUIRE_OK(pz_mesh_copy(mesh, &noisy, &ctx), ctx);
    double amplitude = 0.005 * mean_edge(mesh);
    unsigned state = 12345u;
    for (int32_t i = 0; i < 3 * noisy->vertex_count; ++i) {
        state = state * 1103515245u + 12345u;
        noisy->positions[i] += amplitude * (((state >> 8) & 0xffff) / 32767.5 - 1.0);
    }
    pz_field *shaken = field_of(noisy, NULL);
    double max_change = 0.0, mean_change = mean_field_change(reference, shaken, &max_change);
    printf("noise 0.5%% of the mean edge: mean field change %.4f deg, max %.3f deg\n", mean_change, max_change);
    CHECK(mean_change < 1.0, "noise of 0.5%% of an edge turns the field by %.3f degrees on average", mean_change);
    pz_field_free(&shaken);
    pz_field_free(&turned);
    pz_field_free(&reference);
    pz_mesh_free(&noisy);
    pz_mesh_free(&rotated);
    pz_mesh_free(&mesh);
}

/* Curvature directions under heavier noise (5 % of the edge): the coarse scales must hold them. */
static void test_curvature_noise(void)
{
    pz_mesh *mesh = generate(PZ_SHAPE_BODICE, 20000, 0);
    pz_topology *topology = test_topology(mesh, &ctx);
    double amplitude = 0.05 * pz_field_mean_edge_length(mesh, topology);
    double *noisy = malloc((size_t)mesh->vertex_count * 3 * sizeof(double));
    REQUIRE(noisy, "out of memory");
    unsigned state = 777u;
    for (int32_t i = 0; i < 3 * mesh->vertex_count; ++i) {
        state = state * 1103515245u + 12345u;
        noisy[i] = mesh->positions[i] + amplitude * (((state >> 8) & 0xffff) / 32767.5 - 1.0);
    }
    double change[2];
    for (int pass = 0; pass < 2; ++pass) {
        int32_t scales = pass == 0 ? 1 : 3;
        pz_curvature *clean = NULL, *shaken = NULL;
        REQUIRE_OK(pz_curvature_compute(mesh, topology, NULL, scales, &clean, &ctx), ctx);
        REQUIRE_OK(pz_curvature_compute(mesh, topology, noisy, scales, &shaken, &ctx), ctx);
        double sum = 0.0, weight = 0.0;
        double *normals = malloc((size_t)mesh->face_count * 3 * sizeof(double));
        REQUIRE(normals, "out of memory");
        pz_geom_face_normals(mesh, normals);
        for (int32_t f = 0; f < mesh->face_count; ++f) {
            double w = clean->anisotropy[f];
            sum += w * pz_field_cross_angle_deg(clean->directions + 3 * f, shaken->directions + 3 * f, normals + 3 * f);
            weight += w;
        }
        change[pass] = sum / weight;
        free(normals);
        pz_curvature_free(&clean);
        pz_curvature_free(&shaken);
    }
    printf("noise 5%% of the mean edge: curvature direction change %.2f deg (1 scale), %.2f deg (3 scales)\n",
           change[0], change[1]);
    CHECK(change[1] < change[0], "three scales (%.2f) should resist noise better than one (%.2f)", change[1], change[0]);
    free(noisy);
    pz_topology_free(&topology);
    pz_mesh_free(&mesh);
}

/* ---------------------------------------------------------------- poses */

static void test_poses(void)
{
    pz_mesh *mesh = generate(PZ_SHAPE_SLEEVE, 8000, 0);
    /* One pose bending the sleeve further round the elbow (z ~ 260): the vertices below
     * z0 turn about the x axis through (y0, z0) by up to 60 degrees, blended over +-40 mm. */
    const double z0 = 260.0, y0 = -20.0, band = 40.0, bend = 60.0 * TEST_PI / 180.0;
    double *pose = malloc((size_t)mesh->vertex_count * 3 * sizeof(double));
    REQUIRE(pose, "out of memory");
    for (int32_t v = 0; v < mesh->vertex_count; ++v) {
        const double *p = mesh->positions + 3 * v;
        double t = (z0 + band - p[2]) / (2.0 * band);
        t = t < 0.0 ? 0.0 : t > 1.0 ? 1.0 : t;
        double a = bend * t * t * (3.0 - 2.0 * t), c = cos(a), s = sin(a);
        double y = p[1] - y0, z = p[2] - z0;
        pose[3 * v] = p[0];
        pose[3 * v + 1] = y0 + c * y - s * z;
        pose[3 * v + 2] = z0 + s * y + c * z;
    }
    pz_mesh *posed = NULL;
    REQUIRE_OK(pz_mesh_copy(mesh, &posed, &ctx), ctx);
    REQUIRE_OK(pz_mesh_add_pose(posed, pose, &ctx), ctx);
    free(pose);
    pz_field_options options = {0, 0.0, NULL, 1};
    pz_field *rest = field_of(mesh, &options);
    pz_field *both = field_of(posed, &options);
    double near_sum = 0.0, far_sum = 0.0;
    int32_t near_count = 0, far_count = 0;
    for (int32_t f = 0; f < mesh->face_count; ++f) {
        double z = 0.0;
        for (int k = 0; k < 3; ++k)
            z += mesh->positions[3 * mesh->faces[3 * f + k] + 2] / 3.0;
        double change = pz_field_cross_angle_deg(both->directions + 3 * f, rest->directions + 3 * f, rest->normals + 3 * f);
        if (fabs(z - z0) < band)
            near_sum += change, ++near_count;
        else if (fabs(z - z0) > 3.0 * band)
            far_sum += change, ++far_count;
    }
    REQUIRE(near_count > 0 && far_count > 0, "faces near and far from the elbow");
    double near_mean = near_sum / near_count, far_mean = far_sum / far_count;
    printf("poses: mean field change %.3f deg near the bend, %.3f deg far from it\n", near_mean, far_mean);
    CHECK(near_mean > 1.0, "the bent pose should change the field near the elbow (%.3f deg)", near_mean);
    CHECK(far_mean < 0.5 * near_mean, "far from the elbow the field should change less (%.3f vs %.3f)", far_mean,
          near_mean);
    pz_field_free(&rest);
    pz_field_free(&both);
    pz_mesh_free(&posed);
    pz_mesh_free(&mesh);

    /* pz_generate's own bent pose bends the whole sleeve about a vertical axis: the straight
     * upper arm keeps its principal directions, the tilted forearm and the elbow (z < 300) do not. */
    mesh = generate(PZ_SHAPE_SLEEVE, 8000, 1);
    pz_field_options rest_only = {0, 0.0, NULL, 0};
    rest = field_of(mesh, &rest_only);
    both = field_of(mesh, &options);
    near_sum = far_sum = 0.0, near_count = far_count = 0;
    for (int32_t f = 0; f < mesh->face_count; ++f) {
        double z = 0.0;
        for (int k = 0; k < 3; ++k)
            z += mesh->positions[3 * mesh->faces[3 * f + k] + 2] / 3.0;
        double change = pz_field_cross_angle_deg(both->directions + 3 * f, rest->directions + 3 * f, rest->normals + 3 * f);
        if (z < 300.0)
            near_sum += change, ++near_count;
        else if (z > 350.0)
            far_sum += change, ++far_count;
    }
    near_mean = near_sum / near_count, far_mean = far_sum / far_count;
    printf("generated bent pose: mean field change %.3f deg below the elbow, %.3f deg on the upper arm\n", near_mean,
           far_mean);
    CHECK(near_mean > 0.1 && far_mean < 0.2 * near_mean, "generated pose: %.3f deg at the elbow, %.3f deg above",
          near_mean, far_mean);
    pz_field_free(&rest);
    pz_field_free(&both);
    pz_mesh_free(&mesh);
}

/* ---------------------------------------------------------------- closed surfaces */

/* A latitude-longitude ellipsoid with semi-axes a, b, c: poles plus `rings` rings of `columns` vertices. */
static pz_mesh *ellipsoid(int columns, int rings, double a, double b, double c)
{
    int32_t vertex_count = columns * rings + 2, face_count = 2 * columns * rings;
    pz_mesh *mesh = NULL;
    REQUIRE_OK(pz_mesh_create(vertex_count, face_count, &mesh, &ctx), ctx);
    for (int j = 0; j < rings; ++j)
        for (int i = 0; i < columns; ++i) {
            double theta = TEST_PI * (j + 1) / (rings + 1), phi = 2.0 * TEST_PI * (i + 0.5 * (j % 2)) / columns;
            double *p = mesh->positions + 3 * (j * columns + i);
            p[0] = a * sin(theta) * cos(phi), p[1] = b * sin(theta) * sin(phi), p[2] = c * cos(theta);
        }
    int32_t north = columns * rings, south = north + 1, f = 0;
    mesh->positions[3 * north + 2] = c, mesh->positions[3 * south + 2] = -c;
    for (int i = 0; i < columns; ++i) {
        int32_t *face = mesh->faces + 3 * f++;
        face[0] = north, face[1] = i, face[2] = (i + 1) % columns;
        face = mesh->faces + 3 * f++;
        int32_t last = (rings - 1) * columns;
        face[0] = south, face[1] = last + (i + 1) % columns, face[2] = last + i;
    }
    for (int j = 0; j + 1 < rings; ++j)
        for (int i = 0; i < columns; ++i) {
            /* Rings alternate by half a column, so the quads are split along the short diagonal. */
            int32_t a0 = j * columns + i, a1 = j * columns + (i + 1) % columns;
            int32_t b0 = (j + 1) * columns + i, b1 = (j + 1) * columns + (i + 1) % columns;
            int32_t *face = mesh->faces + 3 * f++;
            if (j % 2 == 0) {
                face[0] = a0, face[1] = b0, face[2] = b1;
                face = mesh->faces + 3 * f++;
                face[0] = a0, face[1] = b1, face[2] = a1;
            } else {
                face[0] = a0, face[1] = b0, face[2] = a1;
                face = mesh->faces + 3 * f++;
                face[0] = a1, face[1] = b0, face[2] = b1;
            }
        }
    mesh->face_count = f;
    return mesh;
}


/* The field of a closed mesh, its singularities checked against index_at. */
static pz_field *closed_field(const pz_mesh *mesh, const char *name)
{
    pz_topology_summary summary = test_summary(mesh, &ctx);
    REQUIRE(summary.boundary_loop_count == 0, "%s must be closed", name);
    pz_field *field = field_of(mesh, NULL);
    check_singularities_measured(mesh, field, name);
    printf("%s: %d singularities, index sum %g\n", name, (int)field->singularity_count, field->index_sum);
    return field;
}

/*
 * An ellipsoid with semi-axes a > b > c has four umbilics, in the plane of
 * its longest and shortest axes at x = +-a sqrt((a^2-b^2)/(a^2-c^2)),
 * z = +-c sqrt((b^2-c^2)/(a^2-c^2)); its lines of curvature turn by half a
 * turn round each. The curvature-aligned field must put index +1/2 within
 * `radius` of every umbilic (one +1/2 or two +1/4) and, away from them, only
 * singularities that cancel (at most `stray` of them: noise makes pairs).
 */
static void check_umbilics(const pz_mesh *mesh, const pz_field *field, double a, double b, double c, double radius,
                           int32_t stray, const char *name)
{
    double x = a * sqrt((a * a - b * b) / (a * a - c * c)), z = c * sqrt((b * b - c * c) / (a * a - c * c));
    const double umbilics[4][3] = {{x, 0.0, z}, {-x, 0.0, z}, {x, 0.0, -z}, {-x, 0.0, -z}};
    double near[4] = {0.0, 0.0, 0.0, 0.0}, away = 0.0;
    int32_t away_count = 0;
    for (int32_t k = 0; k < field->singularity_count; ++k) {
        const double *p = mesh->positions + 3 * field->singular_vertices[k];
        int nearest = -1;
        for (int u = 0; u < 4; ++u) {
            double offset[3];
            pz_vec3_sub(p, umbilics[u], offset);
            if (pz_vec3_norm(offset) < radius)
                nearest = u;
        }
        if (nearest >= 0)
            near[nearest] += field->singular_indices[k];
        else
            away += field->singular_indices[k], ++away_count;
    }
    for (int u = 0; u < 4; ++u)
        CHECK(fabs(near[u] - 0.5) < 1e-9, "%s: index %g within %g of the umbilic (%.1f, 0, %.1f), not 1/2", name,
              near[u], radius, umbilics[u][0], umbilics[u][2]);
    CHECK(fabs(away) < 1e-9 && away_count <= stray, "%s: %d singularities away from the umbilics, index sum %g",
          name, (int)away_count, away);
}

static void test_closed_surfaces(void)
{
    /* A torus of revolution: the lines of curvature are its meridians and parallels, no singularity at all. */
    pz_mesh *torus = test_grid(48, 24, TEST_GRID_TORUS, 0, &ctx);
    for (int32_t i = 0; i < 3 * torus->vertex_count; ++i)
        torus->positions[i] *= 100.0;
    pz_field *field = closed_field(torus, "torus");
    CHECK(field->singularity_count == 0, "torus: %d singularities", (int)field->singularity_count);
    pz_field_free(&field);
    pz_mesh_free(&torus);

    pz_mesh *egg = ellipsoid(64, 40, 250.0, 180.0, 120.0);
    field = closed_field(egg, "ellipsoid");
    check_umbilics(egg, field, 250.0, 180.0, 120.0, 60.0, 0, "ellipsoid");
    pz_field_free(&field);
    /* Noise breaks every symmetry: the umbilics keep their half turn; pairs of opposite sign may appear. */
    unsigned state = 99u;
    for (int32_t i = 0; i < 3 * egg->vertex_count; ++i) {
        state = state * 1103515245u + 12345u;
        egg->positions[i] += 2.0 * (((state >> 8) & 0xffff) / 32767.5 - 1.0);
    }
    field = closed_field(egg, "noisy ellipsoid");
    check_umbilics(egg, field, 250.0, 180.0, 120.0, 70.0, 4, "noisy ellipsoid");
    pz_field_free(&field);
    pz_mesh_free(&egg);

    /* A sphere is umbilic everywhere: no anisotropy, no boundary, the field is seeded at one face. A smooth
     * cross-field on it turns only one way (no negative index) in at most 8 quarter-turn singularities. */
    pz_mesh *sphere = ellipsoid(48, 30, 200.0, 200.0, 200.0);
    field = closed_field(sphere, "sphere");
    int32_t negative = 0;
    for (int32_t k = 0; k < field->singularity_count; ++k)
        negative += field->singular_indices[k] < 0.0;
    CHECK(negative == 0 && field->singularity_count >= 1 && field->singularity_count <= 8,
          "sphere: %d singularities, %d of negative index", (int)field->singularity_count, (int)negative);
    pz_field_free(&field);
    pz_mesh_free(&sphere);
}

/* ---------------------------------------------------------------- options */

static void test_bad_options(void)
{
    pz_mesh *mesh = generate(PZ_SHAPE_CYLINDER, 1000, 0);
    pz_topology *topology = test_topology(mesh, &ctx);
    pz_field *field = NULL;
    pz_field_options options = {PZ_FIELD_MAX_SCALES + 1, 0.0, NULL, 0};
    CHECK(pz_field_compute(mesh, topology, &options, &field, &ctx) == PZ_ERR_USAGE && !field, "too many scales");
    options.scale_count = 0, options.smoothness = -1.0;
    CHECK(pz_field_compute(mesh, topology, &options, &field, &ctx) == PZ_ERR_USAGE && !field, "negative smoothness");
    pz_field_free(&field);
    pz_topology_free(&topology);
    pz_mesh_free(&mesh);
}

int main(void)
{
    pz_ctx_init(&ctx);
    ctx.quiet = 1;
    test_cylinder();
    test_bodice_boundary();
    test_bodice_sketch();
    test_sketch_errors();
    test_rotation_and_noise();
    test_curvature_noise();
    test_poses();
    test_closed_surfaces();
    test_bad_options();
    return test_finish();
}

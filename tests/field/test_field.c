/*
 * tests/field/test_field.c -- the cross-field on shapes whose answer is known:
 * a cylinder (axis and circumference within 1 degree, no singularities), the
 * bodice (boundary faces hold an arm along the boundary within 2 degrees; a
 * sketched diagonal on the front is followed within 2 degrees), invariance
 * under a rigid rotation and stability under vertex noise of 0.5 % of the
 * mean edge (mean angle change printed), extra poses changing the field near
 * a bend only (a local elbow bend, and pz_generate's bent pose), singularity indices summing to the Euler characteristic on
 * closed surfaces (torus 0, ellipsoid 2, sphere 2 with no preferred
 * direction at all), and the sketch parser's errors.
 *
 * SPDX-License-Identifier: GPL-3.0-or-later
 */
#include "field/field.h"
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

static void check_index_sum(pz_mesh *mesh, const char *name)
{
    pz_topology_summary summary = test_summary(mesh, &ctx);
    REQUIRE(summary.boundary_loop_count == 0, "%s must be closed", name);
    pz_field *field = field_of(mesh, NULL);
    double sum = 0.0;
    for (int32_t k = 0; k < field->singularity_count; ++k) {
        double quarters = field->singular_indices[k] * 4.0;
        CHECK(fabs(quarters - round(quarters)) < 1e-9 && quarters != 0.0, "%s: index %g", name,
              field->singular_indices[k]);
        sum += field->singular_indices[k];
    }
    printf("%s: %d singularities, index sum %g, Euler characteristic %d\n", name, (int)field->singularity_count, sum,
           (int)summary.euler_characteristic);
    CHECK(fabs(sum - summary.euler_characteristic) < 1e-9 && fabs(field->index_sum - sum) < 1e-9,
          "%s: singularity indices sum to %g, Euler characteristic %d", name, sum, (int)summary.euler_characteristic);
    pz_field_free(&field);
}

static void test_closed_surfaces(void)
{
    pz_mesh *torus = test_grid(48, 24, TEST_GRID_TORUS, 0, &ctx);
    for (int32_t i = 0; i < 3 * torus->vertex_count; ++i)
        torus->positions[i] *= 100.0;
    check_index_sum(torus, "torus");
    pz_mesh_free(&torus);
    pz_mesh *egg = ellipsoid(64, 40, 250.0, 180.0, 120.0);
    check_index_sum(egg, "ellipsoid");
    /* Noise breaks every symmetry: the sum must still hold. */
    unsigned state = 99u;
    for (int32_t i = 0; i < 3 * egg->vertex_count; ++i) {
        state = state * 1103515245u + 12345u;
        egg->positions[i] += 2.0 * (((state >> 8) & 0xffff) / 32767.5 - 1.0);
    }
    check_index_sum(egg, "noisy ellipsoid");
    pz_mesh_free(&egg);
    /* A sphere is umbilic everywhere: no anisotropy, no boundary, the field is seeded at one face. */
    pz_mesh *sphere = ellipsoid(48, 30, 200.0, 200.0, 200.0);
    check_index_sum(sphere, "sphere");
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

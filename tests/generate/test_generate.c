/*
 * tests/generate/test_generate.c -- the synthetic shapes of pz_generate.
 *
 * For every shape (and the open cylinder and cone) at ~2000 faces, and some
 * at 500 and 200,000: the mesh validates, has one component of genus 0 with
 * the expected boundary loops, the face count is within 10 % of the target,
 * faces are well shaped (corner angles), the bounding box and girths are the
 * documented human-scale millimetres, normals point outward, the angle
 * defect has the sign of the surface's Gaussian curvature (exactly 0 on the
 * developable cylinder and cone), and poses keep the connectivity without
 * inverting or badly stretching any face. Also: names, defaults, errors,
 * determinism and the duplicated seam of the open shapes.
 *
 * SPDX-License-Identifier: GPL-3.0-or-later
 */
#include "core/vec.h"
#include "generate/generate.h"
#include "mesh/mesh.h"
#include "test_util.h"

#include <math.h>
#include <stdlib.h>
#include <string.h>

#define DEGREES (PZ_PI / 180.0)

/* What each shape must look like: loops, bounding box (each bound within `slack` mm of the value). */
typedef struct expectation {
    pz_shape shape;
    int open;
    int loop_count;
    double bbox_min[3], bbox_max[3];
} expectation;

static const expectation expectations[] = {
    {PZ_SHAPE_BODICE, 0, 2, {-176, -138, 0}, {176, 133, 600}},
    {PZ_SHAPE_SKIRT, 0, 2, {-286, -286, 0}, {286, 286, 650}},
    {PZ_SHAPE_SLEEVE, 0, 2, {-51, -174, 20}, {51, 51, 580}},
    {PZ_SHAPE_HEMISPHERE, 0, 1, {-150, -150, 0}, {150, 150, 150}},
    {PZ_SHAPE_QUARTER_SPHERE, 0, 1, {0, -150, 0}, {150, 150, 150}},
    {PZ_SHAPE_SADDLE, 0, 1, {-212, -212, -75}, {212, 212, 75}},
    {PZ_SHAPE_CYLINDER, 0, 2, {-150, -150, 0}, {150, 150, 400}},
    {PZ_SHAPE_CONE, 0, 2, {-200, -200, 0}, {200, 200, 300}},
    {PZ_SHAPE_CYLINDER, 1, 1, {-150, -150, 0}, {150, 150, 400}},
    {PZ_SHAPE_CONE, 1, 1, {-200, -200, 0}, {200, 200, 300}},
};
#define EXPECTATION_COUNT (int)(sizeof expectations / sizeof expectations[0])

static pz_mesh *generate(pz_shape shape, int32_t faces, int32_t poses, int open)
{
    pz_ctx ctx = {0};
    pz_generate_options options = {faces, poses, open};
    pz_mesh *mesh = NULL;
    pz_status status = pz_generate(shape, &options, &mesh, &ctx);
    REQUIRE(status == PZ_OK && mesh, "%s %d faces: %s", pz_shape_name(shape), (int)faces, ctx.error);
    return mesh;
}

static void face_centroid(const pz_mesh *mesh, const double *positions, int32_t f, double *out)
{
    out[0] = out[1] = out[2] = 0.0;
    for (int k = 0; k < 3; ++k)
        for (int d = 0; d < 3; ++d)
            out[d] += positions[3 * mesh->faces[3 * f + k] + d] / 3.0;
}

/* Twice-area vector of face f in `positions`. */
static void face_cross(const pz_mesh *mesh, const double *positions, int32_t f, double *out)
{
    const int32_t *c = mesh->faces + 3 * f;
    double u[3], w[3];
    pz_vec3_sub(positions + 3 * c[1], positions + 3 * c[0], u);
    pz_vec3_sub(positions + 3 * c[2], positions + 3 * c[0], w);
    pz_vec3_cross(u, w, out);
}

/*
 * Volume enclosed by the surface with each boundary loop capped by a fan to
 * its centroid (divergence theorem): positive when the normals point out.
 */
static double capped_volume(const pz_mesh *mesh, const pz_loops *loops)
{
    double volume = 0.0, cross[3];
    for (int32_t f = 0; f < mesh->face_count; ++f) {
        const int32_t *c = mesh->faces + 3 * f;
        pz_vec3_cross(mesh->positions + 3 * c[1], mesh->positions + 3 * c[2], cross);
        volume += pz_vec3_dot(mesh->positions + 3 * c[0], cross) / 6.0;
    }
    for (int32_t l = 0; l < loops->loop_count; ++l) {
        int32_t begin = loops->loop_offsets[l], end = loops->loop_offsets[l + 1];
        double center[3] = {0, 0, 0};
        for (int32_t i = begin; i < end; ++i)
            for (int d = 0; d < 3; ++d)
                center[d] += mesh->positions[3 * loops->loop_vertices[i] + d] / (end - begin);
        /* the loop runs with the surface on its left; the cap runs the other way */
        for (int32_t i = begin; i < end; ++i) {
            const double *p = mesh->positions + 3 * loops->loop_vertices[i];
            const double *q = mesh->positions + 3 * loops->loop_vertices[i + 1 < end ? i + 1 : begin];
            pz_vec3_cross(q, p, cross);
            volume += pz_vec3_dot(center, cross) / 6.0;
        }
    }
    return volume;
}

static double loop_length(const pz_mesh *mesh, const pz_loops *loops, int32_t l)
{
    int32_t begin = loops->loop_offsets[l], end = loops->loop_offsets[l + 1];
    double length = 0.0, d[3];
    for (int32_t i = begin; i < end; ++i) {
        pz_vec3_sub(mesh->positions + 3 * loops->loop_vertices[i],
                    mesh->positions + 3 * loops->loop_vertices[i + 1 < end ? i + 1 : begin], d);
        length += sqrt(pz_vec3_dot(d, d));
    }
    return length;
}

/* Length of the section of the surface by the plane z = height (sum of the face chords). */
static double girth_at(const pz_mesh *mesh, double height)
{
    double total = 0.0;
    for (int32_t f = 0; f < mesh->face_count; ++f) {
        double points[2][3];
        int found = 0;
        for (int k = 0; k < 3 && found < 2; ++k) {
            const double *a = mesh->positions + 3 * mesh->faces[3 * f + k];
            const double *b = mesh->positions + 3 * mesh->faces[3 * f + (k + 1) % 3];
            if ((a[2] - height) * (b[2] - height) < 0.0) {
                double t = (height - a[2]) / (b[2] - a[2]);
                for (int d = 0; d < 3; ++d)
                    points[found][d] = a[d] + t * (b[d] - a[d]);
                ++found;
            }
        }
        if (found == 2)
            total += hypot(points[0][0] - points[1][0], points[0][1] - points[1][1]);
    }
    return total;
}

/* Fraction of faces whose smallest corner angle is above `degrees`. */
static double fraction_above(const pz_mesh *mesh, double degrees, double *smallest)
{
    double *angles = malloc((size_t)mesh->face_count * 3 * sizeof(double));
    REQUIRE(angles, "out of memory");
    pz_geom_corner_angles(mesh, angles);
    int32_t good = 0;
    *smallest = INFINITY;
    for (int32_t f = 0; f < mesh->face_count; ++f) {
        double low = fmin(angles[3 * f], fmin(angles[3 * f + 1], angles[3 * f + 2]));
        good += low > degrees * DEGREES;
        *smallest = fmin(*smallest, low / DEGREES);
    }
    free(angles);
    return (double)good / mesh->face_count;
}

/* Fraction of faces whose normal points away from the outward reference of the shape. */
static double outward_fraction(const pz_mesh *mesh, pz_shape shape)
{
    int32_t outward = 0, counted = 0;
    for (int32_t f = 0; f < mesh->face_count; ++f) {
        double c[3], n[3], away[3];
        face_centroid(mesh, mesh->positions, f, c);
        face_cross(mesh, mesh->positions, f, n);
        if (shape == PZ_SHAPE_HEMISPHERE || shape == PZ_SHAPE_QUARTER_SPHERE) {
            memcpy(away, c, sizeof away);                       /* from the centre */
        } else if (shape == PZ_SHAPE_SADDLE) {
            away[0] = 0, away[1] = 0, away[2] = 1;              /* up */
        } else if (shape == PZ_SHAPE_SLEEVE && c[2] < 380.0) {
            continue;                                           /* the bent part has no vertical axis */
        } else {
            away[0] = c[0], away[1] = c[1], away[2] = 0;        /* from the vertical axis */
        }
        ++counted;
        outward += pz_vec3_dot(n, away) > 0.0;
    }
    return counted ? (double)outward / counted : 0.0;
}

/* Structure, size and shape checks every generated mesh must pass. */
static void check_mesh(const expectation *e, int32_t target)
{
    pz_status status;
    const char *name = pz_shape_name(e->shape);
    pz_mesh *mesh = generate(e->shape, target, 0, e->open);
    pz_ctx ctx = {0};

    pz_validation validation;
    status = pz_mesh_validate(mesh, &validation, &ctx);
    REQUIRE(status == PZ_OK, "%s: %s", name, ctx.error);
    CHECK(pz_validation_ok(&validation) && validation.unreferenced_vertices == 0, "%s %d: %s", name, (int)target,
          validation.problem_count ? validation.problems[0] : "unreferenced vertices");
    pz_validation_clear(&validation);

    double error = fabs((double)mesh->face_count - target) / target;
    CHECK(error <= 0.10, "%s: %d faces for a target of %d", name, (int)mesh->face_count, (int)target);

    pz_topology *topology = NULL;
    status = pz_topology_build(mesh, &topology, &ctx);
    REQUIRE(status == PZ_OK, "%s: %s", name, ctx.error);
    pz_topology_summary summary;
    status = pz_topology_summarize(topology, &summary, &ctx);
    REQUIRE(status == PZ_OK, "%s: %s", name, ctx.error);
    CHECK(summary.component_count == 1, "%s: %d components", name, (int)summary.component_count);
    CHECK(summary.boundary_loop_count == e->loop_count, "%s open=%d: %d boundary loops, expected %d", name, e->open,
          (int)summary.boundary_loop_count, e->loop_count);
    CHECK(summary.genus == 0, "%s: genus %d", name, (int)summary.genus);

    double smallest;
    double good30 = fraction_above(mesh, 30.0, &smallest);
    CHECK(good30 >= 0.99, "%s %d: only %.2f%% of faces have all angles above 30 degrees", name, (int)target,
          100.0 * good30);
    CHECK(smallest > 20.0, "%s %d: smallest corner angle %.1f degrees", name, (int)target, smallest);

    double lo[3], hi[3];
    pz_mesh_bbox(mesh, lo, hi);
    double slack = target < 1000 ? 8.0 : 4.0;  /* a coarse ring misses the extremes by a little */
    for (int k = 0; k < 3; ++k) {
        CHECK(fabs(lo[k] - e->bbox_min[k]) <= slack, "%s: bbox min[%d] = %.1f, expected %.0f", name, k, lo[k],
              e->bbox_min[k]);
        CHECK(fabs(hi[k] - e->bbox_max[k]) <= slack, "%s: bbox max[%d] = %.1f, expected %.0f", name, k, hi[k],
              e->bbox_max[k]);
    }

    double outward = outward_fraction(mesh, e->shape);
    CHECK(outward >= 0.999, "%s: only %.2f%% of the normals point outward", name, 100.0 * outward);
    pz_loops *loops = NULL;
    status = pz_topology_boundary_loops(topology, &loops, &ctx);
    REQUIRE(status == PZ_OK, "%s: %s", name, ctx.error);
    if (e->shape != PZ_SHAPE_SADDLE)
        CHECK(capped_volume(mesh, loops) > 0.0, "%s: capped volume %.0f is not positive (normals inward)", name,
              capped_volume(mesh, loops));
    pz_loops_free(&loops);

    /* Gaussian curvature: the sign of the angle defect at interior vertices. */
    double *defect = malloc((size_t)mesh->vertex_count * sizeof(double));
    REQUIRE(defect, "out of memory");
    pz_geom_angle_defect(mesh, topology, defect);
    int32_t interior = 0, positive = 0, negative = 0, flat = 0;
    double largest = 0.0;
    for (int32_t v = 0; v < mesh->vertex_count; ++v) {
        if (topology->vertex_on_boundary[v])
            continue;
        ++interior;
        positive += defect[v] > 0.0;
        negative += defect[v] < 0.0;
        flat += fabs(defect[v]) < 1e-9;
        largest = fmax(largest, fabs(defect[v]));
    }
    CHECK(interior > 0, "%s: no interior vertex", name);
    switch (e->shape) {
    case PZ_SHAPE_CYLINDER:
    case PZ_SHAPE_CONE:
        CHECK(flat == interior, "%s open=%d: %d of %d interior vertices have |defect| >= 1e-9 (max %.3g)", name,
              e->open, (int)(interior - flat), (int)interior, largest);
        break;
    case PZ_SHAPE_HEMISPHERE:
    case PZ_SHAPE_QUARTER_SPHERE:
        CHECK(positive == interior, "%s: %d of %d interior vertices have defect <= 0", name,
              (int)(interior - positive), (int)interior);
        break;
    case PZ_SHAPE_SADDLE:
        CHECK(negative == interior, "%s: %d of %d interior vertices have defect >= 0", name,
              (int)(interior - negative), (int)interior);
        break;
    default:
        break;
    }
    free(defect);
    pz_topology_free(&topology);
    pz_mesh_free(&mesh);
}

/* Bodice: both signs of curvature where a body has them, and its girths. */
static void check_bodice_shape(void)
{
    pz_status status;
    pz_mesh *mesh = generate(PZ_SHAPE_BODICE, 20000, 0, 0);
    pz_ctx ctx = {0};
    pz_topology *topology = NULL;
    status = pz_topology_build(mesh, &topology, &ctx);
    REQUIRE(status == PZ_OK, "bodice: %s", ctx.error);
    double *defect = malloc((size_t)mesh->vertex_count * sizeof(double));
    REQUIRE(defect, "out of memory");
    pz_geom_angle_defect(mesh, topology, defect);
    /* Defects scale with the vertex area: compare with a flat-grid value. */
    double vertex_area = 2.0 * pz_geom_total_area(mesh) / mesh->face_count;
    double clear = 0.2 * vertex_area / (300.0 * 300.0);  /* |K| of a 300 mm radius, a fifth of it */
    int32_t clearly_positive = 0, clearly_negative = 0, waist = 0, waist_negative = 0, bust = 0, bust_positive = 0;
    for (int32_t v = 0; v < mesh->vertex_count; ++v) {
        if (topology->vertex_on_boundary[v])
            continue;
        const double *p = mesh->positions + 3 * v;
        clearly_positive += defect[v] > clear;
        clearly_negative += defect[v] < -clear;
        if (fabs(p[2] - 280.0) < 20.0) {
            ++waist;
            waist_negative += defect[v] < 0.0;
        }
        /* around a bust point: front, 92 mm from the centre, at 455 */
        if (p[1] < 0.0 && hypot(fabs(p[0]) - 92.0, p[2] - 455.0) < 25.0) {
            ++bust;
            bust_positive += defect[v] > 0.0;
        }
    }
    CHECK(clearly_positive > mesh->vertex_count / 20, "bodice: only %d clearly positive vertices",
          (int)clearly_positive);
    CHECK(clearly_negative > mesh->vertex_count / 20, "bodice: only %d clearly negative vertices",
          (int)clearly_negative);
    CHECK(waist > 0 && waist_negative >= 0.9 * waist, "bodice: %d of %d waist vertices negative", (int)waist_negative,
          (int)waist);
    CHECK(bust > 0 && bust_positive >= 0.9 * bust, "bodice: %d of %d bust vertices positive", (int)bust_positive,
          (int)bust);
    free(defect);
    pz_topology_free(&topology);

    double hip = girth_at(mesh, 80.0), waist_girth = girth_at(mesh, 280.0), bust_girth = girth_at(mesh, 455.0);
    CHECK(fabs(hip - 980.0) < 30.0, "bodice: hip girth %.0f", hip);
    CHECK(fabs(waist_girth - 740.0) < 30.0, "bodice: waist girth %.0f", waist_girth);
    CHECK(fabs(bust_girth - 920.0) < 30.0, "bodice: bust girth %.0f", bust_girth);
    pz_mesh_free(&mesh);
}

/* Skirt girths at the waist, hip and hem; sleeve girths and its elbow bend. */
static void check_skirt_and_sleeve(void)
{
    pz_status status;
    pz_ctx ctx = {0};
    pz_mesh *skirt = generate(PZ_SHAPE_SKIRT, 20000, 0, 0);
    double waist = girth_at(skirt, 649.0), hip = girth_at(skirt, 450.0), hem = girth_at(skirt, 1.0);
    CHECK(fabs(waist - 700.0) < 30.0, "skirt: waist girth %.0f", waist);
    CHECK(fabs(hip - 960.0) < 30.0, "skirt: hip girth %.0f", hip);
    CHECK(hem > 1600.0 && hem < 2000.0, "skirt: hem girth %.0f", hem);
    pz_mesh_free(&skirt);

    pz_mesh *sleeve = generate(PZ_SHAPE_SLEEVE, 20000, 0, 0);
    pz_topology *topology = NULL;
    pz_loops *loops = NULL;
    status = pz_topology_build(sleeve, &topology, &ctx);
    REQUIRE(status == PZ_OK, "sleeve: %s", ctx.error);
    status = pz_topology_boundary_loops(topology, &loops, &ctx);
    REQUIRE(status == PZ_OK && loops->loop_count == 2, "sleeve: loops");
    /* Newell normals of the two end loops: the angle between them is the bend. */
    double normals[2][3] = {{0}}, lengths[2];
    for (int32_t l = 0; l < 2; ++l) {
        lengths[l] = loop_length(sleeve, loops, l);
        int32_t begin = loops->loop_offsets[l], end = loops->loop_offsets[l + 1];
        for (int32_t i = begin; i < end; ++i) {
            const double *p = sleeve->positions + 3 * loops->loop_vertices[i];
            const double *q = sleeve->positions + 3 * loops->loop_vertices[i + 1 < end ? i + 1 : begin];
            double c[3];
            pz_vec3_cross(p, q, c);
            for (int d = 0; d < 3; ++d)
                normals[l][d] += c[d];
        }
    }
    double top = fmax(lengths[0], lengths[1]), wrist = fmin(lengths[0], lengths[1]);
    CHECK(fabs(top - 320.0) < 5.0, "sleeve: top girth %.1f", top);
    CHECK(fabs(wrist - 220.0) < 5.0, "sleeve: wrist girth %.1f", wrist);
    double cosine = -pz_vec3_dot(normals[0], normals[1]) /
                    sqrt(pz_vec3_dot(normals[0], normals[0]) * pz_vec3_dot(normals[1], normals[1]));
    double bend = acos(fmin(1.0, fmax(-1.0, cosine))) / DEGREES;
    CHECK(bend > 30.0 && bend < 40.0, "sleeve: elbow bend %.1f degrees", bend);
    pz_loops_free(&loops);
    pz_topology_free(&topology);
    pz_mesh_free(&sleeve);
}

/* Poses: same vertex count, finite, different from the rest, no face inverted or badly stretched. */
static void check_poses(pz_shape shape, int32_t pose_count)
{
    const char *name = pz_shape_name(shape);
    pz_mesh *mesh = generate(shape, 3000, pose_count, 0);
    CHECK(mesh->pose_count == pose_count && mesh->poses, "%s: %d poses", name, (int)mesh->pose_count);
    for (int32_t p = 0; p < mesh->pose_count; ++p) {
        const double *pose = mesh->poses + (size_t)p * mesh->vertex_count * 3;
        int finite = 1;
        double moved = 0.0;
        for (int32_t i = 0; i < mesh->vertex_count * 3; ++i) {
            finite = finite && isfinite(pose[i]);
            moved = fmax(moved, fabs(pose[i] - mesh->positions[i]));
        }
        CHECK(finite, "%s pose %d: non-finite coordinate", name, (int)p);
        CHECK(moved > 3.0, "%s pose %d: moves at most %.2f mm", name, (int)p, moved);
        int32_t inverted = 0;
        double low = INFINITY, high = 0.0;
        for (int32_t f = 0; f < mesh->face_count; ++f) {
            double rest[3], posed[3];
            face_cross(mesh, mesh->positions, f, rest);
            face_cross(mesh, pose, f, posed);
            double ratio = sqrt(pz_vec3_dot(posed, posed) / pz_vec3_dot(rest, rest));
            inverted += pz_vec3_dot(rest, posed) <= 0.0;
            low = fmin(low, ratio);
            high = fmax(high, ratio);
        }
        CHECK(inverted == 0, "%s pose %d: %d faces flipped", name, (int)p, (int)inverted);
        CHECK(low >= 0.8 && high <= 1.25, "%s pose %d: area ratios %.3f .. %.3f", name, (int)p, low, high);
    }
    pz_mesh_free(&mesh);
}

/* The bodice's twist turns the top by ~25 degrees and its breathing scales sections by 2-4 %. */
static void check_pose_amplitudes(void)
{
    pz_mesh *mesh = generate(PZ_SHAPE_BODICE, 2000, 3, 0);
    const double *twist = mesh->poses + (size_t)1 * mesh->vertex_count * 3;
    const double *breath = mesh->poses + (size_t)2 * mesh->vertex_count * 3;
    double top_turn = 0.0, scale_low = INFINITY, scale_high = 0.0;
    for (int32_t v = 0; v < mesh->vertex_count; ++v) {
        const double *p = mesh->positions + 3 * v;
        if (p[2] > 599.0)
            top_turn = fmax(top_turn, fabs(remainder(atan2(twist[3 * v + 1], twist[3 * v]) - atan2(p[1], p[0]), 2.0 * PZ_PI)));
        double scale = hypot(breath[3 * v], breath[3 * v + 1]) / hypot(p[0], p[1]);
        scale_low = fmin(scale_low, scale);
        scale_high = fmax(scale_high, scale);
    }
    CHECK(top_turn > 20.0 * DEGREES && top_turn < 30.0 * DEGREES, "bodice twist: top turns %.1f degrees",
          top_turn / DEGREES);
    CHECK(scale_low > 1.015 && scale_high < 1.05, "bodice breathing: scales %.3f .. %.3f", scale_low, scale_high);
    pz_mesh_free(&mesh);
}

/* The open cylinder is the closed one with its seam vertices doubled, at identical positions. */
static int compare_positions(const void *a, const void *b)
{
    const double *p = a, *q = b;
    for (int k = 0; k < 3; ++k)
        if (p[k] != q[k])
            return p[k] < q[k] ? -1 : 1;
    return 0;
}

static void check_open_seam(pz_shape shape)
{
    const char *name = pz_shape_name(shape);
    pz_mesh *closed = generate(shape, 2000, 0, 0), *open = generate(shape, 2000, 0, 1);
    CHECK(open->face_count == closed->face_count, "%s: open %d faces, closed %d", name, (int)open->face_count,
          (int)closed->face_count);
    double *sorted = malloc((size_t)open->vertex_count * 3 * sizeof(double));
    REQUIRE(sorted, "out of memory");
    memcpy(sorted, open->positions, (size_t)open->vertex_count * 3 * sizeof(double));
    qsort(sorted, (size_t)open->vertex_count, 3 * sizeof(double), compare_positions);
    int32_t duplicates = 0;
    for (int32_t v = 1; v < open->vertex_count; ++v)
        duplicates += compare_positions(sorted + 3 * v, sorted + 3 * (v - 1)) == 0;
    CHECK(duplicates > 0 && duplicates == open->vertex_count - closed->vertex_count,
          "%s: %d coincident seam vertices for %d extra vertices", name, (int)duplicates,
          (int)(open->vertex_count - closed->vertex_count));
    free(sorted);
    pz_mesh_free(&closed);
    pz_mesh_free(&open);
}

static void check_errors_and_names(void)
{
    pz_status status;
    pz_ctx ctx = {0};
    pz_mesh *mesh = (pz_mesh *)&ctx;  /* must come back NULL */
    for (int i = 0; i < EXPECTATION_COUNT; ++i) {
        const char *name = pz_shape_name(expectations[i].shape);
        CHECK(pz_shape_parse(name) == expectations[i].shape, "parse(name(%d))", (int)expectations[i].shape);
    }
    CHECK(pz_shape_parse("quarter-sphere") == PZ_SHAPE_QUARTER_SPHERE, "parse quarter-sphere");
    CHECK(pz_shape_parse("torus") == PZ_SHAPE_UNKNOWN, "parse torus");
    CHECK(pz_shape_parse("") == PZ_SHAPE_UNKNOWN, "parse empty");
    CHECK(strcmp(pz_shape_name(PZ_SHAPE_UNKNOWN), "unknown") == 0, "name of unknown");

    struct {
        pz_shape shape;
        pz_generate_options options;
        const char *mentions;
    } bad[] = {
        {PZ_SHAPE_UNKNOWN, {0, 0, 0}, "unknown shape"},
        {(pz_shape)99, {0, 0, 0}, "unknown shape"},
        {PZ_SHAPE_CYLINDER, {-1, 0, 0}, "cylinder"},
        {PZ_SHAPE_BODICE, {10000001, 0, 0}, "bodice"},
        {PZ_SHAPE_SKIRT, {2000, -1, 0}, "skirt"},
        {PZ_SHAPE_SKIRT, {2000, 65, 0}, "skirt"},
        {PZ_SHAPE_HEMISPHERE, {2000, 0, 1}, "hemisphere"},
    };
    for (size_t i = 0; i < sizeof bad / sizeof bad[0]; ++i) {
        ctx.error[0] = '\0';
        mesh = (pz_mesh *)&ctx;
        status = pz_generate(bad[i].shape, &bad[i].options, &mesh, &ctx);
        CHECK(status == PZ_ERR_USAGE && mesh == NULL, "bad case %d: status %d", (int)i, (int)status);
        CHECK(strstr(ctx.error, bad[i].mentions) && !strchr(ctx.error, '\n'), "bad case %d: message '%s'", (int)i,
              ctx.error);
    }

    /* Defaults: NULL options and target 0 both mean 20000 faces, no poses. */
    status = pz_generate(PZ_SHAPE_CONE, NULL, &mesh, &ctx);
    REQUIRE(status == PZ_OK, "cone defaults: %s", ctx.error);
    CHECK(fabs(mesh->face_count - 20000.0) <= 2000.0 && mesh->pose_count == 0, "defaults: %d faces, %d poses",
          (int)mesh->face_count, (int)mesh->pose_count);
    pz_mesh_free(&mesh);

    /* Below 500 faces the shapes are coarse but still valid. */
    for (int i = 0; i < EXPECTATION_COUNT; ++i) {
        pz_mesh *tiny = generate(expectations[i].shape, 1, 0, expectations[i].open);
        pz_validation validation;
        CHECK(pz_mesh_validate(tiny, &validation, &ctx) == PZ_OK && pz_validation_ok(&validation),
              "%s with 1 face: not valid", pz_shape_name(expectations[i].shape));
        pz_validation_clear(&validation);
        pz_mesh_free(&tiny);
    }
}

static void check_deterministic(void)
{
    pz_mesh *first = generate(PZ_SHAPE_BODICE, 5000, 2, 0), *second = generate(PZ_SHAPE_BODICE, 5000, 2, 0);
    CHECK(first->vertex_count == second->vertex_count && first->face_count == second->face_count &&
              memcmp(first->positions, second->positions, (size_t)first->vertex_count * 3 * sizeof(double)) == 0 &&
              memcmp(first->faces, second->faces, (size_t)first->face_count * 3 * sizeof(int32_t)) == 0 &&
              memcmp(first->poses, second->poses, (size_t)first->vertex_count * 6 * sizeof(double)) == 0,
          "bodice: two runs differ");
    pz_mesh_free(&first);
    pz_mesh_free(&second);
}

int main(void)
{
    for (int i = 0; i < EXPECTATION_COUNT; ++i)
        check_mesh(&expectations[i], 2000);
    for (int i = 0; i < EXPECTATION_COUNT; ++i)
        check_mesh(&expectations[i], 500);
    check_mesh(&expectations[0], 200000);  /* bodice */
    check_mesh(&expectations[3], 200000);  /* hemisphere */
    check_mesh(&expectations[5], 200000);  /* saddle */
    check_mesh(&expectations[9], 200000);  /* open cone */
    check_bodice_shape();
    check_skirt_and_sleeve();
    for (int i = 0; i < 8; ++i)
        check_poses(expectations[i].shape, 3);
    check_poses(PZ_SHAPE_BODICE, 9);  /* later cycles: larger amplitudes */
    check_poses(PZ_SHAPE_CYLINDER, 9);
    check_pose_amplitudes();
    check_open_seam(PZ_SHAPE_CYLINDER);
    check_open_seam(PZ_SHAPE_CONE);
    check_errors_and_names();
    check_deterministic();
    return test_finish();
}

/*
 * generate/generate.c -- synthetic garments and test surfaces (pz_generate).
 *
 * Every shape is a parametric surface P(v, t) sampled by one of two meshers
 * (docs/generate.md has the dimensions and the pictures in words):
 *
 *  - The ring mesher (bodice, skirt, sleeve, hemisphere, quarter-sphere).
 *    Rings are curves of constant v, spaced sqrt(3)/2 * w apart in surface
 *    distance (from a table of the average meridian length), each with a
 *    vertex count proportional to its own length (edges of length ~ w),
 *    alternate closed rings shifted by half a step. Non-circular rings are
 *    resampled by arc length. Two neighbouring rings are zipped together by
 *    merging their edges in the order of their midpoints' ring fractions, so
 *    every face has one edge on a ring and near-equilateral shape even where
 *    the two counts differ. On coaxial circles (the spheres) that merge picks
 *    exactly the faces of the convex hull, so every interior vertex of a
 *    sphere has a strictly positive angle defect.
 *  - The grid mesher (cylinder, cone, saddle). A rows x columns grid, each
 *    cell split along the same diagonal. Grid lines of the cylinder and the
 *    cone are rulings and circles, so every cell is a planar quad and the
 *    angle sum at an interior vertex is exactly 2 pi (a prism or a pyramid
 *    frustum; staggered rows would make a non-developable Schwarz lantern).
 *    The cone's rows are spaced geometrically so that cells stay square while
 *    the radius grows. The saddle's grid lines are its two families of
 *    rulings (z = p q / R); every interior vertex sees the same star up to an
 *    affine map, whose face normals wind backwards: defect < 0 everywhere.
 *
 * The resolution is solved from the target face count: for the grids
 * directly (cells square), for rings by adjusting the edge length w until
 * the exact count of the layout is within rounding of the target.
 *
 * Poses (options->pose_count): pose p is a bend (p % 3 == 0), a twist (1) or
 * a breathing (2) of the rest positions about the vertical axis through the
 * bounding-box centre, with amplitudes growing in later cycles and clamped
 * by the shape's width so no face is stretched more than ~12 %.
 *
 * Failure: PZ_ERR_USAGE for an unknown shape, a target outside
 * [1, 10,000,000], a pose count outside [0, 64] or `open` on a shape other
 * than the cylinder and cone; PZ_ERR_NOMEM when an allocation fails. Nothing
 * is leaked and *out stays NULL on failure.
 *
 * SPDX-License-Identifier: GPL-3.0-or-later
 */
#include "generate/generate.h"

#include <math.h>
#include <stdlib.h>
#include <string.h>

#define GEN_PI 3.14159265358979323846
#define GEN_DEFAULT_FACES 20000
#define GEN_MAX_FACES 10000000
#define GEN_MAX_POSES 64

/* ------------------------------------------------------------------------ */
/* Names                                                                     */
/* ------------------------------------------------------------------------ */

static const struct {
    pz_shape shape;
    const char *name;
} shape_names[] = {
    {PZ_SHAPE_BODICE, "bodice"},       {PZ_SHAPE_SKIRT, "skirt"},
    {PZ_SHAPE_SLEEVE, "sleeve"},       {PZ_SHAPE_HEMISPHERE, "hemisphere"},
    {PZ_SHAPE_QUARTER_SPHERE, "quarter-sphere"}, {PZ_SHAPE_SADDLE, "saddle"},
    {PZ_SHAPE_CYLINDER, "cylinder"},   {PZ_SHAPE_CONE, "cone"},
};
#define SHAPE_NAME_COUNT (sizeof shape_names / sizeof shape_names[0])

pz_shape pz_shape_parse(const char *name)
{
    for (size_t i = 0; name && i < SHAPE_NAME_COUNT; ++i)
        if (strcmp(name, shape_names[i].name) == 0)
            return shape_names[i].shape;
    return PZ_SHAPE_UNKNOWN;
}

const char *pz_shape_name(pz_shape shape)
{
    for (size_t i = 0; i < SHAPE_NAME_COUNT; ++i)
        if (shape_names[i].shape == shape)
            return shape_names[i].name;
    return "unknown";
}

/* ------------------------------------------------------------------------ */
/* Parametric surfaces                                                       */
/* ------------------------------------------------------------------------ */

/*
 * A surface P(v, t): v in [0, 1] across the rings or rows (0 = top), t in
 * [0, 1] along them (periodic for closed ones), t increasing
 * counter-clockwise seen from above, so that faces built top-down with t
 * increasing face outward.
 */
typedef struct surface surface;
typedef void (*surface_eval)(const surface *s, double v, double t, double out[3]);

/* The sleeve's centre line, tabulated: position and unit tangent at equal arc-length steps. */
typedef struct centerline {
    int32_t step_count;
    double length;
    double *points;    /* (step_count + 1) x 3 */
    double *tangents;  /* (step_count + 1) x 3 */
} centerline;

struct surface {
    surface_eval eval;
    int closed;       /* t is periodic: rings are loops */
    int pole_first;   /* the ring at v = 0 is a single point (ring mesher) */
    int arc_length;   /* resample rings by arc length: their t is not uniform in length */
    const centerline *spine;  /* sleeve only */
};

static double smoothstep(double x)
{
    x = x < 0.0 ? 0.0 : x > 1.0 ? 1.0 : x;
    return x * x * (3.0 - 2.0 * x);
}

/*
 * Piecewise smoothstep through (knots[i], values[i]): zero slope at every
 * knot, so a knot is a local extremum (full hip, waist, bust) and the
 * profile's curvature has one sign on each side of it.
 */
static double profile(const double *knots, const double *values, int count, double x)
{
    if (x <= knots[0])
        return values[0];
    for (int i = 0; i + 1 < count; ++i)
        if (x <= knots[i + 1])
            return values[i] + (values[i + 1] - values[i]) * smoothstep((x - knots[i]) / (knots[i + 1] - knots[i]));
    return values[count - 1];
}

/* Ramanujan's perimeter of an ellipse with half-axes a, b. */
static double ellipse_perimeter(double a, double b)
{
    return GEN_PI * (3.0 * (a + b) - sqrt((3.0 * a + b) * (a + 3.0 * b)));
}

/* Bodice: hem (just below the full hip) at z = 0 to the underarm line at z = 600. */
enum { BODICE_KNOTS = 5 };
static const double bodice_height = 600.0;
static const double bodice_z[BODICE_KNOTS] = {0.0, 80.0, 280.0, 460.0, 600.0};
static const double bodice_half_width[BODICE_KNOTS] = {170.0, 176.0, 134.0, 158.0, 152.0};
static const double bodice_half_depth[BODICE_KNOTS] = {128.0, 133.0, 100.0, 118.0, 114.0};
static const double bust_height = 455.0, bust_apart = 92.0, bust_depth = 42.0;
static const double bust_sigma_x = 48.0, bust_sigma_z = 58.0;

static void bodice_eval(const surface *s, double v, double t, double out[3])
{
    (void)s;
    double z = bodice_height * (1.0 - v);
    double a = profile(bodice_z, bodice_half_width, BODICE_KNOTS, z);
    double b = profile(bodice_z, bodice_half_depth, BODICE_KNOTS, z);
    double theta = 0.5 * GEN_PI + 2.0 * GEN_PI * t;  /* t = 0 at the centre back (+y) */
    double x = a * cos(theta), y = b * sin(theta);
    /* Two bumps pushing the front (-y) forward; the weight sin^2 fades them
     * out smoothly (C1) towards the side seams. */
    double front = sin(theta) < 0.0 ? -sin(theta) : 0.0;
    double dz = (z - bust_height) / bust_sigma_z;
    double dl = (x - bust_apart) / bust_sigma_x, dr = (x + bust_apart) / bust_sigma_x;
    double bump = bust_depth * exp(-0.5 * dz * dz) * (exp(-0.5 * dl * dl) + exp(-0.5 * dr * dr));
    out[0] = x;
    out[1] = y - bump * front * front;
    out[2] = z;
}

/* Skirt: waist at z = 650, hip 200 below it, flaring to the hem at z = 0. */
static const double skirt_length = 650.0, skirt_hip_drop = 200.0;
static const double skirt_waist_girth = 700.0, skirt_hip_girth = 960.0, skirt_hem_girth = 1800.0;

static double skirt_girth(double drop)
{
    if (drop <= skirt_hip_drop) {
        double x = drop / skirt_hip_drop;  /* convex hip curve, level at the full hip */
        return skirt_waist_girth + (skirt_hip_girth - skirt_waist_girth) * (2.0 * x - x * x);
    }
    double x = (drop - skirt_hip_drop) / (skirt_length - skirt_hip_drop);  /* flare, level at the hip */
    return skirt_hip_girth + (skirt_hem_girth - skirt_hip_girth) * x * x;
}

static void skirt_eval(const surface *s, double v, double t, double out[3])
{
    (void)s;
    double drop = skirt_length * v;
    double aspect = 1.2 - 0.2 * v;  /* width / depth: oval at the waist, round at the hem */
    double b = skirt_girth(drop) / ellipse_perimeter(aspect, 1.0);
    double theta = 0.5 * GEN_PI + 2.0 * GEN_PI * t;
    out[0] = aspect * b * cos(theta);
    out[1] = b * sin(theta);
    out[2] = skirt_length - drop;
}

/* Sleeve: 580 along its centre line from the armhole (z = 580) down, the
 * forearm bent forward (-y) by 35 degrees over 220 around the elbow. */
static const double sleeve_length = 580.0, sleeve_top = 580.0;
static const double sleeve_elbow = 330.0, sleeve_bend_length = 220.0;
static const double sleeve_bend_degrees = 35.0;
static const double sleeve_top_girth = 320.0, sleeve_wrist_girth = 220.0;

static double sleeve_bend_angle(double arc)
{
    return sleeve_bend_degrees * GEN_PI / 180.0 *
           smoothstep((arc - sleeve_elbow + 0.5 * sleeve_bend_length) / sleeve_bend_length);
}

/* Tangent (0, -sin phi, -cos phi) and in-plane normal (0, cos phi, -sin phi) of the centre line. */
static void sleeve_frame(double arc, double tangent[3], double normal[3])
{
    double phi = sleeve_bend_angle(arc);
    tangent[0] = 0.0, tangent[1] = -sin(phi), tangent[2] = -cos(phi);
    normal[0] = 0.0, normal[1] = cos(phi), normal[2] = -sin(phi);
}

/* Integrates the tangent with Simpson's rule per step. */
static pz_status centerline_build(centerline *line, pz_ctx *ctx)
{
    line->step_count = 2048;
    line->length = sleeve_length;
    size_t size = (size_t)(line->step_count + 1) * 3 * sizeof(double);
    line->points = malloc(size);
    line->tangents = malloc(size);
    if (!line->points || !line->tangents)
        return pz_error(ctx, PZ_ERR_NOMEM, "sleeve: out of memory");
    double step = line->length / line->step_count, normal[3], mid[3];
    line->points[0] = 0.0, line->points[1] = 0.0, line->points[2] = sleeve_top;
    sleeve_frame(0.0, line->tangents, normal);
    for (int32_t i = 1; i <= line->step_count; ++i) {
        const double *before = line->tangents + 3 * (i - 1);
        double *tangent = line->tangents + 3 * i;
        sleeve_frame(step * (i - 0.5), mid, normal);
        sleeve_frame(step * i, tangent, normal);
        for (int k = 0; k < 3; ++k)
            line->points[3 * i + k] =
                line->points[3 * (i - 1) + k] + step / 6.0 * (before[k] + 4.0 * mid[k] + tangent[k]);
    }
    return PZ_OK;
}

static void centerline_free(centerline *line)
{
    free(line->points);
    free(line->tangents);
    line->points = line->tangents = NULL;
}

/* Cubic Hermite interpolation of the tabulated centre line at arc length `arc`. */
static void centerline_point(const centerline *line, double arc, double out[3])
{
    double step = line->length / line->step_count;
    int32_t i = (int32_t)(arc / step);
    if (i < 0) i = 0;
    if (i >= line->step_count) i = line->step_count - 1;
    double x = arc / step - i;
    double h00 = (1 + 2 * x) * (1 - x) * (1 - x), h10 = x * (1 - x) * (1 - x);
    double h01 = x * x * (3 - 2 * x), h11 = x * x * (x - 1);
    const double *p0 = line->points + 3 * i, *p1 = p0 + 3;
    const double *m0 = line->tangents + 3 * i, *m1 = m0 + 3;
    for (int k = 0; k < 3; ++k)
        out[k] = h00 * p0[k] + h10 * step * m0[k] + h01 * p1[k] + h11 * step * m1[k];
}

static void sleeve_eval(const surface *s, double v, double t, double out[3])
{
    double arc = sleeve_length * v, center[3], tangent[3], normal[3];
    centerline_point(s->spine, arc, center);
    sleeve_frame(arc, tangent, normal);
    double girth = sleeve_top_girth + (sleeve_wrist_girth - sleeve_top_girth) * v;
    double radius = girth / (2.0 * GEN_PI), theta = 2.0 * GEN_PI * t;
    /* Cross-section axes x and `normal`: counter-clockwise seen from the shoulder. */
    for (int k = 0; k < 3; ++k)
        out[k] = center[k] + radius * sin(theta) * normal[k];
    out[0] += radius * cos(theta);
}

/* Spheres: pole at (0, 0, R), v = polar angle / (pi / 2), centre at the origin. */
static const double sphere_radius = 150.0;

static void sphere_point(double v, double longitude, double out[3])
{
    double polar = 0.5 * GEN_PI * v;
    out[0] = sphere_radius * sin(polar) * cos(longitude);
    out[1] = sphere_radius * sin(polar) * sin(longitude);
    out[2] = sphere_radius * cos(polar);
}

static void hemisphere_eval(const surface *s, double v, double t, double out[3])
{
    (void)s;
    sphere_point(v, 2.0 * GEN_PI * t, out);
}

/* The half of the hemisphere with x >= 0: longitudes -90 .. 90 degrees. */
static void quarter_sphere_eval(const surface *s, double v, double t, double out[3])
{
    (void)s;
    sphere_point(v, GEN_PI * (t - 0.5), out);
}

static const double cylinder_radius = 150.0, cylinder_height = 400.0;

static void cylinder_eval(const surface *s, double v, double t, double out[3])
{
    (void)s;
    out[0] = cylinder_radius * cos(2.0 * GEN_PI * t);
    out[1] = cylinder_radius * sin(2.0 * GEN_PI * t);
    out[2] = cylinder_height * (1.0 - v);
}

/* Truncated cone: radius 80 at the top (z = 300), 200 at the bottom (z = 0);
 * the radius grows geometrically with v so square cells stay square. */
static const double cone_top_radius = 80.0, cone_bottom_radius = 200.0, cone_height = 300.0;

static void cone_eval(const surface *s, double v, double t, double out[3])
{
    (void)s;
    double radius = cone_top_radius * pow(cone_bottom_radius / cone_top_radius, v);
    out[0] = radius * cos(2.0 * GEN_PI * t);
    out[1] = radius * sin(2.0 * GEN_PI * t);
    out[2] = cone_height * (cone_bottom_radius - radius) / (cone_bottom_radius - cone_top_radius);
}

/* Saddle z = (x^2 - y^2) / (2R) = p q / R in ruling coordinates
 * p = (x - y) / sqrt 2, q = (x + y) / sqrt 2, over the square |p|, |q| <= 150. */
static const double saddle_half_side = 150.0, saddle_radius = 300.0;

static void saddle_eval(const surface *s, double v, double t, double out[3])
{
    (void)s;
    double p = saddle_half_side * (2.0 * t - 1.0);
    double q = saddle_half_side * (1.0 - 2.0 * v);
    out[0] = (p + q) / sqrt(2.0);
    out[1] = (q - p) / sqrt(2.0);
    out[2] = p * q / saddle_radius;
}

/* ------------------------------------------------------------------------ */
/* The grid mesher                                                           */
/* ------------------------------------------------------------------------ */

/*
 * rows x columns cells; `periodic` joins column `columns` to column 0, `open`
 * (with periodic) keeps them as separate, coincident vertices instead.
 * Cell (i, j) with corners c00 (top left), c01, c10, c11 is split along
 * c00-c11 into (c00, c10, c11) and (c00, c11, c01): counter-clockwise with t
 * to the right and v downward, seen from outside.
 */
static pz_status grid_build(const surface *s, int32_t rows, int32_t columns, int open, pz_mesh **out, pz_ctx *ctx)
{
    int shared_seam = s->closed && !open;
    int32_t row_vertices = shared_seam ? columns : columns + 1;
    pz_status status = pz_mesh_create((rows + 1) * row_vertices, 2 * rows * columns, out, ctx);
    if (status)
        return status;
    pz_mesh *mesh = *out;
    for (int32_t i = 0; i <= rows; ++i)
        for (int32_t j = 0; j < row_vertices; ++j) {
            /* the seam copy reuses column 0's parameter: bit-identical positions */
            int32_t column = s->closed && j == columns ? 0 : j;
            s->eval(s, (double)i / rows, (double)column / columns, mesh->positions + 3 * ((size_t)i * row_vertices + j));
        }
    int32_t *face = mesh->faces;
    for (int32_t i = 0; i < rows; ++i)
        for (int32_t j = 0; j < columns; ++j) {
            int32_t right = shared_seam ? (j + 1) % columns : j + 1;
            int32_t c00 = i * row_vertices + j, c01 = i * row_vertices + right;
            int32_t c10 = c00 + row_vertices, c11 = c01 + row_vertices;
            face[0] = c00, face[1] = c10, face[2] = c11;
            face[3] = c00, face[4] = c11, face[5] = c01;
            face += 6;
        }
    return PZ_OK;
}

/* Nearest integer, at least `minimum` (and capped far above any valid count, to stay in int32_t). */
static int32_t round_at_least(double x, int32_t minimum)
{
    double r = floor(x + 0.5);
    return r < minimum ? minimum : r > 1e8 ? 100000000 : (int32_t)r;
}

/* Columns from the aspect: 2 rows columns = target with cells as wide as tall
 * means columns = sqrt(target / 2 * width / height). */
static void grid_resolution(double target, double width_over_height, int min_columns, int32_t *rows, int32_t *columns)
{
    *columns = round_at_least(sqrt(0.5 * target * width_over_height), min_columns);
    *rows = round_at_least(0.5 * target / *columns, 1);
}

/* ------------------------------------------------------------------------ */
/* The ring mesher                                                           */
/* ------------------------------------------------------------------------ */

enum { TABLE_STEPS = 512, TABLE_RING_SAMPLES = 256, TABLE_MERIDIANS = 32 };

/* Average meridian length and ring length as functions of v, tabulated. */
typedef struct ring_table {
    double meridian[TABLE_STEPS + 1];  /* cumulative average distance from v = 0 */
    double ring[TABLE_STEPS + 1];      /* ring length at v = i / TABLE_STEPS */
    double area;                       /* approximate surface area */
} ring_table;

static double distance3(const double *a, const double *b)
{
    double dx = a[0] - b[0], dy = a[1] - b[1], dz = a[2] - b[2];
    return sqrt(dx * dx + dy * dy + dz * dz);
}

static double ring_length_at(const surface *s, double v, int samples)
{
    double first[3], previous[3], point[3], length = 0.0;
    s->eval(s, v, 0.0, first);
    memcpy(previous, first, sizeof previous);
    for (int k = 1; k <= samples; ++k) {
        s->eval(s, v, (double)k / samples, point);
        length += distance3(previous, point);
        memcpy(previous, point, sizeof previous);
    }
    return length;
}

static void ring_table_fill(const surface *s, ring_table *table)
{
    table->meridian[0] = 0.0;
    table->area = 0.0;
    for (int i = 0; i <= TABLE_STEPS; ++i) {
        double v = (double)i / TABLE_STEPS;
        table->ring[i] = ring_length_at(s, v, TABLE_RING_SAMPLES);
        if (i == 0)
            continue;
        double sum = 0.0, a[3], b[3];
        for (int m = 0; m < TABLE_MERIDIANS; ++m) {
            double t = (m + 0.5) / TABLE_MERIDIANS;
            s->eval(s, v - 1.0 / TABLE_STEPS, t, a);
            s->eval(s, v, t, b);
            sum += distance3(a, b);
        }
        double step = sum / TABLE_MERIDIANS;
        table->meridian[i] = table->meridian[i - 1] + step;
        table->area += 0.5 * (table->ring[i - 1] + table->ring[i]) * step;
    }
}

/* v at which the cumulative meridian length reaches `length` (inverse of a monotone table). */
static double table_v_at(const ring_table *table, double length, int *cursor)
{
    int i = *cursor;
    while (i < TABLE_STEPS && table->meridian[i + 1] < length)
        ++i;
    *cursor = i;
    if (i >= TABLE_STEPS)
        return 1.0;
    double span = table->meridian[i + 1] - table->meridian[i];
    double x = span > 0.0 ? (length - table->meridian[i]) / span : 0.0;
    return (i + (x < 0.0 ? 0.0 : x > 1.0 ? 1.0 : x)) / TABLE_STEPS;
}

static double table_ring_at(const ring_table *table, double v)
{
    double x = v * TABLE_STEPS;
    int i = (int)x;
    if (i >= TABLE_STEPS)
        return table->ring[TABLE_STEPS];
    return table->ring[i] + (x - i) * (table->ring[i + 1] - table->ring[i]);
}

/* Rings: v and edge count of each (0 for a pole). */
typedef struct ring_layout {
    int32_t ring_count;
    double *v;           /* ring_count */
    int32_t *segments;   /* ring_count */
    int64_t face_count;
    int64_t vertex_count;
} ring_layout;

static int32_t ring_vertex_count(const surface *s, int32_t segments)
{
    return segments == 0 ? 1 : s->closed ? segments : segments + 1;
}

/*
 * Lays out rings for edge length `edge`: ring spacing sqrt(3)/2 edge along
 * the meridian, each ring's count its length / edge. The arrays must hold
 * `capacity` rings; returns 0 when more would be needed.
 */
static int ring_layout_fill(const surface *s, const ring_table *table, double edge, int32_t capacity, ring_layout *layout)
{
    double total = table->meridian[TABLE_STEPS];
    int32_t gaps = round_at_least(total / (0.5 * sqrt(3.0) * edge), 1);
    if (gaps + 1 > capacity)
        return 0;
    layout->ring_count = gaps + 1;
    layout->face_count = 0;
    layout->vertex_count = 0;
    int cursor = 0;
    for (int32_t i = 0; i <= gaps; ++i) {
        double v = i == gaps ? 1.0 : table_v_at(table, total * i / gaps, &cursor);
        int32_t segments = round_at_least(table_ring_at(table, v) / edge, s->closed ? 3 : 1);
        if (i == 0 && s->pole_first) {
            v = 0.0;
            segments = 0;
        }
        layout->v[i] = v;
        layout->segments[i] = segments;
        layout->vertex_count += ring_vertex_count(s, segments);
        if (i > 0)
            layout->face_count += layout->segments[i - 1] + segments;
    }
    return 1;
}

/*
 * Chooses the edge length whose layout's face count is nearest the target:
 * start from area / (sqrt(3)/4 edge^2) = target, then correct by the ratio
 * of counts (the count goes as 1 / edge^2) a few times.
 */
static int ring_layout_solve(const surface *s, const ring_table *table, double target, int32_t capacity,
                             ring_layout *layout)
{
    double edge = sqrt(table->area / (0.25 * sqrt(3.0) * target));
    double best_edge = edge, best_error = INFINITY;
    for (int iteration = 0; iteration < 6; ++iteration) {
        if (!ring_layout_fill(s, table, edge, capacity, layout))
            return 0;
        double error = fabs((double)layout->face_count - target);
        if (error < best_error)
            best_error = error, best_edge = edge;
        edge *= sqrt((double)layout->face_count / target);
    }
    return ring_layout_fill(s, table, best_edge, capacity, layout);
}

/*
 * Places ring `index`'s vertices at the ring fractions `keys` (closed rings:
 * (j + shift) / segments with alternate rings shifted by half a step; arcs:
 * j / segments). With `arc_length` the fractions are of arc length, found in
 * a table of `samples` chords (scratch: samples + 1 doubles).
 */
static void ring_place(const surface *s, double v, int32_t segments, int32_t index, double *keys, double *positions,
                       double *scratch, int32_t samples)
{
    int32_t count = ring_vertex_count(s, segments);
    double shift = s->closed && (index & 1) ? 0.5 : 0.0;
    for (int32_t j = 0; j < count; ++j)
        keys[j] = segments == 0 ? 0.0 : (j + shift) / segments;
    if (!s->arc_length || segments == 0) {
        for (int32_t j = 0; j < count; ++j)
            s->eval(s, v, keys[j], positions + 3 * j);
        return;
    }
    double previous[3], point[3];
    scratch[0] = 0.0;
    s->eval(s, v, 0.0, previous);
    for (int32_t k = 1; k <= samples; ++k) {
        s->eval(s, v, (double)k / samples, point);
        scratch[k] = scratch[k - 1] + distance3(previous, point);
        memcpy(previous, point, sizeof point);
    }
    int32_t k = 0;
    for (int32_t j = 0; j < count; ++j) {
        double length = keys[j] * scratch[samples];
        while (k < samples - 1 && scratch[k + 1] < length)
            ++k;
        double span = scratch[k + 1] - scratch[k];
        double x = span > 0.0 ? (length - scratch[k]) / span : 0.0;
        s->eval(s, v, (k + x) / samples, positions + 3 * j);
    }
}

/* Index in 0..count-1 of the key nearest `key` on the circle of circumference 1. */
static int32_t nearest_cyclic(const double *keys, int32_t count, double key)
{
    int32_t best = 0;
    double best_distance = INFINITY;
    for (int32_t j = 0; j < count; ++j) {
        double d = fabs(keys[j] - key);
        d = d < 1.0 - d ? d : 1.0 - d;
        if (d < best_distance)
            best_distance = d, best = j;
    }
    return best;
}

/*
 * One ring seen by the zipper: its keys unwrapped so that they increase from
 * the start vertex over one turn (closed rings) or along the arc.
 */
typedef struct zip_ring {
    const double *keys;
    int32_t base;      /* mesh index of vertex 0 */
    int32_t count;     /* vertices */
    int32_t start;     /* the zip begins at this vertex */
    double offset;     /* added to the keys: -1, 0 or 1 */
    int closed;
} zip_ring;

/* Mesh index of the i-th vertex from the start. */
static int32_t zip_index(const zip_ring *r, int32_t i) { return r->base + (r->start + i) % r->count; }

/* Unwrapped key of the i-th vertex from the start: one more turn after wrapping past vertex 0. */
static double zip_key(const zip_ring *r, int32_t i)
{
    int32_t j = r->start + i;
    return r->keys[j % r->count] + r->offset + (r->closed && j >= r->count ? 1.0 : 0.0);
}

/*
 * Zips ring A (upper) to ring B (lower): A's and B's edges taken in the order
 * of their midpoints' keys, an A edge (a_i, a_i+1) making face
 * (a_i, b_j, a_i+1), a B edge making (b_j, b_j+1, a_i). Closed rings start at
 * a_0 and the B vertex nearest it, so the merge covers one turn exactly.
 * Writes segments_a + segments_b faces at `face`; returns the end.
 */
static int32_t *ring_zip(const surface *s, const double *keys_a, int32_t base_a, int32_t segments_a,
                         const double *keys_b, int32_t base_b, int32_t segments_b, int32_t *face)
{
    zip_ring a = {keys_a, base_a, ring_vertex_count(s, segments_a), 0, 0.0, s->closed};
    zip_ring b = {keys_b, base_b, ring_vertex_count(s, segments_b), 0, 0.0, s->closed};
    if (s->closed) {
        b.start = nearest_cyclic(keys_b, b.count, keys_a[0]);
        double gap = keys_b[b.start] - keys_a[0];
        b.offset = gap > 0.5 ? -1.0 : gap < -0.5 ? 1.0 : 0.0;
    }
    int32_t i = 0, j = 0;
    while (i < segments_a || j < segments_b) {
        int take_a = j == segments_b ||
                     (i < segments_a && zip_key(&a, i) + zip_key(&a, i + 1) <= zip_key(&b, j) + zip_key(&b, j + 1));
        if (take_a) {
            face[0] = zip_index(&a, i), face[1] = zip_index(&b, j), face[2] = zip_index(&a, i + 1);
            ++i;
        } else {
            face[0] = zip_index(&b, j), face[1] = zip_index(&b, j + 1), face[2] = zip_index(&a, i);
            ++j;
        }
        face += 3;
    }
    return face;
}

static pz_status ring_build(const surface *s, double target, pz_mesh **out, pz_ctx *ctx)
{
    ring_table *table = malloc(sizeof *table);
    /* rings ~ sqrt(target) for any sane aspect; 4 sqrt + 16 leaves room */
    int32_t capacity = (int32_t)(4.0 * sqrt(target)) + 16;
    ring_layout layout = {0};
    layout.v = malloc((size_t)capacity * sizeof(double));
    layout.segments = malloc((size_t)capacity * sizeof(int32_t));
    double *keys = NULL, *scratch = NULL;
    pz_status status = PZ_OK;
    if (!table || !layout.v || !layout.segments) {
        status = pz_error(ctx, PZ_ERR_NOMEM, "generate: out of memory");
        goto done;
    }
    ring_table_fill(s, table);
    if (!ring_layout_solve(s, table, target, capacity, &layout) || layout.face_count > INT32_MAX / 3 ||
        layout.vertex_count > INT32_MAX / 3) {
        status = pz_error(ctx, PZ_ERR_INTERNAL, "generate: cannot lay out %.0f faces", target);
        goto done;
    }
    status = pz_mesh_create((int32_t)layout.vertex_count, (int32_t)layout.face_count, out, ctx);
    if (status)
        goto done;
    int32_t widest = 1;
    for (int32_t i = 0; i < layout.ring_count; ++i)
        if (layout.segments[i] > widest)
            widest = layout.segments[i];
    int32_t samples = 4 * widest + 64;  /* chords per ring for the arc-length table */
    keys = malloc(2 * ((size_t)widest + 2) * sizeof(double));
    scratch = malloc(((size_t)samples + 1) * sizeof(double));
    if (!keys || !scratch) {
        pz_mesh_free(out);
        status = pz_error(ctx, PZ_ERR_NOMEM, "generate: out of memory");
        goto done;
    }
    double *keys_above = keys, *keys_below = keys + widest + 2;
    int32_t base = 0, *face = (*out)->faces;
    for (int32_t i = 0; i < layout.ring_count; ++i) {
        ring_place(s, layout.v[i], layout.segments[i], i, keys_below, (*out)->positions + 3 * (size_t)base, scratch,
                   samples);
        int32_t count = ring_vertex_count(s, layout.segments[i]);
        if (i > 0) {
            int32_t above = base - ring_vertex_count(s, layout.segments[i - 1]);
            face = ring_zip(s, keys_above, above, layout.segments[i - 1], keys_below, base, layout.segments[i], face);
        }
        double *swap = keys_above;
        keys_above = keys_below, keys_below = swap;
        base += count;
    }
done:
    free(table);
    free(layout.v);
    free(layout.segments);
    free(keys);
    free(scratch);
    return status;
}

/* ------------------------------------------------------------------------ */
/* Poses                                                                     */
/* ------------------------------------------------------------------------ */

/* The vertical axis poses turn about, and the sizes that bound their strain. */
typedef struct pose_frame {
    double center_x, center_y;  /* bounding-box centre */
    double bottom, height;      /* z range */
    double reach_y;             /* max |y - centre_y|: bending strain is reach_y * curvature */
    double reach;               /* max horizontal distance from the axis */
} pose_frame;

static const double pose_max_strain = 0.12;  /* bend: stretch of the farthest fibre */
static const double pose_max_shear = 0.3;    /* twist: radius * twist per height */

static pose_frame pose_frame_of(const pz_mesh *mesh)
{
    double lo[3], hi[3];
    pz_mesh_bbox(mesh, lo, hi);
    pose_frame frame = {0.5 * (lo[0] + hi[0]), 0.5 * (lo[1] + hi[1]), lo[2], hi[2] - lo[2], 0.0, 0.0};
    if (!(frame.height > 1e-9))
        frame.height = 1e-9;
    for (int32_t v = 0; v < mesh->vertex_count; ++v) {
        double dx = mesh->positions[3 * v] - frame.center_x, dy = mesh->positions[3 * v + 1] - frame.center_y;
        if (fabs(dy) > frame.reach_y) frame.reach_y = fabs(dy);
        if (hypot(dx, dy) > frame.reach) frame.reach = hypot(dx, dy);
    }
    return frame;
}

/*
 * Bend: the vertical axis becomes an arc of curvature k leaning forward (-y),
 * turning by `degrees` at the top: (y, h) -> centre (-1/k, 0) + (1/k + y)
 * (cos kh, sin kh). An isometry on the axis; fibres at y are stretched by
 * 1 + k y, so k is capped by pose_max_strain / reach_y.
 */
static void pose_bend(const pose_frame *f, double degrees, const double *rest, int32_t count, double *out)
{
    double curvature = degrees * GEN_PI / 180.0 / f->height;
    if (f->reach_y > 0.0 && curvature * f->reach_y > pose_max_strain)
        curvature = pose_max_strain / f->reach_y;
    double radius = 1.0 / curvature;
    for (int32_t v = 0; v < count; ++v) {
        const double *p = rest + 3 * v;
        double y = p[1] - f->center_y, angle = curvature * (p[2] - f->bottom);
        out[3 * v] = p[0];
        out[3 * v + 1] = f->center_y - radius + (radius + y) * cos(angle);
        out[3 * v + 2] = f->bottom + (radius + y) * sin(angle);
    }
}

/* Twist: rotation about the axis growing linearly with height to `degrees` at the top. */
static void pose_twist(const pose_frame *f, double degrees, const double *rest, int32_t count, double *out)
{
    double top = degrees * GEN_PI / 180.0;
    if (f->reach > 0.0 && top * f->reach / f->height > pose_max_shear)
        top = pose_max_shear * f->height / f->reach;
    for (int32_t v = 0; v < count; ++v) {
        const double *p = rest + 3 * v;
        double angle = top * (p[2] - f->bottom) / f->height, c = cos(angle), s = sin(angle);
        double x = p[0] - f->center_x, y = p[1] - f->center_y;
        out[3 * v] = f->center_x + c * x - s * y;
        out[3 * v + 1] = f->center_y + s * x + c * y;
        out[3 * v + 2] = p[2];
    }
}

/* Breathing: horizontal scaling about the axis, by `fraction` at mid-height and half of it at the ends. */
static void pose_breathe(const pose_frame *f, double fraction, const double *rest, int32_t count, double *out)
{
    for (int32_t v = 0; v < count; ++v) {
        const double *p = rest + 3 * v;
        double scale = 1.0 + fraction * (0.5 + 0.5 * sin(GEN_PI * (p[2] - f->bottom) / f->height));
        out[3 * v] = f->center_x + scale * (p[0] - f->center_x);
        out[3 * v + 1] = f->center_y + scale * (p[1] - f->center_y);
        out[3 * v + 2] = p[2];
    }
}

static pz_status add_poses(pz_mesh *mesh, int32_t pose_count, pz_ctx *ctx)
{
    if (pose_count == 0)
        return PZ_OK;
    size_t pose_size = (size_t)mesh->vertex_count * 3;
    mesh->poses = malloc((size_t)pose_count * pose_size * sizeof(double) + 1);
    if (!mesh->poses)
        return pz_error(ctx, PZ_ERR_NOMEM, "generate: out of memory for %d poses", (int)pose_count);
    mesh->pose_count = pose_count;
    pose_frame frame = pose_frame_of(mesh);
    for (int32_t p = 0; p < pose_count; ++p) {
        int cycle = p / 3;
        double amplitude = 1.0 + 0.5 * (cycle < 2 ? cycle : 2);  /* 1, 1.5, then 2 */
        double *out = mesh->poses + (size_t)p * pose_size;
        if (p % 3 == 0)
            pose_bend(&frame, 20.0 * amplitude, mesh->positions, mesh->vertex_count, out);
        else if (p % 3 == 1)
            pose_twist(&frame, 25.0 * amplitude, mesh->positions, mesh->vertex_count, out);
        else
            pose_breathe(&frame, 0.04 * amplitude, mesh->positions, mesh->vertex_count, out);
    }
    return PZ_OK;
}

/* ------------------------------------------------------------------------ */
/* Entry point                                                               */
/* ------------------------------------------------------------------------ */

static pz_status generate_rest(pz_shape shape, double target, int open, pz_mesh **out, pz_ctx *ctx)
{
    surface s = {0};
    int32_t rows = 0, columns = 0;
    switch (shape) {
    case PZ_SHAPE_CYLINDER:
        s.eval = cylinder_eval, s.closed = 1;
        grid_resolution(target, 2.0 * GEN_PI * cylinder_radius / cylinder_height, 3, &rows, &columns);
        return grid_build(&s, rows, columns, open, out, ctx);
    case PZ_SHAPE_CONE: {
        /* Square cells: column width 2 pi r / columns = slant step r ln(q) / sin(beta) for ratio q per row. */
        double slant = hypot(cone_height, cone_bottom_radius - cone_top_radius);
        double sin_beta = (cone_bottom_radius - cone_top_radius) / slant;
        double log_ratio = log(cone_bottom_radius / cone_top_radius);
        s.eval = cone_eval, s.closed = 1;
        grid_resolution(target, 2.0 * GEN_PI * sin_beta / log_ratio, 3, &rows, &columns);
        return grid_build(&s, rows, columns, open, out, ctx);
    }
    case PZ_SHAPE_SADDLE:
        s.eval = saddle_eval;
        grid_resolution(target, 1.0, 1, &rows, &columns);
        return grid_build(&s, columns, columns, 0, out, ctx);
    case PZ_SHAPE_HEMISPHERE:
        s.eval = hemisphere_eval, s.closed = 1, s.pole_first = 1;
        return ring_build(&s, target, out, ctx);
    case PZ_SHAPE_QUARTER_SPHERE:
        s.eval = quarter_sphere_eval, s.pole_first = 1;
        return ring_build(&s, target, out, ctx);
    case PZ_SHAPE_BODICE:
        s.eval = bodice_eval, s.closed = 1, s.arc_length = 1;
        return ring_build(&s, target, out, ctx);
    case PZ_SHAPE_SKIRT:
        s.eval = skirt_eval, s.closed = 1, s.arc_length = 1;
        return ring_build(&s, target, out, ctx);
    case PZ_SHAPE_SLEEVE: {
        centerline spine = {0};
        pz_status status = centerline_build(&spine, ctx);
        s.eval = sleeve_eval, s.closed = 1, s.spine = &spine;
        if (status == PZ_OK)
            status = ring_build(&s, target, out, ctx);
        centerline_free(&spine);
        return status;
    }
    case PZ_SHAPE_UNKNOWN:
        break;
    }
    return pz_error(ctx, PZ_ERR_USAGE, "generate: unknown shape %d", (int)shape);
}

pz_status pz_generate(pz_shape shape, const pz_generate_options *options, pz_mesh **out, pz_ctx *ctx)
{
    *out = NULL;
    pz_generate_options defaults = {0};
    if (!options)
        options = &defaults;
    const char *name = pz_shape_name(shape);
    if (strcmp(name, "unknown") == 0)  /* PZ_SHAPE_UNKNOWN or out of the enum */
        return pz_error(ctx, PZ_ERR_USAGE, "generate: unknown shape %d", (int)shape);
    int32_t target = options->target_faces == 0 ? GEN_DEFAULT_FACES : options->target_faces;
    if (target < 1 || target > GEN_MAX_FACES)
        return pz_error(ctx, PZ_ERR_USAGE, "%s: target face count %d is outside 1 .. %d", name,
                        (int)options->target_faces, GEN_MAX_FACES);
    if (options->pose_count < 0 || options->pose_count > GEN_MAX_POSES)
        return pz_error(ctx, PZ_ERR_USAGE, "%s: pose count %d is outside 0 .. %d", name, (int)options->pose_count,
                        GEN_MAX_POSES);
    if (options->open && shape != PZ_SHAPE_CYLINDER && shape != PZ_SHAPE_CONE)
        return pz_error(ctx, PZ_ERR_USAGE, "%s: `open` applies to the cylinder and the cone only", name);
    pz_mesh *mesh = NULL;
    pz_status status = generate_rest(shape, (double)target, options->open, &mesh, ctx);
    if (status == PZ_OK)
        status = add_poses(mesh, options->pose_count, ctx);
    if (status != PZ_OK) {
        pz_mesh_free(&mesh);
        return status;
    }
    *out = mesh;
    return PZ_OK;
}

/*
 * tests/param/test_metrics.c -- every metric against a value worked out by
 * hand: strains and shear of a stretched and of a sheared triangle; the
 * orthotropic energy (mccartney2005 Eqs. 8-9), ARAP, E_len, E_ang, E_S and
 * E_C of one known triangle; flipped triangles; boundary self-intersections
 * (a bow-tie found, a convex fan not, the grid agreeing with a
 * brute-force count on random polygons, a pulled 20,001-edge circle with
 * exactly its 2 crossing pairs and their 5 vertices marked, touching and
 * collinear overlap counted); seam lengths and the reflection
 * residual of an exactly mirrored and of a stretched pair; dart leg lengths
 * and symmetry; measuring against an extra pose; a pose that does not exist.
 *
 * SPDX-License-Identifier: GPL-3.0-or-later
 */
#include "param/param.h"
#include "test_meshes.h"

#include <math.h>
#include <stdlib.h>
#include <string.h>

static pz_ctx ctx;

static int near(double a, double b, double tolerance) { return fabs(a - b) <= tolerance; }

/* p3 = J p2 with J's columns dX/du = du, dX/dv = dv (3D points of the 2D triangle p2). */
static void map_triangle(const double p2[3][2], const double du[3], const double dv[3], double p3[3][3])
{
    for (int i = 0; i < 3; ++i)
        for (int k = 0; k < 3; ++k)
            p3[i][k] = du[k] * p2[i][0] + dv[k] * p2[i][1];
}

static void test_triangle_strain(void)
{
    const double p2[3][2] = {{0, 0}, {10, 0}, {0, 10}};
    double p3[3][3], warp, weft, shear;
    /* 10 % longer along v (the warp), laid in the xz plane. */
    double du[3] = {1, 0, 0}, dv[3] = {0, 0, 1.1};
    map_triangle(p2, du, dv, p3);
    pz_metrics_triangle_strain((const double(*)[3])p3, p2, &warp, &weft, &shear);
    CHECK(near(warp, 0.1, 1e-12) && near(weft, 0, 1e-12) && near(shear, 0, 1e-9), "stretched along v: %g %g %g", warp,
          weft, shear);
    /* 20 % shorter along u (the weft). */
    double du2[3] = {0, 0.8, 0}, dv2[3] = {0, 0, 1};
    map_triangle(p2, du2, dv2, p3);
    pz_metrics_triangle_strain((const double(*)[3])p3, p2, &warp, &weft, &shear);
    CHECK(near(warp, 0, 1e-12) && near(weft, -0.2, 1e-12) && near(shear, 0, 1e-9), "compressed along u: %g %g %g",
          warp, weft, shear);
    /* The warp thread leans 10 degrees towards the weft: the angle closes to 80 degrees. */
    double a = 10 * TEST_PI / 180, du3[3] = {1, 0, 0}, dv3[3] = {sin(a), 0, cos(a)};
    map_triangle(p2, du3, dv3, p3);
    pz_metrics_triangle_strain((const double(*)[3])p3, p2, &warp, &weft, &shear);
    CHECK(near(warp, 0, 1e-12) && near(weft, 0, 1e-12) && near(shear, -10, 1e-9), "sheared: %g %g %g", warp, weft,
          shear);
    /* The same triangle described in another order and rotated in the plane gives the same figures. */
    const double q2[3][2] = {{0, 10}, {0, 0}, {10, 0}};
    double q3[3][3];
    map_triangle(q2, du3, dv3, q3);
    pz_metrics_triangle_strain((const double(*)[3])q3, q2, &warp, &weft, &shear);
    CHECK(near(shear, -10, 1e-9), "corner order does not matter: %g", shear);
}

/* A one-panel pattern of a single triangle (p3 its 3D corners). */
static pz_pattern *triangle_pattern(const double p3[3][3])
{
    static const int32_t face[3] = {0, 1, 2};
    pz_mesh *mesh = test_mesh_from(3, &p3[0][0], 1, face, &ctx);
    int32_t panel = 0;
    pz_pattern *pattern = NULL;
    REQUIRE_OK(pz_pattern_build(mesh, &panel, NULL, NULL, "triangle", &pattern, &ctx), ctx);
    pz_mesh_free(&mesh);
    return pattern;
}

static void test_panel_figures(void)
{
    /* Stretched 5 % along u and 10 % along v, threads kept square. */
    const double p2[3][2] = {{0, 0}, {10, 0}, {0, 10}};
    double p3[3][3], du[3] = {1.05, 0, 0}, dv[3] = {0, 1.1, 0};
    map_triangle(p2, du, dv, p3);
    pz_pattern *pattern = triangle_pattern((const double(*)[3])p3);
    REQUIRE(pattern->mesh->vertex_count == 3, "3 vertices");
    pz_metrics *m = NULL;
    REQUIRE_OK(pz_metrics_compute(pattern, &p2[0][0], 0, NULL, &m, &ctx), ctx);
    const pz_panel_metrics *pm = &m->panels[0];
    double area_2d = 50, area_3d = 50 * 1.05 * 1.1;
    CHECK(near(pm->area_2d_mm2, area_2d, 1e-9) && near(pm->area_3d_mm2, area_3d, 1e-9), "areas %g %g", pm->area_2d_mm2,
          pm->area_3d_mm2);
    CHECK(near(pm->strain_warp.max, 0.1, 1e-12) && near(pm->strain_warp.mean, 0.1, 1e-12) &&
              near(pm->strain_warp.p95, 0.1, 1e-12),
          "warp stats");
    CHECK(near(pm->strain_weft.max, 0.05, 1e-12), "weft max %g", pm->strain_weft.max);
    /* Eq. 8: 0.5 A (K_su (S_u - 1)^2 + K_sv (S_v - 1)^2), defaults K_su 0.946 (u), K_sv 0.548 (v). */
    double expected = 0.5 * area_2d * (0.946 * 0.05 * 0.05 + 0.548 * 0.1 * 0.1);
    CHECK(near(pm->orthotropic_energy, expected, 1e-12), "orthotropic energy %g, expected %g", pm->orthotropic_energy,
          expected);
    CHECK(near(pm->arap_energy, area_2d * (0.05 * 0.05 + 0.1 * 0.1), 1e-12), "ARAP %g", pm->arap_energy);
    /* Edges: 3D 10.5, 11, hypot(10.5, 11); 2D 10, 10, hypot(10, 10). All three are boundary (wires). */
    double l3[3] = {10.5, 11, hypot(10.5, 11)}, l2[3] = {10, 10, hypot(10, 10)}, e_len = 0, diff = 0, sum = 0;
    for (int i = 0; i < 3; ++i) {
        e_len += fabs(l3[i] - l2[i]) / l3[i] / 3;
        diff += fabs(l3[i] - l2[i]);
        sum += l3[i];
    }
    CHECK(near(pm->e_len, e_len, 1e-12), "E_len %g expected %g", pm->e_len, e_len);
    CHECK(near(pm->e_shape, diff / sum, 1e-12), "E_C %g expected %g", pm->e_shape, diff / sum);
    CHECK(near(pm->e_area, (area_3d - area_2d) / area_3d, 1e-12), "E_S %g", pm->e_area);
    /* Angles: 3D 90, atan(11/10.5), atan(10.5/11); 2D 90, 45, 45. */
    double b3 = atan2(11, 10.5), c3 = atan2(10.5, 11), q = TEST_PI / 4;
    double e_ang = (fabs(b3 - q) / b3 + fabs(c3 - q) / c3) / 3;
    CHECK(near(pm->e_ang, e_ang, 1e-12), "E_ang %g expected %g", pm->e_ang, e_ang);
    CHECK(pm->flipped_triangles == 0 && pm->boundary_self_intersections == 0 && m->injective, "injective");
    CHECK(near(m->max_abs_strain, 0.1, 1e-12), "max |strain| %g", m->max_abs_strain);
    pz_metrics_free(&m);

    /* Own fabric constants and a shear: Eq. 9 adds 0.5 A K_r phi^2. */
    double a = 0.2, du2[3] = {1, 0, 0}, dv2[3] = {sin(a), cos(a), 0};
    map_triangle(p2, du2, dv2, p3);
    pz_pattern_free(&pattern);
    pattern = triangle_pattern((const double(*)[3])p3);
    pz_fabric fabric = {2.0, 3.0, 0.5};
    REQUIRE_OK(pz_metrics_compute(pattern, &p2[0][0], 0, &fabric, &m, &ctx), ctx);
    CHECK(near(m->panels[0].orthotropic_energy, 0.5 * area_2d * 0.5 * a * a, 1e-12), "shear energy %g",
          m->panels[0].orthotropic_energy);
    CHECK(near(m->panels[0].shear_deg.max, a * 180 / TEST_PI, 1e-9) && m->panels[0].shear_deg.mean < 0,
          "shear stats: max %g mean %g", m->panels[0].shear_deg.max, m->panels[0].shear_deg.mean);
    pz_metrics_free(&m);

    /* A mirrored pattern is not flipped (the panel's majority orientation); strains are unchanged. */
    const double mirrored[3][2] = {{0, 0}, {-10, 0}, {0, 10}};
    REQUIRE_OK(pz_metrics_compute(pattern, &mirrored[0][0], 0, NULL, &m, &ctx), ctx);
    CHECK(m->panels[0].flipped_triangles == 0 && m->injective, "mirrored panel is not flipped");
    pz_metrics_free(&m);
    pz_pattern_free(&pattern);
}

/* A fan: centre vertex 0 and n rim vertices on the unit circle (z = 0), one panel. */
static pz_pattern *fan_pattern(int n)
{
    double *positions = malloc((size_t)(n + 1) * 3 * sizeof(double));
    int32_t *faces = malloc((size_t)n * 3 * sizeof(int32_t));
    REQUIRE(positions && faces, "out of memory");
    positions[0] = positions[1] = positions[2] = 0;
    for (int i = 0; i < n; ++i) {
        positions[3 * (i + 1)] = 100 * cos(2 * TEST_PI * i / n);
        positions[3 * (i + 1) + 1] = 100 * sin(2 * TEST_PI * i / n);
        positions[3 * (i + 1) + 2] = 0;
        faces[3 * i] = 0;
        faces[3 * i + 1] = 1 + i;
        faces[3 * i + 2] = 1 + (i + 1) % n;
    }
    pz_mesh *mesh = test_mesh_from(n + 1, positions, n, faces, &ctx);
    int32_t *panels = calloc((size_t)n, sizeof(int32_t));
    REQUIRE(panels, "out of memory");
    pz_pattern *pattern = NULL;
    REQUIRE_OK(pz_pattern_build(mesh, panels, NULL, NULL, "fan", &pattern, &ctx), ctx);
    free(panels);
    free(positions);
    free(faces);
    pz_mesh_free(&mesh);
    return pattern;
}

static int brute_force_crossings(const double *uv, const int32_t *rim, int n)
{
    int count = 0;
    for (int i = 0; i < n; ++i)
        for (int j = i + 1; j < n; ++j) {
            int a = rim[i], b = rim[(i + 1) % n], c = rim[j], d = rim[(j + 1) % n];
            if (a == c || a == d || b == c || b == d)
                continue;
            const double *p = uv + 2 * a, *q = uv + 2 * b, *r = uv + 2 * c, *s = uv + 2 * d;
            double d1 = (q[0] - p[0]) * (r[1] - p[1]) - (q[1] - p[1]) * (r[0] - p[0]);
            double d2 = (q[0] - p[0]) * (s[1] - p[1]) - (q[1] - p[1]) * (s[0] - p[0]);
            double d3 = (s[0] - r[0]) * (p[1] - r[1]) - (s[1] - r[1]) * (p[0] - r[0]);
            double d4 = (s[0] - r[0]) * (q[1] - r[1]) - (s[1] - r[1]) * (q[0] - r[0]);
            count += d1 * d2 < 0 && d3 * d4 < 0; /* random points: no touching cases */
        }
    return count;
}

static void test_flips_and_crossings(void)
{
    pz_pattern *pattern = fan_pattern(4);
    int32_t nv = pattern->mesh->vertex_count;
    double *uv = malloc((size_t)nv * 2 * sizeof(double));
    REQUIRE(uv, "out of memory");
    for (int32_t v = 0; v < nv; ++v) {
        uv[2 * v] = pattern->mesh->positions[3 * v];
        uv[2 * v + 1] = pattern->mesh->positions[3 * v + 1];
    }
    pz_metrics *m = NULL;
    REQUIRE_OK(pz_metrics_compute(pattern, uv, 0, NULL, &m, &ctx), ctx);
    CHECK(m->panels[0].boundary_self_intersections == 0 && m->panels[0].flipped_triangles == 0 && m->injective,
          "a convex fan: no crossing, no flip");
    CHECK(m->max_abs_strain < 1e-12, "identity: no strain (%g)", m->max_abs_strain);
    pz_metrics_free(&m);

    /* Swap rim vertices 2 and 3 (at 90 and 180 degrees): the rim becomes a bow-tie. */
    double swap[2] = {uv[4], uv[5]};
    uv[4] = uv[6];
    uv[5] = uv[7];
    uv[6] = swap[0];
    uv[7] = swap[1];
    REQUIRE_OK(pz_metrics_compute(pattern, uv, 0, NULL, &m, &ctx), ctx);
    CHECK(m->panels[0].boundary_self_intersections == 1, "bow-tie: %d crossings",
          (int)m->panels[0].boundary_self_intersections);
    CHECK(m->panels[0].flipped_triangles >= 1 && !m->injective, "bow-tie: %d flipped",
          (int)m->panels[0].flipped_triangles);
    pz_metrics_free(&m);
    free(uv);
    pz_pattern_free(&pattern);

    /* Random rims: the grid finds exactly the crossings a brute-force count finds. */
    srand(7);
    for (int trial = 0; trial < 5; ++trial) {
        int n = 40 + 20 * trial;
        pattern = fan_pattern(n);
        nv = pattern->mesh->vertex_count;
        uv = malloc((size_t)nv * 2 * sizeof(double));
        int32_t *rim = malloc((size_t)n * sizeof(int32_t));
        REQUIRE(uv && rim, "out of memory");
        for (int32_t v = 0; v < 2 * nv; ++v)
            uv[v] = (double)rand() / RAND_MAX * 100;
        for (int i = 0; i < n; ++i)
            rim[i] = 1 + i;
        REQUIRE_OK(pz_metrics_compute(pattern, uv, 0, NULL, &m, &ctx), ctx);
        int expected = brute_force_crossings(uv, rim, n);
        CHECK(m->panels[0].boundary_self_intersections == expected && expected > 0, "n %d: grid %d, brute force %d", n,
              (int)m->panels[0].boundary_self_intersections, expected);
        pz_metrics_free(&m);
        free(rim);
        free(uv);
        pz_pattern_free(&pattern);
    }
}

/*
 * pz_metrics_outline_crossings_marked on a big outline: a circle of 20,001
 * edges (the grid's common case: short edges, one per cell) with vertex 0
 * pulled across to (-150, 0). Its two edges each cross the one circle edge
 * that straddles 180 degrees (20,001 is odd: no vertex there), so 2 pairs,
 * and exactly the 5 vertices of those 3 edges are marked. Touching counts:
 * a vertex of one edge lying on another edge, and collinear overlap.
 */
static void test_outline_crossings(void)
{
    const int32_t n = 20001;
    double *uv = malloc((size_t)n * 2 * sizeof(double));
    int32_t *edges = malloc((size_t)n * 2 * sizeof(int32_t));
    uint8_t *marked = calloc((size_t)n, 1);
    REQUIRE(uv && edges && marked, "out of memory");
    for (int32_t i = 0; i < n; ++i) {
        uv[2 * i] = 100 * cos(2 * TEST_PI * i / n);
        uv[2 * i + 1] = 100 * sin(2 * TEST_PI * i / n);
        edges[2 * i] = i;
        edges[2 * i + 1] = (i + 1) % n;
    }
    CHECK(pz_metrics_outline_crossings(edges, n, uv) == 0, "a circle crosses itself");
    uv[0] = -150;
    uv[1] = 0;
    int32_t crossings = pz_metrics_outline_crossings_marked(edges, n, uv, marked);
    int32_t straddle = n / 2; /* the edge straddle -> straddle + 1 crosses 180 degrees */
    int marked_count = 0, marked_right = marked[n - 1] && marked[0] && marked[1] && marked[straddle] &&
                                          marked[straddle + 1];
    for (int32_t i = 0; i < n; ++i)
        marked_count += marked[i];
    CHECK(crossings == 2 && marked_count == 5 && marked_right, "pulled circle: %d crossings, %d marked (%s)", crossings,
          marked_count, marked_right ? "the right ones" : "not the right ones");
    free(uv);
    free(edges);
    free(marked);

    /* T-touch: the end of one segment on the middle of another; and two
     * collinear overlapping segments. Each is one meeting pair. */
    double touch[8] = {0, 0, 10, 0, 5, 0, 5, 10};
    int32_t pair[4] = {0, 1, 2, 3};
    CHECK(pz_metrics_outline_crossings(pair, 2, touch) == 1, "T-touch not counted");
    double overlap[8] = {0, 0, 10, 0, 5, 0, 15, 0};
    CHECK(pz_metrics_outline_crossings(pair, 2, overlap) == 1, "collinear overlap not counted");
    double apart[8] = {0, 0, 10, 0, 0, 1, 10, 1};
    CHECK(pz_metrics_outline_crossings(pair, 2, apart) == 0, "parallel segments counted");
}

/* Two panels of a flat 2 x 4 grid (x 0..2, y 0..4) split at x = 1, the shared column bent. */
static void test_seams(void)
{
    pz_mesh *mesh = test_grid(2, 4, TEST_GRID_FLAT, 0, &ctx);
    for (int32_t v = 0; v < mesh->vertex_count; ++v)
        if (v % 3 == 1)
            mesh->positions[3 * v] += 0.1 * sin(mesh->positions[3 * v + 1]); /* a curved seam */
    int32_t panels[16];
    for (int32_t f = 0; f < mesh->face_count; ++f)
        panels[f] = (f / 2) % 2;
    pz_pattern *pattern = NULL;
    REQUIRE_OK(pz_pattern_build(mesh, panels, NULL, NULL, "grid", &pattern, &ctx), ctx);
    REQUIRE(pattern->seam_count == 1 && pattern->seams[0].pair_count == 5, "one seam of 5 pairs: %d seams",
            (int)pattern->seam_count);
    int32_t nv = pattern->mesh->vertex_count;
    double *uv = malloc((size_t)nv * 2 * sizeof(double));
    REQUIRE(uv, "out of memory");
    /* Panel 0 as it is; panel 1 mirrored about x = 3 (a reflection of its own 3D shape). */
    for (int32_t f = 0; f < pattern->mesh->face_count; ++f)
        for (int k = 0; k < 3; ++k) {
            int32_t v = pattern->mesh->faces[3 * f + k];
            const double *p = pattern->mesh->positions + 3 * v;
            uv[2 * v] = pattern->face_panel[f] ? 6 - p[0] : p[0];
            uv[2 * v + 1] = p[1];
        }
    pz_metrics *m = NULL;
    REQUIRE_OK(pz_metrics_compute(pattern, uv, 0, NULL, &m, &ctx), ctx);
    const pz_seam_metrics *sm = &m->seams[0];
    CHECK(near(sm->length_a_mm, sm->length_3d_mm, 1e-12) && near(sm->length_b_mm, sm->length_3d_mm, 1e-12) &&
              sm->length_3d_mm > 4,
          "lengths %g %g %g", sm->length_3d_mm, sm->length_a_mm, sm->length_b_mm);
    CHECK(near(sm->reflection_residual_mm, 0, 1e-9) && near(sm->mismatch_rel, 0, 1e-12), "mirrored: residual %g",
          sm->reflection_residual_mm);
    CHECK(m->injective, "both panels injective (panel 1 mirrored as a whole)");
    pz_metrics_free(&m);

    /* Stretch panel 1 by 20 % in v: the sides differ by 20 % of the 3D length, reflection no longer fits. */
    for (int32_t f = 0; f < pattern->mesh->face_count; ++f)
        if (pattern->face_panel[f])
            for (int k = 0; k < 3; ++k) {
                int32_t v = pattern->mesh->faces[3 * f + k];
                uv[2 * v + 1] = 1.2 * pattern->mesh->positions[3 * v + 1];
            }
    REQUIRE_OK(pz_metrics_compute(pattern, uv, 0, NULL, &m, &ctx), ctx);
    sm = &m->seams[0];
    int a_is_0 = sm->panel_a == 0;
    double stretched = a_is_0 ? sm->length_b_mm : sm->length_a_mm, expected = 0;
    const int32_t *side = a_is_0 ? pattern->seams[0].side_b : pattern->seams[0].side_a;
    for (int32_t i = 0; i + 1 < 5; ++i) {
        const double *p = pattern->mesh->positions + 3 * side[i], *q = pattern->mesh->positions + 3 * side[i + 1];
        expected += hypot(p[0] - q[0], 1.2 * (p[1] - q[1]));
    }
    double mismatch = (expected - sm->length_3d_mm) / sm->length_3d_mm;
    CHECK(near(stretched, expected, 1e-9) && near(sm->mismatch_rel, mismatch, 1e-9) && mismatch > 0.19,
          "stretched side: %g vs %g, mismatch %g", stretched, expected, sm->mismatch_rel);
    CHECK(sm->reflection_residual_mm > 0.1 && near(m->max_seam_mismatch_rel, mismatch, 1e-9), "residual %g",
          sm->reflection_residual_mm);
    pz_metrics_free(&m);
    free(uv);
    pz_pattern_free(&pattern);
    pz_mesh_free(&mesh);
}

static void test_darts(void)
{
    pz_pattern *pattern = fan_pattern(8);
    int32_t nv = pattern->mesh->vertex_count;
    double *uv = calloc((size_t)nv * 2, sizeof(double));
    pz_dart *dart = calloc(1, sizeof *dart);
    REQUIRE(uv && dart, "out of memory");
    /* Tip at rim vertex 1; legs (2, 3) and (8, 7): mirror images about the line through the tip at 30 degrees. */
    dart->panel = 0;
    dart->tip = 1;
    dart->pair_count = 2;
    dart->leg_a = malloc(2 * sizeof(int32_t));
    dart->leg_b = malloc(2 * sizeof(int32_t));
    REQUIRE(dart->leg_a && dart->leg_b, "out of memory");
    dart->leg_a[0] = 2, dart->leg_a[1] = 3;
    dart->leg_b[0] = 8, dart->leg_b[1] = 7;
    pattern->darts = dart;
    pattern->dart_count = 1;
    double axis = 30 * TEST_PI / 180, tip[2] = {5, 7};
    const double local[2][2] = {{2, 1}, {5, 3}}; /* leg a in axis coordinates; leg b has the other sign */
    uv[2] = tip[0];
    uv[3] = tip[1];
    for (int i = 0; i < 2; ++i)
        for (int side = 0; side < 2; ++side) {
            double x = local[i][0], y = side ? -local[i][1] : local[i][1];
            int32_t v = side ? dart->leg_b[i] : dart->leg_a[i];
            uv[2 * v] = tip[0] + x * cos(axis) - y * sin(axis);
            uv[2 * v + 1] = tip[1] + x * sin(axis) + y * cos(axis);
        }
    pz_metrics *m = NULL;
    REQUIRE_OK(pz_metrics_compute(pattern, uv, 0, NULL, &m, &ctx), ctx);
    double leg = hypot(2, 1) + hypot(3, 2);
    const pz_dart_metrics *dm = &m->darts[0];
    CHECK(near(dm->leg_a_mm, leg, 1e-9) && near(dm->leg_b_mm, leg, 1e-9), "legs %g %g, expected %g", dm->leg_a_mm,
          dm->leg_b_mm, leg);
    CHECK(near(dm->symmetry_residual_mm, 0, 1e-9) && near(dm->mismatch_rel, 0, 1e-12), "symmetric: residual %g",
          dm->symmetry_residual_mm);
    pz_metrics_free(&m);
    /* Move one leg b vertex by 1 mm along the axis: no mirror fits any more. */
    uv[2 * 7] += cos(axis);
    uv[2 * 7 + 1] += sin(axis);
    REQUIRE_OK(pz_metrics_compute(pattern, uv, 0, NULL, &m, &ctx), ctx);
    CHECK(m->darts[0].symmetry_residual_mm > 0.1 && m->darts[0].symmetry_residual_mm < 1, "residual %g",
          m->darts[0].symmetry_residual_mm);
    pz_metrics_free(&m);
    free(uv);
    pz_pattern_free(&pattern);
}

static void test_poses(void)
{
    const double p2[3][2] = {{0, 0}, {10, 0}, {0, 10}};
    double p3[3][3], du[3] = {1, 0, 0}, dv[3] = {0, 1, 0};
    map_triangle(p2, du, dv, p3);
    static const int32_t face[3] = {0, 1, 2};
    pz_mesh *mesh = test_mesh_from(3, &p3[0][0], 1, face, &ctx);
    double pose[9];
    for (int i = 0; i < 9; ++i)
        pose[i] = (&p3[0][0])[i] * (i % 3 == 1 ? 1.3 : 1.0); /* 30 % longer along v */
    REQUIRE_OK(pz_mesh_add_pose(mesh, pose, &ctx), ctx);
    int32_t panel = 0;
    pz_pattern *pattern = NULL;
    REQUIRE_OK(pz_pattern_build(mesh, &panel, NULL, NULL, "posed", &pattern, &ctx), ctx);
    pz_metrics *m = NULL;
    REQUIRE_OK(pz_metrics_compute(pattern, &p2[0][0], 1, NULL, &m, &ctx), ctx);
    CHECK(near(m->strain_warp[0], 0.3, 1e-12) && near(m->strain_weft[0], 0, 1e-12), "pose 1: warp %g",
          m->strain_warp[0]);
    pz_metrics_free(&m);
    m = (pz_metrics *)&ctx;
    CHECK(pz_metrics_compute(pattern, &p2[0][0], 2, NULL, &m, &ctx) == PZ_ERR_USAGE && m == NULL,
          "pose 2 does not exist");
    CHECK(strstr(ctx.error, "pose 2") != NULL, "message names the pose: %s", ctx.error);
    pz_pattern_free(&pattern);
    pz_mesh_free(&mesh);
}

int main(void)
{
    pz_ctx_init(&ctx);
    ctx.quiet = 1;
    test_triangle_strain();
    test_panel_figures();
    test_flips_and_crossings();
    test_outline_crossings();
    test_seams();
    test_darts();
    test_poses();
    return test_finish();
}

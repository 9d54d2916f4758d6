/*
 * tests/param/test_textile.c -- the textile parameterization (pz_param_textile)
 * on generated shapes (the shared real garments: test_textile_garments.c):
 *  - open cylinder and open cone (developable, one panel): every 2D edge
 *    within 1e-4 relative of its 3D length, no flipped face;
 *  - a flat grid with in-plane noise comes back as itself up to a rigid
 *    motion (Procrustes residual below 1e-6 of its size);
 *  - a hemisphere: no flipped face; the strain is printed; asked for 20
 *    steps with no tolerance stop, it takes all 20 with at most 2
 *    backtracked (the step's slope is Eq. 10's and it keeps the grain:
 *    docs/param.md, "Consistent stretch steps"; the paper's step stalled
 *    after 5, 3 of them backtracked);
 *  - grain: the 3D image of +v (the warp) follows the projected grain axis:
 *    area-weighted mean angle below 1 degree (absolute on the cylinder with
 *    the default +z grain, signed on the saddle with a +x grain, absolute
 *    with a given (1, 1, 0) grain on a mildly curved saddle and on a
 *    cylinder lying along that axis);
 *  - a closed cylinder (not a disk) and two panels sharing vertices are
 *    refused with PZ_ERR_DATA;
 *  - two panels of a rolled grid (10,000 faces: the parallel paths) joined
 *    by a seam: isometric, seam sides equal and mirror images;
 *  - a flat half annulus sewn along its semicircle to a straight strip 5 %
 *    shorter: the seam is found length-only, its sides end within a quarter
 *    of the seam-free mismatch, and the pieces are distorted far less than
 *    when the reflection is forced.
 *  - a 110K-face hemisphere on two threads (the iterations threaded, its
 *    systems ordered as its LSCM start was) gives one thread's uv
 *    byte for byte (both take one thread when the load leaves no core free:
 *    printed).
 * Patterns are built by hand (one panel = all faces) so the test does not
 * depend on pz_pattern_build; the fixtures are in textile_fixtures.h.
 *
 * SPDX-License-Identifier: GPL-3.0-or-later
 */
#define _DEFAULT_SOURCE /* getloadavg */
#include "textile_fixtures.h"

/* ------------------------------------------------------------------ helpers */

static pz_mesh *generate(pz_shape shape, int32_t faces, int open)
{
    pz_generate_options options = {.target_faces = faces, .open = open};
    pz_mesh *mesh = NULL;
    REQUIRE_OK(pz_generate(shape, &options, &mesh, &ctx), ctx);
    return mesh;
}

/* Worst relative edge-length error, positions = a pose (or the rest). */
static double worst_edge_error(const pz_mesh *mesh, const double *positions, const double *uv)
{
    double worst = 0;
    for (int32_t f = 0; f < mesh->face_count; ++f)
        for (int k = 0; k < 3; ++k) {
            int32_t a = mesh->faces[3 * f + k], b = mesh->faces[3 * f + (k + 1) % 3];
            const double *pa = positions + 3 * a, *pb = positions + 3 * b;
            double l3 = sqrt((pa[0] - pb[0]) * (pa[0] - pb[0]) + (pa[1] - pb[1]) * (pa[1] - pb[1]) +
                             (pa[2] - pb[2]) * (pa[2] - pb[2]));
            double l2 = hypot(uv[2 * a] - uv[2 * b], uv[2 * a + 1] - uv[2 * b + 1]);
            worst = fmax(worst, fabs(l2 - l3) / l3);
        }
    return worst;
}

/* Area-and-projection-weighted mean angle (degrees) between the warp J e_v
 * and the grain projected onto each triangle; signed (about the normal) or
 * absolute. */
static double mean_grain_angle(const pz_mesh *mesh, const double *uv, const double grain[3], int absolute)
{
    double sum = 0, weight_sum = 0;
    for (int32_t f = 0; f < mesh->face_count; ++f) {
        const int32_t *face = mesh->faces + 3 * f;
        const double *a = mesh->positions + 3 * face[0], *b = mesh->positions + 3 * face[1],
                     *c = mesh->positions + 3 * face[2];
        double e1[3] = {b[0] - a[0], b[1] - a[1], b[2] - a[2]}, e2[3] = {c[0] - a[0], c[1] - a[1], c[2] - a[2]};
        double n[3] = {e1[1] * e2[2] - e1[2] * e2[1], e1[2] * e2[0] - e1[0] * e2[2], e1[0] * e2[1] - e1[1] * e2[0]};
        double twice_area = sqrt(n[0] * n[0] + n[1] * n[1] + n[2] * n[2]);
        for (int d = 0; d < 3; ++d)
            n[d] /= twice_area;
        double gn = grain[0] * n[0] + grain[1] * n[1] + grain[2] * n[2];
        double g[3] = {grain[0] - gn * n[0], grain[1] - gn * n[1], grain[2] - gn * n[2]};
        double projected = sqrt(g[0] * g[0] + g[1] * g[1] + g[2] * g[2]);
        if (projected < 1e-9)
            continue;
        double ju[3], jv[3];
        tangents(mesh->positions, face, uv, ju, jv);
        double cross[3] = {jv[1] * g[2] - jv[2] * g[1], jv[2] * g[0] - jv[0] * g[2], jv[0] * g[1] - jv[1] * g[0]};
        double angle = atan2(cross[0] * n[0] + cross[1] * n[1] + cross[2] * n[2],
                             jv[0] * g[0] + jv[1] * g[1] + jv[2] * g[2]) * 180 / TEST_PI;
        double weight = 0.5 * twice_area * projected;
        sum += weight * (absolute ? fabs(angle) : angle);
        weight_sum += weight;
    }
    return sum / weight_sum;
}

/* ------------------------------------------------------------------ tests */

static void test_developable(pz_shape shape)
{
    pz_pattern *pattern = pattern_of(generate(shape, 3000, 1), NULL, 1);
    pz_textile_result result;
    double *uv = flatten(pattern, NULL, &result);
    double error = worst_edge_error(pattern->mesh, pattern->mesh->positions, uv);
    int flipped = count_flipped(pattern->mesh, uv);
    printf("%s: textile worst edge error %.3g, %d iterations, energy %.3g -> %.3g\n", pz_shape_name(shape), error,
           result.iterations_run, result.initial_energy, result.final_energy);
    CHECK(error < 1e-4, "%s: worst edge error %g", pz_shape_name(shape), error);
    CHECK(flipped == 0, "%s: %d flipped faces", pz_shape_name(shape), flipped);
    CHECK(result.final_energy <= result.initial_energy + 1e-9, "energy grew: %g -> %g", result.initial_energy,
          result.final_energy);
    if (shape == PZ_SHAPE_CYLINDER) {
        double up[3] = {0, 0, 1};
        double angle = mean_grain_angle(pattern->mesh, uv, up, 1);
        printf("cylinder: mean |angle| warp to grain %.3g degrees\n", angle);
        CHECK(angle < 1, "cylinder: warp is %g degrees off the grain", angle);
    }
    free(uv);
    pattern_release(pattern);
}

/* Deterministic noise in [-1, 1]. */
static double noise(uint32_t *state)
{
    *state = *state * 1664525u + 1013904223u;
    return (*state >> 8) / (double)(1u << 24) * 2 - 1;
}

static void test_planar(void)
{
    const int columns = 30, rows = 20;
    pz_mesh *mesh = test_grid(columns, rows, TEST_GRID_FLAT, 0, &ctx);
    uint32_t seed = 12345;
    for (int32_t v = 0; v < mesh->vertex_count; ++v) {
        mesh->positions[3 * v] = 10 * mesh->positions[3 * v] + 2 * noise(&seed);
        mesh->positions[3 * v + 1] = 10 * mesh->positions[3 * v + 1] + 2 * noise(&seed);
    }
    pz_pattern *pattern = pattern_of(mesh, NULL, 1);
    double *uv = flatten(pattern, NULL, NULL);
    /* Best rigid motion (rotation only, no reflection) of uv onto (x, y). */
    int32_t n = mesh->vertex_count;
    double cu[2] = {0, 0}, cx[2] = {0, 0};
    for (int32_t v = 0; v < n; ++v)
        for (int k = 0; k < 2; ++k) {
            cu[k] += uv[2 * v + k] / n;
            cx[k] += mesh->positions[3 * v + k] / n;
        }
    double s00 = 0, s01 = 0, s10 = 0, s11 = 0;
    for (int32_t v = 0; v < n; ++v) {
        double px = uv[2 * v] - cu[0], py = uv[2 * v + 1] - cu[1];
        double qx = mesh->positions[3 * v] - cx[0], qy = mesh->positions[3 * v + 1] - cx[1];
        s00 += qx * px;
        s01 += qx * py;
        s10 += qy * px;
        s11 += qy * py;
    }
    double c = s00 + s11, s = s10 - s01, norm = hypot(c, s);
    c /= norm;
    s /= norm;
    double residual = 0;
    for (int32_t v = 0; v < n; ++v) {
        double px = uv[2 * v] - cu[0], py = uv[2 * v + 1] - cu[1];
        double dx = c * px - s * py - (mesh->positions[3 * v] - cx[0]);
        double dy = s * px + c * py - (mesh->positions[3 * v + 1] - cx[1]);
        residual = fmax(residual, hypot(dx, dy));
    }
    double size = hypot(10 * columns, 10 * rows);
    printf("planar: worst rigid residual %.3g mm (size %.0f mm)\n", residual, size);
    CHECK(residual < 1e-6 * size, "planar: residual %g mm", residual);
    free(uv);
    pattern_release(pattern);
}

static void test_hemisphere(void)
{
    pz_pattern *pattern = pattern_of(generate(PZ_SHAPE_HEMISPHERE, 3000, 0), NULL, 1);
    pz_textile_result result;
    energy_trace trace = {0};
    pz_textile_options options = {.on_iteration = record_energy, .user = &trace};
    double *uv = flatten(pattern, &options, &result);
    printf("hemisphere: energy %.4g -> %.4g, %d iterations, %d damped\n", result.initial_energy, result.final_energy,
           result.iterations_run, result.damped_steps);
    CHECK(trace.increases == 0 && trace.count == result.iterations_run + 1 && trace.first == result.initial_energy &&
              trace.last == result.final_energy,
          "hemisphere: %d energies, %d increases", trace.count, trace.increases);
    int flipped = count_flipped(pattern->mesh, uv);
    double max_strain, rms = rms_strain(pattern->mesh, pattern->mesh->positions, uv, &max_strain);
    printf("hemisphere: %d flipped, strain rms %.4f max %.4f, worst edge error %.4f, %d iterations\n", flipped,
           rms, max_strain, worst_edge_error(pattern->mesh, pattern->mesh->positions, uv), result.iterations_run);
    CHECK(flipped == 0, "hemisphere: %d flipped faces", flipped);
    /* The textile energy penalizes thread stretch: it must beat its LSCM start. */
    REQUIRE_OK(pz_param_lscm_pattern(pattern, NULL, uv, &ctx), ctx);
    double lscm_max, lscm_rms = rms_strain(pattern->mesh, pattern->mesh->positions, uv, &lscm_max);
    printf("hemisphere: LSCM strain rms %.4f max %.4f\n", lscm_rms, lscm_max);
    CHECK(rms < 0.8 * lscm_rms && max_strain < lscm_max, "hemisphere: textile strain rms %g max %g, LSCM %g %g", rms,
          max_strain, lscm_rms, lscm_max);
    free(uv);
    pattern_release(pattern);
}

static void test_hemisphere_steps(void)
{
    pz_pattern *pattern = pattern_of(generate(PZ_SHAPE_HEMISPHERE, 3000, 0), NULL, 1);
    pz_textile_result result;
    double *uv = twenty_steps(pattern, "hemisphere", &result);
    CHECK(result.iterations_run == 20 && result.damped_steps <= 2 && result.final_energy < result.initial_energy,
          "hemisphere, 20 steps: %d iterations, %d damped", result.iterations_run, result.damped_steps);
    free(uv);
    pattern_release(pattern);
}

#define HALF_ROOT2 0.70710678118654752440

static void test_saddle_grain(void)
{
    pz_pattern *pattern = pattern_of(generate(PZ_SHAPE_SADDLE, 3000, 0), NULL, 1);
    pz_textile_options options = {.grain_given = 1, .grain = {1, 0, 0}};
    double *uv = flatten(pattern, &options, NULL);
    double angle = mean_grain_angle(pattern->mesh, uv, options.grain, 0);
    double spread = mean_grain_angle(pattern->mesh, uv, options.grain, 1);
    printf("saddle, grain +x: mean signed angle %.3g degrees (mean |angle| %.3g)\n", angle, spread);
    CHECK(fabs(angle) < 1, "saddle: warp is %g degrees off the grain on average", angle);
    CHECK(count_flipped(pattern->mesh, uv) == 0, "saddle: flipped faces");
    free(uv);
    pattern_release(pattern);

    /* The mean ABSOLUTE angle: on the saddle above (z = xy / 300 over 300 x
     * 300 mm) the projected axis turns across the surface by more than a
     * flattening can follow (1.7 degrees on average); on a mildly curved
     * panel (the same saddle flattened 4x in z: 19 mm deep) and on a
     * developable one (the open cylinder lying along the diagonal (1, 1, 0),
     * grain given along its axis) every triangle's warp must follow the
     * projected axis to within 1 degree on average. */
    pattern = pattern_of(generate(PZ_SHAPE_SADDLE, 3000, 0), NULL, 1);
    for (int32_t v = 0; v < pattern->mesh->vertex_count; ++v)
        pattern->mesh->positions[3 * v + 2] *= 0.25;
    pz_textile_options diagonal = {.grain_given = 1, .grain = {HALF_ROOT2, HALF_ROOT2, 0}};
    uv = flatten(pattern, &diagonal, NULL);
    double mild = mean_grain_angle(pattern->mesh, uv, diagonal.grain, 1);
    printf("mild saddle, grain (1,1,0): mean |angle| %.3g degrees (signed %.3g)\n", mild,
           mean_grain_angle(pattern->mesh, uv, diagonal.grain, 0));
    CHECK(mild < 1, "mild saddle: warp is %g degrees off the grain (mean |angle|)", mild);
    free(uv);
    pattern_release(pattern);

    pattern = pattern_of(generate(PZ_SHAPE_CYLINDER, 3000, 1), NULL, 1);
    for (int32_t v = 0; v < pattern->mesh->vertex_count; ++v) {
        /* Axis z -> (1, 1, 0) / sqrt 2: a rotation by 90 degrees about (-1, 1, 0) / sqrt 2. */
        double *x = pattern->mesh->positions + 3 * v, r[3];
        r[0] = 0.5 * x[0] - 0.5 * x[1] + HALF_ROOT2 * x[2];
        r[1] = -0.5 * x[0] + 0.5 * x[1] + HALF_ROOT2 * x[2];
        r[2] = -HALF_ROOT2 * x[0] - HALF_ROOT2 * x[1];
        memcpy(x, r, sizeof r);
    }
    uv = flatten(pattern, &diagonal, NULL);
    double along = mean_grain_angle(pattern->mesh, uv, diagonal.grain, 1);
    printf("tilted cylinder, grain along its axis (1,1,0): mean |angle| %.3g degrees\n", along);
    CHECK(along < 1, "tilted cylinder: warp is %g degrees off the grain (mean |angle|)", along);
    free(uv);
    pattern_release(pattern);
}

/* Gives a two-panel pattern one seam from panel 0 to panel 1 of `pairs`
 * pairs, its sides allocated for the caller to fill. */
static pz_seam *only_seam(pz_pattern *pattern, int32_t pairs)
{
    pattern->seams = calloc(1, sizeof(pz_seam));
    REQUIRE(pattern->seams, "out of memory");
    pz_seam *seam = &pattern->seams[pattern->seam_count++];
    seam->panel_a = 0;
    seam->panel_b = 1;
    seam->pair_count = pairs;
    seam->side_a = malloc((size_t)pairs * sizeof(int32_t));
    seam->side_b = malloc((size_t)pairs * sizeof(int32_t));
    REQUIRE(seam->side_a && seam->side_b, "out of memory");
    return seam;
}

/*
 * Two panels joined by a seam, big enough (10,000 faces) for the parallel
 * paths: a 100 x 50 grid of 5 mm squares, cut down the middle column (the
 * right half gets copies of those vertices), then rolled onto a cylinder of
 * radius 150 mm around the y axis (developable). Both pieces must come out
 * isometric, the seam sides equal and mirror images.
 */
static void test_two_panels(void)
{
    const int columns = 100, rows = 50, middle = columns / 2;
    pz_mesh *grid = test_grid(columns, rows, TEST_GRID_FLAT, 0, &ctx);
    int32_t nv = grid->vertex_count, extra = rows + 1;
    pz_mesh *mesh = NULL;
    REQUIRE_OK(pz_mesh_create(nv + extra, grid->face_count, &mesh, &ctx), ctx);
    for (int32_t v = 0; v < nv + extra; ++v) {
        int32_t source = v < nv ? v : (v - nv) * (columns + 1) + middle;
        double x = 5 * grid->positions[3 * source], y = 5 * grid->positions[3 * source + 1];
        double angle = x / 150;
        mesh->positions[3 * v] = 150 * sin(angle);
        mesh->positions[3 * v + 1] = y;
        mesh->positions[3 * v + 2] = 150 * cos(angle);
    }
    int32_t *face_panel = malloc((size_t)grid->face_count * sizeof(int32_t));
    REQUIRE(face_panel, "out of memory");
    for (int32_t f = 0; f < grid->face_count; ++f) {
        int column = (f / 2) % columns;
        face_panel[f] = column >= middle;
        for (int k = 0; k < 3; ++k) {
            int32_t v = grid->faces[3 * f + k];
            if (column >= middle && v % (columns + 1) == middle)
                v = nv + v / (columns + 1);
            mesh->faces[3 * f + k] = v;
        }
    }
    pz_mesh_free(&grid);
    pz_pattern *pattern = pattern_of(mesh, face_panel, 2);
    free(face_panel);
    pz_seam *seam = only_seam(pattern, rows + 1);
    for (int j = 0; j <= rows; ++j) {
        seam->side_a[j] = j * (columns + 1) + middle;
        seam->side_b[j] = nv + j;
    }
    pz_textile_options options = {.threads = 2};
    pz_textile_result result;
    double *uv = flatten(pattern, &options, &result);
    double error = worst_edge_error(mesh, mesh->positions, uv);
    double la = polyline_length(uv, seam->side_a, seam->pair_count);
    double lb = polyline_length(uv, seam->side_b, seam->pair_count);
    double residual = reflection_residual(uv, seam);
    printf("two panels: worst edge error %.3g, %d flipped, seam %.3f / %.3f mm, reflection residual %.3g mm\n",
           error, count_flipped(mesh, uv), la, lb, residual);
    CHECK(error < 1e-4, "two panels: worst edge error %g", error);
    CHECK(count_flipped(mesh, uv) == 0, "two panels: flipped faces");
    CHECK(fabs(la - lb) < 1e-4 * la && fabs(la - 5 * rows) < 1e-3, "two panels: seam sides %g / %g mm", la, lb);
    CHECK(residual < 1e-3, "two panels: reflection residual %g mm", residual);
    free(uv);
    pattern_release(pattern);
}

static void test_bad_input(void)
{
    pz_pattern *pattern = pattern_of(generate(PZ_SHAPE_CYLINDER, 1000, 0), NULL, 1); /* closed: not a disk */
    double *uv = malloc((size_t)pattern->mesh->vertex_count * 2 * sizeof(double));
    REQUIRE(uv, "out of memory");
    pz_status status = pz_param_textile(pattern, NULL, uv, NULL, &ctx);
    CHECK(status == PZ_ERR_DATA, "closed cylinder: status %d", status);
    CHECK(strstr(ctx.error, "panel 0") != NULL, "message does not name the panel: %s", ctx.error);
    /* Two panels sharing vertices: the mesh was not cut between them. */
    pattern->panel_count = 2;
    for (int32_t f = pattern->mesh->face_count / 2; f < pattern->mesh->face_count; ++f)
        pattern->face_panel[f] = 1;
    status = pz_param_textile(pattern, NULL, uv, NULL, &ctx);
    CHECK(status == PZ_ERR_DATA && strstr(ctx.error, "not cut"), "uncut panels: status %d: %s", status, ctx.error);
    free(uv);
    pattern_release(pattern);
}

/*
 * A seam that cannot be a mirror image, without ../shared/data: a flat half
 * annulus (radii 100 and 200 mm) whose outer semicircle is sewn to the
 * straight top edge of a flat 60 mm strip 5 % shorter than the arc. A
 * semicircle cannot be reflected onto a line, so the seam must be found
 * length-only; then the two sides end (nearly) equal in length, while
 * with the seam term off they stay 5 % apart, and the pieces stay close to
 * their flat shapes, unlike when the reflection is forced on them.
 */
static pz_pattern *curved_seam_pattern(void)
{
    enum { arc = 24, rings = 4, strip = 3 };
    const double pi = 3.14159265358979323846, r_in = 100, r_out = 200, height = 60;
    double length = 0.95 * pi * r_out;
    int32_t na = (arc + 1) * (rings + 1), nb = (arc + 1) * (strip + 1);
    pz_mesh *mesh = NULL;
    REQUIRE_OK(pz_mesh_create(na + nb, 2 * arc * (rings + strip), &mesh, &ctx), ctx);
    for (int i = 0; i <= arc; ++i) {
        double angle = pi * i / arc;
        for (int j = 0; j <= rings; ++j) {
            double r = r_in + (r_out - r_in) * j / rings, *p = mesh->positions + 3 * (i * (rings + 1) + j);
            p[0] = r * cos(angle);
            p[1] = r * sin(angle);
            p[2] = 0;
        }
        for (int j = 0; j <= strip; ++j) {
            double *p = mesh->positions + 3 * (na + i * (strip + 1) + j);
            p[0] = length * i / arc - length / 2;
            p[1] = -300 + height * j / strip;
            p[2] = 0;
        }
    }
    int32_t *face_panel = malloc((size_t)mesh->face_count * sizeof(int32_t)), f = 0;
    REQUIRE(face_panel, "out of memory");
    for (int part = 0; part < 2; ++part) {
        int32_t base = part ? na : 0, columns = part ? strip : rings;
        for (int i = 0; i < arc; ++i)
            for (int j = 0; j < columns; ++j) {
                int32_t a = base + i * (columns + 1) + j, b = a + columns + 1;
                int32_t quad[2][3] = {{a, a + 1, b + 1}, {a, b + 1, b}};
                if (part) { /* the strip's rows run along +x: this keeps its faces counter-clockwise too */
                    int32_t flip[2][3] = {{a, b, b + 1}, {a, b + 1, a + 1}};
                    memcpy(quad, flip, sizeof quad);
                }
                for (int t = 0; t < 2; ++t, ++f) {
                    memcpy(mesh->faces + 3 * f, quad[t], sizeof quad[t]);
                    face_panel[f] = part;
                }
            }
    }
    pz_pattern *pattern = pattern_of(mesh, face_panel, 2);
    free(face_panel);
    pz_seam *seam = only_seam(pattern, arc + 1);
    for (int i = 0; i <= arc; ++i) {
        seam->side_a[i] = i * (rings + 1) + rings;
        seam->side_b[i] = na + i * (strip + 1) + strip;
    }
    return pattern;
}

static void test_curved_seam(void)
{
    pz_pattern *pattern = curved_seam_pattern();
    const pz_seam *seam = &pattern->seams[0];
    const pz_mesh *mesh = pattern->mesh;
    pz_textile_options runs[3] = {{0}, {.weights_given = 1, .weight_stretch = 5, .weight_rigid = 1, .weight_dart = 5},
                                  {.seam_mirror_tolerance = 1e300}};
    const char *labels[3] = {"defaults", "seam term off", "reflection forced"};
    double mismatch[3], error[3];
    int32_t length_only[3];
    for (int run = 0; run < 3; ++run) {
        pz_textile_result result;
        double *uv = flatten(pattern, &runs[run], &result);
        double la = polyline_length(uv, seam->side_a, seam->pair_count);
        double lb = polyline_length(uv, seam->side_b, seam->pair_count);
        mismatch[run] = fabs(la - lb) / fmax(la, lb);
        error[run] = worst_edge_error(mesh, mesh->positions, uv);
        length_only[run] = result.length_only_seams;
        printf("curved seam (%s): %d length-only, sides %.2f / %.2f mm (%.3f%%), worst edge error %.4f, "
               "%d flipped\n", labels[run], (int)length_only[run], la, lb, 100 * mismatch[run], error[run],
               count_flipped(mesh, uv));
        CHECK(count_flipped(mesh, uv) == 0, "curved seam (%s): flipped faces", labels[run]);
        free(uv);
    }
    CHECK(length_only[0] == 1 && length_only[2] == 0, "curved seam: length-only %d (defaults), %d (forced)",
          (int)length_only[0], (int)length_only[2]);
    CHECK(mismatch[1] > 0.04 && mismatch[0] < 0.25 * mismatch[1],
          "curved seam: the length term does not match the sides: %g against %g with the seam term off", mismatch[0],
          mismatch[1]);
    CHECK(error[0] < 0.5 * error[2], "curved seam: length-only distorts as much as a forced reflection (%g, %g)",
          error[0], error[2]);
    pattern_release(pattern);
}

/*
 * One panel of 100K+ faces on two threads: the iterations split their faces, the systems are ordered as the LSCM
 * start was: the same uv as on one thread, byte for byte. pz_param_textile takes the cores
 * the load average leaves free only, so on a busy machine both runs take one thread: said, not skipped (the rest
 * of this test ran).
 */
static void test_threads_same(void)
{
    double load[1] = {0};
    if (getloadavg(load, 1) == 1 && load[0] > 1.0)
        printf("threads: load %.2f, the two-thread run may take one thread\n", load[0]);
    pz_pattern *pattern = pattern_of(generate(PZ_SHAPE_HEMISPHERE, 110000, 0), NULL, 1);
    pz_textile_options one = {.threads = 1, .iterations = 3}, two = {.threads = 2, .iterations = 3};
    pz_textile_result result_one, result_two;
    double *uv_one = flatten(pattern, &one, &result_one), *uv_two = flatten(pattern, &two, &result_two);
    size_t bytes = (size_t)pattern->mesh->vertex_count * 2 * sizeof(double);
    printf("threads: %d faces, 1 thread set-up %.0f ms, 2 threads %.0f ms\n", (int)pattern->mesh->face_count,
           result_one.init_ms, result_two.init_ms);
    CHECK(memcmp(uv_one, uv_two, bytes) == 0, "two threads give another uv than one");
    /* Its systems ordered as its start was (55K unknowns): a sound flattening still. */
    CHECK(count_flipped(pattern->mesh, uv_one) == 0 && result_one.final_energy < result_one.initial_energy,
          "110K hemisphere: %d flipped, energy %g -> %g", count_flipped(pattern->mesh, uv_one),
          result_one.initial_energy, result_one.final_energy);
    free(uv_one);
    free(uv_two);
    pattern_release(pattern);
}

int main(void)
{
    pz_ctx_init(&ctx);
    ctx.quiet = 1;
    test_developable(PZ_SHAPE_CYLINDER);
    test_developable(PZ_SHAPE_CONE);
    test_planar();
    test_hemisphere();
    test_hemisphere_steps();
    test_saddle_grain();
    test_bad_input();
    test_two_panels();
    test_curved_seam();
    test_threads_same();
    return test_finish();
}

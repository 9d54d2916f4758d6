/*
 * tests/param/test_solvers.c -- the set-up / solve split of the textile
 * parameterization (pz_textile_setup, pz_textile_solve,
 * pz_textile_solver_free):
 *  - on a generated bodice cut into front and back (two seams, one extra
 *    pose), with the default options, with the poses, and with a strain goal
 *    (warm-up with the seams open, reweighting, demotion rounds: the state a
 *    solve changes most), set-up then solve gives the same uv, byte for byte,
 *    and the same result as pz_param_textile;
 *  - solving twice with one set-up gives the same uv and result twice (every
 *    solve starts from the set-up's state), also with other solvers set up
 *    and solved in between;
 *  - a hemisphere (one panel) likewise;
 *  - a solve cancelled through the context returns PZ_ERR_CANCELLED, and the
 *    same solver then solves as if nothing had happened;
 *  - usage errors: no solver pointer, no pattern, negative weights (*out stays
 *    NULL), no uv;
 *  - WireWarping (pz_wirewarp_setup, pz_wirewarp_solve) on a hemisphere and on
 *    the bodice's front and back with a feature curve: the global and the
 *    progressive scheme, cotangent and 1/length interiors, each solve of one
 *    set-up equal byte for byte to pz_param_wirewarp with the same options
 *    (the second and later solves factorize the kept interior analysis).
 *
 * SPDX-License-Identifier: GPL-3.0-or-later
 */
#include "generate/generate.h"
#include "io/io.h"
#include "param/param.h"
#include "test_util.h"

#include <math.h>
#include <stdlib.h>
#include <string.h>

static pz_ctx ctx;

/* A generated shape cut into panels by the sign of x (front and back of a tube) or one panel. */
static pz_pattern *generated_pattern(pz_shape shape, int32_t faces, int32_t poses, int split)
{
    pz_generate_options options = {.target_faces = faces, .pose_count = poses};
    pz_mesh *mesh = NULL;
    REQUIRE_OK(pz_generate(shape, &options, &mesh, &ctx), ctx);
    int32_t *face_panel = calloc((size_t)mesh->face_count, sizeof(int32_t));
    REQUIRE(face_panel, "out of memory");
    for (int32_t f = 0; split && f < mesh->face_count; ++f) {
        double x = 0;
        for (int k = 0; k < 3; ++k)
            x += mesh->positions[3 * mesh->faces[3 * f + k]];
        face_panel[f] = x > 0;
    }
    pz_pattern *pattern = NULL;
    REQUIRE_OK(pz_pattern_build(mesh, face_panel, NULL, NULL, "generated", &pattern, &ctx), ctx);
    free(face_panel);
    pz_mesh_free(&mesh);
    return pattern;
}

static double *new_uv(const pz_pattern *pattern)
{
    double *uv = malloc((size_t)pattern->mesh->vertex_count * 2 * sizeof(double));
    REQUIRE(uv, "out of memory");
    return uv;
}

/* Everything of a result but the timings. */
static int same_result(const pz_textile_result *a, const pz_textile_result *b)
{
    return a->iterations_run == b->iterations_run && a->initial_energy == b->initial_energy &&
           a->final_energy == b->final_energy && a->converged == b->converged && a->bounded_steps == b->bounded_steps &&
           a->damped_steps == b->damped_steps && a->length_only_seams == b->length_only_seams &&
           a->length_only_darts == b->length_only_darts;
}

/* The one-shot call, set-up then two solves (with another solver's work in between), all equal. */
static void check_split(const char *name, const pz_pattern *pattern, const pz_textile_options *options,
                        const pz_pattern *other)
{
    size_t bytes = (size_t)pattern->mesh->vertex_count * 2 * sizeof(double);
    double *once = new_uv(pattern), *first = new_uv(pattern), *second = new_uv(pattern);
    pz_textile_result once_result, first_result, second_result;
    REQUIRE_OK(pz_param_textile(pattern, options, once, &once_result, &ctx), ctx);
    pz_textile_solver *solver = NULL;
    REQUIRE_OK(pz_textile_setup(pattern, options, &solver, &ctx), ctx);
    REQUIRE(solver, "%s: no solver", name);
    REQUIRE_OK(pz_textile_solve(solver, first, &first_result, &ctx), ctx);
    if (other) { /* another solver's set-up and solve must not disturb this one */
        pz_textile_solver *between = NULL;
        double *uv = new_uv(other);
        REQUIRE_OK(pz_textile_setup(other, options, &between, &ctx), ctx);
        REQUIRE_OK(pz_textile_solve(between, uv, NULL, &ctx), ctx);
        pz_textile_solver_free(&between);
        CHECK(between == NULL, "%s: the freed solver pointer is cleared", name);
        free(uv);
    }
    REQUIRE_OK(pz_textile_solve(solver, second, &second_result, &ctx), ctx);
    CHECK(memcmp(once, first, bytes) == 0, "%s: set-up + solve gives pz_param_textile's uv byte for byte", name);
    CHECK(memcmp(first, second, bytes) == 0, "%s: the second solve gives the first's uv byte for byte", name);
    CHECK(same_result(&once_result, &first_result), "%s: set-up + solve gives pz_param_textile's result (%d its, E %g)",
          name, first_result.iterations_run, first_result.final_energy);
    CHECK(same_result(&first_result, &second_result), "%s: the second solve gives the first's result", name);
    /* (With a strain goal the weights, hence the energy, change as it goes: only the iterations count.) */
    int goal = options && options->strain_limit > 0;
    CHECK(first_result.iterations_run > 1 && (goal || first_result.final_energy < first_result.initial_energy),
          "%s: the solve iterated (%d iterations, energy %g -> %g)", name, first_result.iterations_run,
          first_result.initial_energy, first_result.final_energy);
    pz_textile_solver_free(&solver);
    free(once);
    free(first);
    free(second);
}

static void test_bodice(void)
{
    pz_pattern *bodice = generated_pattern(PZ_SHAPE_BODICE, 3000, 1, 1);
    pz_pattern *hemisphere = generated_pattern(PZ_SHAPE_HEMISPHERE, 1500, 0, 0);
    REQUIRE(bodice->panel_count == 2 && bodice->seam_count >= 2, "bodice: %d panels, %d seams", bodice->panel_count,
            bodice->seam_count);
    pz_textile_options defaults = {0};
    check_split("bodice, defaults", bodice, &defaults, hemisphere);
    pz_textile_options poses = {.use_poses = 1, .iterations = 8};
    check_split("bodice, poses", bodice, &poses, NULL);
    pz_textile_options goal = {.use_poses = 1, .strain_limit = 0.01, .iterations = 6};
    check_split("bodice, strain goal", bodice, &goal, hemisphere);
    check_split("hemisphere", hemisphere, NULL, bodice);
    pz_pattern_free(&bodice);
    pz_pattern_free(&hemisphere);
}

static volatile int cancel_flag;

/* Cancels from the first iteration's report on. */
static void cancel_at_first(void *user, int iteration, double energy)
{
    (void)user;
    (void)energy;
    if (iteration >= 1)
        cancel_flag = 1;
}

static void test_cancel(void)
{
    pz_pattern *pattern = generated_pattern(PZ_SHAPE_HEMISPHERE, 1500, 0, 0);
    size_t bytes = (size_t)pattern->mesh->vertex_count * 2 * sizeof(double);
    double *reference = new_uv(pattern), *uv = new_uv(pattern);
    pz_textile_options options = {.on_iteration = cancel_at_first};
    pz_textile_result reference_result, result;
    pz_textile_solver *solver = NULL;
    REQUIRE_OK(pz_textile_setup(pattern, &options, &solver, &ctx), ctx);
    pz_ctx cancelling;
    pz_ctx_init(&cancelling);
    cancelling.cancel = &cancel_flag;
    cancel_flag = 0;
    pz_status status = pz_textile_solve(solver, uv, &result, &cancelling);
    CHECK(status == PZ_ERR_CANCELLED, "a cancelled solve returns PZ_ERR_CANCELLED (got %d: %s)", (int)status,
          cancelling.error);
    cancel_flag = 0;
    REQUIRE_OK(pz_textile_solve(solver, uv, &result, &ctx), ctx);
    pz_textile_solver_free(&solver);
    options.on_iteration = NULL;
    REQUIRE_OK(pz_param_textile(pattern, &options, reference, &reference_result, &ctx), ctx);
    CHECK(memcmp(reference, uv, bytes) == 0, "after a cancelled solve the solver solves as a fresh one, byte for byte");
    CHECK(same_result(&reference_result, &result), "after a cancelled solve the result is a fresh one's");
    free(reference);
    free(uv);
    pz_pattern_free(&pattern);
}

static void test_usage(void)
{
    pz_pattern *pattern = generated_pattern(PZ_SHAPE_HEMISPHERE, 600, 0, 0);
    pz_textile_solver *solver = (pz_textile_solver *)&ctx; /* must be overwritten */
    CHECK(pz_textile_setup(pattern, NULL, NULL, &ctx) == PZ_ERR_USAGE, "no solver pointer: usage error");
    CHECK(pz_textile_setup(NULL, NULL, &solver, &ctx) == PZ_ERR_USAGE && solver == NULL,
          "no pattern: usage error, *out NULL");
    pz_textile_options negative = {.weights_given = 1, .weight_stretch = -1, .weight_rigid = 1};
    solver = (pz_textile_solver *)&ctx;
    CHECK(pz_textile_setup(pattern, &negative, &solver, &ctx) == PZ_ERR_USAGE && solver == NULL,
          "negative weights: usage error, *out NULL");
    REQUIRE_OK(pz_textile_setup(pattern, NULL, &solver, &ctx), ctx);
    CHECK(pz_textile_solve(solver, NULL, NULL, &ctx) == PZ_ERR_USAGE, "no uv: usage error");
    CHECK(pz_textile_solve(NULL, NULL, NULL, &ctx) == PZ_ERR_USAGE, "no solver: usage error");
    pz_textile_solver_free(&solver);
    pz_textile_solver_free(&solver); /* NULL: nothing */
    pz_textile_solver_free(NULL);
    pz_pattern_free(&pattern);
}

/* A key curve down the middle of panel 0: its vertices nearest to x = 0 from the lowest to the highest. */
static pz_feature_curves *middle_curve(const pz_pattern *pattern)
{
    const pz_mesh *mesh = pattern->mesh;
    pz_topology *topology = NULL;
    REQUIRE_OK(pz_topology_build(mesh, &topology, &ctx), ctx);
    double low = INFINITY, high = -INFINITY;
    for (int32_t v = 0; v < mesh->vertex_count; ++v) {
        low = fmin(low, mesh->positions[3 * v + 2]);
        high = fmax(high, mesh->positions[3 * v + 2]);
    }
    pz_feature_polyline line = {.kind = PZ_FEATURE_KEY, .point_count = 2};
    double points[6] = {0, -1e9, 0, 0, -1e9, 0};
    /* The panel's points nearest to the bottom and the top of its middle. */
    double best[2] = {INFINITY, INFINITY};
    for (int32_t f = 0; f < mesh->face_count; ++f)
        for (int k = 0; k < 3; ++k) {
            int32_t v = mesh->faces[3 * f + k];
            const double *p = mesh->positions + 3 * v;
            if (pattern->face_panel[f] != 0 || topology->vertex_on_boundary[v])
                continue;
            for (int end = 0; end < 2; ++end) {
                double z = end ? high - 0.25 * (high - low) : low + 0.25 * (high - low);
                double d = fabs(p[0]) + fabs(p[2] - z);
                if (d < best[end]) {
                    best[end] = d;
                    memcpy(points + 3 * end, p, 3 * sizeof(double));
                }
            }
        }
    line.points = points;
    pz_feature_curves *curves = NULL;
    REQUIRE_OK(pz_feature_curves_snap(pattern, &line, 1, 0, &curves, &ctx), ctx);
    pz_topology_free(&topology);
    return curves;
}

static void check_wirewarp(const char *name, const pz_pattern *pattern, const pz_feature_curves *features)
{
    size_t bytes = (size_t)pattern->mesh->vertex_count * 2 * sizeof(double);
    double *once = new_uv(pattern), *solved = new_uv(pattern);
    pz_wirewarp_solver *solver = NULL;
    REQUIRE_OK(pz_wirewarp_setup(pattern, features, &solver, &ctx), ctx);
    pz_wirewarp_options variants[4] = {{.scheme = 0}, {.scheme = 1}, {.interior = 1}, {.scheme = 0}};
    for (int i = 0; i < 4; ++i) {
        pz_wirewarp_result a, b;
        REQUIRE_OK(pz_param_wirewarp(pattern, &variants[i], features, once, &a, &ctx), ctx);
        REQUIRE_OK(pz_wirewarp_solve(solver, &variants[i], solved, &b, &ctx), ctx);
        CHECK(memcmp(once, solved, bytes) == 0, "%s, scheme %d, interior %d (solve %d of one set-up): the uv of "
              "pz_param_wirewarp byte for byte", name, variants[i].scheme, variants[i].interior, i + 1);
        CHECK(a.iterations == b.iterations && a.constraint_residual == b.constraint_residual &&
                  a.flipped_triangles == b.flipped_triangles && a.e_len_wires == b.e_len_wires &&
                  a.wire_patch_count == b.wire_patch_count,
              "%s, solve %d: the result of pz_param_wirewarp (%d patches, %d iterations, E_len %g)", name, i + 1,
              b.wire_patch_count, b.iterations, b.e_len_wires);
    }
    pz_wirewarp_solver_free(&solver);
    CHECK(solver == NULL, "%s: the freed solver pointer is cleared", name);
    free(once);
    free(solved);
}

static void test_wirewarp(void)
{
    pz_pattern *hemisphere = generated_pattern(PZ_SHAPE_HEMISPHERE, 1500, 0, 0);
    check_wirewarp("wirewarp, hemisphere", hemisphere, NULL);
    pz_pattern *bodice = generated_pattern(PZ_SHAPE_BODICE, 3000, 0, 1);
    pz_feature_curves *curves = middle_curve(bodice);
    REQUIRE(curves->curve_count == 1, "one feature curve snapped");
    check_wirewarp("wirewarp, bodice with a key curve", bodice, curves);
    pz_wirewarp_solver *solver = (pz_wirewarp_solver *)&ctx;
    CHECK(pz_wirewarp_setup(NULL, NULL, &solver, &ctx) == PZ_ERR_USAGE && solver == NULL,
          "wirewarp: no pattern: usage error, *out NULL");
    CHECK(pz_wirewarp_setup(bodice, NULL, NULL, &ctx) == PZ_ERR_USAGE, "wirewarp: no solver pointer: usage error");
    pz_feature_curves_free(&curves);
    pz_pattern_free(&bodice);
    pz_pattern_free(&hemisphere);
}

int main(void)
{
    pz_ctx_init(&ctx);
    ctx.quiet = 1;
    test_bodice();
    test_cancel();
    test_usage();
    test_wirewarp();
    return test_finish();
}

/*
 * tests/param/test_slivers.c -- the back-ends on panels with sliver
 * triangles (issue 17: spring-mass reached strain 31,772 on such a panel).
 *
 * A panel of a cylinder (developable: its true flattening has no strain) is
 * meshed as a grid, and some faces are split 1-to-3 at a point a tiny
 * height above one of their edges (caps: a triangle of height 1e-4 of its
 * base) or next to a corner (needles). The new vertices lie in their
 * faces' planes, so the panel stays exactly developable. Every back-end must give an
 * injective piece (no flipped face, no outline crossing) whose strain is
 * bounded -- the slivers' own strain included: a face of height 1e-4 mm
 * moved by 1e-3 mm is strained 10x, which is what "blowing up" means -- or
 * say in its result that the panel fell back. Spring-mass (isotropic and
 * orthotropic), WireWarping and the textile default are run.
 *
 * SPDX-License-Identifier: GPL-3.0-or-later
 */
#include "param/param.h"
#include "test_util.h"

#include <math.h>
#include <stdlib.h>
#include <string.h>

static pz_ctx ctx;

#define ROWS 14
#define COLUMNS 20
#define CELL 10.0     /* mm */
#define RADIUS 120.0  /* mm */

/* The cylinder point of the flat point (x, y): x wraps around, y runs along the axis. */
static void on_cylinder(double x, double y, double *out)
{
    out[0] = RADIUS * sin(x / RADIUS);
    out[1] = RADIUS * (1 - cos(x / RADIUS));
    out[2] = y;
}

/*
 * The grid with every `every`-th face split at a point `height` (relative)
 * above its first edge (caps) or, with `needles`, that close to its first
 * corner. flat: the true pattern (vertex_count x 2), written, malloc'd.
 */
static pz_mesh *sliver_panel(int every, double height, int needles, int on_surface, double **flat)
{
    int32_t grid_vertices = (ROWS + 1) * (COLUMNS + 1), grid_faces = 2 * ROWS * COLUMNS;
    int32_t splits = (grid_faces + every - 1) / every;
    pz_mesh *mesh = calloc(1, sizeof *mesh);
    REQUIRE(mesh, "out of memory");
    mesh->vertex_count = grid_vertices + splits;
    mesh->face_count = grid_faces + 2 * splits;
    mesh->positions = malloc((size_t)mesh->vertex_count * 3 * sizeof(double));
    mesh->faces = malloc((size_t)mesh->face_count * 3 * sizeof(int32_t));
    *flat = malloc((size_t)mesh->vertex_count * 2 * sizeof(double));
    REQUIRE(mesh->positions && mesh->faces && *flat, "out of memory");
    mesh->unit_scale = 1;
    double *xy = *flat;
    for (int i = 0; i <= ROWS; ++i)
        for (int j = 0; j <= COLUMNS; ++j) {
            int32_t v = i * (COLUMNS + 1) + j;
            xy[2 * v] = CELL * j;
            xy[2 * v + 1] = CELL * i;
        }
    int32_t *split_corner = malloc((size_t)splits * sizeof(int32_t)); /* per split point: its face's third corner */
    REQUIRE(split_corner, "out of memory");
    int32_t face = 0, extra = grid_vertices;
    for (int i = 0; i < ROWS; ++i)
        for (int j = 0; j < COLUMNS; ++j) {
            int32_t a = i * (COLUMNS + 1) + j, b = a + 1, c = b + COLUMNS + 1, d = a + COLUMNS + 1;
            int32_t corners[2][3] = {{a, b, c}, {a, c, d}};
            for (int t = 0; t < 2; ++t) {
                const int32_t *k = corners[t];
                int32_t index = 2 * (i * COLUMNS + j) + t;
                if (index % every) {
                    memcpy(mesh->faces + 3 * face++, k, 3 * sizeof(int32_t));
                    continue;
                }
                /* The split point: near edge k0-k1 (cap) or near corner k0 (needle). */
                double p[2];
                for (int e = 0; e < 2; ++e) {
                    double mid = 0.5 * (xy[2 * k[0] + e] + xy[2 * k[1] + e]);
                    double centroid = (xy[2 * k[0] + e] + xy[2 * k[1] + e] + xy[2 * k[2] + e]) / 3;
                    p[e] = needles ? xy[2 * k[0] + e] + height * (centroid - xy[2 * k[0] + e])
                                   : mid + height * (xy[2 * k[2] + e] - mid);
                }
                xy[2 * extra] = p[0];
                xy[2 * extra + 1] = p[1];
                split_corner[extra - grid_vertices] = k[2];
                int32_t split[3][3] = {{k[0], k[1], extra}, {k[1], k[2], extra}, {k[2], k[0], extra}};
                for (int s = 0; s < 3; ++s)
                    memcpy(mesh->faces + 3 * face++, split[s], 3 * sizeof(int32_t));
                ++extra;
            }
        }
    REQUIRE(face == mesh->face_count && extra == mesh->vertex_count, "sliver panel: %d faces, %d vertices", (int)face,
            (int)extra);
    for (int32_t v = 0; v < mesh->vertex_count; ++v)
        on_cylinder(xy[2 * v], xy[2 * v + 1], mesh->positions + 3 * v);
    /* A split point lies in its face's plane, at the same barycentric coordinates as in the flat pattern:
     * every face of a split stays a flat piece of that face, and the mesh stays exactly developable. With
     * on_surface it stays on the cylinder instead, off the face's plane by the sagitta of the edge it caps
     * (0.1 mm here): the 3D cap is then 1e-2 as high as long, not a sliver in 3D, and the mesh is no longer
     * developable at the split points -- their angle defect has to go somewhere, and it must not all go
     * into the flat cap (spring-mass: strain 4.2 before sliver fitting). */
    for (int32_t f = 0; f < mesh->face_count && !on_surface; ++f) {
        const int32_t *k = mesh->faces + 3 * f;
        if (k[2] < grid_vertices || k[0] >= grid_vertices || k[1] >= grid_vertices)
            continue;
        const double *p0 = xy + 2 * k[0], *p1 = xy + 2 * k[1], *p2 = xy + 2 * k[2];
        int32_t corner = split_corner[k[2] - grid_vertices];
        if (corner == k[0] || corner == k[1])
            continue; /* the split's other two triangles */
        const double *q = xy + 2 * corner;
        /* (k0, k1, extra) is the first triangle of the split; the third corner is `corner`. */
        double det = (p1[0] - p0[0]) * (q[1] - p0[1]) - (p1[1] - p0[1]) * (q[0] - p0[0]);
        double s = ((p2[0] - p0[0]) * (q[1] - p0[1]) - (p2[1] - p0[1]) * (q[0] - p0[0])) / det;
        double t = ((p1[0] - p0[0]) * (p2[1] - p0[1]) - (p1[1] - p0[1]) * (p2[0] - p0[0])) / det;
        const double *a = mesh->positions + 3 * k[0], *b = mesh->positions + 3 * k[1];
        const double *c = mesh->positions + 3 * corner;
        for (int e = 0; e < 3; ++e)
            mesh->positions[3 * k[2] + e] = a[e] + s * (b[e] - a[e]) + t * (c[e] - a[e]);
    }
    free(split_corner);
    return mesh;
}

/* The smallest height of a face relative to its longest edge, in the flat pattern. */
static double thinnest(const pz_mesh *mesh, const double *xy)
{
    double worst = INFINITY;
    for (int32_t f = 0; f < mesh->face_count; ++f) {
        const int32_t *k = mesh->faces + 3 * f;
        double longest = 0;
        for (int e = 0; e < 3; ++e) {
            double dx = xy[2 * k[(e + 1) % 3]] - xy[2 * k[e]], dy = xy[2 * k[(e + 1) % 3] + 1] - xy[2 * k[e] + 1];
            longest = fmax(longest, sqrt(dx * dx + dy * dy));
        }
        double twice = fabs((xy[2 * k[1]] - xy[2 * k[0]]) * (xy[2 * k[2] + 1] - xy[2 * k[0] + 1]) -
                            (xy[2 * k[1] + 1] - xy[2 * k[0] + 1]) * (xy[2 * k[2]] - xy[2 * k[0]]));
        worst = fmin(worst, twice / (longest * longest));
    }
    return worst;
}

enum { SPRINGMASS, ORTHOTROPIC, WIREWARP, TEXTILE };
static const char *const backend_names[] = {"spring-mass", "orthotropic spring-mass", "WireWarping", "textile"};

/* Flattens with one back-end; returns the metrics (caller frees) and whether the back-end said it fell back. */
static pz_metrics *flatten(const pz_pattern *pattern, int backend, int *fell_back)
{
    double *uv = malloc((size_t)pattern->mesh->vertex_count * 2 * sizeof(double));
    REQUIRE(uv, "out of memory");
    *fell_back = 0;
    if (backend == SPRINGMASS || backend == ORTHOTROPIC) {
        pz_springmass_options options = {.orthotropic = backend == ORTHOTROPIC};
        pz_springmass_result result;
        REQUIRE_OK(pz_param_springmass(pattern, &options, uv, &result, &ctx), ctx);
        *fell_back = result.retried_panels > 0;
        pz_springmass_result_clear(&result);
    } else if (backend == WIREWARP) {
        pz_wirewarp_result result;
        REQUIRE_OK(pz_param_wirewarp(pattern, NULL, NULL, uv, &result, &ctx), ctx);
        *fell_back = result.best_effort;
    } else {
        REQUIRE_OK(pz_param_textile(pattern, NULL, uv, NULL, &ctx), ctx);
    }
    pz_metrics *metrics = NULL;
    REQUIRE_OK(pz_metrics_compute(pattern, uv, 0, NULL, &metrics, &ctx), ctx);
    free(uv);
    return metrics;
}

static void test_slivers(const char *name, int every, double height, int needles, int on_surface)
{
    double *flat = NULL;
    pz_mesh *mesh = sliver_panel(every, height, needles, on_surface, &flat);
    double thin = thinnest(mesh, flat);
    free(flat);
    int32_t *panels = calloc((size_t)mesh->face_count, sizeof(int32_t));
    REQUIRE(panels, "out of memory");
    pz_pattern *pattern = NULL;
    REQUIRE_OK(pz_pattern_build(mesh, panels, NULL, NULL, name, &pattern, &ctx), ctx);
    free(panels);
    CHECK(thin < 1e-3, "%s: the thinnest face has height %.2g of its longest edge: no sliver", name, thin);
    for (int backend = SPRINGMASS; backend <= TEXTILE; ++backend) {
        int fell_back = 0;
        pz_metrics *metrics = flatten(pattern, backend, &fell_back);
        printf("%s, %s: thinnest face %.2g, max |strain| %.4g, injective %d%s\n", name, backend_names[backend],
               thin, metrics->max_abs_strain, metrics->injective, fell_back ? ", fell back" : "");
        CHECK(metrics->injective, "%s, %s: not injective", name, backend_names[backend]);
        /* Developable: the true pattern has no strain, and a sliver must not blow it up (issue 17: 31,772). */
        CHECK(metrics->max_abs_strain < 0.5, "%s, %s: max |strain| %g", name, backend_names[backend],
              metrics->max_abs_strain);
        pz_metrics_free(&metrics);
    }
    pz_pattern_free(&pattern);
    pz_mesh_free(&mesh);
}

int main(void)
{
    pz_ctx_init(&ctx);
    ctx.quiet = 1;
    test_slivers("caps of height 1e-4", 7, 1e-4, 0, 0);
    test_slivers("needles 1e-4 long", 5, 1e-4, 1, 0);
    test_slivers("caps of height 1e-7", 3, 1e-7, 0, 0);
    test_slivers("caps on the cylinder", 7, 1e-4, 0, 1);
    test_slivers("needles on the cylinder", 5, 1e-4, 1, 1);
    return test_finish();
}

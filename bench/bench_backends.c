/*
 * bench/bench_backends.c -- the comparison table of the flattening back-ends,
 * like wang2008's Table 1: for every back-end in `backends` below and every
 * mesh (generated quarter-sphere, hemisphere, saddle, open cylinder and
 * cone, the bodice cut into front and back; and, when ../shared/data is
 * there, surfaces/hemisphere.obj, saddle.obj, face-scan.obj, camelhead.off,
 * max-planck.obj, nefertiti.off, mannequin.off, in mm) one line:
 *   bench_backends backend=... mesh=... faces=... E_len=... E_ang=... E_area=...
 *                  E_shape=... max_strain=... orthotropic_energy=... ms=...
 * E_len, E_ang, E_area, E_shape are pz_metrics_compute's per-panel figures
 * averaged over panels weighted by face count; max_strain is the largest
 * |warp or weft strain|; orthotropic_energy (mccartney2005 Eq. 9, N*mm) is
 * summed over panels; ms is the best of 3 runs (of 1 above 20K faces or
 * when the first run took over a second), metrics not included. A back-end is one table entry: a name, a
 * function flattening a whole pattern and a face limit (spring-mass with
 * full relaxation, O(faces^2), is skipped above FULL_RELAX_MAX_FACES).
 * Back-ends: WireWarping global and progressive, LSCM, textile, spring-mass
 * with heap (IISERM) and full (wang2002) relaxation. Usage: bench_backends [DATA_DIR]
 * (default $PZ_SHARED_DATA, then ../shared/data).
 *
 * SPDX-License-Identifier: GPL-3.0-or-later
 */
#include "param/param.h"

#include <stdio.h>
#include <stdlib.h>
#include <string.h>

typedef pz_status (*backend_fn)(const pz_pattern *pattern, double *uv, pz_ctx *ctx);

static pz_status run_wirewarp_global(const pz_pattern *pattern, double *uv, pz_ctx *ctx)
{
    pz_wirewarp_options options = {.scheme = 0};
    return pz_param_wirewarp(pattern, &options, NULL, uv, NULL, ctx);
}

static pz_status run_wirewarp_progressive(const pz_pattern *pattern, double *uv, pz_ctx *ctx)
{
    pz_wirewarp_options options = {.scheme = 1};
    return pz_param_wirewarp(pattern, &options, NULL, uv, NULL, ctx);
}

static pz_status run_lscm(const pz_pattern *pattern, double *uv, pz_ctx *ctx)
{
    return pz_param_lscm_pattern(pattern, NULL, uv, ctx);
}

static pz_status run_textile(const pz_pattern *pattern, double *uv, pz_ctx *ctx)
{
    return pz_param_textile(pattern, NULL, uv, NULL, ctx);
}

static pz_status run_springmass_heap(const pz_pattern *pattern, double *uv, pz_ctx *ctx)
{
    return pz_param_springmass(pattern, NULL, uv, NULL, ctx);
}

static pz_status run_springmass_full(const pz_pattern *pattern, double *uv, pz_ctx *ctx)
{
    pz_springmass_options options = {.relax = 1};
    return pz_param_springmass(pattern, &options, uv, NULL, ctx);
}

/* Full relaxation grows as faces^2 (38 s at 20K faces; on the tangled
 * 8K-face max-planck every triangle runs its 50 sweeps): skipped above this. */
#define FULL_RELAX_MAX_FACES 5000
/* A back-end whose first run takes longer than this is run once. */
#define REPEAT_BELOW_MS 1000

/* The back-ends compared: add a row here (max_faces 0: no limit). */
static const struct {
    const char *name;
    backend_fn run;
    int32_t max_faces;
} backends[] = {
    {"wirewarp-global", run_wirewarp_global, 0},
    {"wirewarp-progressive", run_wirewarp_progressive, 0},
    {"lscm", run_lscm, 0},
    {"textile", run_textile, 0},
    {"springmass-heap", run_springmass_heap, 0},
    {"springmass-full", run_springmass_full, FULL_RELAX_MAX_FACES},
};

static void measure(const char *mesh_name, const pz_pattern *pattern)
{
    pz_ctx ctx;
    pz_ctx_init(&ctx);
    ctx.quiet = 1;
    int32_t nf = pattern->mesh->face_count;
    double *uv = malloc((size_t)pattern->mesh->vertex_count * 2 * sizeof(double) + 1);
    if (!uv)
        return;
    for (size_t b = 0; b < sizeof backends / sizeof backends[0]; ++b) {
        if (backends[b].max_faces > 0 && nf > backends[b].max_faces) {
            printf("bench_backends backend=%s mesh=%s faces=%d skipped=\"more than %d faces\"\n", backends[b].name,
                   mesh_name, nf, backends[b].max_faces);
            continue;
        }
        double best = 1e300;
        pz_status status = PZ_OK;
        int runs = nf > 20000 ? 1 : 3;
        for (int run = 0; run < runs && !status; ++run) {
            double start = pz_seconds();
            status = backends[b].run(pattern, uv, &ctx);
            double ms = 1e3 * (pz_seconds() - start);
            best = ms < best ? ms : best;
            if (ms > REPEAT_BELOW_MS)
                runs = 1;
        }
        pz_metrics *m = NULL;
        if (!status)
            status = pz_metrics_compute(pattern, uv, 0, NULL, &m, &ctx);
        if (status) {
            printf("bench_backends backend=%s mesh=%s faces=%d error=\"%s\"\n", backends[b].name, mesh_name, nf,
                   ctx.error);
            continue;
        }
        double e_len = 0, e_ang = 0, e_area = 0, e_shape = 0, energy = 0;
        for (int32_t p = 0; p < m->panel_count; ++p) {
            const pz_panel_metrics *pm = &m->panels[p];
            double weight = (double)pm->face_count / nf;
            e_len += weight * pm->e_len;
            e_ang += weight * pm->e_ang;
            e_area += weight * pm->e_area;
            e_shape += weight * pm->e_shape;
            energy += pm->orthotropic_energy;
        }
        printf("bench_backends backend=%s mesh=%s faces=%d E_len=%.3g E_ang=%.4g E_area=%.4g E_shape=%.4g "
               "max_strain=%.4g orthotropic_energy=%.4g ms=%.2f\n",
               backends[b].name, mesh_name, nf, e_len, e_ang, e_area, e_shape, m->max_abs_strain, energy, best);
        fflush(stdout);
        pz_metrics_free(&m);
    }
    free(uv);
}

/* One pattern per mesh: `split` 1 cuts into front (y >= 0) and back by face centroid. */
static void bench_mesh(const char *name, pz_mesh *mesh, int split)
{
    pz_ctx ctx;
    pz_ctx_init(&ctx);
    ctx.quiet = 1;
    int32_t *face_panel = calloc((size_t)mesh->face_count + 1, sizeof(int32_t));
    pz_pattern *pattern = NULL;
    if (!face_panel)
        return;
    for (int32_t f = 0; split && f < mesh->face_count; ++f) {
        double y = 0;
        for (int k = 0; k < 3; ++k)
            y += mesh->positions[3 * mesh->faces[3 * f + k] + 1];
        face_panel[f] = y < 0;
    }
    if (pz_pattern_build(mesh, face_panel, NULL, NULL, name, &pattern, &ctx))
        printf("bench_backends mesh=%s faces=%d error=\"%s\"\n", name, mesh->face_count, ctx.error);
    else
        measure(name, pattern);
    pz_pattern_free(&pattern);
    free(face_panel);
}

int main(int argc, char **argv)
{
    pz_ctx ctx;
    pz_ctx_init(&ctx);
    ctx.quiet = 1;
    static const struct {
        pz_shape shape;
        int32_t faces;
        int open, split;
        const char *name;
    } generated[] = {
        {PZ_SHAPE_QUARTER_SPHERE, 2000, 0, 0, "quarter-sphere"},
        {PZ_SHAPE_HEMISPHERE, 2000, 0, 0, "hemisphere"},
        {PZ_SHAPE_SADDLE, 2000, 0, 0, "saddle"},
        {PZ_SHAPE_CYLINDER, 2000, 1, 0, "cylinder-open"},
        {PZ_SHAPE_CONE, 2000, 1, 0, "cone-open"},
        {PZ_SHAPE_BODICE, 4000, 0, 1, "bodice-halves"},
        {PZ_SHAPE_QUARTER_SPHERE, 20000, 0, 0, "quarter-sphere-20k"},
    };
    for (size_t i = 0; i < sizeof generated / sizeof generated[0]; ++i) {
        pz_generate_options options = {.target_faces = generated[i].faces, .open = generated[i].open};
        pz_mesh *mesh = NULL;
        if (pz_generate(generated[i].shape, &options, &mesh, &ctx)) {
            printf("bench_backends mesh=%s error=\"%s\"\n", generated[i].name, ctx.error);
            continue;
        }
        bench_mesh(generated[i].name, mesh, generated[i].split);
        pz_mesh_free(&mesh);
    }
    const char *dir = argc > 1 ? argv[1] : getenv("PZ_SHARED_DATA");
    if (!dir || !*dir)
        dir = "../shared/data";
    static const char *surfaces[] = {"hemisphere.obj", "saddle.obj", "face-scan.obj", "camelhead.off",
                                     "max-planck.obj", "nefertiti.off", "mannequin.off"};
    for (size_t i = 0; i < sizeof surfaces / sizeof surfaces[0]; ++i) {
        char path[4200];
        snprintf(path, sizeof path, "%s/surfaces/%s", dir, surfaces[i]);
        pz_mesh *mesh = NULL;
        if (pz_mesh_read(path, &mesh, &ctx)) {
            printf("bench_backends mesh=%s skipped=\"%s\"\n", surfaces[i], ctx.error);
            continue;
        }
        pz_units used;
        pz_mesh_to_mm(mesh, PZ_UNITS_AUTO, &used);
        if (pz_mesh_prepare(mesh, path, PZ_REPAIR_NONE, &ctx))
            printf("bench_backends mesh=%s skipped=\"%s\"\n", surfaces[i], ctx.error);
        else
            bench_mesh(surfaces[i], mesh, 0);
        pz_mesh_free(&mesh);
    }
    return 0;
}

/*
 * bench/bench_backends.c -- the comparison table of the flattening back-ends,
 * like wang2008's Table 1: for every back-end in `backends` below and every
 * mesh (generated quarter-sphere, hemisphere, saddle, open cylinder and
 * cone, the bodice cut into front and back; and, when ../shared/data is
 * there, the two-panel skirt of seams/ with its seam and dart files, and
 * surfaces/hemisphere.obj, saddle.obj, face-scan.obj, camelhead.off,
 * max-planck.obj, nefertiti.off, mannequin.off, in mm) one line:
 *   bench_backends backend=... mesh=... faces=... E_len=... E_ang=... E_area=...
 *                  E_shape=... max_strain=... orthotropic_energy=... seam_mismatch=...
 *                  ms=... cpu_ms=...
 * E_len, E_ang, E_area, E_shape are pz_metrics_compute's per-panel figures
 * averaged over panels weighted by face count; max_strain is the largest
 * |warp or weft strain|; orthotropic_energy (mccartney2005 Eq. 9, N*mm) is
 * summed over panels; seam_mismatch is the worst |side a - side b| / 3D
 * length over the seams and darts (pz_metrics_compute; 0 with one panel and
 * no dart); ms (wall) and cpu_ms (this process's CPU time, which other
 * programs on the machine do not inflate) are the best of 3 runs (of 1 above
 * 20K faces or when the first run took over a second), metrics not
 * included. The load average is printed first. A back-end is one table entry: a name, a
 * function flattening a whole pattern and a face limit (spring-mass with
 * full relaxation, O(faces^2), is skipped above FULL_RELAX_MAX_FACES, the
 * orthotropic one above ORTHO_MAX_FACES).
 * Back-ends: WireWarping global and progressive, LSCM, textile, spring-mass
 * with heap (IISERM) and full (wang2002) relaxation, and orthotropic
 * spring-mass (mccartney2005's energy, heap relaxation). Two more rows run
 * the WireWarping schemes on the 2K quarter-sphere with its meridian as a
 * feature curve (accessory, then key), where the schemes differ (Table 1).
 * Usage: bench_backends [DATA_DIR]
 * (default $PZ_SHARED_DATA, then ../shared/data).
 *
 * SPDX-License-Identifier: GPL-3.0-or-later
 */
#define _POSIX_C_SOURCE 200809L
#include "generate/generate.h"
#include "io/io.h"
#include "param/param.h"
#include "bench_util.h"

#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <time.h>

/* CPU time of this process, seconds. */
static double cpu_seconds(void)
{
    struct timespec now;
    clock_gettime(CLOCK_PROCESS_CPUTIME_ID, &now);
    return (double)now.tv_sec + 1e-9 * (double)now.tv_nsec;
}

/* Flattens a whole pattern; features (may be NULL) are WireWarping's feature curves, ignored by the others. */
typedef pz_status (*backend_fn)(const pz_pattern *pattern, const pz_feature_curves *features, double *uv,
                                pz_ctx *ctx);

static pz_status run_wirewarp_global(const pz_pattern *pattern, const pz_feature_curves *features, double *uv,
                                     pz_ctx *ctx)
{
    pz_wirewarp_options options = {.scheme = 0};
    return pz_param_wirewarp(pattern, &options, features, uv, NULL, ctx);
}

static pz_status run_wirewarp_progressive(const pz_pattern *pattern, const pz_feature_curves *features, double *uv,
                                          pz_ctx *ctx)
{
    pz_wirewarp_options options = {.scheme = 1};
    return pz_param_wirewarp(pattern, &options, features, uv, NULL, ctx);
}

static pz_status run_lscm(const pz_pattern *pattern, const pz_feature_curves *features, double *uv, pz_ctx *ctx)
{
    (void)features;
    return pz_param_lscm_pattern(pattern, NULL, uv, ctx);
}

static pz_status run_textile(const pz_pattern *pattern, const pz_feature_curves *features, double *uv, pz_ctx *ctx)
{
    (void)features;
    return pz_param_textile(pattern, NULL, uv, NULL, ctx);
}

static pz_status run_springmass_heap(const pz_pattern *pattern, const pz_feature_curves *features, double *uv,
                                     pz_ctx *ctx)
{
    (void)features;
    return pz_param_springmass(pattern, NULL, uv, NULL, ctx);
}

static pz_status run_springmass_full(const pz_pattern *pattern, const pz_feature_curves *features, double *uv,
                                     pz_ctx *ctx)
{
    (void)features;
    pz_springmass_options options = {.relax = 1};
    return pz_param_springmass(pattern, &options, uv, NULL, ctx);
}

/* McCartney's warp/weft/shear energy with the paper's fabric constants, grain +z, heap relaxation. */
static pz_status run_springmass_ortho(const pz_pattern *pattern, const pz_feature_curves *features, double *uv,
                                      pz_ctx *ctx)
{
    (void)features;
    pz_springmass_options options = {.orthotropic = 1};
    return pz_param_springmass(pattern, &options, uv, NULL, ctx);
}

/* Full relaxation grows as faces^2 (38 s at 20K faces; on the tangled
 * 8K-face max-planck every triangle runs its 50 sweeps): skipped above this. */
#define FULL_RELAX_MAX_FACES 5000
/* Orthotropic spring-mass relaxes with ISERM's node sweeps only (docs/springmass.md): 11 s of CPU at 20K
 * faces, 12 s on the 34K face scan, where it ends on its LSCM second try; skipped above this. */
#define ORTHO_MAX_FACES 20000
/* A back-end whose first run takes longer than this is run once. */
#define REPEAT_BELOW_MS 1000

/* The back-ends compared: add a row here (max_faces 0: no limit; features 1: takes feature curves, the only
 * ones run on a mesh with curves). */
static const struct {
    const char *name;
    backend_fn run;
    int32_t max_faces;
    int features;
} backends[] = {
    {"wirewarp-global", run_wirewarp_global, 0, 1},
    {"wirewarp-progressive", run_wirewarp_progressive, 0, 1},
    {"lscm", run_lscm, 0, 0},
    {"textile", run_textile, 0, 0},
    {"springmass-heap", run_springmass_heap, 0, 0},
    {"springmass-full", run_springmass_full, FULL_RELAX_MAX_FACES, 0},
    {"springmass-ortho", run_springmass_ortho, ORTHO_MAX_FACES, 0},
};

static void measure(const char *mesh_name, const pz_pattern *pattern, const pz_feature_curves *features)
{
    pz_ctx ctx;
    pz_ctx_init(&ctx);
    ctx.quiet = 1;
    int32_t nf = pattern->mesh->face_count;
    double *uv = malloc((size_t)pattern->mesh->vertex_count * 2 * sizeof(double) + 1);
    if (!uv)
        return;
    for (size_t b = 0; b < sizeof backends / sizeof backends[0]; ++b) {
        if (features && !backends[b].features)
            continue;
        if (backends[b].max_faces > 0 && nf > backends[b].max_faces) {
            printf("bench_backends backend=%s mesh=%s faces=%d skipped=\"more than %d faces\"\n", backends[b].name,
                   mesh_name, nf, backends[b].max_faces);
            continue;
        }
        double best = 1e300, best_cpu = 1e300;
        pz_status status = PZ_OK;
        int runs = nf > 20000 ? 1 : 3;
        for (int run = 0; run < runs && !status; ++run) {
            double start = pz_seconds(), cpu_start = cpu_seconds();
            status = backends[b].run(pattern, features, uv, &ctx);
            double ms = 1e3 * (pz_seconds() - start), cpu_ms = 1e3 * (cpu_seconds() - cpu_start);
            best = ms < best ? ms : best;
            best_cpu = cpu_ms < best_cpu ? cpu_ms : best_cpu;
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
        double mismatch = m->max_seam_mismatch_rel;
        for (int32_t d = 0; d < m->dart_count; ++d)
            mismatch = fmax(mismatch, m->darts[d].mismatch_rel);
        printf("bench_backends backend=%s mesh=%s faces=%d E_len=%.3g E_ang=%.4g E_area=%.4g E_shape=%.4g "
               "max_strain=%.4g orthotropic_energy=%.4g seam_mismatch=%.3g ms=%.2f cpu_ms=%.2f\n",
               backends[b].name, mesh_name, nf, e_len, e_ang, e_area, e_shape, m->max_abs_strain, energy, mismatch,
               best, best_cpu);
        fflush(stdout);
        pz_metrics_free(&m);
    }
    free(uv);
}

/* The `a b` pairs after `header` lines of a seam or dart file (ids within their files); -1 when unreadable. */
static int32_t read_pairs(const char *path, int32_t *header, int header_count, int32_t **pairs)
{
    FILE *file = fopen(path, "r");
    int32_t count = 0, capacity = 64, a, b;
    *pairs = malloc((size_t)capacity * 2 * sizeof(int32_t));
    for (int k = 0; file && *pairs && k < header_count; ++k)
        if (fscanf(file, "%d", &header[k]) != 1)
            count = -1;
    while (file && *pairs && count >= 0 && fscanf(file, "%d %d", &a, &b) == 2) {
        if (count == capacity) {
            int32_t *bigger = realloc(*pairs, (size_t)(capacity *= 2) * 2 * sizeof(int32_t));
            if (!bigger)
                break;
            *pairs = bigger;
        }
        (*pairs)[2 * count] = a;
        (*pairs)[2 * count++ + 1] = b;
    }
    if (file)
        fclose(file);
    return file && *pairs ? count : -1;
}

/* The shared two-panel skirt (seams/skirt_0.obj, skirt_1.obj in mm) with its seam and dart files, as
 * `panelize flatten` reads them (ids within each file); NULL when missing or unreadable. */
static pz_pattern *skirt_pattern(const char *dir, pz_mesh **garment, pz_ctx *ctx)
{
    pz_mesh *part[2] = {NULL, NULL};
    char path[4200];
    for (int k = 0; k < 2; ++k) {
        snprintf(path, sizeof path, "%s/seams/skirt_%d.obj", dir, k);
        pz_units used;
        if (pz_mesh_read(path, &part[k], ctx))
            break;
        pz_mesh_to_mm(part[k], PZ_UNITS_AUTO, &used);
    }
    pz_pattern *pattern = NULL;
    pz_correspondences given = {0};
    pz_seam seams[2] = {{0}};
    pz_dart darts[4] = {{0}};
    int32_t *face_panel = NULL, offset[2] = {0, part[0] ? part[0]->vertex_count : 0};
    if (!part[0] || !part[1] ||
        pz_mesh_create(offset[1] + part[1]->vertex_count, part[0]->face_count + part[1]->face_count, garment, ctx))
        goto done;
    face_panel = malloc((size_t)(*garment)->face_count * sizeof(int32_t));
    for (int k = 0, f0 = 0; k < 2 && face_panel; f0 += part[k]->face_count, ++k) {
        memcpy((*garment)->positions + 3 * offset[k], part[k]->positions, (size_t)part[k]->vertex_count * 3 * sizeof(double));
        for (int32_t f = 0; f < part[k]->face_count; ++f) {
            face_panel[f0 + f] = k;
            for (int c = 0; c < 3; ++c)
                (*garment)->faces[3 * (f0 + f) + c] = part[k]->faces[3 * f + c] + offset[k];
        }
    }
    for (int s = 0; s < 2 && face_panel; ++s) {
        int32_t panels[2], *pairs = NULL;
        snprintf(path, sizeof path, "%s/seams/seam%d.txt", dir, s);
        int32_t n = read_pairs(path, panels, 2, &pairs);
        seams[s].side_a = malloc((size_t)(n > 0 ? n : 1) * sizeof(int32_t));
        seams[s].side_b = malloc((size_t)(n > 0 ? n : 1) * sizeof(int32_t));
        for (int32_t i = 0; i < n && seams[s].side_a && seams[s].side_b; ++i) {
            seams[s].side_a[i] = pairs[2 * i] + offset[panels[0] & 1];
            seams[s].side_b[i] = pairs[2 * i + 1] + offset[panels[1] & 1];
        }
        seams[s].pair_count = n > 0 ? n : 0;
        free(pairs);
    }
    for (int d = 0; d < 4 && face_panel; ++d) {
        int32_t tip, *pairs = NULL, panel = d / 2;
        snprintf(path, sizeof path, "%s/seams/patch_%d_dart_%d.txt", dir, panel, d % 2);
        int32_t n = read_pairs(path, &tip, 1, &pairs);
        darts[d].leg_a = malloc((size_t)(n > 0 ? n : 1) * sizeof(int32_t));
        darts[d].leg_b = malloc((size_t)(n > 0 ? n : 1) * sizeof(int32_t));
        for (int32_t i = 0; i < n && darts[d].leg_a && darts[d].leg_b; ++i) {
            darts[d].leg_a[i] = pairs[2 * i] + offset[panel];
            darts[d].leg_b[i] = pairs[2 * i + 1] + offset[panel];
        }
        darts[d].tip = tip + offset[panel];
        darts[d].panel = panel;
        darts[d].pair_count = n > 0 ? n : 0;
        free(pairs);
    }
    given.seam_count = 2;
    given.seams = seams;
    given.dart_count = 4;
    given.darts = darts;
    if (face_panel && pz_pattern_build(*garment, face_panel, NULL, &given, "skirt", &pattern, ctx))
        pattern = NULL;
done:
    for (int k = 0; k < 2; ++k) {
        free(seams[k].side_a);
        free(seams[k].side_b);
        pz_mesh_free(&part[k]);
    }
    for (int d = 0; d < 4; ++d) {
        free(darts[d].leg_a);
        free(darts[d].leg_b);
    }
    free(face_panel);
    return pattern;
}

/* One pattern per mesh: `split` 1 cuts into front (y >= 0) and back by face centroid; `line` (may be NULL)
 * is snapped into a feature curve for WireWarping (then only the back-ends taking curves run). */
static void bench_mesh(const char *name, pz_mesh *mesh, int split, const pz_feature_polyline *line)
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
    pz_feature_curves *features = NULL;
    if (pz_pattern_build(mesh, face_panel, NULL, NULL, name, &pattern, &ctx) ||
        (line && pz_feature_curves_snap(pattern, line, 1, 0, &features, &ctx)))
        printf("bench_backends mesh=%s faces=%d error=\"%s\"\n", name, mesh->face_count, ctx.error);
    else
        measure(name, pattern, features);
    pz_feature_curves_free(&features);
    pz_pattern_free(&pattern);
    free(face_panel);
}

int main(int argc, char **argv)
{
    pz_ctx ctx;
    pz_ctx_init(&ctx);
    ctx.quiet = 1;
    printf("bench_backends load_average=%.2f\n", bench_load_average());
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
        bench_mesh(generated[i].name, mesh, generated[i].split, NULL);
        pz_mesh_free(&mesh);
    }
    /* wang2008 Table 1's point: with a feature curve the global scheme spreads the distortion over both
     * wire-patches and the progressive one does not. The quarter-sphere's meridian y = 0 from the pole to the
     * equator (radius 150 mm), as an accessory and as a key curve. */
    double meridian[21 * 3];
    for (int i = 0; i <= 20; ++i) {
        double a = 3.14159265358979323846 / 2 * i / 20;
        meridian[3 * i] = 150 * sin(a);
        meridian[3 * i + 1] = 0;
        meridian[3 * i + 2] = 150 * cos(a);
    }
    static const struct {
        pz_feature_kind kind;
        const char *name;
    } curve_rows[] = {{PZ_FEATURE_ACCESSORY, "quarter-sphere+meridian-accessory"},
                      {PZ_FEATURE_KEY, "quarter-sphere+meridian-key"}};
    for (size_t i = 0; i < sizeof curve_rows / sizeof curve_rows[0]; ++i) {
        pz_generate_options options = {.target_faces = 2000};
        pz_feature_polyline line = {.kind = curve_rows[i].kind, .point_count = 21, .points = meridian};
        pz_mesh *mesh = NULL;
        if (pz_generate(PZ_SHAPE_QUARTER_SPHERE, &options, &mesh, &ctx)) {
            printf("bench_backends mesh=%s error=\"%s\"\n", curve_rows[i].name, ctx.error);
            continue;
        }
        bench_mesh(curve_rows[i].name, mesh, 0, &line);
        pz_mesh_free(&mesh);
    }
    const char *dir = argc > 1 ? argv[1] : getenv("PZ_SHARED_DATA");
    if (!dir || !*dir)
        dir = "../shared/data";
    pz_mesh *skirt = NULL;
    pz_pattern *pattern = skirt_pattern(dir, &skirt, &ctx);
    if (pattern)
        measure("skirt-seams", pattern, NULL);
    else
        printf("bench_backends mesh=skirt skipped=\"%s\"\n", ctx.error);
    pz_pattern_free(&pattern);
    pz_mesh_free(&skirt);
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
            bench_mesh(surfaces[i], mesh, 0, NULL);
        pz_mesh_free(&mesh);
    }
    return 0;
}

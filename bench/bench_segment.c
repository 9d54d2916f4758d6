/*
 * bench/bench_segment.c -- the automatic layout (pz_segment) at the defaults
 * (S = 0.05, C = 8, darts, symmetry auto) on every garment of
 * ../shared/data/garments (skipped when missing; meshes that fail
 * validation are reported and skipped) and on pz_generate's bodice at 7K
 * and 50K faces (PZ_SHARED_DATA, else ../shared/data or ../../shared/data).
 * One machine-readable line per mesh:
 *
 *   bench_segment mesh=bodice faces=7000 panels=6 darts=2 worst_strain=0.041 goals_met=1
 *     field_ms=... graph_ms=... candidates_ms=... insert_ms=... remove_ms=... darts_ms=... segment_ms=...
 *     segment_cpu_ms=... (CPU time of all threads: steadier than segment_ms when the cores are shared)
 *     evaluations=... symmetry=AXIS|-1 layout_residual_mm=... load=...
 *
 *   bench_segment [MESH|SHAPE:FACES]...   (SHAPE a pz_generate shape: bodice:3000, skirt:7000, ...;
 *                                          default: the shared garments, bodice:7000, bodice:50000)
 *
 * Target (docs/segment.md): the whole `run` on a 7K-face garment under 2 s,
 * a 50K-face bodice under 10 s on 2 cores, so segment_ms must stay well
 * below that. Exit status 1 when a step fails.
 *
 * SPDX-License-Identifier: GPL-3.0-or-later
 */
#define _POSIX_C_SOURCE 200809L
#include "field/field.h"
#include "generate/generate.h"
#include "io/io.h"
#include "segment/segment.h"

#include <dirent.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <time.h>

#include "bench_util.h"

/* CPU seconds of the process (all threads): with the cores shared, a steadier figure than the wall clock. */
static double cpu_seconds(void)
{
    struct timespec now;
    clock_gettime(CLOCK_PROCESS_CPUTIME_ID, &now);
    return (double)now.tv_sec + 1e-9 * (double)now.tv_nsec;
}

static int measure(const char *name, pz_mesh *mesh)
{
    pz_ctx ctx;
    pz_ctx_init(&ctx);
    ctx.quiet = 1;
    pz_topology *topology = NULL;
    pz_field *field = NULL;
    pz_segment_result *result = NULL;
    double start = pz_seconds();
    pz_status status = pz_topology_build(mesh, &topology, &ctx);
    if (!status)
        status = pz_field_compute(mesh, topology, NULL, &field, &ctx);
    double field_ms = 1e3 * (pz_seconds() - start);
    pz_segment_options options;
    pz_segment_options_default(&options);
    pz_mesh_vertical_axis(mesh, options.grain);
    double cpu_start = cpu_seconds();
    if (!status)
        status = pz_segment(mesh, topology, field, &options, &result, &ctx);
    double segment_cpu_ms = 1e3 * (cpu_seconds() - cpu_start);
    if (status) {
        fprintf(stderr, "bench_segment: %s: %s\n", name, ctx.error);
    } else {
        double worst = 0;
        for (int32_t p = 0; p < result->panel_count; ++p)
            worst = result->panels[p].goals.max_abs_strain > worst ? result->panels[p].goals.max_abs_strain : worst;
        printf("bench_segment mesh=%s faces=%d panels=%d darts=%d worst_strain=%.4f goals_met=%d field_ms=%.0f "
               "graph_ms=%.0f candidates_ms=%.0f insert_ms=%.0f remove_ms=%.0f darts_ms=%.0f segment_ms=%.0f segment_cpu_ms=%.0f "
               "evaluations=%d symmetry=%d layout_residual_mm=%.2f load=%.2f\n",
               name, (int)mesh->face_count, (int)result->panel_count, (int)result->dart_count, worst,
               result->goals_met, field_ms, result->graph_ms, result->candidates_ms, result->insert_ms,
               result->remove_ms, result->darts_ms, result->total_ms, segment_cpu_ms, (int)result->evaluation_count,
               result->symmetry.found ? result->symmetry.axis : -1, result->symmetry_residual_mm, bench_load_average());
        if (!result->goals_met)
            printf("  reasons: %s\n", result->reasons);
    }
    pz_segment_result_free(&result);
    pz_field_free(&field);
    pz_topology_free(&topology);
    return status ? 1 : 0;
}

static int run_one(const char *spec)
{
    pz_ctx ctx;
    pz_ctx_init(&ctx);
    ctx.quiet = 1;
    pz_mesh *mesh = NULL;
    const char *colon = strchr(spec, ':');
    char shape_name[32] = "";
    if (colon && (size_t)(colon - spec) < sizeof shape_name)
        memcpy(shape_name, spec, (size_t)(colon - spec));
    pz_shape shape = colon ? pz_shape_parse(shape_name) : PZ_SHAPE_UNKNOWN;
    if (shape != PZ_SHAPE_UNKNOWN) {
        pz_generate_options options = {(int32_t)atol(colon + 1), 0, 0};
        if (pz_generate(shape, &options, &mesh, &ctx)) {
            fprintf(stderr, "bench_segment: %s\n", ctx.error);
            return 1;
        }
    } else if (pz_mesh_read(spec, &mesh, &ctx) == PZ_OK) {
        pz_mesh_to_mm(mesh, PZ_UNITS_AUTO, NULL);
        if (pz_mesh_prepare(mesh, spec, PZ_REPAIR_NONE, &ctx)) {
            printf("bench_segment mesh=%s skipped: %s\n", spec, ctx.error);
            pz_mesh_free(&mesh);
            return 0;
        }
    } else {
        fprintf(stderr, "bench_segment: %s\n", ctx.error);
        return 1;
    }
    const char *name = strrchr(spec, '/') ? strrchr(spec, '/') + 1 : spec;
    int code = measure(name, mesh);
    pz_mesh_free(&mesh);
    fflush(stdout);
    return code;
}

static int compare_names(const void *l, const void *r)
{
    return strcmp(*(char *const *)l, *(char *const *)r);
}

/* The shared garments (.obj, .ply), sorted by name. */
static int run_shared(void)
{
    /* PZ_SHARED_DATA, else ../shared/data from the source or the build directory. */
    const char *data = getenv("PZ_SHARED_DATA");
    const char *tries[3] = {data && *data ? data : NULL, "../shared/data", "../../shared/data"};
    char dir[4096];
    DIR *listing = NULL;
    for (int i = 0; i < 3 && !listing; ++i)
        if (tries[i]) {
            snprintf(dir, sizeof dir, "%s/garments", tries[i]);
            listing = opendir(dir);
        }
    if (!listing) {
        printf("bench_segment: no shared garments directory, skipped\n");
        return 0;
    }
    char *names[256];
    int count = 0, failed = 0;
    for (struct dirent *entry; (entry = readdir(listing)) && count < 256;) {
        const char *dot = strrchr(entry->d_name, '.');
        if (dot && (strcmp(dot, ".obj") == 0 || strcmp(dot, ".ply") == 0)) {
            size_t size = strlen(dir) + strlen(entry->d_name) + 2;
            names[count] = malloc(size);
            if (names[count])
                snprintf(names[count++], size, "%s/%s", dir, entry->d_name);
        }
    }
    closedir(listing);
    qsort(names, (size_t)count, sizeof names[0], compare_names);
    for (int i = 0; i < count; ++i) {
        failed |= run_one(names[i]);
        free(names[i]);
    }
    return failed;
}

int main(int argc, char **argv)
{
    int failed = 0;
    if (argc > 1) {
        for (int i = 1; i < argc; ++i)
            failed |= run_one(argv[i]);
        return failed;
    }
    failed |= run_shared();
    failed |= run_one("bodice:7000");
    failed |= run_one("bodice:50000");
    return failed;
}

/*
 * bench/bench_param.c -- speed of the flattening back-ends.
 *
 * For generated hemispheres of about 2K, 20K and 200K faces (one panel each)
 * and, when ../shared/data is there, surfaces/face-scan.obj, runs the textile
 * parameterization (20 iterations, no early stop) and LSCM, and prints one
 * line per run:
 *   bench_param mesh=... backend=textile faces=... init_ms=... iteration_ms=...
 *               total_ms=... iterations=... damped=... threads=... peak_bytes_per_face=... load=...
 * iterations counts the global steps run (the textile iteration stops early
 * when a step cannot lower the energy: docs/param.md, "Monotone steps"),
 * damped those that were backtracked, load is the 1-minute load average
 * (/proc/loadavg) when the run ended: with 2 cores, figures taken at a load
 * above 1 are not comparable.
 * peak_bytes_per_face is the growth of the process's peak resident size
 * (getrusage) during the run divided by the face count; runs go from small
 * to large so each one can raise the peak (0 means it stayed below an
 * earlier peak). Usage: bench_param [MAX_FACES [THREADS]] (default 200000
 * faces, THREADS 0 = pz_param_textile's default: threaded from 100K faces;
 * an explicit count >= 2 threads from 8K faces, see docs/param.md).
 *
 * SPDX-License-Identifier: GPL-3.0-or-later
 */
#define _POSIX_C_SOURCE 200809L
#include "param/param.h"

#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/resource.h>

#include "bench_util.h"

static long peak_kb(void)
{
    struct rusage usage;
    getrusage(RUSAGE_SELF, &usage);
    return usage.ru_maxrss;
}

static int run(const char *name, pz_mesh *mesh, int threads)
{
    pz_ctx ctx;
    pz_ctx_init(&ctx);
    ctx.quiet = 1;
    pz_pattern pattern;
    memset(&pattern, 0, sizeof pattern);
    pattern.mesh = mesh;
    pattern.panel_count = 1;
    pattern.face_panel = calloc((size_t)mesh->face_count, sizeof(int32_t));
    double *uv = malloc((size_t)mesh->vertex_count * 2 * sizeof(double));
    if (!pattern.face_panel || !uv) {
        fprintf(stderr, "bench_param: out of memory\n");
        return 1;
    }
    long before = peak_kb();
    double start = pz_seconds();
    pz_textile_options options = {.iterations = 20, .tolerance = 1e-300, .threads = threads};
    pz_textile_result result;
    if (pz_param_textile(&pattern, &options, uv, &result, &ctx)) {
        fprintf(stderr, "bench_param: %s\n", ctx.error);
        return 1;
    }
    double total = 1e3 * (pz_seconds() - start);
    long after = peak_kb();
    printf("bench_param mesh=%s backend=textile faces=%d init_ms=%.1f iteration_ms=%.2f total_ms=%.1f "
           "iterations=%d bounded=%d damped=%d energy=%.6g threads=%d peak_bytes_per_face=%.0f load=%.2f\n",
           name, mesh->face_count, result.init_ms, result.iteration_ms, total, result.iterations_run,
           result.bounded_steps, result.damped_steps, result.final_energy, threads, 1024.0 * (double)(after - before) / mesh->face_count, bench_load_average());
    before = after;
    start = pz_seconds();
    if (pz_param_lscm_pattern(&pattern, NULL, uv, &ctx)) {
        fprintf(stderr, "bench_param: %s\n", ctx.error);
        return 1;
    }
    total = 1e3 * (pz_seconds() - start);
    printf("bench_param mesh=%s backend=lscm faces=%d init_ms=%.1f iteration_ms=0 total_ms=%.1f "
           "peak_bytes_per_face=%.0f load=%.2f\n",
           name, mesh->face_count, total, total, 1024.0 * (double)(peak_kb() - before) / mesh->face_count,
           bench_load_average());
    fflush(stdout);
    free(uv);
    free(pattern.face_panel);
    return 0;
}

int main(int argc, char **argv)
{
    long max_faces = argc > 1 ? atol(argv[1]) : 200000;
    int threads = argc > 2 ? atoi(argv[2]) : 0;
    pz_ctx ctx;
    pz_ctx_init(&ctx);
    ctx.quiet = 1;
    static const int32_t sizes[] = {2000, 20000, 200000};
    for (size_t i = 0; i < sizeof sizes / sizeof sizes[0]; ++i) {
        if (sizes[i] > max_faces)
            break;
        pz_generate_options options = {.target_faces = sizes[i]};
        pz_mesh *mesh = NULL;
        if (pz_generate(PZ_SHAPE_HEMISPHERE, &options, &mesh, &ctx)) {
            fprintf(stderr, "bench_param: %s\n", ctx.error);
            return 1;
        }
        char name[64];
        snprintf(name, sizeof name, "hemisphere-%d", sizes[i]);
        int failed = run(name, mesh, threads);
        pz_mesh_free(&mesh);
        if (failed)
            return 1;
    }
    const char *shared = getenv("PZ_SHARED_DATA");
    char path[4096];
    snprintf(path, sizeof path, "%s/surfaces/face-scan.obj", shared && *shared ? shared : "../shared/data");
    pz_mesh *scan = NULL;
    if (pz_mesh_read(path, &scan, &ctx) == PZ_OK) {
        pz_mesh_to_mm(scan, PZ_UNITS_AUTO, NULL);
        int failed = run("face-scan", scan, threads);
        pz_mesh_free(&scan);
        if (failed)
            return 1;
    } else {
        printf("bench_param: face-scan skipped (%s)\n", ctx.error);
    }
    return 0;
}

/*
 * bench/bench_param.c -- speed of the flattening back-ends (issue 3,
 * "Benchmark"; the table is in docs/param.md, "Speed").
 *
 * For generated hemispheres of about 2K, 3K, 20K and 200K faces (one panel
 * each) and, when ../shared/data is there, surfaces/face-scan.obj (34K
 * faces), runs the textile parameterization (20 iterations, no early stop on
 * the energy tolerance) and then LSCM alone, each in a forked child so that
 * one run's peak resident size does not hide the next. One line per run:
 *
 *   bench_param mesh=hemisphere-20000 backend=textile faces=19913 threads=0 init_ms=52.1
 *     iteration_ms=6.10 iterations=20 iterations_ms=122.0 total_ms=174.1 cpu_ms=170.2
 *     init_cpu_ms=52.0 iteration_cpu_ms=5.90 bounded=0 damped=1 energy_start=105714 energy_end=30636.2 max_strain=0.2535
 *     peak_mb=31.2 peak_bytes_per_face=1642 load=1.02
 *
 * init_ms: LSCM start and setup; iteration_ms: the mean over the iterations
 * run; iterations_ms: all of them (the time for 20 iterations when
 * iterations=20: the run only stops earlier when no fraction of a step lowers
 * the energy, docs/param.md "Monotone steps"); total_ms: the whole call
 * (wall), cpu_ms its CPU time (all threads; compare it with total_ms when
 * the machine is busy), init_cpu_ms the CPU time until the start's energy
 * is reported (on_iteration's iteration 0) and iteration_cpu_ms the mean
 * from there to the last iterate's. bounded / damped: steps shortened so no face flips /
 * backtracked because the energy rose; energy_start / energy_end: Eq. 10 at
 * the start and the end; max_strain: the worst |warp| or |weft| strain of the
 * result (pz_metrics_compute, not timed). peak_mb: the child's peak resident
 * size (VmHWM) over its size before the call, in MB and per face. load: the
 * 1-minute load average when the run ended (2 cores: above 1, other work
 * competes for them).
 *
 *   bench_param [MAX_FACES [THREADS]]
 *
 * MAX_FACES (default 200000) skips the larger hemispheres; THREADS (default
 * 0 = pz_param_textile's default: threaded from 100K faces, and only when
 * the load average leaves a second core; an explicit count >= 2 threads
 * from 8K faces, docs/param.md "Threads"). load= is what getloadavg
 * reports (docs/param.md "Speed" also measures with it faked to 0, which
 * is how libgomp's dynamic teams see a machine that has been idle).
 *
 * SPDX-License-Identifier: GPL-3.0-or-later
 */
#define _POSIX_C_SOURCE 200809L
#include "generate/generate.h"
#include "io/io.h"
#include "param/param.h"

#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/types.h>
#include <sys/wait.h>
#include <time.h>
#include <unistd.h>

#include "bench_util.h"

/* Wall time, CPU time and peak resident size of one call. */
typedef struct run_clock {
    long before_kb;
    double start, cpu_start;
    double total_ms, cpu_ms, peak_mb, peak_bytes_per_face;
} run_clock;

static run_clock clock_start(void)
{
    run_clock clock = {.before_kb = bench_status_kb("VmRSS"), .start = pz_seconds(), .cpu_start = bench_cpu_seconds()};
    return clock;
}

/* Times since clock_start, and the peak resident size since then over the
 * size then (at least 0). */
static void clock_stop(run_clock *clock, int32_t faces)
{
    clock->total_ms = 1e3 * (pz_seconds() - clock->start);
    clock->cpu_ms = 1e3 * (bench_cpu_seconds() - clock->cpu_start);
    long peak_kb = bench_status_kb("VmHWM") - clock->before_kb;
    peak_kb = peak_kb > 0 ? peak_kb : 0;
    clock->peak_mb = peak_kb / 1024.0;
    clock->peak_bytes_per_face = 1024.0 * peak_kb / faces;
}

static int run_textile(const char *name, const pz_pattern *pattern, int threads, double *uv, pz_ctx *ctx)
{
    const pz_mesh *mesh = pattern->mesh;
    bench_iteration_cpu cpu = {0, 0};
    run_clock clock = clock_start();
    pz_textile_options options = {.iterations = 20, .tolerance = 1e-300, .threads = threads,
                                  .on_iteration = bench_record_cpu, .user = &cpu};
    pz_textile_result result;
    if (pz_param_textile(pattern, &options, uv, &result, ctx)) {
        fprintf(stderr, "bench_param: %s: %s\n", name, ctx->error);
        return 1;
    }
    clock_stop(&clock, mesh->face_count);
    pz_metrics *metrics = NULL;
    double max_strain = -1;
    if (pz_metrics_compute(pattern, uv, 0, NULL, &metrics, ctx) == PZ_OK)
        max_strain = metrics->max_abs_strain;
    pz_metrics_free(&metrics);
    int iterations = result.iterations_run > 0 ? result.iterations_run : 1;
    printf("bench_param mesh=%s backend=textile faces=%d threads=%d init_ms=%.1f iteration_ms=%.2f iterations=%d "
           "iterations_ms=%.1f total_ms=%.1f cpu_ms=%.1f init_cpu_ms=%.1f iteration_cpu_ms=%.2f bounded=%d damped=%d "
           "energy_start=%.6g energy_end=%.6g max_strain=%.4f peak_mb=%.1f peak_bytes_per_face=%.0f load=%.2f\n",
           name, mesh->face_count, threads, result.init_ms, result.iteration_ms, result.iterations_run,
           result.solve_ms, clock.total_ms, clock.cpu_ms, 1e3 * (cpu.start - clock.cpu_start),
           1e3 * (cpu.last - cpu.start) / iterations, result.bounded_steps, result.damped_steps,
           result.initial_energy, result.final_energy, max_strain, clock.peak_mb, clock.peak_bytes_per_face,
           bench_load_average());
    return 0;
}

static int run_lscm(const char *name, const pz_pattern *pattern, double *uv, pz_ctx *ctx)
{
    run_clock clock = clock_start();
    if (pz_param_lscm_pattern(pattern, NULL, uv, ctx)) {
        fprintf(stderr, "bench_param: %s: %s\n", name, ctx->error);
        return 1;
    }
    clock_stop(&clock, pattern->mesh->face_count);
    printf("bench_param mesh=%s backend=lscm faces=%d total_ms=%.1f cpu_ms=%.1f peak_mb=%.1f "
           "peak_bytes_per_face=%.0f load=%.2f\n",
           name, pattern->mesh->face_count, clock.total_ms, clock.cpu_ms, clock.peak_mb, clock.peak_bytes_per_face,
           bench_load_average());
    return 0;
}

/* The mesh of one run: a generated hemisphere (faces > 0) or the face scan. */
static pz_mesh *load_mesh(int32_t faces, char *name, size_t name_size, pz_ctx *ctx)
{
    pz_mesh *mesh = NULL;
    if (faces > 0) {
        pz_generate_options options = {.target_faces = faces};
        if (pz_generate(PZ_SHAPE_HEMISPHERE, &options, &mesh, ctx))
            return NULL;
        snprintf(name, name_size, "hemisphere-%d", faces);
        return mesh;
    }
    const char *shared = getenv("PZ_SHARED_DATA");
    char path[4096];
    snprintf(path, sizeof path, "%s/surfaces/face-scan.obj", shared && *shared ? shared : "../shared/data");
    if (pz_mesh_read(path, &mesh, ctx))
        return NULL;
    pz_mesh_to_mm(mesh, PZ_UNITS_AUTO, NULL);
    snprintf(name, name_size, "face-scan");
    return mesh;
}

/* One run in the calling (child) process: 0 ok, 1 failed, 2 mesh missing. */
static int measure(int32_t faces, int lscm, int threads)
{
    pz_ctx ctx;
    pz_ctx_init(&ctx);
    ctx.quiet = 1;
    char name[64];
    pz_mesh *mesh = load_mesh(faces, name, sizeof name, &ctx);
    if (!mesh) {
        if (faces > 0) {
            fprintf(stderr, "bench_param: %s\n", ctx.error);
            return 1;
        }
        printf("bench_param: face-scan skipped (%s)\n", ctx.error);
        return 2;
    }
    pz_pattern pattern;
    double *uv = NULL;
    int failed = !bench_one_panel(mesh, &pattern, &uv) ||
                 (lscm ? run_lscm(name, &pattern, uv, &ctx) : run_textile(name, &pattern, threads, uv, &ctx));
    free(uv);
    free(pattern.face_panel);
    pz_mesh_free(&mesh);
    return failed;
}

int main(int argc, char **argv)
{
    long max_faces = argc > 1 ? atol(argv[1]) : 200000;
    int threads = argc > 2 ? atoi(argv[2]) : 0;
    static const int32_t sizes[] = {2000, 3000, 20000, 200000, 0}; /* 0: the face scan */
    for (size_t i = 0; i < sizeof sizes / sizeof sizes[0]; ++i) {
        if (sizes[i] > max_faces)
            continue;
        for (int lscm = 0; lscm < 2; ++lscm) {
            fflush(stdout);
            pid_t child = fork();
            if (child < 0) {
                perror("bench_param: fork");
                return 1;
            }
            if (child == 0) {
                int code = measure(sizes[i], lscm, threads);
                fflush(stdout);
                _exit(code);
            }
            int status = 0;
            if (waitpid(child, &status, 0) < 0 || !WIFEXITED(status) || WEXITSTATUS(status) == 1)
                return 1;
            if (WEXITSTATUS(status) == 2)
                break;
        }
    }
    return 0;
}

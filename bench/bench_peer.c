/*
 * bench/bench_peer.c -- the textile iteration side by side with libigl's
 * ARAP iteration (issue 17; the table is in docs/param.md, "Speed against
 * libigl").
 *
 *   bench_peer [--runs N] [--iterations I] [--one-thread] [MESH ...]
 *
 * MESH: a mesh file, or hemisphere:FACES for a generated hemisphere (written
 * to a temporary OBJ so the peer reads the same mesh). Default: the
 * hemispheres of 2K, 20K and 200K faces and, when ../shared/data is there
 * (PZ_SHARED_DATA overrides), surfaces/camelhead.off and
 * surfaces/face-scan.obj. Every mesh is one panel.
 *
 * Per mesh, N rounds (default 5), each of three processes one after the
 * other (interleaved, so load changes hit all three alike): panelize's
 * textile on 1 thread, on 2 threads, then the peer: libigl's
 * arap_precomputation and arap_solve from an LSCM start (../shared/peers,
 * built by this build's `igl_peer` target: `cmake --build build --target
 * igl_peer`; IGL_BENCH=PATH overrides; without it only panelize's figures
 * are printed). Both run I iterations (default 20; panelize with no early
 * stop). One line per run, then the medians:
 *
 *   bench_peer mesh=camelhead.off faces=22884 pz_iteration_ms=8.10 pz2_iteration_ms=7.90
 *     igl_iteration_ms=6.80 ratio=1.19 ratio2=1.16 pz_init_ms=60.1 pz2_init_ms=58.0 igl_init_ms=190.3
 *     factorizations=2 failed_steps=0 max_strain=0.2100 igl_distortion=0.0812 runs=5 load=1.10
 *
 * pz_iteration_ms: panelize's mean time per iteration (1 thread; pz2_: 2
 * threads); igl_iteration_ms: the peer's; ratio = pz / igl from the same
 * rounds (median of the per-round ratios); init_ms: the LSCM start plus the
 * set-up (the peer: its LSCM start plus arap_precomputation);
 * factorizations / failed_steps: numeric factorizations of the global step
 * and preconditioned steps that failed (1 thread; the same on 2).
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
#include <unistd.h>

#include "bench_util.h"

#define MAX_RUNS 31

/* --one-thread: skip the 2-thread runs (profiling). */
static int one_thread;

/* One run's figures (written by a child through a pipe). */
typedef struct run_figures {
    double iteration_ms, iteration_cpu_ms, init_ms, max_strain, energy_end;
    int32_t faces, factorizations, failed_steps, pcg_solves, iterations;
} run_figures;

/* A mesh from a file or hemisphere:FACES, in mm. */
static pz_mesh *load_mesh(const char *spec, pz_ctx *ctx)
{
    pz_mesh *mesh = NULL;
    if (strncmp(spec, "hemisphere:", 11) == 0) {
        pz_generate_options options = {.target_faces = atoi(spec + 11)};
        return pz_generate(PZ_SHAPE_HEMISPHERE, &options, &mesh, ctx) ? NULL : mesh;
    }
    if (pz_mesh_read(spec, &mesh, ctx))
        return NULL;
    pz_mesh_to_mm(mesh, PZ_UNITS_AUTO, NULL);
    return mesh;
}

/* panelize's textile on the whole mesh as one panel (in the child). */
static int measure_textile(const char *spec, int threads, int iterations, run_figures *figures)
{
    pz_ctx ctx;
    pz_ctx_init(&ctx);
    ctx.quiet = 1;
    pz_mesh *mesh = load_mesh(spec, &ctx);
    if (!mesh) {
        fprintf(stderr, "bench_peer: %s\n", ctx.error);
        return 1;
    }
    pz_pattern pattern;
    double *uv = NULL;
    int allocated = bench_one_panel(mesh, &pattern, &uv);
    bench_iteration_cpu cpu = {0, 0};
    pz_textile_options options = {.iterations = iterations, .tolerance = 1e-300, .threads = threads,
                                  .on_iteration = bench_record_cpu, .user = &cpu};
    pz_textile_result result;
    int failed = !allocated || pz_param_textile(&pattern, &options, uv, &result, &ctx) != PZ_OK;
    if (failed) {
        fprintf(stderr, "bench_peer: %s: %s\n", spec, ctx.error);
    } else {
        pz_metrics *metrics = NULL;
        figures->max_strain = pz_metrics_compute(&pattern, uv, 0, NULL, &metrics, &ctx) == PZ_OK
                                  ? metrics->max_abs_strain : -1;
        pz_metrics_free(&metrics);
        figures->iteration_ms = result.iteration_ms;
        figures->iteration_cpu_ms = 1e3 * (cpu.last - cpu.start) / (result.iterations_run > 0 ? result.iterations_run : 1);
        figures->init_ms = result.init_ms;
        figures->faces = mesh->face_count;
        figures->factorizations = result.factorizations;
        figures->failed_steps = result.failed_steps;
        figures->pcg_solves = result.pcg_solves;
        figures->iterations = result.iterations_run;
        figures->energy_end = result.final_energy;
    }
    free(uv);
    free(pattern.face_panel);
    pz_mesh_free(&mesh);
    return failed;
}

/* Runs measure_textile in a forked child (its own peak memory, allocator and OpenMP
 * state) and reads its figures back. 0 on success. */
static int run_child(const char *spec, int threads, int iterations, run_figures *figures)
{
    int fd[2];
    if (pipe(fd) != 0)
        return 1;
    fflush(stdout);
    pid_t child = fork();
    if (child < 0)
        return 1;
    if (child == 0) {
        close(fd[0]);
        run_figures mine;
        memset(&mine, 0, sizeof mine);
        int code = measure_textile(spec, threads, iterations, &mine);
        if (!code && write(fd[1], &mine, sizeof mine) != (ssize_t)sizeof mine)
            code = 1;
        _exit(code);
    }
    close(fd[1]);
    ssize_t got = read(fd[0], figures, sizeof *figures);
    close(fd[0]);
    int status = 0;
    if (waitpid(child, &status, 0) < 0 || !WIFEXITED(status) || WEXITSTATUS(status) != 0)
        return 1;
    return got != (ssize_t)sizeof *figures;
}

/* The value of `key=` in a key=value line, or -1. */
static double field(const char *line, const char *key)
{
    char pattern[64];
    snprintf(pattern, sizeof pattern, " %s=", key);
    const char *at = strstr(line, pattern);
    return at ? atof(at + strlen(pattern)) : -1;
}

/* The peer's figures on one file. */
typedef struct peer_figures {
    double iteration_ms, iteration_cpu_ms, init_ms, distortion;
} peer_figures;

/* The peer on `path` (a file). 0 on success. */
static int run_peer(const char *peer, const char *path, int iterations, peer_figures *figures)
{
    char command[8192];
    snprintf(command, sizeof command, "'%s' '%s' arap %d", peer, path, iterations);
    fflush(stdout);
    FILE *pipe = popen(command, "r");
    if (!pipe)
        return 1;
    char line[4096];
    int found = 0;
    while (fgets(line, sizeof line, pipe))
        if (strncmp(line, "igl_bench ", 10) == 0) {
            figures->iteration_ms = field(line, "iteration_ms");
            figures->iteration_cpu_ms = field(line, "iteration_cpu_ms");
            figures->init_ms = field(line, "init_ms");
            figures->distortion = field(line, "distortion");
            found = figures->iteration_ms > 0 && figures->iteration_cpu_ms > 0;
        }
    return pclose(pipe) != 0 || !found;
}

static int compare_doubles(const void *a, const void *b)
{
    double x = *(const double *)a, y = *(const double *)b;
    return (x > y) - (x < y);
}

static double median(double *values, int count)
{
    if (count == 0)
        return -1;
    qsort(values, (size_t)count, sizeof *values, compare_doubles);
    return count % 2 ? values[count / 2] : 0.5 * (values[count / 2 - 1] + values[count / 2]);
}

/* The mesh file the peer reads: the file itself, or the generated mesh
 * written to `scratch`. 0 on success. */
static int peer_file(const char *spec, const char *scratch, char *path, size_t size)
{
    if (strncmp(spec, "hemisphere:", 11) != 0) {
        snprintf(path, size, "%s", spec);
        return 0;
    }
    pz_ctx ctx;
    pz_ctx_init(&ctx);
    ctx.quiet = 1;
    pz_mesh *mesh = load_mesh(spec, &ctx);
    snprintf(path, size, "%s/hemisphere-%s.obj", scratch, spec + 11);
    int failed = !mesh || pz_mesh_write(mesh, path, NULL, &ctx) != PZ_OK;
    pz_mesh_free(&mesh);
    return failed;
}

/* Per-round series of one mesh. */
enum { PZ1, PZ2, IGL, RATIO, RATIO2, PZ1_CPU, IGL_CPU, RATIO_CPU, PZ1_INIT, PZ2_INIT, IGL_INIT, SERIES };

/* All rounds of one mesh; prints each run and the medians. */
static int bench_mesh(const char *spec, const char *peer, const char *scratch, int runs, int iterations)
{
    const char *name = strrchr(spec, '/') ? strrchr(spec, '/') + 1 : spec;
    char path[4096];
    int have_peer = peer && peer_file(spec, scratch, path, sizeof path) == 0;
    static double series[SERIES][MAX_RUNS];
    int count[SERIES] = {0};
    run_figures one, two;
    peer_figures igl = {-1, -1, -1, -1};
    for (int r = 0; r < runs; ++r) {
        if (run_child(spec, 1, iterations, &one) || (one_thread ? (two = one, 0) : run_child(spec, 2, iterations, &two))) {
            fprintf(stderr, "bench_peer: %s: the textile run failed\n", spec);
            return 1;
        }
        double pz_values[] = {one.iteration_ms, two.iteration_ms, one.iteration_cpu_ms, one.init_ms, two.init_ms};
        int pz_series[] = {PZ1, PZ2, PZ1_CPU, PZ1_INIT, PZ2_INIT};
        for (int i = 0; i < 5; ++i)
            series[pz_series[i]][count[pz_series[i]]++] = pz_values[i];
        int peer_ok = have_peer && run_peer(peer, path, iterations, &igl) == 0;
        if (peer_ok) {
            double peer_values[] = {igl.iteration_ms, one.iteration_ms / igl.iteration_ms,
                                    two.iteration_ms / igl.iteration_ms, igl.iteration_cpu_ms,
                                    one.iteration_cpu_ms / igl.iteration_cpu_ms, igl.init_ms};
            int peer_series[] = {IGL, RATIO, RATIO2, IGL_CPU, RATIO_CPU, IGL_INIT};
            for (int i = 0; i < 6; ++i)
                series[peer_series[i]][count[peer_series[i]]++] = peer_values[i];
        }
        printf("bench_peer run=%d mesh=%s pz_iteration_ms=%.3f pz2_iteration_ms=%.3f igl_iteration_ms=%.3f "
               "pz_iteration_cpu_ms=%.3f igl_iteration_cpu_ms=%.3f pz_init_ms=%.1f igl_init_ms=%.1f load=%.2f\n",
               r, name, one.iteration_ms, two.iteration_ms, peer_ok ? igl.iteration_ms : -1, one.iteration_cpu_ms,
               peer_ok ? igl.iteration_cpu_ms : -1, one.init_ms, peer_ok ? igl.init_ms : -1, bench_load_average());
    }
    double m[SERIES];
    for (int i = 0; i < SERIES; ++i)
        m[i] = median(series[i], count[i]);
    printf("bench_peer mesh=%s faces=%d pz_iteration_ms=%.3f pz2_iteration_ms=%.3f igl_iteration_ms=%.3f ratio=%.2f "
           "ratio2=%.2f pz_iteration_cpu_ms=%.3f igl_iteration_cpu_ms=%.3f ratio_cpu=%.2f threads2_over_1=%.2f "
           "pz_init_ms=%.1f pz2_init_ms=%.1f igl_init_ms=%.1f factorizations=%d failed_steps=%d pcg_solves=%d "
           "iterations=%d energy_end=%.6g max_strain=%.4f igl_distortion=%.4f runs=%d load=%.2f\n",
           name, one.faces, m[PZ1], m[PZ2], m[IGL], m[RATIO], m[RATIO2], m[PZ1_CPU], m[IGL_CPU], m[RATIO_CPU],
           m[PZ2] / m[PZ1], m[PZ1_INIT], m[PZ2_INIT], m[IGL_INIT], one.factorizations, one.failed_steps,
           one.pcg_solves, one.iterations, one.energy_end, one.max_strain, igl.distortion, runs, bench_load_average());
    if (!have_peer)
        printf("bench_peer: %s: no libigl peer (build it: cmake --build build --target igl_peer)\n", name);
    return 0;
}

int main(int argc, char **argv)
{
    int runs = 5, iterations = 20, first = 1;
    while (first + 1 < argc && argv[first][0] == '-' && argv[first][1] == '-') {
        if (strcmp(argv[first], "--one-thread") == 0) {
            one_thread = 1;
            first += 1;
            continue;
        }
        if (strcmp(argv[first], "--runs") == 0)
            runs = atoi(argv[first + 1]);
        else if (strcmp(argv[first], "--iterations") == 0)
            iterations = atoi(argv[first + 1]);
        else
            break;
        first += 2;
    }
    if (runs < 1 || runs > MAX_RUNS || iterations < 1 || (first < argc && argv[first][0] == '-')) {
        fprintf(stderr, "usage: bench_peer [--runs 1..%d] [--iterations N] [--one-thread] [MESH|hemisphere:FACES ...]\n", MAX_RUNS);
        return 64;
    }
    const char *peer = getenv("IGL_BENCH") ? getenv("IGL_BENCH") : PZ_IGL_BENCH;
    if (access(peer, X_OK) != 0)
        peer = NULL;
    char scratch[] = "/tmp/bench_peer.XXXXXX";
    if (!mkdtemp(scratch)) {
        perror("bench_peer: mkdtemp");
        return 73;
    }
    const char *shared = getenv("PZ_SHARED_DATA") && *getenv("PZ_SHARED_DATA") ? getenv("PZ_SHARED_DATA")
                                                                                  : PZ_SHARED_DATA_DIR;
    char camel[4096], scan[4096];
    snprintf(camel, sizeof camel, "%s/surfaces/camelhead.off", shared);
    snprintf(scan, sizeof scan, "%s/surfaces/face-scan.obj", shared);
    const char *defaults[] = {"hemisphere:2000", "hemisphere:20000", "hemisphere:200000", camel, scan};
    int failed = 0;
    if (first < argc) {
        for (int i = first; i < argc && !failed; ++i)
            failed = bench_mesh(argv[i], peer, scratch, runs, iterations);
    } else {
        for (size_t i = 0; i < sizeof defaults / sizeof defaults[0] && !failed; ++i) {
            if (i >= 3 && access(defaults[i], R_OK) != 0) {
                printf("bench_peer: %s skipped (no shared data)\n", defaults[i]);
                continue;
            }
            failed = bench_mesh(defaults[i], peer, scratch, runs, iterations);
        }
    }
    char command[64];
    snprintf(command, sizeof command, "rm -rf '%s'", scratch);
    if (system(command) != 0)
        fprintf(stderr, "bench_peer: could not remove %s\n", scratch);
    return failed;
}

/*
 * bench/bench_springmass.c -- spring-mass flattening: heap (IISERM) versus
 * full relaxation, as in IISERM Figs. 7-8 (time and remaining energy).
 *
 * For generated hemispheres (one panel) of about 5K and 20K faces, runs the
 * heap release with a single path and with multi-path (8 paths), the heap
 * release with phase two as the paper's node sweeps only (heap-local:
 * local_release_only, no global release), and the full release (wang2002
 * InitFlatten) unless the mesh has more than MAX_FULL_FACES faces (and
 * full-local below 10000 faces), and prints one line per run:
 *   bench_springmass mesh=... relax=heap|multi|heap-local|full|full-local faces=...
 *       phase_one_ms=... phase_two_ms=... total_ms=... cpu_ms=... relaxations=...
 *       phase_one_relaxations=... global_iterations=... phase_one_energy=...
 *       final_energy=... e_area=... e_shape=... sweeps=...
 * cpu_ms is this process's CPU time for the run (the machine is shared; the
 * load average is printed first). Usage: bench_springmass [MAX_FULL_FACES]
 * (default 25000; full relaxation grows as faces^2).
 *
 * SPDX-License-Identifier: GPL-3.0-or-later
 */
#define _POSIX_C_SOURCE 200809L
#include "generate/generate.h"
#include "param/param.h"
#include "bench_util.h"

#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <time.h>

/* CPU time of this process, seconds (other programs on the shared machine do not inflate it). */
static double cpu_seconds(void)
{
    struct timespec now;
    clock_gettime(CLOCK_PROCESS_CPUTIME_ID, &now);
    return (double)now.tv_sec + 1e-9 * (double)now.tv_nsec;
}

static int run(const char *name, pz_mesh *mesh, const char *label, const pz_springmass_options *options)
{
    pz_ctx ctx;
    pz_ctx_init(&ctx);
    ctx.quiet = 1;
    pz_pattern pattern;
    double *uv = NULL;
    if (!bench_one_panel(mesh, &pattern, &uv)) {
        fprintf(stderr, "bench_springmass: out of memory\n");
        return 1;
    }
    pz_springmass_result result;
    double start = pz_seconds(), cpu_start = cpu_seconds();
    if (pz_param_springmass(&pattern, options, uv, &result, &ctx)) {
        fprintf(stderr, "bench_springmass: %s\n", ctx.error);
        return 1;
    }
    double total = 1e3 * (pz_seconds() - start), cpu = 1e3 * (cpu_seconds() - cpu_start);
    printf("bench_springmass mesh=%s relax=%s faces=%d phase_one_ms=%.1f phase_two_ms=%.1f total_ms=%.1f cpu_ms=%.1f "
           "relaxations=%lld phase_one_relaxations=%lld global_iterations=%lld phase_one_energy=%.6g final_energy=%.6g e_area=%.5f "
           "e_shape=%.5f sweeps=%d\n",
           name, label, mesh->face_count, result.phase_one_ms, result.phase_two_ms, total, cpu, result.node_relaxations,
           result.phase_one_relaxations, result.global_iterations, result.phase_one_energy, result.final_energy, result.panels[0].e_area,
           result.panels[0].e_shape, result.panels[0].iterations);
    fflush(stdout);
    pz_springmass_result_clear(&result);
    free(uv);
    free(pattern.face_panel);
    return 0;
}

int main(int argc, char **argv)
{
    long max_full = argc > 1 ? strtol(argv[1], NULL, 10) : 25000;
    printf("bench_springmass load_average=%.2f\n", bench_load_average());
    static const int32_t sizes[] = {5000, 20000};
    for (size_t i = 0; i < sizeof sizes / sizeof sizes[0]; ++i) {
        pz_ctx ctx;
        pz_ctx_init(&ctx);
        pz_generate_options generate = {.target_faces = sizes[i]};
        pz_mesh *mesh = NULL;
        if (pz_generate(PZ_SHAPE_HEMISPHERE, &generate, &mesh, &ctx)) {
            fprintf(stderr, "bench_springmass: %s\n", ctx.error);
            return 1;
        }
        char name[64];
        snprintf(name, sizeof name, "hemisphere-%d", (int)sizes[i]);
        pz_springmass_options heap = {0}, multi = {.heap_paths = 8}, full = {.relax = 1};
        pz_springmass_options heap_local = {.local_release_only = 1}, full_local = {.relax = 1, .local_release_only = 1};
        int failed = run(name, mesh, "heap", &heap) || run(name, mesh, "multi", &multi) ||
                     run(name, mesh, "heap-local", &heap_local) ||
                     (mesh->face_count <= max_full && run(name, mesh, "full", &full)) ||
                     (mesh->face_count < 10000 && run(name, mesh, "full-local", &full_local));
        pz_mesh_free(&mesh);
        if (failed)
            return 1;
    }
    return 0;
}

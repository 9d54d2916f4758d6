/*
 * bench/bench_field.c -- how long the cross-field takes, and how much memory:
 * multi-scale curvature (3 scales) plus the CHOLMOD solve, singularities and
 * figures, on pz_generate's bodice at 10K, 100K and 1M faces.
 *
 *   bench_field [FACES]...      (default 10000 100000 1000000)
 *
 * Each size runs in a forked child so that one size's peak resident size
 * (VmHWM in /proc/self/status) does not hide the next; the peak is reported
 * over the child's size after the mesh and its topology exist (so it is what
 * the field stage itself needs). One machine-readable line per size:
 *
 *   bench_field faces=100229 curvature_ms=190.1 solve_ms=820.3 total_ms=1050.2 peak_bytes_per_face=420
 *
 * solve_ms covers constraints, assembly, factorisation and solve;
 * total_ms = pz_field_compute as a whole. Target (docs/field.md): 100K faces
 * under 1 s on two cores. Exit status 1 when a step fails.
 *
 * SPDX-License-Identifier: GPL-3.0-or-later
 */
#define _POSIX_C_SOURCE 200809L
#include "field/field.h"
#include "generate/generate.h"

#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/types.h>
#include <sys/wait.h>
#include <unistd.h>

#include "bench_util.h"

static int measure(int32_t target_faces)
{
    pz_ctx ctx;
    pz_ctx_init(&ctx);
    ctx.quiet = 1;
    pz_generate_options options = {target_faces, 0, 0};
    pz_mesh *mesh = NULL;
    pz_topology *topology = NULL;
    pz_field *field = NULL;
    if (pz_generate(PZ_SHAPE_BODICE, &options, &mesh, &ctx) || pz_topology_build(mesh, &topology, &ctx)) {
        fprintf(stderr, "bench_field: %s\n", ctx.error);
        pz_mesh_free(&mesh);
        return 1;
    }
    long before_kb = bench_status_kb("VmRSS");
    double start = pz_seconds();
    pz_status status = pz_field_compute(mesh, topology, NULL, &field, &ctx);
    double total_ms = 1e3 * (pz_seconds() - start);
    long peak_kb = bench_status_kb("VmHWM");
    if (status) {
        fprintf(stderr, "bench_field: %s\n", ctx.error);
    } else {
        double peak_per_face = (peak_kb - before_kb) * 1024.0 / mesh->face_count;
        printf("bench_field faces=%d curvature_ms=%.1f solve_ms=%.1f total_ms=%.1f peak_bytes_per_face=%.0f "
               "singularities=%d\n",
               (int)mesh->face_count, field->curvature_ms, field->solve_ms, total_ms, peak_per_face,
               (int)field->singularity_count);
    }
    pz_field_free(&field);
    pz_topology_free(&topology);
    pz_mesh_free(&mesh);
    return status ? 1 : 0;
}

int main(int argc, char **argv)
{
    int32_t defaults[] = {10000, 100000, 1000000};
    int count = argc > 1 ? argc - 1 : 3;
    int failed = 0;
    for (int i = 0; i < count; ++i) {
        int32_t faces = argc > 1 ? (int32_t)atol(argv[i + 1]) : defaults[i];
        if (faces < 100) {
            fprintf(stderr, "usage: bench_field [FACES]...   (each at least 100)\n");
            return 1;
        }
        fflush(stdout);
        pid_t child = fork();
        if (child < 0) {
            perror("bench_field: fork");
            return 1;
        }
        if (child == 0)
        {
            int code = measure(faces);
            fflush(stdout); /* _exit does not flush */
            _exit(code);
        }
        int wstatus = 0;
        if (waitpid(child, &wstatus, 0) < 0 || !WIFEXITED(wstatus) || WEXITSTATUS(wstatus) != 0)
            failed = 1;
    }
    return failed;
}

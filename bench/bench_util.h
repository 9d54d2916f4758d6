/*
 * bench/bench_util.h -- what every benchmark program measures besides time:
 * resident memory (from /proc/self/status) and the machine's load, so that a
 * figure taken on a busy machine says so.
 *
 * SPDX-License-Identifier: GPL-3.0-or-later
 */
#ifndef PZ_BENCH_UTIL_H
#define PZ_BENCH_UTIL_H

#include "param/param.h"

#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <time.h>

/* A field of /proc/self/status in kB ("VmHWM" = peak, "VmRSS" = now), or -1. */
static inline long bench_status_kb(const char *field)
{
    FILE *file = fopen("/proc/self/status", "r");
    if (!file)
        return -1;
    char line[256];
    long value = -1;
    size_t length = strlen(field);
    while (fgets(line, sizeof line, file))
        if (strncmp(line, field, length) == 0 && line[length] == ':') {
            value = strtol(line + length + 1, NULL, 10);
            break;
        }
    fclose(file);
    return value;
}

/* The 1-minute load average, or -1. */
static inline double bench_load_average(void)
{
    double load = -1;
    FILE *file = fopen("/proc/loadavg", "r");
    if (file) {
        if (fscanf(file, "%lf", &load) != 1)
            load = -1;
        fclose(file);
    }
    return load;
}

/* CPU time of the process (all threads), in seconds. */
static inline double bench_cpu_seconds(void)
{
    struct timespec now;
    clock_gettime(CLOCK_PROCESS_CPUTIME_ID, &now);
    return (double)now.tv_sec + 1e-9 * (double)now.tv_nsec;
}

/* A textile on_iteration callback: the CPU time when the start's energy is
 * reported (iteration 0: the initialization is done) and when the last
 * iterate's is. */
typedef struct bench_iteration_cpu {
    double start, last;
} bench_iteration_cpu;

static inline void bench_record_cpu(void *user, int iteration, double energy)
{
    (void)energy;
    bench_iteration_cpu *cpu = user;
    cpu->last = bench_cpu_seconds();
    if (iteration == 0)
        cpu->start = cpu->last;
}

/* The whole mesh as panel 0 of *pattern (which borrows mesh) and a uv
 * buffer for it: the caller frees pattern->face_panel and *uv. 0 when out
 * of memory. */
static inline int bench_one_panel(pz_mesh *mesh, pz_pattern *pattern, double **uv)
{
    memset(pattern, 0, sizeof *pattern);
    pattern->mesh = mesh;
    pattern->panel_count = 1;
    pattern->face_panel = calloc((size_t)mesh->face_count + 1, sizeof(int32_t));
    *uv = malloc((size_t)mesh->vertex_count * 2 * sizeof(double) + 1);
    return pattern->face_panel && *uv;
}

#endif

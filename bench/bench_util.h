/*
 * bench/bench_util.h -- what every benchmark program measures besides time:
 * resident memory (from /proc/self/status) and the machine's load, so that a
 * figure taken on a busy machine says so.
 *
 * SPDX-License-Identifier: GPL-3.0-or-later
 */
#ifndef PZ_BENCH_UTIL_H
#define PZ_BENCH_UTIL_H

#include <stdio.h>
#include <stdlib.h>
#include <string.h>

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

#endif

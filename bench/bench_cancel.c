/*
 * bench/bench_cancel.c -- how soon pz_run stops once cancelled (issue 13:
 * "a cancel flag checked often enough that a 50K-face run stops within a
 * second"). A 50K-face bodice is run once to time it, then again several
 * times with the flag set from another thread after a growing delay; each
 * line gives the stage the run was in (its last progress report) and the
 * latency from setting the flag to pz_run's return.
 *
 *   build/bench_cancel [FACES] [--prepare off]
 *
 * SPDX-License-Identifier: GPL-3.0-or-later
 */
#define _POSIX_C_SOURCE 200809L
#include "generate/generate.h"
#include "pipeline/pipeline.h"

#include "bench_util.h"

#include <pthread.h>
#include <time.h>

typedef struct cancel_run {
    const pz_mesh *mesh;
    pz_run_options options;
    volatile int flag;
    double returned_at;
    pz_status status;
    char stage[32];
} cancel_run;

static void remember_stage(void *user, const char *stage, double fraction, const char *message)
{
    cancel_run *run = user;
    (void)fraction, (void)message;
    snprintf(run->stage, sizeof run->stage, "%s", stage);
}

static void *run_thread(void *user)
{
    cancel_run *run = user;
    pz_ctx ctx;
    pz_ctx_init(&ctx);
    ctx.quiet = 1;
    ctx.cancel = &run->flag;
    ctx.progress = remember_stage;
    ctx.progress_user = run;
    pz_result *result = NULL;
    run->status = pz_run(run->mesh, &run->options, &result, &ctx);
    run->returned_at = pz_seconds();
    pz_result_free(&result);
    return NULL;
}

static void sleep_seconds(double seconds)
{
    struct timespec pause = {(time_t)seconds, (long)((seconds - (double)(time_t)seconds) * 1e9)};
    nanosleep(&pause, NULL);
}

int main(int argc, char **argv)
{
    int32_t faces = argc > 1 && argv[1][0] != '-' ? (int32_t)atoi(argv[1]) : 50000;
    int prepare = !(argc > 2 && strcmp(argv[argc - 1], "off") == 0);
    pz_ctx ctx;
    pz_ctx_init(&ctx);
    pz_generate_options generate = {.target_faces = faces};
    pz_mesh *mesh = NULL;
    if (pz_generate(PZ_SHAPE_BODICE, &generate, &mesh, &ctx) != PZ_OK) {
        fprintf(stderr, "bench_cancel: %s\n", ctx.error);
        return 1;
    }
    cancel_run run;
    memset(&run, 0, sizeof run);
    run.mesh = mesh;
    pz_run_options_default(&run.options);
    run.options.prepare = prepare;
    double start = pz_seconds();
    pthread_t thread;
    pthread_create(&thread, NULL, run_thread, &run);
    pthread_join(thread, NULL);
    double whole = run.returned_at - start;
    printf("bench_cancel: bodice %d faces, prepare %s, load %.2f: the whole run %.2f s (status %d)\n",
           (int)mesh->face_count, prepare ? "auto" : "off", bench_load_average(), whole, (int)run.status);
    printf("%-10s %-10s %-10s %s\n", "cancel at", "stage", "latency", "status");
    double worst = 0;
    for (double fraction = 0.05; fraction < 0.99; fraction += 0.1) {
        memset(&run, 0, sizeof run);
        run.mesh = mesh;
        pz_run_options_default(&run.options);
        run.options.prepare = prepare;
        start = pz_seconds();
        pthread_create(&thread, NULL, run_thread, &run);
        sleep_seconds(fraction * whole);
        char stage[32];
        snprintf(stage, sizeof stage, "%s", run.stage);
        double set_at = pz_seconds();
        run.flag = 1;
        pthread_join(thread, NULL);
        double latency = run.returned_at > set_at ? run.returned_at - set_at : 0;
        if (run.status == PZ_ERR_CANCELLED && latency > worst)
            worst = latency;
        printf("%-10.2f %-10s %-10.3f %s\n", set_at - start, stage, latency,
               run.status == PZ_ERR_CANCELLED ? "cancelled" : "finished first");
    }
    printf("worst latency %.3f s (goal: under 1 s)\n", worst);
    pz_mesh_free(&mesh);
    return 0;
}

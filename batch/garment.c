/*
 * batch/garment.c -- the work of one garment: read it with its poses, run
 * the pipeline, write its folder. The same steps as `panelize run`, through
 * the library (pz_run, pz_result_write).
 *
 * SPDX-License-Identifier: GPL-3.0-or-later
 */
#include "batch/batch.h"
#include "io/io.h"

#include <math.h>
#include <stdio.h>
#include <string.h>

/* The pattern's figures for the summary. */
static void describe(const pz_result *result, pz_batch_outcome *outcome)
{
    outcome->pieces = result->pattern->panel_count;
    outcome->darts = result->pattern->dart_count;
    outcome->goals_judged = result->verdict.judged;
    outcome->goals_met = result->verdict.goals_met;
    double worst = result->verdict.worst_strain;
    if (!result->verdict.judged) /* pz_flatten's results: the metrics' worst pose */
        for (int i = 0; i < result->metrics_count; ++i)
            worst = fmax(worst, result->metrics[i]->max_abs_strain);
    outcome->worst_strain = worst;
}

pz_status pz_batch_run_garment(const char *path, const char *const *pose_paths, int pose_count,
                               const pz_run_options *options, const char *folder, unsigned outputs,
                               pz_batch_outcome *outcome, pz_ctx *ctx)
{
    memset(outcome, 0, sizeof *outcome);
    outcome->worst_strain = -1;
    pz_mesh *mesh = NULL;
    pz_result *result = NULL;
    pz_status status = pz_mesh_read_with_poses(path, pose_paths, pose_count, &mesh, ctx);
    if (status == PZ_OK)
        status = pz_run(mesh, options, &result, ctx);
    pz_mesh_free(&mesh);
    if (status == PZ_OK)
        status = pz_result_write(result, folder, outputs, NULL, ctx);
    if (status == PZ_OK)
        describe(result, outcome);
    pz_result_free(&result);
    outcome->status = status;
    if (status != PZ_OK)
        snprintf(outcome->message, sizeof outcome->message, "%s", ctx->error[0] ? ctx->error : pz_status_str(status));
    return status;
}

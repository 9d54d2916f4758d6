/*
 * cli/cmd_batch.c -- `panelize batch INPUT... -o OUTROOT`: many garments,
 * each as `panelize run` would do it, in worker processes (docs/batch.md).
 * A caller of batch/batch.h: this file turns argv (and each manifest line's
 * options) into pz_run_options and hands the batch module the work of one
 * garment; the listing, shards, workers, time-outs, resume and summaries
 * live in batch/.
 *
 * SPDX-License-Identifier: GPL-3.0-or-later
 */
#define _POSIX_C_SOURCE 200809L
#include "batch/batch.h"
#include "cli/cli.h"

#include <errno.h>
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <unistd.h>

#define MAX_JOBS 256

const char pz_cli_batch_usage[] =
    "usage: panelize batch INPUT... -o OUTROOT [--jobs N] [--shard I/N] [--resume]\n"
    "           [--timeout S] [run's options] [--json] [--quiet]\n"
    "       panelize batch --merge OUTROOT\n"
    "\n"
    "Runs `panelize run` on many garments, each in its own worker process, into\n"
    "OUTROOT/NAME/ (one folder per garment), and lists every garment in\n"
    "OUTROOT/summary.csv and summary.jsonl: status, exit category, pieces,\n"
    "darts, goals met, worst strain, seconds, peak memory, error.\n"
    "\n"
    "INPUT is a garment file (.obj .ply .off .glb .gltf), a folder (searched\n"
    "through its sub-folders for such files) or a manifest (.txt or .list: one\n"
    "garment per line, `PATH [--pose FILE]... [--name NAME] [run's options]`,\n"
    "paths relative to the manifest; # starts a comment). A garment's options\n"
    "are the command line's, then its manifest line's.\n"
    "\n"
    "options:\n"
    "  -o OUTROOT      the folder of the garments' folders and the summaries\n"
    "  -j, --jobs N    N garments at once (default 1), each with the usable cores / N\n"
    "                  threads\n"
    "  --shard I/N     only garments I, I+N, I+2N, ... of the list sorted by name\n"
    "                  (I from 0: sbatch --array=0-(N-1)); writes summary-I-of-N.*\n"
    "  --resume        skip garments whose folder is complete (its batch.json)\n"
    "  --timeout S     kill a garment after S seconds (recorded as timeout)\n"
    "  --merge         join OUTROOT's shard summaries into summary.csv/.jsonl\n"
    "  --strict        a garment whose pattern misses its goals counts as failed\n"
    "  run's options   see panelize run --help (--panels uv only; --pose per\n"
    "                  garment in a manifest)\n"
    "\n"
    "exit: 0 every garment written, 1 one or more failed (see the summary),\n"
    "64/66/73 bad batch input, 130 interrupted (unfinished garments: pending).\n"
    "A progress line (done/total, failures, ETA) on a terminal; else one line\n"
    "per garment on stderr. See docs/batch.md (Slurm job arrays).\n";

/* What a manifest line may give (each garment's own options). */
#define GARMENT_OPTIONS ((PZ_CLI_OPT_RUN | PZ_CLI_OPT_POSE) & ~(PZ_CLI_OPT_OUTPUT | PZ_CLI_OPT_COMMON))

/* --panels uv (each garment's own UV islands as its panels: a dataset flattened with its true panels). A
 * panel file numbers one garment's faces, so it is refused here. */
static const pz_panels uv_panels = {.source = PZ_PANELS_UV};

static pz_status batch_panels(const pz_cli_args *merged, pz_run_options *options, pz_ctx *ctx)
{
    const char *text = pz_cli_value(merged, PZ_CLI_OPT_PANELS);
    if (!text)
        return PZ_OK;
    if (strcmp(text, "uv") != 0)
        return pz_error(ctx, PZ_ERR_USAGE, "--panels: only 'uv' in a batch (a panel file '%s' numbers one "
                        "garment's faces: run that garment alone)", text);
    options->panels = &uv_panels;
    return PZ_OK;
}

typedef struct batch_work_context {
    const pz_cli_args *common; /* the batch's command line */
} batch_work_context;

/*
 * The `run` arguments of one garment into *merged: the command line's,
 * overlaid by its manifest line's (parsed into *line, which the caller
 * clears); its file, and its folder as -o.
 */
static pz_status garment_args(const pz_cli_args *common, const pz_batch_garment *garment, const char *folder,
                              pz_cli_args *line, pz_cli_args *merged, const char **positional, pz_ctx *ctx)
{
    pz_status status = pz_cli_parse_args("batch", GARMENT_OPTIONS, garment->arg_count, garment->args, 0, line, ctx);
    if (status == PZ_OK && line->positional_count > 0)
        status = pz_error(ctx, PZ_ERR_USAGE, "unexpected '%s' after the garment's file", line->positionals[0]);
    if (status != PZ_OK)
        return status;
    *merged = *common;
    merged->command = "run";
    for (int i = 0; i < PZ_CLI_VALUE_COUNT; ++i)
        if (line->values[i])
            merged->values[i] = line->values[i];
    if (line->units != PZ_UNITS_AUTO)
        merged->units = line->units;
    merged->repair_flags |= line->repair_flags;
    merged->pose_paths = line->pose_paths, merged->pose_path_count = line->pose_path_count;
    if (line->dart_path_count)
        merged->dart_paths = line->dart_paths, merged->dart_path_count = line->dart_path_count;
    positional[0] = garment->path, positional[1] = NULL;
    merged->positionals = positional, merged->positional_count = 1;
    merged->output_path = folder;
    return PZ_OK;
}

/*
 * A garment's run options, checked: PZ_ERR_USAGE "batch: SOURCE: problem".
 * options (input_files, name) points into positional[2], which must outlive it.
 */
static pz_status garment_options(const pz_cli_args *common, const pz_batch_garment *garment, const char *folder,
                                 pz_run_options *options, unsigned *outputs, pz_cli_args *line, pz_cli_args *merged,
                                 const char **positional, pz_ctx *ctx)
{
    pz_status status = garment_args(common, garment, folder, line, merged, positional, ctx);
    if (status == PZ_OK)
        status = pz_cli_run_options(merged, options, ctx);
    if (status == PZ_OK)
        status = batch_panels(merged, options, ctx);
    if (status == PZ_OK)
        status = pz_cli_outputs(merged, outputs, ctx);
    if (status != PZ_OK) {
        char message[sizeof ctx->error];
        snprintf(message, sizeof message, "%s", ctx->error);
        pz_error(ctx, status, "batch: %s: %.*s", garment->source, (int)sizeof message - 300, message);
    }
    return status;
}

/* The work of one garment, in its worker (pz_batch_work_fn). */
static pz_status work(const pz_batch_garment *garment, const char *folder, int threads, pz_batch_outcome *outcome,
                      void *user, pz_ctx *ctx)
{
    const batch_work_context *context = user;
    pz_cli_args line, merged;
    pz_run_options options;
    unsigned outputs = PZ_OUTPUT_ALL;
    const char *positional[2];
    pz_status status = garment_options(context->common, garment, folder, &options, &outputs, &line, &merged,
                                       positional, ctx);
    if (status == PZ_OK) {
        options.segment.threads = threads;
        status = pz_batch_run_garment(garment->path, merged.pose_paths, merged.pose_path_count, &options, folder,
                                      outputs, outcome, ctx);
    }
    pz_cli_args_clear(&line);
    return status;
}

/* Every garment's options before any runs: a bad manifest line is exit 64 at once, not a failed garment. */
static pz_status check_garments(const pz_cli_args *args, const pz_batch_list *list, pz_ctx *ctx)
{
    pz_status status = PZ_OK;
    for (int32_t i = 0; i < list->count && status == PZ_OK; ++i) {
        const pz_batch_garment *garment = &list->garments[i];
        char *folder = malloc(strlen(args->output_path) + strlen(garment->name) + 2);
        if (!folder)
            return pz_error(ctx, PZ_ERR_NOMEM, "batch: out of memory");
        sprintf(folder, "%s/%s", args->output_path, garment->name);
        pz_cli_args line, merged;
        pz_run_options options;
        unsigned outputs;
        const char *positional[2];
        status = garment_options(args, garment, folder, &options, &outputs, &line, &merged, positional, ctx);
        pz_cli_args_clear(&line);
        free(folder);
    }
    return status;
}

/* --jobs, --shard, --resume, --timeout, --strict into *options. */
static pz_status parse_batch_options(const pz_cli_args *args, pz_batch_options *options, pz_ctx *ctx)
{
    memset(options, 0, sizeof *options);
    options->jobs = 1;
    const char *text;
    if ((text = pz_cli_value(args, PZ_CLI_OPT_JOBS))) {
        char *end = NULL;
        errno = 0;
        long jobs = strtol(text, &end, 10);
        if (end == text || *end || errno || jobs < 1 || jobs > MAX_JOBS)
            return pz_error(ctx, PZ_ERR_USAGE, "batch: --jobs: '%s' is not a whole number in 1..%d", text, MAX_JOBS);
        options->jobs = (int)jobs;
    }
    if ((text = pz_cli_value(args, PZ_CLI_OPT_SHARD))) {
        pz_status status = pz_batch_shard_parse(text, &options->shard_index, &options->shard_count, ctx);
        if (status != PZ_OK)
            return status;
    }
    if ((text = pz_cli_value(args, PZ_CLI_OPT_TIMEOUT))) {
        char *end = NULL;
        errno = 0;
        double seconds = strtod(text, &end);
        if (end == text || *end || errno || !isfinite(seconds) || seconds <= 0 || seconds > 1e7)
            return pz_error(ctx, PZ_ERR_USAGE, "batch: --timeout: '%s' is not a number of seconds in (0, 1e7]", text);
        options->timeout_s = seconds;
    }
    options->resume = pz_cli_value(args, PZ_CLI_OPT_RESUME) != NULL;
    options->strict = pz_cli_value(args, PZ_CLI_OPT_STRICT) != NULL;
    options->outroot = args->output_path;
    options->progress = !args->quiet && isatty(STDERR_FILENO);
    options->work = work;
    if (!args->output_path)
        return pz_error(ctx, PZ_ERR_USAGE, "batch: -o OUTROOT is required (see panelize batch --help)");
    if (args->positional_count < 1)
        return pz_error(ctx, PZ_ERR_USAGE, "batch: expected INPUT... (garments, folders or manifests)");
    return PZ_OK;
}

/* The totals on stdout: text, or one JSON object with --json. */
static pz_status print_totals(const pz_cli_args *args, const pz_batch_totals *totals, pz_ctx *ctx)
{
    if (args->json) {
        cJSON *root = cJSON_CreateObject();
        int failed = !root || !cJSON_AddNumberToObject(root, "garments", totals->garments) ||
                     !cJSON_AddNumberToObject(root, "ok", totals->ok) ||
                     !cJSON_AddNumberToObject(root, "resumed", totals->resumed) ||
                     !cJSON_AddNumberToObject(root, "failed", totals->failed) ||
                     !cJSON_AddNumberToObject(root, "pending", totals->pending) ||
                     !cJSON_AddNumberToObject(root, "seconds", pz_round(totals->seconds, 3)) ||
                     !cJSON_AddStringToObject(root, "summary", totals->summary_csv);
        return pz_cli_print_json(root, failed, ctx);
    }
    printf("garments:  %d\n", (int)totals->garments);
    printf("ok:        %d (%d resumed)\n", (int)totals->ok, (int)totals->resumed);
    printf("failed:    %d\n", (int)totals->failed);
    if (totals->pending)
        printf("pending:   %d\n", (int)totals->pending);
    printf("summary:   %s\n", totals->summary_csv);
    return PZ_OK;
}

/* The batch's outcome as a status: failures are exit 1 (PZ_CLI_BATCH_FAILED) once the totals are out. */
static pz_status finish(const pz_cli_args *args, pz_status status, const pz_batch_totals *totals, pz_ctx *ctx)
{
    if (status != PZ_OK)
        return status;
    status = print_totals(args, totals, ctx);
    if (status == PZ_OK && totals->failed > 0) {
        pz_error(ctx, PZ_ERR_DATA, "batch: %d of %d garments failed (see %s)", (int)totals->failed,
                 (int)totals->garments, totals->summary_csv);
        return PZ_CLI_BATCH_FAILED;
    }
    return status;
}

static pz_status merge(const pz_cli_args *args, pz_ctx *ctx)
{
    const char *outroot = args->output_path;
    if ((outroot && args->positional_count > 0) || (!outroot && args->positional_count != 1))
        return pz_error(ctx, PZ_ERR_USAGE, "batch: --merge takes one OUTROOT (panelize batch --merge OUTROOT)");
    pz_batch_totals totals;
    pz_status status = pz_batch_merge(outroot ? outroot : args->positionals[0], &totals, ctx);
    return finish(args, status, &totals, ctx);
}

pz_status pz_cli_batch(const pz_cli_args *args, pz_ctx *ctx)
{
    if (pz_cli_value(args, PZ_CLI_OPT_MERGE))
        return merge(args, ctx);
    pz_batch_options options;
    pz_status status = parse_batch_options(args, &options, ctx);
    pz_batch_list *list = NULL;
    if (status == PZ_OK)
        status = pz_batch_list_read(args->positionals, args->positional_count, &list, ctx);
    if (status == PZ_OK)
        status = check_garments(args, list, ctx);
    pz_batch_totals totals;
    memset(&totals, 0, sizeof totals);
    if (status == PZ_OK) {
        batch_work_context context = {args};
        options.user = &context;
        pz_cli_progress_begin(args, ctx);
        ctx->progress = NULL; /* the batch draws its own line */
        status = pz_batch_run(list, &options, &totals, ctx);
        pz_cli_progress_end(ctx);
    }
    pz_batch_list_free(&list);
    return finish(args, status, &totals, ctx);
}

/*
 * cli/options.c -- what `flatten` and `run` share on the command line: their
 * options turned into pz_run_options (every default comes from the library's
 * _default functions), the write of a result with --outputs, the summary on
 * stdout, and progress on a terminal with Ctrl-C as cancellation.
 *
 * SPDX-License-Identifier: GPL-3.0-or-later
 */
#define _POSIX_C_SOURCE 200809L
#include "cli/cli.h"

#include <errno.h>
#include <limits.h>
#include <math.h>
#include <signal.h>
#include <stdlib.h>
#include <string.h>
#include <unistd.h>

/* ---------------------------------------------------------------- parsing */

/* Exactly `count` comma-separated finite numbers. */
static pz_status parse_numbers(const char *option, const char *text, double *values, int count, pz_ctx *ctx)
{
    const char *cursor = text;
    for (int i = 0; i < count; ++i) {
        char *end = NULL;
        errno = 0;
        values[i] = strtod(cursor, &end);
        int separator_ok = i + 1 < count ? *end == ',' : *end == '\0';
        if (end == cursor || errno == ERANGE || !isfinite(values[i]) || !separator_ok)
            return pz_error(ctx, PZ_ERR_USAGE, "flatten: %s: '%s' is not %d finite numbers separated by commas",
                            option, text, count);
        cursor = end + 1;
    }
    return PZ_OK;
}

/* --scheme, --relax and --features belong to one back-end each; elsewhere they are a mistake. */
static pz_status parse_backend_options(const pz_cli_args *args, pz_flatten_options *flatten, pz_ctx *ctx)
{
    const char *backend = pz_backend_name(flatten->backend);
    const char *text;
    if ((text = pz_cli_value(args, PZ_CLI_OPT_SCHEME))) {
        if (flatten->backend != PZ_BACKEND_WIREWARP)
            return pz_error(ctx, PZ_ERR_USAGE, "flatten: --scheme works with --backend wirewarp, not %s", backend);
        if (strcmp(text, "global") != 0 && strcmp(text, "progressive") != 0)
            return pz_error(ctx, PZ_ERR_USAGE, "flatten: --scheme: '%s' is not global or progressive", text);
        flatten->progressive = strcmp(text, "progressive") == 0;
    }
    if ((text = pz_cli_value(args, PZ_CLI_OPT_RELAX))) {
        if (flatten->backend != PZ_BACKEND_SPRINGMASS)
            return pz_error(ctx, PZ_ERR_USAGE, "flatten: --relax works with --backend springmass, not %s", backend);
        if (strcmp(text, "heap") != 0 && strcmp(text, "full") != 0)
            return pz_error(ctx, PZ_ERR_USAGE, "flatten: --relax: '%s' is not heap or full", text);
        flatten->relax_full = strcmp(text, "full") == 0;
    }
    if ((text = pz_cli_value(args, PZ_CLI_OPT_FEATURES))) {
        if (flatten->backend != PZ_BACKEND_WIREWARP)
            return pz_error(ctx, PZ_ERR_USAGE, "flatten: --features works with --backend wirewarp, not %s", backend);
        if (!*text)
            return pz_error(ctx, PZ_ERR_USAGE, "flatten: --features: empty file name");
        flatten->features_path = text;
    }
    return PZ_OK;
}

/* One finite number for a length option (mm); its range is checked with every other option's
 * (pz_run_options_check). */
static pz_status parse_length(const char *option, const char *text, double *out, pz_ctx *ctx)
{
    return parse_numbers(option, text, out, 1, ctx);
}

/* The pattern-file options of the export stage (export/export.h). */
static pz_status parse_export_options(const pz_cli_args *args, pz_run_options *run, pz_ctx *ctx)
{
    pz_export_options *options = &run->output;
    const char *text;
    pz_status status = PZ_OK;
    int hem_given = 0;
    if ((text = pz_cli_value(args, PZ_CLI_OPT_SEAM_ALLOWANCE)))
        status = parse_length("--seam-allowance", text, &options->seam_allowance_mm, ctx);
    if (status == PZ_OK && (text = pz_cli_value(args, PZ_CLI_OPT_HEM_ALLOWANCE)))
        status = parse_length("--hem-allowance", text, &options->hem_allowance_mm, ctx), hem_given = 1;
    if (!hem_given)
        options->hem_allowance_mm = options->seam_allowance_mm;
    if (status == PZ_OK && (text = pz_cli_value(args, PZ_CLI_OPT_NOTCH_SPACING)))
        status = parse_length("--notch-spacing", text, &options->notch_spacing_mm, ctx);
    if (status == PZ_OK && (text = pz_cli_value(args, PZ_CLI_OPT_FABRIC_WIDTH)))
        status = parse_length("--fabric-width", text, &options->fabric_width_mm, ctx);
    if (status == PZ_OK && (text = pz_cli_value(args, PZ_CLI_OPT_GAP)))
        status = parse_length("--gap", text, &options->gap_mm, ctx);
    if (status == PZ_OK && (text = pz_cli_value(args, PZ_CLI_OPT_PAPER))) {
        if (strcmp(text, "a4") != 0 && strcmp(text, "letter") != 0 && strcmp(text, "A4") != 0 &&
            strcmp(text, "Letter") != 0)
            return pz_error(ctx, PZ_ERR_USAGE, "%s: --paper: '%s' is not a4 or letter", args->command, text);
        options->paper = (text[0] == 'a' || text[0] == 'A') ? "a4" : "letter";
    }
    options->dxf_strict = pz_cli_value(args, PZ_CLI_OPT_DXF_STRICT) != NULL;
    if (status == PZ_OK && (text = pz_cli_value(args, PZ_CLI_OPT_SIZE)))
        options->size_name = text;
    if (status == PZ_OK && (text = pz_cli_value(args, PZ_CLI_OPT_ALLOWANCES))) {
        if (!*text)
            return pz_error(ctx, PZ_ERR_USAGE, "%s: --allowances: empty file name", args->command);
        run->allowances_path = text;
    }
    return status;
}

/* --backend, --iterations, --weights, --fabric, --grain. */
static pz_status parse_flatten_options(const pz_cli_args *args, pz_flatten_options *flatten, pz_ctx *ctx)
{
    const char *text;
    if ((text = pz_cli_value(args, PZ_CLI_OPT_BACKEND))) {
        flatten->backend = pz_backend_parse(text);
        if (flatten->backend == PZ_BACKEND_COUNT)
            return pz_error(ctx, PZ_ERR_USAGE, "flatten: --backend: '%s' is not textile, lscm, wirewarp or springmass",
                            text);
    }
    pz_status status = parse_backend_options(args, flatten, ctx);
    if (status != PZ_OK)
        return status;
    if ((text = pz_cli_value(args, PZ_CLI_OPT_ITERATIONS))) {
        char *end = NULL;
        errno = 0;
        long iterations = strtol(text, &end, 10);
        if (end == text || *end || errno == ERANGE || iterations < INT_MIN || iterations > INT_MAX)
            return pz_error(ctx, PZ_ERR_USAGE, "flatten: --iterations: '%s' is not a whole number in 1..%d", text,
                            PZ_MAX_ITERATIONS);
        flatten->iterations = (int)iterations;
    }
    if ((text = pz_cli_value(args, PZ_CLI_OPT_WEIGHTS))) {
        if ((status = parse_numbers("--weights", text, flatten->weights, 4, ctx)))
            return status;
    }
    if ((text = pz_cli_value(args, PZ_CLI_OPT_FABRIC))) {
        double fabric[3];
        if ((status = parse_numbers("--fabric", text, fabric, 3, ctx)))
            return status;
        flatten->fabric = (pz_fabric){fabric[0], fabric[1], fabric[2]};
        flatten->fabric_given = 1;
    }
    if ((text = pz_cli_value(args, PZ_CLI_OPT_GRAIN))) {
        if ((status = parse_numbers("--grain", text, flatten->grain, 3, ctx)))
            return status;
        flatten->grain_given = 1;
    }
    return PZ_OK;
}

pz_status pz_cli_pipeline_options(const pz_cli_args *args, pz_run_options *options, pz_ctx *ctx)
{
    pz_run_options_default(options);
    /* Every command writes the result as soon as it has it: the marker and the trade-off are made by the
     * write, beside the pattern files that do not need them (pipeline/write.c). */
    options->defer_extras = 1;
    options->units = args->units;
    options->repair_flags = args->repair_flags;
    options->name = args->positional_count > 0 ? args->positionals[0] : NULL;
    options->input_files = args->positionals;
    options->input_file_count = args->positional_count;
    pz_status status = parse_flatten_options(args, &options->flatten, ctx);
    if (status == PZ_OK)
        status = parse_export_options(args, options, ctx);
    const char *hints = pz_cli_value(args, PZ_CLI_OPT_GRAIN_HINTS);
    if (status == PZ_OK && hints && !*hints)
        status = pz_error(ctx, PZ_ERR_USAGE, "%s: --grain-hints: empty file name", args->command);
    options->grain_hints_path = hints;
    if (status == PZ_OK) /* the ranges: the library's, shared with the Python package */
        status = pz_run_options_check(options, "flatten", PZ_OPTION_FLAG, ctx);
    if (status == PZ_OK) {
        unsigned outputs;
        status = pz_cli_outputs(args, &outputs, ctx);
    }
    if (status != PZ_OK)
        return status;
    if (!args->output_path)
        return pz_error(ctx, PZ_ERR_USAGE, "%s: -o DIR is required (see panelize %s --help)", args->command,
                        args->command);
    if (args->positional_count < 1)
        return pz_error(ctx, PZ_ERR_USAGE, "%s: expected MESH (see panelize %s --help)", args->command,
                        args->command);
    if (args->positional_count > 1 && args->pose_path_count > 0)
        return pz_error(ctx, PZ_ERR_USAGE, "flatten: --pose works with one MESH, not %d panel files",
                        args->positional_count);
    /* Before any work: a folder that cannot receive the result is exit 73 at once, not after minutes. */
    return pz_output_folder_check(args->output_path, ctx);
}

pz_status pz_cli_outputs(const pz_cli_args *args, unsigned *outputs, pz_ctx *ctx)
{
    const char *text = pz_cli_value(args, PZ_CLI_OPT_OUTPUTS);
    *outputs = PZ_OUTPUT_ALL;
    if (!text)
        return PZ_OK;
    pz_status status = pz_outputs_parse(text, outputs, ctx);
    if (status != PZ_OK) {
        char message[sizeof ctx->error];
        snprintf(message, sizeof message, "%s", ctx->error);
        pz_error(ctx, status, "%s: %.*s", args->command, (int)sizeof message - 32, message);
    }
    return status;
}

/* ---------------------------------------------------------------- the result */

/* Every file the result would write, for the summary's "wrote:" line. */
static void print_written(const pz_cli_args *args, const pz_result *result, unsigned outputs)
{
    static const struct {
        unsigned bit;
        const char *name;
    } files[] = {{PZ_OUTPUT_GARMENT_OBJ, "garment.obj"}, {PZ_OUTPUT_SVG, "pattern.svg"},
                 {PZ_OUTPUT_PDF, "pattern.pdf"},         {PZ_OUTPUT_TILED_PDF, "pattern-tiled.pdf"},
                 {PZ_OUTPUT_DXF, "pattern.dxf"},         {PZ_OUTPUT_MARKER, "marker.svg"},
                 {PZ_OUTPUT_GLB, "garment.glb"},         {PZ_OUTPUT_LAYOUT_OBJ, "layout.obj"},
                 {PZ_OUTPUT_REPORT_JSON, "report.json"}, {PZ_OUTPUT_REPORT_HTML, "report.html"},
                 {PZ_OUTPUT_ENERGY_SVG, "energy.svg"}};
    printf("wrote:              %s/{", args->output_path);
    int first = 1;
    for (size_t i = 0; i < sizeof files / sizeof files[0]; ++i) {
        if (!(outputs & files[i].bit))
            continue;
        if (files[i].bit == PZ_OUTPUT_LAYOUT_OBJ && !result->from_run)
            continue;
        if (files[i].bit == PZ_OUTPUT_MARKER && !result->marker)
            continue;
        if (files[i].bit == PZ_OUTPUT_ENERGY_SVG && result->options.flatten.backend != PZ_BACKEND_SPRINGMASS)
            continue;
        printf("%s%s", first ? "" : ",", files[i].name);
        first = 0;
    }
    printf("}\n");
}

static void print_summary(const pz_cli_args *args, const pz_result *result, unsigned outputs)
{
    const pz_metrics *rest = result->metrics[0];
    double max_abs_strain = 0;
    int injective = 1;
    for (int i = 0; i < result->metrics_count; ++i) {
        max_abs_strain = fmax(max_abs_strain, result->metrics[i]->max_abs_strain);
        injective &= result->metrics[i]->injective != 0;
    }
    const pz_flatten_options *flatten = &result->options.flatten;
    printf("backend:            %s%s\n", pz_backend_name(flatten->backend),
           flatten->backend == PZ_BACKEND_WIREWARP ? (flatten->progressive ? " (progressive)" : " (global)")
           : flatten->backend == PZ_BACKEND_SPRINGMASS ? (flatten->relax_full ? " (full relaxation)"
                                                                              : " (heap relaxation)")
                                                       : "");
    printf("panels:             %d (from %s)\n", (int)rest->panel_count, result->panels_source);
    printf("seams, darts:       %d, %d\n", (int)rest->seam_count, (int)rest->dart_count);
    printf("max |strain|:       %.6f%s\n", max_abs_strain, result->metrics_count > 1 ? " (worst pose)" : "");
    printf("injective:          %s\n", injective ? "yes" : "no");
    printf("max seam mismatch:  %.6f\n", rest->max_seam_mismatch_rel);
    if (result->marker)
        printf("marker:             %.1f mm long, efficiency %.1f%% (at most %.1f%% for these pieces)\n",
               result->marker->length_mm, 100.0 * result->marker->efficiency, 100.0 * result->marker->efficiency_bound);
    if (result->from_run) {
        const pz_verdict *verdict = &result->verdict;
        if (result->segment)
            printf("segmentation:       %d panels, %d darts, symmetry %s\n", (int)result->segment->panel_count,
                   (int)result->segment->dart_count, result->segment->symmetry.found ? "yes" : "no");
        printf("goals met:          %s%s%s\n", verdict->goals_met ? "yes" : "no", verdict->goals_met ? "" : ": ",
               verdict->goals_met ? "" : verdict->reasons);
    }
    print_written(args, result, outputs);
}

pz_status pz_cli_write_result(const pz_cli_args *args, pz_result *result, double read_ms, pz_ctx *ctx)
{
    unsigned outputs = PZ_OUTPUT_ALL;
    pz_status status = pz_cli_outputs(args, &outputs, ctx);
    char *report_text = NULL;
    result->timings.read = read_ms;
    if (status == PZ_OK)
        status = pz_result_write(result, args->output_path, outputs, &report_text, ctx);
    if (status != PZ_OK)
        return status;
    const pz_timings *t = &result->timings;
    pz_note(ctx, "flatten: %d panel%s; read %.1f ms, pattern %.1f ms (choosing the panels %.1f ms), "
            "flatten %.1f ms, metrics %.1f ms, write %.1f ms, total %.1f ms", (int)result->pattern->panel_count,
            result->pattern->panel_count == 1 ? "" : "s", t->read, t->pattern, t->panels, t->flatten, t->metrics,
            t->pieces + t->write, t->read + t->total + t->write);
    if (args->json) {
        if (report_text) {
            fputs(report_text, stdout);
            fputc('\n', stdout);
        } else {
            cJSON *root = pz_result_report(result);
            status = pz_cli_print_json(root, root == NULL, ctx);
        }
    } else {
        print_summary(args, result, outputs);
    }
    free(report_text);
    return status;
}

/* ---------------------------------------------------------------- progress and Ctrl-C */

static volatile int cancel_flag;
static struct sigaction old_interrupt, old_terminate;
static int progress_drawn;

static void on_signal(int signal_number)
{
    (void)signal_number;
    cancel_flag = 1;
}

/* One line, redrawn in place: "panelize: segment  43%  insert: 6 panels". */
static void draw_progress(void *user, const char *stage, double fraction, const char *message)
{
    (void)user;
    fprintf(stderr, "\rpanelize: %-8s %3d%%  %-50.50s", stage, (int)(100 * fraction + 0.5), message);
    fflush(stderr);
    progress_drawn = 1;
}

void pz_cli_progress_begin(const pz_cli_args *args, pz_ctx *ctx)
{
    cancel_flag = 0;
    ctx->cancel = &cancel_flag;
    struct sigaction action;
    memset(&action, 0, sizeof action);
    action.sa_handler = on_signal;
    sigemptyset(&action.sa_mask);
    sigaction(SIGINT, &action, &old_interrupt);
    sigaction(SIGTERM, &action, &old_terminate);
    if (!args->quiet && isatty(STDERR_FILENO)) {
        ctx->progress = draw_progress;
        ctx->progress_user = NULL;
    }
}

void pz_cli_progress_end(pz_ctx *ctx)
{
    if (progress_drawn)
        fprintf(stderr, "\r%*s\r", 72, "");
    progress_drawn = 0;
    ctx->progress = NULL;
    ctx->cancel = NULL;
    sigaction(SIGINT, &old_interrupt, NULL);
    sigaction(SIGTERM, &old_terminate, NULL);
}

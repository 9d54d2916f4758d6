/*
 * pipeline/options.c -- the range of every option a person sets, checked in
 * one place for every front end: the command line (cli/) and the Python
 * package (python/) parse their text or arguments into the options structs
 * and then call these, so "--max-strain 11" and max_strain=11 fail with the
 * same rule and the same words (only the option's spelling differs).
 *
 * SPDX-License-Identifier: GPL-3.0-or-later
 */
#include "pipeline/pipeline.h"

#include <math.h>
#include <stddef.h>
#include <stdio.h>
#include <string.h>

/* "--max-strain" or "max_strain" from the option's name "max-strain". */
static const char *spelled(const char *name, pz_option_style style, char *buffer, size_t size)
{
    if (style == PZ_OPTION_FLAG) {
        snprintf(buffer, size, "--%s", name);
        return buffer;
    }
    snprintf(buffer, size, "%s", name);
    for (char *c = buffer; *c; ++c)
        if (*c == '-')
            *c = '_';
    return buffer;
}

/* What every check needs to phrase its message. */
typedef struct option_checker {
    const char *command;
    pz_option_style style;
    pz_ctx *ctx;
} option_checker;

static pz_status refuse(const option_checker *checker, const char *name, const char *problem)
{
    char option[64];
    return pz_error(checker->ctx, PZ_ERR_USAGE, "%s: %s: %s", checker->command,
                    spelled(name, checker->style, option, sizeof option), problem);
}

/* A finite number in lo..hi (whole when `whole`). */
static pz_status in_range(const option_checker *checker, const char *name, double value, double lo, double hi,
                          int whole)
{
    if (isfinite(value) && value >= lo && value <= hi && (!whole || value == floor(value)))
        return PZ_OK;
    char problem[160];
    snprintf(problem, sizeof problem, "%.17g is not a %s in %g..%g", value, whole ? "whole number" : "number", lo,
             hi);
    return refuse(checker, name, problem);
}

/* `count` finite numbers, each at least `lo` (above it when `strictly`). */
static pz_status all_at_least(const option_checker *checker, const char *name, const double *values, int count,
                              double lo, int strictly)
{
    for (int i = 0; i < count; ++i)
        if (!isfinite(values[i]) || values[i] < lo || (strictly && values[i] == lo))
            return refuse(checker, name, strictly ? "every value must be finite and positive"
                                                  : "every value must be finite and not negative");
    return PZ_OK;
}

/* A number option's range: its name, where it is in the struct, lo..hi, whole or not. */
typedef struct option_range {
    const char *name;
    size_t offset;
    double lo, hi;
    int whole;
} option_range;

/* Every number of `ranges` (doubles in `options`) in its range. */
static pz_status check_ranges(const option_checker *checker, const void *options, const option_range *ranges,
                              int count)
{
    pz_status status = PZ_OK;
    for (int i = 0; i < count && status == PZ_OK; ++i) {
        double value = *(const double *)((const char *)options + ranges[i].offset);
        status = in_range(checker, ranges[i].name, value, ranges[i].lo, ranges[i].hi, ranges[i].whole);
    }
    return status;
}

static pz_status check_goals(const option_checker *checker, const pz_goal_options *goals)
{
    static const option_range ranges[] = {
        {"max-strain", offsetof(pz_goal_options, max_strain), 0, 10, 0},
        {"max-seam-mismatch", offsetof(pz_goal_options, max_seam_mismatch), 0, 1, 0},
        {"min-piece-width", offsetof(pz_goal_options, min_piece_width_mm), 0, 1000, 0},
        {"min-piece-area", offsetof(pz_goal_options, min_piece_area), 0, 0.5, 0},
        {"min-dart-intake", offsetof(pz_goal_options, min_dart_intake_mm), 0, 1000, 0}};
    pz_status status = in_range(checker, "max-corners", goals->max_corners, 1, 1000, 1);
    return status == PZ_OK ? check_ranges(checker, goals, ranges, (int)(sizeof ranges / sizeof ranges[0])) : status;
}

static pz_status check_flatten(const option_checker *checker, const pz_flatten_options *flatten)
{
    if (flatten->backend < 0 || flatten->backend >= PZ_BACKEND_COUNT)
        return refuse(checker, "backend", "not textile, lscm, wirewarp or springmass");
    pz_status status = in_range(checker, "iterations", flatten->iterations, 1, PZ_MAX_ITERATIONS, 1);
    if (status == PZ_OK)
        status = all_at_least(checker, "weights", flatten->weights, 4, 0, 0);
    if (status == PZ_OK && flatten->fabric_given) {
        const double fabric[3] = {flatten->fabric.k_su, flatten->fabric.k_sv, flatten->fabric.k_r};
        status = all_at_least(checker, "fabric", fabric, 3, 0, 1);
    }
    if (status == PZ_OK && flatten->grain_given &&
        (!isfinite(flatten->grain[0] + flatten->grain[1] + flatten->grain[2]) ||
         (flatten->grain[0] == 0 && flatten->grain[1] == 0 && flatten->grain[2] == 0)))
        status = refuse(checker, "grain", "not a finite, non-zero direction");
    return status;
}

static pz_status check_export(const option_checker *checker, const pz_export_options *output)
{
    static const option_range ranges[] = {
        {"seam-allowance", offsetof(pz_export_options, seam_allowance_mm), 0, 100, 0},
        {"notch-spacing", offsetof(pz_export_options, notch_spacing_mm), 1, 10000, 0},
        {"fabric-width", offsetof(pz_export_options, fabric_width_mm), 10, 10000, 0},
        {"gap", offsetof(pz_export_options, gap_mm), 0, 1000, 0}};
    pz_status status = check_ranges(checker, output, ranges, (int)(sizeof ranges / sizeof ranges[0]));
    if (status == PZ_OK && !(output->hem_allowance_mm < 0)) /* < 0: the seam allowance */
        status = in_range(checker, "hem-allowance", output->hem_allowance_mm, 0, 100, 0);
    if (status == PZ_OK && output->paper && strcmp(output->paper, "a4") != 0 && strcmp(output->paper, "letter") != 0)
        status = refuse(checker, "paper", "not a4 or letter");
    if (status == PZ_OK && output->size_name &&
        (!*output->size_name || strlen(output->size_name) >= sizeof ((pz_pieces *)0)->size_name)) {
        char problem[96];
        snprintf(problem, sizeof problem, "not a name of 1 to %d characters",
                 (int)sizeof ((pz_pieces *)0)->size_name - 1);
        status = refuse(checker, "size", problem);
    }
    return status;
}

pz_status pz_run_options_check(const pz_run_options *options, const char *command, pz_option_style style,
                               pz_ctx *ctx)
{
    option_checker checker = {command ? command : "run", style, ctx};
    pz_status status = check_goals(&checker, &options->goals);
    if (status == PZ_OK)
        status = check_flatten(&checker, &options->flatten);
    if (status == PZ_OK)
        status = check_export(&checker, &options->output);
    const double *plane = options->segment.symmetry_plane;
    if (status == PZ_OK && options->segment.symmetry == PZ_SYMMETRY_PLANE &&
        (!isfinite(plane[0] + plane[1] + plane[2] + plane[3]) ||
         !(plane[0] * plane[0] + plane[1] * plane[1] + plane[2] * plane[2] > 0)))
        status = refuse(&checker, "symmetry", "the plane's normal must be finite and not zero");
    return status;
}

pz_status pz_field_options_check(const pz_field_options *options, const char *command, pz_option_style style,
                                 pz_ctx *ctx)
{
    option_checker checker = {command ? command : "field", style, ctx};
    pz_status status = in_range(&checker, "scales", options->scale_count, 1, PZ_FIELD_MAX_SCALES, 1);
    if (status == PZ_OK && !(isfinite(options->smoothness) && options->smoothness > 0))
        status = refuse(&checker, "smoothness", "must be a finite positive number");
    return status;
}

pz_status pz_prepare_options_check(const pz_prepare_options *options, const char *command, pz_option_style style,
                                   pz_ctx *ctx)
{
    option_checker checker = {command ? command : "prepare", style, ctx};
    char problem[96];
    if (options->target_edge != 0 && options->target_faces != 0) {
        char other[64];
        snprintf(problem, sizeof problem, "give it or %s, not both", spelled("faces", style, other, sizeof other));
        return refuse(&checker, "edge", problem);
    }
    if (!isfinite(options->target_edge) || options->target_edge < 0)
        return refuse(&checker, "edge", "must be a finite length in mm, not negative");
    if (options->target_faces < 0)
        return refuse(&checker, "faces", "must not be negative");
    if (!isfinite(options->weld_distance))
        return refuse(&checker, "weld", "must be a finite length in mm");
    return PZ_OK;
}

/*
 * cli/cmd_run.c -- `panelize run GARMENT -o DIR`: the whole pipeline, garment
 * in, sewable pattern out, no hand work (docs/run.md). A caller of pz_run
 * (pipeline/pipeline.h): this file turns argv into options, reads the files,
 * and writes the result; no algorithm lives here.
 *
 * With --panels the user's own panels are flattened and segmentation is
 * skipped (so is preparation, which would renumber the faces the panels
 * refer to); the goals are still judged.
 *
 * SPDX-License-Identifier: GPL-3.0-or-later
 */
#define _POSIX_C_SOURCE 200809L
#include "cli/cli.h"

#include <errno.h>
#include <math.h>
#include <stdlib.h>
#include <string.h>

const char pz_cli_run_usage[] =
    "usage: panelize run GARMENT -o DIR [--max-corners C] [--max-strain S] [--max-pieces N]\n"
    "           [--pose FILE]... [--sketch FILE] [--mirror-sketch] [--panels FILE|uv]\n"
    "           [--symmetry auto|off|x|y|z|PLANE] [--fold] [--darts on|off] [--truing on|off]\n"
    "           [--consolidate on|off]\n"
    "           [--grain X,Y,Z] [--grain-hints FILE]\n"
    "           [--prepare auto|off] [--backend textile|lscm|wirewarp|springmass]\n"
    "           [--iterations N] [--weights S,R,D,M] [--fabric KSU,KSV,KR]\n"
    "           [--seam-allowance MM] [--hem-allowance MM] [--allowances FILE]\n"
    "           [--notch-spacing MM] [--paper a4|letter] [--dxf-strict]\n"
    "           [--fabric-width MM] [--gap MM] [--size NAME] [--outputs LIST]\n"
    "           [--max-seam-mismatch R] [--min-piece-width MM] [--min-piece-area R]\n"
    "           [--min-dart-intake MM] [--strict] [--units U] [--repair]\n"
    "           [--json] [--quiet]\n"
    "\n"
    "Cuts a 3D garment into panels along field-aligned seams, adds darts and\n"
    "flattens every panel into a sewable pattern. Writes into DIR everything\n"
    "`panelize flatten` writes (garment.obj, the pattern files, report.json)\n"
    "plus layout.obj, the seams and darts as polylines on the 3D garment.\n"
    "\n"
    "options:\n"
    "  -o DIR               the output directory (required)\n"
    "  --max-corners C      at most C corners per panel (default 8)\n"
    "  --max-strain S       every triangle's warp and weft strain within +-S\n"
    "                       (default 0.05: 5% in tension or compression)\n"
    "  --max-pieces N       at most N pieces (a mirror pair counts as two), with the\n"
    "                       least strain: the layout is made, then merged down;\n"
    "                       corners and S then give way (default: no budget)\n"
    "  --max-seam-mismatch R  every seam's and dart's two sides within R of their\n"
    "                       length (default 0.005: 0.5%)\n"
    "  --min-piece-width MM no piece narrower (twice its largest inscribed distance;\n"
    "                       default 40, 0: off) unless the garment is that narrow\n"
    "  --min-piece-area R   no piece under R of the garment's area (default 0.01)\n"
    "                       unless it is a whole part of the garment\n"
    "  --min-dart-intake MM a dart takes in at least MM at its mouth (default 6)\n"
    "  --strict             exit 3 when the pattern misses a goal (files written)\n"
    "  --symmetry M         auto (default: find a mirror plane in any orientation),\n"
    "                       off, x, y or z (that axis's plane, its offset fitted),\n"
    "                       or a plane: NX,NY,NZ,D (the plane n . p = D) or\n"
    "                       PX,PY,PZ,NX,NY,NZ (a point on it and its normal), in\n"
    "                       the garment's units. The layout is made on one half\n"
    "                       and mirrored, unless that gives more panels than the\n"
    "                       layout without the plane (then it is not used)\n"
    "  --fold               draw a piece that is its own mirror image as its half,\n"
    "                       to be cut on the fold (the fold line marked)\n"
    "  --darts on|off       insert darts where a seam can be partly closed (default on)\n"
    "  --consolidate on|off on (default): once the layout of a garment with a mirror\n"
    "                       plane meets its goals, it is made again with one piece\n"
    "                       fewer and kept when that meets them too, with no more\n"
    "                       seam on the plane (off: the greedy layout as made)\n"
    "  --truing on|off      smooth the seams traced along mesh edges into clean lines\n"
    "                       by moving their vertices along the surface (default on;\n"
    "                       off keeps garment.obj's positions exactly the input's)\n"
    "  --sketch FILE        JSON {\"curves\": [[[x,y,z], ...], ...]} in the garment's\n"
    "                       units: curves that become seams, never removed. On a\n"
    "                       garment with a mirror plane, a sketch that is not\n"
    "                       symmetric lays the garment out without the plane\n"
    "  --mirror-sketch      draw each sketch curve's mirror image too (about the\n"
    "                       garment's plane, when one is found): symmetric pieces\n"
    "  --panels FILE|uv     the user's own panels (see panelize flatten): no\n"
    "                       segmentation, no preparation\n"
    "  --prepare auto|off   auto (default): weld, repair and remesh the garment\n"
    "                       only when it needs it (see panelize prepare)\n"
    "  --grain X,Y,Z        the 3D warp direction (default: the garment's vertical)\n"
    "  --grain-hints FILE   JSON {\"curves\": [[[x,y,z], ...], ...]} in the garment's\n"
    "                       units: short strokes along which the warp runs in the\n"
    "                       piece each lies on (a bias-cut region); the field\n"
    "                       follows them too\n"
    "  --pose FILE          an extra pose with the same connectivity (repeatable)\n"
    "  --outputs LIST       the files to write (see panelize flatten --help; layout\n"
    "                       adds layout.obj)\n"
    "  other options        as in panelize flatten --help\n"
    "\n"
    "See docs/run.md.\n";

/* One of the words in `names` (count of them) into *index; PZ_ERR_USAGE listing them otherwise. */
static pz_status parse_word(const char *option, const char *text, const char *const *names, int count, int *index,
                            pz_ctx *ctx)
{
    for (int i = 0; i < count; ++i)
        if (strcmp(text, names[i]) == 0) {
            *index = i;
            return PZ_OK;
        }
    char list[128] = "";
    size_t used = 0;
    for (int i = 0; i < count && used < sizeof list; ++i)
        used += (size_t)snprintf(list + used, sizeof list - used, "%s%s", i == 0 ? "" : i + 1 < count ? ", " : " or ",
                                 names[i]);
    return pz_error(ctx, PZ_ERR_USAGE, "run: %s: '%s' is not %s", option, text, list);
}

static pz_status parse_on_off(const char *option, const char *text, int *value, pz_ctx *ctx)
{
    static const char *const words[] = {"off", "on"};
    return parse_word(option, text, words, 2, value, ctx);
}

/* The number of option `flag` (when given) into *value: a finite number, else exit 64 (its range is
 * checked with every other option's, pz_run_options_check). */
static pz_status parse_number(const pz_cli_args *args, uint64_t flag, const char *option, double *value, pz_ctx *ctx)
{
    const char *text = pz_cli_value(args, flag);
    if (!text)
        return PZ_OK;
    char *end = NULL;
    errno = 0;
    double number = strtod(text, &end);
    if (end == text || *end || errno == ERANGE || !isfinite(number))
        return pz_error(ctx, PZ_ERR_USAGE, "run: %s: '%s' is not a number", option, text);
    *value = number;
    return PZ_OK;
}

/*
 * --symmetry: a word (auto, off, x, y, z) or a plane given by numbers, 4
 * (nx,ny,nz,d: the plane n . p = d) or 6 (px,py,pz,nx,ny,nz: a point on it
 * and its normal), in the garment's units (the pipeline scales d with the
 * mesh).
 */
static pz_status parse_symmetry(const char *text, pz_segment_options *segment, pz_ctx *ctx)
{
    static const char *const names[] = {"auto", "off", "x", "y", "z"};
    static const pz_symmetry_mode modes[] = {PZ_SYMMETRY_AUTO, PZ_SYMMETRY_OFF, PZ_SYMMETRY_X, PZ_SYMMETRY_Y,
                                             PZ_SYMMETRY_Z};
    int index = 0;
    if (!(text[0] == '-' || text[0] == '+' || text[0] == '.' || (text[0] >= '0' && text[0] <= '9'))) {
        pz_status status = parse_word("--symmetry", text, names, 5, &index, ctx);
        if (status == PZ_OK)
            segment->symmetry = modes[index];
        return status;
    }
    double values[6];
    int count = 0;
    const char *at = text;
    while (count < 6) {
        char *end = NULL;
        errno = 0;
        values[count] = strtod(at, &end);
        if (end == at || errno == ERANGE || !isfinite(values[count]))
            break;
        ++count;
        at = end;
        if (*at != ',')
            break;
        ++at;
    }
    double n[3] = {count == 6 ? values[3] : values[0], count == 6 ? values[4] : values[1],
                   count == 6 ? values[5] : values[2]};
    double length = sqrt(n[0] * n[0] + n[1] * n[1] + n[2] * n[2]);
    if (*at || (count != 4 && count != 6) || !(length > 0))
        return pz_error(ctx, PZ_ERR_USAGE,
                        "run: --symmetry: '%s' is not auto, off, x, y, z, a plane NX,NY,NZ,D or a point and a normal "
                        "PX,PY,PZ,NX,NY,NZ (the normal not zero)", text);
    segment->symmetry = PZ_SYMMETRY_PLANE;
    memcpy(segment->symmetry_plane, n, sizeof n);
    segment->symmetry_plane[3] = count == 4 ? values[3] : n[0] * values[0] + n[1] * values[1] + n[2] * values[2];
    return PZ_OK;
}

/* The goals: --max-corners, --max-strain, --max-seam-mismatch, and the piece shapes: --min-piece-width,
 * --min-piece-area, --min-dart-intake (0 turns one off). */
static pz_status parse_goals(const pz_cli_args *args, pz_goal_options *goals, pz_ctx *ctx)
{
    double corners = goals->max_corners;
    pz_status status = parse_number(args, PZ_CLI_OPT_MIN_PIECE_WIDTH, "--min-piece-width", &goals->min_piece_width_mm,
                                    ctx);
    if (status == PZ_OK)
        status = parse_number(args, PZ_CLI_OPT_MIN_PIECE_AREA, "--min-piece-area", &goals->min_piece_area, ctx);
    if (status == PZ_OK)
        status = parse_number(args, PZ_CLI_OPT_MIN_DART_INTAKE, "--min-dart-intake", &goals->min_dart_intake_mm, ctx);
    if (status == PZ_OK)
        status = parse_number(args, PZ_CLI_OPT_MAX_CORNERS, "--max-corners", &corners, ctx);
    if (status == PZ_OK)
        status = parse_number(args, PZ_CLI_OPT_MAX_STRAIN, "--max-strain", &goals->max_strain, ctx);
    if (status == PZ_OK)
        status = parse_number(args, PZ_CLI_OPT_MAX_SEAM_MISMATCH, "--max-seam-mismatch", &goals->max_seam_mismatch,
                              ctx);
    if (status == PZ_OK && corners != floor(corners))
        status = pz_error(ctx, PZ_ERR_USAGE, "run: --max-corners: '%s' is not a whole number",
                          pz_cli_value(args, PZ_CLI_OPT_MAX_CORNERS));
    /* Out of int32's range: kept out of range (the check below names it) without an undefined conversion. */
    goals->max_corners = corners > 1e6 ? 1000001 : corners < -1e6 ? -1 : (int32_t)corners;
    return status;
}

static pz_status parse_run_options(const pz_cli_args *args, pz_run_options *options, pz_ctx *ctx)
{
    pz_status status = parse_goals(args, &options->goals, ctx);
    const char *text;
    if (status == PZ_OK && (text = pz_cli_value(args, PZ_CLI_OPT_MAX_PIECES))) {
        char *end = NULL;
        errno = 0;
        long pieces = strtol(text, &end, 10);
        if (end == text || *end || errno == ERANGE || pieces < 1 || pieces > 100000)
            return pz_error(ctx, PZ_ERR_USAGE, "run: --max-pieces: '%s' is not a whole number in 1..100000", text);
        options->segment.max_pieces = (int32_t)pieces;
    }
    if (status == PZ_OK && (text = pz_cli_value(args, PZ_CLI_OPT_SYMMETRY)))
        status = parse_symmetry(text, &options->segment, ctx);
    options->output.fold = pz_cli_value(args, PZ_CLI_OPT_FOLD) != NULL;
    if (status == PZ_OK && args->dart_path_count > 1)
        return pz_error(ctx, PZ_ERR_USAGE, "run: --darts given twice");
    if (status == PZ_OK && args->dart_path_count == 1)
        status = parse_on_off("--darts", args->dart_paths[0], &options->segment.darts, ctx);
    if (status == PZ_OK && (text = pz_cli_value(args, PZ_CLI_OPT_PREPARE))) {
        static const char *const modes[] = {"off", "auto"};
        status = parse_word("--prepare", text, modes, 2, &options->prepare, ctx);
    }
    if (status == PZ_OK && (text = pz_cli_value(args, PZ_CLI_OPT_TRUING)))
        status = parse_on_off("--truing", text, &options->truing, ctx);
    if (status == PZ_OK && (text = pz_cli_value(args, PZ_CLI_OPT_CONSOLIDATE)))
        status = parse_on_off("--consolidate", text, &options->consolidate, ctx);
    if (status == PZ_OK && (text = pz_cli_value(args, PZ_CLI_OPT_SKETCH))) {
        if (!*text)
            return pz_error(ctx, PZ_ERR_USAGE, "run: --sketch: empty file name");
        options->sketch_path = text;
    }
    options->mirror_sketch = pz_cli_value(args, PZ_CLI_OPT_MIRROR_SKETCH) != NULL;
    if (status == PZ_OK && args->positional_count > 1)
        status = pz_error(ctx, PZ_ERR_USAGE, "run: expected one GARMENT, got %d files", args->positional_count);
    if (status == PZ_OK) /* the ranges: the library's, shared with the Python package */
        status = pz_run_options_check(options, "run", PZ_OPTION_FLAG, ctx);
    return status;
}

/* --panels FILE|uv: the user's panels (no segmentation, no preparation). */
static pz_status read_panels(const pz_cli_args *args, const pz_mesh *mesh, pz_panels *panels, int32_t **face_panel,
                             pz_ctx *ctx)
{
    const char *text = pz_cli_value(args, PZ_CLI_OPT_PANELS);
    memset(panels, 0, sizeof *panels);
    if (strcmp(text, "uv") == 0) {
        panels->source = PZ_PANELS_UV;
        return PZ_OK;
    }
    *face_panel = malloc(((size_t)mesh->face_count + 1) * sizeof(int32_t));
    if (!*face_panel)
        return pz_error(ctx, PZ_ERR_NOMEM, "run: out of memory finding panels");
    panels->source = PZ_PANELS_FACES;
    panels->face_panel = *face_panel;
    panels->face_panel_name = text;
    return pz_read_panel_file(text, mesh->face_count, *face_panel, &panels->panel_count, ctx);
}

/* Messages from the shared steps say "flatten:"; name the command that ran. */
static void rename_message(pz_ctx *ctx)
{
    if (strncmp(ctx->error, "flatten: ", 9) != 0)
        return;
    char message[sizeof ctx->error];
    snprintf(message, sizeof message, "%s", ctx->error + 9);
    snprintf(ctx->error, sizeof ctx->error, "run: %.*s", (int)(sizeof message - 16), message);
}

pz_status pz_cli_run_options(const pz_cli_args *args, pz_run_options *options, pz_ctx *ctx)
{
    pz_status status = pz_cli_pipeline_options(args, options, ctx);
    if (status == PZ_OK)
        status = parse_run_options(args, options, ctx);
    if (status != PZ_OK)
        rename_message(ctx);
    return status;
}

pz_status pz_cli_run(const pz_cli_args *args, pz_ctx *ctx)
{
    pz_run_options options;
    pz_status status = pz_cli_run_options(args, &options, ctx);
    if (status != PZ_OK)
        return status;
    double start = pz_seconds();
    pz_mesh *mesh = NULL;
    pz_panels panels;
    int32_t *face_panel = NULL;
    status = pz_cli_read_meshes(args, &mesh, NULL, ctx);
    if (status == PZ_OK && pz_cli_value(args, PZ_CLI_OPT_PANELS)) {
        status = read_panels(args, mesh, &panels, &face_panel, ctx);
        options.panels = &panels;
    }
    double read_ms = pz_elapsed_ms(start, pz_seconds());
    pz_result *result = NULL;
    pz_cli_progress_begin(args, ctx);
    if (status == PZ_OK)
        status = pz_run(mesh, &options, &result, ctx);
    pz_mesh_free(&mesh);
    free(face_panel);
    if (status == PZ_OK)
        status = pz_cli_write_result(args, result, read_ms, ctx);
    pz_cli_progress_end(ctx);
    /* --strict: a pattern that misses its goals is a failure for scripts, once its files are written. */
    if (status == PZ_OK && pz_cli_value(args, PZ_CLI_OPT_STRICT) && !result->verdict.goals_met) {
        /* The S that can be met first (issue 15: the one figure a script can act on), then the panels. */
        char reachable[160] = "";
        if (result->looser_reachable_strain > options.goals.max_strain)
            snprintf(reachable, sizeof reachable, "S = %g cannot be met here, S = %g can (%d panels%s); ",
                     options.goals.max_strain, result->looser_reachable_strain, (int)result->looser_reachable_panels,
                     result->looser_written_strain > 0 ? ", its layout written" : "");
        pz_error(ctx, PZ_ERR_USAGE, "run: goals not met (--strict): %s%s", reachable, result->verdict.reasons);
        status = PZ_CLI_GOALS_NOT_MET;
    }
    pz_result_free(&result);
    if (status != PZ_OK)
        rename_message(ctx);
    return status;
}

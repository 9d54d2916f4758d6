/*
 * cli/cmd_prepare.c -- `panelize prepare MESH -o OUT`: scan-ready input
 * (mesh/prepare.c, docs/prepare.md): weld, repair, drop fragments, decimate,
 * remesh, carry the poses over, report the Hausdorff distance.
 *
 * The preparation runs quietly and its steps are printed only once it has
 * succeeded, so that a failed run prints exactly its one error line. Outputs:
 * OUT (rest pose; with poses and an .obj/.ply OUT, pose p goes to
 * OUT-stem.poseP.EXT as `generate` does, a .glb keeps them as morph targets)
 * and, only when welding found seams, OUT-stem.seams.json beside OUT: the
 * welded seams as a sketch file for `panelize field --sketch` (named after
 * OUT so that it never replaces a user's own seams.json; refused when it
 * would replace an input). All written atomically (temporary file, then
 * rename); a failure removes what was already written.
 *
 * SPDX-License-Identifier: GPL-3.0-or-later
 */
#include "cli/cli.h"
#include "io/io.h"
#include "prepare/prepare.h"

#include <errno.h>
#include <math.h>
#include <sys/stat.h>
#include <stdlib.h>
#include <string.h>

const char pz_cli_prepare_usage[] =
    "usage: panelize prepare MESH -o OUT [--edge MM | --faces N] [--weld MM]\n"
    "                        [--keep largest|all] [--repair] [--pose FILE]...\n"
    "                        [--units U] [--json] [--quiet]\n"
    "\n"
    "Makes a scan or an export ready for panelize: welds coincident vertices\n"
    "(unwelded panels become one surface; the welded edges are kept as seams),\n"
    "drops non-finite, degenerate, duplicate and non-manifold faces, splits\n"
    "non-manifold vertices, orients the faces, drops fragments, decimates huge\n"
    "inputs and remeshes isotropically (outline and seams kept), carries extra\n"
    "poses over, and reports the Hausdorff distance to the repaired input\n"
    "against 0.5% of the bounding-box diagonal. Writes OUT (.obj, .ply or .glb,\n"
    "in mm) and, when welding found seams, OUT-stem.seams.json beside it\n"
    "({\"curves\": [[[x,y,z], ...], ...]}, for `panelize field --sketch`).\n"
    "\n"
    "options:\n"
    "  -o, --output OUT   output mesh; with poses and .obj/.ply, pose P goes to\n"
    "                     OUT-stem.poseP.EXT beside it\n"
    "  --edge MM          remeshing edge length in mm\n"
    "  --faces N          remesh to about N faces instead (default 20000)\n"
    "  --weld MM          weld vertices closer than MM (default 0.01; 0 = off)\n"
    "  --keep largest|all largest (default): drop components under 1% of the\n"
    "                     area; all: keep every component as a garment part\n"
    "  --repair           weld and repair only: no decimation or remeshing\n"
    "  --pose FILE        an extra pose with the input's connectivity (repeatable)\n"
    "  --units U          the mesh file's units: mm, cm, m, or auto (default)\n"
    "  --json             print the report (every step with its counts) on stdout\n"
    "  --quiet            nothing on stderr but an error\n";

/* A positive (or, with allow_zero, non-negative) finite number, else a usage error naming the option. */
static pz_status parse_length(const char *option, const char *text, int allow_zero, double *out, pz_ctx *ctx)
{
    char *end = NULL;
    errno = 0;
    double value = strtod(text, &end);
    if (errno || end == text || *end || !isfinite(value) || value < 0.0 || (!allow_zero && value == 0.0))
        return pz_error(ctx, PZ_ERR_USAGE, "prepare: %s: expected a %s length in mm, got '%s'", option,
                        allow_zero ? "non-negative" : "positive", text);
    *out = value;
    return PZ_OK;
}

static pz_status refuse_input(const pz_cli_args *args, const char *path, pz_ctx *ctx);

static pz_status parse_options(const pz_cli_args *args, pz_prepare_options *options, pz_ctx *ctx)
{
    memset(options, 0, sizeof *options);
    pz_status status = pz_cli_expect_positionals(args, 1, "one MESH", ctx);
    if (status)
        return status;
    if (!args->output_path)
        return pz_error(ctx, PZ_ERR_USAGE, "prepare: -o OUT is required");
    pz_format format = pz_format_from_path(args->output_path);
    if (format != PZ_FORMAT_OBJ && format != PZ_FORMAT_PLY && format != PZ_FORMAT_GLB)
        return pz_error(ctx, PZ_ERR_USAGE, "prepare: %s: cannot write this format (use .obj, .ply or .glb)",
                        args->output_path);
    /* Before the long work: never the input itself (by any path to it), and a place the file can be made. */
    if ((status = refuse_input(args, args->output_path, ctx)) || (status = pz_output_file_check(args->output_path, ctx)))
        return status;
    const char *edge = pz_cli_value(args, PZ_CLI_OPT_EDGE);
    if (edge && (status = parse_length("--edge", edge, 0, &options->target_edge, ctx)))
        return status;
    options->target_faces = args->target_faces;
    const char *weld = pz_cli_value(args, PZ_CLI_OPT_WELD);
    if (weld) {
        if ((status = parse_length("--weld", weld, 1, &options->weld_distance, ctx)))
            return status;
        if (options->weld_distance == 0.0)
            options->weld_distance = -1.0; /* off */
    }
    const char *keep = pz_cli_value(args, PZ_CLI_OPT_KEEP);
    if (keep && strcmp(keep, "all") == 0)
        options->keep = PZ_PREPARE_KEEP_ALL;
    else if (keep && strcmp(keep, "largest") != 0)
        return pz_error(ctx, PZ_ERR_USAGE, "prepare: --keep: expected largest or all, got '%s'", keep);
    options->no_remesh = args->repair_flags != 0;
    options->name = args->positionals[0];
    return pz_prepare_options_check(options, "prepare", PZ_OPTION_FLAG, ctx); /* shared with the Python package */
}

/* ---------------------------------------------------------------- output */

/* "dir/out.obj" -> "dir/out.pose2.obj" (pose_number 2); "dir/out.obj" -> "dir/out.seams.json" (0) (caller frees). */
static char *sibling_path(const char *path, int pose_number)
{
    const char *slash = strrchr(path, '/');
    const char *dot = strrchr(path, '.');
    if (!dot || (slash && dot < slash))
        dot = path + strlen(path);
    size_t size = strlen(path) + 32;
    char *result = malloc(size);
    if (!result)
        return NULL;
    if (pose_number > 0)
        snprintf(result, size, "%.*s.pose%d%s", (int)(dot - path), path, pose_number, dot);
    else
        snprintf(result, size, "%.*s.seams.json", (int)(dot - path), path);
    return result;
}

static void remove_all(char **paths, int count)
{
    for (int i = 0; i < count; ++i)
        if (paths[i])
            remove(paths[i]);
}

/* Whether the two paths name the same existing file. */
static int same_file(const char *a, const char *b)
{
    struct stat sa, sb;
    return stat(a, &sa) == 0 && stat(b, &sb) == 0 && sa.st_dev == sb.st_dev && sa.st_ino == sb.st_ino;
}

/* A usage error when `path` (an output) is the input mesh or one of its pose files. */
static pz_status refuse_input(const pz_cli_args *args, const char *path, pz_ctx *ctx)
{
    int clash = same_file(path, args->positionals[0]);
    for (int p = 0; p < args->pose_path_count && !clash; ++p)
        clash = same_file(path, args->pose_paths[p]);
    return clash ? pz_error(ctx, PZ_ERR_USAGE, "prepare: %s: is an input: refusing to overwrite it (choose another -o)",
                            path)
                 : PZ_OK;
}

/*
 * Writes pose files, the mesh, then the seams file (only when there are
 * seams); paths[0] = seams (NULL when none), [1..] = poses, filled for the
 * report.
 */
static pz_status write_outputs(const pz_cli_args *args, const pz_prepare_result *result, char **paths,
                               pz_ctx *ctx)
{
    const pz_mesh *mesh = result->mesh;
    const char *out = args->output_path;
    int separate = pz_format_from_path(out) != PZ_FORMAT_GLB ? mesh->pose_count : 0;
    for (int p = result->seam_count > 0 ? 0 : 1; p <= separate; ++p)
        if (!(paths[p] = sibling_path(out, p)))
            return pz_error(ctx, PZ_ERR_NOMEM, "%s: out of memory", out);
    pz_status status = paths[0] ? refuse_input(args, paths[0], ctx) : PZ_OK;
    for (int p = 1; p <= separate && !status; ++p)
        status = refuse_input(args, paths[p], ctx);
    int written = 1; /* paths[0], the seams, is written last */
    for (; written <= separate && !status; ++written) {
        pz_mesh view = *mesh;
        view.positions = mesh->poses + (size_t)(written - 1) * mesh->vertex_count * 3;
        view.pose_count = 0;
        view.poses = NULL;
        status = pz_mesh_write(&view, paths[written], NULL, ctx);
    }
    if (!status) {
        pz_mesh rest = *mesh;
        if (separate) {
            rest.pose_count = 0;
            rest.poses = NULL;
        }
        status = pz_mesh_write(&rest, out, NULL, ctx);
        if (!status && paths[0] && (status = pz_prepare_write_seams(result, paths[0], ctx)))
            remove(out);
    }
    if (status)
        remove_all(paths + 1, written - 1);
    return status;
}

/* ---------------------------------------------------------------- report */

static void note_steps(const pz_prepare_report *report, const char *name, pz_ctx *ctx)
{
    for (int s = 0; s < PZ_PREPARE_STEP_COUNT; ++s)
        pz_note(ctx, "%s: %-9s %s (%.2f s)", name, report->steps[s].name, report->steps[s].detail,
                report->steps[s].seconds);
}

static pz_status print_json(const pz_cli_args *args, const pz_prepare_result *result, char **paths, int pose_files,
                            pz_ctx *ctx)
{
    const pz_prepare_report *r = &result->report;
    cJSON *root = cJSON_CreateObject(), *steps = cJSON_CreateObject(), *counts = cJSON_CreateObject();
    int failed = !root || !steps || !counts;
    if (!failed) {
        cJSON_AddItemToObject(root, "steps", steps);
        cJSON_AddItemToObject(root, "counts", counts);
    } else {
        cJSON_Delete(steps);
        cJSON_Delete(counts);
    }
    failed = failed || !cJSON_AddStringToObject(root, "input", args->positionals[0]);
    failed = failed || !cJSON_AddStringToObject(root, "output", args->output_path);
    failed = failed || !(paths[0] ? cJSON_AddStringToObject(root, "seams_file", paths[0])
                                  : cJSON_AddNullToObject(root, "seams_file"));
    cJSON *pose_list = failed ? NULL : cJSON_AddArrayToObject(root, "pose_files");
    failed = failed || !pose_list;
    for (int p = 1; !failed && p <= pose_files; ++p)
        failed = !cJSON_AddItemToArray(pose_list, cJSON_CreateString(paths[p]));
    for (int s = 0; !failed && s < PZ_PREPARE_STEP_COUNT; ++s) {
        cJSON *step = cJSON_AddObjectToObject(steps, r->steps[s].name);
        failed = !step || !cJSON_AddBoolToObject(step, "ran", r->steps[s].ran) ||
                 !cJSON_AddStringToObject(step, "detail", r->steps[s].detail) ||
                 !cJSON_AddNumberToObject(step, "ms", pz_round(r->steps[s].seconds * 1000.0, 1));
    }
    const struct { const char *key; double value; } numbers[] = {
        {"input_vertices", r->input_vertices}, {"input_faces", r->input_faces},
        {"welded_vertices", r->welded_vertices}, {"seam_edges", r->seam_edges},
        {"seam_curves", result->seam_count}, {"nonfinite_faces", r->nonfinite_faces},
        {"degenerate_faces", r->degenerate_faces}, {"duplicate_faces", r->duplicate_faces},
        {"nonmanifold_edge_faces", r->nonmanifold_edge_faces}, {"split_vertices", r->split_vertices},
        {"flipped_faces", r->flipped_faces}, {"components", r->components},
        {"dropped_components", r->dropped_components}, {"dropped_component_faces", r->dropped_component_faces},
        {"decimated_faces", r->decimated_faces}, {"output_vertices", r->output_vertices},
        {"output_faces", r->output_faces}, {"poses", result->mesh->pose_count},
    };
    for (size_t i = 0; !failed && i < sizeof numbers / sizeof numbers[0]; ++i)
        failed = !cJSON_AddNumberToObject(counts, numbers[i].key, numbers[i].value);
    failed = failed || !cJSON_AddNumberToObject(root, "target_edge_mm", pz_round(r->target_edge, 4));
    failed = failed || !cJSON_AddNumberToObject(root, "bbox_diagonal_mm", pz_round(r->bbox_diagonal, 3));
    failed = failed || !cJSON_AddNumberToObject(root, "hausdorff_mm", pz_round(r->hausdorff, 4));
    failed = failed || !cJSON_AddNumberToObject(root, "pose_hausdorff_mm", pz_round(r->pose_hausdorff_max, 4));
    failed = failed || !cJSON_AddNumberToObject(root, "hausdorff_bound_mm", pz_round(r->hausdorff_bound, 4));
    failed = failed || !cJSON_AddBoolToObject(root, "within_bound", r->within_bound);
    failed = failed || !cJSON_AddNumberToObject(root, "min_angle_over_20_fraction",
                                                pz_round(r->min_angle_over_20_fraction, 5));
    return pz_cli_print_json(root, failed, ctx);
}

pz_status pz_cli_prepare(const pz_cli_args *args, pz_ctx *ctx)
{
    pz_prepare_options options;
    pz_status status = parse_options(args, &options, ctx);
    if (status)
        return status;
    const char *path = args->positionals[0];
    pz_mesh *mesh = NULL;
    if ((status = pz_mesh_read_with_poses(path, args->pose_paths, args->pose_path_count, &mesh, ctx)))
        return status;
    pz_units used = PZ_UNITS_AUTO;
    pz_cli_mesh_to_mm(args, mesh, &used, NULL);
    if ((status = pz_mesh_check_units(mesh, used, args->units == PZ_UNITS_AUTO, path, ctx))) {
        pz_mesh_free(&mesh);
        return status;
    }
    pz_prepare_result *result = NULL;
    int quiet = ctx->quiet;
    ctx->quiet = 1; /* the steps are printed once the whole run has succeeded */
    status = pz_prepare(mesh, &options, &result, ctx);
    ctx->quiet = quiet;
    char **paths = NULL;
    int pose_files = 0;
    if (!status) {
        pose_files = pz_format_from_path(args->output_path) != PZ_FORMAT_GLB ? result->mesh->pose_count : 0;
        paths = calloc((size_t)pose_files + 1, sizeof *paths);
        status = paths ? write_outputs(args, result, paths, ctx) : pz_error(ctx, PZ_ERR_NOMEM, "out of memory");
    }
    if (!status && args->json && (status = print_json(args, result, paths, pose_files, ctx)))
        remove_all(paths, pose_files + 1), remove(args->output_path);
    if (!status) {
        note_steps(&result->report, path, ctx);
        pz_note(ctx, "wrote %s: %d vertices, %d faces, %d seam curves%s%s", args->output_path,
                (int)result->mesh->vertex_count, (int)result->mesh->face_count, (int)result->seam_count,
                paths[0] ? " in " : "", paths[0] ? paths[0] : "");
    }
    for (int p = 0; paths && p <= pose_files; ++p)
        free(paths[p]);
    free(paths);
    pz_prepare_result_free(&result);
    pz_mesh_free(&mesh);
    return status;
}

/*
 * cli/cmd_field.c -- `panelize field MESH -o DIR`: the curvature-aligned
 * cross-field (field/field.h, docs/field.md).
 *
 * Reads and validates the mesh (with --pose files), reads the --sketch file
 * (before any work, so a bad sketch fails fast), computes the field, then
 * writes DIR/field.obj, DIR/field.glb and DIR/report.json. DIR is created
 * when missing (one level). The three files are written to temporaries and
 * renamed only once all three are complete, so a failed run leaves none of
 * them (a directory it created stays, empty).
 *
 * SPDX-License-Identifier: GPL-3.0-or-later
 */
#define _POSIX_C_SOURCE 200809L
#include "cli/cli.h"

#include "field/field.h"

#include <errno.h>
#include <math.h>
#include <stdlib.h>
#include <string.h>
#include <sys/stat.h>
#include <sys/types.h>

const char pz_cli_field_usage[] =
    "usage: panelize field MESH -o DIR [--pose FILE]... [--sketch FILE] [--scales K]\n"
    "                      [--smoothness W] [--units U] [--repair] [--json] [--quiet]\n"
    "\n"
    "Computes the smooth 4-way cross-field that guides the seams: aligned to\n"
    "the principal curvature directions where one curvature dominates\n"
    "(estimated at K scales), exactly along the boundary and along sketched\n"
    "curves, with extra poses' curvature averaged in. Writes to DIR:\n"
    "  field.obj    two line segments per face (l) and the singular vertices (p)\n"
    "  field.glb    the same as glTF LINES and POINTS, for a browser viewer\n"
    "  report.json  timings, singularities {vertex, index}, alignment figures\n"
    "\n"
    "options:\n"
    "  -o, --output DIR   output directory (created when missing)\n"
    "  --pose FILE        an extra pose with the same connectivity (repeatable)\n"
    "  --sketch FILE      JSON {\"curves\": [[[x,y,z], ...], ...]}: polylines on the\n"
    "                     surface, in the mesh file's units; the field follows them\n"
    "  --scales K         curvature scales, radius 1, 2, 4 ... mean edges (default 3, 1 .. 8)\n"
    "  --smoothness W     weight of smoothness against curvature alignment (default 4)\n"
    "  --units U          the mesh file's units: mm, cm, m, or auto (default)\n"
    "  --repair           drop degenerate and duplicate faces, orient faces first\n"
    "  --json             print the report on stdout\n"
    "  --quiet            nothing on stderr but an error\n";

/* ---------------------------------------------------------------- options */

static pz_status parse_options(const pz_cli_args *args, pz_field_options *options, pz_ctx *ctx)
{
    memset(options, 0, sizeof *options);
    options->use_poses = 1;
    const char *scales = pz_cli_value(args, PZ_CLI_OPT_SCALES);
    if (scales) {
        char *end = NULL;
        errno = 0;
        long k = strtol(scales, &end, 10);
        if (errno || end == scales || *end || k < 1 || k > PZ_FIELD_MAX_SCALES)
            return pz_error(ctx, PZ_ERR_USAGE, "field: --scales: expected an integer 1 .. %d, got '%s'",
                            PZ_FIELD_MAX_SCALES, scales);
        options->scale_count = (int32_t)k;
    }
    const char *smoothness = pz_cli_value(args, PZ_CLI_OPT_SMOOTHNESS);
    if (smoothness) {
        char *end = NULL;
        errno = 0;
        double w = strtod(smoothness, &end);
        if (errno || end == smoothness || *end || !isfinite(w) || !(w > 0.0))
            return pz_error(ctx, PZ_ERR_USAGE, "field: --smoothness: expected a positive number, got '%s'",
                            smoothness);
        options->smoothness = w;
    }
    if (!args->output_path)
        return pz_error(ctx, PZ_ERR_USAGE, "field: -o DIR is required");
    return PZ_OK;
}

/* ---------------------------------------------------------------- report */

static double figure_or_null(cJSON *object, const char *key, double value, int *failed)
{
    cJSON *item = value < 0.0 ? cJSON_AddNullToObject(object, key)
                              : cJSON_AddNumberToObject(object, key, pz_round(value, 4));
    if (!item)
        *failed = 1;
    return value;
}

typedef struct run_timings {
    double read_ms, write_ms, total_ms;
} run_timings;

static cJSON *build_report(const char *path, const pz_mesh *mesh, const pz_field *field,
                           const pz_field_options *options, int has_sketch, const run_timings *times, int *failed)
{
    cJSON *root = cJSON_CreateObject();
    if (!root) {
        *failed = 1;
        return NULL;
    }
    int ok = cJSON_AddStringToObject(root, "file", path) && cJSON_AddNumberToObject(root, "vertices", mesh->vertex_count) &&
             cJSON_AddNumberToObject(root, "faces", mesh->face_count) &&
             cJSON_AddNumberToObject(root, "poses", mesh->pose_count) &&
             cJSON_AddNumberToObject(root, "scales", options->scale_count ? options->scale_count : PZ_FIELD_DEFAULT_SCALES) &&
             cJSON_AddNumberToObject(root, "smoothness", options->smoothness > 0.0 ? options->smoothness : PZ_FIELD_DEFAULT_SMOOTHNESS) &&
             cJSON_AddNumberToObject(root, "mean_edge_mm", pz_round(field->mean_edge_length, 4)) &&
             cJSON_AddNumberToObject(root, "boundary_faces", field->boundary_face_count) &&
             cJSON_AddNumberToObject(root, "sketch_faces", field->sketch_face_count);
    cJSON *timings = cJSON_AddObjectToObject(root, "timings_ms");
    ok = ok && timings && cJSON_AddNumberToObject(timings, "read", pz_round(times->read_ms, 3)) &&
         cJSON_AddNumberToObject(timings, "curvature", pz_round(field->curvature_ms, 3)) &&
         cJSON_AddNumberToObject(timings, "sketch", pz_round(field->sketch_ms, 3)) &&
         cJSON_AddNumberToObject(timings, "solve", pz_round(field->solve_ms, 3)) &&
         cJSON_AddNumberToObject(timings, "singularities", pz_round(field->singularity_ms, 3)) &&
         cJSON_AddNumberToObject(timings, "write", pz_round(times->write_ms, 3)) &&
         cJSON_AddNumberToObject(timings, "total", pz_round(times->total_ms, 3));
    cJSON *singularities = cJSON_AddArrayToObject(root, "singularities");
    ok = ok && singularities;
    for (int32_t k = 0; ok && k < field->singularity_count; ++k) {
        cJSON *s = cJSON_CreateObject();
        ok = s && cJSON_AddItemToArray(singularities, s) &&
             cJSON_AddNumberToObject(s, "vertex", field->singular_vertices[k]) &&
             cJSON_AddNumberToObject(s, "index", field->singular_indices[k]);
        if (s && !ok && !cJSON_GetArrayItem(singularities, k))
            cJSON_Delete(s);
    }
    ok = ok && cJSON_AddNumberToObject(root, "singularity_count", field->singularity_count) &&
         cJSON_AddNumberToObject(root, "index_sum", field->index_sum);
    *failed = !ok;
    figure_or_null(root, "curvature_alignment_deg", field->curvature_alignment_deg, failed);
    figure_or_null(root, "boundary_alignment_deg", field->boundary_alignment_deg, failed);
    if (has_sketch)
        figure_or_null(root, "sketch_alignment_deg", field->sketch_alignment_deg, failed);
    return root;
}

/* ---------------------------------------------------------------- outputs */

static char *join_path(const char *dir, const char *name)
{
    size_t size = strlen(dir) + strlen(name) + 2;
    char *path = malloc(size);
    if (path)
        snprintf(path, size, "%s/%s", dir, name);
    return path;
}

static pz_status make_directory(const char *dir, pz_ctx *ctx)
{
    struct stat info;
    if (stat(dir, &info) == 0) {
        if (S_ISDIR(info.st_mode))
            return PZ_OK;
        return pz_error(ctx, PZ_ERR_CREATE, "%s: not a directory", dir);
    }
    if (mkdir(dir, 0777) != 0 && errno != EEXIST)
        return pz_error(ctx, PZ_ERR_CREATE, "%s: cannot create: %s", dir, strerror(errno));
    return PZ_OK;
}

enum { OUT_OBJ, OUT_GLB, OUT_REPORT, OUT_COUNT };
static const char *const output_names[OUT_COUNT] = {"field.obj", "field.glb", "report.json"};

/* Opens the three temporaries, writes obj and glb, then the report (which
 * includes the write time), and commits all three only when all succeeded. */
static pz_status write_outputs(const char *dir, const pz_mesh *mesh, const pz_field *field, cJSON *(*report)(void *, double),
                               void *report_data, char **report_text, pz_ctx *ctx)
{
    pz_output outputs[OUT_COUNT];
    char *paths[OUT_COUNT] = {NULL, NULL, NULL};
    memset(outputs, 0, sizeof outputs);
    pz_status status = make_directory(dir, ctx);
    int opened = 0;
    for (int k = 0; status == PZ_OK && k < OUT_COUNT; ++k) {
        paths[k] = join_path(dir, output_names[k]);
        if (!paths[k])
            status = pz_error(ctx, PZ_ERR_NOMEM, "field: out of memory");
        else if ((status = pz_output_open(&outputs[k], paths[k], "wb", ctx)) == PZ_OK)
            opened = k + 1;
    }
    double start = pz_seconds();
    if (status == PZ_OK)
        status = pz_field_write_obj(mesh, field, 0.0, outputs[OUT_OBJ].file, paths[OUT_OBJ], ctx);
    if (status == PZ_OK)
        status = pz_field_write_glb(mesh, field, 0.0, outputs[OUT_GLB].file, paths[OUT_GLB], ctx);
    if (status == PZ_OK) {
        cJSON *root = report(report_data, 1e3 * (pz_seconds() - start));
        *report_text = root ? cJSON_Print(root) : NULL;
        cJSON_Delete(root);
        if (!*report_text)
            status = pz_error(ctx, PZ_ERR_NOMEM, "field: out of memory for the report");
        else
            fprintf(outputs[OUT_REPORT].file, "%s\n", *report_text);
    }
    int committed = 0;
    for (int k = 0; k < opened; ++k) {
        if (status == PZ_OK && (status = pz_output_commit(&outputs[k], ctx)) == PZ_OK)
            committed = k + 1;
        else
            pz_output_abort(&outputs[k]); /* after a failed commit: frees what is left */
    }
    if (status != PZ_OK) /* a later commit failed: take back the files this run renamed */
        for (int k = 0; k < committed; ++k)
            remove(paths[k]);
    for (int k = 0; k < OUT_COUNT; ++k)
        free(paths[k]);
    return status;
}

/* ---------------------------------------------------------------- the command */

typedef struct report_data {
    const char *path;
    const pz_mesh *mesh;
    const pz_field *field;
    const pz_field_options *options;
    int has_sketch;
    double run_start, read_ms;
} report_data;

static cJSON *make_report(void *data, double write_ms)
{
    report_data *r = data;
    run_timings times = {r->read_ms, write_ms, 1e3 * (pz_seconds() - r->run_start)};
    int failed = 0;
    cJSON *root = build_report(r->path, r->mesh, r->field, r->options, r->has_sketch, &times, &failed);
    if (failed) {
        cJSON_Delete(root);
        return NULL;
    }
    return root;
}

pz_status pz_cli_field(const pz_cli_args *args, pz_ctx *ctx)
{
    double run_start = pz_seconds();
    pz_field_options options;
    pz_status status = pz_cli_expect_positionals(args, 1, "one MESH", ctx);
    if (status == PZ_OK)
        status = parse_options(args, &options, ctx);
    if (status != PZ_OK)
        return status;
    const char *path = args->positionals[0];
    pz_mesh *mesh = NULL;
    pz_topology *topology = NULL;
    pz_sketch *sketch = NULL;
    pz_field *field = NULL;
    char *report_text = NULL;
    pz_units used = PZ_UNITS_AUTO;
    status = pz_cli_load_valid_mesh(args, path, &mesh, &used, ctx);
    const char *sketch_path = pz_cli_value(args, PZ_CLI_OPT_SKETCH);
    if (status == PZ_OK && sketch_path)
        status = pz_sketch_read(sketch_path, mesh->unit_scale, &sketch, ctx);
    if (status == PZ_OK && sketch)
        status = pz_sketch_check(sketch, mesh, sketch_path, ctx);
    if (status == PZ_OK)
        status = pz_topology_build(mesh, &topology, ctx);
    double read_end = pz_seconds();
    options.sketch = sketch;
    if (status == PZ_OK)
        status = pz_field_compute(mesh, topology, &options, &field, ctx);
    if (status == PZ_OK) {
        report_data data = {path, mesh, field, &options, sketch != NULL, run_start, 1e3 * (read_end - run_start)};
        status = write_outputs(args->output_path, mesh, field, make_report, &data, &report_text, ctx);
    }
    if (status == PZ_OK) {
        if (args->json)
            printf("%s\n", report_text);
        else
            printf("%s: %d faces, %d singularities (index sum %g), curvature alignment %.2f deg, "
                   "boundary alignment %.2f deg -> %s\n",
                   path, (int)mesh->face_count, (int)field->singularity_count, field->index_sum,
                   field->curvature_alignment_deg, field->boundary_alignment_deg, args->output_path);
        pz_note(ctx, "field: curvature %.1f ms, solve %.1f ms, %d boundary and %d sketched faces", field->curvature_ms,
                field->solve_ms, (int)field->boundary_face_count, (int)field->sketch_face_count);
    }
    free(report_text);
    pz_field_free(&field);
    pz_sketch_free(&sketch);
    pz_topology_free(&topology);
    pz_mesh_free(&mesh);
    return status;
}

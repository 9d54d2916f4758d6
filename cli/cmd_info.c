/*
 * cli/cmd_info.c -- `panelize info` and `panelize check`.
 *
 * info describes a mesh and never refuses one that parses: it reads the mesh
 * and its poses, converts to millimetres and prints pz_mesh_describe's
 * description (mesh/describe.c: topology when the mesh is valid, what needs
 * no manifoldness when it is not; unknown figures are JSON null). Only
 * reading errors (missing, unreadable, malformed files, mismatched poses)
 * fail.
 *
 * check is the gate every command that needs a valid mesh goes through
 * (pz_cli_load_valid_mesh): it fails with exit 65 and one line naming the
 * file and the first problem when the mesh stays invalid after --repair.
 *
 * SPDX-License-Identifier: GPL-3.0-or-later
 */
#include "cli/cli.h"
#include "io/io.h"

#include <math.h>
#include <stdlib.h>
#include <string.h>

const char pz_cli_info_usage[] =
    "usage: panelize info MESH [--pose FILE]... [--units mm|cm|m|auto] [--json] [--quiet]\n"
    "\n"
    "Describes a mesh (.obj .ply .off .glb .gltf): vertices, faces, edges,\n"
    "connected components, boundary loops with their lengths, genus, Euler\n"
    "characteristic, whether it is a valid manifold (and every problem found\n"
    "when it is not), units, bounding box and area in millimetres, UVs,\n"
    "labels, poses and timings. An invalid mesh is described, not refused:\n"
    "info exits 0 for any file that parses.\n"
    "\n"
    "options:\n"
    "  --pose FILE    an extra pose with the same connectivity (repeatable)\n"
    "  --units U      the file's units: mm, cm, m, or auto (default: guessed\n"
    "                 from the size, a garment being 0.2 - 2 m)\n"
    "  --json         one JSON object on stdout\n"
    "  --quiet        nothing on stderr but an error\n";

const char pz_cli_check_usage[] =
    "usage: panelize check MESH [--pose FILE]... [--units U] [--repair] [--json] [--quiet]\n"
    "\n"
    "Validates a mesh exactly as every command that needs a valid mesh does:\n"
    "drops unreferenced vertices, applies the --repair fixes, and fails with\n"
    "exit 65 and one line naming the file and the first problem when the mesh\n"
    "is not an oriented manifold with finite coordinates and well-formed faces.\n"
    "\n"
    "options:\n"
    "  --pose FILE    an extra pose with the same connectivity (repeatable)\n"
    "  --units U      the file's units: mm, cm, m, or auto (default)\n"
    "  --repair       drop degenerate and duplicate faces, orient faces\n"
    "                 consistently, before validating\n"
    "  --json         one JSON object on stdout\n"
    "  --quiet        nothing on stderr but an error\n";

/* Decimals printed for millimetre lengths and areas (micrometre precision). */
#define LENGTH_DECIMALS 4

/* Everything info reports: the library's description and what the command knows of the file. */
typedef struct mesh_report {
    const char *path;
    const pz_mesh *mesh;
    pz_units units;
    int units_guessed;
    int units_plausible;   /* the extent in those units fits a garment (0.2 - 2 m) */
    pz_mesh_description d; /* pz_mesh_describe */
    double read_ms, total_ms;
} mesh_report;

/* ---------------------------------------------------------------- output */

static void print_vec3(const char *name, const double values[3])
{
    printf("  %-5s %12.3f %12.3f %12.3f\n", name, values[0], values[1], values[2]);
}

/* At most this many boundary loops are listed one per line in the text output. */
#define TEXT_MAX_LOOPS 20

static void print_text(const mesh_report *report)
{
    const pz_mesh *mesh = report->mesh;
    printf("file:                 %s\n", report->path);
    printf("vertices:             %d\n", (int)mesh->vertex_count);
    printf("faces:                %d\n", (int)mesh->face_count);
    printf("edges:                %d\n", (int)report->d.edge_count);
    printf("components:           %d\n", (int)report->d.component_count);
    if (report->d.boundary_loop_count < 0) {
        printf("boundary loops:       unknown (mesh is not a valid manifold)\n");
    } else {
        printf("boundary loops:       %d\n", (int)report->d.boundary_loop_count);
        for (int32_t i = 0; i < report->d.boundary_loop_count && i < TEXT_MAX_LOOPS; ++i)
            printf("  loop %-3d            %d vertices, %.1f mm\n", (int)i, (int)report->d.loop_vertex_counts[i],
                   report->d.loop_lengths[i]);
        if (report->d.boundary_loop_count > TEXT_MAX_LOOPS)
            printf("  ... and %d more\n", (int)(report->d.boundary_loop_count - TEXT_MAX_LOOPS));
    }
    printf("euler characteristic: %d\n", (int)report->d.euler_characteristic);
    if (report->d.genus < 0)
        printf("genus:                unknown\n");
    else
        printf("genus:                %d\n", (int)report->d.genus);
    printf("manifold:             %s\n", report->d.manifold ? "yes" : "no");
    for (int32_t i = 0; i < report->d.validation.problem_count; ++i)
        printf("  problem:            %s\n", report->d.validation.problems[i]);
    printf("units:                %s (%s)\n", pz_units_str(report->units),
           !report->units_guessed ? "given"
           : report->units_plausible ? "guessed"
                                     : "guessed, but the size fits no garment: give --units");
    double size[3];
    for (int k = 0; k < 3; ++k)
        size[k] = report->d.bbox_max[k] - report->d.bbox_min[k];
    printf("bounding box (mm):\n");
    print_vec3("min", report->d.bbox_min);
    print_vec3("max", report->d.bbox_max);
    print_vec3("size", size);
    if (report->d.area_known)
        printf("area:                 %.1f mm^2 (%.4f m^2)\n", report->d.area_mm2, report->d.area_mm2 * 1e-6);
    else
        printf("area:                 unknown (faces with bad indices)\n");
    if (mesh->uv_count > 0)
        printf("uvs:                  yes (%d)\n", (int)mesh->uv_count);
    else
        printf("uvs:                  no\n");
    printf("labels:               %d", (int)mesh->label_count);
    for (int32_t i = 0; i < mesh->label_count; ++i) {
        const char *name = mesh->label_names ? mesh->label_names[i] : NULL;
        printf("%s%s", i == 0 ? " (" : ", ", name ? name : "(unnamed)");
    }
    printf("%s\n", mesh->label_count > 0 ? ")" : "");
    printf("poses:                %d\n", (int)mesh->pose_count);
    printf("timings (ms):         read %.1f, validate %.1f, topology %.1f, total %.1f\n", report->read_ms,
           report->d.validate_ms, report->d.topology_ms, report->total_ms);
}

/* A count, or null when it is unknown (negative). */
static cJSON *json_count_or_null(int32_t count)
{
    return count < 0 ? cJSON_CreateNull() : cJSON_CreateNumber(count);
}

static cJSON *json_loops(const mesh_report *report, int lengths)
{
    if (report->d.boundary_loop_count < 0)
        return cJSON_CreateNull();
    cJSON *array = cJSON_CreateArray();
    for (int32_t i = 0; array && i < report->d.boundary_loop_count; ++i) {
        double value = lengths ? pz_round(report->d.loop_lengths[i], LENGTH_DECIMALS)
                               : report->d.loop_vertex_counts[i];
        if (!cJSON_AddItemToArray(array, cJSON_CreateNumber(value))) {
            cJSON_Delete(array);
            return NULL;
        }
    }
    return array;
}

static cJSON *json_labels(const pz_mesh *mesh)
{
    cJSON *array = cJSON_CreateArray();
    for (int32_t i = 0; array && i < mesh->label_count; ++i) {
        const char *name = mesh->label_names ? mesh->label_names[i] : NULL;
        if (!cJSON_AddItemToArray(array, name ? cJSON_CreateString(name) : cJSON_CreateNull())) {
            cJSON_Delete(array);
            return NULL;
        }
    }
    return array;
}

static cJSON *json_problems(const pz_validation *validation)
{
    /* cJSON_CreateStringArray refuses a NULL list, which is what "no problems" is. */
    if (validation->problem_count == 0)
        return cJSON_CreateArray();
    return cJSON_CreateStringArray((const char *const *)validation->problems, validation->problem_count);
}

static cJSON *json_bbox(const mesh_report *report)
{
    double size[3];
    for (int k = 0; k < 3; ++k)
        size[k] = report->d.bbox_max[k] - report->d.bbox_min[k];
    cJSON *bbox = cJSON_CreateObject();
    if (bbox && (!cJSON_AddItemToObject(bbox, "min", pz_cli_json_vec3(report->d.bbox_min, LENGTH_DECIMALS)) ||
                 !cJSON_AddItemToObject(bbox, "max", pz_cli_json_vec3(report->d.bbox_max, LENGTH_DECIMALS)) ||
                 !cJSON_AddItemToObject(bbox, "size", pz_cli_json_vec3(size, LENGTH_DECIMALS)))) {
        cJSON_Delete(bbox);
        return NULL;
    }
    return bbox;
}

static cJSON *json_timings(const mesh_report *report)
{
    cJSON *timings = cJSON_CreateObject();
    if (timings && (!cJSON_AddNumberToObject(timings, "read", report->read_ms) ||
                    !cJSON_AddNumberToObject(timings, "validate", pz_round(report->d.validate_ms, 3)) ||
                    !cJSON_AddNumberToObject(timings, "topology", pz_round(report->d.topology_ms, 3)) ||
                    !cJSON_AddNumberToObject(timings, "total", report->total_ms))) {
        cJSON_Delete(timings);
        return NULL;
    }
    return timings;
}

static pz_status print_json(const mesh_report *report, pz_ctx *ctx)
{
    const pz_mesh *mesh = report->mesh;
    cJSON *root = cJSON_CreateObject();
    int failed = !root;
    failed = failed || !cJSON_AddStringToObject(root, "file", report->path);
    failed = failed || !cJSON_AddNumberToObject(root, "vertices", mesh->vertex_count);
    failed = failed || !cJSON_AddNumberToObject(root, "faces", mesh->face_count);
    failed = failed || !cJSON_AddNumberToObject(root, "edges", report->d.edge_count);
    failed = failed || !cJSON_AddNumberToObject(root, "components", report->d.component_count);
    failed = failed || !cJSON_AddItemToObject(root, "boundary_loops", json_count_or_null(report->d.boundary_loop_count));
    failed = failed || !cJSON_AddItemToObject(root, "boundary_loop_lengths_mm", json_loops(report, 1));
    failed = failed || !cJSON_AddItemToObject(root, "boundary_loop_vertices", json_loops(report, 0));
    failed = failed || !cJSON_AddItemToObject(root, "genus", json_count_or_null(report->d.genus));
    failed = failed || !cJSON_AddNumberToObject(root, "euler_characteristic", report->d.euler_characteristic);
    failed = failed || !cJSON_AddBoolToObject(root, "manifold", report->d.manifold);
    failed = failed || !cJSON_AddItemToObject(root, "problems", json_problems(&report->d.validation));
    failed = failed || !cJSON_AddNumberToObject(root, "poses", mesh->pose_count);
    failed = failed || !cJSON_AddStringToObject(root, "units", pz_units_str(report->units));
    failed = failed || !cJSON_AddBoolToObject(root, "units_guessed", report->units_guessed);
    failed = failed || !cJSON_AddBoolToObject(root, "units_plausible", report->units_plausible);
    failed = failed || !cJSON_AddItemToObject(root, "bbox_mm", json_bbox(report));
    failed = failed || !cJSON_AddItemToObject(root, "area_mm2", report->d.area_known
                                                                    ? cJSON_CreateNumber(pz_round(report->d.area_mm2, LENGTH_DECIMALS))
                                                                    : cJSON_CreateNull());
    failed = failed || !cJSON_AddNumberToObject(root, "uvs", mesh->uv_count);
    failed = failed || !cJSON_AddItemToObject(root, "labels", json_labels(mesh));
    failed = failed || !cJSON_AddItemToObject(root, "timings_ms", json_timings(report));
    return pz_cli_print_json(root, failed, ctx);
}

/* ---------------------------------------------------------------- commands */

pz_status pz_cli_info(const pz_cli_args *args, pz_ctx *ctx)
{
    pz_status status = pz_cli_expect_positionals(args, 1, "one MESH file", ctx);
    if (status != PZ_OK)
        return status;
    double start = pz_seconds();
    mesh_report report;
    memset(&report, 0, sizeof report);
    report.path = args->positionals[0];
    pz_mesh *mesh = NULL;
    status = pz_mesh_read_with_poses(report.path, args->pose_paths, args->pose_path_count, &mesh, ctx);
    if (status != PZ_OK)
        return status;
    pz_cli_mesh_to_mm(args, mesh, &report.units, &report.units_plausible);
    report.units_guessed = args->units == PZ_UNITS_AUTO;
    report.mesh = mesh;
    report.read_ms = pz_elapsed_ms(start, pz_seconds());

    status = pz_mesh_describe(mesh, &report.d, ctx);
    report.total_ms = pz_elapsed_ms(start, pz_seconds());
    if (status == PZ_OK)
        status = args->json ? print_json(&report, ctx) : (print_text(&report), PZ_OK);
    if (status == PZ_OK)
        pz_cli_warn_units(args, report.path, mesh, report.units, ctx);
    pz_mesh_description_clear(&report.d);
    pz_mesh_free(&mesh);
    return status;
}

pz_status pz_cli_check(const pz_cli_args *args, pz_ctx *ctx)
{
    pz_status status = pz_cli_expect_positionals(args, 1, "one MESH file", ctx);
    if (status != PZ_OK)
        return status;
    const char *path = args->positionals[0];
    pz_mesh *mesh = NULL;
    pz_units units = PZ_UNITS_AUTO;
    status = pz_cli_load_valid_mesh(args, path, &mesh, &units, ctx);
    if (status != PZ_OK)
        return status;
    if (args->json) {
        cJSON *root = cJSON_CreateObject();
        int failed = !root;
        failed = failed || !cJSON_AddStringToObject(root, "file", path);
        failed = failed || !cJSON_AddBoolToObject(root, "valid", 1);
        failed = failed || !cJSON_AddNumberToObject(root, "vertices", mesh->vertex_count);
        failed = failed || !cJSON_AddNumberToObject(root, "faces", mesh->face_count);
        failed = failed || !cJSON_AddNumberToObject(root, "poses", mesh->pose_count);
        failed = failed || !cJSON_AddStringToObject(root, "units", pz_units_str(units));
        failed = failed || !cJSON_AddBoolToObject(root, "repaired", args->repair_flags != 0);
        status = pz_cli_print_json(root, failed, ctx);
    } else {
        printf("%s: valid (%d vertices, %d faces, %d poses, units %s)\n", path, (int)mesh->vertex_count,
               (int)mesh->face_count, (int)mesh->pose_count, pz_units_str(units));
    }
    pz_mesh_free(&mesh);
    return status;
}

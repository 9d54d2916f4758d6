/*
 * cli/cmd_info.c -- `panelize info` and `panelize check`.
 *
 * info describes a mesh and never refuses one that parses: it reads the mesh
 * and its poses, converts to millimetres, validates, and reports what holds.
 * When the mesh is valid the half-edge topology gives components, boundary
 * loops, Euler characteristic and genus. When it is not, topology cannot be
 * built (it needs an edge-manifold, consistently oriented mesh), so info
 * falls back to what needs no manifoldness: components by union-find over the
 * vertices of each face, edges by sorting undirected vertex pairs (both
 * O(F log F)), and the Euler characteristic from those counts; boundary loops
 * and genus are then reported as unknown (JSON null). Only reading errors
 * (missing, unreadable, malformed files, mismatched poses) fail.
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

/* Everything info reports. Counts are -1 and pointers NULL where unknown. */
typedef struct mesh_report {
    const char *path;
    const pz_mesh *mesh;
    pz_units units;
    int units_guessed;
    int units_plausible;   /* the extent in those units fits a garment (0.2 - 2 m) */
    pz_validation validation;
    int manifold;
    int32_t edge_count;
    int32_t component_count;
    int32_t euler_characteristic;
    int32_t genus;
    int32_t boundary_loop_count;     /* -1 when topology could not be built */
    int32_t *loop_vertex_counts;     /* boundary_loop_count, or NULL */
    double *loop_lengths;            /* boundary_loop_count (mm), or NULL */
    int area_known;
    double area_mm2;
    double bbox_min[3], bbox_max[3];
    double read_ms, validate_ms, topology_ms, total_ms;
} mesh_report;

static void report_clear(mesh_report *report)
{
    pz_validation_clear(&report->validation);
    free(report->loop_vertex_counts);
    free(report->loop_lengths);
    report->loop_vertex_counts = NULL;
    report->loop_lengths = NULL;
}

/* ---------------------------------------------------------------- robust counts for invalid meshes */

static int vertex_in_range(const pz_mesh *mesh, int32_t v)
{
    return v >= 0 && v < mesh->vertex_count;
}

/* Vertices that some face references through an in-range index. */
static pz_status count_referenced(const pz_mesh *mesh, int32_t *referenced_count, pz_ctx *ctx)
{
    uint8_t *referenced = calloc((size_t)mesh->vertex_count + 1, 1);
    if (!referenced)
        return pz_error(ctx, PZ_ERR_NOMEM, "out of memory counting vertices");
    for (int32_t c = 0; c < 3 * mesh->face_count; ++c)
        if (vertex_in_range(mesh, mesh->faces[c]))
            referenced[mesh->faces[c]] = 1;
    int32_t total = 0;
    for (int32_t v = 0; v < mesh->vertex_count; ++v)
        total += referenced[v];
    free(referenced);
    *referenced_count = total;
    return PZ_OK;
}

static int compare_u64(const void *a, const void *b)
{
    uint64_t x = *(const uint64_t *)a, y = *(const uint64_t *)b;
    return (x > y) - (x < y);
}

/* Distinct undirected edges between two different in-range vertices. */
static pz_status count_edges(const pz_mesh *mesh, int32_t *edge_count, pz_ctx *ctx)
{
    uint64_t *keys = malloc(((size_t)mesh->face_count * 3 + 1) * sizeof *keys);
    if (!keys)
        return pz_error(ctx, PZ_ERR_NOMEM, "out of memory counting edges");
    size_t key_count = 0;
    for (int32_t f = 0; f < mesh->face_count; ++f)
        for (int k = 0; k < 3; ++k) {
            int32_t a = mesh->faces[3 * f + k], b = mesh->faces[3 * f + (k + 1) % 3];
            if (a == b || !vertex_in_range(mesh, a) || !vertex_in_range(mesh, b))
                continue;
            uint32_t low = (uint32_t)(a < b ? a : b), high = (uint32_t)(a < b ? b : a);
            keys[key_count++] = (uint64_t)low << 32 | high;
        }
    qsort(keys, key_count, sizeof *keys, compare_u64);
    int32_t distinct = 0;
    for (size_t i = 0; i < key_count; ++i)
        if (i == 0 || keys[i] != keys[i - 1])
            ++distinct;
    free(keys);
    *edge_count = distinct;
    return PZ_OK;
}

/* ---------------------------------------------------------------- analysis */

static double loop_length(const pz_mesh *mesh, const int32_t *vertices, int32_t count)
{
    double length = 0.0;
    for (int32_t i = 0; i < count; ++i) {
        const double *a = mesh->positions + 3 * (size_t)vertices[i];
        const double *b = mesh->positions + 3 * (size_t)vertices[(i + 1) % count];
        length += sqrt((a[0] - b[0]) * (a[0] - b[0]) + (a[1] - b[1]) * (a[1] - b[1]) + (a[2] - b[2]) * (a[2] - b[2]));
    }
    return length;
}

/* Topology of a valid mesh: components, edges, Euler, genus and boundary loops. */
static pz_status analyse_topology(mesh_report *report, pz_ctx *ctx)
{
    pz_topology *topology = NULL;
    pz_loops *loops = NULL;
    pz_topology_summary summary;
    pz_status status = pz_topology_build(report->mesh, &topology, ctx);
    if (status == PZ_OK)
        status = pz_topology_summarize(topology, &summary, ctx);
    if (status == PZ_OK)
        status = pz_topology_boundary_loops(topology, &loops, ctx);
    if (status == PZ_OK) {
        int32_t count = loops->loop_count;
        report->loop_vertex_counts = malloc(((size_t)count + 1) * sizeof *report->loop_vertex_counts);
        report->loop_lengths = malloc(((size_t)count + 1) * sizeof *report->loop_lengths);
        if (!report->loop_vertex_counts || !report->loop_lengths)
            status = pz_error(ctx, PZ_ERR_NOMEM, "%s: out of memory", report->path);
    }
    if (status == PZ_OK) {
        for (int32_t i = 0; i < loops->loop_count; ++i) {
            int32_t begin = loops->loop_offsets[i], end = loops->loop_offsets[i + 1];
            report->loop_vertex_counts[i] = end - begin;
            report->loop_lengths[i] = loop_length(report->mesh, loops->loop_vertices + begin, end - begin);
        }
        report->boundary_loop_count = loops->loop_count;
        report->edge_count = summary.edge_count;
        report->component_count = summary.component_count;
        report->euler_characteristic = summary.euler_characteristic;
        report->genus = summary.genus;
    }
    pz_loops_free(&loops);
    pz_topology_free(&topology);
    return status;
}

/* What can be counted without manifoldness (see the file comment). */
static pz_status analyse_robustly(mesh_report *report, pz_ctx *ctx)
{
    int32_t referenced_count = 0;
    int32_t component_count = pz_mesh_face_components(report->mesh, NULL, ctx);
    if (component_count < 0)
        return (pz_status)component_count;
    report->component_count = component_count;
    pz_status status = count_referenced(report->mesh, &referenced_count, ctx);
    if (status == PZ_OK)
        status = count_edges(report->mesh, &report->edge_count, ctx);
    if (status == PZ_OK)
        report->euler_characteristic = referenced_count - report->edge_count + report->mesh->face_count;
    return status;
}

static pz_status analyse(mesh_report *report, pz_ctx *ctx)
{
    const pz_mesh *mesh = report->mesh;
    double start = pz_seconds();
    pz_status status = pz_mesh_validate(mesh, &report->validation, ctx);
    if (status != PZ_OK)
        return status;
    report->manifold = pz_validation_ok(&report->validation);
    double validated = pz_seconds();
    report->validate_ms = pz_cli_elapsed_ms(start, validated);

    report->boundary_loop_count = -1;
    report->genus = -1;
    status = report->manifold ? analyse_topology(report, ctx) : analyse_robustly(report, ctx);
    if (status != PZ_OK)
        return status;
    report->topology_ms = pz_cli_elapsed_ms(validated, pz_seconds());

    /* Out-of-range corners would make the geometry read outside the arrays. */
    report->area_known = report->validation.bad_indices == 0;
    report->area_mm2 = report->area_known ? pz_geom_total_area(mesh) : 0.0;
    pz_mesh_bbox(mesh, report->bbox_min, report->bbox_max);
    return PZ_OK;
}

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
    printf("edges:                %d\n", (int)report->edge_count);
    printf("components:           %d\n", (int)report->component_count);
    if (report->boundary_loop_count < 0) {
        printf("boundary loops:       unknown (mesh is not a valid manifold)\n");
    } else {
        printf("boundary loops:       %d\n", (int)report->boundary_loop_count);
        for (int32_t i = 0; i < report->boundary_loop_count && i < TEXT_MAX_LOOPS; ++i)
            printf("  loop %-3d            %d vertices, %.1f mm\n", (int)i, (int)report->loop_vertex_counts[i],
                   report->loop_lengths[i]);
        if (report->boundary_loop_count > TEXT_MAX_LOOPS)
            printf("  ... and %d more\n", (int)(report->boundary_loop_count - TEXT_MAX_LOOPS));
    }
    printf("euler characteristic: %d\n", (int)report->euler_characteristic);
    if (report->genus < 0)
        printf("genus:                unknown\n");
    else
        printf("genus:                %d\n", (int)report->genus);
    printf("manifold:             %s\n", report->manifold ? "yes" : "no");
    for (int32_t i = 0; i < report->validation.problem_count; ++i)
        printf("  problem:            %s\n", report->validation.problems[i]);
    printf("units:                %s (%s)\n", pz_units_str(report->units),
           !report->units_guessed ? "given"
           : report->units_plausible ? "guessed"
                                     : "guessed, but the size fits no garment: give --units");
    double size[3];
    for (int k = 0; k < 3; ++k)
        size[k] = report->bbox_max[k] - report->bbox_min[k];
    printf("bounding box (mm):\n");
    print_vec3("min", report->bbox_min);
    print_vec3("max", report->bbox_max);
    print_vec3("size", size);
    if (report->area_known)
        printf("area:                 %.1f mm^2 (%.4f m^2)\n", report->area_mm2, report->area_mm2 * 1e-6);
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
           report->validate_ms, report->topology_ms, report->total_ms);
}

/* A count, or null when it is unknown (negative). */
static cJSON *json_count_or_null(int32_t count)
{
    return count < 0 ? cJSON_CreateNull() : cJSON_CreateNumber(count);
}

static cJSON *json_loops(const mesh_report *report, int lengths)
{
    if (report->boundary_loop_count < 0)
        return cJSON_CreateNull();
    cJSON *array = cJSON_CreateArray();
    for (int32_t i = 0; array && i < report->boundary_loop_count; ++i) {
        double value = lengths ? pz_cli_round(report->loop_lengths[i], LENGTH_DECIMALS)
                               : report->loop_vertex_counts[i];
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
        size[k] = report->bbox_max[k] - report->bbox_min[k];
    cJSON *bbox = cJSON_CreateObject();
    if (bbox && (!cJSON_AddItemToObject(bbox, "min", pz_cli_json_vec3(report->bbox_min, LENGTH_DECIMALS)) ||
                 !cJSON_AddItemToObject(bbox, "max", pz_cli_json_vec3(report->bbox_max, LENGTH_DECIMALS)) ||
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
                    !cJSON_AddNumberToObject(timings, "validate", report->validate_ms) ||
                    !cJSON_AddNumberToObject(timings, "topology", report->topology_ms) ||
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
    failed = failed || !cJSON_AddNumberToObject(root, "edges", report->edge_count);
    failed = failed || !cJSON_AddNumberToObject(root, "components", report->component_count);
    failed = failed || !cJSON_AddItemToObject(root, "boundary_loops", json_count_or_null(report->boundary_loop_count));
    failed = failed || !cJSON_AddItemToObject(root, "boundary_loop_lengths_mm", json_loops(report, 1));
    failed = failed || !cJSON_AddItemToObject(root, "boundary_loop_vertices", json_loops(report, 0));
    failed = failed || !cJSON_AddItemToObject(root, "genus", json_count_or_null(report->genus));
    failed = failed || !cJSON_AddNumberToObject(root, "euler_characteristic", report->euler_characteristic);
    failed = failed || !cJSON_AddBoolToObject(root, "manifold", report->manifold);
    failed = failed || !cJSON_AddItemToObject(root, "problems", json_problems(&report->validation));
    failed = failed || !cJSON_AddNumberToObject(root, "poses", mesh->pose_count);
    failed = failed || !cJSON_AddStringToObject(root, "units", pz_units_str(report->units));
    failed = failed || !cJSON_AddBoolToObject(root, "units_guessed", report->units_guessed);
    failed = failed || !cJSON_AddBoolToObject(root, "units_plausible", report->units_plausible);
    failed = failed || !cJSON_AddItemToObject(root, "bbox_mm", json_bbox(report));
    failed = failed || !cJSON_AddItemToObject(root, "area_mm2", report->area_known
                                                                    ? cJSON_CreateNumber(pz_cli_round(report->area_mm2, LENGTH_DECIMALS))
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
    report.read_ms = pz_cli_elapsed_ms(start, pz_seconds());

    status = analyse(&report, ctx);
    report.total_ms = pz_cli_elapsed_ms(start, pz_seconds());
    if (status == PZ_OK)
        status = args->json ? print_json(&report, ctx) : (print_text(&report), PZ_OK);
    if (status == PZ_OK)
        pz_cli_warn_units(args, report.path, mesh, report.units, ctx);
    report_clear(&report);
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

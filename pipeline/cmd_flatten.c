/*
 * pipeline/cmd_flatten.c -- `panelize flatten MESH... -o DIR`: cut a garment
 * into its panels, flatten every panel and write garment.obj (the garment
 * with the pattern as vt), pattern.svg (the pieces at 1:1) and report.json
 * (the metrics). docs/flatten.md describes inputs, outputs and the report.
 *
 * Steps (each timed for report.json):
 *  1. read: one MESH (with --pose files), or several panel files
 *     concatenated without welding (panel K = file K); millimetres; the
 *     mesh is prepared and validated like every command's input. Vertex ids
 *     of the input files are kept through a map (raw id -> prepared id), since
 *     preparation drops unreferenced vertices.
 *  2. pattern: panels from --panels FILE, --panels uv (the input's UV islands
 *     and UV seams, pz_pattern_panels_from_uv), the input files, or else the
 *     groups split into connected components; --seams/--darts files become
 *     pz_correspondences in garment vertex ids; pz_pattern_build cuts the
 *     garment (and cuts non-disk panels into disks).
 *  3. flatten with the chosen back-end: pz_param_textile (pietroni2022
 *     Sec. 4.3, default), pz_param_lscm_pattern (Levy 2002),
 *     pz_param_wirewarp (wang2008; --scheme, --features snapped with
 *     pz_feature_curves_snap_lenient: a curve off the mesh is left out with
 *     a warning; relaxed key curves are a warning too) or
 *     pz_param_springmass (wang2002 with the
 *     IISERM heap relaxation; --relax; orthotropic with --fabric), then a
 *     shelf layout when pieces overlap. The grain is --grain or, by default,
 *     the garment's vertical axis (pz_mesh_vertical_axis: y-up tools and
 *     z-up scanners both get their warp along the garment's height), passed
 *     explicitly to every back-end.
 *  4. metrics: pz_metrics_compute on the rest pose and on every extra pose;
 *     strain figures in the report are the worst over the poses.
 *  5. write: DIR is created (mkdir -p); the three files (four with
 *     springmass: energy.svg) are written to temporaries and renamed only
 *     when all are complete. If anything
 *     fails, the files renamed so far and the directories created are removed
 *     again, so a failed run leaves nothing (all or nothing).
 *
 * Every option is checked before any file is read (exit 64); data problems
 * are exit 65 naming the file (and line); nothing is written on any error.
 *
 * SPDX-License-Identifier: GPL-3.0-or-later
 */
#define _POSIX_C_SOURCE 200809L
#include "io/io.h"
#include "pipeline/pattern_output.h"

#include <errno.h>
#include <math.h>
#include <stdlib.h>
#include <string.h>
#include <sys/stat.h>
#include <unistd.h>

const char pz_cli_flatten_usage[] =
    "usage: panelize flatten MESH... -o DIR [--panels FILE|uv] [--seams FILE]...\n"
    "           [--darts [K:]FILE]... [--grain X,Y,Z] [--pose FILE]...\n"
    "           [--backend textile|lscm|wirewarp|springmass] [--scheme global|progressive]\n"
    "           [--relax heap|full] [--features FILE] [--iterations N] [--weights S,R,D,M]\n"
    "           [--fabric KSU,KSV,KR] [--seam-allowance MM] [--hem-allowance MM]\n"
    "           [--allowances FILE] [--notch-spacing MM] [--paper a4|letter] [--dxf-strict]\n"
    "           [--fabric-width MM] [--gap MM] [--size NAME] [--units U] [--repair]\n"
    "           [--json] [--quiet]\n"
    "\n"
    "Flattens every panel of a garment into a sewing pattern and writes, into DIR\n"
    "(created when missing; all files or none):\n"
    "  garment.obj        the input's vertices and faces unchanged, vt = the pattern\n"
    "                     (mm), one group panel_K per panel\n"
    "  pattern.svg        the pieces at 1:1 in mm: cut and sew lines, notches, darts,\n"
    "                     grainlines, labels, a 10 cm scale box\n"
    "  pattern.pdf        the same on one 1:1 sheet; pattern-tiled.pdf on A4/Letter\n"
    "  pattern.dxf        AAMA/ASTM D6673 DXF R12 for CAD and cutters\n"
    "  marker.svg         the pieces nested on the fabric (grain kept)\n"
    "  garment.glb        the 3D garment, one colour per panel, the pattern as UVs\n"
    "  report.json        strain, shear, energies, seam and dart figures, marker\n"
    "  report.html        a self-contained page with the pattern and the figures\n"
    "  energy.svg         (springmass only) the pieces coloured by strain energy,\n"
    "                     with the suggested cutting lines\n"
    "\n"
    "Panels: a disk mesh is one panel; OBJ groups and connected components are\n"
    "panels; several MESH files are concatenated, panel K = file K. A panel that\n"
    "is not a disk is cut into one.\n"
    "\n"
    "options:\n"
    "  -o DIR               the output directory (required)\n"
    "  --panels FILE        a panel id per face, one integer per line\n"
    "  --panels uv          panels and cuts from the input's own UVs (vt)\n"
    "  --seams FILE         a seam: panel A, panel B, then `a b` vertex pairs\n"
    "                       (repeatable)\n"
    "  --darts [K:]FILE     a dart of panel K: tip vertex, then `p q` pairs; K\n"
    "                       defaults to the K of a file named patch_K_dart_J\n"
    "                       (repeatable)\n"
    "  --grain X,Y,Z        the 3D direction of the warp (default: the garment's\n"
    "                       vertical, +y or +z, whichever it is taller along)\n"
    "  --pose FILE          an extra pose (repeatable; one MESH only)\n"
    "  --backend B          textile (default), lscm, wirewarp (length-exact\n"
    "                       boundaries) or springmass (with an energy map)\n"
    "  --scheme S           wirewarp: global (default) or progressive\n"
    "  --relax R            springmass: heap (default) or full\n"
    "  --features FILE      wirewarp: feature curves, JSON {\"curves\":[{\"kind\":\n"
    "                       \"key\"|\"accessory\",\"points\":[[x,y,z],...]}]}\n"
    "  --iterations N       textile iterations, 1..10000 (default 20)\n"
    "  --weights S,R,D,M    stretch, rigidity, dart and seam weights\n"
    "                       (default 5,1,5,5)\n"
    "  --fabric KSU,KSV,KR  weft (u) and warp (v) tensile stiffness (N/mm) and shear\n"
    "                       stiffness (N/mm/rad) for the orthotropic energy\n"
    "                       (default 0.946,0.548,0.159); with springmass, given\n"
    "                       = use the orthotropic energy instead of springs\n"
    "  --seam-allowance MM  the cut line's distance outside the sew line (default 10)\n"
    "  --hem-allowance MM   the same on open edges (default: the seam allowance)\n"
    "  --allowances FILE    per-seam allowances (docs/export.md)\n"
    "  --notch-spacing MM   notches along every seam this far apart (default 100)\n"
    "  --paper a4|letter    pattern-tiled.pdf's pages (default a4)\n"
    "  --dxf-strict         DXF without TABLES, 7-bit ASCII, for strict cutters\n"
    "  --fabric-width MM    the marker's fabric width (default 1500)\n"
    "  --gap MM             space between pieces on the marker (default 5)\n"
    "  --size NAME          the size printed on every piece (default base)\n"
    "  --units U            the input's units: mm, cm, m or auto (default)\n"
    "  --repair             repair the mesh before validating (see panelize check)\n"
    "  --json               print report.json on stdout\n"
    "  --quiet              nothing on stderr but an error\n"
    "\n"
    "See docs/flatten.md and docs/export.md.\n";

#define DEFAULT_ITERATIONS 20
#define MAX_ITERATIONS 10000
/* Space between pieces when they have to be laid out again (mm). */
#define LAYOUT_GAP_MM 20.0

enum timing { TIME_READ, TIME_PATTERN, TIME_FLATTEN, TIME_METRICS, TIME_WRITE, TIME_TOTAL };

/* ---------------------------------------------------------------- options */

enum backend { BACKEND_TEXTILE, BACKEND_LSCM, BACKEND_WIREWARP, BACKEND_SPRINGMASS, BACKEND_COUNT };
static const char *const backend_names[BACKEND_COUNT] = {"textile", "lscm", "wirewarp", "springmass"};

typedef struct flatten_settings {
    int backend;              /* enum backend */
    int progressive;          /* --scheme progressive (wirewarp) */
    int relax_full;           /* --relax full (springmass) */
    const char *features_path; /* --features (wirewarp), or NULL */
    int fabric_given;         /* --fabric: springmass turns orthotropic */
    int iterations;
    int weights_given;
    double weights[4];        /* stretch, rigid, dart, seam */
    pz_fabric fabric;
    int grain_given;
    double grain[3];
    pz_export_options export_options; /* --seam-allowance ... --gap */
    const char *allowances_path;      /* --allowances FILE, or NULL */
    double strain_limit;              /* textile's strain goal: run's --max-strain, 0 for flatten */
} flatten_settings;

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
static pz_status parse_backend_options(const pz_cli_args *args, flatten_settings *settings, pz_ctx *ctx)
{
    const char *backend = backend_names[settings->backend];
    const char *text;
    if ((text = pz_cli_value(args, PZ_CLI_OPT_SCHEME))) {
        if (settings->backend != BACKEND_WIREWARP)
            return pz_error(ctx, PZ_ERR_USAGE, "flatten: --scheme works with --backend wirewarp, not %s", backend);
        if (strcmp(text, "global") != 0 && strcmp(text, "progressive") != 0)
            return pz_error(ctx, PZ_ERR_USAGE, "flatten: --scheme: '%s' is not global or progressive", text);
        settings->progressive = strcmp(text, "progressive") == 0;
    }
    if ((text = pz_cli_value(args, PZ_CLI_OPT_RELAX))) {
        if (settings->backend != BACKEND_SPRINGMASS)
            return pz_error(ctx, PZ_ERR_USAGE, "flatten: --relax works with --backend springmass, not %s", backend);
        if (strcmp(text, "heap") != 0 && strcmp(text, "full") != 0)
            return pz_error(ctx, PZ_ERR_USAGE, "flatten: --relax: '%s' is not heap or full", text);
        settings->relax_full = strcmp(text, "full") == 0;
    }
    if ((text = pz_cli_value(args, PZ_CLI_OPT_FEATURES))) {
        if (settings->backend != BACKEND_WIREWARP)
            return pz_error(ctx, PZ_ERR_USAGE, "flatten: --features works with --backend wirewarp, not %s", backend);
        if (!*text)
            return pz_error(ctx, PZ_ERR_USAGE, "flatten: --features: empty file name");
        settings->features_path = text;
    }
    return PZ_OK;
}

/* One finite number >= minimum for a length option (mm). */
static pz_status parse_length(const char *option, const char *text, double minimum, double *out, pz_ctx *ctx)
{
    pz_status status = parse_numbers(option, text, out, 1, ctx);
    if (status == PZ_OK && *out < minimum)
        status = pz_error(ctx, PZ_ERR_USAGE, "flatten: %s: %s is below %g mm", option, text, minimum);
    return status;
}

/* The pattern-file options of the export stage (export/export.h). */
static pz_status parse_export_options(const pz_cli_args *args, flatten_settings *settings, pz_ctx *ctx)
{
    pz_export_options *options = &settings->export_options;
    pz_export_options_default(options);
    const char *text;
    pz_status status = PZ_OK;
    int hem_given = 0;
    if ((text = pz_cli_value(args, PZ_CLI_OPT_SEAM_ALLOWANCE)))
        status = parse_length("--seam-allowance", text, 0, &options->seam_allowance_mm, ctx);
    if (status == PZ_OK && (text = pz_cli_value(args, PZ_CLI_OPT_HEM_ALLOWANCE)))
        status = parse_length("--hem-allowance", text, 0, &options->hem_allowance_mm, ctx), hem_given = 1;
    if (!hem_given)
        options->hem_allowance_mm = options->seam_allowance_mm;
    if (status == PZ_OK && (text = pz_cli_value(args, PZ_CLI_OPT_NOTCH_SPACING)))
        status = parse_length("--notch-spacing", text, 1, &options->notch_spacing_mm, ctx);
    if (status == PZ_OK && (text = pz_cli_value(args, PZ_CLI_OPT_FABRIC_WIDTH)))
        status = parse_length("--fabric-width", text, 10, &options->fabric_width_mm, ctx);
    if (status == PZ_OK && (text = pz_cli_value(args, PZ_CLI_OPT_GAP)))
        status = parse_length("--gap", text, 0, &options->gap_mm, ctx);
    if (status == PZ_OK && (text = pz_cli_value(args, PZ_CLI_OPT_PAPER))) {
        if (strcmp(text, "a4") != 0 && strcmp(text, "letter") != 0 && strcmp(text, "A4") != 0 &&
            strcmp(text, "Letter") != 0)
            return pz_error(ctx, PZ_ERR_USAGE, "%s: --paper: '%s' is not a4 or letter", args->command, text);
        options->paper = (text[0] == 'a' || text[0] == 'A') ? "a4" : "letter";
    }
    options->dxf_strict = pz_cli_value(args, PZ_CLI_OPT_DXF_STRICT) != NULL;
    if (status == PZ_OK && (text = pz_cli_value(args, PZ_CLI_OPT_SIZE))) {
        if (!*text || strlen(text) >= sizeof ((pz_pieces *)0)->size_name)
            return pz_error(ctx, PZ_ERR_USAGE, "%s: --size: '%s' is not a name of 1 to %d characters", args->command,
                            text, (int)sizeof ((pz_pieces *)0)->size_name - 1);
        options->size_name = text;
    }
    if (status == PZ_OK && (text = pz_cli_value(args, PZ_CLI_OPT_ALLOWANCES))) {
        if (!*text)
            return pz_error(ctx, PZ_ERR_USAGE, "%s: --allowances: empty file name", args->command);
        settings->allowances_path = text;
    }
    return status;
}

static pz_status parse_settings(const pz_cli_args *args, flatten_settings *settings, pz_ctx *ctx)
{
    memset(settings, 0, sizeof *settings);
    settings->iterations = DEFAULT_ITERATIONS;
    settings->weights[0] = 5, settings->weights[1] = 1, settings->weights[2] = 5, settings->weights[3] = 5;
    settings->fabric = (pz_fabric){0.946, 0.548, 0.159};
    /* No --grain: the garment's vertical axis, known once the mesh is read (pz_cli_flatten). */
    const char *text;
    if ((text = pz_cli_value(args, PZ_CLI_OPT_BACKEND))) {
        settings->backend = BACKEND_COUNT;
        for (int b = 0; b < BACKEND_COUNT; ++b)
            if (strcmp(text, backend_names[b]) == 0)
                settings->backend = b;
        if (settings->backend == BACKEND_COUNT)
            return pz_error(ctx, PZ_ERR_USAGE, "flatten: --backend: '%s' is not textile, lscm, wirewarp or springmass",
                            text);
    }
    pz_status status = parse_backend_options(args, settings, ctx);
    if (status != PZ_OK)
        return status;
    if ((text = pz_cli_value(args, PZ_CLI_OPT_ITERATIONS))) {
        char *end = NULL;
        errno = 0;
        long iterations = strtol(text, &end, 10);
        if (end == text || *end || errno == ERANGE || iterations < 1 || iterations > MAX_ITERATIONS)
            return pz_error(ctx, PZ_ERR_USAGE, "flatten: --iterations: '%s' is not a whole number in 1..%d", text,
                            MAX_ITERATIONS);
        settings->iterations = (int)iterations;
    }
    if ((text = pz_cli_value(args, PZ_CLI_OPT_WEIGHTS))) {
        if ((status = parse_numbers("--weights", text, settings->weights, 4, ctx)))
            return status;
        for (int i = 0; i < 4; ++i)
            if (settings->weights[i] < 0)
                return pz_error(ctx, PZ_ERR_USAGE, "flatten: --weights: '%s': weights must not be negative", text);
        settings->weights_given = 1;
    }
    if ((text = pz_cli_value(args, PZ_CLI_OPT_FABRIC))) {
        double fabric[3];
        if ((status = parse_numbers("--fabric", text, fabric, 3, ctx)))
            return status;
        for (int i = 0; i < 3; ++i)
            if (fabric[i] <= 0)
                return pz_error(ctx, PZ_ERR_USAGE, "flatten: --fabric: '%s': stiffnesses must be positive", text);
        settings->fabric = (pz_fabric){fabric[0], fabric[1], fabric[2]};
        settings->fabric_given = 1;
    }
    if ((text = pz_cli_value(args, PZ_CLI_OPT_GRAIN))) {
        if ((status = parse_numbers("--grain", text, settings->grain, 3, ctx)))
            return status;
        if (settings->grain[0] == 0 && settings->grain[1] == 0 && settings->grain[2] == 0)
            return pz_error(ctx, PZ_ERR_USAGE, "flatten: --grain: '%s' is the zero vector", text);
        settings->grain_given = 1;
    }
    if ((status = parse_export_options(args, settings, ctx)))
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
    return PZ_OK;
}

/* ---------------------------------------------------------------- reading */

/* The garment and how the input files' vertex ids map onto it. */
typedef struct garment_input {
    pz_mesh *mesh;              /* prepared, millimetres */
    pz_units units;
    int32_t file_count;
    int32_t *file_vertex_offset;  /* file_count + 1, raw ids */
    int32_t raw_vertex_count, raw_face_count;
    double *raw_positions;      /* raw_vertex_count x 3 in the file's units */
    int32_t *raw_to_garment;    /* raw_vertex_count: prepared vertex, or -1 when unreferenced */
    int ids_preserved;          /* preparation dropped only unreferenced vertices: raw ids map exactly */
    double *output_positions;   /* mesh->vertex_count x 3 in the file's units, for garment.obj */
} garment_input;

static void garment_input_clear(garment_input *input)
{
    pz_mesh_free(&input->mesh);
    free(input->file_vertex_offset);
    free(input->raw_positions);
    free(input->raw_to_garment);
    free(input->output_positions);
    memset(input, 0, sizeof *input);
}

static char *duplicate_base_name(const char *path)
{
    const char *base = strrchr(path, '/');
    base = base ? base + 1 : path;
    size_t length = strlen(base);
    const char *dot = strrchr(base, '.');
    if (dot && dot != base)
        length = (size_t)(dot - base);
    char *copy = malloc(length + 1);
    if (copy) {
        memcpy(copy, base, length);
        copy[length] = '\0';
    }
    return copy;
}

/* Panel files one after another, no welding; label K = file K (named after the file). */
static pz_status concatenate(pz_mesh *const *parts, const char *const *paths, int32_t count, pz_mesh **out,
                             int32_t *vertex_offset, pz_ctx *ctx)
{
    *out = NULL;
    int64_t vertices = 0, faces = 0, uvs = 0;
    int all_uvs = 1;
    for (int32_t i = 0; i < count; ++i) {
        vertex_offset[i] = (int32_t)vertices;
        vertices += parts[i]->vertex_count;
        faces += parts[i]->face_count;
        uvs += parts[i]->uv_count;
        all_uvs &= parts[i]->uvs != NULL;
    }
    vertex_offset[count] = (int32_t)vertices;
    if (vertices > INT32_MAX / 3 || faces > INT32_MAX / 3 || uvs > INT32_MAX / 2)
        return pz_error(ctx, PZ_ERR_DATA, "%s: the panel files together are too large", paths[0]);
    pz_mesh *mesh = NULL;
    pz_status status = pz_mesh_create((int32_t)vertices, (int32_t)faces, &mesh, ctx);
    if (status != PZ_OK)
        return status;
    mesh->face_labels = malloc(((size_t)faces + 1) * sizeof(int32_t));
    mesh->label_names = calloc((size_t)count + 1, sizeof(char *));
    if (all_uvs) {
        mesh->uvs = malloc(((size_t)uvs + 1) * 2 * sizeof(double));
        mesh->corner_uvs = malloc(((size_t)faces + 1) * 3 * sizeof(int32_t));
        mesh->uv_count = (int32_t)uvs;
    }
    int failed = !mesh->face_labels || !mesh->label_names || (all_uvs && (!mesh->uvs || !mesh->corner_uvs));
    mesh->label_count = count;
    size_t face_at = 0, uv_at = 0;
    for (int32_t i = 0; i < count && !failed; ++i) {
        const pz_mesh *part = parts[i];
        memcpy(mesh->positions + 3 * (size_t)vertex_offset[i], part->positions,
               3 * (size_t)part->vertex_count * sizeof(double));
        for (size_t c = 0; c < 3 * (size_t)part->face_count; ++c) {
            mesh->faces[3 * face_at + c] = part->faces[c] + vertex_offset[i];
            if (all_uvs)
                mesh->corner_uvs[3 * face_at + c] = part->corner_uvs[c] + (int32_t)uv_at;
        }
        for (int32_t f = 0; f < part->face_count; ++f)
            mesh->face_labels[face_at + (size_t)f] = i;
        if (all_uvs)
            memcpy(mesh->uvs + 2 * uv_at, part->uvs, 2 * (size_t)part->uv_count * sizeof(double));
        face_at += (size_t)part->face_count;
        uv_at += (size_t)part->uv_count;
        mesh->label_names[i] = duplicate_base_name(paths[i]);
        failed |= !mesh->label_names[i];
    }
    if (failed) {
        pz_mesh_free(&mesh);
        return pz_error(ctx, PZ_ERR_NOMEM, "%s: out of memory joining the panel files", paths[0]);
    }
    *out = mesh;
    return PZ_OK;
}

/* Reads the input files into input->mesh (raw units) and sets the file offsets. */
static pz_status read_raw(const pz_cli_args *args, garment_input *input, pz_ctx *ctx)
{
    int32_t count = args->positional_count;
    input->file_count = count;
    input->file_vertex_offset = calloc((size_t)count + 1, sizeof(int32_t));
    if (!input->file_vertex_offset)
        return pz_error(ctx, PZ_ERR_NOMEM, "flatten: out of memory");
    if (count == 1) {
        pz_status status = pz_mesh_read_with_poses(args->positionals[0], args->pose_paths, args->pose_path_count,
                                                   &input->mesh, ctx);
        if (status == PZ_OK)
            input->file_vertex_offset[1] = input->mesh->vertex_count;
        return status;
    }
    pz_mesh **parts = calloc((size_t)count, sizeof *parts);
    if (!parts)
        return pz_error(ctx, PZ_ERR_NOMEM, "flatten: out of memory");
    pz_status status = PZ_OK;
    for (int32_t i = 0; i < count && status == PZ_OK; ++i)
        status = pz_mesh_read(args->positionals[i], &parts[i], ctx);
    if (status == PZ_OK)
        status = concatenate(parts, args->positionals, count, &input->mesh, input->file_vertex_offset, ctx);
    for (int32_t i = 0; i < count; ++i)
        pz_mesh_free(&parts[i]);
    free(parts);
    return status;
}

/* Raw id -> id after dropping unreferenced vertices (the compaction pz_mesh_prepare does first). */
static pz_status map_raw_ids(garment_input *input, int32_t *kept, pz_ctx *ctx)
{
    const pz_mesh *mesh = input->mesh;
    input->raw_vertex_count = mesh->vertex_count;
    input->raw_face_count = mesh->face_count;
    input->raw_positions = malloc(((size_t)mesh->vertex_count + 1) * 3 * sizeof(double));
    input->raw_to_garment = malloc(((size_t)mesh->vertex_count + 1) * sizeof(int32_t));
    if (!input->raw_positions || !input->raw_to_garment)
        return pz_error(ctx, PZ_ERR_NOMEM, "flatten: out of memory");
    memcpy(input->raw_positions, mesh->positions, 3 * (size_t)mesh->vertex_count * sizeof(double));
    for (int32_t v = 0; v < mesh->vertex_count; ++v)
        input->raw_to_garment[v] = -1;
    for (int32_t c = 0; c < 3 * mesh->face_count; ++c)
        if (mesh->faces[c] >= 0 && mesh->faces[c] < mesh->vertex_count)
            input->raw_to_garment[mesh->faces[c]] = 0;
    *kept = 0;
    for (int32_t v = 0; v < mesh->vertex_count; ++v)
        if (input->raw_to_garment[v] == 0)
            input->raw_to_garment[v] = (*kept)++;
    return PZ_OK;
}

static pz_status load_garment(const pz_cli_args *args, const pz_flatten_extension *extension,
                              garment_input *input, pz_ctx *ctx)
{
    pz_status status = read_raw(args, input, ctx);
    int32_t kept = 0;
    if (status == PZ_OK)
        status = map_raw_ids(input, &kept, ctx);
    if (status != PZ_OK)
        return status;
    pz_cli_mesh_to_mm(args, input->mesh, &input->units, NULL);
    int prepared = 0;
    if (extension && extension->prepare_mesh &&
        (status = extension->prepare_mesh(extension->user, &input->mesh, &prepared, ctx)) != PZ_OK)
        return status;
    status = pz_cli_prepare_quietly_first(&input->mesh, args->positionals[0], args->repair_flags, ctx);
    if (status != PZ_OK)
        return status;
    pz_mesh *mesh = input->mesh;
    input->ids_preserved = !prepared && mesh->face_count == input->raw_face_count && mesh->vertex_count == kept;
    input->output_positions = malloc(((size_t)mesh->vertex_count + 1) * 3 * sizeof(double));
    if (!input->output_positions)
        return pz_error(ctx, PZ_ERR_NOMEM, "flatten: out of memory");
    /* garment.obj keeps the input's coordinates exactly: the raw ones when ids still match. */
    for (int32_t v = 0; v < input->raw_vertex_count && input->ids_preserved; ++v)
        if (input->raw_to_garment[v] >= 0)
            memcpy(input->output_positions + 3 * (size_t)input->raw_to_garment[v], input->raw_positions + 3 * (size_t)v,
                   3 * sizeof(double));
    if (!input->ids_preserved)
        for (size_t i = 0; i < 3 * (size_t)mesh->vertex_count; ++i)
            input->output_positions[i] = mesh->positions[i] / mesh->unit_scale;
    return PZ_OK;
}

/* ---------------------------------------------------------------- panels */

/* What the panels were chosen from, their per-face ids, names and extra cuts. */
typedef struct panel_choice {
    const char *source;       /* "file", "uv", "files", "groups", "components" */
    int32_t *face_panel;      /* face_count */
    int32_t panel_count;
    uint8_t *extra_cuts;      /* --panels uv only */
    char **names;             /* panel_count entries (may be NULL), or NULL */
} panel_choice;

static void panel_choice_drop_names(panel_choice *choice)
{
    if (choice->names)
        for (int32_t p = 0; p < choice->panel_count; ++p)
            free(choice->names[p]);
    free(choice->names);
    choice->names = NULL;
}

static void panel_choice_clear(panel_choice *choice)
{
    free(choice->face_panel);
    free(choice->extra_cuts);
    panel_choice_drop_names(choice);
    memset(choice, 0, sizeof *choice);
}

typedef struct face_key {
    int64_t key;    /* label << 32 | component */
    int32_t face;
} face_key;

static int compare_face_key(const void *a, const void *b)
{
    const face_key *x = a, *y = b;
    if (x->key != y->key)
        return (x->key > y->key) - (x->key < y->key);
    return (x->face > y->face) - (x->face < y->face);
}

static int compare_int64(const void *a, const void *b)
{
    int64_t x = *(const int64_t *)a, y = *(const int64_t *)b;
    return (x > y) - (x < y);
}

/*
 * One panel per connected piece of each label (group); ids in the order of
 * the pieces' first faces. Sorting (label, component, face) keys: O(F log F).
 */
static pz_status panels_from_groups(const pz_mesh *mesh, panel_choice *choice, pz_ctx *ctx)
{
    int32_t face_count = mesh->face_count;
    int32_t *component = malloc(((size_t)face_count + 1) * sizeof(int32_t));
    face_key *keys = malloc(((size_t)face_count + 1) * sizeof *keys);
    int64_t *firsts = malloc(((size_t)face_count + 1) * sizeof *firsts);  /* first face << 32 | group */
    int32_t *group_label = malloc(((size_t)face_count + 1) * sizeof(int32_t));
    int32_t *group_rank = malloc(((size_t)face_count + 1) * sizeof(int32_t));
    pz_status status = PZ_OK;
    if (!component || !keys || !firsts || !group_label || !group_rank)
        status = pz_error(ctx, PZ_ERR_NOMEM, "flatten: out of memory finding panels");
    int32_t components = status == PZ_OK ? pz_mesh_face_components(mesh, component, ctx) : 0;
    if (status == PZ_OK && components < 0)
        status = (pz_status)components;
    int32_t group_count = 0;
    if (status == PZ_OK) {
        for (int32_t f = 0; f < face_count; ++f) {
            int64_t label = mesh->face_labels ? mesh->face_labels[f] : 0;
            keys[f] = (face_key){label << 32 | component[f], f};
        }
        qsort(keys, (size_t)face_count, sizeof *keys, compare_face_key);
        for (int32_t i = 0; i < face_count; ++i) {
            if (i == 0 || keys[i].key != keys[i - 1].key) {
                group_label[group_count] = (int32_t)(keys[i].key >> 32);
                firsts[group_count] = (int64_t)keys[i].face << 32 | group_count;
                ++group_count;
            }
            component[keys[i].face] = group_count - 1;  /* reused: the face's group */
        }
        qsort(firsts, (size_t)group_count, sizeof *firsts, compare_int64);
        for (int32_t rank = 0; rank < group_count; ++rank)
            group_rank[firsts[rank] & 0xffffffff] = rank;
        choice->face_panel = malloc(((size_t)face_count + 1) * sizeof(int32_t));
        choice->names = calloc((size_t)group_count + 1, sizeof(char *));
        if (!choice->face_panel || !choice->names)
            status = pz_error(ctx, PZ_ERR_NOMEM, "flatten: out of memory finding panels");
    }
    if (status == PZ_OK) {
        choice->panel_count = group_count;
        for (int32_t f = 0; f < face_count; ++f)
            choice->face_panel[f] = group_rank[component[f]];
        for (int32_t g = 0; g < group_count && mesh->label_names; ++g) {
            const char *name = mesh->label_names[group_label[g]];
            if (name && !(choice->names[group_rank[g]] = strdup(name)))
                status = pz_error(ctx, PZ_ERR_NOMEM, "flatten: out of memory finding panels");
        }
        choice->source = mesh->label_count > 1 ? "groups" : "components";
    }
    free(component);
    free(keys);
    free(firsts);
    free(group_label);
    free(group_rank);
    return status;
}

/* One panel per input file (the labels concatenate() set). */
static pz_status panels_from_files(const pz_mesh *mesh, panel_choice *choice, pz_ctx *ctx)
{
    choice->face_panel = malloc(((size_t)mesh->face_count + 1) * sizeof(int32_t));
    choice->names = calloc((size_t)mesh->label_count + 1, sizeof(char *));
    if (!choice->face_panel || !choice->names)
        return pz_error(ctx, PZ_ERR_NOMEM, "flatten: out of memory finding panels");
    memcpy(choice->face_panel, mesh->face_labels, (size_t)mesh->face_count * sizeof(int32_t));
    choice->panel_count = mesh->label_count;
    for (int32_t p = 0; p < mesh->label_count; ++p)
        if (mesh->label_names[p] && !(choice->names[p] = strdup(mesh->label_names[p])))
            return pz_error(ctx, PZ_ERR_NOMEM, "flatten: out of memory finding panels");
    choice->source = "files";
    return PZ_OK;
}

/* The extension's panels; it may move vertices along the surface (run's seam truing): the moved
 * vertices' garment.obj positions follow, the others keep the file's exact numbers. */
static pz_status extension_panels(const pz_flatten_extension *extension, garment_input *input, panel_choice *choice,
                                  pz_ctx *ctx)
{
    pz_mesh *mesh = input->mesh;
    size_t size = (size_t)mesh->vertex_count * 3;
    double *before = malloc(size * sizeof(double) + 1);
    if (!before)
        return pz_error(ctx, PZ_ERR_NOMEM, "flatten: out of memory");
    memcpy(before, mesh->positions, size * sizeof(double));
    choice->source = extension->panels_source ? extension->panels_source : "extension";
    pz_status status = extension->choose_panels(extension->user, mesh, &choice->face_panel, &choice->panel_count,
                                                &choice->extra_cuts, ctx);
    for (size_t v = 0; status == PZ_OK && v < size / 3; ++v)
        if (memcmp(before + 3 * v, mesh->positions + 3 * v, 3 * sizeof(double)) != 0)
            for (int d = 0; d < 3; ++d)
                input->output_positions[3 * v + d] = mesh->positions[3 * v + d] / mesh->unit_scale;
    free(before);
    return status;
}

static pz_status choose_panels(const pz_cli_args *args, const pz_flatten_extension *extension,
                               garment_input *input, panel_choice *choice, pz_ctx *ctx)
{
    const pz_mesh *mesh = input->mesh;
    const char *panels = pz_cli_value(args, PZ_CLI_OPT_PANELS);
    if (!panels && extension && extension->choose_panels)
        return extension_panels(extension, input, choice, ctx);
    if (panels && strcmp(panels, "uv") == 0) {
        if (!mesh->uvs || !mesh->corner_uvs)
            return pz_error(ctx, PZ_ERR_DATA, "%s: --panels uv: the mesh has no UVs (vt)", args->positionals[0]);
        choice->face_panel = malloc(((size_t)mesh->face_count + 1) * sizeof(int32_t));
        if (!choice->face_panel)
            return pz_error(ctx, PZ_ERR_NOMEM, "flatten: out of memory finding panels");
        choice->source = "uv";
        return pz_pattern_panels_from_uv(mesh, choice->face_panel, &choice->panel_count, &choice->extra_cuts, ctx);
    }
    if (panels) {
        if (!input->ids_preserved)
            return pz_error(ctx, PZ_ERR_DATA, "%s: --repair removed faces, so the per-face panel ids no longer apply",
                            panels);
        choice->face_panel = malloc(((size_t)mesh->face_count + 1) * sizeof(int32_t));
        if (!choice->face_panel)
            return pz_error(ctx, PZ_ERR_NOMEM, "flatten: out of memory finding panels");
        choice->source = "file";
        return pz_flatten_read_panel_file(panels, mesh->face_count, choice->face_panel, &choice->panel_count, ctx);
    }
    if (input->file_count > 1)
        return panels_from_files(mesh, choice, ctx);
    return panels_from_groups(mesh, choice, ctx);
}

/* --seams and --darts files as correspondences in garment vertex ids. */
static pz_status read_correspondences(const pz_cli_args *args, const garment_input *input, int32_t panel_count,
                                      pz_correspondences *out, pz_ctx *ctx)
{
    memset(out, 0, sizeof *out);
    if (args->seam_path_count + args->dart_path_count == 0)
        return PZ_OK;
    const char *first = args->seam_path_count ? args->seam_paths[0] : args->dart_paths[0];
    if (!input->ids_preserved)
        return pz_error(ctx, PZ_ERR_DATA, "%s: --repair removed faces or vertices, so the vertex ids no longer apply",
                        first);
    pz_vertex_space space = {input->file_count, input->file_vertex_offset, input->raw_to_garment, panel_count};
    out->seams = calloc((size_t)args->seam_path_count + 1, sizeof(pz_seam));
    out->darts = calloc((size_t)args->dart_path_count + 1, sizeof(pz_dart));
    if (!out->seams || !out->darts) {
        pz_correspondences_clear(out);
        return pz_error(ctx, PZ_ERR_NOMEM, "flatten: out of memory reading seams");
    }
    pz_status status = PZ_OK;
    for (int i = 0; i < args->seam_path_count && status == PZ_OK; ++i)
        if ((status = pz_flatten_read_seam(args->seam_paths[i], &space, &out->seams[i], ctx)) == PZ_OK)
            out->seam_count = i + 1;
    for (int i = 0; i < args->dart_path_count && status == PZ_OK; ++i)
        if ((status = pz_flatten_read_dart(args->dart_paths[i], &space, &out->darts[i], ctx)) == PZ_OK)
            out->dart_count = i + 1;
    if (status != PZ_OK)
        pz_correspondences_clear(out);
    return status;
}

/* ---------------------------------------------------------------- flatten and measure */

/* What the back-end reports about its own run (backend_result in report.json). */
typedef struct backend_outcome {
    pz_textile_result textile;
    pz_wirewarp_result wirewarp;       /* relaxed_key_curves are indices in the features file */
    pz_springmass_result springmass;   /* cleared with pz_springmass_result_clear */
    int32_t feature_count;             /* curves of --features used */
    pz_skipped_feature *skipped;       /* curves of --features left out (skipped_count), malloc'd */
    int32_t skipped_count;
    size_t skipped_capacity;
    int skipped_failed;                /* out of memory while recording a skipped curve */
    double ms;
} backend_outcome;

static void backend_outcome_clear(backend_outcome *outcome)
{
    pz_springmass_result_clear(&outcome->springmass);
    free(outcome->skipped);
    memset(outcome, 0, sizeof *outcome);
}

/* pz_feature_curves_snap_lenient's report of a curve it left out. */
static void record_skipped_curve(void *user, int32_t curve, const char *problem)
{
    backend_outcome *outcome = user;
    if ((size_t)outcome->skipped_count == outcome->skipped_capacity) {
        size_t capacity = outcome->skipped_capacity ? 2 * outcome->skipped_capacity : 4;
        pz_skipped_feature *bigger = realloc(outcome->skipped, capacity * sizeof *bigger);
        if (!bigger) {
            outcome->skipped_failed = 1;
            return;
        }
        outcome->skipped = bigger;
        outcome->skipped_capacity = capacity;
    }
    pz_skipped_feature *skipped = &outcome->skipped[outcome->skipped_count++];
    skipped->curve = curve;
    snprintf(skipped->problem, sizeof skipped->problem, "%s", problem);
}

/*
 * --features: read in the input's units, converted like the mesh, snapped to the cut mesh's edges.
 * A malformed file fails (exit 65); a well-formed curve that cannot be snapped (off the mesh, across
 * panels) is left out and recorded in outcome->skipped (a warning and report.json say so): the issue
 * asks for a best-effort result. *kept_from gets, per curve used, its index in the file.
 */
static pz_status read_feature_curves(const flatten_settings *settings, const pz_pattern *pattern, double mm_per_unit,
                                     pz_feature_curves **out, int32_t **kept_from, backend_outcome *outcome,
                                     pz_ctx *ctx)
{
    *out = NULL;
    *kept_from = NULL;
    if (!settings->features_path)
        return PZ_OK;
    pz_feature_file file;
    pz_status status = pz_flatten_read_features(settings->features_path, mm_per_unit, &file, ctx);
    if (status != PZ_OK)
        return status;
    uint8_t *skipped = calloc((size_t)file.curve_count + 1, 1);
    *kept_from = malloc((size_t)file.curve_count * sizeof(int32_t) + 1);
    if (!skipped || !*kept_from)
        status = pz_error(ctx, PZ_ERR_NOMEM, "flatten: out of memory");
    if (status == PZ_OK)
        status = pz_feature_curves_snap_lenient(pattern, file.polylines, file.curve_count, 0, out, skipped,
                                                record_skipped_curve, outcome, ctx);
    if (status == PZ_OK && outcome->skipped_failed)
        status = pz_error(ctx, PZ_ERR_NOMEM, "flatten: out of memory");
    for (int32_t c = 0, k = 0; status == PZ_OK && c < file.curve_count; ++c)
        if (!skipped[c])
            (*kept_from)[k++] = c;
    pz_feature_file_clear(&file);
    free(skipped);
    if (status != PZ_OK) {
        pz_feature_curves_free(out);
        free(*kept_from);
        *kept_from = NULL;
    }
    return status;
}

static pz_status flatten_wirewarp(const flatten_settings *settings, const pz_pattern *pattern, double mm_per_unit,
                                  double *uv, backend_outcome *outcome, pz_ctx *ctx)
{
    pz_feature_curves *features = NULL;
    int32_t *kept_from = NULL;
    pz_status status = read_feature_curves(settings, pattern, mm_per_unit, &features, &kept_from, outcome, ctx);
    if (status != PZ_OK)
        return status;
    outcome->feature_count = features ? features->curve_count : 0;
    pz_wirewarp_options options = {0};
    options.scheme = settings->progressive;
    options.grain_given = 1;
    memcpy(options.grain, settings->grain, sizeof options.grain);
    status = pz_param_wirewarp(pattern, &options, features, uv, &outcome->wirewarp, ctx);
    /* The user knows the curves by their place in the file. */
    pz_wirewarp_result *r = &outcome->wirewarp;
    for (int32_t i = 0; kept_from && i < r->relaxed_key_curve_count && i < PZ_WIREWARP_RELAXED_MAX; ++i)
        r->relaxed_key_curves[i] = kept_from[r->relaxed_key_curves[i]];
    pz_feature_curves_free(&features);
    free(kept_from);
    return status;
}

/* One warning line per thing the user should know about a best-effort WireWarping (docs/wirewarp.md). */
static void warn_wirewarp(const flatten_settings *settings, const backend_outcome *outcome, pz_ctx *ctx)
{
    const char *file = settings->features_path ? settings->features_path : "--features";
    for (int32_t i = 0; i < outcome->skipped_count; ++i)
        pz_note(ctx, "warning: %s: %s; the curve is left out, the pattern is flattened with the %d other%s", file,
                outcome->skipped[i].problem, (int)outcome->feature_count, outcome->feature_count == 1 ? "" : "s");
    const pz_wirewarp_result *r = &outcome->wirewarp;
    if (r->relaxed_key_curve_count > 0) {
        char list[160] = "";
        size_t used = 0;
        for (int32_t i = 0; i < r->relaxed_key_curve_count && i < PZ_WIREWARP_RELAXED_MAX && used < sizeof list; ++i)
            used += (size_t)snprintf(list + used, sizeof list - used, "%s%d", i ? ", " : "",
                                     (int)r->relaxed_key_curves[i]);
        pz_note(ctx, "warning: %s: key curve%s %s%s over-constrain%s the pattern (the pieces cannot close with "
                "their angles fixed, wang2008 Figs. 13-14): best effort, %s angles relaxed by up to %.2f degrees, "
                "wire lengths kept (worst error %.2g)", file, r->relaxed_key_curve_count == 1 ? "" : "s", list,
                r->relaxed_key_curve_count > PZ_WIREWARP_RELAXED_MAX ? ", ..." : "",
                r->relaxed_key_curve_count == 1 ? "s" : "", r->relaxed_key_curve_count == 1 ? "its" : "their",
                r->relaxed_key_angle * 180 / 3.14159265358979323846,
                r->max_wire_error);
    }
    if (r->trimmed_feature_edges > 0 || r->flipped_triangles > 0 || !(r->constraint_residual <= 1e-9))
        pz_note(ctx, "warning: wirewarp: best effort: %d edge%s given up at dangling feature-curve ends, %d face%s "
                "still flipped, constraint residual %.2g, worst wire error %.2g",
                (int)r->trimmed_feature_edges, r->trimmed_feature_edges == 1 ? "" : "s", (int)r->flipped_triangles,
                r->flipped_triangles == 1 ? "" : "s", r->constraint_residual, r->max_wire_error);
}

static pz_status flatten_springmass(const flatten_settings *settings, const pz_pattern *pattern, double *uv,
                                    backend_outcome *outcome, pz_ctx *ctx)
{
    pz_springmass_options options = {0};
    options.relax = settings->relax_full;
    /* --fabric asks for McCartney's warp/weft/shear energy; without it, isotropic springs (wang2002). */
    options.orthotropic = settings->fabric_given;
    options.fabric = settings->fabric;
    options.grain_given = 1;
    memcpy(options.grain, settings->grain, sizeof options.grain);
    /* The trial cut classifies each suggested cutting line as dart or gusset (mccartney2005). */
    options.trial_cut = 1;
    return pz_param_springmass(pattern, &options, uv, &outcome->springmass, ctx);
}

static pz_status flatten_textile(const flatten_settings *settings, const pz_pattern *pattern, double *uv,
                                 pz_textile_result *result, pz_ctx *ctx)
{
    pz_textile_options options = {0};
    options.iterations = settings->iterations;
    options.weights_given = 1;
    options.weight_stretch = settings->weights[0];
    options.weight_rigid = settings->weights[1];
    options.weight_dart = settings->weights[2];
    options.weight_seam = settings->weights[3];
    options.grain_given = 1;
    memcpy(options.grain, settings->grain, sizeof options.grain);
    options.use_poses = pattern->mesh->pose_count > 0;
    options.strain_limit = settings->strain_limit;
    return pz_param_textile(pattern, &options, uv, result, ctx);
}

static pz_status flatten(const flatten_settings *settings, const pz_pattern *pattern, double mm_per_unit,
                         double *uv, backend_outcome *outcome, pz_ctx *ctx)
{
    double start = pz_seconds();
    pz_status status;
    switch (settings->backend) {
    case BACKEND_LSCM: status = pz_param_lscm_pattern(pattern, settings->grain, uv, ctx); break;
    case BACKEND_WIREWARP: status = flatten_wirewarp(settings, pattern, mm_per_unit, uv, outcome, ctx); break;
    case BACKEND_SPRINGMASS: status = flatten_springmass(settings, pattern, uv, outcome, ctx); break;
    default: status = flatten_textile(settings, pattern, uv, &outcome->textile, ctx); break;
    }
    outcome->ms = pz_cli_elapsed_ms(start, pz_seconds());
    return status;
}

pz_status pz_flatten_pattern_like_cli(const pz_cli_args *args, const pz_mesh *garment, const pz_pattern *pattern,
                                      double strain_limit, double *uv, pz_fabric *fabric, pz_ctx *ctx)
{
    flatten_settings settings;
    pz_status status = parse_settings(args, &settings, ctx);
    if (status != PZ_OK)
        return status;
    if (!settings.grain_given)
        pz_mesh_vertical_axis(garment, settings.grain);
    settings.strain_limit = strain_limit;
    if (fabric)
        *fabric = settings.fabric;
    if (!uv)
        return PZ_OK;
    if (settings.backend == BACKEND_LSCM)
        return pz_param_lscm_pattern(pattern, settings.grain, uv, ctx);
    pz_textile_result result;
    return flatten_textile(&settings, pattern, uv, &result, ctx);
}

/* metrics[0] on the rest pose, metrics[p] on extra pose p. */
static pz_status measure(const pz_pattern *pattern, const double *uv, const pz_fabric *fabric,
                         pz_metrics **metrics, int count, pz_ctx *ctx)
{
    for (int pose = 0; pose < count; ++pose) {
        pz_status status = pz_metrics_compute(pattern, uv, pose, fabric, &metrics[pose], ctx);
        if (status != PZ_OK)
            return status;
    }
    return PZ_OK;
}

/* ---------------------------------------------------------------- writing */

/* Directories created by this run, removed again when it fails. */
typedef struct created_dirs {
    char *paths[64];
    int count;
} created_dirs;

static void remove_created_dirs(created_dirs *dirs)
{
    while (dirs->count > 0) {
        --dirs->count;
        rmdir(dirs->paths[dirs->count]);
        free(dirs->paths[dirs->count]);
    }
}

static void forget_created_dirs(created_dirs *dirs)
{
    while (dirs->count > 0)
        free(dirs->paths[--dirs->count]);
}

/* mkdir -p: every missing prefix of `dir`, remembering what it created. */
static pz_status make_directories(const char *dir, created_dirs *dirs, pz_ctx *ctx)
{
    char *path = strdup(dir);
    if (!path)
        return pz_error(ctx, PZ_ERR_NOMEM, "%s: out of memory", dir);
    size_t length = strlen(path);
    pz_status status = PZ_OK;
    for (size_t end = 1; end <= length && status == PZ_OK; ++end) {
        if (end < length && path[end] != '/')
            continue;
        char saved = path[end];
        path[end] = '\0';
        struct stat info;
        if (stat(path, &info) == 0) {
            if (!S_ISDIR(info.st_mode))
                status = pz_error(ctx, PZ_ERR_CREATE, "%s: cannot create the output directory: %s is not a directory",
                                  dir, path);
        } else if (mkdir(path, 0777) != 0) {
            status = pz_error(ctx, PZ_ERR_CREATE, "%s: cannot create the output directory: %s", dir, strerror(errno));
        } else if (dirs->count < (int)(sizeof dirs->paths / sizeof dirs->paths[0])) {
            if (!(dirs->paths[dirs->count] = strdup(path)))
                status = pz_error(ctx, PZ_ERR_NOMEM, "%s: out of memory", dir);
            else
                ++dirs->count;
        }
        path[end] = saved;
    }
    free(path);
    return status;
}

static char *join_path(const char *dir, const char *name)
{
    size_t size = strlen(dir) + strlen(name) + 2;
    char *path = malloc(size);
    if (path)
        snprintf(path, size, "%s%s%s", dir, dir[strlen(dir) - 1] == '/' ? "" : "/", name);
    return path;
}

/*
 * The files of one run, in writing order: garment.obj, the old pattern.svg
 * (only while the export table has no pattern.svg of its own), every file
 * of the export table but report.html, the command's extra files
 * (layout.obj), report.json (built then, so it can carry the write timing of
 * the files before it), report.html (which shows report.json).
 */
enum output_kind { OUT_OBJ, OUT_OLD_SVG, OUT_EXPORT, OUT_EXTRA, OUT_REPORT, OUT_HTML };

typedef struct output_entry {
    const char *name;
    enum output_kind kind;
    int index;                /* OUT_EXPORT / OUT_HTML: pz_export_files index; OUT_EXTRA: extension index */
    int binary;
} output_entry;

#define MAX_OUTPUTS 32

/* Everything the write step needs. */
typedef struct flatten_run {
    const pz_cli_args *args;
    const pz_flatten_extension *extension;
    const garment_input *input;
    const panel_choice *panels;
    const pz_pattern *pattern;
    double *uv;
    const pz_springmass_result *springmass;  /* energy.svg is written when set */
    pz_flatten_report report;
    pz_export_inputs export_inputs;
    const pz_marker *marker;
    double start, write_start;
    cJSON *report_root;       /* built just before report.json is written */
    char *report_text;        /* report.json, for --json too */
    output_entry outputs[MAX_OUTPUTS];
    int output_count;
} flatten_run;

static int export_table_has(const char *name)
{
    for (int i = 0; i < pz_export_file_count; ++i)
        if (strcmp(pz_export_files[i].name, name) == 0)
            return 1;
    return 0;
}

static void add_output(flatten_run *run, const char *name, enum output_kind kind, int index, int binary)
{
    if (run->output_count < MAX_OUTPUTS)
        run->outputs[run->output_count++] = (output_entry){name, kind, index, binary};
}

static void list_outputs(flatten_run *run)
{
    run->output_count = 0;
    add_output(run, "garment.obj", OUT_OBJ, 0, 1);
    if (!export_table_has("pattern.svg"))
        add_output(run, "pattern.svg", OUT_OLD_SVG, 0, 1);
    for (int i = 0; i < pz_export_file_count; ++i)
        if (strcmp(pz_export_files[i].name, "report.html") != 0 &&
            (run->marker || strcmp(pz_export_files[i].name, "marker.svg") != 0))
            add_output(run, pz_export_files[i].name, OUT_EXPORT, i, pz_export_files[i].binary);
    const pz_flatten_extension *extension = run->extension;
    for (int i = 0; extension && i < extension->extra_file_count; ++i)
        add_output(run, extension->extra_files[i].name, OUT_EXTRA, i, 1);
    add_output(run, "report.json", OUT_REPORT, 0, 1);
    for (int i = 0; i < pz_export_file_count; ++i)
        if (strcmp(pz_export_files[i].name, "report.html") == 0)
            add_output(run, pz_export_files[i].name, OUT_HTML, i, 1);
}

/* report.json's content, with the marker and the command's own keys. */
static pz_status build_report(flatten_run *run, pz_ctx *ctx)
{
    double now = pz_seconds();
    run->report.timings_ms[TIME_WRITE] = pz_cli_elapsed_ms(run->write_start, now);
    run->report.timings_ms[TIME_TOTAL] = pz_cli_elapsed_ms(run->start, now);
    cJSON *root = pz_flatten_report_json(&run->report);
    int failed = !root;
    if (root && run->marker) {
        cJSON *marker = pz_marker_report_json(run->marker);
        failed |= !marker || !cJSON_AddItemToObject(root, "marker", marker);
    }
    const pz_flatten_extension *extension = run->extension;
    if (root && !failed && extension && extension->extend_report)
        failed |= !extension->extend_report(extension->user, root, run->input->mesh, run->pattern, run->uv,
                                            run->report.metrics[0]);
    run->report_text = root && !failed ? cJSON_Print(root) : NULL;
    if (!run->report_text) {
        cJSON_Delete(root);
        return pz_error(ctx, PZ_ERR_NOMEM, "report.json: out of memory");
    }
    run->report_root = root;
    run->export_inputs.report = root;
    return PZ_OK;
}

/* Writes one output; path (the file's full name) names it in errors. */
static pz_status write_file(flatten_run *run, const output_entry *entry, const char *path, FILE *file, pz_ctx *ctx)
{
    switch (entry->kind) {
    case OUT_OBJ:
        return pz_pattern_write_obj(file, run->input->mesh, run->input->output_positions, run->pattern, run->uv, ctx);
    case OUT_OLD_SVG:
        return pz_pattern_write_svg(file, run->pattern, run->uv, (const char *const *)run->panels->names, ctx);
    case OUT_EXPORT:
    case OUT_HTML:
        return pz_export_files[entry->index].write(file, &run->export_inputs, path, ctx);
    case OUT_EXTRA: {
        const pz_flatten_extension *extension = run->extension;
        return extension->extra_files[entry->index].write(extension->user, file, run->pattern, ctx);
    }
    case OUT_REPORT: {
        pz_status status = build_report(run, ctx);
        if (status != PZ_OK)
            return status;
        fputs(run->report_text, file);
        fputc('\n', file);
        return PZ_OK;
    }
    }
    return pz_error(ctx, PZ_ERR_INTERNAL, "%s: unknown output", path);
}

/*
 * Writes every file all or nothing. energy.svg is written by the library's
 * own atomic writer once the others are complete in their temporaries, and
 * removed again should a rename fail afterwards.
 */
static pz_status write_outputs(flatten_run *run, pz_ctx *ctx)
{
    const char *dir = run->args->output_path;
    list_outputs(run);
    int count = run->output_count;
    created_dirs dirs = {{0}, 0};
    char *paths[MAX_OUTPUTS] = {0};
    char *energy_path = NULL;
    int energy_written = 0;
    pz_output outputs[MAX_OUTPUTS];
    memset(outputs, 0, sizeof outputs);
    int committed = 0;
    pz_status status = make_directories(dir, &dirs, ctx);
    for (int i = 0; i < count && status == PZ_OK; ++i)
        if (!(paths[i] = join_path(dir, run->outputs[i].name)))
            status = pz_error(ctx, PZ_ERR_NOMEM, "%s: out of memory", dir);
    for (int i = 0; i < count && status == PZ_OK; ++i)
        if ((status = pz_output_open(&outputs[i], paths[i], "wb", ctx)) == PZ_OK)
            status = write_file(run, &run->outputs[i], paths[i], outputs[i].file, ctx);
    if (status == PZ_OK && run->springmass) {
        if (!(energy_path = join_path(dir, "energy.svg")))
            status = pz_error(ctx, PZ_ERR_NOMEM, "%s: out of memory", dir);
        else if ((status = pz_springmass_write_energy_svg(run->pattern, run->uv, run->springmass, energy_path, ctx)) ==
                 PZ_OK)
            energy_written = 1;
    }
    for (; committed < count && status == PZ_OK; ++committed)
        if ((status = pz_output_commit(&outputs[committed], ctx)) != PZ_OK)
            break;
    if (status != PZ_OK) {
        /* Abort is a no-op on an output never opened or already committed (its fields are cleared). */
        for (int i = 0; i < count; ++i)
            pz_output_abort(&outputs[i]);
        for (int i = 0; i < committed; ++i)
            remove(paths[i]);
        if (energy_written)
            remove(energy_path);
        remove_created_dirs(&dirs);
    }
    free(energy_path);
    forget_created_dirs(&dirs);
    for (int i = 0; i < count; ++i)
        free(paths[i]);
    return status;
}

static pz_status print_result(const flatten_run *run, const pz_metrics *const *metrics, int metrics_count,
                              pz_ctx *ctx)
{
    if (run->args->json) {
        fputs(run->report_text, stdout);
        fputc('\n', stdout);
        return PZ_OK;
    }
    const pz_metrics *rest = metrics[0];
    double max_abs_strain = 0;
    int injective = 1;
    for (int i = 0; i < metrics_count; ++i) {
        max_abs_strain = fmax(max_abs_strain, metrics[i]->max_abs_strain);
        injective &= metrics[i]->injective != 0;
    }
    const pz_flatten_report *report = &run->report;
    printf("backend:            %s%s\n", report->backend,
           report->wirewarp ? (report->progressive ? " (progressive)" : " (global)")
           : report->springmass ? (report->relax_full ? " (full relaxation)" : " (heap relaxation)") : "");
    printf("panels:             %d (from %s)\n", (int)rest->panel_count, run->panels->source);
    printf("seams, darts:       %d, %d\n", (int)rest->seam_count, (int)rest->dart_count);
    printf("max |strain|:       %.6f%s\n", max_abs_strain, metrics_count > 1 ? " (worst pose)" : "");
    printf("injective:          %s\n", injective ? "yes" : "no");
    printf("max seam mismatch:  %.6f\n", rest->max_seam_mismatch_rel);
    if (run->marker)
        printf("marker:             %.1f mm long, efficiency %.1f%%\n", run->marker->length_mm,
               100.0 * run->marker->efficiency);
    if (run->extension && run->extension->print_summary)
        run->extension->print_summary(run->extension->user);
    printf("wrote:              %s/{", run->args->output_path);
    for (int i = 0; i < run->output_count; ++i)
        printf("%s%s", i ? "," : "", run->outputs[i].name);
    printf("%s}\n", run->springmass ? ",energy.svg" : "");
    (void)ctx;
    return PZ_OK;
}

/* ---------------------------------------------------------------- the command */

/* The pieces (and the marker) every export file is drawn from; nothing when the export table is empty. */
static pz_status build_pieces(const flatten_settings *settings, const pz_flatten_extension *extension,
                              const pz_pattern *pattern, const double *uv, const char *const *panel_names,
                              double **seam_allowances, pz_pieces **pieces, pz_marker **marker, pz_ctx *ctx)
{
    if (pz_export_file_count == 0)
        return PZ_OK;
    pz_export_options options = settings->export_options;
    pz_status status = PZ_OK;
    if (settings->allowances_path) {
        status = pz_export_read_allowances(settings->allowances_path, pattern, seam_allowances, ctx);
        options.seam_allowances_mm = *seam_allowances;
    }
    const int32_t *panel_mirror = NULL;
    if (status == PZ_OK && extension && extension->panel_mirror)
        panel_mirror = extension->panel_mirror(extension->user, pattern);
    if (status == PZ_OK)
        status = pz_pieces_build(pattern, uv, &options, panel_mirror, panel_names, pieces, ctx);
    if (status == PZ_OK)
        status = pz_marker_build(*pieces, &options, marker, ctx);
    for (int32_t i = 0; status == PZ_OK && i < (*marker)->unplaced_count; ++i) {
        const pz_piece *piece = &(*pieces)->pieces[(*marker)->unplaced[i]];
        pz_note(ctx, "warning: marker: piece %s (%.0f mm wide) does not fit on a fabric %.0f mm wide: left out of "
                "marker.svg (give a wider --fabric-width)", piece->name, piece->bbox_max[0] - piece->bbox_min[0],
                (*marker)->fabric_width_mm);
    }
    return status;
}

/* Asks the extension whether the flattened pattern (rest-pose metrics) is accepted. */
static pz_status judge_pattern(const pz_flatten_extension *extension, const pz_pattern *pattern, const double *uv,
                               const pz_fabric *fabric, int *accepted, pz_ctx *ctx)
{
    pz_metrics *metrics = NULL;
    pz_status status = pz_metrics_compute(pattern, uv, 0, fabric, &metrics, ctx);
    if (status == PZ_OK)
        *accepted = extension->accept_pattern(extension->user, pattern, uv, metrics);
    pz_metrics_free(&metrics);
    return status;
}

pz_status pz_cli_flatten(const pz_cli_args *args, pz_ctx *ctx)
{
    return pz_flatten_execute(args, NULL, ctx);
}

pz_status pz_flatten_execute(const pz_cli_args *args, const pz_flatten_extension *extension, pz_ctx *ctx)
{
    flatten_settings settings;
    pz_status status = parse_settings(args, &settings, ctx);
    if (extension)
        settings.strain_limit = extension->strain_limit;
    if (status != PZ_OK)
        return status;
    flatten_run run;
    memset(&run, 0, sizeof run);
    run.args = args;
    run.start = pz_seconds();
    garment_input input = {0};
    panel_choice panels = {0};
    pz_correspondences correspondences = {0};
    pz_pattern *pattern = NULL;
    double *uv = NULL;
    backend_outcome outcome;
    memset(&outcome, 0, sizeof outcome);
    const char *grain_source = "given";
    int metrics_count = 0, layout_moved = 0;
    pz_metrics **metrics = NULL;
    double *seam_allowances = NULL;
    pz_pieces *pieces = NULL;
    pz_marker *marker = NULL;
    double *timings = run.report.timings_ms, mark = run.start, now;
    run.extension = extension;

    status = load_garment(args, extension, &input, ctx);
    timings[TIME_READ] = pz_cli_elapsed_ms(mark, now = pz_seconds()), mark = now;
    if (status == PZ_OK && !settings.grain_given) {
        /* y-up (glTF, CLO3D, Blender) and z-up (scanners, CAD) garments both get the warp along their height. */
        pz_mesh_vertical_axis(input.mesh, settings.grain);
        grain_source = settings.grain[1] > 0.5 ? "vertical axis (y)" : "vertical axis (z)";
    }
    /* Choosing the panels is part of `pattern` (docs/flatten.md) but, in `run`, is the segmentation:
     * the timings line shows it apart, or the segmentation reads as the cost of cutting the garment.
     * The extension may judge the joint flattening and choose panels again (run's final verdict):
     * each phase's time is summed over the rounds. */
    double panels_ms = 0, pattern_ms = 0, flatten_ms = 0;
    for (int round = 0; status == PZ_OK; ++round) {
        if (round > 0) {
            backend_outcome_clear(&outcome);
            free(uv);
            uv = NULL;
            pz_pattern_free(&pattern);
            panel_choice_clear(&panels);
        }
        mark = pz_seconds();
        status = choose_panels(args, extension, &input, &panels, ctx);
        panels_ms += pz_cli_elapsed_ms(mark, pz_seconds());
        /* run's --darts is on|off, not dart files; it takes no --seams. */
        if (status == PZ_OK && !extension && round == 0)
            status = read_correspondences(args, &input, panels.panel_count, &correspondences, ctx);
        if (status == PZ_OK)
            status = pz_pattern_build(input.mesh, panels.face_panel, panels.extra_cuts, &correspondences,
                                      args->positionals[0], &pattern, ctx);
        pattern_ms += pz_cli_elapsed_ms(mark, now = pz_seconds()), mark = now;
        if (status == PZ_OK && !(uv = calloc(2 * (size_t)pattern->mesh->vertex_count + 2, sizeof(double))))
            status = pz_error(ctx, PZ_ERR_NOMEM, "flatten: out of memory");
        if (status == PZ_OK)
            status = flatten(&settings, pattern, input.mesh->unit_scale, uv, &outcome, ctx);
        int accepted = 1;
        if (status == PZ_OK && extension && extension->accept_pattern)
            status = judge_pattern(extension, pattern, uv, &settings.fabric, &accepted, ctx);
        flatten_ms += pz_cli_elapsed_ms(mark, now = pz_seconds()), mark = now;
        if (status != PZ_OK || accepted)
            break;
    }
    timings[TIME_PATTERN] = pattern_ms;
    if (status == PZ_OK && settings.backend == BACKEND_WIREWARP)
        warn_wirewarp(&settings, &outcome, ctx);  /* once, for the pattern kept */
    if (status == PZ_OK)
        status = pz_pattern_layout(pattern, uv, LAYOUT_GAP_MM, &layout_moved, ctx);
    timings[TIME_FLATTEN] = flatten_ms + pz_cli_elapsed_ms(mark, now = pz_seconds()), mark = now;
    if (status == PZ_OK) {
        metrics_count = 1 + pattern->mesh->pose_count;
        if (!(metrics = calloc((size_t)metrics_count, sizeof *metrics)))
            status = pz_error(ctx, PZ_ERR_NOMEM, "flatten: out of memory");
    }
    if (status == PZ_OK)
        status = measure(pattern, uv, &settings.fabric, metrics, metrics_count, ctx);
    timings[TIME_METRICS] = pz_cli_elapsed_ms(mark, now = pz_seconds());
    /* Names belong to the panels as chosen; should the pattern number them otherwise, show none. */
    if (status == PZ_OK && pattern->panel_count != panels.panel_count)
        panel_choice_drop_names(&panels);
    run.write_start = pz_seconds();
    /* The pieces carry the garment's name: the input's base name, unless a size name says otherwise. */
    char *garment_name = duplicate_base_name(args->positionals[0]);
    if (garment_name && !settings.export_options.garment_name)
        settings.export_options.garment_name = garment_name;
    if (status == PZ_OK)
        status = build_pieces(&settings, extension, pattern, uv, (const char *const *)panels.names,
                              &seam_allowances, &pieces, &marker, ctx);
    if (status == PZ_OK) {
        pz_export_inputs *inputs = &run.export_inputs;
        inputs->garment = input.mesh;
        inputs->positions = input.output_positions;
        inputs->pattern = pattern;
        inputs->uv = uv;
        inputs->metrics = metrics[0];
        inputs->pieces = pieces;
        inputs->marker = marker;
        inputs->options = &settings.export_options;
        inputs->panel_names = (const char *const *)panels.names;
        if (extension && extension->layout_curves)
            extension->layout_curves(extension->user, pattern, &inputs->layout_vertices, &inputs->layout_offsets,
                                     &inputs->layout_curve_count);
        run.marker = marker;
    }
    if (status == PZ_OK) {
        run.input = &input;
        run.panels = &panels;
        run.pattern = pattern;
        run.uv = uv;
        run.springmass = settings.backend == BACKEND_SPRINGMASS ? &outcome.springmass : NULL;
        pz_flatten_report *report = &run.report;
        report->input_paths = args->positionals;
        report->input_count = args->positional_count;
        report->vertices = input.mesh->vertex_count;
        report->faces = input.mesh->face_count;
        report->poses = input.mesh->pose_count;
        report->units = pz_units_str(input.units);
        report->units_guessed = args->units == PZ_UNITS_AUTO;
        report->panels_source = panels.source;
        report->backend = backend_names[settings.backend];
        report->iterations = settings.iterations;
        memcpy(report->weights, settings.weights, sizeof report->weights);
        report->fabric = settings.fabric;
        memcpy(report->grain, settings.grain, sizeof report->grain);
        report->grain_source = grain_source;
        report->textile = settings.backend == BACKEND_TEXTILE ? &outcome.textile : NULL;
        report->wirewarp = settings.backend == BACKEND_WIREWARP ? &outcome.wirewarp : NULL;
        report->progressive = settings.progressive;
        report->feature_count = outcome.feature_count;
        report->skipped_features = outcome.skipped;
        report->skipped_feature_count = outcome.skipped_count;
        report->springmass = run.springmass;
        report->relax_full = settings.relax_full;
        report->orthotropic = settings.fabric_given;
        report->backend_ms = outcome.ms;
        report->uv = uv;
        report->layout_moved = layout_moved;
        report->pattern = pattern;
        report->metrics = (const pz_metrics *const *)metrics;
        report->metrics_count = metrics_count;
        report->panel_names = (const char *const *)panels.names;
        status = write_outputs(&run, ctx);
    }
    if (status == PZ_OK) {
        pz_note(ctx, "flatten: %d panel%s; read %.1f ms, pattern %.1f ms (choosing the panels %.1f ms), "
                "flatten %.1f ms, metrics %.1f ms, write %.1f ms, total %.1f ms", (int)pattern->panel_count,
                pattern->panel_count == 1 ? "" : "s", timings[TIME_READ], timings[TIME_PATTERN], panels_ms,
                timings[TIME_FLATTEN], timings[TIME_METRICS], timings[TIME_WRITE], timings[TIME_TOTAL]);
        pz_cli_warn_units(args, args->positionals[0], input.mesh, input.units, ctx);
        status = print_result(&run, (const pz_metrics *const *)metrics, metrics_count, ctx);
    }
    free(run.report_text);
    cJSON_Delete(run.report_root);
    pz_marker_free(&marker);
    pz_pieces_free(&pieces);
    free(garment_name);
    free(seam_allowances);
    for (int i = 0; metrics && i < metrics_count; ++i)
        pz_metrics_free(&metrics[i]);
    free(metrics);
    backend_outcome_clear(&outcome);
    free(uv);
    pz_pattern_free(&pattern);
    pz_correspondences_clear(&correspondences);
    panel_choice_clear(&panels);
    garment_input_clear(&input);
    /* Messages from the shared steps say "flatten:"; name the command that ran. */
    if (status != PZ_OK && strcmp(args->command, "flatten") != 0 && strncmp(ctx->error, "flatten: ", 9) == 0) {
        char message[sizeof ctx->error];
        snprintf(message, sizeof message, "%s", ctx->error + 9);
        snprintf(ctx->error, sizeof ctx->error, "%s: %.*s", args->command, (int)(sizeof message - 16), message);
    }
    return status;
}

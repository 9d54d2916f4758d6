/*
 * cli/cmd_flatten.c -- `panelize flatten MESH... -o DIR`: the user's own
 * panels flattened into a sewing pattern (docs/flatten.md). A caller of
 * pz_flatten (pipeline/pipeline.h): this file turns argv into options and
 * inputs, reads the files, and writes the result; no algorithm lives here.
 *
 *  1. options, all checked before any file is read (exit 64);
 *  2. read: one MESH (with --pose files), or several panel files joined
 *     without welding (panel K = file K, pz_mesh_join); --panels FILE, and
 *     the --seams/--darts files in the input's vertex ids;
 *  3. pz_flatten, then pz_result_write into DIR (all or nothing).
 *
 * SPDX-License-Identifier: GPL-3.0-or-later
 */
#define _POSIX_C_SOURCE 200809L
#include "cli/cli.h"

#include <stdlib.h>
#include <string.h>

const char pz_cli_flatten_usage[] =
    "usage: panelize flatten MESH... -o DIR [--panels FILE|uv] [--seams FILE]...\n"
    "           [--darts [K:]FILE]... [--grain X,Y,Z] [--grain-hints FILE] [--pose FILE]...\n"
    "           [--backend textile|lscm|wirewarp|springmass] [--scheme global|progressive]\n"
    "           [--relax heap|full] [--features FILE] [--iterations N] [--weights S,R,D,M]\n"
    "           [--fabric KSU,KSV,KR] [--seam-allowance MM] [--hem-allowance MM]\n"
    "           [--allowances FILE] [--notch-spacing MM] [--paper a4|letter] [--dxf-strict]\n"
    "           [--fabric-width MM] [--gap MM] [--size NAME] [--outputs LIST]\n"
    "           [--units U] [--repair]\n"
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
    "  --grain-hints FILE   JSON {\"curves\": [[[x,y,z], ...], ...]} in the mesh's\n"
    "                       units: short strokes along which the warp runs in the\n"
    "                       panel each lies on (its own grain, e.g. a bias cut)\n"
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
    "  --outputs LIST       the files to write, comma-separated: obj, svg, pdf, tiled,\n"
    "                       dxf, marker, glb, json, html, energy, all (default all)\n"
    "  --units U            the input's units: mm, cm, m or auto (default)\n"
    "  --repair             repair the mesh before validating (see panelize check)\n"
    "  --json               print report.json on stdout\n"
    "  --quiet              nothing on stderr but an error\n"
    "\n"
    "See docs/flatten.md and docs/export.md.\n";

/* The inputs as read: the mesh (the files' units), where each file's vertices start, the panels. */
typedef struct flatten_inputs {
    pz_mesh *mesh;
    int32_t *file_vertex_offset;    /* file count + 1 */
    uint8_t *vertex_used;           /* a face uses the vertex */
    int32_t *face_panel;            /* --panels FILE */
    pz_panels panels;
    pz_correspondences correspondences;
} flatten_inputs;

static void flatten_inputs_clear(flatten_inputs *inputs)
{
    pz_mesh_free(&inputs->mesh);
    free(inputs->file_vertex_offset);
    free(inputs->vertex_used);
    free(inputs->face_panel);
    pz_correspondences_clear(&inputs->correspondences);
    memset(inputs, 0, sizeof *inputs);
}

/* A garment too large for pattern-tiled.pdf (when it is asked for) is refused before the computation. */
static pz_status check_tiled_size(const pz_cli_args *args, const pz_mesh *mesh, pz_ctx *ctx)
{
    unsigned outputs = 0;
    if (pz_cli_outputs(args, &outputs, ctx) != PZ_OK || !(outputs & PZ_OUTPUT_TILED_PDF))
        return PZ_OK;
    if (args->units == PZ_UNITS_AUTO && !pz_mesh_units_plausible(mesh, PZ_UNITS_AUTO))
        return PZ_OK; /* a guess that fits no garment: the units check says so, more plainly */
    double mm = pz_units_to_mm(args->units == PZ_UNITS_AUTO ? pz_mesh_guess_units(mesh) : args->units);
    return pz_export_check_tiled_area(pz_geom_total_area(mesh) * mm * mm, pz_cli_value(args, PZ_CLI_OPT_PAPER),
                                      args->positionals[0], ctx);
}

/* MESH with its poses, or several panel files joined. */
pz_status pz_cli_read_meshes(const pz_cli_args *args, pz_mesh **mesh, int32_t *file_vertex_offset, pz_ctx *ctx)
{
    int32_t count = args->positional_count;
    if (count == 1) {
        pz_status status = pz_mesh_read_with_poses(args->positionals[0], args->pose_paths, args->pose_path_count,
                                                   mesh, ctx);
        if (status == PZ_OK && file_vertex_offset)
            file_vertex_offset[0] = 0, file_vertex_offset[1] = (*mesh)->vertex_count;
        if (status == PZ_OK && (status = check_tiled_size(args, *mesh, ctx)) != PZ_OK)
            pz_mesh_free(mesh);
        return status;
    }
    pz_mesh **parts = calloc((size_t)count, sizeof *parts);
    if (!parts)
        return pz_error(ctx, PZ_ERR_NOMEM, "flatten: out of memory");
    pz_status status = PZ_OK;
    for (int32_t i = 0; i < count && status == PZ_OK; ++i)
        status = pz_mesh_read(args->positionals[i], &parts[i], ctx);
    if (status == PZ_OK)
        status = pz_mesh_join(parts, args->positionals, count, mesh, file_vertex_offset, ctx);
    if (status == PZ_OK && (status = check_tiled_size(args, *mesh, ctx)) != PZ_OK)
        pz_mesh_free(mesh);
    for (int32_t i = 0; i < count; ++i)
        pz_mesh_free(&parts[i]);
    free(parts);
    return status;
}

/* --panels FILE|uv, or the files / groups. */
static pz_status read_panels(const pz_cli_args *args, flatten_inputs *inputs, pz_ctx *ctx)
{
    const char *panels = pz_cli_value(args, PZ_CLI_OPT_PANELS);
    pz_panels *out = &inputs->panels;
    out->source = args->positional_count > 1 ? PZ_PANELS_LABELS : PZ_PANELS_GROUPS;
    if (!panels)
        return PZ_OK;
    if (strcmp(panels, "uv") == 0) {
        out->source = PZ_PANELS_UV;
        return PZ_OK;
    }
    const pz_mesh *mesh = inputs->mesh;
    inputs->face_panel = malloc(((size_t)mesh->face_count + 1) * sizeof(int32_t));
    if (!inputs->face_panel)
        return pz_error(ctx, PZ_ERR_NOMEM, "flatten: out of memory finding panels");
    out->source = PZ_PANELS_FACES;
    out->face_panel = inputs->face_panel;
    out->face_panel_name = panels;
    return pz_read_panel_file(panels, mesh->face_count, inputs->face_panel, &out->panel_count, ctx);
}

/* --seams and --darts files, in the input's (joined) vertex ids. */
static pz_status read_correspondences(const pz_cli_args *args, flatten_inputs *inputs, pz_ctx *ctx)
{
    if (args->seam_path_count + args->dart_path_count == 0)
        return PZ_OK;
    const pz_mesh *mesh = inputs->mesh;
    inputs->vertex_used = calloc((size_t)mesh->vertex_count + 1, 1);
    if (!inputs->vertex_used)
        return pz_error(ctx, PZ_ERR_NOMEM, "flatten: out of memory reading seams");
    pz_mesh_mark_used_vertices(mesh, inputs->vertex_used);
    /* Panel ids in the files: one per file when there are several; with one mesh the panels are known only
     * once the pipeline has found them, and it checks them then. */
    int32_t files = args->positional_count;
    pz_vertex_space space = {files, inputs->file_vertex_offset, inputs->vertex_used, files > 1 ? files : INT32_MAX};
    pz_correspondences *out = &inputs->correspondences;
    pz_status status = pz_read_correspondences(args->seam_paths, args->seam_path_count, args->dart_paths,
                                               args->dart_path_count, &space, out, ctx);
    pz_panels_use_correspondences(&inputs->panels, out,
                                  args->seam_path_count ? args->seam_paths[0] : args->dart_paths[0]);
    return status;
}

pz_status pz_cli_flatten(const pz_cli_args *args, pz_ctx *ctx)
{
    pz_run_options options;
    pz_status status = pz_cli_pipeline_options(args, &options, ctx);
    if (status != PZ_OK)
        return status;
    double start = pz_seconds();
    flatten_inputs inputs;
    memset(&inputs, 0, sizeof inputs);
    inputs.file_vertex_offset = calloc((size_t)args->positional_count + 1, sizeof(int32_t));
    if (!inputs.file_vertex_offset)
        status = pz_error(ctx, PZ_ERR_NOMEM, "flatten: out of memory");
    if (status == PZ_OK)
        status = pz_cli_read_meshes(args, &inputs.mesh, inputs.file_vertex_offset, ctx);
    if (status == PZ_OK)
        status = read_panels(args, &inputs, ctx);
    if (status == PZ_OK)
        status = read_correspondences(args, &inputs, ctx);
    double read_ms = pz_elapsed_ms(start, pz_seconds());
    pz_result *result = NULL;
    pz_cli_progress_begin(args, ctx);
    if (status == PZ_OK)
        status = pz_flatten(inputs.mesh, &inputs.panels, &options, &result, ctx);
    flatten_inputs_clear(&inputs);
    if (status == PZ_OK)
        status = pz_cli_write_result(args, result, read_ms, ctx);
    pz_cli_progress_end(ctx);
    pz_result_free(&result);
    return status;
}

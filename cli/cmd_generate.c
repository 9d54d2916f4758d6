/*
 * cli/cmd_generate.c -- `panelize generate SHAPE -o FILE`.
 *
 * Generates a synthetic garment or test surface with pz_generate and writes
 * it with pz_mesh_write (format by extension, each file atomic).
 *
 * Poses: a GLB carries extra poses as morph targets. OBJ and PLY hold one
 * set of positions, so pose p (1-based) goes to its own file next to FILE:
 * `bodice.obj` gets `bodice.pose1.obj`, `bodice.pose2.obj`, ... (same
 * extension as FILE), ready for `panelize info bodice.obj --pose
 * bodice.pose1.obj ...`. The set is all or nothing: the pose files are
 * written first, FILE last, and when any write fails the files this run
 * already wrote are removed again, so a failed run leaves no output at all.
 *
 * SPDX-License-Identifier: GPL-3.0-or-later
 */
#include "cli/cli.h"
#include "generate/generate.h"
#include "io/io.h"

#include <stdlib.h>
#include <string.h>

const char pz_cli_generate_usage[] =
    "usage: panelize generate SHAPE -o FILE [--faces N] [--poses K] [--open] [--json] [--quiet]\n"
    "\n"
    "Writes a synthetic shape in millimetres, faces counter-clockwise with\n"
    "normals pointing away from the body, manifold and well shaped.\n"
    "\n"
    "shapes:\n"
    "  bodice          sleeveless torso tube (bust, waist, hip); two boundary loops\n"
    "  skirt           flared skirt shaped at the hip; two boundary loops\n"
    "  sleeve          bent tube; two boundary loops\n"
    "  hemisphere      one boundary loop, positive curvature\n"
    "  quarter-sphere  one boundary loop, positive curvature\n"
    "  saddle          one boundary loop, negative curvature\n"
    "  cylinder        developable; two boundary loops, one with --open\n"
    "  cone            developable truncated cone; two loops, one with --open\n"
    "\n"
    "options:\n"
    "  -o, --output FILE  output mesh: .obj, .ply or .glb\n"
    "  --faces N          approximate face count (default 20000; 500 .. 1000000\n"
    "                     keep faces well shaped)\n"
    "  --poses K          K extra deformed poses (bending, twisting, breathing).\n"
    "                     A .glb stores them as morph targets; for .obj and .ply\n"
    "                     pose p is written to FILE-stem.poseP.EXT beside FILE\n"
    "  --open             cylinder and cone: cut along a ruling into a disk\n"
    "  --json             print {file, shape, vertices, faces, poses, pose_files}\n"
    "  --quiet            no summary line on stderr\n";

/* "dir/bodice.obj", 2 -> "dir/bodice.pose2.obj" (caller frees); NULL when out of memory. */
static char *pose_file_path(const char *path, int pose_number)
{
    const char *slash = strrchr(path, '/');
    const char *dot = strrchr(path, '.');
    if (!dot || (slash && dot < slash))
        dot = path + strlen(path);
    size_t stem_length = (size_t)(dot - path);
    size_t size = strlen(path) + 32;
    char *pose_path = malloc(size);
    if (pose_path)
        snprintf(pose_path, size, "%.*s.pose%d%s", (int)stem_length, path, pose_number, dot);
    return pose_path;
}

/* The rest-pose-only view of pose `pose_index` (-1 = rest) of `mesh`; borrows its arrays. */
static pz_mesh single_pose_view(const pz_mesh *mesh, int32_t pose_index)
{
    pz_mesh view = *mesh;
    if (pose_index >= 0)
        view.positions = mesh->poses + (size_t)pose_index * (size_t)mesh->vertex_count * 3;
    view.pose_count = 0;
    view.poses = NULL;
    return view;
}

/* Removes the first `count` paths: undoing a partly written set of outputs. */
static void remove_written(char **paths, int count)
{
    for (int i = 0; i < count; ++i)
        remove(paths[i]);
}

/*
 * Writes the mesh, and for OBJ/PLY each pose to its own file (paths filled
 * into pose_paths[0 .. pose_count-1], which the caller frees).
 */
static pz_status write_outputs(const pz_mesh *mesh, const char *path, int separate_poses, char **pose_paths,
                               pz_ctx *ctx)
{
    int pose_files = separate_poses ? mesh->pose_count : 0;
    for (int p = 0; p < pose_files; ++p) {
        pose_paths[p] = pose_file_path(path, p + 1);
        if (!pose_paths[p])
            return pz_error(ctx, PZ_ERR_NOMEM, "%s: out of memory", path);
    }
    int written = 0;
    pz_status status = PZ_OK;
    while (written < pose_files && status == PZ_OK) {
        pz_mesh view = single_pose_view(mesh, written);
        status = pz_mesh_write(&view, pose_paths[written], NULL, ctx);
        if (status == PZ_OK)
            ++written;
    }
    if (status == PZ_OK) {
        pz_mesh rest = single_pose_view(mesh, -1);
        status = pz_mesh_write(separate_poses ? &rest : mesh, path, NULL, ctx);
    }
    if (status != PZ_OK)
        remove_written(pose_paths, written);
    return status;
}

static pz_status print_summary(const pz_cli_args *args, const pz_mesh *mesh, pz_shape shape, char **pose_paths,
                               int pose_file_count, pz_ctx *ctx)
{
    const char *path = args->output_path;
    if (args->json) {
        cJSON *root = cJSON_CreateObject();
        int failed = !root;
        failed = failed || !cJSON_AddStringToObject(root, "file", path);
        failed = failed || !cJSON_AddStringToObject(root, "shape", pz_shape_name(shape));
        failed = failed || !cJSON_AddNumberToObject(root, "vertices", mesh->vertex_count);
        failed = failed || !cJSON_AddNumberToObject(root, "faces", mesh->face_count);
        failed = failed || !cJSON_AddNumberToObject(root, "poses", mesh->pose_count);
        failed = failed || !cJSON_AddItemToObject(root, "pose_files",
                                                  pose_file_count > 0
                                                      ? cJSON_CreateStringArray((const char *const *)pose_paths, pose_file_count)
                                                      : cJSON_CreateArray());
        pz_status status = pz_cli_print_json(root, failed, ctx);
        if (status != PZ_OK)
            return status;
    }
    pz_note(ctx, "wrote %s: %s, %d vertices, %d faces, %d extra poses%s", path, pz_shape_name(shape),
            (int)mesh->vertex_count, (int)mesh->face_count, (int)mesh->pose_count,
            pose_file_count > 0 ? " (in .poseN files beside it)" : "");
    return PZ_OK;
}

/* Checks the arguments before anything is generated; returns the shape through *shape. */
static pz_status check_arguments(const pz_cli_args *args, pz_shape *shape, pz_ctx *ctx)
{
    pz_status status = pz_cli_expect_positionals(args, 1, "one SHAPE", ctx);
    if (status != PZ_OK)
        return status;
    const char *name = args->positionals[0];
    *shape = pz_shape_parse(name);
    if (*shape == PZ_SHAPE_UNKNOWN)
        return pz_error(ctx, PZ_ERR_USAGE, "generate: unknown shape '%s' (see panelize generate --help)", name);
    if (args->open && *shape != PZ_SHAPE_CYLINDER && *shape != PZ_SHAPE_CONE)
        return pz_error(ctx, PZ_ERR_USAGE, "generate: --open applies to cylinder and cone only, not %s", name);
    if (!args->output_path)
        return pz_error(ctx, PZ_ERR_USAGE, "generate: -o FILE is required");
    pz_format format = pz_format_from_path(args->output_path);
    if (format != PZ_FORMAT_OBJ && format != PZ_FORMAT_PLY && format != PZ_FORMAT_GLB)
        return pz_error(ctx, PZ_ERR_USAGE, "generate: %s: cannot write this format (use .obj, .ply or .glb)",
                        args->output_path);
    return PZ_OK;
}

pz_status pz_cli_generate(const pz_cli_args *args, pz_ctx *ctx)
{
    pz_shape shape = PZ_SHAPE_UNKNOWN;
    pz_status status = check_arguments(args, &shape, ctx);
    if (status != PZ_OK)
        return status;
    pz_generate_options options = {
        .target_faces = args->target_faces, .pose_count = args->pose_count, .open = args->open};
    pz_mesh *mesh = NULL;
    status = pz_generate(shape, &options, &mesh, ctx);
    if (status != PZ_OK)
        return status;
    int separate_poses = pz_format_from_path(args->output_path) != PZ_FORMAT_GLB && mesh->pose_count > 0;
    char **pose_paths = calloc((size_t)mesh->pose_count + 1, sizeof *pose_paths);
    if (!pose_paths)
        status = pz_error(ctx, PZ_ERR_NOMEM, "%s: out of memory", args->output_path);
    if (status == PZ_OK)
        status = write_outputs(mesh, args->output_path, separate_poses, pose_paths, ctx);
    if (status == PZ_OK)
        status = print_summary(args, mesh, shape, pose_paths, separate_poses ? mesh->pose_count : 0, ctx);
    for (int32_t p = 0; pose_paths && p < mesh->pose_count; ++p)
        free(pose_paths[p]);
    free(pose_paths);
    pz_mesh_free(&mesh);
    return status;
}

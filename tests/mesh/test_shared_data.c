/*
 * tests/mesh/test_shared_data.c -- every real mesh listed in
 * ../shared/data/INVENTORY.md loads with the listed vertex, face and boundary
 * loop counts, passes validation, and has UVs exactly when it has a `vt`
 * atlas; the multipose sets load as rest + poses. Files read in place; the
 * whole test skips when PZ_SHARED_DATA is missing, and single missing files
 * are skipped and listed.
 *
 * Vertex counts are taken after pz_mesh_drop_unreferenced; none of these
 * files has unreferenced vertices today (checked: removed == 0), so the
 * INVENTORY counts are the file's own.
 *
 * SPDX-License-Identifier: GPL-3.0-or-later
 */
#define _POSIX_C_SOURCE 200809L
#include "io/io.h"
#include "mesh/mesh.h"
#include "test_util.h"

#include <string.h>
#include <sys/stat.h>

typedef struct expected_mesh {
    const char *path;       /* under PZ_SHARED_DATA */
    int32_t vertex_count, face_count, boundary_loops;
    int has_uvs;            /* the file has a complete vt atlas */
} expected_mesh;

/* From INVENTORY.md (garments/, seams/, multipose/, surfaces/). */
static const expected_mesh inventory[] = {
    {"garments/diffavatar-tshirt.obj", 2799, 5483, 4, 1},
    {"garments/diffavatar-shirt.obj", 3717, 7326, 4, 1},
    {"garments/parafashion-skirt.obj", 1417, 2762, 2, 1},
    {"garments/parafashion-dress.ply", 3918, 7574, 4, 0},
    {"garments/parafashion-leggings.ply", 3804, 7525, 3, 0},
    {"garments/parafashion-shirt.obj", 3244, 6390, 4, 0},
    {"garments/parafashion-wetsuit.obj", 1178, 2274, 5, 0},
    {"garments/shirtfront-panel.obj", 3743, 7177, 1, 0},
    {"seams/skirt_0.obj", 829, 1474, 1, 0},
    {"seams/skirt_1.obj", 829, 1474, 1, 0},
    {"multipose/jumpsuit/front1.obj", 3154, 6022, 1, 1},
    {"multipose/jumpsuit/front2.obj", 3154, 6022, 1, 1},
    {"multipose/jumpsuit/front3.obj", 3154, 6022, 1, 1},
    {"multipose/diffcloth-tshirt/tshirt1900.obj", 1921, 3726, 4, 1},
    {"multipose/diffcloth-tshirt/tshirt1900-flattened.obj", 1921, 3726, 4, 0},
    {"multipose/diffcloth-tshirt/tshirt1900-folding-biFolded.obj", 1921, 3726, 4, 0},
    {"multipose/diffcloth-tshirt/tshirt1900-folding-triFolded.obj", 1921, 3726, 4, 0},
    {"surfaces/hemisphere.obj", 2051, 4000, 1, 0},
    {"surfaces/face-scan.obj", 17157, 34144, 1, 0},
    {"surfaces/camelhead.off", 11381, 22704, 1, 0},
    {"surfaces/max-planck.obj", 4026, 7999, 1, 0},
    {"surfaces/nefertiti.off", 299, 562, 1, 0},
    {"surfaces/mannequin.off", 428, 839, 1, 0},
    {"surfaces/saddle.obj", 1089, 2048, 1, 1},
};

static char full_path[4096];

static const char *in_data(const char *data_dir, const char *relative)
{
    snprintf(full_path, sizeof full_path, "%s/%s", data_dir, relative);
    return full_path;
}

static int exists(const char *path)
{
    struct stat info;
    return stat(path, &info) == 0;
}

static int32_t count_boundary_loops(const pz_mesh *mesh, pz_ctx *ctx)
{
    pz_topology *topology = NULL;
    pz_loops *loops = NULL;
    int32_t count = -1;
    if (pz_topology_build(mesh, &topology, ctx) == PZ_OK && pz_topology_boundary_loops(topology, &loops, ctx) == PZ_OK)
        count = loops->loop_count;
    pz_loops_free(&loops);
    pz_topology_free(&topology);
    return count;
}

static void check_mesh(const char *data_dir, const expected_mesh *expected)
{
    pz_ctx ctx;
    pz_ctx_init(&ctx);
    ctx.quiet = 1;
    const char *path = in_data(data_dir, expected->path);
    pz_mesh *mesh = NULL;
    pz_status status = pz_mesh_read(path, &mesh, &ctx);
    CHECK(status == PZ_OK, "%s: %s", expected->path, ctx.error);
    if (status != PZ_OK)
        return;
    int32_t removed = -1;
    CHECK(pz_mesh_drop_unreferenced(mesh, &removed, &ctx) == PZ_OK, "%s: drop: %s", expected->path, ctx.error);
    CHECK(removed == 0, "%s: %d unreferenced vertices", expected->path, (int)removed);
    CHECK(mesh->vertex_count == expected->vertex_count, "%s: %d vertices, INVENTORY says %d", expected->path,
          mesh->vertex_count, expected->vertex_count);
    CHECK(mesh->face_count == expected->face_count, "%s: %d faces, INVENTORY says %d", expected->path,
          mesh->face_count, expected->face_count);
    CHECK((mesh->uv_count > 0) == expected->has_uvs, "%s: uv_count %d", expected->path, mesh->uv_count);
    pz_validation validation;
    memset(&validation, 0, sizeof validation);
    CHECK(pz_mesh_validate(mesh, &validation, &ctx) == PZ_OK, "%s: validate: %s", expected->path, ctx.error);
    CHECK(pz_validation_ok(&validation), "%s: not valid: %s", expected->path,
          validation.problem_count ? validation.problems[0] : "?");
    pz_validation_clear(&validation);
    int32_t loops = count_boundary_loops(mesh, &ctx);
    CHECK(loops == expected->boundary_loops, "%s: %d boundary loops, INVENTORY says %d (%s)", expected->path,
          (int)loops, expected->boundary_loops, loops < 0 ? ctx.error : "");
    pz_mesh_free(&mesh);
}

/* A multipose set: the first file is the rest pose, the others its poses. */
static void check_pose_set(const char *data_dir, const char *const *files, int file_count)
{
    char paths[4][4096];
    const char *pose_paths[3];
    for (int i = 0; i < file_count; ++i) {
        snprintf(paths[i], sizeof paths[i], "%s/%s", data_dir, files[i]);
        if (!exists(paths[i])) {
            printf("skipped pose set %s: %s missing\n", files[0], files[i]);
            return;
        }
        if (i > 0)
            pose_paths[i - 1] = paths[i];
    }
    pz_ctx ctx;
    pz_ctx_init(&ctx);
    pz_mesh *mesh = NULL;
    CHECK(pz_mesh_read_with_poses(paths[0], pose_paths, file_count - 1, &mesh, &ctx) == PZ_OK, "%s + poses: %s",
          files[0], ctx.error);
    if (!mesh)
        return;
    CHECK(mesh->pose_count == file_count - 1, "%s: %d poses", files[0], mesh->pose_count);
    /* The poses really differ from the rest pose (they are different states of the garment). */
    for (int32_t p = 0; p < mesh->pose_count; ++p) {
        const double *pose = mesh->poses + (size_t)p * 3 * (size_t)mesh->vertex_count;
        CHECK(memcmp(pose, mesh->positions, 3 * sizeof(double) * (size_t)mesh->vertex_count) != 0,
              "%s: pose %d equals the rest pose", files[0], (int)p);
    }
    pz_mesh_free(&mesh);
}

int main(void)
{
    const char *data_dir = test_shared_data();
    if (!data_dir || !exists(data_dir))
        test_skip("PZ_SHARED_DATA is not set or missing: no real meshes to check");
    int skipped = 0;
    for (size_t i = 0; i < sizeof inventory / sizeof inventory[0]; ++i) {
        if (!exists(in_data(data_dir, inventory[i].path))) {
            printf("skipped %s: not present\n", inventory[i].path);
            ++skipped;
            continue;
        }
        check_mesh(data_dir, &inventory[i]);
    }
    static const char *const jumpsuit[] = {"multipose/jumpsuit/front1.obj", "multipose/jumpsuit/front2.obj",
                                           "multipose/jumpsuit/front3.obj"};
    static const char *const tshirt[] = {"multipose/diffcloth-tshirt/tshirt1900.obj",
                                         "multipose/diffcloth-tshirt/tshirt1900-flattened.obj",
                                         "multipose/diffcloth-tshirt/tshirt1900-folding-biFolded.obj",
                                         "multipose/diffcloth-tshirt/tshirt1900-folding-triFolded.obj"};
    check_pose_set(data_dir, jumpsuit, 3);
    check_pose_set(data_dir, tshirt, 4);
    printf("%zu meshes checked, %d skipped\n", sizeof inventory / sizeof inventory[0] - (size_t)skipped, skipped);
    return test_finish();
}

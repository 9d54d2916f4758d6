/*
 * tests/io/test_io_roundtrip.c -- write -> read through files: OBJ and PLY
 * keep positions bit for bit, faces, UVs (OBJ: per corner with seams; PLY:
 * per vertex) and labels with their names; the dispatcher's format detection
 * and error paths (missing file, directory, unknown extension, unwritable
 * path, atomic output); rest + pose files.
 *
 * SPDX-License-Identifier: GPL-3.0-or-later
 */
#define _POSIX_C_SOURCE 200809L
#include "io/io.h"
#include "mesh/mesh.h"
#include "test_files.h"

#include <dirent.h>
#include <math.h>
#include <stdlib.h>
#include <string.h>
#include <sys/stat.h>
#include <unistd.h>

/* A file in the scratch directory (the name lasts until the next call). */
static const char *scratch_path(const char *file)
{
    static char path[512];
    return test_temp_path(path, sizeof path, file);
}

/*
 * A 5 x 4 vertex grid with awkward coordinates (thirds, tiny and huge values,
 * -0), corner UVs with a seam down the middle column, and three labels, one
 * of them unnamed.
 */
static pz_mesh *make_grid(int with_seams)
{
    pz_ctx ctx;
    pz_ctx_init(&ctx);
    enum { columns = 5, rows = 4 };
    pz_mesh *mesh = NULL;
    REQUIRE_OK(pz_mesh_create(columns * rows, 2 * (columns - 1) * (rows - 1), &mesh, &ctx), ctx);
    for (int r = 0; r < rows; ++r)
        for (int c = 0; c < columns; ++c) {
            double *p = mesh->positions + 3 * (r * columns + c);
            p[0] = c / 3.0 + 1e-17 * r;
            p[1] = r * 0.1 + sin(c * r);
            p[2] = c == 0 ? -0.0 : r == 1 ? 1e300 / (c + 7) : exp(-40.0 * c);
        }
    int32_t f = 0;
    for (int r = 0; r + 1 < rows; ++r)
        for (int c = 0; c + 1 < columns; ++c) {
            int32_t a = r * columns + c, b = a + 1, d = a + columns, e = d + 1;
            int32_t quad[6] = {a, b, e, a, e, d};
            memcpy(mesh->faces + 3 * f, quad, sizeof quad);
            f += 2;
        }
    /* UVs: one per vertex, plus a second copy of the middle column's for the seam. */
    mesh->uv_count = columns * rows + (with_seams ? rows : 0);
    mesh->uvs = malloc(sizeof(double) * 2 * (size_t)mesh->uv_count);
    mesh->corner_uvs = malloc(sizeof(int32_t) * 3 * (size_t)mesh->face_count);
    REQUIRE(mesh->uvs && mesh->corner_uvs, "malloc");
    for (int v = 0; v < columns * rows; ++v) {
        mesh->uvs[2 * v] = (v % columns) / 4.0 + 0.1;
        mesh->uvs[2 * v + 1] = (v / columns) / 3.0;
    }
    for (int r = 0; with_seams && r < rows; ++r) {
        mesh->uvs[2 * (columns * rows + r)] = 2.0 + 1.0 / 7.0;
        mesh->uvs[2 * (columns * rows + r) + 1] = r / 3.0;
    }
    for (int32_t corner = 0; corner < 3 * mesh->face_count; ++corner) {
        int32_t v = mesh->faces[corner];
        int right_of_seam = (corner / 3) % 8 >= 4; /* faces of columns 2 and 3 */
        mesh->corner_uvs[corner] = with_seams && v % columns == 2 && right_of_seam ? columns * rows + v / columns : v;
    }
    mesh->label_count = 3;
    mesh->face_labels = malloc(sizeof(int32_t) * (size_t)mesh->face_count);
    mesh->label_names = calloc(3, sizeof(char *));
    REQUIRE(mesh->face_labels && mesh->label_names, "malloc");
    for (int32_t face = 0; face < mesh->face_count; ++face)
        mesh->face_labels[face] = face < 6 ? 0 : face < 14 ? 2 : face < 18 ? 1 : 0;
    mesh->label_names[0] = test_strdup("front");
    mesh->label_names[2] = test_strdup("sleeve left");
    return mesh;
}

static pz_mesh *read_back(const char *path)
{
    pz_ctx ctx;
    pz_ctx_init(&ctx);
    pz_mesh *mesh = NULL;
    CHECK(pz_mesh_read(path, &mesh, &ctx) == PZ_OK, "reading back %s: %s", path, ctx.error);
    return mesh;
}

static void write_ok(const pz_mesh *mesh, const char *path)
{
    pz_ctx ctx;
    pz_ctx_init(&ctx);
    ctx.quiet = 1;
    CHECK(pz_mesh_write(mesh, path, NULL, &ctx) == PZ_OK, "writing %s: %s", path, ctx.error);
}

static void check_same_geometry(const pz_mesh *a, const pz_mesh *b, const char *what)
{
    REQUIRE(a->vertex_count == b->vertex_count && a->face_count == b->face_count, "%s: counts", what);
    CHECK(memcmp(a->positions, b->positions, sizeof(double) * 3 * (size_t)a->vertex_count) == 0,
          "%s: positions not bit-identical", what);
    CHECK(memcmp(a->faces, b->faces, sizeof(int32_t) * 3 * (size_t)a->face_count) == 0, "%s: faces", what);
}

/* The UV of every corner is the same value (indices may differ). */
static void check_same_corner_uvs(const pz_mesh *a, const pz_mesh *b, const char *what)
{
    REQUIRE(b->uvs != NULL && b->corner_uvs != NULL, "%s: UVs lost", what);
    int differences = 0;
    for (int32_t corner = 0; corner < 3 * a->face_count; ++corner) {
        const double *x = a->uvs + 2 * a->corner_uvs[corner], *y = b->uvs + 2 * b->corner_uvs[corner];
        differences += x[0] != y[0] || x[1] != y[1];
    }
    CHECK(differences == 0, "%s: %d corner UVs differ", what, differences);
}

static void check_same_labels(const pz_mesh *a, const pz_mesh *b, const char *what)
{
    REQUIRE(b->face_labels != NULL, "%s: labels lost", what);
    CHECK(b->label_count == a->label_count, "%s: label_count %d", what, b->label_count);
    CHECK(memcmp(a->face_labels, b->face_labels, sizeof(int32_t) * (size_t)a->face_count) == 0, "%s: face labels",
          what);
    REQUIRE(b->label_names != NULL, "%s: names lost", what);
    CHECK(b->label_names[0] && strcmp(b->label_names[0], "front") == 0, "%s: name 0", what);
    CHECK(b->label_names[2] && strcmp(b->label_names[2], "sleeve left") == 0, "%s: name 2", what);
}

static void test_obj_roundtrip(void)
{
    pz_mesh *mesh = make_grid(1);
    write_ok(mesh, scratch_path("grid.obj"));
    pz_mesh *back = read_back(scratch_path("grid.obj"));
    if (back) {
        check_same_geometry(mesh, back, "obj");
        check_same_corner_uvs(mesh, back, "obj");
        CHECK(back->uv_count == mesh->uv_count, "obj: uv_count %d", back->uv_count);
        check_same_labels(mesh, back, "obj");
        CHECK(back->label_names[1] && strcmp(back->label_names[1], "label_1") == 0, "obj: unnamed label");
        CHECK(back->pose_count == 0, "obj: no poses");
    }
    pz_mesh_free(&back);
    /* Without UVs and labels: `f a b c` and no groups. */
    free(mesh->uvs), free(mesh->corner_uvs), free(mesh->face_labels);
    for (int i = 0; i < 3; ++i)
        free(mesh->label_names[i]);
    free(mesh->label_names);
    mesh->uvs = NULL, mesh->corner_uvs = NULL, mesh->face_labels = NULL, mesh->label_names = NULL;
    mesh->uv_count = mesh->label_count = 0;
    write_ok(mesh, scratch_path("plain.OBJ"));
    back = read_back(scratch_path("plain.OBJ"));
    if (back) {
        check_same_geometry(mesh, back, "plain obj");
        CHECK(back->uvs == NULL && back->face_labels == NULL, "plain obj: nothing extra");
    }
    pz_mesh_free(&back);
    pz_mesh_free(&mesh);
}

static void test_ply_roundtrip(void)
{
    pz_mesh *mesh = make_grid(0);
    write_ok(mesh, scratch_path("grid.ply"));
    pz_mesh *back = read_back(scratch_path("grid.ply"));
    if (back) {
        check_same_geometry(mesh, back, "ply");
        check_same_corner_uvs(mesh, back, "ply");
        check_same_labels(mesh, back, "ply");
        CHECK(back->label_names[1] == NULL, "ply: unnamed label stays unnamed");
    }
    pz_mesh_free(&back);
    pz_mesh_free(&mesh);

    /* UV seams cannot be stored per vertex: the UVs are dropped, the rest survives. */
    mesh = make_grid(1);
    write_ok(mesh, scratch_path("seams.ply"));
    back = read_back(scratch_path("seams.ply"));
    if (back) {
        check_same_geometry(mesh, back, "ply with seams");
        CHECK(back->uvs == NULL, "ply with seams: UVs dropped");
        check_same_labels(mesh, back, "ply with seams");
    }
    pz_mesh_free(&back);
    pz_mesh_free(&mesh);
}

static int count_files_in_scratch(void)
{
    DIR *dir = opendir(test_temp_dir);
    int count = 0;
    for (struct dirent *entry; dir && (entry = readdir(dir));)
        count += entry->d_name[0] != '.';
    if (dir)
        closedir(dir);
    return count;
}

static void expect_error(pz_status status, pz_status expected, const pz_ctx *ctx, const char *needle)
{
    CHECK(status == expected, "status %d, expected %d (%s)", (int)status, (int)expected, ctx->error);
    CHECK(strstr(ctx->error, needle) != NULL, "message '%s' lacks '%s'", ctx->error, needle);
}

static void test_dispatch_errors(void)
{
    CHECK(pz_format_from_path("a/b.c/mesh.Obj") == PZ_FORMAT_OBJ, "obj");
    CHECK(pz_format_from_path("x.PLY") == PZ_FORMAT_PLY, "ply");
    CHECK(pz_format_from_path("x.off") == PZ_FORMAT_OFF, "off");
    CHECK(pz_format_from_path("x.glb") == PZ_FORMAT_GLB, "glb");
    CHECK(pz_format_from_path("x.GLTF") == PZ_FORMAT_GLTF, "gltf");
    CHECK(pz_format_from_path("dir.obj/file") == PZ_FORMAT_UNKNOWN, "dot in a directory");
    CHECK(pz_format_from_path("x.objx") == PZ_FORMAT_UNKNOWN && pz_format_from_path("obj") == PZ_FORMAT_UNKNOWN,
          "no such extension");

    pz_ctx ctx;
    pz_ctx_init(&ctx);
    pz_mesh *mesh = (pz_mesh *)&ctx, *dummy = NULL;
    const char *missing = scratch_path("missing.obj");
    expect_error(pz_mesh_read(missing, &mesh, &ctx), PZ_ERR_OPEN, &ctx, "missing.obj: cannot open: ");
    CHECK(mesh == NULL, "*out NULL");
    char directory[512];
    test_temp_path(directory, sizeof directory, "folder.obj");
    int made = mkdir(directory, 0700);
    REQUIRE(made == 0, "mkdir");
    expect_error(pz_mesh_read(directory, &mesh, &ctx), PZ_ERR_OPEN, &ctx, "folder.obj: cannot open: Is a directory");
    expect_error(pz_mesh_read(scratch_path("mesh.stl"), &mesh, &ctx), PZ_ERR_DATA, &ctx,
                 "mesh.stl: unknown format (expected .obj, .ply, .off, .glb, .gltf)");
    test_write_file(scratch_path("empty.ply"), "", 0);
    expect_error(pz_mesh_read(scratch_path("empty.ply"), &mesh, &ctx), PZ_ERR_DATA, &ctx, "empty.ply: ");

    int files_before = count_files_in_scratch();
    dummy = make_grid(0);
    expect_error(pz_mesh_write(dummy, scratch_path("out.stl"), NULL, &ctx), PZ_ERR_USAGE, &ctx, "out.stl: ");
    expect_error(pz_mesh_write(dummy, scratch_path("out.off"), NULL, &ctx), PZ_ERR_USAGE, &ctx, "out.off: ");
    expect_error(pz_mesh_write(dummy, scratch_path("no/such/dir/out.obj"), NULL, &ctx), PZ_ERR_CREATE, &ctx,
                 "no/such/dir/out.obj: cannot create");
    CHECK(count_files_in_scratch() == files_before, "failed writes leave no file behind");
    pz_mesh_free(&dummy);
}

static void write_text(const char *path, const char *text)
{
    test_write_file(path, text, strlen(text));
}

static void test_poses(void)
{
    write_text(scratch_path("rest.obj"), "v 0 0 0\nv 1 0 0\nv 0 1 0\nv 1 1 0\nf 1 2 3\nf 2 4 3\n");
    write_text(scratch_path("pose1.obj"), "v 0 0 1\nv 1 0 1\nv 0 1 1\nv 1 1 2\nf 1 2 3\nf 2 4 3\n");
    write_text(scratch_path("pose2.off"), "OFF\n4 2 0\n0 0 5\n1 0 5\n0 1 5\n1 1 5\n3 0 1 2\n3 1 3 2\n");
    write_text(scratch_path("fewer.obj"), "v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 3\n");
    write_text(scratch_path("other.obj"), "v 0 0 0\nv 1 0 0\nv 0 1 0\nv 1 1 0\nf 1 2 3\nf 2 3 4\n");
    pz_ctx ctx;
    pz_ctx_init(&ctx);
    char rest[512], pose1[512], pose2[512], fewer[512], other[512];
    test_temp_path(rest, sizeof rest, "rest.obj");
    test_temp_path(pose1, sizeof pose1, "pose1.obj");
    test_temp_path(pose2, sizeof pose2, "pose2.off");
    test_temp_path(fewer, sizeof fewer, "fewer.obj");
    test_temp_path(other, sizeof other, "other.obj");
    const char *poses[2] = {pose1, pose2};
    pz_mesh *mesh = NULL;
    CHECK(pz_mesh_read_with_poses(rest, poses, 2, &mesh, &ctx) == PZ_OK, "poses: %s", ctx.error);
    if (mesh) {
        CHECK(mesh->pose_count == 2 && mesh->poses, "two poses");
        CHECK(mesh->positions[11] == 0 && mesh->poses[11] == 2 && mesh->poses[12 + 11] == 5, "pose positions");
        pz_mesh_free(&mesh);
    }
    const char *bad[1] = {fewer};
    mesh = (pz_mesh *)&ctx;
    expect_error(pz_mesh_read_with_poses(rest, bad, 1, &mesh, &ctx), PZ_ERR_DATA, &ctx,
                 "fewer.obj: does not match ");
    CHECK(strstr(ctx.error, "rest.obj: 3 vertices, expected 4") != NULL, "names both files: %s", ctx.error);
    CHECK(mesh == NULL, "*out NULL");
    bad[0] = other;
    expect_error(pz_mesh_read_with_poses(rest, bad, 1, &mesh, &ctx), PZ_ERR_DATA, &ctx, "rest.obj: face 1 differs");
    bad[0] = scratch_path("absent.obj");
    expect_error(pz_mesh_read_with_poses(rest, bad, 1, &mesh, &ctx), PZ_ERR_OPEN, &ctx, "absent.obj: cannot open");
}

int main(void)
{
    test_temp_dir_create("pz_io_roundtrip");
    test_obj_roundtrip();
    test_ply_roundtrip();
    test_dispatch_errors();
    test_poses();
    CHECK(test_temp_dir_remove() == 0, "cleanup: cannot remove %s", test_temp_dir);
    return test_finish();
}

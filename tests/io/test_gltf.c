/*
 * tests/io/test_gltf.c -- glTF reading and GLB writing (io/gltf_read.cpp, io/gltf_write.cpp).
 *
 *  - A grid with a UV seam, two labels, two poses and an unreferenced vertex
 *    survives GLB write -> read: counts, face indices (through _PZ_VERTEX_ID),
 *    positions and poses to float precision, corner UVs and their seam
 *    structure, labels and their names; a plain mesh stays unlabelled.
 *  - The written JSON follows the rules the Khronos validator checks (aligned
 *    views with targets, POSITION min/max, targets, materials, extras).
 *  - A GLB built here by hand: node transforms through the hierarchy (TRS and
 *    matrix), a mirroring node reverses the winding, a triangle strip with
 *    ubyte indices, a sparse morph target without a bufferView, an unused
 *    mesh ignored.
 *  - Failures: garbage, truncated GLB, a BIN chunk longer than the file,
 *    accessors and views out of bounds, an index out of range, mismatched
 *    morph target counts, a node cycle, deeply nested JSON, external files
 *    with no base_dir or outside it -> PZ_ERR_DATA naming the input.
 *  - OBJ -> GLB -> OBJ through pz_mesh_read / pz_mesh_write keeps counts and
 *    indices exactly.
 *  - The palette (12 distinct opaque colours, wrapping) and the sRGB ->
 *    linear conversion of both curve segments.
 * With PZ_GLB_OUT set, the GLBs are also left in that directory for
 * tests/io/test_gltf_validator.sh.
 *
 * SPDX-License-Identifier: GPL-3.0-or-later
 */
#define _POSIX_C_SOURCE 200809L
#include "io/io.h"
#include "mesh/mesh.h"
#include "test_files.h"

#include <cjson/cJSON.h>
#include <math.h>
#include <stdint.h>
#include <stdlib.h>
#include <string.h>
#include <sys/stat.h>
#include <unistd.h>

static int close_to(double a, double b)
{
    /* float32 in the file: about 6e-8 relative, twice for poses */
    return fabs(a - b) <= 1e-6 * (1.0 + fabs(a));
}

/* ------------------------------------------------------------------ */
/* The grid fixture                                                   */
/* ------------------------------------------------------------------ */

enum { GRID_X = 6, GRID_Y = 4 };

static int32_t grid_vertex(int i, int j)
{
    return j * (GRID_X + 1) + i;
}

/*
 * (GRID_X x GRID_Y) quads in mm, away from the origin, plus one unreferenced
 * vertex. Columns 0..2 are label 0 "front", 3..5 label 1 "back" (the labels
 * alternate along each row), label 2 is empty; each half has its own UV
 * island, so column 3 is a UV seam.
 */
static pz_mesh *make_grid(int with_uvs, int with_labels, int with_poses)
{
    pz_ctx ctx = {0};
    pz_mesh *mesh = NULL;
    int32_t grid_vertices = (GRID_X + 1) * (GRID_Y + 1);
    REQUIRE_OK(pz_mesh_create(grid_vertices + 1, 2 * GRID_X * GRID_Y, &mesh, &ctx), ctx);
    for (int j = 0; j <= GRID_Y; ++j)
        for (int i = 0; i <= GRID_X; ++i) {
            double *p = &mesh->positions[3 * grid_vertex(i, j)];
            p[0] = 250.0 + 10.5 * i;
            p[1] = -40.0 + 7.25 * j;
            p[2] = 1000.0 + 0.3 * i * j;
        }
    double *extra = &mesh->positions[3 * grid_vertices];
    extra[0] = 1.0, extra[1] = 2.0, extra[2] = 3.0;
    if (with_uvs) {
        mesh->uv_count = 2 * 4 * (GRID_Y + 1);
        mesh->uvs = calloc((size_t)mesh->uv_count * 2, sizeof(double));
        mesh->corner_uvs = calloc((size_t)mesh->face_count * 3, sizeof(int32_t));
    }
    if (with_labels) {
        /* Label 2 has no faces and no name: it must survive anyway. */
        mesh->label_count = 3;
        mesh->face_labels = calloc((size_t)mesh->face_count, sizeof(int32_t));
        mesh->label_names = calloc(3, sizeof(char *));
        mesh->label_names[0] = test_strdup("front");
        mesh->label_names[1] = test_strdup("back");
    }
    /* UV index of (i, j) in island `half`: 4 columns x (GRID_Y + 1) rows each. */
    for (int half = 0; with_uvs && half < 2; ++half)
        for (int j = 0; j <= GRID_Y; ++j)
            for (int c = 0; c < 4; ++c) {
                int32_t uv = half * 4 * (GRID_Y + 1) + j * 4 + c;
                mesh->uvs[2 * uv] = 0.1 * c + 0.5 * half;
                mesh->uvs[2 * uv + 1] = 0.2 * j + 0.05;
            }
    int32_t f = 0;
    for (int j = 0; j < GRID_Y; ++j)
        for (int i = 0; i < GRID_X; ++i) {
            int half = i >= 3;
            int32_t quad[4] = {grid_vertex(i, j), grid_vertex(i + 1, j), grid_vertex(i + 1, j + 1),
                               grid_vertex(i, j + 1)};
            int32_t quad_uv[4];
            int column = i - 3 * half;
            quad_uv[0] = half * 4 * (GRID_Y + 1) + j * 4 + column;
            quad_uv[1] = quad_uv[0] + 1;
            quad_uv[2] = quad_uv[0] + 5;
            quad_uv[3] = quad_uv[0] + 4;
            static const int split[2][3] = {{0, 1, 2}, {0, 2, 3}};
            for (int t = 0; t < 2; ++t, ++f) {
                for (int k = 0; k < 3; ++k) {
                    mesh->faces[3 * f + k] = quad[split[t][k]];
                    if (with_uvs)
                        mesh->corner_uvs[3 * f + k] = quad_uv[split[t][k]];
                }
                if (with_labels)
                    mesh->face_labels[f] = half;
            }
        }
    if (with_poses) {
        double *pose = malloc((size_t)mesh->vertex_count * 3 * sizeof(double));
        for (int p = 0; p < 2; ++p) {
            for (int32_t v = 0; v < mesh->vertex_count; ++v) {
                const double *rest = &mesh->positions[3 * v];
                pose[3 * v] = rest[0] + (p ? 3.0 * sin(0.1 * v) : 0.0);
                pose[3 * v + 1] = rest[1] - 0.25 * v * p;
                pose[3 * v + 2] = rest[2] + 0.5 * (v % 7) + 12.0 * p;
            }
            REQUIRE_OK(pz_mesh_add_pose(mesh, pose, &ctx), ctx);
        }
        free(pose);
    }
    return mesh;
}

/* Reads a GLB the way pz_mesh_read would, but through the memory entry point. */
static pz_status read_glb(const char *path, pz_mesh **out, pz_ctx *ctx)
{
    size_t size = 0;
    unsigned char *data = test_read_file(path, &size);
    REQUIRE(data, "cannot read back %s", path);
    pz_status status = pz_gltf_read_memory(data, size, 1, NULL, path, out, ctx);
    free(data);
    return status;
}

static void check_same_geometry(const pz_mesh *expected, const pz_mesh *got, const char *what)
{
    REQUIRE(got->vertex_count == expected->vertex_count, "%s: %d vertices, expected %d", what,
            (int)got->vertex_count, (int)expected->vertex_count);
    REQUIRE(got->face_count == expected->face_count, "%s: %d faces, expected %d", what, (int)got->face_count,
            (int)expected->face_count);
    CHECK(memcmp(got->faces, expected->faces, sizeof(int32_t) * 3 * (size_t)got->face_count) == 0,
          "%s: face indices differ", what);
    int far = 0;
    for (int32_t i = 0; i < 3 * got->vertex_count; ++i)
        far += !close_to(expected->positions[i], got->positions[i]);
    CHECK(far == 0, "%s: %d coordinates differ beyond float precision", what, far);
}

static void check_grid_round_trip(const pz_mesh *grid, const pz_mesh *got)
{
    check_same_geometry(grid, got, "grid");

    /* UVs: same values per corner; same seam structure (bijection of UV indices). */
    REQUIRE(got->corner_uvs && got->uvs, "UVs lost");
    CHECK(got->uv_count == grid->uv_count, "%d UVs, expected %d", (int)got->uv_count, (int)grid->uv_count);
    int32_t *seen = malloc(sizeof(int32_t) * (size_t)grid->uv_count);
    for (int32_t i = 0; i < grid->uv_count; ++i)
        seen[i] = -1;
    int value_mismatch = 0, structure_mismatch = 0;
    for (int32_t c = 0; c < 3 * grid->face_count; ++c) {
        int32_t a = grid->corner_uvs[c], b = got->corner_uvs[c];
        REQUIRE(b >= 0 && b < got->uv_count, "corner %d has UV index %d", (int)c, (int)b);
        value_mismatch += !close_to(grid->uvs[2 * a], got->uvs[2 * b]) ||
                          !close_to(grid->uvs[2 * a + 1], got->uvs[2 * b + 1]);
        if (seen[a] < 0)
            seen[a] = b;
        structure_mismatch += seen[a] != b;
    }
    free(seen);
    CHECK(value_mismatch == 0, "%d corner UVs differ", value_mismatch);
    CHECK(structure_mismatch == 0, "%d corners split from their UV", structure_mismatch);

    REQUIRE(got->face_labels && got->label_count == 3, "labels: %d, expected 3", (int)got->label_count);
    CHECK(got->label_names[2] == NULL, "unnamed empty label got the name '%s'", got->label_names[2]);
    CHECK(memcmp(got->face_labels, grid->face_labels, sizeof(int32_t) * (size_t)grid->face_count) == 0,
          "face labels differ");
    CHECK(got->label_names && got->label_names[0] && strcmp(got->label_names[0], "front") == 0, "label 0 name");
    CHECK(got->label_names && got->label_names[1] && strcmp(got->label_names[1], "back") == 0, "label 1 name");

    REQUIRE(got->pose_count == 2 && got->poses, "%d poses, expected 2", (int)got->pose_count);
    int far = 0;
    for (int32_t i = 0; i < 2 * 3 * grid->vertex_count; ++i)
        far += !close_to(grid->poses[i], got->poses[i]);
    CHECK(far == 0, "%d pose coordinates differ", far);
}

/* The JSON chunk of a GLB file, parsed. */
static cJSON *glb_json(const char *path)
{
    size_t size = 0;
    unsigned char *data = test_read_file(path, &size);
    REQUIRE(data && size >= 20 && memcmp(data, "glTF", 4) == 0, "%s is not a GLB", path);
    uint32_t length, json_length;
    memcpy(&length, data + 8, 4);
    memcpy(&json_length, data + 12, 4);
    CHECK(length == size, "GLB length %u, file %zu", (unsigned)length, size);
    CHECK(json_length % 4 == 0, "JSON chunk not padded");
    cJSON *json = cJSON_ParseWithLength((const char *)data + 20, json_length);
    free(data);
    REQUIRE(json, "%s: JSON chunk does not parse", path);
    return json;
}

static int accessor_has_bounds(const cJSON *accessors, int index, int components)
{
    const cJSON *accessor = cJSON_GetArrayItem(accessors, index);
    const cJSON *min = cJSON_GetObjectItem(accessor, "min"), *max = cJSON_GetObjectItem(accessor, "max");
    return cJSON_GetArraySize(min) == components && cJSON_GetArraySize(max) == components;
}

/* The target of the buffer view under accessor `index` (0 when it has none). */
static int view_target(const cJSON *json, int index)
{
    const cJSON *accessor = cJSON_GetArrayItem(cJSON_GetObjectItem(json, "accessors"), index);
    const cJSON *view_index = cJSON_GetObjectItem(accessor, "bufferView");
    if (!view_index)
        return 0;
    const cJSON *view = cJSON_GetArrayItem(cJSON_GetObjectItem(json, "bufferViews"), view_index->valueint);
    const cJSON *target = cJSON_GetObjectItem(view, "target");
    return target ? target->valueint : 0;
}

/* The rules of the glTF spec the Khronos validator would otherwise be needed for. */
static void check_glb_structure(const char *path)
{
    cJSON *json = glb_json(path);
    const cJSON *asset = cJSON_GetObjectItem(json, "asset");
    CHECK(cJSON_IsString(cJSON_GetObjectItem(asset, "generator")) &&
              strcmp(cJSON_GetObjectItem(asset, "generator")->valuestring, "panelize " PZ_VERSION_STRING) == 0,
          "asset.generator");
    const cJSON *extras = cJSON_GetObjectItem(asset, "extras");
    CHECK(cJSON_IsString(cJSON_GetObjectItem(extras, "garment")) &&
              strcmp(cJSON_GetObjectItem(extras, "garment")->valuestring, "grid") == 0,
          "asset.extras.garment missing");
    CHECK(cJSON_GetArraySize(cJSON_GetObjectItem(extras, "sizes")) == 3, "asset.extras.sizes");
    CHECK(cJSON_IsNumber(cJSON_GetObjectItem(extras, "big")) &&
              cJSON_GetObjectItem(extras, "big")->valuedouble == 12345678901.0,
          "asset.extras.big beyond int32 not kept");

    const cJSON *view;
    int bad_views = 0;
    cJSON_ArrayForEach(view, cJSON_GetObjectItem(json, "bufferViews")) {
        const cJSON *offset = cJSON_GetObjectItem(view, "byteOffset");
        const cJSON *target = cJSON_GetObjectItem(view, "target");
        bad_views += (offset && (long)offset->valuedouble % 4 != 0) || cJSON_GetObjectItem(view, "byteStride") ||
                     (target && target->valueint != 34962 && target->valueint != 34963);
    }
    CHECK(bad_views == 0, "%d buffer views unaligned, strided or with a bad target", bad_views);

    const cJSON *accessors = cJSON_GetObjectItem(json, "accessors");
    const cJSON *meshes = cJSON_GetObjectItem(json, "meshes");
    REQUIRE(cJSON_GetArraySize(meshes) == 1, "one mesh expected");
    const cJSON *mesh = cJSON_GetArrayItem(meshes, 0);
    const cJSON *primitives = cJSON_GetObjectItem(mesh, "primitives");
    CHECK(cJSON_GetArraySize(primitives) == 2, "%d primitives, expected 2", cJSON_GetArraySize(primitives));
    CHECK(cJSON_GetArraySize(cJSON_GetObjectItem(cJSON_GetObjectItem(mesh, "extras"), "targetNames")) == 2,
          "mesh.extras.targetNames");
    CHECK(cJSON_GetArraySize(cJSON_GetObjectItem(cJSON_GetObjectItem(mesh, "extras"), "pzLabelNames")) == 3,
          "mesh.extras.pzLabelNames");
    const cJSON *primitive;
    cJSON_ArrayForEach(primitive, primitives) {
        const cJSON *attributes = cJSON_GetObjectItem(primitive, "attributes");
        const cJSON *position = cJSON_GetObjectItem(attributes, "POSITION");
        REQUIRE(position, "primitive without POSITION");
        CHECK(accessor_has_bounds(accessors, position->valueint, 3), "POSITION without min/max");
        CHECK(cJSON_GetObjectItem(attributes, "NORMAL"), "no NORMAL");
        CHECK(cJSON_GetObjectItem(attributes, "TEXCOORD_0"), "no TEXCOORD_0");
        CHECK(cJSON_GetObjectItem(attributes, "_PZ_VERTEX_ID"), "no _PZ_VERTEX_ID");
        CHECK(cJSON_GetObjectItem(primitive, "material"), "no material");
        CHECK(view_target(json, position->valueint) == 34962, "POSITION view target not ARRAY_BUFFER");
        const cJSON *indices = cJSON_GetObjectItem(primitive, "indices");
        CHECK(indices && view_target(json, indices->valueint) == 34963, "indices view target not ELEMENT_ARRAY_BUFFER");
        /* The grid's labels interleave: the original face order travels in pzFaceIds. */
        CHECK(cJSON_IsNumber(cJSON_GetObjectItem(cJSON_GetObjectItem(primitive, "extras"), "pzFaceIds")),
              "no pzFaceIds for interleaved labels");
        CHECK(indices && cJSON_GetObjectItem(cJSON_GetArrayItem(accessors, indices->valueint), "componentType")
                                 ->valueint == 5125,
              "indices are not UNSIGNED_INT");
        const cJSON *targets = cJSON_GetObjectItem(primitive, "targets");
        CHECK(cJSON_GetArraySize(targets) == 2, "%d targets", cJSON_GetArraySize(targets));
        const cJSON *target;
        cJSON_ArrayForEach(target, targets) {
            const cJSON *displacement = cJSON_GetObjectItem(target, "POSITION");
            CHECK(displacement && accessor_has_bounds(accessors, displacement->valueint, 3),
                  "target POSITION without min/max");
        }
    }

    /* Custom colours: opaque red, half-transparent green (stored linear; 0x80 alpha = 0.502). */
    const cJSON *materials = cJSON_GetObjectItem(json, "materials");
    REQUIRE(cJSON_GetArraySize(materials) == 2, "two materials expected");
    const cJSON *front = cJSON_GetArrayItem(materials, 0), *back = cJSON_GetArrayItem(materials, 1);
    CHECK(strcmp(cJSON_GetObjectItem(front, "name")->valuestring, "front") == 0, "material 0 name");
    const cJSON *red = cJSON_GetObjectItem(cJSON_GetObjectItem(front, "pbrMetallicRoughness"), "baseColorFactor");
    const cJSON *green = cJSON_GetObjectItem(cJSON_GetObjectItem(back, "pbrMetallicRoughness"), "baseColorFactor");
    CHECK(cJSON_GetArraySize(red) == 4 && cJSON_GetArrayItem(red, 0)->valuedouble == 1.0 &&
              cJSON_GetArrayItem(red, 1)->valuedouble == 0.0 && cJSON_GetArrayItem(red, 3)->valuedouble == 1.0,
          "front colour is not red");
    CHECK(cJSON_GetArraySize(green) == 4 && cJSON_GetArrayItem(green, 1)->valuedouble == 1.0 &&
              fabs(cJSON_GetArrayItem(green, 3)->valuedouble - 128.0 / 255.0) < 1e-9,
          "back colour is not half-transparent green");
    CHECK(cJSON_GetObjectItem(back, "alphaMode") &&
              strcmp(cJSON_GetObjectItem(back, "alphaMode")->valuestring, "BLEND") == 0,
          "transparent material not BLEND");
    cJSON_Delete(json);
}

static void test_grid_round_trip(void)
{
    pz_ctx ctx = {0};
    pz_mesh *grid = make_grid(1, 1, 1);
    char path[512];
    test_temp_path(path, sizeof path, "grid.glb");
    const uint32_t colours[2] = {0xff0000ffu, 0x00ff0080u};
    pz_write_options options = {0};
    options.label_colors = colours;
    options.extras_json = "{\"garment\": \"grid\", \"sizes\": [1, 2.5, \"M\"], \"big\": 12345678901}";
    CHECK(pz_glb_write(grid, path, &options, &ctx) == PZ_OK, "write: %s", ctx.error);

    pz_mesh *got = NULL;
    REQUIRE_OK(read_glb(path, &got, &ctx), ctx);
    check_grid_round_trip(grid, got);
    check_glb_structure(path);
    pz_mesh_free(&got);

    /* No temporary left beside the output. */
    char tmp_name[600];
    snprintf(tmp_name, sizeof tmp_name, "%s.tmp-%ld", path, (long)getpid());
    CHECK(access(tmp_name, F_OK) != 0, "temporary %s left behind", tmp_name);

    /* Metadata that is not an object is refused, and nothing is written. */
    options.extras_json = "[1, 2";
    test_temp_path(path, sizeof path, "bad_extras.glb");
    CHECK(pz_glb_write(grid, path, &options, &ctx) == PZ_ERR_USAGE, "bad extras accepted");
    CHECK(strstr(ctx.error, "bad_extras.glb") != NULL, "message without the path: %s", ctx.error);
    CHECK(access(path, F_OK) != 0, "file written despite the error");

    /* Poses can be left out. */
    options.extras_json = NULL;
    options.write_poses = -1;
    test_temp_path(path, sizeof path, "no_poses.glb");
    CHECK(pz_glb_write(grid, path, &options, &ctx) == PZ_OK, "%s", ctx.error);
    REQUIRE_OK(read_glb(path, &got, &ctx), ctx);
    CHECK(got->pose_count == 0 && got->poses == NULL, "poses written despite write_poses < 0");
    pz_mesh_free(&got);

    /* A face pointing outside the vertices is refused. */
    grid->faces[5] = grid->vertex_count;
    test_temp_path(path, sizeof path, "bad_face.glb");
    CHECK(pz_glb_write(grid, path, NULL, &ctx) == PZ_ERR_INVALID_MESH, "bad face accepted");
    pz_mesh_free(&grid);
}

static void test_plain_round_trip(void)
{
    pz_ctx ctx = {0};
    pz_mesh *plain = make_grid(0, 0, 0);
    char path[512];
    test_temp_path(path, sizeof path, "plain.glb");
    CHECK(pz_glb_write(plain, path, NULL, &ctx) == PZ_OK, "write: %s", ctx.error);
    pz_mesh *got = NULL;
    REQUIRE_OK(read_glb(path, &got, &ctx), ctx);
    check_same_geometry(plain, got, "plain");
    CHECK(got->face_labels == NULL && got->label_count == 0, "an unlabelled mesh came back with %d labels",
          (int)got->label_count);
    CHECK(got->uv_count == 0 && got->corner_uvs == NULL, "UVs appeared");
    CHECK(got->pose_count == 0, "poses appeared");
    pz_mesh_free(&got);
    pz_mesh_free(&plain);
}

/* ------------------------------------------------------------------ */
/* Hand-built files                                                   */
/* ------------------------------------------------------------------ */

/* A GLB container around `json` and `bin` (both padded as the spec wants). */
static unsigned char *make_glb(const char *json, const void *bin, size_t bin_size, size_t *out_size)
{
    size_t json_length = strlen(json), json_padded = (json_length + 3) & ~(size_t)3;
    size_t bin_padded = (bin_size + 3) & ~(size_t)3;
    size_t total = 12 + 8 + json_padded + (bin_size ? 8 + bin_padded : 0);
    unsigned char *data = calloc(1, total);
    uint32_t header[5] = {0x46546c67u, 2, (uint32_t)total, (uint32_t)json_padded, 0x4e4f534au};
    memcpy(data, header, sizeof header);
    memcpy(data + 20, json, json_length);
    memset(data + 20 + json_length, ' ', json_padded - json_length);
    if (bin_size) {
        uint32_t chunk[2] = {(uint32_t)bin_padded, 0x004e4942u};
        memcpy(data + 20 + json_padded, chunk, sizeof chunk);
        memcpy(data + 28 + json_padded, bin, bin_size);
    }
    *out_size = total;
    return data;
}

/* The binary data of the hand-built scene (offsets in the JSON below). */
static size_t scene_bin(unsigned char *bin)
{
    memset(bin, 0, 112);
    const float triangle[9] = {0, 0, 0, 1, 0, 0, 0, 1, 0};
    const uint16_t triangle_indices[3] = {0, 1, 2};
    const float strip[12] = {0, 0, 5, 1, 0, 5, 0, 1, 5, 1, 1, 5};
    const uint8_t strip_indices[4] = {0, 1, 2, 3};
    const uint8_t sparse_index = 1;
    const float sparse_value[3] = {0, 0, 3};
    memcpy(bin + 0, triangle, sizeof triangle);
    memcpy(bin + 36, triangle_indices, sizeof triangle_indices);
    memcpy(bin + 44, strip, sizeof strip);
    memcpy(bin + 92, strip_indices, sizeof strip_indices);
    memcpy(bin + 96, &sparse_index, 1);
    memcpy(bin + 100, sparse_value, sizeof sparse_value);
    return 112;
}

static const char *scene_json =
    "{\"asset\":{\"version\":\"2.0\",\"generator\":\"hand\"},"
    "\"buffers\":[{\"byteLength\":112}],"
    "\"bufferViews\":["
    "{\"buffer\":0,\"byteOffset\":0,\"byteLength\":36},"
    "{\"buffer\":0,\"byteOffset\":36,\"byteLength\":6},"
    "{\"buffer\":0,\"byteOffset\":44,\"byteLength\":48},"
    "{\"buffer\":0,\"byteOffset\":92,\"byteLength\":4},"
    "{\"buffer\":0,\"byteOffset\":96,\"byteLength\":1},"
    "{\"buffer\":0,\"byteOffset\":100,\"byteLength\":12}],"
    "\"accessors\":["
    "{\"bufferView\":0,\"componentType\":5126,\"count\":3,\"type\":\"VEC3\"},"
    "{\"bufferView\":1,\"componentType\":5123,\"count\":3,\"type\":\"SCALAR\"},"
    "{\"bufferView\":2,\"componentType\":5126,\"count\":4,\"type\":\"VEC3\"},"
    "{\"bufferView\":3,\"componentType\":5121,\"count\":4,\"type\":\"SCALAR\"},"
    "{\"componentType\":5126,\"count\":3,\"type\":\"VEC3\",\"sparse\":{\"count\":1,"
    "\"indices\":{\"bufferView\":4,\"componentType\":5121},\"values\":{\"bufferView\":5}}},"
    "{\"componentType\":5126,\"count\":4,\"type\":\"VEC3\"}],"
    "\"meshes\":["
    "{\"name\":\"tri\",\"primitives\":[{\"attributes\":{\"POSITION\":0},\"indices\":1,"
    "\"targets\":[{\"POSITION\":4}]}]},"
    "{\"name\":\"strip\",\"primitives\":[{\"attributes\":{\"POSITION\":2},\"indices\":3,\"mode\":5,"
    "\"targets\":[{\"POSITION\":5}]},{\"attributes\":{\"POSITION\":2},\"mode\":0,"
    "\"targets\":[{\"POSITION\":5}]}]},"
    "{\"name\":\"unused\",\"primitives\":[{\"attributes\":{\"POSITION\":0}}]}],"
    "\"nodes\":["
    "{\"name\":\"root\",\"translation\":[10,0,0],\"children\":[1]},"
    "{\"name\":\"child\",\"scale\":[2,2,2],\"rotation\":[0,0,0.7071067811865476,0.7071067811865476],\"mesh\":0},"
    "{\"name\":\"mirror\",\"matrix\":[-1,0,0,0,0,1,0,0,0,0,1,0,0,0,0,1],\"mesh\":0},"
    "{\"name\":\"strip\",\"mesh\":1}],"
    "\"scenes\":[{\"nodes\":[0,2,3]}],\"scene\":0}";

static void face_normal(const pz_mesh *mesh, const double *positions, int32_t f, double n[3])
{
    const double *a = &positions[3 * mesh->faces[3 * f]], *b = &positions[3 * mesh->faces[3 * f + 1]],
                 *c = &positions[3 * mesh->faces[3 * f + 2]];
    double u[3] = {b[0] - a[0], b[1] - a[1], b[2] - a[2]}, v[3] = {c[0] - a[0], c[1] - a[1], c[2] - a[2]};
    n[0] = u[1] * v[2] - u[2] * v[1];
    n[1] = u[2] * v[0] - u[0] * v[2];
    n[2] = u[0] * v[1] - u[1] * v[0];
}

static int has_vertex_at(const pz_mesh *mesh, const double *positions, double x, double y, double z)
{
    for (int32_t v = 0; v < mesh->vertex_count; ++v) {
        const double *p = &positions[3 * v];
        if (fabs(p[0] - x) < 1e-6 && fabs(p[1] - y) < 1e-6 && fabs(p[2] - z) < 1e-6)
            return 1;
    }
    return 0;
}

static void test_hand_built_scene(void)
{
    pz_ctx ctx = {0};
    ctx.quiet = 1; /* the skipped POINTS primitive is noted */
    unsigned char bin[112];
    size_t bin_size = scene_bin(bin), size = 0;
    unsigned char *glb = make_glb(scene_json, bin, bin_size, &size);
    pz_mesh *mesh = NULL;
    REQUIRE_OK(pz_gltf_read_memory(glb, size, 1, NULL, "scene.glb", &mesh, &ctx), ctx);
    /* Triangle instances "child" and "mirror" (3 vertices each) and the strip (4); the unused mesh
       and the POINTS primitive add nothing. */
    CHECK(mesh->vertex_count == 10, "%d vertices, expected 10", (int)mesh->vertex_count);
    CHECK(mesh->face_count == 4, "%d faces, expected 4", (int)mesh->face_count);
    /* root T(10,0,0) * child R(z, 90 deg) S(2): (1,0,0) -> (10,2,0), (0,1,0) -> (8,0,0). */
    CHECK(has_vertex_at(mesh, mesh->positions, 10, 0, 0) && has_vertex_at(mesh, mesh->positions, 10, 2, 0) &&
              has_vertex_at(mesh, mesh->positions, 8, 0, 0),
          "TRS hierarchy not applied");
    CHECK(has_vertex_at(mesh, mesh->positions, -1, 0, 0), "matrix not applied");
    CHECK(has_vertex_at(mesh, mesh->positions, 1, 1, 5), "strip vertex missing");
    /* Every face faces +z, the mirrored one included (its winding was reversed). */
    for (int32_t f = 0; f < mesh->face_count; ++f) {
        double n[3];
        face_normal(mesh, mesh->positions, f, n);
        CHECK(n[2] > 0 && fabs(n[0]) < 1e-9 && fabs(n[1]) < 1e-9, "face %d normal (%g %g %g)", (int)f, n[0], n[1],
              n[2]);
    }
    /* The sparse target moves local vertex 1 by (0,0,3): x2 scale -> (10,2,6) in the child instance. */
    REQUIRE(mesh->pose_count == 1 && mesh->poses, "%d poses, expected 1", (int)mesh->pose_count);
    CHECK(has_vertex_at(mesh, mesh->poses, 10, 2, 6), "sparse morph target not applied with the transform");
    CHECK(has_vertex_at(mesh, mesh->poses, -1, 0, 3), "sparse morph target not applied in the mirror instance");
    CHECK(has_vertex_at(mesh, mesh->poses, 1, 1, 5), "zero morph target moved the strip");
    /* Labels by mesh name: both triangle instances share "tri". */
    REQUIRE(mesh->face_labels && mesh->label_count == 2, "%d labels, expected 2", (int)mesh->label_count);
    CHECK(strcmp(mesh->label_names[mesh->face_labels[0]], "tri") == 0, "label of face 0");
    CHECK(mesh->face_labels[0] == mesh->face_labels[1], "instances of one mesh got different labels");
    CHECK(strcmp(mesh->label_names[mesh->face_labels[3]], "strip/0") == 0, "strip label '%s'",
          mesh->label_names[mesh->face_labels[3]]);
    CHECK(mesh->uv_count == 0, "UVs from nowhere");
    pz_mesh_free(&mesh);
    free(glb);
}

/* Reads `json` (with the scene's binary) as a GLB and expects PZ_ERR_DATA naming the input. */
static void expect_data_error(const char *json, const char *what)
{
    pz_ctx ctx = {0};
    unsigned char bin[112];
    size_t size = 0;
    unsigned char *glb = make_glb(json, bin, scene_bin(bin), &size);
    pz_mesh *mesh = NULL;
    pz_status status = pz_gltf_read_memory(glb, size, 1, NULL, "broken.glb", &mesh, &ctx);
    CHECK(status == PZ_ERR_DATA, "%s: status %d (%s)", what, (int)status, ctx.error);
    CHECK(mesh == NULL, "%s: mesh returned", what);
    CHECK(strncmp(ctx.error, "broken.glb: ", 12) == 0 && !strchr(ctx.error, '\n'), "%s: message '%s'", what,
          ctx.error);
    free(glb);
}

/* The scene JSON with the first occurrence of `from` replaced by `to`. */
static char *scene_variant(const char *from, const char *to)
{
    const char *at = strstr(scene_json, from);
    REQUIRE(at, "fixture has no '%s'", from);
    size_t head = (size_t)(at - scene_json);
    char *text = malloc(strlen(scene_json) + strlen(to) + 1);
    memcpy(text, scene_json, head);
    strcpy(text + head, to);
    strcat(text, at + strlen(from));
    return text;
}

static void test_bad_inputs(void)
{
    pz_ctx ctx = {0};
    pz_mesh *mesh = NULL;

    /* Garbage, as GLB and as JSON. */
    unsigned char garbage[256];
    for (size_t i = 0; i < sizeof garbage; ++i)
        garbage[i] = (unsigned char)(i * 131 + 7);
    CHECK(pz_gltf_read_memory(garbage, sizeof garbage, 1, NULL, "garbage.glb", &mesh, &ctx) == PZ_ERR_DATA,
          "garbage GLB accepted");
    CHECK(strstr(ctx.error, "garbage.glb") != NULL, "message '%s'", ctx.error);
    CHECK(pz_gltf_read_memory(garbage, sizeof garbage, 0, NULL, "garbage.gltf", &mesh, &ctx) == PZ_ERR_DATA,
          "garbage glTF accepted");
    CHECK(strstr(ctx.error, "garbage.gltf") != NULL && !strchr(ctx.error, '\n'), "message '%s'", ctx.error);
    CHECK(mesh == NULL, "mesh returned for garbage");

    /* Every truncation of a valid GLB fails cleanly. */
    unsigned char bin[112];
    size_t size = 0;
    unsigned char *glb = make_glb(scene_json, bin, scene_bin(bin), &size);
    int accepted = 0;
    for (size_t cut = 0; cut < size; cut += 7) {
        accepted += pz_gltf_read_memory(glb, cut, 1, NULL, "cut.glb", &mesh, &ctx) != PZ_ERR_DATA;
        pz_mesh_free(&mesh);
    }
    CHECK(accepted == 0, "%d truncated GLBs not refused", accepted);
    CHECK(strstr(ctx.error, "cut.glb") != NULL, "message '%s'", ctx.error);

    /* A BIN chunk claiming more bytes than the file has. */
    size_t json_padded;
    {
        uint32_t json_length;
        memcpy(&json_length, glb + 12, 4);
        json_padded = json_length;
    }
    uint32_t too_long = 112 + 4;
    memcpy(glb + 20 + json_padded, &too_long, 4);
    CHECK(pz_gltf_read_memory(glb, size, 1, NULL, "long.glb", &mesh, &ctx) == PZ_ERR_DATA, "long BIN accepted");
    free(glb);

    /* The scene with one piece of its JSON replaced, each a different fault. */
    static const struct {
        const char *from, *to, *what;
    } variants[] = {
        {"{\"bufferView\":1,\"componentType\":5123,\"count\":3", "{\"bufferView\":1,\"componentType\":5123,\"count\":4",
         "accessor past its view"},
        {"\"byteOffset\":36,\"byteLength\":6", "\"byteOffset\":36,\"byteLength\":600", "view past its buffer"},
        /* reads float bytes as indices */
        {"\"byteOffset\":92,\"byteLength\":4", "\"byteOffset\":90,\"byteLength\":4", "strip index out of range"},
        {"\"indices\":1,\"targets\":[{\"POSITION\":4}]", "\"indices\":1", "morph target count mismatch"},
        {"\"children\":[1]", "\"children\":[1,0]", "node cycle"},
        {"\"children\":[1]", "\"children\":[7]", "missing child"},
        {"{\"componentType\":5126,\"count\":4,", "{\"componentType\":5126,\"count\":400000000,",
         "huge accessor without data"},
        {"\"POSITION\":0},\"indices\":1", "\"NORMAL\":0},\"indices\":1", "no POSITION"},
        {"\"scene\":0}", "\"scene\":0,\"extensionsRequired\":[\"KHR_draco_mesh_compression\"]}",
         "unsupported required extension"},
    };
    for (size_t i = 0; i < sizeof variants / sizeof variants[0]; ++i) {
        char *text = scene_variant(variants[i].from, variants[i].to);
        expect_data_error(text, variants[i].what);
        free(text);
    }

    /* Deeply nested extras would overflow tinygltf's recursive conversion. */
    size_t depth = 100000;
    char *deep = malloc(2 * depth + 64);
    strcpy(deep, "{\"asset\":{\"version\":\"2.0\",\"extras\":");
    size_t at = strlen(deep);
    memset(deep + at, '[', depth);
    memset(deep + at + depth, ']', depth);
    strcpy(deep + at + 2 * depth, "}}");
    CHECK(pz_gltf_read_memory((const unsigned char *)deep, strlen(deep), 0, NULL, "deep.gltf", &mesh, &ctx) ==
              PZ_ERR_DATA,
          "deep JSON accepted");
    CHECK(strstr(ctx.error, "deep.gltf") != NULL, "message '%s'", ctx.error);
    free(deep);
}

/* base_dir NULL must never read a file, even one sitting in the current directory. */
static void test_external_files(void)
{
    pz_ctx ctx = {0};
    unsigned char bin[112];
    scene_bin(bin);
    char path[512], sub[512];
    test_temp_path(path, sizeof path, "ext.bin");
    test_write_file(path, bin, 36);
    test_temp_path(sub, sizeof sub, "sub");
    mkdir(sub, 0700);
    static const char *json_format =
        "{\"asset\":{\"version\":\"2.0\"},\"buffers\":[{\"uri\":\"%s\",\"byteLength\":36}],"
        "\"bufferViews\":[{\"buffer\":0,\"byteLength\":36}],"
        "\"accessors\":[{\"bufferView\":0,\"componentType\":5126,\"count\":3,\"type\":\"VEC3\"}],"
        "\"meshes\":[{\"primitives\":[{\"attributes\":{\"POSITION\":0}}]}]}";
    char json[1024];
    snprintf(json, sizeof json, json_format, "ext.bin");

    char cwd[512];
    int moved = getcwd(cwd, sizeof cwd) != NULL;
    REQUIRE(moved, "getcwd");
    moved = chdir(test_temp_dir) == 0;
    REQUIRE(moved, "chdir");
    pz_mesh *mesh = NULL;
    CHECK(pz_gltf_read_memory((const unsigned char *)json, strlen(json), 0, NULL, "ext.gltf", &mesh, &ctx) ==
              PZ_ERR_DATA,
          "base_dir NULL read an external file");
    CHECK(strstr(ctx.error, "ext.gltf") != NULL, "message '%s'", ctx.error);
    pz_mesh_free(&mesh);
    moved = chdir(cwd) == 0;
    REQUIRE(moved, "chdir back");

    CHECK(pz_gltf_read_memory((const unsigned char *)json, strlen(json), 0, test_temp_dir, "ext.gltf", &mesh,
                              &ctx) == PZ_OK,
          "base_dir read failed: %s", ctx.error);
    CHECK(mesh && mesh->face_count == 1 && mesh->vertex_count == 3, "external triangle not read");
    pz_mesh_free(&mesh);

    /* "..": outside the base directory. */
    snprintf(json, sizeof json, json_format, "../ext.bin");
    CHECK(pz_gltf_read_memory((const unsigned char *)json, strlen(json), 0, sub, "up.gltf", &mesh, &ctx) ==
              PZ_ERR_DATA,
          "a URI with .. escaped the base directory");
    /* An absolute URI. */
    snprintf(json, sizeof json, json_format, path);
    CHECK(pz_gltf_read_memory((const unsigned char *)json, strlen(json), 0, sub, "abs.gltf", &mesh, &ctx) ==
              PZ_ERR_DATA,
          "an absolute URI was read");

    /* data: URIs need no filesystem. */
    static const char *alphabet = "ABCDEFGHIJKLMNOPQRSTUVWXYZabcdefghijklmnopqrstuvwxyz0123456789+/";
    char base64[64] = {0};
    for (int i = 0, o = 0; i < 36; i += 3) {
        uint32_t triple = (uint32_t)bin[i] << 16 | (uint32_t)bin[i + 1] << 8 | bin[i + 2];
        for (int k = 3; k >= 0; --k)
            base64[o++] = alphabet[(triple >> (6 * k)) & 63];
    }
    char uri[128];
    snprintf(uri, sizeof uri, "data:application/octet-stream;base64,%s", base64);
    snprintf(json, sizeof json, json_format, uri);
    CHECK(pz_gltf_read_memory((const unsigned char *)json, strlen(json), 0, NULL, "data.gltf", &mesh, &ctx) == PZ_OK,
          "data URI: %s", ctx.error);
    CHECK(mesh && mesh->face_count == 1, "data URI triangle not read");
    pz_mesh_free(&mesh);
}

/* OBJ -> GLB -> OBJ through the dispatcher keeps vertex count and indices exactly. */
static void test_obj_glb_obj(void)
{
    static const char *obj =
        "# a cube missing its bottom, two groups, a seam, an unused vertex\n"
        "v 0 0 0\nv 1 0 0\nv 1 1 0\nv 0 1 0\nv 0 0 1\nv 1 0 1\nv 1 1 1\nv 0 1 1\nv 9 9 9\n"
        "vt 0 0\nvt 1 0\nvt 1 1\nvt 0 1\nvt 0.5 0.5\n"
        "g sides\n"
        "f 1/1 2/2 6/3 5/4\nf 2/1 3/2 7/3 6/4\nf 3/1 4/2 8/3 7/4\nf 4/1 1/2 5/3 8/4\n"
        "g top\n"
        "f 5/1 6/2 7/3 8/5\n";
    char obj_path[512], glb_path[512], back_path[512];
    test_temp_path(obj_path, sizeof obj_path, "cube.obj");
    test_temp_path(glb_path, sizeof glb_path, "cube.glb");
    test_temp_path(back_path, sizeof back_path, "cube_back.obj");
    test_write_file(obj_path, obj, strlen(obj));

    pz_ctx ctx = {0};
    pz_mesh *original = NULL, *via_glb = NULL, *back = NULL;
    REQUIRE_OK(pz_mesh_read(obj_path, &original, &ctx), ctx);
    REQUIRE_OK(pz_mesh_write(original, glb_path, NULL, &ctx), ctx);
    REQUIRE_OK(pz_mesh_read(glb_path, &via_glb, &ctx), ctx);
    check_same_geometry(original, via_glb, "cube.glb");
    REQUIRE_OK(pz_mesh_write(via_glb, back_path, NULL, &ctx), ctx);
    REQUIRE_OK(pz_mesh_read(back_path, &back, &ctx), ctx);
    check_same_geometry(original, back, "cube_back.obj");
    CHECK(back->label_count == original->label_count, "%d labels, expected %d", (int)back->label_count,
          (int)original->label_count);
    for (int32_t l = 0; l < original->label_count && l < back->label_count; ++l)
        CHECK(original->label_names[l] && back->label_names[l] &&
                  strcmp(original->label_names[l], back->label_names[l]) == 0,
              "label %d name differs", (int)l);
    CHECK(back->corner_uvs && original->corner_uvs, "UVs lost on the way");
    for (int32_t c = 0; back->corner_uvs && original->corner_uvs && c < 3 * original->face_count; ++c) {
        const double *a = &original->uvs[2 * original->corner_uvs[c]], *b = &back->uvs[2 * back->corner_uvs[c]];
        CHECK(close_to(a[0], b[0]) && close_to(a[1], b[1]), "corner %d UV (%g %g) vs (%g %g)", (int)c, a[0], a[1],
              b[0], b[1]);
    }
    pz_mesh_free(&original);
    pz_mesh_free(&via_glb);
    pz_mesh_free(&back);
}

/* The GLB writers' palette and glTF's linear colours (pz_glb_label_color, pz_glb_color_linear). */
static void test_colours(void)
{
    CHECK(pz_glb_label_color(0) == 0x4e79a7ffu, "palette colour 0 is %08x", (unsigned)pz_glb_label_color(0));
    int distinct = 1, opaque = 1;
    for (int32_t a = 0; a < 12; ++a) {
        opaque &= (pz_glb_label_color(a) & 0xff) == 0xff;
        for (int32_t b = 0; b < a; ++b)
            distinct &= pz_glb_label_color(a) != pz_glb_label_color(b);
    }
    CHECK(distinct && opaque, "the 12 palette colours are distinct and opaque");
    CHECK(pz_glb_label_color(12) == pz_glb_label_color(0) && pz_glb_label_color(29) == pz_glb_label_color(5),
          "labels past 12 wrap round the palette");
    double white[4], black[4], mixed[4];
    pz_glb_color_linear(0xffffffffu, white);
    pz_glb_color_linear(0x000000ffu, black);
    pz_glb_color_linear(0x800a0080u, mixed);
    CHECK(white[0] == 1 && white[1] == 1 && white[2] == 1 && white[3] == 1, "white stays white");
    CHECK(black[0] == 0 && black[1] == 0 && black[2] == 0 && black[3] == 1, "black stays black, opaque");
    /* sRGB 0x80 is the power segment, 0x0a (under 0.04045) the linear one; alpha is not converted. */
    double half = pow((128.0 / 255.0 + 0.055) / 1.055, 2.4);
    CHECK(fabs(mixed[0] - half) < 1e-15 && fabs(half - 0.2158605) < 1e-6, "sRGB 0x80 -> %g", mixed[0]);
    CHECK(fabs(mixed[1] - 10.0 / 255.0 / 12.92) < 1e-15, "sRGB 0x0a -> %g", mixed[1]);
    CHECK(mixed[2] == 0 && fabs(mixed[3] - 128.0 / 255.0) < 1e-15, "blue 0, alpha 0x80 -> %g", mixed[3]);
}

/* Leaves GLBs for the validator test: plain, UVs + labels, everything. */
static void write_validator_samples(const char *directory)
{
    struct {
        const char *file;
        int uvs, labels, poses;
    } samples[] = {{"plain.glb", 0, 0, 0}, {"labelled.glb", 1, 1, 0}, {"posed.glb", 1, 1, 1}};
    pz_write_options options = {0};
    options.extras_json = "{\"source\": \"test_gltf\", \"panels\": 2}";
    for (size_t i = 0; i < sizeof samples / sizeof samples[0]; ++i) {
        pz_ctx ctx = {0};
        pz_mesh *mesh = make_grid(samples[i].uvs, samples[i].labels, samples[i].poses);
        char path[1024];
        snprintf(path, sizeof path, "%s/%s", directory, samples[i].file);
        CHECK(pz_glb_write(mesh, path, &options, &ctx) == PZ_OK, "%s", ctx.error);
        pz_mesh_free(&mesh);
    }
}

int main(void)
{
    test_temp_dir_create("pz_test_gltf");
    test_grid_round_trip();
    test_plain_round_trip();
    test_hand_built_scene();
    test_bad_inputs();
    test_external_files();
    test_obj_glb_obj();
    test_colours();
    const char *samples = getenv("PZ_GLB_OUT");
    if (samples && *samples)
        write_validator_samples(samples);
    CHECK(test_temp_dir_remove() == 0, "cannot remove %s", test_temp_dir);
    return test_finish();
}

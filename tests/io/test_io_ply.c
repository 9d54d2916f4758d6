/*
 * tests/io/test_io_ply.c -- the PLY reader on files built byte by byte:
 * ascii, binary little and big endian, every scalar type in some role,
 * skipped properties, lists and elements, element order, UVs, labels, and
 * every failure path (bad header, truncation, out-of-range index, huge counts).
 *
 * SPDX-License-Identifier: GPL-3.0-or-later
 */
#include "io/io.h"
#include "test_meshes.h"

#include <stdint.h>
#include <stdlib.h>
#include <string.h>

/* A growing byte buffer with explicit-endian writers. */
typedef struct bytes {
    unsigned char data[8192];
    size_t size;
    int big_endian;
} bytes;

static void put_text(bytes *b, const char *text)
{
    size_t length = strlen(text);
    REQUIRE(b->size + length <= sizeof b->data, "test buffer too small");
    memcpy(b->data + b->size, text, length);
    b->size += length;
}

static void put_bits(bytes *b, uint64_t bits, size_t size)
{
    REQUIRE(b->size + size <= sizeof b->data, "test buffer too small");
    for (size_t i = 0; i < size; ++i)
        b->data[b->size + (b->big_endian ? size - 1 - i : i)] = (unsigned char)(bits >> (8 * i));
    b->size += size;
}

static void put_u8(bytes *b, unsigned value) { put_bits(b, value, 1); }
static void put_i16(bytes *b, int value) { put_bits(b, (uint16_t)(int16_t)value, 2); }
static void put_u16(bytes *b, unsigned value) { put_bits(b, (uint16_t)value, 2); }
static void put_i32(bytes *b, int32_t value) { put_bits(b, (uint32_t)value, 4); }
static void put_f32(bytes *b, float value)
{
    uint32_t bits;
    memcpy(&bits, &value, 4);
    put_bits(b, bits, 4);
}
static void put_f64(bytes *b, double value)
{
    uint64_t bits;
    memcpy(&bits, &value, 8);
    put_bits(b, bits, 8);
}

/* pz_ply_read_memory as a test_reader. */
static pz_status read_ply(const char *data, size_t size, const char *name, pz_mesh **out, pz_ctx *ctx)
{
    return pz_ply_read_memory((const unsigned char *)data, size, name, out, ctx);
}

static pz_mesh *read_ok(const bytes *b, const char *what)
{
    return test_read_ok(read_ply, (const char *)b->data, b->size, "test.ply", what);
}

static void read_fails(const bytes *b, const char *expected)
{
    test_read_fails(read_ply, (const char *)b->data, b->size, "bad.ply", expected);
}

/* A unit square as a quad plus a triangle on vertex 4, with properties to skip. */
static void test_ascii(void)
{
    bytes b = {.size = 0};
    put_text(&b, "ply\r\nformat ascii 1.0\r\ncomment made by hand\r\nobj_info nothing\r\n"
                 "element vertex 5\r\nproperty float x\r\nproperty float y\r\nproperty float z\r\n"
                 "property float nx\r\nproperty uchar red\r\nproperty list uchar int extra\r\n"
                 "element face 2\r\nproperty uchar flags\r\nproperty list uchar int vertex_indices\r\n"
                 "property list uchar float texcoord\r\n"
                 "element edge 1\r\nproperty int vertex1\r\nproperty int vertex2\r\n"
                 "end_header\r\n"
                 "0 0 0 1 255 0\r\n1 0 0 1 255 2 7 8\r\n1 1 0 1 0 0\r\n0 1 0.5 1 0 0\r\n"
                 "2 2 -1.5e2 0 0 1 99\r\n"
                 "3 4 0 1 2 3 0\r\n"
                 "0 3\t1 4 2 2 0.5 0.5\n"  /* tokens may spread over lines */
                 "0 1\r\n");
    pz_mesh *mesh = read_ok(&b, "ascii");
    if (!mesh)
        return;
    CHECK(mesh->vertex_count == 5 && mesh->face_count == 3, "counts %d/%d", mesh->vertex_count, mesh->face_count);
    CHECK(test_face_is(mesh, 0, 0, 1, 2) && test_face_is(mesh, 1, 0, 2, 3) && test_face_is(mesh, 2, 1, 4, 2), "faces");
    CHECK(mesh->positions[11] == 0.5 && mesh->positions[12] == 2 && mesh->positions[14] == -150.0, "positions");
    CHECK(mesh->uvs == NULL && mesh->face_labels == NULL, "no UVs or labels");
    pz_mesh_free(&mesh);
}

/*
 * The same square written in binary with the given endianness; `faces_first`
 * puts the face element before the vertex element.
 */
static void build_binary(bytes *b, int big_endian, int faces_first)
{
    memset(b, 0, sizeof *b);
    put_text(b, big_endian ? "ply\nformat binary_big_endian 1.0\n" : "ply\nformat binary_little_endian 1.0\n");
    static const char vertex_header[] = "element vertex 4\nproperty double x\nproperty float32 y\n"
                                        "property int16 z\nproperty uchar alpha\nproperty float s\n"
                                        "property float t\nproperty list int8 double normals\n";
    static const char face_header[] = "element face 2\nproperty list uint8 uint16 vertex_index\n"
                                      "property list int int32 other\n";
    put_text(b, faces_first ? face_header : vertex_header);
    put_text(b, faces_first ? vertex_header : face_header);
    put_text(b, "element material 3\nproperty ushort id\nproperty double weight\nend_header\n");
    b->big_endian = big_endian;
    for (int pass = 0; pass < 2; ++pass) {
        if ((pass == 0) == (faces_first != 0)) {
            put_u8(b, 3), put_u16(b, 0), put_u16(b, 1), put_u16(b, 2), put_i32(b, 0);
            put_u8(b, 3), put_u16(b, 0), put_u16(b, 2), put_u16(b, 3), put_i32(b, 1), put_i32(b, -7);
        } else {
            static const double xyz[4][3] = {{0.1, 0, -3}, {1.0 / 3.0, 0.25, 0}, {1e-300, 1, 2}, {-0.0, 1, 300}};
            for (int v = 0; v < 4; ++v) {
                put_f64(b, xyz[v][0]), put_f32(b, (float)xyz[v][1]), put_i16(b, (int)xyz[v][2]);
                put_u8(b, 200), put_f32(b, 0.5f * (float)v), put_f32(b, 1.0f - 0.25f * (float)v);
                put_bits(b, 1, 1), put_f64(b, 9.0);
            }
        }
    }
    for (int m = 0; m < 3; ++m)
        put_u16(b, 7), put_f64(b, 0.5);
}

static void test_binary(void)
{
    for (int big_endian = 0; big_endian < 2; ++big_endian)
        for (int faces_first = 0; faces_first < 2; ++faces_first) {
            bytes b;
            build_binary(&b, big_endian, faces_first);
            pz_mesh *mesh = read_ok(&b, big_endian ? "big endian" : "little endian");
            if (!mesh)
                continue;
            CHECK(mesh->vertex_count == 4 && mesh->face_count == 2, "be %d ff %d: counts", big_endian, faces_first);
            CHECK(test_face_is(mesh, 0, 0, 1, 2) && test_face_is(mesh, 1, 0, 2, 3), "be %d ff %d: faces", big_endian,
                  faces_first);
            CHECK(mesh->positions[0] == 0.1 && mesh->positions[3] == 1.0 / 3.0 && mesh->positions[6] == 1e-300,
                  "be %d: doubles exact", big_endian);
            CHECK(mesh->positions[2] == -3 && mesh->positions[11] == 300 && mesh->positions[4] == 0.25,
                  "be %d: int16 and float32", big_endian);
            REQUIRE(mesh->uvs != NULL && mesh->corner_uvs != NULL, "per-vertex s,t read");
            CHECK(mesh->uv_count == 4 && mesh->uvs[2 * 3] == 1.5 && mesh->uvs[2 * 3 + 1] == 0.25, "uv values");
            CHECK(memcmp(mesh->corner_uvs, mesh->faces, 6 * sizeof(int32_t)) == 0, "corner uvs = vertex ids");
            pz_mesh_free(&mesh);
        }
}

static void test_labels_and_types(void)
{
    bytes b = {.size = 0};
    put_text(&b, "ply\nformat binary_little_endian 1.0\ncomment pz_label 9 left sleeve\n"
                 "comment pz_label 4 body\ncomment pz_label 77 unused\n"
                 "element vertex 4\nproperty int8 x\nproperty uint8 y\nproperty uint32 z\n"
                 "property double texture_u\nproperty double texture_v\n"
                 "element face 3\nproperty list ushort float32 vertex_indices\nproperty uint label\nend_header\n");
    for (int v = 0; v < 4; ++v)
        put_u8(&b, (unsigned)(-v) & 0xff), put_u8(&b, 250), put_bits(&b, 4000000000u, 4), put_f64(&b, v),
            put_f64(&b, -v);
    int32_t labels[3] = {9, 4, 9};
    for (int f = 0; f < 3; ++f) {
        put_u16(&b, 3), put_f32(&b, 0), put_f32(&b, (float)(f + 1)), put_f32(&b, (float)((f + 2) % 4));
        put_bits(&b, (uint32_t)labels[f], 4);
    }
    pz_mesh *mesh = read_ok(&b, "labels");
    if (!mesh)
        return;
    CHECK(mesh->positions[3] == -1 && mesh->positions[4] == 250 && mesh->positions[5] == 4e9, "int8 uint8 uint32");
    CHECK(mesh->uvs && mesh->uvs[2] == 1 && mesh->uvs[3] == -1, "texture_u / texture_v");
    CHECK(test_face_is(mesh, 2, 0, 3, 0), "float32 indices");
    REQUIRE(mesh->face_labels != NULL, "labels read");
    CHECK(mesh->label_count == 2, "distinct labels renumbered densely: %d", mesh->label_count);
    CHECK(mesh->face_labels[0] == 1 && mesh->face_labels[1] == 0 && mesh->face_labels[2] == 1, "label order kept");
    REQUIRE(mesh->label_names != NULL, "names from comments");
    CHECK(mesh->label_names[0] && strcmp(mesh->label_names[0], "body") == 0, "name 0");
    CHECK(mesh->label_names[1] && strcmp(mesh->label_names[1], "left sleeve") == 0, "name 1");
    pz_mesh_free(&mesh);
}

static const char small_header[] = "ply\nformat binary_little_endian 1.0\nelement vertex 3\n"
                                   "property float x\nproperty float y\nproperty float z\n"
                                   "element face 1\nproperty list uchar int vertex_indices\nend_header\n";

static void build_small(bytes *b, int32_t third_index, unsigned corner_count)
{
    memset(b, 0, sizeof *b);
    put_text(b, small_header);
    for (int i = 0; i < 9; ++i)
        put_f32(b, (float)i);
    put_u8(b, corner_count);
    put_i32(b, 0), put_i32(b, 1), put_i32(b, third_index);
}

static void test_failures(void)
{
    bytes b;
    build_small(&b, 2, 3);
    pz_mesh *mesh = read_ok(&b, "small");
    pz_mesh_free(&mesh);
    for (size_t cut = 1; cut <= 12; ++cut) { /* every truncation of the face data fails cleanly */
        bytes truncated = b;
        truncated.size -= cut;
        read_fails(&truncated, "truncated");
    }
    build_small(&b, 3, 3);
    read_fails(&b, "vertex index out of range");
    build_small(&b, -1, 3);
    read_fails(&b, "vertex index out of range");
    build_small(&b, 2, 2);
    read_fails(&b, "face 0 has 2 corners");

    static const struct {
        const char *text;
        const char *expected;
    } cases[] = {
        {"", "not a PLY file"},
        {"plx\nformat ascii 1.0\nend_header\n", "not a PLY file"},
        {"ply\nformat ascii 1.0\nelement vertex 1\nproperty float x\n", "no end_header"},
        {"ply\nformat ascii 1.0\nproperty float x\nend_header\n", "property before any element"},
        {"ply\nformat ascii 1.0\nelement vertex 1\nproperty quad x\nend_header\n", "unknown property type"},
        {"ply\nformat ascii 1.0\nelement vertex -1\nend_header\n", "malformed element"},
        {"ply\nformat xml 1.0\nend_header\n", "unknown format"},
        {"ply\nelement vertex 0\nend_header\n", "no format line"},
        {"ply\nformat ascii 1.0\nbogus line\nend_header\n", "unexpected header line"},
        {"ply\nformat ascii 1.0\nelement vertex 1\nproperty float x\nproperty float y\nend_header\n0 0\n",
         "lacks x, y or z"},
        {"ply\nformat ascii 1.0\nelement vertex 3\nproperty float x\nproperty float y\nproperty float z\n"
         "end_header\n0 0 0 1 0 0 0 1 0\n",
         "no faces"},
        {"ply\nformat ascii 1.0\nelement vertex 3\nproperty float x\nproperty float y\nproperty float z\n"
         "element face 1\nproperty list uchar int vertex_indices\nend_header\n0 0 0 1 0 0 0 1 0\n3 0 1 x\n",
         "malformed data in element 'face'"},
        {"ply\nformat ascii 1.0\nelement vertex 3\nproperty float x\nproperty float y\nproperty float z\n"
         "element face 1\nproperty list uchar int vertex_indices\nend_header\n0 0 0 1 0 0 0 1 0\n3 0 1.5 2\n",
         "non-integral vertex index"},
        /* A declared count the data cannot hold is refused before allocating for it. */
        {"ply\nformat binary_little_endian 1.0\nelement vertex 2000000000\nproperty double x\n"
         "property double y\nproperty double z\nend_header\n\1\2\3",
         "declares 2000000000 items"},
        {"ply\nformat ascii 1.0\nelement vertex 9999999999\nproperty float x\nproperty float y\n"
         "property float z\nend_header\n0 0 0\n",
         "declares 9999999999 items"},
        {"ply\nformat binary_little_endian 1.0\nelement vertex 3\nproperty uchar x\nproperty uchar y\n"
         "property uchar z\nelement face 1\nproperty list uint int vertex_indices\nend_header\n"
         "\0\0\0\1\0\0\0\1\0\377\377\377\177",
         "truncated"},
    };
    for (size_t i = 0; i < sizeof cases / sizeof cases[0]; ++i) {
        memset(&b, 0, sizeof b);
        put_text(&b, cases[i].text);
        if (i == sizeof cases / sizeof cases[0] - 1) { /* its binary tail holds NUL bytes */
            b.size = strlen(cases[i].text) + 13;
            memcpy(b.data, cases[i].text, b.size);
        }
        read_fails(&b, cases[i].expected);
    }
}

int main(void)
{
    test_ascii();
    test_binary();
    test_labels_and_types();
    test_failures();
    return test_finish();
}

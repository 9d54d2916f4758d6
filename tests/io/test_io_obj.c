/*
 * tests/io/test_io_obj.c -- the OBJ reader on small hand-written files:
 * every face corner form, negative and forward indices, polygons, groups,
 * UV rules, line endings, exact numbers, and every failure path.
 *
 * SPDX-License-Identifier: GPL-3.0-or-later
 */
#include "io/io.h"
#include "test_meshes.h"

#include <math.h>
#include <stdlib.h>
#include <string.h>

static pz_mesh *read_ok(const char *text)
{
    return test_read_ok(pz_obj_read_memory, text, strlen(text), "inline.obj", "inline.obj");
}

/* Reads text that must fail with PZ_ERR_DATA and a message containing `expected`. */
static void read_fails(const char *text, const char *expected)
{
    test_read_fails(pz_obj_read_memory, text, strlen(text), "bad.obj", expected);
}

static const char square[] = "v 0 0 0\nv 1 0 0\nv 1 1 0\nv 0 1 0\n"
                             "vt 0 0\nvt 1 0\nvt 1 1\nvt 0 1\n";

static void test_corner_forms(void)
{
    static const char *const bodies[] = {"f 1 2 3\nf 1 3 4\n", "f 1/1 2/2 3/3\nf 1/1 3/3 4/4\n",
                                         "f 1//1 2//2 3//3\nf 1//1 3//3 4//4\n",
                                         "f 1/1/1 2/2/1 3/3/1\nf 1/1/1 3/3/1 4/4/1\n"};
    static const int has_uvs[] = {0, 1, 0, 1};
    for (int form = 0; form < 4; ++form) {
        char text[512];
        snprintf(text, sizeof text, "%svn 0 0 1\n%s", square, bodies[form]);
        pz_mesh *mesh = read_ok(text);
        if (!mesh)
            continue;
        CHECK(mesh->vertex_count == 4 && mesh->face_count == 2, "form %d: %d/%d", form, mesh->vertex_count,
              mesh->face_count);
        CHECK(test_face_is(mesh, 0, 0, 1, 2) && test_face_is(mesh, 1, 0, 2, 3), "form %d: faces wrong", form);
        CHECK((mesh->uvs != NULL) == has_uvs[form], "form %d: uvs presence", form);
        if (has_uvs[form] && mesh->uvs) {
            CHECK(mesh->uv_count == 4, "uv_count %d", mesh->uv_count);
            CHECK(mesh->corner_uvs[5] == 3, "corner uv of face 1 corner 2: %d", mesh->corner_uvs[5]);
            CHECK(mesh->uvs[2 * 2] == 1.0 && mesh->uvs[2 * 2 + 1] == 1.0, "uv 2 values");
        }
        CHECK(mesh->face_labels == NULL && mesh->label_count == 0, "form %d: labels without groups", form);
        CHECK(mesh->unit_scale == 1.0, "unit_scale");
        pz_mesh_free(&mesh);
        CHECK(mesh == NULL, "free sets NULL");
    }
}

static void test_negative_and_forward_indices(void)
{
    pz_mesh *mesh = read_ok("v 0 0 0\nv 1 0 0\nv 1 1 0\nf -3 -2 -1\nv 0 1 0\nf -4 -2 -1\n");
    if (mesh) {
        CHECK(mesh->face_count == 2 && test_face_is(mesh, 0, 0, 1, 2) && test_face_is(mesh, 1, 0, 2, 3),
              "relative indices resolve against the vertices defined so far");
        pz_mesh_free(&mesh);
    }
    mesh = read_ok("f 1 2 3\nv 0 0 0\nv 1 0 0\nv 0 1 0\n");
    if (mesh) {
        CHECK(mesh->vertex_count == 3 && test_face_is(mesh, 0, 0, 1, 2), "a forward reference is allowed");
        pz_mesh_free(&mesh);
    }
}

/* A regular n-gon of every n from 3 to 130: n - 2 triangles, all counter-clockwise, covering its area exactly. */
static void test_polygon_cover(void)
{
    char text[16384];
    for (int n = 3; n <= 130; ++n) {
        size_t used = 0;
        for (int i = 0; i < n; ++i)
            used += (size_t)snprintf(text + used, sizeof text - used, "v %.17g %.17g 0\n", cos(2 * 3.14159265358979323846 * i / n),
                                     sin(2 * 3.14159265358979323846 * i / n));
        used += (size_t)snprintf(text + used, sizeof text - used, "f");
        for (int i = 0; i < n; ++i)
            used += (size_t)snprintf(text + used, sizeof text - used, " %d", i + 1);
        pz_mesh *mesh = read_ok(text);
        if (!mesh)
            continue;
        double area = 0.0, smallest = INFINITY;
        for (int32_t f = 0; f < mesh->face_count; ++f) {
            const double *a = mesh->positions + 3 * mesh->faces[3 * f], *b = mesh->positions + 3 * mesh->faces[3 * f + 1],
                         *c = mesh->positions + 3 * mesh->faces[3 * f + 2];
            double signed_area = 0.5 * ((b[0] - a[0]) * (c[1] - a[1]) - (b[1] - a[1]) * (c[0] - a[0]));
            area += signed_area;
            smallest = fmin(smallest, signed_area);
        }
        double expected = 0.5 * n * sin(2 * 3.14159265358979323846 / n);
        CHECK(mesh->face_count == n - 2 && smallest > 0 && fabs(area - expected) < 1e-9,
              "%d-gon: %d triangles, smallest signed area %g, area %.12f (expected %.12f)", n, mesh->face_count,
              smallest, area, expected);
        pz_mesh_free(&mesh);
    }
}

static void test_polygons(void)
{
    pz_mesh *mesh = read_ok("v 0 0 0\nv 1 0 0\nv 2 1 0\nv 1 2 0\nv 0 1 0\nf 1 2 3 4 5\n");
    if (mesh) {
        CHECK(mesh->face_count == 3, "pentagon -> 3 triangles, got %d", mesh->face_count);
        /* Level by level (io/polygon.h): (0,1,2), (2,3,4), then (0,2,4). */
        CHECK(test_face_is(mesh, 0, 0, 1, 2) && test_face_is(mesh, 1, 2, 3, 4) && test_face_is(mesh, 2, 0, 2, 4),
              "triangulation order");
        pz_mesh_free(&mesh);
    }
    /* One face line of 20000 corners: lines of any length. */
    size_t corner_count = 20000, capacity = corner_count * 24 + 64;
    char *text = malloc(capacity);
    REQUIRE(text != NULL, "malloc");
    size_t used = 0;
    for (size_t v = 0; v < corner_count; ++v)
        used += (size_t)snprintf(text + used, capacity - used, "v %zu %zu 0\n", v % 7, v);
    used += (size_t)snprintf(text + used, capacity - used, "f");
    for (size_t v = 0; v < corner_count && used + 16 < capacity; ++v)
        used += (size_t)snprintf(text + used, capacity - used, " %zu", v + 1);
    mesh = read_ok(text);
    if (mesh) {
        CHECK(mesh->face_count == (int32_t)corner_count - 2, "long polygon: %d faces", mesh->face_count);
        /* Not a fan: no corner is in more than 2 log2(n) + 2 triangles (a fan puts corner 0 in all of them). */
        int32_t *uses = calloc(corner_count, sizeof *uses), most = 0;
        REQUIRE(uses != NULL, "calloc");
        for (int32_t i = 0; i < 3 * mesh->face_count; ++i)
            most = ++uses[mesh->faces[i]] > most ? uses[mesh->faces[i]] : most;
        CHECK(most <= 2 * 15 + 2, "long polygon: a corner is in %d triangles", (int)most);
        free(uses);
        pz_mesh_free(&mesh);
    }
    free(text);
}

static void test_groups(void)
{
    pz_mesh *mesh = read_ok("v 0 0 0\nv 1 0 0\nv 0 1 0\n"
                            "f 1 2 3\n"
                            "g front panel \n"
                            "f 1 2 3\nf 1 2 3\n"
                            "o back\n"
                            "f 1 2 3\n"
                            "g front panel\n"
                            "f 1 2 3\n");
    if (!mesh)
        return;
    REQUIRE(mesh->face_labels != NULL && mesh->label_names != NULL, "labels present");
    CHECK(mesh->label_count == 3, "labels: front panel, back, default; got %d", mesh->label_count);
    int32_t expected[5] = {2, 0, 0, 1, 0};
    for (int f = 0; f < 5; ++f)
        CHECK(mesh->face_labels[f] == expected[f], "face %d label %d, expected %d", f, mesh->face_labels[f],
              expected[f]);
    CHECK(strcmp(mesh->label_names[0], "front panel") == 0, "name 0 '%s' (trimmed, spaces kept)",
          mesh->label_names[0]);
    CHECK(strcmp(mesh->label_names[1], "back") == 0, "name 1 '%s'", mesh->label_names[1]);
    CHECK(strcmp(mesh->label_names[2], "default") == 0, "faces before the first group: '%s'", mesh->label_names[2]);
    pz_mesh_free(&mesh);
}

static void test_uv_rules(void)
{
    /* One corner without vt: UVs are dropped without an error. */
    pz_mesh *mesh = read_ok("v 0 0 0\nv 1 0 0\nv 0 1 0\nvt 0 0\nvt 1 0\nvt 0 1\nf 1/1 2/2 3/3\nf 1/1 2 3/3\n");
    if (mesh) {
        CHECK(mesh->uvs == NULL && mesh->corner_uvs == NULL && mesh->uv_count == 0, "partial UVs dropped");
        pz_mesh_free(&mesh);
    }
    /* vt with one value, and with a w: v defaults to 0, w ignored. */
    mesh = read_ok("v 0 0 0\nv 1 0 0\nv 0 1 0\nvt 0.25\nvt 1 0.5 7\nvt 0 1\nf 1/1 2/2 3/3\n");
    if (mesh) {
        CHECK(mesh->uv_count == 3 && mesh->uvs[0] == 0.25 && mesh->uvs[1] == 0.0, "vt u");
        CHECK(mesh->uvs[2] == 1.0 && mesh->uvs[3] == 0.5, "vt u v w");
        pz_mesh_free(&mesh);
    }
}

static void test_whitespace_and_skipped_lines(void)
{
    pz_mesh *mesh = read_ok("# comment\r\nmtllib x.mtl\r\nv\t1 2 3 0.5 0.25 0.125\r\nv 4\t5 6\r\n"
                            "\r\n   \r\nv 7 8 9 1\r\nvn 0 0 1\r\nusemtl red\r\ns off\r\nl 1 2\r\n"
                            "vp 0.5\r\n\tf 1 2\t3   "); /* no final newline, trailing blanks */
    if (mesh) {
        CHECK(mesh->vertex_count == 3 && mesh->face_count == 1, "counts %d/%d", mesh->vertex_count,
              mesh->face_count);
        CHECK(mesh->positions[0] == 1 && mesh->positions[2] == 3 && mesh->positions[3] == 4 &&
                  mesh->positions[8] == 9,
              "extra vertex values are ignored");
        CHECK(test_face_is(mesh, 0, 0, 1, 2), "face");
        pz_mesh_free(&mesh);
    }
}

/* Numbers: the fast path must agree bit for bit with strtod, and nan parses. */
static void test_numbers(void)
{
    enum { count = 30000 };
    static const char *const formats[] = {"%.17g", "%.6f", "%.3e", "%.1f", "%.12g", "%.9g"};
    char *text = malloc((size_t)count * 3 * 40 + 64);
    double *expected = malloc((size_t)count * 3 * sizeof(double));
    REQUIRE(text && expected, "malloc");
    size_t used = 0;
    srand(12345);
    for (int i = 0; i < 3 * count; ++i) {
        double magnitude = pow(10.0, (rand() % 40) - 20);
        double value = (rand() / (double)RAND_MAX - 0.3) * magnitude;
        char number[40];
        snprintf(number, sizeof number, formats[i % 6], value);
        expected[i] = strtod(number, NULL);
        used += (size_t)sprintf(text + used, i % 3 == 0 ? "v %s" : i % 3 == 1 ? " %s" : " %s\n", number);
    }
    used += (size_t)sprintf(text + used, "f 1 2 3\n");
    pz_mesh *mesh = read_ok(text);
    if (mesh) {
        int mismatches = 0;
        for (int i = 0; i < 3 * count; ++i)
            mismatches += memcmp(&mesh->positions[i], &expected[i], sizeof(double)) != 0;
        CHECK(mismatches == 0, "%d numbers differ from strtod", mismatches);
        pz_mesh_free(&mesh);
    }
    free(text);
    free(expected);

    mesh = read_ok("v nan 1e-320 -0\nv 1e308 .5 5.\nv 0x10 +2 1E2\nf 1 2 3\n");
    if (mesh) {
        CHECK(isnan(mesh->positions[0]), "nan parses as NaN (validation rejects it later)");
        CHECK(mesh->positions[1] == 1e-320 && signbit(mesh->positions[2]), "subnormal and -0");
        CHECK(mesh->positions[3] == 1e308 && mesh->positions[4] == 0.5 && mesh->positions[5] == 5.0, "forms");
        CHECK(mesh->positions[6] == 16.0 && mesh->positions[7] == 2.0 && mesh->positions[8] == 100.0, "hex, +, E");
        pz_mesh_free(&mesh);
    }
}

static void test_failures(void)
{
    read_fails("", "no faces");
    read_fails("# nothing\nv 1 2 3\n", "no faces");
    read_fails("v 0 0 0\nv 1 0 0\nv 0 1 0\nf 0 1 2\n", "line 4: vertex index 0");
    read_fails("v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 9\nf 1 2 3\n", "line 4: vertex index 9 out of range");
    read_fails("v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 -4\n", "line 4: vertex index -4 out of range");
    read_fails("v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 99999999999999999999\n", "line 4: vertex index");
    read_fails("v 0 0 0\nv 1 0 0\nv 0 1 0\nvt 0 0\nf 1/1 2/1 3/5\n", "line 5: texture coordinate index 5");
    read_fails("v 0 0 0\nv 1 0 x\n", "line 2: malformed vertex");
    read_fails("v 0 0\nf 1 1 1\n", "line 1: malformed vertex");
    read_fails("v 0 0 1e\nf 1 1 1\n", "line 1: malformed vertex");
    read_fails("vt zz\n", "line 1: malformed texture coordinate");
    read_fails("v 0 0 0\nv 1 0 0\nf 1 2\n", "line 3: face with 2 corners");
    read_fails("v 0 0 0\nv 1 0 0\nv 0 1 0\nf\n", "line 4: face with 0 corners");
    read_fails("v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 3a\n", "line 4: malformed face corner");
    read_fails("v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1/x 2 3\n", "line 4: malformed face corner");
    read_fails("v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1//x 2 3\n", "line 4: malformed face corner");
    /* A forward reference that never gets defined is reported at its line. */
    read_fails("v 0 0 0\nf 1 2 3\nv 1 0 0\n", "line 2: vertex index 3 out of range (2 defined)");
    /* NUL bytes and binary junk are data errors, not crashes. */
    static const char junk[] = "v 1 2 3\nf 1 \0 1\n";
    pz_ctx ctx;
    pz_ctx_init(&ctx);
    pz_mesh *mesh = NULL;
    CHECK(pz_obj_read_memory(junk, sizeof junk - 1, "junk.obj", &mesh, &ctx) == PZ_ERR_DATA && !mesh,
          "NUL inside a face line");
    CHECK(pz_obj_read_memory(NULL, 0, "null.obj", &mesh, &ctx) == PZ_ERR_DATA && !mesh, "NULL data");
    /* Found by fuzzing: a NUL byte inside a group name read past the stored name. */
    static const char nul_group[] = "v 0 0 0\nv 1 0 0\nv 0 1 0\ng fr\0ont\nf 1 2 3\ng fr\nf 1 2 3\no fr\0x\nf 1 2 3\n";
    CHECK(pz_obj_read_memory(nul_group, sizeof nul_group - 1, "nul.obj", &mesh, &ctx) == PZ_OK, "%s", ctx.error);
    if (mesh) {
        CHECK(mesh->label_count == 1 && strcmp(mesh->label_names[0], "fr") == 0, "a NUL ends a group name");
        pz_mesh_free(&mesh);
    }
}

int main(void)
{
    test_corner_forms();
    test_negative_and_forward_indices();
    test_polygons();
    test_polygon_cover();
    test_groups();
    test_uv_rules();
    test_whitespace_and_skipped_lines();
    test_numbers();
    test_failures();
    return test_finish();
}

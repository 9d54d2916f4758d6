/*
 * tests/io/test_io_off.c -- the OFF reader: header variants, counts on the
 * header line, comments, colours, polygons, and every failure path.
 *
 * SPDX-License-Identifier: GPL-3.0-or-later
 */
#include "io/io.h"
#include "test_meshes.h"

#include <string.h>

static pz_mesh *read_ok(const char *text)
{
    return test_read_ok(pz_off_read_memory, text, strlen(text), "inline.off", "inline.off");
}

static void read_fails(const char *text, const char *expected)
{
    test_read_fails(pz_off_read_memory, text, strlen(text), "bad.off", expected);
}

/* Every variant describes the same square (a quad) plus one triangle. */
static void check_square(const char *text, const char *what)
{
    pz_mesh *mesh = read_ok(text);
    if (!mesh)
        return;
    CHECK(mesh->vertex_count == 5 && mesh->face_count == 3, "%s: counts %d/%d", what, mesh->vertex_count,
          mesh->face_count);
    static const int32_t faces[9] = {0, 1, 2, 0, 2, 3, 1, 4, 2};
    CHECK(memcmp(mesh->faces, faces, sizeof faces) == 0, "%s: faces", what);
    CHECK(mesh->positions[3] == 1.0 && mesh->positions[7] == 1.0 && mesh->positions[14] == -2.5, "%s: positions",
          what);
    CHECK(mesh->uvs == NULL && mesh->face_labels == NULL, "%s: no uvs, labels", what);
    pz_mesh_free(&mesh);
}

static void test_variants(void)
{
    check_square("OFF\n5 2 0\n0 0 0\n1 0 0\n1 1 0\n0 1 0\n2 0.5 -2.5\n4 0 1 2 3\n3 1 4 2\n", "OFF");
    check_square("OFF 5 2 7\n0 0 0\n1 0 0\n1 1 0\n0 1 0\n2 0.5 -2.5\n4 0 1 2 3\n3 1 4 2", "counts on header line");
    check_square("# a comment first\r\n\r\nCOFF\r\n# counts next\r\n5 2\r\n"
                 "0 0 0 255 0 0 255\r\n1 0 0 0 255 0 255\r\n1 1 0 0 0 255 255 # trailing comment\r\n"
                 "0 1 0 9 9 9 9\r\n2\t0.5 -2.5 1 1 1 1\r\n"
                 "4 0 1 2 3 255 0 0\r\n3 1 4 2 0.5 0.5 0.5 1\r\n",
                 "COFF with colours, comments, CRLF");
    check_square("NOFF\n5 2 0\n0 0 0 0 0 1\n1 0 0 0 0 1\n1 1 0 0 0 1\n0 1 0 0 0 1\n2 0.5 -2.5 0 0 1\n"
                 "4 0 1 2 3\n3 1 4 2\n",
                 "NOFF");
    check_square("STOFF\n5 2 0\n0 0 0 0 0\n1 0 0 1 0\n1 1 0 1 1\n0 1 0 0 1\n2 0.5 -2.5 2 0\n4 0 1 2 3\n3 1 4 2\n",
                 "STOFF");
    check_square("STCNOFF\n5 2 0\n0 0 0\n1 0 0\n1 1 0\n0 1 0\n2 0.5 -2.5\n4  0 1 2 3\n   3 1 4 2\n", "STCNOFF");
}

static void test_failures(void)
{
    read_fails("", "empty file");
    read_fails("# only a comment\n", "empty file");
    read_fails("garbage\n3 1 0\n", "line 1: not an OFF file");
    read_fails("4OFF\n3 1 0\n", "not an OFF file");
    read_fails("OFF BINARY\n", "binary OFF is not supported");
    read_fails("OFF\n", "no vertex and face counts");
    read_fails("OFF\nthree 1 0\n", "line 2: malformed counts");
    read_fails("OFF\n3 1 zero\n", "line 2: malformed counts");
    read_fails("OFF\n3 1 0\n0 0 0\n1 0 0\n", "truncated: 2 of 3 vertices");
    read_fails("OFF\n3 2 0\n0 0 0\n1 0 0\n0 1 0\n3 0 1 2\n", "truncated: 1 of 2 faces");
    read_fails("OFF\n3 1 0\n0 0 0\n1 0 0\n0 1 0\n3 0 1 3\n", "line 6: vertex index 3 out of range");
    read_fails("OFF\n3 1 0\n0 0 0\n1 0 0\n0 1 0\n3 0 1 -1\n", "line 6: malformed face");
    read_fails("OFF\n3 1 0\n0 0 0\n1 0 0\n0 1 0\n2 0 1\n", "line 6: face with fewer than 3 corners");
    read_fails("OFF\n3 1 0\n0 0 0\n1 0 0\n0 1 0\n4 0 1 2\n", "fewer indices than it declares");
    read_fails("OFF\n3 1 0\n0 0 0\n1 0 0\n0 1 0\n1000000 0 1 2\n", "fewer indices than it declares");
    read_fails("OFF\n3 1 0\n0 0 0\n1 x 0\n0 1 0\n3 0 1 2\n", "line 4: malformed vertex");
    read_fails("OFF\n3 0 0\n0 0 0\n1 0 0\n0 1 0\n", "no faces");
    /* A huge declared count is refused before allocating positions for it. */
    read_fails("OFF\n2000000000 1 0\n0 0 0\n", "larger than the file can hold");
    read_fails("OFF\n99999999999 1 0\n0 0 0\n", "malformed counts");
}

int main(void)
{
    test_variants();
    test_failures();
    return test_finish();
}

/*
 * tests/mesh/test_cut.c -- cutting a tube open along a line of edges (a disk
 * with one boundary loop and one copy more of every vertex on the line), an
 * empty cut changing nothing, and extracting half a grid with correct vertex,
 * face and UV maps; UVs, labels and poses carried through both.
 *
 * SPDX-License-Identifier: GPL-3.0-or-later
 */
#include "test_meshes.h"

#include <string.h>

static pz_ctx ctx;

/* Adds per-corner UVs (one per corner, (f, k)), labels (face parity, named)
 * and one pose (the rest pose shifted by +100 in z). */
static void decorate(pz_mesh *mesh)
{
    int32_t corners = 3 * mesh->face_count;
    mesh->uv_count = corners;
    mesh->uvs = malloc((size_t)corners * 2 * sizeof(double));
    mesh->corner_uvs = malloc((size_t)corners * sizeof(int32_t));
    mesh->face_labels = malloc((size_t)mesh->face_count * sizeof(int32_t));
    mesh->label_names = calloc(2, sizeof(char *));
    REQUIRE(mesh->uvs && mesh->corner_uvs && mesh->face_labels && mesh->label_names, "out of memory");
    mesh->label_count = 2;
    mesh->label_names[0] = test_strdup("front");
    mesh->label_names[1] = test_strdup("back");
    for (int32_t c = 0; c < corners; ++c) {
        mesh->corner_uvs[c] = c;
        mesh->uvs[2 * c] = c / 3;
        mesh->uvs[2 * c + 1] = c % 3;
    }
    for (int32_t f = 0; f < mesh->face_count; ++f)
        mesh->face_labels[f] = f % 2;
    double *pose = malloc((size_t)mesh->vertex_count * 3 * sizeof(double));
    REQUIRE(pose, "out of memory");
    for (int32_t i = 0; i < 3 * mesh->vertex_count; ++i)
        pose[i] = mesh->positions[i] + (i % 3 == 2 ? 100.0 : 0.0);
    REQUIRE_OK(pz_mesh_add_pose(mesh, pose, &ctx), ctx);
    free(pose);
}

static void test_cut_tube(void)
{
    const int columns = 8, rows = 3;
    pz_mesh *mesh = test_grid(columns, rows, TEST_GRID_TUBE, 0, &ctx);
    decorate(mesh);
    pz_topology *topology = test_topology(mesh, &ctx);
    /* Cut the vertical edges at angle 0: between (0, j) and (0, j + 1). */
    uint8_t *cut = calloc((size_t)topology->edge_count, 1);
    REQUIRE(cut, "out of memory");
    int cut_count = 0;
    for (int32_t e = 0; e < topology->edge_count; ++e) {
        int32_t h = topology->edge_halfedge[2 * e];
        int32_t a = pz_he_from(topology, h), b = pz_he_to(topology, h);
        if (a % columns == 0 && b % columns == 0) {
            cut[e] = 1;
            ++cut_count;
        }
    }
    CHECK(cut_count == rows, "%d cut edges", cut_count);
    pz_mesh *opened = NULL;
    int32_t *vertex_map = NULL;
    REQUIRE_OK(pz_mesh_cut(mesh, topology, cut, &opened, &vertex_map, &ctx), ctx);
    CHECK(opened->vertex_count == mesh->vertex_count + rows + 1, "vertices %d: one copy more per vertex on the line",
          (int)opened->vertex_count);
    CHECK(opened->face_count == mesh->face_count, "faces kept");
    pz_topology_summary s = test_summary(opened, &ctx);
    CHECK(s.boundary_loop_count == 1 && s.euler_characteristic == 1 && s.genus == 0 && s.component_count == 1,
          "a disk: loops %d chi %d genus %d", (int)s.boundary_loop_count, (int)s.euler_characteristic, (int)s.genus);
    int map_ok = 1, copies_on_line = 1, faces_ok = 1, pose_ok = 1;
    for (int32_t v = 0; v < opened->vertex_count; ++v) {
        int32_t o = vertex_map[v];
        map_ok &= o >= 0 && o < mesh->vertex_count && (v >= mesh->vertex_count || o == v);
        if (v >= mesh->vertex_count)
            copies_on_line &= o % columns == 0;
        for (int k = 0; k < 3; ++k) {
            map_ok &= opened->positions[3 * v + k] == mesh->positions[3 * o + k];
            pose_ok &= opened->poses[3 * v + k] == mesh->poses[3 * o + k];
        }
    }
    for (int32_t c = 0; c < 3 * mesh->face_count; ++c)
        faces_ok &= vertex_map[opened->faces[c]] == mesh->faces[c];
    CHECK(map_ok, "first copies keep their index; positions follow the map");
    CHECK(copies_on_line, "new vertices are copies of vertices on the cut");
    CHECK(faces_ok, "faces point at copies of their original vertices");
    CHECK(opened->pose_count == 1 && pose_ok, "pose carried");
    CHECK(opened->uv_count == mesh->uv_count && memcmp(opened->corner_uvs, mesh->corner_uvs,
                                                        (size_t)mesh->face_count * 3 * sizeof(int32_t)) == 0,
          "corner UVs carried");
    CHECK(opened->label_count == 2 && strcmp(opened->label_names[1], "back") == 0 &&
              opened->face_labels[5] == 1 && opened->label_names[1] != mesh->label_names[1],
          "labels carried (names copied)");

    /* Cutting along nothing gives back the same mesh. */
    pz_mesh *same = NULL;
    memset(cut, 0, (size_t)topology->edge_count);
    REQUIRE_OK(pz_mesh_cut(mesh, topology, cut, &same, NULL, &ctx), ctx);
    CHECK(same->vertex_count == mesh->vertex_count &&
              memcmp(same->faces, mesh->faces, (size_t)mesh->face_count * 3 * sizeof(int32_t)) == 0,
          "an empty cut changes nothing");
    pz_mesh_free(&same);

    /* Cutting every edge separates every face. */
    memset(cut, 1, (size_t)topology->edge_count);
    REQUIRE_OK(pz_mesh_cut(mesh, topology, cut, &same, NULL, &ctx), ctx);
    CHECK(same->vertex_count == 3 * mesh->face_count, "all edges cut: 3 vertices per face, got %d",
          (int)same->vertex_count);
    s = test_summary(same, &ctx);
    CHECK(s.component_count == mesh->face_count, "all edges cut: one component per face");
    pz_mesh_free(&same);

    free(cut);
    free(vertex_map);
    pz_mesh_free(&opened);
    pz_topology_free(&topology);
    pz_mesh_free(&mesh);
}

static void test_extract(void)
{
    /* Take the faces of the first half of the columns (i < 4) of the tube, in
     * reverse order, so the maps are not the identity. */
    const int columns = 8, rows = 2;
    pz_mesh *mesh = test_grid(columns, rows, TEST_GRID_TUBE, 0, &ctx);
    decorate(mesh);
    int32_t face_ids[16], count = 0;
    for (int32_t f = mesh->face_count - 1; f >= 0; --f)
        if ((f / 2) % columns < 4)
            face_ids[count++] = f;
    REQUIRE(count == 16, "16 faces chosen");
    pz_mesh *panel = NULL;
    int32_t *vertex_map = NULL, *face_map = NULL;
    REQUIRE_OK(pz_mesh_extract(mesh, face_ids, count, &panel, &vertex_map, &face_map, &ctx), ctx);
    CHECK(panel->face_count == 16 && panel->vertex_count == 15, "5 x 3 vertices, 16 faces: %d %d",
          (int)panel->vertex_count, (int)panel->face_count);
    int faces_ok = 1, positions_ok = 1, uvs_ok = 1, labels_ok = 1, pose_ok = 1, first_use = 1;
    int32_t seen = 0;
    for (int32_t i = 0; i < count; ++i) {
        faces_ok &= face_map[i] == face_ids[i];
        labels_ok &= panel->face_labels[i] == mesh->face_labels[face_ids[i]];
        for (int k = 0; k < 3; ++k) {
            int32_t v = panel->faces[3 * i + k];
            faces_ok &= vertex_map[v] == mesh->faces[3 * face_ids[i] + k];
            if (v == seen)
                ++seen;
            first_use &= v < seen;  /* never jumps ahead: numbered in order of first use */
            const double *uv = panel->uvs + 2 * panel->corner_uvs[3 * i + k];
            const double *original_uv = mesh->uvs + 2 * mesh->corner_uvs[3 * face_ids[i] + k];
            uvs_ok &= uv[0] == original_uv[0] && uv[1] == original_uv[1];
        }
    }
    for (int32_t v = 0; v < panel->vertex_count; ++v)
        for (int k = 0; k < 3; ++k) {
            positions_ok &= panel->positions[3 * v + k] == mesh->positions[3 * vertex_map[v] + k];
            pose_ok &= panel->poses[3 * v + k] == mesh->poses[3 * vertex_map[v] + k];
        }
    CHECK(faces_ok, "face map and vertex map agree with the original faces");
    CHECK(first_use, "panel vertices numbered in order of first use");
    CHECK(positions_ok && pose_ok && panel->pose_count == 1, "positions and pose follow the vertex map");
    CHECK(panel->uv_count == 48 && uvs_ok, "UVs compacted to the %d used, values kept", (int)panel->uv_count);
    CHECK(labels_ok && panel->label_count == 2 && strcmp(panel->label_names[0], "front") == 0, "labels carried");
    pz_topology_summary s = test_summary(panel, &ctx);
    CHECK(s.boundary_loop_count == 1 && s.euler_characteristic == 1, "half a tube is a disk");
    free(vertex_map);
    free(face_map);
    pz_mesh_free(&panel);

    /* Maps are optional; a bad face id is a usage error with nothing allocated. */
    REQUIRE_OK(pz_mesh_extract(mesh, face_ids, 2, &panel, NULL, NULL, &ctx), ctx);
    CHECK(panel->face_count == 2, "extract without maps");
    pz_mesh_free(&panel);
    int32_t bad_ids[2] = {0, 999};
    panel = mesh;
    vertex_map = face_ids;
    CHECK(pz_mesh_extract(mesh, bad_ids, 2, &panel, &vertex_map, NULL, &ctx) == PZ_ERR_USAGE, "bad face id refused");
    CHECK(panel == NULL && vertex_map == NULL, "outputs NULL on failure");
    CHECK(strstr(ctx.error, "999") != NULL, "message names the id: %s", ctx.error);
    pz_mesh_free(&mesh);
}

int main(void)
{
    pz_ctx_init(&ctx);
    ctx.quiet = 1;
    test_cut_tube();
    test_extract();
    return test_finish();
}

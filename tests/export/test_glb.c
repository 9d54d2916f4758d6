/*
 * tests/export/test_glb.c -- garment.glb (pz_export_write_glb) on a bodice
 * cut into 4 panels, pieces from pz_pieces_build, nested by pz_marker_build:
 *  - read back through our glTF reader: the cut mesh's vertices and faces,
 *    positions equal to the garment's in metres (glTF's unit: x 0.001, float
 *    precision), and the POSITION accessor's min/max = the garment's box in
 *    metres (a bodice well under 2 m, not 1000x);
 *  - COLOR_0: no two panels that share a seam have the same colour (4 and
 *    13 sectors: a palette cycled by panel index would fail the 13);
 *  - pieces the marker leaves out (a fabric narrower than the widest piece)
 *    are laid out after the marker (v > 1), each keeping its shape, apart
 *    from one another, none at (0, 0);
 *  - TEXCOORD_0 of every corner = its uv through its piece's marker placement
 *    divided by the fabric width and marker length (within float
 *    precision), all inside [0, 1];
 *  - the second piece of a mirrored pair (made so by hand) lands on its
 *    partner's mirrored copy: sew-line centroids within 5 mm, inside the
 *    marker;
 *  - COLOR_0 and a LINES primitive (the seams) are in the file;
 *  - a garment name that is not UTF-8 is written with '?'; a stream that
 *    cannot be written gives PZ_ERR_CREATE.
 * With PZ_GLB_OUT set, the GLBs are also written there for
 * tests/export/test_glb_validator.sh (the Khronos validator).
 *
 * SPDX-License-Identifier: GPL-3.0-or-later
 */
#define _POSIX_C_SOURCE 200809L
#include "io/io.h"
#include "fixture_export_b.h"

#include <stdio.h>

static pz_ctx ctx;

/* The GLB bytes of the writer (malloc'd). */
static unsigned char *write_glb(const pz_export_inputs *inputs, size_t *size, const char *sample)
{
    FILE *file = tmpfile();
    REQUIRE(file, "tmpfile");
    REQUIRE_OK(pz_export_write_glb(file, inputs, "garment.glb", &ctx), ctx);
    long length = ftell(file);
    REQUIRE(length > 20, "empty GLB");
    rewind(file);
    unsigned char *bytes = malloc((size_t)length);
    REQUIRE(bytes && fread(bytes, 1, (size_t)length, file) == (size_t)length, "read back");
    fclose(file);
    *size = (size_t)length;
    const char *out_dir = getenv("PZ_GLB_OUT");
    if (out_dir && *out_dir) {
        char path[1024];
        snprintf(path, sizeof path, "%s/%s.glb", out_dir, sample);
        FILE *copy = fopen(path, "wb");
        REQUIRE(copy && fwrite(bytes, 1, *size, copy) == *size && fclose(copy) == 0, "cannot write %s", path);
    }
    return bytes;
}

/* The JSON chunk as a string (malloc'd). */
static char *glb_json(const unsigned char *bytes, size_t size)
{
    uint32_t length;
    REQUIRE(size > 20 && memcmp(bytes, "glTF", 4) == 0, "not a GLB");
    memcpy(&length, bytes + 12, 4);
    REQUIRE(20 + (size_t)length <= size, "bad JSON chunk");
    char *json = malloc((size_t)length + 1);
    REQUIRE(json, "out of memory");
    memcpy(json, bytes + 20, length);
    json[length] = 0;
    return json;
}

/* The floats of accessor `index` (malloc'd, count x components), from the GLB's JSON and BIN chunk. */
static float *accessor_floats(const unsigned char *bytes, size_t size, const cJSON *root, int index, int *count,
                              int components)
{
    uint32_t json_length, bin_length;
    memcpy(&json_length, bytes + 12, 4);
    REQUIRE(28 + (size_t)json_length <= size, "no BIN chunk");
    memcpy(&bin_length, bytes + 20 + json_length, 4);
    const unsigned char *bin = bytes + 28 + json_length;
    const cJSON *accessor = cJSON_GetArrayItem(cJSON_GetObjectItem(root, "accessors"), index);
    const cJSON *view = cJSON_GetArrayItem(cJSON_GetObjectItem(root, "bufferViews"),
                                           cJSON_GetObjectItem(accessor, "bufferView")->valueint);
    const cJSON *accessor_offset = cJSON_GetObjectItem(accessor, "byteOffset");
    const cJSON *view_offset = cJSON_GetObjectItem(view, "byteOffset");
    size_t offset = (size_t)(accessor_offset ? accessor_offset->valueint : 0) +
                    (size_t)(view_offset ? view_offset->valueint : 0);
    *count = cJSON_GetObjectItem(accessor, "count")->valueint;
    size_t length = (size_t)*count * (size_t)components * sizeof(float);
    REQUIRE(cJSON_GetObjectItem(accessor, "componentType")->valueint == 5126 && offset + length <= bin_length,
            "accessor %d is not %d floats in the BIN chunk", index, *count * components);
    float *values = malloc(length + 1);
    REQUIRE(values, "out of memory");
    memcpy(values, bin + offset, length);
    return values;
}

/* The index of attribute `name` of the first primitive. */
static int attribute(const cJSON *root, const char *name)
{
    const cJSON *mesh = cJSON_GetArrayItem(cJSON_GetObjectItem(root, "meshes"), 0);
    const cJSON *primitive = cJSON_GetArrayItem(cJSON_GetObjectItem(mesh, "primitives"), 0);
    const cJSON *index = cJSON_GetObjectItem(cJSON_GetObjectItem(primitive, "attributes"), name);
    REQUIRE(cJSON_IsNumber(index), "no %s", name);
    return index->valueint;
}

/* Units and colours of a written GLB: POSITION's box is the cut mesh's in metres; panels sharing a seam differ
 * in COLOR_0. */
static void check_units_and_colours(const unsigned char *bytes, size_t size, const fixture_pattern *fixture)
{
    char *json = glb_json(bytes, size);
    cJSON *root = cJSON_Parse(json);
    REQUIRE(root, "GLB JSON does not parse");
    const pz_mesh *cut = fixture->pattern->mesh;
    const cJSON *accessor = cJSON_GetArrayItem(cJSON_GetObjectItem(root, "accessors"), attribute(root, "POSITION"));
    const cJSON *min = cJSON_GetObjectItem(accessor, "min"), *max = cJSON_GetObjectItem(accessor, "max");
    double worst = 0, extent = 0;
    for (int d = 0; d < 3; ++d) {
        double lo = INFINITY, hi = -INFINITY;
        for (int32_t v = 0; v < cut->vertex_count; ++v) {
            lo = fmin(lo, cut->positions[3 * v + d]);
            hi = fmax(hi, cut->positions[3 * v + d]);
        }
        worst = fmax(worst, fmax(fabs(cJSON_GetArrayItem(min, d)->valuedouble - lo / 1000),
                                 fabs(cJSON_GetArrayItem(max, d)->valuedouble - hi / 1000)));
        extent = fmax(extent, cJSON_GetArrayItem(max, d)->valuedouble - cJSON_GetArrayItem(min, d)->valuedouble);
    }
    printf("POSITION box: largest extent %.3f m, min/max within %.1e m of the garment's box in metres\n", extent,
           worst);
    CHECK(worst < 1e-6 && extent > 0.1 && extent < 2.0, "POSITION box off by %g m, extent %g m (not metres?)", worst,
          extent);

    int count = 0;
    float *colours = accessor_floats(bytes, size, root, attribute(root, "COLOR_0"), &count, 3);
    REQUIRE(count == cut->vertex_count, "%d colours for %d vertices", count, (int)cut->vertex_count);
    float *panel_colour = calloc(3 * (size_t)fixture->pattern->panel_count + 1, sizeof(float));
    REQUIRE(panel_colour, "out of memory");
    int mixed = 0;
    for (int32_t f = 0; f < cut->face_count; ++f)
        for (int k = 0; k < 3; ++k) {
            const float *c = &colours[3 * cut->faces[3 * f + k]];
            float *p = &panel_colour[3 * fixture->pattern->face_panel[f]];
            if (f > 0 && p[0] + p[1] + p[2] > 0)
                mixed += p[0] != c[0] || p[1] != c[1] || p[2] != c[2];
            memcpy(p, c, 3 * sizeof(float));
        }
    int same = 0;
    for (int32_t s = 0; s < fixture->pattern->seam_count; ++s) {
        const pz_seam *seam = &fixture->pattern->seams[s];
        const float *a = &panel_colour[3 * seam->panel_a], *b = &panel_colour[3 * seam->panel_b];
        same += seam->panel_a != seam->panel_b && a[0] == b[0] && a[1] == b[1] && a[2] == b[2];
    }
    CHECK(mixed == 0 && same == 0, "%d vertices off their panel's colour, %d seams between panels of one colour",
          mixed, same);
    free(panel_colour);
    free(colours);
    cJSON_Delete(root);
    free(json);
}

/* The piece of each panel (-1 none). */
static int32_t piece_of_panel(const pz_pieces *pieces, int32_t panel)
{
    for (int32_t p = 0; p < pieces->piece_count; ++p)
        if (pieces->pieces[p].panel == panel)
            return p;
    return -1;
}

static void polygon_centroid(const double *p, int32_t n, double out[2])
{
    double area = 0, cx = 0, cy = 0;
    for (int32_t i = 0; i < n; ++i) {
        const double *a = &p[2 * i], *b = &p[2 * ((i + 1) % n)];
        double cross = a[0] * b[1] - b[0] * a[1];
        area += cross, cx += (a[0] + b[0]) * cross, cy += (a[1] + b[1]) * cross;
    }
    out[0] = cx / (3 * area), out[1] = cy / (3 * area);
}

static const pz_marker_placement *placement_of(const pz_marker *marker, int32_t piece, int32_t copy)
{
    for (int32_t i = 0; i < marker->placement_count; ++i)
        if (marker->placements[i].piece == piece && marker->placements[i].copy == copy)
            return &marker->placements[i];
    return NULL;
}

static void test_bodice(void)
{
    fixture_pattern fixture;
    fixture_pattern_build(&fixture, 3000, 4);
    fixture_pattern_export(&fixture);
    pz_pieces *pieces = fixture.pieces;
    const pz_marker *marker = fixture.marker;
    pz_export_inputs inputs = fixture.inputs;
    size_t size;
    unsigned char *bytes = write_glb(&inputs, &size, "bodice");
    char *json = glb_json(bytes, size);
    CHECK(strstr(json, "\"COLOR_0\"") && strstr(json, "\"TEXCOORD_0\"") && strstr(json, "\"mode\":1"),
          "COLOR_0, TEXCOORD_0 or the LINES primitive missing");
    free(json);
    check_units_and_colours(bytes, size, &fixture);

    pz_mesh *back = NULL;
    REQUIRE_OK(pz_gltf_read_memory(bytes, size, 1, NULL, "garment.glb", &back, &ctx), ctx);
    const pz_mesh *cut = fixture.pattern->mesh;
    CHECK(back->vertex_count == cut->vertex_count && back->face_count == cut->face_count, "%d/%d vertices",
          (int)back->vertex_count, (int)cut->vertex_count);
    REQUIRE(back->corner_uvs != NULL, "no UVs read back");
    double worst_position = 0, worst_uv = 0, lo = INFINITY, hi = -INFINITY;
    for (int32_t f = 0; f < back->face_count && back->face_count == cut->face_count; ++f) {
        int32_t panel = fixture.pattern->face_panel[f];
        int32_t piece = piece_of_panel(pieces, panel);
        const pz_marker_placement *placement = placement_of(marker, piece, 0);
        REQUIRE(placement, "panel %d has no placement", (int)panel);
        for (int k = 0; k < 3; ++k) {
            int32_t v = cut->faces[3 * f + k], w = back->faces[3 * f + k];
            for (int d = 0; d < 3; ++d)
                worst_position =
                    fmax(worst_position, fabs(1000 * back->positions[3 * w + d] - cut->positions[3 * v + d]));
            double placed[2];
            pz_marker_place_points(&pieces->pieces[piece], placement, &fixture.uv[2 * v], 1, placed);
            const double *uv = &back->uvs[2 * back->corner_uvs[3 * f + k]];
            worst_uv = fmax(worst_uv, fmax(fabs(uv[0] * marker->fabric_width_mm - placed[0]),
                                           fabs(uv[1] * marker->length_mm - placed[1])));
            lo = fmin(lo, fmin(uv[0], uv[1]));
            hi = fmax(hi, fmax(uv[0], uv[1]));
        }
    }
    printf("bodice.glb: %zu bytes, worst position %.2g mm, worst texcoord %.2g mm, range [%.4f, %.4f]\n", size,
           worst_position, worst_uv, lo, hi);
    CHECK(worst_position < 1e-3, "positions off by %g", worst_position);
    CHECK(worst_uv < 1e-3 * fmax(marker->fabric_width_mm, marker->length_mm), "texcoords off by %g mm", worst_uv);
    CHECK(lo >= -1e-6 && hi <= 1 + 1e-6, "texcoords outside [0, 1]: %g %g", lo, hi);
    pz_mesh_free(&back);
    free(bytes);

    /* Panels 0 and 1 made a mirrored pair by hand: panel 1 is drawn on piece 0's mirrored copy. */
    pieces->pieces[0].cut_quantity = 2, pieces->pieces[0].mirror_piece = 1;
    pieces->pieces[1].mirrored = 1, pieces->pieces[1].mirror_piece = 0;
    pz_marker *paired = NULL;
    REQUIRE_OK(pz_marker_build(pieces, &fixture.options, &paired, &ctx), ctx);
    inputs.marker = paired;
    bytes = write_glb(&inputs, &size, "bodice_pair");
    REQUIRE_OK(pz_gltf_read_memory(bytes, size, 1, NULL, "garment.glb", &back, &ctx), ctx);
    const pz_marker_placement *copy = placement_of(paired, 0, 1);
    REQUIRE(copy && copy->mirrored, "no mirrored copy");
    /* Sew-line area centroids: the mirrored panel's (from its texcoords) and its partner's mirrored copy. */
    const pz_piece *first = &pieces->pieces[0], *second = &pieces->pieces[1];
    double *points = malloc((size_t)(first->sew_count > second->sew_count ? first->sew_count : second->sew_count) *
                            2 * sizeof(double));
    REQUIRE(points, "out of memory");
    pz_marker_place_points(first, copy, first->sew, first->sew_count, points);
    double expected[2], got[2];
    polygon_centroid(points, first->sew_count, expected);
    int32_t *corner_of_vertex = malloc((size_t)cut->vertex_count * sizeof(int32_t));
    REQUIRE(corner_of_vertex, "out of memory");
    for (int32_t f = 0; f < back->face_count; ++f)
        for (int k = 0; k < 3; ++k)
            corner_of_vertex[back->faces[3 * f + k]] = 3 * f + k; /* row v of the GLB is cut-mesh vertex v */
    for (int32_t i = 0; i < second->sew_count; ++i) {
        const double *uv = &back->uvs[2 * back->corner_uvs[corner_of_vertex[second->sew_vertex[i]]]];
        points[2 * i] = uv[0] * paired->fabric_width_mm, points[2 * i + 1] = uv[1] * paired->length_mm;
        CHECK(uv[0] >= -1e-6 && uv[0] <= 1 + 1e-6 && uv[1] >= -1e-6 && uv[1] <= 1 + 1e-6, "outside the marker");
    }
    polygon_centroid(points, second->sew_count, got);
    free(points);
    free(corner_of_vertex);
    double miss = hypot(got[0] - expected[0], got[1] - expected[1]);
    printf("mirrored panel: sew centroid (%.1f, %.1f), partner's mirrored copy (%.1f, %.1f): %.2f mm apart\n", got[0],
           got[1], expected[0], expected[1], miss);
    CHECK(miss < 5.0, "mirrored panel %.1f mm away from its copy", miss);
    pz_mesh_free(&back);
    free(bytes);

    /* A garment name that is not UTF-8 (a Latin-1 file name): still written, with '?'. */
    snprintf(pieces->garment_name, sizeof pieces->garment_name, "robe_d\xe9" "t\xe9");
    bytes = write_glb(&inputs, &size, "latin1");
    char *named = glb_json(bytes, size);
    CHECK(strstr(named, "robe_d?t?") != NULL, "name not cleaned");
    free(named);
    free(bytes);

    /* A stream that fails. */
    FILE *full = fopen("/dev/full", "wb");
    if (full) {
        CHECK(pz_export_write_glb(full, &inputs, "full.glb", &ctx) == PZ_ERR_CREATE && strstr(ctx.error, "full.glb"),
              "%s", ctx.error);
        fclose(full);
    }
    pz_marker_free(&paired);
    fixture_pattern_free(&fixture);
}

/*
 * Pieces wider than the fabric are left out of the marker: they get a layout of their own after its end (v > 1),
 * each piece's texcoords its uv moved by one translation, the pieces' boxes apart, none at (0, 0).
 */
static void test_left_out(void)
{
    fixture_pattern fixture;
    fixture_pattern_build(&fixture, 3000, 13);   /* 13 sectors: a 12-colour cycle would give 12 and 0 one colour */
    fixture_pattern_export(&fixture);
    pz_pieces *pieces = fixture.pieces;
    double narrowest = INFINITY, widest = 0;
    for (int32_t p = 0; p < pieces->piece_count; ++p) {
        double width = pieces->pieces[p].bbox_max[0] - pieces->pieces[p].bbox_min[0];
        narrowest = fmin(narrowest, width), widest = fmax(widest, width);
    }
    fixture.options.fabric_width_mm = 0.5 * (narrowest + widest);
    pz_marker *marker = NULL;
    REQUIRE_OK(pz_marker_build(pieces, &fixture.options, &marker, &ctx), ctx);
    REQUIRE(marker->unplaced_count > 0, "no piece left out of a %.0f mm fabric", fixture.options.fabric_width_mm);
    pz_export_inputs inputs = fixture.inputs;
    inputs.marker = marker;
    size_t size;
    unsigned char *bytes = write_glb(&inputs, &size, "bodice_left_out");
    check_units_and_colours(bytes, size, &fixture);
    pz_mesh *back = NULL;
    REQUIRE_OK(pz_gltf_read_memory(bytes, size, 1, NULL, "garment.glb", &back, &ctx), ctx);
    const pz_mesh *cut = fixture.pattern->mesh;
    REQUIRE(back->face_count == cut->face_count && back->corner_uvs, "read back");
    /* Per left-out piece: its texcoords' box (mm) and how far they stray from one translation of its uv. */
    int32_t n = marker->unplaced_count;
    double *box = malloc(4 * (size_t)n * sizeof(double) + 1), *shift = malloc(2 * (size_t)n * sizeof(double) + 1);
    REQUIRE(box && shift, "out of memory");
    for (int32_t i = 0; i < n; ++i)
        box[4 * i] = box[4 * i + 1] = INFINITY, box[4 * i + 2] = box[4 * i + 3] = -INFINITY, shift[2 * i] = NAN;
    double worst_shape = 0;
    for (int32_t f = 0; f < cut->face_count; ++f) {
        int32_t i = 0;
        while (i < n && marker->unplaced[i] != piece_of_panel(pieces, fixture.pattern->face_panel[f]))
            ++i;
        if (i == n)
            continue;
        for (int k = 0; k < 3; ++k) {
            const double *tc = &back->uvs[2 * back->corner_uvs[3 * f + k]];
            const double *uv = &fixture.uv[2 * cut->faces[3 * f + k]];
            double at[2] = {tc[0] * marker->fabric_width_mm, tc[1] * marker->length_mm};
            if (isnan(shift[2 * i]))
                shift[2 * i] = at[0] - uv[0], shift[2 * i + 1] = at[1] - uv[1];
            worst_shape = fmax(worst_shape, hypot(at[0] - uv[0] - shift[2 * i], at[1] - uv[1] - shift[2 * i + 1]));
            box[4 * i] = fmin(box[4 * i], at[0]), box[4 * i + 1] = fmin(box[4 * i + 1], at[1]);
            box[4 * i + 2] = fmax(box[4 * i + 2], at[0]), box[4 * i + 3] = fmax(box[4 * i + 3], at[1]);
        }
    }
    int overlaps = 0;
    for (int32_t i = 0; i < n; ++i) {
        CHECK(box[4 * i + 1] > marker->length_mm, "left-out piece %d at v %.1f mm, inside the %.1f mm marker",
              (int)marker->unplaced[i], box[4 * i + 1], marker->length_mm);
        for (int32_t j = 0; j < i; ++j)
            overlaps += box[4 * i] < box[4 * j + 2] && box[4 * j] < box[4 * i + 2] && box[4 * i + 1] < box[4 * j + 3] &&
                        box[4 * j + 1] < box[4 * i + 3];
    }
    printf("left out of a %.0f mm fabric: %d pieces, after the %.0f mm marker, shapes kept within %.1e mm\n",
           marker->fabric_width_mm, (int)n, marker->length_mm, worst_shape);
    CHECK(worst_shape < 1e-3 * marker->length_mm && overlaps == 0, "shape off by %g mm, %d overlaps", worst_shape,
          overlaps);
    free(box);
    free(shift);
    pz_mesh_free(&back);
    free(bytes);
    pz_marker_free(&marker);
    fixture_pattern_free(&fixture);
}

int main(void)
{
    ctx.quiet = 1; /* the reader notes the LINES primitive it skips */
    test_bodice();
    test_left_out();
    return test_finish();
}

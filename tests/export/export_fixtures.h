/*
 * tests/export/export_fixtures.h -- flattened patterns for the export tests:
 * a generated garment cut into halves or quarters around its vertical axis
 * (with the mirror map of the halves), and the shared real garments (their
 * own UV panels where the file carries a true pattern, else two halves).
 *
 * Needs test_util.h, param/param.h, export/export.h.
 *
 * SPDX-License-Identifier: GPL-3.0-or-later
 */
#ifndef PZ_TEST_EXPORT_FIXTURES_H
#define PZ_TEST_EXPORT_FIXTURES_H

#include "export/export.h"
#include "generate/generate.h"
#include "io/io.h"
#include "param/param.h"
#include "../test_util.h"

#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

typedef struct fixture {
    pz_mesh *garment;
    pz_pattern *pattern;
    double *uv;
    int32_t *panel_mirror;   /* panel_count, or NULL */
} fixture;

static inline void fixture_free(fixture *f)
{
    pz_pattern_free(&f->pattern);
    pz_mesh_free(&f->garment);
    free(f->uv);
    free(f->panel_mirror);
    memset(f, 0, sizeof *f);
}

/* The two horizontal axes (not the garment's vertical) and the centroid. */
static inline void fixture_axes(const pz_mesh *mesh, int *first, int *second, double centre[3])
{
    double up[3];
    pz_mesh_vertical_axis(mesh, up);
    int vertical = fabs(up[1]) > fabs(up[2]) ? 1 : 2;
    *first = 0;
    *second = vertical == 1 ? 2 : 1;
    for (int k = 0; k < 3; ++k)
        centre[k] = 0;
    for (int32_t v = 0; v < mesh->vertex_count; ++v)
        for (int k = 0; k < 3; ++k)
            centre[k] += mesh->positions[3 * v + k] / mesh->vertex_count;
}

/*
 * Panels by the side of the centre each face's centroid lies on: along the
 * first horizontal axis (2 panels), and with `quarters` along the second too
 * (4). The mirror map pairs panels across the first axis' plane.
 */
static inline void fixture_split(fixture *f, int quarters, int32_t *face_panel, int32_t *panel_count)
{
    int first, second;
    double centre[3];
    fixture_axes(f->garment, &first, &second, centre);
    for (int32_t t = 0; t < f->garment->face_count; ++t) {
        double c[3] = {0, 0, 0};
        for (int k = 0; k < 3; ++k)
            for (int d = 0; d < 3; ++d)
                c[d] += f->garment->positions[3 * f->garment->faces[3 * t + k] + d] / 3;
        int side = c[first] >= centre[first], half = quarters && c[second] >= centre[second];
        face_panel[t] = side + 2 * half;
    }
    *panel_count = quarters ? 4 : 2;
    f->panel_mirror = malloc(4 * sizeof(int32_t));
    REQUIRE(f->panel_mirror, "out of memory");
    for (int32_t p = 0; p < 4; ++p)
        f->panel_mirror[p] = p ^ 1;
}

/* Builds the pattern from face_panel (and optional extra cuts) and flattens it (textile or LSCM). */
static inline void fixture_flatten(fixture *f, const int32_t *face_panel, const uint8_t *cuts, const char *path,
                            int textile)
{
    pz_ctx ctx = {0};
    REQUIRE_OK(pz_pattern_build(f->garment, face_panel, cuts, NULL, path, &f->pattern, &ctx), ctx);
    f->uv = malloc(2 * (size_t)f->pattern->mesh->vertex_count * sizeof(double) + 1);
    REQUIRE(f->uv, "out of memory");
    pz_textile_options options = {.grain_given = 1};
    pz_mesh_vertical_axis(f->garment, options.grain);   /* the warp runs down the body */
    if (textile)
        REQUIRE_OK(pz_param_textile(f->pattern, &options, f->uv, NULL, &ctx), ctx);
    else
        REQUIRE_OK(pz_param_lscm_pattern(f->pattern, options.grain, f->uv, &ctx), ctx);
}

/* A generated garment in halves or quarters, flattened with the textile back-end. */
static inline fixture fixture_generated(pz_shape shape, int32_t faces, int quarters)
{
    pz_ctx ctx = {0};
    fixture f = {0};
    pz_generate_options options = {.target_faces = faces};
    REQUIRE_OK(pz_generate(shape, &options, &f.garment, &ctx), ctx);
    int32_t *face_panel = malloc((size_t)f.garment->face_count * sizeof(int32_t)), panel_count = 0;
    REQUIRE(face_panel, "out of memory");
    fixture_split(&f, quarters, face_panel, &panel_count);
    fixture_flatten(&f, face_panel, NULL, pz_shape_name(shape), 1);
    free(face_panel);
    return f;
}

/*
 * Panel ids from the `g panel_K` groups of a garment.obj that panelize wrote
 * (the same numbers as its pieces), when every face has such a group;
 * face_panel is left alone otherwise.
 */
static inline void fixture_panels_from_groups(const pz_mesh *mesh, int32_t *face_panel)
{
    if (!mesh->face_labels || !mesh->label_names)
        return;
    for (int32_t l = 0; l < mesh->label_count; ++l) {
        int id = -1, consumed = 0;
        if (!mesh->label_names[l] || sscanf(mesh->label_names[l], "panel_%d%n", &id, &consumed) != 1 ||
            mesh->label_names[l][consumed] != '\0' || id < 0)
            return;
    }
    for (int32_t t = 0; t < mesh->face_count; ++t) {
        int id = -1;
        sscanf(mesh->label_names[mesh->face_labels[t]], "panel_%d", &id);
        face_panel[t] = id;
    }
}

/* f->pattern from f->garment's UV islands (use_uv; numbered by the `g panel_K` groups when it has them) or two
 * halves. 0 when it cannot be built (printed, f freed). */
static inline int fixture_pattern_of(fixture *f, const char *path, int use_uv)
{
    pz_ctx ctx = {0};
    int32_t *face_panel = malloc((size_t)f->garment->face_count * sizeof(int32_t) + 1), panel_count = 0;
    uint8_t *cuts = NULL;
    REQUIRE(face_panel, "out of memory");
    pz_status status = PZ_OK;
    if (use_uv)
        status = pz_pattern_panels_from_uv(f->garment, face_panel, &panel_count, &cuts, &ctx);
    else
        fixture_split(f, 0, face_panel, &panel_count);
    if (status == PZ_OK && use_uv)
        fixture_panels_from_groups(f->garment, face_panel);
    if (status == PZ_OK)
        status = pz_pattern_build(f->garment, face_panel, cuts, NULL, path, &f->pattern, &ctx);
    free(face_panel);
    free(cuts);
    if (status != PZ_OK) {
        printf("  %s: no pattern: %s\n", path, ctx.error);
        fixture_free(f);
        return 0;
    }
    f->uv = malloc(2 * (size_t)f->pattern->mesh->vertex_count * sizeof(double) + 1);
    REQUIRE(f->uv, "out of memory");
    return 1;
}

/* A shared garment: its UV panels when use_uv, else two halves; LSCM. 0 when it cannot be built (printed). */
static inline int fixture_shared(fixture *f, const char *path, int use_uv)
{
    pz_ctx ctx = {0};
    memset(f, 0, sizeof *f);
    if (pz_mesh_read(path, &f->garment, &ctx) != PZ_OK) {
        printf("  %s: cannot read: %s\n", path, ctx.error);
        return 0;
    }
    pz_mesh_to_mm(f->garment, PZ_UNITS_AUTO, NULL);
    if (!fixture_pattern_of(f, path, use_uv))
        return 0;
    double up[3];
    pz_mesh_vertical_axis(f->garment, up);
    if (pz_param_lscm_pattern(f->pattern, up, f->uv, &ctx) != PZ_OK) {
        printf("  %s: not flattened: %s\n", path, ctx.error);
        fixture_free(f);
        return 0;
    }
    if (!use_uv) {
        free(f->panel_mirror);
        f->panel_mirror = NULL;   /* halves of a real scan are rarely mirror images */
    }
    return 1;
}

/*
 * The pattern a `panelize flatten` or `run` wrote as garment.obj: panels from
 * its vt (the pattern, mm), seams and darts found again by pz_pattern_build
 * (darts are the slits of the UV layout), uv = each cut-mesh corner's vt (the
 * cut mesh keeps the garment's face order). No mirror map. 0 when it cannot
 * be built (printed).
 */
static inline int fixture_from_pattern_obj(fixture *f, const char *path)
{
    pz_ctx ctx = {0};
    memset(f, 0, sizeof *f);
    if (pz_mesh_read(path, &f->garment, &ctx) != PZ_OK || !f->garment->corner_uvs) {
        printf("  %s: cannot read a pattern: %s\n", path, f->garment ? "no vt" : ctx.error);
        fixture_free(f);
        return 0;
    }
    pz_mesh_to_mm(f->garment, PZ_UNITS_AUTO, NULL);
    if (!fixture_pattern_of(f, path, 1))
        return 0;
    const pz_mesh *cut = f->pattern->mesh;
    for (int32_t t = 0; t < cut->face_count; ++t)
        for (int k = 0; k < 3; ++k) {
            const double *vt = &f->garment->uvs[2 * (size_t)f->garment->corner_uvs[3 * t + k]];
            f->uv[2 * (size_t)cut->faces[3 * t + k]] = vt[0];
            f->uv[2 * (size_t)cut->faces[3 * t + k] + 1] = vt[1];
        }
    return 1;
}

/* The shared garments: file name and whether its UVs are a true pattern (INVENTORY.md). */
static const struct {
    const char *file;
    int use_uv;
} fixture_garments[] = {
    {"diffavatar-tshirt.obj", 1}, {"diffavatar-shirt.obj", 1},   {"parafashion-skirt.obj", 1},
    {"parafashion-dress.ply", 0}, {"parafashion-leggings.ply", 0}, {"parafashion-shirt.obj", 0},
    {"parafashion-wetsuit.obj", 0}, {"shirtfront-panel.obj", 0},
};

#endif /* PZ_TEST_EXPORT_FIXTURES_H */

/*
 * pipeline/panels.c -- the user's own panels (pz_flatten, and pz_run with
 * panels given) on the loaded garment: one panel per connected piece of each
 * label (OBJ groups), one per label (joined panel files), the mesh's UV
 * islands, or per-face ids; and the user's seams and darts mapped from the
 * caller's vertex ids onto the prepared garment's.
 *
 * SPDX-License-Identifier: GPL-3.0-or-later
 */
#define _POSIX_C_SOURCE 200809L
#include "pipeline/internal.h"

#include <stdlib.h>
#include <string.h>

void pl_panel_choice_drop_names(pl_panel_choice *choice)
{
    if (choice->names)
        for (int32_t p = 0; p < choice->panel_count; ++p)
            free(choice->names[p]);
    free(choice->names);
    choice->names = NULL;
}

void pl_panel_choice_clear(pl_panel_choice *choice)
{
    free(choice->face_panel);
    free(choice->extra_cuts);
    pl_panel_choice_drop_names(choice);
    memset(choice, 0, sizeof *choice);
}

typedef struct face_key {
    int64_t key;    /* label << 32 | component */
    int32_t face;
} face_key;

static int compare_face_key(const void *a, const void *b)
{
    const face_key *x = a, *y = b;
    if (x->key != y->key)
        return (x->key > y->key) - (x->key < y->key);
    return (x->face > y->face) - (x->face < y->face);
}

static int compare_int64(const void *a, const void *b)
{
    int64_t x = *(const int64_t *)a, y = *(const int64_t *)b;
    return (x > y) - (x < y);
}

/*
 * One panel per connected piece of each label (group); ids in the order of
 * the pieces' first faces. Sorting (label, component, face) keys: O(F log F).
 */
static pz_status panels_from_groups(const pz_mesh *mesh, pl_panel_choice *choice, pz_ctx *ctx)
{
    int32_t face_count = mesh->face_count;
    int32_t *component = malloc(((size_t)face_count + 1) * sizeof(int32_t));
    face_key *keys = malloc(((size_t)face_count + 1) * sizeof *keys);
    int64_t *firsts = malloc(((size_t)face_count + 1) * sizeof *firsts);  /* first face << 32 | group */
    int32_t *group_label = malloc(((size_t)face_count + 1) * sizeof(int32_t));
    int32_t *group_rank = malloc(((size_t)face_count + 1) * sizeof(int32_t));
    pz_status status = PZ_OK;
    if (!component || !keys || !firsts || !group_label || !group_rank)
        status = pz_error(ctx, PZ_ERR_NOMEM, "flatten: out of memory finding panels");
    int32_t components = status == PZ_OK ? pz_mesh_face_components(mesh, component, ctx) : 0;
    if (status == PZ_OK && components < 0)
        status = (pz_status)components;
    int32_t group_count = 0;
    if (status == PZ_OK) {
        for (int32_t f = 0; f < face_count; ++f) {
            int64_t label = mesh->face_labels ? mesh->face_labels[f] : 0;
            keys[f] = (face_key){label << 32 | component[f], f};
        }
        qsort(keys, (size_t)face_count, sizeof *keys, compare_face_key);
        for (int32_t i = 0; i < face_count; ++i) {
            if (i == 0 || keys[i].key != keys[i - 1].key) {
                group_label[group_count] = (int32_t)(keys[i].key >> 32);
                firsts[group_count] = (int64_t)keys[i].face << 32 | group_count;
                ++group_count;
            }
            component[keys[i].face] = group_count - 1;  /* reused: the face's group */
        }
        qsort(firsts, (size_t)group_count, sizeof *firsts, compare_int64);
        for (int32_t rank = 0; rank < group_count; ++rank)
            group_rank[firsts[rank] & 0xffffffff] = rank;
        choice->face_panel = malloc(((size_t)face_count + 1) * sizeof(int32_t));
        choice->names = calloc((size_t)group_count + 1, sizeof(char *));
        if (!choice->face_panel || !choice->names)
            status = pz_error(ctx, PZ_ERR_NOMEM, "flatten: out of memory finding panels");
    }
    if (status == PZ_OK) {
        choice->panel_count = group_count;
        for (int32_t f = 0; f < face_count; ++f)
            choice->face_panel[f] = group_rank[component[f]];
        for (int32_t g = 0; g < group_count && mesh->label_names; ++g) {
            const char *name = mesh->label_names[group_label[g]];
            if (name && !(choice->names[group_rank[g]] = strdup(name)))
                status = pz_error(ctx, PZ_ERR_NOMEM, "flatten: out of memory finding panels");
        }
        choice->source = mesh->label_count > 1 ? "groups" : "components";
    }
    free(component);
    free(keys);
    free(firsts);
    free(group_label);
    free(group_rank);
    return status;
}

/* One panel per label (the labels pz_mesh_join set), named after the labels. */
static pz_status panels_from_labels(const pz_mesh *mesh, pl_panel_choice *choice, pz_ctx *ctx)
{
    if (!mesh->face_labels || mesh->label_count < 1)
        return panels_from_groups(mesh, choice, ctx);
    choice->face_panel = malloc(((size_t)mesh->face_count + 1) * sizeof(int32_t));
    choice->names = calloc((size_t)mesh->label_count + 1, sizeof(char *));
    if (!choice->face_panel || !choice->names)
        return pz_error(ctx, PZ_ERR_NOMEM, "flatten: out of memory finding panels");
    memcpy(choice->face_panel, mesh->face_labels, (size_t)mesh->face_count * sizeof(int32_t));
    choice->panel_count = mesh->label_count;
    for (int32_t p = 0; p < mesh->label_count; ++p)
        if (mesh->label_names && mesh->label_names[p] && !(choice->names[p] = strdup(mesh->label_names[p])))
            return pz_error(ctx, PZ_ERR_NOMEM, "flatten: out of memory finding panels");
    choice->source = "files";
    return PZ_OK;
}

/* The caller's per-face ids, mapped onto the prepared garment's faces (which must be the caller's). */
static pz_status panels_from_faces(const pz_panels *panels, const pl_garment *garment, pl_panel_choice *choice,
                                   pz_ctx *ctx)
{
    const char *name = panels->face_panel_name ? panels->face_panel_name : "the panel ids";
    if (!garment->ids_preserved)
        return pz_error(ctx, PZ_ERR_DATA, "%s: --repair removed faces, so the per-face panel ids no longer apply",
                        name);
    const pz_mesh *mesh = garment->mesh;
    if (!panels->face_panel || panels->panel_count < 1)
        return pz_error(ctx, PZ_ERR_USAGE, "%s: no panel ids", name);
    choice->face_panel = malloc(((size_t)mesh->face_count + 1) * sizeof(int32_t));
    uint8_t *used = calloc((size_t)panels->panel_count + 1, 1);
    pz_status status = PZ_OK;
    if (!choice->face_panel || !used)
        status = pz_error(ctx, PZ_ERR_NOMEM, "flatten: out of memory finding panels");
    for (int32_t f = 0; status == PZ_OK && f < mesh->face_count; ++f) {
        int32_t panel = panels->face_panel[f];
        if (panel < 0 || panel >= panels->panel_count)
            status = pz_error(ctx, PZ_ERR_DATA, "%s: face %d: panel id %d is out of range (%d panels)", name, (int)f,
                              (int)panel, (int)panels->panel_count);
        else
            choice->face_panel[f] = panel, used[panel] = 1;
    }
    for (int32_t p = 0; status == PZ_OK && p < panels->panel_count; ++p)
        if (!used[p])
            status = pz_error(ctx, PZ_ERR_DATA, "%s: panel id %d is not used by any face", name, (int)p);
    free(used);
    choice->panel_count = panels->panel_count;
    choice->source = "file";
    return status;
}

pz_status pl_user_panels(const pz_panels *panels, const pl_garment *garment, const pz_result *result,
                         pl_panel_choice *choice, pz_ctx *ctx)
{
    const pz_mesh *mesh = garment->mesh;
    pz_panels_source source = panels ? panels->source : PZ_PANELS_GROUPS;
    switch (source) {
    case PZ_PANELS_UV:
        if (!mesh->uvs || !mesh->corner_uvs)
            return pz_error(ctx, PZ_ERR_DATA, "%s: --panels uv: the mesh has no UVs (vt)",
                            result->options.name ? result->options.name : "garment");
        choice->face_panel = malloc(((size_t)mesh->face_count + 1) * sizeof(int32_t));
        if (!choice->face_panel)
            return pz_error(ctx, PZ_ERR_NOMEM, "flatten: out of memory finding panels");
        choice->source = "uv";
        return pz_pattern_panels_from_uv(mesh, choice->face_panel, &choice->panel_count, &choice->extra_cuts, ctx);
    case PZ_PANELS_FACES:
        return panels_from_faces(panels, garment, choice, ctx);
    case PZ_PANELS_LABELS:
        return panels_from_labels(mesh, choice, ctx);
    case PZ_PANELS_GROUPS:
        break;
    }
    return panels_from_groups(mesh, choice, ctx);
}

/* One side's vertices, from the caller's ids to the garment's. */
static pz_status map_side(const int32_t *raw, int32_t count, const pl_garment *garment, const char *name,
                          int32_t **out, pz_ctx *ctx)
{
    *out = malloc(((size_t)count + 1) * sizeof(int32_t));
    if (!*out)
        return pz_error(ctx, PZ_ERR_NOMEM, "%s: out of memory", name);
    for (int32_t i = 0; i < count; ++i) {
        int32_t id = raw[i];
        int32_t mapped = id >= 0 && id < garment->raw_vertex_count ? garment->raw_to_garment[id] : -1;
        if (mapped < 0)
            return pz_error(ctx, PZ_ERR_DATA, "%s: vertex %d is %s", name, (int)id,
                            id >= 0 && id < garment->raw_vertex_count ? "used by no face" : "out of range");
        (*out)[i] = mapped;
    }
    return PZ_OK;
}

static pz_status check_panel(int32_t panel, int32_t panel_count, const char *name, pz_ctx *ctx)
{
    if (panel >= 0 && panel < panel_count)
        return PZ_OK;
    return pz_error(ctx, PZ_ERR_DATA, "%s: panel id %d is out of range (%d panel%s)", name, (int)panel,
                    (int)panel_count, panel_count == 1 ? "" : "s");
}

pz_status pl_user_correspondences(const pz_panels *panels, const pl_garment *garment, int32_t panel_count,
                                  pz_correspondences *out, pz_ctx *ctx)
{
    memset(out, 0, sizeof *out);
    if (!panels || panels->seam_count + panels->dart_count == 0)
        return PZ_OK;
    const char *name = panels->correspondence_name ? panels->correspondence_name : "the seams and darts";
    if (!garment->ids_preserved)
        return pz_error(ctx, PZ_ERR_DATA, "%s: --repair removed faces or vertices, so the vertex ids no longer apply",
                        name);
    out->seams = calloc((size_t)panels->seam_count + 1, sizeof(pz_seam));
    out->darts = calloc((size_t)panels->dart_count + 1, sizeof(pz_dart));
    if (!out->seams || !out->darts) {
        pz_correspondences_clear(out);
        return pz_error(ctx, PZ_ERR_NOMEM, "flatten: out of memory reading seams");
    }
    pz_status status = PZ_OK;
    for (int32_t i = 0; i < panels->seam_count && status == PZ_OK; ++i) {
        const pz_seam *given = &panels->seams[i];
        pz_seam *seam = &out->seams[out->seam_count++];
        seam->panel_a = given->panel_a, seam->panel_b = given->panel_b, seam->pair_count = given->pair_count;
        status = check_panel(given->panel_a, panel_count, name, ctx);
        if (status == PZ_OK)
            status = check_panel(given->panel_b, panel_count, name, ctx);
        if (status == PZ_OK)
            status = map_side(given->side_a, given->pair_count, garment, name, &seam->side_a, ctx);
        if (status == PZ_OK)
            status = map_side(given->side_b, given->pair_count, garment, name, &seam->side_b, ctx);
    }
    for (int32_t i = 0; i < panels->dart_count && status == PZ_OK; ++i) {
        const pz_dart *given = &panels->darts[i];
        pz_dart *dart = &out->darts[out->dart_count++];
        dart->panel = given->panel, dart->pair_count = given->pair_count;
        int32_t *tip = NULL;
        status = check_panel(given->panel, panel_count, name, ctx);
        if (status == PZ_OK && (status = map_side(&given->tip, 1, garment, name, &tip, ctx)) == PZ_OK)
            dart->tip = tip[0];
        free(tip);
        if (status == PZ_OK)
            status = map_side(given->leg_a, given->pair_count, garment, name, &dart->leg_a, ctx);
        if (status == PZ_OK)
            status = map_side(given->leg_b, given->pair_count, garment, name, &dart->leg_b, ctx);
    }
    if (status != PZ_OK)
        pz_correspondences_clear(out);
    return status;
}

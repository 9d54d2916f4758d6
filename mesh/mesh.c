/*
 * mesh/mesh.c -- creating, copying and freeing meshes; units.
 *
 * SPDX-License-Identifier: GPL-3.0-or-later
 */
#include "mesh.h"

#include "core/util.h"

#include <math.h>
#include <stdlib.h>
#include <string.h>

pz_status pz_mesh_create(int32_t vertex_count, int32_t face_count, pz_mesh **out, pz_ctx *ctx)
{
    *out = NULL;
    if (vertex_count < 0 || face_count < 0)
        return pz_error(ctx, PZ_ERR_INTERNAL, "pz_mesh_create: negative count");
    pz_mesh *mesh = calloc(1, sizeof *mesh);
    if (!mesh)
        return pz_error(ctx, PZ_ERR_NOMEM, "out of memory");
    mesh->vertex_count = vertex_count;
    mesh->face_count = face_count;
    mesh->unit_scale = 1.0;
    mesh->positions = calloc((size_t)vertex_count * 3 + 1, sizeof(double));
    mesh->faces = calloc((size_t)face_count * 3 + 1, sizeof(int32_t));
    if (!mesh->positions || !mesh->faces) {
        pz_mesh_free(&mesh);
        return pz_error(ctx, PZ_ERR_NOMEM, "out of memory for a mesh of %d vertices and %d faces",
                        (int)vertex_count, (int)face_count);
    }
    *out = mesh;
    return PZ_OK;
}

void pz_mesh_free(pz_mesh **mesh)
{
    if (!mesh || !*mesh)
        return;
    pz_mesh *m = *mesh;
    free(m->positions);
    free(m->faces);
    free(m->uvs);
    free(m->corner_uvs);
    free(m->face_labels);
    if (m->label_names)
        for (int32_t i = 0; i < m->label_count; ++i)
            free(m->label_names[i]);
    free(m->label_names);
    free(m->poses);
    free(m);
    *mesh = NULL;
}

pz_status pz_mesh_copy(const pz_mesh *mesh, pz_mesh **out, pz_ctx *ctx)
{
    *out = NULL;
    pz_mesh *copy = calloc(1, sizeof *copy);
    if (!copy)
        return pz_error(ctx, PZ_ERR_NOMEM, "out of memory");
    *copy = *mesh;
    int failed = 0;
    size_t nv = (size_t)mesh->vertex_count, nf = (size_t)mesh->face_count;
    copy->positions = pz_copy_array(mesh->positions, nv * 3, sizeof(double), &failed);
    copy->faces = pz_copy_array(mesh->faces, nf * 3, sizeof(int32_t), &failed);
    copy->uvs = pz_copy_array(mesh->uvs, (size_t)mesh->uv_count * 2, sizeof(double), &failed);
    copy->corner_uvs = pz_copy_array(mesh->corner_uvs, nf * 3, sizeof(int32_t), &failed);
    copy->face_labels = pz_copy_array(mesh->face_labels, nf, sizeof(int32_t), &failed);
    copy->poses = pz_copy_array(mesh->poses, (size_t)mesh->pose_count * nv * 3, sizeof(double), &failed);
    copy->label_names = NULL;
    if (mesh->label_names) {
        copy->label_names = calloc((size_t)mesh->label_count + 1, sizeof(char *));
        if (!copy->label_names)
            failed = 1;
        for (int32_t i = 0; !failed && i < mesh->label_count; ++i)
            if (mesh->label_names[i])
                copy->label_names[i] = pz_copy_array(mesh->label_names[i], strlen(mesh->label_names[i]) + 1, 1, &failed);
    } else {
        copy->label_names = NULL;
    }
    if (failed) {
        if (!copy->label_names)
            copy->label_count = 0;
        pz_mesh_free(&copy);
        return pz_error(ctx, PZ_ERR_NOMEM, "out of memory copying a mesh");
    }
    *out = copy;
    return PZ_OK;
}

void pz_mesh_bbox(const pz_mesh *mesh, double bbox_min[3], double bbox_max[3])
{
    for (int k = 0; k < 3; ++k) {
        bbox_min[k] = mesh->vertex_count > 0 ? INFINITY : 0.0;
        bbox_max[k] = mesh->vertex_count > 0 ? -INFINITY : 0.0;
    }
    for (int32_t v = 0; v < mesh->vertex_count; ++v)
        for (int k = 0; k < 3; ++k) {
            double x = mesh->positions[3 * v + k];
            if (x < bbox_min[k]) bbox_min[k] = x;
            if (x > bbox_max[k]) bbox_max[k] = x;
        }
}

void pz_mesh_vertical_axis(const pz_mesh *mesh, double axis[3])
{
    double lo[3], hi[3];
    pz_mesh_bbox(mesh, lo, hi);
    int y_up = hi[1] - lo[1] > hi[2] - lo[2];
    axis[0] = 0.0;
    axis[1] = y_up ? 1.0 : 0.0;
    axis[2] = y_up ? 0.0 : 1.0;
}

const char *pz_units_str(pz_units units)
{
    switch (units) {
    case PZ_UNITS_MM: return "mm";
    case PZ_UNITS_CM: return "cm";
    case PZ_UNITS_M: return "m";
    case PZ_UNITS_AUTO: break;
    }
    return "auto";
}

pz_status pz_units_parse(const char *text, pz_units *out, pz_ctx *ctx)
{
    static const struct { const char *name; pz_units units; } table[] = {
        {"auto", PZ_UNITS_AUTO}, {"mm", PZ_UNITS_MM}, {"cm", PZ_UNITS_CM}, {"m", PZ_UNITS_M}};
    for (size_t i = 0; i < sizeof table / sizeof table[0]; ++i)
        if (strcmp(text, table[i].name) == 0) {
            *out = table[i].units;
            return PZ_OK;
        }
    return pz_error(ctx, PZ_ERR_USAGE, "--units: '%s' is not one of mm, cm, m, auto", text);
}

double pz_units_to_mm(pz_units units)
{
    switch (units) {
    case PZ_UNITS_CM: return 10.0;
    case PZ_UNITS_M: return 1000.0;
    default: return 1.0;
    }
}

/*
 * A garment is 0.2 - 2 m in its largest extent. Read the extent in each unit
 * and take the unit that puts it inside [200, 2000] mm; when several do (an
 * extent of 20-200 file units fits both cm and mm...), or none does, take the
 * unit whose reading is closest, in log scale, to 632 mm (the geometric middle
 * of the range). Ties in the overlap therefore go to the reading nearest a
 * typical garment, which is what a user with a 1.2-unit-tall mesh means (m).
 */
static double largest_extent(const pz_mesh *mesh)
{
    double lo[3], hi[3];
    pz_mesh_bbox(mesh, lo, hi);
    double extent = 0.0;
    for (int k = 0; k < 3; ++k)
        if (hi[k] - lo[k] > extent)
            extent = hi[k] - lo[k];
    return extent;
}

int pz_mesh_units_plausible(const pz_mesh *mesh, pz_units units)
{
    double extent_mm = largest_extent(mesh) * pz_units_to_mm(units == PZ_UNITS_AUTO ? pz_mesh_guess_units(mesh) : units);
    return extent_mm >= PZ_MESH_HUMAN_MIN_MM && extent_mm <= PZ_MESH_HUMAN_MAX_MM;
}

pz_status pz_mesh_check_units(const pz_mesh *mesh, pz_units used, int guessed, const char *name, pz_ctx *ctx)
{
    double extent_m = largest_extent(mesh) / 1000.0;
    if (mesh->vertex_count == 0 || !isfinite(extent_m) || pz_mesh_units_plausible(mesh, PZ_UNITS_MM))
        return PZ_OK; /* a non-finite coordinate is the validation's to report */
    if (guessed)
        return pz_error(ctx, PZ_ERR_DATA,
                        "%s: cannot tell its units: read as %s (the closest reading to a garment) it is %.3g m "
                        "across, outside a garment's 0.2-3 m; give --units mm, cm or m",
                        name, pz_units_str(used), extent_m);
    pz_note(ctx, "%s: warning: in %s (--units) it is %.3g m across, outside a garment's 0.2-3 m", name,
            pz_units_str(used), extent_m);
    return PZ_OK;
}

pz_units pz_mesh_guess_units(const pz_mesh *mesh)
{
    double extent = largest_extent(mesh);
    if (!(extent > 0.0) || !isfinite(extent))
        return PZ_UNITS_MM;
    static const pz_units candidates[3] = {PZ_UNITS_MM, PZ_UNITS_CM, PZ_UNITS_M};
    const double middle = log(sqrt(200.0 * 2000.0));
    pz_units best = PZ_UNITS_MM;
    double best_distance = INFINITY;
    for (int i = 0; i < 3; ++i) {
        double distance = fabs(log(extent * pz_units_to_mm(candidates[i])) - middle);
        if (distance < best_distance) {
            best_distance = distance;
            best = candidates[i];
        }
    }
    return best;
}

void pz_mesh_to_mm(pz_mesh *mesh, pz_units units, pz_units *used)
{
    if (units == PZ_UNITS_AUTO)
        units = pz_mesh_guess_units(mesh);
    if (used)
        *used = units;
    double scale = pz_units_to_mm(units);
    mesh->unit_scale *= scale;
    if (scale == 1.0)
        return;
    size_t count = (size_t)mesh->vertex_count * 3;
    for (size_t i = 0; i < count; ++i)
        mesh->positions[i] *= scale;
    count *= (size_t)mesh->pose_count;
    for (size_t i = 0; i < count; ++i)
        mesh->poses[i] *= scale;
}

pz_status pz_mesh_add_pose(pz_mesh *mesh, const double *positions, pz_ctx *ctx)
{
    if (mesh->pose_count >= PZ_MESH_MAX_POSES)
        return pz_error(ctx, PZ_ERR_DATA, "more than %d poses (at most %d extra poses are supported)",
                        PZ_MESH_MAX_POSES, PZ_MESH_MAX_POSES);
    size_t pose_size = (size_t)mesh->vertex_count * 3;
    double *grown = realloc(mesh->poses, (size_t)(mesh->pose_count + 1) * pose_size * sizeof(double) + 1);
    if (!grown)
        return pz_error(ctx, PZ_ERR_NOMEM, "out of memory adding a pose");
    mesh->poses = grown;
    memcpy(grown + (size_t)mesh->pose_count * pose_size, positions, pose_size * sizeof(double));
    mesh->pose_count += 1;
    return PZ_OK;
}

/*
 * field/writers.c -- the cross-field as files (docs/field.md): field.obj
 * (two segments per face through its centroid, singular vertices as points)
 * and field.glb (the same as glTF lines and points).
 *
 * Separate from field/crossfield.c because writing is not computing: these
 * read a finished pz_field through field/field.h only.
 *
 * SPDX-License-Identifier: GPL-3.0-or-later
 */
#include "field/field.h"
#include "core/vec.h"

#include <cjson/cJSON.h>
#include <stdlib.h>
#include <string.h>

/* ---------------------------------------------------------------- writers */

/* Segment end points: 4 per face (two arms through the centroid), then the singular vertices. */
static float *field_points(const pz_mesh *mesh, const pz_field *field, double arm_length)
{
    size_t count = 4 * (size_t)mesh->face_count + (size_t)field->singularity_count;
    float *points = malloc((count + 1) * 3 * sizeof *points);
    if (!points)
        return NULL;
    if (!(arm_length > 0.0))
        arm_length = 0.8 * field->mean_edge_length;
    for (int32_t f = 0; f < mesh->face_count; ++f) {
        const int32_t *face = mesh->faces + 3 * (size_t)f;
        double c[3], arms[2][3];
        for (int i = 0; i < 3; ++i)
            c[i] = (mesh->positions[3 * (size_t)face[0] + i] + mesh->positions[3 * (size_t)face[1] + i] +
                    mesh->positions[3 * (size_t)face[2] + i]) / 3.0;
        memcpy(arms[0], field->directions + 3 * (size_t)f, sizeof arms[0]);
        pz_vec3_cross(field->normals + 3 * (size_t)f, arms[0], arms[1]);
        float *p = points + 12 * (size_t)f;
        for (int a = 0; a < 2; ++a)
            for (int i = 0; i < 3; ++i) {
                p[6 * a + i] = (float)(c[i] - 0.5 * arm_length * arms[a][i]);
                p[6 * a + 3 + i] = (float)(c[i] + 0.5 * arm_length * arms[a][i]);
            }
    }
    float *s = points + 12 * (size_t)mesh->face_count;
    for (int32_t k = 0; k < field->singularity_count; ++k)
        for (int i = 0; i < 3; ++i)
            s[3 * (size_t)k + i] = (float)mesh->positions[3 * (size_t)field->singular_vertices[k] + i];
    return points;
}

pz_status pz_field_write_obj(const pz_mesh *mesh, const pz_field *field, double arm_length, FILE *file,
                             const char *name, pz_ctx *ctx)
{
    float *points = field_points(mesh, field, arm_length);
    if (!points)
        return pz_error(ctx, PZ_ERR_NOMEM, "%s: out of memory", name);
    size_t segment_points = 4 * (size_t)mesh->face_count, total = segment_points + (size_t)field->singularity_count;
    fprintf(file, "# panelize cross-field: two segments per face, singular vertices as points\n");
    for (size_t i = 0; i < total; ++i)
        fprintf(file, "v %.7g %.7g %.7g\n", points[3 * i], points[3 * i + 1], points[3 * i + 2]);
    fprintf(file, "g cross\n");
    for (size_t i = 0; i < segment_points; i += 2)
        fprintf(file, "l %zu %zu\n", i + 1, i + 2);
    if (field->singularity_count)
        fprintf(file, "g singularities\n");
    for (size_t i = segment_points; i < total; ++i)
        fprintf(file, "p %zu\n", i + 1);
    free(points);
    if (ferror(file))
        return pz_error(ctx, PZ_ERR_CREATE, "%s: write error", name);
    return PZ_OK;
}

static void put_u32(unsigned char *p, uint32_t v)
{
    p[0] = (unsigned char)v, p[1] = (unsigned char)(v >> 8), p[2] = (unsigned char)(v >> 16), p[3] = (unsigned char)(v >> 24);
}

/* An accessor of `count` VEC3 floats in bufferView `view`, with the min/max glTF requires for POSITION. */
/* A new object appended to `array` (NULL when array is NULL or out of memory; nothing leaks). */
static cJSON *append_object(cJSON *array)
{
    if (!array)
        return NULL;
    cJSON *item = cJSON_CreateObject();
    if (item && !cJSON_AddItemToArray(array, item)) {
        cJSON_Delete(item);
        return NULL;
    }
    return item;
}

/* Adds `item` (which may be NULL) to object under key; deletes it when that fails. */
static int add_item(cJSON *object, const char *key, cJSON *item)
{
    if (!item)
        return 0;
    if (!object || !cJSON_AddItemToObject(object, key, item)) {
        cJSON_Delete(item);
        return 0;
    }
    return 1;
}

/* An accessor of `count` VEC3 floats in bufferView `view`, with the min/max glTF requires for POSITION. */
static int add_accessor(cJSON *accessors, int view, const float *points, size_t count)
{
    double lo[3] = {HUGE_VAL, HUGE_VAL, HUGE_VAL}, hi[3] = {-HUGE_VAL, -HUGE_VAL, -HUGE_VAL};
    for (size_t i = 0; i < count; ++i)
        for (int c = 0; c < 3; ++c) {
            lo[c] = points[3 * i + c] < lo[c] ? points[3 * i + c] : lo[c];
            hi[c] = points[3 * i + c] > hi[c] ? points[3 * i + c] : hi[c];
        }
    cJSON *a = append_object(accessors);
    return a && cJSON_AddNumberToObject(a, "bufferView", view) && cJSON_AddNumberToObject(a, "componentType", 5126) &&
           cJSON_AddNumberToObject(a, "count", (double)count) && cJSON_AddStringToObject(a, "type", "VEC3") &&
           add_item(a, "min", cJSON_CreateDoubleArray(lo, 3)) && add_item(a, "max", cJSON_CreateDoubleArray(hi, 3));
}

static int add_view(cJSON *views, size_t offset, size_t length)
{
    cJSON *v = append_object(views);
    return v && cJSON_AddNumberToObject(v, "buffer", 0) && cJSON_AddNumberToObject(v, "byteOffset", (double)offset) &&
           cJSON_AddNumberToObject(v, "byteLength", (double)length) && cJSON_AddNumberToObject(v, "target", 34962);
}

static int add_primitive(cJSON *primitives, int accessor, int mode)
{
    cJSON *p = append_object(primitives);
    cJSON *attributes = p ? cJSON_AddObjectToObject(p, "attributes") : NULL;
    return attributes && cJSON_AddNumberToObject(attributes, "POSITION", accessor) &&
           cJSON_AddNumberToObject(p, "mode", mode);
}

/* The glTF JSON for the lines (and points) in one buffer of bin_length bytes. */
static char *glb_json(const float *points, size_t line_points, size_t point_count, size_t bin_length)
{
    cJSON *root = cJSON_CreateObject();
    cJSON *asset = root ? cJSON_AddObjectToObject(root, "asset") : NULL;
    int node = 0;
    int ok = asset && cJSON_AddStringToObject(asset, "version", "2.0") &&
             cJSON_AddStringToObject(asset, "generator", "panelize " PZ_VERSION_STRING " field") &&
             cJSON_AddNumberToObject(root, "scene", 0);
    cJSON *scene = ok ? append_object(cJSON_AddArrayToObject(root, "scenes")) : NULL;
    ok = ok && add_item(scene, "nodes", cJSON_CreateIntArray(&node, 1));
    cJSON *node_object = ok ? append_object(cJSON_AddArrayToObject(root, "nodes")) : NULL;
    ok = ok && node_object && cJSON_AddNumberToObject(node_object, "mesh", 0);
    cJSON *mesh = ok ? append_object(cJSON_AddArrayToObject(root, "meshes")) : NULL;
    ok = ok && mesh && cJSON_AddStringToObject(mesh, "name", "cross-field");
    cJSON *primitives = ok ? cJSON_AddArrayToObject(mesh, "primitives") : NULL;
    cJSON *accessors = ok ? cJSON_AddArrayToObject(root, "accessors") : NULL;
    cJSON *views = ok ? cJSON_AddArrayToObject(root, "bufferViews") : NULL;
    cJSON *buffer = ok ? append_object(cJSON_AddArrayToObject(root, "buffers")) : NULL;
    ok = ok && primitives && accessors && views && buffer &&
         cJSON_AddNumberToObject(buffer, "byteLength", (double)bin_length);
    ok = ok && add_view(views, 0, line_points * 12) && add_accessor(accessors, 0, points, line_points) &&
         add_primitive(primitives, 0, 1);
    if (ok && point_count)
        ok = add_view(views, line_points * 12, point_count * 12) &&
             add_accessor(accessors, 1, points + 3 * line_points, point_count) && add_primitive(primitives, 1, 0);
    char *text = ok ? cJSON_PrintUnformatted(root) : NULL;
    cJSON_Delete(root);
    return text;
}

pz_status pz_field_write_glb(const pz_mesh *mesh, const pz_field *field, double arm_length, FILE *file,
                             const char *name, pz_ctx *ctx)
{
    float *points = field_points(mesh, field, arm_length);
    size_t line_points = 4 * (size_t)mesh->face_count, point_count = (size_t)field->singularity_count;
    size_t bin_length = (line_points + point_count) * 12;
    char *json = points ? glb_json(points, line_points, point_count, bin_length) : NULL;
    if (!json) {
        free(points);
        return pz_error(ctx, PZ_ERR_NOMEM, "%s: out of memory", name);
    }
    size_t json_length = strlen(json), json_padded = (json_length + 3) & ~(size_t)3;
    size_t total = 12 + 8 + json_padded + 8 + bin_length;
    pz_status status = PZ_OK;
    if (total > UINT32_MAX) {
        status = pz_error(ctx, PZ_ERR_CREATE, "%s: too large for GLB (%zu bytes)", name, total);
    } else {
        unsigned char header[20];
        memcpy(header, "glTF", 4);
        put_u32(header + 4, 2), put_u32(header + 8, (uint32_t)total);
        put_u32(header + 12, (uint32_t)json_padded), memcpy(header + 16, "JSON", 4);
        fwrite(header, 1, 20, file);
        fwrite(json, 1, json_length, file);
        for (size_t i = json_length; i < json_padded; ++i)
            fputc(' ', file);
        put_u32(header, (uint32_t)bin_length), memcpy(header + 4, "BIN\0", 4);
        fwrite(header, 1, 8, file);
        for (size_t i = 0; i < 3 * (line_points + point_count); ++i) {
            uint32_t bits;
            memcpy(&bits, points + i, 4);
            unsigned char le[4];
            put_u32(le, bits);
            fwrite(le, 1, 4, file);
        }
        if (ferror(file))
            status = pz_error(ctx, PZ_ERR_CREATE, "%s: write error", name);
    }
    free(json);
    free(points);
    return status;
}

/*
 * studio/request.c -- the page's requests, checked before any work
 * (docs/studio.md, "The API"): a run's options and strokes, the paths it
 * names. Every problem is PZ_ERR_USAGE with a message the page shows (the
 * server answers 400 with it); nothing here trusts the text it reads.
 *
 * SPDX-License-Identifier: GPL-3.0-or-later
 */
#define _GNU_SOURCE
#include "studio/internal.h"

#include <errno.h>
#include <math.h>
#include <stdlib.h>
#include <string.h>

/* The body as a JSON object, or PZ_ERR_USAGE. */
static pz_status parse_object(const char *body, size_t length, cJSON **out, pz_ctx *ctx)
{
    *out = NULL;
    if (length == 0)
        return pz_error(ctx, PZ_ERR_USAGE, "the request has no JSON body");
    const char *end = NULL;
    cJSON *root = cJSON_ParseWithLengthOpts(body, length, &end, 0);
    if (!root) {
        size_t at = end && end >= body ? (size_t)(end - body) : 0;
        return pz_error(ctx, PZ_ERR_USAGE, "the request is not valid JSON (near byte %zu)", at);
    }
    for (; end && (size_t)(end - body) < length; ++end)
        if (!strchr(" \t\r\n", *end) && *end != '\0') {
            cJSON_Delete(root);
            return pz_error(ctx, PZ_ERR_USAGE, "the request has text after its JSON value");
        }
    if (!cJSON_IsObject(root)) {
        cJSON_Delete(root);
        return pz_error(ctx, PZ_ERR_USAGE, "the request is not a JSON object");
    }
    *out = root;
    return PZ_OK;
}

pz_status studio_json_string(const char *body, size_t length, const char *key, char **value, pz_ctx *ctx)
{
    *value = NULL;
    cJSON *root = NULL;
    pz_status status = parse_object(body, length, &root, ctx);
    if (status != PZ_OK)
        return status;
    const cJSON *item = cJSON_GetObjectItemCaseSensitive(root, key);
    if (!cJSON_IsString(item) || !item->valuestring[0])
        status = pz_error(ctx, PZ_ERR_USAGE, "%s: expected a non-empty string", key);
    else if (!(*value = strdup(item->valuestring)))
        status = pz_error(ctx, PZ_ERR_NOMEM, "out of memory");
    cJSON_Delete(root);
    return status;
}

/* A number member in [minimum, maximum] (whole when `whole`), left as it is when absent. */
static pz_status read_number(const cJSON *item, double minimum, double maximum, int whole, double *value,
                             pz_ctx *ctx)
{
    if (!cJSON_IsNumber(item) || !isfinite(item->valuedouble))
        return pz_error(ctx, PZ_ERR_USAGE, "%s: expected a number", item->string);
    double number = item->valuedouble;
    if (number < minimum || number > maximum || (whole && number != floor(number)))
        return pz_error(ctx, PZ_ERR_USAGE, "%s: %g is not a %s in %g .. %g", item->string, number,
                        whole ? "whole number" : "number", minimum, maximum);
    *value = number;
    return PZ_OK;
}

static pz_status read_symmetry(const cJSON *item, pz_segment_options *segment, pz_ctx *ctx)
{
    static const char *const names[] = {"auto", "off", "x", "y", "z"};
    static const pz_symmetry_mode modes[] = {PZ_SYMMETRY_AUTO, PZ_SYMMETRY_OFF, PZ_SYMMETRY_X, PZ_SYMMETRY_Y,
                                             PZ_SYMMETRY_Z};
    for (int i = 0; cJSON_IsString(item) && i < 5; ++i)
        if (strcmp(item->valuestring, names[i]) == 0) {
            segment->symmetry = modes[i];
            return PZ_OK;
        }
    return pz_error(ctx, PZ_ERR_USAGE, "symmetry: expected \"auto\", \"off\", \"x\", \"y\" or \"z\"");
}

/* "fabric": [k_su, k_sv, k_r], each finite and positive (N/mm; docs/flatten.md). */
static pz_status read_fabric(const cJSON *item, pz_flatten_options *flatten, pz_ctx *ctx)
{
    double values[3];
    if (!cJSON_IsArray(item) || cJSON_GetArraySize(item) != 3)
        return pz_error(ctx, PZ_ERR_USAGE, "fabric: expected [k_su, k_sv, k_r]");
    for (int i = 0; i < 3; ++i) {
        const cJSON *value = cJSON_GetArrayItem(item, i);
        if (!cJSON_IsNumber(value) || !(value->valuedouble > 0) || !(value->valuedouble < 1e6))
            return pz_error(ctx, PZ_ERR_USAGE, "fabric: each stiffness must be a number in (0, 1e6)");
        values[i] = value->valuedouble;
    }
    flatten->fabric = (pz_fabric){values[0], values[1], values[2]};
    flatten->fabric_given = 1;
    return PZ_OK;
}

pz_status studio_sketch_new(int32_t curves, int32_t points, pz_sketch **out, pz_ctx *ctx)
{
    pz_sketch *sketch = calloc(1, sizeof *sketch);
    if (sketch) {
        sketch->curve_offsets = calloc((size_t)curves + 1, sizeof(int32_t));
        sketch->points = malloc(((size_t)points + 1) * 3 * sizeof(double));
    }
    if (!sketch || !sketch->curve_offsets || !sketch->points) {
        pz_sketch_free(&sketch);
        *out = NULL;
        return pz_error(ctx, PZ_ERR_NOMEM, "strokes: out of memory");
    }
    sketch->curve_count = curves;
    *out = sketch;
    return PZ_OK;
}

/* One point [x, y, z] inside the box lo..hi into p. */
static pz_status read_point(const cJSON *item, const char *name, int stroke, int index, const double lo[3],
                            const double hi[3], double *p, pz_ctx *ctx)
{
    if (!cJSON_IsArray(item) || cJSON_GetArraySize(item) != 3)
        return pz_error(ctx, PZ_ERR_USAGE, "%s[%d][%d]: expected [x, y, z]", name, stroke, index);
    for (int k = 0; k < 3; ++k) {
        const cJSON *value = cJSON_GetArrayItem(item, k);
        if (!cJSON_IsNumber(value) || !isfinite(value->valuedouble))
            return pz_error(ctx, PZ_ERR_USAGE, "%s[%d][%d]: coordinates must be finite numbers", name, stroke, index);
        p[k] = value->valuedouble;
        if (p[k] < lo[k] || p[k] > hi[k])
            return pz_error(ctx, PZ_ERR_USAGE, "%s[%d][%d]: the point is far from the garment", name, stroke, index);
    }
    return PZ_OK;
}

/* "strokes" (seams) or "grain_strokes" (`name`): [[[x, y, z], ...], ...] in millimetres, within the limits of
 * internal.h, into a new sketch. */
static pz_status read_strokes(const cJSON *item, const char *name, const pz_mesh *mesh, pz_sketch **out, pz_ctx *ctx)
{
    if (!cJSON_IsArray(item))
        return pz_error(ctx, PZ_ERR_USAGE, "%s: expected an array of polylines", name);
    int count = cJSON_GetArraySize(item);
    if (count > STUDIO_MAX_STROKES)
        return pz_error(ctx, PZ_ERR_USAGE, "%s: %d strokes, at most %d", name, count, STUDIO_MAX_STROKES);
    if (count == 0)
        return PZ_OK;
    size_t total = 0;
    for (int s = 0; s < count; ++s) {
        const cJSON *stroke = cJSON_GetArrayItem(item, s);
        int points = cJSON_IsArray(stroke) ? cJSON_GetArraySize(stroke) : -1;
        if (points < 2 || points > STUDIO_MAX_STROKE_POINTS)
            return pz_error(ctx, PZ_ERR_USAGE, "%s[%d]: expected 2 .. %d points", name, s, STUDIO_MAX_STROKE_POINTS);
        total += (size_t)points;
    }
    if (total > STUDIO_MAX_TOTAL_POINTS)
        return pz_error(ctx, PZ_ERR_USAGE, "%s: %zu points, at most %d", name, total, STUDIO_MAX_TOTAL_POINTS);
    /* Points must lie near the garment: its box grown by its diagonal on every side. */
    double lo[3], hi[3];
    pz_mesh_bbox(mesh, lo, hi);
    double diagonal = sqrt((hi[0] - lo[0]) * (hi[0] - lo[0]) + (hi[1] - lo[1]) * (hi[1] - lo[1]) +
                           (hi[2] - lo[2]) * (hi[2] - lo[2]));
    for (int k = 0; k < 3; ++k)
        lo[k] -= diagonal, hi[k] += diagonal;
    pz_sketch *sketch = NULL;
    pz_status status = studio_sketch_new(count, (int32_t)total, &sketch, ctx);
    if (status != PZ_OK)
        return status;
    size_t at = 0;
    for (int s = 0; s < count && status == PZ_OK; ++s) {
        const cJSON *stroke = cJSON_GetArrayItem(item, s);
        sketch->curve_offsets[s] = (int32_t)at;
        int index = 0;
        for (const cJSON *point = stroke->child; point && status == PZ_OK; point = point->next, ++index)
            status = read_point(point, name, s, index, lo, hi, sketch->points + 3 * at++, ctx);
    }
    sketch->curve_offsets[count] = (int32_t)at;
    if (status != PZ_OK)
        pz_sketch_free(&sketch);
    *out = sketch;
    return status;
}

/* One member of the run request into options, sketch (seam strokes) or grain (grain strokes). */
static pz_status read_member(const cJSON *item, const pz_mesh *mesh, pz_run_options *options, pz_sketch **sketch,
                             pz_sketch **grain, pz_ctx *ctx)
{
    const char *key = item->string;
    double number = 0;
    pz_status status = PZ_OK;
    if (strcmp(key, "max_strain") == 0)
        status = read_number(item, 0, 10, 0, &options->goals.max_strain, ctx);
    else if (strcmp(key, "max_corners") == 0) {
        number = options->goals.max_corners;
        status = read_number(item, 1, 1000, 1, &number, ctx);
        options->goals.max_corners = (int32_t)number;
    } else if (strcmp(key, "max_pieces") == 0) {
        number = options->segment.max_pieces;
        status = read_number(item, 0, 100000, 1, &number, ctx); /* 0: no budget */
        options->segment.max_pieces = (int32_t)number;
    } else if (strcmp(key, "darts") == 0) {
        if (!cJSON_IsBool(item))
            return pz_error(ctx, PZ_ERR_USAGE, "darts: expected true or false");
        options->segment.darts = cJSON_IsTrue(item);
    } else if (strcmp(key, "consolidate") == 0) {
        if (!cJSON_IsBool(item))
            return pz_error(ctx, PZ_ERR_USAGE, "consolidate: expected true or false");
        options->consolidate = cJSON_IsTrue(item);
    } else if (strcmp(key, "mirror_sketch") == 0) {
        if (!cJSON_IsBool(item))
            return pz_error(ctx, PZ_ERR_USAGE, "mirror_sketch: expected true or false");
        options->mirror_sketch = cJSON_IsTrue(item);
    } else if (strcmp(key, "symmetry") == 0)
        status = read_symmetry(item, &options->segment, ctx);
    else if (strcmp(key, "fabric") == 0)
        status = read_fabric(item, &options->flatten, ctx);
    else if (strcmp(key, "strokes") == 0)
        status = read_strokes(item, "strokes", mesh, sketch, ctx);
    else if (strcmp(key, "grain_strokes") == 0)
        status = read_strokes(item, "grain_strokes", mesh, grain, ctx);
    else
        status = pz_error(ctx, PZ_ERR_USAGE, "%s: not an option (max_strain, max_corners, max_pieces, darts, "
                          "consolidate, mirror_sketch, symmetry, fabric, strokes, grain_strokes)", key);
    return status;
}

pz_status studio_parse_run(const char *body, size_t length, const pz_mesh *mesh, const pz_sketch *welded,
                           pz_run_options *options, pz_sketch **sketch, pz_sketch **grain, pz_ctx *ctx)
{
    *sketch = NULL;
    *grain = NULL;
    pz_run_options_default(options);
    options->units = PZ_UNITS_MM; /* the studio's garments are in millimetres once loaded */
    options->prepare = 0;         /* and prepared once (garments.c) */
    options->defer_extras = 1;    /* most runs are looked at, not written: the marker and the trade-off wait
                                     for a download or the report */
    cJSON *root = NULL;
    pz_status status = parse_object(body, length, &root, ctx);
    for (const cJSON *item = root ? root->child : NULL; item && status == PZ_OK; item = item->next) {
        if (cJSON_GetObjectItemCaseSensitive(root, item->string) != item)
            status = pz_error(ctx, PZ_ERR_USAGE, "%s: given twice", item->string);
        else if (strcmp(item->string, "strokes") == 0 && *sketch)
            status = pz_error(ctx, PZ_ERR_USAGE, "strokes: given twice");
        else
            status = read_member(item, mesh, options, sketch, grain, ctx);
    }
    cJSON_Delete(root);
    if (status == PZ_OK)
        status = pz_run_options_check(options, "run", PZ_OPTION_KEYWORD, ctx);
    if (status != PZ_OK) {
        pz_sketch_free(sketch);
        pz_sketch_free(grain);
    }
    options->sketch = *sketch;
    options->garment_seams = welded; /* the garment's own seams: kept, and no part of the sketch's symmetry */
    options->grain_hints = *grain;
    return status;
}

/* 1 when `path` is `root` or inside it (both canonical). */
static int inside(const char *root, const char *path)
{
    size_t length = strlen(root);
    if (strcmp(root, "/") == 0)
        return path[0] == '/';
    return strncmp(path, root, length) == 0 && (path[length] == '\0' || path[length] == '/');
}

pz_status studio_resolve_path(const pz_studio *studio, const char *path, int must_exist, char *out, pz_ctx *ctx)
{
    if (!path[0] || strlen(path) >= PATH_MAX - 2)
        return pz_error(ctx, PZ_ERR_USAGE, "path: empty or too long");
    for (const char *c = path; *c; ++c)
        if ((unsigned char)*c < 0x20)
            return pz_error(ctx, PZ_ERR_USAGE, "path: control characters are not allowed");
    char joined[2 * PATH_MAX];
    if (path[0] == '/')
        snprintf(joined, sizeof joined, "%s", path);
    else
        snprintf(joined, sizeof joined, "%s/%s", studio->root, path);
    if (strlen(joined) >= PATH_MAX)
        return pz_error(ctx, PZ_ERR_USAGE, "path: too long");
    /* The nearest existing ancestor, canonical, then the rest as written: the rest must not climb out. */
    char head[PATH_MAX];
    snprintf(head, sizeof head, "%s", joined);
    const char *rest = "";
    char resolved[PATH_MAX];
    while (!realpath(head, resolved)) {
        if (must_exist || errno != ENOENT)
            return pz_error(ctx, PZ_ERR_USAGE, "%s: %s", path, must_exist ? "no such file" : strerror(errno));
        char *slash = strrchr(head, '/');
        if (!slash || slash == head)
            return pz_error(ctx, PZ_ERR_USAGE, "%s: no such folder", path);
        *slash = '\0';
        rest = joined + (slash - head) + 1;
    }
    if (strstr(rest, "..") && (strcmp(rest, "..") == 0 || strncmp(rest, "../", 3) == 0 || strstr(rest, "/../") ||
                               (strlen(rest) >= 3 && strcmp(rest + strlen(rest) - 3, "/..") == 0)))
        return pz_error(ctx, PZ_ERR_USAGE, "%s: '..' is not allowed", path);
    if (!inside(studio->root, resolved))
        return pz_error(ctx, PZ_ERR_USAGE, "%s: outside the allowed folder %s", path, studio->root);
    if (snprintf(out, PATH_MAX, "%s%s%s", resolved, rest[0] ? "/" : "", rest) >= PATH_MAX)
        return pz_error(ctx, PZ_ERR_USAGE, "path: too long");
    return PZ_OK;
}

/*
 * pipeline/pattern_output.c -- the files of `panelize flatten`: readers for
 * panels, seam and dart files, the layout of the flat pieces, and the writers
 * of garment.obj, pattern.svg and report.json (formats: docs/flatten.md).
 *
 * Readers go line by line and name the file and line of the first problem
 * (PZ_ERR_DATA): a token that is not a whole number, a line with the wrong
 * count of numbers (an odd pair), an id out of range. Seam and dart vertex ids
 * are mapped onto the prepared garment through pz_vertex_space, so several
 * panel files (ids local to each file) and a single garment (ids global) read
 * alike.
 *
 * Layout: the back-ends place pieces as they like; when two pieces' bounding
 * boxes overlap, every piece is moved into rows ("shelves", tallest first),
 * found by a sort and a sweep over the boxes, O(P log P) in the panel count.
 *
 * pattern.svg draws each piece with its boundary loops (half-edge topology of
 * the cut mesh, where every panel is a disk), its triangle edges, and a
 * grainline along +v (the warp: param.h orients every piece so) through the
 * area centroid. SVG's y axis points down, so y = -v keeps the warp pointing
 * up on paper. 1 user unit = 1 mm, and width/height carry "mm".
 *
 * Memory: the readers hold one line and the pairs; the SVG writer holds the
 * topology of the cut mesh and per-panel edge buckets, O(V + F).
 *
 * SPDX-License-Identifier: GPL-3.0-or-later
 */
#define _POSIX_C_SOURCE 200809L
#include "pipeline/pattern_output.h"

#include "core/util.h"

#include <ctype.h>
#include <errno.h>
#include <float.h>
#include <limits.h>
#include <math.h>
#include <stdlib.h>
#include <string.h>

/* ---------------------------------------------------------------- line reading */

/* Splits `line` into whole non-negative numbers. Returns the count, or -1
 * with *bad pointing at the first token that is not one. */
static int parse_ids(char *line, int32_t *ids, int capacity, char **bad)
{
    int count = 0;
    char *cursor = line;
    for (;;) {
        while (*cursor && isspace((unsigned char)*cursor))
            ++cursor;
        if (!*cursor)
            return count;
        char *token = cursor;
        while (*cursor && !isspace((unsigned char)*cursor))
            ++cursor;
        char saved = *cursor;
        *cursor = '\0';
        char *end = NULL;
        errno = 0;
        long value = strtol(token, &end, 10);
        int ok = end != token && *end == '\0' && errno != ERANGE && value >= 0 && value <= INT32_MAX;
        *cursor = saved;
        if (!ok) {
            *cursor = '\0'; /* the message quotes the token alone */
            *bad = token;
            return -1;
        }
        if (count < capacity)
            ids[count] = (int32_t)value;
        ++count;
    }
}

static int is_blank(const char *line)
{
    for (; *line; ++line)
        if (!isspace((unsigned char)*line))
            return 0;
    return 1;
}

/*
 * A file of numbered lines: `header_count` lines of one id, then lines of two
 * ids. Blank lines are skipped. *pairs (2 x *pair_count) and *pair_lines
 * (line number of each pair) are allocated.
 */
static pz_status read_id_file(const char *path, const char *const *header_names, int header_count,
                              int32_t *header, int32_t *header_lines, int32_t **pairs, int32_t **pair_lines,
                              int32_t *pair_count, pz_ctx *ctx)
{
    *pairs = NULL;
    *pair_lines = NULL;
    *pair_count = 0;
    FILE *file = fopen(path, "r");
    if (!file)
        return pz_error(ctx, PZ_ERR_OPEN, "%s: cannot open: %s", path, strerror(errno));
    char *line = NULL;
    size_t line_capacity = 0, capacity = 0, line_capacity_lines = 0;
    int32_t line_number = 0, headers_seen = 0;
    pz_status status = PZ_OK;
    while (status == PZ_OK && getline(&line, &line_capacity, file) >= 0) {
        ++line_number;
        if (is_blank(line))
            continue;
        int32_t ids[3];
        char *bad = NULL;
        int count = parse_ids(line, ids, 3, &bad);
        if (count < 0) {
            status = pz_error(ctx, PZ_ERR_DATA, "%s: line %d: '%s' is not a non-negative whole number", path,
                              (int)line_number, bad);
        } else if (headers_seen < header_count) {
            if (count != 1)
                status = pz_error(ctx, PZ_ERR_DATA, "%s: line %d: expected one number (the %s), found %d", path,
                                  (int)line_number, header_names[headers_seen], count);
            else {
                header_lines[headers_seen] = line_number;
                header[headers_seen++] = ids[0];
            }
        } else if (count != 2) {
            status = pz_error(ctx, PZ_ERR_DATA, "%s: line %d: expected a vertex pair `a b`, found %d number%s",
                              path, (int)line_number, count, count == 1 ? "" : "s");
        } else if (!pz_grow((void **)pairs, &capacity, 2 * ((size_t)*pair_count + 1), sizeof(int32_t)) ||
                   !pz_grow((void **)pair_lines, &line_capacity_lines, (size_t)*pair_count + 1, sizeof(int32_t))) {
            status = pz_error(ctx, PZ_ERR_NOMEM, "%s: out of memory", path);
        } else {
            (*pairs)[2 * *pair_count] = ids[0];
            (*pairs)[2 * *pair_count + 1] = ids[1];
            (*pair_lines)[(*pair_count)++] = line_number;
        }
    }
    if (status == PZ_OK && ferror(file))
        status = pz_error(ctx, PZ_ERR_OPEN, "%s: cannot read: %s", path, strerror(errno));
    if (status == PZ_OK && headers_seen < header_count)
        status = pz_error(ctx, PZ_ERR_DATA, "%s: line %d: missing the %s", path, (int)line_number + 1,
                          header_names[headers_seen]);
    if (status == PZ_OK && *pair_count == 0)
        status = pz_error(ctx, PZ_ERR_DATA, "%s: no vertex pairs", path);
    free(line);
    fclose(file);
    if (status != PZ_OK) {
        free(*pairs);
        free(*pair_lines);
        *pairs = NULL;
        *pair_lines = NULL;
        *pair_count = 0;
    }
    return status;
}

/* ---------------------------------------------------------------- panels file */

pz_status pz_flatten_read_panel_file(const char *path, int32_t face_count, int32_t *face_panel,
                                     int32_t *panel_count, pz_ctx *ctx)
{
    *panel_count = 0;
    FILE *file = fopen(path, "r");
    if (!file)
        return pz_error(ctx, PZ_ERR_OPEN, "%s: cannot open: %s", path, strerror(errno));
    char *line = NULL;
    size_t line_capacity = 0;
    int32_t line_number = 0, read = 0, first_blank = 0, largest = -1;
    pz_status status = PZ_OK;
    while (status == PZ_OK && getline(&line, &line_capacity, file) >= 0) {
        ++line_number;
        if (is_blank(line)) {
            if (!first_blank)
                first_blank = line_number;
            continue;
        }
        int32_t id = 0;
        char *bad = NULL;
        int count = parse_ids(line, &id, 1, &bad);
        if (first_blank)
            status = pz_error(ctx, PZ_ERR_DATA, "%s: line %d: empty line (one panel id per face expected)", path,
                              (int)first_blank);
        else if (count < 0)
            status = pz_error(ctx, PZ_ERR_DATA, "%s: line %d: '%s' is not a non-negative whole number", path,
                              (int)line_number, bad);
        else if (count != 1)
            status = pz_error(ctx, PZ_ERR_DATA, "%s: line %d: expected one panel id, found %d numbers", path,
                              (int)line_number, count);
        else if (read >= face_count)
            status = pz_error(ctx, PZ_ERR_DATA, "%s: line %d: more panel ids than the mesh's %d faces", path,
                              (int)line_number, (int)face_count);
        else if (id >= face_count)
            status = pz_error(ctx, PZ_ERR_DATA, "%s: line %d: panel id %d is not below the face count %d", path,
                              (int)line_number, (int)id, (int)face_count);
        else {
            face_panel[read++] = id;
            if (id > largest)
                largest = id;
        }
    }
    if (status == PZ_OK && ferror(file))
        status = pz_error(ctx, PZ_ERR_OPEN, "%s: cannot read: %s", path, strerror(errno));
    free(line);
    fclose(file);
    if (status != PZ_OK)
        return status;
    if (read == 0)
        return pz_error(ctx, PZ_ERR_DATA, "%s: empty panels file", path);
    if (read != face_count)
        return pz_error(ctx, PZ_ERR_DATA, "%s: %d panel ids for a mesh of %d faces (one per line expected)", path,
                        (int)read, (int)face_count);
    uint8_t *used = calloc((size_t)largest + 1, 1);
    if (!used)
        return pz_error(ctx, PZ_ERR_NOMEM, "%s: out of memory", path);
    for (int32_t f = 0; f < face_count; ++f)
        used[face_panel[f]] = 1;
    int32_t unused = -1;
    for (int32_t id = 0; id <= largest && unused < 0; ++id)
        if (!used[id])
            unused = id;
    free(used);
    if (unused >= 0)
        return pz_error(ctx, PZ_ERR_DATA, "%s: panel id %d is unused (ids must be 0..%d, each used)", path,
                        (int)unused, (int)largest);
    *panel_count = largest + 1;
    return PZ_OK;
}

/* ---------------------------------------------------------------- seams and darts */

/* The garment vertex of id `id` in panel file `panel` (ignored with one input file). */
static pz_status map_vertex(const char *path, int32_t line, const pz_vertex_space *space, int32_t panel,
                            int32_t id, int32_t *out, pz_ctx *ctx)
{
    int32_t file = space->file_count > 1 ? panel : 0;
    int32_t first = space->file_vertex_offset[file];
    int32_t count = space->file_vertex_offset[file + 1] - first;
    if (id >= count) {
        if (space->file_count > 1)
            return pz_error(ctx, PZ_ERR_DATA,
                            "%s: line %d: vertex %d is out of range (panel %d's file has %d vertices)", path,
                            (int)line, (int)id, (int)panel, (int)count);
        return pz_error(ctx, PZ_ERR_DATA, "%s: line %d: vertex %d is out of range (the mesh has %d vertices)", path,
                        (int)line, (int)id, (int)count);
    }
    int32_t garment_vertex = space->raw_to_garment[first + id];
    if (garment_vertex < 0)
        return pz_error(ctx, PZ_ERR_DATA, "%s: line %d: vertex %d is used by no face", path, (int)line, (int)id);
    *out = garment_vertex;
    return PZ_OK;
}

static pz_status check_panel(const char *path, int32_t line, const pz_vertex_space *space, int32_t panel,
                             pz_ctx *ctx)
{
    if (panel < space->panel_count)
        return PZ_OK;
    return pz_error(ctx, PZ_ERR_DATA, "%s: line %d: panel id %d is out of range (%d panel%s)", path, (int)line,
                    (int)panel, (int)space->panel_count, space->panel_count == 1 ? "" : "s");
}

/* Maps pairs[2i + side] of panel `panel` into out[i]. */
static pz_status map_pairs(const char *path, const pz_vertex_space *space, const int32_t *pairs,
                           const int32_t *pair_lines, int32_t pair_count, int side, int32_t panel, int32_t *out,
                           pz_ctx *ctx)
{
    for (int32_t i = 0; i < pair_count; ++i) {
        pz_status status = map_vertex(path, pair_lines[i], space, panel, pairs[2 * i + side], &out[i], ctx);
        if (status != PZ_OK)
            return status;
    }
    return PZ_OK;
}

pz_status pz_flatten_read_seam(const char *path, const pz_vertex_space *space, pz_seam *seam, pz_ctx *ctx)
{
    memset(seam, 0, sizeof *seam);
    static const char *const names[2] = {"panel id of side A", "panel id of side B"};
    int32_t header[2] = {0, 0}, header_lines[2] = {1, 2}, *pairs = NULL, *pair_lines = NULL, pair_count = 0;
    pz_status status = read_id_file(path, names, 2, header, header_lines, &pairs, &pair_lines, &pair_count, ctx);
    if (status != PZ_OK)
        return status;
    for (int k = 0; k < 2 && status == PZ_OK; ++k)
        status = check_panel(path, header_lines[k], space, header[k], ctx);
    if (status == PZ_OK) {
        seam->side_a = malloc((size_t)pair_count * sizeof(int32_t));
        seam->side_b = malloc((size_t)pair_count * sizeof(int32_t));
        if (!seam->side_a || !seam->side_b)
            status = pz_error(ctx, PZ_ERR_NOMEM, "%s: out of memory", path);
    }
    if (status == PZ_OK)
        status = map_pairs(path, space, pairs, pair_lines, pair_count, 0, header[0], seam->side_a, ctx);
    if (status == PZ_OK)
        status = map_pairs(path, space, pairs, pair_lines, pair_count, 1, header[1], seam->side_b, ctx);
    free(pairs);
    free(pair_lines);
    if (status != PZ_OK) {
        free(seam->side_a);
        free(seam->side_b);
        memset(seam, 0, sizeof *seam);
        return status;
    }
    seam->panel_a = header[0];
    seam->panel_b = header[1];
    seam->pair_count = pair_count;
    return PZ_OK;
}

/* The K of a base name "patch_K_dart_J...", or -1. */
static int32_t panel_from_dart_name(const char *path)
{
    const char *base = strrchr(path, '/');
    base = base ? base + 1 : path;
    if (strncmp(base, "patch_", 6) != 0 || !isdigit((unsigned char)base[6]))
        return -1;
    char *end = NULL;
    errno = 0;
    long panel = strtol(base + 6, &end, 10);
    if (errno == ERANGE || panel > INT32_MAX || strncmp(end, "_dart_", 6) != 0)
        return -1;
    return (int32_t)panel;
}

/* Splits "K:FILE" (K digits only) into K and FILE; otherwise *panel = -1 and *path = spec. */
static void split_dart_spec(const char *spec, int32_t *panel, const char **path)
{
    *panel = -1;
    *path = spec;
    const char *colon = strchr(spec, ':');
    if (!colon || colon == spec || colon - spec > 9)
        return;
    for (const char *c = spec; c < colon; ++c)
        if (!isdigit((unsigned char)*c))
            return;
    *panel = (int32_t)strtol(spec, NULL, 10);
    *path = colon + 1;
}

pz_status pz_flatten_read_dart(const char *spec, const pz_vertex_space *space, pz_dart *dart, pz_ctx *ctx)
{
    memset(dart, 0, sizeof *dart);
    int32_t panel;
    const char *path;
    split_dart_spec(spec, &panel, &path);
    if (panel >= 0 && panel >= space->panel_count)
        return pz_error(ctx, PZ_ERR_USAGE, "flatten: --darts %s: panel %d is out of range (%d panel%s)", spec,
                        (int)panel, (int)space->panel_count, space->panel_count == 1 ? "" : "s");
    if (panel < 0) {
        panel = panel_from_dart_name(path);
        if (panel >= space->panel_count)
            return pz_error(ctx, PZ_ERR_DATA, "%s: panel %d (from the file name) is out of range (%d panel%s)", path,
                            (int)panel, (int)space->panel_count, space->panel_count == 1 ? "" : "s");
    }
    if (panel < 0 && space->file_count > 1)
        return pz_error(ctx, PZ_ERR_USAGE,
                        "flatten: --darts %s: cannot tell the panel; name the file patch_K_dart_J.txt or give K:FILE",
                        spec);
    static const char *const names[1] = {"tip vertex"};
    int32_t tip = 0, tip_line = 1, *pairs = NULL, *pair_lines = NULL, pair_count = 0;
    pz_status status = read_id_file(path, names, 1, &tip, &tip_line, &pairs, &pair_lines, &pair_count, ctx);
    if (status != PZ_OK)
        return status;
    int32_t file_panel = panel < 0 ? 0 : panel;
    status = map_vertex(path, tip_line, space, file_panel, tip, &dart->tip, ctx);
    if (status == PZ_OK) {
        dart->leg_a = malloc((size_t)pair_count * sizeof(int32_t));
        dart->leg_b = malloc((size_t)pair_count * sizeof(int32_t));
        if (!dart->leg_a || !dart->leg_b)
            status = pz_error(ctx, PZ_ERR_NOMEM, "%s: out of memory", path);
    }
    if (status == PZ_OK)
        status = map_pairs(path, space, pairs, pair_lines, pair_count, 0, file_panel, dart->leg_a, ctx);
    if (status == PZ_OK)
        status = map_pairs(path, space, pairs, pair_lines, pair_count, 1, file_panel, dart->leg_b, ctx);
    free(pairs);
    free(pair_lines);
    if (status != PZ_OK) {
        free(dart->leg_a);
        free(dart->leg_b);
        memset(dart, 0, sizeof *dart);
        return status;
    }
    dart->panel = file_panel;
    dart->pair_count = pair_count;
    return PZ_OK;
}

/* ---------------------------------------------------------------- features file */

/* The whole file as one string; PZ_ERR_OPEN when it cannot be read. */
static pz_status read_text_file(const char *path, char **out, pz_ctx *ctx)
{
    *out = NULL;
    FILE *file = fopen(path, "rb");
    if (!file)
        return pz_error(ctx, PZ_ERR_OPEN, "%s: cannot open: %s", path, strerror(errno));
    size_t size = 0, capacity = 4096;
    char *text = malloc(capacity);
    while (text) {
        size += fread(text + size, 1, capacity - size - 1, file);
        if (size < capacity - 1)
            break;
        char *grown = capacity < ((size_t)1 << 30) ? realloc(text, capacity *= 2) : NULL;
        if (!grown)
            free(text);
        text = grown;
    }
    int failed = ferror(file);
    fclose(file);
    if (!text)
        return pz_error(ctx, PZ_ERR_NOMEM, "%s: out of memory reading the file", path);
    if (failed) {
        free(text);
        return pz_error(ctx, PZ_ERR_OPEN, "%s: cannot read", path);
    }
    text[size] = '\0';
    *out = text;
    return PZ_OK;
}

/* The curves array, checked for shape; counts its points. */
static pz_status check_features(const char *path, const cJSON *root, int64_t *point_total, pz_ctx *ctx)
{
    const cJSON *curves = cJSON_IsObject(root) ? cJSON_GetObjectItemCaseSensitive(root, "curves") : NULL;
    if (!cJSON_IsArray(curves) || cJSON_GetArraySize(curves) < 1)
        return pz_error(ctx, PZ_ERR_DATA, "%s: expected an object with a non-empty \"curves\" array", path);
    *point_total = 0;
    int c = 0;
    for (const cJSON *curve = curves->child; curve; curve = curve->next, ++c) {
        const cJSON *kind = cJSON_GetObjectItemCaseSensitive(curve, "kind");
        const cJSON *points = cJSON_GetObjectItemCaseSensitive(curve, "points");
        if (!cJSON_IsString(kind) || (strcmp(kind->valuestring, "key") != 0 && strcmp(kind->valuestring, "accessory") != 0))
            return pz_error(ctx, PZ_ERR_DATA, "%s: curve %d: \"kind\" must be \"key\" or \"accessory\"", path, c);
        if (!cJSON_IsArray(points) || cJSON_GetArraySize(points) < 2)
            return pz_error(ctx, PZ_ERR_DATA, "%s: curve %d: \"points\" must be an array of at least 2 points", path, c);
        int i = 0;
        for (const cJSON *point = points->child; point; point = point->next, ++i) {
            int ok = cJSON_IsArray(point) && cJSON_GetArraySize(point) == 3;
            for (const cJSON *x = ok ? point->child : NULL; x; x = x->next)
                ok &= cJSON_IsNumber(x) && isfinite(x->valuedouble);
            if (!ok)
                return pz_error(ctx, PZ_ERR_DATA, "%s: curve %d point %d: expected [x, y, z] (3 finite numbers)", path,
                                c, i);
        }
        *point_total += i;
    }
    if (c > INT32_MAX / 2 || *point_total > INT32_MAX / 3)
        return pz_error(ctx, PZ_ERR_DATA, "%s: too many curves or points", path);
    return PZ_OK;
}

/* Copies the checked curves out, converted to millimetres. */
static pz_status copy_features(const char *path, const cJSON *root, int64_t point_total, double mm_per_unit,
                               pz_feature_file *out, pz_ctx *ctx)
{
    const cJSON *curves = cJSON_GetObjectItemCaseSensitive(root, "curves");
    out->curve_count = (int32_t)cJSON_GetArraySize(curves);
    out->polylines = calloc((size_t)out->curve_count, sizeof *out->polylines);
    out->points = malloc(3 * (size_t)point_total * sizeof(double));
    if (!out->polylines || !out->points)
        return pz_error(ctx, PZ_ERR_NOMEM, "%s: out of memory", path);
    size_t at = 0;
    int32_t c = 0;
    for (const cJSON *curve = curves->child; curve; curve = curve->next, ++c) {
        const cJSON *kind = cJSON_GetObjectItemCaseSensitive(curve, "kind");
        const cJSON *points = cJSON_GetObjectItemCaseSensitive(curve, "points");
        pz_feature_polyline *polyline = &out->polylines[c];
        polyline->kind = strcmp(kind->valuestring, "key") == 0 ? PZ_FEATURE_KEY : PZ_FEATURE_ACCESSORY;
        polyline->point_count = (int32_t)cJSON_GetArraySize(points);
        polyline->points = out->points + 3 * at;
        for (const cJSON *point = points->child; point; point = point->next, ++at) {
            int k = 0;
            for (const cJSON *x = point->child; x; x = x->next, ++k)
                out->points[3 * at + (size_t)k] = x->valuedouble * mm_per_unit;
        }
    }
    return PZ_OK;
}

pz_status pz_flatten_read_features(const char *path, double mm_per_unit, pz_feature_file *out, pz_ctx *ctx)
{
    memset(out, 0, sizeof *out);
    char *text = NULL;
    pz_status read_status = read_text_file(path, &text, ctx);
    if (read_status != PZ_OK)
        return read_status;
    const char *end = NULL;
    cJSON *root = cJSON_ParseWithOpts(text, &end, 1);
    pz_status status = PZ_OK;
    if (!root) {
        /* cJSON stops where the text stops being JSON: name that line. */
        int line = 1;
        for (const char *c = text; end && c < end && *c; ++c)
            line += *c == '\n';
        status = pz_error(ctx, PZ_ERR_DATA, "%s: line %d: not valid JSON", path, line);
    }
    int64_t point_total = 0;
    if (status == PZ_OK)
        status = check_features(path, root, &point_total, ctx);
    if (status == PZ_OK)
        status = copy_features(path, root, point_total, mm_per_unit, out, ctx);
    cJSON_Delete(root);
    free(text);
    if (status != PZ_OK)
        pz_feature_file_clear(out);
    return status;
}

void pz_feature_file_clear(pz_feature_file *features)
{
    free(features->polylines);
    free(features->points);
    memset(features, 0, sizeof *features);
}

/* ---------------------------------------------------------------- per-panel boxes */

typedef struct panel_box {
    double lo[2], hi[2];
    double area, centroid[2];  /* signed 2D area and area centroid of the piece */
    int32_t panel;
} panel_box;

static pz_status panel_boxes(const pz_pattern *pattern, const double *uv, panel_box **out, pz_ctx *ctx)
{
    int32_t panel_count = pattern->panel_count;
    panel_box *boxes = malloc(((size_t)panel_count + 1) * sizeof *boxes);
    if (!boxes)
        return pz_error(ctx, PZ_ERR_NOMEM, "out of memory laying out %d panels", (int)panel_count);
    for (int32_t p = 0; p < panel_count; ++p) {
        boxes[p] = (panel_box){{DBL_MAX, DBL_MAX}, {-DBL_MAX, -DBL_MAX}, 0, {0, 0}, p};
    }
    const pz_mesh *mesh = pattern->mesh;
    for (int32_t f = 0; f < mesh->face_count; ++f) {
        panel_box *box = &boxes[pattern->face_panel[f]];
        const double *a = &uv[2 * mesh->faces[3 * f]], *b = &uv[2 * mesh->faces[3 * f + 1]],
                     *c = &uv[2 * mesh->faces[3 * f + 2]];
        const double *corners[3] = {a, b, c};
        for (int k = 0; k < 3; ++k)
            for (int d = 0; d < 2; ++d) {
                box->lo[d] = fmin(box->lo[d], corners[k][d]);
                box->hi[d] = fmax(box->hi[d], corners[k][d]);
            }
        double area = 0.5 * ((b[0] - a[0]) * (c[1] - a[1]) - (c[0] - a[0]) * (b[1] - a[1]));
        box->area += area;
        for (int d = 0; d < 2; ++d)
            box->centroid[d] += area * (a[d] + b[d] + c[d]) / 3.0;
    }
    for (int32_t p = 0; p < panel_count; ++p) {
        panel_box *box = &boxes[p];
        if (fabs(box->area) > 0) {
            box->centroid[0] /= box->area;
            box->centroid[1] /= box->area;
        } else {
            box->centroid[0] = 0.5 * (box->lo[0] + box->hi[0]);
            box->centroid[1] = 0.5 * (box->lo[1] + box->hi[1]);
        }
    }
    *out = boxes;
    return PZ_OK;
}

/* ---------------------------------------------------------------- layout */

static int compare_box_lo_x(const void *a, const void *b)
{
    const panel_box *x = a, *y = b;
    return (x->lo[0] > y->lo[0]) - (x->lo[0] < y->lo[0]);
}

static int compare_box_height(const void *a, const void *b)
{
    const panel_box *x = a, *y = b;
    double hx = x->hi[1] - x->lo[1], hy = y->hi[1] - y->lo[1];
    if (hx != hy)
        return (hx < hy) - (hx > hy);  /* tallest first */
    return (x->panel > y->panel) - (x->panel < y->panel);
}

/* 1 when two boxes overlap: a sweep over the boxes sorted by min x. */
static int boxes_overlap(panel_box *boxes, int32_t count)
{
    qsort(boxes, (size_t)count, sizeof *boxes, compare_box_lo_x);
    for (int32_t i = 0; i < count; ++i)
        for (int32_t j = i + 1; j < count && boxes[j].lo[0] < boxes[i].hi[0]; ++j)
            if (boxes[j].lo[1] < boxes[i].hi[1] && boxes[i].lo[1] < boxes[j].hi[1])
                return 1;
    return 0;
}

pz_status pz_pattern_layout(const pz_pattern *pattern, double *uv, double gap_mm, int *moved, pz_ctx *ctx)
{
    *moved = 0;
    int32_t panel_count = pattern->panel_count;
    panel_box *boxes = NULL;
    pz_status status = panel_boxes(pattern, uv, &boxes, ctx);
    if (status != PZ_OK)
        return status;
    if (!boxes_overlap(boxes, panel_count)) {
        free(boxes);
        return PZ_OK;
    }
    double *shift = calloc(2 * (size_t)panel_count + 1, sizeof(double));
    if (!shift) {
        free(boxes);
        return pz_error(ctx, PZ_ERR_NOMEM, "out of memory laying out %d panels", (int)panel_count);
    }
    /* Rows about as wide as the layout will be tall: the square root of the total box area. */
    double box_area = 0, widest = 0;
    for (int32_t i = 0; i < panel_count; ++i) {
        double width = boxes[i].hi[0] - boxes[i].lo[0], height = boxes[i].hi[1] - boxes[i].lo[1];
        box_area += (width + gap_mm) * (height + gap_mm);
        widest = fmax(widest, width);
    }
    double row_width = fmax(widest, 1.2 * sqrt(box_area));
    qsort(boxes, (size_t)panel_count, sizeof *boxes, compare_box_height);
    double x = 0, row_top = 0, row_height = 0;
    for (int32_t i = 0; i < panel_count; ++i) {
        const panel_box *box = &boxes[i];
        double width = box->hi[0] - box->lo[0], height = box->hi[1] - box->lo[1];
        if (x > 0 && x + width > row_width) {
            row_top -= row_height + gap_mm;
            x = 0;
            row_height = 0;
        }
        shift[2 * box->panel] = x - box->lo[0];
        shift[2 * box->panel + 1] = row_top - box->hi[1];
        x += width + gap_mm;
        row_height = fmax(row_height, height);
    }
    /* Each cut-mesh vertex belongs to one panel: move it with that panel's shift. */
    const pz_mesh *mesh = pattern->mesh;
    uint8_t *done = calloc((size_t)mesh->vertex_count + 1, 1);
    if (!done) {
        free(shift);
        free(boxes);
        return pz_error(ctx, PZ_ERR_NOMEM, "out of memory laying out %d panels", (int)panel_count);
    }
    for (int32_t c = 0; c < 3 * mesh->face_count; ++c) {
        int32_t v = mesh->faces[c], p = pattern->face_panel[c / 3];
        if (done[v])
            continue;
        done[v] = 1;
        uv[2 * v] += shift[2 * p];
        uv[2 * v + 1] += shift[2 * p + 1];
    }
    free(done);
    free(shift);
    free(boxes);
    *moved = 1;
    return PZ_OK;
}

/* ---------------------------------------------------------------- garment.obj */

/* The shortest %.Ng (15..17 digits) that reads back as exactly `value`. */
static void format_exact(char *buffer, size_t size, double value)
{
    for (int digits = 15; digits <= 17; ++digits) {
        snprintf(buffer, size, "%.*g", digits, value);
        if (strtod(buffer, NULL) == value)
            return;
    }
}

pz_status pz_pattern_write_obj(FILE *file, const pz_mesh *garment, const double *positions,
                               const pz_pattern *pattern, const double *uv, pz_ctx *ctx)
{
    (void)ctx; /* write errors surface in pz_output_commit */
    fprintf(file, "# panelize flatten: the garment's own vertices and faces; vt = the sewing pattern in mm;\n"
                  "# one group per panel (panel_K)\n");
    char x[32], y[32], z[32];
    for (int32_t v = 0; v < garment->vertex_count; ++v) {
        format_exact(x, sizeof x, positions[3 * v]);
        format_exact(y, sizeof y, positions[3 * v + 1]);
        format_exact(z, sizeof z, positions[3 * v + 2]);
        fprintf(file, "v %s %s %s\n", x, y, z);
    }
    const pz_mesh *cut = pattern->mesh;
    for (int32_t v = 0; v < cut->vertex_count; ++v)
        fprintf(file, "vt %.6f %.6f\n", uv[2 * v], uv[2 * v + 1]);
    int32_t current = -1;
    for (int32_t f = 0; f < garment->face_count; ++f) {
        if (pattern->face_panel[f] != current) {
            current = pattern->face_panel[f];
            fprintf(file, "g panel_%d\n", (int)current);
        }
        const int32_t *corners = &garment->faces[3 * f], *cut_corners = &cut->faces[3 * f];
        fprintf(file, "f %d/%d %d/%d %d/%d\n", (int)corners[0] + 1, (int)cut_corners[0] + 1, (int)corners[1] + 1,
                (int)cut_corners[1] + 1, (int)corners[2] + 1, (int)cut_corners[2] + 1);
    }
    return PZ_OK;
}

/* ---------------------------------------------------------------- pattern.svg */

static void write_xml_text(FILE *file, const char *text)
{
    for (; *text; ++text) {
        switch (*text) {
        case '&': fputs("&amp;", file); break;
        case '<': fputs("&lt;", file); break;
        case '>': fputs("&gt;", file); break;
        case '"': fputs("&quot;", file); break;
        default:
            if ((unsigned char)*text >= 0x20 || *text == '\t')
                fputc(*text, file);
        }
    }
}

/* Point v of the cut mesh in SVG coordinates (y down). */
static void svg_point(FILE *file, const double *uv, int32_t v, const char *command)
{
    fprintf(file, "%s%.3f %.3f", command, uv[2 * v], -uv[2 * v + 1]);
}

/* Buckets of ids by panel: offsets (panel_count + 1) and ids, a counting sort. */
typedef struct panel_buckets {
    int32_t *offsets;
    int32_t *ids;
} panel_buckets;

static int bucket_by_panel(const int32_t *panel_of, int32_t count, int32_t panel_count, panel_buckets *out)
{
    out->offsets = calloc((size_t)panel_count + 2, sizeof(int32_t));
    out->ids = malloc(((size_t)count + 1) * sizeof(int32_t));
    if (!out->offsets || !out->ids)
        return 0;
    for (int32_t i = 0; i < count; ++i)
        ++out->offsets[panel_of[i] + 2];
    for (int32_t p = 0; p < panel_count; ++p)
        out->offsets[p + 2] += out->offsets[p + 1];
    for (int32_t i = 0; i < count; ++i)
        out->ids[out->offsets[panel_of[i] + 1]++] = i;
    return 1;
}

static void buckets_free(panel_buckets *buckets)
{
    free(buckets->offsets);
    free(buckets->ids);
}

static void write_svg_piece(FILE *file, const pz_topology *topology,
                            const pz_loops *loops, const double *uv, const panel_box *box, const char *name,
                            const panel_buckets *edges, const panel_buckets *loop_buckets)
{
    int32_t p = box->panel;
    fprintf(file, "<g id=\"panel_%d\">\n", (int)p);
    fputs("<path class=\"mesh\" fill=\"none\" stroke=\"#c8c8c8\" stroke-width=\"0.2\" d=\"", file);
    for (int32_t i = edges->offsets[p]; i < edges->offsets[p + 1]; ++i) {
        int32_t h = topology->edge_halfedge[2 * edges->ids[i]];
        svg_point(file, uv, pz_he_from(topology, h), i == edges->offsets[p] ? "M" : " M");
        svg_point(file, uv, pz_he_to(topology, h), " L");
    }
    fputs("\"/>\n<path class=\"outline\" fill=\"none\" stroke=\"#000000\" stroke-width=\"0.5\" d=\"", file);
    for (int32_t i = loop_buckets->offsets[p]; i < loop_buckets->offsets[p + 1]; ++i) {
        int32_t loop = loop_buckets->ids[i];
        for (int32_t j = loops->loop_offsets[loop]; j < loops->loop_offsets[loop + 1]; ++j) {
            const char *command = j > loops->loop_offsets[loop] ? " L" : i > loop_buckets->offsets[p] ? " M" : "M";
            svg_point(file, uv, loops->loop_vertices[j], command);
        }
        fputs(" Z", file);
    }
    fputs("\"/>\n", file);
    /* Grainline: 60% of the piece's height along +v (up on paper), arrowhead at the top. */
    double height = box->hi[1] - box->lo[1], width = box->hi[0] - box->lo[0];
    double half = 0.3 * height, head = fmin(0.05 * height, 15.0);
    double cx = box->centroid[0], top = -(box->centroid[1] + half), bottom = -(box->centroid[1] - half);
    double font = fmax(4.0, fmin(30.0, 0.06 * fmin(width, height)));
    fprintf(file,
            "<path class=\"grainline\" fill=\"none\" stroke=\"#b00000\" stroke-width=\"0.8\" "
            "d=\"M%.3f %.3f L%.3f %.3f M%.3f %.3f L%.3f %.3f L%.3f %.3f\"/>\n",
            cx, bottom, cx, top, cx - 0.6 * head, top + head, cx, top, cx + 0.6 * head, top + head);
    fprintf(file,
            "<text class=\"grain\" x=\"%.3f\" y=\"%.3f\" font-size=\"%.2f\" fill=\"#b00000\" "
            "text-anchor=\"middle\" transform=\"rotate(-90 %.3f %.3f)\">grain (warp)</text>\n",
            cx - 0.4 * font, -box->centroid[1], 0.7 * font, cx - 0.4 * font, -box->centroid[1]);
    fprintf(file, "<text class=\"name\" x=\"%.3f\" y=\"%.3f\" font-size=\"%.2f\" text-anchor=\"start\">panel_%d",
            cx + 0.8 * font, -box->centroid[1], font, (int)p);
    if (name && *name) {
        fputs(" (", file);
        write_xml_text(file, name);
        fputc(')', file);
    }
    fputs("</text>\n</g>\n", file);
}

pz_status pz_pattern_write_svg(FILE *file, const pz_pattern *pattern, const double *uv,
                               const char *const *panel_names, pz_ctx *ctx)
{
    const pz_mesh *mesh = pattern->mesh;
    int32_t panel_count = pattern->panel_count;
    pz_topology *topology = NULL;
    pz_loops *loops = NULL;
    panel_box *boxes = NULL;
    int32_t *edge_panel = NULL, *loop_panel = NULL;
    panel_buckets edges = {0}, loop_buckets = {0};
    pz_status status = pz_topology_build(mesh, &topology, ctx);
    if (status == PZ_OK)
        status = pz_topology_boundary_loops(topology, &loops, ctx);
    if (status == PZ_OK)
        status = panel_boxes(pattern, uv, &boxes, ctx);
    if (status == PZ_OK) {
        edge_panel = malloc(((size_t)topology->edge_count + 1) * sizeof(int32_t));
        loop_panel = malloc(((size_t)loops->loop_count + 1) * sizeof(int32_t));
        if (!edge_panel || !loop_panel)
            status = pz_error(ctx, PZ_ERR_NOMEM, "pattern.svg: out of memory");
    }
    if (status == PZ_OK) {
        for (int32_t e = 0; e < topology->edge_count; ++e)
            edge_panel[e] = pattern->face_panel[pz_he_face(topology->edge_halfedge[2 * e])];
        /* A boundary vertex's vertex_halfedge is its outgoing boundary half-edge: its face names the panel. */
        for (int32_t l = 0; l < loops->loop_count; ++l)
            loop_panel[l] = pattern->face_panel[pz_he_face(
                topology->vertex_halfedge[loops->loop_vertices[loops->loop_offsets[l]]])];
        if (!bucket_by_panel(edge_panel, topology->edge_count, panel_count, &edges) ||
            !bucket_by_panel(loop_panel, loops->loop_count, panel_count, &loop_buckets))
            status = pz_error(ctx, PZ_ERR_NOMEM, "pattern.svg: out of memory");
    }
    if (status == PZ_OK) {
        double lo[2] = {DBL_MAX, DBL_MAX}, hi[2] = {-DBL_MAX, -DBL_MAX};
        for (int32_t p = 0; p < panel_count; ++p)
            for (int d = 0; d < 2; ++d) {
                lo[d] = fmin(lo[d], boxes[p].lo[d]);
                hi[d] = fmax(hi[d], boxes[p].hi[d]);
            }
        if (panel_count == 0)
            lo[0] = lo[1] = hi[0] = hi[1] = 0;
        double margin = 10.0, width = hi[0] - lo[0] + 2 * margin, height = hi[1] - lo[1] + 2 * margin;
        fprintf(file,
                "<?xml version=\"1.0\" encoding=\"UTF-8\"?>\n"
                "<!-- panelize flatten: pattern pieces at 1:1 scale, 1 user unit = 1 mm; "
                "grainlines along the warp -->\n"
                "<svg xmlns=\"http://www.w3.org/2000/svg\" version=\"1.1\" width=\"%.3fmm\" height=\"%.3fmm\" "
                "viewBox=\"%.3f %.3f %.3f %.3f\" font-family=\"sans-serif\">\n",
                width, height, lo[0] - margin, -hi[1] - margin, width, height);
        for (int32_t p = 0; p < panel_count; ++p)
            write_svg_piece(file, topology, loops, uv, &boxes[p], panel_names ? panel_names[p] : NULL,
                            &edges, &loop_buckets);
        fputs("</svg>\n", file);
    }
    buckets_free(&edges);
    buckets_free(&loop_buckets);
    free(edge_panel);
    free(loop_panel);
    free(boxes);
    pz_loops_free(&loops);
    pz_topology_free(&topology);
    return status;
}

/* ---------------------------------------------------------------- report.json */

typedef struct json_builder {
    int failed;
} json_builder;

static void add_number(json_builder *builder, cJSON *object, const char *key, double value, int decimals)
{
    /* + 0.0 turns a rounded -0 into 0 */
    if (!cJSON_AddNumberToObject(object, key, pz_cli_round(value, decimals) + 0.0))
        builder->failed = 1;
}

static cJSON *add_object(json_builder *builder, cJSON *parent, const char *key)
{
    cJSON *object = cJSON_AddObjectToObject(parent, key);
    if (!object)
        builder->failed = 1;
    return object;
}

static cJSON *add_array(json_builder *builder, cJSON *parent, const char *key)
{
    cJSON *array = cJSON_AddArrayToObject(parent, key);
    if (!array)
        builder->failed = 1;
    return array;
}

static cJSON *append_object(json_builder *builder, cJSON *array)
{
    cJSON *object = cJSON_CreateObject();
    if (!object || !cJSON_AddItemToArray(array, object)) {
        cJSON_Delete(object);
        builder->failed = 1;
        return NULL;
    }
    return object;
}

static void add_doubles(json_builder *builder, cJSON *parent, const char *key, const double *values, int count,
                        int decimals)
{
    double rounded[8];
    for (int i = 0; i < count && i < 8; ++i)
        rounded[i] = pz_cli_round(values[i], decimals);
    cJSON *array = cJSON_CreateDoubleArray(rounded, count);
    if (!array || !cJSON_AddItemToObject(parent, key, array)) {
        cJSON_Delete(array);
        builder->failed = 1;
    }
}

/* max and p95 (magnitudes): the largest over the poses measured; mean (signed): the one of largest magnitude. */
static void add_stat(json_builder *builder, cJSON *parent, const char *key, const pz_flatten_report *report,
                     int32_t panel, size_t offset, int decimals)
{
    cJSON *object = cJSON_AddObjectToObject(parent, key);
    if (!object) {
        builder->failed = 1;
        return;
    }
    pz_stat worst = {-DBL_MAX, -DBL_MAX, 0};
    for (int i = 0; i < report->metrics_count; ++i) {
        const pz_stat *stat = (const pz_stat *)((const char *)&report->metrics[i]->panels[panel] + offset);
        worst.max = fmax(worst.max, stat->max);
        worst.p95 = fmax(worst.p95, stat->p95);
        if (i == 0 || fabs(stat->mean) > fabs(worst.mean))
            worst.mean = stat->mean;
    }
    add_number(builder, object, "max", worst.max, decimals);
    add_number(builder, object, "p95", worst.p95, decimals);
    add_number(builder, object, "mean", worst.mean, decimals);
}

static void add_input(json_builder *builder, cJSON *root, const pz_flatten_report *report)
{
    cJSON *input = add_object(builder, root, "input");
    if (!input)
        return;
    if (!cJSON_AddStringToObject(input, "file", report->input_paths[0]))
        builder->failed = 1;
    cJSON *files = cJSON_CreateStringArray(report->input_paths, report->input_count);
    if (!files || !cJSON_AddItemToObject(input, "files", files)) {
        cJSON_Delete(files);
        builder->failed = 1;
    }
    add_number(builder, input, "vertices", report->vertices, 0);
    add_number(builder, input, "faces", report->faces, 0);
    add_number(builder, input, "poses", report->poses, 0);
    if (!cJSON_AddStringToObject(input, "units", report->units) ||
        !cJSON_AddBoolToObject(input, "units_guessed", report->units_guessed) ||
        !cJSON_AddStringToObject(input, "panels_from", report->panels_source))
        builder->failed = 1;
}

static void add_parameters(json_builder *builder, cJSON *root, const pz_flatten_report *report)
{
    cJSON *parameters = add_object(builder, root, "parameters");
    if (!parameters)
        return;
    if (!cJSON_AddStringToObject(parameters, "backend", report->backend))
        builder->failed = 1;
    add_number(builder, parameters, "iterations", report->iterations, 0);
    cJSON *weights = add_object(builder, parameters, "weights");
    if (weights) {
        add_number(builder, weights, "stretch", report->weights[0], 6);
        add_number(builder, weights, "rigid", report->weights[1], 6);
        add_number(builder, weights, "dart", report->weights[2], 6);
        add_number(builder, weights, "seam", report->weights[3], 6);
    }
    cJSON *fabric = add_object(builder, parameters, "fabric");
    if (fabric) {
        add_number(builder, fabric, "k_su_N_per_mm", report->fabric.k_su, 6);
        add_number(builder, fabric, "k_sv_N_per_mm", report->fabric.k_sv, 6);
        add_number(builder, fabric, "k_r_N_per_mm_rad", report->fabric.k_r, 6);
    }
    add_doubles(builder, parameters, "grain", report->grain, 3, 6);
    if (report->grain_source && !cJSON_AddStringToObject(parameters, "grain_source", report->grain_source))
        builder->failed = 1;
    if (report->wirewarp && !cJSON_AddStringToObject(parameters, "scheme", report->progressive ? "progressive" : "global"))
        builder->failed = 1;
    if (report->springmass) {
        if (!cJSON_AddStringToObject(parameters, "relax", report->relax_full ? "full" : "heap") ||
            !cJSON_AddBoolToObject(parameters, "orthotropic", report->orthotropic))
            builder->failed = 1;
    }
    if (report->textile) {
        cJSON *textile = add_object(builder, parameters, "textile_result");
        if (textile) {
            add_number(builder, textile, "iterations_run", report->textile->iterations_run, 0);
            add_number(builder, textile, "initial_energy", report->textile->initial_energy, 6);
            add_number(builder, textile, "final_energy", report->textile->final_energy, 6);
            if (!cJSON_AddBoolToObject(textile, "converged", report->textile->converged))
                builder->failed = 1;
        }
    }
}

static void add_timings(json_builder *builder, cJSON *root, const pz_flatten_report *report)
{
    static const char *const names[6] = {"read", "pattern", "flatten", "metrics", "write", "total"};
    cJSON *timings = add_object(builder, root, "timings_ms");
    for (int i = 0; timings && i < 6; ++i)
        add_number(builder, timings, names[i], report->timings_ms[i], 3);
}

static void add_panels(json_builder *builder, cJSON *root, const pz_flatten_report *report)
{
    cJSON *panels = add_array(builder, root, "panels");
    const pz_metrics *rest = report->metrics[0];
    for (int32_t p = 0; panels && p < rest->panel_count; ++p) {
        const pz_panel_metrics *m = &rest->panels[p];
        cJSON *panel = append_object(builder, panels);
        if (!panel)
            return;
        add_number(builder, panel, "id", p, 0);
        const char *name = report->panel_names ? report->panel_names[p] : NULL;
        if (name && !cJSON_AddStringToObject(panel, "name", name))
            builder->failed = 1;
        add_number(builder, panel, "faces", m->face_count, 0);
        add_number(builder, panel, "area_3d_mm2", m->area_3d_mm2, 3);
        add_number(builder, panel, "area_2d_mm2", m->area_2d_mm2, 3);
        add_stat(builder, panel, "strain_warp", report, p, offsetof(pz_panel_metrics, strain_warp), 8);
        add_stat(builder, panel, "strain_weft", report, p, offsetof(pz_panel_metrics, strain_weft), 8);
        add_stat(builder, panel, "shear_deg", report, p, offsetof(pz_panel_metrics, shear_deg), 6);
        add_number(builder, panel, "orthotropic_energy", m->orthotropic_energy, 6);
        add_number(builder, panel, "arap_energy", m->arap_energy, 6);
        add_number(builder, panel, "E_len", m->e_len, 12);
        add_number(builder, panel, "E_ang", m->e_ang, 12);
        add_number(builder, panel, "E_area", m->e_area, 12);
        add_number(builder, panel, "E_shape", m->e_shape, 12);
        add_number(builder, panel, "flipped_triangles", m->flipped_triangles, 0);
        add_number(builder, panel, "boundary_self_intersections", m->boundary_self_intersections, 0);
    }
}

static void add_bool(json_builder *builder, cJSON *object, const char *key, int value)
{
    if (!cJSON_AddBoolToObject(object, key, value))
        builder->failed = 1;
}

static void add_string(json_builder *builder, cJSON *object, const char *key, const char *value)
{
    if (!cJSON_AddStringToObject(object, key, value))
        builder->failed = 1;
}

static void add_wirewarp_result(json_builder *builder, cJSON *object, const pz_flatten_report *report)
{
    const pz_wirewarp_result *r = report->wirewarp;
    add_string(builder, object, "scheme", report->progressive ? "progressive" : "global");
    add_number(builder, object, "feature_curves", report->feature_count, 0);
    add_number(builder, object, "wire_patches", r->wire_patch_count, 0);
    add_number(builder, object, "wire_nodes", r->wire_node_count, 0);
    add_number(builder, object, "wire_edges", r->wire_edge_count, 0);
    add_number(builder, object, "locked_angles", r->locked_count, 0);
    add_number(builder, object, "constraints", r->constraint_count, 0);
    add_number(builder, object, "newton_iterations", r->iterations, 0);
    add_number(builder, object, "e_len_wires", r->e_len_wires, 15);
    add_number(builder, object, "max_wire_error", r->max_wire_error, 15);
    add_number(builder, object, "constraint_residual", r->constraint_residual, 15);
    add_bool(builder, object, "best_effort", r->best_effort);
    add_bool(builder, object, "interior_fallback", r->interior_fallback);
    add_bool(builder, object, "interior_inverse_length", r->interior_inverse_length);
    add_bool(builder, object, "injective", r->injective);
    add_number(builder, object, "flipped_triangles", r->flipped_triangles, 0);
    add_number(builder, object, "angle_ms", r->angle_ms, 3);
    add_number(builder, object, "layout_ms", r->layout_ms, 3);
    add_number(builder, object, "interior_ms", r->interior_ms, 3);
    /* What a best-effort result gave up (docs/wirewarp.md "Results that are not errors"). */
    add_number(builder, object, "trimmed_feature_edges", r->trimmed_feature_edges, 0);
    add_number(builder, object, "untangled_vertices", r->untangled_vertices, 0);
    int32_t listed = r->relaxed_key_curve_count < PZ_WIREWARP_RELAXED_MAX ? r->relaxed_key_curve_count
                                                                           : PZ_WIREWARP_RELAXED_MAX;
    cJSON *relaxed = cJSON_CreateIntArray(r->relaxed_key_curves, listed);
    if (!relaxed || !cJSON_AddItemToObject(object, "relaxed_key_curves", relaxed)) {
        cJSON_Delete(relaxed);
        builder->failed = 1;
    }
    add_number(builder, object, "relaxed_key_curve_count", r->relaxed_key_curve_count, 0);
    add_number(builder, object, "relaxed_key_angle_deg", r->relaxed_key_angle * 180 / 3.14159265358979323846, 6);
    cJSON *skipped = add_array(builder, object, "skipped_feature_curves");
    for (int32_t i = 0; skipped && i < report->skipped_feature_count; ++i) {
        cJSON *curve = append_object(builder, skipped);
        if (!curve)
            return;
        add_number(builder, curve, "curve", report->skipped_features[i].curve, 0);
        add_string(builder, curve, "problem", report->skipped_features[i].problem);
    }
}

static const char *stop_name(int stop)
{
    switch (stop) {
    case PZ_SPRINGMASS_STOP_ACCURACY: return "accuracy";
    case PZ_SPRINGMASS_STOP_VARIATION: return "energy variation";
    case PZ_SPRINGMASS_STOP_ITERATIONS: return "iteration cap";
    default: return "none";
    }
}

static const char *seam_kind_name(pz_seam_kind kind)
{
    return kind == PZ_SEAM_KIND_DART ? "dart" : kind == PZ_SEAM_KIND_GUSSET ? "gusset" : "none";
}

/* The crest line of one panel: cut-mesh vertices, their 3D points (mm) and pattern points (mm). */
static void add_cutting_line(json_builder *builder, cJSON *object, const pz_flatten_report *report,
                             const pz_springmass_panel *panel)
{
    cJSON *line = add_object(builder, object, "cutting_line");
    cJSON *vertices = line ? cJSON_CreateIntArray(panel->cut_vertices, panel->cut_vertex_count) : NULL;
    if (!vertices || !cJSON_AddItemToObject(line, "vertices", vertices)) {
        cJSON_Delete(vertices);
        builder->failed = 1;
        return;
    }
    cJSON *points = add_array(builder, line, "points_3d_mm");
    cJSON *points_2d = add_array(builder, line, "points_2d_mm");
    const pz_mesh *mesh = report->pattern->mesh;
    for (int32_t i = 0; points && points_2d && i < panel->cut_vertex_count; ++i) {
        int32_t v = panel->cut_vertices[i];
        const double *x = mesh->positions + 3 * (size_t)v;
        double xyz[3] = {pz_cli_round(x[0], 6), pz_cli_round(x[1], 6), pz_cli_round(x[2], 6)};
        cJSON *point = cJSON_CreateDoubleArray(xyz, 3);
        if (!point || !cJSON_AddItemToArray(points, point)) {
            cJSON_Delete(point);
            builder->failed = 1;
        }
        double uv[2] = {pz_cli_round(report->uv[2 * (size_t)v], 6), pz_cli_round(report->uv[2 * (size_t)v + 1], 6)};
        cJSON *point_2d = cJSON_CreateDoubleArray(uv, 2);
        if (!point_2d || !cJSON_AddItemToArray(points_2d, point_2d)) {
            cJSON_Delete(point_2d);
            builder->failed = 1;
        }
    }
}

static void add_springmass_result(json_builder *builder, cJSON *object, const pz_flatten_report *report)
{
    const pz_springmass_result *r = report->springmass;
    add_string(builder, object, "relax", report->relax_full ? "full" : "heap");
    add_bool(builder, object, "orthotropic", report->orthotropic);
    add_number(builder, object, "phase_one_energy", r->phase_one_energy, 6);
    add_number(builder, object, "final_energy", r->final_energy, 6);
    add_number(builder, object, "node_relaxations", (double)r->node_relaxations, 0);
    add_number(builder, object, "phase_one_relaxations", (double)r->phase_one_relaxations, 0);
    add_number(builder, object, "energy_evaluations", (double)r->energy_evaluations, 0);
    add_number(builder, object, "phase_one_ms", r->phase_one_ms, 3);
    add_number(builder, object, "phase_two_ms", r->phase_two_ms, 3);
    add_number(builder, object, "matched_pairs", r->matched_pairs, 0);
    add_number(builder, object, "unmatched_panels", r->unmatched_panels, 0);
    add_number(builder, object, "retried_panels", r->retried_panels, 0);
    add_number(builder, object, "max_seam_mismatch", r->max_seam_mismatch, 8);
    cJSON *panels = add_array(builder, object, "panels");
    for (int32_t p = 0; panels && p < r->panel_count; ++p) {
        const pz_springmass_panel *m = &r->panels[p];
        cJSON *panel = append_object(builder, panels);
        if (!panel)
            return;
        add_number(builder, panel, "id", m->panel, 0);
        add_string(builder, panel, "stop", stop_name(m->stop));
        add_number(builder, panel, "sweeps", m->iterations, 0);
        add_number(builder, panel, "phase_one_energy", m->phase_one_energy, 6);
        add_number(builder, panel, "final_energy", m->final_energy, 6);
        add_number(builder, panel, "E_area", m->e_area, 12);
        add_number(builder, panel, "E_shape", m->e_shape, 12);
        add_number(builder, panel, "max_energy_vertex", m->max_energy_vertex, 0);
        add_string(builder, panel, "seam_kind", seam_kind_name(m->cut_kind));
        add_number(builder, panel, "cut_opening_mm2", m->cut_opening_mm2, 3);
        add_number(builder, panel, "cut_energy", m->cut_energy, 6);
        add_cutting_line(builder, panel, report, m);
    }
    /* Indexed by cut-mesh vertex = the vt index of garment.obj. */
    add_string(builder, object, "energy_map_vertices", "pattern (vt of garment.obj)");
    add_number(builder, object, "energy_map_count", r->vertex_count, 0);
    cJSON *map = cJSON_CreateArray();
    for (int32_t v = 0; map && v < r->vertex_count; ++v) {
        cJSON *value = cJSON_CreateNumber(pz_cli_round(r->vertex_energy[v], 9) + 0.0);
        if (!value || !cJSON_AddItemToArray(map, value)) {
            cJSON_Delete(value);
            cJSON_Delete(map);
            map = NULL;
        }
    }
    if (!map || !cJSON_AddItemToObject(object, "energy_map", map)) {
        cJSON_Delete(map);
        builder->failed = 1;
    }
}

/* backend_result: what the chosen back-end itself reports (the metrics above are shared by all). */
static void add_backend_result(json_builder *builder, cJSON *root, const pz_flatten_report *report)
{
    cJSON *object = add_object(builder, root, "backend_result");
    if (!object)
        return;
    add_string(builder, object, "backend", report->backend);
    add_number(builder, object, "ms", report->backend_ms, 3);
    if (report->textile) {
        add_number(builder, object, "iterations_run", report->textile->iterations_run, 0);
        add_number(builder, object, "initial_energy", report->textile->initial_energy, 6);
        add_number(builder, object, "final_energy", report->textile->final_energy, 6);
        add_bool(builder, object, "converged", report->textile->converged);
        add_number(builder, object, "damped_steps", report->textile->damped_steps, 0);
    }
    if (report->wirewarp)
        add_wirewarp_result(builder, object, report);
    if (report->springmass)
        add_springmass_result(builder, object, report);
}

static void add_seams_and_darts(json_builder *builder, cJSON *root, const pz_flatten_report *report)
{
    const pz_metrics *rest = report->metrics[0];
    cJSON *seams = add_array(builder, root, "seams");
    for (int32_t s = 0; seams && s < rest->seam_count; ++s) {
        const pz_seam_metrics *m = &rest->seams[s];
        cJSON *seam = append_object(builder, seams);
        if (!seam)
            return;
        add_number(builder, seam, "id", s, 0);
        int panels[2] = {m->panel_a, m->panel_b};
        cJSON *pair = cJSON_CreateIntArray(panels, 2);
        if (!pair || !cJSON_AddItemToObject(seam, "panels", pair)) {
            cJSON_Delete(pair);
            builder->failed = 1;
        }
        if (s < report->pattern->seam_count)
            add_number(builder, seam, "vertex_pairs", report->pattern->seams[s].pair_count, 0);
        add_number(builder, seam, "length_3d_mm", m->length_3d_mm, 4);
        add_number(builder, seam, "length_a_mm", m->length_a_mm, 4);
        add_number(builder, seam, "length_b_mm", m->length_b_mm, 4);
        add_number(builder, seam, "mismatch_rel", m->mismatch_rel, 8);
        add_number(builder, seam, "reflection_residual_mm", m->reflection_residual_mm, 6);
    }
    cJSON *darts = add_array(builder, root, "darts");
    for (int32_t d = 0; darts && d < rest->dart_count; ++d) {
        const pz_dart_metrics *m = &rest->darts[d];
        cJSON *dart = append_object(builder, darts);
        if (!dart)
            return;
        add_number(builder, dart, "id", d, 0);
        if (d < report->pattern->dart_count) {
            add_number(builder, dart, "panel", report->pattern->darts[d].panel, 0);
            add_number(builder, dart, "vertex_pairs", report->pattern->darts[d].pair_count, 0);
        }
        add_number(builder, dart, "leg_a_mm", m->leg_a_mm, 4);
        add_number(builder, dart, "leg_b_mm", m->leg_b_mm, 4);
        add_number(builder, dart, "mismatch_rel", m->mismatch_rel, 8);
        add_number(builder, dart, "symmetry_residual_mm", m->symmetry_residual_mm, 6);
    }
}

static void add_summary(json_builder *builder, cJSON *root, const pz_flatten_report *report)
{
    cJSON *summary = add_object(builder, root, "summary");
    if (!summary)
        return;
    const pz_metrics *rest = report->metrics[0];
    double max_abs_strain = 0;
    int injective = 1;
    for (int i = 0; i < report->metrics_count; ++i) {
        max_abs_strain = fmax(max_abs_strain, report->metrics[i]->max_abs_strain);
        injective &= report->metrics[i]->injective != 0;
    }
    int32_t flipped = 0, intersections = 0;
    for (int32_t p = 0; p < rest->panel_count; ++p) {
        flipped += rest->panels[p].flipped_triangles;
        intersections += rest->panels[p].boundary_self_intersections;
    }
    add_number(builder, summary, "panel_count", rest->panel_count, 0);
    add_number(builder, summary, "seam_count", rest->seam_count, 0);
    add_number(builder, summary, "dart_count", rest->dart_count, 0);
    add_number(builder, summary, "max_abs_strain", max_abs_strain, 8);
    cJSON *by_pose = add_array(builder, summary, "max_abs_strain_by_pose");
    for (int i = 0; by_pose && i < report->metrics_count; ++i) {
        cJSON *value = cJSON_CreateNumber(pz_cli_round(report->metrics[i]->max_abs_strain, 8) + 0.0);
        if (!value || !cJSON_AddItemToArray(by_pose, value)) {
            cJSON_Delete(value);
            builder->failed = 1;
        }
    }
    if (!cJSON_AddBoolToObject(summary, "injective", injective))
        builder->failed = 1;
    add_number(builder, summary, "flipped_triangles", flipped, 0);
    add_number(builder, summary, "boundary_self_intersections", intersections, 0);
    add_number(builder, summary, "max_seam_mismatch_rel", rest->max_seam_mismatch_rel, 8);
    if (!cJSON_AddBoolToObject(summary, "layout_moved", report->layout_moved))
        builder->failed = 1;
}

cJSON *pz_flatten_report_json(const pz_flatten_report *report)
{
    json_builder builder = {0};
    cJSON *root = cJSON_CreateObject();
    if (!root)
        return NULL;
    add_input(&builder, root, report);
    add_parameters(&builder, root, report);
    add_timings(&builder, root, report);
    add_panels(&builder, root, report);
    add_seams_and_darts(&builder, root, report);
    add_summary(&builder, root, report);
    add_backend_result(&builder, root, report);
    if (builder.failed) {
        cJSON_Delete(root);
        return NULL;
    }
    return root;
}

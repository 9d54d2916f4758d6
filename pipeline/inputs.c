/*
 * pipeline/inputs.c -- the files a pipeline reads besides the mesh: panel
 * files, seam and dart files, feature curves (docs/flatten.md), and panel
 * files joined into one mesh.
 *
 * Readers go line by line and name the file and line of the first problem
 * (PZ_ERR_DATA): a token that is not a whole number, a line with the wrong
 * count of numbers (an odd pair), an id out of range, a vertex no face uses.
 * Seam and dart ids are mapped into the joined mesh's ids through
 * pz_vertex_space, so several panel files (ids local to each file) and a
 * single garment (ids global) read alike; the pipeline maps them onto the
 * prepared garment.
 *
 * Memory: the readers hold one line and the pairs.
 *
 * SPDX-License-Identifier: GPL-3.0-or-later
 */
#define _POSIX_C_SOURCE 200809L
#include "pipeline/internal.h"

#include "core/util.h"

#include <ctype.h>
#include <errno.h>
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
    FILE *file = NULL;
    pz_status opened = pz_input_open(path, &file, ctx);
    if (opened != PZ_OK)
        return opened;
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

pz_status pz_read_panel_file(const char *path, int32_t face_count, int32_t *face_panel,
                                     int32_t *panel_count, pz_ctx *ctx)
{
    *panel_count = 0;
    FILE *file = NULL;
    pz_status opened = pz_input_open(path, &file, ctx);
    if (opened != PZ_OK)
        return opened;
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

/* The joined mesh's vertex of id `id` in panel file `panel` (ignored with one input file). */
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
    if (space->vertex_used && !space->vertex_used[first + id])
        return pz_error(ctx, PZ_ERR_DATA, "%s: line %d: vertex %d is used by no face", path, (int)line, (int)id);
    *out = first + id;
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

pz_status pz_read_seam_file(const char *path, const pz_vertex_space *space, pz_seam *seam, pz_ctx *ctx)
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

pz_status pz_read_dart_file(const char *spec, const pz_vertex_space *space, pz_dart *dart, pz_ctx *ctx)
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
    FILE *file = NULL;
    pz_status opened = pz_input_open(path, &file, ctx);
    if (opened != PZ_OK)
        return opened;
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
                               pl_feature_file *out, pz_ctx *ctx)
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

pz_status pl_read_features(const char *path, double mm_per_unit, pl_feature_file *out, pz_ctx *ctx)
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
        pl_feature_file_clear(out);
    return status;
}

void pl_feature_file_clear(pl_feature_file *features)
{
    free(features->polylines);
    free(features->points);
    memset(features, 0, sizeof *features);
}

/* ---------------------------------------------------------------- joining panel files */

char *pl_base_name(const char *path)
{
    const char *base = strrchr(path, '/');
    base = base ? base + 1 : path;
    size_t length = strlen(base);
    const char *dot = strrchr(base, '.');
    if (dot && dot != base)
        length = (size_t)(dot - base);
    char *copy = malloc(length + 1);
    if (copy) {
        memcpy(copy, base, length);
        copy[length] = '\0';
    }
    return copy;
}

/* Panel files one after another, no welding; label K = file K (named after the file). */
pz_status pz_mesh_join(pz_mesh *const *parts, const char *const *names, int32_t count, pz_mesh **out,
                       int32_t *vertex_offset, pz_ctx *ctx)
{
    *out = NULL;
    int64_t vertices = 0, faces = 0, uvs = 0;
    int all_uvs = 1;
    for (int32_t i = 0; i < count; ++i) {
        vertex_offset[i] = (int32_t)vertices;
        vertices += parts[i]->vertex_count;
        faces += parts[i]->face_count;
        uvs += parts[i]->uv_count;
        all_uvs &= parts[i]->uvs != NULL;
    }
    vertex_offset[count] = (int32_t)vertices;
    if (vertices > INT32_MAX / 3 || faces > INT32_MAX / 3 || uvs > INT32_MAX / 2)
        return pz_error(ctx, PZ_ERR_DATA, "%s: the panel files together are too large", names[0]);
    pz_mesh *mesh = NULL;
    pz_status status = pz_mesh_create((int32_t)vertices, (int32_t)faces, &mesh, ctx);
    if (status != PZ_OK)
        return status;
    mesh->face_labels = malloc(((size_t)faces + 1) * sizeof(int32_t));
    mesh->label_names = calloc((size_t)count + 1, sizeof(char *));
    if (all_uvs) {
        mesh->uvs = malloc(((size_t)uvs + 1) * 2 * sizeof(double));
        mesh->corner_uvs = malloc(((size_t)faces + 1) * 3 * sizeof(int32_t));
        mesh->uv_count = (int32_t)uvs;
    }
    int failed = !mesh->face_labels || !mesh->label_names || (all_uvs && (!mesh->uvs || !mesh->corner_uvs));
    mesh->label_count = count;
    size_t face_at = 0, uv_at = 0;
    for (int32_t i = 0; i < count && !failed; ++i) {
        const pz_mesh *part = parts[i];
        memcpy(mesh->positions + 3 * (size_t)vertex_offset[i], part->positions,
               3 * (size_t)part->vertex_count * sizeof(double));
        for (size_t c = 0; c < 3 * (size_t)part->face_count; ++c) {
            mesh->faces[3 * face_at + c] = part->faces[c] + vertex_offset[i];
            if (all_uvs)
                mesh->corner_uvs[3 * face_at + c] = part->corner_uvs[c] + (int32_t)uv_at;
        }
        for (int32_t f = 0; f < part->face_count; ++f)
            mesh->face_labels[face_at + (size_t)f] = i;
        if (all_uvs)
            memcpy(mesh->uvs + 2 * uv_at, part->uvs, 2 * (size_t)part->uv_count * sizeof(double));
        face_at += (size_t)part->face_count;
        uv_at += (size_t)part->uv_count;
        mesh->label_names[i] = pl_base_name(names[i]);
        failed |= !mesh->label_names[i];
    }
    if (failed) {
        pz_mesh_free(&mesh);
        return pz_error(ctx, PZ_ERR_NOMEM, "%s: out of memory joining the panel files", names[0]);
    }
    *out = mesh;
    return PZ_OK;
}


pz_status pz_read_correspondences(const char *const *seam_paths, int seam_count, const char *const *dart_specs,
                                  int dart_count, const pz_vertex_space *space, pz_correspondences *out,
                                  pz_ctx *ctx)
{
    memset(out, 0, sizeof *out);
    out->seams = calloc((size_t)seam_count + 1, sizeof(pz_seam));
    out->darts = calloc((size_t)dart_count + 1, sizeof(pz_dart));
    if (!out->seams || !out->darts)
        return pz_error(ctx, PZ_ERR_NOMEM, "flatten: out of memory reading seams");
    pz_status status = PZ_OK;
    for (int i = 0; i < seam_count && status == PZ_OK; ++i)
        if ((status = pz_read_seam_file(seam_paths[i], space, &out->seams[i], ctx)) == PZ_OK)
            out->seam_count = i + 1;
    for (int i = 0; i < dart_count && status == PZ_OK; ++i)
        if ((status = pz_read_dart_file(dart_specs[i], space, &out->darts[i], ctx)) == PZ_OK)
            out->dart_count = i + 1;
    return status;
}

void pz_mesh_mark_used_vertices(const pz_mesh *mesh, uint8_t *used)
{
    for (int32_t c = 0; c < 3 * mesh->face_count; ++c)
        if (mesh->faces[c] >= 0 && mesh->faces[c] < mesh->vertex_count)
            used[mesh->faces[c]] = 1;
}

void pz_panels_use_correspondences(pz_panels *panels, const pz_correspondences *read, const char *name)
{
    panels->seams = read->seams;
    panels->seam_count = read->seam_count;
    panels->darts = read->darts;
    panels->dart_count = read->dart_count;
    panels->correspondence_name = name;
}

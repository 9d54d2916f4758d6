/*
 * io/io_obj.c -- Wavefront OBJ reader and writer.
 *
 * Reading. The whole file is in memory; one pass walks it line by line
 * (memchr for '\n', so lines of any length cost nothing extra and '\r',
 * tabs and a missing final newline are plain whitespace). Keywords:
 *   v x y z [w | r g b]   position; anything after z is ignored
 *   vt u [v [w]]          texture coordinate (v defaults to 0)
 *   f a b c ...           corners as v, v/vt, v//vn or v/vt/vn; 1-based, or
 *                         negative = relative to the elements defined so far;
 *                         polygons are triangulated level by level (io/polygon.h)
 *   g NAME / o NAME       starts a group: faces that follow get label NAME
 *                         (the whole rest of the line, trimmed; a repeated
 *                         name reuses its label)
 * Everything else (comments, vn, usemtl, mtllib, s, l, p, ...) is skipped.
 *
 * Rules worth knowing:
 *  - UVs are kept only when EVERY face corner has a vt index; otherwise the
 *    mesh has none (no error: a file with partial UVs has no usable atlas).
 *  - When a file has groups, faces before the first group get a label named
 *    "default"; without any g/o line, face_labels is NULL.
 *  - Positive indices may point forward (some exporters write faces before
 *    vertices); they are checked once the whole file is read, and an index
 *    past the end is reported at the line of the largest one.
 *  - Numbers are parsed with a fast exact path (at most 19 significant digits
 *    and a small exponent: one correctly rounded multiply or divide) and
 *    strtod for everything else, in the C locale. "nan" and "inf" parse (to
 *    NaN and infinity): rejecting non-finite coordinates is validation's job
 *    (pz_mesh_validate), not the parser's. A number longer than 127
 *    characters is reported as malformed.
 *
 * Failure: PZ_ERR_DATA with "NAME: line N: problem" for malformed numbers,
 * index 0, an index out of range and faces with fewer than 3 corners;
 * "NAME: no faces" for an empty file. Memory grows geometrically with what
 * the file actually contains, never with a count it declares.
 *
 * Writing: `v` and `vt` with the shortest "%.Ng" that reads back to the same
 * double, `f v/vt` (or `f v`), and labels as `g NAME` whenever the label
 * changes between consecutive faces. Every label is first declared by an
 * empty `g NAME` line in label order, so a reader that numbers groups by first
 * appearance (this one) gets the same label ids back. Unnamed labels are
 * written as `label_K`. Poses are not written: an OBJ holds one pose.
 *
 * SPDX-License-Identifier: GPL-3.0-or-later
 */
#include "io/io.h"
#include "core/util.h"
#include "io/polygon.h"

#include <math.h>
#include <stdint.h>
#include <stdlib.h>
#include <string.h>

/* ------------------------------------------------------------------------ */
/* Group names -> labels (open addressing hash table)                        */
/* ------------------------------------------------------------------------ */

typedef struct obj_labels {
    char **names;
    size_t count, capacity;
    int32_t *slots;        /* label + 1, or 0 for an empty slot */
    size_t slot_count;     /* a power of two, kept at most half full */
} obj_labels;

static uint64_t obj_hash(const char *text, size_t length)
{
    uint64_t hash = 1469598103934665603ull; /* FNV-1a */
    for (size_t i = 0; i < length; ++i)
        hash = (hash ^ (unsigned char)text[i]) * 1099511628211ull;
    return hash;
}

static int obj_labels_rehash(obj_labels *labels)
{
    size_t slot_count = labels->slot_count ? labels->slot_count * 2 : 64;
    int32_t *slots = calloc(slot_count, sizeof *slots);
    if (!slots)
        return 0;
    for (size_t label = 0; label < labels->count; ++label) {
        const char *name = labels->names[label];
        size_t slot = obj_hash(name, strlen(name)) & (slot_count - 1);
        while (slots[slot])
            slot = (slot + 1) & (slot_count - 1);
        slots[slot] = (int32_t)label + 1;
    }
    free(labels->slots);
    labels->slots = slots;
    labels->slot_count = slot_count;
    return 1;
}

/* The label of `name` (length bytes), added when new; -1 when out of memory. */
static int32_t obj_labels_find(obj_labels *labels, const char *name, size_t length)
{
    if (2 * (labels->count + 1) > labels->slot_count && !obj_labels_rehash(labels))
        return -1;
    size_t mask = labels->slot_count - 1;
    size_t slot = obj_hash(name, length) & mask;
    for (; labels->slots[slot]; slot = (slot + 1) & mask) {
        const char *known = labels->names[labels->slots[slot] - 1];
        if (strncmp(known, name, length) == 0 && known[length] == '\0')
            return labels->slots[slot] - 1;
    }
    if (labels->count >= INT32_MAX - 1 ||
        !pz_grow((void **)&labels->names, &labels->capacity, labels->count + 1, sizeof(char *)))
        return -1;
    char *copy = malloc(length + 1);
    if (!copy)
        return -1;
    memcpy(copy, name, length);
    copy[length] = '\0';
    labels->names[labels->count] = copy;
    labels->slots[slot] = (int32_t)labels->count + 1;
    return (int32_t)labels->count++;
}

static void obj_labels_free(obj_labels *labels)
{
    for (size_t i = 0; i < labels->count; ++i)
        free(labels->names[i]);
    free(labels->names);
    free(labels->slots);
    memset(labels, 0, sizeof *labels);
}

/* ------------------------------------------------------------------------ */
/* Reader state                                                              */
/* ------------------------------------------------------------------------ */

/* A positive index that pointed past what was defined at its line. */
typedef struct obj_forward {
    int64_t largest;   /* largest 0-based forward index seen, -1 for none */
    long line;
} obj_forward;

typedef struct obj_reader {
    const char *name;
    pz_ctx *ctx;
    long line;

    double *positions;
    size_t vertex_count, position_capacity;   /* capacity in doubles */
    double *uvs;
    size_t uv_count, uv_capacity;             /* capacity in doubles */

    int32_t *faces, *corner_uvs, *face_labels;
    size_t face_count, faces_capacity, corner_uvs_capacity, face_labels_capacity;
    int some_corner_lacks_uv;

    obj_labels labels;
    int32_t current_label;                    /* -1 before the first g/o */

    int32_t *polygon_vertices, *polygon_uvs;  /* the corners of the face being read */
    size_t polygon_capacity, polygon_uv_capacity;

    obj_forward vertex_forward, uv_forward;
} obj_reader;

static int obj_is_space(char c)
{
    return c == ' ' || c == '\t' || c == '\r' || c == '\v' || c == '\f';
}

static const char *obj_skip_space(const char *p, const char *end)
{
    while (p < end && obj_is_space(*p))
        ++p;
    return p;
}

static pz_status obj_fail(obj_reader *reader, const char *problem)
{
    return pz_error(reader->ctx, PZ_ERR_DATA, "%s: line %ld: %s", reader->name, reader->line, problem);
}

static pz_status obj_out_of_memory(obj_reader *reader)
{
    return pz_error(reader->ctx, PZ_ERR_NOMEM, "%s: line %ld: out of memory", reader->name, reader->line);
}

/* ------------------------------------------------------------------------ */
/* Numbers                                                                   */
/* ------------------------------------------------------------------------ */

static const double obj_powers_of_ten[23] = {
    1e0,  1e1,  1e2,  1e3,  1e4,  1e5,  1e6,  1e7,  1e8,  1e9,  1e10, 1e11,
    1e12, 1e13, 1e14, 1e15, 1e16, 1e17, 1e18, 1e19, 1e20, 1e21, 1e22};

/*
 * Clinger's fast path: a decimal with a mantissa below 2^53 and a power of ten
 * up to 22 is exactly m * 10^e or m / 10^e, one correctly rounded operation,
 * so the result equals strtod's. Returns 0 when the text needs strtod.
 */
static int obj_fast_double(const char *p, const char *end, double *value)
{
    int negative = 0;
    if (p < end && (*p == '-' || *p == '+'))
        negative = *p++ == '-';
    uint64_t mantissa = 0;
    int digits = 0, exponent = 0, any_digit = 0;
    for (; p < end && *p >= '0' && *p <= '9'; ++p, any_digit = 1) {
        if (mantissa == 0 && *p == '0')
            continue;
        if (++digits > 19)
            return 0;
        mantissa = mantissa * 10 + (uint64_t)(*p - '0');
    }
    if (p < end && *p == '.')
        for (++p; p < end && *p >= '0' && *p <= '9'; ++p, any_digit = 1) {
            if (mantissa == 0 && *p == '0') {
                --exponent;
                continue;
            }
            if (++digits > 19)
                return 0;
            mantissa = mantissa * 10 + (uint64_t)(*p - '0');
            --exponent;
        }
    if (!any_digit)
        return 0;
    if (p < end && (*p == 'e' || *p == 'E')) {
        ++p;
        int exponent_negative = 0;
        if (p < end && (*p == '-' || *p == '+'))
            exponent_negative = *p++ == '-';
        if (p == end || *p < '0' || *p > '9')
            return 0;
        int written = 0;
        for (; p < end && *p >= '0' && *p <= '9'; ++p)
            if (written < 10000)
                written = written * 10 + (*p - '0');
        exponent += exponent_negative ? -written : written;
    }
    if (p != end || mantissa > (1ull << 53))
        return 0;
    double result = (double)mantissa;
    if (mantissa != 0) {
        if (exponent < -22 || exponent > 22)
            return 0;
        result = exponent < 0 ? result / obj_powers_of_ten[-exponent] : result * obj_powers_of_ten[exponent];
    }
    *value = negative ? -result : result;
    return 1;
}

/* Parses one whitespace-delimited number. Returns 0 when there is none or it is malformed. */
static int obj_parse_double(const char **cursor, const char *end, double *value)
{
    const char *start = obj_skip_space(*cursor, end), *stop = start;
    while (stop < end && !obj_is_space(*stop))
        ++stop;
    size_t length = (size_t)(stop - start);
    if (length == 0)
        return 0;
    if (!obj_fast_double(start, stop, value)) {
        char buffer[128];
        if (length >= sizeof buffer)
            return 0;
        memcpy(buffer, start, length);
        buffer[length] = '\0';
        char *parsed_end;
        *value = strtod(buffer, &parsed_end);
        if (parsed_end != buffer + length)
            return 0;
    }
    *cursor = stop;
    return 1;
}

/*
 * Parses an optionally signed integer; values beyond +-2^40 are clamped to
 * that bound (they are out of range whatever the file holds). Returns 0 when
 * there are no digits.
 */
static int obj_parse_integer(const char **cursor, const char *end, int64_t *value)
{
    const char *p = *cursor;
    int negative = 0;
    if (p < end && (*p == '-' || *p == '+'))
        negative = *p++ == '-';
    if (p == end || *p < '0' || *p > '9')
        return 0;
    const int64_t bound = (int64_t)1 << 40;
    int64_t magnitude = 0;
    for (; p < end && *p >= '0' && *p <= '9'; ++p)
        if (magnitude < bound)
            magnitude = magnitude * 10 + (*p - '0');
    if (magnitude > bound)
        magnitude = bound;
    *value = negative ? -magnitude : magnitude;
    *cursor = p;
    return 1;
}

/* ------------------------------------------------------------------------ */
/* Lines                                                                     */
/* ------------------------------------------------------------------------ */

static pz_status obj_read_vertex(obj_reader *reader, const char *p, const char *end)
{
    double xyz[3];
    for (int k = 0; k < 3; ++k)
        if (!obj_parse_double(&p, end, &xyz[k]))
            return obj_fail(reader, "malformed vertex (expected v x y z)");
    if (reader->vertex_count >= INT32_MAX)
        return obj_fail(reader, "too many vertices");
    if (!pz_grow((void **)&reader->positions, &reader->position_capacity, 3 * reader->vertex_count + 3,
                     sizeof(double)))
        return obj_out_of_memory(reader);
    memcpy(reader->positions + 3 * reader->vertex_count++, xyz, sizeof xyz);
    return PZ_OK;
}

static pz_status obj_read_uv(obj_reader *reader, const char *p, const char *end)
{
    double uv[2] = {0.0, 0.0};
    if (!obj_parse_double(&p, end, &uv[0]))
        return obj_fail(reader, "malformed texture coordinate (expected vt u v)");
    p = obj_skip_space(p, end);
    if (p < end && !obj_parse_double(&p, end, &uv[1]))
        return obj_fail(reader, "malformed texture coordinate (expected vt u v)");
    if (reader->uv_count >= INT32_MAX)
        return obj_fail(reader, "too many texture coordinates");
    if (!pz_grow((void **)&reader->uvs, &reader->uv_capacity, 2 * reader->uv_count + 2, sizeof(double)))
        return obj_out_of_memory(reader);
    memcpy(reader->uvs + 2 * reader->uv_count++, uv, sizeof uv);
    return PZ_OK;
}

/*
 * Turns a 1-based or negative OBJ index into a 0-based one. `defined` is how
 * many elements exist at this line; forward references are remembered.
 */
static pz_status obj_resolve_index(obj_reader *reader, int64_t index, size_t defined, obj_forward *forward,
                                   const char *what, int32_t *resolved)
{
    if (index == 0)
        return pz_error(reader->ctx, PZ_ERR_DATA, "%s: line %ld: %s index 0 (OBJ indices start at 1)",
                        reader->name, reader->line, what);
    int64_t zero_based = index > 0 ? index - 1 : (int64_t)defined + index;
    if (zero_based < 0 || zero_based >= INT32_MAX)
        return pz_error(reader->ctx, PZ_ERR_DATA, "%s: line %ld: %s index %lld out of range (%zu defined)",
                        reader->name, reader->line, what, (long long)index, defined);
    if (zero_based >= (int64_t)defined && zero_based > forward->largest) {
        forward->largest = zero_based;
        forward->line = reader->line;
    }
    *resolved = (int32_t)zero_based;
    return PZ_OK;
}

/* Reads one corner "v", "v/vt", "v//vn" or "v/vt/vn"; *uv = -1 without vt. */
static pz_status obj_read_corner(obj_reader *reader, const char **cursor, const char *end, int32_t *vertex,
                                 int32_t *uv)
{
    const char *p = *cursor;
    int64_t index;
    pz_status status;
    if (!obj_parse_integer(&p, end, &index))
        return obj_fail(reader, "malformed face corner (expected v, v/vt, v//vn or v/vt/vn)");
    if ((status = obj_resolve_index(reader, index, reader->vertex_count, &reader->vertex_forward, "vertex", vertex)))
        return status;
    *uv = -1;
    if (p < end && *p == '/') {
        ++p;
        if (p < end && *p != '/') {
            if (!obj_parse_integer(&p, end, &index))
                return obj_fail(reader, "malformed face corner (expected v, v/vt, v//vn or v/vt/vn)");
            status = obj_resolve_index(reader, index, reader->uv_count, &reader->uv_forward, "texture coordinate", uv);
            if (status)
                return status;
        }
        if (p < end && *p == '/') {
            ++p;
            int64_t normal; /* normals are not used, but must be well formed */
            if (!obj_parse_integer(&p, end, &normal))
                return obj_fail(reader, "malformed face corner (expected v, v/vt, v//vn or v/vt/vn)");
        }
    }
    if (p < end && !obj_is_space(*p))
        return obj_fail(reader, "malformed face corner (expected v, v/vt, v//vn or v/vt/vn)");
    *cursor = p;
    return PZ_OK;
}

/* Appends the triangles of the polygon just read (io/polygon.h). */
static pz_status obj_add_polygon(obj_reader *reader, size_t corner_count)
{
    size_t triangle_count = corner_count - 2;
    size_t needed = reader->face_count + triangle_count;
    if (needed > INT32_MAX)
        return obj_fail(reader, "too many faces");
    if (!pz_grow((void **)&reader->faces, &reader->faces_capacity, 3 * needed, sizeof(int32_t)) ||
        !pz_grow((void **)&reader->corner_uvs, &reader->corner_uvs_capacity, 3 * needed, sizeof(int32_t)) ||
        !pz_grow((void **)&reader->face_labels, &reader->face_labels_capacity, needed, sizeof(int32_t)))
        return obj_out_of_memory(reader);
    const int32_t *vertices = reader->polygon_vertices, *uvs = reader->polygon_uvs;
    io_polygon_walk walk = {corner_count, 1, 0};
    size_t corner[3];
    while (io_polygon_next(&walk, corner)) {
        size_t face = reader->face_count++;
        int32_t *corners = reader->faces + 3 * face, *corner_uvs = reader->corner_uvs + 3 * face;
        for (int k = 0; k < 3; ++k)
            corners[k] = vertices[corner[k]], corner_uvs[k] = uvs[corner[k]];
        reader->face_labels[face] = reader->current_label;
    }
    return PZ_OK;
}

static pz_status obj_read_face(obj_reader *reader, const char *p, const char *end)
{
    size_t corner_count = 0;
    for (p = obj_skip_space(p, end); p < end; p = obj_skip_space(p, end)) {
        if (!pz_grow((void **)&reader->polygon_vertices, &reader->polygon_capacity, corner_count + 1,
                         sizeof(int32_t)) ||
            !pz_grow((void **)&reader->polygon_uvs, &reader->polygon_uv_capacity, corner_count + 1,
                         sizeof(int32_t)))
            return obj_out_of_memory(reader);
        int32_t vertex = 0, uv = -1;
        pz_status status = obj_read_corner(reader, &p, end, &vertex, &uv);
        if (status)
            return status;
        if (uv < 0)
            reader->some_corner_lacks_uv = 1;
        reader->polygon_vertices[corner_count] = vertex;
        reader->polygon_uvs[corner_count++] = uv;
    }
    if (corner_count < 3)
        return pz_error(reader->ctx, PZ_ERR_DATA, "%s: line %ld: face with %zu corners (at least 3 needed)",
                        reader->name, reader->line, corner_count);
    return obj_add_polygon(reader, corner_count);
}

static pz_status obj_read_group(obj_reader *reader, const char *p, const char *end)
{
    p = obj_skip_space(p, end);
    /* names are C strings: a NUL byte ends one (the label table compares with strncmp) */
    for (const char *c = p; c < end; ++c)
        if (*c == '\0') {
            end = c;
            break;
        }
    while (end > p && obj_is_space(end[-1]))
        --end;
    static const char unnamed[] = "default";
    const char *group_name = p < end ? p : unnamed;
    size_t length = p < end ? (size_t)(end - p) : sizeof unnamed - 1;
    int32_t label = obj_labels_find(&reader->labels, group_name, length);
    if (label < 0)
        return obj_out_of_memory(reader);
    reader->current_label = label;
    return PZ_OK;
}

/* True when the keyword [p, keyword_end) is `word`. */
static int obj_keyword_is(const char *p, const char *keyword_end, const char *word)
{
    size_t length = strlen(word);
    return (size_t)(keyword_end - p) == length && memcmp(p, word, length) == 0;
}

static pz_status obj_read_line(obj_reader *reader, const char *p, const char *end)
{
    p = obj_skip_space(p, end);
    const char *keyword_end = p;
    while (keyword_end < end && !obj_is_space(*keyword_end))
        ++keyword_end;
    if (obj_keyword_is(p, keyword_end, "v"))
        return obj_read_vertex(reader, keyword_end, end);
    if (obj_keyword_is(p, keyword_end, "vt"))
        return obj_read_uv(reader, keyword_end, end);
    if (obj_keyword_is(p, keyword_end, "f"))
        return obj_read_face(reader, keyword_end, end);
    if (obj_keyword_is(p, keyword_end, "g") || obj_keyword_is(p, keyword_end, "o"))
        return obj_read_group(reader, keyword_end, end);
    return PZ_OK; /* comments, blank lines, vn, usemtl, mtllib, s, l, ... */
}

/* ------------------------------------------------------------------------ */
/* Finishing                                                                 */
/* ------------------------------------------------------------------------ */

static pz_status obj_check_forward(obj_reader *reader, const obj_forward *forward, size_t defined, const char *what)
{
    if (forward->largest < (int64_t)defined)
        return PZ_OK;
    return pz_error(reader->ctx, PZ_ERR_DATA, "%s: line %ld: %s index %lld out of range (%zu defined)", reader->name,
                    forward->line, what, (long long)forward->largest + 1, defined);
}

/* Faces before the first group join a "default" label; no groups: no labels. */
static pz_status obj_finish_labels(obj_reader *reader)
{
    if (reader->labels.count == 0)
        return PZ_OK;
    int32_t fallback = -1;
    for (size_t face = 0; face < reader->face_count; ++face) {
        if (reader->face_labels[face] >= 0)
            continue;
        if (fallback < 0 && (fallback = obj_labels_find(&reader->labels, "default", 7)) < 0)
            return obj_out_of_memory(reader);
        reader->face_labels[face] = fallback;
    }
    return PZ_OK;
}

/* Hands the arrays over to a new mesh (no copy). */
static pz_status obj_build_mesh(obj_reader *reader, pz_mesh **out)
{
    pz_mesh *mesh = calloc(1, sizeof *mesh);
    if (!mesh)
        return obj_out_of_memory(reader);
    mesh->unit_scale = 1.0;
    mesh->vertex_count = (int32_t)reader->vertex_count;
    mesh->face_count = (int32_t)reader->face_count;
    mesh->positions = reader->positions;
    mesh->faces = reader->faces;
    reader->positions = NULL;
    reader->faces = NULL;
    if (!reader->some_corner_lacks_uv && reader->uv_count > 0) {
        mesh->uv_count = (int32_t)reader->uv_count;
        mesh->uvs = reader->uvs;
        mesh->corner_uvs = reader->corner_uvs;
        reader->uvs = NULL;
        reader->corner_uvs = NULL;
    }
    if (reader->labels.count > 0) {
        mesh->face_labels = reader->face_labels;
        mesh->label_count = (int32_t)reader->labels.count;
        mesh->label_names = reader->labels.names;
        reader->face_labels = NULL;
        reader->labels.names = NULL;
        reader->labels.count = 0;
    }
    *out = mesh;
    return PZ_OK;
}

static void obj_reader_free(obj_reader *reader)
{
    free(reader->positions);
    free(reader->uvs);
    free(reader->faces);
    free(reader->corner_uvs);
    free(reader->face_labels);
    free(reader->polygon_vertices);
    free(reader->polygon_uvs);
    obj_labels_free(&reader->labels);
}

static pz_status obj_read_all(obj_reader *reader, const char *data, size_t size, pz_mesh **out)
{
    const char *p = data, *end = data + size;
    while (p < end) {
        const char *line_end = memchr(p, '\n', (size_t)(end - p));
        if (!line_end)
            line_end = end;
        ++reader->line;
        pz_status status = obj_read_line(reader, p, line_end);
        if (status)
            return status;
        if (line_end == end)
            break;
        p = line_end + 1;
    }
    if (reader->face_count == 0)
        return pz_error(reader->ctx, PZ_ERR_DATA, "%s: no faces", reader->name);
    pz_status status = obj_check_forward(reader, &reader->vertex_forward, reader->vertex_count, "vertex");
    if (!status && !reader->some_corner_lacks_uv)
        status = obj_check_forward(reader, &reader->uv_forward, reader->uv_count, "texture coordinate");
    if (!status)
        status = obj_finish_labels(reader);
    if (!status)
        status = obj_build_mesh(reader, out);
    return status;
}

pz_status pz_obj_read_memory(const char *data, size_t size, const char *name, pz_mesh **out, pz_ctx *ctx)
{
    *out = NULL;
    obj_reader reader;
    memset(&reader, 0, sizeof reader);
    reader.name = name ? name : "OBJ";
    reader.ctx = ctx;
    reader.current_label = -1;
    reader.vertex_forward.largest = reader.uv_forward.largest = -1;
    pz_status status = obj_read_all(&reader, data ? data : "", data ? size : 0, out);
    obj_reader_free(&reader);
    return status;
}

/* ------------------------------------------------------------------------ */
/* Writer                                                                    */
/* ------------------------------------------------------------------------ */

/* The shortest "%.Ng" (N = 15..17) that strtod reads back to exactly `value`. */
static void obj_format_double(double value, char buffer[40])
{
    for (int precision = 15; precision < 17; ++precision) {
        snprintf(buffer, 40, "%.*g", precision, value);
        if (strtod(buffer, NULL) == value)
            return;
    }
    snprintf(buffer, 40, "%.17g", value);
}

/* `g NAME`: the label's name with control characters made blanks-safe, or label_K. */
static void obj_write_group(FILE *file, const pz_mesh *mesh, int32_t label)
{
    const char *name = NULL;
    if (mesh->label_names && label >= 0 && label < mesh->label_count)
        name = mesh->label_names[label];
    if (!name || !*name) {
        fprintf(file, "g label_%d\n", (int)label);
        return;
    }
    fputs("g ", file);
    for (const char *c = name; *c; ++c)
        fputc((unsigned char)*c < 32 ? '_' : *c, file); /* a newline would end the group name */
    fputc('\n', file);
}

static void obj_write_vertices(const pz_mesh *mesh, FILE *file)
{
    char x[40], y[40], z[40];
    for (int32_t v = 0; v < mesh->vertex_count; ++v) {
        const double *p = mesh->positions + 3 * (size_t)v;
        obj_format_double(p[0], x);
        obj_format_double(p[1], y);
        obj_format_double(p[2], z);
        fprintf(file, "v %s %s %s\n", x, y, z);
    }
    if (!mesh->uvs || !mesh->corner_uvs)
        return;
    for (int32_t t = 0; t < mesh->uv_count; ++t) {
        obj_format_double(mesh->uvs[2 * (size_t)t], x);
        obj_format_double(mesh->uvs[2 * (size_t)t + 1], y);
        fprintf(file, "vt %s %s\n", x, y);
    }
}

static void obj_write_faces(const pz_mesh *mesh, FILE *file)
{
    int with_uvs = mesh->uvs && mesh->corner_uvs && mesh->uv_count > 0;
    int with_labels = mesh->face_labels != NULL;
    int32_t current_label = INT32_MIN;
    for (int32_t f = 0; f < mesh->face_count; ++f) {
        if (with_labels && mesh->face_labels[f] != current_label) {
            current_label = mesh->face_labels[f];
            obj_write_group(file, mesh, current_label);
        }
        const int32_t *corners = mesh->faces + 3 * (size_t)f;
        if (with_uvs) {
            const int32_t *uvs = mesh->corner_uvs + 3 * (size_t)f;
            fprintf(file, "f %d/%d %d/%d %d/%d\n", corners[0] + 1, uvs[0] + 1, corners[1] + 1, uvs[1] + 1,
                    corners[2] + 1, uvs[2] + 1);
        } else {
            fprintf(file, "f %d %d %d\n", corners[0] + 1, corners[1] + 1, corners[2] + 1);
        }
    }
}

pz_status pz_obj_write_file(const pz_mesh *mesh, FILE *file, pz_ctx *ctx)
{
    fprintf(file, "# panelize %s: %d vertices, %d faces\n", PZ_VERSION_STRING, (int)mesh->vertex_count,
            (int)mesh->face_count);
    if (mesh->face_labels)
        for (int32_t label = 0; label < mesh->label_count; ++label)
            obj_write_group(file, mesh, label); /* declares labels in id order */
    obj_write_vertices(mesh, file);
    obj_write_faces(mesh, file);
    if (ferror(file))
        return pz_error(ctx, PZ_ERR_CREATE, "OBJ output: write error");
    return PZ_OK;
}

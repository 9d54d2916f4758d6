/*
 * io/io_ply.c -- Stanford PLY reader and writer.
 *
 * Reading. The header ("ply", "format ...", "element NAME COUNT",
 * "property TYPE NAME", "property list COUNT_TYPE ITEM_TYPE NAME", comments,
 * "end_header") is parsed into a list of elements; the body is then walked
 * element by element in header order, in ascii (whitespace-separated tokens,
 * line breaks anywhere), binary_little_endian or binary_big_endian.
 *  - element "vertex": scalar x, y, z (any numeric type) and optionally a UV
 *    pair s/t, u/v, texture_u/texture_v or texture_s/texture_t. Per-vertex UVs
 *    become corner UVs equal to the vertex indices (uv_count = vertex_count).
 *  - element "face": list vertex_indices (or vertex_index), triangulated (io/polygon.h),
 *    and optionally a scalar "label" that becomes the face label; label values
 *    are renumbered densely in increasing order (identity for 0..K-1), and
 *    header lines "comment pz_label K NAME" (written by our writer) give
 *    their names.
 *  - every other property (colours, normals, lists of any type) and every
 *    other element is skipped; a binary element without lists is skipped in
 *    one step.
 * Types: char/int8, uchar/uint8, short/int16, ushort/uint16, int/int32,
 * uint/uint32, float/float32, double/float64, in any role (an index or label
 * stored as a float must be integral).
 *
 * Failure (PZ_ERR_DATA naming the file): a bad or missing header, a
 * declared count the body cannot hold (checked before anything is allocated:
 * every element instance needs at least one byte per binary scalar or two
 * characters per ascii token), truncated data, an index out of range, a
 * polygon with fewer than 3 corners, no faces.
 *
 * Writing: binary_little_endian, double x y z (and s t when every vertex has a
 * single UV), face "list uchar int vertex_indices" plus "int label" when the
 * mesh has labels, with "comment pz_label K NAME" for named labels. Bytes are
 * assembled explicitly, so the output is little endian on any host. UV seams
 * cannot be stored per vertex: such UVs are left out with a note. Poses are
 * not written.
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

typedef enum ply_type {
    PLY_NONE = 0, PLY_INT8, PLY_UINT8, PLY_INT16, PLY_UINT16, PLY_INT32, PLY_UINT32, PLY_FLOAT32, PLY_FLOAT64
} ply_type;

typedef enum ply_format { PLY_ASCII, PLY_BINARY_LE, PLY_BINARY_BE } ply_format;

/* What a property is used for; everything else is skipped. */
typedef enum ply_role {
    ROLE_SKIP = 0, ROLE_X, ROLE_Y, ROLE_Z, ROLE_U, ROLE_V, ROLE_INDICES, ROLE_LABEL
} ply_role;

typedef enum ply_kind { KIND_OTHER, KIND_VERTEX, KIND_FACE } ply_kind;

typedef struct ply_property {
    ply_type type;        /* the scalar type, or the item type of a list */
    ply_type count_type;  /* PLY_NONE for a scalar */
    ply_role role;
} ply_property;

typedef struct ply_element {
    char name[64];        /* truncated copy, for messages */
    ply_kind kind;
    int64_t count;
    ply_property *properties;
    size_t property_count, property_capacity;
} ply_element;

typedef struct ply_label_name {
    int64_t value;
    char *name;
} ply_label_name;

typedef struct ply_reader {
    const char *name;
    pz_ctx *ctx;
    ply_format format;
    const unsigned char *cursor, *end;

    ply_element *elements;
    size_t element_count, element_capacity;
    ply_label_name *label_names;
    size_t label_name_count, label_name_capacity;

    int32_t vertex_count;
    double *positions, *vertex_uvs;
    int have_vertices;
    int32_t *faces;
    int64_t *face_labels;   /* raw label values per triangle, or NULL */
    size_t face_count, faces_capacity, face_labels_capacity;
    int64_t *polygon;
    size_t polygon_capacity;
} ply_reader;

static const struct {
    const char *name;
    ply_type type;
} ply_type_names[] = {
    {"char", PLY_INT8},     {"int8", PLY_INT8},       {"uchar", PLY_UINT8},   {"uint8", PLY_UINT8},
    {"short", PLY_INT16},   {"int16", PLY_INT16},     {"ushort", PLY_UINT16}, {"uint16", PLY_UINT16},
    {"int", PLY_INT32},     {"int32", PLY_INT32},     {"uint", PLY_UINT32},   {"uint32", PLY_UINT32},
    {"float", PLY_FLOAT32}, {"float32", PLY_FLOAT32}, {"double", PLY_FLOAT64}, {"float64", PLY_FLOAT64}};

static size_t ply_type_size(ply_type type)
{
    static const size_t sizes[] = {0, 1, 1, 2, 2, 4, 4, 4, 8};
    return sizes[type];
}

static pz_status ply_out_of_memory(ply_reader *reader)
{
    return pz_error(reader->ctx, PZ_ERR_NOMEM, "%s: out of memory", reader->name);
}

/* ------------------------------------------------------------------------ */
/* Header                                                                    */
/* ------------------------------------------------------------------------ */

/* A token of a header line: [start, start + length). */
typedef struct ply_token {
    const char *start;
    size_t length;
} ply_token;

static int ply_is_space(int c)
{
    return c == ' ' || c == '\t' || c == '\r' || c == '\n' || c == '\v' || c == '\f';
}

/* Splits a header line into up to `capacity` tokens; returns how many there are. */
static size_t ply_split(const char *line, const char *line_end, ply_token *tokens, size_t capacity)
{
    size_t count = 0;
    for (const char *p = line; p < line_end;) {
        while (p < line_end && ply_is_space((unsigned char)*p))
            ++p;
        if (p == line_end)
            break;
        const char *start = p;
        while (p < line_end && !ply_is_space((unsigned char)*p))
            ++p;
        if (count < capacity)
            tokens[count] = (ply_token){start, (size_t)(p - start)};
        ++count;
    }
    return count;
}

static int ply_token_is(ply_token token, const char *word)
{
    return token.length == strlen(word) && memcmp(token.start, word, token.length) == 0;
}

static ply_type ply_parse_type(ply_token token)
{
    for (size_t i = 0; i < sizeof ply_type_names / sizeof ply_type_names[0]; ++i)
        if (ply_token_is(token, ply_type_names[i].name))
            return ply_type_names[i].type;
    return PLY_NONE;
}

/* Parses a non-negative decimal count; returns 0 for anything else or above 2^40. */
static int ply_parse_count(ply_token token, int64_t *count)
{
    if (token.length == 0 || token.length > 13)
        return 0;
    int64_t value = 0;
    for (size_t i = 0; i < token.length; ++i) {
        if (token.start[i] < '0' || token.start[i] > '9')
            return 0;
        value = value * 10 + (token.start[i] - '0');
    }
    *count = value;
    return 1;
}

static pz_status ply_header_error(ply_reader *reader, long line, const char *problem)
{
    return pz_error(reader->ctx, PZ_ERR_DATA, "%s: header line %ld: %s", reader->name, line, problem);
}

static pz_status ply_add_element(ply_reader *reader, const ply_token *tokens, size_t token_count, long line)
{
    int64_t count;
    if (token_count != 3 || !ply_parse_count(tokens[2], &count))
        return ply_header_error(reader, line, "malformed element (expected: element NAME COUNT)");
    if (!pz_grow((void **)&reader->elements, &reader->element_capacity, reader->element_count + 1,
                     sizeof(ply_element)))
        return ply_out_of_memory(reader);
    ply_element *element = &reader->elements[reader->element_count++];
    memset(element, 0, sizeof *element);
    size_t length = tokens[1].length < sizeof element->name - 1 ? tokens[1].length : sizeof element->name - 1;
    memcpy(element->name, tokens[1].start, length);
    element->count = count;
    if (ply_token_is(tokens[1], "vertex"))
        element->kind = KIND_VERTEX;
    else if (ply_token_is(tokens[1], "face"))
        element->kind = KIND_FACE;
    for (size_t i = 0; i + 1 < reader->element_count; ++i)
        if (element->kind != KIND_OTHER && reader->elements[i].kind == element->kind)
            return ply_header_error(reader, line, "a second vertex or face element");
    return PZ_OK;
}

/* The role of a property, given its element and name; the first claimant of a role wins. */
static ply_role ply_choose_role(const ply_element *element, ply_token name, int is_list)
{
    static const char *const u_names[] = {"s", "u", "texture_u", "texture_s"};
    static const char *const v_names[] = {"t", "v", "texture_v", "texture_t"};
    ply_role role = ROLE_SKIP;
    if (element->kind == KIND_VERTEX && !is_list) {
        if (ply_token_is(name, "x")) role = ROLE_X;
        else if (ply_token_is(name, "y")) role = ROLE_Y;
        else if (ply_token_is(name, "z")) role = ROLE_Z;
        for (int i = 0; i < 4; ++i) {
            if (ply_token_is(name, u_names[i])) role = ROLE_U;
            if (ply_token_is(name, v_names[i])) role = ROLE_V;
        }
    } else if (element->kind == KIND_FACE) {
        if (is_list && (ply_token_is(name, "vertex_indices") || ply_token_is(name, "vertex_index")))
            role = ROLE_INDICES;
        else if (!is_list && ply_token_is(name, "label"))
            role = ROLE_LABEL;
    }
    for (size_t i = 0; i < element->property_count; ++i)
        if (element->properties[i].role == role)
            return ROLE_SKIP;
    return role;
}

static pz_status ply_add_property(ply_reader *reader, const ply_token *tokens, size_t token_count, long line)
{
    if (reader->element_count == 0)
        return ply_header_error(reader, line, "property before any element");
    ply_element *element = &reader->elements[reader->element_count - 1];
    ply_property property = {PLY_NONE, PLY_NONE, ROLE_SKIP};
    int is_list = token_count >= 2 && ply_token_is(tokens[1], "list");
    if (is_list) {
        if (token_count != 5)
            return ply_header_error(reader, line, "malformed property (expected: property list TYPE TYPE NAME)");
        property.count_type = ply_parse_type(tokens[2]);
        property.type = ply_parse_type(tokens[3]);
        if (property.count_type == PLY_NONE || property.type == PLY_NONE)
            return ply_header_error(reader, line, "unknown property type");
    } else {
        if (token_count != 3)
            return ply_header_error(reader, line, "malformed property (expected: property TYPE NAME)");
        if ((property.type = ply_parse_type(tokens[1])) == PLY_NONE)
            return ply_header_error(reader, line, "unknown property type");
    }
    property.role = ply_choose_role(element, tokens[token_count - 1], is_list);
    if (!pz_grow((void **)&element->properties, &element->property_capacity, element->property_count + 1,
                     sizeof(ply_property)))
        return ply_out_of_memory(reader);
    element->properties[element->property_count++] = property;
    return PZ_OK;
}

/* "comment pz_label K NAME": the name of label value K (written by our writer). */
static pz_status ply_add_label_name(ply_reader *reader, const ply_token *tokens, size_t token_count,
                                    const char *line_end)
{
    int64_t value;
    if (token_count < 4 || !ply_token_is(tokens[1], "pz_label") || !ply_parse_count(tokens[2], &value))
        return PZ_OK;
    const char *name_end = line_end;
    while (name_end > tokens[3].start && ply_is_space((unsigned char)name_end[-1]))
        --name_end;
    size_t length = (size_t)(name_end - tokens[3].start);
    char *name = malloc(length + 1);
    if (!name || !pz_grow((void **)&reader->label_names, &reader->label_name_capacity,
                              reader->label_name_count + 1, sizeof(ply_label_name))) {
        free(name);
        return ply_out_of_memory(reader);
    }
    memcpy(name, tokens[3].start, length);
    name[length] = '\0';
    reader->label_names[reader->label_name_count++] = (ply_label_name){value, name};
    return PZ_OK;
}

static pz_status ply_header_line(ply_reader *reader, const char *line, const char *line_end, long line_number,
                                 int *done)
{
    ply_token tokens[6];
    size_t token_count = ply_split(line, line_end, tokens, 6);
    if (token_count == 0)
        return PZ_OK;
    if (ply_token_is(tokens[0], "comment") || ply_token_is(tokens[0], "obj_info"))
        return ply_add_label_name(reader, tokens, token_count < 6 ? token_count : 6, line_end);
    if (token_count > 6)
        return ply_header_error(reader, line_number, "unexpected header line");
    if (ply_token_is(tokens[0], "element"))
        return ply_add_element(reader, tokens, token_count, line_number);
    if (ply_token_is(tokens[0], "property"))
        return ply_add_property(reader, tokens, token_count, line_number);
    if (ply_token_is(tokens[0], "end_header")) {
        *done = 1;
        return PZ_OK;
    }
    if (ply_token_is(tokens[0], "format")) {
        if (token_count != 3)
            return ply_header_error(reader, line_number, "malformed format line");
        if (ply_token_is(tokens[1], "ascii")) reader->format = PLY_ASCII;
        else if (ply_token_is(tokens[1], "binary_little_endian")) reader->format = PLY_BINARY_LE;
        else if (ply_token_is(tokens[1], "binary_big_endian")) reader->format = PLY_BINARY_BE;
        else return ply_header_error(reader, line_number, "unknown format");
        return PZ_OK;
    }
    return ply_header_error(reader, line_number, "unexpected header line");
}

static pz_status ply_read_header(ply_reader *reader)
{
    const char *p = (const char *)reader->cursor, *end = (const char *)reader->end;
    if (end - p < 4 || memcmp(p, "ply", 3) != 0 || (p[3] != '\n' && p[3] != '\r'))
        return pz_error(reader->ctx, PZ_ERR_DATA, "%s: not a PLY file (no 'ply' magic line)", reader->name);
    int done = 0, format_seen = 0;
    for (long line_number = 1; !done; ++line_number) {
        const char *line_end = memchr(p, '\n', (size_t)(end - p));
        if (!line_end)
            return pz_error(reader->ctx, PZ_ERR_DATA, "%s: truncated header (no end_header)", reader->name);
        if (line_number > 1) {
            format_seen |= line_end - p >= 6 && memcmp(p, "format", 6) == 0;
            pz_status status = ply_header_line(reader, p, line_end, line_number, &done);
            if (status)
                return status;
        }
        p = line_end + 1;
    }
    if (!format_seen)
        return pz_error(reader->ctx, PZ_ERR_DATA, "%s: header has no format line", reader->name);
    reader->cursor = (const unsigned char *)p;
    return PZ_OK;
}

/* ------------------------------------------------------------------------ */
/* Body values                                                               */
/* ------------------------------------------------------------------------ */

static uint64_t ply_load_bytes(const unsigned char *p, size_t size, int big_endian)
{
    uint64_t bits = 0;
    for (size_t i = 0; i < size; ++i)
        bits |= (uint64_t)p[big_endian ? size - 1 - i : i] << (8 * i);
    return bits;
}

static double ply_decode(const unsigned char *p, ply_type type, int big_endian)
{
    uint64_t bits = ply_load_bytes(p, ply_type_size(type), big_endian);
    switch (type) {
    case PLY_INT8: return (double)(int8_t)(uint8_t)bits;
    case PLY_UINT8: return (double)(uint8_t)bits;
    case PLY_INT16: return (double)(int16_t)(uint16_t)bits;
    case PLY_UINT16: return (double)(uint16_t)bits;
    case PLY_INT32: return (double)(int32_t)(uint32_t)bits;
    case PLY_UINT32: return (double)(uint32_t)bits;
    case PLY_FLOAT32: {
        uint32_t narrow = (uint32_t)bits;
        float value;
        memcpy(&value, &narrow, sizeof value);
        return (double)value;
    }
    case PLY_FLOAT64: {
        double value;
        memcpy(&value, &bits, sizeof value);
        return value;
    }
    case PLY_NONE: break;
    }
    return 0.0;
}

/* Reads one value of `type`; returns 0 at the end of the data or on a malformed ascii token. */
static int ply_read_value(ply_reader *reader, ply_type type, double *value)
{
    if (reader->format != PLY_ASCII) {
        size_t size = ply_type_size(type);
        if ((size_t)(reader->end - reader->cursor) < size)
            return 0;
        *value = ply_decode(reader->cursor, type, reader->format == PLY_BINARY_BE);
        reader->cursor += size;
        return 1;
    }
    const unsigned char *p = reader->cursor;
    while (p < reader->end && ply_is_space(*p))
        ++p;
    const unsigned char *start = p;
    while (p < reader->end && !ply_is_space(*p))
        ++p;
    size_t length = (size_t)(p - start);
    char buffer[128];
    if (length == 0 || length >= sizeof buffer)
        return 0;
    memcpy(buffer, start, length);
    buffer[length] = '\0';
    char *parsed_end;
    *value = strtod(buffer, &parsed_end);
    reader->cursor = p;
    return parsed_end == buffer + length;
}

static int ply_skip_values(ply_reader *reader, ply_type type, int64_t count)
{
    if (reader->format != PLY_ASCII) {
        size_t size = ply_type_size(type);
        if ((uint64_t)count > (size_t)(reader->end - reader->cursor) / size)
            return 0;
        reader->cursor += (size_t)count * size;
        return 1;
    }
    double ignored;
    for (int64_t i = 0; i < count; ++i)
        if (!ply_read_value(reader, type, &ignored))
            return 0;
    return 1;
}

static int ply_is_integral(double value, double limit)
{
    return value == floor(value) && fabs(value) <= limit;
}

/* ------------------------------------------------------------------------ */
/* Body elements                                                             */
/* ------------------------------------------------------------------------ */

static pz_status ply_truncated(ply_reader *reader, const ply_element *element, int64_t instance)
{
    return pz_error(reader->ctx, PZ_ERR_DATA, "%s: truncated or malformed data in element '%s' (item %lld of %lld)",
                    reader->name, element->name, (long long)instance, (long long)element->count);
}

/*
 * Refuses a declared count the remaining bytes cannot possibly hold, before
 * anything is allocated for it (a fuzzed header must not allocate gigabytes).
 */
static pz_status ply_check_count(ply_reader *reader, const ply_element *element)
{
    size_t least_bytes = 0;
    for (size_t i = 0; i < element->property_count; ++i) {
        const ply_property *property = &element->properties[i];
        if (reader->format == PLY_ASCII)
            least_bytes += 2; /* one character and one separator per token */
        else
            least_bytes += ply_type_size(property->count_type ? property->count_type : property->type);
    }
    size_t remaining = (size_t)(reader->end - reader->cursor);
    if (reader->format == PLY_ASCII)
        remaining += 1; /* the last token may lack a separator */
    if (least_bytes > 0 && (uint64_t)element->count > remaining / least_bytes)
        return pz_error(reader->ctx, PZ_ERR_DATA, "%s: element '%s' declares %lld items but the data is too short",
                        reader->name, element->name, (long long)element->count);
    return PZ_OK;
}

/* Appends the triangles of the polygon just read (io/polygon.h), with its label. */
static pz_status ply_add_polygon(ply_reader *reader, size_t corner_count, int64_t label, int64_t polygon_number)
{
    if (corner_count < 3)
        return pz_error(reader->ctx, PZ_ERR_DATA, "%s: face %lld has %zu corners (at least 3 needed)", reader->name,
                        (long long)polygon_number, corner_count);
    size_t needed = reader->face_count + corner_count - 2;
    if (needed > INT32_MAX)
        return pz_error(reader->ctx, PZ_ERR_DATA, "%s: too many faces", reader->name);
    if (!pz_grow((void **)&reader->faces, &reader->faces_capacity, 3 * needed, sizeof(int32_t)) ||
        !pz_grow((void **)&reader->face_labels, &reader->face_labels_capacity, needed, sizeof(int64_t)))
        return ply_out_of_memory(reader);
    io_polygon_walk walk = {corner_count, 1, 0};
    size_t corner[3];
    while (io_polygon_next(&walk, corner)) {
        /* Indices are checked against the vertex count once every element has been read. */
        int32_t *corners = reader->faces + 3 * reader->face_count;
        for (int k = 0; k < 3; ++k)
            corners[k] = (int32_t)reader->polygon[corner[k]];
        reader->face_labels[reader->face_count++] = label;
    }
    return PZ_OK;
}

/* Reads a list; indices are kept in reader->polygon. Returns the item count or -1 when truncated. */
static int64_t ply_read_list(ply_reader *reader, const ply_property *property, int *bad_index)
{
    double count_value;
    if (!ply_read_value(reader, property->count_type, &count_value) || !ply_is_integral(count_value, 1e12) ||
        count_value < 0)
        return -1;
    int64_t count = (int64_t)count_value;
    if (property->role != ROLE_INDICES)
        return ply_skip_values(reader, property->type, count) ? count : -1;
    /* Each item takes at least one byte, which bounds the scratch polygon by the data size. */
    if ((uint64_t)count > (size_t)(reader->end - reader->cursor) ||
        !pz_grow((void **)&reader->polygon, &reader->polygon_capacity, (size_t)count + 1, sizeof(int64_t)))
        return -1;
    for (int64_t i = 0; i < count; ++i) {
        double index;
        if (!ply_read_value(reader, property->type, &index))
            return -1;
        if (!ply_is_integral(index, 1e12))
            *bad_index = 1;
        reader->polygon[i] = index < 0 || index >= INT32_MAX || *bad_index ? -1 : (int64_t)index;
    }
    return count;
}

static pz_status ply_read_instance(ply_reader *reader, const ply_element *element, int64_t instance)
{
    double values[8] = {0};  /* by role */
    int64_t corner_count = -1;
    int bad_index = 0;
    for (size_t i = 0; i < element->property_count; ++i) {
        const ply_property *property = &element->properties[i];
        if (property->count_type != PLY_NONE) {
            int64_t count = ply_read_list(reader, property, &bad_index);
            if (count < 0)
                return ply_truncated(reader, element, instance);
            if (property->role == ROLE_INDICES)
                corner_count = count;
        } else if (!ply_read_value(reader, property->type, &values[property->role])) {
            return ply_truncated(reader, element, instance);
        }
    }
    if (element->kind == KIND_VERTEX) {
        memcpy(reader->positions + 3 * instance, &values[ROLE_X], 3 * sizeof(double));
        if (reader->vertex_uvs)
            memcpy(reader->vertex_uvs + 2 * instance, &values[ROLE_U], 2 * sizeof(double));
        return PZ_OK;
    }
    if (element->kind != KIND_FACE || corner_count < 0)
        return PZ_OK;
    if (bad_index)
        return pz_error(reader->ctx, PZ_ERR_DATA, "%s: face %lld has a non-integral vertex index", reader->name,
                        (long long)instance);
    if (!ply_is_integral(values[ROLE_LABEL], 1e12) || values[ROLE_LABEL] < 0)
        return pz_error(reader->ctx, PZ_ERR_DATA, "%s: face %lld has a bad label %g", reader->name,
                        (long long)instance, values[ROLE_LABEL]);
    return ply_add_polygon(reader, (size_t)corner_count, (int64_t)values[ROLE_LABEL], instance);
}

static int ply_has_role(const ply_element *element, ply_role role)
{
    for (size_t i = 0; i < element->property_count; ++i)
        if (element->properties[i].role == role)
            return 1;
    return 0;
}

static pz_status ply_prepare_vertices(ply_reader *reader, const ply_element *element)
{
    if (!ply_has_role(element, ROLE_X) || !ply_has_role(element, ROLE_Y) || !ply_has_role(element, ROLE_Z))
        return pz_error(reader->ctx, PZ_ERR_DATA, "%s: vertex element lacks x, y or z", reader->name);
    if (element->count > INT32_MAX)
        return pz_error(reader->ctx, PZ_ERR_DATA, "%s: too many vertices", reader->name);
    reader->vertex_count = (int32_t)element->count;
    reader->have_vertices = 1;
    reader->positions = malloc(((size_t)element->count * 3 + 1) * sizeof(double));
    if (ply_has_role(element, ROLE_U) && ply_has_role(element, ROLE_V))
        reader->vertex_uvs = malloc(((size_t)element->count * 2 + 1) * sizeof(double));
    if (!reader->positions || (ply_has_role(element, ROLE_U) && ply_has_role(element, ROLE_V) && !reader->vertex_uvs))
        return ply_out_of_memory(reader);
    return PZ_OK;
}

static pz_status ply_read_element(ply_reader *reader, const ply_element *element)
{
    pz_status status = ply_check_count(reader, element);
    if (status)
        return status;
    if (element->kind == KIND_VERTEX && (status = ply_prepare_vertices(reader, element)))
        return status;
    int fixed_size = reader->format != PLY_ASCII && element->kind == KIND_OTHER;
    for (size_t i = 0; fixed_size && i < element->property_count; ++i)
        fixed_size = element->properties[i].count_type == PLY_NONE;
    if (fixed_size) { /* skip the whole block at once (its size was checked above) */
        size_t size = 0;
        for (size_t i = 0; i < element->property_count; ++i)
            size += ply_type_size(element->properties[i].type);
        reader->cursor += (size_t)element->count * size;
        return PZ_OK;
    }
    if (element->property_count == 0)
        return PZ_OK;
    for (int64_t instance = 0; instance < element->count; ++instance)
        if ((status = ply_read_instance(reader, element, instance)))
            return status;
    return PZ_OK;
}

/* ------------------------------------------------------------------------ */
/* Finishing                                                                 */
/* ------------------------------------------------------------------------ */

static int ply_compare_int64(const void *a, const void *b)
{
    int64_t x = *(const int64_t *)a, y = *(const int64_t *)b;
    return (x > y) - (x < y);
}

/* Index of `value` in the sorted distinct `values`, or -1. */
static int64_t ply_find_value(const int64_t *values, size_t count, int64_t value)
{
    size_t low = 0, high = count;
    while (low < high) {
        size_t middle = low + (high - low) / 2;
        if (values[middle] < value)
            low = middle + 1;
        else
            high = middle;
    }
    return low < count && values[low] == value ? (int64_t)low : -1;
}

/* Renumbers the raw label values densely (sorted), and attaches any pz_label names. */
static pz_status ply_finish_labels(ply_reader *reader, pz_mesh *mesh)
{
    size_t count = reader->face_count;
    int64_t *values = malloc(count * sizeof *values + 1);
    mesh->face_labels = malloc(count * sizeof(int32_t) + 1);
    if (!values || !mesh->face_labels) {
        free(values);
        return ply_out_of_memory(reader);
    }
    memcpy(values, reader->face_labels, count * sizeof *values);
    qsort(values, count, sizeof *values, ply_compare_int64);
    size_t distinct = 0;
    for (size_t i = 0; i < count; ++i)
        if (distinct == 0 || values[distinct - 1] != values[i])
            values[distinct++] = values[i];
    for (size_t f = 0; f < count; ++f)
        mesh->face_labels[f] = (int32_t)ply_find_value(values, distinct, reader->face_labels[f]);
    mesh->label_count = (int32_t)distinct;
    pz_status status = PZ_OK;
    if (reader->label_name_count > 0) {
        mesh->label_names = calloc(distinct + 1, sizeof(char *));
        if (!mesh->label_names)
            status = ply_out_of_memory(reader);
        for (size_t i = 0; !status && i < reader->label_name_count; ++i) {
            int64_t label = ply_find_value(values, distinct, reader->label_names[i].value);
            if (label >= 0 && !mesh->label_names[label]) {
                mesh->label_names[label] = reader->label_names[i].name;
                reader->label_names[i].name = NULL;
            }
        }
    }
    free(values);
    return status;
}

static pz_status ply_build_mesh(ply_reader *reader, int has_labels, pz_mesh **out)
{
    for (size_t i = 0; i < 3 * reader->face_count; ++i)
        if (reader->faces[i] < 0 || reader->faces[i] >= reader->vertex_count)
            return pz_error(reader->ctx, PZ_ERR_DATA, "%s: face %zu: vertex index out of range (%d vertices)",
                            reader->name, i / 3, (int)reader->vertex_count);
    pz_mesh *mesh = calloc(1, sizeof *mesh);
    if (!mesh)
        return ply_out_of_memory(reader);
    mesh->unit_scale = 1.0;
    mesh->vertex_count = reader->vertex_count;
    mesh->face_count = (int32_t)reader->face_count;
    mesh->positions = reader->positions;
    mesh->faces = reader->faces;
    reader->positions = NULL;
    reader->faces = NULL;
    pz_status status = PZ_OK;
    if (reader->vertex_uvs) {
        mesh->uv_count = mesh->vertex_count;
        mesh->uvs = reader->vertex_uvs;
        reader->vertex_uvs = NULL;
        mesh->corner_uvs = malloc(3 * reader->face_count * sizeof(int32_t) + 1);
        if (!mesh->corner_uvs)
            status = ply_out_of_memory(reader);
        else
            memcpy(mesh->corner_uvs, mesh->faces, 3 * reader->face_count * sizeof(int32_t));
    }
    if (!status && has_labels)
        status = ply_finish_labels(reader, mesh);
    if (status) {
        pz_mesh_free(&mesh);
        return status;
    }
    *out = mesh;
    return PZ_OK;
}

static pz_status ply_read_all(ply_reader *reader, pz_mesh **out)
{
    pz_status status = ply_read_header(reader);
    int has_labels = 0, has_indices = 0;
    for (size_t i = 0; !status && i < reader->element_count; ++i) {
        const ply_element *element = &reader->elements[i];
        if (element->kind == KIND_FACE) {
            has_labels = ply_has_role(element, ROLE_LABEL);
            has_indices = ply_has_role(element, ROLE_INDICES);
        }
        status = ply_read_element(reader, element);
    }
    if (status)
        return status;
    if (!reader->have_vertices)
        return pz_error(reader->ctx, PZ_ERR_DATA, "%s: no vertex element", reader->name);
    if (!has_indices || reader->face_count == 0)
        return pz_error(reader->ctx, PZ_ERR_DATA, "%s: no faces", reader->name);
    return ply_build_mesh(reader, has_labels, out);
}

static void ply_reader_free(ply_reader *reader)
{
    for (size_t i = 0; i < reader->element_count; ++i)
        free(reader->elements[i].properties);
    free(reader->elements);
    for (size_t i = 0; i < reader->label_name_count; ++i)
        free(reader->label_names[i].name);
    free(reader->label_names);
    free(reader->positions);
    free(reader->vertex_uvs);
    free(reader->faces);
    free(reader->face_labels);
    free(reader->polygon);
}

pz_status pz_ply_read_memory(const unsigned char *data, size_t size, const char *name, pz_mesh **out, pz_ctx *ctx)
{
    *out = NULL;
    static const unsigned char nothing[1] = {0};
    ply_reader reader;
    memset(&reader, 0, sizeof reader);
    reader.name = name ? name : "PLY";
    reader.ctx = ctx;
    reader.cursor = data ? data : nothing;
    reader.end = reader.cursor + (data ? size : 0);
    pz_status status = ply_read_all(&reader, out);
    ply_reader_free(&reader);
    return status;
}

/* ------------------------------------------------------------------------ */
/* Writer                                                                    */
/* ------------------------------------------------------------------------ */

/* A small output buffer so each value is not a separate stdio call. */
typedef struct ply_sink {
    FILE *file;
    size_t used;
    unsigned char bytes[1 << 16];
} ply_sink;

static void ply_flush(ply_sink *sink)
{
    fwrite(sink->bytes, 1, sink->used, sink->file);
    sink->used = 0;
}

static void ply_put(ply_sink *sink, uint64_t bits, size_t size)
{
    if (sink->used + size > sizeof sink->bytes)
        ply_flush(sink);
    for (size_t i = 0; i < size; ++i)
        sink->bytes[sink->used++] = (unsigned char)(bits >> (8 * i));
}

static void ply_put_double(ply_sink *sink, double value)
{
    uint64_t bits;
    memcpy(&bits, &value, sizeof bits);
    ply_put(sink, bits, 8);
}

/*
 * Per-vertex UVs (vertex_count x 2) when every corner of a vertex has the
 * same UV value; NULL when the mesh has no UVs or has seams (*has_seams = 1).
 * Unreferenced vertices get (0, 0). Returns PZ_ERR_NOMEM on failure.
 */
static pz_status ply_vertex_uvs(const pz_mesh *mesh, double **out, int *has_seams, pz_ctx *ctx)
{
    *out = NULL;
    *has_seams = 0;
    if (!mesh->uvs || !mesh->corner_uvs || mesh->uv_count <= 0)
        return PZ_OK;
    double *uvs = calloc((size_t)mesh->vertex_count * 2 + 1, sizeof(double));
    uint8_t *seen = calloc((size_t)mesh->vertex_count + 1, 1);
    if (!uvs || !seen) {
        free(uvs);
        free(seen);
        return pz_error(ctx, PZ_ERR_NOMEM, "PLY output: out of memory");
    }
    for (size_t corner = 0; corner < 3 * (size_t)mesh->face_count && !*has_seams; ++corner) {
        int32_t v = mesh->faces[corner], t = mesh->corner_uvs[corner];
        const double *uv = mesh->uvs + 2 * (size_t)t;
        if (!seen[v]) {
            seen[v] = 1;
            uvs[2 * (size_t)v] = uv[0];
            uvs[2 * (size_t)v + 1] = uv[1];
        } else if (uvs[2 * (size_t)v] != uv[0] || uvs[2 * (size_t)v + 1] != uv[1]) {
            *has_seams = 1;
        }
    }
    free(seen);
    if (*has_seams)
        free(uvs);
    else
        *out = uvs;
    return PZ_OK;
}

static void ply_write_header(const pz_mesh *mesh, FILE *file, int with_uvs)
{
    fprintf(file, "ply\nformat binary_little_endian 1.0\ncomment written by panelize %s\n", PZ_VERSION_STRING);
    for (int32_t label = 0; mesh->face_labels && mesh->label_names && label < mesh->label_count; ++label) {
        const char *name = mesh->label_names[label];
        if (!name || !*name)
            continue;
        fprintf(file, "comment pz_label %d ", (int)label);
        for (const char *c = name; *c; ++c)
            fputc((unsigned char)*c < 32 ? '_' : *c, file); /* a newline would break the header */
        fputc('\n', file);
    }
    fprintf(file, "element vertex %d\nproperty double x\nproperty double y\nproperty double z\n",
            (int)mesh->vertex_count);
    if (with_uvs)
        fputs("property double s\nproperty double t\n", file);
    fprintf(file, "element face %d\nproperty list uchar int vertex_indices\n", (int)mesh->face_count);
    if (mesh->face_labels)
        fputs("property int label\n", file);
    fputs("end_header\n", file);
}

pz_status pz_ply_write_file(const pz_mesh *mesh, FILE *file, pz_ctx *ctx)
{
    double *vertex_uvs;
    int has_seams;
    pz_status status = ply_vertex_uvs(mesh, &vertex_uvs, &has_seams, ctx);
    if (status)
        return status;
    if (has_seams)
        pz_note(ctx, "PLY output: the UVs have seams, which PLY cannot store per vertex; UVs not written");
    ply_sink *sink = malloc(sizeof *sink);
    if (!sink) {
        free(vertex_uvs);
        return pz_error(ctx, PZ_ERR_NOMEM, "PLY output: out of memory");
    }
    sink->file = file;
    sink->used = 0;
    ply_write_header(mesh, file, vertex_uvs != NULL);
    for (int32_t v = 0; v < mesh->vertex_count; ++v) {
        for (int k = 0; k < 3; ++k)
            ply_put_double(sink, mesh->positions[3 * (size_t)v + k]);
        for (int k = 0; vertex_uvs && k < 2; ++k)
            ply_put_double(sink, vertex_uvs[2 * (size_t)v + k]);
    }
    for (int32_t f = 0; f < mesh->face_count; ++f) {
        ply_put(sink, 3, 1);
        for (int k = 0; k < 3; ++k)
            ply_put(sink, (uint32_t)mesh->faces[3 * (size_t)f + k], 4);
        if (mesh->face_labels)
            ply_put(sink, (uint32_t)mesh->face_labels[f], 4);
    }
    ply_flush(sink);
    free(sink);
    free(vertex_uvs);
    if (ferror(file))
        return pz_error(ctx, PZ_ERR_CREATE, "PLY output: write error");
    return PZ_OK;
}

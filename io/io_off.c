/*
 * io/io_off.c -- Geomview OFF reader.
 *
 * Format: a header keyword, the counts "NV NF [NE]" (on the header line or
 * the next one), NV vertex lines "x y z ...", then NF face lines
 * "K i1 ... iK [colour]" with 0-based indices. The reader is line based:
 * anything after the needed numbers on a line (normals, colours and texture
 * coordinates of the C/N/ST variants, face colours) is ignored, '#' starts a
 * comment anywhere, blank lines are skipped, and '\r' is whitespace.
 * Header keywords: OFF, COFF, NOFF, CNOFF, STOFF, STCOFF, STNOFF, STCNOFF
 * (the 4OFF / nOFF dimensions and "OFF BINARY" are refused as unsupported).
 * Polygons are triangulated level by level (io/polygon.h). Texture coordinates of STOFF are not read
 * (their position on the line depends on optional colour fields).
 *
 * Failure (PZ_ERR_DATA, "NAME: line N: problem"): a missing or unknown
 * header, malformed counts or numbers, fewer lines than declared, an index
 * out of range, a face with fewer than 3 corners, no faces. A declared
 * vertex count is checked against the file size before positions are
 * allocated (a vertex line takes at least 6 bytes).
 *
 * SPDX-License-Identifier: GPL-3.0-or-later
 */
#include "io/io.h"
#include "core/util.h"
#include "io/polygon.h"

#include <stdint.h>
#include <stdlib.h>
#include <string.h>

typedef struct off_reader {
    const char *name;
    pz_ctx *ctx;
    const char *cursor, *end;
    long line;
    int32_t vertex_count;
    double *positions;
    int32_t *faces;
    size_t face_count, faces_capacity;
    int32_t *polygon;
    size_t polygon_capacity;
} off_reader;

static int off_is_space(char c)
{
    return c == ' ' || c == '\t' || c == '\r' || c == '\v' || c == '\f';
}

static pz_status off_fail(off_reader *reader, const char *problem)
{
    return pz_error(reader->ctx, PZ_ERR_DATA, "%s: line %ld: %s", reader->name, reader->line, problem);
}

static pz_status off_out_of_memory(off_reader *reader)
{
    return pz_error(reader->ctx, PZ_ERR_NOMEM, "%s: out of memory", reader->name);
}

/*
 * The next line with content, comment stripped, as [*start, *stop).
 * Returns 0 at the end of the data.
 */
static int off_next_line(off_reader *reader, const char **start, const char **stop)
{
    while (reader->cursor < reader->end) {
        const char *p = reader->cursor;
        const char *line_end = memchr(p, '\n', (size_t)(reader->end - p));
        if (!line_end)
            line_end = reader->end;
        reader->cursor = line_end < reader->end ? line_end + 1 : line_end;
        ++reader->line;
        const char *comment = memchr(p, '#', (size_t)(line_end - p));
        if (comment)
            line_end = comment;
        while (p < line_end && off_is_space(*p))
            ++p;
        if (p < line_end) {
            *start = p;
            *stop = line_end;
            return 1;
        }
    }
    return 0;
}

/* The next whitespace-delimited token of [*cursor, end); returns its length (0: none). */
static size_t off_token(const char **cursor, const char *end, const char **token)
{
    const char *p = *cursor;
    while (p < end && off_is_space(*p))
        ++p;
    *token = p;
    while (p < end && !off_is_space(*p))
        ++p;
    *cursor = p;
    return (size_t)(p - *token);
}

static int off_parse_double(const char **cursor, const char *end, double *value)
{
    const char *token;
    size_t length = off_token(cursor, end, &token);
    char buffer[128];
    if (length == 0 || length >= sizeof buffer)
        return 0;
    memcpy(buffer, token, length);
    buffer[length] = '\0';
    char *parsed_end;
    *value = strtod(buffer, &parsed_end);
    return parsed_end == buffer + length;
}

/* A non-negative decimal integer below 2^31. */
static int off_parse_index(const char **cursor, const char *end, int64_t *value)
{
    const char *token;
    size_t length = off_token(cursor, end, &token);
    if (length == 0 || length > 10)
        return 0;
    int64_t parsed = 0;
    for (size_t i = 0; i < length; ++i) {
        if (token[i] < '0' || token[i] > '9')
            return 0;
        parsed = parsed * 10 + (token[i] - '0');
    }
    if (parsed > INT32_MAX)
        return 0;
    *value = parsed;
    return 1;
}

/* Accepts [ST][C][N]OFF; returns 0 for anything else. */
static int off_header_keyword_ok(const char *token, size_t length)
{
    if (length < 3 || memcmp(token + length - 3, "OFF", 3) != 0)
        return 0;
    size_t prefix = length - 3, at = 0;
    if (prefix - at >= 2 && memcmp(token + at, "ST", 2) == 0)
        at += 2;
    if (at < prefix && token[at] == 'C')
        ++at;
    if (at < prefix && token[at] == 'N')
        ++at;
    return at == prefix;
}

static pz_status off_read_header(off_reader *reader, int64_t *vertex_count, int64_t *face_count)
{
    const char *line, *line_end, *token;
    if (!off_next_line(reader, &line, &line_end))
        return pz_error(reader->ctx, PZ_ERR_DATA, "%s: empty file (no OFF header)", reader->name);
    size_t length = off_token(&line, line_end, &token);
    if (!off_header_keyword_ok(token, length))
        return off_fail(reader, "not an OFF file (expected an OFF, COFF, NOFF or STOFF header)");
    const char *rest = line;
    size_t next_length = off_token(&rest, line_end, &token);
    if (next_length == 6 && memcmp(token, "BINARY", 6) == 0)
        return off_fail(reader, "binary OFF is not supported");
    if (next_length == 0 && !off_next_line(reader, &line, &line_end)) /* counts on the next line */
        return pz_error(reader->ctx, PZ_ERR_DATA, "%s: truncated: no vertex and face counts", reader->name);
    int64_t edge_count;
    if (!off_parse_index(&line, line_end, vertex_count) || !off_parse_index(&line, line_end, face_count))
        return off_fail(reader, "malformed counts (expected NV NF NE)");
    const char *after = line;
    if (off_token(&after, line_end, &token) > 0 && !off_parse_index(&line, line_end, &edge_count))
        return off_fail(reader, "malformed counts (expected NV NF NE)");
    return PZ_OK;
}

static pz_status off_read_vertices(off_reader *reader)
{
    /* A vertex line takes at least 6 bytes ("0 0 0\n"): bound the allocation by the data. */
    if ((size_t)reader->vertex_count > (size_t)(reader->end - reader->cursor) / 6 + 1)
        return off_fail(reader, "the vertex count is larger than the file can hold");
    reader->positions = malloc(((size_t)reader->vertex_count * 3 + 1) * sizeof(double));
    if (!reader->positions)
        return off_out_of_memory(reader);
    for (int32_t v = 0; v < reader->vertex_count; ++v) {
        const char *line, *line_end;
        if (!off_next_line(reader, &line, &line_end))
            return pz_error(reader->ctx, PZ_ERR_DATA, "%s: truncated: %d of %d vertices", reader->name, (int)v,
                            (int)reader->vertex_count);
        for (int k = 0; k < 3; ++k)
            if (!off_parse_double(&line, line_end, &reader->positions[3 * (size_t)v + k]))
                return off_fail(reader, "malformed vertex (expected x y z)");
    }
    return PZ_OK;
}

static pz_status off_read_face(off_reader *reader, const char *line, const char *line_end)
{
    int64_t corner_count, index;
    if (!off_parse_index(&line, line_end, &corner_count))
        return off_fail(reader, "malformed face (expected K i1 ... iK)");
    if (corner_count < 3)
        return off_fail(reader, "face with fewer than 3 corners");
    /* Every corner needs two characters of this line, which bounds the scratch polygon. */
    if (corner_count > (line_end - line + 1) / 2)
        return off_fail(reader, "face has fewer indices than it declares");
    if (!pz_grow((void **)&reader->polygon, &reader->polygon_capacity, (size_t)corner_count, sizeof(int32_t)))
        return off_out_of_memory(reader);
    for (int64_t k = 0; k < corner_count; ++k) {
        if (!off_parse_index(&line, line_end, &index))
            return off_fail(reader, "malformed face (expected K i1 ... iK)");
        if (index >= reader->vertex_count)
            return pz_error(reader->ctx, PZ_ERR_DATA, "%s: line %ld: vertex index %lld out of range (%d vertices)",
                            reader->name, reader->line, (long long)index, (int)reader->vertex_count);
        reader->polygon[k] = (int32_t)index;
    }
    size_t needed = reader->face_count + (size_t)corner_count - 2;
    if (needed > INT32_MAX)
        return off_fail(reader, "too many faces");
    if (!pz_grow((void **)&reader->faces, &reader->faces_capacity, 3 * needed, sizeof(int32_t)))
        return off_out_of_memory(reader);
    io_polygon_walk walk = {(size_t)corner_count, 1, 0};
    size_t corner[3];
    while (io_polygon_next(&walk, corner)) {
        int32_t *corners = reader->faces + 3 * reader->face_count++;
        for (int k = 0; k < 3; ++k)
            corners[k] = reader->polygon[corner[k]];
    }
    return PZ_OK;
}

static pz_status off_read_all(off_reader *reader, pz_mesh **out)
{
    int64_t vertex_count, face_count;
    pz_status status = off_read_header(reader, &vertex_count, &face_count);
    if (status)
        return status;
    reader->vertex_count = (int32_t)vertex_count;
    if ((status = off_read_vertices(reader)))
        return status;
    for (int64_t f = 0; f < face_count; ++f) {
        const char *line, *line_end;
        if (!off_next_line(reader, &line, &line_end))
            return pz_error(reader->ctx, PZ_ERR_DATA, "%s: truncated: %lld of %lld faces", reader->name,
                            (long long)f, (long long)face_count);
        if ((status = off_read_face(reader, line, line_end)))
            return status;
    }
    if (reader->face_count == 0)
        return pz_error(reader->ctx, PZ_ERR_DATA, "%s: no faces", reader->name);
    pz_mesh *mesh = calloc(1, sizeof *mesh);
    if (!mesh)
        return off_out_of_memory(reader);
    mesh->unit_scale = 1.0;
    mesh->vertex_count = reader->vertex_count;
    mesh->face_count = (int32_t)reader->face_count;
    mesh->positions = reader->positions;
    mesh->faces = reader->faces;
    reader->positions = NULL;
    reader->faces = NULL;
    *out = mesh;
    return PZ_OK;
}

pz_status pz_off_read_memory(const char *data, size_t size, const char *name, pz_mesh **out, pz_ctx *ctx)
{
    *out = NULL;
    off_reader reader;
    memset(&reader, 0, sizeof reader);
    reader.name = name ? name : "OFF";
    reader.ctx = ctx;
    reader.cursor = data ? data : "";
    reader.end = reader.cursor + (data ? size : 0);
    pz_status status = off_read_all(&reader, out);
    free(reader.positions);
    free(reader.faces);
    free(reader.polygon);
    return status;
}

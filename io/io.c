/*
 * io/io.c -- reading and writing meshes by file name.
 *
 * The format comes from the extension (case-insensitive): .obj, .ply, .off,
 * .glb, .gltf. A file is read whole into memory (one buffer, grown by
 * doubling, so pipes and /dev/stdin work as well as regular files) and handed
 * to the in-memory parser, which reports errors under the path. Writing goes
 * through pz_output (a temporary file renamed on success), so a failed write
 * never leaves a partial file behind; GLB does its own atomic writing.
 *
 * Failure: PZ_ERR_OPEN "PATH: cannot open: REASON" for a missing, unreadable
 * or directory path; PZ_ERR_DATA for an unknown extension or whatever the
 * parser refuses; PZ_ERR_DATA "POSE: does not match REST: ..." when a pose
 * file's connectivity differs; PZ_ERR_USAGE for an output extension with no
 * writer; PZ_ERR_CREATE naming the path when the output cannot be written.
 *
 * SPDX-License-Identifier: GPL-3.0-or-later
 */
#define _POSIX_C_SOURCE 200809L
#include "io/io.h"

#include <errno.h>
#include <stdlib.h>
#include <string.h>
#include <sys/stat.h>

static const struct {
    const char *extension;
    pz_format format;
} io_extensions[] = {
    {"obj", PZ_FORMAT_OBJ}, {"ply", PZ_FORMAT_PLY}, {"off", PZ_FORMAT_OFF},
    {"glb", PZ_FORMAT_GLB}, {"gltf", PZ_FORMAT_GLTF}};

/* Case-insensitive equality of ASCII strings (strcasecmp is not C11). */
static int io_same_letters(const char *a, const char *b)
{
    for (; *a && *b; ++a, ++b) {
        char x = *a >= 'A' && *a <= 'Z' ? (char)(*a - 'A' + 'a') : *a;
        char y = *b >= 'A' && *b <= 'Z' ? (char)(*b - 'A' + 'a') : *b;
        if (x != y)
            return 0;
    }
    return *a == *b;
}

pz_format pz_format_from_path(const char *path)
{
    if (!path)
        return PZ_FORMAT_UNKNOWN;
    const char *dot = strrchr(path, '.');
    const char *slash = strrchr(path, '/');
    if (!dot || (slash && dot < slash))
        return PZ_FORMAT_UNKNOWN;
    for (size_t i = 0; i < sizeof io_extensions / sizeof io_extensions[0]; ++i)
        if (io_same_letters(dot + 1, io_extensions[i].extension))
            return io_extensions[i].format;
    return PZ_FORMAT_UNKNOWN;
}

/* Bytes looked at before a file is read whole: enough for every format's header. */
#define IO_HEAD_BYTES 512

/*
 * The file's first bytes must look like its format before it is read whole,
 * so that a huge file of something else (a 2 GB sparse file, a renamed
 * archive) is refused at once, not after gigabytes: PLY and GLB by their
 * magic ("ply", "glTF"), glTF JSON by its opening brace, OBJ and OFF as text
 * (no NUL byte). The parsers still check everything after.
 */
static pz_status io_check_head(pz_format format, const unsigned char *head, size_t n, const char *path, pz_ctx *ctx)
{
    const char *expected = NULL;
    if (format == PZ_FORMAT_PLY && !(n >= 4 && memcmp(head, "ply", 3) == 0 && (head[3] == '\n' || head[3] == '\r')))
        expected = "a PLY file starts with \"ply\"";
    else if (format == PZ_FORMAT_GLB && !(n >= 4 && memcmp(head, "glTF", 4) == 0))
        expected = "a GLB file starts with \"glTF\"";
    else if (format == PZ_FORMAT_GLTF) {
        size_t i = n >= 3 && memcmp(head, "\xEF\xBB\xBF", 3) == 0 ? 3 : 0; /* a UTF-8 byte order mark */
        while (i < n && (head[i] == ' ' || head[i] == '\t' || head[i] == '\n' || head[i] == '\r'))
            ++i;
        if (i < n && head[i] != '{')
            expected = "a glTF file is a JSON object";
    } else if (format == PZ_FORMAT_OBJ || format == PZ_FORMAT_OFF) {
        if (memchr(head, '\0', n))
            expected = format == PZ_FORMAT_OBJ ? "an OBJ file is text" : "an OFF file is text";
    }
    if (!expected)
        return PZ_OK;
    return pz_error(ctx, PZ_ERR_DATA, "%s: not what its name says (%s)", path, expected);
}

/* Reads a whole file into a NUL-terminated buffer (*size excludes the NUL), once its head fits the format. */
static pz_status io_read_whole_file(const char *path, pz_format format, unsigned char **data, size_t *size,
                                    pz_ctx *ctx)
{
    *data = NULL;
    *size = 0;
    FILE *file = NULL;
    pz_status opened = pz_input_open(path, &file, ctx);
    if (opened != PZ_OK)
        return opened;
    unsigned char head[IO_HEAD_BYTES];
    size_t head_size = fread(head, 1, sizeof head, file);
    pz_status checked = io_check_head(format, head, head_size, path, ctx);
    if (checked != PZ_OK || fseek(file, 0, SEEK_SET) != 0) {
        fclose(file);
        return checked != PZ_OK ? checked : pz_error(ctx, PZ_ERR_OPEN, "%s: cannot read: %s", path, strerror(errno));
    }
    struct stat info;
    if (fstat(fileno(file), &info) != 0)
        memset(&info, 0, sizeof info);
    size_t capacity = S_ISREG(info.st_mode) && info.st_size > 0 ? (size_t)info.st_size + 1 : 1 << 16;
    unsigned char *buffer = malloc(capacity);
    size_t used = 0;
    while (buffer) {
        used += fread(buffer + used, 1, capacity - 1 - used, file);
        if (used < capacity - 1)
            break; /* end of file or an error */
        int next = getc(file); /* a full buffer is the whole file when this is EOF */
        if (next == EOF)
            break;
        unsigned char *bigger = capacity <= SIZE_MAX / 2 ? realloc(buffer, capacity * 2) : NULL;
        if (!bigger)
            free(buffer);
        buffer = bigger;
        capacity *= 2;
        if (buffer)
            buffer[used++] = (unsigned char)next;
    }
    int read_failed = ferror(file);
    int saved = errno;
    fclose(file);
    if (!buffer)
        return pz_error(ctx, PZ_ERR_NOMEM, "%s: out of memory reading the file", path);
    if (read_failed) {
        free(buffer);
        return pz_error(ctx, PZ_ERR_OPEN, "%s: cannot read: %s", path, strerror(saved));
    }
    buffer[used] = '\0';
    *data = buffer;
    *size = used;
    return PZ_OK;
}

/* The directory part of a path ("." when there is none), for glTF's external buffers. */
static char *io_directory_of(const char *path)
{
    const char *slash = strrchr(path, '/');
    size_t length = slash ? (size_t)(slash - path) : 1;
    if (slash == path)
        length = 1; /* "/x.gltf": the root */
    char *directory = malloc(length + 1);
    if (!directory)
        return NULL;
    memcpy(directory, slash ? path : ".", length);
    directory[length] = '\0';
    return directory;
}

/* Parses the file's bytes and frees them (glTF: as soon as tinygltf has its own copy, pz_gltf_read_owned). */
static pz_status io_parse(pz_format format, unsigned char *data, size_t size, const char *path, pz_mesh **out,
                          pz_ctx *ctx)
{
    pz_status status;
    switch (format) {
    case PZ_FORMAT_OBJ: status = pz_obj_read_memory((const char *)data, size, path, out, ctx); break;
    case PZ_FORMAT_PLY: status = pz_ply_read_memory(data, size, path, out, ctx); break;
    case PZ_FORMAT_OFF: status = pz_off_read_memory((const char *)data, size, path, out, ctx); break;
    case PZ_FORMAT_GLB: return pz_gltf_read_owned(data, size, 1, NULL, path, out, ctx);
    case PZ_FORMAT_GLTF: {
        char *directory = io_directory_of(path);
        if (!directory) {
            free(data);
            return pz_error(ctx, PZ_ERR_NOMEM, "%s: out of memory", path);
        }
        status = pz_gltf_read_owned(data, size, 0, directory, path, out, ctx);
        free(directory);
        return status;
    }
    default:
        status = pz_error(ctx, PZ_ERR_DATA, "%s: unknown format (expected .obj, .ply, .off, .glb, .gltf)", path);
        break;
    }
    free(data);
    return status;
}

pz_status pz_mesh_read(const char *path, pz_mesh **out, pz_ctx *ctx)
{
    *out = NULL;
    pz_format format = pz_format_from_path(path);
    if (format == PZ_FORMAT_UNKNOWN)
        return pz_error(ctx, PZ_ERR_DATA, "%s: unknown format (expected .obj, .ply, .off, .glb, .gltf)", path);
    unsigned char *data;
    size_t size;
    pz_status status = io_read_whole_file(path, format, &data, &size, ctx);
    if (status)
        return status;
    return io_parse(format, data, size, path, out, ctx); /* frees data */
}

/* PZ_OK when `pose` has the connectivity of `rest`; otherwise the mismatch naming both files. */
static pz_status io_check_pose(const pz_mesh *rest, const char *rest_path, const pz_mesh *pose,
                               const char *pose_path, pz_ctx *ctx)
{
    if (pose->vertex_count != rest->vertex_count)
        return pz_error(ctx, PZ_ERR_DATA, "%s: does not match %s: %d vertices, expected %d", pose_path, rest_path,
                        (int)pose->vertex_count, (int)rest->vertex_count);
    if (pose->face_count != rest->face_count)
        return pz_error(ctx, PZ_ERR_DATA, "%s: does not match %s: %d faces, expected %d", pose_path, rest_path,
                        (int)pose->face_count, (int)rest->face_count);
    for (int32_t f = 0; f < rest->face_count; ++f)
        if (memcmp(pose->faces + 3 * (size_t)f, rest->faces + 3 * (size_t)f, 3 * sizeof(int32_t)) != 0)
            return pz_error(ctx, PZ_ERR_DATA, "%s: does not match %s: face %d differs", pose_path, rest_path, (int)f);
    return PZ_OK;
}

pz_status pz_mesh_read_with_poses(const char *path, const char *const *pose_paths, int pose_path_count,
                                  pz_mesh **out, pz_ctx *ctx)
{
    *out = NULL;
    pz_mesh *rest;
    pz_status status = pz_mesh_read(path, &rest, ctx);
    if (status)
        return status;
    for (int i = 0; i < pose_path_count; ++i) {
        pz_mesh *pose;
        status = pz_mesh_read(pose_paths[i], &pose, ctx);
        if (!status)
            status = io_check_pose(rest, path, pose, pose_paths[i], ctx);
        if (!status && rest->pose_count >= PZ_MESH_MAX_POSES)
            status = pz_error(ctx, PZ_ERR_DATA, "%s: one pose too many: at most %d extra poses are supported",
                              pose_paths[i], PZ_MESH_MAX_POSES);
        if (!status)
            status = pz_mesh_add_pose(rest, pose->positions, ctx);
        pz_mesh_free(&pose);
        if (status) {
            pz_mesh_free(&rest);
            return status;
        }
    }
    *out = rest;
    return PZ_OK;
}

/* Writes OBJ or PLY through a temporary file; the message names `path` on failure. */
static pz_status io_write_text_or_binary(const pz_mesh *mesh, const char *path, pz_format format, pz_ctx *ctx)
{
    pz_output output;
    pz_status status = pz_output_open(&output, path, "wb", ctx);
    if (status)
        return status;
    status = format == PZ_FORMAT_OBJ ? pz_obj_write_file(mesh, output.file, ctx)
                                     : pz_ply_write_file(mesh, output.file, ctx);
    if (status) {
        int saved = errno;
        pz_output_abort(&output);
        if (status == PZ_ERR_CREATE)
            return pz_error(ctx, status, "%s: cannot write: %s", path, strerror(saved));
        return pz_error(ctx, status, "%s: cannot write: %s", path, pz_status_str(status));
    }
    return pz_output_commit(&output, ctx);
}

pz_status pz_mesh_write(const pz_mesh *mesh, const char *path, const pz_write_options *options, pz_ctx *ctx)
{
    pz_format format = pz_format_from_path(path);
    switch (format) {
    case PZ_FORMAT_OBJ:
    case PZ_FORMAT_PLY:
        return io_write_text_or_binary(mesh, path, format, ctx);
    case PZ_FORMAT_GLB: {
        pz_write_options defaults;
        memset(&defaults, 0, sizeof defaults);
        return pz_glb_write(mesh, path, options ? options : &defaults, ctx);
    }
    case PZ_FORMAT_OFF:
    case PZ_FORMAT_GLTF:
    case PZ_FORMAT_UNKNOWN:
        break;
    }
    return pz_error(ctx, PZ_ERR_USAGE, "%s: cannot write this format (expected .obj, .ply or .glb)", path);
}

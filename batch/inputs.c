/*
 * batch/inputs.c -- the garments of a batch: mesh files, folders searched for
 * meshes, manifests; their folder names; the stable order and the shards
 * (docs/batch.md, "Inputs").
 *
 * A manifest line is `PATH [OPTION]...`, tokens separated by blanks, a token
 * in double quotes may hold blanks, `#` starts a comment. Relative paths (the
 * PATH and the values of --pose, --sketch, --allowances, --features) are
 * relative to the manifest's folder. `--name NAME` sets the garment's folder
 * name; the other options are handed to the caller uninterpreted (the
 * command line checks them as `run` options before any garment runs).
 *
 * SPDX-License-Identifier: GPL-3.0-or-later
 */
#define _POSIX_C_SOURCE 200809L
#include "batch/internal.h"

#include <dirent.h>
#include <errno.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <strings.h>
#include <sys/stat.h>

#define MAX_NAME 200          /* a garment's folder name, characters */
#define MAX_DEPTH 32          /* sub-folder levels searched */
#define MAX_LINE 65536        /* a manifest line, bytes */
#define MAX_TOKENS 256        /* tokens on a manifest line */
#define MAX_SHARDS 100000

typedef struct garments {
    pz_batch_garment *items;
    int32_t count, capacity;
} garments;

char *bt_join(const char *folder, const char *name)
{
    size_t size = strlen(folder) + strlen(name) + 2;
    char *path = malloc(size);
    if (path)
        snprintf(path, size, "%s/%s", folder, name);
    return path;
}

static int has_extension(const char *path, const char *const *extensions, int count)
{
    const char *dot = strrchr(path, '.');
    const char *slash = strrchr(path, '/');
    if (!dot || (slash && dot < slash))
        return 0;
    for (int i = 0; i < count; ++i)
        if (strcasecmp(dot + 1, extensions[i]) == 0)
            return 1;
    return 0;
}

static const char *const mesh_extensions[] = {"obj", "ply", "off", "glb", "gltf"};
static const char *const manifest_extensions[] = {"txt", "list"};

static int is_mesh(const char *path) { return has_extension(path, mesh_extensions, 5); }

/* The folder name of a relative path: the extension dropped, "", "." and ".." components dropped, '/' as
 * '-', other characters outside [A-Za-z0-9._-] as '_', no leading '.'; at most MAX_NAME characters. */
static char *name_of(const char *relative)
{
    char *name = malloc(MAX_NAME + 1);
    if (!name)
        return NULL;
    const char *dot = strrchr(relative, '.');
    const char *slash = strrchr(relative, '/');
    const char *end = (dot && (!slash || dot > slash)) ? dot : relative + strlen(relative);
    size_t length = 0;
    for (const char *part = relative; part < end && length < MAX_NAME;) {
        const char *part_end = part;
        while (part_end < end && *part_end != '/')
            ++part_end;
        size_t part_length = (size_t)(part_end - part);
        int skipped = part_length == 0 || (part_length == 1 && part[0] == '.') ||
                      (part_length == 2 && part[0] == '.' && part[1] == '.');
        if (!skipped && length && length < MAX_NAME)
            name[length++] = '-';
        for (const char *c = part; !skipped && c < part_end && length < MAX_NAME; ++c) {
            int plain = (*c >= 'a' && *c <= 'z') || (*c >= 'A' && *c <= 'Z') || (*c >= '0' && *c <= '9') ||
                        *c == '.' || *c == '_' || *c == '-';
            name[length++] = plain ? *c : '_';
        }
        part = part_end + (part_end < end);
    }
    name[length] = '\0';
    if (!length)
        strcpy(name, "_");
    if (name[0] == '.')
        name[0] = '_';
    return name;
}

/* Adds a garment (takes ownership of name, path, source and args even on failure). */
static pz_status add(garments *list, char *name, char *path, char *source, char **args, int arg_count,
                     pz_ctx *ctx)
{
    if (list->count == list->capacity) {
        int32_t capacity = list->capacity ? 2 * list->capacity : 64;
        pz_batch_garment *items = realloc(list->items, (size_t)capacity * sizeof *items);
        if (!items) {
            free(name), free(path), free(source);
            for (int i = 0; i < arg_count; ++i)
                free(args[i]);
            free(args);
            return pz_error(ctx, PZ_ERR_NOMEM, "batch: out of memory listing the garments");
        }
        list->items = items, list->capacity = capacity;
    }
    list->items[list->count++] = (pz_batch_garment){name, path, source, args, arg_count, 0};
    if (!name || !path || !source)
        return pz_error(ctx, PZ_ERR_NOMEM, "batch: out of memory listing the garments");
    return PZ_OK;
}

/* ---------------------------------------------------------------- folders */

/* 1 when `folder` is a panelize output (holds .panelize): its garment.obj is an output, not an input. */
static int is_output_folder(const char *folder)
{
    char *marker = bt_join(folder, ".panelize");
    struct stat info;
    int found = marker && stat(marker, &info) == 0;
    free(marker);
    return found;
}

/* Adds the meshes under root/relative (relative "" at the top), sub-folders in any order (sorted later). */
static pz_status search(garments *list, const char *root, const char *relative, int depth, pz_ctx *ctx)
{
    char *folder = relative[0] ? bt_join(root, relative) : strdup(root);
    if (!folder)
        return pz_error(ctx, PZ_ERR_NOMEM, "batch: out of memory listing the garments");
    DIR *dir = opendir(folder);
    if (!dir) {
        pz_status status = pz_error(ctx, PZ_ERR_OPEN, "batch: %s: cannot read the folder: %s", folder, strerror(errno));
        free(folder);
        return status;
    }
    pz_status status = PZ_OK;
    for (struct dirent *entry; status == PZ_OK && (entry = readdir(dir));) {
        if (entry->d_name[0] == '.')
            continue; /* ".", "..", hidden files and the half-written folders of pz_result_write */
        char *path = bt_join(folder, entry->d_name);
        char *below = relative[0] ? bt_join(relative, entry->d_name) : strdup(entry->d_name);
        struct stat link_info, info;
        if (!path || !below) {
            status = pz_error(ctx, PZ_ERR_NOMEM, "batch: out of memory listing the garments");
        } else if (lstat(path, &link_info) == 0 && S_ISDIR(link_info.st_mode)) {
            if (depth < MAX_DEPTH && !is_output_folder(path))
                status = search(list, root, below, depth + 1, ctx);
        } else if (is_mesh(entry->d_name) && stat(path, &info) == 0 && S_ISREG(info.st_mode)) {
            status = add(list, name_of(below), path, strdup(path), NULL, 0, ctx);
            path = NULL;
        }
        free(path), free(below);
    }
    closedir(dir);
    free(folder);
    return status;
}

/* ---------------------------------------------------------------- manifests */

/* Splits a line into tokens (blanks; "quoted" tokens; # comment). -1 on an open quote or too many tokens. */
static int tokenize(char *line, char **tokens)
{
    int count = 0;
    char *at = line;
    for (;;) {
        while (*at == ' ' || *at == '\t' || *at == '\r' || *at == '\n')
            ++at;
        if (!*at || *at == '#')
            return count;
        if (count == MAX_TOKENS)
            return -1;
        if (*at == '"') {
            char *close = strchr(at + 1, '"');
            if (!close)
                return -1;
            *close = '\0';
            tokens[count++] = at + 1;
            at = close + 1;
            continue;
        }
        tokens[count++] = at;
        while (*at && *at != ' ' && *at != '\t' && *at != '\r' && *at != '\n')
            ++at;
        if (*at)
            *at++ = '\0';
    }
}

/* A manifest's path made usable from here: relative ones are relative to the manifest's folder. */
static char *resolve(const char *base, const char *path)
{
    if (path[0] == '/' || !base)
        return strdup(path);
    return bt_join(base, path);
}

/* Options whose value is a file (resolved against the manifest's folder). */
static int takes_file(const char *option, size_t length)
{
    static const char *const names[] = {"--pose", "--sketch", "--allowances", "--features"};
    for (size_t i = 0; i < sizeof names / sizeof names[0]; ++i)
        if (strlen(names[i]) == length && strncmp(option, names[i], length) == 0)
            return 1;
    return 0;
}

/* The options after PATH, file values resolved; --name taken out into *name. */
static pz_status line_options(char **tokens, int count, const char *base, const char *where, char ***args_out,
                              int *arg_count, char **name, pz_ctx *ctx)
{
    char **args = calloc((size_t)count + 1, sizeof *args);
    int used = 0;
    if (!args)
        return pz_error(ctx, PZ_ERR_NOMEM, "batch: out of memory reading %s", where);
    pz_status status = PZ_OK;
    for (int i = 0; i < count && status == PZ_OK; ++i) {
        const char *token = tokens[i];
        const char *equals = strncmp(token, "--", 2) == 0 ? strchr(token, '=') : NULL;
        size_t option_length = equals ? (size_t)(equals - token) : strlen(token);
        if (option_length == 6 && strncmp(token, "--name", 6) == 0) {
            const char *value = equals ? equals + 1 : (i + 1 < count ? tokens[++i] : NULL);
            if (!value || !*value)
                status = pz_error(ctx, PZ_ERR_USAGE, "batch: %s: --name needs a value", where);
            else if (!(free(*name), *name = name_of(value)))
                status = pz_error(ctx, PZ_ERR_NOMEM, "batch: out of memory reading %s", where);
            continue;
        }
        if (token[0] == '-' && takes_file(token, option_length)) {
            if (equals) {
                char *path = resolve(base, equals + 1);
                size_t size = option_length + 2 + (path ? strlen(path) : 0);
                args[used] = path ? malloc(size) : NULL;
                if (args[used])
                    snprintf(args[used], size, "%.*s=%s", (int)option_length, token, path);
                free(path);
                ++used;
            } else {
                args[used++] = strdup(token);
                if (i + 1 < count)
                    args[used++] = resolve(base, tokens[++i]);
            }
        } else {
            args[used++] = strdup(token);
        }
        if (args[used - 1] == NULL)
            status = pz_error(ctx, PZ_ERR_NOMEM, "batch: out of memory reading %s", where);
    }
    if (status != PZ_OK) {
        for (int i = 0; i < used; ++i)
            free(args[i]);
        free(args);
        return status;
    }
    *args_out = args, *arg_count = used;
    return PZ_OK;
}

/* The folder part of a manifest's path ("." for a bare name). */
static char *folder_of(const char *path)
{
    const char *slash = strrchr(path, '/');
    if (!slash)
        return strdup(".");
    size_t length = slash == path ? 1 : (size_t)(slash - path);
    char *folder = malloc(length + 1);
    if (folder)
        memcpy(folder, path, length), folder[length] = '\0';
    return folder;
}

static pz_status read_manifest(garments *list, const char *manifest, pz_ctx *ctx)
{
    FILE *file = NULL;
    pz_status status = pz_input_open(manifest, &file, ctx);
    if (status != PZ_OK)
        return pz_error(ctx, status, "batch: %s", ctx->error);
    char *base = folder_of(manifest);
    char *line = malloc(MAX_LINE + 2);
    char *tokens[MAX_TOKENS];
    if (!base || !line)
        status = pz_error(ctx, PZ_ERR_NOMEM, "batch: out of memory reading %s", manifest);
    int number = 0;
    while (status == PZ_OK && fgets(line, MAX_LINE + 2, file)) {
        ++number;
        char where[4200];
        snprintf(where, sizeof where, "%s:%d", manifest, number);
        size_t length = strlen(line);
        if (length > MAX_LINE && line[length - 1] != '\n') {
            status = pz_error(ctx, PZ_ERR_USAGE, "batch: %s: line longer than %d bytes", where, MAX_LINE);
            break;
        }
        int count = tokenize(line, tokens);
        if (count < 0) {
            status = pz_error(ctx, PZ_ERR_USAGE, "batch: %s: unclosed quote or more than %d words", where, MAX_TOKENS);
            break;
        }
        if (count == 0)
            continue;
        if (tokens[0][0] == '-') {
            status = pz_error(ctx, PZ_ERR_USAGE, "batch: %s: the line must start with the garment's file, not '%s'",
                              where, tokens[0]);
            break;
        }
        if (!is_mesh(tokens[0])) {
            status = pz_error(ctx, PZ_ERR_USAGE, "batch: %s: '%s' is not a mesh file (.obj .ply .off .glb .gltf)",
                              where, tokens[0]);
            break;
        }
        char **args = NULL, *name = NULL;
        int arg_count = 0;
        status = line_options(tokens + 1, count - 1, base, where, &args, &arg_count, &name, ctx);
        if (status != PZ_OK)
            break;
        if (!name)
            name = name_of(tokens[0][0] == '/' ? strrchr(tokens[0], '/') + 1 : tokens[0]);
        status = add(list, name, resolve(base, tokens[0]), strdup(where), args, arg_count, ctx);
    }
    if (status == PZ_OK && ferror(file))
        status = pz_error(ctx, PZ_ERR_OPEN, "batch: %s: read error", manifest);
    fclose(file);
    free(base), free(line);
    return status;
}

/* ---------------------------------------------------------------- the list */

static void free_garments(pz_batch_garment *items, int32_t count)
{
    for (int32_t i = 0; i < count; ++i) {
        free(items[i].name), free(items[i].path), free(items[i].source);
        for (int k = 0; k < items[i].arg_count; ++k)
            free(items[i].args[k]);
        free(items[i].args);
    }
    free(items);
}

static int by_name(const void *a, const void *b)
{
    return strcmp(((const pz_batch_garment *)a)->name, ((const pz_batch_garment *)b)->name);
}

static pz_status read_input(garments *list, const char *input, pz_ctx *ctx)
{
    struct stat info;
    if (stat(input, &info) != 0)
        return pz_error(ctx, PZ_ERR_OPEN, "batch: %s: %s", input, strerror(errno));
    if (S_ISDIR(info.st_mode)) {
        int32_t before = list->count;
        pz_status status = search(list, input, "", 0, ctx);
        if (status == PZ_OK && list->count == before)
            return pz_error(ctx, PZ_ERR_USAGE, "batch: %s: no garment in the folder (.obj .ply .off .glb .gltf)",
                            input);
        return status;
    }
    if (has_extension(input, manifest_extensions, 2))
        return read_manifest(list, input, ctx);
    if (!is_mesh(input))
        return pz_error(ctx, PZ_ERR_USAGE,
                        "batch: %s: not a garment (.obj .ply .off .glb .gltf), a folder or a manifest (.txt .list)",
                        input);
    const char *slash = strrchr(input, '/');
    return add(list, name_of(slash ? slash + 1 : input), strdup(input), strdup(input), NULL, 0, ctx);
}

pz_status pz_batch_list_read(const char *const *inputs, int input_count, pz_batch_list **out, pz_ctx *ctx)
{
    *out = NULL;
    garments found = {0};
    pz_status status = PZ_OK;
    for (int i = 0; i < input_count && status == PZ_OK; ++i)
        status = read_input(&found, inputs[i], ctx);
    if (status == PZ_OK && found.count == 0)
        status = pz_error(ctx, PZ_ERR_USAGE, "batch: no garment given (see panelize batch --help)");
    if (status == PZ_OK) {
        qsort(found.items, (size_t)found.count, sizeof *found.items, by_name);
        for (int32_t i = 0; i < found.count; ++i) {
            found.items[i].order = i;
            if (i > 0 && strcmp(found.items[i].name, found.items[i - 1].name) == 0) {
                status = pz_error(ctx, PZ_ERR_USAGE, "batch: %s and %s would both write the folder %s (give "
                                  "--name in a manifest, or rename one)", found.items[i - 1].source,
                                  found.items[i].source, found.items[i].name);
                break;
            }
        }
    }
    pz_batch_list *list = calloc(1, sizeof *list);
    if (status == PZ_OK && !list)
        status = pz_error(ctx, PZ_ERR_NOMEM, "batch: out of memory listing the garments");
    if (status != PZ_OK) {
        free_garments(found.items, found.count);
        free(list);
        return status;
    }
    list->garments = found.items, list->count = found.count;
    *out = list;
    return PZ_OK;
}

void pz_batch_list_free(pz_batch_list **list)
{
    if (!list || !*list)
        return;
    free_garments((*list)->garments, (*list)->count);
    free(*list);
    *list = NULL;
}

pz_status pz_batch_shard_parse(const char *text, int32_t *index, int32_t *count, pz_ctx *ctx)
{
    char *end = NULL;
    errno = 0;
    long i = strtol(text, &end, 10);
    long n = -1;
    if (end != text && *end == '/' && errno == 0) {
        const char *second = end + 1;
        n = strtol(second, &end, 10);
        if (end == second || *end || errno)
            n = -1;
    }
    if (n < 1 || n > MAX_SHARDS || i < 0 || i >= n || text[0] == '-' || text[0] == '+')
        return pz_error(ctx, PZ_ERR_USAGE, "batch: --shard: '%s' is not I/N with 0 <= I < N <= %d (I counts "
                        "from 0, as sbatch --array=0-(N-1) numbers its tasks)", text, MAX_SHARDS);
    *index = (int32_t)i, *count = (int32_t)n;
    return PZ_OK;
}

/*
 * pipeline/folder.c -- the output folder as one unit (docs/cli.md, "The
 * output folder").
 *
 * A result's files are written into a hidden folder beside the target,
 * PARENT/.NAME.tmp-PID, each file synced, then a marker file `.panelize`
 * written last; the folder is synced and swapped in: renamed onto the target
 * when that is missing or empty, exchanged with it atomically
 * (renameat2 RENAME_EXCHANGE) when it holds an earlier panelize output, whose
 * files are then removed. A reader sees the old set or the new one, never a
 * mix; files of an earlier run that this run does not write are gone; a
 * failed or cancelled write removes its hidden folder and leaves the earlier
 * set untouched.
 *
 * A folder that is not empty and has no `.panelize` marker is someone
 * else's: it is refused (PZ_ERR_CREATE) before any work (pz_output_folder_check),
 * never overwritten. Writers into the same parent take turns (an exclusive
 * flock on the parent during the swap), and hidden folders left by a killed
 * run (its PID no longer alive) are removed by the next one.
 *
 * SPDX-License-Identifier: GPL-3.0-or-later
 */
#define _GNU_SOURCE
#include "pipeline/internal.h"

#include <dirent.h>
#include <errno.h>
#include <fcntl.h>
#include <ftw.h>
#include <signal.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/file.h>
#include <sys/stat.h>
#include <unistd.h>

#define MARKER_NAME ".panelize"

/* PARENT and NAME of a folder path (trailing slashes ignored); malloc'd, NULL when out of memory. */
static int split_path(const char *folder, char **parent, char **name)
{
    size_t length = strlen(folder);
    while (length > 1 && folder[length - 1] == '/')
        --length;
    const char *slash = NULL;
    for (size_t i = 0; i < length; ++i)
        if (folder[i] == '/')
            slash = folder + i;
    size_t parent_length = slash ? (size_t)(slash - folder) : 1;
    *parent = malloc(parent_length + 1);
    *name = malloc(length + 1);
    if (!*parent || !*name) {
        free(*parent), free(*name);
        *parent = *name = NULL;
        return 0;
    }
    if (!slash)
        strcpy(*parent, ".");
    else if (slash == folder)
        strcpy(*parent, "/");
    else
        memcpy(*parent, folder, parent_length), (*parent)[parent_length] = '\0';
    size_t start = slash ? (size_t)(slash - folder) + 1 : 0;
    memcpy(*name, folder + start, length - start);
    (*name)[length - start] = '\0';
    return 1;
}

/* 1 when `path` is an empty directory, 0 when it holds something, -1 when it cannot be read. */
static int folder_is_empty(const char *path)
{
    DIR *dir = opendir(path);
    if (!dir)
        return -1;
    int empty = 1;
    for (struct dirent *entry; empty && (entry = readdir(dir));)
        if (strcmp(entry->d_name, ".") != 0 && strcmp(entry->d_name, "..") != 0)
            empty = 0;
    closedir(dir);
    return empty;
}

static int has_marker(const char *folder)
{
    size_t size = strlen(folder) + sizeof MARKER_NAME + 2;
    char *path = malloc(size);
    if (!path)
        return 0;
    snprintf(path, size, "%s/%s", folder, MARKER_NAME);
    struct stat info;
    int found = lstat(path, &info) == 0 && S_ISREG(info.st_mode);
    free(path);
    return found;
}

static int remove_entry(const char *path, const struct stat *info, int type, struct FTW *walk)
{
    (void)info, (void)type, (void)walk;
    return remove(path);
}

/* Removes a folder and everything in it (no symbolic link is followed). */
static void remove_tree(const char *path)
{
    nftw(path, remove_entry, 16, FTW_DEPTH | FTW_PHYS);
}

/* The deepest existing ancestor of a path that does not exist (for the writability check). */
static char *existing_ancestor(const char *path)
{
    char *copy = strdup(path);
    if (!copy)
        return NULL;
    for (;;) {
        struct stat info;
        if (stat(copy, &info) == 0)
            return copy;
        char *slash = strrchr(copy, '/');
        if (!slash) {
            strcpy(copy, ".");
            return copy;
        }
        if (slash == copy) {
            copy[1] = '\0';
            return copy;
        }
        *slash = '\0';
    }
}

pz_status pz_output_folder_check(const char *folder, pz_ctx *ctx)
{
    if (!folder || !*folder)
        return pz_error(ctx, PZ_ERR_USAGE, "no output folder");
    struct stat info;
    if (stat(folder, &info) == 0) {
        if (!S_ISDIR(info.st_mode))
            return pz_error(ctx, PZ_ERR_CREATE, "%s: cannot create the output folder: it is a file", folder);
        int empty = folder_is_empty(folder);
        if (empty < 0)
            return pz_error(ctx, PZ_ERR_CREATE, "%s: cannot read the output folder: %s", folder, strerror(errno));
        if (!empty && !has_marker(folder))
            return pz_error(ctx, PZ_ERR_CREATE,
                            "%s: the output folder is not empty and was not written by panelize (no %s): give a new "
                            "or an empty folder",
                            folder, MARKER_NAME);
    }
    char *parent = NULL, *name = NULL;
    if (!split_path(folder, &parent, &name))
        return pz_error(ctx, PZ_ERR_NOMEM, "%s: out of memory", folder);
    char *ancestor = existing_ancestor(parent);
    pz_status status = PZ_OK;
    if (!ancestor)
        status = pz_error(ctx, PZ_ERR_NOMEM, "%s: out of memory", folder);
    else if (stat(ancestor, &info) != 0 || !S_ISDIR(info.st_mode))
        status = pz_error(ctx, PZ_ERR_CREATE, "%s: cannot create the output folder: %s is not a directory", folder,
                          ancestor);
    else if (access(ancestor, W_OK | X_OK) != 0)
        status = pz_error(ctx, PZ_ERR_CREATE, "%s: cannot create the output folder: %s: %s", folder, ancestor,
                          strerror(errno));
    free(ancestor), free(parent), free(name);
    return status;
}

/* ---------------------------------------------------------------- the hidden folder */

/* Removes PARENT/.NAME.tmp-PID and .NAME.old-PID folders whose process is gone (a killed run's). */
static void clear_dead_runs(const char *parent, const char *name)
{
    DIR *dir = opendir(parent);
    if (!dir)
        return;
    size_t name_length = strlen(name);
    for (struct dirent *entry; (entry = readdir(dir));) {
        const char *d = entry->d_name;
        if (d[0] != '.' || strncmp(d + 1, name, name_length) != 0)
            continue;
        const char *rest = d + 1 + name_length;
        if (strncmp(rest, ".tmp-", 5) != 0 && strncmp(rest, ".old-", 5) != 0)
            continue;
        char *end = NULL;
        long pid = strtol(rest + 5, &end, 10);
        if (!end || *end || pid <= 0 || pid == (long)getpid() || !(kill((pid_t)pid, 0) != 0 && errno == ESRCH))
            continue;
        size_t size = strlen(parent) + strlen(d) + 2;
        char *path = malloc(size);
        if (path) {
            snprintf(path, size, "%s/%s", parent, d);
            remove_tree(path);
            free(path);
        }
    }
    closedir(dir);
}

static void sync_path(const char *path)
{
    int fd = open(path, O_RDONLY);
    if (fd >= 0) {
        fsync(fd);
        close(fd);
    }
}

pz_status pl_folder_begin(const char *folder, pl_folder *out, pz_ctx *ctx)
{
    memset(out, 0, sizeof *out);
    out->lock_fd = -1;
    pz_status status = pz_output_folder_check(folder, ctx);
    if (status != PZ_OK)
        return status;
    out->target = strdup(folder);
    if (!out->target || !split_path(folder, &out->parent, &out->name))
        return pz_error(ctx, PZ_ERR_NOMEM, "%s: out of memory", folder);
    size_t size = strlen(out->parent) + strlen(out->name) + 40;
    out->hidden = malloc(size);
    if (!out->hidden)
        return pz_error(ctx, PZ_ERR_NOMEM, "%s: out of memory", folder);
    snprintf(out->hidden, size, "%s/.%s.tmp-%ld", out->parent, out->name, (long)getpid());
    /* Take turns with other writers into this parent; the lock goes with the process. */
    out->lock_fd = open(out->parent, O_RDONLY | O_DIRECTORY);
    if (out->lock_fd >= 0)
        flock(out->lock_fd, LOCK_EX);
    clear_dead_runs(out->parent, out->name);
    remove_tree(out->hidden); /* a folder of this very PID can only be a leftover */
    if (mkdir(out->hidden, 0777) != 0)
        return pz_error(ctx, PZ_ERR_CREATE, "%s: cannot create the output folder: %s", folder, strerror(errno));
    return PZ_OK;
}

/* The marker, written last: the folder is a complete panelize output. */
static pz_status write_marker(const pl_folder *folder, const char *const *files, int file_count, pz_ctx *ctx)
{
    size_t size = strlen(folder->hidden) + sizeof MARKER_NAME + 2;
    char *path = malloc(size);
    if (!path)
        return pz_error(ctx, PZ_ERR_NOMEM, "%s: out of memory", folder->target);
    snprintf(path, size, "%s/%s", folder->hidden, MARKER_NAME);
    pz_output out;
    pz_status status = pz_output_open(&out, path, "w", ctx);
    if (status == PZ_OK) {
        fprintf(out.file, "{\"writer\": \"panelize %s\", \"complete\": true, \"files\": [", PZ_VERSION_STRING);
        for (int i = 0; i < file_count; ++i)
            fprintf(out.file, "%s\"%s\"", i ? ", " : "", files[i]);
        fputs("]}\n", out.file);
        status = pz_output_commit(&out, ctx);
    }
    free(path);
    return status;
}

pz_status pl_folder_commit(pl_folder *folder, const char *const *files, int file_count, pz_ctx *ctx)
{
    pz_status status = write_marker(folder, files, file_count, ctx);
    if (status != PZ_OK)
        return status;
    sync_path(folder->hidden);
    struct stat info;
    int exists = stat(folder->target, &info) == 0;
    int empty = exists ? folder_is_empty(folder->target) == 1 : 0;
    if (!exists || empty) {
        /* rename(2) replaces an empty directory in one step. */
        if (rename(folder->hidden, folder->target) != 0)
            return pz_error(ctx, PZ_ERR_CREATE, "%s: cannot write the output folder: %s", folder->target,
                            strerror(errno));
    } else if (renameat2(AT_FDCWD, folder->hidden, AT_FDCWD, folder->target, RENAME_EXCHANGE) == 0) {
        remove_tree(folder->hidden); /* now the earlier run's files */
    } else {
        /* No atomic exchange on this file system: move the old set aside, then the new one in. */
        size_t size = strlen(folder->parent) + strlen(folder->name) + 40;
        char *old = malloc(size);
        if (!old)
            return pz_error(ctx, PZ_ERR_NOMEM, "%s: out of memory", folder->target);
        snprintf(old, size, "%s/.%s.old-%ld", folder->parent, folder->name, (long)getpid());
        int moved = rename(folder->target, old) == 0;
        int saved = errno;
        if (moved && rename(folder->hidden, folder->target) != 0) {
            saved = errno;
            rename(old, folder->target); /* put the earlier set back */
            moved = 0;
        }
        if (moved)
            remove_tree(old);
        free(old);
        if (!moved)
            return pz_error(ctx, PZ_ERR_CREATE, "%s: cannot write the output folder: %s", folder->target,
                            strerror(saved));
    }
    sync_path(folder->parent);
    folder->committed = 1;
    return PZ_OK;
}

void pl_folder_end(pl_folder *folder)
{
    if (folder->hidden && !folder->committed)
        remove_tree(folder->hidden);
    if (folder->lock_fd >= 0)
        close(folder->lock_fd); /* releases the lock */
    free(folder->target), free(folder->parent), free(folder->name), free(folder->hidden);
    memset(folder, 0, sizeof *folder);
    folder->lock_fd = -1;
}

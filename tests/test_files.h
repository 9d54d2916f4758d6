/*
 * tests/test_files.h -- a scratch directory and whole files for the C tests
 * that touch the filesystem. POSIX: define _POSIX_C_SOURCE 200809L before
 * the first #include.
 *
 *  - test_temp_dir_create("pz_thing") makes $TMPDIR/pz_thing_XXXXXX (or under
 *    /tmp) in test_temp_dir; test_temp_path names a file in it;
 *    test_temp_dir_remove removes it with everything inside (0 on success).
 *  - test_write_file writes a whole file (REQUIRE), test_read_file reads one
 *    (malloc'd, NULL when it cannot).
 *
 * SPDX-License-Identifier: GPL-3.0-or-later
 */
#ifndef PZ_TEST_FILES_H
#define PZ_TEST_FILES_H

#if !defined(_POSIX_C_SOURCE) || _POSIX_C_SOURCE < 200809L
#error "test_files.h needs _POSIX_C_SOURCE 200809L, defined before the first #include"
#endif

#include "test_util.h"

#include <dirent.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/stat.h>
#include <unistd.h>

static char test_temp_dir[256];

/* Makes a fresh directory $TMPDIR/PREFIX_XXXXXX into test_temp_dir and returns it. */
static inline const char *test_temp_dir_create(const char *prefix)
{
    const char *tmp = getenv("TMPDIR");
    snprintf(test_temp_dir, sizeof test_temp_dir, "%s/%s_XXXXXX", tmp && *tmp ? tmp : "/tmp", prefix);
    int made = mkdtemp(test_temp_dir) != NULL;
    REQUIRE(made, "mkdtemp %s", test_temp_dir);
    return test_temp_dir;
}

/* Writes "test_temp_dir/FILE" into out and returns out. */
static inline char *test_temp_path(char *out, size_t size, const char *file)
{
    snprintf(out, size, "%s/%s", test_temp_dir, file);
    return out;
}

/* Removes path: a file, or a directory with all it holds (symbolic links are not followed). 0 on success. */
static inline int test_remove_tree(const char *path)
{
    struct stat info;
    if (lstat(path, &info) != 0)
        return -1;
    if (!S_ISDIR(info.st_mode))
        return unlink(path);
    DIR *dir = opendir(path);
    if (!dir)
        return -1;
    int failed = 0;
    for (struct dirent *entry; (entry = readdir(dir));) {
        if (strcmp(entry->d_name, ".") == 0 || strcmp(entry->d_name, "..") == 0)
            continue;
        char child[4096];
        if (snprintf(child, sizeof child, "%s/%s", path, entry->d_name) >= (int)sizeof child) {
            failed = 1; /* a path this long is not one the tests make */
            continue;
        }
        failed |= test_remove_tree(child) != 0;
    }
    closedir(dir);
    return failed || rmdir(path) != 0 ? -1 : 0;
}

static inline int test_temp_dir_remove(void)
{
    return test_remove_tree(test_temp_dir);
}

/* Writes size bytes of data to path (creating or truncating it); stops the test when it cannot. */
static inline void test_write_file(const char *path, const void *data, size_t size)
{
    FILE *file = fopen(path, "wb");
    REQUIRE(file != NULL, "cannot create %s", path);
    size_t written = fwrite(data, 1, size, file);
    int closed = fclose(file) == 0;
    REQUIRE(written == size && closed, "cannot write %s", path);
}

/* The whole file at path (malloc'd, one byte more than *size) or NULL when it cannot be read. */
static inline unsigned char *test_read_file(const char *path, size_t *size)
{
    FILE *file = fopen(path, "rb");
    if (!file)
        return NULL;
    unsigned char *data = NULL;
    long length = -1;
    if (fseek(file, 0, SEEK_END) == 0 && (length = ftell(file)) >= 0 && fseek(file, 0, SEEK_SET) == 0)
        data = malloc((size_t)length + 1);
    if (data && fread(data, 1, (size_t)length, file) != (size_t)length) {
        free(data);
        data = NULL;
    }
    fclose(file);
    *size = data ? (size_t)length : 0;
    return data;
}

#endif

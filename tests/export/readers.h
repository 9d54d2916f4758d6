/*
 * tests/export/readers.h -- running the real readers (ezdxf, the Khronos
 * glTF validator, rsvg-convert, poppler, Python's XML parser) from a C test:
 *  - reader_run: a shell command's exit status;
 *  - reader_available: 1 when a probe command succeeds; else the reader's
 *    checks are a skipped part (test_skip_part: the test exits 77), which
 *    fails the test when CI=true;
 *  - reader_passes: CHECKs that a reader's command succeeds, quoting its
 *    output (kept in a log file) when it does not.
 * Needs test_util.h and test_files.h.
 *
 * SPDX-License-Identifier: GPL-3.0-or-later
 */
#ifndef PZ_TEST_READERS_H
#define PZ_TEST_READERS_H

#include "../test_files.h"
#include "../test_util.h"

#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/wait.h>

/* The exit status of a shell command, -1 when it did not run. */
static inline int reader_run(const char *command)
{
    int status = system(command);
    return status != -1 && WIFEXITED(status) ? WEXITSTATUS(status) : -1;
}

static inline int reader_available(const char *probe, const char *what)
{
    char command[1200];
    snprintf(command, sizeof command, "(%s) >/dev/null 2>&1", probe);
    if (reader_run(command) == 0)
        return 1;
    const char *ci = getenv("CI");
    CHECK(!(ci && strcmp(ci, "true") == 0), "%s is not installed (required when CI=true)", what);
    char why[300];
    snprintf(why, sizeof why, "the checks by %s (not installed)", what);
    test_skip_part(why);
    return 0;
}

static inline void reader_passes(const char *command, const char *log, const char *what)
{
    size_t length = strlen(command) + strlen(log) + 16;
    char *line = malloc(length);
    REQUIRE(line, "out of memory");
    snprintf(line, length, "%s > '%s' 2>&1", command, log);
    int status = reader_run(line);
    free(line);
    size_t size = 0;
    char *text = (char *)test_read_file(log, &size);
    if (text)
        text[size] = '\0';
    CHECK(status == 0, "%s: %s", what, text ? text : "(no output)");
    free(text);
}

#endif /* PZ_TEST_READERS_H */

/*
 * tests/test_util.h -- the small assertion kit every C test uses.
 *
 * CHECK(cond, fmt, ...) records a failure with file and line and goes on;
 * REQUIRE stops the test. A test's main ends with `return test_finish();`
 * which prints "N passed, M failed" and returns 1 when anything failed.
 * test_skip("why") prints the reason and exits 77 (ctest's SKIP_RETURN_CODE).
 * test_skip_part("why") is for a part that cannot run (its data or a tool
 * missing) while the rest goes on: printed, and test_finish then returns 77
 * unless a check failed, so ctest shows the test as skipped, not passed.
 * REQUIRE_OK(call, ctx) requires a pz_status call to return PZ_OK.
 * test_strdup copies a string (REQUIRE on out of memory).
 *
 * Mesh fixtures and reader checks are in test_meshes.h, scratch directories
 * and whole files in test_files.h.
 *
 * SPDX-License-Identifier: GPL-3.0-or-later
 */
#ifndef PZ_TEST_UTIL_H
#define PZ_TEST_UTIL_H

#include <stdio.h>
#include <stdlib.h>
#include <string.h>

static int test_checks_passed;
static int test_checks_failed;
static int test_check_result; /* the last CHECK's outcome: REQUIRE must not evaluate twice */
static int test_parts_skipped;

#define CHECK(cond, ...)                                                   \
    do {                                                                   \
        if (test_check_result = !!(cond), test_check_result) {                                                        \
            ++test_checks_passed;                                          \
        } else {                                                           \
            ++test_checks_failed;                                          \
            fprintf(stderr, "%s:%d: CHECK failed: %s: ", __FILE__, __LINE__, #cond); \
            fprintf(stderr, __VA_ARGS__);                                  \
            fputc('\n', stderr);                                           \
        }                                                                  \
    } while (0)

#define REQUIRE(cond, ...)                                                 \
    do {                                                                   \
        CHECK(cond, __VA_ARGS__);                                          \
        if (!test_check_result) {                                                     \
            fprintf(stderr, "stopping this test\n");                       \
            exit(test_finish());                                           \
        }                                                                  \
    } while (0)

/* REQUIRE_OK(call, ctx): `call` (evaluated once) must return PZ_OK; the failure
 * message names the call and gives ctx.error (ctx is a pz_ctx, not a pointer).
 * Needs mesh/mesh.h. */
#define REQUIRE_OK(call, ctx) REQUIRE((call) == PZ_OK, "%s: %s", #call, (ctx).error)

static inline int test_finish(void)
{
    printf("%d passed, %d failed", test_checks_passed, test_checks_failed);
    if (test_parts_skipped)
        printf(", %d part%s skipped", test_parts_skipped, test_parts_skipped == 1 ? "" : "s");
    putchar('\n');
    return test_checks_failed ? 1 : test_parts_skipped ? 77 : 0;
}

static inline void test_skip(const char *why)
{
    printf("SKIPPED: %s\n", why);
    exit(77);
}

/* A part of the test cannot run here (why: its data or a tool is missing); the rest goes on. */
static inline void test_skip_part(const char *why)
{
    printf("SKIPPED part: %s\n", why);
    ++test_parts_skipped;
}

/* A malloc'd copy of text (free it); stops the test when out of memory. */
static inline char *test_strdup(const char *text)
{
    char *copy = malloc(strlen(text) + 1);
    REQUIRE(copy != NULL, "out of memory");
    return strcpy(copy, text);
}

/*
 * Directory of the shared real meshes, or NULL when it is not there (the
 * variable unset, or no INVENTORY.md in it: a clone without ../shared).
 */
static inline const char *test_shared_data(void)
{
    const char *dir = getenv("PZ_SHARED_DATA");
    if (!dir || !*dir)
        return NULL;
    char inventory[4096];
    if (snprintf(inventory, sizeof inventory, "%s/INVENTORY.md", dir) >= (int)sizeof inventory)
        return NULL;
    FILE *file = fopen(inventory, "r");
    if (!file)
        return NULL;
    fclose(file);
    return dir;
}

#endif

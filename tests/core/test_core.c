/*
 * tests/core/test_core.c -- the core headers (core/core.h, core/vec.h,
 * core/util.h):
 *  - every status has its own short name and its sysexits exit code
 *    (PZ_ERR_CANCELLED: 130), an unknown one "unknown status" and 70;
 *    pz_version is PZ_VERSION_STRING;
 *  - pz_error returns its status and keeps the message one line (newlines
 *    and carriage returns become spaces), truncated to the buffer;
 *  - pz_ctx_quiet: the child is quiet, has no progress callback, shares the
 *    parent's cancel flag (a flag set later stops the child too);
 *  - pz_cancelled / pz_check_cancel: no flag or a zero flag is OK, a set
 *    flag is PZ_ERR_CANCELLED with "WHAT: cancelled";
 *  - pz_progress passes stage, message and user, clamps the fraction to
 *    0..1, and calls nothing when quiet or without a callback; pz_note
 *    writes "panelize: ..." to stderr unless quiet (stderr captured);
 *  - pz_output: nothing at the final path until commit, the temporary gone
 *    after commit or abort; a stream in error or a path that cannot be
 *    renamed onto (a directory) is PZ_ERR_CREATE naming the path, leaving
 *    nothing; an output in a missing folder is PZ_ERR_CREATE at open;
 *  - pz_vec3_*: known differences, dot and cross products (x cross y = z,
 *    out aliasing either input), norms, normalize (a zero vector stays zero);
 *  - pz_grow: capacities 64, then doubling, contents kept, no change when
 *    there is room, 0 and nothing changed on overflow;
 *  - union-find: the root of every set is its smallest id whatever the order
 *    of the joins (checked against components found by a flood fill).
 *
 * SPDX-License-Identifier: GPL-3.0-or-later
 */
#define _POSIX_C_SOURCE 200809L
#include "core/core.h"
#include "core/heap.h"
#include "core/util.h"
#include "core/vec.h"
#include "test_files.h"

#include <fcntl.h>
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/stat.h>
#include <unistd.h>

/* ---------------------------------------------------------------- status */

static void test_status(void)
{
    const struct {
        pz_status status;
        const char *name;
        int exit_code;
    } table[] = {
        {PZ_OK, "ok", 0},
        {PZ_ERR_USAGE, "usage error", 64},
        {PZ_ERR_DATA, "bad input data", 65},
        {PZ_ERR_INVALID_MESH, "invalid mesh", 65},
        {PZ_ERR_OPEN, "cannot open input", 66},
        {PZ_ERR_CREATE, "cannot create output", 73},
        {PZ_ERR_NOMEM, "out of memory", 70},
        {PZ_ERR_INTERNAL, "internal error", 70},
        {PZ_ERR_CANCELLED, "cancelled", 130},
    };
    size_t count = sizeof table / sizeof table[0];
    for (size_t i = 0; i < count; ++i) {
        const char *name = pz_status_str(table[i].status);
        CHECK(name && strcmp(name, table[i].name) == 0, "status %d is '%s', expected '%s'", (int)table[i].status,
              name ? name : "(null)", table[i].name);
        CHECK(pz_status_exit_code(table[i].status) == table[i].exit_code, "status %d exits %d, expected %d",
              (int)table[i].status, pz_status_exit_code(table[i].status), table[i].exit_code);
        for (size_t j = 0; j < i; ++j)
            CHECK(strcmp(pz_status_str(table[j].status), name) != 0, "statuses %d and %d share the name '%s'",
                  (int)table[j].status, (int)table[i].status, name);
    }
    pz_status unknown = (pz_status)-99;
    CHECK(strcmp(pz_status_str(unknown), "unknown status") == 0, "unknown status named '%s'", pz_status_str(unknown));
    CHECK(pz_status_exit_code(unknown) == 70, "unknown status exits %d", pz_status_exit_code(unknown));
    CHECK(strcmp(pz_version(), PZ_VERSION_STRING) == 0, "pz_version %s, header %s", pz_version(), PZ_VERSION_STRING);
}

/* ---------------------------------------------------------------- errors */

static void test_error(void)
{
    pz_ctx ctx;
    pz_ctx_init(&ctx);
    CHECK(pz_error(&ctx, PZ_ERR_DATA, "%s: line %d: bad face", "a.obj", 7) == PZ_ERR_DATA, "status not returned");
    CHECK(strcmp(ctx.error, "a.obj: line 7: bad face") == 0, "message '%s'", ctx.error);
    CHECK(pz_error(&ctx, PZ_ERR_OPEN, "%s: cannot open", "two\nlines\r\nname") == PZ_ERR_OPEN, "status");
    CHECK(strcmp(ctx.error, "two lines  name: cannot open") == 0, "not one line: '%s'", ctx.error);
    /* A message longer than the buffer is cut, still terminated and still one line. */
    char long_text[3000];
    for (size_t i = 0; i < sizeof long_text - 1; ++i)
        long_text[i] = i % 100 == 99 ? '\n' : 'x';
    long_text[sizeof long_text - 1] = '\0';
    pz_error(&ctx, PZ_ERR_INTERNAL, "%s", long_text);
    CHECK(strlen(ctx.error) == sizeof ctx.error - 1 && !strchr(ctx.error, '\n'), "long message: %zu characters",
          strlen(ctx.error));
    CHECK(pz_error(NULL, PZ_ERR_NOMEM, "nowhere") == PZ_ERR_NOMEM, "a NULL context must still return the status");
}

/* ---------------------------------------------------------------- progress, notes, cancellation */

typedef struct progress_log {
    int calls;
    char stage[32], message[256];
    double fraction;
} progress_log;

static void record_progress(void *user, const char *stage, double fraction, const char *message)
{
    progress_log *log = user;
    ++log->calls;
    snprintf(log->stage, sizeof log->stage, "%s", stage);
    snprintf(log->message, sizeof log->message, "%s", message);
    log->fraction = fraction;
}

static void test_progress(void)
{
    progress_log log = {0};
    pz_ctx ctx;
    pz_ctx_init(&ctx);
    ctx.progress = record_progress;
    ctx.progress_user = &log;
    pz_progress(&ctx, "segment", 0.25, "%d panels", 3);
    CHECK(log.calls == 1 && strcmp(log.stage, "segment") == 0 && strcmp(log.message, "3 panels") == 0 &&
              log.fraction == 0.25,
          "progress: %d calls, '%s' %g '%s'", log.calls, log.stage, log.fraction, log.message);
    ctx.progress_last = 0; /* reports never go back: start again to see the clamp */
    pz_progress(&ctx, "field", -0.5, "before");
    CHECK(log.calls == 2 && log.fraction == 0.0, "fraction -0.5 passed as %g", log.fraction);
    pz_progress(&ctx, "field", 1.5, "after");
    CHECK(log.calls == 3 && log.fraction == 1.0, "fraction 1.5 passed as %g", log.fraction);
    /* A stage's own 0..1 mapped into its part of the whole; a later report below an earlier one is held. */
    ctx.progress_last = 0;
    pz_progress_range(&ctx, 0.2, 0.7);
    pz_progress(&ctx, "segment", 0.5, "half");
    CHECK(fabs(log.fraction - 0.45) < 1e-12, "0.5 of 0.2..0.7 passed as %g", log.fraction);
    pz_progress(&ctx, "segment", 0.1, "again");
    CHECK(fabs(log.fraction - 0.45) < 1e-12, "a report went back to %g", log.fraction);
    pz_progress_range(&ctx, 0, 0);
    pz_progress(&ctx, "done", 1.0, "all");
    CHECK(log.fraction == 1.0, "without a range 1 passed as %g", log.fraction);
    log.calls = 3;
    /* quiet silences the notes on stderr, not a callback the caller set (a binding shows its own bar). */
    ctx.quiet = 1;
    pz_progress(&ctx, "field", 0.5, "quiet");
    CHECK(log.calls == 4, "a quiet context dropped the caller's progress");
    ctx.quiet = 0;
    ctx.progress = NULL;
    pz_progress(&ctx, "field", 0.5, "no callback"); /* must simply do nothing */
    pz_progress(NULL, "field", 0.5, "no context");
    CHECK(log.calls == 4, "progress reported without a callback");
}

static void test_quiet_and_cancel(void)
{
    int stop = 0;
    progress_log log = {0};
    pz_ctx parent;
    pz_ctx_init(&parent);
    parent.verbose = 1;
    parent.progress = record_progress;
    parent.progress_user = &log;
    parent.cancel = &stop;
    pz_ctx child;
    memset(&child, 0x5a, sizeof child); /* whatever was there before */
    pz_ctx_quiet(&parent, &child);
    CHECK(child.quiet == 1 && child.verbose == 0 && child.progress == NULL && child.error[0] == '\0',
          "quiet child: quiet %d verbose %d progress %p", child.quiet, child.verbose, (void *)child.progress);
    CHECK(child.cancel == &stop, "the quiet child lost the cancel flag");
    pz_progress(&child, "inner", 0.5, "hidden");
    CHECK(log.calls == 0, "the quiet child reported progress");

    CHECK(!pz_cancelled(&parent) && !pz_cancelled(&child) && !pz_cancelled(NULL), "cancelled with the flag at 0");
    CHECK(pz_check_cancel(&child, "segment") == PZ_OK, "check_cancel with the flag at 0");
    stop = 1; /* set after the child was made: the child must see it */
    CHECK(pz_cancelled(&parent) && pz_cancelled(&child), "the flag set is not seen");
    CHECK(pz_check_cancel(&child, "segment") == PZ_ERR_CANCELLED && strcmp(child.error, "segment: cancelled") == 0,
          "check_cancel: '%s'", child.error);
    pz_ctx orphan;
    pz_ctx_quiet(NULL, &orphan);
    CHECK(orphan.quiet == 1 && orphan.cancel == NULL && pz_check_cancel(&orphan, "x") == PZ_OK,
          "quiet child of no parent");
    pz_ctx plain;
    pz_ctx_init(&plain);
    CHECK(pz_check_cancel(&plain, "x") == PZ_OK, "no flag at all is not a cancellation");
}

/* What pz_note writes to stderr with this context, captured through a file. */
static char *note_output(pz_ctx *ctx)
{
    char path[512];
    test_temp_path(path, sizeof path, "stderr.txt");
    fflush(stderr);
    int saved = dup(STDERR_FILENO);
    int file = open(path, O_WRONLY | O_CREAT | O_TRUNC, 0600);
    REQUIRE(saved >= 0 && file >= 0, "cannot capture stderr");
    dup2(file, STDERR_FILENO);
    close(file);
    pz_note(ctx, "%d notes", 2);
    fflush(stderr);
    dup2(saved, STDERR_FILENO);
    close(saved);
    size_t size = 0;
    char *text = (char *)test_read_file(path, &size);
    REQUIRE(text, "cannot read %s", path);
    text[size] = '\0';
    unlink(path);
    return text;
}

static void test_note(void)
{
    pz_ctx ctx;
    pz_ctx_init(&ctx);
    char *text = note_output(&ctx);
    CHECK(strcmp(text, "panelize: 2 notes\n") == 0, "note: '%s'", text);
    free(text);
    pz_ctx quiet;
    pz_ctx_quiet(&ctx, &quiet);
    text = note_output(&quiet);
    CHECK(text[0] == '\0', "a quiet context wrote '%s'", text);
    free(text);
}

/* ---------------------------------------------------------------- atomic output */

static int exists(const char *path)
{
    struct stat info;
    return stat(path, &info) == 0;
}

/* The files in the scratch directory besides `keep` (0 when there are none). */
static int strays(const char *keep)
{
    DIR *dir = opendir(test_temp_dir);
    REQUIRE(dir, "cannot list %s", test_temp_dir);
    int count = 0;
    for (struct dirent *entry; (entry = readdir(dir));)
        count += strcmp(entry->d_name, ".") != 0 && strcmp(entry->d_name, "..") != 0 &&
                 (!keep || strcmp(entry->d_name, keep) != 0);
    closedir(dir);
    return count;
}

static void test_output(void)
{
    pz_ctx ctx;
    pz_ctx_init(&ctx);
    char path[512];
    test_temp_path(path, sizeof path, "out.txt");
    pz_output out;
    REQUIRE_OK(pz_output_open(&out, path, "wb", &ctx), ctx);
    fputs("hello\n", out.file);
    CHECK(!exists(path), "the final path exists before the commit");
    CHECK(out.tmp_path && exists(out.tmp_path) && strcmp(out.path, path) == 0, "no temporary next to %s", path);
    REQUIRE_OK(pz_output_commit(&out, &ctx), ctx);
    size_t size = 0;
    char *text = (char *)test_read_file(path, &size);
    CHECK(text && size == 6 && memcmp(text, "hello\n", 6) == 0, "committed file holds %zu bytes", size);
    free(text);
    CHECK(strays("out.txt") == 0 && out.file == NULL && out.path == NULL && out.tmp_path == NULL,
          "commit left a temporary or owned memory");

    /* Abort: nothing at the final path, no temporary. */
    char aborted[512];
    test_temp_path(aborted, sizeof aborted, "aborted.txt");
    REQUIRE_OK(pz_output_open(&out, aborted, "wb", &ctx), ctx);
    fputs("never", out.file);
    pz_output_abort(&out);
    CHECK(!exists(aborted) && strays("out.txt") == 0, "abort left files behind");

    /* A stream in error (read from a write-only stream) fails the commit with PZ_ERR_CREATE, nothing left. */
    char broken[512];
    test_temp_path(broken, sizeof broken, "broken.txt");
    REQUIRE_OK(pz_output_open(&out, broken, "wb", &ctx), ctx);
    fputs("half", out.file);
    (void)fgetc(out.file);
    REQUIRE(ferror(out.file), "could not put the stream in error");
    CHECK(pz_output_commit(&out, &ctx) == PZ_ERR_CREATE && strstr(ctx.error, broken) && !strchr(ctx.error, '\n'),
          "commit of a stream in error: '%s'", ctx.error);
    CHECK(!exists(broken) && strays("out.txt") == 0, "a failed commit left files behind");

    /* The final path is a folder with a file in it: the rename fails, PZ_ERR_CREATE naming it. */
    char folder[512], inside[600];
    test_temp_path(folder, sizeof folder, "folder");
    REQUIRE(mkdir(folder, 0700) == 0, "mkdir %s", folder);
    snprintf(inside, sizeof inside, "%s/keep", folder);
    test_write_file(inside, "k", 1);
    REQUIRE_OK(pz_output_open(&out, folder, "wb", &ctx), ctx);
    fputs("data", out.file);
    CHECK(pz_output_commit(&out, &ctx) == PZ_ERR_CREATE && strstr(ctx.error, folder),
          "commit onto a folder: '%s'", ctx.error);
    struct stat info;
    CHECK(stat(folder, &info) == 0 && S_ISDIR(info.st_mode) && exists(inside), "the folder was replaced");
    CHECK(strays(NULL) == 2, "a failed rename left a temporary (%d entries)", strays(NULL));
    test_remove_tree(folder);

    /* A folder that does not exist: PZ_ERR_CREATE at open, nothing owned. */
    char missing[600];
    snprintf(missing, sizeof missing, "%s/no/such/out.txt", test_temp_dir);
    CHECK(pz_output_open(&out, missing, "wb", &ctx) == PZ_ERR_CREATE && strstr(ctx.error, missing),
          "open in a missing folder: '%s'", ctx.error);
    CHECK(out.file == NULL && out.path == NULL && out.tmp_path == NULL, "a failed open kept something");
}

/* ---------------------------------------------------------------- vectors */

static int same3(const double *a, double x, double y, double z)
{
    return fabs(a[0] - x) < 1e-12 && fabs(a[1] - y) < 1e-12 && fabs(a[2] - z) < 1e-12;
}

static void test_vec3(void)
{
    const double x[3] = {1, 0, 0}, y[3] = {0, 1, 0};
    double out[3];
    pz_vec3_cross(x, y, out);
    CHECK(same3(out, 0, 0, 1), "x cross y = (%g %g %g)", out[0], out[1], out[2]);
    pz_vec3_cross(y, x, out);
    CHECK(same3(out, 0, 0, -1), "y cross x = (%g %g %g)", out[0], out[1], out[2]);
    double a[3] = {1, 2, 3}, b[3] = {4, 5, 6};
    pz_vec3_cross(a, b, out);
    CHECK(same3(out, -3, 6, -3), "(1 2 3) x (4 5 6) = (%g %g %g)", out[0], out[1], out[2]);
    pz_vec3_cross(a, b, a); /* out aliasing the first input */
    CHECK(same3(a, -3, 6, -3), "cross into a = (%g %g %g)", a[0], a[1], a[2]);
    a[0] = 1, a[1] = 2, a[2] = 3;
    pz_vec3_cross(a, b, b); /* and the second */
    CHECK(same3(b, -3, 6, -3), "cross into b = (%g %g %g)", b[0], b[1], b[2]);
    b[0] = 4, b[1] = 5, b[2] = 6;
    CHECK(pz_vec3_dot(a, b) == 32.0, "dot %g", pz_vec3_dot(a, b));
    pz_vec3_sub(b, a, out);
    CHECK(same3(out, 3, 3, 3), "b - a = (%g %g %g)", out[0], out[1], out[2]);
    pz_vec3_sub(a, b, a);
    CHECK(same3(a, -3, -3, -3), "a - b into a = (%g %g %g)", a[0], a[1], a[2]);
    double v[3] = {3, 4, 12};
    CHECK(pz_vec3_norm(v) == 13.0, "|(3 4 12)| = %g", pz_vec3_norm(v));
    CHECK(pz_vec3_normalize(v) == 13.0 && same3(v, 3.0 / 13, 4.0 / 13, 12.0 / 13), "normalized (%g %g %g)", v[0],
          v[1], v[2]);
    double zero[3] = {0, 0, 0};
    CHECK(pz_vec3_normalize(zero) == 0.0 && same3(zero, 0, 0, 0), "a zero vector became (%g %g %g)", zero[0],
          zero[1], zero[2]);
    CHECK(fabs(PZ_PI - acos(-1.0)) < 1e-15, "PZ_PI %.17g", PZ_PI);
}

/* ---------------------------------------------------------------- containers */

static void test_grow(void)
{
    int32_t *data = NULL;
    size_t capacity = 0;
    REQUIRE(pz_grow((void **)&data, &capacity, 1, sizeof *data) && data && capacity == 64, "first growth: %zu",
            capacity);
    for (int32_t i = 0; i < 64; ++i)
        data[i] = 3 * i;
    int32_t *before = data;
    CHECK(pz_grow((void **)&data, &capacity, 64, sizeof *data) && data == before && capacity == 64,
          "room enough, yet it changed: %zu", capacity);
    CHECK(pz_grow((void **)&data, &capacity, 300, sizeof *data) && capacity == 512, "growth to 300: %zu", capacity);
    int kept = 1;
    for (int32_t i = 0; i < 64; ++i)
        kept &= data[i] == 3 * i;
    CHECK(kept, "growth lost the contents");
    data[511] = 7; /* the whole capacity is usable (ASan would catch it otherwise) */
    before = data;
    size_t old_capacity = capacity;
    CHECK(!pz_grow((void **)&data, &capacity, SIZE_MAX / 2, 16) && data == before && capacity == old_capacity,
          "an overflowing size was accepted");
    /* A count past 2^63: doubling the capacity would wrap to 0 and loop for ever; it must be refused. */
    CHECK(!pz_grow((void **)&data, &capacity, SIZE_MAX - 5, 1) && data == before && capacity == old_capacity,
          "a count past 2^63 was accepted");
    free(data);
}

enum { SET_IDS = 40 };

/* Component labels of the join graph by flood fill: the smallest id of each component. */
static void components_by_fill(const int32_t (*joins)[2], int count, int32_t *label)
{
    for (int32_t i = 0; i < SET_IDS; ++i)
        label[i] = -1;
    for (int32_t start = 0; start < SET_IDS; ++start) {
        if (label[start] >= 0)
            continue;
        label[start] = start; /* ids visited in increasing order: start is its component's smallest */
        for (int changed = 1; changed;) {
            changed = 0;
            for (int j = 0; j < count; ++j) {
                int32_t a = joins[j][0], b = joins[j][1];
                if ((label[a] == start) != (label[b] == start)) {
                    label[a] = label[b] = start;
                    changed = 1;
                }
            }
        }
    }
}

static void test_union_find(void)
{
    int32_t joins[30][2];
    unsigned state = 12345u;
    for (int j = 0; j < 30; ++j)
        for (int k = 0; k < 2; ++k) {
            state = state * 1103515245u + 12345u;
            joins[j][k] = (int32_t)((state >> 8) % SET_IDS);
        }
    int32_t expected[SET_IDS];
    components_by_fill((const int32_t(*)[2])joins, 30, expected);
    for (int order = 0; order < 3; ++order) {
        int32_t parent[SET_IDS];
        for (int32_t i = 0; i < SET_IDS; ++i)
            parent[i] = i;
        for (int j = 0; j < 30; ++j) {
            int step = order == 0 ? j : order == 1 ? 29 - j : (j * 7) % 30; /* forward, backward, shuffled */
            int32_t a = joins[step][order == 2], b = joins[step][order != 2];
            pz_union_find_join(parent, a, b);
        }
        int32_t wrong = 0;
        for (int32_t i = 0; i < SET_IDS; ++i)
            wrong += pz_union_find_root(parent, i) != expected[i];
        CHECK(wrong == 0, "join order %d: %d ids have a root other than their set's smallest id", order, (int)wrong);
        wrong = 0;
        for (int32_t i = 0; i < SET_IDS; ++i)
            wrong += parent[pz_union_find_root(parent, i)] != pz_union_find_root(parent, i);
        CHECK(wrong == 0, "join order %d: a root is not its own parent", order);
    }
}

/* The heap pops in (key, item) order whatever the pushes' order, ties included; it grows past 256. */
static void test_heap(void)
{
    enum { COUNT = 1000 };
    pz_heap heap = {0};
    unsigned state = 12345;
    int pushed = 1;
    for (int i = 0; i < COUNT; ++i) {
        state = state * 1103515245u + 12345u;
        double key = (double)((state >> 16) % 37); /* many equal keys */
        pushed &= pz_heap_push(&heap, key, (int32_t)((state >> 8) % 500));
    }
    CHECK(pushed && heap.count == COUNT && heap.capacity >= COUNT, "pushes: count %zu capacity %zu", heap.count,
          heap.capacity);
    double key, last_key = -1;
    int32_t item, last_item = -1;
    int ordered = 1, popped = 0;
    while (pz_heap_pop(&heap, &key, &item)) {
        ordered &= key > last_key || (key == last_key && item >= last_item);
        last_key = key, last_item = item, ++popped;
    }
    CHECK(ordered && popped == COUNT, "pops out of (key, item) order or missing: %d", popped);
    CHECK(!pz_heap_pop(&heap, NULL, NULL), "an empty heap popped");
    pz_heap_push(&heap, 2.0, 7);
    pz_heap_clear(&heap);
    CHECK(heap.count == 0 && !pz_heap_pop(&heap, &key, &item), "clear left entries");
    pz_heap_free(&heap);
    CHECK(!heap.keys && !heap.items && heap.capacity == 0, "free left memory");
}

int main(void)
{
    test_temp_dir_create("pz_core");
    test_status();
    test_error();
    test_progress();
    test_quiet_and_cancel();
    test_note();
    test_output();
    test_vec3();
    test_grow();
    test_union_find();
    test_heap();
    CHECK(test_temp_dir_remove() == 0, "cannot remove %s", test_temp_dir);
    return test_finish();
}

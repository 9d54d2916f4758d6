/*
 * core/core.h -- the smallest public layer every stage stands on: status
 * codes, the context (errors, notes, progress, cancellation), timing and
 * atomic output files. It depends on nothing but the C library.
 *
 * Conventions (docs/architecture.md):
 *  - Every function that can fail takes a `pz_ctx *` last and returns a
 *    pz_status. On failure it writes a one-line message into the context,
 *    leaves every `T **out` at NULL and leaks nothing.
 *  - A function that allocates takes `T **out`; the caller owns the result and
 *    frees it with the matching `pz_*_free(&p)`, which accepts NULL and sets
 *    the pointer to NULL.
 *
 * SPDX-License-Identifier: GPL-3.0-or-later
 */
#ifndef PZ_CORE_H
#define PZ_CORE_H

#include <stddef.h>
#include <stdint.h>
#include <stdio.h>

/* PZ_VERSION_MAJOR, _MINOR, _PATCH and PZ_VERSION_STRING: generated from CMakeLists.txt's project(). */
#include "core/version.h"

#ifdef __cplusplus
extern "C" {
#endif

/** The library's version at run time ("0.1.0"), to compare with PZ_VERSION_STRING at build time. */
const char *pz_version(void);

/* ------------------------------------------------------------------------ */
/* Status and context                                                        */
/* ------------------------------------------------------------------------ */

/** One status enum for every call: 0 is success, negative values are errors. */
typedef enum pz_status {
    PZ_OK = 0,
    PZ_ERR_USAGE = -1,         /* bad command line or impossible parameter   (exit 64) */
    PZ_ERR_DATA = -2,          /* malformed file or mismatched poses         (exit 65) */
    PZ_ERR_INVALID_MESH = -3,  /* parses, but fails validation               (exit 65) */
    PZ_ERR_OPEN = -4,          /* cannot open or read an input               (exit 66) */
    PZ_ERR_CREATE = -5,        /* cannot create or write an output           (exit 73) */
    PZ_ERR_NOMEM = -6,         /* out of memory                              (exit 70) */
    PZ_ERR_INTERNAL = -7,      /* a bug or a failed numerical step           (exit 70) */
    PZ_ERR_CANCELLED = -8      /* stopped through pz_ctx.cancel              (exit 130) */
} pz_status;

/** Short name of a status ("ok", "usage error", ...). Never NULL. */
const char *pz_status_str(pz_status status);

/** The process exit code for a status (0, 64, 65, 66, 70, 73 from sysexits.h; 130 when cancelled). */
int pz_status_exit_code(pz_status status);

/**
 * Progress of a long call: `stage` is a short name ("prepare", "field",
 * "segment", "flatten", "export"), `fraction` the share of the whole call
 * done so far (0..1, never decreasing within one call), `message` one short
 * line (may be empty). Called on the calling thread, never from inside a
 * parallel region.
 */
typedef void (*pz_progress_fn)(void *user, const char *stage, double fraction, const char *message);

/**
 * The context passed last to every fallible call. Zero-initialize it (or call
 * pz_ctx_init). It holds the last error message, the logging switches, the
 * progress callback and the cancellation flag; it owns no heap memory, so it
 * needs no free.
 *
 * Cancellation: point `cancel` at an int the caller owns (a signal handler or
 * another thread sets it to non-zero). Long calls check it between steps
 * (pz_cancelled) and return PZ_ERR_CANCELLED, leaving every output at NULL.
 */
typedef struct pz_ctx {
    char error[1024];  /* last error, one line, "FILE: problem" */
    int quiet;         /* 1: pz_log/pz_note print nothing */
    int verbose;       /* 1: pz_debug prints too */
    pz_progress_fn progress;        /* may be NULL */
    void *progress_user;            /* passed to progress */
    double progress_from, progress_to; /* the part of the whole that a stage's 0..1 maps to (both 0: all of it);
                                          a pipeline sets them around each stage it calls */
    double progress_last;           /* the last fraction reported: reports never go back */
    volatile const int *cancel;     /* may be NULL; non-zero asks the running call to stop */
} pz_ctx;

void pz_ctx_init(pz_ctx *ctx);

/**
 * A quiet context for an inner call whose notes and errors the caller does
 * not want printed: no notes, no progress, but the same cancellation flag as
 * `parent` (may be NULL), so that a cancelled run stops inside it too.
 */
void pz_ctx_quiet(const pz_ctx *parent, pz_ctx *child);

/** Maps the progress of the stage called next into from .. to of the whole (see pz_progress). */
void pz_progress_range(pz_ctx *ctx, double from, double to);

/** 1 when the caller asked the running call to stop (ctx->cancel set). */
int pz_cancelled(const pz_ctx *ctx);

/**
 * PZ_ERR_CANCELLED with the message "WHAT: cancelled" when cancellation was
 * asked for, else PZ_OK: `if ((status = pz_check_cancel(ctx, "segment"))) return status;`.
 */
pz_status pz_check_cancel(pz_ctx *ctx, const char *what);

/**
 * Reports progress through ctx->progress (nothing when it is NULL; ctx->quiet
 * silences notes, not this). `fraction` (clamped to 0..1) is the stage's own;
 * it is mapped into ctx->progress_from .. progress_to when those are set, and
 * never reported below an earlier report (a stage run again, as the
 * segmentation's verdict rounds are, does not move the bar back).
 */
void pz_progress(pz_ctx *ctx, const char *stage, double fraction, const char *fmt, ...)
#if defined(__GNUC__)
    __attribute__((format(printf, 4, 5)))
#endif
    ;

/**
 * Records a one-line error in ctx->error (printf format; newlines are replaced
 * by spaces) and returns `status` so a caller can write
 * `return pz_error(ctx, PZ_ERR_DATA, "%s: line %d: bad face", path, line);`.
 */
pz_status pz_error(pz_ctx *ctx, pz_status status, const char *fmt, ...)
#if defined(__GNUC__)
    __attribute__((format(printf, 3, 4)))
#endif
    ;

/** Progress and notes on stderr ("panelize: ..."), silenced by ctx->quiet. */
void pz_note(pz_ctx *ctx, const char *fmt, ...)
#if defined(__GNUC__)
    __attribute__((format(printf, 2, 3)))
#endif
    ;

/** Wall-clock seconds from a monotonic clock, for timings. */
double pz_seconds(void);

/** Milliseconds between two pz_seconds() readings, rounded to microseconds (report figures). */
double pz_elapsed_ms(double start, double end);

/** value rounded to `decimals` decimals, so that JSON numbers print short (non-finite values as they are). */
double pz_round(double value, int decimals);

/* ------------------------------------------------------------------------ */
/* Atomic output files                                                       */
/* ------------------------------------------------------------------------ */

/**
 * Output is written to "PATH.tmp-PID" and renamed to PATH only on success, so
 * a failed run leaves nothing behind.
 *   pz_output out; FILE *f;
 *   if ((st = pz_output_open(&out, path, "wb", ctx))) return st;
 *   ... write to out.file ...
 *   return pz_output_commit(&out, ctx);   (or pz_output_abort(&out) on error)
 * pz_output_commit flushes and syncs the file, checks write errors (ferror,
 * fsync, fclose) and reports
 * PZ_ERR_CREATE naming PATH. pz_output_abort closes and removes the temporary.
 */
typedef struct pz_output {
    FILE *file;
    char *path;      /* final path (owned) */
    char *tmp_path;  /* temporary path (owned) */
} pz_output;

pz_status pz_output_open(pz_output *out, const char *path, const char *mode, pz_ctx *ctx);

/**
 * Opens an input file for reading ("rb"): only a regular file. A directory, a
 * FIFO, a device or a socket is PZ_ERR_OPEN naming it at once (a FIFO would
 * block for ever, /dev/zero never end); a missing or unreadable file is
 * PZ_ERR_OPEN with the system's reason. *out is the caller's to fclose.
 */
pz_status pz_input_open(const char *path, FILE **out, pz_ctx *ctx);
pz_status pz_output_commit(pz_output *out, pz_ctx *ctx);
void pz_output_abort(pz_output *out);

#ifdef __cplusplus
}
#endif

#endif /* PZ_CORE_H */

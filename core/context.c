/*
 * core/context.c -- status codes, the error context, logging, progress,
 * cancellation, timing and atomic output files.
 *
 * SPDX-License-Identifier: GPL-3.0-or-later
 */
#define _POSIX_C_SOURCE 200809L
#include "core/core.h"

#include <errno.h>
#include <fcntl.h>
#include <math.h>
#include <stdarg.h>
#include <stdlib.h>
#include <string.h>
#include <sys/stat.h>
#include <time.h>
#include <unistd.h>

const char *pz_status_str(pz_status status)
{
    switch (status) {
    case PZ_OK: return "ok";
    case PZ_ERR_USAGE: return "usage error";
    case PZ_ERR_DATA: return "bad input data";
    case PZ_ERR_INVALID_MESH: return "invalid mesh";
    case PZ_ERR_OPEN: return "cannot open input";
    case PZ_ERR_CREATE: return "cannot create output";
    case PZ_ERR_NOMEM: return "out of memory";
    case PZ_ERR_INTERNAL: return "internal error";
    case PZ_ERR_CANCELLED: return "cancelled";
    }
    return "unknown status";
}

int pz_status_exit_code(pz_status status)
{
    switch (status) {
    case PZ_OK: return 0;
    case PZ_ERR_USAGE: return 64;          /* EX_USAGE */
    case PZ_ERR_DATA:
    case PZ_ERR_INVALID_MESH: return 65;   /* EX_DATAERR */
    case PZ_ERR_OPEN: return 66;           /* EX_NOINPUT */
    case PZ_ERR_CREATE: return 73;         /* EX_CANTCREAT */
    case PZ_ERR_NOMEM:
    case PZ_ERR_INTERNAL: return 70;       /* EX_SOFTWARE */
    case PZ_ERR_CANCELLED: return 130;     /* 128 + SIGINT, as shells report an interrupted command */
    }
    return 70;
}

const char *pz_version(void)
{
    return PZ_VERSION_STRING;
}

void pz_ctx_init(pz_ctx *ctx)
{
    memset(ctx, 0, sizeof *ctx);
}

void pz_ctx_quiet(const pz_ctx *parent, pz_ctx *child)
{
    memset(child, 0, sizeof *child);
    child->quiet = 1;
    child->cancel = parent ? parent->cancel : NULL;
}

void pz_progress_range(pz_ctx *ctx, double from, double to)
{
    if (!ctx)
        return;
    ctx->progress_from = from;
    ctx->progress_to = to;
}

int pz_cancelled(const pz_ctx *ctx)
{
    return ctx && ctx->cancel && *ctx->cancel;
}

pz_status pz_check_cancel(pz_ctx *ctx, const char *what)
{
    if (!pz_cancelled(ctx))
        return PZ_OK;
    return pz_error(ctx, PZ_ERR_CANCELLED, "%s: cancelled", what);
}

void pz_progress(pz_ctx *ctx, const char *stage, double fraction, const char *fmt, ...)
{
    if (!ctx || !ctx->progress)
        return;
    char message[256];
    va_list args;
    va_start(args, fmt);
    vsnprintf(message, sizeof message, fmt, args);
    va_end(args);
    if (!(fraction >= 0))
        fraction = 0;
    if (fraction > 1)
        fraction = 1;
    if (ctx->progress_to > ctx->progress_from)
        fraction = ctx->progress_from + (ctx->progress_to - ctx->progress_from) * fraction;
    if (fraction < ctx->progress_last)
        fraction = ctx->progress_last;
    ctx->progress_last = fraction;
    ctx->progress(ctx->progress_user, stage, fraction, message);
}

pz_status pz_error(pz_ctx *ctx, pz_status status, const char *fmt, ...)
{
    if (!ctx)
        return status;
    va_list args;
    va_start(args, fmt);
    vsnprintf(ctx->error, sizeof ctx->error, fmt, args);
    va_end(args);
    /* The message must stay one line whatever a file name or a parser put in it. */
    for (char *c = ctx->error; *c; ++c)
        if (*c == '\n' || *c == '\r')
            *c = ' ';
    return status;
}

void pz_note(pz_ctx *ctx, const char *fmt, ...)
{
    if (ctx && ctx->quiet)
        return;
    va_list args;
    va_start(args, fmt);
    /* A progress line may be drawn on the terminal (ctx->progress is only set there): clear it first. */
    if (ctx && ctx->progress)
        fputs("\r\033[K", stderr);
    fputs("panelize: ", stderr);
    vfprintf(stderr, fmt, args);
    fputc('\n', stderr);
    va_end(args);
}

double pz_seconds(void)
{
    struct timespec now;
    clock_gettime(CLOCK_MONOTONIC, &now);
    return (double)now.tv_sec + 1e-9 * (double)now.tv_nsec;
}

double pz_elapsed_ms(double start, double end)
{
    return pz_round((end - start) * 1000.0, 3);
}

double pz_round(double value, int decimals)
{
    double scale = pow(10.0, decimals);
    if (!isfinite(value) || fabs(value) * scale > 1e15)
        return value; /* nothing to shorten, and value * scale could overflow */
    return round(value * scale) / scale;
}

static char *duplicate_string(const char *text)
{
    size_t length = strlen(text);
    char *copy = malloc(length + 1);
    if (copy)
        memcpy(copy, text, length + 1);
    return copy;
}

pz_status pz_input_open(const char *path, FILE **out, pz_ctx *ctx)
{
    *out = NULL;
    /* O_NONBLOCK: opening a FIFO with no writer must not wait; it is refused below. */
    int fd = open(path, O_RDONLY | O_NONBLOCK | O_CLOEXEC);
    if (fd < 0)
        return pz_error(ctx, PZ_ERR_OPEN, "%s: cannot open: %s", path, strerror(errno));
    struct stat info;
    const char *problem = NULL;
    if (fstat(fd, &info) != 0)
        problem = strerror(errno);
    else if (S_ISDIR(info.st_mode))
        problem = strerror(EISDIR);
    else if (!S_ISREG(info.st_mode))
        problem = "not a regular file (a pipe, a device or a socket)";
    if (!problem && fcntl(fd, F_SETFL, fcntl(fd, F_GETFL) & ~O_NONBLOCK) != 0)
        problem = strerror(errno);
    FILE *file = problem ? NULL : fdopen(fd, "rb");
    if (!file) {
        close(fd);
        return pz_error(ctx, PZ_ERR_OPEN, "%s: cannot open: %s", path, problem ? problem : strerror(errno));
    }
    *out = file;
    return PZ_OK;
}

pz_status pz_output_open(pz_output *out, const char *path, const char *mode, pz_ctx *ctx)
{
    memset(out, 0, sizeof *out);
    size_t tmp_size = strlen(path) + 32;
    out->path = duplicate_string(path);
    out->tmp_path = malloc(tmp_size);
    if (!out->path || !out->tmp_path) {
        free(out->path);
        free(out->tmp_path);
        memset(out, 0, sizeof *out);
        return pz_error(ctx, PZ_ERR_NOMEM, "%s: out of memory", path);
    }
    snprintf(out->tmp_path, tmp_size, "%s.tmp-%ld", path, (long)getpid());
    out->file = fopen(out->tmp_path, mode);
    if (!out->file) {
        int saved = errno;
        free(out->path);
        free(out->tmp_path);
        memset(out, 0, sizeof *out);
        return pz_error(ctx, PZ_ERR_CREATE, "%s: cannot create: %s", path, strerror(saved));
    }
    return PZ_OK;
}

pz_status pz_output_commit(pz_output *out, pz_ctx *ctx)
{
    int failed = ferror(out->file);
    int saved = errno;
    /* On the disk before the rename, so a crash leaves the old file or the whole new one. */
    if (!failed && (fflush(out->file) != 0 || (fsync(fileno(out->file)) != 0 && errno != EINVAL))) {
        failed = 1;
        saved = errno;
    }
    if (fclose(out->file) != 0 && !failed) {
        failed = 1;
        saved = errno;
    }
    out->file = NULL;
    if (!failed && rename(out->tmp_path, out->path) != 0) {
        failed = 1;
        saved = errno;
    }
    pz_status status = PZ_OK;
    if (failed) {
        status = pz_error(ctx, PZ_ERR_CREATE, "%s: cannot write: %s", out->path, strerror(saved));
        remove(out->tmp_path);
    }
    free(out->path);
    free(out->tmp_path);
    out->path = out->tmp_path = NULL;
    return status;
}

void pz_output_abort(pz_output *out)
{
    if (out->file) {
        fclose(out->file);
        out->file = NULL;
    }
    if (out->tmp_path)
        remove(out->tmp_path);
    free(out->path);
    free(out->tmp_path);
    out->path = out->tmp_path = NULL;
}

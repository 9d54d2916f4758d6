/*
 * batch/run.c -- the garments of one shard in worker processes
 * (docs/batch.md, "How a batch runs").
 *
 * The batch process only schedules: it forks one worker per garment, at most
 * `jobs` at once, and waits for them in a poll loop. A worker sets its
 * OpenMP threads, runs the caller's work (pz_batch_run_garment through the
 * command line), writes the garment's marker batch.json last (its summary
 * row, atomically) and sends the outcome through a pipe, one write smaller
 * than PIPE_BUF. A worker that dies (a crash, the kernel's OOM killer) or
 * outlives --timeout (then killed) is recorded from its wait status; the
 * other garments go on. Workers die with the batch (PR_SET_PDEATHSIG), so a
 * killed batch leaves no garment running; a garment whose marker is missing
 * is run again by --resume. The peak memory of each garment is its worker's
 * ru_maxrss.
 *
 * SPDX-License-Identifier: GPL-3.0-or-later
 */
#define _GNU_SOURCE
#include "batch/internal.h"

#include <errno.h>
#include <limits.h>
#include <omp.h>
#include <poll.h>
#include <sched.h>
#include <signal.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/prctl.h>
#include <sys/resource.h>
#include <sys/stat.h>
#include <sys/wait.h>
#include <unistd.h>

#define POLL_MS 100              /* the loop's longest sleep: time-outs and Ctrl-C act within it */
#define PROGRESS_EVERY_S 0.5     /* the progress line's redraws */
#define EXIT_TIMEOUT 124         /* a garment's exit code when killed for --timeout (as timeout(1)) */

/* What a worker sends back (one write: atomic on a pipe). */
typedef struct report {
    pz_batch_outcome outcome;
} report;
_Static_assert(sizeof(report) <= PIPE_BUF, "a worker's report must fit one atomic pipe write");

typedef struct worker {
    pid_t pid;          /* 0: a free slot */
    int fd;             /* the pipe's read end */
    int32_t slot;       /* the garment's index in the batch's selection */
    double start;
    int timed_out;
} worker;

typedef struct batch {
    const pz_batch_list *list;
    const pz_batch_options *options;
    int32_t *selected;           /* the shard's garments (indices into list), in the stable order */
    int32_t count;
    cJSON **rows;                /* count: each garment's row once known */
    int32_t next;                /* the next selected garment to start */
    int32_t finished, failed, resumed;
    worker *workers;
    int jobs, threads, running, stopping;
    double start, last_draw;
    int drawn;
} batch;

/* ---------------------------------------------------------------- the worker */

static char *garment_folder(const batch *b, int32_t slot)
{
    return bt_join(b->options->outroot, b->list->garments[b->selected[slot]].name);
}

/* The outcome's state: a written pattern is "ok" unless --strict and its goals are not met. */
static int strict_failure(const batch *b, const pz_batch_outcome *outcome)
{
    return b->options->strict && outcome->goals_judged && !outcome->goals_met;
}

/* Runs one garment in the forked child and never returns. */
static void run_worker(const batch *b, int32_t slot, int write_fd, pid_t parent)
{
    prctl(PR_SET_PDEATHSIG, SIGKILL);
    if (getppid() != parent) /* the batch died before the line above */
        _exit(EXIT_FAILURE);
    signal(SIGINT, SIG_IGN); /* Ctrl-C reaches the whole group: the batch decides, and stops its workers */
    signal(SIGTERM, SIG_DFL);
    for (int k = 0; k < b->jobs; ++k)
        if (b->workers[k].pid > 0)
            close(b->workers[k].fd);
    omp_set_num_threads(b->threads);
    pz_ctx ctx;
    pz_ctx_init(&ctx);
    ctx.quiet = 1;
    const pz_batch_garment *garment = &b->list->garments[b->selected[slot]];
    char *folder = garment_folder(b, slot);
    report message;
    memset(&message, 0, sizeof message);
    pz_batch_outcome *outcome = &message.outcome;
    outcome->worst_strain = -1;
    double start = pz_seconds();
    pz_status status = folder ? b->options->work(garment, folder, b->threads, outcome, b->options->user, &ctx)
                              : pz_error(&ctx, PZ_ERR_NOMEM, "batch: out of memory");
    outcome->status = status;
    if (status == PZ_OK && !strict_failure(b, outcome)) {
        /* The marker last: its presence says the folder is complete (--resume). */
        struct rusage usage;
        getrusage(RUSAGE_SELF, &usage);
        cJSON *row = bt_row(garment, "ok", 0, "ok", outcome, pz_seconds() - start, usage.ru_maxrss / 1024.0,
                            b->options->shard_index);
        status = row ? bt_write_marker(folder, row, &ctx) : pz_error(&ctx, PZ_ERR_NOMEM, "batch: out of memory");
        cJSON_Delete(row);
        outcome->status = status;
    }
    if (status != PZ_OK && !outcome->message[0])
        snprintf(outcome->message, sizeof outcome->message, "%s", ctx.error[0] ? ctx.error : pz_status_str(status));
    free(folder);
    ssize_t written = write(write_fd, &message, sizeof message);
    _exit(written == (ssize_t)sizeof message ? EXIT_SUCCESS : EXIT_FAILURE);
}

/* ---------------------------------------------------------------- the batch */

static int usable_cores(void)
{
    cpu_set_t set;
    if (sched_getaffinity(0, sizeof set, &set) == 0 && CPU_COUNT(&set) > 0)
        return CPU_COUNT(&set);
    long online = sysconf(_SC_NPROCESSORS_ONLN);
    return online > 0 ? (int)online : 1;
}

static pz_status start_worker(batch *b, worker *w, pz_ctx *ctx)
{
    int fds[2];
    if (pipe(fds) != 0)
        return pz_error(ctx, PZ_ERR_INTERNAL, "batch: cannot make a pipe: %s", strerror(errno));
    int32_t slot = b->next;
    fflush(stdout), fflush(stderr); /* nothing buffered is written twice */
    pid_t parent = getpid();
    pid_t pid = fork();
    if (pid < 0) {
        close(fds[0]), close(fds[1]);
        return pz_error(ctx, PZ_ERR_INTERNAL, "batch: cannot start a worker: %s", strerror(errno));
    }
    if (pid == 0) {
        close(fds[0]);
        run_worker(b, slot, fds[1], parent);
    }
    close(fds[1]);
    *w = (worker){pid, fds[0], slot, pz_seconds(), 0};
    ++b->next, ++b->running;
    return PZ_OK;
}

/* Reads the worker's report; 1 when a whole one came. */
static int read_report(int fd, report *message)
{
    size_t got = 0;
    while (got < sizeof *message) {
        ssize_t n = read(fd, (char *)message + got, sizeof *message - got);
        if (n < 0 && errno == EINTR)
            continue;
        if (n <= 0)
            break;
        got += (size_t)n;
    }
    return got == sizeof *message;
}

/* The row of a finished worker from its report and wait status. */
static cJSON *finished_row(const batch *b, const worker *w, int wait_status, const struct rusage *usage)
{
    const pz_batch_garment *garment = &b->list->garments[b->selected[w->slot]];
    double seconds = pz_seconds() - w->start, peak_mb = usage->ru_maxrss / 1024.0;
    int32_t shard = b->options->shard_index;
    report message;
    memset(&message, 0, sizeof message);
    int reported = read_report(w->fd, &message);
    pz_batch_outcome *outcome = &message.outcome;
    outcome->message[sizeof outcome->message - 1] = '\0';
    if (w->timed_out) {
        outcome->status = PZ_ERR_CANCELLED;
        snprintf(outcome->message, sizeof outcome->message, "batch: %s: killed after %g s (--timeout)",
                 garment->path, b->options->timeout_s);
        return bt_row(garment, "timeout", EXIT_TIMEOUT, "timeout", outcome, seconds, peak_mb, shard);
    }
    if (WIFSIGNALED(wait_status) || !reported) {
        outcome->status = PZ_ERR_INTERNAL;
        int code = WIFSIGNALED(wait_status) ? 128 + WTERMSIG(wait_status) : WEXITSTATUS(wait_status);
        if (WIFSIGNALED(wait_status))
            snprintf(outcome->message, sizeof outcome->message, "batch: %s: the worker died of signal %d (%s)",
                     garment->path, WTERMSIG(wait_status), strsignal(WTERMSIG(wait_status)));
        else
            snprintf(outcome->message, sizeof outcome->message, "batch: %s: the worker exited with %d and no report",
                     garment->path, code);
        return bt_row(garment, "crashed", code, "crash", outcome, seconds, peak_mb, shard);
    }
    if (outcome->status == PZ_OK && strict_failure(b, outcome)) {
        cJSON *row = bt_row(garment, "failed", 3, "goals", outcome, seconds, peak_mb, shard);
        cJSON_ReplaceItemInObjectCaseSensitive(row, "error", cJSON_CreateString("goals not met (--strict)"));
        return row;
    }
    if (outcome->status == PZ_OK)
        return bt_row(garment, "ok", 0, "ok", outcome, seconds, peak_mb, shard);
    return bt_row(garment, "failed", pz_status_exit_code(outcome->status), bt_category(outcome->status), outcome,
                  seconds, peak_mb, shard);
}

static void note_row(batch *b, const cJSON *row, pz_ctx *ctx)
{
    if (b->options->progress)
        return;
    const char *name = cJSON_GetObjectItemCaseSensitive(row, "name")->valuestring;
    const char *state = cJSON_GetObjectItemCaseSensitive(row, "status")->valuestring;
    const cJSON *seconds = cJSON_GetObjectItemCaseSensitive(row, "seconds");
    if (strcmp(state, "ok") == 0)
        pz_note(ctx, "batch: [%d/%d] %s: ok, %d pieces, %.1f s", (int)b->finished, (int)b->count, name,
                (int)cJSON_GetObjectItemCaseSensitive(row, "pieces")->valuedouble,
                cJSON_IsNumber(seconds) ? seconds->valuedouble : 0.0);
    else
        pz_note(ctx, "batch: [%d/%d] %s: %s: %s", (int)b->finished, (int)b->count, name, state,
                cJSON_GetObjectItemCaseSensitive(row, "error")->valuestring);
}

/* Reaps the workers that ended; kills those over the time limit. */
static pz_status reap(batch *b, pz_ctx *ctx)
{
    for (int k = 0; k < b->jobs; ++k) {
        worker *w = &b->workers[k];
        if (w->pid <= 0)
            continue;
        int wait_status = 0;
        struct rusage usage;
        pid_t ended = wait4(w->pid, &wait_status, WNOHANG, &usage);
        if (ended == 0) {
            if (b->options->timeout_s > 0 && !w->timed_out && pz_seconds() - w->start > b->options->timeout_s) {
                kill(w->pid, SIGKILL);
                w->timed_out = 1;
            }
            continue;
        }
        if (ended < 0 && errno == EINTR) {
            --k;
            continue;
        }
        if (!b->stopping) {
            cJSON *row = finished_row(b, w, wait_status, &usage);
            if (!row)
                return pz_error(ctx, PZ_ERR_NOMEM, "batch: out of memory");
            b->rows[w->slot] = row;
            ++b->finished;
            b->failed += strcmp(cJSON_GetObjectItemCaseSensitive(row, "status")->valuestring, "ok") != 0;
            note_row(b, row, ctx);
        }
        close(w->fd);
        w->pid = 0;
        --b->running;
    }
    return PZ_OK;
}

static void draw_progress(batch *b, int force)
{
    double now = pz_seconds();
    if (!b->options->progress || (!force && now - b->last_draw < PROGRESS_EVERY_S))
        return;
    b->last_draw = now;
    int32_t run = b->finished - b->resumed;
    char eta[32] = "--";
    if (run > 0) {
        double left = (now - b->start) / run * (b->count - b->finished);
        snprintf(eta, sizeof eta, "%dm%02ds", (int)(left / 60), (int)left % 60);
    }
    fprintf(stderr, "\rbatch: %d/%d done, %d failed, %d running, ETA %-10s", (int)b->finished, (int)b->count,
            (int)b->failed, b->running, eta);
    fflush(stderr);
    b->drawn = 1;
}

/* Waits until a worker ends or POLL_MS pass. */
static void wait_a_little(const batch *b)
{
    struct pollfd fds[256];
    nfds_t count = 0;
    for (int k = 0; k < b->jobs && count < 256; ++k)
        if (b->workers[k].pid > 0)
            fds[count++] = (struct pollfd){b->workers[k].fd, POLLIN, 0};
    poll(fds, count, POLL_MS); /* a pipe's write end closes when its worker ends; EINTR on Ctrl-C */
}

/* Stops every worker (cancellation): their garments stay pending. */
static void stop_workers(batch *b)
{
    b->stopping = 1;
    for (int k = 0; k < b->jobs; ++k)
        if (b->workers[k].pid > 0)
            kill(b->workers[k].pid, SIGKILL);
}

/* mkdir -p */
static pz_status make_folders(const char *path, pz_ctx *ctx)
{
    char *copy = strdup(path);
    if (!copy)
        return pz_error(ctx, PZ_ERR_NOMEM, "batch: out of memory");
    for (char *at = copy + 1;; ++at) {
        if (*at != '/' && *at != '\0')
            continue;
        char saved = *at;
        *at = '\0';
        struct stat info;
        if (mkdir(copy, 0777) != 0 && (errno != EEXIST || stat(copy, &info) != 0 || !S_ISDIR(info.st_mode))) {
            pz_status status = pz_error(ctx, PZ_ERR_CREATE, "batch: %s: cannot make the folder: %s", copy,
                                        errno == EEXIST ? "not a folder" : strerror(errno));
            free(copy);
            return status;
        }
        if (!saved)
            break;
        *at = saved;
    }
    free(copy);
    return PZ_OK;
}

/* This shard's garments; with --resume the complete ones get their marker's row at once. */
static pz_status select_garments(batch *b, pz_ctx *ctx)
{
    const pz_batch_options *o = b->options;
    b->selected = malloc(((size_t)b->list->count + 1) * sizeof *b->selected);
    b->rows = calloc((size_t)b->list->count + 1, sizeof *b->rows);
    if (!b->selected || !b->rows)
        return pz_error(ctx, PZ_ERR_NOMEM, "batch: out of memory");
    for (int32_t i = 0; i < b->list->count; ++i)
        if (o->shard_count <= 1 || b->list->garments[i].order % o->shard_count == o->shard_index)
            b->selected[b->count++] = i;
    /* The ones to run first, so the loop starts them in order; the complete ones are done. */
    int32_t to_run = 0;
    for (int32_t slot = 0; slot < b->count; ++slot) {
        char *folder = garment_folder(b, slot);
        char *marker = folder ? bt_join(folder, BT_MARKER_NAME) : NULL;
        if (!marker) {
            free(folder);
            return pz_error(ctx, PZ_ERR_NOMEM, "batch: out of memory");
        }
        cJSON *row = o->resume ? bt_read_marker(folder, b->list->garments[b->selected[slot]].name) : NULL;
        if (row) {
            cJSON_ReplaceItemInObjectCaseSensitive(row, "resumed", cJSON_CreateTrue());
            b->rows[slot] = row;
            ++b->finished, ++b->resumed;
        } else {
            unlink(marker); /* a folder about to be redone is not complete, whatever happens to this run */
            int32_t index = b->selected[slot];
            memmove(&b->selected[to_run + 1], &b->selected[to_run], (size_t)(slot - to_run) * sizeof *b->selected);
            memmove(&b->rows[to_run + 1], &b->rows[to_run], (size_t)(slot - to_run) * sizeof *b->rows);
            b->selected[to_run] = index, b->rows[to_run] = NULL;
            ++to_run;
        }
        free(folder), free(marker);
    }
    b->next = 0; /* selected[0 .. to_run-1] are to run, the rest resumed */
    return PZ_OK;
}

/* The summary rows in the stable order (the selection was reordered: runs first). */
static int by_order(const void *a, const void *b)
{
    const cJSON *left = cJSON_GetObjectItemCaseSensitive(*(cJSON *const *)a, "name");
    const cJSON *right = cJSON_GetObjectItemCaseSensitive(*(cJSON *const *)b, "name");
    return strcmp(left->valuestring, right->valuestring);
}

static pz_status write_summary(batch *b, pz_batch_totals *totals, pz_ctx *ctx)
{
    for (int32_t slot = 0; slot < b->count; ++slot) {
        if (b->rows[slot])
            continue;
        pz_batch_outcome pending;
        memset(&pending, 0, sizeof pending);
        pending.status = PZ_ERR_CANCELLED;
        snprintf(pending.message, sizeof pending.message, "not run: the batch was interrupted");
        b->rows[slot] = bt_row(&b->list->garments[b->selected[slot]], "pending", 130, "cancelled", &pending, -1, -1,
                               b->options->shard_index);
        if (!b->rows[slot])
            return pz_error(ctx, PZ_ERR_NOMEM, "batch: out of memory");
    }
    qsort(b->rows, (size_t)b->count, sizeof *b->rows, by_order);
    char name[64] = "summary";
    if (b->options->shard_count >= 1)
        snprintf(name, sizeof name, "summary-%d-of-%d", (int)b->options->shard_index, (int)b->options->shard_count);
    char *base = bt_join(b->options->outroot, name);
    if (!base)
        return pz_error(ctx, PZ_ERR_NOMEM, "batch: out of memory");
    pz_status status = bt_write_summary(base, b->rows, b->count, ctx);
    snprintf(totals->summary_csv, sizeof totals->summary_csv, "%s.csv", base);
    free(base);
    bt_count_rows(b->rows, b->count, totals);
    return status;
}

static pz_status run_loop(batch *b, pz_ctx *ctx)
{
    pz_status status = PZ_OK;
    int32_t to_run = 0;
    while (to_run < b->count && !b->rows[to_run])
        ++to_run;
    while (status == PZ_OK && (b->next < to_run || b->running > 0)) {
        if (!b->stopping && pz_cancelled(ctx))
            stop_workers(b);
        for (int k = 0; k < b->jobs && status == PZ_OK && !b->stopping && b->next < to_run; ++k)
            if (b->workers[k].pid == 0)
                status = start_worker(b, &b->workers[k], ctx);
        if (status != PZ_OK)
            break;
        wait_a_little(b);
        status = reap(b, ctx);
        draw_progress(b, 0);
        if (b->stopping && b->running == 0)
            break;
    }
    if (status != PZ_OK)
        stop_workers(b), reap(b, ctx);
    return status;
}

pz_status pz_batch_run(const pz_batch_list *list, const pz_batch_options *options, pz_batch_totals *totals,
                       pz_ctx *ctx)
{
    memset(totals, 0, sizeof *totals);
    batch b;
    memset(&b, 0, sizeof b);
    b.list = list, b.options = options, b.start = pz_seconds();
    b.jobs = options->jobs > 0 ? options->jobs : 1;
    b.threads = options->threads > 0 ? options->threads : (usable_cores() / b.jobs > 1 ? usable_cores() / b.jobs : 1);
    if (!options->work || !options->outroot || b.jobs > 256)
        return pz_error(ctx, PZ_ERR_USAGE, "batch: no work function, no output folder, or more than 256 jobs");
    pz_status status = make_folders(options->outroot, ctx);
    if (status == PZ_OK)
        status = select_garments(&b, ctx);
    if (status == PZ_OK && !(b.workers = calloc((size_t)b.jobs, sizeof *b.workers)))
        status = pz_error(ctx, PZ_ERR_NOMEM, "batch: out of memory");
    if (status == PZ_OK) {
        if (b.resumed && !options->progress)
            pz_note(ctx, "batch: %d of %d garments already complete (--resume)", (int)b.resumed, (int)b.count);
        status = run_loop(&b, ctx);
        if (b.drawn)
            fprintf(stderr, "\r%*s\r", 78, "");
    }
    if (status == PZ_OK || status == PZ_ERR_CANCELLED) {
        pz_status written = write_summary(&b, totals, ctx);
        if (written != PZ_OK)
            status = written;
        else if (b.stopping)
            status = pz_error(ctx, PZ_ERR_CANCELLED, "batch: cancelled: %d garments not run (summary %s)",
                              (int)totals->pending, totals->summary_csv);
    }
    for (int32_t slot = 0; b.rows && slot < b.count; ++slot)
        cJSON_Delete(b.rows[slot]);
    free(b.rows), free(b.selected), free(b.workers);
    totals->seconds = pz_seconds() - b.start;
    return status;
}

/*
 * python/src/work.c -- a library call run on its own thread with the GIL
 * released, so that other Python threads go on, while the caller's thread
 * (holding the GIL only briefly, every 20 ms) hands the library's progress
 * to the Python callable and turns Ctrl-C or a cancel event into the
 * library's cancel flag (pz_ctx.cancel), which every stage checks between
 * its steps.
 *
 * Why a second thread: CPython runs signal handlers on the main thread only,
 * between bytecodes. While the main thread is inside a long C call, Ctrl-C
 * only sets a flag; the waiting loop here calls PyErr_CheckSignals, which
 * runs the handler (KeyboardInterrupt by default) and so learns of it.
 *
 * SPDX-License-Identifier: GPL-3.0-or-later
 */
#include "internal.h"

#include <errno.h>
#include <pthread.h>
#include <string.h>
#include <time.h>

#define POLL_MS 20

/* One progress report, as the library gave it. */
typedef struct progress_report {
    char stage[32];
    char message[128];
    double fraction;
} progress_report;

/* Stage changes kept between two polls: a run has about ten stages in all. */
#define PENDING_REPORTS 16

/* What the two threads share, under `lock`. */
typedef struct shared_state {
    pthread_mutex_t lock;
    pthread_cond_t changed;
    pzpy_job *job;
    pz_ctx *ctx;
    int done;
    pz_status status;
    /* the reports not delivered yet: the last of each stage, in order (a stage that starts and ends between
     * two polls is still seen); a new report of the pending last stage replaces it */
    progress_report pending[PENDING_REPORTS];
    int pending_count;
} shared_state;

/* The library's progress callback, on the worker thread: queues the report (see shared_state.pending). */
static void keep_progress(void *user, const char *stage, double fraction, const char *message)
{
    shared_state *state = user;
    pthread_mutex_lock(&state->lock);
    stage = stage ? stage : "";
    int last = state->pending_count - 1;
    if (last < 0 || strcmp(state->pending[last].stage, stage) != 0)
        last = state->pending_count < PENDING_REPORTS ? state->pending_count++ : PENDING_REPORTS - 1;
    progress_report *report = &state->pending[last];
    snprintf(report->stage, sizeof report->stage, "%s", stage);
    snprintf(report->message, sizeof report->message, "%s", message ? message : "");
    report->fraction = fraction;
    pthread_mutex_unlock(&state->lock);
}

static void *work(void *argument)
{
    shared_state *state = argument;
    pz_status status = state->job->run(state->job, state->ctx);
    pthread_mutex_lock(&state->lock);
    state->status = status;
    state->done = 1;
    pthread_cond_signal(&state->changed);
    pthread_mutex_unlock(&state->lock);
    return NULL;
}

/* Waits up to POLL_MS for the worker (the GIL released); returns 1 when it is done. */
static int wait_a_little(shared_state *state)
{
    struct timespec until;
    clock_gettime(CLOCK_REALTIME, &until);
    until.tv_nsec += POLL_MS * 1000000L;
    if (until.tv_nsec >= 1000000000L)
        until.tv_sec += 1, until.tv_nsec -= 1000000000L;
    int done;
    Py_BEGIN_ALLOW_THREADS
    pthread_mutex_lock(&state->lock);
    while (!state->done && pthread_cond_timedwait(&state->changed, &state->lock, &until) != ETIMEDOUT)
        ;
    done = state->done;
    pthread_mutex_unlock(&state->lock);
    Py_END_ALLOW_THREADS
    return done;
}

/* Calls progress(stage, fraction, message) for each report queued since the last call; -1 when it raised. */
static int deliver_progress(shared_state *state, PyObject *progress)
{
    progress_report reports[PENDING_REPORTS];
    pthread_mutex_lock(&state->lock);
    int count = state->pending_count;
    memcpy(reports, state->pending, (size_t)count * sizeof reports[0]);
    state->pending_count = 0;
    pthread_mutex_unlock(&state->lock);
    for (int i = 0; i < count && progress != Py_None; ++i) {
        PyObject *returned = PyObject_CallFunction(progress, "sds", reports[i].stage, reports[i].fraction,
                                                   reports[i].message);
        Py_XDECREF(returned);
        if (!returned)
            return -1;
    }
    return 0;
}

/* 1 when cancel.is_set() is true, 0 when not (or cancel is None), -1 when it raised. */
static int cancel_requested(PyObject *cancel)
{
    if (cancel == Py_None)
        return 0;
    PyObject *answer = PyObject_CallMethod(cancel, "is_set", NULL);
    if (!answer)
        return -1;
    int set = PyObject_IsTrue(answer);
    Py_DECREF(answer);
    return set;
}

pz_status pzpy_run_job(pzpy_job *job, pz_ctx *ctx, PyObject *progress, PyObject *cancel, int *python_error)
{
    *python_error = 0;
    if (progress != Py_None && !PyCallable_Check(progress)) {
        PyErr_SetString(PyExc_TypeError, "progress: expected a callable (stage, fraction, message), or None");
        *python_error = 1;
        return PZ_ERR_USAGE;
    }
    if (cancel != Py_None && !PyObject_HasAttrString(cancel, "is_set")) {
        PyErr_SetString(PyExc_TypeError, "cancel: expected an object with is_set() (threading.Event), or None");
        *python_error = 1;
        return PZ_ERR_USAGE;
    }
    shared_state state;
    memset(&state, 0, sizeof state);
    pthread_mutex_init(&state.lock, NULL);
    pthread_cond_init(&state.changed, NULL);
    state.job = job;
    state.ctx = ctx;
    volatile int cancel_flag = 0;
    ctx->cancel = &cancel_flag;
    ctx->progress = keep_progress;
    ctx->progress_user = &state;
    pthread_t thread;
    pthread_attr_t attributes;
    pthread_attr_init(&attributes);
    pthread_attr_setstacksize(&attributes, 64u << 20); /* the size of a main thread's stack, and some */
    int started = pthread_create(&thread, &attributes, work, &state);
    pthread_attr_destroy(&attributes);
    if (started != 0) {
        pthread_cond_destroy(&state.changed);
        pthread_mutex_destroy(&state.lock);
        PyErr_SetString(PyExc_RuntimeError, "panelize: cannot start a thread");
        *python_error = 1;
        return PZ_ERR_INTERNAL;
    }
    int done = 0;
    while (!done) {
        done = wait_a_little(&state);
        if (cancel_flag) /* already stopping: wait for the worker */
            continue;
        int stop = deliver_progress(&state, progress) < 0 || PyErr_CheckSignals() < 0;
        int requested = stop ? 0 : cancel_requested(cancel);
        if (stop || requested < 0)
            *python_error = 1;
        if (stop || requested)
            cancel_flag = 1;
    }
    Py_BEGIN_ALLOW_THREADS
    pthread_join(thread, NULL);
    Py_END_ALLOW_THREADS
    if (!*python_error && state.status == PZ_OK && deliver_progress(&state, progress) < 0)
        *python_error = 1;  /* the last report, delivered like the others */
    ctx->cancel = NULL;
    ctx->progress = NULL;
    pthread_cond_destroy(&state.changed);
    pthread_mutex_destroy(&state.lock);
    return *python_error ? PZ_ERR_CANCELLED : state.status;
}

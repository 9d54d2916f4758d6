/*
 * studio/internal.h -- private to studio/: the server's state, shared by
 * server.c (HTTP: routing, bodies, files), garments.c (loading, runs in
 * threads, results), request.c (the JSON requests checked) and
 * result_json.c (a result as the page's JSON).
 *
 * Locking: one mutex (pz_studio.lock) guards the garment table, every
 * garment's run state and the reference counts of the outputs; it is held
 * for short moments only, never across a pz_run or a file write. A run's
 * thread owns its job; the garment's `job` points at the latest one, which
 * the next run joins (and frees) before it starts.
 *
 * SPDX-License-Identifier: GPL-3.0-or-later
 */
#ifndef PZ_STUDIO_INTERNAL_H
#define PZ_STUDIO_INTERNAL_H

#include "pipeline/pipeline.h"
#include "studio/studio.h"

#include <limits.h>
#include <pthread.h>

/* Limits of one run request: the strokes a designer draws are tens of curves of hundreds of points. */
#define STUDIO_MAX_STROKES 200
#define STUDIO_MAX_STROKE_POINTS 5000
#define STUDIO_MAX_TOTAL_POINTS 50000

typedef enum studio_state {
    STUDIO_IDLE = 0,      /* loaded, never run */
    STUDIO_RUNNING,
    STUDIO_DONE,
    STUDIO_FAILED,
    STUDIO_CANCELLED
} studio_state;

/* A finished run: its result, the result as JSON, its files (written on the first request). Shared by
 * reference count (under the studio lock): the garment holds one, every request serving it another. */
typedef struct studio_output {
    int refs;
    int run_id;
    pz_result *result;              /* its options' strings point into this output (name) or are NULL (sketch):
                                       an output outlives its run and may outlive its garment */
    char name[256];                 /* the garment's name */
    char *json;                     /* the page's JSON of the result (result_json.c) */
    size_t json_length;
    pthread_mutex_t write_lock;     /* one writer of the files at a time */
    int written;                    /* 1: folder holds every file */
    char folder[PATH_MAX + 32];
} studio_output;

struct studio_garment;

/* One run: its options and strokes, its thread, its progress (under the studio lock). */
typedef struct studio_job {
    struct studio_garment *garment;
    pthread_mutex_t *lock;          /* the studio's */
    int run_id;
    pz_run_options options;
    pz_sketch *sketch;              /* the strokes (mm), or NULL; owned */
    pz_sketch *grain;               /* the grain strokes (mm), or NULL; owned */
    volatile int cancel;
    pthread_t thread;
    struct studio_job *previous;    /* the run this one replaces: joined and freed before this one starts */
    char stage[32];
    double fraction;
    char message[256];
} studio_job;

typedef struct studio_garment {
    int id;
    char name[256];                 /* the file's base name */
    pz_mesh *mesh;                  /* as loaded, in millimetres, prepared (pz_prepare_auto) once; read by the
                                       runs (which do not prepare again), freed after them */
    pz_sketch *welded;              /* the seams the preparation welded, every run's garment_seams, or NULL */
    pz_run_cache *cache;            /* the plane and field the runs leave each other (docs/run.md, "Reuse between
                                       runs"; a run joins the one before it, so one run at a time uses it) */
    double mean_edge_mm;
    char *mesh_json;                /* {"positions": [...], "faces": [...]} of mesh */
    long last_used;
    studio_job *job;                /* the latest run, or NULL */
    int next_run;
    studio_state state;
    char error[1024];               /* the failed run's message */
    double run_ms;                  /* the last finished run's time */
    studio_output *output;          /* the latest finished run's, or NULL */
} studio_garment;

struct pz_studio {
    struct MHD_Daemon *daemon;
    pthread_mutex_t lock;
    char url[160];
    char root[PATH_MAX];            /* realpath of the allowed folder */
    char assets[PATH_MAX];          /* the web app's folder ("" when not found) */
    char temp[PATH_MAX];            /* a private temporary folder: uploads and pattern files */
    size_t max_upload;
    int local_only;                 /* 1: requests must name this machine in Host */
    int port;
    studio_garment *garments[PZ_STUDIO_MAX_GARMENTS];
    int next_garment;
    long clock;
    int next_output;
};

/* ---------------------------------------------------------------- garments.c */

/* Loads `path` (already checked to be under root) as a new garment; `name` names it. *id receives its id.
 * Errors as pz_mesh_read (PZ_ERR_OPEN, PZ_ERR_DATA naming `name`). */
pz_status studio_garment_load(pz_studio *studio, const char *path, const char *name, int *id, pz_ctx *ctx);
/* The garment of an id, or NULL; call with the lock held. */
studio_garment *studio_garment_find(pz_studio *studio, int id);
/* Starts a run of garment `id` with `options` and `sketch` (taken: freed here on failure too), cancelling the
 * running one. *run_id receives its number. PZ_ERR_USAGE when there is no such garment. */
pz_status studio_run_start(pz_studio *studio, int id, const pz_run_options *options, pz_sketch *sketch, pz_sketch *grain,
                           int *run_id, pz_ctx *ctx);
/* Asks the running run of garment `id` to stop; 0 when there is no such garment. */
int studio_run_cancel(pz_studio *studio, int id);
/* A reference to the latest output of garment `id` (NULL: none); release with studio_output_release. */
studio_output *studio_output_get(pz_studio *studio, int id);
void studio_output_release(pz_studio *studio, studio_output *output);
/* The output's files in its folder (written once, all of them); PZ_OK when they are there. */
pz_status studio_output_files(pz_studio *studio, studio_output *output, pz_ctx *ctx);
/* Cancels every run, waits for them, frees every garment. */
void studio_garments_free(pz_studio *studio);
/* JSON texts (malloc'd, the caller frees; NULL when out of memory or no such garment). */
char *studio_garment_json(pz_studio *studio, int id);
char *studio_status_json(pz_studio *studio, int id);
char *studio_garments_list_json(pz_studio *studio);

/* ---------------------------------------------------------------- request.c */

/* The run request's JSON into *options (from pz_run_options_default; no preparation: the garment's was
 * done once; options->garment_seams = `welded`, the garment's, may be NULL) and *sketch (the strokes; NULL
 * when there are none): unknown keys, wrong types, values out of range, too many or too long strokes, points not finite or
 * far from the garment (bbox of `mesh` grown by its diagonal) are PZ_ERR_USAGE with a message. */
pz_status studio_parse_run(const char *body, size_t length, const pz_mesh *mesh, const pz_sketch *welded,
                           pz_run_options *options, pz_sketch **sketch, pz_sketch **grain, pz_ctx *ctx);
/* A sketch with room for `curves` curves and `points` points (curve_count set, offsets zeroed), or
 * PZ_ERR_NOMEM; freed with pz_sketch_free. */
pz_status studio_sketch_new(int32_t curves, int32_t points, pz_sketch **out, pz_ctx *ctx);
/* A path the page names, relative to root (or absolute), into `out` (PATH_MAX): it must resolve (symbolic
 * links followed; for `must_exist` 0 its nearest existing ancestor) inside root. PZ_ERR_USAGE otherwise. */
pz_status studio_resolve_path(const pz_studio *studio, const char *path, int must_exist, char *out, pz_ctx *ctx);
/* The string member `key` of a JSON object text, or PZ_ERR_USAGE naming it; *value is malloc'd. */
pz_status studio_json_string(const char *body, size_t length, const char *key, char **value, pz_ctx *ctx);

/* ---------------------------------------------------------------- result_json.c */

/* The page's JSON of a finished run (docs/studio.md, "The result"); NULL when out of memory. */
char *studio_result_json(const pz_result *result, int run_id, double run_ms, size_t *length);
/* {"positions": [...], "faces": [...]} of a mesh (mm, rounded to 1 micrometre); NULL when out of memory. */
char *studio_mesh_json(const pz_mesh *mesh);
/* Rounds to `decimals` decimals so that the JSON is short. */
double studio_round(double value, int decimals);

#endif /* PZ_STUDIO_INTERNAL_H */

/*
 * studio/garments.c -- the studio's garments and their runs.
 *
 * A garment is read once and kept in millimetres. Each run is a thread of
 * its own calling pz_run with a cancel flag and a progress callback; a new
 * run of the same garment sets the running one's flag and, in its own
 * thread, joins it before it starts, so one pz_run at a time works on a
 * garment and the request that started it never waits. A run that finishes
 * after a newer one was asked for is dropped. A finished run's result is an
 * output shared by reference count: the page's JSON is made once, the
 * pattern files are written once into the studio's temporary folder, when
 * first asked for.
 *
 * SPDX-License-Identifier: GPL-3.0-or-later
 */
#define _GNU_SOURCE
#include "studio/internal.h"
#include "io/io.h"

#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

static const char *const state_names[] = {"idle", "running", "done", "failed", "cancelled"};

/* ---------------------------------------------------------------- outputs */

void studio_output_release(pz_studio *studio, studio_output *output)
{
    if (!output)
        return;
    pthread_mutex_lock(&studio->lock);
    int left = --output->refs;
    pthread_mutex_unlock(&studio->lock);
    if (left > 0)
        return;
    pz_result_free(&output->result);
    free(output->json);
    pthread_mutex_destroy(&output->write_lock);
    free(output);
}

studio_output *studio_output_get(pz_studio *studio, int id)
{
    pthread_mutex_lock(&studio->lock);
    studio_garment *garment = studio_garment_find(studio, id);
    studio_output *output = garment ? garment->output : NULL;
    if (output)
        ++output->refs;
    pthread_mutex_unlock(&studio->lock);
    return output;
}

pz_status studio_output_files(pz_studio *studio, studio_output *output, pz_ctx *ctx)
{
    pthread_mutex_lock(&output->write_lock);
    pz_status status = PZ_OK;
    if (!output->written) {
        status = pz_result_write(output->result, output->folder, PZ_OUTPUT_ALL, NULL, ctx);
        output->written = status == PZ_OK;
    }
    pthread_mutex_unlock(&output->write_lock);
    (void)studio;
    return status;
}

/* ---------------------------------------------------------------- runs */

static void job_progress(void *user, const char *stage, double fraction, const char *message)
{
    studio_job *job = user;
    pthread_mutex_lock(job->lock);
    snprintf(job->stage, sizeof job->stage, "%s", stage ? stage : "");
    snprintf(job->message, sizeof job->message, "%s", message ? message : "");
    job->fraction = fraction;
    pthread_mutex_unlock(job->lock);
}

static void job_free(studio_job *job)
{
    if (!job)
        return;
    pz_sketch_free(&job->sketch);
    pz_sketch_free(&job->grain);
    free(job);
}

typedef struct job_start {
    pz_studio *studio;
    studio_job *job;
} job_start;

/* The finished run's output (the page's JSON made here, outside the lock), or NULL when out of memory. */
static studio_output *make_output(pz_studio *studio, pz_result *result, int run_id, double ms)
{
    studio_output *output = calloc(1, sizeof *output);
    if (!output)
        return NULL;
    snprintf(output->name, sizeof output->name, "%s", result->options.name ? result->options.name : "garment");
    result->options.name = output->name;
    result->options.sketch = NULL; /* the job's, freed by the next run */
    result->options.garment_seams = NULL;
    result->options.cache = NULL; /* the garment's */
    result->options.grain_hints = NULL;
    output->json = studio_result_json(result, run_id, ms, &output->json_length);
    if (!output->json) {
        free(output);
        return NULL;
    }
    pthread_mutex_init(&output->write_lock, NULL);
    output->refs = 1;
    output->run_id = run_id;
    output->result = result;
    pthread_mutex_lock(&studio->lock);
    int number = ++studio->next_output;
    pthread_mutex_unlock(&studio->lock);
    snprintf(output->folder, sizeof output->folder, "%s/run-%d", studio->temp, number);
    return output;
}

static void *job_main(void *argument)
{
    job_start start = *(job_start *)argument;
    free(argument);
    pz_studio *studio = start.studio;
    studio_job *job = start.job;
    if (job->previous) {
        pthread_join(job->previous->thread, NULL);
        job_free(job->previous);
        job->previous = NULL;
    }
    pz_ctx ctx;
    pz_ctx_init(&ctx);
    ctx.quiet = 1;
    ctx.cancel = &job->cancel;
    ctx.progress = job_progress;
    ctx.progress_user = job;
    double begin = pz_seconds();
    pz_result *result = NULL;
    pz_status status = job->cancel ? PZ_ERR_CANCELLED : pz_run(job->garment->mesh, &job->options, &result, &ctx);
    double ms = pz_elapsed_ms(begin, pz_seconds());
    studio_output *output = NULL;
    if (status == PZ_OK && !(output = make_output(studio, result, job->run_id, ms))) {
        pz_result_free(&result);
        status = pz_error(&ctx, PZ_ERR_NOMEM, "out of memory making the result");
    }
    studio_output *dropped = output;
    pthread_mutex_lock(&studio->lock);
    studio_garment *garment = job->garment;
    if (garment->job == job) { /* no newer run was asked for */
        garment->state = status == PZ_OK ? STUDIO_DONE : status == PZ_ERR_CANCELLED ? STUDIO_CANCELLED : STUDIO_FAILED;
        snprintf(garment->error, sizeof garment->error, "%s", status == PZ_OK ? "" : ctx.error);
        garment->run_ms = ms;
        if (output) {
            dropped = garment->output;
            garment->output = output;
        }
    }
    pthread_mutex_unlock(&studio->lock);
    studio_output_release(studio, dropped);
    return NULL;
}

pz_status studio_run_start(pz_studio *studio, int id, const pz_run_options *options, pz_sketch *sketch, pz_sketch *grain,
                           int *run_id, pz_ctx *ctx)
{
    studio_job *job = calloc(1, sizeof *job);
    job_start *start = malloc(sizeof *start);
    if (!job || !start) {
        free(job), free(start);
        pz_sketch_free(&sketch);
        pz_sketch_free(&grain);
        return pz_error(ctx, PZ_ERR_NOMEM, "out of memory starting a run");
    }
    job->options = *options;
    job->lock = &studio->lock;
    job->options.name = NULL; /* the garment's name, set below (it lives as long as the job) */
    job->sketch = sketch;
    job->options.sketch = sketch;
    job->grain = grain;
    job->options.grain_hints = grain;
    pthread_mutex_lock(&studio->lock);
    studio_garment *garment = studio_garment_find(studio, id);
    if (!garment) {
        pthread_mutex_unlock(&studio->lock);
        job_free(job), free(start);
        return pz_error(ctx, PZ_ERR_USAGE, "garment %d: not loaded", id);
    }
    job->garment = garment;
    job->options.cache = garment->cache;
    job->options.name = garment->name; /* names the pieces (the file's base name) and the messages */
    job->run_id = ++garment->next_run;
    job->previous = garment->job;
    if (job->previous)
        job->previous->cancel = 1;
    snprintf(job->stage, sizeof job->stage, "%s", job->previous ? "waiting" : "starting");
    *start = (job_start){studio, job};
    if (pthread_create(&job->thread, NULL, job_main, start) != 0) {
        pthread_mutex_unlock(&studio->lock);
        job->previous = NULL;
        job_free(job), free(start);
        return pz_error(ctx, PZ_ERR_NOMEM, "cannot start a thread for the run");
    }
    garment->job = job;
    garment->state = STUDIO_RUNNING;
    garment->error[0] = '\0';
    *run_id = job->run_id;
    pthread_mutex_unlock(&studio->lock);
    return PZ_OK;
}

int studio_run_cancel(pz_studio *studio, int id)
{
    pthread_mutex_lock(&studio->lock);
    studio_garment *garment = studio_garment_find(studio, id);
    if (garment && garment->job)
        garment->job->cancel = 1;
    pthread_mutex_unlock(&studio->lock);
    return garment != NULL;
}

/* ---------------------------------------------------------------- garments */

studio_garment *studio_garment_find(pz_studio *studio, int id)
{
    for (int i = 0; i < PZ_STUDIO_MAX_GARMENTS; ++i)
        if (studio->garments[i] && studio->garments[i]->id == id) {
            studio->garments[i]->last_used = ++studio->clock;
            return studio->garments[i];
        }
    return NULL;
}

/* Stops the garment's runs and frees it (not in the table any more: no request reaches it). */
static void garment_free(pz_studio *studio, studio_garment *garment)
{
    if (!garment)
        return;
    studio_job *job = garment->job;
    if (job) {
        job->cancel = 1;
        pthread_join(job->thread, NULL); /* it joined its own previous run */
        job_free(job);
    }
    studio_output_release(studio, garment->output);
    pz_mesh_free(&garment->mesh);
    pz_sketch_free(&garment->welded);
    pz_run_cache_free(&garment->cache);
    free(garment->mesh_json);
    free(garment);
}

void studio_garments_free(pz_studio *studio)
{
    for (int i = 0; i < PZ_STUDIO_MAX_GARMENTS; ++i) {
        pthread_mutex_lock(&studio->lock);
        studio_garment *garment = studio->garments[i];
        studio->garments[i] = NULL;
        pthread_mutex_unlock(&studio->lock);
        garment_free(studio, garment);
    }
}

static double mean_edge_length(const pz_mesh *mesh)
{
    double sum = 0;
    for (int32_t f = 0; f < mesh->face_count; ++f)
        for (int k = 0; k < 3; ++k) {
            const double *a = mesh->positions + 3 * (size_t)mesh->faces[3 * f + k];
            const double *b = mesh->positions + 3 * (size_t)mesh->faces[3 * f + (k + 1) % 3];
            sum += sqrt((a[0] - b[0]) * (a[0] - b[0]) + (a[1] - b[1]) * (a[1] - b[1]) + (a[2] - b[2]) * (a[2] - b[2]));
        }
    return mesh->face_count ? sum / (3.0 * mesh->face_count) : 0;
}

/* The seams welding closed (polylines of the prepared mesh's vertices) as sketch curves in millimetres. */
static pz_status welded_seams(const pz_prepare_result *prepared, const pz_mesh *mesh, pz_sketch **out, pz_ctx *ctx)
{
    int32_t count = prepared->seam_count, points = prepared->seam_offsets[count];
    pz_sketch *sketch = NULL;
    pz_status status = studio_sketch_new(count, points, &sketch, ctx);
    if (status != PZ_OK)
        return status;
    memcpy(sketch->curve_offsets, prepared->seam_offsets, ((size_t)count + 1) * sizeof(int32_t));
    for (int32_t i = 0; i < points; ++i)
        memcpy(sketch->points + 3 * (size_t)i, mesh->positions + 3 * (size_t)prepared->seam_vertices[i],
               3 * sizeof(double));
    *out = sketch;
    return PZ_OK;
}

/*
 * The automatic preparation, once per garment: every run would do it again (0.75 s of a 50K-face run,
 * docs/studio.md "Speed"), and the strokes are drawn on the mesh the runs use. As pz_run does it: the
 * prepared mesh replaces the garment when a step changed it, and the seams welding closed become curves
 * every run adds to the strokes (*welded, or NULL).
 */
static pz_status prepare_once(pz_mesh **mesh, const char *name, pz_sketch **welded, pz_ctx *ctx)
{
    *welded = NULL;
    pz_prepare_options options;
    pz_prepare_options_default(&options);
    options.name = name;
    pz_ctx quiet;
    pz_ctx_quiet(ctx, &quiet);
    pz_prepare_result *prepared = NULL;
    pz_status status = pz_prepare_auto(*mesh, &options, &prepared, &quiet);
    if (status != PZ_OK)
        return pz_error(ctx, status, "%s", quiet.error);
    const pz_prepare_report *report = &prepared->report;
    int changed = report->output_faces != report->input_faces || report->output_vertices != report->input_vertices;
    for (int i = 0; i < PZ_PREPARE_STEP_COUNT; ++i)
        changed |= report->steps[i].ran && i != PZ_PREPARE_HAUSDORFF && i != PZ_PREPARE_POSES;
    if (changed) {
        pz_mesh_free(mesh);
        *mesh = prepared->mesh;
        prepared->mesh = NULL;
        if (prepared->seam_count > 0)
            status = welded_seams(prepared, *mesh, welded, ctx);
    }
    pz_prepare_result_free(&prepared);
    return status;
}

pz_status studio_garment_load(pz_studio *studio, const char *path, const char *name, int *id, pz_ctx *ctx)
{
    pz_mesh *mesh = NULL;
    pz_status status = pz_mesh_read(path, &mesh, ctx);
    if (status != PZ_OK) /* the message names the file as the page named it, not the server's path */
        return pz_error(ctx, status, "%s: %s", name,
                        strncmp(ctx->error, path, strlen(path)) == 0 ? ctx->error + strlen(path) + 2 : ctx->error);
    if (mesh->face_count == 0 || mesh->vertex_count == 0) {
        pz_mesh_free(&mesh);
        return pz_error(ctx, PZ_ERR_DATA, "%s: no faces", name);
    }
    pz_mesh_to_mm(mesh, PZ_UNITS_AUTO, NULL);
    pz_sketch *welded = NULL;
    if ((status = prepare_once(&mesh, name, &welded, ctx)) != PZ_OK) {
        pz_mesh_free(&mesh);
        return status;
    }
    studio_garment *garment = calloc(1, sizeof *garment);
    if (garment)
        garment->mesh_json = studio_mesh_json(mesh);
    if (garment)
        garment->cache = pz_run_cache_create();
    if (!garment || !garment->mesh_json || !garment->cache) {
        if (garment)
            free(garment->mesh_json), pz_run_cache_free(&garment->cache);
        free(garment);
        pz_mesh_free(&mesh);
        pz_sketch_free(&welded);
        return pz_error(ctx, PZ_ERR_NOMEM, "%s: out of memory", name);
    }
    garment->mesh = mesh;
    garment->welded = welded;
    garment->mean_edge_mm = mean_edge_length(mesh);
    const char *slash = strrchr(name, '/');
    snprintf(garment->name, sizeof garment->name, "%s", slash && slash[1] ? slash + 1 : name);
    /* A free slot, or the least recently used garment's. */
    pthread_mutex_lock(&studio->lock);
    int slot = 0;
    for (int i = 0; i < PZ_STUDIO_MAX_GARMENTS; ++i) {
        if (!studio->garments[i]) {
            slot = i;
            break;
        }
        if (studio->garments[i]->last_used < studio->garments[slot]->last_used)
            slot = i;
    }
    studio_garment *evicted = studio->garments[slot];
    garment->id = ++studio->next_garment;
    garment->last_used = ++studio->clock;
    studio->garments[slot] = garment;
    *id = garment->id;
    pthread_mutex_unlock(&studio->lock);
    garment_free(studio, evicted);
    return PZ_OK;
}

/* ---------------------------------------------------------------- JSON answers */

static char *print_and_delete(cJSON *root)
{
    char *text = root ? cJSON_PrintUnformatted(root) : NULL;
    cJSON_Delete(root);
    return text;
}

/* The garment's figures and run state (call with the lock held). */
static cJSON *garment_summary(const studio_garment *garment)
{
    cJSON *item = cJSON_CreateObject();
    if (!item)
        return NULL;
    cJSON_AddNumberToObject(item, "id", garment->id);
    cJSON_AddStringToObject(item, "name", garment->name);
    cJSON_AddNumberToObject(item, "vertices", garment->mesh->vertex_count);
    cJSON_AddNumberToObject(item, "faces", garment->mesh->face_count);
    cJSON_AddNumberToObject(item, "mean_edge_mm", studio_round(garment->mean_edge_mm, 4));
    cJSON_AddStringToObject(item, "state", state_names[garment->state]);
    const studio_job *job = garment->job;
    cJSON_AddNumberToObject(item, "run", job ? job->run_id : 0);
    cJSON_AddStringToObject(item, "stage", job && garment->state == STUDIO_RUNNING ? job->stage : "");
    cJSON_AddNumberToObject(item, "fraction", job && garment->state == STUDIO_RUNNING
                                                  ? studio_round(job->fraction, 3)
                                                  : garment->state == STUDIO_DONE);
    cJSON_AddStringToObject(item, "message", job && garment->state == STUDIO_RUNNING ? job->message : "");
    cJSON_AddStringToObject(item, "error", garment->error);
    cJSON_AddNumberToObject(item, "result_run", garment->output ? garment->output->run_id : 0);
    cJSON_AddNumberToObject(item, "ms", studio_round(garment->run_ms, 0));
    return item;
}

char *studio_status_json(pz_studio *studio, int id)
{
    pthread_mutex_lock(&studio->lock);
    studio_garment *garment = studio_garment_find(studio, id);
    cJSON *summary = garment ? garment_summary(garment) : NULL;
    pthread_mutex_unlock(&studio->lock);
    return print_and_delete(summary);
}

char *studio_garment_json(pz_studio *studio, int id)
{
    pthread_mutex_lock(&studio->lock);
    studio_garment *garment = studio_garment_find(studio, id);
    cJSON *summary = garment ? garment_summary(garment) : NULL;
    /* The mesh is fixed once loaded: printed from its own text, outside cJSON. */
    char *text = print_and_delete(summary);
    char *whole = NULL;
    if (text && asprintf(&whole, "%.*s,\"mesh\":%s}", (int)strlen(text) - 1, text, garment->mesh_json) < 0)
        whole = NULL;
    pthread_mutex_unlock(&studio->lock);
    free(text);
    return whole;
}

char *studio_garments_list_json(pz_studio *studio)
{
    cJSON *root = cJSON_CreateObject();
    cJSON *list = root ? cJSON_AddArrayToObject(root, "garments") : NULL;
    pthread_mutex_lock(&studio->lock);
    for (int i = 0; list && i < PZ_STUDIO_MAX_GARMENTS; ++i)
        if (studio->garments[i])
            cJSON_AddItemToArray(list, garment_summary(studio->garments[i]));
    pthread_mutex_unlock(&studio->lock);
    return print_and_delete(root);
}

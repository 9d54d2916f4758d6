/*
 * batch/summary.c -- the rows of a batch: one JSON object per garment,
 * written as the garment's marker (batch.json, last, atomically) and as
 * summary.csv and summary.jsonl; the merge of the shards' summaries
 * (docs/batch.md, "The summary").
 *
 * SPDX-License-Identifier: GPL-3.0-or-later
 */
#define _POSIX_C_SOURCE 200809L
#include "batch/internal.h"
#include "core/util.h"

#include <dirent.h>
#include <errno.h>
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#define MAX_ROW 65536  /* a summary line, bytes */

/* The summary's columns, in order (summary.csv's header; summary.jsonl's keys). */
static const char *const columns[] = {"name",         "input",   "status",      "exit",    "category",
                                      "pieces",       "darts",   "goals_met",   "worst_strain",
                                      "seconds",      "peak_rss_mb", "resumed", "shard",   "error"};
#define COLUMN_COUNT ((int)(sizeof columns / sizeof columns[0]))

const char *bt_category(pz_status status)
{
    switch (status) {
    case PZ_OK: return "ok";
    case PZ_ERR_USAGE: return "usage";
    case PZ_ERR_DATA:
    case PZ_ERR_INVALID_MESH: return "data";
    case PZ_ERR_OPEN: return "open";
    case PZ_ERR_CREATE: return "create";
    case PZ_ERR_NOMEM: return "memory";
    case PZ_ERR_CANCELLED: return "cancelled";
    case PZ_ERR_INTERNAL:
    default: return "internal";
    }
}

cJSON *bt_row(const pz_batch_garment *garment, const char *state, int exit_code, const char *category,
              const pz_batch_outcome *outcome, double seconds, double peak_rss_mb, int32_t shard)
{
    cJSON *row = cJSON_CreateObject();
    int written = outcome && outcome->status == PZ_OK;
    int ok = row && cJSON_AddStringToObject(row, "name", garment->name) &&
             cJSON_AddStringToObject(row, "input", garment->path) && cJSON_AddStringToObject(row, "status", state) &&
             cJSON_AddNumberToObject(row, "exit", exit_code) && cJSON_AddStringToObject(row, "category", category);
    ok = ok && (written ? cJSON_AddNumberToObject(row, "pieces", outcome->pieces) != NULL
                        : cJSON_AddNullToObject(row, "pieces") != NULL);
    ok = ok && (written ? cJSON_AddNumberToObject(row, "darts", outcome->darts) != NULL
                        : cJSON_AddNullToObject(row, "darts") != NULL);
    ok = ok && (written && outcome->goals_judged ? cJSON_AddBoolToObject(row, "goals_met", outcome->goals_met) != NULL
                                                 : cJSON_AddNullToObject(row, "goals_met") != NULL);
    ok = ok && (written && outcome->worst_strain >= 0
                    ? cJSON_AddNumberToObject(row, "worst_strain", pz_round(outcome->worst_strain, 6)) != NULL
                    : cJSON_AddNullToObject(row, "worst_strain") != NULL);
    ok = ok && (seconds >= 0 ? cJSON_AddNumberToObject(row, "seconds", pz_round(seconds, 3)) != NULL
                             : cJSON_AddNullToObject(row, "seconds") != NULL);
    ok = ok && (peak_rss_mb >= 0 ? cJSON_AddNumberToObject(row, "peak_rss_mb", pz_round(peak_rss_mb, 1)) != NULL
                                 : cJSON_AddNullToObject(row, "peak_rss_mb") != NULL);
    ok = ok && cJSON_AddFalseToObject(row, "resumed") && cJSON_AddNumberToObject(row, "shard", shard);
    ok = ok && cJSON_AddStringToObject(row, "error", outcome && outcome->status != PZ_OK ? outcome->message : "");
    if (!ok) {
        cJSON_Delete(row);
        return NULL;
    }
    return row;
}

/* ---------------------------------------------------------------- writing */

/* One CSV field: quoted when it holds a comma, a quote or a line break (RFC 4180). */
static void csv_field(FILE *file, const cJSON *value)
{
    if (!value || cJSON_IsNull(value))
        return;
    if (cJSON_IsBool(value)) {
        fputs(cJSON_IsTrue(value) ? "true" : "false", file);
        return;
    }
    if (cJSON_IsNumber(value)) {
        pz_put_plain_number(file, value->valuedouble);
        return;
    }
    const char *text = cJSON_IsString(value) ? value->valuestring : "";
    if (!strpbrk(text, ",\"\r\n")) {
        fputs(text, file);
        return;
    }
    fputc('"', file);
    for (const char *c = text; *c; ++c) {
        if (*c == '"')
            fputc('"', file);
        fputc(*c, file);
    }
    fputc('"', file);
}

static pz_status write_csv(const char *path, cJSON *const *rows, int32_t count, pz_ctx *ctx)
{
    pz_output out;
    pz_status status = pz_output_open(&out, path, "wb", ctx);
    if (status != PZ_OK)
        return status;
    for (int c = 0; c < COLUMN_COUNT; ++c)
        fprintf(out.file, "%s%s", c ? "," : "", columns[c]);
    fputc('\n', out.file);
    for (int32_t i = 0; i < count; ++i) {
        for (int c = 0; c < COLUMN_COUNT; ++c) {
            if (c)
                fputc(',', out.file);
            csv_field(out.file, cJSON_GetObjectItemCaseSensitive(rows[i], columns[c]));
        }
        fputc('\n', out.file);
    }
    return pz_output_commit(&out, ctx);
}

static pz_status write_jsonl(const char *path, cJSON *const *rows, int32_t count, pz_ctx *ctx)
{
    pz_output out;
    pz_status status = pz_output_open(&out, path, "wb", ctx);
    if (status != PZ_OK)
        return status;
    for (int32_t i = 0; i < count && status == PZ_OK; ++i) {
        char *text = cJSON_PrintUnformatted(rows[i]);
        if (!text) {
            status = pz_error(ctx, PZ_ERR_NOMEM, "%s: out of memory", path);
            break;
        }
        fputs(text, out.file);
        fputc('\n', out.file);
        free(text);
    }
    if (status != PZ_OK) {
        pz_output_abort(&out);
        return status;
    }
    return pz_output_commit(&out, ctx);
}

pz_status bt_write_summary(const char *base, cJSON *const *rows, int32_t count, pz_ctx *ctx)
{
    size_t size = strlen(base) + 8;
    char *path = malloc(size);
    if (!path)
        return pz_error(ctx, PZ_ERR_NOMEM, "batch: out of memory");
    snprintf(path, size, "%s.jsonl", base);
    pz_status status = write_jsonl(path, rows, count, ctx);
    snprintf(path, size, "%s.csv", base);
    if (status == PZ_OK)
        status = write_csv(path, rows, count, ctx);
    free(path);
    return status;
}

pz_status bt_write_marker(const char *folder, const cJSON *row, pz_ctx *ctx)
{
    char *path = bt_join(folder, BT_MARKER_NAME);
    char *text = cJSON_Print(row);
    pz_status status = PZ_OK;
    pz_output out;
    if (!path || !text)
        status = pz_error(ctx, PZ_ERR_NOMEM, "batch: out of memory");
    else if ((status = pz_output_open(&out, path, "wb", ctx)) == PZ_OK) {
        fputs(text, out.file);
        fputc('\n', out.file);
        status = pz_output_commit(&out, ctx);
    }
    free(path), free(text);
    return status;
}

/* The whole of a small file (at most `limit` bytes), or NULL. */
static char *read_small_file(const char *path, long limit)
{
    FILE *file = fopen(path, "rb");
    if (!file)
        return NULL;
    char *text = malloc((size_t)limit + 1);
    size_t length = text ? fread(text, 1, (size_t)limit + 1, file) : 0;
    fclose(file);
    if (!text || length > (size_t)limit) {
        free(text);
        return NULL;
    }
    text[length] = '\0';
    return text;
}

cJSON *bt_read_marker(const char *folder, const char *name)
{
    char *path = bt_join(folder, BT_MARKER_NAME);
    char *text = path ? read_small_file(path, MAX_ROW) : NULL;
    cJSON *row = text ? cJSON_Parse(text) : NULL;
    free(path), free(text);
    const cJSON *status = cJSON_GetObjectItemCaseSensitive(row, "status");
    const cJSON *own_name = cJSON_GetObjectItemCaseSensitive(row, "name");
    if (!cJSON_IsObject(row) || !cJSON_IsString(status) || strcmp(status->valuestring, "ok") != 0 ||
        !cJSON_IsString(own_name) || strcmp(own_name->valuestring, name) != 0) {
        cJSON_Delete(row);
        return NULL;
    }
    return row;
}

/* ---------------------------------------------------------------- merge */

typedef struct rows {
    cJSON **items;
    int32_t count, capacity;
} rows;

static int push(rows *list, cJSON *row)
{
    if (list->count == list->capacity) {
        int32_t capacity = list->capacity ? 2 * list->capacity : 256;
        cJSON **items = realloc(list->items, (size_t)capacity * sizeof *items);
        if (!items)
            return 0;
        list->items = items, list->capacity = capacity;
    }
    list->items[list->count++] = row;
    return 1;
}

static void rows_clear(rows *list)
{
    for (int32_t i = 0; i < list->count; ++i)
        cJSON_Delete(list->items[i]);
    free(list->items);
}

/* Reads one shard's summary-I-of-N.jsonl, each line a row with a name and a status. */
static pz_status read_shard(const char *path, rows *list, pz_ctx *ctx)
{
    FILE *file = NULL;
    pz_status status = pz_input_open(path, &file, ctx);
    if (status != PZ_OK)
        return pz_error(ctx, status, "batch: %s", ctx->error);
    char *line = malloc(MAX_ROW + 2);
    if (!line)
        status = pz_error(ctx, PZ_ERR_NOMEM, "batch: out of memory");
    for (int number = 1; status == PZ_OK && fgets(line, MAX_ROW + 2, file); ++number) {
        if (line[0] == '\n')
            continue;
        cJSON *row = strlen(line) <= MAX_ROW ? cJSON_Parse(line) : NULL;
        const cJSON *name = cJSON_GetObjectItemCaseSensitive(row, "name");
        const cJSON *state = cJSON_GetObjectItemCaseSensitive(row, "status");
        if (!cJSON_IsObject(row) || !cJSON_IsString(name) || !cJSON_IsString(state)) {
            cJSON_Delete(row);
            status = pz_error(ctx, PZ_ERR_DATA, "batch: %s: line %d is not a summary row", path, number);
        } else if (!push(list, row)) {
            cJSON_Delete(row);
            status = pz_error(ctx, PZ_ERR_NOMEM, "batch: out of memory");
        }
    }
    fclose(file);
    free(line);
    return status;
}

static int row_by_name(const void *a, const void *b)
{
    const cJSON *left = cJSON_GetObjectItemCaseSensitive(*(cJSON *const *)a, "name");
    const cJSON *right = cJSON_GetObjectItemCaseSensitive(*(cJSON *const *)b, "name");
    return strcmp(left->valuestring, right->valuestring);
}

void bt_count_rows(cJSON *const *items, int32_t count, pz_batch_totals *totals)
{
    for (int32_t i = 0; i < count; ++i) {
        const char *state = cJSON_GetObjectItemCaseSensitive(items[i], "status")->valuestring;
        ++totals->garments;
        if (strcmp(state, "ok") == 0) {
            ++totals->ok;
            totals->resumed += cJSON_IsTrue(cJSON_GetObjectItemCaseSensitive(items[i], "resumed"));
        } else if (strcmp(state, "pending") == 0) {
            ++totals->pending;
        } else {
            ++totals->failed;
        }
    }
}

/* The N of the shard summaries in outroot (-1 when two differ, 0 when there are none); marks present[I]. */
static int32_t shard_files(const char *outroot, unsigned char **present, pz_ctx *ctx, pz_status *status)
{
    DIR *dir = opendir(outroot);
    *present = NULL;
    if (!dir) {
        *status = pz_error(ctx, PZ_ERR_OPEN, "batch: %s: cannot read the folder: %s", outroot, strerror(errno));
        return 0;
    }
    int32_t shards = 0;
    for (struct dirent *entry; *status == PZ_OK && (entry = readdir(dir));) {
        int index = 0, count = 0, used = 0;
        if (sscanf(entry->d_name, "summary-%d-of-%d.jsonl%n", &index, &count, &used) != 2 ||
            entry->d_name[used] != '\0' || count < 1 || count > 100000 || index < 0 || index >= count)
            continue;
        if (shards && count != shards) {
            *status = pz_error(ctx, PZ_ERR_DATA, "batch: %s: summaries of %d and of %d shards (remove the stale ones)",
                               outroot, (int)shards, count);
        } else if (!shards && !(*present = calloc((size_t)count, 1))) {
            *status = pz_error(ctx, PZ_ERR_NOMEM, "batch: out of memory");
        } else {
            shards = count;
            (*present)[index] = 1;
        }
    }
    closedir(dir);
    return shards;
}

pz_status pz_batch_merge(const char *outroot, pz_batch_totals *totals, pz_ctx *ctx)
{
    memset(totals, 0, sizeof *totals);
    double start = pz_seconds();
    unsigned char *present = NULL;
    pz_status status = PZ_OK;
    int32_t shards = shard_files(outroot, &present, ctx, &status);
    if (status == PZ_OK && shards == 0)
        status = pz_error(ctx, PZ_ERR_OPEN, "batch: %s: no shard summaries (summary-I-of-N.jsonl) to merge", outroot);
    rows merged = {0};
    char name[64];
    for (int32_t i = 0; i < shards && status == PZ_OK; ++i) {
        snprintf(name, sizeof name, "summary-%d-of-%d.jsonl", (int)i, (int)shards);
        char *path = bt_join(outroot, name);
        if (!path)
            status = pz_error(ctx, PZ_ERR_NOMEM, "batch: out of memory");
        else if (!present[i])
            status = pz_error(ctx, PZ_ERR_OPEN, "batch: %s: missing (shard %d of %d has not finished)", path, (int)i,
                              (int)shards);
        else
            status = read_shard(path, &merged, ctx);
        free(path);
    }
    free(present);
    if (status == PZ_OK) {
        qsort(merged.items, (size_t)merged.count, sizeof *merged.items, row_by_name);
        for (int32_t i = 1; i < merged.count && status == PZ_OK; ++i)
            if (row_by_name(&merged.items[i - 1], &merged.items[i]) == 0)
                status = pz_error(ctx, PZ_ERR_DATA, "batch: %s: garment %s is in two shards' summaries", outroot,
                                  cJSON_GetObjectItemCaseSensitive(merged.items[i], "name")->valuestring);
    }
    char *base = bt_join(outroot, "summary");
    if (status == PZ_OK && !base)
        status = pz_error(ctx, PZ_ERR_NOMEM, "batch: out of memory");
    if (status == PZ_OK)
        status = bt_write_summary(base, merged.items, merged.count, ctx);
    if (status == PZ_OK) {
        bt_count_rows(merged.items, merged.count, totals);
        snprintf(totals->summary_csv, sizeof totals->summary_csv, "%s.csv", base);
    }
    free(base);
    rows_clear(&merged);
    totals->seconds = pz_seconds() - start;
    return status;
}

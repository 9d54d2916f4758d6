/*
 * batch/internal.h -- shared by the files of batch/ only.
 *
 * SPDX-License-Identifier: GPL-3.0-or-later
 */
#ifndef PZ_BATCH_INTERNAL_H
#define PZ_BATCH_INTERNAL_H

#include "batch/batch.h"

#include <cjson/cJSON.h>

/* The marker written last into a garment's folder: its summary row (batch/summary.c). */
#define BT_MARKER_NAME "batch.json"

/* "A/B" (malloc'd), or NULL when out of memory. */
char *bt_join(const char *folder, const char *name);

/* A summary row (a cJSON object; the caller deletes it) from one garment's outcome. `state` is "ok",
 * "failed", "crashed", "timeout" or "pending"; exit_code and category as docs/batch.md lists them;
 * peak_rss_mb < 0 unknown. NULL when out of memory. */
cJSON *bt_row(const pz_batch_garment *garment, const char *state, int exit_code, const char *category,
              const pz_batch_outcome *outcome, double seconds, double peak_rss_mb, int32_t shard);

/* The category name and exit code of a garment's status ("data", 65; "ok", 0; ...). */
const char *bt_category(pz_status status);

/* Writes `rows` (count cJSON objects) as BASE.csv and BASE.jsonl, each atomically. */
pz_status bt_write_summary(const char *base, cJSON *const *rows, int32_t count, pz_ctx *ctx);

/* Adds the rows' statuses to totals (garments, ok, resumed, failed, pending). */
void bt_count_rows(cJSON *const *rows, int32_t count, pz_batch_totals *totals);

/* Writes one row as the garment folder's marker (atomically: temporary, sync, rename). */
pz_status bt_write_marker(const char *folder, const cJSON *row, pz_ctx *ctx);

/* The marker's row when `folder` holds a marker of garment `name` whose status is "ok" (the caller deletes
 * it); else NULL (no marker, another garment's, or not a row). */
cJSON *bt_read_marker(const char *folder, const char *name);

#endif /* PZ_BATCH_INTERNAL_H */

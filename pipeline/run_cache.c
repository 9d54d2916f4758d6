/*
 * pipeline/run_cache.c -- what one run leaves for the next run of the same
 * garment (docs/run.md, "Reuse between runs"): the mirror plane found before
 * the field, the cross-field with its mirrored version and their tracing
 * graphs. They depend on
 * the garment as laid out (positions, faces, poses), the sketch, the grain
 * hints and the field's and symmetry's options, and on nothing a designer
 * changes between two looks at a pattern (S, C, darts, the piece budget, the
 * fabric): an entry is found by a 64-bit hash of all of those, so any other
 * change simply computes them again.
 *
 * pz_run keeps its own cache between the first layout and a consolidation
 * trial when the caller gives none; the studio keeps one per garment.
 *
 * SPDX-License-Identifier: GPL-3.0-or-later
 */
#include "pipeline/internal.h"

#include "prepare/prepare.h"

#include <stdlib.h>
#include <string.h>

/* Two entries: a run that lays the symmetric garment out and then the garment as loaded (or a consolidation
 * trial that does both) finds both again. */
#define CACHE_ENTRIES 2

typedef struct cache_entry {
    uint64_t key;               /* 0: empty */
    uint64_t used;              /* the cache's clock when last stored or found: the older entry is replaced */
    pl_plane_and_field value;
} cache_entry;

struct pz_run_cache {
    cache_entry entries[CACHE_ENTRIES];
    uint64_t clock;
    int64_t hits, misses;
};

pz_run_cache *pz_run_cache_create(void)
{
    return calloc(1, sizeof(pz_run_cache));
}

void pl_plane_and_field_clear(pl_plane_and_field *value)
{
    pz_field_free(&value->field);
    pz_field_free(&value->mirror_field);
    pz_trace_graph_free(&value->graph);
    pz_trace_graph_free(&value->mirror_graph);
    pz_symmetry_clear(&value->symmetry);
    memset(value, 0, sizeof *value);
}

void pz_run_cache_free(pz_run_cache **cache)
{
    if (!cache || !*cache)
        return;
    for (int i = 0; i < CACHE_ENTRIES; ++i)
        pl_plane_and_field_clear(&(*cache)->entries[i].value);
    free(*cache);
    *cache = NULL;
}

void pz_run_cache_counts(const pz_run_cache *cache, int64_t *hits, int64_t *misses)
{
    *hits = cache ? cache->hits : 0;
    *misses = cache ? cache->misses : 0;
}

/* ---------------------------------------------------------------- the key */

/* FNV-1a, 64 bits, over `size` bytes (a content hash, not a defence: the inputs are the caller's own). */
static uint64_t hash_bytes(uint64_t hash, const void *bytes, size_t size)
{
    const unsigned char *p = bytes;
    for (size_t i = 0; i < size; ++i)
        hash = (hash ^ p[i]) * UINT64_C(1099511628211);
    return hash;
}

static uint64_t hash_int(uint64_t hash, int64_t value)
{
    return hash_bytes(hash, &value, sizeof value);
}

static uint64_t hash_sketch(uint64_t hash, const pz_sketch *sketch)
{
    if (!sketch || sketch->curve_count == 0)
        return hash_int(hash, -1);
    hash = hash_int(hash, sketch->curve_count);
    hash = hash_bytes(hash, sketch->curve_offsets, ((size_t)sketch->curve_count + 1) * sizeof(int32_t));
    return hash_bytes(hash, sketch->points, 3 * (size_t)sketch->curve_offsets[sketch->curve_count] * sizeof(double));
}

pz_status pl_plane_and_field_key(const pz_run_options *options, const pz_prepare_result *prepared,
                                 const pz_sketch *grain_hints, const pz_symmetry *given_plane, const pz_mesh *garment,
                                 uint64_t *key, pz_ctx *ctx)
{
    uint64_t hash = UINT64_C(14695981039346656037);
    hash = hash_int(hash, garment->vertex_count);
    hash = hash_int(hash, garment->face_count);
    hash = hash_int(hash, garment->pose_count);
    hash = hash_bytes(hash, garment->positions, 3 * (size_t)garment->vertex_count * sizeof(double));
    hash = hash_bytes(hash, garment->faces, 3 * (size_t)garment->face_count * sizeof(int32_t));
    if (garment->pose_count > 0 && garment->poses)
        hash = hash_bytes(hash, garment->poses,
                          3 * (size_t)garment->pose_count * (size_t)garment->vertex_count * sizeof(double));
    /* The options they depend on, field by field (the structs hold pointers and padding). */
    hash = hash_int(hash, options->field.scale_count);
    hash = hash_bytes(hash, &options->field.smoothness, sizeof(double));
    hash = hash_int(hash, options->segment.symmetry);
    hash = hash_bytes(hash, options->segment.symmetry_plane, sizeof options->segment.symmetry_plane);
    hash = hash_int(hash, options->mirror_sketch);
    hash = hash_bytes(hash, &options->segment.graph.match_angle_deg, sizeof(double));
    hash = hash_bytes(hash, &options->segment.graph.drift_weight, sizeof(double));
    /* The designer's strokes (read again: a file may have changed), the garment's seams, the welded ones. */
    pz_sketch *designer = NULL;
    pz_status status = pl_designer_sketch(options, garment, &designer, ctx);
    if (status != PZ_OK)
        return status;
    hash = hash_sketch(hash, designer);
    pz_sketch_free(&designer);
    hash = hash_sketch(hash, options->garment_seams);
    hash = hash_sketch(hash, grain_hints);
    int32_t welded = prepared && prepared->mesh == NULL ? prepared->seam_count : 0;
    hash = hash_int(hash, welded);
    if (welded > 0) {
        hash = hash_bytes(hash, prepared->seam_offsets, ((size_t)welded + 1) * sizeof(int32_t));
        hash = hash_bytes(hash, prepared->seam_vertices, (size_t)prepared->seam_offsets[welded] * sizeof(int32_t));
    }
    /* The symmetric garment's exact maps, when given (they decide the mirrored field). */
    int given = given_plane && given_plane->vertex_count == garment->vertex_count && given_plane->vertex_mirror;
    hash = hash_int(hash, given);
    if (given)
        hash = hash_bytes(hash, given_plane->vertex_mirror, (size_t)given_plane->vertex_count * sizeof(int32_t));
    *key = hash ? hash : 1; /* 0 marks an empty entry */
    return PZ_OK;
}

/* ---------------------------------------------------------------- entries */

/* A deep copy of `from` into *to (cleared first). */
static pz_status copy_value(const pl_plane_and_field *from, pl_plane_and_field *to, pz_ctx *ctx)
{
    pl_plane_and_field_clear(to);
    to->plane = from->plane;
    to->sketch_asymmetric = from->sketch_asymmetric;
    to->field_ms = from->field_ms;
    pz_status status = pz_symmetry_copy(&from->symmetry, &to->symmetry, ctx);
    if (status == PZ_OK && from->field)
        status = pz_field_copy(from->field, &to->field, ctx);
    if (status == PZ_OK && from->mirror_field)
        status = pz_field_copy(from->mirror_field, &to->mirror_field, ctx);
    if (status == PZ_OK && from->graph)
        status = pz_trace_graph_copy(from->graph, &to->graph, ctx);
    if (status == PZ_OK && from->mirror_graph)
        status = pz_trace_graph_copy(from->mirror_graph, &to->mirror_graph, ctx);
    if (status != PZ_OK)
        pl_plane_and_field_clear(to);
    return status;
}

pz_status pl_run_cache_find(pz_run_cache *cache, uint64_t key, pl_plane_and_field *out, int *found, pz_ctx *ctx)
{
    *found = 0;
    if (!cache)
        return PZ_OK;
    for (int i = 0; i < CACHE_ENTRIES; ++i)
        if (cache->entries[i].key == key && cache->entries[i].value.field) {
            pz_status status = copy_value(&cache->entries[i].value, out, ctx);
            if (status != PZ_OK)
                return status;
            cache->entries[i].used = ++cache->clock;
            ++cache->hits;
            *found = 1;
            return PZ_OK;
        }
    ++cache->misses;
    return PZ_OK;
}

pz_status pl_run_cache_keep(pz_run_cache *cache, uint64_t key, const pl_plane_and_field *value, pz_ctx *ctx)
{
    if (!cache || !value->field)
        return PZ_OK;
    cache_entry *oldest = &cache->entries[0];
    for (int i = 0; i < CACHE_ENTRIES; ++i) {
        if (cache->entries[i].key == key) {
            oldest = &cache->entries[i];
            break;
        }
        if (cache->entries[i].used < oldest->used)
            oldest = &cache->entries[i];
    }
    oldest->key = 0;
    pz_status status = copy_value(value, &oldest->value, ctx);
    if (status == PZ_OK) {
        oldest->key = key;
        oldest->used = ++cache->clock;
    }
    return status;
}

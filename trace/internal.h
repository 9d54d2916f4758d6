/*
 * trace/internal.h -- what the files of trace/ share (not public): path
 * measuring and a binary min-heap for the Dijkstra searches. Items are ordered by key, then by item
 * index, so equal keys pop in a fixed order and every search is deterministic.
 * Stale entries are left in the heap (lazy deletion): the caller skips an
 * item whose key is larger than its current distance.
 *
 * SPDX-License-Identifier: GPL-3.0-or-later
 */
#ifndef PZ_TRACE_INTERNAL_H
#define PZ_TRACE_INTERNAL_H

#include "trace/trace.h"

#include <stdint.h>
#include <stdlib.h>

/*
 * Recomputes path->length_mm and path->cost from its vertices and arms: the
 * cost of a step is the weight of the graph link from (vertex, arm) to the
 * next vertex, or its length times 1 + drift_weight when there is no such
 * link (a step off the field). (trace/paths.c)
 */
void trace_path_measure(const pz_trace_graph *graph, const pz_mesh *mesh, pz_trace_path *path);

typedef struct trace_heap {
    double *keys;
    int32_t *items;
    size_t count, capacity;
} trace_heap;

static inline int trace_heap_less(const trace_heap *heap, size_t a, size_t b)
{
    return heap->keys[a] < heap->keys[b] || (heap->keys[a] == heap->keys[b] && heap->items[a] < heap->items[b]);
}

static inline void trace_heap_swap(trace_heap *heap, size_t a, size_t b)
{
    double key = heap->keys[a];
    int32_t item = heap->items[a];
    heap->keys[a] = heap->keys[b], heap->items[a] = heap->items[b];
    heap->keys[b] = key, heap->items[b] = item;
}

/* Returns 0 when out of memory (the heap is unchanged). */
static inline int trace_heap_push(trace_heap *heap, double key, int32_t item)
{
    if (heap->count == heap->capacity) {
        size_t capacity = heap->capacity ? 2 * heap->capacity : 256;
        double *keys = realloc(heap->keys, capacity * sizeof *keys);
        if (!keys)
            return 0;
        heap->keys = keys;
        int32_t *items = realloc(heap->items, capacity * sizeof *items);
        if (!items)
            return 0;
        heap->items = items;
        heap->capacity = capacity;
    }
    size_t i = heap->count++;
    heap->keys[i] = key, heap->items[i] = item;
    while (i > 0 && trace_heap_less(heap, i, (i - 1) / 2)) {
        trace_heap_swap(heap, i, (i - 1) / 2);
        i = (i - 1) / 2;
    }
    return 1;
}

/* Pops the smallest entry into *key, *item; returns 0 when the heap is empty. */
static inline int trace_heap_pop(trace_heap *heap, double *key, int32_t *item)
{
    if (heap->count == 0)
        return 0;
    *key = heap->keys[0], *item = heap->items[0];
    heap->keys[0] = heap->keys[--heap->count], heap->items[0] = heap->items[heap->count];
    size_t i = 0;
    for (;;) {
        size_t smallest = i, left = 2 * i + 1, right = left + 1;
        if (left < heap->count && trace_heap_less(heap, left, smallest))
            smallest = left;
        if (right < heap->count && trace_heap_less(heap, right, smallest))
            smallest = right;
        if (smallest == i)
            break;
        trace_heap_swap(heap, i, smallest);
        i = smallest;
    }
    return 1;
}

static inline void trace_heap_free(trace_heap *heap)
{
    free(heap->keys), free(heap->items);
    heap->keys = NULL, heap->items = NULL, heap->count = heap->capacity = 0;
}

#endif

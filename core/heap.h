/*
 * core/heap.h -- a binary min-heap of (key, item) pairs, shared by the
 * stages' shortest-path searches (header only).
 *
 * Entries are ordered by key, then by item, a total order: the pop sequence
 * is the same whatever the order of the pushes or the implementation, so
 * searches stay deterministic when several keys are equal (common on
 * symmetric meshes). Zero-initialize a heap; pz_heap_free releases it.
 *
 * SPDX-License-Identifier: GPL-3.0-or-later
 */
#ifndef PZ_CORE_HEAP_H
#define PZ_CORE_HEAP_H

#include <stddef.h>
#include <stdint.h>
#include <stdlib.h>

typedef struct pz_heap {
    double *keys;
    int32_t *items;
    size_t count, capacity;
} pz_heap;

static inline int pz_heap_less(const pz_heap *heap, size_t a, size_t b)
{
    return heap->keys[a] < heap->keys[b] || (heap->keys[a] == heap->keys[b] && heap->items[a] < heap->items[b]);
}

static inline void pz_heap_swap(pz_heap *heap, size_t a, size_t b)
{
    double key = heap->keys[a];
    int32_t item = heap->items[a];
    heap->keys[a] = heap->keys[b], heap->items[a] = heap->items[b];
    heap->keys[b] = key, heap->items[b] = item;
}

/* Adds (key, item). Returns 0 when out of memory (the heap is unchanged). O(log n). */
static inline int pz_heap_push(pz_heap *heap, double key, int32_t item)
{
    if (heap->count == heap->capacity) {
        size_t capacity = heap->capacity ? 2 * heap->capacity : 256;
        double *keys = (double *)realloc(heap->keys, capacity * sizeof *keys); /* casts: C++ includes it too */
        if (!keys)
            return 0;
        heap->keys = keys;
        int32_t *items = (int32_t *)realloc(heap->items, capacity * sizeof *items);
        if (!items)
            return 0;
        heap->items = items;
        heap->capacity = capacity;
    }
    size_t i = heap->count++;
    heap->keys[i] = key, heap->items[i] = item;
    while (i > 0 && pz_heap_less(heap, i, (i - 1) / 2)) {
        pz_heap_swap(heap, i, (i - 1) / 2);
        i = (i - 1) / 2;
    }
    return 1;
}

/* Pops the smallest entry into *key, *item (either may be NULL); returns 0 when the heap is empty. */
static inline int pz_heap_pop(pz_heap *heap, double *key, int32_t *item)
{
    if (heap->count == 0)
        return 0;
    if (key)
        *key = heap->keys[0];
    if (item)
        *item = heap->items[0];
    heap->keys[0] = heap->keys[--heap->count], heap->items[0] = heap->items[heap->count];
    size_t i = 0;
    for (;;) {
        size_t smallest = i, left = 2 * i + 1, right = left + 1;
        if (left < heap->count && pz_heap_less(heap, left, smallest))
            smallest = left;
        if (right < heap->count && pz_heap_less(heap, right, smallest))
            smallest = right;
        if (smallest == i)
            break;
        pz_heap_swap(heap, i, smallest);
        i = smallest;
    }
    return 1;
}

/* Empties the heap, keeping its memory for the next search. */
static inline void pz_heap_clear(pz_heap *heap) { heap->count = 0; }

static inline void pz_heap_free(pz_heap *heap)
{
    free(heap->keys), free(heap->items);
    heap->keys = NULL, heap->items = NULL, heap->count = heap->capacity = 0;
}

#endif /* PZ_CORE_HEAP_H */

/*
 * core/util.h -- small containers shared by every stage (header only):
 * growing arrays, array copies and union-find.
 *
 * SPDX-License-Identifier: GPL-3.0-or-later
 */
#ifndef PZ_CORE_UTIL_H
#define PZ_CORE_UTIL_H

#include <math.h>
#include <stddef.h>
#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

/* A copy of `count` elements of `size` bytes (malloc'd, the caller's), or NULL for a NULL source; sets *failed
 * when out of memory (a run of copies checks once). */
static inline void *pz_copy_array(const void *source, size_t count, size_t size, int *failed)
{
    if (!source)
        return NULL;
    void *copy = malloc(count * size + 1);
    if (!copy) {
        *failed = 1;
        return NULL;
    }
    memcpy(copy, source, count * size);
    return copy;
}

/*
 * Makes room for `needed` elements of `element_size` bytes in *data, doubling
 * the capacity (from 64) so that n appends cost O(n). Returns 0 when out of
 * memory or when the size would overflow; *data is then unchanged.
 */
static inline int pz_grow(void **data, size_t *capacity, size_t needed, size_t element_size)
{
    if (needed <= *capacity)
        return 1;
    /* No object may be larger than PTRDIFF_MAX bytes: refuse before asking (and before doubling could wrap). */
    size_t most = (size_t)PTRDIFF_MAX / element_size;
    if (needed > most)
        return 0;
    size_t grown = *capacity ? *capacity : 64;
    while (grown < needed)
        grown *= 2;
    if (grown > most)
        grown = needed;
    void *bigger = realloc(*data, grown * element_size);
    if (!bigger)
        return 0;
    *data = bigger;
    *capacity = grown;
    return 1;
}

/* A number as a person reads it in a table or a report: whole numbers without a fraction, others with 6
 * significant digits (summary.csv, report.html). */
static inline void pz_put_plain_number(FILE *file, double number)
{
    if (number == floor(number) && fabs(number) < 1e15)
        fprintf(file, "%.0f", number);
    else
        fprintf(file, "%.6g", number);
}

/* Union-find over int32 ids with path halving; parent[x] == x marks a root. */
static inline int32_t pz_union_find_root(int32_t *parent, int32_t x)
{
    while (parent[x] != x) {
        parent[x] = parent[parent[x]];
        x = parent[x];
    }
    return x;
}

/* Joins the sets of a and b; the smaller root id wins, so results are deterministic. */
static inline void pz_union_find_join(int32_t *parent, int32_t a, int32_t b)
{
    a = pz_union_find_root(parent, a);
    b = pz_union_find_root(parent, b);
    if (a != b)
        parent[a > b ? a : b] = a < b ? a : b;
}

#endif /* PZ_CORE_UTIL_H */

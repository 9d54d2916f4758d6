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

#include "core/heap.h"
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


#endif

/*
 * tests/trace/trace_fixtures.h -- what the trace tests share: the edge test
 * every path check needs.
 *
 * SPDX-License-Identifier: GPL-3.0-or-later
 */
#ifndef PZ_TRACE_FIXTURES_H
#define PZ_TRACE_FIXTURES_H

#include "mesh/mesh.h"

/* 1 when vertices a and b share a mesh edge. */
static inline int test_share_edge(const pz_topology *topology, int32_t a, int32_t b)
{
    int32_t ring[256];
    int32_t count = pz_topology_vertex_ring(topology, a, ring, 256);
    for (int32_t i = 0; i < count && i < 256; ++i)
        if (ring[i] == b)
            return 1;
    return 0;
}

#endif

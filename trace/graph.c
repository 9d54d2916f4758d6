/*
 * trace/graph.c -- (being written)
 *
 * SPDX-License-Identifier: GPL-3.0-or-later
 */
#include "trace/trace.h"
#include <stdlib.h>
#include <string.h>

pz_status pz_trace_graph_build(const pz_mesh *mesh, const pz_topology *topology, const double *face_arms,
                               const pz_trace_graph_options *options, pz_trace_graph **out, pz_ctx *ctx)
{
    (void)mesh; (void)topology; (void)face_arms; (void)options; *out = NULL;
    return pz_error(ctx, PZ_ERR_INTERNAL, "trace: not written yet");
}
void pz_trace_graph_free(pz_trace_graph **graph) { (void)graph; }

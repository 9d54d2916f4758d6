/*
 * mesh/describe.c -- what a mesh is, valid or not (`panelize info`).
 *
 * A valid mesh gets its half-edge topology: components, boundary loops with
 * their lengths, Euler characteristic and genus. An invalid one cannot have
 * it (topology needs an edge-manifold, consistently oriented mesh), so what
 * needs no manifoldness is counted instead: components by union-find over
 * the vertices of each face, edges by sorting undirected vertex pairs (both
 * O(F log F)), and the Euler characteristic from those counts; boundary
 * loops and genus are then unknown (-1).
 *
 * SPDX-License-Identifier: GPL-3.0-or-later
 */
#include "mesh/mesh.h"

#include <math.h>
#include <stdlib.h>
#include <string.h>

void pz_mesh_description_clear(pz_mesh_description *description)
{
    pz_validation_clear(&description->validation);
    free(description->loop_vertex_counts);
    free(description->loop_lengths);
    memset(description, 0, sizeof *description);
}

/* ---------------------------------------------------------------- robust counts for invalid meshes */

static int vertex_in_range(const pz_mesh *mesh, int32_t v)
{
    return v >= 0 && v < mesh->vertex_count;
}

/* Vertices that some face references through an in-range index. */
static pz_status count_referenced(const pz_mesh *mesh, int32_t *referenced_count, pz_ctx *ctx)
{
    uint8_t *referenced = calloc((size_t)mesh->vertex_count + 1, 1);
    if (!referenced)
        return pz_error(ctx, PZ_ERR_NOMEM, "out of memory counting vertices");
    for (int32_t c = 0; c < 3 * mesh->face_count; ++c)
        if (vertex_in_range(mesh, mesh->faces[c]))
            referenced[mesh->faces[c]] = 1;
    int32_t total = 0;
    for (int32_t v = 0; v < mesh->vertex_count; ++v)
        total += referenced[v];
    free(referenced);
    *referenced_count = total;
    return PZ_OK;
}

static int compare_u64(const void *a, const void *b)
{
    uint64_t x = *(const uint64_t *)a, y = *(const uint64_t *)b;
    return (x > y) - (x < y);
}

/* Distinct undirected edges between two different in-range vertices. */
static pz_status count_edges(const pz_mesh *mesh, int32_t *edge_count, pz_ctx *ctx)
{
    uint64_t *keys = malloc(((size_t)mesh->face_count * 3 + 1) * sizeof *keys);
    if (!keys)
        return pz_error(ctx, PZ_ERR_NOMEM, "out of memory counting edges");
    size_t key_count = 0;
    for (int32_t f = 0; f < mesh->face_count; ++f)
        for (int k = 0; k < 3; ++k) {
            int32_t a = mesh->faces[3 * f + k], b = mesh->faces[3 * f + (k + 1) % 3];
            if (a == b || !vertex_in_range(mesh, a) || !vertex_in_range(mesh, b))
                continue;
            uint32_t low = (uint32_t)(a < b ? a : b), high = (uint32_t)(a < b ? b : a);
            keys[key_count++] = (uint64_t)low << 32 | high;
        }
    qsort(keys, key_count, sizeof *keys, compare_u64);
    int32_t distinct = 0;
    for (size_t i = 0; i < key_count; ++i)
        if (i == 0 || keys[i] != keys[i - 1])
            ++distinct;
    free(keys);
    *edge_count = distinct;
    return PZ_OK;
}

/* ---------------------------------------------------------------- analysis */

static double loop_length(const pz_mesh *mesh, const int32_t *vertices, int32_t count)
{
    double length = 0.0;
    for (int32_t i = 0; i < count; ++i) {
        const double *a = mesh->positions + 3 * (size_t)vertices[i];
        const double *b = mesh->positions + 3 * (size_t)vertices[(i + 1) % count];
        length += sqrt((a[0] - b[0]) * (a[0] - b[0]) + (a[1] - b[1]) * (a[1] - b[1]) + (a[2] - b[2]) * (a[2] - b[2]));
    }
    return length;
}

/* Topology of a valid mesh: components, edges, Euler, genus and boundary loops. */
static pz_status analyse_topology(const pz_mesh *mesh, pz_mesh_description *report, pz_ctx *ctx)
{
    pz_topology *topology = NULL;
    pz_loops *loops = NULL;
    pz_topology_summary summary;
    pz_status status = pz_topology_build(mesh, &topology, ctx);
    if (status == PZ_OK)
        status = pz_topology_summarize(topology, &summary, ctx);
    if (status == PZ_OK)
        status = pz_topology_boundary_loops(topology, &loops, ctx);
    if (status == PZ_OK) {
        int32_t count = loops->loop_count;
        report->loop_vertex_counts = malloc(((size_t)count + 1) * sizeof *report->loop_vertex_counts);
        report->loop_lengths = malloc(((size_t)count + 1) * sizeof *report->loop_lengths);
        if (!report->loop_vertex_counts || !report->loop_lengths)
            status = pz_error(ctx, PZ_ERR_NOMEM, "%s: out of memory", "mesh");
    }
    if (status == PZ_OK) {
        for (int32_t i = 0; i < loops->loop_count; ++i) {
            int32_t begin = loops->loop_offsets[i], end = loops->loop_offsets[i + 1];
            report->loop_vertex_counts[i] = end - begin;
            report->loop_lengths[i] = loop_length(mesh, loops->loop_vertices + begin, end - begin);
        }
        report->boundary_loop_count = loops->loop_count;
        report->edge_count = summary.edge_count;
        report->component_count = summary.component_count;
        report->euler_characteristic = summary.euler_characteristic;
        report->genus = summary.genus;
    }
    pz_loops_free(&loops);
    pz_topology_free(&topology);
    return status;
}

/* What can be counted without manifoldness (see the file comment). */
static pz_status analyse_robustly(const pz_mesh *mesh, pz_mesh_description *report, pz_ctx *ctx)
{
    int32_t referenced_count = 0;
    int32_t component_count = pz_mesh_face_components(mesh, NULL, ctx);
    if (component_count < 0)
        return (pz_status)component_count;
    report->component_count = component_count;
    pz_status status = count_referenced(mesh, &referenced_count, ctx);
    if (status == PZ_OK)
        status = count_edges(mesh, &report->edge_count, ctx);
    if (status == PZ_OK)
        report->euler_characteristic = referenced_count - report->edge_count + mesh->face_count;
    return status;
}

pz_status pz_mesh_describe(const pz_mesh *mesh, pz_mesh_description *report, pz_ctx *ctx)
{
    memset(report, 0, sizeof *report);
    double start = pz_seconds();
    pz_status status = pz_mesh_validate(mesh, &report->validation, ctx);
    if (status != PZ_OK)
        return status;
    report->manifold = pz_validation_ok(&report->validation);
    double validated = pz_seconds();
    report->validate_ms = 1000.0 * (validated - start);

    report->boundary_loop_count = -1;
    report->genus = -1;
    status = report->manifold ? analyse_topology(mesh, report, ctx) : analyse_robustly(mesh, report, ctx);
    if (status != PZ_OK)
        return status;
    report->topology_ms = 1000.0 * (pz_seconds() - validated);

    /* Out-of-range corners would make the geometry read outside the arrays. */
    report->area_known = report->validation.bad_indices == 0;
    report->area_mm2 = report->area_known ? pz_geom_total_area(mesh) : 0.0;
    pz_mesh_bbox(mesh, report->bbox_min, report->bbox_max);
    return PZ_OK;
}


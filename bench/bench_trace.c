/*
 * bench/bench_trace.c -- how long the tracing stage takes: the tracing graph
 * (pz_trace_graph_build) and the default candidate set (pz_trace_candidates)
 * and the mirror plane (pz_symmetry_detect, AUTO) on pz_generate's bodice at
 * 7K and 50K faces and on the shared garments (skipped when ../shared/data
 * is missing). The cross-field is computed first and not timed.
 *
 *   bench_trace [SHARED_DATA_DIR]     (default $PZ_SHARED_DATA, then ../shared/data)
 *
 * One machine-readable line per mesh:
 *
 *   bench_trace mesh=bodice-7k faces=6955 graph_ms=9.9 candidates_ms=17.9 loops=35 borders=64
 *               symmetry_ms=3.1 symmetry_axis=0 residual_rel=1.9e-08 load=1.9
 *
 * (on one line; symmetry_axis -1: no plane within the default tolerance).
 *
 * Goal (docs/trace.md): a 7K-face garment gets 50-150 candidates in well
 * under 0.5 s. Exit status 1 when a step fails on a generated mesh.
 *
 * SPDX-License-Identifier: GPL-3.0-or-later
 */
#include "field/field.h"
#include "generate/generate.h"
#include "io/io.h"
#include "segment/segment.h"
#include "trace/trace.h"

#include <stdio.h>
#include <stdlib.h>

#include "bench_util.h"

/* Times graph and candidates on a valid millimetre mesh; returns 0 on success. */
static int measure(const char *name, const pz_mesh *mesh)
{
    pz_ctx ctx;
    pz_ctx_init(&ctx);
    ctx.quiet = 1;
    pz_topology *topology = NULL;
    pz_field *field = NULL;
    pz_trace_graph *graph = NULL;
    pz_trace_paths *paths = NULL;
    pz_symmetry symmetry = {0};
    double graph_ms = 0, candidates_ms = 0, symmetry_ms = 0;
    pz_status status = pz_topology_build(mesh, &topology, &ctx);
    if (!status)
        status = pz_field_compute(mesh, topology, NULL, &field, &ctx);
    if (!status) {
        double start = pz_seconds();
        status = pz_trace_graph_build(mesh, topology, field->directions, NULL, &graph, &ctx);
        graph_ms = 1e3 * (pz_seconds() - start);
    }
    if (!status) {
        double start = pz_seconds();
        status = pz_trace_candidates(graph, mesh, topology, NULL, &paths, &ctx);
        candidates_ms = 1e3 * (pz_seconds() - start);
    }
    if (!status) {
        double start = pz_seconds();
        status = pz_symmetry_detect(mesh, topology, PZ_SYMMETRY_AUTO, NULL, 0.0, &symmetry, &ctx);
        symmetry_ms = 1e3 * (pz_seconds() - start);
    }
    if (status) {
        printf("bench_trace mesh=%s error=\"%s\"\n", name, ctx.error);
    } else {
        int loops = 0;
        for (int32_t i = 0; i < paths->path_count; ++i)
            loops += paths->paths[i].kind == PZ_TRACE_LOOP;
        printf("bench_trace mesh=%s faces=%d graph_ms=%.1f candidates_ms=%.1f loops=%d borders=%d symmetry_ms=%.1f "
               "symmetry_axis=%d residual_rel=%.2g load=%.1f\n",
               name, (int)mesh->face_count, graph_ms, candidates_ms, loops, (int)paths->path_count - loops,
               symmetry_ms, symmetry.axis, symmetry.residual_rel, bench_load_average());
    }
    fflush(stdout);
    pz_symmetry_clear(&symmetry);
    pz_trace_paths_free(&paths);
    pz_trace_graph_free(&graph);
    pz_field_free(&field);
    pz_topology_free(&topology);
    return status ? 1 : 0;
}

int main(int argc, char **argv)
{
    pz_ctx ctx;
    pz_ctx_init(&ctx);
    ctx.quiet = 1;
    int failed = 0;
    static const struct {
        int32_t faces;
        const char *name;
    } bodices[] = {{7000, "bodice-7k"}, {50000, "bodice-50k"}};
    for (size_t i = 0; i < sizeof bodices / sizeof bodices[0]; ++i) {
        pz_generate_options options = {bodices[i].faces, 0, 0};
        pz_mesh *mesh = NULL;
        if (pz_generate(PZ_SHAPE_BODICE, &options, &mesh, &ctx)) {
            printf("bench_trace mesh=%s error=\"%s\"\n", bodices[i].name, ctx.error);
            return 1;
        }
        failed |= measure(bodices[i].name, mesh);
        pz_mesh_free(&mesh);
    }
    const char *dir = argc > 1 ? argv[1] : getenv("PZ_SHARED_DATA");
    if (!dir || !*dir)
        dir = "../shared/data";
    static const char *garments[] = {"diffavatar-tshirt.obj", "diffavatar-shirt.obj", "parafashion-skirt.obj",
                                     "parafashion-dress.ply", "parafashion-leggings.ply", "parafashion-shirt.obj",
                                     "parafashion-wetsuit.obj", "shirtfront-panel.obj"};
    for (size_t i = 0; i < sizeof garments / sizeof garments[0]; ++i) {
        char path[4200];
        snprintf(path, sizeof path, "%s/garments/%s", dir, garments[i]);
        pz_mesh *mesh = NULL;
        if (pz_mesh_read(path, &mesh, &ctx)) {
            printf("bench_trace mesh=%s skipped=\"%s\"\n", garments[i], ctx.error);
            continue;
        }
        pz_mesh_to_mm(mesh, PZ_UNITS_AUTO, NULL);
        if (pz_mesh_prepare(mesh, path, PZ_REPAIR_DROP_DEGENERATE | PZ_REPAIR_DROP_DUPLICATES | PZ_REPAIR_ORIENT,
                            &ctx))
            printf("bench_trace mesh=%s skipped=\"%s\"\n", garments[i], ctx.error);
        else
            measure(garments[i], mesh);
        pz_mesh_free(&mesh);
    }
    return failed;
}

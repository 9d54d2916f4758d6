/*
 * bench/bench_load.c -- how long loading a big garment takes, and how much
 * memory: read, prepare (drop unreferenced vertices + validate), connectivity
 * and the topological summary of a ~1,000,000-face mesh, from binary PLY and
 * from OBJ.
 *
 *   bench_load [FACES]      (default 1000000)
 *
 * The mesh is pz_generate's bodice (a torus grid if generation fails), written
 * into a fresh temporary directory that is removed afterwards. Each format is
 * measured in a fresh process (this program re-executed with --measure) so
 * that the peak resident size (VmHWM in /proc/self/status) of one run does
 * not hide the next; the peak is reported over the process's size before
 * loading. One machine-readable line per format:
 *
 *   bench_load format=ply faces=1000000 vertices=500000 read_s=0.210 validate_s=0.180
 *     topology_s=0.150 summarize_s=0.020 total_s=0.560 peak_bytes_per_face=210
 *     read_peak_over_mesh=1.9
 *
 * read_peak_over_mesh: the peak after reading alone over the bytes of the mesh read (positions, faces,
 * labels, UVs): what the reader holds beside its result (issue 15: under 3 for every format). Formats:
 * binary PLY, OBJ and GLB (panelize's own writers).
 *
 * Targets (docs/mesh.md): total_s < 1 and peak_bytes_per_face < 300 on two
 * cores. Exit status 1 when a step fails (the message is on stderr).
 *
 * SPDX-License-Identifier: GPL-3.0-or-later
 */
#define _POSIX_C_SOURCE 200809L
#include "generate/generate.h"
#include "io/io.h"
#include "mesh/mesh.h"

#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/types.h>
#include <sys/wait.h>
#include <unistd.h>

#include "bench_util.h"

static int fail(const char *step, const pz_ctx *ctx)
{
    fprintf(stderr, "bench_load: %s: %s\n", step, ctx->error);
    return 1;
}

/* Loads one file and times each step; runs in its own process. */
static int measure(const char *path)
{
    pz_ctx ctx;
    pz_ctx_init(&ctx);
    ctx.quiet = 1;
    long baseline_kb = bench_status_kb("VmHWM");
    pz_mesh *mesh = NULL;
    pz_topology *topology = NULL;
    pz_topology_summary summary;
    double start = pz_seconds();
    if (pz_mesh_read(path, &mesh, &ctx))
        return fail("read", &ctx);
    double read_done = pz_seconds();
    long read_peak_kb = bench_status_kb("VmHWM");
    double mesh_bytes = (double)mesh->vertex_count * 3 * sizeof(double) +
                        (double)mesh->face_count * 3 * sizeof(int32_t) +
                        (mesh->face_labels ? (double)mesh->face_count * sizeof(int32_t) : 0) +
                        (double)mesh->uv_count * 2 * sizeof(double) +
                        (mesh->corner_uvs ? (double)mesh->face_count * 3 * sizeof(int32_t) : 0);
    if (pz_mesh_prepare(mesh, path, PZ_REPAIR_NONE, &ctx))
        return fail("validate", &ctx);
    double validate_done = pz_seconds();
    if (pz_topology_build(mesh, &topology, &ctx))
        return fail("topology", &ctx);
    double topology_done = pz_seconds();
    if (pz_topology_summarize(topology, &summary, &ctx))
        return fail("summarize", &ctx);
    double summarize_done = pz_seconds();
    long peak_kb = bench_status_kb("VmHWM");
    const char *extension = strrchr(path, '.');
    printf("bench_load format=%s faces=%d vertices=%d read_s=%.3f validate_s=%.3f topology_s=%.3f "
           "summarize_s=%.3f total_s=%.3f peak_bytes_per_face=%.0f read_peak_over_mesh=%.2f genus=%d "
           "boundary_loops=%d\n",
           extension ? extension + 1 : "?", (int)mesh->face_count, (int)mesh->vertex_count, read_done - start,
           validate_done - read_done, topology_done - validate_done, summarize_done - topology_done,
           summarize_done - start, 1024.0 * (double)(peak_kb - baseline_kb) / (mesh->face_count ? mesh->face_count : 1),
           1024.0 * (double)(read_peak_kb - baseline_kb) / (mesh_bytes > 0 ? mesh_bytes : 1),
           (int)summary.genus, (int)summary.boundary_loop_count);
    fflush(stdout);
    pz_topology_free(&topology);
    pz_mesh_free(&mesh);
    return 0;
}

/* Fallback input: a torus grid of about face_target faces. */
static pz_status torus(int32_t face_target, pz_mesh **out, pz_ctx *ctx)
{
    int32_t rows = (int32_t)sqrt(face_target / 8.0) + 3, columns = face_target / (2 * rows) + 3;
    pz_status status = pz_mesh_create(rows * columns, 2 * rows * columns, out, ctx);
    if (status)
        return status;
    pz_mesh *mesh = *out;
    const double pi = 3.14159265358979323846;
    for (int32_t j = 0; j < rows; ++j)
        for (int32_t i = 0; i < columns; ++i) {
            double u = 2 * pi * i / columns, v = 2 * pi * j / rows, *p = mesh->positions + 3 * (j * columns + i);
            p[0] = (300 + 100 * cos(v)) * cos(u);
            p[1] = (300 + 100 * cos(v)) * sin(u);
            p[2] = 100 * sin(v);
        }
    int32_t *face = mesh->faces;
    for (int32_t j = 0; j < rows; ++j)
        for (int32_t i = 0; i < columns; ++i) {
            int32_t a = j * columns + i, b = j * columns + (i + 1) % columns;
            int32_t c = ((j + 1) % rows) * columns + i, d = ((j + 1) % rows) * columns + (i + 1) % columns;
            int32_t quad[6] = {a, b, d, a, d, c};
            memcpy(face, quad, sizeof quad);
            face += 6;
        }
    return PZ_OK;
}

/* Re-executes this program to measure `path` in a fresh process. */
static int measure_in_child(const char *path)
{
    fflush(stdout);
    pid_t child = fork();
    if (child < 0) {
        perror("bench_load: fork");
        return 1;
    }
    if (child == 0) {
        execl("/proc/self/exe", "bench_load", "--measure", path, (char *)NULL);
        perror("bench_load: exec");
        _exit(127);
    }
    int child_status = 0;
    if (waitpid(child, &child_status, 0) < 0 || !WIFEXITED(child_status) || WEXITSTATUS(child_status) != 0)
        return 1;
    return 0;
}

int main(int argc, char **argv)
{
    if (argc == 3 && strcmp(argv[1], "--measure") == 0)
        return measure(argv[2]);
    int32_t face_target = argc > 1 ? (int32_t)atol(argv[1]) : 1000000;
    if (face_target < 100) {
        fprintf(stderr, "usage: bench_load [FACES]   (at least 100)\n");
        return 64;
    }
    pz_ctx ctx;
    pz_ctx_init(&ctx);
    ctx.quiet = 1;
    pz_mesh *mesh = NULL;
    pz_generate_options options = {.target_faces = face_target};
    const char *source = "bodice";
    if (pz_generate(PZ_SHAPE_BODICE, &options, &mesh, &ctx)) {
        fprintf(stderr, "bench_load: pz_generate failed (%s); using a torus\n", ctx.error);
        source = "torus";
        if (torus(face_target, &mesh, &ctx))
            return fail("torus", &ctx);
    }
    char directory[] = "/tmp/bench_load.XXXXXX";
    if (!mkdtemp(directory)) {
        perror("bench_load: mkdtemp");
        pz_mesh_free(&mesh);
        return 1;
    }
    static const char *const formats[] = {"ply", "obj", "glb"};
    enum { FORMATS = 3 };
    char paths[FORMATS][sizeof directory + 16];
    int failed = 0;
    printf("bench_load source=%s faces=%d vertices=%d\n", source, (int)mesh->face_count, (int)mesh->vertex_count);
    for (int i = 0; i < FORMATS && !failed; ++i) {
        snprintf(paths[i], sizeof paths[i], "%s/mesh.%s", directory, formats[i]);
        if (pz_mesh_write(mesh, paths[i], NULL, &ctx))
            failed = fail("write", &ctx);
    }
    pz_mesh_free(&mesh);
    for (int i = 0; i < FORMATS && !failed; ++i)
        failed = measure_in_child(paths[i]);
    for (int i = 0; i < FORMATS; ++i)
        remove(paths[i]);
    rmdir(directory);
    return failed;
}

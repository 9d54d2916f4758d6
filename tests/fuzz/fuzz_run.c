/*
 * tests/fuzz/fuzz_run.c -- libFuzzer target for the whole pipeline on tiny
 * meshes: the bytes are an OBJ file; one that parses with at most 64 faces is
 * run through pz_run (preparation, field, segmentation, flattening, the
 * verdict) with the default goals. Crashes, leaks, undefined behaviour and
 * hangs (run it with -timeout) are the bugs looked for; an error status is a
 * fine answer. Seeds: tests/fuzz/corpus/run/ (tiny meshes and the hostile
 * shapes of issue 15: a flipped face, a sliver quad, a 50-gon).
 *
 * SPDX-License-Identifier: GPL-3.0-or-later
 */
#include "io/io.h"
#include "pipeline/pipeline.h"
#include "fuzz_util.h"

int LLVMFuzzerTestOneInput(const uint8_t *data, size_t size)
{
    pz_ctx ctx;
    fuzz_ctx_init(&ctx);
    pz_mesh *mesh = NULL;
    if (pz_obj_read_memory((const char *)data, size, "fuzz.obj", &mesh, &ctx) != PZ_OK)
        return 0; /* the OBJ target looks after the parser's failures */
    if (mesh->face_count <= 64) {
        pz_run_options options;
        pz_run_options_default(&options);
        options.segment.threads = 1;
        pz_result *result = NULL;
        if (pz_run(mesh, &options, &result, &ctx) == PZ_OK)
            pz_result_free(&result);
    }
    pz_mesh_free(&mesh);
    return 0;
}

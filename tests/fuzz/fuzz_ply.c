/*
 * tests/fuzz/fuzz_ply.c -- libFuzzer target for the PLY reader: parse any
 * bytes; when they parse, validation must run on the result too. Crashes,
 * leaks, undefined behaviour and huge allocations are the bugs looked for.
 * Seeds: tests/fuzz/corpus/ply/ (copy them to a scratch directory first).
 *
 * SPDX-License-Identifier: GPL-3.0-or-later
 */
#include "mesh/mesh.h"

#include <stddef.h>
#include <stdint.h>

int LLVMFuzzerTestOneInput(const uint8_t *data, size_t size);

int LLVMFuzzerTestOneInput(const uint8_t *data, size_t size)
{
    pz_ctx ctx;
    pz_ctx_init(&ctx);
    ctx.quiet = 1;
    pz_mesh *mesh = NULL;
    if (pz_ply_read_memory(data, size, "fuzz.ply", &mesh, &ctx) == PZ_OK) {
        pz_validation validation;
        if (pz_mesh_validate(mesh, &validation, &ctx) == PZ_OK)
            pz_validation_clear(&validation);
        pz_mesh_free(&mesh);
    }
    return 0;
}

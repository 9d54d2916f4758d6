/*
 * tests/fuzz/fuzz_gltf.c -- libFuzzer target for pz_gltf_read_memory.
 *
 * Input starting with "glTF" is a GLB, anything else JSON glTF. base_dir is
 * NULL, so the reader must never touch the filesystem (external URIs fail).
 * A mesh that parses is validated too, to exercise its arrays.
 * Seeds: tests/fuzz/corpus/gltf (copy them to a scratch directory first).
 *
 * SPDX-License-Identifier: GPL-3.0-or-later
 */
#include "io/io.h"
#include "fuzz_util.h"

#include <string.h>

int LLVMFuzzerTestOneInput(const uint8_t *data, size_t size)
{
    pz_ctx ctx;
    fuzz_ctx_init(&ctx);
    pz_mesh *mesh = NULL;
    int binary = size >= 4 && memcmp(data, "glTF", 4) == 0;
    pz_status status = pz_gltf_read_memory(data, size, binary, NULL, "fuzz", &mesh, &ctx);
    return fuzz_end(status, &mesh, &ctx);
}

/*
 * tests/fuzz/fuzz_gltf.c -- libFuzzer target for pz_gltf_read_owned, as pz_mesh_read calls it (the file's
 * bytes malloc'd and freed by the reader once tinygltf has parsed them; pz_gltf_read_memory is the same
 * reader without that free).
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

#include <stdlib.h>
#include <string.h>

int LLVMFuzzerTestOneInput(const uint8_t *data, size_t size)
{
    pz_ctx ctx;
    fuzz_ctx_init(&ctx);
    pz_mesh *mesh = NULL;
    int binary = size >= 4 && memcmp(data, "glTF", 4) == 0;
    unsigned char *owned = malloc(size + 1);
    if (!owned)
        return 0;
    memcpy(owned, data, size);
    owned[size] = '\0';
    pz_status status = pz_gltf_read_owned(owned, size, binary, NULL, "fuzz", &mesh, &ctx);
    return fuzz_end(status, &mesh, &ctx);
}

/*
 * tests/fuzz/fuzz_seams.c -- libFuzzer target for the seam and dart files
 * (`--seams FILE`, `--darts K:FILE`: pz_read_seam_file, pz_read_dart_file)
 * over two panel files of 8 vertices each: any bytes, read as both. Seeds:
 * tests/fuzz/corpus/seams/.
 *
 * SPDX-License-Identifier: GPL-3.0-or-later
 */
#include "pipeline/pipeline.h"
#include "fuzz_util.h"

#include <stdio.h>
#include <stdlib.h>

int LLVMFuzzerTestOneInput(const uint8_t *data, size_t size)
{
    pz_ctx ctx;
    const char *path = fuzz_begin_file(&ctx, data, size, ".txt");
    if (!path)
        return 0;
    static const int32_t offsets[3] = {0, 8, 16};
    pz_vertex_space space = {2, offsets, NULL, 2};
    pz_seam seam = {0};
    if (pz_read_seam_file(path, &space, &seam, &ctx) == PZ_OK)
        free(seam.side_a), free(seam.side_b);
    char spec[300];
    snprintf(spec, sizeof spec, "1:%s", path);
    pz_dart dart = {0};
    if (pz_read_dart_file(spec, &space, &dart, &ctx) == PZ_OK)
        free(dart.leg_a), free(dart.leg_b);
    return 0;
}

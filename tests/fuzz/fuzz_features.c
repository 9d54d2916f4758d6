/*
 * tests/fuzz/fuzz_features.c -- libFuzzer target for the feature-curves
 * reader (`flatten --features FILE`, JSON: pl_read_features): any bytes.
 * Seeds: tests/fuzz/corpus/features/.
 *
 * SPDX-License-Identifier: GPL-3.0-or-later
 */
#include "pipeline/internal.h"
#include "fuzz_util.h"

int LLVMFuzzerTestOneInput(const uint8_t *data, size_t size)
{
    pz_ctx ctx;
    const char *path = fuzz_begin_file(&ctx, data, size, ".json");
    pl_feature_file features;
    if (path && pl_read_features(path, 10.0, &features, &ctx) == PZ_OK)
        pl_feature_file_clear(&features);
    return 0;
}

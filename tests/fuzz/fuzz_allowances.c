/*
 * tests/fuzz/fuzz_allowances.c -- libFuzzer target for the per-seam
 * allowances file (`--allowances FILE`: pz_export_read_allowances) of a
 * pattern of three panels joined by three seams: any bytes. Seeds:
 * tests/fuzz/corpus/allowances/.
 *
 * SPDX-License-Identifier: GPL-3.0-or-later
 */
#include "export/export.h"
#include "fuzz_util.h"

#include <stdlib.h>

int LLVMFuzzerTestOneInput(const uint8_t *data, size_t size)
{
    pz_ctx ctx;
    const char *path = fuzz_begin_file(&ctx, data, size, ".txt");
    if (!path)
        return 0;
    pz_seam seams[3] = {{0, 1, 0, NULL, NULL}, {1, 2, 0, NULL, NULL}, {2, 0, 0, NULL, NULL}};
    pz_pattern pattern = {0};
    pattern.panel_count = 3;
    pattern.seam_count = 3;
    pattern.seams = seams;
    double *allowances = NULL;
    if (pz_export_read_allowances(path, &pattern, &allowances, &ctx) == PZ_OK)
        free(allowances);
    return 0;
}

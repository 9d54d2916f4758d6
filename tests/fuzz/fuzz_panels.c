/*
 * tests/fuzz/fuzz_panels.c -- libFuzzer target for the panels file (`--panels
 * FILE`: one panel id per face, pz_read_panel_file) of a 16-face mesh: any
 * bytes. Seeds: tests/fuzz/corpus/panels/.
 *
 * SPDX-License-Identifier: GPL-3.0-or-later
 */
#include "pipeline/pipeline.h"
#include "fuzz_util.h"

int LLVMFuzzerTestOneInput(const uint8_t *data, size_t size)
{
    pz_ctx ctx;
    const char *path = fuzz_begin_file(&ctx, data, size, ".txt");
    int32_t face_panel[16], panel_count = 0;
    if (path)
        (void)pz_read_panel_file(path, 16, face_panel, &panel_count, &ctx);
    return 0;
}

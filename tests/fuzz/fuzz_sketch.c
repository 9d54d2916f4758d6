/*
 * tests/fuzz/fuzz_sketch.c -- libFuzzer target for the sketch reader
 * (pz_sketch_parse: `--sketch FILE`, JSON): any bytes; a sketch that parses
 * is checked against a small generated surface (pz_sketch_check), the
 * distance test a hostile sketch (1e306, 1.7 km off) must pass quickly.
 * Seeds: tests/fuzz/corpus/sketch/.
 *
 * SPDX-License-Identifier: GPL-3.0-or-later
 */
#include "field/field.h"
#include "generate/generate.h"
#include "fuzz_util.h"

#include <stdlib.h>

int LLVMFuzzerTestOneInput(const uint8_t *data, size_t size)
{
    static pz_mesh *surface;
    pz_ctx ctx;
    fuzz_ctx_init(&ctx);
    if (!surface) {
        pz_generate_options options = {500, 0, 0};
        if (pz_generate(PZ_SHAPE_HEMISPHERE, &options, &surface, &ctx) != PZ_OK)
            abort();
    }
    pz_sketch *sketch = NULL;
    if (pz_sketch_parse((const char *)data, size, "fuzz.json", 1.0, &sketch, &ctx) == PZ_OK) {
        (void)pz_sketch_check(sketch, surface, "fuzz.json", &ctx);
        pz_sketch_free(&sketch);
    }
    return 0;
}

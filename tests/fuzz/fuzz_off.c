/*
 * tests/fuzz/fuzz_off.c -- libFuzzer target for the OFF reader: parse any
 * bytes; when they parse, validation must run on the result too. Crashes,
 * leaks, undefined behaviour and huge allocations are the bugs looked for.
 * Seeds: tests/fuzz/corpus/off/ (copy them to a scratch directory first).
 *
 * SPDX-License-Identifier: GPL-3.0-or-later
 */
#include "io/io.h"
#include "fuzz_util.h"

int LLVMFuzzerTestOneInput(const uint8_t *data, size_t size)
{
    pz_ctx ctx;
    fuzz_ctx_init(&ctx);
    pz_mesh *mesh = NULL;
    pz_status status = pz_off_read_memory((const char *)data, size, "fuzz.off", &mesh, &ctx);
    return fuzz_end(status, &mesh, &ctx);
}

/*
 * tests/fuzz/fuzz_util.h -- what every libFuzzer target here does around its
 * parser call: a quiet context, and validation of whatever parsed (to
 * exercise its arrays) before it is freed. Still one target per parser:
 *
 *     pz_ctx ctx;
 *     fuzz_ctx_init(&ctx);
 *     pz_mesh *mesh = NULL;
 *     pz_status status = pz_obj_read_memory((const char *)data, size, "fuzz.obj", &mesh, &ctx);
 *     return fuzz_end(status, &mesh, &ctx);
 *
 * A mesh a failing parser leaves behind is not freed here: the leak checker
 * is to report it.
 *
 * SPDX-License-Identifier: GPL-3.0-or-later
 */
#ifndef PZ_FUZZ_UTIL_H
#define PZ_FUZZ_UTIL_H

#include "mesh/mesh.h"

#include <stddef.h>
#include <stdint.h>

int LLVMFuzzerTestOneInput(const uint8_t *data, size_t size);

static inline void fuzz_ctx_init(pz_ctx *ctx)
{
    pz_ctx_init(ctx);
    ctx->quiet = 1;
}

/* After the parser: a mesh that parsed is validated and freed. Returns 0, libFuzzer's "keep going". */
static inline int fuzz_end(pz_status status, pz_mesh **mesh, pz_ctx *ctx)
{
    if (status == PZ_OK) {
        pz_validation validation;
        if (pz_mesh_validate(*mesh, &validation, ctx) == PZ_OK)
            pz_validation_clear(&validation);
        pz_mesh_free(mesh);
    }
    return 0;
}

/*
 * The readers of the input files besides the mesh take a path: the bytes are
 * written to one scratch file per process (its name ends in `suffix`, made
 * once, rewritten for every input, removed at exit) and its path is
 * returned, NULL when it cannot be written.
 */
#include <stdio.h>
#include <stdlib.h>
#include <unistd.h>

static char fuzz_file_path[256];

static void fuzz_file_remove(void)
{
    unlink(fuzz_file_path);
}

static inline const char *fuzz_file(const uint8_t *data, size_t size, const char *suffix)
{
    char *path = fuzz_file_path;
    if (!path[0]) {
        snprintf(path, sizeof fuzz_file_path, "/tmp/pz-fuzz-%ld%s", (long)getpid(), suffix);
        atexit(fuzz_file_remove);
    }
    FILE *file = fopen(path, "wb");
    if (!file)
        return NULL;
    size_t written = fwrite(data, 1, size, file);
    return fclose(file) == 0 && written == size ? path : NULL;
}

/* The start of a file reader's target: a quiet context, the bytes in the scratch file (NULL: skip the input). */
static inline const char *fuzz_begin_file(pz_ctx *ctx, const uint8_t *data, size_t size, const char *suffix)
{
    fuzz_ctx_init(ctx);
    return fuzz_file(data, size, suffix);
}

#endif

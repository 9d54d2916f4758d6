/*
 * examples/run_bodice.c -- panelize used as a library: generates a bodice
 * (about 3000 faces), runs the whole pipeline on it (pz_run) and prints the
 * verdict. Build it against an installed panelize (docs/install.md):
 *
 *   cc run_bodice.c $(pkg-config --cflags --libs panelize) -o run_bodice
 *   ./run_bodice
 *
 * Exits 0 when the pipeline ran, whatever its verdict; 1 (with the error on
 * stderr) when it could not run.
 *
 * SPDX-License-Identifier: GPL-3.0-or-later
 */
#include "panelize.h"

#include <stdio.h>

int main(void)
{
    pz_ctx ctx;
    pz_ctx_init(&ctx);
    ctx.quiet = 1;

    pz_generate_options shape = {.target_faces = 3000};
    pz_mesh *garment = NULL;
    if (pz_generate(PZ_SHAPE_BODICE, &shape, &garment, &ctx) != PZ_OK) {
        fprintf(stderr, "run_bodice: %s\n", ctx.error);
        return 1;
    }

    pz_run_options options;
    pz_run_options_default(&options);
    options.units = PZ_UNITS_MM; /* pz_generate works in millimetres */
    options.name = "bodice";
    pz_result *result = NULL;
    if (pz_run(garment, &options, &result, &ctx) != PZ_OK) {
        fprintf(stderr, "run_bodice: %s\n", ctx.error);
        pz_mesh_free(&garment);
        return 1;
    }

    const pz_verdict *verdict = &result->verdict;
    printf("panels: %d\n", (int)result->pattern->panel_count);
    printf("darts: %d\n", (int)result->pattern->dart_count);
    printf("goals_met: %s\n", verdict->goals_met ? "yes" : "no");
    printf("worst_strain: %.4f\n", verdict->worst_strain);
    printf("reasons: %s\n", verdict->reasons[0] ? verdict->reasons : "none");

    pz_result_free(&result);
    pz_mesh_free(&garment);
    return 0;
}

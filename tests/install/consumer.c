/*
 * tests/install/consumer.c -- a program built against an installed panelize
 * by tests/install/test_install.sh (pkg-config and find_package), through the
 * public API only: generates a garment, validates it, writes it as GLB and
 * reads it back (the glTF code is C++ inside the library, so a static link
 * must bring the C++ runtime and tinygltf along). Prints what the script
 * checks: the library's version at run time and in the headers, the counts,
 * whether the mesh is valid, and the counts read back.
 *
 *   consumer SCRATCH.glb
 *
 * SPDX-License-Identifier: GPL-3.0-or-later
 */
#include "panelize.h"

#include <stdio.h>

int main(int argc, char **argv)
{
    if (argc != 2) {
        fprintf(stderr, "usage: consumer SCRATCH.glb\n");
        return 2;
    }
    printf("version: %s headers %s\n", pz_version(), PZ_VERSION_STRING);

    pz_ctx ctx;
    pz_ctx_init(&ctx);
    pz_generate_options shape = {.target_faces = 3000};
    pz_mesh *garment = NULL;
    pz_mesh *read_back = NULL;
    pz_validation validation = {0};
    int ok = pz_generate(PZ_SHAPE_BODICE, &shape, &garment, &ctx) == PZ_OK &&
             pz_mesh_validate(garment, &validation, &ctx) == PZ_OK;
    if (ok)
        printf("bodice: %d vertices, %d faces, %s\n", (int)garment->vertex_count, (int)garment->face_count,
               pz_validation_ok(&validation) ? "valid" : "invalid");
    ok = ok && pz_mesh_write(garment, argv[1], NULL, &ctx) == PZ_OK && pz_mesh_read(argv[1], &read_back, &ctx) == PZ_OK;
    if (ok)
        printf("glb: %d vertices, %d faces\n", (int)read_back->vertex_count, (int)read_back->face_count);
    else
        fprintf(stderr, "consumer: %s\n", ctx.error);
    pz_validation_clear(&validation);
    pz_mesh_free(&read_back);
    pz_mesh_free(&garment);
    return ok ? 0 : 1;
}

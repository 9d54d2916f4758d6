/*
 * io/io.h -- meshes in and out of files: the formats panelize knows (OBJ,
 * PLY, OFF, glTF 2.0), readers from files and from memory, a rest mesh read
 * with its pose files, and the writers (OBJ, PLY, plain mesh GLB).
 *
 * Readers return the file's own units (unit_scale = 1) and do not validate
 * (mesh/mesh.h: pz_mesh_to_mm, pz_mesh_prepare). Conventions as in
 * mesh/mesh.h; formats in docs/formats.md. The glTF reader and the GLB
 * writer are C++ (tinygltf) behind this header: io/gltf_read.cpp,
 * io/gltf_write.cpp.
 *
 * SPDX-License-Identifier: GPL-3.0-or-later
 */
#ifndef PZ_IO_H
#define PZ_IO_H

#include <stddef.h>
#include <stdint.h>
#include <stdio.h>

#include "mesh/mesh.h"

#ifdef __cplusplus
extern "C" {
#endif

/* ------------------------------------------------------------------------ */
/* Formats                                                                   */
/* ------------------------------------------------------------------------ */

typedef enum pz_format {
    PZ_FORMAT_UNKNOWN = 0,
    PZ_FORMAT_OBJ,
    PZ_FORMAT_PLY,
    PZ_FORMAT_OFF,
    PZ_FORMAT_GLB,   /* binary glTF */
    PZ_FORMAT_GLTF   /* JSON glTF with external or data: URI buffers */
} pz_format;

/** The format from a path's extension (case-insensitive), PZ_FORMAT_UNKNOWN otherwise. */
pz_format pz_format_from_path(const char *path);

/* ------------------------------------------------------------------------ */
/* Reading                                                                   */
/* ------------------------------------------------------------------------ */

/**
 * Reads a mesh in any supported format (chosen by extension). Errors name the
 * path: PZ_ERR_OPEN (missing or unreadable), PZ_ERR_DATA (malformed, empty,
 * index out of range, truncated). Does not validate; coordinates are in the
 * file's units (unit_scale = 1).
 */
pz_status pz_mesh_read(const char *path, pz_mesh **out, pz_ctx *ctx);

/**
 * Parsers from memory, for tests and fuzzing. `name` is used in messages.
 * OBJ: v, vt, f (v, v/vt, v//vn, v/vt/vn, negative indices), polygons
 * triangulated level by level (no fan), `g`/`o` groups become labels, other lines ignored.
 * PLY: ascii, binary_little_endian, binary_big_endian; vertex x y z,
 * face vertex_indices / vertex_index lists, optional per-vertex s t / u v /
 * texture_u texture_v (shared per vertex), other properties skipped.
 * OFF: OFF / COFF / NOFF headers, polygons triangulated likewise.
 */
pz_status pz_obj_read_memory(const char *data, size_t size, const char *name, pz_mesh **out, pz_ctx *ctx);
pz_status pz_ply_read_memory(const unsigned char *data, size_t size, const char *name, pz_mesh **out, pz_ctx *ctx);
pz_status pz_off_read_memory(const char *data, size_t size, const char *name, pz_mesh **out, pz_ctx *ctx);
/** glTF 2.0 from memory: binary GLB (`binary` = 1) or JSON (base_dir for external buffers; may be NULL). */
pz_status pz_gltf_read_memory(const unsigned char *data, size_t size, int binary, const char *base_dir,
                              const char *name, pz_mesh **out, pz_ctx *ctx);
/** The same, taking `data` (malloc'd, size + 1 bytes or more): freed as soon as tinygltf has parsed it (its model
 *  holds its own copy of the binary chunk), whatever the outcome, so that the two never stay side by side. */
pz_status pz_gltf_read_owned(unsigned char *data, size_t size, int binary, const char *base_dir, const char *name,
                             pz_mesh **out, pz_ctx *ctx);

/**
 * Loads a rest mesh plus extra pose files with identical connectivity: the
 * rest file's own poses (glTF morph targets) come first, then each pose
 * file's rest positions. A pose whose vertex or face count or face list
 * differs is PZ_ERR_DATA naming both files.
 */
pz_status pz_mesh_read_with_poses(const char *path, const char *const *pose_paths, int pose_path_count,
                                  pz_mesh **out, pz_ctx *ctx);

/* ------------------------------------------------------------------------ */
/* Writing                                                                   */
/* ------------------------------------------------------------------------ */

/** Options for writers. Zero = defaults. */
typedef struct pz_write_options {
    const uint32_t *label_colors;  /* label_count RGBA8 colours (0xRRGGBBAA) for GLB; NULL = a built-in palette */
    const char *extras_json;       /* GLB: a JSON object text stored as the asset's extras (metadata), or NULL */
    int write_poses;               /* GLB: write poses as morph targets (default 1 when 0 and poses exist: see docs) */
} pz_write_options;

/**
 * Writes a mesh, atomically (temporary file, then rename). Format by
 * extension: .obj (v, vt, f v/vt, one `g NAME` group per label run), .ply
 * (binary little endian; UVs as per-vertex s,t only when each vertex has one
 * UV), .glb. Errors: PZ_ERR_CREATE naming the path.
 */
pz_status pz_mesh_write(const pz_mesh *mesh, const char *path, const pz_write_options *options, pz_ctx *ctx);

/** Writers to an open stream (used by pz_mesh_write). */
pz_status pz_obj_write_file(const pz_mesh *mesh, FILE *file, pz_ctx *ctx);
pz_status pz_ply_write_file(const pz_mesh *mesh, FILE *file, pz_ctx *ctx);
/** GLB writer: path is the final file; writes atomically itself. */
pz_status pz_glb_write(const pz_mesh *mesh, const char *path, const pz_write_options *options, pz_ctx *ctx);

/**
 * The GLB writers' palette: 12 colours that stay apart from each other, sRGB
 * RGBA8 (0xRRGGBBAA). pz_glb_write gives label L (>= 0) colour L % 12 unless
 * options->label_colors are given; export's garment.glb colours its panels
 * with it.
 */
uint32_t pz_glb_label_color(int32_t label);

/** An sRGB RGBA8 colour (0xRRGGBBAA) as glTF stores colours: linear red, green, blue, then alpha, each in [0, 1]. */
void pz_glb_color_linear(uint32_t rgba, double linear[4]);

#ifdef __cplusplus
}
#endif

#endif /* PZ_IO_H */

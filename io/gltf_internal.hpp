/*
 * io/gltf_internal.hpp -- what io's glTF files share (C++, private to io/):
 * the names panelize gives its extras, the error that the shim throws and
 * the guard that turns it into a pz_status at the extern "C" boundary, and
 * the checked access to a loaded tinygltf model (io/gltf_model.cpp) that
 * the reader (io/gltf_read.cpp) stands on. The writer is io/gltf_write.cpp.
 * Only io.h's C functions leave these files.
 *
 * SPDX-License-Identifier: GPL-3.0-or-later
 */
#ifndef PZ_IO_GLTF_INTERNAL_HPP
#define PZ_IO_GLTF_INTERNAL_HPP

#include "io/io.h"

#include <tiny_gltf.h>

#include <cstdint>
#include <exception>
#include <new>
#include <string>
#include <vector>

namespace pz_gltf {

/* Attribute and extras names panelize writes and reads back (io/gltf_read.cpp describes them). */
const char *const kVertexIdAttribute = "_PZ_VERTEX_ID";
const char *const kLabelExtra = "pzLabel";
const char *const kFaceIdsExtra = "pzFaceIds";
const char *const kLabelNamesExtra = "pzLabelNames";

/* A failure inside the shim; turned into a pz_status at the extern "C" boundary. */
struct ShimError {
    pz_status status;
    std::string message;
};

[[noreturn]] inline void fail(pz_status status, const std::string &message)
{
    throw ShimError{status, message};
}

[[noreturn]] inline void fail_data(const std::string &message)
{
    fail(PZ_ERR_DATA, message);
}

/* tinygltf's messages are several lines, each ending in '\n': joined with "; " (io/gltf_model.cpp). */
std::string one_line(const std::string &text);

/* Runs `body` and turns whatever it throws into a status and a message. */
template <typename Body>
pz_status guarded(pz_ctx *ctx, const std::string &name, Body body)
{
    try {
        return body();
    } catch (const ShimError &error) {
        return pz_error(ctx, error.status, "%s", error.message.c_str());
    } catch (const std::bad_alloc &) {
        return pz_error(ctx, PZ_ERR_NOMEM, "%s: out of memory", name.c_str());
    } catch (const std::exception &error) {
        return pz_error(ctx, PZ_ERR_DATA, "%s: %s", name.c_str(), one_line(error.what()).c_str());
    } catch (...) {
        return pz_error(ctx, PZ_ERR_INTERNAL, "%s: unexpected failure in the glTF shim", name.c_str());
    }
}

/* ------------------------------------------------------------------ */
/* A loaded model (io/gltf_model.cpp)                                 */
/* ------------------------------------------------------------------ */

/*
 * Parses GLB (`binary`) or JSON glTF into `model`, after checking the GLB
 * container and the JSON's nesting depth; external files only from under
 * base_dir (none when NULL). Throws ShimError naming `name`.
 */
void load_model(tinygltf::Model &model, const unsigned char *data, size_t size, int binary, const char *base_dir,
                const std::string &name);

/* 4x4 column-major matrices, as glTF stores them. */
struct Matrix {
    double m[16];
};

Matrix matrix_identity();
Matrix matrix_multiply(const Matrix &a, const Matrix &b);
double matrix_determinant3(const Matrix &a);
void matrix_apply(const Matrix &a, const double *point, double *out);
/* The node's local transform: its matrix, or translation * rotation * scale. */
Matrix node_local_matrix(const tinygltf::Node &node, const std::string &what);

/* What an accessor may hold for a given use. */
enum class AccessorUse {
    Float,     /* POSITION, morph targets, _PZ_VERTEX_ID: FLOAT only */
    Texcoord,  /* FLOAT, or normalized UNSIGNED_BYTE / UNSIGNED_SHORT */
    Index      /* any integer type, not normalized */
};

/*
 * Reads accessor `index` into count x `components` doubles, checking its type
 * against `use` and every byte range against its buffer. `byte_budget` bounds
 * an accessor without a buffer view (its size is otherwise free).
 */
std::vector<double> read_accessor(const tinygltf::Model &model, int index, AccessorUse use, int components,
                                  uint64_t byte_budget, const std::string &what);

/* An index accessor (scalar integers) as 32-bit values, 4 bytes each instead of 8 (read_accessor's doubles): a
 * signed value below 0 comes out past 2^31, which the caller's range check refuses. */
std::vector<uint32_t> read_index_accessor(const tinygltf::Model &model, int index, uint64_t byte_budget,
                                          const std::string &what);

/* The element count of accessor `index`, 0 when there is no such accessor. */
uint64_t accessor_count(const tinygltf::Model &model, int index);

} // namespace pz_gltf

#endif /* PZ_IO_GLTF_INTERNAL_HPP */

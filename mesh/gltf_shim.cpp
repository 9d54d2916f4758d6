/*
 * mesh/gltf_shim.cpp -- glTF 2.0 in (binary GLB or JSON) and out (GLB), through
 * tinygltf. The only C++ in the mesh core: two extern "C" functions declared in
 * mesh.h; every exception (bad_alloc, tinygltf's, ours) is caught at that
 * boundary and becomes a pz_status with a one-line "NAME: problem" message.
 *
 * Reading (pz_gltf_read_memory)
 *  - Which geometry: the nodes of the default scene; with no default scene the
 *    nodes of every scene; with no scenes every root node (a node nobody lists
 *    as a child); with no nodes at all every mesh once, untransformed. Meshes
 *    that exist but are not reached from a node are ignored on purpose: they
 *    are not part of the scene (asset libraries keep spare meshes around).
 *  - Each node's world transform (matrix, or T * R * S, through the hierarchy)
 *    is applied to positions and poses; a mirroring transform (negative
 *    determinant) reverses the face winding so faces stay counter-clockwise.
 *    The hierarchy must be a forest: a node with two parents, or reached twice,
 *    is PZ_ERR_DATA (this also rules out cycles and the exponential blow-up of
 *    shared children). Traversal uses an explicit stack: deep chains are fine.
 *  - Primitives: TRIANGLES, TRIANGLE_STRIP and TRIANGLE_FAN (strip and fan
 *    triangles with a repeated corner, the usual strip joints, are dropped);
 *    POINTS and LINES primitives are skipped with a note. Indices of any
 *    integer component type, or none (sequential). POSITION must be FLOAT
 *    VEC3; TEXCOORD_0 FLOAT or normalized UNSIGNED_BYTE / UNSIGNED_SHORT VEC2.
 *    Sparse accessors are supported. Bounds of every accessor, buffer view and
 *    index are checked here: tinygltf does not check them.
 *  - UVs: glTF puts the UV origin at the top left, panelize (like OBJ) at the
 *    bottom left, so v is flipped (v' = 1 - v) both ways. UVs stay per corner:
 *    corners with the same vertex and the same (u, v) share one UV index. If
 *    some primitives have TEXCOORD_0 and others not, UVs are dropped (a note).
 *  - Labels: a file written by panelize (asset.generator "panelize ...")
 *    stores each face label as primitive extras {"pzLabel": L} and its name as
 *    the material name; mesh extras {"pzLabelNames": [...]} list every label,
 *    also those without faces ("" for unnamed). No pzLabel means an
 *    unlabelled mesh. When the labels were interleaved, the writer grouped
 *    the faces and each primitive's extras {"pzFaceIds": A} name an
 *    UNSIGNED_INT accessor with the original index of each of its faces: the
 *    reader restores the face order (a single mesh instance and a complete
 *    permutation only). For any other file
 *    every primitive becomes a label named after its mesh ("mesh<i>" if
 *    unnamed), plus "/MATERIAL" (or "/<primitive>") when the mesh has several
 *    primitives; primitives that end up with the same name share a label.
 *  - Morph targets become extra poses: pose k = rest + displacement k (a
 *    target without POSITION repeats the rest pose). Every triangle primitive
 *    must have the same number of targets. mesh.weights are ignored: the rest
 *    pose is the base mesh.
 *  - Vertices are not welded across primitives (a later step does that), with
 *    one exception: when every triangle primitive of a mesh has the custom
 *    attribute _PZ_VERTEX_ID (FLOAT SCALAR, written by pz_glb_write) its value
 *    is the original vertex index, and rows with the same id become one vertex
 *    again, so OBJ -> GLB -> OBJ keeps the vertex count and the face indices.
 *    Ids must be integers below the number of rows of that mesh.
 *  - External files: base_dir NULL forbids every filesystem access (only the
 *    GLB's BIN chunk and data: URIs are read); with a base_dir only files
 *    under it are read (no absolute URIs, no "..").
 *  - Guards against hostile input: the GLB header and chunk lengths are
 *    checked before tinygltf sees them (tinygltf 2.7 lets the BIN chunk run 8
 *    bytes past the end); JSON nested deeper than 64 levels is refused
 *    (tinygltf converts it recursively and would overflow the stack); an
 *    accessor without a buffer view (all zeros plus sparse values) may not
 *    declare more elements than the file has bytes; instancing may not
 *    expand the geometry beyond 16 elements per input byte.
 *  - Errors: PZ_ERR_DATA "NAME: problem" (tinygltf's messages condensed to
 *    one line), PZ_ERR_NOMEM. The data is little-endian as the spec says; the
 *    shim assumes a little-endian host.
 *
 * Writing (pz_glb_write)
 *  One buffer, one mesh, one node, one scene. One primitive per face label
 *  (one in all without labels), each with its own vertices (a vertex on a
 *  label boundary is written once per primitive) and a material named after
 *  the label whose baseColorFactor is the label's colour (options->label_colors
 *  or a 12-colour palette, taken as sRGB and stored linear as glTF wants),
 *  double sided. Per primitive: POSITION (float32 with min/max), NORMAL
 *  (area-weighted vertex normals of the whole mesh, unit length), TEXCOORD_0
 *  when the mesh has UVs (a vertex is written once per distinct UV index it
 *  has), _PZ_VERTEX_ID (float32 holds integers exactly up to 2^24 vertices; it
 *  is left out above that), UNSIGNED_INT indices, and one morph target per
 *  pose (POSITION displacement from the stored float rest position, with
 *  min/max) named in mesh.extras.targetNames. Primitives carry extras
 *  {"pzLabel": L} and, when labels interleave in the face list,
 *  {"pzFaceIds": A} (see Reading; the validator reports that accessor as
 *  unused, an info message). Vertices no face uses go into the first
 *  primitive so the vertex count survives. Every bufferView is tightly
 *  packed (no byteStride) and 4-byte aligned; those of vertex attributes and
 *  indices have their target.
 *  Positions are float32 in the file: a round trip keeps them to float
 *  precision, about 6e-8 relative (6e-5 mm on a 1 m garment in mm).
 *  asset.extras is options->extras_json through tinygltf's Value: object keys
 *  come out sorted and null values are dropped (tinygltf cannot write null).
 *  Errors: PZ_ERR_INVALID_MESH for indices, labels or UV indices out of range
 *  and non-finite or float-overflowing coordinates, PZ_ERR_USAGE for
 *  extras_json that is not a JSON object, PZ_ERR_CREATE naming the path.
 *  The file is written to a temporary name and renamed (pz_output_*).
 *
 * SPDX-License-Identifier: GPL-3.0-or-later
 */
#include "mesh.h"
#include "gltf_shim.h"

#include <tiny_gltf.h>
#include <nlohmann/json.hpp>

#include <algorithm>
#include <climits>
#include <map>
#include <cmath>
#include <cstdio>
#include <cstring>
#include <new>
#include <numeric>
#include <sstream>
#include <string>
#include <vector>

namespace {

const char *const kVertexIdAttribute = "_PZ_VERTEX_ID";
const char *const kLabelExtra = "pzLabel";
const char *const kFaceIdsExtra = "pzFaceIds";
const char *const kLabelNamesExtra = "pzLabelNames";
const char *const kGenerator = "panelize " PZ_VERSION_STRING;
/* Integers a float32 holds exactly. */
const double kFloatExactIntegers = 16777216.0;
/* Geometry may expand this many elements per input byte through instancing. */
const uint64_t kExpansionPerByte = 16;

/* A failure inside the shim; turned into a pz_status at the extern "C" boundary. */
struct ShimError {
    pz_status status;
    std::string message;
};

[[noreturn]] void fail(pz_status status, const std::string &message)
{
    throw ShimError{status, message};
}

[[noreturn]] void fail_data(const std::string &message)
{
    fail(PZ_ERR_DATA, message);
}

/* tinygltf's messages are several lines, each ending in '\n': join them with "; ". */
std::string one_line(const std::string &text)
{
    std::string line;
    bool separator_due = false;
    for (char c : text) {
        if (c == '\n' || c == '\r') {
            separator_due = !line.empty();
            continue;
        }
        if (separator_due) {
            line += "; ";
            separator_due = false;
        }
        line += c;
    }
    if (line.size() > 400) {
        line.resize(400);
        line += "...";
    }
    return line.empty() ? std::string("malformed glTF") : line;
}

/* ------------------------------------------------------------------ */
/* 4x4 column-major matrices, as glTF stores them                     */
/* ------------------------------------------------------------------ */

struct Matrix {
    double m[16];
};

Matrix matrix_identity()
{
    Matrix result{};
    result.m[0] = result.m[5] = result.m[10] = result.m[15] = 1.0;
    return result;
}

Matrix matrix_multiply(const Matrix &a, const Matrix &b)
{
    Matrix result{};
    for (int column = 0; column < 4; ++column)
        for (int row = 0; row < 4; ++row) {
            double sum = 0.0;
            for (int k = 0; k < 4; ++k)
                sum += a.m[k * 4 + row] * b.m[column * 4 + k];
            result.m[column * 4 + row] = sum;
        }
    return result;
}

double matrix_determinant3(const Matrix &a)
{
    const double *m = a.m;
    return m[0] * (m[5] * m[10] - m[9] * m[6]) - m[4] * (m[1] * m[10] - m[9] * m[2]) +
           m[8] * (m[1] * m[6] - m[5] * m[2]);
}

void matrix_apply(const Matrix &a, const double *point, double *out)
{
    const double *m = a.m;
    for (int row = 0; row < 3; ++row)
        out[row] = m[row] * point[0] + m[4 + row] * point[1] + m[8 + row] * point[2] + m[12 + row];
}

/* The node's local transform: its matrix, or translation * rotation * scale. */
Matrix node_local_matrix(const tinygltf::Node &node, const std::string &what)
{
    Matrix result = matrix_identity();
    if (!node.matrix.empty()) {
        if (node.matrix.size() != 16)
            fail_data(what + ": matrix must have 16 numbers");
        std::copy(node.matrix.begin(), node.matrix.end(), result.m);
        return result;
    }
    if ((!node.translation.empty() && node.translation.size() != 3) ||
        (!node.rotation.empty() && node.rotation.size() != 4) || (!node.scale.empty() && node.scale.size() != 3))
        fail_data(what + ": translation, rotation or scale has the wrong number of elements");
    double qx = 0, qy = 0, qz = 0, qw = 1;
    if (!node.rotation.empty()) {
        qx = node.rotation[0], qy = node.rotation[1], qz = node.rotation[2], qw = node.rotation[3];
        /* The spec wants unit quaternions; normalizing keeps a sloppy exporter's rotation a rotation. */
        double length = std::sqrt(qx * qx + qy * qy + qz * qz + qw * qw);
        if (length > 0 && std::isfinite(length))
            qx /= length, qy /= length, qz /= length, qw /= length;
        else
            qx = qy = qz = 0, qw = 1;
    }
    const double rotation[3][3] = {
        {1 - 2 * (qy * qy + qz * qz), 2 * (qx * qy - qz * qw), 2 * (qx * qz + qy * qw)},
        {2 * (qx * qy + qz * qw), 1 - 2 * (qx * qx + qz * qz), 2 * (qy * qz - qx * qw)},
        {2 * (qx * qz - qy * qw), 2 * (qy * qz + qx * qw), 1 - 2 * (qx * qx + qy * qy)},
    };
    for (int column = 0; column < 3; ++column) {
        double scale = node.scale.empty() ? 1.0 : node.scale[column];
        for (int row = 0; row < 3; ++row)
            result.m[column * 4 + row] = rotation[row][column] * scale;
    }
    for (int row = 0; row < 3; ++row)
        result.m[12 + row] = node.translation.empty() ? 0.0 : node.translation[row];
    return result;
}

/* ------------------------------------------------------------------ */
/* Accessors                                                          */
/* ------------------------------------------------------------------ */

uint64_t component_size(int component_type)
{
    switch (component_type) {
    case TINYGLTF_COMPONENT_TYPE_BYTE:
    case TINYGLTF_COMPONENT_TYPE_UNSIGNED_BYTE: return 1;
    case TINYGLTF_COMPONENT_TYPE_SHORT:
    case TINYGLTF_COMPONENT_TYPE_UNSIGNED_SHORT: return 2;
    case TINYGLTF_COMPONENT_TYPE_INT:
    case TINYGLTF_COMPONENT_TYPE_UNSIGNED_INT:
    case TINYGLTF_COMPONENT_TYPE_FLOAT: return 4;
    default: return 0;
    }
}

int type_component_count(int type)
{
    switch (type) {
    case TINYGLTF_TYPE_SCALAR: return 1;
    case TINYGLTF_TYPE_VEC2: return 2;
    case TINYGLTF_TYPE_VEC3: return 3;
    case TINYGLTF_TYPE_VEC4:
    case TINYGLTF_TYPE_MAT2: return 4;
    case TINYGLTF_TYPE_MAT3: return 9;
    case TINYGLTF_TYPE_MAT4: return 16;
    default: return 0;
    }
}

const char *type_name(int component_count)
{
    switch (component_count) {
    case 1: return "SCALAR";
    case 2: return "VEC2";
    case 3: return "VEC3";
    default: return "VEC4";
    }
}

/* One component, as a double; normalized integers map to [0, 1] or [-1, 1] (spec 3.11). */
double read_component(const unsigned char *bytes, int component_type, bool normalized)
{
    switch (component_type) {
    case TINYGLTF_COMPONENT_TYPE_BYTE: {
        int8_t value;
        std::memcpy(&value, bytes, 1);
        return normalized ? std::max(value / 127.0, -1.0) : value;
    }
    case TINYGLTF_COMPONENT_TYPE_UNSIGNED_BYTE: return normalized ? bytes[0] / 255.0 : bytes[0];
    case TINYGLTF_COMPONENT_TYPE_SHORT: {
        int16_t value;
        std::memcpy(&value, bytes, 2);
        return normalized ? std::max(value / 32767.0, -1.0) : value;
    }
    case TINYGLTF_COMPONENT_TYPE_UNSIGNED_SHORT: {
        uint16_t value;
        std::memcpy(&value, bytes, 2);
        return normalized ? value / 65535.0 : value;
    }
    case TINYGLTF_COMPONENT_TYPE_INT: {
        int32_t value;
        std::memcpy(&value, bytes, 4);
        return value;
    }
    case TINYGLTF_COMPONENT_TYPE_UNSIGNED_INT: {
        uint32_t value;
        std::memcpy(&value, bytes, 4);
        return value;
    }
    default: {
        float value;
        std::memcpy(&value, bytes, 4);
        return value;
    }
    }
}

/* What an accessor may hold for a given use. */
enum class AccessorUse {
    Float,     /* POSITION, morph targets, _PZ_VERTEX_ID: FLOAT only */
    Texcoord,  /* FLOAT, or normalized UNSIGNED_BYTE / UNSIGNED_SHORT */
    Index      /* any integer type, not normalized */
};

/* The bytes of a buffer view, after checking that it lies inside its buffer. */
struct ViewSpan {
    const unsigned char *data;
    uint64_t size;
    uint64_t stride;  /* 0: tightly packed */
};

ViewSpan buffer_view_span(const tinygltf::Model &model, int view_index, const std::string &what)
{
    if (view_index < 0 || (size_t)view_index >= model.bufferViews.size())
        fail_data(what + ": bufferView " + std::to_string(view_index) + " does not exist");
    const tinygltf::BufferView &view = model.bufferViews[(size_t)view_index];
    if (view.buffer < 0 || (size_t)view.buffer >= model.buffers.size())
        fail_data(what + ": bufferView " + std::to_string(view_index) + " names a missing buffer");
    const tinygltf::Buffer &buffer = model.buffers[(size_t)view.buffer];
    uint64_t buffer_size = buffer.data.size();
    if (view.byteOffset > buffer_size || view.byteLength > buffer_size - view.byteOffset)
        fail_data(what + ": bufferView " + std::to_string(view_index) + " runs past the end of its buffer");
    return ViewSpan{buffer.data.data() + view.byteOffset, view.byteLength, view.byteStride};
}

/* Applies a sparse accessor's substitutions (spec 3.6.2.3) to `values` (count x components). */
void apply_sparse(const tinygltf::Model &model, const tinygltf::Accessor &accessor, int components,
                  uint64_t element_size, bool normalized, std::vector<double> &values, const std::string &what)
{
    const auto &sparse = accessor.sparse;
    if (sparse.count <= 0 || (uint64_t)sparse.count > accessor.count)
        fail_data(what + ": sparse count out of range");
    if (sparse.indices.byteOffset < 0 || sparse.values.byteOffset < 0)
        fail_data(what + ": negative sparse byteOffset");
    uint64_t index_size = component_size(sparse.indices.componentType);
    if (sparse.indices.componentType != TINYGLTF_COMPONENT_TYPE_UNSIGNED_BYTE &&
        sparse.indices.componentType != TINYGLTF_COMPONENT_TYPE_UNSIGNED_SHORT &&
        sparse.indices.componentType != TINYGLTF_COMPONENT_TYPE_UNSIGNED_INT)
        fail_data(what + ": sparse indices must be unsigned integers");
    uint64_t count = (uint64_t)sparse.count;
    ViewSpan index_span = buffer_view_span(model, sparse.indices.bufferView, what + " sparse indices");
    ViewSpan value_span = buffer_view_span(model, sparse.values.bufferView, what + " sparse values");
    uint64_t index_offset = (uint64_t)sparse.indices.byteOffset;
    uint64_t value_offset = (uint64_t)sparse.values.byteOffset;
    /* Sizes are below 2^31 * 64, no overflow in uint64. */
    if (index_offset + count * index_size > index_span.size || value_offset + count * element_size > value_span.size)
        fail_data(what + ": sparse data runs past the end of its bufferView");
    uint64_t component_bytes = component_size(accessor.componentType);
    for (uint64_t k = 0; k < count; ++k) {
        double target =
            read_component(index_span.data + index_offset + k * index_size, sparse.indices.componentType, false);
        if (target >= (double)accessor.count)
            fail_data(what + ": sparse index out of range");
        const unsigned char *element = value_span.data + value_offset + k * element_size;
        for (int c = 0; c < components; ++c)
            values[(uint64_t)target * components + c] =
                read_component(element + c * component_bytes, accessor.componentType, normalized);
    }
}

/*
 * Reads accessor `index` into count x `components` doubles, checking its type
 * against `use` and every byte range against its buffer. `byte_budget` bounds
 * an accessor without a buffer view (its size is otherwise free).
 */
std::vector<double> read_accessor(const tinygltf::Model &model, int index, AccessorUse use, int components,
                                  uint64_t byte_budget, const std::string &what)
{
    if (index < 0 || (size_t)index >= model.accessors.size())
        fail_data(what + ": accessor " + std::to_string(index) + " does not exist");
    const tinygltf::Accessor &accessor = model.accessors[(size_t)index];
    if (type_component_count(accessor.type) != components)
        fail_data(what + ": accessor " + std::to_string(index) + " should be " + type_name(components));
    int ct = accessor.componentType;
    bool type_ok = false;
    switch (use) {
    case AccessorUse::Float: type_ok = ct == TINYGLTF_COMPONENT_TYPE_FLOAT; break;
    case AccessorUse::Texcoord:
        type_ok = ct == TINYGLTF_COMPONENT_TYPE_FLOAT ||
                  (accessor.normalized && (ct == TINYGLTF_COMPONENT_TYPE_UNSIGNED_BYTE ||
                                           ct == TINYGLTF_COMPONENT_TYPE_UNSIGNED_SHORT));
        break;
    case AccessorUse::Index: type_ok = ct != TINYGLTF_COMPONENT_TYPE_FLOAT && component_size(ct) != 0; break;
    }
    if (!type_ok)
        fail_data(what + ": accessor " + std::to_string(index) + " has an unsupported component type " +
                  std::to_string(ct));
    bool normalized = use == AccessorUse::Texcoord && accessor.normalized;
    uint64_t component_bytes = component_size(ct);
    uint64_t element_size = component_bytes * (uint64_t)components;
    uint64_t count = accessor.count;
    std::vector<double> values;
    if (accessor.bufferView >= 0) {
        ViewSpan span = buffer_view_span(model, accessor.bufferView, what);
        uint64_t stride = span.stride ? span.stride : element_size;
        if (stride < element_size || stride % component_bytes != 0)
            fail_data(what + ": byteStride " + std::to_string(stride) + " does not fit the accessor");
        if (count > 0) {
            uint64_t offset = accessor.byteOffset;
            if (offset > span.size || span.size - offset < element_size ||
                count - 1 > (span.size - offset - element_size) / stride)
                fail_data(what + ": accessor " + std::to_string(index) + " runs past the end of its bufferView");
        }
        values.resize(count * (uint64_t)components);
        const unsigned char *base = span.data + accessor.byteOffset;
        for (uint64_t i = 0; i < count; ++i)
            for (int c = 0; c < components; ++c)
                values[i * components + c] = read_component(base + i * stride + c * component_bytes, ct, normalized);
    } else {
        if (count > byte_budget)
            fail_data(what + ": accessor " + std::to_string(index) + " declares " + std::to_string(count) +
                      " elements without data");
        values.assign(count * (uint64_t)components, 0.0);
    }
    if (accessor.sparse.isSparse)
        apply_sparse(model, accessor, components, element_size, normalized, values, what);
    return values;
}

uint64_t accessor_count(const tinygltf::Model &model, int index)
{
    return index >= 0 && (size_t)index < model.accessors.size() ? model.accessors[(size_t)index].count : 0;
}

/* ------------------------------------------------------------------ */
/* Reading                                                            */
/* ------------------------------------------------------------------ */

/* One placement of a mesh in the scene. */
struct Instance {
    int mesh_index;
    Matrix world;
};

/* What a primitive contributes: its label (-1 for none). */
struct PrimitivePlan {
    int32_t label;
};

/* The mesh as it is gathered, before it becomes a pz_mesh. */
struct Gathered {
    std::vector<double> positions;             /* vertex_count x 3 */
    std::vector<std::vector<double>> poses;    /* pose_count x (vertex_count x 3) */
    std::vector<int32_t> faces;                /* face_count x 3 */
    std::vector<int32_t> face_labels;          /* face_count */
    std::vector<double> corner_uv_values;      /* face_count x 3 x 2, glTF values already flipped */
    bool uvs_present = false;
    bool uvs_missing = false;
    std::vector<std::string> label_names;
    std::vector<char> label_named;
    bool labelled = false;
};

class Reader {
public:
    Reader(const tinygltf::Model &model, const std::string &name, uint64_t byte_budget, pz_ctx *ctx)
        : model_(model), name_(name), byte_budget_(byte_budget), ctx_(ctx) {}

    Gathered run()
    {
        check_required_extensions();
        std::vector<Instance> instances = collect_instances();
        plan_primitives(instances);
        for (const Instance &instance : instances) {
            read_instance(instance);
            check_budget(gathered_.positions.size() / 3, gathered_.faces.size() / 3);
        }
        if (skipped_primitives_ > 0)
            pz_note(ctx_, "%s: skipped %d point or line primitives", name_.c_str(), skipped_primitives_);
        if (gathered_.faces.empty())
            fail_data(name_ + ": no triangles");
        if (gathered_.uvs_present && gathered_.uvs_missing)
            pz_note(ctx_, "%s: some primitives have no TEXCOORD_0: UVs dropped", name_.c_str());
        if (instances.size() == 1 && face_ids_complete_ && face_ids_.size() == gathered_.faces.size() / 3)
            restore_face_order();
        return std::move(gathered_);
    }

private:
    const tinygltf::Model &model_;
    const std::string &name_;
    uint64_t byte_budget_;
    pz_ctx *ctx_;
    /* Vertices in every pose plus faces the input may expand to (instancing, morph targets). */
    uint64_t element_budget_ = kExpansionPerByte * byte_budget_ + 65536;
    Gathered gathered_;
    int pose_count_ = -1;
    int skipped_primitives_ = 0;
    bool from_panelize_ = false;
    /* Original index of every gathered face, from pzFaceIds; usable only when every primitive had them. */
    std::vector<double> face_ids_;
    bool face_ids_complete_ = true;
    /* label of primitive p of mesh m: plans_[m][p] */
    std::vector<std::vector<PrimitivePlan>> plans_;

    void check_budget(uint64_t vertex_count, uint64_t face_count) const
    {
        uint64_t elements = vertex_count * (uint64_t)(1 + std::max(pose_count_, 0)) + face_count;
        if (elements > element_budget_)
            fail_data(name_ + ": instancing or morph targets expand the geometry beyond " +
                      std::to_string(element_budget_) + " elements");
    }

    void check_required_extensions()
    {
        for (const std::string &extension : model_.extensionsRequired)
            if (extension != "KHR_materials_unlit" && extension != "KHR_texture_transform" &&
                extension != "KHR_materials_emissive_strength")
                fail_data(name_ + ": requires the extension " + extension + ", which panelize does not support");
    }

    std::string mesh_what(int mesh_index, int primitive_index) const
    {
        return name_ + ": mesh " + std::to_string(mesh_index) + " primitive " + std::to_string(primitive_index);
    }

    /* Walks the scene forest from its roots, accumulating world transforms. */
    std::vector<Instance> collect_instances()
    {
        std::vector<Instance> instances;
        size_t node_count = model_.nodes.size();
        if (node_count == 0) {
            for (size_t m = 0; m < model_.meshes.size(); ++m)
                instances.push_back(Instance{(int)m, matrix_identity()});
            return instances;
        }
        std::vector<char> has_parent(node_count, 0);
        for (size_t n = 0; n < node_count; ++n)
            for (int child : model_.nodes[n].children) {
                if (child < 0 || (size_t)child >= node_count)
                    fail_data(name_ + ": node " + std::to_string(n) + " has a missing child " + std::to_string(child));
                if (has_parent[(size_t)child])
                    fail_data(name_ + ": node " + std::to_string(child) + " has more than one parent");
                has_parent[(size_t)child] = 1;
            }
        std::vector<int> roots;
        if (model_.defaultScene >= 0) {
            if ((size_t)model_.defaultScene >= model_.scenes.size())
                fail_data(name_ + ": the default scene " + std::to_string(model_.defaultScene) + " does not exist");
            roots = model_.scenes[(size_t)model_.defaultScene].nodes;
        } else if (!model_.scenes.empty()) {
            for (const tinygltf::Scene &scene : model_.scenes)
                roots.insert(roots.end(), scene.nodes.begin(), scene.nodes.end());
        } else {
            for (size_t n = 0; n < node_count; ++n)
                if (!has_parent[n])
                    roots.push_back((int)n);
        }
        std::vector<char> visited(node_count, 0);
        std::vector<std::pair<int, Matrix>> stack;
        for (int root : roots) {
            if (root < 0 || (size_t)root >= node_count)
                fail_data(name_ + ": a scene lists the missing node " + std::to_string(root));
            if (visited[(size_t)root])
                continue; /* listed by two scenes, or twice by one: read it once */
            stack.emplace_back(root, matrix_identity());
            while (!stack.empty()) {
                int node_index = stack.back().first;
                Matrix parent = stack.back().second;
                stack.pop_back();
                if (visited[(size_t)node_index])
                    fail_data(name_ + ": node " + std::to_string(node_index) +
                              " is reached twice (a cycle, or a scene lists a child node)");
                visited[(size_t)node_index] = 1;
                const tinygltf::Node &node = model_.nodes[(size_t)node_index];
                Matrix world = matrix_multiply(parent, node_local_matrix(node, name_ + ": node " +
                                                                                   std::to_string(node_index)));
                if (node.mesh >= 0) {
                    if ((size_t)node.mesh >= model_.meshes.size())
                        fail_data(name_ + ": node " + std::to_string(node_index) + " has a missing mesh " +
                                  std::to_string(node.mesh));
                    instances.push_back(Instance{node.mesh, world});
                }
                for (auto child = node.children.rbegin(); child != node.children.rend(); ++child)
                    stack.emplace_back(*child, world);
            }
        }
        return instances;
    }

    static bool is_triangle_mode(int mode)
    {
        return mode == -1 || mode == TINYGLTF_MODE_TRIANGLES || mode == TINYGLTF_MODE_TRIANGLE_STRIP ||
               mode == TINYGLTF_MODE_TRIANGLE_FAN;
    }

    /* The pzLabel extra of a primitive, or -1. */
    static int32_t primitive_pz_label(const tinygltf::Primitive &primitive)
    {
        if (!primitive.extras.IsObject() || !primitive.extras.Has(kLabelExtra))
            return -1;
        const tinygltf::Value &value = primitive.extras.Get(kLabelExtra);
        if (!value.IsNumber())
            return -1;
        double label = value.GetNumberAsDouble();
        return label >= 0 && label < 65536 && label == std::floor(label) ? (int32_t)label : -1;
    }

    std::string material_name(int material) const
    {
        if (material >= 0 && (size_t)material < model_.materials.size())
            return model_.materials[(size_t)material].name;
        return std::string();
    }

    int32_t label_for_name(std::map<std::string, int32_t> &by_name, const std::string &label_name)
    {
        auto found = by_name.find(label_name);
        if (found != by_name.end())
            return found->second;
        int32_t label = (int32_t)gathered_.label_names.size();
        by_name.emplace(label_name, label);
        gathered_.label_names.push_back(label_name);
        gathered_.label_named.push_back(1);
        return label;
    }

    /* A panelize mesh's extras {"pzLabelNames": [...]}: every label, also those without faces. */
    void read_label_names(const tinygltf::Mesh &mesh)
    {
        if (!mesh.extras.IsObject() || !mesh.extras.Has(kLabelNamesExtra))
            return;
        const tinygltf::Value &names = mesh.extras.Get(kLabelNamesExtra);
        size_t count = std::min(names.ArrayLen(), (size_t)65536);
        if (count > gathered_.label_names.size()) {
            gathered_.label_names.resize(count);
            gathered_.label_named.resize(count, 0);
        }
        for (size_t l = 0; l < count; ++l)
            if (names.Get((int)l).IsString() && !names.Get((int)l).Get<std::string>().empty() &&
                !gathered_.label_named[l]) {
                gathered_.label_names[l] = names.Get((int)l).Get<std::string>();
                gathered_.label_named[l] = 1;
            }
    }

    /*
     * Decides every used primitive's label and checks the morph target counts
     * before any geometry is read.
     */
    void plan_primitives(const std::vector<Instance> &instances)
    {
        std::vector<char> used(model_.meshes.size(), 0);
        for (const Instance &instance : instances)
            used[(size_t)instance.mesh_index] = 1;
        plans_.assign(model_.meshes.size(), {});
        bool from_panelize = model_.asset.generator.rfind("panelize", 0) == 0;
        from_panelize_ = from_panelize;
        bool all_pz_labels = true, any_pz_label = false;
        for (size_t m = 0; m < model_.meshes.size(); ++m) {
            if (!used[m])
                continue;
            const tinygltf::Mesh &mesh = model_.meshes[m];
            for (size_t p = 0; p < mesh.primitives.size(); ++p) {
                const tinygltf::Primitive &primitive = mesh.primitives[p];
                if (!is_triangle_mode(primitive.mode))
                    continue;
                int target_count = (int)primitive.targets.size();
                if (pose_count_ < 0)
                    pose_count_ = target_count;
                else if (target_count != pose_count_)
                    fail_data(mesh_what((int)m, (int)p) + ": has " + std::to_string(target_count) +
                              " morph targets, an earlier primitive " + std::to_string(pose_count_));
                bool has_label = primitive_pz_label(primitive) >= 0;
                all_pz_labels = all_pz_labels && has_label;
                any_pz_label = any_pz_label || has_label;
            }
        }
        if (pose_count_ < 0)
            pose_count_ = 0;
        gathered_.poses.assign((size_t)pose_count_, {});

        std::map<std::string, int32_t> by_name;
        bool pz_labels = from_panelize && all_pz_labels && any_pz_label;
        gathered_.labelled = !from_panelize || pz_labels;
        if (pz_labels)
            for (size_t m = 0; m < model_.meshes.size(); ++m)
                if (used[m])
                    read_label_names(model_.meshes[m]);
        for (size_t m = 0; m < model_.meshes.size(); ++m) {
            if (!used[m])
                continue;
            const tinygltf::Mesh &mesh = model_.meshes[m];
            plans_[m].assign(mesh.primitives.size(), PrimitivePlan{-1});
            for (size_t p = 0; p < mesh.primitives.size(); ++p) {
                const tinygltf::Primitive &primitive = mesh.primitives[p];
                if (!is_triangle_mode(primitive.mode))
                    continue;
                if (pz_labels) {
                    int32_t label = primitive_pz_label(primitive);
                    if ((size_t)label >= gathered_.label_names.size()) {
                        gathered_.label_names.resize((size_t)label + 1);
                        gathered_.label_named.resize((size_t)label + 1, 0);
                    }
                    std::string material = material_name(primitive.material);
                    if (!material.empty() && !gathered_.label_named[(size_t)label]) {
                        gathered_.label_names[(size_t)label] = material;
                        gathered_.label_named[(size_t)label] = 1;
                    }
                    plans_[m][p].label = label;
                } else if (gathered_.labelled) {
                    std::string label_name = mesh.name.empty() ? "mesh" + std::to_string(m) : mesh.name;
                    if (mesh.primitives.size() > 1) {
                        std::string material = material_name(primitive.material);
                        label_name += "/" + (material.empty() ? std::to_string(p) : material);
                    }
                    plans_[m][p].label = label_for_name(by_name, label_name);
                }
            }
        }
    }

    /*
     * Puts the faces back in the order they had before pz_glb_write grouped
     * them by label. Ids that are not a permutation are ignored.
     */
    void restore_face_order()
    {
        size_t face_count = face_ids_.size();
        std::vector<uint32_t> source(face_count, UINT32_MAX);
        for (size_t f = 0; f < face_count; ++f) {
            double id = face_ids_[f];
            if (!(id >= 0 && id < (double)face_count) || source[(size_t)id] != UINT32_MAX)
                return;
            source[(size_t)id] = (uint32_t)f;
        }
        Gathered &g = gathered_;
        std::vector<int32_t> faces(g.faces.size()), labels(g.face_labels.size());
        std::vector<double> uv_values(g.corner_uv_values.size());
        for (size_t f = 0; f < face_count; ++f) {
            size_t from = source[f];
            std::copy_n(&g.faces[3 * from], 3, &faces[3 * f]);
            std::copy_n(&g.corner_uv_values[6 * from], 6, &uv_values[6 * f]);
            labels[f] = g.face_labels[from];
        }
        g.faces.swap(faces);
        g.face_labels.swap(labels);
        g.corner_uv_values.swap(uv_values);
    }

    /* Reads the pzFaceIds accessor of a panelize primitive, or marks the ids incomplete. */
    void read_face_ids(const tinygltf::Primitive &primitive, size_t triangle_count, const std::string &what)
    {
        if (!face_ids_complete_)
            return;
        if (!from_panelize_ || !primitive.extras.IsObject() || !primitive.extras.Has(kFaceIdsExtra) ||
            !primitive.extras.Get(kFaceIdsExtra).IsInt()) {
            face_ids_complete_ = false;
            return;
        }
        std::vector<double> ids = read_accessor(model_, primitive.extras.Get(kFaceIdsExtra).Get<int>(),
                                                AccessorUse::Index, 1, byte_budget_, what + " " + kFaceIdsExtra);
        if (ids.size() != triangle_count)
            fail_data(what + ": " + kFaceIdsExtra + " and the triangles differ in count");
        face_ids_.insert(face_ids_.end(), ids.begin(), ids.end());
    }

    /* Grows the vertex arrays (rest and poses) by `count` zeroed vertices; returns the first new index. */
    uint64_t add_vertices(uint64_t count)
    {
        uint64_t first = gathered_.positions.size() / 3;
        if (first + count > (uint64_t)INT32_MAX)
            fail_data(name_ + ": more than 2^31 vertices");
        check_budget(first + count, gathered_.faces.size() / 3);
        gathered_.positions.resize((first + count) * 3, 0.0);
        for (std::vector<double> &pose : gathered_.poses)
            pose.resize((first + count) * 3, 0.0);
        return first;
    }

    /* The _PZ_VERTEX_ID of every row of every triangle primitive, or empty when some primitive lacks it. */
    std::vector<std::vector<double>> read_vertex_ids(int mesh_index, uint64_t *id_count)
    {
        const tinygltf::Mesh &mesh = model_.meshes[(size_t)mesh_index];
        std::vector<std::vector<double>> ids(mesh.primitives.size());
        uint64_t row_total = 0;
        bool any = false;
        for (const tinygltf::Primitive &primitive : mesh.primitives) {
            if (!is_triangle_mode(primitive.mode))
                continue;
            if (!primitive.attributes.count(kVertexIdAttribute))
                return {};
            auto position = primitive.attributes.find("POSITION");
            row_total += position == primitive.attributes.end() ? 0 : accessor_count(model_, position->second);
            any = true;
        }
        if (!any)
            return {};
        uint64_t max_id = 0;
        for (size_t p = 0; p < mesh.primitives.size(); ++p) {
            const tinygltf::Primitive &primitive = mesh.primitives[p];
            if (!is_triangle_mode(primitive.mode))
                continue;
            std::string what = mesh_what(mesh_index, (int)p) + " " + kVertexIdAttribute;
            ids[p] = read_accessor(model_, primitive.attributes.at(kVertexIdAttribute), AccessorUse::Float, 1,
                                   byte_budget_, what);
            for (double id : ids[p]) {
                if (!(id >= 0 && id < (double)row_total && id == std::floor(id)))
                    fail_data(what + ": id " + std::to_string(id) + " is not an integer below " +
                              std::to_string(row_total));
                max_id = std::max(max_id, (uint64_t)id);
            }
        }
        *id_count = max_id + 1;
        return ids;
    }

    void read_instance(const Instance &instance)
    {
        const tinygltf::Mesh &mesh = model_.meshes[(size_t)instance.mesh_index];
        uint64_t id_count = 0;
        std::vector<std::vector<double>> ids = read_vertex_ids(instance.mesh_index, &id_count);
        uint64_t id_base = ids.empty() ? 0 : add_vertices(id_count);
        std::vector<char> id_written(ids.empty() ? 0 : id_count, 0);
        for (size_t p = 0; p < mesh.primitives.size(); ++p) {
            const tinygltf::Primitive &primitive = mesh.primitives[p];
            if (!is_triangle_mode(primitive.mode)) {
                if (primitive.mode < 0 || primitive.mode > TINYGLTF_MODE_TRIANGLE_FAN)
                    fail_data(mesh_what(instance.mesh_index, (int)p) + ": unknown mode " +
                              std::to_string(primitive.mode));
                ++skipped_primitives_;
                continue;
            }
            read_primitive(instance, (int)p, ids.empty() ? nullptr : &ids[p], id_base, id_written);
        }
    }

    /* The triangles of a primitive as row indices (count x 3), from its mode and indices. */
    std::vector<uint32_t> primitive_triangles(const tinygltf::Primitive &primitive, uint64_t row_count,
                                              const std::string &what)
    {
        std::vector<uint32_t> order;
        if (primitive.indices >= 0) {
            std::vector<double> indices =
                read_accessor(model_, primitive.indices, AccessorUse::Index, 1, byte_budget_, what + " indices");
            order.resize(indices.size());
            for (size_t i = 0; i < indices.size(); ++i) {
                if (!(indices[i] >= 0 && indices[i] < (double)row_count))
                    fail_data(what + ": index " + std::to_string((int64_t)indices[i]) + " out of range (" +
                              std::to_string(row_count) + " vertices)");
                order[i] = (uint32_t)indices[i];
            }
        } else {
            order.resize(row_count);
            std::iota(order.begin(), order.end(), 0u);
        }
        int mode = primitive.mode < 0 ? TINYGLTF_MODE_TRIANGLES : primitive.mode;
        if (mode == TINYGLTF_MODE_TRIANGLES) {
            if (order.size() % 3 != 0)
                fail_data(what + ": " + std::to_string(order.size()) + " indices is not a multiple of 3");
            return order;
        }
        /* Strips and fans (spec 3.7.2.1); a triangle with a repeated corner is a strip joint. */
        std::vector<uint32_t> triangles;
        for (size_t i = 0; i + 2 < order.size(); ++i) {
            uint32_t a, b, c;
            if (mode == TINYGLTF_MODE_TRIANGLE_STRIP) {
                a = order[i];
                b = order[i + 1 + i % 2];
                c = order[i + 2 - i % 2];
            } else {
                a = order[i + 1];
                b = order[i + 2];
                c = order[0];
            }
            if (a == b || b == c || a == c)
                continue;
            triangles.insert(triangles.end(), {a, b, c});
        }
        return triangles;
    }

    void read_primitive(const Instance &instance, int primitive_index, const std::vector<double> *ids,
                        uint64_t id_base, std::vector<char> &id_written)
    {
        const tinygltf::Mesh &mesh = model_.meshes[(size_t)instance.mesh_index];
        const tinygltf::Primitive &primitive = mesh.primitives[(size_t)primitive_index];
        std::string what = mesh_what(instance.mesh_index, primitive_index);
        auto position = primitive.attributes.find("POSITION");
        if (position == primitive.attributes.end())
            fail_data(what + ": no POSITION attribute");
        std::vector<double> rows = read_accessor(model_, position->second, AccessorUse::Float, 3, byte_budget_,
                                                 what + " POSITION");
        uint64_t row_count = rows.size() / 3;
        check_budget(row_count, 0); /* before the targets are read */
        if (ids && ids->size() != row_count)
            fail_data(what + ": " + kVertexIdAttribute + " and POSITION differ in count");

        std::vector<std::vector<double>> target_rows((size_t)pose_count_);
        for (int t = 0; t < pose_count_; ++t) {
            const auto &target = primitive.targets[(size_t)t];
            auto displacement = target.find("POSITION");
            if (displacement == target.end()) {
                target_rows[(size_t)t] = rows;
                continue;
            }
            std::string target_what = what + " target " + std::to_string(t);
            target_rows[(size_t)t] = read_accessor(model_, displacement->second, AccessorUse::Float, 3,
                                                   byte_budget_, target_what);
            if (target_rows[(size_t)t].size() != rows.size())
                fail_data(target_what + ": count differs from POSITION");
            for (size_t i = 0; i < rows.size(); ++i)
                target_rows[(size_t)t][i] += rows[i];
        }

        /* Row -> vertex: the id's vertex when merging, else a fresh vertex per row. */
        std::vector<int32_t> row_vertex(row_count);
        uint64_t first_new = ids ? 0 : add_vertices(row_count);
        for (uint64_t r = 0; r < row_count; ++r) {
            uint64_t vertex = ids ? id_base + (uint64_t)(*ids)[r] : first_new + r;
            row_vertex[r] = (int32_t)vertex;
            if (ids) {
                if (id_written[(size_t)(*ids)[r]])
                    continue;
                id_written[(size_t)(*ids)[r]] = 1;
            }
            matrix_apply(instance.world, &rows[r * 3], &gathered_.positions[vertex * 3]);
            for (int t = 0; t < pose_count_; ++t)
                matrix_apply(instance.world, &target_rows[(size_t)t][r * 3], &gathered_.poses[(size_t)t][vertex * 3]);
        }

        std::vector<double> texcoords;
        auto texcoord = primitive.attributes.find("TEXCOORD_0");
        if (texcoord != primitive.attributes.end()) {
            texcoords = read_accessor(model_, texcoord->second, AccessorUse::Texcoord, 2, byte_budget_,
                                      what + " TEXCOORD_0");
            if (texcoords.size() / 2 != row_count)
                fail_data(what + ": TEXCOORD_0 and POSITION differ in count");
            gathered_.uvs_present = true;
        } else {
            gathered_.uvs_missing = true;
        }

        std::vector<uint32_t> triangles = primitive_triangles(primitive, row_count, what);
        read_face_ids(primitive, triangles.size() / 3, what);
        bool flip = matrix_determinant3(instance.world) < 0;
        int32_t label = plans_[(size_t)instance.mesh_index][(size_t)primitive_index].label;
        for (size_t i = 0; i < triangles.size(); i += 3) {
            uint32_t corner_rows[3] = {triangles[i], flip ? triangles[i + 2] : triangles[i + 1],
                                       flip ? triangles[i + 1] : triangles[i + 2]};
            for (uint32_t row : corner_rows) {
                gathered_.faces.push_back(row_vertex[row]);
                if (!texcoords.empty()) {
                    gathered_.corner_uv_values.push_back(texcoords[row * 2]);
                    gathered_.corner_uv_values.push_back(1.0 - texcoords[row * 2 + 1]);
                } else {
                    gathered_.corner_uv_values.insert(gathered_.corner_uv_values.end(), {0.0, 0.0});
                }
            }
            gathered_.face_labels.push_back(label);
        }
    }
};

/*
 * Gives corners with the same vertex and the same UV value one UV index:
 * sorts the corners by (vertex, u, v). O(C log C).
 */
void index_corner_uvs(const Gathered &gathered, std::vector<double> &uvs, std::vector<int32_t> &corner_uvs)
{
    size_t corner_count = gathered.faces.size();
    /* NaN would break the sort's strict weak order: such a UV reads as 0. */
    std::vector<double> values(gathered.corner_uv_values);
    for (double &value : values)
        if (std::isnan(value))
            value = 0.0;
    auto corner_less = [&](uint32_t a, uint32_t b) {
        if (gathered.faces[a] != gathered.faces[b])
            return gathered.faces[a] < gathered.faces[b];
        if (values[2 * a] != values[2 * b])
            return values[2 * a] < values[2 * b];
        return values[2 * a + 1] < values[2 * b + 1];
    };
    std::vector<uint32_t> order(corner_count);
    std::iota(order.begin(), order.end(), 0u);
    std::sort(order.begin(), order.end(), corner_less);
    corner_uvs.assign(corner_count, 0);
    uvs.clear();
    for (size_t i = 0; i < corner_count; ++i) {
        if (i == 0 || corner_less(order[i - 1], order[i])) {
            uvs.push_back(values[2 * order[i]]);
            uvs.push_back(values[2 * order[i] + 1]);
        }
        corner_uvs[order[i]] = (int32_t)(uvs.size() / 2 - 1);
    }
}

char *duplicate_cstring(const std::string &text)
{
    char *copy = (char *)malloc(text.size() + 1);
    if (!copy)
        throw std::bad_alloc();
    std::memcpy(copy, text.c_str(), text.size() + 1);
    return copy;
}

/* Moves the gathered arrays into a new pz_mesh (throws bad_alloc; frees on failure). */
pz_mesh *build_mesh(const Gathered &gathered, pz_ctx *ctx)
{
    int32_t vertex_count = (int32_t)(gathered.positions.size() / 3);
    uint64_t face_count = gathered.faces.size() / 3;
    if (face_count > (uint64_t)INT32_MAX)
        fail_data("more than 2^31 faces");
    pz_mesh *mesh = nullptr;
    pz_status status = pz_mesh_create(vertex_count, (int32_t)face_count, &mesh, ctx);
    if (status != PZ_OK)
        fail(status, ctx->error);
    struct Guard {
        pz_mesh *mesh;
        ~Guard() { pz_mesh_free(&mesh); }
    } guard{mesh};
    std::copy(gathered.positions.begin(), gathered.positions.end(), mesh->positions);
    std::copy(gathered.faces.begin(), gathered.faces.end(), mesh->faces);

    if (gathered.uvs_present && !gathered.uvs_missing) {
        std::vector<double> uvs;
        std::vector<int32_t> corner_uvs;
        index_corner_uvs(gathered, uvs, corner_uvs);
        mesh->uvs = (double *)malloc(uvs.size() * sizeof(double) + 1);
        mesh->corner_uvs = (int32_t *)malloc(corner_uvs.size() * sizeof(int32_t) + 1);
        if (!mesh->uvs || !mesh->corner_uvs)
            throw std::bad_alloc();
        std::copy(uvs.begin(), uvs.end(), mesh->uvs);
        std::copy(corner_uvs.begin(), corner_uvs.end(), mesh->corner_uvs);
        mesh->uv_count = (int32_t)(uvs.size() / 2);
    }

    if (gathered.labelled && !gathered.label_names.empty()) {
        mesh->face_labels = (int32_t *)malloc(face_count * sizeof(int32_t) + 1);
        mesh->label_names = (char **)calloc(gathered.label_names.size() + 1, sizeof(char *));
        if (!mesh->face_labels || !mesh->label_names)
            throw std::bad_alloc();
        mesh->label_count = (int32_t)gathered.label_names.size();
        std::copy(gathered.face_labels.begin(), gathered.face_labels.end(), mesh->face_labels);
        for (size_t l = 0; l < gathered.label_names.size(); ++l)
            if (gathered.label_named[l])
                mesh->label_names[l] = duplicate_cstring(gathered.label_names[l]);
    }

    if (!gathered.poses.empty()) {
        size_t pose_size = (size_t)vertex_count * 3;
        mesh->poses = (double *)malloc(gathered.poses.size() * pose_size * sizeof(double) + 1);
        if (!mesh->poses)
            throw std::bad_alloc();
        for (size_t p = 0; p < gathered.poses.size(); ++p)
            std::copy(gathered.poses[p].begin(), gathered.poses[p].end(), mesh->poses + p * pose_size);
        mesh->pose_count = (int32_t)gathered.poses.size();
    }
    guard.mesh = nullptr;
    return mesh;
}

/* ------------------------------------------------------------------ */
/* Filesystem access for external URIs                                */
/* ------------------------------------------------------------------ */

/* The directory external files may come from; NULL-base_dir reads get no callbacks that succeed. */
struct FsJail {
    std::string prefix;  /* base_dir with a trailing '/', or "" for the current directory */
};

std::string fs_expand_identity(const std::string &path, void *)
{
    return path; /* tinygltf's own ExpandFilePath runs wordexp(): no shell expansion of file contents here */
}

bool fs_deny_exists(const std::string &, void *)
{
    return false;
}

bool fs_deny_read(std::vector<unsigned char> *, std::string *err, const std::string &path, void *)
{
    if (err)
        *err += "external file " + path + " not allowed";
    return false;
}

bool fs_deny_write(std::string *err, const std::string &, const std::vector<unsigned char> &, void *)
{
    if (err)
        *err += "writing files is not allowed";
    return false;
}

/* A path tinygltf built by joining a search directory and a URI: allowed only inside the jail. */
bool fs_jail_allows(const std::string &path, const FsJail *jail)
{
    if (path.compare(0, jail->prefix.size(), jail->prefix) != 0)
        return false;
    std::string relative = path.substr(jail->prefix.size());
    if (relative.empty() || relative[0] == '/')
        return false;
    size_t start = 0;
    while (start <= relative.size()) {
        size_t end = relative.find('/', start);
        if (end == std::string::npos)
            end = relative.size();
        if (relative.compare(start, end - start, "..") == 0 && end - start == 2)
            return false;
        start = end + 1;
    }
    return true;
}

bool fs_jail_exists(const std::string &path, void *user)
{
    if (!fs_jail_allows(path, (const FsJail *)user))
        return false;
    FILE *file = std::fopen(path.c_str(), "rb");
    if (!file)
        return false;
    std::fclose(file);
    return true;
}

bool fs_jail_read(std::vector<unsigned char> *out, std::string *err, const std::string &path, void *user)
{
    if (!fs_jail_allows(path, (const FsJail *)user))
        return fs_deny_read(out, err, path, user);
    FILE *file = std::fopen(path.c_str(), "rb");
    if (!file) {
        if (err)
            *err += "cannot open " + path;
        return false;
    }
    out->clear();
    unsigned char chunk[65536];
    size_t got;
    while ((got = std::fread(chunk, 1, sizeof chunk, file)) > 0)
        out->insert(out->end(), chunk, chunk + got);
    bool failed = std::ferror(file) != 0;
    std::fclose(file);
    if (failed && err)
        *err += "cannot read " + path;
    return !failed;
}

/* Textures do not matter to panelize: accept every image without decoding it. */
bool ignore_image(tinygltf::Image *, const int, std::string *, std::string *, int, int, const unsigned char *, int,
                  void *)
{
    return true;
}

/*
 * Checks the GLB container (spec 4.4) before tinygltf parses it: tinygltf 2.7
 * checks the BIN chunk's length without its 8-byte header and may read past
 * the end of the data.
 */
void check_glb_container(const unsigned char *data, size_t size, const std::string &name)
{
    if (size < 20)
        fail_data(name + ": too short for a GLB file");
    if (std::memcmp(data, "glTF", 4) != 0)
        fail_data(name + ": not a GLB file (no glTF magic)");
    uint32_t words[5];
    std::memcpy(words, data, sizeof words);
    uint32_t version = words[1], length = words[2], json_length = words[3];
    if (version != 2)
        fail_data(name + ": GLB version " + std::to_string(version) + ", expected 2");
    if (length > size)
        fail_data(name + ": truncated GLB (" + std::to_string(size) + " bytes, header says " +
                  std::to_string(length) + ")");
    uint64_t json_end = 20ull + json_length;
    if (json_end > length)
        fail_data(name + ": truncated GLB JSON chunk");
    if (length - json_end >= 8) {
        uint32_t bin_length;
        std::memcpy(&bin_length, data + json_end, 4);
        if (json_end + 8ull + bin_length > length)
            fail_data(name + ": truncated GLB BIN chunk");
    }
}

/*
 * tinygltf converts JSON to its Value type recursively: a deeply nested
 * "extras" overflows the stack. No glTF needs more than a few levels.
 */
void check_json_depth(const unsigned char *text, size_t length, const std::string &name)
{
    const int max_depth = 64;
    int depth = 0;
    bool in_string = false;
    for (size_t i = 0; i < length; ++i) {
        unsigned char c = text[i];
        if (in_string) {
            if (c == '\\')
                ++i;
            else if (c == '"')
                in_string = false;
        } else if (c == '"') {
            in_string = true;
        } else if (c == '[' || c == '{') {
            if (++depth > max_depth)
                fail_data(name + ": JSON nested deeper than " + std::to_string(max_depth) + " levels");
        } else if (c == ']' || c == '}') {
            --depth;
        }
    }
}

void load_model(tinygltf::Model &model, const unsigned char *data, size_t size, int binary, const char *base_dir,
                const std::string &name)
{
    if (size > UINT_MAX)
        fail_data(name + ": larger than 4 GiB");
    if (binary) {
        check_glb_container(data, size, name);
        uint32_t json_length;
        std::memcpy(&json_length, data + 12, 4);
        check_json_depth(data + 20, json_length, name);
    } else {
        check_json_depth(data, size, name);
    }
    tinygltf::TinyGLTF loader;
    loader.SetImageLoader(ignore_image, nullptr);
    FsJail jail;
    tinygltf::FsCallbacks callbacks = {fs_deny_exists, fs_expand_identity, fs_deny_read, fs_deny_write, nullptr};
    if (base_dir) {
        jail.prefix = base_dir;
        if (!jail.prefix.empty() && jail.prefix.back() != '/')
            jail.prefix += '/';
        callbacks = {fs_jail_exists, fs_expand_identity, fs_jail_read, fs_deny_write, &jail};
    }
    loader.SetFsCallbacks(callbacks);
    std::string err, warn;
    /* With no base_dir tinygltf still searches ".": the deny callbacks stop it. */
    std::string search_dir = base_dir ? base_dir : "";
    bool loaded = binary ? loader.LoadBinaryFromMemory(&model, &err, &warn, data, (unsigned)size, search_dir)
                         : loader.LoadASCIIFromString(&model, &err, &warn, (const char *)data, (unsigned)size,
                                                      search_dir);
    if (!loaded)
        fail_data(name + ": " + one_line(err));
}

/* ------------------------------------------------------------------ */
/* Writing                                                            */
/* ------------------------------------------------------------------ */

/* 12 colours that stay apart from each other (sRGB, RGBA8). */
const uint32_t kPalette[12] = {0x4e79a7ff, 0xf28e2bff, 0xe15759ff, 0x76b7b2ff, 0x59a14fff, 0xedc948ff,
                               0xb07aa1ff, 0xff9da7ff, 0x9c755fff, 0xbab0acff, 0x86bcb6ff, 0xd37295ff};
const uint32_t kUnlabelledColor = 0xd8d0c0ff; /* undyed cotton */

double srgb_to_linear(double value)
{
    return value <= 0.04045 ? value / 12.92 : std::pow((value + 0.055) / 1.055, 2.4);
}

tinygltf::Value json_to_value(const nlohmann::json &json)
{
    switch (json.type()) {
    case nlohmann::json::value_t::boolean: return tinygltf::Value(json.get<bool>());
    case nlohmann::json::value_t::number_integer:
    case nlohmann::json::value_t::number_unsigned: {
        int64_t number = json.get<int64_t>();
        if (number >= INT_MIN && number <= INT_MAX)
            return tinygltf::Value((int)number);
        return tinygltf::Value((double)number);
    }
    case nlohmann::json::value_t::number_float: return tinygltf::Value(json.get<double>());
    case nlohmann::json::value_t::string: return tinygltf::Value(json.get<std::string>());
    case nlohmann::json::value_t::array: {
        tinygltf::Value::Array array;
        for (const auto &element : json)
            array.push_back(json_to_value(element));
        return tinygltf::Value(std::move(array));
    }
    case nlohmann::json::value_t::object: {
        tinygltf::Value::Object object;
        for (auto it = json.begin(); it != json.end(); ++it)
            object[it.key()] = json_to_value(it.value());
        return tinygltf::Value(std::move(object));
    }
    default: return tinygltf::Value();
    }
}

class GlbBuilder {
public:
    tinygltf::Model model;

    GlbBuilder() { model.buffers.emplace_back(); }

    /* Appends `bytes` as a new buffer view (4-byte aligned) and returns its index. */
    int add_view(const void *data, size_t bytes, int target)
    {
        std::vector<unsigned char> &bin = model.buffers[0].data;
        bin.resize((bin.size() + 3) & ~(size_t)3, 0);
        tinygltf::BufferView view;
        view.buffer = 0;
        view.byteOffset = bin.size();
        view.byteLength = bytes;
        view.target = target;
        bin.insert(bin.end(), (const unsigned char *)data, (const unsigned char *)data + bytes);
        model.bufferViews.push_back(view);
        return (int)model.bufferViews.size() - 1;
    }

    /* A tightly packed float accessor of count x components, with min/max when asked. */
    int add_floats(const std::vector<float> &values, int components, bool with_bounds)
    {
        tinygltf::Accessor accessor;
        accessor.bufferView = add_view(values.data(), values.size() * sizeof(float), TINYGLTF_TARGET_ARRAY_BUFFER);
        accessor.componentType = TINYGLTF_COMPONENT_TYPE_FLOAT;
        accessor.type = components == 1 ? TINYGLTF_TYPE_SCALAR : components;
        accessor.count = values.size() / (size_t)components;
        if (with_bounds) {
            accessor.minValues.assign((size_t)components, INFINITY);
            accessor.maxValues.assign((size_t)components, -INFINITY);
            for (size_t i = 0; i < values.size(); ++i) {
                size_t c = i % (size_t)components;
                accessor.minValues[c] = std::min(accessor.minValues[c], (double)values[i]);
                accessor.maxValues[c] = std::max(accessor.maxValues[c], (double)values[i]);
            }
        }
        model.accessors.push_back(accessor);
        return (int)model.accessors.size() - 1;
    }

    /* UNSIGNED_INT scalars: vertex indices (target ELEMENT_ARRAY_BUFFER) or other data (target 0). */
    int add_indices(const std::vector<uint32_t> &indices, int target = TINYGLTF_TARGET_ELEMENT_ARRAY_BUFFER)
    {
        tinygltf::Accessor accessor;
        accessor.bufferView = add_view(indices.data(), indices.size() * sizeof(uint32_t), target);
        accessor.componentType = TINYGLTF_COMPONENT_TYPE_UNSIGNED_INT;
        accessor.type = TINYGLTF_TYPE_SCALAR;
        accessor.count = indices.size();
        model.accessors.push_back(accessor);
        return (int)model.accessors.size() - 1;
    }
};

/* Rejects what would make an invalid file or an out-of-range read. */
void check_writable(const pz_mesh *mesh, const std::string &path)
{
    if (mesh->face_count <= 0)
        fail(PZ_ERR_INVALID_MESH, path + ": a glTF mesh needs at least one face");
    for (int64_t i = 0; i < 3 * (int64_t)mesh->face_count; ++i)
        if (mesh->faces[i] < 0 || mesh->faces[i] >= mesh->vertex_count)
            fail(PZ_ERR_INVALID_MESH, path + ": face " + std::to_string(i / 3) + " has a vertex index out of range");
    if (mesh->corner_uvs)
        for (int64_t i = 0; i < 3 * (int64_t)mesh->face_count; ++i)
            if (mesh->corner_uvs[i] < 0 || mesh->corner_uvs[i] >= mesh->uv_count)
                fail(PZ_ERR_INVALID_MESH, path + ": face " + std::to_string(i / 3) + " has a UV index out of range");
    if (mesh->face_labels)
        for (int32_t f = 0; f < mesh->face_count; ++f)
            if (mesh->face_labels[f] < 0 || mesh->face_labels[f] >= mesh->label_count)
                fail(PZ_ERR_INVALID_MESH, path + ": face " + std::to_string(f) + " has a label out of range");
    int32_t pose_count = mesh->poses ? mesh->pose_count : 0;
    for (int64_t i = 0; i < 3 * (int64_t)mesh->vertex_count * (1 + pose_count); ++i) {
        double value = i < 3 * (int64_t)mesh->vertex_count ? mesh->positions[i]
                                                           : mesh->poses[i - 3 * (int64_t)mesh->vertex_count];
        if (!std::isfinite((float)value))
            fail(PZ_ERR_INVALID_MESH, path + ": vertex " + std::to_string((i / 3) % mesh->vertex_count) +
                                          " has a coordinate that is not a finite float");
    }
}

/* Area-weighted vertex normals of the rest pose, unit length ((0,0,1) where they vanish). */
std::vector<double> vertex_normals(const pz_mesh *mesh)
{
    std::vector<double> normals((size_t)mesh->vertex_count * 3, 0.0);
    for (int32_t f = 0; f < mesh->face_count; ++f) {
        const int32_t *corner = &mesh->faces[3 * f];
        const double *a = &mesh->positions[3 * corner[0]], *b = &mesh->positions[3 * corner[1]],
                     *c = &mesh->positions[3 * corner[2]];
        double u[3] = {b[0] - a[0], b[1] - a[1], b[2] - a[2]}, v[3] = {c[0] - a[0], c[1] - a[1], c[2] - a[2]};
        double n[3] = {u[1] * v[2] - u[2] * v[1], u[2] * v[0] - u[0] * v[2], u[0] * v[1] - u[1] * v[0]};
        for (int k = 0; k < 3; ++k)
            for (int d = 0; d < 3; ++d)
                normals[3 * (size_t)corner[k] + d] += n[d];
    }
    for (size_t v = 0; v < (size_t)mesh->vertex_count; ++v) {
        double *n = &normals[3 * v];
        double length = std::sqrt(n[0] * n[0] + n[1] * n[1] + n[2] * n[2]);
        if (length > 0 && std::isfinite(length)) {
            n[0] /= length, n[1] /= length, n[2] /= length;
        } else {
            n[0] = n[1] = 0, n[2] = 1;
        }
    }
    return normals;
}

/* A primitive's vertex: original vertex in the high half, UV index (or UINT32_MAX) in the low half. */
uint64_t corner_key(const pz_mesh *mesh, int64_t corner)
{
    uint32_t uv = mesh->corner_uvs ? (uint32_t)mesh->corner_uvs[corner] : 0u;
    return (uint64_t)(uint32_t)mesh->faces[corner] << 32 | uv;
}

struct WriteContext {
    const pz_mesh *mesh;
    const std::vector<double> &normals;
    int32_t pose_count;
    bool write_ids;
};

/* Writes the faces `group` (one label) as a primitive with its own vertices; `extra_vertices` go in unreferenced. */
tinygltf::Primitive write_primitive(GlbBuilder &builder, const WriteContext &context, const std::vector<int32_t> &group,
                                    const std::vector<int32_t> &extra_vertices)
{
    const pz_mesh *mesh = context.mesh;
    std::vector<uint64_t> keys;
    keys.reserve(group.size() * 3 + extra_vertices.size());
    for (int32_t f : group)
        for (int k = 0; k < 3; ++k)
            keys.push_back(corner_key(mesh, 3 * (int64_t)f + k));
    for (int32_t v : extra_vertices)
        keys.push_back((uint64_t)(uint32_t)v << 32 | UINT32_MAX);
    std::sort(keys.begin(), keys.end());
    keys.erase(std::unique(keys.begin(), keys.end()), keys.end());

    size_t row_count = keys.size();
    std::vector<float> positions(row_count * 3), normals(row_count * 3), ids(row_count), texcoords;
    if (mesh->corner_uvs)
        texcoords.resize(row_count * 2);
    for (size_t r = 0; r < row_count; ++r) {
        size_t vertex = (size_t)(keys[r] >> 32);
        uint32_t uv = (uint32_t)keys[r];
        for (int d = 0; d < 3; ++d) {
            positions[3 * r + d] = (float)mesh->positions[3 * vertex + d];
            normals[3 * r + d] = (float)context.normals[3 * vertex + d];
        }
        ids[r] = (float)vertex;
        if (mesh->corner_uvs && uv != UINT32_MAX) {
            texcoords[2 * r] = (float)mesh->uvs[2 * (size_t)uv];
            texcoords[2 * r + 1] = (float)(1.0 - mesh->uvs[2 * (size_t)uv + 1]);
        }
    }
    std::vector<uint32_t> indices;
    indices.reserve(group.size() * 3);
    for (int32_t f : group)
        for (int k = 0; k < 3; ++k) {
            uint64_t key = corner_key(mesh, 3 * (int64_t)f + k);
            indices.push_back((uint32_t)(std::lower_bound(keys.begin(), keys.end(), key) - keys.begin()));
        }

    tinygltf::Primitive primitive;
    primitive.mode = TINYGLTF_MODE_TRIANGLES;
    primitive.attributes["POSITION"] = builder.add_floats(positions, 3, true);
    primitive.attributes["NORMAL"] = builder.add_floats(normals, 3, false);
    if (mesh->corner_uvs)
        primitive.attributes["TEXCOORD_0"] = builder.add_floats(texcoords, 2, false);
    if (context.write_ids)
        primitive.attributes[kVertexIdAttribute] = builder.add_floats(ids, 1, false);
    primitive.indices = builder.add_indices(indices);
    for (int32_t p = 0; p < context.pose_count; ++p) {
        const double *pose = mesh->poses + (size_t)p * (size_t)mesh->vertex_count * 3;
        std::vector<float> displacement(row_count * 3);
        for (size_t r = 0; r < row_count; ++r) {
            size_t vertex = (size_t)(keys[r] >> 32);
            /* Relative to the stored float rest position, so rest + displacement rounds only once. */
            for (int d = 0; d < 3; ++d)
                displacement[3 * r + d] = (float)(pose[3 * vertex + d] - (double)positions[3 * r + d]);
        }
        primitive.targets.push_back({{"POSITION", builder.add_floats(displacement, 3, true)}});
    }
    return primitive;
}

tinygltf::Material label_material(const pz_mesh *mesh, int32_t label, const pz_write_options *options)
{
    uint32_t colour = kUnlabelledColor;
    if (label >= 0)
        colour = options && options->label_colors ? options->label_colors[label] : kPalette[label % 12];
    tinygltf::Material material;
    if (label >= 0 && mesh->label_names && mesh->label_names[label])
        material.name = mesh->label_names[label];
    double alpha = (colour & 0xff) / 255.0;
    material.pbrMetallicRoughness.baseColorFactor = {srgb_to_linear((colour >> 24 & 0xff) / 255.0),
                                                     srgb_to_linear((colour >> 16 & 0xff) / 255.0),
                                                     srgb_to_linear((colour >> 8 & 0xff) / 255.0), alpha};
    material.pbrMetallicRoughness.metallicFactor = 0.0; /* cloth is a dielectric */
    material.pbrMetallicRoughness.roughnessFactor = 0.9;
    material.doubleSided = true; /* a garment is a thin shell seen from both sides */
    if (alpha < 1.0)
        material.alphaMode = "BLEND";
    return material;
}

/* The stem of a path ("out/bodice.glb" -> "bodice"), used to name the mesh and node. */
std::string path_stem(const std::string &path)
{
    size_t slash = path.find_last_of('/');
    std::string base = slash == std::string::npos ? path : path.substr(slash + 1);
    size_t dot = base.find_last_of('.');
    return dot == std::string::npos || dot == 0 ? base : base.substr(0, dot);
}

void build_model(GlbBuilder &builder, const pz_mesh *mesh, const pz_write_options *options, const std::string &path)
{
    tinygltf::Model &model = builder.model;
    model.asset.version = "2.0";
    model.asset.generator = kGenerator;
    if (options && options->extras_json) {
        nlohmann::json extras = nlohmann::json::parse(options->extras_json, nullptr, false);
        if (extras.is_discarded() || !extras.is_object())
            fail(PZ_ERR_USAGE, path + ": the metadata (extras) is not a JSON object");
        model.asset.extras = json_to_value(extras);
    }
    bool write_poses = mesh->poses && mesh->pose_count > 0 && !(options && options->write_poses < 0);
    std::vector<double> normals = vertex_normals(mesh);
    WriteContext context{mesh, normals, write_poses ? mesh->pose_count : 0,
                         (double)mesh->vertex_count <= kFloatExactIntegers};

    /* Faces grouped by label, in label order (one group without labels). */
    int32_t group_count = mesh->face_labels ? mesh->label_count : 1;
    std::vector<std::vector<int32_t>> groups((size_t)std::max(group_count, 1));
    for (int32_t f = 0; f < mesh->face_count; ++f)
        groups[mesh->face_labels ? (size_t)mesh->face_labels[f] : 0].push_back(f);
    std::vector<char> referenced((size_t)mesh->vertex_count, 0);
    for (int64_t i = 0; i < 3 * (int64_t)mesh->face_count; ++i)
        referenced[(size_t)mesh->faces[i]] = 1;
    std::vector<int32_t> unreferenced;
    for (int32_t v = 0; v < mesh->vertex_count; ++v)
        if (!referenced[(size_t)v])
            unreferenced.push_back(v);

    /* Grouping by label reorders interleaved faces: then each primitive records its faces' original indices. */
    bool labels_interleaved = false;
    for (int32_t f = 1; mesh->face_labels && f < mesh->face_count; ++f)
        labels_interleaved = labels_interleaved || mesh->face_labels[f] < mesh->face_labels[f - 1];

    tinygltf::Mesh gltf_mesh;
    gltf_mesh.name = path_stem(path);
    for (size_t g = 0; g < groups.size(); ++g) {
        if (groups[g].empty())
            continue;
        int32_t label = mesh->face_labels ? (int32_t)g : -1;
        tinygltf::Primitive primitive = write_primitive(builder, context, groups[g], unreferenced);
        unreferenced.clear();
        model.materials.push_back(label_material(mesh, label, options));
        primitive.material = (int)model.materials.size() - 1;
        tinygltf::Value::Object extras;
        if (label >= 0)
            extras[kLabelExtra] = tinygltf::Value((int)label);
        if (labels_interleaved) {
            std::vector<uint32_t> face_ids(groups[g].begin(), groups[g].end());
            extras[kFaceIdsExtra] = tinygltf::Value(builder.add_indices(face_ids, 0));
        }
        if (!extras.empty())
            primitive.extras = tinygltf::Value(std::move(extras));
        gltf_mesh.primitives.push_back(std::move(primitive));
    }
    tinygltf::Value::Object mesh_extras;
    if (context.pose_count > 0) {
        gltf_mesh.weights.assign((size_t)context.pose_count, 0.0);
        tinygltf::Value::Array names;
        for (int32_t p = 0; p < context.pose_count; ++p)
            names.push_back(tinygltf::Value("pose" + std::to_string(p + 1)));
        mesh_extras["targetNames"] = tinygltf::Value(std::move(names));
    }
    if (mesh->face_labels) {
        tinygltf::Value::Array names;
        for (int32_t l = 0; l < mesh->label_count; ++l) {
            /* "" for an unnamed label: tinygltf drops null array elements, which would shift the rest. */
            const char *name = mesh->label_names && mesh->label_names[l] ? mesh->label_names[l] : "";
            names.push_back(tinygltf::Value(std::string(name)));
        }
        mesh_extras[kLabelNamesExtra] = tinygltf::Value(std::move(names));
    }
    if (!mesh_extras.empty())
        gltf_mesh.extras = tinygltf::Value(std::move(mesh_extras));
    model.meshes.push_back(std::move(gltf_mesh));
    tinygltf::Node node;
    node.mesh = 0;
    node.name = path_stem(path);
    model.nodes.push_back(node);
    tinygltf::Scene scene;
    scene.nodes = {0};
    model.scenes.push_back(scene);
    model.defaultScene = 0;
    model.buffers[0].data.resize((model.buffers[0].data.size() + 3) & ~(size_t)3, 0);
}

pz_status write_glb(const pz_mesh *mesh, const char *path, const pz_write_options *options, pz_ctx *ctx)
{
    check_writable(mesh, path);
    GlbBuilder builder;
    build_model(builder, mesh, options, path);
    std::ostringstream stream;
    tinygltf::TinyGLTF writer;
    if (!writer.WriteGltfSceneToStream(&builder.model, stream, false, true))
        fail(PZ_ERR_INTERNAL, std::string(path) + ": tinygltf could not serialize the model");
    const std::string bytes = stream.str();
    pz_output output;
    pz_status status = pz_output_open(&output, path, "wb", ctx);
    if (status != PZ_OK)
        return status;
    std::fwrite(bytes.data(), 1, bytes.size(), output.file);
    return pz_output_commit(&output, ctx);
}

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

} // namespace

extern "C" pz_status pz_gltf_read_memory(const unsigned char *data, size_t size, int binary, const char *base_dir,
                                         const char *name, pz_mesh **out, pz_ctx *ctx)
{
    *out = nullptr;
    const char *shown = name ? name : "glTF";
    return guarded(ctx, shown, [&]() -> pz_status {
        std::string label(shown);
        tinygltf::Model model;
        load_model(model, data, size, binary, base_dir, label);
        uint64_t byte_budget = size;
        for (const tinygltf::Buffer &buffer : model.buffers)
            byte_budget += buffer.data.size();
        Gathered gathered = Reader(model, label, byte_budget, ctx).run();
        *out = build_mesh(gathered, ctx);
        return PZ_OK;
    });
}

extern "C" pz_status pz_glb_write(const pz_mesh *mesh, const char *path, const pz_write_options *options, pz_ctx *ctx)
{
    return guarded(ctx, path, [&]() -> pz_status { return write_glb(mesh, path, options, ctx); });
}

/* ------------------------------------------------------------------ */
/* garment.glb: colours per panel, pattern texcoords, seam lines      */
/* ------------------------------------------------------------------ */

/*
 * pz_glb_write_garment (mesh/gltf_shim.h, for export/glb.c): the same buffer
 * layout as pz_glb_write (GlbBuilder: tight, 4-byte aligned views with their
 * targets), one mesh with a TRIANGLES primitive whose vertices are the given
 * ones (no regrouping: the caller's vertices are already split where the
 * pattern differs) and COLOR_0 as float VEC3 in linear space, plus a LINES
 * primitive; positions in metres (the input's millimetres x 0.001, so
 * Blender and AR viewers show the garment at its size); the bytes go to the
 * caller's stream (the export writes all files through temporaries and
 * renames them together).
 */

namespace {

void check_garment(const pz_glb_garment *garment, const std::string &what)
{
    if (garment->face_count <= 0 || garment->vertex_count <= 0)
        fail(PZ_ERR_INVALID_MESH, what + ": a glTF mesh needs at least one face");
    for (int64_t i = 0; i < 3 * (int64_t)garment->face_count; ++i)
        if (garment->faces[i] < 0 || garment->faces[i] >= garment->vertex_count)
            fail(PZ_ERR_INVALID_MESH, what + ": face " + std::to_string(i / 3) + " has a vertex index out of range");
    for (int64_t i = 0; i < garment->line_index_count; ++i)
        if (garment->line_indices[i] < 0 || garment->line_indices[i] >= garment->line_point_count)
            fail(PZ_ERR_INVALID_MESH, what + ": seam line index out of range");
    if (garment->line_index_count % 2)
        fail(PZ_ERR_INVALID_MESH, what + ": seam lines need pairs of indices");
    for (int64_t i = 0; i < 3 * (int64_t)garment->vertex_count; ++i)
        if (!std::isfinite((float)garment->positions[i]))
            fail(PZ_ERR_INVALID_MESH, what + ": vertex " + std::to_string(i / 3) + " is not a finite float");
    for (int64_t i = 0; i < 3 * (int64_t)garment->line_point_count; ++i)
        if (!std::isfinite((float)garment->line_points[i]))
            fail(PZ_ERR_INVALID_MESH, what + ": a seam point is not a finite float");
}

tinygltf::Material plain_material(const char *name, double grey)
{
    tinygltf::Material material;
    material.name = name;
    material.pbrMetallicRoughness.baseColorFactor = {grey, grey, grey, 1.0};
    material.pbrMetallicRoughness.metallicFactor = 0.0;
    material.pbrMetallicRoughness.roughnessFactor = 0.9;
    material.doubleSided = true;
    return material;
}

/* glTF's unit is the metre (spec 3.4); panelize works in millimetres. */
constexpr double kMetresPerMm = 0.001;

/* Colour of group g: the palette, then hues 137.5 degrees apart (the golden angle) should a colouring need more. */
uint32_t group_colour(int32_t group)
{
    if (group < 12)
        return kPalette[group];
    double hue = std::fmod((group - 12) * 137.50776405, 360.0) / 60.0, saturation = 0.55, value = 0.85;
    double chroma = value * saturation, x = chroma * (1 - std::fabs(std::fmod(hue, 2.0) - 1)), m = value - chroma;
    double rgb[3] = {0, 0, 0};
    int sector = (int)hue % 6;
    const int order[6][3] = {{0, 1, 2}, {1, 0, 2}, {1, 2, 0}, {2, 1, 0}, {2, 0, 1}, {0, 2, 1}};
    rgb[order[sector][0]] = chroma, rgb[order[sector][1]] = x;  /* the largest, the middle, 0 */
    uint32_t packed = 0xff;
    for (int d = 0; d < 3; ++d)
        packed |= (uint32_t)std::lround((rgb[d] + m) * 255) << (24 - 8 * d);
    return packed;
}

void build_garment_model(GlbBuilder &builder, const pz_glb_garment *garment)
{
    tinygltf::Model &model = builder.model;
    model.asset.version = "2.0";
    model.asset.generator = kGenerator;
    size_t vertex_count = (size_t)garment->vertex_count;
    /* Normals through the mesh helper: a pz_mesh view of the borrowed arrays. */
    pz_mesh view{};
    view.vertex_count = garment->vertex_count;
    view.face_count = garment->face_count;
    view.positions = const_cast<double *>(garment->positions);
    view.faces = const_cast<int32_t *>(garment->faces);
    std::vector<double> normals = vertex_normals(&view);
    std::vector<float> positions(vertex_count * 3), normal_floats(vertex_count * 3), colours(vertex_count * 3),
        texcoords;
    for (size_t v = 0; v < vertex_count; ++v) {
        uint32_t colour = group_colour(std::max(garment->vertex_group[v], 0));
        for (int d = 0; d < 3; ++d) {
            positions[3 * v + d] = (float)(garment->positions[3 * v + d] * kMetresPerMm);
            normal_floats[3 * v + d] = (float)normals[3 * v + d];
            colours[3 * v + d] = (float)srgb_to_linear((colour >> (24 - 8 * d) & 0xff) / 255.0);
        }
    }
    if (garment->texcoords) {
        texcoords.resize(vertex_count * 2);
        for (size_t v = 0; v < vertex_count; ++v) {
            texcoords[2 * v] = (float)garment->texcoords[2 * v];
            texcoords[2 * v + 1] = (float)(1.0 - garment->texcoords[2 * v + 1]);
        }
    }
    std::vector<uint32_t> indices(garment->faces, garment->faces + 3 * (size_t)garment->face_count);

    tinygltf::Mesh mesh;
    mesh.name = garment->name ? garment->name : "garment";
    tinygltf::Primitive surface;
    surface.mode = TINYGLTF_MODE_TRIANGLES;
    surface.attributes["POSITION"] = builder.add_floats(positions, 3, true);
    surface.attributes["NORMAL"] = builder.add_floats(normal_floats, 3, false);
    surface.attributes["COLOR_0"] = builder.add_floats(colours, 3, false);
    if (garment->texcoords)
        surface.attributes["TEXCOORD_0"] = builder.add_floats(texcoords, 2, false);
    surface.indices = builder.add_indices(indices);
    model.materials.push_back(plain_material("panels", 1.0)); /* white: COLOR_0 shows as is */
    surface.material = 0;
    mesh.primitives.push_back(std::move(surface));

    if (garment->line_index_count > 0) {
        std::vector<float> points((size_t)garment->line_point_count * 3);
        for (size_t i = 0; i < points.size(); ++i)
            points[i] = (float)(garment->line_points[i] * kMetresPerMm);
        std::vector<uint32_t> segments(garment->line_indices, garment->line_indices + garment->line_index_count);
        tinygltf::Primitive seams;
        seams.mode = TINYGLTF_MODE_LINE;
        seams.attributes["POSITION"] = builder.add_floats(points, 3, true);
        seams.indices = builder.add_indices(segments);
        model.materials.push_back(plain_material("seams", 0.02));
        seams.material = 1;
        mesh.primitives.push_back(std::move(seams));
    }
    model.meshes.push_back(std::move(mesh));
    tinygltf::Node node;
    node.mesh = 0;
    node.name = garment->name ? garment->name : "garment";
    model.nodes.push_back(node);
    tinygltf::Scene scene;
    scene.nodes = {0};
    model.scenes.push_back(scene);
    model.defaultScene = 0;
    model.buffers[0].data.resize((model.buffers[0].data.size() + 3) & ~(size_t)3, 0);
}

} // namespace

extern "C" pz_status pz_glb_write_garment(const pz_glb_garment *garment, FILE *file, const char *what, pz_ctx *ctx)
{
    const char *shown = what ? what : "garment.glb";
    return guarded(ctx, shown, [&]() -> pz_status {
        check_garment(garment, shown);
        GlbBuilder builder;
        build_garment_model(builder, garment);
        std::ostringstream stream;
        tinygltf::TinyGLTF writer;
        if (!writer.WriteGltfSceneToStream(&builder.model, stream, false, true))
            fail(PZ_ERR_INTERNAL, std::string(shown) + ": tinygltf could not serialize the model");
        const std::string bytes = stream.str();
        if (std::fwrite(bytes.data(), 1, bytes.size(), file) != bytes.size() || std::fflush(file) != 0)
            fail(PZ_ERR_CREATE, std::string(shown) + ": write error");
        return PZ_OK;
    });
}

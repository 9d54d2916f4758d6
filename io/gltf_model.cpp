/*
 * io/gltf_model.cpp -- the layer under the glTF reader: a model loaded
 * safely, and checked access to it (io/gltf_internal.hpp).
 *
 *  - Loading: the GLB header and chunk lengths are checked before tinygltf
 *    sees them (tinygltf 2.7 lets the BIN chunk run 8 bytes past the end);
 *    JSON nested deeper than 64 levels is refused (tinygltf converts it
 *    recursively and would overflow the stack). External files: base_dir
 *    NULL forbids every filesystem access (only the GLB's BIN chunk and
 *    data: URIs are read); with a base_dir only files under it are read (no
 *    absolute URIs, no ".."). Images are not decoded.
 *  - Access: node transforms (matrix, or T * R * S with the rotation
 *    normalized), and accessors of any component type with their sparse
 *    substitutions, every buffer view, accessor and stride checked against
 *    its buffer (tinygltf does not check them). The data is little-endian
 *    as the spec says; the shim assumes a little-endian host.
 *
 * SPDX-License-Identifier: GPL-3.0-or-later
 */
#include "io/gltf_internal.hpp"

#include <algorithm>
#include <climits>
#include <cmath>
#include <cstdio>
#include <cstring>
#include <string>
#include <vector>

namespace pz_gltf {

namespace {

/* ------------------------------------------------------------------ */
/* Loading: filesystem access for external URIs, container checks    */
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

} // namespace

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
/* Node transforms                                                    */
/* ------------------------------------------------------------------ */

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

namespace {

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
/* A component as T: doubles as read; 32-bit indices with what no index can be (negative, fractional or past
 * 2^32 - 1) as UINT32_MAX, which every range check refuses (a cast would be undefined behaviour). */
template <typename T> T component_as(double value)
{
    return (T)value;
}
template <> uint32_t component_as<uint32_t>(double value)
{
    return value >= 0 && value < 4294967295.0 && value == std::floor(value) ? (uint32_t)value : UINT32_MAX;
}

template <typename T>
void apply_sparse(const tinygltf::Model &model, const tinygltf::Accessor &accessor, int components,
                  uint64_t element_size, bool normalized, std::vector<T> &values, const std::string &what)
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
                component_as<T>(read_component(element + c * component_bytes, accessor.componentType, normalized));
    }
}

/* The accessor's values as T (double; uint32_t for indices, which the range checks then bound). */
template <typename T>
std::vector<T> read_accessor_as(const tinygltf::Model &model, int index, AccessorUse use, int components,
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
    std::vector<T> values;
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
                values[i * components + c] =
                    component_as<T>(read_component(base + i * stride + c * component_bytes, ct, normalized));
    } else {
        if (count > byte_budget)
            fail_data(what + ": accessor " + std::to_string(index) + " declares " + std::to_string(count) +
                      " elements without data");
        values.assign(count * (uint64_t)components, T());
    }
    if (accessor.sparse.isSparse)
        apply_sparse(model, accessor, components, element_size, normalized, values, what);
    return values;
}

} // namespace

std::vector<double> read_accessor(const tinygltf::Model &model, int index, AccessorUse use, int components,
                                  uint64_t byte_budget, const std::string &what)
{
    return read_accessor_as<double>(model, index, use, components, byte_budget, what);
}

std::vector<uint32_t> read_index_accessor(const tinygltf::Model &model, int index, uint64_t byte_budget,
                                          const std::string &what)
{
    /* A signed component below 0 wraps past any vertex count: the caller's range check refuses it. */
    return read_accessor_as<uint32_t>(model, index, AccessorUse::Index, 1, byte_budget, what);
}

uint64_t accessor_count(const tinygltf::Model &model, int index)
{
    return index >= 0 && (size_t)index < model.accessors.size() ? model.accessors[(size_t)index].count : 0;
}

} // namespace pz_gltf

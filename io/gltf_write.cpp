/*
 * io/gltf_write.cpp -- a mesh out as GLB, through tinygltf: pz_glb_write of
 * io/io.h, and the palette and colour conversion the GLB writers share
 * (pz_glb_label_color, pz_glb_color_linear; export/glb_shim.cpp writes
 * garment.glb with them). Every exception is caught at the extern "C"
 * boundary and becomes a pz_status with a one-line message.
 *
 *  - Errors: PZ_ERR_DATA "NAME: problem" (tinygltf's messages condensed to
 *    one line), PZ_ERR_NOMEM. The data is little-endian as the spec says; the
 *    shim assumes a little-endian host.
 *
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
 *
 * SPDX-License-Identifier: GPL-3.0-or-later
 */
#include "io/gltf_internal.hpp"

#include <nlohmann/json.hpp>

#include <algorithm>
#include <climits>
#include <cmath>
#include <cstdio>
#include <sstream>
#include <string>
#include <vector>

namespace pz_gltf {

namespace {

const char *const kGenerator = "panelize " PZ_VERSION_STRING;
/* Integers a float32 holds exactly. */
const double kFloatExactIntegers = 16777216.0;
const uint32_t kUnlabelledColor = 0xd8d0c0ff; /* undyed cotton */

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
    std::vector<double> normals((size_t)mesh->vertex_count * 3);
    pz_geom_vertex_normals(mesh, normals.data());
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
        colour = options && options->label_colors ? options->label_colors[label] : pz_glb_label_color(label);
    tinygltf::Material material;
    if (label >= 0 && mesh->label_names && mesh->label_names[label])
        material.name = mesh->label_names[label];
    double linear[4];
    pz_glb_color_linear(colour, linear);
    double alpha = linear[3];
    material.pbrMetallicRoughness.baseColorFactor = {linear[0], linear[1], linear[2], alpha};
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

} // namespace

} // namespace pz_gltf

/* 12 colours that stay apart from each other (sRGB, RGBA8). */
static const uint32_t kPalette[12] = {0x4e79a7ff, 0xf28e2bff, 0xe15759ff, 0x76b7b2ff, 0x59a14fff, 0xedc948ff,
                                      0xb07aa1ff, 0xff9da7ff, 0x9c755fff, 0xbab0acff, 0x86bcb6ff, 0xd37295ff};

static double srgb_to_linear(double value)
{
    return value <= 0.04045 ? value / 12.92 : std::pow((value + 0.055) / 1.055, 2.4);
}

extern "C" uint32_t pz_glb_label_color(int32_t label)
{
    return kPalette[label % 12];
}

extern "C" void pz_glb_color_linear(uint32_t rgba, double linear[4])
{
    for (int channel = 0; channel < 3; ++channel)
        linear[channel] = srgb_to_linear((rgba >> (24 - 8 * channel) & 0xff) / 255.0);
    linear[3] = (rgba & 0xff) / 255.0;
}

extern "C" pz_status pz_glb_write(const pz_mesh *mesh, const char *path, const pz_write_options *options, pz_ctx *ctx)
{
    return pz_gltf::guarded(ctx, path, [&]() -> pz_status { return pz_gltf::write_glb(mesh, path, options, ctx); });
}

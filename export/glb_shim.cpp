/*
 * export/glb_shim.cpp -- garment.glb through tinygltf: pz_glb_write_garment
 * of export/glb_shim.h, for export/glb.c. The only C++ of export; every
 * exception is caught at the extern "C" boundary and becomes a pz_status
 * with a one-line "NAME: problem" message.
 *
 * The buffer layout is that of io's plain mesh GLB (io/gltf_write.cpp):
 * tight, 4-byte aligned views with their targets. One mesh with a TRIANGLES
 * primitive whose vertices are the given ones (no regrouping: the caller's
 * vertices are already split where the pattern differs), NORMAL the
 * area-weighted vertex normals (pz_geom_vertex_normals) and COLOR_0 as
 * float VEC3 in linear space (io's palette, pz_glb_label_color, then hues a
 * golden angle apart; pz_glb_color_linear), plus a LINES primitive;
 * positions in metres (the input's millimetres x 0.001, so Blender and AR
 * viewers show the garment at its size); the bytes go to the caller's
 * stream (the export writes all files through temporaries and renames them
 * together).
 *
 * SPDX-License-Identifier: GPL-3.0-or-later
 */
#include "export/glb_shim.h"
#include "io/io.h"

#include <tiny_gltf.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <exception>
#include <new>
#include <sstream>
#include <string>
#include <vector>

namespace {

const char *const kGenerator = "panelize " PZ_VERSION_STRING;

/* A failure inside the shim; turned into a pz_status at the extern "C" boundary. */
struct ShimError {
    pz_status status;
    std::string message;
};

[[noreturn]] void fail(pz_status status, const std::string &message)
{
    throw ShimError{status, message};
}

/* A model with one buffer that views and accessors are appended to. */
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

    /* UNSIGNED_INT vertex indices (target ELEMENT_ARRAY_BUFFER). */
    int add_indices(const std::vector<uint32_t> &indices)
    {
        tinygltf::Accessor accessor;
        accessor.bufferView = add_view(indices.data(), indices.size() * sizeof(uint32_t),
                                       TINYGLTF_TARGET_ELEMENT_ARRAY_BUFFER);
        accessor.componentType = TINYGLTF_COMPONENT_TYPE_UNSIGNED_INT;
        accessor.type = TINYGLTF_TYPE_SCALAR;
        accessor.count = indices.size();
        model.accessors.push_back(accessor);
        return (int)model.accessors.size() - 1;
    }
};

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
        return pz_glb_label_color(group);
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
    std::vector<double> normals(vertex_count * 3);
    pz_geom_vertex_normals(&view, normals.data());
    std::vector<float> positions(vertex_count * 3), normal_floats(vertex_count * 3), colours(vertex_count * 3),
        texcoords;
    for (size_t v = 0; v < vertex_count; ++v) {
        double colour[4];
        pz_glb_color_linear(group_colour(std::max(garment->vertex_group[v], 0)), colour);
        for (int d = 0; d < 3; ++d) {
            positions[3 * v + d] = (float)(garment->positions[3 * v + d] * kMetresPerMm);
            normal_floats[3 * v + d] = (float)normals[3 * v + d];
            colours[3 * v + d] = (float)colour[d];
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

/* The GLB bytes of `garment`, serialized by tinygltf. */
std::string garment_bytes(const pz_glb_garment *garment, const std::string &what)
{
    check_garment(garment, what);
    GlbBuilder builder;
    build_garment_model(builder, garment);
    std::ostringstream stream;
    tinygltf::TinyGLTF writer;
    if (!writer.WriteGltfSceneToStream(&builder.model, stream, false, true))
        fail(PZ_ERR_INTERNAL, what + ": tinygltf could not serialize the model");
    return stream.str();
}

} // namespace

extern "C" pz_status pz_glb_write_garment(const pz_glb_garment *garment, FILE *file, const char *what, pz_ctx *ctx)
{
    const char *shown = what ? what : "garment.glb";
    try {
        const std::string bytes = garment_bytes(garment, shown);
        if (std::fwrite(bytes.data(), 1, bytes.size(), file) != bytes.size() || std::fflush(file) != 0)
            return pz_error(ctx, PZ_ERR_CREATE, "%s: write error", shown);
        return PZ_OK;
    } catch (const ShimError &error) {
        return pz_error(ctx, error.status, "%s", error.message.c_str());
    } catch (const std::bad_alloc &) {
        return pz_error(ctx, PZ_ERR_NOMEM, "%s: out of memory", shown);
    } catch (const std::exception &error) { /* tinygltf's JSON writer: a name that is not UTF-8 */
        return pz_error(ctx, PZ_ERR_DATA, "%s: %s", shown, error.what());
    } catch (...) {
        return pz_error(ctx, PZ_ERR_INTERNAL, "%s: unexpected failure in the GLB shim", shown);
    }
}

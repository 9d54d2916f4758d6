/*
 * io/gltf_read.cpp -- glTF 2.0 in (binary GLB or JSON), through tinygltf:
 * pz_gltf_read_memory of io/io.h. Every exception (bad_alloc, tinygltf's,
 * ours) is caught at that boundary and becomes a pz_status with a one-line
 * "NAME: problem" message. Loading and the checked access to the model's
 * transforms and accessors are io/gltf_model.cpp's.
 *
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
 *    must have the same number of targets, at most PZ_MESH_MAX_POSES. mesh.weights are ignored: the rest
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
 * SPDX-License-Identifier: GPL-3.0-or-later
 */
#include "io/gltf_internal.hpp"

#include <algorithm>
#include <climits>
#include <cmath>
#include <cstdlib>
#include <cstring>
#include <map>
#include <numeric>
#include <string>
#include <vector>

namespace pz_gltf {

namespace {

/* Geometry may expand this many elements per input byte through instancing. */
const uint64_t kExpansionPerByte = 16;

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
    std::vector<uint32_t> faces;               /* face_count x 3 (vertex indices below 2^31) */
    std::vector<int32_t> face_labels;          /* face_count */
    std::vector<double> corner_uv_values;      /* face_count x 3 x 2, glTF values already flipped */
    bool uvs_present = false;
    bool uvs_missing = false;
    std::vector<std::string> label_names;
    std::vector<char> label_named;
    bool labelled = false;
};

/* Frees a vector's memory now (clear() keeps the capacity). */
template <typename T> void release(std::vector<T> &values)
{
    std::vector<T>().swap(values);
}

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
    std::vector<uint32_t> face_ids_;
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
                if (target_count > PZ_MESH_MAX_POSES)
                    fail_data(mesh_what((int)m, (int)p) + ": has " + std::to_string(target_count) +
                              " morph targets (at most " + std::to_string(PZ_MESH_MAX_POSES) + " poses are supported)");
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
            uint32_t id = face_ids_[f];
            if (id >= face_count || source[id] != UINT32_MAX)
                return;
            source[id] = (uint32_t)f;
        }
        release(face_ids_);
        /* One array at a time, each old one freed before the next is copied. */
        Gathered &g = gathered_;
        permute(g.faces, source, 3);
        permute(g.face_labels, source, 1);
        permute(g.corner_uv_values, source, 6);
    }

    /* values (width per face; may be empty) in the order source gives: face f is the old face source[f]. */
    template <typename T> static void permute(std::vector<T> &values, const std::vector<uint32_t> &source, size_t width)
    {
        if (values.empty())
            return;
        std::vector<T> ordered(values.size());
        for (size_t f = 0; f < source.size(); ++f)
            std::copy_n(&values[width * source[f]], width, &ordered[width * f]);
        values.swap(ordered);
    }

    /* Reserves room for `more` elements: exactly the first time, at least a quarter more after. */
    template <typename T> static void grow(std::vector<T> &values, size_t more)
    {
        size_t needed = values.size() + more;
        if (needed > values.capacity())
            values.reserve(std::max(needed, values.capacity() + values.capacity() / 4));
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
        std::vector<uint32_t> ids = read_index_accessor(model_, primitive.extras.Get(kFaceIdsExtra).Get<int>(),
                                                        byte_budget_, what + " " + kFaceIdsExtra);
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
            order = read_index_accessor(model_, primitive.indices, byte_budget_, what + " indices");
            for (uint32_t index : order)
                if (index >= row_count)
                    fail_data(what + ": index " + (index == UINT32_MAX ? std::string("below 0 or past 2^32") :
                                                   std::to_string(index)) +
                              " out of range (" + std::to_string(row_count) + " vertices)");
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

        std::vector<double>().swap(rows); /* applied: freed before the triangles are read */
        std::vector<std::vector<double>>().swap(target_rows);

        std::vector<double> texcoords;
        auto texcoord = primitive.attributes.find("TEXCOORD_0");
        if (texcoord != primitive.attributes.end()) {
            texcoords = read_accessor(model_, texcoord->second, AccessorUse::Texcoord, 2, byte_budget_,
                                      what + " TEXCOORD_0");
            if (texcoords.size() / 2 != row_count)
                fail_data(what + ": TEXCOORD_0 and POSITION differ in count");
            gathered_.uvs_present = true;
        } else {
            gathered_.uvs_missing = true; /* the UVs are dropped: none kept from here on */
            std::vector<double>().swap(gathered_.corner_uv_values);
        }
        bool keep_uvs = !gathered_.uvs_missing;

        std::vector<uint32_t> triangles = primitive_triangles(primitive, row_count, what);
        read_face_ids(primitive, triangles.size() / 3, what);
        bool flip = matrix_determinant3(instance.world) < 0;
        int32_t label = plans_[(size_t)instance.mesh_index][(size_t)primitive_index].label;
        /* Room for this primitive's faces at once (one primitive: exactly, no doubling), a quarter more when
         * several primitives grow the arrays in turn. */
        /* The first primitive's triangles become the faces in place (no second array of them). */
        bool in_place = gathered_.faces.empty();
        if (!in_place)
            grow(gathered_.faces, triangles.size());
        grow(gathered_.face_labels, triangles.size() / 3);
        if (keep_uvs)
            grow(gathered_.corner_uv_values, 2 * triangles.size());
        for (size_t i = 0; i < triangles.size(); i += 3) {
            uint32_t corner_rows[3] = {triangles[i], flip ? triangles[i + 2] : triangles[i + 1],
                                       flip ? triangles[i + 1] : triangles[i + 2]};
            for (int k = 0; k < 3; ++k) {
                uint32_t row = corner_rows[k], vertex = (uint32_t)row_vertex[row];
                if (in_place)
                    triangles[i + (size_t)k] = vertex;
                else
                    gathered_.faces.push_back(vertex);
                if (keep_uvs) {
                    gathered_.corner_uv_values.push_back(texcoords[row * 2]);
                    gathered_.corner_uv_values.push_back(1.0 - texcoords[row * 2 + 1]);
                }
            }
            gathered_.face_labels.push_back(label);
        }
        if (in_place)
            gathered_.faces.swap(triangles);
    }
};

/*
 * Gives corners with the same vertex and the same UV value one UV index:
 * sorts the corners by (vertex, u, v). O(C log C).
 */
void index_corner_uvs(Gathered &gathered, std::vector<double> &uvs, std::vector<int32_t> &corner_uvs)
{
    size_t corner_count = gathered.faces.size();
    /* NaN would break the sort's strict weak order: such a UV reads as 0 (in place: no copy). */
    std::vector<double> &values = gathered.corner_uv_values;
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

/* Moves the gathered arrays into a new pz_mesh, each freed once copied so that the two never both hold the
 * whole mesh (throws bad_alloc; frees on failure). */
pz_mesh *build_mesh(Gathered &gathered, pz_ctx *ctx)
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
    release(gathered.positions);

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
    release(gathered.corner_uv_values);
    std::copy(gathered.faces.begin(), gathered.faces.end(), mesh->faces); /* after the UVs: they sort by it */
    release(gathered.faces);

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
        for (size_t p = 0; p < gathered.poses.size(); ++p) {
            std::copy(gathered.poses[p].begin(), gathered.poses[p].end(), mesh->poses + p * pose_size);
            release(gathered.poses[p]);
        }
        mesh->pose_count = (int32_t)gathered.poses.size();
    }
    guard.mesh = nullptr;
    return mesh;
}

} // namespace

} // namespace pz_gltf

/*
 * The reader's memory (issue 15, docs/reliability.md): tinygltf copies the
 * binary chunk into its model, so the file's bytes (`owned`) are freed as soon
 * as it has parsed them, the model as soon as the mesh is gathered, and each
 * gathered array as soon as the mesh has it.
 */
static pz_status read_gltf(const unsigned char *data, size_t size, unsigned char *owned, int binary,
                           const char *base_dir, const char *name, pz_mesh **out, pz_ctx *ctx)
{
    *out = nullptr;
    const char *shown = name ? name : "glTF";
    pz_status status = pz_gltf::guarded(ctx, shown, [&]() -> pz_status {
        std::string label(shown);
        pz_gltf::Gathered gathered;
        {
            tinygltf::Model model;
            pz_gltf::load_model(model, data, size, binary, base_dir, label);
            free(owned);
            owned = nullptr;
            uint64_t byte_budget = size;
            for (const tinygltf::Buffer &buffer : model.buffers)
                byte_budget += buffer.data.size();
            gathered = pz_gltf::Reader(model, label, byte_budget, ctx).run();
        }
        *out = pz_gltf::build_mesh(gathered, ctx);
        return PZ_OK;
    });
    free(owned);
    return status;
}

extern "C" pz_status pz_gltf_read_memory(const unsigned char *data, size_t size, int binary, const char *base_dir,
                                         const char *name, pz_mesh **out, pz_ctx *ctx)
{
    return read_gltf(data, size, nullptr, binary, base_dir, name, out, ctx);
}

extern "C" pz_status pz_gltf_read_owned(unsigned char *data, size_t size, int binary, const char *base_dir,
                                        const char *name, pz_mesh **out, pz_ctx *ctx)
{
    return read_gltf(data, size, data, binary, base_dir, name, out, ctx);
}

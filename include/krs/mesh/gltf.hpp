#pragma once
// Meshes as glTF 2.0: binary .glb (one file: JSON chunk and binary chunk) and text .gltf (the
// buffer embedded as a base64 data URI), through tinygltf (Debian's libtinygltf-dev). This header
// and the CMake target krs::mesh_gltf, provided only where tinygltf is found, are the only parts
// of krs that need it: krs::krs stays dependency-free (tests/test_dependency_free.cpp).
//
// The model: one buffer holding positions (float VEC3, with the min and max glTF requires for
// POSITION), normals (float VEC3), where the mesh has them uvs (TEXCOORD_0, float VEC2) and colours
// (COLOR_0, float VEC3, linear RGB as glTF defines it) and indices (uint32 SCALAR), each in its own
// buffer view; one
// mesh with one triangle primitive (counter-clockwise front faces, as glTF's default); one node;
// one scene. No material: viewers draw glTF's default (white, metallic 1, rough 1). An instanced
// scene (krs/mesh/instances.hpp) is written as core glTF, one node per instance over the shared
// meshes, or on request with EXT_mesh_gpu_instancing, then required (see gltf_instances_model).
//
// Up axis. glTF is y-up by its specification, as krs's scenes are. With up_axis::z
// (krs/io/up_axis.hpp) the meshes' coordinates are written z-up, as a z-up tool reading the
// buffers expects, and the scene's one root node, "krs root (z-up to glTF's y-up)", carries the
// inverse rotation: every glTF loader, which applies node transforms, still shows the scene
// upright. With up_axis::y there is no root node.
//
// Saves check the mesh (krs/mesh/write.hpp's checks) and the path, then write a temporary file and
// rename it (krs/io/write_then_rename.hpp): a failed save is a save_error and leaves no file.

#include "krs/io/up_axis.hpp"
#include "krs/io/write_then_rename.hpp"
#include "krs/mesh/instances.hpp"
#include "krs/mesh/mesh.hpp"
#include "krs/mesh/write.hpp" // detail::require_mesh

#include <tiny_gltf.h>

#include <array>
#include <bit>
#include <cmath>
#include <cstdint>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <limits>
#include <stdexcept>
#include <string>
#include <utility>
#include <vector>

namespace krs {

namespace detail {

// Appends `bytes` to the buffer, aligned to 4 bytes (glTF requires accessor offsets aligned to
// their component size), and returns the index of a new buffer view over them.
inline int add_buffer_view(tinygltf::Model& model, const void* bytes, std::size_t size, int target)
{
    auto& data = model.buffers[0].data;
    while (data.size() % 4) data.push_back(0);
    const std::size_t offset = data.size();
    data.resize(offset + size);
    std::memcpy(data.data() + offset, bytes, size);
    tinygltf::BufferView view;
    view.buffer = 0;
    view.byteOffset = offset;
    view.byteLength = size;
    view.target = target;
    model.bufferViews.push_back(view);
    return int(model.bufferViews.size() - 1);
}

inline int add_accessor(tinygltf::Model& model, int view, int component, int type, std::size_t count)
{
    tinygltf::Accessor a;
    a.bufferView = view;
    a.byteOffset = 0;
    a.componentType = component;
    a.type = type;
    a.count = count;
    model.accessors.push_back(a);
    return int(model.accessors.size() - 1);
}

// vec3f is three packed floats (static_assert below), so its array is glTF's VEC3 layout on a
// little-endian machine; a big-endian one converts byte by byte.
template <class T>
std::vector<unsigned char> little_endian_bytes(const T* values, std::size_t count)
{
    static_assert(sizeof(vec3f) == 3 * sizeof(float));
    std::vector<unsigned char> out(count * sizeof(T));
    std::memcpy(out.data(), values, out.size());
    if constexpr (std::endian::native == std::endian::big)
        for (std::size_t i = 0; i + 4 <= out.size(); i += 4) std::swap(out[i], out[i + 3]), std::swap(out[i + 1], out[i + 2]);
    return out;
}

} // namespace detail

namespace detail {

// Adds the mesh's buffer views, accessors and a glTF mesh (one triangle primitive) to the model,
// returning the mesh's index.
inline int add_gltf_mesh(tinygltf::Model& model, const triangle_mesh& m, const std::string& name, up_axis up)
{
    if (model.buffers.empty()) model.buffers.emplace_back();
    std::vector<vec3f> turned_positions, turned_normals;
    for (const vec3f& p : m.positions) turned_positions.push_back(to_file(up, p));
    for (const vec3f& n : m.normals) turned_normals.push_back(to_file(up, n));
    const auto positions = little_endian_bytes(turned_positions.data(), turned_positions.size());
    const int position = add_accessor(model, add_buffer_view(model, positions.data(), positions.size(), TINYGLTF_TARGET_ARRAY_BUFFER),
                                      TINYGLTF_COMPONENT_TYPE_FLOAT, TINYGLTF_TYPE_VEC3, m.positions.size());
    vec3f lo = turned_positions[0], hi = turned_positions[0];
    for (const vec3f& p : turned_positions) lo = min(lo, p), hi = max(hi, p);
    model.accessors[std::size_t(position)].minValues = {lo.x, lo.y, lo.z};
    model.accessors[std::size_t(position)].maxValues = {hi.x, hi.y, hi.z};

    tinygltf::Primitive primitive;
    primitive.mode = TINYGLTF_MODE_TRIANGLES;
    primitive.attributes["POSITION"] = position;
    if (!m.normals.empty()) {
        const auto normals = little_endian_bytes(turned_normals.data(), turned_normals.size());
        primitive.attributes["NORMAL"] =
            add_accessor(model, add_buffer_view(model, normals.data(), normals.size(), TINYGLTF_TARGET_ARRAY_BUFFER),
                         TINYGLTF_COMPONENT_TYPE_FLOAT, TINYGLTF_TYPE_VEC3, m.normals.size());
    }
    if (!m.uvs.empty()) {
        const auto uvs = little_endian_bytes(m.uvs.data(), m.uvs.size());
        primitive.attributes["TEXCOORD_0"] =
            add_accessor(model, add_buffer_view(model, uvs.data(), uvs.size(), TINYGLTF_TARGET_ARRAY_BUFFER),
                         TINYGLTF_COMPONENT_TYPE_FLOAT, TINYGLTF_TYPE_VEC2, m.uvs.size());
    }
    if (!m.colors.empty()) {
        const auto colors = little_endian_bytes(m.colors.data(), m.colors.size());
        primitive.attributes["COLOR_0"] =
            add_accessor(model, add_buffer_view(model, colors.data(), colors.size(), TINYGLTF_TARGET_ARRAY_BUFFER),
                         TINYGLTF_COMPONENT_TYPE_FLOAT, TINYGLTF_TYPE_VEC3, m.colors.size());
    }
    const auto indices = little_endian_bytes(m.triangles.data(), m.triangles.size());
    primitive.indices = add_accessor(model, add_buffer_view(model, indices.data(), indices.size(), TINYGLTF_TARGET_ELEMENT_ARRAY_BUFFER),
                                     TINYGLTF_COMPONENT_TYPE_UNSIGNED_INT, TINYGLTF_TYPE_SCALAR, 3 * m.triangles.size());
    tinygltf::Mesh mesh;
    mesh.name = name;
    mesh.primitives.push_back(primitive);
    model.meshes.push_back(mesh);
    return int(model.meshes.size() - 1);
}

// A model with one scene and, for up_axis::z, its root node (rotating the file's z-up back to
// glTF's y-up); add_scene_node hangs a node under it, or at the scene's top for up_axis::y.
inline tinygltf::Model empty_gltf_model(up_axis up)
{
    tinygltf::Model model;
    model.asset.version = "2.0";
    model.asset.generator = "krs (krs/mesh/gltf.hpp)";
    model.buffers.emplace_back();
    model.scenes.emplace_back();
    model.defaultScene = 0;
    if (up == up_axis::z) {
        tinygltf::Node root;
        root.name = "krs root (z-up to glTF's y-up)";
        // from_file's rotation, (x, y, z) -> (x, z, -y): -90 degrees about x, q = (-sin 45, 0, 0, cos 45).
        root.rotation = {-std::sqrt(0.5), 0, 0, std::sqrt(0.5)};
        model.nodes.push_back(root);
        model.scenes[0].nodes = {0};
    }
    return model;
}

inline void add_scene_node(tinygltf::Model& model, tinygltf::Node node, up_axis up)
{
    model.nodes.push_back(std::move(node));
    const int index = int(model.nodes.size() - 1);
    if (up == up_axis::z) model.nodes[0].children.push_back(index);
    else model.scenes[0].nodes.push_back(index);
}

} // namespace detail

// The mesh as a tinygltf model (for users who add to it before writing it themselves).
inline tinygltf::Model gltf_model(const triangle_mesh& m, up_axis up = up_axis::y)
{
    detail::require_mesh("gltf_model", m);
    tinygltf::Model model = detail::empty_gltf_model(up);
    tinygltf::Node node;
    node.mesh = detail::add_gltf_mesh(model, m, "krs_mesh", up);
    detail::add_scene_node(model, node, up);
    return model;
}

// The unit quaternion (x, y, z, w) of a rotation matrix (row-major, orthogonal, det +1), taking
// the largest of w, x, y, z from the diagonal first so that no division is by a small number.
inline std::array<double, 4> rotation_quaternion(const std::array<double, 9>& r)
{
    const double trace = r[0] + r[4] + r[8];
    std::array<double, 4> q;
    if (trace > 0) {
        const double s = 2 * std::sqrt(trace + 1);
        q = {(r[7] - r[5]) / s, (r[2] - r[6]) / s, (r[3] - r[1]) / s, s / 4};
    } else if (r[0] > r[4] && r[0] > r[8]) {
        const double s = 2 * std::sqrt(1 + r[0] - r[4] - r[8]);
        q = {s / 4, (r[1] + r[3]) / s, (r[2] + r[6]) / s, (r[7] - r[5]) / s};
    } else if (r[4] > r[8]) {
        const double s = 2 * std::sqrt(1 + r[4] - r[0] - r[8]);
        q = {(r[1] + r[3]) / s, s / 4, (r[5] + r[7]) / s, (r[2] - r[6]) / s};
    } else {
        const double s = 2 * std::sqrt(1 + r[8] - r[0] - r[4]);
        q = {(r[2] + r[6]) / s, (r[5] + r[7]) / s, s / 4, (r[3] - r[1]) / s};
    }
    const double len = std::sqrt(q[0] * q[0] + q[1] * q[1] + q[2] * q[2] + q[3] * q[3]);
    for (double& c : q) c /= len;
    return q;
}

// How an instanced scene is written: as core glTF (every loader places the instances) or with
// EXT_mesh_gpu_instancing (fewer nodes, for loaders that have it), and in which up axis.
struct gltf_instance_options {
    bool gpu_instancing = false;
    up_axis up = up_axis::y;
};

// An instanced scene (krs/mesh/instances.hpp) as a tinygltf model. Per part, its mesh and (when
// some instance is a reflection) its mirrored mesh are stored once each. By default every
// instance is a node of its own whose translation and rotation (unit quaternion x y z w) place it
// and which references the shared mesh: core glTF's reuse of a mesh by many nodes, which every
// loader draws. With `gpu_instancing`, each mesh has one node whose EXT_mesh_gpu_instancing
// attributes TRANSLATION (float VEC3) and ROTATION (float VEC4) place every instance; the
// extension is then listed in extensionsRequired as well as extensionsUsed, so a loader without
// it refuses the file instead of drawing each mesh once at the origin. Parts whose mesh has no
// triangle (a kernel smaller than a cell) are left out: instanced_part::placed says which are in.
// With up_axis::z each instance's placement is turned into the file's frame, R_up (A x + t) =
// (R_up A R_up^T) (R_up x) + R_up t, the meshes turned by R_up, all under the root node.
inline tinygltf::Model gltf_instances_model(const instanced_scene& scene, const gltf_instance_options& options = {})
{
    const up_axis up = options.up;
    tinygltf::Model model = detail::empty_gltf_model(up);
    if (options.gpu_instancing) {
        model.extensionsUsed.push_back("EXT_mesh_gpu_instancing");
        model.extensionsRequired.push_back("EXT_mesh_gpu_instancing");
    }
    const std::array<double, 9> r_up = up_rotation(up);
    const auto in_file_frame = [&](const rigid_motion& i) {
        rigid_motion f;
        for (int row = 0; row < 3; ++row)
            for (int col = 0; col < 3; ++col) {
                double sum = 0; // (R_up A R_up^T)[row][col]
                for (int a = 0; a < 3; ++a)
                    for (int b = 0; b < 3; ++b) sum += r_up[row * 3 + a] * i.rotation[a * 3 + b] * r_up[col * 3 + b];
                f.rotation[row * 3 + col] = sum;
            }
        f.translation = to_file(up, i.translation);
        return f;
    };
    std::size_t nodes = 0;
    const auto add = [&](const triangle_mesh& m, const std::vector<rigid_motion>& instances, const std::string& name) {
        if (m.triangles.empty() || instances.empty()) return;
        detail::require_mesh("gltf_instances_model", m);
        const int mesh = detail::add_gltf_mesh(model, m, name, up);
        ++nodes;
        if (!options.gpu_instancing) {
            for (std::size_t j = 0; j < instances.size(); ++j) {
                const rigid_motion f = in_file_frame(instances[j]);
                tinygltf::Node node;
                node.name = name + " #" + std::to_string(j);
                node.mesh = mesh;
                node.translation = {f.translation.x, f.translation.y, f.translation.z};
                const auto q = rotation_quaternion(f.rotation);
                node.rotation = {q[0], q[1], q[2], q[3]};
                detail::add_scene_node(model, node, up);
            }
            return;
        }
        std::vector<float> t, r;
        for (const rigid_motion& i : instances) {
            const rigid_motion f = in_file_frame(i);
            t.insert(t.end(), {float(f.translation.x), float(f.translation.y), float(f.translation.z)});
            const auto q = rotation_quaternion(f.rotation);
            r.insert(r.end(), {float(q[0]), float(q[1]), float(q[2]), float(q[3])});
        }
        tinygltf::Node node;
        node.name = name;
        node.mesh = mesh;
        const auto tb = detail::little_endian_bytes(t.data(), t.size()), rb = detail::little_endian_bytes(r.data(), r.size());
        const int ta = detail::add_accessor(model, detail::add_buffer_view(model, tb.data(), tb.size(), 0), TINYGLTF_COMPONENT_TYPE_FLOAT,
                                            TINYGLTF_TYPE_VEC3, instances.size());
        const int ra = detail::add_accessor(model, detail::add_buffer_view(model, rb.data(), rb.size(), 0), TINYGLTF_COMPONENT_TYPE_FLOAT,
                                            TINYGLTF_TYPE_VEC4, instances.size());
        tinygltf::Value::Object attributes;
        attributes["TRANSLATION"] = tinygltf::Value(ta);
        attributes["ROTATION"] = tinygltf::Value(ra);
        tinygltf::Value::Object extension;
        extension["attributes"] = tinygltf::Value(attributes);
        node.extensions["EXT_mesh_gpu_instancing"] = tinygltf::Value(extension);
        detail::add_scene_node(model, node, up);
    };
    for (const instanced_part& p : scene.parts) {
        add(p.mesh, p.direct, p.name);
        add(p.mirrored, p.reflected, p.name + " (mirrored)");
    }
    if (nodes == 0)
        throw invalid_parameter("gltf_instances_model scene", "must have at least one part with a triangle and an instance", "none");
    return model;
}

namespace detail {

inline void save_gltf_model(std::string_view caller, const tinygltf::Model& model, const std::filesystem::path& path, bool binary)
{
    write_file(caller, path, [&](std::ostream& out) {
        tinygltf::TinyGLTF writer;
        if (!writer.WriteGltfSceneToStream(&model, out, /*prettyPrint=*/!binary, /*writeBinary=*/binary))
            throw std::runtime_error("tinygltf could not write the model");
    });
}

} // namespace detail

// The mesh as a binary glTF (.glb).
inline void save_glb(const triangle_mesh& m, const std::filesystem::path& path, up_axis up = up_axis::y)
{
    detail::require_output_path("save_glb", path);
    detail::require_mesh("save_glb", m);
    detail::save_gltf_model("save_glb", gltf_model(m, up), path, true);
}

// An instanced scene as glTF (see gltf_instances_model): binary (.glb) or text (.gltf).
inline void save_gltf_instances(const instanced_scene& scene, const std::filesystem::path& path, bool binary,
                                const gltf_instance_options& options = {})
{
    detail::require_output_path("save_gltf_instances", path);
    detail::save_gltf_model("save_gltf_instances", gltf_instances_model(scene, options), path, binary);
}

// The mesh as a text glTF (.gltf) with its buffer embedded as a data URI.
inline void save_gltf(const triangle_mesh& m, const std::filesystem::path& path, up_axis up = up_axis::y)
{
    detail::require_output_path("save_gltf", path);
    detail::require_mesh("save_gltf", m);
    detail::save_gltf_model("save_gltf", gltf_model(m, up), path, false);
}

} // namespace krs

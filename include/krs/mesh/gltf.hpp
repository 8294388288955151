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
// scene (krs/mesh/instances.hpp) is written with EXT_mesh_gpu_instancing (see
// gltf_instances_model).
//
// Saves check the mesh (krs/mesh/write.hpp's checks) and the path, then write a temporary file and
// rename it (krs/io/write_then_rename.hpp): a failed save is a save_error and leaves no file.

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
inline int add_gltf_mesh(tinygltf::Model& model, const triangle_mesh& m, const std::string& name)
{
    if (model.buffers.empty()) model.buffers.emplace_back();
    const auto positions = little_endian_bytes(m.positions.data(), m.positions.size());
    const int position = add_accessor(model, add_buffer_view(model, positions.data(), positions.size(), TINYGLTF_TARGET_ARRAY_BUFFER),
                                      TINYGLTF_COMPONENT_TYPE_FLOAT, TINYGLTF_TYPE_VEC3, m.positions.size());
    vec3f lo = m.positions[0], hi = m.positions[0];
    for (const vec3f& p : m.positions) lo = min(lo, p), hi = max(hi, p);
    model.accessors[std::size_t(position)].minValues = {lo.x, lo.y, lo.z};
    model.accessors[std::size_t(position)].maxValues = {hi.x, hi.y, hi.z};

    tinygltf::Primitive primitive;
    primitive.mode = TINYGLTF_MODE_TRIANGLES;
    primitive.attributes["POSITION"] = position;
    if (!m.normals.empty()) {
        const auto normals = little_endian_bytes(m.normals.data(), m.normals.size());
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

inline tinygltf::Model empty_gltf_model()
{
    tinygltf::Model model;
    model.asset.version = "2.0";
    model.asset.generator = "krs (krs/mesh/gltf.hpp)";
    model.buffers.emplace_back();
    model.scenes.emplace_back();
    model.defaultScene = 0;
    return model;
}

} // namespace detail

// The mesh as a tinygltf model (for users who add to it before writing it themselves).
inline tinygltf::Model gltf_model(const triangle_mesh& m)
{
    detail::require_mesh("gltf_model", m);
    tinygltf::Model model = detail::empty_gltf_model();
    tinygltf::Node node;
    node.mesh = detail::add_gltf_mesh(model, m, "krs_mesh");
    model.nodes.push_back(node);
    model.scenes[0].nodes = {0};
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

// An instanced scene (krs/mesh/instances.hpp) as a tinygltf model: per part, its mesh and (when
// some instance is a reflection) its mirrored mesh, each with one node whose
// EXT_mesh_gpu_instancing attributes TRANSLATION (float VEC3) and ROTATION (float VEC4, unit
// quaternion x y z w) place every instance. The extension is listed in extensionsUsed only: a
// viewer without it draws each node once, at its first instance's place (the node's own
// transform is the identity, which is the first instance of every part). Parts whose mesh has no
// triangle (a kernel smaller than a cell) are left out.
inline tinygltf::Model gltf_instances_model(const instanced_scene& scene)
{
    tinygltf::Model model = detail::empty_gltf_model();
    model.extensionsUsed.push_back("EXT_mesh_gpu_instancing");
    const auto add = [&](const triangle_mesh& m, const std::vector<rigid_motion>& instances, const std::string& name) {
        if (m.triangles.empty() || instances.empty()) return;
        detail::require_mesh("gltf_instances_model", m);
        std::vector<float> t, r;
        for (const rigid_motion& i : instances) {
            t.insert(t.end(), {float(i.translation.x), float(i.translation.y), float(i.translation.z)});
            const auto q = rotation_quaternion(i.rotation);
            r.insert(r.end(), {float(q[0]), float(q[1]), float(q[2]), float(q[3])});
        }
        tinygltf::Node node;
        node.name = name;
        node.mesh = detail::add_gltf_mesh(model, m, name);
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
        model.nodes.push_back(node);
        model.scenes[0].nodes.push_back(int(model.nodes.size() - 1));
    };
    for (const instanced_part& p : scene.parts) {
        add(p.mesh, p.direct, p.name);
        add(p.mirrored, p.reflected, p.name + " (mirrored)");
    }
    if (model.nodes.empty())
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
inline void save_glb(const triangle_mesh& m, const std::filesystem::path& path)
{
    detail::require_output_path("save_glb", path);
    detail::require_mesh("save_glb", m);
    detail::save_gltf_model("save_glb", gltf_model(m), path, true);
}

// An instanced scene as glTF with EXT_mesh_gpu_instancing: binary (.glb) or text (.gltf).
inline void save_gltf_instances(const instanced_scene& scene, const std::filesystem::path& path, bool binary)
{
    detail::require_output_path("save_gltf_instances", path);
    detail::save_gltf_model("save_gltf_instances", gltf_instances_model(scene), path, binary);
}

// The mesh as a text glTF (.gltf) with its buffer embedded as a data URI.
inline void save_gltf(const triangle_mesh& m, const std::filesystem::path& path)
{
    detail::require_output_path("save_gltf", path);
    detail::require_mesh("save_gltf", m);
    detail::save_gltf_model("save_gltf", gltf_model(m), path, false);
}

} // namespace krs

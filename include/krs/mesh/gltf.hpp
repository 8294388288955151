#pragma once
// Meshes as glTF 2.0: binary .glb (one file: JSON chunk and binary chunk) and text .gltf (the
// buffer embedded as a base64 data URI), through tinygltf (Debian's libtinygltf-dev). This header
// and the CMake target krs::mesh_gltf, provided only where tinygltf is found, are the only parts
// of krs that need it: krs::krs stays dependency-free (tests/test_dependency_free.cpp).
//
// The model: one buffer holding positions (float VEC3, with the min and max glTF requires for
// POSITION), normals (float VEC3) and indices (uint32 SCALAR), each in its own buffer view; one
// mesh with one triangle primitive (counter-clockwise front faces, as glTF's default); one node;
// one scene. No material: viewers draw glTF's default (white, metallic 1, rough 1).
//
// Saves check the mesh (krs/mesh/write.hpp's checks) and the path, then write a temporary file and
// rename it (krs/io/write_then_rename.hpp): a failed save is a save_error and leaves no file.

#include "krs/io/write_then_rename.hpp"
#include "krs/mesh/mesh.hpp"
#include "krs/mesh/write.hpp" // detail::require_mesh

#include <tiny_gltf.h>

#include <bit>
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

// The mesh as a tinygltf model (for users who add to it before writing it themselves).
inline tinygltf::Model gltf_model(const triangle_mesh& m)
{
    detail::require_mesh("gltf_model", m);
    tinygltf::Model model;
    model.asset.version = "2.0";
    model.asset.generator = "krs (krs/mesh/gltf.hpp)";
    model.buffers.emplace_back();

    const auto positions = detail::little_endian_bytes(m.positions.data(), m.positions.size());
    const int position = detail::add_accessor(model, detail::add_buffer_view(model, positions.data(), positions.size(), TINYGLTF_TARGET_ARRAY_BUFFER),
                                              TINYGLTF_COMPONENT_TYPE_FLOAT, TINYGLTF_TYPE_VEC3, m.positions.size());
    vec3f lo = m.positions[0], hi = m.positions[0];
    for (const vec3f& p : m.positions) lo = min(lo, p), hi = max(hi, p);
    model.accessors[position].minValues = {lo.x, lo.y, lo.z};
    model.accessors[position].maxValues = {hi.x, hi.y, hi.z};

    tinygltf::Primitive primitive;
    primitive.mode = TINYGLTF_MODE_TRIANGLES;
    primitive.attributes["POSITION"] = position;
    if (!m.normals.empty()) {
        const auto normals = detail::little_endian_bytes(m.normals.data(), m.normals.size());
        primitive.attributes["NORMAL"] = detail::add_accessor(
            model, detail::add_buffer_view(model, normals.data(), normals.size(), TINYGLTF_TARGET_ARRAY_BUFFER),
            TINYGLTF_COMPONENT_TYPE_FLOAT, TINYGLTF_TYPE_VEC3, m.normals.size());
    }
    const auto indices = detail::little_endian_bytes(m.triangles.data(), m.triangles.size());
    primitive.indices = detail::add_accessor(
        model, detail::add_buffer_view(model, indices.data(), indices.size(), TINYGLTF_TARGET_ELEMENT_ARRAY_BUFFER),
        TINYGLTF_COMPONENT_TYPE_UNSIGNED_INT, TINYGLTF_TYPE_SCALAR, 3 * m.triangles.size());

    tinygltf::Mesh mesh;
    mesh.name = "krs_mesh";
    mesh.primitives.push_back(primitive);
    model.meshes.push_back(mesh);
    tinygltf::Node node;
    node.mesh = 0;
    model.nodes.push_back(node);
    tinygltf::Scene scene;
    scene.nodes = {0};
    model.scenes.push_back(scene);
    model.defaultScene = 0;
    return model;
}

namespace detail {

inline void save_gltf_model(std::string_view caller, const tinygltf::Model& model, const std::filesystem::path& path, bool binary)
{
    write_then_rename(caller, path, [&](const std::filesystem::path& partial) {
        std::ofstream out(partial, std::ios::binary | std::ios::trunc);
        if (!out) throw std::runtime_error("cannot open it for writing");
        tinygltf::TinyGLTF writer;
        if (!writer.WriteGltfSceneToStream(&model, out, /*prettyPrint=*/!binary, /*writeBinary=*/binary))
            throw std::runtime_error("tinygltf could not write the model");
        out.close();
        if (!out) throw std::runtime_error("writing failed");
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

// The mesh as a text glTF (.gltf) with its buffer embedded as a data URI.
inline void save_gltf(const triangle_mesh& m, const std::filesystem::path& path)
{
    detail::require_output_path("save_gltf", path);
    detail::require_mesh("save_gltf", m);
    detail::save_gltf_model("save_gltf", gltf_model(m), path, false);
}

} // namespace krs

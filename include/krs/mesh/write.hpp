#pragma once
// Meshes as files every mesh tool reads: PLY (binary, little-endian) and Wavefront OBJ (text).
// Both hold positions, unit normals and triangles (counter-clockwise seen from outside, as the
// formats and glTF expect). glTF/GLB is in krs/mesh/gltf.hpp, which needs tinygltf.
//
// Every save checks the mesh first (indices within the vertices, finite positions, one normal per
// vertex or none) and refuses an empty path or a directory (invalid_parameter), then writes a
// temporary file beside the path and renames it over the path once complete
// (krs/io/write_then_rename.hpp): a failed save is a save_error naming the path and leaves no
// file behind.
//
// PLY's numbers are written byte by byte in little-endian order, never as a struct's memory, so a
// file is the same on every machine:
//     vertex: x y z nx ny nz s t red green blue
//             float32 each but the colour, uint8 each, sRGB-encoded (round(255 srgb_encode(c)));
//             nx ny nz, s t and the colour are left out for a mesh without normals, uvs or colours
//     face:   uint8 3, then three uint32 vertex indices
// OBJ's numbers are printed with 9 significant digits, which round-trip a float exactly: uvs as
// "vt u v", colours as the common extension "v x y z r g b" (read by assimp, MeshLab, Blender).
//
// Colours. The mesh's are linear RGB (krs/mesh/mesh.hpp); PLY's bytes and OBJ's "r g b" are
// written sRGB-encoded (krs/core/srgb.hpp), because their readers take them as display values:
// Blender decodes both from sRGB to its linear colours, MeshLab shows them as they are. (glTF's
// COLOR_0 is linear by its specification: krs/mesh/gltf.hpp writes the floats unchanged.) assimp
// passes every format's numbers through as they are, so its users decode PLY's and OBJ's.
//
// Up axis. The mesh is y-up (krs's scenes); `up` turns positions and normals into the file's
// frame (krs/io/up_axis.hpp). Blender's PLY importer takes the file as z-up (write up_axis::z for
// it); its OBJ importer converts a y-up OBJ by default, as OBJ's convention is y-up.

#include "krs/core/srgb.hpp"
#include "krs/core/validate.hpp"
#include "krs/io/up_axis.hpp"
#include "krs/io/write_then_rename.hpp"
#include "krs/mesh/mesh.hpp"

#include <bit>
#include <cmath>
#include <cstdint>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <string>
#include <string_view>
#include <vector>

namespace krs {

namespace detail {

inline void require_mesh(std::string_view caller, const triangle_mesh& m)
{
    const std::string name = std::string(caller) + " mesh";
    if (m.triangles.empty()) throw invalid_parameter(name, "must hold at least one triangle", "0 triangles");
    if (m.positions.size() > 0xffffffffu)
        throw invalid_parameter(name, "must have fewer than 2^32 vertices", std::to_string(m.positions.size()));
    if (!m.normals.empty() && m.normals.size() != m.positions.size())
        throw invalid_parameter(name, "must have one normal per vertex or none",
                                std::to_string(m.normals.size()) + " normals for " + std::to_string(m.positions.size()) + " vertices");
    for (const vec3f& p : m.positions)
        if (!std::isfinite(p.x) || !std::isfinite(p.y) || !std::isfinite(p.z))
            throw invalid_parameter(name, "must have finite vertex positions", detail::to_text(p));
    for (const vec3f& n : m.normals)
        if (!std::isfinite(n.x) || !std::isfinite(n.y) || !std::isfinite(n.z))
            throw invalid_parameter(name, "must have finite normals", detail::to_text(n));
    if (!m.uvs.empty() && m.uvs.size() != m.positions.size())
        throw invalid_parameter(name, "must have one uv per vertex or none",
                                std::to_string(m.uvs.size()) + " uvs for " + std::to_string(m.positions.size()) + " vertices");
    if (!m.colors.empty() && m.colors.size() != m.positions.size())
        throw invalid_parameter(name, "must have one colour per vertex or none",
                                std::to_string(m.colors.size()) + " colours for " + std::to_string(m.positions.size()) + " vertices");
    for (const auto& t : m.uvs)
        if (!std::isfinite(t[0]) || !std::isfinite(t[1]))
            throw invalid_parameter(name, "must have finite uvs", detail::to_text(t[0]) + ", " + detail::to_text(t[1]));
    for (const vec3f& c : m.colors)
        if (!(c.x >= 0 && c.x <= 1 && c.y >= 0 && c.y <= 1 && c.z >= 0 && c.z <= 1))
            throw invalid_parameter(name, "must have colours in [0, 1]", detail::to_text(c));
    for (const auto& t : m.triangles)
        for (std::uint32_t v : t)
            if (v >= m.positions.size())
                throw invalid_parameter(name, "must index only its own vertices (< " + std::to_string(m.positions.size()) + ")",
                                        std::to_string(v));
}

inline void put_u32(std::string& out, std::uint32_t v)
{
    for (int b = 0; b < 4; ++b) out.push_back(char(v >> (8 * b) & 0xff));
}
inline void put_f32(std::string& out, float v) { put_u32(out, std::bit_cast<std::uint32_t>(v)); }
// A linear colour channel in [0, 1] as PLY's sRGB-encoded uint8.
inline char color_byte(float c) { return char(std::uint8_t(std::lround(srgb_encode(double(c)) * 255.0))); }

} // namespace detail

// The mesh as binary little-endian PLY, in the frame of `up`.
inline std::string ply_bytes(const triangle_mesh& m, up_axis up = up_axis::y)
{
    detail::require_mesh("ply_bytes", m);
    const bool normals = !m.normals.empty();
    std::string out = "ply\nformat binary_little_endian 1.0\ncomment written by krs (krs/mesh/write.hpp)\n";
    out += "element vertex " + std::to_string(m.positions.size()) + "\n";
    out += "property float x\nproperty float y\nproperty float z\n";
    if (normals) out += "property float nx\nproperty float ny\nproperty float nz\n";
    const bool uvs = !m.uvs.empty(), colors = !m.colors.empty();
    if (uvs) out += "property float s\nproperty float t\n";
    if (colors) out += "property uchar red\nproperty uchar green\nproperty uchar blue\n";
    out += "element face " + std::to_string(m.triangles.size()) + "\n";
    out += "property list uchar uint vertex_indices\nend_header\n";
    out.reserve(out.size() + m.positions.size() * ((normals ? 24 : 12) + (uvs ? 8 : 0) + (colors ? 3 : 0)) + m.triangles.size() * 13);
    for (std::size_t v = 0; v < m.positions.size(); ++v) {
        const vec3f p = to_file(up, m.positions[v]);
        detail::put_f32(out, p.x), detail::put_f32(out, p.y), detail::put_f32(out, p.z);
        if (normals) {
            const vec3f n = to_file(up, m.normals[v]);
            detail::put_f32(out, n.x), detail::put_f32(out, n.y), detail::put_f32(out, n.z);
        }
        if (uvs) detail::put_f32(out, m.uvs[v][0]), detail::put_f32(out, m.uvs[v][1]);
        if (colors) {
            const vec3f& c = m.colors[v];
            out.push_back(detail::color_byte(c.x)), out.push_back(detail::color_byte(c.y)), out.push_back(detail::color_byte(c.z));
        }
    }
    for (const auto& t : m.triangles) {
        out.push_back(char(3));
        for (std::uint32_t v : t) detail::put_u32(out, v);
    }
    return out;
}

// The mesh as Wavefront OBJ: "v" (with "r g b" when it has colours), "vt" (uvs), "vn" (normals)
// and faces "f a/a/a ..." (1-based; the uv or normal index left out when there is none), in the
// frame of `up`.
inline std::string obj_text(const triangle_mesh& m, up_axis up = up_axis::y)
{
    detail::require_mesh("obj_text", m);
    const bool normals = !m.normals.empty(), uvs = !m.uvs.empty(), colors = !m.colors.empty();
    std::string out = "# written by krs (krs/mesh/write.hpp)\n";
    char line[256];
    for (std::size_t v = 0; v < m.positions.size(); ++v) {
        const vec3f p = to_file(up, m.positions[v]);
        if (colors)
            std::snprintf(line, sizeof line, "v %.9g %.9g %.9g %.9g %.9g %.9g\n", double(p.x), double(p.y), double(p.z),
                          srgb_encode(double(m.colors[v].x)), srgb_encode(double(m.colors[v].y)), srgb_encode(double(m.colors[v].z)));
        else
            std::snprintf(line, sizeof line, "v %.9g %.9g %.9g\n", double(p.x), double(p.y), double(p.z));
        out += line;
    }
    for (const auto& t : m.uvs) {
        std::snprintf(line, sizeof line, "vt %.9g %.9g\n", double(t[0]), double(t[1]));
        out += line;
    }
    for (const vec3f& normal : m.normals) {
        const vec3f n = to_file(up, normal);
        std::snprintf(line, sizeof line, "vn %.9g %.9g %.9g\n", double(n.x), double(n.y), double(n.z));
        out += line;
    }
    for (const auto& t : m.triangles) {
        out += "f";
        for (std::uint32_t i : t) {
            const unsigned long a = i + 1ul;
            if (uvs && normals) std::snprintf(line, sizeof line, " %lu/%lu/%lu", a, a, a);
            else if (uvs) std::snprintf(line, sizeof line, " %lu/%lu", a, a);
            else if (normals) std::snprintf(line, sizeof line, " %lu//%lu", a, a);
            else std::snprintf(line, sizeof line, " %lu", a);
            out += line;
        }
        out += "\n";
    }
    return out;
}

inline void save_ply(const triangle_mesh& m, const std::filesystem::path& path, up_axis up = up_axis::y)
{
    detail::require_output_path("save_ply", path);
    const std::string bytes = ply_bytes(m, up); // checks the mesh before any file exists
    write_file("save_ply", path, bytes);
}

inline void save_obj(const triangle_mesh& m, const std::filesystem::path& path, up_axis up = up_axis::y)
{
    detail::require_output_path("save_obj", path);
    const std::string text = obj_text(m, up);
    write_file("save_obj", path, text);
}

} // namespace krs

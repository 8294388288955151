#pragma once
// Triangle meshes: what mesh extraction (krs/mesh/extract.hpp) returns and the writers
// (krs/mesh/write.hpp, krs/mesh/gltf.hpp) take. Indexed triangles over shared vertices, so that
// a closed surface is visibly closed: every edge is shared by exactly two triangles, once in each
// direction (the triangles are counter-clockwise seen from outside, the side where the field is
// positive), which `edge_use` counts for tests and users alike.
//
// Optional per-vertex attributes (mesh_options::attributes, krs/mesh/extract.hpp), each empty or
// one per position: `uvs`, the (u, v) of the vertex's kernel at its kernel-space point (a
// sequence's `locate`; (0, 0) for a kernel kind without a uv), and `colors`, linear RGB in [0, 1]
// from the kernel's index (kernel_color), so that a viewer tells the kernels apart.

#include "krs/core/vec3.hpp"

#include <algorithm>
#include <array>
#include <cmath>
#include <cstddef>
#include <cstdint>
#include <map>
#include <utility>
#include <vector>

namespace krs {

struct triangle_mesh {
    std::vector<vec3f> positions;
    std::vector<vec3f> normals; // unit, outward (the field's gradient), one per position
    std::vector<std::array<std::uint32_t, 3>> triangles; // counter-clockwise seen from outside
    std::vector<std::array<float, 2>> uvs; // per vertex (u, v), or empty
    std::vector<vec3f> colors;              // per vertex linear RGB in [0, 1], or empty

    std::size_t vertex_count() const { return positions.size(); }
    std::size_t triangle_count() const { return triangles.size(); }
    // What the mesh occupies (its arrays' contents; not the allocator's slack).
    std::size_t bytes() const
    {
        return positions.size() * sizeof(vec3f) + normals.size() * sizeof(vec3f) + triangles.size() * sizeof(triangles[0]) +
               uvs.size() * sizeof(uvs[0]) + colors.size() * sizeof(vec3f);
    }
};

// A colour per kernel index: hues a golden-ratio turn apart (index * 0.618... mod 1), so that
// neighbouring indices, often neighbouring kernels, differ most; saturation 0.6, value 0.9 (HSV).
inline vec3f kernel_color(std::uint32_t kernel)
{
    const double hue = 6.0 * (double(kernel) * 0.6180339887498949 - std::floor(double(kernel) * 0.6180339887498949));
    const int sector = std::min(int(hue), 5);
    const double f = hue - sector, v = 0.9, p = v * (1 - 0.6), q = v * (1 - 0.6 * f), t = v * (1 - 0.6 * (1 - f));
    const double rgb[6][3] = {{v, t, p}, {q, v, p}, {p, v, t}, {p, q, v}, {t, p, v}, {v, p, q}};
    return {float(rgb[sector][0]), float(rgb[sector][1]), float(rgb[sector][2])};
}

// How the edges of a mesh are shared: a closed manifold surface with consistent orientation has
// every undirected edge used by exactly two triangles, in opposite directions.
struct edge_use {
    std::size_t edges = 0;          // distinct undirected edges
    std::size_t not_two = 0;        // edges used by fewer or more than two triangles
    std::size_t same_direction = 0; // edges used twice in one direction (orientation flips)
    bool closed_manifold() const { return edges > 0 && not_two == 0 && same_direction == 0; }
};

inline edge_use count_edge_use(const triangle_mesh& m)
{
    // (low, high) -> uses from low to high, uses from high to low
    std::map<std::pair<std::uint32_t, std::uint32_t>, std::pair<int, int>> uses;
    for (const auto& t : m.triangles)
        for (int e = 0; e < 3; ++e) {
            const std::uint32_t a = t[e], b = t[(e + 1) % 3];
            auto& u = uses[{std::min(a, b), std::max(a, b)}];
            (a < b ? u.first : u.second) += 1;
        }
    edge_use out;
    out.edges = uses.size();
    for (const auto& [edge, u] : uses) {
        if (u.first + u.second != 2) ++out.not_two;
        else if (u.first != 1) ++out.same_direction;
    }
    return out;
}

} // namespace krs

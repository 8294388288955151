#pragma once
// Triangle meshes: what mesh extraction (krs/mesh/extract.hpp) returns and the writers
// (krs/mesh/write.hpp, krs/mesh/gltf.hpp) take. Indexed triangles over shared vertices, so that
// a closed surface is visibly closed: every edge is shared by exactly two triangles, once in each
// direction (the triangles are counter-clockwise seen from outside, the side where the field is
// positive), which `edge_use` counts for tests and users alike.

#include "krs/core/vec3.hpp"

#include <algorithm>
#include <array>
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

    std::size_t vertex_count() const { return positions.size(); }
    std::size_t triangle_count() const { return triangles.size(); }
    // What the mesh occupies (its arrays' contents; not the allocator's slack).
    std::size_t bytes() const
    {
        return positions.size() * sizeof(vec3f) + normals.size() * sizeof(vec3f) + triangles.size() * sizeof(triangles[0]);
    }
};

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

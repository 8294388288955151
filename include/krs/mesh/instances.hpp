#pragma once
// A sequence as instanced meshes (the KRS paper's section 4, the other GPU route: kernel instance
// transforms computed, each kernel's geometry drawn with instancing). Its glTF form, one node per
// instance over shared meshes or EXT_mesh_gpu_instancing, is written by krs/mesh/gltf.hpp
// (save_gltf_instances).
//
// With n mirrors and `instance_levels` = k (0 <= k <= n), the top k mirrors are expanded into
// instance transforms and what lies below them is meshed whole:
//   - every kernel of level i >= n - k is meshed once, in its own space, and drawn through the
//     2^(n-i) isometries that place its instances (as krs::expand builds them, top-down);
//   - the kernels of the levels below n - k, with mirrors 0 ... n-k-1, form a sub-sequence whose
//     expansion is meshed whole (one mesh, its zero set extracted as for any field) and drawn
//     through the 2^k isometries of level n - k.
// k = n meshes each kernel alone (2^n instances of a level-0 kernel); k = 0 meshes the whole
// sequence as one mesh with one instance.
//
// Reflections. An instance's isometry x -> A x + t has det A = +1 or -1 (a product of
// reflections). glTF's instancing stores a translation, a rotation and a scale, and a negative
// scale would leave the triangles' winding to each renderer; so every part is stored twice when
// needed: as meshed, and mirrored through the plane x = 0 (x negated, triangles reversed: still
// outward and counter-clockwise). An instance with det A = -1 uses the mirrored mesh with the
// rotation A diag(-1, 1, 1), which is proper. Every instance is then a rotation and a translation.
//
// All parts are meshed with one cell size: the whole sequence's box's longest side divided by
// `mesh.resolution`, so a kernel is as fine as it would be in a mesh of the whole. The number of
// instances is checked against `max_instances` before anything is meshed.
//
// Unbounded parts. A part whose box is infinite (a plane kernel: a tree's ground, the facets of a
// rock or a terrain, or the levels below that hold one) is meshed within the scene's box B:
// `mesh.box` when given, else the sequence's own box (a bounded<> wrapper's: the box of its
// sphere). Its instances differ in where they carry the part, so the part is meshed over the box
// of B taken back through every one of its instance isometries (the box of the 8 corners of B
// under each inverse): every instance then covers all of B, and beyond it only surface that the
// same instance also has (the mesh is of the part's own zero set; outside B it is clipped at the
// grid's edge, at most two cells past that box, and is left open there). A part at the top level
// has the one identity instance and is meshed over B itself.

#include "krs/compose/zones.hpp" // bounded
#include "krs/expansion.hpp"
#include "krs/mesh/extract.hpp"
#include "krs/mesh/mesh.hpp"

#include <array>
#include <algorithm>
#include <cmath>
#include <limits>
#include <string>
#include <vector>

namespace krs {

struct instance_options {
    std::size_t instance_levels = 4;       // k: top mirrors expanded into instances, <= the mirror count
    std::size_t max_instances = 1u << 20;  // the most instances in all: > 0
    mesh_options mesh;                     // resolution over the whole sequence's box, budget per part
};

// A proper rigid motion: x -> rotation x + translation (rotation orthogonal, det +1).
struct rigid_motion {
    std::array<double, 9> rotation{1, 0, 0, 0, 1, 0, 0, 0, 1}; // row-major
    vec3d translation{};
};

struct instanced_part {
    std::string name;        // "kernel <index>" or "levels below <n - k>"
    triangle_mesh mesh;      // in the part's own space
    triangle_mesh mirrored;  // the mesh mirrored through x = 0 (empty when no instance needs it)
    std::vector<rigid_motion> direct, reflected; // instances of mesh and of mirrored
};

struct instanced_scene {
    std::vector<instanced_part> parts;
    // Every instance of every part, also of parts whose mesh has no triangle (a kernel smaller
    // than a cell at this resolution): what the expansion places.
    std::size_t instance_count() const
    {
        std::size_t n = 0;
        for (const auto& p : parts) n += p.direct.size() + p.reflected.size();
        return n;
    }
    // The instances a file holds: those of the parts with a triangle (the writers leave the
    // others out, krs/mesh/gltf.hpp), and how many parts those are.
    std::size_t placed_instance_count() const
    {
        std::size_t n = 0;
        for (const auto& p : parts)
            if (!p.mesh.triangles.empty()) n += p.direct.size() + p.reflected.size();
        return n;
    }
    std::size_t placed_part_count() const
    {
        return std::size_t(std::count_if(parts.begin(), parts.end(), [](const instanced_part& p) { return !p.mesh.triangles.empty(); }));
    }
};

namespace detail {

inline triangle_mesh mirrored_through_x(const triangle_mesh& m)
{
    triangle_mesh r = m;
    for (auto& p : r.positions) p.x = -p.x;
    for (auto& n : r.normals) n.x = -n.x;
    for (auto& t : r.triangles) std::swap(t[1], t[2]);
    return r;
}

// Splits an isometry into (mirrored?, proper rigid motion) as described above.
inline void add_instance(instanced_part& part, const isometry& w)
{
    const auto& a = w.a;
    const double det = a[0] * (a[4] * a[8] - a[5] * a[7]) - a[1] * (a[3] * a[8] - a[5] * a[6]) + a[2] * (a[3] * a[7] - a[4] * a[6]);
    rigid_motion m;
    m.rotation = a;
    m.translation = w.t;
    if (det < 0) {
        for (int row = 0; row < 3; ++row) m.rotation[row * 3] = -m.rotation[row * 3]; // A diag(-1, 1, 1)
        part.reflected.push_back(m);
    } else {
        part.direct.push_back(m);
    }
}

// The box in a part's own space whose image under each of `transforms` holds `box`: the box of
// box's 8 corners taken back through every inverse (an isometry maps a box's hull to the hull of
// its image, so the preimage of the box lies in the hull of the preimages of its corners).
inline bounding_box preimage_box(const bounding_box& box, const std::vector<isometry>& transforms)
{
    constexpr double inf = std::numeric_limits<double>::infinity();
    vec3d lo{inf, inf, inf}, hi{-inf, -inf, -inf};
    const vec3d a(box.lo), b(box.hi);
    for (const isometry& w : transforms)
        for (int corner = 0; corner < 8; ++corner) {
            const vec3d p = w.apply_inverse(vec3d{corner & 1 ? b.x : a.x, corner & 2 ? b.y : a.y, corner & 4 ? b.z : a.z});
            lo = {std::min(lo.x, p.x), std::min(lo.y, p.y), std::min(lo.z, p.z)};
            hi = {std::max(hi.x, p.x), std::max(hi.y, p.y), std::max(hi.z, p.z)};
        }
    return box_around(lo, hi);
}

} // namespace detail

template <mirror_kind Mirror, kernel... Kinds>
instanced_scene instance_meshes(const basic_sequence<Mirror, Kinds...>& s, const instance_options& o = {})
{
    o.mesh.validate();
    const std::size_t n = s.mirror_count(), k = o.instance_levels;
    if (k > n)
        throw invalid_parameter("instance_options.instance_levels", "must be at most the sequence's mirror count (" + std::to_string(n) + ")",
                                std::to_string(k));
    if (o.max_instances == 0) throw invalid_parameter("instance_options.max_instances", "must be > 0", "0");
    const std::size_t split = n - k; // levels >= split: kernels instanced; below: meshed whole
    // Instances: 2^(n-i) per kernel of level i >= split, 2^k for the part below (if any kernel is there).
    double count = 0;
    bool below = false;
    for (std::uint32_t i = 0; i < s.kernels().size(); ++i) {
        if (s.kernel_level(i) >= split) count += std::ldexp(1.0, int(n - s.kernel_level(i)));
        else below = true;
    }
    if (below) count += std::ldexp(1.0, int(k));
    if (count > double(o.max_instances))
        throw invalid_parameter("instance_options.max_instances",
                                "exceeded: " + detail::to_text(count) + " instances at instance_levels " + std::to_string(k) +
                                    "; raise it or lower instance_options.instance_levels",
                                std::to_string(o.max_instances));

    // One cell size for every part.
    const bounding_box whole = o.mesh.box.is_bounded() ? o.mesh.box : s.bound_box();
    if (!whole.is_bounded())
        throw invalid_parameter("instance_options.mesh.box", "is needed for a sequence without a bounded box");
    const vec3d ext = vec3d(whole.hi) - vec3d(whole.lo);
    const double cell = std::max({ext.x, ext.y, ext.z}) / double(o.mesh.resolution);
    const auto resolution_for = [&](const bounding_box& b) {
        const vec3d e = vec3d(b.hi) - vec3d(b.lo);
        return int(std::clamp(std::ceil(std::max({e.x, e.y, e.z}) / cell), 1.0, double(max_mesh_resolution)));
    };

    instanced_scene out;
    // Transforms top-down, as krs::expand builds them: at each level below the top, every W and W o R_i.
    std::vector<isometry> transforms{isometry{}};
    for (std::size_t level = n + 1; level-- > split;) {
        if (level < n) {
            const isometry r = isometry::reflection(s.mirrors()[level]);
            const std::size_t half = transforms.size();
            for (std::size_t j = 0; j < half; ++j) transforms.push_back(transforms[j] * r);
        }
        for (std::uint32_t i = s.level_begin(level); i < s.level_begin(level + 1); ++i) {
            instanced_part part;
            part.name = "kernel " + std::to_string(i);
            std::visit(
                [&](const auto& kern) {
                    mesh_options mo = o.mesh;
                    mo.box = kern.bound_box();
                    if (!mo.box.is_bounded()) mo.box = detail::preimage_box(whole, transforms); // a plane: within B
                    mo.resolution = resolution_for(mo.box);
                    part.mesh = extract_mesh(kern, mo);
                },
                s.kernels()[i]);
            for (const isometry& w : transforms) detail::add_instance(part, w);
            out.parts.push_back(std::move(part));
        }
    }
    if (below) {
        typename basic_sequence<Mirror, Kinds...>::builder b;
        for (std::size_t level = 0; level < split; ++level) {
            for (std::uint32_t i = s.level_begin(level); i < s.level_begin(level + 1); ++i)
                std::visit([&](const auto& kern) { b.kernel(kern); }, s.kernels()[i]);
            b.mirror(s.mirrors()[level]);
        }
        const basic_sequence<Mirror, Kinds...> sub = b.build();
        instanced_part part;
        part.name = "levels below " + std::to_string(split);
        mesh_options mo = o.mesh;
        mo.box = sub.bound_box();
        if (!mo.box.is_bounded()) mo.box = detail::preimage_box(whole, transforms); // they hold a plane: within B
        mo.resolution = resolution_for(mo.box);
        part.mesh = extract_mesh(sub, mo);
        for (const isometry& w : transforms) detail::add_instance(part, w);
        out.parts.push_back(std::move(part));
    }
    for (auto& p : out.parts)
        if (!p.reflected.empty()) p.mirrored = detail::mirrored_through_x(p.mesh);
    return out;
}

// A bounded<> sequence (krs/compose/zones.hpp): its geometry is the sequence's within the wrapper's
// sphere, so without a mesh.box the box of that sphere is the scene's box B (see above).
template <mirror_kind Mirror, kernel... Kinds>
instanced_scene instance_meshes(const bounded<basic_sequence<Mirror, Kinds...>>& b, const instance_options& o = {})
{
    instance_options inner = o;
    if (!inner.mesh.box.is_bounded()) inner.mesh.box = intersect(box_around(b.bound()), b.base().bound_box());
    return instance_meshes(b.base(), inner);
}

} // namespace krs

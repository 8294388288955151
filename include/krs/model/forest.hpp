#pragma once
// Forest builder (paper section 7.2): one KRS tree, multiplied by more mirrors with empty kernel
// sets. The tree is krs::model::grow_tree's (same style parameters); `doublings` mirrors scatter it
// into 2^doublings trees (see scatter.hpp for how the mirrors are placed), and one ground plane
// is added at the very top (a single instance under the whole forest). The tree's footprint (the
// circle in the ground plane that the mirrors must keep trees out of each other's) is measured on
// its explicit expansion, which is tight; beyond 2^22 instances the sequence's looser bound is used.
//
// All trees share the tree's geometry (reflected), so a forest alone repeats one motif; a union
// of two or three forests with different seeds (krs::union_of) hides that (section 5.1).

#include "krs/expansion.hpp"
#include "krs/model/scatter.hpp"
#include "krs/model/tree.hpp"

#include <cstdint>
#include <optional>
#include <utility>
#include <vector>

namespace krs::model {

struct forest_parameters {
    tree_style tree{};                // the tree; its ground_height is ignored (see ground_height)
    int doublings = 6;                // trees = 2^doublings, in [0, 20]
    float spacing = 0.25f;            // gap between neighbouring crowns, in crown diameters, [0, 4]
    float angle_jitter_degrees = 20;  // random turn of each mirror off the alternating axes, [0, 90]
    std::optional<float> ground_height = 0.0f; // a ground plane y <= height under the forest
    std::uint32_t seed = 1;           // mirror placement (the tree has its own tree.seed)
};

struct forest {
    tree_sequence sequence;       // the whole forest (and ground)
    bounding_sphere crown{};      // bounding sphere of one tree (ground excluded)
    bounding_sphere bound{};      // bounding sphere of every tree (ground excluded)
    std::vector<bounding_sphere> trees; // each tree's bound (its copy of `crown`), e.g. for empty zones
    std::size_t tree_count = 1;
    double tree_instances = 0;    // kernel instances of one tree
};

inline forest build_forest(const forest_parameters& f)
{
    if (f.doublings < 0 || f.doublings > 20)
        throw invalid_parameter("forest.doublings", "must be in [0, 20]", std::to_string(f.doublings));
    detail::require_range("forest.spacing", f.spacing, 0.0, 4.0);
    detail::require_range("forest.angle_jitter_degrees", f.angle_jitter_degrees, 0.0, 90.0);
    if (f.ground_height) require_magnitude("forest.ground_height", *f.ground_height);
    // (levels - 1 would overflow for INT_MIN, found by fuzzing; grow_tree rejects such levels later.)
    const std::size_t tree_mirrors = f.tree.levels > 1 ? std::size_t(f.tree.levels) - 1 : 0;
    if (tree_mirrors + std::size_t(f.doublings) > tree_sequence::max_levels)
        throw invalid_parameter("forest.doublings", "tree.levels - 1 + doublings must be <= 64",
                                std::to_string(tree_mirrors + std::size_t(f.doublings)));

    tree_style style = f.tree;
    style.ground_height.reset();
    const tree_sequence tree = build_tree(grow_tree(style)); // validates the style
    forest out;
    out.crown = tree.bound();
    out.tree_instances = tree.instance_count();
    // Footprint: horizontal circle around the instances' bounding spheres.
    vec3d center(out.crown.center);
    double footprint = out.crown.radius;
    if (out.tree_instances <= double(std::size_t(1) << 22)) {
        vec3d lo{1e300, 1e300, 1e300}, hi{-1e300, -1e300, -1e300};
        std::vector<std::pair<vec3d, double>> spheres;
        for (const auto& instance : expand(tree).instances) {
            const bounding_sphere b = std::visit([](const auto& k) { return k.bound(); }, tree.kernels()[instance.kernel]);
            const vec3d c = instance.to_world.apply(vec3d(b.center));
            const vec3d r{b.radius, b.radius, b.radius};
            lo = min(lo, c - r), hi = max(hi, c + r);
            spheres.emplace_back(c, double(b.radius));
        }
        center = (lo + hi) * 0.5;
        footprint = 0;
        double reach = 0;
        for (const auto& [c, r] : spheres) {
            footprint = std::max(footprint, std::hypot(c.x - center.x, c.z - center.z) + r);
            reach = std::max(reach, length(c - center) + r);
        }
        out.crown = bound_around(center, reach);
    }

    detail::signed_unit_random random(f.seed);
    const scattering s = detail::scatter_by_mirrors(center, footprint, f.doublings, double(f.spacing) * 2.0 * footprint,
                                                    double(f.angle_jitter_degrees), random, "forest.doublings");
    auto b = detail::replay(tree);
    for (const mirror& m : s.mirrors) b.mirror(m); // empty kernel sets: pure multiplication
    if (f.ground_height) b.kernel(plane({0, 1, 0}, *f.ground_height));
    out.sequence = b.build();
    // Every tree's 3D bound: its copy of the crown sphere (copies are centered on `positions`).
    double spread = 0;
    const vec3d middle(s.bound.center);
    for (const vec3d& p : s.positions) spread = std::max(spread, length(p - middle));
    out.bound = bound_around(middle, spread + double(out.crown.radius));
    // s.positions are the copies of the footprint center, which is the crown's center.
    for (const vec3d& p : s.positions) out.trees.push_back(bound_around(p, double(out.crown.radius)));
    out.tree_count = s.positions.size();
    return out;
}

} // namespace krs::model

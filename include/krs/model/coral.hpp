#pragma once
// Coral and sponge builders (paper sections 7.1 and 6.5, figure 9).
//
// Coral: a branching KRS like a tree (section 7.2) but made of straight capsules with a sphere
// knot at every fork, the route wandering at random, and a blob at the tip. As in the tree, a
// mirror sits at each inner fork, through the fork point, holding the parent's axis, turned so the
// route's own child is on its negative side; the fork plane turns by a random angle each level
// (no two aligned), so the colony does not read as a symmetric pattern.
//
// Menger-like sponge: a KRS of one box kernel and mirrors only. At each of `levels` scales the
// point is folded, around the current cell's center c with cell size a, into the fundamental
// domain x >= y >= z >= 0 of the cube's 48 symmetries (three sign mirrors through c, then three
// compare-and-swap mirrors x = y, y = z, x = y). In that domain the solid sub-cells of a Menger
// cell are (1, 1, 0) and (1, 1, 1) (at least two middle-free indices; face centers and the body
// center are holes); a mirror at z = c.z + a / 2 folds the second onto the first, and the next
// scale works around c + (a, a, 0) with a / 3. The kernel is the solid cube at the last such cell.
// Reflections are isometries, so the distance is the KIFS fold distance without any scale factor:
// exact inside the fundamental domain, an underestimate elsewhere.

#include "krs/kernels/box.hpp"
#include "krs/kernels/capsule.hpp"
#include "krs/kernels/sphere.hpp"
#include "krs/model/tree.hpp"
#include "krs/sequence.hpp"

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <numbers>
#include <vector>

namespace krs::model {

using coral_sequence = sequence<capsule, sphere>;

struct coral_parameters {
    int levels = 12;               // branches on the route, in [1, 40]: 2^(levels-1) tips
    float base_radius = 0.12f;     // radius of the first branch, > 0
    float segment_length = 0.6f;   // length of the first branch, > 0
    float taper = 0.88f;           // radius and length ratio per level, in [0.5, 1]
    float spread_degrees = 32.0f;  // angle between child and parent, in [5, 80]
    float knot = 1.35f;            // knot sphere radius / branch radius, in [1, 3]
    float tip_blob = 1.8f;         // tip sphere radius / tip branch radius, in [1, 4]
    std::uint32_t seed = 1;
};

inline coral_sequence build_coral(const coral_parameters& c)
{
    if (c.levels < 1 || c.levels > 40)
        throw invalid_parameter("coral.levels", "must be in [1, 40]", std::to_string(c.levels));
    require_positive_length("coral.base_radius", c.base_radius);
    require_positive_length("coral.segment_length", c.segment_length);
    detail::require_range("coral.taper", c.taper, 0.5, 1.0);
    detail::require_range("coral.spread_degrees", c.spread_degrees, 5.0, 80.0);
    detail::require_range("coral.knot", c.knot, 1.0, 3.0);
    detail::require_range("coral.tip_blob", c.tip_blob, 1.0, 4.0);
    // The magnitude policy (krs/core/validate.hpp) for what the parameters grow into: the route
    // (levels segments, none longer than the first) and the spheres (at most 4 base radii).
    if (!(double(c.levels) * double(c.segment_length) <= double(max_magnitude)))
        throw invalid_parameter("coral.segment_length", "times levels must be <= 1e9", krs::detail::to_text(c.segment_length));
    if (!(double(std::max(c.knot, c.tip_blob)) * double(c.base_radius) <= double(max_magnitude)))
        throw invalid_parameter("coral.base_radius", "times max(knot, tip_blob) must be <= 1e9",
                                krs::detail::to_text(c.base_radius));

    constexpr double degree = std::numbers::pi / 180.0;
    detail::signed_unit_random random(c.seed);
    std::vector<vec3d> points{{0, 0, 0}};
    std::vector<double> radii;
    std::vector<vec3d> fork_normals; // at points[1 .. levels-1]
    vec3d direction{0, 1, 0}, fork_axis{1, 0, 0};
    double segment = c.segment_length, radius = c.base_radius;
    for (int j = 0; j < c.levels; ++j) {
        if (j > 0) {
            fork_axis = detail::rotate(fork_axis, direction, (90.0 + 70.0 * random()) * degree);
            fork_axis = normalize(fork_axis - direction * dot(fork_axis, direction));
            const double spread = c.spread_degrees * (1.0 + 0.25 * random()) * degree;
            direction = normalize(direction * std::cos(spread) - fork_axis * std::sin(spread));
            fork_normals.push_back(fork_axis);
            segment *= c.taper;
            radius *= c.taper;
        }
        radii.push_back(radius);
        points.push_back(points.back() + direction * segment);
        // A capsule's ends, as stored in float, must coincide or lie min_length apart (capsule.hpp).
        const double stored = length(vec3d(detail::to_float(points.back())) - vec3d(detail::to_float(points[points.size() - 2])));
        if (stored > 0.0 && !(stored >= double(min_length)))
            throw invalid_parameter("coral.segment_length",
                                    "times taper^" + std::to_string(j) + " is below 1e-6 (min_length) (raise it or taper)",
                                    krs::detail::to_text(c.segment_length));
    }
    coral_sequence::builder b;
    const std::size_t last = std::size_t(c.levels) - 1;
    b.kernel(capsule(detail::to_float(points[last]), detail::to_float(points[last + 1]), float(radii[last])));
    b.kernel(sphere(detail::to_float(points[last + 1]), float(radii[last] * c.tip_blob)));
    for (std::size_t j = last; j-- > 0;) {
        // Mirror at fork j + 1 holding branch j's axis; the child (branch j + 1) on its negative side.
        vec3d n = fork_normals[j];
        if (dot(n, points[j + 2] - points[j + 1]) > 0) n = -n;
        b.mirror(mirror::through(detail::to_float(points[j + 1]), detail::to_float(n)));
        b.kernel(capsule(detail::to_float(points[j]), detail::to_float(points[j + 1]), float(radii[j])));
        b.kernel(sphere(detail::to_float(points[j + 1]), float(radii[j] * c.knot)));
    }
    return b.build();
}

using sponge_sequence = sequence<box>;

struct sponge_parameters {
    vec3f center{0, 0, 0};
    float size = 2.0f; // edge length of the whole sponge, > 0
    int levels = 3;    // Menger levels, in [1, 9] (7 mirrors per level, 64 at most)
};

struct sponge {
    sponge_sequence sequence;
    double cube_count = 0; // solid cells of the finest level: 20^levels
};

inline sponge build_sponge(const sponge_parameters& s)
{
    require_magnitude("sponge.center", s.center);
    require_positive_length("sponge.size", s.size);
    // Every mirror and the kernel lie within |center| + size of the origin (the magnitude policy of
    // krs/core/validate.hpp).
    if (!(length(vec3d(s.center)) + double(s.size) <= double(max_magnitude)))
        throw invalid_parameter("sponge.size", "|center| + size must be <= 1e9", krs::detail::to_text(s.size));
    if (s.levels < 1 || s.levels > 9)
        throw invalid_parameter("sponge.levels", "must be in [1, 9]", std::to_string(s.levels));

    // Top-down list of mirrors (the walk order of Algorithm 1), then the builder wants them
    // bottom-up.
    std::vector<mirror> walk;
    vec3d c(s.center);
    double a = s.size / 3.0;
    const double h = std::sqrt(0.5);
    for (int level = 0; level < s.levels; ++level) {
        const vec3f cf = detail::to_float(c);
        // Sign folds: reflect where a coordinate is below the center (normal -axis).
        walk.push_back(mirror::through(cf, {-1, 0, 0}));
        walk.push_back(mirror::through(cf, {0, -1, 0}));
        walk.push_back(mirror::through(cf, {0, 0, -1}));
        // Sorting folds: reflect where y > x, then z > y, then y > x again.
        walk.push_back(mirror::through(cf, {float(-h), float(h), 0}));
        walk.push_back(mirror::through(cf, {0, float(-h), float(h)}));
        walk.push_back(mirror::through(cf, {float(-h), float(h), 0}));
        // Fold sub-cell z index 1 onto index 0.
        walk.push_back(mirror::through(detail::to_float(c + vec3d{0, 0, 0.5 * a}), {0, 0, 1}));
        c = c + vec3d{a, a, 0};
        a /= 3.0;
    }
    // c is now the center of the finest solid cell, of size 3a.
    sponge_sequence::builder b;
    const float half = float(1.5 * a);
    b.kernel(box(detail::to_float(c), {half, half, half}));
    for (std::size_t i = walk.size(); i-- > 0;) b.mirror(walk[i]);
    sponge out;
    out.sequence = b.build();
    out.cube_count = std::pow(20.0, double(s.levels));
    return out;
}

} // namespace krs::model

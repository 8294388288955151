#pragma once
// Tree builder: a KRS tree from intuitive parameters (paper section 7.2).
//
// A tree is modeled along ONE route from the trunk base to a twig tip. The branches of that route
// are the kernels (torus capsules: a bent tube with round caps); a mirror sits at every inner fork,
// through the fork point, so that the two children of a fork start at the same point, one the
// mirror image of the other. The kernels of the deepest level are the twig and its leaves. With
// m branches on the route there are m - 1 mirrors, and the leaves appear 2^(m-1) times.
//
// Levels, bottom-up as in the paper: K_0 = {twig, leaves}, R_0 = mirror at the last fork,
// K_1 = {branch before the twig}, ..., K_{m-1} = {trunk}. A mirror's normal is turned so the
// route's own child lies on its negative side (Algorithm 1 keeps that side and folds the other
// onto it); where a subtree crosses its fork's mirror it is clipped there (section 3).
//
// `tree_parameters` is the direct description (forks, control points, widths, fork normals,
// leaves); `grow_tree` derives one from a handful of numbers (`tree_style`) and a seed.

#include "krs/kernels/plane.hpp"
#include "krs/kernels/sphere.hpp"
#include "krs/kernels/torus_capsule.hpp"
#include "krs/sequence.hpp"

#include <cmath>
#include <cstdint>
#include <numbers>
#include <optional>
#include <random>
#include <string>
#include <vector>

namespace krs::model {

using tree_sequence = sequence<torus_capsule, sphere, plane>;

struct tree_parameters {
    // The route: forks[0] is the trunk base, forks[j] the fork where branch j - 1 ends and branch j
    // starts, forks.back() the twig tip. At least 2 points (a trunk only).
    std::vector<vec3f> forks;
    // One per branch (forks.size() - 1): branch j bends through controls[j]; a point on the chord
    // makes it straight.
    std::vector<vec3f> controls;
    // One per branch: the tube radius of branch j (>= 0).
    std::vector<float> widths;
    // Mirror normal at each inner fork forks[1 .. size-2]; empty = each fork's default, the plane
    // that holds the parent branch's axis (a symmetric fork). Its sign does not matter.
    std::vector<vec3f> fork_normals;
    // Leaves: small kernels of the deepest level, next to the twig; each appears 2^(m-1) times.
    std::vector<sphere> leaves;
    // Optional ground: a horizontal half-space y <= ground_height at the top level (one instance).
    std::optional<float> ground_height;
};

namespace detail {
inline std::string indexed(const char* name, std::size_t i) { return std::string(name) + "[" + std::to_string(i) + "]"; }
} // namespace detail

// Builds the tree's KRS. Every parameter is validated before anything is built.
inline tree_sequence build_tree(const tree_parameters& t)
{
    const std::size_t points = t.forks.size();
    if (points < 2) throw invalid_parameter("tree.forks", "needs at least 2 points (trunk base and tip)", std::to_string(points));
    const std::size_t branches = points - 1;
    if (t.controls.size() != branches)
        throw invalid_parameter("tree.controls", "needs one control point per branch (" + std::to_string(branches) + ")",
                                std::to_string(t.controls.size()));
    if (t.widths.size() != branches)
        throw invalid_parameter("tree.widths", "needs one width per branch (" + std::to_string(branches) + ")",
                                std::to_string(t.widths.size()));
    if (!t.fork_normals.empty() && t.fork_normals.size() != branches - 1)
        throw invalid_parameter("tree.fork_normals", "must be empty or hold one normal per inner fork (" +
                                                        std::to_string(branches - 1) + ")",
                                std::to_string(t.fork_normals.size()));
    if (branches - 1 > tree_sequence::max_levels)
        throw invalid_parameter("tree.forks", "too many forks for one sequence", std::to_string(branches - 1));

    // Every point obeys the magnitude policy (krs/core/validate.hpp), checked here so the message
    // names the tree's parameter rather than the kernel's.
    for (std::size_t j = 0; j < points; ++j) require_magnitude(detail::indexed("tree.forks", j), t.forks[j]);
    for (std::size_t j = 0; j < branches; ++j) {
        require_magnitude(detail::indexed("tree.controls", j), t.controls[j]);
        require_length(detail::indexed("tree.widths", j), t.widths[j]);
        if (!(length(vec3d(t.forks[j + 1]) - vec3d(t.forks[j])) >= double(min_length)))
            throw invalid_parameter(detail::indexed("tree.forks", j + 1),
                                    "must lie at least 1e-6 (min_length) from the fork before it",
                                    krs::detail::to_text(t.forks[j + 1]));
    }
    if (t.ground_height) require_magnitude("tree.ground_height", *t.ground_height);

    // Kernels (the torus_capsule constructor checks the rest: a control point off its arc).
    std::vector<torus_capsule> kernels;
    for (std::size_t j = 0; j < branches; ++j) kernels.emplace_back(t.forks[j], t.forks[j + 1], t.controls[j], t.widths[j]);

    // Mirrors at inner forks 1 .. branches-1, with the route's child on the negative side.
    std::vector<mirror> fork_mirrors;
    for (std::size_t j = 1; j < branches; ++j) {
        const vec3d fork(t.forks[j]);
        const vec3d child = vec3d(t.forks[j + 1]) - fork;
        vec3d n;
        if (!t.fork_normals.empty()) {
            n = vec3d(require_direction(detail::indexed("tree.fork_normals", j - 1), t.fork_normals[j - 1]));
        } else {
            // The plane holding the parent axis: n is the child's component across that axis.
            const vec3d parent = normalize(fork - vec3d(t.forks[j - 1]));
            n = child - parent * dot(child, parent);
            if (!(length(n) > 1e-6 * length(child)))
                throw invalid_parameter(detail::indexed("tree.fork_normals", j - 1),
                                        "is needed: branch " + std::to_string(j) +
                                            " continues its parent straight, so no default fork plane exists");
            n = normalize(n);
        }
        const double side = dot(n, child);
        if (!(std::abs(side) > 1e-6 * length(child)))
            throw invalid_parameter(detail::indexed("tree.fork_normals", j - 1),
                                    "puts branch " + std::to_string(j) + " inside its own mirror plane");
        if (side > 0) n = -n;
        fork_mirrors.push_back(mirror::through(t.forks[j], vec3f{float(n.x), float(n.y), float(n.z)}));
    }

    // Bottom-up: twig and leaves, then alternately the mirror at a fork and the branch above it.
    tree_sequence::builder b;
    b.kernel(kernels[branches - 1]);
    for (std::size_t k = 0; k < t.leaves.size(); ++k) b.kernel(t.leaves[k]);
    for (std::size_t j = branches - 1; j-- > 0;) {
        b.mirror(fork_mirrors[j]);
        b.kernel(kernels[j]);
    }
    if (t.ground_height) b.kernel(plane({0, 1, 0}, *t.ground_height));
    return b.build();
}

// A few numbers that grow a tree_parameters route: each fork turns the fork plane by `twist`
// about the branch, the child leaves its parent's axis by `spread`, lengths and radii shrink by
// their ratios, branches bend upward by `bend`. `jitter` varies angles and lengths per level
// (all instances of a level share its kernel, so randomness is per level, drawn from `seed`).
struct tree_style {
    int levels = 15;                // branches on the route, trunk to twig (levels - 1 mirrors)
    float trunk_length = 2.0f;
    float trunk_radius = 0.12f;
    float length_ratio = 0.8f;      // child length / parent length, in (0, 1.5]
    float radius_ratio = 0.75f;     // child radius / parent radius, in (0, 1]
    float spread_degrees = 30.0f;   // angle between child and parent axis, in (0, 90)
    float twist_degrees = 137.5f;   // turn of the fork plane from one fork to the next
    float bend = 0.1f;              // control point lift, as a fraction of branch length, in [-0.5, 0.5]
    float upward = 0.25f;           // pull of each child toward +y, in [0, 1]
    int leaves_per_twig = 4;        // in [0, 64]
    float leaf_radius = 0.06f;      // >= 0
    float jitter = 0.15f;           // relative random variation, in [0, 0.5]
    std::uint32_t seed = 1;
    std::optional<float> ground_height = 0.0f;
};

namespace detail {
// Deterministic uniform numbers in [-1, 1] on every platform (std distributions are not).
struct signed_unit_random {
    std::mt19937 engine;
    explicit signed_unit_random(std::uint32_t seed) : engine(seed) {}
    double operator()() { return double(engine() >> 8) * (2.0 / 16777216.0) - 1.0; }
};
// Rodrigues' rotation of v about the unit axis k by angle a.
inline vec3d rotate(const vec3d& v, const vec3d& k, double a)
{
    return v * std::cos(a) + cross(k, v) * std::sin(a) + k * (dot(k, v) * (1.0 - std::cos(a)));
}
inline vec3f to_float(const vec3d& v) { return {float(v.x), float(v.y), float(v.z)}; }
// v in [lo, hi], with a float parameter compared against the bounds rounded to float: its
// documented bound written as a float (0.99f is 0.99000001) is inside, as the user expects.
template <class V>
inline void require_range(const char* name, V v, double lo, double hi)
{
    using C = std::conditional_t<std::is_same_v<V, float>, float, double>;
    if (!(C(v) >= C(lo) && C(v) <= C(hi)))
        throw invalid_parameter(name, "must be in [" + krs::detail::to_text(lo) + ", " + krs::detail::to_text(hi) + "]", krs::detail::to_text(v));
}
} // namespace detail

inline tree_parameters grow_tree(const tree_style& s)
{
    using detail::require_range;
    if (s.levels < 1 || s.levels > int(tree_sequence::max_levels) + 1)
        throw invalid_parameter("tree_style.levels", "must be in [1, 65]", std::to_string(s.levels));
    require_positive_length("tree_style.trunk_length", s.trunk_length);
    require_length("tree_style.trunk_radius", s.trunk_radius);
    require_range("tree_style.length_ratio", s.length_ratio, 1e-3, 1.5);
    require_range("tree_style.radius_ratio", s.radius_ratio, 1e-3, 1.0);
    require_range("tree_style.spread_degrees", s.spread_degrees, 1.0, 89.0);
    require_range("tree_style.twist_degrees", s.twist_degrees, -360.0, 360.0);
    require_range("tree_style.bend", s.bend, -0.5, 0.5);
    require_range("tree_style.upward", s.upward, 0.0, 1.0);
    require_range("tree_style.leaves_per_twig", s.leaves_per_twig, 0, 64);
    require_length("tree_style.leaf_radius", s.leaf_radius);
    if (s.ground_height) require_magnitude("tree_style.ground_height", *s.ground_height);
    require_range("tree_style.jitter", s.jitter, 0.0, 0.5);

    constexpr double degree = std::numbers::pi / 180.0;
    const vec3d up{0, 1, 0};
    detail::signed_unit_random random(s.seed);
    tree_parameters t;
    t.ground_height = s.ground_height;

    vec3d point{0, 0, 0}, direction = up, fork_axis{1, 0, 0};
    double branch_length = s.trunk_length, radius = s.trunk_radius;
    t.forks.push_back(detail::to_float(point));
    for (int j = 0; j < s.levels; ++j) {
        if (j > 0) {
            // Fork plane: holds the parent axis, turned by twist from the previous fork's plane.
            fork_axis = detail::rotate(fork_axis, direction, (s.twist_degrees + 20.0 * s.jitter * random()) * degree);
            fork_axis = normalize(fork_axis - direction * dot(fork_axis, direction));
            const double spread = s.spread_degrees * (1.0 + s.jitter * random()) * degree;
            vec3d child = direction * std::cos(spread) - fork_axis * std::sin(spread);
            const vec3d lifted = normalize(child + up * double(s.upward));
            // Tropism must not carry the child across its own fork plane.
            if (dot(lifted, fork_axis) < -0.05) child = lifted;
            direction = normalize(child);
            t.fork_normals.push_back(detail::to_float(fork_axis));
            branch_length *= s.length_ratio * (1.0 + s.jitter * random());
            radius *= s.radius_ratio;
        }
        const vec3d end = point + direction * branch_length;
        // Bend: lift the control point toward +y, across the branch.
        const vec3d across = up - direction * dot(up, direction);
        const double across_len = length(across);
        vec3d control = (point + end) * 0.5;
        if (across_len > 1e-3) control = control + across * (s.bend * branch_length / across_len);
        t.controls.push_back(detail::to_float(control));
        t.widths.push_back(float(radius));
        t.forks.push_back(detail::to_float(end));
        // The grown route must obey the magnitude policy, and each branch must stay a kernel
        // (as stored in float: a branch below float's spacing at its position vanishes).
        if (!(length(vec3d(t.forks.back())) <= double(max_magnitude)))
            throw invalid_parameter("tree_style.trunk_length",
                                    "grows the tree past 1e9 from the origin at level " + std::to_string(j) +
                                        " (lower trunk_length, length_ratio or levels)",
                                    krs::detail::to_text(s.trunk_length));
        if (!(length(vec3d(t.forks.back()) - vec3d(t.forks[t.forks.size() - 2])) >= double(min_length)))
            throw invalid_parameter("tree_style.length_ratio",
                                    "shrinks branch " + std::to_string(j) +
                                        " below 1e-6 (min_length) or below float's spacing at its position "
                                        "(raise length_ratio or trunk_length, or lower levels)",
                                    krs::detail::to_text(s.length_ratio));
        point = end;
    }
    // Leaves along the twig's second half, around it, kept on the negative side of the last fork's
    // mirror so that mirror does not clip them: the fan around the twig reaches across the fork
    // plane when leaves are large or many (radius 0.2: 2 of 4 crossed it by up to 0.057), so a
    // leaf that would is moved back along the plane's normal, as the float plane build_tree makes
    // (normal fork_axis through the twig's start; the twig lies on its negative side).
    const vec3d twig_start(t.forks[t.forks.size() - 2]);
    const vec3d side0 = s.levels > 1 ? -fork_axis : normalize(cross(direction, vec3d{0, 0, 1}));
    const vec3d side1 = cross(direction, side0);
    const vec3d plane_normal = normalize(vec3d(detail::to_float(fork_axis)));
    for (int k = 0; k < s.leaves_per_twig; ++k) {
        const double along = 0.5 + 0.5 * (k + 1.0) / s.leaves_per_twig;
        const double angle = (k - 0.5 * (s.leaves_per_twig - 1)) * (std::numbers::pi * 0.8 / std::max(1, s.leaves_per_twig));
        const vec3d out = side0 * std::cos(angle) + side1 * std::sin(angle);
        vec3d c = twig_start + direction * (along * branch_length) + out * (radius + s.leaf_radius);
        if (s.levels > 1) {
            // Clear by a relative 1e-5 of the leaf and 16 float ulps of the position (rounding of
            // the stored centre and of the plane's float offset).
            const double clearance = 1e-5 * double(s.leaf_radius) + 16 * 1.2e-7 * length(c);
            const double reach = dot(plane_normal, c - twig_start) + double(s.leaf_radius) + clearance;
            if (reach > 0) c = c - plane_normal * reach;
        }
        const vec3f leaf_center = detail::to_float(c);
        if (!(length(vec3d(leaf_center)) <= double(max_magnitude)))
            throw invalid_parameter("tree_style.leaf_radius", "puts a leaf past 1e9 from the origin",
                                    krs::detail::to_text(s.leaf_radius));
        t.leaves.emplace_back(leaf_center, s.leaf_radius);
    }
    return t;
}

} // namespace krs::model

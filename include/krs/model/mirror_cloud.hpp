#pragma once
// Clouds of spheres from one sphere and `doublings` mirrors: the KRS paper's section 5, figure 5.
//
// Each mirror doubles the spheres so far. Mirror k's normal starts along the axis x, y, z in turn
// (k mod 3), so the cloud grows as a compact cluster in all three directions, not as a chain; the
// mirror lies `gap / 2` beyond the surface of the copy furthest along its normal, so every copy so
// far is on its negative side (the kernels stay separated) and the new copies sit at least `gap`
// from the old ones across it.
//
//   - Aligned (`build_aligned_cloud`): the normals are the axes themselves (axis_mirror). The
//     copies form a product of three translation sets, a lattice whose repetition the eye sees at
//     once.
//   - Scattered (`build_scattered_cloud`): each normal is the axis times 1.3 plus a random vector of
//     [-1, 1]^3, normalized ("planes of reflection selected so that the eye can only be near to a
//     few of them"): the same number of spheres reads as a natural cluster. `seed` draws the
//     vectors (std::mt19937 and uniform_real_distribution<float>, three draws a mirror, x then y
//     then z), so a seed gives the same cloud on every run.
//
// Both are built in float, the positions of the copies tracked as the mirrors reflect them (2^k
// after mirror k), which is what bounds `doublings`.

#include "krs/kernels/sphere.hpp"
#include "krs/mirror.hpp"
#include "krs/sequence.hpp"

#include <algorithm>
#include <cstdint>
#include <random>
#include <string>
#include <vector>

namespace krs::model {

template <class Mirror>
using sphere_cloud = basic_sequence<Mirror, sphere>;

struct mirror_cloud_parameters {
    vec3f center{0, 0.4f, 0}; // the seed sphere (figure 5's rests on y = 0)
    float radius = 0.4f;      // > 0
    int doublings = 9;        // mirrors, in [0, 20]: 2^doublings spheres (512 in figure 5)
    float gap = 0.3f;         // space between a copy and its mirror image across a mirror, > 0
    std::uint32_t seed = 1;   // the scattered cloud's random normals (the aligned cloud has none)
};

namespace detail {

inline void validate(const mirror_cloud_parameters& c)
{
    if (c.doublings < 0 || c.doublings > 20)
        throw invalid_parameter("mirror_cloud.doublings", "must be in [0, 20]", std::to_string(c.doublings));
    require_positive("mirror_cloud.gap", c.gap);
    require_magnitude("mirror_cloud.gap", c.gap);
}

// The cloud from the seed sphere and make(k, copies, margin), mirror k's plane placed `margin`
// beyond the copies' centers along its normal.
template <class Mirror, class MakeMirror>
sphere_cloud<Mirror> build_cloud(const mirror_cloud_parameters& c, MakeMirror make)
{
    validate(c);
    const sphere ball(c.center, c.radius); // validates center and radius
    typename sphere_cloud<Mirror>::builder b;
    b.kernel(ball);
    std::vector<vec3f> copies{ball.center};
    for (int k = 0; k < c.doublings; ++k) {
        const Mirror m = make(k, copies, ball.radius + 0.5f * c.gap);
        b.mirror(m);
        const std::size_t count = copies.size();
        for (std::size_t i = 0; i < count; ++i) copies.push_back(m.reflect(copies[i]));
    }
    return b.build();
}

// The largest n . p over the copies: the plane n . x = that + margin has them all below it.
inline float extent_along(const std::vector<vec3f>& copies, const vec3f& n)
{
    float e = -1e30f;
    for (const vec3f& p : copies) e = std::max(e, dot(n, p));
    return e;
}

} // namespace detail

inline sphere_cloud<axis_mirror> build_aligned_cloud(const mirror_cloud_parameters& c)
{
    return detail::build_cloud<axis_mirror>(c, [](int k, const std::vector<vec3f>& copies, float margin) {
        const int axis = k % 3;
        vec3f n{0, 0, 0};
        (axis == 0 ? n.x : axis == 1 ? n.y : n.z) = 1;
        return axis_mirror(axis, detail::extent_along(copies, n) + margin, true);
    });
}

inline sphere_cloud<mirror> build_scattered_cloud(const mirror_cloud_parameters& c)
{
    std::mt19937 random(c.seed);
    std::uniform_real_distribution<float> uniform(-1.0f, 1.0f);
    return detail::build_cloud<mirror>(c, [&](int k, const std::vector<vec3f>& copies, float margin) {
        vec3f n{uniform(random), uniform(random), uniform(random)}; // braces: drawn x, y, z in order
        (k % 3 == 0 ? n.x : k % 3 == 1 ? n.y : n.z) += 1.3f;
        n = normalize(n);
        return mirror(n, detail::extent_along(copies, n) + margin);
    });
}

} // namespace krs::model

#pragma once
// Shading in kernel space with light-direction interpolation (paper section 6.1, Algorithm 2).
//
// A KRS kernel instance is its kernel carried to world space by the reflections recorded on the
// way down (b_i). Rather than carrying the kernel's normal up, Algorithm 2 carries the world
// light (and view) direction *down*, into the kernel's space, and shades there:
//     n_world . l_world = n_kernel . (M_level^b ... M_{n-1}^b l_world),
// because reflections are orthogonal and involutions (each M is its own inverse transpose).
//
// Where kernels are not separated by a mirror (an infinite plane kernel, a rock or terrain whose
// kernels cross the mirrors), the recorded decision b_i flips across the plane and the shading
// jumps there. Algorithm 2 instead blends the unreflected and reflected light by the point's
// signed distance e to the plane:
//     w <- lerp(w, M_i w, clamp(e / e_threshold + 1/2, 0, 1)),
// so within e_threshold / 2 of a mirror the light turns continuously, and farther away it is
// exactly the light reflected by the recorded bit. For one mirror the dot product with the kernel
// normal is then lerp(n . l, (M n) . l, s): the interpolation of the two instances' cosines, which
// is what an interpolated vertex normal would give. The blended vector is deliberately NOT
// normalized (the paper's lerp): keeping it linear keeps n . w a convex combination of true
// cosines, and it can be zero (light exactly along the mirror normal, s = 1/2), where
// normalization would be undefined.
//
// e_threshold sets the width of the smoothed band. The paper makes it follow the pixel footprint
// (proportional to the depth of the hit): bands then stay a few pixels wide at every distance,
// which is what removes the aliasing of sub-pixel creases. `smoothing_threshold` below gives it.

#include "krs/core/validate.hpp"
#include "krs/sequence.hpp"
#include "krs/trace/sphere_trace.hpp"

#include <algorithm>
#include <cmath>
#include <limits>
#include <variant>

namespace krs {

// What Algorithm 2 returns: the nearest kernel (as Algorithm 1's locate() would), its kernel-space
// point and normal, and the light and view directions interpolated into that kernel's space.
template <std::floating_point S>
struct kernel_space_shading {
    location<S> where{};   // nearest kernel, its kernel-space point, level and reflection bits
    vec3<S> normal{};      // the kernel's own outward unit normal at where.kernel_point
    vec3<S> light{};       // world light direction carried into kernel space (interpolated)
    vec3<S> view{};        // world view direction (toward the eye) carried into kernel space
};

// The smoothing band width for a hit at ray depth t: `pixels` pixel footprints wide.
template <std::floating_point S>
S smoothing_threshold(S t, S pixel_footprint, S pixels = S(4), S floor = S(1e-6))
{
    require_non_negative("smoothing_threshold.t", t);
    require_non_negative("smoothing_threshold.pixel_footprint", pixel_footprint);
    require_non_negative("smoothing_threshold.pixels", pixels);
    require_positive("smoothing_threshold.floor", floor);
    return hit_threshold(pixels * pixel_footprint, t, floor);
}

// Algorithm 2 at world point x. `to_light` and `to_eye` are world directions (unit); threshold is
// e_threshold (> 0). A threshold of 0 is allowed and means "no interpolation": the light is then
// reflected exactly by the recorded bits (a step at every mirror).
// Works for every mirror kind (general planes and axis-aligned ones).
template <mirror_kind Mirror, kernel... Kinds, std::floating_point S>
kernel_space_shading<S> shade_in_kernel_space(const basic_sequence<Mirror, Kinds...>& s, const vec3<S>& x,
                                              const vec3<S>& to_light, const vec3<S>& to_eye, S threshold)
{
    require_non_negative("shade_in_kernel_space.threshold", threshold);
    require_finite("shade_in_kernel_space.x", x);
    require_finite("shade_in_kernel_space.to_light", to_light);
    require_finite("shade_in_kernel_space.to_eye", to_eye);
    const std::size_t n = s.mirror_count();
    kernel_space_shading<S> out;
    location<S>& where = out.where;
    vec3<S> p = x, light = to_light, view = to_eye;
    // A threshold below the smallest normal number keeps the step: its inverse would overflow to
    // infinity, and a point on a mirror (e = 0) would weigh 0 * inf = NaN.
    const bool ramp = threshold >= std::numeric_limits<S>::min();
    const S inverse = ramp ? S(1) / threshold : S(0);
    for (std::size_t i = n + 1; i-- > 0;) {
        if (i < n) {
            const Mirror& m = s.mirrors()[i];
            const S e = m.signed_distance(p);
            if (e > S(0)) {
                p = m.reflect(p);
                where.reflections |= std::uint64_t(1) << i;
            }
            // Weight of the reflected light: the step function b_i widened into a ramp of width
            // threshold centered on the plane (threshold 0 keeps the step).
            const S weight = ramp ? std::clamp(e * inverse + S(0.5), S(0), S(1)) : (e > S(0) ? S(1) : S(0));
            light = light + (m.reflect_direction(light) - light) * weight;
            view = view + (m.reflect_direction(view) - view) * weight;
        }
        for (std::uint32_t k = s.level_begin(i); k < s.level_begin(i + 1); ++k) {
            const S d = std::visit([&](const auto& kernel) { return kernel.distance(p); }, s.kernels()[k]);
            if (d < where.distance) {
                where.distance = d;
                where.kernel_point = p;
                where.kernel = k;
                where.level = std::uint32_t(i);
                out.light = light;
                out.view = view;
            }
        }
    }
    out.normal = std::visit([&](const auto& kernel) { return kernel.normal(where.kernel_point); },
                            s.kernels()[where.kernel]);
    return out;
}

// Phong terms evaluated in kernel space: diffuse max(n . l, 0) and specular
// max(r . v, 0)^shininess with r the mirror direction of l about n. With interpolated (not unit)
// light and view vectors both stay continuous across mirror planes.
struct phong_terms {
    float diffuse = 0.0f;
    float specular = 0.0f;
};

template <std::floating_point S>
phong_terms phong(const kernel_space_shading<S>& k, S shininess)
{
    require_positive("phong.shininess", shininess);
    const S cosine = dot(k.normal, k.light);
    phong_terms t;
    t.diffuse = float(std::max(cosine, S(0)));
    if (cosine > S(0)) {
        const vec3<S> r = k.normal * (S(2) * cosine) - k.light;
        const S rv = dot(r, k.view);
        if (rv > S(0)) t.specular = float(std::pow(rv, shininess));
    }
    return t;
}

} // namespace krs

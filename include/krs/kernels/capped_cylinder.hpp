#pragma once
// Capped cylinder kernel: the solid cylinder of `radius` around the segment from a to b, cut flat
// at both ends (a capsule has ball ends instead; this one has discs).
//
// The solid is a solid of revolution about the axis u = (b - a) / |b - a|. With c the segment's
// middle, q = p - c, y = dot(q, u) the height along the axis and x = |q - y u| the distance from
// it, every cross-section through the axis and p shows the same rectangle |x| <= r, |y| <= h
// (h = |b - a| / 2), and the nearest point of the solid to p lies in that half-plane (turning a
// point about the axis keeps its height and its distance to the axis, so the nearest point of
// the solid of revolution is the nearest point of the rectangle). The field is therefore the
// exact 2D box distance of (x - r, |y| - h),
//     length(max((x - r, |y| - h), 0)) + min(max(x - r, |y| - h), 0),
// 1-Lipschitz and zero on the surface. The offset from the axis is formed by subtracting y u per
// coordinate, not as sqrt(|q|^2 - y^2), which cancels near the axis (torus.hpp says why).
//
// radius > 0 and |b - a| >= min_length (krs/core/validate.hpp): coincident ends have no axis.
// Ends and radius obey the magnitude policy.

#include "krs/core/bounds.hpp"
#include "krs/core/validate.hpp"
#include "krs/kernels/torus_capsule.hpp" // surface_uv

#include <array>
#include <cmath>
#include <numbers>
#include <string_view>

namespace krs {

class capped_cylinder {
public:
    capped_cylinder() : capped_cylinder(vec3f{0, 0, -0.5f}, vec3f{0, 0, 0.5f}, 0.5f) {}
    capped_cylinder(const vec3f& a, const vec3f& b, float radius)
        : a_(require_magnitude("capped_cylinder.a", a)), b_(require_magnitude("capped_cylinder.b", b)),
          radius_(require_positive_length("capped_cylinder.radius", radius))
    {
        const vec3d ad(a_), bd(b_);
        const vec3d ab = bd - ad;
        const double len = length(ab);
        if (!(len >= double(min_length)))
            throw invalid_parameter("capped_cylinder.b", "must lie at least 1e-6 (min_length) from a",
                                    detail::to_text(b_) + " with a = " + detail::to_text(a_));
        const vec3d u = ab / len;
        center_ = vec3f((ad + bd) * 0.5);
        axis_ = vec3f(u);
        half_length_ = static_cast<float>(0.5 * len);
        // A fixed unit vector across the axis: the normal's direction on the axis itself (where
        // every radial direction is as near) and uv's angle origin.
        const vec3d e1 = unit_across(u);
        across_ = vec3f(e1);
        across_2_ = vec3f(cross(u, e1));
    }

    const vec3f& a() const { return a_; }
    const vec3f& b() const { return b_; }
    float radius() const { return radius_; }

    // The same cylinder rebuilt through the constructor's checks.
    capped_cylinder checked() const { return capped_cylinder(a_, b_, radius_); }

    template <class T>
    T distance(const vec3<T>& p) const
    {
        const vec3<T> q = p - vec3<T>(center_);
        const T y = dot(q, vec3<T>(axis_));
        const T dx = length(q - vec3<T>(axis_) * y) - T(radius_);
        const T dy = abs(y) - T(half_length_);
        const T ox = max(dx, T(0)), oy = max(dy, T(0));
        return sqrt(ox * ox + oy * oy) + min(max(dx, dy), T(0));
    }

    // Gradient of the distance: outside, from the nearest point of the rectangle (x, y) <= (r, h)
    // toward p, turned back into space; inside, the nearest face's normal (the side when the side
    // and a cap are equally near, as the GLSL does). On the axis the fixed across_ stands in for
    // the radial direction.
    template <class T>
    vec3<T> normal(const vec3<T>& p) const
    {
        const vec3<T> q = p - vec3<T>(center_);
        const T y = dot(q, vec3<T>(axis_));
        const vec3<T> w = q - vec3<T>(axis_) * y;
        const T x = length(w);
        const T one(1);
        const vec3<T> radial = select(x > T(0), w / select(x > T(0), x, one), vec3<T>(across_));
        const vec3<T> up = vec3<T>(axis_) * select(y < T(0), T(-1), one);
        const T dx = x - T(radius_), dy = abs(y) - T(half_length_);
        const T ox = max(dx, T(0)), oy = max(dy, T(0));
        const T ol = sqrt(ox * ox + oy * oy);
        const auto outside = ol > T(0);
        const T safe = select(outside, ol, one);
        const auto side = dx >= dy;
        const T gx = select(outside, ox / safe, select(side, one, T(0)));
        const T gy = select(outside, oy / safe, select(side, T(0), one));
        return radial * gx + up * gy;
    }

    // u: along the axis, 0 at a and 1 at b (clamped); v: angle around the axis / (2 pi) + 0.5, in
    // [0, 1] (0.5 toward across_, rising toward axis x across_).
    template <class T>
    surface_uv<T> uv(const vec3<T>& p) const
    {
        const vec3<T> q = p - vec3<T>(center_);
        const T y = dot(q, vec3<T>(axis_));
        const T u = clamp(T(0.5f) + y / T(2 * half_length_), T(0), T(1));
        const T two_pi(2 * std::numbers::pi_v<float>);
        const T v = lane_atan2(dot(q, vec3<T>(across_2_)), dot(q, vec3<T>(across_))) / two_pi + T(0.5f);
        return {u, v};
    }

    bounding_sphere bound() const
    {
        const double h = half_length_, r = radius_;
        return bound_around(vec3d(center_), std::sqrt(h * h + r * r));
    }
    // Exact: the solid is the two end discs' hull; a disc of radius r across the unit axis n
    // reaches r sqrt(1 - n_i^2) along world axis i (torus.hpp), and its centre is an end. The ends
    // are c +- h n from the stored floats the distance reads; the float axis is unit to about
    // 1e-7, which moves the surface by about 1e-7 of h + r: the pad, a relative 1e-6 of h + r,
    // covers that.
    bounding_box bound_box() const
    {
        const vec3d n(axis_), c(center_);
        const double h = half_length_, r = radius_;
        const auto reach = [&](double ni) { return r * std::sqrt(std::max(0.0, 1.0 - ni * ni)); };
        const vec3d e{reach(n.x), reach(n.y), reach(n.z)};
        const vec3d end_a = c - n * h, end_b = c + n * h;
        return intersect(box_around(min(end_a, end_b) - e, max(end_a, end_b) + e, 1e-6 * (h + r)),
                         box_around(bound()));
    }

    // The colour a Shadertoy program and its reference shade this kind with where the caller
    // gives no palette (linear RGB; stone: cylinders are pillars and posts).
    static constexpr vec3f default_albedo{0.70f, 0.68f, 0.64f};
    // GLSL: the same distance and normal; three vec4s (center, h), (axis, r), (across, 0).
    static constexpr std::string_view glsl_name = "krs_capped_cylinder";
    static constexpr std::string_view glsl_source = R"(float krs_capped_cylinder_distance(vec3 p, vec4 c0, vec4 c1, vec4 c2) {
    vec3 q = p - c0.xyz;
    float y = dot(q, c1.xyz);
    vec2 d = vec2(length(q - c1.xyz * y) - c1.w, abs(y) - c0.w);
    return length(max(d, vec2(0.0))) + min(max(d.x, d.y), 0.0);
}
vec3 krs_capped_cylinder_normal(vec3 p, vec4 c0, vec4 c1, vec4 c2) {
    vec3 q = p - c0.xyz;
    float y = dot(q, c1.xyz);
    vec3 w = q - c1.xyz * y;
    float x = length(w);
    vec3 radial = x > 0.0 ? w / x : c2.xyz;
    vec3 up = y < 0.0 ? -c1.xyz : c1.xyz;
    vec2 d = vec2(x - c1.w, abs(y) - c0.w);
    vec2 o = max(d, vec2(0.0));
    float ol = length(o);
    vec2 g = ol > 0.0 ? o / ol : (d.x >= d.y ? vec2(1.0, 0.0) : vec2(0.0, 1.0));
    return radial * g.x + up * g.y;
}
)";
    std::array<float, 12> glsl_parameters() const
    {
        return {center_.x, center_.y, center_.z, half_length_, axis_.x,   axis_.y,
                axis_.z,   radius_,   across_.x, across_.y,    across_.z, 0.0f};
    }

private:
    vec3f a_, b_;
    float radius_ = 0.5f;
    vec3f center_{}, axis_{0, 0, 1}; // the segment's middle and unit direction, rounded once
    float half_length_ = 0.5f;
    vec3f across_{1, 0, 0}, across_2_{0, 1, 0}; // unit, across the axis, and axis x across_
};

} // namespace krs

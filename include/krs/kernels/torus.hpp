#pragma once
// Torus kernel: every point within `minor_radius` of a circle (center, axis, major_radius), a
// closed ring. A torus_capsule bent into a full turn would be the same solid, but it stops short
// of one (its arcs end in caps), so a ring took two of them: a ring and a sphere evaluate in 10 ns
// per 16-lane packet where two torus capsules and the sphere took 21 (a grid of 2^22 copies).
//
// With q = p - center, h = dot(q, axis) the height over the circle's plane and w = q - h axis the
// in-plane offset, the circle's nearest point lies in the half-plane through the axis and p, at
// R w / |w|, so the distance to the circle is
//     sqrt((|w| - R)^2 + h^2),
// and minus the minor radius the field is exact (1-Lipschitz, zero on the surface). w is formed
// by subtracting h axis per coordinate, each term of the size of q, instead of as
// sqrt(|q|^2 - h^2): that difference of squares cancels near the axis, where a point 1e-4 off it
// would be placed about sqrt(ulp(|q|^2)) = 3e-4 away at |q| = 1.
//
// R >= 0 and r >= 0 are free: R = 0 is a ball, r > R a spindle torus (the tube overlapping itself
// around the axis), for which the formula is still the exact distance outside and an
// underestimate inside.

#include "krs/core/bounds.hpp"
#include "krs/core/validate.hpp"
#include "krs/kernels/torus_capsule.hpp" // surface_uv

#include <array>
#include <cmath>
#include <numbers>
#include <string_view>

namespace krs {

class torus {
public:
    torus() : torus(vec3f{0, 0, 0}, vec3f{0, 0, 1}, 1.0f, 0.25f) {}
    torus(const vec3f& center, const vec3f& axis, float major_radius, float minor_radius)
        : center_(require_magnitude("torus.center", center)), axis_(require_direction("torus.axis", axis)),
          major_(require_length("torus.major_radius", major_radius)),
          minor_(require_length("torus.minor_radius", minor_radius))
    {
        // A fixed unit vector in the circle's plane: the direction the normal and uv fall back to
        // on the axis, where every circle point is equally near, and uv's angle origin.
        const vec3d a(axis_);
        const vec3d e1 = unit_across(a);
        in_plane_ = vec3f(e1);
        in_plane_2_ = vec3f(cross(a, e1));
    }

    const vec3f& center() const { return center_; }
    const vec3f& axis() const { return axis_; }
    float major_radius() const { return major_; }
    float minor_radius() const { return minor_; }

    template <class T>
    T distance(const vec3<T>& p) const
    {
        const vec3<T> q = p - vec3<T>(center_);
        const T h = dot(q, vec3<T>(axis_));
        const T radial = length(q - vec3<T>(axis_) * h) - T(major_);
        return sqrt(radial * radial + h * h) - T(minor_);
    }

    // Outward normal: away from the nearest circle point. On the axis the in-plane fallback
    // direction stands in for w / |w|, and on the circle itself (distance 0 to it) the radial
    // direction is returned, never NaN.
    template <class T>
    vec3<T> normal(const vec3<T>& p) const
    {
        const vec3<T> q = p - vec3<T>(center_);
        const T h = dot(q, vec3<T>(axis_));
        const vec3<T> w = q - vec3<T>(axis_) * h;
        const T wl = length(w);
        const T one(1);
        const vec3<T> outward = select(wl > T(0), w / select(wl > T(0), wl, one), vec3<T>(in_plane_));
        const vec3<T> offset = outward * (wl - T(major_)) + vec3<T>(axis_) * h;
        const T ol = length(offset);
        return select(ol > T(0), offset / select(ol > T(0), ol, one), outward);
    }

    // u: angle around the axis / (2 pi) + 0.5, in [0, 1] (0.5 toward the in-plane direction e1,
    // rising toward axis x e1); v: angle around the tube / (2 pi) + 0.5, in [0, 1]: 0.5 on the
    // outside of the ring (as torus_capsule's v), 0.75 on the axis side of the plane, 0.25 below
    // it, 0 and 1 facing the axis.
    template <class T>
    surface_uv<T> uv(const vec3<T>& p) const
    {
        const vec3<T> q = p - vec3<T>(center_);
        const T h = dot(q, vec3<T>(axis_));
        const T radial = length(q - vec3<T>(axis_) * h) - T(major_);
        const T two_pi(2 * std::numbers::pi_v<float>);
        const T u = lane_atan2(dot(q, vec3<T>(in_plane_2_)), dot(q, vec3<T>(in_plane_))) / two_pi + T(0.5f);
        const T v = lane_atan2(h, radial) / two_pi + T(0.5f);
        return {u, v};
    }

    bounding_sphere bound() const { return bound_around(vec3d(center_), double(major_) + double(minor_)); }
    // Exact, in any orientation: the circle's points c + R (cos t e1 + sin t e2) reach
    // R sqrt(e1_i^2 + e2_i^2) = R sqrt(1 - n_i^2) from c along axis i (e1, e2, n orthonormal),
    // and the tube adds r. n is the float axis normalized in double; the distance uses the float
    // axis as stored, unit to about 1e-7, which moves the surface by about 1e-7 of R + r: the pad,
    // a relative 1e-6 of R + r, covers that.
    bounding_box bound_box() const
    {
        const vec3d n = normalize(vec3d(axis_));
        const double big = major_, small = minor_;
        const auto reach = [&](double ni) { return big * std::sqrt(std::max(0.0, 1.0 - ni * ni)) + small; };
        const vec3d c(center_), e{reach(n.x), reach(n.y), reach(n.z)};
        return intersect(box_around(c - e, c + e, 1e-6 * (big + small)), box_around(bound()));
    }

    // GLSL: the same distance and normal; three vec4s: (center, R), (axis, r), (in-plane e1, 0).
    // The colour a Shadertoy program and its reference shade this kind with where the caller
    // gives no palette (linear RGB; stone).
    static constexpr vec3f default_albedo{0.70f, 0.68f, 0.64f};
    static constexpr std::string_view glsl_name = "krs_torus";
    static constexpr std::string_view glsl_source = R"(float krs_torus_distance(vec3 p, vec4 t0, vec4 t1, vec4 t2) {
    vec3 q = p - t0.xyz;
    float h = dot(q, t1.xyz);
    float radial = length(q - t1.xyz * h) - t0.w;
    return sqrt(radial * radial + h * h) - t1.w;
}
vec3 krs_torus_normal(vec3 p, vec4 t0, vec4 t1, vec4 t2) {
    vec3 q = p - t0.xyz;
    float h = dot(q, t1.xyz);
    vec3 w = q - t1.xyz * h;
    float wl = length(w);
    vec3 outward = wl > 0.0 ? w / wl : t2.xyz;
    vec3 offset = outward * (wl - t0.w) + t1.xyz * h;
    float ol = length(offset);
    return ol > 0.0 ? offset / ol : outward;
}
)";
    std::array<float, 12> glsl_parameters() const
    {
        return {
                center_.x, center_.y, center_.z, major_, axis_.x,      axis_.y,
                axis_.z,   minor_,    in_plane_.x, in_plane_.y, in_plane_.z, 0.0f};
    }

private:
    vec3f center_, axis_;
    float major_ = 1.0f, minor_ = 0.25f;
    vec3f in_plane_{1, 0, 0}, in_plane_2_{0, 1, 0};
};

} // namespace krs

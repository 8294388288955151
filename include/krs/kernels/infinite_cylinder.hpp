#pragma once
// Infinite cylinder kernel: every point within `radius` of the line through `point` along `axis`.
//
// The nearest point of the line to p is its foot point + dot(p - point, u) u (u the unit axis),
// so the distance to the line is |w| with w = q - dot(q, u) u, q = p - point, and |w| - radius is
// exact (1-Lipschitz, zero on the surface). w is formed by subtracting per coordinate, not as
// sqrt(|q|^2 - dot(q, u)^2), which cancels near the axis (torus.hpp says why). Like the plane,
// it has no bound: bound() is unbounded and tracers clip it themselves.
//
// radius > 0; point and radius obey the magnitude policy; the axis is any non-zero direction.

#include "krs/core/bounds.hpp"
#include "krs/core/validate.hpp"

#include <array>
#include <cmath>
#include <limits>
#include <string_view>

namespace krs {

class infinite_cylinder {
public:
    infinite_cylinder() : infinite_cylinder(vec3f{0, 0, 0}, vec3f{0, 0, 1}, 0.5f) {}
    infinite_cylinder(const vec3f& point, const vec3f& axis, float radius)
        : point_(require_magnitude("infinite_cylinder.point", point)),
          axis_(require_direction("infinite_cylinder.axis", axis)),
          radius_(require_positive_length("infinite_cylinder.radius", radius))
    {
        // A fixed unit vector across the axis: the normal on the axis itself, where every radial
        // direction is as near.
        across_ = vec3f(unit_across(vec3d(axis_)));
    }

    const vec3f& point() const { return point_; }
    const vec3f& axis() const { return axis_; }
    float radius() const { return radius_; }

    // The same cylinder rebuilt through the constructor's checks.
    infinite_cylinder checked() const { return infinite_cylinder(point_, axis_, radius_); }

    template <class T>
    T distance(const vec3<T>& p) const
    {
        const vec3<T> q = p - vec3<T>(point_);
        return length(q - vec3<T>(axis_) * dot(q, vec3<T>(axis_))) - T(radius_);
    }

    // Outward normal: away from the axis; on the axis, the fixed across_ direction.
    template <class T>
    vec3<T> normal(const vec3<T>& p) const
    {
        const vec3<T> q = p - vec3<T>(point_);
        const vec3<T> w = q - vec3<T>(axis_) * dot(q, vec3<T>(axis_));
        const T x = length(w);
        const auto degenerate = x <= T(0);
        return select(degenerate, vec3<T>(across_), w / select(degenerate, T(1), x));
    }

    bounding_sphere bound() const { return bounding_sphere::unbounded(); }
    // Unbounded on every world axis the line is not perpendicular to; bounded (the line's
    // coordinate plus or minus r sqrt(1 - n_i^2), as a disc across the axis reaches) on one it is
    // perpendicular to exactly. The stored float axis is unit to about 1e-7: the pad, a relative
    // 1e-6 of |point| + r, covers the surface's shift.
    bounding_box bound_box() const
    {
        const vec3d n(axis_), c(point_);
        const double r = radius_;
        const double inf = std::numeric_limits<double>::infinity();
        const auto reach = [&](double ni) { return ni != 0 ? inf : r; };
        const vec3d e{reach(n.x), reach(n.y), reach(n.z)};
        return box_around(c - e, c + e, 1e-6 * (length(c) + r));
    }

    // The colour a Shadertoy program and its reference shade this kind with where the caller
    // gives no palette (linear RGB; stone: columns).
    static constexpr vec3f default_albedo{0.70f, 0.68f, 0.64f};
    // GLSL: the same distance and normal; three vec4s (point, r), (axis, 0), (across, 0).
    static constexpr std::string_view glsl_name = "krs_infinite_cylinder";
    static constexpr std::string_view glsl_source = R"(float krs_infinite_cylinder_distance(vec3 p, vec4 c0, vec4 c1, vec4 c2) {
    vec3 q = p - c0.xyz;
    return length(q - c1.xyz * dot(q, c1.xyz)) - c0.w;
}
vec3 krs_infinite_cylinder_normal(vec3 p, vec4 c0, vec4 c1, vec4 c2) {
    vec3 q = p - c0.xyz;
    vec3 w = q - c1.xyz * dot(q, c1.xyz);
    float x = length(w);
    return x > 0.0 ? w / x : c2.xyz;
}
)";
    std::array<float, 12> glsl_parameters() const
    {
        return {point_.x, point_.y, point_.z, radius_, axis_.x,   axis_.y,
                axis_.z,  0.0f,     across_.x, across_.y, across_.z, 0.0f};
    }

private:
    vec3f point_, axis_{0, 0, 1};
    float radius_ = 0.5f;
    vec3f across_{1, 0, 0};
};

} // namespace krs

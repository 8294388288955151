#pragma once
// Sphere kernel: the solid ball |p - center| <= radius.
//
// Its signed distance |p - c| - r is exact (1-Lipschitz, zero on the surface), which makes it the
// kernel of choice for coral, rock and leaves (paper section 7.1). Radius 0 is allowed: a point.
// Center and radius obey the magnitude policy of krs/core/validate.hpp (|center|, radius <= 1e9).

#include "krs/core/bounds.hpp"
#include "krs/core/validate.hpp"

#include <array>
#include <string_view>

namespace krs {

struct sphere {
    vec3f center{};
    float radius = 0.0f;

    sphere() = default;
    sphere(const vec3f& center_, float radius_)
        : center(require_magnitude("sphere.center", center_)), radius(require_length("sphere.radius", radius_))
    {
    }

    // The same sphere through the constructor's checks (the fields are public).
    sphere checked() const { return sphere(center, radius); }

    template <class T>
    T distance(const vec3<T>& p) const
    {
        return length(p - vec3<T>(center)) - T(radius);
    }

    // Outward normal; at the center every direction is as good, so +z is returned rather than NaN.
    template <class T>
    vec3<T> normal(const vec3<T>& p) const
    {
        const vec3<T> q = p - vec3<T>(center);
        const T len = length(q);
        const auto degenerate = len <= T(0);
        const T safe = select(degenerate, T(1), len);
        return select(degenerate, vec3<T>(T(0), T(0), T(1)), q / safe);
    }

    bounding_sphere bound() const { return {center, radius}; }
    // Exact: center +- radius on each axis, rounded outward.
    bounding_box bound_box() const
    {
        const vec3d c(center), r{radius, radius, radius};
        return box_around(c - r, c + r);
    }

    // The colour a Shadertoy program and its reference shade this kind with where the caller
    // gives no palette (linear RGB; leaf green: spheres are a tree's leaves).
    static constexpr vec3f default_albedo{0.22f, 0.45f, 0.12f};
    // GLSL (krs/glsl/emitter.hpp): the same distance and normal, parameters packed as one vec4
    // (center, radius).
    static constexpr std::string_view glsl_name = "krs_sphere";
    static constexpr std::string_view glsl_source = R"(float krs_sphere_distance(vec3 p, vec4 s) { return length(p - s.xyz) - s.w; }
vec3 krs_sphere_normal(vec3 p, vec4 s) {
    vec3 q = p - s.xyz;
    float len = length(q);
    return len > 0.0 ? q / len : vec3(0.0, 0.0, 1.0);
}
)";
    std::array<float, 4> glsl_parameters() const { return {center.x, center.y, center.z, radius}; }
};

} // namespace krs

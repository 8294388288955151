#pragma once
// Plane kernel: the solid half-space dot(n, p) <= offset, with n a unit normal.
//
// Its signed distance dot(n, p) - offset is exact (1-Lipschitz because |n| = 1, zero on the
// plane): a ground for terrain and the clipping half of a KRS mirror. The normal is normalized at
// construction (in double), so a user may pass any non-zero direction. A half-space has no finite
// bound, so bound() reports an unbounded sphere and tracers must clip it themselves. The offset
// (the plane's distance from the origin) obeys the magnitude policy of krs/core/validate.hpp.

#include "krs/core/bounds.hpp"
#include "krs/core/oriented_plane.hpp"
#include "krs/core/validate.hpp"

#include <array>
#include <string_view>

namespace krs {

struct plane {
    vec3f normal_direction{0, 0, 1};
    float offset = 0.0f;

    plane() = default;
    plane(const vec3f& normal_, float offset_) : plane(oriented_plane::checked("plane", normal_, offset_)) {}

    // The half-space whose boundary passes through `point` with outward normal `normal` (the
    // offset computed in double from the normalized normal: core/oriented_plane.hpp).
    static plane through(const vec3f& point, const vec3f& normal) { return plane(oriented_plane::through("plane", point, normal)); }

    // The same half-space through the constructor's checks (the fields are public: a normal of
    // length 2 doubled the distance, which then overestimated).
    plane checked() const { return plane(oriented_plane::kept("plane", normal_direction, offset)); }

    template <class T>
    T distance(const vec3<T>& p) const
    {
        return plane_value(vec3<T>(normal_direction), p, T(offset));
    }

    template <class T>
    vec3<T> normal(const vec3<T>&) const
    {
        return vec3<T>(normal_direction);
    }

    bounding_sphere bound() const { return bounding_sphere::unbounded(); }
    bounding_box bound_box() const { return bounding_box::unbounded(); }

    // GLSL: one vec4 (unit normal, offset).
    // The colour a Shadertoy program and its reference shade this kind with where the caller
    // gives no palette (linear RGB; soil: planes are grounds).
    static constexpr vec3f default_albedo{0.42f, 0.40f, 0.33f};
    static constexpr std::string_view glsl_name = "krs_plane";
    static constexpr std::string_view glsl_source = R"(float krs_plane_distance(vec3 p, vec4 n) { return (n.x * p.x - n.w) + n.y * p.y + n.z * p.z; }
vec3 krs_plane_normal(vec3 p, vec4 n) { return n.xyz; }
)";
    std::array<float, 4> glsl_parameters() const { return {normal_direction.x, normal_direction.y, normal_direction.z, offset}; }

private:
    explicit plane(const oriented_plane& p) : normal_direction(p.normal), offset(p.offset) {}
};

} // namespace krs

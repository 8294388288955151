#pragma once
// Capsule kernel: every point within `radius` of the segment from a to b.
//
// Its signed distance |p - closest point of ab| - radius is exact (1-Lipschitz, zero on the
// surface): the straight branch of a tree and the limit of a torus_capsule whose control point
// lies on the chord. a == b is allowed and gives a sphere; radius 0 gives the bare segment.
// Otherwise |b - a| >= min_length (krs/core/validate.hpp): the clamp below multiplies by
// 1 / |b - a|^2, which must be a finite float.

#include "krs/core/bounds.hpp"
#include "krs/core/validate.hpp"

#include <array>
#include <string_view>

namespace krs {

struct capsule {
    vec3f a{}, b{};
    float radius = 0.0f;

    capsule() = default;
    capsule(const vec3f& a_, const vec3f& b_, float radius_)
        : a(require_magnitude("capsule.a", a_)), b(require_magnitude("capsule.b", b_)),
          radius(require_length("capsule.radius", radius_))
    {
        const vec3d ad(a), bd(b);
        const vec3d ab = bd - ad;
        const double len2 = dot(ab, ab);
        if (len2 > 0.0 && !(std::sqrt(len2) >= double(min_length)))
            throw invalid_parameter("capsule.b", "must equal a or lie at least 1e-6 (min_length) from it",
                                    detail::to_text(b) + " with a = " + detail::to_text(a));
        axis_ = vec3f(ab);
        // a == b makes every t equivalent; 0 keeps the clamp below free of a 0/0.
        inverse_length_squared_ = len2 > 0.0 ? static_cast<float>(1.0 / len2) : 0.0f;
        // On the segment itself the normal is any direction perpendicular to it.
        const vec3d helper = std::abs(ab.x) <= std::abs(ab.y) && std::abs(ab.x) <= std::abs(ab.z)
                                 ? vec3d{1, 0, 0}
                                 : (std::abs(ab.y) <= std::abs(ab.z) ? vec3d{0, 1, 0} : vec3d{0, 0, 1});
        const vec3d perpendicular = len2 > 0.0 ? normalize(cross(ab, helper)) : vec3d{0, 0, 1};
        perpendicular_ = vec3f(perpendicular);
    }

    // Offset from the closest point of the segment to p (its length is the unsigned distance to
    // the segment).
    template <class T>
    vec3<T> offset_from_axis(const vec3<T>& p) const
    {
        const vec3<T> ap = p - vec3<T>(a);
        const vec3<T> ab(axis_);
        const T t = clamp(dot(ap, ab) * T(inverse_length_squared_), T(0), T(1));
        return ap - ab * t;
    }

    // The same capsule rebuilt through the constructor (the ends and radius are public; the axis
    // and its inverse length kept below would be stale after a change to them).
    capsule checked() const { return capsule(a, b, radius); }

    template <class T>
    T distance(const vec3<T>& p) const
    {
        return length(offset_from_axis(p)) - T(radius);
    }

    // Outward normal: away from the closest segment point; on the segment, a fixed perpendicular.
    template <class T>
    vec3<T> normal(const vec3<T>& p) const
    {
        const vec3<T> q = offset_from_axis(p);
        const T len = length(q);
        const auto degenerate = len <= T(0);
        const T safe = select(degenerate, T(1), len);
        return select(degenerate, vec3<T>(perpendicular_), q / safe);
    }

    bounding_sphere bound() const
    {
        const vec3d ad(a), bd(b);
        return bound_around((ad + bd) * 0.5, 0.5 * length(bd - ad) + radius);
    }
    // The box of the two end balls, exact: a coordinate is linear along the segment, so its
    // extremes are at the ends. The pad (a relative 1e-6 of the capsule's size) covers the
    // float b - a the distance clamps against, which may end an ulp of |b - a| short of or past b.
    bounding_box bound_box() const
    {
        const vec3d ad(a), bd(b), r{radius, radius, radius};
        const double pad = 1e-6 * (length(bd - ad) + double(radius));
        return intersect(box_around(min(ad, bd) - r, max(ad, bd) + r, pad), box_around(bound()));
    }

    // GLSL: three vec4s (a, radius), (b - a, 1 / |b - a|^2), (perpendicular, 0): the stored float
    // values, so the GPU clamps the same t as the CPU.
    // The colour a Shadertoy program and its reference shade this kind with where the caller
    // gives no palette (linear RGB; bark: capsules are stems).
    static constexpr vec3f default_albedo{0.40f, 0.26f, 0.15f};
    static constexpr std::string_view glsl_name = "krs_capsule";
    static constexpr std::string_view glsl_source = R"(vec3 krs_capsule_offset(vec3 p, vec4 a, vec4 ab) {
    vec3 ap = p - a.xyz;
    float t = clamp(dot(ap, ab.xyz) * ab.w, 0.0, 1.0);
    return ap - ab.xyz * t;
}
float krs_capsule_distance(vec3 p, vec4 a, vec4 ab, vec4 perpendicular) { return length(krs_capsule_offset(p, a, ab)) - a.w; }
vec3 krs_capsule_normal(vec3 p, vec4 a, vec4 ab, vec4 perpendicular) {
    vec3 q = krs_capsule_offset(p, a, ab);
    float len = length(q);
    return len > 0.0 ? q / len : perpendicular.xyz;
}
)";
    std::array<float, 12> glsl_parameters() const
    {
        return {
                a.x, a.y, a.z, radius, axis_.x, axis_.y, axis_.z, inverse_length_squared_,
                perpendicular_.x, perpendicular_.y, perpendicular_.z, 0.0f};
    }

private:
    vec3f axis_{};                      // b - a, rounded to float once
    float inverse_length_squared_ = 0;  // 1 / |b - a|^2, or 0 when a == b
    vec3f perpendicular_{0, 0, 1};      // unit, perpendicular to b - a
};

} // namespace krs

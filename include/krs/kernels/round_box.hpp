#pragma once
// Round box kernel: an axis-aligned box with its edges and corners rounded by `radius`, the same
// outer size as krs::box(center, half_extents). (krs::placed turns or moves it.)
//
// The solid is the inner box B (half extents h - r) grown by a ball of radius r: every point
// within r of B. For a convex set B with exact signed distance d_B, d_B - r is the exact signed
// distance of B grown by r. Outside B, d_B is the distance to B, so the grown solid's boundary is
// the level set d_B = r and a point at d_B = s < r or s > r lies |r - s| from it (d_B is
// 1-Lipschitz and grows at rate 1 along its gradient). Inside B, a convex set's depth is the
// least over directions u of its support h_B(u) - dot(p, u), and growing by r adds r to every
// support, so the depth of p in the grown solid is r + (depth in B). Both are d_B - r, with d_B
// the box distance of box.hpp (a box member here), so the field is exact (1-Lipschitz, zero on
// the surface), and its gradient is the inner box's.
//
// radius > 0 (radius 0 is krs::box) and at most the smallest half extent, so the inner box is
// not empty. Center, half extents and radius obey the magnitude policy.

#include "krs/core/bounds.hpp"
#include "krs/core/validate.hpp"
#include "krs/kernels/box.hpp"

#include <algorithm>
#include <array>
#include <string_view>

namespace krs {

class round_box {
public:
    round_box() : round_box(vec3f{0, 0, 0}, vec3f{0.5f, 0.5f, 0.5f}, 0.1f) {}
    round_box(const vec3f& center, const vec3f& half_extents, float radius)
        : center_(require_magnitude("round_box.center", center)),
          half_extents_(require_magnitude("round_box.half_extents", half_extents)),
          radius_(require_positive_length("round_box.radius", radius))
    {
        if (!(half_extents_.x >= 0 && half_extents_.y >= 0 && half_extents_.z >= 0))
            throw invalid_parameter("round_box.half_extents", "must be >= 0 in every component",
                                    detail::to_text(half_extents_));
        const float smallest = std::min({half_extents_.x, half_extents_.y, half_extents_.z});
        if (!(radius_ <= smallest))
            throw invalid_parameter("round_box.radius", "must be at most the smallest half extent",
                                    detail::to_text(radius_) + " with half extents " + detail::to_text(half_extents_));
        // The inner box's half extents, rounded once; >= 0 since r <= each h_i.
        inner_ = vec3f(vec3d(half_extents_) - vec3d{radius_, radius_, radius_});
        inner_box_ = box(center_, inner_);
    }

    const vec3f& center() const { return center_; }
    const vec3f& half_extents() const { return half_extents_; }
    float radius() const { return radius_; }

    // The same box rebuilt through the constructor's checks.
    round_box checked() const { return round_box(center_, half_extents_, radius_); }

    template <class T>
    T distance(const vec3<T>& p) const
    {
        return inner_box_.distance(p) - T(radius_);
    }

    // The inner box's gradient, which the offset by r keeps.
    template <class T>
    vec3<T> normal(const vec3<T>& p) const
    {
        return inner_box_.normal(p);
    }

    // The ball around the inner box's corners grown by r (tighter than the outer box's corners).
    bounding_sphere bound() const { return bound_around(vec3d(center_), length(vec3d(inner_)) + double(radius_)); }
    // Exact: the inner box grown by r on every axis is the outer box, its faces' flat parts
    // reaching it. The float inner extents plus r may round an ulp past h: the pad covers that.
    bounding_box bound_box() const
    {
        const vec3d c(center_), e = vec3d(inner_) + vec3d{radius_, radius_, radius_};
        return intersect(box_around(c - e, c + e, 1e-6 * (e.x + e.y + e.z)), box_around(bound()));
    }

    // The colour a Shadertoy program and its reference shade this kind with where the caller
    // gives no palette (linear RGB; stone: round boxes are pebbles and blocks).
    static constexpr vec3f default_albedo{0.70f, 0.68f, 0.64f};
    // GLSL: the same distance and normal; two vec4s (center, r), (inner half extents, 0).
    static constexpr std::string_view glsl_name = "krs_round_box";
    static constexpr std::string_view glsl_source = R"(float krs_round_box_distance(vec3 p, vec4 b0, vec4 b1) {
    vec3 q = abs(p - b0.xyz) - b1.xyz;
    return length(max(q, vec3(0.0))) + min(max(q.x, max(q.y, q.z)), 0.0) - b0.w;
}
vec3 krs_round_box_normal(vec3 p, vec4 b0, vec4 b1) {
    vec3 l = p - b0.xyz;
    vec3 s = vec3(l.x < 0.0 ? -1.0 : 1.0, l.y < 0.0 ? -1.0 : 1.0, l.z < 0.0 ? -1.0 : 1.0);
    vec3 q = abs(l) - b1.xyz;
    vec3 o = max(q, vec3(0.0));
    float ol = length(o);
    bool xl = q.x >= q.y && q.x >= q.z;
    bool yl = !xl && q.y >= q.z;
    vec3 face = vec3(xl ? 1.0 : 0.0, yl ? 1.0 : 0.0, (xl || yl) ? 0.0 : 1.0);
    return (ol > 0.0 ? o / ol : face) * s;
}
)";
    std::array<float, 8> glsl_parameters() const
    {
        return {center_.x, center_.y, center_.z, radius_, inner_.x, inner_.y, inner_.z, 0.0f};
    }

private:
    vec3f center_{}, half_extents_{0.5f, 0.5f, 0.5f};
    float radius_ = 0.1f;
    vec3f inner_{0.4f, 0.4f, 0.4f}; // half extents - radius
    box inner_box_{center_, inner_};   // whose distance and normal the round box offsets
};

} // namespace krs

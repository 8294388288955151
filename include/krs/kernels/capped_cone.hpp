#pragma once
// Capped cone kernel: the solid cone frustum from a disc of radius_a at a to a disc of radius_b
// at b, both across the axis b - a (a cone when one radius is 0, a capped cylinder when they
// are equal).
//
// Like the capped cylinder (capped_cylinder.hpp), it is a solid of revolution: with c the
// segment's middle, u the unit axis, y = dot(p - c, u) and x the distance from the axis, the
// nearest point of the solid lies in the half-plane through the axis and p, whose cross-section
// is the trapezoid (0, -h), (ra, -h), (rb, h), (0, h) (h = |b - a| / 2). The axis edge x = 0 is
// no boundary of the solid, so the distance is that to the other three edges: the two caps
// (offset (max(x - r, 0), y -+ h)) and the side from A = (ra, -h) to B = (rb, h) (offset from its
// clamped foot point), the least of them, negative inside (|y| < h and p left of A -> B). Exact:
// 1-Lipschitz and zero on the surface.
//
// radius_a, radius_b >= 0, not both 0; |b - a| >= min_length (krs/core/validate.hpp).

#include "krs/core/bounds.hpp"
#include "krs/core/validate.hpp"

#include <algorithm>
#include <array>
#include <cmath>
#include <string_view>

namespace krs {

class capped_cone {
public:
    capped_cone() : capped_cone(vec3f{0, 0, -0.5f}, vec3f{0, 0, 0.5f}, 0.5f, 0.25f) {}
    capped_cone(const vec3f& a, const vec3f& b, float radius_a, float radius_b)
        : a_(require_magnitude("capped_cone.a", a)), b_(require_magnitude("capped_cone.b", b)),
          radius_a_(require_length("capped_cone.radius_a", radius_a)),
          radius_b_(require_length("capped_cone.radius_b", radius_b))
    {
        if (!(radius_a_ > 0 || radius_b_ > 0))
            throw invalid_parameter("capped_cone.radius_b", "must be > 0 where radius_a is 0 (the solid would be a segment)",
                                    detail::to_text(radius_b_));
        const vec3d ad(a_), bd(b_);
        const double len = length(bd - ad);
        if (!(len >= double(min_length)))
            throw invalid_parameter("capped_cone.b", "must lie at least 1e-6 (min_length) from a",
                                    detail::to_text(b_) + " with a = " + detail::to_text(a_));
        const vec3d u = (bd - ad) / len;
        center_ = vec3f((ad + bd) * 0.5);
        axis_ = vec3f(u);
        half_length_ = static_cast<float>(0.5 * len);
        across_ = vec3f(unit_across(u));
    }

    const vec3f& a() const { return a_; }
    const vec3f& b() const { return b_; }
    float radius_a() const { return radius_a_; }
    float radius_b() const { return radius_b_; }

    // The same cone rebuilt through the constructor's checks.
    capped_cone checked() const { return capped_cone(a_, b_, radius_a_, radius_b_); }

    template <class T>
    T distance(const vec3<T>& p) const
    {
        const section<T> s = nearest(p);
        const T d = sqrt(s.ox * s.ox + s.oy * s.oy);
        return select(s.inside, -d, d);
    }

    // Gradient: from the nearest boundary point of the trapezoid toward p outside, away from it
    // inside, turned back into space; on the boundary itself, the nearest edge's outward normal.
    template <class T>
    vec3<T> normal(const vec3<T>& p) const
    {
        const section<T> s = nearest(p);
        const T len = sqrt(s.ox * s.ox + s.oy * s.oy);
        const auto on_edge = len <= T(0);
        const T scale = select(s.inside, T(-1), T(1)) / select(on_edge, T(1), len);
        const T gx = select(on_edge, s.edge_x, s.ox * scale), gy = select(on_edge, s.edge_y, s.oy * scale);
        return s.radial * gx + vec3<T>(axis_) * gy;
    }

    // The ball around the middle reaching both rims.
    bounding_sphere bound() const
    {
        const double h = half_length_, r = std::max(radius_a_, radius_b_);
        return bound_around(vec3d(center_), std::sqrt(h * h + r * r));
    }
    // Exact: the solid is the hull of its two end discs; a disc of radius r across the unit axis
    // n reaches r sqrt(1 - n_i^2) along world axis i (torus.hpp). From the stored floats, padded
    // by a relative 1e-6 of h + r for the float axis (unit to about 1e-7).
    bounding_box bound_box() const
    {
        const vec3d n(axis_), c(center_);
        const double h = half_length_;
        const auto disc = [&](const vec3d& at, double r, vec3d& lo, vec3d& hi) {
            const vec3d e{r * std::sqrt(std::max(0.0, 1.0 - n.x * n.x)), r * std::sqrt(std::max(0.0, 1.0 - n.y * n.y)),
                          r * std::sqrt(std::max(0.0, 1.0 - n.z * n.z))};
            lo = min(lo, at - e), hi = max(hi, at + e);
        };
        vec3d lo = c, hi = c;
        disc(c - n * h, radius_a_, lo, hi);
        disc(c + n * h, radius_b_, lo, hi);
        return intersect(box_around(lo, hi, 1e-6 * (h + std::max(radius_a_, radius_b_))), box_around(bound()));
    }

    // The colour a Shadertoy program and its reference shade this kind with where the caller
    // gives no palette (linear RGB; terracotta: cones are roofs and pots).
    static constexpr vec3f default_albedo{0.62f, 0.33f, 0.20f};
    // GLSL: the same distance and normal; three vec4s (center, h), (axis, ra), (across, rb).
    static constexpr std::string_view glsl_name = "krs_capped_cone";
    static constexpr std::string_view glsl_source = R"(// The trapezoid edge nearest (x, y): (offset to it, its outward normal).
bool krs_capped_cone_inside(float x, float y, float h, float ra, float rb) {
    vec2 e = vec2(rb - ra, 2.0 * h);
    return abs(y) < h && e.x * (y + h) - e.y * (x - ra) > 0.0;
}
vec4 krs_capped_cone_nearest(float x, float y, float h, float ra, float rb) {
    vec2 bottom = vec2(max(x - ra, 0.0), y + h);
    vec2 top = vec2(max(x - rb, 0.0), y - h);
    vec2 e = vec2(rb - ra, 2.0 * h);
    vec2 w = vec2(x - ra, y + h);
    vec2 side = w - e * clamp(dot(w, e) / dot(e, e), 0.0, 1.0);
    float db = dot(bottom, bottom), dt = dot(top, top), ds = dot(side, side);
    vec2 n = vec2(e.y, -e.x) / length(e);
    vec4 best = db <= dt ? vec4(bottom, 0.0, -1.0) : vec4(top, 0.0, 1.0);
    return ds < min(db, dt) ? vec4(side, n) : best;
}
float krs_capped_cone_distance(vec3 p, vec4 k0, vec4 k1, vec4 k2) {
    vec3 q = p - k0.xyz;
    float y = dot(q, k1.xyz);
    float x = length(q - k1.xyz * y);
    vec4 o = krs_capped_cone_nearest(x, y, k0.w, k1.w, k2.w);
    float d = length(o.xy);
    return krs_capped_cone_inside(x, y, k0.w, k1.w, k2.w) ? -d : d;
}
vec3 krs_capped_cone_normal(vec3 p, vec4 k0, vec4 k1, vec4 k2) {
    vec3 q = p - k0.xyz;
    float y = dot(q, k1.xyz);
    vec3 w = q - k1.xyz * y;
    float x = length(w);
    vec3 radial = x > 0.0 ? w / x : k2.xyz;
    vec4 o = krs_capped_cone_nearest(x, y, k0.w, k1.w, k2.w);
    float len = length(o.xy);
    float s = krs_capped_cone_inside(x, y, k0.w, k1.w, k2.w) ? -1.0 : 1.0;
    vec2 g = len > 0.0 ? o.xy * (s / len) : o.zw;
    return radial * g.x + k1.xyz * g.y;
}
)";
    std::array<float, 12> glsl_parameters() const
    {
        return {center_.x, center_.y, center_.z, half_length_, axis_.x,   axis_.y,
                axis_.z,   radius_a_, across_.x, across_.y,    across_.z, radius_b_};
    }

private:
    // The nearest edge of the cross-section: its offset to p (ox, oy), its outward normal, whether
    // p is inside, and the radial direction that turns the section back into space.
    template <class T>
    struct section {
        T ox, oy, edge_x, edge_y;
        mask_t<T> inside;
        vec3<T> radial;
    };
    template <class T>
    section<T> nearest(const vec3<T>& p) const
    {
        const vec3<T> q = p - vec3<T>(center_);
        const T y = dot(q, vec3<T>(axis_));
        const vec3<T> w = q - vec3<T>(axis_) * y;
        const T x = length(w);
        const T h(half_length_), ra(radius_a_), rb(radius_b_);
        const T bx = max(x - ra, T(0)), by = y + h;  // to the cap at a
        const T tx = max(x - rb, T(0)), ty = y - h;  // to the cap at b
        const T ex = rb - ra, ey = T(2) * h;         // the side, A -> B
        const T wx = x - ra, wy = y + h;
        const T t = clamp((wx * ex + wy * ey) / (ex * ex + ey * ey), T(0), T(1));
        const T sx = wx - ex * t, sy = wy - ey * t;
        const T db = bx * bx + by * by, dt = tx * tx + ty * ty, ds = sx * sx + sy * sy;
        const T elen = sqrt(ex * ex + ey * ey);
        const auto bottom = db <= dt;
        const auto side = ds < min(db, dt);
        section<T> s;
        s.ox = select(side, sx, select(bottom, bx, tx));
        s.oy = select(side, sy, select(bottom, by, ty));
        s.edge_x = select(side, ey / elen, T(0));
        s.edge_y = select(side, -ex / elen, select(bottom, T(-1), T(1)));
        s.inside = abs(y) < h && ex * wy - ey * wx > T(0);
        const T one(1);
        s.radial = select(x > T(0), w / select(x > T(0), x, one), vec3<T>(across_));
        return s;
    }

    vec3f a_, b_;
    float radius_a_ = 0.5f, radius_b_ = 0.25f;
    vec3f center_{}, axis_{0, 0, 1}; // the segment's middle and unit direction, rounded once
    float half_length_ = 0.5f;
    vec3f across_{1, 0, 0};          // unit, across the axis
};

} // namespace krs

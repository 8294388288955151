#pragma once
// Box kernel: a solid rectangular box, axis-aligned or oriented by an orthonormal frame.
//
// In the box's frame, with q = |local p| - half_extents, the signed distance
// length(max(q, 0)) + min(max(q.x, q.y, q.z), 0) is exact: outside it is the distance to the
// nearest point of the surface, inside minus the distance to the nearest face. A rotation keeps
// it exact, which is why the frame must be orthonormal (a skewed frame would stretch space and
// overestimate). The frame is checked to 1e-4 and then re-orthonormalized in double, so the stored
// axes are orthonormal to float precision. Zero half extents are allowed (a rectangle, a segment,
// a point). Center and half extents obey the magnitude policy of krs/core/validate.hpp.

#include "krs/core/bounds.hpp"
#include "krs/core/validate.hpp"
#include "krs/kernels/capsule.hpp"

#include <array>
#include <cmath>
#include <string_view>

namespace krs {

struct box {
    box() = default;
    box(const vec3f& center, const vec3f& half_extents)
        : center_(require_magnitude("box.center", center)), half_extents_(checked_extents(half_extents))
    {
    }
    // Oriented box: local axis i of the box is world direction axis_i.
    box(const vec3f& center, const vec3f& half_extents, const vec3f& axis_x, const vec3f& axis_y,
        const vec3f& axis_z)
        : center_(require_magnitude("box.center", center)), half_extents_(checked_extents(half_extents))
    {
        require_finite("box.axes", axis_x);
        require_finite("box.axes", axis_y);
        require_finite("box.axes", axis_z);
        const vec3d x(axis_x), y(axis_y), z(axis_z);
        constexpr double tolerance = 1e-4;
        const bool orthonormal = std::abs(length(x) - 1) <= tolerance && std::abs(length(y) - 1) <= tolerance &&
                                 std::abs(length(z) - 1) <= tolerance && std::abs(dot(x, y)) <= tolerance &&
                                 std::abs(dot(y, z)) <= tolerance && std::abs(dot(z, x)) <= tolerance;
        if (!orthonormal)
            throw invalid_parameter("box.axes", "must be orthonormal within 1e-4",
                                    detail::to_text(axis_x) + ", " + detail::to_text(axis_y) + ", " +
                                        detail::to_text(axis_z));
        // Gram-Schmidt keeps x's direction; z keeps its handedness (a mirrored frame is still a box).
        const vec3d ux = normalize(x);
        const vec3d uy = normalize(y - ux * dot(ux, y));
        const vec3d c = cross(ux, uy);
        const vec3d uz = dot(c, z) >= 0 ? c : -c;
        axes_[0] = vec3f(ux);
        axes_[1] = vec3f(uy);
        axes_[2] = vec3f(uz);
        oriented_ = true;
    }

    const vec3f& center() const { return center_; }
    const vec3f& half_extents() const { return half_extents_; }
    const vec3f& axis(int i) const { return axes_[i]; }
    bool oriented() const { return oriented_; }

    template <class T>
    T distance(const vec3<T>& p) const
    {
        const vec3<T> q = abs(to_local(p)) - vec3<T>(half_extents_);
        return length(max(q, vec3<T>(T(0), T(0), T(0)))) + min(max(q.x, max(q.y, q.z)), T(0));
    }

    // Gradient of the distance: outside, toward p from the nearest surface point; inside, the
    // normal of the nearest face (ties go to x, then y, the order a GLSL port would use).
    template <class T>
    vec3<T> normal(const vec3<T>& p) const
    {
        const vec3<T> local = to_local(p);
        const vec3<T> sign{select(local.x < T(0), T(-1), T(1)), select(local.y < T(0), T(-1), T(1)),
                           select(local.z < T(0), T(-1), T(1))};
        const vec3<T> q = abs(local) - vec3<T>(half_extents_);
        const vec3<T> outside = max(q, vec3<T>(T(0), T(0), T(0)));
        const T outside_length = length(outside);
        const auto is_outside = outside_length > T(0);
        const vec3<T> outward = outside / select(is_outside, outside_length, T(1));
        const auto x_largest = q.x >= q.y && q.x >= q.z;
        const auto y_largest = !x_largest && q.y >= q.z;
        const vec3<T> face{select(x_largest, T(1), T(0)), select(y_largest, T(1), T(0)),
                           select(x_largest || y_largest, T(0), T(1))};
        const vec3<T> g = select(is_outside, outward, face);
        return to_world(vec3<T>{g.x * sign.x, g.y * sign.y, g.z * sign.z});
    }

    bounding_sphere bound() const
    {
        return bound_around(vec3d(center_), length(vec3d(half_extents_)));
    }
    // Exact: the box of its eight corners center + sum_j (+-h_j) axis_j, whose half extent on
    // world axis i is sum_j |axis_j[i]| h_j. An oriented box's float axes are orthonormal to about
    // 1e-7, so the solid the distance describes (|dot(p - c, axis_j)| <= h_j) reaches past those
    // corners by about 1e-7 of its size: the pad, a relative 1e-6 of sum_j h_j, covers that.
    bounding_box bound_box() const
    {
        const vec3d c(center_), h(half_extents_);
        if (!oriented_) return box_around(c - h, c + h);
        const vec3d ax(axes_[0]), ay(axes_[1]), az(axes_[2]);
        const vec3d reach{std::abs(ax.x) * h.x + std::abs(ay.x) * h.y + std::abs(az.x) * h.z,
                          std::abs(ax.y) * h.x + std::abs(ay.y) * h.y + std::abs(az.y) * h.z,
                          std::abs(ax.z) * h.x + std::abs(ay.z) * h.y + std::abs(az.z) * h.z};
        const double pad = 1e-6 * (h.x + h.y + h.z);
        return intersect(box_around(c - reach, c + reach, pad), box_around(bound()));
    }

    // GLSL: five vec4s (center, oriented ? 1 : 0), (half extents, 0), (axis x, 0), (axis y, 0),
    // (axis z, 0). The orientation test is uniform, as in C++.
    // The colour a Shadertoy program and its reference shade this kind with where the caller
    // gives no palette (linear RGB; stone).
    static constexpr vec3f default_albedo{0.70f, 0.68f, 0.64f};
    static constexpr std::string_view glsl_name = "krs_box";
    static constexpr std::string_view glsl_source = R"(vec3 krs_box_local(vec3 p, vec4 c, vec4 ax, vec4 ay, vec4 az) {
    vec3 d = p - c.xyz;
    return c.w != 0.0 ? vec3(dot(d, ax.xyz), dot(d, ay.xyz), dot(d, az.xyz)) : d;
}
float krs_box_distance(vec3 p, vec4 c, vec4 h, vec4 ax, vec4 ay, vec4 az) {
    vec3 q = abs(krs_box_local(p, c, ax, ay, az)) - h.xyz;
    return length(max(q, vec3(0.0))) + min(max(q.x, max(q.y, q.z)), 0.0);
}
vec3 krs_box_normal(vec3 p, vec4 c, vec4 h, vec4 ax, vec4 ay, vec4 az) {
    vec3 l = krs_box_local(p, c, ax, ay, az);
    vec3 s = vec3(l.x < 0.0 ? -1.0 : 1.0, l.y < 0.0 ? -1.0 : 1.0, l.z < 0.0 ? -1.0 : 1.0);
    vec3 q = abs(l) - h.xyz;
    vec3 o = max(q, vec3(0.0));
    float ol = length(o);
    bool xl = q.x >= q.y && q.x >= q.z;
    bool yl = !xl && q.y >= q.z;
    vec3 face = vec3(xl ? 1.0 : 0.0, yl ? 1.0 : 0.0, (xl || yl) ? 0.0 : 1.0);
    vec3 g = (ol > 0.0 ? o / ol : face) * s;
    return c.w != 0.0 ? ax.xyz * g.x + ay.xyz * g.y + az.xyz * g.z : g;
}
)";
    std::array<float, 20> glsl_parameters() const
    {
        return {
                center_.x, center_.y, center_.z, oriented_ ? 1.0f : 0.0f,
                half_extents_.x, half_extents_.y, half_extents_.z, 0.0f,
                axes_[0].x, axes_[0].y, axes_[0].z, 0.0f,
                axes_[1].x, axes_[1].y, axes_[1].z, 0.0f,
                axes_[2].x, axes_[2].y, axes_[2].z, 0.0f};
    }

private:
    static vec3f checked_extents(const vec3f& h)
    {
        require_magnitude("box.half_extents", h);
        if (h.x < 0 || h.y < 0 || h.z < 0)
            throw invalid_parameter("box.half_extents", "must be >= 0 in every component", detail::to_text(h));
        return h;
    }

    template <class T>
    vec3<T> to_local(const vec3<T>& p) const
    {
        const vec3<T> d = p - vec3<T>(center_);
        if (!oriented_) return d;
        return {dot(d, vec3<T>(axes_[0])), dot(d, vec3<T>(axes_[1])), dot(d, vec3<T>(axes_[2]))};
    }
    template <class T>
    vec3<T> to_world(const vec3<T>& v) const
    {
        if (!oriented_) return v;
        return vec3<T>(axes_[0]) * v.x + vec3<T>(axes_[1]) * v.y + vec3<T>(axes_[2]) * v.z;
    }

    vec3f center_{};
    vec3f half_extents_{};
    vec3f axes_[3] = {{1, 0, 0}, {0, 1, 0}, {0, 0, 1}};
    bool oriented_ = false; // uniform over lanes: the axis-aligned box skips the rotation
};

} // namespace krs

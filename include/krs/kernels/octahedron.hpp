#pragma once
// Octahedron kernel: the regular octahedron |x| + |y| + |z| <= size about `center` (vertices at
// size along each axis; krs::placed turns or moves it).
//
// The field is exact (1-Lipschitz, zero on the surface). Fold p into the first octant (q = |p -
// center|): flipping the signs of the nearest point's coordinates to match q never moves it
// farther, so the nearest point of the solid is that of its first-octant part
// K = {t >= 0, t_x + t_y + t_z <= s}. Inside, the nearest face of the octahedron is the one of
// normal (1, 1, 1) / sqrt(3) (the largest n . q of the eight), at depth (s - sum q) / sqrt(3).
// Outside (sum q > s), the constraint sum t <= s is active at the nearest point (else it would be
// q itself), so that point is q's projection onto the triangle {t >= 0, sum t = s}, which is
// t = max(q - tau, 0) with tau fixed by sum t = s: with q's coordinates sorted u1 >= u2 >= u3,
// tau = (u1 + ... + uk - s) / k for the largest k whose uk > tau (the usual projection onto a
// simplex). Then q - t = min(q, tau) per coordinate and the distance is |min(q, tau)|. tau > 0
// whenever sum q > s, and k = 3 gives (sum q - s) / sqrt(3), the face's plane distance, so the two
// sides meet at zero on the faces.
//
// size > 0; center and size obey the magnitude policy.

#include "krs/core/bounds.hpp"
#include "krs/core/validate.hpp"

#include <array>
#include <string_view>

namespace krs {

class octahedron {
public:
    octahedron() : octahedron(vec3f{0, 0, 0}, 1.0f) {}
    octahedron(const vec3f& center, float size)
        : center_(require_magnitude("octahedron.center", center)),
          size_(require_positive_length("octahedron.size", size))
    {
    }

    const vec3f& center() const { return center_; }
    float size() const { return size_; }

    // The same octahedron through the constructor's checks.
    octahedron checked() const { return octahedron(center_, size_); }

    template <class T>
    T distance(const vec3<T>& p) const
    {
        const vec3<T> q = abs(p - vec3<T>(center_));
        const T s(size_);
        const T sum = q.x + q.y + q.z;
        const T inside = (sum - s) * T(inverse_sqrt3);
        const T tau = projection_shift(q, sum, s);
        const T ox = min(q.x, tau), oy = min(q.y, tau), oz = min(q.z, tau);
        return select(sum > s, sqrt(ox * ox + oy * oy + oz * oz), inside);
    }

    // Gradient: outside, from the nearest surface point toward p (min(q, tau) normalized);
    // inside, the nearest face's normal; both with the octant's signs restored (+ on a plane).
    template <class T>
    vec3<T> normal(const vec3<T>& p) const
    {
        const vec3<T> local = p - vec3<T>(center_);
        const vec3<T> q = abs(local);
        const T s(size_);
        const T sum = q.x + q.y + q.z;
        const T tau = projection_shift(q, sum, s);
        const vec3<T> offset{min(q.x, tau), min(q.y, tau), min(q.z, tau)};
        const T ol = length(offset);
        const auto outside = sum > s && ol > T(0);
        const T face(inverse_sqrt3);
        const vec3<T> g = select(outside, offset / select(outside, ol, T(1)), vec3<T>(face, face, face));
        return {select(local.x < T(0), -g.x, g.x), select(local.y < T(0), -g.y, g.y),
                select(local.z < T(0), -g.z, g.z)};
    }

    bounding_sphere bound() const { return bound_around(vec3d(center_), double(size_)); }
    // Exact: the vertices reach center +- size along each axis.
    bounding_box bound_box() const
    {
        const vec3d c(center_), e{size_, size_, size_};
        return box_around(c - e, c + e);
    }

    // The colour a Shadertoy program and its reference shade this kind with where the caller
    // gives no palette (linear RGB; a pale crystal).
    static constexpr vec3f default_albedo{0.60f, 0.66f, 0.72f};
    // GLSL: the same distance and normal; one vec4 (center, size).
    static constexpr std::string_view glsl_name = "krs_octahedron";
    static constexpr std::string_view glsl_source = R"(float krs_octahedron_shift(vec3 q, float sum, float s) {
    float u1 = max(q.x, max(q.y, q.z));
    float u3 = min(q.x, min(q.y, q.z));
    float u2 = max(min(q.x, q.y), min(max(q.x, q.y), q.z));
    float t3 = (sum - s) / 3.0;
    float t2 = (u1 + u2 - s) * 0.5;
    return u3 > t3 ? t3 : (u2 > t2 ? t2 : u1 - s);
}
float krs_octahedron_distance(vec3 p, vec4 o) {
    vec3 q = abs(p - o.xyz);
    float sum = q.x + q.y + q.z;
    float tau = krs_octahedron_shift(q, sum, o.w);
    return sum > o.w ? length(min(q, vec3(tau))) : (sum - o.w) * 0.57735026918962576;
}
vec3 krs_octahedron_normal(vec3 p, vec4 o) {
    vec3 l = p - o.xyz;
    vec3 q = abs(l);
    float sum = q.x + q.y + q.z;
    vec3 offset = min(q, vec3(krs_octahedron_shift(q, sum, o.w)));
    float ol = length(offset);
    vec3 g = sum > o.w && ol > 0.0 ? offset / ol : vec3(0.57735026918962576);
    return vec3(l.x < 0.0 ? -g.x : g.x, l.y < 0.0 ? -g.y : g.y, l.z < 0.0 ? -g.z : g.z);
}
)";
    std::array<float, 4> glsl_parameters() const { return {center_.x, center_.y, center_.z, size_}; }

private:
    static constexpr float inverse_sqrt3 = 0.57735026918962576f;

    // tau of the projection onto the simplex {t >= 0, sum t = s} (the header's proof): from the
    // sorted coordinates, the k = 3, 2 or 1 candidate that keeps every kept coordinate above it.
    template <class T>
    static T projection_shift(const vec3<T>& q, const T& sum, const T& s)
    {
        const T u1 = max(q.x, max(q.y, q.z));
        const T u3 = min(q.x, min(q.y, q.z));
        const T u2 = max(min(q.x, q.y), min(max(q.x, q.y), q.z)); // the median
        const T t3 = (sum - s) / T(3);
        const T t2 = (u1 + u2 - s) * T(0.5f);
        return select(u3 > t3, t3, select(u2 > t2, t2, u1 - s));
    }

    vec3f center_{};
    float size_ = 1.0f;
};

} // namespace krs

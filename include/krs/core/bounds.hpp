#pragma once
// Bounding spheres: what every kernel and field reports so tracers, tile prepasses, expansion
// exports and tests can tell where the geometry is. An unbounded kernel (a half-space) reports an
// infinite radius.

#include "krs/core/vec3.hpp"

#include <limits>

namespace krs {

struct bounding_sphere {
    vec3f center{};
    float radius = 0.0f;

    static bounding_sphere unbounded() { return {{0, 0, 0}, std::numeric_limits<float>::infinity()}; }
    bool is_bounded() const { return radius < std::numeric_limits<float>::infinity(); }
};

// Smallest sphere of the form "around a's or b's center or between them" holding both: exact for
// two spheres, which is all the enclosing step of an expansion needs.
inline bounding_sphere enclose(const bounding_sphere& a, const bounding_sphere& b)
{
    if (!a.is_bounded() || !b.is_bounded()) return bounding_sphere::unbounded();
    const vec3d ca(a.center), cb(b.center);
    const double dist = length(cb - ca);
    if (dist + b.radius <= a.radius) return a;
    if (dist + a.radius <= b.radius) return b;
    const double r = 0.5 * (dist + a.radius + b.radius);
    const vec3d c = ca + (cb - ca) * ((r - a.radius) / dist);
    // Round the radius up by a few ulps so float storage never shrinks the sphere.
    return {vec3f{float(c.x), float(c.y), float(c.z)}, float(r) * (1.0f + 4e-7f) + 1e-30f};
}

} // namespace krs

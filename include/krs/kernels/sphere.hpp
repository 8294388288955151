#pragma once
// Sphere kernel: the solid ball |p - center| <= radius.
//
// Its signed distance |p - c| - r is exact (1-Lipschitz, zero on the surface), which makes it the
// kernel of choice for coral, rock and leaves (paper section 7.1). Radius 0 is allowed: a point.

#include "krs/core/bounds.hpp"
#include "krs/core/validate.hpp"

namespace krs {

struct sphere {
    vec3f center{};
    float radius = 0.0f;

    sphere() = default;
    sphere(const vec3f& center_, float radius_)
        : center(require_finite("sphere.center", center_)), radius(require_non_negative("sphere.radius", radius_))
    {
    }

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
};

} // namespace krs

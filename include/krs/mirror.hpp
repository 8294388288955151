#pragma once
// Mirror: the reflection plane of one KRS level, m . x = c with |m| = 1 (paper section 3).
//
// Because |m| = 1, e = m . x - c is the signed distance of x to the plane, and the reflection is
//     R x = x - 2 (m . x - c) m          (an isometry, Lipschitz constant 1),
//     M w = w - 2 (m . w) m              (the same for directions).
// Algorithm 1 reflects a point only when it lies on the positive side (e > 0). Written as
//     fold(x) = x - 2 max(e, 0) m
// that choice needs no branch and no select: for e <= 0 the correction is exactly zero, so scalar
// and packet code share one line and the result is bit-identical to the branchy form.

#include "krs/core/validate.hpp"

namespace krs {

struct mirror {
    vec3f normal{0, 0, 1};
    float offset = 0.0f;

    mirror() = default;
    // The plane normal . x = offset; the normal is normalized, and a zero or non-finite one is
    // rejected (it would make every reflection NaN).
    mirror(const vec3f& normal_, float offset_)
        : normal(require_direction("mirror.normal", normal_)), offset(require_finite("mirror.offset", offset_))
    {
    }
    // The plane through `point` with the given normal.
    static mirror through(const vec3f& point, const vec3f& normal_)
    {
        require_finite("mirror.point", point);
        const vec3f n = require_direction("mirror.normal", normal_);
        return mirror(n, float(dot(vec3d(n), vec3d(point))));
    }

    template <class T>
    T signed_distance(const vec3<T>& p) const
    {
        return dot(vec3<T>(normal), p) - T(offset);
    }
    // R x, unconditionally.
    template <class T>
    vec3<T> reflect(const vec3<T>& p) const
    {
        const vec3<T> m(normal);
        return p - m * (T(2) * signed_distance(p));
    }
    // Algorithm 1's step: reflect only from the positive side.
    template <class T>
    vec3<T> fold(const vec3<T>& p) const
    {
        const vec3<T> m(normal);
        return p - m * (T(2) * max(signed_distance(p), T(0)));
    }
    // M w: reflection of a direction (normals, light and view vectors; section 6.1).
    template <class T>
    vec3<T> reflect_direction(const vec3<T>& w) const
    {
        return krs::reflect_direction(w, vec3<T>(normal));
    }
};

} // namespace krs

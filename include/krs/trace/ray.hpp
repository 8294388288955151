#pragma once
// Rays: an origin and a unit direction, over any lane type (a packet of rays is one ray<batch>).
// Sphere tracing advances t by the field's distance, which is a length only along a unit
// direction, so make_ray normalizes; a zero or non-finite direction yields a ray the tracer marks
// invalid (it reports a miss with the `invalid` flag, never NaN).

#include "krs/core/vec3.hpp"

namespace krs {

template <class T>
struct ray {
    vec3<T> origin{};
    vec3<T> direction{0, 0, 1}; // unit length
};

template <class T>
inline ray<T> make_ray(const vec3<T>& origin, const vec3<T>& direction)
{
    return {origin, normalize(direction)};
}

template <class T>
inline vec3<T> point_at(const ray<T>& r, const T& t)
{
    return r.origin + r.direction * t;
}

} // namespace krs

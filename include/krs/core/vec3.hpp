#pragma once
// vec3<T>: the hot path's 3-vector over any lane type.
//
// GLM's geometric functions static-assert on xsimd batches (glm::vec<3, batch> is storage only),
// so the distance code uses this small struct instead. The names mirror GLSL (`dot`, `length`,
// `normalize`, `cross`) so a C++ body and its emitted GLSL read alike. `vec3f`/`vec3d` are the
// scalar aliases; `vec3fP` is a packet of vectors in structure-of-arrays form (one batch per axis).

#include "krs/core/lanes.hpp"

namespace krs {

template <class T>
struct vec3 {
    T x{}, y{}, z{};

    constexpr vec3() = default;
    constexpr vec3(T x_, T y_, T z_) : x(x_), y(y_), z(z_) {}
    // Broadcast a scalar vector into every lane (or convert float <-> double, keeping the rounding:
    // convert_float in lanes.hpp).
    template <class U>
        requires(!std::same_as<U, T> && std::floating_point<U>)
    explicit constexpr vec3(const vec3<U>& v)
        : x(T(convert_float<scalar_t<T>>(v.x))), y(T(convert_float<scalar_t<T>>(v.y))),
          z(T(convert_float<scalar_t<T>>(v.z)))
    {
    }

    friend vec3 operator+(const vec3& a, const vec3& b) { return {a.x + b.x, a.y + b.y, a.z + b.z}; }
    friend vec3 operator-(const vec3& a, const vec3& b) { return {a.x - b.x, a.y - b.y, a.z - b.z}; }
    friend vec3 operator-(const vec3& a) { return {-a.x, -a.y, -a.z}; }
    friend vec3 operator*(const vec3& a, const T& s) { return {a.x * s, a.y * s, a.z * s}; }
    friend vec3 operator*(const T& s, const vec3& a) { return {a.x * s, a.y * s, a.z * s}; }
    friend vec3 operator/(const vec3& a, const T& s) { return {a.x / s, a.y / s, a.z / s}; }
    vec3& operator+=(const vec3& b) { return *this = *this + b; }
    vec3& operator-=(const vec3& b) { return *this = *this - b; }
    vec3& operator*=(const T& s) { return *this = *this * s; }
};

using vec3f = vec3<float>;
using vec3d = vec3<double>;
using vec3fP = vec3<packet_f>;
using vec3dP = vec3<packet_d>;

template <class T>
inline T dot(const vec3<T>& a, const vec3<T>& b)
{
    return a.x * b.x + a.y * b.y + a.z * b.z;
}
// n . p - c, the value of the plane n . x = c at p, summed from the constant outward: where the
// compiler may fuse multiply-adds (GCC's default, -ffp-contract=fast) it makes three fused
// operations of it where dot(n, p) - c takes four. A KRS walk evaluates one or two per level.
template <class T>
inline T plane_value(const vec3<T>& n, const vec3<T>& p, const T& c)
{
    return ((n.x * p.x - c) + n.y * p.y) + n.z * p.z;
}
template <class T>
inline vec3<T> cross(const vec3<T>& a, const vec3<T>& b)
{
    return {a.y * b.z - a.z * b.y, a.z * b.x - a.x * b.z, a.x * b.y - a.y * b.x};
}
template <class T>
inline T length_squared(const vec3<T>& a)
{
    return dot(a, a);
}
template <class T>
inline T length(const vec3<T>& a)
{
    return sqrt(dot(a, a));
}
template <class T>
inline T distance(const vec3<T>& a, const vec3<T>& b)
{
    return length(a - b);
}
// Unit vector along a. A zero vector gives NaN: callers that can meet one validate first.
template <class T>
inline vec3<T> normalize(const vec3<T>& a)
{
    return a / length(a);
}
template <class T>
inline vec3<T> min(const vec3<T>& a, const vec3<T>& b)
{
    return {min(a.x, b.x), min(a.y, b.y), min(a.z, b.z)};
}
template <class T>
inline vec3<T> max(const vec3<T>& a, const vec3<T>& b)
{
    return {max(a.x, b.x), max(a.y, b.y), max(a.z, b.z)};
}
template <class T>
inline vec3<T> abs(const vec3<T>& a)
{
    return {abs(a.x), abs(a.y), abs(a.z)};
}
template <class T>
inline vec3<T> select(const mask_t<T>& m, const vec3<T>& a, const vec3<T>& b)
{
    return {select(m, a.x, b.x), select(m, a.y, b.y), select(m, a.z, b.z)};
}
template <class T>
inline mask_t<T> is_finite(const vec3<T>& a)
{
    return is_finite(a.x) && is_finite(a.y) && is_finite(a.z);
}
// GLSL's mix(vec3, vec3, float): a + (b - a) * t per axis, t not clamped (lanes.hpp's mix for
// one lane value). t = 0 gives a exactly (for finite b).
template <class T>
inline vec3<T> mix(const vec3<T>& a, const vec3<T>& b, const T& t)
{
    return a + (b - a) * t;
}
// Reflection of a direction on a plane with unit normal m (the paper's M_i operator).
template <class T>
inline vec3<T> reflect_direction(const vec3<T>& w, const vec3<T>& m)
{
    return w - m * (T(2) * dot(m, w));
}

// A fixed unit vector perpendicular to the unit vector n, from the coordinate axis x (or y when n
// leans toward x, so the projection never cancels): what a kernel of revolution (torus, cylinder)
// uses for its normal on the axis, where every direction across is as near, and as uv's origin.
inline vec3<double> unit_across(const vec3<double>& n)
{
    const vec3<double> helper = std::abs(n.x) < 0.6 ? vec3<double>{1, 0, 0} : vec3<double>{0, 1, 0};
    return normalize(helper - n * dot(helper, n));
}

// Lane i of a vector of lanes, as a scalar vector.
template <class T>
inline vec3<scalar_t<T>> lane_at(const vec3<T>& v, std::size_t i)
{
    return {lane_at(v.x, i), lane_at(v.y, i), lane_at(v.z, i)};
}

} // namespace krs

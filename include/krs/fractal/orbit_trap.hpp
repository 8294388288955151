#pragma once
// Orbit traps: how close a fractal's orbit comes to a shape, for colouring.
//
// Iterating a fold program from a point x gives its *orbit* p_0 = x, p_1 = program(p_0), ...
// (krs/fractal/kifs_colour.hpp walks it). An orbit trap is a shape T; the trap value of x is
// min_i dist(p_i, T), the closest the orbit comes to T. Points whose orbits pass near T share a
// colour, which paints the fractal's self-similar structure the way Fragmentarium's `orbitTrap`
// and Mandelbulber's orbit-trap colouring do. The shapes are the usual four:
//
//   point(c)          |p - c|
//   plane(n, c)       |n . p - c|                 (n unit: the distance to the plane n . p = c)
//   line(a, d)        |(p - a) - d ((p - a) . d)| (d unit: the distance to the axis through a)
//   shell(c, r)       ||p - c| - r|               (the sphere shell of radius r about c)
//
// Fragmentarium's per-coordinate trap abs(z.xyz) is three planes through the origin. Each is the
// exact Euclidean distance to its shape, so a point on the shape traps 0; the value is measured
// on the orbit point as the program leaves it (not divided by the scale so far), as both programs
// do. The C++ below writes every sum in the order the GLSL does, so the two agree to the few ulps
// of GLSL's `length`.

#include "krs/core/validate.hpp"

#include <array>
#include <string_view>

namespace krs {

enum class orbit_trap_kind { point = 0, plane = 1, line = 2, shell = 3 };

inline std::string_view orbit_trap_kind_name(orbit_trap_kind k)
{
    switch (k) {
    case orbit_trap_kind::point: return "point";
    case orbit_trap_kind::plane: return "plane";
    case orbit_trap_kind::line: return "line";
    default: return "shell";
    }
}

class orbit_trap {
public:
    // The origin as a point trap.
    orbit_trap() = default;

    static orbit_trap point(const vec3f& center)
    {
        return {orbit_trap_kind::point, require_magnitude("orbit_trap.center", center), 0.0f, {0, 0, 0}};
    }
    // The plane normal . p = offset (normal made unit).
    static orbit_trap plane(const vec3f& normal, float offset)
    {
        return {orbit_trap_kind::plane, require_direction("orbit_trap.normal", normal),
                require_magnitude("orbit_trap.offset", offset), {0, 0, 0}};
    }
    // The line through `through` along `direction` (made unit).
    static orbit_trap line(const vec3f& through, const vec3f& direction)
    {
        const vec3f a = require_magnitude("orbit_trap.through", through);
        return {orbit_trap_kind::line, a, 0.0f, require_direction("orbit_trap.direction", direction)};
    }
    // The sphere of radius `radius` about `center` (radius 0 is the point trap).
    static orbit_trap shell(const vec3f& center, float radius)
    {
        const vec3f c = require_magnitude("orbit_trap.center", center);
        return {orbit_trap_kind::shell, c, require_length("orbit_trap.radius", radius), {0, 0, 0}};
    }

    orbit_trap_kind kind() const { return kind_; }

    // The distance from p to the trap's shape (see the table above).
    template <class T>
    T distance(const vec3<T>& p) const
    {
        if (kind_ == orbit_trap_kind::plane)
            return abs(((T(a_.x) * p.x + T(a_.y) * p.y) + T(a_.z) * p.z) - T(w_));
        const vec3<T> q = p - vec3<T>(a_);
        if (kind_ == orbit_trap_kind::line) {
            const T t = (T(d_.x) * q.x + T(d_.y) * q.y) + T(d_.z) * q.z;
            return length(q - vec3<T>(d_) * t);
        }
        const T l = length(q);
        return kind_ == orbit_trap_kind::shell ? abs(l - T(w_)) : l;
    }

    // GLSL (krs/glsl/emitter.hpp): two vec4s, (center | normal | through, offset | radius) and
    // (direction, kind), the kind as 0 point, 1 plane, 2 line, 3 shell.
    static constexpr std::string_view glsl_name = "krs_orbit_trap";
    static constexpr std::string_view glsl_source = R"(float krs_orbit_trap_distance(vec3 p, vec4 a, vec4 b) {
    if (b.w == 1.0) return abs(((a.x * p.x + a.y * p.y) + a.z * p.z) - a.w);
    vec3 q = p - a.xyz;
    if (b.w == 2.0) {
        float t = (b.x * q.x + b.y * q.y) + b.z * q.z;
        return length(q - b.xyz * t);
    }
    float l = length(q);
    return b.w == 3.0 ? abs(l - a.w) : l;
}
)";
    std::array<float, 8> glsl_parameters() const
    {
        return {a_.x, a_.y, a_.z, w_, d_.x, d_.y, d_.z, float(int(kind_))};
    }

private:
    orbit_trap(orbit_trap_kind kind, const vec3f& a, float w, const vec3f& d) : kind_(kind), a_(a), w_(w), d_(d) {}

    orbit_trap_kind kind_ = orbit_trap_kind::point;
    vec3f a_{};     // point / shell center, plane normal, a point of the line
    float w_ = 0;   // plane offset, shell radius
    vec3f d_{};     // line direction
};

} // namespace krs

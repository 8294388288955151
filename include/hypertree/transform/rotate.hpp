#pragma once
// Rotation about an axis through the origin: orientates a fractal subpart (paper section 3.1).
// The angle (radians; definition files use degrees) is per level and randomizable; the axis is
// fixed per transform.

#include "hypertree/transform/maps.hpp"
#include "hypertree/transform/parameter.hpp"

#include <cmath>

namespace hypertree {

struct rotate {
    vec3d axis{0, 1, 0}; // unit after construction
    parameter angle;     // radians, counter-clockwise looking down the axis

    static constexpr bool is_affine = true;
    static constexpr const char* keyword = "ROTATE";

    rotate() = default;
    rotate(const vec3d& axis_, parameter angle_) : axis(axis_), angle(angle_)
    {
        axis = krs::require_direction("rotate.axis", axis_);
        validate();
    }

    void validate() const { angle.validate("rotate.angle"); }
    rotate draw(random_stream& random) const
    {
        rotate r = *this;
        r.angle = angle.draw(random);
        return r;
    }
    // Rodrigues' formula: R = cos a I + sin a [k]x + (1 - cos a) k k^T.
    affine_map map_at(int level) const
    {
        const double a = angle.at(level), c = std::cos(a), s = std::sin(a), v = 1.0 - c;
        const double x = axis.x, y = axis.y, z = axis.z;
        affine_map r;
        r.m = {c + x * x * v,     x * y * v - z * s, x * z * v + y * s, //
               y * x * v + z * s, c + y * y * v,     y * z * v - x * s, //
               z * x * v - y * s, z * y * v + x * s, c + z * z * v};
        return r;
    }
};

} // namespace hypertree

#pragma once
// Scaling: sizes a fractal subpart (paper section 3.1); per axis, per level, randomizable. The
// downsizing scalings are what make a pipeline with shears a contraction.

#include "hypertree/transform/maps.hpp"
#include "hypertree/transform/parameter.hpp"

namespace hypertree {

struct scale {
    parameter x{1}, y{1}, z{1};

    static constexpr bool is_affine = true;
    static constexpr const char* keyword = "SCALE";

    scale() = default;
    explicit scale(parameter uniform) : x(uniform), y(uniform), z(uniform) { validate(); }
    scale(parameter x_, parameter y_, parameter z_) : x(x_), y(y_), z(z_) { validate(); }

    void validate() const { detail::validate_axes(*this, "scale"); }
    scale draw(random_stream& random) const { return detail::drawn_axes(*this, random); }
    affine_map map_at(int level) const
    {
        affine_map a;
        a.m = {x.at(level), 0, 0, 0, y.at(level), 0, 0, 0, z.at(level)};
        return a;
    }
};

} // namespace hypertree

#pragma once
// Translation: positions a fractal subpart (paper section 3.1). Per-level and randomizable offsets.

#include "hypertree/transform/maps.hpp"
#include "hypertree/transform/parameter.hpp"

namespace hypertree {

struct translate {
    parameter x, y, z;

    static constexpr bool is_affine = true;
    static constexpr const char* keyword = "TRANSLATE";

    translate() = default;
    translate(parameter x_, parameter y_, parameter z_) : x(x_), y(y_), z(z_) { validate(); }

    void validate() const { detail::validate_axes(*this, "translate"); }
    translate draw(random_stream& random) const { return detail::drawn_axes(*this, random); }
    affine_map map_at(int level) const
    {
        affine_map a;
        a.t = {x.at(level), y.at(level), z.at(level)};
        return a;
    }
};

} // namespace hypertree

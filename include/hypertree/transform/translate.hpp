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

    void validate() const
    {
        x.validate("translate.x");
        y.validate("translate.y");
        z.validate("translate.z");
    }
    translate draw(random_stream& random) const
    {
        translate t;
        t.x = x.draw(random), t.y = y.draw(random), t.z = z.draw(random);
        return t;
    }
    affine_map map_at(int level) const
    {
        affine_map a;
        a.t = {x.at(level), y.at(level), z.at(level)};
        return a;
    }
};

} // namespace hypertree

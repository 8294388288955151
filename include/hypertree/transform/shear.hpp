#pragma once
// Nonlinear shear (paper section 3.1, figure 1): bends a fractal subpart. The generator's relative
// height h along `axis` (its coordinate over `height`) displaces it by dmax_i * |h|^e along the
// two other axes (`first` and `second` are those in x, y, z order: for axis y, x then z). The
// maximum displacements and the exponent are per level and randomizable; the exponent must be
// >= 1 so that the map stays Lipschitz (h^e with e < 1 has an unbounded slope at h = 0). Shears
// magnify, so pipelines pair them with downsizing scalings (see ifs.hpp's contraction check).

#include "hypertree/transform/maps.hpp"
#include "hypertree/transform/parameter.hpp"

#include <string>

namespace hypertree {

struct shear {
    int axis = 1; // 0 = x, 1 = y, 2 = z
    parameter first, second;
    parameter exponent{2};
    double height = 1; // the height where the displacement reaches dmax

    static constexpr bool is_affine = false;
    static constexpr const char* keyword = "SHEAR";

    shear() = default;
    shear(int axis_, parameter first_, parameter second_, parameter exponent_, double height_ = 1)
        : axis(axis_), first(first_), second(second_), exponent(exponent_), height(height_)
    {
        validate();
    }

    void validate() const
    {
        if (axis < 0 || axis > 2) throw krs::invalid_parameter("shear.axis", "must be 0 (x), 1 (y) or 2 (z)", std::to_string(axis));
        first.validate("shear.first");
        second.validate("shear.second");
        exponent.validate("shear.exponent");
        for (int l = 0; l < distinct_levels; ++l)
            if (!(exponent.mean[l] - exponent.spread[l] >= 1.0))
                throw krs::invalid_parameter("shear.exponent", "must be >= 1 at every level, including its random range",
                                             krs::detail::to_text(exponent.mean[l] - exponent.spread[l]));
        krs::require_positive("shear.height", height);
    }
    shear draw(random_stream& random) const
    {
        shear s = *this;
        s.first = first.draw(random), s.second = second.draw(random), s.exponent = exponent.draw(random);
        return s;
    }
    shear_map map_at(int level) const
    {
        shear_map m;
        m.axis = axis;
        m.first = axis == 0 ? 1 : 0;
        m.second = axis == 2 ? 1 : 2;
        m.dmax_first = first.at(level), m.dmax_second = second.at(level);
        m.set_exponent(exponent.at(level));
        m.inverse_height = 1.0 / height;
        return m;
    }
};

} // namespace hypertree

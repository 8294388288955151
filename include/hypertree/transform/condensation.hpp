#pragma once
// Condensation (paper section 3.3): the resetting transformation that maps any generator into the
// stem volume, limiting the fractal depth and making the trunk that later transformations
// replicate as branches.
//
// `cone` is the CONE of definition files: a truncated cone along a major axis, from `bottom` to
// `top` (positions along the axis) with radii `bottom_radius` and `top_radius`, centred on the
// axis. A condensation samples a point uniformly in the cone's volume (so the stem's density is
// even), then applies its own pipeline (`then`: a shear bends the stem, a rotation tilts one stem
// of a dichotomous fork, a translation moves it). The generator's midpoint is placed there; a line
// generator keeps its orientation.
//

#include "hypertree/random.hpp"
#include "hypertree/transform/pipeline.hpp"

#include <cmath>
#include <numbers>
#include <string>

namespace hypertree {

struct cone {
    int axis = 1; // 0 = x, 1 = y, 2 = z
    double bottom = 0, top = 1;
    double bottom_radius = 0.05, top_radius = 0.02;

    void validate() const
    {
        if (axis < 0 || axis > 2) throw krs::invalid_parameter("cone.axis", "must be 0 (x), 1 (y) or 2 (z)", std::to_string(axis));
        krs::require_magnitude("cone.bottom", bottom);
        krs::require_magnitude("cone.top", top);
        if (!(top > bottom)) throw krs::invalid_parameter("cone.top", "must be above cone.bottom", krs::detail::to_text(top));
        krs::require_length("cone.bottom_radius", bottom_radius);
        krs::require_length("cone.top_radius", top_radius);
        if (!(bottom_radius > 0 || top_radius > 0))
            throw krs::invalid_parameter("cone.bottom_radius", "and cone.top_radius must not both be 0 (the stem would have no volume)", "0");
    }
    double volume() const
    {
        return std::numbers::pi * (top - bottom) *
               (bottom_radius * bottom_radius + bottom_radius * top_radius + top_radius * top_radius) / 3.0;
    }
    vec3d sample(random_stream& random) const
    {
        // Rejection from the bounding cylinder: a height t is kept with probability
        // (r(t) / r_max)^2, the cross-section's share, and a disc point comes from the square
        // around it. Exactly uniform in volume, and cheaper than the inverse-CDF form (a cube root,
        // a sine and a cosine per sample): the generator draws one sample per cycle.
        // The share is taken as (r(t) / r_max)^2, in [0, 1]: as u r_max^2 >= r(t)^2 both sides
        // underflowed to 0 for radii of 1e-200 (0 >= 0 rejected every height: the generator hung).
        const double r0 = bottom_radius, r1 = top_radius, r_max = std::max(r0, r1);
        double t, radius, share;
        do {
            t = random.uniform();
            radius = r0 + (r1 - r0) * t;
            share = radius / r_max;
        } while (random.uniform() >= share * share);
        double a, b;
        do {
            a = random.symmetric(), b = random.symmetric();
        } while (a * a + b * b >= 1.0);
        a *= radius, b *= radius;
        const double along = bottom + (top - bottom) * t;
        if (axis == 0) return {along, a, b};
        if (axis == 1) return {a, along, b};
        return {a, b, along};
    }
};

struct condensation {
    cone stem;
    runtime_pipeline then;

    void validate() const
    {
        stem.validate();
        then.validate();
    }
    condensation draw(random_stream& random) const { return {stem, then.draw(random)}; }
};

} // namespace hypertree

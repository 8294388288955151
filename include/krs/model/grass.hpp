#pragma once
// Grass field builder: a clump of curved blades (torus capsules, level 0) scattered over the
// ground by 2^doublings mirrors (scatter.hpp), with a ground plane at the top level.
//
// Every blade of the clump is its own kernel (so a clump is not symmetric); the clumps are
// reflected copies of each other, turned by the unaligned mirrors so rows never line up.

#include "krs/kernels/plane.hpp"
#include "krs/kernels/torus_capsule.hpp"
#include "krs/model/scatter.hpp"

#include <cmath>
#include <cstdint>
#include <numbers>
#include <string>

namespace krs::model {

using grass_sequence = sequence<torus_capsule, plane>;

struct grass_parameters {
    int blades_per_clump = 8;    // in [1, 64]
    float blade_height = 0.3f;   // > 0, scene units
    float blade_width = 0.008f;  // tube radius, in (0, blade_height / 4]
    float lean = 0.35f;          // how far tips lean out, as a fraction of the height, [0, 1]
    float clump_radius = 0.08f;  // blade roots lie within this radius, > 0
    int doublings = 10;          // clumps = 2^doublings, in [0, 20]
    float spacing = 0.1f;        // gap between clumps, in clump diameters, [0, 4]
    float ground_height = 0.0f;
    std::uint32_t seed = 1;
};

struct grass_field {
    grass_sequence sequence;
    bounding_sphere clump{};   // bound of one clump
    bounding_sphere bound{};   // bound of all clumps
    std::size_t clump_count = 1;
    std::size_t blade_count = 0;
};

inline grass_field build_grass(const grass_parameters& g)
{
    if (g.blades_per_clump < 1 || g.blades_per_clump > 64)
        throw invalid_parameter("grass.blades_per_clump", "must be in [1, 64]", std::to_string(g.blades_per_clump));
    require_positive_length("grass.blade_height", g.blade_height);
    require_positive_length("grass.blade_width", g.blade_width);
    if (g.blade_width > 0.25f * g.blade_height)
        throw invalid_parameter("grass.blade_width", "must be <= blade_height / 4", krs::detail::to_text(g.blade_width));
    detail::require_range("grass.lean", g.lean, 0.0, 1.0);
    require_positive_length("grass.clump_radius", g.clump_radius);
    if (g.doublings < 0 || g.doublings > 20)
        throw invalid_parameter("grass.doublings", "must be in [0, 20]", std::to_string(g.doublings));
    detail::require_range("grass.spacing", g.spacing, 0.0, 4.0);
    require_magnitude("grass.ground_height", g.ground_height);
    // The clump (roots within clump_radius, blades leaning at most blade_height out and rising as
    // much) must obey the magnitude policy (krs/core/validate.hpp) before it is scattered.
    if (!(std::abs(double(g.ground_height)) + double(g.clump_radius) + 3.0 * double(g.blade_height) <= double(max_magnitude)))
        throw invalid_parameter("grass.clump_radius", "|ground_height| + clump_radius + 3 blade_height must be <= 1e9",
                                krs::detail::to_text(g.clump_radius));

    detail::signed_unit_random random(g.seed);
    grass_sequence::builder b;
    const double y0 = g.ground_height;
    double reach = 0;
    for (int k = 0; k < g.blades_per_clump; ++k) {
        // Roots on a sunflower spiral (even cover), each blade leaning outward with jitter.
        const double a = k * 2.39996323 + 0.5 * random();
        const double rr = g.clump_radius * std::sqrt((k + 0.5) / g.blades_per_clump);
        const vec3d root{rr * std::cos(a), y0 - g.blade_width, rr * std::sin(a)};
        const double h = g.blade_height * (0.75 + 0.25 * random());
        const double lean = g.lean * h * (0.6 + 0.4 * random());
        const double la = a + 0.6 * random();
        const vec3d out{std::cos(la), 0.0, std::sin(la)};
        const vec3d tip = root + out * lean + vec3d{0, h, 0};
        // Control point: up from the root, so the blade leaves the ground vertically and arcs over.
        const vec3d control = root + vec3d{0, 0.6 * h, 0} + out * (0.2 * lean);
        // A blade far smaller than float's spacing at its position loses its shape when stored
        // (its root, control and tip coincide, or its chord drops under min_length): name the
        // grass parameter rather than the kernel's.
        const torus_capsule blade = [&] {
            try {
                return torus_capsule(detail::to_float(root), detail::to_float(tip), detail::to_float(control), g.blade_width);
            } catch (const invalid_parameter& e) {
                throw invalid_parameter("grass.blade_height",
                                        std::string("is too small to store as a blade at ground_height (") + e.what() + ")",
                                        krs::detail::to_text(g.blade_height));
            }
        }();
        b.kernel(blade);
        // The footprint must hold the whole blade (its arc may bulge past the tip), or the
        // scattering mirrors would clip it.
        const bounding_sphere bb = blade.bound();
        reach = std::max(reach, std::hypot(double(bb.center.x), double(bb.center.z)) + bb.radius);
    }
    const double radius = reach;
    const scattering s = detail::scatter_by_mirrors(vec3d{0, y0, 0}, radius, g.doublings,
                                                    double(g.spacing) * 2.0 * radius, 12.0, random, "grass.doublings");
    for (const mirror& m : s.mirrors) b.mirror(m);
    b.kernel(plane({0, 1, 0}, g.ground_height));
    grass_field out;
    out.sequence = b.build();
    out.clump = bound_around(vec3d{0, y0 + 0.5 * g.blade_height, 0}, std::hypot(radius, 0.5 * g.blade_height + g.blade_width));
    out.bound = bound_around(vec3d(s.bound.center) + vec3d{0, 0.5 * g.blade_height, 0},
                             std::hypot(double(s.bound.radius), 0.5 * g.blade_height + g.blade_width));
    out.clump_count = s.positions.size();
    out.blade_count = out.clump_count * std::size_t(g.blades_per_clump);
    return out;
}

} // namespace krs::model

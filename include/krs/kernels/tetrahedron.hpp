#pragma once
// Tetrahedron kernel: the regular tetrahedron with vertices (1,1,1), (-1,-1,1), (1,-1,-1),
// (-1,1,-1), the kernel of the Sierpinski tetrahedron (krs/fractal/kifs_presets.hpp).
//
// Its distance is the largest of its four face planes' signed distances n_i . p - 1/sqrt(3),
// n_i = (+-1, +-1, +-1) / sqrt(3) with an odd number of minus signs: a 1-Lipschitz bound, exact
// inside and where the nearest surface point lies inside a face, an underestimate near edges and
// vertices (there the nearest face plane is closer than the solid). It has no parameters, so
// nothing to validate; its zero set is exactly the tetrahedron's surface, so the bounds below,
// the sphere and box through its vertices, hold the whole surface.

#include "krs/core/bounds.hpp"
#include "krs/core/lanes.hpp"
#include "krs/core/vec3.hpp"

#include <array>
#include <numbers>
#include <string_view>

namespace krs {

struct tetrahedron {
    template <class T>
    T distance(const vec3<T>& p) const
    {
        const T a = max(-p.x - p.y - p.z, p.x + p.y - p.z);
        const T b = max(-p.x + p.y + p.z, p.x - p.y + p.z);
        return (max(a, b) - T(1)) * T(std::numbers::inv_sqrt3_v<float>);
    }

    // Gradient of the distance: the unit normal of the face plane that attains the maximum (ties
    // go to the first plane of each pair, then to the pair a, the order distance() compares in).
    template <class T>
    vec3<T> normal(const vec3<T>& p) const
    {
        const T k(std::numbers::inv_sqrt3_v<float>);
        const auto first_of_a = -p.x - p.y - p.z >= p.x + p.y - p.z;
        const auto first_of_b = -p.x + p.y + p.z >= p.x - p.y + p.z;
        const T a = max(-p.x - p.y - p.z, p.x + p.y - p.z);
        const T b = max(-p.x + p.y + p.z, p.x - p.y + p.z);
        const auto pick_a = a >= b;
        const vec3<T> na{select(first_of_a, -k, k), select(first_of_a, -k, k), -k};
        const vec3<T> nb{select(first_of_b, -k, k), select(first_of_b, k, -k), k};
        return {select(pick_a, na.x, nb.x), select(pick_a, na.y, nb.y), select(pick_a, na.z, nb.z)};
    }

    // The vertices lie at distance sqrt(3) from the origin and span [-1, 1] on every axis.
    bounding_sphere bound() const { return bound_around(vec3d(0, 0, 0), std::numbers::sqrt3); }
    bounding_box bound_box() const { return box_around(vec3d(-1, -1, -1), vec3d(1, 1, 1)); }

    // GLSL: the distance only (no parameters; 0.57735026 is inv_sqrt3_v<float>).
    // The colour a Shadertoy program and its reference shade this kind with where the caller
    // gives no palette (linear RGB; stone).
    static constexpr vec3f default_albedo{0.70f, 0.68f, 0.64f};
    static constexpr std::string_view glsl_name = "krs_tetrahedron";
    static constexpr std::string_view glsl_source = R"(float krs_tetrahedron_distance(vec3 p) {
    float a = max(-p.x - p.y - p.z, p.x + p.y - p.z);
    float b = max(-p.x + p.y + p.z, p.x - p.y + p.z);
    return (max(a, b) - 1.0) * 0.57735026;
}
)";
    std::array<float, 0> glsl_parameters() const { return {}; }
};

} // namespace krs

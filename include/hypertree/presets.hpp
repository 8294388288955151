#pragma once
// Four trees shaped like the paper's figure 7 (section 11 gives their workloads), as C++ values
// of the runtime form a definition file produces. They serve the examples, the Table 1 benchmark
// and the tests.
//
// | tree | transformations       | iterations | depth | branch levels | generator            |
// |------|-----------------------|------------|-------|---------------|----------------------|
// | A    | 10 (2 dummy)          | 500 000    | 10    | 1             | point; depths 8+ fruit |
// | B    | 4 (2 dummy)           | 1 000 000  | 8     | 4             | point                |
// | C    | 8                     | 100 000    | 5     | 1             | line of length 0.05  |
// | D    | 7, two condensations  | 1 000 000  | 6     | 3             | point                |
//
// The trees stand on the origin along +y, about one unit tall; the hypervolume is fitted to each
// (no generator escapes it: tested) and `resolution` sets its voxel count per axis.

#include "hypertree/ifs.hpp"

#include <numbers>

namespace hypertree::presets {

namespace detail {
inline constexpr double degrees = std::numbers::pi / 180.0;
inline constexpr double golden_angle = 137.50776405003785;

inline parameter in_radians(parameter p)
{
    for (auto& m : p.mean) m *= degrees;
    for (auto& s : p.spread) s *= degrees;
    return p;
}
// A branch: scaled copy of the whole tree, tilted away from the trunk by `tilt` degrees, turned
// about the trunk by `turn` degrees and raised to `height`.
inline runtime_pipeline branch(parameter size, parameter tilt, double turn, double height)
{
    return runtime_pipeline({scale(size), rotate({0, 0, 1}, in_radians(tilt)), rotate({0, 1, 0}, turn * degrees), translate(0, height, 0)});
}
// The same, bent first: the shear displaces the copy's upper part sideways by up to `bend`.
inline runtime_pipeline bent_branch(parameter size, double bend, double tilt, double turn, double height)
{
    return runtime_pipeline({shear(1, bend, 0, 2), scale(size), rotate({0, 0, 1}, tilt * degrees), rotate({0, 1, 0}, turn * degrees),
                             translate(0, height, 0)});
}
inline hypervolume fitted(const vec3d& lo, const vec3d& hi, int resolution_)
{
    return hypervolume(lo, hi - lo, resolution::cube(resolution_));
}
} // namespace detail

// A: a broad deciduous tree; eight branches in a golden-angle spiral, two dummy transformations
// that only shape deeper levels, fruit at depths 8 and 9.
inline ifs<> tree_a(int resolution_ = 300)
{
    using namespace detail;
    ifs<> t;
    t.name = "A";
    for (int k = 0; k < 8; ++k)
        t.transforms.push_back({branch(parameter::per_level(0.52 - 0.02 * k, 0.5, 0.48), parameter::per_level(48 - 2 * k, 40, 36),
                                       golden_angle * k, 0.28 + 0.055 * k),
                                1.0});
    t.transforms.push_back({branch(0.45, 25, 90, 0.65), 0.6, never, 1});
    t.transforms.push_back({branch(0.4, 60, 210, 0.45), 0.6, never, 1});
    t.condensations = {condensation{cone{1, 0.0, 0.5, 0.035, 0.015}, {}}};
    t.tree_depth = 10;
    t.branch_depth = 1;
    t.iterations = 500000;
    t.volume = fitted({-0.75, -0.01, -0.75}, {0.75, 1.2, 0.75}, resolution_);
    return t;
}

// B: a tall, sparse tree; two forking branches carry four levels of wood, two dummies shorten
// their side shoots (dummy from level 3).
inline ifs<> tree_b(int resolution_ = 300)
{
    using namespace detail;
    ifs<> t;
    t.name = "B";
    t.transforms.push_back({branch(0.68, 28, 0, 0.55), 1.0});
    t.transforms.push_back({branch(0.64, 32, 180, 0.5), 1.0});
    t.transforms.push_back({branch(0.5, 55, 90, 0.35), 0.7, never, 3});
    t.transforms.push_back({branch(0.48, 55, 270, 0.42), 0.7, never, 3});
    t.condensations = {condensation{cone{1, 0.0, 0.55, 0.03, 0.018}, {}}};
    t.tree_depth = 8;
    t.branch_depth = 4;
    t.iterations = 1000000;
    t.volume = fitted({-0.9, -0.01, -0.9}, {0.9, 1.55, 0.9}, resolution_);
    return t;
}

// C: an imaginary bush of short leaf strokes: eight branches, line generators of length 0.05.
inline ifs<> tree_c(int resolution_ = 300)
{
    using namespace detail;
    ifs<> t;
    t.name = "C";
    for (int k = 0; k < 8; ++k)
        t.transforms.push_back({branch(parameter::random(0.5, 0.04), parameter::random(50, 8), 45 * k + 10, 0.2 + 0.06 * k), 1.0});
    t.condensations = {condensation{cone{1, 0.0, 0.45, 0.04, 0.02}, {}}};
    t.tree_depth = 5;
    t.branch_depth = 1;
    t.iterations = 100000;
    t.generator = generator_shape::line({0, -0.025, 0}, {0, 0.025, 0});
    t.volume = fitted({-0.75, -0.03, -0.75}, {0.75, 1.05, 0.75}, resolution_);
    return t;
}

// D: an imaginary forked tree: two sheared cones make a dichotomous stem; seven bent branches.
inline ifs<> tree_d(int resolution_ = 300)
{
    using namespace detail;
    ifs<> t;
    t.name = "D";
    for (int k = 0; k < 7; ++k)
        t.transforms.push_back({bent_branch(parameter::per_level(0.5, 0.46, 0.44), 0.08, 40 + 3 * k, golden_angle * k, 0.3 + 0.07 * k), 1.0});
    t.condensations = {condensation{cone{1, 0.0, 0.5, 0.03, 0.015}, runtime_pipeline({shear(1, 0.12, 0.0, 2, 0.5)})},
                       condensation{cone{1, 0.0, 0.5, 0.03, 0.015}, runtime_pipeline({shear(1, -0.12, 0.03, 2, 0.5)})}};
    t.tree_depth = 6;
    t.branch_depth = 3;
    t.iterations = 1000000;
    t.volume = fitted({-0.8, -0.01, -0.8}, {0.8, 1.3, 0.8}, resolution_);
    return t;
}

} // namespace hypertree::presets

#pragma once
// The small hypertrees the tests share, each defined once so that two tests meaning the same tree
// build the same voxels.

#include "hypertree/ifs.hpp"
#include "hypertree/presets.hpp"

#include <cstdint>
#include <numbers>

namespace krs_test {

using branch_pipeline = hypertree::pipeline<hypertree::scale, hypertree::rotate, hypertree::rotate, hypertree::translate>;

// small_tree: the IFS and noise tests' tree, a stem along y (a cone condensation) and four
// transformations, three tilted branches around it (level-dependent sizes 0.55, 0.5, 0.45) and one
// near-vertical continuation. Small enough (64^3, tens of thousands of iterations) to generate in
// milliseconds, and with first-level parts 0..4 for the tests that count them.
inline hypertree::ifs<branch_pipeline> small_tree(int depth = 6, std::uint64_t iterations = 60000)
{
    using namespace hypertree;
    constexpr double degrees = std::numbers::pi / 180.0;
    ifs<branch_pipeline> t;
    t.name = "small";
    for (int k = 0; k < 3; ++k)
        t.transforms.push_back({branch_pipeline(scale(parameter::per_level(0.55, 0.5, 0.45)), rotate({0, 0, 1}, 35 * degrees),
                                                rotate({0, 1, 0}, (120 * k + 20) * degrees), translate(0, 0.45 + 0.2 * k, 0)),
                                1.0});
    t.transforms.push_back({branch_pipeline(scale(0.6), rotate({0, 0, 1}, 5 * degrees), rotate({0, 1, 0}, 0), translate(0, 0.75, 0)), 1.0});
    t.condensations = {condensation{cone{1, 0.0, 0.6, 0.05, 0.02}, {}}};
    t.tree_depth = depth;
    t.branch_depth = 1;
    t.iterations = iterations;
    t.volume = hypervolume({-1, -0.05, -1}, {2, 2, 2}, resolution::cube(64));
    return t;
}

// small_tree_d: the rendering tests' tree, preset D (presets.hpp) at resolution 40 with 30000
// iterations: a whole tree of the paper's kind, small enough to build and render many times in one
// test case. test_hypertree_render.cpp, test_hypertree_light_sweep.cpp and
// test_hypertree_glsl_gpu.cpp march it.
inline hypertree::ifs<> small_tree_d()
{
    auto t = hypertree::presets::tree_d(40);
    t.iterations = 30000;
    return t;
}

} // namespace krs_test

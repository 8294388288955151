#pragma once
// Scenes shared by the tests: each is built in one place, so two tests that mean the same scene
// trace the same floats, and a change to a scene reaches every test that uses it.

#include "krs/fractal/fold_steps.hpp"
#include "krs/fractal/kifs.hpp"
#include "krs/kernels/plane.hpp"
#include "krs/kernels/sphere.hpp"
#include "krs/kernels/torus_capsule.hpp"
#include "krs/mirror.hpp"
#include "krs/sequence.hpp"

namespace krs_test {

using grove_scene = krs::sequence<krs::sphere, krs::torus_capsule, krs::plane>;
// Trees of curved branches and leaves on a 2 x 2 grid of mirrors, over a ground plane: rays end
// on leaves, on the ground, graze branches, or miss, so lanes finish at very different steps.
// Without the ground the scene is bounded (a small forest).
inline grove_scene grove(bool ground = true)
{
    grove_scene::builder b;
    b.kernel(krs::sphere({0.3f, 1.2f, 0.1f}, 0.25f));
    b.kernel(krs::torus_capsule({0, 0, 0}, {0.3f, 1.0f, 0.1f}, {0.05f, 0.5f, 0.1f}, 0.06f));
    b.mirror(krs::mirror({1, 0, 0.2f}, 0.8f));
    b.mirror(krs::mirror({0.1f, 0, 1}, 0.9f));
    b.kernel(krs::sphere({0, -0.5f, 0}, 0.2f));
    b.mirror(krs::mirror({1, 0, -0.3f}, 2.5f));
    b.mirror(krs::mirror({-0.2f, 0, 1}, 2.6f));
    if (ground) b.kernel(krs::plane({0, 1, 0}, -0.6f));
    return b.build();
}

// A KIFS with every step kind the presets leave out: abs on two axes, a rotation and a
// translation in one program, over a sphere (6 iterations, the kernel at every level).
using spiral_program =
    krs::fold_program<krs::abs_fold<krs::fold_x | krs::fold_z>, krs::rotate_step, krs::translate_step, krs::scale_about>;
using spiral_kifs = krs::kifs<spiral_program, krs::sphere>;
inline spiral_kifs spiral()
{
    return spiral_kifs(spiral_program({}, krs::rotate_step({0.0f, 1.0f, 0.0f}, 0.4f),
                                      krs::translate_step({0.1f, 0.0f, -0.2f}), krs::scale_about(1.5f, {1.0f, 0.5f, 0.0f})),
                       krs::sphere({0.0f, 0.0f, 0.0f}, 0.5f), 6);
}

} // namespace krs_test

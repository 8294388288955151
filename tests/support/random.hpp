#pragma once
// Random sampling shared by the tests: platform-independent (std distributions are not), so a
// failing case reproduces everywhere from its seed.

#include "krs/core/vec3.hpp"

#include <cstdint>
#include <random>

namespace krs_test {

// Uniform in [lo, hi) from the top 53 bits of the engine.
inline double uniform(std::mt19937_64& g, double lo, double hi)
{
    return lo + (hi - lo) * double(g() >> 11) * 0x1.0p-53;
}

// Uniform integer in [lo, hi], from the engine's bits only (the remainder's bias toward small
// values, at most (hi - lo + 1) / 2^64, is far below anything a test sees).
inline std::uint32_t integer(std::mt19937_64& g, std::uint64_t lo, std::uint64_t hi)
{
    return std::uint32_t(lo + g() % (hi - lo + 1));
}

// Uniform in the ball of the given radius (rejection from the cube).
inline krs::vec3d in_ball(std::mt19937_64& g, double radius)
{
    for (;;) {
        const krs::vec3d v{uniform(g, -1, 1), uniform(g, -1, 1), uniform(g, -1, 1)};
        if (krs::length_squared(v) <= 1) return v * radius;
    }
}

// Uniform unit direction (normalized from the ball, avoiding the center's poor precision).
inline krs::vec3d random_direction(std::mt19937_64& g)
{
    for (;;) {
        const krs::vec3d v = in_ball(g, 1);
        const double l = krs::length(v);
        if (l > 0.1) return v / l;
    }
}

} // namespace krs_test

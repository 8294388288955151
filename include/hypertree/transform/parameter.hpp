#pragma once
// A transform parameter: one value per level of execution, each optionally randomized.
//
// Level-dependent self-similarity (paper section 3.4): a value may differ for level 1, level 2,
// and levels 3 and deeper (section 10's pairs and triplets; a pair (a, b) means a for level 1, b
// for the rest). Nondeterministic transformations (section 3.2): each value may be drawn from
// [mean - spread, mean + spread], once per tree before generation starts and then held fixed, so
// the tree does not "break up". `draw` returns the drawn, deterministic parameter.

#include "hypertree/random.hpp"
#include "krs/core/validate.hpp"

#include <array>
#include <string>
#include <string_view>

namespace hypertree {

// Levels 1, 2 and 3-and-deeper have their own values; the generator relies on every level >= 3
// sharing one value (it keeps the part of a pipeline that executes there, figure 2).
inline constexpr int distinct_levels = 3;

inline int level_slot(int level) { return (level < 1 ? 1 : level > distinct_levels ? distinct_levels : level) - 1; }

struct parameter {
    std::array<double, distinct_levels> mean{};
    std::array<double, distinct_levels> spread{}; // half-width of the random range; 0 = fixed

    constexpr parameter() = default;
    constexpr parameter(double value) : mean{value, value, value} {} // NOLINT: a plain number is a fixed parameter

    static constexpr parameter per_level(double level1, double deeper) { return per_level(level1, deeper, deeper); }
    static constexpr parameter per_level(double level1, double level2, double deeper)
    {
        parameter p;
        p.mean = {level1, level2, deeper};
        return p;
    }
    // mean +- spread at every level.
    static constexpr parameter random(double mean, double spread)
    {
        parameter p(mean);
        p.spread = {spread, spread, spread};
        return p;
    }

    double at(int level) const { return mean[level_slot(level)]; }
    bool is_fixed() const { return spread[0] == 0 && spread[1] == 0 && spread[2] == 0; }

    // Values drawn in level order from the stream; a fixed value consumes no random number, so
    // randomizing one parameter does not reshuffle the others' draws.
    parameter draw(random_stream& random) const
    {
        parameter drawn;
        for (int l = 0; l < distinct_levels; ++l)
            drawn.mean[l] = spread[l] == 0 ? mean[l] : mean[l] + spread[l] * random.symmetric();
        return drawn;
    }

    void validate(std::string_view name) const
    {
        for (int l = 0; l < distinct_levels; ++l) {
            const std::string at_level = std::string(name) + "[level " + std::to_string(l + 1) + (l == 2 ? "+]" : "]");
            krs::require_finite(at_level, mean[l]);
            krs::require_non_negative(at_level + ".spread", spread[l]);
        }
    }
};

namespace detail {

// A per-axis transform's parameters x, y, z (scale, translate): checked under the names
// "<transform>.x", ".y" and ".z", and drawn in x, y, z order, which fixes the random numbers
// each takes (so every per-axis transform draws alike).
template <class Axes>
void validate_axes(const Axes& axes, std::string_view transform)
{
    const std::string name(transform);
    axes.x.validate(name + ".x");
    axes.y.validate(name + ".y");
    axes.z.validate(name + ".z");
}
template <class Axes>
Axes drawn_axes(Axes axes, random_stream& random)
{
    axes.x = axes.x.draw(random), axes.y = axes.y.draw(random), axes.z = axes.z.draw(random);
    return axes;
}

} // namespace detail

} // namespace hypertree

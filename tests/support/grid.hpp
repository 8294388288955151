#pragma once
// The peer benchmark's grid for tests: mirrors that double the copies so far alternately along x
// and z, each placed `gap` beyond the copies' reach, so the copies stay separated.

#include "krs/mirror.hpp"

#include <array>

namespace krs_test {

// Adds n axis mirrors to an axis-sequence builder whose level-0 kernels reach `copy_reach` from
// the origin in x and z; returns how far the 2^n copies reach along x and z.
template <class Builder>
std::array<double, 2> add_grid_mirrors(Builder& b, int n, double copy_reach, double gap)
{
    std::array<double, 2> reach{copy_reach, copy_reach};
    for (int i = 0; i < n; ++i) {
        const int a = i % 2;
        const double position = reach[a] + gap;
        b.mirror(krs::axis_mirror(a == 0 ? 0 : 2, float(position)));
        reach[a] = 2 * position + copy_reach;
    }
    return reach;
}

} // namespace krs_test

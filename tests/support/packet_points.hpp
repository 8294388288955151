#pragma once
// A packet of random points and the same points one by one, for the tests that compare a field's
// packet evaluation with its scalar path lane by lane (rule 1: one source for scalar and SIMD).

#include "krs/core/lanes.hpp"
#include "krs/core/vec3.hpp"

#include "random.hpp"

#include <algorithm>
#include <array>
#include <cmath>
#include <cstddef>
#include <random>

namespace krs_test {

struct packet_points {
    krs::vec3<krs::packet_f> packet;
    std::array<krs::vec3f, krs::lane_count<krs::packet_f>> lanes;
};

// Lane i uniform in the box [lo, hi], drawn x, y, z lane after lane.
inline packet_points random_packet(std::mt19937_64& g, const krs::vec3f& lo, const krs::vec3f& hi)
{
    using P = krs::packet_f;
    constexpr std::size_t W = krs::lane_count<P>;
    alignas(64) float x[W], y[W], z[W];
    packet_points r;
    for (std::size_t i = 0; i < W; ++i) {
        x[i] = float(uniform(g, lo.x, hi.x)), y[i] = float(uniform(g, lo.y, hi.y)), z[i] = float(uniform(g, lo.z, hi.z));
        r.lanes[i] = {x[i], y[i], z[i]};
    }
    r.packet = {P::load_aligned(x), P::load_aligned(y), P::load_aligned(z)};
    return r;
}

// Over the packets given to add(): how many lanes of a field's packet distance equal its scalar
// float distance (all, under -ffp-contract=off: the same + - * per lane), and the largest
// |double - float| distance at the same points.
struct scalar_agreement {
    long lanes = 0, equal = 0;
    double worst_double = 0;

    template <class F>
    void add(const F& f, const packet_points& points)
    {
        const krs::packet_f d = f.distance(points.packet);
        for (std::size_t i = 0; i < points.lanes.size(); ++i) {
            const krs::vec3f& p = points.lanes[i];
            ++lanes;
            equal += krs::lane_at(d, i) == f.distance(p);
            worst_double = std::max(worst_double, std::abs(f.distance(krs::vec3d(p)) - double(f.distance(p))));
        }
    }
};

} // namespace krs_test

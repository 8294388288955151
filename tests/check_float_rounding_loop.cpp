// Part of check_float_rounding (see there): the smallest shape found to show the fold at -O2 as
// well as -O3. Whether g++ 12.2 folds (double)(float)x back to x depends on what is inlined where,
// so this loop has its own translation unit: it builds only a torus and a plane from float vectors
// rounded from doubles, and counts directions that are not the float input normalized in double.

#include "krs/kernels/kernels.hpp"

#include "support/float_rounding.hpp"

#include <random>

namespace {

using krs::vec3d;
using krs::vec3f;
using krs_test::direction_of;
using krs_test::through_memory;

int differing = 0;
void count_unless_equal(const vec3f& got, const vec3d& input)
{
    const vec3f expected = direction_of(vec3f{through_memory(input.x), through_memory(input.y), through_memory(input.z)});
    if (got.x != expected.x || got.y != expected.y || got.z != expected.z) ++differing;
}

}  // namespace

int directions_differing_in_a_short_loop()
{
    std::mt19937_64 e{20261201};
    auto u = [&] { return std::uniform_real_distribution<double>(-10, 10)(e); };
    for (int i = 0; i < 2000; ++i) {
        const vec3d c{u(), u(), u()}, a{u(), u(), u()};
        const krs::torus t{vec3f(c), vec3f(a), 1.5f, 0.25f};
        count_unless_equal(t.axis(), a);
        const krs::plane pl = krs::plane::through(vec3f(c), vec3f(a));
        count_unless_equal(pl.normal_direction, a);
    }
    return differing;
}

#pragma once
// The references of check_float_rounding (tests/check_float_rounding.cpp and its loop in
// check_float_rounding_loop.cpp): floats rounded where no optimizer may fold the rounding away.

#include "krs/core/vec3.hpp"

#include <cmath>

namespace krs_test {

// d rounded to float through a volatile float, which the compiler must store and read back.
inline float through_memory(double d)
{
    volatile float f = static_cast<float>(d);
    return f;
}
inline krs::vec3f through_memory(const krs::vec3d& v)
{
    return {through_memory(v.x), through_memory(v.y), through_memory(v.z)};
}

// A direction as the constructors document it (krs/core/validate.hpp): the float input normalized
// in double, rounded once. Out of line, so it is never inlined into the code it checks.
[[gnu::noinline]] inline krs::vec3f direction_of(krs::vec3f v)
{
    const double x = v.x, y = v.y, z = v.z;
    const double length = std::sqrt(x * x + y * y + z * z);
    return {through_memory(x / length), through_memory(y / length), through_memory(z / length)};
}

} // namespace krs_test

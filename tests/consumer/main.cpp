// Compiled against an installed (or add_subdirectory'd) krs: prints a sphere distance and fails
// if it is wrong.
#include "krs/kernels/sphere.hpp"

#include <cmath>
#include <cstdio>

int main()
{
    const krs::sphere ball({1.0f, 2.0f, 3.0f}, 0.5f);
    const float d = ball.distance(krs::vec3f(4.0f, 6.0f, 3.0f)); // |(3, 4, 0)| - 0.5
    std::printf("sphere distance: %g\n", static_cast<double>(d));
    return std::fabs(d - 4.5f) <= 1e-6f ? 0 : 1;
}

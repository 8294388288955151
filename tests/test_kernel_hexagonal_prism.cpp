// Hexagonal prism (krs/kernels/hexagonal_prism.hpp) against a reference built here another way:
// the hexagon as six corners at 2 a / sqrt(3) (angles 0, 60, ... degrees), its 2D distance the
// least segment distance to its six edges signed by the six half-planes, the prism's distance
// from the projection onto the product of hexagon and interval outside and the least face depth
// inside; in double at 10^5 points. Against a dense sampling of the surface (never overestimates,
// zero on it), 1-Lipschitz, packet lanes, normals, bounds (tests/support/kernel_properties.hpp),
// refused parameters. Its GLSL runs on llvmpipe in test_glsl_field_types.cpp.

#include "krs/field.hpp"
#include "krs/kernels/hexagonal_prism.hpp"

#include "support/kernel_properties.hpp"
#include "support/rejects.hpp"
#include "support/random.hpp"

#include <doctest/doctest.h>

#include <algorithm>
#include <array>
#include <cmath>
#include <limits>
#include <numbers>
#include <random>
#include <vector>

static_assert(krs::kernel<krs::hexagonal_prism>);

namespace {

using krs::vec3d;
using krs::vec3f;
using krs_test::uniform;

struct prism_case {
    krs::hexagonal_prism kernel;
    vec3d center;
    double a, h, extent;
    std::array<vec3d, 6> corners; // in the xy plane about the origin
    prism_case(vec3f middle, float apothem, float half_height)
        : kernel(middle, apothem, half_height), center(middle), a(apothem), h(half_height)
    {
        const double r = 2 * a / std::sqrt(3.0);
        for (int i = 0; i < 6; ++i) {
            const double t = i * std::numbers::pi / 3;
            corners[i] = {r * std::cos(t), r * std::sin(t), 0};
        }
        extent = 1.5 * std::hypot(r, h) + 0.1;
    }
    // Signed 2D distance of (x, y) to the hexagon.
    double hexagon(double x, double y) const
    {
        const vec3d q{x, y, 0};
        double d = INFINITY;
        bool inside = true;
        for (int i = 0; i < 6; ++i) {
            const vec3d u = corners[i], v = corners[(i + 1) % 6];
            d = std::min(d, krs_test::segment_distance(q, u, v));
            inside = inside && (v.x - u.x) * (y - u.y) - (v.y - u.y) * (x - u.x) >= 0; // left of each edge
        }
        return inside ? -d : d;
    }
    double reference(const vec3d& p) const
    {
        const vec3d q = p - center;
        const double d2 = hexagon(q.x, q.y), dz = std::abs(q.z) - h;
        if (d2 <= 0 && dz <= 0) return std::max(d2, dz); // the nearer face
        return std::hypot(std::max(d2, 0.0), std::max(dz, 0.0));
    }
    std::vector<vec3d> surface(std::mt19937_64& g, int count) const
    {
        std::vector<vec3d> out;
        while (int(out.size()) < count) {
            if (out.size() % 2 == 0) { // a side face
                const int i = krs_test::integer(g, 0, 5);
                const double t = uniform(g, 0, 1);
                const vec3d e = corners[i] + (corners[(i + 1) % 6] - corners[i]) * t;
                out.push_back(center + e + vec3d{0, 0, uniform(g, -h, h)});
            } else { // a cap: rejection from the corners' box
                const double r = 2 * a / std::sqrt(3.0);
                const double x = uniform(g, -r, r), y = uniform(g, -a, a);
                if (hexagon(x, y) <= 0) out.push_back(center + vec3d{x, y, uniform(g, 0, 1) < 0.5 ? -h : h});
            }
        }
        return out;
    }
};

std::vector<prism_case> cases()
{
    return {prism_case({0, 0, 0}, 0.5f, 0.3f), prism_case({0.2f, -0.1f, 0.3f}, 0.8f, 0.12f),
            prism_case({-0.1f, 0.2f, 0}, 0.25f, 1.0f), prism_case({1000, -999.5f, 1000.25f}, 0.4f, 0.6f)};
}

} // namespace

TEST_CASE("hexagonal_prism: distance, never overestimates, Lipschitz, lanes, normals")
{
    for (const prism_case& c : cases()) krs_test::check_kernel_field_properties(c);
}

TEST_CASE("hexagonal_prism: bound and bound_box hold inside points, and the box is tight")
{
    for (const prism_case& c : cases()) {
        const krs::bounding_box box = c.kernel.bound_box();
        std::vector<vec3d> corners;
        for (const vec3d& v : c.corners) corners.push_back(c.center + v + vec3d{0, 0, c.h});
        const krs::bounding_box sampled = krs_test::check_kernel_bounds(c, corners);
        krs_test::check_box_tight(box, sampled, 1e-5 * (1 + krs::length(c.center)));
    }
}

TEST_CASE("hexagonal_prism: bad parameters are refused by name")
{
    const float nan = std::numeric_limits<float>::quiet_NaN();
    krs_test::rejects([] { krs::hexagonal_prism({0, 0, 0}, 0.0f, 1.0f); }, "hexagonal_prism.apothem");
    krs_test::rejects([] { krs::hexagonal_prism({0, 0, 0}, -1.0f, 1.0f); }, "hexagonal_prism.apothem");
    krs_test::rejects([] { krs::hexagonal_prism({0, 0, 0}, 1.0f, 0.0f); }, "hexagonal_prism.half_height");
    krs_test::rejects([&] { krs::hexagonal_prism({0, 0, 0}, 1.0f, nan); }, "hexagonal_prism.half_height");
    krs_test::rejects([&] { krs::hexagonal_prism({nan, 0, 0}, 1.0f, 1.0f); }, "hexagonal_prism.center");
}

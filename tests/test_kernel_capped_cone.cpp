// Capped cone (krs/kernels/capped_cone.hpp) against a reference built here another way: in a
// frame of its own (Gram-Schmidt from the least aligned coordinate axis), the point's (radial,
// axial) coordinates and the least 3D segment distance to the cross-section's three boundary
// edges (the caps' radii and the slanted side), signed by comparing the radius with the side's
// linear interpolation at that height; in double at 10^5 points. Against a dense sampling of the
// surface (never overestimates, zero on it), 1-Lipschitz, packet lanes, normals, bounds
// (tests/support/kernel_properties.hpp), refused parameters. Its GLSL runs on llvmpipe in
// test_glsl_field_types.cpp.

#include "krs/field.hpp"
#include "krs/kernels/capped_cone.hpp"

#include "support/kernel_properties.hpp"
#include "support/rejects.hpp"
#include "support/random.hpp"

#include <doctest/doctest.h>

#include <algorithm>
#include <cmath>
#include <limits>
#include <numbers>
#include <random>
#include <vector>

static_assert(krs::kernel<krs::capped_cone>);

namespace {

using krs::vec3d;
using krs::vec3f;
using krs_test::uniform;


struct cone_case {
    krs::capped_cone kernel;
    vec3d center, e1, e2, n;
    double h, ra, rb, extent;
    cone_case(vec3f a, vec3f b, float radius_a, float radius_b)
        : kernel(a, b, radius_a, radius_b), center((vec3d(a) + vec3d(b)) * 0.5), n(krs::normalize(vec3d(b) - vec3d(a))),
          h(0.5 * krs::length(vec3d(b) - vec3d(a))), ra(radius_a), rb(radius_b)
    {
        const double ax = std::abs(n.x), ay = std::abs(n.y), az = std::abs(n.z);
        const vec3d helper = az <= ax && az <= ay ? vec3d{0, 0, 1} : (ay <= ax ? vec3d{0, 1, 0} : vec3d{1, 0, 0});
        e1 = krs::normalize(helper - n * krs::dot(helper, n));
        e2 = krs::cross(n, e1);
        extent = 1.5 * std::hypot(h, std::max(ra, rb)) + 0.1;
    }
    double reference(const vec3d& p) const
    {
        const vec3d q = p - center;
        const double rho = std::hypot(krs::dot(q, e1), krs::dot(q, e2)), z = krs::dot(q, n);
        const vec3d at{rho, z, 0};
        const double d = std::min({krs_test::segment_distance(at, {0, -h, 0}, {ra, -h, 0}), krs_test::segment_distance(at, {0, h, 0}, {rb, h, 0}),
                                   krs_test::segment_distance(at, {ra, -h, 0}, {rb, h, 0})});
        const bool inside = std::abs(z) <= h && rho <= ra + (rb - ra) * (z + h) / (2 * h);
        return inside ? -d : d;
    }
    std::vector<vec3d> surface(std::mt19937_64& g, int count) const
    {
        std::vector<vec3d> out;
        const double slant = std::hypot(rb - ra, 2 * h);
        const double side = std::numbers::pi * (ra + rb) * slant, cap_a = std::numbers::pi * ra * ra,
                     cap_b = std::numbers::pi * rb * rb;
        for (int i = 0; i < count; ++i) {
            const double phi = uniform(g, 0, 2 * std::numbers::pi);
            const vec3d around = e1 * std::cos(phi) + e2 * std::sin(phi);
            const double pick = uniform(g, 0, side + cap_a + cap_b);
            if (pick < side) {
                const double t = uniform(g, 0, 1);
                out.push_back(center + around * (ra + (rb - ra) * t) + n * (-h + 2 * h * t));
            } else if (pick < side + cap_a) {
                out.push_back(center + around * (ra * std::sqrt(uniform(g, 0, 1))) - n * h);
            } else {
                out.push_back(center + around * (rb * std::sqrt(uniform(g, 0, 1))) + n * h);
            }
        }
        return out;
    }
};

std::vector<cone_case> cases()
{
    return {cone_case({-0.3f, 0.2f, 0.1f}, {0.5f, -0.4f, 0.7f}, 0.5f, 0.2f),
            cone_case({0, 0, -1}, {0, 0, 1}, 0.6f, 0.0f),                // a pointed cone
            cone_case({0.2f, 0.1f, 0}, {0.1f, 0.3f, 0.2f}, 0.1f, 0.8f),   // widening, short
            cone_case({0.1f, -0.2f, 0.3f}, {0.6f, 0.2f, -0.1f}, 0.3f, 0.3f), // a cylinder
            cone_case({1000, 999.5f, 1001}, {1001, 1000.25f, 1000.5f}, 0.4f, 0.1f)};
}

} // namespace

TEST_CASE("capped_cone: distance, never overestimates, Lipschitz, lanes, normals")
{
    for (const cone_case& c : cases()) krs_test::check_kernel_field_properties(c);
}

TEST_CASE("capped_cone: bound and bound_box hold inside points, and the box is tight")
{
    for (const cone_case& c : cases()) {
        const krs::bounding_box box = c.kernel.bound_box(), sampled = krs_test::check_kernel_bounds(c);
        const double slack = 0.01 * (c.h + std::max(c.ra, c.rb));
        krs_test::check_box_tight(box, sampled, slack);
    }
}

TEST_CASE("capped_cone: bad parameters are refused by name")
{
    const float nan = std::numeric_limits<float>::quiet_NaN();
    krs_test::rejects([] { krs::capped_cone({0, 0, 0}, {0, 0, 1}, 0.0f, 0.0f); }, "capped_cone.radius_b");
    krs_test::rejects([] { krs::capped_cone({0, 0, 0}, {0, 0, 1}, -0.1f, 0.5f); }, "capped_cone.radius_a");
    krs_test::rejects([&] { krs::capped_cone({0, 0, 0}, {0, 0, 1}, 0.5f, nan); }, "capped_cone.radius_b");
    krs_test::rejects([] { krs::capped_cone({1, 2, 3}, {1, 2, 3}, 0.5f, 0.2f); }, "capped_cone.b");
    krs_test::rejects([&] { krs::capped_cone({nan, 0, 0}, {0, 0, 1}, 0.5f, 0.2f); }, "capped_cone.a");
}

TEST_CASE("capped_cone: on its surface exactly, the normal is the side's outward normal")
{
    // The side from (1, -1) to (0, 1) in (radial, axial) passes through (0.5, 0) exactly, where
    // the offset to it is 0 and the side's own normal (2, 1) / sqrt(5) stands in.
    const krs::capped_cone k({0, 0, -1}, {0, 0, 1}, 1.0f, 0.0f);
    const vec3f n = k.normal(vec3f{0.5f, 0, 0});
    CHECK(k.distance(vec3f{0.5f, 0, 0}) == 0.0f);
    CHECK(krs::length(vec3d(n) - vec3d{2 / std::sqrt(5.0), 0, 1 / std::sqrt(5.0)}) < 1e-6);
}

// Round box (krs/kernels/round_box.hpp) against references built here another way: the solid as
// the inner box grown by a ball, its distance as |p - clamp(p, inner box)| - r outside the inner
// box and -(least face depth + r) inside it (a convex set's nearest point is its projection), in
// double at 10^5 points; against a dense sampling of the surface, made by pushing random points
// onto it along their projection (so faces, edges and corners are all sampled): never
// overestimates, zero on it. Also 1-Lipschitz on close random pairs, packet lanes (float and
// double) against the scalar path, bounds holding sampled inside points, normals against the
// central-difference gradient, refused parameters. Its GLSL runs on llvmpipe in
// test_glsl_field_types.cpp.

#include "krs/field.hpp"
#include "krs/kernels/round_box.hpp"

#include "support/kernel_properties.hpp"
#include "support/rejects.hpp"
#include "support/random.hpp"

#include <doctest/doctest.h>

#include <algorithm>
#include <cfloat>
#include <cmath>
#include <limits>
#include <random>
#include <vector>

static_assert(krs::kernel<krs::round_box>);

namespace {

using krs::vec3d;
using krs::vec3f;
using krs_test::uniform;

struct round_box_case {
    krs::round_box kernel;
    vec3d center, inner;
    double r, extent;
    round_box_case(vec3f middle, vec3f half, float radius)
        : kernel(middle, half, radius), center(middle), inner(vec3d(half) - vec3d{radius, radius, radius}), r(radius),
          extent(1.5 * krs::length(vec3d(half)) + 0.1)
    {
    }
    vec3d project_on_inner(const vec3d& q) const
    {
        return {std::clamp(q.x, -inner.x, inner.x), std::clamp(q.y, -inner.y, inner.y),
                std::clamp(q.z, -inner.z, inner.z)};
    }
    double reference(const vec3d& p) const
    {
        const vec3d q = p - center;
        const vec3d x = project_on_inner(q);
        if (x.x == q.x && x.y == q.y && x.z == q.z) // inside the inner box
            return -(std::min({inner.x - std::abs(q.x), inner.y - std::abs(q.y), inner.z - std::abs(q.z)}) + r);
        return krs::length(q - x) - r;
    }
    // Points of the surface: a random point outside the inner box moved to r from its projection.
    std::vector<vec3d> surface(std::mt19937_64& g, int count) const
    {
        std::vector<vec3d> out;
        const vec3d reach = inner + vec3d{2 * r, 2 * r, 2 * r};
        while (int(out.size()) < count) {
            const vec3d q{uniform(g, -reach.x, reach.x), uniform(g, -reach.y, reach.y), uniform(g, -reach.z, reach.z)};
            const vec3d x = project_on_inner(q);
            const double l = krs::length(q - x);
            if (l > 1e-3 * r) out.push_back(center + x + (q - x) * (r / l));
        }
        return out;
    }
};

std::vector<round_box_case> cases()
{
    return {round_box_case({0.1f, -0.2f, 0.3f}, {0.6f, 0.3f, 0.45f}, 0.1f),
            round_box_case({0, 0, 0}, {0.5f, 0.5f, 0.5f}, 0.5f),   // radius = half extent: a ball
            round_box_case({0.3f, 0.1f, 0}, {1.0f, 0.2f, 0.6f}, 0.2f), // rounded to a slab's full thickness
            round_box_case({1000, -999.5f, 1000.25f}, {0.4f, 0.7f, 0.3f}, 0.05f)};
}

} // namespace

TEST_CASE("round_box: distance, never overestimates, Lipschitz, lanes, normals")
{
    for (const round_box_case& c : cases()) krs_test::check_kernel_field_properties(c);
}

TEST_CASE("round_box: bound and bound_box hold inside points, and the box is the outer box")
{
    for (const round_box_case& c : cases()) {
        const krs::bounding_box box = c.kernel.bound_box();
        krs_test::check_kernel_bounds(c);
        const vec3d outer = c.inner + vec3d{c.r, c.r, c.r};
        CHECK(double(box.hi.x) - (c.center.x + outer.x) <= 1e-5 * (1 + std::abs(c.center.x)));
        CHECK((c.center.y - outer.y) - double(box.lo.y) <= 1e-5 * (1 + std::abs(c.center.y)));
    }
}

TEST_CASE("round_box: bad parameters are refused by name")
{
    const float nan = std::numeric_limits<float>::quiet_NaN();
    krs_test::rejects([] { krs::round_box({0, 0, 0}, {1, 1, 1}, 0.0f); }, "round_box.radius");
    krs_test::rejects([] { krs::round_box({0, 0, 0}, {1, 1, 1}, -0.1f); }, "round_box.radius");
    krs_test::rejects([&] { krs::round_box({0, 0, 0}, {1, 1, 1}, nan); }, "round_box.radius");
    krs_test::rejects([] { krs::round_box({0, 0, 0}, {1, 0.2f, 1}, 0.3f); }, "round_box.radius");
    krs_test::rejects([] { krs::round_box({0, 0, 0}, {1, -0.2f, 1}, 0.1f); }, "round_box.half_extents");
    krs_test::rejects([&] { krs::round_box({0, 0, 0}, {1, nan, 1}, 0.1f); }, "round_box.half_extents");
    krs_test::rejects([&] { krs::round_box({nan, 0, 0}, {1, 1, 1}, 0.1f); }, "round_box.center");
}

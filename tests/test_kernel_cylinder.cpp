// Cylinders (krs/kernels/capped_cylinder.hpp, infinite_cylinder.hpp) against references built
// here another way: the solid as the convex set {|radial| <= r, |height| <= h} in a frame made by
// Gram-Schmidt from a different helper vector, its distance as |p - projection of p| outside and
// the nearest face's depth inside (a convex solid's nearest point is its projection), in double at
// 10^5 points; and against a dense sampling of the surface (the field never overestimates the
// distance to a surface point). Also: 1-Lipschitz on close random pairs, packet lanes (float and
// double) against the scalar path, bounds hold sampled inside points, normals against the
// central-difference gradient, refused parameters. Their GLSL runs on llvmpipe in
// test_glsl_field_types.cpp.

#include "krs/field.hpp"
#include "krs/kernels/capped_cylinder.hpp"
#include "krs/kernels/infinite_cylinder.hpp"

#include "support/kernel_properties.hpp"
#include "support/rejects.hpp"
#include "support/random.hpp"

#include <doctest/doctest.h>

#include <algorithm>
#include <cfloat>
#include <cmath>
#include <limits>
#include <numbers>
#include <random>
#include <vector>

static_assert(krs::kernel<krs::capped_cylinder>);
static_assert(krs::kernel<krs::infinite_cylinder>);

namespace {

using krs::vec3d;
using krs::vec3f;
using krs_test::uniform;

// An orthonormal frame (e1, e2, n) around the unit n, from the coordinate axis least aligned with
// it (the kernels use a threshold on x instead, so the two frames differ).
struct frame {
    vec3d e1, e2, n;
    explicit frame(const vec3d& axis) : n(krs::normalize(axis))
    {
        const double ax = std::abs(n.x), ay = std::abs(n.y), az = std::abs(n.z);
        const vec3d helper = az <= ax && az <= ay ? vec3d{0, 0, 1} : (ay <= ax ? vec3d{0, 1, 0} : vec3d{1, 0, 0});
        e1 = krs::normalize(helper - n * krs::dot(helper, n));
        e2 = krs::cross(n, e1);
    }
};

// The capped cylinder as a convex set in its own frame: radial coordinates (s, t), height z.
struct cylinder_reference {
    vec3d c;
    frame f;
    double h, r;
    bool capped = true;
    cylinder_reference(vec3f a, vec3f b, float radius)
        : c((vec3d(a) + vec3d(b)) * 0.5), f(vec3d(b) - vec3d(a)), h(0.5 * krs::length(vec3d(b) - vec3d(a))), r(radius)
    {
    }
    cylinder_reference(vec3f point, vec3f axis, float radius, bool)
        : c(point), f(vec3d(axis)), h(std::numeric_limits<double>::infinity()), r(radius), capped(false)
    {
    }
    double distance(const vec3d& p) const
    {
        const vec3d q = p - c;
        const double s = krs::dot(q, f.e1), t = krs::dot(q, f.e2), z = krs::dot(q, f.n);
        const double rho = std::hypot(s, t);
        if (rho <= r && std::abs(z) <= h) return -std::min(r - rho, h - std::abs(z)); // nearest face
        // The projection: the radial part pulled onto the disc, the height clamped to [-h, h].
        const double scale = rho > r ? r / rho : 1.0;
        const vec3d nearest = f.e1 * (s * scale) + f.e2 * (t * scale) + f.n * std::clamp(z, -h, h);
        return krs::length(q - nearest);
    }
    // Surface samples: the side, and for a capped one both discs (area-weighted by count).
    std::vector<vec3d> surface(std::mt19937_64& g, int count, double side_half_length) const
    {
        std::vector<vec3d> out;
        const double side_area = 2 * std::numbers::pi * r * 2 * side_half_length;
        const double cap_area = capped ? 2 * std::numbers::pi * r * r : 0;
        for (int i = 0; i < count; ++i) {
            const double phi = uniform(g, 0, 2 * std::numbers::pi);
            const vec3d around = f.e1 * std::cos(phi) + f.e2 * std::sin(phi);
            if (uniform(g, 0, side_area + cap_area) < side_area) {
                out.push_back(c + around * r + f.n * uniform(g, -side_half_length, side_half_length));
            } else {
                const double rho = r * std::sqrt(uniform(g, 0, 1));
                out.push_back(c + around * rho + f.n * (uniform(g, 0, 1) < 0.5 ? -h : h));
            }
        }
        return out;
    }
};

struct capped_case {
    krs::capped_cylinder kernel;
    cylinder_reference solid;
    vec3d center;
    double extent;
    capped_case(vec3f a, vec3f b, float r)
        : kernel(a, b, r), solid(a, b, r), center((vec3d(a) + vec3d(b)) * 0.5),
          extent(1.5 * std::hypot(solid.h, solid.r) + 0.1)
    {
    }
    double reference(const vec3d& p) const { return solid.distance(p); }
    std::vector<vec3d> surface(std::mt19937_64& g, int count) const { return solid.surface(g, count, solid.h); }
};
std::vector<capped_case> capped_cases()
{
    return {capped_case({-0.3f, 0.2f, 0.1f}, {0.5f, -0.4f, 0.7f}, 0.35f),
            capped_case({0, 0, -1}, {0, 0, 1}, 0.2f),                  // along z: a flat-capped post
            capped_case({0.1f, 0.2f, 0.3f}, {0.15f, 0.25f, 0.32f}, 0.9f), // a thin disc
            capped_case({1000, 999.5f, 1001}, {1001, 1000.25f, 1000.5f}, 0.3f)};
}

struct infinite_case {
    krs::infinite_cylinder kernel;
    cylinder_reference solid;
    vec3d center;
    double extent = 2;
    infinite_case(vec3f point, vec3f axis, float r)
        : kernel(point, axis, r), solid(point, axis, r, false), center(point)
    {
    }
    double reference(const vec3d& p) const { return solid.distance(p); }
    // The side over 4 extents along the axis: every point of it within reach of the query ball.
    std::vector<vec3d> surface(std::mt19937_64& g, int count) const { return solid.surface(g, count, 4 * extent); }
};
std::vector<infinite_case> infinite_cases()
{
    return {infinite_case({0.2f, -0.1f, 0.3f}, {0.3f, 1, -0.4f}, 0.5f), infinite_case({0, 0, 0}, {1, 0, 0}, 0.1f),
            infinite_case({-2, 1, 0.5f}, {0, 0, 3}, 1.25f)};
}

} // namespace

TEST_CASE("capped_cylinder: distance, never overestimates, Lipschitz, lanes, normals")
{
    for (const capped_case& c : capped_cases()) krs_test::check_kernel_field_properties(c);
}

TEST_CASE("capped_cylinder: bound and bound_box hold inside points, and the box is tight")
{
    for (const capped_case& c : capped_cases()) {
        const krs::bounding_box box = c.kernel.bound_box(), sampled = krs_test::check_kernel_bounds(c);
        // Exact: the sampled extremes (the rims) come within 1% of the size of the box's faces.
        const double slack = 0.01 * (c.solid.h + c.solid.r);
        krs_test::check_box_tight(box, sampled, slack);
    }
}

TEST_CASE("capped_cylinder: uv runs along the axis from a to b and around it")
{
    const krs::capped_cylinder k({0, 0, -1}, {0, 0, 1}, 0.5f);
    const auto at_a = k.uv(vec3f{0.5f, 0, -1}), at_b = k.uv(vec3f{0.5f, 0, 1}), mid = k.uv(vec3f{0, 0.5f, 0});
    CHECK(at_a.u == doctest::Approx(0));
    CHECK(at_b.u == doctest::Approx(1));
    CHECK(mid.u == doctest::Approx(0.5));
    // A quarter turn around the axis moves v by a quarter.
    const auto v0 = k.uv(vec3f{0.5f, 0, 0}).v, v1 = k.uv(vec3f{0, 0.5f, 0}).v, v2 = k.uv(vec3f{-0.5f, 0, 0}).v;
    CHECK(std::abs(std::abs(v1 - v0) - 0.25f) < 1e-5f);
    CHECK(std::abs(std::abs(v2 - v1) - 0.25f) < 1e-5f);
}

TEST_CASE("capped_cylinder: bad parameters are refused by name")
{
    const float nan = std::numeric_limits<float>::quiet_NaN();
    krs_test::rejects([] { krs::capped_cylinder({0, 0, 0}, {0, 0, 1}, 0.0f); }, "capped_cylinder.radius");
    krs_test::rejects([] { krs::capped_cylinder({0, 0, 0}, {0, 0, 1}, -0.5f); }, "capped_cylinder.radius");
    krs_test::rejects([&] { krs::capped_cylinder({0, 0, 0}, {0, 0, 1}, nan); }, "capped_cylinder.radius");
    krs_test::rejects([] { krs::capped_cylinder({1, 2, 3}, {1, 2, 3}, 0.5f); }, "capped_cylinder.b");
    krs_test::rejects([&] { krs::capped_cylinder({nan, 0, 0}, {0, 0, 1}, 0.5f); }, "capped_cylinder.a");
    krs_test::rejects([&] { krs::capped_cylinder({0, 0, 0}, {0, 0, 2e9f}, 0.5f); }, "capped_cylinder.b");
}

TEST_CASE("infinite_cylinder: distance, never overestimates, Lipschitz, lanes, normals, unbounded")
{
    for (const infinite_case& c : infinite_cases()) {
        krs_test::check_kernel_field_properties(c);
        CHECK(!c.kernel.bound().is_bounded());
    }
    // Along x: bounded across the axis (y and z within the radius), unbounded along it.
    const krs::bounding_box box = krs::infinite_cylinder({0, 1, 2}, {1, 0, 0}, 0.5f).bound_box();
    CHECK(std::isinf(box.lo.x));
    CHECK(std::isinf(box.hi.x));
    CHECK(box.lo.y <= 0.5f);
    CHECK(box.lo.y > 0.49f);
    CHECK(box.hi.z >= 2.5f);
    CHECK(box.hi.z < 2.51f);
}

TEST_CASE("infinite_cylinder: bad parameters are refused by name")
{
    const float nan = std::numeric_limits<float>::quiet_NaN();
    krs_test::rejects([] { krs::infinite_cylinder({0, 0, 0}, {0, 0, 1}, 0.0f); }, "infinite_cylinder.radius");
    krs_test::rejects([] { krs::infinite_cylinder({0, 0, 0}, {0, 0, 1}, -1.0f); }, "infinite_cylinder.radius");
    krs_test::rejects([] { krs::infinite_cylinder({0, 0, 0}, {0, 0, 0}, 1.0f); }, "infinite_cylinder.axis");
    krs_test::rejects([&] { krs::infinite_cylinder({0, 0, 0}, {nan, 0, 1}, 1.0f); }, "infinite_cylinder.axis");
    krs_test::rejects([&] { krs::infinite_cylinder({0, nan, 0}, {0, 0, 1}, 1.0f); }, "infinite_cylinder.point");
}

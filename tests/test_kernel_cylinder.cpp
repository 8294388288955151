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

[[gnu::noinline]] vec3f to_f(const vec3d& v) { return vec3f(v); }

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
    cylinder_reference reference;
    vec3d center;
    double extent;
    capped_case(vec3f a, vec3f b, float r)
        : kernel(a, b, r), reference(a, b, r), center((vec3d(a) + vec3d(b)) * 0.5),
          extent(1.5 * std::hypot(reference.h, reference.r) + 0.1)
    {
    }
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
    cylinder_reference reference;
    vec3d center;
    double extent = 2;
    infinite_case(vec3f point, vec3f axis, float r)
        : kernel(point, axis, r), reference(point, axis, r, false), center(point)
    {
    }
};
std::vector<infinite_case> infinite_cases()
{
    return {infinite_case({0.2f, -0.1f, 0.3f}, {0.3f, 1, -0.4f}, 0.5f), infinite_case({0, 0, 0}, {1, 0, 0}, 0.1f),
            infinite_case({-2, 1, 0.5f}, {0, 0, 3}, 1.25f)};
}

// A float-representable point uniform in the ball (c, radius).
vec3d query(std::mt19937_64& g, const vec3d& c, double radius) { return vec3d(to_f(c + krs_test::in_ball(g, radius))); }

// The tolerance of a float evaluation at p: 8 ulps of the problem's scale.
double tolerance_at(const vec3d& p, double extent) { return 8 * FLT_EPSILON * (krs::length(p) + extent); }

template <class Case>
void check_against_reference(const Case& c, int count)
{
    std::mt19937_64 g(11);
    int inside = 0, bad_f = 0, bad_d = 0;
    double worst = 0;
    for (int i = 0; i < count; ++i) {
        const vec3d p = query(g, c.center, c.extent);
        const double expected = c.reference.distance(p);
        const double got_f = c.kernel.distance(to_f(p)), got_d = c.kernel.distance(p);
        const double tolerance = tolerance_at(p, c.extent);
        worst = std::max(worst, std::abs(got_f - expected) / tolerance);
        bad_f += !(std::abs(got_f - expected) <= tolerance);
        bad_d += !(std::abs(got_d - expected) <= tolerance);
        inside += expected < 0;
    }
    MESSAGE("worst float error / tolerance " << worst);
    CHECK(bad_f == 0);
    CHECK(bad_d == 0);
    CHECK(inside > count / 500); // the sign is tested
    CHECK(inside < count);
}

template <class Case>
void check_never_overestimates(const Case& c, double side_half_length)
{
    std::mt19937_64 g(12);
    const std::vector<vec3d> surface = c.reference.surface(g, 20000, side_half_length);
    int off_surface = 0, over = 0;
    for (const vec3d& s : surface) off_surface += !(std::abs(c.kernel.distance(s)) <= tolerance_at(s, c.extent));
    for (int i = 0; i < 1000; ++i) {
        const vec3d p = query(g, c.center, c.extent);
        const double d = c.kernel.distance(to_f(p));
        double nearest = INFINITY;
        for (const vec3d& s : surface) nearest = std::min(nearest, krs::length(p - s));
        over += !(d <= nearest + tolerance_at(p, c.extent));
    }
    CHECK(off_surface == 0);
    CHECK(over == 0);
}

template <class Case>
void check_lipschitz(const Case& c)
{
    std::mt19937_64 g(13);
    int bad = 0;
    for (int i = 0; i < 100000; ++i) {
        const vec3d p = c.center + krs_test::in_ball(g, c.extent);
        const vec3d q = p + krs_test::in_ball(g, 1e-3 * c.extent);
        bad += !(std::abs(c.kernel.distance(p) - c.kernel.distance(q)) <= krs::length(p - q) * (1 + 1e-9) + 1e-12);
    }
    CHECK(bad == 0);
}

template <class P, class Case>
void check_lanes(const Case& c)
{
    using S = krs::scalar_t<P>;
    constexpr std::size_t width = krs::lane_count<P>;
    std::mt19937_64 g(14);
    int mismatches = 0;
    for (int batch = 0; batch < 256; ++batch) {
        alignas(64) S x[width], y[width], z[width];
        for (std::size_t i = 0; i < width; ++i) {
            const vec3d p = query(g, c.center, c.extent);
            x[i] = S(p.x), y[i] = S(p.y), z[i] = S(p.z);
        }
        const krs::vec3<P> p{P::load_aligned(x), P::load_aligned(y), P::load_aligned(z)};
        const P d = c.kernel.distance(p);
        const krs::vec3<P> n = c.kernel.normal(p);
        for (std::size_t i = 0; i < width; ++i) {
            const krs::vec3<S> ps{x[i], y[i], z[i]};
            const double scale = krs::length(vec3d(ps)) + c.extent;
            const double dd = std::abs(double(krs::lane_at(d, i)) - double(c.kernel.distance(ps)));
            const double dn = krs::length(vec3d(krs::lane_at(n, i)) - vec3d(c.kernel.normal(ps)));
            mismatches += !(dd <= 1e-6 * scale) || !(dn <= 1e-5);
        }
    }
    CHECK(mismatches == 0);
}

// The normal against the central difference of the double distance, where that gradient has
// unit length (off the creases: the rim, the axis).
template <class Case>
void check_normal(const Case& c)
{
    std::mt19937_64 g(15);
    const double e = 1e-6;
    int tested = 0, bad = 0;
    for (int i = 0; i < 4000; ++i) {
        const vec3d p = query(g, c.center, c.extent);
        auto d = [&](const vec3d& q) { return c.kernel.distance(q); };
        const vec3d gradient{(d(p + vec3d{e, 0, 0}) - d(p - vec3d{e, 0, 0})) / (2 * e),
                             (d(p + vec3d{0, e, 0}) - d(p - vec3d{0, e, 0})) / (2 * e),
                             (d(p + vec3d{0, 0, e}) - d(p - vec3d{0, 0, e})) / (2 * e)};
        const vec3d n(c.kernel.normal(to_f(p)));
        bad += !(std::abs(krs::length(n) - 1) < 1e-5);
        if (std::abs(krs::length(gradient) - 1) > 1e-6) continue;
        ++tested;
        bad += !(krs::length(n - gradient) < 1e-3);
    }
    CHECK(bad == 0);
    CHECK(tested > 3200);
}

} // namespace

TEST_CASE("capped_cylinder: distance against the projection reference at 10^5 points, float and double")
{
    for (const capped_case& c : capped_cases()) check_against_reference(c, 100000);
}

TEST_CASE("capped_cylinder: never overestimates against dense surface sampling, zero on it")
{
    for (const capped_case& c : capped_cases()) check_never_overestimates(c, c.reference.h);
}

TEST_CASE("capped_cylinder: 1-Lipschitz, lanes, normals")
{
    for (const capped_case& c : capped_cases()) {
        check_lipschitz(c);
        check_lanes<krs::packet_f>(c);
        check_lanes<krs::packet_d>(c);
        check_normal(c);
    }
}

TEST_CASE("capped_cylinder: bound and bound_box hold inside points; the box is tight")
{
    for (const capped_case& c : capped_cases()) {
        std::mt19937_64 g(16);
        const krs::bounding_sphere b = c.kernel.bound();
        const krs::bounding_box box = c.kernel.bound_box();
        vec3d lo{INFINITY, INFINITY, INFINITY}, hi = -lo;
        int outside = 0, inside_points = 0;
        // Inside points from the reference's frame, plus the surface itself (the rim reaches farthest).
        std::vector<vec3d> points = c.reference.surface(g, 20000, c.reference.h);
        for (int i = 0; i < 20000; ++i) {
            const vec3d p = c.center + krs_test::in_ball(g, c.extent);
            if (c.reference.distance(p) <= 0) points.push_back(p), ++inside_points;
        }
        for (const vec3d& p : points) {
            outside += !(krs::length(p - vec3d(b.center)) <= double(b.radius));
            outside += !(p.x >= box.lo.x && p.x <= box.hi.x && p.y >= box.lo.y && p.y <= box.hi.y && p.z >= box.lo.z &&
                         p.z <= box.hi.z);
            lo = krs::min(lo, p), hi = krs::max(hi, p);
        }
        CHECK(inside_points > 100);
        CHECK(outside == 0);
        // Exact: the sampled extremes come within 1% of the size of the box's faces.
        const double slack = 0.01 * (c.reference.h + c.reference.r);
        CHECK(lo.x - box.lo.x <= slack);
        CHECK(box.hi.x - hi.x <= slack);
        CHECK(lo.y - box.lo.y <= slack);
        CHECK(box.hi.y - hi.y <= slack);
        CHECK(lo.z - box.lo.z <= slack);
        CHECK(box.hi.z - hi.z <= slack);
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

TEST_CASE("infinite_cylinder: distance against the projection reference at 10^5 points, float and double")
{
    for (const infinite_case& c : infinite_cases()) check_against_reference(c, 100000);
}

TEST_CASE("infinite_cylinder: never overestimates against dense surface sampling, zero on it")
{
    // The side sampled over a length of 4 extents covers every point of it within reach of the
    // query ball (radius 1 extent around the point on the axis).
    for (const infinite_case& c : infinite_cases()) check_never_overestimates(c, 4 * c.extent);
}

TEST_CASE("infinite_cylinder: 1-Lipschitz, lanes, normals, unbounded")
{
    for (const infinite_case& c : infinite_cases()) {
        check_lipschitz(c);
        check_lanes<krs::packet_f>(c);
        check_lanes<krs::packet_d>(c);
        check_normal(c);
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

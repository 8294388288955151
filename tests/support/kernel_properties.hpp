#pragma once
// The properties every kernel's own test checks (tests/test_kernel_<name>.cpp), written once:
// distance against the test's independent reference at 10^5 points in float and double; never an
// overestimate against a dense sampling of the surface, and zero on it; 1-Lipschitz on close
// random pairs; packet lanes (float and double) against the scalar path; the normal against the
// central-difference gradient off creases; bound and bound_box holding the surface and sampled
// inside points. A case holds the kernel, its `center` and `extent` (the query ball), its
// `reference(p)` distance in double and `surface(g, count)`, points of its surface.

#include "krs/core/bounds.hpp"
#include "krs/core/lanes.hpp"
#include "krs/core/vec3.hpp"

#include "random.hpp"

#include <doctest/doctest.h>

#include <algorithm>
#include <cfloat>
#include <cmath>
#include <random>
#include <vector>

namespace krs_test {

// Rounding to float out of line (tests/test_kernels.cpp says why: GCC 12 drops a vectorized one).
[[gnu::noinline]] inline krs::vec3f to_float(const krs::vec3d& v) { return krs::vec3f(v); }

// A float-representable point uniform in the case's query ball.
template <class Case>
krs::vec3d kernel_query(std::mt19937_64& g, const Case& c)
{
    return krs::vec3d(to_float(c.center + in_ball(g, c.extent)));
}
// What a float evaluation at p may be off by: 8 ulps of the problem's scale.
inline double kernel_tolerance(const krs::vec3d& p, double extent) { return 8 * FLT_EPSILON * (krs::length(p) + extent); }

template <class Case>
void check_kernel_against_reference(const Case& c, int count = 100000)
{
    std::mt19937_64 g(11);
    int inside = 0, bad_f = 0, bad_d = 0;
    for (int i = 0; i < count; ++i) {
        const krs::vec3d p = kernel_query(g, c);
        const double expected = c.reference(p);
        const double tolerance = kernel_tolerance(p, c.extent);
        bad_f += !(std::abs(double(c.kernel.distance(to_float(p))) - expected) <= tolerance);
        bad_d += !(std::abs(c.kernel.distance(p) - expected) <= tolerance);
        inside += expected < 0;
    }
    CHECK(bad_f == 0);
    CHECK(bad_d == 0);
    CHECK(inside > count / 500); // the sign is tested
    CHECK(inside < count);
}

template <class Case>
void check_kernel_never_overestimates(const Case& c)
{
    std::mt19937_64 g(12);
    const std::vector<krs::vec3d> surface = c.surface(g, 20000);
    int off_surface = 0, over = 0;
    for (const krs::vec3d& s : surface) off_surface += !(std::abs(c.kernel.distance(s)) <= kernel_tolerance(s, c.extent));
    for (int i = 0; i < 1000; ++i) {
        const krs::vec3d p = kernel_query(g, c);
        double nearest = INFINITY;
        for (const krs::vec3d& s : surface) nearest = std::min(nearest, krs::length(p - s));
        over += !(double(c.kernel.distance(to_float(p))) <= nearest + kernel_tolerance(p, c.extent));
    }
    CHECK(off_surface == 0);
    CHECK(over == 0);
}

template <class Case>
void check_kernel_lipschitz(const Case& c)
{
    std::mt19937_64 g(13);
    int bad = 0;
    for (int i = 0; i < 100000; ++i) {
        const krs::vec3d p = c.center + in_ball(g, c.extent);
        const krs::vec3d q = p + in_ball(g, 1e-3 * c.extent);
        bad += !(std::abs(c.kernel.distance(p) - c.kernel.distance(q)) <= krs::length(p - q) * (1 + 1e-9) + 1e-12);
    }
    CHECK(bad == 0);
}

// Every lane of a packet against the scalar path of its scalar type: bit-equal in the test build
// (-ffp-contract=off); the tolerances (1e-6 of the scale for distances, 1e-5 for normals) are
// the brief's allowance, not measured under FMA contraction (these files are not parity sources).
template <class P, class Case>
void check_kernel_lanes(const Case& c)
{
    using S = krs::scalar_t<P>;
    constexpr std::size_t width = krs::lane_count<P>;
    std::mt19937_64 g(14);
    int mismatches = 0;
    for (int batch = 0; batch < 256; ++batch) {
        alignas(64) S x[width], y[width], z[width];
        for (std::size_t i = 0; i < width; ++i) {
            const krs::vec3d p = kernel_query(g, c);
            x[i] = S(p.x), y[i] = S(p.y), z[i] = S(p.z);
        }
        const krs::vec3<P> p{P::load_aligned(x), P::load_aligned(y), P::load_aligned(z)};
        const P d = c.kernel.distance(p);
        const krs::vec3<P> n = c.kernel.normal(p);
        for (std::size_t i = 0; i < width; ++i) {
            const krs::vec3<S> ps{x[i], y[i], z[i]};
            const double scale = krs::length(krs::vec3d(ps)) + c.extent;
            mismatches += !(std::abs(double(krs::lane_at(d, i)) - double(c.kernel.distance(ps))) <= 1e-6 * scale);
            mismatches += !(krs::length(krs::vec3d(krs::lane_at(n, i)) - krs::vec3d(c.kernel.normal(ps))) <= 1e-5);
        }
    }
    CHECK(mismatches == 0);
}

// The normal against the central difference of the double distance, where that gradient has
// unit length (off the creases: edges, rims, axes, medial surfaces).
template <class Case>
void check_kernel_normal(const Case& c)
{
    std::mt19937_64 g(15);
    const double e = 1e-6;
    int tested = 0, wrong = 0;
    for (int i = 0; i < 4000; ++i) {
        const krs::vec3d p = kernel_query(g, c);
        auto d = [&](const krs::vec3d& q) { return c.kernel.distance(q); };
        const krs::vec3d gradient{(d(p + krs::vec3d{e, 0, 0}) - d(p - krs::vec3d{e, 0, 0})) / (2 * e),
                                  (d(p + krs::vec3d{0, e, 0}) - d(p - krs::vec3d{0, e, 0})) / (2 * e),
                                  (d(p + krs::vec3d{0, 0, e}) - d(p - krs::vec3d{0, 0, e})) / (2 * e)};
        const krs::vec3d n(c.kernel.normal(to_float(p)));
        wrong += !(std::abs(krs::length(n) - 1) < 1e-5);
        if (std::abs(krs::length(gradient) - 1) > 1e-6) continue;
        ++tested;
        wrong += !(krs::length(n - gradient) < 1e-3);
    }
    CHECK(wrong == 0);
    CHECK(tested > 3000);
}

// All of the above but the bounds.
template <class Case>
void check_kernel_field_properties(const Case& c)
{
    check_kernel_against_reference(c);
    check_kernel_never_overestimates(c);
    check_kernel_lipschitz(c);
    check_kernel_lanes<krs::packet_f>(c);
    check_kernel_lanes<krs::packet_d>(c);
    check_kernel_normal(c);
}

// bound() and bound_box() hold the surface samples, the given extra points (vertices, say) and
// the query ball's points inside the solid (by the reference); returns the box of all of them, for
// a test of the box's tightness.
template <class Case>
krs::bounding_box check_kernel_bounds(const Case& c, const std::vector<krs::vec3d>& extra = {})
{
    std::mt19937_64 g(16);
    const krs::bounding_sphere b = c.kernel.bound();
    const krs::bounding_box box = c.kernel.bound_box();
    std::vector<krs::vec3d> points = c.surface(g, 20000);
    points.insert(points.end(), extra.begin(), extra.end());
    int inside_points = 0, outside = 0;
    for (int i = 0; i < 20000; ++i) {
        const krs::vec3d p = c.center + in_ball(g, c.extent);
        if (c.reference(p) <= 0) points.push_back(p), ++inside_points;
    }
    krs::vec3d lo{INFINITY, INFINITY, INFINITY}, hi = -lo;
    for (const krs::vec3d& p : points) {
        outside += !(krs::length(p - krs::vec3d(b.center)) <= double(b.radius));
        outside += !(p.x >= box.lo.x && p.x <= box.hi.x && p.y >= box.lo.y && p.y <= box.hi.y && p.z >= box.lo.z &&
                     p.z <= box.hi.z);
        lo = krs::min(lo, p), hi = krs::max(hi, p);
    }
    CHECK(inside_points > 100);
    CHECK(outside == 0);
    return {krs::vec3f(lo), krs::vec3f(hi)};
}

// A box is tight: each face within `slack` of the sampled extremes it must hold.
inline void check_box_tight(const krs::bounding_box& box, const krs::bounding_box& sampled, double slack)
{
    CHECK(sampled.lo.x - box.lo.x <= slack);
    CHECK(box.hi.x - sampled.hi.x <= slack);
    CHECK(sampled.lo.y - box.lo.y <= slack);
    CHECK(box.hi.y - sampled.hi.y <= slack);
    CHECK(sampled.lo.z - box.lo.z <= slack);
    CHECK(box.hi.z - sampled.hi.z <= slack);
}

// Distance from p to the segment ab, in double (references build on it).
inline double segment_distance(const krs::vec3d& p, const krs::vec3d& a, const krs::vec3d& b)
{
    const krs::vec3d ab = b - a;
    const double t = std::clamp(krs::dot(p - a, ab) / krs::dot(ab, ab), 0.0, 1.0);
    return krs::length(p - (a + ab * t));
}

} // namespace krs_test

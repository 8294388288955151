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

[[gnu::noinline]] vec3f to_f(const vec3d& v) { return vec3f(v); }

struct round_box_case {
    krs::round_box kernel;
    vec3d c, inner;
    double r, extent;
    round_box_case(vec3f center, vec3f half, float radius)
        : kernel(center, half, radius), c(center), inner(vec3d(half) - vec3d{radius, radius, radius}), r(radius),
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
        const vec3d q = p - c;
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
            if (l > 1e-3 * r) out.push_back(c + x + (q - x) * (r / l));
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

vec3d query(std::mt19937_64& g, const round_box_case& c) { return vec3d(to_f(c.c + krs_test::in_ball(g, c.extent))); }
double tolerance_at(const vec3d& p, double extent) { return 8 * FLT_EPSILON * (krs::length(p) + extent); }

} // namespace

TEST_CASE("round_box: distance against the projection reference at 10^5 points, float and double")
{
    for (const round_box_case& c : cases()) {
        std::mt19937_64 g(21);
        int bad_f = 0, bad_d = 0, inside = 0;
        for (int i = 0; i < 100000; ++i) {
            const vec3d p = query(g, c);
            const double expected = c.reference(p);
            const double tolerance = tolerance_at(p, c.extent);
            bad_f += !(std::abs(double(c.kernel.distance(to_f(p))) - expected) <= tolerance);
            bad_d += !(std::abs(c.kernel.distance(p) - expected) <= tolerance);
            inside += expected < 0;
        }
        CHECK(bad_f == 0);
        CHECK(bad_d == 0);
        CHECK(inside > 1000);
    }
}

TEST_CASE("round_box: never overestimates against dense surface sampling, zero on it")
{
    for (const round_box_case& c : cases()) {
        std::mt19937_64 g(22);
        const std::vector<vec3d> surface = c.surface(g, 20000);
        int off_surface = 0, over = 0;
        for (const vec3d& s : surface) off_surface += !(std::abs(c.kernel.distance(s)) <= tolerance_at(s, c.extent));
        for (int i = 0; i < 1000; ++i) {
            const vec3d p = query(g, c);
            double nearest = INFINITY;
            for (const vec3d& s : surface) nearest = std::min(nearest, krs::length(p - s));
            over += !(double(c.kernel.distance(to_f(p))) <= nearest + tolerance_at(p, c.extent));
        }
        CHECK(off_surface == 0);
        CHECK(over == 0);
    }
}

TEST_CASE("round_box: 1-Lipschitz, packet lanes, normals")
{
    for (const round_box_case& c : cases()) {
        std::mt19937_64 g(23);
        int bad = 0;
        for (int i = 0; i < 100000; ++i) {
            const vec3d p = c.c + krs_test::in_ball(g, c.extent);
            const vec3d q = p + krs_test::in_ball(g, 1e-3 * c.extent);
            bad += !(std::abs(c.kernel.distance(p) - c.kernel.distance(q)) <= krs::length(p - q) * (1 + 1e-9) + 1e-12);
        }
        CHECK(bad == 0);
        // Lanes: float and double packets against the scalar path.
        const auto lanes = [&]<class P>(P) {
            using S = krs::scalar_t<P>;
            constexpr std::size_t width = krs::lane_count<P>;
            int mismatches = 0;
            for (int batch = 0; batch < 256; ++batch) {
                alignas(64) S x[width], y[width], z[width];
                for (std::size_t i = 0; i < width; ++i) {
                    const vec3d p = query(g, c);
                    x[i] = S(p.x), y[i] = S(p.y), z[i] = S(p.z);
                }
                const krs::vec3<P> p{P::load_aligned(x), P::load_aligned(y), P::load_aligned(z)};
                const P d = c.kernel.distance(p);
                const krs::vec3<P> n = c.kernel.normal(p);
                for (std::size_t i = 0; i < width; ++i) {
                    const krs::vec3<S> ps{x[i], y[i], z[i]};
                    const double scale = krs::length(vec3d(ps)) + c.extent;
                    mismatches += !(std::abs(double(krs::lane_at(d, i)) - double(c.kernel.distance(ps))) <= 1e-6 * scale);
                    mismatches += !(krs::length(vec3d(krs::lane_at(n, i)) - vec3d(c.kernel.normal(ps))) <= 1e-5);
                }
            }
            return mismatches;
        };
        CHECK(lanes(krs::packet_f{}) == 0);
        CHECK(lanes(krs::packet_d{}) == 0);
        // Normals against the central difference of the double distance, off the creases.
        const double e = 1e-6;
        int tested = 0, wrong = 0;
        for (int i = 0; i < 4000; ++i) {
            const vec3d p = query(g, c);
            auto d = [&](const vec3d& q) { return c.kernel.distance(q); };
            const vec3d gradient{(d(p + vec3d{e, 0, 0}) - d(p - vec3d{e, 0, 0})) / (2 * e),
                                 (d(p + vec3d{0, e, 0}) - d(p - vec3d{0, e, 0})) / (2 * e),
                                 (d(p + vec3d{0, 0, e}) - d(p - vec3d{0, 0, e})) / (2 * e)};
            const vec3d n(c.kernel.normal(to_f(p)));
            wrong += !(std::abs(krs::length(n) - 1) < 1e-5);
            if (std::abs(krs::length(gradient) - 1) > 1e-6) continue;
            ++tested;
            wrong += !(krs::length(n - gradient) < 1e-3);
        }
        CHECK(wrong == 0);
        CHECK(tested > 3000);
    }
}

TEST_CASE("round_box: bound and bound_box hold inside points; the box is the outer box")
{
    for (const round_box_case& c : cases()) {
        std::mt19937_64 g(24);
        const krs::bounding_sphere b = c.kernel.bound();
        const krs::bounding_box box = c.kernel.bound_box();
        std::vector<vec3d> points = c.surface(g, 20000);
        int inside_points = 0, outside = 0;
        for (int i = 0; i < 20000; ++i) {
            const vec3d p = c.c + krs_test::in_ball(g, c.extent);
            if (c.reference(p) <= 0) points.push_back(p), ++inside_points;
        }
        for (const vec3d& p : points) {
            outside += !(krs::length(p - vec3d(b.center)) <= double(b.radius));
            outside += !(p.x >= box.lo.x && p.x <= box.hi.x && p.y >= box.lo.y && p.y <= box.hi.y && p.z >= box.lo.z &&
                         p.z <= box.hi.z);
        }
        CHECK(inside_points > 100);
        CHECK(outside == 0);
        const vec3d outer = c.inner + vec3d{c.r, c.r, c.r};
        CHECK(double(box.hi.x) - (c.c.x + outer.x) <= 1e-5 * (1 + std::abs(c.c.x)));
        CHECK((c.c.y - outer.y) - double(box.lo.y) <= 1e-5 * (1 + std::abs(c.c.y)));
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

// Domain repetition (krs/compose/repeated.hpp) against the explicit union of the copies, brute
// force in double over every copy within six cells of the point (or all of a count): equal for
// exact parts inside their cells and crossing into their neighbours (where the naive one-cell form
// is shown to overestimate), with counts per axis, of the union's sign and 1-Lipschitz on close
// pairs; a part whose field is only a bound never over the densely sampled distance; packets and
// doubles against the scalar path; refused layouts. Its
// GLSL runs on llvmpipe in test_glsl_field_types.cpp.

#include "krs/compose/placed.hpp"
#include "krs/compose/repeated.hpp"
#include "krs/kernels/box.hpp"
#include "krs/kernels/capsule.hpp"
#include "krs/kernels/plane.hpp"
#include "krs/kernels/sphere.hpp"

#include "support/rejects.hpp"
#include "support/random.hpp"

#include <doctest/doctest.h>

#include <algorithm>
#include <array>
#include <cmath>
#include <cstdio>
#include <limits>
#include <random>
#include <utility>
#include <vector>

namespace {

using krs::vec3d;
using krs::vec3f;
using krs_test::uniform;

// The union of the copies: every index within `window` cells of p's own (by the part's position
// alone, not the library's window) and within the counts, each copy's distance in double.
template <class F>
double union_of_copies(const F& part, const krs::repetition& r, const vec3d& p, int window = 6)
{
    const krs::repetition_axis axes[3] = {r.x, r.y, r.z};
    const double coords[3] = {p.x, p.y, p.z};
    std::array<int, 3> lo{}, hi{};
    for (int a = 0; a < 3; ++a) {
        const int own = int(std::lround(coords[a] / axes[a].period));
        lo[std::size_t(a)] = own - window, hi[std::size_t(a)] = own + window;
        if (axes[a].count != krs::repetition_axis::unlimited) {
            lo[std::size_t(a)] = std::max(lo[std::size_t(a)], 0);
            hi[std::size_t(a)] = std::min(hi[std::size_t(a)], axes[a].count - 1);
            if (lo[std::size_t(a)] > hi[std::size_t(a)]) lo[std::size_t(a)] = hi[std::size_t(a)] = (own < 0 ? 0 : axes[a].count - 1);
        }
    }
    double best = INFINITY;
    for (int i = lo[0]; i <= hi[0]; ++i)
        for (int j = lo[1]; j <= hi[1]; ++j)
            for (int k = lo[2]; k <= hi[2]; ++k)
                best = std::min(best, part.distance(p - vec3d{i * double(r.x.period), j * double(r.y.period),
                                                              k * double(r.z.period)}));
    return best;
}

vec3d point_in(std::mt19937_64& g, const vec3d& lo, const vec3d& hi)
{
    return {uniform(g, lo.x, hi.x), uniform(g, lo.y, hi.y), uniform(g, lo.z, hi.z)};
}

} // namespace

TEST_CASE("repetition of a part inside its cell equals the union of the copies, without end and by count")
{
    std::mt19937_64 g(91);
    const krs::sphere ball({0.05f, -0.04f, 0.03f}, 0.2f);
    const krs::box block({-0.03f, 0.02f, 0.0f}, {0.12f, 0.1f, 0.15f}); // half diagonal 0.217
    krs::repetition grid{{1.0f}, {1.1f}, {0.95f}};
    krs::repetition limited{{1.0f, 3}, {1.1f, 1}, {0.95f, 4}};
    struct layout { const char* name; krs::repetition r; vec3d lo, hi; };
    const layout layouts[] = {{"unlimited", grid, {-4, -4, -4}, {4, 4, 4}},
                              {"counts 3 x 1 x 4", limited, {-3, -2, -3}, {5, 3, 6}},
                              {"xz plane", {{1.0f}, {1.1f, 1}, {0.95f}}, {-4, -1, -4}, {4, 9, 4}}};
    for (const layout& l : layouts) {
        const krs::repeated balls(ball, l.r);
        const krs::repeated blocks(block, l.r);
        CHECK(balls.window_size() == (l.r.y.count == 1 ? 4 : 8)); // Quilez's neighbours: 2 per repeated axis
        double worst = 0;
        for (int i = 0; i < 20000; ++i) {
            const vec3d p = point_in(g, l.lo, l.hi);
            const vec3f pf(p);
            const double tolerance = 1e-6 * (1 + krs::length(p));
            worst = std::max(worst, std::abs(double(balls.distance(pf)) - union_of_copies(ball, l.r, vec3d(pf))) / tolerance);
            worst = std::max(worst, std::abs(double(blocks.distance(pf)) - union_of_copies(block, l.r, vec3d(pf))) / tolerance);
        }
        std::printf("repetition %-16s: window %d copies, |g - union| <= %.3g of 1e-6 (1 + |p|)\n", l.name,
                    balls.window_size(), worst);
        INFO(l.name);
        CHECK(worst <= 1.0);
    }
}

TEST_CASE("repetition of a part crossing its cell equals the union, keeps its sign and is 1-Lipschitz")
{
    std::mt19937_64 g(92);
    // A capsule from the cell's middle into the next cells (bound radius ~0.8 for a period of 1).
    const krs::capsule rod({-0.4f, 0.0f, 0.1f}, {0.9f, 0.35f, -0.2f}, 0.15f);
    for (const krs::repetition r : {krs::repetition{{1.0f}, {1.0f}, {1.0f}}, krs::repetition{{1.0f, 5}, {0.9f, 2}, {1.2f}}}) {
        const krs::repeated rods(rod, r);
        double worst_over = -INFINITY, worst_under = 0, worst_slope = 0, naive_over = 0;
        long sign_checked = 0, sign_wrong = 0;
        for (int i = 0; i < 20000; ++i) {
            const vec3d p = point_in(g, {-3, -3, -3}, {4, 3, 3});
            const vec3f pf(p);
            const double want = union_of_copies(rod, r, vec3d(pf));
            const double got = rods.distance(pf);
            worst_over = std::max(worst_over, got - want);
            worst_under = std::max(worst_under, want - got);
            if (std::abs(want) > 1e-5) {
                ++sign_checked;
                sign_wrong += (got < 0) != (want < 0);
            }
            // The naive form: the copy of the cell p is in (by the part's centre), alone.
            if (r.x.count == krs::repetition_axis::unlimited) {
                const vec3d c(rod.bound().center);
                const vec3d k{std::round((p.x - c.x) / r.x.period), std::round((p.y - c.y) / r.y.period),
                              std::round((p.z - c.z) / r.z.period)};
                const double naive = rod.distance(vec3d(pf) - vec3d{k.x * r.x.period, k.y * r.y.period, k.z * r.z.period});
                naive_over = std::max(naive_over, naive - want);
            }
            const vec3f qf(p + krs_test::random_direction(g) * uniform(g, 1e-3, 5e-2));
            worst_slope = std::max(worst_slope, (std::abs(double(rods.distance(pf)) - double(rods.distance(qf))) - 1e-6) /
                                                    krs::length(vec3d(pf) - vec3d(qf)));
        }
        std::printf("crossing rod (window %d): union - g <= %.3g, g - union <= %.3g, sign wrong %ld/%ld, slope <= "
                    "%.6f, naive form over by up to %.3g\n",
                    rods.window_size(), worst_under, worst_over, sign_wrong, sign_checked, worst_slope, naive_over);
        CHECK(worst_over <= 1e-6);
        CHECK(worst_under <= 1e-6);
        CHECK(sign_wrong == 0);
        CHECK(worst_slope <= 1.0 + 1e-4);
        // The scene is one where the naive form fails (so the checks above test the window).
        if (r.x.count == krs::repetition_axis::unlimited) CHECK(naive_over > 0.1);
    }
}

TEST_CASE("repetition of a part whose field is a bound, not its distance, never overestimates the distance")
{
    // A sheared ball (a placed field: its value is below its distance away from the axes the map
    // keeps) reaching into its neighbours, repeated along x; the union's surface sampled densely.
    std::mt19937_64 g(94);
    const krs::affine_map shear{{vec3d{1.6, 0.9, 0.0}, vec3d{0.0, 0.5, 0.0}, vec3d{0.0, 0.3, 0.7}}, {0.2, 0.0, 0.0}};
    const auto part = krs::placed(krs::sphere({0, 0, 0}, 0.5f), shear);
    const krs::repetition r{{1.0f}, {1.0f, 1}, {1.0f, 1}};
    const krs::repeated copies(part, r);
    std::vector<vec3d> surface;
    for (int k = -8; k <= 8; ++k)
        for (int i = 0; i < 6000; ++i) surface.push_back(shear.apply(krs_test::random_direction(g) * 0.5) + vec3d{double(k), 0, 0});
    double worst_over = -INFINITY;
    for (int i = 0; i < 1500; ++i) {
        const vec3d p = point_in(g, {-3, -2, -2}, {3, 2, 2});
        double sampled = INFINITY; // at least the true distance to the union's surface
        for (const vec3d& q : surface) sampled = std::min(sampled, krs::length(p - q));
        const double got = copies.distance(vec3f(p));
        if (got > 0) worst_over = std::max(worst_over, got - sampled);
    }
    std::printf("repeated sheared ball (window %d): g - sampled distance <= %.3g\n", copies.window_size(), worst_over);
    CHECK(copies.window_size() >= 2);
    CHECK(worst_over <= 1e-6);
}

TEST_CASE("repetition in packets and in double equals the scalar float path")
{
    using P = krs::packet_f;
    constexpr std::size_t W = krs::lane_count<P>;
    std::mt19937_64 g(93);
    const krs::repeated rods(krs::capsule({-0.4f, 0.0f, 0.1f}, {0.9f, 0.35f, -0.2f}, 0.15f),
                             krs::repetition{{1.0f, 4}, {0.9f}, {1.2f, 1}});
    long lanes = 0, equal = 0;
    double worst_double = 0;
    for (int k = 0; k < 256; ++k) {
        alignas(64) float x[W], y[W], z[W];
        for (std::size_t i = 0; i < W; ++i)
            x[i] = float(uniform(g, -3, 6)), y[i] = float(uniform(g, -4, 4)), z[i] = float(uniform(g, -2, 2));
        const P d = rods.distance(krs::vec3<P>{P::load_aligned(x), P::load_aligned(y), P::load_aligned(z)});
        for (std::size_t i = 0; i < W; ++i) {
            const vec3f p{x[i], y[i], z[i]};
            ++lanes;
            equal += krs::lane_at(d, i) == rods.distance(p);
            worst_double = std::max(worst_double, std::abs(rods.distance(vec3d(p)) - double(rods.distance(p))));
        }
    }
    CHECK(equal == lanes);
    CHECK(worst_double <= 1e-5);
}

TEST_CASE("repetition is refused a period that is not a positive length, a count below 1 and an unbounded part")
{
    const krs::sphere ball({0, 0, 0}, 0.3f);
    const float nan = std::numeric_limits<float>::quiet_NaN(), inf = std::numeric_limits<float>::infinity();
    for (const float period : {0.0f, -1.0f, nan, inf}) {
        CAPTURE(period);
        krs_test::rejects([&] { (void)krs::repeated(ball, {{period}, {1.0f}, {1.0f}}); }, "repetition.x.period");
        krs_test::rejects([&] { (void)krs::repeated(ball, {{1.0f}, {1.0f}, {period, 3}}); }, "repetition.z.period");
    }
    for (const int count : {0, -1, std::numeric_limits<int>::min()}) {
        CAPTURE(count);
        krs_test::rejects([&] { (void)krs::repeated(ball, {{1.0f}, {1.0f, count}, {1.0f}}); }, "repetition.y.count");
    }
    // A period under an eighth of the part's radius: a window of more than 17 cells per axis.
    krs_test::rejects([&] { (void)krs::repeated(ball, {{0.03f}, {1.0f}, {1.0f}}); }, "repetition.x.period");
    // An unbounded part (a plane's bound is unbounded) has no window.
    krs_test::rejects([&] { (void)krs::repeated(krs::plane({0, 1, 0}, 0.0f), {{1.0f}, {1.0f, 1}, {1.0f}}); },
                      "repeated part");
}

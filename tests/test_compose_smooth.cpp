// Smooth blends (krs/compose/smooth.hpp): the two forms against formulas written independently
// (Quilez's mix/clamp polynomial and the plain log-sum-exp, in long double), the surface shift
// they promise, the Lipschitz constant 1 on close pairs, packets and doubles against the scalar
// float path, and refused radii. Their GLSL runs on llvmpipe in test_glsl_field_types.cpp.

#include "krs/compose/smooth.hpp"
#include "krs/kernels/box.hpp"
#include "krs/kernels/sphere.hpp"

#include "support/rejects.hpp"
#include "support/random.hpp"

#include <doctest/doctest.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <limits>
#include <random>
#include <string>
#include <vector>

namespace {

using krs::vec3d;
using krs::vec3f;
using krs_test::uniform;

// Quilez's polynomial smooth minimum as his article writes it (a mix and a clamp), which is not
// how the library computes it (min minus a term).
long double quilez_smin(long double a, long double b, long double k)
{
    const long double h = std::clamp(0.5L + 0.5L * (b - a) / k, 0.0L, 1.0L);
    return b + (a - b) * h - k * h * (1.0L - h);
}
// -k ln(e^(-a/k) + e^(-b/k)), summed as written (long double holds e^(-a/k) for the ranges below).
long double log_sum_exp_smin(long double a, long double b, long double k)
{
    return -k * std::log(std::exp(-a / k) + std::exp(-b / k));
}
long double reference_smin(long double a, long double b, long double k, krs::blend_shape shape)
{
    return shape == krs::blend_shape::polynomial ? quilez_smin(a, b, k) : log_sum_exp_smin(a, b, k);
}

constexpr krs::blend_shape shapes[] = {krs::blend_shape::polynomial, krs::blend_shape::exponential};
constexpr krs::blend_operation operations[] = {krs::blend_operation::unite, krs::blend_operation::intersect,
                                               krs::blend_operation::subtract};
const char* name(krs::blend_shape s) { return s == krs::blend_shape::polynomial ? "polynomial" : "exponential"; }
const char* name(krs::blend_operation o)
{
    if (o == krs::blend_operation::unite) return "union";
    return o == krs::blend_operation::intersect ? "intersection" : "subtraction";
}

// A ball and a box that overlap, so every operation has a seam.
using blend = krs::smooth_blend<krs::sphere, krs::box>;
blend ball_and_block(krs::blend_operation operation, krs::smooth_blend_options options)
{
    return blend(krs::sphere({0.0f, 0.0f, 0.0f}, 0.6f), krs::box({0.5f, 0.1f, 0.0f}, {0.35f, 0.3f, 0.4f}), operation,
                 options);
}

// The hard operation's distance of the same parts, in double.
double hard(const blend& f, const vec3d& p)
{
    const double a = f.first().distance(p), b = f.second().distance(p);
    switch (f.operation()) {
    case krs::blend_operation::unite: return std::min(a, b);
    case krs::blend_operation::intersect: return std::max(a, b);
    case krs::blend_operation::subtract: break;
    }
    return std::max(a, -b);
}

} // namespace

TEST_CASE("smooth_min and smooth_max match Quilez's formula and the log-sum-exp, moving min by at most k/4 or k ln 2")
{
    std::mt19937_64 g(71);
    for (const krs::blend_shape shape : shapes) {
        double worst = 0, worst_max = 0;
        long outside_equal = 0, outside = 0;
        for (int i = 0; i < 20000; ++i) {
            const float k = float(std::pow(10.0, uniform(g, -2, 0)));
            // One pair in four inside the blend, the rest anywhere.
            const float a = float(uniform(g, -2, 2));
            const float b = i % 4 == 0 ? a + float(uniform(g, -k, k)) : float(uniform(g, -2, 2));
            const float s = krs::smooth_min(a, b, k, shape);
            const float m = krs::smooth_max(a, b, k, shape);
            const long double want = reference_smin(a, b, k, shape);
            const long double want_max = -reference_smin(-(long double)a, -(long double)b, k, shape);
            const double scale = 1.0 + std::abs(a) + std::abs(b);
            worst = std::max(worst, double(std::abs(s - want)) / scale);
            worst_max = std::max(worst_max, double(std::abs(m - want_max)) / scale);
            // The shift bounds, exactly as the header states them (float rounding of the term
            // allowed for: 2 ulp of the scale).
            const float shift = krs::smooth_blend_options{k, shape}.largest_shift();
            const float slack = 4.0f * std::numeric_limits<float>::epsilon() * float(scale);
            CHECK(s <= std::min(a, b) + slack);
            CHECK(s >= std::min(a, b) - shift - slack);
            CHECK(m >= std::max(a, b) - slack);
            CHECK(m <= std::max(a, b) + shift + slack);
            if (shape == krs::blend_shape::polynomial && std::abs(a - b) >= k) {
                ++outside;
                outside_equal += s == std::min(a, b) && m == std::max(a, b);
            }
        }
        std::printf("smooth blend %-11s: max |smin - reference| %.3g, |smax - reference| %.3g (of 1 + |a| + |b|)\n",
                    name(shape), worst, worst_max);
        INFO(name(shape));
        CHECK(worst <= 4e-7);
        CHECK(worst_max <= 4e-7);
        CHECK(outside_equal == outside); // the polynomial blend is local: exact min and max outside it
    }
}

TEST_CASE("smooth blends of fields are 1-Lipschitz and move the hard operation's surface by at most the stated shift")
{
    std::mt19937_64 g(72);
    for (const krs::blend_operation operation : operations)
        for (const krs::blend_shape shape : shapes)
            for (const float radius : {0.05f, 0.3f}) {
                const blend f = ball_and_block(operation, {radius, shape});
                const double shift = f.options().largest_shift();
                double worst_ratio = 0;
                long wrong_side = 0, samples = 0;
                for (int i = 0; i < 10000; ++i) {
                    // Near the seam: points in a box around both parts, pairs 1e-3 .. 5e-2 apart.
                    const vec3d x{uniform(g, -0.9, 1.1), uniform(g, -0.8, 0.8), uniform(g, -0.8, 0.8)};
                    const vec3d y = x + krs_test::random_direction(g) * uniform(g, 1e-3, 5e-2);
                    const vec3f xf(x), yf(y);
                    const double d = std::abs(double(f.distance(xf)) - double(f.distance(yf)));
                    worst_ratio = std::max(worst_ratio, (d - 2e-7) / krs::length(vec3d(xf) - vec3d(yf)));
                    // The solid: a union only grows (inside the hard union is inside), an
                    // intersection or subtraction only shrinks, each by at most `shift`.
                    const double h = hard(f, vec3d(xf)), s = f.distance(xf);
                    ++samples;
                    if (operation == krs::blend_operation::unite)
                        wrong_side += (h < -1e-6 && s >= 0) || (h > shift + 1e-6 && s <= 0);
                    else
                        wrong_side += (h > 1e-6 && s <= 0) || (h < -shift - 1e-6 && s >= 0);
                }
                std::printf("smooth %-12s %-11s radius %.2f: max |d(x) - d(y)| / |x - y| %.6f over 10^4 close pairs\n",
                            name(operation), name(shape), double(radius), worst_ratio);
                INFO(name(operation) << " " << name(shape) << " radius " << radius);
                CHECK(worst_ratio <= 1.0 + 1e-4);
                CHECK(worst_ratio > 0.5); // the pairs do sample the field's slope
                CHECK(wrong_side == 0);
                CHECK(samples == 10000);
            }
}

TEST_CASE("smooth blends in packets and in double equal the scalar float path")
{
    using P = krs::packet_f;
    constexpr std::size_t W = krs::lane_count<P>;
    std::mt19937_64 g(73);
    for (const krs::blend_operation operation : operations)
        for (const krs::blend_shape shape : shapes) {
            const blend f = ball_and_block(operation, {0.2f, shape});
            long lanes = 0, bit_equal = 0;
            double worst = 0, worst_double = 0;
            for (int k = 0; k < 256; ++k) {
                alignas(64) float x[W], y[W], z[W];
                for (std::size_t i = 0; i < W; ++i)
                    x[i] = float(uniform(g, -1, 1.2)), y[i] = float(uniform(g, -1, 1)), z[i] = float(uniform(g, -1, 1));
                const P d = f.distance(krs::vec3<P>{P::load_aligned(x), P::load_aligned(y), P::load_aligned(z)});
                for (std::size_t i = 0; i < W; ++i) {
                    const vec3f p{x[i], y[i], z[i]};
                    const float one = f.distance(p);
                    ++lanes;
                    bit_equal += krs::lane_at(d, i) == one;
                    worst = std::max(worst, double(std::abs(krs::lane_at(d, i) - one)));
                    // Double lanes: the same formula in double, against the long double reference
                    // of the parts' double distances.
                    const vec3d pd(p);
                    const long double a = f.first().distance(pd), b = f.second().distance(pd);
                    const long double k2 = f.options().radius;
                    const long double want =
                        operation == krs::blend_operation::unite ? reference_smin(a, b, k2, shape)
                        : operation == krs::blend_operation::intersect ? -reference_smin(-a, -b, k2, shape)
                                                                        : -reference_smin(-a, b, k2, shape);
                    worst_double = std::max(worst_double, double(std::abs(f.distance(pd) - want)));
                }
            }
            INFO(name(operation) << " " << name(shape));
            std::printf("smooth %-12s %-11s: packet lanes bit-equal %ld/%ld (max diff %.3g); "
                        "double against long double %.3g\n",
                        name(operation), name(shape), bit_equal, lanes, worst, worst_double);
            // The polynomial form uses only + - * / min max abs: the same operations per lane. The
            // exponential one calls xsimd's exp and log in packets and std's in scalars, each
            // within an ulp or two of exact.
            if (shape == krs::blend_shape::polynomial) CHECK(bit_equal == lanes);
            CHECK(worst <= 1e-6);
            CHECK(worst_double <= 1e-13);
        }
}

TEST_CASE("smooth blends nest and are refused a radius that is not a positive length")
{
    // A blend of blends stays a field: 1-Lipschitz on close pairs.
    const auto carved = krs::smooth_subtraction(krs::box({0, 0, 0}, {0.5f, 0.5f, 0.5f}), krs::sphere({0, 0, 0}, 0.65f),
                                                {0.08f, krs::blend_shape::exponential});
    const auto joined = krs::smooth_union(carved, krs::sphere({0, 0.7f, 0}, 0.25f), {0.15f});
    std::mt19937_64 g(74);
    double worst = 0;
    for (int i = 0; i < 10000; ++i) {
        const vec3d x{uniform(g, -1, 1), uniform(g, -1, 1.1), uniform(g, -1, 1)};
        const vec3f xf(x), yf(x + krs_test::random_direction(g) * uniform(g, 1e-3, 5e-2));
        worst = std::max(worst, (std::abs(double(joined.distance(xf)) - double(joined.distance(yf))) - 2e-7) /
                                    krs::length(vec3d(xf) - vec3d(yf)));
    }
    CHECK(worst <= 1.0 + 1e-4);
    CHECK(joined.distance(vec3f{0, 0, 0}) > 0.0f);   // the ball carved the box's centre away
    CHECK(joined.distance(vec3f{0, 0.7f, 0}) < 0.0f); // the added ball's centre is inside

    const krs::sphere a({0, 0, 0}, 1.0f), b({1, 0, 0}, 1.0f);
    for (const float radius : {0.0f, -0.1f, std::numeric_limits<float>::quiet_NaN(),
                               std::numeric_limits<float>::infinity(), 2e9f}) {
        CAPTURE(radius);
        krs_test::rejects([&] { (void)krs::smooth_union(a, b, {radius}); }, "smooth_blend_options.radius");
        krs_test::rejects([&] { (void)krs::smooth_subtraction(a, b, {radius, krs::blend_shape::exponential}); },
                          "smooth_blend_options.radius");
    }
    krs_test::rejects([&] { (void)krs::smooth_union(a, b, {0.1f, krs::blend_shape(7)}); },
                      "smooth_blend_options.shape");
}

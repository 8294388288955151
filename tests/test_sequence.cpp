// KRS distance (Algorithm 1) against the explicit 2^n expansion, and the properties that must
// hold where kernels are not separated: a subset of the expansion's terms, 1-Lipschitz, and a
// bound of its own zero set found by sampling.

#include "krs/expansion.hpp"
#include "krs/kernels/capsule.hpp"
#include "krs/kernels/plane.hpp"
#include "krs/kernels/sphere.hpp"
#include "krs/kernels/torus_capsule.hpp"
#include "krs/model/mirror_cloud.hpp"
#include "krs/sequence.hpp"
#include "support/grid.hpp"

#include "support/parity.hpp"
#include "support/random.hpp"
#include "support/swept_samples.hpp"

#include <doctest/doctest.h>

#include <algorithm>
#include <array>
#include <cmath>
#include <limits>
#include <random>
#include <variant>
#include <vector>

namespace {

using krs::vec3d;
using krs::vec3f;
using test_sequence = krs::sequence<krs::sphere, krs::torus_capsule>;

struct random_source {
    std::mt19937_64 engine;
    explicit random_source(std::uint64_t seed) : engine(seed) {}
    double uniform(double lo, double hi) { return krs_test::uniform(engine, lo, hi); }
    vec3d in_ball(double radius) { return krs_test::in_ball(engine, radius); }
    vec3d direction() { return krs_test::random_direction(engine); }
};

vec3f to_f(const vec3d& v) { return {float(v.x), float(v.y), float(v.z)}; }

// A random sphere or torus capsule near `center`, of size about `size`.
void add_random_kernel(test_sequence::builder& b, random_source& r, const vec3d& center, double size)
{
    if (r.uniform(0, 1) < 0.5) {
        b.kernel(krs::sphere(to_f(center + r.in_ball(size)), float(r.uniform(0.1, 0.4) * size)));
    } else {
        const vec3d a = center + r.in_ball(size), e = center + r.in_ball(size);
        const vec3d mid = (a + e) * 0.5 + r.in_ball(0.4 * krs::length(e - a));
        b.kernel(krs::torus_capsule(to_f(a), to_f(e), to_f(mid), float(r.uniform(0.05, 0.2) * size)));
    }
}

// A sequence whose kernels are separated by every mirror (the paper's assumption): each mirror
// is placed outside the bounding sphere of the expansion level below it, so L_i lies strictly on
// its negative side.
test_sequence separated_sequence(std::size_t n, std::uint64_t seed)
{
    random_source r(seed);
    test_sequence::builder b;
    add_random_kernel(b, r, {0, 0, 0}, 1.0);
    for (std::size_t i = 0; i < n; ++i) {
        const krs::bounding_sphere level_bound = b.build().bound();
        const vec3d m = r.direction();
        const double gap = r.uniform(0.02, 0.3) * level_bound.radius;
        const double c = krs::dot(m, vec3d(level_bound.center)) + level_bound.radius + gap;
        b.mirror(krs::mirror(to_f(m), float(c)));
        // A new kernel at this level now and then, anywhere near the level so far.
        if (r.uniform(0, 1) < 0.5) add_random_kernel(b, r, vec3d(level_bound.center), 0.5 * level_bound.radius);
    }
    return b.build();
}

// Random planes through random points: kernels are cut by mirrors (non-separated).
test_sequence random_plane_sequence(std::size_t n, std::uint64_t seed)
{
    random_source r(seed);
    test_sequence::builder b;
    add_random_kernel(b, r, {0, 0, 0}, 1.0);
    for (std::size_t i = 0; i < n; ++i) {
        b.mirror(krs::mirror::through(to_f(r.in_ball(1.5)), to_f(r.direction())));
        if (r.uniform(0, 1) < 0.6) add_random_kernel(b, r, r.in_ball(1.0), 1.0);
    }
    return b.build();
}

// Algorithm 1 written out level by level, with no early out and no fold prefix: every mirror
// folds, every kernel counts. The sequence's walk must give the same float, bit for bit.
template <class Sequence>
float full_walk(const Sequence& s, vec3f p)
{
    const std::size_t n = s.mirror_count();
    float d = std::numeric_limits<float>::infinity();
    for (std::size_t i = n + 1; i-- > 0;) {
        if (i < n) p = s.mirrors()[i].fold(p);
        for (std::uint32_t k = s.level_begin(i); k < s.level_begin(i + 1); ++k)
            d = std::min(d, std::visit([&](const auto& kernel) { return kernel.distance(p); }, s.kernels()[k]));
    }
    return d;
}

} // namespace

TEST_CASE("separated KRS: Algorithm 1 equals the minimum over all 2^n instances")
{
    for (std::size_t n : {1u, 4u, 8u, 12u}) {
        const test_sequence s = separated_sequence(n, 1000 + n);
        const auto e = krs::expand(s);
        REQUIRE(double(e.instances.size()) == s.instance_count());
        REQUIRE(e.instances.size() >= (std::size_t(1) << n));

        const double extent = s.bound().radius;
        random_source r(n);
        const int points = n <= 8 ? 100000 : 20000;
        double worst_double = 0, worst_float = 0, worst_relative = 0;
        for (int k = 0; k < points; ++k) {
            // Half the points near a random instance's kernel (where the answer is subtle), half
            // anywhere in the bound.
            vec3d x;
            if (k % 2 == 0) {
                const auto& in = e.instances[std::size_t(r.uniform(0, double(e.instances.size()))) % e.instances.size()];
                const krs::bounding_sphere kb =
                    std::visit([](const auto& kernel) { return kernel.bound(); }, s.kernels()[in.kernel]);
                x = in.to_world.apply(vec3d(kb.center) + r.in_ball(1.5 * kb.radius));
            } else {
                x = vec3d(s.bound().center) + r.in_ball(1.2 * extent);
            }
            const double reference = e.distance(x);
            const double fast = s.distance(x);
            const float fast_float = s.distance(to_f(x));
            worst_double = std::max(worst_double, std::abs(fast - reference) / extent);
            worst_float = std::max(worst_float, std::abs(double(fast_float) - reference) / extent);
            if (std::abs(reference) > 0.05 * extent)
                worst_relative = std::max(worst_relative, std::abs(fast - reference) / std::abs(reference));
        }
        // Mirror normals are stored as float, so |m| = 1 only to ~6e-8 and a reflection is an
        // isometry only to that precision: double evaluation agrees with the expansion to ~1e-7
        // of the extent, float evaluation adds its own rounding through n folds.
        INFO("n = " << n << ", instances = " << e.instances.size() << ", errors/extent: double " << worst_double
                    << ", float " << worst_float << ", double relative to |d| " << worst_relative);
        CHECK(worst_double <= 1e-6);
        CHECK(worst_float <= 1e-5);
        CHECK(worst_relative <= 1e-5);
    }
}

TEST_CASE("axis-aligned grid: Algorithm 1 equals the minimum over all 2^n instances")
{
    // A ring around a sphere, doubled alternately along x and z by mirrors placed beyond the
    // copies so far (the peer benchmark's grid): every kernel lives at level 0, so the walk never
    // has a finite distance to compare with a level's bound before the bottom.
    using grid_sequence = krs::axis_sequence<krs::sphere, krs::torus_capsule>;
    for (std::size_t n : {2u, 7u, 12u}) {
        grid_sequence::builder b;
        b.kernel(krs::torus_capsule({-1, 0, 0}, {1, 0, 0}, {0, 1, 0}, 0.2f));
        b.kernel(krs::torus_capsule({-1, 0, 0}, {1, 0, 0}, {0, -1, 0}, 0.2f));
        b.kernel(krs::sphere({0, 0, 0}, 0.35f));
        const std::array<double, 2> reach = krs_test::add_grid_mirrors(b, int(n), 1.2, 0.3);
        const grid_sequence s = b.build();
        const auto e = krs::expand(s);
        REQUIRE(e.instances.size() == 3 * (std::size_t(1) << n));
        random_source r(77 + n);
        double worst = 0;
        for (int k = 0; k < 4000; ++k) {
            const vec3d x{r.uniform(-3, reach[0] + 3), r.uniform(-2, 2), r.uniform(-3, reach[1] + 3)};
            worst = std::max(worst, std::abs(double(s.distance(to_f(x))) - e.distance(x)));
        }
        INFO("n = " << n);
        CHECK(worst <= 1e-5 * std::max(reach[0], reach[1]));
    }
}

TEST_CASE("a sequence holding a plane above bounded levels equals Algorithm 1 without early outs")
{
    // Separated kernels on levels 0 ... 3 (vertical mirrors beyond the copies so far), a ground
    // plane on level 4, more mirrors and kernels above: levels from 4 up have an unbounded L_i and
    // are walked without bound tests, levels below with them. Reference: Algorithm 1 written out
    // level by level with no early out (which never changes the result), compared bit for bit.
    using mixed = krs::sequence<krs::sphere, krs::torus_capsule, krs::plane>;
    for (std::uint64_t seed : {1u, 2u, 3u}) {
        random_source r(600 + seed);
        mixed::builder b;
        b.kernel(krs::sphere({0, 0.5f, 0}, 0.4f));
        b.kernel(krs::torus_capsule({-0.3f, 0, 0}, {0.3f, 0.9f, 0}, {0, 0.5f, 0.1f}, 0.05f));
        double reach = 1.0;
        for (int i = 0; i < 8; ++i) {
            const double angle = r.uniform(0, 6.283);
            b.mirror(krs::mirror(to_f(vec3d{std::cos(angle), 0, std::sin(angle)}), float(reach + 0.2)));
            reach = 2 * reach + 0.5;
            if (i == 3) b.kernel(krs::plane({0, 1, 0}, float(r.uniform(-0.5, 0.0))));
            else if (i % 2 == 0) b.kernel(krs::sphere(to_f(r.in_ball(0.5)), float(r.uniform(0.1, 0.4))));
        }
        const mixed s = b.build();
        for (int k = 0; k < 3000; ++k) {
            const vec3f x = to_f(r.in_ball(2 * reach));
            INFO("seed " << seed);
            REQUIRE(s.distance(x) == full_walk(s, x));
        }
    }
}

TEST_CASE("the bounding box holds every instance of the expansion, and is flat for a flat grid")
{
    // Every instance's extreme points (the kernel's spine moved by its radius along each axis,
    // from its construction parameters), placed by the expansion's isometries (in double, not by
    // the box's corner reflections), lie inside the box. (The box is now tighter than an
    // instance's bounding sphere: tests/test_bounds.cpp.)
    const auto holds_all = [](const auto& s) {
        const auto e = krs::expand(s);
        const krs::bounding_box box = s.bound_box();
        REQUIRE(box.is_bounded());
        int outside = 0;
        for (const auto& in : e.instances) {
            const std::vector<vec3d> points =
                std::visit([](const auto& k) { return krs_test::reference_points(k, 64); }, s.kernels()[in.kernel]);
            for (const vec3d& p : points) {
                const vec3d c = in.to_world.apply(p);
                outside += !(c.x >= box.lo.x && c.y >= box.lo.y && c.z >= box.lo.z && c.x <= box.hi.x &&
                             c.y <= box.hi.y && c.z <= box.hi.z);
            }
        }
        CHECK(outside == 0);
        return box;
    };
    for (std::size_t n : {0u, 4u, 9u}) holds_all(separated_sequence(n, 900 + n));
    // The grid of rings: 2^10 copies over 96 x 96 in x and z, 2.4 high; its sphere's box is as tall as wide.
    krs::axis_sequence<krs::sphere, krs::torus_capsule>::builder b;
    b.kernel(krs::torus_capsule({-1, 0, 0}, {1, 0, 0}, {0, 1, 0}, 0.2f));
    b.kernel(krs::sphere({0, 0, 0}, 0.35f));
    const std::array<double, 2> reach = krs_test::add_grid_mirrors(b, 10, 1.2, 0.3);
    const auto grid = b.build();
    const krs::bounding_box box = holds_all(grid);
    CHECK(box.hi.y - box.lo.y <= 2.5f);
    CHECK(box.hi.x - box.lo.x <= float(reach[0] + 1.3));
    CHECK(krs::box_around(grid.bound()).hi.y > 40.0f);
    // An unbounded kernel makes an unbounded box.
    using with_plane = krs::sequence<krs::sphere, krs::plane>;
    with_plane::builder pb;
    pb.kernel(krs::sphere({0, 1, 0}, 0.5f));
    pb.mirror(krs::mirror({1, 0, 0}, 2.0f));
    pb.kernel(krs::plane({0, 1, 0}, 0.0f));
    CHECK(!pb.build().bound_box().is_bounded());
}

TEST_CASE_TEMPLATE("axis mirrors: the fold prefix applied axis by axis equals folding level by level", T, float,
                   krs::packet_f)
{
    // Mirrors on all three axes, folding either side, kernels at level 0 and (in odd trials) at
    // one middle level: the walk down to the highest kernel level is folds alone, which the
    // sequence applies per axis. Reference: Algorithm 1 written out level by level, no early out
    // (which never changes the result), compared bit for bit.
    using axis_scene = krs::axis_sequence<krs::sphere, krs::torus_capsule>;
    constexpr std::size_t W = krs::lane_count<T>;
    random_source r(404);
    krs_test::parity same{"axis mirrors: prefix folds against level by level", 12.0}; // points in [-12, 12]^3
    int disagreements = 0;
    for (int trial = 0; trial < 12; ++trial) {
        axis_scene::builder b;
        b.kernel(krs::sphere({0.2f, 0.1f, -0.3f}, 0.25f));
        b.kernel(krs::torus_capsule({-0.5f, 0, 0}, {0.5f, 0.1f, 0}, {0, 0.4f, 0.1f}, 0.08f));
        const std::size_t n = 4 + std::size_t(trial) * 3;
        const std::size_t middle = trial % 2 ? n / 2 : 0;
        for (std::size_t i = 0; i < n; ++i) {
            b.mirror(krs::axis_mirror(int(r.engine() % 3), float(r.uniform(-4, 4)), r.engine() % 4 != 0));
            if (middle != 0 && i + 1 == middle) b.kernel(krs::sphere({1, 0.5f, 0}, 0.3f));
        }
        const axis_scene s = b.build();
        for (int q = 0; q < 200; ++q) {
            alignas(64) float c[3][W];
            for (std::size_t i = 0; i < W; ++i)
                for (int a = 0; a < 3; ++a) c[a][i] = float(r.uniform(-12, 12));
            krs::vec3<T> p;
            if constexpr (std::floating_point<T>)
                p = {c[0][0], c[1][0], c[2][0]};
            else
                p = {T::load_aligned(c[0]), T::load_aligned(c[1]), T::load_aligned(c[2])};
            const T d = s.distance(p);
            for (std::size_t i = 0; i < W; ++i)
                if (!same.agree(krs::lane_at(d, i), full_walk(s, vec3f{c[0][i], c[1][i], c[2][i]}))) ++disagreements;
        }
    }
    same.report();
    CHECK(disagreements == 0);
}

TEST_CASE_TEMPLATE("distances of K points in lockstep equal K separate walks", T, float, krs::packet_f)
{
    // A separated sequence with kernels at many levels: its points leave the walk at different
    // levels (the early out), so the lockstep walk must keep each point's own exit.
    constexpr std::size_t W = krs::lane_count<T>;
    for (std::size_t n : {0u, 3u, 9u}) {
        const test_sequence s = separated_sequence(n, 500 + n);
        const auto e = krs::expand(s);
        const double extent = s.bound().radius;
        krs_test::parity same{"lockstep against separate walks, n = " + std::to_string(n), 3 * extent};
        int disagreements = 0;
        random_source r(n + 3);
        double worst = 0;
        for (int trial = 0; trial < 300; ++trial) {
            std::array<krs::vec3<T>, 3> points;
            alignas(64) float c[3][3][W];
            for (std::size_t k = 0; k < 3; ++k) {
                // Near and far: some lanes stop at the first level, others walk to the bottom.
                for (std::size_t i = 0; i < W; ++i) {
                    const vec3d x = vec3d(s.bound().center) + r.in_ball(extent * r.uniform(0.1, 3.0));
                    c[k][0][i] = float(x.x), c[k][1][i] = float(x.y), c[k][2][i] = float(x.z);
                }
                if constexpr (std::floating_point<T>)
                    points[k] = {c[k][0][0], c[k][1][0], c[k][2][0]};
                else
                    points[k] = {T::load_aligned(c[k][0]), T::load_aligned(c[k][1]), T::load_aligned(c[k][2])};
            }
            const std::array<T, 3> together = s.template distances<T, 3>(points);
            for (std::size_t k = 0; k < 3; ++k) {
                const T alone = s.distance(points[k]);
                for (std::size_t i = 0; i < W; ++i) {
                    if (!same.agree(krs::lane_at(together[k], i), krs::lane_at(alone, i))) ++disagreements;
                    // And the brute-force minimum over every instance (the early outs changed nothing).
                    const vec3d x{c[k][0][i], c[k][1][i], c[k][2][i]};
                    worst = std::max(worst, std::abs(double(krs::lane_at(together[k], i)) - e.distance(x)) / extent);
                }
            }
        }
        same.report();
        INFO("n = " << n);
        CHECK(disagreements == 0);
        CHECK(worst <= 1e-5);
    }
}

TEST_CASE("non-separated KRS: a subset of the expansion's terms, 1-Lipschitz, bound of its zero set")
{
    for (std::uint64_t seed : {1u, 2u, 3u}) {
        const std::size_t n = 6 + 2 * seed;
        const test_sequence s = random_plane_sequence(n, seed);
        const auto e = krs::expand(s);
        random_source r(seed * 77);
        const double extent = 4.0;

        // Never below the minimum over all instances: Algorithm 1 picks some of them. (Up to the
        // ~1e-7 relative isometry error of float-stored mirror normals.)
        for (int k = 0; k < 20000; ++k) {
            const vec3d x = r.in_ball(extent);
            REQUIRE(s.distance(x) >= e.distance(x) - 1e-6);
        }

        // 1-Lipschitz on close pairs.
        for (int k = 0; k < 100000; ++k) {
            const vec3d a = r.in_ball(extent);
            const vec3d b = a + r.direction() * r.uniform(1e-6, 1e-2);
            REQUIRE(std::abs(s.distance(a) - s.distance(b)) <= krs::length(a - b) * (1 + 1e-9) + 1e-12);
        }

        // Points of the zero set by bisection on segments whose ends differ in sign; then the
        // field at any point must not exceed the distance to any of them.
        std::vector<vec3d> surface;
        while (surface.size() < 2000) {
            vec3d a = r.in_ball(extent), b = a + r.direction() * 0.5;
            double fa = s.distance(a), fb = s.distance(b);
            if ((fa > 0) == (fb > 0)) continue;
            for (int it = 0; it < 60; ++it) {
                const vec3d m = (a + b) * 0.5;
                const double fm = s.distance(m);
                if ((fm > 0) == (fa > 0)) a = m, fa = fm;
                else b = m, fb = fm;
            }
            surface.push_back((a + b) * 0.5);
        }
        for (int k = 0; k < 5000; ++k) {
            const vec3d x = r.in_ball(extent);
            double nearest = 1e30;
            for (const vec3d& p : surface) nearest = std::min(nearest, krs::length(x - p));
            REQUIRE(std::abs(s.distance(x)) <= nearest + 1e-9);
        }
    }
}

TEST_CASE_TEMPLATE("the fold: the scalar branch and the packet's max give the same point, the reflection or none", P,
                   krs::packet_f, krs::packet_d)
{
    // The scalar fold branches on 2e > 0 and the packet fold multiplies by max(2e, 0): one lane
    // each way must agree bit for bit (up to the sign of a zero coordinate; both are built here
    // with the same contraction setting), and both with the closed form x - 2 max(m . x - c, 0) m
    // in double. A quarter of the points lie on the plane (up to rounding) and a quarter within
    // 1e-6 of it, where the sign of e decides; the others anywhere within 2 of it.
    using S = krs::scalar_t<P>;
    constexpr std::size_t lanes = krs::lane_count<P>;
    random_source r(21);
    int folded = 0, kept = 0;
    for (int k = 0; k < 2000; ++k) {
        const krs::mirror m(vec3f(r.direction()), float(r.uniform(-1, 1)));
        const vec3d n(m.normal);
        alignas(64) S xs[lanes], ys[lanes], zs[lanes];
        for (std::size_t i = 0; i < lanes; ++i) {
            const double along = i % 4 == 0 ? 0.0 : (i % 4 == 1 ? r.uniform(-1e-6, 1e-6) : r.uniform(-2, 2));
            const vec3d w = r.in_ball(2.0), tangent = w - n * krs::dot(n, w);
            const vec3d v = n * (double(m.offset) + along) + tangent;
            xs[i] = S(v.x), ys[i] = S(v.y), zs[i] = S(v.z);
        }
        const krs::vec3<P> packet = m.fold(krs::vec3<P>{P::load_aligned(xs), P::load_aligned(ys), P::load_aligned(zs)});
        for (std::size_t i = 0; i < lanes; ++i) {
            const krs::vec3<S> x{xs[i], ys[i], zs[i]};
            const krs::vec3<S> scalar = m.fold(x);
            REQUIRE(scalar.x == krs::lane_at(packet.x, i));
            REQUIRE(scalar.y == krs::lane_at(packet.y, i));
            REQUIRE(scalar.z == krs::lane_at(packet.z, i));
            const vec3d xd(x);
            const double e = krs::dot(n, xd) - double(m.offset);
            const vec3d exact = xd - n * (2.0 * std::max(e, 0.0));
            REQUIRE(krs::length(vec3d(scalar) - exact) <= 1e-6 * (1.0 + krs::length(xd)));
            (e > 0 ? folded : kept) += 1;
        }
    }
    CHECK(folded > 1000 * int(lanes) / 4);
    CHECK(kept > 1000 * int(lanes) / 4);
}

TEST_CASE_TEMPLATE("packet lanes equal the scalar distance", P, krs::packet_f, krs::packet_d)
{
    using S = krs::scalar_t<P>;
    constexpr std::size_t lanes = krs::lane_count<P>;
    const test_sequence s = random_plane_sequence(10, 5);
    random_source r(9);
    for (int k = 0; k < 500; ++k) {
        alignas(64) S xs[lanes], ys[lanes], zs[lanes];
        for (std::size_t i = 0; i < lanes; ++i) {
            const vec3d v = r.in_ball(3.0);
            xs[i] = S(v.x), ys[i] = S(v.y), zs[i] = S(v.z);
        }
        const krs::vec3<P> p{P::load_aligned(xs), P::load_aligned(ys), P::load_aligned(zs)};
        const P d = s.distance(p);
        for (std::size_t i = 0; i < lanes; ++i) {
            const S scalar = s.distance(krs::vec3<S>{xs[i], ys[i], zs[i]});
            REQUIRE(krs::lane_at(d, i) == doctest::Approx(scalar).epsilon(1e-6));
        }
    }
}

TEST_CASE("locate: the kernel-space point maps back to the query, its kernel gives the distance")
{
    const test_sequence s = random_plane_sequence(12, 11);
    random_source r(3);
    krs_test::parity same{"located kernel against the field", 3.0}; // points in the ball of radius 3
    int disagreements = 0;
    for (int k = 0; k < 20000; ++k) {
        const vec3d x = r.in_ball(3.0);
        const krs::location<double> where = s.locate(x);
        REQUIRE(where.distance == doctest::Approx(s.distance(x)).epsilon(1e-12));
        REQUIRE(s.kernel_level(where.kernel) == where.level);
        const double d = std::visit([&](const auto& kernel) { return kernel.distance(where.kernel_point); },
                                    s.kernels()[where.kernel]);
        if (!same.agree(d, where.distance)) ++disagreements;
        // Only reflections at or above the kernel's level were taken on the way to it.
        // (R R x = x up to the float-stored normal's deviation from unit length.)
        REQUIRE(krs::length(s.to_world_point(where, where.kernel_point) - x) <= 1e-5);
    }
    same.report();
    CHECK(disagreements == 0);
}

TEST_CASE("normals: the kernel normal carried back by the reflections is the field's gradient")
{
    const test_sequence s = separated_sequence(8, 21);
    random_source r(5);
    const double h = 1e-6;
    int compared = 0;
    for (int k = 0; k < 4000; ++k) {
        const vec3d x = vec3d(s.bound().center) + r.in_ball(s.bound().radius);
        // Central differences; where they do not form a unit vector, x sits on a crease of the
        // field (equidistant from two instances) and no single normal exists.
        const vec3d g{(s.distance(x + vec3d{h, 0, 0}) - s.distance(x - vec3d{h, 0, 0})) / (2 * h),
                      (s.distance(x + vec3d{0, h, 0}) - s.distance(x - vec3d{0, h, 0})) / (2 * h),
                      (s.distance(x + vec3d{0, 0, h}) - s.distance(x - vec3d{0, 0, h})) / (2 * h)};
        if (std::abs(krs::length(g) - 1) > 1e-4) continue;
        ++compared;
        REQUIRE(krs::length(s.normal(x) - g) <= 1e-4);
    }
    CHECK(compared >= 3600);
}

TEST_CASE("sequence validation names the parameter")
{
    test_sequence::builder b;
    CHECK_THROWS_WITH_AS(b.build(), doctest::Contains("sequence.kernels"), krs::invalid_parameter);
    CHECK_THROWS_WITH_AS(krs::mirror({0, 0, 0}, 1.0f), doctest::Contains("mirror.normal"), krs::invalid_parameter);
    CHECK_THROWS_WITH_AS(krs::mirror({1, 0, 0}, std::nanf("")), doctest::Contains("mirror.offset"), krs::invalid_parameter);
    CHECK_THROWS_WITH_AS(krs::mirror::through({0, INFINITY, 0}, {1, 0, 0}), doctest::Contains("mirror.point"),
                         krs::invalid_parameter);
    b.kernel(krs::sphere({0, 0, 0}, 1));
    for (std::size_t i = 0; i < test_sequence::max_levels; ++i) b.mirror(krs::mirror({1, 0, 0}, float(i + 2)));
    CHECK_THROWS_WITH_AS(b.mirror(krs::mirror({1, 0, 0}, 1)), doctest::Contains("sequence.mirror"), krs::invalid_parameter);
    // 2^64 instances: expansion refuses before allocating.
    const test_sequence deep = b.build();
    CHECK(deep.instance_count() == std::ldexp(1.0, 64));
    CHECK_THROWS_WITH_AS(krs::expand(deep), doctest::Contains("max_instances"), krs::invalid_parameter);
}

TEST_CASE("the builder rechecks mirrors and kernels whose public fields were set directly")
{
    // Set after construction, these went into the walk unchecked: an axis of 7 indexed past the
    // fold prefix's three lists, a normal of length 2 doubled every fold, a NaN position made every
    // distance NaN, a plane normal of length 2 overestimated, and a capsule kept its old axis.
    krs::axis_sequence<krs::sphere>::builder axis_builder;
    axis_builder.kernel(krs::sphere({0, 0, 0}, 0.5f));
    krs::axis_mirror wild(0, 1.5f);
    wild.axis = 7;
    CHECK_THROWS_WITH_AS(axis_builder.mirror(wild), doctest::Contains("axis_mirror.axis"), krs::invalid_parameter);
    krs::axis_mirror unplaced(0, 1.5f);
    unplaced.twice_position = NAN;
    CHECK_THROWS_WITH_AS(axis_builder.mirror(unplaced), doctest::Contains("axis_mirror.position"), krs::invalid_parameter);
    krs::axis_mirror far(0, 1.5f);
    far.twice_position = 6e9f;
    CHECK_THROWS_WITH_AS(axis_builder.mirror(far), doctest::Contains("axis_mirror.position"), krs::invalid_parameter);
    krs::axis_mirror turned(0, 1.5f);
    turned.axis = 2; // normal and offset still say x
    CHECK_THROWS_WITH_AS(axis_builder.mirror(turned), doctest::Contains("axis_mirror.normal"), krs::invalid_parameter);

    // A general mirror's normal is normalized, as its constructor does: the walk then equals the
    // expansion of the same plane built properly.
    using plane_sequence = krs::sequence<krs::sphere, krs::plane, krs::capsule>;
    krs::mirror stretched({0, 0, 1}, 0.5f);
    stretched.normal = {0, 0, 2};
    krs::plane steep({0, 1, 0}, -3.0f);
    steep.normal_direction = {0, 2, 0};
    krs::capsule moved({1, 0, 0}, {1, 1, 0}, 0.1f);
    moved.b = {1, 0, 1}; // the cached axis still points along y
    plane_sequence::builder direct, proper;
    direct.kernel(krs::sphere({0.2f, 0, 0}, 0.2f)).kernel(moved).mirror(stretched).kernel(steep);
    proper.kernel(krs::sphere({0.2f, 0, 0}, 0.2f))
        .kernel(krs::capsule({1, 0, 0}, {1, 0, 1}, 0.1f))
        .mirror(krs::mirror({0, 0, 1}, 0.5f))
        .kernel(krs::plane({0, 1, 0}, -3.0f));
    const plane_sequence a = direct.build(), b = proper.build();
    random_source g(23);
    for (int k = 0; k < 2000; ++k) {
        const vec3f p{float(g.uniform(-3, 3)), float(g.uniform(-3, 3)), float(g.uniform(-3, 3))};
        REQUIRE(a.distance(p) == b.distance(p));
    }
    krs::sphere lost({0, 0, 0}, 1.0f);
    lost.center.x = NAN;
    CHECK_THROWS_WITH_AS(plane_sequence::builder().kernel(lost), doctest::Contains("sphere.center"), krs::invalid_parameter);
    // Objects that came through their constructors are kept bit for bit.
    const krs::mirror turned_plane({0.3f, 0.1f, 0.9f}, 0.7f);
    CHECK(turned_plane.checked().normal.x == turned_plane.normal.x);
    CHECK(turned_plane.checked().normal.y == turned_plane.normal.y);
    CHECK(turned_plane.checked().normal.z == turned_plane.normal.z);
}

TEST_CASE("sequence memory grows with n and the kernels: not with the 2^n instances")
{
    using seq = krs::sequence<krs::sphere, krs::torus_capsule>;
    const auto build = [](int n) {
        seq::builder b;
        b.kernel(krs::sphere({0.3f, 1.0f, 0}, 0.2f));
        b.kernel(krs::torus_capsule({0, 0, 0}, {0.3f, 1.0f, 0}, {0.05f, 0.5f, 0}, 0.05f));
        for (int i = 0; i < n; ++i) b.mirror(krs::mirror({std::cos(0.7f * float(i)), 0, std::sin(0.7f * float(i))}, 2.0f + 2.5f * float(i)));
        return b.build();
    };
    for (int n : {8, 16, 32, 64}) {
        const seq s = build(n);
        // The contents, counted element by element: a lower bound; vectors hold at most twice
        // their size (a generous bound on their growth), plus one allocation's rounding.
        const std::size_t contents = sizeof(seq) + std::size_t(n) * sizeof(krs::mirror) + 2 * sizeof(seq::kernel_variant) +
                                     2 * sizeof(std::uint32_t) + std::size_t(n + 2) * sizeof(std::uint32_t) +
                                     std::size_t(n) * sizeof(krs::bounding_sphere);
        CAPTURE(n);
        CHECK(s.memory_bytes() >= contents);
        CHECK(s.memory_bytes() <= 2 * contents);
        if (n <= 32) CHECK(s.memory_bytes() < 64 * 1024); // issue 9: "KRS memory stays under 64 KiB"
        CHECK(s.instance_count() == doctest::Approx(std::ldexp(2.0, n)));
    }
}

namespace {

// KRS paper section 5, figure 5: mirrors aligned with the axes repeat the kernel on a lattice the
// eye reads at once; mirrors turned at random ("planes of reflection selected so that the eye can
// only be near to a few of them") do not. The clouds are krs_scenes' (krs/model/mirror_cloud.hpp),
// with the seed of the random normals varied.
template <class Mirror>
std::vector<vec3d> cloud_centers(const krs::model::sphere_cloud<Mirror>& cloud)
{
    const auto e = krs::expand(cloud);
    std::vector<vec3d> centers;
    for (const auto& in : e.instances)
        centers.push_back(in.to_world.apply(vec3d(std::get<krs::sphere>(cloud.kernels()[in.kernel]).center)));
    return centers;
}

// Visible repetition of a set of instance positions: the highest peak of their autocorrelation
// away from 0, i.e. the largest number of ordered pairs (i, j) whose offset p_i - p_j falls in one
// cell of a grid of `cell` (a motif repeated by a translation t makes a peak at t), divided by N.
// 1 means every instance has a copy at the same offset (a lattice direction); a cloud whose
// offsets never repeat scores about 1 / N.
double repetition(const std::vector<vec3d>& points, double cell)
{
    std::vector<std::array<long long, 3>> keys;
    keys.reserve(points.size() * points.size());
    for (const vec3d& a : points)
        for (const vec3d& b : points) {
            const vec3d v = (a - b) / cell;
            const std::array<long long, 3> key{std::llround(v.x), std::llround(v.y), std::llround(v.z)};
            if (key != std::array<long long, 3>{0, 0, 0}) keys.push_back(key);
        }
    std::sort(keys.begin(), keys.end());
    std::size_t best = 0;
    for (std::size_t i = 0, j; i < keys.size(); i = j) {
        for (j = i; j < keys.size() && keys[j] == keys[i];) ++j;
        best = std::max(best, j - i);
    }
    return double(best) / double(points.size());
}

} // namespace

TEST_CASE("unaligned mirrors hide symmetry: the instances' autocorrelation peak is far lower than with aligned ones")
{
    constexpr int doublings = 9; // 512 spheres, as in figure 5
    double lowest_aligned = 1e30, highest_scattered = 0;
    for (std::uint64_t seed = 1; seed <= 8; ++seed) {
        krs::model::mirror_cloud_parameters parameters;
        parameters.doublings = doublings;
        parameters.seed = std::uint32_t(seed);
        const std::vector<vec3d> centers[2] = {cloud_centers(krs::model::build_aligned_cloud(parameters)),
                                               cloud_centers(krs::model::build_scattered_cloud(parameters))};
        double score[2];
        for (int scattered = 0; scattered < 2; ++scattered) {
            REQUIRE(centers[scattered].size() == std::size_t(1) << doublings);
            // Offsets equal within a fifth of the sphere's radius read as the same to the eye.
            score[scattered] = repetition(centers[scattered], 0.08);
        }
        MESSAGE("seed ", seed, ": repetition aligned ", score[0], ", scattered ", score[1]);
        lowest_aligned = std::min(lowest_aligned, score[0]);
        highest_scattered = std::max(highest_scattered, score[1]);
    }
    MESSAGE("over 8 seeds: lowest aligned ", lowest_aligned, ", highest scattered ", highest_scattered);
    // A product of three translation sets: at least half the spheres repeat at one axis offset
    // (each of the 3 mirrors along an axis pairs 4 of the 8 coordinates), for every seed.
    CHECK(lowest_aligned >= 0.4);
    // Random mirrors: no offset repeats for more than a few percent of the spheres.
    CHECK(highest_scattered <= 0.05);
    CHECK(lowest_aligned >= 10 * highest_scattered);
    // The builder's parameters are checked before anything is built.
    for (const int bad : {-1, 21}) {
        krs::model::mirror_cloud_parameters p;
        p.doublings = bad;
        CHECK_THROWS_WITH_AS(krs::model::build_scattered_cloud(p), doctest::Contains("mirror_cloud.doublings"), krs::invalid_parameter);
    }
    for (const float bad : {0.0f, -0.1f, std::numeric_limits<float>::quiet_NaN()}) {
        krs::model::mirror_cloud_parameters p;
        p.gap = bad;
        CHECK_THROWS_WITH_AS(krs::model::build_aligned_cloud(p), doctest::Contains("mirror_cloud.gap"), krs::invalid_parameter);
    }
    krs::model::mirror_cloud_parameters p;
    p.radius = -1.0f;
    CHECK_THROWS_WITH_AS(krs::model::build_aligned_cloud(p), doctest::Contains("sphere.radius"), krs::invalid_parameter);
}

// Numerical stability on hard cases (issue 10's list, for the fields and tracer that exist so far):
// points on and 1 ulp off mirror planes, coplanar and parallel mirrors, mirrors through kernel
// centers, deep sequences (n = 32, 64) in float against double, scenes far from the origin and at
// tiny scales, degenerate kernels. Each case asserts a property against an independent reference.
// Then the parameter magnitude policy (krs/core/validate.hpp, docs/stability.md): each limit just
// inside and just outside, and the fuzzers' crashers as named regression tests.

#include "krs/expansion.hpp"
#include "krs/fractal/fold_steps.hpp"
#include "krs/fractal/kifs.hpp"
#include "krs/fractal/kifs_presets.hpp"
#include "krs/fractal/log_tilings.hpp"
#include "krs/fractal/shell_presets.hpp"
#include "krs/fractal/similar_shell.hpp"
#include "krs/kernels/kernels.hpp"
#include "krs/model/coral.hpp"
#include "krs/model/forest.hpp"
#include "krs/model/grass.hpp"
#include "krs/model/terrain.hpp"
#include "krs/model/tree.hpp"
#include "krs/sequence.hpp"
#include "krs/trace/sphere_trace.hpp"

#include "support/figures.hpp"
#include "support/random.hpp"

#include <doctest/doctest.h>

#include <cmath>
#include <functional>
#include <limits>
#include <random>
#include <string>
#include <vector>

namespace {
using krs::vec3d;
using krs::vec3f;
using scene = krs::sequence<krs::sphere, krs::torus_capsule, krs::plane>;

using krs_test::in_ball;
using krs_test::uniform;

} // namespace

#if defined(KRS_TEST_COMPILER) && defined(KRS_TEST_FLAGS)
TEST_CASE("stability figures: the build that measured them")
{
    // docs/stability.md states these next to its figures; scripts/stability_figures.py compares
    // them before it compares the figures.
    KRS_FIGURE("build.compiler", KRS_TEST_COMPILER);
    KRS_FIGURE("build.flags", KRS_TEST_FLAGS);
    // The figures are an unfused build's, as the flags say: here a*b + c rounds the product
    // (1 + 2^-11 + 2^-24 to 1 + 2^-11) before the sum, where an fma would keep its last bit. Only a
    // build with FMA instructions and contraction on can fail this.
    volatile float a = 1.0f + 0x1p-12f, b = 1.0f + 0x1p-12f, c = -1.0f;
    CHECK(a * b + c == 0x1p-11f);
}
#endif

TEST_CASE("points on and one ulp off a mirror plane: the fold is continuous there")
{
    // A kernel crossing the mirror x = 1 (non-separated), so both sides matter.
    scene::builder b;
    b.kernel(krs::sphere({0.8f, 0.3f, 0}, 0.5f));
    b.mirror(krs::mirror({1, 0, 0}, 1.0f));
    const scene s = b.build();
    std::mt19937_64 g(1);
    int moved = 0;
    double worst_step = 0;
    for (int k = 0; k < 10000; ++k) {
        const float y = float(uniform(g, -1, 1)), z = float(uniform(g, -1, 1));
        const vec3f on{1.0f, y, z};
        const vec3f above{std::nextafter(1.0f, 2.0f), y, z}, below{std::nextafter(1.0f, 0.0f), y, z};
        const float d = s.distance(on);
        REQUIRE(std::isfinite(d));
        // 1-Lipschitz across the plane, to within float rounding of the sphere's distance.
        REQUIRE(std::abs(s.distance(above) - d) <= 2 * 1.2e-7f + 4e-7f);
        REQUIRE(std::abs(s.distance(below) - d) <= 2 * 1.2e-7f + 4e-7f);
        worst_step = std::max({worst_step, double(std::abs(s.distance(above) - d)), double(std::abs(s.distance(below) - d))});
        // On the plane, the point and its reflection are the same point.
        const krs::mirror& m = s.mirrors()[0];
        if (krs::length(m.fold(on) - on) != 0.0f) ++moved;
    }
    CHECK(moved == 0);
    KRS_FIGURE("on_plane.moved", moved);
    KRS_FIGURE("on_plane.worst_step", worst_step);
}

TEST_CASE("coplanar, parallel and kernel-centered mirrors keep the field a finite 1-Lipschitz bound")
{
    scene::builder b;
    b.kernel(krs::torus_capsule({0, 0, 0}, {1, 1, 0}, {0.3f, 0.6f, 0.1f}, 0.1f));
    b.mirror(krs::mirror({1, 0, 0}, 0.5f));
    b.mirror(krs::mirror({1, 0, 0}, 0.5f));                 // coplanar with the previous one
    b.mirror(krs::mirror({-1, 0, 0}, -0.5f));               // the same plane, opposite normal
    b.mirror(krs::mirror({1, 0, 0}, 2.0f));                 // parallel
    b.kernel(krs::sphere({2, 0, 0}, 0.4f));
    b.mirror(krs::mirror::through({2, 0, 0}, {0, 1, 1}));   // through that sphere's center
    b.mirror(krs::mirror::through({0, 0, 0}, {0, 0, 1}));   // through the torus capsule's start
    const scene s = b.build();
    const auto e = krs::expand(s);
    std::mt19937_64 g(2);
    double lipschitz = 0, excess = 0;
    for (int k = 0; k < 20000; ++k) {
        const vec3d a = in_ball(g, 5), c = a + in_ball(g, 1e-2);
        const double da = s.distance(a), dc = s.distance(c);
        REQUIRE(std::isfinite(da));
        REQUIRE(std::abs(da - dc) <= krs::length(a - c) * (1 + 1e-9) + 1e-12);
        REQUIRE(da >= e.distance(a) - 1e-6); // a subset of the expansion's terms
        if (krs::length(a - c) > 0) lipschitz = std::max(lipschitz, std::abs(da - dc) / krs::length(a - c));
        excess = std::max(excess, e.distance(a) - da);
    }
    KRS_FIGURE("coplanar.lipschitz", krs_test::figure_digits(lipschitz, 5));
    KRS_FIGURE("coplanar.expansion_excess", excess);
}

TEST_CASE("deep sequences: float distance against double as n grows to 64")
{
    // Unaligned mirrors spreading a small kernel set: the float error accumulates through n folds
    // of coordinates of the scene's size. Reported per n; must stay below 1e-4 of the extent.
    std::mt19937_64 g(3);
    scene::builder b;
    b.kernel(krs::sphere({0, 0, 0}, 0.2f));
    b.kernel(krs::torus_capsule({0, -0.3f, 0}, {0.1f, 0.3f, 0.05f}, {0.1f, 0, 0}, 0.05f));
    double worst_at[65] = {};
    for (int n = 1; n <= 64; ++n) {
        const vec3d m = krs::normalize(in_ball(g, 1) + vec3d{0, 0, 0.2});
        // Offsets grow slowly so the scene spreads but stays of bounded size (~ sqrt(n)).
        b.mirror(krs::mirror(vec3f{float(m.x), float(m.y), float(m.z)}, float(0.3 + 0.05 * n)));
        if (n % 8 != 0) continue;
        const scene s = b.build();
        const double extent = 10.0;
        double worst = 0;
        for (int k = 0; k < 4000; ++k) {
            const vec3d x = in_ball(g, extent);
            const vec3f xf{float(x.x), float(x.y), float(x.z)};
            const double reference = s.distance(vec3d(xf)); // same point, double arithmetic
            const float got = s.distance(xf);
            REQUIRE(std::isfinite(got));
            worst = std::max(worst, std::abs(double(got) - reference) / extent);
        }
        worst_at[n] = worst;
        KRS_FIGURE("deep.n" + std::to_string(n), worst);
        CHECK(worst < 1e-4);
    }
    // Growth is at most linear-ish in n (each fold adds about one rounding of the coordinates).
    CHECK(worst_at[64] <= 64.0 * 1.2e-7 * 4);
}

TEST_CASE("far from the origin and at tiny scales: rays through a known solid hit it")
{
    int combinations = 0, all_hit = 0, most_steps = 0;
    double worst_resolved = 0, worst_unresolved = 0;
    for (const double scale : {1e-4, 1.0, 1e3, 1e5, 1e6}) {
        for (const double offset : {0.0, 1e3, 1e6}) {
            // A row of 8 spheres (3 mirrors) of radius `scale`, centered `offset` from the origin.
            const vec3d base{offset, 0.5 * offset, -offset};
            scene::builder b;
            b.kernel(krs::sphere(vec3f{float(base.x), float(base.y), float(base.z)}, float(scale)));
            for (int i = 0; i < 3; ++i) {
                const double plane_x = base.x + scale * (1.5 + 3.0 * ((1 << i) - 1)); // separates the row so far
                b.mirror(krs::mirror({1, 0, 0}, float(plane_x)));
            }
            const scene s = b.build();
            const auto e = krs::expand(s);
            krs::trace_options o;
            o.pixel_footprint = 1e-4f;
            o.threshold_floor = float(1e-5 * scale);
            o.max_distance = float(100 * scale + 1);
            o.max_steps = 2000;
            int hit = 0, found = 0;
            ++combinations;
            for (const auto& instance : e.instances) {
                // Aim at the instance's center from 20 radii away: every such ray must hit, at a t
                // no later than the exact entry distance (float geometry rounding allowed).
                const vec3d c = instance.to_world.apply(base);
                const vec3d origin = c + vec3d{0.0, 0.0, -20.0 * scale};
                const krs::ray<float> r{vec3f{float(origin.x), float(origin.y), float(origin.z)}, {0, 0, 1}};
                const krs::hit<float> h = krs::sphere_trace(s, r, o);
                INFO("scale " << scale << " offset " << offset);
                REQUIRE(h.found);
                ++found;
                most_steps = std::max(most_steps, h.steps);
                const double relative_precision = 4e-7 * (std::abs(offset) + 30 * scale) / scale;
                const double miss = std::abs(double(h.t) - 19.0 * scale) / scale;
                // When float cannot resolve the sphere at this offset, say so rather than pass.
                if (relative_precision > 0.1) {
                    worst_unresolved = std::max(worst_unresolved, miss);
                    continue;
                }
                worst_resolved = std::max(worst_resolved, miss);
                CHECK(h.t == doctest::Approx(19.0 * scale).epsilon(std::max(1e-3, relative_precision)));
                ++hit;
            }
            if (4e-7 * (std::abs(offset) + 30 * scale) / scale <= 0.1) CHECK(hit == 8);
            if (found == 8) ++all_hit;
        }
    }
    KRS_FIGURE("far.combinations", combinations);
    KRS_FIGURE("far.all_hit", all_hit);
    KRS_FIGURE("far.most_steps", most_steps);
    KRS_FIGURE("far.worst_resolved", worst_resolved);
    KRS_FIGURE("far.worst_unresolved", worst_unresolved);
}

TEST_CASE("rays starting on or inside a kernel and rays along a plane are defined")
{
    const krs::sphere s({0, 0, 0}, 1);
    krs::trace_options o;
    // Exactly on the surface, leaving: a hit at t = min_distance (the start is within threshold).
    const krs::hit<float> on = krs::sphere_trace(s, krs::ray<float>{{1, 0, 0}, {1, 0, 0}}, o);
    CHECK(on.found);
    CHECK(on.t == 0.0f);
    // Along the plane y = 0 from inside the half-space: hit immediately; from outside, parallel:
    // a miss within max_steps, never NaN.
    const krs::plane ground({0, 1, 0}, 0);
    const krs::hit<float> along = krs::sphere_trace(ground, krs::ray<float>{{0, 0, 0}, {1, 0, 0}}, o);
    CHECK(along.found);
    o.max_steps = 100;
    const krs::hit<float> parallel = krs::sphere_trace(ground, krs::ray<float>{{0, 0.5f, 0}, {1, 0, 0}}, o);
    CHECK_FALSE(parallel.found);
    CHECK(std::isinf(parallel.t));
    // Grazing a sphere: tangent ray at distance radius + 2 thresholds must miss; + 0 must hit.
    o.max_steps = 1000;
    o.pixel_footprint = 0;
    o.threshold_floor = 1e-4f;
    const krs::hit<float> tangent_miss = krs::sphere_trace(s, krs::ray<float>{{-5, 1.0003f, 0}, {1, 0, 0}}, o);
    CHECK_FALSE(tangent_miss.found);
    const krs::hit<float> tangent_hit = krs::sphere_trace(s, krs::ray<float>{{-5, 0.99999f, 0}, {1, 0, 0}}, o);
    CHECK(tangent_hit.found);
    CHECK(tangent_hit.steps < 1000);
}

TEST_CASE("degenerate kernels give finite, exact distances")
{
    std::mt19937_64 g(5);
    const krs::sphere point({1, 2, 3}, 0.0f); // radius 0: the distance to a point
    const krs::torus_capsule straight({0, 0, 0}, {2, 0, 0}, {1, 0, 0}, 0.1f);  // collinear control
    const krs::torus_capsule nearly({0, 0, 0}, {2, 0, 0}, {1, 1e-7f, 0}, 0.1f); // zero-angle limit
    const krs::torus_capsule thin({0, 0, 0}, {2, 0, 0}, {1, 0.5f, 0}, 1e-30f);  // radius near zero
    for (int k = 0; k < 10000; ++k) {
        const vec3d p = in_ball(g, 4);
        REQUIRE(point.distance(p) == doctest::Approx(krs::length(p - vec3d{1, 2, 3})).epsilon(1e-12));
        // Reference for the straight branch: distance to the segment from (0,0,0) to (2,0,0).
        const double along = std::clamp(p.x, 0.0, 2.0);
        const double to_segment = krs::length(p - vec3d{along, 0, 0});
        const double radius = double(0.1f); // the radius as stored
        REQUIRE(std::abs(straight.distance(p) - (to_segment - radius)) <= 1e-12);
        // The zero-angle arc bulges by at most its control offset (1e-7): within that of the segment.
        REQUIRE(std::abs(nearly.distance(p) - (to_segment - radius)) <= 2e-7);
        REQUIRE(std::isfinite(thin.distance(p)));
        REQUIRE(thin.distance(p) >= -1e-12);
        const krs::vec3<double> n = point.normal(p);
        REQUIRE(std::abs(krs::length(n) - 1) < 1e-12);
    }
    // At the degenerate point itself the normal is a defined unit vector, not NaN.
    CHECK(krs::length(point.normal(vec3d{1, 2, 3})) == doctest::Approx(1.0));
}

// ---- magnitude policy (krs/core/validate.hpp) ---------------------------------------------------
// Each limit: a parameter just inside is accepted and the field's distance is finite at every point
// the policy covers (|p| <= 1e9, down to the origin), in float, double and packet lanes; one float
// step outside is refused with a krs::invalid_parameter naming the parameter and its range.

namespace {

constexpr float limit = krs::max_magnitude;
const float above_limit = std::nextafter(krs::max_magnitude, std::numeric_limits<float>::infinity());

// Points the policy covers: the origin, tiny radii, the limit along axes and diagonals, and random
// directions at radii log-uniform in [1e-30, 1e9]. The limit is approached from inside after
// rounding to float (1 - 1e-6 of it).
const std::vector<vec3f>& reach_points()
{
    static const std::vector<vec3f> points = [] {
        std::vector<vec3f> out{{0, 0, 0}, {1e-30f, 0, 0}, {0, -1e-38f, 0}};
        const double edge = double(limit) * (1 - 1e-6);
        for (const vec3d& d : {vec3d{1, 0, 0}, vec3d{0, 1, 0}, vec3d{0, 0, 1}, vec3d{1, 1, 1}, vec3d{1, -1, 1},
                               vec3d{-1, 1, -1}, vec3d{-1, -1, -1}})
            for (const double sign : {1.0, -1.0}) out.push_back(vec3f(krs::normalize(d) * (sign * edge)));
        std::mt19937_64 g(31);
        for (int i = 0; i < 200; ++i)
            out.push_back(vec3f(krs_test::random_direction(g) * std::pow(10.0, uniform(g, -30.0, 9.0) - 1e-6)));
        return out;
    }();
    return points;
}

// Counts the points of reach_points() where the float, double or packet distance is not finite.
template <class Field>
int non_finite_within_reach(const Field& f)
{
    int bad = 0;
    for (const vec3f& p : reach_points()) {
        const bool ok = std::isfinite(f.distance(p)) && std::isfinite(f.distance(vec3d(p))) &&
                        xsimd::all(krs::is_finite(f.distance(krs::vec3fP(p))));
        if (!ok) {
            ++bad;
            MESSAGE("not finite at (" << p.x << ", " << p.y << ", " << p.z << ")");
        }
    }
    return bad;
}

// `build` must throw krs::invalid_parameter naming `parameter`, with `range` in its message.
void refused(const std::function<void()>& build, const std::string& parameter, const std::string& range)
{
    try {
        build();
    } catch (const krs::invalid_parameter& e) {
        INFO(e.what());
        CHECK(e.parameter() == parameter);
        CHECK(std::string(e.what()).find(range) != std::string::npos);
        return;
    }
    FAIL("no krs::invalid_parameter for " << parameter);
}

} // namespace

TEST_CASE("magnitude policy: the documented limits and the messages agree")
{
    CHECK(krs::max_magnitude == 1e9f);
    CHECK(double(krs::max_magnitude) == 1e9); // exact, so "<= 1e9" means what it says
    CHECK(std::stod(std::string(krs::detail::max_magnitude_text)) == double(krs::max_magnitude));
    CHECK(krs::min_length == 1e-6f);
    CHECK(above_limit > limit);
    refused([] { krs::require_magnitude("x", above_limit); }, "x", "[-1e9, 1e9]");
    refused([] { krs::require_magnitude("x", -above_limit); }, "x", "[-1e9, 1e9]");
    refused([] { krs::require_length("r", -1e-30f); }, "r", "[0, 1e9]");
    refused([] { krs::require_positive_length("r", 0.0f); }, "r", "(0, 1e9]");
    refused([] { krs::require_magnitude("p", vec3f{6e8f, 6e8f, 6e8f}); }, "p", "within 1e9 of the origin");
    refused([] { krs::require_magnitude("p", vec3f{0, std::nanf(""), 0}); }, "p", "finite");
    CHECK(krs::require_magnitude("x", -limit) == -limit);
    CHECK(krs::require_length("r", limit) == limit);
    CHECK(krs::require_magnitude("p", vec3f{0, 0, limit}).z == limit);
}

TEST_CASE("magnitude policy: kernels and mirrors at the limit are finite everywhere in reach, past it refused")
{
    const vec3f far_x{limit, 0, 0}, past_x{above_limit, 0, 0};
    // Sphere: a ball of radius 1e9 centered 1e9 away.
    CHECK(non_finite_within_reach(krs::sphere(far_x, limit)) == 0);
    refused([&] { krs::sphere(past_x, 1); }, "sphere.center", "within 1e9 of the origin");
    refused([] { krs::sphere({6e8f, 6e8f, 6e8f}, 1); }, "sphere.center", "within 1e9"); // |c| = 1.04e9
    refused([] { krs::sphere({0, 0, 0}, above_limit); }, "sphere.radius", "[0, 1e9]");
    // Plane: offset at the limit, through() a point at the limit.
    CHECK(non_finite_within_reach(krs::plane({1, 1, 1}, -limit)) == 0);
    CHECK(krs::plane::through({0, 0, limit}, {0, 0, 1}).offset == limit);
    // (A float point 1e9 away in an unaligned direction rounds just past the limit: 1 - 1e-7 of it.)
    const vec3f unaligned_at_limit(krs::normalize(vec3d{1, 2, 3}) * (double(limit) * (1 - 1e-7)));
    CHECK(krs::plane::through(unaligned_at_limit, {1, 2, 3}).offset <= limit);
    refused([] { krs::plane({0, 1, 0}, above_limit); }, "plane.offset", "[-1e9, 1e9]");
    refused([] { krs::plane::through({0, 0, above_limit}, {0, 0, 1}); }, "plane.point", "within 1e9");
    // Capsule: from one end of the reach to the other; the shortest non-zero axis is min_length.
    CHECK(non_finite_within_reach(krs::capsule({-limit, 0, 0}, far_x, limit)) == 0);
    CHECK(non_finite_within_reach(krs::capsule({0, 0, 0}, {krs::min_length, 0, 0}, 0.0f)) == 0);
    CHECK(non_finite_within_reach(krs::capsule({1, 2, 3}, {1, 2, 3}, 0.5f)) == 0); // a == b: a sphere
    refused([&] { krs::capsule({0, 0, 0}, past_x, 1); }, "capsule.b", "within 1e9");
    refused([] { krs::capsule({0, 0, 0}, {std::nextafter(krs::min_length, 0.0f), 0, 0}, 1); }, "capsule.b", "1e-6");
    refused([] { krs::capsule({0, 0, 0}, {1, 0, 0}, above_limit); }, "capsule.radius", "[0, 1e9]");
    // Box: centered at the limit, half extents of length 1e9.
    CHECK(non_finite_within_reach(krs::box(far_x, vec3f(krs::normalize(vec3d{1, 1, 1}) * 0.999999 * double(limit)))) == 0);
    CHECK(non_finite_within_reach(krs::box({0, 0, -limit}, {limit, 0, 0}, {0, 1, 0}, {0, 0, 1}, {1, 0, 0})) == 0);
    refused([&] { krs::box(past_x, {1, 1, 1}); }, "box.center", "within 1e9");
    refused([&] { krs::box({0, 0, 0}, {0, above_limit, 0}); }, "box.half_extents", "within 1e9");
    // Torus capsule: a half circle of radius 1e9, and the most curved arc min_length allows
    // (curvature ~2e6, the case the policy's bound is about).
    CHECK(non_finite_within_reach(krs::torus_capsule({-limit, 0, 0}, far_x, {0, limit, 0}, limit)) == 0);
    const krs::torus_capsule tight({0, 0, 0}, {krs::min_length, 0, 0}, {0.5f * krs::min_length, 0.5f * krs::min_length, 0}, 0.0f);
    CHECK(tight.curvature() == doctest::Approx(2e6).epsilon(1e-3));
    CHECK(non_finite_within_reach(tight) == 0);
    // Folded by 64 mirrors at the limit, points reach |p| = 1.3e11: there the curvature times the
    // point must still not overflow, or the radial term degenerates to 0 (finite, but the distance
    // of the arc's plane). min_length keeps it accurate.
    for (const vec3d& far : {vec3d{0, 1.3e11, 0}, vec3d{-1.3e11, 0, 0}, vec3d{0, -9e10, 9e10}}) {
        INFO("at " << far.y << ", " << far.z);
        CHECK(double(tight.distance(vec3f(far))) == doctest::Approx(krs::length(far)).epsilon(1e-6));
    }
    refused([&] { krs::torus_capsule({0, 0, 0}, past_x, {1, 1, 0}, 0); }, "torus_capsule.end", "within 1e9");
    refused([&] { krs::torus_capsule(past_x, {0, 0, 0}, {1, 1, 0}, 0); }, "torus_capsule.start", "within 1e9");
    refused([&] { krs::torus_capsule({0, 0, 0}, {1, 0, 0}, {0, above_limit, 0}, 0); }, "torus_capsule.control", "within 1e9");
    refused([] { krs::torus_capsule({0, 0, 0}, {1, 0, 0}, {0.5f, 1, 0}, above_limit); }, "torus_capsule.radius", "[0, 1e9]");
    refused([] { krs::torus_capsule({0, 0, 0}, {std::nextafter(krs::min_length, 0.0f), 0, 0}, {0, 1e-6f, 0}, 0); },
            "torus_capsule.end", "1e-6");
    // Mirrors: offsets, points and positions at the limit.
    CHECK(krs::mirror({1, 0, 0}, limit).offset == limit);
    CHECK(std::abs(krs::mirror::through(unaligned_at_limit, {1, 2, 3}).offset) <= limit);
    CHECK(std::abs(krs::mirror::through(-unaligned_at_limit, {1, 2, 3}).offset) <= limit);
    CHECK(krs::axis_mirror(2, -limit).position() == -limit);
    refused([] { krs::mirror({1, 0, 0}, above_limit); }, "mirror.offset", "[-1e9, 1e9]");
    refused([&] { krs::mirror::through(past_x, {1, 0, 0}); }, "mirror.point", "within 1e9");
    refused([] { krs::axis_mirror(1, -above_limit); }, "axis_mirror.position", "[-1e9, 1e9]");
    // A mirror's fields are public: the sequence builder checks them again.
    krs::mirror m({0, 0, 1}, 1);
    m.offset = above_limit;
    scene::builder b;
    refused([&] { b.mirror(m); }, "sequence.mirror.offset", "[-1e9, 1e9]");
}

TEST_CASE("magnitude policy: 64 mirrors at the limit fold points to 1.3e11 and the distance stays finite")
{
    // The policy's worst case for a KRS: every mirror 1e9 from the origin, unaligned, so the folded
    // point can travel 2 * 64 * 1e9; kernels include the most curved torus capsule.
    std::mt19937_64 g(32);
    scene::builder b;
    b.kernel(krs::torus_capsule({0, 0, 0}, {krs::min_length, 0, 0}, {0.5f * krs::min_length, 0.5f * krs::min_length, 0}, 0.0f));
    b.kernel(krs::sphere({limit, 0, 0}, 1));
    b.kernel(krs::plane({0, 1, 0}, -limit));
    for (int i = 0; i < 64; ++i) b.mirror(krs::mirror(vec3f(krs_test::random_direction(g)), (i % 2 ? 1.0f : -1.0f) * limit));
    const scene s = b.build();
    CHECK(s.mirror_count() == 64);
    CHECK(non_finite_within_reach(s) == 0);
}

TEST_CASE("magnitude policy: fold steps at the limit, KIFS iterations bounded by how far they magnify")
{
    refused([] { krs::plane_fold({1, 0, 0}, above_limit); }, "plane_fold.offset", "[-1e9, 1e9]");
    refused([] { krs::translate_step({0, above_limit, 0}); }, "translate_step.offset", "within 1e9");
    refused([] { krs::scale_about(above_limit, {0, 0, 0}); }, "scale_about.factor", "(0, 1e9]");
    refused([] { krs::scale_about(3, {0, 0, above_limit}); }, "scale_about.center", "within 1e9");
    refused([] { krs::rotate_step({0, 1, 0}, above_limit); }, "rotate_step.angle", "[-1e9, 1e9]");
    CHECK(krs::plane_fold({1, 0, 0}, limit).offset == limit);
    CHECK(krs::scale_about(limit, {0, 0, 0}).factor() == limit);

    // The presets at their deepest magnify 1e9 by 3^20 = 3.5e9: within the 1e19 the kernels handle.
    CHECK(non_finite_within_reach(krs::make_cube_fractal(20)) == 0);
    CHECK(non_finite_within_reach(krs::make_menger_sponge(20)) == 0);
    CHECK(non_finite_within_reach(krs::make_square_fractal(20)) == 0);
    CHECK(non_finite_within_reach(krs::make_koch_curve(12)) == 0);
    // Sierpinski at scale 3: 3^20 * 1e9 (plus the shifts) stays under 1e19, 3^21 does not.
    CHECK(non_finite_within_reach(krs::make_sierpinski_tetrahedron(20, 3.0f)) == 0);
    refused([] { krs::make_sierpinski_tetrahedron(21, 3.0f); }, "sierpinski_tetrahedron.iterations", "[0, 20]");
    CHECK(non_finite_within_reach(krs::make_sierpinski_tetrahedron(30, 2.0f)) == 0);
    refused([] { krs::make_sierpinski_tetrahedron(5, above_limit); }, "sierpinski_tetrahedron.scale", "(1, 1e9]");
    refused([] { krs::make_koch_curve(12, 2000.0f); }, "koch_curve.tube_radius", "1e9"); // 2000 * 3^12 > 1e9

    // A torus capsule kernel squares its curvature times the point: its input_reach() lowers the
    // iteration limit (curvature 40 here: 2.5e17 instead of 1e19).
    using program = krs::fold_program<krs::abs_fold<krs::fold_xyz>, krs::plane_fold, krs::plane_fold, krs::scale_about>;
    const program cube_folds(krs::abs_fold<krs::fold_xyz>{}, krs::plane_fold({1, -1, 0}, 0), krs::plane_fold({1, 0, -1}, 0),
                             krs::scale_about(3, {2, 0, 0}));
    const krs::torus_capsule small({-0.005f, 0, 0}, {0.005f, 0, 0}, {0, 0.005f, 0}, 0.0005f);
    CHECK(small.curvature() == doctest::Approx(200.0).epsilon(1e-3));
    int most = 0;
    for (int n = 0; n <= 20; ++n) {
        try {
            const krs::kifs<program, krs::torus_capsule> k(cube_folds, small, n, krs::kifs_taps::last_iteration);
            INFO("iterations " << n);
            CHECK(non_finite_within_reach(k) == 0);
            most = n;
        } catch (const krs::invalid_parameter& e) {
            CHECK(e.parameter() == "kifs.iterations");
            CHECK(std::string(e.what()).find("[0, " + std::to_string(most) + "]") != std::string::npos);
            break;
        }
    }
    KRS_FIGURE("kifs.torus_capsule_iterations", most); // cube folds, torus capsule of curvature 200
    CHECK(most >= 10);
    CHECK(most < 20); // the box kernel allows 20
}

TEST_CASE("magnitude policy: warp and shell parameters at their limits stay finite down to r = 0")
{
    const krs::sphere in_prototype({1.5f, 0, 0}, 0.3f);
    for (const krs::shell_seams seams : {krs::shell_seams::none, krs::shell_seams::adjacent_shells, krs::shell_seams::hidden_boundary}) {
        krs::shell_options o;
        o.seams = seams;
        INFO("seams " << int(seams));
        CHECK(non_finite_within_reach(krs::similar_shell<krs::sphere>(in_prototype, krs::min_shell_density, o)) == 0);
        CHECK(non_finite_within_reach(krs::similar_shell<krs::sphere>(in_prototype, krs::max_shell_density, o)) == 0);
        CHECK(non_finite_within_reach(krs::make_recursive_lotus(krs::min_shell_density, 16, o)) == 0);
        CHECK(non_finite_within_reach(krs::make_cube_singularity(krs::min_shell_density, o)) == 0);
    }
    refused([&] { krs::similar_shell<krs::sphere>(in_prototype, std::nextafter(krs::min_shell_density, 0.0f)); },
            "similar_shell.density", "[0.125, 1000]");
    refused([&] { krs::similar_shell<krs::sphere>(in_prototype, std::nextafter(krs::max_shell_density, 2000.0f)); },
            "similar_shell.density", "[0.125, 1000]");
    refused([] { krs::make_recursive_lotus(0.1f); }, "recursive_lotus.density", "[0.125, 1000]");
    refused([] { krs::make_cube_singularity(0.1f); }, "cube_singularity.density", "[0.125, 1000]");
    refused([] { const krs::lotus_shell shell(above_limit, 8); }, "lotus_shell.ratio", "(1, 1e9]");
    refused([] { const krs::cube_shell shell(above_limit); }, "cube_shell.ratio", "(1, 1e9]");
    refused([] {
        krs::shell_options o;
        o.hidden_cutoff = above_limit;
        krs::make_recursive_lotus(1.0f, 8, o);
    }, "shell_options.hidden_cutoff", "(0, 1e9]");

    const krs::sphere tile({0, 0, 0}, 0.3f);
    CHECK(non_finite_within_reach(krs::log_polar_tiling<krs::sphere>(tile, 12, limit)) == 0);
    CHECK(non_finite_within_reach(krs::log_spherical_tiling<krs::sphere>(tile, 4096, 0.5f)) == 0);
    refused([&] { krs::log_polar_tiling<krs::sphere>(tile, 12, above_limit); }, "log_polar_tiling.height", "[0, 1e9]");
}

TEST_CASE("magnitude policy: builders refuse parameters that would carry their kernels past the limit")
{
    using namespace krs::model;
    // Raw tree: a trunk from the origin to the limit.
    tree_parameters t;
    t.forks = {{0, 0, 0}, {limit, 0, 0}};
    t.controls = {{0.5f * limit, 1, 0}};
    t.widths = {1};
    t.ground_height = -limit;
    CHECK(non_finite_within_reach(build_tree(t)) == 0);
    t.forks[1].x = above_limit;
    refused([&] { build_tree(t); }, "tree.forks[1]", "within 1e9");
    t.forks[1] = {std::nextafter(krs::min_length, 0.0f), 0, 0};
    t.controls[0] = {0.5f * krs::min_length, 0, 0};
    refused([&] { build_tree(t); }, "tree.forks[1]", "1e-6");
    // Grown trees: too long a trunk for the growth, and twigs shrunk below min_length.
    tree_style big;
    big.levels = 3;
    big.length_ratio = 1.5f;
    big.trunk_length = 5e8f;
    refused([&] { build_tree(grow_tree(big)); }, "tree_style.trunk_length", "past 1e9");
    tree_style tiny;
    tiny.levels = 12;
    tiny.length_ratio = 1e-3f;
    refused([&] { build_tree(grow_tree(tiny)); }, "tree_style.length_ratio", "1e-6");
    refused([] {
        tree_style s;
        s.trunk_length = above_limit;
        grow_tree(s);
    }, "tree_style.trunk_length", "(0, 1e9]");

    // Rock, sponge, terrain: |center| + size (or |height| + size / 10) at the limit.
    rock_parameters r;
    r.center = {9e8f, 0, 0};
    r.radius = 1e8f;
    CHECK(non_finite_within_reach(build_rock(r).sequence) == 0);
    r.radius = std::nextafter(1e8f, 1e9f);
    refused([&] { build_rock(r); }, "rock.radius", "|center| + radius must be <= 1e9");
    sponge_parameters sp;
    sp.center = {0, 5e8f, 0};
    sp.size = 5e8f;
    CHECK(non_finite_within_reach(build_sponge(sp).sequence) == 0);
    sp.size = std::nextafter(5e8f, 1e9f);
    refused([&] { build_sponge(sp); }, "sponge.size", "|center| + size must be <= 1e9");
    terrain_parameters tp;
    tp.size = limit;
    tp.height = 9e8f;
    CHECK(non_finite_within_reach(build_terrain(tp)) == 0);
    tp.height = std::nextafter(9e8f, 1e9f);
    refused([&] { build_terrain(tp); }, "terrain.height", "|height| + size / 10 must be <= 1e9");

    // Coral: levels segments of at most segment_length.
    coral_parameters c;
    c.levels = 10;
    c.segment_length = 1e8f;
    c.base_radius = 1e6f;
    CHECK(non_finite_within_reach(build_coral(c)) == 0);
    c.segment_length = std::nextafter(1e8f, 1e9f);
    refused([&] { build_coral(c); }, "coral.segment_length", "times levels must be <= 1e9");
    c.segment_length = 1e-6f;
    c.taper = 0.5f;
    refused([&] { build_coral(c); }, "coral.segment_length", "1e-6");

    // Grass and forest: 2^20 copies of a large clump or tree spread past the limit.
    grass_parameters gp;
    gp.doublings = 20;
    gp.clump_radius = 1e6f;
    gp.blade_height = 1e6f;
    gp.blade_width = 1e4f;
    refused([&] { build_grass(gp); }, "grass.doublings", "past 1e9");
    gp.doublings = 4;
    CHECK(non_finite_within_reach(build_grass(gp).sequence) == 0);
    forest_parameters fp;
    fp.tree.levels = 4;
    fp.tree.trunk_length = 1e6f;
    fp.doublings = 20;
    refused([&] { build_forest(fp); }, "forest.doublings", "past 1e9");
}

TEST_CASE("regression (fuzz crasher rock_huge_center_nan_distance): a rock centered at -FLT_MAX is refused")
{
    // fuzz/crashers/builders/rock_huge_center_nan_distance: the center was finite, so it was accepted,
    // and the facet planes' offsets dot(n, c) + distance (~1e38) made the float distance inf - inf.
    krs::model::rock_parameters r;
    r.center = {0, -std::numeric_limits<float>::max(), 0};
    refused([&] { krs::model::build_rock(r); }, "rock.center", "within 1e9");
    r.center = {0, -1e30f, 0}; // the example: finite distances, but garbage (-1.9e22 at the center)
    refused([&] { krs::model::build_rock(r); }, "rock.center", "within 1e9");
}

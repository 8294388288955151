// Sphere tracer, camera and shading against closed forms and brute-force references.

#include "krs/expansion.hpp"
#include "krs/kernels/plane.hpp"
#include "krs/kernels/sphere.hpp"
#include "krs/kernels/torus_capsule.hpp"
#include "krs/shade/lambert.hpp"
#include "krs/trace/camera.hpp"
#include "krs/trace/packet_trace.hpp"
#include "krs/trace/tile_prepass.hpp"

#include "support/random.hpp"
#include "support/scenes.hpp"

#include <doctest/doctest.h>

#include <cmath>
#include <random>

namespace {

using krs::vec3d;
using krs::vec3f;

using krs_test::random_direction;
using krs_test::uniform;

// Closed-form first intersection of a ray with a sphere (infinity if none ahead).
double ray_sphere(const vec3d& o, const vec3d& d, const vec3d& c, double r)
{
    const vec3d oc = o - c;
    const double b = krs::dot(oc, d), q = krs::dot(oc, oc) - r * r, disc = b * b - q;
    if (disc < 0) return INFINITY;
    const double t0 = -b - std::sqrt(disc), t1 = -b + std::sqrt(disc);
    return t0 >= 0 ? t0 : (t1 >= 0 ? 0.0 : INFINITY);
}

using scene = krs::sequence<krs::sphere, krs::torus_capsule>;

} // namespace

TEST_CASE_TEMPLATE("sphere tracing a sphere matches the closed-form intersection", S, float, double)
{
    const krs::sphere s({0.5f, -0.2f, 3.0f}, 1.25f);
    krs::trace_options o;
    o.pixel_footprint = 1e-4f;
    o.threshold_floor = 1e-6f;
    std::mt19937_64 g(1);
    int hits = 0;
    for (int k = 0; k < 5000; ++k) {
        const vec3d origin{uniform(g, -3, 3), uniform(g, -3, 3), uniform(g, -6, -2)};
        const vec3d target = vec3d(s.center) + random_direction(g) * (1.5 * s.radius * uniform(g, 0, 1));
        const vec3d d = krs::normalize(target - origin);
        const double exact = ray_sphere(origin, d, vec3d(s.center), s.radius);
        const krs::ray<S> r{krs::vec3<S>(origin), krs::vec3<S>(d)};
        const krs::hit<S> h = krs::sphere_trace(s, r, o);
        if (std::isinf(exact)) {
            // A miss may still come within one threshold of the surface (a grazing ray): then the
            // tracer may report it; otherwise it must not.
            if (h.found) REQUIRE(s.distance(krs::point_at(r, h.t)) <= o.threshold(h.t) * 1.01);
            continue;
        }
        REQUIRE(h.found);
        ++hits;
        // Sphere tracing never passes the surface; it stops within the threshold of it.
        REQUIRE(double(h.t) <= exact + 1e-5);
        REQUIRE(s.distance(krs::point_at(r, h.t)) <= o.threshold(h.t) * 1.01 + 1e-6);
    }
    CHECK(hits > 2000);
}

TEST_CASE("tracing a KRS finds the first intersection of its expansion")
{
    const krs_test::grove_scene s = krs_test::grove(false);
    const auto e = krs::expand(s);
    krs::trace_options o;
    o.pixel_footprint = 2e-4f;
    o.max_distance = 40.0f;
    std::mt19937_64 g(7);
    int hits = 0, misses = 0;
    for (int k = 0; k < 1500; ++k) {
        const vec3d origin{uniform(g, -8, 8), uniform(g, 1, 4), uniform(g, -12, -9)};
        const vec3d target{uniform(g, -3, 5), uniform(g, -0.7, 1.5), uniform(g, -3, 5)};
        const vec3d d = krs::normalize(target - origin);
        // Reference: march the expansion in steps of 1e-3 (far below every kernel's thickness)
        // and bisect the first sign change.
        double t_true = INFINITY;
        for (double t = 0; t < 40.0; t += 1e-3) {
            if (e.distance(origin + d * t) <= 0) {
                double lo = t - 1e-3, hi = t;
                for (int i = 0; i < 40; ++i) {
                    const double mid = 0.5 * (lo + hi);
                    (e.distance(origin + d * mid) <= 0 ? hi : lo) = mid;
                }
                t_true = hi;
                break;
            }
            if (t > 0 && e.distance(origin + d * t) > 0.5) t += e.distance(origin + d * t) - 0.5; // skip empty space safely
        }
        const krs::ray<double> r{origin, d};
        const krs::hit<double> h = krs::sphere_trace(s, r, o);
        if (std::isfinite(t_true)) {
            ++hits;
            REQUIRE(h.found);
            REQUIRE(h.t <= t_true + 1e-9);
        } else {
            ++misses;
        }
        if (h.found) REQUIRE(e.distance(krs::point_at(r, h.t)) <= o.threshold(h.t) + 1e-9);
        REQUIRE(h.evaluations == h.steps);
    }
    CHECK(hits > 200);
    CHECK(misses > 200);
}

TEST_CASE("packet tracing gives every lane the scalar result")
{
    const krs_test::grove_scene s = krs_test::grove(false);
    const krs::pinhole_camera camera({1, 3, -10}, {1, 0.3f, 1}, {0, 1, 0}, 50.0f, 64, 48);
    krs::trace_options o;
    o.pixel_footprint = camera.pixel_footprint();
    using P = krs::packet_f;
    constexpr std::size_t lanes = krs::lane_count<P>;
    int found = 0;
    for (int y = 0; y < camera.height(); ++y)
        for (int x = 0; x + int(lanes) <= camera.width(); x += int(lanes)) {
            alignas(64) float xs[lanes];
            for (std::size_t i = 0; i < lanes; ++i) xs[i] = float(x + int(i)) + 0.5f;
            const krs::hit<P> hp = krs::sphere_trace(s, camera.primary_ray(P::load_aligned(xs), P(y + 0.5f)), o);
            for (std::size_t i = 0; i < lanes; ++i) {
                const krs::hit<float> h = krs::sphere_trace(s, camera.primary_ray(xs[i], y + 0.5f), o);
                REQUIRE(krs::mask_lane<P>(hp.found, i) == h.found);
                REQUIRE(krs::lane_at(hp.steps, i) == float(h.steps));
                if (h.found) REQUIRE(krs::lane_at(hp.t, i) == doctest::Approx(h.t).epsilon(1e-5));
                found += h.found;
            }
        }
    CHECK(found > 100);
}

TEST_CASE("camera: center ray is the view direction, neighbours are one footprint apart")
{
    const krs::pinhole_camera c({1, 2, 3}, {4, 2, -1}, {0, 1, 0}, 60.0f, 640, 480);
    const krs::ray<float> center = c.primary_ray(320.0f, 240.0f);
    CHECK(krs::length(center.direction - krs::normalize(vec3f{3, 0, -4})) < 1e-6f);
    const krs::ray<float> next = c.primary_ray(321.0f, 240.0f);
    CHECK(std::acos(double(krs::dot(center.direction, next.direction))) == doctest::Approx(c.pixel_footprint()).epsilon(1e-3));
    // The top edge of the image is half the vertical field of view above the center.
    const krs::ray<float> top = c.primary_ray(320.0f, 0.0f);
    CHECK(std::acos(double(krs::dot(center.direction, top.direction))) * 180 / M_PI == doctest::Approx(30.0).epsilon(1e-4));
    CHECK_THROWS_WITH_AS(krs::pinhole_camera({0, 0, 0}, {0, 0, 0}, {0, 1, 0}, 60, 10, 10), doctest::Contains("camera.target"),
                         krs::invalid_parameter);
    CHECK_THROWS_WITH_AS(krs::pinhole_camera({0, 0, 0}, {0, 1, 0}, {0, 1, 0}, 60, 10, 10), doctest::Contains("camera.up"),
                         krs::invalid_parameter);
    CHECK_THROWS_WITH_AS(krs::pinhole_camera({0, 0, 0}, {0, 0, 1}, {0, 1, 0}, 180, 10, 10),
                         doctest::Contains("vertical_fov"), krs::invalid_parameter);
    CHECK_THROWS_WITH_AS(krs::pinhole_camera({0, 0, 0}, {0, 0, 1}, {0, 1, 0}, 60, 0, 10), doctest::Contains("camera.size"),
                         krs::invalid_parameter);
}

TEST_CASE("degenerate rays and options give defined results")
{
    const krs::sphere s({0, 0, 0}, 1);
    krs::trace_options o;
    for (const vec3f bad : {vec3f{0, 0, 0}, vec3f{NAN, 0, 1}, vec3f{INFINITY, 0, 0}}) {
        const krs::hit<float> h = krs::sphere_trace(s, krs::ray<float>{{0, 0, -5}, bad}, o);
        CHECK(h.invalid);
        CHECK(!h.found);
        CHECK(std::isinf(h.t));
    }
    // Starting inside the solid is a hit at the start.
    const krs::hit<float> inside = krs::sphere_trace(s, krs::ray<float>{{0, 0, 0.5f}, {0, 0, 1}}, o);
    CHECK(inside.found);
    CHECK(inside.t == 0.0f);
    // A ray that never comes close stops at max_distance, within max_steps.
    o.max_steps = 10000;
    const krs::hit<float> away = krs::sphere_trace(s, krs::ray<float>{{0, 0, -5}, {0, 0, -1}}, o);
    CHECK(!away.found);
    CHECK(away.steps < 10000);
    // A grazing ray parallel to a plane kernel at height > threshold never hits and never loops.
    const krs::plane ground({0, 1, 0}, 0.0f);
    o.max_steps = 64;
    const krs::hit<float> graze = krs::sphere_trace(ground, krs::ray<float>{{0, 1e-3f, 0}, {1, 0, 0}}, o);
    CHECK(!graze.found);
    CHECK(graze.steps == 64);
    CHECK(std::isinf(graze.t));

    krs::trace_options bad;
    bad.max_steps = 0;
    CHECK_THROWS_WITH_AS(bad.validate(), doctest::Contains("max_steps"), krs::invalid_parameter);
    bad = {};
    bad.max_distance = NAN;
    CHECK_THROWS_WITH_AS(bad.validate(), doctest::Contains("max_distance"), krs::invalid_parameter);
    bad = {};
    bad.threshold_floor = 0;
    CHECK_THROWS_WITH_AS(bad.validate(), doctest::Contains("threshold_floor"), krs::invalid_parameter);

    // The tracers validate their options themselves: each of these marched on to a silent miss.
    const krs::ray<float> ahead{{0, 0, -5}, {0, 0, 1}};
    const krs::pinhole_camera camera({0, 0, -5}, {0, 0, 0}, {0, 1, 0}, 40.0f, 16, 16);
    krs::trace_options options[4];
    options[0].pixel_footprint = -0.5f;
    options[1].threshold_floor = NAN;
    options[2].omega = NAN;
    options[3].omega = -1.0f;
    const char* names[4] = {"pixel_footprint", "threshold_floor", "omega", "omega"};
    for (int i = 0; i < 4; ++i) {
        INFO(names[i]);
        CHECK_THROWS_WITH_AS(krs::sphere_trace(s, ahead, options[i]), doctest::Contains(names[i]), krs::invalid_parameter);
        CHECK_THROWS_WITH_AS(krs::sphere_trace(s, ahead, 0.0f, 10.0f, options[i]), doctest::Contains(names[i]),
                             krs::invalid_parameter);
        auto none = [](krs::ray_job&) { return false; };
        auto ignore = [](std::uint32_t, const krs::hit<float>&) {};
        CHECK_THROWS_WITH_AS(krs::trace_stream(s, none, ignore, options[i]), doctest::Contains(names[i]), krs::invalid_parameter);
        CHECK_THROWS_WITH_AS(krs::prepass_tile(s, camera, 0, 0, 8, 8, options[i]), doctest::Contains(names[i]),
                             krs::invalid_parameter);
    }

    // A stream reports an unusable ray as invalid also when its range is empty (it is pulled and
    // reported without entering a packet), as sphere_trace does.
    bool pulled = false;
    krs::hit<float> reported;
    auto one = [&](krs::ray_job& job) {
        if (pulled) return false;
        pulled = true;
        job.r = {{NAN, 0, 0}, {0, 0, 1}};
        job.t_start = 5.0f;
        job.t_max = 1.0f;
        return true;
    };
    krs::trace_stream(s, one, [&](std::uint32_t, const krs::hit<float>& h) { reported = h; }, krs::trace_options{});
    CHECK(reported.invalid);
    CHECK(!reported.found);
    CHECK(krs::sphere_trace(s, krs::ray<float>{{NAN, 0, 0}, {0, 0, 1}}, 5.0f, 1.0f, krs::trace_options{}).invalid);
}

TEST_CASE("normals: tetrahedral gradient and KRS kernel normals agree with the closed form")
{
    const krs::sphere s({1, 2, 3}, 2);
    scene::builder b;
    b.kernel(krs::sphere({1, 2, 3}, 2));
    b.mirror(krs::mirror({1, 0, 0}, 4)); // a second sphere, mirrored to x = 7
    const scene krs_scene = b.build();
    std::mt19937_64 g(3);
    for (int k = 0; k < 1000; ++k) {
        const vec3d n = random_direction(g);
        const vec3d p = vec3d(s.center) + n * 2.0;
        // First-order scheme: error <= h * curvature (1 / radius) times a small constant.
        CHECK(krs::length(krs::gradient_normal(s, p, 1e-5) - n) < 1e-5 / 2.0 * 2.0);
        // The mirrored copy: its normal is the reflected one.
        const vec3d q{8.0 - p.x, p.y, p.z};
        const vec3d expected{-n.x, n.y, n.z};
        CHECK(krs::length(krs::surface_normal(krs_scene, q, 1e-5) - expected) < 1e-9);
    }
}

TEST_CASE("Lambert shading and hard shadows: a sphere over a ground plane")
{
    krs::sequence<krs::sphere, krs::plane>::builder b;
    b.kernel(krs::sphere({0, 2, 0}, 1));
    b.kernel(krs::plane({0, 1, 0}, 0));
    const auto s = b.build();
    const krs::directional_light sun({0, 1, 0}, {1, 1, 1});
    krs::lambert_material m;
    m.albedo = {1, 1, 1};
    m.ambient = 0.1f;
    const vec3d up{0, 1, 0};
    // Under the sphere: shadowed, only ambient remains.
    CHECK(krs::shade_lambert(s, vec3d{0.2, 0, 0.1}, up, sun, m, 1e-4, 100.0).x == doctest::Approx(0.1));
    // Away from it: ambient + n . l = 1.1.
    CHECK(krs::shade_lambert(s, vec3d{3, 0, 0}, up, sun, m, 1e-4, 100.0).x == doctest::Approx(1.1));
    // On the sphere at 60 degrees from the light: ambient + cos 60.
    const vec3d n{std::sin(M_PI / 3), std::cos(M_PI / 3), 0};
    CHECK(krs::shade_lambert(s, vec3d{0, 2, 0} + n, n, sun, m, 1e-4, 100.0).x == doctest::Approx(0.1 + 0.5).epsilon(1e-6));
    // Facing away from the light: ambient only, no shadow ray needed.
    CHECK(krs::shade_lambert(s, vec3d{0, 1, 0}, vec3d{0, -1, 0}, sun, m, 1e-4, 100.0).x == doctest::Approx(0.1));
}

namespace {
// A unit sphere at the origin whose distance is replaced by `bad` (NaN or +infinity) past the
// plane z = cut, counting its calls: the march step's treatment of non-finite field values, and
// its evaluation count, against a loop written out here.
struct spoiled_sphere {
    float cut = 0.0f, bad = 0.0f;
    mutable long long calls = 0;
    template <class T>
    T distance(const krs::vec3<T>& p) const
    {
        using S = krs::scalar_t<T>;
        using krs::select, krs::sqrt; // scalars; xsimd's by argument-dependent lookup
        calls += 1;
        const T d = sqrt(p.x * p.x + p.y * p.y + p.z * p.z) - T(S(1));
        return select(p.z > T(S(cut)), T(S(bad)), d);
    }
};

// Plain sphere tracing (omega = 1) spelled out: one evaluation per step, a hit where d falls
// below the threshold, a miss on a non-finite d, past t1 or after max_steps.
krs::hit<float> march_by_hand(const spoiled_sphere& f, const krs::ray<float>& r, float t0, float t1,
                              const krs::trace_options& o)
{
    krs::hit<float> h;
    h.t = INFINITY;
    if (!(t0 <= t1)) return h;
    float t = t0;
    for (;;) {
        ++h.steps, ++h.evaluations;
        const float d = f.distance(r.origin + r.direction * t);
        if (d < o.threshold(t)) {
            h.found = true, h.t = t;
            return h;
        }
        if (!std::isfinite(d)) return h;
        t = t + d;
        if (!(t <= t1) || h.steps >= o.max_steps) return h;
    }
}
} // namespace

TEST_CASE("the march step against sphere tracing by hand: NaN and infinite field values end a ray as a miss, one evaluation per step")
{
    krs::trace_options o;
    o.max_steps = 40;
    o.pixel_footprint = 1e-3f;
    // Rays toward the sphere from z = -6 (a hit at z = -1) and past it (a miss); the cut spoils
    // the field before the hit, after it, or never; t1 finite and infinite (an infinite distance
    // must still end the ray: t + inf <= inf would not).
    std::mt19937_64 rng(23);
    int spoiled = 0, hits = 0, total = 0;
    for (const float bad : {NAN, INFINITY})
        for (const float cut : {-4.0f, -2.5f, -1.5f, 0.5f, 10.0f})
            for (const float t1 : {9.0f, INFINITY})
                for (int k = 0; k < 24; ++k) {
                    const spoiled_sphere f{cut, bad};
                    const float off = float(uniform(rng, 0.0, 1.4));
                    const krs::ray<float> r{{off, 0.3f * off, -6.0f}, krs::normalize(vec3f{0.05f, 0.0f, 1.0f})};
                    const krs::hit<float> want = march_by_hand(f, r, 0.0f, t1, o);
                    f.calls = 0;
                    const krs::hit<float> got = krs::sphere_trace(f, r, 0.0f, t1, o);
                    INFO("bad " << bad << " cut " << cut << " t1 " << t1 << " offset " << off);
                    CHECK(got.found == want.found);
                    CHECK(got.steps == want.steps);
                    CHECK(got.evaluations == want.evaluations);
                    CHECK(got.evaluations == f.calls);
                    CHECK((got.t == want.t || (std::isinf(got.t) && std::isinf(want.t))));
                    CHECK(!std::isnan(got.t));
                    spoiled += !want.found && want.steps < o.max_steps && cut < 1.0f;
                    hits += want.found;
                    ++total;
                }
    // Both outcomes occurred, and rays did end on a spoiled value.
    CHECK(hits > total / 8);
    CHECK(spoiled > total / 8);

    // Packets: every lane as the scalar march (lanes with different offsets and spoiled values).
    using P = krs::packet_f;
    constexpr std::size_t W = krs::lane_count<P>;
    for (const float bad : {NAN, INFINITY})
        for (const float t1 : {9.0f, INFINITY}) {
            const spoiled_sphere f{-1.5f, bad};
            alignas(64) float ox[W], oz[W];
            for (std::size_t i = 0; i < W; ++i) ox[i] = 0.1f * float(i), oz[i] = -6.0f + 0.25f * float(i % 5);
            const vec3f dir = krs::normalize(vec3f{0.05f, 0.0f, 1.0f});
            const krs::ray<P> r{{P::load_aligned(ox), P(0.0f), P::load_aligned(oz)}, krs::vec3<P>(dir)};
            const krs::hit<P> got = krs::sphere_trace(f, r, P(0.0f), P(t1), o);
            for (std::size_t i = 0; i < W; ++i) {
                const krs::hit<float> want = march_by_hand(f, krs::ray<float>{{ox[i], 0.0f, oz[i]}, dir}, 0.0f, t1, o);
                INFO("lane " << i << " bad " << bad << " t1 " << t1);
                CHECK(krs::mask_lane<P>(got.found, i) == want.found);
                CHECK(int(krs::lane_at(got.steps, i)) == want.steps);
                CHECK(int(krs::lane_at(got.evaluations, i)) == want.evaluations);
                const float t = krs::lane_at(got.t, i);
                CHECK((t == want.t || (std::isinf(t) && std::isinf(want.t))));
            }
        }
}

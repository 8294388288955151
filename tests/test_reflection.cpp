// Reflection rays (krs/shade/reflection.hpp, KRS section 6.5) against closed forms: a KRS of two
// spheres (one sphere kernel and its mirror image) over a ground plane. From known points on the
// sphere kernel and on the plane, the reflected ray traced by sphere_trace hits what the
// closed-form reflection direction hits, at the closed-form point; packets equal scalars.

#include "krs/compose/union.hpp"
#include "krs/kernels/plane.hpp"
#include "krs/kernels/sphere.hpp"
#include "krs/sequence.hpp"
#include "krs/shade/reflection.hpp"
#include "krs/trace/sphere_trace.hpp"

#include "support/parity.hpp"
#include "support/random.hpp"

#include <doctest/doctest.h>

#include <cmath>
#include <limits>
#include <optional>
#include <random>

namespace {

using krs::vec3d;
using krs::vec3f;

const vec3d ball_center{0, 1, 0}, image_center{3, 1, 0}; // the mirror x = 1.5 maps one to the other
constexpr double ball_radius = 1.0;

using two_balls = krs::sequence<krs::sphere>;
two_balls make_balls()
{
    two_balls::builder b;
    b.kernel(krs::sphere(vec3f(ball_center), float(ball_radius)));
    b.mirror(krs::mirror({1, 0, 0}, 1.5f));
    return b.build();
}

// Nearest t > 0 where the ray o + t d (d unit) meets a sphere, if it does.
std::optional<double> ray_sphere(const vec3d& o, const vec3d& d, const vec3d& c, double r)
{
    const vec3d oc = o - c;
    const double b = krs::dot(oc, d), q = krs::dot(oc, oc) - r * r;
    const double disc = b * b - q;
    if (disc < 0) return std::nullopt;
    const double s = std::sqrt(disc);
    if (-b - s > 0) return -b - s;
    if (-b + s > 0) return -b + s;
    return std::nullopt;
}

struct closed_form_hit {
    double t = std::numeric_limits<double>::infinity();
    int what = -1;        // 0 the ball, 1 its mirror image, 2 the ground
    bool grazing = false; // within `slack` of touching something it misses or barely hits
    double cosine = 1;    // |r . normal| where it hits
};
// What the ray o + t d hits first among the two balls and the ground y = 0 (t <= t_max).
closed_form_hit closed_form(const vec3d& o, const vec3d& d, double t_max, double slack)
{
    closed_form_hit h;
    const vec3d centers[2] = {ball_center, image_center};
    for (int i = 0; i < 2; ++i) {
        if (const auto t = ray_sphere(o, d, centers[i], ball_radius); t && *t < h.t) {
            h.t = *t, h.what = i;
            h.cosine = std::abs(krs::dot(d, (o + d * *t - centers[i]) / ball_radius));
        }
        // Closest approach of the ray (t >= 0.05: a ray leaving a ball's surface starts at its
        // radius) to the center: near the radius, a tracer with a hit threshold may honestly
        // decide either way.
        const double along = std::max(krs::dot(centers[i] - o, d), 0.05);
        const double miss = krs::length(o + d * along - centers[i]) - ball_radius;
        if (std::abs(miss) < slack) h.grazing = true;
    }
    if (d.y < 0) {
        const double t = -o.y / d.y;
        if (t > 0 && t < h.t) h.t = t, h.what = 2, h.cosine = -d.y;
    }
    if (h.t > t_max) h = {std::numeric_limits<double>::infinity(), -1, h.grazing, 1};
    // A tracer stops within its threshold of the surface, threshold / cosine short along the ray.
    if (h.cosine < 0.02) h.grazing = true;
    return h;
}

} // namespace

TEST_CASE("a reflected ray from a known point on a sphere or plane kernel hits what the closed-form reflection hits")
{
    const two_balls balls = make_balls();
    const krs::union_of<two_balls, krs::plane> scene(balls, krs::plane({0, 1, 0}, 0.0f));
    krs::trace_options o;
    o.pixel_footprint = 0.0f;
    o.threshold_floor = 1e-4f;
    o.max_distance = 40.0f;
    o.max_steps = 2000;
    const float lift = 2.0f * o.threshold_floor;

    std::mt19937_64 g(5);
    int checked = 0, hits[3] = {0, 0, 0}, misses = 0;
    double worst = 0;
    for (int i = 0; i < 6000; ++i) {
        // A known point: on the ball or on the ground away from the balls.
        const bool on_ball = i % 2 == 0;
        vec3d p, n;
        if (on_ball) {
            n = krs_test::random_direction(g);
            p = ball_center + n * ball_radius;
            if (p.y < 0.05) continue; // not where the ball touches the ground
        } else {
            p = {krs_test::uniform(g, -3, 6), 0, krs_test::uniform(g, -4, 4)};
            n = {0, 1, 0};
            if (krs::length(p - ball_center) < 1.05 || krs::length(p - image_center) < 1.05) continue;
        }
        // Arriving from the normal's side (cosine at least 0.1 so the point is visible).
        vec3d d = krs_test::random_direction(g);
        if (krs::dot(d, n) > 0) d = -d;
        if (krs::dot(d, n) > -0.1) continue;
        // The closed form, in double: r = d - 2 (n . d) n.
        const vec3d r = d - n * (2.0 * krs::dot(n, d));
        const krs::ray<float> ray = krs::reflection_ray(vec3f(p), vec3f(n), vec3f(d), lift);
        CHECK(krs::length(vec3d(ray.direction) - r) < 1e-5);
        // The lifted origin is off the surface (the march must not stop on it) and within `lift`.
        CHECK(scene.distance(ray.origin) > 0.5f * lift);
        const closed_form_hit want = closed_form(vec3d(ray.origin), r, o.max_distance, 1e-3);
        if (want.grazing) continue;
        const krs::hit<float> h = krs::sphere_trace(scene, ray, o);
        ++checked;
        INFO("point (", p.x, ", ", p.y, ", ", p.z, ") incoming (", d.x, ", ", d.y, ", ", d.z, ") expected object ",
             want.what, " at t ", want.t, "; traced found ", h.found, " t ", h.t);
        REQUIRE(h.found == (want.what >= 0));
        if (want.what < 0) {
            ++misses;
            continue;
        }
        ++hits[want.what];
        // The traced hit stops within the threshold before the surface: along the ray that is at
        // most threshold / cos(incidence) short, 0.005 at the cosines kept (>= 0.02).
        const double error = krs::length(vec3d(krs::point_at(ray, h.t)) - (vec3d(ray.origin) + r * want.t));
        worst = std::max(worst, error);
        CHECK(error < 0.01);
        CHECK(h.t <= float(want.t) + 1e-3f);
    }
    MESSAGE(checked, " reflected rays: ", hits[0], " hit the ball, ", hits[1], " its mirror image, ",
            hits[2], " the ground, ", misses, " the sky; worst hit-point error ", worst);
    CHECK(checked > 3000);
    CHECK(hits[0] > 50);
    CHECK(hits[1] > 100);
    CHECK(hits[2] > 100);
    CHECK(misses > 500);
}

TEST_CASE("reflection rays: packet lanes equal the scalar rays and their traced hits")
{
    using P = krs::packet_f;
    constexpr std::size_t W = krs::lane_count<P>;
    const two_balls balls = make_balls();
    const krs::union_of<two_balls, krs::plane> scene(balls, krs::plane({0, 1, 0}, 0.0f));
    krs::trace_options o;
    o.pixel_footprint = 0.0f;
    o.threshold_floor = 1e-4f;
    o.max_distance = 40.0f;
    std::mt19937_64 g(8);
    // Under FMA contraction (krs_parity_contract_native, tests/support/parity.hpp) the paths may
    // fuse p + m lift and the reflection differently: the rays then agree within parity's
    // tolerance of the scene's extent (10: the balls and the plane around them), and a march that
    // passes within the threshold of a surface may stop on one side only, so hits and t agree
    // but for at most 1% of the lanes (the comparison is small: 32 packets). Otherwise bit for bit.
    krs_test::parity same_ray{"reflection rays, packet against scalar", 10.0};
    krs_test::parity same_t{"reflected hits' t, packet against scalar", 10.0};
    long lanes = 0, off = 0;
    for (int round = 0; round < 32; ++round) {
        alignas(64) float px[W], py[W], pz[W], nx[W], ny[W], nz[W], dx[W], dy[W], dz[W];
        vec3f ps[W], ns[W], ds[W];
        for (std::size_t i = 0; i < W; ++i) {
            vec3d n = krs_test::random_direction(g), d = krs_test::random_direction(g);
            if (i % 3 == 0) n = -n; // normals of either sign
            ns[i] = vec3f(n), ds[i] = vec3f(d), ps[i] = vec3f(ball_center + n * ball_radius);
            px[i] = ps[i].x, py[i] = ps[i].y, pz[i] = ps[i].z;
            nx[i] = ns[i].x, ny[i] = ns[i].y, nz[i] = ns[i].z;
            dx[i] = ds[i].x, dy[i] = ds[i].y, dz[i] = ds[i].z;
        }
        const krs::vec3<P> pp{P::load_aligned(px), P::load_aligned(py), P::load_aligned(pz)};
        const krs::vec3<P> np{P::load_aligned(nx), P::load_aligned(ny), P::load_aligned(nz)};
        const krs::vec3<P> dp{P::load_aligned(dx), P::load_aligned(dy), P::load_aligned(dz)};
        const krs::ray<P> rp = krs::reflection_ray(pp, np, dp, P(2e-4f));
        const krs::hit<P> hp = krs::sphere_trace(scene, rp, o);
        for (std::size_t i = 0; i < W; ++i) {
            const krs::ray<float> rs = krs::reflection_ray(ps[i], ns[i], ds[i], 2e-4f);
            const krs::hit<float> hs = krs::sphere_trace(scene, rs, o);
            INFO("round ", round, " lane ", i);
            const vec3f origin = krs::lane_at(rp.origin, i), direction = krs::lane_at(rp.direction, i);
            CHECK(same_ray.agree(origin.x, rs.origin.x));
            CHECK(same_ray.agree(origin.y, rs.origin.y));
            CHECK(same_ray.agree(origin.z, rs.origin.z));
            CHECK(same_ray.agree(direction.x, rs.direction.x));
            CHECK(same_ray.agree(direction.y, rs.direction.y));
            CHECK(same_ray.agree(direction.z, rs.direction.z));
            ++lanes;
            const bool same_hit = krs::mask_lane<P>(hp.found, i) == hs.found && same_t.agree(krs::lane_at(hp.t, i), hs.t);
            if (krs_test::contraction) off += !same_hit;
            else CHECK(same_hit);
        }
    }
    same_ray.report();
    same_t.report();
    if (krs_test::contraction) MESSAGE(off << " of " << lanes << " lanes differ in hit or beyond the tolerance in t");
    CHECK(off <= lanes / 100);
}

TEST_CASE("glossy mix: weight 0 is the base colour exactly, Schlick's weight is F0 head-on and 1 at grazing")
{
    const vec3f base{0.3f, 0.5f, 0.7f}, mirrored{0.9f, 0.1f, 0.2f};
    const vec3f same = krs::mix(base, mirrored, 0.0f);
    CHECK((same.x == base.x && same.y == base.y && same.z == base.z));
    CHECK(krs::mix(base, mirrored, 1.0f).x == doctest::Approx(mirrored.x));
    CHECK(krs::fresnel_schlick(1.0f, 0.04f) == doctest::Approx(0.04f));
    CHECK(krs::fresnel_schlick(0.0f, 0.04f) == doctest::Approx(1.0f));
    // (1 - cos)^5 at cos = 0.5: 1/32.
    CHECK(krs::fresnel_schlick(0.5f, 0.0f) == doctest::Approx(1.0f / 32.0f));
    // |n . d| a little above 1 by rounding is head-on, not a weight below f0.
    CHECK(krs::fresnel_schlick(1.0000001f, 0.04f) == 0.04f);
    // A reflectivity outside [0, 1] or NaN is refused, in any lane.
    for (const float bad : {-0.1f, 1.5f, std::numeric_limits<float>::quiet_NaN()})
        CHECK_THROWS_WITH_AS(krs::fresnel_schlick(0.5f, bad), doctest::Contains("fresnel_schlick.f0"), krs::invalid_parameter);
    CHECK(krs::fresnel_schlick(0.5f, 1.0f) == 1.0f);
    using P = krs::packet_f;
    alignas(64) float f0[krs::lane_count<P>];
    for (std::size_t i = 0; i < krs::lane_count<P>; ++i) f0[i] = 0.5f;
    f0[krs::lane_count<P> - 1] = std::numeric_limits<float>::quiet_NaN();
    CHECK_THROWS_WITH_AS(krs::fresnel_schlick(P(0.5f), P::load_aligned(f0)), doctest::Contains("fresnel_schlick.f0"),
                         krs::invalid_parameter);
}

// Packet tracing with lane refill, tile prepass, over-relaxation and axis-aligned mirrors, each
// against the plain scalar tracer or the general-plane sequence as the independent reference.

#include "krs/kernels/capsule.hpp"
#include "krs/kernels/plane.hpp"
#include "krs/kernels/sphere.hpp"
#include "krs/kernels/torus_capsule.hpp"
#include "krs/trace/box_clip.hpp"
#include "krs/trace/camera.hpp"
#include "krs/trace/packet_shade.hpp"
#include "krs/trace/packet_trace.hpp"
#include "krs/trace/tile_prepass.hpp"
#include "krs/trace/tile_rays.hpp"
#include "support/grid.hpp"
#include "support/random.hpp"
#include "support/rejects.hpp"
#include "support/scenes.hpp"

#include <doctest/doctest.h>

#include <algorithm>
#include <cmath>
#include <random>
#include <string>
#include <vector>

namespace {

using krs::vec3d;
using krs::vec3f;
using P = krs::packet_f;
constexpr std::size_t lanes = krs::lane_count<P>;

using krs_test::uniform;

using scene = krs_test::grove_scene;
using krs_test::grove;

krs::pinhole_camera view(int k, int width, int height)
{
    const float a = 0.6f * float(k);
    const vec3f eye{6.0f * std::sin(a) + 1.5f, 1.0f + 0.4f * float(k % 3), -6.0f * std::cos(a) + 1.5f};
    return krs::pinhole_camera(eye, {1.5f, 0.3f, 1.5f}, {0, 1, 0}, 55.0f, width, height);
}

krs::trace_options primary_options(const krs::pinhole_camera& c)
{
    krs::trace_options o;
    o.pixel_footprint = c.pixel_footprint();
    o.max_distance = 40.0f;
    o.threshold_floor = 1e-5f;
    return o;
}

// Runs the prepass of every 8 x 8 tile of the camera's image (partial tiles at its edges), then
// per_ray(r, x, y, start) for each pixel ray of the tile and per_tile(prepass, x0, y0, x1, y1).
template <class PerRay, class PerTile>
void for_each_prepassed_ray(const scene& s, const krs::pinhole_camera& camera, const krs::trace_options& o, PerRay&& per_ray,
                            PerTile&& per_tile)
{
    const int width = camera.width(), height = camera.height(), tile = 8;
    for (int y0 = 0; y0 < height; y0 += tile)
        for (int x0 = 0; x0 < width; x0 += tile) {
            const int x1 = std::min(x0 + tile, width), y1 = std::min(y0 + tile, height);
            const krs::tile_prepass pre = krs::prepass_tile(s, camera, x0, y0, x1, y1, o);
            for (int y = y0; y < y1; ++y)
                for (int x = x0; x < x1; ++x) {
                    const krs::ray<float> r = camera.primary_ray(float(x) + 0.5f, float(y) + 0.5f);
                    per_ray(r, x, y, pre.start_for(r));
                }
            per_tile(pre, x0, y0, x1, y1);
        }
}

} // namespace

TEST_CASE("refilling packet stream equals the scalar tracer per ray")
{
    const scene s = grove();
    // 37 x 29: no row is a multiple of the lane count, so packets straddle rows and the stream
    // ends on a partial packet.
    const int width = 37, height = 29;
    long long rays = 0, compared_hits = 0, refilled = 0;
    // The grove's walk ends early, so the default refills whole packets; 1 and a quarter of the
    // width refill single lanes (the default for fields of even cost).
    REQUIRE(s.varying_cost());
    for (int refill_at : {0, 1, int(lanes / 4)})
        for (float omega : {1.0f, 1.6f})
            for (int k = 0; k < 6; ++k) {
                const krs::pinhole_camera camera = view(k, width, height);
                krs::trace_options o = primary_options(camera);
                o.omega = omega;
                std::vector<krs::hit<float>> stream(std::size_t(width * height));
                std::vector<int> reported(stream.size(), 0);
                std::uint32_t next_id = 0;
                auto next = [&](krs::ray_job& job) {
                    if (next_id >= stream.size()) return false;
                    job.id = next_id++;
                    job.r = camera.primary_ray(float(job.id % width) + 0.5f, float(job.id / width) + 0.5f);
                    job.t_start = o.min_distance;
                    job.t_max = o.max_distance;
                    return true;
                };
                std::vector<std::uint32_t> order;
                auto done = [&](std::uint32_t id, const krs::hit<float>& h) {
                    stream[id] = h;
                    ++reported[id];
                    order.push_back(id);
                };
                const krs::stream_stats stats = krs::trace_stream<P, 2>(s, next, done, o, refill_at);
                CHECK(stats.rays == width * height);
                int min_steps = 1 << 30, max_steps = 0;
                for (std::size_t id = 0; id < stream.size(); ++id) {
                    REQUIRE(reported[id] == 1);
                    const krs::ray<float> r = camera.primary_ray(float(id % width) + 0.5f, float(id / width) + 0.5f);
                    const krs::hit<float> h = krs::sphere_trace(s, r, o);
                    REQUIRE(stream[id].found == h.found);
                    REQUIRE(stream[id].steps == h.steps);
                    if (h.found) {
                        REQUIRE(std::abs(stream[id].t - h.t) <= o.threshold(h.t));
                        ++compared_hits;
                    }
                    min_steps = std::min(min_steps, h.steps);
                    max_steps = std::max(max_steps, h.steps);
                    ++rays;
                }
                // Lanes really did finish at different steps, and rays finished out of issue order
                // (a lane was refilled while others of its packet still ran).
                CHECK(max_steps > 2 * min_steps);
                for (std::size_t i = 1; i < order.size(); ++i) refilled += order[i] < order[i - 1] ? 1 : 0;
            }
    CHECK(rays >= 10000);
    CHECK(compared_hits > 2000);
    CHECK(refilled > 100);
}

namespace {
// Streams the first `count` pixel rays of a 37 x 29 view through trace_stream with lane type L and
// checks each against the scalar tracer: reported exactly once, before the stream returns, with
// the same found flag, step count and (for hits) t.
template <class L, int Interleave>
void check_stream_of(std::size_t count, long long& hits)
{
    const scene s = grove();
    const int width = 37, height = 29;
    const krs::pinhole_camera camera = view(2, width, height);
    const krs::trace_options o = primary_options(camera);
    std::vector<krs::hit<float>> got(count);
    std::vector<int> reported(count, 0);
    std::uint32_t next_id = 0;
    auto next = [&](krs::ray_job& job) {
        if (next_id >= count) return false;
        job.id = next_id++;
        job.r = camera.primary_ray(float(job.id % width) + 0.5f, float(job.id / width) + 0.5f);
        job.t_start = o.min_distance, job.t_max = o.max_distance;
        return true;
    };
    auto done = [&](std::uint32_t id, const krs::hit<float>& h) {
        REQUIRE(id < count);
        got[id] = h, ++reported[id];
    };
    const krs::stream_stats stats = krs::trace_stream<L, Interleave>(s, next, done, o, 1);
    CHECK(stats.rays == (long long)count);
    for (std::size_t id = 0; id < count; ++id) {
        REQUIRE(reported[id] == 1);
        const krs::ray<float> r = camera.primary_ray(float(id % width) + 0.5f, float(id / width) + 0.5f);
        const krs::hit<float> h = krs::sphere_trace(s, r, o);
        REQUIRE(got[id].found == h.found);
        REQUIRE(got[id].steps == h.steps);
        REQUIRE(got[id].evaluations == h.evaluations);
        if (h.found) {
            REQUIRE(std::abs(got[id].t - h.t) <= o.threshold(h.t));
            ++hits;
        }
    }
}
} // namespace

TEST_CASE("stream results leave in runs: every ray once, as the scalar tracer, for any count of rays")
{
    // The stream keeps finished rays in a buffer and reports them to `done` in runs of 256 and
    // when it ends: counts below, at and past one run and several runs, packets and scalars.
    long long hits = 0;
    for (std::size_t count : {std::size_t(1), std::size_t(15), std::size_t(255), std::size_t(256), std::size_t(257),
                              std::size_t(700), std::size_t(37 * 29)}) {
        CAPTURE(count);
        check_stream_of<P, 2>(count, hits);
        check_stream_of<P, 4>(count, hits);
        check_stream_of<float, 3>(count, hits);
    }
    CHECK(hits > 500);
}

TEST_CASE("plain packets with partial lanes at the image edge equal the scalar tracer")
{
    const scene s = grove();
    const int width = 45, height = 23; // 45 = 2 * 16 + 13: the last packet of a row is partial
    long long rays = 0;
    for (int k = 0; k < 4; ++k) {
        const krs::pinhole_camera camera = view(k + 7, width, height);
        const krs::trace_options o = primary_options(camera);
        for (int y = 0; y < height; ++y)
            for (int x0 = 0; x0 < width; x0 += int(lanes)) {
                alignas(64) float xs[lanes], start[lanes];
                for (std::size_t i = 0; i < lanes; ++i) {
                    xs[i] = float(std::min(x0 + int(i), width - 1)) + 0.5f;
                    // Lanes past the edge get an infinite start: rejected, they cost no step.
                    start[i] = x0 + int(i) < width ? 0.0f : INFINITY;
                }
                const krs::ray<P> r = camera.primary_ray(P::load_aligned(xs), P(float(y) + 0.5f));
                const krs::hit<P> hp = krs::sphere_trace(s, r, P::load_aligned(start), P(o.max_distance), o);
                for (std::size_t i = 0; i < lanes; ++i) {
                    if (x0 + int(i) >= width) {
                        REQUIRE(krs::mask_lane<P>(hp.invalid, i));
                        REQUIRE(!krs::mask_lane<P>(hp.found, i));
                        continue;
                    }
                    const krs::hit<float> h = krs::sphere_trace(s, camera.primary_ray(xs[i], float(y) + 0.5f), o);
                    REQUIRE(krs::mask_lane<P>(hp.found, i) == h.found);
                    if (h.found) REQUIRE(std::abs(krs::lane_at(hp.t, i) - h.t) <= o.threshold(h.t));
                    ++rays;
                }
            }
    }
    CHECK(rays > 4000);
}

TEST_CASE("tile prepass never starts a ray past its first hit")
{
    const scene s = grove();
    const int width = 61, height = 45;
    long long rays = 0, advanced = 0, hits = 0, near_misses = 0;
    double skipped = 0;
    for (int k = 0; k < 4; ++k) {
        const krs::pinhole_camera camera = view(k + 3, width, height);
        const krs::trace_options o = primary_options(camera);
        const auto per_ray = [&](const krs::ray<float>& r, int, int, float start) {
            const krs::hit<float> h = krs::sphere_trace(s, r, o);
            // Independent check: march the segment [0, start] in tiny steps; the field stays
            // above the hit threshold everywhere on it.
            for (float t = 0; t < start; t += 0.02f) REQUIRE(s.distance(krs::point_at(r, t)) >= o.threshold(t));
            REQUIRE(s.distance(krs::point_at(r, start)) >= o.threshold(start));
            if (h.found) {
                REQUIRE(start <= h.t);
                ++hits;
            }
            // The prepass-started ray may step over a near miss where plain tracing stopped
            // (their samples differ), but never through the surface: the field stays positive on
            // everything it skipped.
            const krs::hit<float> hp = krs::sphere_trace(s, r, start, o.max_distance, o);
            if (h.found && (!hp.found || hp.t > h.t + 2 * o.threshold(h.t))) {
                ++near_misses;
                // Steps of half the distance (at least 1e-4, thinner than any kernel) would land
                // inside a surface the ray crossed.
                const float end = hp.found ? hp.t : o.max_distance;
                for (float t = h.t; t < end;) {
                    const float d = s.distance(krs::point_at(r, t));
                    REQUIRE(d > 0.0f);
                    t += std::max(0.5f * d, 1e-4f);
                }
            }
            advanced += start > o.min_distance ? 1 : 0;
            skipped += start;
            ++rays;
        };
        // The packet walk of the stored spheres equals the scalar one.
        const auto per_tile = [&](const krs::tile_prepass& pre, int x0, int y0, int x1, int) {
            alignas(64) float xs[lanes];
            for (std::size_t i = 0; i < lanes; ++i) xs[i] = float(x0 + int(i) % (x1 - x0)) + 0.5f;
            const float yc = float(y0) + 0.5f;
            const P sp = pre.start_for(camera.primary_ray(P::load_aligned(xs), P(yc)));
            for (std::size_t i = 0; i < lanes; ++i)
                REQUIRE(krs::lane_at(sp, i) == doctest::Approx(pre.start_for(camera.primary_ray(xs[i], yc))).epsilon(1e-5));
        };
        for_each_prepassed_ray(s, camera, o, per_ray, per_tile);
    }
    CHECK(rays >= 10000);
    CHECK(hits > 2000);
    CHECK(advanced > rays / 2); // the prepass does skip empty space
    CHECK(skipped / double(rays) > 1.0);
    CHECK(near_misses < rays / 100);
}

TEST_CASE("tile prepass at high resolution and at wide angles")
{
    const scene s = grove();
    // A narrow field of view at 960 x 540: the tile's rays are 3e-4 radians apart and the
    // extra spheres lie at depths of 5-10, where float error in a sphere's exit and in the
    // beam's half-angle had grown past the hit threshold (7403 of 12 million 1080p rays started
    // inside the solid, and hits came more than 2 thresholds late).
    const int width = 960, height = 540, tile = 8;
    long long rays = 0, traced = 0, below = 0, late = 0, lost = 0;
    for (int k = 0; k < 3; ++k) {
        const float a = 0.6f * float(k);
        const vec3f eye{6.0f * std::sin(a) + 1.5f, 1.0f + 0.4f * float(k % 3), -6.0f * std::cos(a) + 1.5f};
        const krs::pinhole_camera camera(eye, {1.5f, 0.3f, 1.5f}, {0, 1, 0}, 10.0f, width, height);
        const krs::trace_options o = primary_options(camera);
        const auto per_ray = [&](const krs::ray<float>& r, int x, int y, float start) {
            const float d = s.distance(krs::point_at(r, start)), threshold = o.threshold(start);
            ++rays;
            // A start at the threshold to within float rounding is fine; below by more means
            // the prepass moved the ray into a near miss or the solid.
            if (d < threshold * (1.0f - 1e-3f)) ++below;
            if (d >= threshold && (x + y) % 16 != 0) return; // trace a sample, and every doubtful ray
            ++traced;
            const krs::hit<float> h = krs::sphere_trace(s, r, o);
            const krs::hit<float> hp = krs::sphere_trace(s, r, start, o.max_distance, o);
            if (h.found && !hp.found) ++lost;
            if (h.found && hp.found && hp.t > h.t + 2 * o.threshold(h.t)) ++late;
        };
        for_each_prepassed_ray(s, camera, o, per_ray, [](const krs::tile_prepass&, int, int, int, int) {});
    }
    CHECK(rays == 3LL * width * height);
    CHECK(traced > rays / 20);
    CHECK(below == 0);
    CHECK(late == 0);
    CHECK(lost == 0);

    // Every pixel ray of a tile lies inside the tile's beam cone (measured in double, by atan2).
    // acos of a float dot product had lost 3e-4 radians near 0: 30% of these tiles had a corner
    // ray up to 3.9% outside.
    const krs::pinhole_camera wide_frame({14.5f, 3.9f, -5.2f}, {0.23f, -0.04f, 2.1f}, {0, 1, 0}, 30.0f, 1920, 1080);
    long long outside = 0;
    for (int y0 = 0; y0 < 1080; y0 += tile)
        for (int x0 = 0; x0 < 1920; x0 += tile) {
            const auto beam = wide_frame.beam(x0, y0, x0 + tile, y0 + tile);
            const double claimed = std::atan2(double(beam.sin_half_angle), double(beam.cos_half_angle));
            const vec3d axis = krs::normalize(vec3d(beam.axis.direction));
            for (int y = y0; y < y0 + tile; ++y)
                for (int x = x0; x < x0 + tile; ++x) {
                    const vec3d v = krs::normalize(vec3d(wide_frame.primary_ray(float(x) + 0.5f, float(y) + 0.5f).direction));
                    outside += std::atan2(krs::length(krs::cross(axis, v)), krs::dot(axis, v)) > claimed ? 1 : 0;
                }
        }
    CHECK(outside == 0);

    // A tile wider than 90 degrees of half-angle (a 165 degree camera): the cone march would put
    // its spheres behind the eye and started rays past their hits; the tile starts at
    // min_distance instead, and its rays still find every hit.
    const krs::pinhole_camera fisheye({-6.73318911f, 5.6227231f, 8.15033817f}, {1.648399f, -0.0485729314f, 1.27629328f},
                                      {0, 1, 0}, 164.7f, 104, 47);
    krs::trace_options o = primary_options(fisheye);
    o.max_distance = 60;
    REQUIRE(fisheye.beam(29, 0, 58, 29).cos_half_angle < 0.0f);
    for (int extra : {0, 4}) {
        const krs::tile_prepass pre = krs::prepass_tile(s, fisheye, 29, 0, 58, 29, o, extra);
        int hits = 0;
        for (int y = 0; y < 29; ++y)
            for (int x = 29; x < 58; ++x) {
                const krs::ray<float> r = fisheye.primary_ray(float(x) + 0.5f, float(y) + 0.5f);
                const krs::hit<float> h = krs::sphere_trace(s, r, o);
                if (!h.found) continue;
                ++hits;
                const float start = pre.start_for(r);
                REQUIRE(start <= h.t);
                const krs::hit<float> hp = krs::sphere_trace(s, r, start, o.max_distance, o);
                REQUIRE(hp.found);
                REQUIRE(hp.t <= h.t + 2 * o.threshold(h.t));
            }
        CHECK(hits > 100);
    }
}

TEST_CASE("over-relaxation with its fallback never misses a hit of plain tracing")
{
    // Thin kernels (tubes of radius 0.004 ... 0.02) and rays grazing them: aimed at points just
    // off the tube surface, nearly along the tube.
    using thin_scene = krs::sequence<krs::capsule, krs::torus_capsule>;
    thin_scene::builder b;
    b.kernel(krs::capsule({0, 0, 0}, {0, 2, 0}, 0.02f));
    b.kernel(krs::torus_capsule({0, 2, 0}, {1, 3, 0.3f}, {0.6f, 2.3f, 0}, 0.004f));
    b.mirror(krs::mirror({1, 0, 0.1f}, 1.3f));
    b.mirror(krs::mirror({0, 0, 1}, 1.1f));
    const thin_scene s = b.build();
    std::mt19937_64 g(11);
    krs::trace_options plain;
    plain.pixel_footprint = 2e-4f;
    plain.threshold_floor = 1e-5f;
    plain.max_distance = 30.0f;
    plain.max_steps = 4000;
    int plain_hits = 0, fallbacks = 0;
    long long plain_evaluations = 0, relaxed_evaluations = 0;
    for (int k = 0; k < 12000; ++k) {
        // A point near a kernel instance: pick a height on the trunk or the twig, offset it by
        // about the tube radius, and shoot a ray at it from afar at a grazing angle.
        const double u = uniform(g, 0, 1);
        vec3d target = k % 2 ? vec3d{0, 2 * u, 0} : vec3d{0.6 * u, 2 + u, 0.15 * u};
        target = target + vec3d{uniform(g, -0.03, 0.03), 0, uniform(g, -0.03, 0.03)};
        if (k % 3 == 0) target.x = 2.6 - target.x; // a mirrored instance
        const vec3d along = k % 2 ? vec3d{0, 1, 0} : krs::normalize(vec3d{0.6, 1, 0.15});
        const vec3d side = krs::normalize(vec3d{uniform(g, -1, 1), uniform(g, -0.2, 0.2), uniform(g, -1, 1)});
        const vec3d dir = krs::normalize(along * uniform(g, -1, 1) + side * uniform(g, 0.05, 1));
        const vec3d origin = target - dir * uniform(g, 3, 8);
        const krs::ray<float> r{vec3f{float(origin.x), float(origin.y), float(origin.z)},
                                vec3f{float(dir.x), float(dir.y), float(dir.z)}};
        const krs::hit<float> h = krs::sphere_trace(s, r, plain);
        plain_evaluations += h.evaluations;
        for (float omega : {1.3f, 1.6f, 1.9f}) {
            krs::trace_options relaxed = plain;
            relaxed.omega = omega;
            const krs::hit<float> hr = krs::sphere_trace(s, r, relaxed);
            if (omega == 1.6f) relaxed_evaluations += hr.evaluations;
            if (h.found) {
                REQUIRE(hr.found);
                // It stopped where the field is within its threshold, no later than plain.
                REQUIRE(s.distance(krs::point_at(r, hr.t)) < relaxed.threshold(hr.t));
                REQUIRE(hr.t <= h.t + plain.threshold(h.t));
            }
            fallbacks += hr.steps > h.steps ? 1 : 0;
        }
        plain_hits += h.found ? 1 : 0;
    }
    CHECK(plain_hits > 3000);
    CHECK(fallbacks > 0); // the fallback path was exercised
    MESSAGE("evaluations: plain ", plain_evaluations, ", omega 1.6 ", relaxed_evaluations);
}

TEST_CASE("over-relaxation finds the hits plain tracing finds just before a far limit")
{
    // A relaxed step that overshot t_max ended the ray, though the plain step would have gone on
    // and found the surface between t + d and t_max: with a clipping box, t_max is the box's far
    // side. A sphere of radius 1 at the origin, rays from 3 to 20 away, t_max just past the hit.
    const krs::sphere ball({0, 0, 0}, 1.0f);
    std::mt19937_64 g(19);
    int hits = 0;
    for (int k = 0; k < 20000; ++k) {
        const vec3d to = krs::normalize(vec3d{uniform(g, -1, 1), uniform(g, -1, 1), uniform(g, -1, 1)});
        const vec3d origin = to * uniform(g, 3, 20);
        const vec3d aim = vec3d{uniform(g, -0.9, 0.9), uniform(g, -0.9, 0.9), uniform(g, -0.9, 0.9)};
        const vec3d dir = krs::normalize(aim - origin);
        const krs::ray<float> r{vec3f{float(origin.x), float(origin.y), float(origin.z)},
                                vec3f{float(dir.x), float(dir.y), float(dir.z)}};
        krs::trace_options plain;
        plain.pixel_footprint = 1e-4f;
        plain.threshold_floor = 1e-5f;
        const krs::hit<float> reference = krs::sphere_trace(ball, r, plain);
        if (!reference.found) continue;
        plain.max_distance = reference.t + float(uniform(g, 0.0, 2.0));
        const krs::hit<float> h = krs::sphere_trace(ball, r, plain);
        REQUIRE(h.found);
        for (float omega : {1.3f, 1.6f, 1.9f}) {
            krs::trace_options relaxed = plain;
            relaxed.omega = omega;
            const krs::hit<float> hr = krs::sphere_trace(ball, r, relaxed);
            INFO("omega ", omega, ", hit at ", h.t, ", t_max ", plain.max_distance);
            REQUIRE(hr.found);
            REQUIRE(std::abs(hr.t - h.t) <= 2 * plain.threshold(h.t));
        }
        ++hits;
    }
    CHECK(hits > 5000);
}

TEST_CASE_TEMPLATE("axis-aligned mirrors give the distances of the same general planes", T, float, P)
{
    std::mt19937_64 g(5);
    using axis_scene = krs::axis_sequence<krs::sphere, krs::capsule>;
    using general_scene = krs::sequence<krs::sphere, krs::capsule>;
    int compared = 0;
    for (int trial = 0; trial < 20; ++trial) {
        axis_scene::builder a;
        general_scene::builder b;
        const krs::sphere leaf({float(uniform(g, -1, 1)), float(uniform(g, -1, 1)), float(uniform(g, -1, 1))}, 0.3f);
        const krs::capsule stem({0, 0, 0}, {float(uniform(g, -1, 1)), 1.5f, float(uniform(g, -1, 1))}, 0.1f);
        a.kernel(leaf), b.kernel(leaf);
        a.kernel(stem), b.kernel(stem);
        const int n = 3 + trial % 10;
        for (int i = 0; i < n; ++i) {
            const int axis = int(g() % 3);
            const float position = float(uniform(g, -3, 3));
            const bool above = (g() & 1) != 0;
            const krs::axis_mirror m(axis, position, above);
            // Independent check of the stored plane against its definition x_axis = position: a
            // point there has zero signed distance, and a point off it keeps its side when its side
            // is the kept one (x_axis below the position for `above`) and is mirrored to it
            // otherwise, as the general fold does.
            for (int q = 0; q < 8; ++q) {
                double c[3] = {uniform(g, -5, 5), uniform(g, -5, 5), uniform(g, -5, 5)};
                c[axis] = position;
                REQUIRE(m.signed_distance(vec3d{c[0], c[1], c[2]}) == 0.0);
                const double offset = uniform(g, 0.01, 4) * (q % 2 ? 1 : -1);
                c[axis] = double(position) + offset;
                const vec3d p{c[0], c[1], c[2]};
                const vec3d folded = m.fold(p), general = m.general().fold(p);
                const double kept[3] = {folded.x, folded.y, folded.z};
                const bool on_kept_side = above ? offset < 0 : offset > 0;
                REQUIRE(kept[axis] == doctest::Approx(on_kept_side ? c[axis] : 2.0 * position - c[axis]));
                REQUIRE(krs::length(folded - general) < 1e-5);
            }
            a.mirror(m);
            b.mirror(m.general());
            if (i == n / 2) {
                const krs::sphere extra({float(uniform(g, -2, 2)), 0.5f, float(uniform(g, -2, 2))}, 0.2f);
                a.kernel(extra), b.kernel(extra);
            }
        }
        const axis_scene sa = a.build();
        const general_scene sb = b.build();
        for (int k = 0; k < 500; ++k) {
            alignas(64) float px[lanes], py[lanes], pz[lanes];
            for (std::size_t i = 0; i < lanes; ++i)
                px[i] = float(uniform(g, -8, 8)), py[i] = float(uniform(g, -8, 8)), pz[i] = float(uniform(g, -8, 8));
            krs::vec3<T> p;
            if constexpr (std::is_same_v<T, float>)
                p = {px[0], py[0], pz[0]};
            else
                p = {T::load_aligned(px), T::load_aligned(py), T::load_aligned(pz)};
            const T da = sa.distance(p), db = sb.distance(p);
            for (std::size_t i = 0; i < krs::lane_count<T>; ++i) {
                // Each fold rounds a coordinate of size <= ~20 differently (2c - x versus
                // x - 2(x - c)): a few ulps of 20 per level.
                const float tolerance = float(n) * 8.0f * 20.0f * 1.2e-7f;
                REQUIRE(std::abs(krs::lane_at(da, i) - krs::lane_at(db, i)) <= tolerance);
                ++compared;
            }
            // Both folds reflect the same points (away from the planes, where rounding can flip it).
            const vec3f q{px[0], py[0], pz[0]};
            const krs::location<float> la = sa.locate(q), lb = sb.locate(q);
            if (std::abs(la.distance - lb.distance) < 1e-6f && la.kernel == lb.kernel)
                CHECK(krs::length(la.kernel_point - lb.kernel_point) < 1e-3f);
        }
    }
    CHECK(compared >= 10000);
}

TEST_CASE("packet shadow query and Lambert shade equal the scalar ones")
{
    using ground_scene = krs::sequence<krs::sphere, krs::plane>;
    ground_scene::builder b;
    b.kernel(krs::sphere({0, 1, 0}, 0.5f));
    b.mirror(krs::mirror({1, 0, 0}, 1.0f));
    b.kernel(krs::plane({0, 1, 0}, 0.0f));
    const ground_scene s = b.build();
    const vec3f to_light = krs::normalize(vec3f{0.4f, 1.0f, 0.2f});
    std::mt19937_64 g(3);
    int shadowed = 0, lit = 0;
    for (int k = 0; k < 400; ++k) {
        alignas(64) float px[lanes], pz[lanes], th[lanes];
        for (std::size_t i = 0; i < lanes; ++i)
            px[i] = float(uniform(g, -1.5, 3.5)), pz[i] = float(uniform(g, -2, 2)), th[i] = float(uniform(g, 1e-4, 1e-2));
        const krs::vec3<P> p{P::load_aligned(px), P(0.0f), P::load_aligned(pz)};
        const krs::vec3<P> n{P(0.0f), P(1.0f), P(0.0f)};
        const P threshold = P::load_aligned(th);
        const auto visible = krs::light_visible(s, p, n, to_light, threshold, 20.0f, P(0.0f) == P(0.0f));
        std::array<krs::location<float>, lanes> where;
        const krs::vec3<P> located = krs::locate_lanes(s, p + n * P(1e-3f), P(0.0f) == P(0.0f), where);
        for (std::size_t i = 0; i < lanes; ++i) {
            // Independent reference: the closed-form ray/sphere test against both instances.
            const vec3d o{px[i], 2.0 * th[i], pz[i]};
            bool blocked = false;
            for (double cx : {0.0, 2.0}) {
                const vec3d oc = o - vec3d{cx, 1, 0};
                const double bq = krs::dot(oc, vec3d(to_light)), c = krs::dot(oc, oc) - 0.25;
                const double disc = bq * bq - c;
                // Rays passing within the threshold of the sphere count as blocked either way.
                if (disc > 0.01 && -bq - std::sqrt(disc) > 0) blocked = true;
            }
            const bool v = krs::mask_lane<P>(visible, i);
            if (blocked) REQUIRE(!v);
            shadowed += v ? 0 : 1;
            lit += v ? 1 : 0;
            REQUIRE(krs::lane_at(located.y, i) == doctest::Approx(1.0f));
            REQUIRE(where[i].kernel == 1); // the plane (level 1's only kernel)
        }
        const krs::vec3<P> color = krs::shade_lambert_lanes(s, p, n, to_light, {1, 1, 1}, krs::vec3<P>(vec3f{1, 1, 1}),
                                                            0.1f, threshold, 20.0f, P(0.0f) == P(0.0f));
        for (std::size_t i = 0; i < lanes; ++i) {
            const float expected = 0.1f + (krs::mask_lane<P>(visible, i) ? to_light.y : 0.0f);
            REQUIRE(krs::lane_at(color.x, i) == doctest::Approx(expected));
        }
    }
    CHECK(shadowed > 50);
    CHECK(lit > 50);
}

TEST_CASE_TEMPLATE("mask bits: a mask as a word of lane bits and back", T, float, double, krs::packet_f, krs::packet_d)
{
    constexpr std::size_t W = krs::lane_count<T>;
    std::mt19937_64 g(5);
    for (int trial = 0; trial < 200; ++trial) {
        // A mask made by a comparison, read lane by lane: its word has bit i exactly for lane i.
        alignas(64) krs::scalar_t<T> values[W];
        std::uint64_t expected = 0;
        for (std::size_t i = 0; i < W; ++i) {
            values[i] = krs::scalar_t<T>(int(g() % 7) - 3);
            if (values[i] > 0) expected |= std::uint64_t(1) << i;
        }
        T x;
        if constexpr (std::floating_point<T>)
            x = values[0];
        else
            x = T::load_aligned(values);
        const krs::mask_t<T> m = x > T(0);
        REQUIRE(krs::mask_bits<T>(m) == expected);
        // A word turned into a mask sets exactly its lanes.
        const std::uint64_t word = g() & (W == 64 ? ~std::uint64_t(0) : (std::uint64_t(1) << W) - 1);
        const krs::mask_t<T> back = krs::mask_from_bits<T>(word);
        for (std::size_t i = 0; i < W; ++i) REQUIRE(krs::mask_lane<T>(back, i) == (((word >> i) & 1u) != 0));
    }
}

TEST_CASE("box clip: a clipped ray starts before its first possible stop, ends after its last, and a ray that misses the box takes no step")
{
    // The grove without its ground (bounded), and a flat grid of rings seen from above at an
    // angle (most of its sphere is empty); primary and four-pixel thresholds.
    const scene grove_only = grove(false);
    krs::axis_sequence<krs::sphere, krs::torus_capsule>::builder rb;
    rb.kernel(krs::torus_capsule({-0.5f, 0, 0}, {0.5f, 0, 0}, {0, 0.5f, 0}, 0.1f));
    rb.kernel(krs::torus_capsule({-0.5f, 0, 0}, {0.5f, 0, 0}, {0, -0.5f, 0}, 0.1f));
    const std::array<double, 2> reach = krs_test::add_grid_mirrors(rb, 6, 0.6, 0.2);
    const auto rings = rb.build();
    const int width = 41, height = 31;
    long long rays = 0, missed_box = 0, later_start = 0, earlier_end = 0, hits = 0, differ = 0;
    const auto check_scene = [&](const auto& s, const krs::pinhole_camera& camera, float pixels) {
        krs::trace_options o = primary_options(camera);
        o.pixel_footprint *= pixels;
        const krs::box_clip clip(krs::field_box(s), camera.eye(), o);
        REQUIRE(clip.clips());
        for (int y = 0; y < height; ++y)
            for (int x = 0; x < width; ++x) {
                const krs::ray<float> r = camera.primary_ray(float(x) + 0.5f, float(y) + 0.5f);
                float t0 = o.min_distance, t1 = o.max_distance;
                clip.apply(r, t0, t1);
                const krs::hit<float> plain = krs::sphere_trace(s, r, o);
                const krs::hit<float> clipped = krs::sphere_trace(s, r, t0, t1, o);
                // Independent check: outside [t0, t1] the field stays above the hit threshold
                // (sampled every 0.01), so no tracer could stop there.
                const float last = t1 < t0 ? o.max_distance : t0;
                for (float t = o.min_distance; t < last; t += 0.01f)
                    REQUIRE(s.distance(krs::point_at(r, t)) >= o.threshold(t));
                if (t1 >= t0)
                    for (float t = t1; t < o.max_distance; t += 0.01f)
                        REQUIRE(s.distance(krs::point_at(r, t)) >= o.threshold(t));
                if (t1 < t0) {
                    ++missed_box;
                    REQUIRE(!clipped.found);
                    REQUIRE(clipped.evaluations == 0);
                } else {
                    later_start += t0 > o.min_distance;
                    earlier_end += t1 < o.max_distance;
                }
                // The same hits, up to grazing rays: their samples differ, so one may stop in a
                // thin near-miss region the other stepped over. Where they differ, the miss is a
                // near miss: the field stays positive along it (steps of half the distance, at
                // least 1e-4, would land inside a surface it crossed).
                if (clipped.found != plain.found || (plain.found && std::abs(clipped.t - plain.t) > 2 * o.threshold(plain.t))) {
                    ++differ;
                    const krs::hit<float>& other = clipped.found && (!plain.found || clipped.t < plain.t) ? plain : clipped;
                    const float from = std::min(clipped.found ? clipped.t : o.max_distance, plain.found ? plain.t : o.max_distance);
                    const float to = other.found ? other.t : o.max_distance;
                    for (float t = from; t < to;) {
                        const float d = s.distance(krs::point_at(r, t));
                        REQUIRE(d > 0.0f);
                        t += std::max(0.5f * d, 1e-4f);
                    }
                }
                hits += plain.found;
                ++rays;
            }
    };
    for (int k = 0; k < 3; ++k)
        for (float pixels : {1.0f, 4.0f}) {
            check_scene(grove_only, view(k, width, height), pixels);
            const vec3f middle{float(reach[0]) / 2, 0, float(reach[1]) / 2};
            const krs::pinhole_camera above(middle + vec3f{-5.0f + 3.0f * float(k), 4.0f, -6.0f}, middle, {0, 1, 0}, 50.0f,
                                            width, height);
            check_scene(rings, above, pixels);
        }
    MESSAGE("rays ", rays, ": missed the box ", missed_box, ", started later ", later_start, ", ended earlier ",
            earlier_end, ", hits ", hits, ", near misses that differ ", differ);
    // Grazing rays sample differently from another start: with the boxes from the kernels' exact
    // boxes (tighter, so rays start later) 90 of these 15252 rays differ, against 65 with the
    // boxes from the kernels' spheres; each is checked above to be a near miss.
    CHECK(differ <= rays / 100);
    CHECK(missed_box > rays / 40);
    CHECK(later_start > rays / 4);
    CHECK(earlier_end > rays / 4);
    CHECK(hits > rays / 10);
}

TEST_CASE("a stream of clipped tile rays reports every pixel once, as the scalar tracer does")
{
    // Rays that miss the box are reported as they are pulled, without a lane or a step; the others
    // are traced in refilled packets. Reference: the scalar tracer on the same clipped range.
    const scene s = grove(false);
    const int width = 45, height = 33, tile = 8;
    // Wide and far: the grove's box covers the middle of the picture only.
    const krs::pinhole_camera camera({1.5f, 3.0f, -9.0f}, {1.5f, 0.3f, 1.5f}, {0, 1, 0}, 75.0f, width, height);
    const krs::trace_options o = primary_options(camera);
    const krs::box_clip clip(krs::field_box(s), camera.eye(), o);
    krs::tile_prepass from_near;
    from_near.start = o.min_distance;
    std::vector<krs::hit<float>> got(std::size_t(width * height));
    std::vector<int> reported(got.size(), 0);
    int x0 = -tile, y0 = 0;
    krs::tile_rays<P> rays;
    auto next = [&](krs::ray_job& job) {
        while (!rays.pop(job)) {
            if ((x0 += tile) >= width) x0 = 0, y0 += tile;
            if (y0 >= height) return false;
            rays.fill(camera, x0, y0, x0 + tile, y0 + tile, from_near, o.max_distance, clip);
        }
        return true;
    };
    auto done = [&](std::uint32_t id, const krs::hit<float>& h) { got[id] = h, ++reported[id]; };
    krs::trace_stream<P, 2>(s, next, done, o);
    int missed_box = 0, differ = 0;
    for (int y = 0; y < height; ++y)
        for (int x = 0; x < width; ++x) {
            const std::size_t id = std::size_t(y * width + x);
            REQUIRE(reported[id] == 1);
            const krs::ray<float> r = camera.primary_ray(float(x) + 0.5f, float(y) + 0.5f);
            float t0 = o.min_distance, t1 = o.max_distance;
            clip.apply(r, t0, t1);
            const krs::hit<float> h = krs::sphere_trace(s, r, t0, t1, o);
            if (t1 < t0) {
                ++missed_box;
                REQUIRE(!got[id].found);
                REQUIRE(got[id].evaluations == 0);
            }
            // Packet and scalar math round differently: a grazing ray may end a step apart.
            differ += got[id].found != h.found || (h.found && std::abs(got[id].t - h.t) > 2 * o.threshold(h.t));
        }
    CHECK(missed_box > 0);
    CHECK(differ <= width * height / 200);
}

TEST_CASE_TEMPLATE("queue_tile_rays: every pixel's ray and id past 2^23 pixels in one tile", L, float, P)
{
    // A tile of 4096 x 2050 = 2^23 + 8192 pixels inside a wider image: in float k + 1/2 rounds to
    // even from 2^23 on, which put the last pixel of each of the tile's last two rows in the next
    // row (a ray one row down and the id of a pixel left of the tile). Reference: the pixel's own
    // row and column in integers and the scalar camera ray through its centre.
    const int width = 4100, height = 2050, x0 = 2, columns = 4096;
    const krs::pinhole_camera camera({0, 0, -5}, {0, 0, 0}, {0, 1, 0}, 60.0f, width, height);
    krs::ray_queue<L> queue;
    const std::size_t count = krs::queue_tile_rays(queue, camera, x0, 0, x0 + columns, height, krs::tile_prepass{}, 100.0f);
    REQUIRE(count == std::size_t(columns) * std::size_t(height));
    REQUIRE(queue.size() == count);
    // A pixel's angle is about 2.6e-4 here: a ray one pixel off is far outside the tolerance.
    std::size_t wrong_id = 0, wrong_ray = 0;
    for (std::size_t i = 0; i < count; ++i) {
        const krs::ray_job job = queue.job(i);
        const int x = x0 + int(i % std::size_t(columns)), y = int(i / std::size_t(columns));
        wrong_id += job.id != std::uint32_t(y * width + x);
        const krs::ray<float> r = camera.primary_ray(float(x) + 0.5f, float(y) + 0.5f);
        wrong_ray += krs::length(job.r.direction - r.direction) > 1e-5f;
    }
    CHECK(wrong_id == 0);
    CHECK(wrong_ray == 0);
    // A tile too wide for exact lane maths is refused, naming the parameter.
    const krs::pinhole_camera wide({0, 0, -5}, {0, 0, 0}, {0, 1, 0}, 60.0f, (1 << 22) + 1, 1);
    CHECK_THROWS_WITH_AS(krs::queue_tile_rays(queue, wide, 0, 0, (1 << 22) + 1, 1, krs::tile_prepass{}, 100.0f),
                         doctest::Contains("queue_tile_rays.x1"), krs::invalid_parameter);
}

TEST_CASE("box clip: parallel rays, unbounded boxes and huge footprints")
{
    krs::trace_options o;
    o.threshold_floor = 1e-4f;
    o.pixel_footprint = 0.0f;
    const krs::bounding_box box{{-1, -1, -1}, {1, 1, 1}};
    const krs::box_clip clip(box, {0, 0, -5}, o);
    // Along z through the box: enters near 4 and leaves near 6, grown by the threshold only.
    float t0 = 0, t1 = 100;
    clip.apply(krs::ray<float>{{0, 0, -5}, {0, 0, 1}}, t0, t1);
    CHECK(t0 == doctest::Approx(4.0f).epsilon(1e-4));
    CHECK(t1 == doctest::Approx(6.0f).epsilon(1e-4));
    // Parallel to the x and y slabs but outside the y slab: misses.
    t0 = 0, t1 = 100;
    clip.apply(krs::ray<float>{{0, 1.5f, -5}, {0, 0, 1}}, t0, t1);
    CHECK(t1 < t0);
    // Starting inside the box: the start stays.
    const krs::box_clip inside(box, {0, 0, 0}, o);
    t0 = 0.25f, t1 = 100;
    inside.apply(krs::ray<float>{{0, 0, 0}, {1, 0, 0}}, t0, t1);
    CHECK(t0 == 0.25f);
    CHECK(t1 == doctest::Approx(1.0f).epsilon(1e-3));
    // A packet gives each lane the scalar answer.
    alignas(64) float oy[lanes];
    for (std::size_t i = 0; i < lanes; ++i) oy[i] = -2.0f + 4.0f * float(i) / float(lanes);
    P pt0(0.0f), pt1(100.0f);
    clip.apply(krs::ray<P>{{P(0.0f), P::load_aligned(oy), P(-5.0f)}, {P(0.0f), P(0.0f), P(1.0f)}}, pt0, pt1);
    for (std::size_t i = 0; i < lanes; ++i) {
        float s0 = 0, s1 = 100;
        clip.apply(krs::ray<float>{{0, oy[i], -5}, {0, 0, 1}}, s0, s1);
        CHECK(krs::lane_at(pt0, i) == s0);
        CHECK(krs::lane_at(pt1, i) == s1);
    }
    // A non-finite origin and invalid options are refused by name.
    using krs_test::rejects;
    rejects([&] { krs::box_clip(box, {std::nanf(""), 0, 0}, o); }, "box_clip.origin");
    krs::trace_options negative = o;
    negative.threshold_floor = -1.0f;
    rejects([&] { krs::box_clip(box, {0, 0, -5}, negative); }, "trace_options.threshold_floor");
    // Nothing to clip to, or a threshold that grows as fast as the ray: no clipping.
    CHECK(!krs::box_clip(krs::bounding_box::unbounded(), {0, 0, 0}, o).clips());
    o.pixel_footprint = 0.6f;
    CHECK(!krs::box_clip(box, {0, 0, -5}, o).clips());
    // A ray whose start is past its end reports a miss without a step.
    const krs::hit<float> h = krs::sphere_trace(krs::sphere({0, 0, 0}, 1.0f), krs::ray<float>{{0, 0, -5}, {0, 0, 1}}, 5.0f, 4.0f, o);
    CHECK(!h.found);
    CHECK(h.evaluations == 0);
}

TEST_CASE("tile rays: every pixel of a clipped tile once, with the scalar camera ray and prepass start")
{
    const scene s = grove();
    const int width = 37, height = 29;
    const krs::pinhole_camera camera = view(2, width, height);
    const krs::trace_options o = primary_options(camera);
    krs::tile_rays<P> rays;
    std::vector<int> seen(std::size_t(width) * height, 0);
    long long checked = 0, set_aside = 0;
    // Tiles of 12 x 10 overrun the right and bottom edges; one lies wholly outside.
    for (int y0 = 0; y0 < height + 10; y0 += 10)
        for (int x0 = 0; x0 < width + 12; x0 += 12) {
            const krs::tile_prepass pre = krs::prepass_tile(s, camera, std::min(x0, width - 1),
                                                            std::min(y0, height - 1), std::min(x0 + 12, width),
                                                            std::min(y0 + 10, height), o);
            rays.fill(camera, x0, y0, x0 + 12, y0 + 10, pre, o.max_distance);
            const int expected = std::max(0, std::min(x0 + 12, width) - x0) * std::max(0, std::min(y0 + 10, height) - y0);
            REQUIRE(rays.remaining() == std::size_t(expected));
            krs::ray_job job;
            while (rays.pop(job)) {
                REQUIRE(job.id < seen.size());
                ++seen[job.id];
                const int x = int(job.id) % width, y = int(job.id) / width;
                REQUIRE((x >= x0 && x < x0 + 12 && y >= y0 && y < y0 + 10));
                const krs::ray<float> r = camera.primary_ray(float(x) + 0.5f, float(y) + 0.5f);
                if (!(job.t_start <= job.t_max)) {
                    // Set aside as a miss (the prepass start passed t_max): its ray is not kept.
                    REQUIRE(!(pre.start_for(r) <= o.max_distance));
                    ++set_aside, ++checked;
                    continue;
                }
                REQUIRE((job.r.origin.x == r.origin.x && job.r.origin.y == r.origin.y && job.r.origin.z == r.origin.z));
                REQUIRE(job.r.direction.x == doctest::Approx(r.direction.x).epsilon(1e-6));
                REQUIRE(job.r.direction.y == doctest::Approx(r.direction.y).epsilon(1e-6));
                REQUIRE(job.r.direction.z == doctest::Approx(r.direction.z).epsilon(1e-6));
                REQUIRE(job.t_start == doctest::Approx(pre.start_for(r)).epsilon(1e-5));
                REQUIRE(job.t_max == o.max_distance);
                ++checked;
            }
            REQUIRE(rays.remaining() == 0);
        }
    for (int n : seen) REQUIRE(n == 1);
    CHECK(checked == width * height);
    CHECK(set_aside < checked / 2);
}

namespace {
// Traces a picture's tiles through trace_queue with lane type L (queue_tile_rays fills the queue
// a tile at a time) and checks every pixel against the scalar tracer on the same clipped range:
// reported once, the same hit/miss and step count (the packet math rounds as the scalar's with
// -ffp-contract=off; a contracting build may end a grazing ray a step apart), rays that miss the
// box reported as misses without an evaluation.
template <class L, int Interleave>
void check_tile_queue(int tile_w, int tile_h, int refill_at, float omega, long long& in_box, long long& out_of_box)
{
    const scene s = grove(false);
    const int width = 45, height = 33;
    const krs::pinhole_camera camera({1.5f, 3.0f, -9.0f}, {1.5f, 0.3f, 1.5f}, {0, 1, 0}, 75.0f, width, height);
    krs::trace_options o = primary_options(camera);
    o.omega = omega;
    const krs::box_clip clip(krs::field_box(s), camera.eye(), o);
    krs::tile_prepass from_near;
    from_near.start = o.min_distance;
    std::vector<krs::hit<float>> got(std::size_t(width * height));
    std::vector<int> reported(got.size(), 0);
    int x0 = -tile_w, y0 = 0;
    krs::ray_queue<L> queue;
    auto more = [&](krs::ray_queue<L>& q) {
        REQUIRE(q.empty());
        if ((x0 += tile_w) >= width) x0 = 0, y0 += tile_h;
        if (y0 >= height) return false;
        krs::queue_tile_rays(q, camera, x0, y0, x0 + tile_w, y0 + tile_h, from_near, o.max_distance, clip);
        return true;
    };
    auto done = [&](std::uint32_t id, const krs::hit<float>& h) {
        REQUIRE(id < got.size());
        got[id] = h, ++reported[id];
    };
    const krs::stream_stats stats = krs::trace_queue<L, Interleave>(s, queue, more, done, o, refill_at);
    CHECK(stats.rays == width * height);
    long long evaluations = 0, steps = 0, differ = 0;
    for (int y = 0; y < height; ++y)
        for (int x = 0; x < width; ++x) {
            const std::size_t id = std::size_t(y * width + x);
            REQUIRE(reported[id] == 1);
            const krs::ray<float> r = camera.primary_ray(float(x) + 0.5f, float(y) + 0.5f);
            float t0 = o.min_distance, t1 = o.max_distance;
            clip.apply(r, t0, t1);
            const krs::hit<float> h = krs::sphere_trace(s, r, t0, t1, o);
            REQUIRE(!got[id].invalid);
            if (!(t0 <= t1)) {
                ++out_of_box;
                REQUIRE(!got[id].found);
                REQUIRE(got[id].evaluations == 0);
                continue;
            }
            ++in_box;
            evaluations += got[id].evaluations;
            steps += got[id].steps;
#if defined(KRS_TEST_FP_CONTRACT)
            differ += got[id].found != h.found || std::abs(got[id].steps - h.steps) > 1;
#else
            REQUIRE(got[id].found == h.found);
            REQUIRE(got[id].steps == h.steps);
            REQUIRE(got[id].evaluations == h.evaluations);
            if (h.found) REQUIRE(std::abs(got[id].t - h.t) <= o.threshold(h.t));
#endif
        }
    CHECK(differ <= width * height / 500);
    // The stream counts its lanes' steps per packet step (a popcount of the active lanes), not
    // per finished ray: the totals must still be the reported rays' sums.
    CHECK(stats.evaluations == evaluations);
    CHECK(stats.busy_lanes == steps);
}
} // namespace

TEST_CASE("trace_queue over queued tile rays: every pixel once, box misses set aside, lanes as the scalar tracer")
{
    // Tiles 8 x 8 (two rows per 16-lane packet), 7 x 5 (packets straddle rows, tiles end on
    // partial packets) and 16 x 16; whole-packet and per-lane refill; plain and relaxed steps;
    // packets and the scalar lane type (one template for both).
    long long in_box = 0, out_of_box = 0;
    for (const auto& [w, h] : {std::pair{8, 8}, std::pair{7, 5}, std::pair{16, 16}})
        for (int refill_at : {0, 1})
            for (float omega : {1.0f, 1.6f}) {
                check_tile_queue<P, 2>(w, h, refill_at, omega, in_box, out_of_box);
                check_tile_queue<P, 4>(w, h, refill_at, omega, in_box, out_of_box);
            }
    check_tile_queue<float, 1>(8, 8, 0, 1.6f, in_box, out_of_box);
    check_tile_queue<float, 3>(7, 5, 1, 1.0f, in_box, out_of_box);
    // The camera sees the box in the middle of the picture: both kinds of rays were exercised.
    CHECK(in_box > out_of_box / 4);
    CHECK(out_of_box > in_box / 4);
}

TEST_CASE("ray_queue: packets queued in lane order, unusable rays and empty ranges set aside by id")
{
    using ids = krs::index_lanes<P>;
    krs::ray_queue<P> q;
    std::mt19937_64 g(9);
    // Reference: the same rays queued one job at a time.
    krs::ray_queue<P> one;
    std::vector<std::int32_t> missed, invalid;
    std::uint32_t next_id = 100;
    for (int round = 0; round < 50; ++round) {
        alignas(64) float c[8][lanes];
        alignas(64) std::int32_t id[lanes];
        for (std::size_t i = 0; i < lanes; ++i) {
            for (int k = 0; k < 8; ++k) c[k][i] = float(uniform(g, -2, 2));
            id[i] = std::int32_t(next_id++);
            const int kind = int(g() % 6);
            if (kind == 0) c[6][i] = c[7][i] + 1.0f;                      // empty range: a miss
            if (kind == 1) c[0][i] = std::numeric_limits<float>::quiet_NaN(); // unusable
            if (kind == 2) c[3][i] = c[4][i] = c[5][i] = 0.0f;             // zero direction: unusable
        }
        const std::uint64_t lanes_used = g() | 1u; // some lanes left out
        const krs::ray<P> r{{P::load_aligned(c[0]), P::load_aligned(c[1]), P::load_aligned(c[2])},
                            {P::load_aligned(c[3]), P::load_aligned(c[4]), P::load_aligned(c[5])}};
        q.push(r, P::load_aligned(c[6]), P::load_aligned(c[7]), ids::load_aligned(id), lanes_used);
        for (std::size_t i = 0; i < lanes; ++i) {
            if (!((lanes_used >> i) & 1u)) continue;
            one.push(krs::ray_job{{{c[0][i], c[1][i], c[2][i]}, {c[3][i], c[4][i], c[5][i]}}, c[6][i], c[7][i], std::uint32_t(id[i])});
        }
    }
    REQUIRE(q.size() == one.size());
    REQUIRE(q.size() > 0);
    REQUIRE(q.missed() == one.missed());
    REQUIRE(q.invalid() == one.invalid());
    CHECK(!q.missed().empty());
    CHECK(!q.invalid().empty());
    for (std::size_t i = 0; i < q.size(); ++i) {
        const krs::ray_job a = q.job(i), b = one.job(i);
        REQUIRE(a.id == b.id);
        // All 8 floats: a compress that mixed up two arrays would show in any one of them.
        const float got[8] = {a.r.origin.x, a.r.origin.y, a.r.origin.z, a.r.direction.x, a.r.direction.y, a.r.direction.z, a.t_start, a.t_max};
        const float want[8] = {b.r.origin.x, b.r.origin.y, b.r.origin.z, b.r.direction.x, b.r.direction.y, b.r.direction.z, b.t_start, b.t_max};
        for (int c = 0; c < 8; ++c) REQUIRE_MESSAGE(got[c] == want[c], "ray " << i << ", value " << c);
        REQUIRE(a.t_start <= a.t_max);
    }
    // take moves the front rays into the chosen lanes, in lane order, and keeps the others.
    krs::ray<P> r{{P(7.0f), P(7.0f), P(7.0f)}, {P(7.0f), P(7.0f), P(7.0f)}};
    P t0(7.0f), t1(7.0f);
    ids id(7);
    const std::uint64_t chosen = 0b1011'0010u & ((std::uint64_t(1) << lanes) - 1);
    const std::size_t before = q.size();
    std::vector<krs::ray_job> front;
    for (std::size_t i = 0; i < std::size_t(std::popcount(chosen)); ++i) front.push_back(q.job(i));
    q.take(chosen, r, t0, t1, id);
    REQUIRE(q.size() == before - front.size());
    alignas(64) std::int32_t id_lanes[lanes];
    id.store_aligned(id_lanes);
    for (std::size_t i = 0, j = 0; i < lanes; ++i) {
        if ((chosen >> i) & 1u) {
            CHECK(krs::lane_at(t0, i) == front[j].t_start);
            CHECK(krs::lane_at(r.origin.y, i) == front[j].r.origin.y);
            CHECK(std::uint32_t(id_lanes[i]) == front[j].id);
            ++j;
        } else {
            CHECK(krs::lane_at(t0, i) == 7.0f);
            CHECK(id_lanes[i] == 7);
        }
    }
}

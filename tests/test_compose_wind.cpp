// Wind (krs/compose/wind.hpp): the warp's displacement against its closed form in double (the
// gust sines and the height profile written out here); 1-Lipschitz on close pairs at the gust
// peaks (found by sampling a(t) densely) and at other instants; never overestimating the distance
// to a swaying sphere whose surface is sampled through the motion; the still field bit for bit
// where the wind is zero; packets and doubles against the scalar path; refused parameters; and the
// cost in sphere-tracing steps of a swaying tree against the still one (printed). Its GLSL runs on
// llvmpipe in test_glsl_field_types.cpp.

#include "krs/compose/warp.hpp"
#include "krs/compose/wind.hpp"
#include "krs/kernels/sphere.hpp"
#include "krs/model/tree.hpp"
#include "krs/trace/camera.hpp"
#include "krs/trace/sphere_trace.hpp"

#include "support/packet_points.hpp"
#include "support/rejects.hpp"
#include "support/random.hpp"

#include <doctest/doctest.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <limits>
#include <numbers>
#include <random>
#include <vector>

namespace {

using krs::vec3d;
using krs::vec3f;
using krs_test::uniform;

// a(t) as the header describes it, in double from the wind's values as given.
double top_offset(const krs::wind& w, double t)
{
    const double o = 2.0 * std::numbers::pi / double(w.gust_period);
    const double g = std::sin(o * t) + std::sin(std::sqrt(2.0) * o * t + 1.3) / 2.0 + std::sin(std::sqrt(5.0) * o * t + 2.9) / 4.0;
    return double(w.sway) + double(w.gust) * g / 1.75;
}
// The unit horizontal wind direction, in double.
vec3d horizontal(const krs::wind& w)
{
    const vec3d h{double(w.direction.x), 0.0, double(w.direction.z)};
    return h / std::sqrt(h.x * h.x + h.z * h.z);
}
// The height profile w(y) in double.
double profile(const krs::wind& w, double y)
{
    const double s = std::clamp((y - double(w.ground)) / double(w.height), 0.0, 1.0);
    return s * s;
}
// Where the wind moves a still point at time t: s + a(t) w(s.y) d.
vec3d moved(const krs::wind& w, double t, const vec3d& s) { return s + horizontal(w) * (top_offset(w, t) * profile(w, s.y)); }

// Instants where |a(t)| has a local maximum (the gust peaks), found by sampling a(t) every
// millisecond over [0, span]; the `count` largest, largest first.
std::vector<float> gust_peaks(const krs::wind& w, double span, std::size_t count)
{
    std::vector<std::pair<double, float>> peaks;
    const double h = 1e-3;
    for (double t = h; t < span; t += h) {
        const double a = std::abs(top_offset(w, t));
        if (a > std::abs(top_offset(w, t - h)) && a >= std::abs(top_offset(w, t + h))) peaks.push_back({a, float(t)});
    }
    std::sort(peaks.begin(), peaks.end(), [](const auto& x, const auto& y) { return x.first > y.first; });
    std::vector<float> instants;
    for (std::size_t i = 0; i < std::min(count, peaks.size()); ++i) instants.push_back(peaks[i].second);
    return instants;
}
// The gust peaks and evenly spread instants: at least 20.
std::vector<float> instants_of(const krs::wind& w)
{
    std::vector<float> t = gust_peaks(w, 60.0, 8);
    for (int i = 0; i < 14; ++i) t.push_back(0.37f + 4.3f * float(i));
    return t;
}

// A tree (with its ground) and the height of its route's top: the highest fork, control point
// (a bent branch lies in its control triangle) or leaf, plus the widest tube.
struct grown_tree {
    krs::model::tree_sequence field;
    float top = 0;
};
grown_tree tree_of(int levels)
{
    krs::model::tree_style style;
    style.levels = levels;
    const krs::model::tree_parameters p = krs::model::grow_tree(style);
    float top = 0, width = 0;
    for (const vec3f& f : p.forks) top = std::max(top, f.y);
    for (const vec3f& c : p.controls) top = std::max(top, c.y);
    for (const float r : p.widths) width = std::max(width, r);
    for (const krs::sphere& leaf : p.leaves) top = std::max(top, leaf.bound().center.y + leaf.bound().radius);
    return {krs::model::build_tree(p), top + width};
}

} // namespace

TEST_CASE("the wind's displacement equals its closed form in double, and a(t) stays within its bound")
{
    krs::wind w;
    w.direction = {1.0f, 0.3f, 0.5f};
    w.ground = -0.5f;
    w.height = 3.0f;
    w.sway = 0.4f;
    w.gust = 0.6f;
    w.gust_period = 5.0f;
    std::mt19937_64 g(351);
    double worst = 0, worst_a = 0, largest_a = 0;
    for (const float t : instants_of(w)) {
        const krs::wind_warp warp = w.warp_at(t);
        worst_a = std::max(worst_a, std::abs(double(warp.offset) - top_offset(w, t)));
        largest_a = std::max(largest_a, std::abs(top_offset(w, t)));
        for (int i = 0; i < 2000; ++i) {
            const vec3f p{float(uniform(g, -3, 3)), float(uniform(g, -1.5, 3.5)), float(uniform(g, -3, 3))};
            const vec3d want = vec3d(p) - horizontal(w) * (top_offset(w, t) * profile(w, p.y));
            worst = std::max(worst, krs::length(vec3d(warp.apply(p)) - want));
            // At or below the ground nothing moves, bit for bit.
            if (p.y <= w.ground) CHECK((warp.apply(p).x == p.x && warp.apply(p).z == p.z));
        }
    }
    std::printf("wind displacement: max |W - W_closed_form| %.3g, max |a_float - a| %.3g, largest |a| at the peaks "
                "%.4f (bound |sway| + gust = %.4f)\n",
                worst, worst_a, largest_a, double(w.sway + w.gust));
    CHECK(worst <= 2e-6);
    CHECK(worst_a <= 1e-6);
    CHECK(largest_a <= double(w.sway) + double(w.gust));
    CHECK(largest_a >= 0.9 * (double(w.sway) + double(w.gust))); // the peaks were found
    // The bound over all times covers every instant's.
    for (double t = 0; t < 60; t += 0.01) CHECK(w.warp_at(float(t)).lipschitz() <= w.lipschitz_all_times());
}

TEST_CASE("a swaying tree is 1-Lipschitz at every instant, the gust peaks included")
{
    const grown_tree grown = tree_of(8);
    const auto& tree = grown.field;
    krs::wind w;
    w.direction = {1.0f, 0.0f, 0.3f};
    w.height = grown.top;
    w.sway = 1.5f;
    w.gust = 2.0f; // a storm: k = 2 * 3.5 / height, about 1
    const std::vector<float> instants = instants_of(w);
    REQUIRE(instants.size() >= 20);
    const krs::bounding_sphere b{{0, 0.5f * grown.top, 0}, 0.5f * grown.top};
    std::mt19937_64 g(352);
    double worst_slope = 0;
    float worst_at = 0;
    long pairs = 0;
    for (const float t : instants) {
        const krs::swaying<krs::model::tree_sequence> f(tree, w, t);
        double slope_here = 0;
        for (int i = 0; i < 10000; ++i) {
            // Half the points in the top fifth of the swaying band, where the shear is largest.
            const double y = i % 2 ? uniform(g, 0.8, 1.05) * double(w.height) : uniform(g, -0.2, 1.05) * double(w.height);
            const vec3d p{double(b.center.x) + uniform(g, -1, 1) * b.radius + double(f.warp().offset) * profile(w, y),
                          y, double(b.center.z) + uniform(g, -1, 1) * b.radius};
            const vec3f x(p), x2(p + krs_test::random_direction(g) * uniform(g, 1e-3, 5e-2));
            const double gap = krs::length(vec3d(x) - vec3d(x2));
            // Allowance for the float rounding of the two distances.
            const double slope = (std::abs(double(f.distance(x)) - double(f.distance(x2))) - 4e-7 * (1 + krs::length(p))) / gap;
            slope_here = std::max(slope_here, slope);
            ++pairs;
        }
        if (slope_here > worst_slope) worst_slope = slope_here, worst_at = t;
    }
    std::printf("swaying tree: %zu instants, %ld close pairs, worst slope %.6f at t = %.3f (L there %.4f, bound "
                "over all t %.4f)\n",
                instants.size(), pairs, worst_slope, double(worst_at), w.warp_at(worst_at).lipschitz(),
                w.lipschitz_all_times());
    CHECK(pairs >= 200000);
    CHECK(worst_slope <= 1.0 + 1e-4);
    CHECK(worst_slope >= 0.9); // the bound is not needlessly loose where the shear is largest
}

TEST_CASE("a swaying sphere never overestimates the distance to its moved surface, is zero on it, and in its bound")
{
    const krs::sphere ball({0.3f, 2.2f, -0.2f}, 0.9f);
    krs::wind w;
    w.direction = {1.0f, 0.0f, 1.0f};
    w.height = 2.5f; // the sphere reaches above the band: its top moves rigidly
    w.sway = 0.8f;
    w.gust = 1.0f;
    w.gust_period = 3.0f;
    std::vector<float> instants = gust_peaks(w, 30.0, 3);
    instants.push_back(1.1f);
    instants.push_back(7.9f);
    std::mt19937_64 g(353);
    for (const float t : instants) {
        const krs::swaying<krs::sphere> f(ball, w, t);
        const double a = top_offset(w, t);
        // The moved surface sampled densely: s + a w(s.y) d for s on the still sphere.
        std::vector<vec3d> surface(30000);
        for (vec3d& s : surface) s = moved(w, t, vec3d(ball.center) + krs_test::random_direction(g) * double(ball.radius));
        double on_surface = 0, worst_over = -INFINITY, tightest = 0;
        for (int i = 0; i < 400; ++i) on_surface = std::max(on_surface, std::abs(double(f.distance(vec3f(surface[std::size_t(i)])))));
        for (int i = 0; i < 1000; ++i) {
            const vec3d p = vec3d(ball.center) + horizontal(w) * (0.5 * a) +
                            vec3d{uniform(g, -2.5, 2.5), uniform(g, -2.5, 2.5), uniform(g, -2.5, 2.5)};
            double sampled = INFINITY;
            for (const vec3d& s : surface) sampled = std::min(sampled, krs::length(p - s));
            const double d = f.distance(vec3f(p));
            // The sampled distance is at least the true one: d <= true <= sampled.
            if (d > 0) worst_over = std::max(worst_over, d - sampled), tightest = std::max(tightest, d / sampled);
            // Inside: the point the motion undoes lies inside the still sphere.
            if (d < -1e-5) CHECK(krs::length(p - horizontal(w) * (a * profile(w, p.y)) - vec3d(ball.center)) < double(ball.radius));
            // and inside the bound (the still sphere's, grown by |a|).
            if (d < 0) CHECK(krs::length(p - vec3d(f.bound().center)) <= double(f.bound().radius));
        }
        std::printf("swaying sphere t = %6.3f: a %+.4f, L %.4f, |d| on surface %.3g, d - sampled <= %.3g, largest "
                    "d / sampled %.4f\n",
                    double(t), a, f.warp().lipschitz(), on_surface, worst_over, tightest);
        CAPTURE(t);
        CHECK(on_surface <= 1e-5);
        CHECK(worst_over <= 1e-5);
    }
}

TEST_CASE("where the wind is zero the swaying field is the still one, bit for bit")
{
    const grown_tree grown = tree_of(8);
    const auto& tree = grown.field;
    krs::wind calm; // no sway, no gusts
    calm.height = grown.top;
    calm.direction = {0.3f, 0.0f, -1.0f};
    std::mt19937_64 g(354);
    long compared = 0, equal = 0;
    for (int i = 0; i < 20; ++i) {
        const krs::swaying<krs::model::tree_sequence> f(tree, calm, 1.7f * float(i));
        CHECK(f.inverse_lipschitz() == 1.0f);
        for (int k = 0; k < 64; ++k) {
            const krs_test::packet_points points = krs_test::random_packet(g, {-3, -1, -3}, {3, 8, 3});
            const krs::packet_f d = f.distance(points.packet);
            for (std::size_t l = 0; l < points.lanes.size(); ++l) {
                const vec3f p = points.lanes[l];
                ++compared;
                equal += f.distance(p) == tree.distance(p) && krs::lane_at(d, l) == tree.distance(p) &&
                         f.distance(vec3d(p)) == tree.distance(vec3d(p));
            }
        }
    }
    CHECK(equal == compared);
    // The instant's warp with no offset is the identity, bit for bit, signed zeros included (x - 0 d
    // would turn -0 into +0 where d's component is negative).
    const krs::wind_warp idle = calm.warp_at(3.0f);
    for (const vec3f p : {vec3f{-0.0f, 1.0f, -0.0f}, vec3f{-0.0f, 5.0f, 0.0f}}) {
        const vec3f q = idle.apply(p);
        CHECK((std::signbit(q.x) == std::signbit(p.x) && q.y == p.y && std::signbit(q.z) == std::signbit(p.z)));
    }
    // In lipschitz_warp: the still field too.
    const krs::lipschitz_warp<krs::model::tree_sequence, krs::wind_warp> frozen(tree, idle);
    for (int k = 0; k < 1000; ++k) {
        const vec3f p{float(uniform(g, -3, 3)), float(uniform(g, -1, 8)), float(uniform(g, -3, 3))};
        CHECK(frozen.distance(p) == tree.distance(p));
    }
}

TEST_CASE("swaying fields in packets and in double equal the scalar float path")
{
    const grown_tree grown = tree_of(8);
    const auto& tree = grown.field;
    krs::wind w;
    w.direction = {-0.4f, 0.0f, 1.0f};
    w.height = grown.top;
    w.sway = 0.3f;
    w.gust = 0.5f;
    std::mt19937_64 g(355);
    krs_test::scalar_agreement agree;
    for (const float t : {0.0f, 2.5f, gust_peaks(w, 20.0, 1)[0]}) {
        const krs::swaying<krs::model::tree_sequence> f(tree, w, t);
        for (int k = 0; k < 128; ++k) agree.add(f, krs_test::random_packet(g, {-3, -1, -3}, {3, 8, 3}));
    }
    std::printf("swaying tree: packets equal to scalar %ld/%ld, max |d_double - d_float| %.3g\n", agree.equal,
                agree.lanes, agree.worst_double);
    CHECK(agree.equal == agree.lanes); // the same + - * per lane (-ffp-contract=off)
    CHECK(agree.worst_double <= 1e-5);
}

TEST_CASE("bad wind parameters are refused by name")
{
    const krs::sphere ball({0, 1, 0}, 0.5f);
    const float nan = std::numeric_limits<float>::quiet_NaN(), inf = std::numeric_limits<float>::infinity();
    const auto with = [&](auto change) {
        krs::wind w;
        w.sway = 0.2f;
        w.gust = 0.1f;
        change(w);
        return w;
    };
    const auto sway_with = [&](auto change, const char* name) {
        krs_test::rejects([&] { (void)krs::swaying<krs::sphere>(ball, with(change)); }, name);
    };
    for (const vec3f d : {vec3f{0, 0, 0}, vec3f{0, 1, 0}, vec3f{nan, 0, 1}, vec3f{1, inf, 0}})
        sway_with([&](krs::wind& w) { w.direction = d; }, "wind.direction");
    for (const float v : {nan, inf, 2e9f}) sway_with([&](krs::wind& w) { w.ground = v; }, "wind.ground");
    for (const float v : {0.0f, -1.0f, nan, inf}) sway_with([&](krs::wind& w) { w.height = v; }, "wind.height");
    for (const float v : {nan, -inf, 2e9f}) sway_with([&](krs::wind& w) { w.sway = v; }, "wind.sway");
    for (const float v : {-0.1f, nan, inf}) sway_with([&](krs::wind& w) { w.gust = v; }, "wind.gust");
    sway_with([&](krs::wind& w) { w.sway = 6e8f, w.gust = 6e8f, w.height = 1e6f; }, "wind.gust"); // the top beyond 1e9
    for (const float v : {0.0f, -2.0f, nan}) sway_with([&](krs::wind& w) { w.gust_period = v; }, "wind.gust_period");
    // A shear of more than a million heights.
    sway_with([&](krs::wind& w) { w.height = 1e-7f; }, "wind.height");
    krs_test::rejects([&] { (void)krs::swaying<krs::sphere>(ball, with([](krs::wind&) {}), nan); }, "swaying.time");
    const krs::swaying<krs::sphere> f(ball, with([](krs::wind&) {}));
    krs_test::rejects([&] { (void)f.at(inf); }, "swaying.time");
    krs_test::rejects([&] { (void)with([](krs::wind&) {}).warp_at(nan); }, "wind.time");
    krs_test::rejects([&] { (void)krs::wind_warp({0, 2, 0}, 0, 1, 0.5f); }, "wind_warp.direction");
    krs_test::rejects([&] { (void)krs::wind_warp({1, 0, 0}, nan, 1, 0.5f); }, "wind_warp.ground");
    krs_test::rejects([&] { (void)krs::wind_warp({1, 0, 0}, 0, 0, 0.5f); }, "wind_warp.height");
    krs_test::rejects([&] { (void)krs::wind_warp({1, 0, 0}, 0, 1, nan); }, "wind_warp.offset");
    krs_test::rejects([&] { (void)krs::wind_warp({1, 0, 0}, 0, 1e-6f, 2.0f); }, "wind_warp.offset");
}

// A field marched in quarter steps: the same surface, found with four times the margin.
template <class F>
struct quartered {
    const F& f;
    template <class T>
    T distance(const krs::vec3<T>& p) const
    {
        return f.distance(p) * T(0.25f);
    }
};

TEST_CASE("sphere tracing a swaying tree: steps against the still tree, and the surfaces of a quarter-step march")
{
    const grown_tree grown = tree_of(12);
    const auto& tree = grown.field;
    const float top = grown.top;
    krs::wind breeze, storm;
    breeze.direction = storm.direction = {1.0f, 0.0f, 0.2f};
    breeze.height = storm.height = top;
    breeze.sway = 0.4f;
    breeze.gust = 0.6f;
    storm.sway = 1.5f;
    storm.gust = 2.0f;
    const krs::pinhole_camera camera({0.0f, 0.55f * top, 2.2f * top}, {0.0f, 0.5f * top, 0.0f}, {0, 1, 0}, 50.0f, 128, 96);
    krs::trace_options o;
    o.pixel_footprint = camera.pixel_footprint();
    o.max_distance = 10.0f * top;
    // The comparison with the quarter-step march: a fixed small threshold (the pixel cone's grows
    // with t, and a march of quarter steps stops four cones early: metres before a grazed ground).
    krs::trace_options tight = o;
    tight.pixel_footprint = 0.0f;
    tight.threshold_floor = 1e-4f;
    tight.max_steps = 4096;
    krs::trace_options quarter = tight; // stops where the field is below the same 1e-4
    quarter.threshold_floor = 0.25f * tight.threshold_floor;
    const auto trace = [&](const auto& f, std::vector<float>& depth, const krs::trace_options& o) {
        long steps = 0;
        depth.clear();
        for (int py = 0; py < camera.height(); ++py)
            for (int px = 0; px < camera.width(); ++px) {
                const krs::hit<float> h = krs::sphere_trace(f, camera.primary_ray(float(px) + 0.5f, float(py) + 0.5f), o);
                steps += h.steps;
                depth.push_back(h.found ? h.t : INFINITY);
            }
        return double(steps) / double(depth.size());
    };
    std::vector<float> still_depth, depth, safe_depth;
    // Hits of the pixel-cone march of the still tree (in view below: at least half as many).
    const double still = trace(tree, still_depth, o);
    const long still_hits = std::count_if(still_depth.begin(), still_depth.end(), [](float t) { return t < INFINITY; });
    std::printf("tree of height %.2f, %dx%d rays: still %.2f steps per ray (%ld hits)\n", double(top), camera.width(),
                camera.height(), still, still_hits);
    for (const auto& [w, t] : {std::pair{breeze, gust_peaks(breeze, 60.0, 1)[0]}, std::pair{breeze, 11.0f},
                               std::pair{storm, gust_peaks(storm, 60.0, 1)[0]}}) {
        const krs::swaying<krs::model::tree_sequence> f(tree, w, t);
        const double steps = trace(f, depth, o);
        (void)trace(f, depth, tight);
        (void)trace(quartered<decltype(f)>{f}, safe_depth, quarter);
        // A march that skipped a surface (a field that overestimated) ends behind it or misses;
        // the quarter-step march, four times as safe, finds it. Rays that graze a silhouette may
        // end within one march's threshold and not the other's: a few may differ.
        long differ = 0, hits = 0;
        for (std::size_t i = 0; i < depth.size(); ++i) {
            hits += depth[i] < INFINITY;
            const bool both_miss = depth[i] == INFINITY && safe_depth[i] == INFINITY;
            differ += !both_miss && !(std::abs(depth[i] - safe_depth[i]) <= 0.01f * top);
        }
        std::printf("  %s at t = %6.3f (a %+.3f, L %.4f): %.2f steps per ray (%.3f x still), %ld hits, %ld rays "
                    "differ from the quarter-step march\n",
                    w.sway == storm.sway ? "storm " : "breeze", double(t), double(f.warp().offset), f.warp().lipschitz(),
                    steps, steps / still, hits, differ);
        CAPTURE(t);
        CHECK(differ <= long(depth.size()) / 1000);
        CHECK(hits > still_hits / 2); // the tree is still in view
    }
}

// Composition: unions and the union tracer, Lipschitz warps, bounds and empty zones, collision
// queries; each against brute force or a closed form.

#include "krs/collision.hpp"
#include "krs/compose.hpp"
#include "krs/expansion.hpp"
#include "krs/kernels/box.hpp"
#include "krs/kernels/sphere.hpp"
#include "krs/kernels/torus_capsule.hpp"
#include "krs/model/forest_ground.hpp"
#include "krs/model/terrain.hpp"
#include "krs/model/tree.hpp"

#include "support/parity.hpp"
#include "support/random.hpp"

#include <doctest/doctest.h>

#include <array>
#include <cmath>
#include <limits>
#include <random>
#include <vector>

namespace {

using krs::vec3d;
using krs::vec3f;

using krs_test::random_direction;
using krs_test::uniform;

using blobs = krs::sequence<krs::sphere, krs::torus_capsule>;
// A small KRS "bush" shifted to `at`.
blobs bush(const vec3f& at, float turn)
{
    blobs::builder b;
    b.kernel(krs::sphere(at + vec3f{0.3f, 0.9f, 0.1f}, 0.18f));
    b.kernel(krs::torus_capsule(at, at + vec3f{0.3f, 0.8f, 0.1f}, at + vec3f{0.05f, 0.4f, 0.1f}, 0.05f));
    b.mirror(krs::mirror::through(at, {std::cos(turn), 0, std::sin(turn)}));
    b.mirror(krs::mirror::through(at, {-std::sin(turn), 0.1f, std::cos(turn)}));
    return b.build();
}

// A KRS whose kernels lie on the negative side of every mirror (separated: its distance is exact,
// so the brute-force expansion is its reference).
blobs separated_bush()
{
    blobs::builder b;
    b.kernel(krs::sphere({-1.0f, 0.9f, -1.2f}, 0.3f));
    b.kernel(krs::torus_capsule({-0.8f, 0, -0.9f}, {-1.0f, 0.8f, -1.2f}, {-0.7f, 0.4f, -1.0f}, 0.06f));
    b.mirror(krs::mirror({1, 0, 0.1f}, 0.0f));
    b.mirror(krs::mirror({0.1f, 0, 1}, 0.0f));
    b.mirror(krs::mirror({1, 0.1f, 0.2f}, 2.0f));
    return b.build();
}

// The min of the three, written out (the reference for union_of).
struct three_bushes_by_hand {
    blobs a, b, c;
    template <class T>
    T distance(const krs::vec3<T>& p) const
    {
        return krs::min(krs::min(a.distance(p), b.distance(p)), c.distance(p));
    }
};

// A warp that claims a bound below 1 (rejected).
struct shrinking_warp {
    template <class T>
    krs::vec3<T> apply(const krs::vec3<T>& p) const
    {
        return p * T(0.5f);
    }
    double lipschitz() const { return 0.5; }
    krs::bounding_sphere domain() const { return krs::bounding_sphere::unbounded(); }
};

// Points on the zero set of g(x) = f(W(x)) in the ball B: bisection between sampled inside and
// outside points (the surface is then known exactly, without trusting the warped distance).
template <class F, class W>
std::vector<vec3d> warped_surface_points(const F& f, const W& w, double radius, std::mt19937_64& g, int count)
{
    std::vector<vec3d> points;
    auto value = [&](const vec3d& x) { return f.distance(w.apply(x)); };
    while (int(points.size()) < count) {
        const vec3d a = random_direction(g) * (radius * std::cbrt(uniform(g, 0, 1)));
        const vec3d b = a + random_direction(g) * uniform(g, 0.05, 0.5);
        if (krs::length(b) > radius) continue;
        double fa = value(a), fb = value(b);
        if ((fa <= 0) == (fb <= 0)) continue;
        vec3d lo = a, hi = b;
        if (fa > 0) std::swap(lo, hi); // lo inside
        for (int i = 0; i < 50; ++i) {
            const vec3d mid = (lo + hi) * 0.5;
            (value(mid) <= 0 ? lo : hi) = mid;
        }
        points.push_back((lo + hi) * 0.5);
    }
    return points;
}

template <class F, class W>
void check_warp(const F& f, const W& w, double radius)
{
    const krs::lipschitz_warp<F, W> g(f, w);
    std::mt19937_64 rng(17);
    // 1-Lipschitz on sampled pairs (inside, across and outside the domain).
    for (int k = 0; k < 20000; ++k) {
        const vec3d a = random_direction(rng) * uniform(rng, 0, 1.6 * radius);
        const vec3d b = a + random_direction(rng) * uniform(rng, 1e-3, 0.5);
        REQUIRE(std::abs(g.distance(a) - g.distance(b)) <= krs::length(a - b) * (1 + 1e-6) + 1e-9);
    }
    // Never overestimates the distance to the warped surface (found by bisection).
    const std::vector<vec3d> surface = warped_surface_points(f, w, radius, rng, 1500);
    double undivided_worst = 0;
    for (int k = 0; k < 1500; ++k) {
        const vec3d x = random_direction(rng) * uniform(rng, 0, 1.5 * radius);
        double nearest = INFINITY;
        for (const vec3d& s : surface) nearest = std::min(nearest, krs::length(x - s));
        REQUIRE(g.distance(x) <= nearest + 1e-9);
        if (krs::length(x) < radius) undivided_worst = std::max(undivided_worst, f.distance(w.apply(x)) - nearest);
    }
    // Without the division the warped distance does overestimate: the bound is needed.
    CHECK(undivided_worst > 0.0);
}

// A forest on its folded terrain and a rock-like sphere among the trees, as one union: three
// components of different kinds whose silhouettes overlap (the union tracer tests below).
struct union_rays_scene {
    krs::model::forest forest;
    krs::model::plane_sequence ground;
    krs::sphere boulder;
    krs::union_of<krs::model::tree_sequence, krs::model::plane_sequence, krs::sphere> u;
    krs::trace_options o;
};
union_rays_scene union_scene()
{
    krs::model::forest_parameters fp;
    fp.tree.levels = 6;
    fp.tree.leaves_per_twig = 2;
    fp.tree.leaf_radius = 0.1f;
    fp.doublings = 3;
    fp.ground_height.reset();
    krs::model::forest forest = krs::model::build_forest(fp);
    krs::model::terrain_parameters tp;
    tp.levels = 8;
    tp.size = 4.0f;
    tp.slope = 0.3f;
    krs::model::plane_sequence ground = krs::model::build_forest_ground(fp, forest, tp);
    const krs::sphere boulder({forest.bound.center.x, 0.3f, forest.bound.center.z - 0.5f * forest.bound.radius}, 0.8f);
    krs::trace_options o;
    o.pixel_footprint = 2e-4f;
    o.threshold_floor = 1e-5f;
    o.max_steps = 4000;
    o.max_distance = 6 * forest.bound.radius;
    krs::union_of<krs::model::tree_sequence, krs::model::plane_sequence, krs::sphere> u(forest.sequence, ground, boulder);
    return {std::move(forest), std::move(ground), boulder, std::move(u), o};
}
} // namespace

TEST_CASE("union_of equals the min of its components")
{
    const krs::union_of<blobs, blobs, krs::sphere> u(bush({0, 0, 0}, 0.3f), bush({2, 0, 1}, 1.1f),
                                                      krs::sphere({-1, 0.5f, 2}, 0.4f));
    std::mt19937_64 g(1);
    for (int k = 0; k < 5000; ++k) {
        const vec3d p{uniform(g, -3, 4), uniform(g, -1, 2), uniform(g, -2, 4)};
        const double expected = std::min(std::min(u.component<0>().distance(p), u.component<1>().distance(p)),
                                         u.component<2>().distance(p));
        REQUIRE(u.distance(p) == expected);
        REQUIRE(u.component_distance(2, p) == u.component<2>().distance(p));
        const vec3f pf(p);
        REQUIRE(u.distance(pf) == std::min(std::min(u.component<0>().distance(pf), u.component<1>().distance(pf)),
                                           u.component<2>().distance(pf)));
    }
}

TEST_CASE("the union tracer finds the hits of the min field with fewer evaluations")
{
    const vec3f at[3] = {{0, 0, 0}, {6, 0, 1}, {-5, 0, 3}};
    const blobs a = bush(at[0], 0.3f), b = bush(at[1], 1.1f), c = bush(at[2], 2.0f);
    const krs::union_of<blobs, blobs, blobs> u(a, b, c);
    const three_bushes_by_hand reference{a, b, c};
    krs::trace_options o;
    o.pixel_footprint = 1e-4f;
    o.max_distance = 40.0f;
    std::mt19937_64 g(21);
    long long union_evaluations = 0, plain_component_evaluations = 0;
    int hits = 0, nearest_ok = 0;
    for (int k = 0; k < 1000; ++k) {
        const vec3d origin{uniform(g, -8, 8), uniform(g, 0, 3), uniform(g, -12, -8)};
        const vec3d target = vec3d(at[k % 3]) + vec3d{uniform(g, -0.7, 0.7), uniform(g, 0, 1.1), uniform(g, -0.7, 0.7)};
        const krs::ray<double> r{origin, krs::normalize(target - origin)};
        const krs::hit<double> plain = krs::sphere_trace(reference, r, o);
        const auto h = krs::union_trace(u, r, o);
        REQUIRE(bool(h.found) == bool(plain.found));
        if (plain.found) {
            ++hits;
            REQUIRE(h.t == doctest::Approx(plain.t).epsilon(1e-9));
            const double d[3] = {a.distance(krs::point_at(r, h.t)), b.distance(krs::point_at(r, h.t)),
                                 c.distance(krs::point_at(r, h.t))};
            nearest_ok += d[h.nearest] <= std::min(d[0], std::min(d[1], d[2]));
        }
        union_evaluations += h.evaluations;
        plain_component_evaluations += 3LL * plain.steps;
    }
    CHECK(hits > 40);
    CHECK(nearest_ok == hits);
    CHECK(union_evaluations < plain_component_evaluations * 3 / 4);
    MESSAGE("union tracer: " << union_evaluations << " component evaluations vs " << plain_component_evaluations
                             << " for plain tracing");
}

TEST_CASE("the union tracer finds the nearest of the components' own first hits")
{
    // A forest on its folded terrain, and a rock-like sphere among the trees: three components of
    // different kinds whose silhouettes overlap. Reference: each component traced alone by
    // plain sphere tracing, the nearest first hit taken.
    const union_rays_scene scene = union_scene();
    const krs::model::forest& forest = scene.forest;
    const krs::sphere& boulder = scene.boulder;
    const auto& u = scene.u;
    const krs::trace_options& o = scene.o;
    std::mt19937_64 g(33);
    const vec3d c(forest.bound.center);
    const double radius = forest.bound.radius;
    int found = 0, grazing = 0, by_component[3] = {0, 0, 0};
    for (int k = 0; k < 10000; ++k) {
        const vec3d origin = c + vec3d{uniform(g, -1, 1) * radius, uniform(g, 0.2, 1.2) * radius, -1.6 * radius};
        // Aim at a tree, the ground, or the boulder in turn.
        vec3d target = c + vec3d{uniform(g, -1, 1) * radius, uniform(g, -0.3, 0.2) * radius, uniform(g, -1, 1) * radius};
        if (k % 3 == 0) {
            const krs::bounding_sphere& tree = forest.trees[std::size_t(g() % forest.trees.size())];
            target = vec3d(tree.center) + random_direction(g) * (0.5 * tree.radius);
        } else if (k % 3 == 2) {
            target = vec3d(boulder.center) + random_direction(g) * double(boulder.radius);
        }
        const krs::ray<double> r{origin, krs::normalize(target - origin)};
        const krs::hit<double> alone[3] = {krs::sphere_trace(u.component<0>(), r, o),
                                           krs::sphere_trace(u.component<1>(), r, o),
                                           krs::sphere_trace(u.component<2>(), r, o)};
        int nearest = -1;
        for (int i = 0; i < 3; ++i)
            if (alone[i].found && (nearest < 0 || alone[i].t < alone[nearest].t)) nearest = i;
        const auto h = krs::union_trace(u, r, o);
        // A component traced alone never finds a hit the union tracer misses.
        if (nearest >= 0) REQUIRE(h.found);
        if (!h.found) continue;
        ++found;
        CAPTURE(k);
        if (nearest >= 0 && std::abs(h.t - alone[nearest].t) <= o.threshold(alone[nearest].t)) {
            ++by_component[nearest];
            // The component hit is the nearest one, unless two components' surfaces are within one
            // threshold of each other there (then either is a correct answer).
            if (h.nearest != nearest) REQUIRE(std::abs(alone[h.nearest].t - alone[nearest].t) <= o.threshold(h.t));
            continue;
        }
        // Otherwise the ray grazes a surface: sphere tracing stops wherever a sample falls within
        // the threshold, and the union's denser samples (steps of the minimum over components) may
        // land in a near-miss band that the component's own longer steps jumped over. Such a hit
        // must come first, be a genuine threshold hit of the component named, and be rare.
        ++grazing;
        REQUIRE(h.t < (nearest >= 0 ? alone[nearest].t : INFINITY));
        REQUIRE(u.component_distance(std::size_t(h.nearest), krs::point_at(r, h.t)) < o.threshold(h.t));
    }
    MESSAGE("grazing hits: " << grazing);
    CHECK(grazing <= found / 200);
    MESSAGE("union tracer vs components: " << found << " hits (trees " << by_component[0] << ", ground "
                                           << by_component[1] << ", boulder " << by_component[2] << ")");
    CHECK(by_component[0] > 500);
    CHECK(by_component[1] > 1000);
    CHECK(by_component[2] > 100);
}

namespace {

// The union tracer as it was before it ran on march_state / march_advance (issue 23): its own
// loop over one scalar ray. The tracer now shares the tracers' step and runs packets too; this is
// the reference that shows it still takes the same samples, stops at the same one and evaluates
// the same components.
struct previous_union_hit {
    double t = INFINITY;
    bool found = false, invalid = false;
    int steps = 0, evaluations = 0, nearest = -1;
    std::vector<int> component_evaluations;
};
template <class S, class U>
previous_union_hit previous_union_trace(const U& u, const krs::ray<S>& r, const krs::trace_options& options)
{
    constexpr std::size_t N = U::size;
    previous_union_hit h;
    h.component_evaluations.assign(N, 0);
    if (!(krs::is_finite(r.origin) && krs::is_finite(r.direction) && krs::length_squared(r.direction) > S(0))) {
        h.invalid = true;
        return h;
    }
    std::array<S, N> value{}, at{};
    std::array<bool, N> known{};
    constexpr S slack = S(64) * std::numeric_limits<S>::epsilon();
    S t = S(options.min_distance);
    const S t_max = S(options.max_distance);
    for (int step = 0; step < options.max_steps; ++step) {
        const krs::vec3<S> p = krs::point_at(r, t);
        S best = std::numeric_limits<S>::infinity();
        std::size_t best_index = 0;
        std::array<bool, N> fresh{};
        for (;;) {
            std::size_t candidate = N;
            S candidate_bound = best;
            for (std::size_t i = 0; i < N; ++i) {
                if (fresh[i]) continue;
                const S bound = known[i] ? value[i] - (t - at[i]) - slack * (std::abs(t) + std::abs(value[i]) + S(1))
                                         : -std::numeric_limits<S>::infinity();
                if (bound < candidate_bound) candidate_bound = bound, candidate = i;
            }
            if (candidate == N) break;
            const S d = u.component_distance(candidate, p);
            ++h.evaluations;
            ++h.component_evaluations[candidate];
            fresh[candidate] = known[candidate] = true;
            value[candidate] = d;
            at[candidate] = t;
            if (!(d == d)) {
                best = d;
                break;
            }
            if (d < best) best = d, best_index = candidate;
        }
        ++h.steps;
        if (!(best == best)) return h;
        if (best < options.threshold(t)) {
            h.found = true;
            h.t = double(t);
            h.nearest = int(best_index);
            return h;
        }
        t += best;
        if (!(t <= t_max)) return h;
    }
    return h;
}

// Every field of a union hit against the previous tracer's, exactly.
template <class H>
void require_same_union_hit(const H& h, const previous_union_hit& old)
{
    REQUIRE(bool(h.found) == old.found);
    REQUIRE(bool(h.invalid) == old.invalid);
    REQUIRE(double(h.t) == old.t);
    REQUIRE(int(h.steps) == old.steps);
    REQUIRE(int(h.evaluations) == old.evaluations);
    REQUIRE(int(h.nearest) == old.nearest);
    for (std::size_t i = 0; i < old.component_evaluations.size(); ++i)
        REQUIRE(int(h.component_evaluations[i]) == old.component_evaluations[i]);
}

krs::ray<double> union_scene_ray(const union_rays_scene& s, std::mt19937_64& g, int k)
{
    const vec3d c(s.forest.bound.center);
    const double radius = s.forest.bound.radius;
    const vec3d origin = c + vec3d{uniform(g, -1, 1) * radius, uniform(g, 0.2, 1.2) * radius, -1.6 * radius};
    vec3d target = c + vec3d{uniform(g, -1, 1) * radius, uniform(g, -0.3, 0.2) * radius, uniform(g, -1, 1) * radius};
    if (k % 3 == 0) {
        const krs::bounding_sphere& tree = s.forest.trees[std::size_t(g() % s.forest.trees.size())];
        target = vec3d(tree.center) + random_direction(g) * (0.5 * tree.radius);
    } else if (k % 3 == 2) {
        target = vec3d(s.boulder.center) + random_direction(g) * double(s.boulder.radius);
    }
    if (k % 5 == 4) target = origin + vec3d{uniform(g, -1, 1), 1, uniform(g, -1, 1)} * radius; // up: a miss
    return {origin, krs::normalize(target - origin)};
}

} // namespace

TEST_CASE("the union tracer on the shared march step takes the previous tracer's samples, for float and double")
{
    const union_rays_scene s = union_scene();
    std::mt19937_64 g(34);
    int hits = 0, skipped = 0;
    for (int k = 0; k < 1500; ++k) {
        const krs::ray<double> rd = union_scene_ray(s, g, k);
        CAPTURE(k);
        const auto hd = krs::union_trace(s.u, rd, s.o);
        require_same_union_hit(hd, previous_union_trace(s.u, rd, s.o));
        const krs::ray<float> rf{vec3f(rd.origin), vec3f(rd.direction)};
        const auto hf = krs::union_trace(s.u, rf, s.o);
        require_same_union_hit(hf, previous_union_trace(s.u, rf, s.o));
        hits += hf.found;
        skipped += hf.evaluations < 3 * hf.steps;
        // And where the step budget ends the march.
        krs::trace_options short_march = s.o;
        short_march.max_steps = 1 + k % 16;
        require_same_union_hit(krs::union_trace(s.u, rf, short_march), previous_union_trace(s.u, rf, short_march));
    }
    // Both outcomes, and the free distances at work, are covered.
    CHECK(hits > 300);
    CHECK(hits < 1400);
    CHECK(skipped > 1000);
    // Rays that cannot be marched, and a NaN from a component, end as the previous tracer's did.
    const krs::ray<float> bad{{0, 0, 0}, {0, 0, 0}};
    require_same_union_hit(krs::union_trace(s.u, bad, s.o), previous_union_trace(s.u, bad, s.o));
    const krs::ray<float> nan_ray{{std::numeric_limits<float>::quiet_NaN(), 0, 0}, {0, 0, 1}};
    require_same_union_hit(krs::union_trace(s.u, nan_ray, s.o), previous_union_trace(s.u, nan_ray, s.o));
}

TEST_CASE("the union tracer in packets equals the scalar union tracer lane by lane")
{
    using P = krs::packet_f;
    constexpr std::size_t W = krs::lane_count<P>;
    const union_rays_scene s = union_scene();
    std::mt19937_64 g(35);
    int hits = 0, by_component[3] = {0, 0, 0};
    // Under FMA contraction (krs_parity_contract_native, tests/support/parity.hpp) the two paths
    // round each distance differently, within the contraction tolerance, and t sums the steps'
    // differences; a march passing within the threshold of a surface may even stop on one side
    // and go on on the other. There t is compared through krs_test::parity (its tolerance of the
    // scene's extent, the far limit), and lanes that differ beyond it or in anything else (hit,
    // nearest component, counts) are counted: at most 0.1%. Otherwise every lane equals the
    // scalar trace bit for bit.
    krs_test::parity same_t{"union trace t, packet against scalar", double(s.o.max_distance)};
    long lanes = 0, off = 0;
    const int packets = 1920 / int(W); // 1920 rays whatever the width
    for (int k = 0; k < packets; ++k) {
        alignas(64) float ox[W], oy[W], oz[W], dx[W], dy[W], dz[W];
        krs::ray<float> rays[W];
        for (std::size_t i = 0; i < W; ++i) {
            const krs::ray<double> rd = union_scene_ray(s, g, int(k * W + i));
            rays[i] = {vec3f(rd.origin), vec3f(rd.direction)};
            ox[i] = rays[i].origin.x, oy[i] = rays[i].origin.y, oz[i] = rays[i].origin.z;
            dx[i] = rays[i].direction.x, dy[i] = rays[i].direction.y, dz[i] = rays[i].direction.z;
        }
        if (k == 7) dx[3] = dy[3] = dz[3] = 0.0f, rays[3].direction = {0, 0, 0}; // one unusable lane
        const krs::ray<P> r{{P::load_aligned(ox), P::load_aligned(oy), P::load_aligned(oz)},
                            {P::load_aligned(dx), P::load_aligned(dy), P::load_aligned(dz)}};
        const auto h = krs::union_trace(s.u, r, s.o);
        for (std::size_t i = 0; i < W; ++i) {
            CAPTURE(k);
            CAPTURE(i);
            const auto one = krs::union_trace(s.u, rays[i], s.o);
            ++lanes;
            const bool same_t_here = same_t.agree(krs::lane_at(h.t, i), one.t);
            if (krs_test::contraction) {
                bool same = same_t_here && krs::mask_lane<P>(h.found, i) == bool(one.found) &&
                            krs::mask_lane<P>(h.invalid, i) == bool(one.invalid) &&
                            krs::lane_at(h.steps, i) == float(one.steps) &&
                            krs::lane_at(h.evaluations, i) == float(one.evaluations) &&
                            krs::lane_at(h.nearest, i) == float(one.nearest);
                for (std::size_t c = 0; c < 3; ++c)
                    same = same && krs::lane_at(h.component_evaluations[c], i) == float(one.component_evaluations[c]);
                off += !same;
            } else {
                REQUIRE(krs::mask_lane<P>(h.found, i) == bool(one.found));
                REQUIRE(krs::mask_lane<P>(h.invalid, i) == bool(one.invalid));
                REQUIRE(same_t_here);
                REQUIRE(krs::lane_at(h.steps, i) == float(one.steps));
                REQUIRE(krs::lane_at(h.evaluations, i) == float(one.evaluations));
                REQUIRE(krs::lane_at(h.nearest, i) == float(one.nearest));
                for (std::size_t c = 0; c < 3; ++c)
                    REQUIRE(krs::lane_at(h.component_evaluations[c], i) == float(one.component_evaluations[c]));
            }
            hits += one.found;
            if (one.found) ++by_component[one.nearest];
        }
    }
    same_t.report();
    if (krs_test::contraction) MESSAGE(off << " of " << lanes << " lanes differ beyond the tolerance or in a count");
    CHECK(off <= lanes / 1000);
    CHECK(hits > 480);
    CHECK(hits < 1760);
    CHECK(by_component[0] > 50);
    CHECK(by_component[1] > 50);
    CHECK(by_component[2] > 20);
}

TEST_CASE("lipschitz_warp stays 1-Lipschitz and never overestimates")
{
    const krs::box slab({0, 0, 0}, {0.9f, 0.25f, 0.4f});
    SUBCASE("twist") { check_warp(slab, krs::twist_warp(2.0f, 1.2f), 1.2); }
    SUBCASE("bend") { check_warp(slab, krs::bend_warp(1.2f, 1.2f), 1.2); }
    SUBCASE("noise") { check_warp(krs::sphere({0, 0, 0}, 0.6f), krs::noise_warp(0.25f, 3.0f), 1.0); }
    CHECK_THROWS_WITH_AS(krs::lipschitz_warp(slab, shrinking_warp{}), doctest::Contains("lipschitz_warp.lipschitz"),
                         krs::invalid_parameter);
    CHECK_THROWS_WITH_AS(krs::twist_warp(1.0f, 0.0f), doctest::Contains("twist_warp.radius"), krs::invalid_parameter);
    CHECK_THROWS_WITH_AS(krs::noise_warp(-1.0f, 1.0f), doctest::Contains("noise_warp.amplitude"), krs::invalid_parameter);
    // Beyond the magnitude policy: an amplitude of 3e19 made the field inf, a frequency of 1e38
    // NaN (p f overflows), a radius of 1e30 passed unchecked, and a twist of rate 1e38 over 1e9
    // had 1/L round to 0 (a field of 0, all surface).
    CHECK_THROWS_WITH_AS(krs::noise_warp(3e19f, 1.0f), doctest::Contains("noise_warp.amplitude"), krs::invalid_parameter);
    CHECK_THROWS_WITH_AS(krs::noise_warp(1.0f, 1e38f), doctest::Contains("noise_warp.frequency"), krs::invalid_parameter);
    CHECK_THROWS_WITH_AS(krs::twist_warp(1.0f, 1e30f), doctest::Contains("twist_warp.radius"), krs::invalid_parameter);
    CHECK_THROWS_WITH_AS(krs::bend_warp(1.0f, 1e30f), doctest::Contains("bend_warp.radius"), krs::invalid_parameter);
    CHECK_THROWS_WITH_AS(krs::lipschitz_warp(slab, krs::twist_warp(1e38f, 1e9f)), doctest::Contains("lipschitz_warp.lipschitz"),
                         krs::invalid_parameter);
    // The largest accepted values give finite fields.
    const krs::lipschitz_warp wide(krs::sphere({0, 0, 0}, 1.0f), krs::noise_warp(1e9f, 1e9f));
    const krs::lipschitz_warp steep(krs::sphere({0, 0, 0}, 1.0f), krs::twist_warp(1e20f, 1e9f));
    for (const vec3f& p : {vec3f{0, 0, 0}, vec3f{5, -3, 2}, vec3f{1e9f, 0, 0}, vec3f{0, 1e9f, 1e9f}}) {
        CHECK(std::isfinite(wide.distance(p)));
        CHECK(std::isfinite(steep.distance(p)));
    }
}

TEST_CASE("bounded never overestimates and skips the field far away")
{
    const blobs a = separated_bush();
    const auto e = krs::expand(a);
    const krs::bounded<blobs> bounded_a(a, 0.5f);
    std::mt19937_64 g(8);
    for (int k = 0; k < 4000; ++k) {
        const vec3d p = vec3d(a.bound().center) + random_direction(g) * uniform(g, 0, 6 * a.bound().radius);
        const double exact = e.distance(p);
        REQUIRE(bounded_a.distance(p) <= exact + 1e-6);
        // Where the field is evaluated the result is at least as tight as the field itself.
        if (krs::length(p - vec3d(a.bound().center)) < a.bound().radius) REQUIRE(bounded_a.distance(p) >= a.distance(p));
    }
    CHECK_THROWS_WITH_AS(krs::bounded<krs::model::plane_sequence>(krs::model::build_terrain({}), 1.0f),
                         doctest::Contains("bounded.bound"), krs::invalid_parameter);
    CHECK_THROWS_WITH_AS(krs::bounded<blobs>(a, -1.0f), doctest::Contains("bounded.margin"), krs::invalid_parameter);
    // Tracing the bounded field: same hits, fewer steps for rays starting far away.
    krs::trace_options o;
    o.pixel_footprint = 1e-4f;
    int hits = 0;
    for (int k = 0; k < 500; ++k) {
        const vec3d origin = random_direction(g) * 30.0;
        const vec3d target = vec3d(a.bound().center) + random_direction(g) * uniform(g, 0, a.bound().radius);
        const krs::ray<double> r{origin, krs::normalize(target - origin)};
        const krs::hit<double> plain = krs::sphere_trace(a, r, o), fast = krs::sphere_trace(bounded_a, r, o);
        REQUIRE(bool(plain.found) == bool(fast.found));
        if (plain.found) REQUIRE(std::abs(plain.t - fast.t) <= o.threshold(plain.t) * 2);
        hits += plain.found;
    }
    CHECK(hits > 50);
}

TEST_CASE("empty zones remove geometry conservatively and rays cross them")
{
    // Three spheres on a line; the middle one lies inside the zone.
    krs::sequence<krs::sphere>::builder b;
    b.kernel(krs::sphere({-2, 0, 0}, 0.5f));
    b.kernel(krs::sphere({0, 0, 0}, 0.5f));
    b.kernel(krs::sphere({2, 0, 0}, 0.5f));
    const auto s = b.build();
    const krs::with_empty_zones<decltype(s)> z(s, {krs::bounding_sphere{{0, 0, 0}, 1.0f}});
    std::mt19937_64 g(12);
    for (int k = 0; k < 5000; ++k) {
        const vec3d p{uniform(g, -4, 4), uniform(g, -2, 2), uniform(g, -2, 2)};
        // Exact distance to what remains: the two outer spheres.
        const double exact = std::min(krs::length(p - vec3d{-2, 0, 0}), krs::length(p - vec3d{2, 0, 0})) - 0.5;
        REQUIRE(z.distance(p) <= exact + 1e-9);
    }
    // A ray straight through the zone misses the removed sphere and hits the one behind it.
    krs::trace_options o;
    o.pixel_footprint = 0;
    o.threshold_floor = 1e-6f;
    const krs::ray<double> r{{-0.9, 0, 0}, {1, 0, 0}};
    const krs::hit<double> h = krs::sphere_trace(z, r, o);
    REQUIRE(h.found);
    CHECK(h.t == doctest::Approx(2.4).epsilon(1e-5));
    CHECK(h.steps < 60);
    // A ray across the zone from outside passes through it too.
    const krs::ray<double> r2{{0, -3, 0}, {0, 1, 0}};
    CHECK_FALSE(krs::sphere_trace(z, r2, o).found);
    CHECK(krs::sphere_trace(s, r2, o).found);
    CHECK_THROWS_WITH_AS(krs::with_empty_zones<decltype(s)>(s, {krs::bounding_sphere{{0, 0, 0}, -1.0f}}),
                         doctest::Contains("with_empty_zones.zones[0].radius"), krs::invalid_parameter);
    CHECK_THROWS_WITH_AS(krs::with_empty_zones<decltype(s)>(s, {}, 0.0f),
                         doctest::Contains("with_empty_zones.skip_depth_fraction"), krs::invalid_parameter);
}

TEST_CASE("closest_point matches the sphere closed form and lands on the zero set")
{
    const krs::sphere ball({0.5f, -0.2f, 1.0f}, 0.8f);
    std::mt19937_64 g(6);
    for (int k = 0; k < 1000; ++k) {
        const vec3d p = vec3d(ball.center) + random_direction(g) * uniform(g, 0.05, 5.0);
        const auto r = krs::closest_point(ball, p);
        REQUIRE(r.converged);
        const vec3d expected = vec3d(ball.center) + krs::normalize(p - vec3d(ball.center)) * double(ball.radius);
        REQUIRE(krs::length(r.point - expected) < 1e-6);
    }
    // A tree KRS (clipped, underestimating): the walk still ends on the surface.
    krs::model::tree_style style;
    style.levels = 6;
    const auto tree = krs::model::build_tree(krs::model::grow_tree(style));
    krs::closest_point_options o;
    o.tolerance = 1e-5f;
    o.max_iterations = 200;
    int converged = 0;
    for (int k = 0; k < 300; ++k) {
        const vec3d p{uniform(g, -2, 2), uniform(g, 0.1, 4), uniform(g, -2, 2)};
        const auto r = krs::closest_point(tree, p, o);
        REQUIRE(std::isfinite(r.distance));
        if (r.converged) {
            ++converged;
            REQUIRE(std::abs(tree.distance(r.point)) <= 1e-5);
            // A surface point is never nearer to p than the field's (under)estimate said.
            REQUIRE(krs::length(r.point - p) >= std::abs(tree.distance(p)) - 1e-6);
        }
    }
    CHECK(converged > 250);
    const krs::contact c = krs::contact_at(ball, vec3f{0.5f, 2.0f, 1.0f});
    CHECK(c.distance == doctest::Approx(1.4));
    CHECK(krs::length(c.normal - vec3f{0, 1, 0}) < 1e-6f);
    o.max_iterations = 0;
    CHECK_THROWS_WITH_AS(krs::closest_point(ball, vec3d{0, 0, 0}, o), doctest::Contains("closest_point_options.max_iterations"),
                         krs::invalid_parameter);
}

TEST_CASE("gradient normals and closest points stay accurate far from the origin")
{
    // A union has no normal of its own, so contact_at and closest_point difference it. At x = 1000
    // the default step 1e-4 is below float's spacing (6e-5 there, 2.4e-4 at 3000): unraised, the
    // normal came out (0.675, 0.738, 0) at 1000 and (0, 1, 0) at 3000.
    for (float x : {1.0f, 1000.0f, 3000.0f}) {
        CAPTURE(x);
        const krs::union_of<krs::sphere, krs::sphere> pair(krs::sphere({x, 0, 0}, 1.0f), krs::sphere({x, 10, 0}, 1.0f));
        const vec3d expected_normal{0.6, 0.8, 0.0};
        const krs::contact c = krs::contact_at(pair, vec3f{x + 0.6f, 0.8f, 0.0f});
        CHECK(krs::length(vec3d(c.normal) - expected_normal) < 0.02);
        const auto r = krs::closest_point(pair, vec3f{x + 1.2f, 1.6f, 0.0f});
        CHECK(r.converged);
        CHECK(krs::length(vec3d(r.point) - vec3d{x + 0.6, 0.8, 0.0}) < 0.01);
    }
}

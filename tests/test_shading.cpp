// Shading (Algorithm 2, Phong), soft shadows, ambient occlusion, texturing and depth composition
// against closed forms and brute-force references.

#include "krs/compose/depth.hpp"
#include "krs/scenes/example_scenes.hpp"
#include "krs/scenes/scene_files.hpp"
#include "krs/kernels/plane.hpp"
#include "krs/kernels/sphere.hpp"
#include "krs/model/terrain.hpp"
#include "krs/shade/global.hpp"
#include "krs/shade/kernel_light.hpp"
#include "krs/shade/lambert.hpp"
#include "krs/shade/texture.hpp"
#include "krs/trace/camera.hpp"

#include "support/random.hpp"

#include "support/parity.hpp"

#include <doctest/doctest.h>

#include <bit>
#include <cmath>
#include <cstdint>
#include <limits>
#include <random>

namespace {

using krs::vec3d;
using krs::vec3f;

using krs_test::random_direction;
using krs_test::uniform;

// A KRS of spheres and planes whose mirrors are unaligned (and cross some kernels).
using mixed = krs::sequence<krs::sphere, krs::plane>;
mixed mixed_scene()
{
    mixed::builder b;
    b.kernel(krs::sphere({0.4f, 0.3f, 0.2f}, 0.3f));
    b.kernel(krs::plane({0.2f, 1, 0.1f}, -0.6f));
    b.mirror(krs::mirror({1, 0.3f, 0.2f}, 0.9f));
    b.kernel(krs::sphere({-0.5f, 0.8f, 0.1f}, 0.25f));
    b.mirror(krs::mirror({0.1f, -0.2f, 1}, 0.7f));
    b.mirror(krs::mirror({-0.6f, 0.1f, 1}, 1.5f));
    b.kernel(krs::sphere({1.5f, 0.2f, -1.0f}, 0.4f));
    b.mirror(krs::mirror({1, 0, -0.4f}, 2.2f));
    return b.build();
}

// Independent reference of the light in the nearest kernel's space: walk the mirrors from the
// top with explicit reflections, record every plane distance, and reflect the light exactly where
// the point was reflected, down to the nearest kernel's level.
struct reference_light {
    vec3d light;
    double nearest_plane_distance;
    std::uint32_t level;
};
reference_light reflect_by_bits(const mixed& s, const vec3d& x, const vec3d& to_light)
{
    const std::size_t n = s.mirror_count();
    vec3d p = x, w = to_light;
    double best = INFINITY, nearest_plane = INFINITY;
    reference_light out{to_light, INFINITY, 0};
    for (std::size_t i = n + 1; i-- > 0;) {
        if (i < n) {
            const vec3d m(s.mirrors()[i].normal);
            const double e = krs::dot(m, p) - double(s.mirrors()[i].offset);
            nearest_plane = std::min(nearest_plane, std::abs(e));
            if (e > 0) {
                p = p - m * (2 * e);
                w = w - m * (2 * krs::dot(m, w));
            }
        }
        for (std::uint32_t k = s.level_begin(i); k < s.level_begin(i + 1); ++k) {
            const double d = std::visit([&](const auto& kernel) { return kernel.distance(p); }, s.kernels()[k]);
            if (d < best) {
                best = d;
                out.light = w;
                out.level = std::uint32_t(i);
                out.nearest_plane_distance = nearest_plane;
            }
        }
    }
    // Only the planes above the nearest kernel's level affect its light.
    return out;
}

} // namespace

TEST_CASE("Algorithm 2: far from mirror planes the light is the light reflected by the recorded bits")
{
    const mixed s = mixed_scene();
    std::mt19937_64 g(11);
    const double threshold = 0.02;
    int compared = 0;
    for (int k = 0; k < 3000; ++k) {
        const vec3d x{uniform(g, -4, 4), uniform(g, -1, 2), uniform(g, -4, 4)};
        const vec3d l = random_direction(g), v = random_direction(g);
        const reference_light ref = reflect_by_bits(s, x, l);
        const auto k_space = krs::shade_in_kernel_space(s, x, l, v, threshold);
        if (ref.nearest_plane_distance <= threshold) continue; // inside a blending band
        ++compared;
        REQUIRE(k_space.where.level == ref.level);
        REQUIRE(krs::length(k_space.light - ref.light) < 1e-9);
        // Shading in kernel space equals shading in world space: n_kernel . l_kernel = n_world . l_world.
        const vec3d n_world = s.normal(s.locate(x));
        REQUIRE(krs::dot(k_space.normal, k_space.light) == doctest::Approx(krs::dot(n_world, l)).epsilon(1e-9));
    }
    CHECK(compared > 1500);
}

TEST_CASE("Algorithm 2: the interpolated light is continuous across a mirror plane")
{
    // A terrain: one plane kernel at level 0, so the nearest kernel never changes and the light is
    // a composition of ramps: each level changes by at most 2 |dx| / threshold (see kernel_light.hpp),
    // so a step of h moves the light by at most 2 n h / threshold.
    krs::model::terrain_parameters tp;
    tp.levels = 10;
    tp.extra_planes = 0;
    tp.size = 4.0f;
    const krs::model::plane_sequence s = krs::model::build_terrain(tp);
    const std::size_t n = s.mirror_count();
    const double threshold = 0.05, h = threshold / 64;
    const vec3d light = krs::normalize(vec3d{0.3, 1, 0.5}), view{0, 1, 0};
    std::mt19937_64 g(5);
    double largest_smooth = 0, largest_step = 0;
    for (int line = 0; line < 20; ++line) {
        // A line crossing the top mirror plane.
        const krs::mirror& m = s.mirrors().back();
        const vec3d on_plane = vec3d(m.normal) * double(m.offset) + vec3d{0, uniform(g, -0.5, 0.5), 0} +
                               krs::cross(vec3d(m.normal), vec3d{0, 1, 0}) * uniform(g, -2, 2);
        const vec3d dir = krs::normalize(vec3d(m.normal) + random_direction(g) * 0.3);
        vec3d prev_smooth{}, prev_step{};
        for (int i = 0; i <= 400; ++i) {
            const vec3d x = on_plane + dir * (h * (i - 200));
            const vec3d smooth = krs::shade_in_kernel_space(s, x, light, view, threshold).light;
            const vec3d step = krs::shade_in_kernel_space(s, x, light, view, 0.0).light;
            if (i > 0) {
                const double change = krs::length(smooth - prev_smooth);
                REQUIRE(change <= 2.0 * double(n) * h / threshold + 1e-9);
                largest_smooth = std::max(largest_smooth, change);
                largest_step = std::max(largest_step, krs::length(step - prev_step));
            }
            prev_smooth = smooth;
            prev_step = step;
        }
    }
    // Without interpolation the light jumps at the plane (what the bound above rules out).
    CHECK(largest_step > 0.2);
    CHECK(largest_smooth > 0.0);
}

TEST_CASE("Algorithm 2: the Lambert shaded value is continuous across a mirror that crosses its kernel")
{
    // A steep plane kernel crossed by two vertical mirrors (not separated: the surface is creased
    // along each). Along a line on the surface crossing the top mirror, the shaded value
    // max(n . l, 0) with the interpolated light l changes between neighbouring samples by at most
    // C |dx| / threshold with C = 2 * mirrors: each level's weight is a clamp of e / threshold
    // with e 1-Lipschitz in x, moves the light by at most 2 |dweight| (M w - w, |w| <= 1), later
    // levels are convex combinations of orthogonal maps (norm <= 1), and max(n . l, 0) is
    // 1-Lipschitz in l for a unit n.
    krs::sequence<krs::plane>::builder b;
    b.kernel(krs::plane(krs::normalize(vec3f{0.9f, 1, 0.4f}), 0.0f));
    b.mirror(krs::mirror(krs::normalize(vec3f{0.3f, 0, 1}), 0.35f));
    b.mirror(krs::mirror(krs::normalize(vec3f{1, 0, -0.2f}), 0.1f));
    const auto s = b.build();
    const double C = 2.0 * double(s.mirror_count());
    const vec3d light = krs::normalize(vec3d{0.8, 0.6, 0.3}), view{0, 1, 0};
    const double threshold = 0.1, h = threshold / 100;
    // The surface point above (x, z): the field's one crossing of the vertical line (bisection).
    auto surface = [&](double x, double z) {
        double lo = -20, hi = 20;
        for (int i = 0; i < 100; ++i) {
            const double mid = 0.5 * (lo + hi);
            (s.distance(vec3d{x, mid, z}) <= 0 ? lo : hi) = mid;
        }
        return vec3d{x, 0.5 * (lo + hi), z};
    };
    auto lambert = [&](const vec3d& p, double band) {
        const auto k = krs::shade_in_kernel_space(s, p, light, view, band);
        return std::max(krs::dot(k.normal, k.light), 0.0);
    };
    const krs::mirror& top = s.mirrors().back();
    const vec3d m(top.normal);
    const vec3d along = krs::normalize(krs::cross(m, vec3d{0, 1, 0}));
    std::mt19937_64 g(13);
    double largest_ratio = 0, largest_step_jump = 0;
    int in_band = 0;
    for (int line = 0; line < 20; ++line) {
        const vec3d start = m * double(top.offset) + along * uniform(g, -1.5, 1.5);
        const vec3d dir = krs::normalize(m + along * uniform(g, -0.4, 0.4));
        vec3d previous{};
        double previous_smooth = 0, previous_step = 0;
        for (int i = 0; i <= 300; ++i) {
            const vec3d q = start + dir * (h * (i - 150));
            const vec3d p = surface(q.x, q.z);
            const double smooth = lambert(p, threshold), step = lambert(p, 0.0);
            in_band += std::abs(krs::dot(m, p) - double(top.offset)) < 0.5 * threshold;
            if (i > 0) {
                const double dx = krs::length(p - previous);
                const double change = std::abs(smooth - previous_smooth);
                REQUIRE(change <= C * dx / threshold + 1e-9);
                largest_ratio = std::max(largest_ratio, change * threshold / dx);
                largest_step_jump = std::max(largest_step_jump, std::abs(step - previous_step));
            }
            previous = p, previous_smooth = smooth, previous_step = step;
        }
    }
    MESSAGE("largest |d shade| * threshold / |dx|: " << largest_ratio << " (bound " << C
                                                     << "); flat shading's largest jump " << largest_step_jump);
    CHECK(in_band > 1000);           // the samples did cross the band on both sides of the plane
    CHECK(largest_ratio > 0.05);     // and the shading does turn there
    // Without interpolation the shaded value jumps at the plane far beyond what the bound allows.
    CHECK(largest_step_jump > 10 * C * h / threshold);
}

TEST_CASE("Algorithm 2 on a mirror plane with a subnormal threshold, and with bad input")
{
    // 1 / threshold overflowed to infinity for a subnormal threshold, and a point on a mirror
    // (e = 0) weighed 0 * inf = NaN: light NaN. Below float's smallest normal the step is kept.
    krs::sequence<krs::sphere>::builder b;
    b.kernel(krs::sphere({0, 0.5f, 0}, 0.3f)).mirror(krs::mirror({1, 0, 0}, 0.0f));
    const auto s = b.build();
    const vec3d on_mirror{0, 0.5, 0}, l = krs::normalize(vec3d{0.3, 1, 0.2});
    for (double threshold : {0.0, 1e-320, 1e-310, 1e-40, 1e-3}) {
        INFO(threshold);
        const auto k = krs::shade_in_kernel_space(s, on_mirror, l, l, threshold);
        REQUIRE(std::isfinite(k.light.x));
        REQUIRE(std::isfinite(k.light.y));
        REQUIRE(std::isfinite(k.light.z));
        // Below double's smallest normal the step keeps the light unit; above it, on the plane,
        // the ramp's weight is 1/2 (the mean of the light and its reflection).
        if (threshold < std::numeric_limits<double>::min()) CHECK(std::abs(krs::length(k.light) - 1.0) < 1e-9);
        else CHECK(krs::length(k.light - (l + krs::mirror({1, 0, 0}, 0.0f).reflect_direction(l)) * 0.5) < 1e-7);
    }
    const auto kf = krs::shade_in_kernel_space(s, vec3f{0, 0.5f, 0}, vec3f(l), vec3f(l), 1e-40f);
    CHECK(std::isfinite(kf.light.x + kf.light.y + kf.light.z));
    CHECK_THROWS_WITH_AS(krs::shade_in_kernel_space(s, vec3d{NAN, 0, 0}, l, l, 0.1), doctest::Contains("shade_in_kernel_space.x"),
                         krs::invalid_parameter);
    CHECK_THROWS_WITH_AS(krs::shade_in_kernel_space(s, on_mirror, vec3d{NAN, 0, 0}, l, 0.1),
                         doctest::Contains("shade_in_kernel_space.to_light"), krs::invalid_parameter);
    CHECK_THROWS_WITH_AS(krs::shade_in_kernel_space(s, on_mirror, l, vec3d{0, INFINITY, 0}, 0.1),
                         doctest::Contains("shade_in_kernel_space.to_eye"), krs::invalid_parameter);
}

TEST_CASE("Algorithm 2 gives axis-aligned mirrors the light of the equivalent general mirrors")
{
    // The same terrain-like KRS with axis_mirror and with general mirrors: same interpolated light.
    krs::axis_sequence<krs::plane>::builder a;
    krs::sequence<krs::plane>::builder g;
    const krs::plane ground({0.3f, 1, -0.2f}, 0.0f);
    a.kernel(ground);
    g.kernel(ground);
    const float positions[4] = {0.4f, -0.7f, 1.3f, 0.2f};
    for (int i = 0; i < 4; ++i) {
        const krs::axis_mirror m(i % 2 == 0 ? 0 : 2, positions[i], i < 2);
        a.mirror(m);
        g.mirror(m.general());
    }
    const auto sa = a.build();
    const auto sg = g.build();
    std::mt19937_64 rng(8);
    for (int k = 0; k < 2000; ++k) {
        const vec3d x{uniform(rng, -3, 3), uniform(rng, -1, 1), uniform(rng, -3, 3)};
        const vec3d l = random_direction(rng);
        const auto ka = krs::shade_in_kernel_space(sa, x, l, l, 0.3);
        const auto kg = krs::shade_in_kernel_space(sg, x, l, l, 0.3);
        REQUIRE(krs::length(ka.light - kg.light) < 1e-6);
        REQUIRE(ka.where.reflections == kg.where.reflections);
    }
}

TEST_CASE("Phong terms match the closed form")
{
    krs::sequence<krs::plane>::builder b;
    b.kernel(krs::plane({0, 0, 1}, 0.0f));
    const auto s = b.build();
    const double a = 30.0 * 3.14159265358979 / 180.0;
    const vec3d l{std::sin(a), 0, std::cos(a)};
    const vec3d mirrored{-std::sin(a), 0, std::cos(a)};
    const auto k1 = krs::shade_in_kernel_space(s, vec3d{0, 0, 0.1}, l, mirrored, 0.01);
    const krs::phong_terms t1 = krs::phong(k1, 20.0);
    CHECK(t1.diffuse == doctest::Approx(std::cos(a)));
    CHECK(t1.specular == doctest::Approx(1.0));
    const auto k2 = krs::shade_in_kernel_space(s, vec3d{0, 0, 0.1}, l, l, 0.01);
    // r . v = cos(2a) for a view along the light.
    CHECK(krs::phong(k2, 8.0).specular == doctest::Approx(std::pow(std::cos(2 * a), 8.0)).epsilon(1e-5));
    CHECK_THROWS_AS(krs::phong(k2, 0.0), krs::invalid_parameter);
    CHECK_THROWS_AS(krs::shade_in_kernel_space(s, vec3d{0, 0, 0.1}, l, l, -1.0), krs::invalid_parameter);
}

TEST_CASE("soft shadow stays in [0 1] and equals the hard shadow as hardness grows")
{
    krs::sequence<krs::sphere, krs::plane>::builder b;
    b.kernel(krs::sphere({0, 1.0f, 0}, 0.4f));
    b.mirror(krs::mirror({1, 0, 0.3f}, 1.2f));
    b.kernel(krs::plane({0, 1, 0}, 0.0f));
    const auto s = b.build();
    const vec3d to_light = krs::normalize(vec3d{0.2, 1, 0.1});
    std::mt19937_64 g(3);
    krs::soft_shadow_options soft;
    soft.threshold = 1e-4f;
    soft.max_distance = 20.0f;
    soft.max_steps = 512;
    soft.hardness = 8.0f;
    krs::soft_shadow_options sharp = soft;
    sharp.hardness = 1e9f;
    int penumbra = 0, shadowed = 0, lit = 0;
    for (int k = 0; k < 2000; ++k) {
        const vec3d p{uniform(g, -2, 4), 0.0, uniform(g, -2, 2)};
        const vec3d n{0, 1, 0};
        const double v = krs::soft_shadow(s, p, n, to_light, soft);
        REQUIRE(v >= 0.0);
        REQUIRE(v <= 1.0);
        const double hard = krs::hard_shadow(s, p, n, to_light, 1e-4, 20.0);
        REQUIRE(krs::soft_shadow(s, p, n, to_light, sharp) == hard);
        // The soft estimate is never brighter where the light is blocked.
        if (hard == 0.0) REQUIRE(v == 0.0);
        penumbra += v > 0.05 && v < 0.95;
        shadowed += hard == 0.0;
        lit += hard == 1.0;
    }
    CHECK(penumbra > 20);
    CHECK(shadowed > 20);
    CHECK(lit > 20);
    soft.hardness = 0.0f;
    CHECK_THROWS_WITH_AS(soft.validate(), doctest::Contains("soft_shadow_options.hardness"), krs::invalid_parameter);
}

TEST_CASE("ambient occlusion above an infinite plane kernel matches the closed form")
{
    // Half-space y <= 0 inside a KRS whose vertical mirror leaves it unchanged. At p = (0, h0, 0)
    // sampling along a unit direction w with w . y = cos(theta): d(s) = h0 + s cos(theta).
    krs::sequence<krs::plane>::builder b;
    b.kernel(krs::plane({0, 1, 0}, 0.0f));
    b.mirror(krs::mirror({1, 0, 0.2f}, 30.0f));
    const auto s = b.build();
    krs::ambient_occlusion_options o;
    o.step = 0.1f;
    o.samples = 6;
    o.falloff = 0.6f;
    o.strength = 1.5f;
    for (double h0 : {0.0, 0.02, 0.1}) {
        for (double theta_degrees : {0.0, 30.0, 60.0, 85.0}) {
            const double theta = theta_degrees * 3.14159265358979 / 180.0;
            const vec3d w{std::sin(theta), std::cos(theta), 0};
            double occlusion = 0, total = 0, weight = 1;
            for (int j = 1; j <= o.samples; ++j) {
                const double sj = j * double(o.step);
                occlusion += weight * (sj - (h0 + sj * std::cos(theta))) / sj;
                total += weight;
                weight *= double(o.falloff);
            }
            const double expected = std::clamp(1.0 - double(o.strength) * occlusion / total, 0.0, 1.0);
            CHECK(krs::ambient_occlusion(s, vec3d{0, h0, 0}, w, o) == doctest::Approx(expected).epsilon(1e-9));
        }
    }
    // Straight up from the surface nothing occludes; in a corner something does.
    CHECK(krs::ambient_occlusion(s, vec3d{0, 0, 0}, vec3d{0, 1, 0}, o) == doctest::Approx(1.0));
    krs::sequence<krs::plane>::builder corner;
    corner.kernel(krs::plane({0, 1, 0}, 0.0f));
    corner.kernel(krs::plane({-1, 0, 0}, 0.0f)); // x >= 0 is solid
    const auto c = corner.build();
    CHECK(krs::ambient_occlusion(c, vec3d{-0.01, 0, 0}, vec3d{0, 1, 0}, o) < 0.9);
    o.samples = 0;
    CHECK_THROWS_WITH_AS(o.validate(), doctest::Contains("ambient_occlusion_options.samples"), krs::invalid_parameter);
}

namespace {

// Soft shadows and ambient occlusion of packets against the scalar calls, lane by lane, on a scene
// of the examples: points near the surface (as the GLSL parity test samples them), each lane with
// its own point, normal (the surface's, or a random one) and light direction, a random quarter of
// the lanes left out of the shadow. The scalar call is the reference; the packet runs the same
// template, so under -ffp-contract=off every lane must equal it bit for bit.
template <class S>
void check_packet_shading(const krs::scenes::scene<S>& scene, std::uint64_t seed)
{
    using P = krs::packet_f;
    constexpr std::size_t W = krs::lane_count<P>;
    const float scale = scene.extent();
    krs::soft_shadow_options so;
    so.hardness = 12.0f;
    so.threshold = 1e-5f * scale;
    so.max_distance = 2.0f * scale;
    so.max_steps = 160;
    krs::ambient_occlusion_options ao;
    ao.step = 0.02f * scale;
    std::mt19937_64 g(seed);
    const auto in_box = [&] {
        return scene.sample_center + vec3f{float(uniform(g, -1, 1)) * scene.sample_half.x,
                                           float(uniform(g, -1, 1)) * scene.sample_half.y,
                                           float(uniform(g, -1, 1)) * scene.sample_half.z};
    };
    krs_test::parity shadows{"soft shadow, packet against scalar, " + scene.name, 1.0};
    krs_test::parity occlusion{"ambient occlusion, packet against scalar, " + scene.name, 1.0};
    // Under FMA contraction (krs_parity_contract_native, tests/support/parity.hpp) the two paths
    // round differently, and the soft shadow has no bound of the contraction tolerance's kind: a
    // march passing within the threshold returns 0 on one side and up to k d / t on the other,
    // whatever last-bit difference decided it. Away from that, an ulp of a step moves the next
    // sample by an ulp of t and k d / t by a few ulp. So there, as in the GLSL comparison
    // (tests/test_glsl_shading.cpp), all but 0.1% of lanes must agree to 1e-3; everywhere else,
    // every lane bit for bit.
    long shadow_lanes = 0, shadow_off = 0;
    const auto same_shadow = [&](float packet, float scalar) {
        ++shadow_lanes;
        if (shadows.agree(packet, scalar)) return true;
        if (!krs_test::contraction) return false;
        shadow_off += std::abs(packet - scalar) > 1e-3f;
        return true;
    };
    int penumbra = 0, dark = 0, lit = 0, left_out = 0, occluded = 0;
    for (int k = 0; k < 60; ++k) {
        alignas(64) float px[W], py[W], pz[W], nx[W], ny[W], nz[W], lx[W], ly[W], lz[W], th[W];
        bool use[W];
        for (std::size_t i = 0; i < W; ++i) {
            vec3f p;
            do p = in_box();
            while (!(scene.field.distance(p) > 1e-4f * scale && scene.field.distance(p) < 0.02f * scale));
            const vec3f n = g() % 4 == 0 ? vec3f(random_direction(g)) : scene.field.normal(p);
            vec3f l = vec3f(random_direction(g));
            if (krs::dot(l, n) < 0) l = -l; // toward the light side mostly, where shadows are marched
            px[i] = p.x, py[i] = p.y, pz[i] = p.z, nx[i] = n.x, ny[i] = n.y, nz[i] = n.z;
            lx[i] = l.x, ly[i] = l.y, lz[i] = l.z;
            use[i] = g() % 4 != 0;
            th[i] = float(uniform(g, 1e-6, 1e-4)) * scale; // each lane's own threshold (a primary hit's)
        }
        const krs::vec3<P> p{P::load_aligned(px), P::load_aligned(py), P::load_aligned(pz)};
        const krs::vec3<P> n{P::load_aligned(nx), P::load_aligned(ny), P::load_aligned(nz)};
        const krs::vec3<P> l{P::load_aligned(lx), P::load_aligned(ly), P::load_aligned(lz)};
        const auto lanes = P::batch_bool_type::load_unaligned(use);
        const P shadow = krs::soft_shadow(scene.field, p, n, l, so, lanes);
        const P all_lanes_shadow = krs::soft_shadow(scene.field, p, n, l, so);
        const P occ = krs::ambient_occlusion(scene.field, p, n, ao);
        const P own_threshold = krs::soft_shadow(scene.field, p, n, l, so, lanes, P::load_aligned(th));
        for (std::size_t i = 0; i < W; ++i) {
            const vec3f pi{px[i], py[i], pz[i]}, ni{nx[i], ny[i], nz[i]}, li{lx[i], ly[i], lz[i]};
            const float scalar = krs::soft_shadow(scene.field, pi, ni, li, so);
            CAPTURE(k);
            CAPTURE(i);
            REQUIRE(same_shadow(krs::lane_at(all_lanes_shadow, i), scalar));
            krs::soft_shadow_options own = so;
            own.threshold = th[i];
            if (use[i]) {
                REQUIRE(same_shadow(krs::lane_at(shadow, i), scalar));
                REQUIRE(same_shadow(krs::lane_at(own_threshold, i), krs::soft_shadow(scene.field, pi, ni, li, own)));
            } else {
                REQUIRE(krs::lane_at(shadow, i) == 0.0f);
                REQUIRE(krs::lane_at(own_threshold, i) == 0.0f);
                ++left_out;
            }
            const float scalar_ao = krs::ambient_occlusion(scene.field, pi, ni, ao);
            REQUIRE(occlusion.agree(krs::lane_at(occ, i), scalar_ao));
            penumbra += scalar > 0.0f && scalar < 1.0f;
            dark += scalar == 0.0f;
            lit += scalar == 1.0f;
            occluded += scalar_ao < 0.9f;
        }
    }
    shadows.report();
    occlusion.report();
    if (krs_test::contraction) MESSAGE(shadow_off << " of " << shadow_lanes << " shadow lanes differ by more than 1e-3");
    CHECK(shadow_off <= shadow_lanes / 1000);
    MESSAGE(scene.name << ": " << penumbra << " penumbra, " << dark << " dark, " << lit << " lit lanes, " << occluded
                       << " occluded");
    // The comparison covers every outcome of the march and of the occlusion sum.
    CHECK(penumbra > int(W) * 2);
    CHECK(dark > int(W) * 3);
    CHECK(left_out > 0);
    CHECK(occluded > int(W) * 3);
}

} // namespace

TEST_CASE("soft shadows and ambient occlusion in packets equal the scalar calls lane by lane")
{
    namespace ex = krs::scenes;
    SUBCASE("tree") { check_packet_shading(ex::tree_scene::build(), 1); }
    SUBCASE("forest") { check_packet_shading(ex::forest_scene::build(), 2); }
    SUBCASE("terrain") { check_packet_shading(ex::terrain_scene::build(), 3); }
}

TEST_CASE("soft shadow: lanes with an unusable shadow ray are dark, in packets and alone")
{
    const auto tree = krs::scenes::tree_scene::build();
    krs::soft_shadow_options o;
    const vec3f p{0.3f, 3.0f, 0.2f}, n{0, 1, 0};
    const float nan = std::numeric_limits<float>::quiet_NaN(), inf = std::numeric_limits<float>::infinity();
    for (const vec3f& l : {vec3f{0, 0, 0}, vec3f{nan, 1, 0}, vec3f{0, inf, 0}}) {
        CHECK(krs::soft_shadow(tree.field, p, n, l, o) == 0.0f);
        const krs::vec3<krs::packet_f> pp(p), np(n), lp(l);
        CHECK(xsimd::all(krs::soft_shadow(tree.field, pp, np, lp, o) == krs::packet_f(0.0f)));
    }
    CHECK(krs::soft_shadow(tree.field, vec3f{nan, 0, 0}, n, n, o) == 0.0f);
    // A lane's own threshold must be a threshold where the lane is shaded, and only there.
    using P = krs::packet_f;
    const krs::vec3<P> pp(p), np(n);
    const P bad(0.0f);
    CHECK_THROWS_WITH_AS(krs::soft_shadow(tree.field, pp, np, np, o, P(0.0f) == P(0.0f), bad),
                         doctest::Contains("soft_shadow.threshold"), krs::invalid_parameter);
    CHECK(xsimd::all(krs::soft_shadow(tree.field, pp, np, np, o, P(0.0f) != P(0.0f), bad) == P(0.0f)));
}

TEST_CASE_TEMPLATE("value noise is bounded and obeys its declared gradient bound", T, float, krs::packet_f)
{
    std::mt19937_64 g(9);
    constexpr std::size_t lanes = krs::lane_count<T>;
    krs_test::parity same{"value noise, packet against scalar", 1.0}; // values in [-1, 1]
    int disagreements = 0;
    for (int k = 0; k < 4000; ++k) {
        alignas(64) float xs[lanes], ys[lanes], zs[lanes];
        for (std::size_t i = 0; i < lanes; ++i)
            xs[i] = float(uniform(g, -50, 50)), ys[i] = float(uniform(g, -50, 50)), zs[i] = float(uniform(g, -50, 50));
        T x, y, z;
        if constexpr (std::floating_point<T>)
            x = xs[0], y = ys[0], z = zs[0];
        else
            x = T::load_aligned(xs), y = T::load_aligned(ys), z = T::load_aligned(zs);
        const T v = krs::value_noise(krs::vec3<T>{x, y, z});
        for (std::size_t i = 0; i < lanes; ++i) {
            const float scalar = krs::value_noise(vec3f{xs[i], ys[i], zs[i]});
            if constexpr (krs_test::contraction) {
                if (!same.agree(krs::lane_at(v, i), scalar)) ++disagreements;
            } else {
                REQUIRE(krs::lane_at(v, i) == doctest::Approx(scalar).epsilon(1e-4));
            }
            REQUIRE(scalar >= -1.0f);
            REQUIRE(scalar <= 1.0f);
            // Lipschitz: a nearby pair never differs by more than the bound allows.
            const vec3d a{xs[i], ys[i], zs[i]};
            const vec3d b = a + random_direction(g) * uniform(g, 1e-3, 0.3);
            const double dv = std::abs(krs::value_noise(a) - krs::value_noise(b));
            REQUIRE(dv <= krs::value_noise_gradient_bound * krs::length(a - b) + 1e-9);
        }
    }
    same.report();
    CHECK(disagreements == 0);
}

// value_noise as it was written before it shared the per-axis scrambles between corners: the
// whole lattice hash per corner, from ix + d (the form the GLSL emitter also uses).
template <class T>
T value_noise_hashing_each_corner(const krs::vec3<T>& p)
{
    using krs::detail::fract;
    auto hash = [](const T& x, const T& y, const T& z) {
        T a = fract(krs::unfused(x * T(0.1031f))), b = fract(krs::unfused(y * T(0.11369f))),
          c = fract(krs::unfused(z * T(0.13787f)));
        const T m = krs::unfused(a * (b + T(19.19f))) + krs::unfused(b * (c + T(19.19f))) +
                    krs::unfused(c * (a + T(19.19f)));
        a = a + m, b = b + m, c = c + m;
        return fract(krs::unfused((a + b) * c));
    };
    const T ix = krs::detail::floor_lane(p.x), iy = krs::detail::floor_lane(p.y), iz = krs::detail::floor_lane(p.z);
    const T fx = krs::detail::fade(p.x - ix), fy = krs::detail::fade(p.y - iy), fz = krs::detail::fade(p.z - iz);
    const T zero(0), one(1);
    auto corner = [&](const T& dx, const T& dy, const T& dz) { return hash(ix + dx, iy + dy, iz + dz); };
    const T x00 = krs::mix(corner(zero, zero, zero), corner(one, zero, zero), fx);
    const T x10 = krs::mix(corner(zero, one, zero), corner(one, one, zero), fx);
    const T x01 = krs::mix(corner(zero, zero, one), corner(one, zero, one), fx);
    const T x11 = krs::mix(corner(zero, one, one), corner(one, one, one), fx);
    const T v = krs::mix(krs::mix(x00, x10, fy), krs::mix(x01, x11, fy), fz);
    return v * T(2) - one;
}

template <class S>
auto bits_of(S x)
{
    if constexpr (sizeof(S) == 4)
        return std::bit_cast<std::uint32_t>(x);
    else
        return std::bit_cast<std::uint64_t>(x);
}

TEST_CASE_TEMPLATE("value noise equals the lattice hash computed per corner, bit for bit", T, float, double, krs::packet_f,
                   krs::packet_d)
{
    using S = krs::scalar_t<T>;
    constexpr std::size_t lanes = krs::lane_count<T>;
    std::mt19937_64 g(20261201);
    // Random points near the origin and out to the hash's documented range (2^16), lattice points,
    // their neighbours one ulp away, and -0 (where ix + 0 is +0 but ix is -0).
    auto coordinate = [&](int k) -> S {
        switch (k % 6) {
        case 0: return S(uniform(g, -50, 50));
        case 1: return S(uniform(g, -65536, 65536));
        case 2: return S(std::floor(uniform(g, -100, 100)));
        case 3: {
            const S i = S(std::floor(uniform(g, -100, 100)));
            return std::nextafter(i, g() % 2 ? S(-1000) : S(1000));
        }
        case 4: return g() % 2 ? S(-0.0) : S(0.0);
        default: return S(uniform(g, -1, 1));
        }
    };
    long compared = 0, differing = 0;
    for (int n = 0; n < 20000; ++n) {
        alignas(64) S xs[lanes], ys[lanes], zs[lanes];
        for (std::size_t i = 0; i < lanes; ++i) {
            const int k = int(g() % 36);
            xs[i] = coordinate(k), ys[i] = coordinate(k / 6), zs[i] = coordinate(k + n);
        }
        krs::vec3<T> p;
        if constexpr (std::floating_point<T>)
            p = {xs[0], ys[0], zs[0]};
        else
            p = {T::load_aligned(xs), T::load_aligned(ys), T::load_aligned(zs)};
        const T got = krs::value_noise(p), expected = value_noise_hashing_each_corner(p);
        for (std::size_t i = 0; i < lanes; ++i) {
            ++compared;
            if (bits_of(krs::lane_at(got, i)) != bits_of(krs::lane_at(expected, i))) {
                if (++differing <= 5)
                    MESSAGE("at (" << xs[i] << ", " << ys[i] << ", " << zs[i] << "): " << krs::lane_at(got, i)
                                   << ", per corner " << krs::lane_at(expected, i));
            }
        }
    }
    MESSAGE(compared << " values compared, " << differing << " differ");
    CHECK(differing == 0);
}

TEST_CASE("fractal noise and triplanar projection")
{
    const krs::fractal_noise fbm(5, 0.7f);
    std::mt19937_64 g(2);
    double lo = 1, hi = -1;
    for (int k = 0; k < 5000; ++k) {
        const vec3d p{uniform(g, -20, 20), uniform(g, -20, 20), uniform(g, -20, 20)};
        const double v = fbm(p);
        lo = std::min(lo, v), hi = std::max(hi, v);
        REQUIRE(std::abs(v) <= 1.0);
    }
    CHECK(hi - lo > 0.8); // it varies
    CHECK_THROWS_WITH_AS(krs::fractal_noise(0, 1.0f), doctest::Contains("fractal_noise.octaves"), krs::invalid_parameter);
    // A first frequency of 1e30 times lacunarity 8^15 overflowed to NaN; up to 1e9 stays finite.
    CHECK_THROWS_WITH_AS(krs::fractal_noise(16, 1e30f, 8.0f), doctest::Contains("fractal_noise.frequency"),
                         krs::invalid_parameter);
    const krs::fractal_noise finest(16, 1e9f, 8.0f);
    for (const vec3f& p : {vec3f{1, 1, 1}, vec3f{1e9f, -1e9f, 3}}) CHECK(std::isfinite(finest(p)));
    // Triplanar: along an axis normal only that axis's projection is seen.
    auto pattern = [](double u, double v) { return u + 10 * v; };
    const vec3d p{1, 2, 3};
    CHECK(krs::triplanar(pattern, p, vec3d{1, 0, 0}) == doctest::Approx(2 + 30));
    CHECK(krs::triplanar(pattern, p, vec3d{0, -1, 0}) == doctest::Approx(3 + 10));
    CHECK(krs::triplanar(pattern, p, vec3d{0, 0, 1}) == doctest::Approx(1 + 20));
    // A diagonal normal averages all three.
    CHECK(krs::triplanar(pattern, p, krs::normalize(vec3d{1, 1, 1})) == doctest::Approx((32 + 13 + 21) / 3.0));
}

TEST_CASE("depth round trip t to buffer depth and back")
{
    const krs::depth_projection proj(0.1f, 500.0f);
    const krs::pinhole_camera camera({0, 1, -5}, {0.3f, 0.8f, 0}, {0, 1, 0}, 60.0f, 64, 48);
    std::mt19937_64 g(4);
    const vec3d forward(camera.forward());
    CHECK(proj.buffer_depth(0.1) == doctest::Approx(0.0));
    CHECK(proj.buffer_depth(500.0) == doctest::Approx(1.0));
    for (int k = 0; k < 2000; ++k) {
        const krs::ray<float> r = camera.primary_ray(float(uniform(g, 0, 64)), float(uniform(g, 0, 48)));
        const vec3d d(r.direction);
        const double t = std::exp(uniform(g, std::log(0.2), std::log(400.0)));
        const double z = krs::view_depth_of(t, d, forward);
        const double depth = proj.buffer_depth(z);
        REQUIRE(depth >= 0.0);
        REQUIRE(depth <= 1.0);
        const double back = krs::t_of_view_depth(proj.view_depth(depth), d, forward);
        REQUIRE(back == doctest::Approx(t).epsilon(1e-9));
    }
    // Monotonic: farther is deeper.
    for (double z = 0.1; z < 500; z *= 1.5) REQUIRE(proj.buffer_depth(z * 1.5 < 500 ? z * 1.5 : 500.0) >= proj.buffer_depth(z));
    CHECK_THROWS_WITH_AS(krs::depth_projection(1.0f, 0.5f), doctest::Contains("depth_projection.far_plane"),
                         krs::invalid_parameter);
}

TEST_CASE("a depth buffer value limits each ray")
{
    const krs::sphere s({0, 0, 5}, 1.0f);
    const krs::depth_projection proj(0.1f, 100.0f);
    krs::trace_options o;
    o.pixel_footprint = 0;
    o.threshold_floor = 1e-6f;
    const krs::ray<double> r{{0, 0, 0}, {0, 0, 1}};
    const vec3d forward{0, 0, 1};
    // Raster geometry at depth 3 hides the sphere (surface at t = 4); at depth 4.5 it does not.
    const krs::hit<double> hidden = krs::trace_against_depth(s, r, o, proj, forward, proj.buffer_depth(3.0));
    CHECK_FALSE(hidden.found);
    const krs::hit<double> seen = krs::trace_against_depth(s, r, o, proj, forward, proj.buffer_depth(4.5));
    REQUIRE(seen.found);
    CHECK(seen.t == doctest::Approx(4.0).epsilon(1e-5));
    // Bad input is refused on every path (the early miss used to skip the checks): a NaN buffer
    // value or min_distance, an invalid floor, a zero or NaN forward axis.
    CHECK_THROWS_WITH_AS(krs::trace_against_depth(s, r, o, proj, forward, double(NAN)),
                         doctest::Contains("trace_against_depth.buffer_value"), krs::invalid_parameter);
    krs::trace_options bad = o;
    bad.min_distance = NAN;
    CHECK_THROWS_WITH_AS(krs::trace_against_depth(s, r, bad, proj, forward, proj.buffer_depth(3.0)),
                         doctest::Contains("trace_options.min_distance"), krs::invalid_parameter);
    bad = o;
    bad.threshold_floor = -1;
    CHECK_THROWS_WITH_AS(krs::trace_against_depth(s, r, bad, proj, forward, proj.buffer_depth(0.01)),
                         doctest::Contains("trace_options.threshold_floor"), krs::invalid_parameter);
    for (const vec3d& axis : {vec3d{0, 0, 0}, vec3d{NAN, 0, 1}})
        CHECK_THROWS_WITH_AS(krs::trace_against_depth(s, r, o, proj, axis, proj.buffer_depth(3.0)),
                             doctest::Contains("trace_against_depth.forward"), krs::invalid_parameter);
}

namespace {

// A field that remembers whether it was ever asked about a point with a NaN or infinite coordinate.
template <class F>
struct watched_field {
    const F* inner;
    mutable bool saw_non_finite = false;

    template <class T>
    T distance(const krs::vec3<T>& p) const
    {
        using krs::any; // (unqualified below: packets take xsimd's, found by argument)
        saw_non_finite = saw_non_finite || any(!krs::is_finite(p));
        return inner->distance(p);
    }
};

} // namespace

TEST_CASE("soft shadow: a left-out lane's NaN or infinite input never reaches the field")
{
    using P = krs::packet_f;
    constexpr std::size_t W = krs::lane_count<P>;
    krs::sequence<krs::sphere, krs::plane>::builder b;
    b.kernel(krs::sphere({0, 1.0f, 0}, 0.4f));
    b.mirror(krs::mirror({1, 0, 0.3f}, 1.2f));
    b.kernel(krs::plane({0, 1, 0}, 0.0f));
    const auto s = b.build();
    krs::soft_shadow_options so;
    so.threshold = 1e-4f;
    so.max_distance = 20.0f;
    so.max_steps = 256;
    so.hardness = 8.0f;
    std::mt19937_64 g(11);
    const float nan = std::numeric_limits<float>::quiet_NaN(), inf = std::numeric_limits<float>::infinity();
    for (int k = 0; k < 20; ++k) {
        alignas(64) float px[W], py[W], pz[W], nx[W], ny[W], nz[W], lx[W], ly[W], lz[W], th[W];
        bool use[W];
        for (std::size_t i = 0; i < W; ++i) {
            const vec3f l = krs::normalize(vec3f{float(uniform(g, -0.5, 0.5)), 1.0f, float(uniform(g, -0.5, 0.5))});
            px[i] = float(uniform(g, -2, 4)), py[i] = 0.0f, pz[i] = float(uniform(g, -2, 2));
            nx[i] = 0, ny[i] = 1, nz[i] = 0, lx[i] = l.x, ly[i] = l.y, lz[i] = l.z;
            th[i] = 1e-4f;
            use[i] = i % 3 != 1;
        }
        const auto lanes = P::batch_bool_type::load_unaligned(use);
        const auto run = [&](const auto& field) {
            return krs::soft_shadow(field, krs::vec3<P>{P::load_aligned(px), P::load_aligned(py), P::load_aligned(pz)},
                                    krs::vec3<P>{P::load_aligned(nx), P::load_aligned(ny), P::load_aligned(nz)},
                                    krs::vec3<P>{P::load_aligned(lx), P::load_aligned(ly), P::load_aligned(lz)}, so, lanes,
                                    P::load_aligned(th));
        };
        const P clean = run(s);
        // Poison every input of the left-out lanes.
        for (std::size_t i = 0; i < W; ++i)
            if (!use[i]) {
                px[i] = nan, py[i] = inf, pz[i] = -inf, nx[i] = inf, ny[i] = nan, nz[i] = 0;
                lx[i] = nan, ly[i] = inf, lz[i] = nan, th[i] = i % 2 ? nan : inf;
            }
        watched_field<decltype(s)> watched{&s};
        const P poisoned = run(watched);
        CHECK_FALSE(watched.saw_non_finite);
        for (std::size_t i = 0; i < W; ++i) {
            CAPTURE(k);
            CAPTURE(i);
            REQUIRE(krs::lane_at(poisoned, i) == krs::lane_at(clean, i)); // active lanes unchanged, left out 0
            if (!use[i]) REQUIRE(krs::lane_at(poisoned, i) == 0.0f);
        }
    }
}

// Placement of any field (krs/compose/placed.hpp): translations, rotations and uniform scales
// against the placed geometry's closed-form distance in double (a sphere's and Quilez's box
// formula, with the map built here independently); a general affine map against its image
// surface sampled densely (never overestimates, zero on the surface); the spectral norm against a
// brute-force maximum over directions; Lipschitz 1 on close pairs; bounds that hold the solid;
// packets and doubles against the scalar path; refused maps. Its GLSL runs on llvmpipe in
// test_glsl_field_types.cpp.

#include "krs/compose/placed.hpp"
#include "krs/compose/smooth.hpp"
#include "krs/kernels/box.hpp"
#include "krs/kernels/sphere.hpp"

#include "support/packet_points.hpp"
#include "support/rejects.hpp"
#include "support/random.hpp"

#include <doctest/doctest.h>

#include <algorithm>
#include <array>
#include <cmath>
#include <cstdio>
#include <limits>
#include <optional>
#include <random>
#include <vector>

namespace {

using krs::vec3d;
using krs::vec3f;
using krs_test::uniform;

// A rotation matrix made another way than Rodrigues: the product of turns about z, y and x.
std::array<vec3d, 3> euler_rotation(double ax, double ay, double az)
{
    const double cx = std::cos(ax), sx = std::sin(ax), cy = std::cos(ay), sy = std::sin(ay), cz = std::cos(az),
                 sz = std::sin(az);
    // R = Rz Ry Rx, written out.
    return {vec3d{cz * cy, cz * sy * sx - sz * cx, cz * sy * cx + sz * sx},
            vec3d{sz * cy, sz * sy * sx + cz * cx, sz * sy * cx - cz * sx}, vec3d{-sy, cy * sx, cy * cx}};
}
vec3d times(const std::array<vec3d, 3>& m, const vec3d& v) { return {dot(m[0], v), dot(m[1], v), dot(m[2], v)}; }
vec3d transposed_times(const std::array<vec3d, 3>& m, const vec3d& v) { return m[0] * v.x + m[1] * v.y + m[2] * v.z; }

// Quilez's box distance in double, in the box's own frame.
double box_distance(const vec3d& p, const vec3d& half)
{
    const vec3d q{std::abs(p.x) - half.x, std::abs(p.y) - half.y, std::abs(p.z) - half.z};
    const vec3d out{std::max(q.x, 0.0), std::max(q.y, 0.0), std::max(q.z, 0.0)};
    return krs::length(out) + std::min(std::max(q.x, std::max(q.y, q.z)), 0.0);
}

} // namespace

TEST_CASE("translated, rotated and scaled fields equal the placed geometry's closed-form distance")
{
    std::mt19937_64 g(81);
    const krs::sphere ball({0.2f, -0.1f, 0.3f}, 0.5f);
    const vec3d half{0.4, 0.25, 0.6};
    const krs::box block({0, 0, 0}, vec3f(half));
    for (int trial = 0; trial < 20; ++trial) {
        const double ax = uniform(g, -3, 3), ay = uniform(g, -1.5, 1.5), az = uniform(g, -3, 3);
        const double s = uniform(g, 0.1, 8.0);
        const vec3d t{uniform(g, -20, 20), uniform(g, -20, 20), uniform(g, -20, 20)};
        const std::array<vec3d, 3> r = euler_rotation(ax, ay, az);
        // The same rotation as the library's axis-angle: its axis and angle read off the matrix.
        const double angle = std::acos(std::clamp((r[0].x + r[1].y + r[2].z - 1.0) / 2.0, -1.0, 1.0));
        const vec3d axis{r[2].y - r[1].z, r[0].z - r[2].x, r[1].x - r[0].y};
        REQUIRE(krs::length(axis) > 1e-3); // no angle near pi in these draws (seeded)
        const auto placed_ball = krs::placed(ball, krs::affine_map::rotation(axis, angle)
                                                       .then(krs::affine_map::scaling(s))
                                                       .then(krs::affine_map::translation(t)));
        const auto placed_block = krs::translated(krs::rotated(krs::scaled(block, float(s)), vec3f(axis), float(angle)),
                                                  vec3f(t));
        const vec3d ball_center = times(r, vec3d(ball.bound().center)) * s + t;
        double worst_ball = 0, worst_block = 0;
        for (int i = 0; i < 5000; ++i) {
            const vec3d p = t + vec3d{uniform(g, -1, 1), uniform(g, -1, 1), uniform(g, -1, 1)} * (2.0 * s);
            const double want_ball = krs::length(p - ball_center) - s * 0.5;
            const vec3d local = transposed_times(r, (p - t) / s);
            const double want_block = s * box_distance(local, half);
            const double scale = s + krs::length(p); // the float coordinates' rounding grows with |p|
            worst_ball = std::max(worst_ball, std::abs(double(placed_ball.distance(vec3f(p))) - want_ball) / scale);
            worst_block = std::max(worst_block, std::abs(double(placed_block.distance(vec3f(p))) - want_block) / scale);
        }
        CAPTURE(trial);
        CHECK(worst_ball <= 2e-6);
        CHECK(worst_block <= 2e-6);
        // A rigid motion after a scale: the factor is s to within the float rows' rounding.
        CHECK(std::abs(double(placed_ball.factor()) - s) <= 1e-6 * s);
    }
}

TEST_CASE("an affine map's placed field never overestimates, is zero on the image surface and 1-Lipschitz")
{
    std::mt19937_64 g(82);
    const krs::sphere ball({0, 0, 0}, 1.0f);
    for (int trial = 0; trial < 6; ++trial) {
        krs::affine_map a;
        for (vec3d& row : a.rows) row = vec3d{uniform(g, -2, 2), uniform(g, -2, 2), uniform(g, -2, 2)};
        a.offset = {uniform(g, -3, 3), uniform(g, -3, 3), uniform(g, -3, 3)};
        // Draws whose condition number the placement refuses are skipped.
        std::optional<krs::placed<krs::sphere>> f;
        try {
            f.emplace(ball, a);
        } catch (const krs::invalid_parameter&) {
            continue;
        }
        // The spectral norm against the largest stretch over 2e5 random directions (a lower bound
        // of it that approaches it): the factor 1/|A^-1| is at most the smallest stretch.
        double smallest_stretch = INFINITY;
        std::array<vec3d, 3> m{};
        {
            const vec3d c0 = cross(a.rows[1], a.rows[2]), c1 = cross(a.rows[2], a.rows[0]), c2 = cross(a.rows[0], a.rows[1]);
            const double det = dot(a.rows[0], c0);
            m = {vec3d{c0.x, c1.x, c2.x} / det, vec3d{c0.y, c1.y, c2.y} / det, vec3d{c0.z, c1.z, c2.z} / det};
        }
        double largest_inverse_stretch = 0;
        for (int i = 0; i < 200000; ++i) {
            const vec3d u = krs_test::random_direction(g);
            smallest_stretch = std::min(smallest_stretch, krs::length(a.linear(u)));
            largest_inverse_stretch = std::max(largest_inverse_stretch, krs::length(times(m, u)));
        }
        CAPTURE(trial);
        CHECK(double(f->factor()) <= 1.0 / largest_inverse_stretch);
        CHECK(double(f->factor()) >= 0.999 / largest_inverse_stretch); // not needlessly small
        CHECK(double(f->factor()) <= smallest_stretch * (1 + 1e-9));

        // The image surface (an ellipsoid) sampled densely: A u + t for unit u.
        std::vector<vec3d> surface(40000);
        for (vec3d& s : surface) s = a.apply(krs_test::random_direction(g));
        double worst_on_surface = 0, worst_over = -INFINITY, worst_slope = 0;
        for (int i = 0; i < 400; ++i) worst_on_surface = std::max(worst_on_surface, std::abs(double(f->distance(vec3f(surface[std::size_t(i)])))));
        const krs::bounding_sphere bound = f->bound();
        const krs::bounding_box box = f->bound_box();
        for (int i = 0; i < 2000; ++i) {
            const vec3d p = a.offset + vec3d{uniform(g, -5, 5), uniform(g, -5, 5), uniform(g, -5, 5)};
            double sampled = INFINITY;
            for (const vec3d& s : surface) sampled = std::min(sampled, krs::length(p - s));
            const double d = f->distance(vec3f(p));
            // The sampled distance is at least the true one: d <= true <= sampled.
            if (d > 0) worst_over = std::max(worst_over, d - sampled);
            if (d < 0) {
                CHECK(krs::length(vec3d(p) - vec3d(bound.center)) <= double(bound.radius));
                CHECK((p.x >= box.lo.x && p.x <= box.hi.x && p.y >= box.lo.y && p.y <= box.hi.y && p.z >= box.lo.z &&
                       p.z <= box.hi.z));
            }
            const vec3f x(p), y(p + krs_test::random_direction(g) * uniform(g, 1e-3, 5e-2));
            worst_slope = std::max(worst_slope, (std::abs(double(f->distance(x)) - double(f->distance(y))) - 4e-7 * (1 + krs::length(p))) /
                                                    krs::length(vec3d(x) - vec3d(y)));
        }
        std::printf("affine trial %d: factor %.6g (1/|A^-1| sampled %.6g), |d| on surface %.3g, d - sampled <= %.3g, "
                    "slope <= %.6f\n",
                    trial, double(f->factor()), 1.0 / largest_inverse_stretch, worst_on_surface, worst_over, worst_slope);
        CHECK(worst_on_surface <= 1e-5);
        CHECK(worst_over <= 1e-5);
        CHECK(worst_slope <= 1.0 + 1e-4);
    }
}

TEST_CASE("placed fields in packets and in double equal the scalar float path")
{
    std::mt19937_64 g(83);
    const auto f = krs::placed(krs::smooth_union(krs::sphere({0, 0, 0}, 0.6f), krs::box({0.5f, 0, 0}, {0.3f, 0.3f, 0.3f})),
                               krs::affine_map{{vec3d{1.2, 0.3, 0}, vec3d{-0.1, 0.8, 0.2}, vec3d{0, 0.4, 1.5}}, {1, 2, 3}});
    krs_test::scalar_agreement agree;
    for (int k = 0; k < 256; ++k) agree.add(f, krs_test::random_packet(g, {-1, 0, 1}, {3, 4, 5}));
    CHECK(agree.equal == agree.lanes); // the same + - * per lane (-ffp-contract=off)
    CHECK(agree.worst_double <= 1e-6);
}

TEST_CASE("placements are refused a scale of 0, a singular or ill-conditioned map and non-finite values")
{
    const krs::sphere ball({0, 0, 0}, 1.0f);
    const float nan = std::numeric_limits<float>::quiet_NaN(), inf = std::numeric_limits<float>::infinity();
    for (const float s : {0.0f, -1.0f, nan, inf}) {
        CAPTURE(s);
        krs_test::rejects([&] { (void)krs::scaled(ball, s); }, "scaled.scale");
    }
    krs_test::rejects([&] { (void)krs::placed(ball, krs::affine_map::scaling(0.0)); }, "placement.linear");
    krs_test::rejects([&] { (void)krs::placed(ball, krs::affine_map{{vec3d{1, 2, 3}, vec3d{2, 4, 6}, vec3d{0, 0, 1}}, {}}); },
                      "placement.linear");
    // Condition number 1e7: one axis squashed ten-millionfold.
    krs_test::rejects([&] { (void)krs::placed(ball, krs::affine_map{{vec3d{1, 0, 0}, vec3d{0, 1, 0}, vec3d{0, 0, 1e-7}}, {}}); },
                      "placement.linear");
    krs_test::rejects([&] { (void)krs::placed(ball, krs::affine_map{{vec3d{1, 0, double(nan)}, vec3d{0, 1, 0}, vec3d{0, 0, 1}}, {}}); },
                      "placement.linear");
    krs_test::rejects([&] { (void)krs::translated(ball, {0, inf, 0}); }, "translated.offset");
    krs_test::rejects([&] { (void)krs::rotated(ball, {0, 0, 0}, 1.0f); }, "rotated.axis");
    krs_test::rejects([&] { (void)krs::rotated(ball, {0, 1, 0}, nan); }, "rotated.radians");
    // A condition number of 1e5 is taken, and so is a reflection (det < 0).
    CHECK_NOTHROW((void)krs::placed(ball, krs::affine_map{{vec3d{1, 0, 0}, vec3d{0, 1, 0}, vec3d{0, 0, 1e-5}}, {}}));
    CHECK(krs::placed(ball, krs::affine_map{{vec3d{-1, 0, 0}, vec3d{0, 1, 0}, vec3d{0, 0, 1}}, {}}).factor() == 1.0f);
}

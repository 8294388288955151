// Bounding boxes (issue 23, item 2): each kernel's box holds its solid and is tight where exact,
// and a sequence's box holds every instance of its expansion and is never larger than the box
// its kernels' bounding spheres gave. References: the solids' extreme points computed from the
// kernels' construction parameters (support/swept_samples.hpp) and the expansion's isometries.

#include "krs/expansion.hpp"
#include "krs/kernels/kernels.hpp"
#include "krs/sequence.hpp"
#include "krs/trace/box_clip.hpp"
#include "support/random.hpp"
#include "support/swept_samples.hpp"

#include <doctest/doctest.h>

#include <algorithm>
#include <cmath>
#include <random>
#include <variant>
#include <vector>

namespace {

using krs::vec3d;
using krs::vec3f;

vec3f to_f(const vec3d& v) { return vec3f(v); }

struct extent {
    vec3d lo{1e300, 1e300, 1e300}, hi{-1e300, -1e300, -1e300};
    void add(const vec3d& p)
    {
        lo = {std::min(lo.x, p.x), std::min(lo.y, p.y), std::min(lo.z, p.z)};
        hi = {std::max(hi.x, p.x), std::max(hi.y, p.y), std::max(hi.z, p.z)};
    }
};

bool inside(const krs::bounding_box& b, const vec3d& p)
{
    return p.x >= b.lo.x && p.y >= b.lo.y && p.z >= b.lo.z && p.x <= b.hi.x && p.y <= b.hi.y && p.z <= b.hi.z;
}

// The largest amount by which the box exceeds the extent on any side.
double excess(const krs::bounding_box& b, const extent& e)
{
    return std::max({e.lo.x - b.lo.x, e.lo.y - b.lo.y, e.lo.z - b.lo.z, b.hi.x - e.hi.x, b.hi.y - e.hi.y,
                     b.hi.z - e.hi.z});
}

bool within(const krs::bounding_box& inner, const krs::bounding_box& outer)
{
    return inner.lo.x >= outer.lo.x && inner.lo.y >= outer.lo.y && inner.lo.z >= outer.lo.z &&
           inner.hi.x <= outer.hi.x && inner.hi.y <= outer.hi.y && inner.hi.z <= outer.hi.z;
}

// Random kernels of every bounded kind, at most `reach` from the origin and of size about 1.
struct kernel_source {
    std::mt19937_64 g;
    explicit kernel_source(unsigned seed) : g(seed) {}
    double uniform(double lo, double hi) { return krs_test::uniform(g, lo, hi); }
    vec3f point(double reach) { return to_f(krs_test::in_ball(g, reach)); }
    vec3f direction() { return to_f(krs_test::random_direction(g)); }

    krs::sphere sphere(double reach) { return {point(reach), float(uniform(0, 0.6))}; }
    krs::capsule capsule(double reach)
    {
        const vec3f a = point(reach);
        return {a, to_f(vec3d(a) + krs_test::in_ball(g, 1.5)), float(uniform(0, 0.4))};
    }
    krs::torus torus(double reach)
    {
        // Sometimes along an axis, where the exact box is flat on that axis.
        const vec3f axis = uniform(0, 1) < 0.25 ? vec3f{0, 0, 1} : direction();
        return {point(reach), axis, float(uniform(0, 1.5)), float(uniform(0, 0.4))};
    }
    krs::torus_capsule torus_capsule(double reach)
    {
        const vec3d s(point(reach));
        const vec3d e = s + krs_test::random_direction(g) * uniform(0.2, 2.0);
        const double pick = uniform(0, 1);
        // Minor arcs, major arcs (control beyond the chord's ends' circle) and straight ones.
        vec3d c;
        if (pick < 0.15) c = s + (e - s) * uniform(0.1, 0.9);
        else c = (s + e) * 0.5 + krs_test::random_direction(g) * (length(e - s) * uniform(0.05, 1.5));
        return {to_f(s), to_f(e), to_f(c), float(uniform(0, 0.3))};
    }
    krs::box box(double reach)
    {
        const vec3f h{float(uniform(0, 1)), float(uniform(0, 1)), float(uniform(0, 1))};
        if (uniform(0, 1) < 0.3) return {point(reach), h};
        const vec3d x = krs_test::random_direction(g);
        const vec3d y = normalize(cross(x, krs_test::random_direction(g)));
        return {point(reach), h, to_f(x), to_f(y), to_f(cross(x, y))};
    }
};

template <class K>
void check_kernel_box(const K& k, const char* kind)
{
    // 4000 samples per circle: a sag of at most rho (1 - cos(pi / 4000)) = 3.1e-7 rho.
    const std::vector<vec3d> points = krs_test::reference_points(k, 4000);
    const krs::bounding_box box = k.bound_box();
    const krs::bounding_box sphere_box = krs::box_around(k.bound());
    extent e;
    int outside = 0;
    for (const vec3d& p : points) {
        outside += !inside(box, p);
        e.add(p);
    }
    // The samples are points of the solid as the kernel's own distance sees it (the reference is
    // the same solid), to float precision: a spine point plus r e_i is within r of the spine.
    double worst_outside = -1e300;
    for (const vec3d& p : points) worst_outside = std::max(worst_outside, k.distance(p));
    const double size = std::max({e.hi.x - e.lo.x, e.hi.y - e.lo.y, e.hi.z - e.lo.z, 1e-3});
    INFO(kind);
    CHECK(outside == 0);
    CHECK(worst_outside <= 1e-5 * (size + 1));
    // Tight: beyond the samples' extent by at most the sag plus the pad (a relative 1e-6) and a
    // float ulp of the coordinates.
    const double scale = std::max({std::abs(e.lo.x), std::abs(e.lo.y), std::abs(e.lo.z), std::abs(e.hi.x),
                                   std::abs(e.hi.y), std::abs(e.hi.z), 1.0});
    CHECK(excess(box, e) <= 2e-6 * size + 3e-7 * scale);
    CHECK(within(box, sphere_box));
}

} // namespace

TEST_CASE("kernel boxes hold their solid's extreme points and are tight")
{
    kernel_source r(2323);
    for (int trial = 0; trial < 60; ++trial) {
        INFO("trial " << trial);
        check_kernel_box(r.sphere(3), "sphere");
        check_kernel_box(r.capsule(3), "capsule");
        check_kernel_box(r.torus(3), "torus");
        check_kernel_box(r.torus_capsule(3), "torus_capsule");
        check_kernel_box(r.box(3), "box");
    }
    // The example, worked by hand: a ring of R 1.1, r 0.25 around the unit axis
    // (0.3, 0.5, 0.8) / |.| reaches R sqrt(1 - n_i^2) + r: 1.2983, 1.1994, 0.8979; its sphere's
    // box is 1.35 on every axis.
    const krs::torus ring({0, 0, 0}, {0.3f, 0.5f, 0.8f}, 1.1f, 0.25f);
    const double n2 = 0.09 + 0.25 + 0.64;
    const double expected[3] = {1.1 * std::sqrt(1 - 0.09 / n2) + 0.25, 1.1 * std::sqrt(1 - 0.25 / n2) + 0.25,
                                1.1 * std::sqrt(1 - 0.64 / n2) + 0.25};
    const krs::bounding_box b = ring.bound_box();
    CHECK(b.hi.x == doctest::Approx(expected[0]).epsilon(1e-5));
    CHECK(b.hi.y == doctest::Approx(expected[1]).epsilon(1e-5));
    CHECK(b.hi.z == doctest::Approx(expected[2]).epsilon(1e-5));
    CHECK(b.lo.z == doctest::Approx(-expected[2]).epsilon(1e-5));
    // A three-quarter arc from +x to -y through -x: the quarter it skips is the +x +y one, so it
    // reaches -1 and +1 in x, -1 and +1 in y (at +y it passes 90 degrees), plus the tube radius.
    const krs::torus_capsule arc({1, 0, 0}, {0, -1, 0}, {-1, 0, 0}, 0.1f);
    const krs::bounding_box ab = arc.bound_box();
    CHECK(ab.lo.x == doctest::Approx(-1.1).epsilon(1e-5));
    CHECK(ab.hi.y == doctest::Approx(1.1).epsilon(1e-5));
    CHECK(ab.hi.z == doctest::Approx(0.1).epsilon(1e-4));
    // A quarter arc from +x to +y stays in x, y >= 0: its box starts at -r there.
    const krs::torus_capsule quarter({1, 0, 0}, {0, 1, 0}, {0.70710678f, 0.70710678f, 0}, 0.1f);
    CHECK(quarter.bound_box().lo.x == doctest::Approx(-0.1).epsilon(1e-5));
    CHECK(quarter.bound_box().lo.y == doctest::Approx(-0.1).epsilon(1e-5));
    // A plane has none, and field_box of a kernel is its own box.
    CHECK(!krs::plane({0, 1, 0}, 0).bound_box().is_bounded());
    CHECK(krs::field_box(ring).hi.z == b.hi.z);
}

namespace {

using all_kinds = krs::sequence<krs::sphere, krs::capsule, krs::torus, krs::torus_capsule, krs::box>;
using all_kinds_axis = krs::axis_sequence<krs::sphere, krs::capsule, krs::torus, krs::torus_capsule, krs::box>;

template <class Builder>
void add_random_kernel(Builder& b, kernel_source& r, double reach)
{
    switch (int(r.uniform(0, 5))) {
    case 0: b.kernel(r.sphere(reach)); break;
    case 1: b.kernel(r.capsule(reach)); break;
    case 2: b.kernel(r.torus(reach)); break;
    case 3: b.kernel(r.torus_capsule(reach)); break;
    default: b.kernel(r.box(reach)); break;
    }
}

// Every instance's reference points, placed by the expansion's isometries (in double), lie in the
// sequence's box; returns their extent.
template <class S>
extent check_holds_every_instance(const S& s)
{
    const auto e = krs::expand(s);
    const krs::bounding_box box = s.bound_box();
    REQUIRE(box.is_bounded());
    extent all;
    int outside = 0;
    for (const auto& in : e.instances) {
        const std::vector<vec3d> points =
            std::visit([](const auto& k) { return krs_test::reference_points(k, 200); }, s.kernels()[in.kernel]);
        for (const vec3d& p : points) {
            const vec3d q = in.to_world.apply(p);
            outside += !inside(box, q);
            all.add(q);
        }
    }
    CHECK(outside == 0);
    // Never larger than the boxes of the kernels' bounding spheres through the same mirrors, nor
    // than the sequence's bounding sphere's box.
    const krs::bounding_box spheres =
        krs::box_through_mirrors(s, [](const auto& k) { return krs::box_around(k.bound()); });
    CHECK(within(box, spheres));
    CHECK(within(box, krs::box_around(s.bound())));
    return all;
}

} // namespace

TEST_CASE("sequence boxes hold every instance of the expansion, within the sphere-derived box")
{
    kernel_source r(4242);
    for (int trial = 0; trial < 40; ++trial) {
        INFO("trial " << trial);
        const int levels = 1 + int(r.uniform(0, 6));
        // General mirrors: random normals, through random points near the scene.
        all_kinds::builder b;
        add_random_kernel(b, r, 2);
        add_random_kernel(b, r, 2);
        for (int i = 0; i < levels; ++i) {
            b.mirror(krs::mirror::through(r.point(3), r.direction()));
            if (r.uniform(0, 1) < 0.4) add_random_kernel(b, r, 3);
        }
        check_holds_every_instance(b.build());

        // Axis mirrors: the box through the mirrors is then the exact box of the instances, up to
        // the rounding margins (a relative 1e-6 of the coordinates) and the samples' sag.
        all_kinds_axis::builder ab;
        add_random_kernel(ab, r, 2);
        add_random_kernel(ab, r, 2);
        for (int i = 0; i < levels; ++i) {
            ab.mirror(krs::axis_mirror(int(r.uniform(0, 3)), float(r.uniform(-3, 3)), r.uniform(0, 1) < 0.5));
            if (r.uniform(0, 1) < 0.4) add_random_kernel(ab, r, 3);
        }
        const all_kinds_axis s = ab.build();
        const extent e = check_holds_every_instance(s);
        const double scale = std::max({std::abs(e.lo.x), std::abs(e.lo.y), std::abs(e.lo.z), std::abs(e.hi.x),
                                       std::abs(e.hi.y), std::abs(e.hi.z), 1.0});
        // 200 samples per circle: a sag of at most rho (1 - cos(pi / 200)) = 1.3e-4 rho (rho <= 1.5
        // for rings, a few units for the widest arcs).
        CHECK(excess(s.bound_box(), e) <= 2e-3 + 3e-6 * scale);
    }
}

TEST_CASE("a sequence's box is flat where its kernels are: an upright ring grid")
{
    // bench_embree_peer's grid: a ring standing in the xy plane and a ball, copied 2^6 times by
    // mirrors of normal x and z. The rings' box is 0.4 deep in z where their spheres' is 2.4, so
    // the grid's box ends 0.35 (the ball) past the outer ring centers in z, not 1.2.
    krs::axis_sequence<krs::torus, krs::sphere>::builder b;
    b.kernel(krs::torus({0, 0, 0}, {0, 0, 1}, 1.0f, 0.2f));
    b.kernel(krs::sphere({0, 0, 0}, 0.35f));
    double reach[2] = {0, 0};
    for (int i = 0; i < 6; ++i) {
        const int axis = i % 2 == 0 ? 0 : 2;
        double& d = reach[i % 2];
        b.mirror(krs::axis_mirror(axis, float(d + 1.5), true));
        d = 2 * d + 3;
    }
    const auto s = b.build();
    const krs::bounding_box box = s.bound_box();
    CHECK(box.lo.z == doctest::Approx(-0.35).epsilon(1e-4));
    CHECK(box.hi.z == doctest::Approx(reach[1] + 0.35).epsilon(1e-4));
    CHECK(box.lo.x == doctest::Approx(-1.2).epsilon(1e-4));
    CHECK(box.hi.y == doctest::Approx(1.2).epsilon(1e-4));
    const krs::bounding_box spheres =
        krs::box_through_mirrors(s, [](const auto& k) { return krs::box_around(k.bound()); });
    CHECK(spheres.lo.z == doctest::Approx(-1.2).epsilon(1e-4));
    check_holds_every_instance(s);
}

// The secondary bounds of the hypertree raymarcher (paper section 8.2, march_options::bounds_by):
// each bound against a brute-force check over every stored voxel's cell, each bound's pixels
// against the box-only march, the paper's sphere rule against points pushed through the maps, and
// a bound made too small caught by both checks (so they can fail).

#include "hypertree/hypertree.hpp"
#include "hypertree/presets.hpp"
#include "hypertree/render/glsl.hpp"
#include "hypertree/render/render.hpp"

#include "support/random.hpp"

#include <doctest/doctest.h>

#include <algorithm>
#include <cmath>
#include <random>

using namespace hypertree;

namespace {

ifs<> small_tree(ifs<> t, std::uint64_t iterations)
{
    t.iterations = iterations;
    return t;
}
// The paper grows its secondary spheres by the largest perturbation offset (8.2).
ifs<> perturbed(ifs<> t)
{
    t.perturb.amplitude = {0.03, 0.02, 0.03};
    t.perturb.frequency = 6;
    return t;
}

double max_difference(const image& a, const image& b)
{
    REQUIRE(a.rgb.size() == b.rgb.size());
    double worst = 0;
    for (std::size_t i = 0; i < a.rgb.size(); ++i) {
        REQUIRE(std::isfinite(a.rgb[i]));
        REQUIRE(std::isfinite(b.rgb[i]));
        worst = std::max(worst, double(std::abs(a.rgb[i] - b.rgb[i])));
    }
    return worst;
}

// The bound's volumes as the shape states them, in double (not through bound_test).
struct reference_bound {
    std::vector<krs::bounding_sphere> spheres;
    std::vector<world_box> boxes;
    static reference_bound of(const tree_shape& shape, bound_method by)
    {
        reference_bound b;
        if (by == bound_method::spheres) b.spheres = shape.spheres;
        if (by == bound_method::paper_spheres) b.spheres = shape.paper_spheres, b.boxes = shape.trunk_box;
        if (by == bound_method::part_boxes) b.boxes = shape.part_boxes;
        return b;
    }
    // A cell lies in a sphere when its 8 corners do (the ball is convex), in a box when its two
    // extreme corners do; it is covered when one volume holds it whole.
    bool covers(const krs::vec3d& lo, const krs::vec3d& hi) const
    {
        for (const auto& s : spheres) {
            bool all = true;
            for (int c = 0; c < 8 && all; ++c) {
                const krs::vec3d p{c & 1 ? hi.x : lo.x, c & 2 ? hi.y : lo.y, c & 4 ? hi.z : lo.z};
                all = krs::length(p - krs::vec3d(s.center)) <= double(s.radius);
            }
            if (all) return true;
        }
        for (const auto& b : boxes)
            if (lo.x >= b.lo.x && lo.y >= b.lo.y && lo.z >= b.lo.z && hi.x <= b.hi.x && hi.y <= b.hi.y && hi.z <= b.hi.z) return true;
        return false;
    }
};

// The stored voxels whose cells no volume of the bound holds whole (brute force over the store).
template <voxel_store S>
std::size_t cells_outside(const S& store, const tree_shape& shape, bound_method by)
{
    const reference_bound bound = reference_bound::of(shape, by);
    const hypervolume& v = store.volume();
    std::size_t outside = 0;
    store.for_each([&](voxel_index i, const voxel&) {
        // (Half a side less 1e-9 of it: the center and the boxes' faces are computed apart, an
        // ulp from each other.)
        const krs::vec3d c = v.voxel_center(i), h = v.voxel_size() * (0.5 - 1e-9);
        outside += !bound.covers(c - h, c + h);
    });
    return outside;
}

struct scene {
    ifs<> definition;
    index_list_store store;
    tree_shape shape;
    scene(ifs<> t, std::uint64_t seed) : definition(std::move(t)), store(build_tree<index_list_store>(definition, seed))
    {
        shape = tree_shape::of(build_tree<partitioned_store>(definition, seed));
        shape.set_paper_spheres_of(drawn_ifs<runtime_pipeline>(definition, seed));
    }
};

constexpr bound_method all_bounds[] = {bound_method::spheres, bound_method::paper_spheres, bound_method::part_boxes};

} // namespace

TEST_CASE("hypertree bounds: every secondary bound holds every stored voxel's cell, and its float test agrees")
{
    // Trees D (shears, level-dependent sizes), A (level-dependent sizes and tilts, dummies), C
    // (line generators, random parameters) and D perturbed, small.
    for (const ifs<>& t : {small_tree(presets::tree_d(48), 40000), small_tree(presets::tree_a(48), 40000), small_tree(presets::tree_c(48), 20000),
                           perturbed(small_tree(presets::tree_d(48), 40000))}) {
        const scene s(t, 3);
        INFO("tree " << t.name);
        REQUIRE(s.store.nonempty_count() > 500);
        REQUIRE(s.shape.paper_spheres.size() >= 7);
        for (const bound_method by : all_bounds) {
            INFO("bound " << int(by));
            CHECK(cells_outside(s.store, s.shape, by) == 0);
            // The marcher's float test accepts points near every corner of every cell.
            const bound_test test = bound_test::of(s.shape, by);
            const hypervolume& v = s.store.volume();
            std::size_t rejected = 0;
            s.store.for_each([&](voxel_index i, const voxel&) {
                const krs::vec3d c = v.voxel_center(i), h = v.voxel_size() * 0.499;
                for (int k = 0; k < 8; ++k)
                    rejected += !test.holds(krs::vec3f(krs::vec3d{c.x + (k & 1 ? h.x : -h.x), c.y + (k & 2 ? h.y : -h.y), c.z + (k & 4 ? h.z : -h.z)}));
            });
            CHECK(rejected == 0);
        }
    }
}

TEST_CASE("hypertree bounds: every secondary bound gives the box-only march's pixels, with fewer lookups")
{
    // Trees D (shears) and A (dummies: transformations with no part of their own), with shadow rays
    // (which test the bound too) and with the light sweep.
    const krs::pinhole_camera camera({0.2f, 0.7f, -2.3f}, {0, 0.6f, 0}, {0, 1, 0}, 45, 64, 56);
    for (const ifs<>& t : {small_tree(presets::tree_d(48), 40000), small_tree(presets::tree_a(48), 40000)}) {
        const scene s(t, 3);
        for (const auto shadows : {march_options::shadow_method::rays, march_options::shadow_method::sweep}) {
            march_options box;
            box.shadow_by = shadows;
            const volume_marcher reference(s.store, s.shape, depth_colors::tree(3, 6), box);
            const image packets = render<krs::packet_f>(reference, camera), scalar = render<float>(reference, camera);
            for (const bound_method by : all_bounds) {
                INFO("tree " << t.name << ", shadows " << int(shadows) << ", bound " << int(by));
                march_options o = box;
                o.bounds_by = by;
                const volume_marcher m(s.store, s.shape, depth_colors::tree(3, 6), o);
                const image p = render<krs::packet_f>(m, camera), f = render<float>(m, camera);
                CHECK(max_difference(p, packets) == 0.0);
                CHECK(max_difference(f, scalar) == 0.0);
                CHECK(p.lookups < packets.lookups);
            }
        }
    }
}

TEST_CASE("hypertree bounds: a bound made too small leaves cells outside and changes pixels")
{
    // The negative control of the two checks above: shrink each bound and both must see it.
    const scene s(small_tree(presets::tree_d(48), 40000), 3);
    tree_shape small = s.shape;
    for (auto& sphere : small.spheres) sphere.radius *= 0.75f;
    for (auto& sphere : small.paper_spheres) sphere.radius *= 0.6f;
    for (auto& b : small.part_boxes) b.hi = b.hi - (b.hi - b.lo) * 0.25;
    small.trunk_box.clear();
    const krs::pinhole_camera camera({0.2f, 0.7f, -2.3f}, {0, 0.6f, 0}, {0, 1, 0}, 45, 64, 56);
    const volume_marcher reference(s.store, s.shape, depth_colors::tree(3, 6), march_options{});
    const image box_only = render<krs::packet_f>(reference, camera);
    for (const bound_method by : all_bounds) {
        INFO("bound " << int(by));
        CHECK(cells_outside(s.store, small, by) > 20);
        march_options o;
        o.bounds_by = by;
        const volume_marcher m(s.store, small, depth_colors::tree(3, 6), o);
        CHECK(max_difference(render<krs::packet_f>(m, camera), box_only) > 0.05);
    }
}

TEST_CASE("hypertree bounds: the paper's rule (1 + dmax / r)^2 holds a sphere's image under a sheared chain")
{
    // Closed form: scale 0.5 then a shear of displacements (0.1, 0.05) and a translation. The
    // sphere (c, r) becomes radius r1 (1 + dmax / r1)^2 with r1 = 0.5 r and dmax = |(0.1, 0.05)|.
    const runtime_pipeline p({scale(0.5), shear(1, 0.1, 0.05, 2, 0.4), translate(0.1, 0.3, -0.2)});
    const auto chain = p.chain_at(1);
    const krs::vec3d c{0.05, 0.3, -0.02};
    const double r = 0.4;
    const auto [center, radius] = tree_shape::paper_sphere_through(chain, c, r);
    const double r1 = 0.5 * r, dmax = std::hypot(0.1, 0.05);
    CHECK(radius == doctest::Approx(r1 * (1 + dmax / r1) * (1 + dmax / r1)).epsilon(1e-12));
    CHECK(krs::length(center - chain(c)) < 1e-12);
    // Dense sampling: points of the ball (surface and inside) map into the derived sphere; the
    // farthest comes within r1 + dmax of the mapped center, which the rule's r1 + 2 dmax + dmax^2/r1 exceeds.
    std::mt19937_64 random(7);
    double farthest = 0;
    for (int i = 0; i < 200000; ++i) {
        const krs::vec3d d = i % 2 ? krs_test::random_direction(random) * r : krs_test::in_ball(random, r);
        farthest = std::max(farthest, krs::length(chain(c + d) - center));
    }
    CHECK(farthest <= radius);
    CHECK(farthest <= r1 + dmax + 1e-12);
    CHECK(farthest > r1); // the shear does move points apart
}

TEST_CASE("hypertree bounds: the paper's spheres of a similarity-only IFS are the closed form, margins included")
{
    // Where the rule is tight: every first-level chain a similarity (scale s, rotation,
    // translation), so the crown (c, R) maps onto exactly the ball (T(c), s R). With generation
    // noise of amplitude a, the unperturbed orbit lies within |a| of the perturbed voxels the crown
    // is fitted to, and the recorded points move |a| again: radius s (R + |a|) + |a| + the cell
    // diagonal. Dropping either |a| (or the cell diagonal) moves the radius by >= s |a| = 0.01.
    ifs<> t;
    const double scales[] = {0.5, 0.4, 0.3};
    for (int k = 0; k < 3; ++k)
        t.transforms.push_back({runtime_pipeline({scale(scales[k]), rotate({0, 0, 1}, 0.6), rotate({0, 1, 0}, 2.1 * k), translate(0, 0.4 + 0.15 * k, 0)}),
                                1.0});
    t.tree_depth = 5;
    t.branch_depth = 1;
    t.iterations = 20000;
    t.volume = hypervolume({-1, -0.05, -1}, {2, 2, 2}, resolution::cube(48));
    t.perturb.amplitude = {0.02, 0.03, 0.02};
    t.perturb.frequency = 5;
    const drawn_ifs<runtime_pipeline> drawn(t, 3);
    tree_shape shape = tree_shape::of(build_tree<partitioned_store>(t, 3));
    shape.set_paper_spheres_of(drawn);
    REQUIRE(shape.paper_spheres.size() == 3);
    const double a = krs::length(t.perturb.amplitude), diagonal = krs::length(t.volume.voxel_size()), R = shape.crown.radius;
    for (int k = 0; k < 3; ++k) {
        INFO("transformation " << k);
        const double want = scales[k] * (R + a) + a + diagonal;
        CHECK(double(shape.paper_spheres[std::size_t(k)].radius) == doctest::Approx(want).epsilon(1e-6));
        CHECK(krs::length(krs::vec3d(shape.paper_spheres[std::size_t(k)].center) - drawn.chain_of(std::size_t(k), 1)(krs::vec3d(shape.crown.center))) < 1e-6);
    }
}

TEST_CASE("hypertree bounds: the float sphere test accepts a point the double sphere holds")
{
    // radius^2 rounded to float may fall below the double r^2, and the float sum of squares may
    // round up: both would reject a point just inside. Points at 1 - 2^-24 of the radius (within
    // float rounding of the surface), in many directions, on spheres of awkward radii.
    std::mt19937_64 random(11);
    std::size_t rejected = 0, tried = 0;
    for (int n = 0; n < 200; ++n) {
        tree_shape shape;
        const krs::vec3d c{0.3 + 0.01 * n, 0.7, -0.2};
        shape.spheres.push_back(krs::bound_around(c, 0.1 + 0.0037 * n));
        const bound_test test = bound_test::of(shape, bound_method::spheres);
        const krs::bounding_sphere s = shape.spheres.front();
        for (int i = 0; i < 200; ++i) {
            const krs::vec3d d = krs_test::random_direction(random);
            const krs::vec3f p(krs::vec3d(s.center) + d * (double(s.radius) * (1 - std::ldexp(1.0, -23))));
            // Only points the double sphere holds count (the float point is a rounding away).
            if (krs::length(krs::vec3d(p) - krs::vec3d(s.center)) > double(s.radius)) continue;
            ++tried;
            rejected += !test.holds(p);
        }
    }
    REQUIRE(tried > 20000);
    CHECK(rejected == 0);
}

TEST_CASE("hypertree bounds: bad choices are refused, naming march_options.bounds_by")
{
    const scene s(small_tree(presets::tree_d(32), 5000), 3);
    tree_shape unset = tree_shape::of(s.store);
    march_options o;
    o.bounds_by = bound_method::paper_spheres;
    CHECK_THROWS_WITH_AS(volume_marcher(s.store, unset, depth_colors::tree(3, 6), o), doctest::Contains("march_options.bounds_by"),
                         krs::invalid_parameter);
    o.bounds_by = bound_method(7);
    CHECK_THROWS_WITH_AS(o.validate(), doctest::Contains("march_options.bounds_by"), krs::invalid_parameter);
    for (const bound_method by : {bound_method::paper_spheres, bound_method::part_boxes}) {
        o.bounds_by = by;
        CHECK_THROWS_WITH_AS(hypertree_glsl(s.store, s.shape, depth_colors::tree(3, 6), o), doctest::Contains("march_options.bounds_by"),
                             krs::invalid_parameter);
    }
    o.bounds_by = bound_method::spheres;
    CHECK_NOTHROW(hypertree_glsl(s.store, s.shape, depth_colors::tree(3, 6), o));
}

// Scene builders (paper section 7): parameter validation, determinism by seed, instance counts,
// and each scene's geometry against an independent reference.

#include "krs/compose/zones.hpp"
#include "krs/kernels/box.hpp"
#include "krs/model/coral.hpp"
#include "krs/model/forest.hpp"
#include "krs/model/grass.hpp"
#include "krs/model/terrain.hpp"
#include "krs/trace/sphere_trace.hpp"

#include <doctest/doctest.h>

#include <cmath>
#include <functional>
#include <random>

namespace {

using krs::vec3d;
using krs::vec3f;

double uniform(std::mt19937_64& g, double lo, double hi) { return lo + (hi - lo) * double(g() >> 11) * 0x1.0p-53; }

// Runs `build` and requires an invalid_parameter naming `name`.
void require_rejects(const std::function<void()>& build, const std::string& name)
{
    try {
        build();
    } catch (const krs::invalid_parameter& e) {
        CHECK(e.parameter() == name);
        return;
    }
    FAIL("no krs::invalid_parameter for " << name);
}

// Two fields agree bit for bit on random points (same build) or not (different seeds).
template <class A, class B>
bool same_field(const A& a, const B& b, double extent)
{
    std::mt19937_64 g(99);
    for (int k = 0; k < 500; ++k) {
        const vec3f p{float(uniform(g, -extent, extent)), float(uniform(g, -extent, extent)),
                      float(uniform(g, -extent, extent))};
        if (a.distance(p) != b.distance(p)) return false;
    }
    return true;
}

} // namespace

TEST_CASE("forest: trees are reflected copies and never clipped by the forest mirrors")
{
    krs::model::forest_parameters f;
    f.tree.levels = 5;
    f.tree.leaves_per_twig = 2;
    f.doublings = 4;
    f.ground_height.reset();
    const krs::model::forest forest = krs::model::build_forest(f);
    CHECK(forest.tree_count == 16);
    CHECK(forest.sequence.instance_count() == doctest::Approx(forest.tree_instances * 16));
    // Reference: the tree's own field at x carried back through every combination of the forest
    // mirrors (top first). If the mirrors kept the trees separated, Algorithm 1 on the forest
    // equals this minimum over copies.
    krs::model::tree_style style = f.tree;
    style.ground_height.reset();
    const auto tree = krs::model::build_tree(krs::model::grow_tree(style));
    const std::size_t tree_mirrors = tree.mirror_count();
    const auto& mirrors = forest.sequence.mirrors();
    std::mt19937_64 g(1);
    const vec3d c(forest.bound.center);
    const double r = forest.bound.radius;
    for (int k = 0; k < 2000; ++k) {
        const vec3d x{uniform(g, c.x - r, c.x + r), uniform(g, -0.5, 2 * forest.crown.radius + 1),
                      uniform(g, c.z - r, c.z + r)};
        double reference = INFINITY;
        for (unsigned mask = 0; mask < 16; ++mask) {
            vec3d p = x;
            for (std::size_t j = mirrors.size(); j-- > tree_mirrors;)
                if ((mask >> (j - tree_mirrors)) & 1u) p = mirrors[j].reflect(p);
            reference = std::min(reference, tree.distance(p));
        }
        REQUIRE(forest.sequence.distance(x) == doctest::Approx(reference).epsilon(1e-9));
    }
    // Each tree's bound: an empty zone over one of them leaves only the ground under it.
    REQUIRE(forest.trees.size() == 16);
    auto grounded = f;
    grounded.ground_height = 0.0f;
    const krs::model::forest with_ground = krs::model::build_forest(grounded);
    for (std::size_t i = 0; i < with_ground.trees.size(); ++i) {
        const krs::bounding_sphere zone = with_ground.trees[i];
        const krs::with_empty_zones<krs::model::tree_sequence> cleared(with_ground.sequence, {zone});
        krs::trace_options o;
        o.pixel_footprint = 0;
        o.threshold_floor = 1e-5f;
        // Straight down through the zone, next to where the trunk stood. The zone reaches below
        // the ground (its radius exceeds its center's height) and removes the ground's solid too,
        // so the first surface is the cut face where the zone's sphere leaves the ground's solid.
        const krs::ray<double> down{vec3d(zone.center) + vec3d{0.3, 0, -0.2}, {0, -1, 0}};
        const krs::hit<double> h = krs::sphere_trace(cleared, down, o);
        REQUIRE(h.found);
        REQUIRE(double(zone.radius) > double(zone.center.y));
        const double exit = std::sqrt(double(zone.radius) * zone.radius - 0.13);
        CHECK(h.t == doctest::Approx(exit).epsilon(1e-4));
    }
    // Determinism by seed.
    CHECK(same_field(forest.sequence, krs::model::build_forest(f).sequence, r));
    krs::model::forest_parameters other = f;
    other.seed = 2;
    CHECK_FALSE(same_field(forest.sequence, krs::model::build_forest(other).sequence, r));
    // Validation.
    require_rejects([&] { auto p = f; p.doublings = 21; krs::model::build_forest(p); }, "forest.doublings");
    require_rejects([&] { auto p = f; p.spacing = -0.1f; krs::model::build_forest(p); }, "forest.spacing");
    require_rejects([&] { auto p = f; p.angle_jitter_degrees = 91; krs::model::build_forest(p); },
                    "forest.angle_jitter_degrees");
    require_rejects([&] { auto p = f; p.tree.spread_degrees = 0; krs::model::build_forest(p); },
                    "tree_style.spread_degrees");
    require_rejects([&] { auto p = f; p.tree.levels = 50; p.doublings = 20; krs::model::build_forest(p); },
                    "forest.doublings");
}

TEST_CASE("grass: counts and validation and determinism")
{
    krs::model::grass_parameters p;
    p.doublings = 5;
    p.blades_per_clump = 6;
    const krs::model::grass_field grass = krs::model::build_grass(p);
    CHECK(grass.clump_count == 32);
    CHECK(grass.blade_count == 192);
    CHECK(grass.sequence.instance_count() == doctest::Approx(192 + 1)); // blades and the ground
    // Above the blades there is only air; just below the ground there is solid.
    std::mt19937_64 g(2);
    const vec3d c(grass.bound.center);
    for (int k = 0; k < 500; ++k) {
        const vec3d x{uniform(g, c.x - 3, c.x + 3), p.ground_height + 1.5 * p.blade_height, uniform(g, c.z - 3, c.z + 3)};
        REQUIRE(grass.sequence.distance(x) > 0.0);
        REQUIRE(grass.sequence.distance(vec3d{x.x, p.ground_height - 0.01, x.z}) < 0.0);
    }
    CHECK(same_field(grass.sequence, krs::model::build_grass(p).sequence, 2.0));
    auto q = p;
    q.seed = 5;
    CHECK_FALSE(same_field(grass.sequence, krs::model::build_grass(q).sequence, 2.0));
    require_rejects([&] { auto b = p; b.blades_per_clump = 0; krs::model::build_grass(b); }, "grass.blades_per_clump");
    require_rejects([&] { auto b = p; b.blade_width = 0.2f; krs::model::build_grass(b); }, "grass.blade_width");
    require_rejects([&] { auto b = p; b.lean = 2; krs::model::build_grass(b); }, "grass.lean");
    require_rejects([&] { auto b = p; b.doublings = -1; krs::model::build_grass(b); }, "grass.doublings");
}

TEST_CASE("terrain: a height field with one crossing per vertical line")
{
    krs::model::terrain_parameters t;
    t.levels = 20;
    t.size = 10.0f;
    const auto terrain = krs::model::build_terrain(t);
    std::mt19937_64 g(3);
    for (int k = 0; k < 200; ++k) {
        const double x = uniform(g, -8, 8), z = uniform(g, -8, 8);
        int crossings = 0;
        bool previous_solid = true;
        for (double y = -12; y <= 12; y += 0.01) {
            const bool solid = terrain.distance(vec3d{x, y, z}) <= 0;
            if (y > -12 && solid != previous_solid) ++crossings;
            previous_solid = solid;
        }
        REQUIRE(crossings == 1);
        REQUIRE(previous_solid == false);
    }
    // 1-Lipschitz on sampled pairs.
    for (int k = 0; k < 5000; ++k) {
        const vec3d a{uniform(g, -8, 8), uniform(g, -3, 3), uniform(g, -8, 8)};
        const vec3d b = a + vec3d{uniform(g, -0.3, 0.3), uniform(g, -0.3, 0.3), uniform(g, -0.3, 0.3)};
        REQUIRE(std::abs(terrain.distance(a) - terrain.distance(b)) <= krs::length(a - b) + 1e-9);
    }
    CHECK(terrain.mirror_count() == 20);
    CHECK(same_field(terrain, krs::model::build_terrain(t), 8.0));
    auto other = t;
    other.seed = 9;
    CHECK_FALSE(same_field(terrain, krs::model::build_terrain(other), 8.0));
    require_rejects([&] { auto b = t; b.levels = 0; krs::model::build_terrain(b); }, "terrain.levels");
    require_rejects([&] { auto b = t; b.size = 0; krs::model::build_terrain(b); }, "terrain.size");
    require_rejects([&] { auto b = t; b.detail_ratio = 1.5f; krs::model::build_terrain(b); }, "terrain.detail_ratio");
    require_rejects([&] { auto b = t; b.slope = -1; krs::model::build_terrain(b); }, "terrain.slope");
}

TEST_CASE("rock: solid at its center and inside its declared bound")
{
    for (std::uint32_t seed = 1; seed <= 5; ++seed) {
        krs::model::rock_parameters p;
        p.seed = seed;
        p.center = {1, 2, 3};
        const krs::model::rock rock = krs::model::build_rock(p);
        CHECK(rock.sequence.distance(vec3d(p.center)) < 0.0);
        std::mt19937_64 g(seed);
        const vec3d c(rock.bound.center);
        for (int k = 0; k < 3000; ++k) {
            vec3d d{uniform(g, -1, 1), uniform(g, -1, 1), uniform(g, -1, 1)};
            if (krs::length(d) < 1e-3) continue;
            d = krs::normalize(d);
            // Just outside the bound there is no geometry.
            REQUIRE(rock.sequence.distance(c + d * (double(rock.bound.radius) * uniform(g, 1.0001, 3.0))) > 0.0);
        }
        CHECK(same_field(rock.sequence, krs::model::build_rock(p).sequence, 4.0));
    }
    krs::model::rock_parameters p;
    auto q = p;
    q.seed = 2;
    CHECK_FALSE(same_field(krs::model::build_rock(p).sequence, krs::model::build_rock(q).sequence, 2.0));
    require_rejects([&] { auto b = p; b.radius = 0; krs::model::build_rock(b); }, "rock.radius");
    require_rejects([&] { auto b = p; b.facets = 0; krs::model::build_rock(b); }, "rock.facets");
    require_rejects([&] { auto b = p; b.folds = 59; krs::model::build_rock(b); }, "rock.folds");
    require_rejects([&] { auto b = p; b.fold_offset = 0.7f; krs::model::build_rock(b); }, "rock.fold_offset");
}

TEST_CASE("coral: instance count and validation")
{
    krs::model::coral_parameters p;
    p.levels = 8;
    const auto coral = krs::model::build_coral(p);
    // Each level holds a branch and a sphere, and level j (from the tip) appears 2^j times.
    CHECK(coral.instance_count() == doctest::Approx(2.0 * (std::pow(2.0, 8) - 1)));
    CHECK(coral.distance(vec3d{0, 0.05, 0}) < 0.0); // the base is solid
    CHECK(same_field(coral, krs::model::build_coral(p), 3.0));
    auto q = p;
    q.seed = 3;
    CHECK_FALSE(same_field(coral, krs::model::build_coral(q), 3.0));
    require_rejects([&] { auto b = p; b.levels = 0; krs::model::build_coral(b); }, "coral.levels");
    require_rejects([&] { auto b = p; b.taper = 0.2f; krs::model::build_coral(b); }, "coral.taper");
    require_rejects([&] { auto b = p; b.knot = 0.5f; krs::model::build_coral(b); }, "coral.knot");
}

TEST_CASE("sponge: the KRS equals the Menger construction")
{
    krs::model::sponge_parameters p;
    p.levels = 2;
    p.size = 3.0f;
    p.center = {0.5f, -0.25f, 1.0f};
    const krs::model::sponge sponge = krs::model::build_sponge(p);
    CHECK(sponge.cube_count == doctest::Approx(400));
    // Reference: the 20^2 solid cells of the Menger recursion, as boxes.
    std::vector<krs::box> cells;
    std::function<void(vec3d, double, int)> recurse = [&](vec3d c, double size, int level) {
        if (level == 0) {
            const float h = float(0.5 * size);
            cells.emplace_back(vec3f{float(c.x), float(c.y), float(c.z)}, vec3f{h, h, h});
            return;
        }
        const double s = size / 3;
        for (int i = -1; i <= 1; ++i)
            for (int j = -1; j <= 1; ++j)
                for (int k = -1; k <= 1; ++k)
                    if ((i == 0) + (j == 0) + (k == 0) < 2) recurse(c + vec3d{i * s, j * s, k * s}, s, level - 1);
    };
    recurse(vec3d(p.center), p.size, p.levels);
    REQUIRE(cells.size() == 400);
    std::mt19937_64 g(4);
    int inside = 0, outside = 0;
    for (int k = 0; k < 4000; ++k) {
        const vec3d x = vec3d(p.center) + vec3d{uniform(g, -2, 2), uniform(g, -2, 2), uniform(g, -2, 2)};
        double exact = INFINITY;
        for (const krs::box& b : cells) exact = std::min(exact, b.distance(x));
        const double d = sponge.sequence.distance(x);
        // Conservative, and the same solid: exact wherever the distance is to a cell face.
        REQUIRE(d <= exact + 1e-5);
        if (exact > 1e-4) REQUIRE(d > 0.0);
        if (exact < -1e-4) REQUIRE(d < 0.0);
        inside += exact < 0;
        outside += exact > 0;
    }
    CHECK(inside > 200);
    CHECK(outside > 1000);
    require_rejects([&] { auto b = p; b.levels = 10; krs::model::build_sponge(b); }, "sponge.levels");
    require_rejects([&] { auto b = p; b.size = -1; krs::model::build_sponge(b); }, "sponge.size");
}

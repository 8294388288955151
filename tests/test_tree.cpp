// The tree builder (paper section 7.2): structure, fork geometry, and validation.

#include "krs/expansion.hpp"
#include "krs/model/tree.hpp"

#include "support/random.hpp"

#include <doctest/doctest.h>

#include <cmath>
#include <random>

namespace {
using krs::vec3d;
using krs::vec3f;

// A hand-made route: trunk up, then three forks.
krs::model::tree_parameters hand_tree()
{
    krs::model::tree_parameters t;
    t.forks = {{0, 0, 0}, {0, 2, 0}, {0.8f, 3.2f, 0.1f}, {1.0f, 4.0f, 0.7f}, {1.5f, 4.5f, 0.8f}};
    t.controls = {{0.1f, 1, 0}, {0.3f, 2.7f, 0}, {0.8f, 3.6f, 0.45f}, {1.25f, 4.3f, 0.75f}};
    t.widths = {0.15f, 0.1f, 0.07f, 0.05f};
    t.leaves = {krs::sphere({1.55f, 4.6f, 0.7f}, 0.06f), krs::sphere({1.4f, 4.5f, 0.9f}, 0.06f)};
    return t;
}
} // namespace

TEST_CASE("tree: levels, kernels and instance count follow the route")
{
    const auto t = hand_tree();
    const krs::model::tree_sequence s = krs::model::build_tree(t);
    const std::size_t m = t.forks.size() - 1; // branches
    CHECK(s.mirror_count() == m - 1);
    CHECK(s.kernels().size() == m + t.leaves.size());
    // Twig and leaves at level 0 (2^(m-1) copies each), branch j at level m-1-j (2^j copies).
    double expected = double(1 + t.leaves.size()) * std::ldexp(1.0, int(m - 1));
    for (std::size_t j = 0; j + 1 < m; ++j) expected += std::ldexp(1.0, int(j));
    CHECK(s.instance_count() == expected);
    CHECK(double(krs::expand(s).instances.size()) == expected);
}

TEST_CASE("tree: each fork's mirror passes through the fork and both children start there")
{
    const auto t = hand_tree();
    const krs::model::tree_sequence s = krs::model::build_tree(t);
    const std::size_t n = s.mirror_count();
    for (std::size_t j = 1; j + 1 < t.forks.size(); ++j) {
        const krs::mirror& m = s.mirrors()[n - j]; // the mirror at fork j sits at level n - j
        const vec3d fork(t.forks[j]);
        CHECK(std::abs(m.signed_distance(fork)) < 1e-6);
        // The route's child lies on the negative side; its mirror image on the positive side.
        const vec3d child(t.forks[j + 1]);
        CHECK(m.signed_distance(child) < 0);
        CHECK(m.signed_distance(m.reflect(child)) > 0);
    }
    // Every branch of the route and its mirror image at the fork above it are solid: the control
    // point lies on the branch axis (the arc passes through it), so it is inside by the width.
    const auto e = krs::expand(s);
    for (std::size_t j = 0; j + 1 < t.forks.size(); ++j) {
        const vec3d p(t.controls[j]);
        CHECK(e.distance(p) == doctest::Approx(-t.widths[j]).epsilon(1e-5));
        CHECK(s.distance(p) == doctest::Approx(-t.widths[j]).epsilon(1e-5));
        if (j >= 1) {
            const vec3d mirrored = s.mirrors()[n - j].reflect(p);
            CHECK(e.distance(mirrored) == doctest::Approx(-t.widths[j]).epsilon(1e-5));
            CHECK(s.distance(mirrored) == doctest::Approx(-t.widths[j]).epsilon(1e-5));
        }
    }
}

TEST_CASE("tree: the field bounds its geometry (subset of instances, 1-Lipschitz)")
{
    krs::model::tree_style style;
    style.levels = 9;
    const krs::model::tree_parameters params = [&] {
        auto p = krs::model::grow_tree(style);
        p.ground_height.reset();
        return p;
    }();
    const krs::model::tree_sequence s = krs::model::build_tree(params);
    const auto e = krs::expand(s);
    std::mt19937_64 g(4);
    auto u = [&](double lo, double hi) { return krs_test::uniform(g, lo, hi); };
    for (int k = 0; k < 3000; ++k) {
        const vec3d x{u(-4, 4), u(0, 8), u(-4, 4)};
        REQUIRE(s.distance(x) >= e.distance(x) - 1e-5); // float-stored normals: see test_sequence
        const vec3d y = x + vec3d{u(-1, 1), u(-1, 1), u(-1, 1)} * 1e-3;
        REQUIRE(std::abs(s.distance(x) - s.distance(y)) <= krs::length(x - y) * (1 + 1e-9) + 1e-12);
    }
}

TEST_CASE("grow_tree: the default tree has at least 2^16 instances and is deterministic by seed")
{
    krs::model::tree_style style;
    const auto a = krs::model::grow_tree(style);
    const krs::model::tree_sequence s = krs::model::build_tree(a);
    CHECK(s.instance_count() >= 65536.0);
    CHECK(a.forks.size() == std::size_t(style.levels) + 1);
    CHECK(a.leaves.size() == std::size_t(style.leaves_per_twig));
    const auto again = krs::model::grow_tree(style);
    for (std::size_t i = 0; i < a.forks.size(); ++i) {
        CHECK(a.forks[i].x == again.forks[i].x);
        CHECK(a.forks[i].y == again.forks[i].y);
    }
    style.seed = 2;
    const auto other = krs::model::grow_tree(style);
    CHECK(krs::length(vec3d(other.forks.back()) - vec3d(a.forks.back())) > 1e-3);
    // Each fork's default plane holds the parent axis: children spread symmetrically about it.
    for (std::size_t j = 1; j + 1 < a.forks.size(); ++j) {
        const vec3d parent = krs::normalize(vec3d(a.forks[j]) - vec3d(a.forks[j - 1]));
        CHECK(std::abs(krs::dot(vec3d(a.fork_normals[j - 1]), parent)) < 1e-5);
    }
    // The leaves stay clear of the last fork's mirror (nothing of them is clipped), also when they
    // are large or many (radius 0.2 and 8 leaves fanned across the fork plane before).
    for (float leaf_radius : {0.02f, 0.06f, 0.1f, 0.2f, 0.4f})
        for (int leaves : {1, 4, 8, 24})
            for (std::uint32_t seed : {1u, 2u, 3u}) {
                auto big = style;
                big.leaf_radius = leaf_radius, big.leaves_per_twig = leaves, big.seed = seed;
                const auto grown = krs::model::grow_tree(big);
                const krs::model::tree_sequence sequence = krs::model::build_tree(grown);
                const krs::mirror& last = sequence.mirrors().front();
                for (const krs::sphere& leaf : grown.leaves) {
                    INFO("leaf radius ", leaf_radius, ", ", leaves, " leaves, seed ", seed);
                    CHECK(last.signed_distance(vec3d(leaf.center)) < -double(leaf.radius));
                }
            }
}

TEST_CASE("tree: bad parameters are rejected with the parameter's name")
{
    auto t = hand_tree();
    t.controls.pop_back();
    CHECK_THROWS_WITH_AS(krs::model::build_tree(t), doctest::Contains("tree.controls"), krs::invalid_parameter);
    t = hand_tree();
    t.widths[1] = -0.1f;
    CHECK_THROWS_WITH_AS(krs::model::build_tree(t), doctest::Contains("tree.widths[1]"), krs::invalid_parameter);
    t = hand_tree();
    t.forks[2].y = NAN;
    CHECK_THROWS_AS(krs::model::build_tree(t), krs::invalid_parameter);
    t = hand_tree();
    t.forks = {{0, 0, 0}};
    CHECK_THROWS_WITH_AS(krs::model::build_tree(t), doctest::Contains("tree.forks"), krs::invalid_parameter);
    // A branch that continues its parent straight has no default fork plane.
    t = hand_tree();
    t.forks[2] = {0, 3, 0};
    t.controls[1] = {0, 2.5f, 0};
    CHECK_THROWS_WITH_AS(krs::model::build_tree(t), doctest::Contains("tree.fork_normals[0]"), krs::invalid_parameter);
    // ... and an explicit normal that holds the child branch is refused.
    t.fork_normals = {{1, 0.5f, 0}, {0, 0, 1}, {1, 0, 0}};
    CHECK_NOTHROW(krs::model::build_tree(t));
    t.fork_normals[0] = {1, 0, 0};
    CHECK_THROWS_WITH_AS(krs::model::build_tree(t), doctest::Contains("tree.fork_normals[0]"), krs::invalid_parameter);
    t.fork_normals[0] = {0, 0, 0};
    CHECK_THROWS_WITH_AS(krs::model::build_tree(t), doctest::Contains("tree.fork_normals[0]"), krs::invalid_parameter);

    krs::model::tree_style style;
    style.spread_degrees = 95;
    CHECK_THROWS_WITH_AS(krs::model::grow_tree(style), doctest::Contains("tree_style.spread_degrees"), krs::invalid_parameter);
    style = {};
    style.levels = 0;
    CHECK_THROWS_WITH_AS(krs::model::grow_tree(style), doctest::Contains("tree_style.levels"), krs::invalid_parameter);
    style = {};
    style.leaf_radius = -1;
    CHECK_THROWS_WITH_AS(krs::model::grow_tree(style), doctest::Contains("tree_style.leaf_radius"), krs::invalid_parameter);
}

// Hypertree transforms, IFS rules and the generator (paper sections 3, 4 and 6), each against an
// independent reference: closed forms for the maps, a from-scratch recomposition of every
// generator's pipeline for the row reuse of figure 2, brute-force sampling for the voxel walk.

#include "hypertree/execution.hpp"
#include "hypertree/hypertree.hpp"
#include "hypertree/presets.hpp"
#include "support/random.hpp"
#include "support/rejects.hpp"
#include "support/threads.hpp"

#include <doctest/doctest.h>

#include "support/small_tree.hpp"

#include <algorithm>
#include <cmath>
#include <functional>
#include <limits>
#include <map>
#include <numbers>
#include <set>
#include <tuple>
#include <type_traits>

using namespace hypertree;
using krs_test::uniform;

namespace {

constexpr double degrees = std::numbers::pi / 180.0;

using krs_test::branch_pipeline;

using krs_test::small_tree;

// Applies a chain by its elements one at a time (no canonical merging): the reference for chain_at.
template <class... E>
vec3d apply_elements(const pipeline<E...>& p, int level, vec3d x)
{
    std::apply([&](const auto&... e) { ((x = e.map_at(level)(x)), ...); }, p.elements);
    return x;
}

} // namespace

TEST_CASE("hypertree shear matches its formula")
{
    std::mt19937_64 g(7);
    for (int axis = 0; axis < 3; ++axis) {
        const shear s(axis, 0.3, -0.2, 2.5, 0.8);
        const shear_map m = s.map_at(1);
        for (int i = 0; i < 200; ++i) {
            const vec3d p{uniform(g, -1, 1), uniform(g, -1, 1), uniform(g, -1, 1)};
            const double c[3] = {p.x, p.y, p.z};
            const double h = std::min(std::abs(c[axis]) / 0.8, 1.0);
            double expect[3] = {p.x, p.y, p.z};
            const int a = axis == 0 ? 1 : 0, b = axis == 2 ? 1 : 2;
            expect[a] += 0.3 * std::pow(h, 2.5);
            expect[b] += -0.2 * std::pow(h, 2.5);
            const vec3d q = m(p);
            CHECK(q.x == doctest::Approx(expect[0]).epsilon(1e-14));
            CHECK(q.y == doctest::Approx(expect[1]).epsilon(1e-14));
            CHECK(q.z == doctest::Approx(expect[2]).epsilon(1e-14));
        }
    }
    // The Lipschitz bound holds on random pairs.
    const shear_map m = shear(1, 0.3, -0.2, 2.5, 0.8).map_at(1);
    for (int i = 0; i < 2000; ++i) {
        const vec3d p{uniform(g, -1, 1), uniform(g, -1, 1), uniform(g, -1, 1)};
        const vec3d q = p + krs_test::random_direction(g) * 1e-3;
        CHECK(krs::length(m(p) - m(q)) <= m.lipschitz() * krs::length(p - q) * (1 + 1e-9));
    }
}

TEST_CASE("hypertree pipelines compose to canonical chains")
{
    std::mt19937_64 g(11);
    const pipeline<translate, rotate, shear, scale, rotate> p(translate(0.1, parameter::per_level(0.2, 0.3, 0.4), 0),
                                                              rotate({1, 2, 3}, parameter::per_level(0.3, -0.4, 0.9)),
                                                              shear(1, 0.1, 0.05, 2), scale(0.5, 0.4, 0.45), rotate({0, 1, 0}, 1.1));
    static_assert(decltype(p)::shear_count == 1);
    runtime_pipeline r({translate(0.1, parameter::per_level(0.2, 0.3, 0.4), 0), rotate({1, 2, 3}, parameter::per_level(0.3, -0.4, 0.9)),
                        shear(1, 0.1, 0.05, 2), scale(0.5, 0.4, 0.45), rotate({0, 1, 0}, 1.1)});
    for (int level = 1; level <= 5; ++level) {
        const auto chain = p.chain_at(level);
        const auto runtime_chain = r.chain_at(level);
        CHECK(runtime_chain.shears == 1);
        for (int i = 0; i < 100; ++i) {
            const vec3d x{uniform(g, -1, 1), uniform(g, 0, 1), uniform(g, -1, 1)};
            const vec3d expect = apply_elements(p, level, x);
            CHECK(krs::length(chain(x) - expect) < 1e-14);
            CHECK(krs::length(runtime_chain(x) - expect) < 1e-14);
        }
    }
    // Level 3 and deeper share their values: the generator's row reuse depends on it.
    CHECK(krs::length(p.chain_at(3)(vec3d{0.3, 0.2, 0.1}) - p.chain_at(9)(vec3d{0.3, 0.2, 0.1})) == 0);
}

TEST_CASE("hypertree affine Lipschitz bound is the spectral norm")
{
    std::mt19937_64 g(5);
    for (int trial = 0; trial < 200; ++trial) {
        affine_map a;
        for (double& v : a.m) v = uniform(g, -1, 1);
        // Reference: power iteration on m^T m from many starts (converges from below).
        double best = 0;
        for (int start = 0; start < 4; ++start) {
            vec3d v = krs_test::random_direction(g);
            for (int it = 0; it < 300; ++it) {
                const vec3d mv = a(v) - a.t;
                const vec3d mtmv{a.m[0] * mv.x + a.m[3] * mv.y + a.m[6] * mv.z, a.m[1] * mv.x + a.m[4] * mv.y + a.m[7] * mv.z,
                                 a.m[2] * mv.x + a.m[5] * mv.y + a.m[8] * mv.z};
                v = mtmv / krs::length(mtmv);
            }
            best = std::max(best, krs::length(a(v) - a.t));
        }
        CHECK(a.lipschitz() >= best);
        CHECK(a.lipschitz() == doctest::Approx(best).epsilon(1e-6));
    }
}

TEST_CASE("hypertree randomized parameters are drawn once per tree")
{
    const parameter p = parameter::random(0.5, 0.1);
    random_stream r1(42), r2(42);
    const parameter a = p.draw(r1), b = p.draw(r2);
    CHECK(a.mean == b.mean);
    CHECK(a.is_fixed());
    for (double v : a.mean) CHECK((v >= 0.4 && v <= 0.6));

    auto tree = small_tree();
    std::get<0>(tree.transforms[0].transform.elements) = scale(parameter::random(0.55, 0.05));
    std::get<1>(tree.transforms[1].transform.elements) = rotate({0, 0, 1}, parameter::random(35 * degrees, 10 * degrees));
    tree.iterations = 20000;
    const auto first = generate(tree, 1234), again = generate(tree, 1234), other = generate(tree, 999);
    REQUIRE(first.hits.size() == again.hits.size());
    bool same = true;
    for (std::size_t i = 0; i < first.hits.size(); ++i)
        same = same && first.hits[i].voxel == again.hits[i].voxel && first.hits[i].level == again.hits[i].level &&
               first.hits[i].part == again.hits[i].part;
    CHECK(same);
    const bool differs = other.hits.size() != first.hits.size() ||
                         !std::equal(first.hits.begin(), first.hits.end(), other.hits.begin(),
                                     [](const hit& x, const hit& y) { return x.voxel == y.voxel; });
    CHECK(differs);
    // One draw per tree: two drawn IFS from one seed have identical chains, and the drawn
    // randomized scale lies in its range.
    const drawn_ifs<branch_pipeline> d1(tree, 77), d2(tree, 77);
    for (int level = 1; level <= 3; ++level) {
        CHECK(d1.chain_of(0, level).affine[0].m == d2.chain_of(0, level).affine[0].m);
        const double s = d1.chain_of(0, level).lipschitz();
        CHECK((s >= 0.5 && s <= 0.6 + 1e-12));
    }
}

TEST_CASE("hypertree generator rows equal their pipelines recomposed from scratch")
{
    // Figure 2: row s applies w_j at level s - j + 1. The generator reuses the deep part of each
    // row; this recomputes every generator from the condensation point with no reuse.
    auto tree = small_tree(7);
    tree.iterations = 7 * 300;
    const drawn_ifs<branch_pipeline> drawn(tree, 5);
    vec3d trunk{};
    std::size_t checked = 0;
    double worst = 0;
    generate(tree, 5, {}, [&](const generator_event& e) {
        if (e.depth == 0) {
            trunk = e.start;
            return;
        }
        vec3d x = trunk;
        for (int j = 1; j <= e.depth; ++j) x = drawn.chain_of(e.selected[j - 1], e.depth - j + 1)(x);
        worst = std::max(worst, krs::length(x - e.start));
        ++checked;
    });
    CHECK(checked > 1000);
    CHECK(worst < 1e-12);
}

TEST_CASE("hypertree line generators keep their length")
{
    auto tree = small_tree();
    tree.generator = generator_shape::line({0, -0.025, 0}, {0, 0.025, 0});
    tree.iterations = 30000;
    tree.perturb.amplitude = {0.01, 0.02, 0.01};
    double worst = 0;
    std::size_t lines = 0;
    generate(tree, 3, {}, [&](const generator_event& e) {
        worst = std::max(worst, std::abs(krs::length(e.end - e.start) - 0.05));
        ++lines;
    });
    CHECK(lines > 20000);
    CHECK(worst < 1e-5);
}

TEST_CASE("hypertree dummy and last level rules")
{
    SUBCASE("dummy from level d leaves that branch without generators at depth d or deeper")
    {
        auto tree = small_tree(6);
        tree.transforms[1].dummy_from = 3;
        const auto result = generate(tree, 21);
        std::map<int, std::size_t> deep_per_part;
        for (const hit& h : result.hits)
            if (h.level >= 3) ++deep_per_part[h.part];
        CHECK(deep_per_part[2] == 0); // part 2 = transform 1
        CHECK(deep_per_part[1] > 100);
        CHECK(deep_per_part[3] > 100);
        // The dummy still transforms: deeper generators of other branches pass through it.
        std::size_t through_dummy = 0;
        generate(tree, 21, {}, [&](const generator_event& e) {
            if (e.recorded && e.depth >= 2 && e.selected[0] == 1 && e.selected[e.depth - 1] != 1) ++through_dummy;
        });
        CHECK(through_dummy > 100);
    }
    SUBCASE("a plain dummy draws nothing of its own branch")
    {
        auto tree = small_tree(5);
        tree.transforms[3].dummy_from = 1;
        const auto result = generate(tree, 8);
        CHECK(std::none_of(result.hits.begin(), result.hits.end(), [](const hit& h) { return h.part == 4; }));
    }
    SUBCASE("last level m: the transformation never executes deeper than m")
    {
        auto tree = small_tree(7);
        tree.transforms[0].last_level = 2;
        std::size_t violations = 0, events = 0, uses_at_two = 0;
        generate(tree, 4, {}, [&](const generator_event& e) {
            ++events;
            for (int j = 1; j <= e.depth; ++j) {
                const int level = e.depth - j + 1;
                if (e.selected[j - 1] == 0 && level > 2) ++violations;
                if (e.selected[j - 1] == 0 && level == 2) ++uses_at_two;
            }
        });
        CHECK(events > 10000);
        CHECK(violations == 0);
        CHECK(uses_at_two > 100);
    }
}

TEST_CASE("hypertree transformations are selected by their relative probabilities")
{
    auto tree = small_tree(2); // one transformation per cycle
    tree.transforms[0].probability = 3;
    tree.transforms[1].probability = 0;
    tree.transforms[2].probability = 1;
    tree.transforms[3].probability = 4;
    tree.iterations = 2 * 80000;
    std::array<std::size_t, 4> count{};
    generate(tree, 99, {}, [&](const generator_event& e) {
        if (e.depth == 1) ++count[e.selected[0]];
    });
    const double n = 80000;
    CHECK(count[1] == 0);
    CHECK(double(count[0]) / n == doctest::Approx(3.0 / 8).epsilon(0.03));
    CHECK(double(count[2]) / n == doctest::Approx(1.0 / 8).epsilon(0.05));
    CHECK(double(count[3]) / n == doctest::Approx(4.0 / 8).epsilon(0.03));
}

TEST_CASE("hypertree generation is the same on one thread and many")
{
    auto tree = small_tree();
    tree.iterations = 100000;
    generation_options serial;
    serial.chunk_cycles = 1000;
    generation_options threaded = serial;
    threaded.parallel_for = krs_test::strided_threads(3);
    const auto a = generate(tree, 17, serial), b = generate(tree, 17, threaded);
    REQUIRE(a.hits.size() == b.hits.size());
    CHECK(std::equal(a.hits.begin(), a.hits.end(), b.hits.begin(),
                     [](const hit& x, const hit& y) { return x.voxel == y.voxel && x.level == y.level && x.part == y.part; }));
    CHECK(a.stats.recorded == b.stats.recorded);
    CHECK(a.stats.recorded_per_depth == b.stats.recorded_per_depth);
}

TEST_CASE("hypertree lanes run in step make the same hits as lanes run one by one")
{
    // In a build with AVX-512 the point generator's eight lanes of cycles run in SIMD registers
    // (create/generator_lanes.hpp); vector_lanes = false runs them through the scalar loop. The
    // tree must not depend on which: the same hits (in another order) and the same counts. Without
    // AVX-512 both runs take the scalar loop.
    const auto sorted_hits = [](const generated_hits& g) {
        std::vector<std::tuple<voxel_index, int, int>> v;
        for (const hit& h : g.hits) v.emplace_back(h.voxel, h.level, h.part);
        std::sort(v.begin(), v.end());
        return v;
    };
    const auto same_tree = [&](const auto& tree, std::uint64_t seed, std::uint64_t chunk_cycles) {
        CHECK(detail::lanes_fit(drawn_ifs(tree, seed)) == detail::lanes_built);
        generation_options lanes, scalar;
        lanes.chunk_cycles = scalar.chunk_cycles = chunk_cycles;
        scalar.vector_lanes = false;
        const generated_hits a = generate(tree, seed, lanes), b = generate(tree, seed, scalar);
        CHECK(a.hits.size() == b.hits.size());
        CHECK(sorted_hits(a) == sorted_hits(b));
        CHECK(a.stats.cycles == b.stats.cycles);
        CHECK(a.stats.generators == b.stats.generators);
        CHECK(a.stats.recorded == b.stats.recorded);
        CHECK(a.stats.escaped == b.stats.escaped);
        CHECK(a.stats.recorded_per_depth == b.stats.recorded_per_depth);
        return a;
    };
    SUBCASE("plain tree")
    {
        same_tree(small_tree(6), 5, 8192);
    }
    SUBCASE("unequal probabilities, last level, dummies, lanes of unequal length")
    {
        auto tree = small_tree(8);
        tree.transforms[0].probability = 3.0;
        tree.transforms[2].probability = 0.4;
        tree.transforms[0].last_level = 3; // cycles end early in some lanes, not in others
        tree.transforms[1].dummy_from = 2;
        tree.iterations = 60001;
        const generated_hits g = same_tree(tree, 11, 777); // 7501 cycles: chunks of 777 and 506, lanes of 98 and 97
        CHECK(g.stats.generators < g.stats.cycles * 8); // the last-level rule did end cycles early
    }
    SUBCASE("sixteen transformations (both permute registers), a forked stem, points escaping the volume")
    {
        auto tree = small_tree(9);
        for (int k = 0; k < 12; ++k)
            tree.transforms.push_back({branch_pipeline(scale(0.4 + 0.01 * k), rotate({0, 0, 1}, (20 + 3 * k) * degrees),
                                                       rotate({0, 1, 0}, 30.0 * k * degrees), translate(0, 0.3 + 0.04 * k, 0)),
                                       0.5 + 0.1 * k});
        REQUIRE(tree.transforms.size() == 16);
        tree.condensations.push_back(condensation{cone{1, 0.0, 0.4, 0.04, 0.02}, {}});
        tree.volume = hypervolume({-0.5, -0.05, -0.5}, {1, 1, 1}, resolution{40, 50, 60});
        const generated_hits g = same_tree(tree, 23, 1000);
        CHECK(g.stats.escaped > 100);
    }
    SUBCASE("the presets: affine maps (A, B), a shear in every chain and sheared stems (D)")
    {
        for (auto tree : {presets::tree_a(64), presets::tree_b(64), presets::tree_d(64)}) {
            CAPTURE(tree.name);
            tree.iterations = 120000;
            same_tree(tree, 9, 2000);
        }
    }
    SUBCASE("line generators: preset C, and lines along an axis clipped by a volume that cuts the tree")
    {
        auto c = presets::tree_c(64);
        c.iterations = 60000;
        same_tree(c, 13, 3000);
        auto tree = small_tree(6);
        tree.generator = generator_shape::line({0, -0.04, 0}, {0, 0.04, 0}); // the stem's lines move along y only
        // x from 0: half the stem's lines lie beside the volume, parallel to it (walks nothing).
        tree.volume = hypervolume({0.0, 0.1, -0.4}, {0.4, 0.7, 0.8}, resolution{33, 47, 29});
        const generated_hits g = same_tree(tree, 31, 1000);
        CHECK(g.stats.escaped > 100);
        CHECK(g.hits.size() > 2 * (g.stats.recorded - g.stats.escaped)); // lines walk several voxels
    }
    SUBCASE("stems along x and z, two shears per chain on other axes with odd exponents")
    {
        // Every preset's cones and shears stand along y with exponent 2: here the other axes, odd
        // exponents and a second shear in each chain (its own table), for points and for lines.
        ifs<> tree;
        tree.name = "sideways";
        for (int k = 0; k < 5; ++k)
            tree.transforms.push_back({runtime_pipeline({shear(0, 0.04 + 0.01 * k, -0.03, 1, 0.8), scale(0.5),
                                                         rotate({0, 0, 1}, (30 + 9 * k) * degrees), shear(2, -0.02, 0.05 + 0.01 * k, 3, 0.6),
                                                         rotate({0, 1, 0}, 70.0 * k * degrees), translate(0.1 * k, 0.35 + 0.08 * k, 0)}),
                                       1.0 + 0.2 * k});
        tree.condensations = {condensation{cone{0, -0.3, 0.4, 0.05, 0.02}, {}}, condensation{cone{2, -0.2, 0.5, 0.04, 0.03}, {}}};
        tree.tree_depth = 6;
        tree.branch_depth = 1;
        tree.iterations = 60000;
        tree.volume = hypervolume({-1, -0.5, -1}, {2, 2, 2}, resolution{50, 40, 45});
        same_tree(tree, 41, 1500);
        tree.generator = generator_shape::line({-0.03, 0.02, -0.01}, {0.03, -0.02, 0.01});
        same_tree(tree, 42, 1500);
    }
    SUBCASE("generators that overflow: infinite and not-a-number ends record nothing")
    {
        auto tree = small_tree(6);
        tree.require_contraction = false;
        tree.transforms.push_back({branch_pipeline(scale(1e200), rotate({0, 0, 1}, 0.3), rotate({0, 1, 0}, 0.2), translate(0, 0.5, 0)), 0.5});
        same_tree(tree, 43, 1000);
        tree.generator = generator_shape::line({0, -0.04, 0}, {0, 0.04, 0});
        const generated_hits g = same_tree(tree, 44, 1000);
        CHECK(g.stats.escaped > 1000);
    }
    SUBCASE("shears of different shapes: the scalar loop")
    {
        auto tree = presets::tree_d(64);
        tree.transforms[0].transform = runtime_pipeline({shear(0, 0.08, 0, 2), scale(0.5), translate(0, 0.3, 0)});
        CHECK_FALSE(detail::lanes_fit(drawn_ifs(tree, 1)));
    }
    SUBCASE("seventeen transformations: beyond the permute tables, the scalar loop")
    {
        auto tree = small_tree(5);
        for (int k = 0; k < 13; ++k) tree.transforms.push_back(tree.transforms[std::size_t(k % 4)]);
        REQUIRE(tree.transforms.size() == 17);
        CHECK_FALSE(detail::lanes_fit(drawn_ifs(tree, 1)));
    }
}

TEST_CASE("hypertree condensation samples the cone uniformly")
{
    const cone c{1, 0.2, 1.2, 0.3, 0.1};
    random_stream r(3);
    const int n = 200000;
    int lower_half = 0, outside = 0;
    for (int i = 0; i < n; ++i) {
        const vec3d p = c.sample(r);
        const double t = (p.y - 0.2) / 1.0, radius = 0.3 + (0.1 - 0.3) * t;
        if (t < 0 || t > 1 || std::hypot(p.x, p.z) > radius * (1 + 1e-12)) ++outside;
        if (t < 0.5) ++lower_half;
    }
    CHECK(outside == 0);
    // Closed form: the lower half's share of the frustum volume.
    const cone lower{1, 0.2, 0.7, 0.3, 0.2};
    CHECK(double(lower_half) / n == doctest::Approx(lower.volume() / c.volume()).epsilon(0.01));
}

TEST_CASE("hypertree segment voxel walk: the most voxels it visits, and non-finite ends")
{
    // The generator makes room for max_voxels_on_segment voxels before walking a line. The worst
    // case for that bound is a cubic grid and a segment along a cube diagonal, crossing a boundary
    // on every axis at each end: walks of such segments, at many offsets and lengths, must fit.
    const hypervolume v({0, 0, 0}, {1, 1, 1}, hypertree::resolution::cube(64));
    std::mt19937_64 g(17);
    std::size_t longest_share = 0; // percent of the bound the longest walk used
    for (int trial = 0; trial < 20000; ++trial) {
        const double length = uniform(g, 0.001, 0.5);
        const vec3d direction = krs::normalize(vec3d{trial % 2 ? 1.0 : -1.0, trial % 3 ? 1.0 : -1.0, 1.0} +
                                               krs_test::random_direction(g) * uniform(g, 0.0, 0.05));
        const vec3d a{uniform(g, 0.25, 0.75), uniform(g, 0.25, 0.75), uniform(g, 0.25, 0.75)};
        const vec3d b = a + direction * length;
        std::size_t visits = 0;
        for_each_voxel_on_segment(v, a, b, [&](voxel_index) { ++visits; });
        const std::size_t bound = hypertree::max_voxels_on_segment(v, length);
        REQUIRE(visits <= bound);
        longest_share = std::max(longest_share, 100 * visits / bound);
    }
    // The bound is not loose beyond the factor 2 / sqrt(3) it allows for rounding.
    CHECK(longest_share >= 80);
    // A non-finite end visits nothing (the walk's cell count would be undefined).
    const double nan = std::numeric_limits<double>::quiet_NaN(), inf = std::numeric_limits<double>::infinity();
    for (const vec3d bad : {vec3d{nan, 0.5, 0.5}, vec3d{0.5, inf, 0.5}, vec3d{0.5, 0.5, -inf}}) {
        std::size_t visits = 0;
        for_each_voxel_on_segment(v, vec3d{0.5, 0.5, 0.5}, bad, [&](voxel_index) { ++visits; });
        for_each_voxel_on_segment(v, bad, vec3d{0.5, 0.5, 0.5}, [&](voxel_index) { ++visits; });
        CHECK(visits == 0);
    }
}

TEST_CASE("hypertree segment voxel walk")
{
    const hypervolume v({-1, -2, 0.5}, {2, 3, 1.5}, {17, 23, 11});
    std::mt19937_64 g(13);
    for (int trial = 0; trial < 500; ++trial) {
        // Segments partly outside the box too.
        const vec3d a{uniform(g, -1.3, 1.3), uniform(g, -2.3, 1.3), uniform(g, 0.3, 2.2)};
        const vec3d b = trial % 3 == 0 ? a + krs_test::random_direction(g) * 0.2 : vec3d{uniform(g, -1.3, 1.3), uniform(g, -2.3, 1.3), uniform(g, 0.3, 2.2)};
        std::vector<voxel_index> walk;
        for_each_voxel_on_segment(v, a, b, [&](voxel_index i) { walk.push_back(i); });
        const std::set<voxel_index> unique(walk.begin(), walk.end());
        CHECK(unique.size() == walk.size());
        CHECK(walk.size() <= hypertree::max_voxels_on_segment(v, krs::length(b - a)));
        // Every voxel dense sampling finds is walked...
        const int samples = 20000;
        for (int s = 0; s <= samples; ++s)
            if (const auto i = v.voxel_at(a + (b - a) * (double(s) / samples))) CHECK(unique.count(*i) == 1);
        // ...and every walked voxel's box meets the segment (slab test, widened by 1e-9).
        for (voxel_index i : walk) {
            const vec3d c = v.voxel_center(i), h = v.voxel_size() * 0.5;
            double t0 = 0, t1 = 1;
            const double s0[3] = {a.x, a.y, a.z}, d[3] = {b.x - a.x, b.y - a.y, b.z - a.z}, cc[3] = {c.x, c.y, c.z}, hh[3] = {h.x, h.y, h.z};
            for (int k = 0; k < 3; ++k) {
                const double lo = cc[k] - hh[k] - 1e-9, hi = cc[k] + hh[k] + 1e-9;
                if (d[k] == 0) {
                    if (s0[k] < lo || s0[k] > hi) t0 = 2;
                    continue;
                }
                double ta = (lo - s0[k]) / d[k], tb = (hi - s0[k]) / d[k];
                if (ta > tb) std::swap(ta, tb);
                t0 = std::max(t0, ta), t1 = std::min(t1, tb);
            }
            CHECK(t0 <= t1);
        }
    }
}

TEST_CASE("hypertree refuses impossible definitions with named parameters")
{
    using krs_test::rejects_naming;
    rejects_naming([] { shear(1, 0.1, 0.1, 0.5); }, "shear.exponent");
    rejects_naming([] { rotate({0, 0, 0}, 1.0); }, "rotate.axis");
    rejects_naming([] { hypervolume({0, 0, 0}, {1, 1, 1}, {0, 10, 10}); }, "hypervolume.resolution.x");
    rejects_naming([] { hypervolume({0, 0, 0}, {1, 1, 1}, {2000, 2000, 2000}); }, "hypervolume.resolution");
    rejects_naming([] { hypervolume({0, 0, 0}, {1, -1, 1}, {10, 10, 10}); }, "hypervolume.extent.y");
    // Boxes float cannot place (each loaded from a file once, and failed later under another name).
    rejects_naming([] { hypervolume({0, 0, 0}, {5e-324, 1, 1}, {1, 1, 1}); }, "hypervolume.extent.x");
    rejects_naming([] { hypervolume({0, 0, 0}, {1, 1e-300, 1}, {1, 4, 1}); }, "hypervolume.extent.y");
    rejects_naming([] { hypervolume({1e300, 0, 0}, {1, 1, 1}, {1, 1, 1}); }, "hypervolume.origin");
    rejects_naming([] { hypervolume({5e8, 0, 0}, {1e-9, 1, 1}, {1, 1, 1}); }, "hypervolume.extent.x");
    rejects_naming([] { hypervolume({0, 0, 0}, {1, 1, 1e300}, {1, 1, 1}); }, "hypervolume.extent.z");
    // The smallest accepted sides: 1e-9 near the origin, 1e-6 of the coordinate far from it.
    CHECK_NOTHROW(hypervolume({0, 0, 0}, {1e-9, 1e-9, 1e-9}, {1, 1, 1}));
    CHECK_NOTHROW(hypervolume({1e6, 0, 0}, {8, 1, 1}, {4, 1, 1}));
    rejects_naming([] { hypervolume({1e6, 0, 0}, {8, 1, 1}, {16, 1, 1}); }, "hypervolume.extent.x");
    rejects_naming([] { scale(std::nan("")); }, "scale.x");
    rejects_naming([] { (cone{1, 1.0, 0.5, 0.1, 0.1}).validate(); }, "cone.top");
    rejects_naming([] {
        auto t = small_tree();
        for (auto& w : t.transforms) w.probability = 0;
        generate(t, 1);
    }, "probabilities");
    rejects_naming([] {
        auto t = small_tree();
        t.transforms[2].probability = -1;
        generate(t, 1);
    }, "ifs.transforms[2].probability");
    rejects_naming([] {
        auto t = small_tree();
        t.tree_depth = 0;
        generate(t, 1);
    }, "ifs.tree_depth");
    rejects_naming([] {
        auto t = small_tree();
        t.branch_depth = 6;
        generate(t, 1);
    }, "ifs.branch_depth");
    rejects_naming([] {
        auto t = small_tree();
        std::get<0>(t.transforms[1].transform.elements) = scale(1.2);
        generate(t, 1);
    }, "ifs.transforms[1]");
    rejects_naming([] {
        auto t = small_tree();
        t.iterations = std::uint64_t(1) << 40;
        generate(t, 1);
    }, "ifs.iterations");
    // build_tree sizes a list per chunk: it must refuse before that, whatever the iteration count
    // (2^52 iterations would be 2^41 chunks).
    for (const int bits : {40, 52, 63}) {
        rejects_naming([bits] {
            auto t = presets::tree_c(64);
            t.iterations = std::uint64_t(1) << bits;
            (void)build_tree<index_list_store>(t, 1);
        }, "ifs.iterations");
    }
    // Near 2^64 the cycle count wrapped to 0: an empty tree instead of a refusal.
    for (const std::uint64_t iterations : {~std::uint64_t(0), ~std::uint64_t(0) - 3}) {
        rejects_naming([iterations] {
            auto t = presets::tree_c(64);
            t.iterations = iterations;
            (void)build_tree<index_list_store>(t, 1);
        }, "ifs.iterations");
    }
    // Stem radii beyond the magnitude policy (their squares overflowed; see the cone test below).
    rejects_naming([] { (cone{1, 0.0, 1.0, 1e200, 1e200}).validate(); }, "cone.bottom_radius");
    rejects_naming([] { (cone{1, 0.0, 1.0, 0.1, 2e9}).validate(); }, "cone.top_radius");
    rejects_naming([] { (cone{1, -2e9, 1.0, 0.1, 0.1}).validate(); }, "cone.bottom");
}

TEST_CASE("hypertree generation edge cases: one chunk of 2^64 - 1 cycles, tiny stems, huge and tiny directions")
{
    // A chunk size of 2^64 - 1 (asking for one chunk) wrapped the chunk count to 0: no hits.
    auto t = presets::tree_a(40);
    t.iterations = 3000;
    generation_options one_chunk;
    one_chunk.chunk_cycles = ~std::uint64_t(0);
    const generated_hits all = generate(t, 5, one_chunk), usual = generate(t, 5);
    CHECK(all.hits.size() > 1000);
    CHECK(all.stats.cycles == usual.stats.cycles);
    // Stems of radius 1e-200: u r_max^2 >= r^2 underflowed to 0 >= 0 and the sampler never
    // accepted a height (build_tree hung). The stem is then a line of voxels along the axis.
    auto thin = presets::tree_a(40);
    thin.iterations = 60;
    thin.condensations[0].stem.bottom_radius = 1e-200;
    thin.condensations[0].stem.top_radius = 0;
    CHECK(build_tree<index_list_store>(thin, 1).nonempty_count() > 0);
    const cone needle{1, 0.0, 1.0, 1e-170, 1e-300};
    random_stream r(9);
    for (int i = 0; i < 1000; ++i) {
        const vec3d p = needle.sample(r);
        REQUIRE(p.y >= 0.0);
        REQUIRE(p.y <= 1.0);
        REQUIRE(std::hypot(p.x, p.z) <= 1e-170);
    }
    // Directions are normalized without squaring their size: a rotation about (0, 0, 1e200) had
    // a length of infinity, its axis became (0, 0, 0) and the rotation a collapse to cos(a) I.
    const rotate huge({0, 0, 1e200}, 0.7), unit({0, 0, 1}, 0.7), tiny({0, 0, 1e-200}, 0.7);
    for (const rotate* r2 : {&huge, &tiny}) {
        REQUIRE(r2->axis.z == doctest::Approx(1.0));
        const affine_map a = r2->map_at(1), b = unit.map_at(1);
        const vec3d p{1, 2, 3};
        CHECK(krs::length(a(p) - b(p)) < 1e-12);
    }
}

TEST_CASE("hypertree non-contractive transforms run when allowed and count escapes")
{
    auto t = small_tree(8);
    std::get<0>(t.transforms[3].transform.elements) = scale(1.3);
    t.require_contraction = false;
    t.iterations = 20000;
    const auto result = generate(t, 2);
    CHECK(result.stats.escaped > 0);
    CHECK(result.stats.escaped < result.stats.recorded);
    for (const hit& h : result.hits) CHECK(std::uint64_t(h.voxel) < t.volume.voxel_count());
}

TEST_CASE("hypertree presets stay inside their hypervolumes")
{
    for (auto make : {presets::tree_a, presets::tree_b, presets::tree_c, presets::tree_d}) {
        auto t = make(60);
        CAPTURE(t.name);
        t.iterations = 20000;
        const auto result = generate(t, 3);
        CHECK(result.stats.escaped == 0);
        CHECK(result.stats.recorded > 10000);
        // Every depth of the tree is populated (the rules leave no level empty).
        for (std::uint64_t n : result.stats.recorded_per_depth) CHECK(n > 0);
    }
}

TEST_CASE("hypertree every store kind agrees on every voxel of a generated tree")
{
    // Same tree, same seed: each build_tree call regenerates it, so this also checks that
    // generation is reproducible across calls. The dense store is the reference; every other kind
    // of store_kinds is compared with it voxel by voxel.
    auto t = presets::tree_d(48);
    t.iterations = 40000;
    build_options options;
    options.density_class_count = 16;
    const auto dense = build_tree<dense_store>(t, 6, options);
    REQUIRE(dense.nonempty_count() > 1000);
    std::size_t kinds_compared = 0;
    for_each_store_kind([&]<class S>() {
        if constexpr (!std::is_same_v<S, dense_store>) {
            INFO(store_kind_name<S>);
            const S other = build_tree<S>(t, 6, options);
            std::size_t mismatches = 0;
            for (voxel_index i = 0; i < voxel_index(t.volume.voxel_count()); ++i) mismatches += !(other.at(i) == dense.at(i));
            CHECK(mismatches == 0);
            ++kinds_compared;
        }
    });
    CHECK(kinds_compared + 1 == std::tuple_size_v<store_kinds>);
    std::size_t branch_full = 0, branch = 0;
    for (voxel_index i = 0; i < voxel_index(t.volume.voxel_count()); ++i) {
        const voxel v = dense.at(i);
        if (v.density > 0 && v.level <= t.branch_depth) ++branch, branch_full += v.density == 255;
    }
    // Branch voxels get full density (section 4).
    CHECK(branch > 100);
    CHECK(branch_full == branch);
}

TEST_CASE("hypertree build_tree with scratch memory: the tree of the separate steps, and no new block the second time")
{
    // build_tree validates the generator's chunks in place and draws every temporary from the
    // scratch; the reference runs the public steps one by one (generate's concatenated hits,
    // compact, classify) without it. Point (D) and line (C) generators, on one thread and three.
    const parallel_for_hook pool = krs_test::strided_threads(3);
    for (auto t : {presets::tree_d(40), presets::tree_c(40)}) {
        INFO(t.name);
        t.iterations = 30000;
        generation_options steps;
        steps.chunk_cycles = 500; // the chunks' random streams shape the tree: the same as below
        const auto generated = generate(t, 9, steps);
        const auto entries = compact(generated.hits);
        const auto voxels = classify(entries, density_classes(entries, 8), t.branch_depth);
        const dense_store reference = dense_store::build(t.volume, voxels);
        REQUIRE(reference.nonempty_count() > 500);
        for (const bool threaded : {false, true}) {
            scratch_memory scratch;
            build_options options;
            options.density_class_count = 8;
            options.generation.chunk_cycles = 500;
            options.generation.scratch = &scratch;
            if (threaded) options.generation.parallel_for = pool;
            for (int build = 0; build < 2; ++build) {
                const std::size_t blocks_before = scratch.system_allocations();
                const auto tree = build_tree<index_list_store>(t, 9, options);
                std::size_t mismatches = 0;
                for (voxel_index i = 0; i < voxel_index(t.volume.voxel_count()); ++i) mismatches += !(tree.at(i) == reference.at(i));
                CHECK(mismatches == 0);
                CHECK(tree.nonempty_count() == reference.nonempty_count());
                // Threads may take blocks in another order the second time; one thread takes the same.
                if (build == 1 && !threaded) CHECK(scratch.system_allocations() == blocks_before);
            }
            CHECK(scratch.kept_bytes() > 0);
        }
    }
}

TEST_CASE("hypertree build_tree's voxels equal the separate steps' on grids above and below 2^25 voxels")
{
    // At most 2^25 voxels each chunk is bucketed as it is made; above, the chunks are validated
    // as pieces. Both must give the voxel list of generate, compact and classify run one by one.
    for (const int resolution : {40, 330}) {
        auto t = presets::tree_c(resolution);
        t.iterations = 20000;
        INFO("resolution " << resolution << ": " << t.volume.voxel_count() << " voxels");
        generation_options steps;
        steps.chunk_cycles = 300;
        const auto generated = generate(t, 12, steps);
        const auto entries = compact(generated.hits);
        const auto expected = classify(entries, density_classes(entries, 16), t.branch_depth);
        scratch_memory scratch;
        const auto voxels = detail::stored_voxels_of(t, 12, 16, steps, &scratch);
        REQUIRE(voxels.size() == expected.size());
        REQUIRE(expected.size() > 1000);
        std::size_t differ = 0;
        for (std::size_t i = 0; i < expected.size(); ++i)
            differ += voxels[i].index != expected[i].index || !(voxels[i].value == expected[i].value) || voxels[i].part != expected[i].part;
        CHECK(differ == 0);
    }
}

TEST_CASE("hypertree lanes: line walks of consecutive rows in flight keep the order of rows walked one by one")
{
    // With lanes in step, a row's voxel walks step along with the next row's (whose hits wait in
    // a side buffer until the first row's walks end; create/generator_lanes.hpp). The hit list
    // must be the one of walking each row to its end before the next begins, in the same order:
    // the lanes-vs-scalar test above compares sorted hits and cannot see an order. Lines short
    // and long (walks of a row ending long after the next row's), lanes of unequal length, a
    // volume the lines leave (clipped and escaping walks).
    if (!detail::lanes_built) {
        MESSAGE("no AVX-512 lanes in this build: nothing to compare");
        return;
    }
    auto long_lines = presets::tree_c(40);
    long_lines.generator = generator_shape::line({0, -0.5, 0}, {0, 0.5, 0});
    auto leaving = presets::tree_c(50);
    leaving.volume = hypervolume({-0.3, 0.1, -0.3}, {0.6, 0.6, 0.6}, resolution{50, 50, 50});
    for (const auto& def : {presets::tree_c(80), presets::tree_c(300), long_lines, leaving}) {
        INFO(def.name << " at " << def.volume.grid().x);
        const drawn_ifs tree(def, 7);
        const auto tables = detail::lane_tables::of(tree);
        REQUIRE(tables);
        const std::uint64_t cycles[detail::cycle_lanes] = {60, 60, 60, 59, 59, 59, 59, 59};
        const std::size_t segment_voxels = max_voxels_on_segment(def.volume, 2.0 * krs::length((def.generator.end - def.generator.start) * 0.5));
        const auto run = [&](auto overlap) {
            std::uint64_t state[detail::cycle_lanes];
            for (std::uint64_t j = 0; j < detail::cycle_lanes; ++j) state[j] = random_stream::derive(7, j + 1).state();
            std::vector<hit> buffer(detail::chunk_room(def, 475));
            const auto room = [&](hit* end, std::size_t more) {
                REQUIRE(std::size_t(end - buffer.data()) + more <= buffer.size());
                return end;
            };
            std::vector<std::uint64_t> per_depth(std::size_t(def.tree_depth));
            detail::lane_counts counts{0, 0, 0, per_depth.data()};
            hit* const end = detail::generate_in_lanes<true, decltype(overlap)::value>(tree, *tables, state, cycles, buffer.data(), counts,
                                                                                       segment_voxels, room);
            std::vector<std::tuple<voxel_index, int, int>> hits;
            for (const hit* h = buffer.data(); h != end; ++h) hits.emplace_back(h->voxel, h->level, h->part);
            return std::pair(hits, counts.escaped);
        };
        const auto [overlapped, escaped] = run(std::true_type{});
        const auto [one_by_one, escaped_one_by_one] = run(std::false_type{});
        CHECK(overlapped.size() > 1000);
        REQUIRE(overlapped.size() == one_by_one.size());
        std::size_t differ = 0;
        for (std::size_t i = 0; i < overlapped.size(); ++i) differ += overlapped[i] != one_by_one[i];
        CHECK(differ == 0);
        CHECK(escaped == escaped_one_by_one);
    }
}

TEST_CASE("hypertree generator chunks never outgrow the room they start with")
{
    // Each chunk makes room for the most hits it can record before it starts, so it never copies
    // itself into a larger buffer: with scratch memory, generation takes exactly one block per
    // chunk. Points and lines (long ones too), lanes in step and one by one.
    for (auto t : {presets::tree_a(30), presets::tree_c(60), presets::tree_c(200)}) {
        t.iterations = 20000;
        for (const bool lanes : {true, false}) {
            INFO(t.name << " at " << t.volume.grid().x << (lanes ? ", lanes in step" : ", lanes one by one"));
            scratch_memory scratch;
            generation_options options;
            options.chunk_cycles = 300;
            options.vector_lanes = lanes;
            options.scratch = &scratch;
            const auto generated = generate(t, 4, options);
            const std::uint64_t cycles = (t.iterations + std::uint64_t(t.tree_depth) - 1) / std::uint64_t(t.tree_depth);
            CHECK(scratch.system_allocations() == (cycles + options.chunk_cycles - 1) / options.chunk_cycles);
            CHECK(generated.hits.size() > 1000);
        }
    }
}

TEST_CASE("hypertree hard cases: resolution 1 and a dense store over the budget")
{
    auto t = presets::tree_a(1);
    t.iterations = 5000;
    const auto one = build_tree<index_list_store>(t, 1);
    CHECK(one.nonempty_count() == 1);
    CHECK(one.at(0).density == 255); // the trunk's level 0 is a branch level: full density
    CHECK(one.at(0).level == 0);     // the shallowest level prevails
    const auto dense_one = build_tree<dense_store>(t, 1);
    CHECK(dense_one.at(0) == one.at(0));

    // Refused before allocating: 1200^3 voxels at 2 bytes each is 3.5 GB against a 64 MiB budget.
    auto big = presets::tree_a(1200);
    big.iterations = 1000;
    build_options small_budget;
    small_budget.generation.budget.bytes = std::size_t(64) << 20;
    CHECK_THROWS_WITH_AS(build_tree<dense_store>(big, 1, small_budget), doctest::Contains("dense_store"), krs::invalid_parameter);
    CHECK_NOTHROW(build_tree<index_list_store>(big, 1, small_budget));
}

// ---- noise at generation (section 3.5) and trimming during generation (section 7) ----------------

TEST_CASE("hypertree generation noise: no generator moves more than its amplitude per axis, and they do move")
{
    // The same seed with and without noise: the noise draws no random numbers, so the runs make
    // the same generators in the same order and each event pairs with its unperturbed twin. The
    // bound is checked by brute force over every generator, per axis (z has amplitude 0 and must
    // not move at all).
    for (const bool line : {false, true}) {
        CAPTURE(line);
        auto plain = small_tree();
        plain.iterations = 30000;
        if (line) plain.generator = generator_shape::line({0, -0.02, 0}, {0, 0.02, 0});
        auto noisy = plain;
        noisy.perturb.amplitude = {0.01, 0.03, 0.0};
        noisy.perturb.frequency = 6;
        std::vector<generator_event> a, b;
        std::vector<vec3d> a_ends, b_ends;
        const auto keep = [](std::vector<generator_event>& events, std::vector<vec3d>& ends) {
            return [&](const generator_event& e) {
                events.push_back(e);
                ends.push_back(e.end);
            };
        };
        generate(plain, 9, {}, keep(a, a_ends));
        const generated_hits noisy_hits = generate(noisy, 9, {}, keep(b, b_ends));
        REQUIRE(a.size() == b.size());
        REQUIRE(a.size() > 20000);
        vec3d most{0, 0, 0};
        std::size_t moved = 0, recorded = 0;
        std::set<voxel_index> voxels_of_points;
        for (std::size_t k = 0; k < a.size(); ++k) {
            REQUIRE(a[k].depth == b[k].depth);
            const vec3d d = b[k].start - a[k].start, de = b_ends[k] - a_ends[k];
            // A line moves whole: both ends by the same shift.
            CHECK(krs::length(d - de) < 1e-12);
            if (!a[k].recorded) {
                CHECK(krs::length(d) == 0.0); // only recorded generators move
                continue;
            }
            ++recorded;
            most = krs::max(most, vec3d{std::abs(d.x), std::abs(d.y), std::abs(d.z)});
            moved += krs::length(d) > 1e-4;
            if (!line)
                if (const auto v = noisy.volume.voxel_at(b[k].start)) voxels_of_points.insert(*v);
        }
        CHECK(most.x <= 0.01);
        CHECK(most.y <= 0.03);
        CHECK(most.z == 0.0);
        // Value noise reaches well past half its range somewhere among thousands of generators.
        CHECK(most.x > 0.005);
        CHECK(most.y > 0.015);
        CHECK(moved > recorded * 9 / 10);
        if (!line) {
            // The recorded voxels are those of the perturbed points (not of the unperturbed ones).
            const std::set<voxel_index> hit_voxels = [&] {
                std::set<voxel_index> s;
                for (const hit& h : noisy_hits.hits) s.insert(h.voxel);
                return s;
            }();
            CHECK(hit_voxels == voxels_of_points);
        }
    }
}

TEST_CASE("hypertree generation noise: amplitudes and frequency are validated by name")
{
    const auto refused = [](auto change, const char* name) {
        auto t = small_tree();
        change(t);
        krs_test::rejects_naming([&] { t.validate(); }, name);
    };
    const double nan = std::numeric_limits<double>::quiet_NaN(), inf = std::numeric_limits<double>::infinity();
    refused([&](auto& t) { t.perturb.amplitude.x = -0.01; }, "ifs.perturb.amplitude.x");
    refused([&](auto& t) { t.perturb.amplitude.y = nan; }, "ifs.perturb.amplitude.y");
    refused([&](auto& t) { t.perturb.amplitude.z = inf; }, "ifs.perturb.amplitude.z");
    refused([&](auto& t) { t.perturb.frequency = -1; }, "ifs.perturb.frequency");
    refused([&](auto& t) { t.perturb.frequency = inf; }, "ifs.perturb.frequency");
    refused([&](auto& t) { t.perturb.frequency = nan; }, "ifs.perturb.frequency");
}

namespace {
// Inside tests written out from the regions' definitions, not through their contains().
struct inside_reference {
    std::vector<std::function<bool(const vec3d&)>> tests;
    bool operator()(const vec3d& p) const
    {
        for (const auto& t : tests)
            if (t(p)) return true;
        return false;
    }
};
} // namespace

TEST_CASE("hypertree trimming during generation: no hit and no voxel inside a region, everything else as untrimmed")
{
    auto plain = small_tree();
    plain.iterations = 40000;
    // A box around the stem's middle, a ball on the crown and everything above a tilted plane.
    const vec3d box_lo{-0.2, 0.2, -0.2}, box_hi{0.2, 0.5, 0.2}, ball{0.2, 0.9, 0.0};
    const double ball_radius = 0.25;
    const vec3d plane_point{0, 1.2, 0}, plane_normal = krs::normalize(vec3d{0.3, 1, 0});
    struct trial {
        std::string name;
        std::vector<trim_region> regions;
        inside_reference inside;
    };
    const auto in_box = [=](const vec3d& p) {
        return box_lo.x <= p.x && p.x <= box_hi.x && box_lo.y <= p.y && p.y <= box_hi.y && box_lo.z <= p.z && p.z <= box_hi.z;
    };
    const auto in_ball = [=](const vec3d& p) {
        const vec3d d = p - ball;
        return d.x * d.x + d.y * d.y + d.z * d.z <= ball_radius * ball_radius;
    };
    const auto above = [=](const vec3d& p) {
        const vec3d d = p - plane_point;
        return d.x * plane_normal.x + d.y * plane_normal.y + d.z * plane_normal.z >= 0;
    };
    const std::vector<trial> trials = {
        {"box", {box_region(box_lo, box_hi)}, {{in_box}}},
        {"sphere", {sphere_region(ball, ball_radius)}, {{in_ball}}},
        {"half-space", {half_space_region(plane_point, plane_normal)}, {{above}}},
        {"all three", {box_region(box_lo, box_hi), sphere_region(ball, ball_radius), half_space_region(plane_point, plane_normal)}, {{in_box, in_ball, above}}},
    };
    const generated_hits untrimmed = generate(plain, 5);
    for (const trial& t : trials) {
        CAPTURE(t.name);
        auto trimmed = plain;
        trimmed.trim = t.regions;
        // The reference: the untrimmed hits, in order, less those whose voxel center is inside.
        std::vector<hit> expected;
        for (const hit& h : untrimmed.hits)
            if (!t.inside(plain.volume.voxel_center(h.voxel))) expected.push_back(h);
        const std::size_t inside = untrimmed.hits.size() - expected.size();
        CHECK(inside > 500); // each region does lock something of this tree
        for (const bool lanes : {true, false}) {
            CAPTURE(lanes);
            generation_options options;
            options.vector_lanes = lanes;
            const generated_hits got = generate(trimmed, 5, options);
            CHECK(got.stats.locked == inside);
            // Lanes in step may order hits differently within a chunk: compare as sorted lists.
            auto sorted = [](std::vector<hit> v) {
                std::sort(v.begin(), v.end(), [](const hit& a, const hit& b) {
                    return std::tie(a.voxel, a.level, a.part) < std::tie(b.voxel, b.level, b.part);
                });
                return v;
            };
            const auto g = sorted(got.hits), e = sorted(expected);
            REQUIRE(g.size() == e.size());
            bool same = true;
            for (std::size_t k = 0; k < g.size(); ++k) same = same && g[k].voxel == e[k].voxel && g[k].level == e[k].level && g[k].part == e[k].part;
            CHECK(same);
        }
        // The built store: brute force over every voxel, none inside a region is stored.
        const auto store = build_tree<index_list_store>(trimmed, 5);
        std::size_t stored_inside = 0;
        for_each_stored(store, [&](const stored_voxel& v) { stored_inside += t.inside(plain.volume.voxel_center(v.index)); });
        CHECK(stored_inside == 0);
        CHECK(store.nonempty_count() > 300);
    }
}

TEST_CASE("hypertree trimming during generation differs from clearing afterwards in densities, not in voxels")
{
    // Density classes are placed on the population of hit voxels (create/density.hpp). Clearing a
    // region afterwards keeps the classes the region's voxels helped place; locking them during
    // generation places the classes on what is left. So: the same voxels and levels either way,
    // densities that differ, and the trimmed tree's densities are those of classifying the
    // untrimmed hits outside the region (the reference, built from generate(), compact() and
    // classify()).
    auto plain = small_tree();
    plain.iterations = 60000;
    plain.branch_depth = 0; // every voxel's density from its class (branch voxels are always full)
    const sphere_region crown({0.0, 0.85, 0.0}, 0.35); // the dense crown: many voxels, many hits
    auto trimmed = plain;
    trimmed.trim = {crown};
    build_options options;
    options.density_class_count = 8;
    const auto whole = build_tree<index_list_store>(plain, 13, options);
    const auto cleared = clear_store(whole, crown);
    const auto locked = build_tree<index_list_store>(trimmed, 13, options);

    const auto a = stored_voxels(cleared), b = stored_voxels(locked);
    REQUIRE(a.size() == b.size());
    REQUIRE(whole.nonempty_count() > a.size() + 200); // the region held many voxels
    std::size_t differ = 0;
    bool same_voxels = true;
    for (std::size_t k = 0; k < a.size(); ++k) {
        same_voxels = same_voxels && a[k].index == b[k].index && a[k].value.level == b[k].value.level && a[k].part == b[k].part;
        differ += a[k].value.density != b[k].value.density;
    }
    CHECK(same_voxels);
    MESSAGE("trimming during generation vs clearing afterwards: " << differ << " of " << a.size() << " voxels differ in density");
    CHECK(differ > a.size() / 20);

    std::vector<hit> outside;
    for (const hit& h : generate(plain, 13).hits)
        if (krs::length(plain.volume.voxel_center(h.voxel) - vec3d{0.0, 0.85, 0.0}) > 0.35) outside.push_back(h);
    const auto entries = compact(outside);
    const auto expected = classify(entries, density_classes(entries, 8), plain.branch_depth);
    REQUIRE(expected.size() == b.size());
    std::size_t mismatched = 0;
    for (std::size_t k = 0; k < b.size(); ++k)
        mismatched += expected[k].index != b[k].index || expected[k].value.density != b[k].value.density || expected[k].value.level != b[k].value.level;
    CHECK(mismatched == 0);
}

TEST_CASE("hypertree trim regions are validated by name: NaN, negative and empty regions")
{
    const auto refused = [](std::vector<trim_region> regions, std::function<void(trim_region&)> spoil, const char* name) {
        auto t = small_tree();
        t.trim = std::move(regions);
        if (spoil) spoil(t.trim.back());
        krs_test::rejects_naming([&] { t.validate(); }, name);
    };
    const double nan = std::numeric_limits<double>::quiet_NaN();
    const box_region box({-0.1, 0.2, -0.1}, {0.1, 0.4, 0.1});
    const sphere_region ball({0, 0.5, 0}, 0.2);
    const half_space_region plane({0, 1.5, 0}, {0, 1, 0});
    refused({box}, [&](trim_region& r) { std::get<box_region>(r).lo.x = nan; }, "ifs.trim[0].lo");
    refused({box}, [&](trim_region& r) { std::get<box_region>(r).hi.y = 0.0; }, "ifs.trim[0].hi");
    refused({box, ball}, [&](trim_region& r) { std::get<sphere_region>(r).radius = -1; }, "ifs.trim[1].radius");
    refused({ball}, [&](trim_region& r) { std::get<sphere_region>(r).center.z = nan; }, "ifs.trim[0].center");
    refused({plane}, [&](trim_region& r) { std::get<half_space_region>(r).normal = {0, 0, 0}; }, "ifs.trim[0].normal");
    refused({plane}, [&](trim_region& r) { std::get<half_space_region>(r).normal = {0, 2, 0}; }, "ifs.trim[0].normal");
    refused({plane}, [&](trim_region& r) { std::get<half_space_region>(r).point.x = nan; }, "ifs.trim[0].point");
    // Empty: a ball between voxel centers, a box outside the volume, a half-space beyond it.
    const hypervolume v = small_tree().volume;
    const vec3d corner = v.origin(); // a voxel corner: its nearest centers are half a diagonal away
    refused({sphere_region(corner + v.voxel_size() * 1.0, 0.1 * v.smallest_voxel_side())}, {}, "ifs.trim[0]");
    refused({box_region({5, 5, 5}, {6, 6, 6})}, {}, "ifs.trim[0]");
    refused({box, half_space_region({0, 3, 0}, {0, 1, 0})}, {}, "ifs.trim[1]");
    // A region that holds a voxel passes.
    auto t = small_tree();
    t.trim = {box, ball, plane};
    CHECK_NOTHROW(t.validate());
}

// Level of detail (paper section 9, figure 5): resolution reduction against brute-force
// references written here. The references walk every new voxel of the grid and integrate the old
// voxels' overlaps in floating point, which is independent of the library's integer scatter over
// non-empty voxels.

#include "hypertree/build.hpp"
#include "hypertree/lod.hpp"
#include "hypertree/presets.hpp"
#include "hypertree/store/store_kinds.hpp"

#include "support/voxel_reference.hpp"

#include <doctest/doctest.h>

#include <algorithm>
#include <array>
#include <cmath>
#include <cstdint>
#include <map>
#include <random>
#include <string>
#include <vector>

namespace {
using hypertree::averaged_voxel;
using hypertree::hypervolume;
using hypertree::resolution;
using hypertree::stored_voxel;
using hypertree::voxel;
using hypertree::voxel_index;
using krs::vec3d;

// A random sparse volume from its own seed (support/voxel_reference.hpp): levels 0..5, parts 0..3.
std::vector<stored_voxel> random_voxels(const hypervolume& volume, double fill, std::uint64_t seed)
{
    std::mt19937_64 g(seed);
    return krs_test::random_voxels(g, volume, fill, 4, 6);
}

// Every voxel of the grid, empty ones included (density 0).
std::vector<stored_voxel> every_voxel(const hypervolume& volume, const std::vector<stored_voxel>& voxels)
{
    std::vector<stored_voxel> grid(volume.voxel_count());
    for (std::size_t i = 0; i < grid.size(); ++i) grid[i] = {voxel_index(i), voxel{}, 0};
    for (const stored_voxel& v : voxels) grid[v.index] = v;
    return grid;
}

struct reference_voxel {
    double density = 0;
    bool touched = false;                 // some non-empty old voxel overlaps it
    std::vector<std::uint8_t> levels;     // the most represented level (empty when untouched)
    std::vector<std::uint8_t> parts;      // the heaviest contributor's part
    bool near_half = false;               // density within 1e-6 of x.5: either rounding is fine
};

// The brute-force reduction: for every new voxel, the old voxels inside its span per axis and
// their overlap lengths in floating point (lengths below 1e-9 are boundary noise, not overlap).
std::vector<reference_voxel> brute_force_reduce(const hypervolume& volume, const std::vector<stored_voxel>& voxels,
                                                resolution target)
{
    const std::vector<stored_voxel> grid = every_voxel(volume, voxels);
    const resolution n = volume.grid();
    const double rx = double(n.x) / target.x, ry = double(n.y) / target.y, rz = double(n.z) / target.z;
    const auto overlaps = [](int k, double r, int cells) {
        std::vector<std::pair<int, double>> out;
        const double lo = k * r, hi = (k + 1) * r;
        for (int i = std::max(0, int(std::floor(lo)) - 1); i < std::min(cells, int(std::ceil(hi)) + 1); ++i) {
            const double o = std::min(i + 1.0, hi) - std::max(double(i), lo);
            if (o > 1e-9) out.emplace_back(i, o);
        }
        return out;
    };
    std::vector<reference_voxel> result(std::size_t(target.x) * target.y * target.z);
    for (int c = 0; c < target.z; ++c)
        for (int b = 0; b < target.y; ++b)
            for (int a = 0; a < target.x; ++a) {
                reference_voxel& out = result[std::size_t(a + target.x * (b + target.y * c))];
                std::map<int, double> level_weight;
                std::map<int, double> part_mass; // heaviest contributor's mass per part
                double sum = 0;
                for (const auto& [z, wz] : overlaps(c, rz, n.z))
                    for (const auto& [y, wy] : overlaps(b, ry, n.y))
                        for (const auto& [x, wx] : overlaps(a, rx, n.x)) {
                            const stored_voxel& v = grid[volume.index(x, y, z)];
                            if (v.value.density == 0) continue;
                            const double w = wx * wy * wz;
                            sum += w * v.value.density;
                            level_weight[v.value.level] += w;
                            part_mass[v.part] = std::max(part_mass[v.part], w * v.value.density);
                            out.touched = true;
                        }
                out.density = sum / (rx * ry * rz);
                const double fraction = out.density - std::floor(out.density);
                out.near_half = std::abs(fraction - 0.5) < 1e-6;
                double best = 0;
                for (const auto& [l, w] : level_weight) best = std::max(best, w);
                // The shallowest of the (near-)heaviest levels: overlaps are multiples of 1/23 or so,
                // so weights within 1e-9 are exact ties, which the shallowest level wins; the same
                // for the heaviest contributor's part (ties: the smaller part).
                for (const auto& [l, w] : level_weight)
                    if (w >= best - 1e-9) {
                        out.levels.push_back(std::uint8_t(l));
                        break;
                    }
                double heaviest = 0;
                for (const auto& [p, m] : part_mass) heaviest = std::max(heaviest, m);
                for (const auto& [p, m] : part_mass)
                    if (m >= heaviest - 1e-9) {
                        out.parts.push_back(std::uint8_t(p));
                        break;
                    }
            }
    return result;
}

bool contains(const std::vector<std::uint8_t>& list, std::uint8_t v)
{
    return std::find(list.begin(), list.end(), v) != list.end();
}

// Compares reduce_unrounded and reduce with the brute-force reference on every new voxel.
void check_against_brute_force(const hypervolume& volume, const std::vector<stored_voxel>& voxels, resolution target)
{
    CAPTURE(target.x);
    CAPTURE(target.y);
    CAPTURE(target.z);
    const auto store = hypertree::partitioned_store::build(volume, voxels);
    const std::vector<reference_voxel> expected = brute_force_reduce(volume, voxels, target);
    const std::vector<averaged_voxel> unrounded = hypertree::reduce_unrounded(store, target);
    const std::vector<stored_voxel> rounded = hypertree::reduce(store, target);
    const hypervolume reduced = hypertree::reduced_volume(volume, target);

    std::vector<const averaged_voxel*> unrounded_at(expected.size(), nullptr);
    for (const averaged_voxel& v : unrounded) unrounded_at[v.index] = &v;
    std::vector<const stored_voxel*> rounded_at(expected.size(), nullptr);
    for (const stored_voxel& v : rounded) rounded_at[v.index] = &v;
    CHECK(std::is_sorted(rounded.begin(), rounded.end(), [](auto& a, auto& b) { return a.index < b.index; }));
    CHECK(std::adjacent_find(rounded.begin(), rounded.end(), [](auto& a, auto& b) { return a.index == b.index; }) ==
          rounded.end());

    int mismatches = 0;
    for (std::size_t i = 0; i < expected.size(); ++i) {
        const reference_voxel& e = expected[i];
        const averaged_voxel* u = unrounded_at[i];
        const stored_voxel* r = rounded_at[i];
        bool ok = (u != nullptr) == e.touched;
        if (u) {
            ok = ok && std::abs(u->density - e.density) < 1e-9 && contains(e.levels, u->level) && contains(e.parts, u->part);
        }
        const long nearest = long(std::floor(e.density + 0.5));
        const int got = r ? r->value.density : 0;
        ok = ok && (got == nearest || (e.near_half && std::abs(got - e.density) <= 0.5 + 1e-6));
        if (r && u) ok = ok && r->value.level == u->level && r->part == u->part;
        if (!ok && ++mismatches <= 5) {
            const auto c = reduced.coordinates(voxel_index(i));
            FAIL_CHECK("new voxel (" << c[0] << ", " << c[1] << ", " << c[2] << "): reference density " << e.density
                                     << ", unrounded " << (u ? u->density : -1.0) << ", rounded " << got << ", level "
                                     << (u ? int(u->level) : -1) << ", part " << (u ? int(u->part) : -1));
        }
    }
    CHECK(mismatches == 0);
}

double integral_of(const hypervolume& volume, const std::vector<stored_voxel>& voxels)
{
    return hypertree::density_integral(volume, voxels);
}

// Tree A of the presets, small enough for a fast test.
hypertree::index_list_store small_tree_a(int resolution_)
{
    auto definition = hypertree::presets::tree_a(resolution_);
    definition.iterations = 100000;
    return hypertree::build_tree<hypertree::index_list_store>(definition, 20240601);
}

} // namespace

TEST_CASE("hypertree lod factor 2 equals the average of each 2x2x2 block")
{
    const hypervolume volume({-1, 0, 2}, {2, 1.5, 1}, {24, 20, 16});
    const std::vector<stored_voxel> voxels = random_voxels(volume, 0.3, 11);
    const std::vector<stored_voxel> grid = every_voxel(volume, voxels);
    const resolution target{12, 10, 8};
    const auto store = hypertree::partitioned_store::build(volume, voxels);
    const std::vector<stored_voxel> reduced = hypertree::reduce(store, target);
    const hypervolume small = hypertree::reduced_volume(volume, target);
    const std::vector<stored_voxel> reduced_grid = every_voxel(small, reduced);

    int mismatches = 0;
    for (int c = 0; c < target.z; ++c)
        for (int b = 0; b < target.y; ++b)
            for (int a = 0; a < target.x; ++a) {
                int sum = 0, heaviest = -1, part = 0;
                std::array<int, 256> count{};
                for (int dz = 0; dz < 2; ++dz)
                    for (int dy = 0; dy < 2; ++dy)
                        for (int dx = 0; dx < 2; ++dx) {
                            const stored_voxel& v = grid[volume.index(2 * a + dx, 2 * b + dy, 2 * c + dz)];
                            if (v.value.density == 0) continue;
                            sum += v.value.density;
                            ++count[v.value.level];
                            if (v.value.density > heaviest || (v.value.density == heaviest && v.part < part))
                                heaviest = v.value.density, part = v.part;
                        }
                // Round half up: sum / 8 + 1/2, in integers.
                const int density = (2 * sum + 8) / 16;
                const int level = int(std::max_element(count.begin(), count.end()) - count.begin()); // first = shallowest
                const stored_voxel& got = reduced_grid[small.index(a, b, c)];
                const bool ok = got.value.density == density &&
                                (density == 0 || (got.value.level == level && got.part == part));
                if (!ok && ++mismatches <= 5)
                    FAIL_CHECK("block (" << a << ", " << b << ", " << c << "): expected density " << density << " level "
                                         << level << " part " << part << ", got " << int(got.value.density) << " "
                                         << int(got.value.level) << " " << int(got.part));
            }
    CHECK(mismatches == 0);
    CHECK(small.origin().x == volume.origin().x);
    CHECK(small.extent().y == volume.extent().y);
    CHECK(small.grid() == target);
}

TEST_CASE("hypertree lod fractional factors match a brute-force overlap integration")
{
    SUBCASE("37 cubed to 23 cubed")
    {
        const hypervolume volume({0, 0, 0}, {1, 1, 1}, resolution::cube(37));
        check_against_brute_force(volume, random_voxels(volume, 0.2, 5), resolution::cube(23));
    }
    SUBCASE("300 to 200 per axis, scaled down: 30 to 20")
    {
        const hypervolume volume({0, 0, 0}, {1, 1, 1}, resolution::cube(30));
        check_against_brute_force(volume, random_voxels(volume, 0.25, 6), resolution::cube(20));
    }
    SUBCASE("1000 to 400, scaled down: 25 to 10 (factor 2.5, more than 27 old voxels)")
    {
        const hypervolume volume({0, 0, 0}, {1, 1, 1}, resolution::cube(25));
        check_against_brute_force(volume, random_voxels(volume, 0.25, 7), resolution::cube(10));
    }
    SUBCASE("different factors per axis, one above 2")
    {
        const hypervolume volume({-3, 1, 0}, {1, 2, 0.5}, {37, 29, 31});
        check_against_brute_force(volume, random_voxels(volume, 0.15, 8), {23, 20, 11});
    }
    SUBCASE("a generated tree")
    {
        const auto tree = small_tree_a(60);
        check_against_brute_force(tree.volume(), hypertree::stored_voxels(tree), resolution::cube(37));
    }
}

TEST_CASE("hypertree lod level is the most represented level and part the heaviest contributor")
{
    using hypertree::partitioned_store;
    SUBCASE("factor 2: counts decide, not densities")
    {
        const hypervolume volume({0, 0, 0}, {2, 1, 1}, {4, 2, 2});
        // New voxel 0 (x 0..1): three faint voxels of level 4 outnumber two dense ones of level 1.
        // New voxel 1 (x 2..3): two of level 3 against two of level 2, a tie: the shallower wins.
        std::vector<stored_voxel> voxels{
            {volume.index(0, 0, 0), voxel{10, 4}, 1},  {volume.index(1, 0, 0), voxel{10, 4}, 1},
            {volume.index(2, 0, 0), voxel{50, 3}, 2},  {volume.index(3, 0, 0), voxel{60, 2}, 3},
            {volume.index(0, 1, 0), voxel{255, 1}, 0}, {volume.index(1, 1, 0), voxel{10, 4}, 1},
            {volume.index(2, 1, 0), voxel{60, 3}, 2},  {volume.index(3, 1, 0), voxel{50, 2}, 3},
            {volume.index(1, 0, 1), voxel{255, 1}, 0},
        };
        std::sort(voxels.begin(), voxels.end(), [](auto& a, auto& b) { return a.index < b.index; });
        const auto reduced = hypertree::reduce(partitioned_store::build(volume, voxels), {2, 1, 1});
        REQUIRE(reduced.size() == 2);
        CHECK(reduced[0].value.level == 4);
        CHECK(reduced[0].value.density == (10 * 3 + 255 * 2 + 4) / 8); // 540 / 8 = 67.5 rounds up
        CHECK(reduced[0].part == 0);                                   // a 255 voxel is the heaviest
        CHECK(reduced[1].value.level == 2);
        CHECK(reduced[1].value.density == (50 + 60 + 60 + 50 + 4) / 8);
        CHECK(reduced[1].part == 2); // two 60s tie: parts 2 and 3, the smaller wins
    }
    SUBCASE("factor 1.5: shared lengths decide")
    {
        const hypervolume volume({0, 0, 0}, {3, 1, 1}, {3, 1, 1});
        // New voxel 0 spans old [0, 1.5): all of voxel 0, half of voxel 1; new voxel 1 the rest.
        const std::vector<stored_voxel> voxels{{0, voxel{30, 5}, 1}, {1, voxel{200, 2}, 2}, {2, voxel{90, 7}, 3}};
        const auto unrounded = hypertree::reduce_unrounded(partitioned_store::build(volume, voxels), {2, 1, 1});
        REQUIRE(unrounded.size() == 2);
        CHECK(unrounded[0].density == doctest::Approx((30 * 1.0 + 200 * 0.5) / 1.5));
        CHECK(unrounded[0].level == 5);
        CHECK(unrounded[0].part == 2); // 200 * 0.5 = 100 outweighs 30 * 1
        CHECK(unrounded[1].density == doctest::Approx((200 * 0.5 + 90 * 1.0) / 1.5));
        CHECK(unrounded[1].level == 7);
        CHECK(unrounded[1].part == 2); // 100 against 90
    }
}

TEST_CASE("hypertree lod preserves the density integral")
{
    const auto check = [](const hypervolume& volume, const std::vector<stored_voxel>& voxels, resolution target) {
        CAPTURE(target.x);
        CAPTURE(target.y);
        CAPTURE(target.z);
        const auto store = hypertree::index_list_store::build(volume, voxels);
        const hypervolume small = hypertree::reduced_volume(volume, target);
        const double before = integral_of(volume, voxels);
        const auto unrounded = hypertree::reduce_unrounded(store, target);
        const auto rounded = hypertree::reduce(store, target);
        const double exact = hypertree::density_integral(small, unrounded);
        REQUIRE(before > 0);
        // The library sums in integers, so only the final double arithmetic errs (the brief's
        // bound is 1e-3 relative; this is far below it).
        CHECK(std::abs(exact - before) <= 1e-9 * before);
        // Rounding moves each new voxel by at most 1/2 density unit.
        const vec3d& s = small.voxel_size();
        const double rounding_bound = 0.5 * double(unrounded.size()) * s.x * s.y * s.z;
        CHECK(std::abs(integral_of(small, rounded) - before) <= rounding_bound);
        CHECK(hypertree::density_integral(store) == doctest::Approx(before).epsilon(1e-12));
    };
    const hypervolume volume({0, 0, 0}, {1, 2, 1}, {40, 50, 30});
    const auto voxels = random_voxels(volume, 0.1, 21);
    check(volume, voxels, {27, 33, 20});
    check(volume, voxels, {20, 25, 15});
    check(volume, voxels, {7, 3, 1});
    check(volume, voxels, {1, 1, 1});
    const auto tree = small_tree_a(100);
    const auto tree_voxels = hypertree::stored_voxels(tree);
    check(tree.volume(), tree_voxels, resolution::cube(73));
    check(tree.volume(), tree_voxels, resolution::cube(40));

    // Reduced to one voxel, the density is the mean over the whole grid.
    const auto one = hypertree::reduce_unrounded(hypertree::index_list_store::build(volume, voxels), {1, 1, 1});
    double sum = 0;
    for (const auto& v : voxels) sum += v.value.density;
    REQUIRE(one.size() == 1);
    CHECK(one[0].density == doctest::Approx(sum / double(volume.voxel_count())).epsilon(1e-12));
}

TEST_CASE_TEMPLATE_DEFINE("hypertree lod identity returns the same voxels", S, lod_identity)
{
    const hypervolume volume({0, 0, 0}, {1, 1, 1}, {17, 13, 11});
    const auto voxels = random_voxels(volume, 0.3, 31);
    const S store = S::build(volume, voxels);
    const auto same = hypertree::reduce(store, volume.grid());
    const auto original = hypertree::stored_voxels(store);
    REQUIRE(same.size() == original.size());
    for (std::size_t k = 0; k < same.size(); ++k) {
        CHECK(same[k].index == original[k].index);
        CHECK(same[k].value == original[k].value);
        CHECK(same[k].part == original[k].part);
    }
    const S rebuilt = hypertree::reduce_store(store, volume.grid());
    CHECK(rebuilt.volume() == volume);
    CHECK(rebuilt.nonempty_count() == store.nonempty_count());
}
TEST_CASE_TEMPLATE_APPLY(lod_identity, hypertree::store_kinds);

TEST_CASE("hypertree lod every store kind reduces alike")
{
    const hypervolume volume({0, 0, 0}, {1, 1, 1}, {21, 19, 23});
    const auto voxels = random_voxels(volume, 0.2, 41);
    const resolution target{13, 12, 9};
    const auto expected = hypertree::reduce(hypertree::partitioned_store::build(volume, voxels), target);
    const auto same_values = [&](const std::vector<stored_voxel>& got) {
        bool ok = got.size() == expected.size();
        for (std::size_t k = 0; ok && k < got.size(); ++k)
            ok = got[k].index == expected[k].index && got[k].value.density == expected[k].value.density;
        return ok;
    };
    // Every kind, the partitioned one included (against itself, built again).
    hypertree::for_each_store_kind([&]<class S>() {
        INFO(hypertree::store_kind_name<S>);
        CHECK(same_values(hypertree::reduce(S::build(volume, voxels), target)));
    });
    // reduce_store into another kind holds the same voxels over the reduced volume.
    const auto source = hypertree::partitioned_store::build(volume, voxels);
    const auto dense = hypertree::reduce_store<hypertree::dense_store>(source, target);
    CHECK(dense.volume() == hypertree::reduced_volume(volume, target));
    CHECK(same_values(hypertree::stored_voxels(dense)));
}

// Section 9: "a chain reduction of hypertree resolution can yield a result that differs from the
// result of a single conversion". Measured on tree A (100 000 iterations), 100 -> 40 directly and
// through 80 and 60: over the voxels non-empty in either result, a mean absolute difference of
// 2.4 density units and 3.5 % of the voxels differing by more than 16/255 (at 1000 -> 400 via 800
// and 600 with the preset's 500 000 iterations: 1.2 units and 0.25 %). The bounds below are
// about three times those figures.
TEST_CASE("hypertree lod chain reduction stays close to a single step")
{
    const auto tree = small_tree_a(100);
    const resolution target = resolution::cube(40);
    const auto single = hypertree::reduce(tree, target);
    const auto through_80 = hypertree::reduce_store(tree, resolution::cube(80));
    const auto through_60 = hypertree::reduce_store(through_80, resolution::cube(60));
    const auto chained = hypertree::reduce(through_60, target);

    const hypervolume small = hypertree::reduced_volume(tree.volume(), target);
    const auto a = every_voxel(small, single), b = every_voxel(small, chained);
    double absolute = 0;
    std::size_t union_count = 0, far_apart = 0, level_differs = 0;
    for (std::size_t i = 0; i < a.size(); ++i) {
        if (a[i].value.density == 0 && b[i].value.density == 0) continue;
        ++union_count;
        const int d = std::abs(int(a[i].value.density) - int(b[i].value.density));
        absolute += d;
        far_apart += d > 16;
        level_differs += a[i].value.level != b[i].value.level && a[i].value.density && b[i].value.density;
    }
    REQUIRE(union_count > 1000);
    const double mean = absolute / double(union_count);
    const double share = double(far_apart) / double(union_count);
    CAPTURE(mean);
    CAPTURE(share);
    CAPTURE(level_differs);
    CAPTURE(union_count);
    CHECK(mean < 7.5);
    CHECK(share < 0.1);
    // Both keep the density integral up to the rounding of each step (measured: 0.03 % and 0.01 %).
    const double before = hypertree::density_integral(tree);
    CHECK(std::abs(integral_of(small, single) - before) < 0.01 * before);
    CHECK(std::abs(integral_of(small, chained) - before) < 0.01 * before);
}

TEST_CASE("hypertree lod refuses targets above the source resolution or below 1")
{
    const hypervolume volume({0, 0, 0}, {1, 1, 1}, {10, 8, 6});
    const auto store = hypertree::index_list_store::build(volume, random_voxels(volume, 0.2, 51));
    const auto refused = [&](resolution target, const std::string& parameter) {
        CAPTURE(parameter);
        try {
            (void)hypertree::reduce(store, target);
            FAIL_CHECK("accepted " << target.x << " x " << target.y << " x " << target.z);
        } catch (const krs::invalid_parameter& e) {
            CHECK(e.parameter() == parameter);
            CHECK(std::string(e.what()).find("between 1 and the source resolution") != std::string::npos);
        }
        CHECK_THROWS_AS((void)hypertree::reduced_volume(volume, target), krs::invalid_parameter);
        CHECK_THROWS_AS((void)hypertree::reduce_unrounded(store, target), krs::invalid_parameter);
        CHECK_THROWS_AS((void)hypertree::reduce_store(store, target), krs::invalid_parameter);
    };
    refused({11, 8, 6}, "reduce.target.x");
    refused({10, 9, 6}, "reduce.target.y");
    refused({10, 8, 7}, "reduce.target.z");
    refused({0, 8, 6}, "reduce.target.x");
    refused({10, -1, 6}, "reduce.target.y");
    CHECK_NOTHROW((void)hypertree::reduce(store, {1, 1, 1}));
}

TEST_CASE("hypertree lod resolution for the projected voxel size")
{
    using hypertree::resolution_for_projected_voxel;
    const hypervolume cube({0, 0, 0}, {1, 1, 1}, resolution::cube(300));
    // Pixel side at distance 10 with footprint 1e-3: 0.01, so 100 voxels of side 0.01 per unit.
    CHECK(resolution_for_projected_voxel(cube, 10, 1e-3) == resolution::cube(100));
    CHECK(resolution_for_projected_voxel(cube, 0, 1e-3) == resolution::cube(300)); // inside: all detail
    CHECK(resolution_for_projected_voxel(cube, 1, 1e-3) == resolution::cube(300)); // never above the source
    CHECK(resolution_for_projected_voxel(cube, 1e9, 1e-3) == resolution::cube(1)); // never below 1

    // Non-cubic voxels keep the grid's aspect ratio; the geometric-mean side decides.
    const hypervolume box({0, 0, 0}, {1, 4, 1}, {100, 200, 100}); // voxels 0.01 x 0.02 x 0.01
    const double mean_side = std::cbrt(0.01 * 0.02 * 0.01);
    for (double distance : {3.0, 7.5, 20.0, 55.0}) {
        const double pixel = distance * 1e-3;
        const resolution r = resolution_for_projected_voxel(box, distance, 1e-3);
        CAPTURE(distance);
        const int source[3] = {100, 200, 100}, got[3] = {r.x, r.y, r.z};
        for (int a = 0; a < 3; ++a) {
            const double side = mean_side * source[a] / got[a]; // mean side if every axis shrank alike
            CHECK(side >= pixel * (1 - 1e-9));                  // at least a pixel
            if (got[a] < source[a]) CHECK(mean_side * source[a] / (got[a] + 1) < pixel); // the largest such
        }
        CHECK(r.y == std::min(200, int(std::floor(200 * mean_side / pixel * (1 + 1e-9)))));
    }

    // From a camera: the distance to the nearest point of the box.
    const krs::pinhole_camera camera({0.5f, 0.5f, 11.0f}, {0.5f, 0.5f, 0.5f}, {0, 1, 0}, 40.0f, 640, 480);
    const double footprint = camera.pixel_footprint();
    CHECK(resolution_for_projected_voxel(cube, camera) == resolution_for_projected_voxel(cube, 10.0, footprint));
    const krs::pinhole_camera inside({0.5f, 0.5f, 0.5f}, {0.5f, 0.5f, 2.0f}, {0, 1, 0}, 40.0f, 640, 480);
    CHECK(resolution_for_projected_voxel(cube, inside) == cube.grid());

    CHECK_THROWS_AS((void)resolution_for_projected_voxel(cube, -1, 1e-3), krs::invalid_parameter);
    CHECK_THROWS_AS((void)resolution_for_projected_voxel(cube, 10, 0), krs::invalid_parameter);
    CHECK_THROWS_AS((void)resolution_for_projected_voxel(cube, std::nan(""), 1e-3), krs::invalid_parameter);
}

// The four voxel stores (store/*.hpp) and what they share (store/store.hpp's coordinate walker,
// index divider and bounds, the zeroed arrays they are built in), each against a plain array of
// every voxel of the grid: every voxel, the visit order, the count, the bounds, the memory budget
// and the refusals of bad lists.

#include "hypertree/store/store_kinds.hpp"
#include "hypertree/store/zeroed_array.hpp"

#include "support/random.hpp"
#include "support/voxel_reference.hpp"

#include <doctest/doctest.h>

#include <algorithm>
#include <cstddef>
#include <cstdint>
#include <filesystem>
#include <iterator>
#include <limits>
#include <map>
#include <optional>
#include <random>
#include <string>
#include <string_view>
#include <tuple>
#include <utility>
#include <vector>

namespace {
using hypertree::hypervolume;
using hypertree::stored_voxel;
using hypertree::voxel;
using hypertree::voxel_index;
using krs::vec3d;
using krs_test::bounds_by_hand;
using krs_test::check_visits_the_list;
using krs_test::count_differences;
using krs_test::grid_of;
using krs_test::grid_of_store;
using krs_test::integer;
using krs_test::random_voxels;
using krs_test::small_volume;

// A sparse "tree" at high resolution: one blob of voxels per part around its own center, the
// trunk (part 0) a thin column, as the generator would produce.
std::vector<stored_voxel> tree_like_voxels(std::mt19937_64& g, const hypervolume& volume, int parts,
                                           std::size_t per_part)
{
    std::map<voxel_index, stored_voxel> unique;
    const auto n = volume.grid();
    for (int p = 0; p < parts; ++p) {
        const vec3d c{krs_test::uniform(g, 0.2, 0.8) * n.x, krs_test::uniform(g, 0.2, 0.8) * n.y,
                      krs_test::uniform(g, 0.2, 0.8) * n.z};
        for (std::size_t k = 0; k < per_part; ++k) {
            const vec3d d =
                p == 0 ? vec3d{krs_test::uniform(g, -2, 2), krs_test::uniform(g, -2, 2), krs_test::uniform(g, -60, 60)}
                       : krs_test::in_ball(g, 25.0);
            const int x = std::clamp(int(c.x + d.x), 0, n.x - 1), y = std::clamp(int(c.y + d.y), 0, n.y - 1),
                      z = std::clamp(int(c.z + d.z), 0, n.z - 1);
            const voxel_index i = volume.index(x, y, z);
            // The first part to claim a voxel keeps it: each voxel is in exactly one part.
            unique.emplace(
                i, stored_voxel{i, voxel{std::uint8_t(integer(g, 1, 255)), std::uint8_t(p == 0 ? 0 : integer(g, 1, 6))},
                                std::uint8_t(p)});
        }
    }
    std::vector<stored_voxel> voxels;
    for (const auto& [i, v] : unique) voxels.push_back(v);
    return voxels;
}
} // namespace

TEST_CASE("the coordinate walker places every index as the volume does, in any order")
{
    std::mt19937_64 g(77);
    using hypertree::resolution;
    for (const resolution grid : {resolution{7, 5, 9}, resolution{300, 300, 300}, resolution{1, 1, 40}, resolution{40, 1, 1}}) {
        const hypervolume volume({0, 0, 0}, {1, 1, 1}, grid);
        const voxel_index count = voxel_index(volume.voxel_count());
        std::vector<voxel_index> order;
        // Increasing with every kind of gap (same row, next rows, far rows), from index 0 and from
        // the last row, then random order (backwards steps divide).
        for (voxel_index i = 0; i < count;) {
            order.push_back(i);
            const voxel_index row = voxel_index(grid.x);
            const voxel_index k = integer(g, 0, 3);
            const voxel_index gap = k == 0 ? 1 : k == 1 ? row : k == 2 ? 3 * row + 1 : 70 * row + 5;
            if (count - i <= gap) break;
            i += gap;
        }
        order.push_back(count - 1);
        for (int k = 0; k < 2000; ++k) order.push_back(integer(g, 0, count - 1));
        hypertree::detail::coordinate_walker walker(volume);
        std::size_t wrong = 0;
        for (const voxel_index i : order) wrong += walker(i) != volume.coordinates(i);
        CHECK(wrong == 0);
        hypertree::detail::coordinate_walker from_last(volume); // a first index in the last row
        CHECK(from_last(count - 1) == volume.coordinates(count - 1));
    }
}

TEST_CASE("index divider: the quotient of every index it is asked, against integer division")
{
    // Store bounds divide each index by the row and slice sizes through a double reciprocal and a
    // correction; it must be exact for every 32-bit index: multiples of the divisor and their
    // neighbours (where truncation errs), the largest index, random ones.
    std::mt19937_64 g(32);
    std::vector<std::uint64_t> divisors = {1, 2, 3, 7, 300, 1000, 65535, 65536, 90000, 1000000, 0x7fffffffu, 0xffffffffu};
    for (int k = 0; k < 40; ++k) divisors.push_back(integer(g, 1, 0xffffffffu));
    std::size_t wrong = 0;
    for (const std::uint64_t d : divisors) {
        const hypertree::detail::index_divider divide(d);
        const auto check = [&](std::uint64_t i) {
            if (i > 0xffffffffu) return;
            wrong += divide.quotient(voxel_index(i)) != voxel_index(i / d);
        };
        check(0), check(0xffffffffu), check(0xfffffffeu);
        for (int k = 0; k < 20000; ++k) {
            const std::uint64_t multiple = (std::uint64_t(integer(g, 0, 0xffffffffu)) / d) * d;
            check(multiple), check(multiple + 1), check(multiple - (multiple > 0)), check(multiple + d - 1);
            check(integer(g, 0, 0xffffffffu));
        }
    }
    CHECK(wrong == 0);
}

TEST_CASE("stores: bounds on a large grid, from its first and last voxels and the extreme rows")
{
    // A grid near the 32-bit index limit, with voxels at the corners of their box and inside it.
    const hypervolume volume({0, 0, 0}, {1, 1, 1}, hypertree::resolution{1621, 1619, 1601});
    std::vector<stored_voxel> voxels;
    const auto add = [&](int x, int y, int z) { voxels.push_back({volume.index(x, y, z), voxel{9, 1}, 0}); };
    add(1620, 5, 3), add(2, 1618, 700), add(0, 700, 1600), add(800, 0, 900), add(1619, 1617, 1599);
    std::sort(voxels.begin(), voxels.end(), [](const stored_voxel& a, const stored_voxel& b) { return a.index < b.index; });
    const auto box = hypertree::detail::bounds_of(volume, voxels);
    CHECK(box == hypertree::index_box{{0, 0, 3}, {1620, 1618, 1600}});
}

// ---- stores ------------------------------------------------------------------------------------------

TEST_CASE_TEMPLATE_DEFINE("stores: every kind returns the reference voxel for every voxel of a small grid", S,
                          small_grid_reference)
{
    std::mt19937_64 g(8);
    for (const double fill : {0.0, 0.002, 0.15, 1.0}) {
        INFO("fill " << fill);
        const auto voxels = random_voxels(g, small_volume, fill);
        const auto reference = grid_of(small_volume, voxels);
        const auto store = S::build(small_volume, voxels);
        CHECK(count_differences(grid_of_store(store), reference) == 0);
        check_visits_the_list(store, voxels);
        const auto box = bounds_by_hand(small_volume, voxels);
        CHECK(store.bounds() == box);
        CHECK(box.empty() == voxels.empty());
    }
}
TEST_CASE_TEMPLATE_APPLY(small_grid_reference, hypertree::store_kinds);

// A kind is one header, include/hypertree/store/<name>_store.hpp (docs/design.md, "A store kind"):
// one written but left out of the list would be built and tested by nothing, so the list must hold
// as many kinds as the folder has such headers (store_kinds.hpp including each is checked by the
// ctest include_layers).
TEST_CASE("stores: the list of kinds holds one kind per *_store.hpp header")
{
    std::size_t headers = 0, kinds = 0;
    for (const auto& entry :
         std::filesystem::directory_iterator(std::filesystem::path(KRS_SOURCE_DIR) / "include" / "hypertree" / "store")) {
        const std::string name = entry.path().filename().string();
        if (name.ends_with("_store.hpp")) ++headers;
    }
    hypertree::for_each_store_kind([&]<class S>() { ++kinds; });
    CHECK(headers >= 4);
    CHECK(kinds == headers);
}

TEST_CASE("stores: the bit array's occupancy bits and the partitioned store's parts on a small grid")
{
    std::mt19937_64 g(8);
    for (const double fill : {0.0, 0.002, 0.15, 1.0}) {
        INFO("fill " << fill);
        const auto voxels = random_voxels(g, small_volume, fill);
        const auto reference = grid_of(small_volume, voxels);
        const auto bits = hypertree::bit_array_store::build(small_volume, voxels);
        const auto parts = hypertree::partitioned_store::build(small_volume, voxels);
        for (voxel_index i = 0; i < small_volume.voxel_count(); ++i)
            if (bits.occupied(i) != (reference[i].density != 0)) FAIL("occupancy bit of voxel " << i);
        // The partitioned store gives back each voxel's part, and so the very list it was built from.
        const auto again = hypertree::stored_voxels(parts);
        REQUIRE(again.size() == voxels.size());
        std::size_t wrong = 0;
        for (std::size_t k = 0; k < voxels.size(); ++k)
            wrong += again[k].index != voxels[k].index || again[k].part != voxels[k].part;
        CHECK(wrong == 0);
    }
}

TEST_CASE("zeroed arrays start zero and copy deeply, copied stores answer like their originals")
{
    hypertree::zeroed_array<std::uint64_t> a(1 << 20); // 8 MiB: calloc maps fresh pages
    REQUIRE(a.size() == std::size_t(1) << 20);
    CHECK(std::all_of(a.data(), a.data() + a.size(), [](std::uint64_t w) { return w == 0; }));
    a[12345] = 7;
    hypertree::zeroed_array<std::uint64_t> b = a;
    b[12345] = 9;
    CHECK(a[12345] == 7);
    CHECK(b[12345] == 9);
    hypertree::zeroed_array<std::uint64_t> c = std::move(b);
    CHECK(b.size() == 0);
    CHECK(c[12345] == 9);
    c = a;
    CHECK(c[12345] == 7);
    c[12345] = 11; // the assigned copy is deep too
    CHECK(a[12345] == 7);
    CHECK(hypertree::zeroed_array<int>(0).size() == 0);
    const hypertree::zeroed_array<voxel> grid(3 << 20); // 6 MiB of empty voxels
    CHECK(std::all_of(grid.data(), grid.data() + grid.size(), [](const voxel& v) { return v == voxel{}; }));

    std::mt19937_64 g(10);
    const auto voxels = random_voxels(g, small_volume, 0.15);
    const auto reference = grid_of(small_volume, voxels);
    std::optional<hypertree::dense_store> dense = hypertree::dense_store::build(small_volume, voxels);
    std::optional<hypertree::bit_array_store> bits = hypertree::bit_array_store::build(small_volume, voxels);
    const hypertree::dense_store dense_copy = *dense;
    const hypertree::bit_array_store bits_copy = *bits;
    dense.reset(), bits.reset(); // the copies own their memory
    CHECK(count_differences(grid_of_store(dense_copy), reference) == 0);
    CHECK(count_differences(grid_of_store(bits_copy), reference) == 0);
}


TEST_CASE("zeroed arrays reuse their block for the same size or up to half of it, and only then")
{
    hypertree::zeroed_array<std::uint64_t> a(1 << 18); // 2 MiB: a mapped block on Linux
    const std::uint64_t* block = a.data();
    CHECK(a.reusable_for(1 << 18));
    CHECK(a.reusable_for(1 << 17));
    CHECK(!a.reusable_for((1 << 17) - 1)); // would pin a block more than twice as large
    CHECK(!a.reusable_for((1 << 18) + 1));
    CHECK(!a.reusable_for(0));
    a[5] = 3;
    a[5] = 0; // the caller's part: what it wrote is zero again
    a.reuse(1 << 17);
    CHECK(a.data() == block);
    CHECK(a.size() == std::size_t(1) << 17);
    CHECK(a.capacity() == std::size_t(1) << 18);
    a.reuse((1 << 18) + 1); // too large: a new, zeroed block
    CHECK(a.size() == (std::size_t(1) << 18) + 1);
    CHECK(std::all_of(a.data(), a.data() + a.size(), [](std::uint64_t w) { return w == 0; }));
}

// A store built again in a recycled store, against one built fresh from the same list and against
// the plain grid of the list: every voxel, the visit order, the count and the bounds.
template <class S>
void check_rebuilt_like_fresh(const hypervolume& volume, const std::vector<stored_voxel>& before,
                              const std::vector<stored_voxel>& after)
{
    S old = S::build(volume, before);
    const S rebuilt = S::build(volume, after, {}, std::move(old));
    const S fresh = S::build(volume, after);
    const auto reference = grid_of(volume, after);
    CHECK(count_differences(grid_of_store(rebuilt), reference) == 0);
    CHECK(count_differences(grid_of_store(rebuilt), grid_of_store(fresh)) == 0);
    check_visits_the_list(rebuilt, after);
    CHECK(rebuilt.bounds() == bounds_by_hand(volume, after));
    CHECK(rebuilt.bounds() == fresh.bounds());
}

TEST_CASE_TEMPLATE_DEFINE("stores: a store rebuilt in a recycled one answers every voxel as one built fresh", S,
                          rebuilt_in_recycled)
{
    std::mt19937_64 g(27);
    const auto many = random_voxels(g, small_volume, 0.3);
    const auto few = random_voxels(g, small_volume, 0.02);
    const std::vector<stored_voxel> none;
    SUBCASE("the same size, more voxels than before") { check_rebuilt_like_fresh<S>(small_volume, few, many); }
    SUBCASE("the same size, fewer voxels: the old ones are gone") { check_rebuilt_like_fresh<S>(small_volume, many, few); }
    SUBCASE("to and from an empty list") {
        check_rebuilt_like_fresh<S>(small_volume, many, none);
        check_rebuilt_like_fresh<S>(small_volume, none, many);
    }
    SUBCASE("another grid, larger and then smaller")
    {
        const hypervolume larger({0, 0, 0}, {1, 1, 1}, {64, 64, 64});
        const auto big = random_voxels(g, larger, 0.1);
        S old = S::build(small_volume, many);
        S grown = S::build(larger, big, {}, std::move(old));
        CHECK(count_differences(grid_of_store(grown), grid_of(larger, big)) == 0);
        const S shrunk = S::build(small_volume, few, {}, std::move(grown));
        CHECK(count_differences(grid_of_store(shrunk), grid_of(small_volume, few)) == 0);
        check_visits_the_list(shrunk, few);
    }
    SUBCASE("a refused rebuild leaves the recycled store as it was")
    {
        S old = S::build(small_volume, many);
        std::vector<stored_voxel> unsorted = few;
        REQUIRE(unsorted.size() > 1);
        std::swap(unsorted.front(), unsorted.back());
        CHECK_THROWS_AS((void)S::build(small_volume, unsorted, {}, std::move(old)), krs::invalid_parameter);
        CHECK(count_differences(grid_of_store(old), grid_of(small_volume, many)) == 0);
    }
}
TEST_CASE_TEMPLATE_APPLY(rebuilt_in_recycled, hypertree::store_kinds);

TEST_CASE("a dense store rebuilt at the same size keeps its memory and clears what it wrote, at 300 cubed")
{
    std::mt19937_64 g(28);
    const hypervolume volume({-5, 0, -5}, {10, 12, 10}, hypertree::resolution::cube(300));
    const auto first = tree_like_voxels(g, volume, 6, 20000);
    const auto second = tree_like_voxels(g, volume, 4, 20000);
    hypertree::dense_store old = hypertree::dense_store::build(volume, first);
    const std::size_t bytes = old.memory_bytes();
    const hypertree::dense_store rebuilt = hypertree::dense_store::build(volume, second, {}, std::move(old));
    CHECK(rebuilt.memory_bytes() == bytes);
    // Every voxel of the first list that is not in the second reads empty; every voxel of the
    // second reads its value; and a scan of the whole grid finds exactly the second list.
    std::size_t wrong = 0;
    for (const stored_voxel& v : first) {
        const auto it = std::lower_bound(second.begin(), second.end(), v.index,
                                         [](const stored_voxel& s, voxel_index k) { return s.index < k; });
        const voxel expected = it != second.end() && it->index == v.index ? it->value : voxel{};
        wrong += !(rebuilt.at(v.index) == expected);
    }
    for (const stored_voxel& v : second) wrong += !(rebuilt.at(v.index) == v.value);
    CHECK(wrong == 0);
    std::size_t nonempty = 0;
    for (voxel_index i = 0; i < volume.voxel_count(); ++i) nonempty += rebuilt.at(i).density != 0;
    CHECK(nonempty == second.size());
}

TEST_CASE("a dense store visits exactly its non-empty voxels, in index order, through the runs it wrote")
{
    // The dense store's for_each reads only the runs of 32 voxels its bits mark as written. The
    // reference is a scan of every voxel of the grid with at(). The grids end inside a run and
    // inside a word of run bits (31 x 7 x 5 = 1085 voxels: 33 full runs and 29 voxels over;
    // 70 x 33 x 29 = 66990 voxels over 33 words of bits), voxels sit on run boundaries and in the
    // last voxel, and a store rebuilt in a recycled one (the runs of its first list cleared)
    // visits only its second list.
    std::mt19937_64 g(29);
    for (const hypertree::resolution grid : {hypertree::resolution{31, 7, 5}, hypertree::resolution{70, 33, 29}}) {
        const hypervolume volume({0, 0, 0}, {1, 1, 1}, grid);
        const voxel_index n = volume.voxel_count();
        INFO("voxels " << n);
        const auto scan = [&](const hypertree::dense_store& store) {
            std::vector<std::pair<voxel_index, voxel>> expected, visited;
            for (voxel_index i = 0; i < n; ++i)
                if (store.at(i).density != 0) expected.emplace_back(i, store.at(i));
            store.for_each([&](voxel_index i, voxel v) { visited.emplace_back(i, v); });
            CHECK(visited.size() == expected.size());
            CHECK(visited == expected);
            return expected.size();
        };
        for (const double fill : {0.001, 0.05, 0.5}) {
            INFO("fill " << fill);
            std::vector<stored_voxel> voxels = random_voxels(g, volume, fill);
            // The first and last voxel of runs, and of the grid.
            std::map<voxel_index, stored_voxel> edges;
            for (const stored_voxel& v : voxels) edges[v.index] = v;
            for (const voxel_index i : {voxel_index(0), voxel_index(31), voxel_index(32), voxel_index(63), voxel_index(64 * 32 - 1),
                                        voxel_index(64 * 32), n - 1})
                if (i < n) edges[i] = stored_voxel{i, voxel{7, 1}, 0};
            voxels.clear();
            for (const auto& [i, v] : edges) voxels.push_back(v);
            const hypertree::dense_store fresh = hypertree::dense_store::build(volume, voxels);
            CHECK(scan(fresh) == voxels.size());
            // Rebuilt over a fuller store: the old runs are cleared and no longer visited.
            hypertree::dense_store old = hypertree::dense_store::build(volume, random_voxels(g, volume, 0.3));
            const hypertree::dense_store rebuilt = hypertree::dense_store::build(volume, voxels, {}, std::move(old));
            CHECK(scan(rebuilt) == voxels.size());
        }
    }
}

TEST_CASE("stores: every kind matches the reference on a sparse 300 cubed tree")
{
    std::mt19937_64 g(9);
    const hypervolume volume({-5, 0, -5}, {10, 12, 10}, hypertree::resolution::cube(300));
    const auto voxels = tree_like_voxels(g, volume, 6, 30000);
    REQUIRE(voxels.size() > 50000);

    const auto reference = [&](voxel_index i) {
        const auto it = std::lower_bound(voxels.begin(), voxels.end(), i,
                                         [](const stored_voxel& v, voxel_index k) { return v.index < k; });
        return it != voxels.end() && it->index == i ? it->value : voxel{};
    };
    // Every non-empty voxel and its two row neighbours, then random voxels anywhere.
    std::vector<voxel_index> probes;
    for (const stored_voxel& v : voxels) {
        probes.push_back(v.index);
        if (v.index > 0) probes.push_back(v.index - 1);
        if (v.index + 1 < volume.voxel_count()) probes.push_back(v.index + 1);
    }
    for (int k = 0; k < 200000; ++k) probes.push_back(integer(g, 0, volume.voxel_count() - 1));
    probes.push_back(0);
    probes.push_back(voxel_index(volume.voxel_count() - 1));
    std::size_t kinds = 0;
    hypertree::for_each_store_kind([&]<class S>() {
        INFO(hypertree::store_kind_name<S>);
        const S store = S::build(volume, voxels);
        std::size_t wrong = 0;
        for (const voxel_index i : probes) wrong += !(store.at(i) == reference(i));
        CHECK(wrong == 0);
        ++kinds;
    });
    CHECK(kinds == std::tuple_size_v<hypertree::store_kinds>);

    // What follows is particular to each kind: its memory formula, the partitions.
    const auto dense = hypertree::dense_store::build(volume, voxels);
    const auto list = hypertree::index_list_store::build(volume, voxels);
    const auto bits = hypertree::bit_array_store::build(volume, voxels);
    const auto parts = hypertree::partitioned_store::build(volume, voxels);
    check_visits_the_list(parts, voxels);
    CHECK(parts.bounds() == bounds_by_hand(volume, voxels));

    // Memory follows the paper's costs.
    {
        const std::size_t n = voxels.size();
        // 2 bytes per voxel and a bit per 32 voxels (which runs a rebuild clears), in 8-byte words.
        const std::size_t runs = (std::size_t(volume.voxel_count()) + 31) / 32;
        CHECK(dense.memory_bytes() == 2 * std::size_t(volume.voxel_count()) + 8 * ((runs + 63) / 64));
        CHECK(dense.memory_bytes() == hypertree::dense_store::bytes_needed(volume));
        // The list and its directory: at most one 4-byte position per two voxels, and two more.
        CHECK(list.memory_bytes() > 6 * n);
        CHECK(list.memory_bytes() <= 8 * n + 8);
        CHECK(list.memory_bytes() >= hypertree::index_list_store::bytes_needed(volume, voxels));
        // The list, one bit per index of the range (rounded up to 512-bit blocks) and 4 bytes per block.
        const std::size_t range = voxels.back().index - voxels.front().index + 1;
        CHECK(bits.memory_bytes() > 6 * n + range / 8);
        CHECK(bits.memory_bytes() <= 6 * n + (range + 511) / 512 * (64 + 4));
        CHECK(bits.memory_bytes() >= hypertree::bit_array_store::bytes_needed(volume, voxels));
        CHECK(parts.memory_bytes() > 6 * n);
        CHECK(parts.memory_bytes() <= 8 * n + 6 * (sizeof(hypertree::store_part) + 8));
        CHECK(parts.memory_bytes() >= hypertree::partitioned_store::bytes_needed(volume, voxels));
        // The paper: a compact hypertree takes under 5% of a dense array.
        CHECK(list.memory_bytes() * 20 < dense.memory_bytes());
        CHECK(parts.memory_bytes() * 20 < dense.memory_bytes());
        CHECK(bits.memory_bytes() * 5 < dense.memory_bytes());
    }

    // Each part's sphere holds its voxels' cells, and the parts hold each voxel once.
    {
        std::map<int, std::vector<stored_voxel>> by_part;
        for (const stored_voxel& v : voxels) by_part[v.part].push_back(v);
        REQUIRE(parts.parts().size() == by_part.size());
        std::size_t total = 0;
        const vec3d half = volume.voxel_size() * 0.5;
        for (const hypertree::store_part& part : parts.parts()) {
            const auto& mine = by_part.at(part.part);
            CHECK(part.count == mine.size());
            CHECK(part.first_index == mine.front().index);
            CHECK(part.last_index == mine.back().index);
            CHECK(part.bounds == bounds_by_hand(volume, mine));
            total += part.count;
            const vec3d center(part.sphere.center);
            double farthest = 0;
            for (const stored_voxel& v : mine) {
                const vec3d c = volume.voxel_center(v.index);
                for (int corner = 0; corner < 8; ++corner) {
                    const vec3d p{c.x + ((corner & 1) ? half.x : -half.x), c.y + ((corner & 2) ? half.y : -half.y),
                                  c.z + ((corner & 4) ? half.z : -half.z)};
                    farthest = std::max(farthest, krs::length(p - center));
                }
            }
            CHECK(farthest <= double(part.sphere.radius));
            // Not loose: the farthest voxel center plus half a diagonal exceeds the farthest corner
            // by at most half a diagonal (a cell's farthest corner is no nearer than its center).
            CHECK(double(part.sphere.radius) <= farthest + 0.5 * krs::length(volume.voxel_size()) + 1e-4);
        }
        CHECK(total == voxels.size());
    }
}

TEST_CASE("stores: the lookup directories agree with the lists at grid edges, in empty rows and in full rows")
{
    // Row length 37 (not a power of two, so buckets and rows do not line up) and 64 (they do).
    for (const int nx : {37, 64}) {
        const hypervolume volume({0, 0, 0}, {1, 1, 1}, {nx, 6, 5});
        const auto n = volume.grid();
        const voxel_index last = voxel_index(volume.voxel_count() - 1);
        const auto value_of = [](voxel_index i) {
            return voxel{std::uint8_t(1 + i % 255), std::uint8_t(i % 7)};
        };
        std::mt19937_64 g(11);
        std::vector<std::pair<std::string, std::vector<voxel_index>>> cases;
        cases.push_back({"first voxel only", {0}});
        cases.push_back({"last voxel only", {last}});
        cases.push_back({"first and last voxels: every row between empty", {0, last}});
        {
            std::vector<voxel_index> corners; // both ends of every row: the grid's x faces
            for (int z = 0; z < n.z; ++z)
                for (int y = 0; y < n.y; ++y) corners.push_back(volume.index(0, y, z)), corners.push_back(volume.index(n.x - 1, y, z));
            cases.push_back({"both ends of every row", corners});
        }
        {
            std::vector<voxel_index> row; // one full row, all else empty
            for (int x = 0; x < n.x; ++x) row.push_back(volume.index(x, 3, 2));
            cases.push_back({"a single full row", row});
        }
        {
            std::vector<voxel_index> slab; // full rows in every other z slice: runs of empty rows between
            for (int z = 0; z < n.z; z += 2)
                for (int y = 0; y < n.y; ++y)
                    for (int x = 0; x < n.x; ++x) slab.push_back(volume.index(x, y, z));
            cases.push_back({"full slices with empty slices between", slab});
        }
        {
            std::vector<voxel_index> mixed = {0, last}; // a full row among scattered voxels
            for (int x = 0; x < n.x; ++x) mixed.push_back(volume.index(x, n.y - 1, n.z - 1));
            for (int k = 0; k < 40; ++k) mixed.push_back(integer(g, 0, last));
            std::sort(mixed.begin(), mixed.end());
            mixed.erase(std::unique(mixed.begin(), mixed.end()), mixed.end());
            cases.push_back({"a full row at the grid's far edge among scattered voxels", mixed});
        }
        cases.push_back({"every voxel", {}});
        for (voxel_index i = 0; i <= last; ++i) cases.back().second.push_back(i);

        for (const auto& [name, indices] : cases) {
            for (const int parts_per_list : {1, 3}) {
                INFO("row length " << nx << ", " << name << ", " << parts_per_list << " part(s)");
                std::vector<stored_voxel> voxels;
                // Parts by row, so that one bucket holds voxels of several parts.
                for (const voxel_index i : indices)
                    voxels.push_back({i, value_of(i), std::uint8_t(i / voxel_index(nx) % voxel_index(parts_per_list))});
                const auto reference = grid_of(volume, voxels);
                const auto list = hypertree::index_list_store::build(volume, voxels);
                const auto bits = hypertree::bit_array_store::build(volume, voxels);
                const auto parts = hypertree::partitioned_store::build(volume, voxels);
                CHECK(count_differences(grid_of_store(list), reference) == 0);
                CHECK(count_differences(grid_of_store(bits), reference) == 0);
                CHECK(count_differences(grid_of_store(parts), reference) == 0);
                // A part answers for its own voxels only.
                std::size_t wrong = 0;
                for (std::size_t slot = 0; slot < parts.parts().size(); ++slot) {
                    const std::uint8_t part = parts.parts()[slot].part;
                    for (const stored_voxel& v : voxels) {
                        const voxel expected = v.part == part ? v.value : voxel{};
                        wrong += !(parts.at_in_part(slot, v.index) == expected);
                    }
                }
                CHECK(wrong == 0);
                CHECK(list.memory_bytes() >= hypertree::index_list_store::bytes_needed(volume, voxels));
                CHECK(list.memory_bytes() <= 8 * voxels.size() + 8);
            }
        }
    }
}

TEST_CASE("stores: index directory positions are the counts of smaller indices, for lists up to the largest index")
{
    using hypertree::detail::index_directory;
    std::mt19937_64 g(12);
    constexpr voxel_index top = std::numeric_limits<voxel_index>::max();
    // Random lists, lists hugging both ends of the index range, and one spanning all of it.
    std::vector<std::vector<voxel_index>> lists;
    for (int k = 0; k < 20; ++k) {
        std::vector<voxel_index> list(integer(g, 1, 3000));
        const std::uint64_t lo = integer(g, 0, top / 2), hi = lo + integer(g, 1, k % 2 ? 10000 : top / 2);
        for (voxel_index& i : list) i = integer(g, lo, hi);
        lists.push_back(list);
    }
    lists.push_back({0, 1, 2, top - 2, top - 1});
    lists.push_back({top});
    lists.push_back({top - 100, top - 50, top});
    for (auto& list : lists) {
        std::sort(list.begin(), list.end());
        list.erase(std::unique(list.begin(), list.end()), list.end());
        INFO("list of " << list.size() << " from " << list.front() << " to " << list.back());
        const auto d = index_directory::shape(list.front(), list.back(), list.size());
        REQUIRE(d.buckets >= 1);
        CHECK(d.positions() <= list.size() / index_directory::voxels_per_bucket + 2);
        // The buckets cover the list's range.
        CHECK(std::uint64_t(list.back()) - list.front() < (d.buckets << d.shift));
        std::vector<std::uint32_t> starts(d.positions());
        d.fill(list.data(), list.size(), starts.data());
        std::size_t wrong = 0;
        for (std::uint64_t b = 0; b <= d.buckets; ++b) {
            const std::uint64_t bucket_first = std::uint64_t(list.front()) + (b << d.shift);
            const auto smaller = std::size_t(
                std::count_if(list.begin(), list.end(), [&](voxel_index i) { return i < bucket_first; }));
            wrong += starts[b] != (b == d.buckets ? list.size() : smaller);
        }
        CHECK(wrong == 0);
        // Every listed index is found where it is; its neighbours and the range's ends are not.
        for (std::size_t k = 0; k < list.size(); ++k) {
            wrong += d.find(list.data(), starts.data(), list[k]) != k;
            for (const voxel_index near : {voxel_index(list[k] - 1), voxel_index(list[k] + 1)})
                if (!std::binary_search(list.begin(), list.end(), near))
                    wrong += d.find(list.data(), starts.data(), near) != index_directory::npos;
        }
        for (const voxel_index end : {voxel_index(0), top, voxel_index(list.front() / 2)})
            if (!std::binary_search(list.begin(), list.end(), end))
                wrong += d.find(list.data(), starts.data(), end) != index_directory::npos;
        CHECK(wrong == 0);
    }
}

TEST_CASE("stores: the memory budget is checked before anything is allocated")
{
    // 1000^3 voxels: a dense store needs 2 GB, and a bit per 32 voxels (488282 words: 3.9 MB).
    // The refusal must come from the budget check, since an allocation first would succeed (or
    // fail with bad_alloc) instead of throwing this.
    const hypervolume big({0, 0, 0}, {1, 1, 1}, hypertree::resolution::cube(1000));
    CHECK(hypertree::dense_store::bytes_needed(big) == 2000000000u + 8 * 488282u);
    try {
        (void)hypertree::dense_store::build(big, {}, hypertree::memory_budget{std::size_t(1) << 30});
        FAIL("a 2 GB dense store fit a 1 GiB budget");
    } catch (const krs::invalid_parameter& e) {
        const std::string what = e.what();
        CHECK(what.find("dense_store") != std::string::npos);
        CHECK(what.find("2003906256") != std::string::npos);
        CHECK(what.find("1073741824") != std::string::npos);
    }
    // The default budget (4 GiB) refuses 1600^3 (8 GB dense) too.
    const hypervolume bigger({0, 0, 0}, {1, 1, 1}, hypertree::resolution::cube(1600));
    CHECK_THROWS_AS((void)hypertree::dense_store::build(bigger, {}), krs::invalid_parameter);

    std::mt19937_64 g(10);
    const auto voxels = random_voxels(g, small_volume, 0.05);
    const auto refuses = [&](auto build, std::size_t needed, const char* name) {
        INFO(name);
        CHECK_NOTHROW(build(hypertree::memory_budget{needed}));
        try {
            build(hypertree::memory_budget{needed - 1});
            FAIL("one byte under the need was accepted");
        } catch (const krs::invalid_parameter& e) {
            CHECK(std::string(e.what()).find(name) != std::string::npos);
            CHECK(std::string(e.what()).find(std::to_string(needed)) != std::string::npos);
        }
        CHECK_THROWS_AS(build(hypertree::memory_budget{100}), krs::invalid_parameter);
    };
    refuses([&](hypertree::memory_budget b) { return hypertree::index_list_store::build(small_volume, voxels, b); },
            hypertree::index_list_store::bytes_needed(small_volume, voxels), "index_list_store");
    refuses([&](hypertree::memory_budget b) { return hypertree::bit_array_store::build(small_volume, voxels, b); },
            hypertree::bit_array_store::bytes_needed(small_volume, voxels), "bit_array_store");
    refuses([&](hypertree::memory_budget b) { return hypertree::partitioned_store::build(small_volume, voxels, b); },
            hypertree::partitioned_store::bytes_needed(small_volume, voxels), "partitioned_store");
    refuses([&](hypertree::memory_budget b) { return hypertree::dense_store::build(small_volume, voxels, b); },
            hypertree::dense_store::bytes_needed(small_volume), "dense_store");
    CHECK(hypertree::index_list_store::bytes_needed(small_volume, voxels) > 6 * voxels.size());
    CHECK(hypertree::index_list_store::bytes_needed(small_volume, voxels) <= 8 * voxels.size() + 8);
}

TEST_CASE("stores: build refuses lists that are unsorted, repeated, outside the volume or empty-valued")
{
    const std::vector<std::vector<stored_voxel>> bad = {
        {{5, {9, 0}, 0}, {3, {9, 0}, 0}},                       // unsorted
        {{5, {9, 0}, 0}, {5, {7, 1}, 0}},                       // repeated
        {{voxel_index(small_volume.voxel_count()), {9, 0}, 0}}, // outside
        {{5, {0, 0}, 0}},                                       // empty voxel
    };
    for (const auto& voxels : bad) {
        CHECK_THROWS_AS(hypertree::dense_store::build(small_volume, voxels), krs::invalid_parameter);
        CHECK_THROWS_AS(hypertree::index_list_store::build(small_volume, voxels), krs::invalid_parameter);
        CHECK_THROWS_AS(hypertree::bit_array_store::build(small_volume, voxels), krs::invalid_parameter);
        CHECK_THROWS_AS(hypertree::partitioned_store::build(small_volume, voxels), krs::invalid_parameter);
    }
}

TEST_CASE("store kinds: each enumerator, forest-file name and type agree")
{
    // The spellings of forest files (docs/hypertree_format.md, STORAGETYPE), written out here
    // beside the enumerator of the same name: each enumerator names the kind whose type carries
    // that spelling, and the kinds are these four.
    using hypertree::storage_type;
    const std::pair<std::string_view, storage_type> spelled[] = {
        {"dense", storage_type::dense},
        {"index_list", storage_type::index_list},
        {"bit_array", storage_type::bit_array},
        {"partitioned", storage_type::partitioned},
    };
    CHECK(std::size(spelled) == std::tuple_size_v<hypertree::store_kinds>);
    for (const auto& [name, kind] : spelled) {
        INFO(name);
        CHECK(hypertree::name_of(kind) == name);
        hypertree::with_store(kind, [&]<class S>() {
            CHECK(S::kind_name == name);
            CHECK(hypertree::store_kind_name<S> == name);
            CHECK(hypertree::storage_type_of<S> == kind);
        });
    }
}

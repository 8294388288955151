// Hypertree validation, density classes, the four voxel stores and the volume operations
// (paper sections 4, 5 and 7), each against a brute-force reference written here: a std::map for
// compaction, counting by hand for classes, a plain array of every voxel of the grid for stores
// and operations.

#include "hypertree/create/compact.hpp"
#include "hypertree/create/density.hpp"
#include "hypertree/execution.hpp"
#include "hypertree/huge_pages.hpp"
#include "hypertree/ops.hpp"
#include "hypertree/create/scratch.hpp"
#include "hypertree/store/store_kinds.hpp"

#include "support/random.hpp"

#include <doctest/doctest.h>

#include <algorithm>
#include <atomic>
#include <cmath>
#include <cstddef>
#include <cstdint>
#include <functional>
#include <iterator>
#include <limits>
#include <map>
#include <memory_resource>
#include <optional>
#include <random>
#include <span>
#include <string>
#include <thread>
#include <tuple>
#include <utility>
#include <vector>

namespace {
using hypertree::hit;
using hypertree::hypervolume;
using hypertree::stored_voxel;
using hypertree::voxel;
using hypertree::voxel_entry;
using hypertree::voxel_index;
using krs::vec3d;

// A parallel_for hook on two threads started for the call, task i on thread i % 2.
hypertree::parallel_for_hook two_threads()
{
    return [](std::size_t count, const std::function<void(std::size_t)>& body) {
        std::vector<std::thread> threads;
        for (unsigned t = 0; t < 2; ++t)
            threads.emplace_back([&, t] {
                for (std::size_t i = t; i < count; i += 2) body(i);
            });
        for (std::thread& t : threads) t.join();
    };
}

// Uniform integer in [lo, hi], from the engine's bits only (platform-independent).
std::uint32_t integer(std::mt19937_64& g, std::uint64_t lo, std::uint64_t hi)
{
    return std::uint32_t(lo + g() % (hi - lo + 1));
}

// ---- compaction reference ---------------------------------------------------------------------

std::vector<voxel_entry> compact_with_map(const std::vector<hit>& hits)
{
    struct merged {
        std::uint32_t hits = 0;
        int level = 1000, part = 1000;
    };
    std::map<voxel_index, merged> by_voxel;
    for (const hit& h : hits) {
        merged& m = by_voxel[h.voxel];
        ++m.hits;
        if (h.level < m.level || (h.level == m.level && h.part < m.part)) m.level = h.level, m.part = h.part;
    }
    std::vector<voxel_entry> entries;
    for (const auto& [v, m] : by_voxel) entries.push_back({v, m.hits, std::uint8_t(m.level), std::uint8_t(m.part)});
    return entries;
}

void check_same_entries(const std::vector<voxel_entry>& got, const std::vector<voxel_entry>& expected)
{
    REQUIRE(got.size() == expected.size());
    std::size_t wrong = 0, first_wrong = got.size();
    for (std::size_t i = 0; i < got.size(); ++i) {
        const bool same = got[i].voxel == expected[i].voxel && got[i].hits == expected[i].hits &&
                          got[i].level == expected[i].level && got[i].part == expected[i].part;
        if (!same && wrong++ == 0) first_wrong = i;
    }
    INFO("first differing entry " << first_wrong);
    CHECK(wrong == 0);
}

std::vector<hit> random_hits(std::mt19937_64& g, std::size_t count, voxel_index lowest, voxel_index highest, int levels,
                             int parts)
{
    std::vector<hit> hits(count);
    for (hit& h : hits)
        h = {integer(g, lowest, highest), std::uint8_t(integer(g, 0, levels - 1)),
             std::uint8_t(integer(g, 0, parts - 1))};
    return hits;
}

// 1 + a geometric number of failures with success probability p (inverse transform).
std::uint32_t geometric_hits(std::mt19937_64& g, double p)
{
    const double u = krs_test::uniform(g, 0, 1);
    return 1 + std::uint32_t(std::floor(std::log1p(-u) / std::log1p(-p)));
}

// ---- store and operation reference: every voxel of the grid -------------------------------------

std::vector<voxel> grid_of(const hypervolume& volume, const std::vector<stored_voxel>& voxels)
{
    std::vector<voxel> grid(std::size_t(volume.voxel_count()));
    for (const stored_voxel& v : voxels) grid[v.index] = v.value;
    return grid;
}

template <class S>
std::vector<voxel> grid_of_store(const S& store)
{
    std::vector<voxel> grid(std::size_t(store.volume().voxel_count()));
    for (std::size_t i = 0; i < grid.size(); ++i) grid[i] = store.at(voxel_index(i));
    return grid;
}

// Each voxel of the grid non-empty with probability `fill`, with a random density, level, part.
std::vector<stored_voxel> random_voxels(std::mt19937_64& g, const hypervolume& volume, double fill, int parts = 4)
{
    std::vector<stored_voxel> voxels;
    for (voxel_index i = 0; i < volume.voxel_count(); ++i)
        if (krs_test::uniform(g, 0, 1) < fill)
            voxels.push_back({i, voxel{std::uint8_t(integer(g, 1, 255)), std::uint8_t(integer(g, 0, 7))},
                              std::uint8_t(integer(g, 0, parts - 1))});
    return voxels;
}

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

// Bounds by the definition: min and max coordinates of the voxels, computed by % and /.
hypertree::index_box bounds_by_hand(const hypervolume& volume, const std::vector<stored_voxel>& voxels)
{
    hypertree::index_box box;
    if (voxels.empty()) return box;
    const auto n = volume.grid();
    box.lo = {n.x, n.y, n.z};
    box.hi = {-1, -1, -1};
    for (const stored_voxel& v : voxels) {
        const int c[3] = {int(v.index % voxel_index(n.x)), int(v.index / voxel_index(n.x) % voxel_index(n.y)),
                          int(v.index / voxel_index(n.x) / voxel_index(n.y))};
        for (int a = 0; a < 3; ++a) box.lo[a] = std::min(box.lo[a], c[a]), box.hi[a] = std::max(box.hi[a], c[a]);
    }
    return box;
}

template <class S>
void check_visits_the_list(const S& store, const std::vector<stored_voxel>& voxels)
{
    std::vector<std::pair<voxel_index, voxel>> visited;
    store.for_each([&](voxel_index i, voxel v) { visited.emplace_back(i, v); });
    REQUIRE(visited.size() == voxels.size());
    std::size_t wrong = 0;
    for (std::size_t k = 0; k < voxels.size(); ++k)
        wrong += visited[k].first != voxels[k].index || !(visited[k].second == voxels[k].value);
    CHECK(wrong == 0);
    CHECK(store.nonempty_count() == voxels.size());
}

std::size_t count_differences(const std::vector<voxel>& a, const std::vector<voxel>& b)
{
    REQUIRE(a.size() == b.size());
    std::size_t different = 0;
    for (std::size_t i = 0; i < a.size(); ++i) different += !(a[i] == b[i]);
    return different;
}

const hypervolume small_volume({-1.5, 0.25, 2.0}, {2.0, 1.2, 0.9}, {40, 30, 20});
} // namespace

// ---- compaction -----------------------------------------------------------------------------------

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
        std::uniform_int_distribution<voxel_index> gap_kind(0, 3);
        for (voxel_index i = 0; i < count;) {
            order.push_back(i);
            const voxel_index row = voxel_index(grid.x);
            const voxel_index k = gap_kind(g);
            const voxel_index gap = k == 0 ? 1 : k == 1 ? row : k == 2 ? 3 * row + 1 : 70 * row + 5;
            if (count - i <= gap) break;
            i += gap;
        }
        order.push_back(count - 1);
        for (int k = 0; k < 2000; ++k) order.push_back(std::uniform_int_distribution<voxel_index>(0, count - 1)(g));
        hypertree::detail::coordinate_walker walker(volume);
        std::size_t wrong = 0;
        for (const voxel_index i : order) wrong += walker(i) != volume.coordinates(i);
        CHECK(wrong == 0);
        hypertree::detail::coordinate_walker from_last(volume); // a first index in the last row
        CHECK(from_last(count - 1) == volume.coordinates(count - 1));
    }
}

TEST_CASE("compact: the shallowest level prevails and ties take the smallest part")
{
    const std::vector<hit> hits = {{5, 2, 3}, {9, 4, 1}, {5, 1, 4}, {5, 1, 2}, {5, 3, 0}, {2, 7, 7}, {9, 4, 0}};
    const auto entries = hypertree::compact(hits);
    REQUIRE(entries.size() == 3);
    CHECK(entries[0].voxel == 2);
    CHECK(entries[0].hits == 1);
    CHECK(entries[1].voxel == 5);
    CHECK(entries[1].hits == 4);
    CHECK(entries[1].level == 1);
    CHECK(entries[1].part == 2);
    CHECK(entries[2].voxel == 9);
    CHECK(entries[2].hits == 2);
    CHECK(entries[2].level == 4);
    CHECK(entries[2].part == 0);
    CHECK(hypertree::compact({}).empty());
}

TEST_CASE("compact: random hit lists match a map-based reference")
{
    std::mt19937_64 g(20040601);
    struct shape {
        std::size_t hits;
        voxel_index lowest, highest;
    };
    // Few voxels hit very often; a 300^3 volume; the full 32-bit index range (every radix digit
    // in use); one voxel; huge indices only (leading digits constant, skipped passes); small sizes.
    const shape shapes[] = {{20000, 0, 60},
                            {200000, 0, 300 * 300 * 300 - 1},
                            {50000, 0, 0xfffffffeu},
                            {3000, 77, 77},
                            {40000, 0xfff00000u, 0xfffffffeu},
                            {1, 0, 10},
                            {2, 10, 11},
                            {300, 0, 255}};
    for (const shape& s : shapes) {
        INFO("hits " << s.hits << " in [" << s.lowest << ", " << s.highest << "]");
        const auto hits = random_hits(g, s.hits, s.lowest, s.highest, 9, 6);
        check_same_entries(hypertree::compact(hits), compact_with_map(hits));
    }
}

TEST_CASE("compact: levels of 64 and more, parts up to 255, and the grid's voxel count as the bound")
{
    // Grids to 2^25 voxels move 32-bit keys when every level is below 64; deeper levels and any
    // part take the 64-bit keys. Passing the voxel count skips the search for the largest index
    // and gives the same entries; a hit at or past it is refused.
    std::mt19937_64 g(64);
    for (const voxel_index highest : {voxel_index(4095), voxel_index(300 * 300 * 300 - 1), voxel_index(1) << 30}) {
        INFO("voxels up to " << highest);
        for (const int levels : {64, 65, 256}) {
            const auto hits = random_hits(g, 50000, 0, highest, levels, 256);
            const auto reference = compact_with_map(hits);
            check_same_entries(hypertree::compact(hits), reference);
            check_same_entries(hypertree::compact(hits, {}, std::uint64_t(highest) + 1), reference);
            check_same_entries(hypertree::compact(hits, {}, std::uint64_t(highest) + 1000), reference);
        }
        auto hits = random_hits(g, 1000, 0, highest - 1, 9, 6);
        hits.push_back({highest, 3, 1}); // one hit in the last voxel: a count of `highest` is one short
        CHECK_NOTHROW(hypertree::compact(hits, {}, std::uint64_t(highest) + 1));
        CHECK_THROWS_WITH_AS(hypertree::compact(hits, {}, std::uint64_t(highest)), doctest::Contains("compact.voxel_count"),
                             krs::invalid_parameter);
    }
}

TEST_CASE("compact on threads gives the entries of one thread")
{
    // Tasks run in reverse order on a pool of three threads: any schedule must give the same list.
    const hypertree::parallel_for_hook pool = [](std::size_t count, const std::function<void(std::size_t)>& body) {
        std::atomic<std::size_t> next{0};
        std::vector<std::thread> threads;
        for (int t = 0; t < 3; ++t)
            threads.emplace_back([&] {
                for (std::size_t i; (i = next++) < count;) body(count - 1 - i);
            });
        for (std::thread& t : threads) t.join();
    };
    std::mt19937_64 g(29);
    // Large enough to be split; clustered (few buckets in use) and spread over 300^3.
    for (const voxel_index highest : {voxel_index(5000), voxel_index(300 * 300 * 300 - 1)}) {
        const auto hits = random_hits(g, 400000, 0, highest, 9, 6);
        const auto entries = hypertree::compact(hits, pool);
        check_same_entries(entries, compact_with_map(hits));
        check_same_entries(entries, hypertree::compact(hits));
    }
}

TEST_CASE("compact over pieces (the generator's chunks) gives the entries of the whole list")
{
    // build_tree validates the chunks as the generator left them: any split, with empty pieces
    // and pieces shorter than a task's share, on threads or not, into a std::pmr::vector drawn
    // from scratch memory, must give the map's entries.
    const hypertree::parallel_for_hook pool = two_threads();
    std::mt19937_64 g(31);
    hypertree::scratch_memory scratch;
    for (const voxel_index highest : {voxel_index(3000), voxel_index(300 * 300 * 300 - 1), voxel_index(1) << 30}) {
        INFO("voxels up to " << highest);
        const auto hits = random_hits(g, 300000, 0, highest, 9, 6);
        const auto reference = compact_with_map(hits);
        std::vector<std::span<const hit>> pieces;
        for (std::size_t at = 0; at < hits.size();) {
            const std::size_t length = std::min<std::size_t>(hits.size() - at, integer(g, 0, 3) == 0 ? 0 : integer(g, 1, 90000));
            pieces.emplace_back(hits.data() + at, length);
            at += length;
        }
        pieces.emplace_back(); // an empty piece last
        REQUIRE(pieces.size() > 3);
        for (const bool threaded : {false, true}) {
            std::pmr::vector<voxel_entry> entries(&scratch);
            hypertree::detail::compact_into(pieces, threaded ? pool : hypertree::parallel_for_hook{}, std::uint64_t(highest) + 1,
                                            &scratch, entries);
            check_same_entries(std::vector<voxel_entry>(entries.begin(), entries.end()), reference);
            std::vector<voxel_entry> plain;
            hypertree::detail::compact_into(pieces, threaded ? pool : hypertree::parallel_for_hook{}, 0, &scratch, plain);
            check_same_entries(plain, reference);
        }
    }
}

TEST_CASE("compact chunk by chunk (build_tree's way) gives the entries of the whole list")
{
    // Each chunk bucketed on its own, then every bucket merged across the chunks: random chunks,
    // empty ones among them, on threads or not, must give the map's entries; hits past the grid
    // or at level 64 are refused with the parameter named.
    const hypertree::parallel_for_hook pool = two_threads();
    std::mt19937_64 g(33);
    hypertree::scratch_memory scratch;
    for (const std::uint64_t voxels : {std::uint64_t(1), std::uint64_t(3000), std::uint64_t(300) * 300 * 300, std::uint64_t(1) << 25}) {
        INFO("grid of " << voxels << " voxels");
        const auto plan = hypertree::detail::direct_buckets::for_grid(voxels);
        REQUIRE(plan);
        const auto hits = random_hits(g, 250000, 0, voxel_index(voxels - 1), 64, 256);
        const auto reference = compact_with_map(hits);
        std::vector<hypertree::detail::bucketed_chunk> chunks;
        for (std::size_t at = 0; at < hits.size();) {
            const std::size_t length = std::min<std::size_t>(hits.size() - at, integer(g, 0, 3) == 0 ? 0 : integer(g, 1, 70000));
            chunks.push_back(hypertree::detail::bucket_chunk(std::span<const hit>(hits.data() + at, length), *plan, &scratch));
            at += length;
        }
        for (const bool threaded : {false, true}) {
            std::pmr::vector<voxel_entry> entries(&scratch);
            hypertree::detail::merge_bucketed(chunks, *plan, threaded ? pool : hypertree::parallel_for_hook{}, &scratch, entries);
            check_same_entries(std::vector<voxel_entry>(entries.begin(), entries.end()), reference);
        }
    }
    CHECK_FALSE(hypertree::detail::direct_buckets::for_grid((std::uint64_t(1) << 25) + 1));
    CHECK_FALSE(hypertree::detail::direct_buckets::for_grid(0));
    const auto plan = hypertree::detail::direct_buckets::for_grid(1000);
    const std::vector<hit> past = {{5, 1, 0}, {1000, 1, 0}}, deep = {{5, 64, 0}};
    CHECK_THROWS_WITH_AS(hypertree::detail::bucket_chunk(past, *plan, &scratch), doctest::Contains("bucket_chunk.hits"), krs::invalid_parameter);
    CHECK_THROWS_WITH_AS(hypertree::detail::bucket_chunk(deep, *plan, &scratch), doctest::Contains("bucket_chunk.hits"), krs::invalid_parameter);
}

// ---- scratch memory ----------------------------------------------------------------------------------

TEST_CASE("scratch memory keeps released blocks and lends them again")
{
    hypertree::scratch_memory scratch;
    std::pmr::memory_resource& r = scratch;
    void* a = r.allocate(1 << 20, 64);
    CHECK(reinterpret_cast<std::uintptr_t>(a) % 64 == 0);
    CHECK(scratch.system_allocations() == 1);
    CHECK(scratch.kept_bytes() == 0);
    r.deallocate(a, 1 << 20, 64);
    CHECK(scratch.kept_bytes() == std::size_t(1) << 20);
    // The same size, and a request a little smaller, take the kept block back.
    void* b = r.allocate((1 << 20) - 1000, 8);
    CHECK(b == a);
    CHECK(scratch.system_allocations() == 1);
    // A request under half the kept block does not pin it: a new block.
    r.deallocate(b, (1 << 20) - 1000, 8);
    void* c = r.allocate(100000, 4);
    CHECK(c != a);
    CHECK(scratch.system_allocations() == 2);
    CHECK(scratch.kept_bytes() == std::size_t(1) << 20);
    // A larger request than any kept block: a new block.
    void* d = r.allocate(2 << 20, 16);
    CHECK(scratch.system_allocations() == 3);
    // release() frees the kept blocks; blocks lent out stay valid and are kept when returned.
    scratch.release();
    CHECK(scratch.kept_bytes() == 0);
    std::fill_n(static_cast<char*>(d), 2 << 20, 'x');
    r.deallocate(d, 2 << 20, 16);
    r.deallocate(c, 100000, 4);
    CHECK(scratch.kept_bytes() >= std::size_t(2 << 20) + 100000);
    // More than cache-line alignment is not offered.
    CHECK_THROWS_AS((void)r.allocate(4096, 128), std::bad_alloc);
    // std::pmr containers draw from it.
    std::pmr::vector<int> v(&scratch);
    v.assign(300000, 7);
    CHECK(std::count(v.begin(), v.end(), 7) == 300000);
}

TEST_CASE("scratch memory lends each block to one user at a time across threads")
{
    // Two threads take and return blocks of varied sizes; each fills its block with its own mark
    // and checks it before returning it, so a block lent twice at once would show the other's.
    hypertree::scratch_memory scratch;
    std::atomic<int> corrupted{0};
    std::vector<std::thread> threads;
    for (int t = 0; t < 2; ++t)
        threads.emplace_back([&, t] {
            std::mt19937_64 g(std::uint64_t(100 + t));
            for (int round = 0; round < 400; ++round) {
                const std::size_t bytes = integer(g, 1, 200000);
                auto* p = static_cast<unsigned char*>(static_cast<std::pmr::memory_resource&>(scratch).allocate(bytes, 8));
                std::fill_n(p, bytes, static_cast<unsigned char>(t + 1));
                std::this_thread::yield();
                if (std::count(p, p + bytes, static_cast<unsigned char>(t + 1)) != std::ptrdiff_t(bytes)) ++corrupted;
                static_cast<std::pmr::memory_resource&>(scratch).deallocate(p, bytes, 8);
            }
        });
    for (std::thread& t : threads) t.join();
    CHECK(corrupted == 0);
    CHECK(scratch.system_allocations() < 800); // blocks were reused
}

// ---- density classes -------------------------------------------------------------------------------

namespace {
// Checks what density classes promise on entries, all by counting: contiguous increasing ranges
// holding every hit voxel once, the reported populations, the densities round(255 c / K), and
// classify's densities. Returns the populations.
std::vector<std::size_t> check_classes(const std::vector<voxel_entry>& entries,
                                       const hypertree::density_classes& classes)
{
    const auto k = classes.classes();
    REQUIRE(!k.empty());
    const std::size_t count = k.size();
    for (std::size_t c = 0; c + 1 < count; ++c) CHECK(k[c].most_hits < k[c + 1].fewest_hits);
    // The class holding a hit count: the last whose fewest_hits <= h, which must also reach h.
    const auto holding = [&](std::uint32_t h) -> std::ptrdiff_t {
        const auto after =
            std::upper_bound(k.begin(), k.end(), h, [](std::uint32_t x, const auto& kc) { return x < kc.fewest_hits; });
        if (after == k.begin() || h > std::prev(after)->most_hits) return -1;
        return std::prev(after) - k.begin();
    };
    std::vector<std::size_t> population(count, 0);
    std::size_t unclassed = 0;
    for (const voxel_entry& e : entries) {
        const std::ptrdiff_t c = holding(e.hits);
        if (c < 0)
            ++unclassed;
        else
            ++population[std::size_t(c)];
    }
    REQUIRE(unclassed == 0);
    for (std::size_t c = 0; c < count; ++c) {
        CHECK(k[c].population == population[c]);
        CHECK(population[c] > 0);
        // round(255 c / K) in integers: (2 * 255 * c + K) / (2 K), c = 1..K.
        CHECK(int(k[c].density) == int((2 * 255 * (c + 1) + count) / (2 * count)));
    }
    CHECK(k.back().density == 255);

    const auto stored = hypertree::classify(entries, classes, hypertree::no_branch_structure);
    REQUIRE(stored.size() == entries.size());
    std::size_t wrong = 0;
    for (std::size_t i = 0; i < entries.size(); ++i)
        wrong += stored[i].index != entries[i].voxel || stored[i].value.level != entries[i].level ||
                 stored[i].part != entries[i].part ||
                 stored[i].value.density != k[std::size_t(holding(entries[i].hits))].density;
    CHECK(wrong == 0);
    return population;
}

std::size_t largest_hit_count_population(const std::vector<voxel_entry>& entries, std::uint32_t from_hits = 0)
{
    std::map<std::uint32_t, std::size_t> by_hits;
    for (const voxel_entry& e : entries)
        if (e.hits >= from_hits) ++by_hits[e.hits];
    std::size_t largest = 0;
    for (const auto& [h, n] : by_hits) largest = std::max(largest, n);
    return largest;
}
} // namespace

TEST_CASE("density classes: near-equal populations on a geometric hit distribution")
{
    std::mt19937_64 g(3);
    std::vector<voxel_entry> entries(200000);
    for (std::size_t i = 0; i < entries.size(); ++i)
        entries[i] = {voxel_index(3 * i), geometric_hits(g, 0.002), std::uint8_t(integer(g, 0, 6)),
                      std::uint8_t(integer(g, 0, 4))};
    // One hit count cannot be split between classes, so a class can miss its equal share by up to
    // the largest number of voxels sharing one hit count.
    const double bound = double(largest_hit_count_population(entries));
    for (const int c : {3, 16, 64, 128, 255}) {
        INFO("classes " << c);
        const hypertree::density_classes classes(entries, c);
        CHECK(classes.class_count() == c);
        REQUIRE(classes.classes().size() == std::size_t(c - 1));
        const double share = double(entries.size()) / double(c - 1);
        for (const std::size_t population : check_classes(entries, classes))
            CHECK(std::abs(double(population) - share) <= bound);
    }
}

TEST_CASE("density classes: small, large and huge hit counts are counted alike")
{
    // The histogram is built three ways by the largest count: below 2^16 (four interleaved
    // tables), up to four per voxel (one table) and beyond (sorted). Each must give every class
    // the population counted by hand, here with list lengths that are not multiples of four.
    std::mt19937_64 g(11);
    struct shape {
        std::size_t voxels;
        double p; // geometric hit counts of mean 1 / p
    };
    for (const shape s : {shape{10002, 0.01}, shape{50003, 0.0001}, shape{30001, 0.00005}}) {
        std::vector<voxel_entry> entries(s.voxels);
        std::uint32_t most = 0;
        for (std::size_t i = 0; i < entries.size(); ++i) {
            entries[i] = {voxel_index(i), geometric_hits(g, s.p), 3, 1};
            most = std::max(most, entries[i].hits);
        }
        INFO(s.voxels << " voxels, largest count " << most);
        if (s.p == 0.0001) CHECK((most >= 65536 && most <= 4 * s.voxels + 1024));
        if (s.p == 0.00005) CHECK(most > 4 * s.voxels + 1024);
        for (const int c : {2, 32, 255}) check_classes(entries, hypertree::density_classes(entries, c));
    }
}

TEST_CASE("density classes: a figure 3 spike at one hit fills one class and the rest share evenly")
{
    std::mt19937_64 g(4);
    std::vector<voxel_entry> entries(100000);
    for (std::size_t i = 0; i < entries.size(); ++i) {
        const bool spike = krs_test::uniform(g, 0, 1) < 0.6;
        entries[i] = {voxel_index(i), spike ? 1u : 1 + geometric_hits(g, 0.003), 3, 1};
    }
    const std::size_t spike =
        std::size_t(std::count_if(entries.begin(), entries.end(), [](const voxel_entry& e) { return e.hits == 1; }));
    const hypertree::density_classes classes(entries, 32);
    const auto population = check_classes(entries, classes);
    REQUIRE(population.size() == 31);
    CHECK(classes.classes()[0].fewest_hits == 1);
    CHECK(classes.classes()[0].most_hits == 1);
    CHECK(population[0] == spike);
    const double share = double(entries.size() - spike) / 30.0;
    const double bound = double(largest_hit_count_population(entries, 2));
    for (std::size_t c = 1; c < population.size(); ++c) CHECK(std::abs(double(population[c]) - share) <= bound);
}

TEST_CASE("density classes: two classes make a binary hypertree")
{
    std::mt19937_64 g(5);
    std::vector<voxel_entry> entries;
    for (voxel_index i = 0; i < 5000; ++i)
        entries.push_back({i * 7, integer(g, 1, 400), std::uint8_t(integer(g, 0, 5)), 0});
    const hypertree::density_classes classes(entries, 2);
    REQUIRE(classes.classes().size() == 1);
    for (const stored_voxel& v : hypertree::classify(entries, classes, hypertree::no_branch_structure))
        CHECK(v.value.density == 255);
    CHECK(classes.class_of(0) == 0);
    CHECK(classes.density_of(0) == 0);
}

TEST_CASE("density classes: fewer distinct hit counts than classes spread densities up to 255")
{
    std::vector<voxel_entry> entries;
    for (voxel_index i = 0; i < 300; ++i) entries.push_back({i, 1 + i % 3, 2, 0});
    const hypertree::density_classes classes(entries, 128);
    const auto population = check_classes(entries, classes);
    REQUIRE(population.size() == 3);
    CHECK(classes.classes()[0].density == 85);
    CHECK(classes.classes()[1].density == 170);
    CHECK(classes.classes()[2].density == 255);
}

TEST_CASE("density classes: hit counts absent from the entries fall in the neighbouring class")
{
    std::vector<voxel_entry> entries;
    for (voxel_index i = 0; i < 40; ++i) entries.push_back({i, i < 20 ? 2u : 10u, 1, 0});
    const hypertree::density_classes classes(entries, 3);
    REQUIRE(classes.classes().size() == 2);
    CHECK(classes.class_of(1) == 1); // below the first class
    CHECK(classes.class_of(5) == 1); // between the classes: the lower one
    CHECK(classes.class_of(10) == 2);
    CHECK(classes.class_of(1000) == 2); // above the last class
    CHECK(classes.density_of(1000) == 255);
}

TEST_CASE("classify: the branching structure gets full density")
{
    std::mt19937_64 g(6);
    std::vector<voxel_entry> entries;
    for (voxel_index i = 0; i < 4000; ++i)
        entries.push_back({i * 5 + 1, geometric_hits(g, 0.05), std::uint8_t(i % 7), std::uint8_t(i % 3)});
    const hypertree::density_classes classes(entries, 16);
    for (const int depth : {hypertree::no_branch_structure, 0, 2, 6}) {
        INFO("branch depth " << depth);
        const auto stored = hypertree::classify(entries, classes, depth);
        REQUIRE(stored.size() == entries.size());
        for (std::size_t i = 0; i < entries.size(); ++i) {
            if (entries[i].level <= depth)
                CHECK(stored[i].value.density == 255);
            else
                CHECK(stored[i].value.density == classes.density_of(entries[i].hits));
        }
    }
}

TEST_CASE("classify on threads gives the voxels of one thread, drops entries without hits and finds disorder anywhere")
{
    // Tasks split the entries in four; every entry maps to its voxel by the classes (the
    // reference here is density_of, entry by entry), entries without hits go, and a voxel out of
    // order is refused wherever it lies: at a task's first entry (the check against the task
    // before) or inside one.
    const hypertree::parallel_for_hook pool = [](std::size_t count, const std::function<void(std::size_t)>& body) {
        std::vector<std::thread> threads;
        for (std::size_t t = 0; t < count; ++t) threads.emplace_back([&, t] { body(count - 1 - t); });
        for (std::thread& t : threads) t.join();
    };
    std::mt19937_64 g(65);
    std::vector<voxel_entry> entries;
    for (voxel_index i = 0; i < 100000; ++i)
        entries.push_back({i * 3 + 2, i % 97 == 5 ? 0u : geometric_hits(g, 0.1), std::uint8_t(i % 9), std::uint8_t(i % 5)});
    const hypertree::density_classes classes(entries, 12);
    const auto serial = hypertree::classify(entries, classes, 2);
    const auto threaded = hypertree::classify(entries, classes, 2, std::vector<stored_voxel>{}, pool);
    std::vector<stored_voxel> expected;
    for (const voxel_entry& e : entries)
        if (e.hits != 0) expected.push_back({e.voxel, voxel{e.level <= 2 ? std::uint8_t(255) : classes.density_of(e.hits), e.level}, e.part});
    REQUIRE(threaded.size() == expected.size());
    REQUIRE(serial.size() == expected.size());
    std::size_t wrong = 0;
    for (std::size_t i = 0; i < expected.size(); ++i)
        wrong += threaded[i].index != expected[i].index || !(threaded[i].value == expected[i].value) || threaded[i].part != expected[i].part ||
                 serial[i].index != expected[i].index || !(serial[i].value == expected[i].value) || serial[i].part != expected[i].part;
    CHECK(wrong == 0);
    for (const std::size_t at : {std::size_t(25000), std::size_t(50000), std::size_t(61234), entries.size() - 1}) {
        INFO("disorder at entry " << at);
        auto swapped = entries;
        std::swap(swapped[at - 1].voxel, swapped[at].voxel);
        CHECK_THROWS_WITH_AS(hypertree::classify(swapped, classes, 2, std::vector<stored_voxel>{}, pool),
                             doctest::Contains("classify.entries"), krs::invalid_parameter);
        CHECK_THROWS_AS(hypertree::classify(swapped, classes, 2), krs::invalid_parameter);
    }
}

TEST_CASE("density classes and classify refuse impossible parameters")
{
    const std::vector<voxel_entry> entries = {{1, 3, 0, 0}, {4, 1, 1, 0}};
    for (const int bad : {-1, 0, 1, 256, 1000}) {
        INFO("class count " << bad);
        try {
            hypertree::density_classes classes(entries, bad);
            FAIL("accepted");
        } catch (const krs::invalid_parameter& e) {
            CHECK(e.parameter() == "density_classes.class_count");
            CHECK(std::string(e.what()).find("between 2") != std::string::npos);
        }
    }
    CHECK_NOTHROW(hypertree::density_classes(entries, 2));
    CHECK_NOTHROW(hypertree::density_classes(entries, 255));
    const hypertree::density_classes classes(entries, 4);
    CHECK_THROWS_AS(hypertree::classify(entries, classes, -2), krs::invalid_parameter);
    CHECK_THROWS_AS(hypertree::classify(entries, classes, 256), krs::invalid_parameter);
    const std::vector<voxel_entry> unsorted = {{4, 1, 0, 0}, {1, 3, 0, 0}};
    CHECK_THROWS_AS(hypertree::classify(unsorted, classes, 0), krs::invalid_parameter);
    const std::vector<voxel_entry> repeated = {{4, 1, 0, 0}, {4, 3, 0, 0}};
    CHECK_THROWS_AS(hypertree::classify(repeated, classes, 0), krs::invalid_parameter);
}

TEST_CASE("hypertree pipeline: hits through compact and classify give a store of every hit voxel")
{
    std::mt19937_64 g(7);
    const auto hits = random_hits(g, 60000, 0, voxel_index(small_volume.voxel_count() - 1), 5, 3);
    const auto entries = hypertree::compact(hits);
    const auto stored = hypertree::classify(entries, hypertree::density_classes(entries, 8), 0);
    const auto store = hypertree::bit_array_store::build(small_volume, stored);
    const auto reference = compact_with_map(hits);
    std::vector<bool> hit_voxel(std::size_t(small_volume.voxel_count()), false);
    for (const voxel_entry& e : reference) hit_voxel[e.voxel] = true;
    std::size_t wrong = 0;
    for (voxel_index i = 0; i < small_volume.voxel_count(); ++i) wrong += (store.at(i).density != 0) != hit_voxel[i];
    CHECK(wrong == 0);
    CHECK(store.nonempty_count() == reference.size());
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

TEST_CASE("zeroed arrays start zero and copy deeply; copied stores answer like their originals")
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

TEST_CASE("huge-page blocks are zero, writable to their end and aligned as promised, with huge pages asked or not")
{
    for (const bool wanted : {true, false}) {
        hypertree::huge_pages_wanted = wanted;
        // Under, at and over half a huge page (where blocks start to be mapped on Linux), a whole
        // huge page, an odd size over several, and the 54 MB of a dense store at 300.
        for (const std::size_t bytes : {std::size_t(100), (std::size_t(1) << 20) - 8, std::size_t(1) << 20,
                                        std::size_t(2) << 20, (std::size_t(7) << 20) + 24, std::size_t(54000000)}) {
            INFO(bytes << " bytes, huge pages wanted " << wanted);
            auto* p = static_cast<unsigned char*>(hypertree::pages::allocate_zeroed(bytes));
            REQUIRE(p != nullptr);
            const auto address = reinterpret_cast<std::uintptr_t>(p);
            CHECK(address % alignof(std::max_align_t) == 0);
            CHECK(address % hypertree::pages::alignment(bytes) == 0);
#ifdef __linux__
            // The promise in numbers: from 1 MiB on, a block starts on a 2 MiB boundary.
            if (bytes >= (std::size_t(1) << 20)) CHECK(address % (std::size_t(2) << 20) == 0);
            else CHECK(hypertree::pages::alignment(bytes) == alignof(std::max_align_t));
#endif
            CHECK(std::all_of(p, p + bytes, [](unsigned char b) { return b == 0; }));
            std::fill(p, p + bytes, 0xab); // every byte is ours: no fault past the end
            CHECK(p[bytes - 1] == 0xab);
            hypertree::pages::release(p, bytes);
        }
    }
    hypertree::huge_pages_wanted = true;
    CHECK_THROWS_AS((void)hypertree::pages::allocate_zeroed(0), std::bad_alloc);
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

// ---- operations ----------------------------------------------------------------------------------

namespace {
// The union rules written out per voxel.
voxel max_rule(voxel a, voxel b)
{
    if (a.density == 0) return b;
    if (b.density == 0) return a;
    if (a.density != b.density) return a.density > b.density ? a : b;
    return {a.density, std::min(a.level, b.level)};
}
voxel sum_rule(voxel a, voxel b)
{
    if (a.density == 0) return b;
    if (b.density == 0) return a;
    return {std::uint8_t(std::min(255, a.density + b.density)), std::min(a.level, b.level)};
}
} // namespace

TEST_CASE("unite_max is the per-voxel maximum and is commutative and idempotent")
{
    std::mt19937_64 g(11);
    const auto va = random_voxels(g, small_volume, 0.2);
    const auto vb = random_voxels(g, small_volume, 0.2);
    const auto a_list = hypertree::index_list_store::build(small_volume, va);
    const auto a_dense = hypertree::dense_store::build(small_volume, va);
    const auto b_parts = hypertree::partitioned_store::build(small_volume, vb);
    const auto b_bits = hypertree::bit_array_store::build(small_volume, vb);
    const auto ga = grid_of(small_volume, va), gb = grid_of(small_volume, vb);

    std::vector<voxel> expected(ga.size());
    for (std::size_t i = 0; i < ga.size(); ++i) expected[i] = max_rule(ga[i], gb[i]);
    const auto ab = hypertree::unite_max(a_list, b_parts);
    const auto ba = hypertree::unite_max(b_bits, a_dense);
    CHECK(count_differences(grid_of(small_volume, ab), expected) == 0);
    CHECK(count_differences(grid_of(small_volume, ba), expected) == 0);
    CHECK(std::is_sorted(ab.begin(), ab.end(),
                         [](const stored_voxel& x, const stored_voxel& y) { return x.index < y.index; }));

    CHECK(count_differences(grid_of(small_volume, hypertree::unite_max(a_list, a_dense)), ga) == 0);
    CHECK(count_differences(grid_of(small_volume, hypertree::unite_max(b_parts, b_parts)), gb) == 0);

    const hypertree::partitioned_store united =
        hypertree::unite_max_store(b_parts, hypertree::partitioned_store::build(small_volume, va));
    CHECK(count_differences(grid_of_store(united), expected) == 0);
    const hypertree::dense_store united_dense =
        hypertree::unite_max_store(a_dense, hypertree::dense_store::build(small_volume, vb));
    CHECK(count_differences(grid_of_store(united_dense), expected) == 0);
}

TEST_CASE("unite_sum saturates at 255 and keeps the shallower level")
{
    std::mt19937_64 g(12);
    const auto va = random_voxels(g, small_volume, 0.3);
    const auto vb = random_voxels(g, small_volume, 0.3);
    const auto a = hypertree::bit_array_store::build(small_volume, va);
    const auto b = hypertree::index_list_store::build(small_volume, vb);
    const auto ga = grid_of(small_volume, va), gb = grid_of(small_volume, vb);
    std::vector<voxel> expected(ga.size());
    std::size_t saturated = 0;
    for (std::size_t i = 0; i < ga.size(); ++i) {
        expected[i] = sum_rule(ga[i], gb[i]);
        saturated += ga[i].density + gb[i].density > 255;
    }
    REQUIRE(saturated > 100);
    CHECK(count_differences(grid_of(small_volume, hypertree::unite_sum(a, b)), expected) == 0);
    CHECK(count_differences(grid_of(small_volume, hypertree::unite_sum(b, a)), expected) == 0);
    CHECK(count_differences(
              grid_of_store(hypertree::unite_sum_store(a, hypertree::bit_array_store::build(small_volume, vb))),
              expected) == 0);
}

TEST_CASE("clear and set change exactly the voxels whose centers are inside the region")
{
    std::mt19937_64 g(13);
    const auto voxels = random_voxels(g, small_volume, 0.25);
    const auto original = grid_of(small_volume, voxels);
    const auto list = hypertree::index_list_store::build(small_volume, voxels);
    const auto parts = hypertree::partitioned_store::build(small_volume, voxels);
    const vec3d lo = small_volume.origin(), hi = small_volume.maximum();

    const auto check_region = [&](const auto& region, const auto& inside, const char* name) {
        INFO(name);
        const auto cleared = grid_of(small_volume, hypertree::clear(list, region));
        const voxel value{200, 3};
        const auto set = grid_of(small_volume, hypertree::set(parts, region, value, 2));
        std::size_t wrong_clear = 0, wrong_set = 0, inside_count = 0;
        for (voxel_index i = 0; i < small_volume.voxel_count(); ++i) {
            const bool in = inside(small_volume.voxel_center(i));
            inside_count += in;
            wrong_clear += !(cleared[i] == (in ? voxel{} : original[i]));
            wrong_set += !(set[i] == (in ? value : original[i]));
        }
        CHECK(wrong_clear == 0);
        CHECK(wrong_set == 0);
        // Same through the store-kind variants, and set with density 0 clears.
        CHECK(count_differences(grid_of_store(hypertree::clear_store(parts, region)), cleared) == 0);
        CHECK(count_differences(grid_of_store(hypertree::set_store(list, region, value)), set) == 0);
        CHECK(count_differences(grid_of(small_volume, hypertree::set(list, region, voxel{0, 4})), cleared) == 0);
        return inside_count;
    };

    const vec3d box_lo{lo.x + 0.3, lo.y - 1.0, lo.z + 0.2}, box_hi{lo.x + 1.1, lo.y + 0.7, hi.z + 3.0};
    CHECK(check_region(
              hypertree::box_region(box_lo, box_hi),
              [&](const vec3d& p) {
                  return p.x >= box_lo.x && p.x <= box_hi.x && p.y >= box_lo.y && p.y <= box_hi.y && p.z >= box_lo.z &&
                         p.z <= box_hi.z;
              },
              "box") > 1000);
    const vec3d c{lo.x + 1.7, lo.y + 0.6, lo.z + 0.4};
    CHECK(check_region(
              hypertree::sphere_region(c, 0.55),
              [&](const vec3d& p) {
                  const double dx = p.x - c.x, dy = p.y - c.y, dz = p.z - c.z;
                  return std::sqrt(dx * dx + dy * dy + dz * dz) <= 0.55;
              },
              "sphere") > 1000);
    const vec3d q{lo.x + 1.0, lo.y + 0.5, lo.z + 0.5}, n{0.3, -1.0, 0.45};
    const double n_length = std::sqrt(n.x * n.x + n.y * n.y + n.z * n.z);
    CHECK(
        check_region(
            hypertree::half_space_region(q, n),
            [&](const vec3d& p) { return ((p.x - q.x) * n.x + (p.y - q.y) * n.y + (p.z - q.z) * n.z) / n_length >= 0; },
            "oblique half-space") > 1000);
    const vec3d up{0, 0, 1};
    const vec3d top{0, 0, lo.z + 0.61};
    CHECK(check_region(
              hypertree::half_space_region(top, up), [&](const vec3d& p) { return p.z >= top.z; }, "trimming plane") >
          1000);
    CHECK(check_region(
              hypertree::half_space_region(hi + vec3d{1, 1, 1}, vec3d{1, 1, 1}), [](const vec3d&) { return false; },
              "half-space beyond the volume") == 0);
    CHECK(check_region(
              hypertree::sphere_region(lo - vec3d{5, 5, 5}, 1.0), [](const vec3d&) { return false; },
              "sphere outside the volume") == 0);
    CHECK(check_region(
              hypertree::box_region(lo - vec3d{1, 1, 1}, hi + vec3d{1, 1, 1}), [](const vec3d&) { return true; },
              "box around the volume") == small_volume.voxel_count());
}

TEST_CASE("operations refuse stores of different hypervolumes")
{
    std::mt19937_64 g(14);
    const auto voxels = random_voxels(g, small_volume, 0.1);
    const auto a = hypertree::index_list_store::build(small_volume, voxels);
    const hypervolume finer(small_volume.origin(), small_volume.extent(), {40, 30, 21});
    const hypervolume moved(small_volume.origin() + vec3d{0.5, 0, 0}, small_volume.extent(), small_volume.grid());
    for (const hypervolume& other : {finer, moved}) {
        const auto b = hypertree::index_list_store::build(other, {});
        try {
            (void)hypertree::unite_max(a, b);
            FAIL("different hypervolumes united");
        } catch (const krs::invalid_parameter& e) {
            CHECK(std::string(e.what()).find("same hypervolume") != std::string::npos);
        }
        CHECK_THROWS_AS((void)hypertree::unite_sum(b, a), krs::invalid_parameter);
        CHECK_THROWS_AS((void)hypertree::unite_max_store(a, b), krs::invalid_parameter);
    }
}

TEST_CASE("regions refuse impossible parameters and set refuses a result over budget")
{
    const vec3d nan{std::nan(""), 0, 0};
    CHECK_THROWS_AS(hypertree::box_region({1, 0, 0}, {0, 1, 1}), krs::invalid_parameter);
    CHECK_THROWS_AS(hypertree::box_region(nan, {0, 1, 1}), krs::invalid_parameter);
    CHECK_THROWS_AS(hypertree::sphere_region({0, 0, 0}, -1.0), krs::invalid_parameter);
    CHECK_THROWS_AS(hypertree::sphere_region(nan, 1.0), krs::invalid_parameter);
    CHECK_THROWS_AS(hypertree::half_space_region({0, 0, 0}, {0, 0, 0}), krs::invalid_parameter);
    // Huge and tiny normals are directions like any other: (0, 1e160, 0) overflowed its length to
    // infinity and became (0, 0, 0), which contains every point (a clear wiped the store), and
    // (1e-170, 0, 0) underflowed to 0 and was refused.
    const hypertree::half_space_region huge({0, 100, 0}, {0, 1e160, 0}), tiny({0, 0, 0}, {1e-170, 0, 0});
    CHECK(huge.normal.y == 1.0);
    CHECK_FALSE(huge.contains({0, 0, 0}));
    CHECK(huge.contains({0, 101, 0}));
    CHECK(tiny.normal.x == 1.0);
    CHECK_THROWS_AS(hypertree::half_space_region({0, 0, 0}, nan), krs::invalid_parameter);

    const auto store = hypertree::index_list_store::build(small_volume, {});
    const hypertree::box_region everything(small_volume.origin(), small_volume.maximum());
    CHECK_THROWS_AS((void)hypertree::set(store, everything, voxel{9, 0}, 0, hypertree::memory_budget{1000}),
                    krs::invalid_parameter);
    CHECK(hypertree::set(store, everything, voxel{9, 0}).size() == small_volume.voxel_count());
}

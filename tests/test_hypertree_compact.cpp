// Hypertree validation (paper section 5, create/compact.hpp): compact and its chunked, threaded and
// bucketed forms against a std::map over the hits, which merges by the definition (count, shallowest
// level, smallest part on a tie).

#include "hypertree/create/compact.hpp"
#include "hypertree/create/scratch.hpp"
#include "hypertree/execution.hpp"

#include "support/threads.hpp"
#include "support/voxel_reference.hpp"

#include <doctest/doctest.h>

#include <algorithm>
#include <atomic>
#include <cstddef>
#include <cstdint>
#include <functional>
#include <map>
#include <memory_resource>
#include <random>
#include <span>
#include <thread>
#include <vector>

namespace {
using hypertree::hit;
using hypertree::voxel_entry;
using hypertree::voxel_index;
using krs_test::compact_with_map;
using krs_test::integer;
using krs_test::random_hits;

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
} // namespace

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
    const hypertree::parallel_for_hook pool = krs_test::strided_threads(2);
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
    const hypertree::parallel_for_hook pool = krs_test::strided_threads(2);
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

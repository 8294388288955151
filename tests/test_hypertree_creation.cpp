// build_tree's creation path (generation in groups of chunks; per-voxel tables up to 2^21 voxels,
// else four-way bucketing, the merge's groups classified where they lie) against a brute-force
// reference built from generate()'s hit list with a std::map (compact_with_map,
// support/voxel_reference.hpp): per voxel the hit count and the shallowest (level, part), then the
// density classes of those entries and the branch rule, voxel by voxel. The reference shares
// only the generator (tested on its own in test_hypertree_ifs.cpp) and the placing of classes
// over a histogram (test_hypertree_density.cpp) with the code under test.

#include "hypertree/build.hpp"
#include "hypertree/create/voxel_table.hpp"
#include "hypertree/execution.hpp"
#include "hypertree/presets.hpp"

#include "support/threads.hpp"
#include "support/voxel_reference.hpp"

#include <doctest/doctest.h>

#include <algorithm>
#include <stdexcept>
#include <utility>
#include <vector>

using namespace hypertree;

namespace {

std::vector<stored_voxel> brute_force_voxels(const ifs<>& tree, std::uint64_t seed, int class_count)
{
    const std::vector<voxel_entry> entries = krs_test::compact_with_map(generate(tree, seed).hits);
    const density_classes classes(entries, class_count);
    std::vector<stored_voxel> voxels;
    for (const voxel_entry& e : entries) {
        const std::uint8_t density = int(e.level) <= tree.branch_depth ? 255 : classes.density_of(e.hits);
        voxels.push_back({e.voxel, voxel{density, e.level}, e.part});
    }
    return voxels;
}

} // namespace

TEST_CASE("hypertree creation: build_tree's voxels equal a brute-force map over generate()'s hits, presets A-D")
{
    // Full workloads (tree A: 25 chunks in 8 groups; D: 82 chunks; C: lines of up to 33 voxels),
    // at 100 and 300, on one thread and two: every voxel's index, density, level and part.
    for (const int resolution : {100, 300}) {
        for (const auto& make : {presets::tree_a, presets::tree_b, presets::tree_c, presets::tree_d}) {
            const ifs<> tree = make(resolution);
            const std::vector<stored_voxel> expected = brute_force_voxels(tree, 5, 32);
            REQUIRE(expected.size() > 10000);
            for (const bool threaded : {false, true}) {
                INFO("tree " << tree.name << " at " << resolution << (threaded ? ", two threads" : ", one thread"));
                scratch_memory scratch;
                generation_options options;
                if (threaded) options.parallel_for = krs_test::strided_threads(2);
                const std::pmr::vector<stored_voxel> voxels = detail::stored_voxels_of(tree, 5, 32, options, &scratch);
                REQUIRE(voxels.size() == expected.size());
                std::size_t differ = 0;
                for (std::size_t i = 0; i < expected.size(); ++i)
                    differ += voxels[i].index != expected[i].index || !(voxels[i].value == expected[i].value) || voxels[i].part != expected[i].part;
                CHECK(differ == 0);
            }
        }
    }
}

TEST_CASE("hypertree creation: generation in groups of chunks makes the chunk-by-chunk hit list")
{
    // Groups of consecutive chunks in one buffer each: the hits taken in group order are
    // generate()'s, in the same order, whatever the number of groups.
    auto tree = presets::tree_c(80);
    tree.iterations = 30000;
    generation_options options;
    options.chunk_cycles = 250; // 24 chunks
    const generated_hits whole = generate(tree, 3, options);
    for (const std::size_t groups : {std::size_t(1), std::size_t(5), std::size_t(24), std::size_t(100)}) {
        INFO(groups << " groups");
        detail::no_observer observer;
        std::vector<hit> taken;
        std::size_t calls = 0;
        detail::generate_chunks(tree, 3, options, observer, [&](std::size_t, detail::chunk_output& out) {
            ++calls;
            taken.insert(taken.end(), out.data(), out.data() + out.size());
        }, groups);
        CHECK(calls == std::min<std::size_t>(groups, 24));
        REQUIRE(taken.size() == whole.hits.size());
        std::size_t differ = 0;
        for (std::size_t i = 0; i < taken.size(); ++i)
            differ += taken[i].voxel != whole.hits[i].voxel || taken[i].level != whole.hits[i].level || taken[i].part != whole.hits[i].part;
        CHECK(differ == 0);
    }
}

TEST_CASE("hypertree creation: classify over pieces finds disorder across piece boundaries")
{
    // Entries sorted within each piece but not across two of them, an empty piece between: the
    // refusal names the voxels, as classify's over the whole list does.
    const std::vector<voxel_entry> first = {{1, 2, 3, 0}, {5, 1, 3, 0}}, second = {{5, 1, 3, 0}, {9, 4, 3, 0}};
    const std::vector<std::span<const voxel_entry>> pieces = {first, {}, second};
    const density_classes classes(std::span<const std::span<const voxel_entry>>(pieces), 8, {});
    CHECK_THROWS_WITH_AS(classify_pieces(std::span<const std::span<const voxel_entry>>(pieces), classes, 1), doctest::Contains("voxel 5 after 5"),
                         krs::invalid_parameter);
    const std::vector<voxel_entry> third = {{6, 1, 3, 0}, {9, 4, 3, 0}};
    const std::vector<std::span<const voxel_entry>> sorted = {first, {}, third};
    const auto voxels = classify_pieces(std::span<const std::span<const voxel_entry>>(sorted), classes, 1);
    // Each voxel as the classes give it, written out here: level <= branch depth 1 is full
    // density, deeper levels take their count's class; index, level and part as entered.
    const std::vector<voxel_entry> all = {first[0], first[1], third[0], third[1]};
    REQUIRE(voxels.size() == all.size());
    for (std::size_t i = 0; i < all.size(); ++i) {
        INFO("voxel " << all[i].voxel);
        CHECK(voxels[i].index == all[i].voxel);
        CHECK(voxels[i].value.level == all[i].level);
        CHECK(voxels[i].part == all[i].part);
        CHECK(voxels[i].value.density == (all[i].level <= 1 ? 255 : classes.density_of(all[i].hits)));
    }
    // Disorder inside a later piece (not at its border) is refused too, naming those voxels.
    const std::vector<voxel_entry> unsorted_inside = {{6, 1, 3, 0}, {12, 4, 3, 0}, {11, 2, 3, 0}};
    const std::vector<std::span<const voxel_entry>> late = {first, {}, unsorted_inside};
    CHECK_THROWS_WITH_AS(classify_pieces(std::span<const std::span<const voxel_entry>>(late), classes, 1), doctest::Contains("voxel 11 after 12"),
                         krs::invalid_parameter);
}

TEST_CASE("hypertree creation: the per-voxel table (two tables at once) equals a brute-force map, and flags a voxel past 2^17 hits")
{
    // Hits drawn at random over a small grid whose size is not a multiple of the table's lines
    // (16 slots) nor of its used words (1024 slots), many per voxel, levels and parts over their
    // whole range; given to two tables at once, as two tasks would, then read out in three pieces.
    const std::uint64_t voxel_count = 70001;
    std::vector<hit> hits;
    std::uint64_t state = 12345;
    const auto next = [&] {
        state = state * 6364136223846793005ull + 1442695040888963407ull;
        return std::uint32_t(state >> 33);
    };
    for (int i = 0; i < 400000; ++i) {
        const std::uint32_t r = next();
        // Half the hits in the first 3000 voxels (runs of the same voxel), the rest anywhere.
        const voxel_index v = voxel_index((r & 1) ? next() % 3000 : next() % voxel_count);
        hits.push_back({v, std::uint8_t(next() % 64), std::uint8_t(next() % 256)});
    }
    hits.push_back({voxel_index(voxel_count - 1), 63, 255});
    const std::vector<voxel_entry> expected = krs_test::compact_with_map(hits);
    scratch_memory scratch;
    detail::voxel_table_pool pool(voxel_count, &scratch);
    const std::size_t half = hits.size() / 2;
    // Nested: the outer task holds its table, so the inner one makes a second.
    pool.with_table([&](detail::voxel_table& first) {
        first.add({hits.data(), half});
        pool.with_table([&](detail::voxel_table& second) {
            CHECK(&second != &first);
            second.add({hits.data() + half, hits.size() - half});
        });
    });
    REQUIRE(!pool.overflowed());
    const auto pieces = pool.read_out<std::vector<voxel_entry>>(3, krs_test::strided_threads(2));
    std::vector<voxel_entry> entries;
    for (const auto& p : pieces) entries.insert(entries.end(), p.begin(), p.end());
    REQUIRE(entries.size() == expected.size());
    std::size_t differ = 0;
    for (std::size_t i = 0; i < entries.size(); ++i) {
        const voxel_entry &got = entries[i], &e = expected[i];
        differ += got.voxel != e.voxel || got.hits != e.hits || got.level != e.level || got.part != e.part;
    }
    CHECK(differ == 0);
    // Read out, the tables are empty again: a second round gives the same entries.
    pool.with_table([&](detail::voxel_table& t) { t.add(hits); });
    const auto again = pool.read_out<std::vector<voxel_entry>>(1, {});
    REQUIRE(again.size() == 1);
    CHECK(again[0].size() == entries.size());
    CHECK(std::equal(again[0].begin(), again[0].end(), entries.begin(), [](const voxel_entry& a, const voxel_entry& b) {
        return a.voxel == b.voxel && a.hits == b.hits && a.level == b.level && a.part == b.part;
    }));

    // 2^17 - 1 hits in one voxel fit; one more is flagged (the caller then takes the bucketed path).
    detail::voxel_table_pool busy(16, &scratch);
    const std::vector<hit> same((std::size_t(1) << 17) - 1, hit{7, 3, 1});
    busy.with_table([&](detail::voxel_table& t) { t.add(same); });
    CHECK(!busy.overflowed());
    const auto one = busy.read_out<std::vector<voxel_entry>>(1, {});
    REQUIRE(one.size() == 1);
    REQUIRE(one[0].size() == 1);
    CHECK(one[0][0].hits == (1u << 17) - 1);
    busy.with_table([&](detail::voxel_table& t) { t.add(same), t.add(std::vector<hit>(2, hit{7, 3, 1})); });
    CHECK(busy.overflowed());

    // Hits the table cannot hold are refused, naming the parameter.
    detail::voxel_table_pool small(16, &scratch);
    small.with_table([&](detail::voxel_table& t) {
        CHECK_THROWS_WITH_AS(t.add(std::vector<hit>{{3, 1, 0}, {16, 1, 0}}), doctest::Contains("voxel_table.hits"), krs::invalid_parameter);
        CHECK_THROWS_WITH_AS(t.add(std::vector<hit>{{3, 64, 0}}), doctest::Contains("level 64"), krs::invalid_parameter);
    });
    // A task that throws still returns its table: the next task is handed the same one.
    detail::voxel_table_pool thrown(16, &scratch);
    const detail::voxel_table* used = nullptr;
    CHECK_THROWS_AS(thrown.with_table([&](detail::voxel_table& t) {
        used = &t;
        throw std::runtime_error("a task failed");
    }),
                    std::runtime_error);
    const detail::voxel_table* handed = nullptr;
    thrown.with_table([&](detail::voxel_table& t) { handed = &t; });
    CHECK(handed == used);
}

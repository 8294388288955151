// Density classes and classify (paper section 4, create/density.hpp), all by counting: the classes
// hold every hit voxel once in contiguous ranges of hit counts with near-equal populations, and
// classify gives each voxel its class's density. Last, hits through compact and classify into a
// store, against a std::map over the hits.

#include "hypertree/create/compact.hpp"
#include "hypertree/create/density.hpp"
#include "hypertree/execution.hpp"
#include "hypertree/store/bit_array_store.hpp"

#include "support/random.hpp"
#include "support/voxel_reference.hpp"

#include <doctest/doctest.h>

#include <algorithm>
#include <cmath>
#include <cstddef>
#include <cstdint>
#include <functional>
#include <iterator>
#include <map>
#include <random>
#include <string>
#include <thread>
#include <utility>
#include <vector>

namespace {
using hypertree::hit;
using hypertree::stored_voxel;
using hypertree::voxel;
using hypertree::voxel_entry;
using hypertree::voxel_index;
using krs_test::compact_with_map;
using krs_test::integer;
using krs_test::random_hits;
using krs_test::small_volume;

// 1 + a geometric number of failures with success probability p (inverse transform).
std::uint32_t geometric_hits(std::mt19937_64& g, double p)
{
    const double u = krs_test::uniform(g, 0, 1);
    return 1 + std::uint32_t(std::floor(std::log1p(-u) / std::log1p(-p)));
}

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

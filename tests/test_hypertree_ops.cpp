// The volume operations (paper section 7, ops.hpp) and their regions (region.hpp): unions, clear and
// set over every store kind, against the rules written out per voxel over a plain array of every
// voxel of the grid.

#include "hypertree/ops.hpp"
#include "hypertree/region.hpp"
#include "hypertree/store/store_kinds.hpp"

#include "support/voxel_reference.hpp"

#include <doctest/doctest.h>

#include <algorithm>
#include <cmath>
#include <cstddef>
#include <cstdint>
#include <random>
#include <string>
#include <vector>

namespace {
using hypertree::hypervolume;
using hypertree::stored_voxel;
using hypertree::voxel;
using hypertree::voxel_index;
using krs::vec3d;
using krs_test::count_differences;
using krs_test::grid_of;
using krs_test::grid_of_store;
using krs_test::random_voxels;
using krs_test::small_volume;

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

#pragma once
// The brute-force references the hypertree creation, store and operation tests share
// (test_hypertree_compact.cpp, test_hypertree_creation.cpp, test_hypertree_density.cpp,
// test_hypertree_lod.cpp, test_hypertree_ops.cpp, test_hypertree_scratch.cpp,
// test_hypertree_store.cpp): a std::map for validation, a plain array of every voxel of the grid for
// stores and operations, and the random hit and voxel lists they are given. Written with nothing
// of the code under test beyond its data types, so a store or an operation is compared with a
// reference that cannot share its mistakes.

#include "hypertree/store/store.hpp"
#include "hypertree/voxel.hpp"

#include "random.hpp"

#include <doctest/doctest.h>

#include <algorithm>
#include <cstddef>
#include <cstdint>
#include <map>
#include <random>
#include <utility>
#include <vector>

namespace krs_test {

// ---- compaction reference ---------------------------------------------------------------------

// One entry per hit voxel by the definition of validation (paper section 5): the hits counted, the
// shallowest level kept, and with a tie the smallest part.
inline std::vector<hypertree::voxel_entry> compact_with_map(const std::vector<hypertree::hit>& hits)
{
    struct merged {
        std::uint32_t hits = 0;
        int level = 1000, part = 1000;
    };
    std::map<hypertree::voxel_index, merged> by_voxel;
    for (const hypertree::hit& h : hits) {
        merged& m = by_voxel[h.voxel];
        ++m.hits;
        if (h.level < m.level || (h.level == m.level && h.part < m.part)) m.level = h.level, m.part = h.part;
    }
    std::vector<hypertree::voxel_entry> entries;
    for (const auto& [v, m] : by_voxel) entries.push_back({v, m.hits, std::uint8_t(m.level), std::uint8_t(m.part)});
    return entries;
}

inline std::vector<hypertree::hit> random_hits(std::mt19937_64& g, std::size_t count, hypertree::voxel_index lowest,
                                               hypertree::voxel_index highest, int levels, int parts)
{
    std::vector<hypertree::hit> hits(count);
    for (hypertree::hit& h : hits)
        h = {integer(g, lowest, highest), std::uint8_t(integer(g, 0, levels - 1)),
             std::uint8_t(integer(g, 0, parts - 1))};
    return hits;
}

// ---- store and operation reference: every voxel of the grid -------------------------------------

inline std::vector<hypertree::voxel> grid_of(const hypertree::hypervolume& volume,
                                             const std::vector<hypertree::stored_voxel>& voxels)
{
    std::vector<hypertree::voxel> grid(std::size_t(volume.voxel_count()));
    for (const hypertree::stored_voxel& v : voxels) grid[v.index] = v.value;
    return grid;
}

template <class S>
std::vector<hypertree::voxel> grid_of_store(const S& store)
{
    std::vector<hypertree::voxel> grid(std::size_t(store.volume().voxel_count()));
    for (std::size_t i = 0; i < grid.size(); ++i) grid[i] = store.at(hypertree::voxel_index(i));
    return grid;
}

// Each voxel of the grid non-empty with probability `fill`, with a random density 1..255, level
// 0..levels - 1 and part 0..parts - 1; sorted by construction.
inline std::vector<hypertree::stored_voxel> random_voxels(std::mt19937_64& g, const hypertree::hypervolume& volume,
                                                          double fill, int parts = 4, int levels = 8)
{
    std::vector<hypertree::stored_voxel> voxels;
    for (hypertree::voxel_index i = 0; i < volume.voxel_count(); ++i)
        if (uniform(g, 0, 1) < fill)
            voxels.push_back({i, hypertree::voxel{std::uint8_t(integer(g, 1, 255)), std::uint8_t(integer(g, 0, levels - 1))},
                              std::uint8_t(integer(g, 0, parts - 1))});
    return voxels;
}

// Bounds by the definition: min and max coordinates of the voxels, computed by % and /.
inline hypertree::index_box bounds_by_hand(const hypertree::hypervolume& volume,
                                           const std::vector<hypertree::stored_voxel>& voxels)
{
    using hypertree::voxel_index;
    hypertree::index_box box;
    if (voxels.empty()) return box;
    const auto n = volume.grid();
    box.lo = {n.x, n.y, n.z};
    box.hi = {-1, -1, -1};
    for (const hypertree::stored_voxel& v : voxels) {
        const int c[3] = {int(v.index % voxel_index(n.x)), int(v.index / voxel_index(n.x) % voxel_index(n.y)),
                          int(v.index / voxel_index(n.x) / voxel_index(n.y))};
        for (int a = 0; a < 3; ++a) box.lo[a] = std::min(box.lo[a], c[a]), box.hi[a] = std::max(box.hi[a], c[a]);
    }
    return box;
}

// A store's visit (for_each) is the list it was built from: every voxel once, in index order.
template <class S>
void check_visits_the_list(const S& store, const std::vector<hypertree::stored_voxel>& voxels)
{
    std::vector<std::pair<hypertree::voxel_index, hypertree::voxel>> visited;
    store.for_each([&](hypertree::voxel_index i, hypertree::voxel v) { visited.emplace_back(i, v); });
    REQUIRE(visited.size() == voxels.size());
    std::size_t wrong = 0;
    for (std::size_t k = 0; k < voxels.size(); ++k)
        wrong += visited[k].first != voxels[k].index || !(visited[k].second == voxels[k].value);
    CHECK(wrong == 0);
    CHECK(store.nonempty_count() == voxels.size());
}

inline std::size_t count_differences(const std::vector<hypertree::voxel>& a, const std::vector<hypertree::voxel>& b)
{
    REQUIRE(a.size() == b.size());
    std::size_t different = 0;
    for (std::size_t i = 0; i < a.size(); ++i) different += !(a[i] == b[i]);
    return different;
}

// A small grid with unequal sides and an off-origin box, so that an axis or an offset mixed up
// shows.
inline const hypertree::hypervolume small_volume({-1.5, 0.25, 2.0}, {2.0, 1.2, 0.9}, {40, 30, 20});

} // namespace krs_test

#pragma once
// dense_store: the hypertree as a plain 3D array (paper section 5).
//
// The fastest lookup, one load, at the price of memory for every voxel of the grid whether hit or
// not: 2 bytes per voxel (density and level), 54 MB at 300^3 and 2 GB at 1000^3 (reported and
// budgeted in full, as the paper counts it; the pages no voxel is written to stay untouched zero
// pages until read, see zeroed_array.hpp). The paper keeps this form for resolutions up to about
// 300. Density and level sit side by side in one 2-byte `voxel`, so a lookup touches one cache
// line, not two arrays.

#include "hypertree/store/store.hpp"
#include "hypertree/store/zeroed_array.hpp"

#include <cassert>
#include <cstddef>
#include <cstdint>
#include <cstring>
#include <span>
#include <string>

namespace hypertree {

class dense_store {
public:
    static constexpr std::size_t bytes_per_voxel = sizeof(voxel);

    // An empty store over the default one-voxel hypervolume.
    dense_store() : voxels_(1) {}

    static std::size_t bytes_needed(const hypervolume& volume, std::span<const stored_voxel> = {})
    {
        return bytes_per_voxel * std::size_t(volume.voxel_count());
    }

    static dense_store build(const hypervolume& volume, std::span<const stored_voxel> voxels, memory_budget budget = {})
    {
        detail::require_storable("dense_store", volume, voxels);
        detail::require_within_budget("dense_store", bytes_needed(volume), budget,
                                      std::to_string(bytes_per_voxel) + " bytes x " +
                                          std::to_string(volume.voxel_count()) + " voxels of the grid");
        dense_store store(volume);
        for (const stored_voxel& v : voxels) store.voxels_[v.index] = v.value;
        store.count_ = voxels.size();
        store.bounds_ = detail::bounds_of(volume, voxels);
        if (!voxels.empty()) store.first_ = voxels.front().index, store.last_ = voxels.back().index;
        return store;
    }

    const hypervolume& volume() const { return volume_; }
    // Precondition: i < volume().voxel_count().
    voxel at(voxel_index i) const
    {
        assert(i < voxels_.size());
        return voxels_[i];
    }
    std::size_t memory_bytes() const { return voxels_.size() * sizeof(voxel); }
    std::size_t nonempty_count() const { return count_; }
    index_box bounds() const { return bounds_; }

    // Scans only [first, last] non-empty index, not the whole grid, and skips runs of empty
    // voxels 4 at a time (8 bytes read as one word: most of a sparse tree's grid is empty).
    template <class F>
    void for_each(F&& visit) const
    {
        static_assert(sizeof(voxel) == 2, "4 voxels per 8-byte word");
        if (count_ == 0) return;
        const voxel* v = voxels_.data();
        std::size_t i = first_;
        for (; i + 4 <= last_ + 1; i += 4) {
            std::uint64_t word;
            std::memcpy(&word, v + i, sizeof word);
            if (word == 0) continue;
            for (std::size_t j = i; j < i + 4; ++j)
                if (v[j].density != 0) visit(voxel_index(j), v[j]);
        }
        for (; i <= last_; ++i)
            if (v[i].density != 0) visit(voxel_index(i), v[i]);
    }

private:
    explicit dense_store(const hypervolume& volume) : volume_(volume), voxels_(std::size_t(volume.voxel_count())) {}

    hypervolume volume_{};
    zeroed_array<voxel> voxels_; // the empty voxels cost nothing until written (zeroed_array.hpp)
    std::size_t count_ = 0;
    index_box bounds_{};
    voxel_index first_ = 0, last_ = 0;
};

static_assert(voxel_store<dense_store>);

} // namespace hypertree

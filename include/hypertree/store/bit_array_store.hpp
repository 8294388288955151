#pragma once
// bit_array_store: the index list with an occupancy bit array in front (paper section 5).
//
// Most lookups a raymarcher makes are of empty voxels, and in an index list those cost a full
// bisection. The paper's compromise for medium resolutions (300-600) adds one bit per voxel
// saying whether it is non-empty, so an empty voxel costs one bit test and only non-empty ones
// are bisected. The bits cover only the indices between the lowest and the highest non-empty
// voxel, not the whole grid: 1/16 of a dense store's bytes at most, usually much less.

#include "hypertree/store/index_list_store.hpp"

#include <cstddef>
#include <cstdint>
#include <span>
#include <string>
#include <vector>

namespace hypertree {

class bit_array_store {
public:
    bit_array_store() = default;

    static std::size_t bytes_needed(const hypervolume& volume, std::span<const stored_voxel> voxels)
    {
        return index_list_store::bytes_needed(volume, voxels) + sizeof(std::uint64_t) * word_count(voxels);
    }

    static bit_array_store build(const hypervolume& volume, std::span<const stored_voxel> voxels,
                                 memory_budget budget = {})
    {
        detail::require_storable("bit_array_store", volume, voxels);
        detail::require_within_budget("bit_array_store", bytes_needed(volume, voxels), budget,
                                      std::to_string(index_list_store::bytes_per_voxel) + " bytes x " +
                                          std::to_string(voxels.size()) + " non-empty voxels + " +
                                          std::to_string(word_count(voxels)) +
                                          " 8-byte words of occupancy bits over the non-empty index range");
        bit_array_store store;
        store.list_ = index_list_store::build_checked(volume, voxels);
        if (!voxels.empty()) {
            store.first_ = voxels.front().index;
            store.span_ = std::uint64_t(voxels.back().index) - store.first_ + 1;
        }
        store.bits_.assign(word_count(voxels), 0);
        for (const stored_voxel& v : voxels) {
            const std::uint64_t offset = v.index - store.first_;
            store.bits_[offset >> 6] |= std::uint64_t(1) << (offset & 63);
        }
        return store;
    }

    const hypervolume& volume() const { return list_.volume(); }
    voxel at(voxel_index i) const
    {
        // Unsigned wrap-around makes an index below first_ a huge offset, outside the span too.
        const std::uint64_t offset = voxel_index(i - first_);
        if (offset >= span_ || !((bits_[offset >> 6] >> (offset & 63)) & 1)) return voxel{};
        return list_.at(i);
    }
    // Only the occupancy bit: whether voxel i is non-empty, without touching the lists.
    bool occupied(voxel_index i) const
    {
        const std::uint64_t offset = voxel_index(i - first_);
        return offset < span_ && ((bits_[offset >> 6] >> (offset & 63)) & 1);
    }
    std::size_t memory_bytes() const { return list_.memory_bytes() + bits_.capacity() * sizeof(std::uint64_t); }
    std::size_t nonempty_count() const { return list_.nonempty_count(); }
    index_box bounds() const { return list_.bounds(); }

    template <class F>
    void for_each(F&& visit) const
    {
        list_.for_each(visit);
    }

    const index_list_store& list() const { return list_; }

private:
    static std::size_t word_count(std::span<const stored_voxel> voxels)
    {
        if (voxels.empty()) return 0;
        const std::uint64_t span = std::uint64_t(voxels.back().index) - voxels.front().index + 1;
        return std::size_t((span + 63) / 64);
    }

    index_list_store list_;
    voxel_index first_ = 0;
    std::uint64_t span_ = 0; // indices first_ .. first_ + span_ - 1 have a bit
    std::vector<std::uint64_t> bits_;
};

static_assert(voxel_store<bit_array_store>);

} // namespace hypertree

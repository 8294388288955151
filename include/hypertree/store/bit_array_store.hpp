#pragma once
// bit_array_store: the index list with an occupancy bit array in front (paper section 5).
//
// Most lookups a raymarcher makes are of empty voxels, and in an index list those cost a full
// search. The paper's compromise for medium resolutions (300-600) adds one bit per voxel saying
// whether it is non-empty, so an empty voxel costs one bit test. The bits cover only the indices
// between the lowest and the highest non-empty voxel, not the whole grid: 1/16 of a dense store's
// bytes at most, usually much less.
//
// Where the paper then bisects the list for a non-empty voxel, this store counts: the voxel's
// position in the sorted list is the number of set bits before its own (its rank), because the
// list holds exactly the voxels whose bit is set, in index order. A running count of set bits
// before each 512-bit block (4 bytes per 64 bytes of bits, +6.25%) leaves at most eight words to
// count, all in the cache lines the bit test has just read: a non-empty voxel costs the bit test
// and one load of its value, at any list length.
//
// Built again in a recycled store (build's last parameter), it keeps its lists' capacity and its
// bit array when the new bits fit it (at most twice as many words): the old list says exactly
// which words hold a set bit, and only those are cleared.

#include "hypertree/execution.hpp"
#include "hypertree/store/store.hpp"
#include "hypertree/store/zeroed_array.hpp"

#include <bit>
#include <cstddef>
#include <cstdint>
#include <span>
#include <string>
#include <string_view>
#include <utility>
#include <vector>

namespace hypertree {

class bit_array_store {
public:
    // Its name in forest files and on command lines (store_kinds.hpp: the kinds' one list).
    static constexpr std::string_view kind_name = "bit_array";
    static constexpr std::size_t bytes_per_voxel = sizeof(voxel_index) + sizeof(voxel);

    bit_array_store() = default;

    static std::size_t bytes_needed(const hypervolume&, std::span<const stored_voxel> voxels)
    {
        const std::size_t words = word_count(voxels);
        return bytes_per_voxel * voxels.size() + sizeof(std::uint64_t) * words +
               sizeof(std::uint32_t) * (words / words_per_block);
    }

    static bit_array_store build(const hypervolume& volume, std::span<const stored_voxel> voxels,
                                 memory_budget budget = {})
    {
        return build(volume, voxels, budget, bit_array_store());
    }
    // The same store, built in `recycled`'s memory, which it consumes (see above). Refused as build
    // refuses, before recycled is touched.
    static bit_array_store build(const hypervolume& volume, std::span<const stored_voxel> voxels, memory_budget budget,
                                 bit_array_store&& recycled)
    {
        detail::require_storable("bit_array_store", volume, voxels);
        detail::require_within_budget("bit_array_store", bytes_needed(volume, voxels), budget,
                                      std::to_string(bytes_per_voxel) + " bytes x " + std::to_string(voxels.size()) +
                                          " non-empty voxels + " + std::to_string(word_count(voxels)) +
                                          " 8-byte words of occupancy bits over the non-empty index range + " +
                                          "a 4-byte count per " + std::to_string(words_per_block) + " words");
        bit_array_store store = std::move(recycled);
        // Its old list names every word with a set bit: clearing those makes the block all zero.
        for (const voxel_index i : store.indices_) store.bits_[(i - store.first_) >> 6] = 0;
        store.volume_ = volume;
        store.first_ = 0, store.span_ = 0;
        detail::split_voxels(voxels, store.indices_, store.values_);
        store.bounds_ = detail::bounds_of(volume, voxels);
        if (!voxels.empty()) {
            store.first_ = voxels.front().index;
            store.span_ = std::uint64_t(voxels.back().index) - store.first_ + 1;
        }
        // The bits start zero without being written (zeroed_array.hpp), or were set back to zero
        // above: only the pages holding a set bit are touched. The block counts come from the
        // list, not from reading the bits back: block b's count is the number of voxels whose offset lies below b's first bit,
        // which a walk in list order gives because build's check made the list sorted and unique
        // (store.hpp); word_count rounds the bits up to whole blocks, so every block gets one.
        store.bits_.reuse(word_count(voxels));
        store.ranks_.resize(store.bits_.size() / words_per_block);
        std::size_t block = 0;
        std::uint32_t before = 0;
        for (const stored_voxel& v : voxels) {
            const std::uint64_t offset = v.index - store.first_;
            store.bits_[offset >> 6] |= std::uint64_t(1) << (offset & 63);
            for (const std::size_t own = std::size_t(offset / (64 * words_per_block)); block <= own; ++block)
                store.ranks_[block] = before;
            ++before;
        }
        for (; block < store.ranks_.size(); ++block) store.ranks_[block] = before;
        return store;
    }

    const hypervolume& volume() const { return volume_; }
    voxel at(voxel_index i) const
    {
        // Unsigned wrap-around makes an index below first_ a huge offset, outside the span too.
        const std::uint64_t offset = voxel_index(i - first_);
        if (offset >= span_) return voxel{};
        const std::uint64_t word = offset >> 6;
        const std::uint64_t bit = std::uint64_t(1) << (offset & 63);
        if (!(bits_[word] & bit)) return voxel{};
        // The rank: set bits of the block's words before this one and of this word below the bit.
        // A fixed eight-word loop with masks, not a loop to the word, so nothing mispredicts.
        const std::size_t block = std::size_t(word / words_per_block);
        const std::uint64_t* words = bits_.data() + block * words_per_block;
        const std::uint64_t here = word % words_per_block;
        std::size_t rank = ranks_[block];
        for (std::uint64_t w = 0; w < words_per_block; ++w) {
            const std::uint64_t mask = w < here ? ~std::uint64_t(0) : w == here ? bit - 1 : 0;
            rank += std::size_t(std::popcount(words[w] & mask));
        }
        return values_[rank];
    }
    // Only the occupancy bit: whether voxel i is non-empty, without touching the lists.
    bool occupied(voxel_index i) const
    {
        const std::uint64_t offset = voxel_index(i - first_);
        return offset < span_ && ((bits_[offset >> 6] >> (offset & 63)) & 1);
    }
    std::size_t memory_bytes() const
    {
        return indices_.capacity() * sizeof(voxel_index) + values_.capacity() * sizeof(voxel) +
               bits_.capacity() * sizeof(std::uint64_t) + ranks_.capacity() * sizeof(std::uint32_t);
    }
    std::size_t nonempty_count() const { return indices_.size(); }
    index_box bounds() const { return bounds_; }

    template <class F>
    void for_each(F&& visit) const
    {
        for (std::size_t k = 0; k < indices_.size(); ++k) visit(indices_[k], values_[k]);
    }

    // The lists themselves, for code that walks them in bulk.
    std::span<const voxel_index> indices() const { return indices_; }
    std::span<const voxel> values() const { return values_; }

private:
    static constexpr std::size_t words_per_block = 8; // 512 bits: one cache line of bits

    // Words of bits over the non-empty index range, rounded up to whole blocks.
    static std::size_t word_count(std::span<const stored_voxel> voxels)
    {
        if (voxels.empty()) return 0;
        const std::uint64_t span = voxels.back().index > voxels.front().index
                                       ? std::uint64_t(voxels.back().index) - voxels.front().index + 1
                                       : 1;
        const std::uint64_t words = (span + 63) / 64;
        return std::size_t((words + words_per_block - 1) / words_per_block * words_per_block);
    }

    hypervolume volume_{};
    std::vector<voxel_index> indices_;
    std::vector<voxel> values_;
    voxel_index first_ = 0;
    std::uint64_t span_ = 0; // indices first_ .. first_ + span_ - 1 have a bit
    zeroed_array<std::uint64_t> bits_; // pages without a set bit are never written
    std::vector<std::uint32_t> ranks_; // set bits before each block of words_per_block words
    index_box bounds_{};
};

static_assert(voxel_store<bit_array_store>);

} // namespace hypertree

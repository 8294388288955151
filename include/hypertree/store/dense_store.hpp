#pragma once
// dense_store: the hypertree as a plain 3D array (paper section 5).
//
// The fastest lookup, one load, at the price of memory for every voxel of the grid whether hit or
// not: 2 bytes per voxel (density and level), 54 MB at 300^3 and 2 GB at 1000^3 (reported and
// budgeted in full, as the paper counts it; the pages no voxel is written to stay untouched zero
// pages until read, and the array lies on huge pages where the system offers them, see
// zeroed_array.hpp). The paper keeps this form for resolutions up to about 300. Density and level
// sit side by side in one 2-byte `voxel`, so a lookup touches one cache line, not two arrays.
//
// Built again at the same size (build with a recycled store), the store keeps its array: it sets
// back to zero only the runs of 32 voxels (64 bytes, a cache line) it wrote, which one bit each
// records (1/256 byte per voxel), instead of mapping 54 MB afresh or clearing all of it.

#include "hypertree/execution.hpp"
#include "hypertree/store/store.hpp"
#include "hypertree/store/zeroed_array.hpp"

#include <algorithm>
#include <bit>
#include <cassert>
#include <cstddef>
#include <cstdint>
#include <cstring>
#include <span>
#include <string>
#include <string_view>
#include <utility>
#include <vector>

namespace hypertree {

class dense_store {
public:
    // Its name in forest files and on command lines (store_kinds.hpp: the kinds' one list).
    static constexpr std::string_view kind_name = "dense";
    static constexpr std::size_t bytes_per_voxel = sizeof(voxel);

    // An empty store over the default one-voxel hypervolume.
    dense_store() : voxels_(1) {}

    static std::size_t bytes_needed(const hypervolume& volume, std::span<const stored_voxel> = {})
    {
        return bytes_per_voxel * std::size_t(volume.voxel_count()) + sizeof(std::uint64_t) * run_words(volume);
    }

    static dense_store build(const hypervolume& volume, std::span<const stored_voxel> voxels, memory_budget budget = {})
    {
        require_buildable(volume, voxels, budget);
        dense_store store(volume);
        store.fill(volume, voxels);
        return store;
    }
    // The same store, built in `recycled`'s memory (which it consumes): when recycled's grid has
    // as many voxels as the new one, or up to twice as many, its array is kept and only the runs
    // it wrote are set back to zero, so no page is mapped again. An application that makes tree after
    // tree at one resolution passes its last store. Refused as build refuses, before recycled is
    // touched.
    static dense_store build(const hypervolume& volume, std::span<const stored_voxel> voxels, memory_budget budget,
                             dense_store&& recycled)
    {
        require_buildable(volume, voxels, budget);
        dense_store store = std::move(recycled);
        store.clear_written();
        store.voxels_.reuse(std::size_t(volume.voxel_count()));
        store.fill(volume, voxels);
        return store;
    }

    const hypervolume& volume() const { return volume_; }
    // Precondition: i < volume().voxel_count().
    voxel at(voxel_index i) const
    {
        assert(i < voxels_.size());
        return voxels_[i];
    }
    std::size_t memory_bytes() const
    {
        return voxels_.capacity() * sizeof(voxel) + written_.capacity() * sizeof(std::uint64_t);
    }
    std::size_t nonempty_count() const { return count_; }
    index_box bounds() const { return bounds_; }

    // Visits only the runs of 32 voxels (64 bytes) the build wrote, found from their bits in
    // written_, not the whole grid: every non-empty voxel lies in a written run (fill sets the bit
    // of each voxel it writes, and nothing else writes the array). A run's non-empty voxels come
    // from a 32-bit mask of its densities (one compare per voxel, vectorised), then one visit per
    // set bit, in increasing index order as before. The grid's empty part costs a bit per run
    // (1/512 of the array): the marcher's brick copy of tree A from a dense store (voxel_bricks.hpp)
    // read 54 MB at resolution 300 and 2 MB at 100 through the word scan that was here before.
    template <class F>
    void for_each(F&& visit) const
    {
        static_assert(sizeof(voxel) == 2, "32 voxels per 64-byte run");
        if (count_ == 0) return;
        const voxel* v = voxels_.data();
        const std::size_t n = voxels_.size();
        // The runs lie scattered over the array, a cache miss each that the hardware prefetcher
        // does not foresee: the runs of the next word of bits are prefetched while this word's are
        // read, so their misses overlap (tree A at 300 from a dense store, the brick copy's CPU time
        // in runs under load 13: 8.8-9.3 ms by the word scan, 8.1 ms by runs, 6.3-6.4 ms by runs
        // prefetched; the index list's copy took 2.6-2.8 ms in the same runs).
        const auto prefetch_word = [&](std::size_t w) {
            for (std::uint64_t runs = written_[w]; runs != 0; runs &= runs - 1)
                __builtin_prefetch(v + (w * 64 + std::size_t(std::countr_zero(runs))) * voxels_per_run);
        };
        if (!written_.empty()) prefetch_word(0);
        for (std::size_t w = 0; w < written_.size(); ++w) {
            if (w + 1 < written_.size()) prefetch_word(w + 1);
            for (std::uint64_t runs = written_[w]; runs != 0; runs &= runs - 1) {
                const std::size_t start = (w * 64 + std::size_t(std::countr_zero(runs))) * voxels_per_run;
                const std::size_t count = std::min(voxels_per_run, n - start);
                const voxel* run = v + start;
                std::uint32_t nonempty = 0;
                if (count == voxels_per_run) // (a fixed trip count: the compares vectorise)
                    for (std::size_t j = 0; j < voxels_per_run; ++j) nonempty |= std::uint32_t(run[j].density != 0) << j;
                else
                    for (std::size_t j = 0; j < count; ++j) nonempty |= std::uint32_t(run[j].density != 0) << j;
                for (; nonempty != 0; nonempty &= nonempty - 1) {
                    const std::size_t j = std::size_t(std::countr_zero(nonempty));
                    visit(voxel_index(start + j), run[j]);
                }
            }
        }
    }

private:
    static constexpr std::size_t voxels_per_run = 32; // 64 bytes: one bit of written_ each

    explicit dense_store(const hypervolume& volume) : volume_(volume), voxels_(std::size_t(volume.voxel_count())) {}

    static std::size_t run_words(const hypervolume& volume)
    {
        const std::size_t runs = (std::size_t(volume.voxel_count()) + voxels_per_run - 1) / voxels_per_run;
        return (runs + 63) / 64;
    }
    static void require_buildable(const hypervolume& volume, std::span<const stored_voxel> voxels, memory_budget budget)
    {
        detail::require_storable("dense_store", volume, voxels);
        detail::require_within_budget("dense_store", bytes_needed(volume), budget,
                                      std::to_string(bytes_per_voxel) + " bytes x " +
                                          std::to_string(volume.voxel_count()) + " voxels of the grid + a bit per " +
                                          std::to_string(voxels_per_run) + " voxels written");
    }

    // Writes the voxels into an all-zero array of the volume's voxel count.
    void fill(const hypervolume& volume, std::span<const stored_voxel> voxels)
    {
        volume_ = volume;
        written_.assign(run_words(volume), 0); // keeps its capacity when rebuilt
        for (const stored_voxel& v : voxels) {
            voxels_[v.index] = v.value;
            const std::size_t run = v.index / voxels_per_run;
            written_[run / 64] |= std::uint64_t(1) << (run % 64);
        }
        count_ = voxels.size();
        bounds_ = detail::bounds_of(volume, voxels);
    }
    // Sets back to zero the runs the last fill wrote: afterwards the whole block is zero.
    void clear_written()
    {
        for (std::size_t w = 0; w < written_.size(); ++w)
            for (std::uint64_t bits = written_[w]; bits; bits &= bits - 1) {
                const std::size_t start = (w * 64 + std::size_t(std::countr_zero(bits))) * voxels_per_run;
                std::fill_n(voxels_.data() + start, std::min(voxels_per_run, voxels_.size() - start), voxel{});
            }
        std::fill(written_.begin(), written_.end(), 0);
    }

    hypervolume volume_{};
    zeroed_array<voxel> voxels_; // the empty voxels cost nothing until written (zeroed_array.hpp)
    std::vector<std::uint64_t> written_; // bit r: voxels [32 r, 32 r + 32) hold some voxel written
    std::size_t count_ = 0;
    index_box bounds_{};
};

static_assert(voxel_store<dense_store>);

} // namespace hypertree

#pragma once
// Validation through a table of one slot per voxel (paper section 5, as create/compact.hpp): the
// way build_tree validates on grids of at most 2^21 voxels, where the table lies in the L3 cache.
// Its entries equal compact()'s, so it shares compact.hpp's entry lists.

#include "hypertree/create/compact.hpp"
#include "hypertree/create/scratch.hpp"
#include "hypertree/execution.hpp"
#include "hypertree/voxel.hpp"

#include <algorithm>
#include <bit>
#include <cstddef>
#include <cstdint>
#include <memory>
#include <memory_resource>
#include <mutex>
#include <span>
#include <string>
#include <utility>
#include <vector>

namespace hypertree::detail {

// Validation through one table slot per voxel, for grids of at most `voxel_table::max_voxels`
// (2^21: 128^3, so resolution 100 and below). A hit adds one to its voxel's count and keeps the
// smaller (level, part) in the slot, a single read-modify-write in a 4 MiB table that the L3
// cache holds, where bucketing wrote each hit as a key and read it back in the merge: one pass
// instead of two, and no per-bucket loops (measured on one thread at 100^3, the worse of two runs
// per tree: 1.94x / 2.26x / 2.17x / 2.58x less time than bucket + merge for trees A / B / C / D,
// docs/benchmarks.md). A bit per line of 16 slots marks the lines in
// use, so reading the entries out visits only those (a tree at 100^3 touches 1-5% of its grid)
// and clears them as it goes. The entries come out in voxel order with every voxel's count and
// minimum, which is what the merge made: the same list whatever order the hits came in.
//
// A slot is count << 14 | (0x3fff - (level << 8 | part)): levels are below 64 (6 bits), so the
// complement of level and part takes 14 bits, and its maximum is their minimum, with an empty
// slot (0) below every hit. The count has the other 18 bits; a voxel reaching 2^17 hits sets the
// top bit, which `overflowed` reports, and the caller then takes the bucketed path (generating
// again: a cost paid only by a tree that piles that many hits on one voxel).
//
// Threads: each task adds a group of hits to a table of its own, taken from a pool (a task finds
// a free table or makes one, zeroed); the tables' slots add and take maxima, so reading out sums
// every table's slot and the result does not depend on which task used which table.
class voxel_table {
public:
    static constexpr std::uint64_t max_voxels = std::uint64_t(1) << 21;
    static constexpr unsigned line_slots = 16; // one cache line of slots per used bit

    voxel_table(std::uint64_t voxel_count, std::pmr::memory_resource* scratch)
        : voxel_count_(voxel_count), lines_((voxel_count + line_slots - 1) / line_slots), slots_(lines_ * line_slots, scratch), used_((lines_ + 63) / 64, scratch)
    {
        std::fill_n(slots_.get(), slots_.size(), std::uint32_t(0));
        std::fill_n(used_.get(), used_.size(), std::uint64_t(0));
    }
    // Adds `hits` (voxels inside the table's grid, levels below 64: the generator's; a hit
    // outside is refused before anything is written, as bucket_chunk refuses it). The hits
    // are taken as four interleaved streams (the list's quarters), as bucket_chunk does: a line's
    // consecutive hits share a used word, and one stream would wait for its own last store to it.
    void add(std::span<const hit> hits)
    {
        std::uint32_t* const slot = slots_.get();
        std::uint64_t* const used = used_.get();
        // One pass over the hits (8 bytes each, streamed) before the table is touched: a stray
        // index would write past the table, a level of 64 or more would carry into the count.
        voxel_index most = 0;
        unsigned levels = 0;
        for (const hit& h : hits) most = std::max(most, h.voxel), levels |= h.level;
        if (!hits.empty() && (std::uint64_t(most) >= voxel_count_ || levels >= 64))
            throw invalid_parameter("voxel_table.hits", "must lie in the grid, at levels below 64 (as the generator makes them)",
                                    levels >= 64 ? std::string("a hit at level 64 or deeper") : "a hit in voxel " + std::to_string(most) + " of " + std::to_string(voxel_count_));
        std::uint32_t top = 0;
        const auto one = [&](const hit& h) {
            const std::uint32_t rank = 0x3fffu - (std::uint32_t(h.level) << 8 | h.part);
            const std::uint32_t was = slot[h.voxel];
            const std::uint32_t now = (was & ~0x3fffu) + 0x4000u + std::max(was & 0x3fffu, rank);
            slot[h.voxel] = now;
            top |= now;
            used[h.voxel >> 10] |= std::uint64_t(1) << ((h.voxel >> 4) & 63);
        };
        const hit* const h = hits.data();
        const std::size_t n = hits.size(), q = n / 4;
        // Each stream's slot `ahead` hits on is asked for before it is needed: the table (4 MiB
        // at 100^3) lies past the L2 cache, and with the request in flight early the adds ran
        // 1.8-2.5x faster (one thread, trees A-D at 100; 16 and 48 hits ahead alike).
        constexpr std::size_t ahead = 16;
        const std::size_t prefetched = q > ahead ? q - ahead : 0;
        for (std::size_t i = 0; i < prefetched; ++i) {
#if defined(__GNUC__) || defined(__clang__)
            for (std::size_t k = 0; k < 4; ++k) __builtin_prefetch(slot + h[k * q + i + ahead].voxel, 1);
#endif
            one(h[i]), one(h[q + i]), one(h[2 * q + i]), one(h[3 * q + i]);
        }
        for (std::size_t i = prefetched; i < q; ++i) one(h[i]), one(h[q + i]), one(h[2 * q + i]), one(h[3 * q + i]);
        for (std::size_t i = 4 * q; i < n; ++i) one(h[i]);
        overflowed_ = overflowed_ || (top >> 31) != 0;
    }
    bool overflowed() const { return overflowed_; }
    std::size_t used_words() const { return used_.size(); }

    // Appends the entries of used words [first, last) of every table in `tables` (their sum per
    // voxel) to `entries`, and clears those words and their slots. The entries are written
    // through a pointer into a buffer from `scratch` (push_back would reload the vector's end for
    // each), then appended at once.
    template <class Entries>
    static void read_out(std::span<voxel_table* const> tables, std::size_t first, std::size_t last, Entries& entries,
                         std::pmr::memory_resource* scratch)
    {
        std::size_t lines = 0;
        for (std::size_t w = first; w < last; ++w) {
            std::uint64_t bits = 0;
            for (voxel_table* t : tables) bits |= t->used_[w];
            lines += std::size_t(std::popcount(bits));
        }
        const scratch_array<voxel_entry> found(lines * line_slots, scratch);
        voxel_entry* out = found.get();
        for (std::size_t w = first; w < last; ++w) {
            std::uint64_t bits = 0;
            for (voxel_table* t : tables) bits |= std::exchange(t->used_[w], 0);
            for (; bits != 0; bits &= bits - 1) {
                const std::size_t base = (w * 64 + std::size_t(std::countr_zero(bits))) * line_slots;
                for (std::size_t k = 0; k < line_slots; ++k) {
                    std::uint32_t count = 0, rank = 0;
                    for (voxel_table* t : tables) {
                        const std::uint32_t s = std::exchange(t->slots_[base + k], 0);
                        count += s >> 14, rank = std::max(rank, s & 0x3fffu);
                    }
                    const std::uint32_t best = 0x3fffu - rank;
                    *out = {voxel_index(base + k), count, std::uint8_t(best >> 8), std::uint8_t(best & 0xff)};
                    out += count != 0; // written always, kept when the voxel was hit
                }
            }
        }
        entries.insert(entries.end(), found.get(), out);
    }

private:
    std::uint64_t voxel_count_;
    std::size_t lines_;
    scratch_array<std::uint32_t> slots_;
    scratch_array<std::uint64_t> used_;
    bool overflowed_ = false;
};

// The tables tasks add to at once: a task takes a free one, or makes one when none is free.
class voxel_table_pool {
public:
    voxel_table_pool(std::uint64_t voxel_count, std::pmr::memory_resource* scratch) : voxel_count_(voxel_count), scratch_(scratch) {}
    template <class F>
    void with_table(F&& f)
    {
        voxel_table* t = nullptr;
        {
            std::lock_guard lock(mutex_);
            if (!free_.empty()) t = free_.back(), free_.pop_back();
        }
        if (!t) {
            auto made = std::make_unique<voxel_table>(voxel_count_, scratch_); // zeroed on this task
            std::lock_guard lock(mutex_);
            t = all_.emplace_back(std::move(made)).get();
        }
        // Back on the free list however f leaves, an exception included: a table dropped here
        // would be made again by every later task (its slots still count in read_out).
        struct give_back {
            voxel_table_pool& pool;
            voxel_table* table;
            ~give_back()
            {
                std::lock_guard lock(pool.mutex_);
                pool.free_.push_back(table);
            }
        } guard{*this, t};
        f(*t);
    }
    bool overflowed() const
    {
        return std::any_of(all_.begin(), all_.end(), [](const auto& t) { return t->overflowed(); });
    }
    // The entries of every table, in voxel order, as up to `tasks` consecutive pieces made on the
    // caller's threads.
    template <class Entries>
    std::vector<Entries> read_out(std::size_t tasks, const parallel_for_hook& parallel_for)
    {
        std::vector<voxel_table*> tables;
        for (const auto& t : all_) tables.push_back(t.get());
        std::vector<Entries> pieces;
        if (tables.empty()) return pieces;
        const std::size_t words = tables[0]->used_words();
        tasks = std::max<std::size_t>(1, std::min(tasks, words));
        for (std::size_t p = 0; p < tasks; ++p) pieces.push_back(entries_from<Entries>(scratch_));
        run_tasks(parallel_for, tasks, [&](std::size_t p) {
            voxel_table::read_out(std::span<voxel_table* const>(tables), words * p / tasks, words * (p + 1) / tasks, pieces[p], scratch_);
        });
        return pieces;
    }

private:
    std::uint64_t voxel_count_;
    std::pmr::memory_resource* scratch_;
    std::mutex mutex_;
    std::vector<std::unique_ptr<voxel_table>> all_;
    std::vector<voxel_table*> free_;
};

} // namespace hypertree::detail

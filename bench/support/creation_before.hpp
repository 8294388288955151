#pragma once
// Today's creation path as it was before issue 27's rework (commit d69f522), kept callable so
// bench_hypertree_create can time it side by side with the library's, alternating, in one run.
// A frozen copy of build.hpp's stored_voxels_of, of create/compact.hpp's bucket_chunk, direct_merge
// and merge_bucketed and of create/density.hpp's classify as they were; nothing here is used by the
// library. The generator (generate_chunks one chunk at a time, as before), density_classes and
// the stores' build are the library's own, which the rework leaves as they were.

#include "hypertree/build.hpp"
#include "hypertree/execution.hpp"

#include <bit>
#include <cstdint>
#include <memory>
#include <memory_resource>
#include <optional>
#include <string>
#include <span>
#include <utility>
#include <vector>

namespace bench::before {

using namespace hypertree;
using hypertree::detail::bucketed_chunk;
using hypertree::detail::direct_buckets;

// One bucket's table: count, shallowest level << 8 | part and a used bit per voxel of the bucket.
class direct_merge {
public:
    explicit direct_merge(unsigned low_bits)
        : size_(std::size_t(1) << low_bits), count_(new std::uint32_t[size_]()), best_(new std::uint16_t[size_]),
          used_(new std::uint64_t[(size_ + 63) / 64]())
    {
        std::fill_n(best_.get(), size_, std::uint16_t(0xffff));
    }
    template <class Key>
    void add(const Key* keys, std::size_t n, unsigned shift)
    {
        const Key mask = Key(size_ - 1), below = Key((Key(1) << shift) - 1);
        for (std::size_t i = 0; i < n; ++i) {
            const std::size_t slot = std::size_t((keys[i] >> shift) & mask);
            ++count_[slot];
            best_[slot] = std::min(best_[slot], std::uint16_t(keys[i] & below));
            used_[slot >> 6] |= std::uint64_t(1) << (slot & 63);
        }
    }
    template <class Entries>
    void flush(voxel_index base, Entries& entries)
    {
        for (std::size_t w = 0; w < (size_ + 63) / 64; ++w)
            for (std::uint64_t bits = std::exchange(used_[w], 0); bits != 0; bits &= bits - 1) {
                const std::size_t slot = w * 64 + std::size_t(std::countr_zero(bits));
                entries.push_back({base + voxel_index(slot), count_[slot], std::uint8_t(best_[slot] >> 8), std::uint8_t(best_[slot] & 0xff)});
                count_[slot] = 0, best_[slot] = 0xffff;
            }
    }

private:
    std::size_t size_;
    std::unique_ptr<std::uint32_t[]> count_;
    std::unique_ptr<std::uint16_t[]> best_;
    std::unique_ptr<std::uint64_t[]> used_;
};

inline bucketed_chunk bucket_chunk(std::span<const hit> hits, const direct_buckets& plan, std::pmr::memory_resource* scratch)
{
    bucketed_chunk out{scratch_array<std::uint32_t>(hits.size(), scratch), std::vector<std::size_t>(plan.buckets + 1, 0)};
    bool beyond = false;
    unsigned level_bits = 0;
    hypertree::detail::count_buckets(hits, plan.low_bits, plan.buckets, plan.largest, out.start.data(), beyond, level_bits);
    if (beyond || level_bits >= 64) throw invalid_parameter("bucket_chunk.hits", "must lie in the grid, at levels below 64", "");
    for (std::size_t b = 0, offset = 0; b <= plan.buckets; ++b) offset += std::exchange(out.start[b], offset);
    std::vector<std::size_t> next(out.start.begin(), out.start.end() - 1);
    std::uint32_t* const to = out.keys.get();
    const unsigned low_bits = plan.low_bits;
    for (const hit& h : hits) to[next[h.voxel >> low_bits]++] = hypertree::detail::short_key(h, low_bits);
    return out;
}

template <class Entries>
void merge_bucketed(std::span<const bucketed_chunk> chunks, const direct_buckets& plan, const parallel_for_hook& parallel_for,
                    std::pmr::memory_resource* scratch, Entries& entries)
{
    entries = hypertree::detail::entries_from<Entries>(scratch);
    std::vector<std::size_t> start(plan.buckets + 1, 0);
    for (std::size_t b = 0, offset = 0; b <= plan.buckets; ++b) {
        start[b] = offset;
        if (b < plan.buckets)
            for (const bucketed_chunk& c : chunks) offset += c.start[b + 1] - c.start[b];
    }
    const std::size_t n = start[plan.buckets];
    if (n == 0) return;
    const std::size_t tasks = parallel_for && n >= (std::size_t(1) << 16) ? 4 : 1;
    hypertree::detail::merge_in_groups(std::span<const std::size_t>(start), tasks, parallel_for, scratch,
                                       [&](std::size_t first, std::size_t last, Entries& out) {
                                           direct_merge table(plan.low_bits);
                                           for (std::size_t b = first; b < last; ++b) {
                                               for (const bucketed_chunk& c : chunks)
                                                   table.add(c.keys.get() + c.start[b], c.start[b + 1] - c.start[b],
                                                             hypertree::detail::short_key_shift);
                                               table.flush(voxel_index(b << plan.low_bits), out);
                                           }
                                       },
                                       entries);
}

// classify as it was (create/density.hpp), one list split into tasks.
template <class Voxels = std::vector<stored_voxel>>
Voxels classify(std::span<const voxel_entry> entries, const density_classes& classes, int branch_depth, Voxels voxels = {},
                const parallel_for_hook& parallel_for = {})
{
    if (branch_depth < no_branch_structure || branch_depth > 255)
        throw invalid_parameter("classify.branch_depth",
                                "must be -1 (no branching structure) or a level between 0 and 255",
                                std::to_string(branch_depth));

    // Hit count -> density as a table over the counts the classes span, so classifying a million
    // voxels costs a load each instead of a bisection; counts above it take the last class.
    const auto spanned = classes.classes();
    const std::uint32_t table_top = spanned.empty() ? 0 : spanned.back().most_hits;
    std::vector<std::uint8_t> density_by_hits;
    if (std::size_t(table_top) <= 4 * entries.size() + 1024) {
        density_by_hits.resize(std::size_t(table_top) + 1);
        for (std::size_t h = 0; h < density_by_hits.size(); ++h)
            density_by_hits[h] = classes.density_of(std::uint32_t(h));
    }
    const auto density_of = [&](std::uint32_t hits) {
        return hits < density_by_hits.size() ? density_by_hits[hits] : classes.density_of(hits);
    };

    // Voxel i comes from entry i; each task checks its entries' order (against the one before
    // too) and counts those without hits, which a serial pass then removes (compact makes none).
    // Written through indices into a sized list: push_back's end pointer lives in the vector, and
    // the byte-sized fields written in between may alias it, so it was reloaded and stored for
    // every voxel.
    const std::size_t n = entries.size();
    voxels.resize(n);
    const std::size_t tasks = parallel_for && n >= (std::size_t(1) << 16) ? 4 : 1;
    std::vector<std::size_t> first_unsorted(tasks, n), without_hits(tasks, 0);
    run_tasks(parallel_for, tasks, [&](std::size_t p) {
        const std::size_t begin = n * p / tasks, end = n * (p + 1) / tasks;
        std::size_t unsorted = n, empty = 0;
        for (std::size_t i = begin; i < end; ++i) {
            const voxel_entry& e = entries[i];
            if (i > 0 && !(entries[i - 1].voxel < e.voxel) && unsorted == n) unsorted = i;
            const std::uint8_t density = int(e.level) <= branch_depth ? std::uint8_t(255) : density_of(e.hits);
            voxels[i] = {e.voxel, voxel{density, e.level}, e.part};
            empty += e.hits == 0;
        }
        first_unsorted[p] = unsorted, without_hits[p] = empty;
    });
    if (const std::size_t i = *std::min_element(first_unsorted.begin(), first_unsorted.end()); i < n)
        throw invalid_parameter("classify.entries", "must be sorted by voxel without duplicates (as compact returns them)",
                                "voxel " + std::to_string(entries[i].voxel) + " after " + std::to_string(entries[i - 1].voxel));
    if (std::find_if(without_hits.begin(), without_hits.end(), [](std::size_t c) { return c != 0; }) != without_hits.end()) {
        std::size_t kept = 0;
        for (std::size_t i = 0; i < n; ++i) {
            voxels[kept] = voxels[i];
            kept += entries[i].hits != 0;
        }
        voxels.resize(kept);
    }
    return voxels;
}


template <transform_pipeline P>
std::pmr::vector<stored_voxel> stored_voxels_of(const ifs<P>& definition, std::uint64_t seed, int density_class_count,
                                                const generation_options& options, std::pmr::memory_resource* scratch)
{
    generation_options drawing = options;
    drawing.scratch = scratch;
    std::pmr::vector<voxel_entry> entries(scratch);
    hypertree::detail::no_observer observer;
    if (const auto plan = direct_buckets::for_grid(definition.volume.voxel_count())) {
        std::vector<bucketed_chunk> keyed(hypertree::detail::plan_generation(definition, drawing).chunks);
        hypertree::detail::generate_chunks(definition, seed, drawing, observer, [&](std::size_t c, hypertree::detail::chunk_output& chunk) {
            keyed[c] = bench::before::bucket_chunk({chunk.data(), chunk.size()}, *plan, scratch);
            chunk = {};
        });
        bench::before::merge_bucketed(keyed, *plan, options.parallel_for, scratch, entries);
    } else {
        const hypertree::detail::generated_chunks generated = hypertree::detail::generate_chunks(definition, seed, drawing, observer);
        hypertree::detail::compact_into(generated.pieces(), options.parallel_for, definition.volume.voxel_count(), scratch, entries);
    }
    const density_classes classes(entries, density_class_count);
    return bench::before::classify(entries, classes, definition.branch_depth, std::pmr::vector<stored_voxel>(scratch), options.parallel_for);
}

// build_tree as it was.
template <class Store, transform_pipeline P>
Store build_tree(const ifs<P>& definition, std::uint64_t seed, const build_options& options, Store&& recycled)
{
    std::optional<scratch_memory> own;
    if (!options.generation.scratch) own.emplace();
    std::pmr::memory_resource* const scratch = options.generation.scratch ? options.generation.scratch : &*own;
    const std::pmr::vector<stored_voxel> voxels =
        bench::before::stored_voxels_of(definition, seed, options.density_class_count, options.generation, scratch);
    return Store::build(definition.volume, voxels, options.generation.budget, std::move(recycled));
}

} // namespace bench::before

#pragma once
// Hypertree validation (paper section 5, step 5 of the algorithm in section 6).
//
// The generator records one `hit` per voxel a generator occupies, so the same voxel appears many
// times. Validation sorts the hits by voxel and merges each run of equal voxels into one
// `voxel_entry`: its hit count is the run's length, and the shallowest level in the run prevails
// (the paper's rule), with the part of that hit; among hits of equal level the smallest part wins,
// so the result does not depend on the order the generator produced the hits in.
//
// The paper quick-sorts. A tree makes 0.5 to 2 million hits and should be built in a few
// milliseconds, so `compact` radix-sorts instead, over only the bits the largest voxel index needs
// (25 bits at 300^3): one most-significant-digit pass scatters the hits into up to 2^8 buckets of
// neighbouring voxels (2^11 where every bucket is merged directly), then each bucket, small enough
// to stay in cache, is merged into entries while still hot: through a table indexed by the
// voxel's remaining bits when they are few (direct_merge), else sorted by a least-significant-digit
// radix sort on them and merged by runs.
// Main memory is thus crossed once by the scatter, and only one extra hit-sized buffer is touched
// (fresh pages cost more than the sorting itself at this size). Only the voxel is a sort key: the
// level and part are reduced by a minimum over each run, which gives the same result as sorting on
// (voxel, level, part) with fewer passes.
//
// On grids of at most 2^21 voxels build_tree skips the buckets: voxel_table (voxel_table.hpp)
// keeps one slot per voxel, so each hit is one read-modify-write and the entries are read out in
// voxel order.

#include "hypertree/create/scratch.hpp"
#include "hypertree/execution.hpp"
#include "hypertree/voxel.hpp"

#include <algorithm>
#include <array>
#include <bit>
#include <cstddef>
#include <cstdint>
#include <limits>
#include <memory>
#include <memory_resource>
#include <optional>
#include <span>
#include <string>
#include <type_traits>
#include <utility>
#include <vector>

namespace hypertree {

namespace detail {

// A hit as one integer: voxel in bits 16..47, level in bits 8..15, part in bits 0..7. Ordering the
// packed values orders by voxel, then by the shallowest level, then by the smallest part.
inline constexpr unsigned packed_voxel_shift = 16;
inline std::uint64_t pack_hit(const hit& h)
{
    return (std::uint64_t(h.voxel) << packed_voxel_shift) | (std::uint64_t(h.level) << 8) | std::uint64_t(h.part);
}
inline voxel_index packed_voxel(std::uint64_t key)
{
    return voxel_index(key >> packed_voxel_shift);
}

// Widest digit: 2^11 counters stay in the L1 cache while a pass scatters.
inline constexpr unsigned max_radix_digit_bits = 11;
// The first, scattering pass uses at most 2^8 buckets: 256 write streams fit the L1 cache and the
// TLB (2^11 streams measured 35% slower overall), and 2 million hits make buckets of about 8000
// hits (64 KiB), which the in-bucket sort keeps in the L2 cache.
inline constexpr unsigned max_bucket_bits = 8;

// Stable LSD radix sort of keys[0, n) on bits [low_bit, low_bit + key_bits), ping-ponging with
// scratch[0, n). Returns where the sorted keys ended: `keys` or `scratch`. A pass whose digit is
// the same for every key moves nothing and is skipped.
inline std::uint64_t* radix_sort_bits(std::uint64_t* keys, std::uint64_t* scratch, std::size_t n, unsigned low_bit,
                                      unsigned key_bits)
{
    if (n < 2 || key_bits == 0) return keys;
    const unsigned passes = (key_bits + max_radix_digit_bits - 1) / max_radix_digit_bits;
    const unsigned digit_bits = (key_bits + passes - 1) / passes; // balanced digits: 14 bits -> 7 + 7
    const std::size_t buckets = std::size_t(1) << digit_bits;
    const std::uint64_t digit_mask = buckets - 1;
    std::array<std::size_t, std::size_t(1) << max_radix_digit_bits> count;
    std::uint64_t* from = keys;
    std::uint64_t* to = scratch;
    for (unsigned p = 0; p < passes; ++p) {
        const unsigned shift = low_bit + p * digit_bits;
        std::fill_n(count.begin(), buckets, std::size_t(0));
        for (std::size_t i = 0; i < n; ++i) ++count[(from[i] >> shift) & digit_mask];
        if (count[(from[0] >> shift) & digit_mask] == n) continue; // every key has this digit
        std::size_t offset = 0;
        for (std::size_t b = 0; b < buckets; ++b) offset += std::exchange(count[b], offset);
        for (std::size_t i = 0; i < n; ++i) {
            const std::uint64_t k = from[i];
            to[count[(k >> shift) & digit_mask]++] = k;
        }
        std::swap(from, to);
    }
    return from;
}

// Appends one entry per run of equal voxels in sorted[0, n).
template <class Entries>
void append_runs(const std::uint64_t* sorted, std::size_t n, Entries& entries)
{
    constexpr std::uint64_t level_and_part = (std::uint64_t(1) << packed_voxel_shift) - 1;
    std::size_t begin = 0;
    while (begin < n) {
        const voxel_index v = packed_voxel(sorted[begin]);
        std::uint64_t shallowest = sorted[begin] & level_and_part;
        std::size_t end = begin + 1;
        for (; end < n && packed_voxel(sorted[end]) == v; ++end)
            shallowest = std::min(shallowest, sorted[end] & level_and_part);
        const std::size_t repetitions = std::min<std::size_t>(end - begin, std::numeric_limits<std::uint32_t>::max());
        entries.push_back(
            {v, std::uint32_t(repetitions), std::uint8_t(shallowest >> 8), std::uint8_t(shallowest & 0xff)});
        begin = end;
    }
}

// Grids of at most 2^25 voxels (300^3 and below) are merged without sorting: within a bucket,
// each hit adds to its voxel's slot in a table indexed by the voxel's low bits (count, and the
// minimum of level and part, which is what a sorted run reduces to), and a bit per slot marks the
// slots used, so the entries come out in voxel order by walking the set bits. One pass over the
// bucket and a walk over its distinct voxels, where the radix sort made two passes of counting
// and scattering.
// (The direct path's limit, as bits below 2^8 buckets: 8 + 17 = 25 bits of voxel index.)
inline constexpr unsigned max_direct_bits = 17;
// When every bucket can be merged directly the scatter makes up to 2^11 buckets instead of 2^8,
// so a bucket spans at most 2^14 voxels and its table (96 KiB) stays in L2 with room to spare:
// the merge gains more than the wider scatter loses (compaction of tree C at 300: 5 to 10%
// faster, A and D within noise). The radix sort's buckets stay at 2^8, where the scatter's cost
// decides.
inline constexpr unsigned direct_bucket_bits = 11;
// Then the keys the scatter moves are 32 bits, half the bytes, when every level is below 64 (the
// generator's are: max_tree_depth = 64): slot << 14 | level << 8 | part, the slot below 2^14.
inline constexpr unsigned short_key_shift = 14;

// How the hits split into buckets: by the voxel's bits from low_bits up.
struct bucket_layout {
    unsigned low_bits = 0;
    std::size_t buckets = 1;
    bool direct = false; // every bucket merges directly (max_direct_bits)

    static bucket_layout for_largest(voxel_index largest)
    {
        const unsigned voxel_bits = unsigned(std::bit_width(largest));
        bucket_layout layout;
        layout.direct = voxel_bits <= max_bucket_bits + max_direct_bits;
        const unsigned bucket_bits = std::min(voxel_bits, layout.direct ? direct_bucket_bits : max_bucket_bits);
        layout.low_bits = voxel_bits - bucket_bits; // sorted inside each bucket
        layout.buckets = std::size_t(1) << bucket_bits;
        return layout;
    }
};

// A hit as a 32-bit key within its bucket (levels below 64, direct layouts only).
inline std::uint32_t short_key(const hit& h, unsigned low_bits)
{
    const voxel_index low_mask = voxel_index((std::uint64_t(1) << low_bits) - 1);
    return std::uint32_t((h.voxel & low_mask) << short_key_shift) | std::uint32_t(h.level) << 8 | std::uint32_t(h.part);
}

class direct_merge {
public:
    explicit direct_merge(unsigned low_bits)
        : size_(std::size_t(1) << low_bits), count_(new std::uint32_t[size_]()), best_(new std::uint16_t[size_]),
          used_(new std::uint64_t[(size_ + 63) / 64]())
    {
        std::fill_n(best_.get(), size_, std::uint16_t(0xffff));
    }
    // Appends the entries of one bucket's keys (fewer than 2^32 of them), whose voxels start at
    // `base`, and leaves the table empty again. A key holds the voxel from bit `shift` up and
    // level << 8 | part below it.
    template <class Key, class Entries>
    void merge(const Key* keys, std::size_t n, unsigned shift, voxel_index base, Entries& entries)
    {
        add(keys, n, shift);
        flush(base, entries);
    }
    // The two halves of merge: add keys (of one bucket, perhaps in several calls, fewer than 2^32
    // in all), then append the bucket's entries and empty the table.
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
    // The bucket's entries are appended through a pointer into space made for them at once (their
    // number is the used bits' population): push_back kept the vector's end in memory and
    // reloaded it for every entry. The used bits are read, then cleared in one sweep: writing
    // each word back as it was read was the slowest step of the flush (a store per word of every
    // bucket, used or not).
    template <class Entries>
    void flush(voxel_index base, Entries& entries)
    {
        const std::size_t words = (size_ + 63) / 64;
        std::size_t found = 0;
        for (std::size_t w = 0; w < words; ++w) found += std::size_t(std::popcount(used_[w]));
        if (found == 0) return;
        const std::size_t first = entries.size();
        entries.resize(first + found);
        voxel_entry* out = entries.data() + first;
        const std::uint32_t* const count = count_.get();
        std::uint16_t* const best = best_.get();
        for (std::size_t w = 0; w < words; ++w)
            for (std::uint64_t bits = used_[w]; bits != 0; bits &= bits - 1) {
                const std::size_t slot = w * 64 + std::size_t(std::countr_zero(bits));
                const std::uint16_t b = best[slot];
                *out++ = {base + voxel_index(slot), count[slot], std::uint8_t(b >> 8), std::uint8_t(b & 0xff)};
                count_[slot] = 0, best[slot] = 0xffff;
            }
        std::fill_n(used_.get(), words, std::uint64_t(0));
    }

private:
    std::size_t size_;
    std::unique_ptr<std::uint32_t[]> count_;
    std::unique_ptr<std::uint16_t[]> best_;
    std::unique_ptr<std::uint64_t[]> used_;
};

} // namespace detail

namespace detail {

// The pieces' shares of hits [first, last) of `pieces` taken end to end.
inline std::vector<std::span<const hit>> pieces_in(std::span<const std::span<const hit>> pieces, std::size_t first, std::size_t last)
{
    std::vector<std::span<const hit>> shares;
    std::size_t offset = 0;
    for (const std::span<const hit>& piece : pieces) {
        const std::size_t from = std::max(first, offset), to = std::min(last, offset + piece.size());
        if (from < to) shares.push_back(piece.subspan(from - offset, to - from));
        offset += piece.size();
        if (offset >= last) break;
    }
    return shares;
}

// Counts hits per bucket (the voxel's bits from `low_bits` up; past the last bucket counts in
// the last), and says whether a hit lies past voxel `largest` and which level bits the hits use.
// Bits or'ed together rather than maxima: GCC moved the maxima to vector registers through the
// stack, which made this loop, half of compaction, twice as slow.
inline void count_buckets(std::span<const hit> hits, unsigned low_bits, std::size_t buckets, voxel_index largest,
                          std::size_t* count, bool& beyond, unsigned& level_bits)
{
    bool past = beyond;
    unsigned levels = level_bits;
    for (const hit& h : hits) {
        ++count[std::min(std::size_t(h.voxel >> low_bits), buckets - 1)];
        past |= h.voxel > largest;
        levels |= h.level;
    }
    beyond = past, level_bits = levels;
}

// An empty entry list of type Entries: a std::pmr::vector draws from `scratch`.
template <class Entries>
Entries entries_from(std::pmr::memory_resource* scratch)
{
    if constexpr (std::is_same_v<Entries, std::pmr::vector<voxel_entry>>) return Entries(scratch);
    else return Entries();
}

// The merge's last stage, shared by both ways of bucketing: splits the buckets into up to `tasks`
// groups of consecutive buckets holding about equal numbers of keys (start[b]: the keys before
// bucket b, start[buckets] all of them), runs merge_group(first, last, out) for each on the
// caller's threads, and returns their entries, group by group in bucket order.
template <class Entries, class MergeGroup>
std::vector<Entries> merge_groups(std::span<const std::size_t> start, std::size_t tasks, const parallel_for_hook& parallel_for,
                                  std::pmr::memory_resource* scratch, const MergeGroup& merge_group)
{
    const std::size_t buckets = start.size() - 1, n = start[buckets];
    std::vector<std::size_t> group_begin{0};
    for (std::size_t b = 1; b < buckets && group_begin.size() < tasks; ++b)
        if (start[b] >= n * group_begin.size() / tasks) group_begin.push_back(b);
    const std::size_t groups = group_begin.size();
    group_begin.push_back(buckets);
    std::vector<Entries> group_entries;
    for (std::size_t g = 0; g < groups; ++g) group_entries.push_back(entries_from<Entries>(scratch));
    run_tasks(parallel_for, groups, [&](std::size_t g) {
        const std::size_t first = group_begin[g], last = group_begin[g + 1];
        // At most one entry per key. Reserving that much only reserves address space: pages
        // that are never written are never touched.
        group_entries[g].reserve(start[last] - start[first]);
        merge_group(first, last, group_entries[g]);
    });
    return group_entries;
}

// The groups' entries end to end, in `entries`.
template <class Entries>
void concatenate(std::vector<Entries>&& group_entries, Entries& entries)
{
    if (group_entries.size() == 1) {
        entries = std::move(group_entries[0]);
        entries.shrink_to_fit();
        return;
    }
    std::size_t total = 0;
    for (const auto& e : group_entries) total += e.size();
    entries.reserve(total);
    for (const auto& e : group_entries) entries.insert(entries.end(), e.begin(), e.end());
}

// merge_groups, concatenated into `entries`.
template <class Entries, class MergeGroup>
void merge_in_groups(std::span<const std::size_t> start, std::size_t tasks, const parallel_for_hook& parallel_for,
                     std::pmr::memory_resource* scratch, const MergeGroup& merge_group, Entries& entries)
{
    concatenate(merge_groups<Entries>(start, tasks, parallel_for, scratch, merge_group), entries);
}

// compact() over hits given as pieces taken end to end (the generator's chunks), with its
// temporary buffers from `scratch`, into `entries` (a std::vector or a std::pmr::vector, which
// then draws from `scratch` too).
template <class Entries>
void compact_into(std::span<const std::span<const hit>> pieces, const parallel_for_hook& parallel_for, std::uint64_t voxel_count,
                  std::pmr::memory_resource* scratch, Entries& entries)
{
    entries = entries_from<Entries>(scratch);
    std::size_t n = 0;
    for (const std::span<const hit>& piece : pieces) n += piece.size();
    if (n == 0) return;
    // 4 tasks per pass balance two to four threads; below 2^16 hits a pass takes microseconds.
    const std::size_t tasks = parallel_for && n >= (std::size_t(1) << 16) ? 4 : 1;
    // Task p's part of the hits, as pieces.
    const auto part = [&](std::size_t p) { return pieces_in(pieces, n * p / tasks, n * (p + 1) / tasks); };

    voxel_index largest = voxel_index(std::min<std::uint64_t>(voxel_count, std::uint64_t(1) << 32) - 1);
    if (voxel_count == 0) {
        std::vector<voxel_index> part_largest(tasks, 0);
        run_tasks(parallel_for, tasks, [&](std::size_t p) {
            for (const std::span<const hit> hits : part(p))
                for (const hit& h : hits) part_largest[p] = std::max(part_largest[p], h.voxel);
        });
        largest = *std::max_element(part_largest.begin(), part_largest.end());
    }
    const bucket_layout layout = bucket_layout::for_largest(largest);
    const bool direct = layout.direct;
    const unsigned low_bits = layout.low_bits;
    const std::size_t buckets = layout.buckets;

    // counts[p * buckets + b]: part p's hits in bucket b; then where part p writes them. The same
    // pass finds whether a hit lies past voxel_count (counted in the last bucket, then refused)
    // and whether every level is below 64 (then 32-bit keys hold the hits).
    std::vector<std::size_t> counts(tasks * buckets, 0);
    std::vector<char> part_beyond(tasks, 0);
    std::vector<unsigned> part_levels(tasks, 0);
    run_tasks(parallel_for, tasks, [&](std::size_t p) {
        bool beyond = false;
        for (const std::span<const hit> hits : part(p))
            count_buckets(hits, low_bits, buckets, largest, counts.data() + p * buckets, beyond, part_levels[p]);
        part_beyond[p] = beyond;
    });
    if (std::find(part_beyond.begin(), part_beyond.end(), 1) != part_beyond.end()) {
        voxel_index most = 0;
        for (const std::span<const hit>& piece : pieces)
            for (const hit& h : piece) most = std::max(most, h.voxel);
        throw invalid_parameter("compact.voxel_count", "must be above every hit's voxel index (it is the hypervolume's voxel count)",
                                std::to_string(voxel_count) + " with a hit in voxel " + std::to_string(most));
    }
    unsigned level_bits = 0;
    for (const unsigned l : part_levels) level_bits |= l;
    // Every level below 64, and (as direct_merge counts in 32 bits) fewer than 2^32 hits, where
    // a bucket of short keys could otherwise be too large to merge directly.
    const bool short_keys = direct && level_bits < 64 && n < (std::size_t(1) << 32);
    std::vector<std::size_t> start(buckets + 1, 0);
    for (std::size_t b = 0, offset = 0; b < buckets; ++b) {
        start[b] = offset;
        for (std::size_t p = 0; p < tasks; ++p) offset += std::exchange(counts[p * buckets + b], offset);
    }
    start[buckets] = n;

    // Scatters the hits into their buckets as keys (the voxel from bit `shift` up, level << 8 |
    // part below), then merges each group of buckets into its entries.
    const auto scatter_and_merge = [&]<class Key>(unsigned shift, const auto& key_of) {
        // Not zeroed: every element is written by the scatter, so zeroing would only cost.
        const scratch_array<Key> scattered(n, scratch);
        run_tasks(parallel_for, tasks, [&](std::size_t p) {
            std::size_t* const next = counts.data() + p * buckets;
            Key* const to = scattered.get();
            const unsigned bucket_shift = low_bits;
            for (const std::span<const hit> hits : part(p))
                for (const hit& h : hits) to[next[h.voxel >> bucket_shift]++] = key_of(h);
        });
        merge_in_groups(std::span<const std::size_t>(start), tasks, parallel_for, scratch, [&](std::size_t first, std::size_t last, Entries& out) {
            std::size_t largest_bucket = 0;
            for (std::size_t b = first; b < last; ++b) largest_bucket = std::max(largest_bucket, start[b + 1] - start[b]);
            if (direct && largest_bucket < (std::size_t(1) << 32)) {
                direct_merge table(low_bits);
                for (std::size_t b = first; b < last; ++b)
                    table.merge(scattered.get() + start[b], start[b + 1] - start[b], shift, voxel_index(b << low_bits), out);
                return;
            }
            if constexpr (std::is_same_v<Key, std::uint64_t>) {
                const scratch_array<std::uint64_t> sort_scratch(std::max<std::size_t>(largest_bucket, 1), scratch);
                for (std::size_t b = first; b < last; ++b) {
                    const std::size_t size = start[b + 1] - start[b];
                    if (size == 0) continue;
                    const std::uint64_t* sorted =
                        radix_sort_bits(scattered.get() + start[b], sort_scratch.get(), size, packed_voxel_shift, low_bits);
                    append_runs(sorted, size, out);
                }
            }
        }, entries);
    };
    if (short_keys) {
        scatter_and_merge.template operator()<std::uint32_t>(short_key_shift, [low_bits](const hit& h) { return short_key(h, low_bits); });
    } else {
        scatter_and_merge.template operator()<std::uint64_t>(packed_voxel_shift, pack_hit);
    }
}

// Validation piece by piece (build_tree's way, on grids whose buckets all merge directly: up to
// 2^25 voxels). A piece is one buffer of hits: in build_tree, a group of consecutive chunks
// generated together (generate.hpp's generation_group_count). Its hits become short keys grouped
// by bucket on the piece's own task, while they are hot in cache, and its buffer goes back to the
// scratch memory for the next piece; then each bucket merges its keys from every piece. The
// generator's hits always fit short keys (levels below max_tree_depth = 64, voxels inside the
// grid). The entries equal compact()'s: a voxel's entry reduces its keys by count and minimum,
// whatever their order.
struct direct_buckets {
    unsigned low_bits = 0;
    std::size_t buckets = 0;
    voxel_index largest = 0; // the grid's last voxel

    static std::optional<direct_buckets> for_grid(std::uint64_t voxel_count)
    {
        if (voxel_count == 0 || voxel_count > (std::uint64_t(1) << (max_bucket_bits + max_direct_bits))) return std::nullopt;
        const voxel_index largest = voxel_index(voxel_count - 1);
        const bucket_layout layout = bucket_layout::for_largest(largest);
        return direct_buckets{layout.low_bits, layout.buckets, largest};
    }
};

struct bucketed_chunk {
    scratch_array<std::uint32_t> keys; // grouped by bucket
    std::vector<std::size_t> start;    // start[b]: bucket b's first key; start[buckets]: the key count
};

// The hits are taken as `bucket_ways` = 4 interleaved streams (the chunk's four quarters, one hit
// of each per step), each with its own counters and write positions. A line's consecutive hits
// fall in the same bucket, and one counter incremented hit after hit waits for its own last store
// every time (store-to-load forwarding, ~5 cycles): the scatter of tree C ran at 10 ns a hit.
// Four quarters make four independent chains. Within a bucket the keys come quarter by quarter,
// which the merge does not see: a voxel's entry is a count and a minimum over its keys.
inline constexpr std::size_t bucket_ways = 4;

inline bucketed_chunk bucket_chunk(std::span<const hit> hits, const direct_buckets& plan, std::pmr::memory_resource* scratch)
{
    const std::size_t n = hits.size(), buckets = plan.buckets;
    if (n >= (std::size_t(1) << 32))
        throw invalid_parameter("bucket_chunk.hits", "must be fewer than 2^32 per chunk (its positions are counted in 32 bits)", std::to_string(n));
    bucketed_chunk out{scratch_array<std::uint32_t>(n, scratch), std::vector<std::size_t>(buckets + 1, 0)};
    // counter[k * buckets + b]: quarter k's hits in bucket b, then where quarter k writes the next.
    const std::unique_ptr<std::uint32_t[]> counter(new std::uint32_t[bucket_ways * buckets]());
    std::size_t begin[bucket_ways + 1];
    for (std::size_t k = 0; k <= bucket_ways; ++k) begin[k] = n * k / bucket_ways;
    const std::size_t step_count = begin[1] - begin[0]; // the shortest quarter (the first)
    const unsigned low_bits = plan.low_bits;
    const std::size_t last_bucket = buckets - 1;
    const voxel_index largest = plan.largest;
    const hit* const h = hits.data();
    std::uint32_t* const c = counter.get();
    bool beyond = false;
    unsigned level_bits = 0;
    const auto count_one = [&](std::size_t k, const hit& x) {
        ++c[k * buckets + std::min(std::size_t(x.voxel >> low_bits), last_bucket)];
        beyond |= x.voxel > largest;
        level_bits |= x.level;
    };
    for (std::size_t i = 0; i < step_count; ++i)
        for (std::size_t k = 0; k < bucket_ways; ++k) count_one(k, h[begin[k] + i]);
    for (std::size_t k = 0; k < bucket_ways; ++k)
        for (std::size_t i = begin[k] + step_count; i < begin[k + 1]; ++i) count_one(k, h[i]);
    if (beyond || level_bits >= 64)
        throw invalid_parameter("bucket_chunk.hits", "must lie in the grid, at levels below 64 (as the generator makes them)",
                                beyond ? "a hit past voxel " + std::to_string(plan.largest) : "a hit at level 64 or deeper");
    std::uint32_t offset = 0;
    for (std::size_t b = 0; b < buckets; ++b) {
        out.start[b] = offset;
        for (std::size_t k = 0; k < bucket_ways; ++k) offset += std::exchange(c[k * buckets + b], offset);
    }
    out.start[buckets] = n;
    std::uint32_t* const to = out.keys.get();
    const auto place = [&](std::size_t k, const hit& x) { to[c[k * buckets + (x.voxel >> low_bits)]++] = short_key(x, low_bits); };
    for (std::size_t i = 0; i < step_count; ++i)
        for (std::size_t k = 0; k < bucket_ways; ++k) place(k, h[begin[k] + i]);
    for (std::size_t k = 0; k < bucket_ways; ++k)
        for (std::size_t i = begin[k] + step_count; i < begin[k + 1]; ++i) place(k, h[i]);
    return out;
}

// The entries of bucketed chunks, in groups of consecutive buckets (merge_groups): taken end to end
// they are merge_bucketed's. build_tree classifies the groups where they lie, on their own
// tasks, without first copying them into one list (3 MB at 300^3, on one thread).
template <class Entries>
std::vector<Entries> merge_bucketed_groups(std::span<const bucketed_chunk> chunks, const direct_buckets& plan,
                                           const parallel_for_hook& parallel_for, std::pmr::memory_resource* scratch)
{
    std::vector<std::size_t> start(plan.buckets + 1, 0);
    for (std::size_t b = 0, offset = 0; b <= plan.buckets; ++b) {
        start[b] = offset;
        if (b < plan.buckets)
            for (const bucketed_chunk& c : chunks) offset += c.start[b + 1] - c.start[b];
    }
    const std::size_t n = start[plan.buckets];
    if (n == 0) return {};
    for (std::size_t b = 0; b < plan.buckets; ++b)
        if (start[b + 1] - start[b] >= (std::size_t(1) << 32))
            throw invalid_parameter("merge_bucketed.chunks", "must hold fewer than 2^32 hits per bucket of voxels", std::to_string(start[b + 1] - start[b]));
    const std::size_t tasks = parallel_for && n >= (std::size_t(1) << 16) ? 4 : 1;
    return merge_groups<Entries>(std::span<const std::size_t>(start), tasks, parallel_for, scratch, [&](std::size_t first, std::size_t last, Entries& out) {
        direct_merge table(plan.low_bits);
        for (std::size_t b = first; b < last; ++b) {
            for (const bucketed_chunk& c : chunks) table.add(c.keys.get() + c.start[b], c.start[b + 1] - c.start[b], short_key_shift);
            table.flush(voxel_index(b << plan.low_bits), out);
        }
    });
}

template <class Entries>
void merge_bucketed(std::span<const bucketed_chunk> chunks, const direct_buckets& plan, const parallel_for_hook& parallel_for,
                    std::pmr::memory_resource* scratch, Entries& entries)
{
    entries = entries_from<Entries>(scratch);
    std::vector<Entries> groups = merge_bucketed_groups<Entries>(chunks, plan, parallel_for, scratch);
    if (!groups.empty()) concatenate(std::move(groups), entries);
}

} // namespace detail

// One entry per distinct voxel of `hits`, in increasing voxel order; see the header comment for
// which level and part an entry keeps. Hit counts saturate at 2^32 - 1.
//
// `voxel_count`, when the caller knows it (the hypervolume's: build_tree passes it), bounds
// the voxel indices and spares a pass over the hits to find the largest; a hit at or past it is
// refused. 0 = unknown.
//
// With `parallel_for`, each pass is split into tasks on the caller's threads: the hits into
// parts that count and scatter their own share (part p's hits of a bucket go after parts < p's,
// so a bucket holds the same keys in the same order as one pass would), then the buckets into
// groups of about equal hit counts, each sorted and merged into its own entries, concatenated in
// bucket order. The entries are the same whatever the threads.
//
// `scratch` (scratch.hpp) serves the temporary buffers; null: new and delete.
inline std::vector<voxel_entry> compact(std::span<const hit> hits, const parallel_for_hook& parallel_for = {},
                                        std::uint64_t voxel_count = 0, std::pmr::memory_resource* scratch = nullptr)
{
    std::vector<voxel_entry> entries;
    const std::span<const hit> pieces[1] = {hits};
    detail::compact_into(pieces, parallel_for, voxel_count, scratch_or_default(scratch), entries);
    return entries;
}

} // namespace hypertree

#pragma once
// Voxel stores (paper section 5): what holds a hypertree's densities once it is generated.
//
// The paper weighs memory against lookup time and describes four organizations, which are the
// four store kinds here, one header each:
//   dense_store        a plain 3D array: fastest lookup, 2 bytes per voxel of the whole grid
//                      and a bit per 32 voxels saying which it wrote, for rebuilding
//                      (the paper's choice up to resolution ~300);
//   index_list_store   sorted voxel indices with their densities and levels: 6 bytes per non-empty
//                      voxel, lookup by bisection (resolutions over 1000 fit in memory);
//   bit_array_store    the index list plus one occupancy bit per voxel between the first and last
//                      non-empty index, so empty voxels (most lookups) cost one bit test
//                      (the paper's compromise for resolutions 300-600);
//   partitioned_store  one index list per first-level subpart, each with its index range and
//                      bounding sphere, for shorter raymarching paths (sections 5 and 8.2).
//
// Every store satisfies `voxel_store`: it answers `at(index)` for any voxel of its hypervolume
// (density 0 when empty), visits its non-empty voxels in increasing index order, reports its
// memory from its containers' actual capacities, and knows the index-space bounding box of its
// non-empty voxels (the box the paper marks during generation, section 8.2). Stores are immutable
// values once built (docs/design.md#rule-6) and are all built the same way, from the sorted list of
// `stored_voxel` that `classify` or an operation (ops.hpp) produces:
//
//     S::build(volume, voxels, budget)
//
// `build` checks the list (sorted, unique, inside the volume, no empty voxel) and refuses, before
// allocating anything, a store whose memory would exceed the budget; `S::bytes_needed` tells in
// advance, so a caller can pick the fastest kind that fits. `S::build(volume, voxels, budget,
// std::move(old))` builds in the memory of a store `old` the caller is done with: a tree of the
// same size then maps no new page (huge_pages.hpp says why pages cost).

#include "hypertree/execution.hpp"
#include "hypertree/voxel.hpp"
#include "krs/core/bounds.hpp"

#include <algorithm>
#include <array>
#include <cassert>
#include <cmath>
#include <concepts>
#include <cstddef>
#include <cstdint>
#include <limits>
#include <span>
#include <string>
#include <string_view>
#include <vector>

namespace hypertree {

// Inclusive box of voxel coordinates; empty when lo > hi on any axis (the default).
struct index_box {
    std::array<int, 3> lo{0, 0, 0};
    std::array<int, 3> hi{-1, -1, -1};

    bool empty() const { return lo[0] > hi[0] || lo[1] > hi[1] || lo[2] > hi[2]; }
    bool contains(const std::array<int, 3>& c) const
    {
        return lo[0] <= c[0] && c[0] <= hi[0] && lo[1] <= c[1] && c[1] <= hi[1] && lo[2] <= c[2] && c[2] <= hi[2];
    }
    void include(const std::array<int, 3>& c)
    {
        for (int a = 0; a < 3; ++a) lo[a] = std::min(lo[a], c[a]), hi[a] = std::max(hi[a], c[a]);
    }
    static index_box nothing()
    {
        constexpr int big = std::numeric_limits<int>::max();
        return {{big, big, big}, {-big, -big, -big}};
    }
    friend bool operator==(const index_box&, const index_box&) = default;
};

// World-space corners of the voxels' cells: [minimum corner of lo's cell, maximum corner of hi's].
struct world_box {
    vec3d lo{}, hi{};
};
inline world_box world_bounds(const hypervolume& volume, const index_box& box)
{
    const vec3d& s = volume.voxel_size();
    const vec3d& o = volume.origin();
    return {{o.x + box.lo[0] * s.x, o.y + box.lo[1] * s.y, o.z + box.lo[2] * s.z},
            {o.x + (box.hi[0] + 1) * s.x, o.y + (box.hi[1] + 1) * s.y, o.z + (box.hi[2] + 1) * s.z}};
}

namespace detail {

// The coordinates of voxel indices met in (mostly) increasing order without dividing for each
// voxel: the walker keeps the grid row it is in and steps forward row by row (y, then z) to reach
// a later index's row, so a pass over a sorted list steps at most once per row of the whole grid
// (ny nz steps, a few operations each) where a division per row met cost more than the rest of
// the pass. An index more than a few rows ahead, or behind, is placed by dividing.
class coordinate_walker {
public:
    explicit coordinate_walker(const hypervolume& volume)
        : nx_(voxel_index(volume.grid().x)), ny_(voxel_index(volume.grid().y))
    {
    }
    std::array<int, 3> operator()(voxel_index i)
    {
        if (i >= row_end_ && i < row_end_ + std::uint64_t(steps_before_dividing) * nx_) {
            do {
                row_start_ = voxel_index(row_end_), row_end_ += nx_;
                if (++y_ == int(ny_)) y_ = 0, ++z_;
            } while (i >= row_end_);
        } else if (i < row_start_ || i >= row_end_) {
            const voxel_index row = i / nx_;
            row_start_ = row * nx_;
            row_end_ = std::uint64_t(row_start_) + nx_;
            y_ = int(row % ny_);
            z_ = int(row / ny_);
        }
        return {int(i - row_start_), y_, z_};
    }

private:
    static constexpr int steps_before_dividing = 64; // a division costs about as much
    voxel_index nx_, ny_;
    voxel_index row_start_ = 0;
    std::uint64_t row_end_ = 0; // the row before row 0 (y = -1): a first index in the first rows steps there
    int y_ = -1, z_ = 0;
};

// The sphere around the cells of voxels given by index (in roughly increasing order, for the
// walker): centered on the box of their centers, reaching the farthest center plus half a voxel
// diagonal, so it holds every cell whole. Parts' secondary bounding spheres (section 8.2).
template <class Indices>
krs::bounding_sphere cell_bounding_sphere(const hypervolume& volume, const Indices& indices)
{
    const vec3d& size = volume.voxel_size();
    const vec3d& origin = volume.origin();
    const auto center_of = [&](const std::array<int, 3>& c) {
        return vec3d{origin.x + (c[0] + 0.5) * size.x, origin.y + (c[1] + 0.5) * size.y, origin.z + (c[2] + 0.5) * size.z};
    };
    index_box box = index_box::nothing();
    coordinate_walker coordinates(volume);
    for (const voxel_index i : indices) box.include(coordinates(i));
    if (box.empty()) return {};
    const vec3d center = (center_of(box.lo) + center_of(box.hi)) * 0.5;
    double farthest_squared = 0;
    coordinate_walker again(volume);
    for (const voxel_index i : indices) farthest_squared = std::max(farthest_squared, krs::length_squared(center_of(again(i)) - center));
    return krs::bound_around(center, std::sqrt(farthest_squared) + 0.5 * krs::length(size));
}

// Position of the first element of sorted[0, n) that is >= key (n when none), by a bisection
// without data-dependent branches: it always takes ceil(log2 n) + 1 steps, and the compiler turns
// the step into a conditional move, so a lookup never pays for a mispredicted branch (the paper's
// bisection, section 5).
inline std::size_t lower_bound_position(const voxel_index* sorted, std::size_t n, voxel_index key)
{
    if (n == 0) return 0;
    const voxel_index* base = sorted;
    // Invariant: the answer lies in [base, base + n].
    while (n > 1) {
        const std::size_t half = n / 2;
        base = base[half] < key ? base + half : base;
        n -= half;
    }
    return std::size_t(base - sorted) + (*base < key);
}

// A directory over sorted index lists, so that a lookup need not bisect a whole list: the lists'
// index range [first, last] is cut into buckets of 2^shift consecutive indices, and the directory
// holds, for each bucket and each list, the position in that list of its first entry in the bucket
// (row b of the directory, `lists` positions, is bucket b; row `buckets` holds the lists' ends).
// A lookup reads a bucket's [begin, end) from two rows and bisects only the bucket's few entries,
// which lie in one or two cache lines: two or three cache misses instead of the ~log2(n)
// dependent misses of a bisection over 0.25-3 M indices. A bucket is a power of two of indices,
// not a grid row, so finding it is a subtraction and a shift (a division by the row length costs
// as much as the rest of a lookup). Several lists share one grid of buckets, so the parts of a
// partitioned store all find their entries, or their lack of any, in one row.
//
// The bucket width is the smallest power of two that keeps the directory to one position per
// `voxels_per_bucket` listed voxels at most, so it adds at most 4 / voxels_per_bucket bytes per
// non-empty voxel to the list's 6 whatever the resolution (a directory per grid row would take
// 4 MB at 1000^3, more than most trees' lists).
struct index_directory {
    static constexpr std::size_t voxels_per_bucket = 2;
    static constexpr std::size_t npos = std::numeric_limits<std::size_t>::max();

    voxel_index first = 0;     // the lowest listed index: bucket 0 starts here
    std::uint64_t buckets = 0; // 0 when the lists are empty
    unsigned shift = 0;        // bucket b holds indices first + [b << shift, (b + 1) << shift)
    std::size_t lists = 1;     // positions per row

    // The shape for `lists` lists of `count` sorted indices in all, from `first` to `last`, known
    // before the lists are copied anywhere (so bytes_needed can count the directory).
    static index_directory shape(voxel_index first, voxel_index last, std::size_t count, std::size_t lists = 1)
    {
        index_directory d;
        if (count == 0 || lists == 0) return d;
        d.first = first;
        d.lists = lists;
        // The offset of the last index (0 for a list that is not sorted, which build refuses).
        const std::uint64_t reach = last > first ? std::uint64_t(last) - first : 0;
        const std::uint64_t allowed = std::max<std::uint64_t>(1, count / (voxels_per_bucket * lists));
        while ((reach >> d.shift) + 1 > allowed) ++d.shift;
        d.buckets = (reach >> d.shift) + 1;
        return d;
    }
    // Directory entries: a row of positions per bucket and a row of the lists' ends.
    std::size_t positions() const { return buckets == 0 ? 0 : (std::size_t(buckets) + 1) * lists; }
    std::size_t bytes() const { return positions() * sizeof(std::uint32_t); }

    // Writes column `list` of the directory: sorted[0, n) is that list, its indices within
    // [first, last] of the shape.
    // (Counted, then summed: each bucket's start is the number of indices in the buckets before
    // it. Searching each bucket's start in the list branched on every index unpredictably.)
    void fill(const voxel_index* sorted, std::size_t n, std::uint32_t* starts, std::size_t list = 0) const
    {
        if (buckets == 0) return;
        assert(n == 0 || (sorted[0] >= first && bucket_of(sorted[n - 1]) != npos));
        for (std::uint64_t b = 0; b <= buckets; ++b) starts[b * lists + list] = 0;
        // Index k counts in the entry after its bucket's (all in [first, last] of the shape).
        for (std::size_t k = 0; k < n; ++k) ++starts[((std::uint64_t(sorted[k] - first) >> shift) + 1) * lists + list];
        for (std::uint64_t b = 1; b <= buckets; ++b) starts[b * lists + list] += starts[(b - 1) * lists + list];
    }

    // The bucket of index i, or npos when i is outside every bucket.
    std::size_t bucket_of(voxel_index i) const
    {
        // Unsigned wrap-around makes an index below first a huge offset: past the last bucket, or
        // in it and not found there.
        const std::uint64_t bucket = std::uint64_t(voxel_index(i - first)) >> shift;
        return bucket < buckets ? std::size_t(bucket) : npos;
    }
    // Position of i in sorted[begin, end), or npos.
    static std::size_t search(const voxel_index* sorted, std::size_t begin, std::size_t end, voxel_index i)
    {
        const std::size_t p = begin + lower_bound_position(sorted + begin, end - begin, i);
        return p < end && sorted[p] == i ? p : npos;
    }
    // Position of index i in a directory's only list (starts its filled directory), or npos.
    std::size_t find(const voxel_index* sorted, const std::uint32_t* starts, voxel_index i) const
    {
        const std::size_t bucket = bucket_of(i);
        if (bucket == npos) return npos;
        return search(sorted, starts[bucket], starts[bucket + 1], i);
    }
};

// A visitor of (index, voxel) with nothing in it, to state the for_each requirement.
struct voxel_visitor_archetype {
    void operator()(voxel_index, voxel) const {}
};

// The checks every build makes before it allocates: a list that breaks them is a caller's bug
// that would otherwise surface as wrong lookups far from its cause.
inline void require_storable(std::string_view store, const hypervolume& volume, std::span<const stored_voxel> voxels)
{
    const std::string name = std::string(store) + ".build voxels";
    for (std::size_t i = 0; i < voxels.size(); ++i) {
        const stored_voxel& v = voxels[i];
        if (v.index >= volume.voxel_count())
            throw invalid_parameter(
                name, "must name voxels of the hypervolume (index < " + std::to_string(volume.voxel_count()) + ")",
                std::to_string(v.index));
        if (v.value.density == 0)
            throw invalid_parameter(name, "must have density > 0 (empty voxels are not stored)",
                                    "voxel " + std::to_string(v.index));
        if (i > 0 && !(voxels[i - 1].index < v.index))
            throw invalid_parameter(name, "must be sorted by index without duplicates",
                                    "voxel " + std::to_string(v.index) + " after " +
                                        std::to_string(voxels[i - 1].index));
    }
}

inline void require_within_budget(std::string_view store, std::size_t needed, memory_budget budget,
                                  std::string_view why)
{
    if (needed > budget.bytes)
        throw invalid_parameter(std::string(store) + ".build memory_budget",
                                "must allow the " + std::to_string(needed) + " bytes the store needs (" +
                                    std::string(why) + ")",
                                std::to_string(budget.bytes) + " bytes");
}

// The voxels as the two parallel arrays the list stores keep: indices and values.
inline void split_voxels(std::span<const stored_voxel> voxels, std::vector<voxel_index>& indices, std::vector<voxel>& values)
{
    indices.resize(voxels.size());
    values.resize(voxels.size());
    for (std::size_t k = 0; k < voxels.size(); ++k) {
        indices[k] = voxels[k].index;
        values[k] = voxels[k].value;
    }
}

// Division of voxel indices by a fixed divisor without a divide instruction: the product with
// the divisor's reciprocal in double is within 2^-20 of the true quotient (an index has 32 bits,
// a double 53), so truncating it is the quotient or one off, which the remainder's sign or size
// corrects. A few instructions that vectorize, where a division costs 10 cycles or more.
struct index_divider {
    std::uint64_t divisor;
    double reciprocal;
    explicit index_divider(std::uint64_t d) : divisor(d), reciprocal(1.0 / double(d)) {}
    voxel_index quotient(voxel_index i) const
    {
        std::int64_t q = std::int64_t(double(i) * reciprocal);
        const std::int64_t r = std::int64_t(i) - q * std::int64_t(divisor);
        q += (r >= std::int64_t(divisor)) - (r < 0);
        return voxel_index(q);
    }
};

// The box of the voxels' coordinates. Voxels are sorted, so the first and last give the z range;
// x and y come from each index by two divisions, by the row length nx and the height ny (index_divider),
// a loop the compiler vectorizes (the coordinate walker stepped row by row: 0.2 ms at 300^3).
inline index_box bounds_of(const hypervolume& volume, std::span<const stored_voxel> voxels)
{
    if (voxels.empty()) return {};
    const voxel_index nx = voxel_index(volume.grid().x), ny = voxel_index(volume.grid().y);
    const index_divider by_nx(nx), by_ny(ny);
    voxel_index x_lo = nx, x_hi = 0, y_lo = ny, y_hi = 0;
    for (const stored_voxel& v : voxels) {
        const voxel_index row = by_nx.quotient(v.index), x = v.index - row * nx;
        const voxel_index y = row - by_ny.quotient(row) * ny;
        x_lo = std::min(x_lo, x), x_hi = std::max(x_hi, x), y_lo = std::min(y_lo, y), y_hi = std::max(y_hi, y);
    }
    const std::uint64_t slice = std::uint64_t(nx) * ny;
    return {{int(x_lo), int(y_lo), int(voxels.front().index / slice)}, {int(x_hi), int(y_hi), int(voxels.back().index / slice)}};
}

} // namespace detail

// What the raymarcher, the operations and the level-of-detail code need from a store.
template <class S>
concept voxel_store = requires(const S& store, voxel_index i, const hypervolume& volume,
                               std::span<const stored_voxel> voxels, memory_budget budget,
                               detail::voxel_visitor_archetype visit)
{
    {
        store.volume()
        } -> std::convertible_to<const hypervolume&>;
    {
        store.at(i)
        } -> std::same_as<voxel>;
    {
        store.memory_bytes()
        } -> std::same_as<std::size_t>;
    {
        store.nonempty_count()
        } -> std::same_as<std::size_t>;
    {
        store.bounds()
        } -> std::same_as<index_box>;
    store.for_each(visit);
    {
        S::bytes_needed(volume, voxels)
        } -> std::same_as<std::size_t>;
    {
        S::build(volume, voxels, budget)
        } -> std::same_as<S>;
};

// Visits every non-empty voxel of a store as a stored_voxel, in increasing index order, with the
// part it was built with where the store keeps parts (partitioned_store) and part 0 otherwise.
template <voxel_store S, class F>
void for_each_stored(const S& store, F&& visit)
{
    if constexpr (requires { store.for_each_stored(visit); })
        store.for_each_stored(visit);
    else
        store.for_each([&](voxel_index i, voxel v) { visit(stored_voxel{i, v, 0}); });
}

// The list a store was built from (parts as for_each_stored gives them): rebuild it as another
// kind with `T::build(store.volume(), stored_voxels(store))`.
template <voxel_store S>
std::vector<stored_voxel> stored_voxels(const S& store)
{
    std::vector<stored_voxel> voxels;
    voxels.reserve(store.nonempty_count());
    for_each_stored(store, [&](const stored_voxel& v) { voxels.push_back(v); });
    return voxels;
}

} // namespace hypertree

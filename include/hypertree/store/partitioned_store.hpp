#pragma once
// partitioned_store: one index list per first-level subpart (paper sections 5 and 8.2).
//
// A hypertree is a union of mostly disjoint subparts: the trunk (the condensation, part 0) and
// one copy of the whole tree under each first-level transformation j (part j + 1). Keeping a
// separate sorted list per part gives each part a tight description the raymarcher can use to
// skip empty space: its bounding sphere (spheres, not boxes, because the paper derives secondary
// bounds by transforming the primary sphere) and its index range. Each voxel belongs to exactly one part, the part of its
// shallowest hit as `compact` chose it, so the parts' lists are disjoint and together hold every
// non-empty voxel once.
//
// A lookup does not bisect the parts' lists whole: one directory over all of them
// (detail::index_directory) gives, for the bucket of consecutive indices that holds the index,
// each part's entries in that bucket, side by side, so the parts with none are passed over
// without touching their lists and the others are searched over a few entries.
//
// Storage is the index list's 6 bytes per non-empty voxel (the parts' lists lie back to back in
// one index array and one value array), the directory (at most 2 bytes per non-empty voxel) and
// one small record per part.
//
// Built again in a recycled store (build's last parameter), it keeps its lists' capacity: a tree
// of the same size or smaller maps no new page.

#include "hypertree/execution.hpp"
#include "hypertree/store/store.hpp"

#include "krs/core/bounds.hpp"

#include <algorithm>
#include <array>
#include <cmath>
#include <cstddef>
#include <cstdint>
#include <span>
#include <string>
#include <string_view>
#include <utility>
#include <vector>

namespace hypertree {

// One first-level subpart of a partitioned store.
struct store_part {
    std::uint8_t part = 0;       // stored_voxel::part: 0 trunk, j + 1 under transformation j
    krs::bounding_sphere sphere; // world space; holds every cell (not only the center) of the part's voxels
    index_box bounds;            // index-space box of its voxels
    voxel_index first_index = 0; // lowest and highest voxel index in the part
    voxel_index last_index = 0;
    std::size_t offset = 0; // its voxels are entries offset .. offset + count - 1 of the store's lists
    std::size_t count = 0;
};

class partitioned_store {
public:
    // Its name in forest files and on command lines (store_kinds.hpp: the kinds' one list).
    static constexpr std::string_view kind_name = "partitioned";
    static constexpr std::size_t bytes_per_voxel = sizeof(voxel_index) + sizeof(voxel);

    partitioned_store() = default;

    static std::size_t bytes_needed(const hypervolume&, std::span<const stored_voxel> voxels)
    {
        const std::size_t parts = part_count(voxels);
        return bytes_per_voxel * voxels.size() + sizeof(store_part) * parts + directory_of(voxels, parts).bytes();
    }

    static partitioned_store build(const hypervolume& volume, std::span<const stored_voxel> voxels,
                                   memory_budget budget = {})
    {
        return build(volume, voxels, budget, partitioned_store());
    }
    // The same store, built in `recycled`'s memory, which it consumes. Refused as build refuses,
    // before recycled is touched.
    static partitioned_store build(const hypervolume& volume, std::span<const stored_voxel> voxels, memory_budget budget,
                                   partitioned_store&& recycled)
    {
        detail::require_storable("partitioned_store", volume, voxels);
        detail::require_within_budget("partitioned_store", bytes_needed(volume, voxels), budget,
                                      std::to_string(bytes_per_voxel) + " bytes x " + std::to_string(voxels.size()) +
                                          " non-empty voxels + " + std::to_string(sizeof(store_part)) +
                                          " bytes per part + " +
                                          std::to_string(directory_of(voxels, part_count(voxels)).bytes()) +
                                          " bytes of list directory");
        partitioned_store store = std::move(recycled);
        store.parts_.clear();
        store.volume_ = volume;
        store.bounds_ = detail::bounds_of(volume, voxels);

        std::array<std::size_t, 256> population{};
        for (const stored_voxel& v : voxels) ++population[v.part];
        std::array<std::size_t, 256> next{};
        std::size_t offset = 0;
        const std::size_t parts = part_count(voxels);
        store.parts_.reserve(parts);
        for (std::size_t p = 0; p < 256; ++p) {
            if (population[p] == 0) continue;
            store_part part;
            part.part = std::uint8_t(p);
            part.offset = offset;
            part.count = population[p];
            store.parts_.push_back(part);
            next[p] = offset;
            offset += population[p];
        }
        // A stable scatter by part: each part's list stays sorted because the input is.
        store.indices_.resize(voxels.size());
        store.values_.resize(voxels.size());
        for (const stored_voxel& v : voxels) {
            const std::size_t k = next[v.part]++;
            store.indices_[k] = v.index;
            store.values_[k] = v.value;
        }
        for (store_part& part : store.parts_) store.describe(part);

        store.directory_ = directory_of(voxels, parts);
        store.starts_.resize(store.directory_.positions());
        for (std::size_t slot = 0; slot < parts; ++slot) {
            const store_part& part = store.parts_[slot];
            store.directory_.fill(store.indices_.data() + part.offset, part.count, store.starts_.data(), slot);
        }
        return store;
    }

    const hypervolume& volume() const { return volume_; }
    // Parts' index ranges overlap (a part spans many z slices, and so do its neighbours), so the
    // directory row of the index's bucket, which says where each part has entries near it, passes
    // over the parts with none; a part with some is also tested against its index box before it is
    // searched, since the two divisions that give the coordinates cost less than a needless search.
    voxel at(voxel_index i) const
    {
        const std::size_t bucket = directory_.bucket_of(i);
        if (bucket == detail::index_directory::npos) return voxel{};
        const std::uint32_t* begin = starts_.data() + bucket * parts_.size();
        const std::uint32_t* end = begin + parts_.size();
        std::array<int, 3> c{};
        bool have_coordinates = false;
        for (std::size_t slot = 0; slot < parts_.size(); ++slot) {
            if (begin[slot] == end[slot]) continue;
            if (!have_coordinates) c = volume_.coordinates(i), have_coordinates = true;
            if (!parts_[slot].bounds.contains(c)) continue;
            const std::size_t offset = parts_[slot].offset;
            const std::size_t p = detail::index_directory::search(indices_.data() + offset, begin[slot], end[slot], i);
            if (p != detail::index_directory::npos) return values_[offset + p];
        }
        return voxel{};
    }
    // The voxel as part parts()[slot] holds it: empty when the voxel belongs to another part. For
    // a raymarcher that already knows which part's sphere it is in.
    voxel at_in_part(std::size_t slot, voxel_index i) const
    {
        const std::size_t bucket = directory_.bucket_of(i);
        if (bucket == detail::index_directory::npos) return voxel{};
        const std::uint32_t* begin = starts_.data() + bucket * parts_.size() + slot;
        const std::size_t offset = parts_[slot].offset;
        const std::size_t p =
            detail::index_directory::search(indices_.data() + offset, *begin, *(begin + parts_.size()), i);
        return p != detail::index_directory::npos ? values_[offset + p] : voxel{};
    }
    std::size_t memory_bytes() const
    {
        return indices_.capacity() * sizeof(voxel_index) + values_.capacity() * sizeof(voxel) +
               parts_.capacity() * sizeof(store_part) + starts_.capacity() * sizeof(std::uint32_t);
    }
    std::size_t nonempty_count() const { return indices_.size(); }
    index_box bounds() const { return bounds_; }
    std::span<const store_part> parts() const { return parts_; }

    // In increasing index order across parts: a merge of the parts' sorted lists.
    template <class F>
    void for_each(F&& visit) const
    {
        for_each_stored([&](const stored_voxel& v) { visit(v.index, v.value); });
    }
    template <class F>
    void for_each_stored(F&& visit) const
    {
        if (parts_.size() == 1) {
            const std::uint8_t part = parts_.front().part;
            for (std::size_t k = 0; k < indices_.size(); ++k) visit(stored_voxel{indices_[k], values_[k], part});
            return;
        }
        // A min-heap of (next index, part slot); a part's next voxel replaces the one it gave.
        using cursor = std::pair<voxel_index, std::size_t>;
        std::vector<cursor> heap;
        std::vector<std::size_t> position(parts_.size());
        heap.reserve(parts_.size());
        for (std::size_t s = 0; s < parts_.size(); ++s) {
            position[s] = parts_[s].offset;
            heap.emplace_back(indices_[position[s]], s);
        }
        const auto later = [](const cursor& a, const cursor& b) { return a.first > b.first; };
        std::make_heap(heap.begin(), heap.end(), later);
        while (!heap.empty()) {
            std::pop_heap(heap.begin(), heap.end(), later);
            const std::size_t s = heap.back().second;
            const std::size_t k = position[s]++;
            visit(stored_voxel{indices_[k], values_[k], parts_[s].part});
            if (position[s] < parts_[s].offset + parts_[s].count) {
                heap.back().first = indices_[position[s]];
                std::push_heap(heap.begin(), heap.end(), later);
            } else {
                heap.pop_back();
            }
        }
    }

private:
    static std::size_t part_count(std::span<const stored_voxel> voxels)
    {
        std::array<bool, 256> present{};
        std::size_t parts = 0;
        for (const stored_voxel& v : voxels) parts += !std::exchange(present[v.part], true);
        return parts;
    }
    // One column of positions per part, over the index range of all the voxels.
    static detail::index_directory directory_of(std::span<const stored_voxel> voxels, std::size_t parts)
    {
        if (voxels.empty()) return {};
        return detail::index_directory::shape(voxels.front().index, voxels.back().index, voxels.size(), parts);
    }

    // Index range, index box and bounding sphere (detail::cell_bounding_sphere: every cell whole)
    // of a part whose list is in place.
    void describe(store_part& part) const
    {
        const std::span<const voxel_index> list(indices_.data() + part.offset, part.count);
        part.first_index = list.front();
        part.last_index = list.back();
        part.bounds = index_box::nothing();
        detail::coordinate_walker coordinates(volume_);
        for (const voxel_index i : list) part.bounds.include(coordinates(i));

        part.sphere = detail::cell_bounding_sphere(volume_, list);
    }

    hypervolume volume_{};
    std::vector<voxel_index> indices_;
    std::vector<voxel> values_;
    std::vector<store_part> parts_;
    detail::index_directory directory_{};
    std::vector<std::uint32_t> starts_; // directory_'s positions: a row per bucket, a column per part
    index_box bounds_{};
};

static_assert(voxel_store<partitioned_store>);

} // namespace hypertree

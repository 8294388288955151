#pragma once
// index_list_store: the paper's compact hypertree (section 5).
//
// Only non-empty voxels are kept: their indices in increasing order (4 bytes each, as in the
// paper) and beside them their density and level (2 bytes), 6 bytes per non-empty voxel. A tree
// fills a few percent of its hypervolume, so this is a small fraction of a dense array, and
// resolutions over 1000 fit in memory. An index that is not in the list is an empty voxel.
//
// The paper finds an index by bisecting the whole list, ~log2(n) dependent cache misses for the
// 0.25-3 M voxels of a tree. A directory over the list (detail::index_directory: one list position
// per bucket of consecutive indices, at most 2 bytes per non-empty voxel) narrows the bisection
// to a bucket's few entries first, so a lookup costs a few cache misses at any list length.
//
// Built again in a recycled store (build's last parameter), it keeps its lists' capacity: a tree
// of the same size or smaller maps no new page.

#include "hypertree/execution.hpp"
#include "hypertree/store/store.hpp"

#include <cstddef>
#include <cstdint>
#include <span>
#include <string>
#include <string_view>
#include <utility>
#include <vector>

namespace hypertree {

class index_list_store {
public:
    // Its name in forest files and on command lines (store_kinds.hpp: the kinds' one list).
    static constexpr std::string_view kind_name = "index_list";
    static constexpr std::size_t bytes_per_voxel = sizeof(voxel_index) + sizeof(voxel);

    index_list_store() = default;

    static std::size_t bytes_needed(const hypervolume&, std::span<const stored_voxel> voxels)
    {
        return bytes_per_voxel * voxels.size() + directory_of(voxels).bytes();
    }

    static index_list_store build(const hypervolume& volume, std::span<const stored_voxel> voxels,
                                  memory_budget budget = {})
    {
        return build(volume, voxels, budget, index_list_store());
    }
    // The same store, built in `recycled`'s memory, which it consumes. Refused as build refuses,
    // before recycled is touched.
    static index_list_store build(const hypervolume& volume, std::span<const stored_voxel> voxels, memory_budget budget,
                                  index_list_store&& recycled)
    {
        detail::require_storable("index_list_store", volume, voxels);
        detail::require_within_budget("index_list_store", bytes_needed(volume, voxels), budget,
                                      std::to_string(bytes_per_voxel) + " bytes x " + std::to_string(voxels.size()) +
                                          " non-empty voxels + " + std::to_string(directory_of(voxels).bytes()) +
                                          " bytes of list directory");
        index_list_store store = std::move(recycled);
        store.volume_ = volume;
        detail::split_voxels(voxels, store.indices_, store.values_);
        store.directory_ = directory_of(voxels);
        store.starts_.resize(store.directory_.positions());
        store.directory_.fill(store.indices_.data(), store.indices_.size(), store.starts_.data());
        store.bounds_ = detail::bounds_of(volume, voxels);
        return store;
    }

    const hypervolume& volume() const { return volume_; }
    voxel at(voxel_index i) const
    {
        const std::size_t p = directory_.find(indices_.data(), starts_.data(), i);
        return p != detail::index_directory::npos ? values_[p] : voxel{};
    }
    std::size_t memory_bytes() const
    {
        return indices_.capacity() * sizeof(voxel_index) + values_.capacity() * sizeof(voxel) +
               starts_.capacity() * sizeof(std::uint32_t);
    }
    std::size_t nonempty_count() const { return indices_.size(); }
    index_box bounds() const { return bounds_; }

    template <class F>
    void for_each(F&& visit) const
    {
        for (std::size_t k = 0; k < indices_.size(); ++k) visit(indices_[k], values_[k]);
    }

    // The lists themselves, for code that walks them in bulk (level of detail, the raymarcher).
    std::span<const voxel_index> indices() const { return indices_; }
    std::span<const voxel> values() const { return values_; }

private:
    static detail::index_directory directory_of(std::span<const stored_voxel> voxels)
    {
        if (voxels.empty()) return {};
        return detail::index_directory::shape(voxels.front().index, voxels.back().index, voxels.size());
    }

    hypervolume volume_{};
    std::vector<voxel_index> indices_;
    std::vector<voxel> values_;
    detail::index_directory directory_{};
    std::vector<std::uint32_t> starts_; // directory_'s list positions
    index_box bounds_{};
};

static_assert(voxel_store<index_list_store>);

} // namespace hypertree

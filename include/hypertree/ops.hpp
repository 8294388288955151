#pragma once
// Operations on hypertrees (paper section 7).
//
// Hypertrees are volume densities, so combining and editing them needs no surface geometry: an
// operation is a rule per voxel. Both operands must share one hypervolume (origin, extent and
// resolution), so voxel i means the same cell in each; anything else is refused.
//
//   unite_max   the paper's union, density max(a, b). The level (and part) of the denser voxel
//               is kept, the shallower one on equal densities: the result is commutative and
//               unite_max(a, a) == a.
//   unite_sum   density a + b saturating at 255, the shallower level: the paper's alternative,
//               which equals running both IFSs into one volume.
//   clear       empties every voxel of a region (cutting branches off, trimming).
//   set         gives every voxel of a region one value.
//
// A voxel is in a region when its center is. Regions (region.hpp) are world-space boxes, spheres
// and half-spaces; the same regions trim a tree while it is generated (ifs::trim), which is not
// the same as clearing them afterwards (region.hpp says how the two differ).
//
// Each operation takes stores of any kinds (a and b may differ) and returns the sorted
// `stored_voxel` list, from which the caller builds the store kind it wants; the `_store`
// variants build the operands' kind directly. Parts survive where the operands keep them
// (partitioned_store), as the part of the voxel whose level is kept.

#include "hypertree/execution.hpp"
#include "hypertree/region.hpp"
#include "hypertree/store/store.hpp"

#include <algorithm>
#include <array>
#include <cmath>
#include <concepts>
#include <cstddef>
#include <cstdint>
#include <limits>
#include <string>
#include <string_view>
#include <vector>

namespace hypertree {

namespace detail {

inline void require_same_volume(std::string_view operation, const hypervolume& a, const hypervolume& b)
{
    if (a == b) return;
    const auto describe = [](const hypervolume& v) {
        const resolution r = v.grid();
        return std::to_string(r.x) + "x" + std::to_string(r.y) + "x" + std::to_string(r.z) + " voxels over " +
               krs::detail::to_text(v.origin()) + " + " + krs::detail::to_text(v.extent());
    };
    throw invalid_parameter(std::string(operation) + " b",
                            "must have the same hypervolume as a (origin, extent and resolution)",
                            describe(b) + " vs a: " + describe(a));
}

// The better of two stored voxels for keeping level and part: the shallower level, then the
// smaller part, so a choice between equals does not depend on operand order.
inline const stored_voxel& shallower(const stored_voxel& a, const stored_voxel& b)
{
    if (a.value.level != b.value.level) return a.value.level < b.value.level ? a : b;
    return a.part <= b.part ? a : b;
}

// Merges the non-empty voxels of a and b by index; `combine` decides a voxel present in both.
template <voxel_store A, voxel_store B, class Combine>
std::vector<stored_voxel> merge_stores(std::string_view operation, const A& a, const B& b, Combine combine)
{
    require_same_volume(operation, a.volume(), b.volume());
    const std::vector<stored_voxel> from_b = stored_voxels(b);
    std::vector<stored_voxel> merged;
    merged.reserve(a.nonempty_count() + from_b.size());
    std::size_t k = 0;
    for_each_stored(a, [&](const stored_voxel& va) {
        for (; k < from_b.size() && from_b[k].index < va.index; ++k) merged.push_back(from_b[k]);
        if (k < from_b.size() && from_b[k].index == va.index)
            merged.push_back(combine(va, from_b[k++]));
        else
            merged.push_back(va);
    });
    merged.insert(merged.end(), from_b.begin() + std::ptrdiff_t(k), from_b.end());
    return merged;
}

} // namespace detail

// ---- operations ----------------------------------------------------------------------------------

template <voxel_store A, voxel_store B>
std::vector<stored_voxel> unite_max(const A& a, const B& b)
{
    return detail::merge_stores("unite_max", a, b, [](const stored_voxel& va, const stored_voxel& vb) {
        if (va.value.density != vb.value.density) return va.value.density > vb.value.density ? va : vb;
        return detail::shallower(va, vb);
    });
}

template <voxel_store A, voxel_store B>
std::vector<stored_voxel> unite_sum(const A& a, const B& b)
{
    return detail::merge_stores("unite_sum", a, b, [](const stored_voxel& va, const stored_voxel& vb) {
        stored_voxel sum = detail::shallower(va, vb);
        sum.value.density = std::uint8_t(std::min(255, int(va.value.density) + int(vb.value.density)));
        return sum;
    });
}

// Every voxel of the store except those whose centers are inside the region.
template <voxel_store S, voxel_region R>
std::vector<stored_voxel> clear(const S& store, const R& region)
{
    const hypervolume& volume = store.volume();
    const index_box candidates = region.candidates(volume);
    std::vector<stored_voxel> kept;
    kept.reserve(store.nonempty_count());
    detail::coordinate_walker coordinates(volume);
    const vec3d& size = volume.voxel_size();
    const vec3d& origin = volume.origin();
    for_each_stored(store, [&](const stored_voxel& v) {
        const std::array<int, 3> c = coordinates(v.index);
        if (candidates.contains(c)) {
            const vec3d center{origin.x + (c[0] + 0.5) * size.x, origin.y + (c[1] + 0.5) * size.y,
                               origin.z + (c[2] + 0.5) * size.z};
            if (region.contains(center)) return;
        }
        kept.push_back(v);
    });
    return kept;
}

// The store with every voxel whose center is inside the region set to `value` (and `part`);
// setting density 0 clears. Only the region's index box is visited. The result may be much
// larger than the store (a region is filled whole), so its size is checked against the budget
// first, counting every voxel of the region's box.
template <voxel_store S, voxel_region R>
std::vector<stored_voxel> set(const S& store, const R& region, voxel value, std::uint8_t part = 0,
                              memory_budget budget = {})
{
    if (value.density == 0) return clear(store, region);
    const hypervolume& volume = store.volume();
    const index_box box = region.candidates(volume);
    const std::uint64_t box_voxels = box.empty() ? 0
                                                 : std::uint64_t(box.hi[0] - box.lo[0] + 1) *
                                                       std::uint64_t(box.hi[1] - box.lo[1] + 1) *
                                                       std::uint64_t(box.hi[2] - box.lo[2] + 1);
    const std::uint64_t most = (box_voxels + store.nonempty_count()) * sizeof(stored_voxel);
    if (most > budget.bytes)
        throw invalid_parameter("set memory_budget",
                                "must allow the " + std::to_string(most) + " bytes the result may take (" +
                                    std::to_string(box_voxels) + " voxels in the region's box + " +
                                    std::to_string(store.nonempty_count()) + " in the store, " +
                                    std::to_string(sizeof(stored_voxel)) + " bytes each)",
                                std::to_string(budget.bytes) + " bytes");

    const std::vector<stored_voxel> old = stored_voxels(store);
    std::vector<stored_voxel> result;
    result.reserve(old.size());
    std::size_t k = 0;
    const vec3d& size = volume.voxel_size();
    const vec3d& origin = volume.origin();
    // z, y, x nesting walks the region's voxels in increasing index, in step with the old list.
    for (int z = box.lo[2]; z <= box.hi[2]; ++z)
        for (int y = box.lo[1]; y <= box.hi[1]; ++y)
            for (int x = box.lo[0]; x <= box.hi[0]; ++x) {
                const vec3d center{origin.x + (x + 0.5) * size.x, origin.y + (y + 0.5) * size.y,
                                   origin.z + (z + 0.5) * size.z};
                if (!region.contains(center)) continue;
                const voxel_index i = volume.index(x, y, z);
                for (; k < old.size() && old[k].index < i; ++k) result.push_back(old[k]);
                if (k < old.size() && old[k].index == i) ++k; // replaced
                result.push_back({i, value, part});
            }
    result.insert(result.end(), old.begin() + std::ptrdiff_t(k), old.end());
    return result;
}

// ---- the same, building the operands' store kind ------------------------------------------------

template <voxel_store S>
S unite_max_store(const S& a, const S& b, memory_budget budget = {})
{
    return S::build(a.volume(), unite_max(a, b), budget);
}
template <voxel_store S>
S unite_sum_store(const S& a, const S& b, memory_budget budget = {})
{
    return S::build(a.volume(), unite_sum(a, b), budget);
}
template <voxel_store S, voxel_region R>
S clear_store(const S& store, const R& region, memory_budget budget = {})
{
    return S::build(store.volume(), clear(store, region), budget);
}
template <voxel_store S, voxel_region R>
S set_store(const S& store, const R& region, voxel value, std::uint8_t part = 0, memory_budget budget = {})
{
    return S::build(store.volume(), set(store, region, value, part, budget), budget);
}

} // namespace hypertree

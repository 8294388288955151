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
// A voxel is in a region when its center is. Regions are world-space boxes, spheres and
// half-spaces (a plane's point and normal; the half the normal points into is inside, so
// clearing it trims the tree along the plane).
//
// Each operation takes stores of any kinds (a and b may differ) and returns the sorted
// `stored_voxel` list, from which the caller builds the store kind it wants; the `_store`
// variants build the operands' kind directly. Parts survive where the operands keep them
// (partitioned_store), as the part of the voxel whose level is kept.

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

// Conservative index box of the voxels whose centers lie in the world box [lo, hi]: one voxel
// wider on each side than the exact bound, so rounding can only add candidates, and the exact
// decision is the region's contains() on each candidate's center.
inline index_box candidate_box(const hypervolume& volume, const vec3d& lo, const vec3d& hi)
{
    const resolution n = volume.grid();
    const vec3d& o = volume.origin();
    const vec3d& s = volume.voxel_size();
    // Center of cell i is o + (i + 0.5) s, so centers in [lo, hi] have i in [(lo - o)/s - 0.5, (hi - o)/s - 0.5].
    const auto first = [](double lo_, double o_, double s_, int cells) {
        const double c = std::ceil((lo_ - o_) / s_ - 0.5) - 1;
        return int(std::clamp(c, 0.0, double(cells)));
    };
    const auto last = [](double hi_, double o_, double s_, int cells) {
        const double c = std::floor((hi_ - o_) / s_ - 0.5) + 1;
        return int(std::clamp(c, -1.0, double(cells - 1)));
    };
    return {{first(lo.x, o.x, s.x, n.x), first(lo.y, o.y, s.y, n.y), first(lo.z, o.z, s.z, n.z)},
            {last(hi.x, o.x, s.x, n.x), last(hi.y, o.y, s.y, n.y), last(hi.z, o.z, s.z, n.z)}};
}

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

// ---- regions -----------------------------------------------------------------------------------

// What an operation needs of a region: whether a point is inside, and a world-space box that
// holds every inside point within the hypervolume (so an operation visits only that box).
template <class R>
concept voxel_region = requires(const R& region, const vec3d& p, const hypervolume& volume)
{
    {
        region.contains(p)
        } -> std::same_as<bool>;
    {
        region.candidates(volume)
        } -> std::same_as<index_box>;
};

// An axis-aligned world-space box, faces included.
struct box_region {
    vec3d lo, hi;

    box_region(const vec3d& lo_, const vec3d& hi_) : lo(lo_), hi(hi_)
    {
        krs::require_finite("box_region.lo", lo_);
        krs::require_finite("box_region.hi", hi_);
        if (!(lo_.x <= hi_.x && lo_.y <= hi_.y && lo_.z <= hi_.z))
            throw invalid_parameter("box_region.hi", "must be >= lo on every axis",
                                    krs::detail::to_text(hi_) + " with lo " + krs::detail::to_text(lo_));
    }
    bool contains(const vec3d& p) const
    {
        return lo.x <= p.x && p.x <= hi.x && lo.y <= p.y && p.y <= hi.y && lo.z <= p.z && p.z <= hi.z;
    }
    index_box candidates(const hypervolume& volume) const { return detail::candidate_box(volume, lo, hi); }
};

// A world-space ball, boundary included.
struct sphere_region {
    vec3d center;
    double radius;

    sphere_region(const vec3d& center_, double radius_) : center(center_), radius(radius_)
    {
        krs::require_finite("sphere_region.center", center_);
        krs::require_non_negative("sphere_region.radius", radius_);
    }
    bool contains(const vec3d& p) const { return krs::length_squared(p - center) <= radius * radius; }
    index_box candidates(const hypervolume& volume) const
    {
        const vec3d r{radius, radius, radius};
        return detail::candidate_box(volume, center - r, center + r);
    }
};

// The closed half-space on the side the normal points to: { p : dot(p - point, normal) >= 0 }.
struct half_space_region {
    vec3d point;
    vec3d normal; // unit length

    half_space_region(const vec3d& point_, const vec3d& normal_) : point(point_), normal(normal_)
    {
        krs::require_finite("half_space_region.point", point_);
        normal = krs::require_direction("half_space_region.normal", normal_);
    }
    bool contains(const vec3d& p) const { return krs::dot(p - point, normal) >= 0; }
    // The box of the hypervolume's part inside the half-space: of the box's corners inside and
    // the points where the plane crosses its edges (the vertices of the clipped box).
    index_box candidates(const hypervolume& volume) const
    {
        const vec3d lo = volume.origin(), hi = volume.maximum();
        std::array<vec3d, 8> corner;
        std::array<double, 8> side;
        for (int c = 0; c < 8; ++c) {
            corner[c] = {(c & 1) ? hi.x : lo.x, (c & 2) ? hi.y : lo.y, (c & 4) ? hi.z : lo.z};
            side[c] = krs::dot(corner[c] - point, normal);
        }
        constexpr double inf = std::numeric_limits<double>::infinity();
        vec3d box_lo{inf, inf, inf}, box_hi{-inf, -inf, -inf};
        const auto include = [&](const vec3d& p) {
            box_lo = krs::min(box_lo, p);
            box_hi = krs::max(box_hi, p);
        };
        for (int c = 0; c < 8; ++c) {
            if (side[c] >= 0) include(corner[c]);
            for (int axis = 1; axis < 8; axis <<= 1) { // the edges from c to corners above it
                const int d = c | axis;
                if (d == c || (side[c] >= 0) == (side[d] >= 0)) continue;
                const double t = side[c] / (side[c] - side[d]);
                include(corner[c] + (corner[d] - corner[c]) * t);
            }
        }
        if (!(box_lo.x <= box_hi.x)) return {}; // the half-space misses the box
        return detail::candidate_box(volume, box_lo, box_hi);
    }
};

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

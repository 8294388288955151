#pragma once
// Regions of a hypervolume (paper section 7): world-space boxes, spheres and half-spaces, and the
// voxels they hold. A voxel is in a region when its center is.
//
// They serve two kinds of trimming, which the paper names side by side ("certain voxels have to
// be locked for hits or cleared afterward, so such deformation can be implemented as an internal
// constraint of IFS or performed as postprocessing"):
//   - afterwards: ops.hpp's clear() and set() empty or fill a region of a finished store;
//   - during generation: ifs::trim lists regions whose voxels are locked while the IFS runs
//     (create/generate.hpp): a hit on a locked voxel is never recorded. Generators still transform
//     and move on (the IFS is unchanged), so branches that pass through a region continue beyond
//     it: the paper's "dangling parts", which it leaves open.
//
// The two give the same occupied voxels (a voxel outside every region collects the same hits
// either way, and a voxel inside none), but not the same densities: density classes
// (create/density.hpp) are placed on the population of hit voxels, so the voxels a region would
// have held change the class boundaries of every other voxel when they are cleared afterwards, and
// not when they were never recorded. Trimming during generation classifies only what is left
// (tested in test_hypertree_ifs.cpp on a tree whose region holds many voxels).

#include "hypertree/store/store.hpp"
#include "krs/core/validate.hpp"

#include <algorithm>
#include <array>
#include <cmath>
#include <concepts>
#include <limits>
#include <span>
#include <string>
#include <string_view>
#include <variant>
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

} // namespace detail

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

    box_region(const vec3d& lo_, const vec3d& hi_) : lo(lo_), hi(hi_) { validate("box_region"); }
    // Fields are public, so a definition that holds regions checks them again under its own name.
    void validate(std::string_view name) const
    {
        const std::string n(name);
        krs::require_finite(n + ".lo", lo);
        krs::require_finite(n + ".hi", hi);
        if (!(lo.x <= hi.x && lo.y <= hi.y && lo.z <= hi.z))
            throw invalid_parameter(n + ".hi", "must be >= lo on every axis", krs::detail::to_text(hi) + " with lo " + krs::detail::to_text(lo));
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

    sphere_region(const vec3d& center_, double radius_) : center(center_), radius(radius_) { validate("sphere_region"); }
    void validate(std::string_view name) const
    {
        const std::string n(name);
        krs::require_finite(n + ".center", center);
        krs::require_non_negative(n + ".radius", radius);
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
    void validate(std::string_view name) const
    {
        const std::string n(name);
        krs::require_finite(n + ".point", point);
        // A normal set by hand after construction must still be unit: contains() compares a
        // signed distance, and a direction of length 0 or NaN put everything, or nothing, inside.
        const vec3d unit = krs::require_direction(n + ".normal", normal);
        if (!(std::abs(krs::length(normal) - 1.0) <= 1e-9))
            throw invalid_parameter(n + ".normal", "must be unit length (the constructor normalizes it)", krs::detail::to_text(normal));
        (void)unit;
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

// Any of the three, as a tree definition lists them (ifs::trim, the definition file's TRIM).
using trim_region = std::variant<box_region, sphere_region, half_space_region>;

// Whether a region holds the center of at least one voxel of the volume: a region that holds
// none (a sphere between centers, a box outside the volume, a half-space beyond it) locks nothing,
// which is a mistake in a definition rather than a request. Visits the candidate box until the
// first center inside (for a region not thinner than a voxel, at once).
template <voxel_region R>
bool holds_a_voxel(const R& region, const hypervolume& volume)
{
    const index_box box = region.candidates(volume);
    if (box.empty()) return false;
    const vec3d& s = volume.voxel_size();
    const vec3d& o = volume.origin();
    for (int z = box.lo[2]; z <= box.hi[2]; ++z)
        for (int y = box.lo[1]; y <= box.hi[1]; ++y)
            for (int x = box.lo[0]; x <= box.hi[0]; ++x)
                if (region.contains({o.x + (x + 0.5) * s.x, o.y + (y + 0.5) * s.y, o.z + (z + 0.5) * s.z})) return true;
    return false;
}

// Checks trim regions for a volume, naming each as `name`[i] (its fields, and that it holds a voxel).
inline void validate_trim_regions(std::string_view name, std::span<const trim_region> regions, const hypervolume& volume)
{
    for (std::size_t i = 0; i < regions.size(); ++i) {
        const std::string n = std::string(name) + "[" + std::to_string(i) + "]";
        std::visit(
            [&](const auto& r) {
                r.validate(n);
                if (!holds_a_voxel(r, volume))
                    throw invalid_parameter(n, "must hold the center of at least one voxel of the hypervolume (an empty region locks nothing)",
                                            "a region holding none");
            },
            regions[i]);
    }
}

// The voxels locked by a list of regions: is_locked(i) is true when voxel i's center lies in any
// of them. Each region's candidate box is computed once, so a voxel far from every region costs
// one index-box test per region and no center.
class voxel_lock {
public:
    voxel_lock(const hypervolume& volume, std::span<const trim_region> regions) : volume_(volume), regions_(regions.begin(), regions.end())
    {
        for (const trim_region& r : regions_) boxes_.push_back(std::visit([&](const auto& v) { return v.candidates(volume_); }, r));
    }
    bool empty() const { return regions_.empty(); }
    bool is_locked(voxel_index i) const
    {
        const std::array<int, 3> c = volume_.coordinates(i);
        for (std::size_t k = 0; k < regions_.size(); ++k) {
            if (!boxes_[k].contains(c)) continue;
            const vec3d& s = volume_.voxel_size();
            const vec3d& o = volume_.origin();
            const vec3d center{o.x + (c[0] + 0.5) * s.x, o.y + (c[1] + 0.5) * s.y, o.z + (c[2] + 0.5) * s.z};
            if (std::visit([&](const auto& r) { return r.contains(center); }, regions_[k])) return true;
        }
        return false;
    }

private:
    hypervolume volume_;
    std::vector<trim_region> regions_;
    std::vector<index_box> boxes_;
};

} // namespace hypertree

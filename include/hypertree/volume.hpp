#pragma once
// The hypervolume (paper section 4): the axis-aligned box that holds a hypertree, cut into a
// rectilinear grid of voxels whose resolution may differ per axis.
//
// A voxel is named by one linear index, x + nx * (y + ny * z), so that sorted index lists
// (section 5) walk the volume in rows. Indices are 32-bit as in the paper: a volume of more than
// 2^32 - 1 voxels (beyond about 1625^3) is refused at construction. Tree coordinates are the IFS
// space; the box is [origin, origin + extent], and the definition file's DISPLACEMENT says where the
// tree's origin sits inside it (origin = -displacement).

#include "krs/core/validate.hpp"

#include <algorithm>
#include <array>
#include <cmath>
#include <cstdint>
#include <limits>
#include <optional>
#include <string>

namespace hypertree {

using krs::invalid_parameter;
using krs::vec3d;

using voxel_index = std::uint32_t;

struct resolution {
    int x = 0, y = 0, z = 0;
    static constexpr resolution cube(int n) { return {n, n, n}; }
    friend bool operator==(const resolution&, const resolution&) = default;
};

// The largest voxel count a 32-bit index can name (one value is kept free as "no voxel").
inline constexpr std::uint64_t max_voxel_count = std::numeric_limits<voxel_index>::max();

// The smallest voxel side a hypervolume takes (the magnitude policy's 1e9, inverted).
inline constexpr double min_voxel_side = 1e-9;

class hypervolume {
public:
    hypervolume() = default;
    hypervolume(const vec3d& origin, const vec3d& extent, resolution res)
    {
        // The magnitude policy (krs/core/validate.hpp), and voxels float can place: renderers
        // work in float, where a box at 1e9 with sides of 1e-9, or a side of 5e-324, collapsed
        // to zero width and failed later under another parameter's name.
        krs::require_magnitude("hypervolume.origin", origin);
        krs::require_positive_length("hypervolume.extent.x", extent.x);
        krs::require_positive_length("hypervolume.extent.y", extent.y);
        krs::require_positive_length("hypervolume.extent.z", extent.z);
        for (auto [name, n] : {std::pair{"hypervolume.resolution.x", res.x}, std::pair{"hypervolume.resolution.y", res.y},
                               std::pair{"hypervolume.resolution.z", res.z}})
            if (n < 1) throw invalid_parameter(name, "must be >= 1", std::to_string(n));
        const double sides[3] = {extent.x / res.x, extent.y / res.y, extent.z / res.z};
        const double lows[3] = {origin.x, origin.y, origin.z}, spans[3] = {extent.x, extent.y, extent.z};
        const char* names[3] = {"hypervolume.extent.x", "hypervolume.extent.y", "hypervolume.extent.z"};
        for (int a = 0; a < 3; ++a) {
            // At least 8 float ulps of the box's farthest coordinate on that axis, and 1e-9.
            const double farthest = std::max(std::abs(lows[a]), std::abs(lows[a] + spans[a]));
            if (!(sides[a] >= std::max(min_voxel_side, 1e-6 * farthest)))
                throw invalid_parameter(names[a],
                                        "gives voxels of side " + krs::detail::to_text(sides[a]) +
                                            " (extent / resolution): a side must be at least 1e-9 and 1e-6 of the "
                                            "box's farthest coordinate, so float can place the voxels",
                                        krs::detail::to_text(spans[a]));
        }
        const std::uint64_t count = std::uint64_t(res.x) * std::uint64_t(res.y) * std::uint64_t(res.z);
        if (count > max_voxel_count)
            throw invalid_parameter("hypervolume.resolution", "must name at most 2^32 - 1 voxels (32-bit voxel indices)",
                                    std::to_string(res.x) + " x " + std::to_string(res.y) + " x " + std::to_string(res.z));
        origin_ = origin, extent_ = extent, res_ = res;
        voxel_size_ = {extent.x / res.x, extent.y / res.y, extent.z / res.z};
        cells_per_unit_ = {res.x / extent.x, res.y / extent.y, res.z / extent.z};
    }
    // The paper's form: the box extent, and where the tree's origin lies measured from the box's
    // minimum corner.
    static hypervolume from_displacement(const vec3d& extent, const vec3d& displacement, resolution res)
    {
        krs::require_finite("hypervolume.displacement", displacement);
        return hypervolume(-displacement, extent, res);
    }

    const vec3d& origin() const { return origin_; }
    const vec3d& extent() const { return extent_; }
    vec3d maximum() const { return origin_ + extent_; }
    resolution grid() const { return res_; }
    const vec3d& voxel_size() const { return voxel_size_; }
    double smallest_voxel_side() const { return std::min({voxel_size_.x, voxel_size_.y, voxel_size_.z}); }
    std::uint64_t voxel_count() const { return std::uint64_t(res_.x) * std::uint64_t(res_.y) * std::uint64_t(res_.z); }

    voxel_index index(int x, int y, int z) const
    {
        return voxel_index(x) + voxel_index(res_.x) * (voxel_index(y) + voxel_index(res_.y) * voxel_index(z));
    }
    std::array<int, 3> coordinates(voxel_index i) const
    {
        const int x = int(i % voxel_index(res_.x));
        i /= voxel_index(res_.x);
        return {x, int(i % voxel_index(res_.y)), int(i / voxel_index(res_.y))};
    }
    // The voxel holding p, or nothing when p lies outside the box (or is not finite). Cells are
    // half-open [lo, hi) except that the box's maximum face belongs to the last cell. The cell
    // coordinate is (p - origin) * cells_per_unit truncated: the voxel walk of create/generate.hpp
    // computes cells the same way, so both agree on boundaries.
    std::optional<voxel_index> voxel_at(const vec3d& p) const
    {
        const vec3d f = cell_coordinates(p);
        // Written so that NaN fails the test.
        if (!(f.x >= 0 && f.y >= 0 && f.z >= 0 && f.x <= res_.x && f.y <= res_.y && f.z <= res_.z)) return std::nullopt;
        return index(std::min(int(f.x), res_.x - 1), std::min(int(f.y), res_.y - 1), std::min(int(f.z), res_.z - 1));
    }
    // p in units of voxels from the origin corner.
    vec3d cell_coordinates(const vec3d& p) const
    {
        return {(p.x - origin_.x) * cells_per_unit_.x, (p.y - origin_.y) * cells_per_unit_.y, (p.z - origin_.z) * cells_per_unit_.z};
    }
    const vec3d& cells_per_unit() const { return cells_per_unit_; }
    vec3d voxel_center(voxel_index i) const
    {
        const auto c = coordinates(i);
        return {origin_.x + (c[0] + 0.5) * voxel_size_.x, origin_.y + (c[1] + 0.5) * voxel_size_.y,
                origin_.z + (c[2] + 0.5) * voxel_size_.z};
    }

    friend bool operator==(const hypervolume& a, const hypervolume& b)
    {
        return a.res_ == b.res_ && a.origin_.x == b.origin_.x && a.origin_.y == b.origin_.y &&
               a.origin_.z == b.origin_.z && a.extent_.x == b.extent_.x && a.extent_.y == b.extent_.y &&
               a.extent_.z == b.extent_.z;
    }

private:
    vec3d origin_{}, extent_{1, 1, 1}, voxel_size_{1, 1, 1}, cells_per_unit_{1, 1, 1};
    resolution res_{1, 1, 1};
};

} // namespace hypertree

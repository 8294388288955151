#pragma once
// What the raymarcher knows about a tree's shape beyond its voxels (paper sections 8.2 and 8.3):
// its bounding box, the secondary bounding spheres of its first-level subparts, and the structure
// flow of those subparts for procedural normals.
//
// Bounding volumes (8.2): rays are clipped to the box of the non-empty voxels, and a sample is
// only looked up when it lies in one of the part spheres. The paper derives the secondary spheres
// by pushing the primary sphere through each IFS transformation (radius scaled by (1 + dmax/r)^2
// for shears, grown by the perturbation amplitude); with per-level parameters that is only
// approximately conservative, so here each sphere is fitted to the voxels its part actually
// holds: it holds every cell of them, and skipping samples outside all spheres changes no pixel.
//
// Structure flow (8.3, figure 4): each first-level subpart has a centroid and a principal axis
// (the dominant eigenvector of its voxels' covariance: the direction its branch grows). The
// normal at a point is its offset from the nearby axes, made perpendicular to each axis and
// blended with weights 1 / (distance to the centroid)^2: outward from the branch structure, smooth,
// and defined for point generators that carry no direction of their own.

#include "hypertree/store/store.hpp"
#include "krs/core/bounds.hpp"
#include "krs/core/lanes.hpp"

#include <array>
#include <cmath>
#include <span>
#include <vector>

namespace hypertree {

struct part_flow {
    vec3d centroid{};
    vec3d axis{0, 1, 0};
    double weight_radius = 1; // softens 1/d^2 near the centroid: the part's RMS extent
};

struct tree_shape {
    world_box box{};                           // of the non-empty voxels' cells
    std::vector<krs::bounding_sphere> spheres; // per first-level part (empty: box only)
    std::vector<part_flow> flows;
    krs::bounding_sphere crown{}; // the whole tree: its "outer shell" for ambient attenuation

    // From a sorted stored-voxel list (parts as classify or a partitioned store keep them).
    static tree_shape of(const hypervolume& volume, std::span<const stored_voxel> voxels)
    {
        tree_shape shape;
        if (voxels.empty()) return shape;
        constexpr int max_parts = 256;
        struct moments {
            std::size_t n = 0;
            vec3d sum{};
            std::array<double, 6> second{}; // xx, xy, xz, yy, yz, zz
        };
        std::vector<moments> parts(max_parts);
        index_box box = index_box::nothing();
        for (const stored_voxel& v : voxels) {
            const vec3d c = volume.voxel_center(v.index);
            box.include(volume.coordinates(v.index));
            moments& m = parts[v.part];
            ++m.n;
            m.sum += c;
            m.second[0] += c.x * c.x, m.second[1] += c.x * c.y, m.second[2] += c.x * c.z;
            m.second[3] += c.y * c.y, m.second[4] += c.y * c.z, m.second[5] += c.z * c.z;
        }
        shape.box = world_bounds(volume, box);
        std::vector<std::vector<voxel_index>> part_indices(max_parts);
        for (const stored_voxel& v : voxels) part_indices[v.part].push_back(v.index);
        for (int p = 0; p < max_parts; ++p) {
            const moments& m = parts[p];
            if (!m.n) continue;
            shape.spheres.push_back(detail::cell_bounding_sphere(volume, part_indices[std::size_t(p)]));
            const double n = double(m.n);
            const vec3d c = m.sum / double(m.n);
            const std::array<double, 6> cov{m.second[0] / n - c.x * c.x, m.second[1] / n - c.x * c.y, m.second[2] / n - c.x * c.z,
                                            m.second[3] / n - c.y * c.y, m.second[4] / n - c.y * c.z, m.second[5] / n - c.z * c.z};
            part_flow f;
            f.centroid = c;
            f.axis = principal_axis(cov);
            f.weight_radius = std::max(std::sqrt(std::max(cov[0] + cov[3] + cov[5], 0.0)), volume.smallest_voxel_side());
            shape.flows.push_back(f);
        }
        const vec3d lo = shape.box.lo, hi = shape.box.hi;
        shape.crown = krs::bound_around((lo + hi) * 0.5, krs::length(hi - lo) * 0.5);
        return shape;
    }
    template <voxel_store S>
    static tree_shape of(const S& store)
    {
        const std::vector<stored_voxel> voxels = stored_voxels(store);
        return of(store.volume(), voxels);
    }

    // The blended outward normal at p (zero when there is no flow). One template for a point
    // (D = double) and for a packet of points (D = krs::packet_d, a point per lane), each lane
    // computing exactly what the scalar does: square roots and divisions are correctly rounded.
    template <class D = double>
    krs::vec3<D> normal_at(const krs::vec3<D>& p) const
    {
        using krs::select, krs::sqrt;
        const D zero(0.0);
        krs::vec3<D> n{zero, zero, zero};
        for (const part_flow& f : flows) {
            const krs::vec3<D> centroid{D(f.centroid.x), D(f.centroid.y), D(f.centroid.z)}, axis{D(f.axis.x), D(f.axis.y), D(f.axis.z)};
            const krs::vec3<D> d = p - centroid;
            const krs::vec3<D> radial = d - axis * krs::dot(d, axis);
            const D w = D(1.0) / (krs::dot(d, d) + D(f.weight_radius * f.weight_radius * 0.05));
            const D len = sqrt(krs::dot(radial, radial));
            const auto some = len > zero;
            // (A lane with no radial part divides by 0 and discards it.)
            const D scale = w / select(some, len, D(1.0));
            n = {n.x + select(some, radial.x * scale, zero), n.y + select(some, radial.y * scale, zero), n.z + select(some, radial.z * scale, zero)};
        }
        const D len = sqrt(krs::dot(n, n));
        const auto some = len > zero;
        const D safe = select(some, len, D(1.0));
        return {select(some, n.x / safe, zero), select(some, n.y / safe, zero), select(some, n.z / safe, zero)};
    }

private:
    // Dominant eigenvector of a symmetric 3x3 matrix by power iteration from the axis with the
    // largest variance (converges unless that start is orthogonal to it, which the choice avoids).
    static vec3d principal_axis(const std::array<double, 6>& c)
    {
        vec3d v = c[0] >= c[3] && c[0] >= c[5] ? vec3d{1, 0, 0} : c[3] >= c[5] ? vec3d{0, 1, 0} : vec3d{0, 0, 1};
        for (int i = 0; i < 64; ++i) {
            const vec3d w{c[0] * v.x + c[1] * v.y + c[2] * v.z, c[1] * v.x + c[3] * v.y + c[4] * v.z,
                          c[2] * v.x + c[4] * v.y + c[5] * v.z};
            const double len = krs::length(w);
            if (!(len > 0)) break;
            v = w / len;
        }
        return v.y < 0 ? -v : v; // branches grow upward-ish: a stable sign
    }
};

} // namespace hypertree

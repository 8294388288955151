#pragma once
// Level of detail (paper section 9, figure 5): a hypertree of lower resolution made by fusing
// voxels, and the resolution a view needs.
//
// Treating every voxel as a region of homogeneous density, a hypervolume of resolution n per axis
// becomes one of resolution m <= n over the same box. The reduction factor of an axis is
// r = n / m (normally in (1, 2]; any real ratio >= 1 is allowed), and new voxel k of that axis
// spans old voxels [k r, (k + 1) r). The density of a new voxel is the average of the old
// densities weighted by the volume each old voxel shares with it (figure 5's formula in three
// dimensions):
//
//     mu' = sum over old voxels i of  overlap_x(i) overlap_y(i) overlap_z(i) mu_i  /  (r_x r_y r_z)
//
// with overlaps measured in old voxels. For r <= 2 at most 3 old voxels per axis (27 in all) meet
// a new voxel; for larger factors more do. The other attributes follow the paper's empirical
// rules: the level is the most represented level among the overlapped non-empty voxels, each
// counted by its shared volume (ties: the shallower level); the part (a partitioned store's
// first-level subpart) is that of the heaviest contributor, the old voxel with the largest
// overlap times density (ties: the smaller part). The density is rounded to the nearest integer;
// a new voxel whose density rounds to 0 is empty and not stored.
//
// Exactness: with the old cell of an axis scaled to length m and the new one to length n, every
// cell boundary is an integer (old boundary i m, new boundary k n), so every overlap is an exact
// integer and a new voxel's density is the exact ratio
//     sum_i mu_i O_x O_y O_z  /  (n_x n_y n_z)      (O in units of 1/m old voxels).
// Each old voxel's overlaps sum to m per axis, so the total density (sum of density times voxel
// volume over the box) is preserved exactly before rounding, and rounding moves each new voxel's
// density by at most 1/2.
//
// Cost: only the non-empty old voxels are visited; an old voxel is at most one new voxel long per
// axis (r >= 1), so it touches at most 2 new voxels per axis and scatters at most 8
// contributions. Old voxels arrive in increasing index order, hence in increasing z, and each new
// z slab gathers from a contiguous run of them: contributions are collected for the current new
// slab and the next one, sorted by (new voxel, level) when the slab is complete and summed into
// its voxels, which therefore come out in increasing index order. Memory is two slabs' worth of
// contributions, never the new grid.
//
// As the paper notes, new voxels are treated as homogeneous again, so reducing in a chain (1000 to
// 800 to 600 to 400) differs from reducing once (1000 to 400); tests/test_hypertree_lod.cpp
// measures by how much.
//
// `resolution_for_projected_voxel` picks the reduction target from the projected voxel size
// (the paper names the criterion and leaves the study open; see its description below).

#include "hypertree/execution.hpp"
#include "hypertree/store/store.hpp"

#include "krs/trace/camera.hpp"

#include <algorithm>
#include <array>
#include <cmath>
#include <cstddef>
#include <cstdint>
#include <span>
#include <string>
#include <vector>

namespace hypertree {

// A new voxel before its density is rounded: what `reduce_unrounded` returns.
struct averaged_voxel {
    voxel_index index;
    double density; // the exact weighted average, in [0, 255]
    std::uint8_t level;
    std::uint8_t part;
};

namespace detail {

inline void require_reduction_target(const hypervolume& volume, resolution target)
{
    const auto check = [](const char* name, int wanted, int source) {
        if (wanted < 1 || wanted > source)
            throw invalid_parameter(name,
                                    "must be between 1 and the source resolution " + std::to_string(source) +
                                        " (level of detail only reduces)",
                                    std::to_string(wanted));
    };
    const resolution n = volume.grid();
    check("reduce.target.x", target.x, n.x);
    check("reduce.target.y", target.y, n.y);
    check("reduce.target.z", target.z, n.z);
}

// How the old cells of one axis meet the new ones. Old cell i spans [i m, (i + 1) m) and new
// cell k spans [k n, (k + 1) n) in units of 1 / m old voxels, so overlaps are exact integers.
// Since m <= n an old cell meets new cell `first` and, when it crosses a boundary, `first + 1`.
struct axis_overlap {
    std::uint32_t first;       // the first new cell the old cell meets
    std::uint32_t with_first;  // overlap with it
    std::uint32_t with_second; // overlap with first + 1 (0: none)
};

inline std::vector<axis_overlap> axis_overlaps(int old_cells, int new_cells)
{
    const std::uint64_t n = std::uint64_t(old_cells), m = std::uint64_t(new_cells);
    std::vector<axis_overlap> table(static_cast<std::size_t>(old_cells));
    for (std::uint64_t i = 0; i < n; ++i) {
        const std::uint64_t start = i * m, end = start + m; // < 2^64: n, m < 2^32
        const std::uint64_t first = start / n;
        const std::uint64_t boundary = (first + 1) * n;
        axis_overlap& o = table[std::size_t(i)];
        o.first = std::uint32_t(first);
        o.with_first = std::uint32_t(std::min(end, boundary) - start);
        o.with_second = std::uint32_t(end > boundary ? end - boundary : 0);
    }
    return table;
}

// One old voxel's share of one new voxel. weight = O_x O_y O_z <= m_x m_y m_z < 2^32.
struct contribution {
    voxel_index target;
    std::uint32_t weight;
    std::uint8_t level;
    std::uint8_t part;
    std::uint8_t density;
};

// The new voxels of one slab, from its contributions: sorted by (new voxel, level), then each
// voxel's run is summed. `emit(index, weighted_density_sum, level, part)` in increasing index
// order; the density is weighted_density_sum / (n_x n_y n_z).
template <class Emit>
void fuse_slab(std::vector<contribution>& slab, Emit& emit)
{
    std::sort(slab.begin(), slab.end(), [](const contribution& a, const contribution& b) {
        return a.target != b.target ? a.target < b.target : a.level < b.level;
    });
    for (std::size_t start = 0; start < slab.size();) {
        const voxel_index target = slab[start].target;
        std::uint64_t density_sum = 0;
        std::uint64_t best_level_weight = 0, heaviest = 0;
        std::uint8_t best_level = 0, part = 0;
        bool first_contributor = true;
        std::size_t k = start;
        while (k < slab.size() && slab[k].target == target) {
            // One run of equal level; levels ascend, so only a strictly heavier run replaces the
            // best one and ties keep the shallower level.
            const std::uint8_t level = slab[k].level;
            std::uint64_t level_weight = 0;
            for (; k < slab.size() && slab[k].target == target && slab[k].level == level; ++k) {
                const contribution& c = slab[k];
                const std::uint64_t mass = std::uint64_t(c.weight) * c.density;
                density_sum += mass;
                level_weight += c.weight;
                if (first_contributor || mass > heaviest || (mass == heaviest && c.part < part))
                    heaviest = mass, part = c.part, first_contributor = false;
            }
            if (level_weight > best_level_weight) best_level_weight = level_weight, best_level = level;
        }
        emit(target, density_sum, best_level, part);
        start = k;
    }
    slab.clear();
}

// The reduction itself, shared by the rounded and unrounded forms (see the header comment).
template <voxel_store S, class Emit>
void reduce_into(const S& store, resolution target, Emit&& emit)
{
    const hypervolume& volume = store.volume();
    require_reduction_target(volume, target);
    const resolution n = volume.grid();
    const std::vector<axis_overlap> along_x = axis_overlaps(n.x, target.x);
    const std::vector<axis_overlap> along_y = axis_overlaps(n.y, target.y);
    const std::vector<axis_overlap> along_z = axis_overlaps(n.z, target.z);
    const hypervolume reduced(volume.origin(), volume.extent(), target);

    // current: contributions to new slab `slab_z`; next: to slab_z + 1.
    std::vector<contribution> current, next;
    std::uint32_t slab_z = 0;
    coordinate_walker coordinates(volume);
    for_each_stored(store, [&](const stored_voxel& v) {
        const auto c = coordinates(v.index);
        const axis_overlap& oz = along_z[std::size_t(c[2])];
        // Old voxels come in increasing z: slabs before oz.first will receive nothing more.
        while (slab_z < oz.first) {
            fuse_slab(current, emit);
            std::swap(current, next);
            ++slab_z;
            if (current.empty() && next.empty()) slab_z = oz.first;
        }
        const axis_overlap& ox = along_x[std::size_t(c[0])];
        const axis_overlap& oy = along_y[std::size_t(c[1])];
        for (int dz = 0; dz < 2; ++dz) {
            const std::uint32_t wz = dz == 0 ? oz.with_first : oz.with_second;
            if (wz == 0) continue;
            for (int dy = 0; dy < 2; ++dy) {
                const std::uint32_t wy = dy == 0 ? oy.with_first : oy.with_second;
                if (wy == 0) continue;
                for (int dx = 0; dx < 2; ++dx) {
                    const std::uint32_t wx = dx == 0 ? ox.with_first : ox.with_second;
                    if (wx == 0) continue;
                    const voxel_index t =
                        reduced.index(int(ox.first) + dx, int(oy.first) + dy, int(oz.first) + dz);
                    (dz == 0 ? current : next)
                        .push_back({t, wx * wy * wz, v.value.level, v.part, v.value.density});
                }
            }
        }
    });
    fuse_slab(current, emit);
    fuse_slab(next, emit);
}

} // namespace detail

// The hypervolume of a reduction: the same box at the target resolution. Refuses a target
// larger than the source or below 1 on any axis.
inline hypervolume reduced_volume(const hypervolume& volume, resolution target)
{
    detail::require_reduction_target(volume, target);
    return hypervolume(volume.origin(), volume.extent(), target);
}

// The reduced hypertree as the sorted stored_voxel list stores are built from (over
// reduced_volume(store.volume(), target)). A target equal to the source resolution returns the
// source's voxels unchanged.
template <voxel_store S>
std::vector<stored_voxel> reduce(const S& store, resolution target)
{
    const resolution n = store.volume().grid();
    const std::uint64_t denominator = std::uint64_t(n.x) * std::uint64_t(n.y) * std::uint64_t(n.z);
    std::vector<stored_voxel> voxels;
    detail::reduce_into(store, target, [&](voxel_index i, std::uint64_t density_sum, std::uint8_t level, std::uint8_t part) {
        // Round half up, in integers: floor((2 s + d) / 2d). s <= 255 d, so this is <= 255.
        const std::uint64_t density = (2 * density_sum + denominator) / (2 * denominator);
        if (density != 0) voxels.push_back({i, voxel{std::uint8_t(density), level}, part});
    });
    return voxels;
}

// The same new voxels before rounding (every new voxel that any non-empty old voxel touches, even
// those whose density would round to 0): for measuring what rounding costs.
template <voxel_store S>
std::vector<averaged_voxel> reduce_unrounded(const S& store, resolution target)
{
    const resolution n = store.volume().grid();
    const double denominator = double(n.x) * double(n.y) * double(n.z);
    std::vector<averaged_voxel> voxels;
    detail::reduce_into(store, target, [&](voxel_index i, std::uint64_t density_sum, std::uint8_t level, std::uint8_t part) {
        voxels.push_back({i, double(density_sum) / denominator, level, part});
    });
    return voxels;
}

// The reduction as a store of kind T (the source's kind unless given).
template <voxel_store T, voxel_store S>
T reduce_store(const S& store, resolution target, memory_budget budget = {})
{
    return T::build(reduced_volume(store.volume(), target), reduce(store, target), budget);
}
template <voxel_store S>
S reduce_store(const S& store, resolution target, memory_budget budget = {})
{
    return reduce_store<S, S>(store, target, budget);
}

// The density integral over the box: sum of density times voxel volume (world units cubed times
// density units). Reduction preserves it exactly before rounding.
inline double density_integral(const hypervolume& volume, std::span<const stored_voxel> voxels)
{
    double sum = 0;
    for (const stored_voxel& v : voxels) sum += v.value.density;
    const vec3d& s = volume.voxel_size();
    return sum * s.x * s.y * s.z;
}
inline double density_integral(const hypervolume& volume, std::span<const averaged_voxel> voxels)
{
    double sum = 0;
    for (const averaged_voxel& v : voxels) sum += v.density;
    const vec3d& s = volume.voxel_size();
    return sum * s.x * s.y * s.z;
}
template <voxel_store S>
double density_integral(const S& store)
{
    double sum = 0;
    store.for_each([&](voxel_index, voxel v) { sum += v.density; });
    const vec3d& s = store.volume().voxel_size();
    return sum * s.x * s.y * s.z;
}

// ---- choosing the resolution from the projected voxel size ------------------------------------
//
// A voxel is worth its memory and marching steps only while it covers at least about one pixel
// (section 9: "the most appropriate voxel size based on the projected voxel area"). At distance
// d, a pixel whose footprint at distance 1 is f (the camera's pixel_footprint(): 2 tan(fov/2) /
// height; for a pixel of angular size a, f = 2 tan(a / 2), about a) covers a square of side
// p = d f facing the viewer (krs::pixel_size_at, the rule krs/trace/camera.hpp states once). A voxel of sides s_x, s_y, s_z is taken to have the projected area
// of a square of its geometric-mean side s = (s_x s_y s_z)^(1/3), which is exact for cubic
// voxels seen face-on. Keeping the grid's aspect ratio, the target resolution is
//
//     n'_a = clamp(floor(n_a s / p), 1, n_a)        for each axis a,
//
// the largest per-axis resolution (up to a relative 1e-9 against floating-point noise) whose
// mean voxel side s n_a / n'_a is at least p, never above the source resolution: projected voxel
// area >= pixel area. At distance 0 (viewer inside the box) the source resolution is returned.
// Off the image center a pixel subtends a smaller angle than at the center, so a voxel that
// covers a center pixel covers at least a pixel everywhere at that distance.
inline resolution resolution_for_projected_voxel(const hypervolume& volume, double distance, double pixel_footprint)
{
    krs::require_non_negative("resolution_for_projected_voxel.distance", distance);
    krs::require_positive("resolution_for_projected_voxel.pixel_footprint", pixel_footprint);
    const resolution n = volume.grid();
    const double pixel = krs::pixel_size_at(distance, pixel_footprint);
    if (!(pixel > 0)) return n;
    const vec3d& s = volume.voxel_size();
    const double mean_side = std::cbrt(s.x * s.y * s.z);
    const double scale = mean_side / pixel;
    const auto axis = [&](int cells) {
        const double wanted = std::floor(double(cells) * scale * (1 + 1e-9));
        return int(std::clamp(wanted, 1.0, double(cells)));
    };
    return {axis(n.x), axis(n.y), axis(n.z)};
}

// The same for a camera: the distance is from the eye to the nearest point of the hypervolume's
// box (0 when the eye is inside it), so the nearest voxels, the largest on screen, decide.
inline resolution resolution_for_projected_voxel(const hypervolume& volume, const krs::pinhole_camera& camera)
{
    const vec3d eye(camera.eye());
    const vec3d lo = volume.origin(), hi = volume.maximum();
    const vec3d nearest{std::clamp(eye.x, lo.x, hi.x), std::clamp(eye.y, lo.y, hi.y), std::clamp(eye.z, lo.z, hi.z)};
    return resolution_for_projected_voxel(volume, krs::length(eye - nearest), double(camera.pixel_footprint()));
}

} // namespace hypertree

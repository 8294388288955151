#pragma once
// The brick-walk tests' scenes and rays, shared by the CPU test (test_hypertree_brick_walk.cpp) and
// the GPU one (test_hypertree_glsl_gpu.cpp): a scattered grid and a forest of clumps whose occupied
// bricks are known independently of voxel_bricks, plain stepping as the reference, the scalar
// walk, and random rays.

#include "hypertree/render/brick_walk.hpp"
#include "hypertree/store/index_list_store.hpp"

#include <algorithm>
#include <array>
#include <cmath>
#include <cstdint>
#include <set>
#include <vector>

namespace krs_test {

using namespace hypertree;

struct lcg {
    std::uint32_t state;
    float uniform()
    {
        state = state * 1664525u + 1013904223u;
        return float(state >> 8) * 0x1.0p-24f;
    }
};

// A grid whose sides are not multiples of 4 or 16, off the origin, with non-cubic voxels, and a
// few scattered non-empty voxels: most bricks empty. At this density nearly every 16^3 block holds
// a voxel, so the corner x < 16, z < 32 (every y: four whole blocks) is left empty for the walk's
// block skips.
struct scattered {
    hypervolume volume{{-1.3, 0.2, 2.0}, {2.0, 1.5, 2.6}, resolution{37, 29, 45}};
    std::set<std::array<int, 3>> occupied; // bricks (cell >> 2) holding a voxel: the reference
    index_list_store store;
    voxel_bricks bricks;
    explicit scattered(std::uint32_t seed)
    {
        lcg random{seed};
        std::vector<stored_voxel> voxels;
        for (int z = 0; z < 45; ++z)
            for (int y = 0; y < 29; ++y)
                for (int x = 0; x < 37; ++x)
                    if (random.uniform() < 0.004f && !(x < 16 && z < 32)) {
                        voxels.push_back({volume.index(x, y, z), {std::uint8_t(1 + int(random.uniform() * 254)), 2}, 0});
                        occupied.insert({x >> 2, y >> 2, z >> 2});
                    }
        store = index_list_store::build(volume, voxels);
        bricks = voxel_bricks(store);
    }
    // Blocks coded empty (place below -64): at least the four of the empty corner.
    std::size_t empty_blocks() const
    {
        const auto codes = bricks.block_codes();
        return std::size_t(std::count(codes.begin(), codes.end(), -std::int32_t(voxel_bricks::brick_voxels)));
    }
};

// A forest: a 150 x 40 x 170 grid (off the origin, non-cubic voxels) holding a few clumps of
// voxels (trees) with wide clearings between them, the empty space the walk's coarse levels
// skip: most of the grid lies in empty cubes of 32^3 and more.
struct forest {
    hypervolume volume{{3.0, -0.5, -4.0}, {7.5, 1.6, 6.8}, resolution{150, 40, 170}};
    std::set<std::array<int, 3>> occupied; // bricks (cell >> 2) holding a voxel: the reference
    index_list_store store;
    voxel_bricks bricks;
    explicit forest(std::uint32_t seed)
    {
        lcg random{seed};
        std::vector<stored_voxel> voxels;
        // Clumps: a trunk up from the ground and a ball of scattered voxels above it.
        for (int tree = 0; tree < 7; ++tree) {
            const int cx = 6 + int(random.uniform() * 136), cz = 6 + int(random.uniform() * 156), top = 20 + int(random.uniform() * 14);
            const float radius = 3 + random.uniform() * 4;
            for (int z = 0; z < 170; ++z)
                for (int y = 0; y < 40; ++y)
                    for (int x = 0; x < 150; ++x) {
                        const float dx = float(x - cx), dy = float(y - top), dz = float(z - cz);
                        const bool trunk = x == cx && z == cz && y < top;
                        const bool crown = dx * dx + dy * dy + dz * dz < radius * radius && random.uniform() < 0.3f;
                        if (trunk || crown) voxels.push_back({volume.index(x, y, z), {std::uint8_t(1 + int(random.uniform() * 254)), 3}, 0});
                    }
        }
        std::sort(voxels.begin(), voxels.end(), [](const stored_voxel& a, const stored_voxel& b) { return a.index < b.index; });
        voxels.erase(std::unique(voxels.begin(), voxels.end(), [](const stored_voxel& a, const stored_voxel& b) { return a.index == b.index; }),
                     voxels.end());
        for (const stored_voxel& v : voxels) {
            const auto c = volume.coordinates(v.index);
            occupied.insert({int(c[0]) >> 2, int(c[1]) >> 2, int(c[2]) >> 2});
        }
        store = index_list_store::build(volume, voxels);
        bricks = voxel_bricks(store);
    }
};

struct looked_at {
    float k;
    int x, y, z;
    friend bool operator==(const looked_at&, const looked_at&) = default;
};

inline krs::vec3f cells_of(const hypervolume& v, const krs::vec3f& p)
{
    const krs::vec3f o(v.origin()), c(v.cells_per_unit());
    return {(p.x - o.x) * c.x, (p.y - o.y) * c.y, (p.z - o.z) * c.z};
}

// Plain stepping: every sample k of [0, count), in a non-empty brick by the reference set.
template <class Scene>
std::vector<looked_at> stepped(const Scene& s, const krs::vec3f& o, const krs::vec3f& d, float t0, float ds, int count)
{
    std::vector<looked_at> out;
    const int n[3] = {s.volume.grid().x, s.volume.grid().y, s.volume.grid().z};
    for (int k = 0; k < count; ++k) {
        const float t = t0 + (float(k) + 0.5f) * ds;
        const krs::vec3f f = cells_of(s.volume, o + d * t);
        if (!(f.x >= 0 && f.y >= 0 && f.z >= 0 && f.x < float(n[0]) && f.y < float(n[1]) && f.z < float(n[2]))) continue;
        const int x = std::min(int(f.x), n[0] - 1), y = std::min(int(f.y), n[1] - 1), z = std::min(int(f.z), n[2] - 1);
        if (s.occupied.count({x >> 2, y >> 2, z >> 2})) out.push_back({float(k), x, y, z});
    }
    return out;
}

// What the walks did: probes, samples skipped, probes in an empty cube of 16^3 or more (level
// >= 2, or the reference walk's empty block), probes in one of 32^3 or more (level >= 3), and skips
// whose landing lies two or more bricks (along some axis) past the sample that made them, which
// only a cube larger than a brick's can.
struct skip_counts {
    std::size_t probes = 0, skipped = 0, in_empty_block = 0, in_coarse_cube = 0, over_bricks = 0;
};

// The walk of one ray, scalar: what probe looks at, advancing as it says.
template <class Scene>
std::vector<looked_at> walked(const Scene& s, const brick_walk& w, const krs::vec3f& o, const krs::vec3f& d, float t0, int count,
                              skip_counts& counts)
{
    std::vector<looked_at> out;
    float slope[3];
    w.slopes_of(d, slope);
    const brick_walk::exit_faces faces = brick_walk::faces_of(slope);
    const float m0 = w.margin_at_origin(o);
    for (float k = 0; k < float(count);) {
        const float t = t0 + (k + 0.5f) * w.step();
        const auto found = w.probe<float>(s.bricks.view_of(), o + d * t, slope, true, w.skip_margin(m0, t), faces);
        if (found.looks) out.push_back({k, found.cell[0], found.cell[1], found.cell[2]});
        ++counts.probes;
        counts.skipped += std::size_t(found.advance - 1);
        const bool levels = w.skipping() == brick_walk::skips::every_level;
        const int level = found.place < 0 ? voxel_bricks::view::empty_level(found.place) : -1;
        counts.in_empty_block += levels ? level >= 2 : found.place < -64;
        counts.in_coarse_cube += levels && level >= 3;
        if (found.advance > 1) {
            const krs::vec3f here = cells_of(s.volume, o + d * t), there = cells_of(s.volume, o + d * (t0 + (k + found.advance + 0.5f) * w.step()));
            const float from[3] = {here.x, here.y, here.z}, to[3] = {there.x, there.y, there.z};
            bool far = false;
            for (int a = 0; a < 3; ++a) far = far || std::abs(std::floor(to[a] / 4) - std::floor(from[a] / 4)) >= 2;
            counts.over_bricks += far;
        }
        k += found.advance;
    }
    return out;
}

// Every probe of the scalar walk of one ray, in order: its sample k, and the index of the cell it
// looks at (x fastest), or -1 when it looks at nothing. Equal lists mean equal samples and equal
// skips, which the looked-at samples alone do not show (a short skip changes none of them).
struct probe_record {
    float k;
    int cell;
    friend bool operator==(const probe_record&, const probe_record&) = default;
};
inline std::vector<probe_record> probes_of(const scattered& s, const brick_walk& w, const krs::vec3f& o, const krs::vec3f& d, float t0, int count)
{
    std::vector<probe_record> out;
    float slope[3];
    w.slopes_of(d, slope);
    const brick_walk::exit_faces faces = brick_walk::faces_of(slope);
    const float m0 = w.margin_at_origin(o);
    const int nx = s.volume.grid().x, ny = s.volume.grid().y;
    for (float k = 0; k < float(count);) {
        const float t = t0 + (k + 0.5f) * w.step();
        const auto found = w.probe<float>(s.bricks.view_of(), o + d * t, slope, true, w.skip_margin(m0, t), faces);
        out.push_back({k, found.looks ? found.cell[0] + nx * (found.cell[1] + ny * found.cell[2]) : -1});
        k += found.advance;
    }
    return out;
}

// A ray toward a random point of the grid: from outside at `distance` (world units from the
// grid's center), or from inside; every 5th along an axis.
inline void random_ray(lcg& r, const hypervolume& v, float distance, int i, krs::vec3f& o, krs::vec3f& d)
{
    const krs::vec3f lo(v.origin()), size(v.extent());
    const krs::vec3f target{lo.x + r.uniform() * size.x, lo.y + r.uniform() * size.y, lo.z + r.uniform() * size.z};
    if (i % 5 == 0) {
        const int axis = i / 5 % 3;
        const float sign = i / 15 % 2 ? 1.0f : -1.0f;
        d = {axis == 0 ? sign : 0.0f, axis == 1 ? sign : 0.0f, axis == 2 ? sign : 0.0f};
        o = target - d * distance;
        return;
    }
    const krs::vec3f from{r.uniform() * 2 - 1, r.uniform() * 2 - 1, r.uniform() * 2 - 1};
    d = krs::normalize(from);
    o = target - d * (distance * (0.2f + r.uniform()));
}

// The samples of a ray that cover the grid: from 3 steps before it to 3 past, at t0 + (k + 1/2) ds
// for k in [0, count). False when the ray misses the grid.
inline bool samples_across(const hypervolume& v, const krs::vec3f& o, const krs::vec3f& d, float ds, float& t0, int& count)
{
    double enter = 0, leave = 1e30;
    const krs::vec3d lo(v.origin()), hi = lo + v.extent();
    const double od[3] = {o.x, o.y, o.z}, dd[3] = {d.x, d.y, d.z}, l[3] = {lo.x, lo.y, lo.z}, h[3] = {hi.x, hi.y, hi.z};
    for (int a = 0; a < 3; ++a) {
        if (dd[a] == 0) continue;
        const double ta = (l[a] - od[a]) / dd[a], tb = (h[a] - od[a]) / dd[a];
        enter = std::max(enter, std::min(ta, tb)), leave = std::min(leave, std::max(ta, tb));
    }
    if (!(enter < leave)) return false;
    t0 = float(std::max(0.0, enter - 3 * ds));
    count = int((leave + 3 * ds - double(t0)) / ds) + 1;
    return true;
}

} // namespace krs_test

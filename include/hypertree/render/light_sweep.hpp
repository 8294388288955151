#pragma once
// Self-shadowing by a sweep in light order (issue 27): each non-empty voxel's transmittance toward
// each light, computed once per marcher in one pass over the voxels, instead of a shadow ray per
// voxel marched again in every render.
//
// The shadow ray of a voxel v (marcher.hpp, shadow_transmittances) multiplies (1 - alpha) over its
// samples p_1, p_2, ... toward the light until it leaves the box or the light is gone. Its tail
// from a sample p_j on is the shadow ray of p_j. The sweep cuts every shadow ray at its first
// sample p_j (j >= near_steps) that lands in another non-empty voxel w, and takes the tail from
// w's own shadow: T(v) = prod_{i<j} (1 - alpha(p_i)) x (1 - alpha(w)) x T(w). The only
// approximation is that w's shadow starts at w's center rather than at p_j: a parallel ray offset
// by less than half a voxel diagonal. The samples before the cut are the shadow ray's own, so the
// shadow a voxel casts on its near neighbours is exact, and only the far part is shared. Each voxel
// then marches to its first non-empty neighbour toward the light (a few samples, empty bricks
// skipped) instead of through the crown, and one pass gives every voxel its light.
//
// The cuts form no cycle. A ray toward l moves every cell coordinate monotonically in the
// direction of sign(l_a) (its float positions are monotone in t), so along it the key
// sum_a sign(l_a) c_a never decreases, and grows strictly whenever the cell changes: w has a
// larger key than v. The sweep as first made visited the voxels by decreasing key (nearest the
// light first, `sweep_order`), so every w was swept before v, on one thread
// (volume_marcher::make_sweep_in_light_order, kept as the reference). The marcher now makes the
// table in two passes (volume_marcher::make_sweep): every voxel's ray to its cut, in memory order
// and in any order of tasks on the caller's threads, keeping the product P(v) and the cut w; then
// T(v) = P(v) T(w) along each chain of cuts (chains end, since keys grow). Each value is the same
// product in the same order either way. The table is a pure function of the voxels, options and
// light: the same on every run and thread count, and by both ways (tested, bit for bit). It does
// not depend on the camera (the lights' directions are the world's, march_options::lights): a
// marcher made once renders any number of views, and only a new tree or new lights pay the sweep.
//
// Rendering reads the table instead of marching: shading at a voxel's center takes T(v) as it is;
// a point elsewhere (shading per sample) marches to its own cut and takes the tail there. The
// difference from shadow rays is measured, not assumed (bench_hypertree_render --only error, and
// tests/test_hypertree_light_sweep.cpp against shadow rays at trees A-D). The GLSL marcher keeps
// shadow rays (glsl.hpp).

#include "hypertree/render/voxel_bricks.hpp"
#include "krs/core/vec3.hpp"

#include <algorithm>
#include <array>
#include <bit>
#include <cstddef>
#include <cstdint>
#include <vector>

namespace hypertree {

// The places of the non-empty voxels in sweep order toward the unit direction l: by decreasing
// key sum_a sign(l_a) c_a, grouped in levels of equal key. places[level[i], level[i + 1]) is
// level i. A counting sort over the key's range (at most 2 x the grid's perimeter + 1 keys).
struct sweep_order {
    std::vector<std::uint32_t> places;
    std::vector<std::size_t> level; // level starts, with places.size() last

    static sweep_order toward(const voxel_bricks& bricks, const krs::vec3f& l)
    {
        const int sign[3] = {l.x > 0 ? 1 : l.x < 0 ? -1 : 0, l.y > 0 ? 1 : l.y < 0 ? -1 : 0, l.z > 0 ? 1 : l.z < 0 ? -1 : 0};
        // key + offset in [0, range): the largest key (nearest the light) gets bucket 0.
        const std::int64_t offset = std::int64_t(bricks.grid()[0]) + bricks.grid()[1] + bricks.grid()[2];
        const std::size_t range = std::size_t(2 * offset + 1);
        const auto bucket = [&](const std::array<int, 3>& c) {
            return std::size_t(offset - (std::int64_t(sign[0]) * c[0] + std::int64_t(sign[1]) * c[1] + std::int64_t(sign[2]) * c[2]));
        };
        std::vector<std::size_t> start(range + 1, 0);
        for (std::size_t b = 0; b < bricks.brick_count(); ++b)
            for (std::uint64_t m = bricks.mask(b); m != 0; m &= m - 1)
                ++start[bucket(voxel_bricks::cell_at(bricks.origin(b), std::size_t(std::countr_zero(m)))) + 1];
        for (std::size_t k = 0; k < range; ++k) start[k + 1] += start[k];
        sweep_order order;
        order.places.resize(start[range]);
        std::vector<std::size_t> next(start.begin(), start.end() - 1);
        for (std::size_t b = 0; b < bricks.brick_count(); ++b)
            for (std::uint64_t m = bricks.mask(b); m != 0; m &= m - 1) {
                const std::size_t offset_in_brick = std::size_t(std::countr_zero(m));
                order.places[next[bucket(voxel_bricks::cell_at(bricks.origin(b), offset_in_brick))]++] =
                    std::uint32_t(b * voxel_bricks::brick_voxels + offset_in_brick);
            }
        for (std::size_t k = 0; k < range; ++k)
            if (start[k + 1] > start[k]) order.level.push_back(start[k]);
        order.level.push_back(start[range]);
        return order;
    }
    std::size_t levels() const { return level.size() - 1; }
};

// The swept transmittances: per light, one float per slot (voxel_bricks.hpp) of the non-empty
// voxels. Empty when the marcher uses shadow rays (or has no shadows or no lights).
class light_sweep {
public:
    light_sweep() = default;
    light_sweep(std::size_t slots, std::size_t lights) : slots_(slots), values_(std::max<std::size_t>(1, slots) * lights, 1.0f) {}

    bool empty() const { return values_.empty(); }
    // Light i's transmittance per slot (at least one entry, so that gathers of lanes with no
    // voxel, which read slot 0, stay inside).
    const float* toward(std::size_t light) const { return values_.data() + light * std::max<std::size_t>(1, slots_); }
    float* toward(std::size_t light) { return values_.data() + light * std::max<std::size_t>(1, slots_); }
    std::size_t memory_bytes() const { return values_.capacity() * sizeof(float); }

private:
    std::size_t slots_ = 0;
    std::vector<float> values_;
};

} // namespace hypertree

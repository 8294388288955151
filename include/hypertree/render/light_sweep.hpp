#pragma once
// Self-shadowing by a sweep in light order (issue 27): each non-empty voxel's transmittance toward
// each light, computed once per marcher in one pass over the voxels, instead of a shadow ray per
// voxel marched again in every render.
//
// The shadow ray of a voxel v (shadow_ray.hpp) multiplies (1 - alpha) over its samples p_1, p_2,
// ... toward the light until it leaves the box or the light is gone. Its tail from a sample p_j
// on is the shadow ray of p_j. The sweep cuts every shadow ray at its first
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
// (sweep_in_light_order, below, kept as the reference). The marcher makes the table in two
// passes (sweep_in_two_passes, through volume_marcher::make_sweep): every voxel's ray to its cut,
// in memory order and in any order of tasks on the caller's threads, keeping the product P(v) and
// the cut w; then T(v) = P(v) T(w) along each chain of cuts (chains end, since keys grow). Each
// value is the same product in the same order either way. The table is a pure function of the voxels, options and
// light: the same on every run and thread count, and by both ways (tested, bit for bit). It does
// not depend on the camera (the lights' directions are the world's, march_options::lights): a
// marcher made once renders any number of views, and only a new tree or new lights pay the sweep.
//
// Rendering reads the table instead of marching: shading at a voxel's center takes T(v) as it is;
// a point elsewhere (shading per sample) marches to its own cut and takes the tail there. The
// difference from shadow rays is measured, not assumed (bench_hypertree_render --only error, and
// tests/test_hypertree_light_sweep.cpp against shadow rays at trees A-D). The GLSL marcher keeps
// shadow rays (glsl.hpp).

#include "hypertree/execution.hpp"
#include "hypertree/render/shadow_ray.hpp"
#include "hypertree/render/voxel_bricks.hpp"
#include "krs/core/lanes.hpp"
#include "krs/core/vec3.hpp"

#include <algorithm>
#include <array>
#include <bit>
#include <concepts>
#include <cstddef>
#include <cstdint>
#include <span>
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

// What the sweep's passes read, all the marcher's (volume_marcher::make_sweep): its bricks, what
// its shadow rays read (shadow_ray.hpp), the lights' directions, and per axis and cell coordinate
// the coordinate of a voxel's center (the rays' origins, volume_marcher::center_of's values).
struct sweep_source {
    const voxel_bricks& bricks;
    shadow_reads reads;
    const std::vector<krs::vec3f>& lights;
    const std::array<std::vector<float>, 3>& centers;
};

namespace detail {

// The state of a wave of shadow rays, an entry per voxel (struct of arrays).
struct sweep_wave {
    std::vector<float> x, y, z, base, t1, margin0, j, transmittance, live;
    std::vector<float> cut; // the cut voxel's slot as bits (krs::index_bits), ~0: none (yet)
    std::vector<std::int32_t> own;
    std::vector<std::uint32_t> slot; // ~0: padding
    void resize(std::size_t n)
    {
        for (auto* v : {&x, &y, &z, &base, &t1, &margin0, &j, &transmittance, &live, &cut}) v->resize(n);
        own.resize(n), slot.resize(n);
    }
    void move(std::size_t to, std::size_t from)
    {
        for (auto* v : {&x, &y, &z, &base, &t1, &margin0, &j, &transmittance, &live, &cut}) (*v)[to] = (*v)[from];
        own[to] = own[from], slot[to] = slot[from];
    }
};

// The cut shadow rays (shadow_ray.hpp, with cuts) of the voxels at `places` toward the light l,
// marched as a wavefront: packets of live rays take a few steps each, then the finished rays
// leave the wave (their transmittance is written) and the rest close ranks, so packets stay full.
// Packets of fixed voxels waited on their longest ray (one that meets no voxel marches out of the
// box): 15% of the lanes worked (tree A at 300).
// Without `cut_slots`, a ray is completed at its cut by the cut voxel's entry of `out` (the sweep
// by levels: the places are one level, and no ray of a level reads a voxel of its own level, so
// writing during the level is safe); with `cut_slots`, a ray stops at its cut without it, and the
// cut voxel's slot is written to cut_slots[slot] (the first pass: nothing is read).
template <class T = krs::packet_f>
void sweep_rays(const sweep_source& source, const krs::vec3f& l, std::span<const std::uint32_t> places, float* out,
                std::uint32_t* cut_slots, sweep_wave& wave)
{
    using I = krs::index_lanes<T>;
    using krs::select, krs::any; // (unqualified below: packets take xsimd's, found by argument)
    constexpr std::size_t w = krs::lane_count<T>;
    // Steps between two closings of ranks: most rays meet their cut within a few steps, so
    // after 8 most lanes of a packet idled (sweep alone, one thread, trees A-D at resolution
    // 100: 4 steps 0.85-0.95 of 8's time, 3 and 2 alike, 16 1.15-1.25; at 300 4 as 8).
    constexpr int steps_per_pass = 4;
    const auto load_f = [](const float* a) {
        if constexpr (std::floating_point<T>) return *a;
        else return T::load_unaligned(a);
    };
    const auto load_i = [](const std::int32_t* a) {
        if constexpr (std::floating_point<T>) return *a;
        else return I::load_unaligned(a);
    };
    const auto store_f = [](float* a, const T& v) {
        if constexpr (std::floating_point<T>) *a = v;
        else v.store_unaligned(a);
    };
    const voxel_bricks& bricks = source.bricks;
    const shadow_ray<T> ray(source.reads, l);
    using lanes = typename shadow_ray<T>::lanes;
    const T zero(0.0f), one(1.0f);
    const std::size_t n = places.size();
    std::size_t active = (n + w - 1) / w * w;
    wave.resize(active);
    // A voxel's center by axis from the centers (read rather than computed through a division per
    // voxel); its own place is the place itself (the probe of its center, a gather, found it
    // before).
    for (std::size_t e = 0; e < active; ++e) {
        const std::uint32_t place = places[std::min(e, n - 1)];
        const std::array<int, 3> c = voxel_bricks::cell_at(bricks.origin(place / voxel_bricks::brick_voxels), place % voxel_bricks::brick_voxels);
        wave.x[e] = source.centers[0][std::size_t(c[0])], wave.y[e] = source.centers[1][std::size_t(c[1])],
        wave.z[e] = source.centers[2][std::size_t(c[2])];
        wave.own[e] = std::int32_t(place);
        wave.slot[e] = e < n ? bricks.slot(place) : ~std::uint32_t(0);
        wave.cut[e] = std::bit_cast<float>(~std::uint32_t(0)); // none (a quiet NaN's bits: moves keep them)
        wave.live[e] = e < n ? 1.0f : 0.0f;
    }
    for (std::size_t a = 0; a < active; a += w) {
        lanes s;
        s.p = {load_f(&wave.x[a]), load_f(&wave.y[a]), load_f(&wave.z[a])};
        ray.start(s);
        store_f(&wave.base[a], s.base), store_f(&wave.t1[a], s.t1), store_f(&wave.margin0[a], s.margin0);
        store_f(&wave.j[a], s.j), store_f(&wave.transmittance[a], s.transmittance);
    }
    while (active > 0) {
        // K packets in turn within one loop, as the marcher's shadow rays: each step's gathers
        // wait on the last step's, so one packet alone waits on memory at every step.
        constexpr std::size_t K = 4;
        for (std::size_t first = 0; first < active; first += K * w) {
            const std::size_t packets = std::min(K, (active - first) / w);
            std::array<lanes, K> s;
            std::array<T, K> cut_bits;
            for (std::size_t k = 0; k < packets; ++k) {
                const std::size_t a = first + k * w;
                s[k].p = {load_f(&wave.x[a]), load_f(&wave.y[a]), load_f(&wave.z[a])};
                s[k].base = load_f(&wave.base[a]), s[k].t1 = load_f(&wave.t1[a]), s[k].margin0 = load_f(&wave.margin0[a]);
                s[k].own = load_i(&wave.own[a]);
                s[k].j = load_f(&wave.j[a]), s[k].transmittance = load_f(&wave.transmittance[a]), cut_bits[k] = load_f(&wave.cut[a]);
                s[k].running = load_f(&wave.live[a]) > zero;
            }
            for (int step = 0; step < steps_per_pass; ++step) {
                bool marching = false;
                for (std::size_t k = 0; k < packets; ++k) {
                    krs::mask_t<T> cut;
                    I place;
                    if (!ray.step(s[k], nullptr, true, cut, place)) continue;
                    marching = true;
                    if (cut_slots) {
                        // The cut voxel's slot, its bits in a float lane (krs::index_bits).
                        if (any(cut)) cut_bits[k] = select(cut, krs::index_bits(ray.slot_of(place)), cut_bits[k]);
                    } else {
                        ray.complete(s[k], cut, place, out);
                    }
                }
                if (!marching) break;
            }
            // (A ray still running after its last step is checked against its end at the next pass.)
            for (std::size_t k = 0; k < packets; ++k) {
                const std::size_t a = first + k * w;
                store_f(&wave.j[a], s[k].j), store_f(&wave.transmittance[a], s[k].transmittance), store_f(&wave.cut[a], cut_bits[k]);
                store_f(&wave.live[a], select(s[k].running, one, zero));
            }
        }
        std::size_t kept = 0;
        for (std::size_t e = 0; e < active; ++e) {
            if (wave.live[e] > 0.0f) wave.move(kept++, e);
            else if (wave.slot[e] != ~std::uint32_t(0)) {
                out[wave.slot[e]] = wave.transmittance[e];
                if (cut_slots) cut_slots[wave.slot[e]] = std::bit_cast<std::uint32_t>(wave.cut[e]);
            }
        }
        active = (kept + w - 1) / w * w;
        for (std::size_t e = kept; e < active; ++e) wave.move(e, 0), wave.live[e] = 0.0f, wave.slot[e] = ~std::uint32_t(0);
    }
}

} // namespace detail

// Bricks per task of sweep_in_two_passes's first pass (tree A at resolution 300: about 750 voxels).
inline constexpr std::size_t sweep_task_bricks = 64;

// The sweep's table in two passes, the first on the caller's threads (`parallel_for`; empty: this
// thread).
//
// A voxel's swept transmittance is P(v) T(w): P(v) the product of (1 - alpha) over its ray's
// samples up to and including its cut w, T(w) the cut voxel's own. Only the last factor depends on
// another voxel's result, and only through one multiply. So the first pass marches every voxel's
// ray to its cut, with no order at all: the voxels of runs of sweep_task_bricks bricks per task,
// in memory order, so a packet's 16 rays start side by side and read the same bricks (the level
// order of the first sweep spread a packet over a diagonal plane of the tree); it writes P(v) to
// the table and w (or none) to a list. The second pass, on this thread, completes T(v) = P(v) T(w)
// along each chain of cuts: from each voxel it follows the cuts to the first voxel already
// complete (a voxel with no cut is complete), then completes the chain backwards. Cuts go to
// strictly larger keys (above), so a chain ends; each voxel is completed once. Every voxel's value
// is the same product in the same order as in the sweep by levels (sweep_in_light_order): the
// tables are equal to the bit, on any number of threads (tested).
inline light_sweep sweep_in_two_passes(const sweep_source& source, const parallel_for_hook& parallel_for = {})
{
    const voxel_bricks& bricks = source.bricks;
    const std::vector<krs::vec3f>& lights = source.lights;
    light_sweep table(bricks.voxel_count(), lights.size());
    constexpr std::uint32_t none = ~std::uint32_t(0);
    std::vector<std::uint32_t> cut(bricks.voxel_count() * lights.size(), none);
    const std::size_t runs = (bricks.brick_count() + sweep_task_bricks - 1) / sweep_task_bricks;
    run_tasks(parallel_for, runs * lights.size(), [&](std::size_t task) {
        const std::size_t light = task / runs, first = task % runs * sweep_task_bricks;
        const std::size_t last = std::min(bricks.brick_count(), first + sweep_task_bricks);
        std::vector<std::uint32_t> places;
        for (std::size_t b = first; b < last; ++b)
            for (std::uint64_t m = bricks.mask(b); m != 0; m &= m - 1)
                places.push_back(std::uint32_t(b * voxel_bricks::brick_voxels + std::size_t(std::countr_zero(m))));
        if (places.empty()) return;
        detail::sweep_wave wave;
        detail::sweep_rays(source, lights[light], places, table.toward(light), cut.data() + light * bricks.voxel_count(), wave);
    });
    // The chains are followed from the voxels in slot order (bricks by their first voxel in the
    // store's index order, z slowest) when the light is below (l_z <= 0: cuts go to lower z, whose
    // slots come first), else backwards: then a voxel's cut is mostly complete when it comes, and
    // its chain is one link, a branch the core predicts (in slot order toward a light above,
    // chains ran across the tree, and the pass took 15% of the sweep at tree A, resolution 100).
    // The order changes nothing else: each value is P(v) T(w) either way.
    std::vector<std::uint32_t> chain;
    for (std::size_t light = 0; light < lights.size(); ++light) {
        float* out = table.toward(light);
        std::uint32_t* next = cut.data() + light * bricks.voxel_count();
        const bool backwards = lights[light].z > 0;
        const std::size_t count = bricks.voxel_count();
        for (std::size_t i = 0; i < count; ++i) {
            const std::size_t v = backwards ? count - 1 - i : i;
            if (next[v] == none) continue;
            if (next[next[v]] == none) { // a chain of one link (the common case), without the list
                out[v] = out[v] * out[next[v]];
                next[v] = none;
                continue;
            }
            chain.clear();
            for (std::uint32_t u = std::uint32_t(v); next[u] != none; u = next[u]) chain.push_back(u);
            for (std::size_t i = chain.size(); i-- > 0;) {
                const std::uint32_t u = chain[i];
                out[u] = out[u] * out[next[u]]; // (as shadow_ray::complete multiplies at the cut)
                next[u] = none;
            }
        }
    }
    return table;
}

// The sweep's table as it was first made (the reference): per light, the levels of sweep_order in
// turn, nearest the light first, each level's rays completed at their cuts from the levels before.
// One thread.
inline light_sweep sweep_in_light_order(const sweep_source& source)
{
    light_sweep table(source.bricks.voxel_count(), source.lights.size());
    detail::sweep_wave wave;
    for (std::size_t i = 0; i < source.lights.size(); ++i) {
        const sweep_order order = sweep_order::toward(source.bricks, source.lights[i]);
        for (std::size_t level = 0; level < order.levels(); ++level)
            detail::sweep_rays(source, source.lights[i],
                               std::span(order.places).subspan(order.level[level], order.level[level + 1] - order.level[level]),
                               table.toward(i), nullptr, wave);
    }
    return table;
}

} // namespace hypertree

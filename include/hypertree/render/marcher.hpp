#pragma once
// The hypertree raymarcher (paper section 8): front-to-back accumulation along each ray with
// self-shadowing, one template for scalar rays (T = float) and SIMD packets of rays
// (T = krs::packet_f, one ray per lane).
//
// Along a ray clipped to the tree's box, samples sit at t_k = t_0 + (k + 1/2) ds, ds = step factor
// x the smallest voxel side ("a quality choice", 8.2). A sample's voxel takes its opacity for one
// step from the opacity law, and is lit, by voxel_shading.hpp; its color, multiplied by that
// opacity and by the transmittance so far, is added; the march ends when the transmittance falls
// below `min_transmittance` (full opacity) or the ray leaves the box.
//
// The marcher is made from any store and keeps what it reads: its copy of the voxels regrouped
// into 4^3 bricks (voxel_bricks.hpp, the layout the GLSL marcher reads too), the hypervolume, the
// shape and the shading. The store kind only changes how long the copy takes to make, and the
// store may go once the marcher is made. Empty space is skipped by the brick walk
// (brick_walk.hpp): a sample in an empty brick is not looked up, and the ray jumps by whole steps
// to the exit of the largest empty aligned cube around it (4^3 voxels up to the whole grid), so it
// takes exactly the samples it would have stepped through. (The walk of empty bricks and 16^3
// blocks only, the one before, is kept as a reference: the constructor's `skipping`.)
// Optionally (march_options::bounds_by), samples outside every secondary bound (part spheres,
// the paper's derived spheres, or part boxes: tree_shape.hpp) are not looked up either. Neither
// changes a pixel while the bound holds every non-empty cell, only the work.
//
// Shading (8.3, voxel_shading.hpp): ambient light attenuated toward the interior, wrapped Lambert
// diffuse and Blinn-Phong specular with the procedural normals of the structure flow, each light's
// term attenuated by the opacity a shadow ray accumulates toward it (shadow_ray.hpp: same step,
// same early exit). By default (march_options::shadow_by = sweep) those shadows come from the
// light sweep (light_sweep.hpp, which marches its rays and makes its table), computed once when
// the marcher is made (on the threads of the hook the constructor is given): each voxel's shadow
// ray is cut at its first non-empty voxel toward the light and completed by that voxel's swept
// shadow. With `rays` every shaded voxel marches its full shadow ray in every render (the
// reference; the GLSL marcher always does). By default a sample is shaded at its voxel's center
// (shade_per_voxel), so a voxel's shading is computed once per render and kept in a table
// (shade_memo.hpp): either all voxels before the rays (shade_bricks: the swept shadows read, or
// shadow rays marched 16 at a time), or each when a ray first meets it.
//
// Two marches, one accumulation: the loop over samples, the masks and the compositing are written
// once over T. Rays through voxels all shaded ahead only read: their lanes march in step,
// gathering places, opacities and colors from the table (march_in_step). So do rays under flat
// shading (no lights, no ambient falloff: voxel_shading::flat), where a sample's color depends on
// its voxel's level alone and is gathered by level, shaded per sample or per voxel alike (the
// OpenVDB comparison's "lighting off"; march_context::shade_each_sample keeps the per-lane march
// there, the reference). Otherwise each lane
// looks up and shades what it meets in scalar code, shading (and memoizing) each voxel it is the
// first to reach (march_shading_as_met). Either way a packet's lanes compute exactly what the
// scalar marcher computes for the same ray: packet and scalar images, and images shaded ahead or
// as met, are equal pixel for pixel (tested). Equal to the bit where the compiler does not fuse
// multiplies and adds (-ffp-contract=off, as the tests build, or no FMA in the target): a fusion
// made in one path and not in the other moves the last bits, and clang and gcc fuse by default
// where FMA exists.
//
// The ray cache of 8.2 is an option of the scalar marcher: entry k remembers the voxel index and
// voxel of sample k of the previous ray; a ray reads it until its first mismatch and then
// overwrites the rest. (The paper found it gave little; bench_hypertree_render measures it.)

#include "hypertree/depth_colors.hpp"
#include "hypertree/execution.hpp"
#include "hypertree/render/brick_walk.hpp"
#include "hypertree/render/light_sweep.hpp"
#include "hypertree/render/march_options.hpp"
#include "hypertree/render/shade_memo.hpp"
#include "hypertree/render/shadow_ray.hpp"
#include "hypertree/render/tree_shape.hpp"
#include "hypertree/render/voxel_bricks.hpp"
#include "hypertree/render/voxel_shading.hpp"
#include "krs/core/lanes.hpp"
#include "krs/trace/ray.hpp"

#include <algorithm>
#include <array>
#include <bit>
#include <cmath>
#include <span>
#include <vector>

namespace hypertree {

// The front-to-back sums of one ray: premultiplied color and the remaining transmittance.
template <class T>
struct march_result {
    T r = T(0.0f), g = T(0.0f), b = T(0.0f);
    T transmittance = T(1.0f);
    T lookups = T(0.0f); // store lookups made (primary and shadow)
    T probes = T(0.0f);  // the primary ray's samples probed (brick walk visits: lookups and skips)
};

// A ray cache for the scalar marcher (8.2): one per thread, reused ray after ray.
struct ray_cache {
    std::vector<voxel_index> index;
    std::vector<voxel> value;
    std::size_t hits = 0, misses = 0;
};

// What a thread brings to a march: its caches, each optional. `shading` may be shared by all
// threads of a render (make it with volume_marcher::new_shade_memo()).
struct march_context {
    ray_cache* rays = nullptr; // scalar marcher only
    shade_memo* shading = nullptr;
    // Flat shading (voxel_shading::flat) marches in step, gathering colors by level
    // (march_in_step); true takes the per-lane march instead (march_shading_as_met), the
    // reference that tests and benchmarks compare with. The same pixels either way.
    bool shade_each_sample = false;
};

class volume_marcher {
public:
    // Validates the options for this tree (march_options::validate) before copying the store.
    // `skipping` picks the brick walk's empty space (brick_walk::skips): the same pixels either way.
    // `parallel_for` runs the light sweep (light_sweep.hpp, shadow_method::sweep) on the caller's
    // threads (empty: on this one); the table is the same, bit for bit, whatever the threads.
    template <voxel_store S>
    volume_marcher(const S& store, tree_shape shape, depth_colors colors, march_options options = {},
                   const parallel_for_hook& parallel_for = {}, brick_walk::skips skipping = brick_walk::skips::every_level)
        : volume_(validated(store.volume(), shape, options)), options_(std::move(options)), shape_(std::move(shape)),
          bricks_(store), walk_(volume_, options_.step_factor * float(volume_.smallest_voxel_side()), skipping),
          shading_(options_, shape_, colors)
    {
        // (At least one entry: lanes with no voxel read entry 0, even in an empty tree.)
        alpha_at_.resize(std::max<std::size_t>(1, bricks_.brick_count() * voxel_bricks::brick_voxels));
        for (std::size_t place = 0; place < bricks_.brick_count() * voxel_bricks::brick_voxels; ++place)
            alpha_at_[place] = shading_.opacity()[bricks_.at_place(place).density];
        box_lo_ = krs::vec3f(shape_.box.lo);
        box_hi_ = krs::vec3f(shape_.box.hi);
        // (A center's coordinate on an axis depends on the cell's coordinate on that axis only.)
        for (int x = 0; x < bricks_.grid()[0]; ++x) centers_[0].push_back(center_of(volume_.index(x, 0, 0)).x);
        for (int y = 0; y < bricks_.grid()[1]; ++y) centers_[1].push_back(center_of(volume_.index(0, y, 0)).y);
        for (int z = 0; z < bricks_.grid()[2]; ++z) centers_[2].push_back(center_of(volume_.index(0, 0, z)).z);
        if (options_.shadows && options_.shadow_by == march_options::shadow_method::sweep && !shading_.light_directions().empty())
            swept_ = make_sweep(parallel_for);
    }

    const march_options& options() const { return options_; }
    const hypervolume& volume() const { return volume_; }
    const tree_shape& shape() const { return shape_; }
    const voxel_shading& shading() const { return shading_; }
    float step() const { return walk_.step(); }
    // The marcher's copy of the store's voxels (voxel_bricks.hpp), which every ray reads.
    const voxel_bricks& bricks() const { return bricks_; }
    // What the marcher holds besides the store: its brick copy and the bricks' opacities.
    std::size_t memory_bytes() const { return bricks_.memory_bytes() + alpha_at_.capacity() * sizeof(float) + swept_.memory_bytes(); }
    // The swept transmittances (light_sweep.hpp), made with the marcher under shadow_method::sweep;
    // empty under rays.
    const light_sweep& sweep() const { return swept_; }
    // The sweep's table as the constructor makes it (light_sweep.hpp, sweep_in_two_passes): every
    // voxel's ray to its cut on the caller's threads (`parallel_for`; empty: this thread), then the
    // chains of cuts. The same table, bit for bit, whatever the threads.
    light_sweep make_sweep(const parallel_for_hook& parallel_for = {}) const
    {
        return sweep_in_two_passes(sweep_source{bricks_, shadow_reads_of(), shading_.light_directions(), centers_}, parallel_for);
    }
    // The sweep's table as it was first made, level by level in light order on one thread
    // (light_sweep.hpp, sweep_in_light_order): the reference make_sweep is tested against.
    light_sweep make_sweep_in_light_order() const
    {
        return sweep_in_light_order(sweep_source{bricks_, shadow_reads_of(), shading_.light_directions(), centers_});
    }
    // An empty shading memo sized for this marcher (its voxel count and lights), for one render:
    // all its threads may share it.
    shade_memo new_shade_memo() const { return shade_memo(bricks_.voxel_count(), 3 + shading_.light_directions().size()); }
    // Whether a memo was made for this marcher, as new_shade_memo() makes it (its voxel count
    // and lights): only such a memo is read or written.
    bool made_for(const shade_memo& memo) const
    {
        return memo.slots() == bricks_.voxel_count() && memo.stride() == 3 + shading_.light_directions().size();
    }
    // ... and rays may gather from it: it has an entry (lanes with no voxel read entry 0) and
    // fewer than 2^31 floats.
    bool fits(const shade_memo& memo) const
    {
        return made_for(memo) && memo.slots() > 0 && memo.slots() * memo.stride() < (std::size_t(1) << 31);
    }

    // Whether march_packets marches flat shading in step (colors by level, no shading memo read):
    // not with a ray cache (scalar), a render-time displacement, or the per-lane reference asked.
    bool marches_flat_in_step(bool ray_cache, bool shade_each_sample) const
    {
        return shading_.flat() && !ray_cache && !shade_each_sample && !options_.displacement.enabled();
    }

    // Marches the rays of the lanes.
    template <class T>
    march_result<T> march(const krs::ray<T>& ray, march_context context = {}) const
    {
        return march_packets<T, 1>({ray}, context)[0];
    }
    // Marches K packets of rays: under flat shading (voxel_shading::flat: no lights, no ambient
    // falloff), or through a complete memo with nothing left to compute per sample, the K packets
    // march in turn within one loop, their lanes in step (march_in_step); otherwise each lane of
    // each packet looks up and shades its samples on its own (march_shading_as_met). Both give
    // the same pixels (tested).
    template <class T, std::size_t K>
    std::array<march_result<T>, K> march_packets(const std::array<krs::ray<T>, K>& rays, march_context context = {}) const
    {
        // (Displaced samples read voxels off the ray's own path: only the per-lane march displaces.)
        const bool cached = std::floating_point<T> && context.rays;
        if (marches_flat_in_step(cached, context.shade_each_sample)) return march_in_step<T, K, true>(rays, nullptr);
        const bool per_sample = !options_.shade_per_voxel || options_.specular > 0 || cached || options_.displacement.enabled();
        if (!per_sample && context.shading && context.shading->complete() && fits(*context.shading))
            return march_in_step<T, K, false>(rays, context.shading);
        std::array<march_result<T>, K> out;
        for (std::size_t k = 0; k < K; ++k) out[k] = march_shading_as_met(rays[k], context);
        return out;
    }

    // Transmittance from p toward the light along direction l (unit): p's shadow ray
    // (shadow_ray.hpp: within the tree's box, from one step out, with the primary rays' empty-space
    // skipping and early exit). One template for one point (T = float) and for a packet of
    // points, one per lane, toward the same light: the shading pass marches the shadow rays of
    // voxels a packet at a time (shade_bricks), each lane computing exactly what the scalar march
    // computes for its point. `lookups` counts each lane's voxel reads.
    template <class T>
    T shadow_transmittance(const krs::vec3<T>& p, const krs::vec3f& l, T& lookups, krs::mask_t<T> running = krs::mask_t<T>(true)) const
    {
        std::array<T, 1> looked{lookups};
        const T transmittance = shadow_transmittances<T, 1>({p}, l, looked, {running})[0];
        lookups = looked[0];
        return transmittance;
    }
    // The same for K packets at once, marched in turn within one loop: a sample's place comes
    // from gathers that depend on the previous sample's, so one packet alone waits on memory at
    // every step; K independent packets give the core other work meanwhile.
    //
    // With `swept` (light l's column of the sweep, light_sweep.hpp) the ray is cut at its first
    // sample, from step `sweep_near_steps` on, in a non-empty voxel other than p's own, and
    // completed by that voxel's swept transmittance: the step the sweep's own rays take
    // (shadow_ray::step), so a voxel's center marched here gives its table entry. Without, it is
    // the full shadow ray.
    template <class T, std::size_t K>
    std::array<T, K> shadow_transmittances(const std::array<krs::vec3<T>, K>& p, const krs::vec3f& l, std::array<T, K>& lookups,
                                           std::array<krs::mask_t<T>, K> running, const float* swept = nullptr) const
    {
        const shadow_ray<T> ray(shadow_reads_of(), l);
        std::array<typename shadow_ray<T>::lanes, K> s;
        for (std::size_t k = 0; k < K; ++k) {
            s[k].p = p[k], s[k].running = running[k];
            ray.start(s[k]);
            if (swept) s[k].own = ray.origin_place(s[k]);
        }
        for (bool marching = true; marching;) {
            marching = false;
            for (std::size_t k = 0; k < K; ++k) {
                krs::mask_t<T> cut;
                krs::index_lanes<T> place;
                if (!ray.step(s[k], &lookups[k], swept != nullptr, cut, place)) continue;
                marching = true;
                if (swept) ray.complete(s[k], cut, place, swept);
            }
        }
        std::array<T, K> transmittance;
        for (std::size_t k = 0; k < K; ++k) transmittance[k] = s[k].transmittance;
        return transmittance;
    }

    // Shades the non-empty voxels of bricks [first, last) into `memo` (shade_per_voxel), their
    // shadow rays marched four packets of voxels at a time, and returns the lookups made. What it
    // stores equals what shade() computes for the same voxel (tested), so a render may shade its
    // voxels ahead of its rays (render_settings::shade_ahead) or as its rays meet them.
    template <class T = krs::packet_f>
    std::uint64_t shade_bricks(shade_memo& memo, std::size_t first, std::size_t last) const
    {
        constexpr std::size_t packets = std::floating_point<T> ? 1 : 4, w = lanes<T>, n = packets * w;
        const std::size_t lights = shading_.light_directions().size();
        if (!made_for(memo)) throw krs::invalid_parameter("shade_bricks.memo", "must come from this marcher's new_shade_memo()");
        std::array<float, n> x{}, y{}, z{};
        std::array<std::uint32_t, n> slots{};
        std::array<std::uint8_t, n> levels{};
        std::size_t count = 0;
        double lookups = 0;
        const auto shade_packet = [&] {
            for (std::size_t k = count; k < n; ++k) x[k] = x[0], y[k] = y[0], z[k] = z[0]; // idle lanes: a copy of lane 0
            std::array<krs::vec3<T>, packets> p;
            std::array<krs::mask_t<T>, packets> running;
            for (std::size_t k = 0; k < packets; ++k) {
                const auto segment = [&](const std::array<float, n>& a) {
                    std::array<float, w> lanes_k;
                    std::copy_n(a.begin() + std::ptrdiff_t(k * w), w, lanes_k.begin());
                    return load<T>(lanes_k);
                };
                p[k] = {segment(x), segment(y), segment(z)};
                const std::size_t live = std::min(w, count > k * w ? count - k * w : 0);
                running[k] = krs::mask_from_bits<T>(live == 64 ? ~std::uint64_t(0) : (std::uint64_t(1) << live) - 1);
            }
            // The lanes' voxel slots (idle lanes keep an earlier voxel's, or slot 0 in the first batch:
            // a valid slot, not used).
            std::array<krs::index_lanes<T>, packets> at;
            for (std::size_t k = 0; k < packets; ++k) {
                std::array<std::int32_t, w> lanes_k;
                for (std::size_t lane = 0; lane < w; ++lane) lanes_k[lane] = std::int32_t(slots[k * w + lane]);
                if constexpr (std::floating_point<T>) at[k] = lanes_k[0];
                else at[k] = krs::index_lanes<T>::load_unaligned(lanes_k.data());
            }
            std::array<std::array<float, n>, march_options::max_lights> shadows{};
            for (std::size_t i = 0; i < lights; ++i) {
                std::array<T, packets> looked;
                looked.fill(T(0.0f));
                const std::array<T, packets> t = shadows_toward<T, packets>(i, p, &at, looked, running);
                for (std::size_t k = 0; k < packets; ++k) {
                    const auto transmittance = krs::lanes_of(t[k]), per_lane = krs::lanes_of(looked[k]);
                    std::copy(transmittance.begin(), transmittance.end(), shadows[i].begin() + std::ptrdiff_t(k * w));
                    for (std::size_t lane = 0; lane < w && k * w + lane < count; ++lane) lookups += double(per_lane[lane]);
                }
            }
            // The structure-flow normals, a packet of doubles at a time.
            using D = std::conditional_t<std::floating_point<T>, double, krs::packet_d>;
            constexpr std::size_t m = krs::lane_count<D>;
            std::array<krs::vec3d, n> normal{};
            for (std::size_t first = 0; lights > 0 && first < count; first += m) {
                std::array<double, m> nx{}, ny{}, nz{};
                for (std::size_t k = 0; k < m; ++k) {
                    const std::size_t lane = std::min(first + k, count - 1);
                    nx[k] = double(x[lane]), ny[k] = double(y[lane]), nz[k] = double(z[lane]);
                }
                const krs::vec3<D> nd = shape_.normal_at(krs::vec3<D>{load<D>(nx), load<D>(ny), load<D>(nz)}, options_.normals_by);
                const auto ox = krs::lanes_of(nd.x), oy = krs::lanes_of(nd.y), oz = krs::lanes_of(nd.z);
                for (std::size_t k = 0; k < m && first + k < count; ++k) normal[first + k] = {ox[k], oy[k], oz[k]};
            }
            std::array<float, 3 + march_options::max_lights> entry{};
            for (std::size_t k = 0; k < count; ++k) {
                for (std::size_t i = 0; i < lights; ++i) entry[3 + i] = shadows[i][k];
                const rgb c = shading_.lit({x[k], y[k], z[k]}, levels[k], entry.data() + 3, normal[k]);
                entry[0] = c.r, entry[1] = c.g, entry[2] = c.b;
                memo.store(slots[k], entry.data());
            }
            count = 0;
        };
        for (std::size_t b = first; b < last && b < bricks_.brick_count(); ++b) {
            for (std::uint64_t mask = bricks_.mask(b); mask != 0; mask &= mask - 1) {
                const std::size_t offset = std::size_t(std::countr_zero(mask)), place = b * voxel_bricks::brick_voxels + offset;
                const std::array<int, 3> c = voxel_bricks::cell_at(bricks_.origin(b), offset);
                // (center_of's values, from the per-axis tables: no division per voxel.)
                const krs::vec3f q{centers_[0][std::size_t(c[0])], centers_[1][std::size_t(c[1])], centers_[2][std::size_t(c[2])]};
                x[count] = q.x, y[count] = q.y, z[count] = q.z;
                slots[count] = bricks_.slot(place);
                levels[count] = bricks_.at_place(place).level;
                if (++count == n) shade_packet();
            }
        }
        if (count > 0) shade_packet();
        return std::uint64_t(lookups);
    }

private:
    static const hypervolume& validated(const hypervolume& volume, const tree_shape& shape, const march_options& options)
    {
        options.validate(volume, shape.box);
        return volume;
    }

    // What the shadow rays' samples read (shadow_ray.hpp), made where they are marched (its
    // pointers are into this marcher, which may have moved since it was made).
    shadow_reads shadow_reads_of() const
    {
        return {walk_, bricks_.view_of(), &bounds_, alpha_at_.data(), bricks_.slots(), box_lo_, box_hi_, options_.min_transmittance,
                float(options_.sweep_near_steps)};
    }

    // The brick walk's probe, and with a secondary bound (bounds_by) its test on top.
    template <class T>
    [[gnu::always_inline]] brick_walk::probe_result<T> probe(const brick_walk& walk, const voxel_bricks::view& view, const krs::vec3<T>& p,
                                                             const T (&slope)[3], const krs::mask_t<T>& running, const T& margin,
                                                             const brick_walk::exit_faces& faces) const
    {
        return walk.probe(view, p, slope, running, margin, faces, bounds_);
    }

    // The march of rays whose lanes march in step, gathering what each sample needs: through
    // voxels all shaded ahead (march_packets checks that the memo is complete and fits), each
    // lane's place in the bricks, its opacity and its voxel's lit color from the memo; under flat
    // shading (`flat`, no memo), the color from the flat table by the voxel's level byte (from a
    // 3 KB table, instead of shading each sample lane by lane). Either way the
    // accumulation of march_shading_as_met, the same operations in the same order. K packets
    // march in turn within one loop: a sample's place comes from gathers that depend on the
    // previous sample's, so one packet alone waits on memory at every step, and K independent
    // ones give the core other work.
    template <class T, std::size_t K, bool flat>
    std::array<march_result<T>, K> march_in_step(const std::array<krs::ray<T>, K>& rays, const shade_memo* memo) const
    {
        using I = krs::index_lanes<T>;
        using krs::any, krs::select;
        const brick_walk walk = walk_;
        const voxel_bricks::view view = bricks_.view_of();
        const T ds(walk_.step()), half(0.5f), zero(0.0f), one(1.0f), least(options_.min_transmittance);
        const float* alpha_at = alpha_at_.data();
        const std::int32_t* slot_at = bricks_.slots();
        // Colors at entry, entry + 1, entry + 2: the memo's at slot x stride, or flat ones at level x 3.
        const float* colors = flat ? shading_.flat_colors().data() : memo->values();
        const I stride(flat ? 0 : std::int32_t(memo->stride()));
        // (levels: 64 bytes per brick, cache-line aligned, as gather_byte requires.)
        const std::uint8_t* level_at = bricks_.levels().data();
        std::array<march_result<T>, K> out;
        std::array<T, K> t0, t1, k;
        std::array<krs::mask_t<T>, K> active;
        T slope[K][3];
        std::array<T, K> margin0;
        std::array<brick_walk::exit_faces, K> faces;
        for (std::size_t r = 0; r < K; ++r) {
            margin0[r] = walk_.margin_at_origin(rays[r].origin);
            enter_box(rays[r], t0[r], t1[r]);
            k[r] = zero;
            active[r] = t0[r] + half * ds < t1[r];
            walk_.slopes_of(rays[r].direction, slope[r]);
            faces[r] = brick_walk::faces_of(slope[r]);
        }
        for (bool marching = true; marching;) {
            marching = false;
            for (std::size_t r = 0; r < K; ++r) {
                if (!any(active[r])) continue;
                marching = true;
                march_result<T>& o = out[r];
                const T t = t0[r] + (k[r] + half) * ds;
                const krs::vec3<T> p = rays[r].origin + rays[r].direction * t;
                const brick_walk::probe_result<T> found = probe(walk, view, p, slope[r], active[r], walk.skip_margin(margin0[r], t), faces[r]);
                // A sample of opacity 0 in every lane adds nothing (composite leaves the sums as
                // they are, bit for bit: the lit colors are finite), so its gathers are left out:
                // all five where no lane looks (empty space, where the walk alone runs), the
                // four of the colors where the lanes that look find empty voxels.
                // (The slots are gathered beside the opacities, before the test: after it, they
                // waited for the opacities' gather too.)
                if (any(found.looks)) {
                    const I place = krs::index_max(found.place, I(0));
                    const T a = select(found.looks, krs::gather(alpha_at, place), zero);
                    o.lookups = o.lookups + select(found.looks, one, zero);
                    I entry;
                    if constexpr (flat) entry = krs::gather_byte(level_at, place) * I(3);
                    else entry = krs::gather(slot_at, place) * stride;
                    if (any(a > zero))
                        composite(o, a, krs::gather(colors, entry), krs::gather(colors, entry + I(1)), krs::gather(colors, entry + I(2)));
                }
                o.probes = o.probes + select(active[r], one, zero);
                k[r] = k[r] + found.advance;
                active[r] = active[r] & (t0[r] + (k[r] + half) * ds < t1[r]) & (o.transmittance >= least);
            }
        }
        return out;
    }

    // One sample composited front to back: its color weighted by its opacity and the light still
    // passing, then that light dimmed. Both marches step through this, so their pixels agree.
    template <class T>
    static void composite(march_result<T>& o, const T& alpha, const T& r, const T& g, const T& b)
    {
        o.r = o.r + o.transmittance * alpha * r;
        o.g = o.g + o.transmittance * alpha * g;
        o.b = o.b + o.transmittance * alpha * b;
        o.transmittance = o.transmittance * (T(1.0f) - alpha);
    }

    // The march of rays that shade as they go: lane by lane, each sample is looked up (through
    // the ray cache if there is one) and shaded (from the memo, or computed and recorded there).
    template <class T>
    march_result<T> march_shading_as_met(const krs::ray<T>& ray, march_context context) const
    {
        ray_cache* cache = std::floating_point<T> ? context.rays : nullptr;
        const brick_walk walk = walk_;
        const voxel_bricks::view view = bricks_.view_of();
        using krs::any; // (unqualified below: packets take xsimd's, found by argument)
        march_result<T> out;
        T t0, t1;
        enter_box(ray, t0, t1, options_.displacement.enabled());
        const T ds(walk_.step()), half(0.5f);
        // Sample k sits at t0 + (k + 1/2) ds, computed from k (not accumulated), so skipping the
        // empty samples of an empty brick lands exactly where stepping would.
        T k(0.0f);
        auto active = t0 + half * ds < t1;
        bool cache_valid = cache != nullptr;
        if constexpr (std::floating_point<T>) {
            if (cache && cache->index.size() < max_samples()) cache->index.resize(max_samples(), ~voxel_index(0)), cache->value.resize(max_samples());
        }
        const auto dx = krs::lanes_of(ray.direction.x), dy = krs::lanes_of(ray.direction.y), dz = krs::lanes_of(ray.direction.z);
        const bool displaced = options_.displacement.enabled();
        float slope[lanes<T>][3];
        std::array<brick_walk::exit_faces, lanes<T>> faces;
        const T margin0 = walk_.margin_at_origin(ray.origin);
        for (std::size_t i = 0; i < lanes<T>; ++i) walk_.slopes_of(krs::vec3f{dx[i], dy[i], dz[i]}, slope[i]), faces[i] = brick_walk::faces_of(slope[i]);
        while (any(active)) {
            const T t = t0 + (k + half) * ds;
            // (Render-time noise: the sample's displaced position, all lanes at once.)
            const krs::vec3<T> p = displaced ? options_.displacement.displaced(ray.origin + ray.direction * t) : ray.origin + ray.direction * t;
            // Per lane: the voxel, its opacity for one step, and its shaded color if it is not
            // empty; or, in an empty brick, how many samples to skip.
            std::array<float, lanes<T>> alpha{}, r{}, g{}, b{}, lookups{}, advance{};
            // The lanes' inputs, spilled once per sample rather than once per lane.
            const auto px = krs::lanes_of(p.x), py = krs::lanes_of(p.y), pz = krs::lanes_of(p.z), ks = krs::lanes_of(k);
            const auto margin = krs::lanes_of(walk_.skip_margin(margin0, t));
            const std::uint64_t running = krs::mask_bits<T>(active);
            for (std::size_t i = 0; i < lanes<T>; ++i) {
                advance[i] = 1.0f;
                if (!((running >> i) & 1u)) continue;
                const krs::vec3f pi{px[i], py[i], pz[i]};
                const krs::vec3f di{dx[i], dy[i], dz[i]};
                const brick_walk::probe_result<float> found = probe<float>(walk, view, pi, slope[i], true, margin[i], faces[i]);
                if (!found.looks) {
                    advance[i] = displaced ? 1.0f : found.advance; // no skips off the ray's path
                    continue;
                }
                const std::size_t place = std::size_t(found.place);
                const voxel_index index = voxel_index(found.cell[0]) +
                                          voxel_index(walk_.grid()[0]) * (voxel_index(found.cell[1]) + voxel_index(walk_.grid()[1]) * voxel_index(found.cell[2]));
                voxel v;
                if constexpr (std::floating_point<T>) {
                    v = cache ? fetch_cached(index, place, std::size_t(ks[i]), *cache, cache_valid, lookups[i])
                              : (++lookups[i], bricks_.at_place(place));
                } else {
                    v = (++lookups[i], bricks_.at_place(place));
                }
                if (v.density == 0) continue;
                alpha[i] = shading_.opacity()[v.density];
                const rgb c = shade(pi, index, place, v.level, -di, context.shading, lookups[i]);
                r[i] = c.r, g[i] = c.g, b[i] = c.b;
            }
            composite(out, load<T>(alpha), load<T>(r), load<T>(g), load<T>(b));
            out.lookups = out.lookups + load<T>(lookups);
            {
                using krs::select; // (packets take xsimd's, found by argument)
                out.probes = out.probes + select(active, T(1.0f), T(0.0f));
            }
            k = k + load<T>(advance);
            active = active & (t0 + (k + half) * ds < t1) & (out.transmittance >= T(options_.min_transmittance));
        }
        return out;
    }

    // The most samples a ray can take through the box (the paper's cache size q).
    std::size_t max_samples() const
    {
        const krs::vec3f e = box_hi_ - box_lo_ + options_.displacement.amplitude * 2.0f; // enter_box's widened box
        return std::size_t(std::ceil(krs::length(e) / walk_.step())) + 2;
    }

    template <class T>
    static constexpr std::size_t lanes = krs::lane_count<T>;

    template <class T>
    static T load(const std::array<krs::scalar_t<T>, lanes<T>>& a)
    {
        if constexpr (std::floating_point<T>)
            return a[0];
        else
            return T::load_unaligned(a.data());
    }

    // The slab test against the tree's box (brick_walk.hpp, enter_box); t0 >= 0. Rays that miss
    // get t0 >= t1. Primary rays with render-time noise: widened by its amplitude, so samples
    // whose displaced positions fall in the box are taken (march_options.hpp).
    template <class T>
    void enter_box(const krs::ray<T>& ray, T& t0, T& t1, bool displaced = false) const
    {
        const krs::vec3f pad = displaced ? options_.displacement.amplitude : krs::vec3f{0.0f, 0.0f, 0.0f};
        hypertree::enter_box(ray, box_lo_ - pad, box_hi_ + pad, t0, t1);
    }

    voxel fetch_cached(voxel_index index, std::size_t place, std::size_t k, ray_cache& cache, bool& valid, float& lookups) const
    {
        if (k < cache.index.size()) {
            if (valid && cache.index[k] == index) {
                ++cache.hits;
                return cache.value[k];
            }
            valid = false; // past the first mismatch the rest of the ray overwrites the cache
            ++cache.misses;
            ++lookups;
            const voxel v = bricks_.at_place(place);
            cache.index[k] = index, cache.value[k] = v;
            return v;
        }
        ++lookups;
        return bricks_.at_place(place);
    }

    krs::vec3f center_of(voxel_index index) const
    {
        const krs::vec3d c = volume_.voxel_center(index);
        return {float(c.x), float(c.y), float(c.z)};
    }

    // The lit color of a sample (voxel_shading.hpp). With shade_per_voxel the shading point is the
    // voxel's center, so all but the view-dependent specular term is a pure function of the voxel
    // and is memoized by its slot (voxel_bricks.hpp) in the render's table.
    rgb shade(const krs::vec3f& p, voxel_index index, std::size_t place, int level, const krs::vec3f& view, shade_memo* memo,
              float& lookups) const
    {
        // The shading point, computed only where needed: a memo hit needs none (unless specular).
        const auto point = [&] { return options_.shade_per_voxel ? center_of(index) : p; };
        std::array<float, 3 + march_options::max_lights> entry{}; // lit rgb, then one shadow per light
        const float* shadows = entry.data() + 3;
        // A memo made for another marcher is not used.
        if (options_.shade_per_voxel && memo && made_for(*memo)) {
            const std::uint32_t slot = bricks_.slot(place);
            if (!memo->find(slot, entry.data())) {
                const rgb lit = light_at(point(), level, entry.data() + 3, lookups, std::int64_t(slot));
                entry[0] = lit.r, entry[1] = lit.g, entry[2] = lit.b;
                memo->store(slot, entry.data());
            }
        } else {
            const rgb lit = light_at(point(), level, entry.data() + 3, lookups,
                                     options_.shade_per_voxel ? std::int64_t(bricks_.slot(place)) : std::int64_t(-1));
            entry[0] = lit.r, entry[1] = lit.g, entry[2] = lit.b;
        }
        const rgb lit{entry[0], entry[1], entry[2]};
        if (!(options_.specular > 0)) return lit;
        const krs::vec3d nd = shape_.normal_at(krs::vec3d(point()), options_.normals_by);
        if (nd.x == 0 && nd.y == 0 && nd.z == 0) return lit;
        return shading_.with_specular(lit, {float(nd.x), float(nd.y), float(nd.z)}, view, shadows);
    }

    // The lit color at shading point q; writes each light's shadow transmittance to `shadows`.
    // `slot` is the voxel's when q is its center (shade_per_voxel), else -1: with the sweep, a
    // center reads its swept shadow, another point marches to its cut (shadows_toward).
    rgb light_at(const krs::vec3f& q, int level, float* shadows, float& lookups, std::int64_t slot) const
    {
        const std::array<std::int32_t, 1> at{std::int32_t(slot)};
        for (std::size_t i = 0; i < shading_.light_directions().size(); ++i) {
            std::array<float, 1> looked{lookups};
            shadows[i] = shadows_toward<float, 1>(i, {q}, slot >= 0 ? &at : nullptr, looked, {true})[0];
            lookups = looked[0];
        }
        return lit(q, level, shadows);
    }

    // Light i's shadow transmittance at the lanes' points, by the one rule of both shading paths
    // (light_at: one point; shade_bricks: packets of voxel centers): 1 without shadows; under the
    // sweep, at voxel centers (`slots`: their voxels' slots) the table's entry as it is, and at
    // other points (no slots) the point's ray to its cut, completed by the table; under rays, the
    // full shadow ray. `lookups` counts each lane's voxel reads.
    template <class T, std::size_t K>
    std::array<T, K> shadows_toward(std::size_t i, const std::array<krs::vec3<T>, K>& p, const std::array<krs::index_lanes<T>, K>* slots,
                                    std::array<T, K>& lookups, const std::array<krs::mask_t<T>, K>& running) const
    {
        const krs::vec3f& l = shading_.light_directions()[i];
        std::array<T, K> out;
        if (!options_.shadows) out.fill(T(1.0f));
        else if (swept_.empty()) out = shadow_transmittances<T, K>(p, l, lookups, running);
        else if (slots) // swept when the marcher was made: read, not marched
            for (std::size_t k = 0; k < K; ++k) out[k] = krs::gather(swept_.toward(i), (*slots)[k]);
        else out = shadow_transmittances<T, K>(p, l, lookups, running, swept_.toward(i));
        return out;
    }

    // The lit color at q given each light's shadow transmittance, with the structure-flow normal
    // at q (computed only when there is a light to use it).
    rgb lit(const krs::vec3f& q, int level, const float* shadows) const
    {
        return shading_.lit(q, level, shadows, shading_.light_directions().empty() ? krs::vec3d{} : shape_.normal_at(krs::vec3d(q), options_.normals_by));
    }

    hypervolume volume_;
    march_options options_;
    tree_shape shape_;
    bound_test bounds_ = bound_test::of(shape_, options_.bounds_by); // (after shape_ and options_)
    voxel_bricks bricks_;
    brick_walk walk_;
    voxel_shading shading_;
    krs::vec3f box_lo_{}, box_hi_{};
    std::vector<float> alpha_at_; // per place of the bricks: its voxel's opacity for one step
    light_sweep swept_;           // per light and slot: the swept transmittance (shadow_method::sweep)
    std::array<std::vector<float>, 3> centers_; // per axis and cell coordinate: center_of's coordinate (the sweep's ray origins)
};

} // namespace hypertree

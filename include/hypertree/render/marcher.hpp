#pragma once
// The hypertree raymarcher (paper section 8): front-to-back accumulation along each ray with
// self-shadowing, one template for scalar rays (T = float) and SIMD packets of rays
// (T = krs::packet_f, one ray per lane).
//
// Along a ray clipped to the tree's box, samples sit at t_k = t_0 + (k + 1/2) ds, ds = step factor
// x the smallest voxel side ("a quality choice", 8.2). A sample's voxel density mu (density/255)
// becomes opacity alpha = 1 - (1 - mu)^(k ds / side) (8.1, with the normalization k per voxel
// side so k = 1 makes a voxel of density mu, crossed along one side, exactly mu opaque). It is
// shaded, multiplied by alpha and by the transmittance so far, and added; the march ends when the
// transmittance falls below `min_transmittance` (full opacity) or the ray leaves the box.
// Empty space is skipped by occupancy bricks (4^3 and 16^3 voxels): a sample in an empty brick is
// not looked up, and the ray jumps by whole steps to the brick's exit, so it takes exactly the
// samples it would have stepped through. Optionally, samples outside every secondary bounding
// sphere are not looked up either (tree_shape.hpp: the spheres hold every non-empty cell).
// Neither changes a pixel, only the work.
//
// Shading (8.3): ambient light attenuated toward the interior (Reeves' exponential falloff with
// the depth below the crown's bounding sphere), Lambert diffuse and Blinn-Phong specular with the
// procedural normals of the structure flow, each light's term attenuated by the opacity a shadow
// ray accumulates toward it (same step, same early exit). The base color comes from the voxel's
// depth (transfer.hpp). By default a sample is shaded at its voxel's center (shade_per_voxel), so
// a voxel's shading is computed about once per render, whatever the thread count.
//
// One template: the loop over samples, the masks and the accumulation are written once over T.
// What each lane looks up (store access, sphere test, shading of a sample) runs per lane in scalar
// code, so a packet's lanes compute exactly what the scalar marcher computes for the same ray:
// packet and scalar images are equal pixel for pixel (tested).
//
// The ray cache of 8.2 is an option of the scalar marcher: entry k remembers the voxel index and
// voxel of sample k of the previous ray; a ray reads it until its first mismatch and then
// overwrites the rest. (The paper found it gave little; bench_hypertree_render measures it.)

#include "hypertree/render/shade_memo.hpp"
#include "hypertree/render/transfer.hpp"
#include "hypertree/render/tree_shape.hpp"
#include "krs/core/lanes.hpp"
#include "krs/trace/ray.hpp"

#include <algorithm>
#include <array>
#include <cmath>
#include <vector>

namespace hypertree {

struct directional_light {
    krs::vec3f direction{0.4f, 0.8f, 0.45f}; // toward the light; normalized by the marcher
    rgb color{1.0f, 0.97f, 0.9f};
};

struct march_options {
    float step_factor = 1.0f;           // ds = step_factor * smallest voxel side
    float density_scale = 1.0f;         // k of alpha = 1 - (1 - mu)^(k ds / side)
    float min_transmittance = 1.0f / 256.0f;
    // Skip lookups outside the secondary bounding spheres (8.2). Off by default: the brick
    // occupancy bits already skip empty space, and testing every sphere at every sample then costs
    // more than it saves (bench_hypertree_render: ~20% slower with them on tree A). The paper saw
    // the same spread, "from 40% faster to twice slower".
    bool use_spheres = false;
    bool shadows = true;
    // Shade at the voxel's center instead of the sample (the voxel is a homogeneous region, as in
    // section 9), so one voxel's ambient, normal and shadow rays serve every sample in it
    // (memoized for all threads of a render: see shade_memo.hpp). Off: everything per sample, shadow rays included:
    // the reference the benchmark measures the difference against.
    bool shade_per_voxel = true;
    float ambient = 0.3f;
    float ambient_falloff = 2.5f;       // per crown radius of depth below the crown sphere
    float diffuse = 0.85f;
    float specular = 0.0f;
    float shininess = 24.0f;
    std::vector<directional_light> lights{directional_light{}};
};

// The front-to-back sums of one ray: premultiplied color and the remaining transmittance.
template <class T>
struct march_result {
    T r = T(0.0f), g = T(0.0f), b = T(0.0f);
    T transmittance = T(1.0f);
    T lookups = T(0.0f); // store lookups made (primary and shadow)
};

// A ray cache for the scalar marcher (8.2): one per thread, reused ray after ray.
struct ray_cache {
    std::vector<voxel_index> index;
    std::vector<voxel> value;
    std::size_t hits = 0, misses = 0;
};

// Per-voxel shading remembered by one thread: a direct-mapped table (slot = hash of the voxel
// index) in plain memory, sized by the marcher on first use. It sits in front of the render's
// shared memo (shade_memo.hpp): a thread meets the same voxels again and again along its rows,
// and its own table answers those without touching memory another core writes.
struct thread_shade_memo {
    std::size_t slots = 0;
    std::vector<voxel_index> index;
    std::vector<float> value; // per slot: lit rgb, then one shadow per light
};

// What a thread brings to a march: its caches, each optional. `shared_shading` may be shared by
// all threads of a render (make it with volume_marcher::new_shade_memo()); it is consulted where
// the thread's own `shading` misses.
struct march_context {
    ray_cache* rays = nullptr; // scalar marcher only
    thread_shade_memo* shading = nullptr;
    shade_memo* shared_shading = nullptr;
};

template <voxel_store S>
class volume_marcher {
public:
    volume_marcher(const S& store, tree_shape shape, depth_colors colors, march_options options = {})
        : store_(&store), shape_(std::move(shape)), colors_(std::move(colors)), options_(std::move(options))
    {
        krs::require_positive("march_options.step_factor", options_.step_factor);
        krs::require_positive("march_options.density_scale", options_.density_scale);
        krs::require_non_negative("march_options.min_transmittance", options_.min_transmittance);
        const hypervolume& v = store.volume();
        origin_ = {float(v.origin().x), float(v.origin().y), float(v.origin().z)};
        cells_per_unit_ = {float(v.cells_per_unit().x), float(v.cells_per_unit().y), float(v.cells_per_unit().z)};
        grid_ = {v.grid().x, v.grid().y, v.grid().z};
        side_ = float(v.smallest_voxel_side());
        step_ = options_.step_factor * side_;
        // alpha per density byte for one step: (1 - mu)^(k ds / side).
        const double exponent = double(options_.density_scale) * double(options_.step_factor);
        for (int d = 0; d < 256; ++d) alpha_[d] = d == 255 ? 1.0f : float(1.0 - std::pow(1.0 - d / 255.0, exponent));
        for (int l = 0; l < 256; ++l) level_color_[l] = colors_.at(l);
        // Empty-space skipping: one bit per brick of 4^3 voxels, and per brick of 16^3, that holds
        // a non-empty voxel. A sample in an empty brick needs no store lookup, and a ray skips the
        // rest of the largest empty brick it is in.
        for (occupancy& level : occupancy_) {
            for (int a = 0; a < 3; ++a) level.count[std::size_t(a)] = std::size_t((grid_[a] + level.side() - 1) >> level.shift);
            level.bits.assign((level.count[0] * level.count[1] * level.count[2] + 63) / 64, 0);
        }
        store.for_each([&](voxel_index i, const voxel&) {
            const auto c = v.coordinates(i);
            for (occupancy& level : occupancy_) level.mark(c[0], c[1], c[2]);
        });
        // Room for twice the non-empty voxels (up to 2^20 slots), so few voxels evict each other
        // from the shading memo.
        while (memo_slots_ < 2 * store.nonempty_count() && memo_slots_ < (std::size_t(1) << 20)) memo_slots_ *= 2;
        box_lo_ = {float(shape_.box.lo.x), float(shape_.box.lo.y), float(shape_.box.lo.z)};
        box_hi_ = {float(shape_.box.hi.x), float(shape_.box.hi.y), float(shape_.box.hi.z)};
        if (options_.lights.size() > max_lights)
            throw krs::invalid_parameter("march_options.lights", "may hold at most " + std::to_string(max_lights) + " lights",
                                         std::to_string(options_.lights.size()));
        for (const auto& light : options_.lights) {
            const krs::vec3d d(light.direction);
            const double len = krs::length(d);
            if (!(len > 0)) throw krs::invalid_parameter("march_options.lights.direction", "must be non-zero");
            const krs::vec3d u = d / len;
            light_dirs_.push_back({float(u.x), float(u.y), float(u.z)});
        }
    }

    const march_options& options() const { return options_; }
    // An empty shading memo sized for this marcher (its voxel count and lights), for one render:
    // all its threads may share it.
    shade_memo new_shade_memo() const { return shade_memo(memo_slots_, 3 + light_dirs_.size()); }
    const tree_shape& shape() const { return shape_; }
    float step() const { return step_; }

    // Marches the rays of the lanes.
    template <class T>
    march_result<T> march(const krs::ray<T>& ray, march_context context = {}) const
    {
        ray_cache* cache = std::floating_point<T> ? context.rays : nullptr;
        using krs::any;
        (void)cache;
        march_result<T> out;
        T t0, t1;
        enter_box(ray, t0, t1);
        const T ds(step_), half(0.5f);
        // Sample k sits at t0 + (k + 1/2) ds, computed from k (not accumulated), so skipping the
        // empty samples of an empty brick lands exactly where stepping would.
        T k(0.0f);
        auto active = t0 + half * ds < t1;
        bool cache_valid = cache != nullptr;
        if constexpr (std::floating_point<T>) {
            if (cache && cache->index.size() < max_samples()) cache->index.resize(max_samples(), ~voxel_index(0)), cache->value.resize(max_samples());
        }
        const auto dx = krs::lanes_of(ray.direction.x), dy = krs::lanes_of(ray.direction.y), dz = krs::lanes_of(ray.direction.z);
        const grid_probe grid = probe_view();
        std::array<cell_slopes, lanes<T>> inverse;
        for (std::size_t i = 0; i < lanes<T>; ++i) inverse[i] = slopes({dx[i], dy[i], dz[i]});
        while (any(active)) {
            const T t = t0 + (k + half) * ds;
            const krs::vec3<T> p = ray.origin + ray.direction * t;
            // Per lane: the voxel, its opacity for one step, and its shaded color if it is not
            // empty; or, in an empty brick, how many samples to skip.
            std::array<float, lanes<T>> alpha{}, r{}, g{}, b{}, lookups{}, advance{};
            // The lanes' inputs, spilled once per sample rather than once per lane.
            const auto px = krs::lanes_of(p.x), py = krs::lanes_of(p.y), pz = krs::lanes_of(p.z), ks = krs::lanes_of(k);
            const std::uint64_t running = krs::mask_bits<T>(active);
            for (std::size_t i = 0; i < lanes<T>; ++i) {
                advance[i] = 1.0f;
                if (!((running >> i) & 1u)) continue;
                const krs::vec3f pi{px[i], py[i], pz[i]};
                const krs::vec3f di{dx[i], dy[i], dz[i]};
                const probe_result found = grid(pi, inverse[i]);
                if (!found.occupied()) {
                    advance[i] = float(found.skip);
                    continue;
                }
                const voxel_index index = found.index;
                voxel v;
                if constexpr (std::floating_point<T>) {
                    v = cache ? fetch_cached(index, std::size_t(ks[i]), *cache, cache_valid, lookups[i])
                              : (++lookups[i], store_->at(index));
                } else {
                    v = (++lookups[i], store_->at(index));
                }
                if (v.density == 0) continue;
                alpha[i] = alpha_[v.density];
                const rgb c = shade(pi, index, v.level, -di, context.shading, context.shared_shading, lookups[i]);
                r[i] = c.r, g[i] = c.g, b[i] = c.b;
            }
            const T a = load<T>(alpha);
            out.r = out.r + out.transmittance * a * load<T>(r);
            out.g = out.g + out.transmittance * a * load<T>(g);
            out.b = out.b + out.transmittance * a * load<T>(b);
            out.transmittance = out.transmittance * (T(1.0f) - a);
            out.lookups = out.lookups + load<T>(lookups);
            k = k + load<T>(advance);
            active = active & (t0 + (k + half) * ds < t1) & (out.transmittance >= T(options_.min_transmittance));
        }
        return out;
    }

    // Transmittance from p toward the light along direction l (unit), within the tree's box.
    float shadow_transmittance(const krs::vec3f& p, const krs::vec3f& l, float& lookups) const
    {
        float t0, t1;
        enter_box(krs::ray<float>{p, l}, t0, t1);
        float transmittance = 1.0f;
        // Sample j at base + j ds from j = 1: one step out, so the sample does not shadow itself.
        const float base = std::max(t0, 0.0f);
        const cell_slopes inverse = slopes(l);
        const grid_probe grid = probe_view();
        const S& store = *store_;
        const float step = step_, least = options_.min_transmittance;
        int looked = 0;
        for (int j = 1;; ) {
            const float t = base + float(j) * step;
            if (!(t < t1 && transmittance >= least)) break;
            const krs::vec3f q = p + l * t;
            const probe_result found = grid(q, inverse);
            if (!found.occupied()) {
                j += found.skip;
                continue;
            }
            ++looked;
            transmittance *= 1.0f - alpha_[store.at(found.index).density];
            ++j;
        }
        lookups += float(looked);
        return transmittance;
    }

    // A ray direction d as the t it takes to cross one cell along each axis, 1 / (d * cells per
    // unit), with 0 for an axis the ray does not move along: computed once per ray, so probing
    // an empty brick multiplies instead of dividing.
    struct cell_slopes {
        float inverse[3];
    };
    cell_slopes slopes(const krs::vec3f& d) const
    {
        const float dir[3] = {d.x * cells_per_unit_.x, d.y * cells_per_unit_.y, d.z * cells_per_unit_.z};
        cell_slopes s;
        for (int a = 0; a < 3; ++a) s.inverse[a] = dir[a] != 0 ? 1.0f / dir[a] : 0.0f;
        return s;
    }

    // What a sample at p finds: its voxel index when its 4^3 brick holds voxels (and, with
    // use_spheres, p lies in a part's sphere); otherwise the number of samples along the ray
    // (direction given by its slopes) that certainly lie in empty space (at least 1): the step
    // count to the exit of the largest empty brick holding p, rounded so that a sample on the
    // exit face is never skipped.
    // (A sentinel index, not std::optional: the optional's flag and index were stored as two
    // narrow writes and read back as one wide load, a store-forwarding stall on every sample
    // that was a fifth of the shadow rays' time.)
    struct probe_result {
        static constexpr voxel_index none = ~voxel_index(0); // no voxel: indices stop at max_voxel_count - 1 (volume.hpp)
        voxel_index index = none;
        int skip = 1;
        bool occupied() const { return index != none; }
    };
    // What probing reads, copied by value into a march's local variable: the loops around it
    // write floats through references (lookup counts, the lanes' arrays), which the compiler must
    // assume may alias the marcher's own float members, so probing through `this` reloaded the
    // grid from memory for every sample. A local copy whose address is never taken stays in
    // registers.
    struct grid_probe {
        struct level {
            const std::uint64_t* bits;
            std::size_t count_x, count_xy;
            int shift;
            std::size_t brick(int x, int y, int z) const
            {
                return std::size_t(x >> shift) + count_x * std::size_t(y >> shift) + count_xy * std::size_t(z >> shift);
            }
            bool occupied(int x, int y, int z) const
            {
                const std::size_t b = brick(x, y, z);
                return (bits[b >> 6] >> (b & 63)) & 1;
            }
        };
        krs::vec3f origin, cells_per_unit;
        float size[3];
        int last[3];
        voxel_index stride_y, stride_z;
        level fine, coarse;
        float step;
        const volume_marcher* spheres; // set when use_spheres: the rare path through the marcher

        probe_result operator()(const krs::vec3f& p, const cell_slopes& slope) const
        {
            const float f[3] = {(p.x - origin.x) * cells_per_unit.x, (p.y - origin.y) * cells_per_unit.y, (p.z - origin.z) * cells_per_unit.z};
            if (!(f[0] >= 0 && f[1] >= 0 && f[2] >= 0 && f[0] < size[0] && f[1] < size[1] && f[2] < size[2])) return {};
            int c[3];
            for (int a = 0; a < 3; ++a) c[a] = std::min(int(f[a]), last[a]);
            if (fine.occupied(c[0], c[1], c[2])) {
                if (spheres && !spheres->inside_a_sphere(p)) return {};
                return {voxel_index(c[0]) + stride_y * voxel_index(c[1]) + stride_z * voxel_index(c[2]), 1};
            }
            // The largest empty brick (two levels: the marcher's occupancy_, finest first).
            const int shift = coarse.occupied(c[0], c[1], c[2]) ? fine.shift : coarse.shift;
            float exit = 3.0e38f;
            for (int a = 0; a < 3; ++a) {
                const float lo = float((c[a] >> shift) << shift), hi = lo + float(1 << shift);
                const float inv = slope.inverse[a];
                if (inv > 0) exit = std::min(exit, (hi - f[a]) * inv);
                else if (inv < 0) exit = std::min(exit, (lo - f[a]) * inv);
            }
            // The 1e-3 margin covers the rounding of exit / step (a few float ulps of a number < 64).
            const float steps = std::ceil(exit / step - 1e-3f);
            return {probe_result::none, steps > 1.0f ? int(std::min(steps, 1.0e6f)) : 1};
        }
    };
    grid_probe probe_view() const
    {
        return {origin_,
                cells_per_unit_,
                {float(grid_[0]), float(grid_[1]), float(grid_[2])},
                {grid_[0] - 1, grid_[1] - 1, grid_[2] - 1},
                voxel_index(grid_[0]),
                voxel_index(grid_[0]) * voxel_index(grid_[1]),
                occupancy_[0].view(),
                occupancy_[1].view(),
                step_,
                options_.use_spheres ? this : nullptr};
    }

    bool inside_a_sphere(const krs::vec3f& p) const
    {
        if (shape_.spheres.empty()) return true;
        for (const auto& s : shape_.spheres) {
            const krs::vec3f d = p - s.center;
            if (krs::dot(d, d) <= s.radius * s.radius) return true;
        }
        return false;
    }

    // The most samples a ray can take through the box (the paper's cache size q).
    std::size_t max_samples() const
    {
        const krs::vec3f e = box_hi_ - box_lo_;
        return std::size_t(std::ceil(krs::length(e) / step_)) + 2;
    }

private:
    template <class T>
    static constexpr std::size_t lanes = krs::lane_count<T>;

    template <class T>
    static T load(const std::array<float, lanes<T>>& a)
    {
        if constexpr (std::floating_point<T>)
            return a[0];
        else
            return T::load_unaligned(a.data());
    }

    // Slab test against the tree's box; t0 >= 0. Rays that miss get t0 >= t1.
    template <class T>
    void enter_box(const krs::ray<T>& ray, T& t0, T& t1) const
    {
        using krs::abs, krs::max, krs::min, krs::select;
        t0 = T(0.0f);
        t1 = T(3.0e38f);
        const T lo[3] = {T(box_lo_.x), T(box_lo_.y), T(box_lo_.z)}, hi[3] = {T(box_hi_.x), T(box_hi_.y), T(box_hi_.z)};
        const T o[3] = {ray.origin.x, ray.origin.y, ray.origin.z}, d[3] = {ray.direction.x, ray.direction.y, ray.direction.z};
        for (int a = 0; a < 3; ++a) {
            // A zero direction component becomes tiny, so the division gives a huge finite slope
            // instead of inf * 0 = NaN when the origin lies on a slab plane.
            const T safe = select(abs(d[a]) < T(1e-30f), T(1e-30f), d[a]);
            const T inv = T(1.0f) / safe;
            const T ta = (lo[a] - o[a]) * inv, tb = (hi[a] - o[a]) * inv;
            t0 = max(t0, min(ta, tb));
            t1 = min(t1, max(ta, tb));
        }
    }

    voxel fetch_cached(voxel_index index, std::size_t k, ray_cache& cache, bool& valid, float& lookups) const
    {
        if (k < cache.index.size()) {
            if (valid && cache.index[k] == index) {
                ++cache.hits;
                return cache.value[k];
            }
            valid = false; // past the first mismatch the rest of the ray overwrites the cache
            ++cache.misses;
            ++lookups;
            const voxel v = store_->at(index);
            cache.index[k] = index, cache.value[k] = v;
            return v;
        }
        ++lookups;
        return store_->at(index);
    }

    krs::vec3f center_of(voxel_index index) const
    {
        const krs::vec3d c = store_->volume().voxel_center(index);
        return {float(c.x), float(c.y), float(c.z)};
    }

    // The lit color of a sample: base color x (ambient + diffuse), plus specular. With
    // shade_per_voxel the shading point is the voxel's center, so all but the view-dependent
    // specular term is a pure function of the voxel and is memoized: in the thread's own table,
    // and behind it in the render's shared one.
    rgb shade(const krs::vec3f& p, voxel_index index, int level, const krs::vec3f& view, thread_shade_memo* memo,
              shade_memo* shared, float& lookups) const
    {
        // The shading point, computed only where needed: a memo hit needs none (unless specular).
        const auto point = [&] { return options_.shade_per_voxel ? center_of(index) : p; };
        const std::size_t lights = light_dirs_.size();
        std::array<float, 3 + max_lights> local{}; // an entry: lit rgb, then one shadow per light
        const float* shadows = local.data() + 3;
        rgb lit;
        if (options_.shade_per_voxel && memo) {
            const std::size_t stride = 3 + lights;
            // (Re)sized for this marcher: its slot count and its number of lights. With a shared
            // memo behind it, the thread's own is a small one (recent voxels, in the core's cache).
            const std::size_t slots = shared ? std::min(memo_slots_, thread_memo_slots) : memo_slots_;
            if (memo->slots != slots || memo->value.size() != slots * stride) {
                memo->slots = slots;
                memo->index.assign(slots, ~voxel_index(0));
                memo->value.assign(slots * stride, 0.0f);
            }
            const std::size_t slot = (std::size_t(index) * 0x9e3779b1u >> 7) & (memo->slots - 1);
            float* entry = &memo->value[slot * stride];
            if (memo->index[slot] != index) {
                // Behind this thread's table, the render's (a memo of another size is not used).
                const bool usable = shared && shared->stride() == stride && shared->slots() == memo_slots_;
                if (!(usable && shared->find(index, entry))) {
                    lit = light_at(point(), level, entry + 3, lookups);
                    entry[0] = lit.r, entry[1] = lit.g, entry[2] = lit.b;
                    if (usable) shared->store(index, entry);
                }
                memo->index[slot] = index;
            }
            lit = {entry[0], entry[1], entry[2]};
            shadows = entry + 3;
        } else {
            lit = light_at(point(), level, local.data() + 3, lookups);
        }
        if (!(options_.specular > 0)) return lit;
        const krs::vec3d nd = shape_.normal_at(krs::vec3d(point()));
        if (nd.x == 0 && nd.y == 0 && nd.z == 0) return lit;
        const krs::vec3f n{float(nd.x), float(nd.y), float(nd.z)};
        for (std::size_t i = 0; i < lights; ++i) {
            // Blinn-Phong: the half-vector of light and viewer.
            const krs::vec3f h = krs::normalize(light_dirs_[i] + view);
            const float sp = options_.specular * std::pow(std::max(0.0f, krs::dot(n, h)), options_.shininess) * shadows[i];
            const rgb lc = options_.lights[i].color;
            lit.r += sp * lc.r, lit.g += sp * lc.g, lit.b += sp * lc.b;
        }
        return lit;
    }

    // Base color x (Reeves' attenuated ambient + shadowed Lambert) at shading point q; writes each
    // light's shadow transmittance to `shadows`.
    rgb light_at(const krs::vec3f& q, int level, float* shadows, float& lookups) const
    {
        const rgb base = level_color_[std::clamp(level, 0, 255)];
        const krs::vec3d qd(q);
        const krs::vec3d c(shape_.crown.center);
        const double depth = std::max(0.0, double(shape_.crown.radius) - krs::length(qd - c)) / std::max(double(shape_.crown.radius), 1e-30);
        const float ambient = options_.ambient * float(std::exp(-double(options_.ambient_falloff) * depth));
        float lr = ambient, lg = ambient, lb = ambient;
        const krs::vec3d nd = light_dirs_.empty() ? krs::vec3d{} : shape_.normal_at(qd);
        const krs::vec3f n{float(nd.x), float(nd.y), float(nd.z)};
        const bool has_normal = nd.x != 0 || nd.y != 0 || nd.z != 0;
        for (std::size_t i = 0; i < light_dirs_.size(); ++i) {
            const krs::vec3f& l = light_dirs_[i];
            shadows[i] = options_.shadows ? shadow_transmittance(q, l, lookups) : 1.0f;
            // Without a normal (no flow) the diffuse term is the shadow alone: "shadow attenuated
            // diffuse" of 8.3 for isotropic leaves.
            const float lambert = has_normal ? std::max(0.0f, krs::dot(n, l)) * 0.75f + 0.25f : 1.0f;
            const rgb lc = options_.lights[i].color;
            const float d = options_.diffuse * lambert * shadows[i];
            lr += d * lc.r, lg += d * lc.g, lb += d * lc.b;
        }
        return {base.r * lr, base.g * lg, base.b * lb};
    }

    const S* store_;
    tree_shape shape_;
    depth_colors colors_;
    march_options options_;
    krs::vec3f origin_{}, cells_per_unit_{}, box_lo_{}, box_hi_{};
    std::array<int, 3> grid_{};
    float side_ = 1, step_ = 1;
    static constexpr std::size_t max_lights = 8;
    std::size_t memo_slots_ = 1024;
    // A thread's own memo in front of the shared one: 16384 entries (about 320 KiB with one light,
    // within a core's L2). With 4096, a close 300 x 300 view of tree A at resolution 100 (eye 1.4
    // box diagonals away) went to the shared memo's cache lines for most voxels and rendered in
    // 16.3 ms instead of 12.3 on 2 threads (Table 1's framing shows no difference either way).
    static constexpr std::size_t thread_memo_slots = 16384;
    // Occupancy bits of one brick size (2^shift voxels a side): whether a brick holds any
    // non-empty voxel. Shifts, not divisions: this runs for every sample.
    struct occupancy {
        int shift;
        std::array<std::size_t, 3> count{};
        std::vector<std::uint64_t> bits;
        int side() const { return 1 << shift; }
        typename grid_probe::level view() const { return {bits.data(), count[0], count[0] * count[1], shift}; }
        void mark(int x, int y, int z)
        {
            const std::size_t b = view().brick(x, y, z);
            bits[b >> 6] |= std::uint64_t(1) << (b & 63);
        }
    };
    // 4^3 and 16^3, finest first: grid_probe reads exactly these two.
    std::array<occupancy, 2> occupancy_{occupancy{2, {}, {}}, occupancy{4, {}, {}}};
    std::array<float, 256> alpha_{};
    std::array<rgb, 256> level_color_{};
    std::vector<krs::vec3f> light_dirs_;
};

} // namespace hypertree

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
// Rays read the marcher's copy of the voxels, regrouped into 4^3 bricks (voxel_bricks.hpp), not
// the store: the store kind only changes how long the copy takes to make. Empty space is skipped
// by those bricks and their 16^3 blocks: a sample in an empty brick is not looked up, and the ray
// jumps by whole steps to the brick's exit, so it takes exactly the samples it would have stepped
// through. Optionally, samples outside every secondary bounding sphere are not looked up either
// (tree_shape.hpp: the spheres hold every non-empty cell). Neither changes a pixel, only the work.
//
// Shading (8.3): ambient light attenuated toward the interior (Reeves' exponential falloff with
// the depth below the crown's bounding sphere), Lambert diffuse and Blinn-Phong specular with the
// procedural normals of the structure flow, each light's term attenuated by the opacity a shadow
// ray accumulates toward it (same step, same early exit). The base color comes from the voxel's
// depth (transfer.hpp). By default a sample is shaded at its voxel's center (shade_per_voxel), so
// a voxel's shading is computed once per render and kept in a table (shade_memo.hpp): either all
// voxels before the rays, their shadow rays marched 16 at a time (shade_bricks), or each when a
// ray first meets it.
//
// One template: the loop over samples, the masks and the accumulation are written once over T.
// Rays through voxels shaded ahead march lanes in step, gathering places, opacities and colors
// (march_shaded); otherwise what each lane looks up and shades runs per lane in scalar code
// (march_shading). Either way a packet's lanes compute exactly what the scalar marcher computes
// for the same ray: packet and scalar images, and images shaded ahead or as met, are equal pixel
// for pixel (tested). Equal to the bit where the compiler does not fuse multiplies and adds
// (-ffp-contract=off, as the tests build, or no FMA in the target): a fusion made in one path and
// not in the other moves the last bits, and clang and gcc fuse by default where FMA exists.
//
// The ray cache of 8.2 is an option of the scalar marcher: entry k remembers the voxel index and
// voxel of sample k of the previous ray; a ray reads it until its first mismatch and then
// overwrites the rest. (The paper found it gave little; bench_hypertree_render measures it.)

#include "hypertree/render/shade_memo.hpp"
#include "hypertree/render/transfer.hpp"
#include "hypertree/render/tree_shape.hpp"
#include "hypertree/render/voxel_bricks.hpp"
#include "krs/core/lanes.hpp"
#include "krs/trace/ray.hpp"

#include <algorithm>
#include <array>
#include <bit>
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

// What a thread brings to a march: its caches, each optional. `shading` may be shared by all
// threads of a render (make it with volume_marcher::new_shade_memo()).
struct march_context {
    ray_cache* rays = nullptr; // scalar marcher only
    shade_memo* shading = nullptr;
};

template <voxel_store S>
class volume_marcher {
public:
    volume_marcher(const S& store, tree_shape shape, depth_colors colors, march_options options = {})
        : store_(&store), bricks_(store), shape_(std::move(shape)), colors_(std::move(colors)), options_(std::move(options))
    {
        krs::require_positive("march_options.step_factor", options_.step_factor);
        krs::require_positive("march_options.density_scale", options_.density_scale);
        krs::require_non_negative("march_options.min_transmittance", options_.min_transmittance);
        // Every shading term finite and non-negative: a NaN or infinite one made covered pixels
        // NaN, a negative ambient made them negative; a transmittance floor above 1 stopped every
        // ray after its first sample.
        if (!(options_.min_transmittance <= 1.0f))
            throw krs::invalid_parameter("march_options.min_transmittance", "must be in [0, 1]",
                                         krs::detail::to_text(options_.min_transmittance));
        krs::require_non_negative("march_options.ambient", options_.ambient);
        krs::require_non_negative("march_options.ambient_falloff", options_.ambient_falloff);
        krs::require_non_negative("march_options.diffuse", options_.diffuse);
        krs::require_non_negative("march_options.specular", options_.specular);
        krs::require_non_negative("march_options.shininess", options_.shininess);
        for (const auto& light : options_.lights) require_color("march_options.lights.color", light.color);
        const hypervolume& v = store.volume();
        origin_ = {float(v.origin().x), float(v.origin().y), float(v.origin().z)};
        cells_per_unit_ = {float(v.cells_per_unit().x), float(v.cells_per_unit().y), float(v.cells_per_unit().z)};
        grid_ = {v.grid().x, v.grid().y, v.grid().z};
        side_ = float(v.smallest_voxel_side());
        step_ = options_.step_factor * side_;
        rounding_per_step_ = float(0x1.0p-21 / double(step_));
        grid_reach_ = std::max({std::abs(origin_.x), std::abs(origin_.y), std::abs(origin_.z)});
        // alpha per density byte for one step: (1 - mu)^(k ds / side).
        const double exponent = double(options_.density_scale) * double(options_.step_factor);
        for (int d = 0; d < 256; ++d) alpha_[d] = d == 255 ? 1.0f : float(1.0 - std::pow(1.0 - d / 255.0, exponent));
        for (int l = 0; l < 256; ++l) level_color_[l] = colors_.at(l);
        // (At least one entry: lanes with no voxel read entry 0, even in an empty tree.)
        alpha_at_.resize(std::max<std::size_t>(1, bricks_.brick_count() * voxel_bricks::brick_voxels));
        for (std::size_t place = 0; place < bricks_.brick_count() * voxel_bricks::brick_voxels; ++place)
            alpha_at_[place] = alpha_[bricks_.at_place(place).density];
        box_lo_ = {float(shape_.box.lo.x), float(shape_.box.lo.y), float(shape_.box.lo.z)};
        box_hi_ = {float(shape_.box.hi.x), float(shape_.box.hi.y), float(shape_.box.hi.z)};
        // Rays count their samples in floats, exact to 2^24, and a skip adds up to 10^6 at once:
        // a ray may take at most 2^23 samples across the box, or its count would stop growing.
        const double samples = krs::length(krs::vec3d(box_hi_ - box_lo_)) / double(step_);
        if (!(samples < double(1 << 23)))
            throw krs::invalid_parameter("march_options.step_factor",
                                         "must leave at most 2^23 samples across the tree's box (its diagonal / (step_factor x the smallest "
                                         "voxel side) is " + std::to_string(samples) + ")",
                                         std::to_string(options_.step_factor));
        if (options_.lights.size() > max_lights)
            throw krs::invalid_parameter("march_options.lights", "may hold at most " + std::to_string(max_lights) + " lights",
                                         std::to_string(options_.lights.size()));
        // Finite and non-zero: an infinite component normalized to NaN, and every shadow ray then
        // took a span of 1e31 that its float sample count never crossed (render hung).
        for (const auto& light : options_.lights)
            light_dirs_.push_back(krs::require_direction("march_options.lights.direction", light.direction));
    }


    const march_options& options() const { return options_; }
    // An empty shading memo sized for this marcher (its voxel count and lights), for one render:
    // all its threads may share it.
    shade_memo new_shade_memo() const { return shade_memo(bricks_.voxel_count(), 3 + light_dirs_.size()); }
    // The marcher's copy of the store's voxels (voxel_bricks.hpp), which every ray reads.
    const voxel_bricks& bricks() const { return bricks_; }
    // What the marcher holds besides the store: its brick copy and the bricks' opacities.
    std::size_t memory_bytes() const { return bricks_.memory_bytes() + alpha_at_.capacity() * sizeof(float); }
    const tree_shape& shape() const { return shape_; }
    float step() const { return step_; }

    // Marches the rays of the lanes.
    template <class T>
    march_result<T> march(const krs::ray<T>& ray, march_context context = {}) const
    {
        return march_packets<T, 1>({ray}, context)[0];
    }
    // Marches K packets of rays. With every voxel shaded ahead (and nothing left to compute per
    // sample), the rays only read, and the packets march in turn within one loop, their lanes in
    // step (march_shaded). Otherwise each lane of each packet looks up and shades its samples on
    // its own (march_shading). Both give the same pixels (tested).
    template <class T, std::size_t K>
    std::array<march_result<T>, K> march_packets(const std::array<krs::ray<T>, K>& rays, march_context context = {}) const
    {
        const bool per_sample = !options_.shade_per_voxel || options_.specular > 0 || (std::floating_point<T> && context.rays);
        if (!per_sample && context.shading && context.shading->complete() && fits(*context.shading))
            return march_shaded<T, K>(rays, *context.shading);
        std::array<march_result<T>, K> out;
        for (std::size_t k = 0; k < K; ++k) out[k] = march_shading(rays[k], context);
        return out;
    }

    // Whether a memo was made for this marcher, as new_shade_memo() makes it (its voxel count
    // and lights): only such a memo is read or written.
    bool made_for(const shade_memo& memo) const
    {
        return memo.slots() == bricks_.voxel_count() && memo.stride() == 3 + light_dirs_.size();
    }
    // ... and rays may gather from it: it has an entry (lanes with no voxel read entry 0) and
    // fewer than 2^31 floats.
    bool fits(const shade_memo& memo) const
    {
        return made_for(memo) && memo.slots() > 0 && memo.slots() * memo.stride() < (std::size_t(1) << 31);
    }

private:
    // The march of rays through voxels all shaded ahead (march_packets checks that the table is
    // complete and fits): per sample, each lane's place in the bricks, its opacity and its
    // voxel's lit color are gathered, in the accumulation of march_shading, the same operations
    // in the same order. K packets march in turn within one
    // loop: a sample's place comes from gathers that depend on the previous sample's, so one
    // packet alone waits on memory at every step, and K independent ones give the core other work.
    template <class T, std::size_t K>
    std::array<march_result<T>, K> march_shaded(const std::array<krs::ray<T>, K>& rays, const shade_memo& memo) const
    {
        using I = krs::index_lanes<T>;
        using krs::any, krs::select;
        const T ds(step_), half(0.5f), zero(0.0f), one(1.0f), least(options_.min_transmittance);
        const float* alpha_at = alpha_at_.data();
        const std::int32_t* slot_at = bricks_.slots();
        const float* lit = memo.values();
        const I stride(std::int32_t(memo.stride()));
        std::array<march_result<T>, K> out;
        std::array<T, K> t0, t1, k;
        std::array<krs::mask_t<T>, K> active;
        T slope[K][3];
        std::array<T, K> margin0;
        std::array<exit_faces, K> faces;
        for (std::size_t r = 0; r < K; ++r) {
            margin0[r] = margin_at_origin(rays[r].origin);
            enter_box(rays[r], t0[r], t1[r]);
            k[r] = zero;
            active[r] = t0[r] + half * ds < t1[r];
            slopes_of(rays[r].direction, slope[r]);
            faces[r] = faces_of(slope[r]);
        }
        for (bool marching = true; marching;) {
            marching = false;
            for (std::size_t r = 0; r < K; ++r) {
                if (!any(active[r])) continue;
                marching = true;
                march_result<T>& o = out[r];
                const T t = t0[r] + (k[r] + half) * ds;
                const krs::vec3<T> p = rays[r].origin + rays[r].direction * t;
                const lane_probe<T> found = probe_lanes(p, slope[r], active[r], skip_margin(margin0[r], t), faces[r]);
                const I place = krs::index_max(found.place, I(0));
                const T a = select(found.looks, krs::gather(alpha_at, place), zero);
                const I entry = krs::gather(slot_at, place) * stride;
                composite(o, a, krs::gather(lit, entry), krs::gather(lit, entry + I(1)), krs::gather(lit, entry + I(2)));
                o.lookups = o.lookups + select(found.looks, one, zero);
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
    march_result<T> march_shading(const krs::ray<T>& ray, march_context context) const
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
        float slope[lanes<T>][3];
        std::array<exit_faces, lanes<T>> faces;
        const T margin0 = margin_at_origin(ray.origin);
        for (std::size_t i = 0; i < lanes<T>; ++i) slopes_of(krs::vec3f{dx[i], dy[i], dz[i]}, slope[i]), faces[i] = faces_of(slope[i]);
        while (any(active)) {
            const T t = t0 + (k + half) * ds;
            const krs::vec3<T> p = ray.origin + ray.direction * t;
            // Per lane: the voxel, its opacity for one step, and its shaded color if it is not
            // empty; or, in an empty brick, how many samples to skip.
            std::array<float, lanes<T>> alpha{}, r{}, g{}, b{}, lookups{}, advance{};
            // The lanes' inputs, spilled once per sample rather than once per lane.
            const auto px = krs::lanes_of(p.x), py = krs::lanes_of(p.y), pz = krs::lanes_of(p.z), ks = krs::lanes_of(k);
            const auto margin = krs::lanes_of(skip_margin(margin0, t));
            const std::uint64_t running = krs::mask_bits<T>(active);
            for (std::size_t i = 0; i < lanes<T>; ++i) {
                advance[i] = 1.0f;
                if (!((running >> i) & 1u)) continue;
                const krs::vec3f pi{px[i], py[i], pz[i]};
                const krs::vec3f di{dx[i], dy[i], dz[i]};
                const lane_probe<float> found = probe_lanes<float>(pi, slope[i], true, margin[i], faces[i]);
                if (!found.looks) {
                    advance[i] = found.advance;
                    continue;
                }
                const std::size_t place = std::size_t(found.place);
                const voxel_index index = voxel_index(found.cell[0]) +
                                          voxel_index(grid_[0]) * (voxel_index(found.cell[1]) + voxel_index(grid_[1]) * voxel_index(found.cell[2]));
                voxel v;
                if constexpr (std::floating_point<T>) {
                    v = cache ? fetch_cached(index, place, std::size_t(ks[i]), *cache, cache_valid, lookups[i])
                              : (++lookups[i], bricks_.at_place(place));
                } else {
                    v = (++lookups[i], bricks_.at_place(place));
                }
                if (v.density == 0) continue;
                alpha[i] = alpha_[v.density];
                const rgb c = shade(pi, index, place, v.level, -di, context.shading, lookups[i]);
                r[i] = c.r, g[i] = c.g, b[i] = c.b;
            }
            composite(out, load<T>(alpha), load<T>(r), load<T>(g), load<T>(b));
            out.lookups = out.lookups + load<T>(lookups);
            k = k + load<T>(advance);
            active = active & (t0 + (k + half) * ds < t1) & (out.transmittance >= T(options_.min_transmittance));
        }
        return out;
    }

public:
    // Transmittance from p toward the light along direction l (unit), within the tree's box:
    // samples at base + j ds from j = 1, one step out. At step factor 1 on cubic voxels that
    // sample has left the shading voxel whatever the light's direction (the voxel's far face is
    // at most sqrt(3)/2 of a side from its centre), so a voxel does not shadow itself. Below step
    // factor 0.87, or on elongated voxels, the first samples can fall in the voxel itself, which
    // then dims its own light: shading depends on the step factor there (a lone voxel of density
    // 200: shadow 1.0 at step 1, 0.46 at 0.5). The GLSL marcher keeps the same convention. The
    // march has the primary rays' empty-space skipping and early exit. One template for one point (T =
    // float) and for a packet of points, one per lane, toward the same light: the shading pass
    // marches the shadow rays of voxels a packet at a time (shade_bricks), each lane computing
    // exactly what the scalar march computes for its point. `lookups` counts each lane's voxel
    // reads.
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
    template <class T, std::size_t K>
    std::array<T, K> shadow_transmittances(const std::array<krs::vec3<T>, K>& p, const krs::vec3f& l, std::array<T, K>& lookups,
                                           std::array<krs::mask_t<T>, K> running) const
    {
        using krs::select, krs::max, krs::any;
        const krs::vec3<T> direction{T(l.x), T(l.y), T(l.z)};
        T slope[3];
        slopes_of(direction, slope);
        const exit_faces faces = faces_of(slope);
        const float* alpha_at = alpha_at_.data();
        const T step(step_), least(options_.min_transmittance), zero(0.0f), one(1.0f);
        std::array<T, K> base, t1, transmittance, j, margin0;
        for (std::size_t k = 0; k < K; ++k) {
            T t0;
            margin0[k] = margin_at_origin(p[k]);
            enter_box(krs::ray<T>{p[k], direction}, t0, t1[k]);
            base[k] = max(t0, zero);
            transmittance[k] = one, j[k] = one;
        }
        for (bool marching = true; marching;) {
            marching = false;
            for (std::size_t k = 0; k < K; ++k) {
                const T t = base[k] + j[k] * step;
                running[k] = running[k] & (t < t1[k]) & (transmittance[k] >= least);
                if (!any(running[k])) continue;
                marching = true;
                const lane_probe<T> found = probe_lanes(p[k] + direction * t, slope, running[k], skip_margin(margin0[k], t), faces);
                const T alpha = krs::gather(alpha_at, krs::index_max(found.place, krs::index_lanes<T>(0)));
                transmittance[k] = select(found.looks, transmittance[k] * (one - alpha), transmittance[k]);
                lookups[k] = lookups[k] + select(found.looks, one, zero);
                j[k] = j[k] + found.advance;
            }
        }
        return transmittance;
    }

    // Which face of a brick the rays of a packet leave by, per axis, when all lanes agree (rays of
    // neighbouring pixels nearly always do, shadow rays toward one light always): then the exit
    // is one product per axis instead of two and a choice per lane. The same exit either way.
    struct exit_faces {
        enum face : int { low, high, none, per_lane };
        face along[3] = {per_lane, per_lane, per_lane};
    };
    template <class T>
    static exit_faces faces_of(const T (&slope)[3])
    {
        using krs::all; // (unqualified below: packets take xsimd's, found by argument)
        exit_faces faces;
        const T zero(0.0f);
        for (int a = 0; a < 3; ++a) {
            if (all(slope[a] > zero)) faces.along[a] = exit_faces::high;
            else if (all(slope[a] < zero)) faces.along[a] = exit_faces::low;
            else if (all(slope[a] == zero)) faces.along[a] = exit_faces::none;
        }
        return faces;
    }

    // What a sample finds, lane by lane: its cell and its place in the bricks (negative in an
    // empty brick), whether it reads a voxel (`looks`: a running lane in a non-empty brick and,
    // with use_spheres, in a part's sphere), and how many samples to advance: 1, or in an empty
    // brick the steps to the exit of the largest empty brick or block, less `margin` steps
    // (skip_margin) and rounded up, so that no sample that would land in a non-empty brick is
    // skipped. The slopes are the t it takes to cross one cell along each axis (0 for an axis the
    // ray does not move along), so an empty brick costs multiplications.
    template <class T>
    struct lane_probe {
        krs::index_lanes<T> place;
        krs::mask_t<T> looks;
        T advance;
        krs::index_lanes<T> cell[3]; // cell 0 outside the grid
    };
    template <class T>
    [[gnu::always_inline]] lane_probe<T> probe_lanes(const krs::vec3<T>& p, const T (&slope)[3], const krs::mask_t<T>& running,
                                                     const T& margin, const exit_faces& faces) const
    {
        using I = krs::index_lanes<T>;
        using krs::select, krs::min, krs::ceil, krs::index_to_float, krs::truncate_to_index;
        const T zero(0.0f), one(1.0f);
        const T f[3] = {(p.x - T(origin_.x)) * T(cells_per_unit_.x), (p.y - T(origin_.y)) * T(cells_per_unit_.y),
                        (p.z - T(origin_.z)) * T(cells_per_unit_.z)};
        auto inside = running;
        for (int a = 0; a < 3; ++a) inside = inside & (f[a] >= zero) & (f[a] < T(float(grid_[std::size_t(a)])));
        // Lanes outside the grid look up cell 0 (their result is not used): a float to int
        // conversion outside int's range would be undefined.
        I c[3];
        for (int a = 0; a < 3; ++a) c[a] = krs::index_min(truncate_to_index(select(inside, f[a], zero)), I(grid_[std::size_t(a)] - 1));
        const I place = bricks_.view_of().place(c[0], c[1], c[2]);
        const T found = index_to_float(place); // >= 0: a voxel; < -64: an empty 16^3 block
        krs::mask_t<T> looks = inside & (found >= zero);
        if (options_.use_spheres) looks = looks & inside_a_sphere(p);
        const auto in_block = found < T(-64.5f);
        T exit(3.0e38f);
        for (int a = 0; a < 3; ++a) {
            const T lo = select(in_block, index_to_float(c[a] & I(~15)), index_to_float(c[a] & I(~3)));
            const T hi = lo + select(in_block, T(16.0f), T(4.0f));
            switch (faces.along[a]) {
            case exit_faces::high: exit = min(exit, (hi - f[a]) * slope[a]); break;
            case exit_faces::low: exit = min(exit, (lo - f[a]) * slope[a]); break;
            case exit_faces::none: break;
            default: // lanes going different ways
                exit = select(slope[a] > zero, min(exit, (hi - f[a]) * slope[a]), select(slope[a] < zero, min(exit, (lo - f[a]) * slope[a]), exit));
            }
        }
        const T steps = ceil(exit / T(step_) - margin);
        const T advance = select(inside & (found < zero), select(steps > one, min(steps, T(1.0e6f)), one), one);
        return {place, looks, advance, {c[0], c[1], c[2]}};
    }
    // How many steps short of an empty brick's exit a skip must stop, for a ray from `from` at t:
    // skip_margin(margin_at_origin(from), t). The exit is predicted from this sample's position,
    // but each sample's position is computed anew in floats, p = o + d t then (p - origin) x cells
    // per unit, with an error of a few ulps of |o| + t + |origin|: 2^-21 of that in all, both
    // samples' errors counted, in steps. Close to the tree it is the 1e-3 of the exit's own
    // rounding; from a camera 1000 units away it grows to several steps, and skips stop short
    // rather than jump over a voxel. (The part that does not depend on t is computed once per ray.)
    template <class T>
    T margin_at_origin(const krs::vec3<T>& from) const
    {
        using krs::abs, krs::max;
        const T reach = max(max(abs(from.x), abs(from.y)), abs(from.z)) + T(grid_reach_);
        return T(1e-3f) + reach * T(rounding_per_step_);
    }
    template <class T>
    T skip_margin(const T& at_origin, const T& t) const
    {
        return at_origin + t * T(rounding_per_step_);
    }

    // The slopes of the lanes of a direction: 1 / (d * cells per unit) per axis, or 0.
    template <class T>
    void slopes_of(const krs::vec3<T>& d, T (&slope)[3]) const
    {
        using krs::select;
        const T zero(0.0f), dir[3] = {d.x * T(cells_per_unit_.x), d.y * T(cells_per_unit_.y), d.z * T(cells_per_unit_.z)};
        for (int a = 0; a < 3; ++a) slope[a] = select(dir[a] != zero, T(1.0f) / dir[a], zero);
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
    template <class T>
    krs::mask_t<T> inside_a_sphere(const krs::vec3<T>& p) const
    {
        if constexpr (std::floating_point<T>) {
            return inside_a_sphere(krs::vec3f(p));
        } else {
            krs::mask_t<T> inside(shape_.spheres.empty());
            for (const auto& s : shape_.spheres) {
                const krs::vec3<T> d{p.x - T(s.center.x), p.y - T(s.center.y), p.z - T(s.center.z)};
                inside = inside | (d.x * d.x + d.y * d.y + d.z * d.z <= T(s.radius * s.radius));
            }
            return inside;
        }
    }

    // Shades the non-empty voxels of bricks [first, last) into `memo` (shade_per_voxel), their
    // shadow rays marched four packets of voxels at a time, and returns the lookups made. What it
    // stores equals what shade() computes for the same voxel (tested), so a render may shade its
    // voxels ahead of its rays (render_settings::shade_ahead) or as its rays meet them.
    template <class T = krs::packet_f>
    std::uint64_t shade_bricks(shade_memo& memo, std::size_t first, std::size_t last) const
    {
        constexpr std::size_t packets = std::floating_point<T> ? 1 : 4, w = lanes<T>, n = packets * w;
        const std::size_t lights = light_dirs_.size();
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
            std::array<std::array<float, n>, max_lights> shadows{};
            for (std::size_t i = 0; i < lights; ++i) {
                if (!options_.shadows) {
                    shadows[i].fill(1.0f);
                    continue;
                }
                std::array<T, packets> looked;
                looked.fill(T(0.0f));
                const std::array<T, packets> t = shadow_transmittances<T, packets>(p, light_dirs_[i], looked, running);
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
                const krs::vec3<D> nd = shape_.normal_at(krs::vec3<D>{load<D>(nx), load<D>(ny), load<D>(nz)});
                const auto ox = krs::lanes_of(nd.x), oy = krs::lanes_of(nd.y), oz = krs::lanes_of(nd.z);
                for (std::size_t k = 0; k < m && first + k < count; ++k) normal[first + k] = {ox[k], oy[k], oz[k]};
            }
            std::array<float, 3 + max_lights> entry{};
            for (std::size_t k = 0; k < count; ++k) {
                for (std::size_t i = 0; i < lights; ++i) entry[3 + i] = shadows[i][k];
                const rgb c = lit({x[k], y[k], z[k]}, levels[k], entry.data() + 3, normal[k]);
                entry[0] = c.r, entry[1] = c.g, entry[2] = c.b;
                memo.store(slots[k], entry.data());
            }
            count = 0;
        };
        const hypervolume& volume = store_->volume();
        for (std::size_t b = first; b < last && b < bricks_.brick_count(); ++b) {
            for (std::uint64_t mask = bricks_.mask(b); mask != 0; mask &= mask - 1) {
                const std::size_t offset = std::size_t(std::countr_zero(mask)), place = b * voxel_bricks::brick_voxels + offset;
                const std::array<int, 3> c = voxel_bricks::cell_at(bricks_.origin(b), offset);
                const krs::vec3f q = center_of(volume.index(c[0], c[1], c[2]));
                x[count] = q.x, y[count] = q.y, z[count] = q.z;
                slots[count] = bricks_.slot(place);
                levels[count] = bricks_.at_place(place).level;
                if (++count == n) shade_packet();
            }
        }
        if (count > 0) shade_packet();
        return std::uint64_t(lookups);
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
    static T load(const std::array<krs::scalar_t<T>, lanes<T>>& a)
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
        // Rays march in steps of ds along t, so a direction must be unit (krs::make_ray makes it
        // so): a zero one had a span of 1e30 that a float sample count never crossed (march hung),
        // and a short one would take more samples than the 2^23 the constructor allows. Such a
        // ray, or one from a non-finite origin, misses the box.
        const T length_squared = d[0] * d[0] + d[1] * d[1] + d[2] * d[2];
        const auto usable = (abs(length_squared - T(1.0f)) <= T(1e-3f)) && krs::is_finite(o[0]) && krs::is_finite(o[1]) &&
                            krs::is_finite(o[2]);
        t0 = select(usable, t0, T(0.0f)); // (a NaN slab bound could leave t0 at -1e31, not NaN)
        t1 = select(usable, t1, T(-1.0f));
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
        const krs::vec3d c = store_->volume().voxel_center(index);
        return {float(c.x), float(c.y), float(c.z)};
    }

    // The lit color of a sample: base color x (ambient + diffuse), plus specular. With
    // shade_per_voxel the shading point is the voxel's center, so all but the view-dependent
    // specular term is a pure function of the voxel and is memoized by its slot (voxel_bricks.hpp)
    // in the render's table.
    rgb shade(const krs::vec3f& p, voxel_index index, std::size_t place, int level, const krs::vec3f& view, shade_memo* memo,
              float& lookups) const
    {
        // The shading point, computed only where needed: a memo hit needs none (unless specular).
        const auto point = [&] { return options_.shade_per_voxel ? center_of(index) : p; };
        std::array<float, 3 + max_lights> entry{}; // lit rgb, then one shadow per light
        const float* shadows = entry.data() + 3;
        // A memo made for another marcher is not used.
        if (options_.shade_per_voxel && memo && made_for(*memo)) {
            const std::uint32_t slot = bricks_.slot(place);
            if (!memo->find(slot, entry.data())) {
                const rgb lit = light_at(point(), level, entry.data() + 3, lookups);
                entry[0] = lit.r, entry[1] = lit.g, entry[2] = lit.b;
                memo->store(slot, entry.data());
            }
        } else {
            const rgb lit = light_at(point(), level, entry.data() + 3, lookups);
            entry[0] = lit.r, entry[1] = lit.g, entry[2] = lit.b;
        }
        rgb lit{entry[0], entry[1], entry[2]};
        const std::size_t lights = light_dirs_.size();
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
        for (std::size_t i = 0; i < light_dirs_.size(); ++i)
            shadows[i] = options_.shadows ? shadow_transmittance(q, light_dirs_[i], lookups) : 1.0f;
        return lit(q, level, shadows);
    }
    // Base color x (Reeves' attenuated ambient + shadowed Lambert) at q, given each light's shadow
    // transmittance and the structure-flow normal at q.
    rgb lit(const krs::vec3f& q, int level, const float* shadows) const
    {
        return lit(q, level, shadows, light_dirs_.empty() ? krs::vec3d{} : shape_.normal_at(krs::vec3d(q)));
    }
    rgb lit(const krs::vec3f& q, int level, const float* shadows, const krs::vec3d& nd) const
    {
        const rgb base = level_color_[std::clamp(level, 0, 255)];
        const krs::vec3d qd(q);
        const krs::vec3d c(shape_.crown.center);
        const double depth = std::max(0.0, double(shape_.crown.radius) - krs::length(qd - c)) / std::max(double(shape_.crown.radius), 1e-30);
        const float ambient = options_.ambient * float(std::exp(-double(options_.ambient_falloff) * depth));
        float lr = ambient, lg = ambient, lb = ambient;
        const krs::vec3f n{float(nd.x), float(nd.y), float(nd.z)};
        const bool has_normal = nd.x != 0 || nd.y != 0 || nd.z != 0;
        for (std::size_t i = 0; i < light_dirs_.size(); ++i) {
            const krs::vec3f& l = light_dirs_[i];
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
    voxel_bricks bricks_;
    tree_shape shape_;
    depth_colors colors_;
    march_options options_;
    krs::vec3f origin_{}, cells_per_unit_{}, box_lo_{}, box_hi_{};
    std::array<int, 3> grid_{};
    float side_ = 1, step_ = 1;
    float rounding_per_step_ = 0, grid_reach_ = 0; // skip_margin's: 2^-21 / step, and max |origin|
    static constexpr std::size_t max_lights = 8;
    std::array<float, 256> alpha_{};
    std::vector<float> alpha_at_; // per place of the bricks: its voxel's opacity for one step
    std::array<rgb, 256> level_color_{};
    std::vector<krs::vec3f> light_dirs_;
};

} // namespace hypertree

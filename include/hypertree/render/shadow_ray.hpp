#pragma once
// One shadow ray's march toward a light (self-shadowing, paper 8.3), written once for everything
// that marches one: the marcher's shadow rays (volume_marcher::shadow_transmittances: a voxel's
// full shadow ray, or under the light sweep a point's ray to its cut) and the light sweep's passes
// (light_sweep.hpp: every voxel's ray to its cut). Each takes the same operations in the same
// order through `step`, so a shadow is the same float whoever marches it (tested bit for bit: the
// sweep uncut against shadow rays, the two ways of making the sweep against each other).
//
// From p toward the light along the unit direction l, within the tree's box: samples at
// base + j ds from j = 1, one step out (base: where the ray enters the box, 0 from inside; ds the
// marcher's step). At step factor 1 on cubic voxels that sample has left the shading voxel
// whatever the light's direction (the voxel's far face is at most sqrt(3)/2 of a side from its
// centre), so a voxel does not shadow itself. Below step factor 0.87, or on elongated voxels, the
// first samples can fall in the voxel itself, which then dims its own light: shading depends on
// the step factor there (a lone voxel of density 200: shadow 1.0 at step 1, 0.46 at 0.5). The
// GLSL marcher keeps the same convention (glsl.hpp, NAME_shadow_transmittance). A sample the walk looks at multiplies the transmittance by (1 - alpha) of its
// voxel (alpha: its opacity for one step); the ray ends when it leaves the box or the
// transmittance falls below min_transmittance (the light is gone), and skips empty space as the
// primary rays do (brick_walk.hpp). With cuts (the light sweep) the ray also stops at its first
// sample from step `near_steps` on that lands in a non-empty voxel other than p's own: the caller
// completes it there, by the cut voxel's swept transmittance (`complete`, T(v) = P(v) T(w)) or by
// noting the cut voxel's slot (the sweep's first pass, `slot_of`).
//
// One template for one ray (T = float) and a packet of rays toward the same light, one per lane
// (T = krs::packet_f); each lane computes exactly what the scalar ray computes from its point.

#include "hypertree/render/brick_walk.hpp"
#include "hypertree/render/tree_shape.hpp"
#include "hypertree/render/voxel_bricks.hpp"
#include "krs/core/lanes.hpp"
#include "krs/core/vec3.hpp"
#include "krs/trace/ray.hpp"

#include <cstdint>

namespace hypertree {

// What a shadow ray's samples read, all owned by the marcher (volume_marcher::shadow_reads_of): its
// walk and the bricks' view (copies, so that what every sample reads stays in registers: see
// voxel_bricks::view), its secondary bound, per place of the bricks the voxel's opacity for one
// step and its slot, the tree's box, and the options the march stops by.
struct shadow_reads {
    brick_walk walk;
    voxel_bricks::view view;
    const bound_test* bound = nullptr;
    const float* alpha_at = nullptr;
    const std::int32_t* slot_at = nullptr;
    krs::vec3f box_lo{}, box_hi{};
    float min_transmittance = 0.0f;
    float near_steps = 1.0f; // march_options::sweep_near_steps
};

// The shadow rays toward one light, T lanes at a time. A caller keeps one `lanes` per packet,
// sets its p and running, calls start (and origin_place, when it cuts), then step until it says
// no lane is running.
template <class T>
class shadow_ray {
public:
    using I = krs::index_lanes<T>;

    // The state of a packet's rays.
    struct lanes {
        krs::vec3<T> p;             // the rays' origins
        krs::mask_t<T> running;     // lanes still marching
        T base, t1, margin0;        // box entry (>= 0) and exit, the walk's margin at p
        T j, transmittance;         // the next sample's index, the product so far
        I own = I(-1);              // p's own place (origin_place), which never cuts its own ray
    };

    shadow_ray(const shadow_reads& reads, const krs::vec3f& l)
        : reads_(reads), direction_{T(l.x), T(l.y), T(l.z)}, step_(reads.walk.step()), least_(reads.min_transmittance),
          near_(reads.near_steps)
    {
        reads_.walk.slopes_of(direction_, slope_);
        faces_ = brick_walk::faces_of(slope_);
    }

    // Clips the rays from s.p to the box; the first sample is one step out.
    void start(lanes& s) const
    {
        using krs::max;
        T t0;
        s.margin0 = reads_.walk.margin_at_origin(s.p);
        enter_box(krs::ray<T>{s.p, direction_}, reads_.box_lo, reads_.box_hi, t0, s.t1);
        s.base = max(t0, T(0.0f));
        s.transmittance = T(1.0f), s.j = T(1.0f);
    }
    // The place of p itself (negative outside the bricks), what s.own must be for cuts.
    I origin_place(const lanes& s) const
    {
        return probe(s.p, s.running, reads_.walk.skip_margin(s.margin0, T(0.0f))).place;
    }

    // One sample of each running lane: false (nothing done) when no lane still runs. Adds the
    // lanes' voxel reads to `lookups` (if given). With `cuts`, `cut` gets the lanes cut at this
    // sample (they stop running) and `place` the sample's place (>= 0), for complete or slot_of.
    [[gnu::always_inline]] bool step(lanes& s, T* lookups, bool cuts, krs::mask_t<T>& cut, I& place) const
    {
        using krs::select, krs::any;
        const T zero(0.0f), one(1.0f);
        const T t = s.base + s.j * step_;
        s.running = s.running & (t < s.t1) & (s.transmittance >= least_);
        if (!any(s.running)) return false;
        const brick_walk::probe_result<T> found = probe(s.p + direction_ * t, s.running, reads_.walk.skip_margin(s.margin0, t));
        place = krs::index_max(found.place, I(0));
        const T alpha = krs::gather(reads_.alpha_at, place);
        s.transmittance = select(found.looks, s.transmittance * (one - alpha), s.transmittance);
        if (lookups) *lookups = *lookups + select(found.looks, one, zero);
        if (cuts) {
            // (Places compared in the float domain as their difference, exact: zero only when equal.)
            cut = found.looks & (alpha > zero) & (s.j >= near_) & (krs::index_to_float(found.place - s.own) != zero);
            s.running = s.running & !cut;
        }
        s.j = s.j + found.advance;
        return true;
    }

    // Completes the lanes `cut` at `place` by the cut voxel's swept transmittance (one light's
    // column of the sweep's table): T(v) = P(v) T(w), light_sweep.hpp.
    void complete(lanes& s, const krs::mask_t<T>& cut, const I& place, const float* swept) const
    {
        using krs::select; // (unqualified: packets take xsimd's, found by argument)
        s.transmittance = select(cut, s.transmittance * krs::gather(swept, slot_of(place)), s.transmittance);
    }
    // The slot (voxel_bricks.hpp) of the voxel at `place`.
    I slot_of(const I& place) const { return krs::gather(reads_.slot_at, place); }

private:
    [[gnu::always_inline]] brick_walk::probe_result<T> probe(const krs::vec3<T>& p, const krs::mask_t<T>& running, const T& margin) const
    {
        return reads_.walk.probe(reads_.view, p, slope_, running, margin, faces_, *reads_.bound);
    }

    shadow_reads reads_;
    krs::vec3<T> direction_;
    T slope_[3];
    brick_walk::exit_faces faces_;
    T step_, least_, near_;
};

} // namespace hypertree

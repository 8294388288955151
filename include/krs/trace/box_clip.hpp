#pragma once
// Clipping rays to a field's bounding box: no surface lies outside the box, so a ray may start
// where it enters the box and stop where it leaves it, and a ray that misses the box is done
// before its first field evaluation. Sphere tracing alone would leave the box in steps that grow
// only geometrically: a ray passing under a flat grid of 2^22 copies took about twenty more
// evaluations to reach the far plane.
//
// The box must also hold every point where the tracer may stop, and it stops where the field is
// below threshold(t) = footprint t + floor: up to threshold(t) outside the geometry. Such a point
// p is within threshold(t) of a surface point s in the box, so with D the distance from the rays'
// origin to the box's farthest corner, t = |p - o| <= D + threshold(t), that is
//     t <= T = (D + floor) / (1 - footprint),
// and growing the box by threshold(T) keeps every possible stop inside it (plus a relative 1e-6
// of the box's reach for the float rounding of the slab test). A clipped ray then starts no later
// than its first stop, as the tile prepass's start does, and ends no earlier than its last.
//
// The rays share one origin (a camera's eye; rays from another origin need their own box_clip).
//
// The growth is one function, `box_clip_growth` (in double here, in float in the GLSL), and the
// GLSL twin `box_clip_glsl` defines it and `krs_box_clip`, which grows the box for its ray's
// origin and cuts [t0, t1] as `apply` does (a Shadertoy program's eye moves with iTime, so its
// box is grown per pixel).

#include "krs/core/bounds.hpp"
#include "krs/field.hpp"
#include "krs/trace/sphere_trace.hpp"

#include <algorithm>
#include <cmath>
#include <concepts>
#include <limits>
#include <string_view>

namespace krs {

// How far a box must grow so that every stop of rays from an origin within `reach` of its
// farthest corner lies inside it: threshold(T) at the last possible stop T (see above), plus a
// relative 1e-6 of the reach for the rounding of the slab test.
template <std::floating_point S>
S box_clip_growth(S reach, S footprint, S floor)
{
    const S last_stop = (reach + floor) / (S(1) - footprint);
    return hit_threshold(footprint, last_stop, floor) + S(1e-6) * reach;
}

// The tightest bound a field reports: its box where it has one (a sequence), else the box of
// its bounding sphere, else none.
template <field F>
bounding_box field_box(const F& f)
{
    if constexpr (requires { { f.bound_box() } -> std::convertible_to<bounding_box>; })
        return f.bound_box();
    else if constexpr (requires { { f.bound() } -> std::convertible_to<bounding_sphere>; })
        return box_around(f.bound());
    else
        return bounding_box::unbounded();
}

class box_clip {
public:
    // Clips nothing.
    box_clip() = default;
    // Clips rays from `origin` traced with `options` to `box` grown as above. An unbounded box,
    // a footprint of 0.5 radian or more (a threshold that grows as fast as the ray), or an
    // inherited threshold (threshold_policy::inherited: the lanes' own, unknown here) clips
    // nothing. A non-finite origin or invalid options are refused by name (a NaN origin would
    // otherwise clip every ray away as a silent miss).
    box_clip(const bounding_box& box, const vec3f& origin, const trace_options& options)
    {
        require_finite("box_clip.origin", origin);
        options.validate();
        if (!box.is_bounded() || !(options.pixel_footprint < 0.5f) || options.threshold_by != threshold_policy::pixel_cone)
            return;
        const vec3d lo(box.lo), hi(box.hi), o(origin);
        const vec3d far{std::max(std::abs(lo.x - o.x), std::abs(hi.x - o.x)), std::max(std::abs(lo.y - o.y), std::abs(hi.y - o.y)),
                        std::max(std::abs(lo.z - o.z), std::abs(hi.z - o.z))};
        const double reach = length(far); // D
        const double grow = box_clip_growth(reach, double(options.pixel_footprint), double(options.threshold_floor));
        const vec3d g{grow, grow, grow};
        box_ = box_around(lo - g, hi + g);
        clips_ = true;
    }

    bool clips() const { return clips_; }
    const bounding_box& box() const { return box_; }

    // Narrows [t_start, t_max] to the ray's stretch inside the box; a ray that misses it gets
    // t_max = -infinity (the tracer then reports a miss without a step).
    template <class T>
    void apply(const ray<T>& r, T& t_start, T& t_max) const
    {
        if (!clips_) return;
        using S = scalar_t<T>;
        const T inf(std::numeric_limits<S>::infinity());
        T enter(-std::numeric_limits<S>::infinity()), leave = inf;
        const auto slab = [&](const T& o, const T& d, float lo, float hi) {
            // Parallel to the slab: inside it, no constraint; outside, no entry.
            const mask_t<T> parallel = d == T(0);
            const T safe = select(parallel, T(1), d);
            const T a = (T(lo) - o) / safe, b = (T(hi) - o) / safe;
            const mask_t<T> inside = o >= T(lo) && o <= T(hi);
            enter = max(enter, select(parallel, select(inside, -inf, inf), min(a, b)));
            leave = min(leave, select(parallel, select(inside, inf, -inf), max(a, b)));
        };
        slab(r.origin.x, r.direction.x, box_.lo.x, box_.hi.x);
        slab(r.origin.y, r.direction.y, box_.lo.y, box_.hi.y);
        slab(r.origin.z, r.direction.z, box_.lo.z, box_.hi.z);
        const mask_t<T> misses = !(enter <= leave);
        t_start = max(t_start, enter);
        t_max = select(misses, -inf, min(t_max, leave));
    }

private:
    bounding_box box_ = bounding_box::unbounded();
    bool clips_ = false;
};

// box_clip as GLSL: krs_box_clip(lo, hi, origin, direction, footprint, floor, t0, t1) grows the
// box [lo, hi] for `origin` (box_clip's constructor, in float) and cuts [t0, t1] to the ray's
// stretch inside it (apply); false when the ray misses it (apply's t_max = -infinity), or
// [t0, t1] unchanged when the footprint is 0.5 or more. Needs hit_threshold_glsl.
inline constexpr std::string_view box_clip_glsl = R"(// krs::box_clip_growth.
float krs_box_clip_growth(float reach, float footprint, float thresholdFloor) {
    float lastStop = (reach + thresholdFloor) / (1.0 - footprint);
    return krs_hit_threshold(footprint, lastStop, thresholdFloor) + 1e-6 * reach;
}
// krs::box_clip for rays from `origin`, then apply: [t0, t1] cut to the grown box.
bool krs_box_clip(vec3 boxLo, vec3 boxHi, vec3 origin, vec3 direction, float footprint, float thresholdFloor,
        inout float t0, inout float t1) {
    if (!(footprint < 0.5)) return true;
    float reach = length(max(abs(boxLo - origin), abs(boxHi - origin)));
    float grow = krs_box_clip_growth(reach, footprint, thresholdFloor);
    vec3 lo = boxLo - vec3(grow);
    vec3 hi = boxHi + vec3(grow);
    float enter = t0;
    float leave = t1;
    for (int k = 0; k < 3; ++k) {
        if (direction[k] == 0.0) {
            if (origin[k] < lo[k] || origin[k] > hi[k]) return false;
        } else {
            float a = (lo[k] - origin[k]) / direction[k];
            float b = (hi[k] - origin[k]) / direction[k];
            enter = max(enter, min(a, b));
            leave = min(leave, max(a, b));
        }
    }
    if (!(enter <= leave)) return false;
    t0 = enter;
    t1 = leave;
    return true;
}
)";

} // namespace krs

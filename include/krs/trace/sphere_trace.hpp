#pragma once
// Sphere tracing (Hart 1996) of any field, one template for scalar rays and packets.
//
// Each step evaluates the field at the ray point; the distance is the radius of an unbounding
// sphere, so the point may advance by it without crossing the surface. A lane stops when the
// distance falls below the hit threshold footprint * t + floor (the unbounding sphere projects to
// less than a pixel, section 4), when t passes max_distance, or after max_steps. Packets keep an
// active mask and stop when no lane is active; finished lanes freeze through `select`.
//
// The result never holds NaN: a ray with a non-finite origin or a zero/non-finite direction is
// reported as a miss with `invalid` set, and a field value that is NaN ends that lane as a miss.

#include "krs/core/validate.hpp"
#include "krs/field.hpp"
#include "krs/trace/ray.hpp"

#include <limits>
#include <type_traits>

namespace krs {

struct trace_options {
    int max_steps = 512;
    float min_distance = 0.0f;    // t where marching starts (a near plane, or a depth from a prepass)
    float max_distance = 1.0e4f;  // t beyond which the ray misses (a far plane, or a depth buffer)
    float pixel_footprint = 1e-3f; // radians: threshold grows as footprint * t (camera.pixel_footprint())
    float threshold_floor = 1e-6f; // absolute threshold near t = 0, in scene units

    // Rejects impossible options; returns *this for chaining.
    const trace_options& validate() const
    {
        if (max_steps < 1)
            throw invalid_parameter("trace_options.max_steps", "must be >= 1", std::to_string(max_steps));
        require_non_negative("trace_options.min_distance", min_distance);
        require_positive("trace_options.max_distance", max_distance);
        if (!(max_distance > min_distance))
            throw invalid_parameter("trace_options.max_distance", "must exceed min_distance",
                                    detail::to_text(max_distance));
        require_non_negative("trace_options.pixel_footprint", pixel_footprint);
        require_positive("trace_options.threshold_floor", threshold_floor);
        return *this;
    }
    // The hit threshold at depth t.
    template <class T>
    T threshold(const T& t) const
    {
        return T(pixel_footprint) * t + T(threshold_floor);
    }
};

// Counters are ints for a scalar ray and float lanes for a packet (exact up to 2^24 steps).
template <class T>
using count_t = std::conditional_t<std::floating_point<T>, int, T>;

template <class T>
struct hit {
    T t{};                 // ray parameter of the hit; +infinity on a miss
    mask_t<T> found{};     // the threshold was reached within max_distance and max_steps
    mask_t<T> invalid{};   // the ray itself was unusable (non-finite origin, zero direction)
    count_t<T> steps{};    // march iterations this lane took
    count_t<T> evaluations{}; // field evaluations this lane used
};

namespace detail {
template <class T>
inline count_t<T> count_if(const mask_t<T>& m)
{
    if constexpr (std::floating_point<T>)
        return m ? 1 : 0;
    else
        return select(m, T(1), T(0));
}
} // namespace detail

template <field F, class T>
hit<T> sphere_trace(const F& f, const ray<T>& r, const trace_options& options)
{
    using S = scalar_t<T>;
    const T inf(std::numeric_limits<S>::infinity());
    hit<T> h;
    const T dir_len2 = length_squared(r.direction);
    h.invalid = !(is_finite(r.origin) && is_finite(r.direction) && dir_len2 > T(0));
    mask_t<T> active = !h.invalid;
    h.found = active && !active; // all false, in the mask's own type
    T t(options.min_distance);
    const T t_max(options.max_distance);

    for (int step = 0; step < options.max_steps && any(active); ++step) {
        const T d = f.distance(point_at(r, t));
        h.steps += detail::count_if<T>(active);
        h.evaluations += detail::count_if<T>(active);
        const mask_t<T> close = active && (d < options.threshold(t));
        h.found = h.found || close;
        active = active && !close && is_finite(d);
        t = select(active, t + d, t);
        active = active && (t <= t_max);
    }
    h.t = select(h.found, t, inf);
    return h;
}

} // namespace krs

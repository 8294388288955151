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
//
// The hit threshold is one rule, `hit_threshold` (footprint * t + floor), and a march says which
// footprint and floor it wants by its `threshold_policy`: a primary ray's pixel cone, or a
// shadow ray's threshold inherited from the hit it leaves (the lane's `threshold_bias`, the same
// at every t). The GLSL twins (`hit_threshold_glsl`, `march_glsl`, `sphere_trace_glsl`) are the
// C++ operation for operation, for a Shadertoy program (krs/glsl/shadertoy.hpp) and its CPU
// reference, which is this tracer.

#include "krs/core/validate.hpp"
#include "krs/field.hpp"
#include "krs/trace/ray.hpp"

#include <limits>
#include <string>
#include <string_view>
#include <type_traits>
#include <utility>

namespace krs {

// The hit threshold at depth t: an unbounding sphere smaller than footprint * t projects to less
// than a pixel of angular size `footprint` (section 4), and `floor` keeps it above 0 near t = 0.
// Every threshold of the library and of its GLSL (krs_hit_threshold below) is this function.
template <class T>
[[gnu::always_inline]] inline T hit_threshold(const T& footprint, const T& t, const T& floor)
{
    return footprint * t + floor;
}

// How a march's hit threshold is made (trace_options::threshold_by).
enum class threshold_policy {
    // hit_threshold(pixel_footprint, t, threshold_floor) (plus the lane's threshold_bias, 0 unless
    // set): the threshold grows with the pixel's cone, as a primary ray's.
    pixel_cone,
    // Exactly each lane's threshold_bias, at every t: a shadow ray judges its occluders at the
    // threshold of the hit it leaves (pixel_footprint and threshold_floor are not used).
    inherited,
};

struct trace_options {
    int max_steps = 512;
    float min_distance = 0.0f;    // t where marching starts (a near plane, or a depth from a prepass)
    float max_distance = 1.0e4f;  // t beyond which the ray misses (a far plane, or a depth buffer)
    float pixel_footprint = 1e-3f; // radians: threshold grows as footprint * t (camera.pixel_footprint())
    float threshold_floor = 1e-6f; // absolute threshold near t = 0, in scene units
    // Over-relaxation factor (Keinert et al. 2014): step omega * d while consecutive unbounding
    // spheres overlap, fall back to omega = 1 for the rest of the ray when they do not. 1 is plain
    // sphere tracing; useful values are about 1.2 ... 1.8, and it must stay below 2.
    float omega = 1.0f;
    threshold_policy threshold_by = threshold_policy::pixel_cone;

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
        if (threshold_by == threshold_policy::pixel_cone) {
            require_non_negative("trace_options.pixel_footprint", pixel_footprint);
            require_positive("trace_options.threshold_floor", threshold_floor);
        } else if (threshold_by != threshold_policy::inherited) {
            throw invalid_parameter("trace_options.threshold_by", "must be pixel_cone or inherited",
                                    std::to_string(int(threshold_by)));
        }
        require_finite("trace_options.omega", omega);
        if (!(omega >= 1.0f && omega < 2.0f))
            throw invalid_parameter("trace_options.omega", "must be in [1, 2)", detail::to_text(omega));
        return *this;
    }
    // The footprint and floor the march puts into hit_threshold: the options' own, or 0 and 0 for
    // an inherited threshold (0 * t + 0 + bias is the bias exactly, for every finite t).
    float marched_footprint() const { return threshold_by == threshold_policy::inherited ? 0.0f : pixel_footprint; }
    float marched_floor() const { return threshold_by == threshold_policy::inherited ? 0.0f : threshold_floor; }
    // The hit threshold at depth t, before a lane's threshold_bias.
    template <class T>
    T threshold(const T& t) const
    {
        return hit_threshold(T(marched_footprint()), t, T(marched_floor()));
    }
};

// A shadow ray's options: the threshold inherited from the hit (the lanes' threshold_bias).
inline trace_options inherited_threshold_options(float max_distance, int max_steps = 512)
{
    trace_options o;
    o.threshold_by = threshold_policy::inherited;
    o.max_distance = max_distance;
    o.max_steps = max_steps;
    return o;
}

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

// The state of one ray (or one packet of rays) between march steps. Each lane carries its own
// start, step count and over-relaxation factor, so a packet tracer may refill a finished lane with
// a new ray while the other lanes go on. `result.evaluations` is not counted during the march:
// every step is one evaluation, so it equals `result.steps`, and `march_result` fills it in (one
// counter less to update per step).
template <class T>
struct march_state {
    ray<T> r{};
    T t{};               // current sample point
    T t_max{};           // the lane's far limit
    T accepted_t{};      // last sample whose unbounding sphere was kept (over-relaxation)
    T accepted_d{};      // its radius; +infinity before the first sample
    T omega{};           // this lane's relaxation factor (drops to 1 after a failed overlap test)
    T threshold_bias{};  // added to the hit threshold (threshold_policy::inherited: the whole of it)
    mask_t<T> active{};
    hit<T> result{};
};

// Whether a ray cannot be marched (per lane): a non-finite origin, a zero or non-finite direction
// or a non-finite start. Such a ray is a miss with `invalid` set.
template <class T>
[[gnu::always_inline]] inline mask_t<T> unusable_ray(const ray<T>& r, const T& t_start)
{
    return !(is_finite(r.origin) && is_finite(r.direction) && length_squared(r.direction) > T(0) && is_finite(t_start));
}

// What a new ray's lanes start with, besides their ray, t and t_max (which the caller has put in
// place) and their active mask: no hit yet (t = +infinity, found false, no step), and the
// over-relaxation's kept sphere at the start with an infinite radius and the options' omega.
// start_march sets it for every lane; a packet tracer that puts new rays into finished lanes
// (krs/trace/packet_trace.hpp) sets it for those lanes and marks them active. With Relaxed false
// (a plain march's loop) the kept sphere and omega are left as they are: the plain step never
// reads them. The lanes' threshold_bias is kept: a stream's rays share it.
template <bool Relaxed, class T>
[[gnu::always_inline]] inline void restart_lanes(march_state<T>& m, const mask_t<T>& fresh, const T& omega)
{
    using S = scalar_t<T>;
    const T inf(std::numeric_limits<S>::infinity());
    if constexpr (Relaxed) {
        m.accepted_t = select(fresh, m.t, m.accepted_t);
        m.accepted_d = select(fresh, inf, m.accepted_d);
        m.omega = select(fresh, omega, m.omega);
    }
    m.result.t = select(fresh, inf, m.result.t);
    if constexpr (std::floating_point<T>) {
        if (fresh) m.result.steps = 0, m.result.found = false;
    } else {
        m.result.steps = select(fresh, T(0), m.result.steps);
        // (As words of bits: a mask's `!` is not a single instruction with every xsimd target.)
        m.result.found = mask_from_bits<T>(mask_bits<T>(m.result.found) & ~mask_bits<T>(fresh));
    }
}

// Starts a march along r from t_start (per lane) to t_max.
template <class T>
march_state<T> start_march(const ray<T>& r, const T& t_start, const T& t_max, const trace_options& options)
{
    march_state<T> m;
    m.r = r;
    m.result.invalid = unusable_ray(r, t_start);
    // A lane whose start is already past its end (a ray clipped away, krs/trace/box_clip.hpp)
    // misses without a step.
    m.active = !m.result.invalid && t_start <= t_max;
    m.t = t_start;
    m.t_max = t_max;
    restart_lanes<true>(m, m.active || !m.active, T(options.omega)); // every lane
    return m;
}

// What a march step reads from trace_options, converted once per march to the lane type: a
// tracer that steps in a loop keeps these in registers (or one broadcast away) instead of reading
// and converting the options at every step. `relaxed` (omega > 1) picks the step's form.
template <class T>
struct march_limits {
    T footprint, floor, omega;
    count_t<T> max_steps;
    bool relaxed;
    explicit march_limits(const trace_options& o)
        : footprint(o.marched_footprint()), floor(o.marched_floor()), omega(o.omega), max_steps{},
          relaxed(o.omega > 1.0f)
    {
        if constexpr (std::floating_point<T>)
            max_steps = o.max_steps;
        else
            max_steps = T(scalar_t<T>(o.max_steps)); // float lanes count exactly to 2^24
    }
};

// The hit of a march (its evaluations are its steps: see march_state).
template <class T>
hit<T> march_result(const march_state<T>& m)
{
    hit<T> h = m.result;
    h.evaluations = h.steps;
    return h;
}

// One march step, given the field's value d at the lane's sample point t: the single body every
// tracer (scalar, packet, refilling packet) runs. With over-relaxation the previous kept sphere (t_a, d_a) and this one must
// overlap along the ray, with room for the hit threshold: d_a + |d| - (t - t_a) >= 2 threshold(t).
// Then, because the field is 1-Lipschitz, every point between t_a and t is at least
// (d_a + |d| - (t - t_a)) / 2 >= threshold from the surface: the long step skipped nothing plain
// sphere tracing could stop at. If they do not overlap, the sample is discarded, the lane steps
// back to t_a + d_a (the plain step from the kept sphere) and marches with omega = 1 from there.
// Lanes that are not active are left untouched (their state freezes through `select`).
//
// `Relaxed` is limits.relaxed as a constant, so a tracer's loop is compiled once per form and the
// plain form (omega = 1, every lane's omega 1: start_march sets it from the options) carries none
// of the over-relaxation's work: no kept sphere, no multiply by omega. In both forms a lane
// advances only on a finite d (d < +infinity once d < threshold has taken -infinity: NaN and
// +infinity end the lane as a miss).
//
// march_step evaluates the field at the sample point and advances; a tracer that evaluates
// several packets' points in one call (krs/trace/packet_trace.hpp) calls march_advance itself.
template <bool Relaxed, class T>
[[gnu::always_inline]] inline void march_advance(march_state<T>& m, const T& d, const march_limits<T>& c)
{
    using S = scalar_t<T>;
    const mask_t<T> was_active = m.active;
    if constexpr (std::floating_point<T>)
        m.result.steps += was_active ? 1 : 0;
    else
        m.result.steps = select(was_active, m.result.steps + T(1), m.result.steps);
    const T threshold = hit_threshold(c.footprint, m.t, c.floor) + m.threshold_bias;
    mask_t<T> accept = was_active;
    if constexpr (Relaxed) {
        const mask_t<T> relaxed = m.omega > T(1);
        const mask_t<T> overlap = (m.accepted_d + abs(d) - (m.t - m.accepted_t)) >= T(2) * threshold;
        const mask_t<T> fail = was_active && relaxed && !overlap;
        accept = was_active && !fail;
        // Step back on failure (accepted_d is finite here: the first sample always overlaps).
        m.t = select(fail, m.accepted_t + m.accepted_d, m.t);
        m.omega = select(fail, T(1), m.omega);
        const mask_t<T> close = accept && (d < threshold);
        m.result.found = m.result.found || close;
        m.result.t = select(close, m.t, m.result.t);
        const mask_t<T> advance = accept && !close && is_finite(d);
        m.accepted_t = select(advance, m.t, m.accepted_t);
        m.accepted_d = select(advance, d, m.accepted_d);
        T next = m.t + m.omega * d;
        // A relaxed step past t_max must not end the lane where the plain step would not: it
        // lands on t_max instead, whose sample the overlap test then checks (a surface between
        // t + d and t_max, the far side of a clipping box, was missed that way).
        next = select(next > m.t_max, max(m.t + d, m.t_max), next);
        m.t = select(advance, next, m.t);
        // A lane ends on a hit, a NaN field value, passing t_max, or its step budget.
        m.active = (advance || fail) && (m.t <= m.t_max) && (m.result.steps < c.max_steps);
    } else {
        const mask_t<T> close = accept && (d < threshold);
        m.result.found = m.result.found || close;
        m.result.t = select(close, m.t, m.result.t);
        const mask_t<T> advance = accept && !close && (d < T(std::numeric_limits<S>::infinity()));
        m.t = select(advance, m.t + d, m.t);
        m.active = advance && (m.t <= m.t_max) && (m.result.steps < c.max_steps);
    }
}

// The same step with the options as given (the form chosen per call).
template <class T>
void march_advance(march_state<T>& m, const T& d, const trace_options& options)
{
    const march_limits<T> c(options);
    if (c.relaxed)
        march_advance<true>(m, d, c);
    else
        march_advance<false>(m, d, c);
}

template <field F, class T>
void march_step(const F& f, march_state<T>& m, const trace_options& options)
{
    march_advance(m, f.distance(point_at(m.r, m.t)), options);
}

// The step with an observer: `observe(m, d)` sees every sample the step takes, the state as the
// step found it (each lane's sample point t, its active mask) and the field's value d there, before
// the step acts on them. It is how a march that wants more than the hit reads the ray without a
// loop of its own: the soft shadow keeps min k d / t over its samples (krs/shade/global.hpp). (The
// union tracer, krs/compose/union.hpp, does not use it: it evaluates its components itself, skipping
// the ones that cannot be nearest, and calls the plain march_advance with their minimum.) The step
// itself is march_advance, unchanged, so an observed march stops where an unobserved one does.
// (With over-relaxation the observer also sees samples the overlap test then discards: they are
// still the field's true values at points on the ray.)
template <class T, class Observer>
void march_advance(march_state<T>& m, const T& d, const trace_options& options, Observer&& observe)
{
    observe(std::as_const(m), d);
    march_advance(m, d, options);
}

template <field F, class T, class Observer>
void march_step(const F& f, march_state<T>& m, const trace_options& options, Observer&& observe)
{
    march_advance(m, f.distance(point_at(m.r, m.t)), options, observe);
}

// Both validate the options (trace_options::validate names what is wrong): a negative footprint, a
// NaN floor or omega marched on to a silent miss.
template <field F, class T>
hit<T> sphere_trace(const F& f, const ray<T>& r, const trace_options& options)
{
    options.validate();
    march_state<T> m = start_march(r, T(options.min_distance), T(options.max_distance), options);
    while (any(m.active)) march_step(f, m, options);
    return march_result(m);
}

// The same with a per-lane start (a tile prepass gives every ray its own) and far limit, and a
// per-lane threshold_bias (a shadow ray's inherited threshold, or one added to the pixel cone's).
template <field F, class T>
hit<T> sphere_trace(const F& f, const ray<T>& r, const T& t_start, const T& t_max, const trace_options& options,
                    const T& threshold_bias = T(0))
{
    options.validate();
    march_state<T> m = start_march(r, t_start, t_max, options);
    m.threshold_bias = threshold_bias;
    while (any(m.active)) march_step(f, m, options);
    return march_result(m);
}

// ---- GLSL ----------------------------------------------------------------------------------
//
// hit_threshold as GLSL.
inline constexpr std::string_view hit_threshold_glsl = R"(// krs::hit_threshold: the hit threshold at depth t.
float krs_hit_threshold(float footprint, float t, float thresholdFloor) {
    return footprint * t + thresholdFloor;
}
)";

// One ray's march_state and march_advance in the plain form (omega = 1), for a threshold of
// threshold_policy::pixel_cone plus threshold_bias (inherited: footprint and floor 0). A hit ends
// the march with found; a NaN or infinite distance makes t NaN or infinite, which ends it as a
// miss as the C++ does (the C++ keeps t; a miss's t is not used). Needs hit_threshold_glsl.
inline constexpr std::string_view march_glsl = R"(// krs::march_state of one ray (the plain form: omega = 1).
struct krs_march {
    vec3 origin;
    vec3 direction;
    float t;
    float t_max;
    float threshold_bias;
    bool marching; // march_state::active (`active` is a GLSL reserved word)
    bool found;
    int steps;
};
// krs::start_march (the ray is usable: a camera's or a shadow ray).
krs_march krs_start_march(vec3 origin, vec3 direction, float t_start, float t_max, float threshold_bias) {
    return krs_march(origin, direction, t_start, t_max, threshold_bias, t_start <= t_max, false, 0);
}
// krs::march_advance, given the field's value d at the sample point m.t.
void krs_march_advance(inout krs_march m, float d, float footprint, float thresholdFloor, int max_steps) {
    m.steps += 1;
    if (d < krs_hit_threshold(footprint, m.t, thresholdFloor) + m.threshold_bias) {
        m.found = true;
        m.marching = false;
        return;
    }
    m.t += d;
    m.marching = m.t <= m.t_max && m.steps < max_steps;
}
)";

// krs::sphere_trace (per-lane start, far limit and bias) of one ray through the GLSL field
// `float field(vec3 p)`, as the GLSL function `function`. Needs march_glsl.
inline std::string sphere_trace_glsl(const std::string& function, const std::string& field)
{
    return "// krs::sphere_trace through " + field + ".\n"
           "krs_march " + function + "(vec3 origin, vec3 direction, float t_start, float t_max, float footprint,\n"
           "        float thresholdFloor, float threshold_bias, int max_steps) {\n"
           "    krs_march m = krs_start_march(origin, direction, t_start, t_max, threshold_bias);\n"
           "    while (m.marching)\n"
           "        krs_march_advance(m, " + field + "(m.origin + m.direction * m.t), footprint, thresholdFloor, max_steps);\n"
           "    return m;\n"
           "}\n";
}

} // namespace krs

#pragma once
// Global shading by sphere tracing secondary rays (paper section 6.5): soft shadows and ambient
// occlusion. Both only need a field's distance, so they work for a KRS, a union, a warp alike, and
// both take one point or a packet of points (docs/design.md#rule-1): a shading pass lights W
// pixels at once, each lane the scalar call's arithmetic.
//
// Soft shadow (the penumbra estimate popularized for distance fields): march toward the light as a
// shadow ray would, and keep the smallest ratio k * d(t) / t seen on the way. d(t) / t is the
// tangent of the widest cone around the ray that the field proves empty at t, so the minimum over
// the ray estimates how much of a light of angular radius ~ 1/k is visible. The result is in
// [0, 1]; a ray that meets the surface (d below the threshold) returns 0 exactly as the hard
// shadow does, and as k -> infinity every ratio of a non-hitting ray exceeds 1 and the estimate
// becomes the hard shadow.
//
// Ambient occlusion from distance samples along the normal: at s_j = j * step (j = 1..N) an
// unoccluded surface has d(p + n s_j) = s_j (the distance grows as fast as we leave it); the
// shortfall (s_j - d) / s_j measures how much nearby geometry closes in. Samples are weighted by
// falloff^(j-1) (near samples matter more) and normalized, and the result is
// clamp(1 - strength * sum w_j (s_j - d_j) / s_j, 0, 1): 1 open, 0 fully enclosed.
//
// GLSL: each options struct carries its function's GLSL (`glsl_source`), the C++ loop line for line
// with the validated options baked in under their C++ names. A shader has no function parameters,
// so the function is written per field: emitter::add_shading(options, "NAME", "FIELD") writes
// `PREFIXNAME`, which samples `float PREFIXFIELD(vec3 p)`, a field added to the same emitter.
// The march's arithmetic is the C++'s, so on an implementation that rounds as C++ float does
// the results agree; elsewhere a step's last-bit difference moves the next sample point, and the
// shadow (a minimum of ratios along the march) moves by a like relative amount.

#include "krs/core/validate.hpp"
#include "krs/field.hpp"
#include "krs/trace/sphere_trace.hpp"

#include <string>
#include <string_view>

namespace krs {

struct soft_shadow_options {
    float hardness = 16.0f;     // k: larger gives sharper penumbrae (light of angular radius ~ 1/k), > 0
    float threshold = 1e-4f;    // the hit threshold of the shadow ray (use the primary hit's), > 0
    float max_distance = 1e3f;  // how far toward the light occluders are searched, > 0
    int max_steps = 256;        // >= 1; an unfinished march keeps the estimate found so far

    const soft_shadow_options& validate() const
    {
        require_positive("soft_shadow_options.hardness", hardness);
        require_positive("soft_shadow_options.threshold", threshold);
        require_positive("soft_shadow_options.max_distance", max_distance);
        if (max_steps < 1)
            throw invalid_parameter("soft_shadow_options.max_steps", "must be >= 1", std::to_string(max_steps));
        return *this;
    }

    // float NAME(vec3 p, vec3 n, vec3 to_light): soft_shadow(FIELD, p, n, to_light, *this).
    // (A zero light direction returns 0 there, as the C++'s unusable ray does.)
    // (The test is written `d >= threshold` negated, as the C++, so a NaN distance blocks where
    // the implementation keeps NaNs, as llvmpipe does; GLSL lets a compiler assume there are none,
    // so elsewhere a NaN's outcome is the driver's.)
    static constexpr std::string_view glsl_source = R"(float NAME(vec3 p, vec3 n, vec3 to_light) {
    const float hardness = HARDNESS;
    const float threshold = THRESHOLD;
    const float max_distance = MAX_DISTANCE;
    const int max_steps = MAX_STEPS;
    if (!(dot(to_light, to_light) > 0.0)) return 0.0;
    vec3 origin = p + n * (2.0 * threshold);
    float visible = 1.0;
    float t = 0.0;
    for (int step = 0; step < max_steps; ++step) {
        float d = FIELD(origin + to_light * t);
        if (!(d >= threshold)) return 0.0;
        if (t > 0.0) visible = min(visible, hardness * d / t);
        t += d;
        if (t > max_distance) break;
    }
    return clamp(visible, 0.0, 1.0);
}
)";
    static constexpr bool glsl_takes_field = true;
    template <class Out>
    void glsl_shading(Out& out, const std::string& function, const std::string& field) const
    {
        validate();
        out.function(Out::fill(glsl_source, {{"NAME", function}, {"FIELD", field}, {"HARDNESS", Out::literal(hardness)},
                                             {"THRESHOLD", Out::literal(threshold)},
                                             {"MAX_DISTANCE", Out::literal(max_distance)},
                                             {"MAX_STEPS", std::to_string(max_steps)}}));
    }
};

// Visible fraction of the light from surface point p with normal n, for one point (T = float,
// double) or a packet of points (T = packet_f: W shadow rays marched together, each lane with its
// own point, normal and light direction). The march starts at p lifted by two thresholds along n
// (as krs::hard_shadow does), so it does not re-hit the surface it leaves; t counts from that
// lifted point.
//
// The march is the tracers' own (docs/design.md#rule-1): march_state / march_step with the
// threshold fixed at `threshold` (no footprint), over-relaxation off, `max_steps` samples and the
// far limit `max_distance`. The penumbra ratio rides in the step's observer, which sees each
// sample t and its distance d before the step acts on them. That is the loop of the GLSL above,
// line for line: a sample with !(d >= threshold) (the surface, or NaN) makes the lane 0; others
// lower the estimate to k d / t where t > 0; the step is t += d; the lane stops once t passes
// max_distance or after max_steps samples. (An infinite d ends the march without lowering the
// estimate, as t += d passing max_distance does in the GLSL.)
//
// Lanes outside `lanes` are not marched and return 0, as does a lane whose shadow ray is unusable
// (a non-finite point or normal, a zero or non-finite light direction): no light arrives along a
// direction that is not one, and a NaN distance blocks as well.
//
// `threshold` gives each lane its own hit threshold (and lift), e.g. its primary hit's, in place
// of o.threshold: a packet of shading points at different depths. It must be > 0 in every lane in
// `lanes`. It rides in the march state's threshold_bias (threshold_policy::inherited), so the
// test is d < threshold exactly, as the scalar call with o.threshold makes it.
template <field F, class T>
T soft_shadow(const F& f, const vec3<T>& p, const vec3<T>& n, const vec3<T>& to_light, const soft_shadow_options& o,
              const mask_t<T>& lanes, const T& threshold)
{
    using S = scalar_t<T>;
    o.validate();
    if (any(lanes && !(threshold > T(0) && is_finite(threshold))))
        throw invalid_parameter("soft_shadow.threshold", "must be finite and > 0 in every lane shaded");
    const trace_options march = inherited_threshold_options(o.max_distance, o.max_steps); // the lane's, see above
    const T k(S(o.hardness));
    // A lane left out ends before its start: start_march rejects it without a step. march_step
    // still evaluates the field in every lane, and a left-out lane's p, n, threshold and direction
    // are never checked (a NaN or infinity there is allowed), so its ray is replaced by the origin
    // with a zero direction: the field never sees a point that was not asked for.
    const vec3<T> zero(T(0), T(0), T(0));
    const vec3<T> origin = select(lanes, p + n * (T(2) * threshold), zero);
    const ray<T> r{origin, select(lanes, to_light, zero)};
    const T far = select(lanes, T(S(o.max_distance)), T(-1));
    march_state<T> m = start_march(r, T(0), far, march);
    m.threshold_bias = select(lanes, threshold, T(1)); // finite in left-out lanes too
    T visible(1);
    mask_t<T> blocked = m.active && !m.active; // all false, in the mask's own type
    auto penumbra = [&](const march_state<T>& at, const T& d) {
        const mask_t<T> open = d >= threshold;
        blocked = blocked || (at.active && !open);
        visible = select(at.active && open && at.t > T(0), min(visible, k * d / at.t), visible);
    };
    while (any(m.active)) march_step(f, m, march, penumbra);
    // visible starts at 1 and only falls by positive ratios: the clamp is the GLSL's, for form.
    return select(blocked || m.result.invalid || !lanes, T(0), clamp(visible, T(0), T(1)));
}

// The lanes in `lanes`, with o.threshold.
template <field F, class T>
T soft_shadow(const F& f, const vec3<T>& p, const vec3<T>& n, const vec3<T>& to_light, const soft_shadow_options& o,
              const mask_t<T>& lanes)
{
    return soft_shadow(f, p, n, to_light, o, lanes, T(scalar_t<T>(o.threshold)));
}

// Every lane (one point: the point itself), with o.threshold.
template <field F, class T>
T soft_shadow(const F& f, const vec3<T>& p, const vec3<T>& n, const vec3<T>& to_light, const soft_shadow_options& o)
{
    const T zero(0);
    return soft_shadow(f, p, n, to_light, o, zero == zero);
}

struct ambient_occlusion_options {
    float step = 0.05f;      // spacing of the samples along the normal, > 0 (about the size of
                             // the crevices that should darken)
    int samples = 5;         // in [1, 32]
    float falloff = 0.7f;    // weight ratio of consecutive samples, in (0, 1]
    float strength = 1.0f;   // >= 0

    const ambient_occlusion_options& validate() const
    {
        require_positive("ambient_occlusion_options.step", step);
        if (samples < 1 || samples > 32)
            throw invalid_parameter("ambient_occlusion_options.samples", "must be in [1, 32]", std::to_string(samples));
        require_positive("ambient_occlusion_options.falloff", falloff);
        if (falloff > 1.0f)
            throw invalid_parameter("ambient_occlusion_options.falloff", "must be <= 1", detail::to_text(falloff));
        require_non_negative("ambient_occlusion_options.strength", strength);
        return *this;
    }

    // float NAME(vec3 p, vec3 n): ambient_occlusion(FIELD, p, n, *this). A non-finite result
    // (a field that returns inf or NaN) is 1, as in the C++, where the implementation keeps NaNs
    // and infinities (llvmpipe does): GLSL lets isnan and isinf be false on one that does not.
    static constexpr std::string_view glsl_source = R"(float NAME(vec3 p, vec3 n) {
    const float step = STEP;
    const int samples = SAMPLES;
    const float falloff = FALLOFF;
    const float strength = STRENGTH;
    float occlusion = 0.0;
    float total = 0.0;
    float weight = 1.0;
    for (int j = 1; j <= samples; ++j) {
        float s = float(j) * step;
        float d = FIELD(p + n * s);
        occlusion += weight * (s - d) / s;
        total += weight;
        weight *= falloff;
    }
    float ao = 1.0 - strength * occlusion / total;
    return isnan(ao) || isinf(ao) ? 1.0 : clamp(ao, 0.0, 1.0);
}
)";
    static constexpr bool glsl_takes_field = true;
    template <class Out>
    void glsl_shading(Out& out, const std::string& function, const std::string& field) const
    {
        validate();
        out.function(Out::fill(glsl_source, {{"NAME", function}, {"FIELD", field}, {"STEP", Out::literal(step)},
                                             {"SAMPLES", std::to_string(samples)}, {"FALLOFF", Out::literal(falloff)},
                                             {"STRENGTH", Out::literal(strength)}}));
    }
};

// Ambient occlusion at p with normal n, for one point (T = float, double) or a packet (T = packet_f,
// each lane its own point and normal). The samples sit at fixed distances along the normal, so
// there is no march to share with the tracers: the loop is one template over the lane type, the
// weights and sample distances are the same for every lane and stay scalar, and each lane does
// the scalar call's arithmetic in its order (a lane equals the scalar result bit for bit where
// the build does not contract a * b + c differently in the two, tests/support/parity.hpp).
template <field F, class T>
T ambient_occlusion(const F& f, const vec3<T>& p, const vec3<T>& n, const ambient_occlusion_options& o)
{
    using S = scalar_t<T>;
    o.validate();
    T occlusion(0);
    S total = 0, weight = 1;
    for (int j = 1; j <= o.samples; ++j) {
        const S s = S(j) * S(o.step);
        const T d = f.distance(p + n * T(s));
        occlusion += T(weight) * (T(s) - d) / T(s);
        total += weight;
        weight *= S(o.falloff);
    }
    const T ao = T(1) - T(S(o.strength)) * occlusion / T(total);
    return select(is_finite(ao), clamp(ao, T(0), T(1)), T(1));
}

} // namespace krs

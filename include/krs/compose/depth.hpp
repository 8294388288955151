#pragma once
// Depth composition (paper section 6.3): a sphere-traced field inside a rasterized scene.
//
// A hit at ray parameter t, on a unit ray direction d from the eye, lies at view depth
//     z = t * (d . forward)
// (forward the camera's unit view axis). An OpenGL-style perspective projection with near n and
// far f stores it in the [0, 1] depth buffer as
//     depth(z) = f (z - n) / (z (f - n))      (window depth of NDC z_ndc = (f+n)/(f-n) - 2fn/((f-n) z)),
// which is 0 at the near plane and 1 at the far plane; the inverse is z = f n / (f - depth (f - n)).
// Reading a depth buffer back into t gives each ray a maximum distance: rays stop where the
// rasterized geometry already covers the pixel (early termination), and written depths let
// transparent or deferred passes run after the ray caster.
//
// GLSL: depth_projection carries its functions' GLSL (`glsl_source`) with near_plane and far_plane
// baked in: emitter::add_shading(projection, "NAME") writes NAME_buffer_depth, NAME_view_depth,
// NAME_hit_depth (the depth output: write it to gl_FragDepth) and NAME_ray_limit (the depth-buffer
// early exit: march no farther than it, and miss where it is not beyond the march's start).

#include "krs/core/validate.hpp"
#include "krs/field.hpp"
#include "krs/trace/sphere_trace.hpp"

#include <algorithm>
#include <limits>
#include <string>
#include <string_view>

namespace krs {

// View depth of ray parameter t on a unit direction. `forward` is the camera's unit view axis.
template <std::floating_point S>
S view_depth_of(S t, const vec3<S>& direction, const vec3<S>& forward)
{
    return t * dot(direction, forward);
}
// Ray parameter at view depth z (infinite for a ray parallel to the image plane).
template <std::floating_point S>
S t_of_view_depth(S z, const vec3<S>& direction, const vec3<S>& forward)
{
    const S c = dot(direction, forward);
    return c > S(0) ? z / c : std::numeric_limits<S>::infinity();
}

struct depth_projection {
    float near_plane = 0.1f; // > 0
    float far_plane = 1e3f;  // > near_plane

    depth_projection() = default;
    depth_projection(float near_, float far_) : near_plane(near_), far_plane(far_) { validate(); }
    const depth_projection& validate() const
    {
        require_positive("depth_projection.near_plane", near_plane);
        require_positive("depth_projection.far_plane", far_plane);
        if (!(far_plane > near_plane))
            throw invalid_parameter("depth_projection.far_plane", "must exceed near_plane", detail::to_text(far_plane));
        return *this;
    }

    // [0, 1] buffer value of view depth z (clamped to the near/far range).
    template <std::floating_point S>
    S buffer_depth(S z) const
    {
        const S n = S(near_plane), f = S(far_plane);
        z = std::clamp(z, n, f);
        return std::clamp(f * (z - n) / (z * (f - n)), S(0), S(1));
    }
    // View depth of a [0, 1] buffer value.
    template <std::floating_point S>
    S view_depth(S depth) const
    {
        const S n = S(near_plane), f = S(far_plane);
        depth = std::clamp(depth, S(0), S(1));
        return f * n / (f - depth * (f - n));
    }
    // The depth output: the buffer value of a hit at ray parameter t.
    template <std::floating_point S>
    S hit_depth(S t, const vec3<S>& direction, const vec3<S>& forward) const
    {
        return buffer_depth(view_depth_of(t, direction, forward));
    }
    // The depth-buffer early exit: how far a ray need march where the raster holds `buffer_value`
    // (its t there), capped by max_distance; a ray parallel to the image plane keeps max_distance.
    template <std::floating_point S>
    S ray_limit(S buffer_value, const vec3<S>& direction, const vec3<S>& forward, S max_distance) const
    {
        return std::min<S>(t_of_view_depth(view_depth(buffer_value), direction, forward), max_distance);
    }

    // The four functions above in GLSL, line for line (dot written out in the C++'s order). For
    // finite and infinite x, GLSL's clamp(x, a, b), min(max(x, a), b), is std::clamp's value; for
    // a NaN std::clamp returns the NaN, while GLSL leaves min and max of a NaN undefined (llvmpipe
    // returns the other operand, so a NaN clamps to the lower end: tests/test_glsl_shading.cpp pins
    // it). A ray parallel to the image plane has no infinity to take the min with in GLSL ES: it
    // takes max_distance directly.
    static constexpr std::string_view glsl_source = R"(float NAME_buffer_depth(float z) {
    const float near_plane = NEAR_PLANE;
    const float far_plane = FAR_PLANE;
    z = clamp(z, near_plane, far_plane);
    return clamp(far_plane * (z - near_plane) / (z * (far_plane - near_plane)), 0.0, 1.0);
}
float NAME_view_depth(float depth) {
    const float near_plane = NEAR_PLANE;
    const float far_plane = FAR_PLANE;
    depth = clamp(depth, 0.0, 1.0);
    return far_plane * near_plane / (far_plane - depth * (far_plane - near_plane));
}
float NAME_hit_depth(float t, vec3 direction, vec3 forward) {
    return NAME_buffer_depth(t * (direction.x * forward.x + direction.y * forward.y + direction.z * forward.z));
}
float NAME_ray_limit(float buffer_value, vec3 direction, vec3 forward, float max_distance) {
    float c = direction.x * forward.x + direction.y * forward.y + direction.z * forward.z;
    return c > 0.0 ? min(NAME_view_depth(buffer_value) / c, max_distance) : max_distance;
}
)";
    template <class Out>
    void glsl_shading(Out& out, const std::string& function, const std::string&) const
    {
        validate();
        out.function(Out::fill(glsl_source, {{"NAME", function}, {"NEAR_PLANE", Out::literal(near_plane)},
                                             {"FAR_PLANE", Out::literal(far_plane)}}));
    }
};

// Sphere traces with the ray's far limit taken from a depth-buffer value: the ray misses where
// the rasterized scene is nearer than the field. options.max_distance still caps the limit.
template <field F, std::floating_point S>
hit<S> trace_against_depth(const F& f, const ray<S>& r, trace_options options, const depth_projection& projection,
                           const vec3<S>& forward, S buffer_value)
{
    // Validated up front: the early miss below returned without a look at them (a NaN buffer value
    // or min_distance was a silent miss, a zero forward axis dropped the depth limit).
    projection.validate();
    options.validate();
    require_finite("trace_against_depth.buffer_value", buffer_value);
    require_finite("trace_against_depth.forward", forward);
    if (!(length_squared(forward) > S(0)))
        throw invalid_parameter("trace_against_depth.forward", "must be a non-zero direction", detail::to_text(forward));
    options.max_distance = float(projection.ray_limit(buffer_value, r.direction, forward, S(options.max_distance)));
    if (!(options.max_distance > options.min_distance)) {
        hit<S> h;
        h.t = std::numeric_limits<S>::infinity();
        return h; // the raster is in front of where marching would start
    }
    return sphere_trace(f, r, options);
}

} // namespace krs

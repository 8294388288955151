#pragma once
// A whole Shadertoy program for a KRS scene: paste the text into Shadertoy's Image tab as-is.
//
// mainImage builds the pinhole camera ray of the pixel (as krs::pinhole_camera::primary_ray does,
// with the vertical field of view fixed and the width following iResolution), sphere traces the
// field with the pixel-footprint threshold (footprint * t + floor, as trace_options::threshold),
// shades with Lambert in kernel space (Algorithm 2: the kernel's own normal against the light
// carried down the mirrors, blended over a band of `band_pixels` footprints) and a hard shadow
// ray that inherits the hit's threshold and starts far enough along the light to clear the
// surface. A primary ray is first clipped to the sequence's bounding box, grown by the largest
// hit threshold a stop in it can have, as krs::box_clip does (a flat forest fills a small part of
// the picture and of its bounding sphere). `render_reference` below is the same math in C++ on
// the CPU field, pixel for pixel, so the GLSL can be checked against it. Alpha is 1 where the ray
// hit the scene and 0 on the sky.

#include "krs/glsl/emitter.hpp"
#include "krs/kernels/kernels.hpp"
#include "krs/sequence.hpp"
#include "krs/shade/kernel_light.hpp"
#include "krs/trace/box_clip.hpp"

#include <algorithm>
#include <cmath>
#include <concepts>
#include <numbers>
#include <string>
#include <vector>

namespace krs::glsl {

struct view {
    vec3f eye{0, 0, -5}, forward{0, 0, 1}, right{1, 0, 0}, up{0, 1, 0};
    float tan_half_fov = 0.5f;
    vec3f to_light{0, 1, 0};    // unit, world
    float max_distance = 100.0f;
    int max_steps = 256;
    float threshold_floor = 1e-5f;
    float footprint_scale = 0.5f; // hit threshold in pixel footprints
    float band_pixels = 4.0f;     // Algorithm 2 band width in pixel footprints

    // Camera basis computed in double and rounded once (as the GLSL constants store it).
    static view look_at(const vec3f& eye, const vec3f& target, const vec3f& up_hint, float vertical_fov_degrees,
                        const vec3f& to_light, float max_distance)
    {
        view v;
        v.eye = require_finite("view.eye", eye);
        const vec3d f = normalize(vec3d(require_direction("view.target - view.eye", target - eye)));
        const vec3d r = cross(f, vec3d(require_direction("view.up", up_hint)));
        if (!(length(r) > 1e-6)) throw invalid_parameter("view.up", "must not be parallel to the view direction");
        const vec3d rn = normalize(r);
        v.forward = vec3f(f);
        v.right = vec3f(rn);
        v.up = vec3f(cross(rn, f));
        v.tan_half_fov = float(std::tan(0.5 * double(vertical_fov_degrees) * std::numbers::pi / 180.0));
        v.to_light = vec3f(normalize(vec3d(require_direction("view.to_light", to_light))));
        v.max_distance = require_positive("view.max_distance", max_distance);
        return v;
    }
};

namespace detail {
// Shading palette by kernel type (linear RGB): bark for stems, leaf green for spheres, soil for
// planes, stone for the rest.
template <class K>
constexpr vec3f albedo_of()
{
    if constexpr (std::same_as<K, torus_capsule> || std::same_as<K, capsule>) return {0.40f, 0.26f, 0.15f};
    else if constexpr (std::same_as<K, sphere>) return {0.22f, 0.45f, 0.12f};
    else if constexpr (std::same_as<K, plane>) return {0.42f, 0.40f, 0.33f};
    else return {0.70f, 0.68f, 0.64f};
}
} // namespace detail

// Albedo of kernel type index `kind` of sequence S (krs_kernel_shading::kind).
template <class M, class... Kinds>
vec3f albedo(const basic_sequence<M, Kinds...>&, std::uint32_t kind)
{
    const vec3f palette[] = {detail::albedo_of<Kinds>()...};
    return palette[kind];
}

template <class M, class... Kinds>
std::string shadertoy(const basic_sequence<M, Kinds...>& s, const view& v, const std::string& name)
{
    emitter e({target::shadertoy, data_mode::constants, name + "_data", 0});
    const std::string scene = e.add(s, name); // krs_NAME
    std::string out = "// krs scene '" + name + "' for Shadertoy: paste into the Image tab as-is.\n";
    out += e.source();
    const vec3f palette[] = {detail::albedo_of<Kinds>()...};
    out += "vec3 krs_albedo(uint kind) {\n";
    for (std::size_t i = 0; i < sizeof...(Kinds); ++i)
        out += "    if (kind == " + std::to_string(i) + "u) return " + vec3_literal(palette[i]) + ";\n";
    out += "    return vec3(0.5);\n}\n";
    out += "const vec3 KRS_EYE = " + vec3_literal(v.eye) + ";\n";
    out += "const vec3 KRS_FORWARD = " + vec3_literal(v.forward) + ";\n";
    out += "const vec3 KRS_RIGHT = " + vec3_literal(v.right) + ";\n";
    out += "const vec3 KRS_UP = " + vec3_literal(v.up) + ";\n";
    out += "const vec3 KRS_TO_LIGHT = " + vec3_literal(v.to_light) + ";\n";
    out += "const float KRS_TAN_HALF_FOV = " + float_literal(v.tan_half_fov) + ";\n";
    out += "const float KRS_MAX_DISTANCE = " + float_literal(v.max_distance) + ";\n";
    out += "const int KRS_MAX_STEPS = " + std::to_string(v.max_steps) + ";\n";
    out += "const float KRS_THRESHOLD_FLOOR = " + float_literal(v.threshold_floor) + ";\n";
    out += "const float KRS_FOOTPRINT_SCALE = " + float_literal(v.footprint_scale) + ";\n";
    out += "const float KRS_BAND_PIXELS = " + float_literal(v.band_pixels) + ";\n";
    const bounding_box box = s.bound_box();
    out += std::string("const bool KRS_CLIP = ") + (box.is_bounded() ? "true" : "false") + ";\n";
    out += "const vec3 KRS_BOX_LO = " + vec3_literal(box.is_bounded() ? box.lo : vec3f{}) + ";\n";
    out += "const vec3 KRS_BOX_HI = " + vec3_literal(box.is_bounded() ? box.hi : vec3f{}) + ";\n";
    out += "float krs_scene(vec3 p) { return " + scene + "(p); }\n";
    out += R"(// Sphere tracing from t0 to t1; a hit when the distance drops under footprint * t + floor + bias.
float krs_trace(vec3 origin, vec3 direction, float t0, float t1, float footprint, float bias, out bool found) {
    float t = t0;
    found = false;
    for (int i = 0; i < KRS_MAX_STEPS; ++i) {
        float d = krs_scene(origin + direction * t);
        if (d < footprint * t + KRS_THRESHOLD_FLOOR + bias) { found = true; return t; }
        t += d;
        if (!(t <= t1)) return t;
    }
    return t;
}
// [t0, t1] cut to the scene's box grown by the largest threshold a stop in it can have (a stop
// within threshold(t) of the box lies at t <= (reach + floor) / (1 - footprint)); false when the
// ray misses it.
bool krs_clip(vec3 origin, vec3 direction, float footprint, inout float t0, inout float t1) {
    if (!KRS_CLIP || !(footprint < 0.5)) return true;
    float reach = length(max(abs(KRS_BOX_LO - origin), abs(KRS_BOX_HI - origin)));
    float grow = footprint * ((reach + KRS_THRESHOLD_FLOOR) / (1.0 - footprint)) + KRS_THRESHOLD_FLOOR + 1e-6 * reach;
    vec3 lo = KRS_BOX_LO - vec3(grow);
    vec3 hi = KRS_BOX_HI + vec3(grow);
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
vec3 krs_sky(vec3 direction) {
    return mix(vec3(0.78, 0.86, 0.95), vec3(0.36, 0.55, 0.88), clamp(direction.y, 0.0, 1.0));
}
void mainImage(out vec4 fragColor, in vec2 fragCoord) {
    float scale = KRS_TAN_HALF_FOV * 2.0 / iResolution.y;
    float sx = (fragCoord.x - 0.5 * iResolution.x) * scale;
    float sy = (fragCoord.y - 0.5 * iResolution.y) * scale;
    vec3 d = KRS_FORWARD + KRS_RIGHT * sx + KRS_UP * sy;
    vec3 direction = d / sqrt(dot(d, d));
    float footprint = KRS_FOOTPRINT_SCALE * scale;
    bool found = false;
    float t0 = 0.0;
    float t1 = KRS_MAX_DISTANCE;
    float t = KRS_MAX_DISTANCE;
    if (krs_clip(KRS_EYE, direction, footprint, t0, t1)) t = krs_trace(KRS_EYE, direction, t0, t1, footprint, 0.0, found);
    vec3 color = krs_sky(direction);
    if (found) {
        vec3 p = KRS_EYE + direction * t;
        float band = KRS_BAND_PIXELS * scale * t + 1e-6;
        krs_kernel_shading s = )" + scene + R"(_shade(p, KRS_TO_LIGHT, -direction, band);
        float diffuse = max(dot(s.normal, s.light), 0.0);
        if (diffuse > 0.0) {
            float hitThreshold = footprint * t + KRS_THRESHOLD_FLOOR;
            bool shadowed;
            // Start where the surface is at least two thresholds away along the light
            // (t cos >= 2 threshold): no self-shadowing acne at grazing light.
            krs_trace(p, KRS_TO_LIGHT, hitThreshold * (1.0 + 2.0 / max(diffuse, 0.1)), KRS_MAX_DISTANCE, footprint, hitThreshold, shadowed);
            if (shadowed) diffuse = 0.0;
        }
        color = krs_albedo(s.kind) * (0.25 + 0.75 * diffuse);
    }
    fragColor = vec4(sqrt(clamp(color, 0.0, 1.0)), found ? 1.0 : 0.0);
}
)";
    // The program's own names (krs_scene, krs_trace, krs_sky, ...) share the scene's prefix: a scene
    // named "sky" or "scene" would define one of them twice.
    const std::string again = twice_declared(out);
    if (!again.empty())
        throw invalid_parameter("glsl.shadertoy.name",
                                "makes " + again + ", which the Shadertoy program declares too: choose another name", name);
    return out;
}

namespace detail {
template <field F>
float trace_reference(const F& f, const vec3f& origin, const vec3f& direction, float t0, float t1, float footprint,
                      float bias, const view& v, bool& found)
{
    float t = t0;
    found = false;
    for (int i = 0; i < v.max_steps; ++i) {
        const float d = f.distance(origin + direction * t);
        if (d < footprint * t + v.threshold_floor + bias) {
            found = true;
            return t;
        }
        t += d;
        if (!(t <= t1)) return t;
    }
    return t;
}
} // namespace detail

// The Shadertoy program's math in C++ on the CPU field: RGBA rows bottom-up (as glReadPixels
// returns them), width x height x 4 floats. `clip_to_box` false traces primary rays unclipped
// (what the program did before it clipped them, for comparison).
template <class M, class... Kinds>
std::vector<float> render_reference(const basic_sequence<M, Kinds...>& s, const view& v, int width, int height,
                                    bool clip_to_box = true)
{
    std::vector<float> rgba(std::size_t(width) * std::size_t(height) * 4);
    const float w = float(width), h = float(height);
    const float scale = v.tan_half_fov * 2.0f / h;
    const float footprint = v.footprint_scale * scale;
    trace_options clip_options;
    clip_options.pixel_footprint = footprint;
    clip_options.threshold_floor = v.threshold_floor;
    const box_clip clip = clip_to_box ? box_clip(s.bound_box(), v.eye, clip_options) : box_clip();
    for (int j = 0; j < height; ++j)
        for (int i = 0; i < width; ++i) {
            const float sx = (float(i) + 0.5f - 0.5f * w) * scale;
            const float sy = (float(j) + 0.5f - 0.5f * h) * scale;
            const vec3f d = v.forward + v.right * sx + v.up * sy;
            const vec3f direction = d / std::sqrt(dot(d, d));
            bool found = false;
            float t0 = 0.0f, t1 = v.max_distance;
            clip.apply(ray<float>{v.eye, direction}, t0, t1);
            const float t = t1 < t0 ? v.max_distance
                                    : detail::trace_reference(s, v.eye, direction, t0, t1, footprint, 0.0f, v, found);
            const float y = std::clamp(direction.y, 0.0f, 1.0f);
            vec3f color = vec3f{0.78f, 0.86f, 0.95f} + (vec3f{0.36f, 0.55f, 0.88f} - vec3f{0.78f, 0.86f, 0.95f}) * y;
            if (found) {
                const vec3f p = v.eye + direction * t;
                const float band = v.band_pixels * scale * t + 1e-6f;
                const kernel_space_shading<float> k = shade_in_kernel_space(s, p, v.to_light, -direction, band);
                float diffuse = std::max(dot(k.normal, k.light), 0.0f);
                if (diffuse > 0.0f) {
                    const float hit_threshold = footprint * t + v.threshold_floor;
                    bool shadowed = false;
                    detail::trace_reference(s, p, v.to_light, hit_threshold * (1.0f + 2.0f / std::max(diffuse, 0.1f)),
                                            v.max_distance, footprint, hit_threshold, v, shadowed);
                    if (shadowed) diffuse = 0.0f;
                }
                color = albedo(s, std::uint32_t(s.kernels()[k.where.kernel].index())) * (0.25f + 0.75f * diffuse);
            }
            float* out = &rgba[(std::size_t(j) * std::size_t(width) + std::size_t(i)) * 4];
            out[0] = std::sqrt(std::clamp(color.x, 0.0f, 1.0f));
            out[1] = std::sqrt(std::clamp(color.y, 0.0f, 1.0f));
            out[2] = std::sqrt(std::clamp(color.z, 0.0f, 1.0f));
            out[3] = found ? 1.0f : 0.0f;
        }
    return rgba;
}

} // namespace krs::glsl

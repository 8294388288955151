#pragma once
// A whole Shadertoy program for a KRS scene, or for any field: paste the text into Shadertoy's
// Image tab as-is.
//
// The program is assembled from the library's own pieces and their GLSL twins, so it draws what
// the C++ tracer draws: the camera and its turn by iTime and the pointer (krs::pinhole_camera,
// krs/trace/camera.hpp), the hit threshold (krs::hit_threshold), the primary ray clipped to the
// field's box (krs::box_clip, krs/trace/box_clip.hpp) and traced by sphere tracing (krs::march_advance
// and krs::sphere_trace, krs/trace/sphere_trace.hpp), then shaded, with one hard shadow ray that
// inherits the hit's threshold (added to its own pixel cone) and starts far enough along the light
// to clear the surface. Two ways to shade:
//
//   - a KRS sequence: Lambert in kernel space (Algorithm 2: the kernel's own normal against the
//     light carried down the mirrors, blended over a band of `band_pixels` footprints), with an
//     albedo per kernel type (each kind's `default_albedo`, or the caller's palette);
//   - any other field (a warp, KIFS, a log-spherical shell, ...): Lambert with the normal of the
//     field's tetrahedral gradient (krs::gradient_normal) at a step of `normal_step` hit
//     thresholds, turned toward the eye, and one albedo for the whole scene.
//
// `render_reference` below is the program on the CPU: the camera's primary_ray, box_clip and
// sphere_trace (the library's tracer, whose steps are the GLSL's float operations in the same order:
// krs::glsl tests build it with -ffp-contract=off), so a GPU frame can be held against it;
// `camera.turned(iTime, iMouse.x, iMouse.y)` is the camera the program uses at a given iTime and
// iMouse. Alpha is 1 on every pixel: in a WebGL page with premultiplied alpha (the default) a 0 on
// the sky would let the page show through. `framebuffer_byte` stores a channel as an 8-bit
// framebuffer does.

#include "krs/glsl/emitter.hpp"
#include "krs/kernels/kernels.hpp"
#include "krs/sequence.hpp"
#include "krs/shade/kernel_light.hpp"
#include "krs/shade/normal.hpp"
#include "krs/trace/box_clip.hpp"
#include "krs/trace/camera.hpp"
#include "krs/trace/sphere_trace.hpp"

#include <algorithm>
#include <cmath>
#include <concepts>
#include <limits>
#include <numbers>
#include <string>
#include <vector>

namespace krs::glsl {

// What a Shadertoy program bakes besides its camera: the light, the march's limits and threshold,
// and the widths its shading works at.
struct shadertoy_options {
    vec3f to_light{0, 1, 0};      // unit, world
    float max_distance = 100.0f;
    int max_steps = 256;
    float threshold_floor = 1e-5f;
    float footprint_scale = 0.5f; // hit threshold in pixel footprints
    float band_pixels = 4.0f;     // Algorithm 2 band width in pixel footprints (sequences)
    float normal_step = 0.5f;     // gradient step in hit thresholds (other fields), as krs_fractals

    // The light toward `toward_light` (normalized in double and rounded once, as the constants
    // store it) and the far limit.
    static shadertoy_options lit(const vec3f& toward_light, float max_distance)
    {
        shadertoy_options o;
        o.to_light = vec3f(normalize(vec3d(require_direction("shadertoy_options.to_light", toward_light))));
        o.max_distance = require_positive("shadertoy_options.max_distance", max_distance);
        return o;
    }

    // Throws invalid_parameter naming the first member that would make the program or its
    // reference draw NaN or nothing: shadertoy and render_reference call it.
    const shadertoy_options& validate() const
    {
        const auto at_least = [](const char* name, float x, float lowest, bool strictly, const char* rule) {
            if (!std::isfinite(x)) throw invalid_parameter(name, "must be finite", krs::detail::to_text(x));
            if (strictly ? !(x > lowest) : !(x >= lowest)) throw invalid_parameter(name, rule, krs::detail::to_text(x));
        };
        require_finite("shadertoy_options.to_light", to_light);
        if (!(std::abs(length(vec3d(to_light)) - 1.0) <= 1e-4))
            throw invalid_parameter("shadertoy_options.to_light", "must be a unit vector");
        at_least("shadertoy_options.max_distance", max_distance, 0.0f, true, "must be > 0");
        if (max_steps < 1 || max_steps > 100000)
            throw invalid_parameter("shadertoy_options.max_steps", "must be in [1, 100000]", std::to_string(max_steps));
        at_least("shadertoy_options.threshold_floor", threshold_floor, 0.0f, true, "must be > 0");
        at_least("shadertoy_options.footprint_scale", footprint_scale, 0.0f, false, "must be >= 0");
        at_least("shadertoy_options.band_pixels", band_pixels, 0.0f, true, "must be > 0");
        at_least("shadertoy_options.normal_step", normal_step, 0.0f, true, "must be > 0 (a step of 0 has no gradient)");
        return *this;
    }

    // The primary rays' trace options through `camera` (the program's KRS_FOOTPRINT_SCALE *
    // krs_pixel_footprint(iResolution.y) for a camera of the frame's size).
    trace_options primary(const pinhole_camera& camera) const
    {
        trace_options t;
        t.pixel_footprint = footprint_scale * camera.pixel_footprint();
        t.threshold_floor = threshold_floor;
        t.max_distance = max_distance;
        t.max_steps = max_steps;
        return t;
    }
};

// A channel in [0, 1] as an 8-bit framebuffer stores it: round(255 v) to the nearest integer, ties
// to even (GPUs convert to unorm8 so; std::lround's ties away from zero stored 122.5 as 123 where
// both ANGLE back ends store 122). What glsl_export --reference writes and the tests compare.
inline unsigned char framebuffer_byte(float v)
{
    return (unsigned char)std::nearbyint(255.0f * std::clamp(v, 0.0f, 1.0f));
}

namespace detail {
template <class T>
inline constexpr bool is_sequence = false;
template <class M, class... Kinds>
inline constexpr bool is_sequence<basic_sequence<M, Kinds...>> = true;

// Names K in the error when a sequence without a palette holds a kernel kind with no colour.
template <class K>
struct kernel_without_default_albedo {
    static_assert(sizeof(K) == 0, "krs::glsl: this kernel kind has no `static constexpr vec3f default_albedo`: give "
                                  "it one, or pass a palette; the kind is the template argument");
};
template <class K>
constexpr vec3f default_albedo_of()
{
    if constexpr (requires { { K::default_albedo } -> std::convertible_to<vec3f>; })
        return K::default_albedo;
    else
        return vec3f(float(sizeof(kernel_without_default_albedo<K>)));
}

// The literals of the program's constants (the emitter's writing interface's `literal`).
struct literals {
    static std::string literal(float v) { return float_literal(v); }
};
} // namespace detail

// Whether F is shaded in kernel space (a KRS sequence) or by its gradient (any other field).
template <class F>
concept kernel_shaded = detail::is_sequence<F>;

// The albedo of each kernel type of sequence S, indexed as krs_kernel_shading::kind: `palette`
// when given (one finite colour per type, e.g. green grass blades where a torus_capsule would
// be bark), else each kind's default_albedo.
template <class M, class... Kinds>
std::vector<vec3f> palette_of(const basic_sequence<M, Kinds...>&, const std::vector<vec3f>& palette = {})
{
    if (palette.empty()) return {detail::default_albedo_of<Kinds>()...};
    if (palette.size() != sizeof...(Kinds))
        throw invalid_parameter("glsl.palette", "must hold one colour per kernel type of the sequence (" +
                                                    std::to_string(sizeof...(Kinds)) + ")",
                                std::to_string(palette.size()) + " colours");
    for (const vec3f& c : palette) require_finite("glsl.palette", c);
    return palette;
}

namespace detail {

// The program's constants and the functions every program shares, after the field's code: the
// camera, the threshold, the march, the clip (each the library's GLSL twin), the shadow and the
// sky. `surface` defines `vec3 krs_surface(vec3 p, vec3 direction, float t, float scale, float
// footprint)`, the colour of a hit; mainImage is appended last.
template <field F>
std::string program(const F& f, const pinhole_camera& camera, const shadertoy_options& o, const std::string& name,
                    const std::string& library, const std::string& surface)
{
    o.validate();
    const std::string orbit = camera.orbit().rate() == 0.0f ? "iTime leaves the camera still"
                                                             : "iTime orbits the camera (one turn per " +
                                                                   float_literal(camera.orbit().seconds) + " s)";
    std::string out = "// krs scene '" + name + "' for Shadertoy: paste into the Image tab as-is. " + orbit +
                      ",\n// the pointer's position (click or drag) turns it, and pointer up raises it. Alpha is 1 everywhere.\n";
    out += library;
    out += camera.glsl_source<literals>();
    out += "const vec3 KRS_TO_LIGHT = " + vec3_literal(o.to_light) + ";\n";
    out += "const float KRS_MAX_DISTANCE = " + float_literal(o.max_distance) + ";\n";
    out += "const int KRS_MAX_STEPS = " + std::to_string(o.max_steps) + ";\n";
    out += "const float KRS_THRESHOLD_FLOOR = " + float_literal(o.threshold_floor) + ";\n";
    out += "const float KRS_FOOTPRINT_SCALE = " + float_literal(o.footprint_scale) + ";\n";
    const bounding_box box = field_box(f);
    out += std::string("const bool KRS_CLIP = ") + (box.is_bounded() ? "true" : "false") + ";\n";
    out += "const vec3 KRS_BOX_LO = " + vec3_literal(box.is_bounded() ? box.lo : vec3f{}) + ";\n";
    out += "const vec3 KRS_BOX_HI = " + vec3_literal(box.is_bounded() ? box.hi : vec3f{}) + ";\n";
    out += "float krs_scene(vec3 p) { return krs_" + name + "(p); }\n";
    out += hit_threshold_glsl;
    out += march_glsl;
    out += sphere_trace_glsl("krs_trace", "krs_scene");
    out += box_clip_glsl;
    out += R"(// The Lambert term `diffuse` at the hit p (ray depth t), or 0 when the light is blocked: the
// shadow ray starts where the surface is at least two thresholds away along the light
// (t cos >= 2 threshold), so there is no self-shadowing acne at grazing light, and adds the hit's
// threshold to its own.
float krs_shadow(vec3 p, float t, float footprint, float diffuse) {
    if (diffuse > 0.0) {
        float hitThreshold = krs_hit_threshold(footprint, t, KRS_THRESHOLD_FLOOR);
        float start = hitThreshold * (1.0 + 2.0 / max(diffuse, 0.1));
        if (krs_trace(p, KRS_TO_LIGHT, start, KRS_MAX_DISTANCE, footprint, KRS_THRESHOLD_FLOOR, hitThreshold,
                      KRS_MAX_STEPS).found)
            diffuse = 0.0;
    }
    return diffuse;
}
vec3 krs_sky(vec3 direction) {
    return mix(vec3(0.78, 0.86, 0.95), vec3(0.36, 0.55, 0.88), clamp(dot(direction, KRS_VERTICAL), 0.0, 1.0));
}
)";
    out += surface;
    out += R"(void mainImage(out vec4 fragColor, in vec2 fragCoord) {
    krs_view c = krs_camera(iTime, iMouse, iResolution.xy);
    vec3 direction = krs_primary_direction(c, fragCoord, iResolution.xy);
    float scale = krs_pixel_footprint(iResolution.y);
    float footprint = KRS_FOOTPRINT_SCALE * scale;
    float t0 = 0.0;
    float t1 = KRS_MAX_DISTANCE;
    krs_march m = krs_march(c.eye, direction, 0.0, 0.0, 0.0, false, false, 0);
    if (!KRS_CLIP || krs_box_clip(KRS_BOX_LO, KRS_BOX_HI, c.eye, direction, footprint, KRS_THRESHOLD_FLOOR, t0, t1))
        m = krs_trace(c.eye, direction, t0, t1, footprint, KRS_THRESHOLD_FLOOR, 0.0, KRS_MAX_STEPS);
    vec3 color = m.found ? krs_surface(c.eye + direction * m.t, direction, m.t, scale, footprint) : krs_sky(direction);
    fragColor = vec4(sqrt(clamp(color, 0.0, 1.0)), 1.0);
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

} // namespace detail

// A KRS sequence: Algorithm 2 Lambert, albedo by kernel type (palette_of).
template <class M, class... Kinds>
std::string shadertoy(const basic_sequence<M, Kinds...>& s, const pinhole_camera& camera, const shadertoy_options& o,
                      const std::string& name, const std::vector<vec3f>& palette_by_type = {})
{
    o.validate();
    emitter e({.target = target::shadertoy, .mode = data_mode::constants, .data_name = name + "_data"});
    const std::string scene = e.add(s, name); // krs_NAME
    std::string library = e.source();
    const std::vector<vec3f> palette = palette_of(s, palette_by_type);
    library += "vec3 krs_albedo(uint kind) {\n";
    for (std::size_t i = 0; i < sizeof...(Kinds); ++i)
        library += "    if (kind == " + std::to_string(i) + "u) return " + vec3_literal(palette[i]) + ";\n";
    library += "    return vec3(0.5);\n}\n";
    library += "const float KRS_BAND_PIXELS = " + float_literal(o.band_pixels) + ";\n";
    const std::string surface = R"(// Lambert in kernel space (Algorithm 2) over a band of KRS_BAND_PIXELS footprints at depth t
// (krs::smoothing_threshold).
vec3 krs_surface(vec3 p, vec3 direction, float t, float scale, float footprint) {
    float band = krs_hit_threshold(KRS_BAND_PIXELS * scale, t, 1e-6);
    krs_kernel_shading s = )" + scene + R"(_shade(p, KRS_TO_LIGHT, -direction, band);
    float diffuse = krs_shadow(p, t, footprint, max(dot(s.normal, s.light), 0.0));
    return krs_albedo(s.kind) * (0.25 + 0.75 * diffuse);
}
)";
    return detail::program(s, camera, o, name, library, surface);
}

// Any other field: Lambert with the normal of the field's tetrahedral gradient, one albedo.
template <field F>
    requires(!kernel_shaded<F>)
std::string shadertoy(const F& f, const pinhole_camera& camera, const shadertoy_options& o, const std::string& name,
                      const vec3f& albedo)
{
    // Shaded by the gradient: the distance is all the program calls (a sequence inside a warp would
    // bring its _locate and _shade, and the krs_location structs, otherwise).
    emitter e({.target = target::shadertoy, .mode = data_mode::constants, .data_name = name + "_data", .distance_only = true});
    o.validate();
    e.add(f, name);
    std::string library = e.source();
    library += "const vec3 KRS_ALBEDO = " + vec3_literal(require_finite("glsl.shadertoy.albedo", albedo)) + ";\n";
    library += "const float KRS_NORMAL_STEP = " + float_literal(o.normal_step) + ";\n";
    library += "const float KRS_NORMAL_STEP_FLOOR = " +
               float_literal(32.0f * std::numeric_limits<float>::epsilon()) + "; // of the largest coordinate\n";
    const std::string surface = R"(// The field's tetrahedral gradient with step h (krs::gradient_normal, operation for operation).
vec3 krs_normal(vec3 p, float h) {
    float largest = max(max(abs(p.x), abs(p.y)), abs(p.z));
    h = max(h, KRS_NORMAL_STEP_FLOOR * largest);
    vec3 k0 = vec3(1.0, -1.0, -1.0);
    vec3 k1 = vec3(-1.0, -1.0, 1.0);
    vec3 k2 = vec3(-1.0, 1.0, -1.0);
    vec3 k3 = vec3(1.0, 1.0, 1.0);
    vec3 g = k0 * krs_scene(p + k0 * h) + k1 * krs_scene(p + k1 * h) + k2 * krs_scene(p + k2 * h) + k3 * krs_scene(p + k3 * h);
    float len = sqrt(dot(g, g));
    return len > 0.0 ? g / len : vec3(0.0, 0.0, 1.0);
}
// Lambert with the gradient normal at a step of KRS_NORMAL_STEP hit thresholds, turned to the eye.
vec3 krs_surface(vec3 p, vec3 direction, float t, float scale, float footprint) {
    vec3 n = krs_normal(p, KRS_NORMAL_STEP * krs_hit_threshold(footprint, t, KRS_THRESHOLD_FLOOR));
    if (dot(n, direction) > 0.0) n = -n;
    float diffuse = krs_shadow(p, t, footprint, max(dot(n, KRS_TO_LIGHT), 0.0));
    return KRS_ALBEDO * (0.25 + 0.75 * diffuse);
}
)";
    return detail::program(f, camera, o, name, library, surface);
}

namespace detail {
// krs_shadow on the CPU: the library's sphere_trace from the lifted start, with the hit's
// threshold as the lane's bias over the primary rays' pixel cone.
template <field F>
float shadow_reference(const F& f, const vec3f& p, float t, const trace_options& primary, float diffuse,
                       const vec3f& to_light)
{
    if (diffuse > 0.0f) {
        const float hit = primary.threshold(t);
        const float start = hit * (1.0f + 2.0f / std::max(diffuse, 0.1f));
        if (sphere_trace(f, ray<float>{p, to_light}, start, primary.max_distance, primary, hit).found) diffuse = 0.0f;
    }
    return diffuse;
}

// mainImage on the CPU, with `surface(p, direction, t, scale, footprint)` as krs_surface: RGBA rows
// bottom-up (as glReadPixels returns them), width x height x 4 floats. The rays are the camera's
// primary rays through the pixel centers (row j from the bottom is y = height - j - 1/2 from the
// top), clipped by box_clip and traced by sphere_trace.
template <field F, class Surface>
std::vector<float> render_frame(const F& f, const pinhole_camera& view, const shadertoy_options& o, int width,
                                int height, bool clip_to_box, const Surface& surface)
{
    o.validate();
    // A frame as large as a GL framebuffer may be; larger ones are a typo, not a picture.
    if (width < 1 || width > 16384)
        throw invalid_parameter("glsl.render_reference.width", "must be in [1, 16384]", std::to_string(width));
    if (height < 1 || height > 16384)
        throw invalid_parameter("glsl.render_reference.height", "must be in [1, 16384]", std::to_string(height));
    const pinhole_camera camera = view.with_size(width, height);
    std::vector<float> rgba(std::size_t(width) * std::size_t(height) * 4);
    const float h = float(height);
    const float scale = camera.pixel_footprint();
    const trace_options primary = o.primary(camera);
    const box_clip clip = clip_to_box ? box_clip(field_box(f), camera.eye(), primary) : box_clip();
    for (int j = 0; j < height; ++j)
        for (int i = 0; i < width; ++i) {
            const ray<float> r = camera.primary_ray(float(i) + 0.5f, h - (float(j) + 0.5f));
            float t0 = 0.0f, t1 = o.max_distance;
            clip.apply(r, t0, t1);
            const hit<float> found = sphere_trace(f, r, t0, t1, primary);
            const float y = std::clamp(dot(r.direction, camera.vertical()), 0.0f, 1.0f);
            vec3f color = vec3f{0.78f, 0.86f, 0.95f} + (vec3f{0.36f, 0.55f, 0.88f} - vec3f{0.78f, 0.86f, 0.95f}) * y;
            if (found.found)
                color = surface(point_at(r, found.t), r.direction, found.t, scale, primary);
            float* out = &rgba[(std::size_t(j) * std::size_t(width) + std::size_t(i)) * 4];
            out[0] = std::sqrt(std::clamp(color.x, 0.0f, 1.0f));
            out[1] = std::sqrt(std::clamp(color.y, 0.0f, 1.0f));
            out[2] = std::sqrt(std::clamp(color.z, 0.0f, 1.0f));
            out[3] = 1.0f;
        }
    return rgba;
}
} // namespace detail

// The Shadertoy program of a sequence in C++ on the CPU field: RGBA rows bottom-up (as
// glReadPixels returns them), width x height x 4 floats, for `camera` (the program's at iTime = 0
// and no drag; camera.turned gives the others) at the frame's size. `clip_to_box` false traces
// primary rays unclipped (what the program did before it clipped them, for comparison).
template <class M, class... Kinds>
std::vector<float> render_reference(const basic_sequence<M, Kinds...>& s, const pinhole_camera& camera,
                                    const shadertoy_options& o, int width, int height, bool clip_to_box = true,
                                    const std::vector<vec3f>& palette_by_type = {})
{
    const std::vector<vec3f> palette = palette_of(s, palette_by_type);
    return detail::render_frame(
        s, camera, o, width, height, clip_to_box,
        [&](const vec3f& p, const vec3f& direction, float t, float scale, const trace_options& primary) {
            const float band = smoothing_threshold(t, scale, o.band_pixels, 1e-6f);
            const kernel_space_shading<float> k = shade_in_kernel_space(s, p, o.to_light, -direction, band);
            const float diffuse =
                detail::shadow_reference(s, p, t, primary, std::max(dot(k.normal, k.light), 0.0f), o.to_light);
            return palette[s.kernels()[k.where.kernel].index()] * (0.25f + 0.75f * diffuse);
        });
}

// The Shadertoy program of any other field in C++ on the CPU field (as above).
template <field F>
    requires(!kernel_shaded<F>)
std::vector<float> render_reference(const F& f, const pinhole_camera& camera, const shadertoy_options& o,
                                    const vec3f& albedo, int width, int height, bool clip_to_box = true)
{
    return detail::render_frame(
        f, camera, o, width, height, clip_to_box,
        [&](const vec3f& p, const vec3f& direction, float t, float, const trace_options& primary) {
            vec3f n = gradient_normal(f, p, o.normal_step * primary.threshold(t));
            if (dot(n, direction) > 0.0f) n = -n;
            const float diffuse =
                detail::shadow_reference(f, p, t, primary, std::max(dot(n, o.to_light), 0.0f), o.to_light);
            return albedo * (0.25f + 0.75f * diffuse);
        });
}

} // namespace krs::glsl

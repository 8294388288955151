#pragma once
// A whole Shadertoy program for a KRS scene, or for any field: paste the text into Shadertoy's
// Image tab as-is.
//
// mainImage builds the pinhole camera ray of the pixel (as krs::pinhole_camera::primary_ray does,
// with the vertical field of view fixed and the width following iResolution), sphere traces the
// field with the pixel-footprint threshold (footprint * t + floor, as trace_options::threshold),
// shades the hit and casts a hard shadow ray that inherits the hit's threshold and starts far
// enough along the light to clear the surface. A primary ray is first clipped to the field's
// bounding box (krs::field_box; none for an unbounded field), grown by the largest hit threshold
// a stop in it can have, as krs::box_clip does (a flat forest fills a small part of the picture
// and of its bounding sphere). Two ways to shade:
//
//   - a KRS sequence: Lambert in kernel space (Algorithm 2: the kernel's own normal against the
//     light carried down the mirrors, blended over a band of `band_pixels` footprints), with an
//     albedo per kernel type;
//   - any other field (a warp, KIFS, a log-spherical shell, ...): Lambert with the normal of the
//     field's tetrahedral gradient (krs::gradient_normal) at a step of `normal_step` hit
//     thresholds, turned toward the eye, and one albedo for the whole scene.
//
// The camera moves with Shadertoy's inputs, about the point it looks at (view::pivot) and the
// scene's vertical (view::vertical, the look-at's up: y for most scenes, the lotus's axis z).
// iTime turns it about the vertical, one turn every `orbit_seconds` (60 by default; 0 keeps it
// still). A click or drag sets a turn as well, from the pointer's position, not its motion: across
// the frame's width a full turn about the vertical; across its height a tilt of up to +-60 degrees
// about the camera's right axis, pointer up raising the eye. The tilt keeps the eye's elevation
// (seen from the pivot) within [min_elevation, max_elevation] degrees (5 to 85 by default; widened
// to include the baked elevation), so the eye stays above a ground and never passes the pole. The
// centre of the frame is no turn, and before the first click (iMouse = 0) the mouse does nothing.
// The turn is reduced to [-pi, pi] (mobile GPUs' sin and cos lose accuracy far outside it). The
// baked basis is rotated rigidly (Rodrigues), never recomputed from a look-at, so it cannot
// degenerate, and with no turn at all (iTime = 0, no click) the program uses the baked camera
// unchanged.
//
// `render_reference` below is the same math in C++ on the CPU field, pixel for pixel, with the
// same float operations in the same order (krs::glsl tests build it with -ffp-contract=off), so a
// GPU frame can be held against it; `shadertoy_view` is the camera the program uses at a given
// iTime and iMouse. Alpha is 1 on every pixel: in a WebGL page with premultiplied alpha (the
// default) a 0 on the sky would let the page show through.

#include "krs/glsl/emitter.hpp"
#include "krs/kernels/kernels.hpp"
#include "krs/sequence.hpp"
#include "krs/shade/kernel_light.hpp"
#include "krs/shade/normal.hpp"
#include "krs/trace/box_clip.hpp"

#include <algorithm>
#include <cmath>
#include <concepts>
#include <limits>
#include <numbers>
#include <string>
#include <vector>

namespace krs::glsl {

struct view {
    vec3f eye{0, 0, -5}, forward{0, 0, 1}, right{1, 0, 0}, up{0, 1, 0};
    vec3f pivot{0, 0, 0};       // what iTime and the mouse orbit about (look_at's target)
    vec3f vertical{0, 1, 0};    // unit: the orbit's axis, what elevation and the sky's gradient follow
    float tan_half_fov = 0.5f;
    vec3f to_light{0, 1, 0};    // unit, world
    float max_distance = 100.0f;
    int max_steps = 256;
    float threshold_floor = 1e-5f;
    float footprint_scale = 0.5f; // hit threshold in pixel footprints
    float band_pixels = 4.0f;     // Algorithm 2 band width in pixel footprints (sequences)
    float normal_step = 0.5f;     // gradient step in hit thresholds (other fields), as krs_fractals
    float orbit_seconds = 60.0f;  // one turn about the pivot per this many seconds of iTime; 0: still
    // The elevation (degrees, the eye seen from the pivot above the plane across `vertical`) a
    // mouse tilt may reach; the baked camera's own elevation is always allowed.
    float min_elevation = 5.0f, max_elevation = 85.0f;

    // Camera basis computed in double and rounded once (as the GLSL constants store it); up_hint
    // is the vertical.
    static view look_at(const vec3f& eye, const vec3f& target, const vec3f& up_hint, float vertical_fov_degrees,
                        const vec3f& to_light, float max_distance)
    {
        view v;
        v.eye = require_finite("view.eye", eye);
        v.pivot = require_finite("view.target", target);
        const vec3d f = normalize(vec3d(require_direction("view.target - view.eye", target - eye)));
        const vec3d vertical = normalize(vec3d(require_direction("view.up", up_hint)));
        const vec3d r = cross(f, vertical);
        if (!(length(r) > 1e-6)) throw invalid_parameter("view.up", "must not be parallel to the view direction");
        const vec3d rn = normalize(r);
        v.forward = vec3f(f);
        v.right = vec3f(rn);
        v.up = vec3f(cross(rn, f));
        v.vertical = vec3f(vertical);
        v.tan_half_fov = float(std::tan(0.5 * double(vertical_fov_degrees) * std::numbers::pi / 180.0));
        v.to_light = vec3f(normalize(vec3d(require_direction("view.to_light", to_light))));
        v.max_distance = require_positive("view.max_distance", max_distance);
        return v;
    }

    // Throws invalid_parameter naming the first member that would make the program or its
    // reference draw NaN or nothing: shadertoy, render_reference and shadertoy_view call it.
    void validate() const
    {
        const auto finite = [](const char* name, float x) {
            if (!std::isfinite(x)) throw invalid_parameter(name, "must be finite", krs::detail::to_text(x));
        };
        const auto at_least = [&](const char* name, float x, float lowest, bool strictly, const char* rule) {
            finite(name, x);
            if (strictly ? !(x > lowest) : !(x >= lowest)) throw invalid_parameter(name, rule, krs::detail::to_text(x));
        };
        const auto unit = [](const char* name, const vec3f& d) {
            require_finite(name, d);
            if (!(std::abs(length(vec3d(d)) - 1.0) <= 1e-4)) throw invalid_parameter(name, "must be a unit vector");
        };
        require_finite("view.eye", eye);
        require_finite("view.pivot", pivot);
        unit("view.forward", forward);
        unit("view.right", right);
        unit("view.up", up);
        unit("view.vertical", vertical);
        unit("view.to_light", to_light);
        at_least("view.tan_half_fov", tan_half_fov, 0.0f, true, "must be > 0");
        at_least("view.max_distance", max_distance, 0.0f, true, "must be > 0");
        if (max_steps < 1 || max_steps > 100000)
            throw invalid_parameter("view.max_steps", "must be in [1, 100000]", std::to_string(max_steps));
        at_least("view.threshold_floor", threshold_floor, 0.0f, true, "must be > 0");
        at_least("view.footprint_scale", footprint_scale, 0.0f, false, "must be >= 0");
        at_least("view.band_pixels", band_pixels, 0.0f, true, "must be > 0");
        at_least("view.normal_step", normal_step, 0.0f, true, "must be > 0 (a step of 0 has no gradient)");
        at_least("view.orbit_seconds", orbit_seconds, 0.0f, false, "must be finite and >= 0 (0: no orbit)");
        finite("view.min_elevation", min_elevation);
        finite("view.max_elevation", max_elevation);
        if (!(min_elevation > -90.0f && min_elevation <= max_elevation && max_elevation < 90.0f))
            throw invalid_parameter("view.min_elevation, view.max_elevation", "must satisfy -90 < min <= max < 90",
                                    krs::detail::to_text(min_elevation) + ", " + krs::detail::to_text(max_elevation));
    }

    // Radians of turn per second of iTime (the program's KRS_ORBIT_RATE), of a validated view.
    float orbit_rate() const
    {
        return orbit_seconds == 0.0f ? 0.0f : float(2.0 * std::numbers::pi / double(orbit_seconds));
    }
};

namespace detail {
// Full turn and largest tilt of the pointer (radians): the program's literals, as floats.
inline constexpr float drag_turn = float(2.0 * std::numbers::pi);
inline constexpr float drag_tilt = float(2.0 * std::numbers::pi / 3.0); // +-60 degrees over the height

// v turned by the angle of cosine c and sine s about the unit axis k (Rodrigues); exactly v when
// c = 1 and s = 0. The program's krs_turn, operation for operation.
inline vec3f turn(const vec3f& v, const vec3f& k, float c, float s)
{
    return v * c + cross(k, v) * s + k * (dot(k, v) * (1.0f - c));
}

// x reduced to [-pi, pi] by whole turns (the program's krs_one_turn); exactly x = 0 at 0.
inline float one_turn(float x)
{
    return x - drag_turn * std::floor(x / drag_turn + 0.5f);
}

// The tilt a vertical drag makes: about `axis` (the right axis, signed so that a positive angle
// raises the eye), by an angle clamped to [lowest, highest] radians: from the baked elevation to
// the view's [min_elevation, max_elevation], 0 always inside. The elevation is read from the
// forward axis (the eye seen from what it looks at), exact for a level right axis (look_at).
struct tilt_range {
    vec3f axis;
    float lowest, highest;
};
inline tilt_range tilt_of(const view& v)
{
    const vec3d forward = normalize(vec3d(v.forward)), vertical = normalize(vec3d(v.vertical));
    const double elevation = std::asin(std::clamp(-dot(forward, vertical), -1.0, 1.0));
    const double degree = std::numbers::pi / 180.0;
    // Turning forward about `right` by a small positive angle moves it along cross(right, forward):
    // down (the eye up) when that points against the vertical.
    const bool raises = dot(cross(vec3d(v.right), forward), vertical) <= 0.0;
    return {raises ? v.right : -v.right, float(std::min(0.0, double(v.min_elevation) * degree - elevation)),
            float(std::max(0.0, double(v.max_elevation) * degree - elevation))};
}
} // namespace detail

// The camera the Shadertoy program uses at `time` (iTime) with the pointer at (mouse_x, mouse_y)
// (iMouse.xy, y up) in a frame of width x height pixels: the baked view tilted, then turned about
// the vertical through the pivot, as the program's krs_camera does.
inline view shadertoy_view(const view& v, float time, float mouse_x, float mouse_y, float width, float height)
{
    v.validate();
    const detail::tilt_range tilt = detail::tilt_of(v);
    const bool dragged = mouse_x > 0.0f || mouse_y > 0.0f;
    const float drag_x = dragged ? mouse_x / width - 0.5f : 0.0f;
    const float drag_y = dragged ? mouse_y / height - 0.5f : 0.0f;
    const float yaw = detail::one_turn(time * v.orbit_rate() + drag_x * detail::drag_turn);
    const float pitch = std::clamp(drag_y * detail::drag_tilt, tilt.lowest, tilt.highest);
    if (yaw == 0.0f && pitch == 0.0f) return v;
    view o = v;
    const vec3f k = tilt.axis, vertical = v.vertical;
    const float cp = std::cos(pitch), sp = std::sin(pitch), cy = std::cos(yaw), sy = std::sin(yaw);
    const vec3f offset = detail::turn(detail::turn(v.eye - v.pivot, k, cp, sp), vertical, cy, sy);
    o.eye = v.pivot + offset;
    o.forward = detail::turn(detail::turn(v.forward, k, cp, sp), vertical, cy, sy);
    o.up = detail::turn(detail::turn(v.up, k, cp, sp), vertical, cy, sy);
    o.right = detail::turn(v.right, vertical, cy, sy); // the tilt's own axis does not move under it
    return o;
}

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

template <class T>
inline constexpr bool is_sequence = false;
template <class M, class... Kinds>
inline constexpr bool is_sequence<basic_sequence<M, Kinds...>> = true;
} // namespace detail

// Whether F is shaded in kernel space (a KRS sequence) or by its gradient (any other field).
template <class F>
concept kernel_shaded = detail::is_sequence<F>;

// The albedo of each kernel type of sequence S, indexed as krs_kernel_shading::kind: `palette`
// when given (one finite colour per type, e.g. green grass blades where a torus_capsule would
// be bark), else by type as above.
template <class M, class... Kinds>
std::vector<vec3f> palette_of(const basic_sequence<M, Kinds...>&, const std::vector<vec3f>& palette = {})
{
    if (palette.empty()) return {detail::albedo_of<Kinds>()...};
    if (palette.size() != sizeof...(Kinds))
        throw invalid_parameter("glsl.palette", "must hold one colour per kernel type of the sequence (" +
                                                    std::to_string(sizeof...(Kinds)) + ")",
                                std::to_string(palette.size()) + " colours");
    for (const vec3f& c : palette) require_finite("glsl.palette", c);
    return palette;
}

namespace detail {

// The program's constants and the functions every program shares, after the field's code:
// camera and orbit, tracing, clipping, shadow and sky. `surface` defines
// `vec3 krs_surface(vec3 p, vec3 direction, float t, float scale, float footprint)`, the colour of
// a hit; mainImage is appended last.
template <field F>
std::string program(const F& f, const view& v, const std::string& name, const std::string& library,
                    const std::string& surface)
{
    v.validate();
    const tilt_range tilt = tilt_of(v);
    const std::string orbit = v.orbit_rate() == 0.0f ? "iTime leaves the camera still"
                                                      : "iTime orbits the camera (one turn per " +
                                                            float_literal(v.orbit_seconds) + " s)";
    std::string out = "// krs scene '" + name + "' for Shadertoy: paste into the Image tab as-is. " + orbit +
                      ",\n// the pointer's position (click or drag) turns it, and pointer up raises it. Alpha is 1 everywhere.\n";
    out += library;
    out += "const vec3 KRS_EYE = " + vec3_literal(v.eye) + ";\n";
    out += "const vec3 KRS_FORWARD = " + vec3_literal(v.forward) + ";\n";
    out += "const vec3 KRS_RIGHT = " + vec3_literal(v.right) + ";\n";
    out += "const vec3 KRS_UP = " + vec3_literal(v.up) + ";\n";
    out += "const vec3 KRS_PIVOT = " + vec3_literal(v.pivot) + ";\n";
    out += "const vec3 KRS_VERTICAL = " + vec3_literal(v.vertical) + ";\n";
    out += "const vec3 KRS_TILT_AXIS = " + vec3_literal(tilt.axis) + "; // a positive tilt raises the eye\n";
    out += "const float KRS_TILT_LOWEST = " + float_literal(tilt.lowest) + ";\n";
    out += "const float KRS_TILT_HIGHEST = " + float_literal(tilt.highest) + ";\n";
    out += "const float KRS_ORBIT_RATE = " + float_literal(v.orbit_rate()) + "; // radians per second of iTime\n";
    out += "const float KRS_DRAG_TURN = " + float_literal(drag_turn) + ";\n";
    out += "const float KRS_DRAG_TILT = " + float_literal(drag_tilt) + ";\n";
    out += "const vec3 KRS_TO_LIGHT = " + vec3_literal(v.to_light) + ";\n";
    out += "const float KRS_TAN_HALF_FOV = " + float_literal(v.tan_half_fov) + ";\n";
    out += "const float KRS_MAX_DISTANCE = " + float_literal(v.max_distance) + ";\n";
    out += "const int KRS_MAX_STEPS = " + std::to_string(v.max_steps) + ";\n";
    out += "const float KRS_THRESHOLD_FLOOR = " + float_literal(v.threshold_floor) + ";\n";
    out += "const float KRS_FOOTPRINT_SCALE = " + float_literal(v.footprint_scale) + ";\n";
    const bounding_box box = field_box(f);
    out += std::string("const bool KRS_CLIP = ") + (box.is_bounded() ? "true" : "false") + ";\n";
    out += "const vec3 KRS_BOX_LO = " + vec3_literal(box.is_bounded() ? box.lo : vec3f{}) + ";\n";
    out += "const vec3 KRS_BOX_HI = " + vec3_literal(box.is_bounded() ? box.hi : vec3f{}) + ";\n";
    out += "float krs_scene(vec3 p) { return krs_" + name + "(p); }\n";
    out += R"(struct krs_view {
    vec3 eye;
    vec3 forward;
    vec3 right;
    vec3 up;
};
// v turned by the angle of cosine c and sine s about the unit axis k (Rodrigues).
vec3 krs_turn(vec3 v, vec3 k, float c, float s) {
    return v * c + cross(k, v) * s + k * (dot(k, v) * (1.0 - c));
}
// x reduced to [-pi, pi] by whole turns (mobile GPUs' sin and cos lose accuracy far outside it).
float krs_one_turn(float x) {
    return x - KRS_DRAG_TURN * floor(x / KRS_DRAG_TURN + 0.5);
}
// The baked camera tilted about its right axis by the pointer's height (up raises the eye, its
// elevation kept within the scene's range), then turned about KRS_VERTICAL through KRS_PIVOT by
// iTime and the pointer's x; unchanged (bit for bit) when nothing turns.
krs_view krs_camera(float time, vec4 mouse, vec2 resolution) {
    krs_view c = krs_view(KRS_EYE, KRS_FORWARD, KRS_RIGHT, KRS_UP);
    bool dragged = mouse.x > 0.0 || mouse.y > 0.0;
    float dragX = dragged ? mouse.x / resolution.x - 0.5 : 0.0;
    float dragY = dragged ? mouse.y / resolution.y - 0.5 : 0.0;
    float yaw = krs_one_turn(time * KRS_ORBIT_RATE + dragX * KRS_DRAG_TURN);
    float pitch = clamp(dragY * KRS_DRAG_TILT, KRS_TILT_LOWEST, KRS_TILT_HIGHEST);
    if (yaw == 0.0 && pitch == 0.0) return c;
    float cp = cos(pitch), sp = sin(pitch), cy = cos(yaw), sy = sin(yaw);
    c.eye = KRS_PIVOT + krs_turn(krs_turn(KRS_EYE - KRS_PIVOT, KRS_TILT_AXIS, cp, sp), KRS_VERTICAL, cy, sy);
    c.forward = krs_turn(krs_turn(KRS_FORWARD, KRS_TILT_AXIS, cp, sp), KRS_VERTICAL, cy, sy);
    c.up = krs_turn(krs_turn(KRS_UP, KRS_TILT_AXIS, cp, sp), KRS_VERTICAL, cy, sy);
    c.right = krs_turn(KRS_RIGHT, KRS_VERTICAL, cy, sy);
    return c;
}
// Sphere tracing from t0 to t1; a hit when the distance drops under footprint * t + floor + bias.
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
// The Lambert term `diffuse` at the hit p (ray depth t), or 0 when the light is blocked: the
// shadow ray starts where the surface is at least two thresholds away along the light
// (t cos >= 2 threshold), so there is no self-shadowing acne at grazing light.
float krs_shadow(vec3 p, float t, float footprint, float diffuse) {
    if (diffuse > 0.0) {
        float hitThreshold = footprint * t + KRS_THRESHOLD_FLOOR;
        bool shadowed;
        krs_trace(p, KRS_TO_LIGHT, hitThreshold * (1.0 + 2.0 / max(diffuse, 0.1)), KRS_MAX_DISTANCE, footprint, hitThreshold, shadowed);
        if (shadowed) diffuse = 0.0;
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
    float scale = KRS_TAN_HALF_FOV * 2.0 / iResolution.y;
    float sx = (fragCoord.x - 0.5 * iResolution.x) * scale;
    float sy = (fragCoord.y - 0.5 * iResolution.y) * scale;
    vec3 d = c.forward + c.right * sx + c.up * sy;
    vec3 direction = d / sqrt(dot(d, d));
    float footprint = KRS_FOOTPRINT_SCALE * scale;
    bool found = false;
    float t0 = 0.0;
    float t1 = KRS_MAX_DISTANCE;
    float t = KRS_MAX_DISTANCE;
    if (krs_clip(c.eye, direction, footprint, t0, t1)) t = krs_trace(c.eye, direction, t0, t1, footprint, 0.0, found);
    vec3 color = found ? krs_surface(c.eye + direction * t, direction, t, scale, footprint) : krs_sky(direction);
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
std::string shadertoy(const basic_sequence<M, Kinds...>& s, const view& v, const std::string& name,
                      const std::vector<vec3f>& palette_by_type = {})
{
    v.validate();
    emitter e({.target = target::shadertoy, .mode = data_mode::constants, .data_name = name + "_data"});
    const std::string scene = e.add(s, name); // krs_NAME
    std::string library = e.source();
    const std::vector<vec3f> palette = palette_of(s, palette_by_type);
    library += "vec3 krs_albedo(uint kind) {\n";
    for (std::size_t i = 0; i < sizeof...(Kinds); ++i)
        library += "    if (kind == " + std::to_string(i) + "u) return " + vec3_literal(palette[i]) + ";\n";
    library += "    return vec3(0.5);\n}\n";
    library += "const float KRS_BAND_PIXELS = " + float_literal(v.band_pixels) + ";\n";
    const std::string surface = R"(// Lambert in kernel space (Algorithm 2) over a band of KRS_BAND_PIXELS footprints at depth t.
vec3 krs_surface(vec3 p, vec3 direction, float t, float scale, float footprint) {
    float band = KRS_BAND_PIXELS * scale * t + 1e-6;
    krs_kernel_shading s = )" + scene + R"(_shade(p, KRS_TO_LIGHT, -direction, band);
    float diffuse = krs_shadow(p, t, footprint, max(dot(s.normal, s.light), 0.0));
    return krs_albedo(s.kind) * (0.25 + 0.75 * diffuse);
}
)";
    return detail::program(s, v, name, library, surface);
}

// Any other field: Lambert with the normal of the field's tetrahedral gradient, one albedo.
template <field F>
    requires(!kernel_shaded<F>)
std::string shadertoy(const F& f, const view& v, const std::string& name, const vec3f& albedo)
{
    // Shaded by the gradient: the distance is all the program calls (a sequence inside a warp would
    // bring its _locate and _shade, and the krs_location structs, otherwise).
    emitter e({.target = target::shadertoy, .mode = data_mode::constants, .data_name = name + "_data", .distance_only = true});
    v.validate();
    e.add(f, name);
    std::string library = e.source();
    library += "const vec3 KRS_ALBEDO = " + vec3_literal(require_finite("glsl.shadertoy.albedo", albedo)) + ";\n";
    library += "const float KRS_NORMAL_STEP = " + float_literal(v.normal_step) + ";\n";
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
    vec3 n = krs_normal(p, KRS_NORMAL_STEP * (footprint * t + KRS_THRESHOLD_FLOOR));
    if (dot(n, direction) > 0.0) n = -n;
    float diffuse = krs_shadow(p, t, footprint, max(dot(n, KRS_TO_LIGHT), 0.0));
    return KRS_ALBEDO * (0.25 + 0.75 * diffuse);
}
)";
    return detail::program(f, v, name, library, surface);
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

// krs_shadow on the CPU.
template <field F>
float shadow_reference(const F& f, const vec3f& p, float t, float footprint, float diffuse, const view& v)
{
    if (diffuse > 0.0f) {
        const float hit_threshold = footprint * t + v.threshold_floor;
        bool shadowed = false;
        trace_reference(f, p, v.to_light, hit_threshold * (1.0f + 2.0f / std::max(diffuse, 0.1f)), v.max_distance,
                        footprint, hit_threshold, v, shadowed);
        if (shadowed) diffuse = 0.0f;
    }
    return diffuse;
}

// mainImage on the CPU, with `surface(p, direction, t, scale, footprint)` as krs_surface: RGBA rows
// bottom-up (as glReadPixels returns them), width x height x 4 floats.
template <field F, class Surface>
std::vector<float> render_frame(const F& f, const view& v, int width, int height, bool clip_to_box,
                                const Surface& surface)
{
    v.validate();
    // A frame as large as a GL framebuffer may be; larger ones are a typo, not a picture.
    if (width < 1 || width > 16384)
        throw invalid_parameter("glsl.render_reference.width", "must be in [1, 16384]", std::to_string(width));
    if (height < 1 || height > 16384)
        throw invalid_parameter("glsl.render_reference.height", "must be in [1, 16384]", std::to_string(height));
    std::vector<float> rgba(std::size_t(width) * std::size_t(height) * 4);
    const float w = float(width), h = float(height);
    const float scale = v.tan_half_fov * 2.0f / h;
    const float footprint = v.footprint_scale * scale;
    trace_options clip_options;
    clip_options.pixel_footprint = footprint;
    clip_options.threshold_floor = v.threshold_floor;
    const box_clip clip = clip_to_box ? box_clip(field_box(f), v.eye, clip_options) : box_clip();
    for (int j = 0; j < height; ++j)
        for (int i = 0; i < width; ++i) {
            const float sx = (float(i) + 0.5f - 0.5f * w) * scale;
            const float sy = (float(j) + 0.5f - 0.5f * h) * scale;
            const vec3f d = v.forward + v.right * sx + v.up * sy;
            const vec3f direction = d / std::sqrt(dot(d, d));
            bool found = false;
            float t0 = 0.0f, t1 = v.max_distance;
            clip.apply(ray<float>{v.eye, direction}, t0, t1);
            const float t = t1 < t0 ? v.max_distance : trace_reference(f, v.eye, direction, t0, t1, footprint, 0.0f, v, found);
            const float y = std::clamp(dot(direction, v.vertical), 0.0f, 1.0f);
            vec3f color = vec3f{0.78f, 0.86f, 0.95f} + (vec3f{0.36f, 0.55f, 0.88f} - vec3f{0.78f, 0.86f, 0.95f}) * y;
            if (found) color = surface(v.eye + direction * t, direction, t, scale, footprint);
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
// glReadPixels returns them), width x height x 4 floats, for the camera `v` (the program's at
// iTime = 0 and no drag; shadertoy_view gives it for others). `clip_to_box` false traces primary
// rays unclipped (what the program did before it clipped them, for comparison).
template <class M, class... Kinds>
std::vector<float> render_reference(const basic_sequence<M, Kinds...>& s, const view& v, int width, int height,
                                    bool clip_to_box = true, const std::vector<vec3f>& palette_by_type = {})
{
    const std::vector<vec3f> palette = palette_of(s, palette_by_type);
    return detail::render_frame(s, v, width, height, clip_to_box,
                                [&](const vec3f& p, const vec3f& direction, float t, float scale, float footprint) {
                                    const float band = v.band_pixels * scale * t + 1e-6f;
                                    const kernel_space_shading<float> k =
                                        shade_in_kernel_space(s, p, v.to_light, -direction, band);
                                    const float diffuse = detail::shadow_reference(
                                        s, p, t, footprint, std::max(dot(k.normal, k.light), 0.0f), v);
                                    return palette[s.kernels()[k.where.kernel].index()] *
                                           (0.25f + 0.75f * diffuse);
                                });
}

// The Shadertoy program of any other field in C++ on the CPU field (as above).
template <field F>
    requires(!kernel_shaded<F>)
std::vector<float> render_reference(const F& f, const view& v, const vec3f& albedo, int width, int height,
                                    bool clip_to_box = true)
{
    return detail::render_frame(f, v, width, height, clip_to_box,
                                [&](const vec3f& p, const vec3f& direction, float t, float, float footprint) {
                                    vec3f n = gradient_normal(f, p, v.normal_step * (footprint * t + v.threshold_floor));
                                    if (dot(n, direction) > 0.0f) n = -n;
                                    const float diffuse =
                                        detail::shadow_reference(f, p, t, footprint, std::max(dot(n, v.to_light), 0.0f), v);
                                    return albedo * (0.25f + 0.75f * diffuse);
                                });
}

} // namespace krs::glsl

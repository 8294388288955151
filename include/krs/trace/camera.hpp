#pragma once
// Pinhole camera: primary rays, the size of one pixel, and the turn that Shadertoy's inputs give
// the camera, with the GLSL of both.
//
// The pixel footprint is the side, at distance 1 along the view direction, of the pixel at the
// image center: 2 tan(fov / 2) / height (for small pixels, about the angle it subtends, in
// radians). A center pixel at distance d covers a square of side d * footprint facing the eye
// (`pixel_size_at`), and pixels off the center cover less there. It sets the sphere tracer's hit
// threshold: at depth t an unbounding sphere smaller than footprint * t projects to less than a
// pixel (paper section 4, trace_options::threshold). That makes the threshold, and with it the
// level of detail, follow the camera: far geometry merges into smooth formations instead of
// aliasing.
//
// The basis is a look-at computed in double and rounded once: forward from the eye to the target,
// right = forward x up, up = right x forward. The target is also the camera's pivot and the up
// hint its vertical, which is what the turn below moves it about.
//
// The turn (`turned`: what Shadertoy's iTime and iMouse do to the camera of a krs program). iTime
// turns it about the vertical through the pivot, one turn every `camera_orbit::seconds` (60 by
// default; 0 keeps it still). A click or drag sets a turn as well, from the pointer's position,
// not its motion: across the frame's width a full turn about the vertical; across its height a
// tilt of up to +-60 degrees about the camera's right axis, pointer up raising the eye. The tilt
// keeps the eye's elevation (seen from the pivot) within [min_elevation, max_elevation] degrees
// (5 to 85 by default; widened to include the baked elevation), so the eye stays above a ground
// and never passes the pole. The centre of the frame is no turn, and before the first click
// (iMouse = 0) the pointer does nothing. The turn is reduced to [-pi, pi] (mobile GPUs' sin and
// cos lose accuracy far outside it). The basis is rotated rigidly (Rodrigues), never recomputed
// from a look-at, so it cannot degenerate, and with no turn at all the camera is unchanged.
//
// GLSL (`glsl_source`): the camera's constants and `krs_camera(time, mouse, resolution)` (the
// turn), `krs_pixel_footprint(height)` and `krs_primary_direction(view, pixel, resolution)`, the
// C++ operation for operation, so a program's rays are the C++ camera's (pixel y up, as
// gl_FragCoord).

#include "krs/core/validate.hpp"
#include "krs/trace/ray.hpp"

#include <algorithm>
#include <cmath>
#include <numbers>
#include <string>

namespace krs {

// How iTime and the pointer turn a camera (see above).
struct camera_orbit {
    float seconds = 60.0f; // one turn about the pivot per this many seconds of iTime; 0: still
    // The elevation (degrees, the eye seen from the pivot above the plane across the vertical) a
    // pointer tilt may reach; the camera's own elevation is always allowed.
    float min_elevation = 5.0f, max_elevation = 85.0f;

    const camera_orbit& validate() const
    {
        if (!std::isfinite(seconds) || !(seconds >= 0.0f))
            throw invalid_parameter("camera_orbit.seconds", "must be finite and >= 0 (0: no orbit)",
                                    detail::to_text(seconds));
        require_finite("camera_orbit.min_elevation", min_elevation);
        require_finite("camera_orbit.max_elevation", max_elevation);
        if (!(min_elevation > -90.0f && min_elevation <= max_elevation && max_elevation < 90.0f))
            throw invalid_parameter("camera_orbit.min_elevation, camera_orbit.max_elevation",
                                    "must satisfy -90 < min <= max < 90",
                                    detail::to_text(min_elevation) + ", " + detail::to_text(max_elevation));
        return *this;
    }
    // Radians of turn per second of iTime (the program's KRS_ORBIT_RATE).
    float rate() const { return seconds == 0.0f ? 0.0f : float(2.0 * std::numbers::pi / double(seconds)); }
};

// The world side of a pixel of footprint `footprint` (pinhole_camera::pixel_footprint, the side
// at distance 1) facing the eye at distance d: d * footprint. The one rule for a pixel's size at
// a distance (a voxel's level of detail, hypertree/lod.hpp; supersampling, hypertree/render).
inline double pixel_size_at(double distance, double footprint)
{
    return distance * footprint;
}

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
} // namespace detail

class pinhole_camera {
public:
    pinhole_camera(const vec3f& eye, const vec3f& target, const vec3f& up, float vertical_fov_degrees, int width,
                   int height)
        : eye_(require_finite("camera.eye", eye)), pivot_(require_finite("camera.target", target))
    {
        require_size(width, height);
        require_finite("camera.vertical_fov_degrees", vertical_fov_degrees);
        if (!(vertical_fov_degrees > 0.0f && vertical_fov_degrees < 180.0f))
            throw invalid_parameter("camera.vertical_fov_degrees", "must be in (0, 180)",
                                    detail::to_text(vertical_fov_degrees));
        const vec3d f = normalize(vec3d(require_direction("camera.target - camera.eye", target - eye)));
        const vec3d vertical = normalize(vec3d(require_direction("camera.up", up)));
        const vec3d r = cross(f, vertical);
        if (!(length(r) > 1e-6)) throw invalid_parameter("camera.up", "must not be parallel to the view direction");
        const vec3d rn = normalize(r);
        forward_ = vec3f(f);
        right_ = vec3f(rn);
        up_ = vec3f(cross(rn, f));
        vertical_ = vec3f(vertical);
        width_ = width;
        height_ = height;
        tan_half_fov_ = float(std::tan(0.5 * double(vertical_fov_degrees) * std::numbers::pi / 180.0));
    }

    int width() const { return width_; }
    int height() const { return height_; }
    const vec3f& eye() const { return eye_; }
    const vec3f& forward() const { return forward_; }
    const vec3f& right() const { return right_; }
    const vec3f& up() const { return up_; }
    const vec3f& pivot() const { return pivot_; }       // the look-at target: what the turn orbits
    const vec3f& vertical() const { return vertical_; } // unit: the turn's axis, the up hint
    float tan_half_fov() const { return tan_half_fov_; }
    const camera_orbit& orbit() const { return orbit_; }

    // The same camera with another orbit or another image size (a Shadertoy frame's).
    pinhole_camera with_orbit(const camera_orbit& o) const
    {
        pinhole_camera c = *this;
        c.orbit_ = o.validate();
        return c;
    }
    pinhole_camera with_size(int width, int height) const
    {
        require_size(width, height);
        pinhole_camera c = *this;
        c.width_ = width, c.height_ = height;
        return c;
    }

    // The side, at distance 1, of the pixel at the image center (see above).
    float pixel_footprint() const { return tan_half_fov_ * 2.0f / float(height_); }
    // The world side of a center pixel at distance d from the eye (d * footprint): what a voxel
    // or a sphere must reach to cover a pixel there.
    double pixel_size_at(double distance) const { return krs::pixel_size_at(distance, double(pixel_footprint())); }

    // The ray through image position (px, py), in pixels from the top-left corner; pixel centers
    // are at half-integers. Works for scalar and packet coordinates alike.
    template <class T>
    ray<T> primary_ray(const T& px, const T& py) const
    {
        const T scale = T(pixel_footprint());
        const T sx = (px - T(0.5f * float(width_))) * scale;
        const T sy = (T(0.5f * float(height_)) - py) * scale;
        const vec3<T> d = vec3<T>(forward_) + vec3<T>(right_) * sx + vec3<T>(up_) * sy;
        return {vec3<T>(eye_), normalize(d)};
    }

    // The camera at `time` (iTime) with the pointer at (mouse_x, mouse_y) (iMouse.xy: pixels, y up)
    // in a frame of this camera's size: tilted, then turned about the vertical through the pivot
    // (see above), as the program's krs_camera does.
    pinhole_camera turned(float time, float mouse_x, float mouse_y) const
    {
        const tilt_range tilt = tilt_of();
        const bool dragged = mouse_x > 0.0f || mouse_y > 0.0f;
        const float drag_x = dragged ? mouse_x / float(width_) - 0.5f : 0.0f;
        const float drag_y = dragged ? mouse_y / float(height_) - 0.5f : 0.0f;
        const float yaw = detail::one_turn(time * orbit_.rate() + drag_x * detail::drag_turn);
        const float pitch = std::clamp(drag_y * detail::drag_tilt, tilt.lowest, tilt.highest);
        if (yaw == 0.0f && pitch == 0.0f) return *this;
        pinhole_camera o = *this;
        const vec3f k = tilt.axis;
        const float cp = std::cos(pitch), sp = std::sin(pitch), cy = std::cos(yaw), sy = std::sin(yaw);
        const auto both = [&](const vec3f& v) { return detail::turn(detail::turn(v, k, cp, sp), vertical_, cy, sy); };
        o.eye_ = pivot_ + both(eye_ - pivot_);
        o.forward_ = both(forward_);
        o.up_ = both(up_);
        o.right_ = detail::turn(right_, vertical_, cy, sy); // the tilt's own axis does not move under it
        return o;
    }

    // The beam of the pixel rectangle [x0, x1) x [y0, y1): its axis (the ray through the
    // rectangle's center) and the cosine and sine of the smallest half-angle about that axis that
    // holds every pixel-center ray of the rectangle. The rays that hit the image plane inside a
    // cone about the axis form an ellipse there (a convex set), so the widest ray is one through
    // a corner pixel center; the angle is widened by a few float ulps against rounding.
    struct beam_cone {
        ray<float> axis;
        float cos_half_angle = 1.0f, sin_half_angle = 0.0f;
    };
    beam_cone beam(int x0, int y0, int x1, int y1) const
    {
        const float cx = 0.5f * float(x0 + x1), cy = 0.5f * float(y0 + y1);
        beam_cone b;
        b.axis = primary_ray(cx, cy);
        // The angle as atan2(|a x v|, a . v) of the float directions normalized in double: acos of
        // a dot product near 1 loses half its digits (about 3e-4 radians from float unit vectors,
        // far above the margin, so 30% of a 1080p frame's 8 x 8 tiles left a corner ray outside).
        const vec3d a = normalize(vec3d(b.axis.direction));
        double angle = 0.0;
        const float xs[2] = {float(x0) + 0.5f, float(x1) - 0.5f}, ys[2] = {float(y0) + 0.5f, float(y1) - 0.5f};
        for (float x : xs)
            for (float y : ys) {
                const vec3d v = normalize(vec3d(primary_ray(x, y).direction));
                angle = std::max(angle, std::atan2(length(cross(a, v)), dot(a, v)));
            }
        angle = angle * (1.0 + 1e-5) + 1e-6;
        b.cos_half_angle = float(std::cos(angle));
        b.sin_half_angle = float(std::sin(angle));
        return b;
    }

    // The tilt a vertical drag makes: about `axis` (the right axis, signed so that a positive angle
    // raises the eye), by an angle clamped to [lowest, highest] radians: from the camera's
    // elevation to the orbit's [min_elevation, max_elevation], 0 always inside. The elevation is
    // read from the forward axis (the eye seen from what it looks at), exact for a level right
    // axis (a look-at's).
    struct tilt_range {
        vec3f axis;
        float lowest, highest;
    };
    tilt_range tilt_of() const
    {
        const vec3d forward = normalize(vec3d(forward_)), vertical = normalize(vec3d(vertical_));
        const double elevation = std::asin(std::clamp(-dot(forward, vertical), -1.0, 1.0));
        const double degree = std::numbers::pi / 180.0;
        // Turning forward about `right` by a small positive angle moves it along cross(right,
        // forward): down (the eye up) when that points against the vertical.
        const bool raises = dot(cross(vec3d(right_), forward), vertical) <= 0.0;
        return {raises ? right_ : -right_, float(std::min(0.0, double(orbit_.min_elevation) * degree - elevation)),
                float(std::max(0.0, double(orbit_.max_elevation) * degree - elevation))};
    }

    // The GLSL of the camera and its turn (see above), with Out::literal writing the floats (as
    // the emitter's writing interface does). Defines the constants KRS_EYE ... KRS_TAN_HALF_FOV,
    // `struct krs_view`, krs_turn, krs_one_turn, krs_camera, krs_pixel_footprint and
    // krs_primary_direction.
    template <class Out>
    std::string glsl_source() const
    {
        const auto vec3 = [](const vec3f& v) {
            return "vec3(" + Out::literal(v.x) + ", " + Out::literal(v.y) + ", " + Out::literal(v.z) + ")";
        };
        const tilt_range tilt = tilt_of();
        std::string out;
        out += "const vec3 KRS_EYE = " + vec3(eye_) + ";\n";
        out += "const vec3 KRS_FORWARD = " + vec3(forward_) + ";\n";
        out += "const vec3 KRS_RIGHT = " + vec3(right_) + ";\n";
        out += "const vec3 KRS_UP = " + vec3(up_) + ";\n";
        out += "const vec3 KRS_PIVOT = " + vec3(pivot_) + ";\n";
        out += "const vec3 KRS_VERTICAL = " + vec3(vertical_) + ";\n";
        out += "const vec3 KRS_TILT_AXIS = " + vec3(tilt.axis) + "; // a positive tilt raises the eye\n";
        out += "const float KRS_TILT_LOWEST = " + Out::literal(tilt.lowest) + ";\n";
        out += "const float KRS_TILT_HIGHEST = " + Out::literal(tilt.highest) + ";\n";
        out += "const float KRS_ORBIT_RATE = " + Out::literal(orbit_.rate()) + "; // radians per second of iTime\n";
        out += "const float KRS_DRAG_TURN = " + Out::literal(detail::drag_turn) + ";\n";
        out += "const float KRS_DRAG_TILT = " + Out::literal(detail::drag_tilt) + ";\n";
        out += "const float KRS_TAN_HALF_FOV = " + Out::literal(tan_half_fov_) + ";\n";
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
// pinhole_camera::pixel_footprint for a frame `height` pixels high.
float krs_pixel_footprint(float height) {
    return KRS_TAN_HALF_FOV * 2.0 / height;
}
// pinhole_camera::primary_ray's direction through `pixel` (pixels from the bottom-left corner).
vec3 krs_primary_direction(krs_view c, vec2 pixel, vec2 resolution) {
    float scale = krs_pixel_footprint(resolution.y);
    float sx = (pixel.x - 0.5 * resolution.x) * scale;
    float sy = (pixel.y - 0.5 * resolution.y) * scale;
    vec3 d = c.forward + c.right * sx + c.up * sy;
    return d / sqrt(dot(d, d));
}
)";
        return out;
    }

private:
    static void require_size(int width, int height)
    {
        if (width < 1 || height < 1)
            throw invalid_parameter("camera.size", "width and height must be >= 1",
                                    std::to_string(width) + "x" + std::to_string(height));
    }

    vec3f eye_, forward_, right_, up_, pivot_, vertical_{0, 1, 0};
    int width_ = 1, height_ = 1;
    float tan_half_fov_ = 1.0f;
    camera_orbit orbit_{};
};

} // namespace krs

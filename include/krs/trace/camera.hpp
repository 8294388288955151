#pragma once
// Pinhole camera: primary rays and the angular size of one pixel.
//
// The pixel footprint (radians per pixel at the image center) sets the sphere tracer's hit
// threshold: at depth t an unbounding sphere smaller than footprint * t projects to less than a
// pixel (paper section 4). That makes the threshold, and with it the level of detail, follow the
// camera: far geometry merges into smooth formations instead of aliasing.

#include "krs/core/validate.hpp"
#include "krs/trace/ray.hpp"

#include <algorithm>
#include <cmath>
#include <numbers>

namespace krs {

class pinhole_camera {
public:
    pinhole_camera(const vec3f& eye, const vec3f& target, const vec3f& up, float vertical_fov_degrees, int width,
                   int height)
        : eye_(require_finite("camera.eye", eye))
    {
        require_finite("camera.target", target);
        if (width < 1 || height < 1)
            throw invalid_parameter("camera.size", "width and height must be >= 1",
                                    std::to_string(width) + "x" + std::to_string(height));
        require_finite("camera.vertical_fov_degrees", vertical_fov_degrees);
        if (!(vertical_fov_degrees > 0.0f && vertical_fov_degrees < 180.0f))
            throw invalid_parameter("camera.vertical_fov_degrees", "must be in (0, 180)",
                                    detail::to_text(vertical_fov_degrees));
        forward_ = require_direction("camera.target - camera.eye", target - eye);
        const vec3f u = require_direction("camera.up", up);
        const vec3f r = cross(forward_, u);
        if (!(length(r) > 1e-6f)) throw invalid_parameter("camera.up", "must not be parallel to the view direction");
        right_ = normalize(r);
        up_ = cross(right_, forward_);
        width_ = width;
        height_ = height;
        tan_half_fov_ = std::tan(0.5f * vertical_fov_degrees * std::numbers::pi_v<float> / 180.0f);
    }

    int width() const { return width_; }
    int height() const { return height_; }
    const vec3f& eye() const { return eye_; }
    const vec3f& forward() const { return forward_; }

    // Angle subtended by one pixel at the image center.
    float pixel_footprint() const { return 2.0f * tan_half_fov_ / float(height_); }

    // The ray through image position (px, py), in pixels from the top-left corner; pixel centers
    // are at half-integers. Works for scalar and packet coordinates alike.
    template <class T>
    ray<T> primary_ray(const T& px, const T& py) const
    {
        const T scale = T(tan_half_fov_ * 2.0f / float(height_));
        const T sx = (px - T(0.5f * float(width_))) * scale;
        const T sy = (T(0.5f * float(height_)) - py) * scale;
        const vec3<T> d = vec3<T>(forward_) + vec3<T>(right_) * sx + vec3<T>(up_) * sy;
        return {vec3<T>(eye_), normalize(d)};
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

private:
    vec3f eye_, forward_, right_, up_;
    int width_ = 1, height_ = 1;
    float tan_half_fov_ = 1.0f;
};

} // namespace krs

#pragma once
// The cross-section view: any field's distance on a plane, as images, for debugging a field.
//
// A sphere tracer trusts two things of a field: its zero set is the surface, and it never
// overestimates the distance (docs/design.md#rule-2), i.e. it is 1-Lipschitz: |grad d| <= 1. A
// slice shows both where a rendered image only shows their consequences (holes, stripes, surfaces
// that vanish). `cross_section(field, plane, options)` samples the distance at the pixel centres of
// a rectangle in a plane (origin at its centre, unit axes u (right) and v (up), half extents along
// each, columns x rows pixels, row 0 at the top) and the gradient magnitude there by central
// differences along the world axes:
//
//     g_k = (d(p + h e_k) - d(p - h e_k)) / ((p + h e_k)_k - (p - h e_k)_k),   |grad| = |(g_x, g_y, g_z)|
//
// (divided by the step the float coordinates really took, not 2h). Where the field is smooth this
// is its gradient to O(h^2), and |grad| > 1 means it overestimates. Within h of a crease (a
// union's seam, a fold plane) it is not: each axis's quotient is taken across the crease on its
// own side, and the vector of them can be longer than 1 for a 1-Lipschitz field (the Menger
// sponge, 1-Lipschitz by construction, reads |grad| up to 1.008 along its fold planes; the cube
// singularity 1.009). So the flag rests on a witness instead: the quotient along the measured
// gradient's direction u,
//
//     slope = |d(p + h u) - d(p - h u)| / |(p + h u) - (p - h u)|,
//
// which is the gradient's magnitude where the field is smooth and, being the quotient of one pair
// of points, can exceed 1 only where the field really does overestimate between them (a crease of
// a 1-Lipschitz field stays <= 1). A pixel is flagged where slope > 1 + lipschitz_tolerance: a
// sphere tracer stepping the full distance from there may step through the surface. The tolerance
// covers the float noise of a difference, about ulp(|d|) / h: keep h (half a pixel by default)
// well above the ulps of the coordinates. (A field that overestimates only across a direction
// other than its gradient's, which no field of this library does, goes unflagged.)
//
// Two images come out, linear RGB rows top first (an example writes them as PNG):
//   distance_image   outside orange, inside blue, in bands of iso_spacing (alternate bands darker);
//                    iso lines where d is within half a line width (line_width pixels, measured in
//                    world units as pixel_size) of a multiple k of the spacing, dark, and the zero
//                    line (k = 0) white. Each pixel's class is `kind[i]`.
//   gradient_image   |grad| as grey (black 0 .. light 1); flagged pixels red, turning yellow as the
//                    slope reaches 2. Each pixel's flag is `overestimates(i)`.
// A pixel where the distance or any of the 8 samples of its gradient is NaN or infinite is of kind
// `not_finite`, magenta in both images, flagged (a tracer cannot step by such a value) and counted
// in `non_finite`; max_gradient and max_slope are over the other pixels (NaN would vanish in a
// maximum and an infinite distance gives a NaN gradient, so none of them may hide the problem).
// Sampling costs 9 scalar distance evaluations per pixel; nothing is cached, no thread started.

#include "krs/core/validate.hpp"
#include "krs/field.hpp"

#include <algorithm>
#include <cmath>
#include <cstddef>
#include <string>
#include <vector>

namespace krs {

struct slice_plane {
    static constexpr int max_resolution = 16384;
    vec3f origin{0, 0, 0};  // the centre of the image
    vec3f u_axis{1, 0, 0};  // image right; made unit by validate()
    vec3f v_axis{0, 1, 0};  // image up; made unit, must be perpendicular to u_axis
    float half_width = 1.0f, half_height = 1.0f; // extent along u and v from the origin
    int columns = 256, rows = 256;

    // Checks every parameter and makes the axes unit (so a plane built with axes (2, 0, 0) reads
    // back unit); throws invalid_parameter naming the first bad one.
    void validate()
    {
        require_magnitude("slice_plane.origin", origin);
        u_axis = require_direction("slice_plane.u_axis", u_axis);
        v_axis = require_direction("slice_plane.v_axis", v_axis);
        // 1e-4: an image whose axes are not perpendicular shows the field sheared.
        if (!(std::abs(double(dot(vec3d(u_axis), vec3d(v_axis)))) <= 1e-4))
            throw invalid_parameter("slice_plane.v_axis", "must be perpendicular to slice_plane.u_axis",
                                    detail::to_text(v_axis));
        require_positive_length("slice_plane.half_width", half_width);
        require_positive_length("slice_plane.half_height", half_height);
        require_resolution("slice_plane.columns", columns);
        require_resolution("slice_plane.rows", rows);
        if (!(length(vec3d(origin)) + std::hypot(double(half_width), double(half_height)) <= double(max_magnitude)))
            throw invalid_parameter("slice_plane.half_width",
                                    "with half_height and the origin must keep every pixel within 1e9 of the origin",
                                    detail::to_text(half_width));
    }

    // The world point at the centre of pixel (column, row), rounded once from double.
    vec3f point(int column, int row) const
    {
        const double s = ((double(column) + 0.5) / double(columns) * 2.0 - 1.0) * double(half_width);
        const double t = (1.0 - (double(row) + 0.5) / double(rows) * 2.0) * double(half_height);
        return vec3f(vec3d(origin) + vec3d(u_axis) * s + vec3d(v_axis) * t);
    }
    // The larger side of a pixel in world units.
    double pixel_size() const { return std::max(2.0 * half_width / columns, 2.0 * half_height / rows); }

private:
    static void require_resolution(const char* name, int n)
    {
        if (n < 1 || n > max_resolution)
            throw invalid_parameter(name, "must be in [1, 16384]", std::to_string(n));
    }
};

struct cross_section_options {
    float iso_spacing = 0.1f;          // world distance between iso lines
    float line_width = 1.0f;           // iso line width in pixels
    float gradient_step = 0.0f;        // h of the central differences; 0: half a pixel
    float lipschitz_tolerance = 1e-3f; // |grad| > 1 + this is flagged

    void validate() const
    {
        require_positive_length("cross_section_options.iso_spacing", iso_spacing);
        if (!std::isfinite(line_width) || !(line_width > 0.0f && line_width <= 64.0f))
            throw invalid_parameter("cross_section_options.line_width", "must be in (0, 64] pixels",
                                    detail::to_text(line_width));
        require_length("cross_section_options.gradient_step", gradient_step);
        if (!std::isfinite(lipschitz_tolerance) || !(lipschitz_tolerance >= 0.0f && lipschitz_tolerance <= 1.0f))
            throw invalid_parameter("cross_section_options.lipschitz_tolerance", "must be in [0, 1]",
                                    detail::to_text(lipschitz_tolerance));
    }
};

enum class section_pixel : unsigned char { outside, inside, iso_line, zero_line, not_finite };

struct cross_section_image {
    slice_plane plane;
    cross_section_options options;
    double step = 0;                      // the h used for the gradient
    std::vector<float> distance;          // per pixel, rows top first
    std::vector<float> gradient;          // |grad d| per pixel (central differences)
    std::vector<float> slope;             // the quotient along the gradient's direction per pixel
    std::vector<section_pixel> kind;      // the distance image's class per pixel
    std::size_t overestimating = 0;       // pixels with overestimates(i), the non-finite ones included
    std::size_t non_finite = 0;           // pixels of kind not_finite
    float max_gradient = 0, max_slope = 0; // over the finite pixels

    std::size_t pixels() const { return distance.size(); }
    bool overestimates(std::size_t i) const
    {
        return kind[i] == section_pixel::not_finite || slope[i] > 1.0f + options.lipschitz_tolerance;
    }

    // Linear RGB, 3 floats per pixel, rows top first (see the top of this file).
    std::vector<float> distance_image() const
    {
        std::vector<float> rgb(3 * pixels());
        for (std::size_t i = 0; i < pixels(); ++i) {
            float r = 1, g = 1, b = 1; // the zero line
            const double d = distance[i];
            if (kind[i] == section_pixel::not_finite) {
                r = b = 1.0f, g = 0.0f; // magenta
            } else if (kind[i] == section_pixel::iso_line) {
                r = g = b = 0.05f;
            } else if (kind[i] != section_pixel::zero_line) {
                const bool inside = kind[i] == section_pixel::inside;
                const double band = std::floor(d / double(options.iso_spacing));
                // Alternate bands darker; fade with distance so the nearest bands stand out.
                const float shade = (std::fmod(std::abs(band), 2.0) < 1.0 ? 1.0f : 0.8f) *
                                    float(0.55 + 0.45 * std::exp(-std::abs(d) / (8.0 * double(options.iso_spacing))));
                r = (inside ? 0.25f : 0.90f) * shade;
                g = (inside ? 0.50f : 0.55f) * shade;
                b = (inside ? 0.90f : 0.25f) * shade;
            }
            rgb[3 * i] = r, rgb[3 * i + 1] = g, rgb[3 * i + 2] = b;
        }
        return rgb;
    }
    std::vector<float> gradient_image() const
    {
        std::vector<float> rgb(3 * pixels());
        for (std::size_t i = 0; i < pixels(); ++i) {
            const float m = gradient[i];
            if (kind[i] == section_pixel::not_finite) {
                rgb[3 * i] = rgb[3 * i + 2] = 1.0f, rgb[3 * i + 1] = 0.0f; // magenta
            } else if (overestimates(i)) {
                rgb[3 * i] = 1.0f, rgb[3 * i + 1] = 0.9f * std::clamp(slope[i] - 1.0f, 0.0f, 1.0f), rgb[3 * i + 2] = 0.05f;
            } else {
                const float grey = 0.05f + 0.75f * std::clamp(m, 0.0f, 1.0f);
                rgb[3 * i] = rgb[3 * i + 1] = rgb[3 * i + 2] = grey;
            }
        }
        return rgb;
    }
};

// Samples `f` on `plane` (see the top of this file). Validates plane and options first.
template <field F>
cross_section_image cross_section(const F& f, slice_plane plane, const cross_section_options& options = {})
{
    plane.validate();
    options.validate();
    cross_section_image out;
    out.plane = plane;
    out.options = options;
    out.step = options.gradient_step > 0.0f ? double(options.gradient_step) : 0.5 * plane.pixel_size();
    const std::size_t n = std::size_t(plane.columns) * std::size_t(plane.rows);
    out.distance.resize(n);
    out.gradient.resize(n);
    out.slope.resize(n);
    out.kind.resize(n);
    const double half_line = 0.5 * double(options.line_width) * plane.pixel_size();
    const double spacing = options.iso_spacing;
    const float h = float(out.step);
    for (int row = 0; row < plane.rows; ++row)
        for (int column = 0; column < plane.columns; ++column) {
            const std::size_t i = std::size_t(row) * std::size_t(plane.columns) + std::size_t(column);
            const vec3f p = plane.point(column, row);
            const float d = f.distance(p);
            bool finite = std::isfinite(d);
            double g[3] = {0, 0, 0};
            for (int axis = 0; axis < 3; ++axis) {
                vec3f a = p, b = p;
                float& ca = axis == 0 ? a.x : axis == 1 ? a.y : a.z;
                float& cb = axis == 0 ? b.x : axis == 1 ? b.y : b.z;
                ca += h;
                cb -= h;
                const double taken = double(ca) - double(cb);
                // A step below the coordinate's ulp moves nothing: no slope is measured on that axis.
                const float da = f.distance(a), db = f.distance(b);
                finite = finite && std::isfinite(da) && std::isfinite(db);
                if (taken > 0) g[axis] = (double(da) - double(db)) / taken;
            }
            const double magnitude = std::sqrt(g[0] * g[0] + g[1] * g[1] + g[2] * g[2]);
            double slope = 0;
            if (finite && magnitude > 0) {
                const vec3d u = vec3d{g[0], g[1], g[2]} * (double(h) / magnitude);
                const vec3f a(vec3d(p) + u), b(vec3d(p) - u);
                const double taken = length(vec3d(a) - vec3d(b));
                const float da = f.distance(a), db = f.distance(b);
                finite = finite && std::isfinite(da) && std::isfinite(db);
                if (taken > 0) slope = std::abs(double(da) - double(db)) / taken;
            }
            // Finite samples can still give an infinite quotient (differences near FLT_MAX / h).
            finite = finite && std::isfinite(float(magnitude)) && std::isfinite(float(slope));
            const double dd = d;
            const double k = std::round(dd / spacing);
            section_pixel kind = dd < 0 ? section_pixel::inside : section_pixel::outside;
            if (std::abs(dd - k * spacing) <= half_line) kind = k == 0 ? section_pixel::zero_line : section_pixel::iso_line;
            if (!finite) kind = section_pixel::not_finite;
            out.distance[i] = d;
            out.gradient[i] = float(magnitude);
            out.slope[i] = float(slope);
            out.kind[i] = kind;
            if (finite) {
                out.max_gradient = std::max(out.max_gradient, out.gradient[i]);
                out.max_slope = std::max(out.max_slope, out.slope[i]);
            }
            out.non_finite += !finite;
            out.overestimating += out.overestimates(i);
        }
    return out;
}

} // namespace krs

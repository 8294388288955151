// The cross-section view (krs/cross_section.hpp) against closed forms: a sphere's slice (distance
// at every pixel = |p - c| - r, iso lines exactly where that is within half a line of a multiple
// of the spacing, |grad| = 1 within the central differences' bound), a field scaled by 2 flagged
// at every pixel, a plane field's gradient, a 1-Lipschitz field with creases (Menger sponge) not
// flagged where its |grad| reads above 1, the images' colours per class, and validation.

#include "krs/cross_section.hpp"
#include "krs/fractal/kifs_presets.hpp"
#include "krs/kernels/plane.hpp"
#include "krs/kernels/sphere.hpp"
#include "support/rejects.hpp"

#include <doctest/doctest.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <functional>
#include <limits>
#include <string>

namespace {

using krs::vec3d;
using krs::vec3f;

// A sphere whose distance is scaled by 2: it overestimates everywhere (|grad| = 2).
struct doubled_sphere {
    krs::sphere s;
    template <class T>
    T distance(const krs::vec3<T>& p) const
    {
        return T(2) * s.distance(p);
    }
};

krs::slice_plane test_plane()
{
    krs::slice_plane plane;
    plane.origin = {0.05f, -0.1f, 0.45f}; // 0.15 above the sphere's centre: no pixel at the centre
    plane.u_axis = {1, 0, 0};
    plane.v_axis = {0, 1, 0};
    plane.half_width = 1.2f;
    plane.half_height = 0.9f;
    plane.columns = 160;
    plane.rows = 120;
    return plane;
}

// A sphere whose distance is NaN where x > 0.5 and +infinity where x < -0.5.
struct broken_sphere {
    krs::sphere s;
    template <class T>
    T distance(const krs::vec3<T>& p) const
    {
        using krs::select;
        const T d = s.distance(p);
        return select(p.x > T(0.5f), T(std::numeric_limits<float>::quiet_NaN()),
                      select(p.x < T(-0.5f), T(std::numeric_limits<float>::infinity()), d));
    }
};

const vec3d centre{0.1, -0.2, 0.3};
constexpr double radius = 0.7;

} // namespace

TEST_CASE("cross_section of a sphere: distances, iso lines and gradient against the closed form")
{
    const krs::sphere s{vec3f(centre), float(radius)};
    krs::slice_plane plane = test_plane();
    krs::cross_section_options options;
    options.iso_spacing = 0.125f;
    options.line_width = 1.5f;
    const krs::cross_section_image image = krs::cross_section(s, plane, options);
    plane.validate();
    REQUIRE(image.pixels() == std::size_t(plane.columns * plane.rows));

    const double half_line = 0.5 * 1.5 * plane.pixel_size();
    const double h = image.step;
    CHECK(h == doctest::Approx(0.5 * plane.pixel_size()));
    double worst_distance = 0, worst_gradient = 0;
    std::size_t lines = 0, zero = 0, inside = 0, outside = 0, class_wrong = 0, ambiguous = 0, gradient_wrong = 0;
    for (int row = 0; row < plane.rows; ++row)
        for (int column = 0; column < plane.columns; ++column) {
            const std::size_t i = std::size_t(row * plane.columns + column);
            // The pixel centre from its definition, in double: origin + u s + v t.
            const double sx = ((column + 0.5) / plane.columns * 2 - 1) * 1.2, ty = (1 - (row + 0.5) / plane.rows * 2) * 0.9;
            const vec3d p = vec3d(vec3f{0.05f, -0.1f, 0.45f}) + vec3d{sx, ty, 0};
            const double r = krs::length(p - centre);
            const double closed = r - radius;
            // float point (one rounding) and float distance: a few ulps of |p| and r
            worst_distance = std::max(worst_distance, std::abs(double(image.distance[i]) - closed));
            // The class from the closed form, unless it lies within 1e-5 of a class boundary.
            const double k = std::round(closed / options.iso_spacing), off = std::abs(closed - k * options.iso_spacing);
            if (std::abs(off - half_line) < 1e-5) {
                ++ambiguous;
            } else {
                const krs::section_pixel want = off <= half_line ? (k == 0 ? krs::section_pixel::zero_line : krs::section_pixel::iso_line)
                                                                 : closed < 0 ? krs::section_pixel::inside
                                                                              : krs::section_pixel::outside;
                class_wrong += image.kind[i] != want;
            }
            lines += image.kind[i] == krs::section_pixel::iso_line;
            zero += image.kind[i] == krs::section_pixel::zero_line;
            inside += image.kind[i] == krs::section_pixel::inside;
            outside += image.kind[i] == krs::section_pixel::outside;
            // Central differences of |p - c|: each component is 4 h q_k / (|q + h e_k| + |q - h e_k|),
            // at most q_k / |q|, and |grad| falls short of 1 by at most h^2 / (2 |q|^2) (second order),
            // plus the float error of two distances over the step (~1e-7 |q| / h each).
            // The slope along the gradient is the same difference quotient in one direction: the same bound.
            const double bound = h * h / (r * r) + 4e-7 * (r + 1) / h;
            const double e = std::max(std::abs(double(image.gradient[i]) - 1.0), std::abs(double(image.slope[i]) - 1.0));
            worst_gradient = std::max(worst_gradient, e / bound);
            gradient_wrong += e > bound;
        }
    std::printf("cross_section sphere %dx%d: max |d - (|p - c| - r)| %.3g; classes wrong %zu (ambiguous %zu); iso-line "
                "pixels %zu, zero line %zu, inside %zu, outside %zu; max | |grad| - 1 | and | slope - 1 | / bound %.3g; "
                "max |grad| %.7g, slope %.7g; flagged %zu\n",
                plane.columns, plane.rows, worst_distance, class_wrong, ambiguous, lines, zero, inside, outside,
                worst_gradient, double(image.max_gradient), double(image.max_slope), image.overestimating);
    CHECK(worst_distance <= 4e-7);
    CHECK(class_wrong == 0);
    CHECK(ambiguous <= 10);
    // The slice cuts the sphere in a circle of radius sqrt(0.7^2 - 0.15^2) = 0.68: lines inside and out.
    CHECK(lines >= 500);
    CHECK(zero >= 200);
    CHECK(inside >= 1000);
    CHECK(outside >= 5000);
    CHECK(gradient_wrong == 0);
    CHECK(image.overestimating == 0);

    // The images show each class in its colour.
    const std::vector<float> rgb = image.distance_image(), grad = image.gradient_image();
    REQUIRE(rgb.size() == 3 * image.pixels());
    for (std::size_t i = 0; i < image.pixels(); ++i) {
        const float r = rgb[3 * i], g = rgb[3 * i + 1], b = rgb[3 * i + 2];
        switch (image.kind[i]) {
        case krs::section_pixel::zero_line: CHECK((r == 1.0f && g == 1.0f && b == 1.0f)); break;
        case krs::section_pixel::iso_line: CHECK((r < 0.1f && g < 0.1f && b < 0.1f)); break;
        case krs::section_pixel::inside: CHECK(b > r); break;
        default: CHECK(r > b);
        }
        CHECK(grad[3 * i] == grad[3 * i + 2]); // grey: nothing flagged
    }
}

TEST_CASE("cross_section flags a field that overestimates by 2 at every pixel")
{
    const doubled_sphere f{krs::sphere(vec3f(centre), float(radius))};
    const krs::cross_section_image image = krs::cross_section(f, test_plane());
    double worst = 0;
    for (std::size_t i = 0; i < image.pixels(); ++i)
        worst = std::max({worst, std::abs(double(image.gradient[i]) - 2.0), std::abs(double(image.slope[i]) - 2.0)});
    std::printf("cross_section doubled sphere: %zu of %zu pixels flagged, max | |grad| - 2 | %.3g\n", image.overestimating,
                image.pixels(), worst);
    CHECK(image.overestimating == image.pixels());
    CHECK(worst <= 0.01); // twice the sphere's bound above, at its worst pixel (nearest the centre)
    CHECK(image.max_slope > 1.99f);
    const std::vector<float> grad = image.gradient_image();
    for (std::size_t i = 0; i < image.pixels(); ++i) CHECK((grad[3 * i] == 1.0f && grad[3 * i + 2] < 0.1f)); // red
}

TEST_CASE("cross_section shows and counts non-finite distances: NaN and infinity are flagged, never hidden")
{
    const broken_sphere f{krs::sphere(vec3f(centre), float(radius))};
    const krs::slice_plane plane = test_plane();
    const krs::cross_section_image image = krs::cross_section(f, plane);
    // Reference by position: a pixel past |x| = 0.5 has a non-finite distance itself; one within
    // 0.5 - 2h has all 9 samples (each within h of it) in the sphere's finite region.
    const double h = image.step, margin = 0.5 - 2 * h;
    const std::vector<float> rgb = image.distance_image(), grad = image.gradient_image();
    std::size_t outer = 0, inner = 0, wrong = 0, not_magenta = 0;
    for (int row = 0; row < plane.rows; ++row)
        for (int column = 0; column < plane.columns; ++column) {
            const std::size_t i = std::size_t(row * plane.columns + column);
            const double x = plane.point(column, row).x;
            const bool bad = image.kind[i] == krs::section_pixel::not_finite;
            if (std::abs(x) > 0.5) {
                ++outer;
                wrong += !bad || !image.overestimates(i);
                for (const std::vector<float>* c : {&rgb, &grad})
                    not_magenta += !((*c)[3 * i] == 1.0f && (*c)[3 * i + 1] == 0.0f && (*c)[3 * i + 2] == 1.0f);
            } else if (std::abs(x) < margin) {
                ++inner;
                wrong += bad || image.overestimates(i);
            }
        }
    std::size_t counted = 0;
    for (std::size_t i = 0; i < image.pixels(); ++i) counted += image.kind[i] == krs::section_pixel::not_finite;
    std::printf("cross_section NaN/inf sphere: %zu non-finite, %zu flagged of %zu pixels (%zu past |x| = 0.5)\n",
                image.non_finite, image.overestimating, image.pixels(), outer);
    REQUIRE(outer > 0);
    REQUIRE(inner > 0);
    CHECK(wrong == 0);
    CHECK(not_magenta == 0);
    CHECK(image.non_finite == counted);
    CHECK(image.non_finite >= outer);
    CHECK(image.overestimating == image.non_finite); // the finite part is a true sphere: nothing else flagged
    CHECK(std::isfinite(image.max_gradient));
    CHECK(std::isfinite(image.max_slope));
    CHECK(image.max_slope <= 1.0f + 1e-3f);
}

TEST_CASE("cross_section does not flag a 1-Lipschitz field at its creases, where |grad| reads above 1")
{
    // The Menger sponge is 1-Lipschitz by construction (krs/fractal/kifs.hpp; measured on close
    // pairs in test_fractal.cpp). Within h of its fold planes the central differences of different
    // axes straddle a crease and their vector is longer than 1; the slope along it stays <= 1.
    krs::slice_plane plane;
    plane.origin = {0, 0, 0.1f};
    plane.half_width = plane.half_height = 1.3f;
    plane.columns = plane.rows = 128;
    const krs::cross_section_image image = krs::cross_section(krs::make_menger_sponge(4), plane);
    std::size_t above = 0;
    for (std::size_t i = 0; i < image.pixels(); ++i) above += image.gradient[i] > 1.001f;
    std::printf("cross_section Menger sponge: %zu pixels with |grad| > 1.001 (max %.5f), max slope %.7f, flagged %zu\n",
                above, double(image.max_gradient), double(image.max_slope), image.overestimating);
    CHECK(above >= 50); // the case this guards: the norm alone would flag these
    CHECK(image.overestimating == 0);
    CHECK(image.max_slope <= 1.0f + 1e-4f);
}

TEST_CASE("cross_section of a tilted plane in a tilted slice: gradient 1, distance the closed form")
{
    const vec3f n = krs::normalize(vec3f{0.3f, 0.8f, -0.5f});
    const krs::plane field(n, 0.2f);
    krs::slice_plane plane;
    plane.origin = {0.1f, 0.2f, -0.3f};
    plane.u_axis = {1, 1, 0};
    plane.v_axis = {0, 0, 2}; // made unit by validate
    plane.columns = plane.rows = 64;
    const krs::cross_section_image image = krs::cross_section(field, plane);
    plane.validate();
    CHECK(image.plane.v_axis.z == 1.0f);
    double worst_d = 0, worst_g = 0;
    for (int row = 0; row < plane.rows; ++row)
        for (int column = 0; column < plane.columns; ++column) {
            const std::size_t i = std::size_t(row * plane.columns + column);
            const vec3d p(plane.point(column, row));
            worst_d = std::max(worst_d, std::abs(double(image.distance[i]) - (krs::dot(vec3d(field.normal_direction), p) - double(field.offset))));
            worst_g = std::max({worst_g, std::abs(double(image.gradient[i]) - 1.0), std::abs(double(image.slope[i]) - 1.0)});
        }
    std::printf("cross_section plane: max |d - closed form| %.3g, max | |grad| - 1 | %.3g\n", worst_d, worst_g);
    CHECK(worst_d <= 1e-6);
    CHECK(worst_g <= 1e-4);
    CHECK(image.overestimating == 0);
}

TEST_CASE("cross_section parameters are validated")
{
    const krs::sphere s({0, 0, 0}, 1.0f);
    auto rejects = [&](const std::function<void(krs::slice_plane&, krs::cross_section_options&)>& spoil,
                       const std::string& parameter) {
        krs::slice_plane plane;
        krs::cross_section_options options;
        spoil(plane, options);
        krs_test::rejects([&] { krs::cross_section(s, plane, options); }, parameter);
    };
    const float nan = std::nanf(""), inf = std::numeric_limits<float>::infinity();
    rejects([&](auto& p, auto&) { p.origin = {nan, 0, 0}; }, "slice_plane.origin");
    rejects([](auto& p, auto&) { p.origin = {2e9f, 0, 0}; }, "slice_plane.origin");
    rejects([](auto& p, auto&) { p.u_axis = {0, 0, 0}; }, "slice_plane.u_axis");
    rejects([&](auto& p, auto&) { p.v_axis = {0, inf, 0}; }, "slice_plane.v_axis");
    rejects([](auto& p, auto&) { p.v_axis = {1, 1, 0}; }, "slice_plane.v_axis"); // not perpendicular
    rejects([](auto& p, auto&) { p.half_width = 0; }, "slice_plane.half_width");
    rejects([&](auto& p, auto&) { p.half_height = nan; }, "slice_plane.half_height");
    rejects([](auto& p, auto&) { p.half_width = p.half_height = 1e9f; }, "slice_plane.half_width"); // corners beyond 1e9
    rejects([](auto& p, auto&) { p.columns = 0; }, "slice_plane.columns");
    rejects([](auto& p, auto&) { p.rows = 16385; }, "slice_plane.rows");
    rejects([](auto&, auto& o) { o.iso_spacing = 0; }, "cross_section_options.iso_spacing");
    rejects([&](auto&, auto& o) { o.iso_spacing = nan; }, "cross_section_options.iso_spacing");
    rejects([](auto&, auto& o) { o.line_width = 0; }, "cross_section_options.line_width");
    rejects([](auto&, auto& o) { o.line_width = 65; }, "cross_section_options.line_width");
    rejects([](auto&, auto& o) { o.gradient_step = -1; }, "cross_section_options.gradient_step");
    rejects([&](auto&, auto& o) { o.lipschitz_tolerance = nan; }, "cross_section_options.lipschitz_tolerance");
    rejects([](auto&, auto& o) { o.lipschitz_tolerance = -0.5f; }, "cross_section_options.lipschitz_tolerance");
}

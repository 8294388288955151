#pragma once
// Reference points of kernel solids for the bounding-box tests, computed from the parameters a
// kernel was built from and not from anything the kernel derived.
//
// Sphere, capsule, torus and torus capsule are each a ball of radius r swept along a spine (a
// point, a segment, a circle, a circular arc). A ball is the same in every orientation, so the
// solid's extreme point along world axis i is a spine point plus r e_i, also after any isometry:
// the spine's samples, moved by r along each of the six axis directions, reach the solid's box
// up to the sampling's sag, rho (1 - cos(pi / N)) for a circle of radius rho in N samples. A box
// kernel's extreme points are its corners.

#include "krs/core/vec3.hpp"
#include "krs/kernels/kernels.hpp"

#include <cmath>
#include <numbers>
#include <vector>

namespace krs_test {

struct swept_ball {
    std::vector<krs::vec3d> spine;
    double radius = 0;
};

// The circle of radius rho around `center` in the plane with normal `axis`, from angle 0 to
// `turn` (radians, either sign) starting at `first` (a unit vector in the plane): count samples.
inline std::vector<krs::vec3d> circle_samples(const krs::vec3d& center, const krs::vec3d& axis, double rho,
                                              const krs::vec3d& first, double turn, int count)
{
    const krs::vec3d n = krs::normalize(axis);
    const krs::vec3d e1 = krs::normalize(first - n * krs::dot(first, n));
    const krs::vec3d e2 = krs::cross(n, e1);
    std::vector<krs::vec3d> out;
    for (int k = 0; k < count; ++k) {
        const double t = turn * double(k) / double(count - 1);
        out.push_back(center + (e1 * std::cos(t) + e2 * std::sin(t)) * rho);
    }
    return out;
}

// A ring: the circle (center, axis, major) and the tube radius.
inline swept_ball ring_spine(const krs::vec3d& center, const krs::vec3d& axis, double major, double minor, int count)
{
    const krs::vec3d helper = std::abs(axis.x) < std::abs(axis.y) ? krs::vec3d{1, 0, 0} : krs::vec3d{0, 1, 0};
    return {circle_samples(center, axis, major, helper, 2 * std::numbers::pi, count), minor};
}

// The arc from `start` through `control` to `end`: the circle through the three points (their
// circumcenter), walked from start in the direction that meets control before end; a segment
// when the three are collinear.
inline swept_ball arc_spine(const krs::vec3d& start, const krs::vec3d& end, const krs::vec3d& control, double radius,
                            int count)
{
    const krs::vec3d u = control - start, v = end - start, w = krs::cross(u, v);
    const double w2 = krs::dot(w, w);
    swept_ball out{{}, radius};
    if (w2 <= 1e-24 * krs::dot(u, u) * krs::dot(v, v)) {
        for (int k = 0; k < count; ++k) out.spine.push_back(start + v * (double(k) / double(count - 1)));
        return out;
    }
    const krs::vec3d center =
        start + (krs::cross(w, u) * krs::dot(v, v) + krs::cross(v, w) * krs::dot(u, u)) * (1.0 / (2 * w2));
    const double rho = krs::length(start - center);
    const krs::vec3d e1 = (start - center) / rho, e2 = krs::normalize(krs::cross(w, e1));
    const auto angle = [&](const krs::vec3d& p) {
        const double a = std::atan2(krs::dot(p - center, e2), krs::dot(p - center, e1));
        return a < 0 ? a + 2 * std::numbers::pi : a;
    };
    const double to_control = angle(control), to_end = angle(end);
    const double turn = to_control < to_end ? to_end : to_end - 2 * std::numbers::pi;
    out.spine = circle_samples(center, w, rho, e1, turn, count);
    return out;
}

// Where the swept ball reaches along each axis: spine points +- r e_i.
inline std::vector<krs::vec3d> extreme_candidates(const swept_ball& b)
{
    std::vector<krs::vec3d> out;
    const double r = b.radius;
    for (const krs::vec3d& p : b.spine)
        for (const krs::vec3d& e : {krs::vec3d{r, 0, 0}, krs::vec3d{0, r, 0}, krs::vec3d{0, 0, r}}) {
            out.push_back(p + e);
            out.push_back(p - e);
        }
    return out;
}

// The eight corners of a box (center, half extents, orthonormal axes as given).
inline std::vector<krs::vec3d> box_corners(const krs::vec3d& center, const krs::vec3d& half, const krs::vec3d& ax,
                                           const krs::vec3d& ay, const krs::vec3d& az)
{
    std::vector<krs::vec3d> out;
    for (int c = 0; c < 8; ++c)
        out.push_back(center + ax * ((c & 1) ? half.x : -half.x) + ay * ((c & 2) ? half.y : -half.y) +
                      az * ((c & 4) ? half.z : -half.z));
    return out;
}

// Points of a kernel's solid reaching its box on every side (up to the sampling's sag), from the
// parameters it was given: `count` samples per spine.
inline std::vector<krs::vec3d> reference_points(const krs::sphere& k, int)
{
    return extreme_candidates({{krs::vec3d(k.center)}, k.radius});
}
inline std::vector<krs::vec3d> reference_points(const krs::capsule& k, int count)
{
    return extreme_candidates(arc_spine(krs::vec3d(k.a), krs::vec3d(k.b), krs::vec3d(k.a), k.radius, count));
}
inline std::vector<krs::vec3d> reference_points(const krs::torus& k, int count)
{
    return extreme_candidates(
        ring_spine(krs::vec3d(k.center()), krs::vec3d(k.axis()), k.major_radius(), k.minor_radius(), count));
}
inline std::vector<krs::vec3d> reference_points(const krs::torus_capsule& k, int count)
{
    return extreme_candidates(
        arc_spine(krs::vec3d(k.start()), krs::vec3d(k.end()), krs::vec3d(k.control()), k.radius(), count));
}
inline std::vector<krs::vec3d> reference_points(const krs::box& k, int)
{
    return box_corners(krs::vec3d(k.center()), krs::vec3d(k.half_extents()), krs::vec3d(k.axis(0)),
                       krs::vec3d(k.axis(1)), krs::vec3d(k.axis(2)));
}

} // namespace krs_test

#pragma once
// Torus-capsule kernel: every point within `radius` of a circular arc (the KRS paper's branch
// kernel, section 7.2: a torus segment capped by two spheres).
//
// Built from intuitive parameters: the arc runs from `start` to `end` through `control`. A
// control point on the chord gives a straight arc (the kernel is then a capsule); one off the
// chord bends it, up to a major arc of almost a full turn.
//
// The distance is evaluated from the chord's midpoint, so it stays exact and free of
// cancellation for any curvature kappa, including 0, and for any arc up to almost a full turn.
// With alpha half the arc's central angle, M the in-plane unit vector from the chord toward the
// bulge, N the plane's normal, u = p - chord middle, h_n = dot(u, N) and u_p = u - h_n N,
//     radial = (kappa |u_p|^2 + 2 cos(alpha) dot(u_p, M) - h sin(alpha)) / (|kappa u_p + cos(alpha) M| + 1)
// equals |p_plane - center| - R written as (|q|^2 - R^2) / (|q| + R) and divided by R = 1/kappa
// (the center is R cos(alpha) behind the chord and R sin(alpha) = h, the half chord). Every term
// is of the size of u, so nothing cancels and it tends to dot(u_p, M) as kappa -> 0; the
// denominator is never below 1. Inside the arc's wedge the distance to the arc is
// sqrt(radial^2 + h_n^2); outside it the distance to the circle grows with the angle from p, so
// the nearer endpoint is the closest arc point. The result minus `radius` is exact (1-Lipschitz,
// zero on the surface).
//
// Anchoring at the chord rather than at the arc's midpoint matters for major arcs of large
// radius (a control point just off the chord's extension): their midpoint is 2R away, and a
// float offset from it would lose ulp(2R) near the branch's ends.

#include "krs/core/bounds.hpp"
#include "krs/core/validate.hpp"
#include "krs/kernels/capsule.hpp"

#include <array>
#include <algorithm>
#include <cmath>
#include <numbers>
#include <string_view>

namespace krs {

// Surface coordinates of a kernel: u along the kernel, v around it, both in [0, 1].
template <class T>
struct surface_uv {
    T u, v;
};

class torus_capsule {
public:
    torus_capsule() : torus_capsule(vec3f{0, 0, 0}, vec3f{0, 0, 1}, vec3f{0, 0, 0.5f}, 0.0f) {}
    torus_capsule(const vec3f& start, const vec3f& end, const vec3f& control, float radius)
        : start_(require_magnitude("torus_capsule.start", start)), end_(require_magnitude("torus_capsule.end", end)),
          control_(require_magnitude("torus_capsule.control", control)),
          radius_(require_length("torus_capsule.radius", radius))
    {
        // Everything derived is computed in double from the float inputs and rounded once.
        const vec3d s(start_), e(end_), c(control_);
        const vec3d chord = e - s;
        const double chord_length = length(chord);
        // The curvature is at most 2 / chord: a chord of min_length or more keeps it <= 2e6, so
        // the distance's curvature * u and curvature * |u|^2 stay finite floats at every point the
        // magnitude policy covers, even folded by 64 mirrors (krs/core/validate.hpp).
        if (!(chord_length >= double(min_length)))
            throw invalid_parameter("torus_capsule.end", "must lie at least 1e-6 (min_length) from start",
                                    detail::to_text(end_) + " with start = " + detail::to_text(start_));
        const vec3d a = s - c, b = e - c;
        const double la = length(a), lb = length(b);
        if (!(la > 0) || !(lb > 0))
            throw invalid_parameter("torus_capsule.control", "must differ from start and end",
                                    detail::to_text(control_));
        // alpha is half the arc's central angle; the inscribed angle at control is pi - alpha.
        double sin_alpha = length(cross(a, b)) / (la * lb);
        double cos_alpha = -dot(a, b) / (la * lb);
        if (sin_alpha < 1e-6 && cos_alpha < 0)
            throw invalid_parameter("torus_capsule.control", "must lie between start and end when collinear",
                                    detail::to_text(control_));
        const double h = 0.5 * chord_length;
        const vec3d tangent = chord / chord_length;
        const vec3d chord_middle = (s + e) * 0.5;
        vec3d toward_control, plane_normal;
        // Below this the bend is under double rounding of the cross product: treat as straight.
        if (sin_alpha > 1e-7) {
            const vec3d sc = c - s;
            toward_control = normalize(sc - tangent * dot(sc, tangent));
            plane_normal = cross(tangent, toward_control);
            const double norm = std::hypot(sin_alpha, cos_alpha); // both came from the same |a||b|
            sin_alpha /= norm;
            cos_alpha /= norm;
        } else {
            sin_alpha = 0;
            cos_alpha = 1;
            const bool x_smallest =
                std::abs(tangent.x) <= std::abs(tangent.y) && std::abs(tangent.x) <= std::abs(tangent.z);
            const vec3d helper = x_smallest
                                     ? vec3d{1, 0, 0}
                                     : (std::abs(tangent.y) <= std::abs(tangent.z) ? vec3d{0, 1, 0} : vec3d{0, 0, 1});
            plane_normal = normalize(cross(tangent, helper));
            toward_control = cross(plane_normal, tangent);
        }
        const double kappa = sin_alpha / h;
        // Sagitta h (1 - cos) / sin, in the form that does not cancel on each side of pi/2.
        const double sagitta = cos_alpha >= 0 ? h * sin_alpha / (1 + cos_alpha) : (1 - cos_alpha) / kappa;
        const vec3d mid = chord_middle + toward_control * sagitta;

        half_chord_ = static_cast<float>(h);
        chord_offset_ = static_cast<float>(h * sin_alpha);
        curvature_ = static_cast<float>(kappa);
        sin_half_angle_ = static_cast<float>(sin_alpha);
        cos_half_angle_ = static_cast<float>(cos_alpha);
        half_angle_ = static_cast<float>(std::atan2(sin_alpha, cos_alpha));
        major_ = cos_alpha < 0;
        // Arc length from the midpoint to either end: alpha R, which is h on a straight arc.
        half_arc_length_ = static_cast<float>(sin_alpha > 0 ? std::atan2(sin_alpha, cos_alpha) / kappa : h);
        chord_middle_ = vec3f(chord_middle);
        chord_direction_ = vec3f(tangent);
        toward_control_ = vec3f(toward_control);
        plane_normal_ = vec3f(plane_normal);
        arc_midpoint_ = vec3f(mid);
        start_tangent_ = vec3f(tangent * cos_alpha + toward_control * sin_alpha);
        end_tangent_ = vec3f(tangent * -cos_alpha + toward_control * sin_alpha);
        // The center sits R cos(alpha) behind the chord (in front of it for a major arc).
        const vec3d center = chord_middle - toward_control * (cos_alpha / (kappa > 0 ? kappa : 1));
        if (kappa > 0) {
            circle_center_ = vec3f(center);
            circle_radius_ = static_cast<float>(1 / kappa);
        }
        // A minor arc sees its chord at an angle >= 90 degrees from every point, so it lies in
        // the ball on the chord as diameter; a major arc needs its whole circle's ball.
        bound_ = major_ ? bound_around(center, 1 / kappa + radius_)
                        : bound_around(chord_middle, h + radius_);
    }

    const vec3f& start() const { return start_; }
    const vec3f& end() const { return end_; }
    const vec3f& control() const { return control_; }
    float radius() const { return radius_; }
    // kappa = 1 / (circle radius); 0 for a straight arc.
    float curvature() const { return curvature_; }
    // The largest |p| at which the float distance is certain to be finite. evaluate() takes the
    // length of curvature * u (u = p - chord middle), which overflows once that passes 1.8e19, and
    // squares u: so |p| <= 1e19 / max(1, curvature), less the chord middle's |c| <= 1e9. Callers
    // that magnify points before evaluating a kernel (a KIFS) check against it; the magnitude
    // policy's own points (|p| <= 1.3e11 after 64 folds) are always within it.
    double input_reach() const { return 1e19 / std::max(1.0, double(curvature_)) - double(max_magnitude); }
    // Unit normal of the arc's plane (arbitrary perpendicular to the chord when straight).
    const vec3f& plane_normal() const { return plane_normal_; }
    // Unit vector in the arc plane, perpendicular to the chord, toward the bulge.
    const vec3f& toward_control() const { return toward_control_; }
    // Unit vector from start to end.
    const vec3f& chord_direction() const { return chord_direction_; }
    float half_chord() const { return half_chord_; }
    const vec3f& chord_middle() const { return chord_middle_; }
    const vec3f& arc_midpoint() const { return arc_midpoint_; }
    // Unit tangents at the ends pointing into the arc.
    const vec3f& start_tangent() const { return start_tangent_; }
    const vec3f& end_tangent() const { return end_tangent_; }
    // alpha: half the central angle of the arc, in [0, pi).
    float half_angle() const { return half_angle_; }
    float sin_half_angle() const { return sin_half_angle_; }
    float cos_half_angle() const { return cos_half_angle_; }
    bool is_major_arc() const { return major_; }
    float half_arc_length() const { return half_arc_length_; }
    // The circle's center and radius; meaningful only when curvature() > 0.
    const vec3f& circle_center() const { return circle_center_; }
    float circle_radius() const { return circle_radius_; }

    template <class T>
    T distance(const vec3<T>& p) const
    {
        return evaluate(p).to_arc - T(radius_);
    }

    // Outward normal: away from the closest arc point. On the arc itself, or on the circle's axis
    // where all circle points are equally near, a fixed unit direction is returned, never NaN.
    template <class T>
    vec3<T> normal(const vec3<T>& p) const
    {
        const arc_point<T> e = evaluate(p);
        const T one(1);
        const vec3<T> offset = e.radial_direction * e.radial + vec3<T>(plane_normal_) * e.height;
        const T torus = sqrt(e.torus_squared);
        const vec3<T> torus_dir = select(torus > T(0), offset / select(torus > T(0), torus, one),
                                         e.radial_direction);
        const T ls = length(e.from_start), le = length(e.from_end);
        const vec3<T> start_dir =
            select(ls > T(0), e.from_start / select(ls > T(0), ls, one), -vec3<T>(start_tangent_));
        const vec3<T> end_dir = select(le > T(0), e.from_end / select(le > T(0), le, one), -vec3<T>(end_tangent_));
        const vec3<T> cap_dir = select(ls <= le, start_dir, end_dir);
        return select(e.in_arc, torus_dir, cap_dir);
    }

    // u: position along the arc by angle (0 at start, 1 at end, clamped beyond the ends);
    // v: angle around the tube / (2 pi), in [0, 1]; 0.5 on the outside of the bend (away from the
    // circle's center; toward toward_control() when straight), 0.25 / 0.75 off the arc plane.
    template <class T>
    surface_uv<T> uv(const vec3<T>& p) const
    {
        const arc_point<T> e = evaluate(p);
        const T k(curvature_);
        const vec3<T> up = e.from_middle - vec3<T>(plane_normal_) * e.height;
        const T along_chord = dot(up, vec3<T>(chord_direction_));
        T from_mid = along_chord;
        // psi / kappa, psi = atan2(kappa x, cos(alpha) + kappa y) the angle from the arc's
        // midpoint: the arc length from it, accurate as kappa -> 0 because atan2 keeps relative
        // precision for small angles.
        if (curvature_ > 0)
            from_mid = lane_atan2(k * along_chord, T(cos_half_angle_) + k * dot(up, vec3<T>(toward_control_))) /
                       k;
        const T u = clamp(T(0.5f) + from_mid / T(2 * half_arc_length_), T(0), T(1));
        const T v = lane_atan2(e.height, e.radial) / T(2 * std::numbers::pi_v<float>) + T(0.5f);
        return {u, v};
    }

    bounding_sphere bound() const { return bound_; }
    // The arc's box grown by the radius, exact (a ball swept along the arc reaches r past the
    // arc on every axis, at the arc's extreme points). From the chord's midpoint m, the arc is
    //     a(t) = m + T sin(t) / kappa + M (cos(t) - cos(alpha)) / kappa,   t in [-alpha, alpha]
    // (T the chord direction, M toward the control point: a(+-alpha) are the ends, a(0) the
    // arc's midpoint), so coordinate i is extreme where T_i cos(t) = M_i sin(t), at
    // t = atan2(T_i, M_i) and that plus or minus pi, when those lie on the arc, or at the ends.
    // cos(t) - cos(alpha) is taken as 2 sin((alpha + t) / 2) sin((alpha - t) / 2), which does not
    // cancel on a nearly straight arc; a straight one is its chord. Computed in double from the
    // stored floats the distance reads; those are rounded from the exact arc by about 1e-7 of its
    // size, which the pad (a relative 1e-6 of the box's size plus r) covers. The ends enter as
    // stored too, so the caps' balls are held to the last ulp.
    bounding_box bound_box() const
    {
        const vec3d m(chord_middle_), t(chord_direction_), toward(toward_control_);
        const vec3d s(start_), e(end_);
        vec3d lo = min(s, e), hi = max(s, e);
        if (curvature_ > 0) {
            const double kappa = curvature_, alpha = std::atan2(double(sin_half_angle_), double(cos_half_angle_));
            const auto add = [&](double angle) {
                if (!(std::abs(angle) <= alpha)) return; // not on the arc
                const double along = std::sin(angle) / kappa;
                const double bulge = 2 * std::sin(0.5 * (alpha + angle)) * std::sin(0.5 * (alpha - angle)) / kappa;
                const vec3d p = m + t * along + toward * bulge;
                lo = min(lo, p), hi = max(hi, p);
            };
            add(alpha), add(-alpha);
            const double ti[3] = {t.x, t.y, t.z}, mi[3] = {toward.x, toward.y, toward.z};
            for (int i = 0; i < 3; ++i) {
                const double extreme = std::atan2(ti[i], mi[i]); // in [-pi, pi]
                add(extreme);
                add(extreme > 0 ? extreme - std::numbers::pi : extreme + std::numbers::pi);
            }
        }
        const vec3d r{radius_, radius_, radius_};
        const double size = std::max({hi.x - lo.x, hi.y - lo.y, hi.z - lo.z});
        return intersect(box_around(lo - r, hi + r, 1e-6 * (size + double(radius_))), box_around(bound_));
    }

    // GLSL: the chord-midpoint evaluation above, line for line. Seven vec4s:
    // (chord middle, kappa), (plane normal, cos alpha), (toward control, h sin alpha),
    // (start, radius), (end, major ? 1 : 0), (start tangent, 0), (end tangent, 0).
    // The colour a Shadertoy program and its reference shade this kind with where the caller
    // gives no palette (linear RGB; bark: bent capsules are stems).
    static constexpr vec3f default_albedo{0.40f, 0.26f, 0.15f};
    static constexpr std::string_view glsl_name = "krs_torus_capsule";
    static constexpr std::string_view glsl_source = R"(float krs_torus_capsule_distance(vec3 p, vec4 t0, vec4 t1, vec4 t2, vec4 t3, vec4 t4, vec4 t5, vec4 t6) {
    vec3 u = p - t0.xyz;
    float h = dot(u, t1.xyz);
    vec3 up = u - t1.xyz * h;
    float wl = length(up * t0.w + t2.xyz * t1.w);
    float radial = (t0.w * dot(up, up) + 2.0 * t1.w * dot(up, t2.xyz) - t2.w) / (wl + 1.0);
    float torus = sqrt(radial * radial + h * h);
    vec3 fs = p - t3.xyz;
    vec3 fe = p - t4.xyz;
    bool is = dot(fs, t5.xyz) >= 0.0;
    bool ie = dot(fe, t6.xyz) >= 0.0;
    bool inArc = t4.w != 0.0 ? (is || ie) : (is && ie);
    float ends = sqrt(min(dot(fs, fs), dot(fe, fe)));
    return (inArc ? torus : ends) - t3.w;
}
vec3 krs_torus_capsule_normal(vec3 p, vec4 t0, vec4 t1, vec4 t2, vec4 t3, vec4 t4, vec4 t5, vec4 t6) {
    vec3 u = p - t0.xyz;
    float h = dot(u, t1.xyz);
    vec3 up = u - t1.xyz * h;
    vec3 w = up * t0.w + t2.xyz * t1.w;
    float wl = length(w);
    float radial = (t0.w * dot(up, up) + 2.0 * t1.w * dot(up, t2.xyz) - t2.w) / (wl + 1.0);
    vec3 rd = wl > 0.0 ? w / wl : t2.xyz;
    float torus = sqrt(radial * radial + h * h);
    vec3 torusDir = torus > 0.0 ? (rd * radial + t1.xyz * h) / torus : rd;
    vec3 fs = p - t3.xyz;
    vec3 fe = p - t4.xyz;
    bool is = dot(fs, t5.xyz) >= 0.0;
    bool ie = dot(fe, t6.xyz) >= 0.0;
    bool inArc = t4.w != 0.0 ? (is || ie) : (is && ie);
    float ls = length(fs);
    float le = length(fe);
    vec3 sd = ls > 0.0 ? fs / ls : -t5.xyz;
    vec3 ed = le > 0.0 ? fe / le : -t6.xyz;
    return inArc ? torusDir : (ls <= le ? sd : ed);
}
)";
    std::array<float, 28> glsl_parameters() const
    {
        return {
                chord_middle_.x, chord_middle_.y, chord_middle_.z, curvature_,
                plane_normal_.x, plane_normal_.y, plane_normal_.z, cos_half_angle_,
                toward_control_.x, toward_control_.y, toward_control_.z, chord_offset_,
                start_.x, start_.y, start_.z, radius_,
                end_.x, end_.y, end_.z, major_ ? 1.0f : 0.0f,
                start_tangent_.x, start_tangent_.y, start_tangent_.z, 0.0f,
                end_tangent_.x, end_tangent_.y, end_tangent_.z, 0.0f};
    }

    // uv() in GLSL: vec2 krs_torus_capsule_uv(p, the seven vec4s of glsl_parameters(), (chord
    // direction, 2 half_arc_length)), the evaluation above up to the radial term and then uv()'s
    // lines (atan(y, x) is GLSL's atan2). Written by krs::kernel_uv_glsl for the kernels of a
    // sequence (krs/sequence_glsl.hpp).
    static constexpr std::string_view glsl_uv_name = "krs_torus_capsule_uv";
    static constexpr std::string_view glsl_uv_source = R"(vec2 krs_torus_capsule_uv(vec3 p, vec4 t0, vec4 t1, vec4 t2, vec4 t3, vec4 t4, vec4 t5, vec4 t6, vec4 t7) {
    vec3 u = p - t0.xyz;
    float h = dot(u, t1.xyz);
    vec3 up = u - t1.xyz * h;
    float wl = length(up * t0.w + t2.xyz * t1.w);
    float radial = (t0.w * dot(up, up) + 2.0 * t1.w * dot(up, t2.xyz) - t2.w) / (wl + 1.0);
    float along = dot(up, t7.xyz);
    float fromMid = t0.w > 0.0 ? atan(t0.w * along, t1.w + t0.w * dot(up, t2.xyz)) / t0.w : along;
    return vec2(clamp(0.5 + fromMid / t7.w, 0.0, 1.0), atan(h, radial) / 6.2831855 + 0.5);
}
)";
    std::array<float, 4> glsl_uv_parameters() const
    {
        return {chord_direction_.x, chord_direction_.y, chord_direction_.z, 2 * half_arc_length_};
    }

private:
    template <class T>
    struct arc_point {
        vec3<T> from_middle, from_start, from_end, radial_direction;
        T height, radial, torus_squared, to_arc;
        mask_t<T> in_arc;
    };

    template <class T>
    arc_point<T> evaluate(const vec3<T>& p) const
    {
        arc_point<T> r;
        const vec3<T> n(plane_normal_), m(toward_control_);
        const T k(curvature_), c(cos_half_angle_);
        r.from_middle = p - vec3<T>(chord_middle_);
        r.height = dot(r.from_middle, n);
        const vec3<T> up = r.from_middle - n * r.height;
        const vec3<T> w = up * k + m * c; // (p_plane - center) / R
        const T wl = length(w);
        r.radial = (k * dot(up, up) + T(2) * c * dot(up, m) - T(chord_offset_)) / (wl + T(1));
        r.radial_direction = select(wl > T(0), w / select(wl > T(0), wl, T(1)), m);
        r.torus_squared = r.radial * r.radial + r.height * r.height;
        r.from_start = p - vec3<T>(start_);
        r.from_end = p - vec3<T>(end_);
        const auto in_start = dot(r.from_start, vec3<T>(start_tangent_)) >= T(0);
        const auto in_end = dot(r.from_end, vec3<T>(end_tangent_)) >= T(0);
        // The wedge of a minor arc is the intersection of the half-spaces bounded by the radial
        // planes at its ends; a major arc's is their union.
        r.in_arc = major_ ? (in_start || in_end) : (in_start && in_end);
        // One square root of whichever squared distance applies (the same value as choosing
        // between two roots, at half the cost).
        const T ends_squared = min(dot(r.from_start, r.from_start), dot(r.from_end, r.from_end));
        r.to_arc = sqrt(select(r.in_arc, r.torus_squared, ends_squared));
        return r;
    }

    vec3f start_{}, end_{}, control_{};
    float radius_ = 0;
    float half_chord_ = 0, curvature_ = 0, sin_half_angle_ = 0, cos_half_angle_ = 1, half_angle_ = 0;
    float chord_offset_ = 0; // h sin(alpha) = h^2 kappa, the constant term of the radial numerator
    float half_arc_length_ = 0, circle_radius_ = 0;
    bool major_ = false; // uniform over lanes: picks the wedge test's union or intersection
    vec3f chord_middle_{}, chord_direction_{}, toward_control_{}, plane_normal_{}, arc_midpoint_{};
    vec3f start_tangent_{}, end_tangent_{}, circle_center_{};
    bounding_sphere bound_{};
};

} // namespace krs

#pragma once
// Domain repetition: copies of a bounded field on a lattice, without end or a count per axis,
// still a bound of the copies' union however the part sits in its cell.
//
// The naive form, f(mod(p, s)), evaluates only the copy of p's own cell. It is wrong wherever a
// copy of another cell is nearer: a part off its cell's centre, or one that reaches into the next
// cell, makes the field overestimate across cell borders, and a sphere tracer steps through
// surfaces (Quilez, "Domain repetition"). Here every copy that can be the nearest is evaluated:
//
// Let the part lie in its bounding sphere B(c, r); copy k (one integer index per axis) is the part
// moved by (k_x s_x, k_y s_y, k_z s_z). For a point p let u = (p - c) / s per axis and
// w_a = r / s_a + 1/2. A copy k with |u_a - k_a| >= w_a on some axis a is never needed: each of
// its points q is at least (|u_a - k_a| s_a - r) >= s_a / 2 from p along a, so moving q one
// period toward p along a (a point of copy k -+ e_a, still in the count, which lies between)
// brings it no farther from p; repeating, every copy's points have a counterpart at least as near
// in the window of indices with |u_a - k_a| < w_a on every axis. That window holds at most
// n_a = ceil(2 w_a) = ceil(2 r / s_a + 1) indices per axis (1 on an axis with one copy), starting at
// floor(u_a - w_a) + 1, shifted to stay within the count. So the field
//     g(p) = min over the window of f(p - k s)
// - equals the union of all copies' fields for a part whose field is its exact distance (the
//   window holds the nearest point of the union), so it is then exact and 1-Lipschitz;
// - never overestimates the distance to the union's surface for any part (a zero z of a copy
//   outside has a zero z' in the window no farther from p, and f(p) <= |p - z'| there);
// - has the union's sign: a point inside a copy is within r of its centre, so |u_a - k_a| < w_a.
// The window costs prod n_a evaluations of the part: 8 in 3-D for a part that stays inside its cell
// (r < s / 2), as Quilez's neighbour form, 27 for one reaching into its neighbours (r < s). Periods
// shorter than an eighth of the part's radius (a window of more than 17 indices per axis) are
// refused.
//
// A KRS-native alternative, continuous with one evaluation: reflect instead of repeat. Mirror
// planes at every half period fold all of space into one cell (a triangle wave per axis), and the
// copies alternate with their mirror images. That is a sequence of axis mirrors
// (krs/sequence.hpp's axis_sequence), which is exact wherever each copy stays in its cell.

#include "krs/core/bounds.hpp"
#include "krs/core/lanes.hpp"
#include "krs/core/validate.hpp"
#include "krs/field.hpp"

#include <array>
#include <cmath>
#include <limits>
#include <string>
#include <utility>

namespace krs {

// One axis of a repetition: a copy every `period` (> 0) along it, `count` copies (indices 0 to
// count - 1, the part's own place first) or `unlimited`. A count of 1 leaves the axis unrepeated.
struct repetition_axis {
    static constexpr int unlimited = std::numeric_limits<int>::max();
    float period = 1.0f;
    int count = unlimited;
};
struct repetition {
    repetition_axis x, y, z;
};

template <field F>
    requires requires(const F& f) { { f.bound() } -> std::convertible_to<bounding_sphere>; }
class repeated {
public:
    // The window's size per axis is at most 2 largest_reach + 1 indices.
    static constexpr int largest_reach = 8;

    repeated(F part, repetition r) : part_(std::move(part)), repetition_(r)
    {
        const bounding_sphere b = part_.bound();
        if (!b.is_bounded())
            throw invalid_parameter("repeated part", "must be bounded (a finite bounding sphere)", "unbounded");
        center_[0] = b.center.x, center_[1] = b.center.y, center_[2] = b.center.z;
        radius_ = b.radius;
        const repetition_axis* axes[3] = {&r.x, &r.y, &r.z};
        const char* names[3] = {"repetition.x", "repetition.y", "repetition.z"};
        for (int a = 0; a < 3; ++a) {
            const repetition_axis& axis = *axes[a];
            require_positive_length((std::string(names[a]) + ".period").c_str(), axis.period);
            if (axis.count < 1)
                throw invalid_parameter(std::string(names[a]) + ".count", "must be >= 1 (or unlimited)",
                                        std::to_string(axis.count));
            period_[a] = axis.period;
            // Index limits as floats (a count's indices are exact in float up to 2^24); far beyond
            // any index a float point can reach for an unlimited axis.
            first_[a] = axis.count == repetition_axis::unlimited ? -huge : 0.0f;
            last_[a] = axis.count == repetition_axis::unlimited ? huge : float(axis.count - 1);
            const double indices = axis.count == 1 ? 1.0 : std::ceil(2.0 * double(radius_) / double(axis.period) + 1.0);
            if (indices > 2 * largest_reach + 1)
                throw invalid_parameter(std::string(names[a]) + ".period",
                                        "must be at least 1/" + std::to_string(largest_reach) +
                                            " of the part's bounding radius " + detail::to_text(radius_),
                                        detail::to_text(axis.period));
            indices_[a] = int(std::min(indices, double(axis.count)));
            half_width_[a] = float(double(radius_) / double(axis.period) + 0.5);
            latest_start_[a] = axis.count == repetition_axis::unlimited ? huge : float(axis.count - indices_[a]);
        }
    }

    const F& part() const { return part_; }
    const repetition& layout() const { return repetition_; }
    // Copies evaluated per point: prod n_a.
    int window_size() const { return indices_[0] * indices_[1] * indices_[2]; }

    template <class T>
    T distance(const vec3<T>& p) const
    {
        const T x[3] = {p.x, p.y, p.z};
        T start[3];
        for (int a = 0; a < 3; ++a) {
            const T u = (x[a] - splat<T>(center_[a])) / splat<T>(period_[a]);
            // The window's first index, shifted to keep its n_a indices within the count.
            start[a] = clamp(lane_floor(u - splat<T>(half_width_[a])) + T(1.0f), splat<T>(first_[a]),
                             splat<T>(latest_start_[a]));
        }
        const T inf = splat<T>(std::numeric_limits<float>::infinity());
        T best = inf;
        for (int dz = 0; dz < indices_[2]; ++dz)
            for (int dy = 0; dy < indices_[1]; ++dy)
                for (int dx = 0; dx < indices_[0]; ++dx) {
                    const T kx = start[0] + T(float(dx)), ky = start[1] + T(float(dy)), kz = start[2] + T(float(dz));
                    const vec3<T> q{p.x - kx * splat<T>(period_[0]), p.y - ky * splat<T>(period_[1]),
                                    p.z - kz * splat<T>(period_[2])};
                    best = min(best, part_.distance(q));
                }
        return best;
    }

    // Bounded only when every axis has a count: the part's sphere grown by the half diagonal of
    // the copies' centres.
    bounding_sphere bound() const
    {
        for (int a = 0; a < 3; ++a)
            if (last_[a] == huge) return bounding_sphere::unbounded();
        const vec3d half{0.5 * double(last_[0]) * period_[0], 0.5 * double(last_[1]) * period_[1],
                         0.5 * double(last_[2]) * period_[2]};
        return bound_around(vec3d{center_[0], center_[1], center_[2]} + half, double(radius_) + length(half));
    }

    // GLSL (krs/glsl/emitter.hpp): the part as NAME_a, and NAME walking the same window in the
    // same order with the same arithmetic.
    template <class Out>
    void glsl_emit(Out& out, const std::string& name) const
    {
        out.field(part_, name + "_a");
        const std::size_t at = out.vec4({period_[0], period_[1], period_[2], 0.0f}, name + " repetition (period, 0)");
        out.vec4({center_[0], center_[1], center_[2], 0.0f}, name + " repetition (part's centre, 0)");
        out.vec4({half_width_[0], half_width_[1], half_width_[2], 0.0f}, name + " repetition (window half width, 0)");
        out.vec4({first_[0], first_[1], first_[2], 0.0f}, name + " repetition (first index, 0)");
        out.vec4({latest_start_[0], latest_start_[1], latest_start_[2], 0.0f},
                 name + " repetition (latest window start, 0)");
        auto n = [&](int a) { return std::to_string(indices_[a]); };
        out.function("float " + name + "(vec3 x) {\n"
                     "    vec3 s = " + out.at(at) + ".xyz;\n"
                     "    vec3 u = (x - " + out.at(at + 1) + ".xyz) / s;\n"
                     "    vec3 start = clamp(floor(u - " + out.at(at + 2) + ".xyz) + 1.0, " + out.at(at + 3) + ".xyz, " +
                     out.at(at + 4) + ".xyz);\n"
                     "    float best = 3.0e38;\n"
                     "    for (int dz = 0; dz < " + n(2) + "; ++dz)\n"
                     "    for (int dy = 0; dy < " + n(1) + "; ++dy)\n"
                     "    for (int dx = 0; dx < " + n(0) + "; ++dx) {\n"
                     "        vec3 k = start + vec3(float(dx), float(dy), float(dz));\n"
                     "        best = min(best, " + name + "_a(vec3(x.x - k.x * s.x, x.y - k.y * s.y, x.z - k.z * s.z)));\n"
                     "    }\n"
                     "    return best;\n}\n");
    }

private:
    // An index limit no float point reaches (finite, so GLSL can hold it too). The GLSL starts its
    // minimum at 3e38 where the C++ starts at infinity: the window holds at least one copy, so
    // both end at the same finite value.
    static constexpr float huge = 1e30f;

    F part_;
    repetition repetition_;
    float center_[3] = {0, 0, 0};
    float radius_ = 0.0f;
    float period_[3] = {1, 1, 1};
    float first_[3] = {0, 0, 0}, last_[3] = {0, 0, 0};
    float half_width_[3] = {0.5f, 0.5f, 0.5f}; // w_a
    float latest_start_[3] = {0, 0, 0};         // last_a - n_a + 1: the window stays within the count
    int indices_[3] = {1, 1, 1};                // n_a
};

} // namespace krs

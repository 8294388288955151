#pragma once
// Lipschitz distortion of a field (paper section 5.2, after Hart 1996): bend, twist or displace
// space to break a KRS's symmetry, and divide the distance by the warp's Lipschitz bound.
//
// If W is L-Lipschitz on a convex domain D and f is a field, g = f(W(x)) / L is 1-Lipschitz on D:
// |f(W(x)) - f(W(y))| <= |W(x) - W(y)| <= L |x - y|. And g never overestimates the distance to
// its zero set: for a surface point q (f(W(q)) = 0), f(W(x)) <= |W(x) - W(q)| <= L |x - q|.
//
// A warp is a type with `template <class T> vec3<T> apply(const vec3<T>&) const`, a
// `double lipschitz() const` (its bound, >= 1) and a `bounding_sphere domain() const` on which the
// bound holds (unbounded for warps that hold everywhere). Bends and twists rotate by an angle that
// grows along an axis, so their stretch grows with the distance from that axis: their bound only
// holds within a finite domain. lipschitz_warp then defines the geometry clipped to the domain
// ball B(c, R):
//     g(x) = max(|x - c| - R, f(W(P(x))) / L),   P = nearest-point projection onto the ball.
// P is 1-Lipschitz and maps into the ball, where f o W / L is 1-Lipschitz, so both terms are, and
// so is their max. For a point q of the clipped geometry (q in the ball, f(W(q)) <= 0, P(q) = q)
// both terms are <= |x - q|, so g never overestimates.

#include "krs/core/bounds.hpp"
#include "krs/core/noise.hpp"
#include "krs/core/rounding.hpp"
#include "krs/core/validate.hpp"
#include "krs/field.hpp"

#include <array>
#include <cmath>
#include <concepts>
#include <string>
#include <string_view>
#include <tuple>
#include <utility>

namespace krs {

template <class W>
concept warp = requires(const W& w, const vec3f& pf, const vec3d& pd) {
    { w.apply(pf) } -> std::same_as<vec3f>;
    { w.apply(pd) } -> std::same_as<vec3d>;
    { w.lipschitz() } -> std::convertible_to<double>;
    { w.domain() } -> std::same_as<bounding_sphere>;
};

namespace detail {
template <class T>
inline void sin_cos_lane(const T& a, T& s, T& c)
{
    if constexpr (std::floating_point<T>) {
        s = std::sin(a);
        c = std::cos(a);
    } else {
        s = xsimd::sin(a);
        c = xsimd::cos(a);
    }
}
} // namespace detail

// Twist about the y axis: (x, z) turns by rate * y radians.
// J = Rot(rate y) (I + u e_y^T) with u = rate * (-z, 0, x): |u| = |rate| rho (rho the distance
// from the y axis) and u orthogonal to e_y, so ||J|| is the largest singular value of
// [[1, a], [0, 1]], a = |rate| rho: (a + sqrt(a^2 + 4)) / 2. Over the domain ball (center on the
// axis, radius R) rho <= R.
struct twist_warp {
    float rate = 0.0f;   // radians per unit of y
    float radius = 1.0f; // domain: the ball of this radius around the origin, > 0

    twist_warp() = default;
    twist_warp(float rate_, float radius_)
        : rate(require_finite("twist_warp.rate", rate_)), radius(require_positive_length("twist_warp.radius", radius_))
    {
    }
    template <class T>
    vec3<T> apply(const vec3<T>& p) const
    {
        T s, c;
        detail::sin_cos_lane(p.y * T(rate), s, c);
        return {c * p.x - s * p.z, p.y, s * p.x + c * p.z};
    }
    double lipschitz() const
    {
        const double a = std::abs(double(rate)) * double(radius);
        return 0.5 * (a + std::sqrt(a * a + 4.0));
    }
    bounding_sphere domain() const { return {{0, 0, 0}, radius}; }

    // GLSL: one vec4 (rate, 0, 0, 0).
    static constexpr std::string_view glsl_name = "krs_twist_warp";
    static constexpr std::string_view glsl_source = R"(vec3 krs_twist_warp_apply(vec3 p, vec4 w) {
    float a = p.y * w.x;
    float s = sin(a);
    float c = cos(a);
    return vec3(c * p.x - s * p.z, p.y, s * p.x + c * p.z);
}
)";
    std::array<float, 4> glsl_parameters() const { return {rate, 0.0f, 0.0f, 0.0f}; }
};

// Bend in the xy plane: the point turns about the z axis by rate * x radians.
// J = Rot(rate x) (I + u e_x^T) with u = rate * (-y, x, 0), |u| = |rate| r (r = |(x, y)|); u is not
// orthogonal to e_x, so the general bound ||I + u e^T|| <= 1 + |u| is used: 1 + |rate| R.
struct bend_warp {
    float rate = 0.0f;   // radians per unit of x
    float radius = 1.0f; // domain ball around the origin, > 0

    bend_warp() = default;
    bend_warp(float rate_, float radius_)
        : rate(require_finite("bend_warp.rate", rate_)), radius(require_positive_length("bend_warp.radius", radius_))
    {
    }
    template <class T>
    vec3<T> apply(const vec3<T>& p) const
    {
        T s, c;
        detail::sin_cos_lane(p.x * T(rate), s, c);
        return {c * p.x - s * p.y, s * p.x + c * p.y, p.z};
    }
    double lipschitz() const { return 1.0 + std::abs(double(rate)) * double(radius); }
    bounding_sphere domain() const { return {{0, 0, 0}, radius}; }

    // GLSL: one vec4 (rate, 0, 0, 0).
    static constexpr std::string_view glsl_name = "krs_bend_warp";
    static constexpr std::string_view glsl_source = R"(vec3 krs_bend_warp_apply(vec3 p, vec4 w) {
    float a = p.x * w.x;
    float s = sin(a);
    float c = cos(a);
    return vec3(c * p.x - s * p.y, s * p.x + c * p.y, p.z);
}
)";
    std::array<float, 4> glsl_parameters() const { return {rate, 0.0f, 0.0f, 0.0f}; }
};

// Noise displacement: W(x) = x + a * (N(f x), N(f x + o1), N(f x + o2)) with N = value_noise.
// ||J|| <= 1 + a f ||J_N|| and ||J_N|| <= its Frobenius norm <= sqrt(3) * |grad N|max
// = sqrt(3) * 3.75 sqrt(3) = 11.25 (value_noise_gradient_bound, krs/core/noise.hpp). Holds
// everywhere: unbounded domain.
struct noise_warp {
    float amplitude = 0.0f; // displacement scale in [0, 1e9] (the surface moves by up to amplitude)
    float frequency = 1.0f; // in (0, 1e9]: frequency times any coordinate within the policy stays finite

    noise_warp() = default;
    noise_warp(float amplitude_, float frequency_)
        : amplitude(require_length("noise_warp.amplitude", amplitude_)),
          frequency(require_positive_length("noise_warp.frequency", frequency_))
    {
    }
    template <class T>
    vec3<T> apply(const vec3<T>& p) const
    {
        const T f(frequency), a(amplitude);
        const vec3<T> q = p * f;
        const T o1(static_cast<scalar_t<T>>(31.7f)), o2(static_cast<scalar_t<T>>(-47.3f));
        return {p.x + a * value_noise(q), p.y + a * value_noise(vec3<T>{q.x + o1, q.y, q.z - o1}),
                p.z + a * value_noise(vec3<T>{q.x, q.y + o2, q.z + o2})};
    }
    double lipschitz() const
    {
        return 1.0 + double(amplitude) * double(frequency) * std::sqrt(3.0) * value_noise_gradient_bound;
    }
    bounding_sphere domain() const { return bounding_sphere::unbounded(); }

    // GLSL: one vec4 (frequency, amplitude, 0, 0); krs_value_noise from core/noise.hpp.
    using glsl_needs = std::tuple<value_noise_glsl>;
    static constexpr std::string_view glsl_name = "krs_noise_warp";
    static constexpr std::string_view glsl_source = R"(vec3 krs_noise_warp_apply(vec3 p, vec4 w) {
    vec3 q = p * w.x;
    return vec3(p.x + w.y * krs_value_noise(q), p.y + w.y * krs_value_noise(vec3(q.x + 31.7, q.y, q.z - 31.7)),
                p.z + w.y * krs_value_noise(vec3(q.x, q.y + -47.3, q.z + -47.3)));
}
)";
    std::array<float, 4> glsl_parameters() const { return {frequency, amplitude, 0.0f, 0.0f}; }
};

template <field F, warp W>
class lipschitz_warp {
public:
    lipschitz_warp(F f, W w) : field_(std::move(f)), warp_(std::move(w))
    {
        // Up to 1e30: the field is the warped distance times 1/L, and 1/L must stay a normal float
        // (a twist of rate 1e38 over a radius 1e9 had L = 1e47, 1/L rounded to 0, and the field
        // was 0, all surface, everywhere). Long before that the steps are too short to trace.
        const double l = warp_.lipschitz();
        if (!std::isfinite(l) || !(l >= 1.0 && l <= 1e30))
            throw invalid_parameter("lipschitz_warp.lipschitz", "the warp's Lipschitz bound must be in [1, 1e30]",
                                    detail::to_text(l));
        // Rounding 1/L to float must not make it larger than 1/L (that would overestimate).
        inverse_bound_ = float_at_most(1.0 / l);
        const bounding_sphere d = warp_.domain();
        if (d.is_bounded()) {
            require_finite("lipschitz_warp.domain.center", d.center);
            require_positive("lipschitz_warp.domain.radius", d.radius);
        }
        domain_ = d;
    }

    const F& base() const { return field_; }
    const W& distortion() const { return warp_; }
    float inverse_lipschitz() const { return inverse_bound_; }

    template <class T>
    T distance(const vec3<T>& x) const
    {
        if (!domain_.is_bounded()) return field_.distance(warp_.apply(x)) * T(inverse_bound_);
        const vec3<T> c(domain_.center);
        const T r(domain_.radius);
        const vec3<T> offset = x - c;
        const T len = length(offset);
        const T outside = len - r;
        // P(x): points outside the ball move radially onto its surface.
        const T scale = select(outside > T(0), r / select(len > T(0), len, T(1)), T(1));
        const vec3<T> projected = c + offset * scale;
        return max(outside, field_.distance(warp_.apply(projected)) * T(inverse_bound_));
    }

    // GLSL (krs/glsl/emitter.hpp): the base field as NAME_base, the warp's NAME_apply from its own
    // GLSL, 1 / L and the domain ball in the data; the same operations in the same order as
    // distance().
    template <class Out>
    void glsl_emit(Out& out, const std::string& name) const
    {
        out.field(field_, name + "_base");
        out.template library<W>();
        const std::size_t w = out.parameters(warp_, name + " warp");
        const std::size_t inv = out.vec4({inverse_bound_, 0.0f, 0.0f, 0.0f}, name + " (1 / Lipschitz bound, 0, 0, 0)");
        const std::string warped = name + "_base(" + std::string(W::glsl_name) + "_apply(";
        const std::string args = out.template arguments<W>(w) + ")) * " + out.at(inv) + ".x";
        std::string body = "float " + name + "(vec3 x) {\n";
        if (!domain_.is_bounded()) {
            body += "    return " + warped + "x" + args + ";\n}\n";
        } else {
            const std::size_t c = out.vec4({domain_.center.x, domain_.center.y, domain_.center.z, domain_.radius},
                                           name + " domain (center, radius)");
            // max(|x - c| - R, f(W(P(x))) / L), P the projection onto the domain ball.
            body += "    vec4 domain = " + out.at(c) + ";\n"
                    "    vec3 offset = x - domain.xyz;\n"
                    "    float len = length(offset);\n"
                    "    float outside = len - domain.w;\n"
                    "    float scale = outside > 0.0 ? domain.w / (len > 0.0 ? len : 1.0) : 1.0;\n"
                    "    vec3 projected = domain.xyz + offset * scale;\n"
                    "    return max(outside, " + warped + "projected" + args + ");\n}\n";
        }
        out.function(body);
    }

private:
    F field_;
    W warp_;
    float inverse_bound_ = 1.0f;
    bounding_sphere domain_{};
};

} // namespace krs

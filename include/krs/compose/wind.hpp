#pragma once
// Wind: any field swaying in time, by a time-dependent Lipschitz warp (the KRS paper's section 9:
// "Time-dependent Lipschitz transformations appear more promising" for animating its geometry).
//
// The motion. A point s of the still surface moves along a horizontal wind direction d (unit,
// d . e_y = 0) by an amount that grows with its height and changes with time t (seconds):
//     s  ->  s + a(t) w(s.y) d,        w(y) = clamp((y - ground) / height, 0, 1)^2.
// Nothing at or below the ground moves (w = 0), the sway grows quadratically with height (as a
// cantilever bends near its root) up to `height` above the ground, and what lies higher moves
// with the top. a(t) is the displacement of the top, in scene units:
//     a(t) = sway + gust g(t),
//     g(t) = (sin(o t) + sin(sqrt(2) o t + 1.3) / 2 + sin(sqrt(5) o t + 2.9) / 4) / 1.75,
// o = 2 pi / gust_period. `sway` is the mean lean, g the gusts: a sum of three sines (not a value
// noise in t) because it is smooth, three sin calls in GLSL and a closed form for tests; the
// frequency ratios 1 : sqrt 2 : sqrt 5 are independent over the rationals, so the pattern never
// repeats, and the weights sum to 1.75, so |g| <= 1 and |a(t)| <= |sway| + gust at every t.
//
// The field of an instant. Since the motion keeps y, it is undone by W(x) = x - a w(x.y) d, and the
// swaying field is g(x) = f(W(x)) / L(t). Its bound: W's Jacobian is
//     J = I - a w'(y) d e_y^T,
// the identity minus a rank-one shear whose two vectors are orthogonal unit vectors. In the
// orthonormal basis (e_y, d, e_y x d) it is [[1, 0, 0], [-c, 1, 0], [0, 0, 1]] with c = a w'(y);
// J^T J has the block [[1 + c^2, -c], [-c, 1]], eigenvalues (2 + c^2 +- |c| sqrt(c^2 + 4)) / 2,
// so ||J|| = (k + sqrt(k^2 + 4)) / 2 with k = |c|. w' = 2 s / height for s = (y - ground) / height
// in (0, 1) and 0 outside, so |w'| <= 2 / height and at the instant t
//     L(t) = sigma(2 |a(t)| / height),   sigma(k) = (k + sqrt(k^2 + 4)) / 2,
// and over all t, L(t) <= sigma(2 (|sway| + gust) / height) (`wind::lipschitz_all_times`). W is
// continuous and smooth but on two planes, on all of R^3 (convex), so it is L(t)-Lipschitz
// everywhere: unlike a twist or a bend (krs/compose/warp.hpp) the domain is unbounded and nothing
// is clipped. So g is 1-Lipschitz and never overestimates (warp.hpp's argument: for a point q of
// the swaying surface, f(W(x)) <= |W(x) - W(q)| <= L |x - q|) at every instant, and sphere
// tracing is safe in every frame. The price is steps at most 1 / L(t) as long. Measured on a
// tree of height 8.5 seen whole (tests/test_compose_wind.cpp prints it): a gust peak whose top
// moves 0.98 has L = 1.12 and costs 1.09 times the still tree's steps per ray; a storm's 3.4,
// L = 1.48, 1.35 times. The bound is per instant, the tightest this shear allows, so a still
// moment costs nothing: where a(t) = 0 (no wind, or an instant where the gusts cancel the lean)
// W is the identity, L = 1 and the field is the still one bit for bit.
//
// Stored in float: the direction (its horizontal part, normalized), the ground, 1 / height and the
// instant's a. The bound is taken from the stored values (|d| as stored, 2 / height as stored) in
// double and 1 / L rounded down (float_at_most, krs/core/rounding.hpp).
//
// GLSL (krs/glsl/emitter.hpp): swaying<F> emits, for the name NAME,
//     float NAME(vec3 p)                the field at the instant in the data (its a, its 1/L)
//     float NAME_at(vec3 p, float time) the field at any time the shader passes
// NAME is what tracers call; a host animates it without recompiling by uploading
// `krs::glsl::pack(field.at(t))` to the data block (data_mode::buffer) each frame, as for any
// field. NAME_at takes the time from the shader: Shadertoy's `iTime`, or a `uniform float time;` of
// the host's own that it sets per frame (`float d = krs_tree_at(p, time);`). It computes a(time)
// and 1 / L(time) in float, and, since GLSL's sqrt and division may be off by a few ulps where the
// C++ rounds down, multiplies 1 / L by wind_bound_margin = 1 - 2^-18 (64 float ulps, several times
// their error); the C++ applies the same factor, so NAME and NAME_at agree with the C++'s
// swaying::at(time) to float rounding.

#include "krs/core/bounds.hpp"
#include "krs/core/rounding.hpp"
#include "krs/core/validate.hpp"
#include "krs/field.hpp"

#include <array>
#include <cmath>
#include <numbers>
#include <string>
#include <string_view>
#include <tuple>
#include <utility>

namespace krs {

// 1 - 2^-18: the factor on every swaying field's 1 / L(t) (see above: it covers GLSL's rounding
// of the bound it computes for any time).
inline constexpr float wind_bound_margin = 0.999996185302734375f;

namespace detail {
// sigma(k) = (k + sqrt(k^2 + 4)) / 2, the norm of I + u v^T for orthogonal u, v with |u||v| = k.
inline double orthogonal_shear_norm(double k) { return 0.5 * (k + std::sqrt(k * k + 4.0)); }
} // namespace detail

// The warp of one instant: W(x) = x - offset * clamp((x.y - ground) * inverse_height, 0, 1)^2 * d.
// A warp in warp.hpp's sense (usable in lipschitz_warp), unbounded domain. offset * inverse_height
// is at most 1e6 (a shear a million times the height leaves steps too short to trace).
struct wind_warp {
    float direction_x = 1.0f;    // d = (direction_x, 0, direction_z), unit
    float direction_z = 0.0f;
    float ground = 0.0f;         // nothing at or below this y moves
    float inverse_height = 1.0f; // 1 / the height of the swaying band
    float offset = 0.0f;         // a: how far the top moves along d (either sign)

    wind_warp() = default;
    wind_warp(const vec3f& direction, float ground_, float height, float offset_)
    {
        const vec3d d = require_horizontal("wind_warp.direction", direction);
        direction_x = float(d.x);
        direction_z = float(d.z);
        ground = require_magnitude("wind_warp.ground", ground_);
        inverse_height = float(1.0 / double(require_positive_length("wind_warp.height", height)));
        offset = require_magnitude("wind_warp.offset", offset_);
        if (!(std::abs(double(offset)) * double(inverse_height) <= 1e6))
            throw invalid_parameter("wind_warp.offset", "must be at most 1e6 times the height",
                                    detail::to_text(offset));
    }

    // The horizontal part of `direction`, unit, in double; refused (by `name`) when it has none.
    static vec3d require_horizontal(std::string_view name, const vec3f& direction)
    {
        require_finite(name, direction);
        const vec3d h{double(direction.x), 0.0, double(direction.z)};
        const double len = length(h);
        if (!(len > 1e-30))
            throw invalid_parameter(name, "must have a horizontal (x, z) part: the wind blows sideways",
                                    detail::to_text(direction));
        return h / len;
    }

    template <class T>
    vec3<T> apply(const vec3<T>& p) const
    {
        if (offset == 0.0f) return p; // the still field, bit for bit (x - 0 * d could turn -0 to +0)
        const T s = clamp((p.y - T(ground)) * T(inverse_height), T(0), T(1));
        const T o = T(offset) * (s * s);
        return {p.x - o * T(direction_x), p.y, p.z - o * T(direction_z)};
    }
    // max |w'| |d| as stored (2 * inverse_height * |d|, |d| within float ulps of 1): k = |a| slope.
    double slope() const
    {
        return 2.0 * double(inverse_height) *
               std::sqrt(double(direction_x) * direction_x + double(direction_z) * direction_z);
    }
    double lipschitz() const { return detail::orthogonal_shear_norm(std::abs(double(offset)) * slope()); }
    bounding_sphere domain() const { return bounding_sphere::unbounded(); }

    // GLSL: vec4 (direction_x, direction_z, ground, inverse_height), vec4 (offset, 0, 0, 0). The
    // same operations in the same order as apply().
    static constexpr std::string_view glsl_name = "krs_wind_warp";
    static constexpr std::string_view glsl_source = R"(vec3 krs_wind_warp_apply(vec3 p, vec4 w, vec4 a) {
    if (a.x == 0.0) return p;
    float s = clamp((p.y - w.z) * w.w, 0.0, 1.0);
    float o = a.x * (s * s);
    return vec3(p.x - o * w.x, p.y, p.z - o * w.y);
}
)";
    std::array<float, 8> glsl_parameters() const
    {
        return {direction_x, direction_z, ground, inverse_height, offset, 0.0f, 0.0f, 0.0f};
    }
};

// The wind: where it blows, how the sway grows with height, and its lean and gusts over time (the
// description above). Plain values; validate() refuses bad ones by name, and swaying's
// constructor calls it.
struct wind {
    vec3f direction{1, 0, 0}; // the way the wind blows; only its horizontal (x, z) part is used
    float ground = 0.0f;      // y of the ground: nothing at or below it moves
    float height = 1.0f;      // the sway grows up to ground + height (> 0), then stays
    float sway = 0.0f;        // the top's mean displacement along the direction (either sign)
    float gust = 0.0f;        // the gusts' amplitude at the top (>= 0)
    float gust_period = 4.0f; // seconds: the period of the slowest of the three gust sines (> 0)

    const wind& validate() const
    {
        (void)wind_warp::require_horizontal("wind.direction", direction);
        require_magnitude("wind.ground", ground);
        require_positive_length("wind.height", height);
        require_magnitude("wind.sway", sway);
        require_length("wind.gust", gust);
        if (!(std::abs(double(sway)) + double(gust) <= double(max_magnitude)))
            throw invalid_parameter("wind.gust", "|sway| + gust (the farthest the top moves) must be at most " +
                                                     std::string(detail::max_magnitude_text),
                                    detail::to_text(gust));
        require_positive_length("wind.gust_period", gust_period);
        if (!((std::abs(double(sway)) + double(gust)) <= 1e6 * double(height)))
            throw invalid_parameter("wind.height", "must be at least (|sway| + gust) / 1e6: a larger shear leaves "
                                                   "steps too short to trace",
                                    detail::to_text(height));
        return *this;
    }

    // o = 2 pi / gust_period as stored for GLSL (and used by sway_at, so both read one value).
    float angular_frequency() const { return float(2.0 * std::numbers::pi / double(gust_period)); }
    // a(t): the top's displacement at time t, in double from the stored values.
    double sway_at(double t) const
    {
        const double phase = double(angular_frequency()) * t;
        const double g = std::sin(phase) + 0.5 * std::sin(std::numbers::sqrt2 * phase + 1.3) +
                         0.25 * std::sin(std::sqrt(5.0) * phase + 2.9);
        return double(sway) + double(gust) * (g / 1.75);
    }
    // The warp of the instant t (a(t) rounded to float).
    wind_warp warp_at(float t) const
    {
        validate();
        return wind_warp(direction, ground, height, float(sway_at(double(require_finite("wind.time", t)))));
    }
    // The bound for every t at once: sigma(2 (|sway| + gust) / height), an upper bound of L(t).
    double lipschitz_all_times() const
    {
        const wind_warp w(direction, ground, height, 0.0f);
        // |a(t)| as rounded to float is at most the sum rounded up.
        return detail::orthogonal_shear_norm(double(float_at_least(std::abs(double(sway)) + double(gust))) * w.slope());
    }

    // GLSL: vec4 (direction_x, direction_z, ground, inverse_height) as the warp's, then vec4 (sway,
    // gust, o, slope), slope = 2 * inverse_height * |d| rounded up (k = |a| slope). krs_wind_sway
    // is a(t) in float, as sway_at.
    using glsl_needs = std::tuple<wind_warp>;
    static constexpr std::string_view glsl_name = "krs_wind";
    static constexpr std::string_view glsl_source = R"(float krs_wind_sway(float t, vec4 g) {
    float phase = g.z * t;
    float s = sin(phase) + 0.5 * sin(1.41421356 * phase + 1.3) + 0.25 * sin(2.23606798 * phase + 2.9);
    return g.x + g.y * (s / 1.75);
}
)";
    std::array<float, 8> glsl_parameters() const
    {
        const wind_warp w(direction, ground, height, 0.0f);
        return {w.direction_x, w.direction_z, w.ground,           w.inverse_height,
                sway,          gust,          angular_frequency(), float_at_least(w.slope())};
    }
};

// A field swaying in the wind, at one instant: swaying(still, wind, time). at(t) gives the same
// field at another instant (call it per frame); distance() is the instant's field
// g(x) = f(W_t(x)) / L(t) (times wind_bound_margin), and exactly f(x) where a(t) = 0.
template <field F>
class swaying {
public:
    swaying(F still, const wind& air, float time = 0.0f)
        : still_(std::move(still)), wind_(air.validate()), time_(require_finite("swaying.time", time)),
          warp_(air.warp_at(time))
    {
        inverse_bound_ =
            warp_.offset == 0.0f ? 1.0f : float_at_most(double(wind_bound_margin) / warp_.lipschitz());
    }

    // The field at time t: the same still field and wind.
    swaying at(float t) const { return swaying(still_, wind_, t); }

    const F& still() const { return still_; }
    const wind& air() const { return wind_; }
    float time() const { return time_; }
    const wind_warp& warp() const { return warp_; }       // this instant's
    float inverse_lipschitz() const { return inverse_bound_; } // this instant's 1 / L, as applied

    template <class T>
    T distance(const vec3<T>& x) const
    {
        if (warp_.offset == 0.0f) return still_.distance(x);
        return still_.distance(warp_.apply(x)) * T(inverse_bound_);
    }

    // The still field's sphere, grown by how far this instant moves any point (|a(t)|).
    bounding_sphere bound() const
        requires requires(const F& f) { { f.bound() } -> std::convertible_to<bounding_sphere>; }
    {
        const bounding_sphere b = still_.bound();
        if (!b.is_bounded()) return b;
        return bound_around(vec3d(b.center), double(b.radius) + std::abs(double(warp_.offset)));
    }

    // GLSL: the still field as NAME_still; the wind's two vec4s and the instant's (a, 1 / L, time,
    // 0) in the data; NAME_sway(p, instant) the field for an instant's (a, 1 / L), which NAME calls
    // with the data's and NAME_at with those it computes for its time (see the top of this file).
    template <class Out>
    void glsl_emit(Out& out, const std::string& name) const
    {
        out.field(still_, name + "_still");
        out.template library<wind>();
        const std::size_t w = out.parameters(wind_, name + " wind");
        const std::size_t now = out.vec4({warp_.offset, inverse_bound_, time_, 0.0f},
                                         name + " instant (offset, 1 / Lipschitz bound, time, 0)");
        const std::string shape = out.at(w), gusts = out.at(w + 1);
        out.function("float " + name + "_sway(vec3 p, vec4 instant) {\n"
                     "    if (instant.x == 0.0) return " + name + "_still(p);\n"
                     "    return " + name + "_still(krs_wind_warp_apply(p, " + shape + ", instant)) * instant.y;\n}\n"
                     "float " + name + "(vec3 p) { return " + name + "_sway(p, " + out.at(now) + "); }\n"
                     "float " + name + "_at(vec3 p, float time) {\n"
                     "    float a = krs_wind_sway(time, " + gusts + ");\n"
                     "    float k = abs(a) * " + gusts + ".w;\n"
                     "    return " + name + "_sway(p, vec4(a, 2.0 / (k + sqrt(k * k + 4.0)) * " +
                     Out::literal(wind_bound_margin) + ", time, 0.0));\n}\n");
    }

private:
    F still_;
    wind wind_;
    float time_ = 0.0f;
    wind_warp warp_;
    float inverse_bound_ = 1.0f;
};

} // namespace krs

#pragma once
// The similar log-spherical shell: any field placed in the prototype shell 1 <= |p| <= s,
// s = e^(1/density), repeated inside and outside itself at every scale.
//
// It is the forward then inverse log-spherical map (krs/fractal/log_tilings.hpp) with the tiling
// in between, which reduces to p' = p / s^k for the shell k holding p, and the distance found
// there multiplied back by s^k.
//
// The similar shell is a similarity inside each shell (exactly 1-Lipschitz there) but jumps
// between shells: each shell sees only its own copy. shell_options picks the document's fixes:
//   seams::none              the document's field: 1 shell evaluation; rays may overshoot at seams.
//   seams::adjacent_shells   min over shells k-1, k, k+1 (each clamped below by the distance to
//                            its shell) and r (1 - 1/s), a lower bound of the distance to every
//                            other shell that is continuous in r: the three-shell windows of
//                            neighbouring shells then agree at their common boundary, and the field
//                            is 1-Lipschitz and never overestimates. Inside the geometry the same
//                            window with the prototype's field negated bounds the depth (below).
//                            3 shell evaluations.
//   seams::hidden_boundary   hidden geometry: the shell's two boundary spheres, cut off below
//                            cutoff * r so they are never hit, brought into the min. Rays stop
//                            short of the seam and enter the next shell; 1 shell evaluation plus
//                            a sphere, but the field may still overestimate by up to cutoff * r.
//   step_factor              multiplies the distance (shorter steps: more of them, fewer
//                            overshoots); combines with any seam mode.
//   seam_band                makes the step factor local (the document: "shorten the steps
//                            globally, or only locally in problematic regions"). With
//                            g = min(r - inner, outer - r) the distance along r to the nearer
//                            seam of p's shell (beta = g / r, relative) and e = max(g - band r,
//                            0) how far p lies outside the band beta < band, the field is
//                                d_local = min(d, f d + w e),   f = step_factor,
//                                                              w = (1 - f) / (1 + band):
//                            f d within the band (e = 0, as the global factor), d once the
//                            sphere of radius d stays c e = e / (1 + band) short of the band,
//                            between them the step cut short at the band plus f of the rest.
//                            1-Lipschitz whenever d is: g is 1-Lipschitz in r (|dg/dr| = 1) and
//                            r in p, so e is (1 + band)-Lipschitz; then f d + w e is f + (1 - f)
//                            = 1-Lipschitz, and a min of 1-Lipschitz functions is 1-Lipschitz
//                            (the adjacent-shells field keeps its contract, and union_of's skip
//                            stays valid). d_local <= d, so it never overestimates more than d.
//                            (A ramp d g(beta) of the factor from f to 1 has the gradient
//                            g + (1 - f) d / (band r) there: about 6 with adjacent shells at
//                            density 1, f 0.5, band 0.06.) Continuous across seams (g = 0 on both
//                            sides). Inside the geometry (d < 0) d_local = d. 0 (the default)
//                            keeps the factor global; the similar shell refuses a band of
//                            (s - 1) / (s + 1) or more, the largest beta of any shell, where it
//                            would be global too.
// Why the seams are the only problematic region: geometry of other shells lies beyond the seams,
// at least beta r away, so the true distance D >= min(d_k, beta r) with d_k the own shell's
// distance. Hidden boundary returns min(d_k, max(beta r, cutoff r)) <= D wherever beta >= cutoff:
// it can overestimate only within beta < cutoff, where d <= cutoff r, and by at most d_local
// <= f cutoff r + w max(cutoff - band, 0) r there (and <= cutoff r). A band >= cutoff therefore
// keeps the global factor's margin (step_factor cutoff r) with full steps away from the seams;
// overestimate_margin() states the margin.
// The prototype geometry must lie in the shell 1 <= |p| <= s; what leaves it is clipped by the
// adjacent-shells fix and repeated overlapping by the others.
//
// The sign, adjacent shells. The geometry is G = union_j (G_j cap S_j), G_j the prototype's copy at
// scale s^j (field a_j(p) = f(p / s^j) s^j) and S_j its shell; t_j = max(inner_j - r, r - outer_j,
// 0) is p's distance to S_j. A point q of G_j cap S_j is at least max(a_j, t_j) from p, so
//     D_out = min(r (1 - 1/s), min_j max(a_j, t_j))           (j = k-1, k, k+1)
// never exceeds the distance to G. The complement of G is union_j (S_j \ G_j), and a point of
// S_j \ G_j is at least max(-a_j, t_j) from p (-a_j bounds the distance to the complement of G_j
// as a_j bounds the distance to G_j), so the same window with -a_j,
//     D_in  = min(r (1 - 1/s), min_j max(-a_j, t_j)),
// never exceeds the distance to the complement: the depth. p, in S_k, lies in G exactly when
// a_k < 0; then D_out = 0 (its k term is max(a_k, 0)), and where a_k >= 0, D_in = 0 likewise. The
// field is D_out where a_k >= 0 (the field before, bit for bit) and -D_in where a_k < 0: D_out -
// D_in, exactly so but for rounding. Its magnitude never exceeds the distance to the surface on
// either side. D_in is continuous and 1-Lipschitz by
// D_out's argument (the windows agree at the seams), and the two vanish on each other's side, so
// across the surface |d(x) - d(y)| <= |x - z| + |z - y| = |x - y| with z where the segment crosses
// it: the field stays 1-Lipschitz. A prototype inside its shell gives D_in = -a_k, the no-seam
// field's depth (-a_k <= the distance to the seam, which the other terms exceed); geometry that
// continues across a seam stays negative through it, geometry cut there is 0 on the cut.
// (The clamps of t_j at 0 alone, the field before issue 41, gave 0 everywhere inside.) The other
// modes return the own shell's a_k inside (the hidden boundary's term is positive, the band and
// step factor scale or keep a negative d), a depth bound for a prototype inside its shell.

#include "krs/core/rounding.hpp"
#include "krs/core/validate.hpp"
#include "krs/field.hpp"
#include "krs/fractal/log_tilings.hpp"

#include <algorithm>
#include <array>
#include <cmath>
#include <limits>
#include <numbers>
#include <string>
#include <string_view>
#include <utility>

namespace krs {

enum class shell_seams { none, adjacent_shells, hidden_boundary };

// Shell densities (shells per unit of log r) the similar shell accepts. The adjacent shells of the
// innermost radius the warp uses, 1e-30, scale by as little as e^(-69.1 - 2 / density): at density
// 1/8 (shell ratio e^8 ~ 3000) that is e^-85 = 1.2e-37, just above float's smallest normal number
// 1.2e-38. Thinner densities go subnormal, which xsimd's exp already returns as 0 (below e^-88),
// and p / 0 is inf or NaN: with density 0.02 and seams::none, 9% of float and 47% of packet
// distances at points log-uniform in radius from 1e-45 to 1e9 came out non-finite (the other seam
// modes hid it only by the operand order of min and max). Above 1000 a shell is thinner than float
// resolves (ratio 1.001).
inline constexpr float min_shell_density = 0.125f, max_shell_density = 1000.0f;

namespace detail {
inline float require_shell_density(std::string_view name, float density)
{
    require_finite(name, density);
    if (!(density >= min_shell_density && density <= max_shell_density))
        throw invalid_parameter(name, "must be in [0.125, 1000]", detail::to_text(density));
    return density;
}
} // namespace detail

struct shell_options {
    shell_seams seams = shell_seams::adjacent_shells;
    float hidden_cutoff = 0.02f; // hidden_boundary: the boundary spheres' field floor, times r
    float step_factor = 1.0f;    // in (0, 1]: multiplies the distance
    float seam_band = 0.0f;      // in [0, 0.5]: step_factor only within this relative distance of a
                                 // seam (full steps where the step stays outside it, the header
                                 // comment); 0: everywhere. Below (s - 1) / (s + 1) for the shell.

    const shell_options& validate() const
    {
        require_positive_length("shell_options.hidden_cutoff", hidden_cutoff);
        require_positive("shell_options.step_factor", step_factor);
        if (!(step_factor <= 1.0f))
            throw invalid_parameter("shell_options.step_factor", "must be in (0, 1]", detail::to_text(step_factor));
        // 0.5: a band covering half of every relative distance is no longer local. Whether the
        // band leaves any of the shell outside it depends on the density: similar_shell checks it.
        require_non_negative("shell_options.seam_band", seam_band);
        if (!(seam_band <= 0.5f))
            throw invalid_parameter("shell_options.seam_band", "must be in [0, 0.5]", detail::to_text(seam_band));
        return *this;
    }
};

template <field Shell>
class similar_shell {
public:
    // density: shells per unit of log r, in [0.125, 1000]; the prototype shell is
    // 1 <= |p| <= e^(1/density).
    similar_shell(Shell shell, float density, shell_options options = {})
        : shell_(std::move(shell)), options_(options.validate())
    {
        density_ = detail::require_shell_density("similar_shell.density", density);
        ratio_ = float(std::exp(1.0 / double(density_)));
        const double w = 1.0 - 1.0 / std::exp(1.0 / double(density_));
        other_shells_ = float_at_most(w);
        // beta = min(r - inner, outer - r) / r is largest at r = (inner + outer) / 2, where it is
        // (s - 1) / (s + 1): a band at least that wide covers every shell, the factor is global.
        const double widest = (double(ratio_) - 1.0) / (double(ratio_) + 1.0);
        if (options_.seam_band > 0.0f && !(double(options_.seam_band) < widest))
            throw invalid_parameter("shell_options.seam_band",
                                    "must be below (s - 1) / (s + 1) = " + detail::to_text(float(widest)) +
                                        " for density " + detail::to_text(density_) +
                                        " (a wider band covers every shell: use seam_band 0 for a global factor)",
                                    detail::to_text(options_.seam_band));
        // w = (1 - f) / (1 + band) of the header comment, rounded down: f + w (1 + band) <= 1.
        band_weight_ = float_at_most((1.0 - double(options_.step_factor)) / (1.0 + double(options_.seam_band)));
    }

    float density() const { return density_; }
    // s = e^(1 / density): the outer radius of the prototype shell, and the ratio between shells.
    float ratio() const { return ratio_; }
    const shell_options& options() const { return options_; }
    const Shell& shell() const { return shell_; }

    template <class T>
    T distance(const vec3<T>& p) const
    {
        const T r = length(p);
        const T rs = max(r, T(detail::smallest_radius));
        const T inv_density(1.0f / density_);
        const T k = lane_floor(lane_log(rs) * T(density_));
        // Shell k's scale (its inner radius) and outer radius, once for every use below.
        const T inner = lane_exp(k * inv_density), outer = inner * T(ratio_);
        T d;
        switch (options_.seams) {
        case shell_seams::none: d = in_shell(p, inner); break;
        case shell_seams::hidden_boundary: {
            const T boundary = max(min(r - inner, outer - r), T(options_.hidden_cutoff) * r);
            d = min(in_shell(p, inner), boundary);
            break;
        }
        default: {
            // Outside: a lower bound of the distance to the geometry; inside: the same bound of
            // the distance to its complement, from the prototype's field negated (the header
            // comment). Which one holds is the sign of p's own shell's copy.
            T outside = T(other_shells_) * r, inside = outside, own(0);
            for (int j = -1; j <= 1; ++j) {
                const T inner_j = j == 0 ? inner : lane_exp((k + T(float(j))) * inv_density);
                const T outer_j = inner_j * T(ratio_);
                const T to_shell = max(max(inner_j - r, r - outer_j), T(0));
                const T a = in_shell(p, inner_j);
                if (j == 0) own = a;
                outside = min(outside, max(a, to_shell));
                inside = min(inside, max(-a, to_shell));
            }
            d = select(own < T(0), -inside, outside);
            break;
        }
        }
        if (options_.seam_band > 0.0f) {
            // The local factor (the header comment): e = max(g - band r, 0), g the distance to the
            // nearer seam of shell k (a rounding below 0 when r falls just outside [inner, outer]:
            // e = 0 there, the seam's factor).
            const T e = max(min(r - inner, outer - r) - T(options_.seam_band) * r, T(0));
            return min(d, d * T(options_.step_factor) + T(band_weight_) * e);
        }
        return d * T(options_.step_factor);
    }

    // How much the field may exceed the true distance at radius r, as a multiple of r, for a
    // prototype inside its shell (the header comment): adjacent shells 0, hidden boundary the
    // factor at beta = cutoff times cutoff, none unbounded (infinity).
    double overestimate_margin() const
    {
        switch (options_.seams) {
        case shell_seams::none: return std::numeric_limits<double>::infinity();
        case shell_seams::hidden_boundary: {
            // Within beta < cutoff, d <= cutoff r and e <= max(cutoff - band, 0) r.
            const double f = options_.step_factor, band = options_.seam_band, c = options_.hidden_cutoff;
            if (!(band > 0)) return f * c;
            return std::min(c, f * c + double(band_weight_) * std::max(c - band, 0.0));
        }
        default: return 0.0;
        }
    }

    // GLSL (krs/glsl/emitter.hpp): the prototype shell as NAME_shell, the shell scales from a table
    // (NAME_scale), the seam mode fixed in the code. Two vec4s of parameters: (density,
    // 1 / density, s, 1 - 1/s rounded down) and (hidden_cutoff, step_factor, first k of the scale
    // table, its length); then the scale table e^(k / density) for the shells k = k0 .. k0 + n - 1
    // (as many as the float radii 1e-30 .. 3.4e38 reach, at most glsl_max_table), computed by the
    // C++ expression, so the GPU scales each shell by the very float the CPU does (its own exp is
    // ~10 ulp off); shells past the table fall back to the GPU's exp. A seam band adds one vec4
    // after the table (band, (1 - step_factor) / (1 + band) rounded down) and the local factor's
    // code.
    static constexpr std::string_view glsl_name = "krs_similar_shell";
    static constexpr std::string_view glsl_source = "";
    static constexpr int glsl_max_table = 256;
    std::array<float, 8> glsl_parameters() const
    {
        const auto [k0, n] = glsl_table_range();
        return {density_, 1.0f / density_, ratio_, other_shells_, options_.hidden_cutoff, options_.step_factor,
                float(k0), float(n)};
    }
    template <class Out>
    void glsl_emit(Out& out, const std::string& name) const
    {
        out.field(shell_, name + "_shell");
        const std::size_t header = out.parameters(*this, name + " (density, 1 / density, s, 1 - 1/s), (cutoff, step, k0, n)");
        const auto [k0, n] = glsl_table_range();
        const float inv_density = 1.0f / density_;
        std::size_t first = header + 2; // where the table starts (it has no entry when n is 0)
        for (int i = 0; i < n; i += 4) {
            std::array<float, 4> v{}; // zeros past the table's end
            for (int j = 0; j < 4 && i + j < n; ++j) v[std::size_t(j)] = lane_exp(float(k0 + i + j) * inv_density);
            const std::size_t at =
                out.vec4(v, i == 0 ? name + " shell scales e^(k / density), k = k0.." : name + " shell scales");
            if (i == 0) first = at;
        }
        const std::string c = out.at(header), o = out.at(header + 1);
        std::string body = "float " + name + "_scale(float k) {\n"
                           "    float i = k - " + o + ".z;\n"
                           "    if (i >= 0.0 && i < " + o + ".w) {\n"
                           "        int j = int(i);\n"
                           "        return " + out.data_name() + "[" + std::to_string(first) + " + (j >> 2)][j & 3];\n"
                           "    }\n"
                           "    return exp(k * " + c + ".y);\n}\n";
        body += "float " + name + "_in_shell(vec3 p, float scale) {\n"
                "    return " + name + "_shell(p / scale) * scale;\n}\n";
        body += "float " + name + "(vec3 p) {\n"
                "    vec4 c = " + c + ";\n"
                "    float r = sqrt(p.x * p.x + p.y * p.y + p.z * p.z);\n"
                "    float k = floor(log(max(r, 1e-30)) * c.x);\n"
                "    float inner = " + name + "_scale(k);\n"
                "    float outer = inner * c.z;\n";
        switch (options_.seams) {
        case shell_seams::none: body += "    float d = " + name + "_in_shell(p, inner);\n"; break;
        case shell_seams::hidden_boundary:
            body += "    float boundary = max(min(r - inner, outer - r), " + o + ".x * r);\n"
                    "    float d = min(" + name + "_in_shell(p, inner), boundary);\n";
            break;
        default:
            body += "    float outside = c.w * r, inside = outside, own = 0.0;\n"
                    "    for (int j = -1; j <= 1; ++j) {\n"
                    "        float inner_j = j == 0 ? inner : " + name + "_scale(k + float(j));\n"
                    "        float outer_j = inner_j * c.z;\n"
                    "        float to_shell = max(max(inner_j - r, r - outer_j), 0.0);\n"
                    "        float a = " + name + "_in_shell(p, inner_j);\n"
                    "        if (j == 0) own = a;\n"
                    "        outside = min(outside, max(a, to_shell));\n"
                    "        inside = min(inside, max(-a, to_shell));\n"
                    "    }\n"
                    "    float d = own < 0.0 ? -inside : outside;\n";
            break;
        }
        if (options_.seam_band > 0.0f) {
            // The local step factor (distance()), its own vec4 (band, (1 - f) / (1 + band)),
            // appended only when used so that a global factor's GLSL is as before.
            const std::string b = out.at(out.vec4({options_.seam_band, band_weight_, 0.0f, 0.0f},
                                                  name + " seam band, (1 - step factor) / (1 + band)"));
            body += "    float e = max(min(r - inner, outer - r) - " + b + ".x * r, 0.0);\n"
                    "    return min(d, d * " + o + ".y + " + b + ".y * e);\n}\n";
            out.function(body);
            return;
        }
        out.function(body + "    return d * " + o + ".y;\n}\n");
    }

private:
    // The prototype's distance seen from the shell of scale s^k: f(p / s^k) s^k.
    template <class T>
    T in_shell(const vec3<T>& p, const T& scale) const
    {
        return shell_.distance(p / scale) * scale;
    }

    Shell shell_;
    shell_options options_{};
    float density_ = 1, ratio_ = float(std::numbers::e);
    float other_shells_ = 0; // 1 - 1/s, rounded down
    float band_weight_ = 0;  // (1 - step_factor) / (1 + seam_band), rounded down

    // Shells the float radii reach (floor(log r density) for r in [1e-30, 3.4e38], one more
    // inside for the adjacent shells, none whose scale overflows), cut to glsl_max_table around 0.
    std::pair<int, int> glsl_table_range() const
    {
        const double d = double(density_);
        int lo = int(std::floor(std::log(double(detail::smallest_radius)) * d)) - 1;
        // The top shells' scales overflow float: the table stops short of them (the GPU's exp
        // gives inf there, as the C++ does).
        int hi = int(std::floor(std::log(double(std::numeric_limits<float>::max())) * d)) - 1;
        lo = std::max(lo, -glsl_max_table / 2);
        hi = std::min(hi, glsl_max_table / 2 - 1);
        return {lo, hi - lo + 1};
    }
};

} // namespace krs

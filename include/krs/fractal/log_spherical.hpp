#pragma once
// Log-polar and log-spherical warps: infinite self-similarity without loops.
//
// The forward log-polar map (rho, theta) = (log r, atan2) turns scaling about the origin into a
// translation along rho, so a field tiled along rho becomes, mapped back, a geometry repeated at
// every scale. The map scales space locally by 1/r, so a tile's distance is multiplied by r (by
// r / S when the tile coordinates are stretched by S). This header gives three such fields, each a
// template over the user's tile (any krs field) and over the lane type:
//
//   log_polar_tiling<Tile>      2D log-polar cells on the xz plane; the third axis y is divided by
//                               the same factor r / S so the scaling stays uniform.
//   log_spherical_tiling<Tile>  (log r, theta, phi) cells: spheres of cells at every scale.
//   similar_shell<Shell>        forward then inverse log-spherical map with the tiling in between,
//                               which reduces to p' = p / s^k for the shell k holding p: any field
//                               placed in the prototype shell 1 <= |p| <= s, s = e^(1/density),
//                               repeated inside and outside itself.
//
// Bounds. The tilings are not isometries: with m(x) = r / S the field is h(u(x)) m(x), whose
// gradient is m J^T grad h + h grad m. m J is a rotation except along the third axis (log-polar:
// a shear of size |y| / r) or the azimuth (log-spherical: 1 / sin theta), and |grad m| = 1 / S. So
// each tiling bounds the cell field |h| by a margin mu (h = clamp(min(max(F, mu - b), mu), -mu, mu),
// b the distance to the cell's border: equal to mu on every border, so the cells join
// continuously), keeps geometry away from where the shear grows without bound (log-polar: within
// |y| <= (Y / S) r; log-spherical: out of the two polar rows of cells), and divides by the
// resulting Lipschitz bound, as lipschitz_warp does: the fields are 1-Lipschitz and never
// overestimate. A tile's geometry closer than mu to its cell border is clipped there.
//
// The similar shell is a similarity inside each shell (exactly 1-Lipschitz there) but jumps
// between shells: each shell sees only its own copy. shell_options picks the document's fixes:
//   seams::none              the document's field: 1 shell evaluation; rays may overshoot at seams.
//   seams::adjacent_shells   min over shells k-1, k, k+1 (each clamped below by the distance to
//                            its shell) and r (1 - 1/s), a lower bound of the distance to every
//                            other shell that is continuous in r: the three-shell windows of
//                            neighbouring shells then agree at their common boundary, and the field
//                            is 1-Lipschitz and never overestimates. 3 shell evaluations.
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

#include "krs/core/rounding.hpp"
#include "krs/core/validate.hpp"
#include "krs/field.hpp"
#include "krs/kernels/box.hpp"
#include "krs/kernels/capsule.hpp"

#include <algorithm>
#include <array>
#include <cmath>
#include <limits>
#include <numbers>
#include <string>
#include <string_view>
#include <utility>
#include <vector>

namespace krs {

namespace detail {
// The smallest radius the warps take a logarithm of: keeps r = 0 (the singularity) finite; every
// distance there is multiplied by r or a shell scale of this size, so the result is ~0.
inline constexpr float smallest_radius = 1e-30f;

// The cell field h of the header comment, on cell coordinates (x, z) in [-1/2, 1/2).
template <class Tile, class T>
inline T margin_clamped_cell(const Tile& tile, const vec3<T>& u, float margin)
{
    const T mu(margin);
    const T border = T(0.5f) - max(abs(u.x), abs(u.z));
    const T h = min(max(tile.distance(u), mu - border), mu);
    return max(h, -mu);
}

// GLSL of a tiling (log_polar_tiling, log_spherical_tiling; krs/glsl/emitter.hpp): the tile as
// NAME_tile, and NAME(p) = finish(p, u, NAME_tile(u)) at the cell coordinates u = cell(p), with the
// tiling's own _cell and _finish functions and its one vec4 of parameters.
template <class Tiling, class Out>
void glsl_emit_tiling(const Tiling& tiling, Out& out, const std::string& name)
{
    out.field(tiling.tile(), name + "_tile");
    out.template library<Tiling>();
    const std::string c = out.at(out.parameters(tiling, name));
    const std::string kind(Tiling::glsl_name);
    out.function("float " + name + "(vec3 p) {\n    vec3 u = " + kind + "_cell(p, " + c + ");\n    return " + kind +
                 "_finish(p, u, " + name + "_tile(u), " + c + ");\n}\n");
}

} // namespace detail

// ---- log-polar tiling of the xz plane ----------------------------------------------------------

// Cells: u = (S log r, S (theta + pi)) with S = cells / (2 pi), so `cells` cells go around the
// circle (an integer count: the seam at theta = +-pi is then a cell border) and each cell is e^(1/S) times
// larger than the one inside it. The tile is evaluated at (u_rho - cell center, y S / r,
// u_theta - cell center): tile x is radial, y is height, z is around. Tile geometry must lie in
// |y| <= height and at least `margin` inside the cell's square [-1/2, 1/2]^2.
template <field Tile>
class log_polar_tiling {
public:
    log_polar_tiling(Tile tile, int cells, float height, float margin = 0.1f) : tile_(std::move(tile))
    {
        if (cells < 1 || cells > 4096)
            throw invalid_parameter("log_polar_tiling.cells", "must be an integer in [1, 4096]", std::to_string(cells));
        height_ = require_length("log_polar_tiling.height", height);
        margin_ = require_positive("log_polar_tiling.margin", margin);
        if (!(margin_ <= 0.5f))
            throw invalid_parameter("log_polar_tiling.margin", "must be <= 0.5 (half a cell)", detail::to_text(margin));
        cells_ = cells;
        const double s = double(cells) / (2.0 * std::numbers::pi);
        scale_ = float(s);
        const double a = double(height_) / s; // largest |y| / r where the tile is evaluated
        const double sheared = 0.5 * (a + std::sqrt(a * a + 4.0)) + double(margin_) / s;
        const double cone = std::sqrt(1.0 + a * a);
        bound_ = std::max(sheared, cone);
        inverse_bound_ = float_at_most(1.0 / bound_);
    }
    int cells() const { return cells_; }
    // The field's Lipschitz bound before normalization (its distance is already divided by it).
    double lipschitz() const { return bound_; }
    const Tile& tile() const { return tile_; }

    template <class T>
    T distance(const vec3<T>& p) const
    {
        const T s(scale_);
        const T r = sqrt(p.x * p.x + p.z * p.z);
        const T rs = max(r, T(detail::smallest_radius));
        const T theta = lane_atan2(p.z, select(r > T(0), p.x, T(1)));
        const T cu = s * lane_log(rs), cv = s * (theta + T(std::numbers::pi_v<float>));
        const T h(height_);
        const vec3<T> u{cu - lane_floor(cu) - T(0.5f), clamp(p.y * s / rs, -h, h),
                        cv - lane_floor(cv) - T(0.5f)};
        const T sheared = detail::margin_clamped_cell(tile_, u, margin_) * r / s;
        const T cone = abs(p.y) - h * r / s; // height limit, |y| <= (Y / S) r
        return max(sheared, cone) * T(inverse_bound_);
    }

    // GLSL (krs/glsl/emitter.hpp, which emits the tile by recursion as NAME_tile and writes
    // `NAME(p) = finish(p, u, NAME_tile(u = cell(p)))`): one vec4 (S, height, margin, 1 / bound),
    // the same operations in the same order as distance() (atan and log are the GPU's own).
    static constexpr std::string_view glsl_name = "krs_log_polar_tiling";
    static constexpr std::string_view glsl_source = R"(vec3 krs_log_polar_tiling_cell(vec3 p, vec4 c) {
    float r = sqrt(p.x * p.x + p.z * p.z);
    float rs = max(r, 1e-30);
    float theta = atan(p.z, r > 0.0 ? p.x : 1.0);
    float cu = c.x * log(rs);
    float cv = c.x * (theta + 3.1415927);
    return vec3(cu - floor(cu) - 0.5, clamp(p.y * c.x / rs, -c.y, c.y), cv - floor(cv) - 0.5);
}
float krs_log_polar_tiling_finish(vec3 p, vec3 u, float tile, vec4 c) {
    float r = sqrt(p.x * p.x + p.z * p.z);
    float border = 0.5 - max(abs(u.x), abs(u.z));
    float h = max(min(max(tile, c.z - border), c.z), -c.z);
    float sheared = h * r / c.x;
    float cone = abs(p.y) - c.y * r / c.x;
    return max(sheared, cone) * c.w;
}
)";
    std::array<float, 4> glsl_parameters() const { return {scale_, height_, margin_, inverse_bound_}; }
    template <class Out>
    void glsl_emit(Out& out, const std::string& name) const
    {
        detail::glsl_emit_tiling(*this, out, name);
    }

private:
    Tile tile_;
    int cells_ = 1;
    float height_ = 0, margin_ = 0.1f, scale_ = 1;
    double bound_ = 1;
    float inverse_bound_ = 1;
};

// ---- log-spherical tiling ------------------------------------------------------------------------

// Cells: u = S (log r, theta, phi), S = cells / (2 pi) with an even `cells` >= 6, so cells go
// around in phi, cells / 2 from pole to pole, and the cell at the seam phi = pi and the poles are
// borders. The two rows of cells touching the poles stay empty (there the azimuth stretches
// without bound). Tile x is radial, y polar, z azimuthal.
template <field Tile>
class log_spherical_tiling {
public:
    log_spherical_tiling(Tile tile, int cells, float margin = 0.1f) : tile_(std::move(tile))
    {
        if (cells < 6 || cells > 4096 || cells % 2 != 0)
            throw invalid_parameter("log_spherical_tiling.cells", "must be an even integer in [6, 4096]",
                                    std::to_string(cells));
        margin_ = require_positive("log_spherical_tiling.margin", margin);
        if (!(margin_ <= 0.5f))
            throw invalid_parameter("log_spherical_tiling.margin", "must be <= 0.5 (half a cell)",
                                    detail::to_text(margin));
        cells_ = cells;
        const double s = double(cells) / (2.0 * std::numbers::pi);
        scale_ = float(s);
        bound_ = 1.0 / std::sin(1.0 / s) + double(margin_) / s;
        inverse_bound_ = float_at_most(1.0 / bound_);
    }
    int cells() const { return cells_; }
    double lipschitz() const { return bound_; }
    const Tile& tile() const { return tile_; }

    template <class T>
    T distance(const vec3<T>& p) const
    {
        const T s(scale_);
        const T planar = sqrt(p.x * p.x + p.y * p.y);
        const T r = sqrt(planar * planar + p.z * p.z);
        const T rs = max(r, T(detail::smallest_radius));
        const T theta = lane_atan2(planar, select(r > T(0), p.z, T(1)));
        const T phi = lane_atan2(p.y, select(planar > T(0), p.x, T(1)));
        const T cu = s * lane_log(rs), cv = s * theta, cw = s * (phi + T(std::numbers::pi_v<float>));
        const T row = lane_floor(cv);
        const vec3<T> u{cu - lane_floor(cu) - T(0.5f), cv - row - T(0.5f), cw - lane_floor(cw) - T(0.5f)};
        // Cell field with the border clamp in both the polar (y) and azimuth (z) directions.
        const T mu(margin_);
        const T border = T(0.5f) - max(abs(u.x), max(abs(u.y), abs(u.z)));
        T h = max(min(max(tile_.distance(u), mu - border), mu), -mu);
        const T last_row(float(cells_ / 2 - 1));
        h = select(row >= T(1) && row < last_row, h, mu);
        return h * r / s * T(inverse_bound_);
    }

    // GLSL: as log_polar_tiling; one vec4 (S, margin, 1 / bound, cells / 2 - 1).
    static constexpr std::string_view glsl_name = "krs_log_spherical_tiling";
    static constexpr std::string_view glsl_source = R"(vec3 krs_log_spherical_tiling_cell(vec3 p, vec4 c) {
    float planar = sqrt(p.x * p.x + p.y * p.y);
    float r = sqrt(planar * planar + p.z * p.z);
    float rs = max(r, 1e-30);
    float theta = atan(planar, r > 0.0 ? p.z : 1.0);
    float phi = atan(p.y, planar > 0.0 ? p.x : 1.0);
    float cu = c.x * log(rs);
    float cv = c.x * theta;
    float cw = c.x * (phi + 3.1415927);
    return vec3(cu - floor(cu) - 0.5, cv - floor(cv) - 0.5, cw - floor(cw) - 0.5);
}
float krs_log_spherical_tiling_finish(vec3 p, vec3 u, float tile, vec4 c) {
    float planar = sqrt(p.x * p.x + p.y * p.y);
    float r = sqrt(planar * planar + p.z * p.z);
    float theta = atan(planar, r > 0.0 ? p.z : 1.0);
    float row = floor(c.x * theta);
    float border = 0.5 - max(abs(u.x), max(abs(u.y), abs(u.z)));
    float h = max(min(max(tile, c.y - border), c.y), -c.y);
    h = row >= 1.0 && row < c.w ? h : c.y;
    return h * r / c.x * c.z;
}
)";
    std::array<float, 4> glsl_parameters() const { return {scale_, margin_, inverse_bound_, float(cells_ / 2 - 1)}; }
    template <class Out>
    void glsl_emit(Out& out, const std::string& name) const
    {
        detail::glsl_emit_tiling(*this, out, name);
    }

private:
    Tile tile_;
    int cells_ = 6;
    float margin_ = 0.1f, scale_ = 1;
    double bound_ = 1;
    float inverse_bound_ = 1;
};

// ---- similar log-spherical shell -----------------------------------------------------------------

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
            d = T(other_shells_) * r;
            for (int j = -1; j <= 1; ++j) {
                const T inner_j = j == 0 ? inner : lane_exp((k + T(float(j))) * inv_density);
                const T outer_j = inner_j * T(ratio_);
                const T to_shell = max(max(inner_j - r, r - outer_j), T(0));
                d = min(d, max(in_shell(p, inner_j), to_shell));
            }
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
            body += "    float d = c.w * r;\n"
                    "    for (int j = -1; j <= 1; ++j) {\n"
                    "        float inner_j = j == 0 ? inner : " + name + "_scale(k + float(j));\n"
                    "        float outer_j = inner_j * c.z;\n"
                    "        float to_shell = max(max(inner_j - r, r - outer_j), 0.0);\n"
                    "        d = min(d, max(" + name + "_in_shell(p, inner_j), to_shell));\n"
                    "    }\n";
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

// ---- presets -------------------------------------------------------------------------------------

// One ring of `petals` capsule petals in the shell 1 <= |p| <= s (s = e^(1/density)), rising from
// near the inner sphere at 15 degrees above the xy plane to near the outer one at 55 degrees; the
// similar shell makes it a lotus with rings of petals at every scale.
struct lotus_shell {
    static constexpr int max_petals = 16;
    std::array<capsule, max_petals> petal{};
    int petals = 0;

    lotus_shell() = default;
    lotus_shell(float ratio, int petals_)
    {
        if (petals_ < 1 || petals_ > max_petals)
            throw invalid_parameter("lotus_shell.petals", "must be in [1, 16]", std::to_string(petals_));
        const double s = require_finite("lotus_shell.ratio", ratio);
        if (!(s > 1.0 && s <= double(max_magnitude)))
            throw invalid_parameter("lotus_shell.ratio", "must be in (1, 1e9]", detail::to_text(ratio));
        const double rb = std::pow(s, 0.2), rt = std::pow(s, 0.8);
        const double radius = std::min({0.15 * (rt - rb), rb - 1.0, s - rt}) * 0.95;
        const double low = 15.0 * std::numbers::pi / 180.0, high = 55.0 * std::numbers::pi / 180.0;
        petals = petals_;
        for (int i = 0; i < petals; ++i) {
            const double a = 2.0 * std::numbers::pi * (i + 0.5) / petals;
            const vec3d base = vec3d{std::cos(a) * std::cos(low), std::sin(a) * std::cos(low), std::sin(low)} * rb;
            const vec3d tip = vec3d{std::cos(a) * std::cos(high), std::sin(a) * std::cos(high), std::sin(high)} * rt;
            petal[std::size_t(i)] = capsule(vec3f(base), vec3f(tip), float(radius));
        }
    }
    template <class T>
    T distance(const vec3<T>& p) const
    {
        T d = petal[0].distance(p);
        for (int i = 1; i < petals; ++i) d = min(d, petal[std::size_t(i)].distance(p));
        return d;
    }
    // GLSL (krs/glsl/emitter.hpp): petal i as NAME_i, NAME their minimum in this order.
    template <class Out>
    void glsl_emit(Out& out, const std::string& name) const
    {
        for (int i = 0; i < petals; ++i) out.field(petal[std::size_t(i)], name + "_" + std::to_string(i));
        out.minimum_of_parts(name, std::size_t(petals));
    }
};

// Fourteen cubes in the shell: on the six axes and the eight diagonals, at the shell's middle
// radius s^(1/2); the similar shell makes them a cube singularity, cubes around cubes down to the
// origin and out to infinity.
struct cube_shell {
    std::array<box, 14> cube{};

    cube_shell() = default;
    explicit cube_shell(float ratio)
    {
        const double s = require_finite("cube_shell.ratio", ratio);
        if (!(s > 1.0 && s <= double(max_magnitude)))
            throw invalid_parameter("cube_shell.ratio", "must be in (1, 1e9]", detail::to_text(ratio));
        const double rc = std::sqrt(s);
        const double h = 0.8 * std::min(rc - 1.0, s - rc) / std::sqrt(3.0);
        int n = 0;
        for (int axis = 0; axis < 3; ++axis)
            for (int sign = -1; sign <= 1; sign += 2) {
                vec3d c{0, 0, 0};
                (axis == 0 ? c.x : axis == 1 ? c.y : c.z) = sign * rc;
                cube[std::size_t(n++)] = box(vec3f(c), vec3f(vec3d{h, h, h}));
            }
        for (int i = 0; i < 8; ++i) {
            const vec3d c = vec3d{(i & 1) ? 1.0 : -1.0, (i & 2) ? 1.0 : -1.0, (i & 4) ? 1.0 : -1.0} * (rc / std::sqrt(3.0));
            cube[std::size_t(n++)] = box(vec3f(c), vec3f(vec3d{h, h, h}));
        }
    }
    template <class T>
    T distance(const vec3<T>& p) const
    {
        T d = cube[0].distance(p);
        for (std::size_t i = 1; i < cube.size(); ++i) d = min(d, cube[i].distance(p));
        return d;
    }
    // GLSL (krs/glsl/emitter.hpp): cube i as NAME_i, NAME their minimum in this order.
    template <class Out>
    void glsl_emit(Out& out, const std::string& name) const
    {
        for (std::size_t i = 0; i < cube.size(); ++i) out.field(cube[i], name + "_" + std::to_string(i));
        out.minimum_of_parts(name, cube.size());
    }
};

using recursive_lotus = similar_shell<lotus_shell>;
inline recursive_lotus make_recursive_lotus(float density = 1.0f, int petals = 8, shell_options options = {})
{
    detail::require_shell_density("recursive_lotus.density", density);
    return {lotus_shell(float(std::exp(1.0 / double(density))), petals), density, options};
}

using cube_singularity = similar_shell<cube_shell>;
inline cube_singularity make_cube_singularity(float density = 1.0f, shell_options options = {})
{
    detail::require_shell_density("cube_singularity.density", density);
    return {cube_shell(float(std::exp(1.0 / double(density)))), density, options};
}

} // namespace krs

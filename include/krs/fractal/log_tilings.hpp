#pragma once
// Log-polar and log-spherical tilings: infinite self-similarity without loops.
//
// The forward log-polar map (rho, theta) = (log r, atan2) turns scaling about the origin into a
// translation along rho, so a field tiled along rho becomes, mapped back, a geometry repeated at
// every scale. The map scales space locally by 1/r, so a tile's distance is multiplied by r (by
// r / S when the tile coordinates are stretched by S). This header gives two such fields, each a
// template over the user's tile (any krs field) and over the lane type:
//
//   log_polar_tiling<Tile>      2D log-polar cells on the xz plane; the third axis y is divided by
//                               the same factor r / S so the scaling stays uniform.
//   log_spherical_tiling<Tile>  (log r, theta, phi) cells: spheres of cells at every scale.
//
// (The similar shell, krs/fractal/similar_shell.hpp, is the third: the forward then inverse
// log-spherical map with the tiling in between.)
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

#include "krs/core/rounding.hpp"
#include "krs/core/validate.hpp"
#include "krs/field.hpp"

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

} // namespace krs

#pragma once
// Placement of any field: translate, rotate, scale uniformly or map it by any invertible affine
// map, and it stays a field (krs/field.hpp).
//
// An affine map x -> A x + t puts the part's geometry where the user wants it. Its distance at a
// world point x is the part's at the point the map sends there,
//     g(x) = f(M (x - t)) / |M|,   M = A^-1,   |M| its spectral norm (largest singular value),
// which is 1-Lipschitz: |g(x) - g(y)| <= |M (x - y)| / |M| <= |x - y|, and whose zero set is the
// image of f's. So g never overestimates the distance to its own surface (krs/field.hpp's argument).
// For the usual placements this is the exact distance of the placed geometry (IQ's "distance
// functions" article writes each the same way):
//     translation  A = I:        g(x) = f(x - t)
//     rotation     A = R:        g(x) = f(R^T (x - t))       (|R^T| = 1)
//     uniform scale A = s I:     g(x) = s f((x - t) / s)     (|M| = 1/s)
// A general affine map (a shear, a scale by axis) keeps only the bound: where A stretches some
// directions more than others, the stretched directions' distances come out short by up to the
// map's condition number |A| |A^-1|, so a sphere tracer takes more, smaller steps there.
//
// The map is given in double and stored as M (rows), t and 1/|M| in float. 1/|M| is rounded down
// (float_at_most, krs/core/rounding.hpp): a factor rounded up would make the field overestimate.
// |M| is the square root of the largest eigenvalue of the symmetric M^T M, taken in closed form
// (the trigonometric solution of its characteristic cubic) and raised by 1e-12 relative, far more
// than the cubic's rounding error in double for the condition numbers allowed (<= 1e6); where
// M^T M is a multiple of the identity (rigid motions, uniform scales) it is exact, so a rigid
// motion whose rows are exact in float (an axis flip or swap) keeps the factor 1.

#include "krs/core/bounds.hpp"
#include "krs/core/lanes.hpp"
#include "krs/core/rounding.hpp"
#include "krs/core/validate.hpp"
#include "krs/field.hpp"

#include <algorithm>
#include <array>
#include <cmath>
#include <numbers>
#include <string>
#include <utility>

namespace krs {

// x -> linear x + offset, the linear part by its rows, in double (the user's description; the
// placed field stores what it evaluates in float).
struct affine_map {
    std::array<vec3d, 3> rows{vec3d{1, 0, 0}, vec3d{0, 1, 0}, vec3d{0, 0, 1}};
    vec3d offset{};

    static affine_map translation(const vec3d& t) { return {{vec3d{1, 0, 0}, vec3d{0, 1, 0}, vec3d{0, 0, 1}}, t}; }
    // Turns by `radians` about the unit `axis` through the origin, counterclockwise seen from the
    // axis' tip (Rodrigues: R = cos I + sin [axis]x + (1 - cos) axis axis^T).
    static affine_map rotation(const vec3d& axis, double radians)
    {
        const vec3d a = axis / length(axis);
        const double c = std::cos(radians), s = std::sin(radians), k = 1.0 - c;
        return {{vec3d{c + k * a.x * a.x, k * a.x * a.y - s * a.z, k * a.x * a.z + s * a.y},
                 vec3d{k * a.y * a.x + s * a.z, c + k * a.y * a.y, k * a.y * a.z - s * a.x},
                 vec3d{k * a.z * a.x - s * a.y, k * a.z * a.y + s * a.x, c + k * a.z * a.z}},
                {}};
    }
    static affine_map scaling(double s) { return {{vec3d{s, 0, 0}, vec3d{0, s, 0}, vec3d{0, 0, s}}, {}}; }

    vec3d linear(const vec3d& v) const { return {dot(rows[0], v), dot(rows[1], v), dot(rows[2], v)}; }
    vec3d apply(const vec3d& p) const { return linear(p) + offset; }
    // This map followed by `next`: x -> next(this(x)).
    affine_map then(const affine_map& next) const
    {
        affine_map r;
        for (int i = 0; i < 3; ++i) {
            const vec3d& n = next.rows[std::size_t(i)];
            r.rows[std::size_t(i)] = vec3d{n.x * rows[0].x + n.y * rows[1].x + n.z * rows[2].x,
                                           n.x * rows[0].y + n.y * rows[1].y + n.z * rows[2].y,
                                           n.x * rows[0].z + n.y * rows[1].z + n.z * rows[2].z};
        }
        r.offset = next.apply(offset);
        return r;
    }
};

namespace detail {

inline double determinant(const std::array<vec3d, 3>& m) { return dot(m[0], cross(m[1], m[2])); }

// The inverse's rows: the adjugate (cross products of the rows) over the determinant.
inline std::array<vec3d, 3> inverse_rows(const std::array<vec3d, 3>& m)
{
    const vec3d c0 = cross(m[1], m[2]), c1 = cross(m[2], m[0]), c2 = cross(m[0], m[1]);
    const double inv = 1.0 / dot(m[0], c0);
    // c0, c1, c2 are the inverse's columns (times det): transpose them into rows.
    return {vec3d{c0.x, c1.x, c2.x} * inv, vec3d{c0.y, c1.y, c2.y} * inv, vec3d{c0.z, c1.z, c2.z} * inv};
}

// The spectral norm of m, or just above it: sqrt of the largest eigenvalue of the symmetric m^T m.
// A multiple of an orthogonal matrix (m^T m = q I: a rigid motion, a uniform scale) gives sqrt(q)
// as it is; otherwise the trigonometric solution of the characteristic cubic, raised by 1e-12
// relative to cover its rounding in double.
inline double spectral_norm(const std::array<vec3d, 3>& m)
{
    auto column = [&](int j) {
        return vec3d{j == 0 ? m[0].x : j == 1 ? m[0].y : m[0].z, j == 0 ? m[1].x : j == 1 ? m[1].y : m[1].z,
                     j == 0 ? m[2].x : j == 1 ? m[2].y : m[2].z};
    };
    const vec3d c0 = column(0), c1 = column(1), c2 = column(2);
    const double a00 = dot(c0, c0), a11 = dot(c1, c1), a22 = dot(c2, c2);
    const double a01 = dot(c0, c1), a02 = dot(c0, c2), a12 = dot(c1, c2);
    const double q = (a00 + a11 + a22) / 3.0;
    const double off = a01 * a01 + a02 * a02 + a12 * a12;
    const double p2 = (a00 - q) * (a00 - q) + (a11 - q) * (a11 - q) + (a22 - q) * (a22 - q) + 2.0 * off;
    if (p2 <= 0.0) return std::sqrt(std::max(q, 0.0)); // a multiple of the identity
    const double p = std::sqrt(p2 / 6.0);
    // B = (A - q I) / p; the largest eigenvalue is q + 2 p cos(acos(det(B) / 2) / 3).
    const double b00 = (a00 - q) / p, b11 = (a11 - q) / p, b22 = (a22 - q) / p;
    const double b01 = a01 / p, b02 = a02 / p, b12 = a12 / p;
    const double det = b00 * (b11 * b22 - b12 * b12) - b01 * (b01 * b22 - b12 * b02) + b02 * (b01 * b12 - b11 * b02);
    const double phi = std::acos(std::clamp(det / 2.0, -1.0, 1.0)) / 3.0;
    const double largest = std::max(q + 2.0 * p * std::cos(phi), a00);
    return std::sqrt(std::max(largest, std::max(a11, a22))) * (1.0 + 1e-12);
}

} // namespace detail

// A field placed by an affine map: placed(part, map), or translated / rotated / scaled below.
// The map must be finite and invertible with condition number |A| |A^-1| <= 1e6 (beyond that the
// float field's steps would shrink a millionfold).
template <field F>
class placed {
public:
    placed(F part, const affine_map& to_world) : part_(std::move(part)), to_world_(to_world)
    {
        for (const vec3d& r : to_world.rows) require_finite("placement.linear", r);
        require_magnitude("placement.offset", to_world.offset);
        const double norm = detail::spectral_norm(to_world.rows);
        const double det = detail::determinant(to_world.rows);
        if (!(norm > 0.0) || !(std::abs(det) > 0.0))
            throw invalid_parameter("placement.linear", "must be invertible (a scale of 0 flattens the field)",
                                    "determinant " + detail::to_text(det));
        const std::array<vec3d, 3> inverse = detail::inverse_rows(to_world.rows);
        const double inverse_norm = detail::spectral_norm(inverse);
        if (!(norm * inverse_norm <= 1e6))
            throw invalid_parameter("placement.linear", "must have a condition number |A| |A^-1| of at most 1e6",
                                    detail::to_text(norm * inverse_norm));
        for (std::size_t i = 0; i < 3; ++i) to_part_[i] = vec3f(inverse[i]);
        offset_ = vec3f(to_world.offset);
        // Measured on the stored float rows, so the factor bounds the map the field evaluates.
        const std::array<vec3d, 3> stored{vec3d(to_part_[0]), vec3d(to_part_[1]), vec3d(to_part_[2])};
        factor_ = float_at_most(1.0 / detail::spectral_norm(stored));
        stretch_ = norm;
    }

    const F& part() const { return part_; }
    const affine_map& to_world() const { return to_world_; }
    // 1 / |M|: the part's distances are multiplied by it (1 for a rigid motion, s for a scale by s).
    float factor() const { return factor_; }

    template <class T>
    T distance(const vec3<T>& p) const
    {
        const vec3<T> q = p - vec3<T>(offset_);
        const vec3<T> local{dot(vec3<T>(to_part_[0]), q), dot(vec3<T>(to_part_[1]), q), dot(vec3<T>(to_part_[2]), q)};
        return part_.distance(local) * splat<T>(factor_);
    }

    // The part's sphere carried over: its centre mapped, its radius times |A| (the most the map
    // stretches any direction), rounded outward.
    bounding_sphere bound() const
        requires requires(const F& f) { { f.bound() } -> std::convertible_to<bounding_sphere>; }
    {
        const bounding_sphere b = part_.bound();
        if (!b.is_bounded()) return b;
        return bound_around(to_world_.apply(vec3d(b.center)), double(b.radius) * stretch_);
    }
    // The part's box carried over: the hull of its eight corners mapped (the image of a box is the
    // parallelepiped they span), rounded outward.
    bounding_box bound_box() const
        requires requires(const F& f) { { f.bound_box() } -> std::convertible_to<bounding_box>; }
    {
        const bounding_box b = part_.bound_box();
        if (!b.is_bounded()) return b;
        vec3d lo{INFINITY, INFINITY, INFINITY}, hi = -lo;
        for (int corner = 0; corner < 8; ++corner) {
            const vec3d c{(corner & 1) ? b.hi.x : b.lo.x, (corner & 2) ? b.hi.y : b.lo.y, (corner & 4) ? b.hi.z : b.lo.z};
            const vec3d w = to_world_.apply(c);
            lo = {std::min(lo.x, w.x), std::min(lo.y, w.y), std::min(lo.z, w.z)};
            hi = {std::max(hi.x, w.x), std::max(hi.y, w.y), std::max(hi.z, w.z)};
        }
        // The double products round too: a relative pad far above their error.
        const double pad = 1e-12 * (length(lo) + length(hi));
        return box_around(lo - vec3d{pad, pad, pad}, hi + vec3d{pad, pad, pad});
    }

    // GLSL (krs/glsl/emitter.hpp): the part as NAME_a, and NAME evaluating it at the same local
    // point in the C++'s order (the offset, then one dot product per row, then the factor).
    template <class Out>
    void glsl_emit(Out& out, const std::string& name) const
    {
        out.field(part_, name + "_a");
        const std::size_t at = out.vec4({offset_.x, offset_.y, offset_.z, factor_}, name + " placement (offset, factor)");
        for (std::size_t i = 0; i < 3; ++i)
            out.vec4({to_part_[i].x, to_part_[i].y, to_part_[i].z, 0.0f},
                     name + " placement row " + std::to_string(i) + " of the inverse");
        const std::string o = out.at(at), r0 = out.at(at + 1), r1 = out.at(at + 2), r2 = out.at(at + 3);
        out.function("float " + name + "(vec3 x) {\n"
                     "    vec3 q = x - " + o + ".xyz;\n"
                     "    vec3 local = vec3(dot(" + r0 + ".xyz, q), dot(" + r1 + ".xyz, q), dot(" + r2 + ".xyz, q));\n"
                     "    return " + name + "_a(local) * " + o + ".w;\n}\n");
    }

private:
    F part_;
    affine_map to_world_;
    std::array<vec3f, 3> to_part_{}; // M = A^-1, by rows
    vec3f offset_{};
    float factor_ = 1.0f;
    double stretch_ = 1.0; // |A|
};

// The usual placements by name. Each returns a placed field; nest or compose maps with
// affine_map::then for more than one.
template <field F>
placed<F> translated(F part, const vec3f& offset)
{
    return placed<F>(std::move(part), affine_map::translation(vec3d(require_magnitude("translated.offset", offset))));
}
// Turned by `radians` about the unit-length `axis` through the origin.
template <field F>
placed<F> rotated(F part, const vec3f& axis, float radians)
{
    require_finite("rotated.axis", axis);
    if (!(length(vec3d(axis)) > 0.0))
        throw invalid_parameter("rotated.axis", "must be a non-zero vector", detail::to_text(axis));
    return placed<F>(std::move(part), affine_map::rotation(vec3d(axis), double(require_finite("rotated.radians", radians))));
}
// Scaled by s > 0 about the origin (distances scale by s).
template <field F>
placed<F> scaled(F part, float s)
{
    require_positive("scaled.scale", s);
    return placed<F>(std::move(part), affine_map::scaling(double(s)));
}

} // namespace krs

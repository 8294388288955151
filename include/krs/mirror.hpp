#pragma once
// Mirror: the reflection plane of one KRS level, m . x = c with |m| = 1 (paper section 3).
//
// Because |m| = 1, e = m . x - c is the signed distance of x to the plane, and the reflection is
//     R x = x - 2 (m . x - c) m          (an isometry, Lipschitz constant 1),
//     M w = w - 2 (m . w) m              (the same for directions).
// Algorithm 1 reflects a point only when it lies on the positive side (e > 0). Written as
//     fold(x) = x - 2 max(e, 0) m
// that choice needs no select in a packet: for e <= 0 the correction is exactly zero. A scalar
// walk branches instead: the branch is predicted (a ray's successive points mostly fold alike),
// and a predicted branch lets the next level start before this level's dot product is known,
// where max(e, 0) chains every level's operations behind the previous one (the general-mirror
// terrain's scalar walk took 20 cycles per level that way, 11 with the branch).

#include "krs/core/oriented_plane.hpp"
#include "krs/core/validate.hpp"

#include <array>
#include <concepts>
#include <cstdint>
#include <string>
#include <string_view>

namespace krs {

// x - 2 max(m . x - c, 0) m for the plane (m, c), |m| = 1: Algorithm 1's fold, shared by `mirror`
// and the KIFS `plane_fold` so both are the same bit for bit.
// 2 max(e, 0) = max(2e, 0), and 2e is the plane (2m, 2c) at x, exactly (doubling is exact): with
// the factor inside the constants, a level's chain of dependent operations is a fused dot, a max
// and three fused multiply-adds, seven where doubling e took one more (the doubled constants are
// computed off that chain, once per level for all the points walked together). Spelled per
// coordinate: GCC kept a temporary doubled vector on the stack.
template <class T>
inline vec3<T> fold_positive_side(const vec3f& m, float c, const vec3<T>& p)
{
    const T twice_e = ((T(2.0f * m.x) * p.x - T(2.0f * c)) + T(2.0f * m.y) * p.y) + T(2.0f * m.z) * p.z;
    if constexpr (std::floating_point<T>) {
        if (!(twice_e > T(0))) return p;
        return {p.x - T(m.x) * twice_e, p.y - T(m.y) * twice_e, p.z - T(m.z) * twice_e};
    } else {
        const T t = max(twice_e, T(0));
        return {p.x - T(m.x) * t, p.y - T(m.y) * t, p.z - T(m.z) * t};
    }
}

struct mirror {
    vec3f normal{0, 0, 1};
    float offset = 0.0f;

    mirror() = default;
    // The plane normal . x = offset; the normal is normalized, and a zero or non-finite one is
    // rejected (it would make every reflection NaN). The checks: core/oriented_plane.hpp.
    mirror(const vec3f& normal_, float offset_) : mirror(oriented_plane::checked("mirror", normal_, offset_)) {}
    // The plane through `point` with the given normal.
    static mirror through(const vec3f& point, const vec3f& normal_) { return mirror(oriented_plane::through("mirror", point, normal_)); }
    // The same plane through the constructor's checks: the fields are public, and a sequence
    // builder must not trust them (a normal of length 2 doubled every fold).
    mirror checked() const { return mirror(oriented_plane::kept("mirror", normal, offset)); }

    template <class T>
    T signed_distance(const vec3<T>& p) const
    {
        return plane_value(vec3<T>(normal), p, T(offset));
    }
    // R x, unconditionally.
    template <class T>
    vec3<T> reflect(const vec3<T>& p) const
    {
        const vec3<T> m(normal);
        return p - m * (T(2) * signed_distance(p));
    }
    // Algorithm 1's step: reflect only from the positive side.
    template <class T>
    vec3<T> fold(const vec3<T>& p) const
    {
        return fold_positive_side(normal, offset, p);
    }
    // M w: reflection of a direction (normals, light and view vectors; section 6.1).
    template <class T>
    vec3<T> reflect_direction(const vec3<T>& w) const
    {
        return krs::reflect_direction(w, vec3<T>(normal));
    }

    // GLSL (krs/glsl/emitter.hpp): the same four operations on one vec4 (normal, offset).
    static constexpr std::string_view glsl_name = "krs_mirror";
    static constexpr std::string_view glsl_source = R"(float krs_mirror_signed_distance(vec3 p, vec4 m) { return (m.x * p.x - m.w) + m.y * p.y + m.z * p.z; }
vec3 krs_mirror_reflect(vec3 p, vec4 m) { return p - m.xyz * (2.0 * krs_mirror_signed_distance(p, m)); }
vec3 krs_mirror_fold(vec3 p, vec4 m) {
    float twice_e = ((2.0 * m.x) * p.x - 2.0 * m.w) + (2.0 * m.y) * p.y + (2.0 * m.z) * p.z;
    return p - m.xyz * max(twice_e, 0.0);
}
vec3 krs_mirror_reflect_direction(vec3 w, vec4 m) { return w - m.xyz * (2.0 * dot(m.xyz, w)); }
)";
    std::array<float, 4> glsl_parameters() const { return {normal.x, normal.y, normal.z, offset}; }

private:
    explicit mirror(const oriented_plane& p) : normal(p.normal), offset(p.offset) {}
};

// Axis-aligned mirror: the plane x_axis = position, normal +e_axis (reflects the side above the
// plane) or -e_axis (reflects the side below). Algorithm 1's fold then touches one coordinate:
//     normal +e:  x <- min(x, 2 position - x)        normal -e:  x <- max(x, 2 position - x),
// which is the general fold (x - 2 max(x - position, 0) for +e) rewritten, equal to it up to float
// rounding. The axis and side are the same for every lane of a packet, so their branches are
// uniform; a sequence whose mirrors are all axis-aligned (grids of instances, rocks, terrain
// strata) uses `basic_sequence<axis_mirror, ...>` and pays one min per level instead of a dot
// product and a multiply-add per coordinate. It has the same interface as `mirror` (normal,
// offset, signed_distance, reflect, fold, reflect_direction), so code written for one takes both.
struct axis_mirror {
    // A fold reads and writes one coordinate only, so folds on different axes commute: a sequence
    // may apply a run of them axis by axis (basic_sequence's fold prefix) with the same result.
    static constexpr bool folds_one_axis = true;

    vec3f normal{1, 0, 0}; // +-e_axis
    float offset = 0.0f;   // normal . x = offset, as for `mirror`
    std::uint8_t axis = 0; // 0, 1, 2 for x, y, z
    bool above = true;     // true: normal +e_axis, the side x_axis > position is folded
    float twice_position = 0.0f;

    axis_mirror() = default;
    // The plane x_axis = position; `fold_above` chooses which side Algorithm 1 folds onto the other.
    axis_mirror(int axis_, float position, bool fold_above = true)
    {
        if (axis_ < 0 || axis_ > 2)
            throw invalid_parameter("axis_mirror.axis", "must be 0, 1 or 2 (x, y, z)", std::to_string(axis_));
        require_magnitude("axis_mirror.position", position);
        axis = std::uint8_t(axis_);
        above = fold_above;
        const float sign = above ? 1.0f : -1.0f;
        normal = vec3f{axis == 0 ? sign : 0.0f, axis == 1 ? sign : 0.0f, axis == 2 ? sign : 0.0f};
        offset = sign * position;
        twice_position = 2.0f * position;
    }
    float position() const { return 0.5f * twice_position; }
    // The same mirror rebuilt from axis, position and side through the constructor's checks, with
    // the public normal and offset required to agree (an axis of 7 indexed past the fold prefix's
    // three lists; a NaN position made every distance NaN).
    axis_mirror checked() const
    {
        if (axis > 2) throw invalid_parameter("axis_mirror.axis", "must be 0, 1 or 2 (x, y, z)", std::to_string(int(axis)));
        const axis_mirror rebuilt(axis, require_finite("axis_mirror.position", 0.5f * twice_position), above);
        if (!(rebuilt.normal.x == normal.x && rebuilt.normal.y == normal.y && rebuilt.normal.z == normal.z &&
              rebuilt.offset == offset))
            throw invalid_parameter("axis_mirror.normal", "must be +-e_axis with offset +-position, as axis, position and above say",
                                    detail::to_text(normal));
        return rebuilt;
    }
    // The same plane as a general mirror (for code that needs one, and for tests).
    mirror general() const { return mirror(normal, offset); }

    template <class T>
    T signed_distance(const vec3<T>& p) const
    {
        const T x = axis == 0 ? p.x : (axis == 1 ? p.y : p.z);
        return above ? x - T(position()) : T(position()) - x;
    }
    template <class T>
    vec3<T> reflect(const vec3<T>& p) const
    {
        const T c(twice_position);
        switch (axis) {
        case 0: return {c - p.x, p.y, p.z};
        case 1: return {p.x, c - p.y, p.z};
        default: return {p.x, p.y, c - p.z};
        }
    }
    // Built by value per axis (no reference into the vector), so the coordinates stay in registers.
    template <class T>
    vec3<T> fold(const vec3<T>& p) const
    {
        const T c(twice_position);
        if (above) {
            switch (axis) {
            case 0: return {min(p.x, c - p.x), p.y, p.z};
            case 1: return {p.x, min(p.y, c - p.y), p.z};
            default: return {p.x, p.y, min(p.z, c - p.z)};
            }
        }
        switch (axis) {
        case 0: return {max(p.x, c - p.x), p.y, p.z};
        case 1: return {p.x, max(p.y, c - p.y), p.z};
        default: return {p.x, p.y, max(p.z, c - p.z)};
        }
    }
    template <class T>
    vec3<T> reflect_direction(const vec3<T>& w) const
    {
        switch (axis) {
        case 0: return {-w.x, w.y, w.z};
        case 1: return {w.x, -w.y, w.z};
        default: return {w.x, w.y, -w.z};
        }
    }

    // GLSL: one vec4 (axis, above ? 1 : 0, 2 position, position); the fold is one min or max of
    // the indexed coordinate, as above.
    static constexpr std::string_view glsl_name = "krs_axis_mirror";
    static constexpr std::string_view glsl_source = R"(float krs_axis_mirror_signed_distance(vec3 p, vec4 m) {
    float x = p[int(m.x)];
    return m.y != 0.0 ? x - m.w : m.w - x;
}
vec3 krs_axis_mirror_reflect(vec3 p, vec4 m) {
    int a = int(m.x);
    p[a] = m.z - p[a];
    return p;
}
vec3 krs_axis_mirror_fold(vec3 p, vec4 m) {
    int a = int(m.x);
    float r = m.z - p[a];
    p[a] = m.y != 0.0 ? min(p[a], r) : max(p[a], r);
    return p;
}
vec3 krs_axis_mirror_reflect_direction(vec3 w, vec4 m) {
    int a = int(m.x);
    w[a] = -w[a];
    return w;
}
)";
    std::array<float, 4> glsl_parameters() const { return {float(axis), above ? 1.0f : 0.0f, twice_position, position()}; }
};

// What a KRS level's mirror must offer (both `mirror` and `axis_mirror` do).
template <class M>
concept mirror_kind = requires(const M& m, const vec3f& pf, const vec3d& pd) {
    { m.normal } -> std::convertible_to<vec3f>;
    { m.offset } -> std::convertible_to<float>;
    { m.fold(pf) } -> std::same_as<vec3f>;
    { m.fold(pd) } -> std::same_as<vec3d>;
    { m.reflect(pf) } -> std::same_as<vec3f>;
    { m.signed_distance(pd) } -> std::same_as<double>;
    { m.reflect_direction(pf) } -> std::same_as<vec3f>;
    { m.checked() } -> std::same_as<M>;
};

} // namespace krs

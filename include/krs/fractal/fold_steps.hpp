#pragma once
// Fold steps: the maps one iteration of a kaleidoscopic IFS (krs/fractal/kifs.hpp) is made of.
//
// A *fold step* is a type with `template <class T> vec3<T> apply(const vec3<T>&) const` and
// `double scale() const`, whose map stretches no distance by more than scale():
// |apply(a) - apply(b)| <= scale() |a - b|. Reflections, abs and sort folds and rotations are
// isometries or folds (scale 1); `scale_about` scales by its factor. A `fold_program<Steps...>`
// applies its steps in order and its scale is their product: the bound the KIFS field divides by
// (kifs.hpp says why that keeps the field 1-Lipschitz). `plane_fold` built from a `krs::mirror`
// folds exactly as Algorithm 1 does, so a KRS is the special case of identity-or-reflect folds.
//
// Every step is a template over the lane type; the steps are the same for every lane, so a packet
// runs the loop in lockstep and only min/max/abs/select act per lane. Each step carries its GLSL
// (the program emits one function per iteration).

#include "krs/core/rounding.hpp"
#include "krs/core/validate.hpp"
#include "krs/field.hpp"
#include "krs/mirror.hpp"

#include <algorithm>
#include <array>
#include <bit>
#include <cmath>
#include <concepts>
#include <cstdint>
#include <limits>
#include <numbers>
#include <string>
#include <string_view>
#include <tuple>
#include <utility>
#include <vector>

namespace krs {

template <class S>
concept fold_step = requires(const S& s, const vec3f& pf, const vec3d& pd) {
    { s.apply(pf) } -> std::same_as<vec3f>;
    { s.apply(pd) } -> std::same_as<vec3d>;
    { s.scale() } -> std::convertible_to<double>;
};

// Whether a fold step counts as a fold for colouring (krs/fractal/kifs_colour.hpp): a step that
// moves only some points (a reflection taken from one side: abs_fold, plane_fold, sort_fold say
// `static constexpr bool counts_as_fold = true`). scale_about, rotate_step and translate_step move
// every point and are not counted.
template <class S>
inline constexpr bool counts_as_fold = requires { requires S::counts_as_fold; };

// Axis masks for abs_fold.
inline constexpr unsigned fold_x = 1u, fold_y = 2u, fold_z = 4u, fold_xyz = 7u;

// p_i <- |p_i| on the chosen axes: the reflections on the coordinate planes x_i = 0, taken only
// from the negative side.
template <unsigned Axes = fold_xyz>
struct abs_fold {
    static_assert(Axes != 0 && Axes <= fold_xyz, "abs_fold: choose axes from fold_x | fold_y | fold_z");
    template <class T>
    vec3<T> apply(const vec3<T>& p) const
    {
        return {(Axes & fold_x) ? abs(p.x) : p.x, (Axes & fold_y) ? abs(p.y) : p.y,
                (Axes & fold_z) ? abs(p.z) : p.z};
    }
    double scale() const { return 1.0; }
    static constexpr bool counts_as_fold = true; // for colouring (krs/fractal/kifs_colour.hpp)

    // GLSL (krs/glsl/emitter.hpp): one vec4, 1 on the folded axes, 0 elsewhere.
    static constexpr std::string_view glsl_name = "krs_abs_fold";
    static constexpr std::string_view glsl_source = R"(vec3 krs_abs_fold_apply(vec3 p, vec4 m) {
    return vec3(m.x != 0.0 ? abs(p.x) : p.x, m.y != 0.0 ? abs(p.y) : p.y, m.z != 0.0 ? abs(p.z) : p.z);
}
)";
    std::array<float, 4> glsl_parameters() const
    {
        return {(Axes & fold_x) ? 1.0f : 0.0f, (Axes & fold_y) ? 1.0f : 0.0f, (Axes & fold_z) ? 1.0f : 0.0f, 0.0f};
    }
};

// Reflection on the plane normal . p = offset, applied only to points on its negative side: the
// result always has normal . p >= offset. Built from a krs::mirror it keeps the mirror's
// negative side instead, bit for bit Algorithm 1's fold (the KRS special case).
struct plane_fold {
    vec3f normal{1, 0, 0};
    float offset = 0.0f;

    plane_fold() = default;
    plane_fold(const vec3f& normal_, float offset_)
    {
        const oriented_plane p = oriented_plane::checked("plane_fold", normal_, offset_);
        normal = p.normal;
        offset = p.offset;
    }
    // The fold of a KRS level: keeps m's negative side (the stored plane is m with both signs
    // flipped, which is exact in floating point).
    explicit plane_fold(const mirror& m) : normal(-m.normal), offset(-m.offset) {}

    // Keeping the negative side of (-n, -c) is keeping the positive side of (n, c): the mirror's
    // fold on the flipped plane (negation is exact).
    template <class T>
    vec3<T> apply(const vec3<T>& p) const
    {
        return fold_positive_side(-normal, -offset, p);
    }
    double scale() const { return 1.0; }
    static constexpr bool counts_as_fold = true;

    // GLSL: one vec4 (normal, offset); the arithmetic spelled out in the C++ order.
    static constexpr std::string_view glsl_name = "krs_plane_fold";
    static constexpr std::string_view glsl_source = R"(vec3 krs_plane_fold_apply(vec3 p, vec4 m) {
    float twice_e = ((-2.0 * m.x) * p.x + 2.0 * m.w) - (2.0 * m.y) * p.y - (2.0 * m.z) * p.z;
    return p + m.xyz * max(twice_e, 0.0);
}
)";
    std::array<float, 4> glsl_parameters() const { return {normal.x, normal.y, normal.z, offset}; }
};

// Sorts the coordinates so that x >= y >= z: three conditional swaps, each the fold on a plane
// x_i = x_j (the permutation fold of the Menger sponge). Sorting is 1-Lipschitz.
struct sort_fold {
    template <class T>
    vec3<T> apply(const vec3<T>& p) const
    {
        const T a = max(p.x, p.y), b = min(p.x, p.y);
        const T c = min(a, p.z);
        return {max(a, p.z), max(b, c), min(b, c)};
    }
    double scale() const { return 1.0; }
    static constexpr bool counts_as_fold = true;

    // GLSL: no parameters.
    static constexpr std::string_view glsl_name = "krs_sort_fold";
    static constexpr std::string_view glsl_source = R"(vec3 krs_sort_fold_apply(vec3 p) {
    float a = max(p.x, p.y);
    float b = min(p.x, p.y);
    float c = min(a, p.z);
    return vec3(max(a, p.z), max(b, c), min(b, c));
}
)";
    std::array<float, 0> glsl_parameters() const { return {}; }
};

// Rotation by `angle` radians about `axis` (right-handed), an isometry.
struct rotate_step {
    rotate_step() = default;
    rotate_step(const vec3f& axis, float angle)
    {
        const vec3d u(require_direction("rotate_step.axis", axis));
        const double a = require_magnitude("rotate_step.angle", angle);
        const double c = std::cos(a), s = std::sin(a), t = 1.0 - c;
        const double m[3][3] = {{t * u.x * u.x + c, t * u.x * u.y - s * u.z, t * u.x * u.z + s * u.y},
                                {t * u.x * u.y + s * u.z, t * u.y * u.y + c, t * u.y * u.z - s * u.x},
                                {t * u.x * u.z - s * u.y, t * u.y * u.z + s * u.x, t * u.z * u.z + c}};
        for (int i = 0; i < 3; ++i) rows_[i] = vec3f{float(m[i][0]), float(m[i][1]), float(m[i][2])};
    }
    template <class T>
    vec3<T> apply(const vec3<T>& p) const
    {
        return {dot(vec3<T>(rows_[0]), p), dot(vec3<T>(rows_[1]), p), dot(vec3<T>(rows_[2]), p)};
    }
    // Rounding the matrix to float can make it stretch by a few ulps; the scale covers that.
    double scale() const { return 1.0 + 1e-6; }

    // GLSL: three vec4s, the matrix rows (w unused).
    static constexpr std::string_view glsl_name = "krs_rotate_step";
    static constexpr std::string_view glsl_source = R"(vec3 krs_rotate_step_apply(vec3 p, vec4 a, vec4 b, vec4 c) {
    return vec3(a.x * p.x + a.y * p.y + a.z * p.z, b.x * p.x + b.y * p.y + b.z * p.z, c.x * p.x + c.y * p.y + c.z * p.z);
}
)";
    std::array<float, 12> glsl_parameters() const
    {
        return {rows_[0].x, rows_[0].y, rows_[0].z, 0.0f, rows_[1].x, rows_[1].y,
                rows_[1].z, 0.0f,       rows_[2].x, rows_[2].y, rows_[2].z, 0.0f};
    }

private:
    vec3f rows_[3] = {{1, 0, 0}, {0, 1, 0}, {0, 0, 1}};
};

// p <- factor (p - center) + center: the copy of the whole that lies at `center`'s side, blown up
// to full size. factor > 1 is what makes the IFS contract (copies smaller than the whole).
struct scale_about {
    scale_about() = default;
    scale_about(float factor, const vec3f& center)
        : factor_(require_positive_length("scale_about.factor", factor)),
          center_(require_magnitude("scale_about.center", center))
    {
        const vec3d shift = vec3d(center_) * (double(factor_) - 1.0);
        shift_ = vec3f{float(shift.x), float(shift.y), float(shift.z)};
    }
    float factor() const { return factor_; }
    const vec3f& center() const { return center_; }
    template <class T>
    vec3<T> apply(const vec3<T>& p) const
    {
        return p * T(factor_) - vec3<T>(shift_);
    }
    double scale() const { return double(factor_); }

    // GLSL: one vec4 ((factor - 1) center, factor).
    static constexpr std::string_view glsl_name = "krs_scale_about";
    static constexpr std::string_view glsl_source = R"(vec3 krs_scale_about_apply(vec3 p, vec4 m) { return p * m.w - m.xyz; }
)";
    std::array<float, 4> glsl_parameters() const { return {shift_.x, shift_.y, shift_.z, factor_}; }

private:
    float factor_ = 1.0f;
    vec3f center_{};
    vec3f shift_{}; // (factor - 1) center
};

// p <- p + offset.
struct translate_step {
    vec3f offset{};
    translate_step() = default;
    explicit translate_step(const vec3f& offset_) : offset(require_magnitude("translate_step.offset", offset_)) {}
    template <class T>
    vec3<T> apply(const vec3<T>& p) const
    {
        return p + vec3<T>(offset);
    }
    double scale() const { return 1.0; }

    // GLSL: one vec4 (offset, 0).
    static constexpr std::string_view glsl_name = "krs_translate_step";
    static constexpr std::string_view glsl_source = R"(vec3 krs_translate_step_apply(vec3 p, vec4 m) { return p + m.xyz; }
)";
    std::array<float, 4> glsl_parameters() const { return {offset.x, offset.y, offset.z, 0.0f}; }
};

// The steps of one KIFS iteration, applied in order.
template <fold_step... Steps>
class fold_program {
public:
    fold_program() = default;
    explicit fold_program(Steps... steps) : steps_(std::move(steps)...) {}

    template <class T>
    vec3<T> apply(vec3<T> p) const
    {
        std::apply([&](const auto&... step) { ((p = step.apply(p)), ...); }, steps_);
        return p;
    }
    // The most the program stretches a distance: the product of its steps' scales.
    double scale() const
    {
        return std::apply([](const auto&... step) { return (1.0 * ... * double(step.scale())); }, steps_);
    }
    const std::tuple<Steps...>& steps() const { return steps_; }

    // GLSL (krs/glsl/emitter.hpp): `vec3 NAME_program(vec3 p)` for the KIFS called NAME, one
    // iteration: each step's _apply from its own GLSL, in order, its parameters in the data.
    template <class Out>
    void glsl_emit(Out& out, const std::string& name) const
    {
        glsl_emit_program(out, name, false);
    }

    // GLSL for colouring (krs/fractal/kifs_colour.hpp): `vec3 NAME_program_folds(vec3 p, float i,
    // inout float fold_count, inout float last_fold)`, one iteration as NAME_program that also
    // counts each fold step (counts_as_fold) that moved the point, as kifs_colour does.
    template <class Out>
    void glsl_emit_counted(Out& out, const std::string& name) const
    {
        glsl_emit_program(out, name, true);
    }

private:
    // Both functions above, from one walk over the steps. The steps' parameters go to the data
    // once per shader: they are recorded under a key made of the steps' GLSL types and their
    // values' bits, and a second emission of the same program (its distance and its colouring,
    // under two names) reads the first one's (the data is constant, so equal values may be shared).
    template <class Out>
    void glsl_emit_program(Out& out, const std::string& name, bool counted) const
    {
        std::string key = "kifs program";
        std::apply(
            [&](const auto&... step) {
                (
                    [&](const auto& s) {
                        using S = std::remove_cvref_t<decltype(s)>;
                        key += " " + std::string(S::glsl_name);
                        if constexpr (requires { s.glsl_parameters(); })
                            for (const float v : s.glsl_parameters()) key += ":" + std::to_string(std::bit_cast<std::uint32_t>(v));
                    }(step),
                    ...);
            },
            steps_);
        const auto* recorded = out.recorded_kernels(key);
        std::vector<std::size_t> at;
        std::string program = counted ? "vec3 " + name + "_program_folds(vec3 p, float i, inout float fold_count, inout float last_fold) {\n    vec3 q;\n"
                                      : "vec3 " + name + "_program(vec3 p) {\n";
        std::size_t index = 0;
        std::apply(
            [&](const auto&... step) {
                (
                    [&](const auto& s) {
                        using S = std::remove_cvref_t<decltype(s)>;
                        out.template library<S>();
                        const std::size_t k = index++;
                        at.push_back(recorded ? recorded->at[k] : out.parameters(s, name + " step " + std::to_string(k)));
                        const std::string call = std::string(S::glsl_name) + "_apply(p" + out.template arguments<S>(at.back()) + ")";
                        if (counted && counts_as_fold<S>)
                            program += "    q = " + call + ";\n"
                                       "    if (any(notEqual(q, p))) { fold_count += 1.0; last_fold = i; }\n"
                                       "    p = q;\n";
                        else
                            program += "    p = " + call + ";\n";
                    }(step),
                    ...);
            },
            steps_);
        if (!recorded) out.record_kernels(key, {std::move(at), {}});
        out.function(program + "    return p;\n}\n");
    }

    std::tuple<Steps...> steps_;
};

} // namespace krs

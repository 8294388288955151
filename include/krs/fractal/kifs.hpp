#pragma once
// Kaleidoscopic IFS (KIFS): fold programs iterated over a kernel.
//
// A naive self-similar union (a square with four squares three times smaller on its sides, each
// with four more, ...) costs one kernel per copy. Folding space first (reflect the point into the
// wedge that holds one copy) gives the same distance with one kernel per level, and because the
// copy is the whole fractal scaled, the levels become a loop (Bellaard, "Kaleidoscopic IFS
// fractals"):
//
//     d = inf, s = 1
//     repeat N times:  d = min(d, k(p) / s);  p = program(p);  s *= program.scale()
//     d = min(d, k(p) / s)
//
// A *fold step* is a type with `template <class T> vec3<T> apply(const vec3<T>&) const` and
// `double scale() const`, whose map stretches no distance by more than scale():
// |apply(a) - apply(b)| <= scale() |a - b|. Reflections, abs and sort folds and rotations are
// isometries or folds (scale 1); `scale_about` scales by its factor. A `fold_program<Steps...>`
// applies its steps in order and its scale is their product, so after i iterations the point has
// been stretched by at most s_i = scale()^i and k(p_i) / s_i is 1-Lipschitz: the field is the
// minimum of 1-Lipschitz functions and never overestimates the distance to its own zero set, with
// no declared bound needed. (Where a kernel crosses a fold plane the field describes the clipped
// geometry, as a KRS does.)
//
// `kifs_taps::every_iteration` takes the kernel at every level (the square-on-square fractal: the
// union of all generations); `kifs_taps::last_iteration` only at the end (Menger sponge,
// Sierpinski tetrahedron: only the finest generation). A KRS (sequence.hpp) is the special case
// of identity-or-reflect folds with scale 1: `plane_fold` built from a `krs::mirror` folds exactly
// as Algorithm 1 does.
//
// Every step is a template over the lane type; the steps are the same for every lane, so a packet
// runs the loop in lockstep and only min/max/abs/select act per lane.

#include "krs/core/rounding.hpp"
#include "krs/core/validate.hpp"
#include "krs/field.hpp"
#include "krs/kernels/box.hpp"
#include "krs/kernels/capsule.hpp"
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
                        at.push_back(recorded ? recorded->first[k] : out.parameters(s, name + " step " + std::to_string(k)));
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
        if (!recorded) out.record_kernels(key, std::move(at), {});
        out.function(program + "    return p;\n}\n");
    }

    std::tuple<Steps...> steps_;
};

enum class kifs_taps {
    every_iteration, // the kernel at every level: the union of all generations
    last_iteration,  // the kernel only after the last iteration: the finest generation
};

template <class P>
concept kifs_program = fold_step<P>;

// How far a KIFS carries the query points. The magnitude policy (krs/core/validate.hpp) promises
// finite float distances for |p| <= max_magnitude, but each iteration magnifies the point by up to
// scale(), so a deep program could carry such points past 1.8e19, where the kernel's squared
// length overflows, and on to inf and inf - inf = NaN in the next fold. A step that stretches no
// distance by more than s maps |p| <= B into |step(p)| <= s B + |step(0)| (triangle inequality),
// which bounds every intermediate point from the steps' own scale() and their image of the origin,
// for any program. kifs accepts `iterations` only while that bound stays <= kifs_escape_limit =
// 1e19: the library's kernels (sphere, box, capsule, plane, tetrahedron) square at most that
// (1e38 < 3.4e38). A kernel that overflows sooner says so with `double input_reach() const` (a
// torus capsule multiplies the point by its curvature), and the bound must stay within that too.
inline constexpr double kifs_escape_limit = 1e19;

namespace detail {
template <class Step>
double escape_step(const Step& step, double bound)
{
    return double(step.scale()) * bound + length(step.apply(vec3d{0, 0, 0}));
}
// The largest |p| the program meets over `iterations` iterations from |p| <= max_magnitude (the
// loop stops once it passes the limit).
template <kifs_program Program>
double kifs_escape_bound(const Program& program, int iterations)
{
    double bound = double(max_magnitude), worst = bound;
    for (int i = 0; i < iterations && worst <= kifs_escape_limit; ++i) {
        if constexpr (requires { program.steps(); })
            std::apply([&](const auto&... step) { ((bound = escape_step(step, bound), worst = std::max(worst, bound)), ...); },
                       program.steps());
        else
            worst = std::max(worst, bound = escape_step(program, bound));
    }
    return worst;
}
// The largest |p| the kernel's float distance is certain to stay finite at.
template <class Kernel>
double kernel_input_reach(const Kernel& kernel)
{
    if constexpr (requires { { kernel.input_reach() } -> std::convertible_to<double>; })
        return std::min(kifs_escape_limit, double(kernel.input_reach()));
    else
        return kifs_escape_limit;
}
template <kifs_program Program>
void require_kifs_escape(std::string_view name, const Program& program, int iterations, double reach)
{
    if (!(kifs_escape_bound(program, iterations) <= reach)) {
        int most = 0; // the most iterations whose escape bound stays within reach
        while (most < iterations && kifs_escape_bound(program, most + 1) <= reach) ++most;
        throw invalid_parameter(name,
                                "must be in [0, " + std::to_string(most) +
                                    "] for this program and kernel: more iterations magnify points within 1e9 of the "
                                    "origin past " + detail::to_text(reach) + ", where the float distance overflows",
                                std::to_string(iterations));
    }
}
} // namespace detail

template <kifs_program Program, field Kernel>
class kifs {
public:
    static constexpr int max_iterations = 40;

    kifs(Program program, Kernel kernel, int iterations, kifs_taps taps = kifs_taps::every_iteration)
        : program_(std::move(program)), kernel_(std::move(kernel)), taps_(taps)
    {
        if (iterations < 0 || iterations > max_iterations)
            throw invalid_parameter("kifs.iterations", "must be in [0, " + std::to_string(max_iterations) + "]",
                                    std::to_string(iterations));
        const double s = program_.scale();
        if (!std::isfinite(s) || !(s >= 1.0))
            throw invalid_parameter("kifs.program.scale",
                                    "must be finite and >= 1 (each copy no larger than the whole: the IFS must contract "
                                    "or, for a KRS, keep its size)",
                                    detail::to_text(s));
        detail::require_kifs_escape("kifs.iterations", program_, iterations, detail::kernel_input_reach(kernel_));
        iterations_ = iterations;
        for (int i = 0; i <= iterations; ++i) {
            // Rounding 1/s^i up would overestimate the distance.
            const float f = float_at_most(std::pow(s, -double(i)));
            if (!(f > 0.0f))
                throw invalid_parameter("kifs.iterations", "program.scale()^iterations overflows float",
                                        std::to_string(iterations));
            inverse_scale_[std::size_t(i)] = f;
        }
    }

    int iterations() const { return iterations_; }
    kifs_taps taps() const { return taps_; }
    const Program& program() const { return program_; }
    const Kernel& kernel() const { return kernel_; }

    template <class T>
    T distance(const vec3<T>& x) const
    {
        vec3<T> p = x;
        T d(std::numeric_limits<scalar_t<T>>::infinity());
        const bool every = taps_ == kifs_taps::every_iteration;
        for (int i = 0; i < iterations_; ++i) {
            if (every) d = min(d, kernel_.distance(p) * T(inverse_scale_[std::size_t(i)]));
            p = program_.apply(p);
        }
        return min(d, kernel_.distance(p) * T(inverse_scale_[std::size_t(iterations_)]));
    }

    // GLSL (krs/glsl/emitter.hpp): the kernel as NAME_kernel, one iteration of the program as
    // NAME_program, and the loop of distance() with the iteration count and the taps fixed in the
    // code (nothing unrolled). The parameters are the table 1 / s^i, i = 0 .. max_iterations, four
    // per vec4 (zeros past `iterations`), so the GPU multiplies by the same rounded-down floats as
    // the C++.
    static constexpr std::string_view glsl_name = "krs_kifs";
    static constexpr std::string_view glsl_source = "";
    static constexpr std::size_t glsl_table_size = (max_iterations + 1 + 3) / 4 * 4; // whole vec4s
    std::array<float, glsl_table_size> glsl_parameters() const
    {
        std::array<float, glsl_table_size> table{};
        for (int i = 0; i <= iterations_; ++i) table[std::size_t(i)] = inverse_scale_[std::size_t(i)];
        return table;
    }
    template <class Out>
    void glsl_emit(Out& out, const std::string& name) const
    {
        out.field(kernel_, name + "_kernel");
        program_.glsl_emit(out, name);
        const std::size_t table = out.parameters(*this, name + " 1 / scale^i, i = 0.." + std::to_string(iterations_));
        const int n = iterations_;
        const auto inverse_scale = [&](const std::string& i) {
            return out.data_name() + "[" + std::to_string(table) + " + (" + i + " >> 2)][" + i + " & 3]";
        };
        const std::string last = out.at(table + std::size_t(n / 4)) + "." + "xyzw"[n % 4];
        const std::string kernel = name + "_kernel(p)";
        std::string body = "float " + name + "(vec3 p) {\n";
        if (taps_ == kifs_taps::every_iteration) {
            body += "    float d = 3.0e38;\n";
            if (n > 0)
                body += "    for (int i = 0; i < " + std::to_string(n) + "; ++i) {\n"
                        "        d = min(d, " + kernel + " * " + inverse_scale("i") + ");\n"
                        "        p = " + name + "_program(p);\n    }\n";
            body += "    return min(d, " + kernel + " * " + last + ");\n}\n";
        } else {
            if (n > 0) body += "    for (int i = 0; i < " + std::to_string(n) + "; ++i) p = " + name + "_program(p);\n";
            body += "    return " + kernel + " * " + last + ";\n}\n";
        }
        out.function(body);
    }

private:
    Program program_;
    Kernel kernel_;
    kifs_taps taps_ = kifs_taps::every_iteration;
    int iterations_ = 0;
    std::array<float, max_iterations + 1> inverse_scale_{};
};

// A regular tetrahedron with vertices (1,1,1), (-1,-1,1), (1,-1,-1), (-1,1,-1): the maximum of its
// four face planes' signed distances, a 1-Lipschitz bound (exact inside and near faces, an
// underestimate near edges and vertices).
struct tetrahedron {
    template <class T>
    T distance(const vec3<T>& p) const
    {
        const T a = max(-p.x - p.y - p.z, p.x + p.y - p.z);
        const T b = max(-p.x + p.y + p.z, p.x - p.y + p.z);
        return (max(a, b) - T(1)) * T(std::numbers::inv_sqrt3_v<float>);
    }

    // GLSL: no parameters (0.57735026 is inv_sqrt3_v<float>).
    static constexpr std::string_view glsl_name = "krs_tetrahedron";
    static constexpr std::string_view glsl_source = R"(float krs_tetrahedron_distance(vec3 p) {
    float a = max(-p.x - p.y - p.z, p.x + p.y - p.z);
    float b = max(-p.x + p.y + p.z, p.x - p.y + p.z);
    return (max(a, b) - 1.0) * 0.57735026;
}
)";
    std::array<float, 0> glsl_parameters() const { return {}; }
};

// ---- presets -------------------------------------------------------------------------------------

namespace detail {
inline void require_iterations(std::string_view name, int iterations, int most)
{
    if (iterations < 0 || iterations > most)
        throw invalid_parameter(name, "must be in [0, " + std::to_string(most) + "]", std::to_string(iterations));
}
inline float require_contracting(std::string_view name, float scale)
{
    require_finite(name, scale);
    if (!(scale > 1.0f)) throw invalid_parameter(name, "must be > 1 (the IFS must contract)", detail::to_text(scale));
    return scale;
}
} // namespace detail

// The document's square-on-square fractal: a 2x2 square with a square three times smaller on each
// side, recursively. Two folds take the point into the wedge |y| <= x (the copy on +x), then the
// copy at (4/3, 0) is scaled up about (2, 0) (p' = 3 p - (4, 0), as in the document). The
// squares are boxes of half extents (1, 1, thickness): a relief plate in 3D, exact as the 2D
// field on z = 0 when thickness >= 1. (The document turns the lower wedge with a rotation; this
// reflects it instead, which gives the same distance because every copy is mirror-symmetric.)
using square_program = fold_program<plane_fold, plane_fold, scale_about>;
using square_fractal = kifs<square_program, box>;
inline square_fractal make_square_fractal(int iterations, float thickness = 0.25f)
{
    detail::require_iterations("square_fractal.iterations", iterations, 20);
    require_positive_length("square_fractal.thickness", thickness);
    return {square_program(plane_fold({1, -1, 0}, 0), plane_fold({1, 1, 0}, 0), scale_about(3, {2, 0, 0})),
            box({0, 0, 0}, {1, 1, thickness}), iterations, kifs_taps::every_iteration};
}

// Its 3D analogue: a cube with a cube three times smaller on each of its six faces. abs and two
// folds take the point into the region x >= |y|, |z| (the copy on +x).
using cube_program = fold_program<abs_fold<fold_xyz>, plane_fold, plane_fold, scale_about>;
using cube_fractal = kifs<cube_program, box>;
inline cube_fractal make_cube_fractal(int iterations)
{
    detail::require_iterations("cube_fractal.iterations", iterations, 20);
    return {cube_program(abs_fold<fold_xyz>{}, plane_fold({1, -1, 0}, 0), plane_fold({1, 0, -1}, 0),
                         scale_about(3, {2, 0, 0})),
            box({0, 0, 0}, {1, 1, 1}), iterations, kifs_taps::every_iteration};
}

// Menger sponge in [-1, 1]^3: abs and sort take the point into x >= y >= z >= 0, where the two
// sub-cubes left are the corner (2/3, 2/3, 2/3) and the edge cube (2/3, 2/3, 0). Scaling by 3
// about (1, 1, 0) blows the edge cube up; the fold on z = 1 maps the corner cube onto it (the
// usual "z -= 2 above z = 1" translation, made a reflection: same distance since the cube is
// symmetric, but continuous, so the field stays 1-Lipschitz).
using menger_program = fold_program<abs_fold<fold_xyz>, sort_fold, scale_about, plane_fold>;
using menger_sponge = kifs<menger_program, box>;
inline menger_sponge make_menger_sponge(int iterations)
{
    detail::require_iterations("menger_sponge.iterations", iterations, 20);
    return {menger_program(abs_fold<fold_xyz>{}, sort_fold{}, scale_about(3, {1, 1, 0}), plane_fold({0, 0, -1}, -1)),
            box({0, 0, 0}, {1, 1, 1}), iterations, kifs_taps::last_iteration};
}

// Sierpinski tetrahedron on the vertices of `tetrahedron`: three folds (planes x + y = 0,
// x + z = 0, y + z = 0) take the point to the copy at vertex (1, 1, 1), scaled up about it.
// scale 2 gives the classic gasket; larger scales leave gaps, scales in (1, 2) overlap.
using sierpinski_program = fold_program<plane_fold, plane_fold, plane_fold, scale_about>;
using sierpinski_tetrahedron = kifs<sierpinski_program, tetrahedron>;
inline sierpinski_tetrahedron make_sierpinski_tetrahedron(int iterations, float scale = 2.0f)
{
    detail::require_iterations("sierpinski_tetrahedron.iterations", iterations, 30);
    detail::require_contracting("sierpinski_tetrahedron.scale", scale);
    if (!(scale <= max_magnitude))
        throw invalid_parameter("sierpinski_tetrahedron.scale", "must be in (1, 1e9]", detail::to_text(scale));
    sierpinski_program program(plane_fold({1, 1, 0}, 0), plane_fold({1, 0, 1}, 0), plane_fold({0, 1, 1}, 0),
                               scale_about(scale, {1, 1, 1}));
    // Named here: the iteration limit depends on this preset's scale.
    detail::require_kifs_escape("sierpinski_tetrahedron.iterations", program, iterations, kifs_escape_limit);
    return {program, tetrahedron{}, iterations, kifs_taps::last_iteration};
}

// Koch curve from (-1, 0, 0) to (1, 0, 0) in the xy plane, as a tube of world radius
// `tube_radius`. abs folds the left half onto the right; the fold on the line through (1/3, 0) at
// 60 degrees maps the rising segment onto the last one, [1/3, 1], which scaling by 3 about (1, 0)
// blows up to the whole.
using koch_program = fold_program<abs_fold<fold_x>, plane_fold, scale_about>;
using koch_curve = kifs<koch_program, capsule>;
inline koch_curve make_koch_curve(int iterations, float tube_radius = 0.01f)
{
    detail::require_iterations("koch_curve.iterations", iterations, 12);
    require_positive_length("koch_curve.tube_radius", tube_radius);
    const float c = std::numbers::sqrt3_v<float> * 0.5f; // normal (cos -30, sin -30) of the 60-degree line
    // The capsule is the last generation blown up 3^iterations times: its radius must obey the
    // magnitude policy too.
    const double blown_up = double(tube_radius) * std::pow(3.0, iterations);
    if (!(blown_up <= double(max_magnitude)))
        throw invalid_parameter("koch_curve.tube_radius", "times 3^iterations must be <= 1e9",
                                detail::to_text(tube_radius) + " * 3^" + std::to_string(iterations));
    const float radius = tube_radius * float(std::pow(3.0, iterations));
    return {koch_program(abs_fold<fold_x>{}, plane_fold({c, -0.5f, 0}, c / 3.0f), scale_about(3, {1, 0, 0})),
            capsule({-1, 0, 0}, {1, 0, 0}, radius), iterations, kifs_taps::last_iteration};
}

} // namespace krs

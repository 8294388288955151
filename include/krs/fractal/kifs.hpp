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
// The program is a fold_program of fold steps (krs/fractal/fold_steps.hpp), each of which stretches
// no distance by more than its scale(), so after i iterations the point has been stretched by at
// most s_i = scale()^i and k(p_i) / s_i is 1-Lipschitz: the field is the minimum of 1-Lipschitz
// functions and never overestimates the distance to its own zero set, with no declared bound
// needed. (Where a kernel crosses a fold plane the field describes the clipped geometry, as a KRS
// does.)
//
// `kifs_taps::every_iteration` takes the kernel at every level (the square-on-square fractal: the
// union of all generations); `kifs_taps::last_iteration` only at the end (Menger sponge,
// Sierpinski tetrahedron: only the finest generation). A KRS (sequence.hpp) is the special case
// of identity-or-reflect folds with scale 1. The steps are the same for every lane, so a packet
// runs the loop in lockstep.
//
// The presets (square-on-square, cube, Menger sponge, Sierpinski tetrahedron, Koch curve) are in
// krs/fractal/kifs_presets.hpp.

#include "krs/core/rounding.hpp"
#include "krs/core/validate.hpp"
#include "krs/field.hpp"
#include "krs/fractal/fold_steps.hpp"

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

} // namespace krs

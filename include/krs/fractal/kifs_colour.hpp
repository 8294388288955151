#pragma once
// Colouring a KIFS: orbit traps and iteration counts along the fold program's orbit.
//
// `kifs::distance` is the shape; a renderer colours it by what happens to the point on its way
// through the fold program (what Fragmentarium and Mandelbulber users expect of a fractal). For a
// query point x the *orbit* is p_0 = x, p_i = program(p_{i-1}), stopping at the kifs's iteration
// count N or at the first point outside the escape radius R, whichever comes first:
//
//   escape_iteration  the index e of the first p_e with |p_e| > R, or N + 1 when no orbit point
//                     is outside (the point stays in the fractal's neighbourhood)
//   trap[k]           min over the orbit p_0 .. p_min(e, N) of traps[k].distance(p_i)
//                     (krs/fractal/orbit_trap.hpp); a point on trap k has trap[k] = 0
//   fold_count        how many fold steps (abs_fold, plane_fold, sort_fold: the steps that say
//                     `counts_as_fold`) moved the point, over iterations 1 .. min(e, N)
//   last_fold         the iteration (1-based) of the last such fold, 0 when none moved it
//
// The orbit includes the escaping point, so every trap value is finite. Counts are floats (the
// lane type): one template for scalar and packet lanes, each lane stopping at its own escape.
//
// Why a separate call: `kifs::distance` is what a sphere tracer runs at every step and must stay
// as it is; colour is wanted once per hit. `kifs_colour(fractal, p, colouring)` runs the same
// steps one by one (bit for bit the points `distance` folds, since fold_program::apply only
// composes them) and reads nothing `distance` computes, so the distance path costs nothing more
// (it is the same code as before this header existed).
//
// GLSL: `kifs_colour_glsl{fractal, colouring}` given to `emitter::add_shading(request, NAME)`
// writes
//     krs_kifs_colour NAME(vec3 p)   // struct krs_kifs_colour { vec4 trap; float escape_iteration,
//                                    //     fold_count, last_fold; }
// with the same loop; unused trap components hold the largest float, as in C++.

#include "krs/fractal/fold_steps.hpp"
#include "krs/fractal/kifs.hpp"
#include "krs/fractal/orbit_trap.hpp"

#include <array>
#include <cstddef>
#include <initializer_list>
#include <limits>
#include <string>
#include <tuple>

namespace krs {

// What kifs_colour looks for: up to four traps and the escape radius. Immutable and checked when
// built (docs/design.md#rule-6, docs/design.md#rule-7): kifs_colour, called per hit, checks nothing.
class kifs_colouring {
public:
    static constexpr std::size_t max_traps = 4;

    // One point trap at the origin, escape radius 100.
    kifs_colouring() = default;
    // R <= 1e9: R^2 (the escape test compares |p|^2) stays far below float's overflow.
    kifs_colouring(std::initializer_list<orbit_trap> traps, float escape_radius = 100.0f)
    {
        if (traps.size() < 1 || traps.size() > max_traps)
            throw invalid_parameter("kifs_colouring.traps", "must hold 1 to 4 traps", std::to_string(traps.size()));
        escape_radius_ = require_positive_length("kifs_colouring.escape_radius", escape_radius);
        trap_count_ = 0;
        for (const orbit_trap& t : traps) traps_[trap_count_++] = t;
    }

    std::size_t trap_count() const { return trap_count_; }
    const orbit_trap& trap(std::size_t k) const { return traps_[k]; }
    float escape_radius() const { return escape_radius_; }

private:
    std::array<orbit_trap, max_traps> traps_{};
    std::size_t trap_count_ = 1;
    float escape_radius_ = 100.0f;
};

template <class T>
struct kifs_colour_result {
    std::array<T, kifs_colouring::max_traps> trap; // unused traps: the largest float
    T escape_iteration;
    T fold_count;
    T last_fold;
};

namespace detail {
template <class T>
mask_t<T> moved(const vec3<T>& before, const vec3<T>& after)
{
    return (after.x != before.x) || (after.y != before.y) || (after.z != before.z);
}
// One step of the orbit for the lanes in `live`: counts it when it is a fold that moved the point.
template <class T, class Step>
void colour_step(const Step& step, vec3<T>& p, const mask_t<T>& live, const T& iteration, T& fold_count, T& last_fold)
{
    const vec3<T> q = step.apply(p);
    if constexpr (counts_as_fold<Step>) {
        const mask_t<T> counted = live && moved(p, q);
        fold_count = select(counted, fold_count + T(1), fold_count);
        last_fold = select(counted, iteration, last_fold);
    }
    p = q;
}
} // namespace detail

// The orbit of x through fractal's program with its traps and counts (see the top of this file).
template <class T, kifs_program Program, field Kernel>
kifs_colour_result<T> kifs_colour(const kifs<Program, Kernel>& fractal, const vec3<T>& x, const kifs_colouring& c)
{
    using S = scalar_t<T>;
    kifs_colour_result<T> r;
    const T none(std::numeric_limits<float>::max());
    for (std::size_t k = 0; k < c.max_traps; ++k) r.trap[k] = k < c.trap_count() ? T(c.trap(k).distance(x)) : none;
    const int n = fractal.iterations();
    const T escape_r2 = T(S(c.escape_radius()) * S(c.escape_radius()));
    const auto outside = [&](const vec3<T>& p) { return (p.x * p.x + p.y * p.y) + p.z * p.z > escape_r2; };
    mask_t<T> live = !outside(x);
    r.escape_iteration = select(live, T(S(n + 1)), T(0));
    r.fold_count = T(0);
    r.last_fold = T(0);
    vec3<T> p = x;
    for (int i = 1; i <= n && any(live); ++i) {
        const T iteration = T(S(i)); // exact: i <= 40
        if constexpr (requires { fractal.program().steps(); })
            std::apply([&](const auto&... step) { (detail::colour_step(step, p, live, iteration, r.fold_count, r.last_fold), ...); },
                       fractal.program().steps());
        else
            detail::colour_step(fractal.program(), p, live, iteration, r.fold_count, r.last_fold);
        for (std::size_t k = 0; k < c.trap_count(); ++k) r.trap[k] = select(live, min(r.trap[k], c.trap(k).distance(p)), r.trap[k]);
        const mask_t<T> escaped = live && outside(p);
        r.escape_iteration = select(escaped, iteration, r.escape_iteration);
        live = live && !escaped;
    }
    return r;
}

// The GLSL request for kifs_colour (see the top of this file): give it to emitter::add_shading.
template <class Fractal>
struct kifs_colour_glsl {
    Fractal fractal;
    kifs_colouring colouring;

    // The struct, once per shader, then `krs_kifs_colour NAME(vec3 p)`: the program's iteration
    // with its fold counts (fold_program::glsl_emit_counted, as NAME_program_folds; it reads the
    // steps' parameters the distance put in the data, or appends them when the distance is not
    // emitted, so this function may be emitted without it), the
    // traps after every iteration, the escape test as the C++ writes it.
    template <class Out>
    void glsl_shading(Out& out, const std::string& name, const std::string&) const
    {
        out.library_text("krs_kifs_colour", R"(struct krs_kifs_colour {
    vec4 trap;              // min over the orbit of each trap's distance (unused: the largest float)
    float escape_iteration; // first orbit index outside the escape radius, iterations + 1 when none
    float fold_count;       // folds that moved the point
    float last_fold;        // iteration of the last fold that moved it, 0 when none
};
)");
        out.template library<orbit_trap>();
        std::size_t trap_at[kifs_colouring::max_traps] = {};
        for (std::size_t k = 0; k < colouring.trap_count(); ++k)
            trap_at[k] = out.parameters(colouring.trap(k), name + " trap " + std::to_string(k) + " (" +
                                                               std::string(orbit_trap_kind_name(colouring.trap(k).kind())) + ")");
        const auto traps = [&](const std::string& indent) {
            std::string text;
            for (std::size_t k = 0; k < colouring.trap_count(); ++k) {
                const std::string c = std::string("c.trap.") + "xyzw"[k];
                text += indent + c + " = min(" + c + ", krs_orbit_trap_distance(p" +
                        out.template arguments<orbit_trap>(trap_at[k]) + "));\n";
            }
            return text;
        };
        fractal.program().glsl_emit_counted(out, name);
        const float r = colouring.escape_radius();
        const std::string outside = "(p.x * p.x + p.y * p.y) + p.z * p.z > escape_r2";
        const int n = fractal.iterations();
        out.function("krs_kifs_colour " + name + "(vec3 p) {\n    krs_kifs_colour c;\n    c.trap = vec4(" +
                     out.literal(std::numeric_limits<float>::max()) + ");\n" + traps("    ") +
                     "    c.fold_count = 0.0;\n    c.last_fold = 0.0;\n    const float escape_r2 = " + out.literal(r * r) +
                     ";\n    c.escape_iteration = " + outside + " ? 0.0 : " + out.literal(float(n + 1)) +
                     ";\n    if (c.escape_iteration != 0.0) {\n        for (int i = 1; i <= " + std::to_string(n) +
                     "; ++i) {\n            p = " + name + "_program_folds(p, float(i), c.fold_count, c.last_fold);\n" +
                     traps("            ") + "            if (" + outside +
                     ") {\n                c.escape_iteration = float(i);\n                break;\n            }\n        }\n    }\n"
                     "    return c;\n}\n");
    }
};

template <class Fractal>
kifs_colour_glsl(Fractal, kifs_colouring) -> kifs_colour_glsl<Fractal>;

} // namespace krs

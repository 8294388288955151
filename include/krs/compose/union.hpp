#pragma once
// Union of several fields, and a tracer that keeps one free distance per component
// (paper section 5.1: combining KRSs hides each one's symmetry).
//
// union_of<F...> is the compile-time union: its distance is min_i d_i(x). A minimum of
// 1-Lipschitz underestimates is a 1-Lipschitz underestimate of the distance to the union of the
// zero sets, so the union is itself a field.
//
// union_trace marches a ray through the union evaluating only the components that could be the
// nearest. Each component i remembers the value d_i it had at the ray parameter t_i where it was
// last evaluated. Because d_i is 1-Lipschitz along the (unit-speed) ray,
//     d_i(t) >= d_i(t_i) - (t - t_i)                                     (*)
// so that lower bound is a free distance: while it exceeds the smallest exact value found at the
// current t, component i cannot be the minimum and is not evaluated. Every step advances by the
// exact minimum over the components (each either evaluated at t, or proven by (*) to be larger),
// which is the step plain sphere tracing of the union takes: the hits are those of the union
// field, at a fraction of the evaluations where components' silhouettes do not overlap.

#include "krs/field.hpp"
#include "krs/trace/sphere_trace.hpp"

#include <array>
#include <cstddef>
#include <limits>
#include <string>
#include <tuple>
#include <utility>

namespace krs {

template <field... F>
class union_of {
    static_assert(sizeof...(F) > 0, "krs::union_of needs at least one component");

public:
    static constexpr std::size_t size = sizeof...(F);

    union_of() = default;
    explicit union_of(F... components) : components_(std::move(components)...) {}

    template <std::size_t I>
    const auto& component() const
    {
        return std::get<I>(components_);
    }

    template <class T>
    T distance(const vec3<T>& p) const
    {
        return std::apply([&](const auto&... c) { return minimum(c.distance(p)...); }, components_);
    }

    // Distance of component i (a runtime index, for tracers that pick components per step).
    template <class T>
    T component_distance(std::size_t i, const vec3<T>& p) const
    {
        return component_distance_impl(i, p, std::make_index_sequence<size>{});
    }

    // GLSL (krs/glsl/emitter.hpp): component i as NAME_i, NAME their minimum in this order.
    template <class Out>
    void glsl_emit(Out& out, const std::string& name) const
    {
        std::size_t i = 0;
        std::apply([&](const auto&... c) { (out.field(c, name + "_" + std::to_string(i++)), ...); }, components_);
        out.minimum_of_parts(name, size);
    }

private:
    template <class T, class... Rest>
    static T minimum(const T& first, const Rest&... rest)
    {
        T m = first;
        ((m = min(m, rest)), ...);
        return m;
    }
    template <class T, std::size_t... I>
    T component_distance_impl(std::size_t i, const vec3<T>& p, std::index_sequence<I...>) const
    {
        T d(std::numeric_limits<scalar_t<T>>::infinity());
        ((i == I ? (d = std::get<I>(components_).distance(p), true) : false) || ...);
        return d;
    }

    std::tuple<F...> components_;
};

// Per-component counters reported by union_trace, next to the usual hit.
template <std::floating_point S, std::size_t N>
struct union_hit : hit<S> {
    std::array<int, N> component_evaluations{}; // evaluations of each component
    int nearest = -1;                            // component that was hit (-1 on a miss)
};

// Sphere traces the union, skipping components by their free distances (*). `evaluations` in the
// result counts component evaluations (a plain trace of the union costs steps * N).
template <std::floating_point S, field... F>
union_hit<S, sizeof...(F)> union_trace(const union_of<F...>& u, const ray<S>& r, const trace_options& options)
{
    constexpr std::size_t N = sizeof...(F);
    options.validate();
    union_hit<S, N> h;
    h.t = std::numeric_limits<S>::infinity();
    if (!(is_finite(r.origin) && is_finite(r.direction) && length_squared(r.direction) > S(0))) {
        h.invalid = true;
        return h;
    }
    std::array<S, N> value;   // d_i at t_i
    std::array<S, N> at;      // t_i
    std::array<bool, N> known{};
    // Float rounding in the evaluations can make a computed d_i(t) fall a few ulps under (*);
    // a relative slack keeps the skip decision on the safe side.
    constexpr S slack = S(64) * std::numeric_limits<S>::epsilon();
    S t = S(options.min_distance);
    const S t_max = S(options.max_distance);
    for (int step = 0; step < options.max_steps; ++step) {
        const vec3<S> p = point_at(r, t);
        // Pass 1: evaluate the component with the smallest lower bound, then every component whose
        // lower bound is still below the best exact value found.
        S best = std::numeric_limits<S>::infinity();
        std::size_t best_index = 0;
        std::array<bool, N> fresh{};
        for (;;) {
            std::size_t candidate = N;
            S candidate_bound = best;
            for (std::size_t i = 0; i < N; ++i) {
                if (fresh[i]) continue;
                const S bound = known[i] ? value[i] - (t - at[i]) - slack * (std::abs(t) + std::abs(value[i]) + S(1))
                                         : -std::numeric_limits<S>::infinity();
                if (bound < candidate_bound) {
                    candidate_bound = bound;
                    candidate = i;
                }
            }
            if (candidate == N) break; // every unevaluated component is proven >= best
            const S d = u.component_distance(candidate, p);
            ++h.evaluations;
            ++h.component_evaluations[candidate];
            fresh[candidate] = known[candidate] = true;
            value[candidate] = d;
            at[candidate] = t;
            if (!(d == d)) { // NaN: end this ray as a miss, as sphere_trace does
                best = d;
                break;
            }
            if (d < best) {
                best = d;
                best_index = candidate;
            }
        }
        ++h.steps;
        if (!(best == best)) return h;
        if (best < options.threshold(t)) {
            h.found = true;
            h.t = t;
            h.nearest = int(best_index);
            return h;
        }
        t += best;
        if (!(t <= t_max)) return h;
    }
    return h;
}

} // namespace krs

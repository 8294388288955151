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
// field, at a fraction of the evaluations where components' silhouettes do not overlap. The step
// itself is the tracers' march_advance, and the tracer takes a ray or a packet (below).

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

// Per-component counters reported by union_trace, next to the usual hit: ints for one ray, float
// lanes for a packet (as hit's own counters, count_t).
template <class T, std::size_t N>
struct union_hit : hit<T> {
    std::array<count_t<T>, N> component_evaluations{}; // evaluations of each component
    count_t<T> nearest = count_t<T>(-1);                // component that was hit (-1 on a miss)
};

// Sphere traces the union, skipping components by their free distances (*), for one ray (T =
// float, double) or a packet (T = packet_f). `evaluations` in the result counts component
// evaluations (a plain trace of the union costs steps * N).
//
// The march is the tracers' own (docs/design.md#rule-1): each step finds the union's distance at
// the sample, min_i d_i, from the components that (*) cannot rule out, and hands it to
// march_advance, so the stops (threshold, max_distance, max_steps, a NaN) are sphere_trace's. The
// tracer always takes plain steps: options.omega is not used, since a relaxed step that fails its
// overlap test moves t back, where (*) would need |t - t_i|.
//
// In a packet every lane keeps its own free distances and picks its own components in the scalar
// order: each round, every lane names its next candidate (the unevaluated component with the
// smallest lower bound below the lane's best value), each component named by some lane is
// evaluated once for the packet and counted for the lanes that named it. A lane thus evaluates
// the components the scalar call would, in the same order, and gets the same hit, steps and counts.
template <class T, field... F>
union_hit<T, sizeof...(F)> union_trace(const union_of<F...>& u, const ray<T>& r, const trace_options& options)
{
    using S = scalar_t<T>;
    constexpr std::size_t N = sizeof...(F);
    constexpr S infinity = std::numeric_limits<S>::infinity();
    options.validate();
    trace_options plain = options;
    plain.omega = 1.0f;
    march_state<T> m = start_march(r, T(options.min_distance), T(options.max_distance), plain);
    std::array<T, N> value{}; // d_i at t_i
    std::array<T, N> at{};    // t_i
    std::array<mask_t<T>, N> known;
    known.fill(m.active && !m.active);
    // Float rounding in the evaluations can make a computed d_i(t) fall a few ulps under (*);
    // a relative slack keeps the skip decision on the safe side.
    constexpr S slack = S(64) * std::numeric_limits<S>::epsilon();
    std::array<count_t<T>, N> component_evaluations{};
    count_t<T> evaluations{};
    T nearest(-1);
    while (any(m.active)) {
        const vec3<T> p = point_at(m.r, m.t);
        const T t = m.t;
        T best(infinity), best_index(0);
        std::array<mask_t<T>, N> fresh;
        fresh.fill(m.active && !m.active);
        mask_t<T> pending = m.active; // lanes that may still name a candidate this step
        for (;;) {
            // Each lane's candidate: the unevaluated component with the smallest lower bound
            // below its best exact value (the first such on ties); N where none is left.
            T candidate = T(S(N)), candidate_bound = best;
            for (std::size_t i = 0; i < N; ++i) {
                const T bound = select(known[i], value[i] - (t - at[i]) - T(slack) * (abs(t) + abs(value[i]) + T(1)),
                                       T(-infinity));
                const mask_t<T> take = pending && !fresh[i] && bound < candidate_bound;
                candidate_bound = select(take, bound, candidate_bound);
                candidate = select(take, T(S(i)), candidate);
            }
            pending = pending && candidate < T(S(N)); // none left: every other component is >= best
            if (!any(pending)) break;
            for (std::size_t i = 0; i < N; ++i) {
                const mask_t<T> named = pending && candidate == T(S(i));
                if (!any(named)) continue;
                const T d = u.component_distance(i, p);
                evaluations += detail::count_if<T>(named);
                component_evaluations[i] += detail::count_if<T>(named);
                fresh[i] = fresh[i] || named;
                known[i] = known[i] || named;
                value[i] = select(named, d, value[i]);
                at[i] = select(named, t, at[i]);
                // NaN: the lane's step ends with it (march_advance ends the lane as a miss).
                const mask_t<T> nan = named && !(d == d);
                const mask_t<T> better = named && d < best;
                best = select(nan || better, d, best);
                best_index = select(better, T(S(i)), best_index);
                pending = pending && !nan;
            }
        }
        const mask_t<T> was_found = m.result.found;
        march_advance(m, best, plain);
        nearest = select(m.result.found && !was_found, best_index, nearest);
    }
    union_hit<T, N> h;
    static_cast<hit<T>&>(h) = m.result;
    h.evaluations = evaluations; // components evaluated, not steps
    h.component_evaluations = component_evaluations;
    if constexpr (std::floating_point<T>)
        h.nearest = int(nearest);
    else
        h.nearest = nearest;
    return h;
}

} // namespace krs

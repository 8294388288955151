#pragma once
// Surface normals of any field.
//
// A field that knows its normal (a kernel, or a KRS: kernel normal carried back through the
// recorded reflections, section 6.1) is asked for it. Any other field gets the gradient by the
// four-point tetrahedral difference: with k in {(1,-1,-1), (-1,-1,1), (-1,1,-1), (1,1,1)},
//     grad f(p) ~ sum_k k f(p + h k) / (4 h),
// which costs four evaluations instead of six. The vertices' third moments do not cancel, so the
// error is first order, about h times the surface curvature (central differences are O(h^2)); h
// should be about the hit threshold, so the normal sees the geometry the tracer saw.

#include "krs/field.hpp"

namespace krs {

template <field F, std::floating_point S>
vec3<S> gradient_normal(const F& f, const vec3<S>& p, S h)
{
    const vec3<S> k0{1, -1, -1}, k1{-1, -1, 1}, k2{-1, 1, -1}, k3{1, 1, 1};
    const vec3<S> g = k0 * f.distance(p + k0 * h) + k1 * f.distance(p + k1 * h) + k2 * f.distance(p + k2 * h) +
                      k3 * f.distance(p + k3 * h);
    const S len = length(g);
    return len > S(0) ? g / len : vec3<S>{0, 0, 1};
}

// The field's own normal where it has one, else the tetrahedral gradient with step h.
template <field F, std::floating_point S>
vec3<S> surface_normal(const F& f, const vec3<S>& p, S h)
{
    if constexpr (requires { { f.normal(p) } -> std::same_as<vec3<S>>; })
        return f.normal(p);
    else
        return gradient_normal(f, p, h);
}

} // namespace krs

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
//
// Far from the origin a small h falls below the spacing of the coordinates: p + h k rounds back
// to p, or to a neighbour ulps away, and the differences are rounding noise (a union of spheres
// at x = 3000 with h = 1e-4 gave the normal (0, 1, 0) for (0.6, 0.8, 0)). So the step is at least
// about 32 ulps of the largest coordinate: rounding p + h k then misplaces a sample by at most a
// 64th of the step (about 1.5% of the normal), while the stencil's first-order error, h times
// the curvature, stays small for any curvature that float resolves there (the same union's
// normals: within 0.006 at x = 1000 and 3000; 256 ulps doubled the truncation error at 3000).

#include "krs/field.hpp"

#include <algorithm>
#include <cmath>
#include <limits>

namespace krs {

template <field F, std::floating_point S>
vec3<S> gradient_normal(const F& f, const vec3<S>& p, S h)
{
    const vec3<S> k0{1, -1, -1}, k1{-1, -1, 1}, k2{-1, 1, -1}, k3{1, 1, 1};
    const S largest = std::max({std::abs(p.x), std::abs(p.y), std::abs(p.z)});
    h = std::max(h, S(32) * std::numeric_limits<S>::epsilon() * largest);
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

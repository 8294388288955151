#pragma once
// Collision queries on any field (paper section 6.4): the distance and normal at a point, and
// the closest surface point.
//
// closest_point walks q <- q - d(q) n(q). For an exact distance (a sphere, a separated KRS) the
// first step lands on the surface: the nearest surface point is exactly d away along -grad d.
// For an underestimate (a clipped KRS, a warped field) each step moves by at most the true
// distance, so the walk approaches the surface without jumping through it, and is repeated until
// |d| falls below the tolerance or the iteration budget ends (then `converged` is false and the
// last point is returned, never NaN).

#include "krs/core/validate.hpp"
#include "krs/field.hpp"
#include "krs/shade/normal.hpp"

#include <cmath>

namespace krs {

struct contact {
    vec3f point{};      // the query point
    float distance = 0; // signed distance bound there (negative inside)
    vec3f normal{};     // outward unit normal of the nearest surface
};

// Distance and normal at p; h is the finite-difference step for fields without their own normal.
template <field F>
contact contact_at(const F& f, const vec3f& p, float h = 1e-4f)
{
    require_finite("contact_at.point", p);
    require_positive("contact_at.h", h);
    return {p, f.distance(p), surface_normal(f, p, h)};
}

struct closest_point_options {
    int max_iterations = 32;  // in [1, 1000]
    float tolerance = 1e-5f;  // |d| at which the point counts as on the surface, > 0
    float h = 1e-4f;          // finite-difference step for the normal, > 0

    const closest_point_options& validate() const
    {
        if (max_iterations < 1 || max_iterations > 1000)
            throw invalid_parameter("closest_point_options.max_iterations", "must be in [1, 1000]",
                                    std::to_string(max_iterations));
        require_positive("closest_point_options.tolerance", tolerance);
        require_positive("closest_point_options.h", h);
        return *this;
    }
};

template <std::floating_point S>
struct closest_point_result {
    vec3<S> point{};
    S distance = 0;      // field value at `point`
    int iterations = 0;
    bool converged = false;
};

template <field F, std::floating_point S>
closest_point_result<S> closest_point(const F& f, const vec3<S>& p, const closest_point_options& o = {})
{
    o.validate();
    require_finite("closest_point.point", vec3d(p));
    closest_point_result<S> r;
    r.point = p;
    r.distance = f.distance(p);
    for (; r.iterations < o.max_iterations; ++r.iterations) {
        if (!std::isfinite(r.distance)) break;
        if (std::abs(r.distance) <= S(o.tolerance)) {
            r.converged = true;
            break;
        }
        const vec3<S> n = surface_normal(f, r.point, S(o.h));
        const vec3<S> next = r.point - n * r.distance;
        const S d = f.distance(next);
        if (!std::isfinite(d)) break;
        r.point = next;
        r.distance = d;
    }
    if (!r.converged && std::isfinite(r.distance) && std::abs(r.distance) <= S(o.tolerance)) r.converged = true;
    return r;
}

} // namespace krs

#pragma once
// Bounding spheres: what every kernel and field reports so tracers, tile prepasses, expansion
// exports and tests can tell where the geometry is. An unbounded kernel (a half-space) reports an
// infinite radius.

#include "krs/core/rounding.hpp"
#include "krs/core/vec3.hpp"

#include <algorithm>
#include <cmath>
#include <limits>

namespace krs {

struct bounding_sphere {
    vec3f center{};
    float radius = 0.0f;

    static bounding_sphere unbounded() { return {{0, 0, 0}, std::numeric_limits<float>::infinity()}; }
    bool is_bounded() const { return radius < std::numeric_limits<float>::infinity(); }
};

// A float sphere that holds the double sphere (c, r): the radius grows by the distance the
// center moved when rounded to float, then by a few ulps, so float storage never shrinks it.
inline bounding_sphere bound_around(const vec3d& c, double r)
{
    const vec3f cf{static_cast<float>(c.x), static_cast<float>(c.y), static_cast<float>(c.z)};
    const double grown = r + length(vec3d(cf) - c);
    return {cf, static_cast<float>(grown) * (1.0f + 4e-7f) + 1e-30f};
}

// Smallest sphere of the form "around a's or b's center or between them" holding both: exact for
// two spheres, which is all the enclosing step of an expansion needs.
inline bounding_sphere enclose(const bounding_sphere& a, const bounding_sphere& b)
{
    if (!a.is_bounded() || !b.is_bounded()) return bounding_sphere::unbounded();
    const vec3d ca(a.center), cb(b.center);
    const double dist = length(cb - ca);
    if (dist + b.radius <= a.radius) return a;
    if (dist + a.radius <= b.radius) return b;
    const double r = 0.5 * (dist + a.radius + b.radius);
    return bound_around(ca + (cb - ca) * ((r - a.radius) / dist), r);
}

// Axis-aligned bounding boxes: a flat scene (a grid of 2^n copies, a forest) fills a small part
// of its bounding sphere, so a ray clipped to the box skips the empty space above and below it
// (krs/trace/box_clip.hpp). Every kernel reports its own (`bound_box()`): exact where it has a
// closed form (a ring standing upright is 0.4 deep where its sphere's box is 2.4), and never
// larger than its sphere's box on any axis. An unbounded field reports infinite extents.
struct bounding_box {
    vec3f lo{}, hi{};

    static bounding_box unbounded()
    {
        constexpr float inf = std::numeric_limits<float>::infinity();
        return {{-inf, -inf, -inf}, {inf, inf, inf}};
    }
    bool is_bounded() const
    {
        constexpr float inf = std::numeric_limits<float>::infinity();
        return lo.x > -inf && lo.y > -inf && lo.z > -inf && hi.x < inf && hi.y < inf && hi.z < inf;
    }
};

// The float box holding the double box [lo, hi]: each bound rounded outward.
inline bounding_box box_around(const vec3d& lo, const vec3d& hi)
{
    return {{float_at_most(lo.x), float_at_most(lo.y), float_at_most(lo.z)},
            {float_at_least(hi.x), float_at_least(hi.y), float_at_least(hi.z)}};
}

// The float box holding the double box [lo, hi] grown by `pad` on every side: a kernel's exact
// box is computed in double from its float parameters, and the pad covers what the float field
// may differ from that exact solid by (its stored unit vectors are unit to about 1e-7).
inline bounding_box box_around(const vec3d& lo, const vec3d& hi, double pad)
{
    const vec3d g{pad, pad, pad};
    return box_around(lo - g, hi + g);
}

// The common part of two boxes that both hold a set: it holds the set too.
inline bounding_box intersect(const bounding_box& a, const bounding_box& b)
{
    return {{std::max(a.lo.x, b.lo.x), std::max(a.lo.y, b.lo.y), std::max(a.lo.z, b.lo.z)},
            {std::min(a.hi.x, b.hi.x), std::min(a.hi.y, b.hi.y), std::min(a.hi.z, b.hi.z)}};
}

// The box around a bounding sphere (infinite for an unbounded one).
inline bounding_box box_around(const bounding_sphere& b)
{
    if (!b.is_bounded()) return bounding_box::unbounded();
    const vec3d c(b.center), r{b.radius, b.radius, b.radius};
    return box_around(c - r, c + r);
}

} // namespace krs

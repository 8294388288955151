#pragma once
// Lambert shading with a sphere-traced hard shadow (paper sections 6.1 and 6.5).
//
// The shadow ray leaves the hit point along the light direction from a point lifted off the
// surface by twice the hit threshold (the tracer stopped within one threshold of the surface, so
// a smaller lift would re-hit the same surface), and uses that same threshold as its own: its
// occluders are judged at the resolution the primary ray was.

#include "krs/shade/normal.hpp"
#include "krs/trace/sphere_trace.hpp"

namespace krs {

struct directional_light {
    vec3f direction{0, 0, 1}; // unit, from the surface toward the light
    vec3f color{1, 1, 1};

    directional_light() = default;
    directional_light(const vec3f& toward_light, const vec3f& color_)
        : direction(require_direction("light.direction", toward_light)), color(require_finite("light.color", color_))
    {
    }
};

// 1 where the light is visible from p, 0 where the field blocks it.
template <field F, std::floating_point S>
S hard_shadow(const F& f, const vec3<S>& p, const vec3<S>& n, const vec3<S>& to_light, S threshold, S max_distance)
{
    const trace_options o = inherited_threshold_options(float(max_distance));
    const ray<S> r{p + n * (S(2) * threshold), to_light};
    return sphere_trace(f, r, S(0), S(o.max_distance), o, S(float(threshold))).found ? S(0) : S(1);
}

struct lambert_material {
    vec3f albedo{0.8f, 0.8f, 0.8f};
    float ambient = 0.15f; // fraction of the light that reaches shadowed and back-facing surfaces
};

// Radiance leaving the hit point toward the viewer: albedo * (ambient + max(n . l, 0) * shadow).
template <field F, std::floating_point S>
vec3<S> shade_lambert(const F& f, const vec3<S>& p, const vec3<S>& n, const directional_light& light,
                      const lambert_material& material, S threshold, S shadow_distance)
{
    const vec3<S> l(light.direction);
    const S cosine = dot(n, l);
    S direct = 0;
    if (cosine > S(0)) direct = cosine * hard_shadow(f, p, n, l, threshold, shadow_distance);
    const vec3<S> albedo(material.albedo), color(light.color);
    const S a = S(material.ambient);
    return {albedo.x * (a + direct * color.x), albedo.y * (a + direct * color.y), albedo.z * (a + direct * color.z)};
}

} // namespace krs

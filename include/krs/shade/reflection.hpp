#pragma once
// Reflection rays: the paper's section 6.5 ("sphere tracing can not only be performed for eye
// rays, but also for secondary rays. Shadows, reflections, ... can be implemented").
//
// A mirror-like surface at hit point p with unit normal n returns the light that arrives along
// the reflected direction r = d - 2 (n . d) n (krs::reflect_direction): the incoming direction d
// with its normal component reversed. The reflected ray is an ordinary ray<T>, traced by the very
// tracer that found p (sphere_trace on a scalar ray or on a packet, union_trace), so every field
// that can be seen can be seen in a mirror. Two details make it robust:
//
//   - The normal is first turned to face the incoming ray (a back face, or a field normal of the
//     other sign, would otherwise lift the origin into the surface). r itself does not depend on
//     the sign of n (it is quadratic in n).
//   - The origin is p lifted by `lift` (two hit thresholds, as krs::hard_shadow does) along that
//     normal: at p the field is below the threshold, so a march started there would stop at once
//     on the surface it leaves. Lifting along n (not along r) moves the origin off the surface by
//     the full amount even for grazing reflections.
//
// A glossy (partly reflecting) surface mixes: colour = mix(base, reflected, weight) (vec3.hpp), with
// weight = reflectivity at normal incidence raised towards 1 at grazing angles by Schlick's
// approximation of the Fresnel factor, F = F0 + (1 - F0) (1 - cos)^5. Weight 0 gives the base
// colour exactly (for finite colours), so a caller that skips the reflected ray at weight 0 draws
// what it drew without reflections.

#include "krs/core/validate.hpp"
#include "krs/core/vec3.hpp"
#include "krs/trace/ray.hpp"

namespace krs {

// The ray reflected at surface point p (unit normal n, either sign) of a ray arriving along the
// unit direction `incoming`, its origin lifted by `lift` off the surface on the incoming side.
template <class T>
ray<T> reflection_ray(const vec3<T>& p, const vec3<T>& n, const vec3<T>& incoming, const T& lift)
{
    const T facing = select(dot(n, incoming) > T(0), T(-1), T(1));
    const vec3<T> m = n * facing;
    // reflect_direction keeps unit length up to rounding; normalize so t stays a length.
    return {p + m * lift, normalize(reflect_direction(incoming, m))};
}

// Schlick's Fresnel weight for a reflectivity f0 at normal incidence, cos_incidence = |n . d|.
// f0 must lie in [0, 1] in every lane (a NaN or a reflectivity outside would give a weight outside
// [0, 1], a colour outside the two it mixes): refused, naming fresnel_schlick.f0. cos_incidence is
// clamped to [0, 1] (rounding can put |n . d| of unit vectors just above 1); the weight is then in
// [f0, 1]. Glossy colour: mix(base, reflected, weight) (vec3.hpp), base exactly at weight 0.
template <class T>
T fresnel_schlick(const T& cos_incidence, const T& f0)
{
    if (any(!(f0 >= T(0) && f0 <= T(1))))
        throw invalid_parameter("fresnel_schlick.f0", "must be in [0, 1] (the reflectivity at normal incidence) in every lane");
    const T c = T(1) - clamp(cos_incidence, T(0), T(1));
    const T c2 = c * c;
    return f0 + (T(1) - f0) * (c2 * c2 * c);
}

} // namespace krs

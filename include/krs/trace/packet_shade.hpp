#pragma once
// Shading for packets: a packet shadow query and a packet Lambert term, built from the same
// march step as every other ray, plus per-lane location on a KRS for normals and materials.
//
// Shadow rays leave each lane's hit point along the light direction, lifted off the surface by
// twice that lane's hit threshold, and use that threshold as their own (as `hard_shadow` does for
// one ray): the per-lane threshold rides in the march state's `threshold_bias`, so one packet
// holds shadow rays of hits at different depths.
//
// Locating the nearest kernel (for the normal, section 6.1, and the material) is done per lane
// with the scalar `locate`: it runs once per hit, not once per step, and the lanes of a packet
// generally end in different kernels, whose normals a packet could only compute by evaluating
// every kernel kind for every lane. The O(n) walk of the march is where packets pay off.

#include "krs/sequence.hpp"
#include "krs/trace/sphere_trace.hpp"

#include <array>

namespace krs {

// Mask of the lanes in `lanes` from which the light is visible: no surface within max_distance
// along to_light, judged with each lane's own threshold.
template <field F, class T>
mask_t<T> light_visible(const F& f, const vec3<T>& p, const vec3<T>& n, const vec3f& to_light, const T& threshold,
                        float max_distance, const mask_t<T>& lanes, int max_steps = 512)
{
    using S = scalar_t<T>;
    const trace_options o = inherited_threshold_options(max_distance, max_steps); // each lane's threshold
    const ray<T> r{p + n * (T(2) * threshold), vec3<T>(to_light)};
    const T start = select(lanes, T(0), T(std::numeric_limits<S>::infinity())); // others: rejected
    march_state<T> m = start_march(r, start, T(max_distance), o);
    m.threshold_bias = threshold;
    while (any(m.active)) march_step(f, m, o);
    return lanes && !m.result.found;
}

// Lambert with a hard shadow, lane by lane: albedo * (ambient + max(n . l, 0) * visible) * color.
// Lanes outside `lanes` return zero.
template <field F, class T>
vec3<T> shade_lambert_lanes(const F& f, const vec3<T>& p, const vec3<T>& n, const vec3f& to_light,
                            const vec3f& light_color, const vec3<T>& albedo, float ambient, const T& threshold,
                            float shadow_distance, const mask_t<T>& lanes)
{
    const T cosine = dot(n, vec3<T>(to_light));
    const mask_t<T> facing = lanes && (cosine > T(0));
    const mask_t<T> lit = light_visible(f, p, n, to_light, threshold, shadow_distance, facing);
    const T direct = select(lit, cosine, T(0));
    const T zero(0);
    const vec3<T> color(light_color);
    const T a(ambient);
    return {select(lanes, albedo.x * (a + direct * color.x), zero), select(lanes, albedo.y * (a + direct * color.y), zero),
            select(lanes, albedo.z * (a + direct * color.z), zero)};
}

// The nearest kernel of a KRS at each lane's point (scalar `locate` per lane, see above) and its
// world-space normal, gathered into lanes. Lanes outside `lanes` get location{} and normal (0,0,1).
template <mirror_kind M, kernel... Kinds, class T>
vec3<T> locate_lanes(const basic_sequence<M, Kinds...>& s, const vec3<T>& p, const mask_t<T>& lanes,
                     std::array<location<scalar_t<T>>, lane_count<T>>& where)
{
    using S = scalar_t<T>;
    constexpr std::size_t W = lane_count<T>;
    alignas(64) S px[W], py[W], pz[W], nx[W], ny[W], nz[W];
    bool use[W];
    if constexpr (std::floating_point<T>) {
        px[0] = p.x, py[0] = p.y, pz[0] = p.z, use[0] = lanes;
    } else {
        p.x.store_aligned(px), p.y.store_aligned(py), p.z.store_aligned(pz);
        alignas(64) bool m[W];
        lanes.store_aligned(m);
        for (std::size_t i = 0; i < W; ++i) use[i] = m[i];
    }
    for (std::size_t i = 0; i < W; ++i) {
        where[i] = location<S>{};
        vec3<S> n{0, 0, 1};
        if (use[i]) {
            where[i] = s.locate(vec3<S>{px[i], py[i], pz[i]});
            n = s.normal(where[i]);
        }
        nx[i] = n.x, ny[i] = n.y, nz[i] = n.z;
    }
    if constexpr (std::floating_point<T>)
        return {nx[0], ny[0], nz[0]};
    else
        return {T::load_aligned(nx), T::load_aligned(ny), T::load_aligned(nz)};
}

} // namespace krs

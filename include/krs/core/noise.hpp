#pragma once
// Procedural value noise over any lane type: the one source of pseudo-random smooth variation that
// texturing (krs/shade/texture.hpp), noise warps and hypertree perturbations share.
//
// value_noise is lattice value noise: a pseudo-random value in [-1, 1] at every integer point,
// blended with the quintic fade 6t^5 - 15t^4 + 10t^3 (C2, so lighting on displaced surfaces shows
// no lattice creases). Its derivative along an axis is at most max|fade'| * max|v_a - v_b| =
// (30/16) * 2 = 3.75, so |grad| <= 3.75 sqrt(3): `value_noise_gradient_bound`, which the noise
// warp uses to declare its Lipschitz bound. The lattice hash uses only float arithmetic (fract of
// products), so it is one template for float, double and packets; it is accurate for lattice
// coordinates of magnitude below about 2^16.

#include "krs/core/lanes.hpp"
#include "krs/core/rounding.hpp"
#include "krs/core/vec3.hpp"

#include <array>
#include <cmath>
#include <string_view>

namespace krs {

// max over space of |grad value_noise| (see above).
inline constexpr double value_noise_axis_slope_bound = 3.75;
inline constexpr double value_noise_gradient_bound = 3.75 * 1.7320508075688772;

namespace detail {
template <class T>
inline T floor_lane(const T& x)
{
    if constexpr (std::floating_point<T>)
        return std::floor(x);
    else
        return xsimd::floor(x);
}
template <class T>
inline T fract(const T& x)
{
    return x - floor_lane(x);
}
// Hash of a lattice point to [0, 1): scramble each coordinate by an irrational multiplier
// (`lattice_scramble`, a function of one axis), mix the three with a dot product against a shifted
// copy, and take the fractional part of a product (`lattice_mix`). The GLSL computes the same
// per corner, lattice_hash(i + d); value_noise computes each axis's scramble once for i and i + 1
// and mixes per corner, which gives the same numbers (the scramble is a function of the axis
// coordinate alone) with 6 floors instead of 24.
//
// Each product is rounded before it is added to or floored away (`unfused`): fused into an fma in
// one path and not in another, a product's last bit moves the fractional part, and with it the
// lattice value anywhere in [0, 1) (a packet lane against the scalar path, under g++'s default
// -ffp-contract=fast with FMA: 41% of 64 000 values were equal, the worst 1.98 apart).
template <class T>
struct lattice_scramble {
    T x, y, z;
};
template <class T>
inline lattice_scramble<T> scramble(const T& x, const T& y, const T& z)
{
    return {fract(unfused(x * T(0.1031f))), fract(unfused(y * T(0.11369f))), fract(unfused(z * T(0.13787f)))};
}
template <class T>
inline T lattice_mix(T a, T b, T c)
{
    const T m = unfused(a * (b + T(19.19f))) + unfused(b * (c + T(19.19f))) + unfused(c * (a + T(19.19f)));
    a = a + m, b = b + m, c = c + m;
    return fract(unfused((a + b) * c));
}
template <class T>
inline T lattice_hash(const T& x, const T& y, const T& z)
{
    const lattice_scramble<T> s = scramble(x, y, z);
    return lattice_mix(s.x, s.y, s.z);
}
template <class T>
inline T fade(const T& t)
{
    return t * t * t * (t * (t * T(6) - T(15)) + T(10));
}
} // namespace detail

// Value noise in [-1, 1] at p (any lane type).
template <class T>
T value_noise(const vec3<T>& p)
{
    using detail::lattice_mix;
    const T one(1);
    const T ix = detail::floor_lane(p.x), iy = detail::floor_lane(p.y), iz = detail::floor_lane(p.z);
    const T fx = detail::fade(p.x - ix), fy = detail::fade(p.y - iy), fz = detail::fade(p.z - iz);
    // The cell's two lattice coordinates per axis, scrambled once (i, then i + 1); ix + 0 would give
    // the same scramble as ix (it only turns -0 into +0, and fract(+-0 * k) is +0 either way).
    const detail::lattice_scramble<T> s0 = detail::scramble(ix, iy, iz), s1 = detail::scramble(ix + one, iy + one, iz + one);
    const T x00 = mix(lattice_mix(s0.x, s0.y, s0.z), lattice_mix(s1.x, s0.y, s0.z), fx);
    const T x10 = mix(lattice_mix(s0.x, s1.y, s0.z), lattice_mix(s1.x, s1.y, s0.z), fx);
    const T x01 = mix(lattice_mix(s0.x, s0.y, s1.z), lattice_mix(s1.x, s0.y, s1.z), fx);
    const T x11 = mix(lattice_mix(s0.x, s1.y, s1.z), lattice_mix(s1.x, s1.y, s1.z), fx);
    const T v = mix(mix(x00, x10, fy), mix(x01, x11, fy), fz);
    return v * T(2) - one;
}

// value_noise's GLSL (krs/glsl/emitter.hpp; what a warp or texture that samples noise lists in its
// glsl_needs): the same operations in the same order, mix written as the C++'s a + (b - a) t
// (GLSL's own mix may round differently). The hash takes the fractional part of products, so a GPU
// that fuses a product into an add (an fma) moves lattice values anywhere in [0, 1): llvmpipe does
// not; on such a GPU the noise is a different noise of the same kind, not the C++'s.
struct value_noise_glsl {
    static constexpr std::string_view glsl_name = "krs_value_noise";
    static constexpr std::string_view glsl_source = R"(float krs_lattice_hash(vec3 p) {
    float a = fract(p.x * 0.1031);
    float b = fract(p.y * 0.11369);
    float c = fract(p.z * 0.13787);
    float m = a * (b + 19.19) + b * (c + 19.19) + c * (a + 19.19);
    a = a + m;
    b = b + m;
    c = c + m;
    return fract((a + b) * c);
}
float krs_fade(float t) { return t * t * t * (t * (t * 6.0 - 15.0) + 10.0); }
float krs_lerp(float a, float b, float t) { return a + (b - a) * t; }
float krs_value_noise(vec3 p) {
    vec3 i = floor(p);
    float fx = krs_fade(p.x - i.x);
    float fy = krs_fade(p.y - i.y);
    float fz = krs_fade(p.z - i.z);
    float x00 = krs_lerp(krs_lattice_hash(i), krs_lattice_hash(i + vec3(1.0, 0.0, 0.0)), fx);
    float x10 = krs_lerp(krs_lattice_hash(i + vec3(0.0, 1.0, 0.0)), krs_lattice_hash(i + vec3(1.0, 1.0, 0.0)), fx);
    float x01 = krs_lerp(krs_lattice_hash(i + vec3(0.0, 0.0, 1.0)), krs_lattice_hash(i + vec3(1.0, 0.0, 1.0)), fx);
    float x11 = krs_lerp(krs_lattice_hash(i + vec3(0.0, 1.0, 1.0)), krs_lattice_hash(i + vec3(1.0, 1.0, 1.0)), fx);
    float v = krs_lerp(krs_lerp(x00, x10, fy), krs_lerp(x01, x11, fy), fz);
    return v * 2.0 - 1.0;
}
)";
    std::array<float, 0> glsl_parameters() const { return {}; }
};

} // namespace krs

#pragma once
// Texturing (paper section 6.2): procedural 3D noise, fractal sums of it, and triplanar projection.
//
// Where a kernel has a natural parametrization (torus_capsule::uv, in *kernel* space: every
// instance shares it) textures follow the kernel. Where kernels are too simple for that (infinite
// planes, whose visible detail is all made by the reflections) texturing every instance alike
// would repeat the symmetry, so textures are evaluated in *world* space instead: procedural 3D
// noise, or a 2D pattern projected along the three axes and blended by the normal (triplanar).
//
// value_noise is lattice value noise: a pseudo-random value in [-1, 1] at every integer point,
// blended with the quintic fade 6t^5 - 15t^4 + 10t^3 (C2, so lighting on displaced surfaces shows
// no lattice creases). Its derivative along an axis is at most max|fade'| * max|v_a - v_b| =
// (30/16) * 2 = 3.75, so |grad| <= 3.75 sqrt(3): `value_noise_gradient_bound`, which the noise
// warp uses to declare its Lipschitz bound. The lattice hash uses only float arithmetic (fract of
// products), so it is one template for float, double and packets; it is accurate for lattice
// coordinates of magnitude below about 2^16.

#include "krs/core/validate.hpp"

#include <algorithm>
#include <cmath>

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
// Hash of a lattice point to [0, 1): scramble each coordinate by an irrational multiplier, mix the
// three with a dot product against a shifted copy, and take the fractional part of a product.
template <class T>
inline T lattice_hash(const T& x, const T& y, const T& z)
{
    T a = fract(x * T(0.1031f)), b = fract(y * T(0.11369f)), c = fract(z * T(0.13787f));
    const T m = a * (b + T(19.19f)) + b * (c + T(19.19f)) + c * (a + T(19.19f));
    a = a + m, b = b + m, c = c + m;
    return fract((a + b) * c);
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
    using detail::lattice_hash;
    const T ix = detail::floor_lane(p.x), iy = detail::floor_lane(p.y), iz = detail::floor_lane(p.z);
    const T fx = detail::fade(p.x - ix), fy = detail::fade(p.y - iy), fz = detail::fade(p.z - iz);
    const T one(1);
    auto corner = [&](const T& dx, const T& dy, const T& dz) { return lattice_hash(ix + dx, iy + dy, iz + dz); };
    const T zero(0);
    const T x00 = mix(corner(zero, zero, zero), corner(one, zero, zero), fx);
    const T x10 = mix(corner(zero, one, zero), corner(one, one, zero), fx);
    const T x01 = mix(corner(zero, zero, one), corner(one, zero, one), fx);
    const T x11 = mix(corner(zero, one, one), corner(one, one, one), fx);
    const T v = mix(mix(x00, x10, fy), mix(x01, x11, fy), fz);
    return v * T(2) - one;
}

// Fractal sum of `octaves` noise layers, each at `lacunarity` times the frequency and `gain`
// times the amplitude of the previous; normalized by the amplitude sum so the result stays in
// [-1, 1].
struct fractal_noise {
    int octaves = 4;         // in [1, 16]
    float frequency = 1.0f;  // of the first octave, > 0
    float lacunarity = 2.0f; // in [1, 8]
    float gain = 0.5f;       // in (0, 1]

    fractal_noise() = default;
    fractal_noise(int octaves_, float frequency_, float lacunarity_ = 2.0f, float gain_ = 0.5f)
        : octaves(octaves_), frequency(frequency_), lacunarity(lacunarity_), gain(gain_)
    {
        validate();
    }
    void validate() const
    {
        if (octaves < 1 || octaves > 16)
            throw invalid_parameter("fractal_noise.octaves", "must be in [1, 16]", std::to_string(octaves));
        require_positive("fractal_noise.frequency", frequency);
        if (!(lacunarity >= 1.0f && lacunarity <= 8.0f))
            throw invalid_parameter("fractal_noise.lacunarity", "must be in [1, 8]", detail::to_text(lacunarity));
        if (!(gain > 0.0f && gain <= 1.0f))
            throw invalid_parameter("fractal_noise.gain", "must be in (0, 1]", detail::to_text(gain));
    }

    template <class T>
    T operator()(const vec3<T>& p) const
    {
        T sum(0);
        float amplitude = 1.0f, total = 0.0f, f = frequency;
        // The fields are public; a value set after construction is clamped to the validated
        // range here rather than trusted (no runaway loop, no division by zero).
        const int count = std::clamp(octaves, 1, 16);
        for (int o = 0; o < count; ++o) {
            // Each octave is offset so the lattice origins do not line up (a visible seam at 0).
            const T shift(static_cast<scalar_t<T>>(17.31f * float(o)));
            sum += T(amplitude) * value_noise(vec3<T>{p.x * T(f) + shift, p.y * T(f) - shift, p.z * T(f) + shift});
            total += amplitude;
            amplitude *= gain;
            f *= lacunarity;
        }
        return sum / T(total);
    }
};

// Triplanar projection: the 2D pattern `pattern(u, v)` projected along x (onto (y, z)), y (onto
// (z, x)) and z (onto (x, y)), blended with weights |n_axis|^sharpness (normalized), so faces see
// the projection most nearly square to them. Evaluated in world space (section 6.2).
template <class Pattern, class T>
T triplanar(const Pattern& pattern, const vec3<T>& p, const vec3<T>& n, float sharpness = 4.0f)
{
    require_positive("triplanar.sharpness", sharpness);
    const vec3<T> a = abs(n);
    T wx, wy, wz;
    if constexpr (std::floating_point<T>) {
        wx = std::pow(a.x, T(sharpness)), wy = std::pow(a.y, T(sharpness)), wz = std::pow(a.z, T(sharpness));
    } else {
        wx = xsimd::pow(a.x, T(sharpness)), wy = xsimd::pow(a.y, T(sharpness)), wz = xsimd::pow(a.z, T(sharpness));
    }
    const T total = wx + wy + wz;
    const T safe = select(total > T(0), total, T(1));
    const T sx = pattern(p.y, p.z), sy = pattern(p.z, p.x), sz = pattern(p.x, p.y);
    return select(total > T(0), (wx * sx + wy * sy + wz * sz) / safe, (sx + sy + sz) / T(3));
}

} // namespace krs

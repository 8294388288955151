#pragma once
// Texturing (paper section 6.2): procedural 3D noise, fractal sums of it, and triplanar projection.
//
// Where a kernel has a natural parametrization (torus_capsule::uv, in *kernel* space: every
// instance shares it) textures follow the kernel. Where kernels are too simple for that (infinite
// planes, whose visible detail is all made by the reflections) texturing every instance alike
// would repeat the symmetry, so textures are evaluated in *world* space instead: procedural 3D
// noise, or a 2D pattern projected along the three axes and blended by the normal (triplanar).
//
// Value noise itself lives in krs/core/noise.hpp.
//
// GLSL: fractal_noise and triplanar_projection carry their functions' GLSL (`glsl_source`), the C++
// line for line with the validated values baked in under their C++ names; emitter::add_shading
// writes them (fractal noise after the value noise it sums, once per shader).

#include "krs/core/noise.hpp"
#include "krs/core/validate.hpp"

#include <algorithm>
#include <cmath>
#include <string>
#include <string_view>

namespace krs {

// Fractal sum of `octaves` noise layers, each at `lacunarity` times the frequency and `gain`
// times the amplitude of the previous; normalized by the amplitude sum so the result stays in
// [-1, 1].
struct fractal_noise {
    int octaves = 4;         // in [1, 16]
    float frequency = 1.0f;  // of the first octave, in (0, 1e9]: with lacunarity^15 <= 8^15 the last
                             // octave's frequency times a coordinate within the policy stays finite
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
        require_positive_length("fractal_noise.frequency", frequency);
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

    // float NAME(vec3 p): operator()(p). The amplitude, total and frequency are float in the C++
    // too, so each octave's weights round alike.
    static constexpr std::string_view glsl_source = R"(float NAME(vec3 p) {
    const int octaves = OCTAVES;
    const float frequency = FREQUENCY;
    const float lacunarity = LACUNARITY;
    const float gain = GAIN;
    float sum = 0.0;
    float amplitude = 1.0;
    float total = 0.0;
    float f = frequency;
    for (int o = 0; o < octaves; ++o) {
        float shift = 17.31 * float(o);
        sum += amplitude * krs_value_noise(vec3(p.x * f + shift, p.y * f - shift, p.z * f + shift));
        total += amplitude;
        amplitude *= gain;
        f *= lacunarity;
    }
    return sum / total;
}
)";
    template <class Out>
    void glsl_shading(Out& out, const std::string& function, const std::string&) const
    {
        validate();
        out.template library<value_noise_glsl>();
        out.function(Out::fill(glsl_source, {{"NAME", function}, {"OCTAVES", std::to_string(octaves)},
                                             {"FREQUENCY", Out::literal(frequency)},
                                             {"LACUNARITY", Out::literal(lacunarity)}, {"GAIN", Out::literal(gain)}}));
    }
};

namespace detail {
inline void validate_triplanar(float sharpness) { require_positive("triplanar.sharpness", sharpness); }
} // namespace detail

// Triplanar projection: the 2D pattern `pattern(u, v)` projected along x (onto (y, z)), y (onto
// (z, x)) and z (onto (x, y)), blended with weights |n_axis|^sharpness (normalized), so faces see
// the projection most nearly square to them. Evaluated in world space (section 6.2).
template <class Pattern, class T>
T triplanar(const Pattern& pattern, const vec3<T>& p, const vec3<T>& n, float sharpness = 4.0f)
{
    detail::validate_triplanar(sharpness);
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

// triplanar() in GLSL: the pattern is a GLSL function `float pattern(float u, float v)` of the
// shader's (declared before the snippet) or of another snippet, named by `pattern`; `sharpness` as
// triplanar()'s. emitter::add_shading(triplanar_projection{"stripes", 4.0f}, "NAME") writes
//     float NAME(vec3 p, vec3 n)     triplanar(stripes, p, n, sharpness)
// GLSL's pow(x, y) is exp2(y log2(x)) to within a few ulp: the weights, and so the result, differ
// from the C++'s by about 1e-6 relative.
struct triplanar_projection {
    std::string pattern;     // a GLSL function name of the shader's, not starting with krs_ or gl_
    float sharpness = 4.0f;  // > 0

    // The pattern's name is checked where it is written, by the emitter's name rules (krs/glsl/
    // names.hpp, above this layer): glsl_shading, the only place it is used.
    void validate() const { detail::validate_triplanar(sharpness); }

    static constexpr std::string_view glsl_source = R"(float NAME(vec3 p, vec3 n) {
    const float sharpness = SHARPNESS;
    vec3 a = abs(n);
    float wx = pow(a.x, sharpness);
    float wy = pow(a.y, sharpness);
    float wz = pow(a.z, sharpness);
    float total = wx + wy + wz;
    float sx = PATTERN(p.y, p.z);
    float sy = PATTERN(p.z, p.x);
    float sz = PATTERN(p.x, p.y);
    return total > 0.0 ? (wx * sx + wy * sy + wz * sz) / total : (sx + sy + sz) / 3.0;
}
)";
    template <class Out>
    void glsl_shading(Out& out, const std::string& function, const std::string&) const
    {
        validate();
        Out::require_user_function_name("triplanar_projection.pattern", pattern);
        out.function(Out::fill(glsl_source, {{"NAME", function}, {"SHARPNESS", Out::literal(sharpness)},
                                             {"PATTERN", pattern}}));
    }
};

} // namespace krs

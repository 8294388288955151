#pragma once
// What the libFuzzer targets share (fuzz_builders.cpp, fuzz_fractals.cpp): decoding parameters
// from bytes, and the checks every built field must pass.
//
// Byte layout: every float field is a mode byte followed by a 16-bit little-endian value (mode <
// 200: in the field's range; 200..239: just outside it; 240..255: a special value: NaN, +-inf, 0,
// -0, +-FLT_MAX, subnormal, FLT_MIN, +-1e-30, 1e30, the magnitude limit 1e9 and the next float
// above it, or raw bits from the next 4 bytes); every int field is one byte (< 224: in range; else
// an invalid value). A missing byte reads as 0.
//
// The check: the field's distance in float, double and packet lanes is finite (not NaN, not inf) at
// probe points decoded from the bytes, near the scene or anywhere within the magnitude policy's
// reach |p| <= 1e9 (krs/core/validate.hpp), down to the origin itself. Anything else traps.

#include "krs/core/lanes.hpp"
#include "krs/core/validate.hpp"
#include "krs/core/vec3.hpp"

#include <algorithm>
#include <climits>
#include <cmath>
#include <cstddef>
#include <cstdint>
#include <cstdio>
#include <cstring>
#include <limits>

namespace krs_fuzz {

using krs::vec3d;
using krs::vec3f;

[[noreturn]] inline void fail() { __builtin_trap(); }

// A line on stderr about the input (what was refused and why) in verbose builds; nothing otherwise.
#ifdef KRS_FUZZ_VERBOSE
inline void note(const char* what, const char* detail) { std::fprintf(stderr, "  %s: %s\n", what, detail); }
#else
inline void note(const char*, const char*) {}
#endif

struct reader {
    const std::uint8_t* data;
    std::size_t size;
    std::size_t at = 0;

    std::uint8_t byte() { return at < size ? data[at++] : std::uint8_t(0); }
    std::uint16_t u16()
    {
        const std::uint16_t lo = byte();
        return std::uint16_t(lo | (std::uint16_t(byte()) << 8));
    }
    std::uint32_t u32() { return std::uint32_t(u16()) | (std::uint32_t(u16()) << 16); }
    // In [0, 1].
    double unit() { return u16() / 65535.0; }

    // A float field whose valid range is [lo, hi].
    float real(float lo, float hi)
    {
        const std::uint8_t mode = byte();
        const double u = unit();
        const double w = double(hi) - double(lo);
        if (mode < 200) return float(lo + w * u);
        if (mode < 220) return float(lo - w * (0.001 + u));
        if (mode < 240) return float(hi + w * (0.001 + u));
        switch (mode & 15) {
        case 0: return std::numeric_limits<float>::quiet_NaN();
        case 1: return std::numeric_limits<float>::infinity();
        case 2: return -std::numeric_limits<float>::infinity();
        case 3: return 0.0f;
        case 4: return -0.0f;
        case 5: return std::numeric_limits<float>::max();
        case 6: return -std::numeric_limits<float>::max();
        case 7: return std::numeric_limits<float>::denorm_min();
        case 8: return std::numeric_limits<float>::min();
        case 9: return 1e-30f;
        case 10: return 1e30f;
        case 11: return -1e-30f;
        case 12: return krs::max_magnitude;
        case 13: return std::nextafter(krs::max_magnitude, std::numeric_limits<float>::infinity());
        case 14: return -krs::max_magnitude;
        default: {
            const std::uint32_t bits = u32();
            float f;
            std::memcpy(&f, &bits, sizeof f);
            return f;
        }
        }
    }
    // A vector field, each component with the valid range [lo, hi].
    vec3f point(float lo, float hi)
    {
        const float x = real(lo, hi), y = real(lo, hi);
        return {x, y, real(lo, hi)};
    }
    // An int field: in range [lo, hi] (kept small by the caller), or one of the invalid values.
    int integer(int lo, int hi, int bad_lo, int bad_hi)
    {
        const std::uint8_t mode = byte();
        if (mode < 224) return lo + int(mode % unsigned(hi - lo + 1));
        switch (mode & 3) {
        case 0: return bad_lo;
        case 1: return bad_hi;
        case 2: return INT_MIN;
        default: return INT_MAX;
        }
    }

    // A probe point: a mode byte, then three 16-bit values.
    //   mode % 8 < 4: within +-reach of the origin in each coordinate (the scene itself);
    //   4: a direction from the values at a length 10^(9 u) in [1, 1e9] (far from the scene);
    //   5: that direction at the limit of the magnitude policy, |p| = 1e9;
    //   6: at a length 10^(-40 u) (toward the warps' singularity at the origin);
    //   7: the origin exactly.
    // Points are rounded to float first so the float and double evaluations see the same point.
    vec3d probe(double reach)
    {
        const std::uint8_t mode = byte() % 8;
        const double x = double(std::int16_t(u16())) / 32768.0, y = double(std::int16_t(u16())) / 32768.0,
                     z = double(std::int16_t(u16())) / 32768.0;
        vec3d p{x * reach, y * reach, z * reach};
        if (mode >= 4) {
            vec3d d{x, y, z};
            const double l = krs::length(d);
            d = l > 1e-3 ? d / l : vec3d{0, 1, 0};
            const double u = 0.5 * (z + 1.0);
            // 1 - 1e-6 keeps the float-rounded point inside the limit.
            if (mode == 4) p = d * std::min(std::pow(10.0, 9.0 * u), double(krs::max_magnitude) * (1 - 1e-6));
            else if (mode == 5) p = d * (double(krs::max_magnitude) * (1 - 1e-6));
            else if (mode == 6) p = d * std::pow(10.0, -40.0 * u);
            else p = vec3d{0, 0, 0};
        }
        return vec3d(vec3f{float(p.x), float(p.y), float(p.z)});
    }
};

// The field's distance must be finite at `count` probe points, in float, double and packet lanes.
template <class Field>
void probe(const Field& field, reader& in, double reach, int count = 8)
{
    using P = krs::packet_f;
    constexpr std::size_t W = krs::lane_count<P>;
    alignas(64) float xs[W], ys[W], zs[W];
    std::size_t filled = 0;
    auto flush = [&] {
        for (std::size_t i = filled; i < W; ++i) xs[i] = xs[0], ys[i] = ys[0], zs[i] = zs[0];
        const krs::vec3fP pp{P::load_aligned(xs), P::load_aligned(ys), P::load_aligned(zs)};
        if (!xsimd::all(krs::is_finite(field.distance(pp)))) fail();
        filled = 0;
    };
    for (int i = 0; i < count; ++i) {
        const vec3d p = in.probe(reach);
        const vec3f pf{float(p.x), float(p.y), float(p.z)};
        if (!std::isfinite(field.distance(pf))) fail();
        if (!std::isfinite(field.distance(p))) fail();
        xs[filled] = pf.x, ys[filled] = pf.y, zs[filled] = pf.z;
        if (++filled == W) flush();
    }
    if (filled > 0) flush();
}

// One fuzz input: `build(in)` reads parameters and builds and checks a field. Refused parameters
// (krs::invalid_parameter) are the expected outcome for bad input; any other exception is a bug.
template <class Build>
int run_one(const std::uint8_t* data, std::size_t size, Build&& build)
{
    reader in{data, size};
    try {
        build(in);
    } catch (const krs::invalid_parameter& e) {
#ifdef KRS_FUZZ_VERBOSE
        std::fprintf(stderr, "  rejected: %s\n", e.what());
#else
        (void)e;
#endif
        return 0;
    } catch (...) {
        fail();
    }
#ifdef KRS_FUZZ_VERBOSE
    std::fprintf(stderr, "  built\n");
#endif
    return 0;
}

} // namespace krs_fuzz

#pragma once
// Rounding that the optimizer must keep.
//
// C++ says a float (or double) value is rounded to its type, but two optimizations may compute
// with a value that was never rounded: g++ 12.2's SLP vectorizer at -O2/-O3 folds a vectorized
// (double)(float)x back to x, and contraction (g++'s default -ffp-contract=fast, clang's default
// on) fuses a product into the add that follows, in one path and not another. Both are stopped
// the same way: `detail::keep_rounded` is an empty asm that claims to change the value in its
// register, so the value must exist there, rounded, and nothing may be folded across it.
//
// What it costs: it emits no instruction itself, but the value must be materialized in a
// register at that point. On double lanes a widening convert_float<double>(float) from memory
// becomes movss + cvtss2sd instead of one cvtss2sd with a memory operand, and the compiler may
// no longer share equal computations on either side of the barrier (value_noise hashes 8 corners
// and so computes each axis's scrambled coordinates once by hand: krs/core/noise.hpp). With
// contraction off and no fold to prevent, the values are the same with and without the barrier.

#include <cmath>
#include <concepts>
#include <limits>
#include <type_traits>

namespace krs {

namespace detail {
// T is a float, a double or an xsimd batch of them (its register is `.data`).
template <class T>
inline constexpr void keep_rounded(T& x) noexcept
{
#if defined(__GNUC__) // g++ and clang
    if (std::is_constant_evaluated())
        return;
    auto& value = [&]() -> auto& {
        if constexpr (std::floating_point<T>)
            return x;
        else
            return x.data;
    }();
#if defined(__AVX512F__)
    asm("" : "+v"(value)); // any of the 32 vector registers, zmm16-31 included
#elif defined(__SSE2__)
    asm("" : "+x"(value));
#elif defined(__aarch64__)
    asm("" : "+w"(value));
#else
    asm("" : "+m"(value));
#endif
#else
    (void)x;
#endif
}
}  // namespace detail

// Conversion between float and double that keeps the rounding. g++ 12.2 at -O2 and -O3 (its SLP
// vectorizer) folds a vectorized (double)(float)x back to x: a constructor that widens its float
// parameters to double, inlined where the caller just rounded them from doubles, then computed
// with the unrounded doubles (a torus's axis normalized from the caller's double, in half of the
// cases of tests/check_float_rounding.cpp; docs/stability.md, "Double to float rounding"). Keeping
// the float on either side of the conversion makes it exist, so the fold cannot apply.
template <std::floating_point To, std::floating_point From>
inline constexpr To convert_float(From x) noexcept
{
    if constexpr (std::same_as<To, From>) {
        return x;
    } else if constexpr (sizeof(To) < sizeof(From)) {
        To narrowed = static_cast<To>(x);
        detail::keep_rounded(narrowed);
        return narrowed;
    } else {
        detail::keep_rounded(x);
        return static_cast<To>(x);
    }
}

// x as rounded in its own type, never fused into the add or subtract that follows. With FMA
// hardware g++ (default -ffp-contract=fast) and clang (default on) may compute a*b+c as one fma,
// and may do so in the scalar path and not in the packet one: the results then differ in the last
// bit. Most code tolerates that (docs/stability.md, "Packet and scalar results under FMA
// contraction"); code that amplifies the last bit, such as a hash taking the fractional part of a
// product, wraps its products in `unfused`. Float, double or an xsimd batch of them.
template <class T>
inline T unfused(T x) noexcept
{
    detail::keep_rounded(x);
    return x;
}

// The largest float no larger than v, and the smallest float no smaller than v: the one rule for
// storing a bound computed in double as a float. A factor that divides a distance (1/L, 1/s^i,
// 1 - 1/s) rounded up would make the field overestimate, so it is stored rounded down (toward
// zero: those factors are positive); a box is stored rounded outward, so it still holds the
// solid. The float is kept rounded (`convert_float`) so the comparison sees the stored value.
inline float float_at_most(double v) noexcept
{
    const float f = convert_float<float>(v);
    return double(f) <= v ? f : std::nextafter(f, -std::numeric_limits<float>::infinity());
}
inline float float_at_least(double v) noexcept
{
    const float f = convert_float<float>(v);
    return double(f) >= v ? f : std::nextafter(f, std::numeric_limits<float>::infinity());
}

}  // namespace krs

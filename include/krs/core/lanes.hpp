#pragma once
// Lane types: the one abstraction that lets a single template serve scalars and SIMD packets.
//
// Every distance, fold and march step in krs is written once, as a template over a *lane type* T:
// `float`, `double`, or `xsimd::batch<float, A>` / `xsimd::batch<double, A>`. A lane type knows
// its scalar (`scalar_t<T>`), its mask (`mask_t<T>`: `bool` for scalars, `xsimd::batch_bool` for
// packets) and its width (`lane_count<T>`). Data-dependent branches are written as
// `select(mask, a, b)`, so the same source compiles to a branch for scalars and a blend for
// packets. The free functions below (`select`, `min`, `max`, `abs`, `sqrt`, `any`, `all`, ...) are
// the vocabulary of that source; their scalar overloads exist because xsimd 8.1 has none (its
// scalar `select` arrived in 9.0).

#include "krs/core/rounding.hpp" // convert_float and unfused, which code using lanes calls

#include <xsimd/xsimd.hpp>

#include <algorithm>
#include <array>
#include <bit>
#include <cmath>
#include <concepts>
#include <cstddef>
#include <cstdint>
#include <type_traits>

namespace krs {

// Primary template: a scalar is its own scalar, its mask is bool, it is one lane wide.
template <class T>
struct lane_traits {
    using scalar = T;
    using mask = bool;
    static constexpr std::size_t size = 1;
};

template <class S, class A>
struct lane_traits<xsimd::batch<S, A>> {
    using scalar = S;
    using mask = xsimd::batch_bool<S, A>;
    static constexpr std::size_t size = xsimd::batch<S, A>::size;
};

template <class T>
using scalar_t = typename lane_traits<T>::scalar;
template <class T>
using mask_t = typename lane_traits<T>::mask;
template <class T>
inline constexpr std::size_t lane_count = lane_traits<T>::size;

// A lane type is a floating-point scalar or an xsimd batch of one.
template <class T>
concept lane = std::floating_point<scalar_t<T>> &&
               (std::floating_point<T> || std::same_as<T, xsimd::batch<scalar_t<T>, typename T::arch_type>>);

// The widest packet the compiler targets for this translation unit (16 floats with AVX-512,
// 8 with AVX2, 4 with SSE2).
using packet_f = xsimd::batch<float>;
using packet_d = xsimd::batch<double>;

// Broadcast a scalar parameter into a lane. Parameters are stored as float (the precision a
// shader would use); a double lane evaluates the same geometry in double arithmetic.
template <lane T>
inline T splat(float v) noexcept
{
    return T(convert_float<scalar_t<T>>(v));
}
template <lane T>
inline T splat(double v) noexcept
{
    return T(convert_float<scalar_t<T>>(v));
}

// ---- scalar overloads ------------------------------------------------------------------------
// Packets use xsimd's own functions of the same names, found by argument-dependent lookup, so
// generic code calls these unqualified (`min(a, b)`, not `krs::min(a, b)`), as with std::swap.

template <std::floating_point T>
inline T select(bool m, T a, T b) noexcept
{
    return m ? a : b;
}
template <std::floating_point T>
inline T min(T a, T b) noexcept
{
    return a < b ? a : b;
}
template <std::floating_point T>
inline T max(T a, T b) noexcept
{
    return a > b ? a : b;
}
template <std::floating_point T>
inline T abs(T a) noexcept
{
    return std::abs(a);
}
template <std::floating_point T>
inline T sqrt(T a) noexcept
{
    return std::sqrt(a);
}
template <std::floating_point T>
inline T ceil(T a) noexcept
{
    return std::ceil(a);
}
// atan2(y, x) on any lane type, 0 where y = x = 0 in every lane: xsimd's atan2 is NaN there,
// which made a packet's texture coordinates NaN where the scalar's were finite, and std's is 0
// or +-pi by the zeros' signs (both are angles of no direction).
template <class T>
inline T lane_atan2(const T& y, const T& x) noexcept
{
    if constexpr (std::floating_point<T>) return y == T(0) && x == T(0) ? T(0) : std::atan2(y, x);
    else return xsimd::select(y == T(0) && x == T(0), T(0), xsimd::atan2(y, x));
}
// log, exp and floor on any lane type: std:: for scalars, xsimd for packets.
template <class T>
inline T lane_log(const T& x)
{
    if constexpr (std::floating_point<T>) return std::log(x);
    else return xsimd::log(x);
}
template <class T>
inline T lane_exp(const T& x)
{
    if constexpr (std::floating_point<T>) return std::exp(x);
    else return xsimd::exp(x);
}
template <class T>
inline T lane_floor(const T& x)
{
    if constexpr (std::floating_point<T>) return std::floor(x);
    else return xsimd::floor(x);
}
inline bool any(bool m) noexcept { return m; }
inline bool all(bool m) noexcept { return m; }
inline bool none(bool m) noexcept { return !m; }

// Lane-wise finiteness: false for NaN and +-inf. (x - x) is 0 for finite x and NaN otherwise,
// which avoids relying on std::isfinite under -ffast-math-like flags the user might set.
template <lane T>
inline mask_t<T> is_finite(const T& x) noexcept
{
    return (x - x) == T(0);
}

template <lane T>
inline T clamp(const T& x, const T& lo, const T& hi) noexcept
{
    return min(max(x, lo), hi);
}

// lerp as in GLSL's mix: a + (b - a) * t.
template <lane T>
inline T mix(const T& a, const T& b, const T& t) noexcept
{
    return a + (b - a) * t;
}

// Extract lane i of a lane value (scalars have just lane 0).
template <lane T>
inline scalar_t<T> lane_at(const T& x, std::size_t i) noexcept
{
    if constexpr (std::floating_point<T>) {
        (void)i;
        return x;
    } else {
        alignas(64) scalar_t<T> buffer[lane_count<T>];
        x.store_aligned(buffer);
        return buffer[i];
    }
}
// All lanes of a lane value as an array, in one store: for code that reads several lanes (lane_at
// spills the whole value for each one).
template <lane T>
inline std::array<scalar_t<T>, lane_count<T>> lanes_of(const T& x) noexcept
{
    std::array<scalar_t<T>, lane_count<T>> a;
    if constexpr (std::floating_point<T>)
        a[0] = x;
    else
        x.store_unaligned(a.data());
    return a;
}
// Lane i of a mask; T names the lane type because a mask alone cannot say it (bool is every
// scalar's mask).
template <lane T>
inline bool mask_lane(const mask_t<T>& m, std::size_t i) noexcept
{
    if constexpr (std::floating_point<T>) {
        (void)i;
        return m;
    } else {
        alignas(64) bool buffer[lane_count<T>];
        m.store_aligned(buffer);
        return buffer[i];
    }
}

// The word with bits 0 .. n-1 set (lanes 0 .. n-1 of a lane word): every bit for n >= 64, where
// the plain (1 << n) - 1 would shift by the word's width (undefined behaviour in C++).
constexpr std::uint64_t low_bits(std::size_t n) noexcept
{
    return n >= 64 ? ~std::uint64_t(0) : (std::uint64_t(1) << n) - 1;
}

// A mask as a word of bits (bit i = lane i) and back, for code that keeps per-lane flags between
// packet operations (a refilling tracer's finished lanes). With AVX-512 the mask register is
// that word already; other targets go through memory.
template <lane T>
inline std::uint64_t mask_bits(const mask_t<T>& m) noexcept
{
    static_assert(lane_count<T> <= 64, "a mask of more than 64 lanes does not fit one word");
    if constexpr (std::floating_point<T>) {
        return m ? 1u : 0u;
    } else {
        if constexpr (std::is_base_of_v<xsimd::avx512f, typename T::arch_type>) {
            using word = typename mask_t<T>::register_type;
            return std::uint64_t(static_cast<word>(m));
        } else {
            alignas(64) bool lanes[lane_count<T>];
            m.store_aligned(lanes);
            std::uint64_t bits = 0;
            for (std::size_t i = 0; i < lane_count<T>; ++i) bits |= std::uint64_t(lanes[i]) << i;
            return bits;
        }
    }
}
template <lane T>
inline mask_t<T> mask_from_bits(std::uint64_t bits) noexcept
{
    static_assert(lane_count<T> <= 64, "a mask of more than 64 lanes does not fit one word");
    if constexpr (std::floating_point<T>) {
        return (bits & 1u) != 0;
    } else {
        if constexpr (std::is_base_of_v<xsimd::avx512f, typename T::arch_type>) {
            using word = typename mask_t<T>::register_type;
            return mask_t<T>(static_cast<word>(bits));
        } else {
            alignas(64) bool lanes[lane_count<T>];
            for (std::size_t i = 0; i < lane_count<T>; ++i) lanes[i] = ((bits >> i) & 1u) != 0;
            return mask_t<T>::load_aligned(lanes);
        }
    }
}

// The sum of a value's lanes (a scalar is its own sum): a packet's counters added up in one
// reduction where a loop over its lanes would add one at a time.
template <lane T>
inline scalar_t<T> lane_sum(const T& x) noexcept
{
    if constexpr (std::floating_point<T>) return x;
    else return xsimd::hadd(x);
}

// ---- compress and expand ----------------------------------------------------------------------
// Moving the lanes a mask selects to the front of memory, and back: what a refilling tracer needs
// to report its finished lanes and pull new rays into them, a whole register at a time instead of
// one lane at a time. `bits` is a word of lane flags as mask_bits gives it (bit i = lane i).
//
//   compress_store(out, x, bits): out[0 .. c) = the lanes i of x with bit i set, in lane order;
//       returns c = popcount(bits restricted to the lanes). Writes lane_count<V> values (the ones
//       from c on are unspecified), so out must have room for all of them.
//   expand_load(x, bits, in): lane i is in[j], j = the number of set bits below i, where bit i is
//       set, and x's lane i elsewhere. Reads lane_count<V> values from in (the first c are used),
//       so in must hold that many readable values.
//
// AVX-512 has both as instructions (vcompressps / vexpandps; their register forms are used with a
// plain store / load, because the forms with a memory operand are microcoded on some cores).
// AVX2 permutes by a table of 256 lane orders; other packets go through memory one lane at a
// time, with the same meaning. Scalars are one lane: bit 0 says whether it moves. Values of 32
// bits (float, std::int32_t lanes).
namespace detail {
// For 8 lanes: row b lists, first, the lanes with a bit set in b, in order (compress), and the
// rest padded with 0; expand's row b gives lane i the rank of bit i among b's set bits.
struct lane_orders_8 {
    std::uint8_t compress[256][8];
    std::uint8_t expand[256][8];
};
inline constexpr lane_orders_8 make_lane_orders_8()
{
    lane_orders_8 t{};
    for (unsigned b = 0; b < 256; ++b) {
        unsigned c = 0;
        for (unsigned i = 0; i < 8; ++i) {
            t.expand[b][i] = std::uint8_t(c & 7u);
            if ((b >> i) & 1u) t.compress[b][c++] = std::uint8_t(i);
        }
    }
    return t;
}
inline constexpr lane_orders_8 lane_orders_8_table = make_lane_orders_8();
} // namespace detail

template <class S>
    requires(sizeof(S) == 4 && std::is_arithmetic_v<S>)
inline std::size_t compress_store(S* out, S x, std::uint64_t bits) noexcept
{
    out[0] = x;
    return std::size_t(bits & 1u);
}
template <class S, class A>
    requires(sizeof(S) == 4)
inline std::size_t compress_store(S* out, const xsimd::batch<S, A>& x, std::uint64_t bits) noexcept
{
    constexpr std::size_t n = xsimd::batch<S, A>::size;
    bits &= low_bits(n);
    const std::size_t count = std::size_t(std::popcount(bits));
#if defined(__AVX512F__)
    if constexpr (std::is_base_of_v<xsimd::avx512f, A>) {
        if constexpr (std::is_same_v<S, float>)
            _mm512_storeu_ps(out, _mm512_maskz_compress_ps(__mmask16(bits), x));
        else
            _mm512_storeu_si512(out, _mm512_maskz_compress_epi32(__mmask16(bits), x));
        return count;
    } else
#endif
#if defined(__AVX2__)
        if constexpr (std::is_base_of_v<xsimd::avx2, A>) {
        const __m256i order = _mm256_cvtepu8_epi32(
            _mm_loadl_epi64(reinterpret_cast<const __m128i*>(detail::lane_orders_8_table.compress[bits])));
        if constexpr (std::is_same_v<S, float>)
            _mm256_storeu_ps(out, _mm256_permutevar8x32_ps(x, order));
        else
            _mm256_storeu_si256(reinterpret_cast<__m256i*>(out), _mm256_permutevar8x32_epi32(x, order));
        return count;
    } else
#endif
    {
        alignas(64) S lanes[n];
        x.store_aligned(lanes);
        std::size_t c = 0;
        for (std::size_t i = 0; i < n; ++i) {
            out[c] = lanes[i];
            c += (bits >> i) & 1u;
        }
        return count;
    }
}

template <class S>
    requires(sizeof(S) == 4 && std::is_arithmetic_v<S>)
inline S expand_load(S x, std::uint64_t bits, const S* in) noexcept
{
    return (bits & 1u) ? in[0] : x;
}
template <class S, class A>
    requires(sizeof(S) == 4)
inline xsimd::batch<S, A> expand_load(const xsimd::batch<S, A>& x, std::uint64_t bits, const S* in) noexcept
{
    using V = xsimd::batch<S, A>;
    constexpr std::size_t n = V::size;
    bits &= low_bits(n);
#if defined(__AVX512F__)
    if constexpr (std::is_base_of_v<xsimd::avx512f, A>) {
        // The empty asm keeps the loaded register a register: compilers otherwise fold the load
        // into the expand, which is then the microcoded memory form (AMD Zen 4).
        if constexpr (std::is_same_v<S, float>) {
            __m512 v = _mm512_loadu_ps(in);
            __asm__("" : "+v"(v));
            return V(_mm512_mask_expand_ps(x, __mmask16(bits), v));
        } else {
            __m512i v = _mm512_loadu_si512(in);
            __asm__("" : "+v"(v));
            return V(_mm512_mask_expand_epi32(x, __mmask16(bits), v));
        }
    } else
#endif
#if defined(__AVX2__)
        if constexpr (std::is_base_of_v<xsimd::avx2, A>) {
        const __m256i order = _mm256_cvtepu8_epi32(
            _mm_loadl_epi64(reinterpret_cast<const __m128i*>(detail::lane_orders_8_table.expand[bits])));
        // Lane i's own bit, as an all-ones lane where it is set.
        const __m256i lane_bit = _mm256_setr_epi32(1, 2, 4, 8, 16, 32, 64, 128);
        const __m256i take = _mm256_cmpeq_epi32(_mm256_and_si256(_mm256_set1_epi32(int(bits)), lane_bit), lane_bit);
        if constexpr (std::is_same_v<S, float>)
            return V(_mm256_blendv_ps(x, _mm256_permutevar8x32_ps(_mm256_loadu_ps(in), order), _mm256_castsi256_ps(take)));
        else
            return V(_mm256_blendv_epi8(x, _mm256_permutevar8x32_epi32(_mm256_loadu_si256(reinterpret_cast<const __m256i*>(in)), order), take));
    } else
#endif
    {
        alignas(64) S lanes[n];
        x.store_aligned(lanes);
        std::size_t c = 0;
        for (std::size_t i = 0; i < n; ++i)
            if ((bits >> i) & 1u) lanes[i] = in[c++];
        return V::load_aligned(lanes);
    }
}

// ---- index lanes -----------------------------------------------------------------------------
// Integer lanes beside float lanes, for table lookups done lane by lane in one template (a
// voxel's place in a sparse grid): std::int32_t beside float, xsimd::batch<std::int32_t, A>
// (same lane count) beside xsimd::batch<float, A>. Masks do not cross between the two (xsimd 8.1
// has no mask cast): code decides in the float domain and looks up in the integer one.
template <class T>
struct index_lane_traits {
    using type = std::int32_t;
};
template <class A>
struct index_lane_traits<xsimd::batch<float, A>> {
    using type = xsimd::batch<std::int32_t, A>;
};
template <class T>
using index_lanes = typename index_lane_traits<T>::type;

// Truncation toward zero. Precondition: every lane is finite and within the int32 range (the
// scalar conversion is undefined otherwise), so callers select a safe value first.
inline std::int32_t truncate_to_index(float x) noexcept { return std::int32_t(x); }
template <class A>
inline xsimd::batch<std::int32_t, A> truncate_to_index(const xsimd::batch<float, A>& x) noexcept
{
    return xsimd::to_int(x);
}
inline float index_to_float(std::int32_t i) noexcept { return float(i); }
template <class A>
inline xsimd::batch<float, A> index_to_float(const xsimd::batch<std::int32_t, A>& i) noexcept
{
    return xsimd::to_float(i);
}
// 2^e as a float, from its bits (no per-lane variable shift in xsimd 8.1). Precondition: every
// lane's e lies in [-126, 127] (a normal float).
inline float index_pow2(std::int32_t e) noexcept { return std::bit_cast<float>((e + 127) << 23); }
template <class A>
inline xsimd::batch<float, A> index_pow2(const xsimd::batch<std::int32_t, A>& e) noexcept
{
    return xsimd::bitwise_cast<xsimd::batch<float, A>>((e + xsimd::batch<std::int32_t, A>(127)) << 23);
}
// An index's 32 bits carried in a float lane, unchanged (no conversion): so that a float mask
// can select between indices (masks do not cross domains, above). Only moves and selects may
// touch such a lane; std::bit_cast gives the index back.
inline float index_bits(std::int32_t i) noexcept { return std::bit_cast<float>(i); }
template <class A>
inline xsimd::batch<float, A> index_bits(const xsimd::batch<std::int32_t, A>& i) noexcept
{
    return xsimd::bitwise_cast<xsimd::batch<float, A>>(i);
}
inline std::int32_t index_min(std::int32_t a, std::int32_t b) noexcept { return std::min(a, b); }
inline std::int32_t index_max(std::int32_t a, std::int32_t b) noexcept { return std::max(a, b); }
template <class A>
inline xsimd::batch<std::int32_t, A> index_min(const xsimd::batch<std::int32_t, A>& a, const xsimd::batch<std::int32_t, A>& b) noexcept
{
    return xsimd::min(a, b);
}
template <class A>
inline xsimd::batch<std::int32_t, A> index_max(const xsimd::batch<std::int32_t, A>& a, const xsimd::batch<std::int32_t, A>& b) noexcept
{
    return xsimd::max(a, b);
}
// table[i] in each lane (a gather for packets). Precondition: every lane indexes the table.
// xsimd 8.1's integer gathers never match (their enable_if is not deducible) and fall back to
// inserting one lane at a time, so the AVX-512 and AVX2 gathers are called here directly; other
// targets load lane by lane.
template <class V>
inline V gather(const V* table, std::int32_t i) noexcept
{
    return table[i];
}
template <class V, class A>
inline xsimd::batch<V, A> gather(const V* table, const xsimd::batch<std::int32_t, A>& i) noexcept
{
    static_assert(sizeof(V) == 4, "gathers of 32-bit values");
    [[maybe_unused]] constexpr bool is_float = std::is_same_v<V, float>;
#if defined(__AVX512F__)
    if constexpr (std::is_base_of_v<xsimd::avx512f, A>) {
        if constexpr (is_float)
            return _mm512_i32gather_ps(i, table, 4);
        else
            return _mm512_i32gather_epi32(i, table, 4);
    } else
#endif
#if defined(__AVX2__)
        if constexpr (std::is_base_of_v<xsimd::avx2, A>) {
        if constexpr (is_float)
            return _mm256_i32gather_ps(table, i, 4);
        else
            return _mm256_i32gather_epi32(reinterpret_cast<const int*>(table), i, 4);
    } else
#endif
    {
        constexpr std::size_t n = xsimd::batch<V, A>::size;
        alignas(64) std::int32_t index[n];
        alignas(64) V value[n];
        i.store_aligned(index);
        for (std::size_t k = 0; k < n; ++k) value[k] = table[index[k]];
        return xsimd::batch<V, A>::load_aligned(value);
    }
}

// table[i] for a table of bytes, in each lane as an int32 (a gather for packets). The gather reads
// the aligned 32-bit word that holds the byte and shifts the byte down (a per-lane variable
// shift: AVX2 and AVX-512 have one, xsimd 8.1 does not), so it never reads past the word of the
// last byte. Preconditions: every lane indexes the table, whose start is 4-byte aligned and whose
// length is a multiple of 4 (the last byte's word lies within it); little-endian byte order.
inline std::int32_t gather_byte(const std::uint8_t* table, std::int32_t i) noexcept
{
    return std::int32_t(table[i]);
}
template <class A>
inline xsimd::batch<std::int32_t, A> gather_byte(const std::uint8_t* table, const xsimd::batch<std::int32_t, A>& i) noexcept
{
    using I = xsimd::batch<std::int32_t, A>;
#if defined(__AVX512F__)
    if constexpr (std::is_base_of_v<xsimd::avx512f, A>) {
        const I word = _mm512_i32gather_epi32(i >> 2, table, 4);
        return I(_mm512_srlv_epi32(word, (i & I(3)) << 3)) & I(0xff);
    } else
#endif
#if defined(__AVX2__)
        if constexpr (std::is_base_of_v<xsimd::avx2, A>) {
        const I word = _mm256_i32gather_epi32(reinterpret_cast<const int*>(table), i >> 2, 4);
        return I(_mm256_srlv_epi32(word, (i & I(3)) << 3)) & I(0xff);
    } else
#endif
    {
        constexpr std::size_t n = I::size;
        alignas(64) std::int32_t index[n], value[n];
        i.store_aligned(index);
        for (std::size_t k = 0; k < n; ++k) value[k] = std::int32_t(table[index[k]]);
        return I::load_aligned(value);
    }
}

} // namespace krs

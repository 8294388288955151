// Lane-generic core: the vocabulary every distance is written in must mean the same thing for
// scalars and for each lane of a packet, and GLM must round-trip at the API surface.

#include "krs/core/bounds.hpp"
#include "krs/core/glm_interop.hpp"
#include "krs/core/validate.hpp"
#include "support/random.hpp"

#include <doctest/doctest.h>

#include <glm/geometric.hpp>

#include <cmath>
#include <limits>
#include <random>
#include <vector>

static_assert(std::same_as<krs::scalar_t<float>, float>);
static_assert(std::same_as<krs::mask_t<double>, bool>);
static_assert(std::same_as<krs::scalar_t<krs::packet_f>, float>);
static_assert(std::same_as<krs::mask_t<krs::packet_f>, xsimd::batch_bool<float>>);
static_assert(krs::lane_count<float> == 1 && krs::lane_count<krs::packet_f> == xsimd::batch<float>::size);
static_assert(krs::lane<float> && krs::lane<double> && krs::lane<krs::packet_f> && krs::lane<krs::packet_d>);
static_assert(!krs::lane<int>);

namespace {
template <class P>
P load(const krs::scalar_t<P>* values)
{
    return P::load_unaligned(values);
}
} // namespace

TEST_CASE_TEMPLATE("packet vocabulary equals the scalar one lane by lane", P, krs::packet_f, krs::packet_d)
{
    using S = krs::scalar_t<P>;
    constexpr std::size_t n = krs::lane_count<P>;
    std::mt19937_64 g(1);
    const auto u = [](std::mt19937_64& e) { return krs_test::uniform(e, -10, 10); };
    for (int round = 0; round < 200; ++round) {
        S a[n], b[n], c[n];
        for (std::size_t i = 0; i < n; ++i) a[i] = S(u(g)), b[i] = S(u(g)), c[i] = S(u(g));
        a[0] = b[0]; // equal operands exercise the comparisons' boundary
        const P pa = load<P>(a), pb = load<P>(b), pc = load<P>(c);
        const auto m = pa < pb;
        const P sel = select(m, pa, pb), mn = min(pa, pb), mx = max(pa, pb), ab = abs(pa), sq = sqrt(abs(pc));
        const P cl = krs::clamp(pa, pb, pb + abs(pc)), mi = krs::mix(pa, pb, pc);
        for (std::size_t i = 0; i < n; ++i) {
            CHECK(krs::mask_lane<P>(m, i) == (a[i] < b[i]));
            CHECK(krs::lane_at(sel, i) == krs::select(a[i] < b[i], a[i], b[i]));
            CHECK(krs::lane_at(mn, i) == std::min(a[i], b[i]));
            CHECK(krs::lane_at(mx, i) == std::max(a[i], b[i]));
            CHECK(krs::lane_at(ab, i) == std::abs(a[i]));
            CHECK(krs::lane_at(sq, i) == std::sqrt(std::abs(c[i])));
            CHECK(krs::lane_at(cl, i) == krs::clamp(a[i], b[i], S(b[i] + std::abs(c[i]))));
            CHECK(krs::lane_at(mi, i) == krs::mix(a[i], b[i], c[i]));
        }
        CHECK(any(m) == [&] { for (std::size_t i = 0; i < n; ++i) if (a[i] < b[i]) return true; return false; }());
        CHECK(all(pa == pa));
        CHECK_FALSE(any(pa != pa));
        // lane_sum: whole numbers, so every order of the additions gives the exact sum.
        S whole[n], sum = 0;
        for (std::size_t i = 0; i < n; ++i) whole[i] = std::round(a[i] * 100), sum += whole[i];
        CHECK(krs::lane_sum(load<P>(whole)) == sum);
        CHECK(krs::lane_sum(whole[0]) == whole[0]);
    }
}

namespace {
// The lane types compress/expand are tested on: scalars and every packet this build can run
// (the portable build: SSE2; the native one adds AVX2 and AVX-512, each with its own code path).
template <class V>
struct lane_values {
    using scalar = V;
    static constexpr std::size_t n = 1;
};
template <class S, class A>
struct lane_values<xsimd::batch<S, A>> {
    using scalar = S;
    static constexpr std::size_t n = xsimd::batch<S, A>::size;
};
template <class V>
using lane_scalar = typename lane_values<V>::scalar;
template <class V>
V from_lanes(const lane_scalar<V>* values)
{
    if constexpr (std::is_arithmetic_v<V>) return values[0];
    else return V::load_unaligned(values);
}
template <class V>
void to_lanes(const V& v, lane_scalar<V>* out)
{
    if constexpr (std::is_arithmetic_v<V>) out[0] = v;
    else v.store_unaligned(out);
}
} // namespace

#define KRS_COMPRESS_TYPES float, std::int32_t, xsimd::batch<float, xsimd::sse2>, xsimd::batch<std::int32_t, xsimd::sse2>
#if defined(__AVX512F__)
#define KRS_COMPRESS_TYPES_WIDE , xsimd::batch<float, xsimd::avx2>, xsimd::batch<std::int32_t, xsimd::avx2>, \
    xsimd::batch<float, xsimd::avx512f>, xsimd::batch<std::int32_t, xsimd::avx512f>
#elif defined(__AVX2__)
#define KRS_COMPRESS_TYPES_WIDE , xsimd::batch<float, xsimd::avx2>, xsimd::batch<std::int32_t, xsimd::avx2>
#else
#define KRS_COMPRESS_TYPES_WIDE
#endif

TEST_CASE("low_bits(n) sets bits 0 .. n-1, every bit from 64 on")
{
    // Reference: the bits set one at a time, never a shift by the word's width.
    for (std::size_t n = 0; n <= 70; ++n) {
        std::uint64_t expected = 0;
        for (std::size_t i = 0; i < std::min<std::size_t>(n, 64); ++i) expected |= std::uint64_t(1) << i;
        CHECK_MESSAGE(krs::low_bits(n) == expected, "n = " << n);
    }
    static_assert(krs::low_bits(0) == 0 && krs::low_bits(64) == ~std::uint64_t(0));
}

TEST_CASE_TEMPLATE("compress_store and expand_load equal their lane-by-lane meaning", V, KRS_COMPRESS_TYPES KRS_COMPRESS_TYPES_WIDE)
{
    using S = lane_scalar<V>;
    constexpr std::size_t n = lane_values<V>::n;
    std::mt19937_64 g(5);
    // Every mask for up to 8 lanes; random ones (and the edges) for 16. Bits above the lanes are
    // set too: they must be ignored.
    std::vector<std::uint64_t> masks;
    if (n <= 8)
        for (std::uint64_t b = 0; b < (std::uint64_t(1) << n); ++b) masks.push_back(b | (g() << n));
    else {
        masks = {0, (std::uint64_t(1) << n) - 1, 1, std::uint64_t(1) << (n - 1)};
        for (int k = 0; k < 2000; ++k) masks.push_back(g());
    }
    for (const std::uint64_t bits : masks) {
        S x[n], in[n], old[n];
        for (std::size_t i = 0; i < n; ++i)
            x[i] = S(int(g() % 2001) - 1000) + S(i) / S(4), in[i] = S(int(g() % 2001) + 5000), old[i] = S(-7 - int(i));
        // Reference: walk the lanes one at a time.
        S want_c[n], want_e[n];
        std::size_t c = 0;
        for (std::size_t i = 0; i < n; ++i)
            if ((bits >> i) & 1u) want_c[c++] = x[i];
        for (std::size_t i = 0, j = 0; i < n; ++i) want_e[i] = (bits >> i) & 1u ? in[j++] : old[i];
        S got_c[n];
        const std::size_t count = krs::compress_store(got_c, from_lanes<V>(x), bits);
        REQUIRE(count == c);
        for (std::size_t i = 0; i < c; ++i) REQUIRE(got_c[i] == want_c[i]);
        S got_e[n];
        to_lanes(krs::expand_load(from_lanes<V>(old), bits, in), got_e);
        for (std::size_t i = 0; i < n; ++i) REQUIRE(got_e[i] == want_e[i]);
        // Expand undoes compress on the selected lanes.
        S round[n];
        to_lanes(krs::expand_load(from_lanes<V>(old), bits, got_c), round);
        for (std::size_t i = 0; i < n; ++i) REQUIRE(round[i] == ((bits >> i) & 1u ? x[i] : old[i]));
    }
}

TEST_CASE("scalar vocabulary and finiteness")
{
    CHECK(krs::select(true, 1.0f, 2.0f) == 1.0f);
    CHECK(krs::select(false, 1.0, 2.0) == 2.0);
    CHECK(krs::any(true));
    CHECK_FALSE(krs::all(false));
    CHECK(krs::none(false));
    CHECK(krs::is_finite(1.0f));
    CHECK_FALSE(krs::is_finite(std::numeric_limits<float>::quiet_NaN()));
    CHECK_FALSE(krs::is_finite(-std::numeric_limits<double>::infinity()));
    const float lanes[4] = {1.0f, std::numeric_limits<float>::infinity(), std::nanf(""), -3.0f};
    krs::packet_f p(0.0f);
    alignas(64) float buffer[krs::lane_count<krs::packet_f>] = {};
    for (std::size_t i = 0; i < krs::lane_count<krs::packet_f>; ++i) buffer[i] = lanes[i % 4];
    p = krs::packet_f::load_aligned(buffer);
    const auto finite = krs::is_finite(p);
    for (std::size_t i = 0; i < krs::lane_count<krs::packet_f>; ++i)
        CHECK(krs::mask_lane<krs::packet_f>(finite, i) == std::isfinite(lanes[i % 4]));
}

TEST_CASE("vec3 algebra agrees with GLM and round-trips through it")
{
    std::mt19937_64 g(2);
    const auto u = [](std::mt19937_64& e) { return float(krs_test::uniform(e, -5, 5)); };
    for (int k = 0; k < 1000; ++k) {
        const glm::vec3 a{u(g), u(g), u(g)}, b{u(g), u(g), u(g)};
        const krs::vec3f ka = krs::from_glm(a), kb = krs::from_glm(b);
        CHECK(krs::dot(ka, kb) == doctest::Approx(glm::dot(a, b)).epsilon(1e-6));
        const glm::vec3 c = glm::cross(a, b);
        const krs::vec3f kc = krs::cross(ka, kb);
        CHECK(glm::length(krs::to_glm(kc) - c) <= 1e-5f * (1 + glm::length(c)));
        CHECK(krs::length(ka) == doctest::Approx(glm::length(a)).epsilon(1e-6));
        CHECK(glm::length(krs::to_glm(krs::normalize(ka)) - glm::normalize(a)) < 1e-6f);
        CHECK(krs::to_glm(ka + kb) == a + b);
        CHECK(krs::to_glm(ka - kb) == a - b);
        CHECK(krs::to_glm(ka * 2.0f) == a * 2.0f);
        const glm::vec3 n = glm::normalize(b);
        CHECK(glm::length(krs::to_glm(krs::reflect_direction(ka, krs::from_glm(n))) - glm::reflect(a, n)) < 1e-5f);
    }
    const glm::dvec3 d{1.5, -2.0, 3.25};
    CHECK(krs::to_glm(krs::from_glm(d)) == d);
}

TEST_CASE("validation helpers name the parameter and say what was allowed")
{
    CHECK_THROWS_WITH_AS(krs::require_positive("thing.size", 0.0f), "krs: thing.size: must be > 0 (got 0)",
                         krs::invalid_parameter);
    CHECK_THROWS_WITH_AS(krs::require_non_negative("r", -1.0), doctest::Contains("must be >= 0"), krs::invalid_parameter);
    CHECK_THROWS_WITH_AS(krs::require_finite("x", std::nan("")), doctest::Contains("must be finite"), krs::invalid_parameter);
    CHECK_THROWS_WITH_AS(krs::require_direction("n", krs::vec3f{0, 0, 0}), doctest::Contains("non-zero direction"),
                         krs::invalid_parameter);
    try {
        krs::require_finite("p", krs::vec3f{1, INFINITY, 0});
        FAIL("no exception");
    } catch (const krs::invalid_parameter& e) {
        CHECK(e.parameter() == "p");
    }
    // A direction comes back unit length to float precision, computed in double.
    const krs::vec3f n = krs::require_direction("n", krs::vec3f{3e-20f, 4e-20f, 0});
    CHECK(n.x == doctest::Approx(0.6f));
    CHECK(std::abs(krs::length(krs::vec3d(n)) - 1.0) < 1e-7);
}

TEST_CASE("enclose holds both spheres and is tight for disjoint ones")
{
    std::mt19937_64 g(3);
    const auto u = [](std::mt19937_64& e) { return float(krs_test::uniform(e, -10, 10)); };
    const auto r = [](std::mt19937_64& e) { return float(krs_test::uniform(e, 0, 3)); };
    for (int k = 0; k < 10000; ++k) {
        const krs::bounding_sphere a{{u(g), u(g), u(g)}, r(g)}, b{{u(g), u(g), u(g)}, r(g)};
        const krs::bounding_sphere e = krs::enclose(a, b);
        const auto holds = [&](const krs::bounding_sphere& s) {
            return krs::length(krs::vec3d(s.center) - krs::vec3d(e.center)) + s.radius <= double(e.radius);
        };
        REQUIRE(holds(a));
        REQUIRE(holds(b));
        const double span = krs::length(krs::vec3d(a.center) - krs::vec3d(b.center)) + a.radius + b.radius;
        REQUIRE(double(e.radius) <= std::max({0.5 * span, double(a.radius), double(b.radius)}) * (1 + 1e-6) + 1e-6);
    }
    CHECK_FALSE(krs::enclose(krs::bounding_sphere::unbounded(), krs::bounding_sphere{}).is_bounded());
}

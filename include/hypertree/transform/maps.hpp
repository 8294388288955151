#pragma once
// The concrete maps every transform pipeline reduces to, once its parameters are drawn and its
// level of execution is known: affine maps and nonlinear shears.
//
// Translations, rotations and scalings compose into one affine map, so a pipeline at a given
// level becomes the canonical chain A_0, S_1, A_1, ..., S_K, A_K (K shears, affine maps merged
// between them): applying a chain costs one 3x4 matrix product per shear plus one, whatever the
// number of elementary transforms. Maps are templates over the lane type (double here; packets
// where a caller applies one map to many points).
//
// Each map also bounds its Lipschitz constant, so an IFS can check the contraction condition of
// section 2.2: a chain's constant is at most the product of its maps' constants.

#include "krs/core/vec3.hpp"

#include <algorithm>
#include <array>
#include <cmath>

namespace hypertree {

using krs::vec3;
using krs::vec3d;

struct affine_map {
    // Row-major 3x3 linear part, then the translation: p -> m p + t.
    std::array<double, 9> m{1, 0, 0, 0, 1, 0, 0, 0, 1};
    vec3d t{};

    template <class L>
    vec3<L> operator()(const vec3<L>& p) const
    {
        return {L(m[0]) * p.x + L(m[1]) * p.y + L(m[2]) * p.z + L(t.x),
                L(m[3]) * p.x + L(m[4]) * p.y + L(m[5]) * p.z + L(t.y),
                L(m[6]) * p.x + L(m[7]) * p.y + L(m[8]) * p.z + L(t.z)};
    }
    // outer after inner: p -> outer(inner(p)).
    friend affine_map compose(const affine_map& outer, const affine_map& inner)
    {
        affine_map r;
        for (int i = 0; i < 3; ++i)
            for (int j = 0; j < 3; ++j)
                r.m[3 * i + j] = outer.m[3 * i] * inner.m[j] + outer.m[3 * i + 1] * inner.m[3 + j] +
                                 outer.m[3 * i + 2] * inner.m[6 + j];
        r.t = outer(inner.t);
        return r;
    }
    // The spectral norm of m: the square root of the largest eigenvalue of m^T m, from the
    // closed form for symmetric 3x3 matrices (trigonometric solution of the characteristic cubic),
    // with a relative margin of 1e-12 so rounding never makes the bound too small.
    double lipschitz() const
    {
        std::array<double, 9> g{}; // m^T m
        for (int i = 0; i < 3; ++i)
            for (int j = 0; j < 3; ++j)
                g[3 * i + j] = m[i] * m[j] + m[3 + i] * m[3 + j] + m[6 + i] * m[6 + j];
        const double off = g[1] * g[1] + g[2] * g[2] + g[5] * g[5];
        const double q = (g[0] + g[4] + g[8]) / 3.0;
        const double a = g[0] - q, b = g[4] - q, c = g[8] - q;
        const double p2 = a * a + b * b + c * c + 2.0 * off;
        double largest = q;
        if (p2 > 0) {
            const double p = std::sqrt(p2 / 6.0);
            // det((g - q I) / p) / 2, clamped into [-1, 1] against rounding.
            const double det = a * (b * c - g[5] * g[5]) - g[1] * (g[1] * c - g[5] * g[2]) + g[2] * (g[1] * g[5] - b * g[2]);
            const double r = std::clamp(det / (2.0 * p * p * p), -1.0, 1.0);
            largest = q + 2.0 * p * std::cos(std::acos(r) / 3.0);
        }
        return std::sqrt(std::max(largest, 0.0)) * (1.0 + 1e-12) + 1e-300;
    }
};

// Nonlinear shear (section 3.1, figure 1): the point's relative height h = |p_axis| / height
// displaces it by d_i = dmax_i * h^e along the two other axes (first and second in x, y, z order).
// h is clamped to 1 above the given height, so the displacement never exceeds dmax; that keeps the
// map bounded, which the bounding spheres of section 8.2 rely on.
struct shear_map {
    int axis = 1, first = 0, second = 2; // height axis and the two bending directions
    double dmax_first = 0, dmax_second = 0;
    double exponent = 1; // >= 1: h^e is then Lipschitz with constant e on [0, 1]
    double inverse_height = 1;
    int whole_exponent = 1; // the exponent when it is a whole number <= 64 (repeated squaring), else -1

    void set_exponent(double e)
    {
        exponent = e;
        whole_exponent = (e == std::floor(e) && e >= 1 && e <= 64) ? int(e) : -1;
    }

    template <class L>
    vec3<L> operator()(const vec3<L>& p) const
    {
        using std::abs, std::min, std::pow;
        const L height = axis == 0 ? p.x : axis == 1 ? p.y : p.z;
        const L h = min(abs(height) * L(inverse_height), L(1));
        // Whole exponents (the usual 2 or 3) by repeated squaring: pow() would cost more than the
        // rest of the chain.
        L f;
        if (whole_exponent > 0) {
            L base = h;
            f = L(1);
            for (int n = whole_exponent; n > 0; n >>= 1, base = base * base)
                if (n & 1) f = f * base;
        } else {
            f = pow(h, L(exponent));
        }
        // Every component gets its displacement (0 for the height axis): adding 0 * f leaves it
        // as it was, and the axis choice becomes three constants rather than a write through a
        // computed reference, which compiles to a store and reload on the generator's hot path.
        const auto along = [&](int i) { return (first == i ? dmax_first : 0.0) + (second == i ? dmax_second : 0.0); };
        return {p.x + L(along(0)) * f, p.y + L(along(1)) * f, p.z + L(along(2)) * f};
    }
    // The Jacobian is I + u v^T with |v| = e / height (the derivative of h^e) and u the unit
    // displacement scaled by |dmax|: its norm is at most 1 + |u||v|.
    double lipschitz() const { return 1.0 + std::hypot(dmax_first, dmax_second) * exponent * inverse_height; }

    template <class L>
    static L& component(vec3<L>& p, int i)
    {
        return i == 0 ? p.x : i == 1 ? p.y : p.z;
    }
    template <class L>
    static const L& component(const vec3<L>& p, int i)
    {
        return i == 0 ? p.x : i == 1 ? p.y : p.z;
    }
};

// A canonical chain with room for `MaxShears` shears. With `Fixed` the count is exactly MaxShears
// (a compile-time pipeline: the loop unrolls); otherwise `shears` says how many are used (the
// runtime pipeline of a definition file).
template <int MaxShears, bool Fixed>
struct map_chain {
    std::array<affine_map, MaxShears + 1> affine{};
    std::array<shear_map, MaxShears> shear{};
    int shears = Fixed ? MaxShears : 0;

    template <class L>
    vec3<L> operator()(vec3<L> p) const
    {
        const int count = Fixed ? MaxShears : shears;
        for (int k = 0; k < count; ++k) p = shear[k](affine[k](p));
        return affine[count](p);
    }
    double lipschitz() const
    {
        const int count = Fixed ? MaxShears : shears;
        double l = affine[count].lipschitz();
        for (int k = 0; k < count; ++k) l *= affine[k].lipschitz() * shear[k].lipschitz();
        return l;
    }
};

} // namespace hypertree

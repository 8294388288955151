#pragma once
// The explicit expansion of a KRS: every one of its sum_i |K_i| 2^(n-i) kernel instances, each with
// the isometry that places it in the world.
//
// A kernel of level i is seen through the compositions R_{n-1}^{b_{n-1}} ... R_i^{b_i} for all
// choices of b, so its instances are built top-down: start from the identity and, at each mirror
// below the top, keep every transform W and add W o R_i. The expansion is the brute-force
// reference of the O(n) distance (tests) and the instance list an exporter or a triangle tracer
// needs. Its cost is exponential by nature: expansion refuses to exceed a stated instance budget.

#include "krs/sequence.hpp"

#include <array>
#include <cmath>
#include <string>
#include <vector>

namespace krs {

// x -> A x + t with A orthogonal (a product of reflections), kept in double so that deep
// compositions stay exact enough to serve as a reference.
struct isometry {
    std::array<double, 9> a{1, 0, 0, 0, 1, 0, 0, 0, 1}; // row-major
    vec3d t{};

    vec3d apply(const vec3d& p) const
    {
        return {a[0] * p.x + a[1] * p.y + a[2] * p.z + t.x, a[3] * p.x + a[4] * p.y + a[5] * p.z + t.y,
                a[6] * p.x + a[7] * p.y + a[8] * p.z + t.z};
    }
    // A is orthogonal, so its inverse is its transpose.
    vec3d apply_inverse(const vec3d& p) const
    {
        const vec3d q = p - t;
        return {a[0] * q.x + a[3] * q.y + a[6] * q.z, a[1] * q.x + a[4] * q.y + a[7] * q.z,
                a[2] * q.x + a[5] * q.y + a[8] * q.z};
    }
    // The reflection R x = x - 2 (m . x - c) m = (I - 2 m m^T) x + 2 c m (any mirror kind: an
    // axis_mirror states its plane by the same normal and offset).
    template <mirror_kind M>
    static isometry reflection(const M& m)
    {
        const vec3d n(m.normal);
        const double c = m.offset;
        isometry r;
        const double v[3] = {n.x, n.y, n.z};
        for (int row = 0; row < 3; ++row)
            for (int col = 0; col < 3; ++col) r.a[row * 3 + col] = (row == col ? 1.0 : 0.0) - 2.0 * v[row] * v[col];
        r.t = n * (2.0 * c);
        return r;
    }
    // (this o other)(x) = this(other(x)).
    isometry operator*(const isometry& other) const
    {
        isometry r;
        for (int row = 0; row < 3; ++row)
            for (int col = 0; col < 3; ++col)
                r.a[row * 3 + col] = a[row * 3 + 0] * other.a[0 + col] + a[row * 3 + 1] * other.a[3 + col] +
                                     a[row * 3 + 2] * other.a[6 + col];
        r.t = apply(other.t);
        return r;
    }
};

template <mirror_kind Mirror, kernel... Kinds>
struct expansion {
    struct instance {
        std::uint32_t kernel = 0; // index into sequence::kernels()
        isometry to_world;        // kernel space -> world
    };

    const basic_sequence<Mirror, Kinds...>* source = nullptr;
    std::vector<instance> instances;

    // min over all instances of k(W^-1 x): the distance to the union, computed the slow way.
    template <std::floating_point S>
    S distance(const vec3<S>& x) const
    {
        const vec3d xd(x);
        double d = std::numeric_limits<double>::infinity();
        for (const instance& in : instances) {
            const vec3d p = in.to_world.apply_inverse(xd);
            d = std::min(d, std::visit([&](const auto& k) { return k.distance(p); }, source->kernels()[in.kernel]));
        }
        return S(d);
    }
};

// Expands every kernel instance of `s`. Throws invalid_parameter("max_instances") when the
// expansion would exceed the budget, before allocating anything.
template <mirror_kind Mirror, kernel... Kinds>
expansion<Mirror, Kinds...> expand(const basic_sequence<Mirror, Kinds...>& s,
                                   std::size_t max_instances = std::size_t(1) << 22)
{
    const double count = s.instance_count();
    if (count > double(max_instances))
        throw invalid_parameter("max_instances", "the expansion has more kernel instances than allowed",
                                detail::to_text(count) + " > " + std::to_string(max_instances));
    expansion<Mirror, Kinds...> e;
    e.source = &s;
    e.instances.reserve(std::size_t(count));

    const std::size_t n = s.mirror_count();
    // Kernels are stored lowest level first; no transform is needed below the lowest one.
    const std::size_t lowest = s.kernel_level(0);
    std::vector<isometry> transforms{isometry{}}; // for the current level, top-down
    for (std::size_t level = n + 1; level-- > lowest;) {
        if (level < n) {
            const isometry r = isometry::reflection(s.mirrors()[level]);
            const std::size_t half = transforms.size();
            for (std::size_t j = 0; j < half; ++j) transforms.push_back(transforms[j] * r);
        }
        for (std::uint32_t k = s.level_begin(level); k < s.level_begin(level + 1); ++k)
            for (const isometry& w : transforms) e.instances.push_back({k, w});
    }
    return e;
}

} // namespace krs

#pragma once
// Shell presets: prototype shells for the similar shell (krs/fractal/similar_shell.hpp) from the
// source documents: a ring of lotus petals and the cube singularity, and their similar shells.

#include "krs/core/validate.hpp"
#include "krs/fractal/similar_shell.hpp"
#include "krs/kernels/box.hpp"
#include "krs/kernels/capsule.hpp"

#include <algorithm>
#include <array>
#include <cmath>
#include <limits>
#include <numbers>
#include <string>
#include <string_view>
#include <utility>
#include <vector>

namespace krs {

// One ring of `petals` capsule petals in the shell 1 <= |p| <= s (s = e^(1/density)), rising from
// near the inner sphere at 15 degrees above the xy plane to near the outer one at 55 degrees; the
// similar shell makes it a lotus with rings of petals at every scale.
struct lotus_shell {
    static constexpr int max_petals = 16;
    std::array<capsule, max_petals> petal{};
    int petals = 0;

    lotus_shell() = default;
    lotus_shell(float ratio, int petals_)
    {
        if (petals_ < 1 || petals_ > max_petals)
            throw invalid_parameter("lotus_shell.petals", "must be in [1, 16]", std::to_string(petals_));
        const double s = require_finite("lotus_shell.ratio", ratio);
        if (!(s > 1.0 && s <= double(max_magnitude)))
            throw invalid_parameter("lotus_shell.ratio", "must be in (1, 1e9]", detail::to_text(ratio));
        const double rb = std::pow(s, 0.2), rt = std::pow(s, 0.8);
        const double radius = std::min({0.15 * (rt - rb), rb - 1.0, s - rt}) * 0.95;
        const double low = 15.0 * std::numbers::pi / 180.0, high = 55.0 * std::numbers::pi / 180.0;
        petals = petals_;
        for (int i = 0; i < petals; ++i) {
            const double a = 2.0 * std::numbers::pi * (i + 0.5) / petals;
            const vec3d base = vec3d{std::cos(a) * std::cos(low), std::sin(a) * std::cos(low), std::sin(low)} * rb;
            const vec3d tip = vec3d{std::cos(a) * std::cos(high), std::sin(a) * std::cos(high), std::sin(high)} * rt;
            petal[std::size_t(i)] = capsule(vec3f(base), vec3f(tip), float(radius));
        }
    }
    template <class T>
    T distance(const vec3<T>& p) const
    {
        T d = petal[0].distance(p);
        for (int i = 1; i < petals; ++i) d = min(d, petal[std::size_t(i)].distance(p));
        return d;
    }
    // GLSL (krs/glsl/emitter.hpp): petal i as NAME_i, NAME their minimum in this order.
    template <class Out>
    void glsl_emit(Out& out, const std::string& name) const
    {
        for (int i = 0; i < petals; ++i) out.field(petal[std::size_t(i)], name + "_" + std::to_string(i));
        out.minimum_of_parts(name, std::size_t(petals));
    }
};

// Fourteen cubes in the shell: on the six axes and the eight diagonals, at the shell's middle
// radius s^(1/2); the similar shell makes them a cube singularity, cubes around cubes down to the
// origin and out to infinity.
struct cube_shell {
    std::array<box, 14> cube{};

    cube_shell() = default;
    explicit cube_shell(float ratio)
    {
        const double s = require_finite("cube_shell.ratio", ratio);
        if (!(s > 1.0 && s <= double(max_magnitude)))
            throw invalid_parameter("cube_shell.ratio", "must be in (1, 1e9]", detail::to_text(ratio));
        const double rc = std::sqrt(s);
        const double h = 0.8 * std::min(rc - 1.0, s - rc) / std::sqrt(3.0);
        int n = 0;
        for (int axis = 0; axis < 3; ++axis)
            for (int sign = -1; sign <= 1; sign += 2) {
                vec3d c{0, 0, 0};
                (axis == 0 ? c.x : axis == 1 ? c.y : c.z) = sign * rc;
                cube[std::size_t(n++)] = box(vec3f(c), vec3f(vec3d{h, h, h}));
            }
        for (int i = 0; i < 8; ++i) {
            const vec3d c = vec3d{(i & 1) ? 1.0 : -1.0, (i & 2) ? 1.0 : -1.0, (i & 4) ? 1.0 : -1.0} * (rc / std::sqrt(3.0));
            cube[std::size_t(n++)] = box(vec3f(c), vec3f(vec3d{h, h, h}));
        }
    }
    template <class T>
    T distance(const vec3<T>& p) const
    {
        T d = cube[0].distance(p);
        for (std::size_t i = 1; i < cube.size(); ++i) d = min(d, cube[i].distance(p));
        return d;
    }
    // GLSL (krs/glsl/emitter.hpp): cube i as NAME_i, NAME their minimum in this order.
    template <class Out>
    void glsl_emit(Out& out, const std::string& name) const
    {
        for (std::size_t i = 0; i < cube.size(); ++i) out.field(cube[i], name + "_" + std::to_string(i));
        out.minimum_of_parts(name, cube.size());
    }
};

using recursive_lotus = similar_shell<lotus_shell>;
inline recursive_lotus make_recursive_lotus(float density = 1.0f, int petals = 8, shell_options options = {})
{
    detail::require_shell_density("recursive_lotus.density", density);
    return {lotus_shell(float(std::exp(1.0 / double(density))), petals), density, options};
}

using cube_singularity = similar_shell<cube_shell>;
inline cube_singularity make_cube_singularity(float density = 1.0f, shell_options options = {})
{
    detail::require_shell_density("cube_singularity.density", density);
    return {cube_shell(float(std::exp(1.0 / double(density)))), density, options};
}

} // namespace krs

#pragma once
// A KRS sequence's GLSL (basic_sequence::glsl_emit, declared in krs/sequence.hpp, which includes
// this file at its end): three functions that unroll the sequence's walk, as a compiler would for
// the fixed structure (level count, kernel kinds per level), reading the mirrors' and kernels'
// parameters from the emitter's data, so the same code serves constants and buffers.
//
//   float NAME(vec3 p)                    Algorithm 1, the distance
//   krs_location NAME_locate(vec3 p)      Algorithm 1 recording where the minimum was found
//   krs_kernel_shading NAME_shade(vec3 p, vec3 toLight, vec3 toEye, float threshold)
//                                         Algorithm 2 (shade_in_kernel_space): light and view
//                                         carried into the nearest kernel's space, blended across
//                                         each mirror over a band of width `threshold`
//
// The structs krs_location and krs_kernel_shading are the emitter's common library. Reflection
// bits are a uvec2: bit i of the 64-bit word is bit (i % 32) of component i / 32 (x the low word),
// as location::reflections on the CPU.

#include "krs/core/validate.hpp"
#include "krs/sequence.hpp"

#include <charconv>
#include <cstdint>
#include <string>
#include <type_traits>
#include <variant>
#include <vector>

namespace krs {

template <mirror_kind Mirror, kernel... Kinds>
template <class Out>
void basic_sequence<Mirror, Kinds...>::glsl_emit(Out& out, const std::string& name) const
{
    const std::size_t n = mirror_count();
    // Only the kinds this scene uses get their functions emitted (in type-list order).
    bool used[sizeof...(Kinds)] = {};
    for (const auto& k : kernels_) used[k.index()] = true;
    {
        std::size_t i = 0;
        ((used[i++] ? out.template library<Kinds>() : void()), ...);
    }
    if (n > 0) out.template library<Mirror>();
    std::vector<std::size_t> mirror_at(n), kernel_at(kernels_.size());
    for (std::size_t i = 0; i < n; ++i) mirror_at[i] = out.parameters(mirrors_[i], name + " mirror " + std::to_string(i));
    for (std::size_t k = 0; k < kernels_.size(); ++k)
        kernel_at[k] = std::visit(
            [&](const auto& kernel) {
                return out.parameters(kernel, name + " kernel " + std::to_string(k) + " (level " +
                                                  std::to_string(kernel_level(k)) + ")");
            },
            kernels_[k]);
    // Where each kernel's parameters are, for requests that read them (kernel_uv_glsl).
    {
        std::vector<std::size_t> kinds(kernels_.size());
        for (std::size_t k = 0; k < kernels_.size(); ++k) kinds[k] = kernels_[k].index();
        out.record_kernels(name, {kernel_at, std::move(kinds)});
    }
    // The per-level early exit of the C++ walk (distances() in krs/sequence.hpp): below the highest
    // kernel level, where L_i's bounding sphere is finite, the walk stops once the folded point is
    // farther from that sphere than d, since no kernel instance still to come can then lower d. The
    // sphere (center, early_exit_radius) is data, after the kernels, so a buffer of another
    // sequence of the same structure brings its own bounds; the value is the full walk's, only the
    // work differs. options.level_early_exit = false writes the full walk, for timing it
    // (bench/bench_glsl_llvmpipe.cpp); the bounds are written to the data all the same, so the
    // layout, and pack(), do not depend on the option.
    std::vector<std::size_t> bound_at(n);
    for (std::size_t i = 0; i < bound_tests_below_; ++i) {
        const bounding_sphere& b = level_bounds_[i];
        bound_at[i] = out.vec4({b.center.x, b.center.y, b.center.z, early_exit_radius(b)},
                               name + " bound of level " + std::to_string(i) + " (center, radius with margin)");
    }
    const std::size_t tested_levels = out.settings().level_early_exit ? bound_tests_below_ : 0;
    // Kernel k's distance or normal call at point expression `p`.
    const auto kernel_call = [&](std::size_t k, const char* what, const std::string& p) {
        return std::visit(
            [&](const auto& kernel) {
                using K = std::remove_cvref_t<decltype(kernel)>;
                return std::string(K::glsl_name) + "_" + what + "(" + p + out.template arguments<K>(kernel_at[k]) + ")";
            },
            kernels_[k]);
    };
    const std::string mirror_fn = std::string(Mirror::glsl_name) + "_";
    const auto bit = [](std::size_t i) {
        char hex[16];
        const auto r = std::to_chars(hex, hex + sizeof hex, std::uint32_t(1) << (i % 32), 16);
        return std::string(i < 32 ? ".x" : ".y") + " |= 0x" + std::string(hex, r.ptr) + "u;";
    };
    const auto kernel_record = [&](std::size_t k, std::size_t level, const std::string& target, bool shading) {
        std::string b = "    d = " + kernel_call(k, "distance", "p") + ";\n";
        b += "    if (d < " + target + ".dist) { " + target + ".dist = d; " + target + ".kernel_point = p; " + target +
             ".kernel = " + std::to_string(k) + "u; " + target + ".level = " + std::to_string(level) + "u;" +
             (shading ? " s.light = light; s.view = view;" : "") + " }\n";
        return b;
    };

    // Algorithm 1: the distance.
    std::string body = "float " + name + "(vec3 p) {\n    float d = 3.0e38;\n";
    if (tested_levels > 0) body += "    vec3 v;\n    float reach;\n";
    for (std::size_t i = n + 1; i-- > 0;) {
        if (i < n) body += "    p = " + mirror_fn + "fold(p, " + out.at(mirror_at[i]) + ");\n";
        if (i < tested_levels) {
            const std::string b = out.at(bound_at[i]);
            // The C++'s test term for term: |p - c|^2 > (d + r)^2 with d + r > 0.
            body += "    v = p - " + b + ".xyz;\n    reach = d + " + b + ".w;\n"
                    "    if (v.x * v.x + v.y * v.y + v.z * v.z > reach * reach && reach > 0.0) return d;\n";
        }
        for (std::uint32_t k = level_begin(i); k < level_begin(i + 1); ++k)
            body += "    d = min(d, " + kernel_call(k, "distance", "p") + ");\n";
    }
    out.function(body + "    return d;\n}\n");
    if (out.settings().distance_only) return;

    // Algorithm 1 with the location (locate).
    body = "krs_location " + name + "_locate(vec3 p) {\n"
           "    krs_location w = krs_location(3.0e38, p, 0u, 0u, uvec2(0u));\n    float d;\n";
    for (std::size_t i = n + 1; i-- > 0;) {
        if (i < n)
            body += "    if (" + mirror_fn + "signed_distance(p, " + out.at(mirror_at[i]) + ") > 0.0) { p = " +
                    mirror_fn + "reflect(p, " + out.at(mirror_at[i]) + "); w.reflections" + bit(i) + " }\n";
        for (std::uint32_t k = level_begin(i); k < level_begin(i + 1); ++k) body += kernel_record(k, i, "w", false);
    }
    out.function(body + "    return w;\n}\n");

    // Algorithm 2 (shade_in_kernel_space).
    body = "krs_kernel_shading " + name + "_shade(vec3 p, vec3 toLight, vec3 toEye, float threshold) {\n"
           "    krs_kernel_shading s;\n"
           "    s.where = krs_location(3.0e38, p, 0u, 0u, uvec2(0u));\n"
           "    s.light = toLight;\n    s.view = toEye;\n"
           "    vec3 light = toLight;\n    vec3 view = toEye;\n"
           "    bool ramp = threshold >= 1.17549435e-38;\n" // as the C++: below float's smallest normal, the step
           "    float inverse = ramp ? 1.0 / threshold : 0.0;\n"
           "    float d;\n    float e;\n    float weight;\n";
    for (std::size_t i = n + 1; i-- > 0;) {
        if (i < n) {
            const std::string m = out.at(mirror_at[i]);
            body += "    e = " + mirror_fn + "signed_distance(p, " + m + ");\n"
                    "    if (e > 0.0) { p = " + mirror_fn + "reflect(p, " + m + "); s.where.reflections" + bit(i) + " }\n"
                    "    weight = ramp ? clamp(e * inverse + 0.5, 0.0, 1.0) : (e > 0.0 ? 1.0 : 0.0);\n"
                    "    light = light + (" + mirror_fn + "reflect_direction(light, " + m + ") - light) * weight;\n"
                    "    view = view + (" + mirror_fn + "reflect_direction(view, " + m + ") - view) * weight;\n";
        }
        for (std::uint32_t k = level_begin(i); k < level_begin(i + 1); ++k) body += kernel_record(k, i, "s.where", true);
    }
    body += "    vec3 q = s.where.kernel_point;\n";
    for (std::size_t k = 0; k < kernels_.size(); ++k) {
        body += std::string(k == 0 ? "    " : "    else ") +
                (k + 1 < kernels_.size() ? "if (s.where.kernel == " + std::to_string(k) + "u) " : "") +
                "{ s.normal = " + kernel_call(k, "normal", "q") + "; s.kind = " + std::to_string(kernels_[k].index()) +
                "u; }\n";
    }
    out.function(body + "    return s;\n}\n");
}

template <mirror_kind Mirror, kernel... Kinds>
template <class Out>
void basic_sequence<Mirror, Kinds...>::glsl_uv_emit(Out& out, const std::string& function, const std::string& field) const
{
    // The kernels' parameters are the field's own (where its glsl_emit put them), so data packed
    // for the field moves the uv with it; each kernel with a uv adds one vec4 of its own after.
    const auto* recorded = out.recorded_kernels(field);
    bool same = recorded && recorded->at.size() == kernels_.size();
    for (std::size_t k = 0; same && k < kernels_.size(); ++k) same = recorded->kinds[k] == kernels_[k].index();
    if (!same)
        throw invalid_parameter("glsl.add_shading.field",
                                "must name a sequence added before with the kernel kinds of kernel_uv_glsl's, in order",
                                field);
    const std::vector<std::size_t> kernel_at = recorded->at;
    std::string body = "vec2 " + function + "(krs_location where) {\n    vec3 q = where.kernel_point;\n";
    for (std::size_t k = 0; k < kernels_.size(); ++k)
        std::visit(
            [&](const auto& kernel) {
                using K = std::remove_cvref_t<decltype(kernel)>;
                if constexpr (requires { K::glsl_uv_source; kernel.glsl_uv_parameters(); }) {
                    out.library_text(K::glsl_uv_name, K::glsl_uv_source);
                    const std::size_t uv_at = out.vec4(kernel.glsl_uv_parameters(), function + " kernel " +
                                                                                        std::to_string(k) + " uv");
                    body += "    if (where.kernel == " + std::to_string(k) + "u) return " + std::string(K::glsl_uv_name) +
                            "(q" + out.template arguments<K>(kernel_at[k]) + ", " + out.at(uv_at) + ");\n";
                }
            },
            kernels_[k]);
    out.function(body + "    return vec2(0.0);\n}\n");
}

// The request emitter::add_shading takes for a sequence's kernel uv (see glsl_uv_emit), with the
// name of the same sequence added before, whose kernel parameters it reads:
//     krs::glsl::emitter e; e.add(tree, "tree"); e.add_shading(krs::kernel_uv_glsl{tree}, "tree_uv", "tree");
//     ... vec2 uv = krs_tree_uv(krs_tree_locate(p));
// Its data is the field's followed by one vec4 per kernel with a uv (torus capsules: chord
// direction, twice the half arc length): a host animating in buffer mode uploads the data of an
// emitter given the same calls for the new sequence, of which pack(sequence) is the leading part.
template <class Sequence>
struct kernel_uv_glsl {
    const Sequence& sequence;
    static constexpr bool glsl_takes_field = true;
    template <class Out>
    void glsl_shading(Out& out, const std::string& function, const std::string& field) const
    {
        sequence.glsl_uv_emit(out, function, field);
    }
};
template <class Sequence>
kernel_uv_glsl(const Sequence&) -> kernel_uv_glsl<Sequence>;

} // namespace krs

#pragma once
// How a hypertree voxel looks (paper sections 8.1 and 8.3), written once for the CPU marcher
// (marcher.hpp) and the GLSL one (glsl.hpp): the opacity law and its table, the color per level
// and how many levels there are, and the lighting: Reeves' ambient falloff, a wrapped Lambert
// term and Blinn-Phong specular, each light dimmed by its shadow.
//
// As PNanoVDB keeps one portable description that CPU and GPU code both compile, and as curv
// keeps a primitive's CPU evaluation beside its GLSL emitter, each rule here is one C++ function
// with its GLSL next to it, and every constant the GLSL needs (the opacity table, the Lambert
// wrap, the level colors and their count, the weights, the lights) is emitted as a literal from
// the C++ value the CPU uses, never typed again. What differs is only what GLSL lacks: the CPU
// computes the crown depth in double, the GPU in float (GLSL has no double exp).
//
// The opacity law: a voxel of density byte d (mu = d / 255), crossed over one step ds, is
// alpha = 1 - (1 - mu)^(k ds / side) opaque, k = density_scale (8.1, normalized per voxel side
// so that k = 1 makes a voxel of density mu, crossed along one side, exactly mu opaque). With
// ds = step_factor x side the exponent is k x step_factor: one table of 256 floats per set of
// options, computed in double; 255 is fully opaque whatever the exponent.

#include "hypertree/depth_colors.hpp"
#include "hypertree/render/march_options.hpp"
#include "hypertree/render/tree_shape.hpp"
#include "hypertree/render/voxel_bricks.hpp"
#include "krs/glsl/literal.hpp"
#include "krs/glsl/names.hpp"

#include <algorithm>
#include <array>
#include <bit>
#include <cmath>
#include <string>
#include <vector>

namespace hypertree {

// alpha per density byte for one step: 1 - (1 - d / 255)^(density_scale x step_factor).
inline std::array<float, 256> opacity_table(const march_options& options)
{
    const double exponent = double(options.density_scale) * double(options.step_factor);
    std::array<float, 256> alpha{};
    for (int d = 0; d < 256; ++d) alpha[std::size_t(d)] = d == 255 ? 1.0f : float(1.0 - std::pow(1.0 - d / 255.0, exponent));
    return alpha;
}

// The wrapped Lambert term of 8.3: max(0, n.l) x slope + floor, so the side of a leaf cluster
// turned from a light keeps a quarter of its diffuse light (foliage transmits and scatters;
// a hard n.l turns every back face black). slope + floor = 1: a face toward the light gets all.
struct lambert_wrap {
    static constexpr float slope = 0.75f, floor = 0.25f;
    static float of(float n_dot_l) { return std::max(0.0f, n_dot_l) * slope + floor; }
};
static_assert(lambert_wrap::slope + lambert_wrap::floor == 1.0f);

// 1 + the deepest level among the non-empty voxels (1 for an empty tree): the length of the
// GPU's color table, which a deeper level would index past.
inline int level_count(const voxel_bricks& bricks)
{
    int deepest = 0;
    for (std::size_t b = 0; b < bricks.brick_count(); ++b)
        for (std::uint64_t m = bricks.mask(b); m != 0; m &= m - 1)
            deepest = std::max(deepest, int(bricks.at_place(b * voxel_bricks::brick_voxels + std::size_t(std::countr_zero(m))).level));
    return deepest + 1;
}

// The lighting of one tree under one set of options: lit() for the CPU, glsl_constants() and
// glsl_shade() for the GPU. Built from validated options (march_options::validate).
class voxel_shading {
public:
    voxel_shading() = default;
    voxel_shading(const march_options& options, const tree_shape& shape, const depth_colors& colors)
        : options_(options), crown_(shape.crown), alpha_(opacity_table(options)), light_dirs_(options.light_directions())
    {
        for (int l = 0; l < 256; ++l) level_color_[std::size_t(l)] = colors.at(l);
        if (flat()) {
            for (int l = 0; l < 256; ++l) {
                const rgb c = lit(crown_.center, l, nullptr, {});
                flat_[3 * std::size_t(l)] = c.r, flat_[3 * std::size_t(l) + 1] = c.g, flat_[3 * std::size_t(l) + 2] = c.b;
            }
        }
    }

    const std::array<float, 256>& opacity() const { return alpha_; }
    const std::vector<krs::vec3f>& light_directions() const { return light_dirs_; }
    const rgb& level_color(int level) const { return level_color_[std::size_t(std::clamp(level, 0, 255))]; }

    // Whether the lit color is a function of the level alone: no lights (so no diffuse, specular
    // or shadow) and no ambient falloff. Then lit() at any point q is base x ambient x
    // exp(-0 x depth), and exp(-0) = 1 exactly (depth is finite and >= 0), so it equals lit() at
    // the crown's center to the bit; flat_colors() holds that, r, g, b per level byte (level l
    // at 3 l), for marches that gather it by level instead of shading each sample.
    bool flat() const { return light_dirs_.empty() && options_.ambient_falloff == 0.0f; }
    const std::array<float, 3 * 256>& flat_colors() const { return flat_; }

    // Base color x (Reeves' attenuated ambient + shadowed, wrapped Lambert) at shading point q,
    // given each light's shadow transmittance and the structure-flow normal there (zero: none).
    rgb lit(const krs::vec3f& q, int level, const float* shadows, const krs::vec3d& normal) const
    {
        const rgb base = level_color(level);
        const krs::vec3d c(crown_.center);
        const double depth = std::max(0.0, double(crown_.radius) - krs::length(krs::vec3d(q) - c)) / std::max(double(crown_.radius), 1e-30);
        const float ambient = options_.ambient * float(std::exp(-double(options_.ambient_falloff) * depth));
        float lr = ambient, lg = ambient, lb = ambient;
        const krs::vec3f n{float(normal.x), float(normal.y), float(normal.z)};
        const bool has_normal = normal.x != 0 || normal.y != 0 || normal.z != 0;
        for (std::size_t i = 0; i < light_dirs_.size(); ++i) {
            // Without a normal (no flow) the diffuse term is the shadow alone: "shadow attenuated
            // diffuse" of 8.3 for isotropic leaves.
            const float lambert = has_normal ? lambert_wrap::of(krs::dot(n, light_dirs_[i])) : 1.0f;
            const rgb lc = options_.lights[i].color;
            const float d = options_.diffuse * lambert * shadows[i];
            lr += d * lc.r, lg += d * lc.g, lb += d * lc.b;
        }
        return {base.r * lr, base.g * lg, base.b * lb};
    }
    // The view-dependent Blinn-Phong term added to a lit color, with the normal n (non-zero) and
    // the unit direction toward the viewer.
    rgb with_specular(rgb lit, const krs::vec3f& n, const krs::vec3f& view, const float* shadows) const
    {
        for (std::size_t i = 0; i < light_dirs_.size(); ++i) {
            const krs::vec3f h = krs::normalize(light_dirs_[i] + view); // the half-vector of light and viewer
            const float sp = options_.specular * std::pow(std::max(0.0f, krs::dot(n, h)), options_.shininess) * shadows[i];
            const rgb lc = options_.lights[i].color;
            lit.r += sp * lc.r, lit.g += sp * lc.g, lit.b += sp * lc.b;
        }
        return lit;
    }

    // The GLSL constants of the above, NAME being the caller's prefixed name
    // (krs::glsl::fill):
    // NAME_alpha[256], NAME_level_count and NAME_level_color[level_count], NAME_light_count, NAME_light_direction
    // and NAME_light_color (when there are lights), the crown, the weights and the Lambert wrap.
    std::string glsl_constants(const std::string& name, int levels) const
    {
        using krs::glsl::float_literal, krs::glsl::vec3_literal;
        std::string s = "// Opacity of one step per density byte: 1 - (1 - d / 255)^(density_scale x step_factor).\n";
        s += krs::glsl::float_array(name + "_alpha", alpha_.data(), alpha_.size());
        std::vector<krs::vec3f> level_colors;
        for (int l = 0; l < levels; ++l) level_colors.push_back({level_color(l).r, level_color(l).g, level_color(l).b});
        s += "const int " + name + "_level_count = " + std::to_string(levels) + ";\n";
        s += krs::glsl::vec3_array(name + "_level_color", level_colors);
        s += "const vec3 " + name + "_crown_center = " + vec3_literal(crown_.center) + ";\n";
        s += "const float " + name + "_crown_radius = " + float_literal(crown_.radius) + ";\n";
        std::vector<krs::vec3f> light_colors;
        for (const directional_light& l : options_.lights) light_colors.push_back({l.color.r, l.color.g, l.color.b});
        s += "const int " + name + "_light_count = " + std::to_string(light_dirs_.size()) + ";\n";
        if (!light_dirs_.empty()) {
            s += krs::glsl::vec3_array(name + "_light_direction", light_dirs_);
            s += krs::glsl::vec3_array(name + "_light_color", light_colors);
        }
        s += "const float " + name + "_ambient = " + float_literal(options_.ambient) + ";\n";
        s += "const float " + name + "_ambient_falloff = " + float_literal(options_.ambient_falloff) + ";\n";
        s += "const float " + name + "_diffuse = " + float_literal(options_.diffuse) + ";\n";
        s += "const float " + name + "_lambert_slope = " + float_literal(lambert_wrap::slope) + ";\n";
        s += "const float " + name + "_lambert_floor = " + float_literal(lambert_wrap::floor) + ";\n";
        s += "const float " + name + "_specular = " + float_literal(options_.specular) + ";\n";
        s += "const float " + name + "_shininess = " + float_literal(options_.shininess) + ";\n";
        return s;
    }

    // `vec3 NAME_shade(vec3 p, int level, vec3 view)`: lit() and with_specular() at shading point p,
    // calling `float NAME_shadow_transmittance(vec3 p, vec3 l)` (with shadows on) and
    // `vec3 NAME_normal(vec3 p)`, which the caller emits before it.
    std::string glsl_shade(const std::string& name) const
    {
        std::string s = krs::glsl::fill(R"(// shade: Reeves' ambient falloff below the crown sphere, wrapped Lambert (and Blinn-Phong) with the flow
// normal, each light attenuated by its shadow ray (voxel_shading::lit and with_specular).
vec3 NAME_shade(vec3 p, int level, vec3 view) {
    vec3 base = NAME_level_color[min(level, NAME_level_count - 1)];
    float depth = max(0.0, NAME_crown_radius - sqrt(NAME_dot(p - NAME_crown_center, p - NAME_crown_center))) / max(NAME_crown_radius, 1e-30);
    float ambient = NAME_ambient * exp(-NAME_ambient_falloff * depth);
    vec3 light = vec3(ambient), specular = vec3(0.0);
    vec3 n = NAME_normal(p);
    bool has_normal = n.x != 0.0 || n.y != 0.0 || n.z != 0.0;
)",
                                          {{"NAME", name}});
        // (No lights: ambient only, and no loop over arrays GLSL could not declare with size 0.)
        if (!light_dirs_.empty()) {
            s += "    for (int i = 0; i < " + name + "_light_count; ++i) {\n";
            s += krs::glsl::fill("        vec3 l = NAME_light_direction[i];\n", {{"NAME", name}});
            s += options_.shadows ? krs::glsl::fill("        float shadow = NAME_shadow_transmittance(p, l);\n", {{"NAME", name}})
                                  : "        float shadow = 1.0;\n";
            s += krs::glsl::fill(R"(        float lambert = has_normal ? max(0.0, NAME_dot(n, l)) * NAME_lambert_slope + NAME_lambert_floor : 1.0;
        vec3 lc = NAME_light_color[i];
        float d = NAME_diffuse * lambert * shadow;
        light += d * lc;
)",
                                   {{"NAME", name}});
            // GLSL leaves pow(0, 0) undefined where C gives 1: a shininess of 0 is emitted as the 1.
            const std::string highlight = options_.shininess == 0 ? "1.0" : "pow(max(0.0, NAME_dot(n, h)), NAME_shininess)";
            if (options_.specular > 0)
                s += krs::glsl::fill(R"(        if (has_normal) {
            vec3 h = l + view;
            h = h / sqrt(NAME_dot(h, h));
            float s = NAME_specular * )" + highlight + R"( * shadow;
            specular += s * lc;
        }
)",
                                       {{"NAME", name}});
            s += "    }\n";
        }
        return s + "    return base * light + specular;\n}\n\n";
    }

private:
    march_options options_;
    krs::bounding_sphere crown_{};
    std::array<float, 256> alpha_{};
    std::array<rgb, 256> level_color_{};
    std::array<float, 3 * 256> flat_{}; // lit() per level when flat(), else zeros
    std::vector<krs::vec3f> light_dirs_;
};

} // namespace hypertree

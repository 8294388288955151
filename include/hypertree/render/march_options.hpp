#pragma once
// What a march of a hypertree is asked to do (paper section 8): the step, the opacity law's
// scale, the early exit, the secondary bounds, and the shading weights and lights of section 8.3.
//
// `validate()` checks the options alone and names the first bad field; `validate(volume, box)`
// adds the one bound that depends on the tree: how many samples a ray may take across its box.
// The CPU marcher (marcher.hpp) and the GLSL emitter (glsl.hpp) both call it, so an option is
// accepted or refused, with the same message, whichever of them is asked, and neither needs the
// other to find out.

#include "hypertree/depth_colors.hpp"
#include "hypertree/perturbation.hpp"
#include "hypertree/render/tree_shape.hpp"
#include "hypertree/store/store.hpp"
#include "krs/core/validate.hpp"
#include "krs/core/vec3.hpp"

#include <cstddef>
#include <string>
#include <vector>

namespace hypertree {

struct directional_light {
    krs::vec3f direction{0.4f, 0.8f, 0.45f}; // toward the light; normalized by the marcher
    rgb color{1.0f, 0.97f, 0.9f};
};

struct march_options {
    float step_factor = 1.0f;           // ds = step_factor * smallest voxel side
    float density_scale = 1.0f;         // k of alpha = 1 - (1 - mu)^(k ds / side)
    float min_transmittance = 1.0f / 256.0f;
    // Skip lookups outside a secondary bound (8.2, tree_shape.hpp): the part spheres fitted to
    // the voxels, the paper's spheres derived through the transformations (needs
    // tree_shape::set_paper_spheres_of), or the part boxes. `box` (the default) clips to the tree's
    // box only: the brick occupancy bits already skip empty space, and testing every bound at
    // every sample then costs more than it saves (bench_hypertree_render --only bounds, Table 2).
    // The paper saw the same spread, "from 40% faster to twice slower". The GLSL marcher takes
    // box and spheres only.
    bound_method bounds_by = bound_method::box;
    bool shadows = true;
    // How a voxel's shadow is found (light_sweep.hpp): `rays` marches a shadow ray toward each
    // light from every shaded voxel in every render (the paper's method, and the reference);
    // `sweep` computes every voxel's transmittance once, when the marcher is made, each shadow ray
    // cut at its first non-empty voxel toward the light (after at least `sweep_near_steps`
    // samples) and completed by that voxel's own swept shadow. The GLSL marcher always uses rays.
    enum class shadow_method { rays, sweep };
    shadow_method shadow_by = shadow_method::sweep;
    int sweep_near_steps = 1;
    // Shade at the voxel's center instead of the sample (the voxel is a homogeneous region, as in
    // section 9), so one voxel's ambient, normal and shadow rays serve every sample in it
    // (memoized for all threads of a render: see shade_memo.hpp). Off: everything per sample,
    // shadow rays included: the reference the benchmark measures the difference against.
    bool shade_per_voxel = true;
    float ambient = 0.3f;
    float ambient_falloff = 2.5f;       // per crown radius of depth below the crown sphere
    float diffuse = 0.85f;
    float specular = 0.0f;
    float shininess = 24.0f;
    // The normal of Lambert and Blinn-Phong (8.3, tree_shape.hpp): the first-level structure flow
    // (the paper's recommended procedural normal), the part boxes' faces (Hart and DeFanti), or
    // the flow of line generators (tree_shape::set_line_flow_of), on the CPU and in GLSL alike.
    normal_method normals_by = normal_method::structure_flow;
    std::vector<directional_light> lights{directional_light{}};
    sample_displacement displacement; // render-time noise: off at amplitude 0

    // A shading entry holds one shadow per light (shade_memo.hpp) in a fixed-size buffer.
    static constexpr std::size_t max_lights = 8;

    // Throws invalid_parameter naming the first field out of range.
    void validate() const
    {
        krs::require_positive("march_options.step_factor", step_factor);
        krs::require_positive("march_options.density_scale", density_scale);
        krs::require_non_negative("march_options.min_transmittance", min_transmittance);
        // Every shading term finite and non-negative: a NaN or infinite one made covered pixels
        // NaN, a negative ambient made them negative; a transmittance floor above 1 stopped every
        // ray after its first sample.
        if (!(min_transmittance <= 1.0f))
            throw krs::invalid_parameter("march_options.min_transmittance", "must be in [0, 1]", krs::detail::to_text(min_transmittance));
        krs::require_non_negative("march_options.ambient", ambient);
        krs::require_non_negative("march_options.ambient_falloff", ambient_falloff);
        krs::require_non_negative("march_options.diffuse", diffuse);
        krs::require_non_negative("march_options.specular", specular);
        krs::require_non_negative("march_options.shininess", shininess);
        if (normals_by != normal_method::structure_flow && normals_by != normal_method::part_boxes && normals_by != normal_method::line_flow)
            throw krs::invalid_parameter("march_options.normals_by", "must be normal_method::structure_flow, part_boxes or line_flow",
                                         std::to_string(int(normals_by)));
        if (bounds_by != bound_method::box && bounds_by != bound_method::spheres && bounds_by != bound_method::paper_spheres &&
            bounds_by != bound_method::part_boxes)
            throw krs::invalid_parameter("march_options.bounds_by", "must be bound_method::box, spheres, paper_spheres or part_boxes",
                                         std::to_string(int(bounds_by)));
        if (shadow_by != shadow_method::rays && shadow_by != shadow_method::sweep)
            throw krs::invalid_parameter("march_options.shadow_by", "must be shadow_method::rays or shadow_method::sweep",
                                         std::to_string(int(shadow_by)));
        // (Samples are counted in floats, exact to 2^24; a larger count is a full shadow ray anyway.)
        if (!(sweep_near_steps >= 1 && sweep_near_steps <= (1 << 20)))
            throw krs::invalid_parameter("march_options.sweep_near_steps", "must be in [1, 2^20]", std::to_string(sweep_near_steps));
        displacement.validate("march_options.displacement");
        for (const auto& light : lights) require_color("march_options.lights.color", light.color);
        if (lights.size() > max_lights)
            throw krs::invalid_parameter("march_options.lights", "may hold at most " + std::to_string(max_lights) + " lights",
                                         std::to_string(lights.size()));
        (void)light_directions();
    }

    // ... and for a tree: rays count their samples in floats, exact to 2^24, and a skip adds up to
    // 10^6 at once, so a ray may take at most 2^23 samples across the box, or its count would stop
    // growing (and the march never end). The box is the one the marcher walks: with render-time
    // noise, the tree's box widened by the amplitude on every side (marcher enter_box). (The same
    // float step and box corners the marcher uses.)
    void validate(const hypervolume& volume, const world_box& box) const
    {
        validate();
        constexpr double limit = double(1 << 23);
        const float step = step_factor * float(volume.smallest_voxel_side());
        const krs::vec3f lo(box.lo), hi(box.hi);
        const double samples = krs::length(krs::vec3d(hi - lo)) / double(step);
        if (!(samples < limit))
            throw krs::invalid_parameter("march_options.step_factor",
                                         "must leave at most 2^23 samples across the tree's box (its diagonal / (step_factor x the smallest "
                                         "voxel side) is " + std::to_string(samples) + ")",
                                         std::to_string(step_factor));
        const krs::vec3f pad = displacement.amplitude;
        const double widened = krs::length(krs::vec3d((hi + pad) - (lo - pad))) / double(step);
        if (!(widened < limit)) {
            // What fits: the amplitude scaled by t, with |diagonal| + 2 t |amplitude| below the
            // limit's length (the triangle inequality bounds the widened diagonal), a little less
            // so that float rounding keeps it under.
            const double room = (limit * double(step) - krs::length(krs::vec3d(hi - lo))) * 0.999;
            const double t = room > 0 ? room / (2 * krs::length(krs::vec3d(pad))) : 0;
            const krs::vec3d fits = krs::vec3d(pad) * t;
            throw krs::invalid_parameter("march_options.displacement.amplitude",
                                         "must leave at most 2^23 samples across the tree's box widened by it on every side (" +
                                             krs::detail::to_text(widened) + " samples of the march's step); " +
                                             (t > 0 ? "an amplitude of " + krs::detail::to_text(fits.x) + " " + krs::detail::to_text(fits.y) +
                                                          " " + krs::detail::to_text(fits.z) + " or less fits"
                                                    : "no amplitude fits"),
                                         krs::detail::to_text(pad.x) + " " + krs::detail::to_text(pad.y) + " " + krs::detail::to_text(pad.z));
        }
    }

    // The lights' directions made unit. Finite and non-zero: an infinite component normalized to
    // NaN, and every shadow ray then took a span of 1e31 that its float sample count never crossed.
    std::vector<krs::vec3f> light_directions() const
    {
        std::vector<krs::vec3f> out;
        out.reserve(lights.size());
        for (const auto& light : lights) out.push_back(krs::require_direction("march_options.lights.direction", light.direction));
        return out;
    }
};

} // namespace hypertree

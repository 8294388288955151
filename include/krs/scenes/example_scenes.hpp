#pragma once
// The example scenes, listed once: every program and test that names, counts or iterates scenes
// takes them from `example_scene_list` below. krs_scenes and krs_fractals render them (each with
// its own textures and, where a scene stands on one, ground), glsl_export writes the GLSL files of
// glsl/ from them, krs_export meshes them, krs_view shows their Shadertoy programs, and the tests
// check each one's GLSL on the CPU and the GPU, its Shadertoy frame and its mesh.
//
// An entry is a type with
//     static constexpr std::string_view name, summary;  // --scene NAME; --list-scenes prints both
//     static constexpr bool seeded;                     // draws random numbers (--seed applies)
//     static constexpr std::uint32_t default_seed;
//     static P parameters(std::uint32_t seed);          // the model's parameters (seeded entries)
//     static scene<F> build(std::uint32_t seed);        // krs/scenes/scene.hpp
// so a program that dresses a scene (a terrain under the forest, a sand plane under the rock)
// starts from the same parameters and camera as the GLSL and the tests. Adding a scene is one
// entry here plus its files in glsl/ (regenerated; docs/design.md, "Adding a scene").
//
// Every scene is the model alone, at the parameters of its example: every Shadertoy program stays
// a test frame llvmpipe renders at 160 x 120 in well under a second.
//
// Sequences (tree, forest, terrain, rock, grass, sponge) are shaded in kernel space and their
// snippets also define _locate and _shade; every other field (coral's noise warp, the mirrors'
// union of two clouds, KIFS, the shells) is shaded by its gradient with the scene's `albedo` and
// its snippets define only the distance (krs/glsl/shadertoy.hpp).

#include "krs/compose/union.hpp"
#include "krs/compose/warp.hpp"
#include "krs/fractal/kifs_presets.hpp"
#include "krs/fractal/shell_presets.hpp"
#include "krs/model/coral.hpp"
#include "krs/model/forest.hpp"
#include "krs/model/grass.hpp"
#include "krs/model/mirror_cloud.hpp"
#include "krs/model/terrain.hpp"
#include "krs/model/tree.hpp"
#include "krs/scenes/scene.hpp"

#include <array>
#include <cmath>
#include <cstdint>
#include <numbers>
#include <optional>
#include <string>
#include <string_view>
#include <tuple>
#include <type_traits>
#include <utility>
#include <vector>

namespace krs::scenes {

using glsl::shadertoy_options;

// The sun of krs_scenes' outdoor scenes and the light of krs_fractals' frames.
inline const vec3f scenes_sun{0.55f, 0.65f, -0.35f};
inline const vec3f fractals_light{0.5f, 0.8f, 0.35f};

// What an entry says about its random numbers (mixed in as a base).
template <std::uint32_t Seed>
struct seeded_by {
    static constexpr bool seeded = true;
    static constexpr std::uint32_t default_seed = Seed;
};
struct unseeded {
    static constexpr bool seeded = false;
    static constexpr std::uint32_t default_seed = 0;
};

// ---- krs_tree's tree ---------------------------------------------------------------------------

struct tree_scene : seeded_by<3> {
    static constexpr std::string_view name = "tree";
    static constexpr std::string_view summary = "a KRS tree of 12 branching levels on its ground (krs_tree's model)";
    static model::tree_style parameters(std::uint32_t seed = default_seed)
    {
        model::tree_style style;
        style.levels = 12;
        style.seed = seed;
        return style;
    }
    static scene<model::tree_sequence> build(std::uint32_t seed = default_seed)
    {
        const vec3f eye{4.6f, 3.6f, -9.2f};
        return {std::string(name), model::build_tree(model::grow_tree(parameters(seed))),
                pinhole_camera(eye, {0.0f, 3.3f, 0.0f}, {0, 1, 0}, 50.0f, frame_width, frame_height),
                shadertoy_options::lit({0.45f, 0.8f, -0.4f}, 40.0f), {0.0f, 3.0f, 0.0f}, {3.5f, 3.5f, 3.5f}};
    }
};

// ---- krs_scenes' scenes (the KRS paper's section 7) ----------------------------------------------

// krs_scenes stands these trees on a terrain folded by the forest's mirrors (section 7.2) in place
// of the flat ground plane here.
struct forest_scene : seeded_by<1> {
    static constexpr std::string_view name = "forest";
    static constexpr std::string_view summary = "2^6 trees placed by 6 mirrors, on a ground plane";
    static model::forest_parameters parameters(std::uint32_t seed = default_seed)
    {
        model::forest_parameters f;
        f.tree.levels = 9;
        f.tree.leaves_per_twig = 3;
        f.tree.leaf_radius = 0.12f;
        f.tree.seed = seed;
        f.doublings = 6;
        f.seed = seed;
        return f;
    }
    // The camera of a forest whose trees' bound is `b`.
    static pinhole_camera camera_for(const bounding_sphere& b)
    {
        const vec3f eye = b.center + vec3f{0.35f, 0.45f, -1.0f} * (1.1f * b.radius);
        return pinhole_camera(eye, b.center - vec3f{0, 0.15f * b.radius, 0}, {0, 1, 0}, 45.0f, frame_width,
                              frame_height)
            .with_orbit({.min_elevation = 8.0f}); // the trees' crowns reach the orbit's circle below 4 degrees
    }
    static scene<model::tree_sequence> build(std::uint32_t seed = default_seed)
    {
        const model::forest built = model::build_forest(parameters(seed));
        const bounding_sphere b = built.bound;
        return {std::string(name), built.sequence, camera_for(b), shadertoy_options::lit({0.4f, 0.85f, -0.3f}, 6.0f * b.radius),
                b.center, vec3f{b.radius, 0.5f * b.radius, b.radius}};
    }
};

struct terrain_scene : seeded_by<1> {
    static constexpr std::string_view name = "terrain";
    static constexpr std::string_view summary = "a terrain of plane kernels folded by 28 mirrors";
    static model::terrain_parameters parameters(std::uint32_t seed = default_seed)
    {
        model::terrain_parameters t;
        t.levels = 28;
        t.seed = seed;
        return t;
    }
    static scene<model::plane_sequence> build(std::uint32_t seed = default_seed)
    {
        return {std::string(name), model::build_terrain(parameters(seed)),
                pinhole_camera({-4.0f, 7.0f, -16.0f}, {6.0f, -1.0f, 10.0f}, {0, 1, 0}, 55.0f, frame_width, frame_height)
                    .with_orbit({.min_elevation = 14.0f}), // hills cross the orbit's circle up to 11 degrees
                shadertoy_options::lit({-0.6f, 0.45f, 0.4f}, 120.0f), {5.0f, 0.0f, 10.0f}, {15.0f, 4.0f, 15.0f}};
    }
};

// The rock of figure 7 (krs_scenes sets it on a sand plane).
struct rock_scene : seeded_by<1> {
    static constexpr std::string_view name = "rock";
    static constexpr std::string_view summary = "a faceted rock: 3 planes creased by 16 mirrors (figure 7)";
    static model::rock_parameters parameters(std::uint32_t seed = default_seed)
    {
        model::rock_parameters p;
        p.radius = 1.0f;
        p.center = {0, 0.6f, 0};
        p.folds = 16;
        p.seed = seed;
        return p;
    }
    static scene<model::plane_sequence> build(std::uint32_t seed = default_seed)
    {
        return {std::string(name), model::build_rock(parameters(seed)).sequence,
                pinhole_camera({3.4f, 2.9f, -4.7f}, {0, 0.6f, 0}, {0, 1, 0}, 40.0f, frame_width, frame_height),
                shadertoy_options::lit(scenes_sun, 20.0f), {0, 0.6f, 0}, {1.5f, 1.5f, 1.5f}};
    }
};

// Figure 5: one sphere multiplied by 9 mirrors into 512 spheres twice, side by side. On the left:
// the mirrors alternate between the x, y and z axes, and the copies form a lattice whose symmetry
// the eye sees at once. On the right: each mirror's normal is random, and the same 512 spheres
// read as a natural cluster. The scattered cloud is built at a seed sphere moved so its bound
// sits two gaps beyond the aligned one's along -x, the camera's right as it looks along +z (a
// cloud moves with its seed sphere: each mirror is placed from the copies so far).
using mirrors_field = union_of<model::sphere_cloud<axis_mirror>, model::sphere_cloud<mirror>>;
struct mirrors_scene : seeded_by<1> {
    static constexpr std::string_view name = "mirrors";
    static constexpr std::string_view summary = "512 spheres from 9 mirrors, axis-aligned beside random (figure 5)";
    static model::mirror_cloud_parameters parameters(std::uint32_t seed = default_seed)
    {
        model::mirror_cloud_parameters cloud;
        cloud.doublings = 9;
        cloud.gap = 0.3f;
        cloud.seed = seed;
        return cloud;
    }
    static scene<mirrors_field> build(std::uint32_t seed = default_seed)
    {
        const model::mirror_cloud_parameters cloud = parameters(seed);
        const auto aligned = model::build_aligned_cloud(cloud);
        const bounding_sphere a = aligned.bound();
        model::mirror_cloud_parameters moved = cloud;
        const bounding_sphere s0 = model::build_scattered_cloud(cloud).bound();
        const vec3f wanted = a.center - vec3f{a.radius + s0.radius + 2.0f * cloud.gap, 0, 0};
        moved.center = cloud.center + (wanted - s0.center);
        const auto scattered = model::build_scattered_cloud(moved);
        const bounding_sphere s = scattered.bound();
        const vec3f mid = (a.center + vec3f{a.radius, 0, 0} + s.center - vec3f{s.radius, 0, 0}) * 0.5f;
        const float half_width = 0.5f * (a.center.x + a.radius - (s.center.x - s.radius));
        const float half_depth = std::max(a.radius, s.radius);
        const vec3f eye = mid + normalize(vec3f{-0.15f, 0.4f, -1.0f}) * (1.7f * half_width);
        return {std::string(name), mirrors_field(aligned, scattered),
                pinhole_camera(eye, mid, {0, 1, 0}, 40.0f, frame_width, frame_height),
                shadertoy_options::lit(scenes_sun, 8.0f * half_width), mid,
                vec3f{half_width, half_depth, half_depth}, {0.80f, 0.52f, 0.30f}};
    }
};

using coral_field = lipschitz_warp<model::coral_sequence, noise_warp>;
struct coral_scene : seeded_by<1> {
    static constexpr std::string_view name = "coral";
    static constexpr std::string_view summary = "capsules and spheres of 11 levels bent by a Lipschitz noise warp";
    static model::coral_parameters parameters(std::uint32_t seed = default_seed)
    {
        model::coral_parameters p;
        p.levels = 11;
        p.seed = seed;
        return p;
    }
    static noise_warp warp() { return noise_warp(0.02f, 4.0f); }
    static scene<coral_field> build(std::uint32_t seed = default_seed)
    {
        const model::coral_sequence c = model::build_coral(parameters(seed));
        const bounding_sphere b = c.bound();
        shadertoy_options program = shadertoy_options::lit(scenes_sun, 8.0f * b.radius);
        return {std::string(name), coral_field(c, warp()),
                pinhole_camera(b.center + vec3f{0.3f, 0.35f, -1.0f} * (1.15f * b.radius), b.center, {0, 1, 0}, 42.0f,
                               frame_width, frame_height),
                program, b.center, vec3f{b.radius, b.radius, b.radius}, {0.85f, 0.45f, 0.35f}};
    }
};

// A Menger-like sponge of box kernels and axis mirrors (krs_scenes sets it on a plane).
struct sponge_scene : unseeded {
    static constexpr std::string_view name = "sponge";
    static constexpr std::string_view summary = "a Menger-like sponge: one box and 21 axis mirrors, 3 levels";
    static model::sponge_parameters parameters(std::uint32_t = default_seed)
    {
        model::sponge_parameters p;
        p.levels = 3;
        p.center = {0, 1, 0};
        return p;
    }
    static scene<model::sponge_sequence> build(std::uint32_t = default_seed)
    {
        return {std::string(name), model::build_sponge(parameters()).sequence,
                pinhole_camera({2.4f, 2.9f, -3.3f}, {0, 0.9f, 0}, {0, 1, 0}, 42.0f, frame_width, frame_height),
                shadertoy_options::lit({0.5f, 0.75f, -0.35f}, 60.0f), {0, 1, 0}, {1.5f, 1.5f, 1.5f}};
    }
};

struct grass_scene : seeded_by<1> {
    static constexpr std::string_view name = "grass";
    static constexpr std::string_view summary = "2^12 clumps of 10 blades scattered by unaligned mirrors";
    static model::grass_parameters parameters(std::uint32_t seed = default_seed)
    {
        model::grass_parameters p;
        p.doublings = 12;
        p.blades_per_clump = 10;
        p.seed = seed;
        return p;
    }
    static scene<model::grass_sequence> build(std::uint32_t seed = default_seed)
    {
        const model::grass_parameters p = parameters(seed);
        const model::grass_field built = model::build_grass(p);
        // From beside the first clump (at the origin), looking into the field.
        vec3f into = built.bound.center;
        into.y = 0;
        into = length(into) > 1e-3f ? normalize(into) : vec3f{0, 0, 1};
        const vec3f eye = vec3f{0, p.ground_height + 0.7f, 0} - into * 0.8f;
        // Blades green (the middle of krs_scenes' blade colours), the ground its soil.
        static_assert(std::is_same_v<model::grass_sequence, sequence<torus_capsule, plane>>);
        return {std::string(name), built.sequence,
                pinhole_camera(eye, eye + into * 3.0f - vec3f{0, 0.9f, 0}, {0, 1, 0}, 50.0f, frame_width, frame_height)
                    .with_orbit({.min_elevation = 10.0f}), // blades reach the orbit's circle below 6 degrees
                shadertoy_options::lit(scenes_sun, 40.0f), eye + into * 3.0f, {2.0f, 0.5f, 2.0f}, {},
                {{0.26f, 0.385f, 0.115f}, {0.30f, 0.26f, 0.16f}}};
    }
};

// ---- krs_fractals' frames ----------------------------------------------------------------------

// A KIFS gallery frame: its preset, eye and target, 40 degrees, its albedo.
template <class F>
scene<F> kifs_scene(std::string_view name, const F& f, const vec3f& eye, const vec3f& target, const vec3f& albedo,
                    const vec3f& sample_half)
{
    return {std::string(name), f, pinhole_camera(eye, target, {0, 1, 0}, 40.0f, frame_width, frame_height),
            shadertoy_options::lit(fractals_light, 20.0f), {0, 0, 0}, sample_half, albedo};
}
struct kifs_square_scene : unseeded {
    static constexpr std::string_view name = "kifs_square";
    static constexpr std::string_view summary = "KIFS: the square-on-square fractal as a relief, 6 folds";
    static scene<square_fractal> build(std::uint32_t = default_seed)
    {
        return kifs_scene(name, make_square_fractal(6, 0.3f), {0.9f, 1.6f, -4.2f}, {0, 0, 0}, {0.85f, 0.55f, 0.30f},
                          {3.2f, 3.2f, 0.6f});
    }
};
struct kifs_cube_scene : unseeded {
    static constexpr std::string_view name = "kifs_cube";
    static constexpr std::string_view summary = "KIFS: the square fractal's cube analogue, 5 folds";
    static scene<cube_fractal> build(std::uint32_t = default_seed)
    {
        return kifs_scene(name, make_cube_fractal(5), {2.6f, 2.2f, -3.2f}, {0, 0, 0}, {0.45f, 0.65f, 0.85f},
                          {3.2f, 3.2f, 3.2f});
    }
};
struct kifs_menger_scene : unseeded {
    static constexpr std::string_view name = "kifs_menger";
    static constexpr std::string_view summary = "KIFS: the Menger sponge, 4 iterations";
    static scene<menger_sponge> build(std::uint32_t = default_seed)
    {
        return kifs_scene(name, make_menger_sponge(4), {2.2f, 1.8f, -2.8f}, {0, 0, 0}, {0.80f, 0.78f, 0.72f},
                          {1.3f, 1.3f, 1.3f});
    }
};
struct kifs_sierpinski_scene : unseeded {
    static constexpr std::string_view name = "kifs_sierpinski";
    static constexpr std::string_view summary = "KIFS: the Sierpinski tetrahedron, 9 iterations";
    static scene<sierpinski_tetrahedron> build(std::uint32_t = default_seed)
    {
        return kifs_scene(name, make_sierpinski_tetrahedron(9), {2.2f, 1.2f, -3.0f}, {0, 0, 0}, {0.90f, 0.70f, 0.35f},
                          {1.3f, 1.3f, 1.3f});
    }
};
struct kifs_koch_scene : unseeded {
    static constexpr std::string_view name = "kifs_koch";
    static constexpr std::string_view summary = "KIFS: a Koch curve of 6 iterations as a thin tube";
    static scene<koch_curve> build(std::uint32_t = default_seed)
    {
        return kifs_scene(name, make_koch_curve(6, 0.01f), {0.0f, 0.45f, -1.6f}, {0, 0.3f, 0}, {0.55f, 0.85f, 0.55f},
                          {1.3f, 0.6f, 0.2f});
    }
};

// ---- log-spherical scenes (krs/fractal/shell_presets.hpp) ---------------------------------------

// The recursive lotus (8 petals a shell, one shell per e-fold of radius), looking down its axis z
// (the view's vertical, so iTime orbits about it) from 75 degrees above the petals' plane. Petals
// rise at 15 to 55 degrees (58.7 with their radius) at every scale, so the cone above 60 degrees
// is empty at every radius: the eye, orbiting and tilted within [65, 85] degrees, is outside
// every shell's petals.
struct lotus_scene : unseeded {
    static constexpr std::string_view name = "lotus";
    static constexpr std::string_view summary = "the recursive lotus: 8 petals a shell, one shell per e-fold, no loop";
    static scene<recursive_lotus> build(std::uint32_t = default_seed)
    {
        const double elevation = 75.0 * std::numbers::pi / 180.0, radius = 3.3;
        const vec3f eye = vec3f(vec3d{0.0, -std::cos(elevation), std::sin(elevation)} * radius);
        return {std::string(name), make_recursive_lotus(1.0f, 8),
                pinhole_camera(eye, {0, 0, 0}, {0, 0, 1}, 50.0f, frame_width, frame_height)
                    .with_orbit({.min_elevation = 65.0f}),
                shadertoy_options::lit({0.35f, -0.45f, 0.82f}, 20.0f), {0, 0, 0}, {2.0f, 2.0f, 2.0f},
                {0.90f, 0.55f, 0.65f}};
    }
};

// The first frame of krs_fractals' zoom (scale 10^0): along an edge direction, where a cone is
// free of the shell's cubes at every scale. The box's faces x, y, z = +-3.45 cross no cube, so a
// mesh of it closes: shell 1's diagonal cubes reach 3.402 on each axis, its axis cubes start at
// 3.667 (shell k's cubes, half size h s^k with h = 0.2996, are centred s^k sqrt(s) from the origin,
// s = e), and the padding cell of a mesh at resolution 32 or more stays short of them.
struct cube_singularity_scene : unseeded {
    static constexpr std::string_view name = "cube_singularity";
    static constexpr std::string_view summary = "cubes on log-spherical shells shrinking into the origin";
    static scene<cube_singularity> build(std::uint32_t = default_seed)
    {
        return {std::string(name), make_cube_singularity(1.0f),
                pinhole_camera({-2.2f, 0.35f, -2.2f}, {0, 0, 0}, {0, 1, 0}, 50.0f, frame_width, frame_height)
                    .with_orbit({.max_elevation = 30.0f}), // the diagonal's cubes (35.3 degrees) hold the eye's radius near 36
                shadertoy_options::lit(fractals_light, 20.0f), {0, 0, 0}, {3.45f, 3.45f, 3.45f},
                {0.75f, 0.50f, 0.85f}};
    }
};

// ---- the list ------------------------------------------------------------------------------------

// Every example scene, in the order programs list and render them.
using example_scene_list =
    std::tuple<tree_scene, forest_scene, terrain_scene, rock_scene, mirrors_scene, coral_scene, grass_scene,
               sponge_scene, kifs_square_scene, kifs_cube_scene, kifs_menger_scene, kifs_sierpinski_scene,
               kifs_koch_scene, lotus_scene, cube_singularity_scene>;
inline constexpr std::size_t scene_count = std::tuple_size_v<example_scene_list>;
// The field type of an entry's scene.
template <class E>
using field_of = decltype(E::build(E::default_seed).field);

namespace detail {
template <class Fn, std::size_t... I>
constexpr void for_each_entry(Fn& fn, std::index_sequence<I...>)
{
    (fn.template operator()<std::tuple_element_t<I, example_scene_list>>(), ...);
}
} // namespace detail

// fn.template operator()<Entry>() for each entry of the list, in order (no scene is built).
template <class Fn>
constexpr void for_each_scene_entry(Fn&& fn)
{
    detail::for_each_entry(fn, std::make_index_sequence<scene_count>{});
}

// The names in the list's order (a program's --scene choices), known at compile time.
inline constexpr std::array<std::string_view, scene_count> scene_names = [] {
    std::array<std::string_view, scene_count> names{};
    std::size_t i = 0;
    for_each_scene_entry([&]<class E>() { names[i++] = E::name; });
    return names;
}();

// Calls fn(scene) for each example scene built at its default seed, in the list's order.
template <class Fn>
void for_each_scene(Fn&& fn)
{
    for_each_scene_entry([&]<class E>() { fn(E::build(E::default_seed)); });
}

// fn(scene) for the scene named `name`, built at `seed` (its default when none): false when no
// scene has that name.
template <class Fn>
bool with_scene(std::string_view name, std::optional<std::uint32_t> seed, Fn&& fn)
{
    bool found = false;
    for_each_scene_entry([&]<class E>() {
        if (found || E::name != name) return;
        found = true;
        fn(E::build(seed.value_or(E::default_seed)));
    });
    return found;
}

} // namespace krs::scenes

#pragma once
// The example scenes whose GLSL ships in the repository's glsl/ folder, one per scene of the
// examples: the tree of krs_tree; from krs_scenes the forest, terrain, rock, coral, grass and
// sponge (not its mirrors figure, two clouds of spheres side by side); from krs_fractals the five
// KIFS presets (kifs_square, kifs_cube, kifs_menger, kifs_sierpinski, kifs_koch) and the cube
// singularity; and the recursive lotus of krs/fractal/shell_presets.hpp. Each is built with the
// model function and, where practical, the parameters of its example, with a camera and light for
// its Shadertoy program and the region the tests sample. Where an example puts a scene on a
// ground plane, bounds it for speed or textures it with noise, the shipped scene is the model
// alone: the snippets then hold what a user would reuse, and every Shadertoy program stays a test
// frame llvmpipe renders at 160 x 120 in well under a second. The forest differs most: 2^5 trees
// (krs_scenes: 2^6) on the forest's own flat ground plane (krs_scenes: a terrain folded by the
// forest's mirrors, traced as a second sequence in a union).
//
// Sequences (tree, forest, terrain, rock, grass, sponge) are shaded in kernel space and their
// snippets also define _locate and _shade; every other field (coral's noise warp, KIFS, the
// shells) is shaded by its gradient with the scene's `albedo` and its snippets define only the
// distance (krs/glsl/shadertoy.hpp).
//
// examples/glsl_export.cpp writes the files from these; a test regenerates them in memory and
// compares bytes, so the files cannot go stale.

#include "krs/compose/warp.hpp"
#include "krs/fractal/kifs_presets.hpp"
#include "krs/fractal/shell_presets.hpp"
#include "krs/glsl/emitter.hpp"
#include "krs/glsl/shadertoy.hpp"
#include "krs/model/coral.hpp"
#include "krs/model/forest.hpp"
#include "krs/model/grass.hpp"
#include "krs/model/terrain.hpp"
#include "krs/model/tree.hpp"

#include <algorithm>
#include <array>
#include <cmath>
#include <numbers>
#include <type_traits>
#include <string>
#include <string_view>
#include <vector>

namespace krs::glsl::examples {

template <class S>
struct scene {
    std::string name;
    S field;
    glsl::view camera;
    vec3f sample_center{}; // tests sample points in the box center +- sample_half
    vec3f sample_half{1, 1, 1};
    vec3f albedo{0.7f, 0.68f, 0.64f}; // of a field shaded by its gradient (sequences: by kernel type)
    std::vector<vec3f> palette{};      // a sequence's albedo per kernel type (glsl::palette_of; empty: by type)
    float extent() const { return length(sample_half); }
};

inline scene<model::tree_sequence> tree()
{
    model::tree_style style;
    style.levels = 12;
    style.seed = 3;
    model::tree_sequence s = model::build_tree(model::grow_tree(style));
    const vec3f eye{4.6f, 3.6f, -9.2f};
    return {"tree", s, view::look_at(eye, {0.0f, 3.3f, 0.0f}, {0, 1, 0}, 50.0f, {0.45f, 0.8f, -0.4f}, 40.0f),
            {0.0f, 3.0f, 0.0f}, {3.5f, 3.5f, 3.5f}};
}

inline scene<model::tree_sequence> forest()
{
    model::forest_parameters f;
    f.tree.levels = 9;
    f.tree.leaves_per_twig = 3;
    f.tree.leaf_radius = 0.12f;
    f.doublings = 5;
    const model::forest built = model::build_forest(f);
    const bounding_sphere b = built.bound;
    const vec3f look = b.center;
    const vec3f eye = look + vec3f{0.35f, 0.45f, -1.0f} * (1.1f * b.radius);
    scene<model::tree_sequence> s{"forest", built.sequence,
                                  view::look_at(eye, look - vec3f{0, 0.15f * b.radius, 0}, {0, 1, 0}, 45.0f,
                                                {0.4f, 0.85f, -0.3f}, 6.0f * b.radius),
                                  b.center, vec3f{b.radius, 0.5f * b.radius, b.radius}};
    s.camera.min_elevation = 8.0f; // the trees' crowns reach the orbit's circle below 4 degrees
    return s;
}

inline scene<model::plane_sequence> terrain()
{
    model::terrain_parameters t;
    t.levels = 28;
    model::plane_sequence s = model::build_terrain(t);
    scene<model::plane_sequence> built{"terrain", s,
                                       view::look_at({-4.0f, 7.0f, -16.0f}, {6.0f, -1.0f, 10.0f}, {0, 1, 0}, 55.0f,
                                                     {-0.6f, 0.45f, 0.4f}, 120.0f),
                                       {5.0f, 0.0f, 10.0f}, {15.0f, 4.0f, 15.0f}};
    built.camera.min_elevation = 14.0f; // hills cross the orbit's circle up to 11 degrees
    return built;
}

inline scene<model::sponge_sequence> sponge()
{
    model::sponge_parameters p;
    p.levels = 3;
    p.center = {0, 1, 0};
    model::sponge built = model::build_sponge(p);
    return {"sponge", built.sequence,
            view::look_at({2.4f, 2.9f, -3.3f}, {0, 0.9f, 0}, {0, 1, 0}, 42.0f, {0.5f, 0.75f, -0.35f}, 60.0f),
            {0, 1, 0}, {1.5f, 1.5f, 1.5f}};
}

// The sun of krs_scenes and the light of krs_fractals.
inline const vec3f scenes_sun{0.55f, 0.65f, -0.35f};
inline const vec3f fractals_light{0.5f, 0.8f, 0.35f};

inline scene<model::plane_sequence> rock()
{
    model::rock_parameters p; // as krs_scenes' rock (figure 7), without its ground plane
    p.radius = 1.0f;
    p.center = {0, 0.6f, 0};
    p.folds = 16;
    const model::rock built = model::build_rock(p);
    return {"rock", built.sequence,
            view::look_at({3.4f, 2.9f, -4.7f}, {0, 0.6f, 0}, {0, 1, 0}, 40.0f, scenes_sun, 20.0f), {0, 0.6f, 0},
            {1.5f, 1.5f, 1.5f}};
}

using coral_field = lipschitz_warp<model::coral_sequence, noise_warp>;
inline scene<coral_field> coral()
{
    model::coral_parameters p; // as krs_scenes' coral, without its ground plane
    p.levels = 11;
    const model::coral_sequence c = model::build_coral(p);
    const bounding_sphere b = c.bound();
    return {"coral", coral_field(c, noise_warp(0.02f, 4.0f)),
            view::look_at(b.center + vec3f{0.3f, 0.35f, -1.0f} * (1.15f * b.radius), b.center, {0, 1, 0}, 42.0f,
                          scenes_sun, 8.0f * b.radius),
            b.center, vec3f{b.radius, b.radius, b.radius}, {0.85f, 0.45f, 0.35f}};
}

inline scene<model::grass_sequence> grass()
{
    model::grass_parameters p; // as krs_scenes' grass
    p.doublings = 12;
    p.blades_per_clump = 10;
    const model::grass_field built = model::build_grass(p);
    // From beside the first clump (at the origin), looking into the field.
    vec3f into = built.bound.center;
    into.y = 0;
    into = length(into) > 1e-3f ? normalize(into) : vec3f{0, 0, 1};
    const vec3f eye = vec3f{0, p.ground_height + 0.7f, 0} - into * 0.8f;
    // Blades green (the middle of krs_scenes' blade colours), the ground its soil.
    static_assert(std::is_same_v<model::grass_sequence, sequence<torus_capsule, plane>>);
    scene<model::grass_sequence> s{
        "grass", built.sequence,
        view::look_at(eye, eye + into * 3.0f - vec3f{0, 0.9f, 0}, {0, 1, 0}, 50.0f, scenes_sun, 40.0f),
        eye + into * 3.0f, {2.0f, 0.5f, 2.0f}, {}, {{0.26f, 0.385f, 0.115f}, {0.30f, 0.26f, 0.16f}}};
    s.camera.min_elevation = 10.0f; // blades reach the orbit's circle below 6 degrees
    return s;
}

// A KIFS gallery frame of krs_fractals: its preset, eye and target, 40 degrees, its albedo.
template <class F>
scene<F> kifs_scene(const std::string& name, const F& f, const vec3f& eye, const vec3f& target, const vec3f& albedo,
                    const vec3f& sample_half)
{
    return {name, f, view::look_at(eye, target, {0, 1, 0}, 40.0f, fractals_light, 20.0f), {0, 0, 0}, sample_half, albedo};
}
inline scene<square_fractal> kifs_square()
{
    return kifs_scene("kifs_square", make_square_fractal(6, 0.3f), {0.9f, 1.6f, -4.2f}, {0, 0, 0},
                      {0.85f, 0.55f, 0.30f}, {3.2f, 3.2f, 0.6f});
}
inline scene<cube_fractal> kifs_cube()
{
    return kifs_scene("kifs_cube", make_cube_fractal(5), {2.6f, 2.2f, -3.2f}, {0, 0, 0}, {0.45f, 0.65f, 0.85f},
                      {3.2f, 3.2f, 3.2f});
}
inline scene<menger_sponge> kifs_menger()
{
    return kifs_scene("kifs_menger", make_menger_sponge(4), {2.2f, 1.8f, -2.8f}, {0, 0, 0}, {0.80f, 0.78f, 0.72f},
                      {1.3f, 1.3f, 1.3f});
}
inline scene<sierpinski_tetrahedron> kifs_sierpinski()
{
    return kifs_scene("kifs_sierpinski", make_sierpinski_tetrahedron(9), {2.2f, 1.2f, -3.0f}, {0, 0, 0},
                      {0.90f, 0.70f, 0.35f}, {1.3f, 1.3f, 1.3f});
}
inline scene<koch_curve> kifs_koch()
{
    return kifs_scene("kifs_koch", make_koch_curve(6, 0.01f), {0.0f, 0.45f, -1.6f}, {0, 0.3f, 0},
                      {0.55f, 0.85f, 0.55f}, {1.3f, 0.6f, 0.2f});
}

// The first frame of krs_fractals' zoom (scale 10^0): along an edge direction, where a cone is
// free of the shell's cubes at every scale. The box's faces x, y, z = +-3.45 cross no cube, so a
// mesh of it closes: shell 1's diagonal cubes reach 3.402 on each axis, its axis cubes start at
// 3.667 (shell k's cubes, half size h s^k with h = 0.2996, are centred s^k sqrt(s) from the origin,
// s = e), and the padding cell of a mesh at resolution 32 or more stays short of them.
inline scene<cube_singularity> cube_singularity_scene()
{
    scene<cube_singularity> s{"cube_singularity", make_cube_singularity(1.0f),
                              view::look_at({-2.2f, 0.35f, -2.2f}, {0, 0, 0}, {0, 1, 0}, 50.0f, fractals_light, 20.0f),
                              {0, 0, 0}, {3.45f, 3.45f, 3.45f}, {0.75f, 0.50f, 0.85f}};
    s.camera.max_elevation = 30.0f; // the diagonal's cubes (35.3 degrees) hold the eye's radius near 36
    return s;
}

// The recursive lotus (8 petals a shell, one shell per e-fold of radius), looking down its axis z
// (the view's vertical, so iTime orbits about it) from 75 degrees above the petals' plane. Petals
// rise at 15 to 55 degrees (58.7 with their radius) at every scale, so the cone above 60 degrees
// is empty at every radius: the eye, orbiting and tilted within [65, 85] degrees, is outside
// every shell's petals.
inline scene<recursive_lotus> lotus()
{
    const double elevation = 75.0 * std::numbers::pi / 180.0, radius = 3.3;
    const vec3f eye = vec3f(vec3d{0.0, -std::cos(elevation), std::sin(elevation)} * radius);
    scene<recursive_lotus> s{"lotus", make_recursive_lotus(1.0f, 8),
                             view::look_at(eye, {0, 0, 0}, {0, 0, 1}, 50.0f, {0.35f, -0.45f, 0.82f}, 20.0f),
                             {0, 0, 0}, {2.0f, 2.0f, 2.0f}, {0.90f, 0.55f, 0.65f}};
    s.camera.min_elevation = 65.0f;
    return s;
}

// Calls fn(scene) for each example scene, in the order of the names below.
template <class Fn>
void for_each_scene(Fn&& fn)
{
    fn(tree());
    fn(forest());
    fn(terrain());
    fn(rock());
    fn(coral());
    fn(grass());
    fn(sponge());
    fn(kifs_square());
    fn(kifs_cube());
    fn(kifs_menger());
    fn(kifs_sierpinski());
    fn(kifs_koch());
    fn(lotus());
    fn(cube_singularity_scene());
}
// The scenes' names in for_each_scene's order (glsl_export's --scene choices); building every
// scene to read its name takes a fraction of a second and keeps one list of scenes.
inline std::vector<std::string> scene_names()
{
    std::vector<std::string> names;
    for_each_scene([&](const auto& s) { names.push_back(s.name); });
    return names;
}

// The files of glsl/ per scene: (suffix, target, mode). A suffix of ".shadertoy.glsl" is the
// whole Shadertoy program; the others are snippets without a #version line.
struct file_kind {
    std::string_view suffix;
    glsl::target target;
    data_mode mode;
};
inline constexpr std::array<file_kind, 5> files{{
    {".glsl", target::glsl330, data_mode::constants}, // also valid as 450 (no version line)
    {".es300.glsl", target::es300, data_mode::constants},
    {".buffer330.glsl", target::glsl330, data_mode::buffer},
    {".buffer450.glsl", target::glsl450, data_mode::buffer},
    {".shadertoy.glsl", target::shadertoy, data_mode::constants},
}};
// The kind of the whole Shadertoy program among them.
inline constexpr file_kind shadertoy_file = *std::ranges::find(files, target::shadertoy, &file_kind::target);

// The text of one file for one scene (a snippet's names start with `prefix`; a Shadertoy program
// is a whole program and keeps krs_).
template <class S>
std::string file_text(const scene<S>& s, const file_kind& kind, const std::string& prefix = "krs_")
{
    if (kind.target == target::shadertoy) {
        if constexpr (kernel_shaded<S>) return shadertoy(s.field, s.camera, s.name, s.palette);
        else return shadertoy(s.field, s.camera, s.name, s.albedo);
    }
    emitter e({.target = kind.target, .mode = kind.mode, .data_name = s.name + "_data", .prefix = prefix});
    e.add(s.field, s.name);
    return e.source(false);
}

// The CPU reference of the scene's Shadertoy program (krs::glsl::render_reference) seen through
// `camera` (s.camera is the program's at iTime = 0 and no drag; shadertoy_view gives the others):
// RGBA floats, rows bottom-up. `clip_to_box` false traces primary rays unclipped.
template <class S>
std::vector<float> reference_frame(const scene<S>& s, const view& camera, int width, int height,
                                   bool clip_to_box = true)
{
    if constexpr (kernel_shaded<S>) return render_reference(s.field, camera, width, height, clip_to_box, s.palette);
    else return render_reference(s.field, camera, s.albedo, width, height, clip_to_box);
}

// The sky alone through the scene's camera (the same view with nothing in reach): a pixel shows
// the scene where reference_frame differs from this.
template <class S>
std::vector<float> sky_frame(const scene<S>& s, int width, int height)
{
    view empty = s.camera;
    empty.max_distance = 1e-6f;
    return reference_frame(s, empty, width, height, false);
}

} // namespace krs::glsl::examples

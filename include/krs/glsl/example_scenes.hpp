#pragma once
// The example scenes whose GLSL ships in the repository's glsl/ folder (tree, forest, terrain,
// sponge), with a camera and light for their Shadertoy programs and the region the tests sample.
// examples/glsl_export.cpp writes the files from these; a test regenerates them in memory and
// compares bytes, so the files cannot go stale.

#include "krs/glsl/emitter.hpp"
#include "krs/glsl/shadertoy.hpp"
#include "krs/model/coral.hpp"
#include "krs/model/forest.hpp"
#include "krs/model/terrain.hpp"
#include "krs/model/tree.hpp"

#include <array>
#include <string>
#include <string_view>

namespace krs::glsl::examples {

template <class S>
struct scene {
    std::string name;
    S field;
    glsl::view camera;
    vec3f sample_center{}; // tests sample points in the box center +- sample_half
    vec3f sample_half{1, 1, 1};
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
    return {"forest", built.sequence,
            view::look_at(eye, look - vec3f{0, 0.15f * b.radius, 0}, {0, 1, 0}, 45.0f, {0.4f, 0.85f, -0.3f},
                          6.0f * b.radius),
            b.center, vec3f{b.radius, 0.5f * b.radius, b.radius}};
}

inline scene<model::plane_sequence> terrain()
{
    model::terrain_parameters t;
    t.levels = 28;
    model::plane_sequence s = model::build_terrain(t);
    return {"terrain", s, view::look_at({-4.0f, 7.0f, -16.0f}, {6.0f, -1.0f, 10.0f}, {0, 1, 0}, 55.0f,
                                        {-0.6f, 0.45f, 0.4f}, 120.0f),
            {5.0f, 0.0f, 10.0f}, {15.0f, 4.0f, 15.0f}};
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

// Calls fn(scene) for each example scene.
template <class Fn>
void for_each_scene(Fn&& fn)
{
    fn(tree());
    fn(forest());
    fn(terrain());
    fn(sponge());
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

// The text of one file for one scene (a snippet's names start with `prefix`; a Shadertoy program
// is a whole program and keeps krs_).
template <class S>
std::string file_text(const scene<S>& s, const file_kind& kind, const std::string& prefix = "krs_")
{
    if (kind.target == target::shadertoy) return shadertoy(s.field, s.camera, s.name);
    emitter e({kind.target, kind.mode, s.name + "_data", 0, prefix});
    e.add(s.field, s.name);
    return e.source(false);
}

} // namespace krs::glsl::examples

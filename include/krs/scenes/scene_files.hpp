#pragma once
// The files of glsl/ for each example scene, and the CPU reference of its Shadertoy program.
// examples/glsl_export.cpp writes the files from these; a test regenerates them in memory and
// compares bytes with the folder, and checks the folder holds no other scene files, so the files
// can neither go stale nor be forgotten.

#include "krs/glsl/emitter.hpp"
#include "krs/glsl/shadertoy.hpp"
#include "krs/scenes/scene.hpp"

#include <algorithm>
#include <array>
#include <string>
#include <string_view>
#include <vector>

namespace krs::scenes {

// The files of glsl/ per scene: (suffix, target, mode). A suffix of ".shadertoy.glsl" is the
// whole Shadertoy program; the others are snippets without a #version line.
struct file_kind {
    std::string_view suffix;
    glsl::target target;
    glsl::data_mode mode;
};
inline constexpr std::array<file_kind, 5> files{{
    {".glsl", glsl::target::glsl330, glsl::data_mode::constants}, // also valid as 450 (no version line)
    {".es300.glsl", glsl::target::es300, glsl::data_mode::constants},
    {".buffer330.glsl", glsl::target::glsl330, glsl::data_mode::buffer},
    {".buffer450.glsl", glsl::target::glsl450, glsl::data_mode::buffer},
    {".shadertoy.glsl", glsl::target::shadertoy, glsl::data_mode::constants},
}};
// The kind of the whole Shadertoy program among them.
inline constexpr file_kind shadertoy_file = *std::ranges::find(files, glsl::target::shadertoy, &file_kind::target);

// The text of one file for one scene (a snippet's names start with `prefix`; a Shadertoy program
// is a whole program and keeps krs_).
template <class S>
std::string file_text(const scene<S>& s, const file_kind& kind, const std::string& prefix = "krs_")
{
    if (kind.target == glsl::target::shadertoy) {
        if constexpr (glsl::kernel_shaded<S>) return glsl::shadertoy(s.field, s.camera, s.program, s.name, s.palette);
        else return glsl::shadertoy(s.field, s.camera, s.program, s.name, s.albedo);
    }
    glsl::emitter e({.target = kind.target, .mode = kind.mode, .data_name = s.name + "_data", .prefix = prefix});
    e.add(s.field, s.name);
    return e.source(false);
}

// The CPU reference of the scene's Shadertoy program (krs::glsl::render_reference) seen through
// `camera` (s.camera is the program's at iTime = 0 and no drag; s.camera.turned gives the others)
// and with `program` (s.program unless given): RGBA floats, rows bottom-up. `clip_to_box` false
// traces primary rays unclipped.
template <class S>
std::vector<float> reference_frame(const scene<S>& s, const pinhole_camera& camera,
                                   const glsl::shadertoy_options& program, int width, int height,
                                   bool clip_to_box = true)
{
    if constexpr (glsl::kernel_shaded<S>)
        return glsl::render_reference(s.field, camera, program, width, height, clip_to_box, s.palette);
    else
        return glsl::render_reference(s.field, camera, program, s.albedo, width, height, clip_to_box);
}
template <class S>
std::vector<float> reference_frame(const scene<S>& s, const pinhole_camera& camera, int width, int height,
                                   bool clip_to_box = true)
{
    return reference_frame(s, camera, s.program, width, height, clip_to_box);
}

// The sky alone through the scene's camera (the same view with nothing in reach): a pixel shows
// the scene where reference_frame differs from this.
template <class S>
std::vector<float> sky_frame(const scene<S>& s, int width, int height)
{
    glsl::shadertoy_options empty = s.program;
    empty.max_distance = 1e-6f;
    return reference_frame(s, s.camera, empty, width, height, false);
}

} // namespace krs::scenes

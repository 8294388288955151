#pragma once
// What an example scene is: a field with the view, light and colours the examples and its Shadertoy
// program show it with, and the box the tests sample it in. krs/scenes/example_scenes.hpp builds
// one per entry of its list; the examples render these (krs_scenes and krs_fractals dress them with
// their own textures and ground), glsl_export writes their GLSL, krs_export their meshes, and the
// tests check the GLSL, the meshes and the frames of each.

#include "krs/glsl/shadertoy.hpp"
#include "krs/trace/camera.hpp"

#include <string>
#include <vector>

namespace krs::scenes {

// The size of the scenes' cameras: glsl_export's default frame (a Shadertoy program takes its
// frame's size from iResolution; a program rendering another size asks camera.with_size).
inline constexpr int frame_width = 640, frame_height = 360;

template <class F>
struct scene {
    std::string name;
    F field;
    pinhole_camera camera;           // at iTime = 0 and no drag (camera.turned: the others)
    glsl::shadertoy_options program; // light, march limits and shading widths, CPU and GPU alike
    vec3f sample_center{};           // the scene's box: center +- sample_half (tests, meshes)
    vec3f sample_half{1, 1, 1};
    vec3f albedo{0.7f, 0.68f, 0.64f}; // of a field shaded by its gradient (sequences: by kernel type)
    std::vector<vec3f> palette{};     // a sequence's albedo per kernel type (glsl::palette_of; empty: by type)
    float extent() const { return length(sample_half); }
};

} // namespace krs::scenes

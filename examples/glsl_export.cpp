// glsl_export: writes an example scene's GLSL (krs::glsl) to a file or stdout, or the CPU
// reference frame of its Shadertoy program to a PNG file.
//
//   glsl_export --scene NAME --target 330|450|es300|shadertoy --mode constants|buffer|uniform-buffer
//               [--output FILE]
//   glsl_export --scene NAME --reference FILE.png [--width W] [--height H]
//   glsl_export --output-dir DIR   regenerates every file of the repository's glsl/ folder
//                                  (--all DIR: its older spelling)
//
// NAME is one of the scenes of krs/scenes/example_scenes.hpp (--list-scenes prints them; --seed S
// builds the scenes that draw random numbers at seed S instead of their own). Snippets have no #version line (paste them after your own); a shadertoy
// target writes the whole program for Shadertoy's Image tab. --reference renders that program's
// math in C++ (krs::glsl::render_reference) at W x H (default 640 x 360) as the program shows it
// at iTime = 0 with no mouse drag: hold a GPU frame of the program at the same size against it
// (8-bit values, as a framebuffer stores them). With --output as well, both files are written, or
// neither: both are made in memory first, and a file whose writing fails is removed.

#include "krs/scenes/example_scenes.hpp"
#include "krs/scenes/scene_files.hpp"

#include "support/command_line.hpp"
#include "support/common_options.hpp"
#include "support/error_message.hpp"
#include "support/scene_choice.hpp"
#include "support/example_io.hpp"
#include "support/output_path.hpp"

#include <algorithm>
#include <cctype>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <iostream>
#include <string>

namespace {

bool to_stdout(const std::string& path) { return path.empty() || path == "-"; }

// The extensions a GLSL text file may have (--output).
const std::vector<std::string> glsl_extensions{".glsl", ".frag"};

// Writes text to path (empty or -: stdout) through krs::write_file: whole or not at all, an
// earlier file untouched when it fails.
bool write(const std::string& path, const std::string& text)
{
    if (to_stdout(path)) {
        std::cout << text << std::flush;
        if (std::cout) return true;
        std::fprintf(stderr, "glsl_export: cannot write to stdout\n");
        return false;
    }
    try {
        krs::write_file("", path, text);
        return true;
    } catch (const std::exception& e) {
        std::fprintf(stderr, "glsl_export: %s\n", example::message_of(e).c_str());
        return false;
    }
}

// RGBA rows bottom-up (as the GPU reads them back) to the bytes of an RGB PNG, top row first. The
// values are already encoded for display (the program takes sqrt of the colour), so no gamma is
// applied, and each is stored as an 8-bit framebuffer stores it (krs::glsl::framebuffer_byte: ties
// to even), handed to png_bytes as that byte over 255 (which its round(255 v) gives back exactly);
// alpha is 1 everywhere and left out.
std::vector<unsigned char> reference_png(const std::vector<float>& rgba, int width, int height)
{
    std::vector<float> rgb(std::size_t(width) * std::size_t(height) * 3);
    for (int y = 0; y < height; ++y)
        for (int x = 0; x < width; ++x)
            for (int c = 0; c < 3; ++c)
                rgb[(std::size_t(height - 1 - y) * std::size_t(width) + std::size_t(x)) * 3 + std::size_t(c)] =
                    float(krs::glsl::framebuffer_byte(
                        rgba[(std::size_t(y) * std::size_t(width) + std::size_t(x)) * 4 + std::size_t(c)])) /
                    255.0f;
    return example::png_bytes(width, height, rgb, 1.0f);
}

} // namespace

int main(int argc, char** argv)
{
    namespace ex = krs::scenes;
    std::string scene = "tree", target = "450", mode = "constants", output, output_dir;
    example::command_line args("glsl_export", "Writes an example scene's GLSL to a file or stdout; --output-dir DIR "
                                              "regenerates every file of the repository's glsl/ folder.");
    const example::scene_choice scenes(args, scene, example::all_scene_names(), "the scene");
    args.choice("--target", target, {"330", "450", "es300", "shadertoy"}, "the GLSL dialect");
    args.choice("--mode", mode, {"constants", "buffer", "uniform-buffer"},
                "the scene's data as constants, in a buffer (UBO for 330 and ES, SSBO for 450), or in a "
                "uniform buffer (450: at binding 0, for Vulkan)");
    example::add_output_file(args, output, "FILE.glsl", "the file to write: .glsl or .frag (default and -: stdout)");
    std::string prefix = "krs_";
    args.app()
        .add_option("--prefix", prefix, "the start of every global name of a snippet (default krs_)")
        ->type_name("PREFIX")
        ->check(CLI::Validator(
            [](std::string& text) {
                return krs::glsl::is_prefix(text) ? std::string()
                                                  : "'" + text + "' is not a GLSL identifier prefix (lower-case letters, "
                                                              "digits and _, a letter first and _ last, not gl_, no __)";
            },
            "", "prefix"));
    // The glsl/ folder: --all DIR was its spelling before every program's folder was --output-dir.
    example::add_output_folder(args, output_dir, "the files of every scene in every target and mode (as in glsl/)",
                               "--all");
    std::string reference;
    int width = 640, height = 360;
    args.text("--reference", reference, "write the CPU reference frame of the scene's Shadertoy program to this PNG file",
              "FILE.png");
    example::add_image_size(args, width, height, " of the reference frame (with --reference)");
    args.parse(argc, argv);
    if (prefix != "krs_" && (target == "shadertoy" || !output_dir.empty()))
        args.fail("--prefix: applies to snippets, not to a Shadertoy program or the glsl/ folder (--output-dir)");
    if (reference.empty() && (args.app().count("--width") > 0 || args.app().count("--height") > 0))
        args.fail("--width, --height: apply to the reference frame: give --reference FILE.png");
    if (!reference.empty() && !output_dir.empty()) args.fail("--reference: writes one scene's frame, not with --output-dir");
    if (scenes.seed() && !output_dir.empty())
        args.fail("--seed: the glsl/ folder (--output-dir) holds every scene at its own seed");
    // The folder holds every scene in every kind: a choice of one was ignored without a word.
    for (const char* one : {"--scene", "--target", "--mode", "--output"})
        if (!output_dir.empty() && args.app().count(one) > 0)
            args.fail(std::string(one) +
                      ": --output-dir writes every scene in every target and mode; give one or the other");
    // Refused before the work, the same way in every program (support/output_path.hpp); the frame
    // is PNG only (a .jpg would be lossy, not the 8-bit values).
    if (!reference.empty()) example::require_output_file(args, "--reference", reference, {".png"});
    if (!to_stdout(output)) example::require_output_file(args, "--output", output, glsl_extensions);
    if (!output_dir.empty()) example::require_output_folder(args, "--output-dir", output_dir);
    try {
        if (!output_dir.empty()) {
            bool ok = true;
            int count = 0;
            ex::for_each_scene([&](const auto& s) {
                for (const ex::file_kind& kind : ex::files) {
                    const bool written =
                        write(output_dir + "/" + s.name + std::string(kind.suffix), ex::file_text(s, kind));
                    ok = written && ok;
                    count += written ? 1 : 0; // only what reached the disk
                }
            });
            std::fprintf(stderr, "glsl_export: wrote %d files to %s\n", count, output_dir.c_str());
            return ok ? 0 : 1;
        }
        ex::file_kind kind{"", krs::glsl::target::glsl450, krs::glsl::data_mode::constants};
        if (target == "330") kind.target = krs::glsl::target::glsl330;
        else if (target == "450") kind.target = krs::glsl::target::glsl450;
        else if (target == "es300") kind.target = krs::glsl::target::es300;
        else kind.target = krs::glsl::target::shadertoy; // the only word left: --target checked it
        if (mode == "constants") kind.mode = krs::glsl::data_mode::constants;
        else if (mode == "buffer") kind.mode = krs::glsl::data_mode::buffer;
        else kind.mode = krs::glsl::data_mode::uniform_buffer; // the only word left: --mode checked it
        bool ok = false;
        ex::with_scene(scene, scenes.seed(), [&](const auto& s) {
            // Both made in memory first (either may throw), then written. With a file for each,
            // the text's temporary is renamed only after the PNG is in place, so a failed PNG
            // leaves the earlier text file (and PNG) as they were: both or neither.
            const bool text_wanted = reference.empty() || !output.empty();
            const std::string text = text_wanted ? ex::file_text(s, kind, prefix) : std::string();
            if (reference.empty()) {
                ok = write(output, text);
                return;
            }
            const std::vector<unsigned char> png = reference_png(ex::reference_frame(s, s.camera, width, height), width, height);
            const std::string_view png_view(reinterpret_cast<const char*>(png.data()), png.size());
            try {
                if (text_wanted && !to_stdout(output))
                    krs::write_file("", output, [&](std::ostream& out) {
                        // Flushed first: a text the disk refuses fails here, before the PNG
                        // is renamed into place (write_file reports the failed stream).
                        out << text << std::flush;
                        if (out) krs::write_file("", reference, png_view);
                    });
                else {
                    krs::write_file("", reference, png_view);
                    if (text_wanted && !write(output, text)) return;
                }
            } catch (const std::exception& e) {
                std::fprintf(stderr, "glsl_export: %s\n", example::message_of(e).c_str());
                return;
            }
            std::fprintf(stderr, "glsl_export: wrote the %dx%d reference frame to %s\n", width, height, reference.c_str());
            ok = true;
        });
        return ok ? 0 : 1;
    } catch (const std::exception& e) {
        std::fprintf(stderr, "glsl_export: %s\n", example::message_of(e).c_str());
        return 1;
    }
}

// glsl_export: writes an example scene's GLSL (krs::glsl) to a file or stdout.
//
//   glsl_export --scene tree|forest|terrain|sponge --target 330|450|es300|shadertoy
//               --mode constants|buffer [--output FILE]
//   glsl_export --all DIR      regenerates every file of the repository's glsl/ folder
//
// Snippets have no #version line (paste them after your own); a shadertoy target writes the
// whole program for Shadertoy's Image tab.

#include "krs/glsl/example_scenes.hpp"

#include "support/command_line.hpp"

#include <cstdio>
#include <fstream>
#include <iostream>
#include <string>

namespace {

bool write(const std::string& path, const std::string& text)
{
    if (path.empty() || path == "-") {
        std::cout << text;
        return bool(std::cout);
    }
    std::ofstream out(path, std::ios::binary);
    out << text;
    if (!out) {
        std::fprintf(stderr, "glsl_export: cannot write %s\n", path.c_str());
        return false;
    }
    return true;
}

} // namespace

int main(int argc, char** argv)
{
    namespace ex = krs::glsl::examples;
    std::string scene = "tree", target = "450", mode = "constants", output, all;
    example::command_line args("glsl_export", "Writes an example scene's GLSL to a file or stdout; --all DIR "
                                              "regenerates every file of the repository's glsl/ folder.");
    args.choice("--scene", scene, {"tree", "forest", "terrain", "sponge"}, "the scene");
    args.choice("--target", target, {"330", "450", "es300", "shadertoy"}, "the GLSL dialect");
    args.choice("--mode", mode, {"constants", "buffer", "uniform-buffer"},
                "the scene's data as constants, in a buffer (UBO for 330 and ES, SSBO for 450), or in a "
                "uniform buffer (450: at binding 0, for Vulkan)");
    args.text("--output", output, "the file to write (default and -: stdout)", "FILE");
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
    args.text("--all", all, "write every scene in every target and mode into this folder", "DIR");
    args.parse(argc, argv);
    if (prefix != "krs_" && (target == "shadertoy" || !all.empty()))
        args.fail("--prefix: applies to snippets, not to a Shadertoy program or the glsl/ folder (--all)");
    try {
        if (!all.empty()) {
            bool ok = true;
            int count = 0;
            ex::for_each_scene([&](const auto& s) {
                for (const ex::file_kind& kind : ex::files) {
                    const bool written = write(all + "/" + s.name + std::string(kind.suffix), ex::file_text(s, kind));
                    ok = written && ok;
                    count += written ? 1 : 0; // only what reached the disk
                }
            });
            std::fprintf(stderr, "glsl_export: wrote %d files to %s\n", count, all.c_str());
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
        ex::for_each_scene([&](const auto& s) {
            if (s.name == scene) ok = write(output, ex::file_text(s, kind, prefix));
        });
        return ok ? 0 : 1;
    } catch (const std::exception& e) {
        std::fprintf(stderr, "glsl_export: %s\n", e.what());
        return 1;
    }
}

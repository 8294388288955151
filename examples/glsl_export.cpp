// glsl_export: writes an example scene's GLSL (krs::glsl) to a file or stdout.
//
//   glsl_export --scene tree|forest|terrain|sponge --target 330|450|es300|shadertoy
//               --mode constants|buffer [--output FILE]
//   glsl_export --all DIR      regenerates every file of the repository's glsl/ folder
//
// Snippets have no #version line (paste them after your own); a shadertoy target writes the
// whole program for Shadertoy's Image tab.

#include "krs/glsl/example_scenes.hpp"

#include <cstdio>
#include <cstring>
#include <fstream>
#include <iostream>
#include <optional>
#include <string>

namespace {

int usage(const char* problem)
{
    if (problem) std::fprintf(stderr, "glsl_export: %s\n", problem);
    std::fprintf(stderr,
                 "usage: glsl_export --scene tree|forest|terrain|sponge --target 330|450|es300|shadertoy\n"
                 "                   --mode constants|buffer [--output FILE]\n"
                 "       glsl_export --all DIR\n");
    return 2;
}

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
    for (int i = 1; i < argc; ++i) {
        const std::string a = argv[i];
        if (a == "-h" || a == "--help") return usage(nullptr), 0;
        std::string* value = a == "--scene" ? &scene
                             : a == "--target" ? &target
                             : a == "--mode"   ? &mode
                             : a == "--output" ? &output
                             : a == "--all"    ? &all
                                               : nullptr;
        // The name first: an unknown option is reported as one, not as missing its value.
        if (!value) return usage(("unknown option " + a).c_str());
        if (i + 1 >= argc) return usage(("missing value after " + a).c_str());
        *value = argv[++i];
    }
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
        else if (target == "shadertoy") kind.target = krs::glsl::target::shadertoy;
        else return usage(("unknown target " + target).c_str());
        if (mode == "constants") kind.mode = krs::glsl::data_mode::constants;
        else if (mode == "buffer") kind.mode = krs::glsl::data_mode::buffer;
        else return usage(("unknown mode " + mode).c_str());
        if (scene != "tree" && scene != "forest" && scene != "terrain" && scene != "sponge")
            return usage(("unknown scene " + scene).c_str());
        bool ok = false;
        ex::for_each_scene([&](const auto& s) {
            if (s.name == scene) ok = write(output, ex::file_text(s, kind));
        });
        return ok ? 0 : 1;
    } catch (const std::exception& e) {
        std::fprintf(stderr, "glsl_export: %s\n", e.what());
        return 1;
    }
}

#pragma once
// The options every example spells the same way, so that what one program taught a user works in
// the next. A program adds each of these it has through the functions below (never by hand), so
// the name, the range and the --help words are the same in all of them:
//
//     --width W, --height H   the size of an image the program renders, in pixels, [1, 16384] each
//     --threads N             worker threads, [0, 1024]; 0: one per core
//     --seed S                the seed of what the program draws at random, [0, 2^30]
//     --output FILE           the one file the program writes (its kind: its extension)
//     --output-dir DIR        the folder the program writes its files into (made if missing)
//
// (--scene, --list-scenes and the scenes' --seed: support/scene_choice.hpp, which uses these.)
// 16384 is the largest side a GL framebuffer takes here (GL_MAX_RENDERBUFFER_SIZE on llvmpipe) and
// the cross-section's limit (krs/cross_section.hpp): a frame of any program can be held against a
// GPU frame of the same size. 2^30 keeps a seed exact in a float and in GLSL's int.
//
// An option renamed to one of these spellings keeps its older name as an alias: CLI11 takes both,
// --help lists both and says which is the older one ("--only: its older name"), and a refusal
// names the option by its spelling here.

#include "command_line.hpp"

#include <concepts>
#include <string>

namespace example {

// The largest --width and --height (see above).
inline constexpr long long max_image_side = 16384;
// The largest --seed.
inline constexpr long long max_seed = 1ll << 30;

// The CLI11 names and the --help text of an option spelled `name` that still takes `older`.
struct option_spelling {
    std::string names, help;
};
inline option_spelling spelled(const std::string& name, const std::string& help,
                               const std::string& older = "")
{
    if (older.empty()) return {name, help};
    return {name + "," + older, help + " (" + older + ": its older name)"};
}

// --width and --height of the image the program renders. `applies`, when not empty, says when they
// apply (glsl_export's " (with --reference)").
inline void add_image_size(command_line& args, int& width, int& height,
                           const std::string& applies = "")
{
    args.integer("--width", width, 1, max_image_side, "image width in pixels" + applies);
    args.integer("--height", height, 1, max_image_side, "image height in pixels" + applies);
}

// --threads: 0 stands for one per core (example::thread_count turns it into a count).
inline CLI::Option* add_threads(command_line& args, int& threads)
{
    return args.integer("--threads", threads, 0, 1024, "worker threads (0: one per core)");
}

// --seed of `what` ("the tree's random growth").
template <std::integral I>
CLI::Option* add_seed(command_line& args, I& seed, const std::string& what)
{
    return args.integer("--seed", seed, 0, max_seed, "seed of " + what);
}

// --output FILE: `help` says what is written, `type` shows its kinds ("FILE.png"). The path is
// checked after parsing by require_output_file (support/output_path.hpp), as every output is.
inline CLI::Option* add_output_file(command_line& args, std::string& path, const std::string& type,
                                    const std::string& help, const std::string& older = "")
{
    const option_spelling s = spelled("--output", help, older);
    return args.text(s.names, path, s.help, type);
}

// --output-dir DIR: the folder `what` ("the PNG files") go to, made if missing (by
// require_output_folder after parsing).
inline CLI::Option* add_output_folder(command_line& args, std::string& folder, const std::string& what,
                                      const std::string& older = "")
{
    const option_spelling s =
        spelled("--output-dir", "the folder " + what + " go to (made if missing)", older);
    return args.text(s.names, folder, s.help, "DIR");
}

} // namespace example

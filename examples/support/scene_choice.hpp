#pragma once
// The example scenes on a command line, the same in every program that takes one (krs_scenes,
// krs_fractals, glsl_export, krs_export, krs_view):
//
//     --scene NAME    one of the program's scenes, by the names of krs/scenes/example_scenes.hpp
//     --list-scenes   prints each of them with what it shows, and exits with status 0
//     --seed S        the seed of the scenes that draw random numbers (default: each scene's own)
//
// A program offers the scenes it can show: all of them, or those an entry predicate keeps
// (krs_fractals' KIFS frames and zoom).

#include "krs/scenes/example_scenes.hpp"
#include "command_line.hpp"
#include "common_options.hpp"

#include <cstdint>
#include <cstdio>
#include <cstdlib>
#include <optional>
#include <string>
#include <vector>

namespace example {

// The names of every example scene.
inline std::vector<std::string> all_scene_names()
{
    return {krs::scenes::scene_names.begin(), krs::scenes::scene_names.end()};
}

class scene_choice {
public:
    // Adds --scene (into `name`, one of `names`), --list-scenes and --seed to `args`. `alias`, when
    // given, is an older name of --scene the program still takes (krs_scenes' --only).
    scene_choice(command_line& args, std::string& name, std::vector<std::string> names, const std::string& help,
                 const std::string& alias = "")
        : names_(std::move(names))
    {
        const option_spelling scene = spelled("--scene", help, alias);
        scene_ = args.choice(scene.names, name, names_, scene.help);
        args.app().add_flag_callback("--list-scenes", [this] { list(); }, "print the scenes --scene takes, and exit");
        seed_ = add_seed(args, seed_value_, "the scenes that draw random numbers");
        seed_->default_str("each scene's own");
    }

    // The seed asked for, if any (read after parsing).
    std::optional<std::uint32_t> seed() const
    {
        return seed_->count() > 0 ? std::optional<std::uint32_t>(seed_value_) : std::nullopt;
    }
    // The seed of the entry E: the one asked for or E's own.
    template <class E>
    std::uint32_t seed_of() const
    {
        return seed().value_or(E::default_seed);
    }
    CLI::Option* option() const { return scene_; }

private:
    void list() const
    {
        krs::scenes::for_each_scene_entry([&]<class E>() {
            for (const std::string& n : names_)
                if (n == E::name)
                    std::printf("%-17s %s%s\n", n.c_str(), std::string(E::summary).c_str(),
                                E::seeded ? " (--seed)" : "");
        });
        std::exit(0);
    }

    std::vector<std::string> names_;
    CLI::Option* scene_ = nullptr;
    CLI::Option* seed_ = nullptr;
    std::uint32_t seed_value_ = 0;
};

} // namespace example

#pragma once
// --up y|z, the same in every program that writes files for other tools (krs_export's meshes and
// glTF, hypertree_render's VDB and NanoVDB grids): one wording, one refusal ("--up: 'x': one of
// y|z"), one meaning. krs's scenes and trees are y-up; z-up tools (Blender, Houdini) read a PLY's
// coordinates or a VDB's transform as they are, so --up z writes the file turned by
// krs/io/up_axis.hpp's rotation, (x, y, z) -> (x, -z, y), and the tree stands up there.

#include "krs/io/up_axis.hpp"
#include "command_line.hpp"

#include <string>

namespace example {

class up_axis_option {
public:
    // Adds --up to `args`. The option writes into this object: it is neither copied nor moved.
    explicit up_axis_option(command_line& args)
    {
        option_ = args.choice("--up", name_, {"y", "z"},
                              "the written files' up axis: y (the default, the scenes' own) or z (for z-up tools such as "
                              "Blender and Houdini, which read the coordinates as they are)");
    }
    up_axis_option(const up_axis_option&) = delete;
    up_axis_option& operator=(const up_axis_option&) = delete;

    krs::up_axis axis() const { return name_ == "z" ? krs::up_axis::z : krs::up_axis::y; }
    const std::string& name() const { return name_; }
    // Whether --up was on the command line (a program refuses it where it writes nothing it turns).
    bool given() const { return option_->count() > 0; }

private:
    std::string name_ = "y";
    CLI::Option* option_ = nullptr;
};

} // namespace example

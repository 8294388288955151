#pragma once
// What the OpenVDB and NanoVDB writers (io/openvdb.hpp, io/nanovdb.hpp) share, without either
// library: the check of grid names and output paths. Both write through io/binary.hpp's
// write_then_rename (a temporary file beside the path, renamed over it once complete).

#include "hypertree/io/binary.hpp" // save_error, write_then_rename
#include "krs/core/validate.hpp"

#include <filesystem>
#include <initializer_list>
#include <string>
#include <string_view>
#include <system_error>
#include <utility>

namespace hypertree::detail {

// Grid names: non-empty printable ASCII of at most `longest` characters (NanoVDB keeps 255 in the
// grid), all different (readers find grids by name). `names` pairs each field's name with its value.
inline void require_grid_names(std::string_view caller, std::initializer_list<std::pair<const char*, const std::string*>> names,
                               std::size_t longest = 255)
{
    for (const auto& [field, name] : names) {
        const std::string parameter = std::string(caller) + " names." + field;
        if (name->empty()) throw krs::invalid_parameter(parameter, "must not be empty");
        if (name->size() > longest)
            throw krs::invalid_parameter(parameter, "must be at most " + std::to_string(longest) + " characters",
                                         std::to_string(name->size()));
        for (const char c : *name)
            if (static_cast<unsigned char>(c) < 0x20 || static_cast<unsigned char>(c) >= 0x7f)
                throw krs::invalid_parameter(parameter, "must be printable ASCII (no control characters)", "\"" + *name + "\"");
        for (const auto& [other_field, other] : names)
            if (other != name && *other == *name)
                throw krs::invalid_parameter(parameter, std::string("must differ from names.") + other_field + " (grids are found by name)",
                                             "\"" + *name + "\"");
    }
}

inline void require_output_path(std::string_view caller, const std::filesystem::path& path)
{
    if (path.empty()) throw krs::invalid_parameter(std::string(caller) + " path", "must name a file", "an empty path");
    std::error_code ec;
    if (std::filesystem::is_directory(path, ec))
        throw krs::invalid_parameter(std::string(caller) + " path", "must name a file, not a directory", path.string());
}

} // namespace hypertree::detail

#pragma once
// The examples' outputs, checked when the command line is read, before any work: a render or a
// mesh can take minutes, and a path that cannot be written should be refused before them, not
// after. Every program checks every output option through these two functions, so each refuses
// the same things with the same words (exit 2, "<program>: --output: ..."):
//
// - require_output_file(args, "--output", path, {".png"}): the name ends in one of the extensions (any case), the path is not a
//   directory, its directory exists (no program makes a directory the user did not ask for) and
//   a file can be made in it (tried: krs::detail::create_partial_file, then removed, because
//   permission bits do not tell: root writes through them, a read-only mount refuses root).
// - require_output_folder(args, "--output-dir", folder): an --output-dir, made if missing (the one kind of directory a program
//   makes, and its --help says so), which must then take a new file.
//
// The files themselves are written by krs::write_file (krs/io/write_then_rename.hpp).

#include "krs/io/write_then_rename.hpp"
#include "command_line.hpp"

#include <algorithm>
#include <cctype>
#include <filesystem>
#include <initializer_list>
#include <string>
#include <system_error>
#include <vector>

namespace example {

namespace detail {

inline std::string lower(std::string text)
{
    std::transform(text.begin(), text.end(), text.begin(), [](unsigned char c) { return char(std::tolower(c)); });
    return text;
}

// "" when a new file can be made in `folder`, else the system's reason.
inline std::string cannot_create_in(const std::filesystem::path& folder)
{
    try {
        const std::filesystem::path probe = krs::detail::create_partial_file(folder / "krs-output-probe");
        std::error_code ignored;
        std::filesystem::remove(probe, ignored);
        return {};
    } catch (const krs::save_error& e) {
        const std::string what = e.what();
        const std::size_t reason = what.rfind(": ");
        return reason == std::string::npos ? what : what.substr(reason + 2);
    }
}

} // namespace detail

// Why `path` cannot be the output file of a writer of `extensions` (lower case, with the dot;
// none: a format of any name), or "" when it can.
inline std::string output_file_problem(const std::string& path, const std::vector<std::string>& extensions)
{
    const std::string extension = detail::lower(std::filesystem::path(path).extension().string());
    if (!extensions.empty() && std::find(extensions.begin(), extensions.end(), extension) == extensions.end()) {
        std::string listed;
        for (std::size_t i = 0; i < extensions.size(); ++i)
            listed += (i == 0 ? "" : i + 1 == extensions.size() ? " or " : ", ") + extensions[i];
        return "'" + path + "' does not end in " + listed + " (the format" + (extensions.size() > 1 ? "s" : "") + " written)";
    }
    std::error_code ec;
    if (std::filesystem::is_directory(path, ec)) return "'" + path + "' is a directory, not a file";
    const std::filesystem::path given = std::filesystem::path(path).parent_path();
    const std::filesystem::path folder = given.empty() ? std::filesystem::path(".") : given;
    const std::filesystem::file_status status = std::filesystem::status(folder, ec);
    if (!std::filesystem::exists(status))
        return "'" + path + "': the directory " + folder.string() + " does not exist (" +
               (ec ? ec.message() : std::string("no such directory")) + "; no directory is made)";
    if (!std::filesystem::is_directory(status)) return "'" + path + "': " + folder.string() + " is not a directory";
    if (const std::string why = detail::cannot_create_in(folder); !why.empty())
        return "'" + path + "': no file can be made in " + folder.string() + ": " + why;
    return {};
}

// Why `folder` cannot take the output files, after making it if missing, or "" when it can.
inline std::string output_folder_problem(const std::string& folder)
{
    std::error_code ec;
    std::filesystem::create_directories(folder, ec);
    if (!std::filesystem::is_directory(folder))
        return "'" + folder + "' is not a directory and cannot be made one" + (ec ? ": " + ec.message() : std::string());
    if (const std::string why = detail::cannot_create_in(folder); !why.empty())
        return "'" + folder + "': no file can be made in it: " + why;
    return {};
}

// The two checks on a parsed command line: a problem refuses it (exit 2, "<program>: <option>:
// <why>"). Called after parse() rather than as CLI11 validators, so that a default (an option not
// given) is checked too, and a folder is made only for a command line that parsed.
inline void require_output_file(const command_line& args, const std::string& option, const std::string& path,
                                const std::vector<std::string>& extensions)
{
    if (const std::string why = output_file_problem(path, extensions); !why.empty()) args.fail(option + ": " + why);
}
inline void require_output_folder(const command_line& args, const std::string& option, const std::string& folder)
{
    if (const std::string why = output_folder_problem(folder); !why.empty()) args.fail(option + ": " + why);
}

} // namespace example

#pragma once
// Files written whole or not at all: a save writes a new temporary file beside its path and
// renames it over the path once complete, so a reader never sees half a file and a failed save
// (a full disk, an exception from the caller's data, a budget refused half way) leaves nothing
// behind and any earlier file at the path as it was. Shared by every writer of krs (meshes,
// krs/mesh/write.hpp) and of hypertree (hypertree/io/binary.hpp and the VDB writers), which may
// include krs but never the reverse.

#include "krs/core/validate.hpp"

#include <atomic>
#include <cerrno>
#include <cstdint>
#include <cstdio>
#include <cstring>
#include <filesystem>
#include <stdexcept>
#include <string>
#include <string_view>
#include <system_error>
#if defined(_WIN32)
#include <process.h> // _getpid
#else
#include <unistd.h> // getpid
#endif

namespace krs {

// A file that could not be written (the stream failed, the file could not be created or renamed).
class save_error : public std::runtime_error {
public:
    using std::runtime_error::runtime_error;
};

namespace detail {

// A new, empty file beside `path` for a save to write before renaming it over `path`:
// "<path>.partial-<process id>-<n>", created exclusively (fopen's "x" mode), so that two writers
// of one path, in one process or several, never share it and a file of the user's that happens
// to have such a name is never overwritten (n counts up until a name is free).
inline std::filesystem::path create_partial_file(const std::filesystem::path& path)
{
    static std::atomic<std::uint64_t> counter{0};
#if defined(_WIN32)
    const long process = long(_getpid());
#else
    const long process = long(::getpid());
#endif
    for (int attempt = 0; attempt < 1000; ++attempt) {
        std::filesystem::path partial = path;
        partial += ".partial-" + std::to_string(process) + "-" + std::to_string(counter.fetch_add(1));
        if (std::FILE* f = std::fopen(partial.string().c_str(), "wbx")) {
            std::fclose(f);
            return partial;
        }
        if (errno != EEXIST) break; // a directory that cannot be written: another name will not help
    }
    throw save_error(path.string() + ": cannot open a new temporary file beside it: " + std::strerror(errno));
}

// Calls write(partial) with a new file from create_partial_file, then renames it over path. Any
// exception from write, or a failed rename, removes the partial file and becomes a save_error
// naming the caller and the path; a file already at `path` is left as it was.
template <class Write>
void write_then_rename(std::string_view caller, const std::filesystem::path& path, Write&& write)
{
    const auto message = [&](const std::string& text) { return std::string(caller) + ": " + path.string() + ": " + text; };
    std::filesystem::path partial;
    try {
        partial = create_partial_file(path);
    } catch (const save_error& e) {
        throw save_error(std::string(caller) + ": " + e.what());
    }
    const auto fail = [&](const std::string& text) {
        std::error_code ignored;
        std::filesystem::remove(partial, ignored);
        return save_error(message(text));
    };
    try {
        write(partial);
    } catch (const std::exception& e) {
        throw fail("cannot write " + partial.string() + ": " + e.what());
    }
    std::error_code failure;
    std::filesystem::rename(partial, path, failure);
    if (failure) throw fail("cannot replace the file: " + failure.message());
}

// An output path a save can rename onto: not empty, not a directory. The parameter is named
// "<caller> path".
inline void require_output_path(std::string_view caller, const std::filesystem::path& path)
{
    if (path.empty()) throw invalid_parameter(std::string(caller) + " path", "must name a file", "an empty path");
    std::error_code ec;
    if (std::filesystem::is_directory(path, ec))
        throw invalid_parameter(std::string(caller) + " path", "must name a file, not a directory", path.string());
}

} // namespace detail
} // namespace krs

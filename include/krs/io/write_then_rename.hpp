#pragma once
// Files written whole or not at all, the one way every writer of krs, hypertree and the examples
// reaches the disk (meshes: krs/mesh/write.hpp, gltf.hpp; volumes: hypertree/io/binary.hpp, the
// VDB writers; the examples' PNG, GLSL and CSV files): write_file writes a new temporary file
// beside its path, checks every write and the close (a full disk, a file size limit or a quota
// fails the write, and a stream that failed is never renamed), and renames it over the path only
// once complete. So a reader never sees half a file, and a failed save (a full disk, an exception
// from the caller's data, a budget refused half way) leaves no temporary behind and any earlier
// file at the path as it was; the save_error names the path and the system's reason (errno's
// text: "No space left on device", "File too large", "Permission denied"). What is not promised:
// that the file survives a power cut (no fsync), only that a reader sees the old or the new file.

#include "krs/core/validate.hpp"

#include <atomic>
#include <concepts>
#include <cerrno>
#include <cstdint>
#include <cstdio>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <ostream>
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
    // "<caller>: " leads, unless the caller is empty (a program that names itself instead).
    const std::string lead = caller.empty() ? std::string() : std::string(caller) + ": ";
    const auto message = [&](const std::string& text) { return lead + path.string() + ": " + text; };
    std::filesystem::path partial;
    try {
        partial = create_partial_file(path);
    } catch (const save_error& e) {
        throw save_error(lead + e.what());
    }
    const auto fail = [&](const std::string& text) {
        std::error_code ignored;
        std::filesystem::remove(partial, ignored);
        return save_error(message(text));
    };
    try {
        write(partial);
    } catch (const std::exception& e) {
        throw fail(e.what());
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

// The system's reason for the last failed call (errno's text), or a stated fallback when the
// failing layer left none (a std::ostream that failed without a system call failing).
inline std::string system_reason(int error, std::string_view fallback)
{
    return error != 0 ? std::string(std::strerror(error)) : std::string(fallback);
}

// Opens `file` (a temporary from create_partial_file), lets fill(std::ostream&) write it, then
// checks the stream after a flush and after the close: a write refused by the system (a full
// disk) sets the stream's badbit and errno, which becomes the save_error's reason.
template <class Fill>
void write_checked_stream(const std::filesystem::path& file, Fill&& fill)
{
    errno = 0;
    std::ofstream out(file, std::ios::binary | std::ios::trunc);
    if (!out) throw save_error("cannot open it for writing: " + system_reason(errno, "the stream did not open"));
    try {
        fill(static_cast<std::ostream&>(out));
    } catch (const std::exception& e) {
        // A writer that checks its own stream (hypertree's binary format, NanoVDB) throws its own
        // words for a write the system refused; the system's reason is the one worth reporting.
        const int error = errno;
        if (out) throw;
        throw save_error("writing failed: " + system_reason(error, e.what()));
    }
    const auto failed = [&](const char* when) {
        return save_error(std::string(when) + ": " + system_reason(errno, "the output stream failed"));
    };
    if (!out) throw failed("writing failed");
    out.flush(); // what the stream still holds, so that a full disk shows here rather than never
    if (!out) throw failed("writing failed");
    out.close();
    if (!out) throw failed("closing failed");
}

} // namespace detail

// The one way to write a file whole: fill(std::ostream&) writes the content, or `bytes` is it.
// Checks the path (not empty, not a directory: invalid_parameter "<caller> path"), writes a
// temporary beside it with every write and the close checked, renames it over `path` once whole.
// Any failure is a save_error "<caller>: <path>: <what failed>: <the system's reason>", the
// temporary removed and an earlier file at `path` untouched.
template <class Fill>
    requires std::invocable<Fill&, std::ostream&>
void write_file(std::string_view caller, const std::filesystem::path& path, Fill&& fill)
{
    detail::require_output_path(caller, path);
    detail::write_then_rename(caller, path, [&](const std::filesystem::path& partial) { detail::write_checked_stream(partial, fill); });
}

inline void write_file(std::string_view caller, const std::filesystem::path& path, std::string_view bytes)
{
    write_file(caller, path, [&](std::ostream& out) { out.write(bytes.data(), std::streamsize(bytes.size())); });
}

} // namespace krs

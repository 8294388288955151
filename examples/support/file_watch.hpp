#pragma once
// A file watched for edits by polling: changed() is true when its modification time or size differ
// from the last look (the size too, because an editor can write twice within the clock's step).
// A poll is one stat(), cheap at a frame's rate, and needs nothing of the platform (inotify would
// miss an editor that saves by renaming a new file over the old one, unless it watched the folder).
// A file that is missing for a moment (between an editor's delete and its write) is not a change:
// the next look that finds it is.

#include <filesystem>
#include <fstream>
#include <iterator>
#include <optional>
#include <string>
#include <system_error>

namespace example {

class file_watch {
public:
    explicit file_watch(std::filesystem::path path) : path_(std::move(path)) {}

    const std::filesystem::path& path() const { return path_; }

    // True once per edit: the file exists and differs from the last look.
    bool changed()
    {
        std::error_code error;
        const auto time = std::filesystem::last_write_time(path_, error);
        if (error) return false;
        const auto size = std::filesystem::file_size(path_, error);
        if (error) return false;
        if (seen_ && time == time_ && size == size_) return false;
        seen_ = true, time_ = time, size_ = size;
        return true;
    }

    // The file's text, or nothing when it cannot be read.
    std::optional<std::string> read() const
    {
        std::ifstream in(path_, std::ios::binary);
        if (!in) return std::nullopt;
        std::string text((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
        if (in.bad()) return std::nullopt;
        return text;
    }

private:
    std::filesystem::path path_;
    bool seen_ = false;
    std::filesystem::file_time_type time_{};
    std::uintmax_t size_ = 0;
};

} // namespace example

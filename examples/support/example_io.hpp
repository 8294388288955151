#pragma once
// What every example shares and the library must not have: a thread count, and writing a linear
// RGB float image as a gamma-encoded PNG with OpenImageIO. The command line is command_line.hpp,
// progress reports progress.hpp.

#include "krs/io/write_then_rename.hpp"

#include <OpenImageIO/imageio.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <stdexcept>
#include <string>
#include <thread>
#include <vector>

namespace example {

// 0 means "all cores".
inline int thread_count(int requested)
{
    return requested > 0 ? requested : int(std::max(1u, std::thread::hardware_concurrency()));
}

// RGB bytes (row-major, top row first) as a PNG, creating the folder. The file is written whole or
// not at all (krs/io/write_then_rename.hpp: a temporary file beside it, renamed over the path once
// closed), so a viewer of the path never reads half an image and a failed write leaves any earlier
// file as it was. Returns false after printing the reason.
inline bool write_png_bytes(const std::string& path, int width, int height,
                            const std::vector<unsigned char>& bytes)
{
    const std::filesystem::path folder = std::filesystem::path(path).parent_path();
    std::error_code made;
    if (!folder.empty()) std::filesystem::create_directories(folder, made);
    try {
        krs::detail::write_then_rename(
            "write_png", path, [&](const std::filesystem::path& partial) {
                // The format from the path's extension: the temporary name ends in ".partial-...".
                auto file = OIIO::ImageOutput::create(path);
                if (!file) throw std::runtime_error(OIIO::geterror());
                const OIIO::ImageSpec spec(width, height, 3, OIIO::TypeDesc::UINT8);
                // close() flushes: it can fail too (a full disk).
                if (!file->open(partial.string(), spec) ||
                    !file->write_image(OIIO::TypeDesc::UINT8, bytes.data()) || !file->close())
                    throw std::runtime_error(file->geterror());
            });
        return true;
    } catch (const krs::save_error& e) {
        std::fprintf(stderr, "cannot write %s: %s%s%s\n", path.c_str(), e.what(), made ? "; " : "",
                     made ? made.message().c_str() : "");
        return false;
    }
}

// Writes linear RGB floats (row-major, top row first) as an 8-bit sRGB-ish PNG (gamma 2.2), as
// write_png_bytes writes. `gamma` 1 writes values that are already encoded for display (a shader's
// output) as they are: round(255 v), as a GL framebuffer of 8-bit channels stores them.
inline bool write_png(const std::string& path, int width, int height, const std::vector<float>& rgb,
                      float gamma = 2.2f)
{
    std::vector<unsigned char> bytes(rgb.size());
    for (std::size_t i = 0; i < rgb.size(); ++i) {
        const float v = std::clamp(rgb[i], 0.0f, 1.0f);
        bytes[i] =
            (unsigned char)std::lround(255.0f * (gamma == 1.0f ? v : std::pow(v, 1.0f / gamma)));
    }
    return write_png_bytes(path, width, height, bytes);
}

} // namespace example

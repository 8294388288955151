#pragma once
// What every example shares and the library must not have: a thread count, and writing a linear
// RGB float image as a gamma-encoded PNG with OpenImageIO. The command line is command_line.hpp,
// progress reports progress.hpp.

#include <OpenImageIO/imageio.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <string>
#include <thread>
#include <vector>

namespace example {

// 0 means "all cores".
inline int thread_count(int requested)
{
    return requested > 0 ? requested : int(std::max(1u, std::thread::hardware_concurrency()));
}

// Writes linear RGB floats (row-major, top row first) as an 8-bit sRGB-ish PNG (gamma 2.2),
// creating the folder. Returns false after printing OpenImageIO's reason, and removes a file it
// opened but could not finish. `gamma` 1 writes values
// that are already encoded for display (a shader's output) as they are: round(255 v), as a GL
// framebuffer of 8-bit channels stores them.
inline bool write_png(const std::string& path, int width, int height, const std::vector<float>& rgb, float gamma = 2.2f)
{
    std::vector<unsigned char> bytes(rgb.size());
    for (std::size_t i = 0; i < rgb.size(); ++i) {
        const float v = std::clamp(rgb[i], 0.0f, 1.0f);
        bytes[i] = (unsigned char)std::lround(255.0f * (gamma == 1.0f ? v : std::pow(v, 1.0f / gamma)));
    }
    const std::filesystem::path folder = std::filesystem::path(path).parent_path();
    std::error_code made;
    if (!folder.empty()) std::filesystem::create_directories(folder, made);
    auto file = OIIO::ImageOutput::create(path);
    const OIIO::ImageSpec spec(width, height, 3, OIIO::TypeDesc::UINT8);
    const bool opened = file && file->open(path, spec);
    // close() flushes: it can fail too (a full disk).
    const bool written = opened && file->write_image(OIIO::TypeDesc::UINT8, bytes.data());
    if (opened && file->close() && written) return true;
    const std::string why = file ? file->geterror() : OIIO::geterror();
    std::fprintf(stderr, "cannot write %s: %s\n", path.c_str(), why.empty() ? made.message().c_str() : why.c_str());
    if (opened) {
        std::error_code ignored;
        std::filesystem::remove(path, ignored);
    }
    return false;
}

} // namespace example

#pragma once
// What every example shares and the library must not have: a thread count, and writing a linear
// RGB float image as a gamma-encoded PNG with OpenImageIO. The command line is command_line.hpp,
// progress reports progress.hpp.

#include "krs/io/write_then_rename.hpp"

#include <OpenImageIO/filesystem.h>
#include <OpenImageIO/imageio.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <stdexcept>
#include <string>
#include <string_view>
#include <thread>
#include <vector>

namespace example {

// 0 means "all cores".
inline int thread_count(int requested)
{
    return requested > 0 ? requested : int(std::max(1u, std::thread::hardware_concurrency()));
}

// The PNG file of linear RGB floats (row-major, top row first), 8-bit sRGB-ish (gamma 2.2), made
// in memory by OpenImageIO. `gamma` 1 writes values that are already encoded for display (a
// shader's output) as they are: round(255 v), as a GL framebuffer of 8-bit channels stores them.
// Throws std::runtime_error with OpenImageIO's reason when it cannot encode the image.
inline std::vector<unsigned char> png_bytes(int width, int height, const std::vector<float>& rgb, float gamma = 2.2f)
{
    std::vector<unsigned char> pixels(rgb.size());
    for (std::size_t i = 0; i < rgb.size(); ++i) {
        const float v = std::clamp(rgb[i], 0.0f, 1.0f);
        pixels[i] = (unsigned char)std::lround(255.0f * (gamma == 1.0f ? v : std::pow(v, 1.0f / gamma)));
    }
    // Encoded into memory (an IOProxy, which OIIO's PNG writer supports), not into the file: OIIO's
    // own file writes go unchecked (a full disk gave a truncated PNG and success), while
    // krs::write_file checks every write of the bytes it is given.
    std::vector<unsigned char> encoded;
    OIIO::Filesystem::IOVecOutput memory(encoded);
    auto out = OIIO::ImageOutput::create("png");
    if (!out) throw std::runtime_error("OpenImageIO has no PNG writer: " + OIIO::geterror());
    const OIIO::ImageSpec spec(width, height, 3, OIIO::TypeDesc::UINT8);
    const bool written = out->set_ioproxy(&memory) && out->open("memory.png", spec) &&
                         out->write_image(OIIO::TypeDesc::UINT8, pixels.data());
    const bool closed = out->close(); // close() finishes the PNG: it can fail too
    if (!written || !closed || out->has_error()) {
        const std::string why = out->geterror();
        throw std::runtime_error("OpenImageIO could not encode the PNG: " + (why.empty() ? std::string("no reason given") : why));
    }
    return encoded;
}

// Writes the image as a PNG file at `path` through krs::write_file (a temporary beside it, every
// write checked, renamed over it when whole; no folder is made). Returns false after printing
// "<program>: <path>: <what failed>: <the system's reason>"; an earlier file at `path` is untouched.
inline bool write_png(const std::string& program, const std::string& path, int width, int height, const std::vector<float>& rgb,
                      float gamma = 2.2f)
{
    try {
        const std::vector<unsigned char> bytes = png_bytes(width, height, rgb, gamma);
        krs::write_file("", path, std::string_view(reinterpret_cast<const char*>(bytes.data()), bytes.size()));
        return true;
    } catch (const std::exception& e) {
        std::fprintf(stderr, "%s: %s\n", program.c_str(), e.what());
        return false;
    }
}

} // namespace example

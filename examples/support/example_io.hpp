#pragma once
// What every example shares and the library must not have: command-line parsing with clear
// errors, and writing a linear RGB float image as a gamma-encoded PNG with OpenImageIO.

#include <OpenImageIO/imageio.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <filesystem>
#include <string>
#include <thread>
#include <vector>

namespace example {

// Walks argv; each accessor consumes the option's value and exits with status 2 and a message
// naming the option when it is missing or out of range.
class arguments {
public:
    arguments(int argc, char** argv, std::string usage) : argc_(argc), argv_(argv), usage_(std::move(usage)) {}

    // The next option name, or false when argv is exhausted. -h and --help print the usage and
    // exit with status 0 (they were refused as unknown options).
    bool next(std::string& option)
    {
        if (++i_ >= argc_) return false;
        option = argv_[i_];
        if (option == "-h" || option == "--help") {
            std::printf("usage: %s\n", usage_.c_str());
            std::exit(0);
        }
        return true;
    }
    std::string text(const char* option)
    {
        if (i_ + 1 >= argc_) fail(std::string(option) + " needs a value");
        return argv_[++i_];
    }
    int integer(const char* option, int lo, int hi)
    {
        const std::string v = text(option);
        char* end = nullptr;
        const long n = std::strtol(v.c_str(), &end, 10);
        if (end == v.c_str() || *end != '\0' || n < lo || n > hi)
            fail(std::string(option) + " must be an integer in [" + std::to_string(lo) + ", " + std::to_string(hi) +
                 "] (got '" + v + "')");
        return int(n);
    }
    [[noreturn]] void unknown(const std::string& option) { fail("unknown option '" + option + "'"); }
    [[noreturn]] void fail(const std::string& why) const
    {
        std::fprintf(stderr, "%s: %s\nusage: %s\n", program().c_str(), why.c_str(), usage_.c_str());
        std::exit(2);
    }
    std::string program() const { return std::filesystem::path(argv_[0]).filename().string(); }

private:
    int argc_;
    char** argv_;
    std::string usage_;
    int i_ = 0;
};

// 0 means "all cores".
inline int thread_count(int requested)
{
    return requested > 0 ? requested : int(std::max(1u, std::thread::hardware_concurrency()));
}

// Writes linear RGB floats (row-major, top row first) as an 8-bit sRGB-ish PNG (gamma 2.2),
// creating the folder. Returns false after printing OpenImageIO's reason.
inline bool write_png(const std::string& path, int width, int height, const std::vector<float>& rgb)
{
    std::vector<unsigned char> bytes(rgb.size());
    for (std::size_t i = 0; i < rgb.size(); ++i)
        bytes[i] = (unsigned char)std::lround(255.0f * std::pow(std::clamp(rgb[i], 0.0f, 1.0f), 1.0f / 2.2f));
    const std::filesystem::path folder = std::filesystem::path(path).parent_path();
    std::error_code made;
    if (!folder.empty()) std::filesystem::create_directories(folder, made);
    auto file = OIIO::ImageOutput::create(path);
    const OIIO::ImageSpec spec(width, height, 3, OIIO::TypeDesc::UINT8);
    if (!file || !file->open(path, spec) || !file->write_image(OIIO::TypeDesc::UINT8, bytes.data())) {
        const std::string why = file ? file->geterror() : OIIO::geterror();
        std::fprintf(stderr, "cannot write %s: %s\n", path.c_str(), why.empty() ? made.message().c_str() : why.c_str());
        return false;
    }
    file->close();
    return true;
}

} // namespace example

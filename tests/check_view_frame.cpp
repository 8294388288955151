// check_view_frame: holds a PNG that krs_view wrote against another image, read by OpenImageIO.
//
//   check_view_frame match FRAME.png REFERENCE.png PERCENT   at least PERCENT % of the pixels have
//                                                            every channel within 2/255
//   check_view_frame colour FRAME.png R G B                 every pixel within 2/255 of the bytes
//                                                            R G B
//
// 2/255 is the bound the GLSL tests hold the Shadertoy programs' frames to against the CPU
// reference (tests/test_glsl_gpu.cpp): the kernels' normals and lengths use GLSL builtins a few ulp
// from C++. Both images must be the same size (a frame of the wrong size fails, it is not scaled).
// Prints what it measured; exit status 0 when the check holds, 1 when not, 2 for a bad call.

#include <OpenImageIO/imageio.h>

#include <algorithm>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <optional>
#include <string>
#include <vector>

namespace {

struct image {
    int width = 0, height = 0;
    std::vector<unsigned char> rgb;
};

// The file's first three channels as bytes, or nothing (after saying why).
std::optional<image> read_rgb(const std::string& path)
{
    auto in = OIIO::ImageInput::open(path);
    if (!in) {
        std::fprintf(stderr, "cannot open %s: %s\n", path.c_str(), OIIO::geterror().c_str());
        return std::nullopt;
    }
    const OIIO::ImageSpec spec = in->spec();
    if (spec.nchannels < 3) {
        std::fprintf(stderr, "%s has %d channels, not RGB\n", path.c_str(), spec.nchannels);
        return std::nullopt;
    }
    image out{spec.width, spec.height, std::vector<unsigned char>(std::size_t(spec.width) * std::size_t(spec.height) * 3)};
    if (!in->read_image(0, 0, 0, 3, OIIO::TypeDesc::UINT8, out.rgb.data())) {
        std::fprintf(stderr, "cannot read %s: %s\n", path.c_str(), in->geterror().c_str());
        return std::nullopt;
    }
    return out;
}

// The largest channel difference of each pixel, in bytes, against the pixel's `expected` bytes.
template <class Expected>
std::vector<int> differences(const image& frame, Expected&& expected)
{
    std::vector<int> out(std::size_t(frame.width) * std::size_t(frame.height));
    for (std::size_t i = 0; i < out.size(); ++i) {
        int worst = 0;
        for (std::size_t c = 0; c < 3; ++c) worst = std::max(worst, std::abs(int(frame.rgb[i * 3 + c]) - expected(i, c)));
        out[i] = worst;
    }
    return out;
}

// Prints the share within 2/255 and the largest difference; returns the share in percent.
double report(const std::string& what, const std::vector<int>& diff)
{
    const std::size_t close = std::size_t(std::count_if(diff.begin(), diff.end(), [](int d) { return d <= 2; }));
    const std::size_t exact = std::size_t(std::count(diff.begin(), diff.end(), 0));
    const double percent = 100.0 * double(close) / double(diff.size());
    std::printf("%s: %zu of %zu pixels (%.3f%%) within 2/255, %.3f%% equal, largest difference %d/255\n", what.c_str(),
                close, diff.size(), percent, 100.0 * double(exact) / double(diff.size()),
                *std::max_element(diff.begin(), diff.end()));
    return percent;
}

} // namespace

int main(int argc, char** argv)
{
    const std::string mode = argc > 1 ? argv[1] : "";
    if (mode == "match" && argc == 5) {
        const std::optional<image> frame = read_rgb(argv[2]), reference = read_rgb(argv[3]);
        const double required = std::atof(argv[4]);
        if (!frame || !reference) return 1;
        if (frame->width != reference->width || frame->height != reference->height) {
            std::fprintf(stderr, "%s is %dx%d, %s is %dx%d\n", argv[2], frame->width, frame->height, argv[3],
                         reference->width, reference->height);
            return 1;
        }
        const double percent = report(std::string(argv[2]) + " against " + argv[3],
                                      differences(*frame, [&](std::size_t i, std::size_t c) { return int(reference->rgb[i * 3 + c]); }));
        if (percent >= required) return 0;
        std::fprintf(stderr, "fewer than %g%% of the pixels are within 2/255\n", required);
        return 1;
    }
    if (mode == "colour" && argc == 6) {
        const std::optional<image> frame = read_rgb(argv[2]);
        if (!frame) return 1;
        const int colour[3] = {std::atoi(argv[3]), std::atoi(argv[4]), std::atoi(argv[5])};
        const double percent = report(std::string(argv[2]) + " against the colour " + argv[3] + " " + argv[4] + " " + argv[5],
                                      differences(*frame, [&](std::size_t, std::size_t c) { return colour[c]; }));
        if (percent == 100.0) return 0;
        std::fprintf(stderr, "not every pixel is the colour\n");
        return 1;
    }
    std::fprintf(stderr, "usage: check_view_frame match FRAME.png REFERENCE.png PERCENT\n"
                         "       check_view_frame colour FRAME.png R G B\n");
    return 2;
}

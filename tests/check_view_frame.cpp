// check_view_frame: holds a PNG that krs_view wrote against another image, read by OpenImageIO.
//
//   check_view_frame match FRAME.png REFERENCE.png PERCENT   at least PERCENT % of the pixels have
//                                                            every channel within 2/255
//   check_view_frame colour FRAME.png R G B                 every pixel within 2/255 of the bytes
//                                                            R G B
//   check_view_frame coverage FRAME.png X Y LOW HIGH        the frame of a program whose red is 1
//                                                            left of x = X + 1/2 and green 1 below
//                                                            y = Y + 1/2 (pixels, y up), else 0:
//                                                            red 255 left of column X and 0 right
//                                                            of it, green so about row Y, blue 0,
//                                                            and the half-covered column's red and
//                                                            row's green bytes in [LOW, HIGH]
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
    image out{spec.width, spec.height,
              std::vector<unsigned char>(std::size_t(spec.width) * std::size_t(spec.height) * 3)};
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
        for (std::size_t c = 0; c < 3; ++c)
            worst = std::max(worst, std::abs(int(frame.rgb[i * 3 + c]) - expected(i, c)));
        out[i] = worst;
    }
    return out;
}

// Prints the share within 2/255 and the largest difference; returns the share in percent.
double report(const std::string& what, const std::vector<int>& diff)
{
    const std::size_t close =
        std::size_t(std::count_if(diff.begin(), diff.end(), [](int d) { return d <= 2; }));
    const std::size_t exact = std::size_t(std::count(diff.begin(), diff.end(), 0));
    const double percent = 100.0 * double(close) / double(diff.size());
    std::printf(
        "%s: %zu of %zu pixels (%.3f%%) within 2/255, %.3f%% equal, largest difference %d/255\n",
        what.c_str(), close, diff.size(), percent, 100.0 * double(exact) / double(diff.size()),
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
            std::fprintf(stderr, "%s is %dx%d, %s is %dx%d\n", argv[2], frame->width, frame->height,
                         argv[3], reference->width, reference->height);
            return 1;
        }
        const double percent = report(std::string(argv[2]) + " against " + argv[3],
                                      differences(*frame, [&](std::size_t i, std::size_t c) {
                                          return int(reference->rgb[i * 3 + c]);
                                      }));
        if (percent >= required) return 0;
        std::fprintf(stderr, "fewer than %g%% of the pixels are within 2/255\n", required);
        return 1;
    }
    if (mode == "colour" && argc == 6) {
        const std::optional<image> frame = read_rgb(argv[2]);
        if (!frame) return 1;
        const int colour[3] = {std::atoi(argv[3]), std::atoi(argv[4]), std::atoi(argv[5])};
        const double percent = report(
            std::string(argv[2]) + " against the colour " + argv[3] + " " + argv[4] + " " + argv[5],
            differences(*frame, [&](std::size_t, std::size_t c) { return colour[c]; }));
        if (percent == 100.0) return 0;
        std::fprintf(stderr, "not every pixel is the colour\n");
        return 1;
    }
    if (mode == "coverage" && argc == 7) {
        const std::optional<image> frame = read_rgb(argv[2]);
        if (!frame) return 1;
        const int column = std::atoi(argv[3]), row = std::atoi(argv[4]), low = std::atoi(argv[5]),
                  high = std::atoi(argv[6]);
        long wrong = 0;
        const auto expect = [&](int x, int y, int c, int got, int at, int position) {
            const bool ok = position < at   ? got == 255
                            : position > at ? got == 0
                                            : got >= low && got <= high;
            if (!ok && wrong++ < 5)
                std::fprintf(stderr, "pixel (%d, %d from the bottom) channel %d is %d\n", x, y, c,
                             got);
        };
        for (int r = 0; r < frame->height; ++r)
            for (int x = 0; x < frame->width; ++x) {
                const int y = frame->height - 1 - r; // files store the top row first
                const unsigned char* p =
                    &frame->rgb[(std::size_t(r) * std::size_t(frame->width) + std::size_t(x)) * 3];
                expect(x, y, 0, p[0], column, x);
                expect(x, y, 1, p[1], row, y);
                expect(x, y, 2, p[2], -1, 0); // blue: 0 everywhere
            }
        const int y_byte =
            frame->rgb[(std::size_t(frame->height - 1 - row) * std::size_t(frame->width)) * 3 + 1];
        const int x_byte = frame->rgb[std::size_t(column) * 3];
        std::printf("%s: the half-covered column's red %d/255, row's green %d/255 (allowed [%d, "
                    "%d]); %ld wrong values\n",
                    argv[2], x_byte, y_byte, low, high, wrong);
        return wrong == 0 ? 0 : 1;
    }
    std::fprintf(stderr, "usage: check_view_frame match FRAME.png REFERENCE.png PERCENT\n"
                         "       check_view_frame colour FRAME.png R G B\n"
                         "       check_view_frame coverage FRAME.png X Y LOW HIGH\n");
    return 2;
}

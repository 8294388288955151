// check_glsl_reference SCENE FILE WIDTH HEIGHT: the PNG `glsl_export --scene SCENE --reference FILE
// --width WIDTH --height HEIGHT` wrote holds, byte for byte, the CPU reference frame as an 8-bit
// framebuffer stores it (krs::glsl::framebuffer_byte: round(255 v), ties to even)
// (krs::scenes::reference_frame, rendered here again), RGB, top row first: the reference
// comes bottom-up (as glReadPixels returns it), so its last row is the file's first. Its first and
// last rows differ (the sky darkens upward), so a file written upside down fails. Exit status 0
// when it holds; a message naming what failed otherwise.

#include "krs/scenes/example_scenes.hpp"
#include "krs/scenes/scene_files.hpp"

#include <OpenImageIO/imageio.h>

#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <string>
#include <vector>

int main(int argc, char** argv)
{
    if (argc != 5) {
        std::fprintf(stderr, "usage: check_glsl_reference SCENE FILE WIDTH HEIGHT\n");
        return 2;
    }
    const std::string scene = argv[1], path = argv[2];
    const int width = std::atoi(argv[3]), height = std::atoi(argv[4]);
    std::vector<float> reference;
    krs::scenes::for_each_scene([&](const auto& s) {
        if (s.name == scene) reference = krs::scenes::reference_frame(s, s.camera, width, height);
    });
    if (reference.empty()) {
        std::fprintf(stderr, "no scene named %s\n", scene.c_str());
        return 2;
    }
    const auto byte = [&](int x, int bottom_up_row, int c) {
        return long(krs::glsl::framebuffer_byte(
            reference[(std::size_t(bottom_up_row) * std::size_t(width) + std::size_t(x)) * 4 + std::size_t(c)]));
    };
    long rows_differ = 0;
    for (int x = 0; x < width; ++x)
        for (int c = 0; c < 3; ++c) rows_differ += byte(x, 0, c) != byte(x, height - 1, c);
    if (rows_differ == 0) {
        std::fprintf(stderr, "the reference's top and bottom rows are equal: the row order would go unchecked\n");
        return 1;
    }

    auto in = OIIO::ImageInput::open(path);
    if (!in) {
        std::fprintf(stderr, "cannot open %s: %s\n", path.c_str(), OIIO::geterror().c_str());
        return 1;
    }
    const OIIO::ImageSpec spec = in->spec();
    if (spec.width != width || spec.height != height || spec.nchannels != 3 || spec.format != OIIO::TypeDesc::UINT8) {
        std::fprintf(stderr, "%s is %dx%d with %d channels of %s, expected %dx%d RGB of uint8\n", path.c_str(), spec.width,
                     spec.height, spec.nchannels, spec.format.c_str(), width, height);
        return 1;
    }
    std::vector<unsigned char> file(std::size_t(width) * std::size_t(height) * 3);
    if (!in->read_image(0, 0, 0, 3, OIIO::TypeDesc::UINT8, file.data())) {
        std::fprintf(stderr, "cannot read %s: %s\n", path.c_str(), in->geterror().c_str());
        return 1;
    }
    long wrong = 0;
    for (int y = 0; y < height; ++y)
        for (int x = 0; x < width; ++x)
            for (int c = 0; c < 3; ++c) {
                const long expected = byte(x, height - 1 - y, c);
                const long got = file[(std::size_t(y) * std::size_t(width) + std::size_t(x)) * 3 + std::size_t(c)];
                if (got != expected && wrong++ < 5)
                    std::fprintf(stderr, "pixel (%d, %d) channel %d: %ld in the file, %ld in the reference\n", x, y, c,
                                 got, expected);
            }
    if (wrong > 0) {
        std::fprintf(stderr, "%s: %ld of %d channel values differ from the reference\n", path.c_str(), wrong,
                     width * height * 3);
        return 1;
    }
    std::printf("%s: %dx%d, every byte equals the %s reference as a framebuffer stores it, top row first\n", path.c_str(), width,
                height, scene.c_str());
    return 0;
}

// check_example_image FILE WIDTH HEIGHT: the image krs_tree wrote has the requested size, sky
// (blue-dominated) pixels and foliage (green-dominated) pixels, each at least 5% of the frame.
// Exit status 0 when it holds; a message naming what failed otherwise.

#include <OpenImageIO/imageio.h>

#include <cstdio>
#include <cstdlib>
#include <vector>

int main(int argc, char** argv)
{
    if (argc != 4) {
        std::fprintf(stderr, "usage: check_example_image FILE WIDTH HEIGHT\n");
        return 2;
    }
    const int want_w = std::atoi(argv[2]), want_h = std::atoi(argv[3]);
    auto in = OIIO::ImageInput::open(argv[1]);
    if (!in) {
        std::fprintf(stderr, "cannot open %s: %s\n", argv[1], OIIO::geterror().c_str());
        return 1;
    }
    const OIIO::ImageSpec& spec = in->spec();
    if (spec.width != want_w || spec.height != want_h || spec.nchannels < 3) {
        std::fprintf(stderr, "%s is %dx%d with %d channels, expected %dx%d RGB\n", argv[1], spec.width, spec.height,
                     spec.nchannels, want_w, want_h);
        return 1;
    }
    std::vector<float> px(std::size_t(spec.width) * spec.height * spec.nchannels);
    if (!in->read_image(0, 0, 0, spec.nchannels, OIIO::TypeDesc::FLOAT, px.data())) {
        std::fprintf(stderr, "cannot read %s\n", argv[1]);
        return 1;
    }
    long sky = 0, foliage = 0;
    const long total = long(spec.width) * spec.height;
    for (long i = 0; i < total; ++i) {
        const float r = px[i * spec.nchannels], g = px[i * spec.nchannels + 1], b = px[i * spec.nchannels + 2];
        if (b > r + 0.1f && b > g + 0.02f) ++sky;
        if (g > r + 0.05f && g > b + 0.1f) ++foliage;
    }
    std::printf("%s: %.1f%% sky, %.1f%% foliage\n", argv[1], 100.0 * sky / total, 100.0 * foliage / total);
    if (sky * 20 < total || foliage * 20 < total) {
        std::fprintf(stderr, "expected at least 5%% sky and 5%% foliage pixels\n");
        return 1;
    }
    return 0;
}

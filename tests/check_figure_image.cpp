// check_figure_image: the properties the paper's figures 8-12 show, measured on the images
// hypertree_render wrote for them (examples/hypertrees/figure*; the tests in examples/CMakeLists.txt).
// Nothing here knows the pictures: every check compares an image with the render's background or
// with another render of the same tree from the same camera.
//
//   check_figure_image coverage FILE MIN MAX          covered fraction (pixels not the background) in [MIN, MAX]
//   check_figure_image smoother SMOOTH ROUGH RATIO    edge statistic of SMOOTH <= RATIO x that of ROUGH
//   check_figure_image close A B BOUND                mean |A - B| per channel (0..1) of 4 x 4 block means, over
//                                                     the blocks covered in either, <= BOUND; covered
//                                                     fractions within 25% of each other
//   check_figure_image closer A REF B RATIO           that block difference of A from REF <= RATIO x B's
//   check_figure_image brighter BRIGHT DIM GAIN       no pixel of BRIGHT darker than DIM's (2/255 slack), mean gain >= GAIN
//   check_figure_image cleared PART WHOLE FRACTION    PART's covered pixels a subset of WHOLE's (up to 1%), the
//                                                     top FRACTION of WHOLE's covered rows empty in PART
//
// Why the slack: removing voxels (clearing) or averaging them (a level of detail) changes the
// tree's box, and a ray's samples start where it enters the box, so a ray that grazes a voxel can
// sample it in one image and step over it in the other: a few edge pixels of PART lie outside
// WHOLE. A reduced tree is also blurred (its voxels are larger), so it covers more pixels.
//
// The edge statistic is the mean absolute difference of horizontally and vertically adjacent
// pixels, over the pixels where either image is covered: aliasing (one sample per pixel of a
// sub-pixel twig structure) makes neighbours jump between twig and sky, and supersampling
// averages those jumps away, so the statistic falls.
// Exit status 0 when the property holds; 1 with a message naming what failed; 2 for bad usage.

#include <OpenImageIO/imageio.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <string>
#include <vector>

namespace {

struct picture {
    int width = 0, height = 0;
    std::vector<float> rgb; // 3 floats a pixel, top row first
    const float* at(int x, int y) const { return &rgb[(std::size_t(y) * width + x) * 3]; }
};

bool read(const char* file, picture& p)
{
    auto in = OIIO::ImageInput::open(file);
    if (!in) {
        std::fprintf(stderr, "cannot open %s: %s\n", file, OIIO::geterror().c_str());
        return false;
    }
    const OIIO::ImageSpec& spec = in->spec();
    if (spec.nchannels < 3) {
        std::fprintf(stderr, "%s has %d channels, expected RGB\n", file, spec.nchannels);
        return false;
    }
    std::vector<float> px(std::size_t(spec.width) * spec.height * spec.nchannels);
    if (!in->read_image(0, 0, 0, spec.nchannels, OIIO::TypeDesc::FLOAT, px.data())) {
        std::fprintf(stderr, "cannot read %s\n", file);
        return false;
    }
    p.width = spec.width, p.height = spec.height;
    p.rgb.resize(std::size_t(p.width) * p.height * 3);
    for (std::size_t i = 0; i < std::size_t(p.width) * p.height; ++i)
        for (int c = 0; c < 3; ++c) p.rgb[i * 3 + c] = px[i * spec.nchannels + c];
    return true;
}

// hypertree::render_settings' default background (render.hpp), which a ray that hits nothing
// returns exactly, as the examples write it (support/example_io.hpp: gamma 2.2, 8 bits); a
// covered pixel differs from it by more than that rounding.
const float linear_background[3] = {0.78f, 0.86f, 0.95f};

float written(float linear) { return std::round(255.0f * std::pow(linear, 1.0f / 2.2f)) / 255.0f; }

bool covered(const float* px)
{
    for (int c = 0; c < 3; ++c)
        if (std::abs(px[c] - written(linear_background[c])) > 1.5f / 255.0f) return true;
    return false;
}

double coverage(const picture& p)
{
    long n = 0;
    for (int y = 0; y < p.height; ++y)
        for (int x = 0; x < p.width; ++x) n += covered(p.at(x, y));
    return double(n) / (double(p.width) * p.height);
}

double luminance(const float* px) { return 0.2126 * px[0] + 0.7152 * px[1] + 0.0722 * px[2]; }

bool same_size(const picture& a, const picture& b, const char* fa, const char* fb)
{
    if (a.width == b.width && a.height == b.height) return true;
    std::fprintf(stderr, "%s is %dx%d but %s is %dx%d: a figure's images share one camera\n", fa, a.width, a.height, fb, b.width,
                 b.height);
    return false;
}

// The edge statistic (see the top of the file) over pixels covered in `a` or `b`.
double edge_statistic(const picture& p, const picture& a, const picture& b)
{
    double sum = 0;
    long n = 0;
    for (int y = 0; y + 1 < p.height; ++y)
        for (int x = 0; x + 1 < p.width; ++x) {
            if (!covered(a.at(x, y)) && !covered(b.at(x, y))) continue;
            const float* c = p.at(x, y);
            const float* r = p.at(x + 1, y);
            const float* d = p.at(x, y + 1);
            for (int k = 0; k < 3; ++k) sum += std::abs(c[k] - r[k]) + std::abs(c[k] - d[k]);
            ++n;
        }
    return n == 0 ? 0 : sum / double(n);
}

// The first and last rows holding a covered pixel (-1 when none).
std::pair<int, int> covered_rows(const picture& p)
{
    int first = -1, last = -1;
    for (int y = 0; y < p.height; ++y)
        for (int x = 0; x < p.width; ++x)
            if (covered(p.at(x, y))) {
                if (first < 0) first = y;
                last = y;
                break;
            }
    return {first, last};
}

// The mean |a - b| per channel of 4 x 4 block means, over the blocks covered in either image (the
// sky, equal in both, would dilute it). A level of detail keeps what a tree looks like at the
// scale of its voxels, not each twig's pixels: at 100 voxels for a tree ~200 pixels tall a
// reduced voxel spans ~2 pixels, and a twig moves by up to one.
double block_difference(const picture& a, const picture& b)
{
    constexpr int block = 4;
    double sum = 0;
    long n = 0;
    for (int by = 0; by + block <= a.height; by += block)
        for (int bx = 0; bx + block <= a.width; bx += block) {
            double ma[3] = {}, mb[3] = {};
            bool any = false;
            for (int y = by; y < by + block; ++y)
                for (int x = bx; x < bx + block; ++x) {
                    any = any || covered(a.at(x, y)) || covered(b.at(x, y));
                    for (int c = 0; c < 3; ++c) ma[c] += a.at(x, y)[c], mb[c] += b.at(x, y)[c];
                }
            if (!any) continue;
            for (int c = 0; c < 3; ++c) sum += std::abs(ma[c] - mb[c]) / (block * block);
            ++n;
        }
    return n ? sum / (3.0 * double(n)) : 0;
}

double number(const char* text, const char* what)
{
    char* end = nullptr;
    const double v = std::strtod(text, &end);
    if (end == text || *end != '\0' || !std::isfinite(v)) {
        std::fprintf(stderr, "%s: '%s' is not a finite number\n", what, text);
        std::exit(2);
    }
    return v;
}

} // namespace

int main(int argc, char** argv)
{
    const std::string mode = argc > 1 ? argv[1] : "";
    if (!(argc == 5 && (mode == "coverage" || mode == "smoother" || mode == "close" || mode == "brighter" || mode == "cleared" || mode == "moved")) &&
        !(argc == 6 && mode == "closer")) {
        std::fprintf(stderr, "usage: check_figure_image coverage|smoother|close|brighter|cleared|moved FILE FILE|NUMBER NUMBER\n"
                             "       check_figure_image closer A REFERENCE B RATIO\n");
        return 2;
    }
    picture a;
    if (!read(argv[2], a)) return 1;
    if (mode == "coverage") {
        const double lo = number(argv[3], "MIN"), hi = number(argv[4], "MAX"), c = coverage(a);
        std::printf("%s: %.2f%% covered (allowed %.2f%% .. %.2f%%)\n", argv[2], 100 * c, 100 * lo, 100 * hi);
        if (!(c >= lo && c <= hi)) {
            std::fprintf(stderr, "coverage %.4f outside [%g, %g]\n", c, lo, hi);
            return 1;
        }
        return 0;
    }
    picture b;
    if (!read(argv[3], b) || !same_size(a, b, argv[2], argv[3])) return 1;
    if (mode == "closer") {
        picture c;
        if (!read(argv[4], c) || !same_size(a, c, argv[2], argv[4])) return 1;
        const double ratio = number(argv[5], "RATIO"), da = block_difference(a, b), dc = block_difference(c, b);
        std::printf("block difference from %s: %s %.5f, %s %.5f, ratio %.3f (allowed <= %g)\n", argv[3], argv[2], da, argv[4], dc,
                    dc > 0 ? da / dc : 0.0, ratio);
        if (!(dc > 0 && da <= ratio * dc)) {
            std::fprintf(stderr, "%s is not closer to %s than %s by the ratio %g\n", argv[2], argv[3], argv[4], ratio);
            return 1;
        }
        return 0;
    }
    const double bound = number(argv[4], "the bound");
    if (mode == "smoother") {
        const double sa = edge_statistic(a, a, b), sb = edge_statistic(b, a, b);
        std::printf("edge statistic: %s %.5f, %s %.5f, ratio %.3f (allowed <= %g)\n", argv[2], sa, argv[3], sb, sb > 0 ? sa / sb : 0.0, bound);
        if (!(sb > 0 && sa <= bound * sb)) {
            std::fprintf(stderr, "%s is not smoother than %s by the ratio %g\n", argv[2], argv[3], bound);
            return 1;
        }
        return 0;
    }
    if (mode == "moved") {
        // The covered pixels of one image and not the other, over those covered in either: 0 for
        // the same silhouette, near 1 for disjoint ones. Noise that moves thin branches by a
        // pixel or more changes a share of their pixels of the order of shift / width.
        long either = 0, one = 0;
        for (int y = 0; y < a.height; ++y)
            for (int x = 0; x < a.width; ++x) {
                const bool ca = covered(a.at(x, y)), cb = covered(b.at(x, y));
                either += ca || cb;
                one += ca != cb;
            }
        const double share = either ? double(one) / double(either) : 0;
        std::printf("%s against %s: %.2f%% of the covered pixels covered in one only (allowed >= %.2f%%)\n", argv[2], argv[3], 100 * share,
                    100 * bound);
        if (!(share >= bound)) {
            std::fprintf(stderr, "%s does not differ from %s by the share %g\n", argv[2], argv[3], bound);
            return 1;
        }
        return 0;
    }
    if (mode == "close") {
        const double mean = block_difference(a, b), ca = coverage(a), cb = coverage(b);
        std::printf("mean |%s - %s| = %.5f (allowed <= %g); covered %.2f%% and %.2f%%\n", argv[2], argv[3], mean, bound, 100 * ca, 100 * cb);
        if (!(mean <= bound) || !(ca > 0 && cb > 0) || std::abs(ca - cb) > 0.25 * std::max(ca, cb)) {
            std::fprintf(stderr, "the images differ more than allowed (mean difference or covered fraction)\n");
            return 1;
        }
        return 0;
    }
    if (mode == "brighter") {
        long darker = 0, shown = 0;
        double gain = 0;
        for (int y = 0; y < a.height; ++y)
            for (int x = 0; x < a.width; ++x) {
                const double d = luminance(a.at(x, y)) - luminance(b.at(x, y));
                if (d < -2.0 / 255.0) ++darker;
                if (covered(b.at(x, y))) gain += d, ++shown;
            }
        gain = shown ? gain / double(shown) : 0;
        std::printf("%s against %s: mean luminance gain %.5f over %ld covered pixels (allowed >= %g), %ld pixels darker\n", argv[2],
                    argv[3], gain, shown, bound, darker);
        if (darker > 0 || !(gain >= bound) || shown == 0) {
            std::fprintf(stderr, "%s is not everywhere at least as bright as %s with a mean gain >= %g\n", argv[2], argv[3], bound);
            return 1;
        }
        return 0;
    }
    // cleared
    long extra = 0, kept = 0, whole = 0;
    for (int y = 0; y < a.height; ++y)
        for (int x = 0; x < a.width; ++x) {
            const bool in_part = covered(a.at(x, y)), in_whole = covered(b.at(x, y));
            extra += in_part && !in_whole;
            kept += in_part, whole += in_whole;
        }
    const auto [part_top, part_bottom] = covered_rows(a);
    const auto [whole_top, whole_bottom] = covered_rows(b);
    const double emptied = whole_bottom > whole_top && part_top >= 0 ? double(part_top - whole_top) / double(whole_bottom - whole_top) : 0;
    std::printf("%s: %ld covered pixels of %s's %ld, %ld outside it; the top %.1f%% of its rows emptied (allowed >= %.1f%%)\n", argv[2], kept,
                argv[3], whole, extra, 100 * emptied, 100 * bound);
    if (extra * 100 > kept || kept == 0 || !(emptied >= bound)) {
        std::fprintf(stderr, "%s is not %s with its top cleared\n", argv[2], argv[3]);
        return 1;
    }
    return 0;
}

// krs_tree: renders a KRS tree (2^14 twigs, 4 leaves each: ~100k kernel instances) to a PNG.
//
//     krs_tree [--width W] [--height H] [--threads N] [--levels L] [--seed S] [--output FILE]
//
// Sphere traces every pixel with the pixel-footprint threshold, shades with Lambert and a
// sphere-traced shadow ray, and prints the time per frame and per ray. Threads render 16x16 tiles
// taken from a shared counter; the library itself starts no threads.

#include "krs/expansion.hpp"
#include "krs/model/tree.hpp"
#include "krs/shade/lambert.hpp"
#include "krs/trace/camera.hpp"
#include "krs/trace/located_hit.hpp"

#include <OpenImageIO/imageio.h>

#include <algorithm>
#include <atomic>
#include <chrono>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <string>
#include <thread>
#include <vector>

namespace {

struct options {
    int width = 960, height = 720, threads = 0, levels = 15;
    unsigned seed = 7;
    std::string output = "krs_tree.png";
};

options parse(int argc, char** argv)
{
    options o;
    for (int i = 1; i < argc; ++i) {
        const std::string a = argv[i];
        auto value = [&](const char* name) -> std::string {
            if (i + 1 >= argc) {
                std::fprintf(stderr, "krs_tree: %s needs a value\n", name);
                std::exit(2);
            }
            return argv[++i];
        };
        auto number = [&](const char* name, int lo, int hi) {
            const std::string v = value(name);
            char* end = nullptr;
            const long n = std::strtol(v.c_str(), &end, 10);
            if (end == v.c_str() || *end != '\0' || n < lo || n > hi) {
                std::fprintf(stderr, "krs_tree: %s must be an integer in [%d, %d] (got '%s')\n", name, lo, hi, v.c_str());
                std::exit(2);
            }
            return int(n);
        };
        if (a == "--width") o.width = number("--width", 1, 16384);
        else if (a == "--height") o.height = number("--height", 1, 16384);
        else if (a == "--threads") o.threads = number("--threads", 0, 1024);
        else if (a == "--levels") o.levels = number("--levels", 1, 30);
        else if (a == "--seed") o.seed = unsigned(number("--seed", 0, 1 << 30));
        else if (a == "--output") o.output = value("--output");
        else {
            std::fprintf(stderr, "usage: krs_tree [--width W] [--height H] [--threads N] [--levels L] [--seed S] [--output FILE]\n");
            std::exit(2);
        }
    }
    if (o.threads == 0) o.threads = int(std::max(1u, std::thread::hardware_concurrency()));
    return o;
}

krs::vec3f sky(const krs::vec3f& d)
{
    const float t = std::clamp(0.5f + 0.5f * d.y, 0.0f, 1.0f);
    return krs::vec3f{0.62f, 0.75f, 0.92f} * (1.0f - t) + krs::vec3f{0.25f, 0.45f, 0.85f} * t;
}

} // namespace

int main(int argc, char** argv)
{
    const options opt = parse(argc, argv);
    krs::model::tree_style style;
    style.levels = opt.levels;
    style.seed = opt.seed;
    krs::model::tree_parameters parameters = krs::model::grow_tree(style);
    const krs::model::tree_sequence tree = krs::model::build_tree(parameters);
    // Frame the tree: the box around every instance's bounding sphere, ground left out.
    parameters.ground_height.reset();
    const krs::model::tree_sequence crown_only = krs::model::build_tree(parameters);
    krs::vec3d lo{1e30, 1e30, 1e30}, hi{-1e30, -1e30, -1e30};
    for (const auto& instance : krs::expand(crown_only).instances) {
        const krs::bounding_sphere b = std::visit([](const auto& k) { return k.bound(); }, crown_only.kernels()[instance.kernel]);
        const krs::vec3d c = instance.to_world.apply(krs::vec3d(b.center)), r{b.radius, b.radius, b.radius};
        lo = krs::min(lo, c - r);
        hi = krs::max(hi, c + r);
    }
    const krs::vec3d mid = (lo + hi) * 0.5;
    const krs::bounding_sphere crown{{float(mid.x), float(mid.y), float(mid.z)}, float(0.5 * krs::length(hi - lo))};
    std::printf("tree: %zu mirrors, %zu kernels, %.0f kernel instances, bound radius %.2f\n", tree.mirror_count(),
                tree.kernels().size(), tree.instance_count(), double(crown.radius));

    // Far enough that the crown's bounding sphere fills the 40-degree vertical field of view.
    const float fov = 40.0f, away = 0.8f * crown.radius / std::sin(0.5f * fov * 3.14159265f / 180.0f);
    const krs::vec3f look = {crown.center.x, crown.center.y, crown.center.z};
    // Look across the first fork's mirror (its two halves side by side), turned 30 degrees so the
    // symmetry is not seen head-on (paper section 5), from slightly above.
    const krs::vec3f n = tree.mirrors().empty() ? krs::vec3f{1, 0, 0} : tree.mirrors().back().normal;
    const krs::vec3f across = krs::normalize(krs::cross(n, krs::vec3f{0, 1, 0}) * 0.866f + n * 0.5f);
    const krs::vec3f eye = look + krs::normalize(across + krs::vec3f{0, 0.15f, 0}) * away;
    const krs::pinhole_camera camera(eye, look, {0, 1, 0}, fov, opt.width, opt.height);
    krs::trace_options trace;
    trace.pixel_footprint = camera.pixel_footprint() * 0.5f; // unbounding sphere under half a pixel
    trace.max_distance = 4.0f * away;
    trace.threshold_floor = 1e-5f;
    trace.validate();
    const krs::directional_light sun({0.5f, 0.8f, 0.35f}, {1.0f, 0.97f, 0.9f});

    std::vector<float> pixels(std::size_t(opt.width) * opt.height * 3);
    constexpr int tile = 16;
    const int tiles_x = (opt.width + tile - 1) / tile, tiles_y = (opt.height + tile - 1) / tile;
    const int tiles = tiles_x * tiles_y;
    std::atomic<int> next{0}, done{0};
    std::atomic<long long> steps{0}, hits{0};

    auto worker = [&] {
        long long my_steps = 0, my_hits = 0;
        for (int k; (k = next.fetch_add(1)) < tiles; done.fetch_add(1)) {
            const int x0 = (k % tiles_x) * tile, y0 = (k / tiles_x) * tile;
            for (int y = y0; y < std::min(y0 + tile, opt.height); ++y)
                for (int x = x0; x < std::min(x0 + tile, opt.width); ++x) {
                    const krs::ray<float> r = camera.primary_ray(x + 0.5f, y + 0.5f);
                    const krs::located_hit<float> h = krs::trace_and_locate(tree, r, trace);
                    my_steps += h.steps;
                    krs::vec3f color = sky(r.direction);
                    if (h.found) {
                        ++my_hits;
                        const krs::vec3f& p = h.position;
                        const krs::location<float>& where = h.where;
                        krs::vec3f n = tree.normal(where);
                        if (krs::dot(n, r.direction) > 0) n = -n; // a ray that started inside sees the back
                        krs::lambert_material material;
                        const auto& kernel = tree.kernels()[where.kernel];
                        if (std::holds_alternative<krs::sphere>(kernel)) {
                            // Leaves: vary the green by the reflections that placed this instance.
                            const float v = float((where.reflections * 0x9E3779B97F4A7C15ull) >> 40 & 0xff) / 255.0f;
                            material.albedo = {0.18f + 0.12f * v, 0.42f + 0.15f * v, 0.10f};
                        } else if (std::holds_alternative<krs::plane>(kernel)) {
                            material.albedo = {0.45f, 0.40f, 0.28f};
                        } else {
                            material.albedo = {0.36f, 0.24f, 0.15f};
                        }
                        color = krs::shade_lambert(tree, p, n, sun, material, trace.threshold(h.t), 2.0f * crown.radius);
                    }
                    float* out = &pixels[(std::size_t(y) * opt.width + x) * 3];
                    out[0] = color.x, out[1] = color.y, out[2] = color.z;
                }
        }
        steps += my_steps;
        hits += my_hits;
    };

    const auto start = std::chrono::steady_clock::now();
    std::vector<std::thread> pool;
    for (int i = 0; i < opt.threads; ++i) pool.emplace_back(worker);
    const bool interactive = std::getenv("CI") == nullptr;
    for (int shown = -1; done.load() < tiles;) {
        const int percent = 100 * done.load() / tiles;
        if (percent != shown && (interactive || percent % 25 == 0)) {
            std::printf("\r[%-40s] %3d%%", std::string(std::size_t(percent * 40 / 100), '#').c_str(), percent);
            std::fflush(stdout);
            shown = percent;
        }
        std::this_thread::sleep_for(std::chrono::milliseconds(50));
    }
    for (std::thread& t : pool) t.join();
    const double seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
    const double rays = double(opt.width) * opt.height;
    std::printf("\r[%s] 100%%\n", std::string(40, '#').c_str());
    std::printf("frame: %.3f s on %d threads; %.2f core-us per primary ray (shading and shadow ray included); "
                "%.1f steps per primary ray; %.1f%% of pixels hit\n",
                seconds, opt.threads, 1e6 * seconds * opt.threads / rays, double(steps.load()) / rays,
                100.0 * double(hits.load()) / rays);

    // Gamma-encode to 8 bits.
    std::vector<unsigned char> bytes(pixels.size());
    for (std::size_t i = 0; i < pixels.size(); ++i)
        bytes[i] = (unsigned char)std::lround(255.0f * std::pow(std::clamp(pixels[i], 0.0f, 1.0f), 1.0f / 2.2f));
    auto file = OIIO::ImageOutput::create(opt.output);
    const OIIO::ImageSpec spec(opt.width, opt.height, 3, OIIO::TypeDesc::UINT8);
    if (!file || !file->open(opt.output, spec) || !file->write_image(OIIO::TypeDesc::UINT8, bytes.data())) {
        std::fprintf(stderr, "krs_tree: cannot write %s: %s\n", opt.output.c_str(), OIIO::geterror().c_str());
        return 1;
    }
    file->close();
    std::printf("wrote %s (%dx%d)\n", opt.output.c_str(), opt.width, opt.height);
    return 0;
}

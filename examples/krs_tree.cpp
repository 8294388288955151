// krs_tree: renders a KRS tree (2^14 twigs, 4 leaves each: ~100k kernel instances) to a PNG.
//
//     krs_tree [--width W] [--height H] [--threads N] [--levels L] [--seed S] [--output FILE]
//
// Sphere traces every pixel with the pixel-footprint threshold, shades with Lambert and a
// sphere-traced shadow ray, and prints the time per frame and per ray. Everything runs on the
// packet path: threads take 16x16 tiles from a shared counter, run the tile prepass (section 4.1)
// and stream the tile's rays through trace_stream (lane refill, two interleaved packets, mild
// over-relaxation); then they shade tiles in packets (per-lane locate for normals and materials,
// packet shadow rays). The library itself starts no threads.

#include "krs/expansion.hpp"
#include "krs/model/tree.hpp"
#include "krs/shade/lambert.hpp"
#include "krs/trace/camera.hpp"
#include "krs/trace/packet_shade.hpp"
#include "krs/trace/packet_trace.hpp"
#include "krs/trace/tile_rays.hpp"

#include "support/command_line.hpp"
#include "support/common_options.hpp"
#include "support/error_message.hpp"
#include "support/example_io.hpp"
#include "support/output_path.hpp"
#include "support/progress.hpp"
#include "support/tiles.hpp"

#include <algorithm>
#include <filesystem>
#include <array>
#include <cmath>
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
    example::command_line args("krs_tree", "Renders a KRS tree to a PNG and prints the time per frame and per ray.");
    example::add_image_size(args, o.width, o.height);
    example::add_threads(args, o.threads);
    // At most 20: each level doubles the twigs, and 21 levels make 6.3 M kernel instances, over
    // the 4.19 M (2^22) that krs::expand takes (the renderer expands every instance).
    args.integer("--levels", o.levels, 1, 20, "branching levels of the tree (20 makes ~3.1 M kernel instances)");
    example::add_seed(args, o.seed, "the tree's random growth");
    example::add_output_file(args, o.output, "FILE.png", "the PNG to write (.png; its directory must exist)");
    args.parse(argc, argv);
    example::require_output_file(args, "--output", o.output, {".png"});
    o.threads = example::thread_count(o.threads);
    return o;
}

krs::vec3f sky(const krs::vec3f& d)
{
    const float t = std::clamp(0.5f + 0.5f * d.y, 0.0f, 1.0f);
    return krs::vec3f{0.62f, 0.75f, 0.92f} * (1.0f - t) + krs::vec3f{0.25f, 0.45f, 0.85f} * t;
}

} // namespace

int render(const options& opt)
{
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
    const krs::directional_light sun({0.5f, 0.8f, 0.35f}, {1.0f, 0.97f, 0.9f});

    trace.omega = 1.2f;
    trace.validate();
    std::vector<float> pixels(std::size_t(opt.width) * opt.height * 3);
    std::vector<float> depth(std::size_t(opt.width) * opt.height, INFINITY);
    // Tiles are traced (phase 0) and then shaded (phase 1); `done` counts both for the progress bar.
    example::tile_queue trace_tiles(opt.width, opt.height), shade_tiles(opt.width, opt.height);
    const int tiles = trace_tiles.count();
    std::atomic<int> done{0};
    std::atomic<long long> traced_rays{0};
    std::atomic<long long> steps{0}, hits{0};
    using P = krs::packet_f;
    constexpr std::size_t W = krs::lane_count<P>;

    // Rays are clipped to the tree's bounding box (a miss outside it costs no field evaluation).
    const krs::box_clip clip(krs::field_box(tree), camera.eye(), trace);
    auto worker = [&](int) {
        // Phase 0: one ray stream per thread over the tiles it takes; a tile's rays start at its
        // prepass depth.
        example::tile traced;
        krs::tile_prepass pre;
        auto take_tile = [&] {
            if (!trace_tiles.take(traced)) return false;
            pre = krs::prepass_tile(tree, camera, traced.x0, traced.y0, traced.x1, traced.y1, trace);
            done.fetch_add(1);
            return true;
        };
        krs::tile_rays<P> rays;
        auto next = [&](krs::ray_job& job) {
            while (!rays.pop(job)) {
                if (!take_tile()) return false;
                rays.fill(camera, traced.x0, traced.y0, traced.x1, traced.y1, pre, trace.max_distance, clip);
            }
            return true;
        };
        long long my_hits = 0;
        auto finished = [&](std::uint32_t id, const krs::hit<float>& h) {
            depth[id] = h.found ? h.t : INFINITY;
            my_hits += h.found ? 1 : 0;
        };
        const krs::stream_stats st = krs::trace_stream<P, 2>(tree, next, finished, trace);
        steps += st.evaluations;
        hits += my_hits;
        traced_rays += st.rays;
        // Phase 1 needs every depth: wait until every thread's rays are traced.
        while (traced_rays.load() < (long long)opt.width * opt.height) std::this_thread::yield();

        // Phase 1: shade tiles W pixels at a time.
        for (example::tile shaded; shade_tiles.take(shaded); done.fetch_add(1)) {
            const int sx0 = shaded.x0, sy0 = shaded.y0, sx1 = shaded.x1, sy1 = shaded.y1;
            const int count = (sx1 - sx0) * (sy1 - sy0);
            for (int first = 0; first < count; first += int(W)) {
                alignas(64) float xs[W], ys[W], ts[W];
                alignas(64) bool lane_hit[W];
                for (std::size_t i = 0; i < W; ++i) {
                    const int q = std::min(first + int(i), count - 1);
                    xs[i] = float(sx0 + q % (sx1 - sx0)), ys[i] = float(sy0 + q / (sx1 - sx0));
                    const float t = depth[std::size_t(ys[i]) * opt.width + std::size_t(xs[i])];
                    lane_hit[i] = std::isfinite(t) && first + int(i) < count;
                    ts[i] = lane_hit[i] ? t : 0.0f;
                }
                const krs::ray<P> r = camera.primary_ray(P::load_aligned(xs) + P(0.5f), P::load_aligned(ys) + P(0.5f));
                const auto found = krs::mask_t<P>::load_aligned(lane_hit);
                const P t = P::load_aligned(ts);
                const krs::vec3<P> p = krs::point_at(r, t);
                std::array<krs::location<float>, W> where;
                krs::vec3<P> n = krs::locate_lanes(tree, p, found, where);
                n = krs::select(krs::dot(n, r.direction) > P(0), -n, n); // a ray that started inside sees the back
                alignas(64) float ax[W], ay[W], az[W];
                for (std::size_t i = 0; i < W; ++i) {
                    krs::vec3f albedo{0.36f, 0.24f, 0.15f};
                    const auto& kernel = tree.kernels()[where[i].kernel];
                    if (std::holds_alternative<krs::sphere>(kernel)) {
                        // Leaves: vary the green by the reflections that placed this instance.
                        const float v = float((where[i].reflections * 0x9E3779B97F4A7C15ull) >> 40 & 0xff) / 255.0f;
                        albedo = {0.18f + 0.12f * v, 0.42f + 0.15f * v, 0.10f};
                    } else if (std::holds_alternative<krs::plane>(kernel)) {
                        albedo = {0.45f, 0.40f, 0.28f};
                    }
                    ax[i] = albedo.x, ay[i] = albedo.y, az[i] = albedo.z;
                }
                const krs::vec3<P> albedo{P::load_aligned(ax), P::load_aligned(ay), P::load_aligned(az)};
                const krs::vec3<P> lit = krs::shade_lambert_lanes(tree, p, n, sun.direction, sun.color, albedo, 0.15f,
                                                                  trace.threshold(t), 2.0f * crown.radius, found);
                for (std::size_t i = 0; i < W && first + int(i) < count; ++i) {
                    krs::vec3f color = krs::lane_at(lit, i);
                    if (!lane_hit[i]) color = sky(krs::lane_at(r.direction, i));
                    float* out = &pixels[(std::size_t(ys[i]) * opt.width + std::size_t(xs[i])) * 3];
                    out[0] = color.x, out[1] = color.y, out[2] = color.z;
                }
            }
        }
    };

    // Progress goes to stderr (stdout carries the results): a bar on a terminal, tenths in a log.
    example::progress shown(stderr, "render");
    const double seconds = example::run_threads(opt.threads, worker, [&] {
        while (done.load() < 2 * tiles) {
            shown.update(std::size_t(done.load()), std::size_t(2 * tiles));
            std::this_thread::sleep_for(std::chrono::milliseconds(50));
        }
    });
    const double rays = double(opt.width) * opt.height;
    shown.update(std::size_t(2 * tiles), std::size_t(2 * tiles));
    shown.finish();
    std::printf("frame: %.3f s on %d threads; %.2f core-us per primary ray (shading and shadow ray included); "
                "%.1f steps per primary ray (%zu-lane packets); %.1f%% of pixels hit\n",
                seconds, opt.threads, 1e6 * seconds * opt.threads / rays, double(steps.load()) / rays, W,
                100.0 * double(hits.load()) / rays);

    if (!example::write_png("krs_tree", opt.output, opt.width, opt.height, pixels)) return 1;
    std::printf("wrote %s (%dx%d)\n", opt.output.c_str(), opt.width, opt.height);
    return 0;
}

// A failure while working (a tree the expansion refuses, an image that cannot be written) is a
// message and exit status 1, never an abort.
int main(int argc, char** argv)
{
    const options opt = parse(argc, argv);
    try {
        return render(opt);
    } catch (const std::exception& e) {
        std::fprintf(stderr, "krs_tree: %s\n", example::message_of(e).c_str());
        return 1;
    }
}

// krs_fractals: KIFS fold programs and log-spherical self-similarity, written to PNG files:
//
//     kifs_square.png, kifs_cube.png, kifs_menger.png, kifs_sierpinski.png, kifs_koch.png
//         the KIFS gallery (krs/fractal/kifs.hpp): the document's square-on-square fractal as a
//         relief, its cube analogue, the Menger sponge, the Sierpinski tetrahedron, a Koch curve
//     zoom_0.png ... zoom_6.png
//         a zoom into the cube singularity (krs/fractal/log_spherical.hpp) at scales 10^0 ...
//         10^-6: the same detail at every scale, with no loop in the distance function
//
// Each frame prints its time per ray (core-microseconds) and mean march steps per ray.
//
//     krs_fractals [--width W] [--height H] [--threads N] [--output-dir DIR]
//
// Threads render 16x16 tiles taken from a shared counter; the library itself starts no threads.

#include "krs/fractal/kifs.hpp"
#include "krs/fractal/log_spherical.hpp"
#include "krs/shade/normal.hpp"
#include "krs/trace/camera.hpp"
#include "krs/trace/sphere_trace.hpp"

#include "support/command_line.hpp"
#include "support/example_io.hpp"

#include <algorithm>
#include <atomic>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <functional>
#include <string>
#include <thread>
#include <vector>

namespace {

using krs::vec3f;

struct options {
    int width = 256, height = 192, threads = 0;
    std::string output_dir = ".";
};

options parse(int argc, char** argv)
{
    options o;
    example::command_line args("krs_fractals", "Renders the KIFS gallery and a log-spherical zoom to PNG files.");
    args.integer("--width", o.width, 1, 8192, "image width in pixels");
    args.integer("--height", o.height, 1, 8192, "image height in pixels");
    args.integer("--threads", o.threads, 0, 1024, "render threads (0: all cores)");
    args.text("--output-dir", o.output_dir, "the folder the PNG files go to", "DIR");
    args.parse(argc, argv);
    o.threads = example::thread_count(o.threads);
    return o;
}

struct ray_counts {
    long long rays = 0, steps = 0;
};

const vec3f light_direction = krs::normalize(vec3f{0.5f, 0.8f, 0.35f});

// Traces one camera ray through `field` and shades the hit with a gradient normal: Lambert from one
// light, a sky term, and a cheap occlusion from the step count (rays that crept through crevices).
template <class F>
vec3f shade_pixel(const F& field, const krs::pinhole_camera& camera, const krs::trace_options& trace, float x,
                  float y, const vec3f& albedo, ray_counts& counts)
{
    const krs::ray<float> r = camera.primary_ray(x + 0.5f, y + 0.5f);
    const krs::hit<float> h = krs::sphere_trace(field, r, trace);
    ++counts.rays, counts.steps += h.steps;
    const float sky = 0.5f + 0.5f * r.direction.y;
    if (!h.found) return vec3f{0.08f, 0.09f, 0.12f} * (1.0f - sky) + vec3f{0.25f, 0.30f, 0.40f} * sky;
    const vec3f p = krs::point_at(r, h.t);
    vec3f n = krs::surface_normal(field, p, 0.5f * trace.threshold(h.t));
    if (krs::dot(n, r.direction) > 0) n = -n;
    const float diffuse = std::max(krs::dot(n, light_direction), 0.0f);
    const float occlusion = std::clamp(1.0f - float(h.steps) / float(trace.max_steps) * 2.5f, 0.15f, 1.0f);
    const float ambient = 0.25f + 0.15f * n.y;
    const float k = (0.8f * diffuse + ambient) * occlusion;
    return vec3f{albedo.x * k, albedo.y * k, albedo.z * k};
}

// Renders `pixel(x, y, counts)` into dir/name.png over tiles and threads; prints time per ray and
// mean steps; returns seconds.
double render(const options& opt, const std::string& name,
              const std::function<vec3f(float, float, ray_counts&)>& pixel)
{
    std::vector<float> pixels(std::size_t(opt.width) * std::size_t(opt.height) * 3);
    constexpr int tile = 16;
    const int tiles_x = (opt.width + tile - 1) / tile, tiles_y = (opt.height + tile - 1) / tile;
    std::atomic<int> next{0};
    std::vector<ray_counts> counts(std::size_t(opt.threads));
    auto worker = [&](ray_counts& mine) {
        for (int k; (k = next.fetch_add(1)) < tiles_x * tiles_y;) {
            const int x0 = (k % tiles_x) * tile, y0 = (k / tiles_x) * tile;
            for (int y = y0; y < std::min(y0 + tile, opt.height); ++y)
                for (int x = x0; x < std::min(x0 + tile, opt.width); ++x) {
                    const vec3f c = pixel(float(x), float(y), mine);
                    float* out = &pixels[(std::size_t(y) * std::size_t(opt.width) + std::size_t(x)) * 3];
                    out[0] = c.x, out[1] = c.y, out[2] = c.z;
                }
        }
    };
    const auto start = std::chrono::steady_clock::now();
    std::vector<std::thread> pool;
    for (int i = 0; i < opt.threads; ++i) pool.emplace_back(worker, std::ref(counts[std::size_t(i)]));
    for (std::thread& t : pool) t.join();
    const double seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
    ray_counts total;
    for (const ray_counts& c : counts) total.rays += c.rays, total.steps += c.steps;

    const std::string path = opt.output_dir + "/" + name + ".png";
    if (!example::write_png(path, opt.width, opt.height, pixels)) std::exit(1);
    std::printf("%-16s %6.2f s  %7.2f core-us per ray  %6.1f steps per ray  -> %s\n", name.c_str(), seconds,
                1e6 * seconds * opt.threads / double(std::max(total.rays, 1LL)),
                double(total.steps) / double(std::max(total.rays, 1LL)), path.c_str());
    std::fflush(stdout);
    return seconds;
}

template <class F>
double gallery_frame(const options& opt, const std::string& name, const F& field, const vec3f& eye, const vec3f& target,
                     const vec3f& albedo)
{
    const krs::pinhole_camera camera(eye, target, {0, 1, 0}, 40.0f, opt.width, opt.height);
    krs::trace_options trace;
    trace.pixel_footprint = camera.pixel_footprint() * 0.5f;
    trace.threshold_floor = 1e-5f;
    trace.max_distance = 20.0f;
    trace.max_steps = 256;
    trace.validate();
    return render(opt, name, [&](float x, float y, ray_counts& c) {
        return shade_pixel(field, camera, trace, x, y, albedo, c);
    });
}

} // namespace

int main(int argc, char** argv)
{
    const options opt = parse(argc, argv);
    double total = 0;
    int frames = 0;

    // ---- KIFS gallery ----
    total += gallery_frame(opt, "kifs_square", krs::make_square_fractal(6, 0.3f), {0.9f, 1.6f, -4.2f}, {0, 0, 0},
                           {0.85f, 0.55f, 0.30f});
    total += gallery_frame(opt, "kifs_cube", krs::make_cube_fractal(5), {2.6f, 2.2f, -3.2f}, {0, 0, 0},
                           {0.45f, 0.65f, 0.85f});
    total += gallery_frame(opt, "kifs_menger", krs::make_menger_sponge(4), {2.2f, 1.8f, -2.8f}, {0, 0, 0},
                           {0.80f, 0.78f, 0.72f});
    total += gallery_frame(opt, "kifs_sierpinski", krs::make_sierpinski_tetrahedron(9), {2.2f, 1.2f, -3.0f},
                           {0, 0, 0}, {0.90f, 0.70f, 0.35f});
    total += gallery_frame(opt, "kifs_koch", krs::make_koch_curve(6, 0.01f), {0.0f, 0.45f, -1.6f}, {0, 0.3f, 0},
                           {0.55f, 0.85f, 0.55f});
    frames += 5;

    // ---- log-spherical zoom: scales 10^0 ... 10^-6 ----
    const krs::cube_singularity singularity = krs::make_cube_singularity(1.0f);
    for (int k = 0; k <= 6; ++k) {
        const float scale = std::pow(10.0f, -float(k));
        // Along an edge direction (-1, 0, -1): the shell's cubes sit on the axes and diagonals, so
        // a cone about this direction is free at every scale and the camera never stands in a cube.
        const vec3f eye = vec3f{-2.2f, 0.35f, -2.2f} * scale;
        const krs::pinhole_camera camera(eye, {0, 0, 0}, {0, 1, 0}, 50.0f, opt.width, opt.height);
        krs::trace_options trace;
        trace.pixel_footprint = camera.pixel_footprint() * 0.5f;
        trace.threshold_floor = 1e-5f * scale;
        trace.max_distance = 20.0f * scale;
        trace.max_steps = 256;
        trace.validate();
        total += render(opt, "zoom_" + std::to_string(k), [&](float x, float y, ray_counts& c) {
            return shade_pixel(singularity, camera, trace, x, y, {0.75f, 0.50f, 0.85f}, c);
        });
        ++frames;
    }
    std::printf("total: %.2f s for %d frames (%dx%d, %d threads)\n", total, frames, opt.width, opt.height, opt.threads);
    return 0;
}

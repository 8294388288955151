// krs_fractals: KIFS fold programs and log-spherical self-similarity, written to PNG files:
//
//     kifs_square.png, kifs_cube.png, kifs_menger.png, kifs_sierpinski.png, kifs_koch.png
//         the KIFS gallery (krs/fractal/kifs_presets.hpp): the document's square-on-square
//         fractal as a relief, its cube analogue, the Menger sponge, the Sierpinski tetrahedron,
//         a Koch curve
//     zoom_0.png ... zoom_6.png
//         a zoom into the cube singularity (krs/fractal/shell_presets.hpp) at scales 10^0 ...
//         10^-6: the same detail at every scale, with no loop in the distance function
//
// The KIFS frames are coloured by their orbits (krs/fractal/kifs_colour.hpp): a point trap and the
// number of folds that moved the point pick the hue, a plane trap the brightness (--colouring off
// renders them in one colour each, as before). Each frame prints its time per ray
// (core-microseconds) and mean march steps per ray.
//
//     krs_fractals [--width W] [--height H] [--threads N] [--output-dir DIR] [--colouring on|off]
//                  [--scene NAME] [--list-scenes]
//
// The frames are the example scenes of krs/scenes/example_scenes.hpp (their fields, cameras, light
// and albedos): --scene renders one of them (cube_singularity: its zoom), --list-scenes names them.
//
// The cross-section view for debugging a field (krs/cross_section.hpp) instead of the frames:
//
//     krs_fractals --slice FIELD [--slice-plane xy|xz|yz] [--slice-offset Z] [--slice-extent E]
//                  [--slice-spacing S] [--width W] [--height H] [--output-dir DIR]
//
// writes slice_FIELD_distance.png (the distance in bands of S with iso lines, the zero line white,
// inside blue, outside orange) and slice_FIELD_gradient.png (|grad d| in grey, red where the slope
// along the gradient exceeds 1: there the field overestimates and a sphere tracer may step
// through), W x H pixels over the
// square [-E, E] (the shorter side scaled to keep pixels square) of the plane at Z along its
// normal, and prints how many pixels overestimate. FIELD is sphere (a reference: none may) or any
// example scene (glsl_export --list-scenes lists them all); square, cube, menger,
// sierpinski and koch, the older names of the kifs_ scenes, are still taken.
//
// Threads render 16x16 tiles taken from a shared counter (support/tiles.hpp); the library itself
// starts no threads.

#include "krs/cross_section.hpp"
#include "krs/fractal/kifs.hpp"
#include "krs/fractal/kifs_colour.hpp"
#include "krs/kernels/sphere.hpp"
#include "krs/scenes/example_scenes.hpp"
#include "krs/shade/normal.hpp"
#include "krs/trace/camera.hpp"
#include "krs/trace/sphere_trace.hpp"

#include "support/command_line.hpp"
#include "support/common_options.hpp"
#include "support/error_message.hpp"
#include "support/example_io.hpp"
#include "support/output_path.hpp"
#include "support/scene_choice.hpp"
#include "support/tiles.hpp"

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <functional>
#include <optional>
#include <type_traits>
#include <utility>
#include <string>
#include <vector>

namespace {

using krs::vec3f;
namespace ex = krs::scenes;

// The frames of the gallery, and the scene whose zoom follows them.
template <class E>
constexpr bool gallery_entry = std::is_same_v<E, ex::kifs_square_scene> || std::is_same_v<E, ex::kifs_cube_scene> ||
                               std::is_same_v<E, ex::kifs_menger_scene> ||
                               std::is_same_v<E, ex::kifs_sierpinski_scene> || std::is_same_v<E, ex::kifs_koch_scene>;
using zoom_entry = ex::cube_singularity_scene;

// The older --slice names of the KIFS scenes (before the scenes had one name in every program).
const std::pair<const char*, std::string_view> slice_aliases[] = {{"square", ex::kifs_square_scene::name},
                                                                   {"cube", ex::kifs_cube_scene::name},
                                                                   {"menger", ex::kifs_menger_scene::name},
                                                                   {"sierpinski", ex::kifs_sierpinski_scene::name},
                                                                   {"koch", ex::kifs_koch_scene::name}};

struct options {
    int width = 256, height = 192, threads = 0;
    std::string output_dir = ".", scene;
    std::string colouring = "on";
    // The cross-section view (empty slice: render the frames).
    std::string slice, slice_plane = "xy";
    std::optional<std::uint32_t> seed; // --seed: the sliced scene's, else its own
    float slice_offset = 0.0f, slice_extent = 1.5f, slice_spacing = 0.05f;
};

options parse(int argc, char** argv)
{
    options o;
    example::command_line args("krs_fractals", "Renders the KIFS gallery and a log-spherical zoom to PNG files, or "
                                               "with --slice a cross-section of one field's distance.");
    example::add_image_size(args, o.width, o.height);
    example::add_threads(args, o.threads);
    example::add_output_folder(args, o.output_dir, "the PNG files");
    args.choice("--colouring", o.colouring, {"on", "off"}, "colour the KIFS frames by orbit traps and fold counts");
    std::vector<std::string> frames;
    ex::for_each_scene_entry([&]<class E>() {
        if (gallery_entry<E> || std::is_same_v<E, zoom_entry>) frames.emplace_back(E::name);
    });
    const example::scene_choice choice(args, o.scene, frames, "render this frame only (cube_singularity: its zoom)");
    std::vector<std::string> fields{"sphere"};
    for (const std::string& n : example::all_scene_names()) fields.push_back(n);
    for (const auto& [alias, name] : slice_aliases) fields.emplace_back(alias);
    args.choice("--slice", o.slice, fields,
                "write a cross-section of this field's distance and gradient instead of the frames (square, cube, "
                "menger, sierpinski, koch: older names of the kifs_ scenes)");
    CLI::Option* plane = args.choice("--slice-plane", o.slice_plane, {"xy", "xz", "yz"}, "the plane of the slice");
    CLI::Option* offset = args.number("--slice-offset", o.slice_offset, -1e6, 1e6, false,
                                      "the slice's position along the plane's normal");
    CLI::Option* extent = args.number("--slice-extent", o.slice_extent, 0.0, 1e6, true,
                                      "half the slice's longer side, in world units");
    CLI::Option* spacing = args.number("--slice-spacing", o.slice_spacing, 0.0, 1e6, true,
                                       "world distance between iso lines");
    args.parse(argc, argv);
    o.seed = choice.seed();
    if (o.slice.empty())
        for (const CLI::Option* given : {plane, offset, extent, spacing})
            if (given->count() > 0) args.fail(given->get_name() + " needs --slice FIELD");
    if (!o.slice.empty() && !o.scene.empty()) args.fail("--slice, --scene: a slice or frames, not both");
    for (const auto& [alias, name] : slice_aliases)
        if (o.slice == alias) o.slice = name;
    example::require_output_folder(args, "--output-dir", o.output_dir);
    o.threads = example::thread_count(o.threads);
    return o;
}

struct ray_counts {
    long long rays = 0, steps = 0;
};

// Traces one camera ray through `field` and shades the hit with a gradient normal: Lambert from one
// light (toward `light`, unit), a sky term, and a cheap occlusion from the step count (rays that
// crept through crevices). `albedo(p)` gives the surface colour at the hit point p.
template <class F, class Albedo>
vec3f shade_pixel(const F& field, const krs::pinhole_camera& camera, const krs::trace_options& trace,
                  const vec3f& light, float x, float y, const Albedo& albedo, ray_counts& counts)
{
    const krs::ray<float> r = camera.primary_ray(x + 0.5f, y + 0.5f);
    const krs::hit<float> h = krs::sphere_trace(field, r, trace);
    ++counts.rays, counts.steps += h.steps;
    const float sky = 0.5f + 0.5f * r.direction.y;
    if (!h.found) return vec3f{0.08f, 0.09f, 0.12f} * (1.0f - sky) + vec3f{0.25f, 0.30f, 0.40f} * sky;
    const vec3f p = krs::point_at(r, h.t);
    vec3f n = krs::surface_normal(field, p, 0.5f * trace.threshold(h.t));
    if (krs::dot(n, r.direction) > 0) n = -n;
    const float diffuse = std::max(krs::dot(n, light), 0.0f);
    const float occlusion = std::clamp(1.0f - float(h.steps) / float(trace.max_steps) * 2.5f, 0.15f, 1.0f);
    const float ambient = 0.25f + 0.15f * n.y;
    const float k = (0.8f * diffuse + ambient) * occlusion;
    const vec3f a = albedo(p);
    return vec3f{a.x * k, a.y * k, a.z * k};
}

// The orbit colouring of the KIFS frames: a point trap at the origin and the plane y = 0
// (krs/fractal/orbit_trap.hpp), escape radius 10.
const krs::kifs_colouring gallery_traps{{krs::orbit_trap::point({0, 0, 0}), krs::orbit_trap::plane({0, 1, 0}, 0.0f)}, 10.0f};

// The hue from how near the orbit came to the point trap and how many folds moved the point (a
// cosine palette, one period per ~0.8 of trap or ~16 folds: on the presets' surfaces the trap
// spans about 0.5 and the fold count about 8 between the 10th and 90th percentiles), brightened
// near the plane trap; mixed into `base` so each fractal keeps a tint of its own.
vec3f orbit_albedo(const krs::kifs_colour_result<float>& c, const vec3f& base)
{
    const float near_plane = std::exp(-8.0f * c.trap[1]);
    const float t = 1.2f * c.trap[0] + 0.06f * c.fold_count;
    const float tau = 6.2831853f;
    const vec3f palette{0.55f + 0.45f * std::cos(tau * t), 0.55f + 0.45f * std::cos(tau * (t + 0.33f)),
                        0.55f + 0.45f * std::cos(tau * (t + 0.67f))};
    const float light = 0.75f + 0.25f * near_plane;
    return vec3f{(0.3f * base.x + 0.7f * palette.x) * light, (0.3f * base.y + 0.7f * palette.y) * light,
                 (0.3f * base.z + 0.7f * palette.z) * light};
}

// Renders `pixel(x, y, counts)` into dir/name.png over tiles and threads; prints time per ray and
// mean steps; returns seconds.
double render(const options& opt, const std::string& name,
              const std::function<vec3f(float, float, ray_counts&)>& pixel)
{
    std::vector<float> pixels(std::size_t(opt.width) * std::size_t(opt.height) * 3);
    example::tile_queue tiles(opt.width, opt.height);
    std::vector<ray_counts> counts(std::size_t(opt.threads));
    const double seconds = example::run_threads(opt.threads, [&](int thread) {
        ray_counts& mine = counts[std::size_t(thread)];
        for (example::tile t; tiles.take(t);)
            for (int y = t.y0; y < t.y1; ++y)
                for (int x = t.x0; x < t.x1; ++x) {
                    const vec3f c = pixel(float(x), float(y), mine);
                    float* out = &pixels[(std::size_t(y) * std::size_t(opt.width) + std::size_t(x)) * 3];
                    out[0] = c.x, out[1] = c.y, out[2] = c.z;
                }
    });
    ray_counts total;
    for (const ray_counts& c : counts) total.rays += c.rays, total.steps += c.steps;

    const std::string path = opt.output_dir + "/" + name + ".png";
    if (!example::write_png("krs_fractals", path, opt.width, opt.height, pixels)) std::exit(1);
    std::printf("%-16s %6.2f s  %7.2f core-us per ray  %6.1f steps per ray  -> %s\n", name.c_str(), seconds,
                1e6 * seconds * opt.threads / double(std::max(total.rays, 1LL)),
                double(total.steps) / double(std::max(total.rays, 1LL)), path.c_str());
    std::fflush(stdout);
    return seconds;
}

// A gallery frame: the scene's field, camera, march settings and albedo (`base`).
template <class Program, class Kernel>
double gallery_frame(const options& opt, const ex::scene<krs::kifs<Program, Kernel>>& s)
{
    const krs::kifs<Program, Kernel>& field = s.field;
    const std::string& name = s.name;
    const vec3f& base = s.albedo;
    const krs::pinhole_camera camera = s.camera.with_size(opt.width, opt.height);
    krs::trace_options trace = s.program.primary(camera);
    trace.validate();
    // The colour is a separate call at the hit: the march runs kifs::distance alone.
    const bool coloured = opt.colouring == "on";
    const auto albedo = [&](const vec3f& p) {
        return coloured ? orbit_albedo(krs::kifs_colour(field, p, gallery_traps), base) : base;
    };
    return render(opt, name, [&](float x, float y, ray_counts& c) {
        return shade_pixel(field, camera, trace, s.program.to_light, x, y, albedo, c);
    });
}

// --slice: the cross-section of `field` (see the top of this file). Returns the exit status.
template <class F>
int write_slice(const options& opt, const F& field)
{
    const vec3f x{1, 0, 0}, y{0, 1, 0}, z{0, 0, 1};
    krs::slice_plane plane;
    vec3f normal = z;
    if (opt.slice_plane == "xy") plane.u_axis = x, plane.v_axis = y, normal = z;
    else if (opt.slice_plane == "xz") plane.u_axis = x, plane.v_axis = z, normal = y;
    else plane.u_axis = y, plane.v_axis = z, normal = x;
    plane.origin = normal * opt.slice_offset;
    const float wide = float(std::max(opt.width, opt.height));
    plane.half_width = opt.slice_extent * float(opt.width) / wide;
    plane.half_height = opt.slice_extent * float(opt.height) / wide;
    plane.columns = opt.width;
    plane.rows = opt.height;
    krs::cross_section_options settings;
    settings.iso_spacing = opt.slice_spacing;
    const auto start = std::chrono::steady_clock::now();
    krs::cross_section_image image;
    try {
        image = krs::cross_section(field, plane, settings);
    } catch (const krs::invalid_parameter& e) {
        std::fprintf(stderr, "krs_fractals: %s\n", example::message_of(e).c_str());
        return 2;
    }
    const double seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
    const std::string stem = opt.output_dir + "/slice_" + opt.slice;
    if (!example::write_png("krs_fractals", stem + "_distance.png", opt.width, opt.height, image.distance_image()) ||
        !example::write_png("krs_fractals", stem + "_gradient.png", opt.width, opt.height, image.gradient_image()))
        return 1;
    std::printf("slice %s: %dx%d, plane %s at %g, extent %g, iso spacing %g, gradient step %.3g: flagged %zu of %zu "
                "pixels (slope along the gradient > 1 + %g, or a distance not finite: %zu pixels, magenta), max slope %.5g, "
                "max |grad| %.4g, %.2f s -> %s_distance.png, "
                "%s_gradient.png\n",
                opt.slice.c_str(), opt.width, opt.height, opt.slice_plane.c_str(), double(opt.slice_offset),
                double(opt.slice_extent), double(opt.slice_spacing), image.step, image.overestimating, image.pixels(),
                double(settings.lipschitz_tolerance), image.non_finite, double(image.max_slope), double(image.max_gradient), seconds,
                stem.c_str(), stem.c_str());
    return 0;
}

int slice_main(const options& opt)
{
    if (opt.slice == "sphere") return write_slice(opt, krs::sphere({0, 0, 0}, 1.0f));
    int status = 2;
    ex::with_scene(opt.slice, opt.seed, [&](const auto& s) { status = write_slice(opt, s.field); });
    return status;
}

// The zoom into the cube singularity at scales 10^0 ... 10^-6: the scene's camera moved toward
// its pivot (the origin) by each scale, its march's limits scaled alike.
double zoom(const options& opt, int& frames)
{
    const auto s = zoom_entry::build();
    double total = 0;
    for (int k = 0; k <= 6; ++k) {
        const float scale = std::pow(10.0f, -float(k));
        // Along an edge direction (-1, 0, -1): the shell's cubes sit on the axes and diagonals, so
        // a cone about this direction is free at every scale and the camera never stands in a cube.
        const krs::pinhole_camera rest = s.camera.with_size(opt.width, opt.height);
        const krs::pinhole_camera camera(rest.eye() * scale, rest.pivot() * scale, rest.vertical(),
                                         2.0f * std::atan(rest.tan_half_fov()) * 180.0f / 3.14159265f, opt.width,
                                         opt.height);
        krs::trace_options trace = s.program.primary(camera);
        trace.threshold_floor *= scale;
        trace.max_distance *= scale;
        trace.validate();
        total += render(opt, "zoom_" + std::to_string(k), [&](float x, float y, ray_counts& c) {
            return shade_pixel(s.field, camera, trace, s.program.to_light, x, y, [&](const vec3f&) { return s.albedo; }, c);
        });
        ++frames;
    }
    return total;
}

} // namespace

int main(int argc, char** argv)
{
    const options opt = parse(argc, argv);
    if (!opt.slice.empty()) return slice_main(opt);
    double total = 0;
    int frames = 0;

    ex::for_each_scene_entry([&]<class E>() {
        if (!opt.scene.empty() && opt.scene != E::name) return;
        if constexpr (gallery_entry<E>) {
            total += gallery_frame(opt, E::build());
            ++frames;
        } else if constexpr (std::is_same_v<E, zoom_entry>) {
            total += zoom(opt, frames);
        }
    });
    std::printf("total: %.2f s for %d frames (%dx%d, %d threads)\n", total, frames, opt.width, opt.height, opt.threads);
    return 0;
}

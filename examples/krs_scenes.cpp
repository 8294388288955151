// krs_scenes: the paper's section 7 scenes built from intuitive parameters, shaded with the
// section 6 techniques, written to PNG files:
//
//     forest.png   a forest standing on a terrain folded by the forest's own mirrors (7.2), the
//                  two KRSs traced together as a union with per-component free distances (5.1);
//                  bark textured by torus-capsule uv (6.2); one tree replaced by user geometry (6.4)
//     terrain.png  plane kernels, smooth shading by light interpolation (Algorithm 2, 6.1),
//                  triplanar noise texture in world space (6.2)
//     rock.png     a faceted rock, flat (left) and smooth (right, Algorithm 2) shaded, figure 7;
//                  inside a procedural bound (4.2)
//     mirrors.png  512 spheres from 9 mirrors: axis-aligned (left) beside unaligned, figure 5;
//                  with --reflectivity F0 > 0 the spheres are glossy: each hit traces one
//                  reflected ray (6.5) with the same tracer and mixes in what it sees
//     coral.png    capsules and spheres, displaced by a Lipschitz noise warp (5.2)
//     sponge.png   a Menger-like sponge of box kernels and mirrors, with ambient occlusion (6.5)
//     grass.png    a clump of blades scattered by unaligned mirrors
//
// The scenes are the example scenes of krs/scenes/example_scenes.hpp, at its parameters, cameras
// and lights (the GLSL of glsl/ and krs_export's meshes are of the same scenes); this program
// dresses them: textures, a terrain under the forest, a plane under the rock, coral and sponge.
//
// Every scene has soft shadows and ambient occlusion from sphere-traced secondary rays (6.5),
// computed a packet of pixels at a time (krs::packet_f lanes) once a tile's primary rays are traced.
// Each prints its kernel-instance count and triangle equivalent (the paper's results table; the
// tessellation assumed is at `complexity` below), its time per ray (primary and secondary rays,
// in core-microseconds) and the mean march steps of a primary ray.
//
//     krs_scenes [--width W] [--height H] [--threads N] [--seed S] [--scene NAME] [--output-dir DIR]
//                [--reflectivity F0] [--list-scenes]
//
// Threads render 16x16 tiles taken from a shared counter (support/tiles.hpp); the library itself
// starts no threads.

#include "krs/compose.hpp"
#include "krs/kernels/capsule.hpp"
#include "krs/model/coral.hpp"
#include "krs/model/forest.hpp"
#include "krs/model/forest_ground.hpp"
#include "krs/model/grass.hpp"
#include "krs/model/terrain.hpp"
#include "krs/scenes/example_scenes.hpp"
#include "krs/shade/global.hpp"
#include "krs/shade/kernel_light.hpp"
#include "krs/shade/normal.hpp"
#include "krs/shade/reflection.hpp"
#include "krs/shade/texture.hpp"
#include "krs/trace/camera.hpp"

#include "support/command_line.hpp"
#include "support/common_options.hpp"
#include "support/example_io.hpp"
#include "support/output_path.hpp"
#include "support/scene_choice.hpp"
#include "support/tiles.hpp"

#include <algorithm>
#include <filesystem>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <functional>
#include <optional>
#include <random>
#include <string>
#include <vector>

namespace {

using krs::vec3f;
namespace ex = krs::scenes;

struct options {
    int width = 480, height = 360, threads = 0;
    std::optional<std::uint32_t> seed; // --seed, else each scene's own
    std::string only, output_dir = ".";
    float reflectivity = 0.0f; // mirrors scene: the spheres' reflectivity at normal incidence (0: none)
};

vec3f sky(const vec3f& d)
{
    const float t = std::clamp(0.5f + 0.5f * d.y, 0.0f, 1.0f);
    return vec3f{0.70f, 0.78f, 0.90f} * (1.0f - t) + vec3f{0.30f, 0.48f, 0.82f} * t;
}
vec3f mul(const vec3f& a, const vec3f& b) { return {a.x * b.x, a.y * b.y, a.z * b.z}; }
// GLSL's mix (krs::mix, vec3.hpp) with the weight clamped to [0, 1].
vec3f mix_clamped(const vec3f& a, const vec3f& b, float t) { return krs::mix(a, b, std::clamp(t, 0.0f, 1.0f)); }

const vec3f sun_color{1.0f, 0.95f, 0.85f}, sky_light{0.30f, 0.36f, 0.45f};

// Per-thread counters: rays traced (primary, and secondary: one per soft-shadow march and one per
// ambient-occlusion probe along the normal) and the march steps of primary rays.
struct ray_counts {
    long long primary = 0, secondary = 0, primary_steps = 0;
    void add(const ray_counts& o) { primary += o.primary, secondary += o.secondary, primary_steps += o.primary_steps; }
};

// A pixel's color with its light still to come: base + sun * shadow + sky * occlusion. A scene's
// pixel function returns one; `render` then computes the soft shadows and the ambient occlusion of a
// tile's pixels in packets (krs::soft_shadow and krs::ambient_occlusion for krs::packet_f: the
// lanes of a packet are neighbouring pixels, whose secondary rays march alike) and sums. `kind`
// names the scene's lighting setup (field and options, see `lighting`); -1: no light to compute.
struct lit {
    vec3f base{}, sun{}, sky{};
    int kind = -1;
    vec3f p{}, n{};
    float threshold = 0;  // the primary hit's: the shadow ray's own threshold
    bool shadowed = false; // a shadow ray is cast (the surface faces the sun)
    lit() = default;
    lit(const vec3f& color) : base(color) {} // a pixel without light (sky, a divider)
    vec3f color(float shadow, float occlusion) const { return base + sun * shadow + sky * occlusion; }
};
lit mul(const vec3f& a, lit l)
{
    l.base = mul(a, l.base), l.sun = mul(a, l.sun), l.sky = mul(a, l.sky);
    return l;
}
lit operator+(lit l, const vec3f& c)
{
    l.base = l.base + c;
    return l;
}
// A lit pixel faded toward a plain colour (fog): its light terms fade with its base.
lit fade_to(const lit& a, const vec3f& b, float t)
{
    const float s = std::clamp(t, 0.0f, 1.0f);
    lit l = a;
    l.base = a.base * (1.0f - s) + b * s, l.sun = a.sun * (1.0f - s), l.sky = a.sky * (1.0f - s);
    return l;
}

// Direct sun (diffuse * soft shadow) plus sky light weighted by ambient occlusion, at p with normal
// n, lit by the scene's lighting setup `kind` once the tile's packets are done.
lit light_surface(int kind, const vec3f& p, const vec3f& n, float diffuse, float threshold, ray_counts& counts,
                  const vec3f& sky_color = sky_light)
{
    counts.secondary += 1 + (diffuse > 0.0f);
    lit l;
    l.sun = sun_color * diffuse, l.sky = sky_color;
    l.kind = kind, l.p = p, l.n = n, l.threshold = threshold, l.shadowed = diffuse > 0.0f;
    return l;
}

using P = krs::packet_f;
constexpr std::size_t lanes = krs::lane_count<P>;
// A scene's lighting: for setup `kind`, the soft shadow (lanes `facing`; each lane's own
// threshold) and the ambient occlusion of a packet of shading points.
using lighting = std::function<void(int kind, const krs::vec3<P>& p, const krs::vec3<P>& n, const P& threshold,
                                    const krs::mask_t<P>& facing, P& shadow, P& occlusion)>;

// The usual setup: shadows toward the sun `sun` of hardness 12 searched `reach` far, 5 occlusion
// samples `ao_step` apart.
template <class F>
void light_packet(const F& field, const vec3f& sun, float reach, float ao_step, const krs::vec3<P>& p,
                  const krs::vec3<P>& n, const P& threshold, const krs::mask_t<P>& facing, P& shadow, P& occlusion)
{
    krs::soft_shadow_options s;
    s.hardness = 12.0f;
    s.max_distance = reach;
    s.max_steps = 160;
    shadow = krs::soft_shadow(field, p, n, krs::vec3<P>(sun), s, facing, threshold);
    krs::ambient_occlusion_options a;
    a.step = ao_step;
    a.samples = 5;
    occlusion = krs::ambient_occlusion(field, p, n, a);
}

// Scene complexity as the paper's results table counts it: kernel instances of the full
// expansion, and the triangles a mesh would need for the same result. Assumption: every instance
// tessellated on its own, a torus capsule as a 16 x 8 quad tube (256 triangles), a sphere as a
// twice-subdivided icosahedron (320), a capsule as a 16 x 6 tube with caps (192), a box as 12,
// and a plane instance (a facet clipped by the mirrors) as 2.
struct complexity {
    double instances = 0, triangles = 0;
    complexity& operator+=(const complexity& o) { return instances += o.instances, triangles += o.triangles, *this; }
};
constexpr double triangles_of(const krs::torus_capsule&) { return 256; }
constexpr double triangles_of(const krs::sphere&) { return 320; }
constexpr double triangles_of(const krs::capsule&) { return 192; }
constexpr double triangles_of(const krs::box&) { return 12; }
constexpr double triangles_of(const krs::plane&) { return 2; }
template <class Mirror, class... Kinds>
complexity complexity_of(const krs::basic_sequence<Mirror, Kinds...>& s)
{
    complexity c;
    for (std::size_t k = 0; k < s.kernels().size(); ++k) {
        const double copies = std::ldexp(1.0, int(s.mirror_count() - s.kernel_level(k)));
        c.instances += copies;
        c.triangles += copies * std::visit([](const auto& kernel) { return triangles_of(kernel); }, s.kernels()[k]);
    }
    return c;
}

// How a scene of the list is seen here: its camera at this frame's size (or half its width, for the
// figures of two halves), its program's march settings (threshold, far limit, steps) for primary
// rays, and its light.
struct view {
    krs::pinhole_camera camera;
    krs::trace_options trace;
    vec3f sun;
};
template <class F>
view view_of(const ex::scene<F>& s, int width, int height)
{
    const krs::pinhole_camera camera = s.camera.with_size(width, height);
    krs::trace_options trace = s.program.primary(camera);
    trace.validate();
    return {camera, trace, s.program.to_light};
}

// Renders `pixel(x, y, counts) -> lit` into dir/name.png with tiles over threads, the light of
// each tile's pixels computed in packets by `light`, and reports the scene's complexity, its time
// per ray and steps per primary ray; returns seconds.
double render(const options& opt, const std::string& name, const complexity& scene,
              const std::function<lit(float, float, ray_counts&)>& pixel, const lighting& light)
{
    std::vector<float> pixels(std::size_t(opt.width) * opt.height * 3);
    example::tile_queue tiles(opt.width, opt.height);
    std::vector<ray_counts> counts(std::size_t(opt.threads));
    const double seconds = example::run_threads(opt.threads, [&](int thread) {
        ray_counts& mine = counts[std::size_t(thread)];
        std::vector<lit> shaded;
        std::vector<float*> out;
        for (example::tile t; tiles.take(t);) {
            shaded.clear(), out.clear();
            for (int y = t.y0; y < t.y1; ++y)
                for (int x = t.x0; x < t.x1; ++x) {
                    shaded.push_back(pixel(float(x), float(y), mine));
                    out.push_back(&pixels[(std::size_t(y) * opt.width + x) * 3]);
                }
            // The tile's lit pixels, by lighting setup, W at a time (the last packet's spare lanes
            // repeat its first pixel with facing 0, so they march no shadow ray, and are not
            // written).
            for (int kind = 0;; ++kind) {
                std::vector<std::size_t> todo;
                bool more = false;
                for (std::size_t i = 0; i < shaded.size(); ++i) {
                    if (shaded[i].kind == kind) todo.push_back(i);
                    more = more || shaded[i].kind > kind;
                }
                for (std::size_t first = 0; first < todo.size(); first += lanes) {
                    alignas(64) float px[lanes], py[lanes], pz[lanes], nx[lanes], ny[lanes], nz[lanes], th[lanes];
                    alignas(64) float facing[lanes], shadow[lanes], occlusion[lanes];
                    for (std::size_t j = 0; j < lanes; ++j) {
                        const bool real = first + j < todo.size();
                        const lit& l = shaded[todo[first + (real ? j : 0)]];
                        px[j] = l.p.x, py[j] = l.p.y, pz[j] = l.p.z, nx[j] = l.n.x, ny[j] = l.n.y, nz[j] = l.n.z;
                        th[j] = l.threshold, facing[j] = real && l.shadowed ? 1.0f : 0.0f;
                    }
                    P s, a;
                    light(kind, {P::load_aligned(px), P::load_aligned(py), P::load_aligned(pz)},
                          {P::load_aligned(nx), P::load_aligned(ny), P::load_aligned(nz)}, P::load_aligned(th),
                          P::load_aligned(facing) > P(0.0f), s, a);
                    s.store_aligned(shadow), a.store_aligned(occlusion);
                    for (std::size_t j = 0; j < lanes && first + j < todo.size(); ++j) {
                        lit& l = shaded[todo[first + j]];
                        l.base = l.color(shadow[j], occlusion[j]);
                        l.kind = -1;
                    }
                }
                if (!more) break;
            }
            for (std::size_t i = 0; i < shaded.size(); ++i) {
                const vec3f c = shaded[i].base;
                out[i][0] = c.x, out[i][1] = c.y, out[i][2] = c.z;
            }
        }
    });
    ray_counts total;
    for (const ray_counts& c : counts) total.add(c);

    const std::string path = opt.output_dir + "/" + name + ".png";
    if (!example::write_png("krs_scenes", path, opt.width, opt.height, pixels)) std::exit(1);
    const double rays = double(total.primary + total.secondary);
    std::printf("%-8s %7.2f s  (%dx%d, %d threads) -> %s\n", name.c_str(), seconds, opt.width, opt.height, opt.threads,
                path.c_str());
    std::printf("%-8s %.4g kernel instances, ~%.3g triangles equivalent; %lld primary + %lld secondary rays, "
                "%.2f core-us per ray, %.1f steps per primary ray\n",
                name.c_str(), scene.instances, scene.triangles, total.primary, total.secondary,
                1e6 * seconds * opt.threads / std::max(rays, 1.0),
                double(total.primary_steps) / double(std::max(total.primary, 1LL)));
    std::fflush(stdout);
    return seconds;
}

// ---- scenes ---------------------------------------------------------------------------------------

double forest_scene(const options& opt)
{
    using entry = ex::forest_scene;
    const std::uint32_t seed = opt.seed.value_or(entry::default_seed);
    const view v = view_of(entry::build(seed), opt.width, opt.height);
    krs::model::forest_parameters fp = entry::parameters(seed);
    fp.ground_height.reset(); // the ground is the terrain below
    const krs::model::forest forest = krs::model::build_forest(fp);
    // The terrain folded by the forest's own mirrors (section 7.2): every trunk base on the ground.
    krs::model::terrain_parameters tp;
    tp.levels = 12;
    tp.size = 3.0f * forest.crown.radius;
    tp.slope = 0.22f;
    tp.extra_planes = 2;
    tp.seed = seed + 3;
    const krs::model::plane_sequence ground = krs::model::build_forest_ground(fp, forest, tp);
    // One tree is "broken off" (section 6.4): an empty zone removes it from the KRS, and user
    // geometry (a fallen trunk and crown, which a physics engine could move) stands in for it.
    const vec3f look = forest.bound.center;
    krs::bounding_sphere removed = forest.trees[0];
    for (const krs::bounding_sphere& t : forest.trees)
        if (krs::length(t.center - look) < krs::length(removed.center - look)) removed = t;
    const vec3f base{removed.center.x, 0.0f, removed.center.z};
    const vec3f fallen = base + krs::normalize(vec3f{1, 0, -0.4f}) * (1.4f * removed.radius);
    const float fallen_ground = -ground.distance(fallen + vec3f{0, 2.0f, 0}) + 2.0f; // roughly: the slopes are gentle
    const krs::capsule trunk(base + vec3f{0, 0.2f, 0}, fallen + vec3f{0, fallen_ground + 0.15f, 0}, 0.2f);
    const krs::sphere crown(fallen + vec3f{0, fallen_ground + 0.6f, 0}, 0.35f * removed.radius);
    using zoned = krs::with_empty_zones<krs::model::tree_sequence>;
    const zoned trees(forest.sequence, {removed});
    using trees_field = krs::bounded<zoned>;
    const krs::union_of<trees_field, krs::model::plane_sequence, krs::capsule, krs::sphere> scene(
        trees_field(trees, forest.bound, 1.0f), ground, trunk, crown);
    // Secondary rays (soft shadows, ambient occlusion) use the fields without their bounds: the
    // bound's distance is a valid but loose underestimate, and a penumbra or occlusion estimate
    // computed from it would show the bounding sphere.
    const krs::union_of<zoned, krs::model::plane_sequence, krs::capsule, krs::sphere> exact(trees, ground, trunk, crown);
    std::printf("forest: %zu trees of %.0f kernel instances each, standing on a %zu-mirror terrain\n", forest.tree_count,
                forest.tree_instances, ground.mirror_count());

    const float span = forest.bound.radius;
    const krs::fractal_noise ground_noise(4, 0.3f);
    complexity c = complexity_of(forest.sequence);
    c += complexity_of(ground);

    return render(opt, "forest", c, [&](float x, float y, ray_counts& counts) -> lit {
        const krs::ray<float> r = v.camera.primary_ray(x + 0.5f, y + 0.5f);
        const auto h = krs::union_trace(scene, r, v.trace);
        ++counts.primary, counts.primary_steps += h.steps;
        if (!h.found) return sky(r.direction);
        const vec3f p = krs::point_at(r, h.t);
        const float threshold = v.trace.threshold(h.t);
        vec3f n{0, 1, 0}, albedo{0.35f, 0.30f, 0.18f};
        float diffuse = 0;
        if (h.nearest == 1) {
            // Terrain: Algorithm 2 smooths the creases of the folded planes.
            const float band = krs::smoothing_threshold(h.t, v.camera.pixel_footprint(), 6.0f) + 0.05f;
            const auto k = krs::shade_in_kernel_space(ground, p, v.sun, -r.direction, band);
            diffuse = std::max(krs::dot(k.normal, k.light), 0.0f);
            n = ground.normal(p);
            albedo = mix_clamped(albedo, vec3f{0.22f, 0.32f, 0.12f}, 0.5f + 0.5f * ground_noise(p));
        } else if (h.nearest == 2) {
            n = krs::normalize(trunk.normal(p));
            albedo = {0.40f, 0.25f, 0.15f};
        } else if (h.nearest == 3) {
            n = crown.normal(p);
            albedo = {0.55f, 0.45f, 0.10f};
        } else {
            const krs::location<float> where = forest.sequence.locate(p);
            n = forest.sequence.normal(where);
            if (krs::dot(n, r.direction) > 0) n = -n;
            const auto& kernel = forest.sequence.kernels()[where.kernel];
            if (const auto* branch = std::get_if<krs::torus_capsule>(&kernel)) {
                // Bark: grooves along the branch from the kernel's own (u, v) (section 6.2).
                const krs::surface_uv<float> uv = branch->uv(where.kernel_point);
                const float groove = 0.5f + 0.5f * std::sin(uv.v * 6.2831853f * 7.0f + 9.0f * uv.u);
                albedo = vec3f{0.30f, 0.21f, 0.14f} * (0.7f + 0.3f * groove);
            } else {
                const float tint = float((where.reflections * 0x9E3779B97F4A7C15ull) >> 40 & 0xff) / 255.0f;
                albedo = vec3f{0.16f + 0.12f * tint, 0.38f + 0.1f * tint, 0.08f};
            }
        }
        if (h.nearest != 1) diffuse = std::max(krs::dot(n, v.sun), 0.0f);
        return mul(albedo, light_surface(0, p, n, diffuse, threshold, counts));
    }, [&](int, const krs::vec3<P>& p, const krs::vec3<P>& n, const P& th, const krs::mask_t<P>& facing, P& s, P& a) {
        light_packet(exact, v.sun, span, 0.3f, p, n, th, facing, s, a);
    });
}

double terrain_scene(const options& opt)
{
    using entry = ex::terrain_scene;
    const auto registered = entry::build(opt.seed.value_or(entry::default_seed));
    const krs::model::plane_sequence& terrain = registered.field;
    const view v = view_of(registered, opt.width, opt.height);
    const krs::fractal_noise detail(5, 0.5f);

    return render(opt, "terrain", complexity_of(terrain), [&](float x, float y, ray_counts& counts) -> lit {
        const krs::ray<float> r = v.camera.primary_ray(x + 0.5f, y + 0.5f);
        const krs::hit<float> h = krs::sphere_trace(terrain, r, v.trace);
        ++counts.primary, counts.primary_steps += h.steps;
        if (!h.found) return sky(r.direction);
        const vec3f p = krs::point_at(r, h.t);
        // Algorithm 2: light and view carried into the plane kernel's space, blended over a band
        // a few pixels wide at this depth, so creases shade smoothly at every distance.
        const float band = krs::smoothing_threshold(h.t, v.camera.pixel_footprint(), 6.0f) + 0.03f;
        const auto k = krs::shade_in_kernel_space(terrain, p, v.sun, -r.direction, band);
        const float diffuse = std::max(krs::dot(k.normal, k.light), 0.0f);
        const vec3f n = terrain.normal(p);
        // World-space texture (triplanar noise): steep faces are rock, flat ones grass.
        auto pattern = [&](float u, float w) { return detail(vec3f{u, w, 0.37f * (u - w)}); };
        const float rock = krs::triplanar(pattern, p * 0.8f, n);
        const vec3f grass{0.22f, 0.34f, 0.10f}, stone{0.45f, 0.41f, 0.36f};
        const vec3f albedo = mix_clamped(grass, stone, (0.955f - n.y) * 10.0f + 1.2f * rock) * (0.75f + 0.25f * rock);
        const lit c = mul(albedo, light_surface(0, p, n, diffuse, v.trace.threshold(h.t), counts));
        const float fog = 1.0f - std::exp(-h.t / 400.0f);
        return fade_to(c, sky(r.direction), fog);
    }, [&](int, const krs::vec3<P>& p, const krs::vec3<P>& n, const P& th, const krs::mask_t<P>& facing, P& s, P& a) {
        light_packet(terrain, v.sun, 60.0f, 0.6f, p, n, th, facing, s, a);
    });
}

// Figure 7: the same rock, flat shaded (left: the kernel normal carried back by the recorded
// reflections, no interpolation) and smooth shaded (right: Algorithm 2, the light interpolated
// across each mirror over a band proportional to the hit's depth, i.e. to the pixel footprint).
double rock_scene(const options& opt)
{
    using entry = ex::rock_scene;
    const std::uint32_t seed = opt.seed.value_or(entry::default_seed);
    const krs::model::rock rock = krs::model::build_rock(entry::parameters(seed));
    using rock_field = krs::bounded<krs::model::plane_sequence>;
    const krs::union_of<rock_field, krs::plane> scene(rock_field(rock.sequence, rock.bound, 0.2f),
                                                      krs::plane({0, 1, 0}, 0.0f));
    const krs::union_of<krs::model::plane_sequence, krs::plane> exact(rock.sequence, krs::plane({0, 1, 0}, 0.0f));
    const int half = std::max(1, opt.width / 2);
    const view v = view_of(entry::build(seed), half, opt.height);
    const krs::fractal_noise grain(4, 3.0f);
    // The smoothing band: this many pixel footprints wide at the hit's depth (paper: e_threshold
    // inversely proportional to depth resolution), so the look does not change with distance.
    const float band_pixels = 0.1f * float(opt.height);
    complexity c = complexity_of(rock.sequence);
    c.instances += 1, c.triangles += 2;

    return render(opt, "rock", c, [&](float x, float y, ray_counts& counts) -> lit {
        const bool smooth = x >= float(half);
        const krs::ray<float> r = v.camera.primary_ray((smooth ? x - float(half) : x) + 0.5f, y + 0.5f);
        if (int(x) == half) return vec3f{1, 1, 1}; // the divider
        const auto h = krs::union_trace(scene, r, v.trace);
        ++counts.primary, counts.primary_steps += h.steps;
        if (!h.found) return sky(r.direction);
        const vec3f p = krs::point_at(r, h.t);
        if (h.nearest == 1) {
            const vec3f sand = vec3f{0.55f, 0.50f, 0.40f} * (0.9f + 0.1f * grain(p));
            return mul(sand, light_surface(0, p, {0, 1, 0}, std::max(v.sun.y, 0.0f), v.trace.threshold(h.t), counts));
        }
        const float band = smooth ? krs::smoothing_threshold(h.t, v.camera.pixel_footprint(), band_pixels) : 0.0f;
        const auto k = krs::shade_in_kernel_space(rock.sequence, p, v.sun, -r.direction, band);
        const krs::phong_terms ph = krs::phong(k, 24.0f);
        const vec3f n = rock.sequence.normal(p);
        const vec3f albedo = vec3f{0.45f, 0.42f, 0.40f} * (0.75f + 0.25f * grain(p));
        const lit light = light_surface(1, p, n, ph.diffuse, v.trace.threshold(h.t), counts);
        return mul(albedo, light) + sun_color * (0.15f * ph.specular);
    }, [&](int kind, const krs::vec3<P>& p, const krs::vec3<P>& n, const P& th, const krs::mask_t<P>& facing, P& s, P& a) {
        light_packet(exact, v.sun, 10.0f, kind == 0 ? 0.15f : 0.1f, p, n, th, facing, s, a); // 0: the ground, 1: the rock
    });
}

// Figure 5 (ex::mirrors_scene): 512 spheres from one sphere and 9 mirrors, twice. Left: the
// mirrors alternate between the x, y and z axes, and the copies form a lattice whose symmetry the
// eye sees at once. Right: each mirror's normal is random, and the same 512 spheres read as a
// natural cluster.
double mirrors_scene(const options& opt)
{
    using entry = ex::mirrors_scene;
    const auto registered = entry::build(opt.seed.value_or(entry::default_seed));
    const ex::mirrors_field& clouds = registered.field;
    const auto& aligned = clouds.component<0>();
    const auto& unaligned = clouds.component<1>();
    const view v = view_of(registered, opt.width, opt.height);
    complexity c = complexity_of(aligned);
    c += complexity_of(unaligned);

    auto albedo_of = [](const krs::location<float>& where) {
        const float tint = float((where.reflections * 0x9E3779B97F4A7C15ull) >> 40 & 0xff) / 255.0f;
        return mix_clamped(vec3f{0.75f, 0.35f, 0.25f}, vec3f{0.85f, 0.75f, 0.35f}, tint);
    };
    // A hit's location and normal in the cloud union_trace found nearest (0: aligned, 1: not).
    auto locate = [&](const vec3f& p, std::size_t cloud) {
        const auto in = [&](const auto& c) {
            const krs::location<float> where = c.locate(p);
            return std::pair{where, c.normal(where)};
        };
        return cloud == 0 ? in(aligned) : in(unaligned);
    };
    return render(opt, "mirrors", c, [&](float x, float y, ray_counts& counts) -> lit {
        const krs::ray<float> r = v.camera.primary_ray(x + 0.5f, y + 0.5f);
        const auto h = krs::union_trace(clouds, r, v.trace);
        ++counts.primary, counts.primary_steps += h.steps;
        if (!h.found) return sky(r.direction);
        const vec3f p = krs::point_at(r, h.t);
        const auto [where, n] = locate(p, h.nearest);
        const vec3f albedo = albedo_of(where);
        const float diffuse = std::max(krs::dot(n, v.sun), 0.0f);
        const float threshold = v.trace.threshold(h.t);
        lit here = mul(albedo, light_surface(0, p, n, diffuse, threshold, counts));
        if (!(opt.reflectivity > 0.0f)) return here; // no reflected ray: the image without reflections
        // Section 6.5: one reflected ray, traced by the same sphere tracer from the hit lifted two
        // thresholds off the sphere; its hit threshold starts at the primary's (the footprint
        // cone goes on). What it sees is lit by the sun and the sky without shadows (one bounce).
        const krs::ray<float> bounce = krs::reflection_ray(p, n, r.direction, 2.0f * threshold);
        krs::trace_options o = v.trace;
        o.threshold_floor = threshold;
        const auto hb = krs::union_trace(clouds, bounce, o);
        ++counts.secondary;
        vec3f seen = sky(bounce.direction);
        if (hb.found) {
            const auto [there, m] = locate(krs::point_at(bounce, hb.t), hb.nearest);
            seen = mul(albedo_of(there), sun_color * std::max(krs::dot(m, v.sun), 0.0f) + sky_light);
        }
        // mix(lit, seen, w) = lit (1 - w) + seen w, and lit's shadow and occlusion terms
        // are still to come (packets, after the tile): scale them by 1 - w now, fold seen into the base.
        const float weight = krs::fresnel_schlick(std::abs(krs::dot(n, r.direction)), opt.reflectivity);
        here.base = krs::mix(here.base, seen, weight);
        here.sun = here.sun * (1.0f - weight);
        here.sky = here.sky * (1.0f - weight);
        return here;
    }, [&](int, const krs::vec3<P>& p, const krs::vec3<P>& n, const P& th, const krs::mask_t<P>& facing, P& s, P& a) {
        light_packet(clouds, v.sun, 4.0f * aligned.bound().radius, 0.1f, p, n, th, facing, s, a);
    });
}

double coral_scene(const options& opt)
{
    using entry = ex::coral_scene;
    const std::uint32_t seed = opt.seed.value_or(entry::default_seed);
    const auto registered = entry::build(seed);
    // Symmetry broken by a noise warp (section 5.2); the distance is divided by its bound.
    const ex::coral_field& bent = registered.field;
    const krs::union_of<ex::coral_field, krs::plane> scene(bent, krs::plane({0, 1, 0}, 0.0f));
    const krs::model::coral_sequence coral = krs::model::build_coral(entry::parameters(seed));
    const krs::bounding_sphere b = coral.bound();
    const view v = view_of(registered, opt.width, opt.height);
    const krs::fractal_noise spots(3, 6.0f);

    complexity c = complexity_of(coral);
    c.instances += 1, c.triangles += 2;

    return render(opt, "coral", c, [&](float x, float y, ray_counts& counts) -> lit {
        const krs::ray<float> r = v.camera.primary_ray(x + 0.5f, y + 0.5f);
        const auto h = krs::union_trace(scene, r, v.trace);
        ++counts.primary, counts.primary_steps += h.steps;
        if (!h.found) return vec3f{0.05f, 0.22f, 0.35f} * (0.6f + 0.4f * r.direction.y);
        const vec3f p = krs::point_at(r, h.t);
        const float threshold = v.trace.threshold(h.t);
        vec3f n{0, 1, 0}, albedo{0.60f, 0.55f, 0.42f};
        if (h.nearest == 0) {
            n = krs::gradient_normal(bent, p, 2.0f * threshold);
            albedo = mix_clamped(vec3f{0.85f, 0.35f, 0.30f}, vec3f{0.95f, 0.65f, 0.45f}, 0.5f + 0.7f * spots(p));
        }
        const float diffuse = std::max(krs::dot(n, v.sun), 0.0f);
        return mul(albedo, light_surface(0, p, n, diffuse, threshold, counts));
    }, [&](int, const krs::vec3<P>& p, const krs::vec3<P>& n, const P& th, const krs::mask_t<P>& facing, P& s, P& a) {
        light_packet(scene, v.sun, 2 * b.radius, 0.04f * b.radius, p, n, th, facing, s, a);
    });
}

double sponge_scene(const options& opt)
{
    using entry = ex::sponge_scene;
    const krs::model::sponge_parameters sp = entry::parameters();
    const krs::model::sponge sponge = krs::model::build_sponge(sp);
    using sponge_field = krs::bounded<krs::model::sponge_sequence>;
    const krs::union_of<sponge_field, krs::plane> scene(
        sponge_field(sponge.sequence, {sp.center, 0.5f * sp.size * 1.7321f}, 0.1f), krs::plane({0, 1, 0}, 0.0f));
    const krs::union_of<krs::model::sponge_sequence, krs::plane> exact(sponge.sequence, krs::plane({0, 1, 0}, 0.0f));
    const view v = view_of(entry::build(), opt.width, opt.height);

    // The KRS has 2^21 box instances, but the sign and sorting folds make them coincide in groups:
    // the sponge shows 20^levels distinct cubes, which is what a mesh would need.
    const complexity c{sponge.cube_count + 1, sponge.cube_count * triangles_of(krs::box{}) + 2};
    std::printf("sponge: %.0f KRS box instances, %.0f distinct cubes\n", complexity_of(sponge.sequence).instances,
                sponge.cube_count);

    return render(opt, "sponge", c, [&](float x, float y, ray_counts& counts) -> lit {
        const krs::ray<float> r = v.camera.primary_ray(x + 0.5f, y + 0.5f);
        const auto h = krs::union_trace(scene, r, v.trace);
        ++counts.primary, counts.primary_steps += h.steps;
        if (!h.found) return sky(r.direction);
        const vec3f p = krs::point_at(r, h.t);
        const float threshold = v.trace.threshold(h.t);
        vec3f n{0, 1, 0}, albedo{0.55f, 0.55f, 0.52f};
        if (h.nearest == 0) {
            n = sponge.sequence.normal(p);
            albedo = {0.75f, 0.62f, 0.45f};
        }
        const float diffuse = std::max(krs::dot(n, v.sun), 0.0f);
        return mul(albedo, light_surface(0, p, n, diffuse, threshold, counts, vec3f{0.45f, 0.5f, 0.6f}));
    }, [&](int, const krs::vec3<P>& p, const krs::vec3<P>& n, const P& th, const krs::mask_t<P>& facing, P& s, P& a) {
        // Deeper occlusion than the other scenes: the sponge's cavities are the subject.
        krs::ambient_occlusion_options ao;
        ao.step = 0.03f;
        ao.samples = 6;
        ao.strength = 1.4f;
        a = krs::ambient_occlusion(exact, p, n, ao);
        krs::soft_shadow_options so;
        so.max_distance = 6.0f;
        so.hardness = 16.0f;
        s = krs::soft_shadow(exact, p, n, krs::vec3<P>(v.sun), so, facing, th);
    });
}

double grass_scene(const options& opt)
{
    using entry = ex::grass_scene;
    const std::uint32_t seed = opt.seed.value_or(entry::default_seed);
    const krs::model::grass_parameters gp = entry::parameters(seed);
    const krs::model::grass_field grass = krs::model::build_grass(gp);
    std::printf("grass: %zu clumps, %zu blades\n", grass.clump_count, grass.blade_count);
    const view v = view_of(entry::build(seed), opt.width, opt.height);
    const krs::fractal_noise tint(3, 0.8f);

    return render(opt, "grass", complexity_of(grass.sequence), [&](float x, float y, ray_counts& counts) -> lit {
        const krs::ray<float> r = v.camera.primary_ray(x + 0.5f, y + 0.5f);
        const krs::hit<float> h = krs::sphere_trace(grass.sequence, r, v.trace);
        ++counts.primary, counts.primary_steps += h.steps;
        if (!h.found) return sky(r.direction);
        const vec3f p = krs::point_at(r, h.t);
        const krs::location<float> where = grass.sequence.locate(p);
        vec3f n = grass.sequence.normal(where);
        if (krs::dot(n, r.direction) > 0) n = -n;
        vec3f albedo{0.30f, 0.26f, 0.16f};
        if (std::holds_alternative<krs::torus_capsule>(grass.sequence.kernels()[where.kernel])) {
            const float height = std::clamp((p.y - gp.ground_height) / gp.blade_height, 0.0f, 1.0f);
            albedo = mix_clamped(vec3f{0.10f, 0.22f, 0.05f}, vec3f{0.42f, 0.55f, 0.18f}, height + 0.3f * tint(p));
        }
        const float diffuse = std::abs(krs::dot(n, v.sun)); // thin blades pass light through
        return mul(albedo, light_surface(0, p, n, diffuse, v.trace.threshold(h.t), counts));
    }, [&](int, const krs::vec3<P>& p, const krs::vec3<P>& n, const P& th, const krs::mask_t<P>& facing, P& s, P& a) {
        light_packet(grass.sequence, v.sun, 3.0f, 0.03f, p, n, th, facing, s, a);
    });
}

// The scenes this program renders, by their entries in the list, in the list's order: --scene
// takes its names from here.
struct scene_entry {
    std::string_view name;
    double (*run)(const options&);
};
const scene_entry scenes[] = {{ex::forest_scene::name, forest_scene}, {ex::terrain_scene::name, terrain_scene},
                              {ex::rock_scene::name, rock_scene},     {ex::mirrors_scene::name, mirrors_scene},
                              {ex::coral_scene::name, coral_scene},   {ex::grass_scene::name, grass_scene},
                              {ex::sponge_scene::name, sponge_scene}};

options parse(int argc, char** argv)
{
    options o;
    example::command_line args("krs_scenes", "Renders the paper's section 7 scenes to PNG files.");
    example::add_image_size(args, o.width, o.height);
    example::add_threads(args, o.threads);
    std::vector<std::string> names;
    for (const scene_entry& e : scenes) names.emplace_back(e.name);
    const example::scene_choice choice(args, o.only, names, "render this scene only (default: all)", "--only");
    example::add_output_folder(args, o.output_dir, "the PNG files");
    args.number("--reflectivity", o.reflectivity, 0.0, 1.0, false, "mirrors scene: reflectivity of the spheres at normal incidence "
                 "(Schlick), each hit tracing one reflected ray; 0: no reflections");
    args.parse(argc, argv);
    o.seed = choice.seed();
    example::require_output_folder(args, "--output-dir", o.output_dir);
    o.threads = example::thread_count(o.threads);
    return o;
}

} // namespace

int main(int argc, char** argv)
{
    const options opt = parse(argc, argv);
    double total = 0;
    int rendered = 0;
    for (const scene_entry& e : scenes) {
        if (!opt.only.empty() && opt.only != e.name) continue;
        total += e.run(opt);
        ++rendered;
    }
    std::printf("total: %.2f s for %d scene(s)\n", total, rendered);
    return 0;
}

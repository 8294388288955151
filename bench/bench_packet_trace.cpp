// bench_packet_trace: scalar against packet tracing, the paper's section 8 table (time per ray
// against expansion level), and speed against error for the tracer's settings.
//
//     bench_packet_trace [--size N] [--csv FILE] [--repeat R] [--only throughput|levels|error|boxes|shadows|stream]
//
// `stream` (issue 23, items 1 and 4; not run by default) times the packet stream before issue 23
// against today's on the tree, the forest and the terrain with both mirror kinds at n = 16 and
// 32, in alternating rounds, and prints where the new stream's time goes (support/stream_compare.hpp).
//
// Prints five tables (the fifth: soft shadows and ambient occlusion, scalar against packet, see
// shadows_table) and writes them to one CSV (default: <executable>.csv next to the
// binary), with a `table` column. Rays are camera rays over N x N pixels (default 256), rendered
// in 8 x 8 tiles taken from a shared counter by 1 or 2 threads. The scalar path traces each pixel
// with sphere_trace<float>; the packet path streams every ray of a thread's tiles through
// trace_queue<packet_f, 4> (lane refill, four interleaved packets) fed by queue_tile_rays. Each timing is the best of R
// runs (default 3). Targets of issue 4 are checked at the end of each table.

#include "support/stream_compare.hpp"
#include "support/text.hpp"
#include "support/timing.hpp"
#include "krs/kernels/plane.hpp"
#include "krs/kernels/sphere.hpp"
#include "krs/kernels/torus_capsule.hpp"
#include "krs/model/tree.hpp"
#include "krs/shade/global.hpp"
#include "krs/trace/camera.hpp"
#include "krs/trace/packet_trace.hpp"
#include "krs/trace/tile_rays.hpp"

#include <benchmark/benchmark.h>

#include <algorithm>
#include <atomic>
#include <chrono>
#include <cmath>
#include <cstdarg>
#include <cstdio>
#include <cstdlib>
#include <fstream>
#include <functional>
#include <optional>
#include <random>
#include <string>
#include <thread>
#include <vector>

namespace {

using krs::vec3f;
constexpr std::size_t packet_width = krs::lane_count<krs::packet_f>;
// Packets a stream steps together (trace_stream's Interleave). Measured here, 4 against 2, with
// trees' packets refilled whole (trace_stream's default for fields of varying cost): 16 lanes,
// tree +9%, forest +16%, terrain +50%; 8 lanes, tree +16%, forest +15%, terrain +33%. (Refilling
// a quarter of the lanes at a time, 4 had cost the tree 5% and the forest 10%.)
constexpr int stream_interleave = 4;

// ---- rendering ---------------------------------------------------------------------------------

struct render_settings {
    bool packet = true;
    int threads = 1;
    bool prepass = false;
    bool clip = true; // rays clipped to the field's bounding box (both paths)
    std::optional<krs::bounding_box> clip_box; // the box to clip to instead of the field's
    int tile = 8;
    krs::trace_options options;
};

struct frame {
    std::vector<float> depth; // +inf where the ray missed
    double seconds = 0;
    long long evaluations = 0;         // field evaluations of the rays
    long long prepass_evaluations = 0; // and of the tile prepasses
    long long steps = 0;
    double utilization = 1.0; // share of packet lanes doing useful work
    std::size_t rays() const { return depth.size(); }
};

// The two paths, each out of line, so that neither one's code shapes the other's compilation
// (inlined into one function, the packet path's size changed the scalar path's speed by up to
// 1.5x between builds, and with it every ratio).
template <class F>
[[gnu::noinline]] long long trace_tile_scalar(const F& f, const krs::pinhole_camera& camera, const krs::tile_prepass& pre,
                                              const krs::box_clip& clip, int x0, int y0, int x1, int y1,
                                              const krs::trace_options& o, float* depth)
{
    long long evaluations = 0;
    for (int py = y0; py < y1; ++py)
        for (int px = x0; px < x1; ++px) {
            const krs::ray<float> r = camera.primary_ray(float(px) + 0.5f, float(py) + 0.5f);
            float t0 = pre.start_for(r), t1 = o.max_distance;
            clip.apply(r, t0, t1);
            const krs::hit<float> h = krs::sphere_trace(f, r, t0, t1, o);
            evaluations += h.evaluations;
            depth[std::size_t(py) * std::size_t(camera.width()) + std::size_t(px)] = h.found ? h.t : INFINITY;
        }
    return evaluations;
}

// The packet path: one stream over every tile take_tile(x0, y0, x1, y1, pre) hands out.
template <class F, class TakeTile>
[[gnu::noinline]] krs::stream_stats trace_stream_packets(const F& f, const krs::pinhole_camera& camera, TakeTile& take_tile,
                                                         const krs::box_clip& clip, const krs::trace_options& o, float* depth)
{
    krs::ray_queue<> queue;
    auto more = [&](krs::ray_queue<>& q) {
        int x0, y0, x1, y1;
        const krs::tile_prepass* pre = take_tile(x0, y0, x1, y1);
        if (!pre) return false;
        krs::queue_tile_rays(q, camera, x0, y0, x1, y1, *pre, o.max_distance, clip);
        return true;
    };
    auto done = [&](std::uint32_t id, const krs::hit<float>& h) { depth[id] = h.found ? h.t : INFINITY; };
    return krs::trace_queue<krs::packet_f, stream_interleave>(f, queue, more, done, o);
}

template <class F>
frame render_once(const F& f, const krs::pinhole_camera& camera, const render_settings& s)
{
    const int width = camera.width(), height = camera.height(), tile = s.tile;
    const int tiles_x = (width + tile - 1) / tile, tiles = tiles_x * ((height + tile - 1) / tile);
    frame out;
    out.depth.assign(std::size_t(width) * std::size_t(height), INFINITY);
    std::atomic<int> next_tile{0};
    std::atomic<long long> evaluations{0}, prepass_evaluations{0}, packet_steps{0}, busy{0};
    const krs::trace_options& o = s.options;
    const krs::box_clip clip =
        s.clip ? krs::box_clip(s.clip_box ? *s.clip_box : krs::field_box(f), camera.eye(), o) : krs::box_clip();

    auto worker = [&] {
        long long my_evaluations = 0, my_prepass = 0;
        // The tile a thread works on and its prepass.
        int x0 = 0, y0 = 0, x1 = 0, y1 = 0;
        krs::tile_prepass pre;
        auto take_tile = [&](int& tx0, int& ty0, int& tx1, int& ty1) -> const krs::tile_prepass* {
            const int k = next_tile.fetch_add(1);
            if (k >= tiles) return nullptr;
            x0 = (k % tiles_x) * tile, y0 = (k / tiles_x) * tile;
            x1 = std::min(x0 + tile, width), y1 = std::min(y0 + tile, height);
            tx0 = x0, ty0 = y0, tx1 = x1, ty1 = y1;
            pre = krs::tile_prepass{};
            pre.start = o.min_distance;
            if (s.prepass) {
                pre = krs::prepass_tile(f, camera, x0, y0, x1, y1, o);
                my_prepass += pre.evaluations;
            }
            return &pre;
        };
        if (!s.packet) {
            int tx0, ty0, tx1, ty1;
            while (take_tile(tx0, ty0, tx1, ty1))
                my_evaluations += trace_tile_scalar(f, camera, pre, clip, tx0, ty0, tx1, ty1, o, out.depth.data());
        } else {
            const krs::stream_stats st = trace_stream_packets(f, camera, take_tile, clip, o, out.depth.data());
            my_evaluations += st.evaluations;
            packet_steps += st.packet_steps;
            busy += st.busy_lanes;
        }
        evaluations += my_evaluations;
        prepass_evaluations += my_prepass;
    };
    const auto start = std::chrono::steady_clock::now();
    std::vector<std::thread> pool;
    for (int i = 1; i < s.threads; ++i) pool.emplace_back(worker);
    worker();
    for (std::thread& t : pool) t.join();
    out.seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
    out.evaluations = evaluations.load();
    out.prepass_evaluations = prepass_evaluations.load();
    out.steps = out.evaluations;
    if (s.packet && packet_steps.load() > 0)
        out.utilization = double(busy.load()) / (double(packet_steps.load()) * double(packet_width));
    benchmark::DoNotOptimize(out.depth.data());
    return out;
}

int repeats = 3;
template <class F>
frame render(const F& f, const krs::pinhole_camera& camera, const render_settings& s)
{
    frame best = render_once(f, camera, s);
    for (int i = 1; i < repeats; ++i) {
        frame again = render_once(f, camera, s);
        if (again.seconds < best.seconds) best = std::move(again);
    }
    return best;
}

// ---- scenes ------------------------------------------------------------------------------------

struct framing {
    vec3f eye, target;
    float far;
};

// A tree of `levels` branches on its route (levels - 1 mirrors), framed from the side; on a
// ground plane unless `ground` is false (a plane makes the box unbounded: nothing is clipped).
krs::model::tree_sequence tree_scene(int levels, framing& view, bool ground = true)
{
    krs::model::tree_style style;
    style.levels = levels;
    style.seed = 7;
    krs::model::tree_parameters p = krs::model::grow_tree(style);
    p.ground_height.reset();
    const krs::bounding_sphere crown = krs::model::build_tree(p).bound();
    if (ground) p.ground_height = 0.0f;
    const float away = 1.1f * crown.radius / std::sin(0.5f * 40.0f * 3.14159265f / 180.0f);
    view = {crown.center + krs::normalize(vec3f{0.8f, 0.25f, -0.6f}) * away, crown.center, 4 * away};
    return krs::model::build_tree(p);
}

// The tree (`levels` branches) replicated on a 2^g x 2^g grid by 2g more mirrors with empty kernel
// sets (paper section 7.3), then the ground as the top level's kernel.
krs::model::tree_sequence forest_scene(int levels, int g, framing& view, bool ground = true)
{
    krs::model::tree_style style;
    style.levels = levels;
    style.seed = 7;
    krs::model::tree_parameters p = krs::model::grow_tree(style);
    p.ground_height.reset();
    const krs::model::tree_sequence tree = krs::model::build_tree(p);
    krs::model::tree_sequence::builder b;
    for (std::size_t level = 0; level <= tree.mirror_count(); ++level) {
        if (level > 0) b.mirror(tree.mirrors()[level - 1]);
        for (std::uint32_t k = tree.level_begin(level); k < tree.level_begin(level + 1); ++k)
            std::visit([&](const auto& kernel) { b.kernel(kernel); }, tree.kernels()[k]);
    }
    const float spacing = 1.6f * tree.bound().radius;
    const vec3f c = tree.bound().center;
    // Copies at c + spacing * {0 ... 2^g - 1}: the mirror at (2^k - 1/2) spacing doubles them.
    for (int k = 0; k < g; ++k) {
        const float at = (float(1 << k) - 0.5f) * spacing;
        b.mirror(krs::mirror({1, 0, 0}, c.x + at));
        b.mirror(krs::mirror({0, 0, 1}, c.z + at));
    }
    if (ground) b.kernel(krs::plane({0, 1, 0}, 0.0f));
    const float extent = float(1 << g) * spacing;
    const vec3f middle{c.x + 0.5f * (extent - spacing), c.y * 0.5f, c.z + 0.5f * (extent - spacing)};
    view = {middle + vec3f{-0.55f * extent, 0.45f * extent, -0.85f * extent}, middle, 4 * extent};
    return b.build();
}

// Terrain (paper section 7.1): tilted half-spaces as kernels, one per level, folded by n mirrors
// whose scale shrinks level by level (the top mirror is the coarsest). Mirror is krs::mirror
// (random near-vertical planes) or krs::axis_mirror (x and z alternately).
template <class Mirror>
krs::basic_sequence<Mirror, krs::plane> terrain_scene(int n, framing& view)
{
    std::mt19937 g(3);
    auto u = [&](float lo, float hi) { return lo + (hi - lo) * float(g() >> 8) * (1.0f / 16777216.0f); };
    typename krs::basic_sequence<Mirror, krs::plane>::builder b;
    b.kernel(krs::plane({u(-0.1f, 0.1f), 1, u(-0.1f, 0.1f)}, 0.0f));
    for (int i = 0; i < n; ++i) {
        const float scale = 30.0f * std::pow(0.8f, float(n - 1 - i));
        if constexpr (std::is_same_v<Mirror, krs::axis_mirror>) {
            b.mirror(krs::axis_mirror(i % 2 == 0 ? 0 : 2, u(-0.5f, 0.5f) * scale, (g() & 1) != 0));
        } else {
            const float a = u(0, 6.2831853f);
            b.mirror(krs::mirror({std::cos(a), u(-0.03f, 0.03f), std::sin(a)}, u(-0.5f, 0.5f) * scale));
        }
        b.kernel(krs::plane({u(-0.12f, 0.12f), 1, u(-0.12f, 0.12f)}, u(-0.1f, 0.0f) * scale));
    }
    view = {{0, 16, -45}, {0, -3, 0}, 300};
    return b.build();
}

krs::pinhole_camera camera_for(const framing& v, int size)
{
    return krs::pinhole_camera(v.eye, v.target, {0, 1, 0}, 40.0f, size, size);
}
krs::trace_options options_for(const krs::pinhole_camera& camera, const framing& v, float pixels = 0.5f)
{
    krs::trace_options o;
    o.pixel_footprint = camera.pixel_footprint() * pixels;
    o.max_distance = v.far;
    o.threshold_floor = 1e-5f;
    o.max_steps = 512;
    return o.validate();
}

// ---- output ------------------------------------------------------------------------------------

struct csv_writer {
    std::ofstream file;
    void row(const std::string& line) { file << line << '\n'; }
};

using bench::format;

const char* verdict(bool met) { return met ? "MET" : "NOT MET"; }

// ---- table 1: scalar against packet ------------------------------------------------------------

template <class F>
void throughput_row(const char* name, const F& f, const framing& v, int size, csv_writer& csv, double& worst_ratio)
{
    const krs::pinhole_camera camera = camera_for(v, size);
    for (int threads : {1, 2}) {
        render_settings s;
        s.options = options_for(camera, v);
        s.threads = threads;
        s.packet = false;
        const frame scalar = render(f, camera, s);
        s.packet = true;
        const frame packet = render(f, camera, s);
        int differ = 0;
        for (std::size_t i = 0; i < scalar.rays(); ++i) differ += std::isinf(scalar.depth[i]) != std::isinf(packet.depth[i]);
        const double ms = double(scalar.rays()) / scalar.seconds * 1e-6, mp = double(packet.rays()) / packet.seconds * 1e-6;
        const double ratio = mp / ms;
        if (threads == 1) worst_ratio = std::min(worst_ratio, ratio);
        std::printf("%-22s %7d %12.2f %12.2f %8.2fx %10.1f%% %11.1f %8d\n", name, threads, ms, mp, ratio,
                    100.0 * packet.utilization, double(packet.evaluations) / double(packet.rays()), differ);
        csv.row(format("throughput,%s,%d,%.4f,%.4f,%.4f,%.4f,%.3f,%d", name, threads, ms, mp, ratio, packet.utilization,
                       double(packet.evaluations) / double(packet.rays()), differ));
    }
}

void throughput_table(int size, csv_writer& csv)
{
    std::printf("\n== scalar vs packet (%zu lanes, lane refill, %d interleaved packets), %dx%d, 8x8 tiles ==\n",
                packet_width, stream_interleave, size, size);
    std::printf("%-22s %7s %12s %12s %9s %11s %11s %8s\n", "scene", "threads", "scalar Mr/s", "packet Mr/s", "ratio",
                "lanes busy", "evals/ray", "hit diff");
    csv.row("table,scene,threads,scalar_mrays_s,packet_mrays_s,ratio,lane_utilization,evals_per_ray,hit_miss_differ");
    double worst = 1e30;
    framing v;
    const auto tree = tree_scene(15, v);
    throughput_row("tree (15 levels)", tree, v, size, csv, worst);
    framing fv;
    const auto forest = forest_scene(12, 3, fv);
    throughput_row("forest (64 trees)", forest, fv, size, csv, worst);
    framing tv;
    const auto terrain = terrain_scene<krs::mirror>(20, tv);
    throughput_row("terrain (general)", terrain, tv, size, csv, worst);
    const auto terrain_axis = terrain_scene<krs::axis_mirror>(20, tv);
    throughput_row("terrain (axis mirrors)", terrain_axis, tv, size, csv, worst);
    // Issue 4: >= 8x with 16 lanes, >= 5x with 8 lanes.
    const double target = packet_width >= 16 ? 8.0 : packet_width >= 8 ? 5.0 : 0.0;
    if (target > 0)
        std::printf("target packet/scalar >= %.0fx on 1 thread with %zu lanes: worst %.2fx -> %s\n", target,
                    packet_width, worst, verdict(worst >= target));
    else
        std::printf("packet/scalar worst %.2fx (no target for %zu lanes)\n", worst, packet_width);
}

// ---- table 4: clip boxes -----------------------------------------------------------------------

// Issue 23, item 2: rays clipped to the sequence's box (its kernels' exact boxes through the
// mirrors) and to the box its kernels' bounding spheres give through the same mirrors (the box
// before issue 23): the share of rays entering each and the packet path's speed, the two boxes
// alternating within each repeat, best of R.
template <class F>
void boxes_row(const char* name, const F& f, const framing& v, int size, csv_writer& csv)
{
    const krs::pinhole_camera camera = camera_for(v, size);
    const krs::bounding_box tight = f.bound_box();
    const krs::bounding_box spheres =
        krs::box_through_mirrors(f, [](const auto& k) { return krs::box_around(k.bound()); });
    render_settings s;
    s.options = options_for(camera, v);
    s.threads = 2;
    const auto in_box = [&](const krs::bounding_box& box) {
        const krs::box_clip clip(box, camera.eye(), s.options);
        std::size_t entering = 0;
        for (int py = 0; py < camera.height(); ++py)
            for (int px = 0; px < camera.width(); ++px) {
                const krs::ray<float> r = camera.primary_ray(float(px) + 0.5f, float(py) + 0.5f);
                float t0 = s.options.min_distance, t1 = s.options.max_distance;
                clip.apply(r, t0, t1);
                entering += t0 <= t1;
            }
        return double(entering) / (double(camera.width()) * double(camera.height()));
    };
    frame best[2];
    for (int r = 0; r < repeats; ++r)
        for (int k = 0; k < 2; ++k) {
            const int which = (k + r) % 2; // the first of the two swaps every repeat
            s.clip_box = which == 0 ? spheres : tight;
            frame fr = render_once(f, camera, s);
            if (r == 0 || fr.seconds < best[which].seconds) best[which] = std::move(fr);
        }
    const auto mrays = [](const frame& fr) { return double(fr.rays()) / fr.seconds * 1e-6; };
    const auto evals = [](const frame& fr) { return double(fr.evaluations) / double(fr.rays()); };
    int differ = 0;
    for (std::size_t i = 0; i < best[0].rays(); ++i) differ += std::isinf(best[0].depth[i]) != std::isinf(best[1].depth[i]);
    std::printf("%-22s %9.1f%% %9.1f%% %10.2f %10.2f %8.3fx %8.1f %8.1f %8d\n", name, 100 * in_box(spheres),
                100 * in_box(tight), mrays(best[0]), mrays(best[1]), mrays(best[1]) / mrays(best[0]), evals(best[0]),
                evals(best[1]), differ);
    csv.row(format("boxes,%s,%.6f,%.6f,%.4f,%.4f,%.3f,%.3f,%d", name, in_box(spheres), in_box(tight), mrays(best[0]),
                   mrays(best[1]), evals(best[0]), evals(best[1]), differ));
}

void boxes_table(int size, csv_writer& csv)
{
    std::printf("\n== clip boxes: kernels' spheres' box vs the tight box (packet path, 2 threads, %dx%d) ==\n", size,
                size);
    std::printf("%-22s %10s %10s %10s %10s %9s %8s %8s %8s\n", "scene", "in spheres", "in tight", "spheres Mr/s",
                "tight Mr/s", "speedup", "evals s", "evals t", "hit diff");
    csv.row("table,scene,in_spheres_box,in_tight_box,spheres_mrays_s,tight_mrays_s,spheres_evals_per_ray,"
            "tight_evals_per_ray,hit_miss_differ");
    framing v;
    // Without their ground: a plane makes the box unbounded, and nothing would be clipped.
    boxes_row("tree, no ground", tree_scene(15, v, false), v, size, csv);
    framing fv;
    boxes_row("forest, no ground", forest_scene(12, 3, fv, false), fv, size, csv);
}

// ---- table 2: time per ray against expansion level ---------------------------------------------

void levels_table(int size, csv_writer& csv)
{
    // The paper's two scenes, the terrain with general mirrors (the paper's: turned planes hide the
    // symmetry); and the same terrain with axis mirrors, whose fold is one min per level.
    std::printf("\n== paper section 8: time per ray vs expansion level n (1 thread, %dx%d) ==\n", size, size);
    std::printf("%4s %15s %15s %15s %15s %15s %15s %11s %11s\n", "n", "tree scalar us", "tree packet us", "terrain scal. us",
                "terrain pack. us", "axis terr. s us", "axis terr. p us", "tree bytes", "terr. bytes");
    csv.row("table,n,tree_scalar_us,tree_packet_us,terrain_scalar_us,terrain_packet_us,tree_evals_per_ray,terrain_evals_per_ray,"
            "tree_memory_bytes,terrain_memory_bytes,terrain_axis_scalar_us,terrain_axis_packet_us");
    constexpr int paths = 6;
    std::vector<double> ns, cols[paths];
    for (int n = 6; n <= 32; n += 2) {
        double us[paths];
        double evals[3];
        std::size_t bytes[3];
        for (int scene = 0; scene < 3; ++scene) {
            framing v;
            auto run = [&](const auto& f) {
                bytes[scene] = f.memory_bytes();
                const krs::pinhole_camera camera = camera_for(v, size);
                render_settings s;
                s.options = options_for(camera, v);
                for (int packet = 0; packet < 2; ++packet) {
                    s.packet = packet != 0;
                    const frame fr = render(f, camera, s);
                    us[scene * 2 + packet] = 1e6 * fr.seconds / double(fr.rays());
                    evals[scene] = double(fr.evaluations) / double(fr.rays());
                }
            };
            if (scene == 0) run(tree_scene(n + 1, v)); // n mirrors
            else if (scene == 1) run(terrain_scene<krs::mirror>(n, v));
            else run(terrain_scene<krs::axis_mirror>(n, v));
        }
        ns.push_back(n);
        for (int c = 0; c < paths; ++c) cols[c].push_back(us[c]);
        std::printf("%4d %15.3f %15.3f %15.3f %15.3f %15.3f %15.3f %11zu %11zu\n", n, us[0], us[1], us[2], us[3], us[4], us[5],
                    bytes[0], bytes[1]);
        csv.row(format("levels,%d,%.5f,%.5f,%.5f,%.5f,%.2f,%.2f,%zu,%zu,%.5f,%.5f", n, us[0], us[1], us[2], us[3], evals[0],
                       evals[1], bytes[0], bytes[1], us[4], us[5]));
    }
    // Least-squares line time = fixed + slope n, and its R^2. For a line, time(32)/time(16) =
    // (fixed + 32 slope) / (fixed + 16 slope), which is <= 1.5 exactly when fixed / slope >= 16:
    // the target asks the cost that does not grow with n (ray setup, the tracer's step, levels that
    // early outs skip) to outweigh 16 levels' walk. `levels of fixed cost` prints that quotient.
    struct line {
        double fixed, slope, r2;
    };
    auto fit = [&](const std::vector<double>& y) {
        double mx = 0, my = 0;
        for (std::size_t i = 0; i < y.size(); ++i) mx += ns[i], my += y[i];
        mx /= double(y.size()), my /= double(y.size());
        double sxy = 0, sxx = 0, syy = 0;
        for (std::size_t i = 0; i < y.size(); ++i)
            sxy += (ns[i] - mx) * (y[i] - my), sxx += (ns[i] - mx) * (ns[i] - mx), syy += (y[i] - my) * (y[i] - my);
        const double slope = sxy / sxx;
        return line{my - slope * mx, slope, syy > 0 ? sxy * sxy / (sxx * syy) : 1.0};
    };
    auto at = [&](const std::vector<double>& y, double n) -> double {
        for (std::size_t i = 0; i < ns.size(); ++i)
            if (ns[i] == n) return y[i];
        return NAN;
    };
    const char* names[paths] = {"tree scalar", "tree packet", "terrain scalar", "terrain packet", "axis terrain scalar",
                                "axis terrain packet"};
    bool all_met = true; // on the paper's two scenes
    std::printf("%-20s %12s %12s %6s %16s %16s\n", "path", "fixed us", "us per level", "R^2", "levels of fixed", "time(32)/(16)");
    csv.row("table,path,us_per_level,time_32_over_16,fixed_us,r2,fixed_in_levels");
    for (int c = 0; c < paths; ++c) {
        const double r = at(cols[c], 32) / at(cols[c], 16);
        const line l = fit(cols[c]);
        if (c < 4) all_met = all_met && r <= 1.5;
        std::printf("%-20s %12.5f %12.6f %6.3f %16.1f %10.2f (target <= 1.5: %s)\n", names[c], l.fixed, l.slope, l.r2,
                    l.fixed / l.slope, r, verdict(r <= 1.5));
        csv.row(format("levels_slope,%s,%.6f,%.4f,%.6f,%.4f,%.2f", names[c], l.slope, r, l.fixed, l.r2, l.fixed / l.slope));
    }
    std::printf("target time(32)/time(16) <= 1.5 on both scenes (tree, terrain with general mirrors): %s\n", verdict(all_met));
}

// ---- table 3: speed against error --------------------------------------------------------------

void error_table(int size, csv_writer& csv)
{
    framing v;
    const auto forest = forest_scene(12, 3, v);
    const krs::pinhole_camera camera = camera_for(v, size);
    std::printf("\n== speed vs error: forest (64 trees), %dx%d, packet path, 2 threads ==\n", size, size);
    // Converged reference: a twentieth of a pixel, many steps, plain sphere tracing.
    render_settings ref;
    ref.options = options_for(camera, v, 0.05f);
    ref.options.max_steps = 20000;
    ref.threads = 2;
    const frame reference = render_once(forest, camera, ref);
    std::printf("reference: threshold 0.05 px, 20000 steps, %.1f evals/ray\n",
                double(reference.evaluations) / double(reference.rays()));
    std::printf("%9s %6s %8s %9s %10s %9s %11s %13s %12s %12s\n", "threshold", "omega", "prepass", "max steps",
                "ns/ray", "steps/ray", "evals/ray", "depth err", "rel. err", "hit differs");
    csv.row("table,threshold_px,omega,prepass,max_steps,ns_per_ray,steps_per_ray,evals_per_ray,mean_depth_error,"
            "mean_relative_depth_error,hit_miss_differ_share,differ_vs_plain_share");
    struct result {
        double evals;
        std::vector<float> depth;
    };
    bool met = false;
    std::string best;
    for (float px : {0.5f, 1.0f, 2.0f})
        for (int max_steps : {128, 512}) {
            result plain{0, {}};
            for (bool prepass : {false, true})
                for (float omega : {1.0f, 1.3f, 1.6f}) {
                    render_settings s;
                    s.options = options_for(camera, v, px);
                    s.options.max_steps = max_steps;
                    s.options.omega = omega;
                    s.prepass = prepass;
                    s.threads = 2;
                    const frame fr = render(forest, camera, s);
                    const double rays = double(fr.rays());
                    double err = 0, rel = 0;
                    long long both = 0, differ = 0, differ_plain = 0;
                    for (std::size_t i = 0; i < fr.rays(); ++i) {
                        const bool a = std::isfinite(fr.depth[i]), b = std::isfinite(reference.depth[i]);
                        if (a != b) ++differ;
                        if (a && b) {
                            const double e = std::abs(double(fr.depth[i]) - double(reference.depth[i]));
                            err += e, rel += e / double(reference.depth[i]), ++both;
                        }
                    }
                    const double evals = double(fr.evaluations + fr.prepass_evaluations) / rays;
                    if (!prepass && omega == 1.0f) plain = {evals, fr.depth};
                    for (std::size_t i = 0; i < fr.rays(); ++i)
                        differ_plain += std::isfinite(fr.depth[i]) != std::isfinite(plain.depth[i]);
                    const double share_plain = double(differ_plain) / rays;
                    std::printf("%7.1fpx %6.1f %8s %9d %10.1f %9.1f %11.1f %13.5f %12.6f %11.3f%%", px, omega,
                                prepass ? "on" : "off", max_steps, 1e9 * fr.seconds * 2 / rays,
                                double(fr.steps) / rays, evals, both ? err / double(both) : 0.0,
                                both ? rel / double(both) : 0.0, 100.0 * double(differ) / rays);
                    if (prepass || omega > 1.0f) {
                        const double saved = 1.0 - evals / plain.evals;
                        std::printf("  (%+.0f%% evals, %.3f%% px differ vs plain)", -100.0 * saved, 100.0 * share_plain);
                        if (prepass && omega > 1.0f && saved >= 0.25 && share_plain <= 0.001 && !met) {
                            met = true;
                            best = format("%.1f px, omega %.1f, %d steps: %.0f%% fewer evaluations, %.3f%% pixels differ",
                                          px, omega, max_steps, 100.0 * saved, 100.0 * share_plain);
                        }
                    }
                    std::printf("\n");
                    csv.row(format("error,%.2f,%.2f,%d,%d,%.2f,%.3f,%.3f,%.6f,%.7f,%.6f,%.6f", px, omega, prepass ? 1 : 0,
                                   max_steps, 1e9 * fr.seconds * 2 / rays, double(fr.steps) / rays, evals,
                                   both ? err / double(both) : 0.0, both ? rel / double(both) : 0.0,
                                   double(differ) / rays, share_plain));
                }
        }
    std::printf("target prepass + over-relaxation >= 25%% fewer evaluations at <= 0.1%% pixels differing: %s%s%s\n",
                verdict(met), met ? " (" : "", met ? (best + ")").c_str() : "");
}

// ---- table 5: soft shadows and ambient occlusion, scalar against packet ----------------------

// Issue 23, item 3: soft_shadow and ambient_occlusion are one template for a ray and a packet
// (the shadow on the tracers' march step). The shading points are the primary hits of the scene's
// camera, in 8 x 8 tile order (neighbouring pixels share a packet, as an example's shading pass
// has them), each with its kernel's normal; the sun is krs_scenes'. A shadow ray is cast from the
// points facing the sun, an occlusion probe from every point. One thread; scalar and packet rounds
// alternate, best of R each; "prev" is the scalar soft shadow's own loop from before it ran on the
// march step (previous_soft_shadow below), and "vs prev" the rays where the two scalar calls
// differ. Beside each rate: the largest |packet lane - scalar call| and how many
// lanes differ at all (this benchmark compiles with g++'s default -ffp-contract=fast, under which
// the two paths may fuse a * b + c differently; the tests, built with it off, require equality).
struct shading_points {
    std::vector<vec3f> p, n; // scalar inputs
    std::vector<float> px, py, pz, nx, ny, nz; // the same, SoA, padded to whole packets
    std::size_t size() const { return p.size(); }
    void add(const vec3f& a, const vec3f& b) { p.push_back(a), n.push_back(b); }
    void pad()
    {
        const auto put = [&](std::vector<float>& v, auto get) {
            v.clear();
            for (std::size_t i = 0; i < p.size(); ++i) v.push_back(get(i));
            while (v.size() % packet_width) v.push_back(v.empty() ? 0.0f : v.back());
        };
        put(px, [&](std::size_t i) { return p[i].x; }), put(py, [&](std::size_t i) { return p[i].y; });
        put(pz, [&](std::size_t i) { return p[i].z; }), put(nx, [&](std::size_t i) { return n[i].x; });
        put(ny, [&](std::size_t i) { return n[i].y; }), put(nz, [&](std::size_t i) { return n[i].z; });
    }
};

// The scalar soft shadow as it was before it ran on the shared march step (its own loop), kept
// here to show what the march step costs a single ray.
template <class F>
float previous_soft_shadow(const F& f, const vec3f& p, const vec3f& n, const vec3f& to_light,
                           const krs::soft_shadow_options& o)
{
    o.validate();
    const float k = o.hardness, threshold = o.threshold, t_max = o.max_distance;
    const vec3f origin = p + n * (2.0f * threshold);
    float visible = 1.0f, t = 0.0f;
    for (int step = 0; step < o.max_steps; ++step) {
        const float d = f.distance(origin + to_light * t);
        if (!(d >= threshold)) return 0.0f;
        if (t > 0.0f) visible = std::min(visible, k * d / t);
        t += d;
        if (t > t_max) break;
    }
    return std::clamp(visible, 0.0f, 1.0f);
}
template <class F>
[[gnu::noinline]] void shadows_previous(const F& f, const shading_points& s, const vec3f& sun,
                                        const krs::soft_shadow_options& o, float* out)
{
    for (std::size_t i = 0; i < s.size(); ++i) out[i] = previous_soft_shadow(f, s.p[i], s.n[i], sun, o);
}
template <class F>
[[gnu::noinline]] void shadows_scalar(const F& f, const shading_points& s, const vec3f& sun,
                                      const krs::soft_shadow_options& o, float* out)
{
    for (std::size_t i = 0; i < s.size(); ++i) out[i] = krs::soft_shadow(f, s.p[i], s.n[i], sun, o);
}
template <class F>
[[gnu::noinline]] void shadows_packet(const F& f, const shading_points& s, const vec3f& sun,
                                      const krs::soft_shadow_options& o, float* out)
{
    using P = krs::packet_f;
    const krs::vec3<P> l(sun);
    for (std::size_t i = 0; i < s.size(); i += packet_width) {
        const krs::vec3<P> p{P::load_unaligned(&s.px[i]), P::load_unaligned(&s.py[i]), P::load_unaligned(&s.pz[i])};
        const krs::vec3<P> n{P::load_unaligned(&s.nx[i]), P::load_unaligned(&s.ny[i]), P::load_unaligned(&s.nz[i])};
        const std::size_t left = s.size() - i;
        const auto lanes = krs::mask_from_bits<P>(left >= 64 ? ~0ull : (1ull << left) - 1);
        alignas(64) float v[packet_width];
        krs::soft_shadow(f, p, n, l, o, lanes).store_aligned(v);
        std::copy(v, v + std::min(left, packet_width), out + i);
    }
}
template <class F>
[[gnu::noinline]] void occlusion_scalar(const F& f, const shading_points& s, const krs::ambient_occlusion_options& o,
                                        float* out)
{
    for (std::size_t i = 0; i < s.size(); ++i) out[i] = krs::ambient_occlusion(f, s.p[i], s.n[i], o);
}
template <class F>
[[gnu::noinline]] void occlusion_packet(const F& f, const shading_points& s, const krs::ambient_occlusion_options& o,
                                        float* out)
{
    using P = krs::packet_f;
    for (std::size_t i = 0; i < s.size(); i += packet_width) {
        const krs::vec3<P> p{P::load_unaligned(&s.px[i]), P::load_unaligned(&s.py[i]), P::load_unaligned(&s.pz[i])};
        const krs::vec3<P> n{P::load_unaligned(&s.nx[i]), P::load_unaligned(&s.ny[i]), P::load_unaligned(&s.nz[i])};
        alignas(64) float v[packet_width];
        krs::ambient_occlusion(f, p, n, o).store_aligned(v);
        std::copy(v, v + std::min(s.size() - i, packet_width), out + i);
    }
}

template <class F>
void shadows_row(const char* name, const F& f, const framing& v, int size, csv_writer& csv, double& worst_shadow)
{
    const krs::pinhole_camera camera = camera_for(v, size);
    const krs::trace_options o = options_for(camera, v);
    const vec3f sun = krs::normalize(vec3f{0.55f, 0.65f, -0.35f});
    const float span = krs::length(v.target - v.eye); // the scene's scale: the camera's distance
    shading_points all, facing;
    for (int y0 = 0; y0 < size; y0 += 8)
        for (int x0 = 0; x0 < size; x0 += 8)
            for (int py = y0; py < std::min(y0 + 8, size); ++py)
                for (int px = x0; px < std::min(x0 + 8, size); ++px) {
                    const krs::ray<float> r = camera.primary_ray(float(px) + 0.5f, float(py) + 0.5f);
                    const krs::hit<float> h = krs::sphere_trace(f, r, o);
                    if (!h.found) continue;
                    const vec3f p = krs::point_at(r, h.t), n = f.normal(p);
                    all.add(p, n);
                    if (krs::dot(n, sun) > 0.0f) facing.add(p, n);
                }
    all.pad(), facing.pad();
    krs::soft_shadow_options so; // as krs_scenes lights its scenes
    so.hardness = 12.0f;
    so.threshold = o.threshold(span);
    so.max_distance = 0.5f * span;
    so.max_steps = 160;
    krs::ambient_occlusion_options ao;
    ao.step = 0.005f * span;
    std::vector<float> shadow[3], occlusion[2]; // shadow[2]: the previous scalar loop
    for (auto* v2 : {&shadow[0], &shadow[1], &shadow[2]}) v2->assign(facing.size(), 0.0f);
    for (auto* v2 : {&occlusion[0], &occlusion[1]}) v2->assign(all.size(), 0.0f);
    double best[5] = {1e30, 1e30, 1e30, 1e30, 1e30}; // seconds: shadow scalar, packet, AO scalar, packet; previous
    const auto time = [](auto&& run) {
        const auto start = std::chrono::steady_clock::now();
        run();
        return std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
    };
    for (int round = 0; round < repeats; ++round) {
        // The first of each pair swaps every round, so neither path always runs on a warm cache.
        for (int k = 0; k < 3; ++k) {
            const int which = (k + round) % 3;
            const int slot = which == 2 ? 4 : which;
            best[slot] = std::min(best[slot], time([&] {
                                      if (which == 0) shadows_scalar(f, facing, sun, so, shadow[0].data());
                                      else if (which == 1) shadows_packet(f, facing, sun, so, shadow[1].data());
                                      else shadows_previous(f, facing, sun, so, shadow[2].data());
                                  }));
        }
        for (int k = 0; k < 2; ++k) {
            const int which = (k + round) % 2;
            best[2 + which] = std::min(best[2 + which], time([&] {
                                           if (which == 0) occlusion_scalar(f, all, ao, occlusion[0].data());
                                           else occlusion_packet(f, all, ao, occlusion[1].data());
                                       }));
        }
    }
    const auto compare = [](const std::vector<float>& a, const std::vector<float>& b, double& worst, long& differ) {
        worst = 0, differ = 0;
        for (std::size_t i = 0; i < a.size(); ++i) {
            worst = std::max(worst, double(std::abs(a[i] - b[i])));
            differ += a[i] != b[i];
        }
    };
    double shadow_gap, occlusion_gap;
    long shadow_differ, occlusion_differ;
    compare(shadow[0], shadow[1], shadow_gap, shadow_differ);
    double previous_gap;
    long previous_differ;
    compare(shadow[2], shadow[0], previous_gap, previous_differ);
    compare(occlusion[0], occlusion[1], occlusion_gap, occlusion_differ);
    long penumbra = 0;
    for (float x : shadow[0]) penumbra += x > 0.0f && x < 1.0f;
    const double rays = double(facing.size()), probes = double(all.size());
    const double ss = rays / best[0] * 1e-6, sp = rays / best[1] * 1e-6, sv = rays / best[4] * 1e-6;
    const double as = probes / best[2] * 1e-6, ap = probes / best[3] * 1e-6;
    worst_shadow = std::min(worst_shadow, sp / ss);
    std::printf("%-20s %8zu %6.1f%% %9.3f %9.3f %9.3f %7.2fx %9.2g %7ld %7ld | %8zu %9.3f %9.3f %7.2fx %9.2g %7ld\n",
                name, facing.size(), 100.0 * double(penumbra) / rays, sv, ss, sp, sp / ss, shadow_gap, shadow_differ,
                previous_differ, all.size(), as, ap, ap / as, occlusion_gap, occlusion_differ);
    csv.row(format("shadows,%s,%zu,%ld,%.4f,%.4f,%.4f,%.3g,%ld,%zu,%.4f,%.4f,%.4f,%.3g,%ld,%.4f,%ld", name, facing.size(),
                   penumbra, ss, sp, sp / ss, shadow_gap, shadow_differ, all.size(), as, ap, ap / as, occlusion_gap,
                   occlusion_differ, sv, previous_differ));
}

void shadows_table(int size, csv_writer& csv)
{
    const std::string load_before = bench::load_average();
    std::printf("\n== soft shadows and ambient occlusion: scalar vs packet (%zu lanes), 1 thread, primary hits of "
                "%dx%d, best of %d alternating rounds ==\n", packet_width, size, size, repeats);
    std::printf("load average before: %s\n", load_before.c_str());
    std::printf("%-20s %8s %7s %9s %9s %9s %8s %9s %7s %7s | %8s %9s %9s %8s %9s %7s\n", "scene", "shadows", "penumb",
                "prev Mr/s", "scal Mr/s", "pack Mr/s", "ratio", "max diff", "differ", "vs prev", "AO", "scal Mp/s",
                "pack Mp/s", "ratio", "max diff", "differ");
    csv.row("table,scene,shadow_rays,penumbra_rays,shadow_scalar_mrays_s,shadow_packet_mrays_s,shadow_ratio,"
            "shadow_max_lane_difference,shadow_lanes_differ,ao_probes,ao_scalar_mprobes_s,ao_packet_mprobes_s,ao_ratio,"
            "ao_max_lane_difference,ao_lanes_differ,shadow_previous_scalar_mrays_s,shadow_previous_differ");
    double worst = 1e30;
    framing v;
    shadows_row("tree (15 levels)", tree_scene(15, v), v, size, csv, worst);
    framing fv;
    shadows_row("forest (64 trees)", forest_scene(12, 3, fv), fv, size, csv, worst);
    framing tv;
    shadows_row("terrain (general)", terrain_scene<krs::mirror>(20, tv), tv, size, csv, worst);
    std::printf("target packet soft shadow >= 6x scalar with 16 lanes: worst %.2fx -> %s\n", worst,
                packet_width >= 16 ? verdict(worst >= 6.0) : "(no target for this width)");
    const std::string load_after = bench::load_average();
    std::printf("load average before: %s; after: %s\n", load_before.c_str(), load_after.c_str());
    csv.row("table,before,after");
    csv.row(format("shadows_load,%s,%s", load_before.c_str(), load_after.c_str()));
}

// ---- table 6: the stream before and after issue 23 ---------------------------------------------

void stream_table(int size, csv_writer& csv)
{
    std::printf("\n== issue 23: packet stream before (reference) vs now, %dx%d, 8x8 tiles, 0.5 px threshold, %d "
                "interleaved packets of %zu lanes; Mr/s on 2 threads, best of %d alternating rounds; the rest on 1 "
                "thread ==\n",
                size, size, stream_interleave, packet_width, repeats);
    std::printf("load average before: %s\n", bench::load_average().c_str());
    bench::print_stream_header();
    csv.row(bench::stream_csv_header());
    for (int n : {16, 32}) {
        auto run = [&](const char* name, const auto& f, const framing& v) {
            const krs::pinhole_camera camera = camera_for(v, size);
            const bench::stream_comparison c = bench::compare_streams<krs::packet_f, stream_interleave>(
                f, camera, options_for(camera, v), 8, 2, repeats, n);
            csv.row(bench::stream_row(name, n, c));
        };
        framing v;
        run("tree", tree_scene(n + 1, v), v);
        run("forest (64 trees)", forest_scene(n - 5, 3, v), v);
        run("terrain (general)", terrain_scene<krs::mirror>(n, v), v);
        run("terrain (axis mirrors)", terrain_scene<krs::axis_mirror>(n, v), v);
    }
    std::printf("load average after: %s\n", bench::load_average().c_str());
}

} // namespace

int main(int argc, char** argv)
{
    int size = 256;
    std::string csv_path, only;
    for (int i = 1; i < argc; ++i) {
        const std::string a = argv[i];
        if (a == "--size" && i + 1 < argc) size = std::max(16, std::atoi(argv[++i]));
        else if (a == "--csv" && i + 1 < argc) csv_path = argv[++i];
        else if (a == "--repeat" && i + 1 < argc) repeats = std::max(1, std::atoi(argv[++i]));
        else if (a == "--only" && i + 1 < argc) only = argv[++i];
        else {
            std::fprintf(stderr, "usage: bench_packet_trace [--size N] [--csv FILE] [--repeat R] [--only throughput|levels|error|boxes|shadows|stream]\n");
            return 2;
        }
    }
    // Named after the executable, so the 8-lane build (bench_packet_trace_avx2) keeps its own.
    if (csv_path.empty()) csv_path = bench::csv_next_to_executable(argv[0]);
    csv_writer csv;
    csv.file.open(csv_path);
    if (!csv.file) {
        std::fprintf(stderr, "bench_packet_trace: cannot write %s\n", csv_path.c_str());
        return 1;
    }
    std::printf("bench_packet_trace: %zu float lanes, %u hardware threads, CSV -> %s\n", packet_width,
                std::thread::hardware_concurrency(), csv_path.c_str());
    if (only.empty() || only == "throughput") throughput_table(size, csv);
    if (only.empty() || only == "levels") levels_table(size, csv);
    if (only.empty() || only == "error") error_table(size, csv);
    if (only.empty() || only == "boxes") boxes_table(size, csv);
    if (only.empty() || only == "shadows") shadows_table(size, csv);
    if (only == "stream") stream_table(size, csv);
    return 0;
}

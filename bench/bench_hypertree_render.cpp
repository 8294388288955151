// bench_hypertree_render: the rendering columns of the hypertree paper's Table 1, and speed
// against error for the raymarcher's settings (docs/design.md#rule-5).
//
//     bench_hypertree_render [--csv FILE] [--threads T] [--size N] [--only table|error|setup|walk|bounds|setup-cpu|frame-cpu]
//     (the CSV goes next to the executable, as <executable>.csv, unless --csv names one)
//
// Table: trees A-D (hypertree/presets.hpp) in a 300 x 300 image, at resolution 100 without
// supersampling and at 300 with factor 2 (the paper's two settings), for each store kind, on T
// threads (default all cores), scalar and packet marchers; next to the paper's times (an Athlon at
// 1.4 GHz; its "3D array + bit array" column against our dense store). A frame is a render from a
// marcher already made; `setup` is the making of the marcher (its brick copy of the store,
// voxel_bricks.hpp, and with the light sweep its swept shadows, light_sweep.hpp), once per tree
// and lighting whatever the frames. Both shadow methods side by side, their rounds alternating:
// shadow rays (marched from every voxel in every frame) and the sweep (the default); RMSE is the
// sweep's image against the shadow rays' (packet marcher). Speedups are the sweep's (the "rays"
// column: shadow rays'), per frame and for one frame with its setup. Each timing is the best of 5.
//
// Speed against error: tree A at resolution 300 in an N x N image (default 200); each setting's
// time and root-mean-square error (linear RGB, over all pixels) against a converged reference:
// step factor 0.25, supersampling 4, shading (shadow rays included) at every sample. Settings: step factor,
// resolution through level of detail (lod.hpp), supersampling, per-voxel shading, bounding
// spheres, ray cache, voxels shaded as rays meet them instead of ahead, shadow rays instead of the
// sweep (with the sweep's setup and its RMSE against the shadow rays' image). Each timing is the
// best of 2 runs.
//
// Setup (`--only setup`): the light sweep's table (light_sweep.hpp), trees A-D at resolutions
// 100 and 300, dense store, three ways in alternating rounds: by levels in light order on one
// thread (as it was first made: volume_marcher::make_sweep_in_light_order), in two passes on one
// thread and on T threads (make_sweep, what the marcher does with the render's hook); wall and
// process CPU time (best of 9), each table compared bit for bit with the marcher's. Then the
// marchers' setups and one packet frame of each shadow method on T threads, and each with its
// setup (best of 9).
//
// Setup CPU (`--only setup-cpu`, not in the default run): each marcher's setup on one thread as
// its CPU time, trees A-D at 100 and 300, dense, index list and bit array, with a hash of the
// sweep's table (two builds with equal hashes made equal tables).
//
// Frame CPU (`--only frame-cpu`, not in the default run): one frame with its setup on one thread,
// as that thread's CPU time: the marcher made without threads, then one packet render() without
// threads (the default lighting: light sweep, per-voxel shading, shading ahead), trees A-D at 100
// (s = 1) and 300 (s = 2), dense store, setup and frame in alternating rounds, best of 31 at 100,
// 5 at 300; with a hash of the frame's pixels and lookups (FNV-1a of the float bits), so that two
// builds (the same benchmark over two versions of the library) can be compared bit for bit.
//
// Walk (`--only walk`): the brick walk with empty cubes of every level (brick_walk::skips, the
// default) against the walk of empty bricks and 16^3 blocks only (the one before), trees A-D at
// resolutions 100 and 300, dense store, side by side in alternating rounds: per primary ray (pixel
// centres of the 300 x 300 view, rays that enter the tree's box) the probes (brick walk visits)
// and lookups, the primary rays' time on one thread through voxels shaded ahead (best of 7, as the
// thread's CPU time, CLOCK_THREAD_CPUTIME_ID, and the wall time: on a loaded machine the CPU time
// leaves out the time the thread waited for a core), the
// frame's time on T threads (render() with march_options' defaults; best of 7), and the
// pixels that differ between the two walks' frames (the walks look at the same samples: 0).
//
// Bounds (`--only bounds`): the paper's Table 2 (section 8.2): trees A-D at resolution 300, dense
// store, with each march_options::bounds_by: AABB only, the part spheres fitted to the voxels,
// the paper's spheres derived through the transformations, the secondary AABBs (part boxes).
// Per bound: the time to make the bounding volumes, the marcher's setup, the frame (render() on T
// threads, with the light sweep and with shadow rays; best of 5, the bounds in alternating
// rounds), lookups and probes per primary ray, the stored voxels the bound leaves outside (brute
// force) and the pixels not bit-equal to AABB only's (0 whenever nothing is left outside).

#include "hypertree/execution.hpp"
#include "hypertree/hypertree.hpp"
#include "hypertree/presets.hpp"
#include "support/text.hpp"
#include "support/timing.hpp"

#include <algorithm>
#include <atomic>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <ctime>
#include <fstream>
#include <functional>
#include <optional>
#include <string>
#include <thread>
#include <limits>
#include <span>
#include <vector>

namespace {

using namespace hypertree;

// Table 1 rendering times (s): resolution 100 without supersampling, 300 with factor 2; columns
// index list, index list + bit array, 3D array + bit array.
const double paper_seconds[4][3][2] = {
    {{1.0, 16.7}, {0.6, 8.0}, {0.5, 7.7}},
    {{0.8, 11.5}, {0.4, 5.7}, {0.4, 5.6}},
    {{1.0, 15.5}, {0.5, 7.5}, {0.5, 7.1}},
    {{0.5, 7.8}, {0.3, 4.1}, {0.3, 4.1}},
};

// The paper's column of a store kind (index list, index list + bit array, 3D array); it has no
// partitioned store.
std::optional<std::size_t> paper_column(storage_type s)
{
    if (s == storage_type::index_list) return 0;
    if (s == storage_type::bit_array) return 1;
    if (s == storage_type::dense) return 2;
    return std::nullopt;
}

double rmse(const image& a, const image& b)
{
    double sum = 0;
    for (std::size_t i = 0; i < a.rgb.size(); ++i) {
        const double d = double(std::clamp(a.rgb[i], 0.0f, 1.0f)) - double(std::clamp(b.rgb[i], 0.0f, 1.0f));
        sum += d * d;
    }
    return std::sqrt(sum / double(a.rgb.size()));
}

std::vector<stored_voxel> classified(const ifs<>& tree, std::uint64_t seed)
{
    const generated_hits hits = generate(tree, seed);
    const std::vector<voxel_entry> entries = compact(hits.hits);
    return classify(entries, density_classes(entries, 32), tree.branch_depth);
}

// One of the paper's trees as the setup and walk tables draw it: its voxels (seed 1), its shape,
// the 300 x 300 view framing it and its depth colours.
struct paper_tree {
    ifs<> tree;
    std::vector<stored_voxel> voxels;
    tree_shape shape;
    krs::pinhole_camera camera;
    depth_colors colors;

    static paper_tree of(ifs<> tree)
    {
        std::vector<stored_voxel> voxels = classified(tree, 1);
        tree_shape shape = tree_shape::of(tree.volume, voxels);
        const krs::pinhole_camera camera = framing_camera(shape.box, 300, 300);
        const depth_colors colors = depth_colors::tree(tree.branch_depth, tree.tree_depth);
        return {std::move(tree), std::move(voxels), std::move(shape), camera, colors};
    }
};

// The primary rays of a view through a marcher's voxels all shaded ahead (as render() marches them,
// four packets at a time, in 4 x 4 tiles at s = 1): pixel centres, one thread. Returns the rays
// that enter the box, and sums their probes and lookups.
struct primary_counts {
    double rays = 0, probes = 0, lookups = 0;
};
primary_counts march_primary(const volume_marcher& marcher, const krs::pinhole_camera& camera, const shade_memo& memo)
{
    using P = krs::packet_f;
    constexpr std::size_t n = krs::lane_count<P>;
    primary_counts c;
    const int w = camera.width(), h = camera.height();
    march_context context{nullptr, const_cast<shade_memo*>(&memo)}; // read only: the memo is complete
    for (int y = 0; y < h; ++y)
        for (int x0 = 0; x0 < w; x0 += int(2 * n)) {
            std::array<krs::ray<P>, 2> rays;
            for (std::size_t g = 0; g < 2; ++g) {
                std::array<float, n> lx, ly;
                for (std::size_t l = 0; l < n; ++l) lx[l] = float(std::min(w - 1, x0 + int(g * n + l))) + 0.5f, ly[l] = float(y) + 0.5f;
                rays[g] = camera.primary_ray(P::load_unaligned(lx.data()), P::load_unaligned(ly.data()));
            }
            const auto out = marcher.march_packets<P, 2>(rays, context);
            for (std::size_t g = 0; g < 2; ++g) {
                const auto probes = krs::lanes_of(out[g].probes), lookups = krs::lanes_of(out[g].lookups);
                for (std::size_t l = 0; l < n && x0 + int(g * n + l) < w; ++l)
                    c.rays += probes[l] > 0, c.probes += double(probes[l]), c.lookups += double(lookups[l]);
            }
        }
    return c;
}
// The stored voxels whose cell no volume of `by` holds whole (spheres: all 8 corners inside; boxes:
// both extreme corners), in double from the shape's own volumes: the bound's containment by brute
// force. (Half a side less 1e-9 of it: cell centers and box faces are computed apart.)
// `needed`: for sphere bounds, the smallest factor every radius could be scaled by (about its
// center) with every cell still held (a box holding a cell holds it at any factor): below 1 the
// spheres have room to spare, above 1 they leave cells out.
std::size_t cells_outside(const hypervolume& v, std::span<const stored_voxel> voxels, const tree_shape& shape, bound_method by, double& needed)
{
    needed = 0;
    std::vector<krs::bounding_sphere> spheres;
    std::vector<world_box> boxes;
    if (by == bound_method::spheres) spheres = shape.spheres;
    if (by == bound_method::paper_spheres) spheres = shape.paper_spheres, boxes = shape.trunk_box;
    if (by == bound_method::part_boxes) boxes = shape.part_boxes;
    if (by == bound_method::box) return 0; // the box is fitted to the cells
    std::size_t outside = 0;
    for (const stored_voxel& sv : voxels) {
        const krs::vec3d c = v.voxel_center(sv.index), h = v.voxel_size() * (0.5 - 1e-9), lo = c - h, hi = c + h;
        bool held = false, in_box = false;
        double scale = std::numeric_limits<double>::infinity();
        for (const auto& s : spheres) {
            double farthest = 0;
            for (int k = 0; k < 8; ++k)
                farthest = std::max(farthest, krs::length(krs::vec3d{k & 1 ? hi.x : lo.x, k & 2 ? hi.y : lo.y, k & 4 ? hi.z : lo.z} - krs::vec3d(s.center)));
            held = held || farthest <= double(s.radius);
            scale = std::min(scale, farthest / double(s.radius));
        }
        for (std::size_t i = 0; i < boxes.size() && !in_box; ++i) {
            const world_box& b = boxes[i];
            in_box = lo.x >= b.lo.x && lo.y >= b.lo.y && lo.z >= b.lo.z && hi.x <= b.hi.x && hi.y <= b.hi.y && hi.z <= b.hi.z;
        }
        if (!in_box && !spheres.empty()) needed = std::max(needed, scale);
        outside += !(held || in_box);
    }
    return outside;
}
// What the paper's marcher looks up: it steps every sample of a ray across the tree's box (no
// empty-space skipping) and looks up those inside the bound. Per ray entering the box, over the
// pixel centres of every `stride`-th row and column, the samples t0 + (k + 1/2) ds in the box
// and in the bound (bound_test, as the marcher tests them).
double samples_in_bound(const tree_shape& shape, const krs::pinhole_camera& camera, float ds, bound_method by, int stride)
{
    const bound_test test = bound_test::of(shape, by);
    const krs::vec3f lo(shape.box.lo), hi(shape.box.hi);
    double samples = 0, rays = 0;
    for (int y = 0; y < camera.height(); y += stride)
        for (int x = 0; x < camera.width(); x += stride) {
            const krs::ray<float> r = camera.primary_ray(float(x) + 0.5f, float(y) + 0.5f);
            float t0 = 0, t1 = std::numeric_limits<float>::infinity();
            const float o[3] = {r.origin.x, r.origin.y, r.origin.z}, d[3] = {r.direction.x, r.direction.y, r.direction.z};
            const float l[3] = {lo.x, lo.y, lo.z}, h[3] = {hi.x, hi.y, hi.z};
            for (int a = 0; a < 3; ++a) {
                const float inv = 1.0f / d[a], ta = (l[a] - o[a]) * inv, tb = (h[a] - o[a]) * inv;
                t0 = std::max(t0, std::min(ta, tb)), t1 = std::min(t1, std::max(ta, tb));
            }
            if (!(t0 + 0.5f * ds < t1)) continue;
            rays += 1;
            for (float k = 0; t0 + (k + 0.5f) * ds < t1; k += 1) samples += test.holds(r.origin + r.direction * (t0 + (k + 0.5f) * ds));
        }
    return samples / std::max(rays, 1.0);
}
} // namespace

int main(int argc, char** argv)
{
    std::string csv_path, only;
    unsigned threads = std::max(1u, std::thread::hardware_concurrency());
    int size = 200;
    for (int i = 1; i < argc; ++i) {
        const std::string a = argv[i];
        if (i + 1 >= argc) {
            std::fprintf(stderr, "usage: %s [--csv FILE] [--threads T] [--size N] [--only table|error|setup|walk|bounds|setup-cpu|frame-cpu]\n", argv[0]);
            return 2;
        }
        const std::string v = argv[++i];
        if (a == "--csv") csv_path = v;
        else if (a == "--threads") threads = unsigned(std::max(1, std::atoi(v.c_str())));
        else if (a == "--size") size = std::max(16, std::atoi(v.c_str()));
        else if (a == "--only") only = v;
        else {
            std::fprintf(stderr, "unknown option %s\n", a.c_str());
            return 2;
        }
    }
    if (csv_path.empty()) csv_path = bench::csv_next_to_executable(argv[0]);
    std::ofstream csv(csv_path);
    csv << "table,tree,resolution,supersampling,store,marcher,setting,seconds,lookups,rmse,paper_seconds\n";

    std::printf("load average before: %s\n", bench::load_average().c_str());
    if (only.empty() || only == "table") {
        std::printf("hypertree rendering (paper Table 1): 300x300, %u thread(s), best of 5 (shadow rays and sweep alternating)\n\n", threads);
        std::printf("%-4s %4s %2s %-12s | %8s %8s %8s | %8s %8s %8s %8s %9s | %8s %6s %6s %8s\n", "tree", "res", "s", "store", "setup", "scalar",
                    "packet", "setup", "scalar", "packet", "lookups", "RMSE", "paper", "rays", "sweep", "w/ setup");
        std::printf("%-4s %4s %2s %-12s | %-26s | %-54s |\n", "", "", "", "", "shadow rays", "light sweep (default)");
        const std::array makers{presets::tree_a, presets::tree_b, presets::tree_c, presets::tree_d};
        double worst = 1e300, worst_with_setup = 1e300, worst_rays = 1e300, worst_rmse = 0;
        for (auto [res, s] : {std::pair{100, 1}, std::pair{300, 2}}) {
            for (std::size_t t = 0; t < makers.size(); ++t) {
                const ifs<> tree = makers[t](res);
                const std::vector<stored_voxel> voxels = classified(tree, 1);
                const tree_shape shape = tree_shape::of(tree.volume, voxels);
                const krs::pinhole_camera camera = framing_camera(shape.box, 300, 300);
                render_settings rs;
                rs.supersampling = s;
                rs.parallel_for = bench::parallel_for(threads);
                const auto row = [&]<class S>(const char* name, const S& store, std::optional<double> paper) {
                    const auto make = [&](march_options::shadow_method by) {
                        march_options o;
                        o.shadow_by = by;
                        return volume_marcher(store, shape, depth_colors::tree(tree.branch_depth, tree.tree_depth), o, rs.parallel_for);
                    };
                    using method = march_options::shadow_method;
                    // Setups and frames of both methods in alternating rounds, the best of 5 each.
                    double setup[2] = {1e300, 1e300}, scalar[2] = {1e300, 1e300}, packet[2] = {1e300, 1e300};
                    for (int round = 0; round < 5; ++round)
                        for (int m = 0; m < 2; ++m) setup[m] = std::min(setup[m], bench::best_seconds(1, [&] { (void)make(method(m)); }));
                    const volume_marcher marchers[2] = {make(method::rays), make(method::sweep)};
                    image img[2];
                    for (int round = 0; round < 5; ++round)
                        for (int m = 0; m < 2; ++m) {
                            scalar[m] = std::min(scalar[m], bench::best_seconds(1, [&] { img[m] = render<float>(marchers[m], camera, rs); }));
                            packet[m] = std::min(packet[m], bench::best_seconds(1, [&] { img[m] = render<krs::packet_f>(marchers[m], camera, rs); }));
                        }
                    const double error = rmse(img[1], img[0]);
                    worst_rmse = std::max(worst_rmse, error);
                    const double best = std::min(scalar[1], packet[1]), best_rays = std::min(scalar[0], packet[0]);
                    std::string paper_text = "-", speedup = "-", speedup_rays = "-", with_setup = "-";
                    if (paper) {
                        char b[32];
                        std::snprintf(b, sizeof b, "%.1f s", *paper), paper_text = b;
                        std::snprintf(b, sizeof b, "%.0fx", *paper / best), speedup = b;
                        std::snprintf(b, sizeof b, "%.0fx", *paper / best_rays), speedup_rays = b;
                        std::snprintf(b, sizeof b, "%.0fx", *paper / (setup[1] + best)), with_setup = b;
                        worst = std::min(worst, *paper / best);
                        worst_rays = std::min(worst_rays, *paper / best_rays);
                        worst_with_setup = std::min(worst_with_setup, *paper / (setup[1] + best));
                    }
                    std::printf("%-4s %4d %2d %-12s | %6.1fms %6.1fms %6.1fms | %6.1fms %6.1fms %6.1fms %7.2fM %9.5f | %8s %6s %6s %8s\n",
                                tree.name.c_str(), res, s, name, setup[0] * 1e3, scalar[0] * 1e3, packet[0] * 1e3, setup[1] * 1e3,
                                scalar[1] * 1e3, packet[1] * 1e3, double(img[1].lookups) / 1e6, error, paper_text.c_str(),
                                speedup_rays.c_str(), speedup.c_str(), with_setup.c_str());
                    for (int m = 0; m < 2; ++m) {
                        const std::string prefix = "table," + tree.name + ',' + std::to_string(res) + ',' + std::to_string(s) + ',' + name + ',';
                        const std::string method_name = m == 0 ? "rays" : "sweep";
                        const std::string paper_field = paper ? std::to_string(*paper) : "";
                        csv << prefix << "setup," << method_name << ',' << setup[m] << ",,," << paper_field << '\n';
                        for (auto [marcher_name, secs] : {std::pair{"scalar", scalar[m]}, std::pair{"packet", packet[m]}})
                            csv << prefix << marcher_name << ',' << method_name << ',' << secs << ',' << img[m].lookups << ','
                                << (m == 1 ? std::to_string(error) : "") << ',' << paper_field << '\n';
                    }
                };
                const int column = res == 100 ? 0 : 1;
                for_each_store_kind([&]<class S>() {
                    const std::optional<std::size_t> p = paper_column(storage_type_of<S>);
                    row(store_kind_name<S>.data(), S::build(tree.volume, voxels),
                        p ? std::optional<double>(paper_seconds[t][*p][column]) : std::nullopt);
                });
            }
            std::printf("\n");
        }
        std::printf("targets (issue 27): rendering >= 150x the paper's per frame: worst %.0fx (shadow rays: %.0fx) -> %s; "
                    ">= 130x for one frame with its setup: worst %.0fx -> %s; sweep against shadow rays: worst RMSE %.5f (bound 0.01 at "
                    "resolution 300)\n\n",
                    worst, worst_rays, worst >= 150 ? "met" : "NOT met", worst_with_setup, worst_with_setup >= 130 ? "met" : "NOT met", worst_rmse);
    }

    if (only.empty() || only == "error") {
        const ifs<> tree = presets::tree_a(300);
        const std::vector<stored_voxel> voxels = classified(tree, 1);
        const bit_array_store store = bit_array_store::build(tree.volume, voxels);
        const tree_shape shape = tree_shape::of(tree.volume, voxels);
        const depth_colors colors = depth_colors::tree(tree.branch_depth, tree.tree_depth);
        const krs::pinhole_camera camera = framing_camera(shape.box, size, size);

        march_options reference_options;
        reference_options.shadow_by = march_options::shadow_method::rays;
        reference_options.step_factor = 0.25f;
        reference_options.shade_per_voxel = false;
        render_settings reference_settings;
        reference_settings.supersampling = 4;
        reference_settings.parallel_for = bench::parallel_for(threads);
        const volume_marcher reference_marcher(store, shape, colors, reference_options);
        image reference;
        const double reference_seconds = bench::best_seconds(1, [&] { reference = render<float>(reference_marcher, camera, reference_settings); });
        std::printf("speed against error: tree A, resolution 300, %dx%d, %u thread(s); reference (step 0.25, s = 4, shadow "
                    "rays per sample) took %.2f s\n\n",
                    size, size, threads, reference_seconds);
        std::printf("%-34s %10s %10s %10s %10s\n", "setting", "setup", "time", "lookups", "RMSE");

        const auto measure = [&]<class S>(const std::string& name, const S& st, const tree_shape& sh, march_options mo, render_settings rs) {
            rs.parallel_for = bench::parallel_for(threads);
            const double setup = bench::best_seconds(2, [&] { (void)volume_marcher(st, sh, colors, mo); });
            const volume_marcher marcher(st, sh, colors, mo);
            image img;
            const double secs = bench::best_seconds(2, [&] { img = render<float>(marcher, camera, rs); });
            const double error = rmse(img, reference);
            std::printf("%-34s %8.1fms %8.1fms %9.2fM %10.5f\n", name.c_str(), setup * 1e3, secs * 1e3, double(img.lookups) / 1e6, error);
            csv << "error,A,300," << rs.supersampling << ",bit_array,scalar," << name << ',' << secs << ',' << img.lookups << ',' << error << ",\n";
            return img;
        };
        const march_options defaults;
        const render_settings one;
        for (float step : {0.5f, 1.0f, 2.0f}) {
            march_options mo = defaults;
            mo.step_factor = step;
            measure("step factor " + std::to_string(step).substr(0, 4), store, shape, mo, one);
        }
        for (int s : {1, 2, 3}) {
            render_settings rs = one;
            rs.supersampling = s;
            measure("supersampling " + std::to_string(s), store, shape, defaults, rs);
        }
        {
            // The two shadow methods, and the sweep's image against the shadow rays'.
            march_options rays = defaults;
            rays.shadow_by = march_options::shadow_method::rays;
            const image by_rays = measure("shadow rays", store, shape, rays, one);
            const image by_sweep = measure("light sweep (default)", store, shape, defaults, one);
            std::printf("%-34s %43.5f\n", "  light sweep against shadow rays", rmse(by_sweep, by_rays));
            csv << "error,A,300,1,bit_array,scalar,sweep against rays,,," << rmse(by_sweep, by_rays) << ",\n";
            for (int near : {2, 4, 8}) {
                march_options mo = defaults;
                mo.sweep_near_steps = near;
                const image img = measure("light sweep near steps " + std::to_string(near), store, shape, mo, one);
                std::printf("%-34s %43.5f\n", "  against shadow rays", rmse(img, by_rays));
            }
            march_options mo = defaults;
            mo.shade_per_voxel = false;
            measure("shading per sample", store, shape, mo, one);
            mo.shadow_by = march_options::shadow_method::rays;
            measure("shading per sample with shadow rays", store, shape, mo, one);
            mo = defaults;
            mo.bounds_by = bound_method::spheres;
            measure("bounding spheres", store, shape, mo, one);
            render_settings rs = one;
            rs.ray_cache = true;
            measure("ray cache", store, shape, defaults, rs);
            rs = one;
            rs.shade_ahead = false;
            measure("voxels shaded as rays meet them", store, shape, defaults, rs);
        }
        for (int res : {200, 150, 100}) {
            const std::vector<stored_voxel> reduced = reduce(store, resolution::cube(res));
            const hypervolume v = reduced_volume(tree.volume, resolution::cube(res));
            const bit_array_store lod = bit_array_store::build(v, reduced);
            measure("level of detail " + std::to_string(res), lod, tree_shape::of(v, reduced), defaults, one);
        }
    }

    if (only.empty() || only == "setup") {
        std::printf("light sweep: by levels in light order on one thread (as first made) against two passes (rays to their cuts, "
                    "then the chains of cuts) on one and on %u thread(s); 300x300, dense store, load average %s\n\n",
                    threads, bench::load_average().c_str());
        std::printf("%-4s %4s %2s | %8s | %17s | %17s | %17s | %8s %8s | %9s %9s %9s\n", "", "", "", "rays", "sweep by levels", "two passes, 1",
                    "two passes, T", "frame", "", "frame + setup", "", "");
        std::printf("%-4s %4s %2s | %8s | %8s %8s | %8s %8s | %8s %8s | %8s %8s | %9s %9s %9s\n", "tree", "res", "s", "setup", "wall", "cpu",
                    "wall", "cpu", "wall", "cpu", "rays", "sweep", "rays", "levels", "2 pass T");
        const parallel_for_hook pool = bench::parallel_for(threads);
        const auto process_cpu = [] {
            timespec t{};
            clock_gettime(CLOCK_PROCESS_CPUTIME_ID, &t);
            return double(t.tv_sec) + 1e-9 * double(t.tv_nsec);
        };
        double worst_gain = 1e300;
        for (auto [res, s] : {std::pair{100, 1}, std::pair{300, 2}}) {
            for (const auto& maker : {presets::tree_a, presets::tree_b, presets::tree_c, presets::tree_d}) {
                const paper_tree scene = paper_tree::of(maker(res));
                const auto& [tree, voxels, shape, camera, colors] = scene;
                const dense_store store = dense_store::build(tree.volume, voxels);
                render_settings rs;
                rs.supersampling = s;
                rs.parallel_for = pool;
                march_options by_rays;
                by_rays.shadow_by = march_options::shadow_method::rays;
                const volume_marcher marchers[2] = {volume_marcher(store, shape, colors, by_rays), volume_marcher(store, shape, colors, {}, pool)};
                // The sweep alone, three ways, in alternating rounds: 0 by levels, 1 two passes on
                // this thread, 2 two passes on the pool. Then the setups and frames.
                double wall[3] = {1e300, 1e300, 1e300}, cpu[3] = {1e300, 1e300, 1e300}, setup[2] = {1e300, 1e300}, frame[2] = {1e300, 1e300};
                std::size_t differ = 0;
                for (int round = 0; round < 9; ++round) {
                    for (int m = 0; m < 3; ++m) {
                        light_sweep table;
                        const double cpu0 = process_cpu();
                        wall[m] = std::min(wall[m], bench::best_seconds(1, [&] {
                            table = m == 0 ? marchers[0].make_sweep_in_light_order() : marchers[0].make_sweep(m == 2 ? pool : parallel_for_hook{});
                        }));
                        cpu[m] = std::min(cpu[m], process_cpu() - cpu0);
                        for (std::size_t i = 0; round == 0 && i < marchers[1].shading().light_directions().size(); ++i)
                            differ += std::memcmp(table.toward(i), marchers[1].sweep().toward(i), marchers[1].bricks().voxel_count() * sizeof(float)) != 0;
                    }
                    setup[0] = std::min(setup[0], bench::best_seconds(1, [&] { (void)volume_marcher(store, shape, colors, by_rays); }));
                    setup[1] = std::min(setup[1], bench::best_seconds(1, [&] { (void)volume_marcher(store, shape, colors, {}, pool); }));
                }
                image img[2];
                for (int round = 0; round < 9; ++round)
                    for (int m = 0; m < 2; ++m)
                        frame[m] = std::min(frame[m], bench::best_seconds(1, [&] { img[m] = render<krs::packet_f>(marchers[m], camera, rs); }));
                // One frame with its setup: shadow rays' (their marcher: the brick copy), the sweep by
                // levels' (the brick copy and that sweep: as the marcher was made before) and the
                // marcher's now (two passes on the pool).
                const double with_setup[3] = {setup[0] + frame[0], setup[0] + wall[0] + frame[1], setup[1] + frame[1]};
                worst_gain = std::min(worst_gain, with_setup[0] / with_setup[2]);
                std::printf("%-4s %4d %2d | %6.1fms | %6.1fms %6.1fms | %6.1fms %6.1fms | %6.1fms %6.1fms | %6.1fms %6.1fms | %7.1fms %7.1fms "
                            "%7.1fms%s\n",
                            tree.name.c_str(), res, s, setup[0] * 1e3, wall[0] * 1e3, cpu[0] * 1e3, wall[1] * 1e3, cpu[1] * 1e3, wall[2] * 1e3,
                            cpu[2] * 1e3, frame[0] * 1e3, frame[1] * 1e3, with_setup[0] * 1e3, with_setup[1] * 1e3, with_setup[2] * 1e3,
                            differ ? "  TABLES DIFFER" : "");
                const std::string prefix = "setup," + tree.name + ',' + std::to_string(res) + ',' + std::to_string(s) + ",dense,";
                const char* names[3] = {"sweep_by_levels", "two_passes_1_thread", "two_passes_threads"};
                for (int m = 0; m < 3; ++m) {
                    csv << prefix << "sweep_wall," << names[m] << ',' << wall[m] << ",," << differ << ",\n";
                    csv << prefix << "sweep_cpu," << names[m] << ',' << cpu[m] << ",,,\n";
                }
                for (int m = 0; m < 2; ++m) {
                    const char* method_name = m == 0 ? "rays" : "sweep";
                    csv << prefix << "setup," << method_name << ',' << setup[m] << ",,,\n";
                    csv << prefix << "packet," << method_name << ',' << frame[m] << ',' << img[m].lookups << ",,\n";
                }
            }
        }
        std::printf("\n(the sweep alone: wall and process CPU time, best of 9 in alternating rounds, every table compared with the "
                    "marcher's bit for bit; rays setup: the marcher with shadow rays, i.e. the brick copy; frame: packet render() on %u "
                    "thread(s), best of 9; frame + setup: shadow rays, the sweep by levels (rays setup + sweep), the marcher made on "
                    "the pool. One frame with setup, shadow rays over the sweep: worst %.2fx)\nload average after: %s\n\n",
                    threads, worst_gain, bench::load_average().c_str());
    }

    if (only.empty() || only == "walk") {
        std::printf("brick walk: empty cubes of every level against empty bricks and 16^3 blocks only; 300x300, dense store, "
                    "load average %s\n\n", bench::load_average().c_str());
        std::printf("%-4s %4s %2s %-7s %7s %10s %11s %11s %11s %11s %8s\n", "tree", "res", "s", "walk", "levels", "probes/ray", "lookups/ray",
                    "primary cpu", "primary", "frame", "pixels!=");
        for (auto [res, s] : {std::pair{100, 1}, std::pair{300, 2}}) {
            for (const auto& maker : {presets::tree_a, presets::tree_b, presets::tree_c, presets::tree_d}) {
                const paper_tree scene = paper_tree::of(maker(res));
                const auto& [tree, voxels, shape, camera, colors] = scene;
                const dense_store store = dense_store::build(tree.volume, voxels);
                render_settings rs;
                rs.supersampling = s;
                rs.parallel_for = bench::parallel_for(threads);
                const std::array<brick_walk::skips, 2> kinds{brick_walk::skips::every_level, brick_walk::skips::bricks_and_blocks};
                const std::array<const char*, 2> names{"levels", "blocks"};
                std::vector<volume_marcher> marchers;
                for (auto k : kinds) marchers.emplace_back(store, shape, colors, march_options{}, parallel_for_hook{}, k);
                std::array<shade_memo, 2> memos{marchers[0].new_shade_memo(), marchers[1].new_shade_memo()};
                for (std::size_t m = 0; m < 2; ++m) {
                    marchers[m].shade_bricks(memos[m], 0, marchers[m].bricks().brick_count());
                    memos[m].seal();
                }
                std::array<double, 2> primary{1e300, 1e300}, primary_cpu{1e300, 1e300}, frame{1e300, 1e300};
                std::array<primary_counts, 2> counts;
                std::array<image, 2> images;
                for (int round = 0; round < 7; ++round)
                    for (std::size_t m = 0; m < 2; ++m) {
                        const double cpu0 = bench::thread_cpu_seconds();
                        primary[m] = std::min(primary[m], bench::best_seconds(1, [&] { counts[m] = march_primary(marchers[m], camera, memos[m]); }));
                        primary_cpu[m] = std::min(primary_cpu[m], bench::thread_cpu_seconds() - cpu0);
                        frame[m] = std::min(frame[m], bench::best_seconds(1, [&] { images[m] = render<krs::packet_f>(marchers[m], camera, rs); }));
                    }
                std::size_t differ = 0;
                for (std::size_t i = 0; i < images[0].rgb.size(); i += 3)
                    differ += std::memcmp(&images[0].rgb[i], &images[1].rgb[i], 3 * sizeof(float)) != 0;
                for (std::size_t m = 0; m < 2; ++m) {
                    std::printf("%-4s %4d %2d %-7s %7d %10.2f %11.2f %9.2fms %9.2fms %9.2fms %8zu\n", tree.name.c_str(), res, s, names[m],
                                marchers[m].bricks().empty_levels(), counts[m].probes / counts[m].rays, counts[m].lookups / counts[m].rays,
                                primary_cpu[m] * 1e3, primary[m] * 1e3, frame[m] * 1e3, differ);
                    csv << "walk," << tree.name << ',' << res << ',' << s << ",dense,packet," << names[m] << "_primary," << primary[m] << ','
                        << counts[m].lookups / counts[m].rays << ",," << '\n';
                    csv << "walk," << tree.name << ',' << res << ',' << s << ",dense,packet," << names[m] << "_primary_cpu," << primary_cpu[m]
                        << ",,,\n";
                    csv << "walk," << tree.name << ',' << res << ',' << s << ",dense,packet," << names[m] << "_frame," << frame[m] << ",,"
                        << differ << ",\n";
                    csv << "walk," << tree.name << ',' << res << ',' << s << ",dense,packet," << names[m] << "_probes_per_ray,"
                        << counts[m].probes / counts[m].rays << ",,,\n";
                }
            }
        }
        std::printf("\n(probes and lookups per primary ray entering the box; primary: those rays on one thread through voxels shaded "
                    "ahead, CPU and wall time; frame: render() on %u thread(s); pixels!=: pixels of the two frames not bit-equal)\n"
                    "load average after: %s\n",
                    threads, bench::load_average().c_str());
    }
    if (only.empty() || only == "bounds") {
        // The paper's Table 2: AABB only, (secondary) spheres, secondary AABBs; here also the
        // spheres fitted to the parts' voxels (tree_shape.hpp).
        std::printf("bounding volumes (the paper's Table 2): trees A-D, resolution 300, 300x300, s = 1, dense store, packet marcher on %u "
                    "thread(s), best of 5 in alternating rounds; load average %s\n\n",
                    threads, bench::load_average().c_str());
        std::printf("%-4s %-14s %9s %9s %11s %11s %11s %10s %11s %9s %8s %9s\n", "tree", "bound", "volumes", "setup", "frame sweep", "frame rays",
                    "lookups/ray", "probes/ray", "paper looks", "cells out", "radius x", "pixels!=");
        const std::array<bound_method, 4> bounds{bound_method::box, bound_method::spheres, bound_method::paper_spheres, bound_method::part_boxes};
        const std::array<const char*, 4> names{"AABB only", "fitted spheres", "paper spheres", "secondary AABB"};
        for (const auto& maker : {presets::tree_a, presets::tree_b, presets::tree_c, presets::tree_d}) {
            paper_tree scene = paper_tree::of(maker(300));
            const ifs<>& tree = scene.tree;
            const dense_store store = dense_store::build(tree.volume, scene.voxels);
            // Creation: the shape (box, fitted spheres, part boxes and flows all in one pass over
            // the voxels) and the paper's spheres from the drawn IFS (best of 5 each).
            const double shape_seconds = bench::best_seconds(5, [&] { (void)tree_shape::of(tree.volume, scene.voxels); });
            const drawn_ifs<runtime_pipeline> drawn(tree, 1);
            const double paper_seconds = bench::best_seconds(5, [&] { scene.shape.set_paper_spheres_of(drawn); });
            const tree_shape& shape = scene.shape;
            render_settings rs;
            rs.parallel_for = bench::parallel_for(threads);
            std::vector<volume_marcher> sweep, rays;
            std::array<double, 4> setup{}, frame_sweep{}, frame_rays{};
            for (std::size_t b = 0; b < 4; ++b) {
                march_options mo;
                mo.bounds_by = bounds[b];
                setup[b] = bench::best_seconds(1, [&] { sweep.emplace_back(store, shape, scene.colors, mo, rs.parallel_for); });
                mo.shadow_by = march_options::shadow_method::rays;
                rays.emplace_back(store, shape, scene.colors, mo, rs.parallel_for);
                frame_sweep[b] = frame_rays[b] = 1e300;
            }
            std::array<image, 4> images, ray_images;
            for (int round = 0; round < 5; ++round)
                for (std::size_t b = 0; b < 4; ++b) {
                    frame_sweep[b] = std::min(frame_sweep[b], bench::best_seconds(1, [&] { images[b] = render<krs::packet_f>(sweep[b], scene.camera, rs); }));
                    frame_rays[b] = std::min(frame_rays[b], bench::best_seconds(1, [&] { ray_images[b] = render<krs::packet_f>(rays[b], scene.camera, rs); }));
                }
            for (std::size_t b = 0; b < 4; ++b) {
                shade_memo memo = sweep[b].new_shade_memo();
                sweep[b].shade_bricks(memo, 0, sweep[b].bricks().brick_count());
                memo.seal();
                const primary_counts counts = march_primary(sweep[b], scene.camera, memo);
                // Pixels not bit-equal to AABB only's, in either shadow method's frame.
                std::size_t differ = 0;
                for (std::size_t i = 0; i < images[0].rgb.size(); i += 3)
                    differ += std::memcmp(&images[0].rgb[i], &images[b].rgb[i], 3 * sizeof(float)) != 0 ||
                              std::memcmp(&ray_images[0].rgb[i], &ray_images[b].rgb[i], 3 * sizeof(float)) != 0;
                double needed = 0;
                const std::size_t outside = cells_outside(tree.volume, scene.voxels, shape, bounds[b], needed);
                const double volumes = b == 2 ? shape_seconds + paper_seconds : shape_seconds;
                const double paper_looks = samples_in_bound(shape, scene.camera, sweep[b].step(), bounds[b], 3);
                std::printf("%-4s %-14s %7.3fms %7.1fms %9.1fms %9.1fms %11.2f %10.2f %11.1f %9zu %8.3f %9zu\n", tree.name.c_str(), names[b],
                            volumes * 1e3, setup[b] * 1e3, frame_sweep[b] * 1e3, frame_rays[b] * 1e3, counts.lookups / counts.rays,
                            counts.probes / counts.rays, paper_looks, outside, needed, differ);
                csv << "bounds," << tree.name << ",300,1,dense,packet," << names[b] << "_radius_needed,," << needed << ",,\n";
                csv << "bounds," << tree.name << ",300,1,dense,packet," << names[b] << "_paper_lookups_per_ray,," << paper_looks << ",,\n";
                csv << "bounds," << tree.name << ",300,1,dense,packet," << names[b] << "_frame_sweep," << frame_sweep[b] << ','
                    << counts.lookups / counts.rays << ',' << differ << ",\n";
                csv << "bounds," << tree.name << ",300,1,dense,packet," << names[b] << "_frame_rays," << frame_rays[b] << ",,,\n";
                csv << "bounds," << tree.name << ",300,1,dense,packet," << names[b] << "_volumes," << volumes << ",,,\n";
                csv << "bounds," << tree.name << ",300,1,dense,packet," << names[b] << "_cells_outside," << outside << ",,,\n";
            }
        }
        std::printf("\n(volumes: making the bounds, the shape's one pass over the voxels, plus the paper's spheres where used; setup: the "
                    "marcher's; frame: render() with the light sweep and with shadow rays; lookups and probes per primary ray entering "
                    "the box; paper looks: samples per ray in box and bound, what the paper's marcher without empty-space skipping looks "
                    "up (every 3rd row and column); cells out: stored voxels whose cell no volume of the bound holds whole, by brute force; radius x: the factor the "
                    "spheres' radii could be scaled by and still hold every cell a sphere must hold (> 1: cells out); pixels!=: pixels "
                    "not bit-equal to AABB only's in either frame)\nload average after: %s\n",
                    bench::load_average().c_str());
    }
    if (only == "setup-cpu") {
        // The marcher's setup alone, on this thread, as its CPU time (CLOCK_THREAD_CPUTIME_ID: on a
        // machine with more runnable threads than cores, wall times of a millisecond varied 10x
        // between runs); best of 9 at resolution 100, 3 at 300, both shadow methods in alternating
        // rounds; trees A-D, dense, index list and bit array. `hash`: FNV-1a of the sweep's table
        // (its float bits in slot order), to compare the values of two builds (equal hashes: equal
        // tables). Not run by default (only with --only setup-cpu).
        std::printf("marcher setup on one thread, thread CPU time (best of 9 at 100, 3 at 300), load average %s\n\n",
                    bench::load_average().c_str());
        std::printf("%-4s %4s %-12s | %9s %9s | %16s\n", "tree", "res", "store", "rays", "sweep", "sweep table hash");
        const auto cpu_of = [](const auto& f) {
            const double t0 = bench::thread_cpu_seconds();
            f();
            return bench::thread_cpu_seconds() - t0;
        };
        for (const int res : {100, 300}) {
            for (const auto& maker : {presets::tree_a, presets::tree_b, presets::tree_c, presets::tree_d}) {
                const paper_tree scene = paper_tree::of(maker(res));
                const auto row = [&]<class S>(const char* name, const S& store) {
                    march_options by_rays;
                    by_rays.shadow_by = march_options::shadow_method::rays;
                    double setup[2] = {1e300, 1e300};
                    for (int round = 0; round < (res == 100 ? 9 : 3); ++round) {
                        setup[0] = std::min(setup[0], cpu_of([&] { (void)volume_marcher(store, scene.shape, scene.colors, by_rays); }));
                        setup[1] = std::min(setup[1], cpu_of([&] { (void)volume_marcher(store, scene.shape, scene.colors, {}); }));
                    }
                    const volume_marcher marcher(store, scene.shape, scene.colors, {});
                    std::uint64_t hash = 1469598103934665603ull;
                    for (std::size_t l = 0; l < marcher.shading().light_directions().size(); ++l)
                        for (std::size_t i = 0; i < marcher.bricks().voxel_count(); ++i) {
                            std::uint32_t bits;
                            std::memcpy(&bits, marcher.sweep().toward(l) + i, sizeof bits);
                            hash = (hash ^ bits) * 1099511628211ull;
                        }
                    std::printf("%-4s %4d %-12s | %7.3fms %7.3fms | %016llx\n", scene.tree.name.c_str(), res, name, setup[0] * 1e3,
                                setup[1] * 1e3, static_cast<unsigned long long>(hash));
                    std::fflush(stdout);
                    const std::string prefix = "setup_cpu," + scene.tree.name + ',' + std::to_string(res) + ",," + name + ",setup,";
                    csv << prefix << "rays," << setup[0] << ",,,\n";
                    csv << prefix << "sweep," << setup[1] << ",,,\n";
                };
                row("dense", dense_store::build(scene.tree.volume, scene.voxels));
                row("index_list", index_list_store::build(scene.tree.volume, scene.voxels));
                row("bit_array", bit_array_store::build(scene.tree.volume, scene.voxels));
            }
        }
    }
    if (only == "frame-cpu") {
        // One frame with its setup, each on this thread alone, as its CPU time
        // (CLOCK_THREAD_CPUTIME_ID: a loaded machine's waits for a core are left out).
        std::printf("one frame with its setup on one thread, thread CPU time (best of 31 at 100, 5 at 300; setup and frame "
                    "alternating), dense store, 300x300, load average %s\n\n",
                    bench::load_average().c_str());
        std::printf("%-4s %4s %2s | %9s %9s %9s | %8s %6s | %16s\n", "tree", "res", "s", "setup", "frame", "sum", "paper", "x", "image hash");
        const auto cpu_of = [](const auto& f) {
            const double t0 = bench::thread_cpu_seconds();
            f();
            return bench::thread_cpu_seconds() - t0;
        };
        for (auto [res, s] : {std::pair{100, 1}, std::pair{300, 2}}) {
            for (std::size_t t = 0; t < 4; ++t) {
                const auto maker = std::array{presets::tree_a, presets::tree_b, presets::tree_c, presets::tree_d}[t];
                const paper_tree scene = paper_tree::of(maker(res));
                const dense_store store = dense_store::build(scene.tree.volume, scene.voxels);
                render_settings rs;
                rs.supersampling = s;
                const volume_marcher marcher(store, scene.shape, scene.colors, {});
                double setup = 1e300, frame = 1e300;
                image img;
                for (int round = 0; round < (res == 100 ? 31 : 5); ++round) {
                    setup = std::min(setup, cpu_of([&] { (void)volume_marcher(store, scene.shape, scene.colors, {}); }));
                    frame = std::min(frame, cpu_of([&] { img = render<krs::packet_f>(marcher, scene.camera, rs); }));
                }
                std::uint64_t hash = 1469598103934665603ull;
                for (const float v : img.rgb) {
                    std::uint32_t bits;
                    std::memcpy(&bits, &v, sizeof bits);
                    hash = (hash ^ bits) * 1099511628211ull;
                }
                hash = (hash ^ img.lookups) * 1099511628211ull;
                const double paper = paper_seconds[t][2][res == 100 ? 0 : 1];
                std::printf("%-4s %4d %2d | %7.3fms %7.3fms %7.3fms | %6.1f s %5.0fx | %016llx\n", scene.tree.name.c_str(), res, s,
                            setup * 1e3, frame * 1e3, (setup + frame) * 1e3, paper, paper / (setup + frame),
                            static_cast<unsigned long long>(hash));
                std::fflush(stdout);
                const std::string prefix = "frame_cpu," + scene.tree.name + ',' + std::to_string(res) + ',' + std::to_string(s) + ",dense,packet,";
                csv << prefix << "setup," << setup << ",,," << paper << '\n';
                csv << prefix << "frame," << frame << ',' << img.lookups << ",," << paper << '\n';
            }
        }
        std::printf("\n(setup: the marcher made on this thread; frame: packet render() on this thread; x: the paper's time (3D array) over "
                    "the sum, one core against the paper's one)\n");
    }
    std::printf("\nload average after: %s\nwrote %s\n", bench::load_average().c_str(), csv_path.c_str());
    return 0;
}

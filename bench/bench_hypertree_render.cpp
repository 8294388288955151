// bench_hypertree_render: the rendering columns of the hypertree paper's Table 1, and speed
// against error for the raymarcher's settings (docs/design.md#rule-5).
//
//     bench_hypertree_render [--csv FILE] [--threads T] [--size N] [--only table|error]
//     (the CSV goes next to the executable, as <executable>.csv, unless --csv names one)
//
// Table: trees A-D (hypertree/presets.hpp) in a 300 x 300 image, at resolution 100 without
// supersampling and at 300 with factor 2 (the paper's two settings), for each store kind, on T
// threads (default all cores), scalar and packet marchers; next to the paper's times (an Athlon at
// 1.4 GHz; its "3D array + bit array" column against our dense store). A frame is a render from a
// marcher already made; `setup` is the making of the marcher (its brick copy of the store,
// voxel_bricks.hpp), once per tree and lighting whatever the frames. Speedups are given per frame
// and for one frame with its setup. Each timing is the best of 5 runs.
//
// Speed against error: tree A at resolution 300 in an N x N image (default 200); each setting's
// time and root-mean-square error (linear RGB, over all pixels) against a converged reference:
// step factor 0.25, supersampling 4, shading (shadow rays included) at every sample. Settings: step factor,
// resolution through level of detail (lod.hpp), supersampling, per-voxel shading, bounding
// spheres, ray cache, voxels shaded as rays meet them instead of ahead. Each timing is the best of
// 2 runs.

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
#include <fstream>
#include <functional>
#include <optional>
#include <string>
#include <thread>
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

} // namespace

int main(int argc, char** argv)
{
    std::string csv_path, only;
    unsigned threads = std::max(1u, std::thread::hardware_concurrency());
    int size = 200;
    for (int i = 1; i < argc; ++i) {
        const std::string a = argv[i];
        if (i + 1 >= argc) {
            std::fprintf(stderr, "usage: %s [--csv FILE] [--threads T] [--size N] [--only table|error]\n", argv[0]);
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

    if (only.empty() || only == "table") {
        std::printf("hypertree rendering (paper Table 1): 300x300, %u thread(s), best of 5\n\n", threads);
        std::printf("%-4s %4s %2s %-12s %10s %10s %10s %8s | %9s %8s %11s\n", "tree", "res", "s", "store", "setup", "scalar", "packet", "lookups",
                    "paper RT", "speedup", "with setup");
        const std::array makers{presets::tree_a, presets::tree_b, presets::tree_c, presets::tree_d};
        double worst = 1e300, worst_with_setup = 1e300;
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
                    const auto make = [&] { return volume_marcher(store, shape, depth_colors::tree(tree.branch_depth, tree.tree_depth)); };
                    const double setup = bench::best_seconds(5, [&] { (void)make(); });
                    const volume_marcher marcher = make();
                    image img;
                    const double scalar = bench::best_seconds(5, [&] { img = render<float>(marcher, camera, rs); });
                    const double packet = bench::best_seconds(5, [&] { img = render<krs::packet_f>(marcher, camera, rs); });
                    const double best = std::min(scalar, packet);
                    std::string paper_text = "-", speedup = "-", with_setup = "-";
                    if (paper) {
                        char b[32];
                        std::snprintf(b, sizeof b, "%.1f s", *paper), paper_text = b;
                        std::snprintf(b, sizeof b, "%.0fx", *paper / best), speedup = b;
                        std::snprintf(b, sizeof b, "%.0fx", *paper / (setup + best)), with_setup = b;
                        worst = std::min(worst, *paper / best);
                        worst_with_setup = std::min(worst_with_setup, *paper / (setup + best));
                    }
                    std::printf("%-4s %4d %2d %-12s %8.1fms %8.1fms %8.1fms %7.2fM | %9s %8s %11s\n", tree.name.c_str(), res, s, name,
                                setup * 1e3, scalar * 1e3, packet * 1e3, double(img.lookups) / 1e6, paper_text.c_str(), speedup.c_str(),
                                with_setup.c_str());
                    csv << "table," << tree.name << ',' << res << ',' << s << ',' << name << ",setup,," << setup << ",,,"
                        << (paper ? std::to_string(*paper) : "") << '\n';
                    for (auto [marcher_name, secs] : {std::pair{"scalar", scalar}, std::pair{"packet", packet}})
                        csv << "table," << tree.name << ',' << res << ',' << s << ',' << name << ',' << marcher_name << ",," << secs << ','
                            << img.lookups << ",," << (paper ? std::to_string(*paper) : "") << '\n';
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
        std::printf("target: rendering >= 100x faster than the paper's on both cores: worst %.0fx per frame -> %s; "
                    "worst %.0fx for one frame with its setup -> %s\n\n",
                    worst, worst >= 100 ? "met" : "NOT met", worst_with_setup, worst_with_setup >= 100 ? "met" : "NOT met");
    }

    if (only.empty() || only == "error") {
        const ifs<> tree = presets::tree_a(300);
        const std::vector<stored_voxel> voxels = classified(tree, 1);
        const bit_array_store store = bit_array_store::build(tree.volume, voxels);
        const tree_shape shape = tree_shape::of(tree.volume, voxels);
        const depth_colors colors = depth_colors::tree(tree.branch_depth, tree.tree_depth);
        const krs::pinhole_camera camera = framing_camera(shape.box, size, size);

        march_options reference_options;
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
        std::printf("%-34s %10s %10s %10s\n", "setting", "time", "lookups", "RMSE");

        const auto measure = [&]<class S>(const std::string& name, const S& st, const tree_shape& sh, march_options mo, render_settings rs) {
            rs.parallel_for = bench::parallel_for(threads);
            const volume_marcher marcher(st, sh, colors, mo);
            image img;
            const double secs = bench::best_seconds(2, [&] { img = render<float>(marcher, camera, rs); });
            const double error = rmse(img, reference);
            std::printf("%-34s %8.1fms %9.2fM %10.5f\n", name.c_str(), secs * 1e3, double(img.lookups) / 1e6, error);
            csv << "error,A,300," << rs.supersampling << ",bit_array,scalar," << name << ',' << secs << ',' << img.lookups << ',' << error << ",\n";
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
            march_options mo = defaults;
            mo.shade_per_voxel = false;
            measure("shading per sample", store, shape, mo, one);
            mo = defaults;
            mo.use_spheres = true;
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
    std::printf("\nwrote %s\n", csv_path.c_str());
    return 0;
}

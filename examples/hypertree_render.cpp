// hypertree_render: reads a hypertree definition file (or a hyperforest file, or one of the
// built-in presets), generates it, renders it with self-shadowing and writes a PNG; prints the
// creation and render times (paper sections 6, 8 and 10).
//
//     hypertree_render [--tree FILE | --forest FILE | --preset A|B|C|D] [--resolution N]
//                      [--store dense|index_list|bit_array|partitioned] [--width W] [--height H]
//                      [--supersampling S|auto] [--density-scale K] [--threads N] [--seed N]
//                      [--output FILE.png] [--save-volume FILE] [--save-vdb FILE.vdb] [--save-nvdb FILE.nvdb]
//                      [--up y|z]
//                      [--lod N] [--clear-above Y] [--ambient A] [--diffuse D] [--specular S]
//                      [--shininess N] [--light-elevation DEG] [--light-azimuth DEG]
//                      [--normals structure_flow|part_boxes|line_flow] [--shadows on|off] [--noise on|off]
//
// The settings of the paper's figures 8-12 (examples/hypertrees/figure*.tree and .forest, whose
// `# render` lines scripts/render_figures.sh runs):
// - --lod N reduces the generated tree to N voxels along each axis (lod.hpp, section 9: densities
//   averaged by overlap) before it is stored and rendered (figure 12);
// - --clear-above Y clears every voxel whose centre lies at or above height Y (tree units) after
//   generation (ops.hpp `clear` with a half-space, section 7: "as if the hypertree has been
//   horizontally docked", figure 9);
// - --ambient, --diffuse, --specular, --shininess, one light from --light-elevation and
//   --light-azimuth, --normals (march_options::normals_by) and --shadows: the shading of section
//   8.3 (figure 10); --supersampling is the antialiasing of figure 11.
// - --noise off drops the tree's noise (PERTURB, VOXELPERTURB, RENDERPERTURB; every tree's in a
//   forest): figure 8's unperturbed companion, against which the check sees the noise's effect.
// The camera is framed on the tree as generated, before --lod or --clear-above, so a reduced or
// cleared tree is seen from exactly where the whole one is (its images compare pixel by pixel).
//
// --save-vdb and --save-nvdb write the store as OpenVDB and NanoVDB grids (hypertree/io/openvdb.hpp,
// io/nanovdb.hpp): they exist only in a build that found OpenVDB and NanoVDB (KRS_WITH_OPENVDB,
// from the target krs::hypertree_openvdb); elsewhere they are refused with a message saying so.
// --up z writes both turned z-up, the tree's +y along the file's +z (the grids' transform carries
// the turn, the voxels are the same), so Blender and Houdini show it standing; --up is refused
// without one of them, as the PNG and --save-volume are of the tree in its own y-up frame.

#include "hypertree/forest.hpp"
#include "hypertree/hypertree.hpp"
#include "hypertree/definition_refusals.hpp"
#include "hypertree/lod.hpp"
#include "hypertree/ops.hpp"
#include "hypertree/presets.hpp"
#include "hypertree/render/render.hpp"
#include "support/command_line.hpp"
#include "support/common_options.hpp"
#include "support/error_message.hpp"
#include "support/example_io.hpp"
#include "support/output_path.hpp"
#include "support/progress.hpp"
#include "support/up_axis_option.hpp"

#ifndef KRS_WITH_OPENVDB
#define KRS_WITH_OPENVDB 0
#endif
#if KRS_WITH_OPENVDB
#include "hypertree/io/nanovdb.hpp"
#include "hypertree/io/openvdb.hpp"
#endif

#include <atomic>
#include <chrono>
#include <cstdio>
#include <filesystem>
#include <functional>
#include <memory>
#include <cmath>
#include <stdexcept>
#include <utility>
#include <optional>
#include <span>
#include <string>
#include <thread>

namespace {

using namespace hypertree;
using clock_type = std::chrono::steady_clock;

double seconds_since(clock_type::time_point t0) { return std::chrono::duration<double>(clock_type::now() - t0).count(); }

struct settings {
    std::string tree_file, forest_file, preset = "A", output = "hypertree.png", save_volume, save_vdb, save_nvdb;
    krs::up_axis up = krs::up_axis::y; // of the .vdb and .nvdb files (--up)
    std::optional<int> resolution;
    storage_type store = storage_type::bit_array;
    int width = 480, height = 480, supersampling = 0, threads = 0; // supersampling 0 = auto
    float density_scale = 4;                                       // k of section 8.1
    std::uint64_t seed = 1;
    int lod = 0;                          // 0: the generated resolution
    std::optional<double> clear_above;    // a height in tree units
    bool noise = true;                    // --noise off: the tree files' noise dropped
    march_options shading;                // ambient, diffuse, specular, shininess, light, normals, shadows
};

// Runs body(0 .. count-1) on `threads` threads, drawing indices from a shared counter, and reports
// progress on stderr as they finish (support/progress.hpp: a bar on a terminal, tenths in a log).
auto parallel_with_progress(int threads, const char* what)
{
    return [threads, what](std::size_t count, const std::function<void(std::size_t)>& body) {
        example::progress shown(stderr, what);
        std::atomic<std::size_t> next{0}, done{0};
        std::vector<std::thread> workers;
        for (int w = 0; w < threads; ++w)
            workers.emplace_back([&] {
                for (std::size_t i; (i = next++) < count;) {
                    body(i);
                    shown.update(++done, count);
                }
            });
        for (auto& t : workers) t.join();
        shown.finish();
    };
}

// What the render needs besides the voxels: the box the camera frames (the tree as generated),
// the line generators' flow when --normals line_flow asks for it, and the render-time noise.
struct render_extras {
    world_box frame{};
    std::function<void(tree_shape&)> adjust_shape;
    sample_displacement displacement; // the definition file's RENDERPERTURB (render-time noise)
    // Who chose the store kind and the resolution, for a store over the budget: "--store" or the
    // forest file's "file:line:col: STORAGETYPE", and "--resolution" or "RESOLUTION".
    std::string store_source = "--store", resolution_word = "RESOLUTION";
};

// A store of the chosen kind over the memory budget, refused with what fits (store_kinds.hpp's
// store_budget_problem) by whoever chose it. Before generation (no voxels yet) only a kind sized
// by its grid (dense) can be refused, and is, so that minutes of generation are not spent first.
void require_store_fits(storage_type kind, const hypervolume& volume, std::span<const stored_voxel> voxels, bool voxels_known,
                        const render_extras& extras)
{
    const std::string problem = store_budget_problem(kind, volume, voxels, voxels_known, memory_budget{}, extras.resolution_word);
    if (!problem.empty()) throw std::runtime_error(extras.store_source + " " + problem);
}

template <voxel_store S>
int render_and_write(const hypervolume& volume, const std::vector<stored_voxel>& voxels, const depth_colors& colors,
                     const settings& o, double creation_seconds, const render_extras& extras)
{
    require_store_fits(storage_type_of<S>, volume, voxels, true, extras);
    // The steps between creation and the light sweep report no progress of their own (a store of
    // a 1600^3 tree takes seconds to build): each is announced with its size, so a long one is
    // seen to be working (stderr, with the progress lines).
    std::fprintf(stderr, "store: %zu voxels in a %s store of %zu bytes\n", voxels.size(), std::string(store_kind_name<S>).c_str(),
                 S::bytes_needed(volume, voxels));
    const auto t0 = clock_type::now();
    const S store = S::build(volume, voxels);
    const double store_seconds = seconds_since(t0);
    if (!o.save_volume.empty()) {
        save(store, o.save_volume); // binary, with a checksum: io/binary.hpp
        std::printf("saved the volume to %s\n", o.save_volume.c_str());
    }
#if KRS_WITH_OPENVDB
    // The library's errors name the path; the option is named here.
    const auto saving = [&o](const char* option, const std::string& path, auto&& save_as) {
        try {
            save_as();
        } catch (const std::exception& e) {
            throw std::runtime_error(std::string(option) + " " + path + ": " + example::message_of(e));
        }
        std::printf("saved the grids to %s, up %s\n", path.c_str(), std::string(krs::up_axis_name(o.up)).c_str());
    };
    if (!o.save_vdb.empty()) saving("--save-vdb", o.save_vdb, [&] { save_vdb(store, o.save_vdb, {}, o.up); });
    if (!o.save_nvdb.empty()) saving("--save-nvdb", o.save_nvdb, [&] { save_nvdb(store, o.save_nvdb, {}, o.up); });
#endif
    if (store.nonempty_count() == 0)
        throw std::runtime_error("nothing is left to render (--clear-above cleared every voxel, or the tree is empty)");
    tree_shape shape = tree_shape::of(volume, voxels);
    if (extras.adjust_shape) extras.adjust_shape(shape);
    march_options mo = o.shading;
    mo.density_scale = o.density_scale;
    mo.displacement = extras.displacement;
    const int threads = example::thread_count(o.threads);
    const resolution grid = volume.grid();
    std::fprintf(stderr, "marcher: bricks of the %d x %d x %d grid\n", grid.x, grid.y, grid.z);
    // The marcher sweeps the lights through the voxels once (light_sweep.hpp), on these threads.
    const volume_marcher marcher(store, shape, colors, mo, parallel_with_progress(threads, "light sweep"));

    const krs::pinhole_camera camera = framing_camera(extras.frame, o.width, o.height);

    render_settings rs;
    rs.supersampling = o.supersampling > 0 ? o.supersampling : std::min(4, supersampling_for(camera, shape, volume));
    rs.parallel_for = parallel_with_progress(threads, "render");
    const auto t1 = clock_type::now();
    const image img = render<krs::packet_f>(marcher, camera, rs);
    const double render_seconds = seconds_since(t1);
    if (!example::write_png("hypertree_render", o.output, img.width, img.height, img.rgb)) return 1;
    std::printf("%zu voxels, %s store %.2f MB built in %.1f ms; created in %.1f ms\n", store.nonempty_count(),
                std::string(name_of(o.store)).c_str(), double(store.memory_bytes()) / 1e6, store_seconds * 1e3, creation_seconds * 1e3);
    std::printf("rendered %dx%d, supersampling %d, %d thread(s), in %.1f ms (%.2f M lookups) -> %s\n", img.width, img.height,
                rs.supersampling, threads, render_seconds * 1e3, double(img.lookups) / 1e6, o.output.c_str());
    return 0;
}

} // namespace

int main(int argc, char** argv)
{
    settings o;
    example::command_line args("hypertree_render",
                               "Generates a hypertree (a definition file, a hyperforest file or a built-in preset), "
                               "renders it with self-shadowing and writes a PNG.");
    CLI::Option* tree = args.text("--tree", o.tree_file, "a hypertree definition file", "FILE");
    CLI::Option* forest = args.text("--forest", o.forest_file, "a hyperforest file", "FILE");
    CLI::Option* preset = args.choice("--preset", o.preset, {"A", "B", "C", "D"}, "a built-in tree (the default)");
    // One source: a second was ignored without a word.
    tree->excludes(forest)->excludes(preset);
    forest->excludes(preset);
    int resolution = 0;
    CLI::Option* resolution_option = args.integer("--resolution", resolution, 1, 1600, "voxels along each axis");
    resolution_option->default_str("of the file, 300 for a preset");
    std::string store = std::string(name_of(o.store));
    std::vector<std::string> store_names(storage_type_names.begin(), storage_type_names.end());
    CLI::Option* store_option = args.choice("--store", store, store_names, "voxel store (default: the forest file's, else bit_array)");
    example::add_image_size(args, o.width, o.height);
    args.integer_or_word("--supersampling", o.supersampling, 1, 16, "auto", 0, "samples per pixel along each axis");
    args.number("--density-scale", o.density_scale, 0, 100, true, "k of section 8.1");
    example::add_threads(args, o.threads);
    example::add_seed(args, o.seed, "the generation");
    example::add_output_file(args, o.output, "FILE.png", "the PNG to write (.png; its directory must exist)");
    args.text("--save-volume", o.save_volume, "also save the voxel store (binary, with a checksum; any name)", "FILE");
    // The extension (what Houdini and Blender look for) is checked with the other outputs after
    // parsing (support/output_path.hpp); here only that this build can write the grids at all.
    const CLI::Validator grid_writer(
        [](std::string&) {
            if (!KRS_WITH_OPENVDB)
                return std::string("this build has no OpenVDB/NanoVDB (install libopenvdb-dev and libnanovdb-dev, "
                                   "then build again)");
            return std::string();
        },
        "", "grid file");
    args.text("--save-vdb", o.save_vdb, "also save the store as OpenVDB grids: density, level, part", "FILE.vdb")
        ->check(grid_writer);
    args.text("--save-nvdb", o.save_nvdb, "also save the store as NanoVDB grids: density, level", "FILE.nvdb")
        ->check(grid_writer);
    const example::up_axis_option up_option(args);
    args.integer("--lod", o.lod, 1, 1600, "reduce the tree to N voxels along each axis before rendering (level of detail, section 9)")
        ->default_str("off");
    double clear_above = 0;
    CLI::Option* clear_option = args.number("--clear-above", clear_above, -1e6, 1e6, false,
                                            "clear every voxel whose centre is at or above this height, tree units (section 7)");
    clear_option->default_str("off");
    args.number("--ambient", o.shading.ambient, 0, 10, false, "ambient weight (section 8.3)");
    args.number("--diffuse", o.shading.diffuse, 0, 10, false, "Lambert weight");
    args.number("--specular", o.shading.specular, 0, 10, false, "Blinn-Phong weight (0: diffuse only)");
    args.number("--shininess", o.shading.shininess, 0, 1000, false, "Blinn-Phong exponent");
    float elevation = 0, azimuth = 0;
    CLI::Option* elevation_option = args.number("--light-elevation", elevation, -90, 90, false, "the light's height above the horizon, degrees");
    CLI::Option* azimuth_option = args.number("--light-azimuth", azimuth, -360, 360, false, "the light's direction about the y axis, degrees from +x toward +z");
    // The default light, directional_light{} (march_options.hpp): (0.4, 0.8, 0.45) made unit.
    elevation_option->default_str("53");
    azimuth_option->default_str("48.4");
    std::string normals = "structure_flow", shadows = "on", noise = "on";
    args.choice("--normals", normals, {"structure_flow", "part_boxes", "line_flow"}, "the shading normal (section 8.3)");
    args.choice("--shadows", shadows, {"on", "off"}, "self-shadowing");
    args.choice("--noise", noise, {"on", "off"}, "the tree files' noise (PERTURB, VOXELPERTURB, RENDERPERTURB)");
    args.parse(argc, argv);
    o.noise = noise == "on";
    if (clear_option->count() > 0) o.clear_above = clear_above;
    o.shading.normals_by = normals == "part_boxes" ? normal_method::part_boxes : normals == "line_flow" ? normal_method::line_flow : normal_method::structure_flow;
    o.shading.shadows = shadows == "on";
    if (elevation_option->count() > 0 || azimuth_option->count() > 0) {
        // The default light's angles, for the one of the two not given.
        const krs::vec3f d = krs::normalize(o.shading.lights.front().direction);
        const float pi = 3.14159265f;
        const float el = elevation_option->count() > 0 ? elevation * pi / 180 : std::asin(d.y);
        const float az = azimuth_option->count() > 0 ? azimuth * pi / 180 : std::atan2(d.z, d.x);
        o.shading.lights.front().direction = {std::cos(el) * std::cos(az), std::sin(el), std::cos(el) * std::sin(az)};
    }
    if (normals == "line_flow" && !o.forest_file.empty())
        args.fail("--normals line_flow needs one tree with a line generator (--tree or --preset), not a --forest");
    // Refused before the tree is generated, which can take minutes (support/output_path.hpp).
    example::require_output_file(args, "--output", o.output, {".png"});
    if (!o.save_vdb.empty()) example::require_output_file(args, "--save-vdb", o.save_vdb, {".vdb"});
    if (!o.save_nvdb.empty()) example::require_output_file(args, "--save-nvdb", o.save_nvdb, {".nvdb"});
    // The PNG and --save-volume are of the tree in its own frame: --up turns only the grid files.
    if (up_option.given() && o.save_vdb.empty() && o.save_nvdb.empty()) args.fail("--up: only with --save-vdb or --save-nvdb");
    o.up = up_option.axis();
    // The binary format has no extension of its own: any name whose directory takes a file.
    if (!o.save_volume.empty())
        example::require_output_file(args, "--save-volume", o.save_volume, {});
    if (resolution_option->count() > 0) o.resolution = resolution;
    const bool store_given = store_option->count() > 0;
    o.store = storage_type(std::find(store_names.begin(), store_names.end(), store) - store_names.begin());

    // The tree file read, so that a refusal of one of its settings while building or rendering
    // is reported at its line (definition_refusals.hpp).
    std::optional<parsed_tree> tree_file;
    try {
        build_options options;
        options.generation.parallel_for = parallel_with_progress(example::thread_count(o.threads), "create");
        hypervolume volume;
        std::vector<stored_voxel> voxels;
        depth_colors colors;
        render_extras extras;
        const auto t0 = clock_type::now();
        if (!o.forest_file.empty()) {
            loaded_forest forest = load_forest(o.forest_file);
            if (!o.noise)
                for (parsed_tree& t : forest.trees) t.ifs.perturb = {}, t.voxel_perturb.reset();
            if (o.resolution) forest.listing.grid = resolution::cube(*o.resolution);
            if (!store_given) {
                o.store = forest.listing.storage;
                const source_position at = forest.listing.storage_at;
                extras.store_source = forest.listing.file_name + ":" + std::to_string(at.line) + ":" + std::to_string(at.column) + ": STORAGETYPE";
            }
            if (o.resolution) extras.resolution_word = "--resolution";
            require_store_fits(o.store, forest.volume(), {}, false, extras);
            generated_forest built = build_forest(forest, o.seed, options);
            volume = built.volume, voxels = std::move(built.voxels);
            colors = forest.trees.front().colors();
        } else {
            parsed_tree tree;
            if (!o.tree_file.empty()) {
                tree = load_definition(o.tree_file);
            } else {
                const int r = o.resolution.value_or(300);
                tree.ifs = o.preset == "A" ? presets::tree_a(r) : o.preset == "B" ? presets::tree_b(r) : o.preset == "C" ? presets::tree_c(r) : presets::tree_d(r);
            }
            if (o.resolution) tree.ifs.volume = hypervolume(tree.ifs.volume.origin(), tree.ifs.volume.extent(), resolution::cube(*o.resolution));
            if (!o.noise) tree.ifs.perturb = {}, tree.voxel_perturb.reset(), tree.render_perturb.reset();
            if (o.resolution || o.tree_file.empty()) extras.resolution_word = "--resolution";
            if (!o.tree_file.empty()) tree_file = tree;
            require_store_fits(o.store, tree.ifs.volume, {}, false, extras);
            const generated_hits hits = generate(tree.ifs, o.seed, options.generation);
            // A file's tree that fills nothing is refused at the line to change (PERTURB's, or the box's).
            if (tree_file && hits.hits.empty()) throw empty_tree_refusal(tree, o.seed);
            const std::vector<voxel_entry> entries = compact(hits.hits, options.generation.parallel_for, hits.volume.voxel_count());
            const density_classes classes(entries, tree.density_class_count.value_or(options.density_class_count));
            voxels = classify(entries, classes, tree.ifs.branch_depth);
            volume = tree.ifs.volume;
            // VOXELPERTURB: the post-process noise, shifting the built tree's voxels (perturbation.hpp).
            // Through a partitioned_store, which keeps the part bytes the shading's flows, fitted
            // spheres and part boxes are made of (an index_list_store would make every voxel part 0).
            if (tree.voxel_perturb) voxels = perturb_voxels(partitioned_store::build(volume, voxels), *tree.voxel_perturb);
            if (tree.render_perturb) extras.displacement = *tree.render_perturb;
            colors = tree.colors();
            if (o.shading.normals_by == normal_method::line_flow) {
                if (tree.ifs.generator.is_point())
                    throw std::runtime_error("--normals line_flow: the tree's generator is a point; it needs a line (LINEINIT)");
                // The same draw of the random values as the generation's (one seed).
                extras.adjust_shape = [drawn = std::make_shared<drawn_ifs<runtime_pipeline>>(tree.ifs, o.seed)](tree_shape& shape) {
                    shape.set_line_flow_of(*drawn);
                };
            }
        }
        if (voxels.empty()) throw std::runtime_error("the tree generated no voxels");
        extras.frame = tree_shape::of(volume, voxels).box;
        if (o.clear_above) {
            // Section 7's clear, over the half-space y >= Y (its normal points up).
            const partitioned_store whole = partitioned_store::build(volume, voxels); // keeps the part bytes
            voxels = clear(whole, half_space_region({0, *o.clear_above, 0}, {0, 1, 0}));
        }
        if (o.lod > 0) {
            const hypertree::resolution n = volume.grid(), target = hypertree::resolution::cube(o.lod);
            if (target.x > n.x || target.y > n.y || target.z > n.z)
                throw std::runtime_error("--lod " + std::to_string(o.lod) + ": must not exceed the tree's resolution (" + std::to_string(n.x) +
                                         " x " + std::to_string(n.y) + " x " + std::to_string(n.z) + ")");
            const partitioned_store whole = partitioned_store::build(volume, voxels);
            voxels = reduce(whole, target);
            volume = reduced_volume(volume, target);
        }
        const double creation = seconds_since(t0);
        return with_store(o.store, [&]<class S>() { return render_and_write<S>(volume, voxels, colors, o, creation, extras); });
    } catch (const krs::invalid_parameter& e) {
        // A limit met while building from a tree file, at the line of the setting that set it.
        const std::optional<definition_error> located = tree_file ? at_its_line(*tree_file, e) : std::nullopt;
        std::fprintf(stderr, "%s: %s\n", args.program().c_str(), located ? located->what() : e.message().c_str());
        return 1;
    } catch (const std::exception& e) {
        std::fprintf(stderr, "%s: %s\n", args.program().c_str(), example::message_of(e).c_str());
        return 1;
    }
    return 1;
}

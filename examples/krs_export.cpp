// krs_export: an example scene as a triangle mesh, for Blender, Houdini, game engines and any
// rasterizer (krs/mesh/extract.hpp; the writers krs/mesh/write.hpp and krs/mesh/gltf.hpp).
//
//   krs_export --scene NAME --output FILE.ply|FILE.obj|FILE.glb|FILE.gltf [--resolution N]
//              [--memory-budget MB] [--projection-steps K] [--uv] [--kernel-colors] [--up y|z]
//   krs_export --scene NAME --instances --output FILE.gltf|FILE.glb [--instance-levels K]
//              [--max-instances M] [--gpu-instancing] [--resolution N] ...
//
// (--mesh FILE and --instances FILE, the older spellings of --output FILE and of --instances
// --output FILE, are still taken.)
//
// NAME is one of the scenes of krs/scenes/example_scenes.hpp (--list-scenes prints them; --seed S
// builds the seeded ones at S). The mesh covers the scene's bounding box, or for a scene without
// one (a ground plane) the box its tests sample, with N cells along the box's longest side (default
// 128). Progress goes to stderr; the summary (triangles, vertices, worst vertex distance to the
// zero set in cells, time) to stdout. .glb and .gltf need a build with tinygltf (krs::mesh_gltf).
// A mesh over the memory budget (default 1024 MB) is refused before the file is written (one a
// coarse pass estimates over it, before the full-resolution meshing starts), and a failed write
// leaves no file behind. --uv and --kernel-colors add per-vertex uv (the kernel's
// own, at the vertex's kernel-space point) and a colour per kernel, for sequence scenes
// (krs/mesh/extract.hpp's mesh_options::attributes). A refusal found while meshing names the
// option typed (--memory-budget, --resolution, ...), not the library's field.
//
// Colours are linear RGB, written as each format's readers take them: glTF's COLOR_0 linear
// floats, PLY's bytes and OBJ's "r g b" sRGB-encoded (krs/mesh/write.hpp), so Blender shows the
// same colour from all three. --up z writes the scene's up (+y) along the file's +z, for z-up
// tools that read the coordinates as they are (Blender's PLY import); glTF stays upright in every
// loader (a root node turns it back, krs/mesh/gltf.hpp), and Blender's OBJ import converts a y-up
// OBJ itself.
//
// --instances writes a scene that is a sequence (its refusal of any other names them) as instanced
// glTF (krs/mesh/instances.hpp): every kernel of the top K mirror levels (default 4) meshed once
// and placed by its instance transforms, the levels below meshed whole and placed 2^K times; more
// than M instances (default 1048576) is refused. Each instance is a node referencing its shared
// mesh (core glTF, which every loader places); --gpu-instancing writes EXT_mesh_gpu_instancing
// instead (one node per mesh), listed as required, so a loader without it refuses the file
// rather than showing each mesh once at the origin. The count printed is the file's: parts whose
// kernel meshes to nothing at this resolution are named and not counted. Unbounded kernels (the
// tree's ground, the rock's and terrain's facet planes) are meshed within the scene's box (the
// sequence's own, or the box its tests sample), so every sequence scene exports.

#include "krs/mesh/extract.hpp"
#include "krs/mesh/write.hpp"
#if defined(KRS_WITH_GLTF)
#include "krs/mesh/gltf.hpp"
#endif
#include "krs/mesh/instances.hpp"

#include "support/command_line.hpp"
#include "support/common_options.hpp"
#include "support/error_message.hpp"
#include "support/scene_choice.hpp"
#include "support/output_path.hpp"
#include "support/progress.hpp"
#include "support/up_axis_option.hpp"

#include <algorithm>
#include <cctype>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <cstring>
#include <optional>
#include <string>
#include <utility>

namespace {

// A library refusal in the words of the command line: every mesh_options or instance_options field
// this program sets from an option is named as that option (a user who typed --memory-budget 64
// should not read about mesh_options.memory_budget), and the budget in the MB the user gave. Other
// messages pass through unchanged.
std::string in_option_words(const std::exception& e, long long budget_mb, std::size_t budget_bytes)
{
    std::string text = example::message_of(e);
    if (!dynamic_cast<const krs::invalid_parameter*>(&e)) return text;
    static const std::pair<const char*, const char*> names[] = {
        {"instance_options.mesh.memory_budget", "--memory-budget"},
        {"instance_options.mesh.resolution", "--resolution"},
        {"instance_options.mesh.projection_steps", "--projection-steps"},
        {"instance_options.mesh.attributes", "--uv / --kernel-colors"},
        {"mesh_options.memory_budget", "--memory-budget"},
        {"mesh_options.resolution", "--resolution"},
        {"mesh_options.projection_steps", "--projection-steps"},
        {"mesh_options.attributes", "--uv / --kernel-colors"},
        {"instance_options.instance_levels", "--instance-levels"},
        {"instance_options.max_instances", "--max-instances"},
        {"at instance_levels", "at --instance-levels"},
    };
    for (const auto& [from, to] : names)
        for (std::size_t at = text.find(from); at != std::string::npos; at = text.find(from, at + std::strlen(to)))
            text.replace(at, std::strlen(from), to);
    const std::string bytes = "(got " + std::to_string(budget_bytes) + ")";
    if (text.find("--memory-budget") != std::string::npos) {
        const auto at = text.rfind(bytes);
        if (at != std::string::npos) text.replace(at, bytes.size(), "(got " + std::to_string(budget_mb) + " MB)");
    }
    return text;
}

std::string lower_extension(const std::string& path)
{
    const auto dot = path.find_last_of('.'), slash = path.find_last_of('/');
    if (dot == std::string::npos || (slash != std::string::npos && slash > dot)) return "";
    std::string e = path.substr(dot);
    std::transform(e.begin(), e.end(), e.begin(), [](unsigned char c) { return char(std::tolower(c)); });
    return e;
}

// The scenes that are sequences, for the --instances refusal: "tree, forest, ..." from the list.
std::string sequence_scene_names()
{
    std::string names;
    krs::scenes::for_each_scene_entry([&]<class E>() {
        if constexpr (krs::glsl::kernel_shaded<krs::scenes::field_of<E>>)
            names += (names.empty() ? "" : ", ") + std::string(E::name);
    });
    return names;
}

} // namespace

int main(int argc, char** argv)
{
    namespace ex = krs::scenes;
    std::string scene = "tree", mesh;
    int resolution = 128, steps = 4;
    long long budget_mb = 1024;
    example::command_line args("krs_export", "Writes an example scene as a triangle mesh (PLY, OBJ, GLB or glTF).");
    const example::scene_choice scenes(args, scene, example::all_scene_names(), "the scene");
    example::add_output_file(args, mesh, "FILE", "the file to write: .ply (binary), .obj, .glb or .gltf", "--mesh");
    args.integer("--resolution", resolution, 1, krs::max_mesh_resolution, "cells along the scene box's longest side (default 128)");
    args.integer("--projection-steps", steps, 0, 64, "Newton steps moving each vertex onto the surface (default 4)");
    args.integer("--memory-budget", budget_mb, 1, 1 << 20, "the most the mesh may take while it is built, in MB (default 1024)");
    std::string instances;
    int instance_levels = 4;
    long long max_instances = 1 << 20;
    // A kind of output, not a second output option: --instances FILE (the file given here) is its
    // older spelling, from before every program's file was --output.
    CLI::Option* instances_option =
        args.text("--instances", instances,
                  "write a sequence scene as instanced glTF (a node per instance) to --output FILE.gltf or "
                  ".glb (--instances FILE: its older spelling)",
                  "[FILE]")
            ->expected(0, 1);
    args.integer("--instance-levels", instance_levels, 0, 64, "mirror levels expanded into instances (default 4)");
    args.integer("--max-instances", max_instances, 1, 1ll << 40, "the most instances allowed (default 1048576)");
    bool uv = false, kernel_colors = false;
    args.app().add_flag("--uv", uv,
                        "per-vertex uv of each vertex's kernel (sequence scenes; a mesh, not --instances)");
    args.app().add_flag("--kernel-colors", kernel_colors,
                        "per-vertex colour by kernel (sequence scenes; a mesh, not --instances); linear RGB, "
                        "written as glTF linear floats, PLY bytes and OBJ floats sRGB-encoded");
    bool gpu_instancing = false;
    args.app().add_flag("--gpu-instancing", gpu_instancing,
                        "--instances with EXT_mesh_gpu_instancing (required by the file) instead of a node per instance");
    const example::up_axis_option up_option(args);
    args.parse(argc, argv);
    // From here on `mesh` is the file of a mesh and `instances` the file of instances, one empty.
    const bool instanced = instances_option->count() > 0;
    if (instanced && !instances.empty() && !mesh.empty())
        args.fail("--instances FILE, --output: one file; give --instances --output FILE.gltf");
    if (instanced && instances.empty()) std::swap(instances, mesh);
    const krs::up_axis up = up_option.axis();
    const std::string& up_name = up_option.name();
    if (gpu_instancing && !instanced) args.fail("--gpu-instancing: only with --instances");
    const std::size_t budget_bytes = std::size_t(budget_mb) << 20;
    const unsigned attributes = (uv ? krs::mesh_attribute::uv : 0u) | (kernel_colors ? krs::mesh_attribute::kernel_color : 0u);
    if (attributes != 0 && instanced) args.fail("--uv, --kernel-colors: only for a mesh, not with --instances");
    if (mesh.empty() && instances.empty())
        args.fail(std::string("--output: give the file to write (") +
                  (instanced ? "FILE.gltf or FILE.glb" : "FILE.ply, FILE.obj, FILE.glb or FILE.gltf") + ")");
    // A format krs_export writes, a directory that takes the file, not a directory: checked as
    // every program checks its outputs (support/output_path.hpp).
    if (!mesh.empty()) example::require_output_file(args, "--output", mesh, {".ply", ".obj", ".glb", ".gltf"});
    if (!instances.empty())
        example::require_output_file(args, "--output (--instances)", instances, {".gltf", ".glb"});
    const std::string ext = lower_extension(mesh);
    const std::string iext = lower_extension(instances);
#if !defined(KRS_WITH_GLTF)
    if (!instances.empty()) args.fail("--instances: this build has no glTF writer (it needs tinygltf, libtinygltf-dev)");
#endif
#if !defined(KRS_WITH_GLTF)
    if (ext == ".glb" || ext == ".gltf")
        args.fail("--output: '" + mesh + "': this build has no glTF writer (it needs tinygltf, libtinygltf-dev)");
#endif

    int status = 1;
    ex::with_scene(scene, scenes.seed(), [&](const auto& s) {
        if (!instances.empty()) {
#if defined(KRS_WITH_GLTF)
            krs::instance_options io;
            io.instance_levels = std::size_t(instance_levels);
            io.max_instances = std::size_t(max_instances);
            io.mesh.resolution = resolution;
            io.mesh.projection_steps = steps;
            io.mesh.memory_budget = budget_bytes;
            if (!krs::field_box(s.field).is_bounded()) {
                const krs::vec3d c(s.sample_center), h(s.sample_half);
                io.mesh.box = krs::box_around(c - h, c + h); // sets the cell size only
            }
            if constexpr (requires { krs::instance_meshes(s.field, io); }) {
                try {
                    const auto start = std::chrono::steady_clock::now();
                    const krs::instanced_scene is = krs::instance_meshes(s.field, io);
                    krs::gltf_instance_options go;
                    go.gpu_instancing = gpu_instancing;
                    go.up = up;
                    krs::save_gltf_instances(is, instances, iext == ".glb", go);
                    std::size_t triangles = 0;
                    std::string empty;
                    for (const auto& p : is.parts) {
                        triangles += p.mesh.triangle_count() + p.mirrored.triangle_count();
                        if (p.mesh.triangles.empty())
                            empty += (empty.empty() ? "" : ", ") + p.name + " (" + std::to_string(p.direct.size() + p.reflected.size()) + ")";
                    }
                    if (!empty.empty())
                        std::printf("krs_export: %s: at --resolution %d these parts mesh to nothing and are not written: %s\n",
                                    scene.c_str(), resolution, empty.c_str());
                    std::printf("krs_export: %s: %zu parts, %zu instances, %zu stored triangles, up %s, %.2f s -> %s\n", scene.c_str(),
                                is.placed_part_count(), is.placed_instance_count(), triangles, up_name.c_str(),
                                std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count(), instances.c_str());
                } catch (const std::exception& e) {
                    std::fprintf(stderr, "krs_export: %s\n", in_option_words(e, budget_mb, budget_bytes).c_str());
                    return;
                }
            } else {
                std::fprintf(stderr, "krs_export: --instances: the scene '%s' is not a sequence (%s are)\n", scene.c_str(),
                             sequence_scene_names().c_str());
                return;
            }
#endif
            if (mesh.empty()) {
                status = 0;
                return;
            }
        }
        krs::mesh_options o;
        o.resolution = resolution;
        o.projection_steps = steps;
        o.memory_budget = budget_bytes;
        o.attributes = attributes;
        if (!krs::field_box(s.field).is_bounded()) {
            const krs::vec3d c(s.sample_center), h(s.sample_half);
            o.box = krs::box_around(c - h, c + h);
        }
        // Alive from the first second: the grid before any pass, the estimate before the full
        // one, and a bar per pass (the library reports each pass's start: mesh_report).
        std::optional<example::progress> bar;
        std::optional<krs::mesh_stage> stage;
        o.progress = [&](const krs::mesh_report& r) {
            if (stage != r.stage) {
                if (bar) bar->finish();
                const std::size_t* n = r.cells_per_axis;
                if (!stage) {
                    const std::string first = r.stage == krs::mesh_stage::estimate
                                                  ? ", its mesh's size estimated first from a pass at resolution " +
                                                        std::to_string(r.coarse_resolution)
                                                  : std::string();
                    std::fprintf(stderr, "krs_export: %s: a grid of %zu x %zu x %zu cells (%.3g in all)%s\n", scene.c_str(), n[0],
                                 n[1], n[2], double(n[0]) * double(n[1]) * double(n[2]), first.c_str());
                }
                if (r.stage == krs::mesh_stage::cells && r.estimated_bytes > 0)
                    std::fprintf(stderr, "krs_export: %s: estimated mesh %.0f MB, within the --memory-budget of %lld MB\n", scene.c_str(),
                                 r.estimated_bytes / double(1 << 20), budget_mb);
                stage = r.stage;
                bar.emplace(stderr, r.stage == krs::mesh_stage::estimate ? "estimate" : r.stage == krs::mesh_stage::cells ? "mesh" : "vertices");
            }
            bar->update(std::size_t(r.done * 1000), 1000);
        };
        try {
            const auto start = std::chrono::steady_clock::now();
            krs::mesh_stats stats;
            const krs::triangle_mesh m = krs::extract_mesh(s.field, o, &stats);
            if (bar) bar->finish();
            const double seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
            if (m.triangles.empty()) {
                // Whether a finer grid can help: only where the field went below a cell's reach.
                const double lowest = stats.lowest_distance / stats.cell_size;
                std::fprintf(stderr, "krs_export: the scene's surface gave no triangle at resolution %d: %s (lowest %.3g cells)\n",
                             resolution,
                             lowest < 0 ? "the field is negative in the box but changes sign on no grid edge"
                             : lowest > 0.5 * std::sqrt(3.0)
                                 ? "the field is positive everywhere in the box: no resolution can mesh it"
                                 : "the field was never negative where sampled: raise --resolution if the geometry is thinner "
                                   "than a cell (a field that is 0 inside cannot be meshed)",
                             lowest);
                return;
            }
            double worst = 0;
            for (const krs::vec3f& p : m.positions) worst = std::max(worst, std::abs(s.field.distance(krs::vec3d(p))));
            if (ext == ".ply") krs::save_ply(m, mesh, up);
            else if (ext == ".obj") krs::save_obj(m, mesh, up);
#if defined(KRS_WITH_GLTF)
            else if (ext == ".glb") krs::save_glb(m, mesh, up);
            else krs::save_gltf(m, mesh, up);
#endif
            std::printf("krs_export: %s: %zu triangles, %zu vertices, cell %.4g, worst vertex |d| %.3g cells, %.2f s "
                        "(%.0f triangles/s) -> %s\n",
                        scene.c_str(), m.triangle_count(), m.vertex_count(), stats.cell_size, worst / stats.cell_size, seconds,
                        double(m.triangle_count()) / seconds, mesh.c_str());
            status = 0;
        } catch (const std::exception& e) {
            if (bar) bar->finish();
            std::fprintf(stderr, "krs_export: %s\n", in_option_words(e, budget_mb, budget_bytes).c_str());
        }
    });
    return status;
}

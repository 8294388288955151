// bench_openvdb_peer: the hypertree stores next to what a user without this library would pick, an
// OpenVDB grid holding the same voxels (issue 9, part 3). Built only with -DKRS_BENCH_OPENVDB=ON.
//
//     bench_openvdb_peer [--csv FILE] [--threads T] [--size N] [--resolution R] [--trees ABCD]
//     (the CSV goes next to the executable, as <executable>.csv, unless --csv names one)
//                        [--queries Q] [--step S] [--shade per-sample|per-voxel] [--march in-step|each-sample]
//
// For each tree (hypertree/presets.hpp, resolution R, default 300) the classified voxel list is
// built once and copied into every store kind and into two OpenVDB 10 grids: a FloatGrid of
// density / 255 (what OpenVDB's volume tools expect) and a grid of bytes (Tree4<uint8_t, 5, 4, 3>,
// the densest value type OpenVDB trees take). Note the stores keep the density *and* the depth
// level (2 bytes per voxel); the grids keep only the density, which favors them.
//
// Memory: the store's memory_bytes() against Grid::memUsage() (the tree's nodes and buffers), plus
// what each raymarcher adds on top to skip empty space: the marcher's brick copy of the store
// (volume_marcher::memory_bytes(): the voxels regrouped in 4^3 bricks with their directory,
// voxel_bricks.hpp, which the library's rays read instead of the store) and the bool tree that
// OpenVDB's VolumeRayIntersector copies from the grid's topology.
//
// Access: Q random voxels (default 2^20), once drawn among the non-empty voxels and once uniformly
// over the whole grid; ns per lookup on one thread, best of 3: store.at(index) against a
// ValueAccessor's getValue(Coord) (indices and coordinates precomputed, so neither side pays for
// the conversion). Random order defeats the accessor's node cache on purpose: a raymarcher's
// coherent access is measured by the render below.
//
// Render: one view of the tree (N x N pixels, default 300, one ray per pixel center), on T threads
// (default 2), without shadows or lighting, so both sides compute the same quantity: the pixel is
// sum_k T_k alpha_k (white voxels) + T_final x background, with alpha = 1 - (1 - mu)^(k ds / side)
// (k = 1), ds = S x the smallest voxel side (default S = 1), samples at t_0 + (j + 1/2) ds from
// the entry into the box of the non-empty voxels, front to back, stopping below transmittance
// 1/256 (the library's defaults). The library side is volume_marcher + render (scalar and packet
// marchers), shading per sample by default: with no light there is nothing for the per-voxel
// shading memo to save but its table lookup per sample (one quiet run on tree A: 64 ms per voxel,
// 43 ms per sample; --shade per-voxel measures it). With no light and no ambient falloff the lit
// color depends on the level alone (voxel_shading::flat), so the packets march in step and gather
// it by level (march_context::shade_each_sample); `--march each-sample` takes the per-lane march
// that shades each sample, the one before (same pixels), for side-by-side runs. The OpenVDB side marches the spans that VolumeRayIntersector reports (runs of active
// leaf nodes, found by its hierarchical DDA) and looks each sample's voxel up with a
// ValueAccessor; it keeps the same sample positions, so the two images should differ only where
// float rounding moves a sample across a voxel face. The presets' voxels are not cubic (a fitted
// box, R cells per axis) and the intersector refuses non-uniform voxels, so the grid keeps the
// identity transform and the bench maps each world ray into index space itself (setIndexRay).
// Timings are the best of 4 renders and include only the rendering (the marcher's brick copy
// and the intersector's bool tree are built once, timed apart as "setup").
//
// Lighting on (rows `lit_per_sample`, `lit_dense` and `openvdb_lit`): the same view and opacity
// law, each sample lit by ambient + diffuse x its transmittance toward one light (march_options'
// default light and weights, no ambient falloff, no normals: the shape is given no structure
// flow). OpenVDB marches a shadow ray per sample as its VolumeRender does (a second intersector,
// the same step, samples from one step out, stopping below 1/256). The library uses the light
// sweep (light_sweep.hpp, its one-time cost in its setup), shading per sample as OpenVDB does
// (`lit_per_sample`, the image the others' RMSE is against) and per voxel, its default
// (`lit_dense`, whose time the ratio takes, per frame and with setup).

#include "support/text.hpp"
#include "support/timing.hpp"
#include "hypertree/hypertree.hpp"
#include "hypertree/presets.hpp"

#include <openvdb/openvdb.h>
#include <openvdb/tools/RayIntersector.h>

#include <algorithm>
#include <array>
#include <atomic>
#include <chrono>
#include <cmath>
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

using namespace hypertree;

using byte_tree = openvdb::tree::Tree4<std::uint8_t, 5, 4, 3>::Type;
using byte_grid = openvdb::Grid<byte_tree>;

struct picture {
    int size = 0;
    std::vector<float> rgb;
};

struct difference {
    double rmse = 0, max = 0, share = 0; // share: pixels whose largest channel error exceeds 2/255
};

difference compare(const std::vector<float>& a, const std::vector<float>& b)
{
    difference d;
    double sum = 0;
    std::size_t differing = 0;
    for (std::size_t p = 0; p + 2 < a.size(); p += 3) {
        double worst = 0;
        for (std::size_t c = 0; c < 3; ++c) {
            const double e = double(std::clamp(a[p + c], 0.0f, 1.0f)) - double(std::clamp(b[p + c], 0.0f, 1.0f));
            sum += e * e;
            worst = std::max(worst, std::abs(e));
        }
        d.max = std::max(d.max, worst);
        differing += worst > 2.0 / 255.0;
    }
    d.rmse = std::sqrt(sum / double(std::max<std::size_t>(a.size(), 1)));
    d.share = double(differing) / double(std::max<std::size_t>(a.size() / 3, 1));
    return d;
}

// The OpenVDB side of the render: front-to-back accumulation over the intersector's spans.
class openvdb_marcher {
public:
    // Lit when `light` (unit, world) is given: ambient + diffuse x the shadow ray's transmittance.
    openvdb_marcher(const openvdb::FloatGrid& grid, const hypervolume& volume, float step_factor, rgb background,
                    std::optional<krs::vec3f> light = std::nullopt, float ambient = 0, float diffuse = 0)
        : grid_(grid), intersector_(grid), background_(background), lit_(light.has_value()), ambient_(ambient), diffuse_(diffuse)
    {
        if (light) light_ = openvdb::Vec3d(double(light->x) * volume.cells_per_unit().x, double(light->y) * volume.cells_per_unit().y,
                                           double(light->z) * volume.cells_per_unit().z);
        origin_ = volume.origin();
        cells_per_unit_ = volume.cells_per_unit();
        step_ = step_factor * volume.smallest_voxel_side();
        for (int d = 0; d < 256; ++d)
            alpha_[std::size_t(d)] = d == 255 ? 1.0f : float(1.0 - std::pow(1.0 - d / 255.0, double(step_factor)));
        const openvdb::CoordBBox active = grid.evalActiveVoxelBoundingBox();
        lo_ = active.min().asVec3d();
        hi_ = active.max().asVec3d() + openvdb::Vec3d(1.0); // voxel ijk is the cell [ijk, ijk + 1)
    }

    std::size_t accelerator_bytes() const { return std::size_t(intersector_.tree().memUsage()); }

    picture render(const krs::pinhole_camera& camera, unsigned threads) const
    {
        picture out;
        out.size = camera.width();
        out.rgb.assign(std::size_t(camera.width()) * std::size_t(camera.height()) * 3, 0.0f);
        bench::run_parallel(threads, std::size_t(camera.height()), [&](std::size_t row) {
            // The shallow copy shares the bool tree and brings its own node cache; so does the
            // accessor: one of each per row keeps threads apart.
            openvdb::tools::VolumeRayIntersector<openvdb::FloatGrid> intersector(intersector_), shadows(intersector_);
            openvdb::FloatGrid::ConstAccessor density = grid_.getConstAccessor();
            for (int x = 0; x < camera.width(); ++x) {
                const krs::ray<float> r = camera.primary_ray(float(x) + 0.5f, float(row) + 0.5f);
                float* pixel = &out.rgb[(row * std::size_t(camera.width()) + std::size_t(x)) * 3];
                const float transmittance = march(r, intersector, shadows, density, pixel);
                pixel[0] += transmittance * background_.r;
                pixel[1] += transmittance * background_.g;
                pixel[2] += transmittance * background_.b;
            }
        });
        return out;
    }

private:
    using index_ray = openvdb::math::Ray<double>;

    // Accumulates white voxels into rgb (premultiplied); returns the remaining transmittance.
    // The transmittance from index point p toward the light, samples at t = j ds from j = 1 to the
    // box's exit (the library's shadow ray), through the spans the intersector reports.
    float shadow(const openvdb::Vec3d& p, openvdb::tools::VolumeRayIntersector<openvdb::FloatGrid>& intersector,
                 openvdb::FloatGrid::ConstAccessor& density) const
    {
        double leave = 1e300;
        for (int a = 0; a < 3; ++a) {
            const double inv = 1.0 / (std::abs(light_[a]) < 1e-30 ? 1e-30 : light_[a]);
            leave = std::min(leave, std::max((lo_[a] - p[a]) * inv, (hi_[a] - p[a]) * inv));
        }
        if (!(leave > 0) || !intersector.setIndexRay(index_ray(p, light_, 0.0, leave))) return 1.0f;
        float transmittance = 1.0f;
        double next = 1, t0, t1;
        while (intersector.march(t0, t1)) {
            const double to = std::min(t1, leave);
            for (double j = std::max(next, std::ceil(t0 / step_));; ++j) {
                const double t = j * step_;
                if (!(t < to)) {
                    next = j;
                    break;
                }
                const float mu = density.getValue(openvdb::Coord::floor(p + light_ * t));
                if (mu <= 0.0f) continue;
                transmittance *= 1.0f - alpha_[std::size_t(std::lround(mu * 255.0f))];
                if (transmittance < min_transmittance) return transmittance;
            }
        }
        return transmittance;
    }

    float march(const krs::ray<float>& r, openvdb::tools::VolumeRayIntersector<openvdb::FloatGrid>& intersector,
                openvdb::tools::VolumeRayIntersector<openvdb::FloatGrid>& shadows, openvdb::FloatGrid::ConstAccessor& density,
                float* rgb_out) const
    {
        // Index space keeps the world parameter t: origin and direction are both scaled per axis.
        const openvdb::Vec3d o((double(r.origin.x) - origin_.x) * cells_per_unit_.x, (double(r.origin.y) - origin_.y) * cells_per_unit_.y,
                               (double(r.origin.z) - origin_.z) * cells_per_unit_.z);
        const openvdb::Vec3d d(double(r.direction.x) * cells_per_unit_.x, double(r.direction.y) * cells_per_unit_.y,
                               double(r.direction.z) * cells_per_unit_.z);
        double enter = 0, leave = 1e300;
        for (int a = 0; a < 3; ++a) {
            const double inv = 1.0 / (std::abs(d[a]) < 1e-30 ? 1e-30 : d[a]);
            const double ta = (lo_[a] - o[a]) * inv, tb = (hi_[a] - o[a]) * inv;
            enter = std::max(enter, std::min(ta, tb));
            leave = std::min(leave, std::max(ta, tb));
        }
        if (!(enter < leave)) return 1.0f;
        if (!intersector.setIndexRay(index_ray(o, d, 0.0, leave))) return 1.0f;
        float transmittance = 1.0f, sum = 0.0f;
        double next = 0; // samples before this index are behind the spans already marched
        double t0, t1;
        while (intersector.march(t0, t1)) {
            const double from = std::max(t0, enter), to = std::min(t1, leave);
            for (double j = std::max(next, std::ceil((from - enter) / step_ - 0.5));; ++j) {
                const double t = enter + (j + 0.5) * step_;
                if (!(t < to)) {
                    next = j;
                    break;
                }
                const float mu = density.getValue(openvdb::Coord::floor(o + d * t));
                if (mu <= 0.0f) continue;
                const float alpha = alpha_[std::size_t(std::lround(mu * 255.0f))];
                const float light = lit_ ? ambient_ + diffuse_ * shadow(o + d * t, shadows, density) : 1.0f;
                sum += transmittance * alpha * light;
                transmittance *= 1.0f - alpha;
                if (transmittance < min_transmittance) {
                    rgb_out[0] = rgb_out[1] = rgb_out[2] = sum;
                    return transmittance;
                }
            }
        }
        rgb_out[0] = rgb_out[1] = rgb_out[2] = sum;
        return transmittance;
    }

    static constexpr float min_transmittance = 1.0f / 256.0f;
    const openvdb::FloatGrid& grid_;
    openvdb::tools::VolumeRayIntersector<openvdb::FloatGrid> intersector_;
    rgb background_;
    vec3d origin_{}, cells_per_unit_{};
    openvdb::Vec3d lo_, hi_;
    double step_ = 1;
    std::array<float, 256> alpha_{};
    bool lit_ = false;
    float ambient_ = 0, diffuse_ = 0;
    openvdb::Vec3d light_{0, 1, 0}; // toward the light, index space (world direction x cells per unit)
};

struct row {
    std::string tree, structure;
    int resolution = 0;
    std::size_t nonempty = 0, memory = 0, accelerator = 0;
    double access_nonempty_ns = -1, access_any_ns = -1;
    double setup_ms = -1, scalar_ms = -1, packet_ms = -1; // OpenVDB: its render in scalar_ms
    difference image{};
    bool rendered = false;
};

std::string number(double v, const char* format = "%.6g")
{
    if (v < 0) return "";
    char b[48];
    std::snprintf(b, sizeof b, format, v);
    return b;
}

} // namespace

int main(int argc, char** argv)
{
    std::string csv_path, trees = "ABCD";
    unsigned threads = 2;
    int size = 300, res = 300;
    std::size_t queries = std::size_t(1) << 20;
    float step_factor = 1.0f;
    bool shade_per_voxel = false, each_sample = false;
    for (int i = 1; i < argc; ++i) {
        const std::string a = argv[i];
        if (i + 1 >= argc) {
            std::fprintf(stderr,
                         "usage: %s [--csv FILE] [--threads T] [--size N] [--resolution R] [--trees ABCD] [--queries Q] [--step S]"
                         " [--shade per-sample|per-voxel] [--march in-step|each-sample]\n",
                         argv[0]);
            return 2;
        }
        const std::string v = argv[++i];
        if (a == "--csv") csv_path = v;
        else if (a == "--threads") threads = unsigned(std::max(1, std::atoi(v.c_str())));
        else if (a == "--size") size = std::max(16, std::atoi(v.c_str()));
        else if (a == "--resolution") res = std::max(8, std::atoi(v.c_str()));
        else if (a == "--trees") trees = v;
        else if (a == "--queries") queries = std::size_t(std::max(1000L, std::atol(v.c_str())));
        else if (a == "--step") step_factor = float(std::max(0.05, std::atof(v.c_str())));
        else if (a == "--shade" && (v == "per-voxel" || v == "per-sample")) shade_per_voxel = v == "per-voxel";
        else if (a == "--march" && (v == "in-step" || v == "each-sample")) each_sample = v == "each-sample";
        else {
            std::fprintf(stderr, "unknown option %s\n", a.c_str());
            return 2;
        }
    }
    openvdb::initialize();
    std::printf("load average before: %s\n", bench::load_average().c_str());

    std::vector<row> rows;
    // Per tree: the four store kinds, lit_per_sample, lit_dense, openvdb_float, openvdb_lit, openvdb_uint8.
    constexpr std::size_t per_tree = 9;
    volatile unsigned sink = 0; // keeps the lookups' sums alive
    std::printf("OpenVDB %s peer: resolution %d, %dx%d view on %u thread(s), step factor %.2f, library shading %s, %s, %zu random lookups\n\n",
                openvdb::getLibraryAbiVersionString(), res, size, size, threads, double(step_factor),
                shade_per_voxel ? "per voxel" : "per sample", each_sample ? "lanes shading each sample (the march before)" : "lanes in step (flat shading)",
                queries);
    std::printf("%-4s %-12s %11s %9s %8s %8s | %8s %9s %9s %8s %7s\n", "tree", "structure", "memory", "+skipping", "ns/hit", "ns/any",
                "setup", "scalar", "packet", "RMSE", "differ");

    for (char letter : trees) {
        ifs<> (*maker)(int) = letter == 'A' ? presets::tree_a : letter == 'B' ? presets::tree_b : letter == 'C' ? presets::tree_c
                              : letter == 'D' ? presets::tree_d : nullptr;
        if (!maker) continue;
        const ifs<> tree = maker(res);
        const generated_hits hits = generate(tree, 1);
        const std::vector<voxel_entry> entries = compact(hits.hits);
        const std::vector<stored_voxel> voxels = classify(entries, density_classes(entries, 32), tree.branch_depth);
        const hypervolume& volume = tree.volume;
        const tree_shape shape = tree_shape::of(volume, voxels);
        const krs::pinhole_camera camera = framing_camera(shape.box, size, size);
        const rgb background{0.78f, 0.86f, 0.95f};

        // The same lookups for everyone: indices for the stores, coordinates for the grids.
        std::mt19937_64 random(7);
        std::vector<voxel_index> hit_index(queries), any_index(queries);
        std::vector<openvdb::Coord> hit_coord(queries), any_coord(queries);
        for (std::size_t q = 0; q < queries; ++q) {
            hit_index[q] = voxels[std::uniform_int_distribution<std::size_t>(0, voxels.size() - 1)(random)].index;
            any_index[q] = voxel_index(std::uniform_int_distribution<std::uint64_t>(0, volume.voxel_count() - 1)(random));
            const auto h = volume.coordinates(hit_index[q]), n = volume.coordinates(any_index[q]);
            hit_coord[q] = openvdb::Coord(h[0], h[1], h[2]);
            any_coord[q] = openvdb::Coord(n[0], n[1], n[2]);
        }
        const auto ns_per = [&](auto&& lookups) {
            return bench::best_seconds(3, lookups) * 1e9 / double(queries);
        };

        // The library: every store kind, the shading that matches the OpenVDB side.
        march_options options;
        options.step_factor = step_factor;
        options.shadows = false;
        options.lights.clear();
        options.ambient = 1.0f;
        options.ambient_falloff = 0.0f;
        options.specular = 0.0f;
        options.shade_per_voxel = shade_per_voxel;
        const depth_colors white({{0, 255, {1, 1, 1}, {1, 1, 1}}});
        render_settings settings;
        settings.background = background;
        settings.shade_each_sample = each_sample;
        settings.parallel_for = [threads](std::size_t count, const std::function<void(std::size_t)>& body) {
            bench::run_parallel(threads, count, body);
        };
        std::vector<float> reference; // the dense store's scalar image

        const auto library = [&]<class S>(const char* name, const S& store) {
            row r;
            r.tree = tree.name, r.structure = name, r.resolution = res, r.nonempty = store.nonempty_count();
            r.memory = store.memory_bytes();
            r.access_nonempty_ns = ns_per([&] {
                unsigned s = 0;
                for (voxel_index i : hit_index) s += store.at(i).density;
                sink = sink + s;
            });
            r.access_any_ns = ns_per([&] {
                unsigned s = 0;
                for (voxel_index i : any_index) s += store.at(i).density;
                sink = sink + s;
            });
            std::optional<volume_marcher> marcher;
            r.setup_ms = bench::best_seconds(1, [&] { marcher.emplace(store, shape, white, options, settings.parallel_for); }) * 1e3;
            r.accelerator = marcher->memory_bytes();
            image scalar, packet;
            r.scalar_ms = bench::best_seconds(4, [&] { scalar = render<float>(*marcher, camera, settings); }) * 1e3;
            r.packet_ms = bench::best_seconds(4, [&] { packet = render<krs::packet_f>(*marcher, camera, settings); }) * 1e3;
            if (reference.empty()) reference = scalar.rgb;
            r.image = compare(packet.rgb, reference);
            const difference scalar_difference = compare(scalar.rgb, reference);
            if (scalar_difference.max > r.image.max) r.image = scalar_difference;
            r.rendered = true;
            rows.push_back(r);
        };
        for_each_store_kind([&]<class S>() { library(store_kind_name<S>.data(), S::build(volume, voxels)); });
        // Lighting on: the library's defaults (per voxel, light sweep) on the dense store.
        march_options lit_options;
        lit_options.step_factor = step_factor;
        lit_options.ambient_falloff = 0.0f;
        tree_shape flowless = shape;
        flowless.flows.clear(); // no normals: diffuse = the shadow alone, as on the OpenVDB side
        std::vector<float> lit_reference; // the library's lit image shaded per sample, as OpenVDB shades
        const dense_store lit_store = dense_store::build(volume, voxels);
        for (const bool per_voxel : {false, true}) {
            const dense_store& store = lit_store;
            lit_options.shade_per_voxel = per_voxel;
            row r;
            r.tree = tree.name, r.structure = per_voxel ? "lit_dense" : "lit_per_sample", r.resolution = res, r.nonempty = store.nonempty_count();
            r.memory = store.memory_bytes();
            std::optional<volume_marcher> marcher;
            r.setup_ms = 1e300;
            for (int k = 0; k < 2; ++k)
                r.setup_ms = std::min(r.setup_ms, bench::best_seconds(1, [&] { marcher.emplace(store, flowless, white, lit_options, settings.parallel_for); }) * 1e3);
            r.accelerator = marcher->memory_bytes();
            image scalar, packet;
            r.scalar_ms = bench::best_seconds(4, [&] { scalar = render<float>(*marcher, camera, settings); }) * 1e3;
            r.packet_ms = bench::best_seconds(4, [&] { packet = render<krs::packet_f>(*marcher, camera, settings); }) * 1e3;
            if (!per_voxel) lit_reference = scalar.rgb;
            r.image = compare(packet.rgb, lit_reference);
            r.rendered = true;
            rows.push_back(r);
        }

        // OpenVDB: the same voxels, active with their density.
        openvdb::FloatGrid::Ptr density = openvdb::FloatGrid::create(0.0f);
        byte_grid::Ptr bytes = byte_grid::create(0);
        {
            openvdb::FloatGrid::Accessor fa = density->getAccessor();
            byte_grid::Accessor ba = bytes->getAccessor();
            for (const stored_voxel& v : voxels) {
                if (v.value.density == 0) continue;
                const auto c = volume.coordinates(v.index);
                fa.setValue(openvdb::Coord(c[0], c[1], c[2]), float(v.value.density) / 255.0f);
                ba.setValue(openvdb::Coord(c[0], c[1], c[2]), v.value.density);
            }
        }
        {
            row r;
            r.tree = tree.name, r.structure = "openvdb_float", r.resolution = res, r.nonempty = std::size_t(density->activeVoxelCount());
            r.memory = std::size_t(density->memUsage());
            openvdb::FloatGrid::ConstAccessor a = density->getConstAccessor();
            r.access_nonempty_ns = ns_per([&] {
                float s = 0;
                for (const openvdb::Coord& c : hit_coord) s += a.getValue(c);
                sink = sink + unsigned(s);
            });
            r.access_any_ns = ns_per([&] {
                float s = 0;
                for (const openvdb::Coord& c : any_coord) s += a.getValue(c);
                sink = sink + unsigned(s);
            });
            std::optional<openvdb_marcher> marcher;
            r.setup_ms = bench::best_seconds(1, [&] { marcher.emplace(*density, volume, step_factor, background); }) * 1e3;
            r.accelerator = marcher->accelerator_bytes();
            picture img;
            r.scalar_ms = bench::best_seconds(4, [&] { img = marcher->render(camera, threads); }) * 1e3;
            r.image = compare(img.rgb, reference);
            r.rendered = true;
            rows.push_back(r);
            row l = r;
            l.structure = "openvdb_lit";
            l.access_nonempty_ns = l.access_any_ns = -1;
            const krs::vec3f light = lit_options.light_directions()[0];
            l.setup_ms = bench::best_seconds(1, [&] {
                marcher.emplace(*density, volume, step_factor, background, light, lit_options.ambient, lit_options.diffuse);
            }) * 1e3;
            l.scalar_ms = bench::best_seconds(4, [&] { img = marcher->render(camera, threads); }) * 1e3;
            l.image = compare(img.rgb, lit_reference);
            rows.push_back(l);
        }
        {
            row r;
            r.tree = tree.name, r.structure = "openvdb_uint8", r.resolution = res, r.nonempty = std::size_t(bytes->activeVoxelCount());
            r.memory = std::size_t(bytes->memUsage());
            byte_grid::ConstAccessor a = bytes->getConstAccessor();
            r.access_nonempty_ns = ns_per([&] {
                unsigned s = 0;
                for (const openvdb::Coord& c : hit_coord) s += a.getValue(c);
                sink = sink + s;
            });
            r.access_any_ns = ns_per([&] {
                unsigned s = 0;
                for (const openvdb::Coord& c : any_coord) s += a.getValue(c);
                sink = sink + s;
            });
            rows.push_back(r);
        }
        for (auto it = rows.end() - per_tree; it != rows.end(); ++it)
            std::printf("%-4s %-12s %9.2fMB %7.1fKB %8.1f %8.1f | %8s %9s %9s %8s %7s\n", it->tree.c_str(), it->structure.c_str(),
                        double(it->memory) / 1e6, double(it->accelerator) / 1e3, it->access_nonempty_ns, it->access_any_ns,
                        (number(it->setup_ms, "%.1f") + (it->setup_ms < 0 ? "-" : "ms")).c_str(),
                        (number(it->scalar_ms, "%.1f") + (it->scalar_ms < 0 ? "-" : "ms")).c_str(),
                        (number(it->packet_ms, "%.1f") + (it->packet_ms < 0 ? "-" : "ms")).c_str(),
                        it->rendered ? number(it->image.rmse, "%.5f").c_str() : "-",
                        it->rendered ? (number(100.0 * it->image.share, "%.2f") + "%").c_str() : "-");
        std::printf("\n");
    }

    // The targets, per tree: the index-list stores under the grid, the marcher as fast.
    bool memory_met = true, speed_met = true, half_met = true;
    for (std::size_t i = 0; i + per_tree <= rows.size(); i += per_tree) {
        const row &index_list = rows[i + 1], &bit_array = rows[i + 2], &lit = rows[i + 5], &vdb = rows[i + 6], &vdb_lit = rows[i + 7],
                  &vdb_bytes = rows[i + 8];
        double library_best = 1e300;
        for (std::size_t s = i; s < i + 4; ++s) library_best = std::min({library_best, rows[s].scalar_ms, rows[s].packet_ms});
        std::printf("tree %s: memory / FloatGrid's: index_list %.2f, bit_array %.2f; / byte grid's: %.2f, %.2f. "
                    "Render: best library %.1f ms, OpenVDB %.1f ms (library time / OpenVDB time %.2f)\n",
                    vdb.tree.c_str(), double(index_list.memory) / double(vdb.memory), double(bit_array.memory) / double(vdb.memory),
                    double(index_list.memory) / double(vdb_bytes.memory), double(bit_array.memory) / double(vdb_bytes.memory), library_best,
                    vdb.scalar_ms, library_best / vdb.scalar_ms);
        const double lit_best = std::min(lit.scalar_ms, lit.packet_ms);
        std::printf("tree %s, lighting on: library %.1f ms (%.1f ms with its setup), OpenVDB %.1f ms (%.1f ms with its setup): library / "
                    "OpenVDB %.2f per frame, %.2f with setup; lighting off %.2f\n",
                    vdb.tree.c_str(), lit_best, lit_best + lit.setup_ms, vdb_lit.scalar_ms, vdb_lit.scalar_ms + vdb_lit.setup_ms,
                    lit_best / vdb_lit.scalar_ms, (lit_best + lit.setup_ms) / (vdb_lit.scalar_ms + vdb_lit.setup_ms),
                    library_best / vdb.scalar_ms);
        memory_met = memory_met && index_list.memory < vdb.memory && bit_array.memory < vdb.memory;
        speed_met = speed_met && library_best <= vdb.scalar_ms;
        half_met = half_met && library_best <= 0.5 * vdb.scalar_ms && lit_best <= 0.5 * vdb_lit.scalar_ms;
    }
    std::printf("targets: index-list stores below the OpenVDB FloatGrid's memory -> %s; library raymarcher at least as fast as "
                "OpenVDB's -> %s; at most 0.5 of OpenVDB's time, lighting off and on (issue 27) -> %s\n",
                memory_met ? "met" : "NOT met", speed_met ? "met" : "NOT met", half_met ? "met" : "NOT met");

    if (csv_path.empty()) csv_path = bench::csv_next_to_executable(argv[0]);
    std::ofstream csv(csv_path);
    csv << "tree,resolution,structure,nonempty,memory_bytes,skipping_bytes,access_nonempty_ns,access_any_ns,setup_ms,render_scalar_ms,"
           "render_packet_ms,image_rmse,image_max_difference,image_differing_share,threads,image_size,step_factor,library_shading\n";
    for (const row& r : rows)
        csv << r.tree << ',' << r.resolution << ',' << r.structure << ',' << r.nonempty << ',' << r.memory << ',' << r.accelerator << ','
            << number(r.access_nonempty_ns) << ',' << number(r.access_any_ns) << ',' << number(r.setup_ms) << ',' << number(r.scalar_ms)
            << ',' << number(r.packet_ms) << ',' << (r.rendered ? number(r.image.rmse) : "") << ','
            << (r.rendered ? number(r.image.max) : "") << ',' << (r.rendered ? number(r.image.share) : "") << ',' << threads << ','
            << size << ',' << step_factor << ',' << (shade_per_voxel ? "per-voxel" : "per-sample") << '\n';
    std::printf("\nload average after: %s", bench::load_average().c_str());
    std::printf("\nwrote %s\n", csv_path.c_str());
    return sink == 0xffffffffu ? 1 : 0;
}

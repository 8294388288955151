// Mesh extraction (krs/mesh/extract.hpp): triangles per second and memory against resolution,
// next to the mesh's error, for a torus (exact distance, closed form) and two example scenes (the
// rock, a creased sequence of bounds; the Menger sponge, a KIFS).
//
//     bench_mesh [--csv FILE] [--rounds N] [--max-resolution R] [--dense-max R]
//     (the CSV goes next to the executable, as <executable>.csv, unless --csv names one)
//
// Per field and resolution (cells along the box's longest side) the sparse extraction and the dense
// one (every cell visited; up to --dense-max) run in alternating rounds, so the load of the moment
// falls on both alike; each time is its best round (wall and this thread's CPU time; single
// thread). Memory is what the extractor counts against its budget (mesh, edge table, pending
// vertices) at the end. Errors:
//   vertex |d|      the largest |field distance| at the mesh's vertices, in cells (the field's own
//                   distance: exact for the torus, a lower bound of the true distance elsewhere);
//   centroid |d|    the same at triangle centroids: how far the flat triangles sag from the surface;
//   surface->mesh   the largest distance from a dense sampling of the zero set (the vertices of an
//                   extraction at twice the resolution, each checked to lie on the zero set) to
//                   the nearest triangle, in cells;
//   Hausdorff est.  the larger of centroid |d| and surface->mesh (a two-sided estimate).
// The sparse and dense meshes are compared triangle for triangle (they must be equal).
// Shared corners: the sparse extraction as it was before corners were shared within 2^3-cell
// blocks (mesh_options::share_corners = false, each cell evaluating its own 8) runs in the same
// alternating rounds; `percell_cpu` is its CPU time, `share_x` the ratio, `same` whether its mesh
// equals the shared one vertex for vertex and triangle for triangle (it must).

#include "krs/scenes/example_scenes.hpp"
#include "krs/scenes/scene_files.hpp"
#include "krs/kernels/torus.hpp"
#include "krs/mesh/extract.hpp"

#include "support/text.hpp"
#include "support/timing.hpp"

#include <algorithm>
#include <array>
#include <cmath>
#include <cstdio>
#include <fstream>
#include <limits>
#include <string>
#include <unordered_map>
#include <vector>

namespace {

using krs::vec3d;

// The closest point of triangle abc to p (by the regions of the triangle's plane: vertices, edges,
// face), returned as a distance.
double point_triangle_distance(const vec3d& p, const vec3d& a, const vec3d& b, const vec3d& c)
{
    const vec3d ab = b - a, ac = c - a, ap = p - a;
    const double d1 = krs::dot(ab, ap), d2 = krs::dot(ac, ap);
    if (d1 <= 0 && d2 <= 0) return krs::length(p - a);
    const vec3d bp = p - b;
    const double d3 = krs::dot(ab, bp), d4 = krs::dot(ac, bp);
    if (d3 >= 0 && d4 <= d3) return krs::length(p - b);
    const double vc = d1 * d4 - d3 * d2;
    if (vc <= 0 && d1 >= 0 && d3 <= 0) return krs::length(p - (a + ab * (d1 / (d1 - d3))));
    const vec3d cp = p - c;
    const double d5 = krs::dot(ab, cp), d6 = krs::dot(ac, cp);
    if (d6 >= 0 && d5 <= d6) return krs::length(p - c);
    const double vb = d5 * d2 - d1 * d6;
    if (vb <= 0 && d2 >= 0 && d6 <= 0) return krs::length(p - (a + ac * (d2 / (d2 - d6))));
    const double va = d3 * d6 - d5 * d4;
    if (va <= 0 && d4 - d3 >= 0 && d5 - d6 >= 0) return krs::length(p - (b + (c - b) * ((d4 - d3) / ((d4 - d3) + (d5 - d6)))));
    const double denom = 1.0 / (va + vb + vc);
    return krs::length(p - (a + ab * (vb * denom) + ac * (vc * denom)));
}

// Triangles bucketed by the cells (side `cell`) their boxes overlap: the nearest triangle to a
// point within `cell` of the mesh lies in the point's cell or a neighbour.
class triangle_buckets {
public:
    triangle_buckets(const krs::triangle_mesh& m, double cell) : m_(m), cell_(cell)
    {
        for (std::uint32_t t = 0; t < m.triangles.size(); ++t) {
            vec3d lo(m.positions[m.triangles[t][0]]), hi = lo;
            for (int v = 1; v < 3; ++v) lo = krs::min(lo, vec3d(m.positions[m.triangles[t][v]])), hi = krs::max(hi, vec3d(m.positions[m.triangles[t][v]]));
            const auto a = index(lo), b = index(hi);
            for (auto k = a[2]; k <= b[2]; ++k)
                for (auto j = a[1]; j <= b[1]; ++j)
                    for (auto i = a[0]; i <= b[0]; ++i) buckets_[key(i, j, k)].push_back(t);
        }
    }
    // The distance to the nearest triangle: the cells within r of the point's cell, r = 1, 2, ...
    // until the nearest found is within r cells (then no farther cell can hold a nearer one), up
    // to 16 cells (infinity beyond: a feature of the fine sampling the mesh does not have at all).
    double distance(const vec3d& p) const
    {
        const auto c = index(p);
        double best = std::numeric_limits<double>::infinity();
        for (int r = 1; r <= 16; ++r) {
            for (int dk = -r; dk <= r; ++dk)
                for (int dj = -r; dj <= r; ++dj)
                    for (int di = -r; di <= r; ++di) {
                        if (std::max({std::abs(di), std::abs(dj), std::abs(dk)}) != r && r > 1) continue; // the shell only
                        const auto it = buckets_.find(key(c[0] + di, c[1] + dj, c[2] + dk));
                        if (it == buckets_.end()) continue;
                        for (std::uint32_t t : it->second) {
                            const auto& tri = m_.triangles[t];
                            best = std::min(best, point_triangle_distance(p, vec3d(m_.positions[tri[0]]), vec3d(m_.positions[tri[1]]),
                                                                          vec3d(m_.positions[tri[2]])));
                        }
                    }
            if (best <= double(r) * cell_) break;
        }
        return best;
    }

private:
    std::array<std::int64_t, 3> index(const vec3d& p) const
    {
        return {std::int64_t(std::floor(p.x / cell_)), std::int64_t(std::floor(p.y / cell_)), std::int64_t(std::floor(p.z / cell_))};
    }
    static std::uint64_t key(std::int64_t i, std::int64_t j, std::int64_t k)
    {
        return (std::uint64_t(i) & 0x1fffff) | (std::uint64_t(j) & 0x1fffff) << 21 | (std::uint64_t(k) & 0x1fffff) << 42;
    }
    const krs::triangle_mesh& m_;
    double cell_;
    std::unordered_map<std::uint64_t, std::vector<std::uint32_t>> buckets_;
};

struct row {
    std::string field;
    int resolution = 0;
    std::size_t triangles = 0, vertices = 0, bytes = 0, evaluations = 0;
    double sparse_s = 0, sparse_cpu_s = 0, dense_s = -1, dense_cpu_s = -1, per_cell_cpu_s = 0;
    bool dense_equal = true, per_cell_same = true;
    double no_estimate_cpu_s = 0; // estimate_first = false
    double coarse_cpu_s = 0;      // the estimate's coarse pass alone
    double vertex_d = 0, centroid_d = 0, surface_to_mesh = 0, reference_d = 0;
};

template <class F>
void measure(const std::string& name, const F& f, const krs::bounding_box& box, int max_resolution, int dense_max, int rounds,
             std::vector<row>& rows)
{
    for (int r = 16; r <= max_resolution; r *= 2) {
        row out;
        out.field = name;
        out.resolution = r;
        krs::mesh_options o;
        o.resolution = r;
        o.box = box;
        o.memory_budget = std::size_t(8) << 30;
        krs::mesh_options dense = o;
        dense.sparse = false;
        krs::mesh_options per_cell = o;
        per_cell.share_corners = false;
        krs::mesh_options no_estimate = o; // the extraction before the up-front estimate
        no_estimate.estimate_first = false;
        double best_no_estimate_cpu = 1e300, best_coarse_cpu = 1e300;
        krs::mesh_options coarse = no_estimate; // the up-front estimate's coarse pass alone
        coarse.resolution = r / krs::detail::estimate_factor(r);
        krs::triangle_mesh m, md, mp;
        krs::mesh_stats stats;
        double best = 1e300, best_cpu = 1e300, best_dense = 1e300, best_dense_cpu = 1e300, best_per_cell_cpu = 1e300;
        for (int round = 0; round < rounds; ++round) {
            {
                const auto c = bench::thread_cpu_seconds();
                mp = krs::extract_mesh(f, per_cell);
                best_per_cell_cpu = std::min(best_per_cell_cpu, bench::thread_cpu_seconds() - c);
            }
            {
                const auto c = bench::thread_cpu_seconds();
                (void)krs::extract_mesh(f, no_estimate);
                best_no_estimate_cpu = std::min(best_no_estimate_cpu, bench::thread_cpu_seconds() - c);
            }
            {
                const auto c = bench::thread_cpu_seconds();
                krs::detail::mesh_extractor<F> x(f, coarse);
                (void)x.count(std::size_t(1) << 40);
                best_coarse_cpu = std::min(best_coarse_cpu, bench::thread_cpu_seconds() - c);
            }
            auto c0 = bench::thread_cpu_seconds();
            auto t0 = std::chrono::steady_clock::now();
            m = krs::extract_mesh(f, o, &stats);
            best = std::min(best, std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count());
            best_cpu = std::min(best_cpu, bench::thread_cpu_seconds() - c0);
            if (r <= dense_max) {
                c0 = bench::thread_cpu_seconds();
                t0 = std::chrono::steady_clock::now();
                md = krs::extract_mesh(f, dense);
                best_dense = std::min(best_dense, std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count());
                best_dense_cpu = std::min(best_dense_cpu, bench::thread_cpu_seconds() - c0);
            }
        }
        out.sparse_s = best, out.sparse_cpu_s = best_cpu;
        out.per_cell_cpu_s = best_per_cell_cpu;
        out.no_estimate_cpu_s = best_no_estimate_cpu;
        out.coarse_cpu_s = best_coarse_cpu;
        out.per_cell_same = mp.triangles == m.triangles && mp.positions.size() == m.positions.size();
        for (std::size_t v = 0; out.per_cell_same && v < m.positions.size(); ++v)
            out.per_cell_same = mp.positions[v].x == m.positions[v].x && mp.positions[v].y == m.positions[v].y && mp.positions[v].z == m.positions[v].z;
        if (r <= dense_max) {
            out.dense_s = best_dense, out.dense_cpu_s = best_dense_cpu;
            out.dense_equal = md.triangles.size() == m.triangles.size() && md.positions.size() == m.positions.size();
            if (out.dense_equal) { // the same vertices in a different order: compare as sorted position lists
                auto a = m.positions, b = md.positions;
                const auto less = [](const krs::vec3f& x, const krs::vec3f& y) {
                    return std::array<float, 3>{x.x, x.y, x.z} < std::array<float, 3>{y.x, y.y, y.z};
                };
                std::sort(a.begin(), a.end(), less), std::sort(b.begin(), b.end(), less);
                for (std::size_t i = 0; i < a.size(); ++i) out.dense_equal = out.dense_equal && a[i].x == b[i].x && a[i].y == b[i].y && a[i].z == b[i].z;
            }
        }
        out.triangles = m.triangle_count(), out.vertices = m.vertex_count(), out.bytes = stats.peak_bytes, out.evaluations = stats.evaluations;
        const double h = stats.cell_size;
        for (const auto& p : m.positions) out.vertex_d = std::max(out.vertex_d, std::abs(f.distance(vec3d(p))) / h);
        for (const auto& t : m.triangles) {
            const vec3d c = (vec3d(m.positions[t[0]]) + vec3d(m.positions[t[1]]) + vec3d(m.positions[t[2]])) / 3.0;
            out.centroid_d = std::max(out.centroid_d, std::abs(f.distance(c)) / h);
        }
        // The dense sampling of the zero set: an extraction at twice the resolution, its vertices
        // checked on the zero set by the field itself.
        krs::mesh_options fine = o;
        fine.resolution = 2 * r;
        const krs::triangle_mesh reference = krs::extract_mesh(f, fine);
        const triangle_buckets buckets(m, h);
        for (const auto& p : reference.positions) {
            out.reference_d = std::max(out.reference_d, std::abs(f.distance(vec3d(p))) / h);
            out.surface_to_mesh = std::max(out.surface_to_mesh, buckets.distance(vec3d(p)) / h);
        }
        std::printf("%-12s %5d %10zu %10zu %9.1f %9.3f %9.3f %11.3f %7.2f %4s %7.3f %8.4f %10.0f %9s %9s %6s %10.2e %9.4f %9.4f %9.4f %10.2e\n",
                    name.c_str(), r, out.triangles, out.vertices, double(out.bytes) / 1048576.0, out.sparse_s, out.sparse_cpu_s,
                    out.per_cell_cpu_s, out.per_cell_cpu_s / out.sparse_cpu_s, out.per_cell_same ? "yes" : "NO",
                    out.sparse_cpu_s / out.no_estimate_cpu_s, out.coarse_cpu_s / out.no_estimate_cpu_s, double(out.triangles) / out.sparse_cpu_s, out.dense_s < 0 ? "-" : bench::format("%.3f", out.dense_s).c_str(),
                    out.dense_cpu_s < 0 ? "-" : bench::format("%.3f", out.dense_cpu_s).c_str(),
                    out.dense_s < 0 ? "-" : (out.dense_equal ? "yes" : "NO"), out.vertex_d, out.centroid_d, out.surface_to_mesh,
                    std::max(out.centroid_d, out.surface_to_mesh), out.reference_d);
        std::fflush(stdout);
        rows.push_back(out);
    }
}

} // namespace

int main(int argc, char** argv)
{
    std::string csv_path;
    int rounds = 2, max_resolution = 256, dense_max = 64;
    for (int i = 1; i < argc; ++i) {
        const std::string a = argv[i];
        if (i + 1 >= argc || (a != "--csv" && a != "--rounds" && a != "--max-resolution" && a != "--dense-max")) {
            std::fprintf(stderr, "usage: %s [--csv FILE] [--rounds N] [--max-resolution R] [--dense-max R]\n", argv[0]);
            return 2;
        }
        const std::string v = argv[++i];
        if (a == "--csv") csv_path = v;
        else if (a == "--rounds") rounds = std::max(1, std::stoi(v));
        else if (a == "--max-resolution") max_resolution = std::max(16, std::stoi(v));
        else dense_max = std::stoi(v);
    }
    std::printf("mesh extraction, single thread, best of %d rounds (per-cell corners, shared corners and dense alternating)\n", rounds);
    std::printf("load average before: %s\n\n", bench::load_average().c_str());
    std::printf("%-12s %5s %10s %10s %9s %9s %9s %11s %7s %4s %7s %8s %10s %9s %9s %6s %10s %9s %9s %9s %10s\n", "field", "res", "triangles",
                "vertices", "mem_MB", "sparse_s", "cpu_s", "percell_cpu", "share_x", "same", "est_x", "coarse_x", "tris/cpu_s", "dense_s", "dense_cpu", "equal", "vertex|d|", "centr|d|", "surf->mesh",
                "hausdorff", "ref|d|");
    std::vector<row> rows;
    const krs::torus torus({0, 0, 0}, {0.2f, 0.3f, 1.0f}, 1.0f, 0.3f);
    measure("torus", torus, krs::bounding_box::unbounded(), max_resolution, std::max(dense_max, 128), rounds, rows);
    namespace ex = krs::scenes;
    // A scene's own box, or the box its tests sample where it has none (as krs_export does).
    const auto scene_box = [](const auto& scene) {
        if (krs::field_box(scene.field).is_bounded()) return krs::bounding_box::unbounded();
        const krs::vec3d c(scene.sample_center), h(scene.sample_half);
        return krs::box_around(c - h, c + h);
    };
    const auto rock = ex::rock_scene::build();
    measure("rock", rock.field, scene_box(rock), std::min(max_resolution, 128), dense_max, rounds, rows);
    const auto menger = ex::kifs_menger_scene::build();
    measure("kifs_menger", menger.field, scene_box(menger), std::min(max_resolution, 128), dense_max, rounds, rows);
    std::printf("\n(mem_MB: mesh + edge table counted by the extractor; errors in cells; equal: sparse mesh == dense mesh; percell_cpu: corners evaluated per cell as before, share_x its CPU time over cpu_s, same: its mesh == the shared one; est_x: cpu_s (with the up-front estimate, the default) over the same extraction with estimate_first = false, same rounds; coarse_x: the estimate's coarse pass alone over that)\n");
    std::printf("load average after: %s\n", bench::load_average().c_str());

    if (csv_path.empty()) csv_path = bench::csv_next_to_executable(argv[0]);
    std::ofstream csv(csv_path);
    csv << "field,resolution,triangles,vertices,memory_bytes,sparse_s,sparse_cpu_s,triangles_per_cpu_s,dense_s,dense_cpu_s,dense_equal,"
           "vertex_d_cells,centroid_d_cells,surface_to_mesh_cells,hausdorff_cells,reference_d_cells,evaluations,rounds,per_cell_cpu_s,"
           "per_cell_same,no_estimate_cpu_s,coarse_cpu_s\n";
    for (const row& r : rows)
        csv << r.field << ',' << r.resolution << ',' << r.triangles << ',' << r.vertices << ',' << r.bytes << ',' << r.sparse_s << ','
            << r.sparse_cpu_s << ',' << double(r.triangles) / r.sparse_cpu_s << ',' << r.dense_s << ',' << r.dense_cpu_s << ','
            << (r.dense_s < 0 ? "" : (r.dense_equal ? "yes" : "no")) << ',' << r.vertex_d << ',' << r.centroid_d << ','
            << r.surface_to_mesh << ',' << std::max(r.centroid_d, r.surface_to_mesh) << ',' << r.reference_d << ',' << r.evaluations
            << ',' << rounds << ',' << r.per_cell_cpu_s << ',' << (r.per_cell_same ? "yes" : "no") << ',' << r.no_estimate_cpu_s << ',' << r.coarse_cpu_s << '\n';
    std::printf("wrote %s\n", csv_path.c_str());
    return 0;
}

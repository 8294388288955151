// Mesh extraction (krs/mesh/extract.hpp) and the PLY/OBJ writers (krs/mesh/write.hpp), against
// references that do not come from the extractor: the field itself at every vertex, closed forms
// (a sphere's and a torus's volume and area), the edge structure of a closed surface, the dense
// grid for the sparse one, and Debian's assimp reading the files.

#include "krs/kernels/sphere.hpp"
#include "krs/kernels/torus.hpp"
#include "krs/kernels/torus_capsule.hpp"
#include "krs/mesh/extract.hpp"
#include "krs/mesh/write.hpp"
#include "krs/sequence.hpp"

#include "support/rejects.hpp"

#include <doctest/doctest.h>

#include <algorithm>
#include <array>
#include <bit>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <limits>
#include <numbers>
#include <set>
#include <sstream>
#include <string>
#include <vector>

#include <unistd.h> // getpid

namespace {

using krs::vec3d;
using krs::vec3f;

// The largest |d| over the mesh's vertices, evaluated by the field itself in double.
template <class F>
double worst_vertex_distance(const F& f, const krs::triangle_mesh& m)
{
    double worst = 0;
    for (const vec3f& p : m.positions) worst = std::max(worst, std::abs(f.distance(vec3d(p))));
    return worst;
}

// The volume enclosed by a closed, outward-oriented mesh (divergence theorem: the sum of the
// signed tetrahedra from the origin to each triangle) and its area.
double enclosed_volume(const krs::triangle_mesh& m)
{
    double v = 0;
    for (const auto& t : m.triangles) {
        const vec3d a(m.positions[t[0]]), b(m.positions[t[1]]), c(m.positions[t[2]]);
        v += krs::dot(a, krs::cross(b, c)) / 6.0;
    }
    return v;
}
double area(const krs::triangle_mesh& m)
{
    double s = 0;
    for (const auto& t : m.triangles) {
        const vec3d a(m.positions[t[0]]), b(m.positions[t[1]]), c(m.positions[t[2]]);
        s += 0.5 * krs::length(krs::cross(b - a, c - a));
    }
    return s;
}

// A small sequence of a sphere and a torus capsule, mirrored twice: four copies of each kernel,
// kernels overlapping (so the surface has creases where they meet).
using small_sequence = krs::sequence<krs::sphere, krs::torus_capsule>;
small_sequence make_small_sequence()
{
    small_sequence::builder b;
    b.kernel(krs::sphere({0.6f, 0.5f, 0.1f}, 0.35f));
    b.kernel(krs::torus_capsule({0.2f, 0.2f, 0.0f}, {0.9f, 0.3f, 0.2f}, {0.5f, 0.6f, 0.3f}, 0.12f));
    b.mirror(krs::mirror({-1, 0, 0}, 0.0f));
    b.mirror(krs::mirror::through({0, 0, 0}, {-0.3f, -1.0f, -0.1f}));
    return b.build();
}

// The triangles as sets of their three corner positions (rotated to start at the smallest), so
// two meshes compare whatever order their vertices were numbered in.
std::multiset<std::array<float, 9>> triangle_set(const krs::triangle_mesh& m)
{
    std::multiset<std::array<float, 9>> out;
    for (const auto& t : m.triangles) {
        std::array<std::array<float, 3>, 3> c;
        for (int i = 0; i < 3; ++i) c[i] = {m.positions[t[i]].x, m.positions[t[i]].y, m.positions[t[i]].z};
        const int first = int(std::min_element(c.begin(), c.end()) - c.begin());
        std::array<float, 9> key;
        for (int i = 0; i < 3; ++i)
            for (int a = 0; a < 3; ++a) key[3 * i + a] = c[(first + i) % 3][a];
        out.insert(key);
    }
    return out;
}

std::filesystem::path temp_path(const std::string& name)
{
    return std::filesystem::temp_directory_path() / ("krs_test_mesh_" + std::to_string(::getpid()) + "_" + name);
}

// No file, and no temporary file beside it, is left at `path`.
bool nothing_left(const std::filesystem::path& path)
{
    std::error_code ec;
    if (std::filesystem::exists(path, ec)) return false;
    const std::string stem = path.filename().string() + ".partial-";
    for (const auto& e : std::filesystem::directory_iterator(path.parent_path(), ec))
        if (e.path().filename().string().rfind(stem, 0) == 0) return false;
    return true;
}

struct nan_field {
    float distance(const vec3f&) const { return std::numeric_limits<float>::quiet_NaN(); }
    double distance(const vec3d&) const { return std::numeric_limits<double>::quiet_NaN(); }
};

} // namespace

TEST_CASE("mesh: a sphere's mesh is closed, on its surface, encloses its volume and faces outward")
{
    const krs::sphere s({0.1f, -0.2f, 0.3f}, 0.8f);
    krs::mesh_options o;
    o.resolution = 32;
    krs::mesh_stats stats;
    const krs::triangle_mesh m = krs::extract_mesh(s, o, &stats);
    REQUIRE(m.triangle_count() > 1000);
    CHECK(krs::count_edge_use(m).closed_manifold());
    // Newton onto an exact distance: every vertex within 1e-5 h (float storage is ~1e-7).
    const double h = stats.cell_size;
    CHECK(worst_vertex_distance(s, m) <= 1e-5 * h);
    // Inscribed in the sphere, the mesh's volume falls short by O(h^2): within 1%.
    const double exact = 4.0 / 3.0 * std::numbers::pi * 0.8 * 0.8 * 0.8;
    CHECK(enclosed_volume(m) == doctest::Approx(exact).epsilon(0.01));
    CHECK(area(m) == doctest::Approx(4.0 * std::numbers::pi * 0.64).epsilon(0.01));
    // Outward: each triangle's normal points away from the centre, and agrees with the vertex
    // normals. Triangles of no area (two vertices projected to one point, where the surface passes
    // a grid corner) have no direction and are only counted.
    std::size_t inward = 0, degenerate = 0;
    for (const auto& t : m.triangles) {
        const vec3d a(m.positions[t[0]]), b(m.positions[t[1]]), c(m.positions[t[2]]);
        const vec3d n = krs::cross(b - a, c - a);
        if (krs::length(n) <= 1e-9 * h * h) {
            ++degenerate;
            continue;
        }
        if (krs::dot(n, (a + b + c) / 3.0 - vec3d(s.center)) <= 0) ++inward;
        if (krs::dot(n, vec3d(m.normals[t[0]])) <= 0) ++inward;
    }
    CHECK(inward == 0);
    MESSAGE(degenerate << " of " << m.triangle_count() << " triangles have no area");
    CHECK(degenerate * 100 < m.triangle_count());
}

TEST_CASE("mesh: a torus's mesh is closed with the torus's genus, on its surface, of its volume")
{
    const krs::torus t({0.0f, 0.1f, 0.0f}, {0.3f, 0.2f, 1.0f}, 1.0f, 0.3f);
    krs::mesh_options o;
    o.resolution = 48;
    krs::mesh_stats stats;
    const krs::triangle_mesh m = krs::extract_mesh(t, o, &stats);
    const krs::edge_use e = krs::count_edge_use(m);
    CHECK(e.closed_manifold());
    // Euler characteristic V - E + F = 2 - 2 genus = 0 for a torus.
    CHECK(std::int64_t(m.vertex_count()) - std::int64_t(e.edges) + std::int64_t(m.triangle_count()) == 0);
    CHECK(worst_vertex_distance(t, m) <= 1e-5 * stats.cell_size);
    const double exact = 2.0 * std::numbers::pi * std::numbers::pi * 1.0 * 0.3 * 0.3;
    CHECK(enclosed_volume(m) == doctest::Approx(exact).epsilon(0.02));
}

TEST_CASE("mesh: a small sequence's mesh is closed and its vertices lie on its zero set")
{
    const small_sequence seq = make_small_sequence();
    krs::mesh_options o;
    o.resolution = 64;
    krs::mesh_stats stats;
    const krs::triangle_mesh m = krs::extract_mesh(seq, o, &stats);
    REQUIRE(m.triangle_count() > 1000);
    CHECK(krs::count_edge_use(m).closed_manifold());
    // The vertex is bracketed on its edge first, so even where kernels meet (the gradient jumps
    // and Newton may stop) it is on the zero set to within float storage: a stated 1e-4 of a cell.
    const double worst = worst_vertex_distance(seq, m);
    MESSAGE("sequence: worst vertex |d| = " << worst / stats.cell_size << " cells");
    CHECK(worst <= 1e-4 * stats.cell_size);
}

TEST_CASE("mesh: sparse extraction gives the dense grid's triangles exactly from far fewer cells")
{
    const small_sequence seq = make_small_sequence();
    const krs::torus t({0.0f, 0.0f, 0.0f}, {0.0f, 1.0f, 0.2f}, 1.0f, 0.25f);
    krs::mesh_options sparse, dense;
    sparse.resolution = dense.resolution = 40;
    dense.sparse = false;
    krs::mesh_stats ss, ds;
    const auto check = [&](const auto& f) {
        const krs::triangle_mesh a = krs::extract_mesh(f, sparse, &ss), b = krs::extract_mesh(f, dense, &ds);
        REQUIRE(a.triangle_count() > 100);
        CHECK(a.triangle_count() == b.triangle_count());
        CHECK(a.vertex_count() == b.vertex_count());
        CHECK(triangle_set(a) == triangle_set(b));
        MESSAGE("cells meshed: sparse " << ss.cells_meshed << ", dense " << ds.cells_meshed << "; evaluations " << ss.evaluations
                                        << " and " << ds.evaluations);
        CHECK(ss.cells_meshed * 3 < ds.cells_meshed);
    };
    check(seq);
    check(t);
}

TEST_CASE("mesh: shared corners give the per-cell mesh vertex for vertex from fewer evaluations")
{
    const small_sequence seq = make_small_sequence();
    const krs::torus t({0.0f, 0.0f, 0.0f}, {0.0f, 1.0f, 0.2f}, 1.0f, 0.25f);
    for (int resolution : {7, 40}) { // odd: 2-blocks at the grid's edge hold cells beyond it
        CAPTURE(resolution);
        krs::mesh_options shared, per_cell;
        shared.resolution = per_cell.resolution = resolution;
        per_cell.share_corners = false;
        krs::mesh_stats ss, ps;
        const auto check = [&](const auto& f) {
            const krs::triangle_mesh a = krs::extract_mesh(f, shared, &ss), b = krs::extract_mesh(f, per_cell, &ps);
            REQUIRE(a.triangle_count() > 10);
            CHECK(a.triangles == b.triangles);
            bool same = a.positions.size() == b.positions.size();
            for (std::size_t v = 0; same && v < a.positions.size(); ++v)
                same = a.positions[v].x == b.positions[v].x && a.positions[v].y == b.positions[v].y && a.positions[v].z == b.positions[v].z;
            CHECK(same);
            CHECK(ss.cells_meshed == ps.cells_meshed);
            // Per surface cell 27 / 8 corner evaluations instead of 8 (projection costs the same).
            const std::size_t corner_saving = ps.cells_meshed * 8 - ss.cells_meshed * 27 / 8;
            MESSAGE("evaluations: shared " << ss.evaluations << ", per cell " << ps.evaluations);
            CHECK(ps.evaluations - ss.evaluations >= corner_saving * 9 / 10);
        };
        check(seq);
        check(t);
    }
}

TEST_CASE("mesh: the triangle count grows about 4x per doubling of the resolution")
{
    const krs::torus t({0.0f, 0.0f, 0.0f}, {0.2f, 0.3f, 1.0f}, 1.0f, 0.3f);
    std::size_t last = 0;
    for (int r : {16, 32, 64, 128}) {
        krs::mesh_options o;
        o.resolution = r;
        const std::size_t n = krs::extract_mesh(t, o).triangle_count();
        if (last) {
            const double ratio = double(n) / double(last);
            MESSAGE("resolution " << r << ": " << n << " triangles, x" << ratio);
            CHECK(ratio > 3.5);
            CHECK(ratio < 4.5);
        }
        last = n;
    }
}

TEST_CASE("mesh: a budget below the estimate is refused before the full-resolution pass starts")
{
    const krs::torus t({0.0f, 0.1f, 0.0f}, {0.3f, 0.2f, 1.0f}, 1.0f, 0.3f);
    krs::mesh_options o;
    o.resolution = 128;
    o.estimate_first = false;
    krs::mesh_stats stats;
    const krs::triangle_mesh m = krs::extract_mesh(t, o, &stats); // the true size, from the full pass
    // A third of the true size: far below any estimate within the slack of the truth.
    o.memory_budget = stats.peak_bytes / 3;
    int reports = 0;
    o.progress = [&](const krs::mesh_report& r) { reports += r.stage != krs::mesh_stage::estimate; };
    // Without the estimate, the growth check refuses too, but only after meshing part of the grid
    // (the progress callback saw it): what the estimate is there to avoid.
    CHECK_THROWS_AS((void)krs::extract_mesh(t, o), krs::invalid_parameter);
    CHECK(reports > 0);
    reports = 0;
    o.estimate_first = true;
    try {
        (void)krs::extract_mesh(t, o);
        FAIL("not refused");
    } catch (const krs::invalid_parameter& e) {
        CHECK(e.parameter() == "mesh_options.memory_budget");
        CHECK(std::string(e.what()).find("estimated") != std::string::npos);
        CHECK(std::string(e.what()).find(std::to_string(o.memory_budget)) != std::string::npos);
        MESSAGE(std::string(e.what()));
    }
    CHECK(reports == 0); // the full-resolution pass never started
}

TEST_CASE("mesh: progress reports each pass from its start, with the grid, and the estimate before the full pass")
{
    const krs::torus t({0.0f, 0.1f, 0.0f}, {0.3f, 0.2f, 1.0f}, 1.0f, 0.3f);
    krs::mesh_options o;
    o.resolution = 128;
    std::vector<krs::mesh_report> reports;
    o.progress = [&](const krs::mesh_report& r) { reports.push_back(r); };
    krs::mesh_stats stats;
    (void)krs::extract_mesh(t, o, &stats);
    REQUIRE(!reports.empty());
    // The passes in order, each first reported at 0 (before its work), its fractions rising.
    const krs::mesh_stage order[] = {krs::mesh_stage::estimate, krs::mesh_stage::cells, krs::mesh_stage::vertices};
    std::size_t pass = 0;
    for (std::size_t i = 0; i < reports.size(); ++i) {
        const krs::mesh_report& r = reports[i];
        CAPTURE(i);
        if (i == 0 || r.stage != reports[i - 1].stage) {
            while (pass < 3 && order[pass] != r.stage) ++pass;
            REQUIRE(pass < 3);
            CHECK(r.done == 0);
        } else {
            CHECK(r.done > reports[i - 1].done);
        }
        CHECK(r.done <= 1);
        // Every report names the full grid, the estimate's pass too.
        for (int a = 0; a < 3; ++a) CHECK(r.cells_per_axis[a] == stats.cells_per_axis[a]);
        CHECK(r.coarse_resolution == 32); // 128 / 4
        // The estimate is known once the full passes start, and within the documented accuracy
        // of the truth for a torus (0.82 to 1.00 of it, with margin).
        if (r.stage == krs::mesh_stage::estimate) CHECK(r.estimated_bytes == 0);
        else CHECK(r.estimated_bytes > 0.7 * double(stats.peak_bytes));
        if (r.stage != krs::mesh_stage::estimate) CHECK(r.estimated_bytes < 1.1 * double(stats.peak_bytes));
    }
    CHECK(reports.front().stage == krs::mesh_stage::estimate);
    CHECK(reports.back().stage == krs::mesh_stage::vertices);
    // Each pass is heard of more than at its start (1% steps): alive throughout, not only at the
    // ends; and each is heard to end.
    for (const krs::mesh_stage stage : order) {
        CAPTURE(int(stage));
        CHECK(std::count_if(reports.begin(), reports.end(), [&](const krs::mesh_report& r) { return r.stage == stage; }) > 5);
        CHECK(std::any_of(reports.begin(), reports.end(), [&](const krs::mesh_report& r) { return r.stage == stage && r.done == 1; }));
    }
}

TEST_CASE("mesh: a budget just above the true mesh size is not refused by the estimate")
{
    const auto fits = [](const auto& f, int resolution) {
        krs::mesh_options o;
        o.resolution = resolution;
        o.estimate_first = false;
        krs::mesh_stats stats;
        const krs::triangle_mesh m = krs::extract_mesh(f, o, &stats);
        // peak_bytes is at least what the growth check counted; 90% of it is refused by the
        // growth check, so the budget below is within about 10% of the true size.
        o.memory_budget = stats.peak_bytes * 9 / 10;
        CHECK_THROWS_AS((void)krs::extract_mesh(f, o), krs::invalid_parameter);
        o.memory_budget = stats.peak_bytes;
        o.estimate_first = true;
        krs::mesh_stats again;
        CHECK_NOTHROW((void)krs::extract_mesh(f, o, &again));
        CHECK(again.peak_bytes == stats.peak_bytes);
    };
    fits(krs::sphere({0.1f, -0.2f, 0.3f}, 0.8f), 64);
    fits(krs::sphere({0.1f, -0.2f, 0.3f}, 0.8f), 128);
    fits(krs::torus({0.0f, 0.1f, 0.0f}, {0.3f, 0.2f, 1.0f}, 1.0f, 0.3f), 64);
    fits(krs::torus({0.0f, 0.1f, 0.0f}, {0.3f, 0.2f, 1.0f}, 1.0f, 0.3f), 128);
    const small_sequence seq = make_small_sequence();
    fits(seq, 64);
}

TEST_CASE("mesh: bad options and fields are refused by name")
{
    const krs::sphere s({0, 0, 0}, 1.0f);
    const auto refused = [&](const krs::mesh_options& o, const std::string& name) {
        krs_test::rejects([&] { (void)krs::extract_mesh(s, o); }, name);
    };
    krs::mesh_options o;
    o.resolution = 0;
    refused(o, "mesh_options.resolution");
    o.resolution = krs::max_mesh_resolution + 1;
    refused(o, "mesh_options.resolution");
    o = {};
    o.projection_steps = -1;
    refused(o, "mesh_options.projection_steps");
    o = {};
    o.memory_budget = 0;
    refused(o, "mesh_options.memory_budget");
    o = {};
    o.resolution = 256;
    o.memory_budget = 1 << 20; // a sphere at 256 cells takes about 20 MB
    refused(o, "mesh_options.memory_budget");
    o = {};
    const float nan = std::numeric_limits<float>::quiet_NaN();
    o.box = {{nan, 0, 0}, {1, 1, 1}};
    refused(o, "mesh_options.box");
    o.box = {{0, 0, 0}, {1, -1, 1}};
    refused(o, "mesh_options.box");
    o.box = {{0, 0, 0}, {0, 0, 0}};
    refused(o, "mesh_options.box");
    // A field that returns NaN, and one without a box.
    krs::mesh_options small;
    small.box = {{-1, -1, -1}, {1, 1, 1}};
    CHECK_THROWS_WITH_AS((void)krs::extract_mesh(nan_field{}, small), doctest::Contains("field: returned a distance that is not finite"),
                         krs::invalid_parameter);
    CHECK_THROWS_WITH_AS((void)krs::extract_mesh(nan_field{}, krs::mesh_options{}), doctest::Contains("mesh_options.box"),
                         krs::invalid_parameter);
}

TEST_CASE("mesh files: PLY and OBJ hold the mesh exactly, bad paths and meshes leave no file")
{
    const krs::sphere s({0, 0, 0}, 1.0f);
    krs::mesh_options o;
    o.resolution = 12;
    const krs::triangle_mesh m = krs::extract_mesh(s, o);

    // PLY: parse the header and the little-endian body independently of the writer's helpers.
    const auto ply = temp_path("sphere.ply");
    krs::save_ply(m, ply);
    {
        std::ifstream in(ply, std::ios::binary);
        std::string line, header;
        while (std::getline(in, line) && line != "end_header") header += line + "\n";
        CHECK(header.find("format binary_little_endian 1.0") != std::string::npos);
        CHECK(header.find("element vertex " + std::to_string(m.vertex_count()) + "\n") != std::string::npos);
        CHECK(header.find("element face " + std::to_string(m.triangle_count()) + "\n") != std::string::npos);
        const auto u32 = [&] {
            unsigned char b[4];
            in.read(reinterpret_cast<char*>(b), 4);
            return std::uint32_t(b[0]) | std::uint32_t(b[1]) << 8 | std::uint32_t(b[2]) << 16 | std::uint32_t(b[3]) << 24;
        };
        const auto f32 = [&] { return std::bit_cast<float>(u32()); };
        std::size_t bad = 0;
        for (std::size_t v = 0; v < m.vertex_count(); ++v) {
            const float x = f32(), y = f32(), z = f32(), nx = f32(), ny = f32(), nz = f32();
            bad += x != m.positions[v].x || y != m.positions[v].y || z != m.positions[v].z;
            bad += nx != m.normals[v].x || ny != m.normals[v].y || nz != m.normals[v].z;
        }
        for (const auto& t : m.triangles) {
            char count = 0;
            in.read(&count, 1);
            bad += count != 3;
            for (std::uint32_t v : t) bad += u32() != v;
        }
        CHECK(bad == 0);
        CHECK(in.good());
        CHECK(in.peek() == std::char_traits<char>::eof());
    }
    // OBJ: every "v" line reads back to the float it was written from.
    const auto obj = temp_path("sphere.obj");
    krs::save_obj(m, obj);
    {
        std::ifstream in(obj);
        std::string tag;
        std::size_t v = 0, f = 0, bad = 0;
        for (std::string line; std::getline(in, line);) {
            std::istringstream l(line);
            l >> tag;
            if (tag == "v") {
                float x, y, z;
                l >> x >> y >> z;
                bad += v >= m.vertex_count() || x != m.positions[v].x || y != m.positions[v].y || z != m.positions[v].z;
                ++v;
            } else if (tag == "f") {
                std::string a, b, c;
                l >> a >> b >> c;
                bad += f >= m.triangle_count() || std::stoul(a) != m.triangles[f][0] + 1 || std::stoul(b) != m.triangles[f][1] + 1 ||
                       std::stoul(c) != m.triangles[f][2] + 1;
                ++f;
            }
        }
        CHECK(v == m.vertex_count());
        CHECK(f == m.triangle_count());
        CHECK(bad == 0);
    }

#ifdef KRS_ASSIMP
    // Debian's assimp reads both: the face count and the bounding box agree.
    for (const auto& file : {ply, obj}) {
        const auto report = temp_path("assimp.txt");
        const std::string command = std::string(KRS_ASSIMP) + " info \"" + file.string() + "\" > \"" + report.string() + "\" 2>&1";
        CHECK(std::system(command.c_str()) == 0);
        std::ifstream in(report);
        const std::string text((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
        INFO(text);
        CHECK(text.find("Faces:              " + std::to_string(m.triangle_count()) + "\n") != std::string::npos);
        std::filesystem::remove(report);
    }
#else
    MESSAGE("assimp not found at configure time: the files were not read by assimp");
#endif
    std::filesystem::remove(ply);
    std::filesystem::remove(obj);

    // An unwritable path, a directory, an empty path, a bad mesh: refused, and nothing left behind.
    const std::filesystem::path missing = std::filesystem::temp_directory_path() / "krs_no_such_directory" / "x.ply";
    CHECK_THROWS_WITH_AS(krs::save_ply(m, missing), doctest::Contains("save_ply: "), krs::save_error);
    CHECK_THROWS_WITH_AS(krs::save_obj(m, std::filesystem::temp_directory_path()), doctest::Contains("save_obj path"),
                         krs::invalid_parameter);
    CHECK_THROWS_WITH_AS(krs::save_ply(m, ""), doctest::Contains("save_ply path"), krs::invalid_parameter);
    krs::triangle_mesh broken = m;
    broken.triangles[3][1] = std::uint32_t(m.vertex_count());
    const auto bad_file = temp_path("broken.ply");
    CHECK_THROWS_WITH_AS(krs::save_ply(broken, bad_file), doctest::Contains("must index only its own vertices"), krs::invalid_parameter);
    CHECK(nothing_left(bad_file));
    broken = m;
    broken.positions[0].y = std::numeric_limits<float>::quiet_NaN();
    CHECK_THROWS_AS(krs::save_obj(broken, bad_file), krs::invalid_parameter);
    CHECK(nothing_left(bad_file));
    // An earlier file at the path survives a failed save whole.
    krs::save_obj(m, bad_file);
    const auto before = std::filesystem::file_size(bad_file);
    CHECK_THROWS_AS(krs::save_obj(broken, bad_file), krs::invalid_parameter);
    CHECK(std::filesystem::file_size(bad_file) == before);
    std::filesystem::remove(bad_file);
}

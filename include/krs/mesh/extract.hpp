#pragma once
// Meshes of any field: the zero set as indexed triangles, at a resolution the user chooses, by
// marching tetrahedra over a cubic grid whose cost follows the surface rather than the volume.
//
// The grid. Cells are cubes of side h = (longest side of the box) / resolution over the field's
// box (`field_box`, or one the user gives), padded by one cell on every side: the outermost
// corners are then at least h outside the box that holds the surface, where the field is positive,
// so every surface the box holds comes out closed.
//
// Sparse. The grid is visited as an octree of blocks of 2^k cells. A field never overestimates
// (docs/design.md, rule 2: it is 1-Lipschitz), so with d the distance at a block's centre and r
// its half-diagonal, |d| > r means every point of the block has the sign of d: no corner of any
// cell in it changes sign and the block holds no triangle. It is skipped whole, after one
// evaluation. Only blocks the surface may cross are divided, so the cost grows with the surface's
// area over h^2 (about 4x per doubling of the resolution), not with the volume (8x). The skip
// is exact, not a heuristic: the sparse mesh equals the dense one (every cell visited) triangle
// for triangle (tests/test_mesh.cpp). A float margin of 1e-5 r keeps the rounding of d on the
// safe side.
//
// Triangles. Each cell is cut into the six tetrahedra around its main diagonal (corner 0 to
// corner 7 along x, y, z in every order: the Kuhn triangulation). A face shared by two cells is
// cut along the same diagonal from both (from its lowest to its highest corner), so the
// triangles of neighbouring cells meet edge to edge. Inside is d < 0. A tetrahedron with one (or
// three) corners inside holds one triangle, with two a quad (two triangles); its vertices lie on
// the tetrahedron's edges that change sign. A vertex is keyed by its grid edge (lower corner,
// direction), so every cell that touches an edge finds the same vertex: the mesh is a closed,
// oriented 2-manifold by construction, whatever the field does between samples (no ambiguous
// case, unlike marching cubes' face saddles). Orientation is decided exactly, in integers, from
// the edges' midpoints: the triangle's normal points from the inside corners to the outside ones.
//
// Shared corners. Each corner of the grid belongs to up to 8 cells; evaluated per cell, a surface
// cell costs 8 evaluations where its share is about 1. A block of 2 x 2 x 2 cells that is not
// skipped has every cell meshed, so it evaluates its 27 corners once (64 per cell before) and
// meshes its cells from that table in the same order as before: the same numbers at the same
// points give the same mesh, vertex for vertex (tests/test_mesh.cpp, bench_mesh).
//
// Vertices. A vertex is first placed on the zero of d along its edge (the corners' distances
// have opposite signs and d is continuous, so the edge holds one: bracketed regula falsi, which
// works for any field, exact distance or bound, creased or smooth). It then takes
// `projection_steps` Newton steps towards the nearest point of the zero set along the gradient
// (central differences, step h / 1000, in double):
//     p <- p - d(p) grad d / |grad d|^2,
// each kept only if it lowers |d| and stays within h of the edge's point (near a crease, where
// the gradient jumps, a step may overshoot). Where the field is the exact distance and smooth,
// each step squares the error. The normal is the gradient there.
//
// Attributes. `attributes` asks for per-vertex uv (mesh_attribute::uv) and colour by kernel
// (mesh_attribute::kernel_color), for a field with a `locate` (a sequence: the nearest kernel and
// the point in its own space, Algorithm 1 recording where the minimum was found). Each placed
// vertex is located (in double, from its stored float position, so a reader who locates the
// written vertex finds the same kernel); its uv is that kernel's uv() at the kernel-space point
// ((0, 0) for kinds without one), its colour kernel_color(index). A field without `locate` asking
// for attributes is refused by name before any work.
//
// Budget. The mesh and its edge table grow as the surface is found; `memory_budget` (bytes) is
// checked after every cell, so an over-fine resolution is refused with an invalid_parameter naming
// mesh_options.memory_budget and what was reached, before it can take more than one cell's worth
// (at most 12 triangles) beyond it. A field returning NaN or infinity is refused by name too.
//
// Up front. That check refuses only after the work up to the budget is done. With
// `estimate_first` (the default), a coarse pass first meshes the same box at resolution / f, f the
// largest of 4 and 2 that keeps it >= 8 cells (none below 16: such a mesh is small anyway), without
// placing vertices, and counts its bytes as the growth check does. A surface's triangles (and
// vertices, and so bytes) grow with its area over h^2, about f^2 from the coarse grid to the full
// one (3.9-4.2x per doubling on torus and rock), so the full mesh is estimated at
// coarse bytes x (resolution / coarse resolution)^2 and refused, before any full-resolution cell,
// with the estimate and the budget when that exceeds the budget by more than `estimate_slack`
// (1/4). Measured estimate / true bytes: sphere and torus 0.82-1.00 at resolutions 16-256, the
// rock 0.96-1.06, the Menger sponge 0-0.50 (detail finer than the coarse cells, 10.6x per
// doubling, is missed: at resolution 24 the coarse grid sees none of it). A smooth surface's
// estimate is thus within a few percent of the truth, above it by at most 6.4% (the rock), which
// the slack absorbs so that a mesh that fits is not refused by the estimate; detail the coarse grid
// misses only makes the estimate lower. So the estimate cannot be trusted to refuse every mesh
// that does not fit: it catches the gross cases cheaply (the coarse pass costs about 1/f^2 of the
// full one's meshing, and places no vertices), and the growth check stays the guarantee. The
// coarse pass has its own budget, budget x (1 + slack) / f^2: going over it already means the
// estimate is over, so it stops there and never takes more than about 1/f^2 of the budget.

#include "krs/core/bounds.hpp"
#include "krs/core/validate.hpp"
#include "krs/field.hpp"
#include "krs/mesh/mesh.hpp"
#include "krs/trace/box_clip.hpp" // field_box

#include <algorithm>
#include <array>
#include <cmath>
#include <cstddef>
#include <cstdint>
#include <functional>
#include <limits>
#include <string>
#include <unordered_map>
#include <variant>
#include <vector>

namespace krs {

// The most cells along the box's longest side: grid corner indices then fit in 17 bits per axis,
// and an edge key (corner index * 8 + direction) in 64 bits with room to spare.
inline constexpr int max_mesh_resolution = 1 << 16;

// Per-vertex attributes mesh_options::attributes can ask for (bits, combined with |).
namespace mesh_attribute {
inline constexpr unsigned uv = 1;           // the kernel's (u, v) at the vertex: triangle_mesh::uvs
inline constexpr unsigned kernel_color = 2; // kernel_color(kernel index): triangle_mesh::colors
inline constexpr unsigned all = uv | kernel_color;
} // namespace mesh_attribute

// What an extraction reports while it works (mesh_options::progress), so a caller can show that a
// long one is alive: which pass runs, the fraction of it done, the full grid, and the estimate once
// the coarse pass has made it. Each pass reports its start (done 0) before any work, then at most
// once per percent, and its end (done 1). The passes, in order: `estimate` (the coarse pass of Up front above, with
// estimate_first), `cells` (the full grid's cells meshed), `vertices` (each vertex placed on the
// surface). The library prints nothing; the caller decides what to show.
enum class mesh_stage { estimate, cells, vertices };
struct mesh_report {
    mesh_stage stage = mesh_stage::cells;
    double done = 0;                           // the fraction of this pass done, in [0, 1]
    std::size_t cells_per_axis[3] = {0, 0, 0}; // the full-resolution grid (padded)
    int coarse_resolution = 0;                 // the estimate's pass (0: none)
    double estimated_bytes = 0;                // the full mesh's estimate (0 until it is made)
};

struct mesh_options {
    int resolution = 64;         // cells along the box's longest side: [1, max_mesh_resolution]
    int projection_steps = 4;    // Newton steps onto the zero set per vertex: [0, 64]
    std::size_t memory_budget = std::size_t(1) << 30; // bytes for the mesh and its edge table: > 0
    unsigned attributes = 0;     // mesh_attribute bits; any needs a field with locate (a sequence)
    bool sparse = true;          // skip blocks by their centre's distance; false visits every cell
    bool share_corners = true;   // sparse: a block of 2^3 cells evaluates its 27 corners once (false:
                                 // each cell its own 8, as before; kept for bench_mesh's comparison)
    bool estimate_first = true;  // refuse up front from a coarse pass's estimate (see Up front above)
    bounding_box box = bounding_box::unbounded(); // where to mesh; unbounded: the field's own box
    // Called at the start of each pass and now and then during it (mesh_report above).
    std::function<void(const mesh_report&)> progress;

    void validate() const
    {
        if (resolution < 1 || resolution > max_mesh_resolution)
            throw invalid_parameter("mesh_options.resolution", "must be in [1, " + std::to_string(max_mesh_resolution) + "]",
                                    std::to_string(resolution));
        if (projection_steps < 0 || projection_steps > 64)
            throw invalid_parameter("mesh_options.projection_steps", "must be in [0, 64]", std::to_string(projection_steps));
        if (memory_budget == 0) throw invalid_parameter("mesh_options.memory_budget", "must be > 0 bytes", "0");
        if (attributes & ~mesh_attribute::all)
            throw invalid_parameter("mesh_options.attributes", "must combine mesh_attribute::uv (1) and kernel_color (2)",
                                    std::to_string(attributes));
    }
};

// What an extraction did, for benchmarks and tests.
struct mesh_stats {
    std::size_t cells_per_axis[3] = {0, 0, 0}; // the padded grid
    double cell_size = 0;
    std::size_t blocks_visited = 0;  // octree blocks whose centre was evaluated
    std::size_t cells_meshed = 0;    // leaf cells whose corners were evaluated
    std::size_t evaluations = 0;     // field evaluations, projection included
    std::size_t peak_bytes = 0;      // mesh plus edge table at the end (what the budget counts)
    // The least distance evaluated. The field is 1-Lipschitz and skipped blocks keep their sign,
    // so with no triangle it is >= lowest_distance - cell_size sqrt(3) / 2 everywhere in the grid.
    double lowest_distance = std::numeric_limits<double>::infinity();
};

namespace detail {

// The estimate may exceed the budget by this fraction before it refuses (see Up front above).
inline constexpr double estimate_slack = 0.25;

// The coarse pass's divisor f: 4, or 2 where resolution / 4 < 8 cells; 1 (no coarse pass) below 16.
inline int estimate_factor(int resolution)
{
    int factor = 4;
    while (factor > 1 && resolution / factor < 8) factor /= 2;
    return factor;
}

template <field F>
class mesh_extractor {
public:
    mesh_extractor(const F& f, const mesh_options& o) : f_(f), o_(o)
    {
        o.validate();
        if (o.attributes != 0 && !locates)
            throw invalid_parameter("mesh_options.attributes",
                                    "needs a field that locates its kernels (a sequence: uv and kernel colours come from its kernels)",
                                    std::to_string(o.attributes));
        // The default (every side infinite) asks for the field's box; any other is the user's,
        // checked by name (a NaN or half-infinite box is not quietly replaced).
        const bounding_box none = bounding_box::unbounded();
        const bool given = !(o.box.lo.x == none.lo.x && o.box.lo.y == none.lo.y && o.box.lo.z == none.lo.z &&
                             o.box.hi.x == none.hi.x && o.box.hi.y == none.hi.y && o.box.hi.z == none.hi.z);
        if (given) check_box(o.box, "mesh_options.box");
        const bounding_box box = given ? o.box : field_box(f);
        if (!box.is_bounded())
            throw invalid_parameter("mesh_options.box", "is needed for a field without a bounded box (the field reports none)");
        check_box(box, "mesh_options.box");
        const vec3d lo(box.lo), hi(box.hi), ext = hi - lo;
        const double longest = std::max({ext.x, ext.y, ext.z});
        if (!(longest > 0)) throw invalid_parameter("mesh_options.box", "must have a side longer than 0", to_text(box));
        h_ = longest / double(o.resolution);
        origin_ = lo - vec3d{h_, h_, h_}; // one cell of padding below
        const double e[3] = {ext.x, ext.y, ext.z};
        for (int a = 0; a < 3; ++a) n_[a] = std::int64_t(std::ceil(e[a] / h_ - 1e-9)) + 2; // and above
        stats_.cell_size = h_;
        for (int a = 0; a < 3; ++a) stats_.cells_per_axis[a] = std::size_t(n_[a]);
    }

    // The coarse pass: the grid meshed without placing vertices; the bytes the growth check counts
    // at the end, or throws over_budget past `counting_budget`.
    struct over_budget {};
    std::size_t count(std::size_t budget)
    {
        counting_budget_ = budget;
        begin(mesh_stage::estimate);
        grid();
        return bytes();
    }

    // The grid as the constructor sized it (cells per axis, cell size), before any pass.
    void describe(mesh_stats& out) const { out = stats_; }
    // The coarse pass's estimate, carried by the full passes' reports.
    void estimated(int coarse_resolution, double bytes) { coarse_resolution_ = coarse_resolution, estimated_bytes_ = bytes; }

    triangle_mesh run(mesh_stats* stats)
    {
        begin(mesh_stage::cells);
        grid();
        begin(mesh_stage::vertices);
        project();
        report(1);
        if constexpr (locates) add_attributes();
        stats_.peak_bytes = bytes();
        if (stats) *stats = stats_;
        return std::move(mesh_);
    }

private:
    void grid()
    {
        if (o_.sparse) {
            std::int64_t size = 1;
            while (size < n_[0] || size < n_[1] || size < n_[2]) size *= 2;
            root_ = size;
            visit(0, 0, 0, size);
            report(1); // the last blocks may lie beyond the grid, which visit() counts unreported
        } else {
            for (std::int64_t k = 0; k < n_[2]; ++k) {
                for (std::int64_t j = 0; j < n_[1]; ++j)
                    for (std::int64_t i = 0; i < n_[0]; ++i) cell(i, j, k);
                report(double(k + 1) / double(n_[2]));
            }
        }
    }

    static constexpr bool locates = requires(const F& f, const vec3d& p) {
        { f.locate(p).kernel_point } -> std::convertible_to<vec3d>;
        f.kernels()[f.locate(p).kernel];
    };

    void add_attributes()
    {
        if constexpr (locates) {
            const bool uv = (o_.attributes & mesh_attribute::uv) != 0, color = (o_.attributes & mesh_attribute::kernel_color) != 0;
            if (uv) mesh_.uvs.resize(mesh_.positions.size());
            if (color) mesh_.colors.resize(mesh_.positions.size());
            for (std::size_t v = 0; v < mesh_.positions.size() && (uv || color); ++v) {
                const auto where = f_.locate(vec3d(mesh_.positions[v]));
                ++stats_.evaluations;
                if (color) mesh_.colors[v] = kernel_color(where.kernel);
                if (uv)
                    mesh_.uvs[v] = std::visit(
                        [&](const auto& kernel) -> std::array<float, 2> {
                            if constexpr (requires { kernel.uv(where.kernel_point); }) {
                                const auto t = kernel.uv(where.kernel_point);
                                return {float(t.u), float(t.v)};
                            } else {
                                return {0.0f, 0.0f};
                            }
                        },
                        f_.kernels()[where.kernel]);
            }
        }
    }

    static std::string to_text(const bounding_box& b) { return detail::to_text(b.lo) + " .. " + detail::to_text(b.hi); }
    static void check_box(const bounding_box& b, const char* name)
    {
        const float v[6] = {b.lo.x, b.lo.y, b.lo.z, b.hi.x, b.hi.y, b.hi.z};
        for (float x : v)
            if (!std::isfinite(x) || std::abs(x) > max_magnitude)
                throw invalid_parameter(name, "must have finite corners within " + std::string(max_magnitude_text) + " of 0",
                                        to_text(b));
        if (!(b.lo.x <= b.hi.x && b.lo.y <= b.hi.y && b.lo.z <= b.hi.z))
            throw invalid_parameter(name, "must have lo <= hi on every axis", to_text(b));
    }

    vec3d corner_point(std::int64_t i, std::int64_t j, std::int64_t k) const
    {
        return {origin_.x + double(i) * h_, origin_.y + double(j) * h_, origin_.z + double(k) * h_};
    }

    double eval(const vec3d& p)
    {
        ++stats_.evaluations;
        const double d = f_.distance(p);
        stats_.lowest_distance = std::min(stats_.lowest_distance, d);
        if (!std::isfinite(d)) throw invalid_parameter("field", "returned a distance that is not finite at " + detail::to_text(p), detail::to_text(d));
        return d;
    }

    // A pass begins: reported at once (done 0), whatever its first cell costs.
    void begin(mesh_stage stage)
    {
        stage_ = stage;
        reported_ = -1;
        report(0);
    }
    void report(double done)
    {
        if (o_.progress && (done >= reported_ + 0.01 || (done == 1 && reported_ < 1))) {
            reported_ = done;
            mesh_report r;
            r.stage = stage_;
            r.done = done;
            for (int a = 0; a < 3; ++a) r.cells_per_axis[a] = std::size_t(n_[a]);
            r.coarse_resolution = coarse_resolution_;
            r.estimated_bytes = estimated_bytes_;
            o_.progress(r);
        }
    }

    // An octree block of `size` cells per side with its lowest cell at (i, j, k).
    void visit(std::int64_t i, std::int64_t j, std::int64_t k, std::int64_t size)
    {
        if (i >= n_[0] || j >= n_[1] || k >= n_[2]) { // beyond the grid (the root is a power of 2)
            done_ += double(size) * double(size) * double(size);
            return;
        }
        if (size == 1) {
            cell(i, j, k);
        } else if (size == 2 && o_.share_corners) {
            ++stats_.blocks_visited;
            const vec3d c = corner_point(i + 1, j + 1, k + 1);
            const double reach = h_ * std::sqrt(3.0);
            if (std::abs(eval(c)) > reach * (1.0 + 1e-5)) {
                done_ += 8;
            } else {
                std::array<double, 27> corner; // (x, y, z) in {0, 1, 2}^3 at x + 3 y + 9 z
                for (int z = 0; z < 3; ++z)
                    for (int y = 0; y < 3; ++y)
                        for (int x = 0; x < 3; ++x) corner[std::size_t(x + 3 * y + 9 * z)] = eval(corner_point(i + x, j + y, k + z));
                for (int child = 0; child < 8; ++child) { // visit()'s order of the eight children
                    const int cx = child & 1, cy = child >> 1 & 1, cz = child >> 2 & 1;
                    if (i + cx >= n_[0] || j + cy >= n_[1] || k + cz >= n_[2]) {
                        done_ += 1;
                        continue;
                    }
                    std::array<double, 8> d;
                    for (int b = 0; b < 8; ++b)
                        d[std::size_t(b)] = corner[std::size_t((cx + (b & 1)) + 3 * (cy + (b >> 1 & 1)) + 9 * (cz + (b >> 2 & 1)))];
                    mesh_cell(i + cx, j + cy, k + cz, d);
                }
            }
        } else {
            ++stats_.blocks_visited;
            const double half = 0.5 * double(size) * h_;
            const vec3d c = corner_point(i, j, k) + vec3d{half, half, half};
            const double reach = half * std::sqrt(3.0);
            if (std::abs(eval(c)) > reach * (1.0 + 1e-5)) {
                done_ += double(size) * double(size) * double(size);
            } else {
                const std::int64_t s = size / 2;
                for (int child = 0; child < 8; ++child)
                    visit(i + (child & 1 ? s : 0), j + (child & 2 ? s : 0), k + (child & 4 ? s : 0), s);
                return; // the children counted their own volume
            }
        }
        report(done_ / (double(root_) * double(root_) * double(root_)));
    }

    std::uint64_t corner_id(std::int64_t i, std::int64_t j, std::int64_t k) const
    {
        return std::uint64_t(i) + std::uint64_t(n_[0] + 1) * (std::uint64_t(j) + std::uint64_t(n_[1] + 1) * std::uint64_t(k));
    }

    void cell(std::int64_t i, std::int64_t j, std::int64_t k)
    {
        // Corner c (bits x = 1, y = 2, z = 4).
        std::array<double, 8> d;
        for (int c = 0; c < 8; ++c) d[std::size_t(c)] = eval(corner_point(i + (c & 1), j + (c >> 1 & 1), k + (c >> 2 & 1)));
        mesh_cell(i, j, k, d);
    }

    // The triangles of cell (i, j, k) from its corners' distances d (corner c: bits x = 1, y = 2, z = 4).
    void mesh_cell(std::int64_t i, std::int64_t j, std::int64_t k, const std::array<double, 8>& d)
    {
        if (o_.sparse) done_ += 1;
        ++stats_.cells_meshed;
        int inside = 0;
        for (int c = 0; c < 8; ++c)
            if (d[std::size_t(c)] < 0) inside |= 1 << c;
        if (inside == 0 || inside == 0xff) return;
        static constexpr int axes[6][3] = {{0, 1, 2}, {0, 2, 1}, {1, 0, 2}, {1, 2, 0}, {2, 0, 1}, {2, 1, 0}};
        for (const auto& perm : axes) {
            // Corners along the monotone path 0 -> e_a -> e_a + e_b -> 7: each holds the bits of
            // the ones before it, so every edge of the tetrahedron points up its lower corner.
            const int t[4] = {0, 1 << perm[0], (1 << perm[0]) | (1 << perm[1]), 7};
            int in[4], out[4], n_in = 0, n_out = 0;
            for (int v = 0; v < 4; ++v) (inside >> t[v] & 1 ? in[n_in++] : out[n_out++]) = t[v];
            if (n_in == 0 || n_out == 0) continue;
            if (n_in == 1) {
                triangle(i, j, k, d, {in[0], out[0]}, {in[0], out[1]}, {in[0], out[2]}, in[0], out[0]);
            } else if (n_out == 1) {
                triangle(i, j, k, d, {in[0], out[0]}, {in[1], out[0]}, {in[2], out[0]}, in[0], out[0]);
            } else {
                // The quad in[0]-out[0], in[0]-out[1], in[1]-out[1], in[1]-out[0] (a cycle).
                triangle(i, j, k, d, {in[0], out[0]}, {in[0], out[1]}, {in[1], out[1]}, in[0], out[0]);
                triangle(i, j, k, d, {in[0], out[0]}, {in[1], out[1]}, {in[1], out[0]}, in[0], out[0]);
            }
        }
        check_budget();
    }

    struct edge {
        int a, b; // cell corners (bit patterns), one inside and one outside
    };
    // Each vertex's edge until it is placed: its lower and upper corner and their distances.
    struct pending {
        vec3d p, q;
        double dp, dq;
    };

    // The triangle on edges e0, e1, e2 of a tetrahedron in cell (i, j, k), turned so that its
    // normal points from corner `in` (inside) to corner `out` (outside).
    void triangle(std::int64_t i, std::int64_t j, std::int64_t k, const std::array<double, 8>& d, edge e0, edge e1, edge e2,
                  int in, int out)
    {
        // Exact orientation: the edges' midpoints, in units of half a cell (2 x corner bits), and
        // the corners in the same units (4 x bits); the triangle's plane through the midpoints
        // separates the inside corners of the tetrahedron from the outside ones.
        const auto mid = [](edge e) {
            return std::array<std::int64_t, 3>{(e.a & 1) + (e.b & 1), (e.a >> 1 & 1) + (e.b >> 1 & 1), (e.a >> 2 & 1) + (e.b >> 2 & 1)};
        };
        const auto m0 = mid(e0), m1 = mid(e1), m2 = mid(e2);
        const std::int64_t u[3] = {m1[0] - m0[0], m1[1] - m0[1], m1[2] - m0[2]};
        const std::int64_t v[3] = {m2[0] - m0[0], m2[1] - m0[1], m2[2] - m0[2]};
        const std::int64_t n[3] = {u[1] * v[2] - u[2] * v[1], u[2] * v[0] - u[0] * v[2], u[0] * v[1] - u[1] * v[0]};
        const std::int64_t w[3] = {2 * ((out & 1) - (in & 1)), 2 * ((out >> 1 & 1) - (in >> 1 & 1)), 2 * ((out >> 2 & 1) - (in >> 2 & 1))};
        const bool flip = n[0] * w[0] + n[1] * w[1] + n[2] * w[2] < 0;
        const std::uint32_t a = vertex(i, j, k, d, e0), b = vertex(i, j, k, d, e1), c = vertex(i, j, k, d, e2);
        mesh_.triangles.push_back(flip ? std::array<std::uint32_t, 3>{a, c, b} : std::array<std::uint32_t, 3>{a, b, c});
    }

    // The vertex on a cell's edge, shared by every cell that has the edge: keyed by the edge's
    // lower corner (its grid index) and its direction (the corner bits it adds, 1 to 7).
    std::uint32_t vertex(std::int64_t i, std::int64_t j, std::int64_t k, const std::array<double, 8>& d, edge e)
    {
        const int lo = (e.a & e.b) == e.a ? e.a : e.b, hi = lo == e.a ? e.b : e.a;
        const std::uint64_t key = corner_id(i + (lo & 1), j + (lo >> 1 & 1), k + (lo >> 2 & 1)) * 8 + std::uint64_t(hi ^ lo);
        const auto [it, added] = vertex_of_edge_.try_emplace(key, std::uint32_t(mesh_.positions.size()));
        if (added) {
            // From the lower corner whichever cell asks: the same numbers give the same point.
            const vec3d p = corner_point(i + (lo & 1), j + (lo >> 1 & 1), k + (lo >> 2 & 1));
            const vec3d q = corner_point(i + (hi & 1), j + (hi >> 1 & 1), k + (hi >> 2 & 1));
            edges_.push_back({p, q, d[lo], d[hi]});
            mesh_.positions.emplace_back();
        }
        return it->second;
    }

    std::size_t bytes() const
    {
        // An unordered_map node: key, value, next pointer and cached hash, plus a bucket pointer.
        constexpr std::size_t per_edge = sizeof(std::uint64_t) * 2 + sizeof(void*) * 2 + sizeof(std::size_t);
        return mesh_.bytes() + edges_.size() * sizeof(pending) + mesh_.positions.size() * sizeof(vec3f) // normals to come
               + vertex_of_edge_.size() * per_edge;
    }

    void check_budget()
    {
        const std::size_t used = bytes();
        if (counting_budget_ != 0) {
            if (used > counting_budget_) throw over_budget{};
            return;
        }
        if (used > o_.memory_budget)
            throw invalid_parameter("mesh_options.memory_budget",
                                    "exceeded after " + std::to_string(mesh_.triangles.size()) + " triangles and " +
                                        std::to_string(mesh_.positions.size()) + " vertices at resolution " +
                                        std::to_string(o_.resolution) + " (" + std::to_string(used) +
                                        " bytes); raise the budget or lower mesh_options.resolution",
                                    std::to_string(o_.memory_budget));
    }

    vec3d gradient(const vec3d& p, double step)
    {
        const vec3d ex{step, 0, 0}, ey{0, step, 0}, ez{0, 0, step};
        return vec3d{eval(p + ex) - eval(p - ex), eval(p + ey) - eval(p - ey), eval(p + ez) - eval(p - ez)} / (2 * step);
    }

    // The zero of d on the edge from p (d = dp) to q (d = dq, of the other sign): d is continuous,
    // so the bracket always holds one. Regula falsi with the Illinois rule (the end that stays is
    // halved in weight, so the bracket shrinks from both sides): superlinear, and never outside
    // the edge. 16 steps, or until |d| <= 1e-9 h.
    vec3d root_on_edge(const pending& e)
    {
        double a = 0, b = 1, da = e.dp, db = e.dq;
        int kept = 0; // which end stayed last time: -1 a, +1 b
        vec3d x = e.p + (e.q - e.p) * std::clamp(da / (da - db), 0.0, 1.0);
        for (int s = 0; s < 16; ++s) {
            const double t = std::clamp((a * db - b * da) / (db - da), a, b);
            x = e.p + (e.q - e.p) * t;
            const double dx = eval(x);
            if (std::abs(dx) <= 1e-9 * h_) break;
            if ((dx < 0) == (da < 0)) {
                a = t, da = dx;
                if (kept == 1) db *= 0.5;
                kept = 1;
            } else {
                b = t, db = dx;
                if (kept == -1) da *= 0.5;
                kept = -1;
            }
        }
        return x;
    }

    void project()
    {
        const double step = h_ * 1e-3;
        mesh_.normals.resize(mesh_.positions.size());
        for (std::size_t v = 0; v < edges_.size(); ++v) {
            if (v % 4096 == 0) report(double(v) / double(edges_.size()));
            const vec3d start = root_on_edge(edges_[v]);
            vec3d p = start;
            double dp = eval(p);
            vec3d g = gradient(p, step);
            for (int s = 0; s < o_.projection_steps && dp != 0; ++s) {
                const double gg = length_squared(g);
                if (!(gg > 1e-12)) break;
                const vec3d next = p - g * (dp / gg);
                if (!(length(next - start) <= h_)) break;
                const double dn = eval(next);
                if (!(std::abs(dn) < std::abs(dp))) break;
                p = next;
                dp = dn;
                g = gradient(p, step);
            }
            mesh_.positions[v] = vec3f(p);
            const double gl = length(g);
            mesh_.normals[v] = gl > 0 ? vec3f(g / gl) : vec3f{0, 0, 1};
        }
    }

    const F& f_;
    const mesh_options& o_;
    double h_ = 0;
    vec3d origin_{};
    std::int64_t n_[3] = {0, 0, 0};
    std::int64_t root_ = 1;
    double done_ = 0, reported_ = 0;
    mesh_stage stage_ = mesh_stage::cells;
    int coarse_resolution_ = 0;
    double estimated_bytes_ = 0;
    std::size_t counting_budget_ = 0; // > 0: the coarse pass (count), with this budget
    triangle_mesh mesh_;
    std::vector<pending> edges_;
    std::unordered_map<std::uint64_t, std::uint32_t> vertex_of_edge_;
    mesh_stats stats_;
};

} // namespace detail

// The zero set of `f` as a closed, oriented triangle mesh (see above). Throws invalid_parameter
// for bad options, a field without a box when none is given, a non-finite distance, or a mesh
// that would exceed options.memory_budget (estimated up front, then checked as it grows).
template <field F>
triangle_mesh extract_mesh(const F& f, const mesh_options& options = {}, mesh_stats* stats = nullptr)
{
    detail::mesh_extractor<F> x(f, options); // validates the options before any pass
    const int factor = detail::estimate_factor(options.resolution);
    if (options.estimate_first && factor > 1) {
        mesh_options coarse = options;
        coarse.resolution = options.resolution / factor;
        coarse.attributes = 0;
        // The coarse pass reports as the estimate's stage of the full mesh: its grid is the full one.
        mesh_stats full_grid;
        x.describe(full_grid);
        if (options.progress)
            coarse.progress = [&](const mesh_report& r) {
                mesh_report full = r;
                for (int a = 0; a < 3; ++a) full.cells_per_axis[a] = full_grid.cells_per_axis[a];
                full.coarse_resolution = coarse.resolution;
                options.progress(full);
            };
        const double scale = double(options.resolution) / double(coarse.resolution);
        const double refuse_above = double(options.memory_budget) * (1.0 + detail::estimate_slack);
        const std::size_t coarse_budget = std::size_t(std::min(refuse_above / (scale * scale), 1e18)) + 1;
        double estimate = 0;
        std::string counted;
        try {
            detail::mesh_extractor<F> c(f, coarse);
            const std::size_t b = c.count(coarse_budget);
            estimate = double(b) * scale * scale;
            counted = std::to_string(b) + " bytes";
        } catch (const typename detail::mesh_extractor<F>::over_budget&) {
            estimate = double(coarse_budget) * scale * scale;
            counted = "over " + std::to_string(coarse_budget) + " bytes";
        }
        if (estimate > refuse_above)
            throw invalid_parameter("mesh_options.memory_budget",
                                    "is below the mesh's estimated size at resolution " + std::to_string(options.resolution) + ": " +
                                        std::string(counted[0] == 'o' ? "at least " : "") + std::to_string(std::size_t(estimate)) +
                                        " bytes (a pass at resolution " +
                                        std::to_string(coarse.resolution) + " counted " + counted + ", times " +
                                        std::to_string(int(scale * scale + 0.5)) +
                                        "); raise the budget or lower mesh_options.resolution",
                                    std::to_string(options.memory_budget));
        x.estimated(coarse.resolution, estimate);
    }
    return x.run(stats);
}

} // namespace krs

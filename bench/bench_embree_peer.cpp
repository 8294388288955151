// bench_embree_peer: the same KRS scene traced two ways, as issue 9 asks. The KRS side is the
// packet tracer on the sequence itself (O(n) distance, memory independent of 2^n); the Embree side
// is what a user without this library would do: tessellate each kernel, expand the sequence into
// its 2^n instance transforms and trace triangles with Embree 3.
//
//     bench_embree_peer [--size N] [--max-n N] [--embree-max-n N] [--budget-gib G] [--tolerance T]
//                       [--repeat R] [--csv FILE] [--scene grid|unaligned|both] [--krs-floor F]
//     bench_embree_peer --boxes [--size N] [--max-n N] [--repeat R] [--scene ...]
//     bench_embree_peer --stream [--size N] [--max-n N] [--repeat R] [--scene ...]
//
// Scenes: a ring (a krs::torus) around a sphere, copied 2^n times by n
// vertical mirrors (krs::sequence, so krs::expand applies): `grid` with x- and z-normal mirrors,
// `unaligned` with each normal turned by up to 10 degrees (ring_scene below); both seen whole
// from above at an angle. n = 8, 10, ... max-n (default 32); Embree runs up to --embree-max-n
// (default 22). Each image is N x N primary rays (default 512) in 16 x 16 tiles taken from a
// shared counter by 2 threads (this machine's cores). Timings are the best of R runs (default 3).
// The table is printed per scene; the CSV (default bench_embree_peer.csv next to the binary) has
// one row per scene and n.
//
// Embree configurations (Debian's build: one instance level):
//   flat       one instance of the level-0 kernel set's mesh per copy (2^n instances);
//   two-level  a bottom mesh of 2^k expanded copies, instanced 2^(n-k) times; k in
//              {n/2 - 2, n/2, n/2 + 2}, the fastest is reported.
// Each is traced with rtcIntersect1 and rtcIntersect16 (4 x 4 pixel packets). Memory is what
// Embree reports through its device memory monitor plus the application's expansion, or the RSS
// growth when that is larger (the monitor does not see Embree's per-geometry objects: at n = 22
// flat, about 0.6 GB reported against 2 GB resident). A configuration stops when its memory
// passes the budget (default 8 GiB), and that is printed.
//
// Agreement: the share of pixels whose hit/miss matches the KRS render with a faithful threshold
// (pixel_footprint = 0, a fixed floor well under the tessellation tolerance, max_steps 4096). The
// pixel-footprint threshold (0.5 px) is timed separately, with its coverage error against the
// faithful render.
//
// --stream (issue 23, items 1 and 4) runs no Embree: at n = 16 and 32, on the grid (axis mirrors)
// and the unaligned scene (general mirrors), the 0.5 px render (rays clipped to the box) by the
// packet stream before issue 23 and by today's, in alternating rounds, and where today's time goes
// (bench/support/stream_compare.hpp).
//
// --boxes (issue 23, item 2) runs no Embree: per n it traces the tuned KRS render twice, with
// rays clipped to the sequence's box (its kernels' exact boxes through the mirrors) and to the
// box the kernels' bounding spheres give through the same mirrors (the box before issue 23),
// alternately within each of the R repeats (the first of the two swapping every repeat), and
// prints the share of rays that enter each box, field evaluations per ray and Mrays/s (best of
// R) side by side.

#include "support/stream_compare.hpp"
#include "support/text.hpp"
#include "krs/expansion.hpp"
#include "krs/kernels/sphere.hpp"
#include "krs/kernels/torus.hpp"
#include "krs/trace/camera.hpp"
#include "krs/trace/packet_trace.hpp"
#include "krs/trace/tile_rays.hpp"

#include <embree3/rtcore.h>

#include <benchmark/benchmark.h>

#include <algorithm>
#include <atomic>
#include <chrono>
#include <cmath>
#include <cstdarg>
#include <cstdio>
#include <cstdlib>
#include <fstream>
#include <numbers>
#include <optional>
#include <random>
#include <array>
#include <malloc.h>
#include <string>
#include <thread>
#include <unistd.h>
#include <vector>

namespace {

using krs::vec3d;
using krs::vec3f;
using scene_sequence = krs::sequence<krs::torus, krs::sphere>;
// The grid's mirrors are axis-aligned: the scene says so in its type and folds with one min.
using grid_sequence = krs::axis_sequence<krs::torus, krs::sphere>;

constexpr int thread_count = 2;
// Tiles of 16 x 16 pixels from a shared counter, for both renderers (Embree's 4 x 4 packets tile it).
constexpr int tile = 16;
constexpr double mib = 1024.0 * 1024.0;

// ---- settings ----------------------------------------------------------------------------------

struct settings {
    int size = 512;
    int max_n = 32;
    int embree_max_n = 22;
    double budget_bytes = 8.0 * 1024 * mib;
    double tolerance = 0.02; // tessellation: largest deviation, as a share of the tube radius
    int repeats = 3;
    std::string csv_path;
    std::string scene = "both";
    float krs_floor = 1e-3f; // the faithful KRS threshold's floor, in scene units
    bool boxes = false;      // compare the clip boxes instead of running Embree
    bool stream = false;     // compare the packet streams instead of running Embree
};

// ---- scene -------------------------------------------------------------------------------------

constexpr float ring_radius = 1.0f, tube_radius = 0.2f, core_radius = 0.35f, spacing = 3.0f;

struct framing {
    vec3f eye, target;
    float far;
    float extent;
};

// One ring (a torus) standing in the xy plane around a sphere, copied 2^n
// times by n vertical mirrors. Each copy fits a ball of radius 1.2 about its center, and each
// mirror is placed 1.5 beyond the support of the copies so far in its normal's direction, so it
// separates its kernels and both renderers draw the same geometry.
//   grid:      normals x and z alternately; the mirror at (2^j - 1/2) spacing doubles the copies
//              along its axis (a 2^ceil(n/2) x 2^floor(n/2) grid, 3 units apart).
//   unaligned: each normal turned by a random angle within +-10 degrees about y (the paper's
//              section 5 hides the symmetry this way); the copies' centers are tracked as a 2D
//              convex hull to place the next mirror, and copies' bounding boxes overlap.
scene_sequence ring_scene(int n, bool unaligned, framing& view)
{
    scene_sequence::builder b;
    const float r = ring_radius;
    b.kernel(krs::torus({0, 0, 0}, {0, 0, 1}, r, tube_radius)); // an upright ring
    b.kernel(krs::sphere({0, 0, 0}, core_radius));
    using point = std::array<double, 2>; // (x, z)
    std::vector<point> hull{{0.0, 0.0}};
    std::mt19937 random(11);
    std::uniform_real_distribution<double> tilt(-10.0, 10.0);
    for (int i = 0; i < n; ++i) {
        const double angle = (i % 2 == 0 ? 0.0 : 90.0) + (unaligned ? tilt(random) : 0.0);
        // The grid's normals are exactly x and z (cos 90 degrees is 6e-17, not 0, in floating point).
        const double nx = unaligned ? std::cos(angle * std::numbers::pi / 180) : (i % 2 == 0 ? 1.0 : 0.0);
        const double nz = unaligned ? std::sin(angle * std::numbers::pi / 180) : (i % 2 == 0 ? 0.0 : 1.0);
        double support = -1e300;
        for (const point& p : hull) support = std::max(support, nx * p[0] + nz * p[1]);
        const double offset = support + 0.5 * spacing;
        b.mirror(krs::mirror(vec3f{float(nx), 0.0f, float(nz)}, float(offset)));
        const std::size_t count = hull.size();
        for (std::size_t j = 0; j < count; ++j) {
            const double d = 2 * (nx * hull[j][0] + nz * hull[j][1] - offset);
            hull.push_back({hull[j][0] - d * nx, hull[j][1] - d * nz});
        }
        // Andrew's monotone chain keeps the hull small (the grid's has 4 corners).
        std::sort(hull.begin(), hull.end());
        hull.erase(std::unique(hull.begin(), hull.end()), hull.end());
        if (hull.size() > 2) {
            auto cross = [](const point& o, const point& a, const point& c) {
                return (a[0] - o[0]) * (c[1] - o[1]) - (a[1] - o[1]) * (c[0] - o[0]);
            };
            std::vector<point> h(2 * hull.size());
            std::size_t k = 0;
            for (std::size_t j = 0; j < hull.size(); ++j) {
                while (k >= 2 && cross(h[k - 2], h[k - 1], hull[j]) <= 0) --k;
                h[k++] = hull[j];
            }
            for (std::size_t j = hull.size() - 1, lower = k + 1; j-- > 0;) {
                while (k >= lower && cross(h[k - 2], h[k - 1], hull[j]) <= 0) --k;
                h[k++] = hull[j];
            }
            h.resize(k - 1);
            hull = std::move(h);
        }
    }
    double lo[2] = {1e300, 1e300}, hi[2] = {-1e300, -1e300};
    for (const point& p : hull)
        for (int a = 0; a < 2; ++a) lo[a] = std::min(lo[a], p[a]), hi[a] = std::max(hi[a], p[a]);
    const float extent = float(std::max(hi[0] - lo[0], hi[1] - lo[1])) + spacing;
    const vec3f middle{float(0.5 * (lo[0] + hi[0])), 0.0f, float(0.5 * (lo[1] + hi[1]))};
    view = {middle + vec3f{-0.55f * extent, 0.45f * extent, -0.85f * extent}, middle, 4 * extent, extent};
    return b.build();
}

krs::pinhole_camera camera_for(const framing& v, int size)
{
    return krs::pinhole_camera(v.eye, v.target, {0, 1, 0}, 40.0f, size, size);
}

// Faithful: no footprint term, a floor far below the tessellation tolerance (raised with the
// scene's extent only where float coordinates cannot resolve it any more).
krs::trace_options faithful_options(const framing& v, float floor)
{
    krs::trace_options o;
    o.pixel_footprint = 0.0f;
    o.threshold_floor = std::max(floor, 4e-7f * v.extent);
    o.max_distance = v.far;
    o.max_steps = 4096;
    return o.validate();
}
krs::trace_options footprint_options(const krs::pinhole_camera& camera, const framing& v)
{
    krs::trace_options o;
    o.pixel_footprint = 0.5f * camera.pixel_footprint();
    o.threshold_floor = 1e-5f;
    o.max_distance = v.far;
    o.max_steps = 512;
    return o.validate();
}

// ---- tessellation ------------------------------------------------------------------------------

struct mesh {
    std::vector<float> vertices;         // x y z
    std::vector<std::uint32_t> indices;  // three per triangle
    std::size_t triangles() const { return indices.size() / 3; }
    std::uint32_t add(const vec3d& p)
    {
        vertices.insert(vertices.end(), {float(p.x), float(p.y), float(p.z)});
        return std::uint32_t(vertices.size() / 3 - 1);
    }
    void quad(std::uint32_t a, std::uint32_t b, std::uint32_t c, std::uint32_t d)
    {
        indices.insert(indices.end(), {a, b, c, a, c, d});
    }
};

// Segments of a circle of radius r whose inscribed polygon stays within `tolerance` of it.
int circle_segments(double r, double tolerance, double angle = 2 * std::numbers::pi)
{
    if (tolerance >= r) return std::max(3, int(std::ceil(angle / (2 * std::numbers::pi) * 3)));
    const double step = 2 * std::acos(1 - tolerance / r);
    return std::max(3, int(std::ceil(angle / step)));
}

// A ball patch: latitudes from the pole `axis` down to `last_latitude` (pi/2: a hemisphere, pi: the
// whole ball); `around` meridians, the first along `x` (x, y, axis orthonormal).
void add_ball(mesh& m, const vec3d& center, double radius, const vec3d& x, const vec3d& y, const vec3d& axis,
              double last_latitude, int around, double tolerance)
{
    const int rings = std::max(2, circle_segments(radius, tolerance, last_latitude));
    std::vector<std::uint32_t> previous, current;
    for (int i = 0; i <= rings; ++i) {
        const double theta = last_latitude * double(i) / double(rings);
        current.clear();
        for (int j = 0; j < around; ++j) {
            const double phi = 2 * std::numbers::pi * double(j) / double(around);
            const vec3d d = axis * std::cos(theta) + (x * std::cos(phi) + y * std::sin(phi)) * std::sin(theta);
            current.push_back(m.add(center + d * radius));
        }
        if (i > 0)
            for (int j = 0; j < around; ++j)
                m.quad(previous[j], current[j], current[(j + 1) % around], previous[(j + 1) % around]);
        std::swap(previous, current);
    }
}

// The torus: a circle of the tube radius swept around the axis. Vertices lie on the surface, so
// the mesh is inside it by at most `tolerance` (the sagitta of the tube's polygon and of the outer
// edge's polygon around the axis).
void add_torus(mesh& m, const krs::torus& k, double tolerance)
{
    const double R = k.major_radius(), r = k.minor_radius();
    const vec3d axis(k.axis()), center(k.center());
    const vec3d e1 = krs::normalize(krs::cross(axis, std::abs(axis.x) < 0.9 ? vec3d{1, 0, 0} : vec3d{0, 1, 0}));
    const vec3d e2 = krs::cross(axis, e1);
    const int around = circle_segments(r, tolerance), along = circle_segments(R + r, tolerance);
    std::vector<std::uint32_t> first, previous, current;
    for (int i = 0; i < along; ++i) {
        const double s = 2 * std::numbers::pi * double(i) / double(along);
        const vec3d radial = e1 * std::cos(s) + e2 * std::sin(s);
        current.clear();
        for (int j = 0; j < around; ++j) {
            const double phi = 2 * std::numbers::pi * double(j) / double(around);
            current.push_back(m.add(center + radial * R + (radial * std::cos(phi) + axis * std::sin(phi)) * r));
        }
        if (i == 0) first = current;
        else
            for (int j = 0; j < around; ++j) m.quad(previous[j], current[j], current[(j + 1) % around], previous[(j + 1) % around]);
        std::swap(previous, current);
    }
    for (int j = 0; j < around; ++j) m.quad(previous[j], first[j], first[(j + 1) % around], previous[(j + 1) % around]);
}

void add_sphere(mesh& m, const krs::sphere& k, double tolerance)
{
    add_ball(m, vec3d(k.center), k.radius, {1, 0, 0}, {0, 1, 0}, {0, 0, 1}, std::numbers::pi,
             circle_segments(k.radius, tolerance), tolerance);
}

// The level-0 kernel set as one mesh (the scene has kernels on level 0 only).
mesh tessellate_level0(const scene_sequence& s, double tolerance)
{
    mesh m;
    for (std::uint32_t k = s.level_begin(0); k < s.level_begin(1); ++k)
        std::visit(
            [&](const auto& kernel) {
                if constexpr (std::is_same_v<std::decay_t<decltype(kernel)>, krs::torus>)
                    add_torus(m, kernel, tolerance);
                else
                    add_sphere(m, kernel, tolerance);
            },
            s.kernels()[k]);
    return m;
}

// ---- memory ------------------------------------------------------------------------------------

double resident_bytes()
{
    long pages = 0, resident = 0;
    if (FILE* f = std::fopen("/proc/self/statm", "r")) {
        if (std::fscanf(f, "%ld %ld", &pages, &resident) != 2) resident = 0;
        std::fclose(f);
    }
    return double(resident) * double(sysconf(_SC_PAGESIZE));
}

// Embree's allocations as its memory monitor reports them; refuses any that would pass the budget
// (Embree then fails the build with RTC_ERROR_OUT_OF_MEMORY).
struct embree_memory {
    std::atomic<long long> current{0}, peak{0};
    double budget = 0;
    std::atomic<bool> refused{false};

    static bool monitor(void* self_pointer, ssize_t bytes, bool /*post*/)
    {
        auto& self = *static_cast<embree_memory*>(self_pointer);
        const long long now = self.current.fetch_add(bytes) + bytes;
        if (bytes > 0 && double(now) > self.budget) {
            self.current.fetch_sub(bytes);
            self.refused = true;
            return false;
        }
        long long p = self.peak.load();
        while (now > p && !self.peak.compare_exchange_weak(p, now)) {}
        return true;
    }
    void reset() { current = 0, peak = 0, refused = false; }
};

// ---- tracing -----------------------------------------------------------------------------------

struct frame {
    std::vector<std::uint8_t> hit;
    double seconds = 0;
    long long evaluations = 0; // field evaluations (KRS only)
    double mrays() const { return double(hit.size()) / seconds * 1e-6; }
};

// Runs `work(take_tile, hit)` on two threads; take_tile(x0, y0, x1, y1) hands out the next 16 x 16
// tile from a shared counter and returns false when none is left. Best of `repeats`.
template <class Work>
frame render_tiles(int size, int repeats, Work&& work)
{
    const int tiles_x = (size + tile - 1) / tile, tiles = tiles_x * tiles_x;
    frame best;
    for (int r = 0; r < repeats; ++r) {
        frame out;
        out.hit.assign(std::size_t(size) * std::size_t(size), 0);
        std::atomic<int> next{0};
        auto take_tile = [&](int& x0, int& y0, int& x1, int& y1) {
            const int k = next.fetch_add(1);
            if (k >= tiles) return false;
            x0 = (k % tiles_x) * tile, y0 = (k / tiles_x) * tile;
            x1 = std::min(x0 + tile, size), y1 = std::min(y0 + tile, size);
            return true;
        };
        auto worker = [&] { work(take_tile, out.hit.data()); };
        const auto start = std::chrono::steady_clock::now();
        std::vector<std::thread> pool;
        for (int i = 1; i < thread_count; ++i) pool.emplace_back(worker);
        worker();
        for (std::thread& t : pool) t.join();
        out.seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
        benchmark::DoNotOptimize(out.hit.data());
        if (r == 0 || out.seconds < best.seconds) best = std::move(out);
    }
    return best;
}

// The same sequence with axis_mirror levels, when every mirror normal is a coordinate axis.
std::optional<grid_sequence> axis_copy(const scene_sequence& s)
{
    grid_sequence::builder b;
    for (std::size_t level = 0; level <= s.mirror_count(); ++level) {
        for (std::uint32_t k = s.level_begin(level); k < s.level_begin(level + 1); ++k)
            std::visit([&](const auto& kernel) { b.kernel(kernel); }, s.kernels()[k]);
        if (level == s.mirror_count()) break;
        const krs::mirror& m = s.mirrors()[level];
        const float c[3] = {m.normal.x, m.normal.y, m.normal.z};
        int axis = -1;
        for (int a = 0; a < 3; ++a)
            if (std::abs(c[a]) == 1.0f && c[(a + 1) % 3] == 0.0f && c[(a + 2) % 3] == 0.0f) axis = a;
        if (axis < 0) return std::nullopt;
        b.mirror(krs::axis_mirror(axis, c[axis] * m.offset, c[axis] > 0));
    }
    return b.build();
}

// One stream per thread over all of its tiles, so lanes are refilled across tile borders; four
// packets step together (the sequence walks their points in lockstep: on this scene 4 beat 2 by
// about 5% with axis mirrors and 30% with general ones). With `clipped`, every ray is clipped to
// the sequence's bounding box (krs/trace/box_clip.hpp), or to `clip_box` when given. (The tile
// prepass is not used: once rays start at the box, it saved no evaluation on these scenes and cost
// 12% of the time at n = 22.)
template <class Field>
frame render_krs(const Field& s, const krs::pinhole_camera& camera, const krs::trace_options& o, int repeats,
                 bool clipped = false, const std::optional<krs::bounding_box>& clip_box = std::nullopt)
{
    const int size = camera.width();
    const krs::box_clip clip =
        clipped ? krs::box_clip(clip_box ? *clip_box : krs::field_box(s), camera.eye(), o) : krs::box_clip();
    std::atomic<long long> evaluations{0};
    frame out = render_tiles(size, repeats, [&](auto& take_tile, std::uint8_t* hit) {
        int x0 = 0, y0 = 0, x1 = 0, y1 = 0;
        krs::tile_prepass from_near; // every ray from the near distance
        from_near.start = o.min_distance;
        krs::ray_queue<> queue;
        auto more = [&](krs::ray_queue<>& q) {
            if (!take_tile(x0, y0, x1, y1)) return false;
            krs::queue_tile_rays(q, camera, x0, y0, x1, y1, from_near, o.max_distance, clip);
            return true;
        };
        auto done = [&](std::uint32_t id, const krs::hit<float>& h) { hit[id] = h.found ? 1 : 0; };
        evaluations += krs::trace_queue<krs::packet_f, 4>(s, queue, more, done, o).evaluations;
    });
    out.evaluations = evaluations.load() / repeats;
    return out;
}

// rtcIntersect1 per pixel, or rtcIntersect16 per 4 x 4 pixels, over one tile.
void embree_tile(RTCScene scene, const krs::pinhole_camera& camera, float far, bool packets, int x0, int y0, int x1,
                 int y1, std::uint8_t* hit)
{
    const int size = camera.width();
    RTCIntersectContext context;
    rtcInitIntersectContext(&context);
    if (!packets) {
        for (int py = y0; py < y1; ++py)
            for (int px = x0; px < x1; ++px) {
                const krs::ray<float> r = camera.primary_ray(float(px) + 0.5f, float(py) + 0.5f);
                RTCRayHit rh{};
                rh.ray.org_x = r.origin.x, rh.ray.org_y = r.origin.y, rh.ray.org_z = r.origin.z;
                rh.ray.dir_x = r.direction.x, rh.ray.dir_y = r.direction.y, rh.ray.dir_z = r.direction.z;
                rh.ray.tnear = 0.0f, rh.ray.tfar = far, rh.ray.mask = ~0u;
                rh.hit.geomID = RTC_INVALID_GEOMETRY_ID, rh.hit.instID[0] = RTC_INVALID_GEOMETRY_ID;
                rtcIntersect1(scene, &context, &rh);
                hit[py * size + px] = rh.hit.geomID != RTC_INVALID_GEOMETRY_ID;
            }
        return;
    }
    context.flags = RTC_INTERSECT_CONTEXT_FLAG_COHERENT;
    for (int by = y0; by < y1; by += 4)
        for (int bx = x0; bx < x1; bx += 4) {
            alignas(64) RTCRayHit16 rh{};
            alignas(64) int valid[16];
            for (int i = 0; i < 16; ++i) {
                const int px = bx + i % 4, py = by + i / 4;
                valid[i] = px < x1 && py < y1 ? -1 : 0;
                const krs::ray<float> r = camera.primary_ray(float(px) + 0.5f, float(py) + 0.5f);
                rh.ray.org_x[i] = r.origin.x, rh.ray.org_y[i] = r.origin.y, rh.ray.org_z[i] = r.origin.z;
                rh.ray.dir_x[i] = r.direction.x, rh.ray.dir_y[i] = r.direction.y, rh.ray.dir_z[i] = r.direction.z;
                rh.ray.tnear[i] = 0.0f, rh.ray.tfar[i] = far, rh.ray.mask[i] = ~0u;
                rh.hit.geomID[i] = RTC_INVALID_GEOMETRY_ID, rh.hit.instID[0][i] = RTC_INVALID_GEOMETRY_ID;
            }
            rtcIntersect16(valid, scene, &context, &rh);
            for (int i = 0; i < 16; ++i)
                if (valid[i]) hit[(by + i / 4) * size + bx + i % 4] = rh.hit.geomID[i] != RTC_INVALID_GEOMETRY_ID;
        }
}

frame render_embree(RTCScene scene, const krs::pinhole_camera& camera, float far, bool packets, int repeats)
{
    return render_tiles(camera.width(), repeats, [&](auto& take_tile, std::uint8_t* hit) {
        int x0 = 0, y0 = 0, x1 = 0, y1 = 0;
        while (take_tile(x0, y0, x1, y1)) embree_tile(scene, camera, far, packets, x0, y0, x1, y1, hit);
    });
}

// The share of the camera's primary rays that enter `box` as box_clip grows it for `o`.
double share_in_box(const krs::bounding_box& box, const krs::pinhole_camera& camera, const krs::trace_options& o)
{
    const krs::box_clip clip(box, camera.eye(), o);
    std::size_t entering = 0;
    for (int py = 0; py < camera.height(); ++py)
        for (int px = 0; px < camera.width(); ++px) {
            const krs::ray<float> r = camera.primary_ray(float(px) + 0.5f, float(py) + 0.5f);
            float t0 = o.min_distance, t1 = o.max_distance;
            clip.apply(r, t0, t1);
            entering += t0 <= t1;
        }
    return double(entering) / (double(camera.width()) * double(camera.height()));
}

double hit_share(const frame& a)
{
    std::size_t hits = 0;
    for (const std::uint8_t h : a.hit) hits += h;
    return double(hits) / double(a.hit.size());
}

double agreement(const frame& a, const frame& b)
{
    std::size_t same = 0;
    for (std::size_t i = 0; i < a.hit.size(); ++i) same += a.hit[i] == b.hit[i];
    return double(same) / double(a.hit.size());
}

// ---- Embree scenes -----------------------------------------------------------------------------

void embree_error(void*, RTCError code, const char* text)
{
    if (code != RTC_ERROR_OUT_OF_MEMORY) std::fprintf(stderr, "embree error %d: %s\n", int(code), text ? text : "");
}

// A triangle scene holding `copies` placements of the mesh (one or many).
RTCScene mesh_scene(RTCDevice device, const mesh& m, const std::vector<krs::isometry>& copies)
{
    RTCScene scene = rtcNewScene(device);
    RTCGeometry g = rtcNewGeometry(device, RTC_GEOMETRY_TYPE_TRIANGLE);
    const std::size_t nv = m.vertices.size() / 3, nt = m.triangles();
    auto* v = static_cast<float*>(
        rtcSetNewGeometryBuffer(g, RTC_BUFFER_TYPE_VERTEX, 0, RTC_FORMAT_FLOAT3, 3 * sizeof(float),
                                nv * copies.size()));
    auto* ix = static_cast<std::uint32_t*>(rtcSetNewGeometryBuffer(g, RTC_BUFFER_TYPE_INDEX, 0, RTC_FORMAT_UINT3,
                                                                   3 * sizeof(std::uint32_t), nt * copies.size()));
    if (!v || !ix) {
        rtcReleaseGeometry(g);
        rtcReleaseScene(scene);
        return nullptr;
    }
    for (std::size_t c = 0; c < copies.size(); ++c) {
        for (std::size_t i = 0; i < nv; ++i) {
            const vec3d p = copies[c].apply({m.vertices[3 * i], m.vertices[3 * i + 1], m.vertices[3 * i + 2]});
            float* out = v + 3 * (c * nv + i);
            out[0] = float(p.x), out[1] = float(p.y), out[2] = float(p.z);
        }
        for (std::size_t i = 0; i < 3 * nt; ++i) ix[3 * c * nt + i] = std::uint32_t(c * nv) + m.indices[i];
    }
    rtcCommitGeometry(g);
    rtcAttachGeometry(scene, g);
    rtcReleaseGeometry(g);
    rtcCommitScene(scene);
    return scene;
}

// The transforms of a sequence with the given mirrors and one placeholder kernel: all 2^m
// compositions, by krs::expand.
std::vector<krs::isometry> mirror_group(const std::vector<krs::mirror>& mirrors)
{
    krs::sequence<krs::sphere>::builder b;
    b.kernel(krs::sphere({0, 0, 0}, 0.0f));
    for (const krs::mirror& m : mirrors) b.mirror(m);
    const krs::sequence<krs::sphere> s = b.build();
    const auto e = krs::expand(s, std::size_t(1) << 40);
    std::vector<krs::isometry> out;
    out.reserve(e.instances.size());
    for (const auto& in : e.instances) out.push_back(in.to_world);
    return out;
}

struct embree_result {
    bool built = false;
    std::string stopped; // why the configuration stopped, when it did
    int k = -1;          // two-level split
    double build_seconds = 0, embree_bytes = 0, app_bytes = 0, rss_growth = 0;
    double single_mrays = 0, packet_mrays = 0, agree = 0;
};

// Top scene of instances of `bottom` placed by `placements`; budget checked as they are made.
RTCScene instance_scene(RTCDevice device, RTCScene bottom, const std::vector<krs::isometry>& placements,
                        const embree_memory& memory, double rss0, double app_bytes, std::string& stopped)
{
    RTCScene top = rtcNewScene(device);
    for (std::size_t i = 0; i < placements.size(); ++i) {
        const krs::isometry& w = placements[i];
        const float xfm[12] = {float(w.a[0]), float(w.a[1]), float(w.a[2]), float(w.t.x),
                               float(w.a[3]), float(w.a[4]), float(w.a[5]), float(w.t.y),
                               float(w.a[6]), float(w.a[7]), float(w.a[8]), float(w.t.z)};
        RTCGeometry g = rtcNewGeometry(device, RTC_GEOMETRY_TYPE_INSTANCE);
        rtcSetGeometryInstancedScene(g, bottom);
        rtcSetGeometryTransform(g, 0, RTC_FORMAT_FLOAT3X4_ROW_MAJOR, xfm);
        rtcCommitGeometry(g);
        rtcAttachGeometry(top, g);
        rtcReleaseGeometry(g);
        if ((i & 0xffff) == 0xffff &&
            std::max(double(memory.current.load()) + app_bytes, resident_bytes() - rss0) > memory.budget) {
            stopped = "instances passed the budget while being created";
            rtcReleaseScene(top);
            return nullptr;
        }
    }
    rtcCommitScene(top);
    return top;
}

embree_result run_embree(RTCDevice device, embree_memory& memory, const scene_sequence& s, const mesh& kernel_mesh,
                         int k, const krs::pinhole_camera& camera, const framing& v, const frame& reference,
                         const settings& opt)
{
    embree_result r;
    r.k = k;
    const int n = int(s.mirror_count());
    // The application's share: expansion (instances and krs::expand's transform list) and the
    // bottom copies' vertices before Embree takes them, estimated before anything is allocated.
    const double copies = std::ldexp(1.0, k), placements = std::ldexp(1.0, n - k);
    r.app_bytes = 2 * (copies + placements) * sizeof(krs::isometry);
    const double bottom_bytes = copies * double(kernel_mesh.vertices.size() * 4 + kernel_mesh.indices.size() * 4);
    if (r.app_bytes + 2 * bottom_bytes > opt.budget_bytes) {
        r.stopped = "expansion alone passes the budget";
        return r;
    }
    memory.reset();
    rtcGetDeviceError(device); // clears an error left by an earlier configuration
    malloc_trim(0); // so that RSS growth counts this build, not memory freed by the previous one
    const double rss0 = resident_bytes();
    const auto start = std::chrono::steady_clock::now();
    const std::vector<krs::mirror> all = s.mirrors();
    const std::vector<krs::isometry> low = mirror_group({all.begin(), all.begin() + k});
    const std::vector<krs::isometry> high = mirror_group({all.begin() + k, all.end()});
    RTCScene bottom = mesh_scene(device, kernel_mesh, low);
    if (!bottom || memory.refused) {
        r.stopped = "bottom mesh passed the budget";
        if (bottom) rtcReleaseScene(bottom);
        return r;
    }
    RTCScene top = instance_scene(device, bottom, high, memory, rss0, r.app_bytes, r.stopped);
    r.build_seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
    r.embree_bytes = double(memory.peak.load());
    r.rss_growth = resident_bytes() - rss0;
    const bool out_of_memory = rtcGetDeviceError(device) == RTC_ERROR_OUT_OF_MEMORY;
    if (!top || memory.refused || out_of_memory) {
        if (r.stopped.empty()) r.stopped = "Embree's memory passed the budget";
        if (top) rtcReleaseScene(top);
        rtcReleaseScene(bottom);
        return r;
    }
    r.built = true;
    const frame single = render_embree(top, camera, v.far, false, opt.repeats);
    const frame packet = render_embree(top, camera, v.far, true, opt.repeats);
    r.single_mrays = single.mrays();
    r.packet_mrays = packet.mrays();
    r.agree = std::min(agreement(single, reference), agreement(packet, reference));
    rtcReleaseScene(top);
    rtcReleaseScene(bottom);
    return r;
}

// ---- output ------------------------------------------------------------------------------------

using bench::format;

std::string cell(const embree_result& r, double value, const char* f)
{
    if (!r.built) return r.k < 0 ? "-" : "stop";
    return format(f, value);
}

// --stream: the stream before issue 23 against today's, 0.5 px threshold, rays clipped to the box.
int compare_streams(const settings& opt)
{
    std::printf("bench_embree_peer --stream: %dx%d primary rays, %d x %d tiles, 0.5 px threshold, rays clipped to "
                "the sequence's box, 4 interleaved packets of %zu lanes; Mr/s on %d threads, best of %d alternating "
                "rounds; the rest on 1 thread\n",
                opt.size, opt.size, tile, tile, krs::lane_count<krs::packet_f>, thread_count, opt.repeats);
    std::printf("load average before: %s\n", bench::load_average().c_str());
    bench::print_stream_header();
    std::ofstream csv(opt.csv_path.empty() ? std::string("bench_embree_peer_stream.csv") : opt.csv_path);
    csv << bench::stream_csv_header() << '\n';
    for (const bool unaligned : {false, true}) {
        if ((unaligned && opt.scene == "grid") || (!unaligned && opt.scene == "unaligned")) continue;
        for (int n : {16, 32}) {
            if (n > opt.max_n) continue; // --max-n 16: the n = 16 rows alone (e.g. to profile them)
            framing v;
            const scene_sequence s = ring_scene(n, unaligned, v);
            const krs::pinhole_camera camera = camera_for(v, opt.size);
            const krs::trace_options o = footprint_options(camera, v);
            const std::optional<grid_sequence> grid = axis_copy(s);
            const bench::stream_comparison c =
                grid ? bench::compare_streams<krs::packet_f, 4>(*grid, camera, o, tile, thread_count, opt.repeats, n)
                     : bench::compare_streams<krs::packet_f, 4>(s, camera, o, tile, thread_count, opt.repeats, n);
            csv << bench::stream_row(unaligned ? "unaligned (general)" : "grid (axis mirrors)", n, c) << '\n';
        }
    }
    std::printf("load average after: %s\n", bench::load_average().c_str());
    return 0;
}

// --boxes: the tuned KRS render clipped to the sequence's box and to its kernels' spheres' box.
int compare_boxes(const settings& opt)
{
    std::printf("bench_embree_peer --boxes: %dx%d primary rays, %d threads, %zu float lanes, best of %d "
                "(the two boxes alternate, the first swapping every repeat)\n",
                opt.size, opt.size, thread_count, krs::lane_count<krs::packet_f>, opt.repeats);
    std::printf("tight = the sequence's box (kernels' exact boxes through the mirrors); spheres = the kernels' "
                "bounding spheres' boxes through the same mirrors (before issue 23)\n");
    for (const bool unaligned : {false, true}) {
        if ((unaligned && opt.scene == "grid") || (!unaligned && opt.scene == "unaligned")) continue;
        std::printf("\n== %s ==\n", unaligned ? "unaligned (+-10 degrees)" : "grid (axis-normal)");
        std::printf("%3s %7s | %-17s | %-15s | %-17s %7s | %7s | %s\n", "n", "hits", "in box: spheres", "tight",
                    "Mr/s: spheres", "tight", "speedup", "evals/ray spheres / tight");
        for (int n = 8; n <= opt.max_n; n += 2) {
            framing v;
            const scene_sequence s = ring_scene(n, unaligned, v);
            const krs::pinhole_camera camera = camera_for(v, opt.size);
            const krs::trace_options faithful = faithful_options(v, opt.krs_floor);
            const std::optional<grid_sequence> grid = axis_copy(s);
            const auto spheres_of = [](const auto& f) {
                return krs::box_through_mirrors(f, [](const auto& k) { return krs::box_around(k.bound()); });
            };
            const krs::bounding_box tight = grid ? grid->bound_box() : s.bound_box();
            const krs::bounding_box spheres = grid ? spheres_of(*grid) : spheres_of(s);
            frame best[2];
            // The order swaps every repeat, so neither box always runs first after the other.
            for (int r = 0; r < opt.repeats; ++r)
                for (int k = 0; k < 2; ++k) {
                    const int which = (k + r) % 2;
                    const krs::bounding_box& box = which == 0 ? spheres : tight;
                    frame f = grid ? render_krs(*grid, camera, faithful, 1, true, box)
                                   : render_krs(s, camera, faithful, 1, true, box);
                    if (r == 0 || f.seconds < best[which].seconds) best[which] = std::move(f);
                }
            const double rays = double(best[0].hit.size());
            std::printf("%3d %6.1f%% | %16.1f%% | %14.1f%% | %17.2f %7.2f | %6.3fx | %.1f / %.1f%s\n", n,
                        100 * hit_share(best[1]), 100 * share_in_box(spheres, camera, faithful),
                        100 * share_in_box(tight, camera, faithful), best[0].mrays(), best[1].mrays(),
                        best[1].mrays() / best[0].mrays(), double(best[0].evaluations) / rays,
                        double(best[1].evaluations) / rays,
                        agreement(best[0], best[1]) < 1 ? " (hit/miss differ)" : "");
            std::fflush(stdout);
        }
    }
    return 0;
}

} // namespace

int main(int argc, char** argv)
{
    settings opt;
    for (int i = 1; i < argc; ++i) {
        const std::string a = argv[i];
        auto value = [&] { return i + 1 < argc ? argv[++i] : "0"; };
        if (a == "--size") opt.size = std::max(16, std::atoi(value()));
        else if (a == "--max-n") opt.max_n = std::clamp(std::atoi(value()), 8, 62);
        else if (a == "--embree-max-n") opt.embree_max_n = std::atoi(value());
        else if (a == "--budget-gib") opt.budget_bytes = std::atof(value()) * 1024 * mib;
        else if (a == "--tolerance") opt.tolerance = std::max(1e-4, std::atof(value()));
        else if (a == "--repeat") opt.repeats = std::max(1, std::atoi(value()));
        else if (a == "--csv") opt.csv_path = value();
        else if (a == "--scene") opt.scene = value();
        else if (a == "--krs-floor") opt.krs_floor = float(std::max(1e-6, std::atof(value())));
        else if (a == "--boxes") opt.boxes = true;
        else if (a == "--stream") opt.stream = true;
        else {
            std::fprintf(stderr, "usage: bench_embree_peer [--size N] [--max-n N] [--embree-max-n N] [--budget-gib G] "
                                 "[--tolerance T] [--repeat R] [--csv FILE] [--scene grid|unaligned|both] "
                                 "[--krs-floor F] [--boxes] [--stream]\n");
            return 2;
        }
    }
    if (opt.boxes) return compare_boxes(opt);
    if (opt.stream) return compare_streams(opt);
    if (opt.csv_path.empty()) opt.csv_path = bench::csv_next_to_executable(argv[0]);
    std::ofstream csv(opt.csv_path);
    if (!csv) {
        std::fprintf(stderr, "bench_embree_peer: cannot write %s\n", opt.csv_path.c_str());
        return 1;
    }

    RTCDevice device = rtcNewDevice("threads=2");
    if (!device) {
        std::fprintf(stderr, "bench_embree_peer: rtcNewDevice failed (error %d)\n", int(rtcGetDeviceError(nullptr)));
        return 1;
    }
    embree_memory memory;
    memory.budget = opt.budget_bytes;
    rtcSetDeviceErrorFunction(device, embree_error, nullptr);
    rtcSetDeviceMemoryMonitorFunction(device, embree_memory::monitor, &memory);

    framing v0;
    const mesh kernel_mesh = tessellate_level0(ring_scene(0, false, v0), opt.tolerance * tube_radius);
    std::printf("bench_embree_peer: %dx%d primary rays, %d threads, %zu float lanes, budget %.1f GiB, CSV -> %s\n",
                opt.size, opt.size, thread_count, krs::lane_count<krs::packet_f>, opt.budget_bytes / (1024 * mib),
                opt.csv_path.c_str());
    std::printf("kernels: a ring (torus, R %.1f, r %.2f) around a sphere (r %.2f); 2 kernels per copy, 2^n "
                "copies\n",
                ring_radius, tube_radius, core_radius);
    std::printf("tessellation: vertices on the surface, deviation <= %.4f (%.1f%% of the tube radius), %zu triangles "
                "per copy\n",
                opt.tolerance * tube_radius, 100 * opt.tolerance, kernel_mesh.triangles());
    std::printf("KRS: packet tracer; faithful threshold = pixel_footprint 0, floor max(%g, 4e-7 extent), 4096 steps;\n"
                "     KRS = rays clipped to the sequence's box, axis mirrors on the grid;\n"
                "     plain = general mirrors, no clipping;\n"
                "     evals = field evaluations per ray; '= plain' hit/miss agreement\n"
                "     of KRS with plain; px = plain with a 0.5 px footprint threshold, 'px agree' its agreement\n",
                double(opt.krs_floor));
    std::printf("Embree: Mr/s single (rtcIntersect1) / x16 (rtcIntersect16); mem = max(monitor + application "
                "expansion, RSS growth);\n"
                "        agree = hit/miss agreement with KRS faithful (worse of single and x16)\n");
    csv << "scene,n,instances,hit_share,krs_mirrors,krs_mrays_s,krs_evals_per_ray,krs_agree_plain,krs_plain_mrays_s,"
           "krs_plain_evals_per_ray,krs_px_mrays_s,krs_px_agree,krs_bytes,"
           "triangles_per_copy,"
           "flat_single_mrays_s,flat_packet_mrays_s,flat_embree_bytes,flat_app_bytes,flat_rss_growth,flat_build_s,"
           "flat_agree,flat_stopped,two_level_k,two_level_single_mrays_s,two_level_packet_mrays_s,"
           "two_level_embree_bytes,two_level_app_bytes,two_level_rss_growth,two_level_build_s,two_level_agree,"
           "two_level_stopped\n";

    {
        // Untimed warm-up: the process's first renders run at about half speed (thread start,
        // first touch of the frame and the ray queues, clock ramp), which would bias n = 8.
        framing v;
        const scene_sequence s = ring_scene(8, false, v);
        const krs::pinhole_camera camera = camera_for(v, opt.size);
        const std::optional<grid_sequence> grid = axis_copy(s);
        for (int i = 0; i < 3; ++i) {
            render_krs(s, camera, faithful_options(v, opt.krs_floor), 1, true);
            render_krs(*grid, camera, faithful_options(v, opt.krs_floor), 1, true); // the tuned path's code too
        }
    }
    for (const bool unaligned : {false, true}) {
        if ((unaligned && opt.scene == "grid") || (!unaligned && opt.scene == "unaligned")) continue;
        const char* scene_name = unaligned ? "unaligned" : "grid";
        std::printf("\n== %s mirrors ==\n", unaligned ? "unaligned (+-10 degrees)" : "grid (axis-normal)");
        std::printf("%3s %6s %9s %6s %9s %6s %8s %9s %8s %8s | %-24s %9s %8s %7s | %-26s %9s %8s %7s\n", "n", "hits",
                    "KRS Mr/s", "evals", "plain", "evals", "= plain", "KRS px",
                    "px agree", "KRS mem", "flat: single / x16 Mr/s", "mem MiB", "build s", "agree",
                    "two-level: k, single / x16", "mem MiB", "build s", "agree");
        bool flat_stopped = false, two_stopped = false;
        // Issue 9's targets on this scene: KRS / Embree's best configuration at each n Embree ran.
        double worst_ratio = 1e300, ratio_at_22 = 0;
        int worst_n = 0;
        std::size_t largest_krs_bytes = 0;
        double worst_tuned_agree = 1;
        for (int n = 8; n <= opt.max_n; n += 2) {
            framing v;
            const scene_sequence s = ring_scene(n, unaligned, v);
            const krs::pinhole_camera camera = camera_for(v, opt.size);
            // The plain packet tracer on the general sequence, then the one a user would run:
            // rays clipped to the box, and axis mirrors where the scene has them. Embree is
            // compared with the plain render; the tuned one must draw the same image.
            const krs::trace_options faithful = faithful_options(v, opt.krs_floor);
            const frame krs_faithful = render_krs(s, camera, faithful, opt.repeats);
            const std::optional<grid_sequence> grid = axis_copy(s);
            const frame krs_tuned = grid ? render_krs(*grid, camera, faithful, opt.repeats, true)
                                         : render_krs(s, camera, faithful, opt.repeats, true);
            const double tuned_agree = agreement(krs_tuned, krs_faithful);
            // The memory of the sequence the timed render traced.
            const std::size_t krs_bytes = grid ? grid->memory_bytes() : s.memory_bytes();
            const frame krs_px = render_krs(s, camera, footprint_options(camera, v), opt.repeats);
            const double px_agree = agreement(krs_px, krs_faithful);

            embree_result flat, two;
            const char* earlier = "stopped at a smaller n";
            if (n <= opt.embree_max_n) {
                if (!flat_stopped) {
                    flat = run_embree(device, memory, s, kernel_mesh, 0, camera, v, krs_faithful, opt);
                    flat_stopped = !flat.built;
                } else {
                    flat.k = 0, flat.stopped = earlier;
                }
                if (!two_stopped) {
                    for (int k : {n / 2 - 2, n / 2, n / 2 + 2}) {
                        embree_result r = run_embree(device, memory, s, kernel_mesh, k, camera, v, krs_faithful, opt);
                        const auto best = [](const embree_result& e) {
                            return std::max(e.single_mrays, e.packet_mrays);
                        };
                        if (r.built && (!two.built || best(r) > best(two))) two = r;
                        else if (!two.built && two.stopped.empty()) two = r;
                    }
                    two_stopped = !two.built;
                } else {
                    two.k = 0, two.stopped = earlier;
                }
            }
            const auto memory_of = [](const embree_result& e) {
                return std::max(e.embree_bytes + e.app_bytes, e.rss_growth) / mib;
            };
            const std::string flat_speed = flat.built ? format("%.2f / %.2f", flat.single_mrays, flat.packet_mrays)
                                                      : (flat.k < 0 ? "-" : "stopped: over budget");
            const std::string two_speed = two.built
                                              ? format("k=%d, %.2f / %.2f", two.k, two.single_mrays, two.packet_mrays)
                                              : (two.k < 0 ? "-" : "stopped: over budget");
            std::printf("%3d %5.1f%% %9.2f %6.1f %9.2f %6.1f %7.3f%% %9.2f %7.2f%% %6zu B | %-24s %9s %8s %7s | %-26s "
                        "%9s %8s %7s\n",
                        n, 100 * hit_share(krs_faithful), krs_tuned.mrays(),
                        double(krs_tuned.evaluations) / double(krs_tuned.hit.size()), krs_faithful.mrays(),
                        double(krs_faithful.evaluations) / double(krs_faithful.hit.size()), 100 * tuned_agree,
                        krs_px.mrays(),
                        100 * px_agree, krs_bytes, flat_speed.c_str(),
                        cell(flat, memory_of(flat), "%.1f").c_str(), cell(flat, flat.build_seconds, "%.2f").c_str(),
                        cell(flat, 100 * flat.agree, "%.2f%%").c_str(), two_speed.c_str(),
                        cell(two, memory_of(two), "%.1f").c_str(), cell(two, two.build_seconds, "%.2f").c_str(),
                        cell(two, 100 * two.agree, "%.2f%%").c_str());
            largest_krs_bytes = std::max(largest_krs_bytes, krs_bytes);
            // Checked where Embree is compared: beyond, coordinates of 1e5 and more round the
            // two mirror kinds' folds differently on some grazing rays (0.12% of pixels at n = 32).
            if (n <= opt.embree_max_n) worst_tuned_agree = std::min(worst_tuned_agree, tuned_agree);
            const double embree_best = std::max({flat.built ? std::max(flat.single_mrays, flat.packet_mrays) : 0.0,
                                                 two.built ? std::max(two.single_mrays, two.packet_mrays) : 0.0});
            if (embree_best > 0) {
                const double ratio = krs_tuned.mrays() / embree_best;
                if (ratio < worst_ratio) worst_ratio = ratio, worst_n = n;
                if (n == 22) ratio_at_22 = ratio;
            }
            if (!flat.built && flat.k >= 0 && flat.stopped != earlier)
                std::printf("    flat stopped at n = %d: %s\n", n, flat.stopped.c_str());
            if (!two.built && two.k >= 0 && two.stopped != earlier)
                std::printf("    two-level stopped at n = %d: %s\n", n, two.stopped.c_str());
            std::fflush(stdout);
            csv << format("%s,%d,%.0f,%.6f,%s,%.4f,%.2f,%.6f,%.4f,%.2f,%.4f,%.6f,%zu,%zu,", scene_name, n,
                          s.instance_count(), hit_share(krs_faithful), grid ? "axis" : "general", krs_tuned.mrays(),
                          double(krs_tuned.evaluations) / double(krs_tuned.hit.size()), tuned_agree,
                          krs_faithful.mrays(), double(krs_faithful.evaluations) / double(krs_faithful.hit.size()),
                          krs_px.mrays(), px_agree, krs_bytes, kernel_mesh.triangles())
                << format("%.4f,%.4f,%.0f,%.0f,%.0f,%.4f,%.6f,%s,", flat.single_mrays, flat.packet_mrays,
                          flat.embree_bytes, flat.app_bytes, flat.rss_growth, flat.build_seconds, flat.agree,
                          flat.built ? "" : (flat.k < 0 ? "not run" : flat.stopped.c_str()))
                << format("%d,%.4f,%.4f,%.0f,%.0f,%.0f,%.4f,%.6f,%s\n", two.k, two.single_mrays, two.packet_mrays,
                          two.embree_bytes, two.app_bytes, two.rss_growth, two.build_seconds, two.agree,
                          two.built ? "" : (two.k < 0 ? "not run" : two.stopped.c_str()));
        }
        if (worst_n > 0)
            std::printf("targets (%s): KRS beats Embree's best at every n it ran: worst KRS/Embree %.2fx at n = %d -> %s; "
                        ">= 10x at n = 22: %s; KRS memory < 64 KiB: largest %zu B -> %s\n",
                        scene_name, worst_ratio, worst_n, worst_ratio > 1 ? "met" : "NOT met",
                        ratio_at_22 <= 0 ? "not measured"
                        // Issue 9 sets the 10x on the grid (its reference figures are the grid's); the
                        // unaligned scene reports the ratio. It is sparse (its tilted copies spread out:
                        // 3% of pixels hit at n = 22), so Embree culls most rays at its root.
                        : unaligned ? format("%.2fx (the 10x target is the grid's)", ratio_at_22).c_str()
                                    : format("%.2fx -> %s", ratio_at_22, ratio_at_22 >= 10 ? "met" : "NOT met").c_str(),
                        largest_krs_bytes, largest_krs_bytes < 65536 ? "met" : "NOT met");
        // The clipping and the axis copy change the work, not the picture (up to near misses).
        std::printf("check (%s): KRS (clipped, mirror kind) draws the plain render's image up to n = %d: worst hit/miss "
                    "agreement %.3f%% -> %s\n",
                    scene_name, opt.embree_max_n, 100 * worst_tuned_agree, worst_tuned_agree >= 0.999 ? "ok" : "DIFFERS");
    }
    rtcReleaseDevice(device);
    return 0;
}

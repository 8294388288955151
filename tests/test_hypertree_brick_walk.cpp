// The brick walk (hypertree/render/brick_walk.hpp) against independent references: plain stepping
// (every sample, its brick's occupancy taken from the voxels the test placed, not from the bricks)
// and a fine walk along the ray. A walk must look at exactly the samples stepping finds in
// non-empty bricks, in order, and skip none of the bricks a ray crosses for more than a step.

#include "hypertree/render/brick_walk.hpp"
#include "hypertree/store/index_list_store.hpp"

#include <doctest/doctest.h>

#include <algorithm>
#include <array>
#include <cmath>
#include <cstdio>
#include <cstdint>
#include <limits>
#include <set>
#include <tuple>
#include <vector>

using namespace hypertree;

namespace {

struct lcg {
    std::uint32_t state;
    float uniform()
    {
        state = state * 1664525u + 1013904223u;
        return float(state >> 8) * 0x1.0p-24f;
    }
};

// A grid whose sides are not multiples of 4 or 16, off the origin, with non-cubic voxels, and a
// few scattered non-empty voxels: most bricks and many blocks empty.
struct scattered {
    hypervolume volume{{-1.3, 0.2, 2.0}, {2.0, 1.5, 2.6}, resolution{37, 29, 45}};
    std::set<std::array<int, 3>> occupied; // bricks (cell >> 2) holding a voxel: the reference
    index_list_store store;
    voxel_bricks bricks;
    explicit scattered(std::uint32_t seed)
    {
        lcg random{seed};
        std::vector<stored_voxel> voxels;
        for (int z = 0; z < 45; ++z)
            for (int y = 0; y < 29; ++y)
                for (int x = 0; x < 37; ++x)
                    if (random.uniform() < 0.004f) {
                        voxels.push_back({volume.index(x, y, z), {std::uint8_t(1 + int(random.uniform() * 254)), 2}, 0});
                        occupied.insert({x >> 2, y >> 2, z >> 2});
                    }
        store = index_list_store::build(volume, voxels);
        bricks = voxel_bricks(store);
    }
};

struct looked_at {
    float k;
    int x, y, z;
    friend bool operator==(const looked_at&, const looked_at&) = default;
};

krs::vec3f cells_of(const hypervolume& v, const krs::vec3f& p)
{
    const krs::vec3f o(v.origin()), c(v.cells_per_unit());
    return {(p.x - o.x) * c.x, (p.y - o.y) * c.y, (p.z - o.z) * c.z};
}

// Plain stepping: every sample k of [0, count), in a non-empty brick by the reference set.
std::vector<looked_at> stepped(const scattered& s, const krs::vec3f& o, const krs::vec3f& d, float t0, float ds, int count)
{
    std::vector<looked_at> out;
    const int n[3] = {s.volume.grid().x, s.volume.grid().y, s.volume.grid().z};
    for (int k = 0; k < count; ++k) {
        const float t = t0 + (float(k) + 0.5f) * ds;
        const krs::vec3f f = cells_of(s.volume, o + d * t);
        if (!(f.x >= 0 && f.y >= 0 && f.z >= 0 && f.x < float(n[0]) && f.y < float(n[1]) && f.z < float(n[2]))) continue;
        const int x = std::min(int(f.x), n[0] - 1), y = std::min(int(f.y), n[1] - 1), z = std::min(int(f.z), n[2] - 1);
        if (s.occupied.count({x >> 2, y >> 2, z >> 2})) out.push_back({float(k), x, y, z});
    }
    return out;
}

// The walk of one ray, scalar: what probe looks at, advancing as it says.
std::vector<looked_at> walked(const scattered& s, const brick_walk& w, const krs::vec3f& o, const krs::vec3f& d, float t0, int count,
                              std::size_t& skipped)
{
    std::vector<looked_at> out;
    float slope[3];
    w.slopes_of(d, slope);
    const brick_walk::exit_faces faces = brick_walk::faces_of(slope);
    const float m0 = w.margin_at_origin(o);
    for (float k = 0; k < float(count);) {
        const float t = t0 + (k + 0.5f) * w.step();
        const auto found = w.probe<float>(s.bricks.view_of(), o + d * t, slope, true, w.skip_margin(m0, t), faces);
        if (found.looks) out.push_back({k, found.cell[0], found.cell[1], found.cell[2]});
        skipped += std::size_t(found.advance - 1);
        k += found.advance;
    }
    return out;
}

// A ray toward a random point of the grid: from outside at `distance` (world units from the
// grid's center), or from inside; every 5th along an axis.
void random_ray(lcg& r, const hypervolume& v, float distance, int i, krs::vec3f& o, krs::vec3f& d)
{
    const krs::vec3f lo(v.origin()), size(v.extent());
    const krs::vec3f target{lo.x + r.uniform() * size.x, lo.y + r.uniform() * size.y, lo.z + r.uniform() * size.z};
    if (i % 5 == 0) {
        const int axis = i / 5 % 3;
        const float sign = i / 15 % 2 ? 1.0f : -1.0f;
        d = {axis == 0 ? sign : 0.0f, axis == 1 ? sign : 0.0f, axis == 2 ? sign : 0.0f};
        o = target - d * distance;
        return;
    }
    const krs::vec3f from{r.uniform() * 2 - 1, r.uniform() * 2 - 1, r.uniform() * 2 - 1};
    d = krs::normalize(from);
    o = target - d * (distance * (0.2f + r.uniform()));
}

} // namespace

TEST_CASE("brick walk looks at exactly the samples plain stepping finds in non-empty bricks, and crosses no brick unseen")
{
    std::size_t rays = 0, looked = 0, skipped = 0, runs_checked = 0;
    for (std::uint32_t seed : {1u, 2u}) {
        const scattered s(seed);
        REQUIRE(s.occupied.size() > 100);
        for (float step_factor : {1.0f, 0.7f, 1.9f}) {
            const float ds = step_factor * float(s.volume.smallest_voxel_side());
            const brick_walk w(s.volume, ds);
            lcg r{seed * 77u + 5u};
            for (float distance : {1.0f, 30.0f, 1000.0f}) {
                for (int i = 0; i < 300; ++i) {
                    krs::vec3f o, d;
                    random_ray(r, s.volume, distance, i, o, d);
                    // From a little before the grid to a little past it.
                    double enter = 0, leave = 1e30;
                    const krs::vec3d lo(s.volume.origin()), hi = lo + s.volume.extent();
                    const double od[3] = {o.x, o.y, o.z}, dd[3] = {d.x, d.y, d.z}, l[3] = {lo.x, lo.y, lo.z}, h[3] = {hi.x, hi.y, hi.z};
                    for (int a = 0; a < 3; ++a) {
                        if (dd[a] == 0) continue;
                        const double ta = (l[a] - od[a]) / dd[a], tb = (h[a] - od[a]) / dd[a];
                        enter = std::max(enter, std::min(ta, tb)), leave = std::min(leave, std::max(ta, tb));
                    }
                    if (!(enter < leave)) continue;
                    const float t0 = float(std::max(0.0, enter - 3 * ds));
                    const int count = int((leave + 3 * ds - double(t0)) / ds) + 1;
                    const std::vector<looked_at> expect = stepped(s, o, d, t0, ds, count);
                    const std::vector<looked_at> got = walked(s, w, o, d, t0, count, skipped);
                    INFO("ray from " << o.x << " " << o.y << " " << o.z << " along " << d.x << " " << d.y << " " << d.z);
                    REQUIRE(got == expect);
                    ++rays, looked += got.size();
                    // The fine walk, in double, 1/16 step apart: each stretch the ray stays in one
                    // occupied brick for over 1.25 steps must hold one of the walk's samples.
                    std::array<int, 3> current{-1, -1, -1};
                    double entered = 0;
                    const auto close = [&](double left) {
                        if (current[0] < 0 || left - entered < 1.25 * ds) return;
                        ++runs_checked;
                        const bool seen = std::any_of(got.begin(), got.end(), [&](const looked_at& a) {
                            return std::array<int, 3>{a.x >> 2, a.y >> 2, a.z >> 2} == current;
                        });
                        CHECK(seen);
                    };
                    const krs::vec3d origin(o), direction(d), cpu(s.volume.cells_per_unit());
                    const int n[3] = {s.volume.grid().x, s.volume.grid().y, s.volume.grid().z};
                    for (double t = t0; t < t0 + double(count) * ds; t += ds / 16) {
                        const krs::vec3d p = origin + direction * t;
                        const double f[3] = {(p.x - lo.x) * cpu.x, (p.y - lo.y) * cpu.y, (p.z - lo.z) * cpu.z};
                        std::array<int, 3> brick{-1, -1, -1};
                        if (f[0] >= 0 && f[1] >= 0 && f[2] >= 0 && f[0] < n[0] && f[1] < n[1] && f[2] < n[2]) {
                            const std::array<int, 3> b{int(f[0]) >> 2, int(f[1]) >> 2, int(f[2]) >> 2};
                            if (s.occupied.count(b)) brick = b;
                        }
                        if (brick != current) {
                            close(t);
                            current = brick, entered = t;
                        }
                    }
                    close(t0 + double(count) * ds);
                }
            }
        }
    }
    std::printf("brick walk: %zu rays, %zu samples looked at, %zu skipped, %zu brick crossings checked\n", rays, looked, skipped,
                runs_checked);
    CHECK(looked > 1000);
    CHECK(skipped > looked); // empty space was skipped, not stepped through
    CHECK(runs_checked > 500);
}

TEST_CASE("brick walk: a packet's lanes walk as the scalar walk, and known exit faces skip as faces chosen per lane")
{
    using P = krs::packet_f;
    constexpr std::size_t n = krs::lane_count<P>;
    const scattered s(3);
    const float ds = float(s.volume.smallest_voxel_side());
    const brick_walk w(s.volume, ds);
    lcg r{11};
    std::size_t lanes_compared = 0, agreed = 0, skipping = 0;
    for (int round = 0; round < 200; ++round) {
        // Lanes near one direction (every 4th round: one axis still) from near one point.
        krs::vec3f base{r.uniform() * 2 - 1, r.uniform() * 2 - 1, r.uniform() * 2 - 1};
        if (round % 4 == 0) base.y = 0;
        std::array<krs::vec3f, n> o, d;
        std::array<float, n> ox, oy, oz, dx, dy, dz;
        const krs::vec3f center = krs::vec3f(s.volume.origin()) + krs::vec3f(s.volume.extent()) * 0.5f;
        for (std::size_t k = 0; k < n; ++k) {
            d[k] = krs::normalize(base + krs::vec3f{r.uniform(), r.uniform(), r.uniform()} * 0.05f);
            if (round % 4 == 0) d[k].y = 0, d[k] = krs::normalize(d[k]);
            o[k] = center - d[k] * 4.0f + krs::vec3f{r.uniform(), r.uniform(), r.uniform()} * 0.5f;
            ox[k] = o[k].x, oy[k] = o[k].y, oz[k] = o[k].z, dx[k] = d[k].x, dy[k] = d[k].y, dz[k] = d[k].z;
        }
        const krs::vec3<P> op{P::load_unaligned(ox.data()), P::load_unaligned(oy.data()), P::load_unaligned(oz.data())};
        const krs::vec3<P> dp{P::load_unaligned(dx.data()), P::load_unaligned(dy.data()), P::load_unaligned(dz.data())};
        P slope[3];
        w.slopes_of(dp, slope);
        const brick_walk::exit_faces faces = brick_walk::faces_of(slope);
        agreed += faces.along[0] != brick_walk::exit_faces::per_lane && faces.along[2] != brick_walk::exit_faces::per_lane;
        const P m0 = w.margin_at_origin(op);
        const int count = int(8.0f / ds);
        std::array<std::vector<looked_at>, n> got;
        P k(0.0f);
        auto running = k < P(float(count));
        using krs::any; // (unqualified below: packets take xsimd's, found by argument)
        while (any(running)) {
            const P t = P(0.0f) + (k + P(0.5f)) * P(ds);
            const krs::vec3<P> p = op + dp * t;
            const auto found = w.probe(s.bricks.view_of(), p, slope, running, w.skip_margin(m0, t), faces);
            const auto per_lane = w.probe(s.bricks.view_of(), p, slope, running, w.skip_margin(m0, t), brick_walk::exit_faces{});
            const auto a = krs::lanes_of(found.advance), b = krs::lanes_of(per_lane.advance), ks = krs::lanes_of(k);
            const std::uint64_t looks = krs::mask_bits<P>(found.looks);
            const auto cx = krs::lanes_of(krs::index_to_float(found.cell[0])), cy = krs::lanes_of(krs::index_to_float(found.cell[1])),
                       cz = krs::lanes_of(krs::index_to_float(found.cell[2]));
            for (std::size_t l = 0; l < n; ++l) {
                REQUIRE(a[l] == b[l]);
                skipping += a[l] > 1;
                if ((looks >> l) & 1u) got[l].push_back({ks[l], int(cx[l]), int(cy[l]), int(cz[l])});
            }
            k = k + found.advance;
            running = running & (k < P(float(count)));
        }
        for (std::size_t l = 0; l < n; ++l) {
            std::size_t ignored = 0;
            REQUIRE(got[l] == walked(s, w, o[l], d[l], 0.0f, count, ignored));
            REQUIRE(got[l] == stepped(s, o[l], d[l], 0.0f, ds, count));
            ++lanes_compared;
        }
    }
    CHECK(lanes_compared == 200 * n);
    CHECK(skipping > 1000); // the skips were compared
    CHECK(agreed > 100);    // and the packets' faces were known
}

TEST_CASE("brick walk refuses a step that is not finite and > 0, by name")
{
    const hypervolume v{{0, 0, 0}, {1, 1, 1}, resolution{8, 8, 8}};
    for (float bad : {0.0f, -0.1f, std::nanf(""), std::numeric_limits<float>::infinity()})
        CHECK_THROWS_WITH_AS(brick_walk(v, bad), doctest::Contains("brick_walk.step"), krs::invalid_parameter);
    CHECK(brick_walk(v, 0.125f).step() == 0.125f);
}

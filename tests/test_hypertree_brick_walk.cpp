// The brick walk (hypertree/render/brick_walk.hpp) against independent references: plain stepping
// (every sample, its brick's occupancy taken from the voxels the test placed, not from the bricks),
// a fine walk along the ray, and the reference walk of empty bricks and 16^3 blocks only. A walk
// must look at exactly the samples stepping finds in non-empty bricks, in order, and skip none of
// the bricks a ray crosses for more than a step.

#include "hypertree/render/brick_walk.hpp"
#include "hypertree/store/index_list_store.hpp"

#include "support/brick_walk_rays.hpp"

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
using namespace krs_test;

TEST_CASE("brick walk looks at exactly the samples plain stepping finds in non-empty bricks, and crosses no brick unseen")
{
    std::size_t rays = 0, looked = 0, runs_checked = 0;
    skip_counts counts;
    for (std::uint32_t seed : {1u, 2u}) {
        const scattered s(seed);
        REQUIRE(s.occupied.size() > 100);
        REQUIRE(s.empty_blocks() >= 4);
        for (float step_factor : {1.0f, 0.7f, 1.9f}) {
            const float ds = step_factor * float(s.volume.smallest_voxel_side());
            const brick_walk w(s.volume, ds);
            lcg r{seed * 77u + 5u};
            for (float distance : {1.0f, 30.0f, 1000.0f}) {
                for (int i = 0; i < 300; ++i) {
                    krs::vec3f o, d;
                    random_ray(r, s.volume, distance, i, o, d);
                    // From a little before the grid to a little past it.
                    float t0 = 0;
                    int count = 0;
                    if (!samples_across(s.volume, o, d, ds, t0, count)) continue;
                    const krs::vec3d lo(s.volume.origin());
                    const std::vector<looked_at> expect = stepped(s, o, d, t0, ds, count);
                    const std::vector<looked_at> got = walked(s, w, o, d, t0, count, counts);
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
    std::printf("brick walk: %zu rays, %zu samples looked at, %zu skipped, %zu probes in empty blocks, %zu skips over 2+ bricks, "
                "%zu brick crossings checked\n",
                rays, looked, counts.skipped, counts.in_empty_block, counts.over_bricks, runs_checked);
    CHECK(looked > 1000);
    CHECK(counts.skipped > looked); // empty space was skipped, not stepped through
    CHECK(counts.in_empty_block > 100); // and empty blocks were met
    CHECK(counts.over_bricks > 100);    // and skipped whole, past more than one brick
    CHECK(runs_checked > 500);
}

TEST_CASE("brick walk: a packet's lanes walk as the scalar walk, and known exit faces skip as faces chosen per lane")
{
    using P = krs::packet_f;
    constexpr std::size_t n = krs::lane_count<P>;
    const scattered s(3);
    REQUIRE(s.empty_blocks() >= 4);
    const float ds = float(s.volume.smallest_voxel_side());
    const brick_walk w(s.volume, ds);
    lcg r{11};
    std::size_t lanes_compared = 0, agreed = 0, skipping = 0, block_skipping = 0;
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
            const auto places = krs::lanes_of(krs::index_to_float(found.place));
            const std::uint64_t looks = krs::mask_bits<P>(found.looks);
            const auto cx = krs::lanes_of(krs::index_to_float(found.cell[0])), cy = krs::lanes_of(krs::index_to_float(found.cell[1])),
                       cz = krs::lanes_of(krs::index_to_float(found.cell[2]));
            for (std::size_t l = 0; l < n; ++l) {
                REQUIRE(a[l] == b[l]);
                skipping += a[l] > 1;
                block_skipping += a[l] > 1 && places[l] < -64;
                if ((looks >> l) & 1u) got[l].push_back({ks[l], int(cx[l]), int(cy[l]), int(cz[l])});
            }
            k = k + found.advance;
            running = running & (k < P(float(count)));
        }
        for (std::size_t l = 0; l < n; ++l) {
            skip_counts ignored;
            REQUIRE(got[l] == walked(s, w, o[l], d[l], 0.0f, count, ignored));
            REQUIRE(got[l] == stepped(s, o[l], d[l], 0.0f, ds, count));
            ++lanes_compared;
        }
    }
    CHECK(lanes_compared == 200 * n);
    CHECK(skipping > 1000);      // the skips were compared
    CHECK(block_skipping > 100); // among them skips over empty blocks
    CHECK(agreed > 100);    // and the packets' faces were known
}

TEST_CASE("brick walk: empty cubes of every level look at the samples of stepping and of the reference walk, in fewer probes, in a forest")
{
    // A forest's clearings are the coarse levels' case: rays from near and far, at three step
    // factors, walked with every level, with bricks and blocks only, and stepped; the three
    // must look at the same samples in the same order.
    std::size_t rays = 0, looked = 0;
    skip_counts levels, blocks;
    for (std::uint32_t seed : {1u, 2u}) {
        const forest s(seed);
        REQUIRE(s.occupied.size() > 100);
        REQUIRE(s.bricks.empty_levels() >= 4); // cubes of 64^3 voxels lie in the clearings
        for (float step_factor : {1.0f, 0.7f, 1.9f}) {
            const float ds = step_factor * float(s.volume.smallest_voxel_side());
            const brick_walk w(s.volume, ds), reference(s.volume, ds, brick_walk::skips::bricks_and_blocks);
            REQUIRE(w.skipping() == brick_walk::skips::every_level);
            lcg r{seed * 31u + 7u};
            for (float distance : {1.0f, 30.0f, 1000.0f}) {
                for (int i = 0; i < 300; ++i) {
                    krs::vec3f o, d;
                    random_ray(r, s.volume, distance, i, o, d);
                    float t0 = 0;
                    int count = 0;
                    if (!samples_across(s.volume, o, d, ds, t0, count)) continue;
                    INFO("ray from " << o.x << " " << o.y << " " << o.z << " along " << d.x << " " << d.y << " " << d.z);
                    const std::vector<looked_at> expect = stepped(s, o, d, t0, ds, count);
                    const std::vector<looked_at> got = walked(s, w, o, d, t0, count, levels);
                    REQUIRE(got == expect);
                    REQUIRE(walked(s, reference, o, d, t0, count, blocks) == expect);
                    ++rays, looked += got.size();
                }
            }
        }
    }
    std::printf("forest walk: %zu rays, %zu samples looked at; probes %zu with every level (%zu in cubes of 32^3 or more), %zu with "
                "bricks and blocks\n",
                rays, looked, levels.probes, levels.in_coarse_cube, blocks.probes);
    CHECK(looked > 1000);
    CHECK(levels.in_coarse_cube > 1000); // the coarse levels were met
    CHECK(levels.over_bricks > 1000);
    // and saved probes (measured: 0.77 of them, though every ray takes 6 probes outside the grid, 3 steps each side)
    CHECK(double(levels.probes) < 0.85 * double(blocks.probes));
}

TEST_CASE("brick walk refuses a step that is not finite and > 0, by name")
{
    const hypervolume v{{0, 0, 0}, {1, 1, 1}, resolution{8, 8, 8}};
    for (float bad : {0.0f, -0.1f, std::nanf(""), std::numeric_limits<float>::infinity()})
        CHECK_THROWS_WITH_AS(brick_walk(v, bad), doctest::Contains("brick_walk.step"), krs::invalid_parameter);
    CHECK(brick_walk(v, 0.125f).step() == 0.125f);
}

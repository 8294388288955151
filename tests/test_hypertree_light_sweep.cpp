// The light sweep (light_sweep.hpp) against the shadow rays it replaces: exactly the shadow rays
// where nothing is approximated (no cut, or lights along an axis, where a cut voxel's ray is the
// cutting ray's tail), and within a measured bound of them in images of trees A-D.

#include "hypertree/execution.hpp"
#include "hypertree/hypertree.hpp"
#include "hypertree/presets.hpp"
#include "hypertree/render/render.hpp"

#include "support/small_tree.hpp"

#include <doctest/doctest.h>

#include <algorithm>
#include <atomic>
#include <cmath>
#include <thread>
#include <vector>

using namespace hypertree;
using krs_test::small_tree_d;

namespace {

using method = march_options::shadow_method;

march_options by(method m, march_options o = {})
{
    o.shadow_by = m;
    return o;
}

double rmse(const image& a, const image& b)
{
    REQUIRE(a.rgb.size() == b.rgb.size());
    double sum = 0;
    for (std::size_t i = 0; i < a.rgb.size(); ++i) {
        REQUIRE(std::isfinite(a.rgb[i]));
        REQUIRE(std::isfinite(b.rgb[i]));
        const double d = double(std::clamp(a.rgb[i], 0.0f, 1.0f)) - double(std::clamp(b.rgb[i], 0.0f, 1.0f));
        sum += d * d;
    }
    return std::sqrt(sum / double(a.rgb.size()));
}

// Every non-empty voxel's center and slot.
template <class F>
void for_each_voxel(const volume_marcher& m, F&& f)
{
    const voxel_bricks& bricks = m.bricks();
    for (std::size_t b = 0; b < bricks.brick_count(); ++b)
        for (std::uint64_t mask = bricks.mask(b); mask != 0; mask &= mask - 1) {
            const std::size_t offset = std::size_t(std::countr_zero(mask));
            const std::array<int, 3> c = voxel_bricks::cell_at(bricks.origin(b), offset);
            const krs::vec3d q = m.volume().voxel_center(m.volume().index(c[0], c[1], c[2]));
            f(krs::vec3f{float(q.x), float(q.y), float(q.z)}, bricks.slot(b * voxel_bricks::brick_voxels + offset));
        }
}

// A 32^3 volume of unit cubes, a third of them non-empty with densities from a hash.
index_list_store random_cubes()
{
    const hypervolume v({0, 0, 0}, {32, 32, 32}, resolution::cube(32));
    std::vector<stored_voxel> voxels;
    for (int z = 0; z < 32; ++z)
        for (int y = 0; y < 32; ++y)
            for (int x = 0; x < 32; ++x) {
                std::uint32_t h = std::uint32_t(x) * 0x8da6b343u ^ std::uint32_t(y) * 0xd8163841u ^ std::uint32_t(z) * 0xcb1ab31fu;
                h ^= h >> 16, h *= 0x7feb352du, h ^= h >> 15;
                if (h % 3 == 0) voxels.push_back({v.index(x, y, z), {std::uint8_t(1 + (h >> 8) % 120), 3}, 0});
            }
    std::sort(voxels.begin(), voxels.end(), [](const stored_voxel& a, const stored_voxel& b) { return a.index < b.index; });
    return index_list_store::build(v, voxels);
}

} // namespace

TEST_CASE("hypertree light sweep: without cuts it is every voxel's shadow ray, whatever the light")
{
    // sweep_near_steps beyond any ray's length: no ray is cut, so the wavefront of each level
    // must reproduce shadow_transmittance for every voxel (same operations, same order).
    const auto store = build_tree<index_list_store>(small_tree_d(), 2);
    const tree_shape shape = tree_shape::of(store);
    march_options o;
    o.sweep_near_steps = 1 << 20;
    o.lights = {directional_light{{0.4f, 0.8f, 0.45f}, {1, 1, 1}}, directional_light{{-0.7f, 0.3f, -0.2f}, {1, 1, 1}},
                directional_light{{0, -1, 0}, {1, 1, 1}}};
    const volume_marcher m(store, shape, depth_colors{}, o);
    REQUIRE(!m.sweep().empty());
    std::size_t voxels = 0, differ = 0, shadowed = 0;
    for_each_voxel(m, [&](const krs::vec3f& q, std::uint32_t slot) {
        for (std::size_t i = 0; i < o.lights.size(); ++i) {
            float lookups = 0;
            const float ray = m.shadow_transmittance(q, m.shading().light_directions()[i], lookups);
            differ += m.sweep().toward(i)[slot] != ray;
            shadowed += ray < 0.5f;
        }
        ++voxels;
    });
    CHECK(voxels == m.bricks().voxel_count());
    CHECK(differ == 0);
    CHECK(shadowed > voxels / 10); // (not a tree in full light)
}

TEST_CASE("hypertree light sweep: lights along an axis give the shadow rays' transmittance")
{
    // Along an axis, at step factor 1, a cut voxel's center lies on the cutting ray and its ray is
    // the cutting ray's tail: the sweep approximates nothing. Only the product's association
    // differs (rounding), and where the product falls below the early exit both stop below it.
    // (Cubic voxels: on elongated ones the step is the smallest side and misses the centers.)
    const auto store = random_cubes();
    const tree_shape shape = tree_shape::of(store);
    for (const krs::vec3f l : {krs::vec3f{1, 0, 0}, krs::vec3f{0, -1, 0}, krs::vec3f{0, 0, 1}, krs::vec3f{-1, 0, 0}, krs::vec3f{0, 1, 0},
                               krs::vec3f{0, 0, -1}}) {
        march_options o;
        o.lights = {directional_light{l, {1, 1, 1}}};
        const volume_marcher m(store, shape, depth_colors{}, o);
        std::size_t cut_short = 0, worse = 0, shadowed = 0;
        for_each_voxel(m, [&](const krs::vec3f& q, std::uint32_t slot) {
            float lookups = 0;
            const float ray = m.shadow_transmittance(q, m.shading().light_directions()[0], lookups);
            const float swept = m.sweep().toward(0)[slot];
            if (ray >= o.min_transmittance) worse += !(std::abs(swept - ray) <= 1e-5f);
            else worse += !(swept < o.min_transmittance);
            cut_short += lookups > 1.0f; // (the sweep's cuts are what this compares)
            shadowed += ray < 0.5f;
        });
        INFO("light " << l.x << " " << l.y << " " << l.z);
        CHECK(worse == 0);
        CHECK(shadowed > 100);
        CHECK(cut_short > 100);
    }
}

TEST_CASE("hypertree light sweep: images of trees A-D within RMSE 0.01 of the shadow rays'")
{
    // The bound is issue 27's: RMSE <= 0.01 against the shadow rays' image. Measured here
    // (resolution 100, 120 x 120, supersampling 1, sweep_near_steps 1; printed below) up to
    // 0.0068 (tree B per voxel; docs/benchmarks.md); bench_hypertree_render measures less at
    // resolution 300. A sweep that lets all light through (transmittance forced to 1) fails it
    // (see the report of issue 27).
    for (const auto maker : {presets::tree_a, presets::tree_b, presets::tree_c, presets::tree_d}) {
        const ifs<> tree = maker(100);
        const auto store = build_tree<bit_array_store>(tree, 1);
        const tree_shape shape = tree_shape::of(store);
        const depth_colors colors = depth_colors::tree(tree.branch_depth, tree.tree_depth);
        const krs::pinhole_camera camera = framing_camera(shape.box, 120, 120);
        for (const bool per_voxel : {true, false}) {
            march_options o;
            o.shade_per_voxel = per_voxel;
            const image rays = render<krs::packet_f>(volume_marcher(store, shape, colors, by(method::rays, o)), camera);
            const image sweep = render<krs::packet_f>(volume_marcher(store, shape, colors, by(method::sweep, o)), camera);
            const double error = rmse(sweep, rays);
            const std::string which = "tree " + std::string(tree.name) + (per_voxel ? " per voxel" : " per sample");
            INFO(which << ": RMSE " << error);
            MESSAGE(which << ": RMSE " << error);
            CHECK(error <= 0.01);
            // The sweep approximates the shadow rays; an exact match would be news, not a failure.
            if (error == 0.0) MESSAGE("the sweep's image equals the shadow rays' exactly");
        }
    }
}

TEST_CASE("hypertree light sweep: without shadows or lights, the pixels of shadow rays")
{
    const auto store = build_tree<index_list_store>(small_tree_d(), 2);
    const tree_shape shape = tree_shape::of(store);
    const krs::pinhole_camera camera({0.3f, 0.7f, -2.4f}, {0, 0.6f, 0}, {0, 1, 0}, 40, 48, 40);
    march_options no_shadows, no_lights;
    no_shadows.shadows = false;
    no_lights.lights.clear();
    for (const march_options& o : {no_shadows, no_lights}) {
        const volume_marcher rays(store, shape, depth_colors::tree(3, 6), by(method::rays, o));
        const volume_marcher sweep(store, shape, depth_colors::tree(3, 6), by(method::sweep, o));
        CHECK(sweep.sweep().empty());
        const image a = render<krs::packet_f>(rays, camera), b = render<krs::packet_f>(sweep, camera);
        CHECK(a.rgb == b.rgb);
    }
}

namespace {
// A hook on `threads` threads started for the call, taking tasks in order from a shared counter.
parallel_for_hook threads_hook(unsigned threads)
{
    return [threads](std::size_t count, const std::function<void(std::size_t)>& body) {
        std::atomic<std::size_t> next{0};
        const auto work = [&] {
            for (std::size_t i; (i = next++) < count;) body(i);
        };
        std::vector<std::thread> pool;
        for (unsigned t = 1; t < threads; ++t) pool.emplace_back(work);
        work();
        for (std::thread& t : pool) t.join();
    };
}
} // namespace

TEST_CASE("hypertree light sweep: in two passes on 1, 2 and 3 threads, the sweep by levels to the bit")
{
    // make_sweep (rays to their cuts in any order, then the chains of cuts) must give every voxel
    // the value of the sweep by levels in light order (make_sweep_in_light_order), bit for bit,
    // whatever the threads: the same product in the same order. Trees A-D at resolution 100, two
    // lights whose directions differ in sign on x and z. A hook running the tasks on one thread in
    // reverse order checks that no task relies on another's being done.
    const parallel_for_hook reverse = [](std::size_t count, const std::function<void(std::size_t)>& body) {
        for (std::size_t i = count; i-- > 0;) body(i);
    };
    for (const auto maker : {presets::tree_a, presets::tree_b, presets::tree_c, presets::tree_d}) {
        const ifs<> tree = maker(100);
        const auto store = build_tree<bit_array_store>(tree, 1);
        const tree_shape shape = tree_shape::of(store);
        march_options o = by(method::sweep);
        o.lights.push_back(o.lights[0]);
        o.lights[1].direction = {-0.5f, 0.3f, -0.8f};
        const volume_marcher m(store, shape, depth_colors::tree(tree.branch_depth, tree.tree_depth), o);
        const light_sweep reference = m.make_sweep_in_light_order();
        INFO("tree " << tree.name);
        REQUIRE(o.lights.size() == 2);
        for (const auto& [name, table] : {std::pair{std::string("the marcher's (no hook)"), m.sweep()},
                                          std::pair{std::string("2 threads"), m.make_sweep(threads_hook(2))},
                                          std::pair{std::string("3 threads"), m.make_sweep(threads_hook(3))},
                                          std::pair{std::string("one thread, tasks reversed"), m.make_sweep(reverse)}}) {
            std::size_t differ = 0, voxels = 0, cut = 0;
            for (std::size_t i = 0; i < o.lights.size(); ++i)
                for_each_voxel(m, [&](const krs::vec3f& q, std::uint32_t slot) {
                    ++voxels;
                    const float swept = table.toward(i)[slot];
                    differ += std::bit_cast<std::uint32_t>(swept) != std::bit_cast<std::uint32_t>(reference.toward(i)[slot]);
                    float lookups = 0;
                    cut += m.shadow_transmittance(q, m.shading().light_directions()[i], lookups) != swept;
                });
            INFO(name << ": " << differ << " of " << voxels << " entries differ; " << cut << " differ from the full shadow ray");
            CHECK(voxels == 2 * m.bricks().voxel_count());
            CHECK(differ == 0);
            CHECK(cut > voxels / 10); // (the chains are used: many voxels are not their full shadow ray)
        }
    }
}

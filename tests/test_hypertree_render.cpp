// The hypertree raymarcher (paper section 8) against closed forms and against itself with its
// accelerations off: packets equal scalar rays, bounding spheres and the ray cache change no pixel.

#include "hypertree/hypertree.hpp"
#include "hypertree/presets.hpp"
#include "hypertree/render/render.hpp"

#include "support/brick_walk_rays.hpp"
#include "support/small_tree.hpp"
#include "support/threads.hpp"

#include <doctest/doctest.h>

#include <algorithm>
#include <atomic>
#include <cmath>
#include <optional>
#include <thread>

using namespace hypertree;
using krs_test::small_tree_d;

namespace {

// A slab of `thickness` voxels of one density, across a 32^3 unit-cell volume.
index_list_store slab(std::uint8_t density, int thickness)
{
    const hypervolume v({0, 0, 0}, {32, 32, 32}, resolution::cube(32));
    std::vector<stored_voxel> voxels;
    for (int z = 0; z < 32; ++z)
        for (int y = 0; y < 32; ++y)
            for (int x = 10; x < 10 + thickness; ++x) voxels.push_back({v.index(x, y, z), {density, 3}, 0});
    std::sort(voxels.begin(), voxels.end(), [](const stored_voxel& a, const stored_voxel& b) { return a.index < b.index; });
    return index_list_store::build(v, voxels);
}

double max_difference(const image& a, const image& b)
{
    REQUIRE(a.rgb.size() == b.rgb.size());
    double worst = 0;
    for (std::size_t i = 0; i < a.rgb.size(); ++i) {
        REQUIRE(std::isfinite(a.rgb[i])); // a NaN would pass any comparison of differences
        REQUIRE(std::isfinite(b.rgb[i]));
        worst = std::max(worst, double(std::abs(a.rgb[i] - b.rgb[i])));
    }
    return worst;
}

struct small_scene {
    index_list_store list;
    partitioned_store parts;
    explicit small_scene(const ifs<>& t) : list(build_tree<index_list_store>(t, 2)), parts(build_tree<partitioned_store>(t, 2)) {}
};

} // namespace

TEST_CASE("hypertree render transmittance through a slab matches the closed form")
{
    for (int density : {40, 128, 230}) {
        for (float step_factor : {1.0f, 0.5f}) {
            const auto store = slab(std::uint8_t(density), 3);
            march_options o;
            o.step_factor = step_factor;
            o.min_transmittance = 0;
            o.shadows = false;
            const volume_marcher m(store, tree_shape::of(store), depth_colors{}, o);
            // Along x through voxel centers: 3 voxels = 3 / step_factor samples of one density.
            const krs::ray<float> r{{-1, 16.5f, 16.5f}, {1, 0, 0}};
            const auto result = m.march(r);
            const double mu = density / 255.0;
            const double expect = std::pow(1 - mu, 3.0); // (1 - mu)^(k * length / side), k = 1
            CAPTURE(density);
            CAPTURE(step_factor);
            CHECK(result.transmittance == doctest::Approx(expect).epsilon(1e-5));
        }
    }
}

TEST_CASE("hypertree render stops at full opacity and shadows behind an opaque wall")
{
    const auto store = slab(255, 2);
    march_options o;
    o.shadow_by = march_options::shadow_method::rays; // (the sweep's shading reads its table: no lookup)
    const volume_marcher m(store, tree_shape::of(store), depth_colors{}, o);
    const auto result = m.march(krs::ray<float>{{-1, 16.5f, 16.5f}, {1, 0, 0}});
    CHECK(result.transmittance == 0.0f);
    CHECK(result.lookups == doctest::Approx(1 + 1)); // the first sample (and its shadow ray's first)
    float lookups = 0;
    // From x = 5 the wall (x in [10, 12)) is toward +x; toward -x the way is open.
    CHECK(m.shadow_transmittance({5, 16.5f, 16.5f}, {-1, 0, 0}, lookups) == 1.0f);
    CHECK(m.shadow_transmittance({5, 16.5f, 16.5f}, {1, 0, 0}, lookups) == 0.0f);
}

TEST_CASE("hypertree render of an empty tree is the background")
{
    const hypervolume v({0, 0, 0}, {1, 1, 1}, resolution::cube(8));
    const index_list_store empty = index_list_store::build(v, {});
    // With the empty box of an empty tree no ray enters; with a box given, rays and shadow rays
    // cross the grid and find nothing.
    tree_shape boxed = tree_shape::of(empty);
    boxed.box = world_box{{0, 0, 0}, {1, 1, 1}};
    for (const tree_shape& shape : {tree_shape::of(empty), boxed}) {
        const volume_marcher m(empty, shape, depth_colors{});
        float lookups = 0;
        CHECK(m.shadow_transmittance({0.5f, 0.5f, 0.5f}, {0, 1, 0}, lookups) == 1.0f);
        CHECK(m.march(krs::ray<float>{{0.5f, 0.5f, -2.0f}, {0, 0, 1}}).transmittance == 1.0f);
        const krs::pinhole_camera camera({0.5f, 0.5f, -2.0f}, {0.5f, 0.5f, 0.5f}, {0, 1, 0}, 40, 16, 12);
        render_settings s;
        for (bool ahead : {true, false}) {
            s.shade_ahead = ahead;
            for (const image& i : {render<float>(m, camera, s), render<krs::packet_f>(m, camera, s)}) {
                CHECK(i.lookups == 0);
                for (std::size_t p = 0; p < i.rgb.size(); p += 3) {
                    REQUIRE(i.rgb[p] == s.background.r);
                    REQUIRE(i.rgb[p + 1] == s.background.g);
                    REQUIRE(i.rgb[p + 2] == s.background.b);
                }
            }
        }
    }
}

TEST_CASE("hypertree render: skipping empty bricks never skips a voxel, from a camera far away and with fine steps")
{
    // A checkerboard of full and empty 4^3 bricks of faint voxels (every empty brick's exit face
    // borders voxels, so a skip one sample too long misses one) seen from far away, each ray
    // marched against a reference that takes every sample with the same float formulas and no
    // skipping: the transmittances must be equal, bit for bit.
    const hypervolume v({-1, -1, -1}, {2, 2, 2}, resolution::cube(48));
    std::vector<stored_voxel> voxels;
    std::uint32_t state = 5;
    for (voxel_index i = 0; i < v.voxel_count(); ++i) {
        state = state * 1664525u + 1013904223u;
        const auto c = v.coordinates(i);
        if (((c[0] >> 2) + (c[1] >> 2) + (c[2] >> 2)) % 2) voxels.push_back({i, {std::uint8_t(1 + (state >> 8) % 6), 4}, 0});
    }
    const index_list_store store = index_list_store::build(v, voxels);
    const tree_shape shape = tree_shape::of(store);
    std::size_t rays = 0, partly_opaque = 0;
    for (float step_factor : {1.0f, 0.3f}) {
        march_options o;
        o.step_factor = step_factor;
        o.shadows = false;
        o.lights.clear();
        o.min_transmittance = 0;
        const volume_marcher m(store, shape, depth_colors{}, o);
        // The reference: samples at t0 + (k + 1/2) ds from the box's slab entry, each looked up.
        const float ds = m.step();
        const double exponent = double(step_factor);
        const auto reference = [&](const krs::ray<float>& r) {
            const krs::vec3f lo(shape.box.lo), hi(shape.box.hi);
            float t0 = 0, t1 = 3.0e38f;
            const float o3[3] = {r.origin.x, r.origin.y, r.origin.z}, d3[3] = {r.direction.x, r.direction.y, r.direction.z};
            const float l3[3] = {lo.x, lo.y, lo.z}, h3[3] = {hi.x, hi.y, hi.z};
            for (int a = 0; a < 3; ++a) {
                const float safe = std::abs(d3[a]) < 1e-30f ? 1e-30f : d3[a], inv = 1.0f / safe;
                const float ta = (l3[a] - o3[a]) * inv, tb = (h3[a] - o3[a]) * inv;
                t0 = std::max(t0, std::min(ta, tb)), t1 = std::min(t1, std::max(ta, tb));
            }
            float transmittance = 1;
            const krs::vec3f origin(v.origin()), per_unit(v.cells_per_unit());
            for (float k = 0;; k += 1) {
                const float t = t0 + (k + 0.5f) * ds;
                if (!(t < t1)) break;
                const krs::vec3f p = r.origin + r.direction * t;
                const float f[3] = {(p.x - origin.x) * per_unit.x, (p.y - origin.y) * per_unit.y, (p.z - origin.z) * per_unit.z};
                if (!(f[0] >= 0 && f[1] >= 0 && f[2] >= 0 && f[0] < 48 && f[1] < 48 && f[2] < 48)) continue;
                const int c[3] = {std::min(int(f[0]), 47), std::min(int(f[1]), 47), std::min(int(f[2]), 47)};
                const int d = store.at(v.index(c[0], c[1], c[2])).density;
                const float alpha = d == 255 ? 1.0f : float(1.0 - std::pow(1.0 - d / 255.0, exponent));
                transmittance *= 1.0f - alpha;
            }
            return transmittance;
        };
        for (float distance : {3.0f, 300.0f, 3000.0f}) {
            for (int n = 0; n < 400; ++n) {
                state = state * 1664525u + 1013904223u;
                const float a = float(state >> 8) * 0x1.0p-24f * 6.2831853f;
                state = state * 1664525u + 1013904223u;
                const float b = float(state >> 8) * 0x1.0p-24f * 2 - 1;
                const krs::vec3f eye = krs::vec3f{std::cos(a) * std::sqrt(1 - b * b), b, std::sin(a) * std::sqrt(1 - b * b)} * distance;
                // Aimed at a random voxel, so the ray meets at least one.
                const krs::vec3f target(v.voxel_center(voxels[(state >> 4) % voxels.size()].index));
                const krs::ray<float> r{eye, krs::normalize(target - eye)};
                const float expect = reference(r);
                REQUIRE(m.march(r).transmittance == expect);
                ++rays, partly_opaque += expect < 1.0f;
            }
        }
    }
    CHECK(partly_opaque > rays / 2);
}

TEST_CASE("hypertree render refuses bad options, naming them")
{
    const auto store = slab(100, 2);
    const tree_shape shape = tree_shape::of(store);
    // The options alone, the marcher and the GLSL emitter refuse alike.
    const auto refuses = [&](march_options o, const char* parameter) {
        CHECK_THROWS_WITH_AS(o.validate(store.volume(), shape.box), doctest::Contains(parameter), krs::invalid_parameter);
        CHECK_THROWS_WITH_AS(volume_marcher(store, shape, depth_colors{}, o), doctest::Contains(parameter),
                             krs::invalid_parameter);
        CHECK_THROWS_WITH_AS(hypertree_glsl(store, shape, depth_colors{}, o), doctest::Contains(parameter), krs::invalid_parameter);
    };
    for (float bad : {0.0f, -1.0f, std::nanf("")}) {
        march_options o;
        o.step_factor = bad;
        refuses(o, "march_options.step_factor");
        o = {};
        o.density_scale = bad;
        refuses(o, "march_options.density_scale");
    }
    march_options o;
    o.min_transmittance = -0.5f;
    refuses(o, "march_options.min_transmittance");
    // Steps so fine that a ray would count more samples than a float counts exactly.
    o = {};
    o.step_factor = 1e-6f;
    refuses(o, "march_options.step_factor");
    CHECK_NOTHROW(o.validate()); // (a bound of the tree, not of the options alone)
    o.step_factor = 1e-4f; // 450 000 samples across the slab's box (diagonal 45): fine
    CHECK_NOTHROW(volume_marcher(store, shape, depth_colors{}, o));
    CHECK_NOTHROW(o.validate(store.volume(), shape.box));
    o = {};
    o.lights.assign(9, directional_light{});
    refuses(o, "march_options.lights");
    o.lights = {directional_light{{0, 0, 0}, {1, 1, 1}}};
    refuses(o, "march_options.lights.direction");
    // An infinite component normalized to NaN, and the shadow rays never ended (render hung).
    o.lights = {directional_light{{INFINITY, 0, 0}, {1, 1, 1}}};
    refuses(o, "march_options.lights.direction");
    // Shading terms: NaN or infinite ones made covered pixels NaN, a negative ambient negative,
    // and a transmittance floor above 1 stopped every ray at its first sample.
    const std::pair<float march_options::*, const char*> terms[] = {
        {&march_options::ambient, "march_options.ambient"},   {&march_options::ambient_falloff, "march_options.ambient_falloff"},
        {&march_options::diffuse, "march_options.diffuse"},   {&march_options::specular, "march_options.specular"},
        {&march_options::shininess, "march_options.shininess"}};
    for (float bad : {std::nanf(""), INFINITY, -5.0f}) {
        for (const auto& [term, name] : terms) {
            o = {};
            o.*term = bad;
            refuses(o, name);
        }
        o = {};
        o.lights = {directional_light{{0, 1, 0}, {bad, 1, 1}}};
        refuses(o, "march_options.lights.color");
    }
    o = {};
    o.min_transmittance = 2.0f;
    refuses(o, "march_options.min_transmittance");
    o = {};
    o.shadow_by = march_options::shadow_method(7);
    refuses(o, "march_options.shadow_by");
    for (int bad : {0, -3, (1 << 20) + 1}) {
        o = {};
        o.sweep_near_steps = bad;
        refuses(o, "march_options.sweep_near_steps");
    }
    CHECK_THROWS_WITH_AS(volume_marcher(store, shape, depth_colors({{0, 3, {std::nanf(""), 0, 0}, {1, 1, 1}}})),
                         doctest::Contains("depth_colors.first"), krs::invalid_parameter);
    const volume_marcher m(store, shape, depth_colors{});
    const krs::pinhole_camera camera({16, 16, -40}, {16, 16, 16}, {0, 1, 0}, 40, 8, 8);
    for (int s : {0, 17}) {
        render_settings rs;
        rs.supersampling = s;
        CHECK_THROWS_WITH_AS(render<float>(m, camera, rs), doctest::Contains("render_settings.supersampling"), krs::invalid_parameter);
    }
    render_settings dark;
    dark.background = {std::nanf(""), 0, 0};
    CHECK_THROWS_WITH_AS(render<float>(m, camera, dark), doctest::Contains("render_settings.background"), krs::invalid_parameter);
    // A ray of zero, tiny or non-finite direction, or from a non-finite origin, misses: a zero
    // direction's span of 1e30 was never crossed by the float sample count (march hung).
    for (const krs::ray<float>& bad :
         {krs::ray<float>{{-40, 16.5f, 16.5f}, {0, 0, 0}}, krs::ray<float>{{-40, 16.5f, 16.5f}, {1e-20f, 0, 0}},
          krs::ray<float>{{-40, 16.5f, 16.5f}, {std::nanf(""), 0, 0}}, krs::ray<float>{{std::nanf(""), 16.5f, 16.5f}, {1, 0, 0}}}) {
        const march_result<float> r = m.march(bad);
        CHECK(r.transmittance == 1.0f);
        CHECK(r.lookups == 0.0f);
    }
    CHECK(m.march(krs::ray<float>{{-40, 16.5f, 16.5f}, {1, 0, 0}}).transmittance < 1.0f); // a unit ray through the slab does
}

TEST_CASE("hypertree render packets give the scalar pixels")
{
    const small_scene scene(small_tree_d());
    const auto shape = tree_shape::of(scene.parts);
    const volume_marcher m(scene.parts, shape, depth_colors::tree(3, 6));
    const krs::pinhole_camera camera({0.3f, 0.7f, -2.4f}, {0, 0.6f, 0}, {0, 1, 0}, 40, 48, 40);
    render_settings s;
    s.supersampling = 2;
    const image scalar = render<float>(m, camera, s);
    const image packet = render<krs::packet_f>(m, camera, s);
    CHECK(max_difference(scalar, packet) == 0.0);
    // Threads share a shading memo behind their own: which thread renders a band of rows changes
    // no pixel, and a voxel's shadow rays are marched about once whatever the thread count.
    render_settings threaded = s;
    threaded.parallel_for = krs_test::strided_threads(3);
    const image threaded_image = render<krs::packet_f>(m, camera, threaded);
    CHECK(max_difference(threaded_image, scalar) == 0.0);
    // (Measured: 0.2% more lookups than serial shared, 6.5% more with a memo per thread alone;
    // shadow rays are short in this small tree.)
    INFO("threaded " << threaded_image.lookups << " serial " << packet.lookups);
    CHECK(double(threaded_image.lookups) <= 1.03 * double(packet.lookups));
    // Not a blank image: some pixels differ from the background by a lot.
    std::size_t covered = 0;
    for (std::size_t i = 0; i < scalar.rgb.size(); i += 3) covered += std::abs(scalar.rgb[i + 2] - s.background.b) > 0.2f;
    CHECK(covered > 100);
}

TEST_CASE("hypertree render bounding spheres and the ray cache change no pixel")
{
    const small_scene scene(small_tree_d());
    const auto shape = tree_shape::of(scene.parts);
    REQUIRE(shape.spheres.size() > 3);
    march_options with, without;
    with.bounds_by = bound_method::spheres;
    without.bounds_by = bound_method::box;
    const volume_marcher a(scene.list, shape, depth_colors::tree(3, 6), with);
    const volume_marcher b(scene.list, shape, depth_colors::tree(3, 6), without);
    const krs::pinhole_camera camera({0.0f, 0.7f, -2.2f}, {0, 0.6f, 0}, {0, 1, 0}, 45, 64, 56);
    const image with_spheres = render<float>(a, camera), box_only = render<float>(b, camera);
    CHECK(max_difference(with_spheres, box_only) == 0.0); // "change no pixel": not a one
    CHECK(with_spheres.lookups < box_only.lookups);
    render_settings cached;
    cached.ray_cache = true;
    CHECK(max_difference(render<float>(a, camera, cached), with_spheres) == 0.0);
}

TEST_CASE("hypertree render: a marcher outlives the store it was made from")
{
    // Issue 26: the marcher keeps its own volume and bricks, no pointer into the store. Its store
    // is destroyed and another store built in the same place before the march: a read through a
    // dangling pointer would see the other store (or, in the suite's ASan build, freed memory).
    const auto definition = small_tree_d();
    const index_list_store alive = build_tree<index_list_store>(definition, 2);
    const auto shape = tree_shape::of(alive);
    const depth_colors colors = depth_colors::tree(3, 6);
    std::optional<index_list_store> gone(build_tree<index_list_store>(definition, 2));
    const volume_marcher survivor(*gone, shape, colors, march_options{});
    gone.emplace(slab(230, 8)); // the tree's store destroyed, a slab in its place
    const volume_marcher reference(alive, shape, colors, march_options{});
    const krs::pinhole_camera camera({0.0f, 0.7f, -2.2f}, {0, 0.6f, 0}, {0, 1, 0}, 45, 48, 40);
    render_settings settings;
    const image after = render<float>(survivor, camera, settings), expected = render<float>(reference, camera, settings);
    CHECK(max_difference(after, expected) == 0.0);
    std::size_t covered = 0;
    for (std::size_t i = 0; i < expected.rgb.size(); i += 3) covered += std::abs(expected.rgb[i + 2] - settings.background.b) > 0.2f;
    CHECK(covered > 50); // the tree is in view, so a wrong store would show
}

TEST_CASE("hypertree render supersampling factor follows the projected voxel size")
{
    const auto t = small_tree_d();
    const small_scene scene(t);
    const auto shape = tree_shape::of(scene.parts);
    const krs::vec3f target = shape.crown.center;
    for (float distance : {1.0f, 4.0f, 16.0f}) {
        const krs::vec3f eye = target - krs::vec3f{0, 0, distance};
        const krs::pinhole_camera camera(eye, target, {0, 1, 0}, 40, 300, 300);
        // s = ceil(pixel side / voxel side) at the tree's distance: ceil(sqrt(area ratio)).
        const double pixel = 2 * std::tan(20.0 * 3.141592653589793 / 180) / 300 * distance;
        const int expect = std::max(1, int(std::ceil(pixel / t.volume.smallest_voxel_side() - 1e-9)));
        CHECK(supersampling_for(camera, shape, t.volume) == expect);
    }
    // Far away the quotient passed INT_MAX (undefined as an int, and 1 came back); render()
    // takes 1 to 16, so that is the range.
    const krs::pinhole_camera far(target - krs::vec3f{0, 0, 1e9f}, target, {0, 1, 0}, 40, 300, 300);
    CHECK(supersampling_for(far, shape, t.volume) == 16);
}

TEST_CASE("hypertree render framing_camera sees the whole box and refuses an empty tree")
{
    const world_box box{{-0.5, 0.0, -0.4}, {0.7, 1.3, 0.6}};
    const krs::pinhole_camera camera = framing_camera(box, 120, 80);
    // Every corner of the box projects inside the image: its direction from the eye lies within
    // the half-angles of the view (the camera's own ray through the image edge bounds them).
    const krs::vec3d eye(camera.eye());
    const krs::vec3d forward = krs::normalize(krs::vec3d(camera.primary_ray(60.0f, 40.0f).direction));
    const double tan_half_v = std::tan(20.0 * 3.141592653589793 / 180.0), tan_half_h = tan_half_v * 120.0 / 80.0;
    const krs::vec3d up_hint{0, 1, 0};
    const krs::vec3d right = krs::normalize(krs::cross(forward, up_hint)), up = krs::cross(right, forward);
    for (int c = 0; c < 8; ++c) {
        const krs::vec3d corner{(c & 1) ? box.hi.x : box.lo.x, (c & 2) ? box.hi.y : box.lo.y, (c & 4) ? box.hi.z : box.lo.z};
        const krs::vec3d d = corner - eye;
        const double depth = krs::dot(d, forward);
        CHECK(depth > 0);
        CHECK(std::abs(krs::dot(d, right)) / depth < tan_half_h);
        CHECK(std::abs(krs::dot(d, up)) / depth < tan_half_v);
    }
    CHECK_THROWS_WITH_AS(framing_camera(world_box{}, 64, 64), doctest::Contains("framing_camera.box"), krs::invalid_parameter);
    for (float fov : {0.0f, 180.0f, std::nanf("")})
        CHECK_THROWS_WITH_AS(framing_camera(box, 64, 64, fov), doctest::Contains("framing_camera.vertical_fov_degrees"),
                             krs::invalid_parameter);
}

TEST_CASE("hypertree shade memo: concurrent readers only ever see whole entries, and a sealed table is whole")
{
    // Two threads store and look up the same slots; an entry's values are a function of its
    // slot, so a copy seen before its values were all written would show.
    shade_memo memo(1000, 5);
    const auto value = [](std::size_t v, std::size_t i) { return float(v) * 8.0f + float(i); };
    std::atomic<long long> found{0}, wrong{0};
    const auto work = [&](std::uint32_t seed) {
        std::uint32_t state = seed;
        float out[5], in[5];
        for (int n = 0; n < 200000; ++n) {
            state = state * 1664525u + 1013904223u;
            const std::size_t v = (state >> 8) % 1000;
            if (memo.find(v, out)) {
                ++found;
                for (std::size_t i = 0; i < 5; ++i) wrong += out[i] != value(v, i) ? 1 : 0;
            } else {
                for (std::size_t i = 0; i < 5; ++i) in[i] = value(v, i);
                memo.store(v, in);
            }
        }
    };
    std::thread other(work, 7u);
    work(11u);
    other.join();
    CHECK(wrong == 0);
    CHECK(found > 1000); // the table is used, not just written
    // A slot past the table is neither found nor stored.
    float out[5] = {};
    CHECK_FALSE(memo.find(5000, out));
    memo.store(5000, out);
    // Sealed only when every slot is recorded; then its values read directly.
    shade_memo partial(10, 2);
    const float in[2] = {1.0f, 2.0f};
    for (std::size_t v = 0; v < 9; ++v) partial.store(v, in);
    CHECK_FALSE(partial.seal());
    CHECK_FALSE(partial.complete());
    partial.store(9, in);
    CHECK(partial.seal());
    CHECK(partial.values()[2 * 9 + 1] == 2.0f);
}

namespace {

// A store whose voxels are scattered at random over a 37 x 21 x 50 grid (sides that are not
// multiples of 4 or 16), with a dense run along one row, whole empty 16^3 blocks, and one empty
// aligned cube of 32^3 (x and z below 32; the grid's 21 rows of y are all in it).
index_list_store scattered_store(std::uint32_t seed)
{
    const hypervolume v({0, 0, 0}, {3.7, 2.1, 5.0}, resolution{37, 21, 50});
    std::vector<stored_voxel> voxels;
    std::uint32_t state = seed;
    for (voxel_index i = 0; i < v.voxel_count(); ++i) {
        state = state * 1664525u + 1013904223u;
        const auto c = v.coordinates(i);
        const bool row = c[1] == 20 && c[2] == 49;
        if (c[2] >= 16 && c[2] < 32 && !row) continue; // an empty slab of blocks
        if (c[0] < 32 && c[2] < 32) continue;         // and the empty cube
        if (row || (state >> 24) < 8) voxels.push_back({i, {std::uint8_t(1 + (state >> 8) % 255), std::uint8_t((state >> 16) % 7)}, 0});
    }
    return index_list_store::build(v, voxels);
}

} // namespace

TEST_CASE("hypertree voxel bricks hold exactly the store's voxels")
{
    for (std::uint32_t seed : {1u, 2u}) {
        const auto store = scattered_store(seed);
        const voxel_bricks bricks(store);
        const hypervolume& v = store.volume();
        CHECK(bricks.voxel_count() == store.nonempty_count());
        std::vector<int> slot_seen(bricks.voxel_count(), 0);
        const voxel_bricks::view view = bricks.view_of();
        // The reference occupancy: a prefix sum of the store's non-empty voxels, so a box's count
        // is 8 reads (cells past the grid hold nothing).
        const int nx = v.grid().x, ny = v.grid().y, nz = v.grid().z;
        std::vector<int> sum(std::size_t(nx + 1) * std::size_t(ny + 1) * std::size_t(nz + 1), 0);
        const auto S = [&](int x, int y, int z) -> int& { return sum[std::size_t(x) + std::size_t(nx + 1) * (std::size_t(y) + std::size_t(ny + 1) * std::size_t(z))]; };
        for (int z = 1; z <= nz; ++z)
            for (int y = 1; y <= ny; ++y)
                for (int x = 1; x <= nx; ++x)
                    S(x, y, z) = (store.at(v.index(x - 1, y - 1, z - 1)).density != 0) + S(x - 1, y, z) + S(x, y - 1, z) + S(x, y, z - 1) -
                                 S(x - 1, y - 1, z) - S(x - 1, y, z - 1) - S(x, y - 1, z - 1) + S(x - 1, y - 1, z - 1);
        // Non-empty voxels in the aligned cube of `side` cells holding cell (x, y, z).
        const auto in_cube = [&](int x, int y, int z, int side) {
            const int x0 = std::min(nx, x & -side), y0 = std::min(ny, y & -side), z0 = std::min(nz, z & -side);
            const int x1 = std::min(nx, x0 + side), y1 = std::min(ny, y0 + side), z1 = std::min(nz, z0 + side);
            return S(x1, y1, z1) - S(x0, y1, z1) - S(x1, y0, z1) - S(x1, y1, z0) + S(x0, y0, z1) + S(x0, y1, z0) + S(x1, y0, z0) - S(x0, y0, z0);
        };
        std::size_t empty_bricks = 0, empty_blocks = 0, coarse = 0;
        for (int z = 0; z < v.grid().z; ++z)
            for (int y = 0; y < v.grid().y; ++y)
                for (int x = 0; x < v.grid().x; ++x) {
                    const voxel expect = store.at(v.index(x, y, z));
                    const voxel got = bricks.at(x, y, z);
                    REQUIRE(got.density == expect.density);
                    REQUIRE(got.level == expect.level);
                    // The place's sign says whether the brick holds a voxel, and an empty
                    // brick's level e names the largest empty aligned cube around it: the cube
                    // of 4 << e cells is empty and the one of 8 << e is not (unless it already
                    // covers the grid), checked against the store's voxels by the prefix sum.
                    const std::int32_t place = view.place(x, y, z);
                    REQUIRE((place >= 0) == (in_cube(x, y, z, 4) > 0));
                    if (place < 0) {
                        const int e = voxel_bricks::view::empty_level(place), side = 4 << e;
                        REQUIRE(e >= 0);
                        REQUIRE(place == -64 * (e + 1) + ((x & 3) | (y & 3) << 2 | (z & 3) << 4));
                        REQUIRE(e <= bricks.empty_levels());
                        CHECK(in_cube(x, y, z, side) == 0);
                        const bool whole_grid = side >= nx && side >= ny && side >= nz;
                        if (!whole_grid) CHECK(in_cube(x, y, z, 2 * side) > 0);
                        coarse += e >= 3;
                    }
                    // The reference walk's place: below -64 exactly where the 16^3 block is empty.
                    const std::int32_t by_blocks = view.place_by_blocks(x, y, z);
                    REQUIRE((by_blocks >= 0) == (place >= 0));
                    REQUIRE((by_blocks < -64) == (in_cube(x, y, z, 16) == 0));
                    if (place >= 0) REQUIRE(by_blocks == place);
                    empty_bricks += place < 0, empty_blocks += by_blocks < -64;
                    if (expect.density != 0) ++slot_seen[bricks.slot(std::size_t(place))];
                }
        // Every non-empty voxel has its own slot.
        CHECK(std::count(slot_seen.begin(), slot_seen.end(), 1) == std::ptrdiff_t(slot_seen.size()));
        CHECK(empty_bricks > 1000); // the cases occur
        CHECK(empty_blocks > 1000);
        CHECK(coarse > 1000);
        // The lanes' lookup gives each lane the scalar place.
        using I = krs::index_lanes<krs::packet_f>;
        constexpr std::size_t n = krs::lane_count<krs::packet_f>;
        std::uint32_t state = seed;
        for (int round = 0; round < 200; ++round) {
            alignas(64) std::int32_t c[3][n];
            for (std::size_t k = 0; k < n; ++k) {
                state = state * 1664525u + 1013904223u;
                c[0][k] = std::int32_t((state >> 8) % 37), c[1][k] = std::int32_t((state >> 12) % 21), c[2][k] = std::int32_t((state >> 17) % 50);
            }
            alignas(64) std::int32_t places[n];
            view.place(I::load_aligned(c[0]), I::load_aligned(c[1]), I::load_aligned(c[2])).store_aligned(places);
            for (std::size_t k = 0; k < n; ++k) REQUIRE(places[k] == view.place(c[0][k], c[1][k], c[2][k]));
            view.place_by_blocks(I::load_aligned(c[0]), I::load_aligned(c[1]), I::load_aligned(c[2])).store_aligned(places);
            for (std::size_t k = 0; k < n; ++k) REQUIRE(places[k] == view.place_by_blocks(c[0][k], c[1][k], c[2][k]));
        }
    }
}

TEST_CASE("hypertree shadow rays: a packet of points gives each lane the scalar transmittance")
{
    const small_scene scene(small_tree_d());
    const auto shape = tree_shape::of(scene.list);
    for (bool spheres : {false, true}) {
        march_options o;
        o.bounds_by = spheres ? bound_method::spheres : bound_method::box;
        const volume_marcher m(scene.list, shape, depth_colors::tree(3, 6), o);
        const hypervolume& v = scene.list.volume();
        constexpr std::size_t n = krs::lane_count<krs::packet_f>;
        // Shadow rays from every non-empty voxel's center (and from points between voxels),
        // toward two lights, n at a time; the last packet runs part of its lanes.
        std::vector<krs::vec3f> points;
        scene.list.for_each([&](voxel_index i, const voxel&) {
            const krs::vec3d c = v.voxel_center(i);
            points.push_back(krs::vec3f(c));
            points.push_back(krs::vec3f(c + v.voxel_size() * 0.37));
        });
        if (points.size() % n == 0) points.push_back(points.back() + krs::vec3f{0.01f, 0.02f, 0.03f});
        REQUIRE(points.size() % n != 0); // a last packet with idle lanes
        std::size_t shadowed = 0;
        for (const krs::vec3f l : {krs::normalize(krs::vec3f{0.4f, 0.8f, 0.45f}), krs::vec3f{0, 0, -1}}) {
            for (std::size_t first = 0; first < points.size(); first += n) {
                const std::size_t count = std::min(n, points.size() - first);
                std::array<float, n> x{}, y{}, z{};
                for (std::size_t k = 0; k < n; ++k) {
                    const krs::vec3f q = points[first + std::min(k, count - 1)];
                    x[k] = q.x, y[k] = q.y, z[k] = q.z;
                }
                const krs::vec3<krs::packet_f> p{krs::packet_f::load_unaligned(x.data()), krs::packet_f::load_unaligned(y.data()),
                                                 krs::packet_f::load_unaligned(z.data())};
                krs::packet_f lookups(0.0f);
                const auto running = krs::mask_from_bits<krs::packet_f>((std::uint64_t(1) << count) - 1);
                const auto t = krs::lanes_of(m.shadow_transmittance<krs::packet_f>(p, l, lookups, running));
                const auto looked = krs::lanes_of(lookups);
                for (std::size_t k = 0; k < count; ++k) {
                    float scalar_lookups = 0;
                    const float expect = m.shadow_transmittance(points[first + k], l, scalar_lookups);
                    REQUIRE(t[k] == expect);
                    REQUIRE(looked[k] == scalar_lookups);
                    shadowed += expect < 0.5f;
                }
                for (std::size_t k = count; k < n; ++k) REQUIRE(looked[k] == 0.0f); // idle lanes read nothing
            }
        }
        CHECK(shadowed > points.size() / 10);
    }
}

TEST_CASE("hypertree render: voxels shaded ahead, in packets, give the pixels of voxels shaded as rays meet them")
{
    const small_scene scene(small_tree_d());
    const auto shape = tree_shape::of(scene.list);
    march_options two_lights;
    two_lights.lights.push_back({{-0.7f, 0.3f, -0.2f}, {0.3f, 0.4f, 0.9f}});
    march_options spheres;
    spheres.bounds_by = bound_method::spheres;
    march_options rays, rays_two_lights = two_lights;
    rays.shadow_by = rays_two_lights.shadow_by = march_options::shadow_method::rays;
    const krs::pinhole_camera camera({0.3f, 0.7f, -2.4f}, {0, 0.6f, 0}, {0, 1, 0}, 40, 48, 40);
    for (const march_options& o : {march_options{}, two_lights, spheres, rays, rays_two_lights}) {
        const volume_marcher m(scene.list, shape, depth_colors::tree(3, 6), o);
        // The shading pass: packets of voxels and one voxel at a time store the same values.
        shade_memo packets = m.new_shade_memo(), scalars = m.new_shade_memo();
        m.shade_bricks<krs::packet_f>(packets, 0, m.bricks().brick_count());
        m.shade_bricks<float>(scalars, 0, m.bricks().brick_count());
        REQUIRE(packets.seal());
        REQUIRE(scalars.seal());
        const std::size_t values = packets.slots() * packets.stride();
        CHECK(std::equal(packets.values(), packets.values() + values, scalars.values()));
        // Rays reading a sealed table (march_in_step) and rays shading as they go (march_shading_as_met).
        render_settings ahead, as_met;
        as_met.shade_ahead = false;
        for (int s : {1, 2}) {
            ahead.supersampling = as_met.supersampling = s;
            const image a = render<krs::packet_f>(m, camera, ahead), b = render<krs::packet_f>(m, camera, as_met);
            const image c = render<float>(m, camera, ahead), d = render<float>(m, camera, as_met);
            CHECK(max_difference(a, b) == 0.0);
            CHECK(max_difference(a, c) == 0.0);
            CHECK(max_difference(a, d) == 0.0);
            // Shading ahead shades every voxel, visible or not; as met, only those rays reach. (With
            // the sweep, shading reads the swept table and looks nothing up.)
            CHECK(a.lookups == c.lookups);
            CHECK(b.lookups == d.lookups);
            if (o.shadow_by == march_options::shadow_method::rays) CHECK(b.lookups < a.lookups);
            else CHECK(b.lookups == a.lookups);
        }
    }
}

TEST_CASE("hypertree render: the walk of empty cubes of every level gives the reference walk's pixels, trees A-D and a forest")
{
    // The two walks look at the same samples (test_hypertree_brick_walk.cpp), so every pixel and
    // every lookup count must be equal, scalar and packet, voxels shaded ahead or as met; ray by
    // ray, the walk of every level never probes more samples.
    std::size_t rays = 0, fewer = 0;
    const auto compare = [&](const auto& store, const std::string& name) {
        INFO(name);
        const tree_shape shape = tree_shape::of(store);
        const depth_colors colors = depth_colors::tree(3, 6);
        const volume_marcher levels(store, shape, colors), blocks(store, shape, colors, march_options{}, {}, brick_walk::skips::bricks_and_blocks);
        const krs::pinhole_camera camera = framing_camera(shape.box, 40, 32);
        for (bool ahead : {true, false}) {
            render_settings s;
            s.shade_ahead = ahead;
            const image a = render<float>(levels, camera, s), b = render<float>(blocks, camera, s);
            const image pa = render<krs::packet_f>(levels, camera, s), pb = render<krs::packet_f>(blocks, camera, s);
            CHECK(max_difference(a, b) == 0.0);
            CHECK(max_difference(pa, pb) == 0.0);
            CHECK(a.lookups == b.lookups);
            CHECK(pa.lookups == pb.lookups);
        }
        for (int y = 0; y < 32; ++y)
            for (int x = 0; x < 40; ++x) {
                const krs::ray<float> r = camera.primary_ray(float(x) + 0.5f, float(y) + 0.5f);
                const march_result<float> a = levels.march(r), b = blocks.march(r);
                REQUIRE(a.transmittance == b.transmittance);
                REQUIRE(a.lookups == b.lookups);
                REQUIRE(a.probes <= b.probes);
                ++rays, fewer += a.probes < b.probes;
            }
    };
    for (const auto& maker : {presets::tree_a, presets::tree_b, presets::tree_c, presets::tree_d}) {
        auto t = maker(40);
        t.iterations = 30000;
        compare(build_tree<dense_store>(t, 2), t.name);
    }
    const krs_test::forest forest(3);
    compare(forest.store, "forest");
    INFO(fewer << " of " << rays << " rays took fewer probes");
    CHECK(fewer > rays / 10);
}

TEST_CASE("krs::gather_byte gives each lane its byte, up to the table's last byte")
{
    // 4-byte aligned, a multiple of 4 long (gather_byte's preconditions); every value differs
    // from its neighbours', so a byte taken from the wrong position in its word shows.
    alignas(64) std::uint8_t table[256];
    for (int i = 0; i < 256; ++i) table[i] = std::uint8_t((i * 37 + 11) & 0xff);
    using I = krs::index_lanes<krs::packet_f>;
    constexpr std::size_t n = krs::lane_count<krs::packet_f>;
    for (int first = 0; first + int(n) <= 256; first += 3) {
        alignas(64) std::int32_t index[n];
        for (std::size_t k = 0; k < n; ++k) index[k] = std::int32_t((std::size_t(first) + k * 7) % 256);
        index[n - 1] = 255; // the last byte: its word is the table's last
        alignas(64) std::int32_t got[n];
        krs::gather_byte(table, I::load_aligned(index)).store_aligned(got);
        for (std::size_t k = 0; k < n; ++k) {
            REQUIRE(got[k] == std::int32_t(table[index[k]]));
            REQUIRE(krs::gather_byte(table, index[k]) == std::int32_t(table[index[k]]));
        }
    }
}

TEST_CASE("hypertree render: flat shading marched in step, colors gathered by level, gives the per-lane pixels, trees A-D")
{
    // No lights and no ambient falloff: the lit color depends on the level alone
    // (voxel_shading::flat), and packets march in step gathering it by level byte. The per-lane
    // march that shades each sample (render_settings::shade_each_sample) is the reference: equal
    // pixels and lookups, scalar and packet, shaded per sample and per voxel, with and without
    // bounding spheres, several levels of color.
    march_options flat;
    flat.shadows = false;
    flat.lights.clear();
    flat.ambient = 0.8f;
    flat.ambient_falloff = 0.0f;
    march_options lit = flat, falloff = flat;
    lit.lights = march_options{}.lights;
    falloff.ambient_falloff = 1.0f;
    for (const auto& maker : {presets::tree_a, presets::tree_b, presets::tree_c, presets::tree_d}) {
        auto t = maker(40);
        t.iterations = 30000;
        INFO(t.name);
        const dense_store store = build_tree<dense_store>(t, 2);
        const tree_shape shape = tree_shape::of(store);
        const depth_colors colors = depth_colors::tree(3, 6);
        const krs::pinhole_camera camera = framing_camera(shape.box, 40, 32);
        CHECK_FALSE(volume_marcher(store, shape, colors, lit).shading().flat());
        CHECK_FALSE(volume_marcher(store, shape, colors, falloff).shading().flat());
        for (const bool per_voxel : {false, true})
            for (const bool spheres : {false, true}) {
                march_options o = flat;
                o.shade_per_voxel = per_voxel;
                o.bounds_by = spheres ? bound_method::spheres : bound_method::box;
                const volume_marcher m(store, shape, colors, o);
                REQUIRE(m.shading().flat());
                for (int s : {1, 2}) {
                    render_settings in_step, each;
                    in_step.supersampling = each.supersampling = s;
                    each.shade_each_sample = true;
                    const image a = render<krs::packet_f>(m, camera, in_step), b = render<krs::packet_f>(m, camera, each);
                    const image c = render<float>(m, camera, in_step), d = render<float>(m, camera, each);
                    CHECK(max_difference(a, b) == 0.0);
                    CHECK(max_difference(a, c) == 0.0);
                    CHECK(max_difference(a, d) == 0.0);
                    CHECK(a.lookups == b.lookups);
                    CHECK(a.lookups == c.lookups);
                    CHECK(a.lookups == d.lookups);
                    CHECK(a.lookups > 0);
                    // Not the background alone: the tree's colors (several levels) were composited.
                    CHECK(max_difference(a, render<krs::packet_f>(volume_marcher(store, shape, depth_colors::tree(1, 2), o), camera, in_step)) > 0.0);
                }
            }
    }
}

TEST_CASE("hypertree render: packets without supersampling take tiles of pixels and give the scalar rows' pixels at any image size")
{
    // render() hands packets tiles of pixels when s = 1 (4 x 4 at 16 lanes) where the scalar
    // marcher takes rows: the same rays, so the same pixels and lookups, on image sizes that cut
    // tiles, groups of tiles and bands (a width not a multiple of 16, heights not of 4 or 8, one
    // pixel), serial and on threads, lit (shading ahead and as met), with shadow rays, and flat.
    const small_scene scene(small_tree_d());
    const auto shape = tree_shape::of(scene.list);
    march_options rays, flat;
    rays.shadow_by = march_options::shadow_method::rays;
    flat.shadows = false;
    flat.lights.clear();
    flat.ambient_falloff = 0.0f;
        for (const march_options& o : {march_options{}, rays, flat}) {
        const volume_marcher m(scene.list, shape, depth_colors::tree(3, 6), o);
        for (const auto& [width, height] : {std::pair{61, 37}, std::pair{17, 5}, std::pair{16, 4}, std::pair{1, 1}, std::pair{33, 19}}) {
            INFO(width << "x" << height);
            const krs::pinhole_camera camera({0.3f, 0.7f, -2.4f}, {0, 0.6f, 0}, {0, 1, 0}, 40, width, height);
            for (const bool ahead : {true, false}) {
                render_settings serial;
                serial.shade_ahead = ahead;
                render_settings threaded = serial;
                threaded.parallel_for = krs_test::strided_threads(3);
                const image rows = render<float>(m, camera, serial);
                const image tiles = render<krs::packet_f>(m, camera, serial);
                CHECK(max_difference(rows, tiles) == 0.0);
                CHECK(rows.lookups == tiles.lookups);
                CHECK(max_difference(rows, render<krs::packet_f>(m, camera, threaded)) == 0.0);
            }
        }
        // Not the background alone: the view at 61 x 37 shows the tree.
        const krs::pinhole_camera camera({0.3f, 0.7f, -2.4f}, {0, 0.6f, 0}, {0, 1, 0}, 40, 61, 37);
        const image img = render<krs::packet_f>(m, camera);
        std::size_t covered = 0;
        for (std::size_t i = 0; i < img.rgb.size(); i += 3) covered += std::abs(img.rgb[i + 2] - render_settings{}.background.b) > 0.2f;
        CHECK(covered > 50);
    }
}

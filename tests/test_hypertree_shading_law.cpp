// The shading law of the hypertree paper (section 8.3, and the opacity law of 8.1) against closed
// forms on constructed volumes whose answer is known: a single voxel, a slab, a rod and a sphere
// of voxels. Each term is checked on its own: Reeves' ambient falloff below the crown sphere, the
// wrapped Lambert term and Blinn-Phong with the normal the structure flow gives, the box normals
// and the line-generator flow, DEPTHCOLOR spans, and transmittance through a slab of constant
// density. Every expected value is computed here, in double, from the formula; the code under
// test only supplies what is compared.

#include "hypertree/ifs.hpp"
#include "hypertree/render/glsl.hpp"
#include "hypertree/render/marcher.hpp"
#include "hypertree/store/index_list_store.hpp"

#include <doctest/doctest.h>

#include <algorithm>
#include <cmath>
#include <numbers>
#include <vector>

using namespace hypertree;

namespace {

// A store of the given cells (all one density and level, part `part`) of a 32^3 unit-cell volume.
struct cell {
    int x, y, z;
    std::uint8_t part = 0;
};
const hypervolume cube32({0, 0, 0}, {32, 32, 32}, resolution::cube(32));
std::vector<stored_voxel> cells_voxels(const std::vector<cell>& cells, std::uint8_t density, std::uint8_t level = 3)
{
    std::vector<stored_voxel> voxels;
    for (const cell& c : cells) voxels.push_back({cube32.index(c.x, c.y, c.z), {density, level}, c.part});
    std::sort(voxels.begin(), voxels.end(), [](const stored_voxel& a, const stored_voxel& b) { return a.index < b.index; });
    return voxels;
}
index_list_store cells_store(const std::vector<cell>& cells, std::uint8_t density, std::uint8_t level = 3)
{
    return index_list_store::build(cube32, cells_voxels(cells, density, level));
}
// The shape with the cells' parts (an index list store keeps no parts).
tree_shape cells_shape(const std::vector<cell>& cells)
{
    return tree_shape::of(cube32, cells_voxels(cells, 128));
}

// x in [x0, x0 + thickness), every y and z.
std::vector<cell> slab_cells(int x0, int thickness)
{
    std::vector<cell> out;
    for (int z = 0; z < 32; ++z)
        for (int y = 0; y < 32; ++y)
            for (int x = x0; x < x0 + thickness; ++x) out.push_back({x, y, z});
    return out;
}

// The cells whose centers lie within `radius` of (16, 16, 16).
std::vector<cell> sphere_cells(double radius)
{
    std::vector<cell> out;
    for (int z = 0; z < 32; ++z)
        for (int y = 0; y < 32; ++y)
            for (int x = 0; x < 32; ++x) {
                const double dx = x + 0.5 - 16, dy = y + 0.5 - 16, dz = z + 0.5 - 16;
                if (dx * dx + dy * dy + dz * dz <= radius * radius) out.push_back({x, y, z});
            }
    return out;
}

// A rod along y: x, z in [x0, x0 + 2) x [z0, z0 + 2), y in [y0, y1).
std::vector<cell> rod_cells(int x0, int z0, int y0, int y1, std::uint8_t part = 0)
{
    std::vector<cell> out;
    for (int y = y0; y < y1; ++y)
        for (int z = z0; z < z0 + 2; ++z)
            for (int x = x0; x < x0 + 2; ++x) out.push_back({x, y, z, part});
    return out;
}

struct dvec {
    double x, y, z;
};
double dot(dvec a, dvec b) { return a.x * b.x + a.y * b.y + a.z * b.z; }
dvec unit(dvec a)
{
    const double l = std::sqrt(dot(a, a));
    return {a.x / l, a.y / l, a.z / l};
}

// The paper's wrapped Lambert as voxel_shading documents it: max(0, n.l) x 3/4 + 1/4.
double wrapped_lambert(double n_dot_l) { return std::max(0.0, n_dot_l) * 0.75 + 0.25; }

} // namespace

TEST_CASE("shading law: Reeves' ambient falls off as exp(-falloff x depth / crown radius) below the crown of a sphere of voxels")
{
    const auto store = cells_store(sphere_cells(9.0), 200);
    const tree_shape shape = tree_shape::of(store);
    // The crown is the sphere around the voxels' box: the cells of a ball of radius 9 about 16
    // span [7, 25) on each axis (centers 7.5 .. 24.5), so its center is 16 and radius 9 sqrt(3).
    const double R = 9.0 * std::sqrt(3.0);
    CHECK(shape.crown.center.x == doctest::Approx(16.0).epsilon(1e-7));
    CHECK(shape.crown.center.y == doctest::Approx(16.0).epsilon(1e-7));
    CHECK(shape.crown.radius == doctest::Approx(R).epsilon(1e-6));
    const rgb base{0.3f, 0.5f, 0.7f};
    const depth_colors colors({{0, 10, base, base}});
    for (float falloff : {0.0f, 1.0f, 2.5f, 6.0f}) {
        march_options o;
        o.ambient = 0.4f, o.ambient_falloff = falloff;
        o.lights.clear(); // ambient alone
        const voxel_shading shading(o, shape, colors);
        for (double r : {0.0, 3.0, 7.5, 12.0, R * 0.999, R + 1.0, 40.0}) {
            const krs::vec3f q{float(16 + r), 16.0f, 16.0f}; // (exact in float)
            const double depth = std::max(0.0, R - double(q.x - 16.0f)) / R;
            const double ambient = 0.4 * std::exp(-double(falloff) * depth);
            const rgb got = shading.lit(q, 4, nullptr, {});
            CAPTURE(falloff);
            CAPTURE(r);
            CHECK(got.r == doctest::Approx(0.3 * ambient).epsilon(2e-6));
            CHECK(got.g == doctest::Approx(0.5 * ambient).epsilon(2e-6));
            CHECK(got.b == doctest::Approx(0.7 * ambient).epsilon(2e-6));
        }
    }
}

TEST_CASE("shading law: one voxel crossed by a ray is base x ambient x exp(-falloff) x (1 - (1 - mu)^k)")
{
    // A single voxel: its crown is the sphere about its own cell, so its center lies one crown
    // radius deep. One sample (step factor 1, through the center along x) of opacity 1 - (1 - mu)^k.
    for (int density : {30, 128, 250}) {
        for (float k : {0.5f, 1.0f, 3.0f}) {
            const auto store = cells_store({{12, 20, 7}}, std::uint8_t(density));
            march_options o;
            o.density_scale = k, o.min_transmittance = 0, o.shadows = false;
            o.ambient = 0.6f, o.ambient_falloff = 1.5f;
            o.lights.clear();
            const rgb base{0.2f, 0.9f, 0.4f};
            const volume_marcher m(store, tree_shape::of(store), depth_colors({{0, 10, base, base}}), o);
            const auto result = m.march(krs::ray<float>{{-1, 20.5f, 7.5f}, {1, 0, 0}});
            const double mu = density / 255.0, transmittance = std::pow(1 - mu, double(k));
            const double colour = 0.6 * std::exp(-1.5) * (1 - transmittance);
            CAPTURE(density);
            CAPTURE(k);
            CHECK(result.transmittance == doctest::Approx(transmittance).epsilon(1e-5));
            CHECK(result.g == doctest::Approx(0.9 * colour).epsilon(1e-5));
            CHECK(result.r == doctest::Approx(0.2 * colour).epsilon(1e-5));
        }
    }
}

TEST_CASE("shading law: transmittance through a slab of constant density is (1 - mu)^(k L / side) for any step")
{
    // Beer-Lambert in the paper's per-side normalization: a slab L voxels thick transmits
    // (1 - mu)^(k L), however the ray's path through it is cut into steps.
    for (int thickness : {1, 4, 7}) {
        for (float k : {0.25f, 2.0f, 3.5f}) {
            for (float step : {1.0f, 0.5f, 0.25f}) {
                const int density = 60;
                const auto store = cells_store(slab_cells(10, thickness), std::uint8_t(density));
                march_options o;
                o.density_scale = k, o.step_factor = step, o.min_transmittance = 0, o.shadows = false;
                const volume_marcher m(store, tree_shape::of(store), depth_colors{}, o);
                const auto result = m.march(krs::ray<float>{{-1, 16.5f, 16.5f}, {1, 0, 0}});
                const double expect = std::pow(1 - density / 255.0, double(k) * thickness);
                CAPTURE(thickness);
                CAPTURE(k);
                CAPTURE(step);
                CHECK(result.transmittance == doctest::Approx(expect).epsilon(1e-5));
            }
        }
    }
}

TEST_CASE("shading law: the structure-flow normal of a rod is radial about its axis, Lambert is max(0, n.l) wrapped")
{
    // One first-level part, a rod along y (cells x, z in [10, 12), y in [4, 28)): centroid (11, 16, 11),
    // principal axis y. With one flow the blended normal is the radial direction about that axis.
    const auto store = cells_store(rod_cells(10, 10, 4, 28), 128);
    const tree_shape shape = tree_shape::of(store);
    REQUIRE(shape.flows.size() == 1);
    march_options o;
    o.ambient = 0, o.diffuse = 0.8f;
    o.lights = {directional_light{{1, 0, 0}, {1.0f, 0.5f, 0.25f}}};
    const rgb base{0.5f, 0.5f, 0.5f};
    const voxel_shading shading(o, shape, depth_colors({{0, 10, base, base}}));
    const float shadow = 0.75f;
    for (int i = 0; i < 16; ++i) {
        const double theta = 2 * std::numbers::pi * i / 16;
        const double y = 7 + i; // anywhere along the rod
        const dvec expect_n{std::cos(theta), 0, std::sin(theta)};
        const krs::vec3d p{11 + 2 * std::cos(theta), y, 11 + 2 * std::sin(theta)};
        const krs::vec3d n = shape.normal_at(p);
        CAPTURE(theta);
        CHECK(n.x == doctest::Approx(expect_n.x).epsilon(1e-9));
        CHECK(n.y == doctest::Approx(0.0).epsilon(1e-9));
        CHECK(n.z == doctest::Approx(expect_n.z).epsilon(1e-9));
        const double lambert = wrapped_lambert(dot(expect_n, {1, 0, 0}));
        const rgb got = shading.lit(krs::vec3f(p), 3, &shadow, n);
        CHECK(got.r == doctest::Approx(0.5 * 0.8 * lambert * 0.75 * 1.0).epsilon(1e-6));
        CHECK(got.b == doctest::Approx(0.5 * 0.8 * lambert * 0.75 * 0.25).epsilon(1e-6));
    }
}

TEST_CASE("shading law: two rods blend their radial normals with weights 1 / (d^2 + soft)")
{
    // Parts 1 and 2: rods at x = 6 and x = 22. At a point between them the normal is the sum of the
    // two radial unit vectors weighted by 1 / (|p - centroid|^2 + 0.05 x rms^2), made unit.
    std::vector<cell> cells = rod_cells(5, 10, 4, 28, 1);
    for (const cell& c : rod_cells(21, 10, 4, 28, 2)) cells.push_back(c);
    const tree_shape shape = cells_shape(cells);
    REQUIRE(shape.flows.size() == 2);
    // Each rod: x, z centers {a + 0.5, a + 1.5} (variance 1/4 each), y centers 4.5 .. 27.5 (24 values,
    // variance (24^2 - 1) / 12): rms^2 = 1/4 + 1/4 + 575 / 12.
    const double soft = 0.05 * (0.5 + 575.0 / 12.0);
    const dvec c1{6, 16, 11}, c2{22, 16, 11};
    for (const dvec p : {dvec{10, 12, 13}, dvec{15, 20, 9}, dvec{19, 16, 11.5}}) {
        dvec sum{0, 0, 0};
        for (const dvec c : {c1, c2}) {
            const dvec d{p.x - c.x, p.y - c.y, p.z - c.z};
            const dvec radial = unit({d.x, 0, d.z});
            const double w = 1 / (dot(d, d) + soft);
            sum = {sum.x + w * radial.x, sum.y + w * radial.y, sum.z + w * radial.z};
        }
        const dvec expect = unit(sum);
        const krs::vec3d n = shape.normal_at(krs::vec3d{p.x, p.y, p.z});
        CAPTURE(p.x);
        CHECK(n.x == doctest::Approx(expect.x).epsilon(1e-9));
        CHECK(n.y == doctest::Approx(0.0).epsilon(1e-9));
        CHECK(n.z == doctest::Approx(expect.z).epsilon(1e-9));
    }
}

TEST_CASE("shading law: Blinn-Phong is specular x max(0, n.h)^shininess x shadow, h the unit half vector")
{
    const auto store = cells_store(rod_cells(10, 10, 4, 28), 128);
    const tree_shape shape = tree_shape::of(store);
    const dvec l = unit({1, 1, 0});
    for (float shininess : {1.0f, 8.0f, 40.0f}) {
        march_options o;
        o.specular = 0.6f, o.shininess = shininess;
        o.lights = {directional_light{{1, 1, 0}, {1.0f, 0.5f, 0.25f}}};
        const voxel_shading shading(o, shape, depth_colors{});
        const float shadow = 0.5f;
        for (int i = 0; i < 12; ++i) {
            const double theta = 2 * std::numbers::pi * i / 12;
            const krs::vec3d p{11 + 3 * std::cos(theta), 14, 11 + 3 * std::sin(theta)};
            const krs::vec3d nd = shape.normal_at(p);
            const dvec n{std::cos(theta), 0, std::sin(theta)}; // the rod's radial normal
            const dvec v = unit({0.2, -0.3, 1.0});
            const dvec h = unit({l.x + v.x, l.y + v.y, l.z + v.z});
            const double s = 0.6 * std::pow(std::max(0.0, dot(n, h)), double(shininess)) * 0.5;
            const rgb got = shading.with_specular({0.1f, 0.2f, 0.3f}, {float(nd.x), float(nd.y), float(nd.z)},
                                                  {float(v.x), float(v.y), float(v.z)}, &shadow);
            CAPTURE(shininess);
            CAPTURE(theta);
            CHECK(got.r == doctest::Approx(0.1 + s * 1.0).epsilon(1e-5));
            CHECK(got.g == doctest::Approx(0.2 + s * 0.5).epsilon(1e-5));
            CHECK(got.b == doctest::Approx(0.3 + s * 0.25).epsilon(1e-5));
        }
    }
}

TEST_CASE("shading law: DEPTHCOLOR spans interpolate linearly in depth, outside every span the nearest end")
{
    const dvec a{0.1, 0.2, 0.3}, b{0.5, 0.1, 0.9}, c{0.0, 1.0, 0.0}, d{0.8, 0.8, 0.2};
    const depth_colors colors({{2, 5, {0.1f, 0.2f, 0.3f}, {0.5f, 0.1f, 0.9f}}, {9, 13, {0.0f, 1.0f, 0.0f}, {0.8f, 0.8f, 0.2f}}});
    march_options o;
    o.ambient = 1, o.ambient_falloff = 0; // lit() = the level color itself
    o.lights.clear();
    const voxel_shading shading(o, tree_shape{}, colors);
    for (int depth = 0; depth <= 20; ++depth) {
        dvec expect;
        const auto mix = [](dvec p, dvec q, double t) { return dvec{p.x + (q.x - p.x) * t, p.y + (q.y - p.y) * t, p.z + (q.z - p.z) * t}; };
        if (depth < 2) expect = a;                                // below the first span: its first color
        else if (depth <= 5) expect = mix(a, b, (depth - 2) / 3.0);
        else if (depth <= 7) expect = b;                          // nearer the first span (gap 1, 2 vs 4, 3)
        else if (depth < 9) expect = c;                           // depth 8: gap 3 to the first, 1 to the second
        else if (depth <= 13) expect = mix(c, d, (depth - 9) / 4.0);
        else expect = d;
        const rgb got = shading.lit({0, 0, 0}, depth, nullptr, {});
        CAPTURE(depth);
        CHECK(got.r == doctest::Approx(expect.x).epsilon(1e-6));
        CHECK(got.g == doctest::Approx(expect.y).epsilon(1e-6));
        CHECK(got.b == doctest::Approx(expect.z).epsilon(1e-6));
    }
}

TEST_CASE("shading law: box normals are the outward normal of the nearest face of the part box")
{
    // A slab x in [10, 13): its part box is [10, 13) x [0, 32) x [0, 32).
    const auto store = cells_store(slab_cells(10, 3), 128);
    const tree_shape shape = tree_shape::of(store);
    REQUIRE(shape.part_boxes.size() == 1);
    struct probe {
        krs::vec3d p;
        krs::vec3d n;
    };
    for (const probe& c : {probe{{10.2, 16, 16}, {-1, 0, 0}}, probe{{12.9, 16, 16}, {1, 0, 0}}, probe{{11.5, 16, 16}, {-1, 0, 0}}, // (tie: lo)
                           probe{{11.7, 31.5, 16}, {0, 1, 0}}, probe{{11.2, 16, 0.1}, {0, 0, -1}},
                           probe{{5, 16, 16}, {-1, 0, 0}}, probe{{20, 16, 40}, {0, 0, 1}}, probe{{11, -3, 16}, {0, -1, 0}}}) {
        CAPTURE(c.p.x);
        CAPTURE(c.p.y);
        CAPTURE(c.p.z);
        const krs::vec3d n = shape.normal_at(c.p, normal_method::part_boxes);
        CHECK(n.x == c.n.x);
        CHECK(n.y == c.n.y);
        CHECK(n.z == c.n.z);
    }
    // Two parts' boxes: in the box holding the point, not the nearer face of the other.
    std::vector<cell> two = rod_cells(4, 4, 4, 28, 1);
    for (const cell& c : rod_cells(20, 4, 4, 28, 2)) two.push_back(c);
    const tree_shape two_shape = cells_shape(two);
    REQUIRE(two_shape.part_boxes.size() == 2);
    CHECK(two_shape.box_normal_at({21.9, 16, 5}).x == 1.0);  // box 2 = [20, 22): its +x face
    CHECK(two_shape.box_normal_at({4.1, 16, 5}).x == -1.0);  // box 1 = [4, 6): its -x face
    CHECK(two_shape.box_normal_at({7, 16, 5}).x == 1.0);     // outside both, nearest box 1, beyond its +x face
    CHECK(two_shape.box_normal_at({18.5, 16, 5}).x == -1.0); // outside both, nearest box 2
}

TEST_CASE("shading law: a slab lit through its box normals is base x diffuse x alpha x sum of T_i x wrapped Lambert")
{
    // A slab 3 voxels thick, shaded per voxel at the voxel centers x = 10.5, 11.5, 12.5: the box
    // normals there are -x, -x (a tie, the lo face) and +x. A light toward -x gives Lambert 1, 1
    // and 1/4; with ambient 0 and no shadow, front to back the color is
    // base x diffuse x alpha x (1 + (1 - alpha) + (1 - alpha)^2 / 4), alpha = 1 - (1 - mu)^k.
    // (Run both through march's per-voxel shading and through a memo shaded ahead in packets.)
    const int density = 90;
    const auto store = cells_store(slab_cells(10, 3), std::uint8_t(density));
    for (bool packets : {false, true}) {
        march_options o;
        o.min_transmittance = 0, o.shadows = false, o.ambient = 0, o.diffuse = 0.8f, o.density_scale = 1.5f;
        o.lights = {directional_light{{-1, 0, 0}, {1.0f, 1.0f, 1.0f}}};
        o.normals_by = normal_method::part_boxes;
        const rgb base{0.25f, 0.5f, 1.0f};
        const volume_marcher m(store, tree_shape::of(store), depth_colors({{0, 10, base, base}}), o);
        const double alpha = 1 - std::pow(1 - density / 255.0, 1.5);
        const double sum = 1 + (1 - alpha) + (1 - alpha) * (1 - alpha) * 0.25;
        const double expect = 0.8 * alpha * sum;
        const krs::ray<float> r{{-1, 16.5f, 16.5f}, {1, 0, 0}};
        march_result<float> result;
        if (packets) { // the memo filled ahead, normals a packet of doubles at a time
            shade_memo memo = m.new_shade_memo();
            m.shade_bricks(memo, 0, m.bricks().brick_count());
            REQUIRE(memo.seal());
            result = m.march(r, {nullptr, &memo});
        } else {
            result = m.march(r);
        }
        CAPTURE(packets);
        CHECK(result.r == doctest::Approx(0.25 * expect).epsilon(1e-5));
        CHECK(result.b == doctest::Approx(1.0 * expect).epsilon(1e-5));
    }
}

TEST_CASE("shading law: the line-generator flow is radial about the lines' direction, not the covariance axis")
{
    // A plate wide in x (x in [4, 28), y in [15, 17), z in [15, 17)): its covariance axis is x,
    // but its line generators run along y. The line flow about y through the centroid (16, 16, 16)
    // gives at p the unit (p - c) without its y part; the structure flow, without its x part.
    std::vector<cell> plate;
    for (int x = 4; x < 28; ++x)
        for (int y = 15; y < 17; ++y)
            for (int z = 15; z < 17; ++z) plate.push_back({x, y, z});
    tree_shape shape = tree_shape::of(cells_store(plate, 128));
    REQUIRE(shape.flows.size() == 1);
    const std::vector<krs::vec3d> along_y{{0, 3, 0}};
    shape.set_line_flow(along_y);
    for (const dvec p : {dvec{18, 17, 16}, dvec{10, 15.5, 19}, dvec{16.5, 20, 13}}) {
        const dvec d{p.x - 16, p.y - 16, p.z - 16};
        const dvec line = unit({d.x, 0, d.z}), cov = unit({0, d.y, d.z});
        const krs::vec3d got_line = shape.normal_at(krs::vec3d{p.x, p.y, p.z}, normal_method::line_flow);
        const krs::vec3d got_cov = shape.normal_at(krs::vec3d{p.x, p.y, p.z}, normal_method::structure_flow);
        CAPTURE(p.x);
        CHECK(got_line.x == doctest::Approx(line.x).epsilon(1e-9));
        CHECK(got_line.y == doctest::Approx(0.0).epsilon(1e-9));
        CHECK(got_line.z == doctest::Approx(line.z).epsilon(1e-9));
        CHECK(got_cov.x == doctest::Approx(0.0).epsilon(1e-9));
        CHECK(got_cov.y == doctest::Approx(cov.y).epsilon(1e-9));
        CHECK(got_cov.z == doctest::Approx(cov.z).epsilon(1e-9));
    }
    // Packets compute lane by lane what the scalar does.
    const krs::vec3<krs::packet_d> pp{krs::packet_d(18.0), krs::packet_d(17.0), krs::packet_d(16.0)};
    const auto lanes = krs::lanes_of(shape.normal_at(pp, normal_method::line_flow).x);
    CHECK(lanes[0] == shape.normal_at(krs::vec3d{18, 17, 16}, normal_method::line_flow).x);
}

TEST_CASE("shading law: the line flow of an IFS runs along each first-level transformation's image of the generator")
{
    // Transformation 0 turns by 90 degrees about z (the vertical generator becomes horizontal, along
    // -x), transformation 1 by 30 degrees about x (along (0, cos 30, sin 30)); both scale by 1/2
    // and lift, which a direction ignores. Parts 1 and 2 are two rods, both along y, so their
    // covariance axes are y and only the line flow can tell them apart; part 0 (the trunk) keeps y.
    ifs<> t;
    t.transforms.push_back({runtime_pipeline({scale(0.5), rotate({0, 0, 1}, std::numbers::pi / 2), translate(0, 0.5, 0)}), 1.0});
    t.transforms.push_back({runtime_pipeline({scale(0.5), rotate({1, 0, 0}, std::numbers::pi / 6), translate(0, 0.3, 0)}), 1.0});
    t.generator = generator_shape::line({0, -0.025, 0}, {0, 0.025, 0});
    const drawn_ifs<runtime_pipeline> drawn(t, 7);
    std::vector<cell> cells = rod_cells(4, 4, 4, 28, 0);
    for (const cell& c : rod_cells(14, 4, 4, 28, 1)) cells.push_back(c);
    for (const cell& c : rod_cells(24, 4, 4, 28, 2)) cells.push_back(c);
    tree_shape shape = cells_shape(cells);
    REQUIRE(shape.flows.size() == 3);
    shape.set_line_flow_of(drawn);
    const double c30 = std::cos(std::numbers::pi / 6), s30 = std::sin(std::numbers::pi / 6);
    // (A rotation's direction: the sign of sin depends on the handedness convention; compare
    // up to the sign of each component but insist on which components are non-zero and their size.)
    CHECK(std::abs(shape.flows[0].line_axis.y) == doctest::Approx(1.0).epsilon(1e-12));
    CHECK(std::abs(shape.flows[1].line_axis.x) == doctest::Approx(1.0).epsilon(1e-12));
    CHECK(shape.flows[1].line_axis.y == doctest::Approx(0.0).epsilon(1e-12));
    CHECK(shape.flows[2].line_axis.x == doctest::Approx(0.0).epsilon(1e-12));
    CHECK(std::abs(shape.flows[2].line_axis.y) == doctest::Approx(c30).epsilon(1e-12));
    CHECK(std::abs(shape.flows[2].line_axis.z) == doctest::Approx(s30).epsilon(1e-12));
    // Near rod 1 (centroid (15, 16, 5)) the line flow is radial about x: a point above it gets +y.
    const krs::vec3d n = shape.normal_at(krs::vec3d{15, 17, 5}, normal_method::line_flow);
    CHECK(n.y > 0.99);
    // A point generator carries no direction.
    t.generator = generator_shape::point();
    CHECK_THROWS_AS(shape.set_line_flow_of(drawn_ifs<runtime_pipeline>(t, 7)), krs::invalid_parameter);
    // Voxels that lost their parts (all part 0, as a list rebuilt through an index_list_store)
    // carry no per-part line axis: refused by name rather than left as one covariance flow.
    std::vector<cell> merged = rod_cells(4, 4, 4, 28, 0);
    for (const cell& c : rod_cells(14, 4, 4, 28, 0)) merged.push_back(c);
    tree_shape one_part = cells_shape(merged);
    REQUIRE(one_part.flows.size() == 1);
    t.generator = generator_shape::line({0, -0.025, 0}, {0, 0.025, 0});
    try {
        one_part.set_line_flow_of(drawn_ifs<runtime_pipeline>(t, 7));
        FAIL("accepted voxels without parts");
    } catch (const krs::invalid_parameter& e) {
        CHECK(std::string(e.what()).find("tree_shape.set_line_flow_of") != std::string::npos);
        CHECK(std::string(e.what()).find("part 0") != std::string::npos);
    }
}

TEST_CASE("shading law: bad normal options are refused by name")
{
    march_options o;
    o.normals_by = normal_method(7);
    CHECK_THROWS_AS(o.validate(), krs::invalid_parameter);
    tree_shape shape = tree_shape::of(cells_store(rod_cells(10, 10, 4, 28), 128));
    const std::vector<krs::vec3d> none{}, zero{{0, 0, 0}}, nan{{std::nan(""), 1, 0}};
    CHECK_THROWS_AS(shape.set_line_flow(none), krs::invalid_parameter);
    CHECK_THROWS_AS(shape.set_line_flow(zero), krs::invalid_parameter);
    CHECK_THROWS_AS(shape.set_line_flow(nan), krs::invalid_parameter);
    // The GLSL marcher emits the box normal's boxes (its frames are compared with the CPU's in
    // test_hypertree_glsl_gpu.cpp).
    const auto store = cells_store(rod_cells(10, 10, 4, 28), 128);
    march_options boxes;
    boxes.normals_by = normal_method::part_boxes;
    CHECK(hypertree_glsl(store, tree_shape::of(store), depth_colors{}, boxes).find("krs_hypertree_part_box_lo") != std::string::npos);
}

// libFuzzer target: scene parameters decoded from bytes and fed to the model builders (issue 10,
// "fuzzing"). Each input either makes a builder throw krs::invalid_parameter (fine) or builds a
// scene whose instance_count() is a non-negative number and whose distance is finite (float,
// double and packet lanes) at probe points derived from the bytes, near the scene and out to the
// magnitude policy's reach |p| <= 1e9. Anything else (a NaN or infinite distance, another
// exception type, a sanitizer report) aborts. Sizes are bounded so one execution stays fast; float
// fields also receive out-of-range, NaN, infinite and huge finite values so validation is exercised.
//
// Input layout (fuzz_input.hpp decodes the fields): byte 0 picks the builder (mod 8), then the
// builder's fields, then probe points. Define KRS_FUZZ_VERBOSE to print each input's outcome.
// fuzz/replay_main.cpp runs the same function over fuzz/corpus/builders/ and fuzz/crashers/builders/
// in ctest.

#include "fuzz_input.hpp"

#include "krs/model/coral.hpp"
#include "krs/model/forest.hpp"
#include "krs/model/forest_ground.hpp"
#include "krs/model/grass.hpp"
#include "krs/model/terrain.hpp"
#include "krs/model/tree.hpp"

#include <algorithm>
#include <cmath>
#include <cstddef>
#include <cstdint>
#ifdef KRS_FUZZ_VERBOSE
#include <cstdio>
#endif

namespace {

using namespace krs;
using namespace krs::model;
using krs_fuzz::fail;
using krs_fuzz::probe;
using krs_fuzz::reader;

void check_count(double count)
{
    if (std::isnan(count) || count < 0) fail();
}

template <class Sequence>
void check(const Sequence& s, reader& in, double reach)
{
    check_count(s.instance_count());
    probe(s, in, reach);
}

tree_style read_style(reader& in, int max_levels)
{
    tree_style s;
    s.levels = in.integer(1, max_levels, 0, int(tree_sequence::max_levels) + 2);
    s.trunk_length = in.real(0.1f, 4.0f);
    s.trunk_radius = in.real(0.0f, 0.5f);
    s.length_ratio = in.real(1e-3f, 1.5f);
    s.radius_ratio = in.real(1e-3f, 1.0f);
    s.spread_degrees = in.real(1.0f, 89.0f);
    s.twist_degrees = in.real(-360.0f, 360.0f);
    s.bend = in.real(-0.5f, 0.5f);
    s.upward = in.real(0.0f, 1.0f);
    s.leaves_per_twig = in.integer(0, 8, -1, 65);
    s.leaf_radius = in.real(0.0f, 0.2f);
    s.jitter = in.real(0.0f, 0.5f);
    s.seed = in.u32();
    if (in.byte() & 1) s.ground_height = in.real(-2.0f, 2.0f);
    else s.ground_height.reset();
    return s;
}

terrain_parameters read_terrain(reader& in)
{
    terrain_parameters t;
    t.levels = in.integer(1, 24, 0, 61);
    t.size = in.real(0.1f, 100.0f);
    t.detail_ratio = in.real(0.5f, 0.99f);
    t.slope = in.real(0.0f, 2.0f);
    t.extra_planes = in.integer(0, 16, -1, 17);
    t.height = in.real(-10.0f, 10.0f);
    t.seed = in.u32();
    return t;
}

void fuzz_style_tree(reader& in)
{
    const tree_sequence tree = build_tree(grow_tree(read_style(in, 20)));
    check(tree, in, 8.0);
}

void fuzz_raw_tree(reader& in)
{
    tree_parameters t;
    const std::size_t points = in.byte() % 7; // 0 and 1 are invalid
    for (std::size_t i = 0; i < points; ++i) t.forks.push_back(in.point(-3.0f, 3.0f));
    const std::size_t branches = points > 0 ? points - 1 : 0;
    const std::uint8_t shape = in.byte(); // mostly the right counts, sometimes off by one
    const std::size_t controls = branches + ((shape & 0x07) == 1 ? 1 : 0) - ((shape & 0x07) == 2 && branches ? 1 : 0);
    const std::size_t widths = branches + ((shape & 0x38) == 0x08 ? 1 : 0);
    for (std::size_t i = 0; i < controls; ++i) t.controls.push_back(in.point(-3.0f, 3.0f));
    for (std::size_t i = 0; i < widths; ++i) t.widths.push_back(in.real(0.0f, 0.3f));
    if (shape & 0x40) {
        const std::size_t normals = (branches > 0 ? branches - 1 : 0) + ((shape & 0x80) ? 1 : 0);
        for (std::size_t i = 0; i < normals; ++i) t.fork_normals.push_back(in.point(-1.0f, 1.0f));
    }
    const std::size_t leaves = in.byte() % 4;
    for (std::size_t i = 0; i < leaves; ++i) {
        const vec3f c = in.point(-3.0f, 3.0f);
        t.leaves.emplace_back(c, in.real(0.0f, 0.2f));
    }
    if (in.byte() & 1) t.ground_height = in.real(-2.0f, 2.0f);
    check(build_tree(t), in, 8.0);
}

void fuzz_terrain(reader& in)
{
    const plane_sequence terrain = build_terrain(read_terrain(in));
    check(terrain, in, 60.0);
}

void fuzz_rock(reader& in)
{
    rock_parameters r;
    r.center = in.point(-5.0f, 5.0f);
    r.radius = in.real(0.01f, 5.0f);
    r.facets = in.integer(1, 16, 0, 17);
    r.folds = in.integer(0, 58, -1, 59);
    r.fold_offset = in.real(0.0f, 0.5f);
    r.seed = in.u32();
    const rock built = build_rock(r);
    if (std::isnan(built.bound.radius)) fail();
    check(built.sequence, in, 10.0);
}

void fuzz_coral(reader& in)
{
    coral_parameters c;
    c.levels = in.integer(1, 40, 0, 41);
    c.base_radius = in.real(0.01f, 0.5f);
    c.segment_length = in.real(0.05f, 2.0f);
    c.taper = in.real(0.5f, 1.0f);
    c.spread_degrees = in.real(5.0f, 80.0f);
    c.knot = in.real(1.0f, 3.0f);
    c.tip_blob = in.real(1.0f, 4.0f);
    c.seed = in.u32();
    check(build_coral(c), in, 10.0);
}

void fuzz_sponge(reader& in)
{
    sponge_parameters s;
    s.center = in.point(-5.0f, 5.0f);
    s.size = in.real(0.01f, 10.0f);
    s.levels = in.integer(1, 9, 0, 10);
    const sponge built = build_sponge(s);
    check_count(built.cube_count);
    check(built.sequence, in, 10.0);
}

void fuzz_grass(reader& in)
{
    grass_parameters g;
    g.blades_per_clump = in.integer(1, 16, 0, 65);
    g.blade_height = in.real(0.01f, 1.0f);
    g.blade_width = in.real(0.001f, 0.05f);
    g.lean = in.real(0.0f, 1.0f);
    g.clump_radius = in.real(0.01f, 0.5f);
    g.doublings = in.integer(0, 8, -1, 21);
    g.spacing = in.real(0.0f, 4.0f);
    g.ground_height = in.real(-2.0f, 2.0f);
    g.seed = in.u32();
    check(build_grass(g).sequence, in, 10.0);
}

void fuzz_forest(reader& in)
{
    forest_parameters f;
    f.tree = read_style(in, 7); // explicit expansion of one tree: keep it small
    f.doublings = in.integer(0, 6, -1, 21);
    f.spacing = in.real(0.0f, 4.0f);
    f.angle_jitter_degrees = in.real(0.0f, 90.0f);
    if (in.byte() & 1) f.ground_height = in.real(-2.0f, 2.0f);
    else f.ground_height.reset();
    f.seed = in.u32();
    const forest built = build_forest(f);
    check_count(built.tree_instances);
    check(built.sequence, in, 20.0);
    if (in.byte() & 1) {
        terrain_parameters t = read_terrain(in);
        if (t.levels > 0 && t.levels <= 60) t.levels = std::min(t.levels, 12);
        check(build_forest_ground(f, built, t), in, 20.0);
    }
}

} // namespace

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size)
{
    return krs_fuzz::run_one(data, size, [](reader& in) {
        switch (in.byte() % 8) {
        case 0: fuzz_style_tree(in); break;
        case 1: fuzz_raw_tree(in); break;
        case 2: fuzz_terrain(in); break;
        case 3: fuzz_rock(in); break;
        case 4: fuzz_coral(in); break;
        case 5: fuzz_sponge(in); break;
        case 6: fuzz_grass(in); break;
        default: fuzz_forest(in); break;
        }
    });
}

// Hypertree definition and forest files (paper section 10). The example files are checked against
// the C++ presets they transcribe, value by value and by generating both: the presets are the
// independent reference, written with C++ arithmetic rather than parsed. Every error class gets a
// small bad text and a check of the location and the expectation in its message.

#include "hypertree/create/generate.hpp"
#include "hypertree/definition_refusals.hpp"
#include "hypertree/forest.hpp"
#include "hypertree/io/definition_file.hpp"
#include "hypertree/io/forest_file.hpp"
#include "hypertree/presets.hpp"
#include "hypertree/render/march_options.hpp"
#include "hypertree/store/store_kinds.hpp"

#include <doctest/doctest.h>

#include <cstdint>
#include <filesystem>
#include <fstream>
#include <random>
#include <sstream>
#include <string>
#include <string_view>
#include <variant>
#include <vector>

using namespace hypertree;

namespace {

const std::filesystem::path examples = std::filesystem::path(KRS_SOURCE_DIR) / "examples" / "hypertrees";

bool same(const parameter& a, const parameter& b) { return a.mean == b.mean && a.spread == b.spread; }
bool same(const vec3d& a, const vec3d& b) { return a.x == b.x && a.y == b.y && a.z == b.z; }

bool same(const transform_element& a, const transform_element& b)
{
    if (a.index() != b.index()) return false;
    if (const auto* t = std::get_if<translate>(&a)) {
        const auto& u = std::get<translate>(b);
        return same(t->x, u.x) && same(t->y, u.y) && same(t->z, u.z);
    }
    if (const auto* r = std::get_if<rotate>(&a)) {
        const auto& u = std::get<rotate>(b);
        return same(r->axis, u.axis) && same(r->angle, u.angle);
    }
    if (const auto* s = std::get_if<scale>(&a)) {
        const auto& u = std::get<scale>(b);
        return same(s->x, u.x) && same(s->y, u.y) && same(s->z, u.z);
    }
    const auto& s = std::get<shear>(a);
    const auto& u = std::get<shear>(b);
    return s.axis == u.axis && same(s.first, u.first) && same(s.second, u.second) && same(s.exponent, u.exponent) && s.height == u.height;
}

bool same(const runtime_pipeline& a, const runtime_pipeline& b)
{
    if (a.elements.size() != b.elements.size()) return false;
    for (std::size_t i = 0; i < a.elements.size(); ++i)
        if (!same(a.elements[i], b.elements[i])) return false;
    return true;
}

// Every value of the two IFSs, exactly.
void check_same_ifs(const ifs<>& parsed, const ifs<>& preset)
{
    CHECK(parsed.name == preset.name);
    CHECK(parsed.tree_depth == preset.tree_depth);
    CHECK(parsed.branch_depth == preset.branch_depth);
    CHECK(parsed.iterations == preset.iterations);
    CHECK(parsed.volume == preset.volume);
    CHECK(same(parsed.generator.start, preset.generator.start));
    CHECK(same(parsed.generator.end, preset.generator.end));
    CHECK(same(parsed.perturb.amplitude, preset.perturb.amplitude));
    CHECK(parsed.perturb.frequency == preset.perturb.frequency);
    REQUIRE(parsed.transforms.size() == preset.transforms.size());
    for (std::size_t j = 0; j < parsed.transforms.size(); ++j) {
        CAPTURE(j);
        CHECK(parsed.transforms[j].probability == preset.transforms[j].probability);
        CHECK(parsed.transforms[j].last_level == preset.transforms[j].last_level);
        CHECK(parsed.transforms[j].dummy_from == preset.transforms[j].dummy_from);
        CHECK(same(parsed.transforms[j].transform, preset.transforms[j].transform));
    }
    REQUIRE(parsed.condensations.size() == preset.condensations.size());
    for (std::size_t c = 0; c < parsed.condensations.size(); ++c) {
        const cone &a = parsed.condensations[c].stem, &b = preset.condensations[c].stem;
        CHECK(a.axis == b.axis);
        CHECK(a.bottom == b.bottom);
        CHECK(a.top == b.top);
        CHECK(a.bottom_radius == b.bottom_radius);
        CHECK(a.top_radius == b.top_radius);
        CHECK(same(parsed.condensations[c].then, preset.condensations[c].then));
    }
}

// The same voxels, levels and parts in the same order.
void check_same_hits(ifs<> parsed, ifs<> preset, std::uint64_t seed)
{
    constexpr int resolution_ = 64;
    parsed.volume = hypervolume(parsed.volume.origin(), parsed.volume.extent(), resolution::cube(resolution_));
    preset.volume = hypervolume(preset.volume.origin(), preset.volume.extent(), resolution::cube(resolution_));
    parsed.iterations = preset.iterations = 20000;
    const generated_hits a = generate(parsed, seed), b = generate(preset, seed);
    REQUIRE(a.hits.size() == b.hits.size());
    CHECK(!a.hits.empty());
    std::size_t differing = 0;
    for (std::size_t i = 0; i < a.hits.size(); ++i)
        differing += a.hits[i].voxel != b.hits[i].voxel || a.hits[i].level != b.hits[i].level || a.hits[i].part != b.hits[i].part;
    CHECK(differing == 0);
}

// The message of the definition_error `run` throws, or "no error".
template <class Run>
std::string thrown_by(Run&& run)
{
    try {
        run();
    } catch (const definition_error& e) {
        return e.what();
    }
    return "no error";
}

std::string error_of(std::string_view text, std::string_view file = "t.tree")
{
    return thrown_by([&] { parse_definition(text, file); });
}

struct bad_text {
    std::string_view text;
    std::string_view location; // "t.tree:line:column:"
    std::string_view expectation;
};

void check_errors(std::initializer_list<bad_text> cases)
{
    for (const bad_text& c : cases) {
        const std::string message = error_of(c.text);
        CAPTURE(c.text);
        CAPTURE(message);
        CHECK(message.starts_with(std::string(c.location) + " "));
        CHECK(message.find(c.expectation) != std::string::npos);
    }
}

// A minimal valid body, so a case can break one thing only.
constexpr std::string_view one_transform = "TRANSFORM 1 0\n  SCALE 0.5\n";

std::string with_transform(std::string_view header) { return std::string(header) + std::string(one_transform); }

} // namespace

TEST_CASE("hypertree io example trees equal their presets")
{
    const struct {
        const char* file;
        ifs<> (*preset)(int);
    } trees[] = {{"tree_a.tree", presets::tree_a}, {"tree_b.tree", presets::tree_b}, {"tree_c.tree", presets::tree_c}, {"tree_d.tree", presets::tree_d}};
    for (const auto& t : trees) {
        CAPTURE(t.file);
        const parsed_tree parsed = load_definition(examples / t.file);
        check_same_ifs(parsed.ifs, t.preset(300));
        check_same_hits(parsed.ifs, t.preset(300), 20240601);
        CHECK(!parsed.depth_colors.empty());
        CHECK(parsed.color_of_depth(0).has_value());
    }
}

TEST_CASE("hypertree io definition keywords and defaults")
{
    const parsed_tree t = parse_definition(R"(# comments run to the end of a line
name "two words"           # keywords in any case
Resolution 40 50 60
ITERATIONS 1234
TREEDEPTH 7
BRANCHDEPTH 2
DENSITYCLASSES 16
PERTURB 0.01 0.02 0.03 4
HYPERVOLUME 2 3 4
DISPLACEMENT 1 0.5 2
LINEINIT 0 -0.1 0 0 0.1 0
DEPTHCOLOR 0 2 0 0 0 1 0.5 0.25
DEPTHCOLOR 5 5 0.5 0.5 0.5 0 0 0
TRANSFORM 2 3 DUMMY 2
  translate 0 0.5 0
  SCALE 0.4 0.5 0.6
TRANSFORM 0.5 0
  SHEAR x 0.1 -0.1 2
  SCALE 0.3
)",
                                           "keywords.tree");
    const ifs<>& f = t.ifs;
    CHECK(f.name == "two words");
    CHECK(f.volume.grid() == resolution{40, 50, 60});
    CHECK(f.iterations == 1234);
    CHECK(f.tree_depth == 7);
    CHECK(f.branch_depth == 2);
    CHECK(t.density_class_count == 16);
    CHECK(f.perturb.amplitude.z == 0.03);
    CHECK(f.perturb.frequency == 4);
    // DISPLACEMENT is where the tree's origin lies from the box's minimum corner.
    CHECK(f.volume.origin().x == -1);
    CHECK(f.volume.origin().y == -0.5);
    CHECK(f.volume.maximum().z == 2);
    CHECK(f.generator.length() == doctest::Approx(0.2));
    REQUIRE(f.transforms.size() == 2);
    CHECK(f.transforms[0].probability == 2);
    CHECK(f.transforms[0].last_level == 3);
    CHECK(f.transforms[0].dummy_from == 2);
    CHECK(f.transforms[1].last_level == never); // last level 0: no limit
    CHECK(f.transforms[1].dummy_from == never);
    REQUIRE(f.transforms[0].transform.elements.size() == 2);
    CHECK(std::get<scale>(f.transforms[0].transform.elements[1]).z.mean[0] == 0.6);
    CHECK(std::get<shear>(f.transforms[1].transform.elements[0]).axis == 0);
    CHECK(std::get<shear>(f.transforms[1].transform.elements[0]).height == 1);
    // No CONDENSATION: the model's default stem.
    REQUIRE(f.condensations.size() == 1);
    CHECK(f.condensations[0].stem.top == cone{}.top);
    // Depth colors interpolate within their range and leave other depths uncolored.
    CHECK(t.color_of_depth(1)->g == doctest::Approx(0.25));
    CHECK(t.color_of_depth(5)->r == 0.5f);
    CHECK(!t.color_of_depth(3).has_value());

    // A file that gives only a transformation keeps the model's defaults for the rest.
    const parsed_tree minimal = parse_definition(one_transform, "minimal.tree");
    const ifs<> defaults;
    CHECK(minimal.ifs.volume == defaults.volume);
    CHECK(minimal.ifs.tree_depth == defaults.tree_depth);
    CHECK(minimal.ifs.iterations == defaults.iterations);
    CHECK(minimal.ifs.generator.is_point());
    CHECK(!minimal.density_class_count.has_value());
}

TEST_CASE("hypertree io per-level and random values")
{
    const parsed_tree t = parse_definition(R"(
CONDENSATION
  CONE y 0 0.5 0.03 0.01
  TRANSLATE 0.1~0.05 0 0
TRANSFORM 1 0
  SCALE (0.5, 0.4)
  SCALE (0.9, 0.8, 0.7)
  SCALE 0.6~0.05
  SCALE (0.5~0.1, 0.4, 0.3 ~ 0.02)
  ROTATE 0 1 0 (90, 45~10)
)",
                                           "levels.tree");
    const auto& e = t.ifs.transforms[0].transform.elements;
    REQUIRE(e.size() == 5);
    // A pair: level 1, then every deeper level.
    const parameter pair = std::get<scale>(e[0]).x;
    CHECK(pair.mean == std::array<double, 3>{0.5, 0.4, 0.4});
    CHECK(pair.is_fixed());
    const parameter triplet = std::get<scale>(e[1]).y;
    CHECK(triplet.mean == std::array<double, 3>{0.9, 0.8, 0.7});
    // mean~spread: the same at every level.
    const parameter random = std::get<scale>(e[2]).z;
    CHECK(random.mean == std::array<double, 3>{0.6, 0.6, 0.6});
    CHECK(random.spread == std::array<double, 3>{0.05, 0.05, 0.05});
    // Each entry of a per-level value may be random on its own.
    const parameter mixed = std::get<scale>(e[3]).x;
    CHECK(mixed.mean == std::array<double, 3>{0.5, 0.4, 0.3});
    CHECK(mixed.spread == std::array<double, 3>{0.1, 0, 0.02});
    // Angles are degrees in the file and radians in the model, spreads included.
    const parameter angle = std::get<rotate>(e[4]).angle;
    CHECK(angle.mean[0] == 90 * radians_per_degree);
    CHECK(angle.mean[2] == 45 * radians_per_degree);
    CHECK(angle.spread[1] == 10 * radians_per_degree);
    CHECK(angle.spread[0] == 0);
    // Condensations take random values too.
    const parameter stem_shift = std::get<translate>(t.ifs.condensations[0].then.elements[0]).x;
    CHECK(stem_shift.mean[0] == 0.1);
    CHECK(stem_shift.spread[0] == 0.05);
}

TEST_CASE("hypertree io definition syntax errors")
{
    check_errors({
        {"FOO 1\n", "t.tree:1:1:", "unknown keyword 'FOO'"},
        {"TRANSFORM 1 0\n  SCALE abc\n", "t.tree:2:9:", "expected a number after SCALE, got 'abc'"},
        {"TRANSFORM 1 0\n  SCALE 0.5 0.5\n", "t.tree:2:16:", "expected a number after SCALE, got end of line"},
        {"TREEDEPTH 5 6\n", "t.tree:1:13:", "unexpected '6' after TREEDEPTH"},
        {"TRANSFORM 1\n", "t.tree:1:12:", "expected an integer after TRANSFORM, got end of line"},
        {"TRANSFORM 1 0 DUMY 1\n", "t.tree:1:15:", "expected DUMMY or the end of the line"},
        {"ITERATIONS 1e6\n", "t.tree:1:12:", "expected an integer >= 1"},
        {"TRANSFORM 1 0\n SCALE (0.5)\n", "t.tree:2:12:", "expected ','"},
        {"TRANSFORM 1 0\n SCALE (0.5, 0.4, 0.3, 0.2)\n", "t.tree:2:22:", "expected ')'"},
        {"TRANSFORM 1 0\n SCALE (0.5 0.4)\n", "t.tree:2:13:", "expected ','"},
        {"TRANSFORM 1 0\n SCALE 0.5~\n", "t.tree:2:12:", "expected a number after '~' in SCALE, got end of line"},
        {"HYPERVOLUME 1 (1, 2) 1\n", "t.tree:1:15:", "per-level"},
        {"ITERATIONS 10~2\n", "t.tree:1:14:", "unexpected '~' after ITERATIONS"},
        {"NAME \"unterminated\n", "t.tree:1:6:", "unterminated quoted text"},
        {"CONDENSATION\n  CONE w 0 1 0.1 0.1\n", "t.tree:2:8:", "expected an axis (x, y or z) after CONE, got 'w'"},
        {"\n\n   SHEAR y 0 0 2\n", "t.tree:3:4:", "expected a TRANSFORM or CONDENSATION line before SHEAR"},
    });
}

TEST_CASE("hypertree io definition range errors")
{
    check_errors({
        {"RESOLUTION 0\n", "t.tree:1:12:", "expected an integer in [1, 2147483647] after RESOLUTION, got '0'"},
        {"RESOLUTION 300 -1 300\n", "t.tree:1:16:", "expected an integer in [1, 2147483647] after RESOLUTION, got '-1'"},
        {"RESOLUTION 2000 2000 2000\n", "t.tree:1:1:", "expected at most 4294967295 voxels"},
        {"RESOLUTION 100000 100000 1\n", "t.tree:1:1:", "expected at most 4294967295 voxels"},
        {"TREEDEPTH 65\n", "t.tree:1:11:", "expected an integer in [1, 64] after TREEDEPTH"},
        {"TREEDEPTH 0\n", "t.tree:1:11:", "expected an integer in [1, 64] after TREEDEPTH"},
        {"ITERATIONS 0\n", "t.tree:1:12:", "expected an integer >= 1"},
        {"TRANSFORM 1 65\n", "t.tree:1:13:", "expected an integer in [0, 64] after TRANSFORM"},
        {"TRANSFORM 1 0 DUMMY 0\n", "t.tree:1:21:", "expected an integer in [1, 64] after DUMMY"},
        {"TRANSFORM -1 0\n", "t.tree:1:11:", "expected a number >= 0 after TRANSFORM"},
        {"HYPERVOLUME 1 0 1\n", "t.tree:1:15:", "expected a number > 0 after HYPERVOLUME"},
        // Accepted and built with no voxel before: a box float cannot place, at its keyword.
        {"HYPERVOLUME 1e-300 1e-300 1e-300\nTRANSFORM 1 0\n SCALE 0.5\n", "t.tree:1:1:", "invalid tree: hypervolume.extent.x: gives voxels of side"},
        {"HYPERVOLUME 1e-9 1e-9 1e-9\nDISPLACEMENT 1e9 1e9 1e9\nTRANSFORM 1 0\n SCALE 0.5\n", "t.tree:2:1:", "invalid tree: hypervolume.origin"},
        {"TRANSFORM 1 0\n SCALE 1e12\n", "t.tree:2:8:", "expected a number of magnitude at most 1e9"},
        {"TRANSFORM 1 0\n TRANSLATE 0 nan 0\n", "t.tree:2:14:", "expected a number after TRANSLATE, got 'nan'"},
        {"DEPTHCOLOR 0 1 0 0 0 1 1 1.5\n", "t.tree:1:26:", "expected a number in [0, 1] after DEPTHCOLOR"},
        {"DEPTHCOLOR 3 2 0 0 0 1 1 1\n", "t.tree:1:14:", "expected an integer in [3, 63] after DEPTHCOLOR"},
        {"DENSITYCLASSES 1\n", "t.tree:1:16:", "expected an integer in [2, 255] after DENSITYCLASSES"},
        {"PERTURB 0.1 0.1 0.1 -2\n", "t.tree:1:21:", "expected a number >= 0 after PERTURB"},
        {"TRANSFORM 1 0\n SCALE 0.5~-0.1\n", "t.tree:2:12:", "expected a number >= 0 after '~' in SCALE"},
    });
}

TEST_CASE("hypertree io definition structure errors")
{
    check_errors({
        {"TRANSFORM 0 0\n SCALE 0.5\nTRANSFORM 0 0\n SCALE 0.4\n", "t.tree:1:1:",
         "expected a positive probability on at least one TRANSFORM, got probabilities that sum to 0"},
        {"TREEDEPTH 4\n", "t.tree:2:1:", "expected at least one TRANSFORM"},
        {"TRANSFORM 1 0\nTREEDEPTH 4\n", "t.tree:1:1:", "expected at least one TRANSLATE, ROTATE, SCALE or SHEAR line after TRANSFORM"},
        {"TREEDEPTH 4\nTREEDEPTH 5\n", "t.tree:2:1:", "TREEDEPTH is given twice (first on line 1)"},
        {"POINTINIT 0 0 0\nLINEINIT 0 0 0 0 1 0\n", "t.tree:2:1:", "the generator (POINTINIT or LINEINIT) is given twice"},
        {"CONDENSATION\n SCALE 0.5\n", "t.tree:2:2:", "expected the CONE line first after CONDENSATION"},
        {"CONDENSATION\nTREEDEPTH 3\n", "t.tree:1:1:", "expected a CONE line after CONDENSATION"},
        {"TRANSFORM 1 0\n CONE y 0 1 0.1 0.1\n", "t.tree:2:2:", "a CONE belongs to a CONDENSATION"},
        {"CONDENSATION\n CONE y 0 1 0.1 0.1\n SCALE (0.5, 0.4)\n", "t.tree:3:8:", "per-level values do not apply"},
        {"CONDENSATION\n CONE y 0 1 0.1 0.1\nCONDENSATION\n CONE y 0 1 0.1 0.1\nCONDENSATION\n", "t.tree:5:1:",
         "expected at most two CONDENSATIONs"},
        {"TRANSFORM 1 0\n SHEAR y 0 0 2\n SHEAR y 0 0 2\n SHEAR y 0 0 2\n SHEAR y 0 0 2\n SHEAR y 0 0 2\n", "t.tree:6:2:",
         "expected at most 4 SHEARs in one TRANSFORM"},
        {with_transform("TREEDEPTH 3\nBRANCHDEPTH 3\n"), "t.tree:2:1:", "expected BRANCHDEPTH below TREEDEPTH"},
        {with_transform("TREEDEPTH 1\n"), "t.tree:1:1:", "got BRANCHDEPTH 1 (the default) with TREEDEPTH 1"},
        {with_transform("TREEDEPTH 4\nDEPTHCOLOR 2 5 0 0 0 1 1 1\n"), "t.tree:2:1:", "expected DEPTHCOLOR depths below TREEDEPTH 4"},
        {"DEPTHCOLOR 0 3 0 0 0 1 1 1\nDEPTHCOLOR 2 4 0 0 0 1 1 1\n", "t.tree:2:1:", "overlaps 0 to 3 on line 1"},
    });
}

TEST_CASE("hypertree io definition errors of the model are reported at their keyword")
{
    check_errors({
        // The shear exponent must be >= 1 over its whole random range (shear.hpp).
        {"TRANSFORM 1 0\n  SHEAR y 0.1 0 0.5\n  SCALE 0.3\n", "t.tree:2:3:", "invalid SHEAR: shear.exponent: must be >= 1"},
        {"TRANSFORM 1 0\n  SHEAR y 0.1 0 1.2~0.3\n  SCALE 0.3\n", "t.tree:2:3:", "invalid SHEAR: shear.exponent"},
        {"TRANSFORM 1 0\n  ROTATE 0 0 0 30\n", "t.tree:2:3:", "invalid ROTATE: rotate.axis: must be a non-zero direction"},
        {"CONDENSATION\n  CONE y 1 0.5 0.03 0.01\n", "t.tree:2:3:", "invalid CONE: cone.top: must be above cone.bottom"},
        {"CONDENSATION\n  CONE y 0 1 0 0\n", "t.tree:2:3:", "invalid CONE"},
        // The generator's contraction condition (ifs.hpp), checked at the mean values.
        {"TREEDEPTH 3\nTRANSFORM 1 0\n  SCALE (0.5, 1.5)\n", "t.tree:2:1:", "expected a contraction (Lipschitz bound < 1) at level 2"},
    });
}

TEST_CASE("hypertree io load_definition reports an unreadable file")
{
    const std::filesystem::path missing = examples / "no_such_tree.tree";
    CHECK(thrown_by([&] { load_definition(missing); }).starts_with(missing.string() + ":1:1: cannot read"));
    // definition_error keeps the parts of its location.
    try {
        parse_definition("TREEDEPTH x\n", "parts.tree");
        FAIL("no error");
    } catch (const definition_error& e) {
        CHECK(e.file() == "parts.tree");
        CHECK(e.line() == 1);
        CHECK(e.column() == 11);
        CHECK(std::string(e.what()) == "parts.tree:1:11: " + e.message());
    }
}

TEST_CASE("hypertree io forest file lists trees with offsets and storage type")
{
    const parsed_forest f = parse_forest(R"(RESOLUTION 64 32 64
storagetype Partitioned
TREE a.tree 1 0 -2.5
TREE "sub dir/b.tree"
TREE /abs/c.tree 0 0 1
)",
                                         "forests/f.forest");
    CHECK(f.grid == resolution{64, 32, 64});
    CHECK(f.storage == storage_type::partitioned);
    REQUIRE(f.trees.size() == 3);
    CHECK(f.trees[0].file == std::filesystem::path("forests/a.tree"));
    CHECK(f.trees[0].offset.z == -2.5);
    CHECK(f.trees[1].file == std::filesystem::path("forests/sub dir/b.tree"));
    CHECK(f.trees[1].offset.x == 0);
    CHECK(f.trees[2].file == std::filesystem::path("/abs/c.tree"));
    CHECK(f.trees[2].at.line == 5);

    // The example forest: the four presets, placed by their offsets in one volume.
    const loaded_forest forest = load_forest(examples / "forest.forest");
    CHECK(forest.listing.storage == storage_type::bit_array);
    REQUIRE(forest.trees.size() == 4);
    CHECK(forest.trees[0].ifs.name == "A");
    CHECK(forest.trees[3].ifs.name == "D");
    const hypervolume v = forest.volume();
    CHECK(v.grid() == forest.listing.grid);
    for (std::size_t i = 0; i < 4; ++i) {
        const vec3d lo = forest.trees[i].ifs.volume.origin() + forest.listing.trees[i].offset;
        const vec3d hi = forest.trees[i].ifs.volume.maximum() + forest.listing.trees[i].offset;
        CHECK(v.origin().x <= lo.x);
        CHECK(v.origin().z <= lo.z);
        CHECK(v.maximum().x >= hi.x - 1e-12);
        CHECK(v.maximum().y >= hi.y - 1e-12);
    }
}

TEST_CASE("hypertree io forest errors")
{
    const auto forest_error = [](std::string_view text) { return thrown_by([&] { parse_forest(text, "f.forest"); }); };
    CHECK(forest_error("RESOLUTION 64\nSTORAGETYPE sparse\nTREE a.tree\n")
              .starts_with("f.forest:2:13: expected a storage type (dense, index_list, bit_array or partitioned) after STORAGETYPE, got 'sparse'"));
    CHECK(forest_error("RESOLUTION 64\nTREE a.tree\n").starts_with("f.forest:3:1: expected a STORAGETYPE line"));
    CHECK(forest_error("STORAGETYPE dense\nTREE a.tree\n").starts_with("f.forest:3:1: expected a RESOLUTION line"));
    CHECK(forest_error("RESOLUTION 64\nSTORAGETYPE dense\n").starts_with("f.forest:3:1: expected at least one TREE line"));
    CHECK(forest_error("RESOLUTION 64\nSTORAGETYPE dense\nTREE a.tree 1 2\n").starts_with("f.forest:3:16: expected a number after TREE"));
    CHECK(forest_error("RESOLUTION 0\n").starts_with("f.forest:1:12: expected an integer in [1, "));
    CHECK(forest_error("GROVE 1\n").starts_with("f.forest:1:1: unknown keyword 'GROVE'"));

    // A tree file that cannot be read is reported at its TREE line; an error inside a tree file
    // names that file.
    // A directory of its own: the portable and native test executables may run this at once.
    const std::filesystem::path dir =
        std::filesystem::temp_directory_path() / ("krs_test_hypertree_io_" + std::to_string(std::random_device{}()));
    std::filesystem::create_directories(dir);
    {
        std::ofstream(dir / "missing.forest") << "RESOLUTION 32\nSTORAGETYPE dense\n\nTREE nowhere.tree\n";
        std::ofstream(dir / "broken.forest") << "RESOLUTION 32\nSTORAGETYPE dense\nTREE broken.tree\n";
        std::ofstream(dir / "broken.tree") << "TREEDEPTH 4\nTRANSFORM 1 0\n  SCALE big\n";
    }
    CHECK(thrown_by([&] { load_forest(dir / "missing.forest"); })
              .starts_with((dir / "missing.forest").string() + ":4:1: cannot read the tree file"));
    CHECK(thrown_by([&] { load_forest(dir / "broken.forest"); })
              .starts_with((dir / "broken.tree").string() + ":3:9: expected a number after SCALE, got 'big'"));
    // A valid tree moved where float cannot place its voxels: reported at its TREE line (it loaded,
    // and the forest's volume() failed unnamed).
    {
        std::ofstream(dir / "far.forest") << "RESOLUTION 8\nSTORAGETYPE dense\nTREE near.tree\nTREE small.tree 9e8 0 0\n";
        std::ofstream(dir / "near.tree") << "RESOLUTION 8\nTRANSFORM 1 0\n  SCALE 0.5\n";
        std::ofstream(dir / "small.tree") << "RESOLUTION 8\nHYPERVOLUME 1 1 1\nTRANSFORM 1 0\n  SCALE 0.5\n";
    }
    const std::string far = thrown_by([&] { load_forest(dir / "far.forest"); });
    CHECK(far.starts_with((dir / "far.forest").string() + ":4:1: the tree's hypervolume moved by this offset is invalid"));
    CHECK(far.find("hypervolume.extent.x") != std::string::npos);
    std::filesystem::remove_all(dir);
}

TEST_CASE("hypertree io forest trees land at their offsets in one volume")
{
    loaded_forest forest = load_forest(std::filesystem::path(KRS_SOURCE_DIR) / "examples/hypertrees/forest.forest");
    forest.listing.grid = resolution{120, 60, 120};
    for (auto& t : forest.trees) t.ifs.iterations = 8000;
    const generated_forest built = build_forest(forest, 3);
    REQUIRE(forest.trees.size() == 4);
    std::array<std::size_t, 4> per_tree{};
    std::size_t misplaced = 0;
    for (const stored_voxel& v : built.voxels) {
        REQUIRE(v.part < 4);
        ++per_tree[v.part];
        // Moved back by its tree's offset, the voxel's center lies in that tree's own box.
        const vec3d p = built.volume.voxel_center(v.index) - forest.listing.trees[v.part].offset;
        const hypervolume& own = forest.trees[v.part].ifs.volume;
        const vec3d h = built.volume.voxel_size() * 0.5;
        misplaced += p.x < own.origin().x - h.x || p.y < own.origin().y - h.y || p.z < own.origin().z - h.z ||
                     p.x > own.maximum().x + h.x || p.y > own.maximum().y + h.y || p.z > own.maximum().z + h.z;
    }
    CHECK(misplaced == 0);
    for (std::size_t n : per_tree) CHECK(n > 200);
    CHECK(std::is_sorted(built.voxels.begin(), built.voxels.end(), [](const stored_voxel& a, const stored_voxel& b) { return a.index < b.index; }));
}

namespace {

// The three numbers after `before` in `text` (what a message offers as fitting), for a check that
// feeds them back to the library.
vec3d three_after(const std::string& text, std::string_view before)
{
    const std::size_t at = text.find(before);
    REQUIRE(at != std::string::npos);
    std::istringstream in(text.substr(at + before.size()));
    vec3d v;
    in >> v.x >> v.y >> v.z;
    REQUIRE(!in.fail());
    return v;
}
std::uint64_t number_after(const std::string& text, std::string_view before)
{
    const std::size_t at = text.find(before);
    REQUIRE(at != std::string::npos);
    return std::stoull(text.substr(at + before.size()));
}

// A small tree whose line `extra` goes in as line 3 (after RESOLUTION and ITERATIONS).
std::string small_tree(std::string_view extra)
{
    return "RESOLUTION 16\nITERATIONS 3000\n" + std::string(extra) +
           "\nTREEDEPTH 5\nHYPERVOLUME 1.5 1.08 1.5\nDISPLACEMENT 0.75 0.03 0.75\nCONDENSATION\n  CONE y 0 0.45 0.04 0.02\n"
           "TRANSFORM 1 0\n  SCALE 0.5\n  ROTATE 0 0 1 50\n  TRANSLATE 0 0.2 0\n";
}

std::string replaced(std::string text, std::string_view from, std::string_view to)
{
    for (std::size_t at = text.find(from); at != std::string::npos; at = text.find(from, at + to.size())) text.replace(at, from.size(), to);
    return text;
}

} // namespace

TEST_CASE("hypertree io line endings: LF, CR LF and a lone CR read alike, a UTF-8 byte-order mark is skipped")
{
    const std::string lf = small_tree("NAME \"with quotes\"  # and a comment");
    const parsed_tree reference = parse_definition(lf, "t.tree");
    for (const std::string& text : {replaced(lf, "\n", "\r"), replaced(lf, "\n", "\r\n"), "\xEF\xBB\xBF" + lf,
                                    "\xEF\xBB\xBF" + replaced(lf, "\n", "\r")}) {
        CAPTURE(text);
        const parsed_tree t = parse_definition(text, "t.tree");
        check_same_ifs(t.ifs, reference.ifs);
        CHECK(t.transform_at == reference.transform_at); // lines counted alike
    }
    // Before, a CR-only file was one line ("unexpected 'ITERATIONS' after RESOLUTION"), and a
    // mark an unknown keyword '\xef\xbb\xbfRESOLUTION'.
    check_errors({
        {"TREEDEPTH 4\rTRANSFORM 1 0\r  SCALE big\r", "t.tree:3:9:", "expected a number after SCALE, got 'big'"},
        {"TREEDEPTH 4\r\rTRANSFORM 1 0\r\n  SCALE big", "t.tree:4:9:", "expected a number after SCALE"},
        {"\xEF\xBB\xBFTREEDEPTH x\n", "t.tree:1:11:", "expected an integer"}, // columns from after the mark
        {"NAME \"no end\rNAME \"x\"\r", "t.tree:1:6:", "unterminated quoted text"}, // a quote ends at a CR too
        {"\xFF\xFET\0R\0", "t.tree:1:1:", "the file is UTF-16 (it starts with that byte-order mark); save it as UTF-8 or ASCII"},
        {"\xFE\xFF\0T", "t.tree:1:1:", "the file is UTF-16"},
        {std::string("\xFF\xFE\0\0T\0\0\0", 8), "t.tree:1:1:", "the file is UTF-32"},
    });
    // The end of input counts CR lines too ("expected at least one TRANSFORM" after the last).
    check_errors({{"TREEDEPTH 4\rTREEDEPTH", "t.tree:2:1:", "TREEDEPTH"}, {"TREEDEPTH 4\r\r", "t.tree:3:1:", "expected at least one TRANSFORM"}});
    const parsed_forest f = parse_forest("\xEF\xBB\xBFRESOLUTION 8\rSTORAGETYPE dense\rTREE a.tree\rTREE b.tree 1 2 3\r", "f.forest");
    REQUIRE(f.trees.size() == 2);
    CHECK(f.trees[1].at.line == 4);
    CHECK(f.trees[1].offset.z == 3);
}

TEST_CASE("hypertree io a forest's TREE naming a forest is refused at its line, a file given as the other kind says what it is")
{
    const std::filesystem::path dir =
        std::filesystem::temp_directory_path() / ("krs_test_hypertree_io_kinds_" + std::to_string(std::random_device{}()));
    std::filesystem::create_directories(dir);
    {
        std::ofstream(dir / "inner.forest") << "RESOLUTION 8\n# a comment\nstoragetype dense\nTREE t.tree\n";
        std::ofstream(dir / "outer.forest") << "RESOLUTION 8\nSTORAGETYPE dense\n\nTREE inner.forest 1 0 0\n";
        std::ofstream(dir / "t.tree") << small_tree("");
    }
    CHECK(thrown_by([&] { load_forest(dir / "outer.forest"); }) ==
          (dir / "outer.forest").string() + ":4:1: '" + (dir / "inner.forest").string() +
              "' is a forest file (line 3 is a forest's keyword); TREE takes a tree definition file");
    // Given where the other kind is wanted (hypertree_render --tree / --forest), at the first
    // keyword only the other kind has (RESOLUTION both share).
    CHECK(thrown_by([&] { load_definition(dir / "inner.forest"); })
              .starts_with((dir / "inner.forest").string() + ":3:1: STORAGETYPE is a forest file's keyword: this is a forest file"));
    CHECK(thrown_by([&] { load_forest(dir / "t.tree"); })
              .starts_with((dir / "t.tree").string() + ":2:1: ITERATIONS is a tree definition's keyword: this is a tree definition file"));
    std::filesystem::remove_all(dir);
}

TEST_CASE("hypertree io ITERATIONS over the generator's budget is refused at its line with the count that fits")
{
    const parsed_tree tree = parse_definition(replaced(small_tree("# a comment"), "ITERATIONS 3000", "ITERATIONS 2000000000"), "t.tree");
    std::string message;
    try {
        building_from(tree, [&] { return generate(tree.ifs, 1); });
        FAIL("not refused");
    } catch (const definition_error& e) {
        message = e.what();
    }
    CAPTURE(message);
    CHECK(message.starts_with("t.tree:2:1: ITERATIONS 2000000000: would record up to "));
    CHECK(message.find("ifs.") == std::string::npos);
    CHECK(message.find("krs: ") == std::string::npos);
    // What it says fits, fits: the generator plans it, and one cycle more it refuses.
    ifs<runtime_pipeline> fitting = tree.ifs;
    fitting.iterations = number_after(message, "at most ");
    CHECK_NOTHROW((void)detail::plan_generation(fitting, generation_options{}));
    fitting.iterations += std::uint64_t(fitting.tree_depth);
    CHECK_THROWS_AS((void)detail::plan_generation(fitting, generation_options{}), krs::invalid_parameter);

    // A refusal of no setting of the file passes unchanged.
    CHECK_THROWS_AS(building_from(tree, [] { throw krs::invalid_parameter("march_options.ambient", "must be >= 0", "-1"); }),
                    krs::invalid_parameter);
}

TEST_CASE("hypertree io RENDERPERTURB wider than the march can step across is refused at its line with an amplitude that fits")
{
    const parsed_tree tree = parse_definition(small_tree("RENDERPERTURB 1e9 1e9 1e9 4"), "t.tree");
    REQUIRE(tree.render_perturb);
    march_options o;
    o.displacement = *tree.render_perturb;
    const hypervolume& v = tree.ifs.volume;
    const world_box box{v.origin(), v.maximum()};
    std::string message;
    try {
        o.validate(v, box);
        FAIL("not refused");
    } catch (const krs::invalid_parameter& e) {
        const std::optional<definition_error> located = at_its_line(tree, e);
        REQUIRE(located);
        message = located->what();
    }
    CAPTURE(message);
    CHECK(message.starts_with("t.tree:3:1: RENDERPERTURB 1e+09 1e+09 1e+09: must leave at most 2^23 samples"));
    CHECK(message.find("march_options") == std::string::npos);
    CHECK(message.find("step_factor") == std::string::npos);
    const vec3d fits = three_after(message, "an amplitude of ");
    o.displacement.amplitude = krs::vec3f(float(fits.x), float(fits.y), float(fits.z));
    CHECK_NOTHROW(o.validate(v, box));
    CHECK(fits.x > 0);
}

TEST_CASE("hypertree io a PERTURB that leaves no voxel is refused at its line with an amplitude that fills some")
{
    const parsed_tree tree = parse_definition(small_tree("PERTURB 1e9 1e9 1e9"), "t.tree");
    REQUIRE(generate(tree.ifs, 1).hits.empty()); // the case: nothing generated
    const std::string message = empty_tree_refusal(tree, 1).what();
    CAPTURE(message);
    CHECK(message.starts_with("t.tree:3:1: PERTURB 1e+09 1e+09 1e+09: the tree generated no voxels"));
    ifs<runtime_pipeline> trial = tree.ifs;
    trial.perturb.amplitude = three_after(message, "an amplitude of ");
    CHECK(trial.perturb.amplitude.x < 1e9);
    CHECK(!generate(trial, 1).hits.empty());

    // Without noise, a tree outside its box is blamed on the placement.
    const parsed_tree away = parse_definition(replaced(small_tree(""), "DISPLACEMENT 0.75 0.03 0.75", "DISPLACEMENT -50 0 0"), "t.tree");
    REQUIRE(generate(away.ifs, 1).hits.empty());
    CHECK(std::string(empty_tree_refusal(away, 1).what()).starts_with("t.tree:6:1: the tree generated no voxels: none of its points"));
}

TEST_CASE("hypertree io a store over the budget names what fits: the other kinds, and the finest dense grid")
{
    const hypervolume big({0, 0, 0}, {1, 1, 1}, resolution::cube(1600));
    const memory_budget budget{}; // 4 GiB
    const std::string before = store_budget_problem(storage_type::dense, big, {}, false, budget, "RESOLUTION");
    CAPTURE(before);
    CHECK(before.starts_with("dense needs " + std::to_string(dense_store::bytes_needed(big)) + " bytes for 1600 x 1600 x 1600 voxels"));
    const int n = int(number_after(before, "dense at RESOLUTION "));
    CHECK(dense_store::bytes_needed(hypervolume({0, 0, 0}, {1, 1, 1}, resolution::cube(n))) <= budget.bytes);
    CHECK(dense_store::bytes_needed(hypervolume({0, 0, 0}, {1, 1, 1}, resolution::cube(n + 1))) > budget.bytes);
    CHECK(store_budget_problem(storage_type::bit_array, big, {}, false, budget, "RESOLUTION").empty()); // not known yet

    // With the voxels known, the kinds listed are exactly those within the budget.
    const hypervolume small({0, 0, 0}, {1, 1, 1}, resolution::cube(64));
    std::vector<stored_voxel> voxels;
    for (voxel_index i = 0; i < 64 * 64 * 64; i += 97) voxels.push_back({i, voxel{1, 0}, 0});
    const memory_budget tight{dense_store::bytes_needed(small) - 1};
    const std::string after = store_budget_problem(storage_type::dense, small, voxels, true, tight, "--resolution");
    CAPTURE(after);
    for_each_store_kind([&]<class S>() {
        if (storage_type_of<S> == storage_type::dense) return;
        const bool fits = S::bytes_needed(small, voxels) <= tight.bytes;
        CHECK((after.find(std::string(store_kind_name<S>) + " (") != std::string::npos) == fits);
    });
    CHECK(after.find("dense at --resolution 63 or less") != std::string::npos);
}

TEST_CASE("hypertree io a forest's tree over the generator's budget is refused at its own file's ITERATIONS line")
{
    const std::filesystem::path dir =
        std::filesystem::temp_directory_path() / ("krs_test_hypertree_io_budget_" + std::to_string(std::random_device{}()));
    std::filesystem::create_directories(dir);
    {
        std::ofstream(dir / "f.forest") << "RESOLUTION 16\nSTORAGETYPE bit_array\nTREE t.tree\n";
        std::ofstream(dir / "t.tree") << replaced(small_tree(""), "ITERATIONS 3000", "ITERATIONS 2000000000");
    }
    const loaded_forest forest = load_forest(dir / "f.forest");
    CHECK(thrown_by([&] { (void)build_forest(forest, 1); }).starts_with((dir / "t.tree").string() + ":2:1: ITERATIONS 2000000000: would record"));
    std::filesystem::remove_all(dir);
}

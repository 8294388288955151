// krs::glsl without a GPU: the shipped glsl/ files are what the emitter writes today, literals read
// back as the same floats, only the kinds a scene uses are emitted, and pack() agrees with the
// emitter's layout. (Execution on llvmpipe: test_glsl_gpu.cpp.)

#include "krs/fractal/fold_steps.hpp"
#include "krs/fractal/kifs_presets.hpp"
#include "krs/fractal/shell_presets.hpp"
#include "krs/fractal/similar_shell.hpp"
#include "krs/scenes/example_scenes.hpp"
#include "krs/scenes/scene_files.hpp"
#include "krs/trace/packet_trace.hpp"

#include <doctest/doctest.h>

#include <algorithm>
#include <cctype>
#include <cmath>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <iterator>
#include <limits>
#include <numbers>
#include <regex>
#include <sstream>
#include <set>
#include <string>
#include <vector>

namespace {

namespace ex = krs::scenes;

std::string read_file(const std::string& path)
{
    std::ifstream in(path, std::ios::binary);
    if (!in) return "<missing file " + path + ">";
    std::ostringstream s;
    s << in.rdbuf();
    return s.str();
}

std::size_t occurrences(const std::string& text, const std::string& what)
{
    std::size_t count = 0;
    for (std::size_t at = text.find(what); at != std::string::npos; at = text.find(what, at + 1)) ++count;
    return count;
}

} // namespace

TEST_CASE("glsl folder is up to date with the emitter, and holds every scene's files and no others")
{
    std::set<std::string> expected;
    ex::for_each_scene([&](const auto& s) {
        for (const ex::file_kind& kind : ex::files) {
            const std::string name = s.name + std::string(kind.suffix);
            const std::string path = std::string(KRS_SOURCE_DIR) + "/glsl/" + name;
            INFO(path << " is stale or missing: regenerate with `cmake --build <build> --target krs_glsl_regenerate` "
                         "(or glsl_export --all glsl)");
            CHECK(read_file(path) == ex::file_text(s, kind));
            expected.insert(name);
        }
    });
    CHECK(expected.size() == ex::files.size() * ex::scene_count);
    // A scene dropped from the list leaves files the regeneration no longer writes: none may stay.
    std::set<std::string> found;
    for (const auto& entry : std::filesystem::directory_iterator(std::string(KRS_SOURCE_DIR) + "/glsl"))
        if (entry.path().extension() == ".glsl") found.insert(entry.path().filename().string());
    for (const std::string& name : found) {
        INFO("glsl/" << name << " belongs to no scene of krs/scenes/example_scenes.hpp: remove it");
        CHECK(expected.count(name) == 1);
    }
    CHECK(found.size() == expected.size());
}

TEST_CASE("example scenes: one name each, a GLSL prefix, the name the scene is built with")
{
    std::set<std::string_view> seen;
    ex::for_each_scene_entry([&]<class E>() {
        INFO(E::name);
        CHECK(seen.insert(E::name).second);
        CHECK(krs::glsl::is_prefix(std::string(E::name) + "_")); // its GLSL names are NAME_...
        CHECK(!E::summary.empty());
        const auto s = E::build(E::default_seed);
        CHECK(s.name == E::name);
        CHECK(s.camera.width() == ex::frame_width);
        CHECK(s.camera.height() == ex::frame_height);
        if constexpr (E::seeded) {
            // The seed is the scene's: another one moves something in its box (on a 5^3 grid over
            // it), its own rebuilds the same field.
            const auto other = E::build(E::default_seed + 1), again = E::build(E::default_seed);
            int moved = 0, same = 0;
            for (int i = 0; i < 125; ++i) {
                const krs::vec3f u{float(i % 5) / 2.0f - 1.0f, float(i / 5 % 5) / 2.0f - 1.0f,
                                   float(i / 25) / 2.0f - 1.0f};
                const krs::vec3f h = s.sample_half, p = s.sample_center + krs::vec3f{u.x * h.x, u.y * h.y, u.z * h.z};
                moved += other.field.distance(p) != s.field.distance(p);
                same += again.field.distance(p) == s.field.distance(p);
            }
            CHECK(moved > 0);
            CHECK(same == 125);
        }
    });
    CHECK(seen.size() == ex::scene_count);
}

// A scene is one entry (docs/design.md, "A scene"): a struct in example_scenes.hpp and its type in
// example_scene_list. A struct left out of the list would be shipped, regenerated and tested by
// nothing, so the header may hold no more scene structs than the list; and the table of scenes in
// glsl/README.md is written by hand, so it must name every scene.
TEST_CASE("example scenes: every scene struct is in the list, and glsl/README.md's table names each")
{
    {
        const std::string header = read_file(std::string(KRS_SOURCE_DIR) + "/include/krs/scenes/example_scenes.hpp");
        const std::regex entry(R"(\bstruct\s+\w+\s*:\s*(?:seeded_by\s*<[^>]*>|unseeded)\s*\{)");
        const auto structs = std::distance(std::sregex_iterator(header.begin(), header.end(), entry), std::sregex_iterator());
        INFO("scene structs in krs/scenes/example_scenes.hpp: " << structs << ", in example_scene_list: " << ex::scene_count);
        CHECK(std::size_t(structs) == ex::scene_count);
    }

    const std::string readme = read_file((std::filesystem::path(KRS_SOURCE_DIR) / "glsl/README.md").string());
    const std::size_t from = readme.find("| scene |");
    REQUIRE(from != std::string::npos);
    const std::string table = readme.substr(from, readme.find("\n\n", from) - from);
    ex::for_each_scene_entry([&]<class E>() {
        INFO("glsl/README.md's table of scenes has no row naming `" << E::name << "`");
        CHECK(table.find("`" + std::string(E::name) + "`") != std::string::npos);
    });
}

TEST_CASE("glsl float literals read back as the same float")
{
    const float values[] = {0.0f, -0.0f, 1.0f, -2.5f, 0.1f, 1e-30f, 3.4e38f, 1.17549435e-38f, 0.70710677f,
                            123456.79f, 7e-6f, 16777216.0f};
    for (float v : values) {
        const std::string s = krs::glsl::float_literal(v);
        CHECK(s.find_first_of(".e") != std::string::npos);
        CHECK(std::strtof(s.c_str(), nullptr) == v);
    }
}

TEST_CASE("render_reference is the library's tracer: its scene pixels are sphere_trace's hits, at rest and turned")
{
    // Independent of the reference's own loop: every pixel's camera ray traced by the packet
    // stream (trace_queue's refilling lanes) over the interval box_clip leaves of [0, max], with
    // the program's primary options. A pixel shows the scene in the reference (differs from the
    // sky alone) exactly where the stream finds a hit: same camera, rays, interval and threshold.
    // (Unclipped, a bounded scene's grazing rays may end on the other side of the threshold: the
    // march starts elsewhere, so its samples differ; 3 of the turned sponge's 3072 pixels did.)
    constexpr int width = 64, height = 48;
    const auto check = [&](const auto& s, const krs::pinhole_camera& camera, const char* what) {
        INFO(s.name << " " << what);
        const krs::pinhole_camera c = camera.with_size(width, height);
        const krs::trace_options primary = s.program.primary(c);
        const krs::box_clip clip(krs::field_box(s.field), c.eye(), primary);
        std::vector<char> found(std::size_t(width) * std::size_t(height), 0);
        std::uint32_t next_id = 0;
        krs::trace_stream(
            s.field,
            [&](krs::ray_job& job) {
                if (next_id == std::uint32_t(width * height)) return false;
                const int i = int(next_id % std::uint32_t(width)), j = int(next_id / std::uint32_t(width));
                job.r = c.primary_ray(float(i) + 0.5f, float(height) - (float(j) + 0.5f)); // row j from the bottom
                job.t_start = 0.0f;
                job.t_max = primary.max_distance;
                clip.apply(job.r, job.t_start, job.t_max);
                job.id = next_id++;
                return true;
            },
            [&](std::uint32_t id, const krs::hit<float>& h) { found[id] = h.found ? 1 : 0; }, primary);
        const std::vector<float> frame = ex::reference_frame(s, c, width, height);
        krs::glsl::shadertoy_options empty = s.program;
        empty.max_distance = 1e-6f;
        const std::vector<float> sky = ex::reference_frame(s, c, empty, width, height, false);
        std::size_t differ = 0, hits = 0;
        for (std::size_t p = 0; p < found.size(); ++p) {
            const std::size_t i = 4 * p;
            const bool scene = frame[i] != sky[i] || frame[i + 1] != sky[i + 1] || frame[i + 2] != sky[i + 2];
            differ += scene != (found[p] != 0);
            hits += found[p] != 0;
        }
        CHECK(hits > found.size() / 20);
        CHECK(differ == 0);
    };
    const auto tree = ex::tree_scene::build();
    check(tree, tree.camera, "at rest");
    check(tree, tree.camera.with_size(width, height).turned(11.0f, 40.0f, 30.0f), "turned");
    const auto koch = ex::kifs_koch_scene::build();
    check(koch, koch.camera, "at rest");
    const auto sponge = ex::sponge_scene::build(); // bounded: both clip to its box
    check(sponge, sponge.camera.with_size(width, height).turned(7.0f, 0.0f, 0.0f), "turned");
}

TEST_CASE("framebuffer_byte rounds as an 8-bit framebuffer: to nearest, ties to even")
{
    // A float v whose 255 v is exactly k + 1/2 in float: the tie a GPU stores as the even
    // neighbour (ANGLE's D3D11 and Vulkan back ends stored 122 for 122.5; std::lround gave 123).
    const auto tie = [](int k) {
        const float target = float(k) + 0.5f;
        float v = target / 255.0f;
        for (int n = 0; n < 64 && 255.0f * v != target; ++n)
            v = std::nextafter(v, 255.0f * v < target ? 1.0f : 0.0f);
        REQUIRE(255.0f * v == target);
        return v;
    };
    CHECK(krs::glsl::framebuffer_byte(tie(122)) == 122);
    CHECK(krs::glsl::framebuffer_byte(tie(123)) == 124);
    CHECK(krs::glsl::framebuffer_byte(tie(0)) == 0);
    CHECK(krs::glsl::framebuffer_byte(tie(254)) == 254);
    // Away from ties, the nearest byte; outside [0, 1], clamped.
    for (int k = 0; k <= 255; ++k) {
        CHECK(krs::glsl::framebuffer_byte(float(k) / 255.0f) == k);
        CHECK(krs::glsl::framebuffer_byte((float(k) + 0.49f) / 255.0f) == std::min(k, 255));
    }
    CHECK(krs::glsl::framebuffer_byte(-0.3f) == 0);
    CHECK(krs::glsl::framebuffer_byte(1.7f) == 255);
}

TEST_CASE("shadertoy clips primary rays to a bounded scene's box without changing the picture")
{
    // The program clips where the sequence is bounded (the sponge; a tree without ground, mostly
    // sky) and not where it holds planes (terrain, a tree on its ground). Its C++ twin, clipped
    // and not, must draw the same picture: the clip only skips empty space.
    krs::model::tree_style style;
    style.levels = 8;
    style.ground_height.reset();
    const ex::scene<krs::model::tree_sequence> bare{
        "bare", krs::model::build_tree(krs::model::grow_tree(style)),
        krs::pinhole_camera({4.6f, 3.6f, -9.2f}, {0.0f, 3.3f, 0.0f}, {0, 1, 0}, 50.0f, 96, 72),
        krs::glsl::shadertoy_options::lit({0.45f, 0.8f, -0.4f}, 40.0f), {}, {1, 1, 1}};
    int bounded = 0;
    const auto check = [&](const auto& s) {
        INFO(s.name);
        const bool is_bounded = krs::field_box(s.field).is_bounded();
        const std::string text = ex::file_text(s, ex::shadertoy_file);
        CHECK(occurrences(text, is_bounded ? "const bool KRS_CLIP = true;" : "const bool KRS_CLIP = false;") == 1);
        if (!is_bounded) return;
        ++bounded;
        const int width = 96, height = 72;
        const std::vector<float> clipped = ex::reference_frame(s, s.camera, width, height, true);
        const std::vector<float> plain = ex::reference_frame(s, s.camera, width, height, false);
        // Alpha is 1 everywhere: a pixel shows the scene where it differs from the sky alone.
        const std::vector<float> sky = ex::sky_frame(s, width, height);
        const auto hit = [&](const std::vector<float>& frame, std::size_t i) {
            return frame[i] != sky[i] || frame[i + 1] != sky[i + 1] || frame[i + 2] != sky[i + 2];
        };
        // A clipped ray starts elsewhere, so its samples, and the point inside the hit threshold
        // where it stops, differ: the shading at that point moves a little (and a shadow ray
        // from it may flip), but what is hit does not.
        std::size_t hit_differs = 0, hits = 0;
        double difference = 0;
        for (std::size_t i = 0; i < clipped.size(); i += 4) {
            hit_differs += hit(clipped, i) != hit(plain, i);
            hits += hit(plain, i);
            for (std::size_t c = 0; c < 4; ++c) difference += std::abs(clipped[i + c] - plain[i + c]);
        }
        CHECK(hits > std::size_t(width * height / 20));
        MESSAGE(s.name << ": hit/miss differs on " << hit_differs << " pixels, mean |difference| "
                       << difference / double(clipped.size()));
        CHECK(hit_differs <= std::size_t(width * height / 500));
        CHECK(difference / double(clipped.size()) <= 0.005);
    };
    ex::for_each_scene(check);
    check(bare);
    CHECK(bounded >= 2);
}

TEST_CASE("glsl emits each kernel kind once and only the kinds a scene uses")
{
    // tree_sequence holds torus_capsule, sphere and plane; a tree without leaves or ground uses
    // only torus capsules.
    krs::model::tree_style style;
    style.levels = 4;
    style.leaves_per_twig = 0;
    style.ground_height.reset();
    const auto bare = krs::model::build_tree(krs::model::grow_tree(style));
    const std::string text = krs::glsl::emit(bare, "bare");
    CHECK(occurrences(text, "float krs_torus_capsule_distance(") == 1);
    CHECK(occurrences(text, "krs_sphere_distance") == 0);
    CHECK(occurrences(text, "krs_plane_distance") == 0);
    CHECK(occurrences(text, "float krs_mirror_signed_distance(") == 1);
    CHECK(occurrences(text, "struct krs_location") == 1);
    CHECK(occurrences(text, "float krs_bare(vec3 p)") == 1);
    CHECK(occurrences(text, "krs_location krs_bare_locate(vec3 p)") == 1);
    CHECK(occurrences(text, "krs_kernel_shading krs_bare_shade(") == 1);

    // Two fields in one program share the library.
    krs::glsl::emitter e;
    e.add(ex::tree_scene::build().field, "a");
    e.add(ex::forest_scene::build().field, "b");
    const std::string both = e.source();
    CHECK(occurrences(both, "float krs_torus_capsule_distance(") == 1);
    CHECK(occurrences(both, "float krs_sphere_distance(") == 1);
    CHECK(occurrences(both, "float krs_a(vec3 p)") == 1);
    CHECK(occurrences(both, "float krs_b(vec3 p)") == 1);
}

TEST_CASE("glsl data layout: pack equals the emitter data and the documented vec4 order")
{
    const auto s = ex::sponge_scene::build();
    krs::glsl::emitter e({krs::glsl::target::glsl330, krs::glsl::data_mode::buffer, "data", 0});
    e.add(s.field, "sponge");
    const std::vector<float> packed = krs::glsl::pack(s.field, "sponge");
    // Mirrors first (vec4 normal, offset), then the kernels.
    REQUIRE(packed.size() == 4 * (s.field.mirror_count() + 5));
    for (std::size_t i = 0; i < s.field.mirror_count(); ++i) {
        const krs::mirror& m = s.field.mirrors()[i];
        CHECK(packed[4 * i] == m.normal.x);
        CHECK(packed[4 * i + 1] == m.normal.y);
        CHECK(packed[4 * i + 2] == m.normal.z);
        CHECK(packed[4 * i + 3] == m.offset);
    }
    const std::string text = e.source();
    CHECK(text.find("layout(std140) uniform krs_data_block {\n    vec4 krs_data[26];\n};") != std::string::npos);
    krs::glsl::emitter ssbo({krs::glsl::target::glsl450, krs::glsl::data_mode::buffer, "data", 3});
    ssbo.add(s.field, "sponge");
    CHECK(ssbo.source().find("layout(std430, binding = 3) readonly buffer krs_data_block {") != std::string::npos);
    // The uniform-buffer mode: a UBO at the binding in 450, the plain UBO in 330.
    krs::glsl::emitter ubo({krs::glsl::target::glsl450, krs::glsl::data_mode::uniform_buffer, "data", 3});
    ubo.add(s.field, "sponge");
    CHECK(ubo.source().find("layout(std140, binding = 3) uniform krs_data_block {\n    vec4 krs_data[26];\n};") !=
          std::string::npos);
    krs::glsl::emitter ubo330({krs::glsl::target::glsl330, krs::glsl::data_mode::uniform_buffer, "data", 3});
    ubo330.add(s.field, "sponge");
    const std::string ubo330_text = ubo330.source();
    CHECK(ubo330_text.substr(ubo330_text.find('\n')) == text.substr(text.find('\n'))); // all but the header line
    CHECK_THROWS_AS(krs::glsl::emitter({krs::glsl::target::shadertoy, krs::glsl::data_mode::buffer}),
                    krs::invalid_parameter);
}

TEST_CASE("glsl data name: follows the prefix, and names nothing else the code declares")
{
    // The array is prefix + data_name. A data name that makes it one of the scene's functions
    // (krs_sponge, krs_sponge_locate) would redefine it: refused by name.
    const auto s = ex::sponge_scene::build();
    for (const char* clash : {"sponge", "sponge_locate", "sponge_shade"}) {
        INFO(std::string(clash));
        krs::glsl::emitter e({krs::glsl::target::glsl330, krs::glsl::data_mode::buffer, clash, 0});
        CHECK_THROWS_WITH_AS(e.add(s.field, "sponge"), doctest::Contains("glsl.options.data_name"), krs::invalid_parameter);
    }
    // Locals of the generated functions (d, p, light) hid an unprefixed array; prefixed they cannot.
    // And names of the library: the struct krs_location, the mirror's fold (the sponge uses it).
    for (const char* clash : {"location", "kernel_shading", "mirror_fold"}) {
        INFO(std::string(clash));
        krs::glsl::emitter e({krs::glsl::target::glsl330, krs::glsl::data_mode::constants, clash, 0});
        CHECK_THROWS_WITH_AS(e.add(s.field, "sponge"), doctest::Contains("glsl.options.data_name"), krs::invalid_parameter);
    }
    for (const char* fine : {"data", "d", "p", "light", "scene", "D", "p2", "1x"}) {
        INFO(std::string(fine));
        krs::glsl::emitter e({krs::glsl::target::glsl330, krs::glsl::data_mode::buffer, fine, 0});
        CHECK_NOTHROW(e.add(s.field, "sponge"));
        CHECK(e.source().find(std::string("vec4 krs_") + fine + "[") != std::string::npos);
    }
    for (const char* bad : {"", "a-b", "my data", "x.y", "_x", "a__b"}) {
        INFO(std::string(bad));
        CHECK_THROWS_WITH_AS(krs::glsl::emitter({krs::glsl::target::glsl330, krs::glsl::data_mode::buffer, bad, 0}),
                             doctest::Contains("glsl.options.data_name"), krs::invalid_parameter);
    }
    // In buffer mode the block is a global name too (a clash with the data's names is reported
    // against the data name, whichever side brought it).
    krs::glsl::emitter blocked({krs::glsl::target::glsl330, krs::glsl::data_mode::buffer, "data", 0});
    CHECK_THROWS_WITH_AS(blocked.add(s.field, "data_block"), doctest::Contains("krs_data_block"), krs::invalid_parameter);
    CHECK(blocked.array_name() == "krs_data");
    CHECK(blocked.block_name() == "krs_data_block");
}

TEST_CASE("glsl scene names: one that makes a name the library or an earlier field declares is refused")
{
    const auto s = ex::sponge_scene::build();
    krs::glsl::emitter e({krs::glsl::target::glsl450, krs::glsl::data_mode::constants, "data", 0});
    REQUIRE(e.add(s.field, "sponge") == "krs_sponge");
    const std::string before = e.source();
    // The structs, a library function the scene uses, and the same scene again.
    for (const char* clash : {"location", "kernel_shading", "mirror_fold", "box_distance", "sponge", "sponge_locate"}) {
        INFO(std::string(clash));
        CHECK_THROWS_WITH_AS(e.add(s.field, clash), doctest::Contains("glsl.add.name"), krs::invalid_parameter);
        CHECK(e.source() == before); // a refused field leaves nothing behind
    }
    for (const char* bad : {"", "my scene", "_x", "a__b", "x-y"}) {
        INFO(std::string(bad));
        CHECK_THROWS_WITH_AS(e.add(s.field, bad), doctest::Contains("glsl.add.name"), krs::invalid_parameter);
    }
    CHECK_NOTHROW(e.add(s.field, "sponge2"));
    // A Shadertoy program declares krs_scene, krs_sky, krs_trace ... beside the scene's krs_NAME.
    for (const char* clash : {"scene", "sky", "trace", "box_clip", "albedo", "camera", "hit_threshold"}) {
        INFO(std::string(clash));
        CHECK_THROWS_WITH_AS(krs::glsl::shadertoy(s.field, s.camera, s.program, clash), doctest::Contains("glsl.shadertoy.name"),
                             krs::invalid_parameter);
    }
    CHECK_NOTHROW(krs::glsl::shadertoy(s.field, s.camera, s.program, "my_scene"));
}

TEST_CASE("glsl twice_declared reads a text's global names")
{
    // Independent of the emitter: small texts written by hand.
    CHECK(krs::glsl::twice_declared("float a(vec3 p) { return 1.0; }\nfloat b(vec3 p) {\n    return a(p);\n}\n") == "");
    CHECK(krs::glsl::twice_declared("float a(vec3 p) { return 1.0; }\nvec3 a(vec3 p) { return p; }\n") == "a");
    CHECK(krs::glsl::twice_declared("struct s {\n    float a;\n};\nfloat s(vec3 p) { return 0.0; }\n") == "s");
    CHECK(krs::glsl::twice_declared("const vec4 d[2] = vec4[2](\n    vec4(0.0),\n    vec4(1.0));\nfloat d(float x) { return x; }\n") == "d");
    CHECK(krs::glsl::twice_declared("layout(std140) uniform b {\n    vec4 d[2];\n};\nfloat d(float x) { return x; }\n") == "d");
    CHECK(krs::glsl::twice_declared("layout(std140) uniform b {\n    vec4 d[2];\n};\nfloat b(float x) { return x; }\n") == "b");
    CHECK(krs::glsl::twice_declared("#ifndef A\n#define A\nfloat f(float x) { return x; }\n#endif\n// f\n") == "");
}

// Identifiers of `text` (maximal runs of letters, digits and _ not starting with a digit).
std::set<std::string> identifiers(const std::string& text)
{
    std::set<std::string> names;
    const auto word = [](char c) { return std::isalnum(static_cast<unsigned char>(c)) || c == '_'; };
    for (std::size_t i = 0; i < text.size();) {
        if (!word(text[i])) {
            ++i;
            continue;
        }
        std::size_t j = i;
        while (j < text.size() && word(text[j])) ++j;
        if (!std::isdigit(static_cast<unsigned char>(text[i]))) names.insert(text.substr(i, j - i));
        i = j;
    }
    return names;
}

TEST_CASE("glsl prefix: every name the snippet declares carries it, the scene function included")
{
    const auto s = ex::forest_scene::build();
    for (const auto mode : {krs::glsl::data_mode::constants, krs::glsl::data_mode::buffer}) {
        krs::glsl::emitter plain({krs::glsl::target::glsl450, mode, "data", 0});
        krs::glsl::emitter mine({krs::glsl::target::glsl450, mode, "data", 0, "forest_gen_"});
        CHECK(mine.array_name() == "forest_gen_data");
        CHECK(plain.add(s.field, "forest") == "krs_forest");
        CHECK(mine.add(s.field, "forest") == "forest_gen_forest");
        const std::string a = plain.source(), b = mine.source();
        // Independent of the renaming: the identifiers the default text declares are those that
        // start with krs_ (or KRS_ for guards); with the prefix none is left, and each is there
        // under the new prefix.
        const std::set<std::string> before = identifiers(a), after = identifiers(b);
        std::size_t renamed = 0;
        for (const std::string& n : before) {
            if (n.rfind("krs_", 0) == 0) {
                INFO(n);
                CHECK(after.count("forest_gen_" + n.substr(4)) == 1);
                ++renamed;
            } else if (n.rfind("KRS_", 0) == 0) {
                CHECK(after.count("FOREST_GEN_" + n.substr(4)) == 1);
            }
        }
        CHECK(renamed >= 10); // functions, structs, the data array, the scene's three functions
        for (const std::string& n : after) {
            INFO(n);
            CHECK(n.rfind("krs_", 0) != 0);
            CHECK(n.rfind("KRS_", 0) != 0);
        }
        CHECK(b.find("float forest_gen_forest(vec3 p)") != std::string::npos);
        // Nothing else changed: the prefix replaced back gives the default text.
        std::string back = b;
        for (const auto& [from, to] : {std::pair<std::string, std::string>{"forest_gen_", "krs_"}, {"FOREST_GEN_", "KRS_"}})
            for (std::size_t at = back.find(from); at != std::string::npos; at = back.find(from, at + to.size()))
                back.replace(at, from.size(), to);
        CHECK(back == a);
    }
    // Not a GLSL identifier, the implementation's gl_ names, GLSL's reserved double underscore; not
    // ending in _ (prefix "i" and name "n" spell the keyword in); upper case (guards carry the prefix
    // in upper case, so KRS_ and krs_ snippets would share them and one library would vanish).
    for (const char* bad : {"", "1a_", "gl_", "gl_mine_", "a-b_", "my__", "x y_", "i", "gl", "KRS_", "Krs_", "_a_"}) {
        INFO(std::string(bad));
        CHECK_THROWS_WITH_AS(krs::glsl::emitter({krs::glsl::target::glsl330, krs::glsl::data_mode::constants, "data", 0, bad}),
                             doctest::Contains("glsl.options.prefix"), krs::invalid_parameter);
    }
}

TEST_CASE("glsl es300 snippets declare precision and the version line is optional")
{
    const auto s = ex::terrain_scene::build();
    const krs::glsl::options es{krs::glsl::target::es300, krs::glsl::data_mode::constants, "t", 0};
    const std::string without = krs::glsl::emit(s.field, "terrain", es);
    const std::string with = krs::glsl::emit(s.field, "terrain", es, true);
    CHECK(without.find("#version") == std::string::npos);
    CHECK(with.rfind("#version 300 es\n", 0) == 0);
    CHECK(without.find("precision highp float;") != std::string::npos);
    CHECK(with.substr(16) == without);
}

TEST_CASE("glsl fractals: KIFS and similar shells emit by recursion, pack agrees")
{
    const auto sponge = krs::make_menger_sponge(4);
    krs::glsl::emitter e({krs::glsl::target::glsl330, krs::glsl::data_mode::buffer, "m", 0});
    e.add(sponge, "menger");
    e.add(krs::make_cube_fractal(3), "cubes"); // shares abs_fold, plane_fold, scale_about and box
    const std::string text = e.source();
    CHECK(occurrences(text, "vec3 krs_abs_fold_apply(") == 1);
    CHECK(occurrences(text, "vec3 krs_sort_fold_apply(") == 1);
    CHECK(occurrences(text, "vec3 krs_plane_fold_apply(") == 1);
    CHECK(occurrences(text, "float krs_box_distance(") == 1);
    CHECK(occurrences(text, "float krs_menger_kernel(vec3 p)") == 1);
    CHECK(occurrences(text, "vec3 krs_menger_program(vec3 p)") == 1);
    CHECK(occurrences(text, "for (int i = 0; i < 4; ++i) p = krs_menger_program(p);") == 1); // last_iteration taps
    CHECK(occurrences(text, "float krs_cubes(vec3 p)") == 1);
    CHECK(krs::glsl::pack(sponge, "menger") ==
          std::vector<float>(e.data().begin(), e.data().begin() + std::ptrdiff_t(krs::glsl::pack(sponge, "menger").size())));
    // Box (5 vec4s), abs (1), sort (none), scale (1), plane (1), then 1 / 3^i for i = 0..4.
    const std::vector<float> packed = krs::glsl::pack(sponge, "menger");
    REQUIRE(packed.size() == 4 * (5 + 3 + 11));
    const float* inverse = packed.data() + 4 * 8;
    CHECK(inverse[0] == 1.0f);
    for (int i = 1; i <= 4; ++i) {
        CHECK(inverse[i] > 0.0f);
        CHECK(double(inverse[i]) <= std::pow(3.0, -i));
    }
    CHECK(inverse[5] == 0.0f);

    const auto lotus = krs::make_recursive_lotus(1.0f, 8, {krs::shell_seams::none, 0.02f, 1.0f});
    const std::string shell = krs::glsl::emit(lotus, "lotus");
    CHECK(occurrences(shell, "float krs_lotus_shell_7(vec3 p)") == 1);
    CHECK(occurrences(shell, "float krs_lotus_scale(float k)") == 1);
    CHECK(occurrences(shell, "for (int j = -1; j <= 1; ++j)") == 0); // seams::none: one shell
    const std::string adjacent = krs::glsl::emit(krs::make_cube_singularity(), "cubes");
    CHECK(occurrences(adjacent, "for (int j = -1; j <= 1; ++j)") == 1);
    CHECK(occurrences(adjacent, "float krs_box_distance(") == 1);
    CHECK(adjacent.find("inf") == std::string::npos);
}

TEST_CASE("pinhole_camera::turned: at rest the camera, an orbit about the pivot's vertical, a rigid basis")
{
    const krs::pinhole_camera v = ex::tree_scene::build().camera.with_size(160, 120);
    const auto equal = [](const krs::vec3f& a, const krs::vec3f& b) { return a.x == b.x && a.y == b.y && a.z == b.z; };
    const auto same = [&](const krs::pinhole_camera& a, const krs::pinhole_camera& b) {
        return equal(a.eye(), b.eye()) && equal(a.forward(), b.forward()) && equal(a.right(), b.right()) &&
               equal(a.up(), b.up());
    };
    // No time, no drag, or the pointer at the frame's centre: the camera, bit for bit (the
    // program's frame at rest is held against render_reference of this very camera).
    CHECK(same(v.turned(0.0f, 0.0f, 0.0f), v));
    CHECK(same(v.turned(0.0f, 80.0f, 60.0f), v));
    const float radius = krs::length(v.eye() - v.pivot());
    const float seconds = v.orbit().seconds;
    for (const float time : {7.0f, 0.5f * seconds, seconds}) {
        const krs::pinhole_camera o = v.turned(time, 0.0f, 0.0f);
        INFO("time " << time);
        // About the vertical through the pivot: height and distance kept, the angle turned is
        // 2 pi time / orbit seconds (measured in the horizontal plane, in double).
        CHECK(o.eye().y == doctest::Approx(v.eye().y).epsilon(1e-5));
        CHECK(krs::length(o.eye() - v.pivot()) == doctest::Approx(radius).epsilon(1e-5));
        const double a0 = std::atan2(double(v.eye().z - v.pivot().z), double(v.eye().x - v.pivot().x));
        const double a1 = std::atan2(double(o.eye().z - v.pivot().z), double(o.eye().x - v.pivot().x));
        const double turned = std::remainder(a0 - a1, 2.0 * std::numbers::pi); // x toward z is negative yaw
        const double expected =
            std::remainder(2.0 * std::numbers::pi * double(time) / double(seconds), 2.0 * std::numbers::pi);
        CHECK(std::abs(std::remainder(turned - expected, 2.0 * std::numbers::pi)) <= 1e-4);
        // Still an orthonormal basis, and still looking at the pivot.
        CHECK(krs::length(o.forward()) == doctest::Approx(1.0f).epsilon(1e-5));
        CHECK(std::abs(krs::dot(o.forward(), o.right())) <= 1e-5f);
        CHECK(std::abs(krs::dot(o.forward(), o.up())) <= 1e-5f);
        CHECK(std::abs(krs::dot(o.right(), o.up())) <= 1e-5f);
        CHECK(krs::length(krs::cross(o.forward(), krs::normalize(v.pivot() - o.eye()))) <= 1e-5f);
    }
    // The pointer above the centre tilts about the right axis and raises the eye.
    const krs::pinhole_camera tilted = v.turned(0.0f, 80.0f, 100.0f);
    CHECK(krs::length(tilted.right() - v.right()) <= 1e-6f);
    CHECK(tilted.eye().y - v.eye().y > 0.1f * radius);
    CHECK(krs::length(tilted.eye() - v.pivot()) == doctest::Approx(radius).epsilon(1e-5));
    // An orbit of 0 seconds keeps the camera still.
    const krs::pinhole_camera still = v.with_orbit({.seconds = 0.0f});
    CHECK(same(still.turned(12.0f, 0.0f, 0.0f), still));
}

TEST_CASE("pinhole_camera::turned: pointer up raises the eye, the elevation stays in range, the eye outside the scene")
{
    // Elevation of the eye seen from the pivot, in degrees above the plane across the vertical,
    // measured from the eye's position (the code clamps an angle read from the forward axis).
    const auto elevation = [](const krs::pinhole_camera& v, const krs::pinhole_camera& o) {
        const krs::vec3d offset = krs::vec3d(o.eye() - v.pivot());
        return std::asin(krs::dot(offset, krs::normalize(krs::vec3d(v.vertical()))) / krs::length(offset)) * 180.0 /
               std::numbers::pi;
    };
    constexpr int width = 160, height = 120;
    int scenes = 0;
    ex::for_each_scene([&](const auto& s) {
        INFO(s.name);
        const krs::pinhole_camera v = s.camera.with_size(width, height);
        const double rest = elevation(v, v);
        const double lowest = std::min(rest, double(v.orbit().min_elevation)) - 1e-3;
        const double highest = std::max(rest, double(v.orbit().max_elevation)) + 1e-3;
        // Straight up and down from the centre (no turn about the vertical): up raises, down lowers
        // (or stays, where the baked elevation is already the lowest allowed).
        const double up = elevation(v, v.turned(0.0f, 0.5f * width, 0.9f * height));
        const double down = elevation(v, v.turned(0.0f, 0.5f * width, 0.1f * height));
        CHECK(up > rest + 1.0);
        CHECK(down <= rest + 1e-3);
        // Anywhere the pointer goes, at any time, the elevation is within the range and the eye
        // outside the scene (above the ground, never past the pole).
        for (const float time : {0.0f, 17.0f, 1e5f})
            for (int column = 0; column < 24; ++column) // every 15 degrees of turn
                for (const float y : {1.0f, 0.25f * height, 0.5f * height, 0.75f * height, float(height)}) {
                    const float x = 1.0f + float(column) * (width - 1.0f) / 23.0f;
                    const krs::pinhole_camera o = v.turned(time, x, y);
                    INFO("time " << time << " pointer " << x << ", " << y);
                    const double e = elevation(v, o);
                    CHECK(e >= lowest);
                    CHECK(e <= highest);
                    CHECK(s.field.distance(o.eye()) > 0.0f);
                    CHECK(krs::dot(o.up(), v.vertical()) > 0.0f); // not flipped over the pole
                }
        ++scenes;
    });
    CHECK(scenes == int(ex::scene_count));
    // The turn is reduced to one turn: a day of iTime gives the camera of the same phase.
    const krs::pinhole_camera v = ex::tree_scene::build().camera.with_size(width, height);
    const krs::pinhole_camera late = v.turned(86400.0f + 15.0f, 0.0f, 0.0f);
    const krs::pinhole_camera early = v.turned(15.0f, 0.0f, 0.0f);
    CHECK(krs::length(late.eye() - early.eye()) <= 1e-3f * krs::length(v.eye() - v.pivot()));
    // The angle handed to sin and cos is within [-pi, pi] (plus rounding), and the same angle.
    CHECK(krs::detail::one_turn(0.0f) == 0.0f);
    for (const float x : {3.0f, -3.0f, 3.2f, -3.2f, 100.0f, -7000.5f, 86400.0f * 0.10471976f}) {
        INFO(x);
        const float r = krs::detail::one_turn(x);
        CHECK(std::abs(double(r)) <= std::numbers::pi * (1.0 + 1e-6));
        const double whole_turns = (double(x) - double(r)) / (2.0 * std::numbers::pi);
        CHECK(std::abs(whole_turns - std::round(whole_turns)) <= 1e-3);
    }
}

TEST_CASE("shadertoy_options::validate and the camera's orbit refuse what would draw NaN or nothing, by name")
{
    const auto s = ex::kifs_koch_scene::build();
    const auto refused = [&](const krs::glsl::shadertoy_options& o, const char* name) {
        INFO(name);
        CHECK_THROWS_WITH_AS(o.validate(), doctest::Contains(name), krs::invalid_parameter);
        CHECK_THROWS_WITH_AS(krs::glsl::shadertoy(s.field, s.camera, o, s.name, s.albedo), doctest::Contains(name),
                             krs::invalid_parameter);
        CHECK_THROWS_WITH_AS(krs::glsl::render_reference(s.field, s.camera, o, s.albedo, 4, 4), doctest::Contains(name),
                             krs::invalid_parameter);
    };
    const float nan = std::numeric_limits<float>::quiet_NaN(), inf = std::numeric_limits<float>::infinity();
    CHECK_NOTHROW(s.program.validate());
    for (const float bad : {0.0f, -0.5f, nan, inf}) {
        krs::glsl::shadertoy_options o = s.program;
        o.normal_step = bad;
        refused(o, "shadertoy_options.normal_step");
        o = s.program;
        o.band_pixels = bad;
        refused(o, "shadertoy_options.band_pixels");
        o = s.program;
        o.max_distance = bad;
        refused(o, "shadertoy_options.max_distance");
        o = s.program;
        o.threshold_floor = bad;
        refused(o, "shadertoy_options.threshold_floor");
        CHECK_THROWS_WITH_AS(krs::glsl::shadertoy_options::lit({0, 1, 0}, bad),
                             doctest::Contains("shadertoy_options.max_distance"), krs::invalid_parameter);
    }
    for (const float bad : {-1.0f, nan, inf}) {
        krs::glsl::shadertoy_options o = s.program;
        o.footprint_scale = bad;
        refused(o, "shadertoy_options.footprint_scale");
        CHECK_THROWS_WITH_AS(s.camera.with_orbit({.seconds = bad}), doctest::Contains("camera_orbit.seconds"),
                             krs::invalid_parameter);
    }
    krs::glsl::shadertoy_options o = s.program;
    o.max_steps = 0;
    refused(o, "shadertoy_options.max_steps");
    o = s.program;
    o.to_light = {0, 2, 0};
    refused(o, "shadertoy_options.to_light");
    CHECK_THROWS_WITH_AS(krs::glsl::shadertoy_options::lit({0, 0, 0}, 1.0f),
                         doctest::Contains("shadertoy_options.to_light"), krs::invalid_parameter);
    for (const auto& [lo, hi] : {std::pair{50.0f, 40.0f}, std::pair{-90.0f, 10.0f}, std::pair{5.0f, 90.0f},
                                 std::pair{nan, 10.0f}}) {
        CHECK_THROWS_WITH_AS(s.camera.with_orbit({.min_elevation = lo, .max_elevation = hi}),
                             doctest::Contains("camera_orbit.m"), krs::invalid_parameter);
    }
    for (const float bad : {0.0f, 180.0f, nan})
        CHECK_THROWS_WITH_AS(krs::pinhole_camera({0, 0, -1}, {0, 0, 0}, {0, 1, 0}, bad, 4, 4),
                             doctest::Contains("camera.vertical_fov_degrees"), krs::invalid_parameter);
    CHECK_THROWS_WITH_AS(krs::pinhole_camera({0, 0, -1}, {0, 0, 0}, {0, 0, 1}, 40.0f, 4, 4),
                         doctest::Contains("camera.up"), krs::invalid_parameter);
    CHECK_THROWS_WITH_AS(s.camera.with_size(0, 4), doctest::Contains("camera.size"), krs::invalid_parameter);
    // A palette must hold one finite colour per kernel type.
    const auto grass = ex::grass_scene::build();
    CHECK_THROWS_WITH_AS(krs::glsl::shadertoy(grass.field, grass.camera, grass.program, "g", {{0.1f, 0.2f, 0.3f}}),
                         doctest::Contains("glsl.palette"), krs::invalid_parameter);
    CHECK_THROWS_WITH_AS(
        krs::glsl::shadertoy(grass.field, grass.camera, grass.program, "g", {{0.1f, nan, 0.3f}, {0.1f, 0.2f, 0.3f}}),
        doctest::Contains("glsl.palette"), krs::invalid_parameter);
}

TEST_CASE("shadertoy grass: blades green, ground soil (the scene's palette, not bark by kernel type)")
{
    const auto s = ex::grass_scene::build();
    const std::vector<krs::vec3f> palette = krs::glsl::palette_of(s.field, s.palette);
    REQUIRE(palette.size() == 2);
    CHECK(palette[0].y > palette[0].x + 0.05f); // torus_capsule blades: green dominates
    CHECK(palette[0].y > palette[0].z + 0.05f);
    const std::string text = ex::file_text(s, ex::shadertoy_file);
    CHECK(occurrences(text, "if (kind == 0u) return " + krs::glsl::vec3_literal(palette[0]) + ";") == 1);
}

TEST_CASE("glsl distance_only: no locate, shade or their structs, a gradient-shaded program has none")
{
    // The coral's warp holds a sequence: without distance_only its program carried the sequence's
    // _locate and _shade and the krs_location structs, none of which it calls.
    int fields = 0;
    ex::for_each_scene([&](const auto& s) {
        INFO(s.name);
        const std::string text = ex::file_text(s, ex::shadertoy_file);
        if constexpr (krs::glsl::kernel_shaded<std::remove_cvref_t<decltype(s.field)>>) {
            CHECK(occurrences(text, "krs_" + s.name + "_shade(") == 2); // defined, called
        } else {
            ++fields;
            CHECK(occurrences(text, "krs_location") == 0);
            CHECK(occurrences(text, "krs_kernel_shading") == 0);
            CHECK(occurrences(text, "_locate(") == 0);
            CHECK(occurrences(text, "_shade(") == 0);
            CHECK(occurrences(text, "float krs_" + s.name + "(vec3 ") == 1);
        }
    });
    CHECK(fields == 9); // coral, mirrors, five KIFS, lotus, cube singularity
    // A snippet keeps them unless asked.
    const auto sponge = ex::sponge_scene::build();
    krs::glsl::options o;
    const std::string full = krs::glsl::emit(sponge.field, "sponge", o);
    o.distance_only = true;
    const std::string lean = krs::glsl::emit(sponge.field, "sponge", o);
    CHECK(occurrences(full, "krs_sponge_locate(") == 1);
    CHECK(occurrences(lean, "krs_sponge_locate(") == 0);
    CHECK(occurrences(lean, "krs_sponge_shade(") == 0);
    CHECK(occurrences(lean, "struct krs_location") == 0);
    CHECK(occurrences(lean, "float krs_sponge(vec3 p)") == 1);
}

TEST_CASE("shadertoy refuses bad orbits and frame sizes by name")
{
    const auto s = ex::kifs_koch_scene::build();
    for (const int bad : {0, -3, 16385}) {
        INFO(bad);
        CHECK_THROWS_WITH_AS(krs::glsl::render_reference(s.field, s.camera, s.program, s.albedo, bad, 8),
                             doctest::Contains("glsl.render_reference.width"), krs::invalid_parameter);
        CHECK_THROWS_WITH_AS(krs::glsl::render_reference(s.field, s.camera, s.program, s.albedo, 8, bad),
                             doctest::Contains("glsl.render_reference.height"), krs::invalid_parameter);
    }
    // Alpha 1 everywhere, the sky too (premultiplied-alpha pages would show through a 0).
    const std::vector<float> frame = krs::glsl::render_reference(s.field, s.camera, s.program, s.albedo, 16, 12);
    for (std::size_t i = 3; i < frame.size(); i += 4) CHECK(frame[i] == 1.0f);
}

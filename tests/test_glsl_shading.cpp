// The shading the C++ has, in GLSL, against the C++ on llvmpipe: the sequence walk's per-level early
// exit, soft shadows, ambient occlusion, fractal noise, triplanar projection, depth output and the
// depth-buffer limit, and kernel uv. Each GLSL function runs at 16,384 points or rays in a compute
// shader; the reference is the C++ function at the same inputs (compiled with -ffp-contract=off,
// as llvmpipe does not fuse either). Every snippet also goes through glslangValidator for 330, 450
// and ES 3.00 and through spirv-val for Vulkan, and bad parameters are refused by name.

#include "krs/compose/depth.hpp"
#include "krs/glsl/emitter.hpp"
#include "krs/scenes/example_scenes.hpp"
#include "krs/scenes/scene_files.hpp"
#include "krs/kernels/torus_capsule.hpp"
#include "krs/shade/global.hpp"
#include "krs/shade/texture.hpp"

#include "support/gl_context.hpp"
#include "support/gpu_points.hpp"
#include "support/header_scan.hpp"
#include "support/random.hpp"

#include <doctest/doctest.h>

#include <algorithm>
#include <bit>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <iterator>
#include <limits>
#include <random>
#include <regex>
#include <set>
#include <string>
#include <vector>

namespace {

using krs::vec3f;
namespace ex = krs::scenes;

constexpr std::size_t point_count = 16384;

// Runs `expression` (GLSL, a float of vec3 a, b, c) once per input triple in a compute shader after
// `snippet` (a 450 snippet without #version); one float per triple. (A field's distance alone runs
// through krs_test::run_points; this is for the shading functions' several inputs.)
std::vector<float> run(const std::string& snippet, const std::string& expression, const std::vector<std::array<vec3f, 3>>& in,
                       const std::vector<float>& data = {})
{
    krs_test::require_context();
    const std::string text = "#version 430 core\nlayout(local_size_x = 64) in;\n" + snippet +
                             "layout(std430, binding = 1) readonly buffer shading_in { float inputs[]; };\n"
                             "layout(std430, binding = 2) writeonly buffer shading_out { float results[]; };\n"
                             "uniform uint count;\n"
                             "vec3 input_at(uint k) { return vec3(inputs[k], inputs[k + 1u], inputs[k + 2u]); }\n"
                             "void main() {\n"
                             "    uint i = gl_GlobalInvocationID.x;\n"
                             "    if (i >= count) return;\n"
                             "    vec3 a = input_at(9u * i);\n    vec3 b = input_at(9u * i + 3u);\n"
                             "    vec3 c = input_at(9u * i + 6u);\n"
                             "    results[i] = " + expression + ";\n"
                             "}\n";
    const GLuint program = krs_test::link({krs_test::compile(GL_COMPUTE_SHADER, text)});
    glUseProgram(program);
    std::vector<float> packed;
    packed.reserve(in.size() * 9);
    for (const auto& t : in)
        for (const vec3f& v : t) packed.insert(packed.end(), {v.x, v.y, v.z});
    GLuint data_buffer = 0;
    if (!data.empty()) {
        data_buffer = krs_test::buffer(GL_SHADER_STORAGE_BUFFER, data.data(), data.size() * sizeof(float), GL_DYNAMIC_DRAW);
        glBindBufferBase(GL_SHADER_STORAGE_BUFFER, 0, data_buffer);
    }
    const GLuint input = krs_test::buffer(GL_SHADER_STORAGE_BUFFER, packed.data(), packed.size() * sizeof(float), GL_STATIC_DRAW);
    const GLuint output = krs_test::buffer(GL_SHADER_STORAGE_BUFFER, nullptr, in.size() * sizeof(float), GL_DYNAMIC_READ);
    glBindBufferBase(GL_SHADER_STORAGE_BUFFER, 1, input);
    glBindBufferBase(GL_SHADER_STORAGE_BUFFER, 2, output);
    glUniform1ui(glGetUniformLocation(program, "count"), GLuint(in.size()));
    glDispatchCompute(GLuint((in.size() + 63) / 64), 1, 1);
    glMemoryBarrier(GL_BUFFER_UPDATE_BARRIER_BIT | GL_SHADER_STORAGE_BARRIER_BIT);
    std::vector<float> results(in.size());
    glBindBuffer(GL_SHADER_STORAGE_BUFFER, output);
    glGetBufferSubData(GL_SHADER_STORAGE_BUFFER, 0, GLsizeiptr(results.size() * sizeof(float)), results.data());
    REQUIRE(glGetError() == GL_NO_ERROR);
    const GLuint buffers[3] = {input, output, data_buffer};
    glDeleteBuffers(data_buffer ? 3 : 2, buffers);
    glDeleteProgram(program);
    return results;
}

vec3f uniform_in_box(std::mt19937_64& g, vec3f center, vec3f half)
{
    return center + vec3f{float(krs_test::uniform(g, -1, 1)) * half.x, float(krs_test::uniform(g, -1, 1)) * half.y,
                          float(krs_test::uniform(g, -1, 1)) * half.z};
}
vec3f unit_direction(std::mt19937_64& g)
{
    for (;;) {
        const vec3f v{float(krs_test::uniform(g, -1, 1)), float(krs_test::uniform(g, -1, 1)),
                      float(krs_test::uniform(g, -1, 1))};
        const float l = krs::length(v);
        if (l > 0.1f && l <= 1.0f) return v / l;
    }
}

// GPU results against the C++'s: the largest absolute difference and how many are bit-equal.
struct agreement {
    float worst = 0;
    std::size_t equal = 0;
};
template <class Reference>
agreement compare(const std::vector<float>& gpu, Reference&& cpu)
{
    agreement a;
    for (std::size_t i = 0; i < gpu.size(); ++i) {
        const float r = cpu(i);
        a.worst = std::max(a.worst, std::abs(gpu[i] - r));
        a.equal += std::bit_cast<std::uint32_t>(gpu[i]) == std::bit_cast<std::uint32_t>(r);
    }
    return a;
}

// Surface-near sample points of the tree: the shading functions' inputs (p, its world normal, a
// light direction) where they matter, at a distance of 1e-3 to 0.3 from the surface.
struct shading_inputs {
    std::vector<std::array<vec3f, 3>> rays;
};
template <class S>
shading_inputs near_surface(const ex::scene<S>& s, std::uint64_t seed)
{
    std::mt19937_64 g(seed);
    shading_inputs in;
    while (in.rays.size() < point_count) {
        const vec3f p = uniform_in_box(g, s.sample_center, s.sample_half);
        const float d = s.field.distance(p);
        if (!(d > 1e-3f && d < 0.3f)) continue;
        in.rays.push_back({p, s.field.normal(p), unit_direction(g)});
    }
    return in;
}

std::string check_dir()
{
    const std::string dir = std::string(KRS_BINARY_DIR) + "/glsl-check";
    std::filesystem::create_directories(dir);
    return dir;
}

} // namespace

namespace {

// The number of level bounds the early exit tests, from the kernels alone: the levels below the
// highest kernel level (down to it d is infinite), and below the lowest level holding a plane (an
// unbounded kernel: every L_i from there on is unbounded).
template <class S>
std::size_t expected_level_bounds(const S& field)
{
    std::size_t top = 0, first_plane = field.mirror_count() + 1;
    for (std::size_t k = 0; k < field.kernels().size(); ++k) {
        top = std::max<std::size_t>(top, field.kernel_level(k));
        if (std::holds_alternative<krs::plane>(field.kernels()[k]))
            first_plane = std::min<std::size_t>(first_plane, field.kernel_level(k));
    }
    return std::min(top, first_plane);
}

template <class S>
void check_early_exit(const ex::scene<S>& scene)
{
    INFO(scene.name);
    const auto& field = scene.field;
    std::mt19937_64 g(0x7ee);
    std::vector<vec3f> points(point_count);
    for (vec3f& p : points) p = uniform_in_box(g, scene.sample_center, scene.sample_half * 2.0f);

    krs::glsl::emitter early({krs::glsl::target::glsl450, krs::glsl::data_mode::buffer});
    const std::string fn = early.add(field, scene.name);
    krs::glsl::options full_walk{krs::glsl::target::glsl450, krs::glsl::data_mode::buffer};
    full_walk.level_early_exit = false;
    krs::glsl::emitter full(full_walk);
    full.add(field, scene.name);
    // The data does not depend on the option (pack() has none): mirrors, kernels, then one vec4
    // per tested level, as many as the kernels' levels say.
    CHECK(early.data() == full.data());
    CHECK(krs::glsl::pack(field, scene.name) == early.data());
    const std::size_t bounds = expected_level_bounds(field);
    std::size_t parameters = field.mirror_count() * krs::glsl::vec4s_of<typename S::mirror_type>;
    for (const auto& k : field.kernels())
        parameters += std::visit([](const auto& kernel) { return krs::glsl::vec4s_of<std::remove_cvref_t<decltype(kernel)>>; }, k);
    CHECK(bounds > 0);
    CHECK(early.vec4_count() == parameters + bounds);
    const auto tests_in = [](const std::string& text) {
        std::size_t n = 0;
        for (std::size_t at = text.find("> reach * reach"); at != std::string::npos; at = text.find("> reach * reach", at + 1)) ++n;
        return n;
    };
    CHECK(tests_in(early.source()) == bounds);
    CHECK(tests_in(full.source()) == 0);

    const auto distances = [&](const krs::glsl::emitter& e, const std::vector<float>& data) {
        std::vector<float> d;
        for (const auto& r : krs_test::run_points(e.source(), fn, points, data, false, fn + "_data")) d.push_back(r.distance);
        return d;
    };
    const std::vector<float> with_exit = distances(early, early.data());
    const std::vector<float> without = distances(full, full.data());
    std::size_t same = 0;
    for (std::size_t i = 0; i < points.size(); ++i)
        same += std::bit_cast<std::uint32_t>(with_exit[i]) == std::bit_cast<std::uint32_t>(without[i]);
    const agreement cpu = compare(with_exit, [&](std::size_t i) { return field.distance(points[i]); });
    std::printf("early exit (%s): %zu level bounds; %zu/%zu equal to the full walk bit for bit; against the C++: max "
                "|d| %.3g, bit-equal %zu/%zu\n",
                scene.name.c_str(), bounds, same, points.size(), double(cpu.worst), cpu.equal, points.size());
    CHECK(same == points.size());
    CHECK(cpu.worst <= 1e-5f * scene.extent());

    // Live: the kernels of the lowest kernel level poisoned (radius 1e30, a distance of -1e30) in
    // a copy of the data. The full walk evaluates them at every point and returns the poison
    // everywhere; the early exit keeps the unpoisoned value at the points it leaves before that
    // level, which only its test (at that level or above) can do.
    std::uint32_t lowest = std::numeric_limits<std::uint32_t>::max();
    for (std::size_t k = 0; k < field.kernels().size(); ++k) lowest = std::min(lowest, field.kernel_level(k));
    REQUIRE(lowest < bounds);
    std::vector<float> poisoned = early.data();
    std::size_t at = field.mirror_count() * krs::glsl::vec4s_of<typename S::mirror_type>, poisons = 0;
    for (std::size_t k = 0; k < field.kernels().size(); ++k) {
        std::visit(
            [&](const auto& kernel) {
                using K = std::remove_cvref_t<decltype(kernel)>;
                // The radius: sphere (center, radius); torus capsule t3.w (start, radius).
                if (field.kernel_level(k) == lowest && std::is_same_v<K, krs::sphere>) poisoned[4 * at + 3] = 1e30f, ++poisons;
                if (field.kernel_level(k) == lowest && std::is_same_v<K, krs::torus_capsule>)
                    poisoned[4 * (at + 3) + 3] = 1e30f, ++poisons;
                at += krs::glsl::vec4s_of<K>;
            },
            field.kernels()[k]);
    }
    REQUIRE(poisons > 0);
    const std::vector<float> full_poisoned = distances(full, poisoned);
    const std::vector<float> early_poisoned = distances(early, poisoned);
    std::size_t full_kept = 0, early_kept = 0;
    for (std::size_t i = 0; i < points.size(); ++i) {
        full_kept += full_poisoned[i] == without[i];
        early_kept += early_poisoned[i] == with_exit[i];
    }
    std::printf("early exit (%s) with level %u's kernels poisoned: the full walk keeps %zu/%zu distances, the early "
                "exit %zu\n",
                scene.name.c_str(), unsigned(lowest), full_kept, points.size(), early_kept);
    CHECK(full_kept == 0);
    CHECK(early_kept > 0);
    CHECK(early_kept < points.size()); // and the points that do reach the level see the poison
}

} // namespace

TEST_CASE("GLSL sequence walk: the per-level early exit gives the full walk's value, and is live")
{
    check_early_exit(ex::tree_scene::build());
    check_early_exit(ex::forest_scene::build());
}

TEST_CASE("GLSL soft shadow and ambient occlusion match the C++ on llvmpipe")
{
    const auto tree = ex::tree_scene::build();
    const shading_inputs in = near_surface(tree, 0x5a4d);
    krs::glsl::emitter e({krs::glsl::target::glsl450});
    const std::string fn = e.add(tree.field, "tree");
    krs::soft_shadow_options shadow;
    shadow.hardness = 12.0f;
    shadow.threshold = 1e-4f;
    shadow.max_distance = 20.0f;
    shadow.max_steps = 128;
    krs::ambient_occlusion_options ao;
    ao.step = 0.06f;
    ao.samples = 6;
    ao.falloff = 0.75f;
    ao.strength = 1.3f;
    const std::string shadow_fn = e.add_shading(shadow, "tree_shadow", "tree");
    const std::string ao_fn = e.add_shading(ao, "tree_occlusion", "tree");
    CHECK(shadow_fn == "krs_tree_shadow");

    const std::vector<float> s = run(e.source(), shadow_fn + "(a, b, c)", in.rays);
    const std::vector<float> o = run(e.source(), ao_fn + "(a, b)", in.rays);
    std::vector<float> cpu_shadow(s.size());
    for (std::size_t i = 0; i < s.size(); ++i)
        cpu_shadow[i] = krs::soft_shadow(tree.field, in.rays[i][0], in.rays[i][1], in.rays[i][2], shadow);
    const agreement sa = compare(s, [&](std::size_t i) { return cpu_shadow[i]; });
    const agreement oa =
        compare(o, [&](std::size_t i) { return krs::ambient_occlusion(tree.field, in.rays[i][0], in.rays[i][1], ao); });
    std::size_t shadowed = 0, open = 0, off = 0;
    for (std::size_t i = 0; i < s.size(); ++i) {
        shadowed += s[i] == 0.0f, open += s[i] == 1.0f;
        off += std::abs(s[i] - cpu_shadow[i]) > 1e-3f;
    }
    std::printf("soft shadow: %zu rays (%zu blocked, %zu fully lit), max |gpu - cpu| %.3g, bit-equal %zu, off by > 1e-3 "
                "%zu\n",
                s.size(), shadowed, open, double(sa.worst), sa.equal, off);
    std::printf("ambient occlusion: %zu points, max |gpu - cpu| %.3g, bit-equal %zu\n", o.size(), double(oa.worst),
                oa.equal);
    // The inputs cover the function's range: some rays blocked, some lit, most in between.
    CHECK(shadowed > 0);
    CHECK(open > 0);
    // Tolerances. Each function repeats the C++'s operations in its order, and the tree's GLSL
    // distance equals the C++'s bit for bit at most points on llvmpipe and within an ulp or two
    // elsewhere (tests/test_glsl_gpu.cpp). Ambient occlusion is 1 - strength * sum w_j (s_j - d_j)
    // / s_j / sum w_j with s_j >= 0.06: an ulp of d_j (<= 3e-8 for d_j < 0.5) moves it by at most
    // strength * 3e-8 / 0.06 = 6.5e-7, the sum's own rounding a few ulp of 1 more: 1e-6.
    CHECK(oa.worst <= 1e-6f);
    // The soft shadow has no such bound: a march that passes within the hit threshold returns 0
    // on one side and up to hardness * d / t on the other, whatever the last-bit difference that
    // decided it. Away from that, an ulp of a step moves the next sample point by an ulp of t and
    // the ratio hardness * d / t by a few ulp: 1e-3 is far above that. So all but 0.1 % of rays
    // agree to 1e-3 (the threshold flips are that rare), and the worst is reported, not bounded.
    CHECK(off <= s.size() / 1000);
}

TEST_CASE("GLSL fractal noise and triplanar projection match the C++ on llvmpipe")
{
    std::mt19937_64 g(0x401e);
    std::vector<std::array<vec3f, 3>> in(point_count);
    for (auto& t : in) t = {uniform_in_box(g, {0, 0, 0}, {20, 20, 20}), unit_direction(g), {}};
    // Some zero normals: no weight, the plain mean of the three projections (triplanar's other branch).
    for (std::size_t i = 0; i < in.size(); i += 1024) in[i][1] = {0, 0, 0};
    // A pattern written twice, in C++ and GLSL, from sin and cos only (1 ulp apart on llvmpipe).
    const auto pattern = [](float u, float v) { return std::sin(3.0f * u) * std::cos(2.0f * v) + 0.25f * u; };
    const std::string pattern_glsl = "float stripes(float u, float v) { return sin(3.0 * u) * cos(2.0 * v) + 0.25 * u; }\n";

    krs::glsl::emitter e({krs::glsl::target::glsl450});
    const krs::fractal_noise rock(5, 0.7f, 2.1f, 0.55f);
    const krs::fractal_noise bark(1, 3.0f);
    const krs::fractal_noise moss(16, 0.05f, 1.9f, 1.0f);
    const std::string rock_fn = e.add_shading(rock, "rock");
    e.add_shading(bark, "bark");
    e.add_shading(moss, "moss");
    const std::string tri_fn = e.add_shading(krs::triplanar_projection{"stripes", 3.0f}, "facade");
    // Value noise once, however many fractal sums use it.
    const std::string text = e.source();
    CHECK(text.find("float krs_value_noise(") == text.rfind("float krs_value_noise("));

    for (const auto& [name, noise] : {std::pair{"rock", rock}, std::pair{"bark", bark}, std::pair{"moss", moss}}) {
        const std::vector<float> gpu = run(pattern_glsl + text, std::string("krs_") + name + "(a)", in);
        const agreement a = compare(gpu, [&](std::size_t i) { return noise(in[i][0]); });
        std::printf("fractal noise %-4s (%d octaves): %zu points, max |gpu - cpu| %.3g, bit-equal %zu\n", name,
                    noise.octaves, gpu.size(), double(a.worst), a.equal);
        // Value noise is + - * floor fract on both sides, all exact on llvmpipe, in the C++'s
        // order; only a lattice hash moved by a product's last bit could differ (it moves the value
        // anywhere in [-1, 1]), which would show here as an error far above 1e-6.
        CHECK(a.worst <= 1e-6f);
    }
    const std::vector<float> tri = run(pattern_glsl + text, tri_fn + "(a, b)", in);
    const agreement t = compare(tri, [&](std::size_t i) { return krs::triplanar(pattern, in[i][0], in[i][1], 3.0f); });
    std::printf("triplanar: %zu points, max |gpu - cpu| %.3g, bit-equal %zu\n", tri.size(), double(t.worst), t.equal);
    // The pattern is within 1.25 + 5 = 6.25 in magnitude for |u| <= 20 (1 + 0.25 |u|); sin, cos
    // (<= 6e-8 absolute) and pow (~10 ulp of each weight) make the blend differ by a few 1e-6 of
    // that: 1e-5 absolute.
    CHECK(t.worst <= 1e-5f);
    // Where the normal is zero, the mean of the three projections, written out here.
    for (std::size_t i = 0; i < in.size(); i += 1024) {
        const vec3f p = in[i][0];
        CHECK(std::abs(tri[i] - (pattern(p.y, p.z) + pattern(p.z, p.x) + pattern(p.x, p.y)) / 3.0f) <= 1e-5f);
    }
}

TEST_CASE("GLSL depth output and depth-buffer limit match the C++ on llvmpipe")
{
    const krs::depth_projection projection(0.25f, 400.0f);
    krs::glsl::emitter e({krs::glsl::target::glsl450});
    const std::string fn = e.add_shading(projection, "camera");
    std::mt19937_64 g(0xde97);
    const vec3f forward = krs::normalize(vec3f{0.2f, -0.3f, 1.0f});
    std::vector<std::array<vec3f, 3>> in(point_count);
    for (auto& t : in) {
        // Directions in front of the camera and some parallel or behind (c <= 0: no limit); t and
        // depths over the whole range, with some beyond it (clamped).
        vec3f d = unit_direction(g);
        if (krs::dot(d, forward) < 0 && g() % 4 != 0) d = -d;
        t = {d, forward,
             {float(std::exp(krs_test::uniform(g, std::log(0.05), std::log(800.0)))), float(krs_test::uniform(g, -0.1, 1.1)),
              float(krs_test::uniform(g, 1.0, 600.0))}};
    }
    const std::vector<float> depth = run(e.source(), fn + "_hit_depth(c.x, a, b)", in);
    const std::vector<float> limit = run(e.source(), fn + "_ray_limit(c.y, a, b, c.z)", in);
    const std::vector<float> view = run(e.source(), fn + "_view_depth(c.y)", in);
    const agreement da = compare(depth, [&](std::size_t i) { return projection.hit_depth(in[i][2].x, in[i][0], in[i][1]); });
    const agreement la = compare(limit, [&](std::size_t i) {
        return projection.ray_limit(in[i][2].y, in[i][0], in[i][1], in[i][2].z);
    });
    const agreement va = compare(view, [&](std::size_t i) { return projection.view_depth(in[i][2].y); });
    std::printf("depth output: max |gpu - cpu| %.3g, bit-equal %zu/%zu; ray limit: max %.3g, bit-equal %zu; view depth: "
                "max %.3g, bit-equal %zu\n",
                double(da.worst), da.equal, depth.size(), double(la.worst), la.equal, double(va.worst), va.equal);
    // + - * / and clamp only, in the C++'s order, all exact on llvmpipe: bit for bit (a division of
    // llvmpipe's could be 1 ulp off: 1 ulp of 1 is 1.2e-7 for the depth, of 600 is 6e-5 for t).
    CHECK(da.worst <= 1.2e-7f);
    CHECK(la.worst <= 6.2e-5f);
    CHECK(va.worst <= 6.2e-5f);
    std::size_t capped = 0;
    for (std::size_t i = 0; i < in.size(); ++i) capped += limit[i] < in[i][2].z;
    CHECK(capped > in.size() / 4); // the raster does limit most rays (the test can see a wrong limit)

    // Non-finite input, where GLSL leaves min, max and so clamp of a NaN undefined: this pins what
    // llvmpipe does (it keeps NaNs, and min / max of a NaN give the other operand). An infinite
    // hit is at the far plane on both sides; a NaN clamps to the lower end in GLSL (a NaN buffer
    // value reads as the near plane, a NaN hit as depth 0) where the C++'s std::clamp keeps it.
    const float inf = std::numeric_limits<float>::infinity(), nan = std::numeric_limits<float>::quiet_NaN();
    const std::vector<std::array<vec3f, 3>> odd{{forward, forward, {inf, nan, 0}}, {forward, forward, {nan, -inf, 0}},
                                                 {forward, forward, {-inf, inf, 0}}};
    const std::vector<float> odd_depth = run(e.source(), fn + "_hit_depth(c.x, a, b)", odd);
    const std::vector<float> odd_view = run(e.source(), fn + "_view_depth(c.y)", odd);
    CHECK(odd_depth[0] == 1.0f);
    CHECK(projection.hit_depth(inf, forward, forward) == 1.0f);
    CHECK(odd_view[0] == projection.view_depth(0.0f)); // view_depth(NaN): the near plane
    CHECK(std::isnan(projection.view_depth(nan)));     // the C++ keeps the NaN
    CHECK(odd_depth[1] == 0.0f);                        // hit_depth(NaN): depth 0
    CHECK(std::isnan(projection.hit_depth(nan, forward, forward)));
    CHECK(odd_view[1] == projection.view_depth(-inf));  // -inf and inf clamp as in the C++
    CHECK(odd_depth[2] == projection.hit_depth(-inf, forward, forward));
    CHECK(odd_view[2] == projection.view_depth(inf));
}

// What the shading comments say of NaNs on llvmpipe (GLSL lets a compiler assume there are none):
// a NaN computed from the input reaches isnan, isinf sees an infinity, and a comparison with a NaN
// is false, so soft shadow's !(d >= threshold) blocks and ambient occlusion's non-finite test holds.
TEST_CASE("llvmpipe keeps NaNs and infinities: isnan, isinf and a negated comparison see them")
{
    const std::vector<std::array<vec3f, 3>> in{{vec3f{0, 0, 1}, {}, {}}};
    CHECK(run("", "isnan(a.x / a.y) ? 1.0 : 0.0", in)[0] == 1.0f);           // 0 / 0
    CHECK(run("", "isinf(a.z / a.y) ? 1.0 : 0.0", in)[0] == 1.0f);           // 1 / 0
    CHECK(run("", "!(a.x / a.y >= 1e-4) ? 1.0 : 0.0", in)[0] == 1.0f);
    CHECK(run("", "(a.x / a.y >= 1e-4) ? 1.0 : 0.0", in)[0] == 0.0f);
}

namespace {

// The C++'s location of near-surface points of `s` handed to the GLSL (a the kernel point, b.x the
// kernel), until `count` lie on torus capsules (the branches), with their C++ uv; `other` gets
// points on other kinds (the leaves).
template <class S>
void uv_inputs(const S& s, std::size_t count, std::vector<std::array<vec3f, 3>>& on_capsules,
               std::vector<krs::surface_uv<float>>& cpu, std::vector<std::array<vec3f, 3>>& other)
{
    for (std::uint64_t seed = 0x0b; on_capsules.size() < count; ++seed) {
        for (const auto& r : near_surface(s, seed).rays) {
            if (on_capsules.size() == count) break;
            const krs::location<float> w = s.field.locate(r[0]);
            const std::array<vec3f, 3> input{w.kernel_point, vec3f{float(w.kernel), 0, 0}, {}};
            if (const auto* k = std::get_if<krs::torus_capsule>(&s.field.kernels()[w.kernel])) {
                on_capsules.push_back(input);
                cpu.push_back(k->uv(w.kernel_point));
            } else {
                other.push_back(input);
            }
        }
    }
}

// The largest difference of u and of v (v wraps at the tube's inside, atan2 at +-pi: 0 and 1 are
// the same angle).
std::pair<float, float> uv_worst(const std::vector<float>& u, const std::vector<float>& v, const std::vector<krs::surface_uv<float>>& cpu)
{
    float worst_u = 0, worst_v = 0;
    for (std::size_t i = 0; i < u.size(); ++i) {
        worst_u = std::max(worst_u, std::abs(u[i] - cpu[i].u));
        const float dv = std::abs(v[i] - cpu[i].v);
        worst_v = std::max(worst_v, std::min(dv, 1.0f - dv));
    }
    return {worst_u, worst_v};
}

const std::string uv_where = "krs_location(0.0, a, uint(b.x), 0u, uvec2(0u))";

} // namespace

TEST_CASE("GLSL kernel uv of a sequence matches the C++ torus_capsule::uv on llvmpipe")
{
    const auto tree = ex::tree_scene::build();
    krs::glsl::emitter e({krs::glsl::target::glsl450});
    e.add(tree.field, "tree");
    const std::size_t field_vec4s = e.vec4_count();
    const std::string fn = e.add_shading(krs::kernel_uv_glsl{tree.field}, "tree_uv", "tree");
    // The kernels' parameters are the field's: the request adds one vec4 per torus capsule.
    std::size_t capsules = 0;
    for (const auto& k : tree.field.kernels()) capsules += std::holds_alternative<krs::torus_capsule>(k);
    CHECK(e.vec4_count() == field_vec4s + capsules);
    std::vector<std::array<vec3f, 3>> in, other;
    std::vector<krs::surface_uv<float>> cpu;
    uv_inputs(tree, point_count, in, cpu, other);
    const std::vector<float> u = run(e.source(), fn + "(" + uv_where + ").x", in);
    const std::vector<float> v = run(e.source(), fn + "(" + uv_where + ").y", in);
    const auto [worst_u, worst_v] = uv_worst(u, v, cpu);
    std::printf("kernel uv: %zu points on torus capsules (%zu on other kinds), max |u| %.3g, max |v| %.3g\n", in.size(),
                other.size(), double(worst_u), double(worst_v));
    // GLSL's atan(y, x) is within 3e-6 of the C++'s (llvmpipe); u divides the angle by kappa and by
    // twice the half arc length (u <= 1 over the arc: the relative error carries over) and v by
    // 2 pi: 1e-5 for both.
    CHECK(worst_u <= 1e-5f);
    CHECK(worst_v <= 1e-5f);
    // A kernel without uv gets vec2(0) (the tree's spheres: leaves).
    REQUIRE(!other.empty());
    const std::vector<float> lengths = run(e.source(), "length(" + fn + "(" + uv_where + "))", other);
    CHECK(std::count(lengths.begin(), lengths.end(), 0.0f) == std::ptrdiff_t(other.size()));
}

TEST_CASE("GLSL kernel uv in buffer mode follows the data of another sequence of the same structure")
{
    // Two trees of one structure (same levels, seed, leaves: same kernel kinds per level) and
    // other shapes; the code is emitted for the first, the data of the same calls for the second.
    const auto tree = ex::tree_scene::build();
    krs::model::tree_style style;
    style.levels = 12;
    style.seed = 3;
    style.bend = 0.3f;
    style.trunk_radius = 0.16f;
    const ex::scene<krs::model::tree_sequence> bent{"bent", krs::model::build_tree(krs::model::grow_tree(style)),
                                                    tree.camera, tree.program, tree.sample_center, tree.sample_half};
    REQUIRE(bent.field.kernels().size() == tree.field.kernels().size());
    for (std::size_t k = 0; k < tree.field.kernels().size(); ++k) {
        REQUIRE(bent.field.kernels()[k].index() == tree.field.kernels()[k].index());
        REQUIRE(bent.field.kernel_level(k) == tree.field.kernel_level(k));
    }
    const krs::glsl::options o{krs::glsl::target::glsl450, krs::glsl::data_mode::buffer};
    krs::glsl::emitter e(o), moved(o);
    e.add(tree.field, "tree");
    const std::string fn = e.add_shading(krs::kernel_uv_glsl{tree.field}, "tree_uv", "tree");
    moved.add(bent.field, "tree");
    moved.add_shading(krs::kernel_uv_glsl{bent.field}, "tree_uv", "tree");
    // pack() of the new sequence is the leading part of its data (the uv vec4s follow).
    const std::vector<float> packed = krs::glsl::pack(bent.field, "tree");
    REQUIRE(packed.size() < moved.data().size());
    CHECK(std::equal(packed.begin(), packed.end(), moved.data().begin()));
    CHECK(moved.data() != e.data());

    std::vector<std::array<vec3f, 3>> in, other;
    std::vector<krs::surface_uv<float>> cpu;
    uv_inputs(bent, 4096, in, cpu, other);
    const auto [worst_u, worst_v] =
        uv_worst(run(e.source(), fn + "(" + uv_where + ").x", in, moved.data()),
                 run(e.source(), fn + "(" + uv_where + ").y", in, moved.data()), cpu);
    // The same code with the first tree's data is far off: the test can see stale data.
    std::vector<std::array<vec3f, 3>> first(in.begin(), in.begin() + 256);
    const auto [stale_u, stale_v] = uv_worst(run(e.source(), fn + "(" + uv_where + ").x", first, e.data()),
                                             run(e.source(), fn + "(" + uv_where + ").y", first, e.data()),
                                             std::vector<krs::surface_uv<float>>(cpu.begin(), cpu.begin() + 256));
    std::printf("kernel uv in buffer mode, the bent tree's data: max |u| %.3g, max |v| %.3g (the first tree's data: %.3g, "
                "%.3g)\n",
                double(worst_u), double(worst_v), double(stale_u), double(stale_v));
    CHECK(worst_u <= 1e-5f); // as in the case above
    CHECK(worst_v <= 1e-5f);
    CHECK(std::max(stale_u, stale_v) > 1e-3f);
}

TEST_CASE("GLSL shading: bad parameters are refused with the C++ parameter's name, the emitter unchanged")
{
    const auto tree = ex::tree_scene::build();
    krs::glsl::emitter e({krs::glsl::target::glsl450});
    e.add(tree.field, "tree");
    const std::string before = e.source();
    const auto refused = [&](auto&& call, const std::string& parameter) {
        try {
            call();
        } catch (const krs::invalid_parameter& error) {
            CHECK(error.parameter() == parameter);
            CHECK(std::string(error.what()).find(parameter) != std::string::npos);
            CHECK(e.source() == before);
            return;
        }
        FAIL("accepted where " << parameter << " is bad");
    };
    krs::soft_shadow_options s;
    s.hardness = 0.0f;
    refused([&] { e.add_shading(s, "shadow", "tree"); }, "soft_shadow_options.hardness");
    s = {};
    s.max_steps = 0;
    refused([&] { e.add_shading(s, "shadow", "tree"); }, "soft_shadow_options.max_steps");
    refused([&] { e.add_shading(krs::soft_shadow_options{}, "shadow", "forest"); }, "glsl.add_shading.field");
    refused([&] { e.add_shading(krs::soft_shadow_options{}, "shadow"); }, "glsl.add_shading.field");
    krs::ambient_occlusion_options o;
    o.falloff = 1.5f;
    refused([&] { e.add_shading(o, "occlusion", "tree"); }, "ambient_occlusion_options.falloff");
    o = {};
    o.samples = 33;
    refused([&] { e.add_shading(o, "occlusion", "tree"); }, "ambient_occlusion_options.samples");
    krs::fractal_noise n;
    n.octaves = 0; // public fields: set after construction, checked when written
    refused([&] { e.add_shading(n, "noise"); }, "fractal_noise.octaves");
    n = {};
    n.gain = 0.0f;
    refused([&] { e.add_shading(n, "noise"); }, "fractal_noise.gain");
    refused([&] { e.add_shading(krs::triplanar_projection{"stripes", -1.0f}, "tri"); }, "triplanar.sharpness");
    // Not a name, reserved by GLSL (gl_, __), or one the emitter would rename (krs_).
    for (const char* pattern : {"9lives", "", "a-b", "_stripes", "gl_stripes", "my__stripes", "krs_stripes"}) {
        INFO("pattern " << pattern);
        refused([&] { e.add_shading(krs::triplanar_projection{pattern, 4.0f}, "tri"); }, "triplanar_projection.pattern");
    }
    krs::depth_projection camera;
    camera.far_plane = 0.05f; // public fields: below near_plane
    refused([&] { e.add_shading(camera, "camera"); }, "depth_projection.far_plane");
    camera = {};
    camera.near_plane = -1.0f;
    refused([&] { e.add_shading(camera, "camera"); }, "depth_projection.near_plane");
    refused([&] { e.add_shading(krs::fractal_noise{}, "tree"); }, "glsl.add_shading.name");
    refused([&] { e.add_shading(krs::fractal_noise{}, "_bad"); }, "glsl.add_shading.name");
    // A field given to a request that reads none is refused, not ignored.
    refused([&] { e.add_shading(krs::fractal_noise{}, "noise", "tree"); }, "glsl.add_shading.field");
    refused([&] { e.add_shading(krs::triplanar_projection{"stripes", 4.0f}, "tri", "tree"); }, "glsl.add_shading.field");
    refused([&] { e.add_shading(krs::depth_projection{}, "camera", "tree"); }, "glsl.add_shading.field");
    // Kernel uv reads its sequence's kernels where add() put them: it needs that sequence's name.
    refused([&] { e.add_shading(krs::kernel_uv_glsl{tree.field}, "tree_uv"); }, "glsl.add_shading.field");
    refused([&] { e.add_shading(krs::kernel_uv_glsl{tree.field}, "tree_uv", "forest"); }, "glsl.add_shading.field");
    const auto forest = ex::forest_scene::build(); // a sequence of the same kinds but other kernels
    refused([&] { e.add_shading(krs::kernel_uv_glsl{forest.field}, "tree_uv", "tree"); }, "glsl.add_shading.field");
}

TEST_CASE("GLSL shading: a field named as a shading function's helper is refused")
{
    krs::glsl::emitter e({krs::glsl::target::glsl450});
    e.add_shading(krs::depth_projection{}, "camera");
    const std::string before = e.source();
    try {
        e.add(ex::tree_scene::build().field, "camera_view_depth");
        FAIL("a field named camera_view_depth was accepted beside depth_projection's krs_camera_view_depth");
    } catch (const krs::invalid_parameter& error) {
        CHECK(error.parameter() == std::string("glsl.add.name"));
    }
    CHECK(e.source() == before);
}

TEST_CASE("GLSL shading compiles for 330, 450 and ES 3.00 (glslangValidator) and for Vulkan (spirv-val)")
{
    const auto tree = ex::tree_scene::build();
    const std::string dir = check_dir();
    // A word of capitals and digits outside the preprocessor lines (include guards): a placeholder
    // of a shading function's GLSL that fill() left.
    const std::regex placeholder(R"(\b[A-Z][A-Z0-9_]+\b)");
    for (const auto t : {krs::glsl::target::glsl330, krs::glsl::target::glsl450, krs::glsl::target::es300}) {
        for (const auto mode : {krs::glsl::data_mode::constants, krs::glsl::data_mode::buffer}) {
            for (const std::string prefix : {"krs_", "scene_"}) {
                krs::glsl::options o{t, mode, "data", 0, prefix};
                krs::glsl::emitter e(o);
                e.add(tree.field, "tree");
                e.add_shading(krs::soft_shadow_options{}, "tree_shadow", "tree");
                e.add_shading(krs::ambient_occlusion_options{}, "tree_occlusion", "tree");
                e.add_shading(krs::fractal_noise{}, "rock");
                e.add_shading(krs::triplanar_projection{"rock_pattern", 4.0f}, "facade");
                e.add_shading(krs::depth_projection(0.1f, 100.0f), "camera");
                e.add_shading(krs::kernel_uv_glsl{tree.field}, "tree_uv", "tree");
                const std::string snippet = e.source();
                if (prefix != "krs_") CHECK(snippet.find("krs_") == std::string::npos);
                std::size_t line = 0;
                for (std::size_t end; line < snippet.size(); line = end + 1) {
                    end = snippet.find('\n', line);
                    if (end == std::string::npos) end = snippet.size();
                    const std::string l = snippet.substr(line, end - line);
                    if (l.starts_with("#")) continue;
                    INFO(l);
                    CHECK(!std::regex_search(l, placeholder));
                }
                const std::string p = prefix;
                // The pattern, a 2D slice of the snippet's own noise, is the shader's, defined after
                // the snippet (declared before it, as a user does).
                const std::string text = krs::glsl::version_line(t) + "float rock_pattern(float u, float v);\n" + snippet +
                                         "float rock_pattern(float u, float v) { return " + p + "rock(vec3(u, v, 0.0)); }\n"
                                         "layout(location = 0) out vec4 color;\n"
                                         "void main() {\n    vec3 p = vec3(0.5, 2.0, 0.25);\n    vec3 n = vec3(0.0, 1.0, 0.0);\n"
                                         "    color = vec4(" + p + "tree_shadow(p, n, normalize(vec3(1.0))), " + p +
                                         "tree_occlusion(p, n), " + p + "rock(p), " + p + "facade(p, n));\n"
                                         "    color.xy += " + p + "tree_uv(" + p + "tree_locate(p));\n"
                                         "    color.z += " + p + "camera_hit_depth(2.0, n, n) + " + p +
                                         "camera_ray_limit(0.5, n, n, 50.0);\n}\n";
                const std::string file = dir + "/shading." + std::string(krs::glsl::target_name(t)) + "." +
                                         (mode == krs::glsl::data_mode::buffer ? "buffer." : "") +
                                         prefix.substr(0, prefix.size() - 1) + ".frag";
                if (t == krs::glsl::target::es300) {
                    // ES: the precision lines of the snippet come after the pattern's declaration, so
                    // the declaration gets one of its own.
                    krs_test::validate_with_glslang(file, krs::glsl::version_line(t) + "precision highp float;\n" +
                                                              text.substr(krs::glsl::version_line(t).size()));
                } else {
                    krs_test::validate_with_glslang(file, text);
                }
                if (t == krs::glsl::target::glsl450) krs_test::validate_spirv(file + ".vk.frag", text);
            }
        }
    }
}

// The shading types the cases above run. A type of include/krs that gains GLSL shading (a
// glsl_shading member: the last class opened before it owns it) without a case here fails this.
TEST_CASE("Every type of include/krs with GLSL shading is run by a case of this file")
{
    // kifs_colour_glsl's case is in test_glsl_gpu.cpp ("GLSL KIFS colouring matches kifs_colour on
    // llvmpipe"), beside the KIFS distance presets it colours.
    const std::set<std::string> run = {"soft_shadow_options", "ambient_occlusion_options", "fractal_noise",
                                       "triplanar_projection", "depth_projection", "kernel_uv_glsl", "kifs_colour_glsl"};
    const std::set<std::string> found = krs_test::classes_with(std::regex(R"(\bvoid\s+glsl_shading\s*\()"));
    for (const std::string& type : found) {
        INFO("krs::" << type << " has GLSL shading that no case of tests/test_glsl_shading.cpp runs");
        CHECK(run.count(type) == 1);
    }
    // The scan sees the library (a broken pattern would find nothing and pass).
    CHECK(found.size() == run.size());
}

// The shading the C++ has, in GLSL, against the C++ on llvmpipe: the sequence walk's per-level early
// exit, soft shadows, ambient occlusion, fractal noise, triplanar projection, depth output and the
// depth-buffer limit, and kernel uv. Each GLSL function runs at 16,384 points or rays in a compute
// shader; the reference is the C++ function at the same inputs (compiled with -ffp-contract=off,
// as llvmpipe does not fuse either). Every snippet also goes through glslangValidator for 330, 450
// and ES 3.00 and through spirv-val for Vulkan, and bad parameters are refused by name.

#include "krs/compose/depth.hpp"
#include "krs/glsl/emitter.hpp"
#include "krs/glsl/example_scenes.hpp"
#include "krs/kernels/torus_capsule.hpp"
#include "krs/shade/global.hpp"
#include "krs/shade/texture.hpp"

#include "support/gl_context.hpp"
#include "support/random.hpp"

#include <doctest/doctest.h>

#include <algorithm>
#include <bit>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <iterator>
#include <random>
#include <regex>
#include <set>
#include <string>
#include <vector>

namespace {

using krs::vec3f;
namespace ex = krs::glsl::examples;

constexpr std::size_t point_count = 16384;

// Runs `expression` (GLSL, a float of vec3 a, b, c) once per input triple in a compute shader after
// `snippet` (a 450 snippet without #version); one float per triple.
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

TEST_CASE("GLSL sequence walk: the per-level early exit gives the full walk's value, and is live")
{
    const auto tree = ex::tree();
    std::mt19937_64 g(0x7ee);
    std::vector<std::array<vec3f, 3>> in(point_count);
    for (auto& t : in) t[0] = uniform_in_box(g, tree.sample_center, tree.sample_half * 2.0f);

    krs::glsl::emitter early({krs::glsl::target::glsl450, krs::glsl::data_mode::buffer, "tree_data", 0});
    const std::string fn = early.add(tree.field, "tree");
    krs::glsl::options full_walk{krs::glsl::target::glsl450, krs::glsl::data_mode::buffer, "tree_data", 0};
    full_walk.level_early_exit = false;
    krs::glsl::emitter full(full_walk);
    full.add(tree.field, "tree");
    // A bound per tested level (at most one per mirror), one vec4 each, after the kernels: the
    // data before them is the full walk's.
    REQUIRE(early.vec4_count() > full.vec4_count());
    const std::size_t bounds = early.vec4_count() - full.vec4_count();
    CHECK(bounds <= tree.field.mirror_count());
    CHECK(std::equal(full.data().begin(), full.data().end(), early.data().begin()));

    const std::vector<float> with_exit = run(early.source(), fn + "(a)", in, early.data());
    const std::vector<float> without = run(full.source(), fn + "(a)", in, full.data());
    std::size_t same = 0;
    for (std::size_t i = 0; i < in.size(); ++i)
        same += std::bit_cast<std::uint32_t>(with_exit[i]) == std::bit_cast<std::uint32_t>(without[i]);
    const agreement cpu = compare(with_exit, [&](std::size_t i) { return tree.field.distance(in[i][0]); });
    std::printf("early exit: %zu level bounds; %zu/%zu equal to the full walk bit for bit; against the C++: max "
                "|d| %.3g, bit-equal %zu/%zu\n",
                bounds, same, in.size(), double(cpu.worst), cpu.equal, in.size());
    CHECK(same == in.size());
    CHECK(cpu.worst <= 1e-5f * tree.extent());

    // Live: the same code with every level bound shrunk to its center (radius 0, a wrong bound) exits
    // too soon at some points, so the exit's test is what stops the walk, not a dead branch.
    std::vector<float> shrunk = early.data();
    for (std::size_t k = full.vec4_count(); k < early.vec4_count(); ++k) shrunk[4 * k + 3] = 0.0f;
    const std::vector<float> wrong = run(early.source(), fn + "(a)", in, shrunk);
    std::size_t changed = 0;
    for (std::size_t i = 0; i < in.size(); ++i) changed += wrong[i] != with_exit[i];
    std::printf("early exit with bounds shrunk to points: %zu/%zu distances change\n", changed, in.size());
    CHECK(changed > 0);
}

TEST_CASE("GLSL soft shadow and ambient occlusion match the C++ on llvmpipe")
{
    const auto tree = ex::tree();
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
    const agreement sa = compare(s, [&](std::size_t i) {
        return krs::soft_shadow(tree.field, in.rays[i][0], in.rays[i][1], in.rays[i][2], shadow);
    });
    const agreement oa =
        compare(o, [&](std::size_t i) { return krs::ambient_occlusion(tree.field, in.rays[i][0], in.rays[i][1], ao); });
    std::size_t shadowed = 0, open = 0;
    for (float v : s) shadowed += v == 0.0f, open += v == 1.0f;
    std::printf("soft shadow: %zu rays (%zu blocked, %zu fully lit), max |gpu - cpu| %.3g, bit-equal %zu\n",
                s.size(), shadowed, open, double(sa.worst), sa.equal);
    std::printf("ambient occlusion: %zu points, max |gpu - cpu| %.3g, bit-equal %zu\n", o.size(), double(oa.worst),
                oa.equal);
    // The inputs cover the function's range: some rays blocked, some lit, most in between.
    CHECK(shadowed > 0);
    CHECK(open > 0);
    // Tolerances. The tree's GLSL distance agrees with the C++ to 1e-5 of the extent (bit for bit
    // on llvmpipe, tests/test_glsl_gpu.cpp), and each march repeats the C++'s operations in its
    // order, so a step's sample point moves by at most a few ulp of t. Ambient occlusion is a
    // weighted sum of 6 ratios (s - d) / s with s >= 0.06: an error e in d moves it by at most
    // strength * e / 0.06 = 22 e, so 1e-5 * extent (6e-5) gives 1.3e-3; we allow 1e-3 and it
    // is exact in practice. The soft shadow is a minimum of hardness * d / t over the march; t
    // starts at the first step's d >= threshold, so a last-bit change of the ratio keeps it
    // within ~1e-6 relative, except where a march passes within the hit threshold: there one
    // side returns 0 and the other a small positive value, at most hardness * 2 threshold / t.
    // We allow 1e-3 absolute for all but 0.1 % of rays, and report the worst.
    CHECK(oa.worst <= 1e-3f);
    std::size_t off = 0;
    for (std::size_t i = 0; i < s.size(); ++i)
        off += std::abs(s[i] - krs::soft_shadow(tree.field, in.rays[i][0], in.rays[i][1], in.rays[i][2], shadow)) > 1e-3f;
    CHECK(off <= s.size() / 1000);
}

TEST_CASE("GLSL fractal noise and triplanar projection match the C++ on llvmpipe")
{
    std::mt19937_64 g(0x401e);
    std::vector<std::array<vec3f, 3>> in(point_count);
    for (auto& t : in) t = {uniform_in_box(g, {0, 0, 0}, {20, 20, 20}), unit_direction(g), {}};
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
}

TEST_CASE("GLSL kernel uv of a sequence matches the C++ torus_capsule::uv on llvmpipe")
{
    const auto tree = ex::tree();
    krs::glsl::emitter e({krs::glsl::target::glsl450});
    e.add(tree.field, "tree");
    const std::string fn = e.add_shading(krs::kernel_uv_glsl{tree.field}, "tree_uv");
    // The C++'s location of each point, handed to the GLSL (a in the kernel point, b.x the
    // kernel): the uv alone is compared, not the walk. Near-surface points until 16,384 lie on
    // torus capsules (the branches; the rest are leaves).
    std::vector<std::array<vec3f, 3>> in;
    std::vector<krs::surface_uv<float>> cpu;
    std::size_t without_uv = 0;
    shading_inputs near;
    for (std::uint64_t seed = 0x0b; in.size() < point_count; ++seed) {
        for (const auto& r : (near = near_surface(tree, seed)).rays) {
            if (in.size() == point_count) break;
            const krs::location<float> w = tree.field.locate(r[0]);
            const auto* k = std::get_if<krs::torus_capsule>(&tree.field.kernels()[w.kernel]);
            if (!k) {
                ++without_uv;
                continue;
            }
            in.push_back({w.kernel_point, vec3f{float(w.kernel), 0, 0}, {}});
            cpu.push_back(k->uv(w.kernel_point));
        }
    }
    const std::string where = "krs_location(0.0, a, uint(b.x), 0u, uvec2(0u))";
    const std::vector<float> u = run(e.source(), fn + "(" + where + ").x", in);
    const std::vector<float> v = run(e.source(), fn + "(" + where + ").y", in);
    const agreement ua = compare(u, [&](std::size_t i) { return cpu[i].u; });
    // v wraps at the tube's inside (atan2 at +-pi): 0 and 1 are the same angle.
    float worst_v = 0;
    for (std::size_t i = 0; i < v.size(); ++i) {
        const float dv = std::abs(v[i] - cpu[i].v);
        worst_v = std::max(worst_v, std::min(dv, 1.0f - dv));
    }
    std::printf("kernel uv: %zu points on torus capsules (%zu on other kinds), max |u| %.3g (bit-equal %zu), max |v| "
                "%.3g\n",
                in.size(), without_uv, double(ua.worst), ua.equal, double(worst_v));
    REQUIRE(in.size() == point_count);
    // GLSL's atan(y, x) is within 3e-6 of the C++'s (llvmpipe); u divides the angle by kappa and by
    // twice the half arc length (u <= 1 over the arc: the relative error carries over) and v by
    // 2 pi: 1e-5 for both.
    CHECK(ua.worst <= 1e-5f);
    CHECK(worst_v <= 1e-5f);
    // A kernel without uv gets vec2(0) (the tree's spheres: leaves).
    CHECK(without_uv > 0);
    {
        for (const auto& r : near.rays) {
            const krs::location<float> w = tree.field.locate(r[0]);
            if (std::holds_alternative<krs::torus_capsule>(tree.field.kernels()[w.kernel])) continue;
            const std::vector<std::array<vec3f, 3>> one{{w.kernel_point, vec3f{float(w.kernel), 0, 0}, {}}};
            CHECK(run(e.source(), "length(" + fn + "(" + where + "))", one)[0] == 0.0f);
            break;
        }
    }
}

TEST_CASE("GLSL shading: bad parameters are refused with the C++ parameter's name, the emitter unchanged")
{
    const auto tree = ex::tree();
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
    refused([&] { e.add_shading(krs::triplanar_projection{"9lives", 4.0f}, "tri"); }, "triplanar.pattern");
    krs::depth_projection camera;
    camera.far_plane = 0.05f; // public fields: below near_plane
    refused([&] { e.add_shading(camera, "camera"); }, "depth_projection.far_plane");
    camera = {};
    camera.near_plane = -1.0f;
    refused([&] { e.add_shading(camera, "camera"); }, "depth_projection.near_plane");
    refused([&] { e.add_shading(krs::fractal_noise{}, "tree"); }, "glsl.add_shading.name");
    refused([&] { e.add_shading(krs::fractal_noise{}, "_bad"); }, "glsl.add_shading.name");
}

TEST_CASE("GLSL shading compiles for 330, 450 and ES 3.00 (glslangValidator) and for Vulkan (spirv-val)")
{
    const auto tree = ex::tree();
    const std::string dir = check_dir();
    for (const auto t : {krs::glsl::target::glsl330, krs::glsl::target::glsl450, krs::glsl::target::es300}) {
        for (const std::string prefix : {"krs_", "scene_"}) {
            krs::glsl::options o{t, krs::glsl::data_mode::constants, "data", 0, prefix};
            krs::glsl::emitter e(o);
            e.add(tree.field, "tree");
            e.add_shading(krs::soft_shadow_options{}, "tree_shadow", "tree");
            e.add_shading(krs::ambient_occlusion_options{}, "tree_occlusion", "tree");
            e.add_shading(krs::fractal_noise{}, "rock");
            e.add_shading(krs::triplanar_projection{prefix + "rock_pattern", 4.0f}, "facade");
            e.add_shading(krs::depth_projection(0.1f, 100.0f), "camera");
            e.add_shading(krs::kernel_uv_glsl{tree.field}, "tree_uv");
            const std::string p = prefix;
            // The pattern, a 2D slice of the snippet's own noise, is defined by the shader after
            // the snippet (declared before it, as a user does).
            const std::string text = krs::glsl::version_line(t) +
                                     "float " + p + "rock_pattern(float u, float v);\n" + e.source() + "float " + p +
                                     "rock_pattern(float u, float v) { return " + p + "rock(vec3(u, v, 0.0)); }\n"
                                     "layout(location = 0) out vec4 color;\n"
                                     "void main() {\n    vec3 p = vec3(0.5, 2.0, 0.25);\n    vec3 n = vec3(0.0, 1.0, 0.0);\n"
                                     "    color = vec4(" + p + "tree_shadow(p, n, normalize(vec3(1.0))), " + p +
                                     "tree_occlusion(p, n), " + p + "rock(p), " + p + "facade(p, n));\n"
                                     "    color.xy += " + p + "tree_uv(" + p + "tree_locate(p));\n"
                                     "    color.z += " + p + "camera_hit_depth(2.0, n, n) + " + p +
                                     "camera_ray_limit(0.5, n, n, 50.0);\n}\n";
            const std::string file = dir + "/shading." + std::string(krs::glsl::target_name(t)) + "." +
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

// The shading types the cases above run. A type of include/krs that gains GLSL shading (a
// glsl_shading member: the last class opened before it owns it) without a case here fails this.
TEST_CASE("Every type of include/krs with GLSL shading is run by a case of this file")
{
    const std::set<std::string> run = {"soft_shadow_options", "ambient_occlusion_options", "fractal_noise",
                                       "triplanar_projection", "depth_projection", "kernel_uv_glsl"};
    const std::filesystem::path root = std::filesystem::path(KRS_SOURCE_DIR) / "include" / "krs";
    const std::regex opening(R"((?:struct|class)\s+(\w+)[^{;()<>]*\{)"); // not `template <class X>`
    const std::regex marker(R"(\bvoid\s+glsl_shading\s*\()");
    std::set<std::string> found;
    for (const auto& entry : std::filesystem::recursive_directory_iterator(root)) {
        // (The emitter's folder describes the member in prose; it owns none.)
        if (entry.path().extension() != ".hpp" || entry.path().parent_path().filename() == "glsl") continue;
        std::ifstream in(entry.path());
        const std::string text((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
        std::vector<std::pair<std::ptrdiff_t, std::string>> classes;
        for (auto it = std::sregex_iterator(text.begin(), text.end(), opening); it != std::sregex_iterator(); ++it)
            classes.emplace_back(it->position(), (*it)[1].str());
        for (auto it = std::sregex_iterator(text.begin(), text.end(), marker); it != std::sregex_iterator(); ++it) {
            std::string owner;
            for (const auto& [at, name] : classes)
                if (at < it->position()) owner = name;
            found.insert(owner);
        }
    }
    for (const std::string& type : found) {
        INFO("krs::" << type << " has GLSL shading that no case of tests/test_glsl_shading.cpp runs");
        CHECK(run.count(type) == 1);
    }
    // The scan sees the library (a broken pattern would find nothing and pass).
    CHECK(found.size() == run.size());
}

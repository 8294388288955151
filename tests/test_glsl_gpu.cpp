// The emitted GLSL, compiled by glslangValidator and executed on Mesa llvmpipe through headless
// EGL (docs/design.md#glsl-on-the-cpu), against the C++ fields: distances and locate (compute shaders), and whole
// frames of the Shadertoy programs (fragment path) against the CPU render of the same math.
//
// Built as its own executable (krs_glsl_tests) because it links EGL and OpenGL; CMake option
// KRS_GLSL_TESTS=OFF leaves it out. A context that cannot be created FAILS the test.

#include "krs/compose.hpp"
#include "krs/fractal/fold_steps.hpp"
#include "krs/fractal/kifs.hpp"
#include "krs/fractal/kifs_colour.hpp"
#include "krs/fractal/kifs_presets.hpp"
#include "krs/fractal/log_tilings.hpp"
#include "krs/fractal/shell_presets.hpp"
#include "krs/fractal/similar_shell.hpp"
#include "krs/scenes/example_scenes.hpp"
#include "krs/scenes/scene_files.hpp"
#include "krs/kernels/sphere.hpp"
#include "krs/kernels/torus.hpp"

#include "support/gl_context.hpp"
#include "support/gpu_points.hpp"
#include "support/random.hpp"
#include "support/scenes.hpp"

#include <doctest/doctest.h>

#include <algorithm>
#include <array>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <fstream>
#include <random>
#include <stdexcept>
#include <string>
#include <type_traits>
#include <vector>

namespace {

using krs_test::buffer, krs_test::compile, krs_test::gpu_result, krs_test::link, krs_test::require_context,
    krs_test::run_point_program, krs_test::run_points, krs_test::validate_spirv, krs_test::validate_with_glslang;

namespace ex = krs::scenes;
using krs::vec3f;





template <class S>
std::vector<vec3f> sample_points(const ex::scene<S>& s, std::size_t count)
{
    std::mt19937_64 random(12345);
    const auto u = [](std::mt19937_64& e) { return float(krs_test::uniform(e, -1, 1)); };
    std::vector<vec3f> points(count);
    for (vec3f& p : points)
        p = s.sample_center + vec3f{u(random) * s.sample_half.x, u(random) * s.sample_half.y, u(random) * s.sample_half.z};
    return points;
}

// Smallest |e| of the mirror decisions locate takes on the way to p's kernel space.
template <class Seq>
float mirror_margin(const Seq& s, vec3f p)
{
    float margin = 3.0e38f;
    for (std::size_t i = s.mirror_count(); i-- > 0;) {
        const float e = s.mirrors()[i].signed_distance(p);
        margin = std::min(margin, std::abs(e));
        if (e > 0.0f) p = s.mirrors()[i].reflect(p);
    }
    return margin;
}

struct parity {
    float max_error = 0;        // max |d_gpu - d_cpu|, scene units
    std::size_t points = 0, near_mirror = 0, bits_equal = 0, kernel_equal = 0;
};

template <class S>
parity compare(const ex::scene<S>& s, const std::vector<vec3f>& points, const std::vector<gpu_result>& gpu)
{
    parity r;
    r.points = points.size();
    const float near = 1e-5f * s.extent();
    for (std::size_t i = 0; i < points.size(); ++i) {
        const float d = s.field.distance(points[i]);
        r.max_error = std::max(r.max_error, std::abs(gpu[i].distance - d));
        const krs::location<float> where = s.field.locate(points[i]);
        if (mirror_margin(s.field, points[i]) < near) {
            ++r.near_mirror;
            continue;
        }
        r.bits_equal += gpu[i].reflections == where.reflections;
        r.kernel_equal += gpu[i].kernel == where.kernel && gpu[i].level == where.level;
    }
    return r;
}

template <class S>
void check_scene(const ex::scene<S>& s)
{
    const std::vector<vec3f> points = sample_points(s, 16384);
    struct variant {
        const char* label;
        krs::glsl::target target;
        krs::glsl::data_mode mode;
    };
    const variant variants[] = {{"450 constants", krs::glsl::target::glsl450, krs::glsl::data_mode::constants},
                                {"450 buffer (SSBO std430)", krs::glsl::target::glsl450, krs::glsl::data_mode::buffer},
                                {"450 uniform buffer (UBO)", krs::glsl::target::glsl450,
                                 krs::glsl::data_mode::uniform_buffer},
                                {"330 buffer (UBO std140)", krs::glsl::target::glsl330, krs::glsl::data_mode::buffer}};
    for (const variant& v : variants) {
        krs::glsl::emitter e({v.target, v.mode, s.name + "_data", 0});
        const std::string fn = e.add(s.field, s.name); // krs_NAME, its data krs_NAME_data
        const bool buffer = v.mode != krs::glsl::data_mode::constants;
        const bool uniform_block =
            v.target == krs::glsl::target::glsl330 || v.mode == krs::glsl::data_mode::uniform_buffer;
        const std::vector<float> data = buffer ? krs::glsl::pack(s.field, s.name) : std::vector<float>{};
        const auto gpu = run_points(e.source(), fn, points, data, uniform_block, e.array_name());
        const parity r = compare(s, points, gpu);
        const std::size_t compared = r.points - r.near_mirror;
        std::printf("%-8s %-26s points %zu  max |d_gpu - d_cpu| %.3g (%.3g of extent %.3g)  reflection bits equal "
                    "%zu/%zu (%zu within 1e-5 extent of a mirror, not compared)  kernel equal %zu/%zu\n",
                    s.name.c_str(), v.label, r.points, double(r.max_error), double(r.max_error / s.extent()),
                    double(s.extent()), r.bits_equal, compared, r.near_mirror, r.kernel_equal, compared);
        INFO(s.name << " " << v.label);
        CHECK(r.max_error <= 1e-5f * s.extent());
        CHECK(r.bits_equal == compared);
        CHECK(double(r.kernel_equal) >= 0.999 * double(compared));
        CHECK(double(r.near_mirror) <= 0.01 * double(r.points));
    }
}

// Renders a Shadertoy program through the fragment path at iTime = time with the mouse at
// mouse (iMouse); RGBA floats, bottom-up rows.
std::vector<float> render_gpu(const std::string& shadertoy, int width, int height, float time = 0.0f,
                              const std::array<float, 4>& mouse = {})
{
    require_context();
    const std::string fragment = "#version 430 core\nuniform vec3 iResolution;\nuniform float iTime;\nuniform vec4 iMouse;\n"
                                 "out vec4 krs_frag_color;\n" +
                                 shadertoy + "void main() { mainImage(krs_frag_color, gl_FragCoord.xy); }\n";
    const GLuint program = link({compile(GL_VERTEX_SHADER, krs_test::fullscreen_vertex_shader), compile(GL_FRAGMENT_SHADER, fragment)});
    const std::vector<float> pixels = krs_test::draw_fullscreen(program, width, height, [&] {
        glUniform3f(glGetUniformLocation(program, "iResolution"), float(width), float(height), 1.0f);
        glUniform1f(glGetUniformLocation(program, "iTime"), time);
        glUniform4f(glGetUniformLocation(program, "iMouse"), mouse[0], mouse[1], mouse[2], mouse[3]);
    });
    glDeleteProgram(program);
    return pixels;
}

std::string read_text(const std::string& path)
{
    std::ifstream in(path, std::ios::binary);
    REQUIRE(in.good());
    return std::string((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
}

// How a GPU frame compares with its CPU reference, over the colour channels.
struct frame_match {
    std::size_t pixels = 0, close = 0, exact = 0, bytes_equal = 0, opaque = 0;
    float worst = 0;
    double close_percent() const { return 100.0 * double(close) / double(pixels); }
    double exact_percent() const { return 100.0 * double(exact) / double(pixels); }
    double bytes_equal_percent() const { return 100.0 * double(bytes_equal) / double(pixels); }
};
frame_match match(const std::vector<float>& gpu, const std::vector<float>& cpu)
{
    REQUIRE(gpu.size() == cpu.size());
    frame_match m;
    m.pixels = cpu.size() / 4;
    for (std::size_t i = 0; i < cpu.size(); i += 4) {
        float diff = 0;
        for (std::size_t c = 0; c < 3; ++c) diff = std::max(diff, std::abs(gpu[i + c] - cpu[i + c]));
        m.worst = std::max(m.worst, diff);
        m.close += diff <= 2.0f / 255.0f;
        m.exact += diff == 0.0f;
        // As an 8-bit framebuffer (and glsl_export --reference's PNG) would store the pixel.
        bool same_bytes = true;
        for (std::size_t c = 0; c < 3; ++c)
            same_bytes = same_bytes && krs::glsl::framebuffer_byte(gpu[i + c]) == krs::glsl::framebuffer_byte(cpu[i + c]);
        m.bytes_equal += same_bytes;
        m.opaque += gpu[i + 3] == 1.0f;
    }
    return m;
}

// Pixels where the scene is seen: where the reference differs from the sky alone.
template <class S>
std::size_t scene_pixels(const ex::scene<S>& s, const std::vector<float>& cpu, int width, int height)
{
    const std::vector<float> sky = ex::sky_frame(s, width, height);
    std::size_t seen = 0;
    for (std::size_t i = 0; i < cpu.size(); i += 4)
        seen += cpu[i] != sky[i] || cpu[i + 1] != sky[i + 1] || cpu[i + 2] != sky[i + 2];
    return seen;
}

// The scene's Shadertoy program as shipped in glsl/ (equal to the emitter's text: tests/test_glsl.cpp)
// at iTime = 0 with no mouse, against the CPU reference of the baked camera: every pixel within
// 2/255 (not bit-equal: the kernels' normals and lengths use GLSL builtins 1-2 ulp off C++).
template <class S>
void check_frame(const ex::scene<S>& s)
{
    constexpr int width = 160, height = 120;
    const std::string text = read_text(std::string(KRS_SOURCE_DIR) + "/glsl/" + s.name + ".shadertoy.glsl");
    const std::vector<float> gpu = render_gpu(text, width, height);
    const std::vector<float> cpu = ex::reference_frame(s, s.camera, width, height);
    const frame_match m = match(gpu, cpu);
    const std::size_t seen = scene_pixels(s, cpu, width, height);
    std::printf("%-16s shadertoy frame %dx%d: %.3f%% of pixels within 2/255, %.3f%% exact, %.3f%% equal in 8 bits, "
                "max difference %.4g (%.3f/255), scene on %zu pixels\n",
                s.name.c_str(), width, height, m.close_percent(), m.exact_percent(), m.bytes_equal_percent(),
                double(m.worst), double(m.worst) * 255.0, seen);
    INFO(s.name);
    CHECK(m.close == m.pixels);
    CHECK(m.opaque == m.pixels); // alpha 1 on the sky too
    CHECK(seen > m.pixels / 20);                        // the camera sees the scene
    CHECK(s.field.distance(s.camera.eye()) > 0.0f);     // from outside it
}

std::string wrapper_main(const std::string& name)
{
    return "out vec4 krs_out;\nvoid main() {\n    krs_location w = " + name + "_locate(vec3(0.5));\n"
           "    krs_kernel_shading s = " + name + "_shade(vec3(0.5), vec3(0.0, 1.0, 0.0), vec3(1.0, 0.0, 0.0), 0.01);\n"
           "    krs_out = vec4(" + name + "(vec3(1.0)), w.kernel_point.x + float(w.reflections.x), s.normal.x, 1.0);\n}\n";
}

// The same calls for Vulkan, where an output needs a location.
std::string vulkan_main(const std::string& name)
{
    return "layout(location = 0) out vec4 krs_out;\nvoid main() {\n    krs_location w = " + name + "_locate(vec3(0.5));\n"
           "    krs_kernel_shading s = " + name + "_shade(vec3(0.5), vec3(0.0, 1.0, 0.0), vec3(1.0, 0.0, 0.0), 0.01);\n"
           "    krs_out = vec4(" + name + "(vec3(1.0)), w.kernel_point.x + float(w.reflections.x), s.normal.x, 1.0);\n}\n";
}

// A main for a scene's snippet: a sequence's three functions, or a field's distance.
template <class S>
std::string scene_main(const ex::scene<S>&, const std::string& name)
{
    if constexpr (krs::glsl::kernel_shaded<S>) return wrapper_main(name);
    else return "out vec4 krs_out;\nvoid main() { krs_out = vec4(" + name + "(vec3(0.5, 0.25, 0.125)), 0.0, 0.0, 1.0); }\n";
}
template <class S>
std::string scene_vulkan_main(const ex::scene<S>&, const std::string& name)
{
    if constexpr (krs::glsl::kernel_shaded<S>) return vulkan_main(name);
    else
        return "layout(location = 0) out vec4 krs_out;\nvoid main() { krs_out = vec4(" + name +
               "(vec3(0.5, 0.25, 0.125)), 0.0, 0.0, 1.0); }\n";
}

} // namespace

TEST_CASE("glslangValidator accepts every emitted snippet for every target")
{
    REQUIRE(std::system("\"" KRS_GLSLANG_VALIDATOR "\" --version > /dev/null 2>&1") == 0);
    const std::string dir = std::string(KRS_BINARY_DIR) + "/glsl-check";
    std::system(("mkdir -p \"" + dir + "\"").c_str());
    int files = 0, spirv_files = 0;
    ex::for_each_scene([&](const auto& s) {
        for (const ex::file_kind& kind : ex::files) {
            const std::string text = ex::file_text(s, kind);
            const std::string path = dir + "/" + s.name + std::string(kind.suffix);
            if (kind.target == krs::glsl::target::shadertoy) {
                // As Shadertoy (WebGL 2) compiles it: ES 3.00 with its uniforms and a main.
                validate_with_glslang(path + ".frag", "#version 300 es\nprecision highp float;\nprecision highp int;\n"
                                         "uniform vec3 iResolution;\nuniform float iTime;\nuniform vec4 iMouse;\n"
                                         "out vec4 krs_out;\n" +
                                             text + "void main() { mainImage(krs_out, gl_FragCoord.xy); }\n");
                // And as desktop GLSL, where the tests run it.
                validate_with_glslang(path + ".330.frag", "#version 330 core\nuniform vec3 iResolution;\nuniform float iTime;\n"
                                                 "uniform vec4 iMouse;\nout vec4 krs_out;\n" + text +
                                                 "void main() { mainImage(krs_out, gl_FragCoord.xy); }\n");
                files += 2;
                continue;
            }
            const std::string body = text + scene_main(s, "krs_" + s.name);
            if (kind.target == krs::glsl::target::glsl330 && kind.mode == krs::glsl::data_mode::constants) {
                // The constants snippet serves 330 and 450 alike.
                validate_with_glslang(path + ".450.frag", "#version 450 core\n" + body);
                ++files;
            }
            validate_with_glslang(path + ".frag", krs::glsl::version_line(kind.target) + body);
            ++files;
        }
        // 450 constants and uniform buffer and es300 buffer are not shipped files; check them too.
        for (const auto& [t, m] : {std::pair{krs::glsl::target::glsl450, krs::glsl::data_mode::constants},
                                   std::pair{krs::glsl::target::glsl450, krs::glsl::data_mode::uniform_buffer},
                                   std::pair{krs::glsl::target::es300, krs::glsl::data_mode::buffer}}) {
            krs::glsl::emitter e({t, m, s.name + "_data", 0});
            const std::string fn = e.add(s.field, s.name);
            validate_with_glslang(dir + "/" + s.name + "." + std::string(krs::glsl::target_name(t)) + "." +
                                      std::to_string(int(m)) + ".extra.frag",
                                  e.source(true) + scene_main(s, fn));
            ++files;
        }
        // Vulkan: the 450 code of every data mode (the shipped buffer450 file among them) to SPIR-V.
        for (const auto m : {krs::glsl::data_mode::constants, krs::glsl::data_mode::buffer,
                             krs::glsl::data_mode::uniform_buffer}) {
            krs::glsl::emitter e({krs::glsl::target::glsl450, m, s.name + "_data", 0});
            const std::string fn = e.add(s.field, s.name);
            if (m == krs::glsl::data_mode::buffer)
                CHECK(e.source() == ex::file_text(s, ex::files[3])); // what glsl/NAME.buffer450.glsl holds
            validate_spirv(dir + "/" + s.name + ".vulkan." + std::to_string(int(m)) + ".frag",
                           e.source(true) + scene_vulkan_main(s, fn));
            ++spirv_files;
        }
    });
    std::printf("glslangValidator: %d shaders checked, %d compiled for Vulkan and passed spirv-val\n", files,
                spirv_files);
}

TEST_CASE("Two shipped snippets in one shader: each library part once, both fields right")
{
    // Unguarded, the second snippet redefined struct krs_location and every shared function.
    const auto tree = ex::tree_scene::build();
    const auto terrain = ex::terrain_scene::build();
    const ex::file_kind& constants = ex::files[0];
    REQUIRE(constants.mode == krs::glsl::data_mode::constants);
    const std::string both = ex::file_text(tree, constants) + ex::file_text(terrain, constants);
    const std::string dir = std::string(KRS_BINARY_DIR) + "/glsl-check";
    std::system(("mkdir -p \"" + dir + "\"").c_str());
    validate_with_glslang(dir + "/tree_and_terrain.frag", "#version 330 core\n" + both + wrapper_main("krs_terrain"));
    // Pasted into a shader that already has globals named like the scenes: every name the snippets
    // declare carries the krs_ prefix, so nothing is redefined or hidden.
    validate_with_glslang(dir + "/tree_and_terrain_in_a_user_shader.frag",
                          "#version 330 core\nuniform float terrain;\nfloat tree(vec3 p) { return p.x - terrain; }\n" +
                              both + "out vec4 color;\nvoid main() { color = vec4(tree(vec3(1.0)) + krs_tree(vec3(1.0)) + "
                                     "krs_terrain(vec3(0.5)) + krs_terrain_locate(vec3(0.5)).dist); }\n");
    const std::vector<vec3f> tree_points = sample_points(tree, 4096), terrain_points = sample_points(terrain, 4096);
    const parity t = compare(tree, tree_points, run_points(both, "krs_tree", tree_points, {}, false, "krs_tree_data"));
    const parity g =
        compare(terrain, terrain_points, run_points(both, "krs_terrain", terrain_points, {}, false, "krs_terrain_data"));
    CHECK(t.max_error <= 1e-5f * tree.extent());
    CHECK(g.max_error <= 1e-5f * terrain.extent());
}

TEST_CASE("GLSL tree scene matches the C++ field on llvmpipe")
{
    check_scene(ex::tree_scene::build());
}
TEST_CASE("GLSL forest scene matches the C++ field on llvmpipe")
{
    check_scene(ex::forest_scene::build());
}
TEST_CASE("GLSL terrain scene matches the C++ field on llvmpipe")
{
    check_scene(ex::terrain_scene::build());
}
TEST_CASE("GLSL sponge scene matches the C++ field on llvmpipe")
{
    check_scene(ex::sponge_scene::build());
}
TEST_CASE("GLSL rock and grass scenes match the C++ field on llvmpipe")
{
    check_scene(ex::rock_scene::build());
    check_scene(ex::grass_scene::build());
}

TEST_CASE("GLSL axis mirrors and a union with a twist warp match the C++ field on llvmpipe")
{
    // An axis-aligned KRS (a grid of capsules, spheres and tilted rings).
    krs::axis_sequence<krs::capsule, krs::sphere, krs::torus>::builder b;
    b.kernel(krs::capsule({0.1f, 0.0f, 0.1f}, {0.2f, 0.6f, 0.15f}, 0.05f));
    b.kernel(krs::sphere({0.2f, 0.7f, 0.1f}, 0.08f));
    b.kernel(krs::torus({0.15f, 0.3f, 0.12f}, {0.3f, 1.0f, -0.2f}, 0.12f, 0.03f));
    b.mirror(krs::axis_mirror(0, 0.35f));
    b.mirror(krs::axis_mirror(2, 0.4f, false));
    b.mirror(krs::axis_mirror(0, 0.9f));
    b.mirror(krs::axis_mirror(1, 1.0f));
    const auto grid = b.build();
    const ex::scene<decltype(grid)> s{"grid", grid, krs::pinhole_camera({0, 0, -5}, {0, 0, 0}, {0, 1, 0}, 50.0f, 64, 48), {}, {0.8f, 1.0f, 0.4f}, {1.2f, 1.2f, 1.2f}};
    check_scene(s);

    // The torus kernel's GLSL normal (shading uses it; the distances above do not), through the
    // location slot: kernel_point carries the normal.
    {
        const krs::torus ring({0.15f, 0.3f, 0.12f}, {0.3f, 1.0f, -0.2f}, 0.12f, 0.03f);
        krs::glsl::emitter te({krs::glsl::target::glsl450, krs::glsl::data_mode::constants, "ring_data", 0});
        te.add(grid, "ring_scene"); // brings krs_torus_* and krs_location
        const std::array<float, 12> c = ring.glsl_parameters();
        const auto v4 = [&](int i) {
            return "vec4(" + krs::glsl::float_literal(c[4 * i]) + ", " + krs::glsl::float_literal(c[4 * i + 1]) + ", " +
                   krs::glsl::float_literal(c[4 * i + 2]) + ", " + krs::glsl::float_literal(c[4 * i + 3]) + ")";
        };
        const std::string args = "p, " + v4(0) + ", " + v4(1) + ", " + v4(2);
        const std::string snippet = te.source() + "float ring(vec3 p) { return krs_torus_distance(" + args + "); }\n" +
                                    "krs_location ring_locate(vec3 p) { return krs_location(0.0, krs_torus_normal(" + args +
                                    "), 0u, 0u, uvec2(0u)); }\n";
        std::vector<vec3f> points = sample_points(s, 4096);
        // And the normal's fallbacks: on the axis and on the circle.
        points.push_back(ring.center());
        points.push_back(ring.center() + ring.axis() * 0.5f);
        const auto gpu = run_points(snippet, "ring", points, {}, false, "ring_data");
        float worst_d = 0, worst_n = 0;
        for (std::size_t i = 0; i < points.size(); ++i) {
            worst_d = std::max(worst_d, std::abs(gpu[i].distance - ring.distance(points[i])));
            worst_n = std::max(worst_n, krs::length(gpu[i].kernel_point - ring.normal(points[i])));
        }
        std::printf("torus kernel: max |d_gpu - d_cpu| %.3g, max |n_gpu - n_cpu| %.3g\n", double(worst_d), double(worst_n));
        CHECK(worst_d <= 1e-6f);
        CHECK(worst_n <= 1e-4f);
    }

    // union_of(lipschitz_warp(sequence, twist), box) through the compute path (distance only).
    const auto tree = ex::tree_scene::build();
    using warped = krs::lipschitz_warp<krs::model::tree_sequence, krs::twist_warp>;
    const krs::union_of<warped, krs::box> scene(warped(tree.field, krs::twist_warp(0.2f, 8.0f)),
                                                krs::box({2.0f, 0.5f, 0.0f}, {0.4f, 0.5f, 0.3f}));
    krs::glsl::emitter e({krs::glsl::target::glsl450, krs::glsl::data_mode::constants, "scene_data", 0});
    const std::string fn = e.add(scene, "scene");
    // The union has no locate of its own: give the compute wrapper one that reports nothing.
    const std::string snippet =
        e.source() + "krs_location " + fn + "_locate(vec3 p) { return krs_location(0.0, p, 0u, 0u, uvec2(0u)); }\n";
    const std::vector<vec3f> points = sample_points(tree, 16384);
    const auto gpu = run_points(snippet, fn, points, {}, false, fn + "_data");
    float worst = 0;
    for (std::size_t i = 0; i < points.size(); ++i) worst = std::max(worst, std::abs(gpu[i].distance - scene.distance(points[i])));
    std::printf("union(twisted tree, box) max |d_gpu - d_cpu| %.3g (extent %.3g)\n", double(worst), double(tree.extent()));
    CHECK(worst <= 1e-5f * tree.extent());
}

TEST_CASE("GLSL buffer mode animates a sequence without recompiling")
{
    // The same code, the data of a sequence with moved mirrors: the GPU follows the new data.
    const auto sponge = ex::sponge_scene::build();
    krs::glsl::emitter e({krs::glsl::target::glsl450, krs::glsl::data_mode::buffer, "sponge_data", 0});
    const std::string fn = e.add(sponge.field, "sponge");
    krs::model::sponge_sequence::builder b;
    for (std::size_t i = 0; i <= sponge.field.mirror_count(); ++i) {
        if (i > 0) {
            const krs::mirror& m = sponge.field.mirrors()[i - 1];
            b.mirror(krs::mirror(m.normal, m.offset + 0.01f * float(i % 3)));
        }
        for (std::uint32_t k = sponge.field.level_begin(i); k < sponge.field.level_begin(i + 1); ++k)
            b.kernel(std::get<krs::box>(sponge.field.kernels()[k]));
    }
    const auto moved = b.build();
    const ex::scene<krs::model::sponge_sequence> s{"sponge", moved, krs::pinhole_camera({0, 0, -5}, {0, 0, 0}, {0, 1, 0}, 50.0f, 64, 48), {}, sponge.sample_center, sponge.sample_half};
    const std::vector<vec3f> points = sample_points(s, 16384);
    const auto gpu = run_points(e.source(), fn, points, krs::glsl::pack(moved, "sponge"), false, fn + "_data");
    const parity r = compare(s, points, gpu);
    CHECK(r.max_error <= 1e-5f * s.extent());
    CHECK(r.bits_equal == r.points - r.near_mirror);
}

TEST_CASE("Every Shadertoy program in glsl/ on llvmpipe matches its CPU reference")
{
    int programs = 0;
    ex::for_each_scene([&](const auto& s) {
        check_frame(s);
        ++programs;
    });
    CHECK(programs == int(ex::scene_count));
}

TEST_CASE("Shadertoy programs orbit with iTime and iMouse as pinhole_camera::turned says")
{
    // A quarter turn of the orbit and the pointer right and up (raising the eye), for a sequence and a field: the
    // GPU frame against the CPU reference seen through the turned camera, and far from the
    // frame at rest (the camera moved).
    constexpr int width = 160, height = 120;
    const auto check = [&](const auto& s) {
        const std::string text = ex::file_text(s, ex::shadertoy_file);
        const float time = 0.25f * s.camera.orbit().seconds;
        const std::array<float, 4> mouse{0.7f * width, 0.75f * height, 0.0f, 0.0f}; // right and up
        for (const auto& [t, m] : {std::pair{time, std::array<float, 4>{}}, std::pair{0.0f, mouse}}) {
            const krs::pinhole_camera moved = s.camera.with_size(width, height).turned(t, m[0], m[1]);
            const std::vector<float> gpu = render_gpu(text, width, height, t, m);
            const frame_match turned = match(gpu, ex::reference_frame(s, moved, width, height));
            const frame_match rest = match(gpu, ex::reference_frame(s, s.camera, width, height));
            std::printf("%-16s iTime %g, iMouse (%g, %g): %.3f%% of pixels within 2/255 of the turned reference "
                        "(%.3f%% exact, max %.4g), %.3f%% of the one at rest\n",
                        s.name.c_str(), double(t), double(m[0]), double(m[1]), turned.close_percent(),
                        turned.exact_percent(), double(turned.worst), rest.close_percent());
            INFO(s.name << " iTime " << t << " iMouse " << m[0] << ", " << m[1]);
            CHECK(turned.close == turned.pixels);
            CHECK(double(rest.pixels - rest.close) >= 0.1 * double(rest.pixels));
            // A quarter turn about the vertical through the pivot keeps the eye's height along the
            // vertical and its distance from the pivot, and turns its horizontal part square.
            if (t != 0.0f) {
                const vec3f up = s.camera.vertical();
                const vec3f before = s.camera.eye() - s.camera.pivot(), after = moved.eye() - s.camera.pivot();
                const float radius = krs::length(before);
                CHECK(std::abs(krs::dot(after, up) - krs::dot(before, up)) <= 1e-5f * radius);
                CHECK(krs::length(after) == doctest::Approx(radius).epsilon(1e-5));
                const vec3f level_before = before - up * krs::dot(before, up), level_after = after - up * krs::dot(after, up);
                CHECK(std::abs(krs::dot(level_before, level_after)) <= 1e-4f * radius * radius);
            }
        }
    };
    check(ex::tree_scene::build());
    check(ex::kifs_menger_scene::build());
    check(ex::lotus_scene::build()); // vertical z: the orbit about the lotus axis
}

// ---- fractal fields (krs/fractal) ---------------------------------------------------------------

namespace {

// The fractal presets, each with the box the tests sample (center 0, these half extents).
template <class F>
struct fractal_case {
    std::string name;
    F field;
    vec3f sample_half;
    float extent() const { return krs::length(sample_half); }
};

template <class Fn>
void for_each_kifs_preset(Fn&& fn)
{
    fn(fractal_case<krs::square_fractal>{"square", krs::make_square_fractal(5), {3.2f, 3.2f, 0.6f}});
    fn(fractal_case<krs::cube_fractal>{"cube", krs::make_cube_fractal(4), {3.2f, 3.2f, 3.2f}});
    fn(fractal_case<krs::menger_sponge>{"menger", krs::make_menger_sponge(4), {1.3f, 1.3f, 1.3f}});
    fn(fractal_case<krs::sierpinski_tetrahedron>{"sierpinski", krs::make_sierpinski_tetrahedron(8), {1.3f, 1.3f, 1.3f}});
    fn(fractal_case<krs::koch_curve>{"koch", krs::make_koch_curve(5, 0.004f), {1.3f, 0.6f, 0.2f}});
}

struct shell_case_options {
    const char* label;
    krs::shell_options options;
};
const shell_case_options shell_variants[] = {
    {"adjacent_shells", {krs::shell_seams::adjacent_shells, 0.02f, 1.0f}},
    {"none", {krs::shell_seams::none, 0.02f, 1.0f}},
    {"hidden_boundary", {krs::shell_seams::hidden_boundary, 0.02f, 1.0f}},
    {"adjacent_shells, step_factor 0.7", {krs::shell_seams::adjacent_shells, 0.02f, 0.7f}},
    {"hidden_boundary, step_factor 0.5 within seam_band 0.06", {krs::shell_seams::hidden_boundary, 0.05f, 0.5f, 0.06f}},
    {"adjacent_shells, step_factor 0.5 within seam_band 0.06", {krs::shell_seams::adjacent_shells, 0.02f, 0.5f, 0.06f}},
    {"none, step_factor 0.5 within seam_band 0.06", {krs::shell_seams::none, 0.02f, 0.5f, 0.06f}},
};

template <class Fn>
void for_each_log_spherical_preset(Fn&& fn)
{
    for (const shell_case_options& v : shell_variants) {
        fn("lotus", v.label, krs::make_recursive_lotus(1.0f, 8, v.options));
        fn("cube_singularity", v.label, krs::make_cube_singularity(1.0f, v.options));
    }
}

std::string fractal_main(const std::string& name)
{
    return "out vec4 krs_out;\nvoid main() { krs_out = vec4(" + name + "(vec3(0.5, 0.25, 0.125)), 0.0, 0.0, 1.0); }\n";
}

template <class F>
int validate_fractal(const std::string& dir, const std::string& name, const F& field)
{
    int files = 0;
    for (const auto t : {krs::glsl::target::glsl330, krs::glsl::target::glsl450, krs::glsl::target::es300})
        for (const auto m : {krs::glsl::data_mode::constants, krs::glsl::data_mode::buffer}) {
            krs::glsl::emitter e({t, m, name + "_data", 0});
            const std::string fn = e.add(field, name);
            validate_with_glslang(dir + "/" + name + "." + std::string(krs::glsl::target_name(t)) +
                         (m == krs::glsl::data_mode::buffer ? ".buffer" : ".constants") + ".frag",
                     e.source(true) + fractal_main(fn));
            ++files;
        }
    return files;
}

// Runs NAME(p) alone (the compute wrapper also calls NAME_locate: a stub reports nothing).
template <class F>
std::vector<float> gpu_distances(const F& field, const std::string& name, const std::vector<vec3f>& points,
                                 krs::glsl::data_mode mode)
{
    krs::glsl::emitter e({krs::glsl::target::glsl450, mode, name + "_data", 0});
    const std::string fn = e.add(field, name);
    const bool buffer = mode == krs::glsl::data_mode::buffer;
    std::vector<float> data;
    if (buffer) data = krs::glsl::pack(field, name);
    const std::string snippet = e.source() + "krs_location " + fn +
                                "_locate(vec3 p) { return krs_location(0.0, p, 0u, 0u, uvec2(0u)); }\n";
    const auto gpu = run_points(snippet, fn, points, data, false, fn + "_data");
    std::vector<float> d(points.size());
    for (std::size_t i = 0; i < points.size(); ++i) d[i] = gpu[i].distance;
    return d;
}

// Points with radii log-uniform in [1e-3, 1e2] and uniform directions. (Kept out of line: the
// float rounding of each coordinate must happen, GCC 12 may fold (double)(float)x otherwise.)
[[gnu::noinline]] float to_float(double x)
{
    return float(x);
}
std::vector<vec3f> log_radial_points(std::size_t count)
{
    std::mt19937 random(4242);
    std::normal_distribution<double> g(0.0, 1.0);
    std::uniform_real_distribution<double> u(std::log(1e-3), std::log(1e2));
    std::vector<vec3f> points(count);
    for (vec3f& p : points) {
        double x = 0, y = 0, z = 0, n = 0;
        while (n < 1e-6) {
            x = g(random), y = g(random), z = g(random);
            n = std::sqrt(x * x + y * y + z * z);
        }
        const double r = std::exp(u(random)) / n;
        p = {to_float(x * r), to_float(y * r), to_float(z * r)};
    }
    return points;
}

} // namespace

TEST_CASE("glslangValidator accepts every fractal preset for every target")
{
    REQUIRE(std::system("\"" KRS_GLSLANG_VALIDATOR "\" --version > /dev/null 2>&1") == 0);
    const std::string dir = std::string(KRS_BINARY_DIR) + "/glsl-check";
    std::system(("mkdir -p \"" + dir + "\"").c_str());
    int files = 0;
    for_each_kifs_preset([&](const auto& c) { files += validate_fractal(dir, c.name, c.field); });
    // Every KIFS step kind and both taps: a rotate and a translate step in one program too.
    const krs_test::spiral_kifs spiral = krs_test::spiral();
    files += validate_fractal(dir, "spiral", spiral);
    for_each_log_spherical_preset([&](const std::string& name, const char* label, const auto& f) {
        std::string id = name + "_" + label;
        for (char& ch : id)
            if (ch == ' ' || ch == ',' || ch == '.') ch = '_';
        for (std::size_t at = id.find("__"); at != std::string::npos; at = id.find("__")) id.erase(at, 1);
        files += validate_fractal(dir, id, f);
    });
    files += validate_fractal(dir, "log_polar",
                              krs::log_polar_tiling<krs::sphere>(krs::sphere({0.0f, 0.0f, 0.0f}, 0.3f), 12, 0.3f));
    files += validate_fractal(dir, "log_spherical",
                              krs::log_spherical_tiling<krs::box>(krs::box({0.0f, 0.0f, 0.0f}, {0.3f, 0.2f, 0.2f}), 16));
    std::printf("glslangValidator: %d fractal shaders checked\n", files);
}

TEST_CASE("GLSL KIFS presets match the C++ field on llvmpipe")
{
    for_each_kifs_preset([&](const auto& c) {
        std::mt19937_64 random(777);
        const auto u = [](std::mt19937_64& e) { return float(krs_test::uniform(e, -1, 1)); };
        std::vector<vec3f> points(16384);
        for (vec3f& p : points) p = {u(random) * c.sample_half.x, u(random) * c.sample_half.y, u(random) * c.sample_half.z};
        for (const auto mode : {krs::glsl::data_mode::constants, krs::glsl::data_mode::buffer}) {
            const std::vector<float> gpu = gpu_distances(c.field, c.name, points, mode);
            float worst = 0;
            std::size_t exact = 0;
            for (std::size_t i = 0; i < points.size(); ++i) {
                const float d = c.field.distance(points[i]);
                worst = std::max(worst, std::abs(gpu[i] - d));
                exact += gpu[i] == d;
            }
            std::printf("%-10s %-9s points %zu  max |d_gpu - d_cpu| %.3g = %.3g of extent %.3g  bit-equal %zu\n",
                        c.name.c_str(), mode == krs::glsl::data_mode::buffer ? "buffer" : "constants", points.size(),
                        double(worst), double(worst / c.extent()), double(c.extent()), exact);
            INFO(c.name);
            CHECK(worst <= 1e-5f * c.extent());
        }
    });
}

TEST_CASE("GLSL log-spherical presets match the C++ field on llvmpipe")
{
    // The field scales with r, so the error is relative: |d_gpu - d_cpu| / max(|d_cpu|, 1e-3 r),
    // r = |p| log-uniform in [1e-3, 1e2]. Seams: with seams::none the field jumps across a shell
    // boundary, and the GPU's log (~5e-7 off) may pick the neighbouring shell within ~1e-6 of it;
    // points within 1e-5 (relative in r) of a boundary are counted and, for that mode only, left out.
    const std::vector<vec3f> points = log_radial_points(16384);
    for_each_log_spherical_preset([&](const std::string& name, const char* label, const auto& f) {
        const std::vector<float> gpu = gpu_distances(f, name, points, krs::glsl::data_mode::buffer);
        const bool jumps = f.options().seams != krs::shell_seams::adjacent_shells;
        double worst = 0;
        std::size_t near_seam = 0, exact = 0, compared = 0;
        for (std::size_t i = 0; i < points.size(); ++i) {
            const double r = double(krs::length(points[i]));
            const double t = std::log(r) * double(f.density());
            if (std::abs(t - std::round(t)) < 1e-5 * double(f.density())) {
                ++near_seam;
                if (jumps) continue;
            }
            const float d = f.distance(points[i]);
            const double e = std::abs(double(gpu[i]) - double(d)) / std::max(std::abs(double(d)), 1e-3 * r);
            worst = std::max(worst, e);
            exact += gpu[i] == d;
            ++compared;
        }
        std::printf("%-16s %-32s points %zu  max |d_gpu - d_cpu| / max(|d|, 1e-3 r) %.3g  bit-equal %zu/%zu  "
                    "within 1e-5 of a seam %zu%s\n",
                    name.c_str(), label, points.size(), worst, exact, compared, near_seam,
                    jumps ? " (not compared)" : " (compared)");
        INFO(name << " " << label);
        CHECK(worst <= 1e-5);
        CHECK(near_seam <= points.size() / 100);
    });
}

TEST_CASE("GLSL field scenes (not sequences) match the C++ field on llvmpipe")
{
    // The sequences' distances, locate and shade are checked above (check_scene); here the other
    // example scenes, in both data modes, at points of the box the scene's tests sample. The
    // log-spherical shells scale with r = |p|, so their error is relative, as for the presets
    // above: |d_gpu - d_cpu| / max(|d_cpu|, 1e-3 r).
    int scenes = 0;
    ex::for_each_scene([&](const auto& s) {
        using F = std::remove_cvref_t<decltype(s.field)>;
        if constexpr (!krs::glsl::kernel_shaded<F>) {
            ++scenes;
            constexpr bool shell = std::is_same_v<F, krs::recursive_lotus> || std::is_same_v<F, krs::cube_singularity>;
            const std::vector<vec3f> points = sample_points(s, 16384);
            for (const auto mode : {krs::glsl::data_mode::constants, krs::glsl::data_mode::buffer}) {
                const std::vector<float> gpu = gpu_distances(s.field, s.name, points, mode);
                double worst = 0;
                std::size_t exact = 0;
                for (std::size_t i = 0; i < points.size(); ++i) {
                    const float d = s.field.distance(points[i]);
                    const double e = std::abs(double(gpu[i]) - double(d));
                    worst = std::max(worst, shell ? e / std::max(std::abs(double(d)), 1e-3 * double(krs::length(points[i])))
                                                  : e / double(s.extent()));
                    exact += gpu[i] == d;
                }
                std::printf("%-16s %-9s points %zu  max |d_gpu - d_cpu| %s %.3g  bit-equal %zu\n", s.name.c_str(),
                            mode == krs::glsl::data_mode::buffer ? "buffer" : "constants", points.size(),
                            shell ? "/ max(|d|, 1e-3 r)" : "/ extent", worst, exact);
                INFO(s.name);
                CHECK(worst <= 1e-5);
            }
        }
    });
    CHECK(scenes == 9); // coral, the mirrors, the five KIFS presets, the lotus and the cube singularity
}

// ---- KIFS colouring (krs/fractal/kifs_colour.hpp) --------------------------------------------

namespace {

// Runs the emitted `krs_kifs_colour NAME(vec3 p)` over the points in a compute shader: trap.xyzw,
// escape_iteration, fold_count, last_fold per point.
std::vector<std::array<float, 7>> gpu_colours(const std::string& snippet, const std::string& name,
                                              const std::vector<vec3f>& points, const std::vector<float>& data)
{
    const std::string body = "    krs_kifs_colour c = " + name + "(p);\n"
                             "    results[krs_n * i] = c.trap.x;\n    results[krs_n * i + 1u] = c.trap.y;\n"
                             "    results[krs_n * i + 2u] = c.trap.z;\n    results[krs_n * i + 3u] = c.trap.w;\n"
                             "    results[krs_n * i + 4u] = c.escape_iteration;\n    results[krs_n * i + 5u] = c.fold_count;\n"
                             "    results[krs_n * i + 6u] = c.last_fold;\n";
    const std::vector<float> raw = run_point_program(snippet, body, 7, points, data, false, "");
    std::vector<std::array<float, 7>> results(points.size());
    std::memcpy(results.data(), raw.data(), raw.size() * sizeof(float));
    return results;
}

krs::kifs_colouring gpu_test_traps()
{
    return {{krs::orbit_trap::point({0.25f, -0.5f, 0.125f}), krs::orbit_trap::plane({1, 2, -0.5f}, 0.3f),
             krs::orbit_trap::line({0.1f, 0.2f, 0.0f}, {0.3f, -1, 0.7f}), krs::orbit_trap::shell({0, 0, 0}, 1.5f)},
            6.0f};
}

} // namespace

TEST_CASE("GLSL KIFS colouring matches kifs_colour on llvmpipe")
{
    // The orbit points are the C++'s bit for bit where the steps' GLSL is (+ - * / exact on
    // llvmpipe, no FMA): the counts must agree except where a fold's output is within an ulp of its
    // input, and the traps to GLSL's length (1-2 ulp) of the orbit's magnitude.
    const std::string dir = std::string(KRS_BINARY_DIR) + "/glsl-check";
    std::system(("mkdir -p \"" + dir + "\"").c_str());
    for_each_kifs_preset([&](const auto& c) {
        const krs::kifs_colour_glsl request{c.field, gpu_test_traps()};
        for (const auto t : {krs::glsl::target::glsl330, krs::glsl::target::glsl450, krs::glsl::target::es300}) {
            krs::glsl::emitter e({t, krs::glsl::data_mode::constants, c.name + "_data", 0});
            const std::string fn = e.add_shading(request, c.name + "_colour");
            validate_with_glslang(dir + "/" + c.name + "_colour." + std::string(krs::glsl::target_name(t)) + ".frag",
                                  e.source(true) + "out vec4 krs_out;\nvoid main() { krs_kifs_colour c = " + fn +
                                      "(vec3(0.5, 0.25, 0.125)); krs_out = c.trap + vec4(c.fold_count); }\n");
        }
        krs::glsl::emitter e({krs::glsl::target::glsl450, krs::glsl::data_mode::buffer, c.name + "_data", 0});
        const std::string fn = e.add_shading(request, c.name + "_colour");
        std::mt19937_64 random(31);
        const auto u = [](std::mt19937_64& e) { return float(krs_test::uniform(e, -1, 1)); };
        std::vector<vec3f> points(16384);
        for (vec3f& p : points) p = {u(random) * c.sample_half.x, u(random) * c.sample_half.y, u(random) * c.sample_half.z};
        const auto gpu = gpu_colours(e.source(), fn, points, e.data());
        // With the distance in the same shader, the colouring reads the steps' parameters the
        // distance put in the data (appended once): the data is the distance's plus the traps',
        // and the colours are the same bit for bit.
        krs::glsl::emitter both({krs::glsl::target::glsl450, krs::glsl::data_mode::buffer, c.name + "_data", 0});
        (void)both.add(c.field, c.name);
        const std::size_t distance_floats = both.data().size();
        const std::string both_fn = both.add_shading(request, c.name + "_colour");
        CHECK(both.data().size() == distance_floats + request.colouring.trap_count() * 4 * krs::glsl::vec4s_of<krs::orbit_trap>);
        CHECK(gpu_colours(both.source(), both_fn, points, both.data()) == gpu);
        double worst_trap = 0;
        std::size_t counts_equal = 0, traps_bit_equal = 0, stayed = 0;
        for (std::size_t i = 0; i < points.size(); ++i) {
            const krs::kifs_colour_result<float> cpu = krs::kifs_colour(c.field, points[i], request.colouring);
            counts_equal += gpu[i][4] == cpu.escape_iteration && gpu[i][5] == cpu.fold_count && gpu[i][6] == cpu.last_fold;
            stayed += cpu.escape_iteration == float(c.field.iterations() + 1);
            bool bits = true;
            for (std::size_t k = 0; k < 4; ++k) {
                worst_trap = std::max(worst_trap, std::abs(double(gpu[i][k]) - double(cpu.trap[k])) / 7.0); // 1 + R
                bits = bits && gpu[i][k] == cpu.trap[k];
            }
            traps_bit_equal += bits;
        }
        std::printf("%-10s colour points %zu  counts equal %zu  traps bit-equal %zu  max |trap_gpu - trap_cpu| / (1 + R) "
                    "%.3g  (orbits that stayed %zu)\n",
                    c.name.c_str(), points.size(), counts_equal, traps_bit_equal, worst_trap, stayed);
        INFO(c.name);
        CHECK(double(counts_equal) >= 0.999 * double(points.size()));
        CHECK(worst_trap <= 1e-6);
    });
}

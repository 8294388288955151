// The hypertree raymarcher emitted as GLSL (hypertree/render/glsl.hpp), run on Mesa llvmpipe
// through headless EGL (docs/design.md#glsl-on-the-cpu) and compared with the CPU marcher: the packed texture
// against the store voxel by voxel, and whole frames against hypertree::render.
//
// Built as its own executable (hypertree_glsl_tests) because it links EGL and OpenGL; CMake option
// KRS_GLSL_TESTS=OFF leaves it out. A context that cannot be created FAILS the test.
//
// Rays: the CPU computes each pixel's camera ray (krs::pinhole_camera::primary_ray at the pixel
// center, as render does) and the shader reads them from a storage buffer, so both marchers start
// from the same floats and the comparison is of the march alone.

#include "hypertree/hypertree.hpp"
#include "hypertree/presets.hpp"
#include "hypertree/render/glsl.hpp"

#include "support/gl_context.hpp"

#include <doctest/doctest.h>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <fstream>
#include <stdexcept>
#include <string>
#include <vector>

using namespace hypertree;

namespace {

using krs_test::buffer, krs_test::compile, krs_test::link, krs_test::require_context, krs_test::validate_with_glslang;





// The upload glsl.hpp documents: RG8UI, unpack alignment 1, nearest filtering, on texture unit 0
// (the sampler uniform's default).
GLuint upload(const packed_volume& v)
{
    GLuint texture = 0;
    glGenTextures(1, &texture);
    glActiveTexture(GL_TEXTURE0);
    glBindTexture(GL_TEXTURE_3D, texture);
    glTexParameteri(GL_TEXTURE_3D, GL_TEXTURE_MIN_FILTER, GL_NEAREST);
    glTexParameteri(GL_TEXTURE_3D, GL_TEXTURE_MAG_FILTER, GL_NEAREST);
    glPixelStorei(GL_UNPACK_ALIGNMENT, 1);
    glTexImage3D(GL_TEXTURE_3D, 0, GL_RG8UI, v.width, v.height, v.depth, 0, GL_RG_INTEGER, GL_UNSIGNED_BYTE, v.texels.data());
    REQUIRE(glGetError() == GL_NO_ERROR);
    return texture;
}


// A small tree (preset D at resolution 40, 30000 iterations): the shape from a partitioned store
// (one sphere and one flow per first-level part), the voxels copied into a dense store for the
// CPU marcher and pack_volume (any store gives the same voxels).
struct small_tree {
    partitioned_store parts;
    dense_store dense;
    tree_shape shape;
    depth_colors colors = depth_colors::tree(3, 6);
    small_tree() : parts(build_tree<partitioned_store>(definition(), 2)), dense(dense_store::build(parts.volume(), stored_voxels(parts)))
    {
        shape = tree_shape::of(parts);
    }
    static ifs<> definition()
    {
        auto t = presets::tree_d(40);
        t.iterations = 30000;
        return t;
    }
};

const small_tree& tree()
{
    static const small_tree t;
    return t;
}

// Options the second frame uses: every branch of the shader that the defaults leave out.
march_options varied_options()
{
    march_options o;
    o.step_factor = 0.7f;
    o.density_scale = 1.5f;
    o.use_spheres = true;
    o.shade_per_voxel = false;
    o.specular = 0.35f;
    o.shininess = 16.0f;
    o.lights = {directional_light{{0.4f, 0.8f, 0.45f}, {1.0f, 0.97f, 0.9f}},
                directional_light{{-0.7f, 0.3f, -0.2f}, {0.25f, 0.3f, 0.45f}}};
    return o;
}

const krs::pinhole_camera& camera()
{
    static const krs::pinhole_camera c({0.7f, 0.9f, 1.9f}, {0, 0.6f, 0}, {0, 1, 0}, 40, 64, 64);
    return c;
}

// Renders march_<name> through the fragment path: one ray per pixel from `rays` (6 floats per
// pixel, image order from the top-left), composited over the background as render does. Returns
// RGB floats from the top-left, as hypertree::image.
std::vector<float> render_gpu(const std::string& snippet, const packed_volume& volume, const std::vector<float>& rays,
                              int width, int height, const rgb& background)
{
    require_context();
    const std::string fragment = "#version 430 core\n" + snippet +
                                 "layout(std430, binding = 0) readonly buffer rays_block { float rays[]; };\n"
                                 "uniform int width;\nuniform int height;\nuniform vec3 background;\n"
                                 "out vec4 frag_color;\n"
                                 "void main() {\n"
                                 "    int x = int(gl_FragCoord.x), y = height - 1 - int(gl_FragCoord.y);\n"
                                 "    int i = 6 * (x + width * y);\n"
                                 "    vec4 m = march_hypertree(vec3(rays[i], rays[i + 1], rays[i + 2]),\n"
                                 "                             vec3(rays[i + 3], rays[i + 4], rays[i + 5]));\n"
                                 "    frag_color = vec4(m.rgb + m.a * background, 1.0);\n"
                                 "}\n";
    const GLuint program = link({compile(GL_VERTEX_SHADER, krs_test::fullscreen_vertex_shader), compile(GL_FRAGMENT_SHADER, fragment)});
    const GLuint texture = upload(volume);
    const GLuint ray_buffer = buffer(GL_SHADER_STORAGE_BUFFER, rays.data(), rays.size() * sizeof(float), GL_STATIC_DRAW);
    glBindBufferBase(GL_SHADER_STORAGE_BUFFER, 0, ray_buffer);
    const std::vector<float> pixels = krs_test::draw_fullscreen(program, width, height, [&] {
        glUniform1i(glGetUniformLocation(program, "width"), width);
        glUniform1i(glGetUniformLocation(program, "height"), height);
        glUniform3f(glGetUniformLocation(program, "background"), background.r, background.g, background.b);
    });
    glDeleteBuffers(1, &ray_buffer);
    glDeleteTextures(1, &texture);
    glDeleteProgram(program);
    // glReadPixels rows are bottom-up.
    std::vector<float> out(std::size_t(width) * std::size_t(height) * 3);
    for (int y = 0; y < height; ++y)
        for (int x = 0; x < width; ++x)
            for (int c = 0; c < 3; ++c)
                out[(std::size_t(y) * std::size_t(width) + std::size_t(x)) * 3 + std::size_t(c)] =
                    pixels[(std::size_t(height - 1 - y) * std::size_t(width) + std::size_t(x)) * 4 + std::size_t(c)];
    return out;
}

struct frame_agreement {
    std::size_t pixels = 0, within = 0, covered = 0, exact = 0;
    float worst = 0;      // largest |gpu - cpu| of a channel, unclamped floats
    int worst_levels = 0; // largest difference of a channel in 8-bit levels
};

// CPU and GPU frames of one set of options; the images are compared after clamping to [0, 1] and
// quantizing to 8 bits, as an image file would hold them.
frame_agreement compare_frames(const march_options& options, const char* label)
{
    const small_tree& t = tree();
    const krs::pinhole_camera& cam = camera();
    const int w = cam.width(), h = cam.height();
    const volume_marcher<dense_store> marcher(t.dense, t.shape, t.colors, options);
    render_settings settings;
    const auto c0 = std::chrono::steady_clock::now();
    const image cpu = render<float>(marcher, cam, settings);
    const auto c1 = std::chrono::steady_clock::now();
    std::vector<float> rays;
    rays.reserve(std::size_t(w) * std::size_t(h) * 6);
    for (int y = 0; y < h; ++y)
        for (int x = 0; x < w; ++x) {
            const krs::ray<float> r = cam.primary_ray(float(x) + 0.5f, float(y) + 0.5f);
            rays.insert(rays.end(), {r.origin.x, r.origin.y, r.origin.z, r.direction.x, r.direction.y, r.direction.z});
        }
    const packed_volume volume = pack_volume(t.dense);
    const std::string code = hypertree_glsl(t.dense, t.shape, t.colors, options);
    const std::vector<float> gpu = render_gpu(code, volume, rays, w, h, settings.background);
    const auto c2 = std::chrono::steady_clock::now();
    frame_agreement a;
    a.pixels = std::size_t(w) * std::size_t(h);
    const auto level = [](float v) { return int(std::lround(std::clamp(v, 0.0f, 1.0f) * 255.0f)); };
    for (std::size_t i = 0; i < a.pixels; ++i) {
        int levels = 0;
        bool same = true, background = true;
        for (std::size_t c = 0; c < 3; ++c) {
            const float g = gpu[3 * i + c], k = cpu.rgb[3 * i + c];
            a.worst = std::max(a.worst, std::abs(g - k));
            levels = std::max(levels, std::abs(level(g) - level(k)));
            same = same && g == k;
            const float bg = c == 0 ? settings.background.r : c == 1 ? settings.background.g : settings.background.b;
            background = background && k == bg;
        }
        a.worst_levels = std::max(a.worst_levels, levels);
        a.within += levels <= 2;
        a.exact += same;
        a.covered += !background;
    }
    std::printf("hypertree GLSL frame (%s) %dx%d: %zu/%zu pixels within 2/255 (%.2f%%), worst %d/255 (%.3g as float), "
                "%zu bit-equal, %zu pixels show the tree; CPU %.0f ms, GPU compile + render %.0f ms, %zu chars of GLSL\n",
                label, w, h, a.within, a.pixels, 100.0 * double(a.within) / double(a.pixels), a.worst_levels, double(a.worst),
                a.exact, a.covered, std::chrono::duration<double, std::milli>(c1 - c0).count(),
                std::chrono::duration<double, std::milli>(c2 - c1).count(), code.size());
    return a;
}

} // namespace

TEST_CASE("hypertree pack_volume lays out the grid as the store indexes it")
{
    const small_tree& t = tree();
    const packed_volume v = pack_volume(t.dense);
    const hypervolume& hv = t.dense.volume();
    REQUIRE(v.width == hv.grid().x);
    REQUIRE(v.height == hv.grid().y);
    REQUIRE(v.depth == hv.grid().z);
    REQUIRE(v.texels.size() == 2 * hv.voxel_count());
    int deepest = 0;
    std::size_t mismatches = 0;
    for (voxel_index i = 0; i < hv.voxel_count(); ++i) {
        const voxel x = t.dense.at(i);
        mismatches += v.texels[2 * std::size_t(i)] != x.density || v.texels[2 * std::size_t(i) + 1] != x.level;
        if (x.density) deepest = std::max(deepest, int(x.level));
    }
    CHECK(mismatches == 0);
    CHECK(v.level_count == deepest + 1);
    CHECK_THROWS_AS(pack_volume(t.dense, memory_budget{1000}), invalid_parameter);
}

TEST_CASE("hypertree GLSL reads back every voxel of the texture at its cell")
{
    // A compute shader asks <name>_cell for each voxel's center and <name>_voxel for what the
    // texture holds there: the GPU's mapping and texel layout against the store's index order.
    const small_tree& t = tree();
    const hypervolume& hv = t.dense.volume();
    march_options o;
    o.use_spheres = false; // every cell, empty or not, must map
    const std::string code = hypertree_glsl(t.dense, t.shape, t.colors, o);
    require_context();
    const std::string text = "#version 430 core\nlayout(local_size_x = 64) in;\n" + code +
                             "layout(std430, binding = 1) readonly buffer points_block { float points[]; };\n"
                             "layout(std430, binding = 2) writeonly buffer results_block { uint results[]; };\n"
                             "uniform uint count;\n"
                             "void main() {\n"
                             "    uint i = gl_GlobalInvocationID.x;\n"
                             "    if (i >= count) return;\n"
                             "    ivec3 cell;\n"
                             "    bool inside = hypertree_cell(vec3(points[3u * i], points[3u * i + 1u], points[3u * i + 2u]), cell);\n"
                             "    uvec2 v = hypertree_voxel(cell);\n"
                             "    results[i] = inside ? uint(cell.x + hypertree_grid.x * (cell.y + hypertree_grid.y * cell.z)) | "
                             "(v.x << 20u) | (v.y << 28u) : 0xffffffffu;\n"
                             "}\n";
    const GLuint program = link({compile(GL_COMPUTE_SHADER, text)});
    const packed_volume volume = pack_volume(t.dense);
    REQUIRE(hv.voxel_count() < (1u << 20));
    REQUIRE(volume.level_count <= 16);
    const GLuint texture = upload(volume);
    std::vector<float> points;
    for (voxel_index i = 0; i < hv.voxel_count(); ++i) {
        const krs::vec3d c = hv.voxel_center(i);
        points.insert(points.end(), {float(c.x), float(c.y), float(c.z)});
    }
    const std::size_t count = hv.voxel_count();
    const GLuint in = buffer(GL_SHADER_STORAGE_BUFFER, points.data(), points.size() * sizeof(float), GL_STATIC_DRAW);
    const GLuint out = buffer(GL_SHADER_STORAGE_BUFFER, nullptr, count * sizeof(std::uint32_t), GL_DYNAMIC_READ);
    glBindBufferBase(GL_SHADER_STORAGE_BUFFER, 1, in);
    glBindBufferBase(GL_SHADER_STORAGE_BUFFER, 2, out);
    glUseProgram(program);
    glUniform1ui(glGetUniformLocation(program, "count"), GLuint(count));
    glDispatchCompute(GLuint((count + 63) / 64), 1, 1);
    glMemoryBarrier(GL_BUFFER_UPDATE_BARRIER_BIT | GL_SHADER_STORAGE_BARRIER_BIT);
    std::vector<std::uint32_t> results(count);
    glBindBuffer(GL_SHADER_STORAGE_BUFFER, out);
    glGetBufferSubData(GL_SHADER_STORAGE_BUFFER, 0, GLsizeiptr(count * sizeof(std::uint32_t)), results.data());
    REQUIRE(glGetError() == GL_NO_ERROR);
    const GLuint buffers[2] = {in, out};
    glDeleteBuffers(2, buffers);
    glDeleteTextures(1, &texture);
    glDeleteProgram(program);
    std::size_t wrong_cell = 0, wrong_voxel = 0, nonempty = 0;
    for (voxel_index i = 0; i < count; ++i) {
        const voxel x = t.dense.at(i);
        nonempty += x.density != 0;
        wrong_cell += (results[i] & 0xfffffu) != i;
        wrong_voxel += ((results[i] >> 20) & 0xffu) != x.density || (results[i] >> 28) != x.level;
    }
    std::printf("hypertree GLSL texture read-back: %zu voxels (%zu non-empty), %zu wrong cells, %zu wrong voxels\n", count,
                nonempty, wrong_cell, wrong_voxel);
    CHECK(nonempty > 1000);
    CHECK(wrong_cell == 0);
    CHECK(wrong_voxel == 0);
}

TEST_CASE("glslangValidator accepts the emitted hypertree volume marcher")
{
    REQUIRE(std::system("\"" KRS_GLSLANG_VALIDATOR "\" --version > /dev/null 2>&1") == 0);
    const std::string dir = std::string(KRS_BINARY_DIR) + "/glsl-check";
    std::system(("mkdir -p \"" + dir + "\"").c_str());
    const small_tree& t = tree();
    march_options no_lights;
    no_lights.lights.clear();
    march_options no_shadows;
    no_shadows.shadows = false;
    const std::pair<const char*, march_options> variants[] = {
        {"defaults", march_options{}}, {"varied", varied_options()}, {"no_lights", no_lights}, {"no_shadows", no_shadows}};
    const std::string main = "out vec4 frag_color;\n"
                             "void main() { frag_color = march_tree(vec3(0.0, 0.5, -2.0), vec3(0.0, 0.0, 1.0)); }\n";
    int files = 0;
    for (const auto& [label, options] : variants) {
        const std::string code = hypertree_glsl(t.dense, t.shape, t.colors, options, {"tree"});
        for (const char* version : {"330", "450"}) {
            validate_with_glslang(dir + "/hypertree_" + label + "." + version + ".frag",
                     std::string("#version ") + version + " core\n" + code + main);
            ++files;
        }
    }
    // With no flows or spheres (a shape of the box alone) the code has no zero-length arrays.
    tree_shape bare = t.shape;
    bare.flows.clear();
    bare.spheres.clear();
    validate_with_glslang(dir + "/hypertree_bare.330.frag", "#version 330 core\n" + hypertree_glsl(t.dense, bare, t.colors, {}, {"tree"}) + main);
    std::printf("glslangValidator: %d hypertree volume shaders checked\n", files + 1);
}

TEST_CASE("hypertree GLSL frame on llvmpipe matches the CPU marcher (default options)")
{
    const frame_agreement a = compare_frames(march_options{}, "defaults");
    CHECK(double(a.within) >= 0.99 * double(a.pixels));
    CHECK(a.covered > a.pixels / 10); // the camera sees the tree
}

TEST_CASE("hypertree GLSL frame on llvmpipe matches the CPU marcher (specular, two lights, per-sample shadows)")
{
    const frame_agreement a = compare_frames(varied_options(), "varied");
    CHECK(double(a.within) >= 0.99 * double(a.pixels));
    CHECK(a.covered > a.pixels / 10);
}

// The hypertree raymarcher emitted as GLSL (hypertree/render/glsl.hpp), run on Mesa llvmpipe
// through headless EGL (docs/design.md#glsl-on-the-cpu) and compared with the CPU marcher: the packed bricks
// against the store voxel by voxel, the emitted constants against the C++ ones, and whole frames
// against hypertree::render.
//
// Built as its own executable (hypertree_glsl_tests) because it links EGL and OpenGL; CMake option
// KRS_GLSL_TESTS=OFF leaves it out. A context that cannot be created FAILS the test.
//
// Rays: the CPU computes each pixel's camera ray (krs::pinhole_camera::primary_ray at the pixel
// center, as render does) and the shader reads them from a storage buffer, so both marchers start
// from the same floats and the comparison is of the march alone.

#include "hypertree/execution.hpp"
#include "hypertree/hypertree.hpp"
#include "hypertree/presets.hpp"
#include "hypertree/render/glsl.hpp"

#include "support/brick_walk_rays.hpp"
#include "support/gl_context.hpp"
#include "support/small_tree.hpp"

#include <doctest/doctest.h>

#include <algorithm>
#include <cctype>
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

using krs_test::buffer, krs_test::compile, krs_test::link, krs_test::require_context, krs_test::validate_spirv,
    krs_test::validate_with_glslang;

// The upload glsl.hpp documents: the words in a buffer, an R32UI buffer texture of it on texture
// unit 0 (the sampler uniform's default).
struct uploaded {
    GLuint buffer = 0, texture = 0;
    uploaded(const uploaded&) = delete; // owns the GL names: a copy would delete them twice
    uploaded& operator=(const uploaded&) = delete;
    explicit uploaded(const packed_bricks& b)
    {
        GLint most = 0;
        glGetIntegerv(GL_MAX_TEXTURE_BUFFER_SIZE, &most);
        REQUIRE(b.words.size() <= std::size_t(most));
        buffer = krs_test::buffer(GL_TEXTURE_BUFFER, b.words.data(), b.words.size() * 4, GL_STATIC_DRAW);
        glGenTextures(1, &texture);
        glActiveTexture(GL_TEXTURE0);
        glBindTexture(GL_TEXTURE_BUFFER, texture);
        glTexBuffer(GL_TEXTURE_BUFFER, GL_R32UI, buffer);
        REQUIRE(glGetError() == GL_NO_ERROR);
    }
    ~uploaded()
    {
        glDeleteTextures(1, &texture);
        glDeleteBuffers(1, &buffer);
    }
};

// The rendering tests' small tree (support/small_tree.hpp): the shape from a partitioned store
// (one sphere and one flow per first-level part), the voxels copied into a dense store for the
// CPU marcher and pack_bricks (any store gives the same voxels).
struct small_tree {
    partitioned_store parts;
    dense_store dense;
    tree_shape shape;
    depth_colors colors = depth_colors::tree(3, 6);
    small_tree() : parts(build_tree<partitioned_store>(definition(), 2)), dense(dense_store::build(parts.volume(), stored_voxels(parts)))
    {
        shape = tree_shape::of(parts);
    }
    static ifs<> definition() { return krs_test::small_tree_d(); }
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
    o.bounds_by = bound_method::spheres;
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
std::vector<float> render_gpu(const std::string& snippet, const packed_bricks& bricks, const std::vector<float>& rays,
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
                                 "    vec4 m = krs_march_hypertree(vec3(rays[i], rays[i + 1], rays[i + 2]),\n"
                                 "                                 vec3(rays[i + 3], rays[i + 4], rays[i + 5]));\n"
                                 "    frag_color = vec4(m.rgb + m.a * background, 1.0);\n"
                                 "}\n";
    const GLuint program = link({compile(GL_VERTEX_SHADER, krs_test::fullscreen_vertex_shader), compile(GL_FRAGMENT_SHADER, fragment)});
    const uploaded texture(bricks);
    const GLuint ray_buffer = buffer(GL_SHADER_STORAGE_BUFFER, rays.data(), rays.size() * sizeof(float), GL_STATIC_DRAW);
    glBindBufferBase(GL_SHADER_STORAGE_BUFFER, 0, ray_buffer);
    const std::vector<float> pixels = krs_test::draw_fullscreen(program, width, height, [&] {
        glUniform1i(glGetUniformLocation(program, "width"), width);
        glUniform1i(glGetUniformLocation(program, "height"), height);
        glUniform3f(glGetUniformLocation(program, "background"), background.r, background.g, background.b);
    });
    glDeleteBuffers(1, &ray_buffer);
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
frame_agreement compare_frames(const march_options& options, const char* label, const tree_shape* shape_override = nullptr)
{
    const small_tree& t = tree();
    const tree_shape& shape = shape_override ? *shape_override : t.shape;
    const krs::pinhole_camera& cam = camera();
    const int w = cam.width(), h = cam.height();
    // The GLSL marcher marches shadow rays (glsl.hpp); the CPU marcher is asked for the same.
    march_options by_rays = options;
    by_rays.shadow_by = march_options::shadow_method::rays;
    const volume_marcher marcher(t.dense, shape, t.colors, by_rays);
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
    // The GPU reads the very bricks this CPU marcher reads.
    const packed_bricks bricks = pack_bricks(marcher.bricks());
    const std::string code = hypertree_glsl(t.dense.volume(), bricks, shape, t.colors, options);
    const std::vector<float> gpu = render_gpu(code, bricks, rays, w, h, settings.background);
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

TEST_CASE("hypertree pack_bricks holds every voxel where glsl.hpp says the shader finds it")
{
    // Decoded here from the layout glsl.hpp documents (ranks, then density and level bytes by
    // place, low byte first), against the store voxel by voxel; an empty brick's rank is -(e + 1),
    // e the level of its empty cube (checked against the store in test_hypertree_render.cpp).
    const small_tree& t = tree();
    const packed_bricks b = pack_bricks(t.dense);
    const hypervolume& hv = t.dense.volume();
    const auto word = [&](std::size_t i) { REQUIRE(i < b.words.size()); return b.words[i]; };
    const auto byte_at = [&](std::uint32_t offset, std::int64_t place) { return (word(offset + std::size_t(place >> 2)) >> (8 * (place & 3))) & 255u; };
    REQUIRE(b.grid_bricks[0] == std::uint32_t((hv.grid().x + 3) / 4));
    REQUIRE(b.grid_bricks[2] == std::uint32_t((hv.grid().z + 3) / 4));
    int deepest = 0;
    const voxel_bricks cpu(t.dense);
    const auto cpu_ranks = cpu.brick_ranks();
    std::size_t mismatches = 0, nonempty = 0, coarse = 0;
    for (int z = 0; z < hv.grid().z; ++z)
        for (int y = 0; y < hv.grid().y; ++y)
            for (int x = 0; x < hv.grid().x; ++x) {
                const voxel v = t.dense.at(hv.index(x, y, z));
                const std::size_t brick = std::size_t(x / 4) + b.grid_bricks[0] * (std::size_t(y / 4) + b.grid_bricks[1] * std::size_t(z / 4));
                const std::int32_t rank = std::int32_t(word(b.rank_offset + brick));
                voxel got{};
                if (rank >= 0) {
                    const std::int64_t place = std::int64_t(rank) * 64 + (x % 4) + 4 * (y % 4) + 16 * (z % 4);
                    got = {std::uint8_t(byte_at(b.density_offset, place)), std::uint8_t(byte_at(b.level_offset, place))};
                } else {
                    REQUIRE(rank == cpu_ranks[brick]); // the CPU's table, word for word
                    coarse += rank <= -3; // in an empty cube of 16^3 or more
                }
                // An empty voxel's level is not kept.
                mismatches += got.density != v.density || (v.density != 0 && got.level != v.level);
                if (v.density) ++nonempty, deepest = std::max(deepest, int(v.level));
            }
    CHECK(mismatches == 0);
    CHECK(nonempty > 1000);
    CHECK(coarse > 0);
    CHECK(b.level_count == deepest + 1);
}

TEST_CASE("hypertree pack_bricks refuses each of its three limits by its own name")
{
    const small_tree& t = tree();
    const std::size_t words = pack_bricks(t.dense).words.size();
    // The memory budget: 4 bytes a word, exactly enough passes.
    CHECK_THROWS_WITH_AS(pack_bricks(t.dense, memory_budget{4 * words - 1}), doctest::Contains("pack_bricks.budget"), invalid_parameter);
    CHECK(pack_bricks(t.dense, memory_budget{4 * words}).words.size() == words);
    // The texels of a buffer texture as the caller states them (GL_MAX_TEXTURE_BUFFER_SIZE): the
    // message names the words needed.
    CHECK_THROWS_WITH_AS(pack_bricks(t.dense, {}, words - 1), doctest::Contains("pack_bricks.max_texels"), invalid_parameter);
    CHECK_THROWS_WITH_AS(pack_bricks(t.dense, {}, words - 1), doctest::Contains(doctest::String((std::to_string(words) + " words").c_str())), invalid_parameter);
    CHECK(pack_bricks(t.dense, {}, words).words.size() == words);
    // 2^31 words (the shader's int offsets) cannot be built here; the check pack_bricks runs before
    // it allocates is called with the sizes, under a budget that allows them.
    const memory_budget plenty{std::size_t(1) << 40};
    CHECK_THROWS_WITH_AS(detail::require_packable(std::size_t(1) << 31, plenty, std::size_t(-1)), doctest::Contains("pack_bricks.bricks"),
                         invalid_parameter);
    CHECK_NOTHROW(detail::require_packable((std::size_t(1) << 31) - 1, plenty, std::size_t(-1)));
    // Over the default budget (4 GiB, 2^30 words) the budget is named, not the offsets.
    CHECK_THROWS_WITH_AS(detail::require_packable(std::size_t(1) << 31, memory_budget{}, std::size_t(-1)),
                         doctest::Contains("pack_bricks.budget"), invalid_parameter);
}

TEST_CASE("hypertree_glsl refuses bricks packed from a grid other than the volume's")
{
    const small_tree& t = tree();
    const hypervolume& hv = t.dense.volume();
    const packed_bricks bricks = pack_bricks(t.dense);
    CHECK(bricks.grid == std::array<int, 3>{hv.grid().x, hv.grid().y, hv.grid().z});
    CHECK_NOTHROW(hypertree_glsl(hv, bricks, t.shape, t.colors, march_options{}));
    // The same tree at another resolution: its own bricks fit it, the small tree's do not.
    auto smaller = presets::tree_d(24);
    smaller.iterations = 20000;
    const dense_store other = build_tree<dense_store>(smaller, 2);
    REQUIRE(other.volume().grid().x != hv.grid().x);
    const tree_shape other_shape = tree_shape::of(other);
    CHECK_NOTHROW(hypertree_glsl(other.volume(), pack_bricks(other), other_shape, t.colors, march_options{}));
    CHECK_THROWS_WITH_AS(hypertree_glsl(other.volume(), bricks, other_shape, t.colors, march_options{}),
                         doctest::Contains("hypertree_glsl.bricks"), invalid_parameter);
    CHECK_THROWS_WITH_AS(hypertree_glsl(hv, pack_bricks(other), t.shape, t.colors, march_options{}), doctest::Contains("hypertree_glsl.bricks"),
                         invalid_parameter);
    // Strides that do not follow from the grid (a hand-made or altered table) are refused too.
    packed_bricks altered = bricks;
    altered.grid_bricks[1] += 1;
    CHECK_THROWS_WITH_AS(hypertree_glsl(hv, altered, t.shape, t.colors, march_options{}), doctest::Contains("hypertree_glsl.bricks"),
                         invalid_parameter);
}

TEST_CASE("hypertree GLSL reads back every voxel of the texture at its cell")
{
    // A compute shader asks the marcher's own <name>_probe for the cell and place of each voxel's
    // center and <name>_voxel_at for what the texture holds there: the GPU's mapping and texel
    // layout against the store's index order.
    const small_tree& t = tree();
    const hypervolume& hv = t.dense.volume();
    march_options o;
    o.bounds_by = bound_method::box;
    const packed_bricks bricks = pack_bricks(t.dense);
    const std::string code = hypertree_glsl(hv, bricks, t.shape, t.colors, o);
    require_context();
    const std::string text = "#version 430 core\nlayout(local_size_x = 64) in;\n" + code +
                             "layout(std430, binding = 1) readonly buffer points_block { float points[]; };\n"
                             "layout(std430, binding = 2) writeonly buffer results_block { uint results[]; };\n"
                             "uniform uint count;\n"
                             "void main() {\n"
                             "    uint i = gl_GlobalInvocationID.x;\n"
                             "    if (i >= count) return;\n"
                             "    ivec3 cell;\n"
                             "    float advance;\n"
                             "    int place = krs_hypertree_probe(vec3(points[3u * i], points[3u * i + 1u], points[3u * i + 2u]), vec3(0.0), 0.0, cell, advance);\n"
                             "    uvec2 v = place >= 0 ? krs_hypertree_voxel_at(place) : uvec2(0u);\n"
                             "    results[i] = uint(cell.x + krs_hypertree_grid.x * (cell.y + krs_hypertree_grid.y * cell.z)) | (v.x << 20u) | (v.y << 28u);\n"
                             "}\n";
    const GLuint program = link({compile(GL_COMPUTE_SHADER, text)});
    REQUIRE(hv.voxel_count() < (1u << 20));
    REQUIRE(bricks.level_count <= 16);
    const uploaded texture(bricks);
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

TEST_CASE("hypertree GLSL walks the brick-walk test's rays probe for probe as the CPU walk")
{
    // A compute shader runs the emitted $_probe along the random rays of test_hypertree_brick_walk
    // (the scattered grid with its empty corner of 16^3 blocks) and writes every probe's sample k
    // and the cell it looks at (-1: none). Equal lists mean equal samples and equal skips: a skip
    // cut short over an empty brick changes no pixel, but it changes this list. The looked-at
    // samples are also compared with plain stepping, the independent reference, on every ray.
    using krs_test::scattered, krs_test::probe_record;
    const scattered s(1);
    REQUIRE(s.empty_blocks() >= 4);
    const hypervolume& v = s.volume;
    tree_shape shape;
    shape.box = {v.origin(), v.origin() + v.extent()};
    const packed_bricks bricks = pack_bricks(s.bricks);
    require_context();
    const uploaded texture(bricks);
    constexpr int most = 512; // probes per ray the shader keeps
    // A skip within one empty brick stops short of its exit, so spans at most its diagonal and a step.
    const krs::vec3d side = v.voxel_size();
    const double brick_diagonal = 4 * std::sqrt(3.0) * std::max({side.x, side.y, side.z});
    std::size_t rays = 0, probes = 0, looked = 0, skips = 0, long_skips = 0, differing_rays = 0, unlike_stepping = 0;
    std::size_t far_rays = 0, far_differing = 0;
    for (float step_factor : {1.0f, 0.7f, 1.9f}) {
        march_options o;
        o.step_factor = step_factor;
        o.bounds_by = bound_method::box;
        const std::string code = hypertree_glsl(v, bricks, shape, depth_colors{}, o, {"walk"});
        const float ds = step_factor * float(v.smallest_voxel_side()); // the marcher's step
        const brick_walk w(v, ds);
        std::vector<float> ray_data; // per ray: origin, direction, t0, count
        std::vector<std::vector<probe_record>> cpu;
        std::vector<std::vector<krs_test::looked_at>> reference;
        std::vector<bool> far; // from 1000 units away
        krs_test::lcg r{1u * 77u + 5u};
        for (float distance : {1.0f, 30.0f, 1000.0f})
            for (int i = 0; i < 300; ++i) {
                krs::vec3f origin, direction;
                krs_test::random_ray(r, v, distance, i, origin, direction);
                float t0 = 0;
                int count = 0;
                if (!krs_test::samples_across(v, origin, direction, ds, t0, count)) continue;
                cpu.push_back(krs_test::probes_of(s, w, origin, direction, t0, count));
                REQUIRE(cpu.back().size() < std::size_t(most));
                reference.push_back(krs_test::stepped(s, origin, direction, t0, ds, count));
                far.push_back(distance > 100);
                ray_data.insert(ray_data.end(), {origin.x, origin.y, origin.z, direction.x, direction.y, direction.z, t0, float(count)});
            }
        const std::size_t n = cpu.size(), stride = 2 * most + 1;
        const std::string text = "#version 430 core\nlayout(local_size_x = 64) in;\n" + code +
                                 "layout(std430, binding = 1) readonly buffer rays_block { float rays[]; };\n"
                                 "layout(std430, binding = 2) writeonly buffer results_block { int results[]; };\n"
                                 "uniform uint ray_count;\n"
                                 "const int most = " + std::to_string(most) + ";\n"
                                 "void main() {\n"
                                 "    uint i = gl_GlobalInvocationID.x;\n"
                                 "    if (i >= ray_count) return;\n"
                                 "    vec3 o = vec3(rays[8u * i], rays[8u * i + 1u], rays[8u * i + 2u]);\n"
                                 "    vec3 d = vec3(rays[8u * i + 3u], rays[8u * i + 4u], rays[8u * i + 5u]);\n"
                                 "    float t0 = rays[8u * i + 6u], count = rays[8u * i + 7u];\n"
                                 "    vec3 slope = krs_walk_slopes(d);\n"
                                 "    float margin0 = krs_walk_margin_at_origin(o);\n"
                                 "    uint base = i * uint(2 * most + 1);\n"
                                 "    int n = 0;\n"
                                 "    for (float k = 0.0; k < count && n < most; ++n) {\n"
                                 "        float t = t0 + (k + 0.5) * krs_walk_step;\n"
                                 "        ivec3 cell;\n"
                                 "        float advance;\n"
                                 "        int place = krs_walk_probe(o + d * t, slope, margin0 + t * krs_walk_rounding_per_step, cell, advance);\n"
                                 "        results[base + 1u + 2u * uint(n)] = int(k);\n"
                                 "        results[base + 2u + 2u * uint(n)] = place >= 0 ? cell.x + krs_walk_grid.x * (cell.y + krs_walk_grid.y * cell.z) : -1;\n"
                                 "        k += advance;\n"
                                 "    }\n"
                                 "    results[base] = n;\n"
                                 "}\n";
        const GLuint program = link({compile(GL_COMPUTE_SHADER, text)});
        const GLuint in = buffer(GL_SHADER_STORAGE_BUFFER, ray_data.data(), ray_data.size() * sizeof(float), GL_STATIC_DRAW);
        const GLuint out = buffer(GL_SHADER_STORAGE_BUFFER, nullptr, n * stride * sizeof(std::int32_t), GL_DYNAMIC_READ);
        glBindBufferBase(GL_SHADER_STORAGE_BUFFER, 1, in);
        glBindBufferBase(GL_SHADER_STORAGE_BUFFER, 2, out);
        glUseProgram(program);
        glUniform1ui(glGetUniformLocation(program, "ray_count"), GLuint(n));
        glDispatchCompute(GLuint((n + 63) / 64), 1, 1);
        glMemoryBarrier(GL_BUFFER_UPDATE_BARRIER_BIT | GL_SHADER_STORAGE_BARRIER_BIT);
        std::vector<std::int32_t> results(n * stride);
        glBindBuffer(GL_SHADER_STORAGE_BUFFER, out);
        glGetBufferSubData(GL_SHADER_STORAGE_BUFFER, 0, GLsizeiptr(results.size() * sizeof(std::int32_t)), results.data());
        REQUIRE(glGetError() == GL_NO_ERROR);
        const GLuint buffers[2] = {in, out};
        glDeleteBuffers(2, buffers);
        glDeleteProgram(program);
        for (std::size_t i = 0; i < n; ++i) {
            const std::int32_t* g = results.data() + i * stride;
            std::vector<probe_record> gpu;
            std::vector<krs_test::looked_at> gpu_looked;
            for (int p = 0; p < g[0]; ++p) {
                const int cell = g[2 + 2 * p];
                gpu.push_back({float(g[1 + 2 * p]), cell});
                if (cell >= 0) gpu_looked.push_back({float(g[1 + 2 * p]), cell % v.grid().x, cell / v.grid().x % v.grid().y, cell / (v.grid().x * v.grid().y)});
                if (p > 0) {
                    const int advance = g[1 + 2 * p] - g[2 * p - 1];
                    skips += advance > 1;
                    long_skips += double(advance) * ds > brick_diagonal + ds; // more than one brick: an empty block's
                }
            }
            if (far[i]) {
                far_rays += 1, far_differing += gpu != cpu[i];
            } else {
                differing_rays += gpu != cpu[i];
            }
            unlike_stepping += gpu_looked != reference[i];
            ++rays, probes += gpu.size(), looked += gpu_looked.size();
        }
    }
    std::printf("hypertree GLSL brick walk: %zu rays, %zu probes (%zu looked at, %zu skips, %zu longer than a brick's diagonal); "
                "%zu rays from near differ from the CPU walk, %zu of %zu from 1000 units away; %zu differ from plain stepping\n",
                rays, probes, looked, skips, long_skips, differing_rays, far_differing, far_rays, unlike_stepping);
    CHECK(rays > 1500);
    CHECK(looked > 1000);
    CHECK(skips > 1000);
    CHECK(long_skips > 100); // skips over empty blocks were compared
    CHECK(differing_rays == 0);
    // From 1000 units away a sample's position (|o| near 500) differs from the CPU's in its last
    // bits on a few rays (measured: 2 of about 900 on llvmpipe), enough to put a sample on the
    // other side of a cell face or a skip's ceil: a skip one sample longer or shorter. The margin
    // keeps both walks from skipping a voxel, so the samples looked at still equal stepping's.
    CHECK(far_rays > 500);
    CHECK(far_differing * 100 <= far_rays);
    CHECK(unlike_stepping == 0);
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
                             "void main() { frag_color = krs_march_tree(vec3(0.0, 0.5, -2.0), vec3(0.0, 0.0, 1.0)); }\n";
    // Vulkan: the sampler bound explicitly, the output at location 0.
    const std::string vulkan_main = "layout(location = 0) out vec4 frag_color;\n"
                                    "void main() { frag_color = krs_march_tree(vec3(0.0, 0.5, -2.0), vec3(0.0, 0.0, 1.0)); }\n";
    int files = 0, spirv_files = 0;
    const packed_bricks bricks = pack_bricks(t.dense);
    for (const auto& [label, options] : variants) {
        const std::string code = hypertree_glsl(t.dense.volume(), bricks, t.shape, t.colors, options, {"tree"});
        for (const char* version : {"330", "450"}) {
            validate_with_glslang(dir + "/hypertree_" + label + "." + version + ".frag",
                     std::string("#version ") + version + " core\n" + code + main);
            ++files;
        }
        hypertree_glsl_options bound{"tree"};
        bound.binding = 0;
        validate_spirv(dir + "/hypertree_" + label + ".vulkan.frag",
                       "#version 450\n" + hypertree_glsl(t.dense.volume(), bricks, t.shape, t.colors, options, bound) + vulkan_main);
        ++spirv_files;
    }
    // With no flows or spheres (a shape of the box alone) the code has no zero-length arrays.
    tree_shape bare = t.shape;
    bare.flows.clear();
    bare.spheres.clear();
    validate_with_glslang(dir + "/hypertree_bare.330.frag", "#version 330 core\n" + hypertree_glsl(t.dense, bare, t.colors, {}, {"tree"}) + main);
    std::printf("glslangValidator: %d hypertree volume shaders checked, %d compiled for Vulkan and passed spirv-val\n", files + 1,
                spirv_files);
}

TEST_CASE("hypertree GLSL: every global name starts with the chosen prefix, bad prefixes and names are refused by name")
{
    const small_tree& t = tree();
    const packed_bricks bricks = pack_bricks(t.dense);
    for (const char* prefix : {"krs_", "tree7_"}) {
        hypertree_glsl_options g;
        g.prefix = prefix;
        const std::string code = hypertree_glsl(t.dense.volume(), bricks, t.shape, t.colors, varied_options(), g);
        // Global declarations start at column 0 (bodies are indented): `[const|uniform] TYPE NAME`.
        std::size_t globals = 0;
        for (std::size_t at = 0; at < code.size();) {
            const std::size_t end = std::min(code.find('\n', at), code.size());
            const std::string line = code.substr(at, end - at);
            at = end + 1;
            if (line.empty() || line[0] == ' ' || line[0] == '/' || line[0] == '}' || line[0] == ')') continue;
            std::vector<std::string> words;
            for (std::size_t i = 0; i < line.size();) {
                std::size_t j = i;
                while (j < line.size() && (std::isalnum(static_cast<unsigned char>(line[j])) || line[j] == '_')) ++j;
                if (j > i) words.push_back(line.substr(i, j - i));
                i = j + 1;
            }
            std::size_t first = 0;
            while (first < words.size() && (words[first] == "const" || words[first] == "uniform" || words[first] == "layout" ||
                                             words[first] == "binding" || std::isdigit(static_cast<unsigned char>(words[first][0]))))
                ++first;
            REQUIRE(first + 1 < words.size()); // a type and a name
            INFO(line);
            CHECK(words[first + 1].rfind(prefix, 0) == 0);
            ++globals;
        }
        CHECK(globals > 30);
        CHECK(code.find(std::string("vec4 ") + prefix + "march_hypertree(") != std::string::npos);
    }
    for (const char* bad : {"", "Krs_", "krs", "gl_", "k__", "1x_"}) {
        hypertree_glsl_options g;
        g.prefix = bad;
        CHECK_THROWS_WITH_AS(hypertree_glsl(t.dense.volume(), bricks, t.shape, t.colors, march_options{}, g),
                             doctest::Contains("hypertree_glsl_options.prefix"), invalid_parameter);
    }
    for (const char* bad : {"", "_tree", "a__b", "tree-1"}) {
        hypertree_glsl_options g;
        g.name = bad;
        CHECK_THROWS_WITH_AS(hypertree_glsl(t.dense.volume(), bricks, t.shape, t.colors, march_options{}, g),
                             doctest::Contains("hypertree_glsl_options.name"), invalid_parameter);
    }
}

TEST_CASE("hypertree GLSL constants read on the GPU equal the options, colors and shape they came from")
{
    // As NanoVDB's tests check the GPU side's constants against the C++ ones: a compute shader
    // copies out the opacity table, the Lambert wrap, the level colors, the lights (direction and
    // color), the ambient, diffuse and specular weights and the crown the code declares. Expected
    // values come from the inputs (the options' lights normalized here, the colors' at(), the
    // shape's crown), not from voxel_shading, except the opacity table (the law in one place).
    const small_tree& t = tree();
    const march_options o = varied_options();
    const packed_bricks bricks = pack_bricks(t.dense);
    const std::string code = hypertree_glsl(t.dense.volume(), bricks, t.shape, t.colors, o);
    const voxel_shading cpu(o, t.shape, t.colors);
    require_context();
    const std::size_t levels = std::size_t(bricks.level_count), lights = o.lights.size();
    REQUIRE(lights == 2);
    const std::size_t at_levels = 258, at_lights = at_levels + 3 * levels, at_weights = at_lights + 6 * lights, count = at_weights + 9;
    const std::string text = "#version 430 core\nlayout(local_size_x = 1) in;\n" + code +
                             "layout(std430, binding = 2) writeonly buffer results_block { float results[]; };\n"
                             "void main() {\n"
                             "    for (int i = 0; i < 256; ++i) results[i] = krs_hypertree_alpha[i];\n"
                             "    results[256] = krs_hypertree_lambert_slope;\n"
                             "    results[257] = krs_hypertree_lambert_floor;\n"
                             "    for (int l = 0; l < krs_hypertree_level_count; ++l)\n"
                             "        for (int c = 0; c < 3; ++c) results[" + std::to_string(at_levels) + " + 3 * l + c] = krs_hypertree_level_color[l][c];\n"
                             "    for (int i = 0; i < krs_hypertree_light_count; ++i)\n"
                             "        for (int c = 0; c < 3; ++c) {\n"
                             "            results[" + std::to_string(at_lights) + " + 6 * i + c] = krs_hypertree_light_direction[i][c];\n"
                             "            results[" + std::to_string(at_lights) + " + 6 * i + 3 + c] = krs_hypertree_light_color[i][c];\n"
                             "        }\n"
                             "    int w = " + std::to_string(at_weights) + ";\n"
                             "    results[w] = krs_hypertree_ambient;\n"
                             "    results[w + 1] = krs_hypertree_ambient_falloff;\n"
                             "    results[w + 2] = krs_hypertree_diffuse;\n"
                             "    results[w + 3] = krs_hypertree_specular;\n"
                             "    results[w + 4] = krs_hypertree_shininess;\n"
                             "    for (int c = 0; c < 3; ++c) results[w + 5 + c] = krs_hypertree_crown_center[c];\n"
                             "    results[w + 8] = krs_hypertree_crown_radius;\n"
                             "}\n";
    const GLuint program = link({compile(GL_COMPUTE_SHADER, text)});
    const GLuint out = buffer(GL_SHADER_STORAGE_BUFFER, nullptr, count * sizeof(float), GL_DYNAMIC_READ);
    glBindBufferBase(GL_SHADER_STORAGE_BUFFER, 2, out);
    glUseProgram(program);
    glDispatchCompute(1, 1, 1);
    glMemoryBarrier(GL_BUFFER_UPDATE_BARRIER_BIT | GL_SHADER_STORAGE_BARRIER_BIT);
    std::vector<float> got(count);
    glBindBuffer(GL_SHADER_STORAGE_BUFFER, out);
    glGetBufferSubData(GL_SHADER_STORAGE_BUFFER, 0, GLsizeiptr(count * sizeof(float)), got.data());
    REQUIRE(glGetError() == GL_NO_ERROR);
    glDeleteBuffers(1, &out);
    glDeleteProgram(program);
    for (std::size_t d = 0; d < 256; ++d) REQUIRE(got[d] == cpu.opacity()[d]);
    CHECK(got[256] == lambert_wrap::slope);
    CHECK(got[257] == lambert_wrap::floor);
    for (std::size_t l = 0; l < levels; ++l) {
        const rgb c = t.colors.at(int(l));
        CHECK(got[at_levels + 3 * l] == c.r);
        CHECK(got[at_levels + 3 * l + 1] == c.g);
        CHECK(got[at_levels + 3 * l + 2] == c.b);
    }
    for (std::size_t i = 0; i < lights; ++i) {
        // The direction normalized here in double: the float the library normalizes to is within
        // an ulp or two of it.
        const krs::vec3f dir = o.lights[i].direction;
        const double length = std::sqrt(double(dir.x) * dir.x + double(dir.y) * dir.y + double(dir.z) * dir.z);
        const double unit[3] = {dir.x / length, dir.y / length, dir.z / length};
        for (std::size_t c = 0; c < 3; ++c) CHECK(std::abs(double(got[at_lights + 6 * i + c]) - unit[c]) <= 2.5e-7);
        CHECK(got[at_lights + 6 * i + 3] == o.lights[i].color.r);
        CHECK(got[at_lights + 6 * i + 4] == o.lights[i].color.g);
        CHECK(got[at_lights + 6 * i + 5] == o.lights[i].color.b);
    }
    CHECK(got[at_weights] == o.ambient);
    CHECK(got[at_weights + 1] == o.ambient_falloff);
    CHECK(got[at_weights + 2] == o.diffuse);
    CHECK(got[at_weights + 3] == o.specular);
    CHECK(got[at_weights + 4] == o.shininess);
    CHECK(got[at_weights + 5] == t.shape.crown.center.x);
    CHECK(got[at_weights + 6] == t.shape.crown.center.y);
    CHECK(got[at_weights + 7] == t.shape.crown.center.z);
    CHECK(got[at_weights + 8] == t.shape.crown.radius);
}

TEST_CASE("hypertree GLSL frame on llvmpipe matches the CPU marcher (default options)")
{
    const frame_agreement a = compare_frames(march_options{}, "defaults");
    CHECK(a.within == a.pixels);
    CHECK(a.worst_levels <= 1);
    CHECK(a.covered > a.pixels / 10); // the camera sees the tree
}

TEST_CASE("hypertree GLSL frame on llvmpipe matches the CPU marcher (specular, two lights, per-sample shadows)")
{
    const frame_agreement a = compare_frames(varied_options(), "varied");
    CHECK(a.within == a.pixels);
    CHECK(a.worst_levels <= 1);
    CHECK(a.covered > a.pixels / 10);
}

TEST_CASE("hypertree GLSL frame on llvmpipe matches the CPU marcher (box normals, line flow, specular)")
{
    march_options boxes = varied_options();
    boxes.normals_by = normal_method::part_boxes;
    const frame_agreement a = compare_frames(boxes, "box normals");
    CHECK(a.within == a.pixels);
    CHECK(a.worst_levels <= 1);
    CHECK(a.covered > a.pixels / 10);
    // Line axes other than the covariance axes (tree D has point generators: given, turned a
    // quarter about z), so the emitted axes must be the line axes for the frames to agree.
    tree_shape turned = tree().shape;
    std::vector<krs::vec3d> lines;
    for (const part_flow& f : turned.flows) lines.push_back({-f.axis.y, f.axis.x, f.axis.z});
    turned.set_line_flow(lines);
    march_options line = varied_options();
    line.normals_by = normal_method::line_flow;
    const frame_agreement b = compare_frames(line, "line flow", &turned);
    CHECK(b.within == b.pixels);
    CHECK(b.worst_levels <= 1);
}

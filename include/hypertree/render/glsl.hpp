#pragma once
// The hypertree raymarcher as GLSL (paper section 8 on a GPU): the loop of volume_marcher
// (marcher.hpp), emitted as a fragment-shader function that marches the same samples through the
// same bricks, stops at the same transmittance and shades with the same formulas and constants
// (voxel_shading.hpp), so a GPU image of a tree equals the CPU image up to the last bits of exp,
// pow and the float (not double) shading geometry.
//
//     GLint max_texels;  // the context's limit, see below
//     glGetIntegerv(GL_MAX_TEXTURE_BUFFER_SIZE, &max_texels);
//     const packed_bricks bricks = pack_bricks(marcher.bricks(), {}, std::size_t(max_texels));
//     const std::string code = hypertree_glsl(store.volume(), bricks, shape, colors, options);
//     // in the shader: vec4 m = krs_march_hypertree(origin, unit_direction);
//     //                color = m.rgb + m.a * background;             // as render() composites
//
// Two parts, as NanoVDB splits a grid from the code that reads it:
//
// The volume is data: the marcher's own bricks (voxel_bricks.hpp), the one layout both marchers
// read, made by voxel_bricks' constructor from any store. `pack_bricks` does not lay anything out
// again: it concatenates the brick arrays, word for word as they lie in the CPU's memory, into one
// buffer of 32-bit words: the brick ranks (int32 per 4^3 brick of the grid; -(e + 1) when empty,
// e the level of the largest empty aligned cube around it), then the densities and the levels by place
// (rank * 64 + offset in the brick), four bytes to a word, the first in the low byte (the memory
// order of a little-endian CPU). The GPU gets it as a buffer texture of R32UI texels:
//
//     glBindBuffer(GL_TEXTURE_BUFFER, buffer);
//     glBufferData(GL_TEXTURE_BUFFER, words.size() * 4, words.data(), GL_STATIC_DRAW);
//     glBindTexture(GL_TEXTURE_BUFFER, texture);
//     glTexBuffer(GL_TEXTURE_BUFFER, GL_R32UI, buffer);
//
// bound to the sampler `<prefix><name>_bricks` (a `usamplerBuffer`, the shader's only uniform),
// read with texelFetch. The shader finds a voxel as voxel_bricks::view::place does (one read of the
// brick's rank, then a byte of a word). A buffer texture holds GL_MAX_TEXTURE_BUFFER_SIZE texels, a
// limit to query: GL guarantees only 65536, and tree A at resolution 300 takes about 1.2 million
// words (75^3 brick ranks, and 25 000 non-empty bricks of 32 words). Pass the queried limit to
// pack_bricks as max_texels: it refuses a larger buffer (pack_bricks.max_texels, naming the words
// needed), where the GL would only draw wrong.
//
// Everything else is constants in the code: the box, the grid and its mapping, the brick table's
// sizes and offsets, the step, the opacity per density byte, the color per level, the lights and
// the shading weights (all from voxel_shading, the C++ values the CPU uses), each axis's voxel
// centers (as the float the CPU rounds its double centers to, so per-voxel shadow rays start from
// the same point), the part spheres, the structure flows (or the line axes, or the part boxes, as
// march_options::normals_by picks the normal). A tree with other options is new code;
// the bricks stay.
//
// Rays and shadow rays walk the bricks as the CPU's do (brick_walk::glsl, emitted from the walk's
// own constants): a sample in an empty brick is not looked up and the ray jumps to the exit of
// the largest empty cube around it, taking exactly the samples it would have stepped through. What the GPU
// leaves out: the shadow memo (a memoized shadow is a pure function of its voxel) and the ray
// cache (a cached voxel equals the bricks'). Each only spares work on the CPU and changes no
// pixel, so the GPU computes the same values directly. Shadows are always shadow rays, whatever
// march_options::shadow_by: the CPU's default light sweep (light_sweep.hpp) is a table made with
// the marcher, which the GPU does not get; its CPU counterpart is shadow_method::rays. The part-sphere test is kept
// (bound_method::spheres): it also changes no pixel, but it is the paper's traversal. The other
// secondary bounds (the paper's derived spheres, the part boxes) are CPU options: asked of the
// GLSL emitter, they are refused (invalid_parameter naming march_options.bounds_by).
//
// Names: every global the code declares starts with the prefix (default krs_, checked by
// krs::glsl::is_prefix as the KRS snippets' is) and then the tree's name: <prefix><name>_*, and
// the march function <prefix>march_<name>. Distinct names or prefixes let several trees share one
// shader.
//
// Precision. Sample positions, the slab test, cell indices, opacities and the front-to-back sums
// are the same float operations in the same order as the C++ (bit for bit on llvmpipe when the
// C++ is built with -ffp-contract=off, for rays from near the tree). From far away (a ray origin
// some 500 units out) a sample's position can differ in its last bits on a few rays, enough to
// cross a cell face or a skip's rounding: the walk then takes a skip one sample longer or shorter
// than the CPU's, and the skip margin keeps either from passing a voxel (the brick-walk test in
// tests/test_hypertree_glsl_gpu.cpp measures both). The shading differs in its last bits: the CPU computes
// the crown depth and the flow normal in double, the GLSL in float (GLSL has no double exp, and
// doubles are slow on many GPUs), and GLSL's exp and pow are a few ulp from the C library's.
//
// The code is one text for GLSL 3.30 and 4.x (no #version line; a 4.3 context runs it in the
// tests). For Vulkan (SPIR-V) set hypertree_glsl_options::binding: the sampler then carries
// layout(binding = N), which GLSL below 4.20 does not accept.

#include "hypertree/execution.hpp"
#include "hypertree/render/brick_walk.hpp"
#include "hypertree/render/march_options.hpp"
#include "hypertree/render/tree_shape.hpp"
#include "hypertree/render/voxel_bricks.hpp"
#include "hypertree/render/voxel_shading.hpp"
#include "krs/core/validate.hpp"
#include "krs/glsl/literal.hpp"
#include "krs/glsl/names.hpp"

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <limits>
#include <string>
#include <vector>

namespace hypertree {

// The bricks of voxel_bricks as one buffer of 32-bit words (see above), with where each array
// starts and the sizes the shader's constants need.
struct packed_bricks {
    std::vector<std::uint32_t> words;
    std::uint32_t rank_offset = 0, density_offset = 0, level_offset = 0; // in words
    std::array<int, 3> grid{};                                         // the volume's, in voxels
    std::array<std::uint32_t, 3> grid_bricks{};                        // (grid + 3) / 4
    int level_count = 1; // 1 + the deepest level stored: the length of the shader's color table
};

namespace detail {
// pack_bricks' three limits on a buffer of `words` words, each refused by its own name: the memory
// budget (4 bytes a word), the shader's int offsets (below 2^31 words), and the texels the GL
// says a buffer texture holds (GL_MAX_TEXTURE_BUFFER_SIZE, stated by the caller).
inline void require_packable(std::size_t words, memory_budget budget, std::size_t max_texels)
{
    const std::string needed = std::to_string(words) + " words (" + std::to_string(words * 4) + " bytes)";
    if (words > budget.bytes / 4)
        throw krs::invalid_parameter("pack_bricks.budget",
                                     "must hold the buffer: 4 bytes per brick of the grid, 1 per density and per level "
                                     "of each voxel of the non-empty bricks (budget " + std::to_string(budget.bytes) + " bytes)",
                                     needed);
    if (words >= (std::size_t(1) << 31))
        throw krs::invalid_parameter("pack_bricks.bricks", "must pack into fewer than 2^31 words (the shader's int offsets)", needed);
    if (words > max_texels)
        throw krs::invalid_parameter("pack_bricks.max_texels",
                                     "must be at least the words of the buffer, one R32UI texel each (GL_MAX_TEXTURE_BUFFER_SIZE is "
                                     "the GL's limit; " + std::to_string(max_texels) + " stated)",
                                     needed);
}
} // namespace detail

// Refuses bricks whose buffer would exceed `budget` (pack_bricks.budget), 2^31 words
// (pack_bricks.bricks: the shader's int offsets) or `max_texels` (pack_bricks.max_texels): pass
// the GL_MAX_TEXTURE_BUFFER_SIZE the context reports, since the GL itself would only fail at draw.
inline packed_bricks pack_bricks(const voxel_bricks& bricks, memory_budget budget = {},
                                 std::size_t max_texels = std::numeric_limits<std::size_t>::max())
{
    const auto ranks = bricks.brick_ranks();
    const auto density = bricks.densities(), level = bricks.levels();
    const std::size_t words = ranks.size() + (density.size() + 3) / 4 + (level.size() + 3) / 4;
    detail::require_packable(words, budget, max_texels);
    packed_bricks out;
    out.words.reserve(words);
    for (std::int32_t r : ranks) out.words.push_back(std::uint32_t(r));
    const auto bytes = [&](std::span<const std::uint8_t> b) {
        for (std::size_t i = 0; i < b.size(); i += 4) {
            std::uint32_t w = 0;
            for (std::size_t k = 0; k < 4 && i + k < b.size(); ++k) w |= std::uint32_t(b[i + k]) << (8 * k);
            out.words.push_back(w);
        }
    };
    out.density_offset = std::uint32_t(out.words.size());
    bytes(density);
    out.level_offset = std::uint32_t(out.words.size());
    bytes(level);
    out.grid = bricks.grid();
    for (std::size_t a = 0; a < 3; ++a) out.grid_bricks[a] = std::uint32_t(bricks.grid_bricks()[a]);
    out.level_count = level_count(bricks);
    return out;
}
template <voxel_store S>
packed_bricks pack_bricks(const S& store, memory_budget budget = {}, std::size_t max_texels = std::numeric_limits<std::size_t>::max())
{
    return pack_bricks(voxel_bricks(store), budget, max_texels);
}

struct hypertree_glsl_options {
    // The tree's name in the code: <prefix><name>_* and <prefix>march_<name>.
    std::string name = "hypertree";
    std::string prefix = "krs_";
    // >= 0: the sampler is declared layout(binding = N) (GLSL 4.20 and later, Vulkan).
    int binding = -1;
};

// The GLSL of the marcher that volume_marcher(store, shape, colors, options) is, for the bricks
// `bricks` = pack_bricks(store) of a store of the volume `v` (refused, as hypertree_glsl.bricks,
// when they were packed from a grid of another size): constants, the sampler uniform and
// `vec4 <prefix>march_<name>(vec3 origin, vec3 direction)` returning the premultiplied color (rgb)
// and the remaining transmittance (a) of a ray with a unit direction, as march_result.
inline std::string hypertree_glsl(const hypervolume& v, const packed_bricks& bricks, const tree_shape& shape, const depth_colors& colors,
                                  const march_options& options, const hypertree_glsl_options& glsl = {})
{
    using krs::glsl::float_literal, krs::glsl::vec3_literal;
    krs::glsl::require_prefix("hypertree_glsl_options.prefix", glsl.prefix);
    krs::glsl::require_name_part("hypertree_glsl_options.name", glsl.name);
    // The strides, offsets and level count below come from the bricks, the mapping from v: bricks
    // of another grid would read wrong or out-of-range texels without any GL error.
    const std::array<int, 3> grid{v.grid().x, v.grid().y, v.grid().z};
    bool matches = bricks.grid == grid;
    for (std::size_t a = 0; a < 3; ++a)
        matches = matches && bricks.grid_bricks[a] == std::uint32_t((grid[a] + 3) / 4);
    if (!matches)
        throw krs::invalid_parameter("hypertree_glsl.bricks", "must be pack_bricks of a store of this volume",
                                     "bricks of a " + std::to_string(bricks.grid[0]) + "x" + std::to_string(bricks.grid[1]) + "x" +
                                         std::to_string(bricks.grid[2]) + " grid, volume " + std::to_string(grid[0]) + "x" +
                                         std::to_string(grid[1]) + "x" + std::to_string(grid[2]));
    options.validate(v, shape.box);
    // (The GPU keeps the fitted spheres only: the paper's spheres and the part boxes are CPU options.)
    if (options.bounds_by != bound_method::box && options.bounds_by != bound_method::spheres)
        throw krs::invalid_parameter("march_options.bounds_by", "the GLSL marcher takes bound_method::box or spheres",
                                     std::to_string(int(options.bounds_by)));
    // Render-time noise is CPU only (march_options.hpp): refused rather than silently dropped.
    if (options.displacement.enabled())
        throw krs::invalid_parameter("march_options.displacement", "is not supported by the GLSL marcher (amplitude must be 0 there; the CPU marcher takes it)",
                                     krs::detail::to_text(options.displacement.amplitude));
    const voxel_shading shading(options, shape, colors);
    const brick_walk walk(v, options.step_factor * float(v.smallest_voxel_side())); // the marcher's walk
    const std::string n = glsl.prefix + glsl.name;
    const auto integer = [](auto i) { return std::to_string(i); };

    std::string s = "// hypertree volume marcher '" + n + "' (hypertree/render/glsl.hpp): the loop of volume_marcher.\n";
    s += "// " + n + "_bricks: R32UI buffer texture of pack_bricks (voxel_bricks' arrays, word for word).\n";
    s += (glsl.binding >= 0 ? "layout(binding = " + integer(glsl.binding) + ") " : std::string()) + "uniform usamplerBuffer " + n + "_bricks;\n";
    // The grid, as the marcher's floats.
    s += "const vec3 " + n + "_box_lo = " + vec3_literal(krs::vec3f(shape.box.lo)) + ";\n";
    s += "const vec3 " + n + "_box_hi = " + vec3_literal(krs::vec3f(shape.box.hi)) + ";\n";
    s += "const vec3 " + n + "_origin = " + vec3_literal(krs::vec3f(v.origin())) + ";\n";
    s += "const vec3 " + n + "_cells_per_unit = " + vec3_literal(krs::vec3f(v.cells_per_unit())) + ";\n";
    s += "const ivec3 " + n + "_grid = ivec3(" + integer(v.grid().x) + ", " + integer(v.grid().y) + ", " + integer(v.grid().z) + ");\n";
    // The bricks' table (voxel_bricks::view).
    s += "const int " + n + "_bricks_x = " + integer(bricks.grid_bricks[0]) + ";\n";
    s += "const int " + n + "_bricks_xy = " + integer(bricks.grid_bricks[0] * bricks.grid_bricks[1]) + ";\n";
    s += "const int " + n + "_rank_offset = " + integer(bricks.rank_offset) + ";\n";
    s += "const int " + n + "_density_offset = " + integer(bricks.density_offset) + ";\n";
    s += "const int " + n + "_level_offset = " + integer(bricks.level_offset) + ";\n";
    s += "const float " + n + "_step = " + float_literal(walk.step()) + ";\n";
    s += "const float " + n + "_min_transmittance = " + float_literal(options.min_transmittance) + ";\n";
    s += shading.glsl_constants(n, bricks.level_count);
    // Voxel centers per axis: origin + (c + 1/2) side in double, then float, as the marcher's
    // per-voxel shading point.
    if (options.shade_per_voxel) {
        const char* axes[3] = {"x", "y", "z"};
        const int counts[3] = {v.grid().x, v.grid().y, v.grid().z};
        const double origins[3] = {v.origin().x, v.origin().y, v.origin().z};
        const double sides[3] = {v.voxel_size().x, v.voxel_size().y, v.voxel_size().z};
        for (int a = 0; a < 3; ++a) {
            std::vector<float> centers(static_cast<std::size_t>(counts[a]));
            for (int c = 0; c < counts[a]; ++c) centers[std::size_t(c)] = float(origins[a] + (c + 0.5) * sides[a]);
            s += krs::glsl::float_array(n + "_center_" + axes[a], centers.data(), centers.size());
        }
    }
    const bool spheres = options.bounds_by == bound_method::spheres && !shape.spheres.empty();
    if (spheres) {
        // center and radius^2: the CPU marcher's own values (bound_test, radius^2 rounded up with
        // room for the float test's rounding), so both skip the same samples
        const bound_test test = bound_test::of(shape, bound_method::spheres);
        const std::size_t count = test.spheres.size();
        s += "const vec4 " + n + "_spheres[" + integer(count) + "] = vec4[" + integer(count) + "](";
        for (std::size_t i = 0; i < count; ++i) {
            const std::array<float, 4>& b = test.spheres[i];
            s += (i ? ",\n    vec4(" : "vec4(") + float_literal(b[0]) + ", " + float_literal(b[1]) + ", " + float_literal(b[2]) + ", " +
                 float_literal(b[3]) + ")";
        }
        s += ");\n";
    }
    if (!shape.flows.empty()) {
        std::vector<krs::vec3f> centroids, axes;
        std::vector<float> soft;
        for (const part_flow& f : shape.flows) {
            centroids.push_back({float(f.centroid.x), float(f.centroid.y), float(f.centroid.z)});
            const vec3d& a = options.normals_by == normal_method::line_flow ? f.line_axis : f.axis; // (tree_shape::normal_at)
            axes.push_back({float(a.x), float(a.y), float(a.z)});
            soft.push_back(float(f.weight_radius * f.weight_radius * 0.05));
        }
        s += krs::glsl::vec3_array(n + "_flow_centroid", centroids);
        s += krs::glsl::vec3_array(n + "_flow_axis", axes);
        s += krs::glsl::float_array(n + "_flow_soft", soft.data(), soft.size());
    }

    // Functions (templates in krs::glsl::fill's dialect, NAME the tree's prefixed name). Each mirrors
    // the marcher member of the same name; sums are spelled out where
    // GLSL's dot or length might associate differently from krs::dot (x, then y, then z).
    s += krs::glsl::fill(R"(float NAME_dot(vec3 a, vec3 b) { return a.x * b.x + a.y * b.y + a.z * b.z; }

// enter_box: the slab test, t0 >= 0; a ray that misses gets t0 >= t1. A zero direction component
// becomes tiny so the division gives a huge finite slope instead of inf * 0 = NaN.
void NAME_enter_box(vec3 o, vec3 d, out float t0, out float t1) {
    t0 = 0.0;
    t1 = 3.0e38;
    for (int a = 0; a < 3; ++a) {
        float safe = abs(d[a]) < 1e-30 ? 1e-30 : d[a];
        float inv = 1.0 / safe;
        float ta = (NAME_box_lo[a] - o[a]) * inv, tb = (NAME_box_hi[a] - o[a]) * inv;
        t0 = max(t0, min(ta, tb));
        t1 = min(t1, max(ta, tb));
    }
}

)", {{"NAME", n}});
    s += krs::glsl::fill(R"(// voxel_bricks::view::place: the voxel's place in the bricks (rank * 64 + offset), or in an
// empty brick -64 (e + 1) + offset, e the level of its empty cube.
int NAME_place(ivec3 c) {
    int brick = (c.x >> 2) + (c.y >> 2) * NAME_bricks_x + (c.z >> 2) * NAME_bricks_xy;
    int rank = int(texelFetch(NAME_bricks, NAME_rank_offset + brick).r);
    return (rank << 6) | (c.x & 3) | ((c.y & 3) << 2) | ((c.z & 3) << 4);
}

// The voxel at a place >= 0: x = density, y = level. Byte k of word w is place 4 w + k.
uvec2 NAME_voxel_at(int place) {
    uint shift = uint(8 * (place & 3));
    uint density = (texelFetch(NAME_bricks, NAME_density_offset + (place >> 2)).r >> shift) & 255u;
    uint level = (texelFetch(NAME_bricks, NAME_level_offset + (place >> 2)).r >> shift) & 255u;
    return uvec2(density, level);
}

)",
                           {{"NAME", n}});
    s += walk.glsl(n);
    s += "// Whether p lies in a part sphere (bound_method::spheres; else always).\n";
    if (spheres) {
        s += krs::glsl::fill("bool NAME_in_spheres(vec3 p) {\n    for (int i = 0; i < ", {{"NAME", n}}) + integer(shape.spheres.size()) +
             krs::glsl::fill(R"(; ++i) {
        vec3 d = p - NAME_spheres[i].xyz;
        if (NAME_dot(d, d) <= NAME_spheres[i].w) return true;
    }
    return false;
}

)",
                               {{"NAME", n}});
    } else {
        s += krs::glsl::fill("bool NAME_in_spheres(vec3 p) {\n    return true;\n}\n\n", {{"NAME", n}});
    }
    s += krs::glsl::fill(R"(// shadow_transmittance: from p toward the light l, starting one step out (as the C++ marcher:
// out of the shading voxel at step factor 1 on cubic voxels), with the primary ray's brick walk
// and early exit.
float NAME_shadow_transmittance(vec3 p, vec3 l) {
    float t0, t1;
    NAME_enter_box(p, l, t0, t1);
    float transmittance = 1.0;
    float base = max(t0, 0.0);
    vec3 slope = NAME_slopes(l);
    float margin0 = NAME_margin_at_origin(p);
    for (float j = 1.0;;) {
        float t = base + j * NAME_step;
        if (!(t < t1 && transmittance >= NAME_min_transmittance)) break;
        vec3 q = p + l * t;
        ivec3 cell;
        float advance;
        int place = NAME_probe(q, slope, margin0 + t * NAME_rounding_per_step, cell, advance);
        if (place >= 0 && NAME_in_spheres(q)) transmittance *= 1.0 - NAME_alpha[int(NAME_voxel_at(place).x)];
        j += advance;
    }
    return transmittance;
}

)",
                           {{"NAME", n}});
    if (options.normals_by == normal_method::part_boxes) {
        // tree_shape::box_normal_at, in float as the CPU computes it.
        const std::string big = float_literal(std::numeric_limits<float>::max());
        if (!shape.part_boxes.empty()) {
            std::vector<krs::vec3f> lo, hi;
            for (const world_box& b : shape.part_boxes) lo.push_back(krs::vec3f(b.lo)), hi.push_back(krs::vec3f(b.hi));
            s += krs::glsl::vec3_array(n + "_part_box_lo", lo);
            s += krs::glsl::vec3_array(n + "_part_box_hi", hi);
        }
        s += krs::glsl::fill("// tree_shape::box_normal_at: the outward normal of the nearest face of the part box p lies in.\n"
                                  "vec3 NAME_normal(vec3 p) {\n"
                                  "    float best_inside = " + big + ", best_outside = " + big + ";\n"
                                  "    vec3 inside_n = vec3(0.0), outside_n = vec3(0.0);\n", {{"NAME", n}});
        if (!shape.part_boxes.empty()) {
            std::string loop = "    for (int i = 0; i < " + integer(shape.part_boxes.size()) + "; ++i) {\n" +
                               krs::glsl::fill(R"(        vec3 lo = NAME_part_box_lo[i], hi = NAME_part_box_hi[i];
        float nearest = BIG, beyond = -BIG, out2 = 0.0;
        vec3 near_n = vec3(-1.0, 0.0, 0.0), beyond_n = vec3(-1.0, 0.0, 0.0);
        for (int a = 0; a < 3; ++a) {
            vec3 e_a = vec3(a == 0 ? 1.0 : 0.0, a == 1 ? 1.0 : 0.0, a == 2 ? 1.0 : 0.0);
            float below = lo[a] - p[a], above = p[a] - hi[a];
            if (-below < nearest) { nearest = -below; near_n = -e_a; }
            if (-above < nearest) { nearest = -above; near_n = e_a; }
            if (below > beyond) { beyond = below; beyond_n = -e_a; }
            if (above > beyond) { beyond = above; beyond_n = e_a; }
            float e = max(max(below, above), 0.0);
            out2 += e * e;
        }
        if (beyond <= 0.0) {
            if (nearest < best_inside) { best_inside = nearest; inside_n = near_n; }
        } else if (out2 < best_outside) {
            best_outside = out2; outside_n = beyond_n;
        }
    }
)", {{"NAME", n}, {"BIG", big}});
            s += loop;
        }
        s += "    return best_inside < " + big + " ? inside_n : outside_n;\n}\n\n";
    } else {
    s += krs::glsl::fill(R"(// tree_shape::normal_at: the structure-flow normal (zero without flows).
vec3 NAME_normal(vec3 p) {
    vec3 n = vec3(0.0);
)", {{"NAME", n}});
    if (!shape.flows.empty()) {
        s += "    for (int i = 0; i < " + integer(shape.flows.size()) + "; ++i) {\n";
        s += krs::glsl::fill(R"(        vec3 d = p - NAME_flow_centroid[i];
        vec3 radial = d - NAME_flow_axis[i] * NAME_dot(d, NAME_flow_axis[i]);
        float w = 1.0 / (NAME_dot(d, d) + NAME_flow_soft[i]);
        float len = sqrt(NAME_dot(radial, radial));
        if (len > 0.0) n += radial * (w / len);
    }
)",
                               {{"NAME", n}});
    }
    s += krs::glsl::fill(R"(    float len = sqrt(NAME_dot(n, n));
    return len > 0.0 ? n / len : vec3(0.0);
}

)",
                           {{"NAME", n}});
    }
    s += shading.glsl_shade(n);
    // The shading point: the voxel's center with shade_per_voxel (the marcher's per-voxel shading),
    // else the sample itself.
    s += krs::glsl::fill(options.shade_per_voxel ? "vec3 NAME_shading_point(vec3 p, ivec3 cell) {\n    return vec3(NAME_center_x[cell.x], NAME_center_y[cell.y], NAME_center_z[cell.z]);\n}\n\n"
                                                   : "vec3 NAME_shading_point(vec3 p, ivec3 cell) {\n    return p;\n}\n\n",
                           {{"NAME", n}});
    s += "// march: samples at t0 + (k + 1/2) ds (computed from k, as the marcher does), front to back, until the ray leaves the box or the\n"
         "// transmittance falls below the minimum. Returns (premultiplied rgb, transmittance).\n";
    s += "vec4 " + glsl.prefix + "march_" + glsl.name + "(vec3 origin, vec3 direction) {\n";
    s += krs::glsl::fill(R"(    float t0, t1;
    NAME_enter_box(origin, direction, t0, t1);
    float ds = NAME_step;
    vec3 color = vec3(0.0);
    float transmittance = 1.0;
    vec3 slope = NAME_slopes(direction);
    float margin0 = NAME_margin_at_origin(origin);
    for (float k = 0.0;;) {
        float t = t0 + (k + 0.5) * ds;
        if (!(t < t1)) break;
        vec3 p = origin + direction * t;
        ivec3 cell;
        float advance;
        int place = NAME_probe(p, slope, margin0 + t * NAME_rounding_per_step, cell, advance);
        if (place >= 0 && NAME_in_spheres(p)) {
            uvec2 v = NAME_voxel_at(place);
            if (v.x != 0u) {
                float a = NAME_alpha[int(v.x)];
                vec3 c = NAME_shade(NAME_shading_point(p, cell), int(v.y), -direction);
                color = color + transmittance * a * c;
                transmittance = transmittance * (1.0 - a);
            }
        }
        k += advance;
        if (!(transmittance >= NAME_min_transmittance)) break;
    }
    return vec4(color, transmittance);
}
)",
                           {{"NAME", n}});
    return s;
}

// The same for a store. It packs the store's bricks itself (a voxel_bricks copy of the store, then
// the buffer) only to read their sizes and offsets: a caller that uploads the bricks has packed them
// already and should pass those to the overload above rather than pack twice.
template <voxel_store S>
std::string hypertree_glsl(const S& store, const tree_shape& shape, const depth_colors& colors, const march_options& options,
                           const hypertree_glsl_options& glsl = {})
{
    return hypertree_glsl(store.volume(), pack_bricks(store), shape, colors, options, glsl);
}

} // namespace hypertree

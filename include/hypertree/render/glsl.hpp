#pragma once
// The hypertree raymarcher as GLSL (paper section 8 on a GPU): the loop of volume_marcher
// (marcher.hpp), emitted as a fragment-shader function that marches the same samples, stops at the
// same transmittance and shades with the same formulas, so a GPU image of a tree equals the CPU
// image up to the last bits of exp, pow and the float (not double) shading geometry.
//
//     const packed_volume texels = pack_volume(store);            // upload once as a 3D texture
//     const std::string code = hypertree_glsl(store, shape, colors, options);
//     // in the shader: vec4 m = march_hypertree(origin, unit_direction);
//     //                color = m.rgb + m.a * background;           // as render() composites
//
// Two parts, as NanoVDB splits a grid from the code that reads it:
//
// The volume is data: `pack_volume` writes the hypervolume's whole grid, two bytes per voxel
// (density, level), in the store's index order x + nx (y + ny z), which is also OpenGL's 3D
// texture order (x fastest, then rows along y, then slices along z). Upload it as an integer
// texture, so the shader reads the bytes themselves and no normalization can round them:
//
//     glPixelStorei(GL_UNPACK_ALIGNMENT, 1);
//     glTexImage3D(GL_TEXTURE_3D, 0, GL_RG8UI, nx, ny, nz, 0, GL_RG_INTEGER, GL_UNSIGNED_BYTE, bytes);
//     GL_TEXTURE_MIN_FILTER and GL_TEXTURE_MAG_FILTER = GL_NEAREST (integer textures are never filtered)
//
// and bind it to the sampler `<name>_volume` (a `usampler3D`, the shader's only uniform). Empty
// voxels are (0, 0); the shader reads the texel with texelFetch, no filtering, no wrapping.
//
// Everything else is constants in the code: the box, the grid and its mapping, the step, the
// opacity per density byte (the marcher's table, computed by the same double pow), the color per
// level, each axis's voxel centers (as the float the CPU rounds its double centers to, so per-voxel
// shadow rays start from the same point), the part spheres, the structure flows, the crown sphere,
// the lights and the shading weights. A tree with other options is new code; the volume texture
// stays.
//
// What the GPU leaves out: the brick occupancy bits, the shadow memo and the ray cache. Each only
// spares work on the CPU (a skipped brick is empty, a memoized shadow is a pure function of its
// voxel, a cached voxel equals the store's), and none changes a pixel, so the GPU computes the
// same values directly. The part-sphere test is kept (use_spheres): it also changes no pixel, but
// it is the paper's traversal and costs the GPU a few dot products against a texel fetch.
//
// Precision. Sample positions, the slab test, cell indices, opacities and the front-to-back sums
// are the same float operations in the same order as the C++ (bit for bit on llvmpipe when the
// C++ is built with -ffp-contract=off). The shading differs in its last bits: the CPU computes
// the crown depth and the flow normal in double, the GLSL in float (GLSL has no double exp, and
// doubles are slow on many GPUs), and GLSL's exp and pow are a few ulp from the C library's.
//
// The code is one text for GLSL 3.30 and 4.x (no #version line; a 4.3 context runs it in the tests).

#include "hypertree/render/marcher.hpp"
#include "krs/glsl/literal.hpp"

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <string>
#include <vector>

namespace hypertree {

// The grid of a store as the bytes of an RG8UI 3D texture: texels[2 i] = density and
// texels[2 i + 1] = level of voxel index i = x + width (y + height z).
struct packed_volume {
    int width = 0, height = 0, depth = 0; // the hypervolume's grid (texture size in texels)
    std::vector<std::uint8_t> texels;
    int level_count = 1; // 1 + the deepest level stored: the length of the shader's color table
};

// Refuses a grid whose texture would exceed `budget` (a dense copy of the whole hypervolume:
// 2 bytes per voxel, empty or not).
template <voxel_store S>
packed_volume pack_volume(const S& store, memory_budget budget = {})
{
    const hypervolume& v = store.volume();
    const std::uint64_t bytes = v.voxel_count() * 2;
    if (bytes > budget.bytes)
        throw invalid_parameter("pack_volume", "the texture (2 bytes per voxel of the whole grid) exceeds the memory budget",
                                std::to_string(bytes) + " bytes");
    packed_volume out;
    out.width = v.grid().x, out.height = v.grid().y, out.depth = v.grid().z;
    out.texels.assign(std::size_t(bytes), 0);
    store.for_each([&](voxel_index i, voxel value) {
        out.texels[2 * std::size_t(i)] = value.density;
        out.texels[2 * std::size_t(i) + 1] = value.level;
        out.level_count = std::max(out.level_count, int(value.level) + 1);
    });
    return out;
}

struct hypertree_glsl_options {
    // The march function is march_<name>; its constants and helpers are <name>_*, its sampler
    // <name>_volume. Distinct names let several trees share one shader.
    std::string name = "hypertree";
};

namespace detail {

using krs::glsl::float_literal, krs::glsl::vec3_literal;

inline std::string glsl_float_array(const std::string& name, const std::vector<float>& values)
{
    std::string s = "const float " + name + "[" + std::to_string(values.size()) + "] = float[" + std::to_string(values.size()) + "](";
    for (std::size_t i = 0; i < values.size(); ++i) s += (i ? (i % 8 ? ", " : ",\n    ") : "") + float_literal(values[i]);
    return s + ");\n";
}
inline std::string glsl_vec3_array(const std::string& name, const std::vector<krs::vec3f>& values)
{
    std::string s = "const vec3 " + name + "[" + std::to_string(values.size()) + "] = vec3[" + std::to_string(values.size()) + "](";
    for (std::size_t i = 0; i < values.size(); ++i) s += (i ? ",\n    " : "") + vec3_literal(values[i]);
    return s + ");\n";
}
// Every `$` of a template becomes the name prefix.
inline std::string with_name(std::string_view text, const std::string& name)
{
    std::string s;
    s.reserve(text.size() + 64);
    for (char c : text)
        if (c == '$')
            s += name;
        else
            s += c;
    return s;
}

} // namespace detail

// The GLSL of the marcher that volume_marcher(store, shape, colors, options) is: constants, the
// sampler uniform and `vec4 march_<name>(vec3 origin, vec3 direction)` returning the premultiplied
// color (rgb) and the remaining transmittance (a) of a ray with a unit direction, as
// march_result. The texture bound to <name>_volume must be pack_volume(store).
template <voxel_store S>
std::string hypertree_glsl(const S& store, const tree_shape& shape, const depth_colors& colors, const march_options& options,
                           const hypertree_glsl_options& glsl = {})
{
    using krs::glsl::float_literal, krs::glsl::vec3_literal;
    // The marcher validates the options and normalizes the lights; building one here makes the
    // same checks with the same messages.
    const volume_marcher<S> marcher(store, shape, colors, options);
    const std::string& n = glsl.name;
    const hypervolume& v = store.volume();
    int level_count = 1;
    store.for_each([&](voxel_index, voxel value) { level_count = std::max(level_count, int(value.level) + 1); });

    std::string s = "// hypertree volume marcher '" + n + "' (hypertree/render/glsl.hpp): the loop of volume_marcher.\n";
    s += "// " + n + "_volume: RG8UI 3D texture of pack_volume(store), r = density, g = level.\n";
    s += "uniform usampler3D " + n + "_volume;\n";
    // The grid, as the marcher's floats.
    s += "const vec3 " + n + "_box_lo = " + vec3_literal(krs::vec3f(shape.box.lo)) + ";\n";
    s += "const vec3 " + n + "_box_hi = " + vec3_literal(krs::vec3f(shape.box.hi)) + ";\n";
    s += "const vec3 " + n + "_origin = " + vec3_literal(krs::vec3f(v.origin())) + ";\n";
    s += "const vec3 " + n + "_cells_per_unit = " +
         vec3_literal(krs::vec3f(v.cells_per_unit())) + ";\n";
    s += "const ivec3 " + n + "_grid = ivec3(" + std::to_string(v.grid().x) + ", " + std::to_string(v.grid().y) + ", " +
         std::to_string(v.grid().z) + ");\n";
    s += "const float " + n + "_step = " + float_literal(marcher.step()) + ";\n";
    s += "const float " + n + "_min_transmittance = " + float_literal(options.min_transmittance) + ";\n";
    // Opacity of one step per density byte: alpha = 1 - (1 - mu)^(k ds / side), the marcher's table.
    {
        const double exponent = double(options.density_scale) * double(options.step_factor);
        std::vector<float> alpha(256);
        for (int d = 0; d < 256; ++d) alpha[std::size_t(d)] = d == 255 ? 1.0f : float(1.0 - std::pow(1.0 - d / 255.0, exponent));
        s += detail::glsl_float_array(n + "_alpha", alpha);
    }
    {
        std::vector<krs::vec3f> level_colors;
        for (int l = 0; l < level_count; ++l) {
            const rgb c = colors.at(l);
            level_colors.push_back({c.r, c.g, c.b});
        }
        s += "const int " + n + "_level_count = " + std::to_string(level_count) + ";\n";
        s += detail::glsl_vec3_array(n + "_level_color", level_colors);
    }
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
            s += detail::glsl_float_array(n + "_center_" + axes[a], centers);
        }
    }
    const bool spheres = options.use_spheres && !shape.spheres.empty();
    if (spheres) {
        // center and radius^2 (the float product the marcher compares with)
        const std::size_t count = shape.spheres.size();
        s += "const vec4 " + n + "_spheres[" + std::to_string(count) + "] = vec4[" + std::to_string(count) + "](";
        for (std::size_t i = 0; i < count; ++i) {
            const krs::bounding_sphere& b = shape.spheres[i];
            s += (i ? ",\n    vec4(" : "vec4(") + float_literal(b.center.x) + ", " + float_literal(b.center.y) + ", " +
                 float_literal(b.center.z) + ", " + float_literal(b.radius * b.radius) + ")";
        }
        s += ");\n";
    }
    if (!shape.flows.empty()) {
        std::vector<krs::vec3f> centroids, axes;
        std::vector<float> soft;
        for (const part_flow& f : shape.flows) {
            centroids.push_back({float(f.centroid.x), float(f.centroid.y), float(f.centroid.z)});
            axes.push_back({float(f.axis.x), float(f.axis.y), float(f.axis.z)});
            soft.push_back(float(f.weight_radius * f.weight_radius * 0.05));
        }
        s += detail::glsl_vec3_array(n + "_flow_centroid", centroids);
        s += detail::glsl_vec3_array(n + "_flow_axis", axes);
        s += detail::glsl_float_array(n + "_flow_soft", soft);
    }
    s += "const vec3 " + n + "_crown_center = " + vec3_literal(shape.crown.center) + ";\n";
    s += "const float " + n + "_crown_radius = " + float_literal(shape.crown.radius) + ";\n";
    {
        std::vector<krs::vec3f> directions, light_colors;
        for (const directional_light& l : options.lights) {
            const krs::vec3d d(l.direction);
            const krs::vec3d u = d / krs::length(d);
            directions.push_back({float(u.x), float(u.y), float(u.z)});
            light_colors.push_back({l.color.r, l.color.g, l.color.b});
        }
        s += "const int " + n + "_light_count = " + std::to_string(directions.size()) + ";\n";
        if (!directions.empty()) {
            s += detail::glsl_vec3_array(n + "_light_direction", directions);
            s += detail::glsl_vec3_array(n + "_light_color", light_colors);
        }
    }
    s += "const float " + n + "_ambient = " + float_literal(options.ambient) + ";\n";
    s += "const float " + n + "_ambient_falloff = " + float_literal(options.ambient_falloff) + ";\n";
    s += "const float " + n + "_diffuse = " + float_literal(options.diffuse) + ";\n";
    s += "const float " + n + "_specular = " + float_literal(options.specular) + ";\n";
    s += "const float " + n + "_shininess = " + float_literal(options.shininess) + ";\n";

    // Functions. Each mirrors the marcher member of the same name; sums are spelled out where
    // GLSL's dot or length might associate differently from krs::dot (x, then y, then z).
    s += detail::with_name(R"(float $_dot(vec3 a, vec3 b) { return a.x * b.x + a.y * b.y + a.z * b.z; }

// enter_box: the slab test, t0 >= 0; a ray that misses gets t0 >= t1. A zero direction component
// becomes tiny so the division gives a huge finite slope instead of inf * 0 = NaN.
void $_enter_box(vec3 o, vec3 d, out float t0, out float t1) {
    t0 = 0.0;
    t1 = 3.0e38;
    for (int a = 0; a < 3; ++a) {
        float safe = abs(d[a]) < 1e-30 ? 1e-30 : d[a];
        float inv = 1.0 / safe;
        float ta = ($_box_lo[a] - o[a]) * inv, tb = ($_box_hi[a] - o[a]) * inv;
        t0 = max(t0, min(ta, tb));
        t1 = min(t1, max(ta, tb));
    }
}

// The marcher's probe: the cell of p, false outside the grid (and outside every part sphere).
bool $_cell(vec3 p, out ivec3 cell) {
    cell = ivec3(0);
    float fx = (p.x - $_origin.x) * $_cells_per_unit.x, fy = (p.y - $_origin.y) * $_cells_per_unit.y,
          fz = (p.z - $_origin.z) * $_cells_per_unit.z;
    if (!(fx >= 0.0 && fy >= 0.0 && fz >= 0.0 && fx < float($_grid.x) && fy < float($_grid.y) && fz < float($_grid.z)))
        return false;
)",
                           n);
    if (spheres) {
        s += "    bool inside = false;\n";
        s += "    for (int i = 0; i < " + std::to_string(shape.spheres.size()) + "; ++i) {\n";
        s += detail::with_name(R"(        vec3 d = p - $_spheres[i].xyz;
        if ($_dot(d, d) <= $_spheres[i].w) {
            inside = true;
            break;
        }
    }
    if (!inside) return false;
)",
                               n);
    }
    s += detail::with_name(R"(    cell = ivec3(min(int(fx), $_grid.x - 1), min(int(fy), $_grid.y - 1), min(int(fz), $_grid.z - 1));
    return true;
}

// The voxel of a cell: x = density, y = level.
uvec2 $_voxel(ivec3 cell) { return texelFetch($_volume, cell, 0).xy; }

// fetch: the density at p, 0 outside the grid and the spheres.
int $_density_at(vec3 p) {
    ivec3 cell;
    return $_cell(p, cell) ? int($_voxel(cell).x) : 0;
}

// shadow_transmittance: from p toward the light l, starting one step out (as the C++ marcher:
// out of the shading voxel at step factor 1 on cubic voxels), with the primary ray's step and
// early exit.
float $_shadow_transmittance(vec3 p, vec3 l) {
    float t0, t1;
    $_enter_box(p, l, t0, t1);
    float transmittance = 1.0;
    float base = max(t0, 0.0);
    for (int j = 1;; ++j) {
        float t = base + float(j) * $_step;
        if (!(t < t1 && transmittance >= $_min_transmittance)) break;
        transmittance *= 1.0 - $_alpha[$_density_at(p + l * t)];
    }
    return transmittance;
}

// tree_shape::normal_at: the structure-flow normal (zero without flows).
vec3 $_normal(vec3 p) {
    vec3 n = vec3(0.0);
)",
                           n);
    if (!shape.flows.empty()) {
        s += "    for (int i = 0; i < " + std::to_string(shape.flows.size()) + "; ++i) {\n";
        s += detail::with_name(R"(        vec3 d = p - $_flow_centroid[i];
        vec3 radial = d - $_flow_axis[i] * $_dot(d, $_flow_axis[i]);
        float w = 1.0 / ($_dot(d, d) + $_flow_soft[i]);
        float len = sqrt($_dot(radial, radial));
        if (len > 0.0) n += radial * (w / len);
    }
)",
                               n);
    }
    s += detail::with_name(R"(    float len = sqrt($_dot(n, n));
    return len > 0.0 ? n / len : vec3(0.0);
}

// shade: Reeves' ambient falloff below the crown sphere, Lambert (and Blinn-Phong) with the flow
// normal, each light attenuated by its shadow ray.
vec3 $_shade(vec3 p, ivec3 cell, int level, vec3 view) {
    vec3 base = $_level_color[min(level, $_level_count - 1)];
    float depth = max(0.0, $_crown_radius - sqrt($_dot(p - $_crown_center, p - $_crown_center))) / max($_crown_radius, 1e-30);
    float ambient = $_ambient * exp(-$_ambient_falloff * depth);
    vec3 light = vec3(ambient), specular = vec3(0.0);
    vec3 n = $_normal(p);
    bool has_normal = n.x != 0.0 || n.y != 0.0 || n.z != 0.0;
)",
                           n);
    // (No lights: ambient only, and no loop over arrays GLSL could not declare with size 0.)
    if (!options.lights.empty()) {
        if (options.shadows) s += "    vec3 shadow_origin = p;\n";
        s += "    for (int i = 0; i < " + n + "_light_count; ++i) {\n";
        s += detail::with_name("        vec3 l = $_light_direction[i];\n", n);
        s += options.shadows ? detail::with_name("        float shadow = $_shadow_transmittance(shadow_origin, l);\n", n)
                             : "        float shadow = 1.0;\n";
        s += detail::with_name(R"(        float lambert = has_normal ? max(0.0, $_dot(n, l)) * 0.75 + 0.25 : 1.0;
        vec3 lc = $_light_color[i];
        float d = $_diffuse * lambert * shadow;
        light += d * lc;
)",
                               n);
        // GLSL leaves pow(0, 0) undefined where C gives 1: a shininess of 0 is emitted as the 1.
        const std::string highlight = options.shininess == 0 ? "1.0" : "pow(max(0.0, $_dot(n, h)), $_shininess)";
        if (options.specular > 0)
            s += detail::with_name(R"(        if (has_normal) {
            vec3 h = l + view;
            h = h / sqrt($_dot(h, h));
            float s = $_specular * )" + highlight + R"( * shadow;
            specular += s * lc;
        }
)",
                                   n);
        s += "    }\n";
    }
    s += detail::with_name(R"(    return base * light + specular;
}

)", n);
    // The shading point: the voxel's center with shade_per_voxel (the marcher's per-voxel shading),
    // else the sample itself.
    s += detail::with_name(options.shade_per_voxel ? "vec3 $_shading_point(vec3 p, ivec3 cell) {\n    return vec3($_center_x[cell.x], $_center_y[cell.y], $_center_z[cell.z]);\n}\n\n"
                                                   : "vec3 $_shading_point(vec3 p, ivec3 cell) {\n    return p;\n}\n\n",
                           n);
    s += detail::with_name(R"(// march: samples at t0 + (k + 1/2) ds (computed from k, as the marcher does), front to back, until the ray leaves the box or the
// transmittance falls below the minimum. Returns (premultiplied rgb, transmittance).
vec4 march_$(vec3 origin, vec3 direction) {
    float t0, t1;
    $_enter_box(origin, direction, t0, t1);
    float ds = $_step;
    vec3 color = vec3(0.0);
    float transmittance = 1.0;
    for (int k = 0;; ++k) {
        float t = t0 + (float(k) + 0.5) * ds;
        if (!(t < t1)) break;
        vec3 p = origin + direction * t;
        ivec3 cell;
        if ($_cell(p, cell)) {
            uvec2 v = $_voxel(cell);
            if (v.x != 0u) {
                float a = $_alpha[int(v.x)];
                vec3 c = $_shade($_shading_point(p, cell), cell, int(v.y), -direction);
                color = color + transmittance * a * c;
                transmittance = transmittance * (1.0 - a);
            }
        }
        if (!(transmittance >= $_min_transmittance)) break;
    }
    return vec4(color, transmittance);
}
)",
                           n);
    return s;
}

} // namespace hypertree

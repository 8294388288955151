// Every field type's GLSL against its C++, on llvmpipe: one small instance of each kernel and
// composite, its emitted distance run at 16,384 points (within 1e-5 of the sampled region's
// extent), and for kernels also the reflection bits and the kernel's own normal through a
// two-mirror sequence's locate and Algorithm 2 shading. The 450 code of each, in
// every data mode, is also compiled for Vulkan and validated (glslangValidator -V, spirv-val).
//
// The cases name the library types they exercise, and the last check reads the library's headers
// for every type that carries GLSL (a glsl_name, or a glsl_emit member) and fails for one that no
// case ran: a new field type cannot ship without being run here. It also fails for a field type
// (a class with a `distance` member) that carries no GLSL at all, which the first scan cannot see.
//
// The scan reads the headers rather than a list of types because a list would be one more thing to
// forget: C++ cannot enumerate a namespace's types, and the type a contributor forgets to run is
// the one they also forget to add to a list. The scan needs nothing from them.

#include "krs/compose.hpp"
#include "krs/fractal/fold_steps.hpp"
#include "krs/fractal/kifs.hpp"
#include "krs/fractal/log_tilings.hpp"
#include "krs/fractal/orbit_trap.hpp"
#include "krs/fractal/shell_presets.hpp"
#include "krs/fractal/similar_shell.hpp"
#include "krs/glsl/emitter.hpp"
#include "krs/glsl/shadertoy.hpp"
#include "krs/kernels/kernels.hpp"
#include "krs/kernels/tetrahedron.hpp"
#include "krs/sequence.hpp"

#include "support/gl_context.hpp"
#include "support/gpu_points.hpp"
#include "support/header_scan.hpp"
#include "support/random.hpp"

#include <doctest/doctest.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <iterator>
#include <regex>
#include <set>
#include <string>
#include <vector>

namespace {

using krs::vec3d;
using krs::vec3f;

// Types the cases below run (filled as they run; the coverage test reads it).
std::set<std::string>& covered()
{
    static std::set<std::string> names;
    return names;
}

// Points uniform in the box center +- half (seeded, the same on every platform).
std::vector<vec3f> box_points(vec3f center, vec3f half, std::size_t count, std::uint64_t seed)
{
    std::mt19937_64 g(seed);
    std::vector<vec3f> points(count);
    for (vec3f& p : points)
        p = center + vec3f{float(krs_test::uniform(g, -1, 1)) * half.x, float(krs_test::uniform(g, -1, 1)) * half.y,
                           float(krs_test::uniform(g, -1, 1)) * half.z};
    return points;
}

// The field's GLSL distance at 16,384 points against the C++, in both data modes.
template <class F>
void check_distance(const std::string& name, const F& field, vec3f center, vec3f half,
                    std::initializer_list<const char*> types)
{
    for (const char* t : types) covered().insert(t);
    const std::vector<vec3f> points = box_points(center, half, 16384, 0x5eed + name.size());
    const float extent = krs::length(half);
    for (const auto mode : {krs::glsl::data_mode::constants, krs::glsl::data_mode::buffer}) {
        krs::glsl::emitter e({krs::glsl::target::glsl450, mode, name + "_data", 0});
        const std::string fn = e.add(field, name); // krs_NAME, its data krs_NAME_data
        const bool buffer = mode == krs::glsl::data_mode::buffer;
        // A sequence emits NAME_locate; any other field gets one that reports nothing.
        std::string snippet = e.source();
        if constexpr (!requires(const F& f, vec3f p) { f.locate(p); })
            snippet += "krs_location " + fn + "_locate(vec3 p) { return krs_location(0.0, p, 0u, 0u, uvec2(0u)); }\n";
        const auto gpu = krs_test::run_points(snippet, fn, points, buffer ? e.data() : std::vector<float>{}, false,
                                              fn + "_data");
        float worst = 0;
        std::size_t exact = 0;
        for (std::size_t i = 0; i < points.size(); ++i) {
            const float d = field.distance(points[i]);
            worst = std::max(worst, std::abs(gpu[i].distance - d));
            exact += gpu[i].distance == d;
        }
        std::printf("%-18s %-9s points %zu  max |d_gpu - d_cpu| %.3g = %.3g of extent %.3g  bit-equal %zu\n",
                    name.c_str(), buffer ? "buffer" : "constants", points.size(), double(worst),
                    double(worst / extent), double(extent), exact);
        INFO(name << (buffer ? " buffer" : " constants"));
        CHECK(worst <= 1e-5f * extent);
    }
    // Vulkan: the 450 code of every data mode compiles to SPIR-V that spirv-val accepts.
    const std::string dir = std::string(KRS_BINARY_DIR) + "/glsl-check";
    std::filesystem::create_directories(dir);
    for (const auto mode : {krs::glsl::data_mode::constants, krs::glsl::data_mode::buffer,
                            krs::glsl::data_mode::uniform_buffer}) {
        krs::glsl::emitter e({krs::glsl::target::glsl450, mode, name + "_data", 0});
        const std::string fn = e.add(field, name);
        krs_test::validate_spirv(dir + "/" + name + ".vulkan." + std::string(krs::glsl::mode_name(mode)).substr(0, 3) +
                                     ".frag",
                                 e.source(true) + "layout(location = 0) out vec4 krs_out;\nvoid main() { krs_out = vec4(" +
                                     fn + "(vec3(0.5, 0.25, 0.125))); }\n");
    }
}

// A kernel through a sequence of itself and two mirrors: distance, locate's reflection bits and
// the kernel's own normal from NAME_shade (in the kernel-space point's slot), against the C++.
template <class K>
void check_kernel(const std::string& name, const K& kernel, const char* type)
{
    check_distance(name, kernel, kernel.bound().center, vec3f{1, 1, 1} * (1.5f * kernel.bound().radius), {type});
    // The colour a Shadertoy program gives the kind without a palette (docs/design.md, "A kernel",
    // step 3): compiling this names the kind in kernel_without_default_albedo<K> when it has none.
    const std::vector<vec3f> albedo = krs::glsl::palette_of(krs::sequence<K>{});
    REQUIRE(albedo.size() == 1);
    CHECK((albedo[0].x >= 0 && albedo[0].x <= 1 && albedo[0].y >= 0 && albedo[0].y <= 1 && albedo[0].z >= 0 &&
           albedo[0].z <= 1));
    typename krs::sequence<K>::builder b;
    b.kernel(kernel);
    b.mirror(krs::mirror(krs::normalize(vec3f{1.0f, 0.2f, 0.1f}), kernel.bound().center.x + 0.3f));
    b.mirror(krs::mirror(krs::normalize(vec3f{-0.1f, 1.0f, 0.3f}), kernel.bound().center.y + 0.2f));
    const krs::sequence<K> s = b.build();
    krs::glsl::emitter e({krs::glsl::target::glsl450, krs::glsl::data_mode::constants, name + "_pair_data", 0});
    const std::string seq = e.add(s, name + "_pair");
    // A locate whose kernel_point slot carries the shading normal.
    const std::string probe = seq + "_probe";
    const std::string snippet = e.source() + "float " + probe + "(vec3 p) { return " + seq + "(p); }\n" +
                                "krs_location " + probe + "_locate(vec3 p) {\n    krs_kernel_shading s = " + seq +
                                "_shade(p, vec3(0.0, 1.0, 0.0), vec3(1.0, 0.0, 0.0), 0.0);\n"
                                "    krs_location w = " + seq + "_locate(p);\n"
                                "    return krs_location(w.dist, s.normal, w.kernel, w.level, w.reflections);\n}\n";
    const krs::bounding_sphere bound = s.bound();
    const std::vector<vec3f> points = box_points(bound.center, vec3f{1, 1, 1} * bound.radius, 16384, 0xfeed);
    const auto gpu = krs_test::run_points(snippet, probe, points, {}, false, seq + "_data");
    const float extent = bound.radius;
    float worst_d = 0, worst_n = 0;
    std::size_t compared = 0, bits_equal = 0;
    for (std::size_t i = 0; i < points.size(); ++i) {
        worst_d = std::max(worst_d, std::abs(gpu[i].distance - s.distance(points[i])));
        const krs::location<float> where = s.locate(points[i]);
        // Within 1e-5 of the extent of a mirror the decision may go either way in the last bit.
        bool near = false;
        vec3f p = points[i];
        for (std::size_t m = s.mirror_count(); m-- > 0;) {
            const float e = s.mirrors()[m].signed_distance(p);
            near = near || std::abs(e) < 1e-5f * extent;
            if (e > 0) p = s.mirrors()[m].reflect(p);
        }
        if (near) continue;
        ++compared;
        bits_equal += gpu[i].reflections == where.reflections;
        worst_n = std::max(worst_n, krs::length(gpu[i].kernel_point - kernel.normal(where.kernel_point)));
    }
    std::printf("%-18s pair of mirrors: max |d_gpu - d_cpu| %.3g of extent %.3g, bits equal %zu/%zu, max |n_gpu - "
                "n_cpu| %.3g\n",
                name.c_str(), double(worst_d), double(extent), bits_equal, compared, double(worst_n));
    INFO(name);
    CHECK(worst_d <= 1e-5f * extent);
    CHECK(compared >= points.size() * 99 / 100);
    CHECK(bits_equal == compared);
    CHECK(worst_n <= 1e-4f);
    covered().insert("basic_sequence");
    covered().insert("mirror");
}

// The library's headers: every class or struct that carries GLSL (its body names glsl_name,
// glsl_parameters or glsl_emit, however declared).
std::set<std::string> types_with_glsl() { return krs_test::classes_with(std::regex(R"(\bglsl_(?:name|parameters|emit)\b)")); }
// Every field type: a class with a member `T distance(const vec3<T>& p) const` (rule 2's contract;
// the `const` after one parameter leaves out vec3.hpp's free distance(a, b)).
std::set<std::string> field_types()
{
    return krs_test::classes_with(std::regex(R"(\bT\s+distance\s*\(\s*const\s+vec3<T>\s*&\s*\w*\s*\)\s*const\b)"));
}

} // namespace

// One test case (one process), so that the last check sees every type the parts before it ran.
TEST_CASE("GLSL of every field type matches the C++ on llvmpipe, and every type with GLSL is run")
{
    check_kernel("sphere", krs::sphere({0.2f, 0.1f, -0.1f}, 0.6f), "sphere");
    check_kernel("capsule", krs::capsule({-0.3f, -0.2f, 0.1f}, {0.4f, 0.5f, -0.2f}, 0.25f), "capsule");
    check_kernel("box", krs::box({0.1f, 0.0f, 0.2f}, {0.5f, 0.3f, 0.4f}), "box");
    check_kernel("oriented_box",
                 krs::box({0.1f, 0.0f, 0.2f}, {0.5f, 0.3f, 0.4f}, krs::normalize(vec3f{1, 0.3f, 0}),
                          krs::normalize(vec3f{-0.3f, 1, 0}), {0, 0, 1}),
                 "box");
    check_kernel("capped_cylinder", krs::capped_cylinder({-0.2f, 0.1f, 0.3f}, {0.3f, 0.5f, -0.1f}, 0.3f),
                 "capped_cylinder");
    // Unbounded like the plane (a sequence pair needs a bound): distance only, over a box around it.
    check_distance("infinite_cylinder",
                   krs::infinite_cylinder({0.1f, -0.2f, 0.2f}, krs::normalize(vec3f{0.3f, 1.0f, -0.4f}), 0.3f),
                   {0.1f, -0.2f, 0.2f}, {1, 1, 1}, {"infinite_cylinder"});
    check_kernel("round_box", krs::round_box({0.1f, -0.1f, 0.2f}, {0.5f, 0.3f, 0.4f}, 0.12f), "round_box");
    check_kernel("octahedron", krs::octahedron({0.1f, 0.2f, -0.1f}, 0.6f), "octahedron");
    check_kernel("capped_cone", krs::capped_cone({-0.2f, 0.1f, 0.3f}, {0.3f, 0.5f, -0.1f}, 0.4f, 0.1f), "capped_cone");
    check_kernel("hexagonal_prism", krs::hexagonal_prism({0.1f, -0.1f, 0.2f}, 0.45f, 0.3f), "hexagonal_prism");
    check_kernel("torus", krs::torus({0.15f, 0.3f, 0.12f}, {0.3f, 1.0f, -0.2f}, 0.5f, 0.12f), "torus");
    check_kernel("torus_capsule", krs::torus_capsule({0, 0, 0}, {0.3f, 1.1f, 0}, {0.05f, 0.6f, 0}, 0.08f),
                 "torus_capsule");
    // A plane is unbounded: distance only, over a box around a point on it.
    check_distance("plane", krs::plane(krs::normalize(vec3f{0.2f, 1.0f, -0.1f}), 0.3f), {0, 0.3f, 0}, {2, 2, 2},
                   {"plane"});
    check_distance("tetrahedron", krs::tetrahedron{}, {0, 0, 0}, {1.6f, 1.6f, 1.6f}, {"tetrahedron"});
    // Orbit traps (krs/fractal/orbit_trap.hpp) are distances to their shapes: each kind run as a field
    // (KIFS colouring runs them along orbits: test_glsl_gpu.cpp).
    check_distance("orbit_trap_point", krs::orbit_trap::point({0.2f, -0.1f, 0.3f}), {0, 0, 0}, {2, 2, 2}, {"orbit_trap"});
    check_distance("orbit_trap_plane", krs::orbit_trap::plane({1, 2, -0.5f}, 0.3f), {0, 0, 0}, {2, 2, 2}, {"orbit_trap"});
    check_distance("orbit_trap_line", krs::orbit_trap::line({0.1f, 0.2f, 0}, {0.3f, -1, 0.7f}), {0, 0, 0}, {2, 2, 2},
                   {"orbit_trap"});
    check_distance("orbit_trap_shell", krs::orbit_trap::shell({0, 0.1f, 0}, 1.5f), {0, 0, 0}, {2, 2, 2}, {"orbit_trap"});

    // An axis-aligned KRS.
    krs::axis_sequence<krs::capsule, krs::sphere>::builder ab;
    ab.kernel(krs::capsule({0.1f, 0.0f, 0.1f}, {0.2f, 0.6f, 0.15f}, 0.05f));
    ab.kernel(krs::sphere({0.2f, 0.7f, 0.1f}, 0.08f));
    ab.mirror(krs::axis_mirror(0, 0.35f));
    ab.mirror(krs::axis_mirror(2, 0.4f, false));
    ab.mirror(krs::axis_mirror(1, 1.0f));
    const auto grid = ab.build();
    check_distance("axis_grid", grid, {0.4f, 1.0f, 0.3f}, {1.0f, 1.2f, 1.0f}, {"basic_sequence", "axis_mirror"});

    const krs::sphere ball({0.0f, 0.5f, 0.0f}, 0.5f);
    const krs::box block({0.6f, 0.2f, 0.1f}, {0.3f, 0.2f, 0.25f});
    check_distance("ball_and_block", krs::union_of<krs::sphere, krs::box>(ball, block), {0.3f, 0.4f, 0}, {1.2f, 1.2f, 1.2f},
                   {"union_of"});

    using twisted = krs::lipschitz_warp<krs::box, krs::twist_warp>;
    check_distance("twist", twisted(block, krs::twist_warp(1.5f, 2.0f)), {0.3f, 0.2f, 0}, {1.5f, 1.5f, 1.5f},
                   {"lipschitz_warp", "twist_warp"});
    using bent = krs::lipschitz_warp<krs::box, krs::bend_warp>;
    check_distance("bend", bent(block, krs::bend_warp(0.8f, 2.0f)), {0.3f, 0.2f, 0}, {1.5f, 1.5f, 1.5f},
                   {"lipschitz_warp", "bend_warp"});
    using noisy = krs::lipschitz_warp<krs::sphere, krs::noise_warp>;
    check_distance("noise", noisy(ball, krs::noise_warp(0.08f, 3.0f)), {0, 0.5f, 0}, {1.0f, 1.0f, 1.0f},
                   {"lipschitz_warp", "noise_warp", "value_noise_glsl"});

    // Wind (krs/compose/wind.hpp): a stem with a head swaying at several instants, the gust peak
    // (found by sampling a(t) every millisecond) among them, each instant's values from the data;
    // then NAME_at(p, time), the time passed by the shader, against the C++'s at(time).
    const krs::union_of<krs::capsule, krs::sphere> stem(krs::capsule({0, 0, 0}, {0, 1.2f, 0}, 0.08f),
                                                        krs::sphere({0, 1.3f, 0}, 0.2f));
    krs::wind breeze;
    breeze.direction = {1.0f, 0.0f, 0.4f};
    breeze.height = 1.4f;
    breeze.sway = 0.25f;
    breeze.gust = 0.3f;
    breeze.gust_period = 3.0f;
    float peak = 0;
    for (double t = 0; t < 30; t += 1e-3)
        if (std::abs(breeze.sway_at(t)) > std::abs(breeze.sway_at(double(peak)))) peak = float(t);
    const krs::swaying<krs::union_of<krs::capsule, krs::sphere>> swaying_stem(stem, breeze);
    const vec3f wind_center{0.3f, 0.7f, 0.1f}, wind_half{1.0f, 1.0f, 0.8f};
    const float instants[] = {0.0f, 1.3f, peak, 47.3f};
    for (std::size_t i = 0; i < 4; ++i)
        check_distance("wind_" + std::to_string(i), swaying_stem.at(instants[i]), wind_center, wind_half,
                       {"swaying", "wind", "wind_warp"});
    check_distance("wind_frozen", krs::lipschitz_warp<krs::box, krs::wind_warp>(block, breeze.warp_at(peak)),
                   {0.6f, 0.4f, 0.1f}, {1.0f, 1.0f, 1.0f}, {"lipschitz_warp", "wind_warp"});
    {
        const std::vector<vec3f> points = box_points(wind_center, wind_half, 16384, 0x3535);
        krs::glsl::emitter e({krs::glsl::target::glsl450, krs::glsl::data_mode::constants, "wind_live_data", 0});
        const std::string fn = e.add(swaying_stem, "wind_live");
        for (const float t : instants) {
            const std::string probe = fn + "_probe";
            const std::string snippet = e.source() + "float " + probe + "(vec3 p) { return " + fn + "_at(p, " +
                                        krs::glsl::float_literal(t) + "); }\nkrs_location " + probe +
                                        "_locate(vec3 p) { return krs_location(0.0, p, 0u, 0u, uvec2(0u)); }\n";
            const auto gpu = krs_test::run_points(snippet, probe, points, {}, false, fn + "_data");
            const auto now = swaying_stem.at(t);
            float worst = 0;
            for (std::size_t i = 0; i < points.size(); ++i) worst = std::max(worst, std::abs(gpu[i].distance - now.distance(points[i])));
            const float extent = krs::length(wind_half);
            std::printf("wind_live_at t = %-7.3f points %zu  max |d_gpu - d_cpu| %.3g = %.3g of extent %.3g\n", double(t),
                        points.size(), double(worst), double(worst / extent), double(extent));
            INFO("wind_live_at t = " << t);
            CHECK(worst <= 1e-5f * extent);
        }
    }

    // Bounded: far points take the sphere's distance, near ones the field's (margin 0.3).
    check_distance("bounded", krs::bounded<krs::box>(block, 0.3f), {0.6f, 0.2f, 0.1f}, {2.0f, 2.0f, 2.0f},
                   {"bounded"});
    // Empty zones: a zone cutting the ball, one deep inside it, one away from it.
    const krs::with_empty_zones<krs::sphere> cut(
        ball, {krs::bounding_sphere{{0.4f, 0.7f, 0.0f}, 0.3f}, krs::bounding_sphere{{0.0f, 0.5f, 0.0f}, 0.2f},
               krs::bounding_sphere{{-1.0f, 0.0f, 0.5f}, 0.25f}},
        0.1f);
    check_distance("zones", cut, {0, 0.5f, 0}, {1.2f, 1.2f, 1.2f}, {"with_empty_zones"});
    // Smooth blends (krs/compose/smooth.hpp): every operation, both shapes, the ball and block
    // overlapping so every seam is sampled.
    const vec3f seam{0.3f, 0.4f, 0}, reach{1.2f, 1.2f, 1.2f};
    check_distance("smooth_union", krs::smooth_union(ball, block, {0.2f}), seam, reach, {"smooth_blend"});
    check_distance("smooth_union_exp", krs::smooth_union(ball, block, {0.2f, krs::blend_shape::exponential}), seam,
                   reach, {"smooth_blend"});
    check_distance("smooth_intersect_exp",
                   krs::smooth_intersection(ball, block, {0.15f, krs::blend_shape::exponential}), seam, reach,
                   {"smooth_blend"});
    check_distance("smooth_subtract", krs::smooth_subtraction(ball, block, {0.1f}), seam, reach, {"smooth_blend"});
    // Placement (krs/compose/placed.hpp): a sheared, scaled and turned blend, moved off the origin.
    const krs::affine_map shear{{vec3d{1.3, 0.4, 0.0}, vec3d{-0.2, 0.7, 0.3}, vec3d{0.1, 0.0, 1.6}}, {2.0, -1.0, 0.5}};
    check_distance("placed", krs::placed(krs::smooth_union(ball, block, {0.2f}), shear), {2.4f, -0.6f, 0.6f},
                   {1.8f, 1.4f, 1.8f}, {"placed", "smooth_blend"});
    check_distance("rotated", krs::rotated(block, {0.3f, 1.0f, -0.2f}, 0.9f), {0.3f, 0.3f, 0}, reach, {"placed"});
    // Repetition (krs/compose/repeated.hpp): a ball in its cell on an endless xz lattice, and a
    // capsule crossing into its neighbours with counts on two axes.
    check_distance("repeated", krs::repeated(ball, {{1.3f}, {1.0f, 1}, {1.2f}}), {0.2f, 0.5f, -0.3f}, {4.0f, 1.5f, 4.0f},
                   {"repeated"});
    check_distance("repeated_counts",
                   krs::repeated(krs::capsule({-0.4f, 0.0f, 0.1f}, {0.9f, 0.35f, -0.2f}, 0.15f),
                                 {{1.0f, 5}, {0.9f, 2}, {1.2f}}),
                   {2.0f, 0.4f, 0.0f}, {4.0f, 2.0f, 3.0f}, {"repeated"});

    // A KIFS with every fold step kind.
    using steps = krs::fold_program<krs::abs_fold<krs::fold_x | krs::fold_z>, krs::plane_fold, krs::sort_fold,
                                    krs::rotate_step, krs::translate_step, krs::scale_about>;
    const krs::kifs<steps, krs::sphere> spiral(
        steps({}, krs::plane_fold(krs::normalize(vec3f{1, 1, 0}), 0.1f), {}, krs::rotate_step({0.0f, 1.0f, 0.0f}, 0.4f),
              krs::translate_step({0.1f, 0.0f, -0.2f}), krs::scale_about(1.6f, {1.0f, 0.5f, 0.0f})),
        krs::sphere({0.0f, 0.0f, 0.0f}, 0.5f), 5);
    check_distance("kifs", spiral, {0, 0, 0}, {1.6f, 1.6f, 1.6f},
                   {"kifs", "fold_program", "abs_fold", "plane_fold", "sort_fold", "rotate_step", "translate_step",
                    "scale_about"});

    // Log-polar and log-spherical tilings, and similar shells of both shipped prototypes.
    check_distance("log_polar", krs::log_polar_tiling<krs::sphere>(krs::sphere({0, 0, 0}, 0.3f), 12, 0.3f), {0, 0, 0},
                   {1.5f, 0.5f, 1.5f}, {"log_polar_tiling"});
    check_distance("log_spherical",
                   krs::log_spherical_tiling<krs::box>(krs::box({0, 0, 0}, {0.3f, 0.2f, 0.2f}), 16), {0, 0, 0},
                   {1.5f, 1.5f, 1.5f}, {"log_spherical_tiling"});
    check_distance("lotus", krs::make_recursive_lotus(1.0f, 8), {0, 0, 0}, {2.0f, 2.0f, 2.0f},
                   {"similar_shell", "lotus_shell"});
    check_distance("cube_shells", krs::make_cube_singularity(1.0f), {0, 0, 0}, {2.0f, 2.0f, 2.0f},
                   {"similar_shell", "cube_shell"});

    const std::set<std::string> with_glsl = types_with_glsl();
    std::printf("types with GLSL in include/krs: %zu; run by the cases above: %zu\n", with_glsl.size(), covered().size());
    // The scan must see the library (a broken pattern would find nothing and pass).
    CHECK(with_glsl.count("sphere") == 1);
    CHECK(with_glsl.count("union_of") == 1);
    CHECK(with_glsl.count("basic_sequence") == 1);
    for (const std::string& type : with_glsl) {
        INFO("krs::" << type << " has GLSL but no case of tests/test_glsl_field_types.cpp runs it");
        CHECK(covered().count(type) == 1);
    }
    const std::set<std::string> fields = field_types();
    CHECK(fields.count("sphere") == 1);
    CHECK(fields.count("lipschitz_warp") == 1);
    for (const std::string& type : fields) {
        INFO("krs::" << type << " is a field (it has distance) but carries no GLSL: give it glsl_name, glsl_source "
                                "and glsl_parameters(), or glsl_emit (docs/design.md#rule-4)");
        CHECK(with_glsl.count(type) == 1);
    }
}

// Kernels built from float vectors that user code just rounded from doubles must be the kernels
// of those floats: every stored member and every distance, bit for bit, equal to the same kernel
// built out of line from the same floats rounded through memory.
//
// Why a separate program: g++ 12.2 at -O2/-O3 (its SLP vectorizer) folds a vectorized
// (double)(float)x back to x. When a constructor that widens its float parameters to double (to
// normalize, to subtract) is inlined into code that made those floats from doubles, it computes
// with the unrounded doubles instead (docs/stability.md, "Double to float rounding"). The suite
// is built with its own flags; this program is built the way a user builds (tests/CMakeLists.txt:
// plain -O2 and -O3, portable and -march=native) and inlines the constructors into such code.
//
// The reference: each kernel built by a [[gnu::noinline]] factory from floats that went through
// a volatile float, which no optimizer may fold (tests/support/float_rounding.hpp).

#include "krs/kernels/kernels.hpp"

#include "support/float_rounding.hpp"

#include <bit>
#include <cmath>
#include <cstdint>
#include <cstdio>
#include <random>
#include <string>

namespace {

using krs::vec3d;
using krs::vec3f;
using krs_test::direction_of;
using krs_test::through_memory;

int failures = 0;
long checked = 0;


void expect_same(const std::string& what, float got, float expected)
{
    ++checked;
    // Read as user code does, widened to double: it must be a float, and the reference's float.
    const double widened = got;
    if (std::bit_cast<std::uint32_t>(got) != std::bit_cast<std::uint32_t>(expected) ||
        (widened == widened && double(through_memory(widened)) != widened)) {
        if (++failures <= 20)
            std::printf("%s: %.9g (as double %.17g), built out of line from the same floats: %.9g\n", what.c_str(),
                        double(got), widened, double(expected));
    }
}
void expect_same(const std::string& what, const vec3f& got, const vec3f& expected)
{
    expect_same(what + ".x", got.x, expected.x);
    expect_same(what + ".y", got.y, expected.y);
    expect_same(what + ".z", got.z, expected.z);
}

[[gnu::noinline]] krs::sphere sphere_of(vec3f c, float r) { return {c, r}; }
[[gnu::noinline]] krs::capsule capsule_of(vec3f a, vec3f b, float r) { return {a, b, r}; }
[[gnu::noinline]] krs::torus torus_of(vec3f c, vec3f axis, float major, float minor) { return {c, axis, major, minor}; }
[[gnu::noinline]] krs::torus_capsule torus_capsule_of(vec3f a, vec3f b, vec3f control, float r)
{
    return {a, b, control, r};
}
[[gnu::noinline]] krs::box box_of(vec3f c, vec3f h, vec3f x, vec3f y, vec3f z) { return {c, h, x, y, z}; }
[[gnu::noinline]] krs::plane plane_of(vec3f p, vec3f n) { return krs::plane::through(p, n); }

struct source {
    std::mt19937_64 engine{20261201};
    double uniform(double lo, double hi) { return std::uniform_real_distribution<double>(lo, hi)(engine); }
    vec3d point() { return {uniform(-10, 10), uniform(-10, 10), uniform(-10, 10)}; }
};

}  // namespace

// check_float_rounding_loop.cpp: the smallest shape found to show the fold at -O2 as well.
int directions_differing_in_a_short_loop();

int main()
{
    if (const int differing = directions_differing_in_a_short_loop(); differing > 0) {
        std::printf("short loop: %d of 4000 torus axes and plane normals are not their float input normalized\n",
                    differing);
        failures += differing;
    }
    source s;
    for (int i = 0; i < 2000; ++i) {
        // Parameters a user computed in double and hands over as float vectors.
        const vec3d c = s.point(), a = s.point(), b = s.point(), q = s.point();
        const double r = s.uniform(0.1, 2);
        const vec3f qf = through_memory(q);

        const krs::sphere sp{vec3f(c), float(r)};
        const krs::sphere sp_ref = sphere_of(through_memory(c), through_memory(r));
        expect_same("sphere.center", sp.center, sp_ref.center);
        expect_same("sphere.radius", sp.radius, sp_ref.radius);
        expect_same("sphere.distance", sp.distance(qf), sp_ref.distance(qf));

        const krs::capsule cap{vec3f(a), vec3f(b), float(r)};
        const krs::capsule cap_ref = capsule_of(through_memory(a), through_memory(b), through_memory(r));
        expect_same("capsule.a", cap.a, cap_ref.a);
        expect_same("capsule.b", cap.b, cap_ref.b);
        expect_same("capsule.distance", cap.distance(qf), cap_ref.distance(qf));
        expect_same("capsule.normal", cap.normal(qf), cap_ref.normal(qf));

        const krs::torus t{vec3f(c), vec3f(a), float(r + 1), float(r / 4)};
        const krs::torus t_ref = torus_of(through_memory(c), through_memory(a), through_memory(r + 1), through_memory(r / 4));
        expect_same("torus.center", t.center(), t_ref.center());
        expect_same("torus.axis", t.axis(), t_ref.axis());
        expect_same("torus.axis (the float axis, normalized)", t.axis(), direction_of(through_memory(a)));
        expect_same("torus.major_radius", t.major_radius(), t_ref.major_radius());
        expect_same("torus.minor_radius", t.minor_radius(), t_ref.minor_radius());
        expect_same("torus.distance", t.distance(qf), t_ref.distance(qf));
        expect_same("torus.normal", t.normal(qf), t_ref.normal(qf));

        const krs::torus_capsule tc{vec3f(a), vec3f(b), vec3f(q), float(r / 4)};
        const krs::torus_capsule tc_ref =
            torus_capsule_of(through_memory(a), through_memory(b), through_memory(q), through_memory(r / 4));
        expect_same("torus_capsule.start", tc.start(), tc_ref.start());
        expect_same("torus_capsule.end", tc.end(), tc_ref.end());
        expect_same("torus_capsule.control", tc.control(), tc_ref.control());
        expect_same("torus_capsule.plane_normal", tc.plane_normal(), tc_ref.plane_normal());
        expect_same("torus_capsule.toward_control", tc.toward_control(), tc_ref.toward_control());
        expect_same("torus_capsule.chord_direction", tc.chord_direction(), tc_ref.chord_direction());
        expect_same("torus_capsule.chord_middle", tc.chord_middle(), tc_ref.chord_middle());
        expect_same("torus_capsule.arc_midpoint", tc.arc_midpoint(), tc_ref.arc_midpoint());
        expect_same("torus_capsule.start_tangent", tc.start_tangent(), tc_ref.start_tangent());
        expect_same("torus_capsule.end_tangent", tc.end_tangent(), tc_ref.end_tangent());
        expect_same("torus_capsule.circle_center", tc.circle_center(), tc_ref.circle_center());
        expect_same("torus_capsule.circle_radius", tc.circle_radius(), tc_ref.circle_radius());
        expect_same("torus_capsule.curvature", tc.curvature(), tc_ref.curvature());
        expect_same("torus_capsule.half_chord", tc.half_chord(), tc_ref.half_chord());
        expect_same("torus_capsule.half_angle", tc.half_angle(), tc_ref.half_angle());
        expect_same("torus_capsule.half_arc_length", tc.half_arc_length(), tc_ref.half_arc_length());
        expect_same("torus_capsule.distance", tc.distance(qf), tc_ref.distance(qf));

        // An oriented box: a frame rotated about z by an angle, computed in double.
        const double phi = s.uniform(0, 6.28);
        const vec3d ux{std::cos(phi), std::sin(phi), 0}, uy{-std::sin(phi), std::cos(phi), 0}, uz{0, 0, 1};
        const vec3d h{r, r + 1, r + 2};
        const krs::box bx{vec3f(c), vec3f(h), vec3f(ux), vec3f(uy), vec3f(uz)};
        const krs::box bx_ref = box_of(through_memory(c), through_memory(h), through_memory(ux), through_memory(uy),
                                       through_memory(uz));
        expect_same("box.center", bx.center(), bx_ref.center());
        expect_same("box.half_extents", bx.half_extents(), bx_ref.half_extents());
        for (int k = 0; k < 3; ++k) expect_same("box.axis" + std::to_string(k), bx.axis(k), bx_ref.axis(k));
        expect_same("box.distance", bx.distance(qf), bx_ref.distance(qf));

        const krs::plane pl = krs::plane::through(vec3f(c), vec3f(a));
        const krs::plane pl_ref = plane_of(through_memory(c), through_memory(a));
        expect_same("plane.normal", pl.normal_direction, pl_ref.normal_direction);
        expect_same("plane.normal (the float normal, normalized)", pl.normal_direction, direction_of(through_memory(a)));
        expect_same("plane.offset", pl.offset, pl_ref.offset);
    }
    std::printf("%ld floats compared with kernels built out of line from the same floats: %d differ\n", checked,
                failures);
    return failures == 0 ? 0 : 1;
}

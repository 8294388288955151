// libFuzzer target: fractal field parameters decoded from bytes (issue 10, "fuzzing"): the KIFS
// presets, KIFS fold programs built from every fold step over each library kernel, log-polar and
// log-spherical tilings, and similar shells (presets and a user shell) with every seam mode. Each
// input either makes a constructor throw krs::invalid_parameter (fine) or builds a field whose
// distance is finite (float, double and packet lanes) at probe points derived from the bytes: near
// the fractal, out to the magnitude policy's reach |p| <= 1e9, and down to the origin, the warps'
// singularity (fuzz_input.hpp). Anything else (NaN or inf, another exception type, a sanitizer
// report) aborts.
//
// Input layout: byte 0 picks the field (mod 11), then its fields as fuzz_input.hpp decodes them,
// then probe points. fuzz/replay_main.cpp runs the same function over fuzz/corpus/fractals/ and
// fuzz/crashers/fractals/ in ctest.

#include "fuzz_input.hpp"

#include "krs/fractal/fold_steps.hpp"
#include "krs/fractal/kifs.hpp"
#include "krs/fractal/kifs_presets.hpp"
#include "krs/fractal/log_tilings.hpp"
#include "krs/fractal/shell_presets.hpp"
#include "krs/fractal/similar_shell.hpp"
#include "krs/kernels/sphere.hpp"
#include "krs/kernels/torus_capsule.hpp"

#include <climits>
#include <cstddef>
#include <cstdint>
#ifdef KRS_FUZZ_VERBOSE
#include <cstdio>
#endif

namespace {

using namespace krs;
using krs_fuzz::fail;
using krs_fuzz::probe;
using krs_fuzz::reader;

constexpr double fractal_reach = 4.0; // the presets live in [-2, 2]^3 or the unit shell

void fuzz_square(reader& in)
{
    const int iterations = in.integer(0, 20, -1, 21);
    probe(make_square_fractal(iterations, in.real(0.01f, 2.0f)), in, fractal_reach);
}

void fuzz_cube(reader& in) { probe(make_cube_fractal(in.integer(0, 20, -1, 21)), in, fractal_reach); }

void fuzz_menger(reader& in) { probe(make_menger_sponge(in.integer(0, 20, -1, 21)), in, fractal_reach); }

void fuzz_sierpinski(reader& in)
{
    const int iterations = in.integer(0, 30, -1, 31);
    probe(make_sierpinski_tetrahedron(iterations, in.real(1.01f, 4.0f)), in, fractal_reach);
}

void fuzz_koch(reader& in)
{
    const int iterations = in.integer(0, 12, -1, 13);
    probe(make_koch_curve(iterations, in.real(1e-4f, 0.1f)), in, fractal_reach);
}

// A fold program with one of every step kind (abs, plane fold, rotation, scale, translation), over
// the kernel picked by a byte. The steps' parameters span the policy's ranges through the special
// values; their in-range values keep the program contracting about as the presets do.
using general_program = fold_program<abs_fold<fold_xyz>, plane_fold, rotate_step, scale_about, translate_step>;

template <class Kernel>
void run_general(reader& in, const general_program& program, Kernel kernel)
{
    const int iterations = in.integer(0, 40, -1, 41);
    const kifs_taps taps = (in.byte() & 1) ? kifs_taps::last_iteration : kifs_taps::every_iteration;
    probe(kifs<general_program, Kernel>(program, std::move(kernel), iterations, taps), in, fractal_reach);
}

void fuzz_general_kifs(reader& in)
{
    const vec3f fold_normal = in.point(-1.0f, 1.0f);
    const float fold_offset = in.real(-1.0f, 1.0f);
    const vec3f axis = in.point(-1.0f, 1.0f);
    const float angle = in.real(-3.2f, 3.2f);
    const float factor = in.real(1.0f, 4.0f);
    const vec3f center = in.point(-2.0f, 2.0f);
    const vec3f shift = in.point(-1.0f, 1.0f);
    const general_program program(abs_fold<fold_xyz>{}, plane_fold(fold_normal, fold_offset), rotate_step(axis, angle),
                                  scale_about(factor, center), translate_step(shift));
    switch (in.byte() % 5) {
    case 0: {
        const vec3f c = in.point(-2.0f, 2.0f);
        run_general(in, program, sphere(c, in.real(0.0f, 1.0f)));
        break;
    }
    case 1: {
        const vec3f c = in.point(-2.0f, 2.0f);
        run_general(in, program, box(c, in.point(0.0f, 1.0f)));
        break;
    }
    case 2: {
        const vec3f a = in.point(-2.0f, 2.0f), b = in.point(-2.0f, 2.0f);
        run_general(in, program, capsule(a, b, in.real(0.0f, 0.5f)));
        break;
    }
    case 3: run_general(in, program, tetrahedron{}); break;
    default: {
        const vec3f s = in.point(-2.0f, 2.0f), e = in.point(-2.0f, 2.0f), c = in.point(-2.0f, 2.0f);
        run_general(in, program, torus_capsule(s, e, c, in.real(0.0f, 0.5f)));
        break;
    }
    }
}

// A tile: a sphere or a box in the cell's coordinates ([-1/2, 1/2] around and along).
template <class F>
void with_tile(reader& in, F&& f)
{
    const vec3f c = in.point(-0.5f, 0.5f);
    if (in.byte() & 1) f(sphere(c, in.real(0.0f, 0.5f)));
    else f(box(c, in.point(0.0f, 0.5f)));
}

void fuzz_log_polar(reader& in)
{
    const int cells = in.integer(1, 64, 0, 4097);
    const float height = in.real(0.0f, 2.0f), margin = in.real(0.01f, 0.5f);
    with_tile(in, [&](auto tile) { probe(log_polar_tiling(tile, cells, height, margin), in, fractal_reach); });
}

void fuzz_log_spherical(reader& in)
{
    // In range: the even counts 6 .. 64; otherwise odd, too few or too many.
    const int half = in.integer(3, 32, 2, 2049);
    const bool odd = (in.byte() & 7) == 0;
    const int cells = half == INT_MIN || half == INT_MAX ? half : (odd ? 2 * half + 1 : 2 * half);
    const float margin = in.real(0.01f, 0.5f);
    with_tile(in, [&](auto tile) { probe(log_spherical_tiling(tile, cells, margin), in, fractal_reach); });
}

shell_options read_shell_options(reader& in)
{
    shell_options o;
    const std::uint8_t seams = in.byte();
    o.seams = seams % 3 == 0 ? shell_seams::none : (seams % 3 == 1 ? shell_seams::adjacent_shells : shell_seams::hidden_boundary);
    o.hidden_cutoff = in.real(0.001f, 0.5f);
    o.step_factor = in.real(0.05f, 1.0f);
    o.seam_band = in.real(0.0f, 0.5f);
    return o;
}

void fuzz_lotus(reader& in)
{
    const float density = in.real(min_shell_density, 20.0f);
    const int petals = in.integer(1, 16, 0, 17);
    probe(make_recursive_lotus(density, petals, read_shell_options(in)), in, fractal_reach);
}

void fuzz_cube_singularity(reader& in)
{
    const float density = in.real(min_shell_density, 20.0f);
    probe(make_cube_singularity(density, read_shell_options(in)), in, fractal_reach);
}

// A user's shell: one sphere placed anywhere (the prototype shell is 1 <= |p| <= e^(1/density),
// but nothing forces the user's geometry to stay in it).
void fuzz_user_shell(reader& in)
{
    const float density = in.real(min_shell_density, 20.0f);
    const vec3f c = in.point(-3.0f, 3.0f);
    const sphere s(c, in.real(0.0f, 1.0f));
    probe(similar_shell<sphere>(s, density, read_shell_options(in)), in, fractal_reach);
}

} // namespace

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size)
{
    return krs_fuzz::run_one(data, size, [](reader& in) {
        switch (in.byte() % 11) {
        case 0: fuzz_square(in); break;
        case 1: fuzz_cube(in); break;
        case 2: fuzz_menger(in); break;
        case 3: fuzz_sierpinski(in); break;
        case 4: fuzz_koch(in); break;
        case 5: fuzz_general_kifs(in); break;
        case 6: fuzz_log_polar(in); break;
        case 7: fuzz_log_spherical(in); break;
        case 8: fuzz_lotus(in); break;
        case 9: fuzz_cube_singularity(in); break;
        default: fuzz_user_shell(in); break;
        }
    });
}

#pragma once
// KIFS presets: the kaleidoscopic IFS fractals of the source documents, each a fold program
// (krs/fractal/fold_steps.hpp) over a library kernel in the KIFS field (krs/fractal/kifs.hpp),
// with its iteration limit and parameters checked where it is made.

#include "krs/core/validate.hpp"
#include "krs/fractal/fold_steps.hpp"
#include "krs/fractal/kifs.hpp"
#include "krs/kernels/box.hpp"
#include "krs/kernels/capsule.hpp"
#include "krs/kernels/tetrahedron.hpp"

#include <cmath>
#include <numbers>
#include <string>
#include <string_view>

namespace krs {

namespace detail {
inline void require_iterations(std::string_view name, int iterations, int most)
{
    if (iterations < 0 || iterations > most)
        throw invalid_parameter(name, "must be in [0, " + std::to_string(most) + "]", std::to_string(iterations));
}
inline float require_contracting(std::string_view name, float scale)
{
    require_finite(name, scale);
    if (!(scale > 1.0f)) throw invalid_parameter(name, "must be > 1 (the IFS must contract)", detail::to_text(scale));
    return scale;
}
} // namespace detail

// The document's square-on-square fractal: a 2x2 square with a square three times smaller on each
// side, recursively. Two folds take the point into the wedge |y| <= x (the copy on +x), then the
// copy at (4/3, 0) is scaled up about (2, 0) (p' = 3 p - (4, 0), as in the document). The
// squares are boxes of half extents (1, 1, thickness): a relief plate in 3D, exact as the 2D
// field on z = 0 when thickness >= 1. (The document turns the lower wedge with a rotation; this
// reflects it instead, which gives the same distance because every copy is mirror-symmetric.)
using square_program = fold_program<plane_fold, plane_fold, scale_about>;
using square_fractal = kifs<square_program, box>;
inline square_fractal make_square_fractal(int iterations, float thickness = 0.25f)
{
    detail::require_iterations("square_fractal.iterations", iterations, 20);
    require_positive_length("square_fractal.thickness", thickness);
    return {square_program(plane_fold({1, -1, 0}, 0), plane_fold({1, 1, 0}, 0), scale_about(3, {2, 0, 0})),
            box({0, 0, 0}, {1, 1, thickness}), iterations, kifs_taps::every_iteration};
}

// Its 3D analogue: a cube with a cube three times smaller on each of its six faces. abs and two
// folds take the point into the region x >= |y|, |z| (the copy on +x).
using cube_program = fold_program<abs_fold<fold_xyz>, plane_fold, plane_fold, scale_about>;
using cube_fractal = kifs<cube_program, box>;
inline cube_fractal make_cube_fractal(int iterations)
{
    detail::require_iterations("cube_fractal.iterations", iterations, 20);
    return {cube_program(abs_fold<fold_xyz>{}, plane_fold({1, -1, 0}, 0), plane_fold({1, 0, -1}, 0),
                         scale_about(3, {2, 0, 0})),
            box({0, 0, 0}, {1, 1, 1}), iterations, kifs_taps::every_iteration};
}

// Menger sponge in [-1, 1]^3: abs and sort take the point into x >= y >= z >= 0, where the two
// sub-cubes left are the corner (2/3, 2/3, 2/3) and the edge cube (2/3, 2/3, 0). Scaling by 3
// about (1, 1, 0) blows the edge cube up; the fold on z = 1 maps the corner cube onto it (the
// usual "z -= 2 above z = 1" translation, made a reflection: same distance since the cube is
// symmetric, but continuous, so the field stays 1-Lipschitz).
using menger_program = fold_program<abs_fold<fold_xyz>, sort_fold, scale_about, plane_fold>;
using menger_sponge = kifs<menger_program, box>;
inline menger_sponge make_menger_sponge(int iterations)
{
    detail::require_iterations("menger_sponge.iterations", iterations, 20);
    return {menger_program(abs_fold<fold_xyz>{}, sort_fold{}, scale_about(3, {1, 1, 0}), plane_fold({0, 0, -1}, -1)),
            box({0, 0, 0}, {1, 1, 1}), iterations, kifs_taps::last_iteration};
}

// Sierpinski tetrahedron on the vertices of `tetrahedron`: three folds (planes x + y = 0,
// x + z = 0, y + z = 0) take the point to the copy at vertex (1, 1, 1), scaled up about it.
// scale 2 gives the classic gasket; larger scales leave gaps, scales in (1, 2) overlap.
using sierpinski_program = fold_program<plane_fold, plane_fold, plane_fold, scale_about>;
using sierpinski_tetrahedron = kifs<sierpinski_program, tetrahedron>;
inline sierpinski_tetrahedron make_sierpinski_tetrahedron(int iterations, float scale = 2.0f)
{
    detail::require_iterations("sierpinski_tetrahedron.iterations", iterations, 30);
    detail::require_contracting("sierpinski_tetrahedron.scale", scale);
    if (!(scale <= max_magnitude))
        throw invalid_parameter("sierpinski_tetrahedron.scale", "must be in (1, 1e9]", detail::to_text(scale));
    sierpinski_program program(plane_fold({1, 1, 0}, 0), plane_fold({1, 0, 1}, 0), plane_fold({0, 1, 1}, 0),
                               scale_about(scale, {1, 1, 1}));
    // Named here: the iteration limit depends on this preset's scale.
    detail::require_kifs_escape("sierpinski_tetrahedron.iterations", program, iterations, kifs_escape_limit);
    return {program, tetrahedron{}, iterations, kifs_taps::last_iteration};
}

// Koch curve from (-1, 0, 0) to (1, 0, 0) in the xy plane, as a tube of world radius
// `tube_radius`. abs folds the left half onto the right; the fold on the line through (1/3, 0) at
// 60 degrees maps the rising segment onto the last one, [1/3, 1], which scaling by 3 about (1, 0)
// blows up to the whole.
using koch_program = fold_program<abs_fold<fold_x>, plane_fold, scale_about>;
using koch_curve = kifs<koch_program, capsule>;
inline koch_curve make_koch_curve(int iterations, float tube_radius = 0.01f)
{
    detail::require_iterations("koch_curve.iterations", iterations, 12);
    require_positive_length("koch_curve.tube_radius", tube_radius);
    const float c = std::numbers::sqrt3_v<float> * 0.5f; // normal (cos -30, sin -30) of the 60-degree line
    // The capsule is the last generation blown up 3^iterations times: its radius must obey the
    // magnitude policy too.
    const double blown_up = double(tube_radius) * std::pow(3.0, iterations);
    if (!(blown_up <= double(max_magnitude)))
        throw invalid_parameter("koch_curve.tube_radius", "times 3^iterations must be <= 1e9",
                                detail::to_text(tube_radius) + " * 3^" + std::to_string(iterations));
    const float radius = tube_radius * float(std::pow(3.0, iterations));
    return {koch_program(abs_fold<fold_x>{}, plane_fold({c, -0.5f, 0}, c / 3.0f), scale_about(3, {1, 0, 0})),
            capsule({-1, 0, 0}, {1, 0, 0}, radius), iterations, kifs_taps::last_iteration};
}

} // namespace krs

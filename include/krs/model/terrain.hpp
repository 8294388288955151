#pragma once
// Terrain and rock builders: KRSs of plane kernels whose mirrors cross them (paper section 7.1).
//
// Neither is made of separated kernels: every detail is a crease where a mirror folds a plane.
// Algorithm 1 clips each kernel to its mirror's negative side (section 3), so the field is the
// distance to the clipped, creased surface, still a 1-Lipschitz underestimate. Shade them with
// shade_in_kernel_space (Algorithm 2), which smooths the creases, and texture them in world
// space (triplanar or 3D noise), since every facet shares its kernel's coordinates.
//
// Terrain: vertical mirrors fold the ground plane. With the vertical folds F (isometries of the
// xz plane, continuous) and a kernel plane tilted by slope s toward a direction a, the surface is
// the height field y = height + s * (a . F(x, z)): continuous and piecewise linear, with facets of
// one steepness turned every way by the folds. Mirror i is at a random angle at distance up to
// scale_i / 2 from the origin, scale_i = size * detail_ratio^(levels - 1 - i): the top (coarse)
// mirrors make the large valleys, the low ones the fine ridges. A few more kernels, each a plane
// of its own tilt added at a coarser level, are unions with the creased ground (the higher
// surface wins), which varies the steepness between regions.

#include "krs/kernels/plane.hpp"
#include "krs/model/tree.hpp"
#include "krs/sequence.hpp"

#include <cmath>
#include <cstdint>
#include <numbers>
#include <vector>

namespace krs::model {

using plane_sequence = sequence<plane>;

struct terrain_parameters {
    int levels = 24;              // mirrors, in [1, 60]: more levels, finer ridges
    float size = 40.0f;           // width of the coarsest folds, scene units, > 0
    float detail_ratio = 0.82f;   // scale ratio between consecutive levels, in [0.5, 0.99]
    float slope = 0.3f;           // steepness of the facets (rise over run), in [0, 2]
    int extra_planes = 3;         // more tilted planes at coarser levels, in [0, 16]
    float height = 0.0f;          // mean ground height at the origin
    std::uint32_t seed = 1;
};

inline plane_sequence build_terrain(const terrain_parameters& t)
{
    if (t.levels < 1 || t.levels > 60)
        throw invalid_parameter("terrain.levels", "must be in [1, 60]", std::to_string(t.levels));
    require_positive_length("terrain.size", t.size);
    detail::require_range("terrain.detail_ratio", t.detail_ratio, 0.5, 0.99);
    detail::require_range("terrain.slope", t.slope, 0.0, 2.0);
    if (t.extra_planes < 0 || t.extra_planes > 16)
        throw invalid_parameter("terrain.extra_planes", "must be in [0, 16]", std::to_string(t.extra_planes));
    require_magnitude("terrain.height", t.height);
    // The kernel planes' offsets are (height + lift) n.y with lift in [-size / 10, 0]: the magnitude
    // policy (krs/core/validate.hpp) holds for them when |height| + size / 10 does.
    if (!(std::abs(double(t.height)) + 0.1 * double(t.size) <= double(max_magnitude)))
        throw invalid_parameter("terrain.height", "|height| + size / 10 must be <= 1e9", krs::detail::to_text(t.height));

    detail::signed_unit_random random(t.seed);
    auto tilted = [&](double slope, double lift) {
        const double a = random() * std::numbers::pi;
        const vec3d n{-slope * std::cos(a), 1.0, -slope * std::sin(a)};
        const vec3d u = normalize(n);
        // y = height + lift + slope * (a . xz)  <=>  n . p <= height + lift, for the unit normal:
        return plane(detail::to_float(u), float((t.height + lift) * u.y));
    };
    // Which levels get an extra plane: spread over the upper half (coarse folds).
    std::vector<int> extra_level(std::size_t(t.levels) + 1, 0);
    for (int k = 0; k < t.extra_planes; ++k)
        ++extra_level[std::size_t(std::max(1, t.levels / 2 + (k * (t.levels - t.levels / 2)) / t.extra_planes))];

    plane_sequence::builder b;
    b.kernel(tilted(t.slope, 0.0));
    for (int i = 0; i < t.levels; ++i) {
        const double scale = t.size * std::pow(double(t.detail_ratio), double(t.levels - 1 - i));
        const double angle = random() * std::numbers::pi;
        const vec3f normal{float(std::cos(angle)), 0.0f, float(std::sin(angle))};
        b.mirror(mirror(normal, float(0.5 * scale * random())));
        for (int k = 0; k < extra_level[std::size_t(i) + 1]; ++k)
            b.kernel(tilted(t.slope * (0.3 + 0.7 * std::abs(random())), -0.05 * scale * (1.0 + std::abs(random()))));
    }
    return b.build();
}

// Rock: a faceted boulder. The lowest three mirrors pass through the center along a randomly
// turned orthonormal frame (unaligned with the world axes), folding space into one octant of that
// frame; the facet planes' outward normals lie within 20 degrees of the octant's diagonal, so in the
// octant each facet's solid n . q <= r is bounded (n . q >= cos(54.7 + 20 degrees) |q| > 0 there):
// the base is an octahedron-like solid of radius <= r / cos(74.7 deg). Above, `folds` mirrors
// through points within `fold_offset * radius` of the center and random normals each keep one side
// and mirror it onto the other, creasing and re-facetting the whole surface. A fold moves the
// solid's points by at most twice its offset from the center, so the rock stays within
//     bound radius = r / cos(74.7 deg) + sum_i 2 |offset_i|.
struct rock_parameters {
    vec3f center{0, 0, 0};
    float radius = 1.0f;      // distance of the facets from the center, > 0
    int facets = 3;           // facet planes, in [1, 16]
    int folds = 14;           // creasing mirrors, in [0, 58]
    float fold_offset = 0.2f; // how far from the center the creasing mirrors pass, in radii, [0, 0.5]
    std::uint32_t seed = 1;
};

struct rock {
    plane_sequence sequence;
    bounding_sphere bound{};
};

inline rock build_rock(const rock_parameters& r)
{
    require_magnitude("rock.center", r.center);
    require_positive_length("rock.radius", r.radius);
    // Facet and fold planes lie within |center| + radius of the origin: the magnitude policy
    // (krs/core/validate.hpp) holds for their offsets when that does.
    if (!(length(vec3d(r.center)) + double(r.radius) <= double(max_magnitude)))
        throw invalid_parameter("rock.radius", "|center| + radius must be <= 1e9", krs::detail::to_text(r.radius));
    if (r.facets < 1 || r.facets > 16)
        throw invalid_parameter("rock.facets", "must be in [1, 16]", std::to_string(r.facets));
    if (r.folds < 0 || r.folds > 58)
        throw invalid_parameter("rock.folds", "must be in [0, 58]", std::to_string(r.folds));
    detail::require_range("rock.fold_offset", r.fold_offset, 0.0, 0.5);

    detail::signed_unit_random random(r.seed);
    auto random_unit = [&] {
        for (;;) {
            const vec3d v{random(), random(), random()};
            const double l = length(v);
            if (l > 0.1 && l <= 1.0) return v / l;
        }
    };
    // A random orthonormal frame.
    const vec3d e0 = random_unit();
    vec3d e1 = random_unit();
    e1 = normalize(e1 - e0 * dot(e0, e1));
    const vec3d e2 = cross(e0, e1);
    const vec3d c(r.center);
    const vec3d diagonal = normalize(e0 + e1 + e2);

    plane_sequence::builder b;
    constexpr double max_tilt = 20.0 * std::numbers::pi / 180.0;
    for (int k = 0; k < r.facets; ++k) {
        // A normal within max_tilt of the diagonal: rotate the diagonal about a random axis
        // perpendicular to it.
        vec3d axis = random_unit();
        axis = axis - diagonal * dot(axis, diagonal);
        if (length(axis) < 1e-6) axis = e0 - diagonal * dot(e0, diagonal);
        axis = normalize(axis);
        const double tilt = max_tilt * std::abs(random());
        const vec3d n = detail::rotate(diagonal, axis, tilt);
        const double distance = r.radius * (0.85 + 0.15 * std::abs(random()));
        b.kernel(plane(detail::to_float(n), float(dot(n, c) + distance)));
    }
    // The octant fold: reflect where a frame coordinate is negative (normal -e, through c).
    for (const vec3d& e : {e0, e1, e2}) b.mirror(mirror::through(r.center, detail::to_float(-e)));
    double radius = r.radius / std::cos(max_tilt + std::acos(1.0 / std::sqrt(3.0)));
    for (int i = 0; i < r.folds; ++i) {
        const vec3d n = random_unit();
        const double offset = r.fold_offset * r.radius * random();
        b.mirror(mirror(detail::to_float(n), float(dot(n, c) + offset)));
        radius += 2.0 * std::abs(offset);
    }
    rock out;
    out.sequence = b.build();
    out.bound = bound_around(c, radius * 1.0001 + 1e-6);
    return out;
}

} // namespace krs::model

// Octahedron (krs/kernels/octahedron.hpp) against a reference built here another way: the least
// distance to its eight triangular faces, each by a point-triangle routine (the plane's foot
// point when it falls inside the triangle by barycentric coordinates, else the nearest of the
// three edges), signed by |x| + |y| + |z| <= size, in double at 10^5 points; against a dense
// sampling of the faces (never overestimates, zero on them). Also 1-Lipschitz on close random
// pairs, packet lanes (float and double) against the scalar path, bounds holding sampled inside
// points, normals against the central-difference gradient, refused parameters. Its GLSL runs on
// llvmpipe in test_glsl_field_types.cpp.

#include "krs/field.hpp"
#include "krs/kernels/octahedron.hpp"

#include "support/kernel_properties.hpp"
#include "support/rejects.hpp"
#include "support/random.hpp"

#include <doctest/doctest.h>

#include <algorithm>
#include <array>
#include <cfloat>
#include <cmath>
#include <limits>
#include <random>
#include <vector>

static_assert(krs::kernel<krs::octahedron>);

namespace {

using krs::vec3d;
using krs::vec3f;
using krs_test::uniform;

double triangle_distance(const vec3d& p, const vec3d& a, const vec3d& b, const vec3d& c)
{
    const vec3d n = krs::normalize(krs::cross(b - a, c - a));
    const double h = krs::dot(p - a, n);
    const vec3d foot = p - n * h;
    // Barycentric coordinates of the foot point by signed areas.
    const double area = krs::dot(krs::cross(b - a, c - a), n);
    const double wa = krs::dot(krs::cross(c - b, foot - b), n) / area, wb = krs::dot(krs::cross(a - c, foot - c), n) / area;
    const double wc = 1 - wa - wb;
    if (wa >= 0 && wb >= 0 && wc >= 0) return std::abs(h);
    return std::min({krs_test::segment_distance(p, a, b), krs_test::segment_distance(p, b, c), krs_test::segment_distance(p, c, a)});
}

struct octahedron_case {
    krs::octahedron kernel;
    vec3d center;
    double s, extent;
    octahedron_case(vec3f middle, float size) : kernel(middle, size), center(middle), s(size), extent(1.5 * size + 0.1)
    {
    }
    std::array<vec3d, 3> face(int octant) const
    {
        const double sx = octant & 1 ? -s : s, sy = octant & 2 ? -s : s, sz = octant & 4 ? -s : s;
        return {center + vec3d{sx, 0, 0}, center + vec3d{0, sy, 0}, center + vec3d{0, 0, sz}};
    }
    double reference(const vec3d& p) const
    {
        double d = INFINITY;
        for (int o = 0; o < 8; ++o) {
            const auto f = face(o);
            d = std::min(d, triangle_distance(p, f[0], f[1], f[2]));
        }
        const vec3d q = p - center;
        return std::abs(q.x) + std::abs(q.y) + std::abs(q.z) <= s ? -d : d;
    }
    std::vector<vec3d> surface(std::mt19937_64& g, int count) const
    {
        std::vector<vec3d> out;
        for (int i = 0; i < count; ++i) {
            const auto f = face(i % 8);
            double u = uniform(g, 0, 1), w = uniform(g, 0, 1);
            if (u + w > 1) u = 1 - u, w = 1 - w;
            out.push_back(f[0] + (f[1] - f[0]) * u + (f[2] - f[0]) * w);
        }
        return out;
    }
};

std::vector<octahedron_case> cases()
{
    return {octahedron_case({0, 0, 0}, 1.0f), octahedron_case({0.3f, -0.2f, 0.1f}, 0.45f),
            octahedron_case({1000, -999.5f, 1000.25f}, 0.7f)};
}

} // namespace

TEST_CASE("octahedron: distance, never overestimates, Lipschitz, lanes, normals")
{
    for (const octahedron_case& c : cases()) krs_test::check_kernel_field_properties(c);
}

TEST_CASE("octahedron: bound and bound_box hold inside points and reach the vertices")
{
    for (const octahedron_case& c : cases()) {
        std::vector<vec3d> vertices;
        for (int o = 0; o < 8; ++o)
            for (const vec3d& v : c.face(o)) vertices.push_back(v);
        krs_test::check_kernel_bounds(c, vertices);
        const krs::bounding_box box = c.kernel.bound_box();
        CHECK(double(box.hi.x) - (c.center.x + c.s) <= 1e-5 * (1 + std::abs(c.center.x)));
    }
}

TEST_CASE("octahedron: bad parameters are refused by name")
{
    const float nan = std::numeric_limits<float>::quiet_NaN();
    krs_test::rejects([] { krs::octahedron({0, 0, 0}, 0.0f); }, "octahedron.size");
    krs_test::rejects([] { krs::octahedron({0, 0, 0}, -1.0f); }, "octahedron.size");
    krs_test::rejects([&] { krs::octahedron({0, 0, 0}, nan); }, "octahedron.size");
    krs_test::rejects([&] { krs::octahedron({nan, 0, 0}, 1.0f); }, "octahedron.center");
}

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

[[gnu::noinline]] vec3f to_f(const vec3d& v) { return vec3f(v); }

double segment_distance(const vec3d& p, const vec3d& a, const vec3d& b)
{
    const vec3d ab = b - a;
    const double t = std::clamp(krs::dot(p - a, ab) / krs::dot(ab, ab), 0.0, 1.0);
    return krs::length(p - (a + ab * t));
}
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
    return std::min({segment_distance(p, a, b), segment_distance(p, b, c), segment_distance(p, c, a)});
}

struct octahedron_case {
    krs::octahedron kernel;
    vec3d c;
    double s, extent;
    octahedron_case(vec3f center, float size) : kernel(center, size), c(center), s(size), extent(1.5 * size + 0.1) {}
    std::array<vec3d, 3> face(int octant) const
    {
        const double sx = octant & 1 ? -s : s, sy = octant & 2 ? -s : s, sz = octant & 4 ? -s : s;
        return {c + vec3d{sx, 0, 0}, c + vec3d{0, sy, 0}, c + vec3d{0, 0, sz}};
    }
    double reference(const vec3d& p) const
    {
        double d = INFINITY;
        for (int o = 0; o < 8; ++o) {
            const auto f = face(o);
            d = std::min(d, triangle_distance(p, f[0], f[1], f[2]));
        }
        const vec3d q = p - c;
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

vec3d query(std::mt19937_64& g, const octahedron_case& c) { return vec3d(to_f(c.c + krs_test::in_ball(g, c.extent))); }
double tolerance_at(const vec3d& p, double extent) { return 8 * FLT_EPSILON * (krs::length(p) + extent); }

} // namespace

TEST_CASE("octahedron: distance against the eight faces' point-triangle distances at 10^5 points")
{
    for (const octahedron_case& c : cases()) {
        std::mt19937_64 g(31);
        int bad_f = 0, bad_d = 0, inside = 0;
        for (int i = 0; i < 100000; ++i) {
            const vec3d p = query(g, c);
            const double expected = c.reference(p);
            const double tolerance = tolerance_at(p, c.extent);
            bad_f += !(std::abs(double(c.kernel.distance(to_f(p))) - expected) <= tolerance);
            bad_d += !(std::abs(c.kernel.distance(p) - expected) <= tolerance);
            inside += expected < 0;
        }
        CHECK(bad_f == 0);
        CHECK(bad_d == 0);
        CHECK(inside > 1000);
    }
}

TEST_CASE("octahedron: never overestimates against dense surface sampling, zero on it")
{
    for (const octahedron_case& c : cases()) {
        std::mt19937_64 g(32);
        const std::vector<vec3d> surface = c.surface(g, 20000);
        int off_surface = 0, over = 0;
        for (const vec3d& s : surface) off_surface += !(std::abs(c.kernel.distance(s)) <= tolerance_at(s, c.extent));
        for (int i = 0; i < 1000; ++i) {
            const vec3d p = query(g, c);
            double nearest = INFINITY;
            for (const vec3d& s : surface) nearest = std::min(nearest, krs::length(p - s));
            over += !(double(c.kernel.distance(to_f(p))) <= nearest + tolerance_at(p, c.extent));
        }
        CHECK(off_surface == 0);
        CHECK(over == 0);
    }
}

TEST_CASE("octahedron: 1-Lipschitz, packet lanes, normals")
{
    for (const octahedron_case& c : cases()) {
        std::mt19937_64 g(33);
        int bad = 0;
        for (int i = 0; i < 100000; ++i) {
            const vec3d p = c.c + krs_test::in_ball(g, c.extent);
            const vec3d q = p + krs_test::in_ball(g, 1e-3 * c.extent);
            bad += !(std::abs(c.kernel.distance(p) - c.kernel.distance(q)) <= krs::length(p - q) * (1 + 1e-9) + 1e-12);
        }
        CHECK(bad == 0);
        const auto lanes = [&]<class P>(P) {
            using S = krs::scalar_t<P>;
            constexpr std::size_t width = krs::lane_count<P>;
            int mismatches = 0;
            for (int batch = 0; batch < 256; ++batch) {
                alignas(64) S x[width], y[width], z[width];
                for (std::size_t i = 0; i < width; ++i) {
                    const vec3d p = query(g, c);
                    x[i] = S(p.x), y[i] = S(p.y), z[i] = S(p.z);
                }
                const krs::vec3<P> p{P::load_aligned(x), P::load_aligned(y), P::load_aligned(z)};
                const P d = c.kernel.distance(p);
                const krs::vec3<P> n = c.kernel.normal(p);
                for (std::size_t i = 0; i < width; ++i) {
                    const krs::vec3<S> ps{x[i], y[i], z[i]};
                    const double scale = krs::length(vec3d(ps)) + c.extent;
                    mismatches += !(std::abs(double(krs::lane_at(d, i)) - double(c.kernel.distance(ps))) <= 1e-6 * scale);
                    mismatches += !(krs::length(vec3d(krs::lane_at(n, i)) - vec3d(c.kernel.normal(ps))) <= 1e-5);
                }
            }
            return mismatches;
        };
        CHECK(lanes(krs::packet_f{}) == 0);
        CHECK(lanes(krs::packet_d{}) == 0);
        const double e = 1e-6;
        int tested = 0, wrong = 0;
        for (int i = 0; i < 4000; ++i) {
            const vec3d p = query(g, c);
            auto d = [&](const vec3d& q) { return c.kernel.distance(q); };
            const vec3d gradient{(d(p + vec3d{e, 0, 0}) - d(p - vec3d{e, 0, 0})) / (2 * e),
                                 (d(p + vec3d{0, e, 0}) - d(p - vec3d{0, e, 0})) / (2 * e),
                                 (d(p + vec3d{0, 0, e}) - d(p - vec3d{0, 0, e})) / (2 * e)};
            const vec3d n(c.kernel.normal(to_f(p)));
            wrong += !(std::abs(krs::length(n) - 1) < 1e-5);
            if (std::abs(krs::length(gradient) - 1) > 1e-6) continue;
            ++tested;
            wrong += !(krs::length(n - gradient) < 1e-3);
        }
        CHECK(wrong == 0);
        CHECK(tested > 3000);
    }
}

TEST_CASE("octahedron: bound and bound_box hold inside points and reach the vertices")
{
    for (const octahedron_case& c : cases()) {
        std::mt19937_64 g(34);
        const krs::bounding_sphere b = c.kernel.bound();
        const krs::bounding_box box = c.kernel.bound_box();
        std::vector<vec3d> points = c.surface(g, 20000);
        int inside_points = 0, outside = 0;
        for (int i = 0; i < 20000; ++i) {
            const vec3d p = c.c + krs_test::in_ball(g, c.extent);
            if (c.reference(p) <= 0) points.push_back(p), ++inside_points;
        }
        for (int o = 0; o < 8; ++o)
            for (const vec3d& v : c.face(o)) points.push_back(v);
        for (const vec3d& p : points) {
            outside += !(krs::length(p - vec3d(b.center)) <= double(b.radius));
            outside += !(p.x >= box.lo.x && p.x <= box.hi.x && p.y >= box.lo.y && p.y <= box.hi.y && p.z >= box.lo.z &&
                         p.z <= box.hi.z);
        }
        CHECK(inside_points > 100);
        CHECK(outside == 0);
        CHECK(double(box.hi.x) - (c.c.x + c.s) <= 1e-5 * (1 + std::abs(c.c.x)));
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

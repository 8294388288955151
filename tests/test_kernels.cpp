// Kernel tests: every kernel's distance against an independent brute-force reference, the
// never-overestimate property, bounds, normals against finite differences, validation, and packet
// lanes against the scalar path.
//
// References. Each kernel's surface is described here independently of its implementation (a
// parametric curve swept by a ball, a set of face rectangles, a plane patch) and the distance is
// found by brute force: the nearest of a dense sampling (20000 points on a curve), then a ternary
// search on the parameter interval between the nearest sample's neighbours, where the squared
// distance is unimodal. Sampling alone would be accurate to half the sample spacing (about 1e-4
// here); the refinement brings the reference to about 1e-12, so the test tolerance is set by the
// kernel's own float rounding, not by the reference: 8 float ulps of the problem's scale
// (|p| + the radius of the query region). Parameters are stored as float, so a double lane
// evaluates the float-rounded geometry in double and the same tolerance applies to both lanes.

#include "krs/field.hpp"
#include "krs/kernels/kernels.hpp"
#include "support/random.hpp"

#include <doctest/doctest.h>

#include <array>
#include <cfloat>
#include <cmath>
#include <functional>
#include <numbers>
#include <random>
#include <string>
#include <string_view>
#include <vector>

namespace {

using krs::vec3d;
using krs::vec3f;

constexpr double float_ulp = FLT_EPSILON;

// GCC 12.2 at -O2/-O3 miscompiles a vectorized (double)(float)x into x (its SLP vectorizer plus
// a match.pd simplification drop the rounding), which made the same query point p take two values
// within one finite difference. Keeping the double -> float rounding out of line stops the
// caller from ever seeing both conversions. (Reproduced standalone; clang and -O1 are correct.)
// The library's own conversions now keep the rounding too (krs::convert_float, which vec3f(v)
// uses; tests/check_float_rounding.cpp); the out-of-line call stays as a second guard.
[[gnu::noinline]] vec3f to_f(const vec3d& v) { return vec3f(v); }

struct random_source {
    std::mt19937_64 engine;
    explicit random_source(unsigned seed) : engine(seed) {}
    double uniform(double lo, double hi) { return krs_test::uniform(engine, lo, hi); }
    vec3d unit()
    {
        for (;;) {
            const vec3d v{uniform(-1, 1), uniform(-1, 1), uniform(-1, 1)};
            const double l = krs::length(v);
            if (l > 0.1 && l <= 1) return v / l;
        }
    }
    // A float-representable point in the ball (c, r), so float lanes and the double reference
    // see the same point.
    vec3d query(const vec3d& c, double r)
    {
        for (;;) {
            const vec3d v{uniform(-1, 1), uniform(-1, 1), uniform(-1, 1)};
            if (krs::length(v) <= 1) return vec3d(to_f(c + v * r));
        }
    }
};

// Minimum of a function that is unimodal on [lo, hi].
template <class F>
double minimize_unimodal(F f, double lo, double hi, int iterations = 100)
{
    for (int i = 0; i < iterations; ++i) {
        const double m1 = lo + (hi - lo) / 3, m2 = hi - (hi - lo) / 3;
        if (f(m1) < f(m2))
            hi = m2;
        else
            lo = m1;
    }
    return std::min({f(lo), f(hi), f(0.5 * (lo + hi))});
}

// Distance from p to a parametric curve c(t), t in [0, 1].
struct curve_reference {
    std::function<vec3d(double)> at;
    std::vector<vec3d> samples;
    explicit curve_reference(std::function<vec3d(double)> f, int n = 20000) : at(std::move(f))
    {
        for (int i = 0; i < n; ++i) samples.push_back(at(double(i) / (n - 1)));
    }
    double distance(const vec3d& p) const
    {
        std::size_t best = 0;
        double best_d2 = INFINITY;
        for (std::size_t i = 0; i < samples.size(); ++i) {
            const double d2 = krs::length_squared(p - samples[i]);
            if (d2 < best_d2) best_d2 = d2, best = i;
        }
        const double n = double(samples.size() - 1);
        const double lo = best == 0 ? 0.0 : (best - 1) / n;
        const double hi = best + 1 == samples.size() ? 1.0 : (best + 1) / n;
        const double d2 = minimize_unimodal([&](double t) { return krs::length_squared(p - at(t)); }, lo, hi);
        return std::sqrt(std::min(d2, best_d2));
    }
    // Unit tangent by central difference (the reference's own, not the kernel's).
    vec3d tangent(double t) const
    {
        const double e = 1e-6;
        const double a = std::max(0.0, t - e), b = std::min(1.0, t + e);
        return krs::normalize(at(b) - at(a));
    }
};

// Distance from p to the rectangle origin + s u + t v, |s| <= su, |t| <= sv (u, v orthonormal):
// nested ternary search on a convex function.
double rectangle_distance(const vec3d& p, const vec3d& origin, const vec3d& u, const vec3d& v, double su, double sv)
{
    auto inner = [&](double s) {
        return minimize_unimodal(
            [&](double t) { return krs::length_squared(p - origin - u * s - v * t); }, -sv, sv, 80);
    };
    return std::sqrt(minimize_unimodal(inner, -su, su, 80));
}

// A random unit vector perpendicular to the unit vector t.
vec3d perpendicular_unit(random_source& rng, const vec3d& t)
{
    for (;;) {
        const vec3d v = rng.unit();
        const vec3d w = v - t * krs::dot(v, t);
        const double l = krs::length(w);
        if (l > 0.1) return w / l;
    }
}

// ---- reference descriptions of the kernels -------------------------------------------------------

// A tube of radius r around a curve, with ball caps: the surface samples are curve points plus
// r * (unit vector perpendicular to the tangent), and cap points on the outer hemispheres.
struct tube_case {
    curve_reference curve;
    double radius;
    std::vector<vec3d> surface(random_source& rng, int n) const
    {
        std::vector<vec3d> out;
        const bool point = krs::length(curve.at(1) - curve.at(0)) == 0; // a ball: no tangent
        for (int i = 0; i < n; ++i) {
            if (point) {
                out.push_back(curve.at(0) + rng.unit() * radius);
            } else if (i % 5 == 0) {
                const bool at_start = (i / 5) % 2 == 0;
                const double t = at_start ? 0.0 : 1.0;
                const vec3d outward = curve.tangent(t) * (at_start ? -1.0 : 1.0);
                vec3d v = rng.unit();
                if (krs::dot(v, outward) < 0) v = v - outward * (2 * krs::dot(v, outward));
                out.push_back(curve.at(t) + v * radius);
            } else {
                const double t = rng.uniform(0, 1);
                out.push_back(curve.at(t) + perpendicular_unit(rng, curve.tangent(t)) * radius);
            }
        }
        return out;
    }
    double reference(const vec3d& p) const { return curve.distance(p) - radius; }
};

// Arc from a through c to b on their circumcircle, by angle; built from the circumcenter
// formula, not from the kernel's midpoint/sagitta construction.
std::function<vec3d(double)> circumcircle_arc(const vec3f& start, const vec3f& end, const vec3f& control)
{
    const vec3d A(start), B(end), C(control);
    const vec3d a = A - C, b = B - C;
    const vec3d axb = krs::cross(a, b);
    const vec3d O = C + krs::cross(a * krs::length_squared(b) - b * krs::length_squared(a), axb) *
                            (-1.0 / (2 * krs::length_squared(axb)));
    const double R = krs::length(A - O);
    const vec3d e1 = (A - O) / R;
    const vec3d e2 = krs::normalize(krs::cross(krs::normalize(axb), e1));
    auto angle = [&](const vec3d& X) {
        const double phi = std::atan2(krs::dot(X - O, e2), krs::dot(X - O, e1));
        return phi < 0 ? phi + 2 * std::numbers::pi : phi;
    };
    const double phi_b = angle(B), phi_c = angle(C);
    const double sweep = phi_c < phi_b ? phi_b : phi_b - 2 * std::numbers::pi;
    return [=](double t) { return O + (e1 * std::cos(t * sweep) + e2 * std::sin(t * sweep)) * R; };
}

struct capsule_case : tube_case {
    krs::capsule kernel;
    std::string name;
    capsule_case(vec3f a, vec3f b, float r, std::string n)
        : tube_case{curve_reference([A = vec3d(a), B = vec3d(b)](double t) { return A + (B - A) * t; }), r},
          kernel(a, b, r), name(std::move(n))
    {
    }
};

struct torus_case : tube_case {
    krs::torus_capsule kernel;
    std::string name;
    torus_case(vec3f s, vec3f e, vec3f c, float r, std::string n)
        : tube_case{curve_reference(circumcircle_arc(s, e, c)), r}, kernel(s, e, c, r), name(std::move(n))
    {
    }
};

// A full circle of radius R around `axis` through `center`, by angle, from a frame built here
// (not the kernel's), swept by a ball of radius r. Closed, so it has no caps: its surface samples
// are the tube's sides only.
struct ring_case {
    curve_reference curve;
    double radius;
    krs::torus kernel;
    std::string name;
    static std::function<vec3d(double)> circle(vec3f center, vec3f axis, float major)
    {
        const vec3d a = krs::normalize(vec3d(axis)), c(center);
        const vec3d e1 = krs::normalize(krs::cross(a, std::abs(a.z) < 0.9 ? vec3d{0, 0, 1} : vec3d{1, 0, 0}));
        const vec3d e2 = krs::cross(a, e1);
        const double R = major;
        return [=](double t) {
            const double phi = 2 * std::numbers::pi * t;
            return c + (e1 * std::cos(phi) + e2 * std::sin(phi)) * R;
        };
    }
    ring_case(vec3f center, vec3f axis, float major, float minor, std::string n)
        : curve(circle(center, axis, major)), radius(minor), kernel(center, axis, major, minor), name(std::move(n))
    {
    }
    std::vector<vec3d> surface(random_source& rng, int n) const
    {
        std::vector<vec3d> out;
        for (int i = 0; i < n; ++i) {
            const double t = rng.uniform(0, 1);
            out.push_back(curve.at(t) + perpendicular_unit(rng, curve.tangent(t)) * radius);
        }
        return out;
    }
    double reference(const vec3d& p) const { return curve.distance(p) - radius; }
};

struct box_case {
    krs::box kernel;
    vec3d center, half, axes[3];
    std::string name;
    box_case(vec3f c, vec3f h, std::string n) : kernel(c, h), center(c), half(h), name(std::move(n))
    {
        axes[0] = {1, 0, 0}, axes[1] = {0, 1, 0}, axes[2] = {0, 0, 1};
    }
    box_case(vec3f c, vec3f h, vec3f x, vec3f y, vec3f z, std::string n)
        : kernel(c, h, x, y, z), center(c), half(h), name(std::move(n))
    {
        axes[0] = krs::normalize(vec3d(x)), axes[1] = krs::normalize(vec3d(y)), axes[2] = krs::normalize(vec3d(z));
    }
    double half_of(int i) const { return i == 0 ? half.x : i == 1 ? half.y : half.z; }
    double reference(const vec3d& p) const
    {
        double d = INFINITY;
        bool inside = true;
        for (int i = 0; i < 3; ++i) {
            const int j = (i + 1) % 3, k = (i + 2) % 3;
            for (double side : {-1.0, 1.0})
                d = std::min(d, rectangle_distance(p, center + axes[i] * (side * half_of(i)), axes[j], axes[k],
                                                   half_of(j), half_of(k)));
            inside = inside && std::abs(krs::dot(p - center, axes[i])) <= half_of(i);
        }
        return inside ? -d : d;
    }
    std::vector<vec3d> surface(random_source& rng, int n) const
    {
        std::vector<vec3d> out;
        for (int s = 0; s < n; ++s) {
            const int i = s % 3, j = (i + 1) % 3, k = (i + 2) % 3;
            const double side = (s / 3) % 2 ? 1.0 : -1.0;
            out.push_back(center + axes[i] * (side * half_of(i)) + axes[j] * (rng.uniform(-1, 1) * half_of(j)) +
                          axes[k] * (rng.uniform(-1, 1) * half_of(k)));
        }
        return out;
    }
};

struct plane_case {
    krs::plane kernel;
    vec3d point, n, u, v;
    std::string name;
    static constexpr double patch = 20; // half size of the reference patch; queries stay within 4
    plane_case(krs::plane k, vec3f point_, vec3f normal, std::string name_)
        : kernel(k), point(point_), n(krs::normalize(vec3d(normal))), name(std::move(name_))
    {
        const vec3d helper = std::abs(n.x) < 0.9 ? vec3d{1, 0, 0} : vec3d{0, 1, 0};
        u = krs::normalize(krs::cross(n, helper));
        v = krs::cross(n, u);
    }
    double reference(const vec3d& p) const
    {
        const double d = rectangle_distance(p, point, u, v, patch, patch);
        return krs::dot(p - point, n) > 0 ? d : -d;
    }
    std::vector<vec3d> surface(random_source& rng, int count) const
    {
        std::vector<vec3d> out;
        for (int i = 0; i < count; ++i) out.push_back(point + u * rng.uniform(-4, 4) + v * rng.uniform(-4, 4));
        return out;
    }
};

// Where to draw query points: around the bound, or around the plane's point.
template <class Case>
void query_region(const Case& c, vec3d& center, double& radius)
{
    if constexpr (requires { c.point; }) {
        center = c.point;
        radius = 4;
    } else {
        const krs::bounding_sphere b = c.kernel.bound();
        center = vec3d(b.center);
        radius = 1.5 * b.radius + 0.1;
    }
}
template <class Case>
double scale_of(const Case& c, const vec3d& p)
{
    vec3d center;
    double radius;
    query_region(c, center, radius);
    return krs::length(p) + radius;
}

template <class T, class K>
double distance_at(const K& k, const vec3d& p)
{
    return double(k.distance(krs::vec3<T>(p)));
}
template <class T, class K>
vec3d normal_at(const K& k, const vec3d& p)
{
    return vec3d(k.normal(krs::vec3<T>(p)));
}

// ---- the properties -------------------------------------------------------------------------------

template <class T, class Case>
void check_against_reference(const Case& c, int count = 2000, unsigned seed = 1)
{
    INFO(c.name);
    random_source rng(seed);
    vec3d center;
    double radius;
    query_region(c, center, radius);
    int inside = 0;
    double worst = 0;
    for (int i = 0; i < count; ++i) {
        const vec3d p = rng.query(center, radius);
        const double expected = c.reference(p);
        const double got = distance_at<T>(c.kernel, p);
        const double tolerance = 8 * float_ulp * scale_of(c, p);
        worst = std::max(worst, std::abs(got - expected) / tolerance);
        inside += expected < 0;
        if (!(std::abs(got - expected) <= tolerance)) {
            INFO("p = " << p.x << ", " << p.y << ", " << p.z);
            CHECK(got == doctest::Approx(expected).epsilon(0).scale(0));
        }
    }
    MESSAGE(c.name << ": worst error / tolerance " << worst);
    // The region reaches inside the solid (when it has one), so the sign is tested.
    bool solid = true;
    if constexpr (requires { c.radius; }) solid = c.radius > 0;
    if (solid) CHECK(inside > 0);
    CHECK(inside < count);
}

template <class T, class Case>
void check_never_overestimates(const Case& c, unsigned seed = 2)
{
    INFO(c.name);
    random_source rng(seed);
    const std::vector<vec3d> surface = c.surface(rng, 2000);
    vec3d center;
    double radius;
    query_region(c, center, radius);
    int failures = 0;
    for (const vec3d& s : surface) {
        // The surface is the zero set: vec3f rounding of s moves it by < 1 ulp.
        const double ds = distance_at<T>(c.kernel, vec3d(to_f(s)));
        const double tolerance = 8 * float_ulp * scale_of(c, s);
        if (!(std::abs(ds) <= tolerance)) ++failures;
    }
    CHECK(failures == 0);
    failures = 0;
    for (int i = 0; i < 300; ++i) {
        const vec3d p = rng.query(center, radius);
        const double d = distance_at<T>(c.kernel, p);
        const double tolerance = 8 * float_ulp * scale_of(c, p);
        for (const vec3d& s : surface)
            if (!(d <= krs::length(p - s) + tolerance)) ++failures;
    }
    CHECK(failures == 0);
}

template <class Case>
void check_bound(const Case& c, unsigned seed = 3)
{
    INFO(c.name);
    random_source rng(seed);
    const krs::bounding_sphere b = c.kernel.bound();
    REQUIRE(b.is_bounded());
    int outside = 0;
    for (const vec3d& s : c.surface(rng, 20000))
        if (!(krs::length(s - vec3d(b.center)) <= b.radius)) ++outside;
    CHECK(outside == 0);
}

// Normal against the central-difference gradient of the double distance. Points on a crease
// (medial surface, the core curve) are recognised by a gradient shorter than 1: away from
// creases the gradient of an exact distance has unit length.
template <class T, class Case>
void check_normal(const Case& c, unsigned seed = 4)
{
    INFO(c.name);
    random_source rng(seed);
    vec3d center;
    double radius;
    query_region(c, center, radius);
    const double h = 1e-6;
    int tested = 0;
    const int count = 2000;
    for (int i = 0; i < count; ++i) {
        const vec3d p = rng.query(center, radius);
        auto d = [&](const vec3d& q) { return distance_at<double>(c.kernel, q); };
        const vec3d g{(d(p + vec3d{h, 0, 0}) - d(p - vec3d{h, 0, 0})) / (2 * h),
                      (d(p + vec3d{0, h, 0}) - d(p - vec3d{0, h, 0})) / (2 * h),
                      (d(p + vec3d{0, 0, h}) - d(p - vec3d{0, 0, h})) / (2 * h)};
        const vec3d n = normal_at<T>(c.kernel, p);
        REQUIRE(std::abs(krs::length(n) - 1) < 1e-5);
        // (A float-stored unit normal is unit only to ~1e-7, so the test for "unit gradient" is 1e-6.)
        if (std::abs(krs::length(g) - 1) > 1e-6) continue;
        ++tested;
        if (!(krs::length(n - g) < 1e-3)) {
            INFO("p = " << p.x << ", " << p.y << ", " << p.z << "  n = " << n.x << ", " << n.y << ", " << n.z
                        << "  gradient = " << g.x << ", " << g.y << ", " << g.z);
            CHECK(krs::length(n - g) < 1e-3);
        }
    }
    CHECK(tested > count * 8 / 10);
}

// Every lane of a packet evaluates what the scalar path of its scalar type does: bit for bit,
// unless the target has FMA, where the compiler may contract a*b + c differently in the scalar
// and the packet code (GCC contracts by default); then within 4 ulps of the problem's scale
// for distances (32 for normals, divided by the distance).
template <class P, class Case>
void check_lanes(const Case& c, unsigned seed = 5)
{
    using S = krs::scalar_t<P>;
    constexpr std::size_t width = krs::lane_count<P>;
    INFO(c.name);
    random_source rng(seed);
    vec3d center;
    double radius;
    query_region(c, center, radius);
    int mismatches = 0;
    for (int batch = 0; batch < 64; ++batch) {
        alignas(64) S x[width], y[width], z[width];
        for (std::size_t i = 0; i < width; ++i) {
            const vec3d p = rng.query(center, radius);
            x[i] = S(p.x), y[i] = S(p.y), z[i] = S(p.z);
        }
        const krs::vec3<P> p{P::load_aligned(x), P::load_aligned(y), P::load_aligned(z)};
        const P d = c.kernel.distance(p);
        const krs::vec3<P> n = c.kernel.normal(p);
        for (std::size_t i = 0; i < width; ++i) {
            const krs::vec3<S> ps{x[i], y[i], z[i]};
            const krs::vec3<S> ns = c.kernel.normal(ps), nl = krs::lane_at(n, i);
#ifdef __FMA__
            const double tolerance = 4 * std::numeric_limits<S>::epsilon() * scale_of(c, vec3d(ps));
            // A normal is an offset divided by its length, so its rounding grows as 1 / distance.
            const double normal_tolerance = 32 * std::numeric_limits<S>::epsilon() * scale_of(c, vec3d(ps)) /
                                            std::max(1e-2, std::abs(double(c.kernel.distance(ps))));
#else
            const double tolerance = 0, normal_tolerance = 0;
#endif
            if (!(std::abs(double(krs::lane_at(d, i)) - double(c.kernel.distance(ps))) <= tolerance) ||
                !(krs::length(vec3d(nl) - vec3d(ns)) <= normal_tolerance)) {
                ++mismatches;
                MESSAGE("lane " << i << " p = " << ps.x << ", " << ps.y << ", " << ps.z << " d " << krs::lane_at(d, i)
                                << " vs " << c.kernel.distance(ps) << " n " << nl.x << ", " << nl.y << ", " << nl.z
                                << " vs " << ns.x << ", " << ns.y << ", " << ns.z);
            }
        }
    }
    CHECK(mismatches == 0);
}

template <class Case>
void check_lanes_all(const Case& c)
{
    check_lanes<krs::packet_f>(c);
    check_lanes<krs::packet_d>(c);
}

template <class F>
void expect_invalid(F make, const std::string& parameter)
{
    CAPTURE(parameter);
    bool thrown = false;
    try {
        make();
    } catch (const krs::invalid_parameter& e) {
        thrown = true;
        CHECK(e.parameter() == parameter);
        CHECK(std::string(e.what()).find(parameter) != std::string::npos);
    }
    CHECK(thrown);
}

const float nan_f = std::numeric_limits<float>::quiet_NaN();
const float inf_f = std::numeric_limits<float>::infinity();

// ---- the kernels under test -----------------------------------------------------------------------

std::vector<plane_case> plane_cases()
{
    const vec3f p{0.3f, -0.2f, 0.5f}, n{1, 2, -0.5f};
    const vec3f n2{0, 0, 3};
    return {plane_case(krs::plane::through(p, n), p, n, "plane through a point"),
            plane_case(krs::plane(n2, -0.75f), {0, 0, -0.75f}, n2, "plane z <= -0.75")};
}
std::vector<capsule_case> capsule_cases()
{
    return {capsule_case({-0.5f, 0.2f, 0.1f}, {0.7f, -0.3f, 0.4f}, 0.35f, "capsule"),
            capsule_case({0.25f, 0.5f, -1}, {0.25f, 0.5f, -1}, 0.5f, "capsule with a == b"),
            capsule_case({0, 0, 0}, {0, 0, 2}, 0.0f, "capsule of radius 0")};
}
// Rotation of the standard frame by `angle` about `axis`, columns as world vectors.
void rotated_frame(vec3d axis, double angle, vec3f out[3])
{
    axis = krs::normalize(axis);
    const vec3d e[3] = {{1, 0, 0}, {0, 1, 0}, {0, 0, 1}};
    for (int i = 0; i < 3; ++i) // Rodrigues
        out[i] = to_f(e[i] * std::cos(angle) + krs::cross(axis, e[i]) * std::sin(angle) +
                      axis * (krs::dot(axis, e[i]) * (1 - std::cos(angle))));
}
std::vector<box_case> box_cases()
{
    vec3f f[3];
    rotated_frame({1, 2, 3}, 0.7, f);
    return {box_case({0.1f, -0.2f, 0.3f}, {0.6f, 0.3f, 0.45f}, "axis-aligned box"),
            box_case({-0.4f, 0.25f, 0.1f}, {0.5f, 0.2f, 0.35f}, f[0], f[1], f[2], "oriented box"),
            box_case({0, 0, 0}, {0.5f, 0.0f, 0.3f}, f[0], f[1], f[2], "flat oriented box (a rectangle)")};
}
std::vector<torus_case> torus_cases()
{
    return {torus_case({-1, 0.2f, 0.1f}, {0.8f, -0.1f, 0.3f}, {0.1f, 0.6f, -0.2f}, 0.2f, "minor arc"),
            torus_case({-1, 0, 0}, {1, 0, 0}, {0, 1, 0}, 0.25f, "semicircle"),
            // 270 degrees: start and end a quarter turn apart, control opposite their midpoint.
            torus_case({1, 0, 0.5f}, {0, 1, 0.5f}, {-0.70710678f, -0.70710678f, 0.5f}, 0.3f, "major arc (270 deg)"),
            torus_case({0.3f, 0.2f, -0.4f}, {-0.2f, 0.5f, 0.6f}, {0.9f, 0.1f, 0.2f}, 0.1f, "major arc (general)"),
            torus_case({1000, 1000.5f, 999}, {1001.5f, 1000, 1000}, {1000.8f, 1001, 999.7f}, 0.2f,
                       "arc far from the origin")};
}

std::vector<ring_case> ring_cases()
{
    return {ring_case({0, 0, 0}, {0, 0, 1}, 1.0f, 0.2f, "ring around z"),
            ring_case({0.3f, -0.2f, 0.5f}, {0.4f, 0.8f, -0.3f}, 0.7f, 0.15f, "tilted ring"),
            ring_case({2, 1, -1}, {1, 0, 0}, 2.5f, 0.05f, "thin wide ring"),
            ring_case({1000, 1000.5f, 999}, {0.2f, 1, 0.1f}, 1.0f, 0.3f, "ring far from the origin")};
}


// The regular tetrahedron's four faces, sampled uniformly (barycentric, folded into the triangle).
// Its distance is a bound, exact only inside and over the faces, so there is no brute-force
// reference to match: the properties are that its zero set is this surface, that it never
// overestimates, and that its normal and bounds hold.
struct tetrahedron_case {
    krs::tetrahedron kernel;
    std::string name = "regular tetrahedron";
    std::vector<vec3d> surface(random_source& rng, int n) const
    {
        const vec3d v[4] = {{1, 1, 1}, {-1, -1, 1}, {1, -1, -1}, {-1, 1, -1}};
        std::vector<vec3d> out;
        for (int s = 0; s < n; ++s) {
            const int skip = s % 4; // the face opposite vertex `skip`
            const vec3d a = v[(skip + 1) % 4], b = v[(skip + 2) % 4], c = v[(skip + 3) % 4];
            double u = rng.uniform(0, 1), w = rng.uniform(0, 1);
            if (u + w > 1) u = 1 - u, w = 1 - w;
            out.push_back(a + (b - a) * u + (c - a) * w);
        }
        return out;
    }
};
} // namespace

// ---- plane ----------------------------------------------------------------------------------------

TEST_CASE_TEMPLATE("plane: distance against brute force, never overestimates, normal, no bound", T, float, double)
{
    for (const plane_case& c : plane_cases()) {
        check_against_reference<T>(c, 500);
        check_never_overestimates<T>(c);
        check_normal<T>(c);
        // A half-space has no finite bound.
        CHECK_FALSE(c.kernel.bound().is_bounded());
    }
}

TEST_CASE("plane: packet lanes equal the scalar path")
{
    for (const plane_case& c : plane_cases()) check_lanes_all(c);
}

TEST_CASE("plane: through() puts the point on the plane")
{
    const vec3f p{1.5f, -2, 0.25f};
    const krs::plane k = krs::plane::through(p, {0.3f, -1, 2});
    CHECK(std::abs(k.distance(vec3d(p))) < 4 * float_ulp * 2.5);
    CHECK(k.distance(vec3d(p) + vec3d(k.normal_direction) * 0.5) == doctest::Approx(0.5).epsilon(1e-6));
}

TEST_CASE("plane: invalid parameters are named")
{
    expect_invalid([] { krs::plane({0, 0, 0}, 1); }, "plane.normal");
    expect_invalid([] { krs::plane({nan_f, 0, 1}, 1); }, "plane.normal");
    expect_invalid([] { krs::plane({0, 0, 1}, nan_f); }, "plane.offset");
    expect_invalid([] { krs::plane({0, 0, 1}, inf_f); }, "plane.offset");
    expect_invalid([] { krs::plane::through({0, 0, 0}, {0, 0, 0}); }, "plane.normal");
    expect_invalid([] { krs::plane::through({0, nan_f, 0}, {0, 0, 1}); }, "plane.point");
}

// ---- capsule --------------------------------------------------------------------------------------

TEST_CASE_TEMPLATE("capsule: distance against brute force, never overestimates, normal", T, float, double)
{
    for (const capsule_case& c : capsule_cases()) {
        check_against_reference<T>(c);
        check_never_overestimates<T>(c);
        check_normal<T>(c);
    }
}

TEST_CASE("capsule: bound holds the surface, packet lanes equal the scalar path")
{
    for (const capsule_case& c : capsule_cases()) {
        check_bound(c);
        check_lanes_all(c);
    }
}

TEST_CASE("capsule: invalid parameters are named")
{
    expect_invalid([] { krs::capsule({0, 0, 0}, {1, 0, 0}, -0.1f); }, "capsule.radius");
    expect_invalid([] { krs::capsule({0, 0, 0}, {1, 0, 0}, nan_f); }, "capsule.radius");
    expect_invalid([] { krs::capsule({nan_f, 0, 0}, {1, 0, 0}, 1); }, "capsule.a");
    expect_invalid([] { krs::capsule({0, 0, 0}, {1, inf_f, 0}, 1); }, "capsule.b");
}

// ---- box ------------------------------------------------------------------------------------------

TEST_CASE_TEMPLATE("box: distance against brute force, never overestimates, normal", T, float, double)
{
    for (const box_case& c : box_cases()) {
        if (c.half.y > 0) check_against_reference<T>(c, 2000);
        check_never_overestimates<T>(c);
        check_normal<T>(c);
    }
}

TEST_CASE("box: a flat box matches brute force (its inside is empty)")
{
    const box_case c = box_cases()[2];
    random_source rng(11);
    for (int i = 0; i < 2000; ++i) {
        const vec3d p = rng.query({0, 0, 0}, 1.0);
        const double tolerance = 16 * float_ulp * (krs::length(p) + 1);
        CHECK(std::abs(distance_at<float>(c.kernel, p) - c.reference(p)) <= tolerance);
    }
}

TEST_CASE("box: bound holds the surface, packet lanes equal the scalar path")
{
    for (const box_case& c : box_cases()) {
        check_bound(c);
        check_lanes_all(c);
    }
}

TEST_CASE("box: invalid parameters are named")
{
    const vec3f x{1, 0, 0}, y{0, 1, 0}, z{0, 0, 1};
    expect_invalid([] { krs::box({0, 0, 0}, {1, -0.5f, 1}); }, "box.half_extents");
    expect_invalid([] { krs::box({0, 0, 0}, {1, nan_f, 1}); }, "box.half_extents");
    expect_invalid([] { krs::box({nan_f, 0, 0}, {1, 1, 1}); }, "box.center");
    expect_invalid([&] { krs::box({0, 0, 0}, {1, 1, 1}, x, {0.1f, 1, 0}, z); }, "box.axes");
    expect_invalid([&] { krs::box({0, 0, 0}, {1, 1, 1}, x, y, {0, 0, 1.01f}); }, "box.axes");
    expect_invalid([&] { krs::box({0, 0, 0}, {1, 1, 1}, x, y, {0, 0, 0}); }, "box.axes");
    expect_invalid([&] { krs::box({0, 0, 0}, {1, 1, 1}, x, {0, inf_f, 0}, z); }, "box.axes");
    // Within 1e-4 of orthonormal is accepted.
    CHECK_NOTHROW(krs::box({0, 0, 0}, {1, 1, 1}, x, {0.00005f, 1, 0}, z));
}

// ---- torus_capsule --------------------------------------------------------------------------------

TEST_CASE_TEMPLATE("torus_capsule: distance against brute force, never overestimates, normal", T, float, double)
{
    for (const torus_case& c : torus_cases()) {
        check_against_reference<T>(c);
        check_never_overestimates<T>(c);
        check_normal<T>(c);
    }
}

TEST_CASE("torus_capsule: bound holds the surface, packet lanes equal the scalar path")
{
    for (const torus_case& c : torus_cases()) {
        check_bound(c);
        check_lanes_all(c);
    }
}

TEST_CASE("torus_capsule: the 270 degree case really is a 3/4 turn")
{
    const krs::torus_capsule k({1, 0, 0.5f}, {0, 1, 0.5f}, {-0.70710678f, -0.70710678f, 0.5f}, 0.3f);
    CHECK(k.is_major_arc());
    CHECK(k.half_angle() == doctest::Approx(0.75 * std::numbers::pi).epsilon(1e-6));
    CHECK(k.curvature() == doctest::Approx(1.0).epsilon(1e-6));
    CHECK(krs::length(vec3d(k.circle_center()) - vec3d{0, 0, 0.5}) < 1e-6);
    // Points just off the arc where the minor arc would be, and where the major arc is.
    // In the gap the nearest arc points are the ends, not the circle.
    CHECK(k.distance(vec3d{0.70710678, 0.70710678, 0.5}) ==
          doctest::Approx(std::sqrt(2 - std::sqrt(2.0)) - 0.3).epsilon(1e-5));
    CHECK(k.distance(vec3d{0.5, 0.5, 0.5}) == doctest::Approx(std::sqrt(0.5) - 0.3).epsilon(1e-5));
    CHECK(k.distance(vec3d{-1, 0, 0.5}) == doctest::Approx(-0.3).epsilon(1e-5));
}

TEST_CASE_TEMPLATE("torus_capsule: collinear control is the capsule", T, float, double)
{
    const vec3f s{-0.7f, 0.2f, 0.4f}, e{0.9f, -0.4f, 0.1f};
    const float r = 0.3f;
    const krs::capsule cap(s, e, r);
    for (float f : {0.5f, 0.1f, 0.93f}) {
        const vec3f c = to_f(vec3d(s) + (vec3d(e) - vec3d(s)) * double(f));
        const krs::torus_capsule k(s, e, c, r);
        CHECK(k.curvature() == 0.0f);
        random_source rng(21);
        for (int i = 0; i < 2000; ++i) {
            const vec3d p = rng.query({0, 0, 0}, 2.0);
            const double tolerance = 8 * float_ulp * (krs::length(p) + 1.5);
            const double dk = distance_at<T>(k, p), dc = distance_at<T>(cap, p);
            CHECK(std::abs(dk - dc) <= tolerance);
            const vec3d nk = normal_at<T>(k, p), nc = normal_at<T>(cap, p);
            if (std::abs(dc + r) > 1e-3) CHECK(krs::length(nk - nc) < 1e-4); // normals agree off the core
        }
    }
}

TEST_CASE_TEMPLATE("torus_capsule: near-collinear control is stable", T, float, double)
{
    const vec3f s{-1, 0.25f, 0}, e{1, 0.25f, 0.5f};
    const float r = 0.2f;
    const vec3d sd(s), ed(e);
    const double chord = krs::length(ed - sd);
    const vec3d bulge = krs::normalize(krs::cross(ed - sd, vec3d{0, 0, 1}));
    const krs::capsule cap(s, e, r);
    for (double offset : {1e-3, 1e-4, 1e-5, 1e-6, 1e-7, 1e-8}) {
        CAPTURE(offset);
        const vec3f c = to_f((sd + ed) * 0.5 + bulge * (offset * chord));
        const krs::torus_capsule k(s, e, c, r);
        // The arc's sagitta is the control point's (rounded) distance from the chord.
        const vec3d cd(c), t = (ed - sd) / chord;
        const double sagitta = krs::length((cd - sd) - t * krs::dot(cd - sd, t));
        random_source rng(31);
        bool finite = true;
        for (int i = 0; i < 2000; ++i) {
            const vec3d p = rng.query((sd + ed) * 0.5, 1.6);
            const double dk = distance_at<T>(k, p), dc = distance_at<T>(cap, p);
            finite = finite && std::isfinite(dk) && krs::is_finite(normal_at<T>(k, p));
            const double tolerance = 8 * float_ulp * (krs::length(p) + 1.5);
            CHECK(std::abs(dk - dc) <= sagitta + tolerance);
        }
        CHECK(finite);
        CHECK(sagitta <= offset * chord + float_ulp); // + the rounding of control to float
        // And against the circumcircle reference, which the bend must still follow.
        if (k.curvature() > 0) {
            const torus_case tc(s, e, c, r, "near-collinear");
            check_against_reference<T>(tc, 300, 32);
        }
    }
}

TEST_CASE_TEMPLATE("torus_capsule: a near-full circle of large radius is accurate near its ends", T, float, double)
{
    // Control just off the chord's extension: a major arc of radius ~400 around a gap of width 2.
    // Near the gap the distance must be as accurate as the gap's own scale allows, not the
    // circle's (a formula anchored at the far arc midpoint would lose ulp(800) here).
    const torus_case c({-1, 0, 0}, {1, 0, 0}, {3, 0.01f, 0}, 0.1f, "near-full circle");
    REQUIRE(c.kernel.is_major_arc());
    CHECK(c.kernel.circle_radius() > 300);
    random_source rng(41);
    double worst = 0;
    for (int i = 0; i < 2000; ++i) {
        const vec3d p = rng.query({0, 0, 0}, 2.0);
        const double tolerance = 8 * float_ulp * (krs::length(p) + 2);
        const double error = std::abs(distance_at<T>(c.kernel, p) - c.reference(p));
        worst = std::max(worst, error / tolerance);
    }
    CHECK(worst <= 1);
}

TEST_CASE("torus_capsule: uv runs along the arc and around the tube")
{
    for (const torus_case& c : torus_cases()) {
        INFO(c.name);
        const krs::torus_capsule& k = c.kernel;
        for (int i = 0; i <= 100; ++i) {
            const double t = i / 100.0;
            const vec3d on = c.curve.at(t);
            // Outward from the circle center in the arc plane.
            const vec3d center(k.circle_center());
            const vec3d out = krs::normalize((on - center) - vec3d(k.plane_normal()) *
                                                                 krs::dot(on - center, vec3d(k.plane_normal())));
            const vec3d lift = krs::normalize(krs::cross(c.curve.tangent(t), out));
            const auto uv_out = k.uv(on + out * 0.1);
            CHECK(std::abs(uv_out.u - t) < 1e-4);
            CHECK(uv_out.v == doctest::Approx(0.5).epsilon(1e-4));
            const auto uv_up = k.uv(on + lift * 0.1), uv_down = k.uv(on - lift * 0.1);
            CHECK(std::abs(uv_up.v - uv_down.v) == doctest::Approx(0.5).epsilon(1e-4));
            CHECK(std::min(uv_up.v, uv_down.v) == doctest::Approx(0.25).epsilon(1e-4));
        }
        // Beyond the ends u clamps.
        CHECK(k.uv(vec3d(k.start()) - vec3d(k.start_tangent()) * 0.5).u == 0.0);
        CHECK(k.uv(vec3d(k.end()) - vec3d(k.end_tangent()) * 0.5).u == 1.0);
    }
}

TEST_CASE("torus_capsule: uv of packet lanes matches the scalar path")
{
    // xsimd's atan2 and libm's differ by an ulp or so, hence the tolerance.
    for (const torus_case& c : torus_cases()) {
        INFO(c.name);
        random_source rng(51);
        vec3d center;
        double radius;
        query_region(c, center, radius);
        constexpr std::size_t width = krs::lane_count<krs::packet_f>;
        for (int batch = 0; batch < 32; ++batch) {
            alignas(64) float x[width], y[width], z[width];
            for (std::size_t i = 0; i < width; ++i) {
                const vec3d p = rng.query(center, radius);
                x[i] = float(p.x), y[i] = float(p.y), z[i] = float(p.z);
            }
            const krs::vec3fP p{krs::packet_f::load_aligned(x), krs::packet_f::load_aligned(y),
                                krs::packet_f::load_aligned(z)};
            const auto uv = c.kernel.uv(p);
            for (std::size_t i = 0; i < width; ++i) {
                const auto s = c.kernel.uv(vec3f{x[i], y[i], z[i]});
                CHECK(std::abs(krs::lane_at(uv.u, i) - s.u) <= 1e-5f);
                CHECK(std::abs(krs::lane_at(uv.v, i) - s.v) <= 1e-5f);
            }
        }
    }
}

TEST_CASE("torus and torus_capsule: uv at points of no direction is finite and the same on packets")
{
    // The centre, points on the axis and on the generating circle have no angle around it: atan2
    // sees (0, 0) there. xsimd's atan2 made those lanes NaN where the scalar path gave 0.5.
    const krs::torus ring({0, 0, 0}, {0, 0, 1}, 1.0f, 0.25f);
    const krs::torus_capsule arc({-1, 0, 0}, {1, 0, 0}, {0, 1, 0}, 0.1f);
    const krs::torus_capsule straight({-1, 0, 0}, {1, 0, 0}, {0, 0, 0}, 0.1f);
    const auto agree = [](const auto& kernel, const vec3f& p) {
        INFO(p.x, " ", p.y, " ", p.z);
        const auto s = kernel.uv(p);
        const auto q = kernel.uv(krs::vec3fP{krs::packet_f(p.x), krs::packet_f(p.y), krs::packet_f(p.z)});
        REQUIRE(std::isfinite(s.u));
        REQUIRE(std::isfinite(s.v));
        for (std::size_t i = 0; i < krs::lane_count<krs::packet_f>; ++i) {
            CHECK(krs::lane_at(q.u, i) == doctest::Approx(s.u).epsilon(1e-5));
            CHECK(krs::lane_at(q.v, i) == doctest::Approx(s.v).epsilon(1e-5));
        }
    };
    for (const vec3f& p : {vec3f{0, 0, 0}, vec3f{1, 0, 0}, vec3f{0, 0, 5}, vec3f{-1, 0, 0}, vec3f{0, -1, 0}}) agree(ring, p);
    // The arc's circle is centred at (0, 0, 0) through (+-1, 0, 0) and (0, 1, 0).
    for (const vec3f& p : {vec3f{0, 0, 0}, vec3f{0, 1, 0}, vec3f{-1, 0, 0}, vec3f{1, 0, 0}, vec3f{0, 0, 3}}) agree(arc, p);
    for (const vec3f& p : {vec3f{0, 0, 0}, vec3f{-1, 0, 0}, vec3f{0.5f, 0, 0}}) agree(straight, p);
}

TEST_CASE("torus_capsule: invalid parameters are named")
{
    const vec3f s{0, 0, 0}, e{2, 0, 0}, c{1, 1, 0};
    expect_invalid([&] { krs::torus_capsule(s, e, c, -0.1f); }, "torus_capsule.radius");
    expect_invalid([&] { krs::torus_capsule(s, e, c, nan_f); }, "torus_capsule.radius");
    expect_invalid([&] { krs::torus_capsule({nan_f, 0, 0}, e, c, 0.1f); }, "torus_capsule.start");
    expect_invalid([&] { krs::torus_capsule(s, {2, inf_f, 0}, c, 0.1f); }, "torus_capsule.end");
    expect_invalid([&] { krs::torus_capsule(s, e, {1, nan_f, 0}, 0.1f); }, "torus_capsule.control");
    expect_invalid([&] { krs::torus_capsule(s, s, c, 0.1f); }, "torus_capsule.end");
    expect_invalid([&] { krs::torus_capsule(s, e, s, 0.1f); }, "torus_capsule.control");
    expect_invalid([&] { krs::torus_capsule(s, e, e, 0.1f); }, "torus_capsule.control");
    expect_invalid([&] { krs::torus_capsule(s, e, {3, 0, 0}, 0.1f); }, "torus_capsule.control");
    expect_invalid([&] { krs::torus_capsule(s, e, {-1, 0, 0}, 0.1f); }, "torus_capsule.control");
    // Collinear between start and end is a straight branch, not an error.
    CHECK_NOTHROW(krs::torus_capsule(s, e, {0.5f, 0, 0}, 0.1f));
}

// ---- torus ---------------------------------------------------------------------------------------

TEST_CASE_TEMPLATE("torus: distance against brute force, never overestimates, normal", T, float, double)
{
    for (const ring_case& c : ring_cases()) {
        check_against_reference<T>(c);
        check_never_overestimates<T>(c);
        check_normal<T>(c);
    }
    // A spindle torus (r > R: the tube overlaps itself around the axis) and R = 0 (a ball) keep
    // the formula "distance to the circle minus r", which the reference computes the same way.
    // (Their tube sweeps are not their surfaces, so only the distance is compared.)
    check_against_reference<T>(ring_case({0.1f, 0.2f, 0}, {0, 1, 1}, 0.3f, 0.5f, "spindle torus"));
    check_against_reference<T>(ring_case({0, 0, 0}, {1, 1, 0}, 0.0f, 0.4f, "R = 0: a ball"));
}

TEST_CASE("torus: bound holds the surface, packet lanes equal the scalar path")
{
    for (const ring_case& c : ring_cases()) {
        check_bound(c);
        check_lanes_all(c);
    }
}

TEST_CASE_TEMPLATE("torus: the same solid as two semicircle torus capsules", T, float, double)
{
    // The ring the Embree peer benchmark built from two half arcs before the torus kernel.
    const krs::torus ring({0, 0, 0}, {0, 0, 1}, 1.0f, 0.2f);
    const krs::torus_capsule upper({-1, 0, 0}, {1, 0, 0}, {0, 1, 0}, 0.2f), lower({-1, 0, 0}, {1, 0, 0}, {0, -1, 0}, 0.2f);
    random_source rng(91);
    double worst = 0;
    for (int i = 0; i < 5000; ++i) {
        const vec3d p = rng.query({0, 0, 0}, 2.0);
        const double pair = std::min(distance_at<T>(upper, p), distance_at<T>(lower, p));
        worst = std::max(worst, std::abs(distance_at<T>(ring, p) - pair));
    }
    MESSAGE("max |torus - min(two torus capsules)| " << worst);
    CHECK(worst <= 8 * float_ulp * 3);
}

TEST_CASE("torus: accurate near its axis")
{
    // sqrt(|q|^2 - h^2) would place these points ~3e-4 off; the in-plane offset keeps float rounding.
    const ring_case c({0.1f, 0.2f, 0.3f}, {0.3f, 1, 0.2f}, 1.0f, 0.2f, "ring");
    const vec3d a = krs::normalize(vec3d(c.kernel.axis()));
    random_source rng(17);
    double worst = 0;
    for (int i = 0; i < 2000; ++i) {
        const vec3d off = perpendicular_unit(rng, a) * std::pow(10.0, rng.uniform(-6, -3));
        const vec3d p = vec3d(to_f(vec3d(c.kernel.center()) + a * rng.uniform(-1, 1) + off));
        worst = std::max(worst, std::abs(distance_at<float>(c.kernel, p) - c.reference(p)));
    }
    MESSAGE("worst error near the axis " << worst);
    CHECK(worst <= 8 * float_ulp * 2);
}

TEST_CASE("torus: normals on the axis and on the circle are finite unit vectors")
{
    const krs::torus k({0.5f, 0, 0}, {0, 1, 0}, 1.0f, 0.3f);
    for (const vec3f p : {vec3f{0.5f, 0, 0}, vec3f{0.5f, 2, 0}, vec3f{1.5f, 0, 0}, vec3f{0.5f, 0, -1}}) {
        const vec3f n = k.normal(p);
        CHECK(std::abs(krs::length(vec3d(n)) - 1) < 1e-6);
    }
    // Off the circle in its plane the normal is radial; above the circle it is the axis.
    CHECK(krs::length(vec3d(k.normal(vec3f{2.5f, 0, 0})) - vec3d{1, 0, 0}) < 1e-6);
    CHECK(krs::length(vec3d(k.normal(vec3f{0.5f, 0.7f, 1})) - vec3d{0, 1, 0}) < 1e-6);
}

TEST_CASE("torus: uv runs around the axis and around the tube")
{
    for (const ring_case& c : ring_cases()) {
        INFO(c.name);
        const krs::torus& k = c.kernel;
        const vec3d axis(k.axis());
        const float u0 = k.uv(vec3f(c.curve.at(0))).u;
        for (int i = 0; i <= 100; ++i) {
            const double t = i / 100.0;
            const vec3d on = c.curve.at(t);
            const vec3d out = krs::normalize(on - vec3d(k.center()));
            // u advances with the angle around the axis (one turn = 1), in either sense.
            const double du = std::fmod(double(k.uv(vec3f(on + out * 0.05)).u - u0) + 2.0, 1.0);
            CHECK(std::min(std::abs(du - t), std::min(std::abs(du - t + 1), std::abs(du + t - 1))) < 1e-4);
            CHECK(k.uv(vec3f(on + out * 0.05)).v == doctest::Approx(0.5).epsilon(1e-4));
            CHECK(k.uv(vec3f(on + axis * 0.05)).v == doctest::Approx(0.75).epsilon(1e-4));
            CHECK(k.uv(vec3f(on - axis * 0.05)).v == doctest::Approx(0.25).epsilon(1e-4));
        }
    }
}

TEST_CASE("torus: invalid parameters are named")
{
    expect_invalid([] { krs::torus({0, 0, 0}, {0, 0, 1}, -1.0f, 0.1f); }, "torus.major_radius");
    expect_invalid([] { krs::torus({0, 0, 0}, {0, 0, 1}, 1.0f, nan_f); }, "torus.minor_radius");
    expect_invalid([] { krs::torus({nan_f, 0, 0}, {0, 0, 1}, 1.0f, 0.1f); }, "torus.center");
    expect_invalid([] { krs::torus({0, 0, 0}, {0, 0, 0}, 1.0f, 0.1f); }, "torus.axis");
    expect_invalid([] { krs::torus({0, 0, 0}, {0, inf_f, 0}, 1.0f, 0.1f); }, "torus.axis");
}

// ---- tetrahedron ----------------------------------------------------------------------------------

TEST_CASE_TEMPLATE("tetrahedron: zero set is the surface, never overestimates, normal", T, float, double)
{
    const tetrahedron_case c;
    check_never_overestimates<T>(c);
    check_normal<T>(c);
}

TEST_CASE("tetrahedron: bounds hold the surface, packet lanes equal the scalar path")
{
    const tetrahedron_case c;
    check_bound(c);
    const krs::bounding_box box = c.kernel.bound_box();
    REQUIRE(box.is_bounded());
    random_source rng(6);
    int outside = 0;
    for (const vec3d& s : c.surface(rng, 20000))
        if (!(s.x >= box.lo.x && s.y >= box.lo.y && s.z >= box.lo.z && s.x <= box.hi.x && s.y <= box.hi.y &&
              s.z <= box.hi.z))
            ++outside;
    CHECK(outside == 0);
    check_lanes_all(c);
}

// Every kernel satisfies the kernel concept (checked when this file compiles).
static_assert(krs::kernel<krs::torus>);
static_assert(krs::kernel<krs::plane>);
static_assert(krs::kernel<krs::capsule>);
static_assert(krs::kernel<krs::box>);
static_assert(krs::kernel<krs::torus_capsule>);
static_assert(krs::kernel<krs::sphere>);
static_assert(krs::kernel<krs::tetrahedron>);

// A kernel carries its GLSL (krs/field.hpp): the same geometry without glsl_name, glsl_source and
// glsl_parameters() is a field but no kernel, so a sequence refuses it as a kind when it compiles.
namespace {
struct sphere_without_glsl {
    krs::sphere s{{0, 0, 0}, 1};
    template <class T>
    T distance(const krs::vec3<T>& p) const { return s.distance(p); }
    template <class T>
    krs::vec3<T> normal(const krs::vec3<T>& p) const { return s.normal(p); }
    krs::bounding_sphere bound() const { return s.bound(); }
    krs::bounding_box bound_box() const { return s.bound_box(); }
};
struct sphere_with_glsl : sphere_without_glsl {
    static constexpr std::string_view glsl_name = krs::sphere::glsl_name;
    static constexpr std::string_view glsl_source = krs::sphere::glsl_source;
    std::array<float, 4> glsl_parameters() const { return s.glsl_parameters(); }
};
} // namespace
static_assert(krs::field<sphere_without_glsl>);
static_assert(!krs::kernel<sphere_without_glsl>);
static_assert(krs::kernel<sphere_with_glsl>);

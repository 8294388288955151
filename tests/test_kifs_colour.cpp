// KIFS colouring (krs/fractal/kifs_colour.hpp, orbit_trap.hpp): orbit traps and iteration counts
// against a brute-force walk of the fold program written here step by step (its own loop, its own
// escape test in double, the traps' closed forms in double), a point on a trap traps 0, packet
// lanes equal the scalar result, and validation.

#include "krs/fractal/kifs_colour.hpp"
#include "krs/fractal/kifs_presets.hpp"
#include "krs/kernels/sphere.hpp"
#include "support/random.hpp"
#include "support/rejects.hpp"
#include "support/scenes.hpp"

#include <doctest/doctest.h>

#include <cmath>
#include <cstdio>
#include <functional>
#include <limits>
#include <random>
#include <string>
#include <type_traits>
#include <vector>

namespace {

using krs::vec3d;
using krs::vec3f;

// Trap distances in double from the trap's definition (not its code): the shapes as built below.
struct trap_shape {
    krs::orbit_trap_kind kind;
    vec3d a, d; // point / normal / line point; line direction (unit)
    double w;   // offset / radius
    double distance(const vec3d& p) const
    {
        switch (kind) {
        case krs::orbit_trap_kind::point: return krs::length(p - a);
        case krs::orbit_trap_kind::plane: return std::abs(krs::dot(a, p) - w);
        case krs::orbit_trap_kind::line: {
            const vec3d q = p - a;
            return krs::length(q - d * krs::dot(q, d));
        }
        default: return std::abs(krs::length(p - a) - w);
        }
    }
};

// Steps that fold (move only some points), named here independently of the library's trait.
template <class S>
constexpr bool test_folds = std::is_same_v<S, krs::plane_fold> || std::is_same_v<S, krs::sort_fold> ||
                            std::is_same_v<S, krs::abs_fold<krs::fold_xyz>> || std::is_same_v<S, krs::abs_fold<krs::fold_x>> ||
                            std::is_same_v<S, krs::abs_fold<krs::fold_x | krs::fold_z>>;

struct reference_colour {
    std::vector<double> trap;
    int escape = 0, folds = 0, last_fold = 0;
    double escape_margin = 1e300; // smallest | |p_i| - R | / R met on the orbit walked
};

// The orbit walked one step at a time: p_0 = x, then each step of each iteration applied to the
// float point (the same float steps the fractal takes), a fold counted when its output differs
// from its input, traps taken in double after every iteration, stopping after the first point
// beyond R.
template <class Fractal>
reference_colour brute_force(const Fractal& f, const vec3f& x, const std::vector<trap_shape>& traps, double radius)
{
    reference_colour r;
    vec3f p = x;
    for (const trap_shape& t : traps) r.trap.push_back(t.distance(vec3d(p)));
    const auto beyond = [&](const vec3f& q) {
        const double l = krs::length(vec3d(q));
        r.escape_margin = std::min(r.escape_margin, std::abs(l - radius) / radius);
        return l > radius;
    };
    r.escape = f.iterations() + 1;
    if (beyond(p)) {
        r.escape = 0;
        return r;
    }
    for (int i = 1; i <= f.iterations(); ++i) {
        std::apply(
            [&](const auto&... step) {
                (
                    [&](const auto& s) {
                        const vec3f q = s.apply(p);
                        if (test_folds<std::remove_cvref_t<decltype(s)>> && (q.x != p.x || q.y != p.y || q.z != p.z)) {
                            ++r.folds;
                            r.last_fold = i;
                        }
                        p = q;
                    }(step),
                    ...);
            },
            f.program().steps());
        for (std::size_t k = 0; k < traps.size(); ++k) r.trap[k] = std::min(r.trap[k], traps[k].distance(vec3d(p)));
        if (beyond(p)) {
            r.escape = i;
            break;
        }
    }
    return r;
}

// Four traps of every kind, and their shapes for the reference.
struct trap_set {
    krs::kifs_colouring colouring;
    std::vector<trap_shape> shapes;
};
trap_set make_traps(float radius)
{
    const vec3f n = krs::normalize(vec3f{1, 2, -0.5f}), dir = krs::normalize(vec3f{0.3f, -1, 0.7f});
    trap_set t{{{krs::orbit_trap::point({0.25f, -0.5f, 0.125f}), krs::orbit_trap::plane(n, 0.3f),
                 krs::orbit_trap::line({0.1f, 0.2f, 0.0f}, dir), krs::orbit_trap::shell({0, 0, 0}, 1.5f)},
                radius},
               {}};
    // The library makes the directions unit in double and rounds to float: the reference uses
    // those floats (the shape the trap holds), so the comparison is of the distance alone.
    const vec3f nn = krs::require_direction("n", n), dd = krs::require_direction("d", dir);
    t.shapes = {{krs::orbit_trap_kind::point, {0.25, -0.5, 0.125}, {}, 0},
                {krs::orbit_trap_kind::plane, vec3d(nn), {}, 0.3f},
                {krs::orbit_trap_kind::line, vec3d(vec3f{0.1f, 0.2f, 0.0f}), vec3d(dd), 0},
                {krs::orbit_trap_kind::shell, {0, 0, 0}, {}, 1.5}};
    return t;
}

// Returns how many points stayed (no orbit point beyond R): thin fractals keep few.
template <class Fractal>
int check_against_brute_force(const Fractal& f, const char* name, float half, float radius)
{
    const trap_set traps = make_traps(radius);
    std::mt19937_64 g(99);
    const auto u = [half](std::mt19937_64& e) { return float(krs_test::uniform(e, -half, half)); };
    int compared = 0, near_escape = 0, escaped = 0, stayed = 0, folded = 0;
    double worst_trap = 0;
    bool counts_equal = true;
    std::string first_mismatch;
    for (int n = 0; n < 4000; ++n) {
        const vec3f x{u(g), u(g), u(g)};
        const reference_colour ref = brute_force(f, x, traps.shapes, radius);
        if (ref.escape_margin < 1e-5) { // float and double may disagree on the side of R
            ++near_escape;
            continue;
        }
        ++compared;
        const krs::kifs_colour_result<float> c = krs::kifs_colour(f, x, traps.colouring);
        const bool same = c.escape_iteration == float(ref.escape) && c.fold_count == float(ref.folds) &&
                          c.last_fold == float(ref.last_fold);
        if (!same && counts_equal)
            first_mismatch = "x (" + std::to_string(x.x) + ", " + std::to_string(x.y) + ", " + std::to_string(x.z) +
                             "): escape " + std::to_string(c.escape_iteration) + " vs " + std::to_string(ref.escape) +
                             ", folds " + std::to_string(c.fold_count) + " vs " + std::to_string(ref.folds) + ", last " +
                             std::to_string(c.last_fold) + " vs " + std::to_string(ref.last_fold);
        counts_equal = counts_equal && same;
        for (std::size_t k = 0; k < 4; ++k) {
            // Float distances of points up to ~R from shapes within ~1.5 of the origin: a few ulps of R.
            const double e = std::abs(double(c.trap[k]) - ref.trap[k]) / (1.0 + double(radius));
            worst_trap = std::max(worst_trap, e);
        }
        escaped += ref.escape <= f.iterations();
        stayed += ref.escape == f.iterations() + 1;
        folded += ref.folds > 0;
    }
    std::printf("kifs_colour %-12s %d points compared (%d within 1e-5 R of the escape radius left out): escaped %d, "
                "stayed %d, folded %d; max |trap - brute force| / (1 + R) %.3g\n",
                name, compared, near_escape, escaped, stayed, folded, worst_trap);
    INFO(name << " " << first_mismatch);
    CHECK(counts_equal);
    CHECK(worst_trap <= 1e-6);
    CHECK(near_escape <= 40);
    // The sample must exercise both endings and the folds, or the comparison proves little.
    CHECK(escaped >= 100);
    CHECK(stayed >= 1);
    CHECK(folded >= 1000);
    return stayed;
}

} // namespace

TEST_CASE("kifs_colour traps and counts equal a brute-force walk of the fold program")
{
    int stayed = 0;
    stayed += check_against_brute_force(krs::make_menger_sponge(4), "menger", 1.6f, 4.0f);
    stayed += check_against_brute_force(krs::make_sierpinski_tetrahedron(8), "sierpinski", 1.6f, 4.0f);
    stayed += check_against_brute_force(krs::make_koch_curve(5), "koch", 1.3f, 3.0f);
    stayed += check_against_brute_force(krs::make_square_fractal(5), "square", 3.0f, 6.0f);
    stayed += check_against_brute_force(krs::make_cube_fractal(4), "cube", 3.0f, 6.0f);
    const krs_test::spiral_kifs spiral = krs_test::spiral();
    stayed += check_against_brute_force(spiral, "spiral", 2.0f, 4.0f);
    CHECK(stayed >= 500);
}

TEST_CASE("kifs_colour: a point on a trap traps 0")
{
    const krs::menger_sponge f = krs::make_menger_sponge(3);
    const auto on = [&](const krs::orbit_trap& t, const vec3f& x) {
        const krs::kifs_colour_result<float> c = krs::kifs_colour(f, x, krs::kifs_colouring{{t}});
        INFO(krs::orbit_trap_kind_name(t.kind()));
        CHECK(c.trap[0] == 0.0f);
        CHECK(t.distance(x) == 0.0f);
        // The unused traps hold the largest float.
        CHECK(c.trap[1] == std::numeric_limits<float>::max());
    };
    on(krs::orbit_trap::point({0.25f, 0.5f, -0.125f}), {0.25f, 0.5f, -0.125f});
    on(krs::orbit_trap::plane({0, 0, 1}, 0.375f), {0.3f, -0.2f, 0.375f});
    on(krs::orbit_trap::line({0, 0.25f, 0}, {1, 0, 0}), {0.7f, 0.25f, 0.0f});
    on(krs::orbit_trap::shell({0, 0, 0}, 1.0f), {1.0f, 0.0f, 0.0f});
    on(krs::orbit_trap::shell({0.5f, 0, 0}, 0.0f), {0.5f, 0.0f, 0.0f});
    // Off the trap: positive, and the exact distance for these aligned shapes.
    CHECK(krs::orbit_trap::plane({0, 0, 2}, 0.375f).distance(vec3f{0.0f, 0.0f, 0.875f}) == 0.5f);
    CHECK(krs::orbit_trap::line({0, 0.25f, 0}, {1, 0, 0}).distance(vec3f{5.0f, 0.25f, -0.75f}) == 0.75f);
    CHECK(krs::orbit_trap::shell({0, 0, 0}, 1.0f).distance(vec3f{0.0f, 0.25f, 0.0f}) == 0.75f);
    // A point outside the escape radius: its orbit is p_0 alone, no fold counted.
    const krs::kifs_colour_result<float> far =
        krs::kifs_colour(f, vec3f{3.0f, 4.0f, 0.0f}, krs::kifs_colouring{{krs::orbit_trap::point({0, 0, 0})}, 4.0f});
    CHECK(far.escape_iteration == 0.0f);
    CHECK(far.fold_count == 0.0f);
    CHECK(far.last_fold == 0.0f);
    CHECK(far.trap[0] == 5.0f);
}

TEST_CASE("kifs_colour packet lanes equal the scalar result")
{
    using P = krs::packet_f;
    constexpr std::size_t W = krs::lane_count<P>;
    const krs::sierpinski_tetrahedron f = krs::make_sierpinski_tetrahedron(8);
    const trap_set traps = make_traps(4.0f);
    std::mt19937_64 g(5);
    const auto u = [](std::mt19937_64& e) { return float(krs_test::uniform(e, -1.6, 1.6)); };
    int mismatches = 0;
    for (int n = 0; n < 500; ++n) {
        alignas(64) float xs[W], ys[W], zs[W];
        for (std::size_t i = 0; i < W; ++i) xs[i] = u(g), ys[i] = u(g), zs[i] = u(g);
        const krs::vec3fP pp{P::load_aligned(xs), P::load_aligned(ys), P::load_aligned(zs)};
        const krs::kifs_colour_result<P> c = krs::kifs_colour(f, pp, traps.colouring);
        for (std::size_t i = 0; i < W; ++i) {
            const krs::kifs_colour_result<float> s = krs::kifs_colour(f, vec3f{xs[i], ys[i], zs[i]}, traps.colouring);
            bool same = krs::lane_at(c.escape_iteration, i) == s.escape_iteration &&
                        krs::lane_at(c.fold_count, i) == s.fold_count && krs::lane_at(c.last_fold, i) == s.last_fold;
            for (std::size_t k = 0; k < 4; ++k) same = same && krs::lane_at(c.trap[k], i) == s.trap[k];
            mismatches += !same;
        }
    }
    CHECK(mismatches == 0);
}

TEST_CASE("kifs_colour parameters are validated")
{
    using krs_test::rejects;
    const float nan = std::nanf(""), inf = std::numeric_limits<float>::infinity();
    rejects([] { krs::orbit_trap::plane({0, 0, 0}, 1.0f); }, "orbit_trap.normal");
    rejects([&] { krs::orbit_trap::plane({0, 0, 1}, nan); }, "orbit_trap.offset");
    rejects([&] { krs::orbit_trap::point({inf, 0, 0}); }, "orbit_trap.center");
    rejects([] { krs::orbit_trap::line({0, 0, 0}, {0, 0, 0}); }, "orbit_trap.direction");
    rejects([&] { krs::orbit_trap::line({nan, 0, 0}, {1, 0, 0}); }, "orbit_trap.through");
    rejects([] { krs::orbit_trap::shell({0, 0, 0}, -1.0f); }, "orbit_trap.radius");
    rejects([] { krs::kifs_colouring({}, 4.0f); }, "kifs_colouring.traps");
    rejects(
        [] {
            const krs::orbit_trap t = krs::orbit_trap::point({0, 0, 0});
            krs::kifs_colouring({t, t, t, t, t}, 4.0f);
        },
        "kifs_colouring.traps");
    rejects([] { krs::kifs_colouring({krs::orbit_trap{}}, 0.0f); }, "kifs_colouring.escape_radius");
    rejects([&] { krs::kifs_colouring({krs::orbit_trap{}}, nan); }, "kifs_colouring.escape_radius");
    rejects([] { krs::kifs_colouring({krs::orbit_trap{}}, 2e9f); }, "kifs_colouring.escape_radius");
    // The default colouring: one point trap at the origin, escape radius 100.
    const krs::kifs_colouring d;
    CHECK(d.trap_count() == 1);
    CHECK(d.escape_radius() == 100.0f);
    CHECK(d.trap(0).kind() == krs::orbit_trap_kind::point);
}

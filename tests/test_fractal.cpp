// Fractal fields: KIFS fold programs against naive unions of their copies and against krs::sequence,
// log-polar / log-spherical warps and the similar shell: Lipschitz bounds measured on close random
// pairs, finiteness at the singularity and far away, packet lanes against scalars, validation.

#include "krs/fractal/fold_steps.hpp"
#include "krs/fractal/kifs.hpp"
#include "krs/fractal/kifs_presets.hpp"
#include "krs/fractal/log_tilings.hpp"
#include "krs/fractal/shell_presets.hpp"
#include "krs/fractal/similar_shell.hpp"
#include "krs/kernels/sphere.hpp"
#include "krs/sequence.hpp"
#include "krs/trace/camera.hpp"
#include "krs/trace/sphere_trace.hpp"

#include "support/parity.hpp"
#include "support/random.hpp"
#include "support/rejects.hpp"

#include <doctest/doctest.h>

#include <algorithm>
#include <cmath>
#include <functional>
#include <limits>
#include <optional>
#include <random>
#include <string>
#include <vector>

namespace {

using krs::vec3d;
using krs::vec3f;

using krs_test::random_direction;
using krs_test::uniform;

// Exact signed distance of an axis-aligned box, written out for the naive unions.
double box_distance(const vec3d& p, const vec3d& c, const vec3d& h)
{
    const vec3d q{std::abs(p.x - c.x) - h.x, std::abs(p.y - c.y) - h.y, std::abs(p.z - c.z) - h.z};
    const vec3d o{std::max(q.x, 0.0), std::max(q.y, 0.0), std::max(q.z, 0.0)};
    return krs::length(o) + std::min(std::max(q.x, std::max(q.y, q.z)), 0.0);
}
double square_distance(double x, double y, double cx, double cy, double h)
{
    const double qx = std::abs(x - cx) - h, qy = std::abs(y - cy) - h;
    return std::hypot(std::max(qx, 0.0), std::max(qy, 0.0)) + std::min(std::max(qx, qy), 0.0);
}

struct square_at {
    double x, y, h;
};
// The document's construction: every square gets a square three times smaller on each side.
void enumerate_squares(double x, double y, double h, int depth, std::vector<square_at>& out)
{
    out.push_back({x, y, h});
    if (depth == 0) return;
    const double step = 4.0 / 3.0 * h;
    enumerate_squares(x + step, y, h / 3, depth - 1, out);
    enumerate_squares(x - step, y, h / 3, depth - 1, out);
    enumerate_squares(x, y + step, h / 3, depth - 1, out);
    enumerate_squares(x, y - step, h / 3, depth - 1, out);
}
struct cube_at {
    vec3d c;
    double h;
};
void enumerate_cubes(const vec3d& c, double h, int depth, std::vector<cube_at>& out)
{
    out.push_back({c, h});
    if (depth == 0) return;
    const double step = 4.0 / 3.0 * h;
    const vec3d axes[3] = {{1, 0, 0}, {0, 1, 0}, {0, 0, 1}};
    for (const vec3d& a : axes) {
        enumerate_cubes(c + a * step, h / 3, depth - 1, out);
        enumerate_cubes(c - a * step, h / 3, depth - 1, out);
    }
}
// The Menger sponge by subdivision: keep the 20 sub-cubes with at most one zero coordinate offset.
void enumerate_menger(const vec3d& c, double h, int depth, std::vector<cube_at>& out)
{
    if (depth == 0) {
        out.push_back({c, h});
        return;
    }
    for (int i = -1; i <= 1; ++i)
        for (int j = -1; j <= 1; ++j)
            for (int k = -1; k <= 1; ++k)
                if ((i == 0) + (j == 0) + (k == 0) <= 1)
                    enumerate_menger(c + vec3d{double(i), double(j), double(k)} * (2.0 * h / 3.0), h / 3, depth - 1, out);
}

// Largest |d(a) - d(b)| / |a - b| over random close pairs; a from `sample`, b at distance
// `separation(a)` in a random direction. Double lanes, so rounding stays far below the 1e-3 margin.
template <class F>
double measured_lipschitz(const F& f, int pairs, const std::function<vec3d(std::mt19937_64&)>& sample,
                          const std::function<double(const vec3d&)>& separation, unsigned seed = 7)
{
    std::mt19937_64 g(seed);
    double worst = 0;
    for (int i = 0; i < pairs; ++i) {
        const vec3d a = sample(g);
        const double delta = separation(a);
        const vec3d b = a + random_direction(g) * delta;
        const double ratio = std::abs(f.distance(a) - f.distance(b)) / krs::length(b - a);
        worst = std::max(worst, ratio);
    }
    return worst;
}
vec3d in_cube(std::mt19937_64& g, double half) { return {uniform(g, -half, half), uniform(g, -half, half), uniform(g, -half, half)}; }
// Log-uniform radius in [lo, hi]: every scale of a self-similar field gets the same share of pairs.
vec3d log_uniform(std::mt19937_64& g, double lo, double hi)
{
    return random_direction(g) * std::exp(uniform(g, std::log(lo), std::log(hi)));
}

struct sphere_tile {
    template <class T>
    T distance(const krs::vec3<T>& p) const
    {
        return krs::length(p) - T(0.3f);
    }
};

} // namespace

TEST_CASE("square fractal fold form equals the naive union of its squares")
{
    for (int depth : {0, 1, 3, 5}) {
        const krs::square_fractal f = krs::make_square_fractal(depth, 1.0f);
        std::vector<square_at> squares;
        enumerate_squares(0, 0, 1, depth, squares);
        REQUIRE(squares.size() == std::size_t((std::pow(4.0, depth + 1) - 1) / 3));
        std::mt19937_64 g(11 + unsigned(depth));
        double worst = 0;
        const int points = depth == 5 ? 100000 : 10000;
        for (int i = 0; i < points; ++i) {
            const double x = uniform(g, -2.2, 2.2), y = uniform(g, -2.2, 2.2);
            double naive = INFINITY;
            for (const square_at& s : squares) naive = std::min(naive, square_distance(x, y, s.x, s.y, s.h));
            worst = std::max(worst, std::abs(f.distance(vec3d{x, y, 0}) - naive));
        }
        INFO("depth ", depth);
        CHECK(worst < 1e-5);
    }
}

TEST_CASE("cube fractal and Menger sponge fold forms equal their naive unions")
{
    const int depth = 3;
    std::vector<cube_at> cubes, menger;
    enumerate_cubes({0, 0, 0}, 1, depth, cubes);
    enumerate_menger({0, 0, 0}, 1, 2, menger);
    REQUIRE(cubes.size() == 259);
    REQUIRE(menger.size() == 400);
    const krs::cube_fractal cf = krs::make_cube_fractal(depth);
    const krs::menger_sponge ms = krs::make_menger_sponge(2);
    std::mt19937_64 g(5);
    double worst_cube = 0, worst_menger = 0;
    for (int i = 0; i < 20000; ++i) {
        const vec3d p = in_cube(g, 1.8);
        double a = INFINITY, b = INFINITY;
        for (const cube_at& c : cubes) a = std::min(a, box_distance(p, c.c, {c.h, c.h, c.h}));
        for (const cube_at& c : menger) b = std::min(b, box_distance(p, c.c, {c.h, c.h, c.h}));
        worst_cube = std::max(worst_cube, std::abs(cf.distance(p) - a));
        // Outside the sponge the union of cubes is the exact distance; inside, min over cubes is
        // not the union's distance and the fold form is its own (also valid) bound.
        if (b > 0) worst_menger = std::max(worst_menger, std::abs(ms.distance(p) - b));
    }
    CHECK(worst_cube < 1e-5);
    CHECK(worst_menger < 1e-5);
}

TEST_CASE("a KRS written as a fold program gives the distances of krs::sequence")
{
    std::mt19937_64 g(3);
    for (int trial = 0; trial < 6; ++trial) {
        // Mirrors a, b, c repeated `repeats` times; the kernel sits at every third level.
        krs::mirror m[3];
        for (krs::mirror& mi : m) mi = krs::mirror(vec3f(random_direction(g)), float(uniform(g, -0.3, 0.3)));
        const krs::sphere kernel(vec3f(in_cube(g, 1.0)), float(uniform(g, 0.05, 0.4)));
        const int repeats = 1 + trial % 4;
        krs::sequence<krs::sphere>::builder b;
        b.kernel(kernel);
        for (int r = 0; r < repeats; ++r) {
            b.mirror(m[2]).mirror(m[1]).mirror(m[0]); // Algorithm 1 walks from the top: a first
            b.kernel(kernel);
        }
        const auto krs_field = b.build();
        using program = krs::fold_program<krs::plane_fold, krs::plane_fold, krs::plane_fold>;
        const krs::kifs<program, krs::sphere> folded{
            program{krs::plane_fold(m[0]), krs::plane_fold(m[1]), krs::plane_fold(m[2])}, kernel, repeats};
        REQUIRE(folded.program().scale() == 1.0);
        int mismatches = 0;
        double worst = 0;
        for (int i = 0; i < 20000; ++i) {
            const vec3f p(in_cube(g, 2.5));
            const float a = folded.distance(p), c = krs_field.distance(p);
            mismatches += a != c;
            worst = std::max(worst, double(std::abs(a - c)));
        }
        INFO("trial ", trial, ": worst difference ", worst);
        CHECK(mismatches == 0);
    }
}

TEST_CASE("fractal presets are 1-Lipschitz or declare their bound")
{
    const int pairs = 100000;
    auto cube_sample = [](std::mt19937_64& g) { return in_cube(g, 2.0); };
    auto fixed = [](const vec3d&) { return 1e-3; };
    auto scaled_sample = [](std::mt19937_64& g) { return log_uniform(g, 1e-3, 1e3); };
    auto relative = [](const vec3d& a) { return 1e-3 * krs::length(a); };

    struct row {
        std::string name;
        double measured;
    };
    std::vector<row> rows;
    rows.push_back({"square fractal", measured_lipschitz(krs::make_square_fractal(6), pairs, cube_sample, fixed)});
    rows.push_back({"cube fractal", measured_lipschitz(krs::make_cube_fractal(5), pairs, cube_sample, fixed)});
    rows.push_back({"Menger sponge", measured_lipschitz(krs::make_menger_sponge(4), pairs, cube_sample, fixed)});
    rows.push_back({"Sierpinski tetrahedron",
                    measured_lipschitz(krs::make_sierpinski_tetrahedron(8), pairs, cube_sample, fixed)});
    rows.push_back({"Koch curve", measured_lipschitz(krs::make_koch_curve(5), pairs, cube_sample, fixed)});
    rows.push_back({"recursive lotus", measured_lipschitz(krs::make_recursive_lotus(), pairs, scaled_sample, relative)});
    rows.push_back({"cube singularity", measured_lipschitz(krs::make_cube_singularity(), pairs, scaled_sample, relative)});
    const krs::log_polar_tiling<sphere_tile> polar(sphere_tile{}, 12, 0.4f, 0.15f);
    rows.push_back({"log-polar tiling", measured_lipschitz(polar, pairs, scaled_sample, relative)});
    const krs::log_spherical_tiling<sphere_tile> spherical(sphere_tile{}, 12, 0.15f);
    rows.push_back({"log-spherical tiling", measured_lipschitz(spherical, pairs, scaled_sample, relative)});
    for (const row& r : rows) {
        MESSAGE(r.name, ": measured Lipschitz ", r.measured);
        INFO(r.name);
        CHECK(r.measured <= 1.0 + 1e-3);
        CHECK(r.measured > 0.5); // the sampling reached the geometry's gradient at all
    }
    MESSAGE("declared bounds divided out: log-polar ", polar.lipschitz(), ", log-spherical ", spherical.lipschitz());
}

TEST_CASE("similar shell seam fixes and their measured Lipschitz values")
{
    const int pairs = 100000;
    auto scaled_sample = [](std::mt19937_64& g) { return log_uniform(g, 1e-3, 1e3); };
    auto relative = [](const vec3d& a) { return 1e-3 * krs::length(a); };
    const krs::shell_seams modes[] = {krs::shell_seams::none, krs::shell_seams::hidden_boundary,
                                      krs::shell_seams::adjacent_shells};
    const char* names[] = {"none", "hidden boundary", "adjacent shells"};
    for (int preset = 0; preset < 2; ++preset) {
        double measured[3][2] = {};
        for (int m = 0; m < 3; ++m)
            for (int half = 0; half < 2; ++half) {
                krs::shell_options o;
                o.seams = modes[m];
                o.step_factor = half ? 0.5f : 1.0f;
                measured[m][half] = preset == 0
                                        ? measured_lipschitz(krs::make_recursive_lotus(1.0f, 8, o), pairs, scaled_sample, relative)
                                        : measured_lipschitz(krs::make_cube_singularity(1.0f, o), pairs, scaled_sample, relative);
                MESSAGE(std::string(preset == 0 ? "recursive lotus" : "cube singularity"), ", seams ", std::string(names[m]),
                        ", step factor ", o.step_factor, ": measured Lipschitz ", measured[m][half]);
            }
        // Without a fix each shell sees only its own copy: the field jumps at the seams.
        CHECK(measured[0][0] > 2.0);
        // The hidden boundary caps how far a seam lets a ray overshoot, so it jumps less.
        CHECK(measured[1][0] < measured[0][0]);
        // Adjacent shells: continuous and 1-Lipschitz; halving the step halves it.
        CHECK(measured[2][0] <= 1.0 + 1e-3);
        CHECK(measured[2][1] == doctest::Approx(0.5 * measured[2][0]).epsilon(1e-3));
    }
}

namespace {

// The self-similar geometry itself, the slow way: the union of the prototype's copies in the
// shells k-2 .. k+2 around p's shell, each scaled by e^(k / density) in double. The prototype
// lies inside its shell, so farther shells are farther than these.
template <class Shell>
double union_of_shells(const krs::similar_shell<Shell>& f, const vec3d& p)
{
    const double density = f.density();
    const double k = std::floor(std::log(krs::length(p)) * density);
    double d = std::numeric_limits<double>::infinity();
    for (int j = -2; j <= 2; ++j) {
        const double scale = std::exp((k + j) / density);
        d = std::min(d, f.shell().distance(p / scale) * scale);
    }
    return d;
}

// A point at relative distance `beta` from a seam of the shells (beta < 0: inside the seam),
// in a random direction, the seam one of the shells -3 .. 3.
vec3d near_seam(std::mt19937_64& g, float density, double beta)
{
    const double seam = std::exp(std::floor(uniform(g, -3, 4)) / density);
    return random_direction(g) * (seam * (1.0 + beta));
}

// Spheres 0.2% of r from the shell's seams (closer than the hidden boundary's cutoff): 6 on the axes
// near the inner sphere, 8 on the diagonals near the outer one.
struct seam_hugging_shell {
    std::vector<krs::sphere> balls;
    explicit seam_hugging_shell(float s)
    {
        const float inner = 0.25f, outer = 0.4f * s / 2.7182817f;
        for (int axis = 0; axis < 3; ++axis)
            for (float sign : {-1.0f, 1.0f}) {
                vec3f c{0, 0, 0};
                (axis == 0 ? c.x : axis == 1 ? c.y : c.z) = sign * (1.002f + inner);
                balls.emplace_back(c, inner);
            }
        for (int i = 0; i < 8; ++i) {
            const vec3f d = krs::normalize(vec3f{(i & 1) ? 1.0f : -1.0f, (i & 2) ? 1.0f : -1.0f, (i & 4) ? 1.0f : -1.0f});
            balls.emplace_back(d * (s / 1.002f - outer), outer);
        }
    }
    template <class T>
    T distance(const krs::vec3<T>& p) const
    {
        T d = balls[0].distance(p);
        using krs::min;
        for (std::size_t i = 1; i < balls.size(); ++i) d = min(d, balls[i].distance(p));
        return d;
    }
};

struct march_tally {
    double steps = 0;
    int rays = 0, hits = 0, reference_hits = 0, mismatched = 0;
};
// Marches a 48 x 48 camera over f and counts hit-mask differences against `reference`'s image.
template <class F, class R>
march_tally march_camera(const F& f, const R& reference, const vec3f& eye)
{
    const krs::pinhole_camera camera(eye, {0, 0, 0.3f}, {0, 0, 1}, 50.0f, 48, 48);
    krs::trace_options o;
    o.max_steps = 2000;
    o.pixel_footprint = camera.pixel_footprint() * 0.5f;
    o.max_distance = 60.0f;
    march_tally tally;
    for (int y = 0; y < 48; ++y)
        for (int x = 0; x < 48; ++x) {
            const krs::ray<float> r = camera.primary_ray(float(x) + 0.5f, float(y) + 0.5f);
            const krs::hit<float> h = krs::sphere_trace(f, r, o), want = krs::sphere_trace(reference, r, o);
            tally.steps += h.steps;
            ++tally.rays;
            tally.hits += h.found;
            tally.reference_hits += want.found;
            tally.mismatched += h.found != want.found;
        }
    return tally;
}

} // namespace

TEST_CASE("similar shell local step factor: a bound within its margin near seams, fewer steps than the global factor")
{
    // Hidden boundary with the step halved everywhere (global) or within a band of the seams
    // (local); the band reaches past the cutoff, where the field may overestimate.
    krs::shell_options global{krs::shell_seams::hidden_boundary, 0.05f, 0.5f};
    krs::shell_options local = global;
    local.seam_band = 0.06f;
    krs::shell_options raw{krs::shell_seams::none, 0.02f, 1.0f};
    krs::shell_options exact; // adjacent shells: the reference images
    const float density = 1.0f;

    auto check_preset = [&](const std::string& name, const auto& make, std::optional<vec3f> eye, bool hugs_seams) {
        INFO(name);
        const auto g = make(global), l = make(local), none = make(raw), reference = make(exact);
        // The band covers the cutoff: the local factor keeps the global factor's margin.
        CHECK(l.overestimate_margin() == doctest::Approx(0.5 * 0.05).epsilon(1e-6));
        CHECK(g.overestimate_margin() == doctest::Approx(l.overestimate_margin()).epsilon(1e-6));
        std::mt19937_64 rng(31);
        double worst_local = -1e30, worst_global = -1e30, worst_none = -1e30, worst_form = 0;
        int longer = 0, full_away = 0, samples_away = 0, shorter = 0;
        for (int i = 0; i < 60000; ++i) {
            // Dense near the seams (|beta| < 0.1), some farther in (up to 0.4).
            const double beta = i % 4 == 3 ? uniform(rng, -0.4, 0.4) : uniform(rng, -0.1, 0.1);
            const vec3d p = near_seam(rng, density, beta);
            const double r = krs::length(p);
            const double truth = union_of_shells(l, p);
            const double dl = l.distance(p), dg = g.distance(p), dn = none.distance(p);
            // Inside the geometry a factor below 1 raises a negative distance: not an overshoot.
            if (!(truth > 0)) continue;
            // Overestimate beyond the stated margin, relative to r (double lanes: rounding ~1e-7).
            worst_local = std::max(worst_local, (dl - truth) / r - l.overestimate_margin());
            worst_global = std::max(worst_global, (dg - truth) / r - g.overestimate_margin());
            worst_none = std::max(worst_none, (dn - truth) / r - g.overestimate_margin());
            // The local field is never shorter than the global one, and longer away from the seams.
            if (dg > 0) CHECK(dl >= dg * (1.0 - 1e-9));
            if (dl > dg * (1.0 + 1e-6) && dg > 0) ++longer;
            // The local field's closed form (the header comment), from d = dg / 0.5 and the
            // distance g to the nearer seam of p's shell, in double.
            if (dg > 0) {
                const double k = std::floor(std::log(r) * density);
                const double inner = std::exp(k / density), outer = std::exp((k + 1) / density);
                const double e = std::max(std::min(r - inner, outer - r) - 0.06 * r, 0.0);
                const double want = std::min(2.0 * dg, dg + 0.5 / 1.06 * e);
                worst_form = std::max(worst_form, std::abs(dl - want) / r);
                // Away from the seams, where the sphere of radius d stays out of the band, the
                // steps are full (2 band = 0.12 < 0.14: the band is always short of beta = 0.14).
                if (std::abs(beta) > 0.14 && 2.0 * dg * 1.06 <= 0.99 * e) {
                    ++samples_away;
                    full_away += dl == doctest::Approx(2.0 * dg).epsilon(1e-5);
                    shorter += dl < dg * (1.0 + 1e-6);
                }
            }
        }
        MESSAGE(name, ": worst overestimate beyond the margin / r: local ", worst_local, ", global ", worst_global,
                ", no seam fix ", worst_none, "; local longer than global at ", longer, " samples");
        CHECK(worst_local <= 1e-6);
        CHECK(worst_global <= 1e-6);
        CHECK(worst_form <= 1e-6);
        // The samples reach where an unfixed field overestimates: the check above can fail.
        CHECK(worst_none > 0.05);
        CHECK(shorter == 0);
        CHECK(full_away == samples_away);
        CHECK(samples_away > 1000);

        // The prototype comes closer to its seams than the cutoff: there the hidden boundary
        // overestimates, and the margin is what holds it.
        if (hugs_seams) CHECK(worst_global > -0.2 * g.overestimate_margin());
        if (!eye) return;
        // Steps per ray on a test camera, and the hit masks against the exact field's image.
        CHECK(l.distance(*eye) > 0.05f * krs::length(*eye)); // the eye is in free space
        const march_tally tg = march_camera(g, reference, *eye), tl = march_camera(l, reference, *eye);
        MESSAGE(name, ": steps per ray global ", tg.steps / tg.rays, ", local ", tl.steps / tl.rays, "; hits ", tg.hits,
                " / ", tl.hits, " of ", tg.rays, " (adjacent shells ", tg.reference_hits, "), hit-mask differences against adjacent shells ", tg.mismatched, " / ",
                tl.mismatched);
        CHECK(tl.hits > tl.rays / 10);
        CHECK(tl.steps < 0.85 * tg.steps);
        CHECK(tl.mismatched <= tg.mismatched + tl.rays / 200);
    };
    // The lotus from below (its petals rise above the xy plane), the cubes from between two of them.
    check_preset("recursive lotus", [&](const krs::shell_options& o) { return krs::make_recursive_lotus(density, 8, o); },
                 vec3f{1.5f, -1.0f, -3.0f}, false);
    check_preset("cube singularity", [&](const krs::shell_options& o) { return krs::make_cube_singularity(density, o); },
                 vec3f{3.0f, 1.3f, -0.6f}, false);
    check_preset("seam-hugging spheres", [&](const krs::shell_options& o) {
        return krs::similar_shell<seam_hugging_shell>(seam_hugging_shell(float(std::exp(1.0 / density))), density, o);
    }, std::nullopt, true);
}

TEST_CASE("similar shell local step factor keeps the field 1-Lipschitz across its transition")
{
    // The factor goes from f within the band to 1 farther out; a factor ramped in beta alone
    // (d g(beta)) has the gradient g + (1 - f) d / (band r) there, about 6 with adjacent shells.
    // Dense close pairs (|p - q| = 1e-4 r) with beta from -0.3 to 0.3, in double lanes (rounding
    // ~1e-12 of the ratio): adjacent shells across seams too; the hidden boundary, which jumps at
    // a seam by design, within one shell (both points of a pair in p's shell).
    const float density = 1.0f;
    for (const auto seams : {krs::shell_seams::adjacent_shells, krs::shell_seams::hidden_boundary}) {
        krs::shell_options o{seams, 0.05f, 0.5f, 0.06f};
        const auto lotus = krs::make_recursive_lotus(density, 8, o);
        const auto cubes = krs::make_cube_singularity(density, o);
        std::mt19937_64 g(17);
        double worst[2] = {0, 0}, worst_band[2] = {0, 0};
        int in_transition = 0;
        for (int i = 0; i < 200000; ++i) {
            const double beta = uniform(g, -0.3, 0.3);
            const vec3d p = near_seam(g, density, beta);
            const vec3d q = p + random_direction(g) * (1e-4 * krs::length(p));
            const double rp = krs::length(p), rq = krs::length(q);
            if (seams == krs::shell_seams::hidden_boundary &&
                std::floor(std::log(rp) * density) != std::floor(std::log(rq) * density))
                continue;
            const double ratio[2] = {std::abs(lotus.distance(p) - lotus.distance(q)) / krs::length(p - q),
                                     std::abs(cubes.distance(p) - cubes.distance(q)) / krs::length(p - q)};
            const double b = std::abs(beta) / (1.0 + beta); // relative to r
            for (int f = 0; f < 2; ++f) {
                worst[f] = std::max(worst[f], ratio[f]);
                if (b >= 0.06 && b <= 0.3) worst_band[f] = std::max(worst_band[f], ratio[f]);
            }
            in_transition += b >= 0.06 && b <= 0.12;
        }
        MESSAGE((seams == krs::shell_seams::adjacent_shells ? "adjacent shells" : "hidden boundary"),
                ", step 0.5 within band 0.06: Lipschitz ratio lotus ", worst[0], " (beyond the band ", worst_band[0],
                "), cubes ", worst[1], " (", worst_band[1], ")");
        CHECK(in_transition > 20000);
        for (int f = 0; f < 2; ++f) {
            CHECK(worst[f] <= 1.0 + 1e-6);
            // The check can fail: the field's gradient reaches 1 beyond the band (full steps).
            CHECK(worst_band[f] >= 0.9);
        }
    }
}

TEST_CASE("log-spherical fields are finite at the singularity and far away")
{
    const krs::recursive_lotus lotus = krs::make_recursive_lotus();
    const krs::cube_singularity cubes = krs::make_cube_singularity(2.0f);
    krs::shell_options raw;
    raw.seams = krs::shell_seams::none;
    const krs::cube_singularity cubes_raw = krs::make_cube_singularity(1.0f, raw);
    krs::shell_options hidden;
    hidden.seams = krs::shell_seams::hidden_boundary;
    const krs::recursive_lotus lotus_hidden = krs::make_recursive_lotus(1.5f, 6, hidden);
    const krs::log_polar_tiling<sphere_tile> polar(sphere_tile{}, 12, 0.4f, 0.15f);
    const krs::log_spherical_tiling<sphere_tile> spherical(sphere_tile{}, 12, 0.15f);

    std::mt19937_64 g(9);
    std::vector<vec3d> points{{0, 0, 0}, {0, 1e-30, 0}, {1e-38, 0, 0}};
    for (double r : {1e-35, 1e-30, 1e-20, 1e-10, 1e-5, 1.0, 1e3, 1e6})
        for (int i = 0; i < 8; ++i) points.push_back(random_direction(g) * r);
    points.push_back({0, 0, 1e6});
    points.push_back({0, 1e6, 0});
    auto check_all = [&](const auto& f, const char* name, bool bounded_by_radius = true) {
        for (const vec3d& p : points) {
            const double dd = f.distance(p);
            const float df = f.distance(vec3f(p));
            const krs::packet_f pf = f.distance(krs::vec3fP(vec3f(p)));
            INFO(name, " at (", p.x, ", ", p.y, ", ", p.z, "): ", dd, " ", df);
            CHECK(std::isfinite(dd));
            CHECK(std::isfinite(df));
            CHECK(xsimd::all(krs::is_finite(pf)));
            // Never far above the distance to the origin, where the copies accumulate.
            if (bounded_by_radius) CHECK(dd <= krs::length(p) * 1.0001 + 1e-30);
        }
    };
    check_all(lotus, "lotus");
    check_all(cubes, "cube singularity");
    check_all(cubes_raw, "cube singularity without fixes", false);
    check_all(lotus_hidden, "lotus with hidden boundary");
    check_all(polar, "log-polar");
    check_all(spherical, "log-spherical");

    // Rays aimed at the singularity end within max_steps with a defined result.
    krs::trace_options o;
    o.max_steps = 512;
    o.pixel_footprint = 1e-3f;
    auto trace_to_origin = [&](const auto& f, const char* name) {
        for (int i = 0; i < 32; ++i) {
            const vec3f from(random_direction(g) * 4.0);
            const krs::ray<float> r = krs::make_ray(from, -from);
            const krs::hit<float> h = krs::sphere_trace(f, r, o);
            INFO(name, " ray ", i, ": steps ", h.steps, " t ", h.t);
            CHECK_FALSE(h.invalid);
            CHECK(h.steps <= o.max_steps);
            CHECK(h.found);
            CHECK(std::isfinite(h.t));
            CHECK(h.t <= 4.0f + 1e-3f);
        }
    };
    trace_to_origin(lotus, "lotus");
    trace_to_origin(cubes, "cube singularity");
    trace_to_origin(polar, "log-polar");
    trace_to_origin(spherical, "log-spherical");
}

TEST_CASE("fractal packet lanes equal the scalar result")
{
    using P = krs::packet_f;
    constexpr std::size_t W = krs::lane_count<P>;
    std::mt19937_64 g(21);
    auto compare = [&](const auto& f, const char* name, bool scaled) {
        int mismatches = 0;
        krs_test::parity same{name, 2.0}; // the folds, over points in the cube of half-size 2
        for (int n = 0; n < 2000; ++n) {
            alignas(64) float xs[W], ys[W], zs[W];
            for (std::size_t i = 0; i < W; ++i) {
                const vec3d p = scaled ? log_uniform(g, 1e-4, 1e4) : in_cube(g, 2.0);
                xs[i] = float(p.x), ys[i] = float(p.y), zs[i] = float(p.z);
            }
            const krs::vec3fP pp{P::load_aligned(xs), P::load_aligned(ys), P::load_aligned(zs)};
            const P d = f.distance(pp);
            for (std::size_t i = 0; i < W; ++i) {
                const vec3f p{xs[i], ys[i], zs[i]};
                const float s = f.distance(p);
                // Bit-equal for the folds; the warps' packet log/exp/atan2 may differ from std's
                // by an ulp, which moves a continuous field by about that much of |p|.
                const bool agree = scaled ? std::abs(krs::lane_at(d, i) - s) <= 1e-5f * std::max(1.0f, krs::length(p))
                                          : same.agree(krs::lane_at(d, i), s);
                if (!agree) ++mismatches;
            }
        }
        same.report();
        INFO(std::string(name));
        CHECK(mismatches == 0);
    };
    compare(krs::make_square_fractal(6), "square fractal", false);
    compare(krs::make_cube_fractal(5), "cube fractal", false);
    compare(krs::make_menger_sponge(4), "Menger sponge", false);
    compare(krs::make_sierpinski_tetrahedron(8), "Sierpinski tetrahedron", false);
    compare(krs::make_koch_curve(5), "Koch curve", false);
    compare(krs::make_recursive_lotus(), "recursive lotus", true);
    compare(krs::make_cube_singularity(), "cube singularity", true);
    compare(krs::log_polar_tiling<sphere_tile>(sphere_tile{}, 12, 0.4f, 0.15f), "log-polar", true);
    compare(krs::log_spherical_tiling<sphere_tile>(sphere_tile{}, 12, 0.15f), "log-spherical", true);
}

TEST_CASE("fractal parameters are validated")
{
    using krs_test::rejects;
    const float nan = std::nanf("");
    rejects([] { krs::make_sierpinski_tetrahedron(5, 1.0f); }, "sierpinski_tetrahedron.scale");
    rejects([] { krs::make_sierpinski_tetrahedron(5, 0.5f); }, "sierpinski_tetrahedron.scale");
    rejects([&] { krs::make_sierpinski_tetrahedron(5, nan); }, "sierpinski_tetrahedron.scale");
    rejects([] { krs::scale_about(0.0f, {0, 0, 0}); }, "scale_about.factor");
    rejects([&] { krs::scale_about(2.0f, {nan, 0, 0}); }, "scale_about.center");
    rejects(
        [] {
            using program = krs::fold_program<krs::abs_fold<>, krs::scale_about>;
            krs::kifs<program, krs::sphere>(program({}, krs::scale_about(0.5f, {1, 1, 1})), krs::sphere({0, 0, 0}, 1), 4);
        },
        "kifs.program.scale");
    rejects([] { krs::make_menger_sponge(-1); }, "menger_sponge.iterations");
    rejects([&] { krs::plane_fold({nan, 0, 1}, 0); }, "plane_fold.normal");
    rejects([] { krs::plane_fold({0, 0, 0}, 0); }, "plane_fold.normal");
    rejects([&] { krs::rotate_step({0, 1, 0}, nan); }, "rotate_step.angle");
    rejects([&] { krs::make_koch_curve(4, nan); }, "koch_curve.tube_radius");
    rejects([] { krs::make_recursive_lotus(0.0f); }, "recursive_lotus.density");
    rejects([&] { krs::make_cube_singularity(nan); }, "cube_singularity.density");
    rejects([] { krs::similar_shell<sphere_tile>(sphere_tile{}, 0.0f); }, "similar_shell.density");
    rejects([&] { krs::similar_shell<sphere_tile>(sphere_tile{}, nan); }, "similar_shell.density");
    rejects(
        [&] {
            krs::shell_options o;
            o.step_factor = nan;
            krs::make_recursive_lotus(1.0f, 8, o);
        },
        "shell_options.step_factor");
    rejects(
        [] {
            krs::shell_options o;
            o.step_factor = 1.5f;
            krs::make_cube_singularity(1.0f, o);
        },
        "shell_options.step_factor");
    rejects(
        [] {
            krs::shell_options o;
            o.seam_band = 0.6f;
            krs::make_cube_singularity(1.0f, o);
        },
        "shell_options.seam_band");
    rejects(
        [] {
            krs::shell_options o;
            o.seam_band = -0.01f;
            krs::make_recursive_lotus(1.0f, 8, o);
        },
        "shell_options.seam_band");
    // A band of (s - 1) / (s + 1) or more covers every shell (0.4621 at density 1, 0.0500 at 10).
    rejects(
        [] {
            krs::shell_options o;
            o.seam_band = 0.47f;
            krs::make_cube_singularity(1.0f, o);
        },
        "shell_options.seam_band");
    rejects(
        [] {
            krs::shell_options o;
            o.seam_band = 0.06f;
            krs::make_recursive_lotus(10.0f, 8, o);
        },
        "shell_options.seam_band");
    {
        krs::shell_options o;
        o.seam_band = 0.46f;
        CHECK_NOTHROW(krs::make_cube_singularity(1.0f, o));
    }
    rejects([] { krs::log_polar_tiling<sphere_tile>(sphere_tile{}, 0, 0.4f); }, "log_polar_tiling.cells");
    rejects([&] { krs::log_polar_tiling<sphere_tile>(sphere_tile{}, 8, nan); }, "log_polar_tiling.height");
    rejects([] { krs::log_spherical_tiling<sphere_tile>(sphere_tile{}, 7); }, "log_spherical_tiling.cells");
    rejects([&] { krs::log_spherical_tiling<sphere_tile>(sphere_tile{}, 8, nan); }, "log_spherical_tiling.margin");
    rejects([] { krs::make_recursive_lotus(1.0f, 0); }, "lotus_shell.petals");
}

// bench_log_spherical_steps: the similar shell's step factor, global against local (issue 25
// item 6; the log-spherical note: "shorten the raymarching steps ... globally, or only locally in
// problematic regions").
//
//     bench_log_spherical_steps [--csv FILE] [--threads T] [--size N] [--rounds R]
//     (the CSV goes next to the executable, as <executable>.csv, unless --csv names one)
//
// For the recursive lotus and the cube singularity (density 1) and each seam setting (adjacent
// shells, none and hidden boundary, each with step factor 1, 0.5 everywhere, 0.5 within a band of
// relative width 0.06 of the seams; the local factor also in its earlier form, d times a factor
// ramped in beta from 0.5 at the band to 1 at twice it, reproduced here as `old ramp` for the
// side-by-side), next to the exact adjacent-shells field:
//   - the measured Lipschitz ratio max |d(p) - d(q)| / |p - q| over 200000 close pairs (|p - q| =
//     1e-3 |p|) near the seams (relative distance beta < 0.06), in the old ramp (0.06 <= beta <=
//     0.12, both points) and away from the seams (beta > 0.12);
//   - the worst overestimate (d - D) / r over 200000 points near the seams, D the union of the
//     prototype's copies in the five nearest shells (brute force, double);
//   - an N x N image (default 256) from a camera in free space: steps per ray, milliseconds (best
//     of R rounds, the settings alternating within each round), hits, and the pixels whose hit
//     differs from the exact field's image, and the depth RMSE (relative to depth) over the pixels
//     both hit.
// The load average before and after is printed: above the core count, other work shared the cores.

#include "krs/fractal/shell_presets.hpp"
#include "krs/fractal/similar_shell.hpp"
#include "krs/trace/camera.hpp"
#include "krs/trace/sphere_trace.hpp"
#include "support/text.hpp"
#include "support/timing.hpp"

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <fstream>
#include <functional>
#include <limits>
#include <random>
#include <string>
#include <thread>
#include <vector>

namespace {

using krs::vec3d;
using krs::vec3f;

double uniform(std::mt19937_64& g, double lo, double hi) { return lo + (hi - lo) * double(g() >> 11) * 0x1.0p-53; }
vec3d direction(std::mt19937_64& g)
{
    for (;;) {
        const vec3d v{uniform(g, -1, 1), uniform(g, -1, 1), uniform(g, -1, 1)};
        const double l = krs::length(v);
        if (l > 0.1 && l <= 1) return v / l;
    }
}
// A point at relative distance beta (signed) from the seam of one of the shells -3 .. 3.
vec3d near_seam(std::mt19937_64& g, double density, double beta)
{
    const double seam = std::exp(std::floor(uniform(g, -3, 4)) / density);
    return direction(g) * (seam * (1.0 + beta));
}
// The relative distance to the nearer seam of p's shell.
double seam_distance(const vec3d& p, double density)
{
    const double r = krs::length(p), k = std::floor(std::log(r) * density);
    const double inner = std::exp(k / density), outer = std::exp((k + 1) / density);
    return std::min(r - inner, outer - r) / r;
}
template <class F>
double union_of_shells(const F& f, const vec3d& p)
{
    const double density = f.density();
    const double k = std::floor(std::log(krs::length(p)) * density);
    double d = std::numeric_limits<double>::infinity();
    for (int j = -2; j <= 2; ++j) {
        const double scale = std::exp((k + j) / density);
        d = std::min(d, f.prototype().distance(p / scale) * scale);
    }
    return d;
}

struct setting {
    const char* name;
    krs::shell_options options;
    bool old_ramp = false; // the local factor's earlier form (bench_field)
};
constexpr float band = 0.06f;
const setting settings[] = {
    {"adjacent shells (exact)", {krs::shell_seams::adjacent_shells, 0.05f, 1.0f, 0.0f}},
    {"adjacent, 0.5 local", {krs::shell_seams::adjacent_shells, 0.05f, 0.5f, band}},
    {"adjacent, 0.5 old ramp", {krs::shell_seams::adjacent_shells, 0.05f, 0.5f, band}, true},
    {"none", {krs::shell_seams::none, 0.05f, 1.0f, 0.0f}},
    {"none, 0.5 global", {krs::shell_seams::none, 0.05f, 0.5f, 0.0f}},
    {"none, 0.5 local", {krs::shell_seams::none, 0.05f, 0.5f, band}},
    {"none, 0.5 old ramp", {krs::shell_seams::none, 0.05f, 0.5f, band}, true},
    {"hidden boundary", {krs::shell_seams::hidden_boundary, 0.05f, 1.0f, 0.0f}},
    {"hidden, 0.5 global", {krs::shell_seams::hidden_boundary, 0.05f, 0.5f, 0.0f}},
    {"hidden, 0.5 local", {krs::shell_seams::hidden_boundary, 0.05f, 0.5f, band}},
    {"hidden, 0.5 old ramp", {krs::shell_seams::hidden_boundary, 0.05f, 0.5f, band}, true},
};

// A setting's field. With old_ramp, the local factor as similar_shell had it before it was made
// 1-Lipschitz (log_spherical.hpp at 5a952cd, local_step): the field with factor 1 times
// f + (1 - f) clamp((beta - band) / band, 0, 1), beta = min(r - inner, outer - r) / r, the same
// operations in the same order. Its gradient in the ramp is about g + (1 - f) d / (band r).
template <class F>
struct bench_field {
    F shell;
    bool old_ramp = false;
    float factor = 1.0f, seam_band = 0.0f;

    template <class T>
    T distance(const krs::vec3<T>& p) const
    {
        const T d = shell.distance(p);
        if (!old_ramp) return d;
        const T r = krs::length(p);
        const T rs = krs::max(r, T(1e-30f));
        const T inv_density(1.0f / shell.density());
        const T k = krs::lane_floor(krs::lane_log(rs) * T(shell.density()));
        const T inner = krs::lane_exp(k * inv_density), outer = inner * T(shell.ratio());
        const T beta = krs::min(r - inner, outer - r) / krs::max(r, T(1e-30f));
        const T ramp = krs::clamp((beta - T(seam_band)) * T(1.0f / seam_band), T(0), T(1));
        return d * (T(factor) + T(1.0f - factor) * ramp);
    }
    double density() const { return shell.density(); }
    const auto& prototype() const { return shell.shell(); }
};
template <class F>
bench_field<F> field_of(const setting& s, const std::function<F(const krs::shell_options&)>& make)
{
    if (!s.old_ramp) return {make(s.options), false};
    krs::shell_options plain = s.options;
    plain.step_factor = 1.0f, plain.seam_band = 0.0f;
    return {make(plain), true, s.options.step_factor, s.options.seam_band};
}
constexpr std::size_t setting_count = std::size(settings);

struct frame {
    std::vector<float> t;
    std::vector<int> steps;
};

template <class F>
frame render(const F& f, const krs::pinhole_camera& camera, const krs::trace_options& o, int size, unsigned threads)
{
    frame fr;
    fr.t.assign(std::size_t(size) * size, 0.0f);
    fr.steps.assign(std::size_t(size) * size, 0);
    bench::run_parallel(threads, std::size_t(size), [&](std::size_t y) {
        for (int x = 0; x < size; ++x) {
            const krs::hit<float> h = krs::sphere_trace(f, camera.primary_ray(float(x) + 0.5f, float(y) + 0.5f), o);
            const std::size_t i = y * std::size_t(size) + std::size_t(x);
            fr.t[i] = h.found ? h.t : std::numeric_limits<float>::infinity();
            fr.steps[i] = h.steps;
        }
    });
    return fr;
}

template <class Make>
void bench_preset(const char* preset, const Make& make, const vec3f& eye, int size, int rounds, unsigned threads,
                  std::ofstream& csv)
{
    const double density = 1.0;
    using shell_t = decltype(make(krs::shell_options{}));
    using field_t = bench_field<shell_t>;
    std::vector<field_t> fields;
    const std::function<shell_t(const krs::shell_options&)> maker = make;
    for (const setting& s : settings) fields.push_back(field_of(s, maker));

    const krs::pinhole_camera camera(eye, {0, 0, 0.3f}, {0, 0, 1}, 50.0f, size, size);
    krs::trace_options o;
    o.max_steps = 2000;
    o.pixel_footprint = camera.pixel_footprint() * 0.5f;
    o.max_distance = 60.0f;
    std::vector<frame> frames(setting_count);
    std::vector<double> best(setting_count, 1e300);
    for (int r = 0; r < rounds; ++r)
        for (std::size_t i = 0; i < setting_count; ++i) {
            const auto start = std::chrono::steady_clock::now();
            frames[i] = render(fields[i], camera, o, size, threads);
            best[i] = std::min(best[i], std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count());
        }

    std::printf("%s (density 1, %dx%d, eye (%.1f, %.1f, %.1f))\n", preset, size, size, eye.x, eye.y, eye.z);
    std::printf("%-24s %9s %9s %9s %10s | %9s %8s %6s %9s %8s\n", "setting", "Lip seam", "Lip ramp", "Lip away", "over / r",
                "steps/ray", "ms", "hits", "hit diff", "depth");
    const frame& reference = frames[0];
    for (std::size_t i = 0; i < setting_count; ++i) {
        const field_t& f = fields[i];
        // Lipschitz ratios near the seams and away, and the worst overestimate near them.
        std::mt19937_64 g(11);
        double lip_seam = 0, lip_ramp = 0, lip_away = 0, over = -1e300;
        for (int k = 0; k < 200000; ++k) {
            const vec3d a = near_seam(g, density, uniform(g, -0.3, 0.3));
            const vec3d b = a + direction(g) * (1e-3 * krs::length(a));
            const double ratio = std::abs(f.distance(a) - f.distance(b)) / krs::length(b - a);
            const double beta = std::min(seam_distance(a, density), seam_distance(b, density));
            const double beta_far = std::max(seam_distance(a, density), seam_distance(b, density));
            if (beta < band) lip_seam = std::max(lip_seam, ratio);
            if (beta >= band && beta_far <= 2 * band) lip_ramp = std::max(lip_ramp, ratio);
            if (beta > 2 * band) lip_away = std::max(lip_away, ratio);
            const vec3d p = near_seam(g, density, uniform(g, -double(band), double(band)));
            const double truth = union_of_shells(f, p);
            if (truth > 0) over = std::max(over, (f.distance(p) - truth) / krs::length(p));
        }
        long long steps = 0, hits = 0, differ = 0, both = 0;
        double depth_sq = 0;
        for (std::size_t p = 0; p < frames[i].t.size(); ++p) {
            steps += frames[i].steps[p];
            const bool h = std::isfinite(frames[i].t[p]), w = std::isfinite(reference.t[p]);
            hits += h;
            differ += h != w;
            if (h && w) {
                const double e = (double(frames[i].t[p]) - double(reference.t[p])) / double(reference.t[p]);
                depth_sq += e * e, ++both;
            }
        }
        const double rays = double(frames[i].t.size());
        const double depth_rmse = both ? std::sqrt(depth_sq / double(both)) : 0.0;
        std::printf("%-24s %9.3f %9.3f %9.3f %10.4f | %9.2f %8.1f %6lld %9lld %8.2e\n", settings[i].name, lip_seam, lip_ramp,
                    lip_away, over, double(steps) / rays, best[i] * 1e3, hits, differ, depth_rmse);
        csv << preset << ",\"" << settings[i].name << "\"," << settings[i].options.step_factor << ','
            << settings[i].options.seam_band << ',' << settings[i].old_ramp << ',' << lip_seam << ',' << lip_ramp << ','
            << lip_away << ',' << over << ','
            << double(steps) / rays << ',' << best[i] << ',' << hits << ',' << differ << ',' << depth_rmse << ',' << size
            << '\n';
    }
    std::printf("\n");
}

} // namespace

int main(int argc, char** argv)
{
    std::string csv_path;
    unsigned threads = std::max(1u, std::thread::hardware_concurrency());
    int size = 256, rounds = 3;
    for (int i = 1; i < argc; ++i) {
        const std::string a = argv[i];
        if (i + 1 >= argc) {
            std::fprintf(stderr, "usage: %s [--csv FILE] [--threads T] [--size N] [--rounds R]\n", argv[0]);
            return 2;
        }
        const std::string v = argv[++i];
        if (a == "--csv") csv_path = v;
        else if (a == "--threads") threads = unsigned(std::max(1, std::atoi(v.c_str())));
        else if (a == "--size") size = std::clamp(std::atoi(v.c_str()), 16, 4096);
        else if (a == "--rounds") rounds = std::clamp(std::atoi(v.c_str()), 1, 100);
        else {
            std::fprintf(stderr, "unknown option %s\n", a.c_str());
            return 2;
        }
    }
    if (csv_path.empty()) csv_path = bench::csv_next_to_executable(argv[0]);
    std::ofstream csv(csv_path);
    csv << "preset,setting,step_factor,seam_band,old_ramp,lipschitz_near_seams,lipschitz_ramp,lipschitz_away,overestimate_over_r,steps_per_ray,"
           "seconds,hits,hit_differences,depth_rmse,size\n";
    const std::string load_before = bench::load_average();
    std::printf("similar shell step factor, global against local (seam band %.2f), %u thread(s), best of %d rounds\n"
                "Lip: max |d(p)-d(q)|/|p-q| over close pairs near the seams (beta < %.2f), in the old ramp (%.2f..%.2f) and away (beta > %.2f); "
                "over / r: worst (d - D) / r near the seams, D the union of shells (brute force); hit diff: pixels "
                "whose hit differs from the exact field's image; depth: RMSE of (t - t_exact) / t_exact where both "
                "hit\n\n",
                band, threads, rounds, band, band, 2 * band, 2 * band);
    bench_preset("recursive lotus", [](const krs::shell_options& o) { return krs::make_recursive_lotus(1.0f, 8, o); },
                 vec3f{1.5f, -1.0f, -3.0f}, size, rounds, threads, csv);
    bench_preset("cube singularity", [](const krs::shell_options& o) { return krs::make_cube_singularity(1.0f, o); },
                 vec3f{3.0f, 1.3f, -0.6f}, size, rounds, threads, csv);
    std::printf("load average before: %s; after: %s (%u cores)\n", load_before.c_str(), bench::load_average().c_str(),
                std::thread::hardware_concurrency());
    return 0;
}

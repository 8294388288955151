#pragma once
// Issue 23, items 1 and 4: the packet stream before issue 23 (bench/support/stream_reference.hpp)
// and the one now (trace_queue over queue_tile_rays) on the same scene, camera, rays and
// threshold, timed side by side in alternating rounds; and where the new stream's time goes.
//
// Figures "per core" and "1 thread" are in CPU time (thread_cpu_seconds below); the 2-thread
// Mrays/s is wall time, as the other tables' are.
//
// Where the time goes (one thread): the stream is run once more through `recording_field`, which
// keeps every batch of points the stream hands the field; replaying those batches through the
// field alone, in the same order and grouping, is the field's share of the stream's time (the
// replay reads its points, 12 bytes per lane, which the stream computes in registers; it replays
// chunks that are first read into the cache untimed, so what is left of that is L2 reads: a
// small overestimate of the field's part). What is left, divided by the rays that
// enter the box, is the stream's cost per ray outside the field. The queue rate is
// queue_tile_rays alone over every tile of the picture (camera rays, box test, compaction).
//
// Ceiling: Amdahl's bound on the one-thread ratio new / old, the old stream's time over the
// field's alone (= ratio / field share): what a stream with no cost outside the field would
// reach. Where it is below a target ratio (bench_packet_trace's tree, forest and terrain, whose
// rays take 14-18 evaluations each), no work on the stream can meet the target.
//
// Roofline: this machine's hypervisor exposes no hardware counters (`perf stat -e instructions`
// says "not supported"), so cycles are seconds times the nominal clock (/proc/cpuinfo), and the
// bound is empirical: the same field on its first recorded batch, over and over (all in L1,
// no dependence between calls): the rate of a level's instructions when nothing but their issue
// limits them. Lane-levels count each busy lane's evaluation once per level of the sequence.

#include "stream_reference.hpp"
#include "timing.hpp"
#include "krs/trace/box_clip.hpp"
#include "krs/trace/camera.hpp"
#include "krs/trace/packet_trace.hpp"
#include "krs/trace/tile_rays.hpp"

#include <benchmark/benchmark.h>

#include <algorithm>
#include <atomic>
#include <chrono>
#include <cmath>
#include <cstdint>
#include <cstdio>
#include <cstdlib>
#include <fstream>
#include <string>
#include <thread>
#include <time.h>
#include <vector>

namespace bench {

// The clock the cycle figures (lane-lv/cyc) are counted at, and where it was read. The nominal
// (base) clock where the system gives it: cpufreq's base_frequency, else its cpuinfo_max_freq (the
// highest, boost included), else the "@ N GHz" of the model name; failing all three (e.g. in a VM),
// the "cpu MHz" of /proc/cpuinfo, which is the first core's clock at the moment of reading, not a
// nominal one.
struct cpu_clock {
    double ghz = 0.0;
    const char* source = "unknown";
};
inline cpu_clock read_cpu_clock()
{
    for (const char* file : {"/sys/devices/system/cpu/cpu0/cpufreq/base_frequency",
                             "/sys/devices/system/cpu/cpu0/cpufreq/cpuinfo_max_freq"}) {
        std::ifstream in(file);
        double khz = 0;
        if (in >> khz && khz > 0) return {khz * 1e-6, file};
    }
    double current = 0.0;
    std::ifstream in("/proc/cpuinfo");
    std::string line;
    while (std::getline(in, line)) {
        if (line.rfind("model name", 0) == 0) {
            const std::size_t at = line.find('@'), unit = line.find("GHz");
            if (at != std::string::npos && unit != std::string::npos && unit > at) {
                const double ghz = std::atof(line.substr(at + 1, unit - at - 1).c_str());
                if (ghz > 0) return {ghz, "the model name"};
            }
        }
        if (current == 0.0 && line.rfind("cpu MHz", 0) == 0)
            current = std::atof(line.substr(line.find(':') + 1).c_str()) * 1e-3;
    }
    if (current > 0) return {current, "cpu MHz of /proc/cpuinfo (the current clock, not the nominal one)"};
    return {};
}

// A field that keeps every batch of K packets the stream evaluates together.
template <class F, class P, std::size_t K>
struct recording_field {
    const F& f;
    std::vector<std::array<krs::vec3<P>, K>>* log;
    float distance(const krs::vec3f& p) const { return f.distance(p); }
    double distance(const krs::vec3d& p) const { return f.distance(p); }
    template <class T, std::size_t N>
    std::array<T, N> distances(const std::array<krs::vec3<T>, N>& points) const
    {
        if constexpr (std::is_same_v<T, P> && N == K) log->push_back(points);
        return krs::detail::distances_of(f, points);
    }
    bool varying_cost() const
    {
        if constexpr (requires { f.varying_cost(); }) return f.varying_cost();
        return false;
    }
};

struct stream_frame {
    std::vector<std::uint8_t> hit;
    double seconds = 0;     // wall time
    double cpu_seconds = 0; // the threads' CPU time, summed
    long long evaluations = 0;
    double mrays() const { return double(hit.size()) / seconds * 1e-6; }
    double mrays_per_cpu_second() const { return double(hit.size()) / cpu_seconds * 1e-6; }
};

// One render of the picture in tile x tile tiles from a shared counter on `threads` threads, with
// the new stream (`old_path` false) or the old one, Interleave packets of P stepped together.
template <class P, int Interleave, class F>
stream_frame render_stream(const F& f, const krs::pinhole_camera& camera, const krs::box_clip& clip,
                           const krs::trace_options& o, int tile, int threads, bool old_path)
{
    const int width = camera.width(), height = camera.height();
    const int tiles_x = (width + tile - 1) / tile, tiles = tiles_x * ((height + tile - 1) / tile);
    stream_frame out;
    out.hit.assign(std::size_t(width) * std::size_t(height), 0);
    std::atomic<int> next_tile{0};
    std::atomic<long long> evaluations{0};
    krs::tile_prepass from_near;
    from_near.start = o.min_distance;
    auto take_tile = [&](int& x0, int& y0, int& x1, int& y1) {
        const int k = next_tile.fetch_add(1);
        if (k >= tiles) return false;
        x0 = (k % tiles_x) * tile, y0 = (k / tiles_x) * tile, x1 = x0 + tile, y1 = y0 + tile;
        return true;
    };
    std::atomic<long long> cpu_ns{0};
    auto worker = [&] {
        const double cpu0 = thread_cpu_seconds();
        std::uint8_t* hit = out.hit.data();
        auto done = [&](std::uint32_t id, const krs::hit<float>& h) { hit[id] = h.found ? 1 : 0; };
        int x0, y0, x1, y1;
        if (old_path) {
            reference::tile_rays_reference<P> rays;
            auto next = [&](krs::ray_job& job) {
                while (!rays.pop(job)) {
                    if (!take_tile(x0, y0, x1, y1)) return false;
                    rays.fill(camera, x0, y0, x1, y1, from_near, o.max_distance, clip);
                }
                return true;
            };
            evaluations += reference::trace_stream_reference<P, Interleave>(f, next, done, o).evaluations;
        } else {
            krs::ray_queue<P> queue;
            auto more = [&](krs::ray_queue<P>& q) {
                if (!take_tile(x0, y0, x1, y1)) return false;
                krs::queue_tile_rays(q, camera, x0, y0, x1, y1, from_near, o.max_distance, clip);
                return true;
            };
            evaluations += krs::trace_queue<P, Interleave>(f, queue, more, done, o).evaluations;
        }
        cpu_ns += (long long)(1e9 * (thread_cpu_seconds() - cpu0));
    };
    const auto start = std::chrono::steady_clock::now();
    std::vector<std::thread> pool;
    for (int i = 1; i < threads; ++i) pool.emplace_back(worker);
    worker();
    for (std::thread& t : pool) t.join();
    out.seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
    out.evaluations = evaluations.load();
    out.cpu_seconds = 1e-9 * double(cpu_ns.load());
    benchmark::DoNotOptimize(out.hit.data());
    return out;
}

struct stream_comparison {
    double old_mrays = 0, new_mrays = 0;     // best of the rounds, `threads` threads
    double old_mrays_1 = 0, new_mrays_1 = 0; // the same on one thread
    int frames = 1;                          // renders per timing
    long long hit_differ = 0, pixels = 0;
    long long in_box = 0;
    double evals_per_in_box = 0;
    double new_seconds_1 = 0, field_seconds = 0; // one thread
    double queue_mrays = 0;                      // queue_tile_rays alone, one thread
    double lane_levels_per_cycle = 0, bound_lane_levels_per_cycle = 0;
    double field_share() const { return field_seconds / new_seconds_1; }
    // Amdahl's ceiling on new / old: the one-thread ratio a stream that cost nothing outside the
    // field would reach (the old stream's time over the field's time alone, i.e. the measured
    // ratio over the field share). Below a target ratio, no work on the stream can reach it.
    double ceiling() const { return (new_mrays_1 / old_mrays_1) / field_share(); }
    double outside_ns_per_in_box() const { return 1e9 * (new_seconds_1 - field_seconds) / double(in_box); }
};

// Old and new alternate within each of `rounds` rounds (the first of the two swapping every
// round); each figure is the best of its rounds. `levels`: the sequence's mirror count.
template <class P, int Interleave, class F>
stream_comparison compare_streams(const F& f, const krs::pinhole_camera& camera, const krs::trace_options& o,
                                  int tile, int threads, int rounds, int levels)
{
    constexpr std::size_t W = krs::lane_count<P>;
    const krs::box_clip clip(krs::field_box(f), camera.eye(), o);
    stream_comparison c;
    // Each timing renders the picture `frames` times, enough for about 50 ms of the old path on
    // one thread: a single frame of a cheap scene takes a few milliseconds, and on a shared
    // machine a descheduled thread then decides the figure.
    const double first = render_stream<P, Interleave>(f, camera, clip, o, tile, 1, true).cpu_seconds;
    const int frames = std::clamp(int(0.05 / std::max(first, 1e-6)), 1, 200);
    c.frames = frames;
    auto timed = [&](int thread_count, bool old_path, stream_frame& out) {
        double total = 0, cpu = 0;
        for (int i = 0; i < frames; ++i) {
            stream_frame fr = render_stream<P, Interleave>(f, camera, clip, o, tile, thread_count, old_path);
            total += fr.seconds, cpu += fr.cpu_seconds;
            if (i == 0) out = std::move(fr);
        }
        out.seconds = total / frames, out.cpu_seconds = cpu / frames;
    };
    stream_frame best[2], best_1[2];
    for (int r = 0; r < rounds; ++r)
        for (int k = 0; k < 2; ++k) {
            const int which = (k + r) % 2; // 0: old, 1: new
            stream_frame fr, fr1;
            timed(threads, which == 0, fr);
            timed(1, which == 0, fr1);
            if (r == 0 || fr.seconds < best[which].seconds) best[which] = std::move(fr);
            if (r == 0 || fr1.cpu_seconds < best_1[which].cpu_seconds) best_1[which] = std::move(fr1);
        }
    c.old_mrays = best[0].mrays(), c.new_mrays = best[1].mrays();
    c.old_mrays_1 = best_1[0].mrays_per_cpu_second(), c.new_mrays_1 = best_1[1].mrays_per_cpu_second();
    c.pixels = (long long)best[0].hit.size();
    for (std::size_t i = 0; i < best[0].hit.size(); ++i) c.hit_differ += best[0].hit[i] != best[1].hit[i];

    // The queue alone, one thread: every tile queued (and cleared) in turn.
    const int width = camera.width(), height = camera.height();
    krs::tile_prepass from_near;
    from_near.start = o.min_distance;
    krs::ray_queue<P> queue;
    double queue_best = 1e300;
    for (int r = 0; r < rounds; ++r) {
        long long in_box = 0;
        const double start = thread_cpu_seconds();
        for (int i = 0; i < frames; ++i) {
            in_box = 0;
            for (int y0 = 0; y0 < height; y0 += tile)
                for (int x0 = 0; x0 < width; x0 += tile) {
                    queue.clear();
                    krs::queue_tile_rays(queue, camera, x0, y0, x0 + tile, y0 + tile, from_near, o.max_distance, clip);
                    in_box += (long long)queue.size();
                }
        }
        queue_best = std::min(queue_best, (thread_cpu_seconds() - start) / frames);
        c.in_box = in_box;
    }
    c.queue_mrays = double(width) * double(height) / queue_best * 1e-6;

    // One thread: the stream (timed above), then its recorded field batches replayed.
    const long long evaluations = best_1[1].evaluations;
    c.new_seconds_1 = best_1[1].cpu_seconds;
    c.evals_per_in_box = double(evaluations) / double(std::max<long long>(c.in_box, 1));
    std::vector<std::array<krs::vec3<P>, Interleave>> log;
    log.reserve(std::size_t(evaluations) / W + 1024);
    const recording_field<F, P, Interleave> rec{f, &log};
    render_stream<P, Interleave>(rec, camera, clip, o, tile, 1, false);
    // The log is replayed in chunks of 128 batches (96 KiB with 4 packets of 16 lanes), each read
    // once untimed (into the L2 cache) and then timed through the field: the stream makes its
    // points in registers, and a log of 10-20 MB streamed from memory (tree, forest, terrain)
    // made the replay slower than the whole stream on a loaded machine (shares above 100%).
    constexpr std::size_t chunk = 128;
    double replay = 1e300;
    P sink(0.0f);
    for (int r = 0; r < rounds; ++r) {
        double timed = 0.0;
        for (int i = 0; i < frames; ++i)
            for (std::size_t first = 0; first < log.size(); first += chunk) {
                const std::size_t last = std::min(log.size(), first + chunk);
                P touch(0.0f);
                for (std::size_t b = first; b < last; ++b)
                    for (const krs::vec3<P>& p : log[b]) touch += p.x + p.y + p.z;
                benchmark::DoNotOptimize(touch);
                const double start = thread_cpu_seconds();
                for (std::size_t b = first; b < last; ++b) {
                    const std::array<P, Interleave> d = krs::detail::distances_of(f, log[b]);
                    for (const P& v : d) sink += v;
                }
                timed += thread_cpu_seconds() - start;
            }
        replay = std::min(replay, timed / frames);
    }
    c.field_seconds = replay;
    // The hot loop: the first batch again and again (no dependence from one call to the next).
    double hot = 1e300;
    const std::size_t hot_calls = std::max<std::size_t>(log.size() * std::size_t(frames), 1000);
    if (!log.empty()) {
        const auto points = log[log.size() / 2];
        for (int r = 0; r < rounds; ++r) {
            const double start = thread_cpu_seconds();
            for (std::size_t i = 0; i < hot_calls; ++i) {
                auto p = points;
                benchmark::DoNotOptimize(p);
                const std::array<P, Interleave> d = krs::detail::distances_of(f, p);
                for (const P& v : d) sink += v;
            }
            hot = std::min(hot, thread_cpu_seconds() - start);
        }
    }
    benchmark::DoNotOptimize(sink);
    const double ghz = read_cpu_clock().ghz;
    if (ghz > 0 && !log.empty()) {
        c.lane_levels_per_cycle = double(evaluations) * double(levels) / (replay * ghz * 1e9);
        c.bound_lane_levels_per_cycle =
            double(hot_calls) * double(Interleave) * double(W) * double(levels) / (hot * ghz * 1e9);
    }
    return c;
}

inline void print_stream_header()
{
    const cpu_clock clock = read_cpu_clock();
    std::printf("lane-lv/cyc: cycles at %.3f GHz, read from %s\n", clock.ghz, clock.source);
    std::printf("ceiling: the 1-thread new/old ratio if the stream cost nothing outside the field (old time / field "
                "time = ratio / field share: Amdahl)\n");
    std::printf("%-22s %3s %17s %6s %17s %6s %7s %5s %7s %6s %7s %7s %6s %13s\n", "scene", "n", "old / new Mr/s", "ratio",
                "1 thread: old/new", "ratio", "ceiling", "hit", "evals", "field", "ns out", "queue", "in box", "lane-lv/cyc");
    std::printf("%-22s %3s %17s %6s %17s %6s %7s %5s %7s %6s %7s %7s %6s %13s\n", "", "", "(2 threads)", "", "", "", "",
                "diff", "/in-box", "share", "/in-box", "Mr/s/c", "", "meas / bound");
}

inline std::string stream_row(const char* scene, int n, const stream_comparison& c)
{
    std::printf("%-22s %3d %8.2f /%8.2f %5.2fx %8.2f /%8.2f %5.2fx %6.2fx %5lld %7.2f %5.1f%% %7.2f %7.1f %5.1f%% %6.2f / %5.2f\n",
                scene, n, c.old_mrays, c.new_mrays, c.new_mrays / c.old_mrays, c.old_mrays_1, c.new_mrays_1,
                c.new_mrays_1 / c.old_mrays_1, c.ceiling(), c.hit_differ, c.evals_per_in_box, 100 * c.field_share(),
                c.outside_ns_per_in_box(), c.queue_mrays, 100.0 * double(c.in_box) / double(c.pixels),
                c.lane_levels_per_cycle, c.bound_lane_levels_per_cycle);
    std::fflush(stdout);
    char line[512];
    std::snprintf(line, sizeof line, "stream,%s,%d,%.4f,%.4f,%.4f,%.4f,%.4f,%lld,%lld,%.4f,%.4f,%.3f,%.2f,%.6f,%.4f,%.4f,%d,%.4f",
                  scene, n, c.old_mrays, c.new_mrays, c.new_mrays / c.old_mrays, c.old_mrays_1, c.new_mrays_1,
                  c.hit_differ, c.pixels, c.evals_per_in_box, c.field_share(), c.outside_ns_per_in_box(), c.queue_mrays,
                  double(c.in_box) / double(c.pixels), c.lane_levels_per_cycle, c.bound_lane_levels_per_cycle, c.frames, c.ceiling());
    return line;
}
inline const char* stream_csv_header()
{
    return "table,scene,n,old_mrays_s,new_mrays_s,ratio,old_mrays_s_1_thread,new_mrays_s_1_thread,hit_differ,pixels,"
           "evals_per_in_box_ray,field_share,outside_ns_per_in_box_ray,queue_mrays_s_per_core,in_box_share,"
           "lane_levels_per_cycle,bound_lane_levels_per_cycle,frames_per_timing,ceiling_ratio";
}

} // namespace bench

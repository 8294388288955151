#pragma once
// Packet tracing with lane refill: a stream of rays traced W at a time (W = lane_count<P>).
//
// A plain packet (`sphere_trace(f, ray<packet_f>, ...)`) runs until its slowest lane is done, so
// most lanes idle while one grazing ray creeps along a branch. Here a packet pulls a new ray from
// the caller's queue into every lane that finished, and several packets (`Interleave`) are
// stepped together: their sample points go to the field in one call, and a field that walks
// several points in lockstep (a sequence's `distances`) overlaps one packet's chain of dependent
// operations with another's (about 1.5x on general mirrors, bench_embree_peer). The step itself
// is `march_advance`, the template the scalar tracer's `march_step` runs: scheduling is the only
// thing this header adds (docs/design.md#rule-1).
//
// Rays wait in a `ray_queue` (krs/trace/ray_queue.hpp): a packet's finished lanes are refilled
// from it a whole register at a time, and a ray that cannot be marched never takes a lane.
//
// `trace_queue(f, queue, more, done, ...)` traces a queue and asks `more(queue)` for more rays
// when it runs dry (false: there are no more; krs/trace/tile_rays.hpp queues a screen tile's
// rays in packets). `trace_stream(f, next, done, ...)` takes rays one at a time from
// `next(ray_job&) -> bool` instead and queues them itself. Results leave through
// `done(std::uint32_t id, const hit<float>&)`, in completion order, on the calling thread, in
// runs: finished rays wait in a buffer of a few hundred and are reported when it is full and
// before the stream returns (so `done` may see a ray after `more` was asked for the next rays;
// every ray is reported exactly once, before trace_queue returns). The library starts no thread;
// callers run one stream per thread (e.g. one per tile).

#include "krs/trace/ray_queue.hpp"
#include "krs/trace/sphere_trace.hpp"

#include <algorithm>
#include <array>
#include <bit>
#include <cstdint>
#include <limits>
#include <utility>
#include <vector>

namespace krs {

// What a stream did, for benchmarks: rays finished, field evaluations used by rays, packet steps
// executed and how many of their lanes did useful work (utilization = busy_lanes / (steps * W)).
struct stream_stats {
    long long rays = 0;
    long long evaluations = 0;
    long long packet_steps = 0;
    long long busy_lanes = 0;
    double lane_utilization(std::size_t width) const
    {
        return packet_steps ? double(busy_lanes) / (double(packet_steps) * double(width)) : 0.0;
    }
    stream_stats& operator+=(const stream_stats& o)
    {
        rays += o.rays, evaluations += o.evaluations, packet_steps += o.packet_steps, busy_lanes += o.busy_lanes;
        return *this;
    }
};

namespace detail {

// The field at K points: in one call when the field walks several points in lockstep (a
// sequence's `distances`), else one call per point.
template <field F, class T, std::size_t K>
std::array<T, K> distances_of(const F& f, const std::array<vec3<T>, K>& points)
{
    if constexpr (lockstep_field<F, T, K>) {
        return f.template distances<T, K>(points);
    } else {
        std::array<T, K> d;
        for (std::size_t k = 0; k < K; ++k) d[k] = f.distance(points[k]);
        return d;
    }
}

// The lowest n set bits of `bits` (all of them when it has at most n).
inline std::uint64_t lowest_bits(std::uint64_t bits, std::size_t n)
{
    std::uint64_t out = 0;
    for (std::size_t k = 0; k < n && bits != 0; ++k) {
        const std::uint64_t low = bits & (~bits + 1);
        out |= low, bits ^= low;
    }
    return out;
}

// When to refill. Lanes that finish early idle until refilled, but a lane refilled alone starts
// its ray while its neighbours are deep into theirs: the packet's points then lie far apart. Where
// every evaluation costs about the same (a grid of copies walks every level at every point) that
// does not matter, and refilling as soon as a quarter of the lanes have finished keeps the most
// lanes busy (a grid of 2^22 rings: 86 Mrays/s, against 70 refilling whole packets). Where the
// cost depends on the point (`varying_cost()`: a tree's walk ends early far from the fine
// branches and late near them), a packet walks as deep as its deepest lane, and packets of
// neighbouring rays started together walk alike: refilled whole, a tree's packets go 1.4x faster
// with 92% of lanes busy instead of 98% (bench_packet_trace).
template <class F>
int default_refill(const F& f, int width)
{
    if constexpr (requires { { f.varying_cost() } -> std::convertible_to<bool>; })
        if (f.varying_cost()) return width;
    return width >= 4 ? width / 4 : 1;
}

} // namespace detail

namespace detail {

// trace_queue's loop, compiled once per form of the step (Relaxed: omega > 1, see march_advance).
template <bool Relaxed, class P, int Interleave, field F, class More, class Done>
stream_stats trace_queue_with(const F& f, ray_queue<P>& queue, More& more, Done& done, const trace_options& options,
                              int refill_at)
{
    using ids = index_lanes<P>;
    constexpr std::size_t W = lane_count<P>;
    if (refill_at <= 0) refill_at = detail::default_refill(f, int(W));
    // The options as lane constants, made once: the step reads nothing else from them.
    const march_limits<P> limits(options);
    stream_stats stats;
    // Reports the rays set aside since the queue was last cleared.
    auto report_set_aside = [&] {
        hit<float> h;
        h.t = std::numeric_limits<float>::infinity();
        // (Bounds in locals, as in report_finished.)
        for (const std::int32_t *id = queue.missed().data(), *end = id + queue.missed().size(); id != end; ++id)
            done(std::uint32_t(*id), h);
        h.invalid = true;
        for (const std::int32_t *id = queue.invalid().data(), *end = id + queue.invalid().size(); id != end; ++id)
            done(std::uint32_t(*id), h);
        stats.rays += (long long)(queue.missed().size() + queue.invalid().size());
        queue.clear_set_aside();
    };
    bool open = true; // `more` may still add rays
    auto refill_queue = [&] {
        while (open && queue.empty()) {
            queue.clear();
            open = more(queue);
            report_set_aside();
        }
        return !queue.empty();
    };
    report_set_aside();

    // Every lane starts idle (an empty range at the origin, no step taken): the first harvest
    // fills them all.
    std::array<march_state<P>, Interleave> state;
    std::array<ids, Interleave> id;
    std::array<std::uint64_t, Interleave> live{};
    for (int k = 0; k < Interleave; ++k) {
        state[k] = start_march(ray<P>{{P(0.0f), P(0.0f), P(0.0f)}, {P(0.0f), P(0.0f), P(1.0f)}}, P(1.0f), P(0.0f), options);
        id[k] = ids(0);
    }

    // Finished rays wait in `out` (structure of arrays, filled by one compress per value and
    // packet) and leave through `done` in runs of up to report_run: calling `done` lane by lane
    // at each harvest cost a loop whose trip count (the lanes that finished, 4-8) changes from
    // one harvest to the next, so its exit was mispredicted about once per harvest; a run of a
    // few hundred ends once. Found is kept as a value (1 or 0) beside t and the step count.
    constexpr std::size_t report_run = 256;
    struct finished_rays {
        alignas(64) std::array<std::int32_t, report_run + W> id;
        alignas(64) std::array<float, report_run + W> t, steps, found;
    };
    std::vector<finished_rays> out_store(1); // on the heap: 16 KiB is too much for the stack
    finished_rays& out = out_store.front();
    std::size_t out_count = 0;
    // (The count and the arrays are read into locals first: `done` typically stores through a
    // byte pointer, which may alias anything, so a bound kept in `out_count` was reloaded from
    // memory at every ray.)
    auto report_finished = [&] {
        const std::size_t n = out_count;
        const std::int32_t* who = out.id.data();
        const float *t = out.t.data(), *steps = out.steps.data(), *found = out.found.data();
        for (std::size_t c = 0; c < n; ++c) {
            hit<float> h;
            h.t = t[c], h.found = found[c] != 0.0f;
            h.steps = h.evaluations = int(steps[c]); // one evaluation per step (march_result)
            done(std::uint32_t(who[c]), h);
        }
        stats.rays += (long long)n;
        out_count = 0;
    };

    // Moves the finished lanes of packet k to `out` and refills its idle lanes (the caller calls
    // it when at least refill_at lanes have finished or none runs). The stream's counters are
    // kept per step (below), not per ray.
    auto harvest = [&](int k, std::uint64_t active) -> std::uint64_t {
        march_state<P>& m = state[k];
        const std::uint64_t finished = live[k] & ~active;
        if (finished != 0) {
            const std::size_t at = out_count;
            compress_store(out.t.data() + at, m.result.t, finished);
            compress_store(out.steps.data() + at, P(m.result.steps), finished); // count_t<P> is int for scalars
            compress_store(out.found.data() + at, select(m.result.found, P(1.0f), P(0.0f)), finished);
            out_count += compress_store(out.id.data() + at, id[k], finished);
            if (out_count >= report_run) report_finished();
        }
        // Every lane not running takes the queue's next ray, while there are rays.
        std::uint64_t want = ~active & low_bits(W), filled = 0;
        while (want != 0 && refill_queue()) {
            const std::size_t need = std::size_t(std::popcount(want));
            const std::uint64_t take = queue.size() >= need ? want : detail::lowest_bits(want, queue.size());
            queue.take(take, m.r, m.t, m.t_max, id[k]);
            filled |= take, want &= ~take;
        }
        live[k] = (live[k] & active) | filled;
        if (filled == 0) return active;
        const mask_t<P> fresh = mask_from_bits<P>(filled);
        restart_lanes<Relaxed>(m, fresh, limits.omega);
        m.active = m.active || fresh;
        return active | filled;
    };

    for (;;) {
        std::array<std::uint64_t, Interleave> active;
        int first_running = -1;
        for (int k = 0; k < Interleave; ++k) {
            active[k] = mask_bits<P>(state[k].active);
            if (active[k] == 0 || std::popcount(live[k] & ~active[k]) >= refill_at) active[k] = harvest(k, active[k]);
            if (active[k] != 0 && first_running < 0) first_running = k;
        }
        // Nothing runs after every packet was refilled: the queue and `more` are used up.
        if (first_running < 0) break;
        // All packets' points in one evaluation. An idle lane is evaluated at its ray's origin
        // (its sample point may be at infinity), and a packet with no active lane left, near the
        // end of the stream, takes the points of an active one: it rides along at no extra depth
        // of the walk and is not advanced.
        // (The array is made whole from its points: a default-constructed one was zeroed first,
        // a call to memset per step.)
        auto point_of = [&](std::size_t k) {
            const march_state<P>& m = state[active[k] != 0 ? k : std::size_t(first_running)];
            return point_at(m.r, select(m.active, m.t, P(0.0f)));
        };
        const std::array<P, Interleave> d = detail::distances_of(f, [&]<std::size_t... k>(std::index_sequence<k...>) {
            return std::array<vec3<P>, Interleave>{point_of(k)...};
        }(std::make_index_sequence<Interleave>{}));
        for (int k = 0; k < Interleave; ++k) {
            if (active[k] == 0) continue;
            march_advance<Relaxed>(state[k], d[std::size_t(k)], limits);
            // Each active lane took one step and one evaluation: counted here, a popcount per
            // packet step, instead of summing the finished lanes' counters at each harvest.
            stats.busy_lanes += std::popcount(active[k]);
            ++stats.packet_steps;
        }
    }
    report_finished();
    stats.evaluations = stats.busy_lanes;
    return stats;
}

} // namespace detail

// Traces every ray of `queue`, and of what `more(queue)` adds each time the queue runs dry (it
// returns false when there is nothing more; the queue is cleared before each call), through f
// with packets of type P, refilling finished lanes. A packet's lanes are refilled once at least
// `refill_at` of them have finished (default: see above), or when none is left running. Rays
// the queue set aside are reported as misses (`invalid` for unusable rays) without a step.
// Results equal per-ray `sphere_trace` calls up to float rounding of the packet math.
//
// Per packet the stream keeps a march_state, the lanes' ids (index lanes) and `live`, the lanes
// holding a ray not yet reported. A harvest compresses the finished lanes' results into the
// report buffer (reported to `done` a run at a time) and expands the queue's next rays into those
// lanes (their ray, t and t_max); `restart_lanes`, start_march's own reset, then starts them, and
// they are marked active. No lane is ever invalid here: the queue set those rays aside.
//
// The step is march_advance with the options made lane constants once (march_limits) and its
// form (relaxed or plain) fixed per compiled loop; the packets' states stay in memory between
// field calls (4 packets' rays, ranges and results are more than the 32 vector registers, and a
// field call that is not inlined keeps none of them), so each step loads and stores only what
// it reads and changes.
template <class P = packet_f, int Interleave = 2, field F, class More, class Done>
stream_stats trace_queue(const F& f, ray_queue<P>& queue, More&& more, Done&& done, const trace_options& options,
                         int refill_at = 0)
{
    static_assert(Interleave >= 1, "trace_queue needs at least one packet");
    options.validate();
    if (options.omega > 1.0f) return detail::trace_queue_with<true, P, Interleave>(f, queue, more, done, options, refill_at);
    return detail::trace_queue_with<false, P, Interleave>(f, queue, more, done, options, refill_at);
}

// Traces every ray `next` yields (taken a few packets' worth at a time into a ray_queue) through
// f with packets of type P, as trace_queue does; rays whose range is empty (t_start > t_max) or
// that cannot be marched are reported as misses without a step. Results equal per-ray
// `sphere_trace` calls up to float rounding of the packet math.
template <class P = packet_f, int Interleave = 2, field F, class Next, class Done>
stream_stats trace_stream(const F& f, Next&& next, Done&& done, const trace_options& options, int refill_at = 0)
{
    options.validate();
    ray_queue<P> queue;
    bool open = true;
    auto more = [&](ray_queue<P>& q) {
        // Enough rays to refill every packet once, so `next` is called in runs.
        constexpr std::size_t batch = 2 * Interleave * lane_count<P>;
        std::size_t pulled = 0;
        ray_job job;
        while (open && pulled < batch && (open = next(job))) q.push(job), ++pulled;
        return pulled > 0;
    };
    return trace_queue<P, Interleave>(f, queue, more, done, options, refill_at);
}

} // namespace krs

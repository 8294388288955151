#pragma once
// The packet stream and tile ray queue as they were before issue 23 (krs/trace/packet_trace.hpp
// and krs/trace/tile_rays.hpp at d69f522), kept verbatim apart from names, so the benchmarks can
// time the old path beside the new one in the same run. Not library code: nothing else uses it.

#include "krs/trace/packet_trace.hpp"
#include "krs/trace/tile_rays.hpp"

#include <array>
#include <bit>
#include <cstdint>
#include <limits>
#include <vector>

namespace bench::reference {
using namespace krs;


namespace old_detail {

// The march state and step as they were before the step was cut down (issue 23, step overhead):
// copied from krs/trace/sphere_trace.hpp at 639ae0a, so the old stream keeps its old step while
// the library's changes.
template <class T>
struct old_march_state {
    ray<T> r{};
    T t{};
    T t_max{};
    T accepted_t{};
    T accepted_d{};
    T omega{};
    T threshold_bias{};
    mask_t<T> active{};
    hit<T> result{};
};

template <class T>
old_march_state<T> old_start_march(const ray<T>& r, const T& t_start, const T& t_max, const trace_options& options)
{
    using S = scalar_t<T>;
    old_march_state<T> m;
    m.r = r;
    m.result.invalid = unusable_ray(r, t_start);
    m.active = !m.result.invalid && t_start <= t_max;
    m.result.found = m.active && !m.active;
    m.result.t = T(std::numeric_limits<S>::infinity());
    m.t = t_start;
    m.t_max = t_max;
    m.accepted_t = t_start;
    m.accepted_d = T(std::numeric_limits<S>::infinity());
    m.omega = T(options.omega);
    return m;
}

template <class T>
void old_march_advance(old_march_state<T>& m, const T& d, const trace_options& options)
{
    const mask_t<T> was_active = m.active;
    m.result.steps += krs::detail::count_if<T>(was_active);
    m.result.evaluations += krs::detail::count_if<T>(was_active);
    const T threshold = options.threshold(m.t) + m.threshold_bias;
    mask_t<T> accept = was_active, fail = was_active && !was_active;
    if (options.omega > 1.0f) {
        const mask_t<T> relaxed = m.omega > T(1);
        const mask_t<T> overlap = (m.accepted_d + abs(d) - (m.t - m.accepted_t)) >= T(2) * threshold;
        fail = was_active && relaxed && !overlap;
        accept = was_active && !fail;
        m.t = select(fail, m.accepted_t + m.accepted_d, m.t);
        m.omega = select(fail, T(1), m.omega);
    }
    const mask_t<T> close = accept && (d < threshold);
    m.result.found = m.result.found || close;
    m.result.t = select(close, m.t, m.result.t);
    const mask_t<T> advance = accept && !close && is_finite(d);
    m.accepted_t = select(advance, m.t, m.accepted_t);
    m.accepted_d = select(advance, d, m.accepted_d);
    T next = m.t + m.omega * d;
    if (options.omega > 1.0f) next = select(next > m.t_max, max(m.t + d, m.t_max), next);
    m.t = select(advance, next, m.t);
    m.active = (advance || fail) && (m.t <= m.t_max);
    if constexpr (std::floating_point<T>)
        m.active = m.active && m.result.steps < options.max_steps;
    else
        m.active = m.active && (m.result.steps < T(scalar_t<T>(options.max_steps)));
}

// SoA staging of one packet's rays, so single lanes can be replaced between steps. Per-lane
// flags are words of bits (bit i = lane i), so finding the finished lanes is a few word
// operations rather than a loop over the packet.
template <class P>
struct packet_lanes {
    static constexpr std::size_t W = lane_count<P>;
    alignas(64) float ox[W]{}, oy[W]{}, oz[W]{}, dx[W], dy[W], dz[W], t0[W], t1[W];
    std::uint32_t id[W];
    std::uint64_t live = 0; // lanes holding a ray that has not been reported yet

    // Fills lane i from the queue. A job whose range is empty (t_start > t_max: a ray clipped
    // away) goes to `empty` at once instead of taking the lane for a step it would not take. A
    // lane left empty gets a ray the tracer rejects at once; it keeps the origin of the lane's
    // last ray, so the point the field is evaluated at for the idle lane (its origin, see
    // trace_stream) is a finite one the caller chose.
    template <class Next, class Empty>
    void pull(std::size_t i, Next& next, bool& queue_open, Empty& empty)
    {
        ray_job job;
        while (queue_open && (queue_open = next(job)) && job.t_start > job.t_max) empty(job);
        const std::uint64_t bit = std::uint64_t(1) << i;
        live = queue_open ? (live | bit) : (live & ~bit);
        if (!queue_open)
            job = ray_job{{{ox[i], oy[i], oz[i]}, {0, 0, 1}}, std::numeric_limits<float>::infinity(), 0.0f, 0};
        ox[i] = job.r.origin.x, oy[i] = job.r.origin.y, oz[i] = job.r.origin.z;
        dx[i] = job.r.direction.x, dy[i] = job.r.direction.y, dz[i] = job.r.direction.z;
        t0[i] = job.t_start, t1[i] = job.t_max, id[i] = job.id;
    }
    old_march_state<P> start(const trace_options& options) const
    {
        const ray<P> r{{P::load_aligned(ox), P::load_aligned(oy), P::load_aligned(oz)},
                       {P::load_aligned(dx), P::load_aligned(dy), P::load_aligned(dz)}};
        return old_start_march(r, P::load_aligned(t0), P::load_aligned(t1), options);
    }
};

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

template <class T>
void blend(const mask_t<T>& m, old_march_state<T>& into, const old_march_state<T>& from)
{
    into.r.origin = select(m, from.r.origin, into.r.origin);
    into.r.direction = select(m, from.r.direction, into.r.direction);
    into.t = select(m, from.t, into.t);
    into.t_max = select(m, from.t_max, into.t_max);
    into.accepted_t = select(m, from.accepted_t, into.accepted_t);
    into.accepted_d = select(m, from.accepted_d, into.accepted_d);
    into.omega = select(m, from.omega, into.omega);
    into.threshold_bias = select(m, from.threshold_bias, into.threshold_bias);
    into.active = (m && from.active) || (!m && into.active);
    into.result.t = select(m, from.result.t, into.result.t);
    into.result.found = (m && from.result.found) || (!m && into.result.found);
    into.result.invalid = (m && from.result.invalid) || (!m && into.result.invalid);
    into.result.steps = select(m, from.result.steps, into.result.steps);
    into.result.evaluations = select(m, from.result.evaluations, into.result.evaluations);
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

} // namespace old_detail

// Traces every ray `next` yields through f with packets of type P, refilling finished lanes.
// A lane is refilled once at least `refill_at` lanes of its packet have finished (default: see
// above; refilling costs a spill of the packet to memory), or when none is left running. Results
// equal per-ray `sphere_trace` calls up to float rounding of the packet math.
template <class P = packet_f, int Interleave = 2, field F, class Next, class Done>
krs::stream_stats trace_stream_reference(const F& f, Next&& next, Done&& done, const trace_options& options, int refill_at = 0)
{
    static_assert(Interleave >= 1, "trace_stream needs at least one packet");
    options.validate();
    constexpr std::size_t W = lane_count<P>;
    if (refill_at <= 0) refill_at = old_detail::default_refill(f, int(W));
    krs::stream_stats stats;
    std::array<old_detail::packet_lanes<P>, Interleave> lanes;
    std::array<old_detail::old_march_state<P>, Interleave> state;
    bool queue_open = true;
    // A job with an empty range is a miss without a step, reported as it is pulled (invalid as
    // sphere_trace reports it when the ray itself is unusable).
    auto empty = [&](const ray_job& job) {
        hit<float> h;
        h.t = std::numeric_limits<float>::infinity();
        h.invalid = unusable_ray(job.r, job.t_start);
        ++stats.rays;
        done(job.id, h);
    };
    for (int k = 0; k < Interleave; ++k) {
        for (std::size_t i = 0; i < W; ++i) lanes[k].pull(i, next, queue_open, empty);
        state[k] = lanes[k].start(options);
    }
    // Reports the finished lanes of packet k and refills them. Lanes whose ray was rejected at
    // start (invalid input) finish without a step and are reported like any other.
    auto harvest = [&](int k, bool force) {
        old_detail::packet_lanes<P>& L = lanes[k];
        old_detail::old_march_state<P>& m = state[k];
        const std::uint64_t finished = L.live & ~mask_bits<P>(m.active);
        const int count = std::popcount(finished);
        if (count == 0 || (count < refill_at && !force)) return;
        alignas(64) float t[W], steps[W], evaluations[W];
        m.result.t.store_aligned(t);
        m.result.steps.store_aligned(steps);
        m.result.evaluations.store_aligned(evaluations);
        const std::uint64_t found = mask_bits<P>(m.result.found), invalid = mask_bits<P>(m.result.invalid);
        for (std::uint64_t rest = finished; rest != 0; rest &= rest - 1) {
            const std::size_t i = std::size_t(std::countr_zero(rest));
            hit<float> h;
            h.t = t[i], h.found = (found >> i) & 1u, h.invalid = (invalid >> i) & 1u;
            h.steps = int(steps[i]), h.evaluations = int(evaluations[i]);
            ++stats.rays;
            stats.evaluations += h.evaluations;
            stats.busy_lanes += h.steps;
            done(L.id[i], h);
            L.pull(i, next, queue_open, empty);
        }
        // Every finished lane was pulled again: those lanes start afresh.
        old_detail::blend(mask_from_bits<P>(finished), m, L.start(options));
    };
    for (;;) {
        for (int k = 0; k < Interleave; ++k) harvest(k, !any(state[k].active));
        // All packets' points in one evaluation. An idle lane is evaluated at its ray's origin
        // (its sample point may be at infinity), and a packet with no active lane left, near the
        // end of the stream, takes the points of an active one: it rides along at no extra depth
        // of the walk and is not advanced.
        std::array<vec3<P>, Interleave> points;
        int first_running = -1;
        for (int k = 0; k < Interleave; ++k) {
            if (!any(state[k].active)) continue;
            if (first_running < 0) first_running = k;
            points[std::size_t(k)] = point_at(state[k].r, select(state[k].active, state[k].t, P(0.0f)));
        }
        for (int k = 0; k < Interleave; ++k)
            if (first_running >= 0 && !any(state[k].active)) points[std::size_t(k)] = points[std::size_t(first_running)];
        if (first_running >= 0) {
            const std::array<P, Interleave> d = old_detail::distances_of(f, points);
            for (int k = 0; k < Interleave; ++k) {
                if (!any(state[k].active)) continue;
                old_detail::old_march_advance(state[k], d[std::size_t(k)], options);
                ++stats.packet_steps;
            }
            continue;
        }
        // Nothing runs: done unless a lane still holds an unreported (rejected) ray.
        bool pending = false;
        for (int k = 0; k < Interleave; ++k) pending = pending || lanes[k].live != 0;
        if (!pending) break;
    }
    return stats;
}


template <class P = packet_f>
class tile_rays_reference {
public:
    static constexpr std::size_t W = lane_count<P>;

    // Replaces the queue by the rays through the pixel centers of [x0, x1) x [y0, y1), row by
    // row. Each starts at `prepass.start_for(ray)` (a default tile_prepass starts every ray at
    // its `start`) and ends at t_max, both narrowed to the field's box by `clip` when given (a
    // ray that misses it is queued with an empty range and reported as a miss without a step);
    // its id is the pixel index y * camera.width() + x. The rectangle is clipped to the image.
    void fill(const pinhole_camera& camera, int x0, int y0, int x1, int y1, const tile_prepass& prepass, float t_max,
              const box_clip& clip = {})
    {
        jobs_.clear();
        next_ = 0;
        x0 = std::max(x0, 0), y0 = std::max(y0, 0);
        x1 = std::min(x1, camera.width()), y1 = std::min(y1, camera.height());
        if (x1 <= x0 || y1 <= y0) return;
        const int columns = x1 - x0;
        const std::size_t count = std::size_t(columns) * std::size_t(y1 - y0);
        jobs_.resize(count);
        alignas(64) float px[W], py[W], ox[W], oy[W], oz[W], dx[W], dy[W], dz[W], start[W], end[W];
        std::uint32_t id[W];
        for (std::size_t first = 0; first < count; first += W) {
            // Lanes past the tile's last pixel repeat it; their results are not kept.
            for (std::size_t i = 0; i < W; ++i) {
                const std::size_t k = std::min(first + i, count - 1);
                const int x = x0 + int(k % std::size_t(columns)), y = y0 + int(k / std::size_t(columns));
                px[i] = float(x) + 0.5f, py[i] = float(y) + 0.5f;
                id[i] = std::uint32_t(std::size_t(y) * std::size_t(camera.width()) + std::size_t(x));
            }
            const ray<P> r = camera.primary_ray(P::load_aligned(px), P::load_aligned(py));
            r.origin.x.store_aligned(ox), r.origin.y.store_aligned(oy), r.origin.z.store_aligned(oz);
            r.direction.x.store_aligned(dx), r.direction.y.store_aligned(dy), r.direction.z.store_aligned(dz);
            P t0 = prepass.start_for(r), t1(t_max);
            clip.apply(r, t0, t1);
            t0.store_aligned(start), t1.store_aligned(end);
            for (std::size_t i = 0; i < W && first + i < count; ++i) {
                ray_job& job = jobs_[first + i];
                job.r = {{ox[i], oy[i], oz[i]}, {dx[i], dy[i], dz[i]}};
                job.t_start = start[i];
                job.t_max = end[i];
                job.id = id[i];
            }
        }
    }

    // The next ray of the tile; false when the tile is used up.
    bool pop(ray_job& job)
    {
        if (next_ >= jobs_.size()) return false;
        job = jobs_[next_++];
        return true;
    }
    std::size_t remaining() const { return jobs_.size() - next_; }

private:
    std::vector<ray_job> jobs_;
    std::size_t next_ = 0;
};


} // namespace bench::reference

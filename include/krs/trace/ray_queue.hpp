#pragma once
// The queue of rays a packet stream (krs/trace/packet_trace.hpp) takes its lanes' rays from.
//
// Rays wait in a `ray_queue`: structure of arrays (one array per coordinate, start, end, id), so
// a packet's finished lanes are refilled by one expand per coordinate (krs/core/lanes.hpp's
// expand_load: the next c rays of the queue go to the c finished lanes, in lane order) and its
// results leave by one compress per value, never by copying rays lane by lane. A ray is checked
// once, W at a time, as it is queued: one that cannot be marched (an unusable ray, or an empty
// range such as a ray that misses the field's box) is set aside as a miss and never takes a lane,
// so a refilled lane is always active and the refill blends only what a new ray changes. Against
// the stream that pulled one `ray_job` per lane and blended a whole march_state (issue 23), that,
// the cheaper step (march_limits, krs/trace/sphere_trace.hpp) and results reported in runs
// (krs/trace/packet_trace.hpp) are 2.0-2.5x the rays per second per core on bench_embree_peer's
// scenes at the 0.5 px threshold (2-4 evaluations per ray), with the same hits; where rays take 15
// evaluations the field is most of the time and the gain is 0.9-1.4x, under Amdahl's ceiling of
// 1.1-2.1x (bench_packet_trace).

#include "krs/core/lanes.hpp"
#include "krs/trace/sphere_trace.hpp" // ray, unusable_ray

#include <algorithm>
#include <array>
#include <bit>
#include <cstdint>
#include <vector>

namespace krs {

// One ray of a stream: where it starts (e.g. a tile prepass depth), where it ends, and the
// caller's id for it (typically the pixel index).
struct ray_job {
    ray<float> r{};
    float t_start = 0.0f;
    float t_max = 1.0e4f;
    std::uint32_t id = 0;
};

// Rays waiting for a stream's lanes, as a structure of arrays, plus the ids of the rays set aside
// as they were queued (reported as misses without a step). Rays are appended W at a time from
// packets (`push`, one compress per array) or one at a time (`push(ray_job)`); the stream takes
// them from the front with `take` (one expand per array). Every array keeps 2 W values of room
// past its end: a compress writes a whole register at the end, an expand reads one at the front.
template <class P = packet_f>
class ray_queue {
public:
    static constexpr std::size_t W = lane_count<P>;
    using ids = index_lanes<P>;

    // Rays waiting (queued, not yet taken).
    std::size_t size() const { return size_ - head_; }
    bool empty() const { return size_ == head_; }
    // Drops every ray, waiting or set aside.
    void clear()
    {
        size_ = head_ = 0;
        missed_.clear(), invalid_.clear();
    }

    // Queues the lanes of `lanes` (bit i = lane i) whose ray can be marched, in lane order. The
    // others are set aside: a ray unusable_ray refuses as invalid, one whose range is empty
    // (t_start > t_max, or NaN: a ray clipped away) as a plain miss; `id` holds the caller's ids
    // (as index lanes; an id is any 32-bit value, stored as its bits).
    void push(const ray<P>& r, const P& t_start, const P& t_max, const ids& id, std::uint64_t lanes)
    {
        lanes &= all_lanes;
        const std::uint64_t bad = mask_bits<P>(unusable_ray(r, t_start)) & lanes;
        const std::uint64_t keep = mask_bits<P>(t_start <= t_max) & lanes & ~bad;
        if (keep != lanes) {
            set_aside(invalid_, id, bad);
            set_aside(missed_, id, lanes & ~bad & ~keep);
        }
        if (keep == 0) return;
        room();
        const std::size_t at = size_;
        compress_store(x_[0].data() + at, r.origin.x, keep);
        compress_store(x_[1].data() + at, r.origin.y, keep);
        compress_store(x_[2].data() + at, r.origin.z, keep);
        compress_store(x_[3].data() + at, r.direction.x, keep);
        compress_store(x_[4].data() + at, r.direction.y, keep);
        compress_store(x_[5].data() + at, r.direction.z, keep);
        compress_store(x_[6].data() + at, t_start, keep);
        compress_store(x_[7].data() + at, t_max, keep);
        size_ += compress_store(id_.data() + at, id, keep);
    }
    // Queues one ray, set aside as above when it cannot be marched.
    void push(const ray_job& job)
    {
        if (unusable_ray(job.r, job.t_start)) {
            invalid_.push_back(std::int32_t(job.id));
            return;
        }
        if (!(job.t_start <= job.t_max)) {
            missed_.push_back(std::int32_t(job.id));
            return;
        }
        room();
        const float v[8] = {job.r.origin.x,    job.r.origin.y,    job.r.origin.z, job.r.direction.x,
                            job.r.direction.y, job.r.direction.z, job.t_start,    job.t_max};
        for (int k = 0; k < 8; ++k) x_[std::size_t(k)][size_] = v[k];
        id_[size_++] = std::int32_t(job.id);
    }

    // Moves the next popcount(lanes) rays into the lanes of `lanes` (in lane order), leaving the
    // other lanes as they are. Precondition: popcount(lanes) <= size().
    void take(std::uint64_t lanes, ray<P>& r, P& t_start, P& t_max, ids& id)
    {
        // The arrays' addresses are read before the first expand: a store of a register may alias
        // anything (the vector types are may_alias), so each one was otherwise reloaded from the
        // queue after the previous lane state was written.
        const std::size_t at = head_;
        const float* in[8];
        for (std::size_t k = 0; k < 8; ++k) in[k] = x_[k].data() + at;
        const std::int32_t* in_id = id_.data() + at;
        r.origin.x = expand_load(r.origin.x, lanes, in[0]);
        r.origin.y = expand_load(r.origin.y, lanes, in[1]);
        r.origin.z = expand_load(r.origin.z, lanes, in[2]);
        r.direction.x = expand_load(r.direction.x, lanes, in[3]);
        r.direction.y = expand_load(r.direction.y, lanes, in[4]);
        r.direction.z = expand_load(r.direction.z, lanes, in[5]);
        t_start = expand_load(t_start, lanes, in[6]);
        t_max = expand_load(t_max, lanes, in[7]);
        id = expand_load(id, lanes, in_id);
        head_ += std::size_t(std::popcount(lanes & all_lanes));
    }

    // Waiting ray i (0 = the next one) as a job, for callers that hand rays out one at a time.
    ray_job job(std::size_t i) const
    {
        const std::size_t k = head_ + i;
        return {{{x_[0][k], x_[1][k], x_[2][k]}, {x_[3][k], x_[4][k], x_[5][k]}}, x_[6][k], x_[7][k], std::uint32_t(id_[k])};
    }
    void drop_front(std::size_t count) { head_ = std::min(size_, head_ + count); }

    // Ids of the rays set aside since the last clear: misses, and rays that could not be marched.
    const std::vector<std::int32_t>& missed() const { return missed_; }
    const std::vector<std::int32_t>& invalid() const { return invalid_; }
    void clear_set_aside() { missed_.clear(), invalid_.clear(); }

private:
    static constexpr std::uint64_t all_lanes = low_bits(W);

    // Room for one more register at the end, and a register's read past it.
    void room()
    {
        const std::size_t need = size_ + 2 * W;
        if (id_.size() >= need) return;
        const std::size_t grow = std::max(need, 2 * id_.size());
        for (auto& a : x_) a.resize(grow);
        id_.resize(grow);
    }
    void set_aside(std::vector<std::int32_t>& list, const ids& id, std::uint64_t lanes)
    {
        if (lanes == 0) return;
        const std::size_t at = list.size();
        list.resize(at + W);
        list.resize(at + compress_store(list.data() + at, id, lanes));
    }

    std::array<std::vector<float>, 8> x_; // origin xyz, direction xyz, start, end
    std::vector<std::int32_t> id_;
    std::size_t size_ = 0, head_ = 0;
    std::vector<std::int32_t> missed_, invalid_;
};

} // namespace krs

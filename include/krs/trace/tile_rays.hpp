#pragma once
// The primary rays of one screen tile, queued for a packet stream (krs/trace/packet_trace.hpp).
//
// A stream asks for its rays one at a time, but making a ray is packet work like any other: the
// camera's direction needs a normalization and the prepass start (krs/trace/tile_prepass.hpp) a
// walk through up to max_extra spheres, each with a square root. Done per ray, that scalar
// chain of dependent square roots costs about as much as a few field evaluations of a deep
// sequence. So `queue_tile_rays` computes a whole tile's rays W at a time with the same templates
// (`primary_ray`, `start_for`, `box_clip::apply`) and appends them to a `ray_queue` in packets:
// the rays that miss the field's box (most of a picture where the scene is small in it) are
// set aside there as misses by the same packet step, so only rays that enter the box are stored
// and handed to lanes. Pixels are numbered through the tile row by row and W consecutive ones
// make a packet whatever the tile's width (a tile 8 wide fills 16 lanes from two rows).
//
// The library starts no threads: callers hand out tiles (one queue per thread) and fill the
// queue from their next tile when it runs dry:
//
//     krs::ray_queue<> queue;
//     auto more = [&](krs::ray_queue<>& q) {
//         if (!take_tile(x0, y0, x1, y1)) return false;
//         krs::queue_tile_rays(q, camera, x0, y0, x1, y1, krs::prepass_tile(f, camera, x0, y0, x1, y1, o),
//                              o.max_distance, clip);
//         return true;
//     };
//     krs::trace_queue<krs::packet_f, 4>(f, queue, more, done, o);
//
// `tile_rays` keeps the older interface, one `ray_job` at a time (`fill`, then `pop`), on the same
// queue.

#include "krs/core/validate.hpp"
#include "krs/trace/box_clip.hpp"
#include "krs/trace/packet_trace.hpp"
#include "krs/trace/tile_prepass.hpp"

#include <algorithm>
#include <cstdint>
#include <limits>
#include <string>
#include <vector>

namespace krs {

// Appends to `queue` the rays through the pixel centres of [x0, x1) x [y0, y1) (clipped to the
// image), row by row. Each starts at `prepass.start_for(ray)` (a default tile_prepass starts every
// ray at its `start`) and ends at t_max, both narrowed to the field's box by `clip` when given;
// a ray that misses the box is set aside by the queue as a miss. Its id is the pixel index
// y * camera.width() + x. Returns the number of pixels (queued or set aside).
template <class P>
std::size_t queue_tile_rays(ray_queue<P>& queue, const pinhole_camera& camera, int x0, int y0, int x1, int y1,
                            const tile_prepass& prepass, float t_max, const box_clip& clip = {})
{
    using ids = index_lanes<P>;
    constexpr std::size_t W = lane_count<P>;
    x0 = std::max(x0, 0), y0 = std::max(y0, 0);
    x1 = std::min(x1, camera.width()), y1 = std::min(y1, camera.height());
    if (x1 <= x0 || y1 <= y0) return 0;
    const int columns = x1 - x0;
    // The lane maths below is exact while a packet's offsets from its row start stay below 2^23
    // (columns + W of them); wider tiles are refused rather than given wrong rays and ids.
    if (columns > (1 << 22))
        throw invalid_parameter("queue_tile_rays.x1", "the tile must be at most 2^22 pixels wide",
                                std::to_string(columns) + " columns");
    const std::size_t count = std::size_t(columns) * std::size_t(y1 - y0);
    // Lane i's offset 0 ... W-1 from the packet's first pixel.
    P lane(0.0f);
    if constexpr (!std::floating_point<P>) {
        alignas(64) float f[W];
        for (std::size_t i = 0; i < W; ++i) f[i] = float(i);
        lane = P::load_aligned(f);
    }
    const P cols = P(float(columns));
    const ids width(std::int32_t(camera.width()));
    const std::int32_t base = std::int32_t(y0) * std::int32_t(camera.width()) + std::int32_t(x0);
    for (std::size_t first = 0; first < count; first += W) {
        // The packet's first pixel splits into row and column in integers; its lanes are at
        // k = column + i (k < columns + W <= 2^23 + W) from that row's start. Then k and
        // k + 1/2 are exact in float (below 2^23 a float holds every half integer; from 2^23 on
        // k + 1/2 would round to even and the last pixel of a row would land in the next one),
        // and (k + 1/2) / columns is at least 1/(2 columns) from an integer, far more than its
        // rounding error, so its floor is the integer quotient: the lane's row past the first.
        const std::size_t first_row = first / std::size_t(columns);
        const P k = P(float(first - first_row * std::size_t(columns))) + lane;
        const P rows_on = lane_floor((k + P(0.5f)) / cols);
        const P column = k - rows_on * cols;
        const P row = rows_on + P(float(first_row));
        const ray<P> r = camera.primary_ray(column + P(float(x0) + 0.5f), row + P(float(y0) + 0.5f));
        const ids id = ids(base + std::int32_t(first_row) * std::int32_t(camera.width())) +
                       truncate_to_index(rows_on) * width + truncate_to_index(column);
        P t0 = prepass.start_for(r), t1(t_max);
        clip.apply(r, t0, t1);
        const std::size_t left = count - first;
        queue.push(r, t0, t1, id, low_bits(left));
    }
    return count;
}

// One tile's rays handed out one `ray_job` at a time, for a caller's `next` of trace_stream.
template <class P = packet_f>
class tile_rays {
public:
    static constexpr std::size_t W = lane_count<P>;

    // Replaces the queue by the rays of [x0, x1) x [y0, y1), as queue_tile_rays makes them. The
    // rays that miss the box are handed out last, with an empty range (t_start = +infinity,
    // t_max = -infinity; the stream reports them as misses without a step); their ray itself is
    // not kept (the origin and direction given are the eye's and +z).
    void fill(const pinhole_camera& camera, int x0, int y0, int x1, int y1, const tile_prepass& prepass, float t_max,
              const box_clip& clip = {})
    {
        queue_.clear();
        next_set_aside_ = 0;
        eye_ = camera.eye();
        queue_tile_rays(queue_, camera, x0, y0, x1, y1, prepass, t_max, clip);
    }

    // The next ray of the tile; false when the tile is used up.
    bool pop(ray_job& job)
    {
        if (!queue_.empty()) {
            job = queue_.job(0);
            queue_.drop_front(1);
            return true;
        }
        const std::size_t missed = queue_.missed().size(), invalid = queue_.invalid().size();
        if (next_set_aside_ >= missed + invalid) return false;
        const std::size_t k = next_set_aside_++;
        constexpr float inf = std::numeric_limits<float>::infinity();
        if (k < missed) {
            job = {{eye_, {0, 0, 1}}, inf, -inf, std::uint32_t(queue_.missed()[k])};
        } else {
            // Unusable: a NaN origin, so the stream reports it invalid as the camera's ray would be.
            const float nan = std::numeric_limits<float>::quiet_NaN();
            job = {{{nan, nan, nan}, {0, 0, 1}}, inf, -inf, std::uint32_t(queue_.invalid()[k - missed])};
        }
        return true;
    }
    std::size_t remaining() const { return queue_.size() + queue_.missed().size() + queue_.invalid().size() - next_set_aside_; }

private:
    ray_queue<P> queue_;
    std::size_t next_set_aside_ = 0;
    vec3f eye_{};
};

} // namespace krs

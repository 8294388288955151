#pragma once
// The primary rays of one screen tile as a queue of `ray_job`s for `trace_stream`.
//
// A stream asks for its rays one at a time, but making a ray is packet work like any other: the
// camera's direction needs a normalization and the prepass start (krs/trace/tile_prepass.hpp) a
// walk through up to max_extra spheres, each with a square root. Done per ray, that scalar
// chain of dependent square roots costs about as much as a few field evaluations of a deep
// sequence. `tile_rays` computes a whole tile's rays W at a time with the same templates
// (`primary_ray`, `start_for`) and hands them out from memory.
//
// The library starts no threads: callers hand out tiles (one queue per thread) and refill the
// queue from their next tile when `pop` finds it empty:
//
//     krs::tile_rays<> rays;
//     auto next = [&](krs::ray_job& job) {
//         while (!rays.pop(job)) {
//             if (!take_tile(x0, y0, x1, y1)) return false;
//             rays.fill(camera, x0, y0, x1, y1, krs::prepass_tile(f, camera, x0, y0, x1, y1, o), o.max_distance);
//         }
//         return true;
//     };

#include "krs/trace/box_clip.hpp"
#include "krs/trace/packet_trace.hpp"
#include "krs/trace/tile_prepass.hpp"

#include <algorithm>
#include <cstdint>
#include <vector>

namespace krs {

template <class P = packet_f>
class tile_rays {
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

} // namespace krs

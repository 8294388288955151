#pragma once
// The examples' tiled, multi-threaded render loop: the image is cut into 16x16 tiles, threads
// take tiles from a shared counter until none is left, and the caller's worker does what a tile
// needs (trace, shade, write pixels). The library itself starts no threads; this is how an
// application would.
//
// Tiles rather than rows: the tile prepass (krs/trace/tile_prepass.hpp) and packet shading work on
// a tile's pixels together, and small square tiles balance the load across threads when some parts
// of the picture cost far more than others. Which thread takes which tile, and when, is not fixed:
// a worker must not let one tile's pixels depend on another tile's, or the image would change
// with the thread count.

#include <algorithm>
#include <atomic>
#include <chrono>
#include <thread>
#include <vector>

namespace example {

// The pixels [x0, x1) x [y0, y1) of one tile; `index` is its place in row-major tile order.
struct tile {
    int index = 0, x0 = 0, y0 = 0, x1 = 0, y1 = 0;
};

// The tiles of a width x height image, handed out once each, to any number of threads.
class tile_queue {
public:
    static constexpr int tile_size = 16;

    tile_queue(int width, int height)
        : width_(width), height_(height), tiles_x_((width + tile_size - 1) / tile_size),
          count_(tiles_x_ * ((height + tile_size - 1) / tile_size))
    {
    }
    tile_queue(const tile_queue&) = delete;
    tile_queue& operator=(const tile_queue&) = delete;

    int count() const { return count_; }

    // The next tile not yet taken; false once every tile has been.
    bool take(tile& t)
    {
        const int k = next_.fetch_add(1);
        if (k >= count_) return false;
        t.index = k;
        t.x0 = (k % tiles_x_) * tile_size, t.y0 = (k / tiles_x_) * tile_size;
        t.x1 = std::min(t.x0 + tile_size, width_), t.y1 = std::min(t.y0 + tile_size, height_);
        return true;
    }

private:
    int width_, height_, tiles_x_, count_;
    std::atomic<int> next_{0};
};

// Runs worker(i) for i = 0 .. threads - 1, each on its own thread, while `wait()` runs on the
// calling thread (a progress display; it must return once the workers are done or about to be);
// returns the wall-clock seconds from the first thread's start to the last one's end.
template <class Worker, class Wait>
double run_threads(int threads, Worker worker, Wait wait)
{
    const auto start = std::chrono::steady_clock::now();
    std::vector<std::thread> pool;
    for (int i = 0; i < threads; ++i) pool.emplace_back(worker, i);
    wait();
    for (std::thread& t : pool) t.join();
    return std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
}
template <class Worker>
double run_threads(int threads, Worker worker)
{
    return run_threads(threads, worker, [] {});
}

} // namespace example

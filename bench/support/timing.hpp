#pragma once
// What the benchmarks share: the best time of repeated runs (the machine is shared, so the
// minimum is the least disturbed figure) and a pool of threads for the library's parallel_for hooks
// (the library starts no threads itself).

#include <algorithm>
#include <atomic>
#include <chrono>
#include <cstddef>
#include <functional>
#include <thread>
#include <vector>

namespace bench {

template <class F>
double best_seconds(int repeat, F&& f)
{
    double best = 1e300;
    for (int r = 0; r < repeat; ++r) {
        const auto start = std::chrono::steady_clock::now();
        f();
        best = std::min(best, std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count());
    }
    return best;
}

// Runs body(0 .. count-1) on `threads` threads (the caller and threads - 1 started for the call)
// taking items in order from a shared counter.
inline void run_parallel(unsigned threads, std::size_t count, const std::function<void(std::size_t)>& body)
{
    std::atomic<std::size_t> next{0};
    const auto work = [&] {
        for (std::size_t i; (i = next++) < count;) body(i);
    };
    std::vector<std::thread> pool;
    for (unsigned w = 1; w < threads; ++w) pool.emplace_back(work);
    work();
    for (auto& t : pool) t.join();
}

// The same as a value for generation_options::parallel_for and render_settings::parallel_for.
inline std::function<void(std::size_t, const std::function<void(std::size_t)>&)> parallel_for(unsigned threads)
{
    return [threads](std::size_t count, const std::function<void(std::size_t)>& body) { run_parallel(threads, count, body); };
}

} // namespace bench

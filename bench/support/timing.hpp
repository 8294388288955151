#pragma once
// What the benchmarks share: the best time of repeated runs (the machine is shared, so the
// minimum is the least disturbed figure) and a pool of threads for the library's parallel_for hooks
// (the library starts no threads itself).

#include <algorithm>
#include <atomic>
#include <chrono>
#include <condition_variable>
#include <cstdint>
#include <exception>
#include <cstddef>
#include <cstdio>
#include <cstdlib>
#include <functional>
#include <memory>
#include <mutex>
#include <string>
#include <thread>
#include <time.h>
#include <utility>
#include <vector>

namespace bench {

// This thread's CPU time: on a machine shared by more runnable threads than cores, wall time
// counts the time the thread waited for a core; its CPU time does not (caches shared with the
// other threads still slow it).
inline double thread_cpu_seconds()
{
    timespec t{};
    clock_gettime(CLOCK_THREAD_CPUTIME_ID, &t);
    return double(t.tv_sec) + 1e-9 * double(t.tv_nsec);
}

// The 1, 5 and 15 minute load averages as "a b c": every table prints them before and after, so a
// figure can be read against how busy the shared machine was.
inline std::string load_average()
{
    double load[3];
    if (getloadavg(load, 3) != 3) return "unknown";
    char text[64];
    std::snprintf(text, sizeof text, "%.2f %.2f %.2f", load[0], load[1], load[2]);
    return text;
}

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

// Threads kept for the calls of one parallel_for hook, as an application's pool would be: a
// creation makes about six calls a few hundred microseconds apart, and starting threads for each
// (run_parallel) cost 20-50 us a call plus cold caches. Workers spin 100 us after a call (the
// next one usually follows sooner), then sleep. A call made from inside a body runs serially;
// calls from two outside threads at once are not supported (the hooks here have one caller).
// A body that throws stops the call from taking more items; run() waits for the bodies under way
// on other threads, then rethrows the first exception on the caller's thread.
class thread_pool {
public:
    explicit thread_pool(unsigned threads)
    {
        for (unsigned w = 1; w < threads; ++w) workers_.emplace_back([this] { serve(); });
    }
    thread_pool(const thread_pool&) = delete;
    thread_pool& operator=(const thread_pool&) = delete;
    ~thread_pool()
    {
        {
            const std::lock_guard lock(mutex_);
            stop_ = true;
            round_.fetch_add(1);
        }
        wake_.notify_all();
        for (std::thread& t : workers_) t.join();
    }

    void run(std::size_t count, const std::function<void(std::size_t)>& body)
    {
        if (workers_.empty() || inside_body() || count < 2) {
            for (std::size_t i = 0; i < count; ++i) body(i);
            return;
        }
        {
            const std::lock_guard lock(mutex_);
            body_ = &body, count_ = count, next_ = 0;
            busy_ = unsigned(workers_.size());
            round_.fetch_add(1);
        }
        wake_.notify_all();
        work();
        std::unique_lock lock(mutex_);
        done_.wait(lock, [this] { return busy_ == 0; });
        body_ = nullptr;
        if (failure_) std::rethrow_exception(std::exchange(failure_, nullptr));
    }

private:
    static bool& inside_body()
    {
        static thread_local bool inside = false;
        return inside;
    }
    void work()
    {
        inside_body() = true;
        try {
            for (std::size_t i; (i = next_++) < count_;) (*body_)(i);
        } catch (...) {
            next_ = count_; // no more items for anyone
            const std::lock_guard lock(mutex_);
            if (!failure_) failure_ = std::current_exception();
        }
        inside_body() = false;
    }
    void serve()
    {
        std::uint64_t seen = 0;
        for (;;) {
            // Spin up to 100 us for the next call before sleeping.
            const auto spin_until = std::chrono::steady_clock::now() + std::chrono::microseconds(100);
            while (round_.load() == seen && std::chrono::steady_clock::now() < spin_until) {
            }
            {
                std::unique_lock lock(mutex_);
                wake_.wait(lock, [&] { return round_.load() != seen; });
                seen = round_.load();
                if (stop_) return;
            }
            work();
            const std::lock_guard lock(mutex_);
            if (--busy_ == 0) done_.notify_one();
        }
    }

    std::mutex mutex_;
    std::condition_variable wake_, done_;
    std::atomic<std::uint64_t> round_{0};
    const std::function<void(std::size_t)>* body_ = nullptr;
    std::size_t count_ = 0;
    std::atomic<std::size_t> next_{0};
    unsigned busy_ = 0;
    bool stop_ = false;
    std::exception_ptr failure_; // the first exception of the current call
    std::vector<std::thread> workers_;
};

// A hook for generation_options::parallel_for and render_settings::parallel_for, on a pool of
// `threads` threads (the caller is one) that lives as long as the hook.
inline std::function<void(std::size_t, const std::function<void(std::size_t)>&)> parallel_for(unsigned threads)
{
    const auto pool = std::make_shared<thread_pool>(threads);
    return [pool](std::size_t count, const std::function<void(std::size_t)>& body) { pool->run(count, body); };
}

} // namespace bench

#pragma once
// Progress of a long loop, written in the form its reader sees it in.
//
// On a terminal a bar is redrawn in place with '\r', once per percent. A log or a pipe keeps every
// byte instead: there each redraw is another frame (scripts/examples.sh logged ~100 KB of them),
// so when the stream is not a terminal the progress is one line per tenth, "render: 40%".
//
// update() may be called from any thread, as often as work finishes: it draws only when the shown
// step moves forward, under a lock so that two threads never draw over each other or backwards.

#include <atomic>
#include <cstddef>
#include <cstdio>
#include <mutex>
#include <string>
#include <unistd.h>

namespace example {

class progress {
public:
    progress(std::FILE* stream, std::string label)
        : stream_(stream), label_(std::move(label)), terminal_(::isatty(::fileno(stream)) == 1)
    {
    }
    progress(const progress&) = delete;
    progress& operator=(const progress&) = delete;

    // `done` of `total` items are finished.
    void update(std::size_t done, std::size_t total)
    {
        if (total == 0) return;
        const int percent = int(100 * (done < total ? done : total) / total);
        const int step = terminal_ ? percent : percent / 10 * 10; // a log hears of tenths only
        if (step <= shown_.load(std::memory_order_relaxed)) return;
        const std::lock_guard<std::mutex> lock(mutex_);
        if (step <= shown_.load(std::memory_order_relaxed)) return;
        shown_.store(step, std::memory_order_relaxed);
        if (terminal_) {
            const std::size_t filled = std::size_t(step * bar_width / 100);
            std::fprintf(stream_, "\r%s [%s%s] %3d%%", label_.c_str(), std::string(filled, '#').c_str(),
                         std::string(bar_width - filled, '.').c_str(), step);
        } else {
            std::fprintf(stream_, "%s: %d%%\n", label_.c_str(), step);
        }
        std::fflush(stream_);
    }

    // Ends the bar's line on a terminal (what follows starts on a line of its own); a log's lines
    // are already ended.
    void finish()
    {
        const std::lock_guard<std::mutex> lock(mutex_);
        if (terminal_ && shown_.load(std::memory_order_relaxed) >= 0) std::fprintf(stream_, "\n");
        shown_.store(100, std::memory_order_relaxed);
    }

private:
    static constexpr std::size_t bar_width = 40;
    std::FILE* stream_;
    std::string label_;
    bool terminal_;
    std::atomic<int> shown_{-1}; // -1: nothing drawn (a terminal shows the empty bar at 0%)
    std::mutex mutex_;
};

} // namespace example

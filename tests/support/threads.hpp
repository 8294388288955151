#pragma once
// The parallel_for hook the hypertree tests hand to creation and rendering when a result made on
// threads must equal the one-thread result: n threads started for the call, task i on thread
// i % n. Neighbouring tasks always land on different threads, so two tasks that share a buffer, a
// memo slot or a scratch block without a lock show as a difference (or a sanitizer report); the
// schedule is fixed, so such a failure repeats.
//
// (Tests that need another schedule say so where they build it: tasks in reverse order, one
// thread per task, a shared counter.)

#include "hypertree/execution.hpp"

#include <cstddef>
#include <functional>
#include <thread>
#include <vector>

namespace krs_test {

inline hypertree::parallel_for_hook strided_threads(unsigned n)
{
    return [n](std::size_t count, const std::function<void(std::size_t)>& body) {
        std::vector<std::thread> threads;
        for (unsigned t = 0; t < n; ++t)
            threads.emplace_back([&, t] {
                for (std::size_t i = t; i < count; i += n) body(i);
            });
        for (std::thread& t : threads) t.join();
    };
}

} // namespace krs_test

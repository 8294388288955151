#pragma once
// How the library's work runs: on which threads, and within how much memory. Every step that can
// split its work (generation, validation, density classes, rendering, light sweeps) takes a
// parallel_for_hook, and every step that allocates a store, a hit list or a texture takes a
// memory_budget; both are the caller's, so neither lives with the data types of voxel.hpp.

#include <cstddef>
#include <functional>

namespace hypertree {

// How the library runs independent work on the caller's threads (it starts none itself,
// docs/design.md#rule-6): parallel_for(count, body) calls body(0) ... body(count - 1) in any
// order, on any threads, and returns when all are done. Empty: the work runs serially on the
// calling thread.
// A body may throw (std::bad_alloc, or a refusal found inside a task): the hook should let the
// bodies under way end and pass the exception on to its caller, as a task group does.
using parallel_for_hook = std::function<void(std::size_t count, const std::function<void(std::size_t)>& body)>;

// Runs body(0) ... body(count - 1) through the hook, or in order on this thread without one (or
// for a single task).
inline void run_tasks(const parallel_for_hook& parallel_for, std::size_t count, const std::function<void(std::size_t)>& body)
{
    if (parallel_for && count > 1) parallel_for(count, body);
    else
        for (std::size_t i = 0; i < count; ++i) body(i);
}

// The most memory a store (or the generator's hit list) may take. A resolution or iteration count
// whose data would exceed it is refused with a message before anything is allocated.
struct memory_budget {
    std::size_t bytes = std::size_t(4) << 30;
};

} // namespace hypertree

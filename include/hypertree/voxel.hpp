#pragma once
// What the generator records and what stores hold (paper sections 4-6).
//
// The generator writes one `hit` per voxel a generator occupies: the voxel, the generator's depth
// (its level: 0 for the condensation, i.e. the trunk; s for a generator s transformations below
// it) and its first-level subpart (0 for the trunk, j + 1 when transformation j was applied at
// level 1, i.e. outermost). Validation (section 5) sorts the hits and merges duplicates into one
// `voxel_entry` per voxel with its hit count; the shallowest level prevails, and with it the part.
// Density classes (section 4) turn hit counts into densities, giving the `stored_voxel` list every
// store is built from: sorted by index, unique, density > 0.

#include "hypertree/volume.hpp"

#include <cstddef>
#include <cstdint>
#include <functional>

namespace hypertree {

struct hit {
    voxel_index voxel;
    std::uint8_t level;
    std::uint8_t part;
};

struct voxel_entry {
    voxel_index voxel;
    std::uint32_t hits;
    std::uint8_t level;
    std::uint8_t part;
};

// What a store answers for one voxel: density 0..255 (0 = empty) and depth level.
struct voxel {
    std::uint8_t density = 0;
    std::uint8_t level = 0;
    friend bool operator==(const voxel&, const voxel&) = default;
};

struct stored_voxel {
    voxel_index index;
    voxel value;
    std::uint8_t part;
};

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

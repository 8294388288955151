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

#include <cstdint>

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

} // namespace hypertree

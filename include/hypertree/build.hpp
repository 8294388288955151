#pragma once
// From an IFS to a store in one call: the whole of section 6's algorithm (generate, validate,
// density classes, then the chosen data structure), for callers that do not need the steps.
//
//     auto tree = hypertree::build_tree<hypertree::bit_array_store>(presets::tree_a(300), seed);
//
// Each step stays public for callers that want to keep the hit list (to build several stores, or
// to unite trees before classifying).

#include "hypertree/compact.hpp"
#include "hypertree/density.hpp"
#include "hypertree/generate.hpp"
#include "hypertree/store/store.hpp"

namespace hypertree {

struct build_options {
    int density_class_count = 32; // C of section 4: 2 = solid trees; the paper uses up to 128
    generation_options generation{};
};

template <class Store, transform_pipeline P>
Store build_tree(const ifs<P>& definition, std::uint64_t seed, const build_options& options = {})
{
    const generated_hits generated = generate(definition, seed, options.generation);
    const std::vector<voxel_entry> entries = compact(generated.hits, options.generation.parallel_for, generated.volume.voxel_count());
    const density_classes classes(entries, options.density_class_count);
    const std::vector<stored_voxel> voxels = classify(entries, classes, definition.branch_depth);
    return Store::build(definition.volume, voxels, options.generation.budget);
}

} // namespace hypertree

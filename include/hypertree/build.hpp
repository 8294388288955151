#pragma once
// From an IFS to a store in one call: the whole of section 6's algorithm (generate, validate,
// density classes, then the chosen data structure), for callers that do not need the steps.
//
//     auto tree = hypertree::build_tree<hypertree::bit_array_store>(presets::tree_a(300), seed);
//
// An application that builds many trees keeps one scratch_memory (create/scratch.hpp) in
// options.generation.scratch: each build then reuses the pages of the last one's temporaries;
// passing its last store as `recycled` builds the new one in that store's memory too (the stores'
// build with a recycled store), so a tree of the same size maps no new page at all.
//
// Each step stays public for callers that want to keep the hit list (to build several stores, or
// to unite trees before classifying).

#include "hypertree/create/compact.hpp"
#include "hypertree/create/density.hpp"
#include "hypertree/create/generate.hpp"
#include "hypertree/create/scratch.hpp"
#include "hypertree/create/voxel_table.hpp"
#include "hypertree/store/store.hpp"

#include <optional>
#include <utility>

namespace hypertree {

struct build_options {
    int density_class_count = 32; // C of section 4: 2 = solid trees; the paper uses up to 128
    generation_options generation{};
};

namespace detail {

// Generation, validation and density classes: the stored voxels of one tree, in a list drawn
// from `scratch` (every temporary of the way too). Each list goes back to the scratch as soon as
// the next is made, so the next step can reuse its pages. Where the grid allows, the chunks are
// generated in groups of consecutive chunks (create/generate.hpp's generation_plan, made once),
// each group's hits validated on its task while they are in cache and its buffer reused by the
// next group: added to a per-voxel table on grids up to 2^21 voxels (create/voxel_table.hpp),
// else bucketed (create/compact.hpp's direct_buckets) and merged; on larger grids validation reads
// the chunks as pieces.
template <transform_pipeline P>
std::pmr::vector<stored_voxel> stored_voxels_of(const ifs<P>& definition, std::uint64_t seed, int density_class_count,
                                                const generation_options& options, std::pmr::memory_resource* scratch)
{
    generation_options drawing = options;
    drawing.scratch = scratch;
    // Planned once, before anything is allocated (a definition or budget is refused here): the
    // chunks in cache-sized groups for the two grouped passes, the second running only where the
    // first's table overflowed, and one task a chunk for the pieces of large grids.
    const generation_plan plan = plan_generation(definition, drawing);
    const generation_plan grouped = plan.in_groups(generation_group_count(definition, plan));
    std::pmr::vector<voxel_entry> entries(scratch);
    no_observer observer;
    const std::uint64_t voxel_count = definition.volume.voxel_count();
    const auto classified = [&](const auto& groups_of_entries) {
        std::vector<std::span<const voxel_entry>> pieces(groups_of_entries.begin(), groups_of_entries.end());
        const density_classes classes(std::span<const std::span<const voxel_entry>>(pieces), density_class_count, options.parallel_for);
        return classify_pieces(std::span<const std::span<const voxel_entry>>(pieces), classes, definition.branch_depth,
                               std::pmr::vector<stored_voxel>(scratch), options.parallel_for);
    };
    if (voxel_count > 0 && voxel_count <= voxel_table::max_voxels) {
        // Small grids: one table slot per voxel (create/voxel_table.hpp), each group's
        // hits added on its task while hot. A voxel past 2^17 hits (never in the presets) sends the
        // build to the bucketed path below, which counts in 32 bits.
        voxel_table_pool pool(voxel_count, scratch);
        generate_chunks(definition, seed, grouped, drawing, observer, [&](std::size_t, chunk_output& hits) {
            pool.with_table([&](voxel_table& table) { table.add({hits.data(), hits.size()}); });
            hits = {}; // its buffer back to the scratch, for the next group
        });
        if (!pool.overflowed()) return classified(pool.read_out<std::pmr::vector<voxel_entry>>(options.parallel_for ? 4 : 1, options.parallel_for));
    }
    if (const auto buckets = direct_buckets::for_grid(voxel_count)) {
        std::vector<bucketed_chunk> keyed(grouped.tasks);
        generate_chunks(definition, seed, grouped, drawing, observer, [&](std::size_t g, chunk_output& hits) {
            keyed[g] = bucket_chunk({hits.data(), hits.size()}, *buckets, scratch);
            hits = {}; // its buffer back to the scratch, for the next group
        });
        // The merge's groups are classified where they lie, each on its own task.
        const std::vector<std::pmr::vector<voxel_entry>> groups_of_entries =
            merge_bucketed_groups<std::pmr::vector<voxel_entry>>(keyed, *buckets, options.parallel_for, scratch);
        keyed.clear(); // the keys back to the scratch
        return classified(groups_of_entries);
    }
    const generated_chunks generated = generate_chunks(definition, seed, plan, drawing, observer);
    compact_into(generated.pieces(), options.parallel_for, voxel_count, scratch, entries);
    const density_classes classes(entries, density_class_count);
    return classify(entries, classes, definition.branch_depth, std::pmr::vector<stored_voxel>(scratch), options.parallel_for);
}

} // namespace detail

// Validation takes the generator's chunks as they are made, without first copying them into one
// list as generate() returns them. Temporaries come from options.generation.scratch, or from a
// scratch memory of this call's own, which still lets the steps reuse each other's pages.
template <class Store, transform_pipeline P>
Store build_tree(const ifs<P>& definition, std::uint64_t seed, const build_options& options = {})
{
    return build_tree<Store>(definition, seed, options, Store());
}
// The same, built in `recycled`'s memory (which it consumes): see the store kinds' build.
template <class Store, transform_pipeline P>
Store build_tree(const ifs<P>& definition, std::uint64_t seed, const build_options& options, Store&& recycled)
{
    std::optional<scratch_memory> own;
    if (!options.generation.scratch) own.emplace();
    const std::pmr::vector<stored_voxel> voxels = detail::stored_voxels_of(
        definition, seed, options.density_class_count, options.generation, options.generation.scratch ? options.generation.scratch : &*own);
    return Store::build(definition.volume, voxels, options.generation.budget, std::move(recycled));
}

} // namespace hypertree

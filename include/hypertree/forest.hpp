#pragma once
// A hyperforest (paper section 10): trees generated into one shared volume, the result of a
// forest file.
//
// Each tree keeps its own IFS and hypervolume shape; its offset moves it in the forest. Rather
// than conjugating every transformation by the offset, the tree is generated against the forest's
// grid moved by minus the offset: a generator at p then lands in the forest voxel of p + offset,
// and every tree's voxels share one index space. Trees are united by the paper's max rule
// (ops.hpp, over partitioned stores: the kind that keeps parts), and a voxel's part becomes its
// tree's number, so the renderer fits one bounding sphere per tree.
//
// Each tree's noise (section 3.5): PERTURB acts during its generation; VOXELPERTURB shifts its
// voxels before the union, the field evaluated in the tree's own coordinates (the moved grid), so
// the tree is perturbed as it would be alone. RENDERPERTURB is refused by load_forest (one march
// renders every tree). A TRIM region is checked against the forest's grid here, which may differ
// from the tree's own: a region holding no forest voxel is reported at the tree file's TRIM line.

#include "hypertree/build.hpp"
#include "hypertree/definition_refusals.hpp"
#include "hypertree/io/forest_file.hpp"
#include "hypertree/ops.hpp"
#include "hypertree/perturbation.hpp"
#include "hypertree/store/partitioned_store.hpp"

#include <algorithm>
#include <optional>
#include <string>
#include <vector>

namespace hypertree {

struct generated_forest {
    hypervolume volume;
    std::vector<stored_voxel> voxels; // sorted, unique: ready for any store's build
};

// Tree i draws from seed + i. A tree without DENSITYCLASSES uses options.density_class_count.
inline generated_forest build_forest(const loaded_forest& forest, std::uint64_t seed, const build_options& options = {})
{
    generated_forest out{forest.volume(), {}};
    // One scratch memory for every tree when the caller gives none: each tree reuses the pages of the last.
    scratch_memory own;
    std::pmr::memory_resource* const scratch = options.generation.scratch ? options.generation.scratch : &own;
    for (std::size_t i = 0; i < forest.trees.size(); ++i) {
        ifs<> tree = forest.trees[i].ifs;
        const parsed_tree& parsed = forest.trees[i];
        tree.volume = hypervolume(out.volume.origin() - forest.listing.trees[i].offset, out.volume.extent(), out.volume.grid());
        std::pmr::vector<stored_voxel> voxels(scratch);
        try {
            voxels = detail::stored_voxels_of(tree, seed + i, parsed.density_class_count.value_or(options.density_class_count),
                                              options.generation, scratch);
        } catch (const krs::invalid_parameter& e) {
            const std::string& name = e.parameter();
            // The tree's own settings (ITERATIONS against the generator's budget, ...) at their
            // line of its file; the grid is the forest's, so a refusal of it is not the tree's.
            if (!name.starts_with("ifs.")) throw;
            if (!name.starts_with("ifs.trim[")) {
                if (std::optional<definition_error> located = at_its_line(parsed, e)) throw *located;
                throw;
            }
            const std::size_t j = std::size_t(std::stoul(name.substr(9)));
            if (j >= parsed.trim_at.size()) throw;
            throw definition_error(parsed.file, parsed.trim_at[j], "TRIM in the forest's grid: " + e.message());
        }
        for (stored_voxel& v : voxels) v.part = std::uint8_t(std::min<std::size_t>(i, 255));
        if (parsed.voxel_perturb) {
            // Over a partitioned_store, which keeps the tree's part; on the moved grid, whose voxel
            // centers are the tree's own coordinates and whose indices are the forest's.
            const std::vector<stored_voxel> moved = perturb_voxels(partitioned_store::build(tree.volume, voxels, options.generation.budget),
                                                                   *parsed.voxel_perturb);
            voxels.assign(moved.begin(), moved.end());
        }
        if (out.voxels.empty()) {
            out.voxels.assign(voxels.begin(), voxels.end());
            continue;
        }
        const partitioned_store so_far = partitioned_store::build(out.volume, out.voxels, options.generation.budget);
        const partitioned_store this_tree = partitioned_store::build(out.volume, voxels, options.generation.budget);
        out.voxels = unite_max(so_far, this_tree);
    }
    return out;
}

} // namespace hypertree

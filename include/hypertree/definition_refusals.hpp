#pragma once
// Refusals found while building from a definition file, reported at the line of the setting that
// caused them, in the file's words, with what would fit where there is one.
//
// The parser checks what a file says on its own (lexer.hpp, definition_file.hpp). Some limits
// show only once the work starts: the generator's memory budget against ITERATIONS
// (create/generate.hpp), the marcher's sample count against RENDERPERTURB (march_options.hpp), a
// PERTURB that carries every point out of the hypervolume. The library raises the first two as a
// krs::invalid_parameter naming a C++ member (`ifs.iterations`, `march_options.displacement
// .amplitude`) that a user of the file never wrote; the third is no exception at all, only an
// empty tree. These turn each into a definition_error at the file's line:
//
//     tree.tree:3:1: ITERATIONS 2000000000: would record up to ... bytes of hits, over the memory
//         budget of 4294967296 bytes; at most 178956966 iterations fit
//
// A store's budget against RESOLUTION and STORAGETYPE is the store kinds' (store_kinds.hpp,
// `store_budget_problem`), which a forest file's STORAGETYPE line or a program's option reports.

#include "hypertree/create/generate.hpp"
#include "hypertree/io/definition_file.hpp"

#include <algorithm>
#include <cstdint>
#include <optional>
#include <string>
#include <utility>

namespace hypertree {

// `e`, raised while building `tree`, as a definition_error at the line of the setting e names
// ("KEYWORD value: problem"); a refusal of no setting of the file (an option the program set) is
// returned as it is, in the empty optional.
inline std::optional<definition_error> at_its_line(const parsed_tree& tree, const krs::invalid_parameter& e)
{
    const std::optional<parsed_tree::setting> s = tree.setting_of(e.parameter());
    if (!s) return std::nullopt;
    std::string message(s->keyword);
    if (!e.got().empty()) message += " " + e.got();
    if (!s->given) message += " (not in the file: the default)";
    return definition_error(tree.file, s->at, message + ": " + e.problem());
}

// Runs `work` (a build from `tree`), rethrowing a refusal of one of the file's settings at its
// line (at_its_line); other exceptions pass unchanged.
template <class Work>
decltype(auto) building_from(const parsed_tree& tree, Work&& work)
{
    try {
        return std::forward<Work>(work)();
    } catch (const krs::invalid_parameter& e) {
        if (std::optional<definition_error> located = at_its_line(tree, e)) throw *located;
        throw;
    }
}

// Why `tree` generated no voxel, at the line to change. With PERTURB, trial generations (at most
// 20000 iterations, one thread, the same seed) tell whether the noise is the cause: if the tree
// without it fills voxels, the refusal is at PERTURB's line and gives the largest amplitude,
// halving the file's, that fills some. Otherwise no point fell in the hypervolume, which
// HYPERVOLUME and DISPLACEMENT place.
inline definition_error empty_tree_refusal(const parsed_tree& tree, std::uint64_t seed)
{
    ifs<runtime_pipeline> trial = tree.ifs;
    trial.iterations = std::min<std::uint64_t>(trial.iterations, 20000);
    const auto fills = [&](const perturbation& p) {
        trial.perturb = p;
        try {
            return !generate(trial, seed).hits.empty();
        } catch (const krs::invalid_parameter&) {
            return false;
        }
    };
    const perturbation noise = tree.ifs.perturb;
    const bool noisy = noise.enabled();
    const auto perturb_at = tree.setting_of("ifs.perturb");
    if (noisy && fills(perturbation{})) {
        std::string fits = "no amplitude above 0 fills one in trials; PERTURB 0 0 0 does";
        perturbation smaller = noise;
        for (int halving = 1; halving <= 64; ++halving) {
            smaller.amplitude = smaller.amplitude * 0.5;
            if (fills(smaller)) {
                fits = "an amplitude of " + krs::detail::to_text(smaller.amplitude.x) + " " + krs::detail::to_text(smaller.amplitude.y) +
                       " " + krs::detail::to_text(smaller.amplitude.z) + " fills some (found by halving this one)";
                break;
            }
        }
        return definition_error(tree.file, perturb_at->at,
                                "PERTURB " + krs::detail::to_text(noise.amplitude.x) + " " + krs::detail::to_text(noise.amplitude.y) + " " +
                                    krs::detail::to_text(noise.amplitude.z) +
                                    ": the tree generated no voxels: the noise carries every point out of the hypervolume (the tree "
                                    "without it fills voxels); " + fits);
    }
    const auto where = tree.setting_of("hypervolume.origin");
    const vec3d e = tree.ifs.volume.extent(), o = tree.ifs.volume.origin();
    return definition_error(tree.file, where->given ? where->at : tree.setting_of("hypervolume.extent")->at,
                            "the tree generated no voxels: none of its points fell in the hypervolume (HYPERVOLUME " +
                                krs::detail::to_text(e.x) + " " + krs::detail::to_text(e.y) + " " + krs::detail::to_text(e.z) +
                                " from " + krs::detail::to_text(o.x) + " " + krs::detail::to_text(o.y) + " " + krs::detail::to_text(o.z) +
                                ", DISPLACEMENT placing the tree's origin in it)");
}

} // namespace hypertree

#pragma once
// The IFS that defines a hypertree (paper sections 3 and 10): transformations with relative
// probabilities and level rules, condensations, depths, the generator, noise perturbation and
// the hypervolume.
//
// Levels: a generator's depth s counts the transformations applied since the last condensation
// (0 = the condensation itself, the trunk). In the pipeline of a depth-s generator (figure 2) the
// transformation selected last executes at level 1 (it places a first-level subpart), the one
// before it at level 2, and so on: per-level parameter values follow that level of execution.
//
// Level rules (section 3.4):
// - `last_level` m: the transformation never executes deeper than level m; a generator that
//   would need it deeper is not generated (and neither is anything below it in that cycle).
// - `dummy_from` d: generators at depth >= d whose outermost (level-1) transformation is this one
//   are not recorded, yet they keep transforming. So the first-level branch made by this
//   transformation stops at depth d - 1 while the transformation still shapes every other
//   branch's subparts; d = 1 is the classic dummy (its branch is not drawn at all).
// - `branch_depth` b: voxels of depth <= b form the lignified branching structure (full density,
//   section 4; colored as branches in section 8.3).
//
// The IFS is a value; `draw(seed)` fixes its random parameters for one tree (section 3.2) and
// checks the contraction condition of section 2.2 on the drawn maps: every transformation's
// chain must have a Lipschitz bound below 1 at every level, unless `require_contraction` is off
// (then generators that leave the hypervolume are only counted).

#include "hypertree/perturbation.hpp"
#include "hypertree/random.hpp"
#include "hypertree/region.hpp"
#include "hypertree/transform/condensation.hpp"
#include "hypertree/transform/pipeline.hpp"
#include "hypertree/volume.hpp"

#include <algorithm>
#include <array>
#include <cstdint>
#include <span>
#include <string>
#include <vector>

namespace hypertree {

// A point (start == end) or a line segment, whose length transformations keep (section 4).
struct generator_shape {
    vec3d start{}, end{};

    static generator_shape point() { return {}; }
    static generator_shape line(const vec3d& start, const vec3d& end) { return {start, end}; }
    bool is_point() const { return start.x == end.x && start.y == end.y && start.z == end.z; }
    double length() const { return krs::length(end - start); }
};

// Noise perturbation of generator positions (section 3.5, perturbation.hpp): each recorded
// generator moves by the field's shift, at most amplitude.x, .y, .z along each axis (tested by
// brute force over every generated point). The shift is applied to recorded generators only and
// does not feed back into the iteration: the next transformation starts from the unperturbed
// point, so the noise bends the tree without being contracted away or amplified.

inline constexpr int max_tree_depth = 64;
inline constexpr int max_transforms = 254; // a voxel's part is a byte: 0 = trunk, 1 + transform index
inline constexpr int never = max_tree_depth + 1;

template <transform_pipeline P>
struct ifs_transform {
    P transform;
    double probability = 1; // relative: probabilities need not sum to 1 (section 10)
    int last_level = never;
    int dummy_from = never;
};

template <transform_pipeline P = runtime_pipeline>
struct ifs {
    std::string name;
    std::vector<ifs_transform<P>> transforms;
    std::vector<condensation> condensations{condensation{}}; // one stem, or two for a fork
    int tree_depth = 6;                                        // generators of depth 0 .. tree_depth - 1
    int branch_depth = 1;
    std::uint64_t iterations = 100000; // N of section 6: a cycle of depth k counts k iterations
    generator_shape generator;
    perturbation perturb;
    hypervolume volume{{-1, 0, -1}, {2, 2, 2}, resolution::cube(100)};
    // Trimming as a constraint of the IFS (section 7, region.hpp): voxels whose centers lie in any
    // of these regions are locked, so no hit on them is recorded while the tree is generated.
    std::vector<trim_region> trim;
    bool require_contraction = true;

    void validate() const
    {
        using krs::invalid_parameter;
        if (transforms.empty()) throw invalid_parameter("ifs.transforms", "must hold at least one transformation");
        if (transforms.size() > std::size_t(max_transforms))
            throw invalid_parameter("ifs.transforms", "may hold at most " + std::to_string(max_transforms) + " transformations",
                                    std::to_string(transforms.size()));
        double total = 0;
        for (std::size_t j = 0; j < transforms.size(); ++j) {
            const auto& t = transforms[j];
            const std::string name_j = "ifs.transforms[" + std::to_string(j) + "]";
            t.transform.validate();
            krs::require_non_negative(name_j + ".probability", t.probability);
            total += t.probability;
            if (t.last_level < 1)
                throw invalid_parameter(name_j + ".last_level", "must be >= 1", std::to_string(t.last_level));
            if (t.dummy_from < 1)
                throw invalid_parameter(name_j + ".dummy_from", "must be >= 1", std::to_string(t.dummy_from));
        }
        if (!(total > 0) || !std::isfinite(total))
            throw invalid_parameter("ifs.transforms", "probabilities must have a positive finite sum", krs::detail::to_text(total));
        if (condensations.empty() || condensations.size() > 2)
            throw invalid_parameter("ifs.condensations", "must hold one or two condensations", std::to_string(condensations.size()));
        for (const auto& c : condensations) c.validate();
        if (tree_depth < 1 || tree_depth > max_tree_depth)
            throw invalid_parameter("ifs.tree_depth", "must be in [1, " + std::to_string(max_tree_depth) + "]", std::to_string(tree_depth));
        if (branch_depth < 0 || branch_depth >= tree_depth)
            throw invalid_parameter("ifs.branch_depth", "must be in [0, tree_depth - 1]", std::to_string(branch_depth));
        if (iterations < 1) throw invalid_parameter("ifs.iterations", "must be >= 1", "0");
        krs::require_finite("ifs.generator.start", generator.start);
        krs::require_finite("ifs.generator.end", generator.end);
        perturb.validate("ifs.perturb");
        validate_trim_regions("ifs.trim", trim, volume);
    }
};

// One tree's IFS with its random parameters drawn and every transformation reduced to its
// canonical chain per level.
template <transform_pipeline P>
class drawn_ifs {
public:
    using chain = typename P::chain;

    drawn_ifs(const ifs<P>& definition, std::uint64_t seed) : definition_(definition)
    {
        definition.validate();
        // Stream 0 of the seed is the parameter draw; the generator's chunks use streams 1, 2, ...
        random_stream random = random_stream::derive(seed, 0);
        for (std::size_t j = 0; j < definition.transforms.size(); ++j) {
            const P drawn = definition.transforms[j].transform.draw(random);
            for (int l = 0; l < distinct_levels; ++l) {
                const chain& at_level = chains_.emplace_back(drawn.chain_at(l + 1));
                const double bound = at_level.lipschitz();
                if (definition.require_contraction && !(bound < 1.0))
                    throw krs::invalid_parameter(
                        "ifs.transforms[" + std::to_string(j) + "]",
                        "must be a contraction at level " + std::to_string(l + 1) + (l + 1 == distinct_levels ? "+" : "") +
                            " (its Lipschitz bound must be < 1; add a downsizing scale, or set require_contraction = false)",
                        krs::detail::to_text(bound));
                lipschitz_ = std::max(lipschitz_, bound);
            }
            last_level_.push_back(definition.transforms[j].last_level);
            dummy_from_.push_back(definition.transforms[j].dummy_from);
        }
        // Trees without shears (A, B and C of the presets) reduce every chain to its one affine
        // map: a table of those is 96 bytes per entry instead of a whole chain, so the
        // generator's working set stays in a few cache lines and each application is branch-free.
        const bool affine = std::all_of(chains_.begin(), chains_.end(), [](const chain& c) { return c.shears == 0; });
        if (affine)
            for (const chain& c : chains_) affine_chains_.push_back(c.affine[0]);
        build_alias_table();
        for (const auto& c : definition.condensations) {
            const condensation drawn = c.draw(random);
            stems_.push_back(drawn.stem);
            stem_chains_.push_back(drawn.then.chain_at(1));
            stem_volume_total_ += drawn.stem.volume();
            stem_cumulative_.push_back(stem_volume_total_);
        }
    }

    const ifs<P>& definition() const { return definition_; }
    std::size_t transform_count() const { return last_level_.size(); }
    const chain& chain_of(std::size_t transform, int level) const { return chains_[transform * distinct_levels + std::size_t(level_slot(level))]; }
    // Every chain, transformation-major: chain_of(j, level) is entry j * distinct_levels + level_slot(level).
    std::span<const chain> chain_table() const { return chains_; }
    // The same table holding each chain's single affine map, when no chain has a shear; else empty.
    std::span<const affine_map> affine_table() const { return affine_chains_; }
    // The level rules per transformation, copied out of the definition so the generator's inner
    // loop reads two small arrays rather than whole ifs_transform records.
    std::span<const int> last_levels() const { return last_level_; }
    std::span<const int> dummies_from() const { return dummy_from_; }
    // The largest Lipschitz bound of any transformation at any level.
    double lipschitz() const { return lipschitz_; }

    // Transformation j with probability p_j / sum(p), for u uniform in [0, 1): one draw from
    // Walker's alias table (column u * n, then the column's own entry or its alias), so selection
    // costs the same for any number of transformations and has no data-dependent loop.
    std::size_t select(double u) const
    {
        const double x = u * double(alias_.size());
        const std::size_t column = std::min(std::size_t(x), alias_.size() - 1);
        // Arithmetic rather than a branch: the comparison is a coin flip the predictor cannot learn.
        const std::size_t keep = std::size_t(x - double(column) < keep_[column]);
        return keep * column + (1 - keep) * alias_[column];
    }
    // The alias table select() draws from: each column's share kept, and the column it defers to.
    std::span<const double> alias_keep() const { return keep_; }
    std::span<const std::size_t> alias_of() const { return alias_; }
    // The drawn condensations: their cones, their chains, and the share of the first by volume
    // (sample_stem's choice between two).
    std::span<const cone> stems() const { return stems_; }
    std::span<const runtime_pipeline::chain> stem_chains() const { return stem_chains_; }
    double stem_volume_total() const { return stem_volume_total_; }
    double first_stem_volume() const { return stem_cumulative_[0]; }
    // A point of the stem: with two condensations, each is chosen in proportion to its volume so
    // the forked stem's density is even.
    vec3d sample_stem(random_stream& random) const
    {
        std::size_t c = 0;
        if (stems_.size() > 1 && !(random.uniform() * stem_volume_total_ < stem_cumulative_[0])) c = 1;
        return stem_chains_[c](stems_[c].sample(random));
    }

private:
    // Vose's construction: scale probabilities so they average 1, then repeatedly fill a column
    // that is short (< 1) with the excess of one that is long (>= 1). A zero-probability
    // transformation keeps nothing of its column, so it is never selected.
    void build_alias_table()
    {
        const std::size_t n = definition_.transforms.size();
        double total = 0;
        for (const auto& t : definition_.transforms) total += t.probability;
        std::vector<double> scaled(n);
        std::vector<std::size_t> small, large;
        for (std::size_t j = 0; j < n; ++j) {
            scaled[j] = definition_.transforms[j].probability * double(n) / total;
            (scaled[j] < 1.0 ? small : large).push_back(j);
        }
        keep_.assign(n, 1.0);
        alias_.resize(n);
        for (std::size_t j = 0; j < n; ++j) alias_[j] = j;
        while (!small.empty() && !large.empty()) {
            const std::size_t s = small.back(), l = large.back();
            small.pop_back();
            keep_[s] = scaled[s];
            alias_[s] = l;
            scaled[l] -= 1.0 - scaled[s];
            if (scaled[l] < 1.0) {
                large.pop_back();
                small.push_back(l);
            }
        }
        // Columns left over hold (up to rounding) exactly 1: they keep themselves, unless their
        // probability is 0 (rounding left a zero-probability column unpaired): then they defer to
        // the most probable transformation.
        std::size_t most = 0;
        for (std::size_t j = 0; j < n; ++j)
            if (definition_.transforms[j].probability > definition_.transforms[most].probability) most = j;
        for (std::size_t j : small)
            if (definition_.transforms[j].probability == 0) keep_[j] = 0, alias_[j] = most;
    }

    ifs<P> definition_;
    std::vector<chain> chains_; // transformation-major, distinct_levels per transformation
    std::vector<affine_map> affine_chains_;
    std::vector<int> last_level_, dummy_from_;
    std::vector<double> keep_;        // per column: the share of the column that is its own
    std::vector<std::size_t> alias_; // per column: who takes the rest
    double lipschitz_ = 0;
    std::vector<cone> stems_;
    std::vector<runtime_pipeline::chain> stem_chains_;
    std::vector<double> stem_cumulative_;
    double stem_volume_total_ = 0;
};

} // namespace hypertree

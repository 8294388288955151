#pragma once
// Density classes (paper section 4, figure 3; step 6 of the algorithm in section 6).
//
// A voxel's hit count is a poor density: the number of voxels with a given count falls off
// exponentially, so a linear map from hits to density leaves trees almost bare of leaves. The
// paper instead sorts the hit voxels into a small number of density classes holding about the
// same number of voxels each, and gives every voxel its class's density.
//
// With C classes, class 0 is the empty voxels and classes 1..C-1 are contiguous ranges of hit
// count, ordered: a voxel hit more often is never in a lower class. The boundaries are placed
// greedily from the fewest hits up: each class takes the next hit counts while that brings its
// population closer to an equal share of the voxels not yet classed. One hit count cannot be split
// between classes, so a count held by very many voxels (the spike at one hit in figure 3) fills a
// class alone and the remaining classes share the rest evenly. Class c of K non-empty classes
// gets density round(255 c / K): the densest class is always full, and K = C - 1 unless there are
// fewer distinct hit counts than that, in which case each count is a class of its own. C = 2 is
// the paper's binary or solid hypertree: every hit voxel gets full density.
//
// `classify` then turns the compacted entries into the list every store is built from. Voxels of
// the branching structure (level <= branch_depth) get full density whatever their hit count, so
// trunk and branches stay solid under sparse foliage.

#include "hypertree/execution.hpp"
#include "hypertree/voxel.hpp"

#include <algorithm>
#include <cmath>
#include <cstddef>
#include <cstdint>
#include <span>
#include <string>
#include <utility>
#include <vector>

namespace hypertree {

class density_classes {
public:
    // One non-empty class: voxels hit fewest_hits..most_hits times (the counts present in the
    // entries it was built from), how many voxels that is, and the class's density.
    struct density_class {
        std::uint32_t fewest_hits = 0;
        std::uint32_t most_hits = 0;
        std::size_t population = 0;
        std::uint8_t density = 0;
    };

    static constexpr int min_class_count = 2;   // binary hypertrees
    static constexpr int max_class_count = 255; // densities are one byte, and class 0 is empty

    density_classes(std::span<const voxel_entry> entries, int class_count) : class_count_(class_count)
    {
        require_class_count(class_count);
        place_classes(hit_count_histogram(entries));
    }
    // The classes of entries given as pieces taken end to end (build_tree's merge groups), each
    // piece's histogram of hit counts made on the caller's threads: the classes of the pieces'
    // concatenation.
    density_classes(std::span<const std::span<const voxel_entry>> pieces, int class_count, const parallel_for_hook& parallel_for)
        : class_count_(class_count)
    {
        require_class_count(class_count);
        std::vector<std::vector<std::pair<std::uint32_t, std::size_t>>> histograms(pieces.size());
        run_tasks(parallel_for, pieces.size(), [&](std::size_t p) { histograms[p] = hit_count_histogram(pieces[p]); });
        if (histograms.size() == 1) {
            place_classes(histograms[0]);
            return;
        }
        // The sum of the pieces' histograms: few distinct counts (hundreds to thousands), sorted.
        std::vector<std::pair<std::uint32_t, std::size_t>> all;
        for (const auto& h : histograms) all.insert(all.end(), h.begin(), h.end());
        std::sort(all.begin(), all.end());
        std::vector<std::pair<std::uint32_t, std::size_t>> histogram;
        for (const auto& [hits, voxels] : all) {
            if (!histogram.empty() && histogram.back().first == hits) histogram.back().second += voxels;
            else histogram.emplace_back(hits, voxels);
        }
        place_classes(histogram);
    }

    // C as asked for, counting the empty class 0.
    int class_count() const { return class_count_; }
    // The non-empty classes 1..K in order: classes()[c - 1] is class c.
    std::span<const density_class> classes() const { return classes_; }

    // The class of a voxel hit `hits` times: 0 for no hit; a count between two classes' ranges
    // (absent from the entries the classes were built from) joins the lower class, one below the
    // first class joins class 1, one above the last joins the last.
    int class_of(std::uint32_t hits) const
    {
        if (hits == 0 || classes_.empty()) return hits == 0 ? 0 : 1;
        const auto above = std::upper_bound(classes_.begin(), classes_.end(), hits,
                                            [](std::uint32_t h, const density_class& k) { return h < k.fewest_hits; });
        return std::max(1, int(above - classes_.begin()));
    }
    // Density of a voxel hit `hits` times. Classes built from no hit voxel at all make every hit
    // voxel full, as in a binary hypertree.
    std::uint8_t density_of(std::uint32_t hits) const
    {
        if (hits == 0) return 0;
        if (classes_.empty()) return 255;
        return classes_[std::size_t(class_of(hits) - 1)].density;
    }

private:
    static void require_class_count(int class_count)
    {
        if (class_count < min_class_count || class_count > max_class_count)
            throw invalid_parameter("density_classes.class_count",
                                    "must be between 2 (binary hypertree: every hit voxel full) and 255",
                                    std::to_string(class_count));
    }
    // The classes over a histogram of (hit count, voxels with it), by increasing count.
    void place_classes(const std::vector<std::pair<std::uint32_t, std::size_t>>& histogram)
    {
        std::size_t remaining = 0;
        for (const auto& bucket : histogram) remaining += bucket.second;

        const std::size_t count_of_classes = std::min<std::size_t>(std::size_t(class_count_ - 1), histogram.size());
        classes_.reserve(count_of_classes);
        std::size_t next = 0;
        for (std::size_t c = 1; c <= count_of_classes; ++c) {
            const std::size_t classes_left = count_of_classes - c + 1;
            // Leave at least one distinct hit count for each class still to come.
            const std::size_t last_allowed = histogram.size() - classes_left;
            density_class k;
            k.fewest_hits = histogram[next].first;
            std::size_t population = histogram[next].second;
            ++next;
            if (classes_left == 1) {
                for (; next < histogram.size(); ++next) population += histogram[next].second;
            } else {
                // Adding a bucket of size b to population p moves it closer to the share
                // remaining / classes_left exactly when p + b / 2 < share; in integers:
                // (2 p + b) * classes_left < 2 * remaining.
                while (next <= last_allowed &&
                       (2 * population + histogram[next].second) * classes_left < 2 * remaining) {
                    population += histogram[next].second;
                    ++next;
                }
            }
            k.most_hits = histogram[next - 1].first;
            k.population = population;
            k.density = std::uint8_t(std::lround(255.0 * double(c) / double(count_of_classes)));
            remaining -= population;
            classes_.push_back(k);
        }
    }

    // (hit count, number of voxels with it) for every hit count present, by increasing count.
    static std::vector<std::pair<std::uint32_t, std::size_t>> hit_count_histogram(std::span<const voxel_entry> entries)
    {
        std::vector<std::pair<std::uint32_t, std::size_t>> histogram;
        std::uint32_t most = 0;
        std::size_t hit_voxels = 0;
        for (const voxel_entry& e : entries) {
            most = std::max(most, e.hits);
            hit_voxels += e.hits > 0;
        }
        if (hit_voxels == 0) return histogram;
        // Compacted hits have counts no larger than the number of hits, so counting into an array
        // indexed by count costs no more than the hit list did; counts far beyond the number of
        // voxels (entries from elsewhere) are sorted instead, so a single huge count allocates
        // nothing huge.
        if (std::size_t(most) < (std::size_t(1) << 16)) {
            // Four interleaved tables: most voxels share a few small counts, and one table's
            // increments of the same count wait for each other's stores (that chain was most of
            // building the classes).
            const std::size_t size = std::size_t(most) + 1;
            std::vector<std::uint32_t> population(4 * size, 0);
            const std::size_t n = entries.size();
            std::size_t i = 0;
            for (; i + 4 <= n; i += 4)
                for (std::size_t k = 0; k < 4; ++k) ++population[k * size + entries[i + k].hits];
            for (; i < n; ++i) ++population[entries[i].hits];
            for (std::size_t h = 1; h < size; ++h) {
                const std::size_t voxels = std::size_t(population[h]) + population[size + h] + population[2 * size + h] + population[3 * size + h];
                if (voxels != 0) histogram.emplace_back(std::uint32_t(h), voxels);
            }
        } else if (std::size_t(most) <= 4 * hit_voxels + 1024) {
            std::vector<std::size_t> population(std::size_t(most) + 1, 0);
            for (const voxel_entry& e : entries) ++population[e.hits];
            for (std::size_t h = 1; h < population.size(); ++h)
                if (population[h] != 0) histogram.emplace_back(std::uint32_t(h), population[h]);
        } else {
            std::vector<std::uint32_t> counts;
            counts.reserve(hit_voxels);
            for (const voxel_entry& e : entries)
                if (e.hits > 0) counts.push_back(e.hits);
            std::sort(counts.begin(), counts.end());
            for (std::size_t i = 0; i < counts.size();) {
                std::size_t j = i + 1;
                while (j < counts.size() && counts[j] == counts[i]) ++j;
                histogram.emplace_back(counts[i], j - i);
                i = j;
            }
        }
        return histogram;
    }

    int class_count_ = 2;
    std::vector<density_class> classes_;
};

// Branch depth meaning "no branching structure": no level gets full density by depth alone.
inline constexpr int no_branch_structure = -1;

// The stored voxels of compacted entries given as pieces taken end to end (as build_tree's merge
// groups leave them): classify's result for their concatenation, each piece on its own task,
// written straight to its place in the list (no piece is copied into one list first).
//
// The loop reads through local pointers and keeps a fault flag: the list it writes is of bytes,
// which may alias anything, so writing through the vector made the compiler reload every
// captured value for each voxel. The first disorder is looked for only when a piece has one.
template <class Voxels = std::vector<stored_voxel>>
Voxels classify_pieces(std::span<const std::span<const voxel_entry>> pieces, const density_classes& classes, int branch_depth,
                       Voxels voxels = {}, const parallel_for_hook& parallel_for = {})
{
    if (branch_depth < no_branch_structure || branch_depth > 255)
        throw invalid_parameter("classify.branch_depth",
                                "must be -1 (no branching structure) or a level between 0 and 255",
                                std::to_string(branch_depth));
    std::vector<std::size_t> offset(pieces.size() + 1, 0);
    for (std::size_t p = 0; p < pieces.size(); ++p) offset[p + 1] = offset[p] + pieces[p].size();
    const std::size_t n = offset.back();

    // Hit count -> density as a table over the counts the classes span, so classifying a million
    // voxels costs a load each instead of a bisection; counts above it take the last class.
    const auto spanned = classes.classes();
    const std::uint32_t table_top = spanned.empty() ? 0 : spanned.back().most_hits;
    std::vector<std::uint8_t> density_by_hits;
    if (std::size_t(table_top) <= 4 * n + 1024) {
        density_by_hits.resize(std::size_t(table_top) + 1);
        for (std::size_t h = 0; h < density_by_hits.size(); ++h)
            density_by_hits[h] = classes.density_of(std::uint32_t(h));
    }

    // Voxel i comes from entry i; each task checks its entries' order (against the one before
    // too) and counts those without hits, which a serial pass then removes (compact makes none).
    voxels.resize(n);
    std::vector<std::size_t> first_unsorted(pieces.size(), n), without_hits(pieces.size(), 0);
    run_tasks(parallel_for, pieces.size(), [&](std::size_t p) {
        const voxel_entry* const e = pieces[p].data();
        const std::size_t count = pieces[p].size();
        if (count == 0) return;
        stored_voxel* const out = voxels.data() + offset[p];
        const std::uint8_t* const table = density_by_hits.data();
        const std::size_t table_size = density_by_hits.size();
        const int depth = branch_depth;
        // The entry before this piece's first: the last of the nearest non-empty piece before.
        const voxel_entry* before = nullptr;
        for (std::size_t q = p; q-- > 0;)
            if (!pieces[q].empty()) {
                before = &pieces[q].back();
                break;
            }
        bool disorder = before && !(before->voxel < e[0].voxel);
        std::size_t empty = 0;
        for (std::size_t i = 0; i < count; ++i) {
            const voxel_entry x = e[i];
            disorder |= i > 0 && !(e[i - 1].voxel < x.voxel);
            const std::uint8_t density = int(x.level) <= depth ? std::uint8_t(255)
                                         : x.hits < table_size ? table[x.hits]
                                                               : classes.density_of(x.hits);
            out[i] = {x.voxel, voxel{density, x.level}, x.part};
            empty += x.hits == 0;
        }
        without_hits[p] = empty;
        if (disorder) {
            if (before && !(before->voxel < e[0].voxel)) first_unsorted[p] = offset[p];
            else
                for (std::size_t i = 1; i < count; ++i)
                    if (!(e[i - 1].voxel < e[i].voxel)) {
                        first_unsorted[p] = offset[p] + i;
                        break;
                    }
        }
    });
    const auto entry = [&](std::size_t i) -> const voxel_entry& {
        const std::size_t p = std::size_t(std::upper_bound(offset.begin(), offset.end(), i) - offset.begin()) - 1;
        return pieces[p][i - offset[p]];
    };
    if (const std::size_t i = first_unsorted.empty() ? n : *std::min_element(first_unsorted.begin(), first_unsorted.end()); i < n)
        throw invalid_parameter("classify.entries", "must be sorted by voxel without duplicates (as compact returns them)",
                                "voxel " + std::to_string(entry(i).voxel) + " after " + std::to_string(entry(i - 1).voxel));
    if (std::find_if(without_hits.begin(), without_hits.end(), [](std::size_t c) { return c != 0; }) != without_hits.end()) {
        std::size_t kept = 0;
        for (std::size_t i = 0; i < n; ++i) {
            voxels[kept] = voxels[i];
            kept += entry(i).hits != 0;
        }
        voxels.resize(kept);
    }
    return voxels;
}

// The stored voxels of compacted entries (as `compact` returns them: sorted by voxel, unique):
// each hit voxel with its class's density, or full density when its level <= branch_depth, its
// level and part. Entries with no hit are left out, so the result is sorted, unique and has no
// empty voxel, as stores require.
//
// `Voxels` is the list type to return: a std::pmr::vector<stored_voxel> passed in as `voxels`
// (empty, with its resource) draws from that resource. With `parallel_for`, the entries are
// split into tasks on the caller's threads; the result is the same.
template <class Voxels = std::vector<stored_voxel>>
Voxels classify(std::span<const voxel_entry> entries, const density_classes& classes, int branch_depth, Voxels voxels = {},
                const parallel_for_hook& parallel_for = {})
{
    const std::size_t n = entries.size();
    const std::size_t tasks = parallel_for && n >= (std::size_t(1) << 16) ? 4 : 1;
    std::vector<std::span<const voxel_entry>> pieces;
    for (std::size_t p = 0; p < tasks; ++p) pieces.push_back(entries.subspan(n * p / tasks, n * (p + 1) / tasks - n * p / tasks));
    return classify_pieces(std::span<const std::span<const voxel_entry>>(pieces), classes, branch_depth, std::move(voxels), parallel_for);
}

} // namespace hypertree

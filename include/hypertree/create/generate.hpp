#pragma once
// The hypertree generator (paper section 6): the random iteration algorithm with condensation,
// recording every voxel each generator occupies with the generator's depth and first-level part.
//
// One cycle: X = a condensation sample (depth 0, the trunk); then for s = 1 .. k-1 a newly
// selected transformation w_s extends the pipeline, and the depth-s generator is
//     Y_s = w_s^1( w_{s-1}^2( w_{s-2}^3( ... w_1^s(X) ) ) )
// (upper index: level of execution, figure 2). Parameter values differ only for levels 1, 2 and
// 3+, so the innermost part w_{s-2}^3 ... w_1^s(X) is the previous row's innermost part with one
// more level-3+ map applied: each row costs three chain applications instead of s ("only the last
// m transformations in each row need to be recalculated", section 3.4).
//
// Determinism and threads: cycles are cut into chunks of `chunk_cycles`, and each chunk into
// cycle_lanes = 8 lanes of cycles: lane j of chunk c draws from its own stream
// derive(seed, 8 c + j + 1) and runs its share of the chunk's cycles (an eighth of them, the first
// lanes taking the remainder). Chunk results are concatenated in chunk order, so the hit list
// is the same bit for bit whether the chunks run on one thread or many. A chunk's lanes run one
// after the other through the scalar loop, or, in a build with AVX-512 and for most trees, in
// step in SIMD registers (generator_lanes.hpp): the same hits either way, interleaved differently. The
// library starts no thread itself (docs/design.md#rule-6): pass `generation_options::parallel_for` to run
// chunks on yours.

#include "hypertree/execution.hpp"
#include "hypertree/ifs.hpp"
#include "hypertree/create/generator_lanes.hpp"
#include "hypertree/create/scratch.hpp"
#include "hypertree/voxel.hpp"
#include "krs/core/noise.hpp"

#include <algorithm>
#include <cassert>
#include <cmath>
#include <cstdint>
#include <functional>
#include <memory>
#include <memory_resource>
#include <optional>
#include <span>
#include <type_traits>
#include <vector>

namespace hypertree {

struct generation_options {
    // Cycles per chunk (the unit of threading). Small enough that the 20 000 cycles of tree C make
    // ten chunks for two threads to share evenly (with 8192 one thread ran two chunks of three:
    // 2.9 -> 2.5 ms at resolution 300), large enough that a chunk's lanes run 256 cycles each.
    std::uint64_t chunk_cycles = 2048;
    memory_budget budget{};
    // Runs body(0) .. body(count - 1), in any order and on any threads; empty = serially here.
    parallel_for_hook parallel_for;
    // Run a chunk's lanes in step in SIMD registers where the build and the tree allow it
    // (generator_lanes.hpp). The generated tree does not depend on it, only the order of its hits.
    bool vector_lanes = true;
    // Where the generator's and validation's temporary buffers come from (scratch.hpp): keep one
    // scratch_memory across builds and they reuse its pages. Null: generate() and compact() use
    // new and delete; build_tree and build_forest keep a scratch memory for the call.
    std::pmr::memory_resource* scratch = nullptr;
};

struct generation_stats {
    std::uint64_t cycles = 0;
    std::uint64_t generators = 0; // generated (including dummies)
    std::uint64_t recorded = 0;   // recorded (not dummy)
    std::uint64_t escaped = 0;    // recorded generators with an end outside the hypervolume
    std::uint64_t locked = 0;     // hits not recorded because their voxel is locked (ifs::trim)
    std::vector<std::uint64_t> recorded_per_depth;
};

struct generated_hits {
    hypervolume volume;
    std::vector<hit> hits; // in generation order, before validation (compact.hpp)
    generation_stats stats;
};

// What a test observer sees of each generator: its depth, the selected transformations w_1 .. w_s
// (innermost first), its segment (start == end for points) and whether it was recorded.
struct generator_event {
    int depth;
    std::span<const std::uint8_t> selected;
    vec3d start, end;
    bool recorded;
};

// Calls visit(index) for each voxel the segment [a, b] passes through, in order from a, each once
// (a 3D digital differential analyser over the part of the segment inside the box). A point
// (a == b) visits its voxel. Outside parts visit nothing, nor does a segment with a non-finite end.
// It visits at most max_voxels_on_segment(volume, |b - a|) voxels.
// (Always inlined: a generator's loop keeps its write pointer in a register across the walk.)
// The most voxels for_each_voxel_on_segment visits on a segment of the given length: 1 + the cell
// span per axis, each at most |d_i| cells_per_unit_i + 1, so 4 + sqrt(3) length x the finest cells
// per unit (2 stands for sqrt(3) with room for rounding), and never more than the grid's
// nx + ny + nz (the walk moves one cell at a time toward its last cell, inside the grid).
inline std::size_t max_voxels_on_segment(const hypervolume& volume, double length)
{
    const vec3d per = volume.cells_per_unit();
    const double finest = std::max({per.x, per.y, per.z});
    const resolution n = volume.grid();
    const double across = double(n.x) + double(n.y) + double(n.z);
    return std::size_t(std::min(4.0 + std::ceil(2.0 * length * finest), across));
}

template <class Visit>
[[gnu::always_inline]] inline void for_each_voxel_on_segment(const hypervolume& volume, const vec3d& a, const vec3d& b, Visit&& visit)
{
    if (!(std::isfinite(a.x) && std::isfinite(a.y) && std::isfinite(a.z) && std::isfinite(b.x) && std::isfinite(b.y) && std::isfinite(b.z)))
        return; // a NaN would pass the clipping below (max(t, NaN) = t) and make the cell count undefined
    const vec3d d = b - a;
    if (d.x == 0 && d.y == 0 && d.z == 0) {
        if (const auto i = volume.voxel_at(a)) visit(*i);
        return;
    }
    const double start[3] = {a.x, a.y, a.z}, dir[3] = {d.x, d.y, d.z};
    const vec3d lo = volume.origin(), hi = volume.maximum(), size = volume.voxel_size(), per = volume.cells_per_unit();
    const double low[3] = {lo.x, lo.y, lo.z}, high[3] = {hi.x, hi.y, hi.z}, side[3] = {size.x, size.y, size.z};
    const double cells_per_unit[3] = {per.x, per.y, per.z};
    const int n[3] = {volume.grid().x, volume.grid().y, volume.grid().z};
    double t0 = 0, t1 = 1;
    for (int i = 0; i < 3; ++i) {
        if (dir[i] == 0) {
            if (start[i] < low[i] || start[i] > high[i]) return;
            continue;
        }
        double ta = (low[i] - start[i]) / dir[i], tb = (high[i] - start[i]) / dir[i];
        if (ta > tb) std::swap(ta, tb);
        t0 = std::max(t0, ta), t1 = std::min(t1, tb);
    }
    if (!(t0 <= t1)) return;
    int cell[3], last[3], step[3];
    double next[3], delta[3];
    for (int i = 0; i < 3; ++i) {
        const auto cell_of = [&](double t) {
            const double c = std::floor((start[i] + dir[i] * t - low[i]) * cells_per_unit[i]);
            return int(std::clamp(c, 0.0, double(n[i] - 1)));
        };
        cell[i] = cell_of(t0), last[i] = cell_of(t1);
        step[i] = dir[i] > 0 ? 1 : dir[i] < 0 ? -1 : 0;
        if (step[i] == 0) {
            next[i] = delta[i] = INFINITY;
            continue;
        }
        const double boundary = low[i] + (cell[i] + (step[i] > 0 ? 1 : 0)) * side[i];
        next[i] = (boundary - start[i]) / dir[i];
        delta[i] = side[i] / std::abs(dir[i]);
    }
    // The walk ends at the last cell, the Manhattan distance away: finite whatever rounding does.
    // Each step moves the axis with the nearest boundary crossing among those that still have
    // cells to go (ties to the lowest axis) one cell toward the last cell. An axis with none left
    // gets crossing +infinity, so the choice is three comparisons; the index moves by the axis's
    // signed stride (unsigned arithmetic wraps it back). Kept in registers and free of branches
    // on the choice, which the segment's slopes make unpredictable.
    int rx = std::abs(last[0] - cell[0]), ry = std::abs(last[1] - cell[1]), rz = std::abs(last[2] - cell[2]);
    int budget = rx + ry + rz;
    const voxel_index sx = voxel_index(step[0]), sy = voxel_index(step[1]) * voxel_index(n[0]),
                      sz = voxel_index(step[2]) * voxel_index(n[0]) * voxel_index(n[1]);
    double tx = rx > 0 ? next[0] : INFINITY, ty = ry > 0 ? next[1] : INFINITY, tz = rz > 0 ? next[2] : INFINITY;
    voxel_index index = volume.index(cell[0], cell[1], cell[2]);
    for (;;) {
        visit(index);
        if (budget-- <= 0) return;
        const bool x = tx <= ty && tx <= tz, y = !x && ty <= tz, z = !x && !y;
        index += x ? sx : (y ? sy : sz);
        rx -= x, ry -= y, rz -= z;
        tx = x ? (rx > 0 ? tx + delta[0] : INFINITY) : tx;
        ty = y ? (ry > 0 ? ty + delta[1] : INFINITY) : ty;
        tz = z ? (rz > 0 ? tz + delta[2] : INFINITY) : tz;
    }
}

namespace detail {

struct no_observer {
    void operator()(const generator_event&) const {}
};

// A generator in flight: its two ends (equal for points).
struct segment {
    vec3d a, b;
};

// Where a chunk's hits go: a buffer the chunk loop writes through a local end pointer, which the
// compiler keeps in a register (a std::vector's push_back reloaded and stored its end in memory for
// every voxel of a line, and that round trip was the walk's slowest step). Points store their hit
// unconditionally and advance the end only when it counts: whether a generator is recorded (dummy
// rule) and inside the box are data-dependent coin flips the branch predictor cannot learn. Lines
// make room for the most voxels one segment can visit before walking it, so the walk writes
// without a check.
struct chunk_output {
    scratch_array<hit> hits; // its size is the capacity
    std::size_t count = 0;
    std::pmr::memory_resource* from = std::pmr::new_delete_resource();
    std::size_t size() const { return count; }
    std::size_t capacity() const { return hits.size(); }
    const hit* data() const { return hits.get(); }
    // Room for at least `more` hits past `count`, keeping those written (grows geometrically).
    void make_room(std::size_t more)
    {
        if (capacity() - count >= more) return;
        scratch_array<hit> bigger(std::max(count + more, capacity() + capacity() / 2), from);
        std::copy_n(hits.get(), count, bigger.get());
        hits = std::move(bigger);
    }
};

// The chunk loop, specialized at compile time for the generator's shape (Line), noise
// perturbation (Perturb) and the map type of the drawn IFS (a bare affine map when no chain has a
// shear, else the whole chain), so the per-generator work carries no runtime flags.
template <bool Line, bool Perturb, class Map, transform_pipeline P, class Observer>
void generate_chunk_as(const drawn_ifs<P>& tree, const Map* maps, random_stream random, std::uint64_t cycles, chunk_output& out,
                       generation_stats& stats, Observer& observer)
{
    constexpr bool observed = !std::is_same_v<Observer, no_observer>;
    const ifs<P>& def = tree.definition();
    const hypervolume& volume = def.volume;
    const int depth = def.tree_depth;
    const vec3d half = (def.generator.end - def.generator.start) * 0.5;
    const double half_length = krs::length(half);
    const int* const last_level = tree.last_levels().data();
    const int* const dummy_from = tree.dummies_from().data();
    const vec3d origin = volume.origin(), per = volume.cells_per_unit();
    const resolution grid = volume.grid();
    const double nx = grid.x, ny = grid.y, nz = grid.z;
    std::uint8_t selected[max_tree_depth];
    // Counted in locals, not through `stats`: the compiler cannot keep a referenced counter in a
    // register across the hit list's stores.
    std::uint64_t generators = 0, recorded_count = 0, escaped = 0, per_depth[max_tree_depth] = {};
    hit* end = out.hits.get() + out.count; // where the next hit goes
    // Room made before walking a line: its length is the generator's (transformed lines are
    // rescaled to it; perturbation moves both ends alike), up to rounding, which the bound's
    // factor 2 for sqrt(3) leaves ample room for.
    const std::size_t segment_voxels = Line ? max_voxels_on_segment(volume, 2.0 * half_length) : 1;

    // One cell-coordinate test decides both "inside" (for the escape count) and the voxel, which
    // voxel_at would otherwise recompute; written so that NaN counts as outside.
    const auto cell_of = [&](const vec3d& p, voxel_index& index) {
        const double fx = (p.x - origin.x) * per.x, fy = (p.y - origin.y) * per.y, fz = (p.z - origin.z) * per.z;
        const bool in = fx >= 0 && fy >= 0 && fz >= 0 && fx <= nx && fy <= ny && fz <= nz;
        // Clamped before converting, so an outside point still makes a valid integer, and NaN
        // becomes 0 (std::clamp would pass NaN on, and converting NaN is undefined); the lanes
        // compute the same (generator_lanes.hpp).
        const auto cell = [](double f, double n) { return int(f >= 0 ? std::min(f, n - 1) : 0.0); };
        const int x = cell(fx, nx), y = cell(fy, ny), z = cell(fz, nz);
        index = volume.index(x, y, z);
        return in;
    };
    // Records a generator (its ends after perturbation go to `a`, `b`), or only stores its would-be
    // hit past the end when `counts` is false; returns the recorded ends for the observer.
    const auto record = [&](vec3d& a, vec3d& b, int s, std::uint8_t part, bool counts) {
        if constexpr (Perturb) {
            // The whole generator moves with its midpoint, so a line keeps its length. Only
            // recorded generators move: the noise costs more than a mispredicted branch.
            if (counts) {
                const vec3d mid = Line ? (a + b) * 0.5 : a, shift = def.perturb.displaced(mid) - mid;
                a += shift;
                if constexpr (Line) b += shift;
            }
        }
        recorded_count += counts;
        per_depth[s] += counts;
        const std::uint8_t level = std::uint8_t(s);
        if constexpr (!Line) {
            voxel_index i;
            const bool in = cell_of(a, i);
            escaped += counts & !in;
            *end = hit{i, level, part};
            end += counts & in;
        } else {
            if (counts) {
                voxel_index ia, ib;
                const bool a_in = cell_of(a, ia), b_in = cell_of(b, ib);
                escaped += !(a_in && b_in);
                if (out.capacity() - std::size_t(end - out.hits.get()) < segment_voxels) {
                    out.count = std::size_t(end - out.hits.get());
                    out.make_room(segment_voxels);
                    end = out.hits.get() + out.count;
                }
                [[maybe_unused]] const hit* const walk_start = end;
                for_each_voxel_on_segment(volume, a, b, [&](voxel_index i) { *end++ = hit{i, level, part}; });
                assert(std::size_t(end - walk_start) <= segment_voxels);
            }
        }
    };
    // A transformed line is rescaled about its midpoint to the generator's length (section 4).
    const auto keep_length = [&](vec3d& a, vec3d& b) {
        const vec3d mid = (a + b) * 0.5, dir = b - a;
        const double len = krs::length(dir);
        const vec3d h = len > 0 ? dir * (half_length / len) : half;
        a = mid - h, b = mid + h;
    };

    for (std::uint64_t c = 0; c < cycles; ++c) {
        const vec3d stem = tree.sample_stem(random);
        const vec3d xa = stem - half, xb = stem + half;
        ++generators;
        {
            vec3d a = xa, b = xb;
            record(a, b, 0, 0, true);
            if constexpr (observed) observer(generator_event{0, {}, a, Line ? b : a, true});
        }

        // (inner_a, inner_b) hold w_{s-2}^3 ... w_1^s (X): the part of row s that row s + 1 reuses.
        vec3d inner_a = xa, inner_b = xb;
        int cycle_end = depth - 1; // the deepest row this cycle may make (last-level rule)
        for (int s = 1; s < depth; ++s) {
            const std::size_t w = tree.select(random.uniform());
            selected[s - 1] = std::uint8_t(w);
            // w_j executes at level s - j + 1 in row s: its last level is passed once s > m + j - 1.
            cycle_end = std::min(cycle_end, last_level[w] + s - 1);
            if (s > cycle_end) break;
            if (s >= 3) {
                const Map& m = maps[selected[s - 3] * distinct_levels + 2];
                inner_a = m(inner_a);
                if constexpr (Line) inner_b = m(inner_b);
            }
            vec3d a = inner_a, b = inner_b;
            if (s >= 2) {
                const Map& m = maps[selected[s - 2] * distinct_levels + 1];
                a = m(a);
                if constexpr (Line) b = m(b);
            }
            const Map& m = maps[w * distinct_levels];
            a = m(a);
            if constexpr (Line) {
                b = m(b);
                keep_length(a, b);
            }
            ++generators;
            const bool recorded = s < dummy_from[w];
            record(a, b, s, std::uint8_t(w + 1), recorded);
            if constexpr (observed)
                observer(generator_event{s, std::span<const std::uint8_t>(selected, std::size_t(s)), a, Line ? b : a, recorded});
        }
    }
    out.count = std::size_t(end - out.hits.get());
    stats.cycles += cycles, stats.generators += generators, stats.recorded += recorded_count, stats.escaped += escaped;
    for (int d = 0; d < depth; ++d) stats.recorded_per_depth[std::size_t(d)] += per_depth[d];
}

// Chunk `chunk` of `cycles` cycles: its lanes, in step when they can be, else one by one.
template <transform_pipeline P, class Observer>
void generate_chunk_unlocked(const drawn_ifs<P>& tree, std::uint64_t seed, std::uint64_t chunk, std::uint64_t cycles,
                             const lane_tables* lanes_in_step, chunk_output& out, generation_stats& stats, Observer& observer)
{
    constexpr std::uint64_t lanes = cycle_lanes;
    std::uint64_t lane_cycles[cycle_lanes];
    for (std::uint64_t j = 0; j < lanes; ++j) lane_cycles[j] = cycles / lanes + (j < cycles % lanes ? 1 : 0);
    const auto stream = [&](std::uint64_t j) { return random_stream::derive(seed, chunk * lanes + j + 1); };
    const bool line = !tree.definition().generator.is_point();
    if constexpr (std::is_same_v<Observer, no_observer>) {
        if (lanes_in_step) {
            std::uint64_t state[cycle_lanes];
            for (std::uint64_t j = 0; j < lanes; ++j) state[j] = stream(j).state();
            lane_counts counts{0, 0, 0, stats.recorded_per_depth.data()};
            const auto room = [&](hit* end, std::size_t more) {
                out.count = std::size_t(end - out.hits.get());
                out.make_room(more);
                return out.hits.get() + out.count;
            };
            const ifs<P>& def = tree.definition();
            hit* const start = out.hits.get() + out.count;
            const std::size_t segment_voxels = max_voxels_on_segment(def.volume, 2.0 * krs::length((def.generator.end - def.generator.start) * 0.5));
            hit* const end = line ? generate_in_lanes<true>(tree, *lanes_in_step, state, lane_cycles, start, counts, segment_voxels, room)
                                  : generate_in_lanes<false>(tree, *lanes_in_step, state, lane_cycles, start, counts, segment_voxels, room);
            out.count = std::size_t(end - out.hits.get());
            stats.cycles += cycles, stats.generators += counts.generators, stats.recorded += counts.recorded, stats.escaped += counts.escaped;
            return;
        }
    }
    const bool perturb = tree.definition().perturb.enabled();
    for (std::uint64_t j = 0; j < lanes; ++j) {
        const auto with_maps = [&](const auto* maps) {
            if (line && perturb) generate_chunk_as<true, true>(tree, maps, stream(j), lane_cycles[j], out, stats, observer);
            else if (line) generate_chunk_as<true, false>(tree, maps, stream(j), lane_cycles[j], out, stats, observer);
            else if (perturb) generate_chunk_as<false, true>(tree, maps, stream(j), lane_cycles[j], out, stats, observer);
            else generate_chunk_as<false, false>(tree, maps, stream(j), lane_cycles[j], out, stats, observer);
        };
        if (!tree.affine_table().empty()) with_maps(tree.affine_table().data());
        else with_maps(tree.chain_table().data());
    }
}

// ... and with locked voxels (ifs::trim, hypertree/region.hpp): the chunk's new hits on locked
// voxels are dropped as soon as the chunk is made, while they are hot in cache and before any other
// step sees them, so a locked voxel never enters the hit list. Filtering the chunk rather than
// testing in the record step keeps both generator loops (scalar and lanes in step) unchanged and
// their hits identical: the lock is a function of the voxel alone, whichever loop found it.
template <transform_pipeline P, class Observer>
void generate_chunk(const drawn_ifs<P>& tree, std::uint64_t seed, std::uint64_t chunk, std::uint64_t cycles,
                    const lane_tables* lanes_in_step, const voxel_lock* lock, chunk_output& out, generation_stats& stats, Observer& observer)
{
    const std::size_t first = out.count;
    generate_chunk_unlocked(tree, seed, chunk, cycles, lanes_in_step, out, stats, observer);
    if (lock == nullptr) return;
    hit* const hits = out.hits.get();
    std::size_t kept = first;
    for (std::size_t k = first; k < out.count; ++k)
        if (!lock->is_locked(hits[k].voxel)) hits[kept++] = hits[k];
    stats.locked += out.count - kept;
    out.count = kept;
}

} // namespace detail

namespace detail {

// The hits as the chunks made them, in chunk order: what generate() concatenates, and what
// build_tree validates without copying them first (at 300^3 the copy alone wrote 14 MB).
struct generated_chunks {
    std::vector<chunk_output> chunks;
    generation_stats stats;
    std::size_t hit_count() const
    {
        std::size_t n = 0;
        for (const chunk_output& c : chunks) n += c.size();
        return n;
    }
    std::vector<std::span<const hit>> pieces() const
    {
        std::vector<std::span<const hit>> p;
        for (const chunk_output& c : chunks) p.emplace_back(c.data(), c.size());
        return p;
    }
};

// Most voxels one generator can record: 1 for a point, the walk's bound for a line.
template <transform_pipeline P>
double voxels_per_generator(const ifs<P>& definition)
{
    return definition.generator.is_point() ? 1.0
                                           : 3.0 * std::ceil(definition.generator.length() / definition.volume.smallest_voxel_side()) + 3.0;
}

namespace detail {
// ceil(a / b) without the overflow of (a + b - 1) / b: near 2^64 that sum wrapped, so an
// iteration count of 2^64 - 1 made 0 cycles (an empty tree instead of a refusal) and a chunk
// size of 2^64 - 1, a natural way to ask for one chunk, made 0 chunks.
inline std::uint64_t divide_up(std::uint64_t a, std::uint64_t b) { return a / b + (a % b != 0 ? 1 : 0); }
} // namespace detail

// Generation cycles: each runs tree_depth iterations, so iterations / tree_depth rounded up.
template <transform_pipeline P>
std::uint64_t cycle_count(const ifs<P>& definition)
{
    return detail::divide_up(definition.iterations, std::uint64_t(definition.tree_depth));
}

// The most hits chunk `count` cycles can record: points make one per generator at most, lines the
// walk's bound per generator; and a row's room more, which the lanes ask for before each row.
template <transform_pipeline P>
std::size_t chunk_room(const ifs<P>& definition, std::uint64_t count)
{
    const std::uint64_t depth = std::uint64_t(definition.tree_depth);
    return definition.generator.is_point() ? std::size_t(count * depth) + cycle_lanes
                                           : std::size_t(double(count) * double(depth) * voxels_per_generator(definition)) +
                                                 cycle_lanes * (max_voxels_on_segment(definition.volume, definition.generator.length()) + 1);
}

// How one run of the generator is cut up, worked out once (plan_generation) before anything is
// allocated: the cycles, the chunks of generation_options::chunk_cycles cycles (the unit of the
// random streams, so of the hits), and the tasks that make them, each a group of consecutive
// chunks generated one after the other into one buffer (one chunk a task unless grouped). The
// hits taken in task order are the hits in chunk order whatever the grouping. generate_chunks runs
// a plan and works none of it out again; build_tree plans once for all its generation passes.
struct generation_plan {
    std::uint64_t cycles = 0;       // cycle_count
    std::uint64_t chunk_cycles = 1; // cycles of every chunk but the last, which takes the rest
    std::uint64_t chunks = 0;
    std::size_t tasks = 0; // task g makes chunks [first_chunk(g), first_chunk(g + 1))

    std::uint64_t cycles_of(std::uint64_t chunk) const { return std::min(chunk_cycles, cycles - chunk * chunk_cycles); }
    // floor(chunks g / tasks) without the product, which could pass 2^64 (g with a task a chunk).
    std::uint64_t first_chunk(std::size_t task) const { return chunks / tasks * task + chunks % tasks * task / tasks; }
    // The same chunks in `groups` tasks (one a chunk at most).
    generation_plan in_groups(std::size_t groups) const
    {
        generation_plan grouped = *this;
        grouped.tasks = std::size_t(std::min<std::uint64_t>(groups, chunks));
        return grouped;
    }
};

// The plan of a run, one task a chunk, and what generate_chunks checks before it allocates
// anything: the definition itself, the chunk size, and the memory budget against the most hits
// the run can record.
template <transform_pipeline P>
generation_plan plan_generation(const ifs<P>& definition, const generation_options& options)
{
    definition.validate();
    generation_plan plan;
    plan.cycles = cycle_count(definition);
    const std::uint64_t depth = std::uint64_t(definition.tree_depth);
    const double bytes_per_cycle = double(depth) * voxels_per_generator(definition) * double(sizeof(hit));
    const double worst_bytes = double(plan.cycles) * bytes_per_cycle;
    if (worst_bytes > double(options.budget.bytes)) {
        // What fits: whole cycles of tree_depth iterations within the budget.
        const std::uint64_t fitting = std::uint64_t(std::floor(double(options.budget.bytes) / bytes_per_cycle)) * depth;
        throw krs::invalid_parameter("ifs.iterations",
                                     "would record up to " + std::to_string(std::uint64_t(worst_bytes)) + " bytes of hits, over the memory budget of " +
                                         std::to_string(options.budget.bytes) + " bytes; " +
                                         (fitting > 0 ? "at most " + std::to_string(fitting) + " iterations fit"
                                                      : "no iteration fits (the generator covers too many voxels for the budget)"),
                                     std::to_string(definition.iterations));
    }
    if (options.chunk_cycles < 1) throw krs::invalid_parameter("generation_options.chunk_cycles", "must be >= 1", "0");
    plan.chunk_cycles = options.chunk_cycles;
    plan.chunks = detail::divide_up(plan.cycles, plan.chunk_cycles);
    plan.tasks = std::size_t(plan.chunks);
    return plan;
}

// How many groups of consecutive chunks build_tree generates, each into one buffer that it
// validates while hot: enough that a group's most hits fill about 1 MiB (the L2 cache of one core),
// and at least 8 groups where there are that many chunks, for two to four threads to share.
// Bucketing chunk by chunk split tree D's 1 M hits into 82 x 2048 pieces of 6 keys on average,
// each a cache line or more to write and to read back, and the merge paid a loop per piece; in
// groups of 10 chunks the pieces hold 60 keys.
template <transform_pipeline P>
std::size_t generation_group_count(const ifs<P>& definition, const generation_plan& plan)
{
    constexpr double group_bytes = double(1 << 20);
    constexpr std::uint64_t fewest_groups = 8;
    const double most_hits_per_chunk = double(chunk_room(definition, std::min(plan.chunk_cycles, plan.cycles)));
    const std::uint64_t chunks = plan.chunks;
    const double per_group = std::max(1.0, std::floor(group_bytes / std::max(1.0, most_hits_per_chunk * double(sizeof(hit)))));
    const std::uint64_t groups = std::max<std::uint64_t>(
        std::min<std::uint64_t>(chunks, fewest_groups), std::uint64_t(std::ceil(double(chunks) / per_group)));
    return std::size_t(std::min(groups, chunks));
}

struct no_after_chunk {
    void operator()(std::size_t, chunk_output&) const {}
};

// Runs `plan` (plan_generation of this definition and options; the options say how: threads,
// lanes, scratch). after_chunk(g, buffer) runs on task g as soon as its chunks are made, while
// their hits are hot in cache; it may take them and empty the buffer.
template <transform_pipeline P, class Observer, class AfterChunk = no_after_chunk>
generated_chunks generate_chunks(const ifs<P>& definition, std::uint64_t seed, const generation_plan& plan, const generation_options& options,
                                 Observer& observer, const AfterChunk& after_chunk = {})
{
    const drawn_ifs<P> tree(definition, seed);
    const std::uint64_t depth = std::uint64_t(definition.tree_depth);
    // The lanes' lookup tables, built once for all chunks (observed runs take the scalar loop).
    const std::optional<lane_tables> lanes_in_step =
        options.vector_lanes && std::is_same_v<Observer, no_observer> ? lane_tables::of(tree) : std::nullopt;
    const std::optional<voxel_lock> lock = definition.trim.empty() ? std::nullopt : std::optional<voxel_lock>(std::in_place, definition.volume, definition.trim);
    generated_chunks out;
    out.chunks.resize(plan.tasks);
    std::vector<generation_stats> chunk_stats(plan.tasks);
    const auto run = [&](std::size_t g) {
        const std::uint64_t begin = plan.first_chunk(g), end = plan.first_chunk(g + 1);
        chunk_stats[g].recorded_per_depth.assign(depth, 0);
        // Room for the most hits the task's chunks can make, so the buffer never grows (a copy
        // that touches fresh pages). Pages never written are never touched, so where the system
        // overcommits (Linux's default) the worst case costs address space only; all chunks
        // together stay within the budget the plan checked.
        std::size_t room = 0;
        for (std::uint64_t c = begin; c < end; ++c) room += chunk_room(definition, plan.cycles_of(c));
        out.chunks[g].from = scratch_or_default(options.scratch);
        out.chunks[g].make_room(room);
        for (std::uint64_t c = begin; c < end; ++c)
            generate_chunk(tree, seed, c, plan.cycles_of(c), lanes_in_step ? &*lanes_in_step : nullptr, lock ? &*lock : nullptr, out.chunks[g],
                           chunk_stats[g], observer);
        after_chunk(g, out.chunks[g]);
    };
    run_tasks(options.parallel_for, plan.tasks, run);

    out.stats.recorded_per_depth.assign(depth, 0);
    for (const generation_stats& s : chunk_stats) {
        out.stats.cycles += s.cycles, out.stats.generators += s.generators;
        out.stats.recorded += s.recorded, out.stats.escaped += s.escaped, out.stats.locked += s.locked;
        for (std::size_t d = 0; d < depth; ++d) out.stats.recorded_per_depth[d] += s.recorded_per_depth[d];
    }
    return out;
}

// The same, planned here: one task a chunk, or with `groups` > 0 that many groups of consecutive
// chunks (group g: chunks [chunks g / groups, chunks (g + 1) / groups)).
template <transform_pipeline P, class Observer, class AfterChunk = no_after_chunk>
generated_chunks generate_chunks(const ifs<P>& definition, std::uint64_t seed, const generation_options& options, Observer& observer,
                                 const AfterChunk& after_chunk = {}, std::size_t groups = 0)
{
    const generation_plan plan = plan_generation(definition, options);
    return generate_chunks(definition, seed, groups == 0 ? plan : plan.in_groups(groups), options, observer, after_chunk);
}

} // namespace detail

// Runs the IFS: N = ifs.iterations iterations in cycles of tree_depth, deterministic for `seed`.
// Refuses, before allocating, a run whose hit list would exceed the memory budget.
template <transform_pipeline P, class Observer = detail::no_observer>
generated_hits generate(const ifs<P>& definition, std::uint64_t seed, const generation_options& options = {},
                        Observer observer = {})
{
    detail::generated_chunks generated = detail::generate_chunks(definition, seed, options, observer);
    generated_hits result{definition.volume, {}, std::move(generated.stats)};
    result.hits.reserve(generated.hit_count());
    for (detail::chunk_output& c : generated.chunks) {
        result.hits.insert(result.hits.end(), c.data(), c.data() + c.size());
        c = {};
    }
    return result;
}

} // namespace hypertree

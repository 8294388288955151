#pragma once
// The generator's loop, eight cycles at a time in the lanes of AVX-512 registers.
//
// A chunk of the generator (generate.hpp) is cut into `cycle_lanes` = 8 lanes of cycles, each
// drawing from its own random stream, in every build: the lanes are what the tree is defined by,
// and how they run is the build's choice. Without AVX-512 they run one after the other through
// the scalar loop. With it, and for the trees this file handles (no noise perturbation, at most 16
// transformations, chains whose shears share one shape: the same count, axes and whole exponent
// in every transformation and level; all four presets), all eight run in step: lane j holds
// cycle i of stream j, for i = 0, 1, ... The scalar loop's per-generator work (a draw, Walker's
// alias selection, three chains of maps, the voxel or the walk along a line, and the level rules)
// is a chain of dependent steps on scalars; in lanes it is the same steps on eight generators.
// The per-lane choice of map becomes a permute: for each level and coefficient a pair of
// registers holds that coefficient of every transformation, and vpermt2pd picks each lane's.
// Where the scalar loop branches (a lane's cycle ends by the last-level rule, a rejection
// sampler retries, a line walk has voxels left), a mask keeps the lanes that go on.
//
// The voxel walks of lines run one row behind: a row's walks step together with the next row's,
// whose hits wait in a small side buffer until the first row's are written (record_line below),
// so the hit list is that of walking each row to its end first.
//
// Every step is the scalar loop's arithmetic in the same order (multiplies and adds, with no
// fused multiply-add written here), so where the compiler does not contract the two paths give
// the same hits, only interleaved differently (tested with contraction off).

#include "hypertree/ifs.hpp"
#include "hypertree/voxel.hpp"

#include <algorithm>
#include <bit>
#include <cmath>
#include <cstdint>
#include <memory>
#include <optional>
#include <span>

#if defined(__AVX512F__) && defined(__AVX512DQ__)
#include <immintrin.h>
#define HYPERTREE_GENERATOR_LANES 1
#else
#define HYPERTREE_GENERATOR_LANES 0
#endif

namespace hypertree::detail {

// Lanes of cycles per chunk, each with its own stream: a property of the generated tree, the same
// in every build.
inline constexpr int cycle_lanes = 8;

// What the lanes count, added to by the caller's totals.
struct lane_counts {
    std::uint64_t generators = 0, recorded = 0, escaped = 0;
    std::uint64_t* per_depth = nullptr; // tree_depth entries
};

#if HYPERTREE_GENERATOR_LANES

inline constexpr bool lanes_built = true;

// The shape all chains share in the lanes: how many shears, and per shear its axes and whole
// exponent (what differs per transformation, the affine maps and the shears' amounts, is looked up
// per lane).
struct lane_chain_shape {
    static constexpr int max_shears = 4;
    struct shear_shape {
        int axis = 1, first = 0, second = 2, whole_exponent = 1;
        bool operator==(const shear_shape&) const = default;
    };
    int shears = 0;
    shear_shape shear[max_shears]{};
};

// The common shape of chains, or nothing when they differ or the lanes cannot take them.
template <class Chain>
std::optional<lane_chain_shape> common_shape(std::span<const Chain> chains)
{
    std::optional<lane_chain_shape> shape;
    for (const Chain& chain : chains) {
        lane_chain_shape c;
        c.shears = chain.shears;
        if (c.shears > lane_chain_shape::max_shears) return std::nullopt;
        for (int k = 0; k < c.shears; ++k) {
            const shear_map& m = chain.shear[std::size_t(k)];
            if (m.whole_exponent < 1) return std::nullopt;
            c.shear[k] = {m.axis, m.first, m.second, m.whole_exponent};
        }
        if (!shape) shape = c;
        else if (shape->shears != c.shears || !std::equal(c.shear, c.shear + c.shears, shape->shear)) return std::nullopt;
    }
    return shape;
}

// Whether the lanes loop handles this tree (else the scalar loop runs each lane): the
// transformations' chains share a shape, and so do the condensations'.
template <transform_pipeline P>
bool lanes_fit(const drawn_ifs<P>& tree)
{
    const ifs<P>& def = tree.definition();
    return !def.perturb.enabled() && tree.transform_count() <= 16 && common_shape(tree.chain_table()) &&
           common_shape(tree.stem_chains());
}

// Chains of one shape as lookup tables of 16 entries (two registers) per quantity: the affine
// maps' 12 coefficients each, and the shears' displacement per axis and inverse height.
struct lane_chain_tables {
    alignas(64) double affine[lane_chain_shape::max_shears + 1][12][16];
    alignas(64) double shear[lane_chain_shape::max_shears][4][16]; // along x, y, z; inverse height

    // Entry j holds `chain`.
    template <class Chain>
    void set(std::size_t j, const lane_chain_shape& shape, const Chain& chain)
    {
        for (int a = 0; a <= shape.shears; ++a) {
            const affine_map& m = chain.affine[std::size_t(a)];
            for (int k = 0; k < 9; ++k) affine[a][k][j] = m.m[std::size_t(k)];
            affine[a][9][j] = m.t.x, affine[a][10][j] = m.t.y, affine[a][11][j] = m.t.z;
        }
        for (int k = 0; k < shape.shears; ++k) {
            const shear_map& m = chain.shear[std::size_t(k)];
            // shear_map::operator()'s along(i), per axis.
            for (int i = 0; i < 3; ++i) shear[k][i][j] = (m.first == i ? m.dmax_first : 0.0) + (m.second == i ? m.dmax_second : 0.0);
            shear[k][3][j] = m.inverse_height;
        }
    }
};

// What the lanes look up, built once per generated tree (generate() shares it among its chunks):
// per level, the transformations' chains; the condensations' chains; and the small tables of
// selection and level rules. Entries past the last are copies of entry 0.
struct lane_tables {
    lane_chain_shape shape, stem_shape;
    std::unique_ptr<lane_chain_tables[]> chains; // distinct_levels levels, then the stems (40 KiB)
    alignas(64) double keep[16];
    alignas(64) std::int64_t alias[16], last_level[16], dummy_from[16];

    // The tables of a tree the lanes handle (lanes_fit), else nothing.
    template <transform_pipeline P>
    static std::optional<lane_tables> of(const drawn_ifs<P>& tree)
    {
        if (!lanes_fit(tree)) return std::nullopt;
        std::optional<lane_tables> t(std::in_place);
        t->shape = *common_shape(tree.chain_table()), t->stem_shape = *common_shape(tree.stem_chains());
        t->chains.reset(new lane_chain_tables[distinct_levels + 1]);
        const std::size_t n = tree.transform_count();
        for (std::size_t j = 0; j < 16; ++j) {
            const std::size_t k = j < n ? j : 0;
            for (int l = 0; l < distinct_levels; ++l) t->chains[l].set(j, t->shape, tree.chain_table()[k * distinct_levels + std::size_t(l)]);
            t->chains[distinct_levels].set(j, t->stem_shape, tree.stem_chains()[j < tree.stem_chains().size() ? j : 0]);
            t->keep[j] = tree.alias_keep()[k];
            t->alias[j] = std::int64_t(tree.alias_of()[k]);
            t->last_level[j] = tree.last_levels()[k];
            t->dummy_from[j] = tree.dummies_from()[k];
        }
        return t;
    }
};

// Runs lane j's `cycles[j]` cycles from random state `state[j]` (updated), with cycles[j] in
// non-increasing order of j, writing each recorded hit at `end` and returning the new end. Every
// store writes a whole register of hits and advances by those that count: before each row,
// room(end, k) must return where `end` now is (the buffer may move) with room for k hits past it;
// the lanes ask for cycle_lanes per row of points and cycle_lanes (segment_voxels + 1) per row of
// lines, segment_voxels being the most one line visits (generate.hpp). OverlapWalks = false walks
// each row of lines to its end before the next row begins (the reference the overlap is tested
// against: the same hits in the same order).
template <bool Line, bool OverlapWalks = true, transform_pipeline P, class Room>
hit* generate_in_lanes(const drawn_ifs<P>& tree, const lane_tables& lookups, std::uint64_t (&state)[cycle_lanes],
                       const std::uint64_t (&cycles)[cycle_lanes], hit* end, lane_counts& counts, std::size_t segment_voxels, Room&& room)
{
    const ifs<P>& def = tree.definition();
    const int depth = def.tree_depth;
    const std::size_t n = tree.transform_count();
    const lane_chain_shape &shape = lookups.shape, &stem_shape = lookups.stem_shape;
    const lane_chain_tables* const tables = lookups.chains.get();
    const lane_chain_tables& stem_tables = tables[distinct_levels];
    const double* const keep = lookups.keep;
    const std::int64_t *const alias = lookups.alias, *const last_level = lookups.last_level, *const dummy_from = lookups.dummy_from;
    const auto lookup = [](const double* table, __m512i index) {
        return _mm512_permutex2var_pd(_mm512_load_pd(table), index, _mm512_load_pd(table + 8));
    };
    const auto lookup_int = [](const std::int64_t* table, __m512i index) {
        return _mm512_permutex2var_epi64(_mm512_load_si512(table), index, _mm512_load_si512(table + 8));
    };
    struct points {
        __m512d x, y, z;
    };
    // affine_map::operator() term by term: ((m0 x + m1 y) + m2 z) + t.
    const auto apply_affine = [&](const double (&coefficient)[12][16], __m512i w, const points& p) {
        const auto c = [&](int k) { return lookup(coefficient[k], w); };
        const auto row = [&](int r, int t) {
            return _mm512_add_pd(_mm512_add_pd(_mm512_add_pd(_mm512_mul_pd(c(3 * r), p.x), _mm512_mul_pd(c(3 * r + 1), p.y)),
                                               _mm512_mul_pd(c(3 * r + 2), p.z)),
                                 c(t));
        };
        return points{row(0, 9), row(1, 10), row(2, 11)};
    };
    // shear_map::operator() step by step: h = min(|p_axis| / height, 1), f = h^e by repeated
    // squaring, then p + along * f per axis.
    const __m512d one = _mm512_set1_pd(1.0);
    const auto apply_shear = [&](const double (&table)[4][16], const lane_chain_shape::shear_shape& k, __m512i w, const points& p) {
        const __m512d height = k.axis == 0 ? p.x : k.axis == 1 ? p.y : p.z;
        // min_pd(a, b) is a < b ? a : b, so min_pd(1, x) is std::min(x, 1), NaN included.
        const __m512d h = _mm512_min_pd(one, _mm512_mul_pd(_mm512_abs_pd(height), lookup(table[3], w)));
        __m512d f = one, base = h;
        for (int e = k.whole_exponent; e > 0; e >>= 1, base = _mm512_mul_pd(base, base))
            if (e & 1) f = _mm512_mul_pd(f, base);
        return points{_mm512_add_pd(p.x, _mm512_mul_pd(lookup(table[0], w), f)), _mm512_add_pd(p.y, _mm512_mul_pd(lookup(table[1], w), f)),
                      _mm512_add_pd(p.z, _mm512_mul_pd(lookup(table[2], w), f))};
    };
    // map_chain::operator(): each shear after its affine map, then the last affine map.
    const auto apply_chain = [&](const lane_chain_tables& t, const lane_chain_shape& form, __m512i w, points p) {
        for (int k = 0; k < form.shears; ++k) p = apply_shear(t.shear[k], form.shear[k], w, apply_affine(t.affine[k], w, p));
        return apply_affine(t.affine[form.shears], w, p);
    };
    const auto apply = [&](int level, __m512i w, const points& p) { return apply_chain(tables[std::size_t(level)], shape, w, p); };

    // splitmix64 in each lane (random_stream::next, then uniform()), advancing only the lanes in m.
    __m512i random = _mm512_loadu_si512(state);
    const __m512i golden = _mm512_set1_epi64(std::int64_t(0x9e3779b97f4a7c15ull));
    const __m512i mix1 = _mm512_set1_epi64(std::int64_t(0xbf58476d1ce4e5b9ull)), mix2 = _mm512_set1_epi64(std::int64_t(0x94d049bb133111ebull));
    const auto uniform = [&](__mmask8 m) {
        random = _mm512_mask_add_epi64(random, m, random, golden);
        __m512i z = _mm512_mullo_epi64(_mm512_xor_si512(random, _mm512_srli_epi64(random, 30)), mix1);
        z = _mm512_mullo_epi64(_mm512_xor_si512(z, _mm512_srli_epi64(z, 27)), mix2);
        z = _mm512_xor_si512(z, _mm512_srli_epi64(z, 31));
        return _mm512_mul_pd(_mm512_cvtepu64_pd(_mm512_srli_epi64(z, 11)), _mm512_set1_pd(0x1.0p-53));
    };

    // The voxel of each lane's point and whether it lies inside (the scalar loop's cell_of).
    const hypervolume& volume = def.volume;
    const vec3d origin = volume.origin(), per = volume.cells_per_unit();
    const resolution grid = volume.grid();
    const __m512d ox = _mm512_set1_pd(origin.x), oy = _mm512_set1_pd(origin.y), oz = _mm512_set1_pd(origin.z);
    const __m512d px = _mm512_set1_pd(per.x), py = _mm512_set1_pd(per.y), pz = _mm512_set1_pd(per.z);
    const __m512d nx = _mm512_set1_pd(grid.x), ny = _mm512_set1_pd(grid.y), nz = _mm512_set1_pd(grid.z);
    const __m512d zero = _mm512_setzero_pd();
    const __m256i stride_y = _mm256_set1_epi32(grid.x), stride_z = _mm256_set1_epi32(int(std::uint32_t(grid.x) * std::uint32_t(grid.y)));
    // Whether each lane's point lies inside (the scalar loop's cell_of), and its voxel.
    const auto cells = [&](const points& p, __m512d& fx, __m512d& fy, __m512d& fz) {
        fx = _mm512_mul_pd(_mm512_sub_pd(p.x, ox), px), fy = _mm512_mul_pd(_mm512_sub_pd(p.y, oy), py),
        fz = _mm512_mul_pd(_mm512_sub_pd(p.z, oz), pz);
        return __mmask8(_mm512_cmp_pd_mask(fx, zero, _CMP_GE_OQ) & _mm512_cmp_pd_mask(fy, zero, _CMP_GE_OQ) &
                        _mm512_cmp_pd_mask(fz, zero, _CMP_GE_OQ) & _mm512_cmp_pd_mask(fx, nx, _CMP_LE_OQ) &
                        _mm512_cmp_pd_mask(fy, ny, _CMP_LE_OQ) & _mm512_cmp_pd_mask(fz, nz, _CMP_LE_OQ));
    };
    const auto inside = [&](const points& p) {
        __m512d fx, fy, fz;
        return cells(p, fx, fy, fz);
    };
    const auto voxel_of = [&](__m512d fx, __m512d fy, __m512d fz) {
        const auto cell = [&](__m512d f, __m512d size) {
            return _mm512_cvttpd_epi32(_mm512_min_pd(_mm512_max_pd(f, zero), _mm512_sub_pd(size, one)));
        };
        const __m256i x = cell(fx, nx), y = cell(fy, ny), z = cell(fz, nz);
        return _mm512_cvtepu32_epi64(_mm256_add_epi32(x, _mm256_add_epi32(_mm256_mullo_epi32(y, stride_y), _mm256_mullo_epi32(z, stride_z))));
    };
    // Stores the hits of the lanes in `kept`: voxel (low 32 bits of `index`) with the tag of
    // level and part, as a hit's 8 bytes (then padding).
    const auto store = [&](__m512i index, __mmask8 kept, __m512i tag) {
        const __m512i packed = _mm512_or_si512(_mm512_and_si512(index, _mm512_set1_epi64(0xffffffffll)), tag);
        _mm512_storeu_si512(end, _mm512_maskz_compress_epi64(kept, packed));
        end += std::popcount(unsigned(kept));
    };
    const auto tag_of = [](int level, __m512i part) {
        return _mm512_or_si512(_mm512_set1_epi64(std::int64_t(level) << 32), _mm512_slli_epi64(part, 40));
    };
    const auto count = [&](__mmask8 mask, __mmask8 escaped, int level) {
        counts.recorded += unsigned(std::popcount(unsigned(mask)));
        counts.escaped += unsigned(std::popcount(unsigned(escaped)));
        counts.per_depth[level] += unsigned(std::popcount(unsigned(mask)));
    };
    // Records the lanes of `mask` whose point is inside; counts those outside as escaped.
    const auto record = [&](const points& p, __mmask8 mask, int level, __m512i part) {
        __m512d fx, fy, fz;
        const __mmask8 in = cells(p, fx, fy, fz);
        store(voxel_of(fx, fy, fz), mask & in, tag_of(level, part));
        count(mask, mask & ~in, level);
    };
    // The voxels of the lanes' segments: for_each_voxel_on_segment in lanes, step for step (its
    // clipping, cells and walk; see generate.hpp), each lane walking until its own budget is spent.
    // Lanes with an end outside count as escaped.
    const vec3d low_corner = volume.origin(), high_corner = volume.maximum(), voxel_side = volume.voxel_size();
    const double low_[3] = {low_corner.x, low_corner.y, low_corner.z}, high_[3] = {high_corner.x, high_corner.y, high_corner.z};
    const double side_[3] = {voxel_side.x, voxel_side.y, voxel_side.z}, per_[3] = {per.x, per.y, per.z};
    const std::int64_t cells_[3] = {grid.x, grid.y, grid.z};
    const std::int64_t strides_[3] = {1, std::int64_t(grid.x), std::int64_t(grid.x) * std::int64_t(grid.y)};
    const __m512d infinity = _mm512_set1_pd(INFINITY);
    const __m512i zero_i = _mm512_setzero_si512(), one_i = _mm512_set1_epi64(1);
    const auto finite = [](__m512d v) { return __mmask8(_mm512_fpclass_pd_mask(v, 0x99) ^ 0xff); }; // not NaN nor +-inf
    // A row's voxel walks in flight: the walk's state between steps (zero before a walk begins, so
    // that stepping a row with no lane walking reads defined values and stores nothing).
    struct walk {
        __mmask8 walking = 0;
        __m512i tag{}, index{}, budget{}, remaining[3]{}, stride[3]{};
        __m512d crossing[3]{}, delta[3]{};
    };
    const auto store_at = [&](hit*& at, __m512i index, __mmask8 kept, __m512i tag) {
        const __m512i packed = _mm512_or_si512(_mm512_and_si512(index, _mm512_set1_epi64(0xffffffffll)), tag);
        _mm512_storeu_si512(at, _mm512_maskz_compress_epi64(kept, packed));
        at += std::popcount(unsigned(kept));
    };
    // Begins the walks of the lanes of `mask` whose segment [a, b] visits voxels (clipping and
    // first cells), storing at `at` the voxel of those whose segment is a point.
    const auto begin_walk = [&](const points& a, const points& b, __mmask8 mask, int level, __m512i part, hit*& at) {
        walk w;
        count(mask, mask & ~(inside(a) & inside(b)), level);
        if (!mask) return w;
        const __m512i tag = tag_of(level, part);
        w.tag = tag;
        __mmask8 walking = mask & finite(a.x) & finite(a.y) & finite(a.z) & finite(b.x) & finite(b.y) & finite(b.z);
        const __m512d start[3] = {a.x, a.y, a.z};
        const __m512d dir[3] = {_mm512_sub_pd(b.x, a.x), _mm512_sub_pd(b.y, a.y), _mm512_sub_pd(b.z, a.z)};
        __mmask8 still = walking, moves[3];
        for (int i = 0; i < 3; ++i) {
            moves[i] = _mm512_cmp_pd_mask(dir[i], zero, _CMP_NEQ_UQ);
            still &= ~moves[i];
        }
        if (still) { // a point: its voxel, if inside
            __m512d fx, fy, fz;
            const __mmask8 in = cells(a, fx, fy, fz);
            store_at(at, voxel_of(fx, fy, fz), still & in, tag);
            walking &= ~still;
        }
        if (!walking) return w;
        __m512d t0 = zero, t1 = one;
        for (int i = 0; i < 3; ++i) {
            const __m512d lo = _mm512_set1_pd(low_[i]), hi = _mm512_set1_pd(high_[i]);
            walking &= moves[i] | ~(_mm512_cmp_pd_mask(start[i], lo, _CMP_LT_OQ) | _mm512_cmp_pd_mask(start[i], hi, _CMP_GT_OQ));
            const __m512d ta = _mm512_div_pd(_mm512_sub_pd(lo, start[i]), dir[i]), tb = _mm512_div_pd(_mm512_sub_pd(hi, start[i]), dir[i]);
            const __mmask8 swap = _mm512_cmp_pd_mask(ta, tb, _CMP_GT_OQ);
            const __m512d near = _mm512_mask_blend_pd(swap, ta, tb), far = _mm512_mask_blend_pd(swap, tb, ta);
            t0 = _mm512_mask_max_pd(t0, moves[i], near, t0); // std::max(t0, near)
            t1 = _mm512_mask_min_pd(t1, moves[i], far, t1);  // std::min(t1, far)
        }
        walking &= _mm512_cmp_pd_mask(t0, t1, _CMP_LE_OQ);
        if (!walking) return w;
        w.index = zero_i, w.budget = zero_i;
        for (int i = 0; i < 3; ++i) {
            const __m512d lo = _mm512_set1_pd(low_[i]), per_unit = _mm512_set1_pd(per_[i]), side = _mm512_set1_pd(side_[i]);
            const __m512d top = _mm512_set1_pd(double(cells_[i] - 1));
            const auto cell_at = [&](__m512d t) {
                const __m512d c = _mm512_roundscale_pd(_mm512_mul_pd(_mm512_sub_pd(_mm512_add_pd(start[i], _mm512_mul_pd(dir[i], t)), lo), per_unit),
                                                       _MM_FROUND_TO_NEG_INF | _MM_FROUND_NO_EXC);
                return _mm512_cvttpd_epi64(_mm512_min_pd(_mm512_max_pd(c, zero), top)); // std::clamp(c, 0, n - 1)
            };
            const __m512i cell = cell_at(t0), last = cell_at(t1);
            const __mmask8 up = _mm512_cmp_pd_mask(dir[i], zero, _CMP_GT_OQ), down = _mm512_cmp_pd_mask(dir[i], zero, _CMP_LT_OQ);
            const __m512i step = _mm512_mask_mov_epi64(_mm512_maskz_mov_epi64(up, one_i), down, _mm512_set1_epi64(-1));
            const __m512d boundary = _mm512_add_pd(lo, _mm512_mul_pd(_mm512_cvtepi64_pd(_mm512_mask_add_epi64(cell, up, cell, one_i)), side));
            const __m512d next = _mm512_div_pd(_mm512_sub_pd(boundary, start[i]), dir[i]);
            w.delta[i] = _mm512_div_pd(side, _mm512_abs_pd(dir[i]));
            w.remaining[i] = _mm512_abs_epi64(_mm512_sub_epi64(last, cell));
            w.budget = _mm512_add_epi64(w.budget, w.remaining[i]);
            w.crossing[i] = _mm512_mask_mov_pd(infinity, _mm512_cmp_epi64_mask(w.remaining[i], zero_i, _MM_CMPINT_GT), next);
            w.stride[i] = _mm512_mullo_epi64(step, _mm512_set1_epi64(strides_[i]));
            w.index = _mm512_add_epi64(w.index, _mm512_mullo_epi64(cell, _mm512_set1_epi64(strides_[i])));
        }
        w.walking = walking;
        return w;
    };
    // One step of the walks: the voxels of the lanes walking, stored at `at`, then each lane's
    // next voxel (lanes that stopped move too, unseen: they store nothing again).
    const auto step_walk = [&](walk& w, hit*& at) {
        store_at(at, w.index, w.walking, w.tag);
        w.walking &= _mm512_cmp_epi64_mask(w.budget, zero_i, _MM_CMPINT_GT);
        w.budget = _mm512_sub_epi64(w.budget, one_i);
        const __mmask8 x = _mm512_cmp_pd_mask(w.crossing[0], w.crossing[1], _CMP_LE_OQ) & _mm512_cmp_pd_mask(w.crossing[0], w.crossing[2], _CMP_LE_OQ);
        const __mmask8 y = __mmask8(~x) & _mm512_cmp_pd_mask(w.crossing[1], w.crossing[2], _CMP_LE_OQ);
        const __mmask8 moved[3] = {x, y, __mmask8(~x & ~y)};
        for (int i = 0; i < 3; ++i) {
            w.index = _mm512_mask_add_epi64(w.index, moved[i], w.index, w.stride[i]);
            w.remaining[i] = _mm512_mask_sub_epi64(w.remaining[i], moved[i], w.remaining[i], one_i);
            const __m512d ahead = _mm512_mask_mov_pd(infinity, _mm512_cmp_epi64_mask(w.remaining[i], zero_i, _MM_CMPINT_GT),
                                                     _mm512_add_pd(w.crossing[i], w.delta[i]));
            w.crossing[i] = _mm512_mask_mov_pd(w.crossing[i], moved[i], ahead);
        }
    };
    // Records a row of segments with the previous row's walks still in flight: this row's walks
    // begin into `side` and step along with the previous row's, which write at `end`; when those
    // end, this row's hits so far follow them and its walks go on at `end`, overlapping the next
    // row's geometry and walks. The hits are those of walking each row to its end before the
    // next, in the same order. Why: one walk is a chain of dependent steps (compare the three
    // crossings, move, add delta; the end pointer advanced by a popcount) that leaves the core
    // idle between steps, and tree C's generation is ~80% walk; two independent walks per step
    // fill it (tree C at 300: 3.3 -> 2.4-2.5 ms on one thread, docs/benchmarks.md). Room: the
    // previous row's walks write within the room asked for when their row took over `end` (at
    // most row_room from there); this row asks again once they are done, as a row walked alone
    // would; `side` holds one row and a register's slack.
    const std::size_t side_room = Line ? cycle_lanes * (segment_voxels + 1) + cycle_lanes : 0;
    std::unique_ptr<hit[]> side(Line ? new hit[side_room] : nullptr);
    walk pending;
    const std::size_t row_room = cycle_lanes * (Line ? segment_voxels + 1 : 1);
    const auto record_line = [&](const points& a, const points& b, __mmask8 mask, int level, __m512i part) {
        hit* at = side.get();
        walk next = begin_walk(a, b, mask, level, part, at);
        while (pending.walking) step_walk(pending, end), step_walk(next, at);
        end = room(end, row_room);
        const std::size_t written = std::size_t(at - side.get());
        std::copy_n(side.get(), written, end);
        end += written;
        pending = next;
        if constexpr (!OverlapWalks)
            while (pending.walking) step_walk(pending, end);
    };

    const __m512i last_column = _mm512_set1_epi64(std::int64_t(n) - 1);
    const __m512d columns = _mm512_set1_pd(double(n));
    // drawn_ifs::sample_stem and cone::sample in the lanes of `alive`, each drawing exactly what the
    // scalar sampler draws: a lane repeats a rejection loop until it accepts, and the lanes that
    // have accepted stop drawing.
    const std::span<const cone> stems = tree.stems();
    const auto sample_stems = [&](__mmask8 alive) {
        __mmask8 second = 0; // the lanes whose stem is the second condensation
        if (stems.size() > 1)
            second = alive & _mm512_cmp_pd_mask(_mm512_mul_pd(uniform(alive), _mm512_set1_pd(tree.stem_volume_total())),
                                                 _mm512_set1_pd(tree.first_stem_volume()), _CMP_NLT_UQ);
        const cone& c0 = stems[0];
        const cone& c1 = stems[stems.size() > 1 ? 1 : 0];
        const auto per_stem = [&](double a, double b) { return _mm512_mask_blend_pd(second, _mm512_set1_pd(a), _mm512_set1_pd(b)); };
        const __m512d r0 = per_stem(c0.bottom_radius, c1.bottom_radius), r1 = per_stem(c0.top_radius, c1.top_radius);
        const __m512d r_max = per_stem(std::max(c0.bottom_radius, c0.top_radius), std::max(c1.bottom_radius, c1.top_radius));
        __m512d t = _mm512_setzero_pd(), radius = t;
        for (__mmask8 pending = alive; pending;) {
            const __m512d tt = uniform(pending), rr = _mm512_add_pd(r0, _mm512_mul_pd(_mm512_sub_pd(r1, r0), tt));
            t = _mm512_mask_mov_pd(t, pending, tt), radius = _mm512_mask_mov_pd(radius, pending, rr);
            // uniform >= (r / r_max)^2, the scalar sampler's test operation for operation.
            const __m512d v = uniform(pending), share = _mm512_div_pd(rr, r_max);
            pending &= _mm512_cmp_pd_mask(v, _mm512_mul_pd(share, share), _CMP_GE_OQ);
        }
        __m512d a = _mm512_setzero_pd(), b = a;
        const __m512d two = _mm512_set1_pd(2.0);
        for (__mmask8 pending = alive; pending;) {
            const __m512d aa = _mm512_sub_pd(_mm512_mul_pd(two, uniform(pending)), one);
            const __m512d bb = _mm512_sub_pd(_mm512_mul_pd(two, uniform(pending)), one);
            a = _mm512_mask_mov_pd(a, pending, aa), b = _mm512_mask_mov_pd(b, pending, bb);
            pending &= _mm512_cmp_pd_mask(_mm512_add_pd(_mm512_mul_pd(aa, aa), _mm512_mul_pd(bb, bb)), one, _CMP_GE_OQ);
        }
        a = _mm512_mul_pd(a, radius), b = _mm512_mul_pd(b, radius);
        const __m512d bottom = per_stem(c0.bottom, c1.bottom), top = per_stem(c0.top, c1.top);
        const __m512d along = _mm512_add_pd(bottom, _mm512_mul_pd(_mm512_sub_pd(top, bottom), t));
        // (along, a, b) with `along` on the cone's axis: (along, a, b), (a, along, b) or (a, b, along).
        const auto on = [&](int axis) { return __mmask8((c0.axis == axis ? ~second : 0) | (c1.axis == axis ? second : 0)); };
        const __mmask8 on_x = on(0), on_y = on(1), on_z = on(2);
        const points sample{_mm512_mask_blend_pd(on_x, a, along), _mm512_mask_blend_pd(on_x, _mm512_mask_blend_pd(on_y, b, along), a),
                            _mm512_mask_blend_pd(on_z, b, along)};
        return apply_chain(stem_tables, stem_shape, _mm512_maskz_mov_epi64(second, _mm512_set1_epi64(1)), sample);
    };
    // A line's half (generator end - start) / 2, and the rescaling of a transformed line about its
    // midpoint to the generator's length (the scalar loop's keep_length).
    const vec3d half = (def.generator.end - def.generator.start) * 0.5;
    const double half_length = krs::length(half);
    const __m512d half_x = _mm512_set1_pd(half.x), half_y = _mm512_set1_pd(half.y), half_z = _mm512_set1_pd(half.z);
    const auto keep_length = [&](points& a, points& b) {
        const __m512d point_five = _mm512_set1_pd(0.5);
        const points mid{_mm512_mul_pd(_mm512_add_pd(a.x, b.x), point_five), _mm512_mul_pd(_mm512_add_pd(a.y, b.y), point_five),
                         _mm512_mul_pd(_mm512_add_pd(a.z, b.z), point_five)};
        const points dir{_mm512_sub_pd(b.x, a.x), _mm512_sub_pd(b.y, a.y), _mm512_sub_pd(b.z, a.z)};
        const __m512d len = _mm512_sqrt_pd(
            _mm512_add_pd(_mm512_add_pd(_mm512_mul_pd(dir.x, dir.x), _mm512_mul_pd(dir.y, dir.y)), _mm512_mul_pd(dir.z, dir.z)));
        const __mmask8 positive = _mm512_cmp_pd_mask(len, zero, _CMP_GT_OQ);
        const __m512d scale = _mm512_div_pd(_mm512_set1_pd(half_length), len);
        const points h{_mm512_mask_mov_pd(half_x, positive, _mm512_mul_pd(dir.x, scale)), _mm512_mask_mov_pd(half_y, positive, _mm512_mul_pd(dir.y, scale)),
                       _mm512_mask_mov_pd(half_z, positive, _mm512_mul_pd(dir.z, scale))};
        a = {_mm512_sub_pd(mid.x, h.x), _mm512_sub_pd(mid.y, h.y), _mm512_sub_pd(mid.z, h.z)};
        b = {_mm512_add_pd(mid.x, h.x), _mm512_add_pd(mid.y, h.y), _mm512_add_pd(mid.z, h.z)};
    };
    for (std::uint64_t i = 0; i < cycles[0]; ++i) {
        // The lanes that still have cycle i (cycles[] does not increase with the lane).
        __mmask8 alive = 0;
        for (int j = 0; j < cycle_lanes; ++j) alive |= __mmask8((cycles[j] > i ? 1u : 0u) << j);
        const points stem = sample_stems(alive);
        // The generator at depth 0: the stem point, or the segment stem -/+ half.
        points inner = stem, inner_b = stem;
        if constexpr (Line) {
            inner = {_mm512_sub_pd(stem.x, half_x), _mm512_sub_pd(stem.y, half_y), _mm512_sub_pd(stem.z, half_z)};
            inner_b = {_mm512_add_pd(stem.x, half_x), _mm512_add_pd(stem.y, half_y), _mm512_add_pd(stem.z, half_z)};
        }
        counts.generators += unsigned(std::popcount(unsigned(alive)));
        end = room(end, row_room);
        if constexpr (Line) record_line(inner, inner_b, alive, 0, _mm512_setzero_si512());
        else record(inner, alive, 0, _mm512_setzero_si512());

        // w_{s-1} and w_{s-2}: the selections one and two rows back.
        __m512i previous = _mm512_setzero_si512(), before = _mm512_setzero_si512();
        __m512i cycle_end = _mm512_set1_epi64(depth - 1);
        for (int s = 1; s < depth; ++s) {
            // select(u): column u n, then the column's own entry or its alias.
            const __m512d x = _mm512_mul_pd(uniform(alive), columns);
            const __m512i column = _mm512_min_epi64(_mm512_cvttpd_epi64(x), last_column);
            const __mmask8 own = _mm512_cmp_pd_mask(_mm512_sub_pd(x, _mm512_cvtepi64_pd(column)), lookup(keep, column), _CMP_LT_OQ);
            const __m512i w = _mm512_mask_blend_epi64(own, lookup_int(alias, column), column);
            cycle_end = _mm512_min_epi64(cycle_end, _mm512_add_epi64(lookup_int(last_level, w), _mm512_set1_epi64(s - 1)));
            alive &= _mm512_cmp_epi64_mask(_mm512_set1_epi64(s), cycle_end, _MM_CMPINT_LE);
            if (!alive) break;
            if (s >= 3) inner = apply(2, before, inner);
            points a = inner;
            if (s >= 2) a = apply(1, previous, a);
            a = apply(0, w, a);
            counts.generators += unsigned(std::popcount(unsigned(alive)));
            const __mmask8 recorded = alive & _mm512_cmp_epi64_mask(_mm512_set1_epi64(s), lookup_int(dummy_from, w), _MM_CMPINT_LT);
            const __m512i part = _mm512_add_epi64(w, _mm512_set1_epi64(1));
            end = room(end, row_room);
            if constexpr (Line) {
                if (s >= 3) inner_b = apply(2, before, inner_b);
                points b = inner_b;
                if (s >= 2) b = apply(1, previous, b);
                b = apply(0, w, b);
                keep_length(a, b);
                record_line(a, b, recorded, s, part);
            } else {
                record(a, recorded, s, part);
            }
            before = previous, previous = w;
        }
    }
    while (pending.walking) step_walk(pending, end);
    _mm512_storeu_si512(state, random);
    return end;
}

#else

inline constexpr bool lanes_built = false;

template <transform_pipeline P>
bool lanes_fit(const drawn_ifs<P>&)
{
    return false;
}

struct lane_tables {
    template <transform_pipeline P>
    static std::optional<lane_tables> of(const drawn_ifs<P>&)
    {
        return std::nullopt;
    }
};

template <bool Line, bool OverlapWalks = true, transform_pipeline P, class Room>
hit* generate_in_lanes(const drawn_ifs<P>&, const lane_tables&, std::uint64_t (&)[cycle_lanes], const std::uint64_t (&)[cycle_lanes], hit* end,
                       lane_counts&, std::size_t, Room&&)
{
    return end; // never called: there are no lane tables
}

#endif

} // namespace hypertree::detail

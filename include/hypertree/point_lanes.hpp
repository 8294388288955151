#pragma once
// The generator's loop for point generators, eight cycles at a time in the lanes of AVX-512
// registers.
//
// A chunk of the generator (generate.hpp) is cut into `cycle_lanes` = 8 lanes of cycles, each
// drawing from its own random stream, in every build: the lanes are what the tree is defined by,
// and how they run is the build's choice. Without AVX-512 they run one after the other through
// the scalar loop. With it, and for the common case this file handles (point generators, no noise
// perturbation, no shears, at most 16 transformations), all eight run in step: lane j holds
// cycle i of stream j, for i = 0, 1, ... The scalar loop's per-generator work (a draw, Walker's
// alias selection, three affine maps, the voxel and its rules) is a chain of dependent steps on
// scalars; in lanes it is the same steps on eight generators, and the per-lane choice of map
// becomes a permute: for each level and coefficient a pair of registers holds that coefficient
// of every transformation, and vpermt2pd picks each lane's. Where the scalar loop branches
// (a lane's cycle ends by the last-level rule), a mask stops the lane's draws and hits.
//
// Every step is the scalar loop's arithmetic in the same order (multiplies and adds, with no
// fused multiply-add written here), so where the compiler does not contract the two paths give
// the same hits, only interleaved differently (tested with contraction off); stem samples, one per
// cycle, come from the scalar sampler in each lane's stream.

#include "hypertree/ifs.hpp"
#include "hypertree/voxel.hpp"

#include <bit>
#include <cstdint>

#if defined(__AVX512F__) && defined(__AVX512DQ__)
#include <immintrin.h>
#define HYPERTREE_POINT_LANES 1
#else
#define HYPERTREE_POINT_LANES 0
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

#if HYPERTREE_POINT_LANES

inline constexpr bool point_lanes_built = true;

// Whether the lanes loop handles this tree (else the scalar loop runs each lane).
template <transform_pipeline P>
bool point_lanes_fit(const drawn_ifs<P>& tree)
{
    const ifs<P>& def = tree.definition();
    return def.generator.is_point() && !def.perturb.enabled() && !tree.affine_table().empty() && tree.transform_count() <= 16;
}

// Runs lane j's `cycles[j]` cycles from random state `state[j]` (updated), with cycles[j] in
// non-increasing order of j, writing each recorded hit inside the hypervolume at `end` and
// returning the new end. The buffer needs room for cycle_lanes hits more than it keeps: each
// row stores a whole register of hits and advances by those that count.
template <transform_pipeline P>
hit* generate_point_lanes(const drawn_ifs<P>& tree, std::uint64_t (&state)[cycle_lanes], const std::uint64_t (&cycles)[cycle_lanes],
                          hit* end, lane_counts& counts)
{
    const ifs<P>& def = tree.definition();
    const int depth = def.tree_depth;
    const std::size_t n = tree.transform_count();
    const std::span<const affine_map> maps = tree.affine_table();

    // Tables of 16 entries (two registers) per looked-up quantity, padded with entry 0.
    alignas(64) double coefficient[distinct_levels][12][16];
    alignas(64) double keep[16];
    alignas(64) std::int64_t alias[16], last_level[16], dummy_from[16];
    for (std::size_t j = 0; j < 16; ++j) {
        const std::size_t t = j < n ? j : 0;
        for (int l = 0; l < distinct_levels; ++l) {
            const affine_map& m = maps[t * distinct_levels + std::size_t(l)];
            for (int k = 0; k < 9; ++k) coefficient[l][k][j] = m.m[std::size_t(k)];
            coefficient[l][9][j] = m.t.x, coefficient[l][10][j] = m.t.y, coefficient[l][11][j] = m.t.z;
        }
        keep[j] = tree.alias_keep()[t];
        alias[j] = std::int64_t(tree.alias_of()[t]);
        last_level[j] = tree.last_levels()[t];
        dummy_from[j] = tree.dummies_from()[t];
    }
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
    const auto apply = [&](int level, __m512i w, const points& p) {
        const auto c = [&](int k) { return lookup(coefficient[level][k], w); };
        const auto row = [&](int r, int t) {
            return _mm512_add_pd(_mm512_add_pd(_mm512_add_pd(_mm512_mul_pd(c(3 * r), p.x), _mm512_mul_pd(c(3 * r + 1), p.y)),
                                               _mm512_mul_pd(c(3 * r + 2), p.z)),
                                 c(t));
        };
        return points{row(0, 9), row(1, 10), row(2, 11)};
    };

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
    const __m512d zero = _mm512_setzero_pd(), one = _mm512_set1_pd(1.0);
    const __m256i stride_y = _mm256_set1_epi32(grid.x), stride_z = _mm256_set1_epi32(int(std::uint32_t(grid.x) * std::uint32_t(grid.y)));
    // Records the lanes of `mask` whose point is inside; counts those outside as escaped.
    const auto record = [&](const points& p, __mmask8 mask, int level, __m512i part) {
        const __m512d fx = _mm512_mul_pd(_mm512_sub_pd(p.x, ox), px), fy = _mm512_mul_pd(_mm512_sub_pd(p.y, oy), py),
                      fz = _mm512_mul_pd(_mm512_sub_pd(p.z, oz), pz);
        const __mmask8 in = _mm512_cmp_pd_mask(fx, zero, _CMP_GE_OQ) & _mm512_cmp_pd_mask(fy, zero, _CMP_GE_OQ) &
                            _mm512_cmp_pd_mask(fz, zero, _CMP_GE_OQ) & _mm512_cmp_pd_mask(fx, nx, _CMP_LE_OQ) &
                            _mm512_cmp_pd_mask(fy, ny, _CMP_LE_OQ) & _mm512_cmp_pd_mask(fz, nz, _CMP_LE_OQ);
        const auto cell = [&](__m512d f, __m512d size) {
            return _mm512_cvttpd_epi32(_mm512_min_pd(_mm512_max_pd(f, zero), _mm512_sub_pd(size, one)));
        };
        const __m256i x = cell(fx, nx), y = cell(fy, ny), z = cell(fz, nz);
        const __m256i index = _mm256_add_epi32(x, _mm256_add_epi32(_mm256_mullo_epi32(y, stride_y), _mm256_mullo_epi32(z, stride_z)));
        // A hit as its 8 bytes: voxel, level, part (then padding).
        const __m512i packed = _mm512_or_si512(_mm512_cvtepu32_epi64(index),
                                               _mm512_or_si512(_mm512_set1_epi64(std::int64_t(level) << 32), _mm512_slli_epi64(part, 40)));
        const __mmask8 kept = mask & in;
        _mm512_storeu_si512(end, _mm512_maskz_compress_epi64(kept, packed));
        end += std::popcount(unsigned(kept));
        counts.recorded += unsigned(std::popcount(unsigned(mask)));
        counts.escaped += unsigned(std::popcount(unsigned(mask & ~in)));
        counts.per_depth[level] += unsigned(std::popcount(unsigned(mask)));
    };

    const __m512i last_column = _mm512_set1_epi64(std::int64_t(n) - 1);
    const __m512d columns = _mm512_set1_pd(double(n));
    alignas(64) double stem_x[cycle_lanes], stem_y[cycle_lanes], stem_z[cycle_lanes];
    for (std::uint64_t i = 0; i < cycles[0]; ++i) {
        // The lanes that still have cycle i (cycles[] does not increase with the lane).
        __mmask8 alive = 0;
        for (int j = 0; j < cycle_lanes; ++j) alive |= __mmask8((cycles[j] > i ? 1u : 0u) << j);
        // Stems from the scalar sampler, in each lane's own stream.
        _mm512_storeu_si512(state, random);
        for (int j = 0; j < cycle_lanes; ++j) {
            if (!((alive >> j) & 1)) {
                stem_x[j] = stem_y[j] = stem_z[j] = 0;
                continue;
            }
            random_stream lane(state[j]);
            const vec3d s = tree.sample_stem(lane);
            state[j] = lane.state();
            stem_x[j] = s.x, stem_y[j] = s.y, stem_z[j] = s.z;
        }
        random = _mm512_loadu_si512(state);
        points inner{_mm512_load_pd(stem_x), _mm512_load_pd(stem_y), _mm512_load_pd(stem_z)};
        counts.generators += unsigned(std::popcount(unsigned(alive)));
        record(inner, alive, 0, _mm512_setzero_si512());

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
            record(a, recorded, s, _mm512_add_epi64(w, _mm512_set1_epi64(1)));
            before = previous, previous = w;
        }
    }
    _mm512_storeu_si512(state, random);
    return end;
}

#else

inline constexpr bool point_lanes_built = false;

template <transform_pipeline P>
bool point_lanes_fit(const drawn_ifs<P>&)
{
    return false;
}

template <transform_pipeline P>
hit* generate_point_lanes(const drawn_ifs<P>&, std::uint64_t (&)[cycle_lanes], const std::uint64_t (&)[cycle_lanes], hit* end, lane_counts&)
{
    return end; // never called: point_lanes_fit is false
}

#endif

} // namespace hypertree::detail

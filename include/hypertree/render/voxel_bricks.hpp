#pragma once
// The raymarcher's copy of a tree: its non-empty voxels regrouped into bricks of 4^3, the layout
// rays read best.
//
// Primary and shadow rays visit voxels in lines across the grid. In a store's own layout a line
// across z rows touches a new cache line at every step (54 MB of dense array at resolution 300,
// and a bisection per step for an index list), and the shadow rays, most of a render's work
// (paper 8.1), repeat that for every shaded voxel. Here each 4^3 brick that holds a non-empty
// voxel keeps its 64 densities in one cache line (and its 64 levels in another), so a ray reads
// one line per brick it crosses. Tree A at resolution 300 has 25 000 bricks: 3.2 MB of densities
// and levels, 6.4 MB of slots (below) and 1.7 MB of directory, against 54 MB of dense store.
//
// Finding a voxel's place is one table read, the same in scalar and SIMD code (a gather): each
// 4^3 brick of the grid has its rank (its place among the stored bricks), 4 bytes per 64 voxels
// of the grid (62 MB at 1000^3, against 2 GB for a dense store). A voxel's place is
// rank * 64 + its offset in the brick (x, y, z low bits).
//
// Empty space at every scale, in the same read. An empty brick's entry is not just "empty" but
// -(e + 1), e the level of the largest empty cube around it among the aligned cubes of 4 << e
// voxels (4^3, 8^3, 16^3, ... up to the whole grid; a cube's part past the grid counts as
// empty): an octree of empty space flattened into its leaves, as OpenVDB's tree and NanoVDB's
// HDDA skip empty nodes of every level. The place of a voxel in an empty brick is then
// -64 (e + 1) + offset, so e = (-1 - place) >> 6 and a ray crossing a forest's clearing jumps to
// the exit of the largest empty cube in one step. (Two levels kept apart, a brick table and a
// 16^3 block table read side by side, was the walk before: its second read cost a gather per
// sample, and the blocks stopped at 16^3. It is kept as the reference walk, `place_by_blocks`.)
// The levels are computed after the voxels are in: a pass up over the brick table, one per level
// above over a byte table 8 times smaller than the last, and the same down, writing the codes
// (tree B at resolution 300: 0.45 ms, against 0.8 ms for the rest of the copy).
//
// A voxel that needs more than a density (the shading memo: shade_memo.hpp) gets a dense number
// among the non-empty voxels, its slot, kept per place (a gather for packets, where a popcount of
// the brick's voxel mask would need a per-lane shift that xsimd 8.1 lacks).
//
// The copy is made once per marcher, from any store's for_each, and holds exactly the store's
// voxels (tested against at() for every voxel of the grid).

#include "hypertree/store/store.hpp"
#include "krs/core/lanes.hpp"
#include "krs/core/validate.hpp"

#include <array>
#include <bit>
#include <cstddef>
#include <cstdint>
#include <new>
#include <span>
#include <string>
#include <vector>

namespace hypertree {

namespace detail {
// Allocates on 64-byte boundaries, so that a brick's 64 densities are exactly one cache line.
template <class T>
struct cache_line_allocator {
    using value_type = T;
    static constexpr std::align_val_t alignment{64};
    cache_line_allocator() = default;
    template <class U>
    cache_line_allocator(const cache_line_allocator<U>&) {}
    T* allocate(std::size_t n) { return static_cast<T*>(::operator new(n * sizeof(T), alignment)); }
    void deallocate(T* p, std::size_t) { ::operator delete(p, alignment); }
    friend bool operator==(const cache_line_allocator&, const cache_line_allocator&) { return true; }
};
} // namespace detail

class voxel_bricks {
public:
    static constexpr int fine_shift = 2;   // 4^3 voxels: densities in one 64-byte line
    static constexpr int coarse_shift = 4; // 16^3 voxels: a block of the reference walk (place_by_blocks)
    static constexpr std::size_t brick_voxels = std::size_t(1) << (3 * fine_shift);
    static constexpr std::int32_t empty_brick = -1;
    // Places must stay within int32 (the lanes' gathers): rank * 64 + 63 < 2^31.
    static constexpr std::size_t max_bricks = std::size_t(1) << 25;

    voxel_bricks() = default;

    template <voxel_store S>
    explicit voxel_bricks(const S& store)
    {
        const hypervolume& v = store.volume();
        grid_ = {v.grid().x, v.grid().y, v.grid().z};
        // (In size_t: a side near INT_MAX must not overflow.)
        const std::array<std::size_t, 3> grid{std::size_t(v.grid().x), std::size_t(v.grid().y), std::size_t(v.grid().z)};
        for (std::size_t a = 0; a < 3; ++a) {
            brick_count_[a] = (grid[a] + 3) >> fine_shift;
            block_count_[a] = (grid[a] + 15) >> coarse_shift;
        }
        const std::size_t grid_bricks = brick_count_[0] * brick_count_[1] * brick_count_[2];
        if (grid_bricks >= (std::size_t(1) << 31))
            throw krs::invalid_parameter("voxel_bricks.volume", "must have fewer than 2^31 bricks of 4^3 voxels", std::to_string(grid_bricks));
        // One pass over the store (a dense store's pass reads the whole grid); a brick is added
        // when its first voxel comes.
        brick_rank_.assign(grid_bricks, empty_brick);
        detail::coordinate_walker coordinates(v); // stores visit in increasing index order
        // The visit is kept small, so the compiler inlines it into the store's loop: a new brick,
        // the rare case, is added out of line (inline, it made the visit a call per voxel, which
        // was most of the copy's time: A at 100 from a dense store 0.52 -> 0.43 ms).
        store.for_each([&](voxel_index i, const voxel& value) {
            if (value.density == 0) return;
            const std::array<int, 3> c = coordinates(i);
            std::int32_t& rank = brick_rank_[brick_of(c[0], c[1], c[2])];
            if (rank == empty_brick) rank = add_brick(c);
            const std::size_t offset = std::size_t((c[0] & 3) | (c[1] & 3) << 2 | (c[2] & 3) << 4);
            const std::size_t place = std::size_t(rank) * brick_voxels + offset;
            density_[place] = value.density;
            level_[place] = value.level;
            mask_[std::size_t(rank)] |= std::uint64_t(1) << offset;
        });
        const std::size_t bricks = mask_.size();
        slot_.assign(bricks * brick_voxels, 0);
        // Slots fit int32: fewer than 2^25 bricks of 64 voxels.
        std::size_t slots = 0;
        for (std::size_t b = 0; b < bricks; ++b)
            for (std::uint64_t m = mask_[b]; m != 0; m &= m - 1) slot_[b * brick_voxels + std::size_t(std::countr_zero(m))] = std::int32_t(slots++);
        voxel_count_ = slots;
        code_empty_levels();
    }

    // What the hot loops read, copied by value into them (a local copy whose address is never
    // taken stays in registers, where loads through the marcher would be reloaded per sample).
    struct view {
        const std::int32_t* brick_rank; // per brick: its rank, or -(e + 1) (empty, in an empty cube of level e)
        const std::int32_t* block_code; // per 16^3 block: 0 when it holds a voxel, else -64 (place_by_blocks only)
        std::int32_t bricks_x, bricks_xy, blocks_x, blocks_xy;

        // The voxel's place in the bricks (rank * 64 + offset), or when its brick is empty
        // -64 (e + 1) + offset, e the level of the largest empty aligned cube around it (of 4 << e
        // voxels): empty_level() gives e. I is std::int32_t or a batch of them (one lane per
        // voxel). Precondition: every lane's cell lies in the grid.
        template <class I>
        I place(const I& x, const I& y, const I& z) const
        {
            const I brick = (x >> fine_shift) + (y >> fine_shift) * bricks_x + (z >> fine_shift) * bricks_xy;
            // (An empty brick's -(e + 1) has its low 6 bits 0 after the shift: the | adds.)
            return (krs::gather(brick_rank, brick) << 6) | (x & 3) | ((y & 3) << 2) | ((z & 3) << 4);
        }
        // The level e of a place < 0 (the empty cube around it has 4 << e voxels a side).
        template <class I>
        static I empty_level(const I& place)
        {
            return (I(-1) - place) >> 6;
        }
        // The reference walk's place: in [-64, -1] when the brick is empty, below -64 when its
        // 16^3 block is, from two reads (the brick's and the block's).
        template <class I>
        I place_by_blocks(const I& x, const I& y, const I& z) const
        {
            const I brick = (x >> fine_shift) + (y >> fine_shift) * bricks_x + (z >> fine_shift) * bricks_xy;
            const I block = (x >> coarse_shift) + (y >> coarse_shift) * blocks_x + (z >> coarse_shift) * blocks_xy;
            const I rank = krs::index_max(krs::gather(brick_rank, brick), I(empty_brick)), code = krs::gather(block_code, block);
            // rank >> 31 is all ones for an empty brick (-1), which then takes its block's code.
            return ((rank << 6) | (x & 3) | ((y & 3) << 2) | ((z & 3) << 4)) + ((rank >> 31) & code);
        }
    };
    view view_of() const
    {
        return {brick_rank_.data(), block_code_.data(), std::int32_t(brick_count_[0]), std::int32_t(brick_count_[0] * brick_count_[1]),
                std::int32_t(block_count_[0]), std::int32_t(block_count_[0] * block_count_[1])};
    }

    // The voxel at a place >= 0 (density 0 for an empty voxel of a non-empty brick).
    voxel at_place(std::size_t place) const { return {density_[place], level_[place]}; }
    // The voxel at a cell of the grid (density 0 when empty).
    voxel at(int x, int y, int z) const
    {
        const std::int32_t place = view_of().place(x, y, z);
        return place < 0 ? voxel{} : at_place(std::size_t(place));
    }
    // The non-empty voxel's number in [0, voxel_count()), numbered in place order; 0 for an
    // empty voxel of a non-empty brick.
    std::uint32_t slot(std::size_t place) const { return std::uint32_t(slot_[place]); }
    // The slots of all places (for gathers).
    const std::int32_t* slots() const { return slot_.data(); }
    // A brick's non-empty voxels (bit i = offset i), and its first cell.
    std::uint64_t mask(std::size_t brick) const { return mask_[brick]; }
    const std::array<int, 3>& origin(std::size_t brick) const { return brick_origin_[brick]; }
    // The cell at an offset in a brick.
    static std::array<int, 3> cell_at(const std::array<int, 3>& origin, std::size_t offset)
    {
        return {origin[0] + int(offset & 3), origin[1] + int((offset >> 2) & 3), origin[2] + int((offset >> 4) & 3)};
    }

    // The arrays as they lie in memory, for a copy that must read as the marcher reads
    // (pack_bricks, glsl.hpp): per 4^3 brick of the grid its rank or -(e + 1), x fastest; per
    // 16^3 block its code (the reference walk's); per place (rank * 64 + offset) the densities
    // and the levels.
    std::span<const std::int32_t> brick_ranks() const { return brick_rank_; }
    std::span<const std::int32_t> block_codes() const { return block_code_; }
    std::span<const std::uint8_t> densities() const { return {density_.data(), density_.size()}; }
    std::span<const std::uint8_t> levels() const { return {level_.data(), level_.size()}; }
    // The levels of empty cubes: the largest e any brick has (0 when no brick is empty).
    int empty_levels() const { return empty_levels_; }
    // The store's grid in voxels, and bricks and blocks per axis of it (the last ones may reach past it).
    const std::array<int, 3>& grid() const { return grid_; }
    const std::array<std::size_t, 3>& grid_bricks() const { return brick_count_; }
    const std::array<std::size_t, 3>& grid_blocks() const { return block_count_; }

    std::size_t voxel_count() const { return voxel_count_; }
    std::size_t brick_count() const { return mask_.size(); }
    std::size_t memory_bytes() const
    {
        return brick_rank_.capacity() * 4 + block_code_.capacity() * 4 + density_.capacity() + level_.capacity() +
               mask_.capacity() * 8 + slot_.capacity() * 4 + brick_origin_.capacity() * sizeof(std::array<int, 3>);
    }

private:
    // Codes each empty brick with the level of the largest empty aligned cube around it, and each
    // 16^3 block (the reference walk's) 0 or -64. Occupancy per level first, from the bricks up:
    // the cube of level e at (i, j, k) (in cubes of 2^e bricks) holds a voxel when one of its 8
    // halves of level e - 1 does; up to the level of one cube over the whole grid. Then from the
    // top down, an empty cube whose parent is empty takes the parent's level, else its own.
    void code_empty_levels()
    {
        using dims = std::array<std::size_t, 3>;
        const auto at = [](const dims& n, std::size_t x, std::size_t y, std::size_t z) { return x + n[0] * (y + n[1] * z); };
        // Row by row, x fastest, pairs of cubes ORed into their parent, the last level written
        // into the rank table without a branch: tree B at resolution 300 (75^3 bricks) copies in
        // 1.2 ms from an index list against 0.8 ms without the levels (with an index computed per
        // cube and a branch per brick, the levels had cost 1.5 ms more).
        std::vector<dims> size{brick_count_};
        std::vector<std::vector<std::uint8_t>> occupied(1); // per level above the bricks (level 0 is the rank table)
        while (size.back()[0] > 1 || size.back()[1] > 1 || size.back()[2] > 1) {
            const dims n = size.back();
            const dims m{(n[0] + 1) / 2, (n[1] + 1) / 2, (n[2] + 1) / 2};
            std::vector<std::uint8_t> up(m[0] * m[1] * m[2], 0);
            for (std::size_t z = 0; z < n[2]; ++z)
                for (std::size_t y = 0; y < n[1]; ++y) {
                    std::uint8_t* to = up.data() + at(m, 0, y / 2, z / 2);
                    // Pairs along x, then the odd last one (a pair of ranks holds a brick unless
                    // both are negative: their & is).
                    const std::size_t pairs = n[0] / 2;
                    if (size.size() == 1) {
                        const std::int32_t* from = brick_rank_.data() + at(n, 0, y, z);
                        for (std::size_t x = 0; x < pairs; ++x) to[x] |= std::uint8_t((from[2 * x] & from[2 * x + 1]) >= 0);
                        if (n[0] % 2) to[pairs] |= std::uint8_t(from[n[0] - 1] >= 0);
                    } else {
                        const std::uint8_t* from = occupied.back().data() + at(n, 0, y, z);
                        for (std::size_t x = 0; x < pairs; ++x) to[x] |= std::uint8_t(from[2 * x] | from[2 * x + 1]);
                        if (n[0] % 2) to[pairs] |= from[n[0] - 1];
                    }
                }
            size.push_back(m);
            occupied.push_back(std::move(up));
        }
        const std::size_t top = size.size() - 1;
        const bool top_occupied = top == 0 ? brick_rank_[0] >= 0 : occupied[top][0] != 0;
        // A 16^3 block (4^3 bricks, the cubes of level 2) is empty when its cube is.
        block_code_.assign(block_count_[0] * block_count_[1] * block_count_[2], 0);
        if (top >= 2) {
            for (std::size_t b = 0; b < block_code_.size(); ++b) block_code_[b] = occupied[2][b] ? 0 : -std::int32_t(brick_voxels);
        } else {
            // A grid of at most 2 bricks a side: its one block is empty when every brick is.
            block_code_[0] = top_occupied ? 0 : -std::int32_t(brick_voxels);
        }
        // From the top down, level[c]: the level of the largest empty cube holding cube c, or -1
        // when c holds a voxel; at the bricks, an empty one's rank becomes -(level + 1).
        std::vector<std::int8_t> level(1, top_occupied ? -1 : std::int8_t(top)), finer;
        empty_levels_ = top_occupied ? 0 : int(top);
        for (std::size_t e = top; e-- > 0;) {
            const dims &n = size[e], &m = size[e + 1];
            if (e > 0) finer.assign(n[0] * n[1] * n[2], -1);
            for (std::size_t z = 0; z < n[2]; ++z)
                for (std::size_t y = 0; y < n[1]; ++y) {
                    const std::int8_t* parent = level.data() + at(m, 0, y / 2, z / 2);
                    if (e > 0) {
                        const std::uint8_t* full = occupied[e].data() + at(n, 0, y, z);
                        std::int8_t* out = finer.data() + at(n, 0, y, z);
                        for (std::size_t x = 0; x < n[0]; ++x)
                            if (!full[x]) out[x] = parent[x / 2] >= 0 ? parent[x / 2] : std::int8_t(e);
                    } else {
                        std::int32_t* rank = brick_rank_.data() + at(n, 0, y, z);
                        for (std::size_t x = 0; x < n[0]; ++x) {
                            const std::int32_t l = std::max<std::int32_t>(parent[x / 2], 0);
                            rank[x] = rank[x] >= 0 ? rank[x] : -(l + 1);
                        }
                    }
                }
            if (e > 0) std::swap(level, finer);
            if (e == 1) // the bricks' levels are these or 0
                for (const std::int8_t l : level) empty_levels_ = std::max(empty_levels_, int(l));
        }
    }

    // Adds the empty brick holding cell c and returns its rank.
    [[gnu::noinline]] std::int32_t add_brick(const std::array<int, 3>& c)
    {
        if (mask_.size() == max_bricks)
            throw krs::invalid_parameter("voxel_bricks.store", "must have at most 2^25 non-empty bricks of 4^3 voxels");
        mask_.push_back(0);
        brick_origin_.push_back({c[0] & ~3, c[1] & ~3, c[2] & ~3});
        density_.resize(density_.size() + brick_voxels, 0);
        level_.resize(level_.size() + brick_voxels, 0);
        return std::int32_t(mask_.size() - 1);
    }

    std::size_t brick_of(int x, int y, int z) const
    {
        return std::size_t(x >> fine_shift) + brick_count_[0] * (std::size_t(y >> fine_shift) + brick_count_[1] * std::size_t(z >> fine_shift));
    }

    std::array<int, 3> grid_{};
    std::array<std::size_t, 3> brick_count_{}, block_count_{};
    std::vector<std::int32_t> brick_rank_; // per 4^3 brick of the grid: its rank, or -(e + 1)
    std::vector<std::int32_t> block_code_; // per 16^3 block: 0 when it holds a voxel, else -64 (the reference walk)
    std::vector<std::uint8_t, detail::cache_line_allocator<std::uint8_t>> density_, level_; // 64 per brick, by rank
    std::vector<std::uint64_t> mask_;              // per brick: its non-empty voxels
    std::vector<std::int32_t> slot_;               // 64 per brick: each voxel's slot
    std::vector<std::array<int, 3>> brick_origin_; // per brick: its first cell
    std::size_t voxel_count_ = 0;
    int empty_levels_ = 0;
};

} // namespace hypertree

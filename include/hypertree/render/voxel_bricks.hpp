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
// 4^3 brick of the grid has its rank (its place among the stored bricks) or -1 when it is empty,
// 4 bytes per 64 voxels of the grid (62 MB at 1000^3, against 2 GB for a dense store). A voxel's
// place is rank * 64 + its offset in the brick (x, y, z low bits): negative when its brick is
// empty. A second read, independent of the first, tells whether the whole 16^3 block around the
// brick is empty, and then the place is below -64: what a ray needs to skip the block. (Two
// levels, a block naming a table of its bricks' ranks, took less memory, but the second read
// waited for the first at every sample: tree A at resolution 100 rendered 10% slower.)
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
    static constexpr int coarse_shift = 4; // 16^3 voxels: a block, skipped whole when empty
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
        block_code_.assign(block_count_[0] * block_count_[1] * block_count_[2], -std::int32_t(brick_voxels));
        detail::coordinate_walker coordinates(v); // stores visit in increasing index order
        // The visit is kept small, so the compiler inlines it into the store's loop: a new brick,
        // the rare case, is added out of line (inline, it made the visit a call per voxel, which
        // was most of the copy's time: A at 100 from a dense store 0.52 -> 0.43 ms).
        store.for_each([&](voxel_index i, const voxel& value) {
            if (value.density == 0) return;
            const std::array<int, 3> c = coordinates(i);
            block_code_[block_of(c[0], c[1], c[2])] = 0;
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
    }

    // What the hot loops read, copied by value into them (a local copy whose address is never
    // taken stays in registers, where loads through the marcher would be reloaded per sample).
    struct view {
        const std::int32_t* brick_rank;
        const std::int32_t* block_code; // per block: 0 when it holds a voxel, else -64
        std::int32_t bricks_x, bricks_xy, blocks_x, blocks_xy;

        // The voxel's place in the bricks (rank * 64 + offset); in [-64, -1] when its brick is
        // empty, below -64 when its block is. I is std::int32_t or a batch of them (one lane per
        // voxel). Precondition: every lane's cell lies in the grid.
        template <class I>
        I place(const I& x, const I& y, const I& z) const
        {
            const I brick = (x >> fine_shift) + (y >> fine_shift) * bricks_x + (z >> fine_shift) * bricks_xy;
            const I block = (x >> coarse_shift) + (y >> coarse_shift) * blocks_x + (z >> coarse_shift) * blocks_xy;
            const I rank = krs::gather(brick_rank, brick), code = krs::gather(block_code, block);
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
    // (pack_bricks, glsl.hpp): per 4^3 brick of the grid its rank or -1, x fastest; per 16^3 block
    // its code; per place (rank * 64 + offset) the densities and the levels.
    std::span<const std::int32_t> brick_ranks() const { return brick_rank_; }
    std::span<const std::int32_t> block_codes() const { return block_code_; }
    std::span<const std::uint8_t> densities() const { return {density_.data(), density_.size()}; }
    std::span<const std::uint8_t> levels() const { return {level_.data(), level_.size()}; }
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
    std::size_t block_of(int x, int y, int z) const
    {
        return std::size_t(x >> coarse_shift) +
               block_count_[0] * (std::size_t(y >> coarse_shift) + block_count_[1] * std::size_t(z >> coarse_shift));
    }

    std::array<int, 3> grid_{};
    std::array<std::size_t, 3> brick_count_{}, block_count_{};
    std::vector<std::int32_t> brick_rank_; // per 4^3 brick of the grid: its rank, or -1
    std::vector<std::int32_t> block_code_; // per 16^3 block: 0 when it holds a voxel, else -64
    std::vector<std::uint8_t, detail::cache_line_allocator<std::uint8_t>> density_, level_; // 64 per brick, by rank
    std::vector<std::uint64_t> mask_;              // per brick: its non-empty voxels
    std::vector<std::int32_t> slot_;               // 64 per brick: each voxel's slot
    std::vector<std::array<int, 3>> brick_origin_; // per brick: its first cell
    std::size_t voxel_count_ = 0;
};

} // namespace hypertree

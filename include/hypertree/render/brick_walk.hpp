#pragma once
// The walk of a ray's samples through the bricks of voxel_bricks.hpp (like NanoVDB's HDDA, a
// hierarchical walk that steps over empty nodes): one sample at a time, what the sample finds,
// and how far the ray may jump when it lies in empty space.
//
// A ray's samples sit at t_k = t_0 + (k + 1/2) ds. `probe` maps a sample's position to its cell
// ((p - origin) x cells per unit, truncated: the float operations the GLSL marcher repeats) and
// its place in the bricks, and says whether the sample reads a voxel (`looks`: in the grid and in
// a non-empty brick) and how many samples to advance: 1, or in an empty brick the steps to the
// exit of the largest empty cube around it along the ray (the aligned cube of 4 << e voxels a
// side that the brick's entry names: 4^3 up to the whole grid), less a margin for rounding
// (below) and rounded up. The invariant: the samples a walk looks at are exactly the samples that
// plain stepping (advance 1 always) finds in non-empty bricks, in the same order; only the empty
// ones between are not computed (tested against such stepping, against a fine walk along the ray,
// and against the reference walk below).
//
// The reference walk (`skips::bricks_and_blocks`, the walk before the levels): empty bricks and
// empty 16^3 blocks only, from two reads per sample (voxel_bricks::view::place_by_blocks). It
// looks at the same samples in the same order, in more probes: the benchmarks' "before".
//
// Why the margin. The exit is predicted from this sample's position, but each sample's position
// is computed anew in floats, p = o + d t then (p - origin) x cells per unit, with an error of a
// few ulps of |o| + t + |origin|: 2^-21 of that in all, both samples' errors counted, in steps.
// The landing sample lies up to the grid's diagonal further (a skip over a whole empty grid), so
// the reach counts the grid's far corner too. Close to the tree it is the 1e-3 of the exit's own
// rounding; from a camera 1000 units away it grows to several steps, and skips stop short rather
// than jump over a voxel. `skip_margin` gives it at t from `margin_at_origin(o)`, the part
// computed once per ray.
//
// The slopes are the t it takes to cross one cell along each axis (0 for an axis the ray does not
// move along), so an empty brick costs multiplications. When all lanes of a packet leave a brick
// by the same face along an axis (rays of neighbouring pixels nearly always do, shadow rays toward
// one light always: `faces_of`), the exit is one product per axis instead of two and a choice per
// lane; the same exit either way. One template serves a scalar ray (T = float) and a packet of
// rays, one per lane (T = krs::packet_f); glsl() writes the same walk for the GPU marcher.

#include "hypertree/render/voxel_bricks.hpp"
#include "hypertree/volume.hpp"
#include "krs/core/lanes.hpp"
#include "krs/core/validate.hpp"
#include "krs/glsl/literal.hpp"
#include "krs/glsl/names.hpp"
#include "krs/trace/ray.hpp"

#include <algorithm>
#include <array>
#include <cmath>
#include <string>

namespace hypertree {

class brick_walk {
public:
    // The bricks' geometry, from voxel_bricks: bricks of 4^3 voxels; an empty brick's place says
    // the level e of its empty cube (4 << e voxels a side). The reference walk's blocks are 16^3:
    // its place is in [-64, -1] in an empty brick, below -64 in an empty block.
    static constexpr int brick_side = 1 << voxel_bricks::fine_shift, block_side = 1 << voxel_bricks::coarse_shift;
    static constexpr int brick_voxels = int(voxel_bricks::brick_voxels);
    static_assert(brick_voxels == brick_side * brick_side * brick_side && block_side % brick_side == 0);

    // The directions of a packet's rays, per axis: all toward +, all toward -, all still, or mixed.
    struct exit_faces {
        enum face : int { low, high, none, per_lane };
        face along[3] = {per_lane, per_lane, per_lane};
    };

    // What a sample finds, lane by lane: its cell (0 outside the grid), its place in the bricks
    // (negative in an empty brick: see voxel_bricks::view), whether it reads a voxel, and how
    // many samples to advance.
    template <class T>
    struct probe_result {
        krs::index_lanes<T> place;
        krs::mask_t<T> looks;
        T advance;
        krs::index_lanes<T> cell[3];
    };

    // Which empty space a walk skips: the largest empty cube of every level (the default), or
    // only empty bricks and 16^3 blocks (the reference walk, as before the levels).
    enum class skips { every_level, bricks_and_blocks };

    brick_walk() = default;
    // Samples `step` apart (world units) through the grid of `volume`. A step that is not finite
    // and > 0 is refused (brick_walk.step): it would give an infinite or NaN skip, a walk without end.
    brick_walk(const hypervolume& volume, float step, skips skipping = skips::every_level)
        : origin_(volume.origin()), cells_per_unit_(volume.cells_per_unit()), grid_{volume.grid().x, volume.grid().y, volume.grid().z},
          step_(krs::require_positive("brick_walk.step", step)), rounding_per_step_(float(0x1.0p-21 / double(step_))),
          grid_reach_(float(std::max({std::abs(volume.origin().x), std::abs(volume.origin().y), std::abs(volume.origin().z)}) +
                            krs::length(volume.extent()))),
          skipping_(skipping)
    {
    }

    float step() const { return step_; }
    skips skipping() const { return skipping_; }
    const std::array<int, 3>& grid() const { return grid_; }

    // The slopes of the lanes of a unit direction: 1 / (d * cells per unit) per axis, or 0.
    template <class T>
    void slopes_of(const krs::vec3<T>& d, T (&slope)[3]) const
    {
        using krs::select;
        const T zero(0.0f), dir[3] = {d.x * T(cells_per_unit_.x), d.y * T(cells_per_unit_.y), d.z * T(cells_per_unit_.z)};
        for (int a = 0; a < 3; ++a) slope[a] = select(dir[a] != zero, T(1.0f) / dir[a], zero);
    }
    template <class T>
    static exit_faces faces_of(const T (&slope)[3])
    {
        using krs::all; // (unqualified below: packets take xsimd's, found by argument)
        exit_faces faces;
        const T zero(0.0f);
        for (int a = 0; a < 3; ++a) {
            if (all(slope[a] > zero)) faces.along[a] = exit_faces::high;
            else if (all(slope[a] < zero)) faces.along[a] = exit_faces::low;
            else if (all(slope[a] == zero)) faces.along[a] = exit_faces::none;
        }
        return faces;
    }

    // The sample at p of rays with these slopes and faces; lanes not `running` look at nothing.
    // `margin` is skip_margin at the sample's t.
    // `bricks` is the bricks' view_of(), best copied into a local before the loop (see there).
    template <class T>
    [[gnu::always_inline]] probe_result<T> probe(const voxel_bricks::view& bricks, const krs::vec3<T>& p, const T (&slope)[3],
                                                 const krs::mask_t<T>& running, const T& margin, const exit_faces& faces) const
    {
        using I = krs::index_lanes<T>;
        using krs::select, krs::min, krs::ceil, krs::index_to_float, krs::truncate_to_index;
        const T zero(0.0f), one(1.0f);
        const T f[3] = {(p.x - T(origin_.x)) * T(cells_per_unit_.x), (p.y - T(origin_.y)) * T(cells_per_unit_.y),
                        (p.z - T(origin_.z)) * T(cells_per_unit_.z)};
        auto inside = running;
        for (int a = 0; a < 3; ++a) inside = inside & (f[a] >= zero) & (f[a] < T(float(grid_[std::size_t(a)])));
        // Lanes outside the grid look up cell 0 (their result is not used): a float to int
        // conversion outside int's range would be undefined.
        I c[3];
        for (int a = 0; a < 3; ++a) c[a] = krs::index_min(truncate_to_index(select(inside, f[a], zero)), I(grid_[std::size_t(a)] - 1));
        T exit(3.0e38f);
        I place;
        T found;
        // The exit along each axis of the cube [lo, lo + side) around the sample's cell.
        const auto leave = [&](const T (&lo)[3], const T& side) {
            for (int a = 0; a < 3; ++a) {
                const T hi = lo[a] + side;
                switch (faces.along[a]) {
                case exit_faces::high: exit = min(exit, (hi - f[a]) * slope[a]); break;
                case exit_faces::low: exit = min(exit, (lo[a] - f[a]) * slope[a]); break;
                case exit_faces::none: break;
                default: // lanes going different ways
                    exit = select(slope[a] > zero, min(exit, (hi - f[a]) * slope[a]),
                                  select(slope[a] < zero, min(exit, (lo[a] - f[a]) * slope[a]), exit));
                }
            }
        };
        if (skipping_ == skips::every_level) {
            place = bricks.place(c[0], c[1], c[2]);
            found = index_to_float(place); // >= 0: a voxel
            // The cube of 4 << e voxels: its side made from float bits (xsimd 8.1 has no per-lane
            // integer shift), then lo = c with its low e + 2 bits cleared (c & -side), as the GLSL
            // does. e is capped at 28 (a side of 2^30, within int; a smaller aligned cube around
            // the cell is empty too); lanes with a voxel take e = 0 (their exit is not used).
            const I e = krs::index_min(krs::index_max(voxel_bricks::view::empty_level(place), I(0)), I(28));
            const T side = krs::index_pow2(e + I(2));
            const I low_bits_cleared = I(0) - truncate_to_index(side);
            const T lo[3] = {index_to_float(c[0] & low_bits_cleared), index_to_float(c[1] & low_bits_cleared),
                             index_to_float(c[2] & low_bits_cleared)};
            leave(lo, side);
        } else {
            place = bricks.place_by_blocks(c[0], c[1], c[2]);
            found = index_to_float(place); // >= 0: a voxel; < -64: an empty 16^3 block
            const auto in_block = found < T(-float(brick_voxels) - 0.5f); // (places are whole: halfway to the next)
            T lo[3];
            for (int a = 0; a < 3; ++a)
                lo[a] = select(in_block, index_to_float(c[a] & I(~(block_side - 1))), index_to_float(c[a] & I(~(brick_side - 1))));
            leave(lo, select(in_block, T(float(block_side)), T(float(brick_side))));
        }
        const krs::mask_t<T> looks = inside & (found >= zero);
        const T steps = ceil(exit / T(step_) - margin);
        const T advance = select(inside & (found < zero), select(steps > one, min(steps, T(1.0e6f)), one), one);
        return {place, looks, advance, {c[0], c[1], c[2]}};
    }

    // The same with a secondary bound's test on top (bound_test of tree_shape.hpp, or any type
    // with everything() and holds(p)): a sample outside the bound looks at nothing, and advances
    // as the walk says. Every march of the marcher and the light sweep probes through this.
    template <class T, class Bound>
    [[gnu::always_inline]] probe_result<T> probe(const voxel_bricks::view& bricks, const krs::vec3<T>& p, const T (&slope)[3],
                                                 const krs::mask_t<T>& running, const T& margin, const exit_faces& faces,
                                                 const Bound& bound) const
    {
        probe_result<T> found = probe(bricks, p, slope, running, margin, faces);
        if (!bound.everything()) found.looks = found.looks & bound.holds(p);
        return found;
    }

    // How many steps short of an empty brick's exit a skip must stop, for a ray from `from` at t:
    // skip_margin(margin_at_origin(from), t).
    template <class T>
    T margin_at_origin(const krs::vec3<T>& from) const
    {
        using krs::abs, krs::max;
        const T reach = max(max(abs(from.x), abs(from.y)), abs(from.z)) + T(grid_reach_);
        return T(1e-3f) + reach * T(rounding_per_step_);
    }
    template <class T>
    T skip_margin(const T& at_origin, const T& t) const
    {
        return at_origin + t * T(rounding_per_step_);
    }

    // The same walk as GLSL (always the walk of every level: the reference walk is the CPU's), for
    // the marcher of glsl.hpp: constants NAME_brick_side and NAME_brick_voxels (the geometry above), NAME_grid_reach and NAME_rounding_per_step (this walk's
    // floats), `float NAME_margin_at_origin(vec3 from)`,
    // `vec3 NAME_slopes(vec3 d)` and `int NAME_probe(vec3 p, vec3 slope, float margin, out ivec3 cell,
    // out float advance)`, which returns the sample's place (< 0: nothing to look at) and how many
    // samples to advance, as probe() does for one lane. NAME is `name` (krs::glsl::fill); the caller emits
    // NAME_origin, NAME_cells_per_unit, NAME_grid, NAME_step and `int NAME_place(ivec3)`
    // (voxel_bricks::view::place) before it.
    std::string glsl(const std::string& name) const
    {
        std::string s = "const int " + name + "_brick_side = " + std::to_string(brick_side) + ";\n";
        s += "const int " + name + "_brick_voxels = " + std::to_string(brick_voxels) + ";\n";
        s += "const float " + name + "_grid_reach = " + krs::glsl::float_literal(grid_reach_) + ";\n";
        s += "const float " + name + "_rounding_per_step = " + krs::glsl::float_literal(rounding_per_step_) + ";\n";
        s += krs::glsl::fill(R"(
// brick_walk::margin_at_origin: steps a skip stops short of an empty brick's exit, but for t.
float NAME_margin_at_origin(vec3 from) {
    float reach = max(max(abs(from.x), abs(from.y)), abs(from.z)) + NAME_grid_reach;
    return 1e-3 + reach * NAME_rounding_per_step;
}

// brick_walk::probe for one ray: the place of the sample at p (< 0: none to look at), its cell,
// and the samples to advance (1, or in an empty brick the whole steps to the exit of its empty cube).
int NAME_probe(vec3 p, vec3 slope, float margin, out ivec3 cell, out float advance) {
    advance = 1.0;
    cell = ivec3(0);
    vec3 f = vec3((p.x - NAME_origin.x) * NAME_cells_per_unit.x, (p.y - NAME_origin.y) * NAME_cells_per_unit.y,
                  (p.z - NAME_origin.z) * NAME_cells_per_unit.z);
    if (!(f.x >= 0.0 && f.y >= 0.0 && f.z >= 0.0 && f.x < float(NAME_grid.x) && f.y < float(NAME_grid.y) && f.z < float(NAME_grid.z)))
        return -1;
    cell = ivec3(min(int(f.x), NAME_grid.x - 1), min(int(f.y), NAME_grid.y - 1), min(int(f.z), NAME_grid.z - 1));
    int place = NAME_place(cell);
    if (place >= 0) return place;
    // The level e of the empty cube (voxel_bricks::view::empty_level): 4 << e voxels a side.
    int side = NAME_brick_side << min((-1 - place) >> 6, 28);
    float exit = 3.0e38;
    for (int a = 0; a < 3; ++a) {
        float lo = float(cell[a] & ~(side - 1));
        float hi = lo + float(side);
        if (slope[a] > 0.0) exit = min(exit, (hi - f[a]) * slope[a]);
        else if (slope[a] < 0.0) exit = min(exit, (lo - f[a]) * slope[a]);
    }
    float steps = ceil(exit / NAME_step - margin);
    advance = steps > 1.0 ? min(steps, 1.0e6) : 1.0;
    return -1;
}

// brick_walk::slopes_of: the t to cross one cell along each axis, 0 for an axis not moved along.
vec3 NAME_slopes(vec3 d) {
    vec3 s = vec3(d.x * NAME_cells_per_unit.x, d.y * NAME_cells_per_unit.y, d.z * NAME_cells_per_unit.z);
    return vec3(s.x != 0.0 ? 1.0 / s.x : 0.0, s.y != 0.0 ? 1.0 / s.y : 0.0, s.z != 0.0 ? 1.0 / s.z : 0.0);
}

)",
                                  {{"NAME", name}});
        return s;
    }

private:
    krs::vec3f origin_{}, cells_per_unit_{};
    std::array<int, 3> grid_{};
    float step_ = 1;
    float rounding_per_step_ = 0, grid_reach_ = 0; // skip_margin's: 2^-21 / step, and max |origin| + the grid's diagonal
    skips skipping_ = skips::every_level;
};

// Where a walk starts and ends: the slab test of the rays' lanes against the box [lo, hi], with
// t0 >= 0 (a ray from inside starts at its origin). Rays that miss get t0 >= t1. Primary rays
// and shadow rays both clip by it (the marcher widens the box for render-time noise).
template <class T>
void enter_box(const krs::ray<T>& ray, const krs::vec3f& lo_corner, const krs::vec3f& hi_corner, T& t0, T& t1)
{
    using krs::abs, krs::max, krs::min, krs::select;
    t0 = T(0.0f);
    t1 = T(3.0e38f);
    const T lo[3] = {T(lo_corner.x), T(lo_corner.y), T(lo_corner.z)}, hi[3] = {T(hi_corner.x), T(hi_corner.y), T(hi_corner.z)};
    const T o[3] = {ray.origin.x, ray.origin.y, ray.origin.z}, d[3] = {ray.direction.x, ray.direction.y, ray.direction.z};
    for (int a = 0; a < 3; ++a) {
        // A zero direction component becomes tiny, so the division gives a huge finite slope
        // instead of inf * 0 = NaN when the origin lies on a slab plane.
        const T safe = select(abs(d[a]) < T(1e-30f), T(1e-30f), d[a]);
        const T inv = T(1.0f) / safe;
        const T ta = (lo[a] - o[a]) * inv, tb = (hi[a] - o[a]) * inv;
        t0 = max(t0, min(ta, tb));
        t1 = min(t1, max(ta, tb));
    }
    // Rays march in steps of ds along t, so a direction must be unit (krs::make_ray makes it
    // so): a zero one had a span of 1e30 that a float sample count never crossed (march hung),
    // and a short one would take more samples than the 2^23 the marcher allows. Such a ray, or
    // one from a non-finite origin, misses the box.
    const T length_squared = d[0] * d[0] + d[1] * d[1] + d[2] * d[2];
    const auto usable = (abs(length_squared - T(1.0f)) <= T(1e-3f)) && krs::is_finite(o[0]) && krs::is_finite(o[1]) &&
                        krs::is_finite(o[2]);
    t0 = select(usable, t0, T(0.0f)); // (a NaN slab bound could leave t0 at -1e31, not NaN)
    t1 = select(usable, t1, T(-1.0f));
}

} // namespace hypertree

#pragma once
// What the raymarcher knows about a tree's shape beyond its voxels (paper sections 8.2 and 8.3):
// its bounding box, the secondary bounding spheres of its first-level subparts, and the structure
// flow of those subparts for procedural normals.
//
// Bounding volumes (8.2, chosen by march_options::bounds_by, bound_method below): rays are always
// clipped to the box of the non-empty voxels (the paper's AABB), and with a secondary bound a
// sample is only looked up when it lies in one of the first-level parts' bounds:
// - `spheres`: each part's sphere fitted to the voxels it holds (detail::cell_bounding_sphere):
//   it holds every cell of them, so skipping samples outside all spheres changes no pixel.
// - `paper_spheres`: the paper's derivation. The primary sphere (`crown`, around the box) is pushed
//   through each transformation's level-1 chain: the center is mapped, the radius scaled by each
//   affine map's spectral norm and, at a shear of maximum displacement dmax (the length of its two
//   displacements), replaced by r (1 + dmax / r)^2 = r + 2 dmax + dmax^2 / r, r being the radius
//   as the shear receives it. (A shear moves every point by f dmax along one direction, f in
//   [0, 1], so two points' offsets differ by at most dmax: r + dmax would do; the paper's rule is
//   wider.) With generation noise (ifs::perturb, amplitude a) the crown is the box of perturbed
//   voxels while the chain maps the unperturbed orbit, which lies within |a| of them: the sphere
//   pushed through the chain is the crown grown by |a|. The image is then grown by |a| again (its
//   recorded points move by at most that, as the paper says) and by one cell diagonal (not in
//   the paper: the sphere bounds generator points, the marcher needs their whole cells).
//   The trunk is bounded by the condensation's box (part 0's cell box), as the paper does. This
//   holds every voxel only if the part's subtree lies in the primary sphere, which level-dependent
//   parameters (3.4) and dummy transformations do not promise: bench_hypertree_render --only
//   bounds counts the voxels left outside for trees A-D, and the pixels that then differ.
// - `part_boxes`: the secondary bounding boxes, each part's box of its voxels' cells (the paper's
//   "determined during generation" variant), the trunk's among them.
//
// Structure flow (8.3, figure 4): each first-level subpart has a centroid and a principal axis
// (the dominant eigenvector of its voxels' covariance: the direction its branch grows). The
// normal at a point is its offset from the nearby axes, made perpendicular to each axis and
// blended with weights 1 / (distance to the centroid)^2: outward from the branch structure, smooth,
// and defined for point generators that carry no direction of their own.
//
// The paper allows two more normals (8.3), chosen by march_options::normals_by (normal_method):
// - Box normals (after Hart and DeFanti): each first-level part keeps its secondary bounding box
//   (the box of its voxels' cells), and the normal at p is the outward normal of the face of that
//   box nearest to p, in the box holding p whose nearest face is nearest (a point in no box takes
//   the nearest box and the face it lies beyond most). Flat, faceted, and exact on a box.
// - Line-generator flow: a tree grown from line segments knows the direction each first-level
//   part's segments run in (the generator pushed through the part's transform), which for a part
//   wider than it is long differs from the covariance axis. set_line_flow_of(drawn_ifs) computes
//   those directions (set_line_flow takes them as given); the normal is then the structure-flow
//   blend about them instead of the covariance axes (until one is called, the line axes are the
//   covariance axes, and line_flow is the structure flow).

#include "hypertree/store/store.hpp"
#include "krs/core/bounds.hpp"
#include "krs/core/lanes.hpp"
#include "krs/core/rounding.hpp"
#include "krs/core/validate.hpp"

#include <algorithm>
#include <array>
#include <cmath>
#include <concepts>
#include <limits>
#include <string>
#include <span>
#include <utility>
#include <vector>

namespace hypertree {

struct part_flow {
    vec3d centroid{};
    vec3d axis{0, 1, 0};
    double weight_radius = 1; // softens 1/d^2 near the centroid: the part's RMS extent
    vec3d line_axis{0, 1, 0}; // the line generators' direction in this part (normal_method::line_flow)
    int part = 0;             // the voxels' part byte: 0 the trunk, 1 + j transformation j's
};

// Which normal the shading uses (section 8.3; see tree_shape below).
enum class normal_method { structure_flow, part_boxes, line_flow };

// Which bound, besides the tree's box, a sample must lie in to be looked up (section 8.2; see the
// head of this file): none (`box`, the paper's "AABB" row), the fitted part spheres, the paper's
// derived spheres, or the part boxes (the paper's "secondary AABB" row).
enum class bound_method { box, spheres, paper_spheres, part_boxes };

struct tree_shape {
    world_box box{};                           // of the non-empty voxels' cells
    std::vector<krs::bounding_sphere> spheres; // per first-level part (empty: box only)
    std::vector<part_flow> flows;
    std::vector<world_box> part_boxes; // per first-level part, in the order of flows: its secondary bounding box
    krs::bounding_sphere crown{}; // the whole tree: its "outer shell" for ambient attenuation
    // The paper's secondary spheres (bound_method::paper_spheres), one per transformation that
    // records a first-level part, and the trunk's box; empty until set_paper_spheres_of is called.
    std::vector<krs::bounding_sphere> paper_spheres;
    std::vector<world_box> trunk_box; // none or one: part 0's cell box

    // From a sorted stored-voxel list (parts as classify or a partitioned store keep them).
    static tree_shape of(const hypervolume& volume, std::span<const stored_voxel> voxels)
    {
        tree_shape shape;
        if (voxels.empty()) return shape;
        constexpr int max_parts = 256;
        struct moments {
            std::size_t n = 0;
            vec3d sum{};
            std::array<double, 6> second{}; // xx, xy, xz, yy, yz, zz
        };
        std::vector<moments> parts(max_parts);
        index_box box = index_box::nothing();
        for (const stored_voxel& v : voxels) {
            const vec3d c = volume.voxel_center(v.index);
            box.include(volume.coordinates(v.index));
            moments& m = parts[v.part];
            ++m.n;
            m.sum += c;
            m.second[0] += c.x * c.x, m.second[1] += c.x * c.y, m.second[2] += c.x * c.z;
            m.second[3] += c.y * c.y, m.second[4] += c.y * c.z, m.second[5] += c.z * c.z;
        }
        shape.box = world_bounds(volume, box);
        std::vector<std::vector<voxel_index>> part_indices(max_parts);
        for (const stored_voxel& v : voxels) part_indices[v.part].push_back(v.index);
        for (int p = 0; p < max_parts; ++p) {
            const moments& m = parts[p];
            if (!m.n) continue;
            shape.spheres.push_back(detail::cell_bounding_sphere(volume, part_indices[std::size_t(p)]));
            const double n = double(m.n);
            const vec3d c = m.sum / double(m.n);
            const std::array<double, 6> cov{m.second[0] / n - c.x * c.x, m.second[1] / n - c.x * c.y, m.second[2] / n - c.x * c.z,
                                            m.second[3] / n - c.y * c.y, m.second[4] / n - c.y * c.z, m.second[5] / n - c.z * c.z};
            part_flow f;
            f.centroid = c;
            f.axis = principal_axis(cov);
            f.weight_radius = std::max(std::sqrt(std::max(cov[0] + cov[3] + cov[5], 0.0)), volume.smallest_voxel_side());
            f.line_axis = f.axis;
            f.part = p;
            shape.flows.push_back(f);
            index_box part_box = index_box::nothing();
            for (const voxel_index i : part_indices[std::size_t(p)]) part_box.include(volume.coordinates(i));
            shape.part_boxes.push_back(world_bounds(volume, part_box));
        }
        const vec3d lo = shape.box.lo, hi = shape.box.hi;
        shape.crown = krs::bound_around((lo + hi) * 0.5, krs::length(hi - lo) * 0.5);
        return shape;
    }
    template <voxel_store S>
    static tree_shape of(const S& store)
    {
        const std::vector<stored_voxel> voxels = stored_voxels(store);
        return of(store.volume(), voxels);
    }

    // The line generators' direction in each first-level part, in the order of `flows` (one per
    // part, finite and non-zero; made unit). Throws invalid_parameter otherwise.
    void set_line_flow(std::span<const vec3d> directions)
    {
        if (directions.size() != flows.size())
            throw krs::invalid_parameter("tree_shape.set_line_flow", "needs one direction per first-level part (" + std::to_string(flows.size()) + ")",
                                         std::to_string(directions.size()));
        for (std::size_t i = 0; i < flows.size(); ++i) {
            const double len = krs::length(directions[i]);
            if (!(len > 0) || !std::isfinite(len))
                throw krs::invalid_parameter("tree_shape.set_line_flow", "directions must be finite and non-zero", "direction " + std::to_string(i));
            flows[i].line_axis = directions[i] / len;
        }
    }

    // The paper's secondary bounding spheres of a drawn IFS (section 8.2, the rule at the head of
    // this file): transformation j's level-1 chain applied to the primary sphere `crown`.
    // Transformations recording no first-level part (dummy_from == 1) get none.
    template <class Drawn>
    void set_paper_spheres_of(const Drawn& drawn)
    {
        const auto& definition = drawn.definition();
        // |a| in, for the unperturbed orbit around the perturbed crown; |a| and a cell diagonal out
        // (the rule at the head of this file).
        const double noise = krs::length(definition.perturb.amplitude);
        const double margin = krs::length(definition.volume.voxel_size()) + noise;
        paper_spheres.clear();
        for (std::size_t j = 0; j < drawn.transform_count(); ++j) {
            if (drawn.dummies_from()[j] <= 1) continue;
            const auto [c, r] = paper_sphere_through(drawn.chain_of(j, 1), vec3d(crown.center), double(crown.radius) + noise);
            paper_spheres.push_back(krs::bound_around(c, r + margin));
        }
        trunk_box.clear();
        for (std::size_t i = 0; i < flows.size(); ++i)
            if (flows[i].part == 0) trunk_box.push_back(part_boxes[i]);
    }

    // The sphere (c, r) through a canonical chain by the paper's rule (no margin): centers mapped,
    // radii scaled by the affine maps' norms and by (1 + dmax / r)^2 at each shear.
    template <class Chain>
    static std::pair<vec3d, double> paper_sphere_through(const Chain& chain, vec3d c, double r)
    {
        for (int k = 0; k < chain.shears; ++k) {
            c = chain.affine[std::size_t(k)](c);
            r *= chain.affine[std::size_t(k)].lipschitz();
            const auto& s = chain.shear[std::size_t(k)];
            const double dmax = std::hypot(s.dmax_first, s.dmax_second);
            c = s(c);
            r = r > 0 ? r * (1 + dmax / r) * (1 + dmax / r) : 2 * dmax; // (r -> 0: the limit is 2 dmax)
        }
        c = chain.affine[std::size_t(chain.shears)](c);
        r *= chain.affine[std::size_t(chain.shears)].lipschitz();
        return {c, r};
    }

    // The line flow of a drawn IFS (drawn_ifs, ifs.hpp) with a line generator: part 1 + j runs
    // along transformation j's first-level chain applied to the generator, chain(end) - chain(start)
    // (shears included). The trunk (part 0, grown from the condensation) keeps its covariance axis,
    // as does a part whose image of the segment is shorter than 1e-12 of its length. Throws
    // invalid_parameter for a point generator, which has no direction to carry.
    template <class Drawn>
    void set_line_flow_of(const Drawn& drawn)
    {
        const auto& g = drawn.definition().generator;
        if (g.is_point()) throw krs::invalid_parameter("tree_shape.set_line_flow_of", "needs an IFS with a line generator", "a point generator");
        // The line axes are per first-level part: voxels that all read part 0 (a list rebuilt
        // through a store that keeps no parts, e.g. index_list_store) would silently leave every
        // axis the covariance one, a single "trunk" flow. Refused instead.
        const bool any_branch = std::any_of(flows.begin(), flows.end(), [](const part_flow& f) { return f.part > 0; });
        if (!flows.empty() && drawn.transform_count() > 0 && !any_branch)
            throw krs::invalid_parameter("tree_shape.set_line_flow_of", "voxels carrying their first-level parts (a partitioned_store's list)",
                                         "every voxel in part 0");
        for (part_flow& f : flows) {
            if (f.part < 1 || std::size_t(f.part - 1) >= drawn.transform_count()) continue;
            const auto& chain = drawn.chain_of(std::size_t(f.part - 1), 1);
            const vec3d d = chain(g.end) - chain(g.start);
            const double len = krs::length(d);
            if (len > 1e-12 * g.length() && std::isfinite(len)) f.line_axis = d / len;
        }
    }

    // The normal at p by `method`: structure_flow and line_flow blend about the covariance or the
    // line axes (normal_at below); part_boxes is box_normal_at, lane by lane for a packet.
    template <class D = double>
    krs::vec3<D> normal_at(const krs::vec3<D>& p, normal_method method) const
    {
        if (method == normal_method::structure_flow) return normal_at(p);
        if (method == normal_method::line_flow) return flow_normal_at(p, true);
        if constexpr (std::floating_point<D>) {
            const vec3d n = box_normal_at(vec3d{p.x, p.y, p.z});
            return {D(n.x), D(n.y), D(n.z)};
        } else {
            const auto x = krs::lanes_of(p.x), y = krs::lanes_of(p.y), z = krs::lanes_of(p.z);
            decltype(krs::lanes_of(p.x)) ox{}, oy{}, oz{};
            for (std::size_t k = 0; k < x.size(); ++k) {
                const vec3d n = box_normal_at(vec3d{x[k], y[k], z[k]});
                ox[k] = n.x, oy[k] = n.y, oz[k] = n.z;
            }
            return {D::load_unaligned(ox.data()), D::load_unaligned(oy.data()), D::load_unaligned(oz.data())};
        }
    }

    // The outward normal of the nearest face of the part box p lies in (zero without boxes).
    // Inside a box, the face distances are p - lo and hi - p per axis, the smallest wins (ties: x
    // before y before z, lo before hi), and among the boxes holding p the one whose nearest face
    // is nearest. Outside every box: the nearest box (Euclidean), and the face p is farthest beyond.
    // In float, as the GLSL marcher computes it (glsl.hpp), so both pick the same face at a tie.
    vec3d box_normal_at(const vec3d& p) const
    {
        constexpr float big = std::numeric_limits<float>::max();
        const float pc[3] = {float(p.x), float(p.y), float(p.z)};
        float best_inside = big, best_outside = big;
        vec3d inside_n{}, outside_n{};
        for (const world_box& b : part_boxes) {
            const float lo[3] = {float(b.lo.x), float(b.lo.y), float(b.lo.z)}, hi[3] = {float(b.hi.x), float(b.hi.y), float(b.hi.z)};
            float nearest = big, beyond = -big, out2 = 0;
            int near_axis = 0, near_sign = -1, beyond_axis = 0, beyond_sign = -1;
            for (int a = 0; a < 3; ++a) {
                const float below = lo[a] - pc[a], above = pc[a] - hi[a]; // > 0: beyond that face
                if (-below < nearest) nearest = -below, near_axis = a, near_sign = -1;
                if (-above < nearest) nearest = -above, near_axis = a, near_sign = 1;
                if (below > beyond) beyond = below, beyond_axis = a, beyond_sign = -1;
                if (above > beyond) beyond = above, beyond_axis = a, beyond_sign = 1;
                const float e = std::max(std::max(below, above), 0.0f);
                out2 += e * e;
            }
            if (beyond <= 0) {
                if (nearest < best_inside) best_inside = nearest, inside_n = axis_normal(near_axis, near_sign);
            } else if (out2 < best_outside) {
                best_outside = out2, outside_n = axis_normal(beyond_axis, beyond_sign);
            }
        }
        return best_inside < big ? inside_n : outside_n;
    }

    // The blended outward normal at p (zero when there is no flow). One template for a point
    // (D = double) and for a packet of points (D = krs::packet_d, a point per lane), each lane
    // computing exactly what the scalar does: square roots and divisions are correctly rounded.
    template <class D = double>
    krs::vec3<D> normal_at(const krs::vec3<D>& p) const
    {
        return flow_normal_at(p, false);
    }

private:
    static vec3d axis_normal(int axis, int sign)
    {
        return {axis == 0 ? double(sign) : 0.0, axis == 1 ? double(sign) : 0.0, axis == 2 ? double(sign) : 0.0};
    }

    template <class D>
    krs::vec3<D> flow_normal_at(const krs::vec3<D>& p, bool line_axes) const
    {
        using krs::select, krs::sqrt;
        const D zero(0.0);
        krs::vec3<D> n{zero, zero, zero};
        for (const part_flow& f : flows) {
            const vec3d& a = line_axes ? f.line_axis : f.axis;
            const krs::vec3<D> centroid{D(f.centroid.x), D(f.centroid.y), D(f.centroid.z)}, axis{D(a.x), D(a.y), D(a.z)};
            const krs::vec3<D> d = p - centroid;
            const krs::vec3<D> radial = d - axis * krs::dot(d, axis);
            const D w = D(1.0) / (krs::dot(d, d) + D(f.weight_radius * f.weight_radius * 0.05));
            const D len = sqrt(krs::dot(radial, radial));
            const auto some = len > zero;
            // (A lane with no radial part divides by 0 and discards it.)
            const D scale = w / select(some, len, D(1.0));
            n = {n.x + select(some, radial.x * scale, zero), n.y + select(some, radial.y * scale, zero), n.z + select(some, radial.z * scale, zero)};
        }
        const D len = sqrt(krs::dot(n, n));
        const auto some = len > zero;
        const D safe = select(some, len, D(1.0));
        return {select(some, n.x / safe, zero), select(some, n.y / safe, zero), select(some, n.z / safe, zero)};
    }

    // Dominant eigenvector of a symmetric 3x3 matrix by power iteration from the axis with the
    // largest variance (converges unless that start is orthogonal to it, which the choice avoids).
    static vec3d principal_axis(const std::array<double, 6>& c)
    {
        vec3d v = c[0] >= c[3] && c[0] >= c[5] ? vec3d{1, 0, 0} : c[3] >= c[5] ? vec3d{0, 1, 0} : vec3d{0, 0, 1};
        for (int i = 0; i < 64; ++i) {
            const vec3d w{c[0] * v.x + c[1] * v.y + c[2] * v.z, c[1] * v.x + c[3] * v.y + c[4] * v.z,
                          c[2] * v.x + c[4] * v.y + c[5] * v.z};
            const double len = krs::length(w);
            if (!(len > 0)) break;
            v = w / len;
        }
        return v.y < 0 ? -v : v; // branches grow upward-ish: a stable sign
    }
};

// A bound_method made ready for the march: float spheres (center, radius^2: radius^2 rounded up
// with room for the float test's own rounding) and float boxes rounded outward, so the float test
// never rejects a point the double bound holds. holds(p) is
// one template for a point (T = float) and a packet (one point per lane), the same operations
// in the same order, so scalar and packet marchers skip the same samples.
struct bound_test {
    bound_method by = bound_method::box;
    std::vector<std::array<float, 4>> spheres; // x, y, z, radius^2
    std::vector<std::array<float, 6>> boxes;   // lo x, y, z, hi x, y, z

    // Throws invalid_parameter when `by` needs what the shape does not hold (paper_spheres before
    // tree_shape::set_paper_spheres_of) or is not a bound_method.
    static bound_test of(const tree_shape& shape, bound_method by)
    {
        bound_test t;
        t.by = by;
        // Each bound is rounded outward to float by the library's one rule (krs/core/rounding.hpp).
        using krs::float_at_least, krs::float_at_most;
        // The center is already float (krs::bound_around grew the radius by its rounding). holds()
        // computes dx^2 + dy^2 + dz^2 in float: three differences, three squares and two sums, a
        // relative error below 6 u = 3.6e-7 (u = 2^-24) for the point's own float position. So r^2
        // is taken in double, grown by 1e-6 relative (half a micron per metre of radius) and
        // rounded up: a point the double sphere holds is never rejected.
        const auto add_sphere = [&](const krs::bounding_sphere& s) {
            t.spheres.push_back({s.center.x, s.center.y, s.center.z, float_at_least(double(s.radius) * double(s.radius) * (1 + 1e-6))});
        };
        const auto add_box = [&](const world_box& b) {
            t.boxes.push_back({float_at_most(b.lo.x), float_at_most(b.lo.y), float_at_most(b.lo.z), float_at_least(b.hi.x),
                               float_at_least(b.hi.y), float_at_least(b.hi.z)});
        };
        switch (by) {
        case bound_method::box: break;
        case bound_method::spheres:
            for (const auto& s : shape.spheres) add_sphere(s);
            break;
        case bound_method::paper_spheres:
            if (shape.paper_spheres.empty() && shape.trunk_box.empty() && !shape.flows.empty())
                throw krs::invalid_parameter("march_options.bounds_by", "paper_spheres needs tree_shape::set_paper_spheres_of(drawn ifs) first",
                                             "bound_method::paper_spheres");
            for (const auto& s : shape.paper_spheres) add_sphere(s);
            for (const auto& b : shape.trunk_box) add_box(b);
            break;
        case bound_method::part_boxes:
            for (const auto& b : shape.part_boxes) add_box(b);
            break;
        default:
            throw krs::invalid_parameter("march_options.bounds_by", "must be bound_method::box, spheres, paper_spheres or part_boxes",
                                         std::to_string(int(by)));
        }
        return t;
    }

    // Whether the test rejects nothing (no secondary bound, or an empty tree's).
    bool everything() const { return spheres.empty() && boxes.empty(); }

    template <class T>
    krs::mask_t<T> holds(const krs::vec3<T>& p) const
    {
        if (everything()) return krs::mask_t<T>(true);
        krs::mask_t<T> inside(false);
        for (const auto& s : spheres) {
            const T dx = p.x - T(s[0]), dy = p.y - T(s[1]), dz = p.z - T(s[2]);
            inside = inside | (dx * dx + dy * dy + dz * dz <= T(s[3]));
        }
        for (const auto& b : boxes)
            inside = inside | ((p.x >= T(b[0])) & (p.y >= T(b[1])) & (p.z >= T(b[2])) & (p.x <= T(b[3])) & (p.y <= T(b[4])) & (p.z <= T(b[5])));
        return inside;
    }
};

} // namespace hypertree

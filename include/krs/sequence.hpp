#pragma once
// Kernel-reflection sequence (KRS), paper section 3.
//
// A KRS is a pair of sequences: kernel sets K_0 ... K_n and mirrors R_0 ... R_{n-1}. Expansion
// level L_{i+1} = K_{i+1} u L_i u R_i L_i with L_0 = K_0, so a kernel of level i is doubled by
// mirrors i ... n-1 and appears 2^(n-i) times: the sequence holds sum_i |K_i| 2^(n-i) instances.
// Its distance is evaluated in O(n) by Algorithm 1: walk the levels from the top, reflect the
// point onto the negative side of each mirror (the closest instance must lie there when kernels
// are separated by the mirror), and take the minimum of the kernels met on the way:
//
//     l_{i+1}(x) = min(k_{i+1}(x), l_i(x))       if m_i . x - c_i <= 0
//                  min(k_{i+1}(x), l_i(R_i x))   otherwise.
//
// Where a kernel crosses a mirror, that choice clips it to the mirror's negative side: the field
// then describes the clipped geometry (section 3, figure 2), and stays a 1-Lipschitz
// underestimate of the distance to it, because folds are 1-Lipschitz and min keeps the bound.
//
// Kernel kinds are fixed at compile time: `sequence<sphere, torus_capsule>` holds only those, and
// a level's kernels dispatch through a closed variant, uniform across the lanes of a packet.
// A sequence is an immutable value once built (use `sequence<...>::builder`), so any number of
// threads may evaluate it.
//
// Mirrors come in kinds chosen by type as well: `sequence<Kinds...>` is
// `basic_sequence<mirror, Kinds...>` (general planes); `basic_sequence<axis_mirror, Kinds...>`
// holds only axis-aligned mirrors, whose fold is one min per level.

#include "krs/field.hpp"
#include "krs/mirror.hpp"

#include <algorithm>
#include <array>
#include <cstdint>
#include <limits>
#include <optional>
#include <string>
#include <utility>
#include <variant>
#include <vector>

namespace krs {

// Where Algorithm 1 found the closest kernel: the point in that kernel's space, which kernel, and
// the reflection decisions b_i (bit i set when R_i was applied). Shading needs them (section 6.1):
// p_world = R_{n-1}^{b_{n-1}} ... R_level^{b_level} p_kernel.
template <class S>
struct location {
    S distance = std::numeric_limits<S>::infinity();
    vec3<S> kernel_point{};
    std::uint32_t kernel = 0; // index into sequence::kernels()
    std::uint32_t level = 0;  // the kernel's level i (it was reached through mirrors n-1 ... i)
    std::uint64_t reflections = 0;

    bool reflected(std::size_t i) const { return (reflections >> i) & 1u; }
};

// The radius the per-level early exit tests against: the level bound's radius with a margin for
// the bound's own float rounding (the C++ walk below and its GLSL, krs/sequence_glsl.hpp, both).
inline float early_exit_radius(const bounding_sphere& b) { return b.radius * 1.0001f + 1e-5f; }

template <mirror_kind Mirror, kernel... Kinds>
class basic_sequence {
    static_assert(sizeof...(Kinds) > 0, "krs::sequence needs at least one kernel kind");

public:
    using kernel_variant = std::variant<Kinds...>;
    using mirror_type = Mirror;
    // The reflection decisions of a point fit one 64-bit word; 2^64 instances is beyond any scene.
    static constexpr std::size_t max_levels = 64;

    class builder;

    basic_sequence() = default;

    // n: the number of mirrors; kernel levels run 0 ... n.
    std::size_t mirror_count() const { return mirrors_.size(); }
    const std::vector<Mirror>& mirrors() const { return mirrors_; }
    const std::vector<kernel_variant>& kernels() const { return kernels_; }
    std::uint32_t kernel_level(std::size_t kernel_index) const { return kernel_levels_[kernel_index]; }
    // Kernels of level i are kernels()[level_begin(i) .. level_begin(i + 1)).
    std::uint32_t level_begin(std::size_t level) const { return level_begin_[level]; }
    // Number of kernel instances of the full expansion, as a double (it reaches 2^64).
    double instance_count() const
    {
        double count = 0;
        for (std::uint32_t level : kernel_levels_) count += std::ldexp(1.0, int(mirrors_.size() - level));
        return count;
    }
    // A sphere holding every instance (infinite if any kernel is unbounded).
    const bounding_sphere& bound() const { return bound_; }
    // An axis-aligned box holding every instance (infinite if any kernel is unbounded): much
    // tighter than the sphere for flat scenes, for clipping rays (krs/trace/box_clip.hpp). It is
    // box_through_mirrors (below) of the kernels' own boxes: exact for axis mirrors up to the
    // float rounding margins, never larger than the sphere's box on any axis.
    const bounding_box& bound_box() const { return box_; }
    // The sequence's memory: the object plus what its vectors hold (allocator overhead aside). It
    // grows with n and the kernel count, never with the 2^n instances it stands for.
    std::size_t memory_bytes() const
    {
        return sizeof(*this) + mirrors_.capacity() * sizeof(Mirror) + kernels_.capacity() * sizeof(kernel_variant) +
               (kernel_levels_.capacity() + level_begin_.capacity()) * sizeof(std::uint32_t) +
               level_bounds_.capacity() * sizeof(bounding_sphere) +
               (axis_prefix_[0].capacity() + axis_prefix_[1].capacity() + axis_prefix_[2].capacity()) * sizeof(axis_fold);
    }

    // Whether the walk can end early (some level below a kernel has a bounded L_i): then an
    // evaluation's cost depends on where the point is, shallow far from the finer levels and deep
    // near them, and packet tracers keep the points of a packet together (krs/trace/packet_trace.hpp).
    bool varying_cost() const { return bound_tests_below_ > 0; }

    // Algorithm 1.
    template <class T>
    T distance(const vec3<T>& x) const
    {
        return distances<T, 1>({x})[0];
    }

    // Algorithm 1 for K points (or packets) at once, walking the levels in lockstep: the folds of
    // one level are independent across the K points, so the processor overlaps their chains of
    // dependent operations (a packet tracer steps K packets this way). Each point leaves the walk
    // at its own early out; the results equal K calls of distance().
    template <class T, std::size_t K>
    std::array<T, K> distances(const std::array<vec3<T>, K>& x) const
    {
        const std::size_t n = mirrors_.size();
        std::array<vec3<T>, K> p = x;
        std::array<T, K> d;
        static_assert(K >= 1 && K <= 32, "distances takes 1 to 32 points");
        std::uint32_t walking = (std::uint32_t(1) << (K - 1) << 1) - 1; // bit k: point k still walks
        // The K points are stepped by a fold expression over compile-time indices, so each
        // point's coordinates stay in registers.
        const auto each = [&]<std::size_t... k>(std::index_sequence<k...>, auto&& step) {
            (step(std::integral_constant<std::size_t, k>{}), ...);
        };
        constexpr auto all_k = std::make_index_sequence<K>{};
        each(all_k, [&](auto k) { d[k] = nearest_kernel(p[k], n, T(std::numeric_limits<scalar_t<T>>::infinity())); });
        std::size_t i = n;
        if constexpr (one_axis_folds) {
            // Down to the highest kernel level the walk is folds and nothing else (d is infinite,
            // no bound test, no kernel): apply them axis by axis, each axis's folds in walk order,
            // in tight loops over the coordinate alone instead of a branch on the axis per level
            // (a grid of 2^22 copies: its whole walk but the last level's kernels).
            if (top_kernel_level_ < n) {
                fold_axis_prefix<0>(p, all_k, each);
                fold_axis_prefix<1>(p, all_k, each);
                fold_axis_prefix<2>(p, all_k, each);
                i = top_kernel_level_; // a level with kernels, by its definition
                each(all_k, [&](auto k) { d[k] = nearest_kernel(p[k], i, d[k]); });
            }
        }
        while (i-- > 0) {
            const Mirror& mirror = mirrors_[i];
            // (A point that has left the walk is folded on regardless: cheaper than testing.)
            each(all_k, [&](auto k) { p[k] = mirror.fold(p[k]); });
            // Early out: every kernel instance still to come lies in L_i's bounding sphere (in
            // this folded space), and each kernel is at least as far as its instance's distance
            // to that sphere, so when the sphere is no nearer than d for every lane the rest of
            // the walk cannot lower d. The result equals the full walk's; far from the finer
            // levels (most sphere-tracing steps) the walk stops after a few levels. Down to the
            // highest level that holds kernels d is still infinite: no test there, which leaves
            // a grid of copies (every kernel at level 0) with folds alone until its last level.
            // Nor where L_i is unbounded (it holds a plane): a terrain of planes never tests.
            if (i < bound_tests_below_) {
                const bounding_sphere& b = level_bounds_[i];
                const T radius(early_exit_radius(b));
                const vec3<T> center(b.center);
                each(all_k, [&](auto k) {
                    const T reach = d[k] + radius;
                    if (((walking >> k) & 1u) && all(length_squared(p[k] - center) > reach * reach && reach > T(0)))
                        walking &= ~(std::uint32_t(1) << k);
                });
                if (walking == 0) break;
            }
            if (level_begin_[i] == level_begin_[i + 1]) continue; // no kernels at this level
            each(all_k, [&](auto k) {
                if ((walking >> k) & 1u) d[k] = nearest_kernel(p[k], i, d[k]);
            });
        }
        return d;
    }

    // Algorithm 1, also recording where the minimum was found (scalar lanes).
    template <std::floating_point S>
    location<S> locate(const vec3<S>& x) const
    {
        const std::size_t n = mirrors_.size();
        location<S> where;
        vec3<S> p = x;
        for (std::size_t i = n + 1; i-- > 0;) {
            if (i < n && mirrors_[i].signed_distance(p) > S(0)) {
                p = mirrors_[i].reflect(p);
                where.reflections |= std::uint64_t(1) << i;
            }
            for (std::uint32_t k = level_begin_[i]; k < level_begin_[i + 1]; ++k) {
                const S d = std::visit([&](const auto& kernel) { return kernel.distance(p); }, kernels_[k]);
                if (d < where.distance) {
                    where.distance = d;
                    where.kernel_point = p;
                    where.kernel = k;
                    where.level = std::uint32_t(i);
                }
            }
        }
        return where;
    }

    // A kernel-space point or direction taken back to world space through the located kernel's
    // reflections (section 6.1: R_level first, R_{n-1} last).
    template <std::floating_point S>
    vec3<S> to_world_point(const location<S>& where, vec3<S> p) const
    {
        for (std::size_t i = where.level; i < mirrors_.size(); ++i)
            if (where.reflected(i)) p = mirrors_[i].reflect(p);
        return p;
    }
    template <std::floating_point S>
    vec3<S> to_world_direction(const location<S>& where, vec3<S> w) const
    {
        for (std::size_t i = where.level; i < mirrors_.size(); ++i)
            if (where.reflected(i)) w = mirrors_[i].reflect_direction(w);
        return w;
    }

    // Outward unit normal of the nearest kernel, in world space: the kernel's own normal at the
    // kernel-space point, carried back by the recorded reflections.
    template <std::floating_point S>
    vec3<S> normal(const vec3<S>& x) const
    {
        return normal(locate(x));
    }
    // The same, from a location already found (a hit's).
    template <std::floating_point S>
    vec3<S> normal(const location<S>& where) const
    {
        const vec3<S> n = std::visit([&](const auto& kernel) { return kernel.normal(where.kernel_point); },
                                     kernels_[where.kernel]);
        return to_world_direction(where, n);
    }

    // GLSL (krs/sequence_glsl.hpp): NAME (Algorithm 1), NAME_locate and NAME_shade (Algorithm 2),
    // written through a krs::glsl::emitter.
    template <class Out>
    void glsl_emit(Out& out, const std::string& name) const;
    // GLSL `vec2 FUNCTION(krs_location where)`: the uv of the kernel `where` names at its
    // kernel_point, for kinds with a uv (a glsl_uv_source); vec2(0) for the others. Reads the
    // kernel parameters of `field`, this sequence's GLSL name in `out`. Written by
    // emitter::add_shading(kernel_uv_glsl{sequence}, NAME, FIELD) (krs/sequence_glsl.hpp).
    template <class Out>
    void glsl_uv_emit(Out& out, const std::string& function, const std::string& field) const;

private:
    static constexpr bool one_axis_folds = requires { Mirror::folds_one_axis; };

    // One fold of an axis prefix: x <- min(x, c - x) (above) or max(x, c - x).
    struct axis_fold {
        float twice_position;
        bool above;
    };

    // Applies the prefix's folds of coordinate `Axis` to every point, in walk order.
    template <int Axis, class T, std::size_t K, class Each, class All>
    void fold_axis_prefix(std::array<vec3<T>, K>& p, All all_k, Each& each) const
    {
        std::array<T, K> x;
        const auto coordinate = [](vec3<T>& q) -> T& { return Axis == 0 ? q.x : (Axis == 1 ? q.y : q.z); };
        each(all_k, [&](auto k) { x[k] = coordinate(p[k]); });
        for (const axis_fold& f : axis_prefix_[Axis]) {
            const T c(f.twice_position);
            if (f.above) each(all_k, [&](auto k) { x[k] = min(x[k], c - x[k]); });
            else each(all_k, [&](auto k) { x[k] = max(x[k], c - x[k]); });
        }
        each(all_k, [&](auto k) { coordinate(p[k]) = x[k]; });
    }

    // Always inlined into the walk: called out of line (GCC's choice once the walk grew the
    // axis prefix), the K points' kernel evaluations ran one after another through memory instead
    // of overlapping in registers (a grid of 2^22 rings: 38.5 -> 47 Mrays/s inlined).
    template <class T>
    [[gnu::always_inline]] inline T nearest_kernel(const vec3<T>& p, std::size_t level, T d) const
    {
        for (std::uint32_t k = level_begin_[level]; k < level_begin_[level + 1]; ++k)
            d = min(d, std::visit([&](const auto& kernel) { return kernel.distance(p); }, kernels_[k]));
        return d;
    }

    std::vector<Mirror> mirrors_;
    std::vector<kernel_variant> kernels_;        // grouped by level, level 0 first
    std::vector<std::uint32_t> kernel_levels_;   // level of each kernel
    std::vector<std::uint32_t> level_begin_{0, 0}; // n + 2 offsets into kernels_
    bounding_sphere bound_{};
    bounding_box box_ = bounding_box::unbounded();
    std::vector<bounding_sphere> level_bounds_; // bound of L_i (levels <= i, mirrors < i), i < n
    std::size_t top_kernel_level_ = 0;          // the highest level that holds a kernel
    // Levels i below this have a finite L_i bound and a finite d to compare it with: below both
    // the highest kernel level and the lowest level whose L_i holds an unbounded kernel.
    std::size_t bound_tests_below_ = 0;
    // Axis mirrors only: the folds of mirrors n-1 ... top_kernel_level_ per axis, in walk order.
    std::array<std::vector<axis_fold>, 3> axis_prefix_;
};

// A box holding every instance of a sequence, from a box per kernel carried through the mirrors
// in O(kernels + levels) without expanding the 2^n instances: the box B_{i+1} of
// L_{i+1} = K_{i+1} u L_i u R_i L_i is that of B_i, of R_i B_i and of the kernel boxes of level
// i + 1, with R_i B_i bounded by the box of B_i's eight reflected corners (R_i is affine, so the
// image of B_i is the hull of its reflected corners and this is that image's box). For an axis
// mirror the image of a box is a box, and with exact kernel boxes the result is the exact box of
// the 2^n instances; a turned mirror makes B_i's image a turned box, whose box may reach past the
// instances by the corners it turns out. Computed in double, then grown by a relative
// 1e-6 of the largest coordinate for the float rounding of the walk's folds (a float mirror normal
// is unit to about 1e-7), rounded outward to float, and cut to the box of the sequence's bounding
// sphere, which holds every instance too. `kernel_box(k)` gives each kernel's box: the sequence's
// own bound_box() passes the kernels' bound_box(), exact where they have a closed form; passing
// box_around(k.bound()) gives the looser box of their bounding spheres (the one before issue 23,
// kept for comparison: bench_embree_peer). The result only grows with the kernel boxes (each step
// is monotone), so the first is never larger than the second on any axis. An unbounded kernel box
// makes the result unbounded.
template <mirror_kind Mirror, kernel... Kinds, class KernelBox>
bounding_box box_through_mirrors(const basic_sequence<Mirror, Kinds...>& s, KernelBox&& kernel_box)
{
    constexpr double inf = std::numeric_limits<double>::infinity();
    vec3d lo{inf, inf, inf}, hi{-inf, -inf, -inf};
    const auto add = [&](const vec3d& p) {
        lo = {std::min(lo.x, p.x), std::min(lo.y, p.y), std::min(lo.z, p.z)};
        hi = {std::max(hi.x, p.x), std::max(hi.y, p.y), std::max(hi.z, p.z)};
    };
    for (std::size_t i = 0; i <= s.mirror_count(); ++i) {
        if (i > 0 && lo.x <= hi.x) {
            const Mirror& m = s.mirrors()[i - 1];
            const vec3d a = lo, b = hi;
            for (int corner = 0; corner < 8; ++corner)
                add(m.reflect(vec3d{corner & 1 ? b.x : a.x, corner & 2 ? b.y : a.y, corner & 4 ? b.z : a.z}));
        }
        for (std::uint32_t k = s.level_begin(i); k < s.level_begin(i + 1); ++k) {
            const bounding_box kb = std::visit([&](const auto& kernel) -> bounding_box { return kernel_box(kernel); },
                                               s.kernels()[k]);
            if (!kb.is_bounded()) return bounding_box::unbounded();
            add(vec3d(kb.lo)), add(vec3d(kb.hi));
        }
    }
    const double margin = 1e-6 * std::max({std::abs(lo.x), std::abs(lo.y), std::abs(lo.z), std::abs(hi.x),
                                            std::abs(hi.y), std::abs(hi.z), 1e-30});
    return intersect(box_around(lo, hi, margin), box_around(s.bound()));
}

// Builds a sequence bottom-up, as the paper writes it: kernels of level 0, then a mirror, then the
// kernels of level 1, and so on. `build()` validates and returns the immutable sequence.
template <mirror_kind Mirror, kernel... Kinds>
class basic_sequence<Mirror, Kinds...>::builder {
public:
    // Adds a kernel to the current level (level 0 until the first mirror).
    template <class K>
        requires(std::same_as<std::remove_cvref_t<K>, Kinds> || ...)
    builder& kernel(K&& k)
    {
        // A kind with public fields is rebuilt through its constructor's checks (checked()).
        if constexpr (requires { { k.checked() } -> std::same_as<std::remove_cvref_t<K>>; })
            levels_.back().push_back(kernel_variant(k.checked()));
        else
            levels_.back().push_back(kernel_variant(std::forward<K>(k)));
        return *this;
    }
    // Closes the current level with its mirror R_i; later kernels belong to level i + 1.
    builder& mirror(const Mirror& m)
    {
        if (mirrors_.size() >= max_levels)
            throw invalid_parameter("sequence.mirror", "at most " + std::to_string(max_levels) + " mirrors are allowed",
                                    std::to_string(mirrors_.size() + 1));
        require_direction("sequence.mirror.normal", m.normal);
        // The fields are public, so a mirror may not have been through its constructor's checks:
        // it is rebuilt through them (a general mirror's normal normalized, an axis mirror's
        // axis, position and side checked against its normal and offset).
        require_magnitude("sequence.mirror.offset", m.offset);
        mirrors_.push_back(m.checked());
        levels_.emplace_back();
        return *this;
    }
    std::size_t current_level() const { return mirrors_.size(); }

    basic_sequence build() const
    {
        basic_sequence s;
        s.mirrors_ = mirrors_;
        s.level_begin_.assign(1, 0);
        for (std::size_t i = 0; i < levels_.size(); ++i) {
            for (const kernel_variant& k : levels_[i]) {
                s.kernels_.push_back(k);
                s.kernel_levels_.push_back(std::uint32_t(i));
            }
            s.level_begin_.push_back(std::uint32_t(s.kernels_.size()));
        }
        if (s.kernels_.empty()) throw invalid_parameter("sequence.kernels", "a sequence needs at least one kernel");
        for (std::size_t i = 0; i < levels_.size(); ++i)
            if (!levels_[i].empty()) s.top_kernel_level_ = i;
        s.bound_ = expansion_bound(s, &s.level_bounds_);
        s.bound_tests_below_ = s.top_kernel_level_;
        for (std::size_t i = 0; i < s.level_bounds_.size(); ++i)
            if (!s.level_bounds_[i].is_bounded()) {
                s.bound_tests_below_ = std::min(s.bound_tests_below_, i);
                break;
            }
        s.box_ = box_through_mirrors(s, [](const auto& kernel) { return kernel.bound_box(); });
        if constexpr (one_axis_folds)
            for (std::size_t i = s.mirrors_.size(); i-- > s.top_kernel_level_;) {
                const Mirror& m = s.mirrors_[i];
                s.axis_prefix_[m.axis].push_back({m.twice_position, m.above});
            }
        return s;
    }

private:
    // Bound of L_{i+1} = K_{i+1} u L_i u R_i L_i, level by level.
    static bounding_sphere expansion_bound(const basic_sequence& s, std::vector<bounding_sphere>* levels)
    {
        std::optional<bounding_sphere> b;
        for (std::size_t i = 0; i <= s.mirrors_.size(); ++i) {
            if (i > 0) levels->push_back(b ? *b : bounding_sphere::unbounded());
            if (i > 0 && b) {
                const Mirror& m = s.mirrors_[i - 1];
                b = enclose(*b, bounding_sphere{m.reflect(b->center), b->radius});
            }
            for (std::uint32_t k = s.level_begin_[i]; k < s.level_begin_[i + 1]; ++k) {
                const bounding_sphere kb = std::visit([](const auto& kernel) { return kernel.bound(); }, s.kernels_[k]);
                b = b ? enclose(*b, kb) : kb;
            }
        }
        return *b;
    }

    std::vector<Mirror> mirrors_;
    std::vector<std::vector<kernel_variant>> levels_{1};
};

// The KRS with general mirror planes (the paper's); existing code names it `sequence<Kinds...>`.
template <kernel... Kinds>
using sequence = basic_sequence<mirror, Kinds...>;
// A KRS whose mirrors are all axis-aligned.
template <kernel... Kinds>
using axis_sequence = basic_sequence<axis_mirror, Kinds...>;

} // namespace krs

#include "krs/sequence_glsl.hpp"

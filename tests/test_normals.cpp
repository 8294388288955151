// Normals from the kernel-space transform (paper section 6.1) against the field itself: at points
// where rays hit a tree and a forest, the kernel's normal carried back to world space (by
// sequence::normal, and by the location Algorithm 2 returns) must be the direction of the field's
// central-difference gradient, which knows nothing of kernels or reflections.

#include "krs/expansion.hpp"
#include "krs/model/forest.hpp"
#include "krs/model/tree.hpp"
#include "krs/shade/kernel_light.hpp"
#include "krs/trace/sphere_trace.hpp"

#include "support/random.hpp"

#include <doctest/doctest.h>

#include <cmath>
#include <numbers>
#include <random>

namespace {

using krs::vec3d;

using krs_test::random_direction;
using krs_test::uniform;

double angle_degrees(const vec3d& a, const vec3d& b)
{
    const double c = krs::dot(a, b) / (krs::length(a) * krs::length(b));
    return std::acos(std::clamp(c, -1.0, 1.0)) * 180.0 / std::numbers::pi;
}

struct normal_statistics {
    int hits = 0, compared = 0;
    double worst_degrees = 0;
};

// Traces `rays` rays from a sphere around `aim` toward kernel instances (a random instance's
// bounding sphere, so thin branches are hit as often as the crown); at each hit compares the
// normals with the central-difference gradient (step h), skipping creases.
template <class S>
normal_statistics compare_normals(const S& s, const krs::bounding_sphere& aim, int rays, std::uint64_t seed)
{
    std::mt19937_64 g(seed);
    std::vector<krs::bounding_sphere> targets;
    for (const auto& instance : krs::expand(s).instances) {
        const krs::bounding_sphere b = std::visit([](const auto& k) { return k.bound(); }, s.kernels()[instance.kernel]);
        targets.push_back({krs::vec3f(instance.to_world.apply(vec3d(b.center))), b.radius});
    }
    krs::trace_options o;
    o.pixel_footprint = 0;
    o.threshold_floor = 1e-7f;
    o.max_steps = 2000;
    o.max_distance = 8 * aim.radius;
    const vec3d center(aim.center);
    const double h = 1e-6;
    const vec3d light = krs::normalize(vec3d{0.3, 1, -0.2});
    normal_statistics out;
    for (int k = 0; k < rays; ++k) {
        const vec3d origin = center + random_direction(g) * (2.5 * aim.radius);
        const krs::bounding_sphere& t = targets[std::size_t(g() % targets.size())];
        const vec3d target = vec3d(t.center) + random_direction(g) * (0.5 * t.radius * uniform(g, 0, 1));
        const krs::ray<double> r{origin, krs::normalize(target - origin)};
        const krs::hit<double> hit = krs::sphere_trace(s, r, o);
        if (!hit.found) continue;
        ++out.hits;
        const vec3d x = krs::point_at(r, hit.t);
        const vec3d gradient{(s.distance(x + vec3d{h, 0, 0}) - s.distance(x - vec3d{h, 0, 0})) / (2 * h),
                             (s.distance(x + vec3d{0, h, 0}) - s.distance(x - vec3d{0, h, 0})) / (2 * h),
                             (s.distance(x + vec3d{0, 0, h}) - s.distance(x - vec3d{0, 0, h})) / (2 * h)};
        // A gradient that is not a unit vector marks a crease (equidistant from two instances, or
        // a kernel clipped by a mirror): no single normal exists there.
        if (std::abs(krs::length(gradient) - 1) > 1e-3) continue;
        ++out.compared;
        const vec3d from_locate = s.normal(x);
        const auto k_space = krs::shade_in_kernel_space(s, x, light, light, 0.0);
        const vec3d from_algorithm_2 = s.to_world_direction(k_space.where, k_space.normal);
        const double worst = std::max(angle_degrees(from_locate, gradient), angle_degrees(from_algorithm_2, gradient));
        out.worst_degrees = std::max(out.worst_degrees, worst);
        REQUIRE(worst < 1.0);
        // Algorithm 2's kernel-space Lambert term is the world-space one.
        REQUIRE(krs::dot(k_space.normal, k_space.light) == doctest::Approx(krs::dot(from_locate, light)).epsilon(1e-9));
    }
    return out;
}

} // namespace

TEST_CASE("normals from the kernel-space transform match the field gradient on a tree and a forest")
{
    krs::model::tree_style style;
    style.levels = 8;
    style.leaves_per_twig = 3;
    style.leaf_radius = 0.08f;
    style.ground_height.reset();
    const auto tree = krs::model::build_tree(krs::model::grow_tree(style));
    const normal_statistics on_tree = compare_normals(tree, tree.bound(), 6000, 1);

    krs::model::forest_parameters f;
    f.tree = style;
    f.tree.levels = 7;
    f.tree.seed = 4;
    f.doublings = 3;
    f.ground_height.reset();
    const krs::model::forest forest = krs::model::build_forest(f);
    const normal_statistics on_forest = compare_normals(forest.sequence, forest.bound, 8000, 2);

    MESSAGE("tree: " << on_tree.compared << " of " << on_tree.hits << " hits compared, worst "
                     << on_tree.worst_degrees << " deg; forest: " << on_forest.compared << " of " << on_forest.hits
                     << ", worst " << on_forest.worst_degrees << " deg");
    const int hits = on_tree.hits + on_forest.hits, compared = on_tree.compared + on_forest.compared;
    CHECK(compared >= 10000);
    CHECK(compared >= 0.9 * hits);
    CHECK(on_tree.compared >= 0.9 * on_tree.hits);
    CHECK(on_forest.compared >= 0.9 * on_forest.hits);
}

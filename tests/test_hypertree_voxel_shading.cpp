// Voxel shading (hypertree/render/voxel_shading.hpp) against closed forms: the opacity law, its
// composition over split steps, and the lit color of a voxel on constructed geometry.

#include "hypertree/render/voxel_shading.hpp"
#include "hypertree/store/index_list_store.hpp"

#include <doctest/doctest.h>

#include <cmath>

using namespace hypertree;

TEST_CASE("voxel shading: the opacity table is 1 - (1 - mu)^(k x step factor), and two half steps dim as one whole")
{
    for (float k : {0.5f, 1.0f, 2.5f}) {
        for (float step : {1.0f, 0.5f, 2.0f}) {
            march_options o;
            o.density_scale = k, o.step_factor = step;
            const auto alpha = opacity_table(o);
            CAPTURE(k);
            CAPTURE(step);
            CHECK(alpha[0] == 0.0f);
            CHECK(alpha[255] == 1.0f);
            for (int d = 1; d < 255; ++d) {
                const double mu = d / 255.0;
                // Closed forms at exponents 1 and 2, the general law elsewhere.
                const double e = double(k) * double(step);
                const double expect = e == 1.0 ? mu : e == 2.0 ? mu * (2 - mu) : 1 - std::pow(1 - mu, e);
                REQUIRE(alpha[std::size_t(d)] == doctest::Approx(expect).epsilon(1e-6));
                REQUIRE(alpha[std::size_t(d)] >= alpha[std::size_t(d - 1)]); // (equal once float rounds both to 1)
            }
            // Transmittance over one voxel side does not depend on how it is cut into steps.
            march_options half = o;
            half.step_factor = step / 2;
            const auto a_half = opacity_table(half);
            for (int d = 0; d < 255; ++d) {
                const double two = (1.0 - a_half[std::size_t(d)]) * (1.0 - a_half[std::size_t(d)]);
                REQUIRE(two == doctest::Approx(1.0 - alpha[std::size_t(d)]).epsilon(1e-5));
            }
        }
    }
}

TEST_CASE("voxel shading: a voxel's lit color is base x (ambient falloff + wrapped Lambert x shadow), plus Blinn-Phong")
{
    march_options o;
    o.ambient = 0.3f, o.ambient_falloff = 2.0f, o.diffuse = 0.8f, o.specular = 0.5f, o.shininess = 8.0f;
    o.lights = {directional_light{{0, 2, 0}, {1.0f, 0.5f, 0.25f}}}; // (normalized to (0, 1, 0))
    tree_shape shape;
    shape.crown.center = {1, 1, 1};
    shape.crown.radius = 2;
    const rgb base{0.2f, 0.6f, 0.4f};
    const depth_colors colors({{0, 7, base, base}});
    const voxel_shading shading(o, shape, colors);
    REQUIRE(shading.light_directions().size() == 1);
    CHECK(shading.light_directions()[0].y == 1.0f);
    const float shadow = 0.5f;
    // At distance 1 from the crown's center: depth (2 - 1) / 2 = 1/2 of a radius below it.
    const krs::vec3f q{1, 1, 2};
    const double ambient = 0.3 * std::exp(-2.0 * 0.5);
    struct normal_case {
        krs::vec3d n;
        double lambert; // max(0, n.l) x 3/4 + 1/4, or 1 without a normal
    };
    const double c60 = std::cos(3.14159265358979 / 3);
    for (const normal_case& c : {normal_case{{0, 1, 0}, 1.0}, normal_case{{0, -1, 0}, 0.25}, normal_case{{1, 0, 0}, 0.25},
                                 normal_case{{0, c60, std::sin(3.14159265358979 / 3)}, 0.5 * 0.75 + 0.25}, normal_case{{0, 0, 0}, 1.0}}) {
        const rgb got = shading.lit(q, 3, &shadow, c.n);
        const double light_r = ambient + 0.8 * c.lambert * 0.5 * 1.0, light_g = ambient + 0.8 * c.lambert * 0.5 * 0.5,
                     light_b = ambient + 0.8 * c.lambert * 0.5 * 0.25;
        INFO("normal " << c.n.x << " " << c.n.y << " " << c.n.z);
        CHECK(got.r == doctest::Approx(0.2 * light_r).epsilon(1e-6));
        CHECK(got.g == doctest::Approx(0.6 * light_g).epsilon(1e-6));
        CHECK(got.b == doctest::Approx(0.4 * light_b).epsilon(1e-6));
    }
    // Outside the crown there is no falloff: ambient alone with no light.
    march_options dark = o;
    dark.lights.clear();
    const rgb outside = voxel_shading(dark, shape, colors).lit({1, 4, 1}, 0, nullptr, {});
    CHECK(outside.g == doctest::Approx(0.6 * 0.3).epsilon(1e-6));
    // Blinn-Phong: viewer and light both along n, so the half-vector is n: specular x shadow.
    const rgb with = shading.with_specular({0, 0, 0}, {0, 1, 0}, {0, 1, 0}, &shadow);
    CHECK(with.r == doctest::Approx(0.5 * 0.5 * 1.0).epsilon(1e-6));
    CHECK(with.b == doctest::Approx(0.5 * 0.5 * 0.25).epsilon(1e-6));
    // Viewer at 90 degrees from the light around n = (0, 1, 0): h at 45 degrees, cos^8.
    const rgb tilted = shading.with_specular({0, 0, 0}, {0, 1, 0}, {1, 0, 0}, &shadow);
    CHECK(tilted.r == doctest::Approx(0.5 * std::pow(std::sqrt(0.5), 8.0) * 0.5).epsilon(1e-5));
}

TEST_CASE("voxel shading: level_count is one more than the deepest stored level")
{
    const hypervolume v({0, 0, 0}, {1, 1, 1}, resolution::cube(16));
    CHECK(level_count(voxel_bricks(index_list_store::build(v, {}))) == 1);
    const std::vector<stored_voxel> voxels{{v.index(15, 0, 0), {1, 2}, 0}, {v.index(1, 2, 3), {10, 4}, 0}, {v.index(9, 9, 9), {200, 11}, 0}};
    CHECK(level_count(voxel_bricks(index_list_store::build(v, voxels))) == 12);
}

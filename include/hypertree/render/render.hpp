#pragma once
// Rendering a hypertree image: camera rays through every pixel, supersampled with jittered
// samples (paper section 8.4), marched by volume_marcher as scalar rays or SIMD packets, and
// composited over a background.
//
// Supersampling: s x s samples per pixel, each at a jittered position inside its sub-cell (the
// jitter is a hash of pixel and sample, so renders are deterministic and the scalar and packet
// paths trace the same rays). The paper's estimate of the factor needed is
// s = ceil(sqrt(area(pixel) / area(voxel projection))): `supersampling_for` computes it for a
// voxel of the tree's smallest side at the distance of the tree's center.
//
// Bands of rows_per_band rows are the unit of work: `parallel_for(bands, body)` may run them on
// any threads (the library starts none); an empty function renders serially.
//
// Packets of rays without supersampling or a ray cache take tiles of pixels (4 x 4 at 16 lanes)
// rather than runs of a row: the rays of a tile stay together through the tree, so a packet ends
// its march nearer the time its first lane does. One lane's march depends on its own ray alone, so
// the pixels are the rows' bit for bit (tested against the scalar marcher's rows).

#include "hypertree/execution.hpp"
#include "hypertree/render/marcher.hpp"
#include "krs/trace/camera.hpp"

#include <algorithm>
#include <array>
#include <atomic>
#include <cmath>
#include <cstdint>
#include <functional>
#include <optional>
#include <vector>

namespace hypertree {

struct image {
    int width = 0, height = 0;
    std::vector<float> rgb; // row-major from the top-left, 3 floats per pixel, linear
    std::uint64_t lookups = 0;
};

struct render_settings {
    int supersampling = 1; // s: s * s samples per pixel
    rgb background{0.78f, 0.86f, 0.95f};
    bool ray_cache = false; // scalar marcher only
    // With shade_per_voxel: shade every non-empty voxel before the rays, a packet of shadow rays
    // at a time on all threads (volume_marcher::shade_bricks), instead of each voxel when a ray
    // first meets it. Ahead is faster when the view shows most of the tree (tree A at resolution
    // 300: see bench_hypertree_render); a close view of a small part may prefer off. Pixels are
    // the same either way.
    bool shade_ahead = true;
    // Under flat shading (voxel_shading::flat: no lights, no ambient falloff) packets march in step
    // and gather colors by level; true shades each sample lane by lane instead (march_context's
    // shade_each_sample: the reference, for tests and benchmarks). The same pixels either way.
    bool shade_each_sample = false;
    parallel_for_hook parallel_for;
};

// s = ceil(sqrt(area(pixel) / area(projection))) for the smallest voxel side at distance d.
inline int supersampling_for(const krs::pinhole_camera& camera, const tree_shape& shape, const hypervolume& volume)
{
    const double distance = krs::length(krs::vec3d(shape.crown.center) - krs::vec3d(camera.eye()));
    const double pixel_side = camera.pixel_size_at(distance); // world side of a center pixel there
    const double voxel_side = volume.smallest_voxel_side();
    // Clamped in double to render()'s range before the conversion (far away the quotient passed
    // INT_MAX, which is undefined as an int).
    return int(std::clamp(std::ceil(pixel_side / voxel_side - 1e-9), 1.0, 16.0));
}

// A camera that frames a tree: it looks at the center of the box (the tree's non-empty cells,
// tree_shape::box) from the front, a little to the right and above, from the nearest distance at
// which all eight corners of the box project inside the image with a 4% margin. (The same view
// serves the example and the benchmarks.)
//
// For a corner at offset x from the center, seen from the eye at center - D f (f the view
// direction, r and u the image axes), it projects inside when |x.r| <= t_h (x.f + D) and
// |x.u| <= t_v (x.f + D), t the tangents of the half-angles: D is the largest of
// |x.r| / t_h - x.f and |x.u| / t_v - x.f over the corners.
inline krs::pinhole_camera framing_camera(const world_box& box, int width, int height, float vertical_fov_degrees = 40)
{
    // First, so a field of view of 0 is named as such (its distance came out infinite and the
    // camera's eye was blamed).
    krs::require_finite("framing_camera.vertical_fov_degrees", vertical_fov_degrees);
    if (!(vertical_fov_degrees > 0.0f && vertical_fov_degrees < 180.0f))
        throw krs::invalid_parameter("framing_camera.vertical_fov_degrees", "must be in (0, 180)",
                                     krs::detail::to_text(vertical_fov_degrees));
    const vec3d center = (box.lo + box.hi) * 0.5, extent = box.hi - box.lo;
    if (!(extent.x > 0 && extent.y > 0 && extent.z > 0))
        throw krs::invalid_parameter("framing_camera.box", "must hold at least one voxel (the tree is empty)");
    if (width < 1 || height < 1)
        throw krs::invalid_parameter("framing_camera.size", "width and height must be >= 1", std::to_string(width) + "x" + std::to_string(height));
    const vec3d forward = krs::normalize(vec3d{-0.45, -0.2, 1.0});
    const vec3d right = krs::normalize(krs::cross(forward, vec3d{0, 1, 0})), up = krs::cross(right, forward);
    const double tan_v = std::tan(0.5 * double(vertical_fov_degrees) * 3.14159265358979 / 180.0) / 1.04;
    const double tan_h = tan_v * double(width) / double(height);
    double distance = 0;
    for (int c = 0; c < 8; ++c) {
        const vec3d x = vec3d{(c & 1) ? box.hi.x : box.lo.x, (c & 2) ? box.hi.y : box.lo.y, (c & 4) ? box.hi.z : box.lo.z} - center;
        const double along = krs::dot(x, forward);
        distance = std::max({distance, std::abs(krs::dot(x, right)) / tan_h - along, std::abs(krs::dot(x, up)) / tan_v - along});
    }
    const vec3d eye = center - forward * distance;
    return krs::pinhole_camera(krs::vec3f(eye), krs::vec3f(center), {0, 1, 0}, vertical_fov_degrees, width, height);
}

namespace detail {
// A jitter in [0, 1) from (pixel x, pixel y, sample, axis): one round of a 32-bit integer mixer.
inline float jitter(std::uint32_t x, std::uint32_t y, std::uint32_t sample, std::uint32_t axis)
{
    std::uint32_t h = x * 0x8da6b343u ^ y * 0xd8163841u ^ sample * 0xcb1ab31fu ^ axis * 0x165667b1u;
    h ^= h >> 16, h *= 0x7feb352du, h ^= h >> 15, h *= 0x846ca68bu, h ^= h >> 16;
    return float(h >> 8) * 0x1.0p-24f;
}
} // namespace detail

// Rows per task of a render (see the end of render()).
inline constexpr std::size_t rows_per_band = 8;

template <class T = float>
image render(const volume_marcher& marcher, const krs::pinhole_camera& camera, const render_settings& settings = {})
{
    if (settings.supersampling < 1 || settings.supersampling > 16)
        throw krs::invalid_parameter("render_settings.supersampling", "must be in [1, 16]", std::to_string(settings.supersampling));
    require_color("render_settings.background", settings.background);
    constexpr std::size_t lanes = krs::lane_count<T>;
    const int w = camera.width(), h = camera.height(), s = settings.supersampling;
    image out;
    out.width = w, out.height = h;
    out.rgb.assign(std::size_t(w) * std::size_t(h) * 3, 0.0f);
    std::vector<std::uint64_t> row_lookups(std::size_t(h), 0);
    // The shading memo (shade_memo.hpp), shared by the call's threads, so that a voxel's shadow
    // rays are marched about once whatever the thread count. It is made for each call (every
    // render pays for its shading, and timings compare). It only holds pure functions of voxels:
    // which thread renders which row changes nothing.
    const march_options& options = marcher.options();
    std::optional<shade_memo> memo;
    // (Flat shading marching in step reads no memo: its colors come by level.)
    const bool in_step_flat = marcher.marches_flat_in_step(std::floating_point<T> && settings.ray_cache, settings.shade_each_sample);
    if (options.shade_per_voxel && !in_step_flat) memo.emplace(marcher.new_shade_memo());
    std::atomic<std::uint64_t> shading_lookups{0};
    if (memo && settings.shade_ahead) {
        // Runs of 64 bricks (about 700 voxels in tree A) per task.
        constexpr std::size_t bricks_per_task = 64;
        const std::size_t tasks = (marcher.bricks().brick_count() + bricks_per_task - 1) / bricks_per_task;
        const auto shade_task = [&](std::size_t task) {
            shading_lookups += marcher.template shade_bricks<krs::packet_f>(*memo, task * bricks_per_task, (task + 1) * bricks_per_task);
        };
        run_tasks(settings.parallel_for, tasks, shade_task);
        memo->seal(); // the threads that shaded are done: rays read the table directly
    }
    // A band's buffers, reused row after row (made per row, their allocations were 5 per row).
    struct row_buffers {
        std::vector<float> px, py, cr, cg, cb;
    };
    const auto render_row = [&](std::size_t row, row_buffers& buffers) {
        const int y = int(row);
        ray_cache cache;
        // Every sample ray of the row, in order; packets take them `lanes` at a time. Without
        // supersampling sample i is pixel i's centre, made where its packet is (below); with it
        // the jittered positions are listed first.
        const std::size_t count = std::size_t(w) * std::size_t(s * s);
        std::vector<float>&px = buffers.px, &py = buffers.py, &cr = buffers.cr, &cg = buffers.cg, &cb = buffers.cb;
        if (s > 1) {
            px.resize(count), py.resize(count);
            for (int x = 0; x < w; ++x)
                for (int j = 0; j < s * s; ++j) {
                    const std::size_t i = std::size_t(x) * std::size_t(s * s) + std::size_t(j);
                    const int sx = j % s, sy = j / s;
                    px[i] = float(x) + (float(sx) + detail::jitter(std::uint32_t(x), std::uint32_t(y), std::uint32_t(j), 0)) / float(s);
                    py[i] = float(y) + (float(sy) + detail::jitter(std::uint32_t(x), std::uint32_t(y), std::uint32_t(j), 1)) / float(s);
                }
        }
        cr.resize(count), cg.resize(count), cb.resize(count);
        // Packets go to the marcher `group` at a time (marching several at once hides the latency
        // of each one's lookups: volume_marcher::march_in_step; four gave 5-13% less CPU than two
        // on tree A at resolution 100, one thread); the last ones repeat the last ray.
        constexpr std::size_t group = 4, rays_per_group = group * lanes;
        const float row_centre = float(y) + 0.5f;
        for (std::size_t first = 0; first < count; first += rays_per_group) {
            std::array<krs::ray<T>, group> rays;
            for (std::size_t g = 0; g < group; ++g) {
                std::array<float, lanes> lx{}, ly{};
                if (s == 1) {
                    // (The pixel centres, as float(x) + 0.5f, computed in place of being listed.)
                    for (std::size_t l = 0; l < lanes; ++l)
                        lx[l] = float(std::int32_t(std::min(first + g * lanes + l, count - 1))) + 0.5f, ly[l] = row_centre;
                } else {
                    for (std::size_t l = 0; l < lanes; ++l) {
                        const std::size_t i = std::min(first + g * lanes + l, count - 1);
                        lx[l] = px[i], ly[l] = py[i];
                    }
                }
                T tx, ty;
                if constexpr (std::floating_point<T>)
                    tx = lx[0], ty = ly[0];
                else
                    tx = T::load_unaligned(lx.data()), ty = T::load_unaligned(ly.data());
                rays[g] = camera.primary_ray(tx, ty);
            }
            const std::array<march_result<T>, group> marched =
                marcher.template march_packets<T, group>(rays, march_context{settings.ray_cache ? &cache : nullptr, memo ? &*memo : nullptr,
                                                                           settings.shade_each_sample});
            for (std::size_t g = 0; g < group; ++g) {
                // Each lane's result, spilled once per packet.
                const march_result<T>& m = marched[g];
                const auto tr = krs::lanes_of(m.transmittance), mr = krs::lanes_of(m.r), mg = krs::lanes_of(m.g),
                           mb = krs::lanes_of(m.b), ml = krs::lanes_of(m.lookups);
                for (std::size_t l = 0; l < lanes && first + g * lanes + l < count; ++l) {
                    const std::size_t i = first + g * lanes + l;
                    cr[i] = mr[l] + tr[l] * settings.background.r;
                    cg[i] = mg[l] + tr[l] * settings.background.g;
                    cb[i] = mb[l] + tr[l] * settings.background.b;
                    row_lookups[row] += std::uint64_t(ml[l]);
                }
            }
        }
        const float inv = 1.0f / float(s * s);
        for (int x = 0; x < w; ++x) {
            float r = 0, g = 0, b = 0;
            for (int j = 0; j < s * s; ++j) {
                const std::size_t i = std::size_t(x) * std::size_t(s * s) + std::size_t(j);
                r += cr[i], g += cg[i], b += cb[i];
            }
            float* o = &out.rgb[(std::size_t(y) * std::size_t(w) + std::size_t(x)) * 3];
            o[0] = r * inv, o[1] = g * inv, o[2] = b * inv;
        }
    };
    // Without supersampling, packets take tiles of tile_cols x tile_rows pixels instead of runs of
    // a row: the rays of a tile stay closer together through the tree, so a packet's lanes end
    // nearer the same sample (a packet marches until its last lane is done) and its gathers touch
    // fewer bricks. Each lane still marches its own pixel's ray alone (its result does not depend
    // on the other lanes: march_packets), so the pixels are those of the rows, bit for bit (tested).
    constexpr std::size_t tile_rows = lanes >= 16 ? 4 : lanes >= 4 ? 2 : 1, tile_cols = lanes / tile_rows;
    static_assert(rows_per_band % tile_rows == 0, "a band is whole tiles high");
    const auto render_tiles = [&](std::size_t row0) {
        constexpr std::size_t group = 4;
        const std::size_t width = std::size_t(w), height = std::size_t(h);
        const float inv = 1.0f / float(s * s); // (1: the arithmetic of render_row's average, kept)
        for (std::size_t x0 = 0; x0 < width; x0 += group * tile_cols) {
            std::array<krs::ray<T>, group> rays;
            for (std::size_t g = 0; g < group; ++g) {
                std::array<float, lanes> lx{}, ly{};
                for (std::size_t l = 0; l < lanes; ++l) {
                    // Lanes past the image repeat its last column or row (their results are dropped).
                    const std::size_t x = std::min(x0 + g * tile_cols + l % tile_cols, width - 1), y = std::min(row0 + l / tile_cols, height - 1);
                    lx[l] = float(std::int32_t(x)) + 0.5f, ly[l] = float(std::int32_t(y)) + 0.5f;
                }
                if constexpr (std::floating_point<T>)
                    rays[g] = camera.primary_ray(lx[0], ly[0]); // (not taken: the scalar marcher keeps the rows)
                else
                    rays[g] = camera.primary_ray(T::load_unaligned(lx.data()), T::load_unaligned(ly.data()));
            }
            const std::array<march_result<T>, group> marched =
                marcher.template march_packets<T, group>(rays, march_context{nullptr, memo ? &*memo : nullptr, settings.shade_each_sample});
            for (std::size_t g = 0; g < group; ++g) {
                const march_result<T>& m = marched[g];
                const auto tr = krs::lanes_of(m.transmittance), mr = krs::lanes_of(m.r), mg = krs::lanes_of(m.g),
                           mb = krs::lanes_of(m.b), ml = krs::lanes_of(m.lookups);
                for (std::size_t l = 0; l < lanes; ++l) {
                    const std::size_t x = x0 + g * tile_cols + l % tile_cols, y = row0 + l / tile_cols;
                    if (x >= width || y >= height) continue;
                    // render_row's operations for s = 1: the sample's color over the background,
                    // then the average of one sample.
                    const float cr = mr[l] + tr[l] * settings.background.r, cg = mg[l] + tr[l] * settings.background.g,
                                cb = mb[l] + tr[l] * settings.background.b;
                    float r = 0, gr = 0, b = 0;
                    r += cr, gr += cg, b += cb;
                    float* o = &out.rgb[(y * width + x) * 3];
                    o[0] = r * inv, o[1] = gr * inv, o[2] = b * inv;
                    row_lookups[y] += std::uint64_t(ml[l]);
                }
            }
        }
    };
    // (The scalar marcher, a ray cache or supersampling keep the rows.)
    const bool tiled = !std::floating_point<T> && s == 1 && !settings.ray_cache;
    // Tasks are bands of rows, not rows: neighbouring rows meet the same voxels, whose bricks and
    // shading then stay in one core's cache.
    const std::size_t bands = (std::size_t(h) + rows_per_band - 1) / rows_per_band;
    run_tasks(settings.parallel_for, bands, [&](std::size_t band) {
        const std::size_t end = std::min(std::size_t(h), (band + 1) * rows_per_band);
        if (tiled) {
            for (std::size_t row = band * rows_per_band; row < end; row += tile_rows) render_tiles(row);
            return;
        }
        row_buffers buffers;
        for (std::size_t row = band * rows_per_band; row < end; ++row) render_row(row, buffers);
    });
    out.lookups = shading_lookups;
    for (auto n : row_lookups) out.lookups += n;
    return out;
}

} // namespace hypertree

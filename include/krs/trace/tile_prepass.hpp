#pragma once
// Tile prepass (paper section 4.1): one cheap march per screen tile gives every ray of the tile a
// start depth past empty space, so the rays skip the first steps they would all have taken alike.
//
// The tile's rays leave the eye inside a cone of half-angle a about the tile's axis. Let every
// ray of the cone be free (no point within the hit threshold of the surface) on [start_0, s].
// Evaluate the field at the axis point at depth c = s cos a, the axis point nearest to the cone's
// edge at depth s, which lies s sin a from it. Its unbounding sphere has radius d; shrink it to
//     r = d - threshold(c + d),
// so that every point inside is at least threshold(c + d) from the surface (the field is
// 1-Lipschitz), which is at least the threshold any ray applies there (its depth is <= c + d).
// If r >= s sin a, the shrunken sphere holds every ray's point at depth s (a ray at angle
// b <= a is s sqrt(1 + cos^2 a - 2 cos a cos b) <= s sin a from the center), and a ray at angle b
// leaves it at  c cos b + sqrt(r^2 - c^2 sin^2 b),  smallest at b = a (it falls as b grows). So
//     s <- c cos a + sqrt(r^2 - c^2 sin^2 a)
// keeps every ray free on [start_0, s]: a cone march whose each step is the paper's "sphere that
// covers the complete solid angle of the beam", with the exact covering condition r >= s sin a
// measured at the depth where the previous sphere left off. It stops when a sphere no longer
// covers the beam; s is then the tile's start depth, and no ray of the tile can have a hit (a
// point where plain sphere tracing would stop) before it.
//
// "A few more" spheres: the march goes on along the axis with plain sphere tracing for up to
// `extra_spheres` steps and stores those (shrunken) spheres. Rays near the axis pass through
// them; a ray walks them in order from its start and advances to the exit of each one that holds
// its current point, stopping at the first that does not. Walking per ray replaces the paper's
// eye-convex union: the paper needs convexity to rasterize the union as one depth, while a ray
// that checks each sphere itself only ever moves through sphere interiors, so it can never pass
// its first hit whatever shape the union has.

#include "krs/trace/camera.hpp"
#include "krs/trace/sphere_trace.hpp"

#include <array>
#include <cmath>

namespace krs {

struct tile_prepass {
    static constexpr int max_extra = 8;
    struct free_sphere {
        vec3f center;
        float radius;
    };
    float start = 0.0f;          // every ray of the tile is free up to this depth
    std::array<free_sphere, max_extra> extra{};
    int extra_count = 0;
    int evaluations = 0;         // field evaluations the prepass spent

    // The start depth of one ray of the tile (any lane type): the common start, then through the
    // stored spheres in order while the ray's current point is inside the next one.
    template <class T>
    T start_for(const ray<T>& r) const
    {
        T t(start);
        mask_t<T> inside = t == t; // all true
        for (int k = 0; k < extra_count && any(inside); ++k) {
            const vec3<T> c(extra[k].center);
            const T r2(extra[k].radius * extra[k].radius);
            const vec3<T> p = (r.origin - c) + r.direction * t; // the current point, from the centre
            const T p2 = length_squared(p);
            inside = inside && (p2 < r2);
            // Exit of the ray from the sphere: t + u for the larger root u of |p + u d|^2 = r^2.
            // Solved from the current point (|p| < r) rather than from the origin: there b^2 and
            // |origin - c|^2 are both about t^2 and cancel, and their float error (about eps t^2)
            // pushed exits past the sphere, so rays started inside the solid (4.6 million of a 4K
            // frame at a 5 degree field of view).
            const T b = dot(p, r.direction);
            const T disc = b * b + (r2 - p2);
            const T exit = t + (sqrt(max(disc, T(0))) - b);
            t = select(inside, max(t, exit), t);
        }
        return t;
    }
};

// Runs the prepass of the pixel rectangle [x0, x1) x [y0, y1) (see above). `options` are the
// primary rays' (threshold, min and max distance, max_steps bounds the march).
template <field F>
tile_prepass prepass_tile(const F& f, const pinhole_camera& camera, int x0, int y0, int x1, int y1,
                          const trace_options& options, int extra_spheres = 4)
{
    options.validate();
    const pinhole_camera::beam_cone beam = camera.beam(x0, y0, x1, y1);
    const float ca = beam.cos_half_angle, sa = beam.sin_half_angle;
    tile_prepass result;
    float s = options.min_distance;
    // The cone march needs a half-angle below 90 degrees (its sphere centres c = s cos a lie ahead
    // of the eye); a wider tile of a wide-angle camera starts at min_distance, and only the extra
    // spheres below, which each ray checks itself, move its rays on.
    const int cone_steps = ca > 0.0f ? options.max_steps : 0;
    for (int step = 0; step < cone_steps && s < options.max_distance; ++step) {
        const float c = s * ca;
        const float d = f.distance(point_at(beam.axis, c));
        ++result.evaluations;
        if (!(d < std::numeric_limits<float>::infinity())) break; // NaN or empty field: stop safely
        const float r = d - options.threshold(c + d);
        if (!(r >= s * sa)) break;
        const float next = c * ca + std::sqrt(std::max(r * r - c * c * sa * sa, 0.0f));
        // Rounding margin: the exit is pulled in by a relative 1e-6 so float error cannot push it out.
        const float safe = next - 1e-6f * next;
        if (!(safe > s * (1.0f + 1e-6f))) break;
        s = safe;
    }
    result.start = std::min(s, options.max_distance);
    // A few more spheres along the axis, for the rays near it.
    float t = result.start;
    extra_spheres = std::clamp(extra_spheres, 0, tile_prepass::max_extra);
    while (result.extra_count < extra_spheres && t < options.max_distance) {
        const vec3f c = point_at(beam.axis, t);
        const float d = f.distance(c);
        ++result.evaluations;
        if (!(d < std::numeric_limits<float>::infinity())) break;
        const float r = (d - options.threshold(t + d)) * (1.0f - 1e-6f);
        if (!(r > 0.0f)) break;
        result.extra[std::size_t(result.extra_count++)] = {c, r};
        t += d;
    }
    return result;
}

} // namespace krs

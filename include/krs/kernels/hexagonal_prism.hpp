#pragma once
// Hexagonal prism kernel: a regular hexagon of inradius `apothem` in the xy plane about `center`
// (flat sides facing +-y), extruded to +-half_height along z. (krs::placed turns or moves it.)
//
// The hexagon's 2D distance is exact by symmetry. Folding q = (|x|, |y|) keeps the distance (the
// hexagon is symmetric in both axes); then reflecting q across the line at 60 degrees, when q
// lies below it, maps angles t in [0, 60] to 120 - t, another symmetry (it swaps the edges of
// outward normal 30 and 90 degrees). Now q lies in the sector [60, 120] degrees, bounded by the
// rays through the two ends of the top edge y = a, |x| <= a / sqrt(3). Outside, the nearest point
// is on that edge (the neighbouring edges' regions, the strips normal to them, meet the sector
// only at its vertices), at x clamped to the edge; inside, the top edge is the nearest face
// (y >= q . (cos 30, sin 30) for angles in [60, 90]). So the 2D distance is
// |q - (clamp(x, -a / sqrt(3), a / sqrt(3)), a)| signed by y - a. The prism is the product of the
// hexagon and the interval |z| <= h, whose exact distance from the two exact ones d2 and
// dz = |z| - h is length(max((d2, dz), 0)) + min(max(d2, dz), 0): 1-Lipschitz, zero on the
// surface.
//
// apothem > 0, half_height > 0; center, apothem, half_height obey the magnitude policy.

#include "krs/core/bounds.hpp"
#include "krs/core/validate.hpp"

#include <array>
#include <cmath>
#include <string_view>

namespace krs {

class hexagonal_prism {
public:
    hexagonal_prism() : hexagonal_prism(vec3f{0, 0, 0}, 0.5f, 0.5f) {}
    hexagonal_prism(const vec3f& center, float apothem, float half_height)
        : center_(require_magnitude("hexagonal_prism.center", center)),
          apothem_(require_positive_length("hexagonal_prism.apothem", apothem)),
          half_height_(require_positive_length("hexagonal_prism.half_height", half_height)),
          half_edge_(static_cast<float>(double(apothem) / std::sqrt(3.0)))
    {
    }

    const vec3f& center() const { return center_; }
    float apothem() const { return apothem_; }
    float half_height() const { return half_height_; }

    // The same prism through the constructor's checks.
    hexagonal_prism checked() const { return hexagonal_prism(center_, apothem_, half_height_); }

    template <class T>
    T distance(const vec3<T>& p) const
    {
        const prism_section<T> s = section(p);
        const T ox = max(s.d2, T(0)), oz = max(s.dz, T(0));
        return sqrt(ox * ox + oz * oz) + min(max(s.d2, s.dz), T(0));
    }

    // Gradient: the hexagon's 2D gradient (toward p from its nearest edge point, unfolded) and z
    // combined as the extrusion's distance combines them; inside, the nearer of side and cap.
    template <class T>
    vec3<T> normal(const vec3<T>& p) const
    {
        const prism_section<T> s = section(p);
        const T ox = max(s.d2, T(0)), oz = max(s.dz, T(0));
        const T ol = sqrt(ox * ox + oz * oz);
        const auto outside = ol > T(0);
        const T safe = select(outside, ol, T(1));
        const auto side = s.d2 >= s.dz;
        const T g2 = select(outside, ox / safe, select(side, T(1), T(0)));
        const T gz = select(outside, oz / safe, select(side, T(0), T(1)));
        return {s.gx * g2, s.gy * g2, s.sz * gz};
    }

    // The ball through the hexagon's corners (circumradius 2 a / sqrt(3)) at the caps.
    bounding_sphere bound() const
    {
        const double r = 2.0 * double(half_edge_), h = half_height_;
        return bound_around(vec3d(center_), std::sqrt(r * r + h * h) * (1 + 1e-6));
    }
    // Exact: corners at x = +-2 a / sqrt(3), flat sides at y = +-a, caps at z = +-h; padded by
    // a relative 1e-6 for the float half edge.
    bounding_box bound_box() const
    {
        const vec3d c(center_), e{2.0 * double(half_edge_), double(apothem_), double(half_height_)};
        return intersect(box_around(c - e, c + e, 1e-6 * (e.x + e.z)), box_around(bound()));
    }

    // The colour a Shadertoy program and its reference shade this kind with where the caller
    // gives no palette (linear RGB; stone: basalt columns and tiles).
    static constexpr vec3f default_albedo{0.70f, 0.68f, 0.64f};
    // GLSL: the same distance and normal; two vec4s (center, apothem), (half height, half edge, 0, 0).
    static constexpr std::string_view glsl_name = "krs_hexagonal_prism";
    static constexpr std::string_view glsl_source = R"(// (2D distance, z distance, unfolded 2D gradient) of the hexagon and the caps.
vec4 krs_hexagonal_prism_section(vec3 p, vec4 h0, vec4 h1, out vec2 g) {
    vec3 l = p - h0.xyz;
    vec2 q = abs(l.xy);
    vec2 k = vec2(-0.86602540378443865, 0.5);
    float f = min(dot(q, k), 0.0);
    q -= 2.0 * f * k;
    vec2 o = q - vec2(clamp(q.x, -h1.y, h1.y), h0.w);
    float ol = length(o);
    float d2 = q.y > h0.w ? ol : -ol;
    vec2 u = q.y > h0.w ? o / ol : vec2(0.0, 1.0);
    u -= 2.0 * (f < 0.0 ? dot(u, k) : 0.0) * k;
    g = vec2(l.x < 0.0 ? -u.x : u.x, l.y < 0.0 ? -u.y : u.y);
    return vec4(d2, abs(l.z) - h1.x, l.z < 0.0 ? -1.0 : 1.0, 0.0);
}
float krs_hexagonal_prism_distance(vec3 p, vec4 h0, vec4 h1) {
    vec2 g;
    vec4 s = krs_hexagonal_prism_section(p, h0, h1, g);
    return length(max(s.xy, vec2(0.0))) + min(max(s.x, s.y), 0.0);
}
vec3 krs_hexagonal_prism_normal(vec3 p, vec4 h0, vec4 h1) {
    vec2 g;
    vec4 s = krs_hexagonal_prism_section(p, h0, h1, g);
    vec2 o = max(s.xy, vec2(0.0));
    float ol = length(o);
    vec2 w = ol > 0.0 ? o / ol : (s.x >= s.y ? vec2(1.0, 0.0) : vec2(0.0, 1.0));
    return vec3(g * w.x, s.z * w.y);
}
)";
    std::array<float, 8> glsl_parameters() const
    {
        return {center_.x, center_.y, center_.z, apothem_, half_height_, half_edge_, 0.0f, 0.0f};
    }

private:
    // The hexagon's signed 2D distance d2 with its unfolded unit gradient (gx, gy), the caps'
    // dz = |z| - h and the sign sz of z.
    template <class T>
    struct prism_section {
        T d2, dz, gx, gy, sz;
    };
    template <class T>
    prism_section<T> section(const vec3<T>& p) const
    {
        const vec3<T> l = p - vec3<T>(center_);
        T qx = abs(l.x), qy = abs(l.y);
        const T kx(-0.86602540378443865f), ky(0.5f); // the 60 degree line's normal
        const T f = min(qx * kx + qy * ky, T(0));
        qx = qx - T(2) * f * kx;
        qy = qy - T(2) * f * ky;
        const T a(apothem_), e(half_edge_);
        const T ox = qx - clamp(qx, -e, e), oy = qy - a;
        const T ol = sqrt(ox * ox + oy * oy);
        const auto beyond = qy > a;
        // Inside, the top edge's normal (0, 1); outside, away from its nearest point.
        const T safe = select(ol > T(0), ol, T(1));
        T ux = select(beyond, ox / safe, T(0)), uy = select(beyond, oy / safe, T(1));
        // Unfold: the reflection (where it was applied), then the signs.
        const T back = T(2) * select(f < T(0), ux * kx + uy * ky, T(0));
        ux = ux - back * kx;
        uy = uy - back * ky;
        prism_section<T> s;
        s.d2 = select(beyond, ol, -ol);
        s.dz = abs(l.z) - T(half_height_);
        s.gx = select(l.x < T(0), -ux, ux);
        s.gy = select(l.y < T(0), -uy, uy);
        s.sz = select(l.z < T(0), T(-1), T(1));
        return s;
    }

    vec3f center_{};
    float apothem_ = 0.5f, half_height_ = 0.5f;
    float half_edge_ = 0.28867513f; // apothem / sqrt(3), half an edge's length
};

} // namespace krs

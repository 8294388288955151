#pragma once
// Procedural bounding (paper section 4.2) and empty zones (section 6.4).
//
// bounded<F>: far from a sphere that holds all of F's geometry, the distance to that sphere is a
// free distance (the geometry is inside it, so no point of it is nearer), and it costs one length
// instead of a KRS walk. Within `margin` of the sphere the field itself is evaluated (and the
// larger of the two lower bounds kept). Tracing then starts with big cheap steps. Where the switch
// happens the value may jump, but only between two valid underestimates: the result never
// overestimates, which is all a sphere tracer needs.
//
// with_empty_zones<F>: unbounding spheres Z_j where F's geometry is removed, so part of a KRS can
// be replaced by user geometry (a tree of rigid bodies that can break). The geometry is G \ Z with
// Z the union of the open balls; its standard distance bound is the CSG difference
//     g(x) = max(f(x), -s(x)),   s(x) = min_j (|x - c_j| - r_j),
// conservative because f <= dist(., G), and for any q outside Z, -s(x) <= -s(q) + |x - q| <= |x - q|.
// Deep inside a zone (depth r_j - |x - c_j| above `skip_depth_fraction * r_j`) the field is not
// evaluated at all: -s(x) alone is a valid (smaller) bound, and a ray crossing the zone then takes
// big steps through it. The shell of skip depth near the boundary keeps the full max: there -s is
// small and g is f, so a ray leaving the zone does not stall on its boundary; only where G itself
// crosses the boundary is there a surface (the cut face), as the difference G \ Z requires.

#include "krs/core/bounds.hpp"
#include "krs/core/validate.hpp"
#include "krs/field.hpp"

#include <limits>
#include <string>
#include <utility>
#include <vector>

namespace krs {

template <field F>
class bounded {
public:
    // `bound` must hold all of f's geometry (checked only for finiteness and radius > 0);
    // `margin` >= 0 is how far outside the sphere the field itself starts to be evaluated.
    bounded(F f, const bounding_sphere& bound, float margin)
        : field_(std::move(f)), bound_(bound), margin_(require_non_negative("bounded.margin", margin))
    {
        require_finite("bounded.bound.center", bound_.center);
        require_positive("bounded.bound.radius", bound_.radius);
    }
    // Uses the field's own bound (a kernel's, a sequence's); it must be finite.
    template <class G = F>
        requires requires(const G& g) { { g.bound() } -> std::convertible_to<bounding_sphere>; }
    bounded(F f, float margin) : bounded(f, checked_bound(f), margin)
    {
    }

    const F& base() const { return field_; }
    const bounding_sphere& bound() const { return bound_; }

    template <class T>
    T distance(const vec3<T>& p) const
    {
        const T outside = length(p - vec3<T>(bound_.center)) - T(bound_.radius);
        const auto far = outside > T(margin_);
        if (all(far)) return outside;
        return select(far, outside, max(outside, field_.distance(p)));
    }

    // GLSL (krs/glsl/emitter.hpp): the field as NAME_base; (center, radius) and (margin, 0, 0, 0)
    // in the data; the same test and the same max as distance().
    template <class Out>
    void glsl_emit(Out& out, const std::string& name) const
    {
        out.field(field_, name + "_base");
        const std::size_t b = out.vec4({bound_.center.x, bound_.center.y, bound_.center.z, bound_.radius},
                                       name + " bound (center, radius)");
        const std::size_t m = out.vec4({margin_, 0.0f, 0.0f, 0.0f}, name + " (margin, 0, 0, 0)");
        out.function("float " + name + "(vec3 p) {\n"
                     "    vec4 b = " + out.at(b) + ";\n"
                     "    float outside = length(p - b.xyz) - b.w;\n"
                     "    if (outside > " + out.at(m) + ".x) return outside;\n"
                     "    return max(outside, " + name + "_base(p));\n}\n");
    }

private:
    static bounding_sphere checked_bound(const F& f)
    {
        const bounding_sphere b = f.bound();
        if (!b.is_bounded())
            throw invalid_parameter("bounded.bound", "the field is unbounded: pass a bounding sphere explicitly");
        return b;
    }
    F field_;
    bounding_sphere bound_;
    float margin_;
};

template <field F>
class with_empty_zones {
public:
    // zones: balls whose geometry is removed (radius > 0 each); skip_depth_fraction in (0, 1]:
    // deeper than this fraction of a zone's radius the field is skipped.
    with_empty_zones(F f, std::vector<bounding_sphere> zones, float skip_depth_fraction = 0.1f)
        : field_(std::move(f)), zones_(std::move(zones)), skip_(skip_depth_fraction)
    {
        for (std::size_t j = 0; j < zones_.size(); ++j) {
            const std::string name = "with_empty_zones.zones[" + std::to_string(j) + "]";
            require_finite(name + ".center", zones_[j].center);
            require_positive(name + ".radius", zones_[j].radius);
        }
        if (!(skip_ > 0.0f && skip_ <= 1.0f))
            throw invalid_parameter("with_empty_zones.skip_depth_fraction", "must be in (0, 1]", detail::to_text(skip_));
    }

    const F& base() const { return field_; }
    const std::vector<bounding_sphere>& zones() const { return zones_; }

    template <class T>
    T distance(const vec3<T>& p) const
    {
        using S = scalar_t<T>;
        T depth(-std::numeric_limits<S>::infinity()); // -s(x): depth inside the deepest zone
        auto deep = depth > T(0);                      // all false
        for (const bounding_sphere& z : zones_) {
            const T d = T(z.radius) - length(p - vec3<T>(z.center));
            depth = max(depth, d);
            deep = deep || (d > T(skip_ * z.radius));
        }
        if (all(deep)) return depth;
        return select(deep, depth, max(field_.distance(p), depth));
    }

    // GLSL (krs/glsl/emitter.hpp): the field as NAME_base; one vec4 (center, radius) per zone and
    // then (skip_depth_fraction, 0, 0, 0) in the data; the loop of distance() over the zones (with
    // no zone the field itself).
    template <class Out>
    void glsl_emit(Out& out, const std::string& name) const
    {
        out.field(field_, name + "_base");
        if (zones_.empty()) {
            out.function("float " + name + "(vec3 p) { return " + name + "_base(p); }\n");
            return;
        }
        std::size_t first = 0;
        for (std::size_t j = 0; j < zones_.size(); ++j) {
            const bounding_sphere& z = zones_[j];
            const std::size_t at =
                out.vec4({z.center.x, z.center.y, z.center.z, z.radius}, name + " zone " + std::to_string(j) + " (center, radius)");
            if (j == 0) first = at;
        }
        const std::size_t skip = out.vec4({skip_, 0.0f, 0.0f, 0.0f}, name + " (skip_depth_fraction, 0, 0, 0)");
        out.function("float " + name + "(vec3 p) {\n"
                     "    float depth = -3.0e38;\n" // below every zone's depth: the C++'s -infinity
                     "    bool deep = false;\n"
                     "    for (int j = 0; j < " + std::to_string(zones_.size()) + "; ++j) {\n"
                     "        vec4 z = " + out.data_name() + "[" + std::to_string(first) + " + j];\n"
                     "        float d = z.w - length(p - z.xyz);\n"
                     "        depth = max(depth, d);\n"
                     "        deep = deep || d > " + out.at(skip) + ".x * z.w;\n"
                     "    }\n"
                     "    if (deep) return depth;\n"
                     "    return max(" + name + "_base(p), depth);\n}\n");
    }

private:
    F field_;
    std::vector<bounding_sphere> zones_;
    float skip_;
};

} // namespace krs

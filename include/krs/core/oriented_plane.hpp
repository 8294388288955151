#pragma once
// An oriented plane n . x = c with |n| = 1: the shape a KRS `mirror`, the `plane` kernel and the
// KIFS `plane_fold` share. Each keeps its own public fields (their names are part of its API);
// what they had each written for themselves lives here once: the checks a constructor makes,
// the plane through a point, and the re-check of fields a user may have set by hand.
//
// Why the checks matter: every use divides nothing and multiplies by the normal, so a normal of
// length 2 doubles a fold's correction or a distance (which then overestimates), and a zero or
// non-finite one makes every value NaN. Errors name the owner's field ("mirror.normal",
// "plane.offset", ...), so the message points at what the user wrote.

#include "krs/core/validate.hpp"

#include <algorithm>
#include <string>
#include <string_view>

namespace krs {

struct oriented_plane {
    vec3f normal{0, 0, 1};
    float offset = 0.0f;

    // A normal of any non-zero length, normalized in double; an offset within the magnitude
    // policy (krs/core/validate.hpp). `owner` prefixes the field names in errors.
    static oriented_plane checked(std::string_view owner, const vec3f& normal, float offset)
    {
        return {require_direction(field(owner, "normal"), normal), require_magnitude(field(owner, "offset"), offset)};
    }

    // The plane through `point` with the given normal. |offset| <= |point| <= max_magnitude, up
    // to the few ulps by which the float normal's length differs from 1: the clamp absorbs those
    // (it moves the plane by about float's spacing at that distance). The offset is computed in
    // double from the stored normal, so `point` lies on the stored plane to within the rounding
    // of the offset.
    static oriented_plane through(std::string_view owner, const vec3f& point, const vec3f& normal)
    {
        const vec3d p(require_magnitude(field(owner, "point"), point));
        const vec3f n = require_direction(field(owner, "normal"), normal);
        const double c = std::clamp(dot(vec3d(n), p), -double(max_magnitude), double(max_magnitude));
        return {n, float(c)};
    }

    // Fields a user may have set by hand, through the same checks; a normal that is already unit
    // is kept bit for bit, so re-checking a built object changes nothing.
    static oriented_plane kept(std::string_view owner, const vec3f& normal, float offset)
    {
        return {require_direction_kept_if_unit(field(owner, "normal"), normal), require_magnitude(field(owner, "offset"), offset)};
    }

private:
    static std::string field(std::string_view owner, std::string_view name) { return std::string(owner) + "." + std::string(name); }
};

} // namespace krs

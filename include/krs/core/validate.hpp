#pragma once
// Parameter validation: bad input is rejected at construction with a message that names the
// parameter and says what was allowed (docs/design.md#rule-7). Nothing is half-built: constructors
// validate everything before they store anything, and throw krs::invalid_parameter.

#include "krs/core/vec3.hpp"

#include <algorithm>
#include <cmath>
#include <sstream>
#include <stdexcept>
#include <string>
#include <string_view>

namespace krs {

// Thrown for impossible parameters. what() reads "krs: <parameter>: <problem> (got <value>)".
// The parts stay available, so a caller that set the parameter from its own input (a definition
// file's keyword, a command-line option) can say the same in that input's words.
class invalid_parameter : public std::invalid_argument {
public:
    invalid_parameter(std::string_view parameter, std::string_view problem, std::string_view got = {})
        : std::invalid_argument("krs: " + compose(parameter, problem, got)), parameter_(parameter), problem_(problem), got_(got)
    {
    }
    const std::string& parameter() const noexcept { return parameter_; }
    const std::string& problem() const noexcept { return problem_; }
    const std::string& got() const noexcept { return got_; } // empty when the message gives no value
    // what() without its "krs: ", for a program or a file reader that puts its own name in front
    // (one prefix per message).
    std::string message() const { return compose(parameter_, problem_, got_); }

private:
    static std::string compose(std::string_view parameter, std::string_view problem, std::string_view got)
    {
        std::string s;
        s += parameter;
        s += ": ";
        s += problem;
        if (!got.empty()) {
            s += " (got ";
            s += got;
            s += ")";
        }
        return s;
    }
    std::string parameter_, problem_, got_;
};

namespace detail {
template <class S>
std::string to_text(S v)
{
    std::ostringstream o;
    o.precision(9);
    o << v;
    return o.str();
}
template <class S>
std::string to_text(const vec3<S>& v)
{
    return "(" + to_text(v.x) + ", " + to_text(v.y) + ", " + to_text(v.z) + ")";
}
} // namespace detail

// ---- magnitude policy ------------------------------------------------------------------------
//
// Every coordinate, offset, length and radius a kernel, mirror, fold step or builder accepts has
// magnitude <= max_magnitude (points: Euclidean length |v| <= max_magnitude), and every field built
// from such parameters returns a finite float distance at every query point with |p| <=
// max_magnitude. Why 1e9: float overflows at 3.4e38, so a squared length overflows once a vector
// is longer than 1.8e19, and a query point and a parameter of 1e9 stay far below that after
// everything the library does to them: 64 KRS folds move a point by at most 2 * 64 * 1e9
// (|p| <= 1.3e11, squared 1.7e22); a torus capsule squares its curvature times the point
// (curvature <= 2 / min_length = 2e6: (2.6e17)^2 = 6.8e34); a KIFS magnifies points by up to
// scale()^iterations, which its constructor bounds so they stay within what its kernel handles
// (1e19, less for a torus capsule: see kifs.hpp). Beyond 1e9 float cannot place geometry anyway:
// its spacing there is 64 units.
inline constexpr float max_magnitude = 1e9f; // exact in float (1953125 * 2^9)
// Lengths that a kernel divides by (a capsule's axis, a torus capsule's chord) are at least this
// when non-zero, so 1 / length^2 and curvature * |p| stay far from overflow at every point above.
// (At 1e-6 a chord is still ~16 float ulps long at distance 1 from the origin.)
inline constexpr float min_length = 1e-6f;

namespace detail {
// max_magnitude as messages print it (tests check the two agree).
inline constexpr std::string_view max_magnitude_text = "1e9";
inline std::string magnitude_range(bool include_zero, bool negative)
{
    const std::string limit(max_magnitude_text);
    if (negative) return "[-" + limit + ", " + limit + "]";
    return (include_zero ? "[0, " : "(0, ") + limit + "]";
}
} // namespace detail

template <std::floating_point S>
inline S require_finite(std::string_view name, S v)
{
    if (!std::isfinite(v)) throw invalid_parameter(name, "must be finite", detail::to_text(v));
    return v;
}
template <std::floating_point S>
inline vec3<S> require_finite(std::string_view name, const vec3<S>& v)
{
    if (!std::isfinite(v.x) || !std::isfinite(v.y) || !std::isfinite(v.z))
        throw invalid_parameter(name, "must have finite components", detail::to_text(v));
    return v;
}
template <std::floating_point S>
inline S require_non_negative(std::string_view name, S v)
{
    require_finite(name, v);
    if (v < S(0)) throw invalid_parameter(name, "must be >= 0", detail::to_text(v));
    return v;
}
template <std::floating_point S>
inline S require_positive(std::string_view name, S v)
{
    require_finite(name, v);
    if (!(v > S(0))) throw invalid_parameter(name, "must be > 0", detail::to_text(v));
    return v;
}
// A coordinate or offset: finite and in [-max_magnitude, max_magnitude].
template <std::floating_point S>
inline S require_magnitude(std::string_view name, S v)
{
    if (!std::isfinite(v) || !(std::abs(double(v)) <= double(max_magnitude)))
        throw invalid_parameter(name, "must be finite and in " + detail::magnitude_range(true, true), detail::to_text(v));
    return v;
}
// A point or offset vector: finite components and |v| <= max_magnitude (Euclidean, so a plane
// through it has |offset| <= max_magnitude as well).
template <std::floating_point S>
inline vec3<S> require_magnitude(std::string_view name, const vec3<S>& v)
{
    require_finite(name, v);
    if (!(length(vec3d(v)) <= double(max_magnitude)))
        throw invalid_parameter(name, "must be finite and lie within " + std::string(detail::max_magnitude_text) + " of the origin",
                                detail::to_text(v));
    return v;
}
// A length or radius that may be 0: in [0, max_magnitude].
template <std::floating_point S>
inline S require_length(std::string_view name, S v)
{
    if (!std::isfinite(v) || !(v >= S(0) && double(v) <= double(max_magnitude)))
        throw invalid_parameter(name, "must be finite and in " + detail::magnitude_range(true, false), detail::to_text(v));
    return v;
}
// A length that must not be 0: in (0, max_magnitude].
template <std::floating_point S>
inline S require_positive_length(std::string_view name, S v)
{
    if (!std::isfinite(v) || !(v > S(0) && double(v) <= double(max_magnitude)))
        throw invalid_parameter(name, "must be finite and in " + detail::magnitude_range(false, false), detail::to_text(v));
    return v;
}

// A direction: finite and not (near) zero. Returns it normalized, computed in double so that a
// float normal is as close to unit length as float allows.
inline vec3f require_direction(std::string_view name, const vec3f& v)
{
    require_finite(name, v);
    const vec3d d(v);
    const double len = length(d);
    if (!(len > 1e-30)) throw invalid_parameter(name, "must be a non-zero direction", detail::to_text(v));
    return vec3f(d / len);
}

// A double direction: finite and not zero, returned unit. Scaled by its largest component first,
// so no square overflows or underflows (a normal of (0, 1e160, 0) had a length of infinity and
// became (0, 0, 0); one of (1e-170, 0, 0) a length of 0, refused as zero).
inline vec3d require_direction(std::string_view name, const vec3d& v)
{
    require_finite(name, v);
    const double scale = std::max({std::abs(v.x), std::abs(v.y), std::abs(v.z)});
    if (!(scale > 0)) throw invalid_parameter(name, "must be a non-zero direction", detail::to_text(v));
    const vec3d u = v / scale;
    return u / length(u);
}

// The same check for a direction that may already be unit (one a constructor normalized): kept
// as it is when its length is 1 to within a few float ulps, so rechecking a built object leaves
// it bit for bit the same; normalized as above otherwise.
inline vec3f require_direction_kept_if_unit(std::string_view name, const vec3f& v)
{
    require_finite(name, v);
    if (std::abs(length(vec3d(v)) - 1.0) <= 4e-7) return v;
    return require_direction(name, v);
}

} // namespace krs

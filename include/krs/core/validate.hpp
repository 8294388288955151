#pragma once
// Parameter validation: bad input is rejected at construction with a message that names the
// parameter and says what was allowed (DESIGN rule 7). Nothing is half-built: constructors
// validate everything before they store anything, and throw krs::invalid_parameter.

#include "krs/core/vec3.hpp"

#include <cmath>
#include <sstream>
#include <stdexcept>
#include <string>
#include <string_view>

namespace krs {

// Thrown for impossible parameters. what() reads "krs: <parameter>: <problem> (got <value>)".
class invalid_parameter : public std::invalid_argument {
public:
    invalid_parameter(std::string_view parameter, std::string_view problem, std::string_view got = {})
        : std::invalid_argument(compose(parameter, problem, got)), parameter_(parameter)
    {
    }
    const std::string& parameter() const noexcept { return parameter_; }

private:
    static std::string compose(std::string_view parameter, std::string_view problem, std::string_view got)
    {
        std::string s = "krs: ";
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
    std::string parameter_;
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
// A direction: finite and not (near) zero. Returns it normalized, computed in double so that a
// float normal is as close to unit length as float allows.
inline vec3f require_direction(std::string_view name, const vec3f& v)
{
    require_finite(name, v);
    const vec3d d(v);
    const double len = length(d);
    if (!(len > 1e-30)) throw invalid_parameter(name, "must be a non-zero direction", detail::to_text(v));
    const vec3d u = d / len;
    return vec3f{float(u.x), float(u.y), float(u.z)};
}

} // namespace krs

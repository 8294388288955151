#pragma once
// GLSL literals of C++ values: what every emitter (krs fields, the Shadertoy wrapper, hypertree
// volumes) writes its constants with, so a constant reads back in GLSL as the same float.

#include "krs/core/vec3.hpp"

#include <charconv>
#include <string>

namespace krs::glsl {

// Shortest decimal that reads back as the same float, always with a '.' or an exponent (a GLSL
// float literal). Callers validate their values finite, so no inf/NaN reaches here.
inline std::string float_literal(float v)
{
    char buffer[32];
    const auto result = std::to_chars(buffer, buffer + sizeof buffer, v);
    std::string s(buffer, result.ptr);
    if (s.find_first_of(".e") == std::string::npos) s += ".0";
    return s;
}

inline std::string vec3_literal(const vec3f& v)
{
    return "vec3(" + float_literal(v.x) + ", " + float_literal(v.y) + ", " + float_literal(v.z) + ")";
}

} // namespace krs::glsl

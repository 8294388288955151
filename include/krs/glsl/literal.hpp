#pragma once
// GLSL literals of C++ values: what every emitter (krs fields, the Shadertoy wrapper, hypertree
// volumes) writes its constants with, so a constant reads back in GLSL as the same float, and
// constant arrays of them. Templates of GLSL text are krs/glsl/names.hpp's `fill`.

#include "krs/core/vec3.hpp"

#include <charconv>
#include <cstddef>
#include <string>
#include <vector>

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

// `const float name[count] = float[count](...);`, eight to a line.
inline std::string float_array(const std::string& name, const float* values, std::size_t count)
{
    std::string s = "const float " + name + "[" + std::to_string(count) + "] = float[" + std::to_string(count) + "](";
    for (std::size_t i = 0; i < count; ++i) s += (i ? (i % 8 ? ", " : ",\n    ") : "") + float_literal(values[i]);
    return s + ");\n";
}
// `const vec3 name[n] = vec3[n](...);`, one to a line.
inline std::string vec3_array(const std::string& name, const std::vector<vec3f>& values)
{
    std::string s = "const vec3 " + name + "[" + std::to_string(values.size()) + "] = vec3[" + std::to_string(values.size()) + "](";
    for (std::size_t i = 0; i < values.size(); ++i) s += (i ? ",\n    " : "") + vec3_literal(values[i]);
    return s + ");\n";
}

} // namespace krs::glsl

#pragma once
// What a GLSL name may be, as the emitter and the shading types that name GLSL functions check it.
// String code only (no GL): krs/shade/texture.hpp includes it for triplanar_projection::pattern.

#include <string_view>

namespace krs::glsl {

// A letter, digit or _: what GLSL names are made of.
inline constexpr bool is_name_char(char c)
{
    return (c >= 'a' && c <= 'z') || (c >= 'A' && c <= 'Z') || (c >= '0' && c <= '9') || c == '_';
}

// Whether `n` can follow the prefix in a name: letters, digits and _, not starting with _ and
// without __ (the prefix's own _ and GLSL's reserved double underscore).
inline constexpr bool is_name_part(std::string_view n)
{
    bool ok = !n.empty() && n[0] != '_' && n.find("__") == std::string_view::npos;
    for (char c : n) ok = ok && is_name_char(c);
    return ok;
}

// Whether `n` can name a function of the user's shader that a snippet calls: a name part that
// does not start with a digit, outside the implementation's reserved gl_, and not starting with
// krs_ (the emitter renames every such word to options.prefix, so the call would silently name
// another function). GLSL's keywords and built-ins are not listed: the shader's compiler names them.
inline constexpr bool is_user_function_name(std::string_view n)
{
    return is_name_part(n) && !(n[0] >= '0' && n[0] <= '9') && !n.starts_with("gl_") && !n.starts_with("krs_");
}

} // namespace krs::glsl

#pragma once
// GLSL names and the one way GLSL text is templated, for both emitters (krs/glsl/emitter.hpp and
// hypertree/render/glsl.hpp) and every type whose GLSL names a function or a value of a request.
// String code only (no GL, nothing of the emitter), so hypertree's GLSL includes it alone.
//
// The template dialect (`fill`): a placeholder is a word of the text, GLSL's own kind of word
// (letters, digits, _), never a character GLSL lacks, so a template is GLSL that reads as the
// code it becomes and compiles as written when its placeholders are names. A word is replaced
// where it is a placeholder, and so is the head of a word that starts with a placeholder and
// then _ (NAME_view_depth: a request's helpers), or with a placeholder that itself ends in _
// (krs_: every global name of the krs text, renamed to the emitter's prefix on output). The
// longest placeholder that matches wins, so MAX_STEPS is never MAX's value followed by _STEPS.
// The emitter's text uses krs_ / KRS_ (the prefix, include guards in upper case); shading
// requests use upper-case placeholders (NAME, FIELD, HARDNESS, ...); hypertree's marcher NAME
// (the tree's prefixed name).

#include "krs/core/validate.hpp"

#include <cstddef>
#include <initializer_list>
#include <string>
#include <string_view>
#include <utility>

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

// Whether `p` can start every global name of the text: lower-case letters, digits and _, starting
// with a letter and ending with _ (prefix + name then never spells a keyword or built-in such as
// `in` or `mix`), without GLSL's reserved __ and outside the implementation's gl_. Lower case,
// because include guards carry the prefix in upper case: prefixes that differ only in case would
// share guards, and the second snippet's library would vanish.
inline constexpr bool is_prefix(std::string_view p)
{
    bool ok = p.size() >= 2 && p[0] >= 'a' && p[0] <= 'z' && p.back() == '_' && !p.starts_with("gl_") &&
              p.find("__") == std::string_view::npos;
    for (char c : p) ok = ok && is_name_char(c) && !(c >= 'A' && c <= 'Z');
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

// The rules above as checks of a parameter, each refusing with the rule in words.
inline void require_name_part(const char* parameter, const std::string& n)
{
    if (!is_name_part(n))
        throw invalid_parameter(parameter, "must be letters, digits and _, not starting with _ and without __ (it "
                                           "follows the prefix in GLSL names)", n);
}
inline void require_prefix(const char* parameter, const std::string& p)
{
    if (!is_prefix(p))
        throw invalid_parameter(parameter,
                                "must be lower-case letters, digits and _, start with a letter, end with _, not "
                                "start with gl_ and hold no __",
                                p);
}
inline void require_user_function_name(const char* parameter, const std::string& n)
{
    if (!is_user_function_name(n))
        throw invalid_parameter(parameter,
                                "must be a GLSL function name of the shader's: letters, digits and _, not "
                                "starting with a digit or _, without __, and not starting with gl_ (reserved) "
                                "or krs_ (the emitter renames such words to its prefix)",
                                n);
}

// ASCII letters to upper case: include guards are the guarded names so, and carry the prefix so.
inline std::string upper_case(std::string_view text)
{
    std::string upper(text);
    for (char& c : upper) c = c >= 'a' && c <= 'z' ? char(c - 'a' + 'A') : c;
    return upper;
}

// A placeholder and the text that replaces it.
using placeholder = std::pair<std::string_view, std::string>;

// `text` with its placeholders replaced (the dialect above).
inline std::string fill(std::string_view text, std::initializer_list<placeholder> values)
{
    std::string out;
    out.reserve(text.size() + text.size() / 8);
    for (std::size_t i = 0; i < text.size();) {
        if (!is_name_char(text[i])) {
            out += text[i++];
            continue;
        }
        std::size_t end = i;
        while (end < text.size() && is_name_char(text[end])) ++end;
        const std::string_view word = text.substr(i, end - i);
        const placeholder* hit = nullptr;
        for (const placeholder& v : values) {
            const std::size_t n = v.first.size();
            const bool head = !v.first.empty() && word.starts_with(v.first) &&
                              (word.size() == n || v.first.back() == '_' || word[n] == '_');
            if (head && (!hit || n > hit->first.size())) hit = &v;
        }
        if (!hit) out += word;
        else out.append(hit->second).append(word.substr(hit->first.size()));
        i = end;
    }
    return out;
}

} // namespace krs::glsl

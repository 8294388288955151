#pragma once
// GLSL emission of fields (docs/design.md#rule-4: GLSL is generated from the C++ types).
//
// Every field type carries its GLSL next to its C++. A kernel, mirror kind, fold step or warp
// is a *GLSL type* (see glsl_type below): the text of its functions and its parameters as one
// array. A field made of other fields (a sequence, a union, KIFS, ...) writes its own functions
// with `glsl_emit` (see glsl_composite), asking the emitter for its parts by recursion. The emitter
// itself only walks the types and keeps three streams, as a compiler would: the library (each
// GLSL type's functions, once, only for the types the scene uses), the data (the parameters) and
// the function bodies that tie them together.
//
//   krs::glsl::emitter e({.target = krs::glsl::target::glsl450});
//   e.add(tree, "tree");               // float krs_tree(vec3 p); krs_location krs_tree_locate(vec3 p);
//                                      // krs_kernel_shading krs_tree_shade(vec3 p, vec3 l, vec3 v, float e)
//   e.add_shading(krs::soft_shadow_options{}, "tree_shadow", "tree");
//                                      // float krs_tree_shadow(vec3 p, vec3 n, vec3 to_light)
//   std::string code = e.source();     // paste into a shader (e.source(true) adds #version)
//
// Safe to paste: every name the text declares at global scope (functions, structs, the data array
// and its block) starts with `options.prefix` (default krs_), the scene's function included, and
// every include guard with the prefix in upper case. A shader that already has `float tree(vec3)`
// or `uniform float terrain;` keeps them; one that uses names starting with the prefix picks another
// (`{.prefix = "forest_gen_"}`). Internally the text is written with krs_ and renamed on output.
//
// A KRS sequence is unrolled: its structure (level count, kernel kinds per level) is fixed in the
// code and its parameters are read from the data, so the same code serves both data modes.
//
// Data layout. All parameters are vec4s in one array (prefix + `options.data_name`, default krs_data):
// kernels and mirrors in the order the functions use them, each a fixed number of vec4s (see each
// type's comment), then what a composite computes (a sequence's level bounds for its early exit).
// Because the element is vec4, the layout is the same under std140 and std430: base alignment 16,
// array stride 16, no padding, element k at byte offset 16 k, components x, y, z, w at +0, +4, +8,
// +12. So the host buffer is exactly `emitter::data()` (float[4 N]).
//   - data_mode::constants: `const vec4 krs_data[N] = vec4[N](...);` baked into the code.
//   - data_mode::buffer, glsl330 / es300: `layout(std140) uniform krs_data_block { vec4 krs_data[N]; };`
//     bind it with glUniformBlockBinding + glBindBufferBase(GL_UNIFORM_BUFFER, ...).
//   - data_mode::buffer, glsl450: `layout(std430, binding = B) readonly buffer krs_data_block
//     { vec4 krs_data[N]; };` (B = options.binding), a shader storage buffer.
//   - data_mode::uniform_buffer, glsl450: `layout(std140, binding = B) uniform krs_data_block
//     { vec4 krs_data[N]; };`, a uniform buffer at an explicit binding, as Vulkan requires of every
//     block (for 330 and ES 3.00, which have no binding qualifier, the same as data_mode::buffer).
// Vulkan takes the glsl450 code of every mode (tests compile it to SPIR-V and run spirv-val).
// A host animates a scene without recompiling by packing a sequence of the same structure (same
// level count, same kernel kinds per level) with `pack(field)` and uploading it with
// glBufferSubData. `pack` and the emitter share one traversal, so offsets always agree.
//
// Reflection bits of `locate` are a uvec2: bit i of the 64-bit word is bit (i % 32) of
// component i / 32 (x the low word), as `location::reflections` on the CPU.

#include "krs/core/validate.hpp"
#include "krs/field.hpp"
#include "krs/glsl/literal.hpp"
#include "krs/glsl/names.hpp"

#include <algorithm>
#include <array>
#include <initializer_list>
#include <concepts>
#include <cstddef>
#include <cstdint>
#include <map>
#include <set>
#include <string>
#include <string_view>
#include <tuple>
#include <utility>
#include <type_traits>
#include <variant>
#include <vector>

namespace krs::glsl {

enum class target {
    glsl330,   // #version 330 core
    glsl450,   // #version 450 core
    es300,     // #version 300 es (WebGL 2), precision qualifiers
    shadertoy, // ES 3.00 as Shadertoy compiles it: no #version, constants only
};
enum class data_mode {
    constants,      // parameters baked into the code
    buffer,         // a uniform block (330, ES 3.00) or a shader storage buffer (450)
    uniform_buffer, // a uniform block, at binding options.binding in 450
};

struct options {
    glsl::target target = glsl::target::glsl450;
    data_mode mode = data_mode::constants;
    std::string data_name = "data";     // the vec4 array is prefix + data_name; its block + "_block"
    int binding = 0;                    // the block's binding for glsl450 buffers
    std::string prefix = "krs_";        // of every global name the text declares
    // A sequence's distance leaves its unrolled walk at the C++'s per-level early exit (same value,
    // less work far from the finer levels). Off writes the full walk: only for timing the exit.
    bool level_early_exit = true;
    bool distance_only = false;         // no _locate / _shade, no krs_location structs (a program
                                        // that shades by the gradient needs only the distance)
};

// The first name a GLSL text declares twice at global scope, or "" when none is. Global
// declarations are the lines that start at column 0 (the emitter indents everything inside a body
// or a block): `TYPE NAME(` functions, `[const] TYPE NAME[` or `NAME =` constants, `struct NAME`,
// and a block's name with the names declared inside it.
inline std::string twice_declared(std::string_view text)
{
    std::vector<std::string> names;
    const auto word_at = [&](std::size_t& i) {
        while (i < text.size() && text[i] == ' ') ++i;
        const std::size_t start = i;
        while (i < text.size() && is_name_char(text[i])) ++i;
        return std::string(text.substr(start, i - start));
    };
    bool in_block = false;
    for (std::size_t line = 0; line < text.size();) {
        std::size_t end = text.find('\n', line);
        if (end == std::string_view::npos) end = text.size();
        const std::string_view l = text.substr(line, end - line);
        std::size_t i = line;
        if (in_block) {
            if (l.starts_with("};")) in_block = false;
            else if (!l.empty() && l[0] == ' ') { // a member: TYPE NAME[N];
                word_at(i);
                names.push_back(word_at(i));
            }
        } else if (!l.empty() && is_name_char(l[0])) {
            if (l.starts_with("layout(")) { // layout(...) uniform|readonly buffer NAME {
                const std::size_t brace = l.find('{');
                std::size_t last = brace == std::string_view::npos ? l.size() : brace; // the name ends before it
                while (last > 0 && !is_name_char(l[last - 1])) --last;
                std::size_t first = last;
                while (first > 0 && is_name_char(l[first - 1])) --first;
                names.emplace_back(l.substr(first, last - first));
                in_block = brace != std::string_view::npos;
            } else {
                std::string first = word_at(i);
                if (first == "const" || first == "uniform") first = word_at(i);
                const std::string name = word_at(i);
                if (!name.empty()) names.push_back(name);
            }
        }
        line = end + 1;
    }
    std::set<std::string> seen;
    for (const std::string& n : names)
        if (!seen.insert(n).second) return n;
    return {};
}

inline std::string_view target_name(target t)
{
    switch (t) {
    case target::glsl330: return "330";
    case target::glsl450: return "450";
    case target::es300: return "es300";
    default: return "shadertoy";
    }
}
inline std::string_view mode_name(data_mode m)
{
    switch (m) {
    case data_mode::constants: return "constants";
    case data_mode::buffer: return "buffer";
    default: return "uniform buffer";
    }
}
inline std::string version_line(target t)
{
    switch (t) {
    case target::glsl330: return "#version 330 core\n";
    case target::glsl450: return "#version 450 core\n";
    case target::es300: return "#version 300 es\n";
    default: return "";
    }
}

// What a type needs to be emitted: its GLSL next to its C++. A *GLSL type* (`krs::glsl_type`,
// krs/field.hpp, which every kernel is) names its functions' prefix, their text and its
// parameters as whole vec4s.
template <glsl_type X>
inline constexpr std::size_t vec4s_of = [] {
    constexpr std::size_t floats = std::tuple_size_v<decltype(std::declval<const X&>().glsl_parameters())>;
    static_assert(floats % 4 == 0, "krs::glsl: glsl_parameters() must return whole vec4s (a multiple of 4 floats)");
    return floats / 4;
}();

// A field whose GLSL is one function: its source defines `float NAME_distance(vec3 p, vec4...)`
// (every kernel, and distance-only fields such as tetrahedron).
template <class F>
concept glsl_field = field<F> && glsl_type<F>;

class emitter;

// What emitter::record_kernels keeps of a composite's parts: the index of each part's first vec4
// in the data, in the composite's order, and each part's kind (its index in the composite's type
// list; empty where the parts have no kinds, as a KIFS program's steps).
struct recorded_parts {
    std::vector<std::size_t> at;
    std::vector<std::size_t> kinds;
};

// Shading functions: the GLSL of krs/shade/ (soft shadow, ambient occlusion, fractal noise,
// triplanar projection), compose/depth.hpp (depth output and the depth-buffer limit) and kernel uv,
// next to their C++. Each such type has a member
//     template <class Out> void glsl_shading(Out& out, const std::string& function, const std::string& field) const;
// that runs the type's own validate() (so a bad value is the C++'s error, with the C++'s parameter
// name) and then writes `... FUNCTION(...)` with its validated values baked in as constants named
// as the C++ members are. A type whose function reads a field added to the same emitter before
// says so with `static constexpr bool glsl_takes_field = true;`: soft shadow and ambient occlusion
// call `float FIELD(vec3 p)` (GLSL has no function parameters, so the emitter writes one such
// function per field asked for, rather than a macro or a generic by name), kernel uv reads the
// sequence FIELD's kernel parameters from the data. Users call emitter::add_shading.
template <class S>
concept glsl_shading = requires(const S& s, emitter& out, const std::string& n) { s.glsl_shading(out, n, n); };
// Whether add_shading needs a field for S (and refuses one for the other types).
template <class S>
inline constexpr bool glsl_takes_field = requires { requires S::glsl_takes_field; };

// A field made of other fields (a sequence, a union, a warp, KIFS, a log-spherical tiling or shell,
// bounded, empty zones) writes its own GLSL next to its C++: a member
//     template <class Out> void glsl_emit(Out& out, const std::string& name) const;
// that defines `float NAME(vec3 p)` through the emitter's writing interface (below: `field` for a
// part, `library`, `parameters`, `vec4`, `at`, `arguments`, `function`). Out is a template
// parameter so that the field's header needs nothing from krs/glsl/.
template <class F>
concept glsl_composite = field<F> && requires(const F& f, emitter& out, const std::string& name) { f.glsl_emit(out, name); };

// Instantiated for a type the emitter cannot write: the compiler's error names the type as this
// template's argument ("In instantiation of 'struct krs::glsl::type_without_glsl<...>'").
template <class X>
struct type_without_glsl {
    static_assert(sizeof(X) == 0, "krs::glsl: this type has no GLSL: give it glsl_name, glsl_source and "
                                  "glsl_parameters() (a kernel, mirror, fold step or warp) or glsl_emit (a "
                                  "composite field); the type is the template argument of type_without_glsl");
};
// Names X in the error when it is not a GLSL type (a fold step or warp that only has C++).
template <class X>
constexpr void require_glsl_type()
{
    if constexpr (!glsl_type<X>) (void)sizeof(type_without_glsl<X>);
}

class emitter {
public:
    explicit emitter(options o = {}) : options_(std::move(o))
    {
        if (options_.target == target::shadertoy && options_.mode != data_mode::constants)
            throw invalid_parameter("glsl.options.mode", "Shadertoy has no buffers: use data_mode::constants");
        require_prefix("glsl.options.prefix", options_.prefix);
        require_data_name(options_.data_name);
        array_ = std::string(internal_prefix) + options_.data_name;
    }

    const options& settings() const { return options_; }

    // Emits `float PREFIXNAME(vec3 p)` for any supported field (krs_tree for "tree"); for a KRS
    // sequence also PREFIXNAME_locate and PREFIXNAME_shade (Algorithm 2). Returns PREFIXNAME, the
    // name to call. `name` is letters, digits and _ (not starting with _, no __). A name that makes
    // one the library or an earlier field declares (add(f, "location") and the struct
    // krs_location; "mirror_fold"; a second "tree") is refused and the emitter is left as it was.
    template <class F>
    std::string add(const F& f, const std::string& name)
    {
        require_name("glsl.add.name", name);
        const emitter before = *this;
        field(f, std::string(internal_prefix) + name);
        refuse_twice_declared(before, "glsl.add.name", name);
        fields_.insert(name);
        return options_.prefix + name;
    }

    // Emits the shading function `s` (a glsl_shading type: soft_shadow_options,
    // ambient_occlusion_options, fractal_noise, triplanar_projection, depth_projection,
    // kernel_uv_glsl) as PREFIXNAME; returns that name. `field` names a field added before
    // (add(f, field)) for the types that read one (glsl_takes_field) and is refused for the others:
    // soft_shadow_options gives
    //     float PREFIXNAME(vec3 p, vec3 n, vec3 to_light)   calling PREFIXFIELD(p)
    // (each type's comment gives its signature). s.validate() runs first: a bad value throws the
    // C++'s invalid_parameter, and the emitter is left as it was.
    template <glsl_shading S>
    std::string add_shading(const S& s, const std::string& name, const std::string& field = {})
    {
        require_name("glsl.add_shading.name", name);
        if constexpr (glsl_takes_field<S>) {
            if (field.empty())
                throw invalid_parameter("glsl.add_shading.field", "this request reads a field: name one added before");
            if (!fields_.contains(field))
                throw invalid_parameter("glsl.add_shading.field", "must name a field added to this emitter before", field);
        } else if (!field.empty()) {
            throw invalid_parameter("glsl.add_shading.field", "this request takes no field (it samples none)", field);
        }
        const emitter before = *this;
        try {
            s.glsl_shading(*this, std::string(internal_prefix) + name,
                           field.empty() ? std::string() : std::string(internal_prefix) + field);
        } catch (...) {
            *this = before;
            throw;
        }
        refuse_twice_declared(before, "glsl.add_shading.name", name);
        return options_.prefix + name;
    }

    // The data array's and its block's names in the text (what a host binds by name).
    std::string array_name() const { return options_.prefix + options_.data_name; }
    std::string block_name() const { return array_name() + "_block"; }

    // The packed parameters, 4 floats per vec4, in the layout documented above.
    const std::vector<float>& data() const { return data_; }
    std::size_t vec4_count() const { return vec4_count_now(); }

    // The library, the data and the functions; with_version puts the #version line (and for
    // es300 / shadertoy nothing else changes) in front so the text compiles alone.
    std::string source(bool with_version = false) const
    {
        std::string out;
        if (with_version) out += version_line(options_.target);
        out += "// Generated by krs::glsl (target " + std::string(target_name(options_.target)) + ", " +
               std::string(mode_name(options_.mode)) + " mode). Do not edit.\n";
        if (options_.target == target::es300) out += "precision highp float;\nprecision highp int;\n";
        out += internal_text();
        return with_prefix(out, options_.prefix);
    }

    // The structs every locate / shade function returns (emitted once, in the library).
    static constexpr std::string_view common_library = R"(struct krs_location {
    float dist;        // distance to the nearest kernel (Algorithm 1)
    vec3 kernel_point; // the point carried into that kernel's space
    uint kernel;       // index into sequence::kernels()
    uint level;        // the kernel's level
    uvec2 reflections; // bit i (x: bits 0-31, y: bits 32-63) set when mirror i was applied
};
struct krs_kernel_shading {
    krs_location where;
    vec3 normal;       // the kernel's own outward unit normal at where.kernel_point
    vec3 light;        // world light direction carried into kernel space (Algorithm 2)
    vec3 view;         // world view direction carried into kernel space
    uint kind;         // index of the kernel's type in the sequence's type list
};
)";

    // ---- the writing interface of glsl_emit ------------------------------------------------
    // What a composite field's glsl_emit (see glsl_composite) writes with. Names and data indices
    // are the emitter's; the text is the field's.

    // Emits `float NAME(vec3 p)` for a part of a composite (any supported field).
    template <class F>
    void field(const F& f, const std::string& name)
    {
        if constexpr (glsl_composite<F>) {
            f.glsl_emit(*this, name);
        } else if constexpr (glsl_field<F>) {
            library<F>();
            const std::size_t k = parameters(f, name);
            functions_ += "float " + name + "(vec3 p) { return " + std::string(F::glsl_name) + "_distance(p" +
                          arguments<F>(k) + "); }\n";
        } else {
            (void)sizeof(type_without_glsl<F>);
        }
    }
    // X's glsl_source, once per shader (guarded, so two pasted snippets define it once too), after
    // the GLSL types it calls (a std::tuple of them in X::glsl_needs, e.g. value noise).
    template <class X>
    void library()
    {
        require_glsl_type<X>();
        if constexpr (requires { typename X::glsl_needs; })
            [this]<class... Needed>(std::tuple<Needed...>*) { (library<Needed>(), ...); }(
                static_cast<typename X::glsl_needs*>(nullptr));
        if (included_.insert(std::string(X::glsl_name)).second) library_ += guarded(X::glsl_name, X::glsl_source);
    }
    // Library text that is not a GLSL type's (a kernel's uv function), once per shader, guarded by
    // `name` as a type's is.
    void library_text(std::string_view name, std::string_view code)
    {
        if (included_.insert(std::string(name)).second) library_ += guarded(name, code);
    }
    // Appends x's glsl_parameters() to the data; returns the index of its first vec4. `what` is
    // the comment the data listing gets.
    template <class X>
    std::size_t parameters(const X& x, const std::string& what)
    {
        require_glsl_type<X>();
        const std::size_t index = vec4_count_now();
        if constexpr (vec4s_of<X> > 0) {
            const auto values = x.glsl_parameters();
            data_.insert(data_.end(), values.begin(), values.end());
            constants_comments_ += "// " + array_ + "[" + std::to_string(index) + "..." +
                                   std::to_string(index + vec4s_of<X> - 1) + "]: " + what + " (" +
                                   std::string(X::glsl_name) + ")\n";
        }
        return index;
    }
    // Appends one vec4 of values computed by the composite; returns its index.
    std::size_t vec4(const std::array<float, 4>& v, const std::string& what)
    {
        const std::size_t index = vec4_count_now();
        data_.insert(data_.end(), v.begin(), v.end());
        constants_comments_ += "// " + array_ + "[" + std::to_string(index) + "]: " + what + "\n";
        return index;
    }
    // The data element at `index`, as GLSL ("krs_data[7]").
    std::string at(std::size_t index) const { return array_ + "[" + std::to_string(index) + "]"; }
    // ", D[k], D[k+1], ...": X's parameters at index k, as the arguments after the point.
    template <class X>
    std::string arguments(std::size_t index) const
    {
        std::string s;
        for (std::size_t i = 0; i < vec4s_of<X>; ++i) s += ", " + at(index + i);
        return s;
    }
    // The data array's name as the composites write it (krs_..., renamed with the rest on output).
    const std::string& data_name() const { return array_; }
    // Records where a sequence named `name` put its kernels' parameters, for requests that read
    // them (kernel_uv_glsl). A KIFS program records its steps' parameters the same way under a key
    // with spaces (no name has one), so that its distance and its colouring share them
    // (krs/fractal/fold_steps.hpp).
    void record_kernels(const std::string& name, recorded_parts parts) { kernels_at_[name] = std::move(parts); }
    // What record_kernels recorded for `name`, or null.
    const recorded_parts* recorded_kernels(const std::string& name) const
    {
        const auto it = kernels_at_.find(name);
        return it == kernels_at_.end() ? nullptr : &it->second;
    }
    // Appends a function the composite wrote.
    void function(const std::string& text) { functions_ += text; }
    // A float as a GLSL literal that reads back as the same float.
    static std::string literal(float v) { return float_literal(v); }
    // glsl::fill (krs/glsl/names.hpp), the one template dialect, for a composite's or a shading
    // request's text: their headers reach it through Out and include nothing of krs/glsl/.
    static std::string fill(std::string_view text, std::initializer_list<placeholder> values)
    {
        return glsl::fill(text, values);
    }
    // glsl::require_user_function_name, for a request that calls a function of the user's shader.
    static void require_user_function_name(const char* parameter, const std::string& n)
    {
        glsl::require_user_function_name(parameter, n);
    }

    // `float NAME(vec3 p)` as the min of NAME_0 .. NAME_{count-1} in that order (the C++
    // `d = part0; d = min(d, part_i)`), for unions and fields made of parts.
    void minimum_of_parts(const std::string& name, std::size_t count)
    {
        if (count == 0) throw invalid_parameter("glsl.parts", "a union of parts must have at least one part", name);
        std::string body = "float " + name + "(vec3 p) {\n    float d = " + name + "_0(p);\n";
        for (std::size_t i = 1; i < count; ++i) body += "    d = min(d, " + name + "_" + std::to_string(i) + "(p));\n";
        functions_ += body + "    return d;\n}\n";
    }

private:
    // ---- names ------------------------------------------------------------------------------
    // The text is written with this prefix and renamed to options.prefix by with_prefix.
    static constexpr std::string_view internal_prefix = "krs_";

    static void require_name(const char* parameter, const std::string& n) { require_name_part(parameter, n); }
    static void require_data_name(const std::string& n) { require_name("glsl.options.data_name", n); }

    // A name the latest addition made twice (see twice_declared) puts the emitter back to `before`
    // and is refused, as the data name's fault when it is the data array's or block's.
    void refuse_twice_declared(const emitter& before, const char* parameter, const std::string& name)
    {
        const std::string again = twice_declared(internal_text());
        if (again.empty()) return;
        *this = before;
        if (again == array_ || again == array_ + "_block")
            throw invalid_parameter("glsl.options.data_name",
                                    "makes " + again + ", which the library or the field declares too: choose another",
                                    options_.data_name);
        throw invalid_parameter(parameter,
                                "makes " + again + ", which the library or an earlier field declares too: choose another",
                                name);
    }

    // The text with every word that starts with krs_ starting with `prefix` instead, and every one
    // that starts with KRS_ (include guards) with the prefix in upper case.
    static std::string with_prefix(const std::string& text, const std::string& prefix)
    {
        if (prefix == internal_prefix) return text;
        return glsl::fill(text, {{"krs_", prefix}, {"KRS_", upper_case(prefix)}});
    }
    // Everything after the version and precision lines, before renaming.
    std::string internal_text() const
    {
        return (options_.distance_only ? std::string() : guarded("KRS_GLSL_COMMON", common_library)) + library_ +
               data_declaration() + constants_comments_ + functions_;
    }

    // ---- data -----------------------------------------------------------------------------
    std::size_t vec4_count_now() const { return data_.size() / 4; }

    std::string data_declaration() const
    {
        const std::size_t n = vec4_count_now();
        if (n == 0) return {};
        const std::string size = std::to_string(n);
        if (options_.mode != data_mode::constants) {
            const std::string members = array_ + "_block {\n    vec4 " + array_ + "[" + size + "];\n};\n";
            const std::string binding = "binding = " + std::to_string(options_.binding);
            if (options_.target != target::glsl450) return "layout(std140) uniform " + members;
            if (options_.mode == data_mode::buffer) return "layout(std430, " + binding + ") readonly buffer " + members;
            return "layout(std140, " + binding + ") uniform " + members;
        }
        std::string s = "const vec4 " + array_ + "[" + size + "] = vec4[" + size + "](\n";
        for (std::size_t k = 0; k < n; ++k) {
            s += "    vec4(";
            for (int c = 0; c < 4; ++c) s += (c ? ", " : "") + float_literal(data_[4 * k + std::size_t(c)]);
            s += k + 1 < n ? "),\n" : "));\n";
        }
        return s;
    }

    // Library code is guarded by its name, so two snippets pasted into one shader define each
    // struct and function once (unguarded, the second krs_location was a redefinition).
    static std::string guarded(std::string_view name, std::string_view code)
    {
        const std::string macro = upper_case(name);
        return "#ifndef " + macro + "\n#define " + macro + "\n" + std::string(code) + "#endif\n";
    }

    options options_;
    std::string array_;              // the data array's name in the text, krs_ + data_name
    std::set<std::string> included_;
    std::set<std::string> fields_;   // the names add() was given
    std::string library_;            // each kind's functions, once
    std::string constants_comments_; // what each data entry holds
    std::string functions_;          // the bodies
    std::vector<float> data_;
    std::map<std::string, recorded_parts> kernels_at_;
};

// The data of `f` in the emitter's layout (std140 == std430 here): upload it to the block of code
// emitted in data_mode::buffer for a field of the same structure.
template <class F>
std::vector<float> pack(const F& f, const std::string& name = "krs")
{
    emitter e({target::glsl450, data_mode::buffer});
    e.add(f, name);
    return e.data();
}

// One field's code in one call.
template <class F>
std::string emit(const F& f, const std::string& name, const options& o = {}, bool with_version = false)
{
    emitter e(o);
    e.add(f, name);
    return e.source(with_version);
}

} // namespace krs::glsl

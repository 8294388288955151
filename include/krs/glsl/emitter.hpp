#pragma once
// GLSL emission of fields (docs/design.md#rule-4: GLSL is generated from the C++ types).
//
// Every kernel, mirror and warp type carries its GLSL next to its C++ (a `glsl_name`, the text of
// its functions `glsl_source`, its parameter count `glsl_vec4_count` and `glsl_constants(float*)`
// that writes them). The emitter walks a field's type by recursion and writes three streams, as a
// compiler would: the library (each kind's functions, once, only for the kinds the scene uses),
// the data (the parameters) and the function bodies that tie them together.
//
//   krs::glsl::emitter e({.target = krs::glsl::target::glsl450});
//   e.add(tree, "tree");               // float tree(vec3 p); krs_location tree_locate(vec3 p);
//                                      // krs_kernel_shading tree_shade(vec3 p, vec3 l, vec3 v, float e)
//   std::string code = e.source();     // paste into a shader (e.source(true) adds #version)
//
// A KRS sequence is unrolled: its structure (level count, kernel kinds per level) is fixed in the
// code and its parameters are read from the data, so the same code serves both data modes.
//
// Data layout. All parameters are vec4s in one array (`options.data_name`, default `krs_data`):
// kernels and mirrors in the order the functions use them, each a fixed number of vec4s (see each
// type's comment). Because the element is vec4, the layout is the same under std140 and std430:
// base alignment 16, array stride 16, no padding, element k at byte offset 16 k, components
// x, y, z, w at +0, +4, +8, +12. So the host buffer is exactly `emitter::data()` (float[4 N]).
//   - data_mode::constants: `const vec4 krs_data[N] = vec4[N](...);` baked into the code.
//   - data_mode::buffer, glsl330 / es300: `layout(std140) uniform krs_data_block { vec4 krs_data[N]; };`
//     bind it with glUniformBlockBinding + glBindBufferBase(GL_UNIFORM_BUFFER, ...).
//   - data_mode::buffer, glsl450: `layout(std430, binding = B) readonly buffer krs_data_block
//     { vec4 krs_data[N]; };` (B = options.binding), a shader storage buffer.
// A host animates a scene without recompiling by packing a sequence of the same structure (same
// level count, same kernel kinds per level) with `pack(field)` and uploading it with
// glBufferSubData. `pack` and the emitter share one traversal, so offsets always agree.
//
// Reflection bits of `locate` are a uvec2: bit i of the 64-bit word is bit (i % 32) of
// component i / 32 (x the low word), as `location::reflections` on the CPU.

#include "krs/compose/union.hpp"
#include "krs/compose/warp.hpp"
#include "krs/core/validate.hpp"
#include "krs/fractal/kifs.hpp"
#include "krs/fractal/log_spherical.hpp"
#include "krs/glsl/literal.hpp"
#include "krs/sequence.hpp"

#include <charconv>
#include <concepts>
#include <cstddef>
#include <cstdint>
#include <set>
#include <string>
#include <string_view>
#include <tuple>
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
enum class data_mode { constants, buffer };

struct options {
    glsl::target target = glsl::target::glsl450;
    data_mode mode = data_mode::constants;
    std::string data_name = "krs_data"; // the vec4 array; its block is data_name + "_block"
    int binding = 0;                    // SSBO binding for glsl450 buffers
};

inline std::string_view target_name(target t)
{
    switch (t) {
    case target::glsl330: return "330";
    case target::glsl450: return "450";
    case target::es300: return "es300";
    default: return "shadertoy";
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

// What a type needs to be emitted: its GLSL next to its C++.
template <class X>
concept glsl_parameters = requires(const X& x, float* out) {
    { X::glsl_name } -> std::convertible_to<std::string_view>;
    { X::glsl_source } -> std::convertible_to<std::string_view>;
    { X::glsl_vec4_count } -> std::convertible_to<int>;
    x.glsl_constants(out);
};
template <class K>
concept glsl_kernel = kernel<K> && glsl_parameters<K>;
// A field with GLSL of its own (every glsl_kernel, and distance-only fields such as tetrahedron):
// its source defines `float NAME_distance(vec3 p, vec4...)`.
template <class F>
concept glsl_field = field<F> && glsl_parameters<F>;
// A KIFS fold step: its source defines `vec3 NAME_apply(vec3 p, vec4...)`.
template <class S>
concept glsl_fold_step = fold_step<S> && glsl_parameters<S>;
// A field that is the min of parts, in the order it visits them (lotus_shell, cube_shell).
template <class F>
concept glsl_part_union = field<F> && requires(const F& f) { f.glsl_for_each_part([](const auto&) {}); };
template <class M>
concept glsl_mirror = mirror_kind<M> && glsl_parameters<M>;
template <class W>
concept glsl_warp = warp<W> && glsl_parameters<W>;

template <class F>
struct is_sequence : std::false_type {};
template <class M, class... K>
struct is_sequence<basic_sequence<M, K...>> : std::true_type {};
template <class F>
struct is_union : std::false_type {};
template <class... F>
struct is_union<union_of<F...>> : std::true_type {};
template <class F>
struct is_warp : std::false_type {};
template <class F, class W>
struct is_warp<lipschitz_warp<F, W>> : std::true_type {};
template <class F>
struct is_kifs : std::false_type {};
template <class P, class K>
struct is_kifs<kifs<P, K>> : std::true_type {};
template <class P>
struct is_fold_program : std::false_type {};
template <class... S>
struct is_fold_program<fold_program<S...>> : std::true_type {};
template <class F>
struct is_log_tiling : std::false_type {};
template <class T>
struct is_log_tiling<log_polar_tiling<T>> : std::true_type {};
template <class T>
struct is_log_tiling<log_spherical_tiling<T>> : std::true_type {};
template <class F>
struct is_similar_shell : std::false_type {};
template <class S>
struct is_similar_shell<similar_shell<S>> : std::true_type {};

class emitter {
public:
    explicit emitter(options o = {}) : options_(std::move(o))
    {
        if (options_.target == target::shadertoy && options_.mode == data_mode::buffer)
            throw invalid_parameter("glsl.options.mode", "Shadertoy has no buffers: use data_mode::constants");
        require_identifier(options_.data_name);
    }

    const options& settings() const { return options_; }

    // Emits `float NAME(vec3 p)` for any supported field; for a KRS sequence also NAME_locate and
    // NAME_shade (Algorithm 2). Returns NAME.
    template <class F>
    std::string add(const F& f, const std::string& name)
    {
        emit_field(f, name);
        require_unshadowed_data_name();
        return name;
    }

    // The packed parameters, 4 floats per vec4, in the layout documented above.
    const std::vector<float>& data() const { return data_; }
    std::size_t vec4_count() const { return data_.size() / 4; }

    // The library, the data and the functions; with_version puts the #version line (and for
    // es300 / shadertoy nothing else changes) in front so the text compiles alone.
    std::string source(bool with_version = false) const
    {
        std::string out;
        if (with_version) out += version_line(options_.target);
        out += "// Generated by krs::glsl (target " + std::string(target_name(options_.target)) + ", " +
               (options_.mode == data_mode::constants ? "constants" : "buffer") + " mode). Do not edit.\n";
        if (options_.target == target::es300) out += "precision highp float;\nprecision highp int;\n";
        out += guarded("KRS_GLSL_COMMON", common_library);
        out += library_;
        out += data_declaration();
        out += constants_comments_;
        out += functions_;
        return out;
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

private:
    // ---- the data array's name ------------------------------------------------------------
    // A GLSL identifier outside the implementation's gl_ prefix, and
    // not one of the library's: every name the library declares at global scope starts with krs_
    // (the default, krs_data, is the one such name left to the data).
    static void require_identifier(const std::string& n)
    {
        const auto letter = [](char c) { return (c >= 'a' && c <= 'z') || (c >= 'A' && c <= 'Z') || c == '_'; };
        const auto digit = [](char c) { return c >= '0' && c <= '9'; };
        bool ok = !n.empty() && letter(n[0]) && !n.starts_with("gl_");
        for (char c : n) ok = ok && (letter(c) || digit(c));
        if (!ok)
            throw invalid_parameter("glsl.options.data_name",
                                    "must be a GLSL identifier (letters, digits and _, not starting with a digit or gl_)",
                                    n);
        if (n.starts_with("krs_") && n != "krs_data")
            throw invalid_parameter("glsl.options.data_name", "must not start with krs_ (the library's names) unless it is krs_data", n);
    }
    // The generated functions use the array as `data_name[`: anywhere else in them the name is
    // something they declare too (a local such as d or p, a function), which hides the array there
    // and breaks the shader (a data_name of "d" failed to compile). Checked on every add, so the
    // field that brought the clash is the one refused. (Library functions take their constants as
    // parameters and never read the array, so their parameter names cannot clash.)
    void require_unshadowed_data_name() const
    {
        const std::string& n = options_.data_name;
        const auto word = [](char c) {
            return (c >= 'a' && c <= 'z') || (c >= 'A' && c <= 'Z') || (c >= '0' && c <= '9') || c == '_';
        };
        const std::string_view text = functions_;
        for (std::size_t at = text.find(n); at != std::string_view::npos; at = text.find(n, at + 1)) {
            const std::size_t end = at + n.size();
            if ((at > 0 && word(text[at - 1])) || (end < text.size() && word(text[end]))) continue;
            if (end < text.size() && text[end] == '[') continue;
            throw invalid_parameter("glsl.options.data_name",
                                    "is also a name the generated functions declare (a local variable or a "
                                    "function), which would hide the data array: choose another",
                                    n);
        }
    }

    // ---- data -----------------------------------------------------------------------------
    template <class X>
    std::size_t push(const X& x, const std::string& what)
    {
        const std::size_t index = vec4_count();
        if constexpr (X::glsl_vec4_count == 0) {
            (void)x;
            (void)what;
            return index;
        }
        data_.resize(data_.size() + 4 * std::size_t(X::glsl_vec4_count));
        x.glsl_constants(data_.data() + 4 * index);
        constants_comments_ += "// " + options_.data_name + "[" + std::to_string(index) + "..." +
                               std::to_string(index + std::size_t(X::glsl_vec4_count) - 1) + "]: " + what + " (" +
                               std::string(X::glsl_name) + ")\n";
        return index;
    }
    std::size_t push_raw(const float (&v)[4], const std::string& what)
    {
        const std::size_t index = vec4_count();
        data_.insert(data_.end(), v, v + 4);
        constants_comments_ += "// " + options_.data_name + "[" + std::to_string(index) + "]: " + what + "\n";
        return index;
    }
    std::string ref(std::size_t index) const { return options_.data_name + "[" + std::to_string(index) + "]"; }
    // "D[k], D[k+1], ..." for a type's parameters at index k.
    template <class X>
    std::string args(std::size_t index) const
    {
        std::string s;
        for (int i = 0; i < X::glsl_vec4_count; ++i) s += ", " + ref(index + std::size_t(i));
        return s;
    }

    std::string data_declaration() const
    {
        const std::size_t n = vec4_count();
        if (n == 0) return {};
        const std::string size = std::to_string(n);
        if (options_.mode == data_mode::buffer) {
            if (options_.target == target::glsl450)
                return "layout(std430, binding = " + std::to_string(options_.binding) + ") readonly buffer " +
                       options_.data_name + "_block {\n    vec4 " + options_.data_name + "[" + size + "];\n};\n";
            return "layout(std140) uniform " + options_.data_name + "_block {\n    vec4 " + options_.data_name + "[" +
                   size + "];\n};\n";
        }
        std::string s = "const vec4 " + options_.data_name + "[" + size + "] = vec4[" + size + "](\n";
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
        std::string macro(name);
        for (char& c : macro) c = c >= 'a' && c <= 'z' ? char(c - 'a' + 'A') : c;
        return "#ifndef " + macro + "\n#define " + macro + "\n" + std::string(code) + "#endif\n";
    }
    template <class X>
    void use_library()
    {
        if (included_.insert(std::string(X::glsl_name)).second) library_ += guarded(X::glsl_name, X::glsl_source);
    }

    // ---- fields, by recursion ---------------------------------------------------------------
    template <class F>
    void emit_field(const F& f, const std::string& name)
    {
        if constexpr (is_sequence<F>::value) {
            emit_sequence(f, name);
        } else if constexpr (is_union<F>::value) {
            emit_union(f, name, std::make_index_sequence<F::size>{});
        } else if constexpr (is_warp<F>::value) {
            emit_warp(f, name);
        } else if constexpr (is_kifs<F>::value) {
            emit_kifs(f, name);
        } else if constexpr (is_log_tiling<F>::value) {
            emit_log_tiling(f, name);
        } else if constexpr (is_similar_shell<F>::value) {
            emit_similar_shell(f, name);
        } else if constexpr (glsl_field<F>) {
            use_library<F>();
            const std::size_t k = push(f, name);
            functions_ += "float " + name + "(vec3 p) { return " + std::string(F::glsl_name) + "_distance(p" +
                          args<F>(k) + "); }\n";
        } else {
            if constexpr (glsl_part_union<F>) {
                emit_parts(f, name);
            } else {
                static_assert(sizeof(F) == 0, "krs::glsl: this field type has no GLSL (kernels, sequences, union_of, "
                                              "lipschitz_warp with a GLSL warp, kifs and the log-spherical fields "
                                              "are supported)");
            }
        }
    }

    // min over the parts a field visits, in its order (the C++ `d = part0; d = min(d, part_i)`).
    template <class F>
    void emit_parts(const F& f, const std::string& name)
    {
        std::size_t count = 0;
        f.glsl_for_each_part([&](const auto& part) { emit_field(part, name + "_" + std::to_string(count++)); });
        if (count == 0) throw invalid_parameter("glsl.parts", "a part union must have at least one part", name);
        std::string body = "float " + name + "(vec3 p) {\n    float d = " + name + "_0(p);\n";
        for (std::size_t i = 1; i < count; ++i) body += "    d = min(d, " + name + "_" + std::to_string(i) + "(p));\n";
        functions_ += body + "    return d;\n}\n";
    }

    // ---- fractals (krs/fractal) -----------------------------------------------------------------
    // KIFS: the kernel as NAME_kernel, one iteration of the program as NAME_program, and the loop
    // of kifs::distance with the iteration count and the taps fixed in the code; 1 / s^i is read
    // from the kifs's table in the data.
    template <class P, class K>
    void emit_kifs(const kifs<P, K>& f, const std::string& name)
    {
        static_assert(is_fold_program<P>::value, "krs::glsl: a kifs program must be a fold_program");
        emit_field(f.kernel(), name + "_kernel");
        std::string program = "vec3 " + name + "_program(vec3 p) {\n";
        std::size_t step_index = 0;
        std::apply(
            [&](const auto&... step) {
                (
                    [&](const auto& st) {
                        using S = std::remove_cvref_t<decltype(st)>;
                        static_assert(glsl_fold_step<S>, "krs::glsl: this fold step type has no GLSL");
                        use_library<S>();
                        const std::size_t at = push(st, name + " step " + std::to_string(step_index++));
                        std::string a = args<S>(at);
                        program += "    p = " + std::string(S::glsl_name) + "_apply(p" + a + ");\n";
                    }(step),
                    ...);
            },
            f.program().steps());
        functions_ += program + "    return p;\n}\n";
        const std::size_t table = push(f, name + " 1 / scale^i, i = 0.." + std::to_string(f.iterations()));
        const int n = f.iterations();
        auto inverse_scale = [&](const std::string& i) {
            return options_.data_name + "[" + std::to_string(table) + " + (" + i + " >> 2)][" + i + " & 3]";
        };
        const std::string last = ref(table + std::size_t(n / 4)) + "." + "xyzw"[n % 4];
        std::string body = "float " + name + "(vec3 p) {\n";
        if (f.taps() == kifs_taps::every_iteration) {
            body += "    float d = 3.0e38;\n";
            if (n > 0)
                body += "    for (int i = 0; i < " + std::to_string(n) + "; ++i) {\n"
                        "        d = min(d, " + name + "_kernel(p) * " + inverse_scale("i") + ");\n"
                        "        p = " + name + "_program(p);\n    }\n";
            body += "    return min(d, " + name + "_kernel(p) * " + last + ");\n}\n";
        } else {
            if (n > 0) body += "    for (int i = 0; i < " + std::to_string(n) + "; ++i) p = " + name + "_program(p);\n";
            body += "    return " + name + "_kernel(p) * " + last + ";\n}\n";
        }
        functions_ += body;
    }

    // log_polar_tiling / log_spherical_tiling: the tile as NAME_tile at the cell coordinates.
    template <class F>
    void emit_log_tiling(const F& f, const std::string& name)
    {
        emit_field(f.tile(), name + "_tile");
        use_library<F>();
        const std::string c = ref(push(f, name));
        const std::string kind(F::glsl_name);
        functions_ += "float " + name + "(vec3 p) {\n    vec3 u = " + kind + "_cell(p, " + c + ");\n    return " + kind +
                      "_finish(p, u, " + name + "_tile(u), " + c + ");\n}\n";
    }

    // similar_shell: the prototype shell as NAME_shell, the shell scales from the table
    // (NAME_scale), the seam mode fixed in the code.
    template <class S>
    void emit_similar_shell(const similar_shell<S>& f, const std::string& name)
    {
        emit_field(f.shell(), name + "_shell");
        const std::size_t header = push(f, name + " (density, 1 / density, s, 1 - 1/s), (cutoff, step, k0, n)");
        const std::vector<float> table = f.glsl_scale_table();
        const std::size_t first = vec4_count();
        for (std::size_t i = 0; i < table.size(); i += 4) {
            const float v[4] = {table[i], table[i + 1], table[i + 2], table[i + 3]};
            push_raw(v, i == 0 ? name + " shell scales e^(k / density), k = k0.." : name + " shell scales");
        }
        const std::string c = ref(header), o = ref(header + 1);
        std::string body = "float " + name + "_scale(float k) {\n"
                           "    float i = k - " + o + ".z;\n"
                           "    if (i >= 0.0 && i < " + o + ".w) {\n"
                           "        int j = int(i);\n"
                           "        return " + options_.data_name + "[" + std::to_string(first) + " + (j >> 2)][j & 3];\n"
                           "    }\n"
                           "    return exp(k * " + c + ".y);\n}\n";
        body += "float " + name + "_in_shell(vec3 p, float k) {\n    float scale = " + name + "_scale(k);\n"
                "    return " + name + "_shell(p / scale) * scale;\n}\n";
        body += "float " + name + "(vec3 p) {\n"
                "    vec4 c = " + c + ";\n"
                "    float r = sqrt(p.x * p.x + p.y * p.y + p.z * p.z);\n"
                "    float k = floor(log(max(r, 1e-30)) * c.x);\n";
        switch (f.options().seams) {
        case shell_seams::none: body += "    float d = " + name + "_in_shell(p, k);\n"; break;
        case shell_seams::hidden_boundary:
            body += "    float inner = " + name + "_scale(k);\n"
                    "    float outer = inner * c.z;\n"
                    "    float boundary = max(min(r - inner, outer - r), " + o + ".x * r);\n"
                    "    float d = min(" + name + "_in_shell(p, k), boundary);\n";
            break;
        default:
            body += "    float d = c.w * r;\n"
                    "    for (int j = -1; j <= 1; ++j) {\n"
                    "        float kj = k + float(j);\n"
                    "        float inner = " + name + "_scale(kj);\n"
                    "        float outer = inner * c.z;\n"
                    "        float to_shell = max(max(inner - r, r - outer), 0.0);\n"
                    "        d = min(d, max(" + name + "_in_shell(p, kj), to_shell));\n"
                    "    }\n";
            break;
        }
        functions_ += body + "    return d * " + o + ".y;\n}\n";
    }

    template <class U, std::size_t... I>
    void emit_union(const U& u, const std::string& name, std::index_sequence<I...>)
    {
        (emit_field(u.template component<I>(), name + "_" + std::to_string(I)), ...);
        std::string body = "float " + name + "(vec3 p) {\n    float d = " + name + "_0(p);\n";
        ((body += I > 0 ? "    d = min(d, " + name + "_" + std::to_string(I) + "(p));\n" : std::string()), ...);
        functions_ += body + "    return d;\n}\n";
    }

    template <class F, class W>
    void emit_warp(const lipschitz_warp<F, W>& f, const std::string& name)
    {
        static_assert(glsl_warp<W>, "krs::glsl: this warp type has no GLSL (twist_warp and bend_warp have)");
        emit_field(f.base(), name + "_base");
        use_library<W>();
        const std::size_t w = push(f.distortion(), name + " warp");
        const bounding_sphere d = f.distortion().domain();
        const float extra[4] = {f.inverse_lipschitz(), 0.0f, 0.0f, 0.0f};
        const std::size_t inv = push_raw(extra, name + " (1 / Lipschitz bound, 0, 0, 0)");
        const std::string apply = std::string(W::glsl_name) + "_apply";
        std::string body = "float " + name + "(vec3 x) {\n";
        if (!d.is_bounded()) {
            body += "    return " + name + "_base(" + apply + "(x" + args<W>(w) + ")) * " + ref(inv) + ".x;\n}\n";
        } else {
            const float dom[4] = {d.center.x, d.center.y, d.center.z, d.radius};
            const std::size_t c = push_raw(dom, name + " domain (center, radius)");
            // max(|x - c| - R, f(W(P(x))) / L), P the projection onto the domain ball.
            body += "    vec4 domain = " + ref(c) + ";\n"
                    "    vec3 offset = x - domain.xyz;\n"
                    "    float len = length(offset);\n"
                    "    float outside = len - domain.w;\n"
                    "    float scale = outside > 0.0 ? domain.w / (len > 0.0 ? len : 1.0) : 1.0;\n"
                    "    vec3 projected = domain.xyz + offset * scale;\n"
                    "    return max(outside, " + name + "_base(" + apply + "(projected" + args<W>(w) + ")) * " +
                    ref(inv) + ".x);\n}\n";
        }
        functions_ += body;
    }

    // A kernel's distance or normal call at point expression `p`.
    template <class V>
    std::string kernel_call(const V& k, std::size_t index, const char* what, const std::string& p) const
    {
        return std::visit(
            [&](const auto& kernel) {
                using K = std::remove_cvref_t<decltype(kernel)>;
                return std::string(K::glsl_name) + "_" + what + "(" + p + args<K>(index) + ")";
            },
            k);
    }

    template <class M, class... Kinds>
    void emit_sequence(const basic_sequence<M, Kinds...>& s, const std::string& name)
    {
        static_assert(glsl_mirror<M>, "krs::glsl: this mirror kind has no GLSL");
        static_assert((glsl_kernel<Kinds> && ...), "krs::glsl: a kernel kind of this sequence has no GLSL");
        const std::size_t n = s.mirror_count();
        // Only the kinds this scene uses get their functions emitted (in type-list order).
        bool used[sizeof...(Kinds)] = {};
        for (const auto& k : s.kernels()) used[k.index()] = true;
        {
            std::size_t i = 0;
            ((used[i++] ? use_library<Kinds>() : void()), ...);
        }
        if (n > 0) use_library<M>();
        std::vector<std::size_t> mirror_at(n), kernel_at(s.kernels().size());
        for (std::size_t i = 0; i < n; ++i) mirror_at[i] = push(s.mirrors()[i], name + " mirror " + std::to_string(i));
        for (std::size_t k = 0; k < s.kernels().size(); ++k)
            kernel_at[k] = std::visit(
                [&](const auto& kernel) {
                    return push(kernel, name + " kernel " + std::to_string(k) + " (level " +
                                            std::to_string(s.kernel_level(k)) + ")");
                },
                s.kernels()[k]);
        const std::string mirror_fn = std::string(M::glsl_name) + "_";
        auto bit = [](std::size_t i) {
            char hex[16];
            const auto r = std::to_chars(hex, hex + sizeof hex, std::uint32_t(1) << (i % 32), 16);
            return std::string(i < 32 ? ".x" : ".y") + " |= 0x" + std::string(hex, r.ptr) + "u;";
        };
        auto kernel_record = [&](std::size_t k, std::size_t level, const std::string& target, bool shading) {
            std::string b = "    d = " + kernel_call(s.kernels()[k], kernel_at[k], "distance", "p") + ";\n";
            b += "    if (d < " + target + ".dist) { " + target + ".dist = d; " + target + ".kernel_point = p; " +
                 target + ".kernel = " + std::to_string(k) + "u; " + target + ".level = " + std::to_string(level) +
                 "u;" + (shading ? " s.light = light; s.view = view;" : "") + " }\n";
            return b;
        };

        // Algorithm 1: the distance.
        std::string body = "float " + name + "(vec3 p) {\n    float d = 3.0e38;\n";
        for (std::size_t i = n + 1; i-- > 0;) {
            if (i < n) body += "    p = " + mirror_fn + "fold(p, " + ref(mirror_at[i]) + ");\n";
            for (std::uint32_t k = s.level_begin(i); k < s.level_begin(i + 1); ++k)
                body += "    d = min(d, " + kernel_call(s.kernels()[k], kernel_at[k], "distance", "p") + ");\n";
        }
        functions_ += body + "    return d;\n}\n";

        // Algorithm 1 with the location (sequence::locate).
        body = "krs_location " + name + "_locate(vec3 p) {\n"
               "    krs_location w = krs_location(3.0e38, p, 0u, 0u, uvec2(0u));\n    float d;\n";
        for (std::size_t i = n + 1; i-- > 0;) {
            if (i < n)
                body += "    if (" + mirror_fn + "signed_distance(p, " + ref(mirror_at[i]) + ") > 0.0) { p = " +
                        mirror_fn + "reflect(p, " + ref(mirror_at[i]) + "); w.reflections" + bit(i) + " }\n";
            for (std::uint32_t k = s.level_begin(i); k < s.level_begin(i + 1); ++k)
                body += kernel_record(k, i, "w", false);
        }
        functions_ += body + "    return w;\n}\n";

        // Algorithm 2 (shade_in_kernel_space): light and view carried into the nearest kernel's
        // space, blended across each mirror over a band of width `threshold`.
        body = "krs_kernel_shading " + name + "_shade(vec3 p, vec3 toLight, vec3 toEye, float threshold) {\n"
               "    krs_kernel_shading s;\n"
               "    s.where = krs_location(3.0e38, p, 0u, 0u, uvec2(0u));\n"
               "    s.light = toLight;\n    s.view = toEye;\n"
               "    vec3 light = toLight;\n    vec3 view = toEye;\n"
               "    bool ramp = threshold >= 1.17549435e-38;\n"  // as the C++: below float's smallest normal, the step
               "    float inverse = ramp ? 1.0 / threshold : 0.0;\n"
               "    float d;\n    float e;\n    float weight;\n";
        for (std::size_t i = n + 1; i-- > 0;) {
            if (i < n) {
                const std::string m = ref(mirror_at[i]);
                body += "    e = " + mirror_fn + "signed_distance(p, " + m + ");\n"
                        "    if (e > 0.0) { p = " + mirror_fn + "reflect(p, " + m + "); s.where.reflections" + bit(i) +
                        " }\n"
                        "    weight = ramp ? clamp(e * inverse + 0.5, 0.0, 1.0) : (e > 0.0 ? 1.0 : 0.0);\n"
                        "    light = light + (" + mirror_fn + "reflect_direction(light, " + m + ") - light) * weight;\n"
                        "    view = view + (" + mirror_fn + "reflect_direction(view, " + m + ") - view) * weight;\n";
            }
            for (std::uint32_t k = s.level_begin(i); k < s.level_begin(i + 1); ++k)
                body += kernel_record(k, i, "s.where", true);
        }
        body += "    vec3 q = s.where.kernel_point;\n";
        for (std::size_t k = 0; k < s.kernels().size(); ++k) {
            body += std::string(k == 0 ? "    " : "    else ") +
                    (k + 1 < s.kernels().size() ? "if (s.where.kernel == " + std::to_string(k) + "u) " : "") + "{ s.normal = " +
                    kernel_call(s.kernels()[k], kernel_at[k], "normal", "q") + "; s.kind = " +
                    std::to_string(s.kernels()[k].index()) + "u; }\n";
        }
        functions_ += body + "    return s;\n}\n";
    }

    options options_;
    std::set<std::string> included_;
    std::string library_;            // each kind's functions, once
    std::string constants_comments_; // what each data entry holds
    std::string functions_;          // the bodies
    std::vector<float> data_;
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

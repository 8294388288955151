#pragma once
// Fields and kernels: the two concepts everything else in krs takes.
//
// A *field* is anything with `template <class T> T distance(const vec3<T>&) const` that never
// overestimates the distance to its own zero set: it is 1-Lipschitz (a warp that stretches space
// divides by its declared bound). Tracers, shading, GLSL emission and tests accept any field.
//
// A *kernel* is a field that is also a primitive a KRS can hold: besides its distance it reports a
// bounding sphere (for expansion, tiling and tests), an axis-aligned bounding box no larger than
// that sphere's on any axis (exact where it has a closed form; a sequence's box and ray clipping
// are built from it) and the outward unit normal at a point (for shading in kernel space, paper
// section 6.1). Kernel parameters are validated at construction. A kernel is also a *GLSL type*:
// it carries its GLSL beside its C++ (docs/design.md#rule-4), so a kernel without the text that
// shaders run fails this concept where it is first used as one (a sequence's kind), not later in
// the emitter or never, if no test emits it.
//
// A *GLSL type* (every kernel, mirror kind, fold step and warp) names its functions' prefix
// (`glsl_name`), their text (`glsl_source`, emitted once per shader however often the type is used)
// and its parameters: `glsl_parameters()` returns them as a std::array<float, 4 N>, the N vec4s its
// functions take after the point, in their order. The array is the one statement of the layout:
// its size is the vec4 count, and the functions' parameter lists are checked by compiling every
// type's GLSL (tests/test_glsl_field_types.cpp). The emitter (krs/glsl/emitter.hpp) writes any.
//
// A *lockstep field* also evaluates K points of lane type T in one call, `distances<T, K>`, equal
// to K calls of `distance` but interleaved so that their dependent operations overlap (a KRS walks
// its levels once for all of them). Packet tracers use it where a field offers it.
//
// Lanes and paths agree: a packet lane's distance equals the scalar one, `distances` equals K calls of
// `distance`. Bit for bit where the compiler does not fuse a*b+c (no FMA hardware targeted, as on
// the default x86-64 target, or -ffp-contract=off); with FMA and g++'s default -ffp-contract=fast each
// path fuses differently, and they agree within 1e-6 of the scene's extent (measured worst 3.2e-7;
// docs/stability.md, "Packet and scalar results under FMA contraction"). That figure is g++'s:
// clang 14 with FMA contracts value noise's fade and blend differently per path (worst 1.3e-6).

#include "krs/core/bounds.hpp"
#include "krs/core/vec3.hpp"

#include <array>
#include <concepts>
#include <cstddef>
#include <string_view>
#include <tuple>
#include <type_traits>

namespace krs {

template <class F>
concept field = requires(const F& f, const vec3f& pf, const vec3d& pd) {
    { f.distance(pf) } -> std::same_as<float>;
    { f.distance(pd) } -> std::same_as<double>;
};

template <class F, class T, std::size_t K>
concept lockstep_field = field<F> && requires(const F& f, const std::array<vec3<T>, K>& points) {
    { f.template distances<T, K>(points) } -> std::same_as<std::array<T, K>>;
};

template <class X>
concept glsl_type = requires(const X& x) {
    { X::glsl_name } -> std::convertible_to<std::string_view>;
    { X::glsl_source } -> std::convertible_to<std::string_view>;
    { std::tuple_size<std::remove_cvref_t<decltype(x.glsl_parameters())>>::value } -> std::convertible_to<std::size_t>;
};

template <class K>
concept kernel = field<K> && glsl_type<K> && requires(const K& k, const vec3f& p) {
    { k.bound() } -> std::same_as<bounding_sphere>;
    { k.bound_box() } -> std::same_as<bounding_box>;
    { k.normal(p) } -> std::same_as<vec3f>;
};

} // namespace krs

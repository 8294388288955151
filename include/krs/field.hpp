#pragma once
// Fields and kernels: the two concepts everything else in krs takes.
//
// A *field* is anything with `template <class T> T distance(const vec3<T>&) const` that never
// overestimates the distance to its own zero set: it is 1-Lipschitz (a warp that stretches space
// divides by its declared bound). Tracers, shading, GLSL emission and tests accept any field.
//
// A *kernel* is a field that is also a primitive a KRS can hold: besides its distance it reports a
// bounding sphere (for expansion, tiling and tests) and the outward unit normal at a point (for
// shading in kernel space, paper section 6.1). Kernel parameters are validated at construction.

#include "krs/core/bounds.hpp"
#include "krs/core/vec3.hpp"

#include <concepts>

namespace krs {

template <class F>
concept field = requires(const F& f, const vec3f& pf, const vec3d& pd) {
    { f.distance(pf) } -> std::same_as<float>;
    { f.distance(pd) } -> std::same_as<double>;
};

template <class K>
concept kernel = field<K> && requires(const K& k, const vec3f& p) {
    { k.bound() } -> std::same_as<bounding_sphere>;
    { k.normal(p) } -> std::same_as<vec3f>;
};

} // namespace krs

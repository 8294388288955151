#pragma once
// Conversions between krs::vec3 and GLM at the API surface.
//
// Users hold their scenes in GLM; the library's hot path holds vec3<T>. These two functions are
// the only bridge, so the conversion is visible where it happens and never inside a loop.

#include "krs/core/vec3.hpp"

#include <glm/vec3.hpp>

namespace krs {

template <class S, glm::qualifier Q>
inline vec3<S> from_glm(const glm::vec<3, S, Q>& v) noexcept
{
    return {v.x, v.y, v.z};
}

template <std::floating_point S>
inline glm::vec<3, S> to_glm(const vec3<S>& v) noexcept
{
    return {v.x, v.y, v.z};
}

} // namespace krs

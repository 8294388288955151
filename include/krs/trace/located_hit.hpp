#pragma once
// A KRS hit with what shading needs: the hit point, and where Algorithm 1 found the nearest
// kernel there (the kernel-space point, the kernel, its level and the reflection decisions,
// section 6.1). Tracing stays generic over fields; locating is one more O(n) walk, paid once per
// hit rather than once per step.

#include "krs/sequence.hpp"
#include "krs/trace/sphere_trace.hpp"

namespace krs {

template <std::floating_point S>
struct located_hit : hit<S> {
    vec3<S> position{};    // world-space hit point (valid when found)
    location<S> where{};   // nearest kernel at the hit point (valid when found)
};

template <mirror_kind M, kernel... Kinds, std::floating_point S>
located_hit<S> trace_and_locate(const basic_sequence<M, Kinds...>& s, const ray<S>& r, const trace_options& options)
{
    located_hit<S> h;
    static_cast<hit<S>&>(h) = sphere_trace(s, r, options);
    if (h.found) {
        h.position = point_at(r, h.t);
        h.where = s.locate(h.position);
    }
    return h;
}

} // namespace krs

#pragma once
// Noise perturbation (paper section 3.5): "The too ideal structure of hypertrees can be distorted
// with a three-dimensional vector-valued noise or turbulence", injected at one of three stages,
// all with the same field here:
//   1. during generation, on generator positions (ifs::perturb, create/generate.hpp): the paper's
//      "best solution", exact in position;
//   2. as a post-process, "a shift operation to the completed hypertree" (perturb_voxels below):
//      every stored voxel moves, with its density, level and part, to the voxel holding its
//      shifted center;
//   3. at render time, on the marcher's sample positions (sample_displacement below, the
//      marcher's march_options::displacement), which moves no voxel.
//
// The field: shift(p) = (ax n(f p), ay n(f p + o1), az n(f p + o2)), n = value noise in [-1, 1]
// (krs/core/noise.hpp), so |shift_i| <= a_i on each axis. It is smooth (value noise's gradient is
// at most value_noise_gradient_bound), so nearby points move alike: a continuous distortion.
//
// The post-process maps voxels forward (each voxel goes where its center goes), so it is exact
// for the voxels it keeps and may leave a cell empty where the field stretches the tree by more
// than a voxel per voxel (where a f value_noise_gradient_bound >= 1); where two voxels land in one
// cell the denser is kept (then the shallower level, then the smaller part, as unite_max).
// Voxels whose shifted center leaves the hypervolume are dropped.

#include "hypertree/execution.hpp"
#include "hypertree/store/store.hpp"
#include "krs/core/lanes.hpp"
#include "krs/core/noise.hpp"
#include "krs/core/validate.hpp"

#include <algorithm>
#include <string>
#include <string_view>
#include <vector>

namespace hypertree {

// The field, written once for every stage: shift(p) for a point of any lane type T (double for
// generation and voxels, float or a packet for the marcher's samples). The offsets decorrelate
// the three components (three looks into one noise); written as the scalar type's literals, the
// double and float callers get the same offsets they always had.
template <class T>
krs::vec3<T> noise_shift(const krs::vec3<T>& p, const krs::vec3<T>& amplitude, const T& frequency)
{
    using S = krs::scalar_t<T>;
    const krs::vec3<T> q{p.x * frequency, p.y * frequency, p.z * frequency};
    return {amplitude.x * krs::value_noise(q), amplitude.y * krs::value_noise(krs::vec3<T>{q.x + T(S(31.7)), q.y - T(S(17.3)), q.z + T(S(5.9))}),
            amplitude.z * krs::value_noise(krs::vec3<T>{q.x - T(S(11.1)), q.y + T(S(23.9)), q.z - T(S(41.3))})};
}

namespace detail {
// The noise of every stage: amplitudes are sizes (a negative one is the same noise mirrored:
// refused rather than silently meaning that); all finite (an infinite frequency made every shift
// NaN). Parameters are named `name.amplitude.x` ... `name.frequency`.
template <class S>
void require_noise(std::string_view name, const krs::vec3<S>& amplitude, S frequency)
{
    const std::string n(name);
    krs::require_non_negative(n + ".amplitude.x", amplitude.x);
    krs::require_non_negative(n + ".amplitude.y", amplitude.y);
    krs::require_non_negative(n + ".amplitude.z", amplitude.z);
    krs::require_non_negative(n + ".frequency", frequency);
}
} // namespace detail

struct perturbation {
    vec3d amplitude{};
    double frequency = 8;
    bool enabled() const { return amplitude.x != 0 || amplitude.y != 0 || amplitude.z != 0; }

    void validate(std::string_view name) const { detail::require_noise(name, amplitude, frequency); }
    // p + shift(p) (noise_shift above).
    vec3d displaced(const vec3d& p) const
    {
        const vec3d s = noise_shift(p, amplitude, frequency);
        return {p.x + s.x, p.y + s.y, p.z + s.z};
    }
};

// Render-time noise (stage 3, march_options::displacement): each primary sample p is looked up,
// and shaded, at p + shift(p), the field above in float (the same noise and offsets as
// generation's, at the sample's world position). |shift_i| <= amplitude_i, so the marcher widens
// the tree's box by the amplitude on every side: a sample outside the box whose displaced position
// falls inside still reads it. Empty-space skipping is off for displaced samples (a skip is
// predicted from the undisplaced ray's path through empty bricks), and shadow rays are not
// displaced (per-voxel shading lights the voxel the sample reads). Amplitude 0 (the default) is
// today's march, pixel for pixel. The GLSL marcher refuses it (render/glsl.hpp). It is here, beside
// the other two stages, so that a definition file's RENDERPERTURB (io/definition_file.hpp) is read
// without the renderer's options.
struct sample_displacement {
    krs::vec3f amplitude{0.0f, 0.0f, 0.0f};
    float frequency = 8.0f;
    bool enabled() const { return amplitude.x != 0.0f || amplitude.y != 0.0f || amplitude.z != 0.0f; }

    void validate(std::string_view name) const { detail::require_noise(name, amplitude, frequency); }
    // p + shift(p) in the sample's lane type.
    template <class T>
    krs::vec3<T> displaced(const krs::vec3<T>& p) const
    {
        const krs::vec3<T> s = noise_shift(p, krs::vec3<T>{T(amplitude.x), T(amplitude.y), T(amplitude.z)}, T(frequency));
        return {p.x + s.x, p.y + s.y, p.z + s.z};
    }
};

// The post-process (stage 2): the store's voxels shifted by the field, as a sorted list any store
// kind builds from. Amplitude 0 gives the store's own list. Each voxel keeps the part byte the
// store gives it (for_each_stored): its first-level part over a partitioned_store, and 0 over
// every other kind, which keeps no parts. A tree whose shading or bounds need the parts (flows,
// fitted part spheres, part boxes) is perturbed over a partitioned_store.
template <voxel_store S>
std::vector<stored_voxel> perturb_voxels(const S& store, const perturbation& perturb)
{
    perturb.validate("perturb_voxels.perturb");
    const hypervolume& volume = store.volume();
    std::vector<stored_voxel> moved;
    moved.reserve(store.nonempty_count());
    for_each_stored(store, [&](const stored_voxel& v) {
        if (const auto to = volume.voxel_at(perturb.displaced(volume.voxel_center(v.index)))) moved.push_back({*to, v.value, v.part});
    });
    // Sort by index, the winner of each cell first: denser, then shallower, then smaller part.
    std::sort(moved.begin(), moved.end(), [](const stored_voxel& a, const stored_voxel& b) {
        if (a.index != b.index) return a.index < b.index;
        if (a.value.density != b.value.density) return a.value.density > b.value.density;
        if (a.value.level != b.value.level) return a.value.level < b.value.level;
        return a.part < b.part;
    });
    moved.erase(std::unique(moved.begin(), moved.end(), [](const stored_voxel& a, const stored_voxel& b) { return a.index == b.index; }),
                moved.end());
    return moved;
}

// ... built as the operand's store kind.
template <voxel_store S>
S perturb_voxels_store(const S& store, const perturbation& perturb, memory_budget budget = {})
{
    return S::build(store.volume(), perturb_voxels(store, perturb), budget);
}

} // namespace hypertree

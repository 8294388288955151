#pragma once
// Per-voxel shading remembered by all the threads of one render.
//
// With shade_per_voxel a voxel's lit color and its shadow transmittances are pure functions of
// the voxel (marcher.hpp), and the shadow rays behind them are most of a render's work. One table
// shared by every thread computes each voxel about once; a table per thread computed it once per
// thread (1.04 million lookups on one thread became 1.56 million on two, tree A at resolution
// 100). What the table holds never changes a result, only how often shadow rays are marched.
//
// The table has one entry per non-empty voxel, at the voxel's slot (voxel_bricks.hpp): no hash,
// no eviction, and only a byte per voxel to clear for each render (the values are written before
// they are read). An entry is published by its flag: values are stored first, then the flag with
// release; a reader that sees the flag with acquire sees the values. Two threads that shade the
// same voxel at once both store it; they store the same bits (the values are a deterministic
// function of the voxel), and values are accessed as relaxed atomics, so this is well defined.

#include <atomic>
#include <cstddef>
#include <cstdint>
#include <memory>

namespace hypertree {

class shade_memo {
public:
    shade_memo() = default;
    // `slots` entries of `stride` floats each, all empty.
    shade_memo(std::size_t slots, std::size_t stride)
        : slots_(slots), stride_(stride), done_(std::make_unique<std::atomic<std::uint8_t>[]>(slots)),
          values_(new float[slots * stride]) // read only once written: left uninitialized
    {
    }

    std::size_t slots() const { return slots_; }
    std::size_t stride() const { return stride_; }

    // Declares the table complete when every slot is recorded, and says whether it is. Call it
    // when no thread stores any more (after they are joined); a complete table is read directly.
    bool seal()
    {
        complete_ = true;
        for (std::size_t i = 0; i < slots_ && complete_; ++i) complete_ = done_[i].load(std::memory_order_acquire) != 0;
        return complete_;
    }
    bool complete() const { return complete_; }
    // Slot i's values at [i * stride, (i + 1) * stride). Precondition: complete().
    const float* values() const { return values_.get(); }

    // Copies the values of `slot` to out[0, stride) and returns true when they are recorded.
    bool find(std::size_t slot, float* out) const
    {
        if (slot >= slots_ || done_[slot].load(std::memory_order_acquire) == 0) return false;
        float* v = &values_[slot * stride_];
        for (std::size_t i = 0; i < stride_; ++i) out[i] = std::atomic_ref<float>(v[i]).load(std::memory_order_relaxed);
        return true;
    }

    // Records values[0, stride) for `slot`. Every store to one slot must store the same values.
    void store(std::size_t slot, const float* values)
    {
        if (slot >= slots_) return;
        float* v = &values_[slot * stride_];
        for (std::size_t i = 0; i < stride_; ++i) std::atomic_ref<float>(v[i]).store(values[i], std::memory_order_relaxed);
        done_[slot].store(1, std::memory_order_release);
    }

private:
    std::size_t slots_ = 0, stride_ = 0;
    bool complete_ = false;
    std::unique_ptr<std::atomic<std::uint8_t>[]> done_;
    std::unique_ptr<float[]> values_;
};

} // namespace hypertree

#pragma once
// Per-voxel shading remembered by all the threads of one render.
//
// With shade_per_voxel a voxel's lit color and its shadow transmittances are pure functions of
// the voxel (marcher.hpp), and the shadow rays behind them are most of a render's work. One table
// shared by every thread computes each voxel about once; a table per thread computed it once per
// thread (1.04 million lookups on one thread became 1.56 million on two, tree A at resolution
// 100). What the table holds never changes a result, only how often shadow rays are marched.
//
// The table is direct-mapped (slot = hash of the voxel index; a newer voxel evicts an older one)
// and lock-free: each slot's word says which voxel its values belong to, with a writing flag and
// a version, and readers check it before and after copying the values (a sequence lock).
//     word = version << 33 | (voxel index + 1) << 1 | writing
// A writer that finds the slot being written by another thread does not wait: it keeps its value
// to itself. A reader that sees the word change while it copies treats the slot as empty. The
// version makes a slot that went from voxel a to b and back to a during one copy look changed.
// Values are relaxed atomics, so concurrent copies are well defined.

#include "hypertree/volume.hpp"

#include <atomic>
#include <cstddef>
#include <cstdint>
#include <memory>

namespace hypertree {

class shade_memo {
public:
    shade_memo() = default;
    // `slots` entries (rounded up to a power of two) of `stride` floats each, all empty.
    shade_memo(std::size_t slots, std::size_t stride) : stride_(stride)
    {
        slots_ = 1;
        while (slots_ < slots) slots_ *= 2;
        words_ = std::make_unique<std::atomic<std::uint64_t>[]>(slots_);
        values_ = std::make_unique<std::atomic<float>[]>(slots_ * stride_);
        for (std::size_t i = 0; i < slots_; ++i) words_[i].store(0, std::memory_order_relaxed);
        for (std::size_t i = 0; i < slots_ * stride_; ++i) values_[i].store(0.0f, std::memory_order_relaxed);
    }

    std::size_t slots() const { return slots_; }
    std::size_t stride() const { return stride_; }

    // Copies the values of `index` to out[0, stride) and returns true when the table holds them.
    bool find(voxel_index index, float* out) const
    {
        if (slots_ == 0) return false;
        const std::size_t slot = slot_of(index);
        const std::uint64_t before = words_[slot].load(std::memory_order_acquire);
        if (owner(before) != std::uint64_t(index) + 1 || (before & writing) != 0) return false;
        const std::atomic<float>* v = &values_[slot * stride_];
        for (std::size_t i = 0; i < stride_; ++i) out[i] = v[i].load(std::memory_order_relaxed);
        std::atomic_thread_fence(std::memory_order_acquire);
        return words_[slot].load(std::memory_order_relaxed) == before;
    }

    // Records values[0, stride) as the entry of `index`, unless another thread is writing its slot.
    void store(voxel_index index, const float* values)
    {
        if (slots_ == 0) return;
        const std::size_t slot = slot_of(index);
        std::uint64_t word = words_[slot].load(std::memory_order_relaxed);
        if ((word & writing) != 0) return;
        const std::uint64_t version = (word >> 33) + 1;
        const std::uint64_t claimed = (version << 33) | ((std::uint64_t(index) + 1) << 1) | writing;
        if (!words_[slot].compare_exchange_strong(word, claimed, std::memory_order_acquire, std::memory_order_relaxed)) return;
        std::atomic<float>* v = &values_[slot * stride_];
        for (std::size_t i = 0; i < stride_; ++i) v[i].store(values[i], std::memory_order_relaxed);
        words_[slot].store(claimed & ~writing, std::memory_order_release);
    }

private:
    static constexpr std::uint64_t writing = 1;
    static std::uint64_t owner(std::uint64_t word) { return (word >> 1) & 0xffffffffu; }
    std::size_t slot_of(voxel_index index) const { return (std::size_t(index) * 0x9e3779b1u >> 7) & (slots_ - 1); }

    std::size_t slots_ = 0, stride_ = 0;
    std::unique_ptr<std::atomic<std::uint64_t>[]> words_;
    std::unique_ptr<std::atomic<float>[]> values_;
};

} // namespace hypertree

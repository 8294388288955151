#pragma once
// Scratch memory for creation: blocks that outlive one build_tree, so the next one finds its
// pages already mapped.
//
// Between its steps a build holds 10 to 40 MB at resolution 300 (the generator's hits, the
// buckets validation scatters them into, the entry and voxel lists), all of it released at the
// end. The C library hands blocks that large back to the system on release, and the system zeroes
// every 4 KiB page again on its first touch: 0.34 ms per MB measured on this project's machine,
// so tree C at 300 spent 10 ms in page faults around 7 ms of work. A scratch_memory the caller
// keeps across builds (generation_options::scratch) keeps the blocks instead, and a build of the
// same size touches no fresh page. It is a std::pmr::memory_resource, so std::pmr containers
// draw from it too.
//
// A request takes the smallest kept block that fits it, unless that block is more than twice as
// large (a small request should not pin a large block), else a new block from the system. Blocks go
// back to the system only when the scratch_memory is destroyed or released. Blocks of half a huge
// page or more are mapped on huge pages where the system offers them (hypertree/huge_pages.hpp), so
// even a first build, or one without a kept scratch, pays one fault per 2 MiB instead of one per
// 4 KiB. Requests are few (two per generator chunk and a few more: 50 to 200 per build) and come
// from the caller's worker threads: a mutex guards the lists.

#include "hypertree/huge_pages.hpp"

#include <algorithm>
#include <cstddef>
#include <limits>
#include <memory_resource>
#include <mutex>
#include <new>
#include <type_traits>
#include <utility>
#include <vector>

namespace hypertree {

class scratch_memory final : public std::pmr::memory_resource {
public:
    scratch_memory() = default;
    scratch_memory(const scratch_memory&) = delete;
    scratch_memory& operator=(const scratch_memory&) = delete;
    ~scratch_memory() override { release(); }

    // Bytes of the blocks kept for reuse (not lent out now).
    std::size_t kept_bytes() const
    {
        const std::lock_guard lock(mutex_);
        std::size_t bytes = 0;
        for (const block& b : kept_) bytes += b.bytes;
        return bytes;
    }
    // How many blocks were taken from the system so far: a build that found all its blocks kept
    // adds none.
    std::size_t system_allocations() const
    {
        const std::lock_guard lock(mutex_);
        return system_allocations_;
    }
    // Returns the kept blocks to the system (blocks lent out stay valid and are kept on return).
    void release()
    {
        const std::lock_guard lock(mutex_);
        for (const block& b : kept_) give_back(b);
        kept_.clear();
    }

private:
    // Cache-line aligned blocks, in whole pages, serve every request of alignment up to 64.
    static constexpr std::size_t block_alignment = 64;
    static constexpr std::size_t page = 4096;
    struct block {
        void* address;
        std::size_t bytes;
    };

    // A large block is mapped on huge pages, 2 MiB-aligned (its zeros are free and unused); a
    // smaller one comes from operator new, cache-line aligned.
    static void* obtain(std::size_t bytes)
    {
        if (pages::mapped(bytes)) return pages::allocate_zeroed(bytes);
        return ::operator new(bytes, std::align_val_t(block_alignment));
    }
    static void give_back(const block& b)
    {
        if (pages::mapped(b.bytes)) pages::release(b.address, b.bytes);
        else ::operator delete(b.address, std::align_val_t(block_alignment));
    }

    void* do_allocate(std::size_t bytes, std::size_t alignment) override
    {
        if (alignment > block_alignment) throw std::bad_alloc(); // no scratch user asks for more
        if (bytes > std::numeric_limits<std::size_t>::max() - page) throw std::bad_array_new_length();
        bytes = std::max<std::size_t>((bytes + page - 1) / page * page, page);
        const std::lock_guard lock(mutex_);
        lent_.reserve(lent_.size() + 1); // so recording the block below cannot throw and lose it
        auto best = kept_.end();
        for (auto b = kept_.begin(); b != kept_.end(); ++b)
            if (b->bytes >= bytes && b->bytes / 2 <= bytes && (best == kept_.end() || b->bytes < best->bytes)) best = b;
        block lent;
        if (best != kept_.end()) {
            lent = *best;
            kept_.erase(best);
        } else {
            lent = {obtain(bytes), bytes};
            ++system_allocations_;
        }
        lent_.push_back(lent);
        return lent.address;
    }
    void do_deallocate(void* address, std::size_t, std::size_t) override
    {
        const std::lock_guard lock(mutex_);
        // The lent block's own size, which may exceed the request it served.
        const auto b = std::find_if(lent_.begin(), lent_.end(), [&](const block& l) { return l.address == address; });
        if (b == lent_.end()) return; // not ours: memory_resource forbids it, so ignore it safely
        kept_.push_back(*b);
        lent_.erase(b);
    }
    bool do_is_equal(const std::pmr::memory_resource& other) const noexcept override { return this == &other; }

    mutable std::mutex mutex_;
    std::vector<block> kept_, lent_;
    std::size_t system_allocations_ = 0;
};

// n default-initialized elements (not zeroed: the caller writes each before reading it) from a
// memory resource, returned to it on destruction. For trivial types only: nothing is constructed
// or destroyed.
template <class T>
class scratch_array {
    static_assert(std::is_trivially_default_constructible_v<T> && std::is_trivially_destructible_v<T>);

public:
    scratch_array() = default;
    scratch_array(std::size_t n, std::pmr::memory_resource* from)
        : data_(n ? static_cast<T*>(from->allocate(bytes_of(n), alignof(T))) : nullptr), size_(n), from_(from)
    {
    }
    scratch_array(scratch_array&& other) noexcept
        : data_(std::exchange(other.data_, nullptr)), size_(std::exchange(other.size_, 0)), from_(other.from_)
    {
    }
    scratch_array& operator=(scratch_array&& other) noexcept
    {
        if (this != &other) {
            free();
            data_ = std::exchange(other.data_, nullptr), size_ = std::exchange(other.size_, 0), from_ = other.from_;
        }
        return *this;
    }
    ~scratch_array() { free(); }

    T* get() const { return data_; }
    std::size_t size() const { return size_; }
    T& operator[](std::size_t i) const { return data_[i]; }

private:
    static std::size_t bytes_of(std::size_t n)
    {
        if (n > std::numeric_limits<std::size_t>::max() / sizeof(T)) throw std::bad_array_new_length();
        return n * sizeof(T);
    }
    void free()
    {
        if (data_) from_->deallocate(data_, size_ * sizeof(T), alignof(T));
        data_ = nullptr, size_ = 0;
    }
    T* data_ = nullptr;
    std::size_t size_ = 0;
    std::pmr::memory_resource* from_ = nullptr;
};

// The resource creation draws from: the caller's scratch, or plain new and delete.
inline std::pmr::memory_resource* scratch_or_default(std::pmr::memory_resource* scratch)
{
    return scratch ? scratch : std::pmr::new_delete_resource();
}

} // namespace hypertree

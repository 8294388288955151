#pragma once
// zeroed_array<T>: a fixed-size array that starts all zero, allocated so that the zeros cost
// nothing until a page is written, and on huge pages where the system offers them.
//
// A dense grid (2 bytes for each of 300^3 voxels: 54 MB) or an occupancy bit array over a wide
// index range is mostly zeros, and a tree writes a few of its pages. std::vector value-initializes
// every element: it writes all 54 MB, so every page faults in and is cleared twice (by the kernel,
// then by the memset). The block here comes from pages::allocate_zeroed (huge_pages.hpp): fresh
// pages from the kernel, zero on first touch and not cleared again, on 2 MiB pages where Linux
// offers them so that a 54 MB grid costs 27 faults rather than 13,000. Reading an untouched page
// sees zeros.
//
// A store built again at the same size keeps its array (see the stores' build with a recycled
// store): the store sets back to zero the elements it wrote, which it knows and the array does
// not, and reuse() then lends the same block again, without a fault.
//
// A value type like the vector it replaces: copies copy the elements, moves move the block. For
// element types whose zero value is all-zero bytes (integers, floats, and aggregates of them).

#include "hypertree/huge_pages.hpp"

#include <algorithm>
#include <cstddef>
#include <new>
#include <type_traits>
#include <utility>

namespace hypertree {

template <class T>
class zeroed_array {
    static_assert(std::is_trivially_copyable_v<T>, "zeroed_array copies its elements as bytes");
    static_assert(alignof(T) <= alignof(std::max_align_t), "blocks are aligned for the fundamental alignments only");

public:
    zeroed_array() = default;
    explicit zeroed_array(std::size_t size) : size_(size), capacity_(size), data_(allocate(size)) {}
    zeroed_array(const zeroed_array& other) : zeroed_array(other.size_)
    {
        std::copy_n(other.data(), size_, data());
    }
    zeroed_array(zeroed_array&& other) noexcept
        : size_(std::exchange(other.size_, 0)), capacity_(std::exchange(other.capacity_, 0)),
          data_(std::exchange(other.data_, nullptr))
    {
    }
    zeroed_array& operator=(const zeroed_array& other)
    {
        if (this != &other) *this = zeroed_array(other);
        return *this;
    }
    zeroed_array& operator=(zeroed_array&& other) noexcept
    {
        if (this != &other) {
            free();
            size_ = std::exchange(other.size_, 0);
            capacity_ = std::exchange(other.capacity_, 0);
            data_ = std::exchange(other.data_, nullptr);
        }
        return *this;
    }
    ~zeroed_array() { free(); }

    std::size_t size() const { return size_; }
    // Elements the block holds: size() or, after reuse() for fewer, more.
    std::size_t capacity() const { return capacity_; }
    T* data() { return data_; }
    const T* data() const { return data_; }
    T& operator[](std::size_t i) { return data_[i]; }
    const T& operator[](std::size_t i) const { return data_[i]; }

    // Whether reuse(size) would keep this block: it holds `size` elements and is at most twice
    // as large (a small array should not pin a large block, as create/scratch.hpp's rule).
    bool reusable_for(std::size_t size) const { return size <= capacity_ && capacity_ / 2 <= size && size > 0; }
    // Precondition: every element of the block is zero again (the caller cleared what it wrote).
    // Makes this a zeroed array of `size` elements, in its own block when reusable_for(size), or
    // in a new one.
    void reuse(std::size_t size)
    {
        if (reusable_for(size)) size_ = size;
        else *this = zeroed_array(size);
    }

private:
    static T* allocate(std::size_t size)
    {
        if (size == 0) return nullptr;
        if (size > std::size_t(-1) / 2 / sizeof(T)) throw std::bad_alloc();
        return static_cast<T*>(pages::allocate_zeroed(size * sizeof(T)));
    }
    void free() noexcept
    {
        pages::release(data_, capacity_ * sizeof(T));
        data_ = nullptr;
    }

    std::size_t size_ = 0, capacity_ = 0;
    T* data_ = nullptr;
};

} // namespace hypertree

#pragma once
// zeroed_array<T>: a fixed-size array that starts all zero, allocated so that the zeros cost
// nothing until a page is written.
//
// A dense grid (2 bytes for each of 300^3 voxels: 54 MB) or an occupancy bit array over a wide
// index range is mostly zeros, and a tree writes a few of its pages. std::vector value-initializes
// every element: it writes all 54 MB, so every page faults in and is cleared twice (by the kernel,
// then by the memset). calloc gets a block this large from the kernel as fresh pages, which the
// kernel supplies zero on first touch and which calloc therefore does not clear (glibc maps blocks
// above its mmap threshold, at least 128 KiB, and skips clearing memory it has just obtained from
// the kernel): only the pages a tree writes cost anything, and reading an untouched page sees
// zeros. Tree A at 300: building the dense store took 22-25 ms with a vector and 4-6 ms this way.
//
// A value type like the vector it replaces: copies copy the elements, moves move the block. For
// element types whose zero value is all-zero bytes (integers, floats, and aggregates of them).

#include <algorithm>
#include <cstddef>
#include <cstdlib>
#include <memory>
#include <new>
#include <type_traits>
#include <utility>

namespace hypertree {

template <class T>
class zeroed_array {
    static_assert(std::is_trivially_copyable_v<T>, "zeroed_array copies its elements as bytes");
    static_assert(alignof(T) <= alignof(std::max_align_t), "calloc aligns for the fundamental alignments only");

public:
    zeroed_array() = default;
    explicit zeroed_array(std::size_t size) : size_(size), data_(allocate(size, true)) {}
    zeroed_array(const zeroed_array& other) : size_(other.size_), data_(allocate(other.size_, false))
    {
        std::copy_n(other.data(), size_, data()); // every element written: no zeros needed first
    }
    zeroed_array(zeroed_array&& other) noexcept : size_(std::exchange(other.size_, 0)), data_(std::move(other.data_)) {}
    zeroed_array& operator=(const zeroed_array& other)
    {
        if (this != &other) *this = zeroed_array(other);
        return *this;
    }
    zeroed_array& operator=(zeroed_array&& other) noexcept
    {
        size_ = std::exchange(other.size_, 0);
        data_ = std::move(other.data_);
        return *this;
    }

    std::size_t size() const { return size_; }
    T* data() { return data_.get(); }
    const T* data() const { return data_.get(); }
    T& operator[](std::size_t i) { return data_[i]; }
    const T& operator[](std::size_t i) const { return data_[i]; }

private:
    struct release {
        void operator()(T* p) const { std::free(p); }
    };
    static std::unique_ptr<T[], release> allocate(std::size_t size, bool zeroed)
    {
        if (size == 0) return nullptr;
        if (!zeroed && size > std::size_t(-1) / sizeof(T)) throw std::bad_alloc();
        void* p = zeroed ? std::calloc(size, sizeof(T)) : std::malloc(size * sizeof(T));
        if (!p) throw std::bad_alloc();
        return std::unique_ptr<T[], release>(static_cast<T*>(p));
    }

    std::size_t size_ = 0;
    std::unique_ptr<T[], release> data_;
};

} // namespace hypertree

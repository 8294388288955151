#pragma once
// zeroed_array<T>: a fixed-size array of trivially copyable T that starts all zero, allocated so
// that the zeros cost nothing until a page is written.
//
// A dense grid (2 bytes for each of 300^3 voxels: 54 MB) or an occupancy bit array over a wide
// index range is mostly zeros, and a tree writes a few of its pages. std::vector value-initializes
// every element: it writes all 54 MB, so every page faults in and is cleared twice (by the kernel,
// then by the memset). calloc of a large block maps fresh pages that the kernel supplies already
// zero on first touch, so only the pages a tree writes cost anything; reading an untouched page
// sees zeros. Tree A at 300: building the dense store took 25 ms with a vector and 6 ms this way.
//
// A value type like the vector it replaces: copies copy the elements, moves move the block.

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
    static_assert(std::is_trivially_copyable_v<T>, "zeroed_array holds trivially copyable elements (all-zero bytes are their zero)");

public:
    zeroed_array() = default;
    explicit zeroed_array(std::size_t size) : size_(size), data_(allocate(size)) {}
    zeroed_array(const zeroed_array& other) : size_(other.size_), data_(allocate(other.size_))
    {
        std::copy_n(other.data(), size_, data());
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
    static std::unique_ptr<T[], release> allocate(std::size_t size)
    {
        if (size == 0) return nullptr;
        void* p = std::calloc(size, sizeof(T));
        if (!p) throw std::bad_alloc();
        return std::unique_ptr<T[], release>(static_cast<T*>(p));
    }

    std::size_t size_ = 0;
    std::unique_ptr<T[], release> data_;
};

} // namespace hypertree

// Scratch memory for creation (create/scratch.hpp): released blocks are kept and lent again, each to
// one user at a time, checked by the addresses it hands out and by writing every byte lent.

#include "hypertree/create/scratch.hpp"

#include "support/voxel_reference.hpp"

#include <doctest/doctest.h>

#include <algorithm>
#include <atomic>
#include <cstddef>
#include <cstdint>
#include <memory_resource>
#include <new>
#include <random>
#include <thread>
#include <vector>

namespace {
using krs_test::integer;
} // namespace

TEST_CASE("scratch memory keeps released blocks and lends them again")
{
    hypertree::scratch_memory scratch;
    std::pmr::memory_resource& r = scratch;
    void* a = r.allocate(1 << 20, 64);
    CHECK(reinterpret_cast<std::uintptr_t>(a) % 64 == 0);
    CHECK(scratch.system_allocations() == 1);
    CHECK(scratch.kept_bytes() == 0);
    r.deallocate(a, 1 << 20, 64);
    CHECK(scratch.kept_bytes() == std::size_t(1) << 20);
    // The same size, and a request a little smaller, take the kept block back.
    void* b = r.allocate((1 << 20) - 1000, 8);
    CHECK(b == a);
    CHECK(scratch.system_allocations() == 1);
    // A request under half the kept block does not pin it: a new block.
    r.deallocate(b, (1 << 20) - 1000, 8);
    void* c = r.allocate(100000, 4);
    CHECK(c != a);
    CHECK(scratch.system_allocations() == 2);
    CHECK(scratch.kept_bytes() == std::size_t(1) << 20);
    // A larger request than any kept block: a new block.
    void* d = r.allocate(2 << 20, 16);
    CHECK(scratch.system_allocations() == 3);
    // release() frees the kept blocks; blocks lent out stay valid and are kept when returned.
    scratch.release();
    CHECK(scratch.kept_bytes() == 0);
    std::fill_n(static_cast<char*>(d), 2 << 20, 'x');
    r.deallocate(d, 2 << 20, 16);
    r.deallocate(c, 100000, 4);
    CHECK(scratch.kept_bytes() >= std::size_t(2 << 20) + 100000);
    // More than cache-line alignment is not offered.
    CHECK_THROWS_AS((void)r.allocate(4096, 128), std::bad_alloc);
    // std::pmr containers draw from it.
    std::pmr::vector<int> v(&scratch);
    v.assign(300000, 7);
    CHECK(std::count(v.begin(), v.end(), 7) == 300000);
}

TEST_CASE("scratch memory lends each block to one user at a time across threads")
{
    // Two threads take and return blocks of varied sizes; each fills its block with its own mark
    // and checks it before returning it, so a block lent twice at once would show the other's.
    hypertree::scratch_memory scratch;
    std::atomic<int> corrupted{0};
    std::vector<std::thread> threads;
    for (int t = 0; t < 2; ++t)
        threads.emplace_back([&, t] {
            std::mt19937_64 g(std::uint64_t(100 + t));
            for (int round = 0; round < 400; ++round) {
                const std::size_t bytes = integer(g, 1, 200000);
                auto* p = static_cast<unsigned char*>(static_cast<std::pmr::memory_resource&>(scratch).allocate(bytes, 8));
                std::fill_n(p, bytes, static_cast<unsigned char>(t + 1));
                std::this_thread::yield();
                if (std::count(p, p + bytes, static_cast<unsigned char>(t + 1)) != std::ptrdiff_t(bytes)) ++corrupted;
                static_cast<std::pmr::memory_resource&>(scratch).deallocate(p, bytes, 8);
            }
        });
    for (std::thread& t : threads) t.join();
    CHECK(corrupted == 0);
    CHECK(scratch.system_allocations() < 800); // blocks were reused
}

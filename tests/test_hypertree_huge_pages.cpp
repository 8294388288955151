// Large zeroed blocks (huge_pages.hpp): zero, writable to their last byte and aligned as promised,
// with huge pages asked for or not.

#include "hypertree/huge_pages.hpp"

#include <doctest/doctest.h>

#include <algorithm>
#include <cstddef>
#include <cstdint>
#include <new>

TEST_CASE("huge-page blocks are zero, writable to their end and aligned as promised, with huge pages asked or not")
{
    for (const bool wanted : {true, false}) {
        hypertree::huge_pages_wanted = wanted;
        // Under, at and over half a huge page (where blocks start to be mapped on Linux), a whole
        // huge page, an odd size over several, and the 54 MB of a dense store at 300.
        for (const std::size_t bytes : {std::size_t(100), (std::size_t(1) << 20) - 8, std::size_t(1) << 20,
                                        std::size_t(2) << 20, (std::size_t(7) << 20) + 24, std::size_t(54000000)}) {
            INFO(bytes << " bytes, huge pages wanted " << wanted);
            auto* p = static_cast<unsigned char*>(hypertree::pages::allocate_zeroed(bytes));
            REQUIRE(p != nullptr);
            const auto address = reinterpret_cast<std::uintptr_t>(p);
            CHECK(address % alignof(std::max_align_t) == 0);
            CHECK(address % hypertree::pages::alignment(bytes) == 0);
#ifdef __linux__
            // The promise in numbers: from 1 MiB on, a block starts on a 2 MiB boundary.
            if (bytes >= (std::size_t(1) << 20)) CHECK(address % (std::size_t(2) << 20) == 0);
            else CHECK(hypertree::pages::alignment(bytes) == alignof(std::max_align_t));
#endif
            CHECK(std::all_of(p, p + bytes, [](unsigned char b) { return b == 0; }));
            std::fill(p, p + bytes, 0xab); // every byte is ours: no fault past the end
            CHECK(p[bytes - 1] == 0xab);
            hypertree::pages::release(p, bytes);
        }
    }
    hypertree::huge_pages_wanted = true;
    CHECK_THROWS_AS((void)hypertree::pages::allocate_zeroed(0), std::bad_alloc);
}

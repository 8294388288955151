#pragma once
// Large blocks of zeroed memory that ask the system for huge pages where it offers them.
//
// The system hands out fresh memory page by page: the first write to each page faults, and the
// kernel finds a page, clears it and maps it. With 4 KiB pages the 54 MB dense store at
// resolution 300 is 13,000 faults, and what one costs differs from machine to machine (a second
// machine measured 45 ms for a build this one did in 10). Linux can back a region with 2 MiB
// pages instead, one fault per 512 small ones; where transparent huge pages are set to `madvise`
// (a common default, and this project's machine) it does so only for regions that ask with
// madvise(MADV_HUGEPAGE), and only for the whole 2 MiB pages that lie inside the region. So a
// large block here is mapped directly (mmap), placed on a 2 MiB boundary, sized to whole huge
// pages, and marked. Memory mapped this way is zero without anyone writing it, and the kernel
// clears each page once, as it maps it: nothing here clears it again.
//
// Blocks under half a huge page, and every block where the system is not Linux, come from
// calloc, which is what zeroed_array used before: glibc also maps blocks over its threshold
// (128 KiB at least) fresh and does not clear them again.
//
// The process-wide switch `huge_pages_wanted` turns the request off (blocks are then still
// mapped alike, on 4 KiB pages): for measuring the difference, and for systems where the
// kernel's compaction to find a free 2 MiB page costs more than the faults it saves.
//
// krs::hypertree depends on nothing: the POSIX calls are made only under __linux__.

#include <atomic>
#include <cstddef>
#include <cstdint>
#include <cstdlib>
#include <new>

#ifdef __linux__
#include <sys/mman.h>
#endif

namespace hypertree {

// Whether large blocks ask for huge pages (read at each allocation; on by default).
inline std::atomic<bool> huge_pages_wanted{true};

namespace pages {

inline constexpr std::size_t huge_page_bytes = std::size_t(2) << 20; // x86-64 and arm64 with 4 KiB base pages

// Whether a block of `bytes` is mapped on its own (Linux, and at least half a huge page: rounding
// it up to whole huge pages then wastes at most half of what it maps).
inline constexpr bool mapped(std::size_t bytes)
{
#ifdef __linux__
    return bytes >= huge_page_bytes / 2;
#else
    (void)bytes;
    return false;
#endif
}

// The alignment a block of `bytes` from allocate_zeroed has: a huge page for mapped blocks,
// the fundamental alignment (calloc's) for the others.
inline constexpr std::size_t alignment(std::size_t bytes)
{
    return mapped(bytes) ? huge_page_bytes : alignof(std::max_align_t);
}

// The bytes a block of `bytes` occupies: whole huge pages when mapped.
inline constexpr std::size_t reserved(std::size_t bytes)
{
    return mapped(bytes) ? (bytes + huge_page_bytes - 1) / huge_page_bytes * huge_page_bytes : bytes;
}

// `bytes` of zeros (bytes > 0), aligned to alignment(bytes); throws std::bad_alloc when the
// system has no memory for it. Give it back with release(p, bytes), the same `bytes`.
inline void* allocate_zeroed(std::size_t bytes)
{
    if (bytes == 0 || bytes > std::size_t(-1) / 2) throw std::bad_alloc();
#ifdef __linux__
    if (mapped(bytes)) {
        // Over-map by one huge page and unmap the head and tail, so the block starts on a 2 MiB
        // boundary: the kernel uses a huge page only for a 2 MiB-aligned stretch of a region.
        const std::size_t size = reserved(bytes);
        void* raw = ::mmap(nullptr, size + huge_page_bytes, PROT_READ | PROT_WRITE, MAP_PRIVATE | MAP_ANONYMOUS, -1, 0);
        if (raw == MAP_FAILED) throw std::bad_alloc();
        char* const start = static_cast<char*>(raw);
        const std::size_t head = (huge_page_bytes - reinterpret_cast<std::uintptr_t>(start) % huge_page_bytes) % huge_page_bytes;
        if (head) ::munmap(start, head);
        if (huge_page_bytes - head) ::munmap(start + head + size, huge_page_bytes - head);
        // Advice only: a kernel without transparent huge pages refuses it, and the block is
        // then what it would have been without asking.
        if (huge_pages_wanted.load(std::memory_order_relaxed)) (void)::madvise(start + head, size, MADV_HUGEPAGE);
        return start + head;
    }
#endif
    void* p = std::calloc(1, bytes);
    if (!p) throw std::bad_alloc();
    return p;
}

// Gives back a block from allocate_zeroed(bytes) (nothing for a null p).
inline void release(void* p, std::size_t bytes) noexcept
{
    if (!p) return;
#ifdef __linux__
    if (mapped(bytes)) {
        ::munmap(p, reserved(bytes));
        return;
    }
#endif
    std::free(p);
}

} // namespace pages
} // namespace hypertree

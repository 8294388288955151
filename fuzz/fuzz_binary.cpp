// libFuzzer target: loading saved hypertrees (issue 10, "fuzzing"; include/hypertree/io/binary.hpp).
//
// Input layout: byte 0 is a selector, the rest is the file.
//   bits 0-1  the store kind to load as: dense, index list, bit array, partitioned;
//   bit 2     recompute the file's checksum: the last 8 bytes are overwritten with the FNV-1a 64 of
//             the bytes before them, so that mutated headers and voxel lists get past the checksum
//             (random bytes almost never match it) and reach the checks behind it;
//   bit 3     append a byte after the file (a stream may hold more after the tree).
// The load uses a 64 MiB memory budget, so a file that claims a huge grid or voxel count must be
// refused (load_error) before anything that size is allocated; ASan's allocation limit and the
// RSS limit of scripts/fuzz.sh catch one that is not.
//
// Each load must either throw hypertree::load_error or return a store that holds what the file
// says: load_voxels on the same bytes gives the same hypervolume and voxels, every listed voxel
// reads back with its density and level through at(), the store counts exactly those, and saving
// the store and loading that again gives the same store (a second save writes the same bytes).
// Anything else (another exception, a sanitizer report, a hang) aborts.
//
// Define KRS_FUZZ_VERBOSE to print each input's outcome. fuzz/replay_main.cpp runs the same
// function over fuzz/corpus/binary/ and fuzz/crashers/binary/ in ctest.

#include "fuzz_input.hpp"
#include "hypertree/execution.hpp"
#include "hypertree/io/binary.hpp"
#include "hypertree/store/store_kinds.hpp"

#include <cstddef>
#include <cstdint>
#include <sstream>
#include <string>

namespace {

using namespace hypertree;

using krs_fuzz::fail;
using krs_fuzz::note;

constexpr memory_budget budget{std::size_t(64) << 20};

std::string saved(const auto& store)
{
    std::ostringstream out(std::ios::binary);
    save(store, out);
    return std::move(out).str();
}

template <voxel_store S>
void check_load(const std::string& file)
{
    std::istringstream in(file, std::ios::binary);
    S store;
    try {
        store = load<S>(in, budget);
    } catch (const load_error& e) {
        note("refused", e.what());
        return;
    }
    // The same bytes, read without building a store: what the store must hold.
    std::istringstream again(file, std::ios::binary);
    const loaded_voxels expected = load_voxels(again);
    const hypervolume& v = store.volume();
    if (v.grid().x != expected.volume.grid().x || v.grid().y != expected.volume.grid().y || v.grid().z != expected.volume.grid().z)
        fail();
    if (store.nonempty_count() != expected.voxels.size()) fail();
    for (const stored_voxel& s : expected.voxels) {
        const voxel got = store.at(s.index);
        if (got.density != s.value.density || got.level != s.value.level) fail();
    }
    std::size_t visited = 0;
    store.for_each([&](voxel_index, voxel) { ++visited; });
    if (visited != expected.voxels.size()) fail();

    // Saving is a fixed point after one load: save -> load -> save writes the same bytes.
    const std::string first = saved(store);
    std::istringstream reread(first, std::ios::binary);
    const S reloaded = load<S>(reread, budget);
    if (saved(reloaded) != first) fail();
    note("loaded", "ok");
}

} // namespace

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size)
{
    if (size == 0) return 0;
    const std::uint8_t selector = data[0];
    std::string file(reinterpret_cast<const char*>(data + 1), size - 1);
    if ((selector & 4) && file.size() >= binary_format::checksum_bytes) {
        const std::size_t body = file.size() - binary_format::checksum_bytes;
        detail::fnv1a64 sum;
        sum.add(reinterpret_cast<const unsigned char*>(file.data()), body);
        for (std::size_t i = 0; i < binary_format::checksum_bytes; ++i)
            file[body + i] = char(static_cast<unsigned char>(sum.value() >> (8 * i)));
    }
    if (selector & 8) file.push_back('\x5a');
    try {
        static_assert(std::tuple_size_v<store_kinds> == 4, "two selector bits pick the store kind");
        with_store(storage_type(selector & 3), [&]<class S>() { check_load<S>(file); });
    } catch (...) {
        fail();
    }
    return 0;
}

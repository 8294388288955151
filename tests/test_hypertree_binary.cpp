// Saving and loading hypertrees (paper section 10): round trips through every store kind, the
// exact byte layout, and refusal of every truncation, every changed byte and each kind of bad
// header with its own message. The checksum used to forge structurally bad files is written here
// from the FNV-1a definition, not taken from the library.

#include "hypertree/build.hpp"
#include "hypertree/execution.hpp"
#include "hypertree/io/binary.hpp"
#include "hypertree/presets.hpp"
#include "hypertree/store/store_kinds.hpp"

#include <doctest/doctest.h>

#include <algorithm>
#include <cstdint>
#include <filesystem>
#include <fstream>
#include <iterator>
#include <random>
#include <sstream>
#include <streambuf>
#include <string>
#include <vector>

namespace {
using hypertree::hypervolume;
using hypertree::load_error;
using hypertree::resolution;
using hypertree::stored_voxel;
using hypertree::voxel;
using hypertree::voxel_index;

// Exactly `wanted` distinct random voxels (the byte-by-byte tests need a known count, where
// krs_test::random_voxels draws each voxel with a probability), random density, level 0..11 and
// part 0..8.
std::vector<stored_voxel> random_voxels(const hypervolume& volume, std::size_t wanted, std::uint64_t seed)
{
    std::mt19937_64 g(seed);
    std::vector<voxel_index> indices;
    while (indices.size() < wanted) {
        indices.push_back(voxel_index(g() % volume.voxel_count()));
        std::sort(indices.begin(), indices.end());
        indices.erase(std::unique(indices.begin(), indices.end()), indices.end());
    }
    std::vector<stored_voxel> voxels;
    for (voxel_index i : indices)
        voxels.push_back({i, voxel{std::uint8_t(1 + g() % 255), std::uint8_t(g() % 12)}, std::uint8_t(g() % 9)});
    return voxels;
}

// A small tree for the byte-by-byte tests: 40 voxels, 80 + 40 * 7 + 8 = 368 bytes.
const hypervolume small_volume({-0.5, 0.25, 3}, {1.5, 2, 0.75}, {9, 7, 5});
hypertree::partitioned_store small_store()
{
    return hypertree::partitioned_store::build(small_volume, random_voxels(small_volume, 40, 3));
}

template <class S>
std::string saved(const S& store)
{
    std::ostringstream out(std::ios::binary);
    hypertree::save(store, out);
    return out.str();
}

// A stream that cannot seek, as a pipe: load must then find truncation while reading.
class unseekable_buffer : public std::streambuf {
public:
    explicit unseekable_buffer(std::string bytes) : bytes_(std::move(bytes))
    {
        setg(bytes_.data(), bytes_.data(), bytes_.data() + bytes_.size());
    }

private:
    std::string bytes_;
};

// Loads `bytes` as index_list_store from a seekable stream and from an unseekable one; returns the
// message of the load_error both throw (they must agree on refusing), or "" when they load.
std::string refusal(const std::string& bytes, bool also_unseekable = true)
{
    std::string message;
    try {
        std::istringstream in(bytes, std::ios::binary);
        (void)hypertree::load<hypertree::index_list_store>(in);
    } catch (const load_error& e) {
        message = e.what();
    }
    if (also_unseekable) {
        bool refused = false;
        try {
            unseekable_buffer buffer(bytes);
            std::istream in(&buffer);
            (void)hypertree::load<hypertree::index_list_store>(in);
        } catch (const load_error&) {
            refused = true;
        }
        if (refused != !message.empty()) return "seekable and unseekable streams disagree";
    }
    return message;
}

std::uint64_t fnv1a(const std::string& bytes)
{
    std::uint64_t h = 14695981039346656037ull;
    for (unsigned char c : bytes) {
        h ^= c;
        h *= 1099511628211ull;
    }
    return h;
}
void put(std::string& bytes, std::size_t at, std::uint64_t value, int size)
{
    for (int k = 0; k < size; ++k) bytes[at + std::size_t(k)] = char((value >> (8 * k)) & 0xff);
}
// Replaces the trailing checksum with the right one for the (edited) bytes before it.
std::string resealed(std::string bytes)
{
    const std::size_t body = bytes.size() - 8;
    put(bytes, body, fnv1a(bytes.substr(0, body)), 8);
    return bytes;
}

bool mentions(const std::string& message, const std::string& part)
{
    return message.find(part) != std::string::npos;
}

// A scratch directory removed when the test ends.
struct scratch_directory {
    std::filesystem::path path = std::filesystem::temp_directory_path() /
                                 ("krs_test_hypertree_binary_" + std::to_string(std::random_device{}()));
    scratch_directory() { std::filesystem::create_directories(path); }
    ~scratch_directory()
    {
        std::error_code ignored;
        std::filesystem::remove_all(path, ignored);
    }
};

template <class A, class B>
void check_same_voxels(const A& a, const B& b, bool compare_parts)
{
    CHECK(a.volume() == b.volume());
    const std::vector<stored_voxel> x = hypertree::stored_voxels(a), y = hypertree::stored_voxels(b);
    REQUIRE(x.size() == y.size());
    int differences = 0;
    for (std::size_t k = 0; k < x.size(); ++k)
        differences += x[k].index != y[k].index || !(x[k].value == y[k].value) || (compare_parts && x[k].part != y[k].part);
    CHECK(differences == 0);
    // And every voxel of the grid answers alike.
    int lookups = 0;
    for (voxel_index i = 0; i < a.volume().voxel_count(); ++i) lookups += !(a.at(i) == b.at(i));
    CHECK(lookups == 0);
}

} // namespace

TEST_CASE_TEMPLATE_DEFINE("hypertree binary round trip of a generated tree", S, binary_round_trip)
{
    auto definition = hypertree::presets::tree_a(48);
    definition.iterations = 30000;
    const S tree = hypertree::build_tree<S>(definition, 77);
    REQUIRE(tree.nonempty_count() > 1000);
    const std::string bytes = saved(tree);
    CHECK(bytes.size() == hypertree::binary_format::file_bytes(tree.nonempty_count()));

    std::istringstream in(bytes, std::ios::binary);
    const S back = hypertree::load<S>(in);
    check_same_voxels(tree, back, true);

    // Any kind loads what any kind saved.
    std::istringstream again(bytes, std::ios::binary);
    check_same_voxels(tree, hypertree::load<hypertree::index_list_store>(again), false);

    // Through a file.
    scratch_directory dir;
    const std::filesystem::path file = dir.path / "tree.htree";
    hypertree::save(tree, file);
    CHECK(std::filesystem::file_size(file) == bytes.size());
    // Nothing but the file is left in the directory (no temporary file).
    CHECK(std::distance(std::filesystem::directory_iterator(dir.path), std::filesystem::directory_iterator()) == 1);
    check_same_voxels(tree, hypertree::load<S>(file), true);
}
TEST_CASE_TEMPLATE_APPLY(binary_round_trip, hypertree::store_kinds);

TEST_CASE("hypertree binary layout is little-endian byte by byte")
{
    const hypervolume volume({1.5, -2, 0}, {0.5, 4, 1}, {3, 513, 11000}); // room for index 0x01020304
    const std::vector<stored_voxel> voxels{{0x01020304, voxel{200, 7}, 5}, {0x01020305, voxel{1, 0}, 0}};
    const std::string bytes = saved(hypertree::partitioned_store::build(volume, voxels));
    REQUIRE(bytes.size() == 80 + 2 * 7 + 8);
    const auto at = [&](std::size_t k) { return int(static_cast<unsigned char>(bytes[k])); };
    CHECK(bytes.substr(0, 8) == "KRSHTREE");
    CHECK((at(8) == 1 && at(9) == 0 && at(10) == 0 && at(11) == 0));
    // origin.x = 1.5 = 0x3FF8000000000000: least significant byte first.
    for (int k = 0; k < 6; ++k) CHECK(at(12 + std::size_t(k)) == 0);
    CHECK((at(18) == 0xF8 && at(19) == 0x3F));
    // origin.y = -2 = 0xC000000000000000.
    CHECK(at(27) == 0xC0);
    // resolution.y = 513 = 0x0201 at bytes 64..67.
    CHECK((at(64) == 0x01 && at(65) == 0x02 && at(66) == 0 && at(67) == 0));
    CHECK((at(72) == 2 && at(73) == 0 && at(79) == 0));
    // First voxel: index 0x01020304, density 200, level 7, part 5.
    CHECK((at(80) == 0x04 && at(81) == 0x03 && at(82) == 0x02 && at(83) == 0x01));
    CHECK((at(84) == 200 && at(85) == 7 && at(86) == 5));
    CHECK(at(87) == 0x05);
    // The checksum is FNV-1a 64 of everything before it.
    std::uint64_t stored = 0;
    for (int k = 7; k >= 0; --k) stored = (stored << 8) | std::uint64_t(at(94 + std::size_t(k)));
    CHECK(stored == fnv1a(bytes.substr(0, 94)));
}

TEST_CASE("hypertree binary refuses every truncation")
{
    const std::string bytes = saved(small_store());
    REQUIRE(bytes.size() == 80 + 40 * 7 + 8);
    CHECK(refusal(bytes).empty());
    int accepted = 0;
    for (std::size_t length = 0; length < bytes.size(); ++length) {
        const std::string message = refusal(bytes.substr(0, length));
        if (message.empty() || message == "seekable and unseekable streams disagree") {
            ++accepted;
            FAIL_CHECK("a prefix of " << length << " bytes: " << (message.empty() ? "loaded" : message));
        }
    }
    CHECK(accepted == 0);
    // Messages say where the file ended and in what.
    CHECK(mentions(refusal(bytes.substr(0, 5)), "byte 5: truncated: the file ends inside the magic bytes"));
    CHECK(mentions(refusal(bytes.substr(0, 74)), "byte 74: truncated: the file ends inside the voxel count"));
    CHECK(mentions(refusal(bytes.substr(0, 100)), "only 20 remain"));
    CHECK(mentions(refusal(bytes.substr(0, bytes.size() - 3)), "only 285 remain"));
    // Without seeking, the reader finds the end inside a voxel or the checksum.
    std::string unseekable_message;
    try {
        unseekable_buffer buffer(bytes.substr(0, 100));
        std::istream in(&buffer);
        (void)hypertree::load<hypertree::index_list_store>(in);
    } catch (const load_error& e) {
        unseekable_message = e.what();
        CHECK(e.offset() == 100u);
    }
    CHECK(mentions(unseekable_message, "byte 100: truncated: the file ends inside voxel 2 of 40"));
}

TEST_CASE("hypertree binary refuses every changed byte")
{
    const std::string bytes = saved(small_store());
    int accepted = 0;
    for (std::size_t k = 0; k < bytes.size(); ++k)
        for (const unsigned char flip : {static_cast<unsigned char>(0xFF), static_cast<unsigned char>(1u << (k % 8))}) {
            std::string changed = bytes;
            changed[k] = char(static_cast<unsigned char>(changed[k]) ^ flip);
            const std::string message = refusal(changed, k % 7 == 0);
            if (message.empty() || message == "seekable and unseekable streams disagree") {
                ++accepted;
                FAIL_CHECK("byte " << k << " xor " << int(flip) << ": " << (message.empty() ? "loaded" : message));
            }
        }
    CHECK(accepted == 0);
    // A changed voxel byte is a checksum mismatch reported at the checksum's offset.
    std::string changed = bytes;
    changed[123] = char(changed[123] ^ 0x10);
    CHECK(mentions(refusal(changed), "byte 360: checksum mismatch"));
}

TEST_CASE("hypertree binary header errors name what is wrong")
{
    const std::string bytes = saved(small_store());
    SUBCASE("wrong magic")
    {
        std::string b = bytes;
        b[3] = 'X';
        const std::string message = refusal(b);
        CHECK(mentions(message, "byte 0: not a saved hypertree"));
        CHECK(mentions(message, "KRSHTREE"));
        // A short file of something else is not a hypertree either, rather than a truncated one.
        CHECK(mentions(refusal("hello"), "byte 0: not a saved hypertree"));
        CHECK(mentions(refusal(""), "byte 0: truncated: the file ends inside the magic bytes"));
    }
    SUBCASE("wrong version")
    {
        std::string b = bytes;
        put(b, 8, 2, 4);
        CHECK(mentions(refusal(resealed(b)), "byte 8: unsupported format version 2 (this library reads version 1)"));
    }
    SUBCASE("voxel count beyond the volume")
    {
        std::string b = bytes;
        put(b, 72, std::uint64_t(1) << 60, 8);
        CHECK(mentions(refusal(resealed(b)),
                       "byte 72: the voxel count 1152921504606846976 exceeds the hypervolume's 315 voxels"));
    }
    SUBCASE("voxel count beyond the file")
    {
        std::string b = bytes;
        put(b, 72, 300, 8);
        CHECK(mentions(refusal(resealed(b)), "byte 72: the voxel count 300 needs 2108 more bytes"));
    }
    SUBCASE("bad hypervolume fields")
    {
        std::string b = bytes;
        put(b, 36 + 8, 0xBFF0000000000000ull, 8); // extent.y = -1
        CHECK(mentions(refusal(resealed(b)), "byte 44: the hypervolume extent's y must be finite and > 0"));
        b = bytes;
        put(b, 12 + 16, 0x7FF8000000000000ull, 8); // origin.z = NaN
        CHECK(mentions(refusal(resealed(b)), "byte 28: the hypervolume origin's z is not finite"));
        b = bytes;
        put(b, 60 + 4, 0xFFFFFFFFull, 4); // resolution.y = -1
        CHECK(mentions(refusal(resealed(b)), "byte 64: the resolution's y must be >= 1 (got -1)"));
        b = bytes;
        put(b, 60, 100000, 4), put(b, 64, 100000, 4);
        CHECK(mentions(refusal(resealed(b)), "names more than 2^32 - 1 voxels"));
        // Finite and positive, but no box float can place: refused at load, by the field's name (such
        // files loaded, and the marcher then blamed its own step factor).
        b = bytes;
        put(b, 36, 1, 8); // extent.x = 5e-324
        CHECK(mentions(refusal(resealed(b)), "byte 12: invalid hypervolume: krs: hypervolume.extent.x: gives voxels of side 0"));
        b = bytes;
        put(b, 12, 0x7FE0000000000000ull, 8); // origin.x = 2^1023
        CHECK(mentions(refusal(resealed(b)), "byte 12: invalid hypervolume: krs: hypervolume.origin"));
    }
    SUBCASE("voxels out of order, empty or outside, with a valid checksum")
    {
        std::string b = bytes;
        // Swap the first two voxels' indices.
        const std::string first = b.substr(80, 4), second = b.substr(87, 4);
        b.replace(80, 4, second), b.replace(87, 4, first);
        CHECK(mentions(refusal(resealed(b)), "byte 87: voxel 1 has index"));
        CHECK(mentions(refusal(resealed(b)), "(indices must increase strictly)"));
        b = bytes;
        b[80 + 7 * 5 + 4] = 0;
        CHECK(mentions(refusal(resealed(b)), "byte 119: voxel 5 has density 0"));
        b = bytes;
        put(b, 80 + 7 * 39, 315, 4);
        CHECK(mentions(refusal(resealed(b)), "byte 353: voxel 39 has index 315 outside the hypervolume's 315 voxels"));
    }
}

TEST_CASE("hypertree binary files by path")
{
    scratch_directory dir;
    const auto store = small_store();
    SUBCASE("a missing file is named")
    {
        const std::filesystem::path missing = dir.path / "no such tree.htree";
        try {
            (void)hypertree::load<hypertree::dense_store>(missing);
            FAIL("loaded a missing file");
        } catch (const load_error& e) {
            CHECK(e.file() == missing.string());
            CHECK(std::string(e.what()) == missing.string() + ": cannot open: no such file");
        }
    }
    SUBCASE("errors in a file name it and the byte")
    {
        const std::filesystem::path file = dir.path / "cut.htree";
        const std::string bytes = saved(store);
        std::ofstream(file, std::ios::binary) << bytes.substr(0, 50);
        try {
            (void)hypertree::load<hypertree::index_list_store>(file);
            FAIL("loaded a truncated file");
        } catch (const load_error& e) {
            CHECK(std::string(e.what()) == file.string() + ": byte 50: truncated: the file ends inside the "
                                                           "hypervolume extent (10 more bytes expected)");
            CHECK(e.offset() == 50u);
        }
        // A file must end with its checksum; a stream may go on.
        std::ofstream(file, std::ios::binary) << bytes << 'x';
        CHECK_THROWS_WITH_AS((void)hypertree::load<hypertree::index_list_store>(file),
                             doctest::Contains("byte 368: unexpected bytes after the checksum"), load_error);
    }
    SUBCASE("saving replaces a file whole, and refuses an impossible path")
    {
        const std::filesystem::path file = dir.path / "tree.htree";
        std::ofstream(file) << "an older tree";
        hypertree::save(store, file);
        check_same_voxels(store, hypertree::load<hypertree::partitioned_store>(file), true);
        CHECK_THROWS_WITH_AS(hypertree::save(store, dir.path / "missing directory" / "tree.htree"),
                             doctest::Contains("cannot open"), hypertree::save_error);
    }
    SUBCASE("saving never touches a file of the user's named like its temporary file, nor leaves one")
    {
        // The temporary file was "<path>.partial", overwritten and then renamed away.
        const std::filesystem::path file = dir.path / "tree.htree", mine = dir.path / "tree.htree.partial";
        std::ofstream(mine) << "the user's own file";
        hypertree::save(store, file);
        hypertree::save(store, file); // over an existing file too
        check_same_voxels(store, hypertree::load<hypertree::partitioned_store>(file), true);
        std::ifstream in(mine);
        CHECK(std::string(std::istreambuf_iterator<char>(in), {}) == "the user's own file");
        std::size_t entries = 0;
        for (const auto& e : std::filesystem::directory_iterator(dir.path))
            entries += e.path().filename().string().starts_with("tree.htree");
        CHECK(entries == 2);
    }
}

TEST_CASE("hypertree binary streams hold several trees and empty ones")
{
    const auto a = small_store();
    const auto b = hypertree::index_list_store::build(small_volume, {});
    std::stringstream stream(std::ios::in | std::ios::out | std::ios::binary);
    hypertree::save(a, stream);
    hypertree::save(b, stream);
    const auto a_back = hypertree::load<hypertree::partitioned_store>(stream);
    const auto b_back = hypertree::load<hypertree::dense_store>(stream);
    check_same_voxels(a, a_back, true);
    check_same_voxels(b, b_back, false);
    CHECK(b_back.nonempty_count() == 0);

    // A stream that fails is reported, not ignored.
    std::ostream broken(nullptr);
    CHECK_THROWS_AS(hypertree::save(a, broken), hypertree::save_error);

    // The memory budget still applies, as a load_error.
    std::istringstream in(saved(a), std::ios::binary);
    CHECK_THROWS_WITH_AS((void)hypertree::load<hypertree::dense_store>(in, hypertree::memory_budget{100}),
                         doctest::Contains("cannot build the store"), load_error);
}

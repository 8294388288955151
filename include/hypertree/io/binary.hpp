#pragma once
// Saving a generated hypertree and loading it back (paper section 10: "the generated hypertree
// can be saved for later use"), so the chaos game need not run again.
//
// The file holds what every store is built from: the hypervolume and the sorted list of
// non-empty voxels. All numbers are little-endian, written byte by byte (never a struct's memory),
// so a file reads the same on every machine:
//
//     offset  size       field
//     0       8          magic "KRSHTREE"
//     8       4          format version, uint32 (1)
//     12      3 x 8      hypervolume origin x, y, z: IEEE-754 binary64
//     36      3 x 8      hypervolume extent x, y, z: IEEE-754 binary64
//     60      3 x 4      resolution x, y, z: int32
//     72      8          voxel count N, uint64
//     80      N x 7      voxels in increasing index order: index uint32, density uint8 (> 0),
//                        level uint8, part uint8
//     80+7N   8          FNV-1a 64 checksum of bytes 0 .. 80+7N-1, uint64
//
// Loading trusts nothing: it checks the magic, the version and the hypervolume, refuses a voxel
// count larger than the hypervolume or than the bytes left in the stream before allocating
// anything for the voxels, reads the voxels and the checksum, verifies the checksum, then checks
// each voxel (index inside the volume, density > 0, indices strictly increasing), and only then
// builds the store: a bad file never yields a half-loaded tree. Every refusal is a `load_error`
// naming the file (when loading from a path), the byte offset and what was wrong. FNV-1a's step
// (xor a byte, multiply by an odd constant mod 2^64) is a bijection of the state for each byte,
// so a file with any single byte changed always fails the checksum.
//
// A stream may hold more after the tree (load reads exactly the tree's bytes); a file loaded by
// path must end with the checksum.

#include "hypertree/execution.hpp"
#include "hypertree/store/store.hpp"
#include "krs/io/write_then_rename.hpp"

#include <algorithm>
#include <array>
#include <atomic>
#include <bit>
#include <cerrno>
#include <cmath>
#include <cstddef>
#include <cstdint>
#include <cstdio>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <istream>
#include <limits>
#include <optional>
#include <ostream>
#include <stdexcept>
#include <string>
#include <string_view>
#include <system_error>
#include <utility>
#include <vector>

namespace hypertree {

// A file (or stream) that is not a valid saved hypertree. what() reads
// "<file>: byte <offset>: <message>", without the file part for an unnamed stream and without the
// offset when the file could not be opened.
class load_error : public std::runtime_error {
public:
    load_error(std::string_view file, std::optional<std::uint64_t> offset, std::string_view message)
        : std::runtime_error(compose(file, offset, message)), file_(file), offset_(offset), message_(message)
    {
    }
    const std::string& file() const noexcept { return file_; }
    std::optional<std::uint64_t> offset() const noexcept { return offset_; }
    const std::string& message() const noexcept { return message_; }

private:
    static std::string compose(std::string_view file, std::optional<std::uint64_t> offset, std::string_view message)
    {
        std::string s;
        if (!file.empty()) s += std::string(file) + ": ";
        if (offset) s += "byte " + std::to_string(*offset) + ": ";
        return s + std::string(message);
    }
    std::string file_;
    std::optional<std::uint64_t> offset_;
    std::string message_;
};

// A tree that could not be written (the stream failed, the file could not be created): the one
// save error of krs and hypertree (krs/io/write_then_rename.hpp), so either name catches it.
using krs::save_error;

namespace detail {
using krs::detail::create_partial_file;
using krs::detail::write_then_rename;
} // namespace detail

namespace binary_format {
inline constexpr std::array<char, 8> magic{'K', 'R', 'S', 'H', 'T', 'R', 'E', 'E'};
inline constexpr std::uint32_t version = 1;
inline constexpr std::size_t header_bytes = 80;
inline constexpr std::size_t voxel_bytes = 7;
inline constexpr std::size_t checksum_bytes = 8;
// Offsets of the header fields.
inline constexpr std::size_t version_offset = 8, origin_offset = 12, extent_offset = 36, resolution_offset = 60,
                             count_offset = 72;
// The size of a file holding `voxels` non-empty voxels.
constexpr std::uint64_t file_bytes(std::uint64_t voxels) { return header_bytes + voxel_bytes * voxels + checksum_bytes; }
} // namespace binary_format

// What a saved tree holds, checked, before any store is built from it.
struct loaded_voxels {
    hypervolume volume;
    std::vector<stored_voxel> voxels;
};

namespace detail {

// FNV-1a, 64-bit: state = (state xor byte) * prime, from the offset basis.
class fnv1a64 {
public:
    void add(const unsigned char* bytes, std::size_t n)
    {
        for (std::size_t i = 0; i < n; ++i) state_ = (state_ ^ bytes[i]) * 0x100000001b3ull;
    }
    std::uint64_t value() const { return state_; }

private:
    std::uint64_t state_ = 0xcbf29ce484222325ull;
};

inline void put_le(unsigned char* out, std::uint64_t v, int bytes)
{
    for (int i = 0; i < bytes; ++i) out[i] = static_cast<unsigned char>(v >> (8 * i));
}
inline std::uint64_t get_le(const unsigned char* in, int bytes)
{
    std::uint64_t v = 0;
    for (int i = 0; i < bytes; ++i) v |= std::uint64_t(in[i]) << (8 * i);
    return v;
}

// Writes in blocks and keeps the running checksum of everything written.
class binary_writer {
public:
    explicit binary_writer(std::ostream& out) : out_(out), buffer_(block) {}
    void write(const unsigned char* bytes, std::size_t n)
    {
        checksum_.add(bytes, n);
        put(bytes, n);
    }
    // Appends the checksum of everything written so far (not covering itself).
    void finish()
    {
        unsigned char sum[binary_format::checksum_bytes];
        put_le(sum, checksum_.value(), 8);
        put(sum, sizeof sum);
        flush();
        out_.flush();
        if (!out_) throw save_error("hypertree save: the output stream failed while writing");
    }

private:
    static constexpr std::size_t block = std::size_t(1) << 16;
    void put(const unsigned char* bytes, std::size_t n)
    {
        for (std::size_t i = 0; i < n; ++i) {
            buffer_[used_++] = bytes[i];
            if (used_ == buffer_.size()) flush();
        }
    }
    void flush()
    {
        out_.write(reinterpret_cast<const char*>(buffer_.data()), std::streamsize(used_));
        used_ = 0;
    }
    std::ostream& out_;
    std::vector<unsigned char> buffer_;
    std::size_t used_ = 0;
    fnv1a64 checksum_;
};

inline std::string hex(std::uint64_t v)
{
    char text[19];
    std::snprintf(text, sizeof text, "0x%016llx", static_cast<unsigned long long>(v));
    return text;
}

// Reads `n` bytes at file offset `at` into `out` or reports where the file ended and inside what.
inline void read_exactly(std::istream& in, unsigned char* out, std::size_t n, std::uint64_t at, std::string_view file,
                         std::string_view what)
{
    in.read(reinterpret_cast<char*>(out), std::streamsize(n));
    const std::uint64_t got = std::uint64_t(in.gcount());
    if (got < n)
        throw load_error(file, at + got,
                         "truncated: the file ends inside " + std::string(what) + " (" + std::to_string(n - got) +
                             " more bytes expected)");
}

inline loaded_voxels read_voxels(std::istream& in, std::string_view file)
{
    namespace f = binary_format;
    std::array<unsigned char, f::header_bytes> header{};
    // Field by field, so a truncation names the field it cut.
    const std::array<std::pair<std::size_t, const char*>, 6> fields{{{0, "the magic bytes"},
                                                                     {f::version_offset, "the format version"},
                                                                     {f::origin_offset, "the hypervolume origin"},
                                                                     {f::extent_offset, "the hypervolume extent"},
                                                                     {f::resolution_offset, "the resolution"},
                                                                     {f::count_offset, "the voxel count"}}};
    const auto not_a_hypertree = [&] {
        return load_error(file, 0, "not a saved hypertree: the file does not start with the magic bytes \"KRSHTREE\"");
    };
    const auto magic_matches = [&](std::size_t n) {
        for (std::size_t i = 0; i < n; ++i)
            if (header[i] != static_cast<unsigned char>(f::magic[i])) return false;
        return true;
    };
    for (std::size_t k = 0; k < fields.size(); ++k) {
        const std::size_t begin = fields[k].first;
        const std::size_t end = k + 1 < fields.size() ? fields[k + 1].first : f::header_bytes;
        if (k == 0) {
            // A short file of something else is "not a hypertree" rather than "truncated".
            in.read(reinterpret_cast<char*>(header.data()), std::streamsize(end));
            const std::size_t got = std::size_t(in.gcount());
            if (!magic_matches(got)) throw not_a_hypertree();
            if (got < end)
                throw load_error(file, got,
                                 "truncated: the file ends inside the magic bytes (" + std::to_string(end - got) +
                                     " more bytes expected)");
            continue;
        }
        read_exactly(in, header.data() + begin, end - begin, begin, file, fields[k].second);
        if (k == 1) {
            const std::uint64_t version = get_le(header.data() + f::version_offset, 4);
            if (version != f::version)
                throw load_error(file, f::version_offset,
                                 "unsupported format version " + std::to_string(version) +
                                     " (this library reads version " + std::to_string(f::version) + ")");
        }
    }

    const auto real = [&](std::size_t at) { return std::bit_cast<double>(get_le(header.data() + at, 8)); };
    const char* axis_names[3] = {"x", "y", "z"};
    vec3d origin{}, extent{};
    double* origin_parts[3] = {&origin.x, &origin.y, &origin.z};
    double* extent_parts[3] = {&extent.x, &extent.y, &extent.z};
    int cells[3] = {};
    for (int a = 0; a < 3; ++a) {
        const std::size_t o_at = f::origin_offset + 8 * std::size_t(a), e_at = f::extent_offset + 8 * std::size_t(a);
        const std::size_t r_at = f::resolution_offset + 4 * std::size_t(a);
        *origin_parts[a] = real(o_at);
        *extent_parts[a] = real(e_at);
        cells[a] = static_cast<std::int32_t>(static_cast<std::uint32_t>(get_le(header.data() + r_at, 4)));
        if (!std::isfinite(*origin_parts[a]))
            throw load_error(file, o_at, std::string("the hypervolume origin's ") + axis_names[a] + " is not finite");
        if (!(std::isfinite(*extent_parts[a]) && *extent_parts[a] > 0))
            throw load_error(file, e_at,
                             std::string("the hypervolume extent's ") + axis_names[a] + " must be finite and > 0");
        if (cells[a] < 1)
            throw load_error(file, r_at,
                             std::string("the resolution's ") + axis_names[a] + " must be >= 1 (got " +
                                 std::to_string(cells[a]) + ")");
    }
    const std::uint64_t grid = std::uint64_t(cells[0]) * std::uint64_t(cells[1]) * std::uint64_t(cells[2]);
    if (grid > max_voxel_count)
        throw load_error(file, f::resolution_offset,
                         "the resolution " + std::to_string(cells[0]) + " x " + std::to_string(cells[1]) + " x " +
                             std::to_string(cells[2]) + " names more than 2^32 - 1 voxels");
    loaded_voxels result;
    try {
        result.volume = hypervolume(origin, extent, resolution{cells[0], cells[1], cells[2]});
    } catch (const invalid_parameter& e) { // checked above; kept so no other refusal escapes unnamed
        throw load_error(file, f::origin_offset, std::string("invalid hypervolume: ") + e.what());
    }

    // The count is checked against the volume and, where the stream can tell, against the bytes
    // left, before a single voxel is read or allocated.
    const std::uint64_t count = get_le(header.data() + f::count_offset, 8);
    if (count > grid)
        throw load_error(file, f::count_offset,
                         "the voxel count " + std::to_string(count) + " exceeds the hypervolume's " +
                             std::to_string(grid) + " voxels");
    const std::uint64_t needed = f::voxel_bytes * count + f::checksum_bytes;
    const std::istream::pos_type here = in.tellg();
    if (here != std::istream::pos_type(-1)) {
        in.seekg(0, std::ios::end);
        const std::istream::pos_type end = in.tellg();
        in.seekg(here);
        if (end != std::istream::pos_type(-1) && in) {
            const std::uint64_t remaining = std::uint64_t(end - here);
            if (remaining < needed)
                throw load_error(file, f::count_offset,
                                 "the voxel count " + std::to_string(count) + " needs " + std::to_string(needed) +
                                     " more bytes (7 per voxel and the 8-byte checksum) but only " +
                                     std::to_string(remaining) + " remain: the file is truncated");
            // The bytes are there, so the whole list may be allocated at once.
            result.voxels.reserve(std::size_t(count));
        }
        in.clear();
    }

    // Read in blocks: memory grows with the bytes that really arrive, whatever the count claims.
    fnv1a64 checksum;
    checksum.add(header.data(), header.size());
    std::vector<unsigned char> block;
    constexpr std::uint64_t voxels_per_block = std::uint64_t(1) << 14;
    std::uint64_t offset = f::header_bytes;
    for (std::uint64_t first = 0; first < count; first += voxels_per_block) {
        const std::uint64_t n = std::min(voxels_per_block, count - first);
        block.resize(std::size_t(n * f::voxel_bytes));
        in.read(reinterpret_cast<char*>(block.data()), std::streamsize(block.size()));
        const std::uint64_t got = std::uint64_t(in.gcount());
        if (got < block.size()) {
            const std::uint64_t voxel = first + got / f::voxel_bytes;
            throw load_error(file, offset + got,
                             "truncated: the file ends inside voxel " + std::to_string(voxel) + " of " +
                                 std::to_string(count));
        }
        checksum.add(block.data(), block.size());
        for (std::uint64_t k = 0; k < n; ++k) {
            const unsigned char* v = block.data() + k * f::voxel_bytes;
            result.voxels.push_back({voxel_index(get_le(v, 4)), voxel{v[4], v[5]}, v[6]});
        }
        offset += block.size();
    }
    unsigned char stored_sum[f::checksum_bytes];
    read_exactly(in, stored_sum, sizeof stored_sum, offset, file, "the checksum");
    const std::uint64_t stored = get_le(stored_sum, 8);
    if (stored != checksum.value())
        throw load_error(file, offset,
                         "checksum mismatch: the file says " + hex(stored) + " but its bytes give " +
                             hex(checksum.value()) + " (the file is corrupted)");

    // The list must be what stores are built from; checked here so the error names the byte.
    for (std::size_t k = 0; k < result.voxels.size(); ++k) {
        const stored_voxel& v = result.voxels[k];
        const std::uint64_t at = f::header_bytes + f::voxel_bytes * k;
        if (v.index >= grid)
            throw load_error(file, at,
                             "voxel " + std::to_string(k) + " has index " + std::to_string(v.index) +
                                 " outside the hypervolume's " + std::to_string(grid) + " voxels");
        if (v.value.density == 0)
            throw load_error(file, at + 4, "voxel " + std::to_string(k) + " has density 0 (empty voxels are not stored)");
        if (k > 0 && !(result.voxels[k - 1].index < v.index))
            throw load_error(file, at,
                             "voxel " + std::to_string(k) + " has index " + std::to_string(v.index) + " after " +
                                 std::to_string(result.voxels[k - 1].index) +
                                 " (indices must increase strictly)");
    }
    return result;
}

template <voxel_store S>
S build_loaded(const loaded_voxels& loaded, std::string_view file, memory_budget budget)
{
    try {
        return S::build(loaded.volume, loaded.voxels, budget);
    } catch (const invalid_parameter& e) {
        // The file is sound (checked above), so only the budget can refuse it.
        throw load_error(file, std::nullopt, std::string("cannot build the store: ") + e.what());
    }
}

} // namespace detail

// Writes the store's hypervolume and non-empty voxels (with their parts where the store keeps
// them) in the format above.
template <voxel_store S>
void save(const S& store, std::ostream& out)
{
    namespace f = binary_format;
    const hypervolume& volume = store.volume();
    std::array<unsigned char, f::header_bytes> header{};
    for (std::size_t i = 0; i < f::magic.size(); ++i) header[i] = static_cast<unsigned char>(f::magic[i]);
    detail::put_le(header.data() + f::version_offset, f::version, 4);
    const double reals[6] = {volume.origin().x, volume.origin().y, volume.origin().z,
                             volume.extent().x, volume.extent().y, volume.extent().z};
    for (int k = 0; k < 6; ++k)
        detail::put_le(header.data() + f::origin_offset + 8 * k, std::bit_cast<std::uint64_t>(reals[k]), 8);
    const resolution n = volume.grid();
    const int cells[3] = {n.x, n.y, n.z};
    for (int a = 0; a < 3; ++a)
        detail::put_le(header.data() + f::resolution_offset + 4 * a, static_cast<std::uint32_t>(cells[a]), 4);
    detail::put_le(header.data() + f::count_offset, store.nonempty_count(), 8);

    detail::binary_writer writer(out);
    writer.write(header.data(), header.size());
    std::uint64_t written = 0;
    for_each_stored(store, [&](const stored_voxel& v) {
        unsigned char bytes[f::voxel_bytes];
        detail::put_le(bytes, v.index, 4);
        bytes[4] = v.value.density, bytes[5] = v.value.level, bytes[6] = v.part;
        writer.write(bytes, sizeof bytes);
        ++written;
    });
    if (written != store.nonempty_count())
        throw save_error("hypertree save: the store visited " + std::to_string(written) + " voxels but reports " +
                         std::to_string(store.nonempty_count()));
    writer.finish();
}

// Writes through krs::write_file (a temporary beside `path`, every write checked, renamed over
// `path` once complete), so a failed save never leaves a truncated file where a good one was.
template <voxel_store S>
void save(const S& store, const std::filesystem::path& path)
{
    krs::write_file("hypertree save", path, [&](std::ostream& out) { save(store, out); });
}

// The checked hypervolume and voxel list of a saved tree, without building a store (to convert
// or inspect files). `name` appears in error messages.
inline loaded_voxels load_voxels(std::istream& in, std::string_view name = {})
{
    return detail::read_voxels(in, name);
}

// Loads a saved tree as a store of kind S (any kind: the file does not depend on the kind it was
// saved from). Reads exactly the tree's bytes from the stream.
template <voxel_store S>
S load(std::istream& in, memory_budget budget = {})
{
    return detail::build_loaded<S>(detail::read_voxels(in, {}), {}, budget);
}

template <voxel_store S>
S load(const std::filesystem::path& path, memory_budget budget = {})
{
    const std::string name = path.string();
    std::ifstream in(path, std::ios::binary);
    if (!in) {
        std::error_code status_error;
        const bool exists = std::filesystem::exists(path, status_error);
        throw load_error(name, std::nullopt,
                         exists ? "cannot open the file for reading" : "cannot open: no such file");
    }
    const loaded_voxels loaded = detail::read_voxels(in, name);
    if (in.peek() != std::char_traits<char>::eof())
        throw load_error(name, binary_format::file_bytes(loaded.voxels.size()),
                         "unexpected bytes after the checksum (the file is longer than the tree it holds)");
    return detail::build_loaded<S>(loaded, name, budget);
}

} // namespace hypertree

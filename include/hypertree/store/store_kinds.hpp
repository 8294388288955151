#pragma once
// The store kinds: the closed set of `voxel_store` models (store/store.hpp), listed once here.
// Everything that names or iterates the kinds uses this list: forest files (io/forest_file.hpp)
// read a kind by name, `with_store` turns a run-time kind into a type, `for_each_store_kind`
// visits every type (benchmarks), and tests are templated over `store_kinds`.
//
// Adding a kind: write its header next to the others, then add it here in three places kept in
// the same order (the `storage_type` enumerator, its name, its type in `store_kinds`). The
// static_assert catches a list left short; docs/design.md ("Store kinds") lists what else to read.

#include "hypertree/store/bit_array_store.hpp"
#include "hypertree/store/dense_store.hpp"
#include "hypertree/store/index_list_store.hpp"
#include "hypertree/store/partitioned_store.hpp"

#include <algorithm>
#include <array>
#include <cstddef>
#include <cstdint>
#include <span>
#include <string>
#include <string_view>
#include <tuple>
#include <utility>

namespace hypertree {

// The data structures of section 5, by the names forest files use.
enum class storage_type { dense, index_list, bit_array, partitioned };
inline constexpr std::array<std::string_view, 4> storage_type_names = {"dense", "index_list", "bit_array", "partitioned"};
// Their types, in the order of `storage_type` (a tuple: doctest's TEST_CASE_TEMPLATE_APPLY takes it).
using store_kinds = std::tuple<dense_store, index_list_store, bit_array_store, partitioned_store>;
static_assert(std::tuple_size_v<store_kinds> == storage_type_names.size());

inline std::string_view name_of(storage_type s) { return storage_type_names[std::size_t(s)]; }

// The names joined for messages and usage lines: ("dense", ", ", " or ") gives
// "dense, index_list, bit_array or partitioned", so no text lists the kinds by hand.
inline std::string storage_type_choices(std::string_view separator, std::string_view last_separator)
{
    std::string out;
    for (std::size_t k = 0; k < storage_type_names.size(); ++k) {
        if (k > 0) out += k + 1 == storage_type_names.size() ? last_separator : separator;
        out += storage_type_names[k];
    }
    return out;
}

namespace detail {
template <class S, std::size_t I = 0>
constexpr std::size_t store_kind_index()
{
    static_assert(I < std::tuple_size_v<store_kinds>, "not a type of store_kinds");
    if constexpr (std::is_same_v<S, std::tuple_element_t<I, store_kinds>>)
        return I;
    else
        return store_kind_index<S, I + 1>();
}

template <std::size_t I, class F>
decltype(auto) with_store_at(std::size_t kind, F& f)
{
    using S = std::tuple_element_t<I, store_kinds>;
    if constexpr (I + 1 == std::tuple_size_v<store_kinds>)
        return f.template operator()<S>();
    else if (kind == I)
        return f.template operator()<S>();
    else
        return with_store_at<I + 1>(kind, f);
}
} // namespace detail

// The kind of a store type, and its name.
template <class S>
inline constexpr storage_type storage_type_of = storage_type(detail::store_kind_index<S>());
template <class S>
inline constexpr std::string_view store_kind_name = storage_type_names[detail::store_kind_index<S>()];

// f.template operator()<S>() for the store type S of `kind`; every S must give f the same result type.
template <class F>
decltype(auto) with_store(storage_type kind, F&& f)
{
    return detail::with_store_at<0>(std::size_t(kind), f);
}

// f.template operator()<S>() for every store type S, in the order of `store_kinds`.
template <class F>
void for_each_store_kind(F&& f)
{
    [&]<std::size_t... I>(std::index_sequence<I...>) {
        (f.template operator()<std::tuple_element_t<I, store_kinds>>(), ...);
    }(std::make_index_sequence<std::tuple_size_v<store_kinds>>());
}

// Why a store of `kind` cannot hold `voxels` of `volume` within `budget`, with what fits: the
// other kinds that hold the same voxels within it, and for a kind whose size follows the grid
// (dense) the finest grid of the same proportions that fits, written as `resolution_word`
// ("RESOLUTION" in a forest file, "--resolution" on a command line) takes it. Empty when it fits.
// Before generation pass no voxels: the kinds sized by their voxels are then named as such,
// since only the grid's cost (dense's) is known.
inline std::string store_budget_problem(storage_type kind, const hypervolume& volume, std::span<const stored_voxel> voxels,
                                        bool voxels_known, memory_budget budget, std::string_view resolution_word)
{
    const auto bytes_of = [&](storage_type k, const hypervolume& v) {
        return with_store(k, [&]<class S>() { return S::bytes_needed(v, voxels); });
    };
    const std::size_t needed = bytes_of(kind, volume);
    if (needed <= budget.bytes) return {};
    const resolution n = volume.grid();
    std::string problem = std::string(name_of(kind)) + " needs " + std::to_string(needed) + " bytes for " + std::to_string(n.x) + " x " +
                          std::to_string(n.y) + " x " + std::to_string(n.z) + " voxels" +
                          (voxels_known ? " holding " + std::to_string(voxels.size()) : "") + ", over the memory budget of " +
                          std::to_string(budget.bytes) + " bytes";
    std::string fitting;
    for (std::size_t k = 0; k < storage_type_names.size(); ++k) {
        const storage_type other = storage_type(k);
        if (other == kind) continue;
        const bool by_grid = other == storage_type::dense;
        if (!by_grid && !voxels_known) continue;
        const std::size_t bytes = bytes_of(other, volume);
        if (bytes <= budget.bytes)
            fitting += (fitting.empty() ? "" : ", ") + std::string(name_of(other)) + " (" + std::to_string(bytes) + " bytes)";
    }
    if (!fitting.empty()) problem += "; these fit: " + fitting;
    else if (!voxels_known && kind == storage_type::dense)
        problem += "; index_list, bit_array and partitioned take memory by the voxels the tree fills, not by the grid";
    if (kind == storage_type::dense) {
        // The finest grid of the same proportions: the longest axis m, the others scaled with it.
        const int longest = std::max({n.x, n.y, n.z});
        const auto scaled = [&](int m) {
            const auto axis = [&](int a) { return std::max(1, int(std::int64_t(a) * m / longest)); };
            return resolution{axis(n.x), axis(n.y), axis(n.z)};
        };
        const auto fits = [&](int m) {
            try {
                return bytes_of(kind, hypervolume(volume.origin(), volume.extent(), scaled(m))) <= budget.bytes;
            } catch (const invalid_parameter&) {
                return false; // a grid the box cannot take (voxels too thin for float): not offered
            }
        };
        int lo = 0, hi = longest; // fits(lo) (or lo = 0: none), !fits(hi)
        while (hi - lo > 1) {
            const int mid = lo + (hi - lo) / 2;
            (fits(mid) ? lo : hi) = mid;
        }
        if (lo > 0) {
            const resolution r = scaled(lo);
            problem += std::string(fitting.empty() ? "; " : ", or ") + std::string(name_of(kind)) + " at " + std::string(resolution_word) + " " +
                       (r.x == r.y && r.y == r.z ? std::to_string(r.x)
                                                  : std::to_string(r.x) + " " + std::to_string(r.y) + " " + std::to_string(r.z)) +
                       " or less";
        }
    }
    return problem;
}

} // namespace hypertree

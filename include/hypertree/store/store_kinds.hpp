#pragma once
// The store kinds: the closed set of `voxel_store` models (store/store.hpp), listed once here, in
// the tuple `store_kinds`. Each store type carries its own name (`S::kind_name`, the spelling of
// forest files and command lines), and the rest is derived from the list: the names in list
// order (`storage_type_names`), the run-time kind (`storage_type`, each enumerator the position
// of its type in the list), `with_store` turning a run-time kind into a type, and
// `for_each_store_kind` visiting every type (benchmarks); tests are templated over `store_kinds`.
//
// Adding a kind: write its header next to the others, with its `kind_name`; include it here and
// add its type to `store_kinds`, and an enumerator valued by its type for users who name the kind
// in C++. A type that is not a store kind, or a name given twice, stops the compile here;
// docs/design.md ("A store kind") lists what else to read.

#include "hypertree/store/bit_array_store.hpp"
#include "hypertree/store/dense_store.hpp"
#include "hypertree/store/index_list_store.hpp"
#include "hypertree/store/partitioned_store.hpp"

#include <algorithm>
#include <array>
#include <concepts>
#include <cstddef>
#include <cstdint>
#include <span>
#include <string>
#include <string_view>
#include <tuple>
#include <utility>

namespace hypertree {

// A store kind: a voxel_store that names itself.
template <class S>
concept store_kind = voxel_store<S> && requires {
    { S::kind_name } -> std::convertible_to<std::string_view>;
};

// The data structures of section 5 (a tuple: doctest's TEST_CASE_TEMPLATE_APPLY takes it).
using store_kinds = std::tuple<dense_store, index_list_store, bit_array_store, partitioned_store>;

namespace detail {
// Deduction fails, naming the type and its unmet requirement, for an entry that is no store kind.
template <store_kind... S>
constexpr bool are_store_kinds(const std::tuple<S...>*)
{
    return true;
}
static_assert(are_store_kinds(static_cast<const store_kinds*>(nullptr)));

template <class S, std::size_t I = 0>
constexpr std::size_t store_kind_index()
{
    static_assert(I < std::tuple_size_v<store_kinds>, "not a type of store_kinds");
    if constexpr (std::is_same_v<S, std::tuple_element_t<I, store_kinds>>)
        return I;
    else
        return store_kind_index<S, I + 1>();
}
} // namespace detail

// Their names, in the order of `store_kinds`, as the types give them.
inline constexpr auto storage_type_names = []<std::size_t... I>(std::index_sequence<I...>) {
    return std::array<std::string_view, sizeof...(I)>{std::string_view(std::tuple_element_t<I, store_kinds>::kind_name)...};
}(std::make_index_sequence<std::tuple_size_v<store_kinds>>());
static_assert(
    [] {
        for (std::size_t i = 0; i < storage_type_names.size(); ++i)
            for (std::size_t j = i + 1; j < storage_type_names.size(); ++j)
                if (storage_type_names[i] == storage_type_names[j]) return false;
        return true;
    }(),
    "two store kinds share a kind_name: a forest file's STORAGETYPE would not say which");

// A kind chosen at run time (forest files, command lines): each enumerator is the position of its
// type in `store_kinds`, so the enumeration cannot drift from the list.
enum class storage_type {
    dense = int(detail::store_kind_index<dense_store>()),
    index_list = int(detail::store_kind_index<index_list_store>()),
    bit_array = int(detail::store_kind_index<bit_array_store>()),
    partitioned = int(detail::store_kind_index<partitioned_store>()),
};

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
inline constexpr std::string_view store_kind_name = storage_type_names[detail::store_kind_index<S>()]; // S::kind_name

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

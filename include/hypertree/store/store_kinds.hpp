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

#include <array>
#include <cstddef>
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

} // namespace hypertree

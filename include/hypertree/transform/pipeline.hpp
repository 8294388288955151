#pragma once
// Transform pipelines: an IFS transformation w_j composed of elementary transforms applied in
// order (paper section 3.1: "the transformations w_j can be composed of many elementary
// transformations").
//
// Two forms with one interface (`transform_pipeline`):
// - `pipeline<translate, rotate, shear, scale>`: composed at compile time. The element types are
//   the pipeline's type; its chain has exactly as many shears as the type names, so applying it
//   is straight-line code with no dispatch.
// - `runtime_pipeline`: a vector of `transform_element` (a closed variant of the same four
//   transforms) for trees read from definition files. Its chain holds up to
//   `max_runtime_shears` shears and loops over the ones used.
// Either way the generator never sees the elements: it asks for the canonical `chain_at(level)`
// (maps.hpp) once per level after the random parameters are drawn.

#include "hypertree/transform/maps.hpp"
#include "hypertree/transform/rotate.hpp"
#include "hypertree/transform/scale.hpp"
#include "hypertree/transform/shear.hpp"
#include "hypertree/transform/translate.hpp"

#include <concepts>
#include <string>
#include <tuple>
#include <variant>
#include <vector>

namespace hypertree {

template <class E>
concept elementary_transform = requires(const E& e, random_stream& random, int level) {
    { E::is_affine } -> std::convertible_to<bool>;
    { e.draw(random) } -> std::same_as<E>;
    e.map_at(level);
    e.validate();
};

template <class P>
concept transform_pipeline = requires(const P& p, random_stream& random, int level) {
    typename P::chain;
    { p.draw(random) } -> std::same_as<P>;
    { p.chain_at(level) } -> std::same_as<typename P::chain>;
    p.validate();
};

namespace detail {
// Folds elements into a canonical chain: affine elements compose into the pending affine map; a
// shear closes it and starts the next.
template <class Chain>
struct chain_builder {
    Chain chain{};
    affine_map pending{};
    int shears = 0;

    template <elementary_transform E>
    void add(const E& element, int level)
    {
        if constexpr (E::is_affine) {
            pending = compose(element.map_at(level), pending);
        } else {
            chain.affine[shears] = pending;
            chain.shear[shears] = element.map_at(level);
            pending = affine_map{};
            ++shears;
        }
    }
    Chain finish()
    {
        chain.affine[shears] = pending;
        chain.shears = shears;
        return chain;
    }
};
} // namespace detail

template <elementary_transform... Elements>
struct pipeline {
    static constexpr int shear_count = (0 + ... + int(!Elements::is_affine));
    using chain = map_chain<shear_count, true>;

    std::tuple<Elements...> elements;

    pipeline() = default;
    explicit pipeline(Elements... e) : elements(std::move(e)...) { validate(); }

    void validate() const
    {
        std::apply([](const auto&... e) { (e.validate(), ...); }, elements);
    }
    // Elements draw in order, so the same seed gives the same parameters.
    pipeline draw(random_stream& random) const
    {
        pipeline drawn;
        drawn.elements = std::apply([&](const auto&... e) { return std::tuple<Elements...>{e.draw(random)...}; }, elements);
        return drawn;
    }
    chain chain_at(int level) const
    {
        detail::chain_builder<chain> builder;
        std::apply([&](const auto&... e) { (builder.add(e, level), ...); }, elements);
        return builder.finish();
    }
};

using transform_element = std::variant<translate, rotate, scale, shear>;

// A definition file's pipelines; more shears than this in one transformation are refused (a
// tree needs one or two: section 3.1 bends in two directions with one shear).
inline constexpr int max_runtime_shears = 4;

struct runtime_pipeline {
    using chain = map_chain<max_runtime_shears, false>;

    std::vector<transform_element> elements;

    runtime_pipeline() = default;
    explicit runtime_pipeline(std::vector<transform_element> e) : elements(std::move(e)) { validate(); }

    void validate() const
    {
        int shears = 0;
        for (const auto& e : elements) {
            std::visit([](const auto& element) { element.validate(); }, e);
            shears += std::holds_alternative<shear>(e) ? 1 : 0;
        }
        if (shears > max_runtime_shears)
            throw krs::invalid_parameter("runtime_pipeline.elements", "may hold at most " + std::to_string(max_runtime_shears) + " shears",
                                         std::to_string(shears));
    }
    runtime_pipeline draw(random_stream& random) const
    {
        runtime_pipeline drawn;
        drawn.elements.reserve(elements.size());
        for (const auto& e : elements)
            drawn.elements.push_back(std::visit([&](const auto& element) { return transform_element{element.draw(random)}; }, e));
        return drawn;
    }
    chain chain_at(int level) const
    {
        detail::chain_builder<chain> builder;
        for (const auto& e : elements) std::visit([&](const auto& element) { builder.add(element, level); }, e);
        return builder.finish();
    }
};

} // namespace hypertree

#pragma once
// The hyperforest file (paper section 10): a group of hypertrees that share one volume data set.
// The file lists the tree definition files and gives what the shared volume needs: its
// resolution and its storage type (the data structures of section 5).
//
//     RESOLUTION 600 300 600          # one value, or nx ny nz
//     STORAGETYPE bit_array           # dense | index_list | bit_array | partitioned
//     TREE tree_a.tree -1 0 -1        # a definition file, and where its origin stands
//     TREE "my trees/oak.tree"        # offset 0 0 0
//
// Tree paths are relative to the forest file's directory (absolute paths stay as they are); an
// offset moves a tree's origin, and with it its hypervolume, in the forest. RESOLUTION and
// STORAGETYPE are required, once each, and at least one TREE. A tree file's own RESOLUTION
// describes the tree alone; in a forest the forest's applies to the shared volume
// (`loaded_forest::volume`).
//
// `parse_forest` reads the listing; `load_forest` also reads every tree, and a tree file that
// cannot be read is reported at its TREE line.

#include "hypertree/io/definition_file.hpp"
#include "hypertree/io/lexer.hpp"
#include "hypertree/store/store_kinds.hpp" // storage_type and its names

#include <algorithm>
#include <array>
#include <filesystem>
#include <optional>
#include <string>
#include <string_view>
#include <vector>

namespace hypertree {

struct forest_tree {
    std::filesystem::path file; // resolved against the forest file's directory
    vec3d offset{};
    source_position at;         // the TREE line, for messages about this tree
};

struct parsed_forest {
    std::string file_name;
    resolution grid;
    storage_type storage = storage_type::index_list;
    std::vector<forest_tree> trees;
    source_position resolution_at, storage_at; // their lines, for refusals found after parsing
};

namespace detail {

inline constexpr std::string_view forest_keywords = "RESOLUTION, STORAGETYPE, TREE";

// The first line of `text` whose keyword only forest files have, if any. Text that does not even
// tokenize is no forest; its own parse reports it.
inline std::optional<int> forest_keyword_line(std::string_view text)
{
    try {
        for (const io::source_line& line : io::tokenize(text, {})) {
            if (is_forest_only_keyword(line.tokens.front())) return line.tokens.front().at.line;
        }
    } catch (const definition_error&) {
    }
    return std::nullopt;
}

inline void forest_once(const io::statement& s, std::optional<source_position>& seen)
{
    if (seen) throw definition_error(s.file(), s.where(), s.keyword() + " is given twice (first on line " + std::to_string(seen->line) + ")");
    seen = s.where();
}

} // namespace detail

// Parses a forest file's text. `file_name` labels the messages and is the base of relative tree
// paths.
inline parsed_forest parse_forest(std::string_view text, std::string_view file_name)
{
    parsed_forest forest;
    forest.file_name = std::string(file_name);
    const std::filesystem::path base = std::filesystem::path(file_name).parent_path();
    std::optional<source_position> resolution_at, storage_at;
    const std::vector<io::source_line> lines = io::tokenize(text, file_name);
    for (const io::source_line& line : lines) {
        const io::token& first = line.tokens.front();
        const auto is = [&](std::string_view k) { return first.kind == io::token_kind::word && io::same_word(first.text, k); };
        if (is("RESOLUTION")) {
            io::statement s(file_name, line, "RESOLUTION n | RESOLUTION nx ny nz");
            detail::forest_once(s, resolution_at);
            forest.grid = io::read_resolution(s);
        } else if (is("STORAGETYPE")) {
            const std::string usage = "STORAGETYPE " + storage_type_choices(" | ", " | "); // outlives s, which keeps a view
            io::statement s(file_name, line, usage);
            detail::forest_once(s, storage_at);
            const io::token* t = s.peek();
            const auto known = std::find_if(storage_type_names.begin(), storage_type_names.end(), [&](std::string_view name) {
                return t != nullptr && t->kind == io::token_kind::word && io::same_word(t->text, name);
            });
            if (known == storage_type_names.end()) s.expected("a storage type (" + storage_type_choices(", ", " or ") + ")");
            s.take();
            s.finish();
            forest.storage = storage_type(known - storage_type_names.begin());
        } else if (is("TREE")) {
            io::statement s(file_name, line, "TREE path [x y z]");
            forest_tree tree;
            tree.at = s.where();
            const std::filesystem::path path(std::string(s.text("a tree file path")));
            tree.file = path.is_absolute() ? path : (base / path).lexically_normal();
            if (!s.at_end()) {
                const double x = s.number(), y = s.number(), z = s.number();
                tree.offset = {x, y, z};
            }
            s.finish();
            forest.trees.push_back(std::move(tree));
        } else if (detail::find_definition_keyword(first) != nullptr) {
            // A tree definition given where a forest is wanted: say so at its first tree keyword.
            throw definition_error(file_name, first.at,
                                   io::upper(first.text) + " is a tree definition's keyword: this is a tree definition file, and a "
                                                           "forest file (" + std::string(detail::forest_keywords) + ") is expected here");
        } else {
            throw definition_error(file_name, first.at,
                                   "unknown keyword " + io::describe(&first) + "; a forest file's keywords are " + std::string(detail::forest_keywords));
        }
    }
    const source_position end = io::end_of_input(text);
    if (!resolution_at) throw definition_error(file_name, end, "expected a RESOLUTION line (the shared volume's resolution)");
    if (!storage_at)
        throw definition_error(file_name, end, "expected a STORAGETYPE line (" + storage_type_choices(", ", " or ") + ")");
    if (forest.trees.empty()) throw definition_error(file_name, end, "expected at least one TREE line");
    forest.resolution_at = *resolution_at, forest.storage_at = *storage_at;
    return forest;
}

// A forest with its trees read, in the order the file lists them.
struct loaded_forest {
    parsed_forest listing;
    std::vector<parsed_tree> trees;

    // The shared volume: the smallest box holding every tree's hypervolume moved by its offset,
    // cut at the forest's resolution.
    hypervolume volume() const
    {
        vec3d lo{}, hi{};
        for (std::size_t i = 0; i < trees.size(); ++i) {
            const hypervolume& v = trees[i].ifs.volume;
            const vec3d a = v.origin() + listing.trees[i].offset, b = v.maximum() + listing.trees[i].offset;
            lo = i == 0 ? a : vec3d{std::min(lo.x, a.x), std::min(lo.y, a.y), std::min(lo.z, a.z)};
            hi = i == 0 ? b : vec3d{std::max(hi.x, b.x), std::max(hi.y, b.y), std::max(hi.z, b.z)};
        }
        return hypervolume(lo, hi - lo, listing.grid);
    }
};

inline loaded_forest load_forest(const std::filesystem::path& path)
{
    const io::text_file file = io::read_text_file(path);
    if (!file.problem.empty())
        throw definition_error(path.string(), {1, 1}, "cannot read the forest file: " + file.problem);
    loaded_forest forest;
    forest.listing = parse_forest(file.text, path.string());
    for (const forest_tree& tree : forest.listing.trees) {
        const io::text_file tree_file = io::read_text_file(tree.file);
        if (!tree_file.problem.empty())
            throw definition_error(forest.listing.file_name, tree.at,
                                   "cannot read the tree file '" + tree.file.string() + "': " + tree_file.problem);
        // Forests do not nest (one volume, one storage type): a TREE naming a forest file is
        // refused at this TREE line, not reported as an unknown keyword inside the other file.
        if (const std::optional<int> line = detail::forest_keyword_line(tree_file.text))
            throw definition_error(forest.listing.file_name, tree.at,
                                   "'" + tree.file.string() + "' is a forest file (line " + std::to_string(*line) +
                                       " is a forest's keyword); TREE takes a tree definition file");
        forest.trees.push_back(parse_definition(tree_file.text, tree.file.string()));
        // Render-time noise is one field for the whole march, which renders every tree at once: a
        // tree cannot carry its own. Refused at its line rather than dropped.
        if (const auto& at = forest.trees.back().render_perturb_at)
            throw definition_error(tree.file.string(), *at,
                                   "RENDERPERTURB is not allowed in a forest's tree (the march is shared by every tree; the noise "
                                   "would be dropped); VOXELPERTURB and PERTURB are applied per tree");
        // The tree's box where the forest puts it must still be a volume float can place (an
        // offset of 1e9 under a box of side 1e-9 loaded, then failed in volume() unnamed).
        const hypervolume& v = forest.trees.back().ifs.volume;
        try {
            (void)hypervolume(v.origin() + tree.offset, v.extent(), v.grid());
        } catch (const invalid_parameter& e) {
            throw definition_error(forest.listing.file_name, tree.at,
                                   "the tree's hypervolume moved by this offset is invalid: " + std::string(e.what()));
        }
    }
    try {
        (void)forest.volume();
    } catch (const invalid_parameter& e) {
        throw definition_error(forest.listing.file_name, forest.listing.trees.front().at,
                               "the forest's shared volume (every tree's box, at the forest's RESOLUTION) is invalid: " +
                                   std::string(e.what()));
    }
    return forest;
}

} // namespace hypertree

// libFuzzer target: the text readers of hypertree definition and forest files (issue 10, "fuzzing";
// include/hypertree/io/definition_file.hpp, forest_file.hpp, lexer.hpp). The input bytes are the
// file's text, unchanged, so the seeds in fuzz/corpus/definition/ are ordinary .tree and .forest
// files and fuzz/definition.dict gives libFuzzer the keywords.
//
// Every input goes to both readers. Each must either return or throw hypertree::definition_error;
// anything else (another exception, a sanitizer report, a hang) aborts. What a reader returns is
// held to its promises:
// - a parsed tree's IFS passes ifs::validate (the parser says nothing half-built escapes), its
//   depth colors lie below TREEDEPTH and give a transfer function, and it is usable: the IFS is
//   drawn (a random draw that is not a contraction may be refused with krs::invalid_parameter, the
//   only refusal allowed past the parser, with the generator's memory budget refusing a line
//   generator much longer than a voxel) and then generated and stored, with the iteration count
//   cut to 200 and the resolution to at most 16 per axis so one execution stays fast. The store
//   must hold only voxels of the (reduced) hypervolume, at most one per hit;
// - a parsed forest has a resolution of at most 2^32 - 1 voxels and at least one tree;
// - how an editor saved the text changes nothing (issue 37): the same text with its LFs made
//   CRs (old Mac endings) or CR LFs, or with a UTF-8 byte-order mark in front, is read by both
//   readers to the same outcome, the same refusal at the same line and column or a success.
//
// Define KRS_FUZZ_VERBOSE to print each input's outcome. fuzz/replay_main.cpp runs the same
// function over fuzz/corpus/definition/ and fuzz/crashers/definition/ in ctest.

#include "fuzz_input.hpp"
#include "hypertree/build.hpp"
#include "hypertree/io/definition_file.hpp"
#include "hypertree/io/forest_file.hpp"
#include "hypertree/store/index_list_store.hpp"

#include <algorithm>
#include <cstddef>
#include <cstdint>
#include <string>
#include <string_view>

namespace {

using krs_fuzz::fail;
using krs_fuzz::note;

// Bounds that keep one execution to a fraction of a millisecond: the generator's work grows with
// the iterations, the store's with the voxels of the grid.
constexpr std::uint64_t iteration_limit = 200;
constexpr int axis_limit = 16;
constexpr std::uint64_t draw_seed = 0x6b7273;

void check_generation(const hypertree::parsed_tree& parsed)
{
    using namespace hypertree;
    ifs<runtime_pipeline> small = parsed.ifs;
    small.iterations = std::min(small.iterations, iteration_limit);
    const resolution grid = small.volume.grid();
    small.volume = hypervolume(small.volume.origin(), small.volume.extent(),
                               {std::min(grid.x, axis_limit), std::min(grid.y, axis_limit), std::min(grid.z, axis_limit)});
    try {
        const drawn_ifs<runtime_pipeline> drawn(small, draw_seed);
        if (!(drawn.lipschitz() < 1.0)) fail();
    } catch (const krs::invalid_parameter& e) {
        // The parser checks the contraction at the mean values; a random draw may exceed it.
        note("draw refused", e.what());
        return;
    }
    build_options options;
    if (parsed.density_class_count) options.density_class_count = *parsed.density_class_count;
    options.generation.budget.bytes = std::size_t(64) << 20;
    generated_hits hits;
    try {
        hits = generate(small, draw_seed, options.generation);
    } catch (const krs::invalid_parameter& e) {
        // A line generator much longer than a voxel may claim more hits than the budget allows.
        if (e.parameter() != "ifs.iterations") fail();
        note("generation refused", e.what());
        return;
    }
    const std::uint64_t cells = small.volume.voxel_count();
    for (const hit& h : hits.hits)
        if (h.voxel >= cells || h.level >= small.tree_depth) fail();
    const index_list_store store = build_tree<index_list_store>(small, draw_seed, options);
    if (store.nonempty_count() > hits.hits.size() || store.nonempty_count() > cells) fail();
    store.for_each([&](voxel_index i, voxel v) {
        if (i >= cells || v.density == 0 || store.at(i).density != v.density) fail();
    });
    note("generated", parsed.ifs.name.c_str());
}

void check_tree(const hypertree::parsed_tree& parsed)
{
    parsed.ifs.validate(); // must not throw: the parser validated it
    for (const auto& c : parsed.depth_colors)
        if (c.from < 0 || c.from > c.to || c.to >= parsed.ifs.tree_depth) fail();
    (void)parsed.colors();
    (void)parsed.color_of_depth(0);
    check_generation(parsed);
}

void check_forest(const hypertree::parsed_forest& forest)
{
    const hypertree::resolution g = forest.grid;
    if (g.x < 1 || g.y < 1 || g.z < 1) fail();
    if (std::uint64_t(g.x) * std::uint64_t(g.y) * std::uint64_t(g.z) > hypertree::max_voxel_count) fail();
    if (forest.trees.empty()) fail();
}

// What each reader makes of `text`: its refusal's message (with the location) or "read".
std::string outcome(std::string_view text)
{
    std::string out;
    try {
        (void)hypertree::parse_definition(text, "fuzz.tree");
        out = "read";
    } catch (const hypertree::definition_error& e) {
        out = e.what();
    }
    try {
        (void)hypertree::parse_forest(text, "fuzz/fuzz.forest");
        return out + " | read";
    } catch (const hypertree::definition_error& e) {
        return out + " | " + e.what();
    }
}

// The text as other editors save it reads the same. Only texts that hold no CR (whose CRs would
// change meaning) and start with no byte-order mark or NUL (which a mark in front would hide).
void check_saved_forms(std::string_view text)
{
    if (text.find('\r') != std::string_view::npos) return;
    if (!text.empty() && (text.front() == '\xEF' || text.front() == '\xFF' || text.front() == '\xFE' || text.front() == '\0')) return;
    const std::string original = outcome(text);
    std::string cr(text), crlf;
    for (char& c : cr)
        if (c == '\n') c = '\r';
    for (char c : text) crlf += c == '\n' ? std::string("\r\n") : std::string(1, c);
    if (outcome(cr) != original || outcome(crlf) != original || outcome("\xEF\xBB\xBF" + std::string(text)) != original) fail();
}

} // namespace

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size)
{
    const std::string_view text(reinterpret_cast<const char*>(data), size);
    check_saved_forms(text);
    try {
        check_tree(hypertree::parse_definition(text, "fuzz.tree"));
    } catch (const hypertree::definition_error& e) {
        note("tree refused", e.what());
    } catch (...) {
        fail();
    }
    try {
        check_forest(hypertree::parse_forest(text, "fuzz/fuzz.forest"));
        note("forest", "parsed");
    } catch (const hypertree::definition_error& e) {
        note("forest refused", e.what());
    } catch (...) {
        fail();
    }
    return 0;
}

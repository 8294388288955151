#pragma once
// The hypertree definition file (paper section 10, figure 6): a text file that describes one
// hypertree (its resolution, iteration count, depths, generator, coloring, perturbation,
// hypervolume and IFS transformations) with the paper's reserved words. docs/hypertree_format.md
// is the full reference; in brief:
//
//     NAME "my tree"
//     RESOLUTION 300                 # or nx ny nz
//     ITERATIONS 500000
//     TREEDEPTH 10                   # generators of depths 0 .. 9
//     BRANCHDEPTH 1                  # depths 0 .. 1 are wood
//     DEPTHCOLOR 0 1 0.35 0.22 0.1 0.45 0.3 0.15
//     HYPERVOLUME 1.5 1.2 1.5        # the box's extent
//     DISPLACEMENT 0.75 0 0.75       # the tree's origin, from the box's minimum corner
//     POINTINIT 0 0 0                # or LINEINIT x0 y0 z0 x1 y1 z1
//     CONDENSATION
//       CONE y 0 0.5 0.035 0.015
//     TRANSFORM 1 0                  # probability, last level (0: no limit) [DUMMY d]
//       SCALE (0.52, 0.5, 0.48)      # per level: 1, 2, 3 and deeper
//       ROTATE 0 0 1 48~5            # degrees; random: mean~spread
//       TRANSLATE 0 0.28 0
//
// `parse_definition` reads such text into the `ifs<runtime_pipeline>` of ifs.hpp plus what the
// IFS does not hold (the depth colors and the density class count). It returns a complete tree or
// throws a `definition_error` ("file:line:column: expected ..."): every value is checked where it
// is read, and what the C++ model refuses afterwards (ifs::validate, the element constructors, the
// contraction condition) is reported at the keyword that set it. Nothing half-built escapes.

#include "hypertree/depth_colors.hpp"
#include "hypertree/ifs.hpp"
#include "hypertree/io/lexer.hpp"
#include "hypertree/perturbation.hpp"

#include <array>
#include <cstdlib>
#include <filesystem>
#include <numbers>
#include <optional>
#include <string>
#include <string_view>
#include <utility>
#include <vector>

namespace hypertree {

// Files give angles in degrees; the transforms take radians. Computed as the presets compute
// theirs (pi / 180, then one multiplication per value), so a file and a C++ tree written with the
// same numbers agree bit for bit.
inline constexpr double radians_per_degree = std::numbers::pi / 180.0;

// Everything a definition file describes. DEPTHCOLOR lines become depth_color_span values of the
// renderer's transfer function (hypertree/depth_colors.hpp): depths from..to get colors first..last,
// linearly in depth (section 8.3), RGB in [0, 1].
struct parsed_tree {
    hypertree::ifs<runtime_pipeline> ifs;
    std::vector<depth_color_span> depth_colors; // in file order; their depth ranges do not overlap
    std::optional<int> density_class_count; // DENSITYCLASSES; empty: the caller's choice (build_options)
    // Noise at the two later stages of section 3.5 (perturbation.hpp): VOXELPERTURB, applied to the
    // built store by perturb_voxels, and RENDERPERTURB, the marcher's sample displacement
    // (march_options::displacement, read here as the sample_displacement it is). Empty: none. (PERTURB, the generation stage, is ifs.perturb;
    // TRIM regions are ifs.trim.)
    std::optional<perturbation> voxel_perturb;
    std::optional<sample_displacement> render_perturb;
    // Where the file said so, for refusals found after parsing (a forest's build checks TRIM
    // against its own grid, and refuses RENDERPERTURB: forest.hpp, forest_file.hpp; budgets and
    // the marcher's limits: hypertree/definition_refusals.hpp).
    std::string file;
    std::optional<source_position> voxel_perturb_at, render_perturb_at;
    std::vector<source_position> trim_at; // one per ifs.trim region, in its order
    std::vector<source_position> transform_at, condensation_at; // one per block, in file order
    // The line of each keyword the file gives once (RESOLUTION, ITERATIONS, PERTURB, ...), the
    // generator's under the word the file used (POINTINIT or LINEINIT).
    std::vector<std::pair<std::string_view, source_position>> keyword_at;

    // A setting of the file: its keyword and the line that gave it (`given` false, and the
    // position 1:1, for a keyword left at its default).
    struct setting {
        std::string_view keyword;
        source_position at;
        bool given = false;
    };
    // The setting a refusal of the C++ model names by its parameter (krs::invalid_parameter's
    // parameter(), "ifs.iterations", "hypervolume.resolution", "ifs.transforms[2]", ...); none for
    // a parameter no keyword sets.
    std::optional<setting> setting_of(const std::string& parameter) const
    {
        const auto keyword = [&](std::string_view k) {
            for (const auto& [name, at] : keyword_at)
                if (name == k) return setting{name, at, true};
            return setting{k, {}, false};
        };
        const auto block = [&](std::string_view k, const std::vector<source_position>& at, std::size_t prefix) {
            std::size_t j = 0;
            if (parameter.size() > prefix && parameter[prefix] == '[') j = std::size_t(std::strtoul(parameter.c_str() + prefix + 1, nullptr, 10));
            return j < at.size() ? setting{k, at[j], true} : setting{k, {}, false};
        };
        if (parameter.starts_with("ifs.transforms")) return block("TRANSFORM", transform_at, 14);
        if (parameter.starts_with("ifs.condensations")) return block("CONDENSATION", condensation_at, 17);
        if (parameter.starts_with("cone")) return block("CONDENSATION", condensation_at, 4);
        if (parameter.starts_with("ifs.trim")) return block("TRIM", trim_at, 8);
        if (parameter.starts_with("ifs.tree_depth")) return keyword("TREEDEPTH");
        if (parameter.starts_with("ifs.branch_depth")) {
            const setting b = keyword("BRANCHDEPTH");
            return b.given ? b : keyword("TREEDEPTH");
        }
        if (parameter.starts_with("ifs.iterations")) return keyword("ITERATIONS");
        if (parameter.starts_with("ifs.generator")) {
            const setting line = keyword("LINEINIT");
            return line.given ? line : keyword("POINTINIT");
        }
        if (parameter.starts_with("ifs.perturb")) return keyword("PERTURB");
        if (parameter.starts_with("march_options.displacement")) return keyword("RENDERPERTURB");
        if (parameter.starts_with("hypervolume.resolution")) return keyword("RESOLUTION");
        if (parameter.starts_with("hypervolume.extent")) return keyword("HYPERVOLUME");
        if (parameter.starts_with("hypervolume")) return keyword("DISPLACEMENT"); // the origin and the box
        return std::nullopt;
    }

    // The color the file gives voxels of `depth`, if a DEPTHCOLOR covers it.
    std::optional<rgb> color_of_depth(int depth) const
    {
        for (const auto& c : depth_colors)
            if (c.from <= depth && depth <= c.to) return hypertree::depth_colors({c}).at(depth);
        return std::nullopt;
    }
    // The renderer's transfer function: the file's DEPTHCOLOR spans, or when it gives none the
    // default bark-and-leaves colors of its branch and tree depths.
    hypertree::depth_colors colors() const
    {
        return depth_colors.empty() ? hypertree::depth_colors::tree(ifs.branch_depth, ifs.tree_depth) : hypertree::depth_colors(depth_colors);
    }
};

namespace detail {

enum class definition_keyword {
    resolution,
    iterations,
    tree_depth,
    branch_depth,
    name,
    depth_color,
    density_classes,
    perturb,
    voxel_perturb,
    render_perturb,
    trim,
    hypervolume,
    displacement,
    point_init,
    line_init,
    transform,
    condensation,
    translate,
    rotate,
    scale,
    shear,
    cone,
    count
};

struct keyword_entry {
    std::string_view name;
    definition_keyword id;
    std::string_view usage;
};

inline constexpr keyword_entry definition_keywords[] = {
    {"RESOLUTION", definition_keyword::resolution, "RESOLUTION n | RESOLUTION nx ny nz"},
    {"ITERATIONS", definition_keyword::iterations, "ITERATIONS count"},
    {"TREEDEPTH", definition_keyword::tree_depth, "TREEDEPTH depth"},
    {"BRANCHDEPTH", definition_keyword::branch_depth, "BRANCHDEPTH depth"},
    {"NAME", definition_keyword::name, "NAME word | NAME \"text\""},
    {"DEPTHCOLOR", definition_keyword::depth_color, "DEPTHCOLOR first_depth last_depth r0 g0 b0 r1 g1 b1"},
    {"DENSITYCLASSES", definition_keyword::density_classes, "DENSITYCLASSES count"},
    {"PERTURB", definition_keyword::perturb, "PERTURB ax ay az [frequency]"},
    {"VOXELPERTURB", definition_keyword::voxel_perturb, "VOXELPERTURB ax ay az [frequency]"},
    {"RENDERPERTURB", definition_keyword::render_perturb, "RENDERPERTURB ax ay az [frequency]"},
    {"TRIM", definition_keyword::trim, "TRIM BOX x0 y0 z0 x1 y1 z1 | TRIM SPHERE x y z radius | TRIM HALFSPACE px py pz nx ny nz"},
    {"HYPERVOLUME", definition_keyword::hypervolume, "HYPERVOLUME x y z"},
    {"DISPLACEMENT", definition_keyword::displacement, "DISPLACEMENT x y z"},
    {"POINTINIT", definition_keyword::point_init, "POINTINIT x y z"},
    {"LINEINIT", definition_keyword::line_init, "LINEINIT x0 y0 z0 x1 y1 z1"},
    {"TRANSFORM", definition_keyword::transform, "TRANSFORM probability last_level [DUMMY level]"},
    {"CONDENSATION", definition_keyword::condensation, "CONDENSATION"},
    {"TRANSLATE", definition_keyword::translate, "TRANSLATE x y z"},
    {"ROTATE", definition_keyword::rotate, "ROTATE ax ay az degrees"},
    {"SCALE", definition_keyword::scale, "SCALE s | SCALE sx sy sz"},
    {"SHEAR", definition_keyword::shear, "SHEAR x|y|z dmax1 dmax2 exponent [height]"},
    {"CONE", definition_keyword::cone, "CONE x|y|z bottom top bottom_radius top_radius"},
};

inline const keyword_entry* find_definition_keyword(const io::token& t)
{
    if (t.kind != io::token_kind::word) return nullptr;
    for (const auto& k : definition_keywords)
        if (io::same_word(t.text, k.name)) return &k;
    return nullptr;
}

// The keywords only forest files have (forest_file.hpp; RESOLUTION both kinds share): what tells
// a forest file from a tree definition.
inline bool is_forest_only_keyword(const io::token& t)
{
    return t.kind == io::token_kind::word && (io::same_word(t.text, "STORAGETYPE") || io::same_word(t.text, "TREE"));
}

// The class counts DENSITYCLASSES accepts: density_classes' limits (create/density.hpp), repeated
// so that reading a file does not pull in the store code.
inline constexpr int density_class_minimum = 2;   // density_classes::min_class_count
inline constexpr int density_class_maximum = 255; // density_classes::max_class_count

class definition_parser {
public:
    definition_parser(std::string_view text, std::string_view file) : text_(text), file_(file)
    {
        // Keywords a file leaves out keep the C++ model's defaults.
        const hypertree::ifs<runtime_pipeline> defaults;
        grid_ = defaults.volume.grid();
        extent_ = defaults.volume.extent();
        displacement_ = -defaults.volume.origin();
    }

    parsed_tree run()
    {
        const std::vector<io::source_line> lines = io::tokenize(text_, file_);
        for (const io::source_line& line : lines) {
            const io::token& first = line.tokens.front();
            const keyword_entry* keyword = find_definition_keyword(first);
            if (keyword == nullptr) {
                // A forest file given where a tree is wanted fails at its first forest keyword;
                // say what the file is rather than list the tree's keywords.
                if (is_forest_only_keyword(first))
                    fail(first.at, io::upper(first.text) + " is a forest file's keyword: this is a forest file, and a tree "
                                                          "definition file is expected here");
                fail(first.at, "unknown keyword " + io::describe(&first) + "; " + keyword_list());
            }
            io::statement s(file_, line, keyword->usage);
            if (!is_element(keyword->id)) close_block();
            read(s, keyword->id);
        }
        close_block();
        return assemble();
    }

private:
    struct transform_block {
        source_position at;
        double probability = 1;
        int last_level = never;
        int dummy_from = never;
        std::vector<transform_element> elements;
        int shears = 0;
    };
    struct condensation_block {
        source_position at;
        std::optional<cone> stem;
        source_position stem_at;
        std::vector<transform_element> elements;
        int shears = 0;
    };
    enum class block { none, transform, condensation };

    static bool is_element(definition_keyword k)
    {
        return k == definition_keyword::translate || k == definition_keyword::rotate || k == definition_keyword::scale ||
               k == definition_keyword::shear || k == definition_keyword::cone;
    }
    static std::string keyword_list()
    {
        std::string list = "the keywords are";
        for (const auto& k : definition_keywords) list += std::string(&k == definition_keywords ? " " : ", ") + std::string(k.name);
        return list;
    }

    [[noreturn]] void fail(source_position at, const std::string& message) const { throw definition_error(file_, at, message); }

    // Runs `build` (a C++ constructor or validate()) and reports what the model refuses at `at`.
    template <class Build>
    auto checked(source_position at, std::string_view what, Build&& build) const
    {
        try {
            return build();
        } catch (const krs::invalid_parameter& e) {
            fail(at, "invalid " + std::string(what) + ": " + e.message());
        }
    }

    // Keywords that may appear once: a second occurrence names the first.
    void once(const io::statement& s, definition_keyword k, std::string_view as = {})
    {
        std::optional<source_position>& seen = seen_[std::size_t(k)];
        if (seen)
            fail(s.where(), (as.empty() ? s.keyword() : std::string(as)) + " is given twice (first on line " + std::to_string(seen->line) + ")");
        seen = s.where();
    }
    std::optional<source_position> seen(definition_keyword k) const { return seen_[std::size_t(k)]; }

    void close_block()
    {
        if (current_ == block::transform && transforms_.back().elements.empty())
            fail(transforms_.back().at, "expected at least one TRANSLATE, ROTATE, SCALE or SHEAR line after TRANSFORM");
        if (current_ == block::condensation && !condensations_.back().stem)
            fail(condensations_.back().at, "expected a CONE line after CONDENSATION (CONE x|y|z bottom top bottom_radius top_radius)");
        current_ = block::none;
    }

    vec3d vector3(io::statement& s, io::number_rule rule = io::number_rule::any)
    {
        const double x = s.number(rule), y = s.number(rule), z = s.number(rule);
        return {x, y, z};
    }

    void read(io::statement& s, definition_keyword k)
    {
        using io::number_rule;
        switch (k) {
        case definition_keyword::resolution:
            once(s, k);
            grid_ = io::read_resolution(s);
            break;
        case definition_keyword::iterations:
            once(s, k);
            tree_.iterations = s.count(1);
            s.finish();
            break;
        case definition_keyword::tree_depth:
            once(s, k);
            tree_.tree_depth = int(s.integer(1, max_tree_depth));
            s.finish();
            break;
        case definition_keyword::branch_depth:
            once(s, k);
            tree_.branch_depth = int(s.integer(0, max_tree_depth - 1));
            s.finish();
            break;
        case definition_keyword::name:
            once(s, k);
            tree_.name = std::string(s.text("a name (a word or \"quoted text\")"));
            s.finish();
            break;
        case definition_keyword::depth_color: read_depth_color(s); break;
        case definition_keyword::density_classes:
            once(s, k);
            density_class_count_ = int(s.integer(density_class_minimum, density_class_maximum));
            s.finish();
            break;
        case definition_keyword::perturb:
            once(s, k);
            tree_.perturb.amplitude = vector3(s, number_rule::non_negative);
            if (!s.at_end()) tree_.perturb.frequency = s.number(number_rule::non_negative);
            s.finish();
            break;
        case definition_keyword::voxel_perturb: {
            once(s, k);
            perturbation p;
            p.amplitude = vector3(s, number_rule::non_negative);
            if (!s.at_end()) p.frequency = s.number(number_rule::non_negative);
            s.finish();
            checked(s.where(), "VOXELPERTURB", [&] { p.validate("VOXELPERTURB"); });
            voxel_perturb_ = p;
            break;
        }
        case definition_keyword::render_perturb: {
            once(s, k);
            const vec3d a = vector3(s, number_rule::non_negative);
            // The marcher's amplitude is float: a positive amplitude that rounds to 0 (1e-50)
            // would switch the noise off silently. (PERTURB and VOXELPERTURB stay double.)
            const auto in_float = [&](double v, const char* axis) {
                const float f = float(v);
                if (v > 0 && !(f > 0))
                    fail(s.where(), std::string("expected a RENDERPERTURB amplitude ") + axis +
                                        " of 0 or one a float holds (>= 1.4e-45; the marcher reads it in float), got " +
                                        krs::detail::to_text(v) + ", which is 0 in float");
                return f;
            };
            sample_displacement d;
            d.amplitude = {in_float(a.x, "x"), in_float(a.y, "y"), in_float(a.z, "z")};
            if (!s.at_end()) d.frequency = float(s.number(number_rule::non_negative));
            s.finish();
            checked(s.where(), "RENDERPERTURB", [&] { d.validate("RENDERPERTURB"); });
            render_perturb_ = d;
            break;
        }
        case definition_keyword::trim: read_trim(s); break;
        case definition_keyword::hypervolume:
            once(s, k);
            extent_ = vector3(s, number_rule::positive);
            s.finish();
            break;
        case definition_keyword::displacement:
            once(s, k);
            displacement_ = vector3(s);
            s.finish();
            break;
        case definition_keyword::point_init: {
            once(s, definition_keyword::point_init, "the generator (POINTINIT or LINEINIT)");
            generator_keyword_ = "POINTINIT";
            const vec3d p = vector3(s);
            s.finish();
            tree_.generator = generator_shape::line(p, p);
            break;
        }
        case definition_keyword::line_init: {
            once(s, definition_keyword::point_init, "the generator (POINTINIT or LINEINIT)");
            generator_keyword_ = "LINEINIT";
            const vec3d a = vector3(s), b = vector3(s);
            s.finish();
            tree_.generator = generator_shape::line(a, b);
            break;
        }
        case definition_keyword::transform: read_transform(s); break;
        case definition_keyword::condensation:
            if (condensations_.size() == 2)
                fail(s.where(), "expected at most two CONDENSATIONs (one stem, or the two stems of a dichotomous fork)");
            s.finish();
            condensations_.push_back({s.where(), std::nullopt, {}, {}, 0});
            current_ = block::condensation;
            break;
        case definition_keyword::cone: read_cone(s); break;
        case definition_keyword::translate:
        case definition_keyword::rotate:
        case definition_keyword::scale:
        case definition_keyword::shear: read_element(s, k); break;
        case definition_keyword::count: break;
        }
    }

    void read_depth_color(io::statement& s)
    {
        using io::number_rule;
        depth_color_span c;
        c.from = int(s.integer(0, max_tree_depth - 1));
        c.to = int(s.integer(c.from, max_tree_depth - 1));
        const vec3d first = vector3(s, number_rule::unit_interval), last = vector3(s, number_rule::unit_interval);
        c.first = {float(first.x), float(first.y), float(first.z)};
        c.last = {float(last.x), float(last.y), float(last.z)};
        s.finish();
        for (std::size_t i = 0; i < depth_colors_.size(); ++i) {
            const depth_color_span& other = depth_colors_[i];
            if (c.from <= other.to && other.from <= c.to)
                fail(s.where(), "expected DEPTHCOLOR depths that no other DEPTHCOLOR covers, got " + std::to_string(c.from) + " to " +
                                    std::to_string(c.to) + ", which overlaps " + std::to_string(other.from) + " to " +
                                    std::to_string(other.to) + " on line " + std::to_string(depth_color_at_[i].line));
        }
        depth_colors_.push_back(c);
        depth_color_at_.push_back(s.where());
    }

    // TRIM BOX lo hi | SPHERE center radius | HALFSPACE point normal: a region locked while the
    // tree is generated (ifs::trim). Whether it holds a voxel is checked with the hypervolume, at
    // the end, and reported here.
    void read_trim(io::statement& s)
    {
        using io::number_rule;
        if (s.accept_word("BOX")) {
            const vec3d lo = vector3(s), hi = vector3(s);
            s.finish();
            tree_.trim.push_back(checked(s.where(), "TRIM BOX", [&] { return trim_region(box_region(lo, hi)); }));
        } else if (s.accept_word("SPHERE")) {
            const vec3d c = vector3(s);
            const double r = s.number(number_rule::positive);
            s.finish();
            tree_.trim.push_back(checked(s.where(), "TRIM SPHERE", [&] { return trim_region(sphere_region(c, r)); }));
        } else if (s.accept_word("HALFSPACE")) {
            const vec3d p = vector3(s), n = vector3(s);
            s.finish();
            tree_.trim.push_back(checked(s.where(), "TRIM HALFSPACE", [&] { return trim_region(half_space_region(p, n)); }));
        } else {
            s.expected("BOX, SPHERE or HALFSPACE", "after TRIM");
        }
        trim_at_.push_back(s.where());
    }

    void read_transform(io::statement& s)
    {
        if (transforms_.size() == std::size_t(max_transforms))
            fail(s.where(), "expected at most " + std::to_string(max_transforms) + " TRANSFORMs (a voxel names its subpart in one byte)");
        transform_block t;
        t.at = s.where();
        t.probability = s.number(io::number_rule::non_negative);
        // Levels are counted from 1, so 0 is free to mean "no limit".
        const int last = int(s.integer(0, max_tree_depth));
        t.last_level = last == 0 ? never : last;
        if (!s.at_end()) {
            if (!s.accept_word("DUMMY")) s.expected("DUMMY or the end of the line", "after TRANSFORM's last level");
            t.dummy_from = int(s.integer(1, max_tree_depth, "after DUMMY"));
        }
        s.finish();
        transforms_.push_back(std::move(t));
        current_ = block::transform;
    }

    void read_cone(io::statement& s)
    {
        using io::number_rule;
        if (current_ != block::condensation)
            fail(s.where(), current_ == block::transform ? "a CONE belongs to a CONDENSATION, not to a TRANSFORM"
                                                         : "expected a CONDENSATION line before CONE");
        condensation_block& c = condensations_.back();
        if (c.stem) fail(s.where(), "expected one CONE per CONDENSATION (its CONE is on line " + std::to_string(c.stem_at.line) + ")");
        cone stem;
        stem.axis = s.axis();
        stem.bottom = s.number();
        stem.top = s.number();
        stem.bottom_radius = s.number(number_rule::non_negative);
        stem.top_radius = s.number(number_rule::non_negative);
        s.finish();
        checked(s.where(), "CONE", [&] { stem.validate(); });
        c.stem = stem;
        c.stem_at = s.where();
    }

    // One value of a transformation: a number, or mean~spread, or a per-level pair or triplet of
    // those. `unit` converts the file's unit to the model's (degrees to radians).
    parameter read_parameter(io::statement& s, bool per_level_allowed, double unit = 1.0)
    {
        parameter p;
        const io::token* t = s.peek();
        if (t != nullptr && t->kind == io::token_kind::open_paren) {
            if (!per_level_allowed)
                s.fail(t->at, "unexpected '(' after " + s.keyword() +
                                  ": a condensation's transformations run once per cycle, at no level, so per-level values do not apply");
            s.take();
            const std::string context = "in the per-level value of " + s.keyword();
            int count = 0;
            for (;;) {
                read_random_number(s, p.mean[std::size_t(count)], p.spread[std::size_t(count)], context);
                ++count;
                const io::token* next = s.peek();
                if (count >= 2 && next != nullptr && next->kind == io::token_kind::close_paren) {
                    s.take();
                    break;
                }
                if (count < distinct_levels && next != nullptr && next->kind == io::token_kind::comma) {
                    s.take();
                    continue;
                }
                // A per-level value is (level 1, deeper levels) or (level 1, level 2, level 3 and deeper).
                s.expected(count < 2                 ? "',' (a per-level value has two or three entries)"
                           : count < distinct_levels ? "',' or ')'"
                                                     : "')' (a per-level value has at most three entries: levels 1, 2, and 3 and deeper)",
                           context);
            }
            // A pair gives level 1 and all deeper levels (section 10).
            if (count == 2) p.mean[2] = p.mean[1], p.spread[2] = p.spread[1];
        } else {
            double mean = 0, spread = 0;
            read_random_number(s, mean, spread, {});
            p.mean = {mean, mean, mean};
            p.spread = {spread, spread, spread};
        }
        if (unit != 1.0)
            for (int l = 0; l < distinct_levels; ++l) p.mean[std::size_t(l)] *= unit, p.spread[std::size_t(l)] *= unit;
        return p;
    }

    // mean or mean~spread.
    static void read_random_number(io::statement& s, double& mean, double& spread, const std::string& context)
    {
        mean = s.number_before_spread(io::number_rule::any, context);
        spread = 0;
        const io::token* t = s.peek();
        if (t != nullptr && t->kind == io::token_kind::tilde) {
            s.take();
            spread = s.number(io::number_rule::non_negative, "after '~' in " + s.keyword());
        }
    }

    void read_element(io::statement& s, definition_keyword k)
    {
        if (current_ == block::none) fail(s.where(), "expected a TRANSFORM or CONDENSATION line before " + s.keyword());
        if (current_ == block::condensation && !condensations_.back().stem)
            fail(s.where(), "expected the CONE line first after CONDENSATION, got " + s.keyword());
        const bool per_level = current_ == block::transform;
        std::vector<transform_element>& elements = per_level ? transforms_.back().elements : condensations_.back().elements;
        int& shears = per_level ? transforms_.back().shears : condensations_.back().shears;
        switch (k) {
        case definition_keyword::translate: {
            const parameter x = read_parameter(s, per_level), y = read_parameter(s, per_level), z = read_parameter(s, per_level);
            s.finish();
            elements.push_back(checked(s.where(), "TRANSLATE", [&] { return translate(x, y, z); }));
            break;
        }
        case definition_keyword::rotate: {
            const vec3d axis = vector3(s);
            const parameter angle = read_parameter(s, per_level, radians_per_degree);
            s.finish();
            elements.push_back(checked(s.where(), "ROTATE", [&] { return rotate(axis, angle); }));
            break;
        }
        case definition_keyword::scale: {
            const parameter x = read_parameter(s, per_level);
            if (s.at_end()) {
                elements.push_back(checked(s.where(), "SCALE", [&] { return scale(x); }));
                break;
            }
            const parameter y = read_parameter(s, per_level), z = read_parameter(s, per_level);
            s.finish();
            elements.push_back(checked(s.where(), "SCALE", [&] { return scale(x, y, z); }));
            break;
        }
        case definition_keyword::shear: {
            if (shears == max_runtime_shears)
                fail(s.where(), "expected at most " + std::to_string(max_runtime_shears) + " SHEARs in one " +
                                    (per_level ? "TRANSFORM" : "CONDENSATION"));
            const int axis = s.axis();
            const parameter first = read_parameter(s, per_level), second = read_parameter(s, per_level);
            const parameter exponent = read_parameter(s, per_level);
            const double height = s.at_end() ? 1.0 : s.number(io::number_rule::positive);
            s.finish();
            elements.push_back(checked(s.where(), "SHEAR", [&] { return shear(axis, first, second, exponent, height); }));
            ++shears;
            break;
        }
        default: break;
        }
    }

    // Where each setting was given, for refusals of the C++ model (parsed_tree::setting_of).
    void record_positions(parsed_tree& out) const
    {
        for (const auto& k : definition_keywords)
            // POINTINIT and LINEINIT share one slot (one generator), kept under the word used.
            if (const std::optional<source_position> at = seen(k.id); at && k.id != definition_keyword::line_init)
                out.keyword_at.emplace_back(k.id == definition_keyword::point_init ? generator_keyword_ : k.name, *at);
        for (const auto& t : transforms_) out.transform_at.push_back(t.at);
        for (const auto& c : condensations_) out.condensation_at.push_back(c.at);
    }

    parsed_tree assemble()
    {
        if (transforms_.empty()) fail(io::end_of_input(text_), "expected at least one TRANSFORM (the IFS needs a transformation)");
        double total_probability = 0;
        for (const auto& t : transforms_) total_probability += t.probability;
        if (!(total_probability > 0))
            fail(transforms_.front().at, "expected a positive probability on at least one TRANSFORM, got probabilities that sum to 0");

        if (tree_.branch_depth >= tree_.tree_depth)
            fail(seen(definition_keyword::branch_depth).value_or(seen(definition_keyword::tree_depth).value_or(source_position{})),
                 "expected BRANCHDEPTH below TREEDEPTH (wood is depths 0 .. BRANCHDEPTH of the tree's 0 .. TREEDEPTH - 1), got BRANCHDEPTH " +
                     std::to_string(tree_.branch_depth) + (seen(definition_keyword::branch_depth) ? "" : " (the default)") +
                     " with TREEDEPTH " + std::to_string(tree_.tree_depth));
        for (std::size_t i = 0; i < depth_colors_.size(); ++i)
            if (depth_colors_[i].to >= tree_.tree_depth)
                fail(depth_color_at_[i], "expected DEPTHCOLOR depths below TREEDEPTH " + std::to_string(tree_.tree_depth) + ", got " +
                                             std::to_string(depth_colors_[i].from) + " to " +
                                             std::to_string(depth_colors_[i].to));

        hypertree::ifs<runtime_pipeline> tree = tree_;
        tree.transforms.clear();
        for (auto& t : transforms_) {
            runtime_pipeline pipeline = checked(t.at, "TRANSFORM", [&] { return runtime_pipeline(std::move(t.elements)); });
            // The generator refuses a transformation that is not a contraction (ifs.hpp); report it
            // here, at its line, for the mean parameter values (a random draw may still exceed 1).
            for (int level = 1; level <= distinct_levels; ++level) {
                const double bound = pipeline.chain_at(level).lipschitz();
                if (!(bound < 1.0))
                    fail(t.at, "expected a contraction (Lipschitz bound < 1) at level " + std::to_string(level) +
                                   (level == distinct_levels ? " and deeper" : "") + ", got a TRANSFORM whose bound at its mean values is " +
                                   krs::detail::to_text(bound) + " (add or shrink a SCALE)");
            }
            tree.transforms.push_back({std::move(pipeline), t.probability, t.last_level, t.dummy_from});
        }
        if (!condensations_.empty()) {
            tree.condensations.clear();
            for (auto& c : condensations_)
                tree.condensations.push_back(
                    {*c.stem, checked(c.at, "CONDENSATION", [&] { return runtime_pipeline(std::move(c.elements)); })});
        }
        parsed_tree out{{},
                        std::move(depth_colors_),
                        density_class_count_,
                        voxel_perturb_,
                        render_perturb_,
                        std::string(file_),
                        seen(definition_keyword::voxel_perturb),
                        seen(definition_keyword::render_perturb),
                        trim_at_,
                        {},
                        {},
                        {}};
        record_positions(out);
        try {
            tree.volume = hypervolume::from_displacement(extent_, displacement_, grid_);
            tree.validate();
        } catch (const krs::invalid_parameter& e) {
            const auto setting = out.setting_of(e.parameter());
            fail(setting ? setting->at : seen(definition_keyword::displacement).value_or(source_position{}),
                 "invalid tree: " + e.message());
        }
        out.ifs = std::move(tree);
        return out;
    }

    std::string_view text_, file_;
    hypertree::ifs<runtime_pipeline> tree_; // the scalar settings as read
    resolution grid_;
    vec3d extent_, displacement_;
    std::vector<transform_block> transforms_;
    std::vector<condensation_block> condensations_;
    block current_ = block::none;
    std::vector<depth_color_span> depth_colors_;
    std::vector<source_position> depth_color_at_;
    std::optional<int> density_class_count_;
    std::optional<perturbation> voxel_perturb_;
    std::optional<sample_displacement> render_perturb_;
    std::vector<source_position> trim_at_;
    std::array<std::optional<source_position>, std::size_t(definition_keyword::count)> seen_{};
    std::string_view generator_keyword_; // POINTINIT or LINEINIT, whichever the file used
};

} // namespace detail

// Parses a definition file's text; `file_name` only labels the messages.
inline parsed_tree parse_definition(std::string_view text, std::string_view file_name)
{
    return detail::definition_parser(text, file_name).run();
}

// Reads and parses a definition file; messages name it as `path` is written.
inline parsed_tree load_definition(const std::filesystem::path& path)
{
    const io::text_file file = io::read_text_file(path);
    if (!file.problem.empty())
        throw definition_error(path.string(), {1, 1}, "cannot read the definition file: " + file.problem);
    return parse_definition(file.text, path.string());
}

} // namespace hypertree

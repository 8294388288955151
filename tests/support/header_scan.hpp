#pragma once
// The classes of include/krs whose body holds a marker (a member's name): how the GLSL tests find
// every type with GLSL, so that a type gaining GLSL without a test fails them.

#include <cstddef>
#include <filesystem>
#include <fstream>
#include <iterator>
#include <regex>
#include <set>
#include <string>
#include <utility>
#include <vector>

namespace krs_test {

// Every class or struct of include/krs (every header but the emitter's own folder, which describes
// the members in prose and owns none) with a match of `marker` in it: the owner is the last class
// opened before the match. An opening is `struct|class [alignas(...)] NAME ... {` with no ( ) ; < >
// between the name and the brace, so `template <class X>` is not taken for a class.
inline std::set<std::string> classes_with(const std::regex& marker)
{
    const std::filesystem::path root = std::filesystem::path(KRS_SOURCE_DIR) / "include" / "krs";
    const std::regex opening(R"((?:struct|class)\s+(?:alignas\([^)]*\)\s*)?(\w+)[^{;()<>]*\{)");
    std::set<std::string> found;
    for (const auto& entry : std::filesystem::recursive_directory_iterator(root)) {
        if (entry.path().extension() != ".hpp" || entry.path().parent_path().filename() == "glsl") continue;
        std::ifstream in(entry.path());
        const std::string text((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
        std::vector<std::pair<std::ptrdiff_t, std::string>> classes;
        for (auto it = std::sregex_iterator(text.begin(), text.end(), opening); it != std::sregex_iterator(); ++it)
            classes.emplace_back(it->position(), (*it)[1].str());
        for (auto it = std::sregex_iterator(text.begin(), text.end(), marker); it != std::sregex_iterator(); ++it) {
            std::string owner;
            for (const auto& [at, name] : classes)
                if (at < it->position()) owner = name;
            if (!owner.empty()) found.insert(owner);
        }
    }
    return found;
}

} // namespace krs_test

// krs::krs and krs::hypertree depend on GLM and xsimd alone (docs/design.md, "Two libraries, two
// targets"): OpenVDB and NanoVDB are included by exactly the two headers of the optional target
// krs::hypertree_openvdb, and no other header includes those two, so a program that never names
// them compiles without either library. (The targets' link interfaces are checked by the tests
// library_targets_link_no_vdb_*, tests/CMakeLists.txt.)

#include <doctest/doctest.h>

#include <filesystem>
#include <fstream>
#include <iterator>
#include <regex>
#include <set>
#include <string>

TEST_CASE("only io/openvdb.hpp and io/nanovdb.hpp include OpenVDB or NanoVDB, and no header includes them")
{
    const std::filesystem::path include = std::filesystem::path(KRS_SOURCE_DIR) / "include";
    const std::set<std::string> allowed = {"hypertree/io/openvdb.hpp", "hypertree/io/nanovdb.hpp"};
    const std::regex library(R"(#\s*include\s*[<"](openvdb|nanovdb)/)");
    const std::regex optional_header(R"(#\s*include\s*[<"]hypertree/io/(openvdb|nanovdb)\.hpp[">])");
    std::set<std::string> including_library, including_optional;
    int headers = 0;
    for (const auto& entry : std::filesystem::recursive_directory_iterator(include)) {
        if (!entry.is_regular_file() || entry.path().extension() != ".hpp") continue;
        ++headers;
        const std::string name = std::filesystem::relative(entry.path(), include).generic_string();
        std::ifstream in(entry.path());
        const std::string text((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
        if (std::regex_search(text, library)) including_library.insert(name);
        if (std::regex_search(text, optional_header)) including_optional.insert(name);
    }
    CHECK(headers > 50);
    CHECK(including_library == allowed);
    CHECK(including_optional.empty());
}

// The same for tinygltf: krs/mesh/gltf.hpp (target krs::mesh_gltf) alone includes it, and no
// header includes krs/mesh/gltf.hpp.
TEST_CASE("only krs/mesh/gltf.hpp includes tinygltf, and no header includes it")
{
    const std::filesystem::path include = std::filesystem::path(KRS_SOURCE_DIR) / "include";
    const std::regex library(R"(#\s*include\s*[<"]tiny_gltf\.h[">])");
    const std::regex optional_header(R"(#\s*include\s*[<"]krs/mesh/gltf\.hpp[">])");
    std::set<std::string> including_library, including_optional;
    for (const auto& entry : std::filesystem::recursive_directory_iterator(include)) {
        if (!entry.is_regular_file() || entry.path().extension() != ".hpp") continue;
        const std::string name = std::filesystem::relative(entry.path(), include).generic_string();
        std::ifstream in(entry.path());
        const std::string text((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
        if (std::regex_search(text, library)) including_library.insert(name);
        if (std::regex_search(text, optional_header)) including_optional.insert(name);
    }
    CHECK(including_library == std::set<std::string>{"krs/mesh/gltf.hpp"});
    CHECK(including_optional.empty());
}

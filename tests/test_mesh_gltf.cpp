// glTF/GLB meshes (krs/mesh/gltf.hpp, target krs::mesh_gltf): read back by tinygltf's own loader
// (every position, normal and index equal to the mesh's), by Debian's assimp, and validated by the
// Khronos glTF validator where it is installed (0 errors); bad input leaves no file.

#include "krs/kernels/torus.hpp"
#include "krs/mesh/extract.hpp"
#include "krs/mesh/gltf.hpp"

#include <doctest/doctest.h>

#include <cstdlib>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <iterator>
#include <limits>
#include <string>

#include <unistd.h> // getpid

namespace {

std::filesystem::path temp_path(const std::string& name)
{
    return std::filesystem::temp_directory_path() / ("krs_test_gltf_" + std::to_string(::getpid()) + "_" + name);
}

// The accessor's elements as floats or uint32 (tightly packed, as gltf_model writes them).
template <class T>
std::vector<T> accessor_values(const tinygltf::Model& model, int index)
{
    const tinygltf::Accessor& a = model.accessors.at(std::size_t(index));
    const tinygltf::BufferView& v = model.bufferViews.at(std::size_t(a.bufferView));
    const auto& data = model.buffers.at(std::size_t(v.buffer)).data;
    const std::size_t per = a.type == TINYGLTF_TYPE_VEC3 ? 3 : 1;
    std::vector<T> out(a.count * per);
    REQUIRE(v.byteOffset + a.byteOffset + out.size() * sizeof(T) <= data.size());
    std::memcpy(out.data(), data.data() + v.byteOffset + a.byteOffset, out.size() * sizeof(T));
    return out;
}

std::string run(const std::string& command, int& status)
{
    const auto report = temp_path("report.txt");
    status = std::system((command + " > \"" + report.string() + "\" 2>&1").c_str());
    std::ifstream in(report);
    std::string text((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
    std::filesystem::remove(report);
    return text;
}

} // namespace

TEST_CASE("glb and gltf: tinygltf reads back the mesh exactly; assimp and the glTF validator accept the files")
{
    const krs::torus t({0, 0, 0}, {0.2f, 0.3f, 1.0f}, 1.0f, 0.3f);
    krs::mesh_options o;
    o.resolution = 24;
    const krs::triangle_mesh m = krs::extract_mesh(t, o);
    REQUIRE(m.triangle_count() > 1000);

    for (const bool binary : {true, false}) {
        CAPTURE(binary);
        const auto file = temp_path(binary ? "torus.glb" : "torus.gltf");
        if (binary) krs::save_glb(m, file);
        else krs::save_gltf(m, file);

        tinygltf::Model model;
        tinygltf::TinyGLTF loader;
        std::string err, warn;
        const bool loaded = binary ? loader.LoadBinaryFromFile(&model, &err, &warn, file.string())
                                   : loader.LoadASCIIFromFile(&model, &err, &warn, file.string());
        INFO(err, warn);
        REQUIRE(loaded);
        REQUIRE(model.meshes.size() == 1);
        const tinygltf::Primitive& p = model.meshes[0].primitives.at(0);
        CHECK(p.mode == TINYGLTF_MODE_TRIANGLES);
        const auto positions = accessor_values<float>(model, p.attributes.at("POSITION"));
        const auto normals = accessor_values<float>(model, p.attributes.at("NORMAL"));
        const auto indices = accessor_values<std::uint32_t>(model, p.indices);
        REQUIRE(positions.size() == 3 * m.vertex_count());
        REQUIRE(normals.size() == 3 * m.vertex_count());
        REQUIRE(indices.size() == 3 * m.triangle_count());
        std::size_t bad = 0;
        for (std::size_t v = 0; v < m.vertex_count(); ++v) {
            bad += positions[3 * v] != m.positions[v].x || positions[3 * v + 1] != m.positions[v].y || positions[3 * v + 2] != m.positions[v].z;
            bad += normals[3 * v] != m.normals[v].x || normals[3 * v + 1] != m.normals[v].y || normals[3 * v + 2] != m.normals[v].z;
        }
        for (std::size_t f = 0; f < m.triangle_count(); ++f)
            for (int c = 0; c < 3; ++c) bad += indices[3 * f + std::size_t(c)] != m.triangles[f][std::size_t(c)];
        CHECK(bad == 0);

#ifdef KRS_ASSIMP
        {
            int status = 0;
            const std::string text = run(std::string(KRS_ASSIMP) + " info \"" + file.string() + "\"", status);
            INFO(text);
            CHECK(status == 0);
            CHECK(text.find("Faces:              " + std::to_string(m.triangle_count()) + "\n") != std::string::npos);
        }
#endif
#ifdef KRS_GLTF_VALIDATE
        {
            int status = 0;
            const std::string text = run(std::string(KRS_GLTF_VALIDATE) + " \"" + file.string() + "\"", status);
            INFO(text);
            CHECK(status == 0);
            CHECK(text.find(": 0 errors") != std::string::npos);
            MESSAGE(text);
        }
#else
        MESSAGE("the Khronos glTF validator was not found at configure time (KRS_GLTF_VALIDATOR_DIR)");
#endif
        std::filesystem::remove(file);
    }
}

TEST_CASE("glb: bad paths and meshes are refused and leave no file behind")
{
    const krs::torus t({0, 0, 0}, {0, 0, 1}, 1.0f, 0.3f);
    krs::mesh_options o;
    o.resolution = 8;
    krs::triangle_mesh m = krs::extract_mesh(t, o);
    const auto missing = std::filesystem::temp_directory_path() / "krs_no_such_directory" / "x.glb";
    CHECK_THROWS_WITH_AS(krs::save_glb(m, missing), doctest::Contains("save_glb: "), krs::save_error);
    CHECK_THROWS_WITH_AS(krs::save_glb(m, ""), doctest::Contains("save_glb path"), krs::invalid_parameter);
    const auto file = temp_path("bad.glb");
    m.normals.pop_back();
    CHECK_THROWS_WITH_AS(krs::save_glb(m, file), doctest::Contains("one normal per vertex"), krs::invalid_parameter);
    CHECK_FALSE(std::filesystem::exists(file));
    m.normals.clear();
    m.triangles.clear();
    CHECK_THROWS_WITH_AS(krs::save_gltf(m, file), doctest::Contains("at least one triangle"), krs::invalid_parameter);
    CHECK_FALSE(std::filesystem::exists(file));
}

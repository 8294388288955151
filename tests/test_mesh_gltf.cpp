// glTF/GLB meshes (krs/mesh/gltf.hpp, target krs::mesh_gltf): read back by tinygltf's own loader
// (every position, normal and index equal to the mesh's), by Debian's assimp, and validated by the
// Khronos glTF validator (0 errors, no warning about extensions); bad input leaves no file.

#include "krs/kernels/plane.hpp"
#include "krs/kernels/sphere.hpp"
#include "krs/kernels/torus.hpp"
#include "krs/kernels/torus_capsule.hpp"
#include "krs/compose/zones.hpp"
#include "krs/expansion.hpp"
#include "krs/sequence.hpp"
#include "krs/mesh/extract.hpp"
#include "krs/mesh/gltf.hpp"
#include "krs/mesh/write.hpp"
#include "krs/core/srgb.hpp"
#include "krs/io/up_axis.hpp"

#include <doctest/doctest.h>

#include <algorithm>
#include <array>
#include <cmath>
#include <cstdlib>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <iterator>
#include <limits>
#include <set>
#include <sstream>
#include <utility>
#include <vector>
#include <string>

#include <sys/wait.h> // WEXITSTATUS
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
    const std::size_t per = a.type == TINYGLTF_TYPE_VEC4 ? 4 : a.type == TINYGLTF_TYPE_VEC3 ? 3 : a.type == TINYGLTF_TYPE_VEC2 ? 2 : 1;
    std::vector<T> out(a.count * per);
    REQUIRE(v.byteOffset + a.byteOffset + out.size() * sizeof(T) <= data.size());
    std::memcpy(out.data(), data.data() + v.byteOffset + a.byteOffset, out.size() * sizeof(T));
    return out;
}

// Every mesh a glTF scene draws, with the transform that places it in the world: the product of
// its node's and its ancestors' transforms (translation, rotation, scale or matrix), and for a
// node with EXT_mesh_gpu_instancing one entry per instance (the node's transform times the
// instance's). An independent reading of glTF's scene graph, by the specification's rules.
struct placed_mesh {
    int mesh;
    krs::isometry to_world;
};

krs::isometry node_transform(const tinygltf::Node& n)
{
    krs::isometry w;
    if (n.matrix.size() == 16) { // column-major
        for (int row = 0; row < 3; ++row)
            for (int col = 0; col < 3; ++col) w.a[std::size_t(row * 3 + col)] = n.matrix[std::size_t(col * 4 + row)];
        w.t = {n.matrix[12], n.matrix[13], n.matrix[14]};
        return w;
    }
    REQUIRE(n.scale.empty());
    if (n.rotation.size() == 4) {
        const double x = n.rotation[0], y = n.rotation[1], z = n.rotation[2], q = n.rotation[3];
        w.a = {1 - 2 * (y * y + z * z), 2 * (x * y - z * q),     2 * (x * z + y * q),
               2 * (x * y + z * q),     1 - 2 * (x * x + z * z), 2 * (y * z - x * q),
               2 * (x * z - y * q),     2 * (y * z + x * q),     1 - 2 * (x * x + y * y)};
    }
    if (n.translation.size() == 3) w.t = {n.translation[0], n.translation[1], n.translation[2]};
    return w;
}

std::vector<placed_mesh> placed_meshes(const tinygltf::Model& model);

void place_node(const tinygltf::Model& model, int index, const krs::isometry& parent, std::vector<placed_mesh>& out)
{
    const tinygltf::Node& n = model.nodes.at(std::size_t(index));
    const krs::isometry w = parent * node_transform(n);
    if (n.mesh >= 0) {
        const auto ext = n.extensions.find("EXT_mesh_gpu_instancing");
        if (ext == n.extensions.end()) {
            out.push_back({n.mesh, w});
        } else {
            const auto& attributes = ext->second.Get("attributes");
            const auto t = accessor_values<float>(model, attributes.Get("TRANSLATION").GetNumberAsInt());
            const auto r = accessor_values<float>(model, attributes.Get("ROTATION").GetNumberAsInt());
            REQUIRE(t.size() / 3 == r.size() / 4);
            for (std::size_t i = 0; i < t.size() / 3; ++i) {
                tinygltf::Node instance;
                instance.translation = {t[3 * i], t[3 * i + 1], t[3 * i + 2]};
                instance.rotation = {r[4 * i], r[4 * i + 1], r[4 * i + 2], r[4 * i + 3]};
                out.push_back({n.mesh, w * node_transform(instance)});
            }
        }
    }
    for (int child : n.children) place_node(model, child, w, out);
}

std::vector<placed_mesh> placed_meshes(const tinygltf::Model& model)
{
    std::vector<placed_mesh> out;
    for (int root : model.scenes.at(std::size_t(std::max(model.defaultScene, 0))).nodes) place_node(model, root, krs::isometry{}, out);
    return out;
}

// How many of `ours` have no distinct partner in `theirs` within `tolerance` (each partner used once).
std::size_t unmatched_points(const std::vector<krs::vec3d>& ours, std::vector<krs::vec3d> theirs, double tolerance)
{
    std::size_t unmatched = 0;
    for (const krs::vec3d& p : ours) {
        const auto near = std::find_if(theirs.begin(), theirs.end(), [&](const krs::vec3d& q) { return krs::length(p - q) <= tolerance; });
        if (near == theirs.end()) ++unmatched;
        else theirs.erase(near);
    }
    return unmatched;
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

// Khronos's glTF validator (scripts/validate_gltf.js) on the file: 0 errors and no warning about
// extensions. It always runs: where node or npm's gltf-validator is missing the check fails with
// the reason (scripts/install-deps.sh --tests installs both).
void check_with_validator(const std::filesystem::path& file)
{
#ifdef KRS_GLTF_VALIDATE
    int status = 0;
    const std::string text = run(std::string(KRS_GLTF_VALIDATE) + " \"" + file.string() + "\"", status);
    INFO(text);
    REQUIRE_MESSAGE(WEXITSTATUS(status) != 2, "the glTF validator could not run");
    CHECK(status == 0);
    CHECK(text.find(": 0 errors") != std::string::npos);
    CHECK(text.find("(0 about extensions)") != std::string::npos);
#else
    (void)file;
    FAIL("the glTF validator cannot run: " KRS_GLTF_VALIDATOR_MISSING);
#endif
}

} // namespace

TEST_CASE("glb and gltf: tinygltf reads back the mesh exactly, assimp reads it, the glTF validator finds 0 errors")
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
        check_with_validator(file);
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

namespace {

// A sphere and a torus capsule mirrored three times (eight copies of each; they overlap).
using instanced_sequence = krs::sequence<krs::sphere, krs::torus_capsule>;
instanced_sequence make_instanced_sequence()
{
    instanced_sequence::builder b;
    b.kernel(krs::sphere({0.6f, 0.5f, 0.1f}, 0.35f));
    b.mirror(krs::mirror({-1, 0, 0}, 0.0f));
    b.kernel(krs::torus_capsule({0.2f, 0.2f, 0.0f}, {0.9f, 0.3f, 0.2f}, {0.5f, 0.6f, 0.3f}, 0.12f));
    b.mirror(krs::mirror::through({0, 0, 0}, {-0.3f, -1.0f, -0.1f}));
    b.mirror(krs::mirror::through({0, 0, 0.4f}, {0.1f, 0.2f, -1.0f}));
    return b.build();
}

krs::vec3d apply(const krs::rigid_motion& m, const krs::vec3d& p)
{
    const auto& r = m.rotation;
    return krs::vec3d{r[0] * p.x + r[1] * p.y + r[2] * p.z, r[3] * p.x + r[4] * p.y + r[5] * p.z, r[6] * p.x + r[7] * p.y + r[8] * p.z} +
           m.translation;
}

} // namespace

TEST_CASE("instanced glTF: the instances are the expansion's, every instanced vertex is on its surface, the file validates")
{
    const instanced_sequence s = make_instanced_sequence();
    const auto e = krs::expand(s);
    for (std::size_t levels : {std::size_t(3), std::size_t(1)}) {
        CAPTURE(levels);
        krs::instance_options o;
        o.instance_levels = levels;
        o.mesh.resolution = 48;
        const krs::instanced_scene scene = krs::instance_meshes(s, o);
        // Levels >= 3 - levels are instanced: the sphere (level 0) 8 times when all three are, the
        // torus capsule (level 1) 4 times; with one level, the part below level 2 twice plus the
        // capsule... which is below too: 2 instances of one part.
        const std::size_t expected = levels == 3 ? 8 + 4 : 2;
        CHECK(scene.instance_count() == expected);
        const krs::bounding_box box = s.bound_box();
        const double cell = std::max({box.hi.x - box.lo.x, box.hi.y - box.lo.y, box.hi.z - box.lo.z}) / 48.0;
        // Every vertex of every instance, placed in the world, is on the expansion's surface (the
        // union's distance is <= 0 there: on its own kernel's zero set, maybe inside another).
        double worst = -1e300;
        std::size_t vertices = 0;
        for (const auto& p : scene.parts) {
            for (const auto& [mesh, instances] : {std::pair{&p.mesh, &p.direct}, std::pair{&p.mirrored, &p.reflected}})
                for (const auto& i : *instances)
                    for (const auto& v : mesh->positions) {
                        worst = std::max(worst, e.distance(apply(i, krs::vec3d(v))));
                        ++vertices;
                    }
        }
        MESSAGE(vertices << " instanced vertices, largest expansion distance " << worst / cell << " cells");
        CHECK(vertices > 1000);
        CHECK(worst <= 1e-4 * cell);
        if (levels == 3) {
            // Each kernel instance of the expansion is one of ours: its kernel's box centre lands at the
            // same world point (a mirrored instance: mirrored mesh, proper rotation).
            std::multiset<std::array<long long, 3>> ours, theirs;
            const auto key = [](const krs::vec3d& p) {
                return std::array<long long, 3>{std::llround(p.x * 1e6), std::llround(p.y * 1e6), std::llround(p.z * 1e6)};
            };
            for (std::size_t part = 0; part < scene.parts.size(); ++part) {
                const auto& p = scene.parts[part];
                const std::uint32_t kernel = std::uint32_t(std::stoul(p.name.substr(7)));
                const krs::bounding_box b = std::visit([](const auto& k) { return k.bound_box(); }, s.kernels()[kernel]);
                const krs::vec3d c = (krs::vec3d(b.lo) + krs::vec3d(b.hi)) * 0.5;
                for (const auto& i : p.direct) ours.insert(key(apply(i, c)));
                for (const auto& i : p.reflected) ours.insert(key(apply(i, krs::vec3d{-c.x, c.y, c.z})));
            }
            for (const auto& in : e.instances) {
                const krs::bounding_box b = std::visit([](const auto& k) { return k.bound_box(); }, s.kernels()[in.kernel]);
                theirs.insert(key(in.to_world.apply((krs::vec3d(b.lo) + krs::vec3d(b.hi)) * 0.5)));
            }
            CHECK(ours == theirs);
        }

        if (levels != 3) continue;
        // The file, read back by tinygltf, in each way it is written (a node per instance, or
        // EXT_mesh_gpu_instancing; y-up, or z-up under a root node): every placed instance's
        // kernel centre, taken through its nodes' transforms (and the extension's), lands within
        // 1e-4 of the expansion's, and the file holds as many instances as placed_instance_count.
        std::vector<krs::vec3d> expected_centres;
        for (const auto& in : e.instances) {
            const krs::bounding_box b = std::visit([](const auto& k) { return k.bound_box(); }, s.kernels()[in.kernel]);
            expected_centres.push_back(in.to_world.apply((krs::vec3d(b.lo) + krs::vec3d(b.hi)) * 0.5));
        }
        for (const bool gpu : {false, true})
            for (const krs::up_axis up : {krs::up_axis::y, krs::up_axis::z}) {
                CAPTURE(gpu);
                CAPTURE(krs::up_axis_name(up));
                const auto file = temp_path(gpu ? "instances_gpu.gltf" : "instances.gltf");
                krs::gltf_instance_options go;
                go.gpu_instancing = gpu;
                go.up = up;
                krs::save_gltf_instances(scene, file, false, go);
                tinygltf::Model model;
                tinygltf::TinyGLTF loader;
                std::string err, warn;
                REQUIRE(loader.LoadASCIIFromFile(&model, &err, &warn, file.string()));
                if (gpu) {
                    CHECK(model.extensionsUsed == std::vector<std::string>{"EXT_mesh_gpu_instancing"});
                    CHECK(model.extensionsRequired == std::vector<std::string>{"EXT_mesh_gpu_instancing"});
                } else {
                    CHECK(model.extensionsUsed.empty());
                    CHECK(model.extensionsRequired.empty());
                }
                std::vector<krs::vec3d> centres;
                for (const placed_mesh& placed : placed_meshes(model)) {
                    const std::string& name = model.meshes.at(std::size_t(placed.mesh)).name;
                    const bool mirrored = name.find("(mirrored)") != std::string::npos;
                    const std::uint32_t kernel = std::uint32_t(std::stoul(name.substr(7)));
                    const krs::bounding_box b = std::visit([](const auto& k) { return k.bound_box(); }, s.kernels()[kernel]);
                    krs::vec3d c = (krs::vec3d(b.lo) + krs::vec3d(b.hi)) * 0.5;
                    if (mirrored) c.x = -c.x;
                    centres.push_back(placed.to_world.apply(krs::to_file(up, c))); // the mesh's coordinates are in the file's frame
                }
                CHECK(centres.size() == scene.placed_instance_count());
                CHECK(centres.size() == expected_centres.size());
                CHECK(unmatched_points(centres, expected_centres, 1e-4) == 0);
                check_with_validator(file);
                std::filesystem::remove(file);
            }
    }
    // rotation_quaternion on rotations about many axes by many angles (every branch: the trace
    // positive, and each diagonal entry the largest): the quaternion's matrix is the rotation.
    std::size_t bad_rotations = 0;
    for (int axis = 0; axis < 12; ++axis)
        for (int step = 0; step < 12; ++step) {
            krs::vec3d u{std::cos(axis * 1.3), std::sin(axis * 0.7), std::cos(axis * 2.1) * 0.8};
            u = u / krs::length(u);
            const double a = 0.26 * step + 0.05, c = std::cos(a), sn = std::sin(a), C = 1 - c;
            const std::array<double, 9> r{c + u.x * u.x * C,        u.x * u.y * C - u.z * sn, u.x * u.z * C + u.y * sn,
                                          u.y * u.x * C + u.z * sn, c + u.y * u.y * C,        u.y * u.z * C - u.x * sn,
                                          u.z * u.x * C - u.y * sn, u.z * u.y * C + u.x * sn, c + u.z * u.z * C};
            const auto q = krs::rotation_quaternion(r);
            const double x = q[0], y = q[1], z = q[2], w = q[3];
            const double m[9] = {1 - 2 * (y * y + z * z), 2 * (x * y - z * w), 2 * (x * z + y * w), 2 * (x * y + z * w), 1 - 2 * (x * x + z * z),
                                 2 * (y * z - x * w),     2 * (x * z - y * w), 2 * (y * z + x * w), 1 - 2 * (x * x + y * y)};
            for (int i = 0; i < 9; ++i) bad_rotations += std::abs(m[i] - r[std::size_t(i)]) > 1e-12;
        }
    CHECK(bad_rotations == 0);
    // Budgets and levels refused by name, before any meshing.
    krs::instance_options o;
    o.instance_levels = 4;
    CHECK_THROWS_WITH_AS((void)krs::instance_meshes(s, o), doctest::Contains("instance_options.instance_levels"), krs::invalid_parameter);
    o.instance_levels = 3;
    o.max_instances = 11;
    CHECK_THROWS_WITH_AS((void)krs::instance_meshes(s, o), doctest::Contains("instance_options.max_instances: exceeded: 12 instances"),
                         krs::invalid_parameter);
}

TEST_CASE("instanced glTF: unbounded kernels (planes) are meshed within the scene's box, on the expansion's surface")
{
    // A tilted plane at level 0 (folded into a valley by the mirror above it), a sphere at level 1,
    // a ground plane at the top: the tree's ground and the rock's facets in small.
    using plane_scene = krs::sequence<krs::sphere, krs::plane>;
    plane_scene::builder b;
    b.kernel(krs::plane({0.3f, 1.0f, 0.1f}, -0.3f));
    b.mirror(krs::mirror({-1, 0, 0}, 0.0f));
    b.kernel(krs::sphere({0.5f, 0.2f, 0.3f}, 0.3f));
    b.mirror(krs::mirror::through({0, 0, 0}, {-0.2f, 0.1f, -1.0f}));
    b.kernel(krs::plane({0, 1, 0}, -0.6f));
    const plane_scene s = b.build();
    REQUIRE_FALSE(s.bound_box().is_bounded());
    const auto e = krs::expand(s);
    const krs::bounding_box box{{-1.5f, -1.0f, -1.2f}, {1.5f, 1.0f, 1.2f}};
    for (std::size_t levels : {std::size_t(2), std::size_t(1), std::size_t(0)}) {
        CAPTURE(levels);
        krs::instance_options o;
        o.instance_levels = levels;
        o.mesh.resolution = 40;
        o.mesh.box = box;
        const krs::instanced_scene scene = krs::instance_meshes(s, o);
        const double cell = 3.0 / 40.0;
        double worst = -1e300;
        std::size_t vertices = 0;
        // The world box of the vertices lying on the ground plane (y = -0.6) and inside B: the
        // ground's mesh covers B's extent in x and z (to a cell).
        krs::vec3d ground_lo{1e300, 1e300, 1e300}, ground_hi{-1e300, -1e300, -1e300};
        for (const auto& p : scene.parts)
            for (const auto& [mesh, instances] : {std::pair{&p.mesh, &p.direct}, std::pair{&p.mirrored, &p.reflected}})
                for (const auto& i : *instances)
                    for (const auto& v : mesh->positions) {
                        const krs::vec3d w = apply(i, krs::vec3d(v));
                        worst = std::max(worst, e.distance(w));
                        ++vertices;
                        if (std::abs(w.y + 0.6) < 1e-4 && w.x >= box.lo.x && w.x <= box.hi.x && w.z >= box.lo.z && w.z <= box.hi.z) {
                            ground_lo = {std::min(ground_lo.x, w.x), std::min(ground_lo.y, w.y), std::min(ground_lo.z, w.z)};
                            ground_hi = {std::max(ground_hi.x, w.x), std::max(ground_hi.y, w.y), std::max(ground_hi.z, w.z)};
                        }
                    }
        MESSAGE(scene.parts.size() << " parts, " << vertices << " instanced vertices, largest expansion distance " << worst / cell
                                   << " cells");
        CHECK(vertices > 1000);
        CHECK(worst <= 1e-4 * cell);
        CHECK(ground_lo.x <= box.lo.x + cell);
        CHECK(ground_hi.x >= box.hi.x - cell);
        CHECK(ground_lo.z <= box.lo.z + cell);
        CHECK(ground_hi.z >= box.hi.z - cell);
        const auto file = temp_path("plane_instances.glb");
        krs::save_gltf_instances(scene, file, true);
        check_with_validator(file);
        std::filesystem::remove(file);
    }
    // Without a box, a sequence holding a plane has none to mesh it in: refused by name.
    krs::instance_options no_box;
    no_box.instance_levels = 2;
    CHECK_THROWS_WITH_AS((void)krs::instance_meshes(s, no_box), doctest::Contains("instance_options.mesh.box"), krs::invalid_parameter);
    // A bounded<> wrapper's sphere gives the box.
    const krs::bounded<plane_scene> wrapped(s, krs::bounding_sphere{{0, 0, 0}, 1.4f}, 0.1f);
    krs::instance_options o;
    o.instance_levels = 2;
    o.mesh.resolution = 24;
    const krs::instanced_scene scene = krs::instance_meshes(wrapped, o);
    CHECK(scene.instance_count() == 4 + 2 + 1);
}

TEST_CASE("mesh attributes: each vertex's uv and colour are its kernel's, and PLY, OBJ and GLB read back by assimp give one colour within 1/255")
{
    const instanced_sequence s = make_instanced_sequence();
    krs::mesh_options o;
    o.resolution = 40;
    o.attributes = krs::mesh_attribute::uv | krs::mesh_attribute::kernel_color;
    const krs::triangle_mesh m = krs::extract_mesh(s, o);
    REQUIRE(m.uvs.size() == m.vertex_count());
    REQUIRE(m.colors.size() == m.vertex_count());
    // Independently, in double: Algorithm 1's walk written out (from the top mirror down, a point
    // on a mirror's positive side is reflected through it, by the reflection's isometry; the nearest
    // kernel over all levels, in the space of its level), and the kernel's own uv there. Vertices
    // within 1e-6 of a mirror or with two kernels within 1e-5 of each other (a crease) may go either
    // way and are skipped.
    const std::size_t n = s.mirror_count();
    std::size_t checked = 0, bad_uv = 0, bad_color = 0;
    double worst_uv = 0;
    for (std::size_t v = 0; v < m.vertex_count(); ++v) {
        krs::vec3d q(m.positions[v]);
        double best = 1e300, second = 1e300, nearest_mirror = 1e300;
        std::uint32_t nearest = 0;
        krs::vec3d nearest_point{};
        for (std::size_t level = n + 1; level-- > 0;) {
            if (level < n) {
                const auto& mi = s.mirrors()[level];
                const double side = krs::dot(krs::vec3d(mi.normal), q) - double(mi.offset);
                nearest_mirror = std::min(nearest_mirror, std::abs(side));
                if (side > 0) q = krs::isometry::reflection(mi).apply(q);
            }
            for (std::uint32_t k = s.level_begin(level); k < s.level_begin(level + 1); ++k) {
                const double d = std::visit([&](const auto& kern) { return double(kern.distance(q)); }, s.kernels()[k]);
                if (d < best) second = best, best = d, nearest = k, nearest_point = q;
                else if (d < second) second = d;
            }
        }
        if (nearest_mirror < 1e-6 || second - best < 1e-5) continue;
        const krs::vec3d q0 = nearest_point;
        ++checked;
        const auto [u, w] = std::visit(
            [&](const auto& k) -> std::array<double, 2> {
                if constexpr (requires { k.uv(q0); }) {
                    const auto t = k.uv(q0);
                    return {double(t.u), double(t.v)};
                } else {
                    return {0.0, 0.0};
                }
            },
            s.kernels()[nearest]);
        const double du = std::abs(u - m.uvs[v][0]), dv0 = std::abs(w - m.uvs[v][1]), dv = std::min(dv0, 1 - dv0); // v wraps
        worst_uv = std::max({worst_uv, du, dv});
        bad_uv += du > 1e-4 || dv > 1e-4;
        const krs::vec3f c = krs::kernel_color(nearest);
        bad_color += m.colors[v].x != c.x || m.colors[v].y != c.y || m.colors[v].z != c.z;
    }
    MESSAGE(checked << " of " << m.vertex_count() << " vertices checked; largest uv difference " << worst_uv);
    CHECK(checked > m.vertex_count() * 9 / 10);
    CHECK(bad_uv == 0);
    CHECK(bad_color == 0);
    // Both kernels' colours appear (the sphere's uv is (0, 0): it has none).
    CHECK(std::count_if(m.colors.begin(), m.colors.end(), [&](const krs::vec3f& c) { return c.x == krs::kernel_color(0).x; }) > 0);
    CHECK(std::count_if(m.colors.begin(), m.colors.end(), [&](const krs::vec3f& c) { return c.x == krs::kernel_color(1).x; }) > 0);

    // glTF: tinygltf reads TEXCOORD_0 and COLOR_0 back exactly; the validator accepts the file.
    for (const bool binary : {true, false}) {
        const auto file = temp_path(binary ? "attributes.glb" : "attributes.gltf");
        if (binary) krs::save_glb(m, file);
        else krs::save_gltf(m, file);
        tinygltf::Model model;
        tinygltf::TinyGLTF loader;
        std::string err, warn;
        REQUIRE((binary ? loader.LoadBinaryFromFile(&model, &err, &warn, file.string())
                        : loader.LoadASCIIFromFile(&model, &err, &warn, file.string())));
        const tinygltf::Primitive& prim = model.meshes.at(0).primitives.at(0);
        const int uv_accessor = prim.attributes.at("TEXCOORD_0"), color_accessor = prim.attributes.at("COLOR_0");
        CHECK(model.accessors.at(std::size_t(uv_accessor)).type == TINYGLTF_TYPE_VEC2);
        const auto uvs = accessor_values<float>(model, uv_accessor);
        const auto colors = accessor_values<float>(model, color_accessor);
        REQUIRE(uvs.size() == 2 * m.vertex_count());
        REQUIRE(colors.size() == 3 * m.vertex_count());
        std::size_t bad = 0;
        for (std::size_t v = 0; v < m.vertex_count(); ++v) {
            bad += uvs[2 * v] != m.uvs[v][0] || uvs[2 * v + 1] != m.uvs[v][1];
            bad += colors[3 * v] != m.colors[v].x || colors[3 * v + 1] != m.colors[v].y || colors[3 * v + 2] != m.colors[v].z;
        }
        CHECK(bad == 0);
        check_with_validator(file);
        std::filesystem::remove(file);
    }
    // PLY and OBJ: assimp reads one texture-coordinate channel and one colour channel from each.
    const auto ply = temp_path("attributes.ply"), obj = temp_path("attributes.obj");
    krs::save_ply(m, ply);
    krs::save_obj(m, obj);
    {
        // The OBJ's "vt" lines are the uvs, to 9 significant digits: read back as the same floats.
        std::ifstream in(obj);
        std::string word;
        std::size_t read = 0, bad = 0;
        while (in >> word)
            if (word == "vt") {
                float a = 0, b = 0;
                in >> a >> b;
                bad += read >= m.vertex_count() || a != m.uvs[read][0] || b != m.uvs[read][1];
                ++read;
            }
        CHECK(read == m.vertex_count());
        CHECK(bad == 0);
    }
#ifdef KRS_ASSIMP
    // assimp's own dump (its XML form) of each file, the GLB too: a texture-coordinate set and a
    // colour set with one entry per vertex it made, each that of the mesh's vertex it came from (the
    // PLY's and GLB's in the file's order; the OBJ's unrolled face by face, corner by corner).
    // assimp passes colours through as the file holds them, so each is put in one space by its
    // format's rule: PLY's bytes and OBJ's floats are sRGB-encoded (what Blender decodes them as),
    // glTF's COLOR_0 linear (its specification), encoded here. The same vertex must then agree
    // across the three within 1/255 in sRGB (a byte's step, where a viewer's eye resolves colour),
    // and each must be the mesh's linear colour encoded (the PLY's to its byte rounding).
    const auto glb = temp_path("attributes_assimp.glb");
    krs::save_glb(m, glb);
    check_with_validator(glb);
    std::vector<std::vector<krs::vec3d>> encoded; // per file, per mesh vertex: its sRGB-encoded colour
    for (const auto& file : {ply, obj, glb}) {
        CAPTURE(file.string());
        const bool is_obj = file.extension() == ".obj", is_gltf = file.extension() == ".glb";
        const auto xml = temp_path("dump.xml");
        int status = 0;
        const std::string log = run(std::string(KRS_ASSIMP) + " dump \"" + file.string() + "\" \"" + xml.string() + "\"", status);
        INFO(log);
        REQUIRE(status == 0);
        std::ifstream in(xml);
        const std::string text((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
        std::filesystem::remove(xml);
        const auto values = [&](const std::string& tag, std::size_t per) {
            const auto at = text.find("<" + tag + " num=\"");
            REQUIRE(at != std::string::npos);
            const std::size_t count = std::stoul(text.substr(at + tag.size() + 7));
            std::istringstream numbers(text.substr(text.find('>', at) + 1));
            std::vector<double> out(count * per);
            for (double& x : out) numbers >> x;
            return out;
        };
        const auto uv = values("TextureCoords", 2), rgba = values("Colors", 4);
        const std::size_t made = uv.size() / 2;
        REQUIRE(made == (is_obj ? 3 * m.triangle_count() : m.vertex_count()));
        REQUIRE(rgba.size() == 4 * made);
        std::vector<krs::vec3d> colour(m.vertex_count());
        std::size_t bad = 0;
        for (std::size_t i = 0; i < made; ++i) {
            const std::size_t v = is_obj ? m.triangles[i / 3][i % 3] : i;
            // assimp flips glTF's v (its origin is bottom-left, glTF's top-left).
            const double file_v = is_gltf ? 1 - uv[2 * i + 1] : uv[2 * i + 1];
            bad += std::abs(uv[2 * i] - m.uvs[v][0]) > 1e-6 || std::abs(file_v - m.uvs[v][1]) > 1e-6;
            krs::vec3d c{rgba[4 * i], rgba[4 * i + 1], rgba[4 * i + 2]};
            if (is_gltf) c = {krs::srgb_encode(c.x), krs::srgb_encode(c.y), krs::srgb_encode(c.z)};
            colour[v] = c;
            const double tolerance = file.extension() == ".ply" ? 0.5 / 255 + 1e-6 : 1e-6;
            const krs::vec3d want{krs::srgb_encode(m.colors[v].x), krs::srgb_encode(m.colors[v].y), krs::srgb_encode(m.colors[v].z)};
            bad += std::abs(c.x - want.x) > tolerance || std::abs(c.y - want.y) > tolerance || std::abs(c.z - want.z) > tolerance;
        }
        CHECK(bad == 0);
        encoded.push_back(std::move(colour));
    }
    std::filesystem::remove(glb);
    double worst = 0;
    for (std::size_t v = 0; v < m.vertex_count(); ++v)
        for (std::size_t f = 0; f < 3; ++f)
            for (std::size_t g = f + 1; g < 3; ++g) {
                const krs::vec3d d = encoded[f][v] - encoded[g][v];
                worst = std::max({worst, std::abs(d.x), std::abs(d.y), std::abs(d.z)});
            }
    MESSAGE("largest difference of one vertex's sRGB colour between PLY, OBJ and GLB: " << worst * 255 << " / 255");
    CHECK(worst <= 1.0 / 255);
#else
    FAIL("assimp was not found at configure time: the PLY, OBJ and GLB colours could not be read back (install assimp-utils)");
#endif
    std::filesystem::remove(ply);
    std::filesystem::remove(obj);
    // A field that cannot locate its kernels is refused by name.
    const krs::torus t({0, 0, 0}, {0, 0, 1}, 1.0f, 0.3f);
    CHECK_THROWS_WITH_AS((void)krs::extract_mesh(t, o), doctest::Contains("mesh_options.attributes"), krs::invalid_parameter);
    o.attributes = 4;
    CHECK_THROWS_WITH_AS((void)krs::extract_mesh(s, o), doctest::Contains("mesh_options.attributes"), krs::invalid_parameter);
}

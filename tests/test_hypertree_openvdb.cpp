// Hypertrees as OpenVDB and NanoVDB files (hypertree/io/openvdb.hpp, io/nanovdb.hpp), checked
// through the libraries' own readers rather than the library's loader: every voxel of the
// hypervolume read back from the .vdb by openvdb::io::File and from the .nvdb by nanovdb::io::readGrid
// equals the store's (density and level, empty where the store is empty), over every store kind
// and the four preset trees; world points map to the voxel `hypervolume::voxel_at` names, through
// the grids' own transforms; load_vdb into every kind gives the same voxels back (with parts) and
// the same hypervolume bit for bit; and bad input is refused by name with no file left behind.

#include "hypertree/build.hpp"
#include "hypertree/io/nanovdb.hpp"
#include "hypertree/io/openvdb.hpp"
#include "hypertree/presets.hpp"
#include "hypertree/store/store_kinds.hpp"

#include "support/random.hpp"

#include <doctest/doctest.h>

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <filesystem>
#include <fstream>
#include <iterator>
#include <random>
#include <stdexcept>
#include <string>
#include <vector>

namespace {

using namespace hypertree;

struct scratch_directory {
    std::filesystem::path path;
    scratch_directory()
    {
        path = std::filesystem::path(KRS_BINARY_DIR) / "test-vdb";
        std::random_device r;
        path /= std::to_string(r()) + std::to_string(r());
        std::filesystem::create_directories(path);
    }
    ~scratch_directory()
    {
        std::error_code ignored;
        std::filesystem::remove_all(path, ignored);
    }
};

// The four presets at a small resolution, generated once, with their parts (partitioned_store keeps them).
struct preset_tree {
    char letter;
    hypervolume volume;
    std::vector<stored_voxel> voxels;
};
const std::vector<preset_tree>& preset_trees()
{
    static const std::vector<preset_tree> trees = [] {
        std::vector<preset_tree> out;
        for (const char letter : {'A', 'B', 'C', 'D'}) {
            const int r = 44;
            ifs<> definition = letter == 'A' ? presets::tree_a(r) : letter == 'B' ? presets::tree_b(r) : letter == 'C' ? presets::tree_c(r) : presets::tree_d(r);
            definition.iterations = std::min<std::uint64_t>(definition.iterations, 20000);
            const auto tree = build_tree<partitioned_store>(definition, 5);
            out.push_back({letter, tree.volume(), stored_voxels(tree)});
        }
        return out;
    }();
    return trees;
}

std::array<int, 3> cell(const hypervolume& v, voxel_index i) { return v.coordinates(i); }

// The world-space test of the transform: random points of the box (away from cell faces, where
// rounding may pick either side) fall in the voxel hypervolume::voxel_at names, found through the
// grid's transform with OpenVDB's (or NanoVDB's) cell-centred rounding.
template <class WorldToIndex>
std::size_t misplaced_points(const hypervolume& volume, WorldToIndex&& to_index, std::uint64_t seed)
{
    std::mt19937_64 g(seed);
    const auto u = [&g] { return krs_test::uniform(g, 0, 1); };
    std::size_t wrong = 0;
    int tested = 0;
    while (tested < 2000) {
        const vec3d p{volume.origin().x + u() * volume.extent().x, volume.origin().y + u() * volume.extent().y,
                      volume.origin().z + u() * volume.extent().z};
        const vec3d f = volume.cell_coordinates(p);
        const double from_face = std::min({f.x - std::floor(f.x), std::ceil(f.x) - f.x, f.y - std::floor(f.y), std::ceil(f.y) - f.y,
                                           f.z - std::floor(f.z), std::ceil(f.z) - f.z});
        if (from_face < 1e-3) continue;
        ++tested;
        const auto expected = volume.coordinates(*volume.voxel_at(p));
        const std::array<double, 3> index = to_index(p);
        for (int a = 0; a < 3; ++a) wrong += int(std::floor(index[a] + 0.5)) != expected[a];
    }
    return wrong;
}

template <class S>
void check_same(const S& a, const voxel_store auto& b)
{
    REQUIRE(a.volume() == b.volume());
    REQUIRE(a.nonempty_count() == b.nonempty_count());
    std::size_t differing = 0;
    for (voxel_index i = 0; i < a.volume().voxel_count(); ++i) differing += !(a.at(i) == b.at(i));
    CHECK(differing == 0);
}

} // namespace

TEST_CASE_TEMPLATE_DEFINE("VDB files read by OpenVDB and NanoVDB hold every voxel of the store", S, vdb_every_voxel)
{
    openvdb::initialize();
    scratch_directory dir;
    for (const preset_tree& t : preset_trees()) {
        CAPTURE(t.letter);
        const S store = S::build(t.volume, t.voxels);
        REQUIRE(store.nonempty_count() > 500);
        REQUIRE(std::any_of(t.voxels.begin(), t.voxels.end(), [](const stored_voxel& v) { return v.part != 0; }));
        const hypervolume& volume = store.volume();
        const std::filesystem::path vdb = dir.path / "tree.vdb", nvdb = dir.path / "tree.nvdb";
        save_vdb(store, vdb);
        save_nvdb(store, nvdb);
        // No temporary file is left beside them.
        for (const auto& e : std::filesystem::directory_iterator(dir.path))
            CHECK(e.path().filename().string().find(".partial") == std::string::npos);

        // OpenVDB's reader, fresh from the file.
        openvdb::io::File file(vdb.string());
        file.open();
        const auto density = openvdb::gridPtrCast<openvdb::FloatGrid>(file.readGrid("density"));
        const auto level = openvdb::gridPtrCast<openvdb::Int32Grid>(file.readGrid("level"));
        file.close();
        REQUIRE(density);
        REQUIRE(level);
        CHECK(density->getGridClass() == openvdb::GRID_FOG_VOLUME);
        CHECK(std::size_t(density->activeVoxelCount()) == store.nonempty_count());
        CHECK(std::size_t(level->activeVoxelCount()) == store.nonempty_count());

        // NanoVDB's reader, fresh from the file.
        const auto nano_density_handle = nanovdb::io::readGrid(nvdb.string(), "density");
        const auto nano_level_handle = nanovdb::io::readGrid(nvdb.string(), "level");
        const nanovdb::FloatGrid* nano_density = nano_density_handle.grid<float>();
        const nanovdb::Int32Grid* nano_level = nano_level_handle.grid<std::int32_t>();
        REQUIRE(nano_density != nullptr);
        REQUIRE(nano_level != nullptr);
        CHECK(nano_density->activeVoxelCount() == store.nonempty_count());

        const auto d = density->getConstAccessor();
        const auto l = level->getConstAccessor();
        const auto nd = nano_density->getAccessor();
        const auto nl = nano_level->getAccessor();
        std::size_t wrong_density = 0, wrong_level = 0, wrong_active = 0, wrong_nano = 0;
        for (voxel_index i = 0; i < volume.voxel_count(); ++i) {
            const voxel v = store.at(i);
            const auto c = cell(volume, i);
            const openvdb::Coord ijk(c[0], c[1], c[2]);
            const nanovdb::Coord nijk(c[0], c[1], c[2]);
            // The density as a byte: exactly what was stored (k / 255 rounds back to k).
            wrong_density += std::lround(d.getValue(ijk) * 255.0f) != v.density;
            wrong_active += d.isValueOn(ijk) != (v.density > 0) || l.isValueOn(ijk) != (v.density > 0);
            wrong_level += v.density > 0 && l.getValue(ijk) != v.level;
            wrong_nano += std::lround(nd.getValue(nijk) * 255.0f) != v.density || nd.isActive(nijk) != (v.density > 0) ||
                          (v.density > 0 && nl.getValue(nijk) != v.level);
        }
        CHECK(wrong_density == 0);
        CHECK(wrong_active == 0);
        CHECK(wrong_level == 0);
        CHECK(wrong_nano == 0);

        // Voxel centres where the hypervolume has them, through each library's own transform.
        const openvdb::math::Transform& xf = density->transform();
        double worst_centre = 0;
        for (voxel_index i = 0; i < volume.voxel_count(); i += 97) {
            const auto c = cell(volume, i);
            const vec3d expected = volume.voxel_center(i);
            const openvdb::Vec3d got = xf.indexToWorld(openvdb::Coord(c[0], c[1], c[2]));
            const nanovdb::Vec3d nano = nano_density->indexToWorld(nanovdb::Vec3d(c[0], c[1], c[2]));
            const vec3d& s = volume.voxel_size();
            worst_centre = std::max({worst_centre, std::abs(got[0] - expected.x) / s.x, std::abs(got[1] - expected.y) / s.y,
                                     std::abs(got[2] - expected.z) / s.z, std::abs(nano[0] - expected.x) / s.x,
                                     std::abs(nano[1] - expected.y) / s.y, std::abs(nano[2] - expected.z) / s.z});
        }
        CHECK(worst_centre < 1e-9); // in voxel sides
        CHECK(misplaced_points(volume, [&](const vec3d& p) {
                  const openvdb::Vec3d q = xf.worldToIndex(openvdb::Vec3d(p.x, p.y, p.z));
                  return std::array<double, 3>{q[0], q[1], q[2]};
              }, 11) == 0);
        CHECK(misplaced_points(volume, [&](const vec3d& p) {
                  const nanovdb::Vec3d q = nano_density->worldToIndex(nanovdb::Vec3d(p.x, p.y, p.z));
                  return std::array<double, 3>{q[0], q[1], q[2]};
              }, 12) == 0);

        // The library's loader into every kind: the same voxels, parts and hypervolume.
        for_each_store_kind([&]<class T>() {
            CAPTURE(store_kind_name<T>);
            const T back = load_vdb<T>(vdb);
            check_same(store, back);
            CHECK(stored_voxels(back).size() == t.voxels.size());
            const auto list = stored_voxels(back);
            std::size_t wrong_part = 0;
            // Parts come back for the kind that keeps them (the list is the one the tree was built from).
            if constexpr (std::is_same_v<S, partitioned_store> && std::is_same_v<T, partitioned_store>)
                for (std::size_t k = 0; k < list.size(); ++k) wrong_part += list[k].part != t.voxels[k].part;
            CHECK(wrong_part == 0);
        });
    }
}
TEST_CASE_TEMPLATE_APPLY(vdb_every_voxel, hypertree::store_kinds);

TEST_CASE("VDB and NanoVDB written z-up: both readers put each voxel at its y-up centre turned to (x, -z, y), load_vdb turns it back")
{
    openvdb::initialize();
    scratch_directory dir;
    const preset_tree& t = preset_trees().front(); // preset A: a tree growing along +y
    const auto store = partitioned_store::build(t.volume, t.voxels);
    const hypervolume& volume = store.volume();
    const std::filesystem::path vdb = dir.path / "up_z.vdb", nvdb = dir.path / "up_z.nvdb";
    save_vdb(store, vdb, {}, krs::up_axis::z);
    save_nvdb(store, nvdb, {}, krs::up_axis::z);

    openvdb::io::File file(vdb.string());
    file.open();
    const auto density = openvdb::gridPtrCast<openvdb::FloatGrid>(file.readGrid("density"));
    file.close();
    REQUIRE(density);
    const auto nano_handle = nanovdb::io::readGrid(nvdb.string(), "density");
    const nanovdb::FloatGrid* nano = nano_handle.grid<float>();
    REQUIRE(nano != nullptr);
    // The voxels themselves are not moved: the same index coordinates hold the same densities.
    CHECK(std::size_t(density->activeVoxelCount()) == store.nonempty_count());
    CHECK(nano->activeVoxelCount() == store.nonempty_count());
    // The z-up turn written out by hand: the +90 degree rotation about x that sends +y to +z.
    const auto turned = [](const vec3d& p) { return vec3d{p.x, -p.z, p.y}; };
    const openvdb::math::Transform& xf = density->transform();
    const auto d = density->getConstAccessor();
    const auto nd = nano->getAccessor();
    const vec3d& s = volume.voxel_size();
    const double side = std::min({s.x, s.y, s.z});
    double worst_vdb = 0, worst_nano = 0;
    std::size_t checked = 0, wrong_value = 0;
    krs::vec3d lo{1e300, 1e300, 1e300}, hi{-1e300, -1e300, -1e300};
    double trunk_z = 0, all_z = 0;
    std::size_t trunk = 0;
    for (const stored_voxel& v : t.voxels) {
        const auto c = cell(volume, v.index);
        const vec3d want = turned(volume.voxel_center(v.index));
        const openvdb::Vec3d got = xf.indexToWorld(openvdb::Coord(c[0], c[1], c[2]));
        const nanovdb::Vec3d nano_got = nano->indexToWorld(nanovdb::Vec3d(c[0], c[1], c[2]));
        worst_vdb = std::max({worst_vdb, std::abs(got[0] - want.x), std::abs(got[1] - want.y),
                              std::abs(got[2] - want.z)});
        worst_nano = std::max({worst_nano, std::abs(nano_got[0] - want.x), std::abs(nano_got[1] - want.y),
                               std::abs(nano_got[2] - want.z)});
        // And back: the turned world point names the voxel that holds the stored density.
        const openvdb::Vec3d q = xf.worldToIndex(openvdb::Vec3d(want.x, want.y, want.z));
        const nanovdb::Vec3d nq = nano->worldToIndex(nanovdb::Vec3d(want.x, want.y, want.z));
        const openvdb::Coord ijk(int(std::floor(q[0] + 0.5)), int(std::floor(q[1] + 0.5)), int(std::floor(q[2] + 0.5)));
        const nanovdb::Coord nijk(int(std::floor(nq[0] + 0.5)), int(std::floor(nq[1] + 0.5)), int(std::floor(nq[2] + 0.5)));
        wrong_value += std::lround(d.getValue(ijk) * 255.0f) != v.value.density ||
                       std::lround(nd.getValue(nijk) * 255.0f) != v.value.density;
        lo = {std::min(lo.x, got[0]), std::min(lo.y, got[1]), std::min(lo.z, got[2])};
        hi = {std::max(hi.x, got[0]), std::max(hi.y, got[1]), std::max(hi.z, got[2])};
        all_z += got[2];
        if (v.value.level == 0) trunk_z += got[2], ++trunk;
        ++checked;
    }
    CHECK(checked == store.nonempty_count());
    CHECK(worst_vdb < 1e-6 * side); // a millionth of a voxel
    CHECK(worst_nano < 1e-6 * side);
    CHECK(wrong_value == 0);
    // The tree stands along +z: the active voxels' world box is longest in z, and the trunk (level 0)
    // lies at its bottom.
    const krs::vec3d extent = hi - lo;
    MESSAGE("z-up world box of the active voxels: " << extent.x << " x " << extent.y << " x " << extent.z);
    CHECK(extent.z > extent.x);
    CHECK(extent.z > extent.y);
    REQUIRE(trunk > 0);
    CHECK(trunk_z / double(trunk) < all_z / double(checked)); // not upside down

    // The library's loader finds the turn in the transform and gives the y-up store back.
    for_each_store_kind([&]<class T>() {
        CAPTURE(store_kind_name<T>);
        check_same(store, load_vdb<T>(vdb));
    });
    // A transform turned any other way names no hypervolume: refused, saying why.
    {
        auto grids = to_openvdb(store);
        grids.density->transform().postRotate(0.3, openvdb::math::Y_AXIS);
        const auto path = dir.path / "turned.vdb";
        openvdb::io::File(path.string()).write(openvdb::GridPtrVec{grids.density});
        try {
            (void)load_vdb<dense_store>(path);
            FAIL("a grid turned about y was read");
        } catch (const std::exception& e) {
            CHECK(std::string(e.what()).find("its transform rotates or shears the voxels") != std::string::npos);
        }
    }
}

TEST_CASE("load_vdb reads a grid written by another tool: the box of its active voxels under its transform")
{
    openvdb::initialize();
    scratch_directory dir;
    // Voxels at negative index coordinates, a non-cubic scale, no krs metadata, no level grid.
    auto grid = openvdb::FloatGrid::create(0.0f);
    grid->setName("density");
    grid->setTransform(openvdb::math::Transform::Ptr(new openvdb::math::Transform(
        openvdb::math::MapBase::Ptr(new openvdb::math::ScaleTranslateMap(openvdb::Vec3d(0.5, 0.25, 2), openvdb::Vec3d(1, -3, 10))))));
    auto a = grid->getAccessor();
    a.setValue(openvdb::Coord(-2, 5, 1), 1.0f);
    a.setValue(openvdb::Coord(1, 7, 1), 0.5f);
    a.setValue(openvdb::Coord(0, 6, 3), 0.001f); // rounds to density 0: left empty
    const std::filesystem::path path = dir.path / "foreign.vdb";
    openvdb::io::File(path.string()).write(openvdb::GridPtrVec{grid});

    const auto store = load_vdb<dense_store>(path);
    // Box of the active voxels: x -2..1, y 5..7, z 1..3: 4 x 3 x 3 voxels; its minimum corner is
    // the centre of (-2, 5, 1) minus half a voxel: (1 - 1 - 0.25, -3 + 1.25 - 0.125, 10 + 2 - 1).
    const hypervolume expected({-0.25, -1.875, 11}, {2, 0.75, 6}, {4, 3, 3});
    CHECK(store.volume() == expected);
    CHECK(store.nonempty_count() == 2);
    CHECK(store.at(expected.index(0, 0, 0)) == voxel{255, 0});
    CHECK(store.at(expected.index(3, 2, 0)) == voxel{128, 0}); // round(0.5 * 255)
}

TEST_CASE("VDB writers and reader refuse bad input by name and leave no file")
{
    openvdb::initialize();
    scratch_directory dir;
    const preset_tree& t = preset_trees().front();
    const auto store = bit_array_store::build(t.volume, t.voxels);
    const auto refusal = [](auto&& f) {
        try {
            f();
        } catch (const std::exception& e) {
            return std::string(e.what());
        }
        return std::string();
    };
    const auto no_file_in = [](const std::filesystem::path& d) { return std::filesystem::is_empty(d); };

    // An empty store.
    const auto empty = index_list_store::build(t.volume, {});
    CHECK(refusal([&] { save_vdb(empty, dir.path / "e.vdb"); }).find("save_vdb store") != std::string::npos);
    CHECK(refusal([&] { save_nvdb(empty, dir.path / "e.nvdb"); }).find("save_nvdb store") != std::string::npos);
    // Unwritable paths: a missing directory, a directory.
    const std::string missing = refusal([&] { save_vdb(store, dir.path / "no" / "such" / "t.vdb"); });
    CHECK(missing.find("save_vdb") != std::string::npos);
    CHECK(missing.find("t.vdb") != std::string::npos);
    CHECK(refusal([&] { save_nvdb(store, dir.path / "no" / "such" / "t.nvdb"); }).find("save_nvdb") != std::string::npos);
    CHECK(refusal([&] { save_vdb(store, dir.path); }).find("save_vdb path") != std::string::npos);
    CHECK(refusal([&] { save_vdb(store, ""); }).find("save_vdb path") != std::string::npos);
    CHECK(refusal([&] { save_nvdb(store, dir.path); }).find("save_nvdb path") != std::string::npos);
    // Bad names.
    vdb_grid_names same;
    same.level = "density";
    CHECK(refusal([&] { save_vdb(store, dir.path / "n.vdb", same); }).find("save_vdb names.") != std::string::npos);
    vdb_grid_names blank;
    blank.part = "";
    CHECK(refusal([&] { save_vdb(store, dir.path / "n.vdb", blank); }).find("save_vdb names.part") != std::string::npos);
    nvdb_grid_names control;
    control.density = "den\nsity";
    CHECK(refusal([&] { save_nvdb(store, dir.path / "n.nvdb", control); }).find("save_nvdb names.density") != std::string::npos);
    CHECK(no_file_in(dir.path));

    // The reader: a missing file, a file that is not OpenVDB, a missing grid, a wrong grid type.
    CHECK(refusal([&] { (void)load_vdb<dense_store>(dir.path / "none.vdb"); }).find("no such file") != std::string::npos);
    {
        std::ofstream(dir.path / "junk.vdb") << "not a vdb file";
    }
    CHECK(refusal([&] { (void)load_vdb<dense_store>(dir.path / "junk.vdb"); }).find("junk.vdb") != std::string::npos);
    save_vdb(store, dir.path / "t.vdb");
    vdb_grid_names other;
    other.density = "smoke";
    CHECK(refusal([&] { (void)load_vdb<dense_store>(dir.path / "t.vdb", other); }).find("no grid named \"smoke\"") != std::string::npos);
    vdb_grid_names swapped;
    swapped.density = "level", swapped.level = "density";
    CHECK(refusal([&] { (void)load_vdb<dense_store>(dir.path / "t.vdb", swapped); }).find("is not a FloatGrid") != std::string::npos);
    // A density outside [0, 1].
    {
        auto grid = openvdb::FloatGrid::create(0.0f);
        grid->setName("density");
        grid->getAccessor().setValue(openvdb::Coord(0, 0, 0), 3.0f);
        openvdb::io::File((dir.path / "hot.vdb").string()).write(openvdb::GridPtrVec{grid});
    }
    CHECK(refusal([&] { (void)load_vdb<dense_store>(dir.path / "hot.vdb"); }).find("outside [0, 1]") != std::string::npos);
    // A write that fails part way, over an existing good file, keeps the good file byte for byte and
    // leaves no temporary file (the writer writes, then throws, as a full disk would make it).
    const auto bytes_of = [](const std::filesystem::path& p) {
        std::ifstream in(p, std::ios::binary);
        return std::string(std::istreambuf_iterator<char>(in), {});
    };
    const auto files_named = [&](const std::string& stem) {
        std::size_t n = 0;
        for (const auto& e : std::filesystem::directory_iterator(dir.path)) n += e.path().filename().string().starts_with(stem);
        return n;
    };
    const std::string good = bytes_of(dir.path / "t.vdb");
    REQUIRE(good.size() > 100);
    const std::string failed = refusal([&] {
        detail::write_then_rename("save_vdb", dir.path / "t.vdb", [&](const std::filesystem::path& partial) {
            std::ofstream(partial, std::ios::binary) << good.substr(0, good.size() / 2);
            REQUIRE(std::filesystem::file_size(partial) == good.size() / 2);
            throw std::runtime_error("no space left on device");
        });
    });
    CHECK(failed.find("save_vdb") != std::string::npos);
    CHECK(failed.find("no space left on device") != std::string::npos);
    CHECK(bytes_of(dir.path / "t.vdb") == good);
    CHECK(files_named("t.vdb") == 1);

    // The grids of t.vdb, changed one way, written to another file.
    const auto edited = [&](const std::string& file, const auto& change) {
        openvdb::io::File in((dir.path / "t.vdb").string());
        in.open();
        const openvdb::GridPtrVecPtr grids = in.getGrids();
        in.close();
        for (const openvdb::GridBase::Ptr& g : *grids) change(*g);
        openvdb::io::File((dir.path / file).string()).write(*grids);
        return dir.path / file;
    };
    // A level or part grid placed by another transform than the density's is refused, by name.
    for (const char* moved : {"level", "part"}) {
        const auto path = edited(std::string(moved) + "_moved.vdb", [&](openvdb::GridBase& g) {
            if (g.getName() == moved) g.setTransform(openvdb::math::Transform::createLinearTransform(0.5));
        });
        CHECK(refusal([&] { (void)load_vdb<dense_store>(path); }).find("grid \"" + std::string(moved) + "\": its transform differs") !=
              std::string::npos);
    }
    // Active tiles in the density grid: one of 4096^3 voxels (far more than the hypervolume) whose
    // value rounds to an empty voxel is skipped without a walk; a non-empty one reaching outside
    // the hypervolume is refused as a tile.
    const auto faint = edited("faint_tile.vdb", [](openvdb::GridBase& g) {
        if (g.getName() == "density") static_cast<openvdb::FloatGrid&>(g).tree().addTile(3, openvdb::Coord(8192, 8192, 8192), 0.0001f, true);
    });
    const auto back = load_vdb<dense_store>(faint);
    CHECK(back.volume() == store.volume());
    CHECK(back.nonempty_count() == store.nonempty_count());
    const auto outside = edited("outside_tile.vdb", [](openvdb::GridBase& g) {
        if (g.getName() == "density") static_cast<openvdb::FloatGrid&>(g).tree().addTile(1, openvdb::Coord(-64, -64, -64), 1.0f, true);
    });
    CHECK(refusal([&] { (void)load_vdb<dense_store>(outside); }).find("an active tile up to (-57, -57, -57) reaches outside") !=
          std::string::npos);
}

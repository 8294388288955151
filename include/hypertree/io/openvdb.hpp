#pragma once
// Hypertrees as OpenVDB grids: what Houdini, Blender and OpenVDB's own tools read (issue 24).
//
// Needs OpenVDB (Debian's libopenvdb-dev): link the CMake target krs::hypertree_openvdb, which
// exists only where OpenVDB was found. krs::krs and krs::hypertree never include this header.
//
// A store becomes three grids over the same active voxels, one per non-empty voxel of the store
// (an empty voxel is inactive, the background):
//   "density"  FloatGrid, class fog volume: density / 255 in (0, 1], the fog-volume convention
//              Houdini's and Blender's volume shaders read;
//   "level"    Int32Grid: the voxel's depth level (0 = trunk); a second grid rather than per-voxel
//              metadata, because OpenVDB has no per-voxel metadata and both applications list a
//              second grid as one more attribute (Int32 is a grid type every reader registers,
//              where a byte grid is not);
//   "part"     Int32Grid: the first-level subpart (stored_voxel::part), so a partitioned store
//              comes back with the same parts.
// The names are the defaults of `vdb_grid_names`.
//
// Transform. OpenVDB places voxel (i, j, k)'s centre at indexToWorld(i, j, k); the hypervolume
// places voxel (i, j, k)'s centre at origin + (i + 1/2, j + 1/2, k + 1/2) * voxel_size, its cell
// spanning [origin + ijk * size, origin + (ijk + 1) * size). So every grid's map is the
// ScaleTranslateMap with scale = voxel_size (per axis: the presets' voxels are not cubes) and
// translation = origin + voxel_size / 2, and index coordinates are the store's voxel coordinates.
// Written z-up (krs/io/up_axis.hpp: for Blender and Houdini, which read the transform as it is),
// the map is that followed by the rotation (x, y, z) -> (x, -z, y): an AffineMap whose linear
// part is the rotation times the scale. The voxels are the same; only where they land turns.
//
// Metadata. Every grid carries the hypervolume as given (doubles, so it comes back bit for bit,
// which the transform's rounded sums would not give): "krs_hypervolume_origin" and
// "krs_hypervolume_extent" (vec3d) and "krs_hypervolume_resolution" (vec3i), in the scene's y-up
// frame whichever the file's up axis. A grid without them (made by another tool) is read too: its
// hypervolume is the box of its active voxels under its transform. The reader takes a transform
// that is an axis-aligned scale and translation, possibly followed by the z-up rotation (found
// from the transform itself, so a z-up file comes back as the y-up store it was written from).
//
// Reading back: density values are turned into densities by round(value * 255), exact for what
// `save_vdb` wrote; a value outside [0, 1] or not finite is refused (rescale such a grid first),
// and a value below 0.5 / 255 rounds to an empty voxel. Files are written to a new
// "<path>.partial-<process>-<n>" and renamed, so a failed write never leaves a partial file under the name.

#include "hypertree/execution.hpp"
#include "hypertree/io/binary.hpp" // load_error, loaded_voxels
#include "hypertree/io/grid_files.hpp"
#include "hypertree/store/store.hpp"
#include "krs/io/up_axis.hpp"

#include <openvdb/openvdb.h>

#include <algorithm>
#include <array>
#include <cmath>
#include <cstdint>
#include <filesystem>
#include <optional>
#include <string>
#include <string_view>
#include <system_error>
#include <vector>

namespace hypertree {

// The grids' names in a file: non-empty printable ASCII of at most 255 characters, all different
// (the reader finds grids by name).
struct vdb_grid_names {
    std::string density = "density";
    std::string level = "level";
    std::string part = "part";
};

// The store as OpenVDB grids (in memory), as described above.
struct vdb_grids {
    openvdb::FloatGrid::Ptr density;
    openvdb::Int32Grid::Ptr level;
    openvdb::Int32Grid::Ptr part;
};

namespace vdb_metadata {
inline constexpr const char* origin = "krs_hypervolume_origin";
inline constexpr const char* extent = "krs_hypervolume_extent";
inline constexpr const char* resolution = "krs_hypervolume_resolution";
} // namespace vdb_metadata

namespace detail {

inline void require_vdb_names(std::string_view caller, const vdb_grid_names& names)
{
    require_grid_names(caller, {{"density", &names.density}, {"level", &names.level}, {"part", &names.part}});
}

// The map described above: voxel centres where the hypervolume has them, turned to the file's up
// axis. OpenVDB's matrices act on row vectors (world = [i j k 1] M), so M's upper 3x3 block is the
// transpose of (rotation * scale) and its last row the turned centre of voxel (0, 0, 0).
inline openvdb::math::Transform::Ptr vdb_transform(const hypervolume& volume, krs::up_axis up)
{
    const vec3d& s = volume.voxel_size();
    const vec3d& o = volume.origin();
    const vec3d centre_of_first{o.x + 0.5 * s.x, o.y + 0.5 * s.y, o.z + 0.5 * s.z};
    using openvdb::math::MapBase;
    using openvdb::math::Transform;
    if (up == krs::up_axis::y)
        return Transform::Ptr(new Transform(MapBase::Ptr(new openvdb::math::ScaleTranslateMap(
            openvdb::Vec3d(s.x, s.y, s.z), openvdb::Vec3d(centre_of_first.x, centre_of_first.y, centre_of_first.z)))));
    const std::array<double, 9> r = krs::up_rotation(up);
    const double scale[3] = {s.x, s.y, s.z};
    const vec3d t = krs::to_file(up, centre_of_first);
    openvdb::Mat4d m = openvdb::Mat4d::identity();
    for (int row = 0; row < 3; ++row)
        for (int column = 0; column < 3; ++column) m(column, row) = r[std::size_t(row * 3 + column)] * scale[column];
    m.setTranslation(openvdb::Vec3d(t.x, t.y, t.z));
    return Transform::Ptr(new Transform(MapBase::Ptr(new openvdb::math::AffineMap(m))));
}

inline void put_vdb_metadata(openvdb::GridBase& grid, const hypervolume& volume)
{
    const vec3d& o = volume.origin();
    const vec3d& e = volume.extent();
    const resolution r = volume.grid();
    grid.insertMeta(vdb_metadata::origin, openvdb::Vec3DMetadata(openvdb::Vec3d(o.x, o.y, o.z)));
    grid.insertMeta(vdb_metadata::extent, openvdb::Vec3DMetadata(openvdb::Vec3d(e.x, e.y, e.z)));
    grid.insertMeta(vdb_metadata::resolution, openvdb::Vec3IMetadata(openvdb::Vec3i(r.x, r.y, r.z)));
}

} // namespace detail

// The store's grids in memory, named and transformed as above (`up`: the file's up axis). An
// empty store gives empty grids.
template <voxel_store S>
vdb_grids to_openvdb(const S& store, const vdb_grid_names& names = {}, krs::up_axis up = krs::up_axis::y)
{
    detail::require_vdb_names("to_openvdb", names);
    openvdb::initialize(); // registers the grid and map types; idempotent
    const hypervolume& volume = store.volume();
    vdb_grids g;
    g.density = openvdb::FloatGrid::create(0.0f);
    g.level = openvdb::Int32Grid::create(0);
    g.part = openvdb::Int32Grid::create(0);
    const openvdb::math::Transform::Ptr transform = detail::vdb_transform(volume, up);
    {
        openvdb::FloatGrid::Accessor density = g.density->getAccessor();
        openvdb::Int32Grid::Accessor level = g.level->getAccessor(), part = g.part->getAccessor();
        detail::coordinate_walker coordinates(volume); // the visit is in increasing index order
        for_each_stored(store, [&](const stored_voxel& v) {
            const std::array<int, 3> c = coordinates(v.index);
            const openvdb::Coord ijk(c[0], c[1], c[2]);
            // setValue makes the voxel active, also where the value equals the background (level 0).
            density.setValue(ijk, float(v.value.density) / 255.0f);
            level.setValue(ijk, int(v.value.level));
            part.setValue(ijk, int(v.part));
        });
    }
    g.density->setName(names.density);
    g.density->setGridClass(openvdb::GRID_FOG_VOLUME);
    g.level->setName(names.level);
    g.part->setName(names.part);
    for (openvdb::GridBase* grid : {static_cast<openvdb::GridBase*>(g.density.get()), static_cast<openvdb::GridBase*>(g.level.get()),
                                    static_cast<openvdb::GridBase*>(g.part.get())}) {
        grid->setTransform(transform->copy());
        detail::put_vdb_metadata(*grid, volume);
    }
    return g;
}

namespace detail {

// openvdb::io::File::write opens its own std::ofstream and never looks at it again, so a full
// disk leaves a truncated .vdb it reports as written. Its base, io::Archive, writes the same file
// (header, grid offsets, grids: `seekable`, as File does) to a stream given to it; this exposes
// that, so the stream is krs::write_file's, whose every write is checked.
struct vdb_file_writer : openvdb::io::Archive {
    void write_to(std::ostream& out, const openvdb::GridCPtrVec& grids) const { Archive::write(out, grids, /*seekable=*/true); }
};

} // namespace detail

// Writes the store's three grids to an OpenVDB file (.vdb), with the up axis `up` (y: the
// scene's own frame). Refuses an empty store, an empty path or a directory, and bad names
// (invalid_parameter); a failed write is a save_error naming the path, and leaves no file behind.
template <voxel_store S>
void save_vdb(const S& store, const std::filesystem::path& path, const vdb_grid_names& names = {},
              krs::up_axis up = krs::up_axis::y)
{
    detail::require_vdb_names("save_vdb", names);
    detail::require_output_path("save_vdb", path);
    if (store.nonempty_count() == 0)
        throw invalid_parameter("save_vdb store", "must hold at least one non-empty voxel (an empty tree has no grid to write)",
                                "0 voxels");
    const vdb_grids g = to_openvdb(store, names, up);
    krs::write_file("save_vdb", path, [&](std::ostream& out) { detail::vdb_file_writer().write_to(out, {g.density, g.level, g.part}); });
}

namespace detail {

// The hypervolume of a grid read back: from its metadata, checked against its transform, or
// (a foreign grid) from its transform and the box of its active voxels. `offset` is what to
// subtract from index coordinates to get voxel coordinates.
struct vdb_volume {
    hypervolume volume;
    openvdb::Coord offset{0, 0, 0};
};

inline vdb_volume volume_of(const openvdb::GridBase& grid, std::string_view file)
{
    const auto fail = [&](const std::string& message) { return load_error(file, std::nullopt, "grid \"" + grid.getName() + "\": " + message); };
    const openvdb::math::Transform& xf = grid.transform();
    if (!xf.isLinear()) throw fail("its transform is not linear (frustum maps name no box of voxels)");
    // World points of the file taken back to the scene's frame under the file's up axis.
    const auto scene_point = [&](krs::up_axis up, const openvdb::Vec3d& index) {
        const openvdb::Vec3d w = xf.indexToWorld(index);
        const vec3d p = krs::from_file(up, vec3d{w[0], w[1], w[2]});
        return openvdb::Vec3d(p.x, p.y, p.z);
    };
    // The Jacobian's columns in the scene's frame: an axis-aligned scale has no off-diagonal entry.
    // The up axis is the one under which that holds (a y-up map is never aligned read as z-up).
    const auto columns = [&](krs::up_axis up) {
        std::array<openvdb::Vec3d, 3> c;
        for (int a = 0; a < 3; ++a) {
            openvdb::Vec3d unit(0, 0, 0);
            unit[a] = 1;
            c[std::size_t(a)] = scene_point(up, unit) - scene_point(up, openvdb::Vec3d(0, 0, 0));
        }
        return c;
    };
    const auto aligned = [](const std::array<openvdb::Vec3d, 3>& c) {
        for (int a = 0; a < 3; ++a)
            for (int b = 0; b < 3; ++b)
                if (b != a && !(std::abs(c[std::size_t(a)][b]) <= 1e-12 * std::abs(c[std::size_t(a)][a]))) return false;
        return true;
    };
    krs::up_axis up = krs::up_axis::y;
    if (!aligned(columns(up))) up = krs::up_axis::z;
    const std::array<openvdb::Vec3d, 3> column = columns(up);
    if (!aligned(column))
        throw fail("its transform rotates or shears the voxels (only an axis-aligned scale and translation, "
                   "or that turned z-up as save_vdb writes it, map to a hypervolume)");
    const openvdb::Vec3d centre0 = scene_point(up, openvdb::Vec3d(0, 0, 0));
    openvdb::Vec3d scale;
    for (int a = 0; a < 3; ++a) {
        if (!(column[std::size_t(a)][a] > 0)) throw fail("its transform's scale must be positive on every axis");
        scale[a] = column[std::size_t(a)][a];
    }
    vdb_volume out;
    const auto origin_meta = grid.getMetadata<openvdb::Vec3DMetadata>(vdb_metadata::origin);
    const auto extent_meta = grid.getMetadata<openvdb::Vec3DMetadata>(vdb_metadata::extent);
    const auto res_meta = grid.getMetadata<openvdb::Vec3IMetadata>(vdb_metadata::resolution);
    try {
        if (origin_meta && extent_meta && res_meta) {
            const openvdb::Vec3d o = origin_meta->value(), e = extent_meta->value();
            const openvdb::Vec3i r = res_meta->value();
            out.volume = hypervolume({o[0], o[1], o[2]}, {e[0], e[1], e[2]}, resolution{r[0], r[1], r[2]});
            // The transform must put voxel centres where this hypervolume does (to a thousandth of
            // a voxel: the sums round differently), or the file was edited inconsistently.
            const vec3d& s = out.volume.voxel_size();
            const double expected[3] = {o[0] + 0.5 * s.x, o[1] + 0.5 * s.y, o[2] + 0.5 * s.z};
            const double sides[3] = {s.x, s.y, s.z};
            for (int a = 0; a < 3; ++a)
                if (!(std::abs(centre0[a] - expected[a]) <= 1e-3 * sides[a] && std::abs(scale[a] - sides[a]) <= 1e-6 * sides[a]))
                    throw fail("its transform does not place voxel centres where its krs_hypervolume metadata does");
        } else if (origin_meta || extent_meta || res_meta) {
            throw fail("it has only part of the krs_hypervolume metadata (origin, extent and resolution go together)");
        } else {
            const openvdb::CoordBBox box = grid.evalActiveVoxelBoundingBox();
            if (box.empty()) throw fail("it has no active voxel, so it names no hypervolume");
            const openvdb::Coord dim = box.dim();
            const openvdb::Vec3d low = scene_point(up, box.min().asVec3d()) - 0.5 * scale;
            out.volume = hypervolume({low[0], low[1], low[2]}, {dim[0] * scale[0], dim[1] * scale[1], dim[2] * scale[2]},
                                     resolution{dim[0], dim[1], dim[2]});
            out.offset = box.min();
        }
    } catch (const invalid_parameter& e) {
        throw fail(std::string("its box is not a valid hypervolume: ") + e.what());
    }
    return out;
}

template <class Grid>
typename Grid::Ptr optional_grid(openvdb::io::File& file, const std::string& name, std::string_view path, const char* type)
{
    if (!file.hasGrid(name)) return nullptr;
    typename Grid::Ptr grid = openvdb::gridPtrCast<Grid>(file.readGrid(name));
    if (!grid) throw load_error(path, std::nullopt, "grid \"" + name + "\" is not " + type);
    return grid;
}

} // namespace detail

// The checked hypervolume and voxel list of an OpenVDB file: the density grid is required, the
// level and part grids are read when present (0 where absent). Every problem is a load_error
// naming the file and the grid.
inline loaded_voxels load_vdb_voxels(const std::filesystem::path& path, const vdb_grid_names& names = {})
{
    detail::require_vdb_names("load_vdb", names);
    openvdb::initialize();
    const std::string name = path.string();
    std::error_code ec;
    if (!std::filesystem::exists(path, ec)) throw load_error(name, std::nullopt, "cannot open: no such file");
    openvdb::FloatGrid::Ptr density;
    openvdb::Int32Grid::Ptr level, part;
    try {
        openvdb::io::File file(name);
        file.open();
        if (!file.hasGrid(names.density))
            throw load_error(name, std::nullopt, "no grid named \"" + names.density + "\" (the density grid)");
        density = detail::optional_grid<openvdb::FloatGrid>(file, names.density, name, "a FloatGrid");
        level = detail::optional_grid<openvdb::Int32Grid>(file, names.level, name, "an Int32Grid");
        part = detail::optional_grid<openvdb::Int32Grid>(file, names.part, name, "an Int32Grid");
        file.close();
    } catch (const openvdb::Exception& e) {
        throw load_error(name, std::nullopt, std::string("not a readable OpenVDB file: ") + e.what());
    }
    const detail::vdb_volume where = detail::volume_of(*density, name);
    // Level and part are read at the density's index coordinates: a grid placed by another
    // transform would give each voxel another voxel's level or part.
    for (const openvdb::GridBase* other : {static_cast<const openvdb::GridBase*>(level.get()), static_cast<const openvdb::GridBase*>(part.get())})
        if (other && other->transform() != density->transform())
            throw load_error(name, std::nullopt, "grid \"" + other->getName() + "\": its transform differs from the density grid \"" +
                                                     names.density + "\"'s (its values would land on other voxels)");
    loaded_voxels out;
    out.volume = where.volume;
    const resolution r = where.volume.grid();
    const auto fail = [&](const openvdb::Coord& c, const std::string& message) {
        return load_error(name, std::nullopt, "voxel (" + std::to_string(c[0]) + ", " + std::to_string(c[1]) + ", " + std::to_string(c[2]) + "): " + message);
    };
    std::optional<openvdb::Int32Grid::ConstAccessor> levels, parts;
    if (level) levels.emplace(level->getConstAccessor());
    if (part) parts.emplace(part->getConstAccessor());
    const auto small_integer = [&](std::optional<openvdb::Int32Grid::ConstAccessor>& a, const openvdb::Coord& c, const char* what) {
        if (!a) return std::uint8_t(0);
        const int v = a->getValue(c);
        if (v < 0 || v > 255) throw fail(c, std::string("its ") + what + " " + std::to_string(v) + " is outside [0, 255]");
        return std::uint8_t(v);
    };
    const auto density_byte = [&](const openvdb::Coord& ijk, float value) {
        if (!(std::isfinite(value) && value >= 0.0f && value <= 1.0f))
            throw fail(ijk, "density " + std::to_string(value) + " is outside [0, 1] (a fog volume's range; rescale the grid first)");
        return std::lround(double(value) * 255.0);
    };
    const auto add = [&](const openvdb::Coord& ijk, float value) {
        const long d = density_byte(ijk, value);
        if (d == 0) return;
        const openvdb::Coord c = ijk - where.offset;
        if (c[0] < 0 || c[1] < 0 || c[2] < 0 || c[0] >= r.x || c[1] >= r.y || c[2] >= r.z)
            throw fail(ijk, "lies outside the hypervolume's " + std::to_string(r.x) + " x " + std::to_string(r.y) + " x " + std::to_string(r.z) + " voxels");
        out.voxels.push_back({where.volume.index(c[0], c[1], c[2]), voxel{std::uint8_t(d), small_integer(levels, ijk, "level")},
                              small_integer(parts, ijk, "part")});
    };
    for (auto it = density->cbeginValueOn(); it; ++it) {
        if (it.isVoxelValue()) {
            add(it.getCoord(), *it);
        } else { // an active tile: every voxel under it (a foreign grid; save_vdb writes none)
            // Checked as a whole before any voxel is walked: a tile whose value rounds to an empty
            // voxel is skipped at once, and one that is walked lies inside the hypervolume (tiles
            // do not overlap, so all the walks together visit at most the hypervolume's voxels).
            const openvdb::CoordBBox tile = it.getBoundingBox();
            if (density_byte(tile.min(), *it) == 0) continue;
            const openvdb::Coord low = tile.min() - where.offset, high = tile.max() - where.offset;
            if (low[0] < 0 || low[1] < 0 || low[2] < 0 || high[0] >= r.x || high[1] >= r.y || high[2] >= r.z)
                throw fail(tile.min(), "an active tile up to (" + std::to_string(tile.max()[0]) + ", " + std::to_string(tile.max()[1]) + ", " +
                                           std::to_string(tile.max()[2]) + ") reaches outside the hypervolume's " + std::to_string(r.x) +
                                           " x " + std::to_string(r.y) + " x " + std::to_string(r.z) + " voxels");
            for (auto c = tile.begin(); c; ++c) add(*c, *it);
        }
    }
    std::sort(out.voxels.begin(), out.voxels.end(), [](const stored_voxel& a, const stored_voxel& b) { return a.index < b.index; });
    return out;
}

// Loads an OpenVDB file as a store of kind S (any kind, whichever kind wrote it).
template <voxel_store S>
S load_vdb(const std::filesystem::path& path, const vdb_grid_names& names = {}, memory_budget budget = {})
{
    return detail::build_loaded<S>(load_vdb_voxels(path, names), path.string(), budget);
}

} // namespace hypertree

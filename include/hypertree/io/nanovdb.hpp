#pragma once
// Hypertrees as NanoVDB grids: one flat buffer per grid that a GPU reads as is (issue 24).
//
// Needs only NanoVDB's headers (Debian's libnanovdb-dev, header-only; OpenVDB itself is not
// needed): the grids are built from the store by NanoVDB's own GridBuilder. The CMake target
// krs::hypertree_openvdb puts them on the include path where they were found.
//
// The grids hold what the OpenVDB grids of io/openvdb.hpp hold, under the same names and transform:
//   "density"  Float grid, class fog volume, density / 255 on the store's non-empty voxels;
//   "level"    Int32 grid, the voxel's depth level.
// (The part grid is left out: a GPU renderer has no use for it. io/openvdb.hpp keeps it.)
// Voxel (i, j, k) of the store is index coordinate (i, j, k), and the map sends it to its centre,
// origin + (ijk + 1/2) * voxel_size: a scale of voxel_size per axis and a translation of
// origin + voxel_size / 2 (hypertree/volume.hpp; io/openvdb.hpp says why). Written z-up
// (krs/io/up_axis.hpp), that map is followed by the rotation (x, y, z) -> (x, -z, y), as in the
// .vdb: the same voxels, turned where they land.
//
// A .nvdb file written by `save_nvdb` holds both grids uncompressed (codec NONE), so a reader can
// copy each grid's buffer to the GPU as it is (NanoVDB's own readGrid). It is written to
// a new "<path>.partial-<process>-<n>" and renamed (io/binary.hpp's write_then_rename).

#include "hypertree/io/grid_files.hpp"
#include "hypertree/store/store.hpp"
#include "krs/io/up_axis.hpp"

#include <nanovdb/NanoVDB.h>
#include <nanovdb/util/GridBuilder.h>
#include <nanovdb/util/GridHandle.h>
#include <nanovdb/util/IO.h>

#include <array>
#include <cstdint>
#include <filesystem>
#include <fstream>
#include <string>
#include <string_view>
#include <stdexcept>
#include <utility>
#include <vector>

namespace hypertree {

// The grids' names in memory and in a .nvdb file (non-empty printable ASCII, different; NanoVDB
// keeps at most 255 characters of a name in the grid itself).
struct nvdb_grid_names {
    std::string density = "density";
    std::string level = "level";
};

// The two grids, each in its own host buffer.
struct nanovdb_grids {
    nanovdb::GridHandle<nanovdb::HostBuffer> density;
    nanovdb::GridHandle<nanovdb::HostBuffer> level;
};

namespace detail {

inline void require_nvdb_names(std::string_view caller, const nvdb_grid_names& names)
{
    require_grid_names(caller, {{"density", &names.density}, {"level", &names.level}});
}

// The map of io/openvdb.hpp: index (i, j, k) to rotation (origin + (ijk + 1/2) * voxel_size).
// Map::set takes its matrices transposed (OpenVDB's row-vector convention): entry [j][i] is the
// world axis i's coefficient of index axis j, for the map (rotation * scale) and its inverse
// (scale^-1 * rotation^T).
inline nanovdb::Map nanovdb_map(const hypervolume& volume, krs::up_axis up)
{
    const vec3d& s = volume.voxel_size();
    const vec3d& o = volume.origin();
    const std::array<double, 9> r = krs::up_rotation(up);
    const double scale[3] = {s.x, s.y, s.z};
    double forward[3][3], inverse[3][3];
    for (int i = 0; i < 3; ++i)
        for (int j = 0; j < 3; ++j) {
            forward[j][i] = r[std::size_t(i * 3 + j)] * scale[j];
            inverse[j][i] = r[std::size_t(j * 3 + i)] / scale[i];
        }
    const vec3d t = krs::to_file(up, vec3d{o.x + 0.5 * s.x, o.y + 0.5 * s.y, o.z + 0.5 * s.z});
    nanovdb::Map map;
    map.set(forward, inverse, std::array<double, 3>{t.x, t.y, t.z}, 1.0);
    return map;
}

} // namespace detail

// The store as NanoVDB grids in memory, with the up axis `up`. An empty store gives grids without
// active voxels.
template <voxel_store S>
nanovdb_grids to_nanovdb(const S& store, const nvdb_grid_names& names = {}, krs::up_axis up = krs::up_axis::y)
{
    detail::require_nvdb_names("to_nanovdb", names);
    const hypervolume& volume = store.volume();
    nanovdb::GridBuilder<float> density(0.0f, nanovdb::GridClass::FogVolume);
    nanovdb::GridBuilder<std::int32_t> level(0);
    {
        auto d = density.getAccessor();
        auto l = level.getAccessor();
        detail::coordinate_walker coordinates(volume);
        for_each_stored(store, [&](const stored_voxel& v) {
            const std::array<int, 3> c = coordinates(v.index);
            const nanovdb::Coord ijk(c[0], c[1], c[2]);
            // setValue marks the voxel active whatever its value (level 0 is the background).
            d.setValue(ijk, float(v.value.density) / 255.0f);
            l.setValue(ijk, std::int32_t(v.value.level));
        });
    }
    const nanovdb::Map map = detail::nanovdb_map(volume, up);
    return {density.getHandle(map, names.density), level.getHandle(map, names.level)};
}

// Writes the store's density and level grids to a .nvdb file, uncompressed, with the up axis `up`
// (y: the scene's own frame). Refuses an empty store, an empty path or a directory, and bad names
// (invalid_parameter); a failed write is a save_error naming the path and leaves no file behind.
template <voxel_store S>
void save_nvdb(const S& store, const std::filesystem::path& path, const nvdb_grid_names& names = {},
               krs::up_axis up = krs::up_axis::y)
{
    detail::require_nvdb_names("save_nvdb", names);
    detail::require_output_path("save_nvdb", path);
    if (store.nonempty_count() == 0)
        throw invalid_parameter("save_nvdb store", "must hold at least one non-empty voxel (an empty tree has no grid to write)", "0 voxels");
    nanovdb_grids g = to_nanovdb(store, names, up);
    std::vector<nanovdb::GridHandle<nanovdb::HostBuffer>> handles;
    handles.push_back(std::move(g.density));
    handles.push_back(std::move(g.level));
    krs::write_file("save_nvdb", path, [&](std::ostream& out) { nanovdb::io::writeGrids(out, handles, nanovdb::io::Codec::NONE); });
}

} // namespace hypertree

// bench_vdb_export: a hypertree written and read as the project's binary format (io/binary.hpp),
// as OpenVDB grids (io/openvdb.hpp: density, level and part) and as NanoVDB grids (io/nanovdb.hpp:
// density and level), next to the stores' memory (issue 24, item 5). Built where the target
// krs::hypertree_openvdb exists.
//
//     bench_vdb_export [--csv FILE] [--resolution R] [--trees ABCD] [--rounds N] [--dir DIR] [--tbb-threads T]
//     (the CSV goes next to the executable, as <executable>.csv, unless --csv names one)
//
// For each preset tree (resolution R, default 300) and each store kind: the store's memory, then N
// rounds (default 5) that each write and read every format once, in turn, so that the machine's
// load of the moment falls on all formats alike; a format's time is its best round. Write times
// include building the grids from the store (to_openvdb / to_nanovdb) and the rename; read times
// go from the file to a store of the same kind (NanoVDB: nanovdb::io::readGrid of both grids, as a
// GPU program would; the library does not build stores from .nvdb). The error column is the number
// of voxels (density or level) that differ between the store and what was read back: 0 is the
// only right answer. File sizes are bytes on disk. The load average before and after is printed.
// OpenVDB reads and writes with TBB tasks; on a loaded machine their wall time swings with the
// other processes, so the CPU time of the process (all threads, std::clock) is printed beside it,
// and --tbb-threads limits TBB's threads (default: TBB's own choice).

#include "support/text.hpp"
#include "support/timing.hpp"
#include "hypertree/build.hpp"
#include "hypertree/io/binary.hpp"
#include "hypertree/io/nanovdb.hpp"
#include "hypertree/io/openvdb.hpp"
#include "hypertree/presets.hpp"
#include "hypertree/store/store_kinds.hpp"

#include <tbb/global_control.h>

#include <algorithm>
#include <chrono>
#include <ctime>
#include <memory>
#include <cerrno>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <string>
#include <vector>

namespace {

using namespace hypertree;
using clock_type = std::chrono::steady_clock;

// Wall and process CPU seconds of f().
struct timing {
    double wall = 1e300, cpu = 1e300;
    void keep_best(const timing& t) { wall = std::min(wall, t.wall), cpu = std::min(cpu, t.cpu); }
};
template <class F>
timing seconds(F&& f)
{
    const auto t0 = clock_type::now();
    const std::clock_t c0 = std::clock();
    f();
    return {std::chrono::duration<double>(clock_type::now() - t0).count(), double(std::clock() - c0) / CLOCKS_PER_SEC};
}

struct row {
    std::string tree, store, format;
    int resolution = 0;
    std::size_t nonempty = 0, memory = 0, file_bytes = 0, differing = 0;
    timing write, read;
};

template <class S, class T>
std::size_t differing_voxels(const S& a, const T& b)
{
    std::size_t n = a.nonempty_count() == b.nonempty_count() ? 0 : 1;
    for (voxel_index i = 0; i < a.volume().voxel_count(); ++i) n += !(a.at(i) == b.at(i));
    return n;
}

} // namespace

int main(int argc, char** argv)
{
    std::string csv_path, trees = "ABCD";
    std::filesystem::path dir = std::filesystem::temp_directory_path() / "krs_bench_vdb";
    int res = 300, rounds = 5, tbb_threads = 0;
    for (int i = 1; i < argc; ++i) {
        const std::string a = argv[i];
        if (i + 1 >= argc) {
            std::fprintf(stderr, "usage: %s [--csv FILE] [--resolution R] [--trees ABCD] [--rounds N] [--dir DIR] [--tbb-threads T]\n", argv[0]);
            return 2;
        }
        const std::string v = argv[++i];
        // A whole number in [least, most], or a refusal naming the option (never a default in its place).
        bool refused = false;
        const auto whole = [&](long least, long most) {
            char* end = nullptr;
            errno = 0;
            const long n = std::strtol(v.c_str(), &end, 10);
            if (v.empty() || *end != '\0' || errno != 0 || n < least || n > most) {
                std::fprintf(stderr, "%s must be a whole number from %ld to %ld (got '%s')\n", a.c_str(), least, most, v.c_str());
                refused = true;
            }
            return int(n);
        };
        if (a == "--csv") csv_path = v;
        else if (a == "--resolution") res = whole(8, 1625); // 1625^3 < 2^32: the largest grid of 32-bit voxel indices
        else if (a == "--trees") {
            trees = v;
            if (v.empty() || v.find_first_not_of("ABCD") != std::string::npos) {
                std::fprintf(stderr, "--trees must be letters of ABCD (got '%s')\n", v.c_str());
                refused = true;
            }
        } else if (a == "--rounds") rounds = whole(1, 1000);
        else if (a == "--dir") dir = v;
        else if (a == "--tbb-threads") tbb_threads = whole(1, 1024);
        else {
            std::fprintf(stderr, "unknown option %s\n", a.c_str());
            return 2;
        }
        if (refused) return 2;
    }
    std::filesystem::create_directories(dir);
    std::unique_ptr<tbb::global_control> tbb_limit;
    if (tbb_threads > 0) tbb_limit = std::make_unique<tbb::global_control>(tbb::global_control::max_allowed_parallelism, std::size_t(tbb_threads));
    openvdb::initialize();
    std::printf("VDB export (OpenVDB %s): resolution %d, best of %d alternating rounds, TBB threads %s; files in %s\n",
                openvdb::getLibraryAbiVersionString(), res, rounds, tbb_threads > 0 ? std::to_string(tbb_threads).c_str() : "default",
                dir.string().c_str());
    std::printf("load average before: %s\n\n", bench::load_average().c_str());
    std::printf("%-4s %-12s %9s %10s | %-7s %11s %9s %9s %9s %9s %8s\n", "tree", "store", "voxels", "memory", "format", "file", "write",
                "(cpu)", "read", "(cpu)", "differ");

    std::vector<row> rows;
    for (const char letter : trees) {
        ifs<> (*maker)(int) = letter == 'A' ? presets::tree_a : letter == 'B' ? presets::tree_b : letter == 'C' ? presets::tree_c
                              : letter == 'D' ? presets::tree_d : nullptr;
        if (!maker) continue;
        const ifs<> definition = maker(res);
        const auto generated = build_tree<partitioned_store>(definition, 1);
        const std::vector<stored_voxel> voxels = stored_voxels(generated);
        for_each_store_kind([&]<class S>() {
            const S store = S::build(generated.volume(), voxels);
            const std::filesystem::path binary = dir / "tree.htree", vdb = dir / "tree.vdb", nvdb = dir / "tree.nvdb";
            row base;
            base.tree = definition.name, base.store = std::string(store_kind_name<S>), base.resolution = res;
            base.nonempty = store.nonempty_count(), base.memory = store.memory_bytes();
            row b = base, o = base, n = base;
            b.format = "binary", o.format = "openvdb", n.format = "nanovdb";
            for (int r = 0; r < rounds; ++r) {
                b.write.keep_best(seconds([&] { save(store, binary); }));
                o.write.keep_best(seconds([&] { save_vdb(store, vdb); }));
                n.write.keep_best(seconds([&] { save_nvdb(store, nvdb); }));
                S back_binary, back_vdb;
                b.read.keep_best(seconds([&] { back_binary = load<S>(binary); }));
                o.read.keep_best(seconds([&] { back_vdb = load_vdb<S>(vdb); }));
                nanovdb::GridHandle<nanovdb::HostBuffer> density, level;
                n.read.keep_best(seconds([&] {
                    density = nanovdb::io::readGrid(nvdb.string(), "density");
                    level = nanovdb::io::readGrid(nvdb.string(), "level");
                }));
                if (r == 0) {
                    b.differing = differing_voxels(store, back_binary);
                    o.differing = differing_voxels(store, back_vdb);
                    // The NanoVDB grids against the store, through NanoVDB's accessor.
                    const auto d = density.grid<float>()->getAccessor();
                    const auto l = level.grid<std::int32_t>()->getAccessor();
                    const hypervolume& volume = store.volume();
                    std::size_t wrong = density.grid<float>()->activeVoxelCount() == store.nonempty_count() ? 0 : 1;
                    for (voxel_index i = 0; i < volume.voxel_count(); ++i) {
                        const auto c = volume.coordinates(i);
                        const nanovdb::Coord ijk(c[0], c[1], c[2]);
                        const voxel v = store.at(i);
                        wrong += std::lround(d.getValue(ijk) * 255.0f) != v.density || (v.density > 0 && l.getValue(ijk) != v.level);
                    }
                    n.differing = wrong;
                }
            }
            b.file_bytes = std::filesystem::file_size(binary);
            o.file_bytes = std::filesystem::file_size(vdb);
            n.file_bytes = std::filesystem::file_size(nvdb);
            for (const row* x : {&b, &o, &n}) {
                std::printf("%-4s %-12s %9zu %8.2fMB | %-7s %9.2fMB %7.1fms %7.1fms %7.1fms %7.1fms %8zu\n", x->tree.c_str(),
                            x->store.c_str(), x->nonempty, double(x->memory) / 1e6, x->format.c_str(), double(x->file_bytes) / 1e6,
                            x->write.wall * 1e3, x->write.cpu * 1e3, x->read.wall * 1e3, x->read.cpu * 1e3, x->differing);
                rows.push_back(*x);
            }
        });
        std::printf("\n");
    }
    std::printf("load average after: %s\n", bench::load_average().c_str());
    std::error_code ignored;
    for (const char* f : {"tree.htree", "tree.vdb", "tree.nvdb"}) std::filesystem::remove(dir / f, ignored);

    if (csv_path.empty()) csv_path = bench::csv_next_to_executable(argv[0]);
    std::ofstream csv(csv_path);
    csv << "tree,resolution,store,nonempty,memory_bytes,format,file_bytes,write_ms,write_cpu_ms,read_ms,read_cpu_ms,differing_voxels,rounds,"
           "tbb_threads\n";
    for (const row& r : rows)
        csv << r.tree << ',' << r.resolution << ',' << r.store << ',' << r.nonempty << ',' << r.memory << ',' << r.format << ','
            << r.file_bytes << ',' << r.write.wall * 1e3 << ',' << r.write.cpu * 1e3 << ',' << r.read.wall * 1e3 << ',' << r.read.cpu * 1e3
            << ',' << r.differing << ',' << rounds << ',' << tbb_threads << '\n';
    std::printf("wrote %s\n", csv_path.c_str());
    return 0;
}

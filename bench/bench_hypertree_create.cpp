// bench_hypertree_create: the creation and memory columns of the hypertree paper's Table 1, for
// four trees shaped like its figure 7 (hypertree/presets.hpp: the iteration counts, transformation
// counts and depths section 11 gives), at resolutions 100, 300 and 1000.
//
//     bench_hypertree_create [--csv FILE] [--repeat R] [--threads T] [--budget-mib M]
//     (the CSV goes next to the executable, as <executable>.csv, unless --csv names one)
//
// Creation is one build_tree call, generate + validate (compact), both on T threads (default all
// cores), + density classes + building the store, best of R calls (default 5; 2 at resolution
// 1000), with a scratch_memory kept across the calls as an application creating trees would keep
// it (hypertree/scratch.hpp): its temporaries then reuse mapped pages. The same call without the
// caller's scratch memory is printed beside it ("no scratch"): build_tree then keeps one for the
// call, so its steps reuse each other's pages, but each call maps them afresh. Each step is also timed alone
// (steps repeated on their own reuse their pages without scratch memory too), to show where the
// time goes. Memory is the store's own report. The paper's figures (an Athlon at 1.4 GHz) stand next
// to ours: its "3D array + bit array" column against our dense store (which needs no bit array),
// and nothing against the partitioned store (the paper gives no figures for it). A store over
// the memory budget (default 1 GiB) is refused, and the table says so.
//
// Targets (issue 7): creation >= 100x faster than the paper's, and the index-list stores <= 5% of
// the dense array's memory at resolution 300.

#include "hypertree/build.hpp"
#include "hypertree/presets.hpp"
#include "hypertree/scratch.hpp"
#include "hypertree/store/bit_array_store.hpp"
#include "hypertree/store/dense_store.hpp"
#include "hypertree/store/index_list_store.hpp"
#include "hypertree/store/partitioned_store.hpp"
#include "support/text.hpp"
#include "support/timing.hpp"

#include <algorithm>
#include <chrono>
#include <cstdio>
#include <cstdlib>
#include <fstream>
#include <functional>
#include <optional>
#include <string>
#include <thread>
#include <vector>

namespace {

using namespace hypertree;

// Table 1 of the paper: creation time (s) and memory (bytes) at resolution 100 and 300.
struct paper_figures {
    double seconds_100, seconds_300;
    double bytes_100, bytes_300;
};
constexpr double K = 1e3, M = 1e6;
// Rows A-D; columns index list, index list + bit array, 3D array (+ bit array).
const paper_figures paper[4][3] = {
    {{0.5, 0.5, 209 * K, 860 * K}, {0.5, 0.5, 331 * K, 4.0 * M}, {0.4, 1.9, 2.9 * M, 80 * M}},
    {{2.6, 2.3, 80 * K, 350 * K}, {2.6, 2.4, 202 * K, 3.5 * M}, {2.2, 3.7, 2.9 * M, 80 * M}},
    {{0.4, 0.8, 210 * K, 1.4 * M}, {0.4, 0.9, 332 * K, 4.6 * M}, {0.3, 2.0, 2.9 * M, 80 * M}},
    {{2.1, 1.4, 56 * K, 315 * K}, {2.2, 1.5, 178 * K, 3.5 * M}, {1.0, 2.5, 2.9 * M, 80 * M}},
};

std::string bytes_text(double b)
{
    char s[32];
    if (b >= 1e9) std::snprintf(s, sizeof s, "%.2fG", b / 1e9);
    else if (b >= 1e6) std::snprintf(s, sizeof s, "%.2fM", b / 1e6);
    else std::snprintf(s, sizeof s, "%.0fK", b / 1e3);
    return s;
}

struct row {
    std::string tree, store;
    int resolution = 0;
    double generate_s = 0, compact_s = 0, classify_s = 0, build_s = 0; // each step alone
    double creation_s = 0;   // one build_tree call, with scratch memory kept across calls
    double no_scratch_s = 0; // one build_tree call without scratch memory
    std::size_t voxels = 0, hits = 0;
    std::optional<std::size_t> bytes; // empty: refused by the budget
    std::optional<paper_figures> paper;
    double steps() const { return generate_s + compact_s + classify_s + build_s; }
};

} // namespace

int main(int argc, char** argv)
{
    std::string csv_path;
    int repeat = 5;
    unsigned threads = std::max(1u, std::thread::hardware_concurrency());
    std::size_t budget_mib = 1024;
    for (int i = 1; i < argc; ++i) {
        const std::string a = argv[i];
        const auto value = [&]() -> std::string {
            if (i + 1 >= argc) {
                std::fprintf(stderr, "%s needs a value\n", a.c_str());
                std::exit(2);
            }
            return argv[++i];
        };
        if (a == "--csv") csv_path = value();
        else if (a == "--repeat") repeat = std::max(1, std::atoi(value().c_str()));
        else if (a == "--threads") threads = unsigned(std::max(1, std::atoi(value().c_str())));
        else if (a == "--budget-mib") budget_mib = std::size_t(std::max(1, std::atoi(value().c_str())));
        else {
            std::fprintf(stderr, "usage: %s [--csv FILE] [--repeat R] [--threads T] [--budget-mib M]\n", argv[0]);
            return 2;
        }
    }

    generation_options generation;
    generation.budget.bytes = budget_mib << 20;
    generation.parallel_for = bench::parallel_for(threads);

    std::printf("hypertree creation (paper Table 1): %u thread(s), best of %d, budget %zu MiB\n\n", threads, repeat, budget_mib);
    std::printf("%-4s %5s %-12s %9s %9s %9s %9s %10s %10s %9s %9s | %9s %9s %8s %10s\n", "tree", "res", "store", "generate", "compact",
                "classify", "build", "creation", "no scratch", "voxels", "memory", "paper CT", "paper MC", "speedup", "no scratch");
    std::vector<row> rows;
    const std::array makers{presets::tree_a, presets::tree_b, presets::tree_c, presets::tree_d};
    for (int resolution_ : {100, 300, 1000}) {
        const int reps = resolution_ >= 1000 ? std::min(repeat, 2) : repeat;
        for (std::size_t t = 0; t < makers.size(); ++t) {
            const ifs<> tree = makers[t](resolution_);
            scratch_memory scratch; // kept across this tree's builds
            build_options with_scratch;
            with_scratch.generation = generation;
            with_scratch.generation.scratch = &scratch;
            build_options without_scratch;
            without_scratch.generation = generation;
            generated_hits hits;
            std::vector<voxel_entry> entries;
            std::vector<stored_voxel> voxels;
            row base;
            base.tree = tree.name;
            base.resolution = resolution_;
            base.generate_s = bench::best_seconds(reps, [&] { hits = generate(tree, 1, generation); });
            base.compact_s = bench::best_seconds(reps, [&] { entries = compact(hits.hits, generation.parallel_for, hits.volume.voxel_count()); });
            base.classify_s = bench::best_seconds(reps, [&] {
                const density_classes classes(entries, 32);
                voxels = classify(entries, classes, tree.branch_depth);
            });
            base.voxels = voxels.size();
            base.hits = hits.hits.size();

            const auto measure = [&]<class Store>(const char* name, std::optional<paper_figures> figures) {
                row r = base;
                r.store = name;
                if (resolution_ <= 300 && figures) r.paper = figures;
                try {
                    std::size_t bytes = 0;
                    r.build_s = bench::best_seconds(reps, [&] { bytes = Store::build(tree.volume, voxels, generation.budget).memory_bytes(); });
                    r.bytes = bytes;
                    r.creation_s = bench::best_seconds(reps, [&] { bytes = build_tree<Store>(tree, 1, with_scratch).memory_bytes(); });
                    r.no_scratch_s = bench::best_seconds(reps, [&] { bytes = build_tree<Store>(tree, 1, without_scratch).memory_bytes(); });
                } catch (const krs::invalid_parameter& e) {
                    r.bytes.reset();
                }
                rows.push_back(r);
                std::string paper_ct = "-", paper_mc = "-", speedup = "-", speedup_no_scratch = "-";
                if (r.paper) {
                    const double ct = resolution_ == 100 ? r.paper->seconds_100 : r.paper->seconds_300;
                    const double mc = resolution_ == 100 ? r.paper->bytes_100 : r.paper->bytes_300;
                    char s[32];
                    std::snprintf(s, sizeof s, "%.1f s", ct), paper_ct = s;
                    paper_mc = bytes_text(mc);
                    if (r.bytes) {
                        std::snprintf(s, sizeof s, "%.0fx", ct / r.creation_s), speedup = s;
                        std::snprintf(s, sizeof s, "%.0fx", ct / r.no_scratch_s), speedup_no_scratch = s;
                    }
                }
                if (r.bytes)
                    std::printf("%-4s %5d %-12s %7.2fms %7.2fms %7.2fms %7.2fms %8.2fms %8.2fms %9zu %9s | %9s %9s %8s %10s\n",
                                r.tree.c_str(), resolution_, name, r.generate_s * 1e3, r.compact_s * 1e3, r.classify_s * 1e3,
                                r.build_s * 1e3, r.creation_s * 1e3, r.no_scratch_s * 1e3, r.voxels, bytes_text(double(*r.bytes)).c_str(),
                                paper_ct.c_str(), paper_mc.c_str(), speedup.c_str(), speedup_no_scratch.c_str());
                else
                    std::printf("%-4s %5d %-12s refused: over the %zu MiB budget\n", r.tree.c_str(), resolution_, name, budget_mib);
            };
            measure.template operator()<index_list_store>("index_list", paper[t][0]);
            measure.template operator()<bit_array_store>("bit_array", paper[t][1]);
            measure.template operator()<dense_store>("dense", paper[t][2]);
            measure.template operator()<partitioned_store>("partitioned", std::nullopt);
        }
        std::printf("\n");
    }

    // Targets.
    double worst_speedup = 1e300, worst_no_scratch = 1e300, worst_share = 0, worst_bit_share = 0;
    for (const row& r : rows) {
        if (r.paper && r.bytes) {
            const double ct = r.resolution == 100 ? r.paper->seconds_100 : r.paper->seconds_300;
            worst_speedup = std::min(worst_speedup, ct / r.creation_s);
            worst_no_scratch = std::min(worst_no_scratch, ct / r.no_scratch_s);
        }
        if (r.resolution == 300 && r.bytes && (r.store == "index_list" || r.store == "bit_array")) {
            const auto dense = std::find_if(rows.begin(), rows.end(), [&](const row& d) {
                return d.tree == r.tree && d.resolution == 300 && d.store == "dense" && d.bytes;
            });
            if (dense != rows.end()) {
                double& worst = r.store == "index_list" ? worst_share : worst_bit_share;
                worst = std::max(worst, double(*r.bytes) / double(*dense->bytes));
            }
        }
    }
    std::printf("target: creation >= 100x the paper's: worst %.0fx -> %s\n", worst_speedup, worst_speedup >= 100 ? "met" : "NOT met");
    std::printf("        (without the caller's scratch memory, each build mapping its temporaries afresh: worst %.0fx)\n", worst_no_scratch);
    // The paper's "less than 5% of a three-dimensional array" is its index list; the bit array is
    // its compromise (4-6% of its array in Table 1), printed for comparison.
    std::printf("target: index list <= 5%% of the dense array at resolution 300: worst %.2f%% -> %s\n", worst_share * 100,
                worst_share <= 0.05 ? "met" : "NOT met");
    std::printf("        (index list + bit array: worst %.2f%% of the dense array)\n", worst_bit_share * 100);

    if (csv_path.empty()) csv_path = bench::csv_next_to_executable(argv[0]);
    std::ofstream csv(csv_path);
    csv << "tree,resolution,store,generate_s,compact_s,classify_s,build_s,creation_s,no_scratch_s,hits,voxels,memory_bytes,paper_creation_s,"
           "paper_memory_bytes\n";
    for (const row& r : rows) {
        csv << r.tree << ',' << r.resolution << ',' << r.store << ',' << r.generate_s << ',' << r.compact_s << ',' << r.classify_s << ','
            << r.build_s << ',' << r.creation_s << ',' << r.no_scratch_s << ',' << r.hits << ',' << r.voxels << ','
            << (r.bytes ? std::to_string(*r.bytes) : "refused") << ',';
        if (r.paper)
            csv << (r.resolution == 100 ? r.paper->seconds_100 : r.paper->seconds_300) << ','
                << (r.resolution == 100 ? r.paper->bytes_100 : r.paper->bytes_300);
        else
            csv << ',';
        csv << '\n';
    }
    std::printf("wrote %s\n", csv_path.c_str());
    return 0;
}

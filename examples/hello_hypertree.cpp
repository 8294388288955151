#include <hypertree/hypertree.hpp>
#include <algorithm>
#include <cstdio>
#include <string_view>
#include <numbers>

int main(int argc, char** argv) {
    if (argc > 1) {                          // no options: -h and --help say so, others are refused
        const bool help = std::string_view(argv[1]) == "-h" || std::string_view(argv[1]) == "--help";
        std::fprintf(help ? stdout : stderr, "usage: hello_hypertree (no options): a hypertree built into voxels, drawn as text\n");
        return help ? 0 : 2;
    }
    using namespace hypertree;
    using branch = pipeline<scale, rotate, rotate, translate>;       // a transform is a type
    ifs<branch> tree;
    for (int k = 0; k < 4; ++k)                                       // four branches up the stem
        tree.transforms.push_back({branch(scale(0.55), rotate({0, 0, 1}, 0.6),
                                          rotate({0, 1, 0}, 2.4 * k), translate(0, 0.3 + 0.15 * k, 0))});
    tree.condensations = {condensation{cone{1, 0.0, 0.5, 0.04, 0.02}, {}}};   // the trunk
    tree.tree_depth = 7;
    tree.iterations = 200000;
    tree.volume = hypervolume({-0.8, 0, -0.8}, {1.6, 1.3, 1.6}, resolution{64, 26, 64});

    const auto store = build_tree<bit_array_store>(tree, /*seed*/ 1);
    for (int y = 25; y >= 0; --y, std::putchar('\n'))                 // front view, densest voxel
        for (int x = 0; x < 64; ++x) {
            int d = 0;
            for (int z = 0; z < 64; ++z) d = std::max<int>(d, store.at(tree.volume.index(x, y, z)).density);
            std::putchar(" .:-=+*#%@"[d * 9 / 255]);
        }
    std::printf("%zu voxels in %zu bytes\n", store.nonempty_count(), store.memory_bytes());
}

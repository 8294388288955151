# Refusals found while a program works from a definition file or against a memory budget, and
# long work shown alive (issue 37), checked by cmake/check_command_lines.cmake (tests
# example_refusals_<program>). A refusal of a file's setting names the file, the line of the
# setting and, where there is one, what would fit, in the file's words (no C++ member names, one
# prefix); one that can be found before the work comes before it ("!create:": no generation
# started). "<data>" is tests/data/refusals/, whose rows each change one line of small.tree.
#
#        program           status  must say                                          arguments

krs_case(hypertree_render  1 "iterations.tree:3:1: ITERATIONS 2000000000: would record up to;iterations fit;!krs: "
                                                                                   --tree <data>/iterations.tree --width 8 --height 8
                                                                                   --threads 1 --output <out>/x.png)
krs_case(hypertree_render  1 "dense.forest:3:1: STORAGETYPE dense needs 8208000000 bytes;over the memory budget;dense at RESOLUTION;or less;!create:"
                                                                                   --forest <data>/dense.forest --width 8 --height 8
                                                                                   --threads 1 --output <out>/x.png)
krs_case(hypertree_render  1 "--store dense needs;dense at --resolution;!create:"   --preset C --store dense --resolution 1600
                                                                                   --width 8 --height 8 --threads 1 --output <out>/x.png)
krs_case(hypertree_render  1 "perturb.tree:4:1: PERTURB 1e+09 1e+09 1e+09: the tree generated no voxels;fills some"
                                                                                   --tree <data>/perturb.tree --width 8 --height 8
                                                                                   --threads 1 --output <out>/x.png)
krs_case(hypertree_render  1 "render_perturb.tree:4:1: RENDERPERTURB;or less fits;!march_options;!step_factor;!krs: "
                                                                                   --tree <data>/render_perturb.tree --width 8 --height 8
                                                                                   --threads 1 --output <out>/x.png)
# Forests do not nest; a forest given as a tree and a tree given as a forest say which they are.
krs_case(hypertree_render  1 "nested.forest:4:1:;is a forest file;TREE takes a tree definition file"
                                                                                   --forest <data>/nested.forest --width 8 --height 8
                                                                                   --threads 1 --output <out>/x.png)
krs_case(hypertree_render  1 "dense.forest:3:1: STORAGETYPE is a forest file's keyword" --tree <data>/dense.forest --width 8
                                                                                   --height 8 --threads 1 --output <out>/x.png)
krs_case(hypertree_render  1 "small.tree:3:1: ITERATIONS is a tree definition's keyword" --forest <data>/small.tree --width 8
                                                                                   --height 8 --threads 1 --output <out>/x.png)
# small.tree with CR-only line endings and with a UTF-8 byte-order mark reads as small.tree;
# saved as UTF-16 it is refused by name.
krs_case(hypertree_render  0 "rendered 8x8"                                        --tree <data>/cr_only.tree --width 8 --height 8
                                                                                   --threads 1 --output <out>/cr.png)
krs_case(hypertree_render  0 "rendered 8x8"                                        --tree <data>/bom.tree --width 8 --height 8
                                                                                   --threads 1 --output <out>/bom.png)
krs_case(hypertree_render  1 "utf16.tree:1:1: the file is UTF-16"                  --tree <data>/utf16.tree --width 8 --height 8
                                                                                   --threads 1 --output <out>/x.png)

# krs_export: the grid before any pass, the estimate before the full one, each pass's progress
# from its start; a budget the estimate refuses is refused before the full pass ("!mesh: 0%").
krs_case(krs_export        0 "stderr:a grid of;stderr:estimated first from a pass at resolution 16;stderr:estimate: 0%;stderr:estimated mesh;stderr:mesh: 0%;stderr:vertices: 100%"
                                                                                   --scene rock --resolution 64 --mesh <out>/rock.ply)
krs_case(krs_export        1 "a grid of;estimate: 0%;--memory-budget;estimated size;!mesh: 0%;!krs: "
                                                                                   --scene tree --resolution 16384 --memory-budget 1
                                                                                   --mesh <out>/tree.ply)
krs_case(krs_export        0 "stderr:a grid of;stderr:mesh: 0%;!estimate:"         --scene rock --resolution 8 --mesh <out>/small.ply)

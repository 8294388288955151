# The examples' command lines and how each must end, checked by cmake/check_command_lines.cmake
# (tests example_command_lines_<program>). A refusal (status 2) must name, on stderr, the option,
# the value given and what is allowed; rows of status 0 are cheap: --help, or a render of a few
# pixels. Rows marked "old" were accepted by the parser before CLI11 (a number's prefix was taken,
# or a float was not checked) or refused without naming the option.
#
# The options every program spells alike (support/common_options.hpp): --width/--height in
# [1, 16384], --threads in [0, 1024] ("one per core"), --seed in [0, 2^30], --output FILE,
# --output-dir DIR. Each program's rows refuse them at their ranges' edges and show them in --help;
# an older spelling kept as an alias has a row that still works and a --help row that says so.
#
#        program           status  must say                                          arguments

# krs_tree
krs_case(krs_tree          2 "--width;'3x';an integer in [1, 16384]"              --width 3x)
krs_case(krs_tree          2 "--width;'2.5'"                                       --width 2.5)
krs_case(krs_tree          2 "--height;'1e9'"                                      --height 1e9)
krs_case(krs_tree          2 "--height;'0';[1, 16384]"                             --height 0)
krs_case(krs_tree          2 "--levels;'21';[1, 20]"                               --levels 21) # old: abort, exit 134
krs_case(krs_tree          2 "--levels;'30';[1, 20]"                               --levels 30) # --help said [1, 30]
# The top of --levels renders (3.1 M kernel instances, under krs::expand's 2^22): the range is
# what the program takes, not a guess (about 10 s and 0.5 GB, the expansion's cost).
krs_case(krs_tree          0 "kernel instances;wrote"                              --levels 20 --width 4 --height 4 --threads 2
                                                                                   --output <out>/krs_tree_20.png)
krs_case(krs_tree          2 "--threads;'-1';[0, 1024]"                            --threads -1)
krs_case(krs_tree          2 "--seed;' 7'"                                         --seed " 7")
krs_case(krs_tree          2 "--width;missing"                                     --width)
krs_case(krs_tree          2 "--seed;missing"                                      --seed=)
krs_case(krs_tree          2 "--output;'--width'"                                  --output --width 8)
krs_case(krs_tree          2 "--fast"                                              --fast)
krs_case(krs_tree          2 "--width;2"                                           --width 8 --width 9)
krs_case(krs_tree          0 "--levels;--output;--width;--height;--threads;one per core;--seed"  --help)
krs_case(krs_tree          2 "--width;'16385';[1, 16384]"                          --width 16385)
krs_case(krs_tree          2 "--seed;'1073741825';[0, 1073741824]"                 --seed 1073741825)
krs_case(krs_tree          0 "wrote"                                               --width 8 --height 8 --levels 2 --threads 1
                                                                                   --output <out>/krs_tree.png)

# hypertree_render
krs_case(hypertree_render  2 "--supersampling;'3x';auto or an integer in [1, 16]"  --supersampling 3x)  # old: 3
krs_case(hypertree_render  2 "--supersampling;'2.5'"                               --supersampling 2.5) # old: 2
krs_case(hypertree_render  2 "--supersampling;'1e9'"                               --supersampling 1e9) # old: 1
krs_case(hypertree_render  2 "--supersampling;'17';[1, 16]"                        --supersampling 17)  # old: no name
krs_case(hypertree_render  2 "--supersampling;'0';[1, 16]"                         --supersampling 0)   # old: no name
krs_case(hypertree_render  2 "--supersampling;'Auto'"                              --supersampling Auto)
krs_case(hypertree_render  2 "--resolution;'-5';[1, 1600]"                         --resolution -5)
krs_case(hypertree_render  2 "--resolution;'1601'"                                 --resolution 1601)
krs_case(hypertree_render  2 "--density-scale;'nan';a finite number in (0, 100]"   --density-scale nan)
krs_case(hypertree_render  2 "--density-scale;'inf'"                               --density-scale inf)
krs_case(hypertree_render  2 "--density-scale;'1e400'"                             --density-scale 1e400)
krs_case(hypertree_render  2 "--density-scale;'0';(0, 100]"                        --density-scale 0)
krs_case(hypertree_render  2 "--density-scale;'4x'"                                --density-scale 4x)  # old: 4
krs_case(hypertree_render  2 "--density-scale;'1e-50';(0, 100]"                   --density-scale 1e-50) # 0 as a float
krs_case(hypertree_render  2 "--resolution;'+-5'"                                  --resolution +-5)
krs_case(hypertree_render  2 "--density-scale;missing"                             --density-scale)
krs_case(hypertree_render  2 "--store;'sparse';one of dense|index_list|bit_array|partitioned" --store sparse)
krs_case(hypertree_render  2 "--preset;'E';one of A|B|C|D"                         --preset E)
krs_case(hypertree_render  2 "--tree;--forest"                                     --tree a.tree --forest b.forest)
krs_case(hypertree_render  2 "--width;'8192x'"                                     --width 8192x)
krs_case(hypertree_render  2 "--seed;missing"                                      --seed)
krs_case(hypertree_render  2 "--samples"                                           --samples 4)
krs_case(hypertree_render  0 "--supersampling;--density-scale;--width;--height;--threads;one per core;--seed;--output" --help)
# The shared sizes (support/common_options.hpp): [1, 16384] as every program's (was [1, 8192]).
krs_case(hypertree_render  2 "--width;'16385';[1, 16384]"                          --width 16385)
krs_case(hypertree_render  2 "--height;'0';[1, 16384]"                             --height 0)
krs_case(hypertree_render  2 "--threads;'1025';[0, 1024]"                          --threads 1025)
krs_case(hypertree_render  2 "--seed;'-1';[0, 1073741824]"                         --seed -1)
krs_case(hypertree_render  0 "rendered 16x16"                                      --preset C --resolution 16 --width 16 --height 16
                                                                                   --supersampling auto --threads 1 --output <out>/hypertree.png)
# Decimal, whole: CLI11 alone reads integers in base 0, where 010 is 8.
krs_case(hypertree_render  0 "rendered 16x16, supersampling 10"                    --preset C --resolution 16 --width 16 --height 16
                                                                                   --supersampling 010 --threads 1 --output <out>/hypertree.png)
krs_case(hypertree_render  0 "rendered 16x16, supersampling 1"                     --preset C --resolution 16 --width 16 --height 16
                                                                                   --supersampling 1 --threads 1 --output <out>/hypertree.png)
# The grid files: a name ending as the format's do, a directory that exists, a build with OpenVDB.
# The settings of the paper's figures 8-12 (examples/hypertrees/figure*; what their images show is
# checked by tests/check_figure_image.cpp).
krs_case(hypertree_render  2 "--lod;'0';[1, 1600]"                                 --lod 0)
krs_case(hypertree_render  2 "--clear-above;'nan'"                                 --clear-above nan)
krs_case(hypertree_render  2 "--specular;'-1';[0, 10]"                             --specular -1)
krs_case(hypertree_render  2 "--ambient;'inf'"                                     --ambient inf)
krs_case(hypertree_render  2 "--shininess;'1e4';[0, 1000]"                         --shininess 1e4)
krs_case(hypertree_render  2 "--light-elevation;'91';[-90, 90]"                    --light-elevation 91)
krs_case(hypertree_render  2 "--light-azimuth;'x'"                                 --light-azimuth x)
krs_case(hypertree_render  2 "--normals;'flat';one of structure_flow|part_boxes|line_flow" --normals flat)
krs_case(hypertree_render  2 "--shadows;'no';one of on|off"                        --shadows no)
krs_case(hypertree_render  2 "--normals line_flow needs one tree"                  --forest f.forest --normals line_flow)
krs_case(hypertree_render  1 "--lod 32;must not exceed the tree's resolution (16 x 16 x 16)"
                                                                                   --preset C --resolution 16 --lod 32 --width 16 --height 16
                                                                                   --threads 1 --output <out>/hypertree.png)
krs_case(hypertree_render  1 "nothing is left to render"                           --preset C --resolution 16 --clear-above -10 --width 16
                                                                                   --height 16 --threads 1 --output <out>/hypertree.png)
krs_case(hypertree_render  1 "--normals line_flow;generator is a point"            --preset A --resolution 16 --normals line_flow --width 16
                                                                                   --height 16 --threads 1 --output <out>/hypertree.png)
krs_case(hypertree_render  0 "rendered 16x16"                                      --preset C --resolution 16 --lod 8 --clear-above 0.5
                                                                                   --normals line_flow --specular 0.5 --shininess 8 --light-elevation 30
                                                                                   --light-azimuth -45 --shadows off --width 16 --height 16 --threads 1
                                                                                   --output <out>/hypertree.png)
krs_case(hypertree_render  0 "rendered 16x16"                                      --preset B --resolution 16 --normals part_boxes --width 16
                                                                                   --height 16 --threads 1 --output <out>/hypertree.png)
krs_case(hypertree_render  2 "--save-vdb;'tree.txt';does not end in .vdb"          --save-vdb tree.txt)
krs_case(hypertree_render  2 "--save-nvdb;'.nvdb';does not end in .nvdb"           --save-nvdb .nvdb)
# --up: krs_export's words and refusal (support/up_axis_option.hpp), only where it turns a file.
krs_case(hypertree_render  2 "--up;'x';y|z"                                         --up x)
krs_case(hypertree_render  2 "--up: only with --save-vdb or --save-nvdb"           --preset C --resolution 16 --up z)
if(KRS_WITH_OPENVDB)
    krs_case(hypertree_render 2 "--save-vdb;/dev/null is not a directory"          --save-vdb /dev/null/t.vdb)
    krs_case(hypertree_render 0 "saved the grids to;t.vdb, up y;t.nvdb, up y;rendered 16x16" --preset C --resolution 16 --width 16
                                                                                  --height 16 --threads 1 --output <out>/hypertree.png
                                                                                  --save-vdb <out>/t.vdb --save-nvdb <out>/t.nvdb)
    krs_case(hypertree_render 0 "t.vdb, up z;t.nvdb, up z"                         --preset C --resolution 16 --width 16 --height 16
                                                                                  --threads 1 --output <out>/hypertree.png --up z
                                                                                  --save-vdb <out>/t.vdb --save-nvdb <out>/t.nvdb)
else()
    krs_case(hypertree_render 2 "--save-vdb;no OpenVDB"                            --save-vdb t.vdb)
endif()

# Paths that are no definition file, refused at once with the reason: before, /dev/zero was read
# until memory ran out, a FIFO blocked forever and a 2 GB file was read whole before its first line
# was refused (io::read_text_file: regular files of at most 16 MiB). The files are made here.
if(PROGRAM STREQUAL "hypertree_render")
    file(REMOVE "${WORK_DIR}/fifo.tree" "${WORK_DIR}/sparse.tree")
    execute_process(COMMAND mkfifo "${WORK_DIR}/fifo.tree")
    file(TOUCH "${WORK_DIR}/sparse.tree")
    execute_process(COMMAND truncate --size=2G "${WORK_DIR}/sparse.tree")
    file(WRITE "${WORK_DIR}/zero.forest" "RESOLUTION 8\nSTORAGETYPE dense\nTREE /dev/zero\n")
endif()
krs_case(hypertree_render  1 "/dev/zero:1:1: cannot read the definition file: it is not a regular file"
                             --tree /dev/zero --output <out>/x.png)
krs_case(hypertree_render  1 "fifo.tree:1:1: cannot read the definition file: it is not a regular file"
                             --tree <out>/fifo.tree --output <out>/x.png)
krs_case(hypertree_render  1 "sparse.tree:1:1: cannot read the definition file: it is 2147483648 bytes, over the limit of 16777216"
                             --tree <out>/sparse.tree --output <out>/x.png)
krs_case(hypertree_render  1 ":1:1: cannot read the definition file: it is a directory" --tree <out> --output <out>/x.png)
krs_case(hypertree_render  1 "none.tree:1:1: cannot read the definition file: No such file or directory"
                             --tree <out>/none.tree --output <out>/x.png)
krs_case(hypertree_render  1 "/dev/zero:1:1: cannot read the forest file: it is not a regular file"
                             --forest /dev/zero --output <out>/x.png)
krs_case(hypertree_render  1 "zero.forest:3:1: cannot read the tree file '/dev/zero': it is not a regular file"
                             --forest <out>/zero.forest --output <out>/x.png)
if(PROGRAM STREQUAL "hypertree_render")
    file(REMOVE "${WORK_DIR}/fifo.tree" "${WORK_DIR}/sparse.tree")
endif()

# krs_scenes
krs_case(krs_scenes        2 "--width;'0';[1, 16384]"                              --width 0) # was [1, 8192]
krs_case(krs_scenes        2 "--height;'16385';[1, 16384]"                         --height 16385)
krs_case(krs_scenes        2 "--height;'abc'"                                      --height abc)
krs_case(krs_scenes        2 "--seed;'2.5'"                                        --seed 2.5)
krs_case(krs_scenes        2 "--threads;'1025';[0, 1024]"                          --threads 1025)
# The scenes are the list's (krs/scenes/example_scenes.hpp) that krs_scenes renders, in its order;
# --only is --scene's older name.
krs_case(krs_scenes        2 "--scene;'sky';one of forest|terrain|rock|mirrors|coral|grass|sponge" --scene sky)
krs_case(krs_scenes        2 "--scene;'sky';one of forest|"                        --only sky)
krs_case(krs_scenes        2 "--scene;'kifs_koch';one of forest|"                  --scene kifs_koch)
krs_case(krs_scenes        2 "--output-dir;missing"                                --output-dir)
krs_case(krs_scenes        0 "--scene;--only: its older name;--list-scenes;--seed;--output-dir;--threads;one per core" -h)
krs_case(krs_scenes        0 "forest ;2^6 trees;mirrors ;figure 5;sponge ;(--seed)"  --list-scenes)
krs_case(krs_scenes        0 "total:;1 scene"                                      --scene rock --seed 4 --width 8 --height 8 --threads 1
                                                                                   --output-dir <out>)
krs_case(krs_scenes        0 "total:;1 scene"                                      --only mirrors --width 8 --height 8 --threads 1
                                                                                   --output-dir <out>)
krs_case(krs_scenes        2 "--reflectivity;'1.5';[0, 1]"                         --reflectivity 1.5)
krs_case(krs_scenes        0 "total:;1 scene"                                      --only mirrors --width 8 --height 8 --threads 1
                                                                                   --reflectivity 0.3 --output-dir <out>)

# krs_fractals
krs_case(krs_fractals      2 "--width;'3x'"                                        --width 3x)
krs_case(krs_fractals      2 "--height;'0';[1, 16384]"                             --height 0) # was [1, 8192]
krs_case(krs_fractals      2 "--width;'16385';[1, 16384]"                          --width 16385)
krs_case(krs_fractals      2 "--seed;'-3';[0, 1073741824]"                         --seed -3)
krs_case(krs_fractals      2 "--threads;'nan'"                                     --threads nan)
krs_case(krs_fractals      2 "--output-dir;missing"                                --output-dir=)
krs_case(krs_fractals      2 "--zoom"                                              --zoom 3)
krs_case(krs_fractals      0 "--width;--height;--output-dir;--threads;one per core;--scene;--list-scenes;--seed" --help)
krs_case(krs_fractals      0 "total:;12 frames"                                    --width 4 --height 4 --threads 1 --output-dir <out>)
krs_case(krs_fractals      0 "total:;12 frames"                                    --width 4 --height 4 --threads 1 --colouring off
                                                                                   --output-dir <out>)
krs_case(krs_fractals      2 "--colouring;'yes';one of on|off"                     --colouring yes)
# One frame of the list, or the zoom (cube_singularity's seven frames).
krs_case(krs_fractals      0 "kifs_koch;total:;1 frames"                           --scene kifs_koch --width 4 --height 4 --threads 1
                                                                                   --output-dir <out>)
krs_case(krs_fractals      0 "zoom_6;total:;7 frames"                              --scene cube_singularity --width 4 --height 4
                                                                                   --threads 1 --output-dir <out>)
krs_case(krs_fractals      2 "--scene;'tree';one of kifs_square|kifs_cube|kifs_menger|kifs_sierpinski|kifs_koch|cube_singularity"
                                                                                   --scene tree)
krs_case(krs_fractals      0 "kifs_square ;kifs_koch ;cube_singularity "           --list-scenes)
krs_case(krs_fractals      2 "--slice, --scene"                                    --slice sphere --scene kifs_koch)
# The cross-section view (krs/cross_section.hpp): a sphere overestimates nowhere, the Menger
# sponge's slice is written as two PNGs; what the images hold is tests/test_cross_section.cpp's.
krs_case(krs_fractals      0 "slice sphere: 32x24;flagged 0 of 768 pixels;slice_sphere_distance.png;slice_sphere_gradient.png"
                                                                                   --slice sphere --width 32 --height 24 --output-dir <out>)
krs_case(krs_fractals      0 "slice kifs_menger: 24x24, plane xz at 0.1;slice_kifs_menger_gradient.png"
                                                                                   --slice menger --slice-plane xz --slice-offset 0.1
                                                                                   --slice-extent 1.2 --slice-spacing 0.1 --width 24 --height 24
                                                                                   --output-dir <out>)
krs_case(krs_fractals      2 "--slice;'torus';one of sphere|tree|forest|"          --slice torus)
# Any scene of the list slices, a seeded one at --seed.
krs_case(krs_fractals      0 "slice rock: 8x8;slice_rock_distance.png"             --slice rock --seed 5 --width 8 --height 8
                                                                                   --output-dir <out>)
krs_case(krs_fractals      0 "slice kifs_koch: 8x8"                                --slice kifs_koch --width 8 --height 8
                                                                                   --output-dir <out>)
krs_case(krs_fractals      2 "--slice-plane;'xw';one of xy|xz|yz"                  --slice menger --slice-plane xw)
krs_case(krs_fractals      2 "--slice-spacing;'0';a finite number in (0, 1000000]" --slice menger --slice-spacing 0)
krs_case(krs_fractals      2 "--slice-extent;'nan'"                                --slice menger --slice-extent nan)
krs_case(krs_fractals      2 "--slice-offset;'2e6';[-1000000, 1000000]"            --slice menger --slice-offset 2e6)
krs_case(krs_fractals      2 "--slice-spacing needs --slice FIELD"                 --slice-spacing 0.1)

# glsl_export
krs_case(glsl_export       2 "--scene;'sky';one of tree|forest|"                   --scene sky) # the list: test_glsl.cpp
krs_case(glsl_export       2 "--scene;'kifs'"                                      --scene kifs)
krs_case(glsl_export       2 "--target;'460';one of 330|450|es300|shadertoy"       --target 460)
krs_case(glsl_export       2 "--mode;'texture';one of constants|buffer"            --mode texture)
krs_case(glsl_export       2 "--output;missing"                                    --output)
krs_case(glsl_export       2 "--prefix;'gl_';GLSL identifier"                       --prefix gl_)
krs_case(glsl_export       2 "--prefix;'1st_'"                                     --prefix 1st_)
krs_case(glsl_export       2 "--prefix;'my__'"                                     --prefix my__)
krs_case(glsl_export       2 "--prefix;'a-b'"                                      --prefix a-b)
krs_case(glsl_export       2 "--prefix;'App_'"                                     --prefix App_)
krs_case(glsl_export       2 "--prefix;'app'"                                      --prefix app)
krs_case(glsl_export       2 "--prefix;Shadertoy"                                  --target shadertoy --prefix app_)
krs_case(glsl_export       2 "--output-dir;'--scene'"                              --all --scene tree)
# --output-dir DIR writes the glsl/ folder (--all DIR: its older spelling); the choices of one file
# do not apply to it and are refused rather than ignored.
krs_case(glsl_export       2 "--output-dir;missing"                                --output-dir)
krs_case(glsl_export       2 "--scene: --output-dir writes every scene"            --output-dir <out>/all --scene tree)
krs_case(glsl_export       2 "--target: --output-dir writes every scene"           --all <out>/all --target 330)
krs_case(glsl_export       2 "--mode: --output-dir"                                --output-dir <out>/all --mode buffer)
krs_case(glsl_export       2 "--output: --output-dir"                              --output-dir <out>/all --output <out>/x.glsl)
krs_case(glsl_export       0 ""                                                    --all <out>/all_old) # the older spelling still writes
krs_case(glsl_export       2 "--version"                                           --version)
krs_case(glsl_export       2 "--width;'0';an integer in [1, 16384]"                --reference <out>/r.png --width 0)
krs_case(glsl_export       2 "--width;'16385';[1, 16384]"                          --reference <out>/r.png --width 16385)
krs_case(glsl_export       2 "--height;'0';[1, 16384]"                             --reference <out>/r.png --height 0)
krs_case(glsl_export       2 "--height;'16385';[1, 16384]"                         --reference <out>/r.png --height 16385)
krs_case(glsl_export       2 "--height;'12x'"                                      --reference <out>/r.png --height 12x)
krs_case(glsl_export       2 "--width;--reference"                                 --width 64)
krs_case(glsl_export       2 "--reference;--output-dir"                            --reference <out>/r.png --output-dir <out>)
krs_case(glsl_export       2 "--reference;missing"                                 --reference)
krs_case(glsl_export       2 "--reference;'k.jpg';.png"                            --reference k.jpg)
krs_case(glsl_export       2 "--reference;'k.png.exr';.png"                        --reference k.png.exr)
krs_case(glsl_export       0 "--scene;--target;--mode;--list-scenes;--seed;--output;--output-dir;--all: its older name;--width;--height" --help)
krs_case(glsl_export       0 "tree ;mirrors ;figure 5;lotus ;cube_singularity ;(--seed)" --list-scenes)
krs_case(glsl_export       2 "--seed;--output-dir"                                 --all <out> --seed 2)
krs_case(glsl_export       2 "--seed;'-1';[0, 1073741824]"                         --seed -1)
krs_case(glsl_export       0 ""                                                    --scene mirrors --target 330 --output <out>/mirrors.glsl)
krs_case(glsl_export       0 ""                                                    --scene forest --seed 9 --target shadertoy
                                                                                   --output <out>/forest9.shadertoy.glsl)
krs_case(glsl_export       0 ""                                                    --scene sponge --target 330 --output <out>/sponge.glsl)
krs_case(glsl_export       0 ""                                                    --scene tree --target 450 --mode uniform-buffer
                                                                                   --output <out>/tree.ubo450.glsl)
krs_case(glsl_export       0 ""                                                    --scene forest --prefix forest_gen_
                                                                                   --output <out>/forest.prefixed.glsl)
krs_case(glsl_export       0 ""                                                    --scene kifs_koch --reference <out>/kifs_koch.png
                                                                                   --width 16 --height 9)
# What the PNG holds and what a failed write leaves: cmake/check_glsl_reference.cmake.
krs_case(glsl_export       0 ""                                                    --scene lotus --target shadertoy --output <out>/lotus.shadertoy.glsl
                                                                                   --reference <out>/lotus.png --width 8 --height 8)

# krs_export
krs_case(krs_export        2 "--scene;'sky';one of tree|forest|"                   --scene sky --mesh <out>/x.ply)
krs_case(krs_export        2 "--resolution;'0';[1, 65536]"                          --scene rock --resolution 0 --mesh <out>/x.ply)
krs_case(krs_export        2 "--resolution;'2.5'"                                   --scene rock --resolution 2.5 --mesh <out>/x.ply)
krs_case(krs_export        2 "--memory-budget;'0';[1, 1048576]"                     --scene rock --memory-budget 0 --mesh <out>/x.ply)
# --output FILE: the file (--mesh FILE: its older spelling); --instances writes it as instances
# (--instances FILE: its older spelling).
krs_case(krs_export        2 "--output;'x.stl';.ply, .obj, .glb or .gltf"           --scene rock --output x.stl)
krs_case(krs_export        2 "--output;'x.stl';.ply, .obj, .glb or .gltf"           --scene rock --mesh x.stl)
krs_case(krs_export        2 "--output: give the file to write (FILE.ply"           --scene rock)
krs_case(krs_export        2 "--output: give the file to write (FILE.gltf or FILE.glb)" --scene tree --instances)
krs_case(krs_export        2 "--output (--instances);'x.ply';.gltf or .glb"         --scene sponge --instances --output x.ply)
krs_case(krs_export        2 "--output (--instances);'x.ply';.gltf or .glb"         --scene sponge --instances x.ply)
krs_case(krs_export        2 "--instances FILE, --output: one file"                 --scene tree --instances <out>/a.gltf --output <out>/b.gltf)
krs_case(krs_export        2 "--instance-levels;'-1';[0, 64]"                       --scene sponge --instance-levels -1 --instances <out>/x.gltf)
krs_case(krs_export        0 "--output;--mesh: its older name;--resolution;--instances;--instances FILE: its older spelling;--list-scenes;--seed" --help)
krs_case(krs_export        0 "krs_export: mirrors: ;triangles"                      --scene mirrors --resolution 24 --output <out>/mirrors.ply)
krs_case(krs_export        0 "krs_export: rock: ;triangles;-> "                      --scene rock --resolution 8 --mesh <out>/rock.obj)
krs_case(krs_export        2 "--projection-steps;'65';[0, 64]"                     --scene rock --projection-steps 65 --mesh <out>/x.ply)
krs_case(krs_export        2 "--uv, --kernel-colors: only for a mesh, not with --instances" --scene tree --uv --instances --output <out>/x.gltf)
krs_case(krs_export        2 "--up;'x';y|z"                                         --scene rock --up x --mesh <out>/x.ply)
krs_case(krs_export        2 "--gpu-instancing: only with --instances"              --scene rock --gpu-instancing --mesh <out>/x.ply)
# Refusals found while meshing (status 1) name the option typed, not the library's field.
krs_case(krs_export        1 "--memory-budget: is below the mesh's estimated size;lower --resolution;(got 1 MB)" --scene tree --resolution 256 --memory-budget 1 --mesh <out>/x.ply)
krs_case(krs_export        1 "--uv / --kernel-colors: needs a field that locates"   --scene kifs_menger --resolution 8 --uv --mesh <out>/x.ply)
krs_case(krs_export        0 "krs_export: tree: ;triangles;-> ;tree.obj"            --scene tree --resolution 16 --uv --kernel-colors --output <out>/tree.obj)
# The similar shells mesh at the default resolution (issue 41: their inside was 0, never negative;
# a few seconds), and a grid too coarse for the geometry says the field was never negative there.
krs_case(krs_export        0 "krs_export: lotus: ;triangles"                        --scene lotus --mesh <out>/lotus.ply)
krs_case(krs_export        0 "krs_export: cube_singularity: ;triangles"             --scene cube_singularity --mesh <out>/cubes.ply)
krs_case(krs_export        1 "no triangle at resolution 40;never negative where sampled" --scene kifs_sierpinski --resolution 40 --mesh <out>/x.ply)
if(KRS_WITH_GLTF)
    krs_case(krs_export    2 "--max-instances;'0'"                                  --scene tree --max-instances 0 --instances <out>/x.glb)
    krs_case(krs_export    1 "--memory-budget: is below the mesh's estimated size;lower --resolution;(got 1 MB)" --scene tree --resolution 256 --memory-budget 1 --instances <out>/x.glb)
    krs_case(krs_export    1 "--max-instances: exceeded;at --instance-levels 4;lower --instance-levels;(got 3)" --scene tree --max-instances 3 --instances <out>/x.glb)
    krs_case(krs_export    1 "--instance-levels: must be at most"                   --scene rock --instance-levels 64 --instances <out>/x.glb)
    krs_case(krs_export    1 "'mirrors' is not a sequence (tree, forest, terrain, rock, grass, sponge are)"
                                                                                    --scene mirrors --instances <out>/x.glb)
    # Scenes with planes (the tree's ground, the rock's and terrain's facets) export as instances:
    # their planes are meshed within the scene's box.
    krs_case(krs_export    0 "krs_export: tree: ;instances;tree.glb"                 --scene tree --resolution 8 --instances --output <out>/tree.glb)
    krs_case(krs_export    0 "krs_export: rock: ;instances"                          --scene rock --resolution 8 --instances <out>/rock.glb)
    krs_case(krs_export    0 "krs_export: terrain: ;instances;terrain.gltf"          --output <out>/terrain.gltf --scene terrain --resolution 8 --instances)
    # The count printed is the file's: kernels that mesh to nothing are named and not counted.
    krs_case(krs_export    0 "mesh to nothing and are not written: kernel;8 parts, 320 instances" --scene tree --resolution 96 --instance-levels 8 --instances <out>/tree8.gltf)
endif()

# krs_view (refused before any window opens, so these rows need no display; what it draws:
# scripts/check_krs_view.sh, tests example_krs_view_*)
krs_case(krs_view          2 "--scene;'nosuch';one of tree|forest|terrain|"         --scene nosuch)
krs_case(krs_view          2 "--width;'0';an integer in [1, 16384]"                --width 0)
krs_case(krs_view          2 "--frames;'0';[1, 1000000]"                           --frames 0)
krs_case(krs_view          2 "--time;'nan';a finite number in [0, 1000000]"        --time nan)
krs_case(krs_view          2 "--glsl;missing.glsl' is not a file"                 --glsl <out>/missing.glsl)
krs_case(krs_view          2 "--glsl, --scene"                                     --glsl <out>/missing.glsl --scene tree)
krs_case(krs_view          2 "--accumulate;--frames"                               --accumulate)
krs_case(krs_view          2 "--exit-after-reload;--glsl FILE"                     --exit-after-reload 5 --frames 2)
krs_case(krs_view          2 "--exit-after-reload;'0';(0, 3600]"                   --exit-after-reload 0)
krs_case(krs_view          2 "--output;'k.jpg';.png"                               --frames 1 --output k.jpg)
krs_case(krs_view          2 "--output;'k.jpg';.png"                               --frames 1 --screenshot k.jpg) # its older name
krs_case(krs_view          2 "--output;missing"                                    --output)
krs_case(krs_view          2 "--height;'16385';[1, 16384]"                         --height 16385)
krs_case(krs_view          2 "--output;/dev/null is not a directory"               --frames 1 --output /dev/null/v.png)
krs_case(krs_view          0 "--scene;--glsl;--frames;--output;--screenshot: its older name;--accumulate;--exit-after-reload;--width;--height;space pauses" --help)
krs_case(krs_view          0 "tree ;grass ;kifs_menger "                           --list-scenes)
krs_case(krs_view          2 "--glsl, --scene, --seed"                             --glsl <out>/missing.glsl --seed 3)

# hello_krs, hello_hypertree: no options, and they say so
foreach(hello hello_krs hello_hypertree)
    krs_case(${hello} 0 "usage: ;no options" --help)
    krs_case(${hello} 0 "usage: ;no options" -h)
    krs_case(${hello} 2 "usage: ;no options" --levels 3)
    krs_case(${hello} 2 "usage: ;no options" tree)
    krs_case(${hello} 2 "usage: ;no options" --version)
endforeach()

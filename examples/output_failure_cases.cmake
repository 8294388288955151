# Every writer of every example, for cmake/check_output_failures.cmake (tests
# example_output_failures_<program> and example_output_read_only_<program>): each row is run on a
# full disk, a read-only directory, a missing directory, a directory as the path and a wrong
# extension, and must lose nothing and claim nothing. Rows are as small as a run can be (a few
# pixels, a few voxels): what is checked is how the bytes reach the disk, which every program does
# through krs::write_file; one row per library writer, not per option that shares one.
#
#   krs_output_file(program extension arguments...)   "<file>": the output; "<work>": the row's folder
#   krs_output_folder(program written arguments...)   "<dir>": the --output-dir; `written`: a file in it

krs_output_file(krs_tree .png           --width 8 --height 8 --levels 2 --threads 1 --output <file>)

krs_output_file(hypertree_render .png   --preset C --resolution 16 --width 8 --height 8 --threads 1 --output <file>)
krs_output_file(hypertree_render ""     --preset C --resolution 16 --width 8 --height 8 --threads 1
                                        --output <work>/render.png --save-volume <file>)
if(KRS_WITH_OPENVDB)
    krs_output_file(hypertree_render .vdb  --preset C --resolution 16 --width 8 --height 8 --threads 1
                                           --output <work>/render.png --save-vdb <file>)
    krs_output_file(hypertree_render .nvdb --preset C --resolution 16 --width 8 --height 8 --threads 1
                                           --output <work>/render.png --save-nvdb <file>)
endif()

krs_output_folder(krs_scenes sponge.png --scene sponge --width 8 --height 6 --threads 1 --output-dir <dir>)

krs_output_folder(krs_fractals slice_sphere_distance.png --slice sphere --width 8 --height 8 --output-dir <dir>)

krs_output_file(glsl_export .glsl       --scene tree --output <file>)
krs_output_file(glsl_export .png        --scene tree --reference <file> --width 8 --height 8)
krs_output_folder(glsl_export tree.glsl --output-dir <dir>)

krs_output_file(krs_export .ply         --scene rock --resolution 8 --output <file>)
krs_output_file(krs_export .obj         --scene rock --resolution 8 --output <file>)
if(KRS_WITH_GLTF)
    krs_output_file(krs_export .glb     --scene rock --resolution 8 --output <file>)
    krs_output_file(krs_export .gltf    --scene tree --resolution 8 --instance-levels 1 --instances --output <file>)
endif()

# Under xvfb-run (LAUNCHER): the screenshot of a headless frame, the viewer's one file.
krs_output_file(krs_view .png           --scene tree --width 8 --height 8 --frames 1 --screenshot <file>)

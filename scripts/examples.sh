#!/usr/bin/env bash
# Install what is missing, build the examples and render their images into out/.
set -euo pipefail
# shellcheck source=scripts/common.sh
source "$(dirname "${BASH_SOURCE[0]}")/common.sh"

"$repo_root/scripts/install-deps.sh" --examples

# Only the examples: no doctest, Mesa or Google Benchmark needed for pictures.
configure -DKRS_BUILD_EXAMPLES=ON -DKRS_BUILD_TESTS=OFF -DKRS_BUILD_BENCHMARKS=OFF
cmake --build "$build_dir" --parallel "$build_jobs" --target krs_examples

out_dir="$repo_root/out"
mkdir -p "$out_dir"
ran=0
if [ -x "$build_dir/examples/krs_tree" ]; then
    echo "examples.sh: krs_tree -> out/krs_tree.png"
    "$build_dir/examples/krs_tree" --output "$out_dir/krs_tree.png"
    ran=$((ran + 1))
fi
if [ -x "$build_dir/examples/krs_scenes" ]; then
    echo "examples.sh: krs_scenes -> out/{forest,terrain,rock,mirrors,coral,sponge,grass}.png"
    "$build_dir/examples/krs_scenes" --output-dir "$out_dir"
    ran=$((ran + 1))
fi
if [ -x "$build_dir/examples/krs_fractals" ]; then
    echo "examples.sh: krs_fractals -> out/{kifs_*,zoom_*}.png"
    "$build_dir/examples/krs_fractals" --output-dir "$out_dir"
    echo "examples.sh: krs_fractals --slice menger -> out/slice_menger_{distance,gradient}.png"
    "$build_dir/examples/krs_fractals" --slice menger --slice-plane xz --slice-offset 0.1 --width 320 --height 320 \
        --output-dir "$out_dir"
    ran=$((ran + 1))
fi
if [ -x "$build_dir/examples/hypertree_render" ]; then
    echo "examples.sh: hypertree_render -> out/hypertree_{a,b,c,d,forest}.png"
    for t in a b c d; do
        "$build_dir/examples/hypertree_render" --tree "$repo_root/examples/hypertrees/tree_$t.tree" \
            --output "$out_dir/hypertree_$t.png"
    done
    "$build_dir/examples/hypertree_render" --forest "$repo_root/examples/hypertrees/forest.forest" \
        --width 640 --height 360 --output "$out_dir/hypertree_forest.png"
    # The paper's figures 8-12: the '# render' lines of examples/hypertrees/figure* (and a montage).
    echo "examples.sh: hypertree_render -> out/figure{08..12}_*.png, out/figures_8_12.jpg"
    "$repo_root/scripts/render_figures.sh" "$build_dir/examples/hypertree_render" "$out_dir"
    ran=$((ran + 1))
fi
if [ -x "$build_dir/examples/krs_export" ]; then
    # .glb where the build has tinygltf (install-deps.sh --examples installs it), else PLY.
    if "$build_dir/examples/krs_export" --help | grep -q "glb"; then mesh_ext=glb; else mesh_ext=ply; fi
    echo "examples.sh: krs_export -> out/{rock,kifs_menger}.$mesh_ext, out/tree.obj"
    "$build_dir/examples/krs_export" --scene rock --resolution 128 --output "$out_dir/rock.$mesh_ext"
    "$build_dir/examples/krs_export" --scene kifs_menger --resolution 128 --output "$out_dir/kifs_menger.$mesh_ext"
    "$build_dir/examples/krs_export" --scene tree --resolution 96 --output "$out_dir/tree.obj"
    ran=$((ran + 1))
fi
echo "examples.sh: $ran example(s) rendered into $out_dir"

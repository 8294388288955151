#!/usr/bin/env bash
# render_figures.sh HYPERTREE_RENDER OUT_DIR: renders the paper's figures 8-12 from their
# definition files (examples/hypertrees/figure*.tree and figure*.forest) into OUT_DIR.
#
# Each figure file carries its render settings on lines of the form
#     # render NAME.png OPTION VALUE ...
# (comments, so the tree and forest parsers skip them): hypertree_render is run once per line
# with --tree FILE or --forest FILE, those options and --output OUT_DIR/NAME.png. Used by
# scripts/examples.sh (into out/) and by the tests (examples/CMakeLists.txt), so the pictures
# the README shows are the ones the tests check.
set -euo pipefail
if [ $# -ne 2 ]; then
    echo "usage: render_figures.sh HYPERTREE_RENDER OUT_DIR" >&2
    exit 2
fi
exe=$1
out_dir=$2
figures_dir="$(cd "$(dirname "${BASH_SOURCE[0]}")/../examples/hypertrees" && pwd)"
mkdir -p "$out_dir"
count=0
for file in "$figures_dir"/figure*.tree "$figures_dir"/figure*.forest; do
    [ -e "$file" ] || continue
    case "$file" in
        *.forest) source_option=--forest ;;
        *) source_option=--tree ;;
    esac
    lines=$(grep -E '^# render ' "$file" || true)
    if [ -z "$lines" ]; then
        echo "render_figures.sh: $file has no '# render NAME.png OPTIONS' line" >&2
        exit 1
    fi
    while read -r _hash _render name options; do
        case "$name" in
            *.png) ;;
            *) echo "render_figures.sh: $file: '$name' is not a .png name" >&2; exit 1 ;;
        esac
        echo "render_figures.sh: $(basename "$file") -> $name"
        # shellcheck disable=SC2086 # the options are words, split on purpose
        "$exe" "$source_option" "$file" $options --output "$out_dir/$name"
        count=$((count + 1))
    done <<< "$lines"
done
echo "render_figures.sh: $count figure image(s) in $out_dir"

# The README's picture (docs/images/hypertree_figures.jpg), when OpenImageIO's oiiotool is there:
# figures 8, 9 (union, cleared), 10 (diffuse, specular) in the top row; 11 (aliased, antialiased:
# crops at 1:1, so that resampling does not smooth the aliasing) and 12 (250 voxels, reduced to
# 100, generated at 100) below, 180 x 180 pixels each.
if command -v oiiotool > /dev/null 2>&1; then
    cd "$out_dir"
    oiiotool figure08_noise.png --cut 224x224+48+48 --resize 180x180 \
        figure09_union.png --cut 200x200+40+40 --resize 180x180 \
        figure09_cleared.png --cut 200x200+40+40 --resize 180x180 \
        figure10_diffuse.png --cut 220x220+30+25 --resize 180x180 \
        figure10_specular.png --cut 220x220+30+25 --resize 180x180 \
        figure11_aliased.png --cut 180x180+62+5 figure11_antialiased.png --cut 180x180+62+5 \
        figure12_lod_250.png --cut 180x180+30+30 figure12_lod_100.png --cut 180x180+30+30 \
        figure12_direct_100.png --cut 180x180+30+30 \
        --mosaic 5x2 --attrib Compression jpeg:88 -o figures_8_12.jpg
    echo "render_figures.sh: montage -> $out_dir/figures_8_12.jpg"
fi

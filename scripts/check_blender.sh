#!/usr/bin/env bash
# Opens every export kind in Blender as a technical artist would, headless (Debian's blender,
# `blender -b --python`), and compares what Blender made with what the programs printed:
#     scripts/check_blender.sh KRS_EXPORT HYPERTREE_RENDER EXPANSION_POINTS [WORK_DIR]
# krs_export writes the tree as GLB, PLY (--up z, as Blender's PLY importer reads z-up) and OBJ with
# kernel colours, and as instanced glTF; hypertree_render writes preset A as VDB with --up z;
# expansion_points (tests/expansion_points.cpp) writes where krs::expand puts each kernel instance.
# check_blender.py (inside Blender) checks: one object per file with the printed vertex and face
# counts, upright (the ground faces +z), the same vertex's colour from the three files within 1/255
# in sRGB, one placed object per printed instance, each kernel's points where the expansion puts
# them (1e-4), the VDB's density, level and part grids and its world box longest along z (the
# tree stands), and one small Cycles frame of the volume. The ctest test check_blender runs it.
# Where Blender is not installed it says so and exits 77 (ctest reports the test skipped).
set -euo pipefail

if [ "$#" -lt 3 ]; then
    echo "usage: scripts/check_blender.sh KRS_EXPORT HYPERTREE_RENDER EXPANSION_POINTS [WORK_DIR]" >&2
    exit 2
fi
krs_export="$(realpath "$1")"
hypertree_render="$(realpath "$2")"
expansion_points="$(realpath "$3")"
work="${4:-$(mktemp -d)}"
for program in "$krs_export" "$hypertree_render" "$expansion_points"; do
    if [ ! -x "$program" ]; then
        echo "check_blender: FAIL: $program is not an executable program" >&2
        exit 1
    fi
done
here="$(cd "$(dirname "${BASH_SOURCE[0]}")" && pwd)"

if ! command -v blender >/dev/null 2>&1; then
    echo "check_blender: skipped: blender is not installed (scripts/install-deps.sh --tests installs Debian's blender)"
    exit 77
fi
mkdir -p "$work"
cd "$work"
rm -f tree.glb tree.ply tree.obj tree_instances.gltf tree_expansion.json tree.vdb frame.png

# The numbers krs_export and hypertree_render print are what Blender must find.
mesh_line=""
for kind in glb ply obj; do
    up=y
    [ "$kind" = ply ] && up=z
    mesh_line="$("$krs_export" --scene tree --resolution 48 --kernel-colors --up "$up" --output "tree.$kind" 2>/dev/null)"
    echo "$mesh_line"
done
triangles="$(sed -n 's/.*: \([0-9]*\) triangles, \([0-9]*\) vertices.*/\1/p' <<<"$mesh_line")"
vertices="$(sed -n 's/.*: \([0-9]*\) triangles, \([0-9]*\) vertices.*/\2/p' <<<"$mesh_line")"
instances_line="$("$krs_export" --scene tree --resolution 48 --instance-levels 8 --instances --output tree_instances.gltf 2>/dev/null | tail -n 1)"
echo "$instances_line"
instance_count="$(sed -n 's/.* parts, \([0-9]*\) instances,.*/\1/p' <<<"$instances_line")"
"$expansion_points" tree tree_expansion.json
"$hypertree_render" --preset A --resolution 64 --width 16 --height 16 --threads 2 --output preview.png --save-vdb tree.vdb \
    --up z 2>/dev/null | tail -n 2
for value in triangles vertices instance_count; do
    if [ -z "${!value}" ]; then
        echo "check_blender: FAIL: could not read $value from the programs' output" >&2
        exit 1
    fi
done

status=0
blender -b --factory-startup --python "$here/check_blender.py" -- \
    glb=tree.glb ply=tree.ply obj=tree.obj vertices="$vertices" triangles="$triangles" \
    instances=tree_instances.gltf instance_count="$instance_count" expansion=tree_expansion.json vdb=tree.vdb \
    render="$work/frame.png" \
    >blender.log 2>&1 || status=$?
grep -E '^check_blender|Error|Traceback' blender.log || true
[ "$status" -eq 0 ] || echo "check_blender: FAIL: blender exited with $status (its whole log: $work/blender.log)"
exit "$status"

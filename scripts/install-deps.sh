#!/usr/bin/env bash
# Install the Debian and npm packages krs needs.  Usage: scripts/install-deps.sh [--tests|--examples|--all|--peers]
#   --tests     compiler, CMake, ccache, GLM, xsimd, doctest, Mesa, glslang and spirv-tools (GLSL tests), Python 3
#               (the check of docs/stability.md's figures), OpenImageIO and CLI11 (a test checks an
#               example's image, others its command line), OpenVDB and NanoVDB (the VDB export's tests
#               read its files with both libraries' own readers), tinygltf and assimp (the mesh
#               tests write glTF/GLB through tinygltf and read PLY, OBJ and GLB back with assimp),
#               Node.js and npm's gltf-validator (package.json, `npm ci` into node_modules/: every
#               glTF/GLB the tests write is validated), Blender (scripts/check_blender.sh imports
#               every export kind headless and renders a frame in Cycles)
#   --examples  compiler, CMake, ccache, GLM, xsimd, OpenImageIO (and its tools, which its CMake
#               config names), CLI11, tinygltf (krs_export's .glb)
#   --all       all of the above plus Google Benchmark (the default)
#   --peers     --all plus the peers the benchmarks compare with: Embree, OpenVDB
# Only missing packages are installed; apt-get update runs only when something is missing, so a
# repeated run costs a dpkg-query (and npm's check of node_modules/) and nothing else.
set -euo pipefail

mode="${1:---all}"

base=(build-essential g++ cmake ccache libglm-dev libxsimd-dev)
tests=(doctest-dev libegl-dev libopengl-dev libgl1-mesa-dri libegl-mesa0 glslang-tools spirv-tools python3
       libopenvdb-dev libnanovdb-dev libboost-dev libboost-iostreams-dev zlib1g-dev # OpenVDB's headers need Boost; its FindOpenVDB, ZLIB
       libtinygltf-dev assimp-utils blender python3-numpy) # Blender's glTF importer needs numpy
examples=(libopenimageio-dev openimageio-tools libcli11-dev libtinygltf-dev)
benchmarks=(libbenchmark-dev)
peers=(libembree-dev libopenvdb-dev libboost-dev libboost-iostreams-dev zlib1g-dev) # OpenVDB's headers need Boost; its FindOpenVDB, ZLIB

needs_npm=true
case "$mode" in
    --tests) wanted=("${base[@]}" "${tests[@]}" "${examples[@]}") ;;
    --examples) wanted=("${base[@]}" "${examples[@]}") needs_npm=false ;;
    --all) wanted=("${base[@]}" "${tests[@]}" "${examples[@]}" "${benchmarks[@]}") ;;
    --peers) wanted=("${base[@]}" "${tests[@]}" "${examples[@]}" "${benchmarks[@]}" "${peers[@]}") ;;
    -h | --help)
        sed -n '2,17p' "$0" | sed 's/^# \{0,1\}//'
        exit 0
        ;;
    *)
        echo "install-deps.sh: unknown option '$mode' (use --tests, --examples, --all or --peers)" >&2
        exit 2
        ;;
esac

# Node.js and npm from Debian only where the machine has no node and npm of its own (a Node.js
# from elsewhere provides npm itself and conflicts with Debian's npm package).
if $needs_npm && ! { command -v node && command -v npm; } >/dev/null 2>&1; then
    wanted+=(nodejs npm)
fi

missing=()
for pkg in "${wanted[@]}"; do
    if ! dpkg-query -W -f='${Status}' "$pkg" 2>/dev/null | grep -q 'install ok installed'; then
        missing+=("$pkg")
    fi
done

# The npm packages: package-lock.json's exact versions into the repository's node_modules/, again
# only when node_modules/ is missing or older than the lockfile.
install_npm_packages() {
    $needs_npm || return 0
    local root
    root="$(cd "$(dirname "${BASH_SOURCE[0]}")/.." && pwd)"
    if [ -f "$root/node_modules/.package-lock.json" ] &&
        [ "$root/node_modules/.package-lock.json" -nt "$root/package-lock.json" ]; then
        echo "install-deps.sh: npm packages (package-lock.json) are installed in node_modules/"
        return 0
    fi
    echo "install-deps.sh: npm ci (package-lock.json into node_modules/)"
    (cd "$root" && npm ci --no-audit --no-fund)
}

if [ "${#missing[@]}" -eq 0 ]; then
    echo "install-deps.sh: all ${#wanted[@]} packages for $mode are installed"
    install_npm_packages
    exit 0
fi

if [ "$(id -u)" -eq 0 ]; then
    as_root=()
elif command -v sudo >/dev/null 2>&1; then
    as_root=(sudo)
else
    echo "install-deps.sh: need root (or sudo) to install: ${missing[*]}" >&2
    exit 1
fi

echo "install-deps.sh: installing ${missing[*]}"
export DEBIAN_FRONTEND=noninteractive
"${as_root[@]}" env DEBIAN_FRONTEND=noninteractive apt-get update -q
"${as_root[@]}" env DEBIAN_FRONTEND=noninteractive \
    apt-get install -y -q --no-install-recommends "${missing[@]}"
install_npm_packages

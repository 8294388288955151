# shellcheck shell=bash
# shellcheck disable=SC2034 # the variables are used by the scripts that source this file
# Shared by test.sh and examples.sh (sourced, not run).
# KRS_BUILD_DIR overrides the build directory (default: build/ in the repo).

repo_root="$(cd "$(dirname "${BASH_SOURCE[0]}")/.." && pwd)"
build_dir="${KRS_BUILD_DIR:-$repo_root/build}"
build_jobs="$(nproc 2>/dev/null || echo 2)"

# On CI keep ccache's files inside the build tree (no writes to $HOME; one directory to cache).
if [ "${CI:-}" = "true" ]; then
    export CCACHE_DIR="${CCACHE_DIR:-$build_dir/.ccache}"
fi
export CCACHE_BASEDIR="${CCACHE_BASEDIR:-$repo_root}"

# configure [cmake -D options...]: (re)configure the build directory as Release.
configure() {
    cmake -S "$repo_root" -B "$build_dir" -DCMAKE_BUILD_TYPE=Release "$@"
}

# shellcheck shell=bash
# shellcheck disable=SC2034 # the variables are used by the scripts that source this file
# Shared by test.sh and examples.sh (sourced, not run).
# KRS_BUILD_DIR overrides the build directory (default: build/ in the repo).

repo_root="$(cd "$(dirname "${BASH_SOURCE[0]}")/.." && pwd)"
build_dir="${KRS_BUILD_DIR:-$repo_root/build}"
build_jobs="$(nproc 2>/dev/null || echo 2)"

# On CI, ccache's files go to /var/tmp/krs-ccache, outside the clean clone (so a later run on the
# same machine reuses what an earlier one compiled; ccache keys on the preprocessed source and the
# flags, so a hit is the object a compile would make) and outside $HOME. Elsewhere ccache's default.
if [ "${CI:-}" = "true" ]; then
    export CCACHE_DIR="${CCACHE_DIR:-/var/tmp/krs-ccache}"
    export CCACHE_MAXSIZE="${CCACHE_MAXSIZE:-8G}"
fi
export CCACHE_BASEDIR="${CCACHE_BASEDIR:-$repo_root}"

# configure [cmake -D options...]: (re)configure the build directory as Release.
configure() {
    cmake -S "$repo_root" -B "$build_dir" -DCMAKE_BUILD_TYPE=Release "$@"
}

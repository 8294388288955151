#!/usr/bin/env bash
# Build the libFuzzer target for the scene builders with clang (ASan + UBSan) in its own build tree
# and run it over a copy of fuzz/corpus/builders/. Exits nonzero on any crash; a crashing input is
# left as crash-* in the working directory printed below (add it to the corpus once fixed).
#   FUZZ_RUNS   executions (default 1000000)
#   FUZZ_BUILD_DIR  build tree (default: <build dir>-fuzz)
set -euo pipefail
# shellcheck source=scripts/common.sh
source "$(dirname "${BASH_SOURCE[0]}")/common.sh"

fuzz_dir="${FUZZ_BUILD_DIR:-${build_dir}-fuzz}"
CXX="${CXX:-clang++}" cmake -S "$repo_root" -B "$fuzz_dir" -DCMAKE_BUILD_TYPE=Release \
    -DKRS_BUILD_FUZZERS=ON -DKRS_BUILD_TESTS=OFF -DKRS_BUILD_EXAMPLES=OFF -DKRS_BUILD_BENCHMARKS=OFF
cmake --build "$fuzz_dir" --parallel "$build_jobs" --target krs_fuzz_builders

work="$fuzz_dir/fuzz-run"
rm -rf "$work"
mkdir -p "$work/corpus"
cp "$repo_root"/fuzz/corpus/builders/* "$work/corpus/"
cd "$work"
echo "fuzz: running in $work"
ASAN_OPTIONS=detect_leaks=1:abort_on_error=1 UBSAN_OPTIONS=print_stacktrace=1 \
    "$fuzz_dir/fuzz/krs_fuzz_builders" -runs="${FUZZ_RUNS:-1000000}" -print_final_stats=1 corpus

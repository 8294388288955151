#!/usr/bin/env bash
# Build the libFuzzer targets with clang (ASan + UBSan) in their own build tree and run each over a
# copy of its seed corpus fuzz/corpus/<target>/. Exits nonzero on any crash; a crashing input is
# left as crash-* in the target's working directory printed below (once fixed, add it to
# fuzz/crashers/<target>/ so ctest replays it).
#   scripts/fuzz.sh [target...]   targets: builders, fractals, definition, binary (default: all,
#                                 one after the other)
#   FUZZ_RUNS       executions per target (default 1000000)
#   FUZZ_BUILD_DIR  build tree (default: <build dir>-fuzz)
# A target with a dictionary fuzz/<target>.dict (keywords of a text format) gets it as -dict=.
# The file readers (definition, binary) run with -malloc_limit_mb=256: they must refuse a huge
# claimed size before allocating it, so one allocation that large is a failure.
set -euo pipefail
# shellcheck source=scripts/common.sh
source "$(dirname "${BASH_SOURCE[0]}")/common.sh"

targets=("$@")
[ ${#targets[@]} -gt 0 ] || targets=(builders fractals definition binary)

fuzz_dir="${FUZZ_BUILD_DIR:-${build_dir}-fuzz}"
CXX="${CXX:-clang++}" cmake -S "$repo_root" -B "$fuzz_dir" -DCMAKE_BUILD_TYPE=Release \
    -DKRS_BUILD_FUZZERS=ON -DKRS_BUILD_TESTS=OFF -DKRS_BUILD_EXAMPLES=OFF -DKRS_BUILD_BENCHMARKS=OFF
for target in "${targets[@]}"; do
    cmake --build "$fuzz_dir" --parallel "$build_jobs" --target "krs_fuzz_$target"
done

for target in "${targets[@]}"; do
    work="$fuzz_dir/fuzz-run-$target"
    rm -rf "$work"
    mkdir -p "$work/corpus"
    cp "$repo_root/fuzz/corpus/$target"/* "$work/corpus/"
    options=(-runs="${FUZZ_RUNS:-1000000}" -print_final_stats=1)
    case "$target" in definition | binary) options+=(-malloc_limit_mb=256) ;; esac
    [ ! -f "$repo_root/fuzz/$target.dict" ] || options+=(-dict="$repo_root/fuzz/$target.dict")
    echo "fuzz: $target running in $work"
    (cd "$work" && ASAN_OPTIONS=detect_leaks=1:abort_on_error=1 UBSAN_OPTIONS=print_stacktrace=1 \
        "$fuzz_dir/fuzz/krs_fuzz_$target" "${options[@]}" corpus)
done

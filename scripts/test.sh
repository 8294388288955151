#!/usr/bin/env bash
# Install what is missing, build everything (library checks, tests, examples, benchmarks) and run
# the whole test suite.  Exits nonzero on any failure.  CI runs exactly this (.ci/run).
set -euo pipefail
# shellcheck source=scripts/common.sh
source "$(dirname "${BASH_SOURCE[0]}")/common.sh"

"$repo_root/scripts/install-deps.sh" --all

# Examples are built too: a test checks an example's image.
configure -DKRS_BUILD_TESTS=ON -DKRS_BUILD_EXAMPLES=ON -DKRS_BUILD_BENCHMARKS=ON
cmake --build "$build_dir" --parallel "$build_jobs"

# Fewer ctest jobs than test processes would leave cores idle; every test case is its own process.
cd "$build_dir"
ctest --output-on-failure --parallel "$build_jobs" --timeout 900

# The suite under AddressSanitizer and UndefinedBehaviorSanitizer, in its own build tree: the
# portable variant at -O1 (tests/CMakeLists.txt says why; examples, benchmarks and the packaging
# checks add nothing there).
sanitize_dir="${build_dir}-sanitize"
cmake -S "$repo_root" -B "$sanitize_dir" -DCMAKE_BUILD_TYPE=Release -DKRS_BUILD_TESTS=ON \
    -DKRS_BUILD_EXAMPLES=OFF -DKRS_BUILD_BENCHMARKS=OFF -DKRS_SANITIZERS=address,undefined
cmake --build "$sanitize_dir" --parallel "$build_jobs"
cd "$sanitize_dir"
ASAN_OPTIONS=detect_leaks=1:abort_on_error=1 UBSAN_OPTIONS=print_stacktrace=1 \
    ctest --output-on-failure --parallel "$build_jobs" --timeout 900 --exclude-regex "consumer"

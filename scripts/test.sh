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

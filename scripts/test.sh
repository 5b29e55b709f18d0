#!/usr/bin/env bash
# The test command of a fresh machine: installs the dependencies (Debian packages), builds
# with warnings as errors and runs every test through CTest.
#   scripts/test.sh            # preset "ci" (RelWithDebInfo, -Werror)
#   PRESET=asan scripts/test.sh  # the same under AddressSanitizer + UBSan
set -euo pipefail
cd "$(dirname "$0")/.."
PRESET="${PRESET:-ci}"

scripts/setup.sh
cmake --preset "$PRESET"
cmake --build --preset "$PRESET" -j "$(nproc)"
ctest --preset "$PRESET" -j "$(nproc)"

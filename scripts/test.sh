#!/usr/bin/env bash
# The test command of a fresh machine: installs the dependencies (Debian packages, including
# the Python stack the tools' tests use), builds
# with warnings as errors and runs every test through CTest.
#   scripts/test.sh            # preset "ci" (RelWithDebInfo, -Werror)
#   PRESET=asan scripts/test.sh  # the same under AddressSanitizer + UBSan
set -euo pipefail
cd "$(dirname "$0")/.."
PRESET="${PRESET:-ci}"

scripts/setup.sh --python
cmake --preset "$PRESET"
cmake --build --preset "$PRESET" -j "$(nproc)"
ctest --preset "$PRESET" -j "$(nproc)"

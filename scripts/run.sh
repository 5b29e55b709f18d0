#!/usr/bin/env bash
# The main job of a fresh machine: installs the dependencies, builds the release binaries
# and runs the lifting demo on the shipped sample DTM with the default configuration.
# Extra arguments go to the demo (see: build/release/tools/lift_demo/vp_lift_demo --help).
set -euo pipefail
cd "$(dirname "$0")/.."

scripts/setup.sh
cmake --preset release >/dev/null
cmake --build --preset release -j "$(nproc)" --target vp_lift_demo
exec build/release/tools/lift_demo/vp_lift_demo --config config/default.yaml "$@"

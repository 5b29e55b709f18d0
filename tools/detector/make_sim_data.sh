#!/usr/bin/env bash
# Renders the simulated training or evaluation set of the detector: one short sequence per seed,
# the scene cycling through intersection / straight / parking, altitude, tilt, light and lens
# drawn from the seed (docs/simulator.md). Seeds are what separate training from evaluation:
# the model card lists the ranges used for each (training 1000-1999, held-out 9000-9999).
#
#   tools/detector/make_sim_data.sh OUTDIR FIRST_SEED COUNT [FRAMES=4] [WIDTHxHEIGHT=1296x1024]
#
# Environment: VP_SIMULATE (default build/release/tools/simulator/vp_simulate, else build/ci),
# THREADS (default 2), SIM_ARGS (further vp_simulate options for every sequence, e.g.
# "--two-tone-share 0.35"). Sequences already complete in OUTDIR are skipped, so an interrupted
# run resumes where it stopped.
set -euo pipefail
if [[ $# -lt 3 || "$1" == "--help" || "$1" == "-h" ]]; then
  sed -n '2,12p' "$0" | sed 's/^# \{0,1\}//'
  exit $([[ $# -lt 3 ]] && [[ "${1:-}" != "--help" && "${1:-}" != "-h" ]] && echo 2 || echo 0)
fi
out=$1 first=$2 count=$3 frames=${4:-4} size=${5:-1296x1024}
width=${size%x*} height=${size#*x}
root=$(cd "$(dirname "$0")/../.." && pwd)
sim=${VP_SIMULATE:-}
if [[ -z "$sim" ]]; then
  source "$root/scripts/lib/find_build.sh"
  build=$(vp_find_build tools/simulator/vp_simulate)
  [[ -z "$build" ]] || sim="$build/tools/simulator/vp_simulate"
fi
[[ -x "$sim" ]] || { echo "make_sim_data.sh: vp_simulate not found; build first (cmake --preset release && cmake --build build/release)" >&2; exit 1; }
scenes=(intersection straight parking)
mkdir -p "$out"
for ((i = 0; i < count; i++)); do
  seed=$((first + i))
  scene=${scenes[$((seed % 3))]}
  dir="$out/${scene}_$seed"
  if [[ -f "$dir/sequence.yaml" ]] && [[ $(ls "$dir/frames" | wc -l) -ge $frames ]]; then continue; fi
  rm -rf "$dir"
  "$sim" --scene "$scene" --seed "$seed" --frames "$frames" --out "$dir" \
    --width "$width" --height "$height" --threads "${THREADS:-2}" ${SIM_ARGS:-} >/dev/null
done
echo "make_sim_data.sh: $count sequences in $out"

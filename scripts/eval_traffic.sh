#!/usr/bin/env bash
# Measures the traffic analysis against ground truth (docs/traffic.md, "Evaluation"): per
# sequence vp_firmware_app --every-frame --no-dds writes the trajectory file, then one
# vp_traffic_eval run compares the analysis of the app's tracks with that of the ground truth
# (gate counts, turning movements, queue lengths) and prints the figures. Renders nothing: give
# recorded sequences with ground truth and a site file (vp_simulate writes both).
#
#   scripts/eval_traffic.sh [options] OUTDIR SEQUENCE_DIR...
#
# Options:
#   --config FILE     app configuration (default config/default.yaml)
#   --build DIR       build folder with the binaries (default build/release, else build/ci)
#   --period S        statistics period of the queue comparison, s (default 10)
#   --details         the gate count tables per sequence
#   --require-acceptance  exit status 3 when a total misses its acceptance threshold
#   -h, --help        this text
#
# Outputs in OUTDIR: <sequence>_tracks.csv, <sequence>.log (the app's summary), traffic.txt
# (the figures, also printed).
set -euo pipefail
usage() { sed -n '2,19p' "$0" | sed 's/^# \{0,1\}//'; }
root=$(cd "$(dirname "$0")/.." && pwd)
config="$root/config/default.yaml"
build=""
eval_args=()
while [[ $# -gt 0 ]]; do
  case "$1" in
    --config) config=$(realpath "${2:?--config needs a file}"); shift 2 ;;
    --build) build=$(realpath "${2:?--build needs a folder}"); shift 2 ;;
    --period) eval_args+=(--period "${2:?--period needs seconds}"); shift 2 ;;
    --details|--require-acceptance) eval_args+=("$1"); shift ;;
    -h|--help) usage; exit 0 ;;
    -*) echo "eval_traffic.sh: unknown option '$1' (see --help)" >&2; exit 2 ;;
    *) break ;;
  esac
done
[[ $# -ge 2 ]] || { usage >&2; exit 2; }
out=$(realpath -m "$1"); shift
source "$root/scripts/lib/find_build.sh"
[[ -n "$build" ]] || build=$(vp_find_build tools/traffic_eval/vp_traffic_eval)
app="$build/firmware_app/vp_firmware_app"
evaluate="$build/tools/traffic_eval/vp_traffic_eval"
[[ -x "$app" && -x "$evaluate" ]] || { echo "eval_traffic.sh: vp_firmware_app / vp_traffic_eval not built in '${build:-build/release or build/ci}'" >&2; exit 1; }
[[ -f "$config" ]] || { echo "eval_traffic.sh: no configuration file '$config'" >&2; exit 1; }
mkdir -p "$out"

args=(--config "$config")
for seq in "$@"; do
  seq=$(realpath "$seq")
  name=$(basename "$seq")
  [[ -f "$seq/sequence.yaml" ]] || { echo "eval_traffic.sh: '$seq' is not a recorded sequence (no sequence.yaml)" >&2; exit 1; }
  "$app" --config "$config" --sequence "$seq" --every-frame --no-dds --quiet \
     --trajectory-csv "$out/${name}_tracks.csv" \
     > "$out/$name.log" 2>&1 || { echo "eval_traffic.sh: the app failed on $seq (see $out/$name.log)" >&2; exit 1; }
  args+=(--sequence "$seq" --tracks "$out/${name}_tracks.csv")
done
set +e
"$evaluate" "${args[@]}" "${eval_args[@]}" | tee "$out/traffic.txt"
rc=${PIPESTATUS[0]}
set -e
exit "$rc"

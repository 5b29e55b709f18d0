#!/usr/bin/env bash
# Runs the firmware app offline on recorded sequences with ground truth and evaluates its
# detections and tracks (docs/evaluation.md, "Tracking"): per sequence vp_firmware_app
# --every-frame --no-dds writes the detections file and the trajectory file, then one
# vp_evaluate run over all sequences writes report.md / report.json.
#
#   scripts/eval_tracking.sh [options] OUTDIR SEQUENCE_DIR...
#
# Options:
#   --config FILE     app configuration (default config/default.yaml)
#   --build DIR       build folder with the binaries (default build/release, else build/ci)
#   --set KEY=VALUE   override a top-level-section key of the configuration for this run,
#                     e.g. --set tracking.high_score=0.45 (repeatable; written to OUTDIR/config.yaml)
#   --model-id TEXT   label in the report (default: the config file name)
#   -h, --help        this text
#
# Outputs in OUTDIR: <sequence>_detections.csv, <sequence>_tracks.csv, <sequence>.log (the
# app's summary), config.yaml (the configuration used), eval/report.{md,json}.
set -euo pipefail
usage() { sed -n '2,19p' "$0" | sed 's/^# \{0,1\}//'; }
root=$(cd "$(dirname "$0")/.." && pwd)
config="$root/config/default.yaml"
build=""
model_id=""
sets=()
while [[ $# -gt 0 ]]; do
  case "$1" in
    --config) config=$(realpath "${2:?--config needs a file}"); shift 2 ;;
    --build) build=$(realpath "${2:?--build needs a folder}"); shift 2 ;;
    --set) sets+=("${2:?--set needs KEY=VALUE}"); shift 2 ;;
    --model-id) model_id="${2:?--model-id needs a text}"; shift 2 ;;
    -h|--help) usage; exit 0 ;;
    -*) echo "eval_tracking.sh: unknown option '$1' (see --help)" >&2; exit 2 ;;
    *) break ;;
  esac
done
[[ $# -ge 2 ]] || { usage >&2; exit 2; }
out=$(realpath -m "$1"); shift
source "$root/scripts/lib/find_build.sh"
[[ -n "$build" ]] || build=$(vp_find_build firmware_app/vp_firmware_app)
app="$build/firmware_app/vp_firmware_app"
evaluate="$build/tools/evaluate/vp_evaluate"
[[ -x "$app" && -x "$evaluate" ]] || { echo "eval_tracking.sh: vp_firmware_app / vp_evaluate not built in '${build:-build/release or build/ci}'" >&2; exit 1; }
[[ -f "$config" ]] || { echo "eval_tracking.sh: no configuration file '$config'" >&2; exit 1; }
mkdir -p "$out"

# The configuration of the run: the file with the --set overrides applied (section.key lines
# are replaced in place; the key must exist in the file so a typo fails loudly). It lives
# beside the original while the app runs, because relative paths in a configuration are
# relative to its folder; a copy is kept in OUTDIR.
run_config=$(mktemp "$(dirname "$config")/.eval_tracking.XXXXXX.yaml")
trap 'rm -f "$run_config" "$run_config.new"' EXIT
cp "$config" "$run_config"
for kv in "${sets[@]}"; do
  key=${kv%%=*} value=${kv#*=}
  section=${key%%.*} name=${key#*.}
  [[ "$section" != "$key" && -n "$name" ]] || { echo "eval_tracking.sh: --set '$kv' is not SECTION.KEY=VALUE" >&2; exit 2; }
  if ! awk -v s="$section" -v k="$name" -v v="$value" '
      /^[A-Za-z_]+:/ { insec = ($1 == s ":") }
      insec && $1 == k ":" && !done { match($0, /^ */); printf "%s%s: %s\n", substr($0, 1, RLENGTH), k, v; done = 1; next }
      { print }
      END { exit done ? 0 : 1 }' "$run_config" > "$run_config.new"; then
    echo "eval_tracking.sh: --set '$kv': no key '$name' in section '$section' of $config" >&2; exit 2
  fi
  mv "$run_config.new" "$run_config"
done
cp "$run_config" "$out/config.yaml"

args=()
for seq in "$@"; do
  seq=$(realpath "$seq")
  name=$(basename "$seq")
  [[ -f "$seq/sequence.yaml" ]] || { echo "eval_tracking.sh: '$seq' is not a recorded sequence (no sequence.yaml)" >&2; exit 1; }
  "$app" --config "$run_config" --sequence "$seq" --every-frame --no-dds --quiet \
     --detections-csv "$out/${name}_detections.csv" --trajectory-csv "$out/${name}_tracks.csv" \
     > "$out/$name.log" 2>&1 || { echo "eval_tracking.sh: the app failed on $seq (see $out/$name.log)" >&2; exit 1; }
  grep -h "summary:" "$out/$name.log" | sed "s|^|$name: |" || true
  args+=(--sequence "$seq" --detections "$out/${name}_detections.csv" --tracks "$out/${name}_tracks.csv")
done
"$evaluate" "${args[@]}" --out "$out/eval" --model-id "${model_id:-$(basename "$config")}"

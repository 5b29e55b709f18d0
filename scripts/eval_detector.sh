#!/usr/bin/env bash
# Evaluates the detector on held-out data as the model card does: vp_detect_images on every
# frame of each simulated sequence (and optionally on the real held-out images), then one
# vp_evaluate run per kind of data writing report.md / report.json (docs/evaluation.md).
#
#   scripts/eval_detector.sh [options] OUTDIR [SEQUENCE_DIR...]
#
# Options:
#   --build DIR          build folder with the binaries (default build/release, else build/ci)
#   --detector FILE      first-stage ONNX (default models/detector/detector_int8.onnx)
#   --crop FILE          crop network ONNX (default models/detector/crop_int8.onnx)
#   --backend B          int8 | fp32 | int8-dnnl | auto (default int8, the model card's reference)
#   --real DIR           also the real images of this YOLO folder ...
#   --split FILE         ... those listed as val_stems in this split (scripts/make_eval_data.sh
#                        writes it: DATA_ROOT/real_split.json); required with --real
#   --gsd-m G            metres per pixel of the real images (default 0.047, CATS Madison)
#   --real-scale S       working scale of the real images (default 0.4, at which every CATS
#                        figure of the model card was measured; vp_detect_images' own default
#                        from the GSD, 0.047 / 0.12 = 0.392, gives recall 88.4 % instead of 89.8 %)
#   --detect-arg ARG     one more argument for every vp_detect_images run, repeatable, e.g.
#                        --detect-arg --min-vehicle-probability --detect-arg 0.5
#   --model-id TEXT      label in the reports (default: the detector file's name)
#   -h, --help           this text
#
# Outputs in OUTDIR: <sequence>.csv (detections), eval/report.{md,json}; with --real:
# real.csv, eval_real/report.{md,json}.
set -euo pipefail
usage() { sed -n '2,26p' "$0" | sed 's/^# \{0,1\}//'; }
root=$(cd "$(dirname "$0")/.." && pwd)
build=""
detector="$root/models/detector/detector_int8.onnx"
crop="$root/models/detector/crop_int8.onnx"
backend=int8
real="" split="" gsd=0.047 real_scale=0.4 model_id=""
extra=()
while [[ $# -gt 0 ]]; do
  case "$1" in
    --build) build=$(realpath "${2:?--build needs a folder}"); shift 2 ;;
    --detector) detector=$(realpath "${2:?--detector needs a file}"); shift 2 ;;
    --crop) crop=$(realpath "${2:?--crop needs a file}"); shift 2 ;;
    --backend) backend="${2:?--backend needs int8, fp32, int8-dnnl or auto}"; shift 2 ;;
    --real) real=$(realpath "${2:?--real needs a folder}"); shift 2 ;;
    --split) split=$(realpath "${2:?--split needs a file}"); shift 2 ;;
    --gsd-m) gsd="${2:?--gsd-m needs a number}"; shift 2 ;;
    --real-scale) real_scale="${2:?--real-scale needs a number}"; shift 2 ;;
    --detect-arg) extra+=("${2?--detect-arg needs an argument}"); shift 2 ;;
    --model-id) model_id="${2:?--model-id needs a text}"; shift 2 ;;
    -h|--help) usage; exit 0 ;;
    -*) echo "eval_detector.sh: unknown option '$1' (see --help)" >&2; exit 2 ;;
    *) break ;;
  esac
done
[[ $# -ge 1 ]] || { usage >&2; exit 2; }
out=$(realpath -m "$1"); shift
[[ $# -ge 1 || -n "$real" ]] || { echo "eval_detector.sh: give sequences, --real, or both" >&2; exit 2; }
[[ -z "$real" || -n "$split" ]] || { echo "eval_detector.sh: --real needs --split (the held-out list)" >&2; exit 2; }
source "$root/scripts/lib/find_build.sh"
[[ -n "$build" ]] || build=$(vp_find_build tools/detect_images/vp_detect_images)
detect="$build/tools/detect_images/vp_detect_images"
evaluate="$build/tools/evaluate/vp_evaluate"
[[ -x "$detect" && -x "$evaluate" ]] || { echo "eval_detector.sh: vp_detect_images / vp_evaluate not built in '${build:-build/release or build/ci}'" >&2; exit 1; }
for f in "$detector" "$crop"; do
  [[ -f "$f" ]] || { echo "eval_detector.sh: no model file '$f'" >&2; exit 1; }
done
model_id=${model_id:-$(basename "$detector")}
common=(--detector "$detector" --crop "$crop" --backend "$backend" --threads "$(nproc)" "${extra[@]}")
mkdir -p "$out"

if [[ $# -ge 1 ]]; then
  args=()
  for seq in "$@"; do
    seq=$(realpath "$seq")
    name=$(basename "$seq")
    [[ -f "$seq/sequence.yaml" ]] || { echo "eval_detector.sh: '$seq' is not a recorded sequence (no sequence.yaml)" >&2; exit 1; }
    "$detect" --sequence "$seq" --out "$out/$name.csv" "${common[@]}" > "$out/$name.log" 2>&1 ||
      { echo "eval_detector.sh: vp_detect_images failed on $seq (see $out/$name.log)" >&2; exit 1; }
    args+=(--sequence "$seq" --detections "$out/$name.csv")
  done
  "$evaluate" "${args[@]}" --out "$out/eval" --model-id "$model_id"
fi
if [[ -n "$real" ]]; then
  "$detect" --images "$real" --list "$split" --gsd-m "$gsd" --working-scale "$real_scale" --out "$out/real.csv" "${common[@]}" \
    > "$out/real.log" 2>&1 || { echo "eval_detector.sh: vp_detect_images failed on $real (see $out/real.log)" >&2; exit 1; }
  "$evaluate" --yolo "$real" --detections "$out/real.csv" --val-list "$split" \
    --out "$out/eval_real" --model-id "$model_id"
fi

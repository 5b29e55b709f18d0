#!/usr/bin/env bash
# Measures the detector on the two real validation sets (docs/evaluation.md, "Real footage") at
# their working scale and at scales around it: bev-intersection-de (rotated boxes with driving
# direction; tools/detector/eval_rotated_real.py) and the CATS Madison held-out split (YOLO;
# vp_evaluate --yolo). A real set's figures move by a point or more when the working scale
# changes by a fraction of a percent (the detector's stride-4 grid falls elsewhere on the cars,
# and the verifier's borderline decisions flip), so a single scale is one draw: the sweep gives
# the mean, min and max over the scales, the nominal one among them.
#
#   scripts/eval_real.sh [options] OUTDIR
#
# Options:
#   --build DIR        build folder with the binaries (default build/release, else build/ci)
#   --real DIR         the real data folder (default ../shared/data/real beside the repository)
#   --split FILE       the CATS split (scripts/make_eval_data.sh DATA real_split writes it);
#                      without it the CATS set is left out
#   --steps N          scales on each side of the nominal one (default 5: 11 scales)
#   --step S           relative distance between them (default 0.004: the sweep spans +-2 %)
#   --detect-arg ARG   one more argument for every vp_detect_images run (repeatable), e.g.
#                      --detect-arg --crop --detect-arg CANDIDATE/crop_int8.onnx
#   -h, --help         this text
#
# Nominal scales: bev 0.567 at 0.068 m/px, CATS 0.4 at 0.047 m/px (the model card's). Outputs in
# OUTDIR: bev_<scale>.csv/.txt, cats_<scale>.csv and cats_<scale>/report.md, summary.txt (also
# printed: one line per scale, then the mean, min and max of each figure; bev's P_inside is its
# precision without the false boxes reaching the image border, which that set never labels).
set -euo pipefail
usage() { sed -n '2,26p' "$0" | sed 's/^# \{0,1\}//'; }
root=$(cd "$(dirname "$0")/.." && pwd)
build=""
real="$root/../shared/data/real"
split=""
steps=5
step=0.004
extra=()
while [[ $# -gt 0 ]]; do
  case "$1" in
    --build) build=$(realpath "${2:?--build needs a folder}"); shift 2 ;;
    --real) real=$(realpath "${2:?--real needs a folder}"); shift 2 ;;
    --split) split=$(realpath "${2:?--split needs a file}"); shift 2 ;;
    --steps) steps="${2:?--steps needs a number}"; shift 2 ;;
    --step) step="${2:?--step needs a number}"; shift 2 ;;
    --detect-arg) extra+=("${2:?--detect-arg needs an argument}"); shift 2 ;;
    -h|--help) usage; exit 0 ;;
    -*) echo "eval_real.sh: unknown option '$1' (see --help)" >&2; exit 2 ;;
    *) break ;;
  esac
done
[[ $# -eq 1 ]] || { usage >&2; exit 2; }
[[ "$steps" =~ ^[0-9]+$ ]] || { echo "eval_real.sh: --steps '$steps' is not a whole number" >&2; exit 2; }
out=$(realpath -m "$1")
source "$root/scripts/lib/find_build.sh"
[[ -n "$build" ]] || build=$(vp_find_build tools/detect_images/vp_detect_images)
detect="$build/tools/detect_images/vp_detect_images"
evaluate="$build/tools/evaluate/vp_evaluate"
[[ -x "$detect" && -x "$evaluate" ]] || { echo "eval_real.sh: vp_detect_images / vp_evaluate not built in '${build:-build/release or build/ci}'" >&2; exit 1; }
bev="$real/bev-intersection-de"
cats="$real/cats-madison"
[[ -d "$bev/images" ]] || { echo "eval_real.sh: no real set '$bev'" >&2; exit 1; }
[[ -z "$split" || -d "$cats/images" ]] || { echo "eval_real.sh: no real set '$cats'" >&2; exit 1; }
mkdir -p "$out"
py=/usr/bin/python3

# The scales: nominal * (1 + k * step), k = -steps..steps, printed with 5 decimals.
scales() { awk -v n="$1" -v s="$step" -v k="$steps" 'BEGIN { for (i = -k; i <= k; ++i) printf "%.5f\n", n * (1 + i * s) }'; }

summary="$out/summary.txt"
: > "$summary"
for scale in $(scales 0.567); do
  "$detect" --images "$bev" --gsd-m 0.068 --working-scale "$scale" --out "$out/bev_$scale.csv" \
      "${extra[@]}" > "$out/bev_$scale.log" 2>&1 ||
    { echo "eval_real.sh: vp_detect_images failed on $bev (see $out/bev_$scale.log)" >&2; exit 1; }
  "$py" "$root/tools/detector/eval_rotated_real.py" --root "$bev" --detections "$out/bev_$scale.csv" \
      --out "$out/bev_$scale.json" > "$out/bev_$scale.txt"
  # The set labels no car cut by the image border (CATS labels them): its precision also
  # without the false boxes that reach the border, P_inside.
  echo "bev $scale $(head -n 1 "$out/bev_$scale.txt")  P_inside $("$py" -c 'import json, sys
print("%.3f" % json.load(open(sys.argv[1]))["precision_inside"])' "$out/bev_$scale.json")" |
    tee -a "$summary"
done
if [[ -n "$split" ]]; then
  for scale in $(scales 0.4); do
    "$detect" --images "$cats" --list "$split" --gsd-m 0.047 --working-scale "$scale" \
        --out "$out/cats_$scale.csv" "${extra[@]}" > "$out/cats_$scale.log" 2>&1 ||
      { echo "eval_real.sh: vp_detect_images failed on $cats (see $out/cats_$scale.log)" >&2; exit 1; }
    "$evaluate" --yolo "$cats" --detections "$out/cats_$scale.csv" --val-list "$split" \
        --out "$out/cats_$scale" > /dev/null
    echo "cats $scale $("$py" -c 'import json, sys
m = json.load(open(sys.argv[1]))["measures"]
p, r, f = m["precision"], m["recall"], m["f1"]
print(f"P {p:.3f}  R {r:.3f}  F1 {f:.3f}")' "$out/cats_$scale/report.json")" | tee -a "$summary"
  done
fi
"$py" - "$summary" <<'PY' | tee -a "$summary"
import re, sys
rows = {}
for line in open(sys.argv[1]):
    name = line.split()[0]
    figures = dict((k, float(v)) for k, v in re.findall(r"\b(P|R|F1|P_inside) ([0-9.]+)", line))
    m = re.search(r"reversed (\d+)/(\d+)", line)
    if m:
        figures["reversed %"] = 100.0 * int(m.group(1)) / max(int(m.group(2)), 1)
    rows.setdefault(name, []).append(figures)
for name, runs in rows.items():
    for key in runs[0]:
        values = [r[key] for r in runs]
        print(f"{name} {key}: mean {sum(values) / len(values):.4f}  min {min(values):.4f}  "
              f"max {max(values):.4f}  ({len(values)} scales)")
PY

#!/usr/bin/env bash
# The evaluation scripts end to end on a tiny simulated sequence (8 frames, 648 x 512):
# scripts/eval_detector.sh, scripts/eval_tracking.sh, scripts/eval_traffic.sh and scripts/eval_real.sh run the real
# binaries and leave reports with the measures the docs quote; scripts/make_eval_data.sh knows its sets and
# refuses unknown ones; bad arguments exit 2 with a message.
#   tests/scripts/eval_scripts_test.sh BUILD_DIR
set -euo pipefail
build=$(realpath "${1:?usage: eval_scripts_test.sh BUILD_DIR}")
root=$(cd "$(dirname "$0")/../.." && pwd)
work=$(mktemp -d)
trap 'rm -rf "$work"' EXIT
fail() { echo "FAIL: $*" >&2; exit 1; }

seq="$work/data/intersection_7"
"$build/tools/simulator/vp_simulate" --scene intersection --seed 7 --frames 8 --width 648 \
  --height 512 --threads 1 --out "$seq" 2>/dev/null

# Detector: one report over the sequence, with precision / recall / F1 in [0, 1].
"$root/scripts/eval_detector.sh" --build "$build" "$work/det" "$seq" > "$work/det.out"
[[ -f "$work/det/intersection_7.csv" ]] || fail "eval_detector.sh wrote no detections file"
/usr/bin/python3 - "$work/det/eval/report.json" <<'PY' || fail "eval_detector.sh report"
import json, sys
m = json.load(open(sys.argv[1]))["measures"]
for k in ("precision", "recall", "f1"):
    assert 0.0 <= m[k] <= 1.0, (k, m[k])
assert m["f1"] > 0.5, m["f1"]  # the shipped detector finds most of these vehicles
PY

# vp_detect_images on photos: --gsd-m G sets the working scale G / 0.12 unless it is given.
mkdir -p "$work/photos"
cp "$seq/frames/$(ls "$seq/frames" | head -1)" "$work/photos/"
"$build/tools/detect_images/vp_detect_images" --images "$work/photos" --gsd-m 0.06 \
  --out "$work/photos.csv" > /dev/null 2>&1 || fail "vp_detect_images --gsd-m"
grep -q "^# source: .* working_scale 0.5" "$work/photos.csv" || fail "--gsd-m 0.06: working scale not 0.5"
"$build/tools/detect_images/vp_detect_images" --images "$work/photos" --gsd-m 0.06 \
  --working-scale 0.3 --out "$work/photos.csv" > /dev/null 2>&1 || fail "vp_detect_images --working-scale"
grep -q "^# source: .* working_scale 0.3" "$work/photos.csv" || fail "--working-scale 0.3 not kept"

# Real footage across working scales: a stand-in for bev-intersection-de (the sequence's first
# frame, its vehicles as rotated labels) swept at three scales; one line per scale, then the mean,
# min and max of each figure.
mkdir -p "$work/real/bev-intersection-de/images" "$work/real/bev-intersection-de/labels"
first=$(ls "$seq/frames" | head -1)
cp "$seq/frames/$first" "$work/real/bev-intersection-de/images/"
/usr/bin/python3 - "$seq/ground_truth/objects.csv" "$work/real/bev-intersection-de/labels/${first%.*}.txt" <<'PY'
import csv, sys
rows = [r for r in csv.DictReader(open(sys.argv[1])) if r["frame_id"] == "0"]
with open(sys.argv[2], "w") as f:
    for r in rows:
        f.write(f"car {r['box_cx_px']} {r['box_cy_px']} {r['box_length_px']} {r['box_width_px']} "
                f"{r['box_angle_rad']}\n")
PY
"$root/scripts/eval_real.sh" --build "$build" --real "$work/real" --steps 1 "$work/real_out" \
  > "$work/real.out" || fail "eval_real.sh failed"
[[ $(grep -c "^bev 0\.5" "$work/real_out/summary.txt") -eq 3 ]] || fail "eval_real.sh: not three scales"
/usr/bin/python3 - "$work/real_out/summary.txt" <<'PY' || fail "eval_real.sh summary"
import re, sys
text = open(sys.argv[1]).read()
scales = [float(m) for m in re.findall(r"^bev (0\.\d+) P", text, re.M)]
assert abs(scales[1] - 0.567) < 1e-9 and abs(scales[0] - 0.567 * 0.996) < 1e-5, scales
p = [float(v) for v in re.findall(r"^bev \S+ P ([0-9.]+)", text, re.M)]
m = re.search(r"^bev P: mean ([0-9.]+)  min ([0-9.]+)  max ([0-9.]+)  \(3 scales\)", text, re.M)
assert m, text
mean, lo, hi = map(float, m.groups())
assert lo == min(p) and hi == max(p) and abs(mean - sum(p) / 3) < 1e-3, (p, m.groups())
inside = [float(v) for v in re.findall(r"^bev \S+ P .* P_inside ([0-9.]+)$", text, re.M)]
assert len(inside) == 3 and all(pi >= pv for pi, pv in zip(inside, p)), (inside, p)
assert re.search(r"^bev P_inside: mean [0-9.]+ ", text, re.M), text
PY
set +e
"$root/scripts/eval_real.sh" --steps x "$work/real_bad" 2> "$work/err"; rc=$?
set -e
[[ $rc -eq 2 ]] && grep -q "not a whole number" "$work/err" || fail "eval_real.sh --steps x: rc $rc"

# Tracking: the app per sequence, then the tracking section with the largest speed errors.
"$root/scripts/eval_tracking.sh" --build "$build" --set perception.working_scale=1.0 \
  "$work/trk" "$seq" > "$work/trk.out"
grep -q "confirm_hits_large" "$work/trk/config.yaml" || fail "eval_tracking.sh kept no config copy"
/usr/bin/python3 - "$work/trk/eval/report.json" <<'PY' || fail "eval_tracking.sh report"
import json, sys
t = json.load(open(sys.argv[1]))["tracking"]
assert t["measures"]["mota"] <= 1.0
errors = t["largest_speed_errors"]
assert 0 < len(errors) <= 10, len(errors)
sums = [e["squared_error_sum"] for e in errors]
assert sums == sorted(sums, reverse=True), sums
assert all(e["samples"] > 0 and e["input"].endswith("intersection_7") for e in errors)
PY

# Traffic: the app's tracks and the ground truth through vp_traffic_eval, figures printed and kept.
"$root/scripts/eval_traffic.sh" --build "$build" --details "$work/trf" "$seq" > "$work/trf.out" \
  || fail "eval_traffic.sh failed"
[[ -f "$work/trf/intersection_7_tracks.csv" ]] || fail "eval_traffic.sh wrote no trajectory file"
grep -q "^intersection_7: 8 frames" "$work/trf/traffic.txt" || fail "eval_traffic.sh: no figures"
for figure in "gate counts: truth" "turning movements: " "queue length: "; do
  grep -q "$figure" "$work/trf.out" || fail "eval_traffic.sh printed no '$figure'"
done

# Bad arguments: exit 2 and say why.
set +e
"$root/scripts/eval_detector.sh" --build "$build" --real "$work" "$work/x" 2> "$work/err"; rc=$?
set -e
[[ $rc -eq 2 ]] && grep -q "needs --split" "$work/err" || fail "--real without --split: rc $rc"
set +e
"$root/scripts/make_eval_data.sh" "$work/sets" no_such_set 2> "$work/err"; rc=$?
set -e
[[ $rc -eq 2 ]] && grep -q "no set 'no_such_set'" "$work/err" || fail "unknown set: rc $rc"
[[ $("$root/scripts/make_eval_data.sh" --list | tail -n +2 | wc -l) -eq 19 ]] || fail "--list"
# The list is read whole first: `grep -q` on a pipe closes it at the first match, and under
# pipefail the writer's SIGPIPE would fail the check now and then.
sets=$("$root/scripts/make_eval_data.sh" --list)
grep -q "^trk_val3 *9300-9305 *60" <<< "$sets" || fail "trk_val3 seeds"
grep -q "^sim_val_full *9000-9012 *4 *2592x2048" <<< "$sets" || fail "sim_val_full seeds and size"
grep -q "^sim_val_pk *9500-9512 *4 *2592x2048" <<< "$sets" || fail "sim_val_pk seeds and size"
grep -q 'sim_val_pk) echo "--pickup-share 1"' "$root/scripts/make_eval_data.sh" || fail "sim_val_pk options"
grep -q "^sim_val4_full *9900-9939 *4 *2592x2048" <<< "$sets" || fail "sim_val4_full seeds and size"
grep -q "^sim_val_ru_plain *9700-9739 *4 *2592x2048" <<< "$sets" || fail "sim_val_ru_plain seeds and size"
grep -q 'sim_val_ru) echo "--road-users"' "$root/scripts/make_eval_data.sh" || fail "sim_val_ru options"
grep -q 'sim_val_tilt42) echo "--tilt-deg 42 --altitude-m 90"' "$root/scripts/make_eval_data.sh" || fail "sim_val_tilt42 options"
echo "eval scripts: ok"

#!/usr/bin/env bash
# The evaluation scripts end to end on a tiny simulated sequence (8 frames, 648 x 512):
# scripts/eval_detector.sh, scripts/eval_tracking.sh and scripts/eval_traffic.sh run the real
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

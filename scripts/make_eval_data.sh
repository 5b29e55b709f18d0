#!/usr/bin/env bash
# Renders the named simulated evaluation and tuning sets that the model card and
# docs/tracking.md quote, with their exact seeds, frame counts and sizes, and writes the real
# images' near-duplicate-free split. The seeds are what keep the sets apart: training uses
# 1000-1999, tuning 5000-5999, held-out 9000-9999 (docs/model_card.md, "Data").
#
#   scripts/make_eval_data.sh DATA_ROOT [SET...]      (default: every set)
#   scripts/make_eval_data.sh --list                  the sets, their seeds and use
#
# Each set becomes DATA_ROOT/<set>/<scene>_<seed>/ (tools/detector/make_sim_data.sh, which
# resumes: complete sequences are skipped). The split becomes DATA_ROOT/real_split.json
# (tools/detector/split_real.py --seed 0, the split every training run holds out).
# Environment: as make_sim_data.sh (VP_SIMULATE, THREADS); REAL (default ../shared/data/real/cats-madison).
set -euo pipefail
root=$(cd "$(dirname "$0")/.." && pwd)

# name  first-seed  count  frames  size  use
sets="sim_tune      5000 9  4   1296x1024  detector tuning (score threshold, calibration)
sim_tune_b    5009 27 4   1296x1024  detector tuning, with sim_tune (verifier threshold, round 6 and 8 choices)
sim_val       9000 13 4   1296x1024  detector held-out
trk_tune      5100 3  50  1296x1024  tracker tuning
trk_tune2     5103 6  60  1296x1024  tracker tuning, with trk_tune (scripts/eval_tracking.sh sweeps)
trk_tune3     5109 12 60  1296x1024  tracker tuning, a second set
trk_val       9100 6  60  1296x1024  tracker held-out, first set
trk_val2      9200 6  60  1296x1024  tracker held-out, second set (used for diagnosis since)
trk_val3      9300 6  60  1296x1024  tracker held-out, third set
sim_tune_full 5000 36 4  2592x2048  detector tuning at the camera's resolution (the seeds of sim_tune + sim_tune_b)
sim_val_full  9000 13 4  2592x2048  detector held-out at the camera's resolution (the seeds of sim_val)
sim_val2_full 9400 40 4  2592x2048  detector held-out, a second and larger set
sim_val_pk    9500 13 4  2592x2048  detector held-out with every SUV drawn as a pickup (front/back of pickups)
sim_val3_full 9600 40 4  2592x2048  detector held-out, a third set of the second's size (confirmatory tests)
sim_val_ru    9700 40 4  2592x2048  detector held-out with motorbikes, bicycles and pedestrians (false boxes on road users)
sim_val_ru_plain 9700 40 4  2592x2048  the same seeds without them (what the road users change)
sim_val_tilt42 9800 20 4  2592x2048  detector held-out seen obliquely: tilt 42 deg from nadir at 90 m
sim_val_nadir 9800 20 4  2592x2048  the same seeds straight down at 90 m (what the tilt changes)
sim_val4_full 9900 40 4  2592x2048  detector held-out, a fourth set of the second's size (the lane prior's confirmatory test)"

# vp_simulate options of a set beyond the defaults (make_sim_data.sh's SIM_ARGS).
set_args() {
  case "$1" in
    sim_val_pk) echo "--pickup-share 1" ;;
    sim_val_ru) echo "--road-users" ;;
    sim_val_tilt42) echo "--tilt-deg 42 --altitude-m 90" ;;
    sim_val_nadir) echo "--tilt-deg 0 --altitude-m 90" ;;
  esac
}

usage() { sed -n '2,13p' "$0" | sed 's/^# \{0,1\}//'; }
case "${1:-}" in
  -h|--help) usage; exit 0 ;;
  --list) printf '%-16s %-11s %-7s %-10s %s\n' set seeds frames size use
          while read -r name first count frames size use; do
            printf '%-16s %-11s %-7s %-10s %s\n' "$name" "$first-$((first + count - 1))" "$frames" "$size" "$use"
          done <<< "$sets"; exit 0 ;;
  "") usage >&2; exit 2 ;;
  -*) echo "make_eval_data.sh: unknown option '$1' (see --help)" >&2; exit 2 ;;
esac
out=$1; shift
wanted=("$@")
known=$(awk '{print $1}' <<< "$sets")
for w in "${wanted[@]}"; do
  [[ "$w" == real_split ]] || grep -qx "$w" <<< "$known" ||
    { echo "make_eval_data.sh: no set '$w' (known: $(echo $known) real_split)" >&2; exit 2; }
done
want() { [[ ${#wanted[@]} -eq 0 ]] || printf '%s\n' "${wanted[@]}" | grep -qx "$1"; }

mkdir -p "$out"
while read -r name first count frames size use; do
  want "$name" || continue
  echo "make_eval_data.sh: $name (seeds $first-$((first + count - 1)), $frames frames, $size): $use"
  SIM_ARGS="$(set_args "$name")" \
    "$root/tools/detector/make_sim_data.sh" "$out/$name" "$first" "$count" "$frames" "$size"
done <<< "$sets"
if want real_split; then
  real=${REAL:-$root/../shared/data/real/cats-madison}
  /usr/bin/python3 "$root/tools/detector/split_real.py" --real "$real" --out "$out/real_split.json" --seed 0
fi

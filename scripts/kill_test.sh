#!/usr/bin/env bash
# Kills vp_firmware_app with SIGKILL at random moments while it writes its CSV outputs, and
# checks what a power cut or an OOM kill leaves: every CSV output holds its header and whole
# rows only (each line has the header's field count, the file ends with a line break).
#   scripts/kill_test.sh [TRIALS]          (default 20)
# The app replays a short simulated sequence (rendered once with vp_simulate into $OUT,
# 8 frames at the camera's size) in a loop, unpaced, with DDS off, writing the trajectory and
# the detections file; each trial kills it between MIN_S and MAX_S seconds after its loop runs.
# Environment: BUILD (build folder; default build/release, else build/ci), OUT (default
# build/kill_test), MIN_S (default 0.5), MAX_S (default 8), SEED (default: random; printed).
# Exit status: 0 when every trial left whole files, 1 otherwise, 2 on a usage or setup error.
set -euo pipefail
root=$(cd "$(dirname "$0")/.." && pwd)
# shellcheck source=lib/find_build.sh
source "$root/scripts/lib/find_build.sh"

case "${1:-}" in
  -h|--help) sed -n '2,12p' "$0" | sed 's/^# \{0,1\}//'; exit 0 ;;
  ""|[0-9]*) ;;
  *) echo "kill_test.sh: TRIALS must be a number, got '$1' (see --help)" >&2; exit 2 ;;
esac
trials=${1:-20}
build=${BUILD:-$(vp_find_build firmware_app/vp_firmware_app)}
app="$build/firmware_app/vp_firmware_app"
simulate="$build/tools/simulator/vp_simulate"
if [[ -z "$build" || ! -x "$app" || ! -x "$simulate" ]]; then
  echo "kill_test.sh: no build with vp_firmware_app and vp_simulate (cmake --build --preset" \
       "release --target vp_firmware_app vp_simulate)" >&2
  exit 2
fi
out=${OUT:-$root/build/kill_test}
min_s=${MIN_S:-0.5}
max_s=${MAX_S:-8}
seed=${SEED:-$RANDOM}
RANDOM=$seed
mkdir -p "$out"

sequence="$out/sequence"
if [[ ! -f "$sequence/frames.csv" ]]; then
  rm -rf "$sequence"
  echo "kill_test: rendering 8 frames into $sequence (vp_simulate, seed 3)"
  "$simulate" --scene intersection --seed 3 --frames 8 --out "$sequence" >/dev/null
fi

# Whole rows only: prints the problem and fails when a line (metadata lines '#' aside) has not
# the header's field count, or the file is empty or does not end with a line break.
check_csv() {
  local file=$1
  if [[ ! -s "$file" ]]; then
    echo "$file: empty (not even the header)"
    return 1
  fi
  if [[ -n "$(tail -c 1 "$file")" ]]; then
    echo "$file: does not end with a line break (last line: '$(tail -n 1 "$file" | cut -c 1-80)')"
    return 1
  fi
  awk -F, -v file="$file" '
    /^#/ { next }
    fields == 0 { fields = NF; next }
    NF != fields { printf "%s:%d: %d fields, the header has %d\n", file, NR, NF, fields; bad = 1 }
    END { exit bad }' "$file"
}

echo "kill_test: $trials trials, SIGKILL between $min_s and $max_s s after the loop starts (SEED=$seed)"
failed=0
total_tracks=0
total_detections=0
for ((trial = 1; trial <= trials; ++trial)); do
  dir="$out/trial_$trial"
  rm -rf "$dir"
  mkdir -p "$dir"
  "$app" --config "$root/config/default.yaml" --sequence "$sequence" --no-dds --loop --fast \
    --every-frame --quiet --trajectory-csv "$dir/tracks.csv" \
    --detections-csv "$dir/detections.csv" 2>"$dir/app.log" &
  pid=$!
  # The clock starts when the loop runs (model loading takes a while on a busy machine).
  for ((i = 0; i < 1200; ++i)); do
    grep -q 'running: ' "$dir/app.log" 2>/dev/null && break
    kill -0 "$pid" 2>/dev/null || break
    sleep 0.05
  done
  delay=$(awk -v a="$min_s" -v b="$max_s" -v r="$RANDOM" 'BEGIN { printf "%.3f", a + (b - a) * r / 32767 }')
  sleep "$delay"
  if ! kill -KILL "$pid" 2>/dev/null; then
    echo "trial $trial: the app was not running any more (see $dir/app.log)"
    failed=$((failed + 1))
    wait "$pid" || true
    continue
  fi
  wait "$pid" 2>/dev/null || true
  problems=""
  for file in "$dir/tracks.csv" "$dir/detections.csv"; do
    if ! problem=$(check_csv "$file"); then
      problems+="$problem"$'\n'
    fi
  done
  # Rows: the lines after the header (none when even the header is missing).
  tracks=$(awk '!/^#/ { n++ } END { print (n > 1 ? n - 1 : 0) }' "$dir/tracks.csv")
  detections=$(awk '!/^#/ { n++ } END { print (n > 1 ? n - 1 : 0) }' "$dir/detections.csv")
  total_tracks=$((total_tracks + tracks))
  total_detections=$((total_detections + detections))
  if [[ -n "$problems" ]]; then
    failed=$((failed + 1))
    echo "trial $trial: killed after $delay s: BROKEN"
    printf '%s' "$problems" | sed 's/^/  /'
  else
    echo "trial $trial: killed after $delay s: whole rows ($tracks track rows, $detections detection rows)"
  fi
done
echo "kill_test: $((trials - failed)) of $trials trials left whole CSV files ($total_tracks track rows, $total_detections detection rows in all; SEED=$seed)"
[[ $failed -eq 0 ]]

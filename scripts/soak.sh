#!/usr/bin/env bash
# Soak test of vp_firmware_app: a long unpaced run on a looped recording, watching the process
# for leaks.
#   scripts/soak.sh [FRAMES]        (default 100000 frames taken from the source)
# Environment: BUILD (build folder; default build/release, else build/ci), OUT (folder for the
# sequence, configuration, log and samples; default a new /tmp/vp_soak.XXXXXX, never inside the
# repository), INTERVAL_S (seconds between samples, default 5), WIDTH/HEIGHT (frame size of the
# simulated sequence, default 320 x 256), SEQ_FRAMES (frames of the sequence, default 100),
# EVERY_FRAME=1 (the source waits for the loop instead of dropping; default: drop-oldest, as on
# the drone).
#
# What it does:
#   1. renders a small sequence with vp_simulate (intersection scene, seed 11, WIDTH x HEIGHT:
#      a small rig, so that 100 000 frames fit in well under an hour on 2 cores; the loop's
#      code path is the same as at 2592 x 2048, only the image work is smaller);
#   2. runs the app on it: --loop --fast --max-frames FRAMES --no-dds, working scale 1 (one
#      detector tile per frame), the statistics line every INTERVAL_S. Unpaced with drop-oldest
#      (the drone's policy), the source takes frames as fast as the small PNGs decode (~150-250
#      frames/s on 2 cores) and the loop processes what it can (one detector run per frame,
#      ~5-25 frames/s): 100 000 frames take about 7-11 minutes. EVERY_FRAME=1 processes every
#      frame instead (~20 frames/s: 100 000 frames in about 85 minutes);
#   3. every INTERVAL_S samples the process from /proc (RSS, open file descriptors, threads)
#      together with the frames taken so far (from the latest statistics line) into
#      OUT/samples.csv;
#   4. at the end checks (a) RSS at the last sample within 1 % of RSS at the first sample after
#      the warm-up (10 % of FRAMES), (b) fd and thread counts do not grow after the warm-up (the
#      capture thread holds one image file open while it reads it, so a sample may see one fd
#      more: the check is that the second half's most is no more than the first half's), (c) the
#      final summary accounts for every frame: frames_in = processed + dropped + bad +
#      pipeline_errors (frames the processing thread refused).
# Exit status 0 when every check passes, 1 when one fails, 2 on a usage or set-up error.
set -euo pipefail
root=$(cd "$(dirname "$0")/.." && pwd)
frames=${1:-100000}
[[ "$frames" =~ ^[0-9]+$ && "$frames" -ge 100 ]] || { echo "soak.sh: FRAMES must be an integer >= 100, got '$frames'" >&2; exit 2; }
interval=${INTERVAL_S:-5}
width=${WIDTH:-320}
height=${HEIGHT:-256}
seq_frames=${SEQ_FRAMES:-100}
warm=$((frames / 10))

source "$root/scripts/lib/find_build.sh"
build=${BUILD:-$(vp_find_build firmware_app/vp_firmware_app)}
[[ -n "$build" ]] || build="$root/build/release"
app="$build/firmware_app/vp_firmware_app"
sim="$build/tools/simulator/vp_simulate"
for binary in "$app" "$sim"; do
  [[ -x "$binary" ]] || { echo "soak.sh: $binary not built (cmake --build $build --target vp_firmware_app vp_simulate)" >&2; exit 2; }
done
out=${OUT:-$(mktemp -d /tmp/vp_soak.XXXXXX)}
case "$(realpath -m "$out")/" in
  "$root"/*) echo "soak.sh: OUT must be outside the repository ($out)" >&2; exit 2 ;;
esac
mkdir -p "$out"

# 1. The sequence (kept between runs of the same size).
sequence="$out/sequence_${width}x${height}_${seq_frames}"
if [[ ! -f "$sequence/sequence.yaml" ]]; then
  rm -rf "$sequence"
  "$sim" --scene intersection --seed 11 --frames "$seq_frames" --width "$width" --height "$height" \
    --out "$sequence" >"$out/simulate.log" 2>&1 || { echo "soak.sh: vp_simulate failed, see $out/simulate.log" >&2; exit 2; }
fi

# 2. The configuration: the shipped defaults with absolute paths (it lives outside the
# repository), working scale 1 and the statistics line every INTERVAL_S.
config="$out/config.yaml"
sed -e "s|\.\./models/|$root/models/|g" -e "s|\.\./tests/|$root/tests/|g" \
  -e "s|^\(  working_scale:\) [0-9.]*|\1 1.0|" -e "s|^\(  stats_period_s:\) [0-9.]*|\1 $interval|" \
  "$root/config/default.yaml" >"$config"
grep -q "^  working_scale: 1.0" "$config" && grep -q "^  stats_period_s: $interval" "$config" ||
  { echo "soak.sh: could not set working_scale / stats_period_s in $config" >&2; exit 2; }

args=(--config "$config" --sequence "$sequence" --loop --fast --max-frames "$frames" --no-dds)
[[ "${EVERY_FRAME:-0}" == 1 ]] && args+=(--every-frame)
log="$out/app.log"
samples="$out/samples.csv"
echo "soak.sh: $frames frames of $sequence (${width}x${height}, $seq_frames frames looped), warm-up $warm frames; $(nproc) cores, load $(cut -d' ' -f1-3 /proc/loadavg)"
echo "soak.sh: log $log, samples $samples"

# 3. Run and sample.
start=$(date +%s%N)
elapsed() { awk -v s="$start" -v n="$(date +%s%N)" 'BEGIN { printf "%.1f", (n - s) / 1e9 }'; }
"$app" "${args[@]}" >/dev/null 2>"$log" &
pid=$!
trap 'kill "$pid" 2>/dev/null || true' EXIT
echo "elapsed_s,frames_in,processed,rss_kib,fds,threads" >"$samples"
while kill -0 "$pid" 2>/dev/null; do
  sleep "$interval"
  status=$(cat "/proc/$pid/status" 2>/dev/null) || break
  rss=$(awk '/^VmRSS:/ { print $2 }' <<<"$status")
  threads=$(awk '/^Threads:/ { print $2 }' <<<"$status")
  fds=$(ls "/proc/$pid/fd" 2>/dev/null | wc -l) || break
  [[ -n "$rss" && -n "$threads" ]] || break
  counts=$({ grep -a -o "frames in [0-9]* processed [0-9]*" "$log" || true; } | tail -1 | awk '{ print $3 "," $5 }')
  echo "$(elapsed),${counts:-0,0},$rss,$fds,$threads" >>"$samples"
done
status=0
wait "$pid" || status=$?
wall=$(elapsed)

# 4. Checks.
summary=$(grep -a "summary:" "$log" | tail -1 || true)
if [[ "$status" -ne 0 || -z "$summary" ]]; then
  echo "soak.sh: the app failed (exit $status); see $log" >&2
  tail -5 "$log" >&2
  exit 1
fi
field() { grep -o " $1=[0-9.]*" <<<"$summary" | head -1 | cut -d= -f2; }
frames_in=$(field frames_in) processed=$(field processed) dropped=$(field dropped) bad=$(field bad)
refused=$(field pipeline_errors)
awk -F, -v warm="$warm" -v frames_in="$frames_in" -v processed="$processed" -v dropped="$dropped" \
  -v bad="$bad" -v refused="$refused" -v wall="$wall" -v total="$frames" '
  NR == 1 { next }
  { n++ }
  $2 >= warm && !have { have = 1; rss0 = $4; t0 = $1; f0 = $2; fdmin = fdmax = $5; thmin = thmax = $6 }
  have { rss1 = $4; t1 = $1; f1 = $2; if ($5 < fdmin) fdmin = $5; if ($5 > fdmax) fdmax = $5;
         if ($6 < thmin) thmin = $6; if ($6 > thmax) thmax = $6; after++
         fd[after] = $5; th[after] = $6 }
  $4 > peak { peak = $4 }
  END {
    fail = 0
    printf "soak: %d frames in %.0f s (%.1f frames/s taken, %.1f processed/s), %d samples, %d after the warm-up\n",
      total, wall, total / wall, processed / wall, n, after
    if (after < 2) { print "soak: FAIL too few samples after the warm-up (run longer or lower INTERVAL_S)"; exit 1 }
    growth = (rss1 - rss0) / rss0 * 100
    printf "soak: (a) RSS %d KiB at frame %d (%.0f s) -> %d KiB at frame %d (%.0f s): %+.2f %% (limit 1 %%), peak %d KiB: %s\n",
      rss0, f0, t0, rss1, f1, t1, growth, peak, (growth <= 1 && growth >= -1) ? "ok" : "FAIL"
    if (growth > 1 || growth < -1) fail = 1
    half = int(after / 2)
    for (i = 1; i <= after; i++) {
      if (i <= half) { if (fd[i] > fd1) fd1 = fd[i]; if (th[i] > th1) th1 = th[i] }
      else { if (fd[i] > fd2) fd2 = fd[i]; if (th[i] > th2) th2 = th[i] }
    }
    grows = (fd2 > fd1 || th2 > th1 || fdmax - fdmin > 1 || thmin != thmax)
    printf "soak: (b) after the warm-up fds %d..%d (most %d in the first half, %d in the second), threads %d..%d: %s\n",
      fdmin, fdmax, fd1, fd2, thmin, thmax, grows ? "FAIL" : "ok"
    if (grows) fail = 1
    sum = processed + dropped + bad + refused
    printf "soak: (c) frames_in %d = processed %d + dropped %d + bad %d + refused %d = %d: %s\n", frames_in,
      processed, dropped, bad, refused, sum, (sum == frames_in) ? "ok" : "FAIL (" frames_in - sum " unaccounted)"
    if (sum != frames_in) fail = 1
    exit fail
  }' "$samples"

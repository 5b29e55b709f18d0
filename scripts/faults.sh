#!/usr/bin/env bash
# Fault injection against the real vp_firmware_app: each case injects one fault into a run on a
# small simulated recording, prints one figure line and checks what the product promises.
#   scripts/faults.sh [CASE...]      cases: full-disk slow-disk subscriber-churn camera-loss
#                                    telemetry-loss (default: all, in that order)
# Environment: BUILD (build folder; default build/release, else build/ci), OUT (folder for the
# sequence, configuration, logs and outputs; default a new /tmp/vp_faults.XXXXXX, never inside
# the repository), FULL_KIB (size of the full file system, default 48), SLOW_BPS (the slow
# disk's bytes/s, default 8192), CHURN (subscriber starts, default 20), GAP_S (silent source
# of camera-loss, default 8).
#
#   full-disk         the CSV outputs on a 48 KiB tmpfs (mount; without the right to mount: a
#                     file-size limit, ulimit -f): the write error is logged at its frame naming
#                     the file, the loop goes on, exit status 1, the files keep whole rows
#   slow-disk         the detections CSV into a FIFO read at SLOW_BPS: write(2) blocking time
#                     (strace), processing rate, drops and latency against a normal run; no row
#                     lost, every frame accounted for
#   subscriber-churn  CHURN vp_rsu_subscriber processes started and killed (SIGTERM, SIGKILL
#                     alternately) during one paced run with DDS on loopback: no publish error,
#                     frames processed rising, each subscriber's first states are every live
#                     vehicle's newest state (transient-local)
#   camera-loss       a recording with a missing, a truncated and a corrupt frame (bad frames
#                     counted, loop goes on); a source silent for GAP_S s under an emulated
#                     systemd watchdog (longest WATCHDOG=1 gap); the emulated V4L2 unplug tests
#                     (test_v4l2, test_firmware_app) when built
#   telemetry-loss    telemetry.csv with a 0.8 s gap and ending 0.5 s before the frames: stale
#                     frames counted and kept image-only, lifting resumes after the gap
# Exit status: 0 when every check passes, 1 when one fails, 2 on a usage or set-up error.
set -euo pipefail
root=$(cd "$(dirname "$0")/.." && pwd)
all_cases=(full-disk slow-disk subscriber-churn camera-loss telemetry-loss)
case "${1:-}" in
  -h|--help) sed -n '2,29p' "$0" | sed 's/^# \{0,1\}//'; exit 0 ;;
esac
cases=("$@")
[[ ${#cases[@]} -gt 0 ]] || cases=("${all_cases[@]}")
for c in "${cases[@]}"; do
  [[ " ${all_cases[*]} " == *" $c "* ]] ||
    { echo "faults.sh: unknown case '$c' (cases: ${all_cases[*]})" >&2; exit 2; }
done

# shellcheck source=lib/find_build.sh
source "$root/scripts/lib/find_build.sh"
build=${BUILD:-$(vp_find_build firmware_app/vp_firmware_app)}
[[ -n "$build" ]] || build="$root/build/release"
app="$build/firmware_app/vp_firmware_app"
sim="$build/tools/simulator/vp_simulate"
sub="$build/tools/rsu_subscriber/vp_rsu_subscriber"
for binary in "$app" "$sim" "$sub"; do
  [[ -x "$binary" ]] || { echo "faults.sh: $binary not built (cmake --build $build --target vp_firmware_app vp_simulate vp_rsu_subscriber)" >&2; exit 2; }
done
command -v python3 >/dev/null || { echo "faults.sh: python3 is needed" >&2; exit 2; }
py() { python3 "$root/scripts/lib/faults_analysis.py" "$@"; }
out=${OUT:-$(mktemp -d /tmp/vp_faults.XXXXXX)}
case "$(realpath -m "$out")/" in
  "$root"/*) echo "faults.sh: OUT must be outside the repository ($out)" >&2; exit 2 ;;
esac
mkdir -p "$out"
echo "faults.sh: cases ${cases[*]}; build $build; out $out; $(nproc) cores, load $(cut -d' ' -f1-3 /proc/loadavg)"

# The recording: a parking lot seen from 60 m, 320 x 256, 30 frames at 10 Hz (about 11
# vehicles per frame: ~4.7 kB of detection rows and ~2.3 kB of trajectory rows per frame).
sequence="$out/sequence"
if [[ ! -f "$sequence/sequence.yaml" ]]; then
  rm -rf "$sequence"
  "$sim" --scene parking --seed 3 --frames 30 --width 320 --height 256 --altitude-m 60 \
    --out "$sequence" >"$out/simulate.log" 2>&1 ||
    { echo "faults.sh: vp_simulate failed, see $out/simulate.log" >&2; exit 2; }
fi
# The configuration: the shipped defaults, absolute paths, working scale 1 (one detector tile
# per frame), a statistics line every second, DDS in a domain and partition of this run only.
domain=$((100 + RANDOM % 130))
partition="vpfaults$$"
config="$out/config.yaml"
sed -e "s|\.\./models/|$root/models/|g" -e "s|\.\./tests/|$root/tests/|g" \
  -e "s|^\(  working_scale:\) [0-9.]*|\1 1.0|" -e "s|^\(  stats_period_s:\) [0-9.]*|\1 1|" \
  -e "s|^\(  domain_id:\) [0-9]*|\1 $domain|" -e "s|^\(  partition:\) vp |\1 $partition |" \
  "$root/config/default.yaml" >"$config"
grep -q "^  working_scale: 1.0" "$config" && grep -q "^  domain_id: $domain" "$config" &&
  grep -q "^  partition: $partition" "$config" ||
  { echo "faults.sh: could not edit $config" >&2; exit 2; }
# DDS on the loopback interface only: nothing leaves the machine.
export CYCLONEDDS_URI='<CycloneDDS><Domain Id="any"><General><Interfaces><NetworkInterface address="127.0.0.1"/></Interfaces><AllowMulticast>false</AllowMulticast></General><Discovery><ParticipantIndex>auto</ParticipantIndex><MaxAutoParticipantIndex>60</MaxAutoParticipantIndex><Peers><Peer Address="127.0.0.1"/></Peers></Discovery></Domain></CycloneDDS>'

# ---- helpers ---------------------------------------------------------------------------------
failed=()
figures=()
# field KEY LOG: a value of the app's last summary line.
field() { grep -a "summary:" "$2" | tail -1 | grep -o " $1=[0-9.]*" | head -1 | cut -d= -f2; }
# value KEY TEXT: a key=value line of faults_analysis.py's output.
value() { grep -o "^$1=.*" <<<"$2" | head -1 | cut -d= -f2; }
# Whole rows only: the header's field count on every line ('#' metadata aside), a final line
# break (as scripts/kill_test.sh checks).
check_csv() {
  local file=$1
  [[ -s "$file" ]] || { echo "$file: empty"; return 1; }
  [[ -z "$(tail -c 1 "$file")" ]] || { echo "$file: does not end with a line break"; return 1; }
  awk -F, -v file="$file" '
    /^#/ { next }
    fields == 0 { fields = NF; next }
    NF != fields { printf "%s:%d: %d fields, the header has %d\n", file, NR, NF, fields; bad = 1 }
    END { exit bad }' "$file"
}
rows() { awk '!/^#/ { n++ } END { print (n > 1 ? n - 1 : 0) }' "$1"; }
# check CASE CONDITION_STATUS MESSAGE: records a failed check.
check() {
  if [[ "$2" -ne 0 ]]; then
    failed+=("$1: $3")
    echo "  FAIL: $3"
  fi
}
ok_if() { if eval "$1"; then echo 0; else echo 1; fi; }
# A copy of the recording whose frames/ is the original's (only the text files change).
copy_sequence() {
  local to=$1
  rm -rf "$to"
  mkdir -p "$to"
  cp "$sequence"/*.csv "$sequence"/*.yaml "$sequence"/dtm.tif "$to"/
  ln -s "$sequence/frames" "$to/frames"
  [[ -d "$sequence/ground_truth" ]] && ln -s "$sequence/ground_truth" "$to/ground_truth"
  return 0
}
common=(--config "$config" --quiet)

# ---- full-disk -------------------------------------------------------------------------------
case_full_disk() {
  local dir="$out/full-disk" kib=${FULL_KIB:-48} how status=0 log
  rm -rf "$dir"
  mkdir -p "$dir/fs"
  log="$dir/app.log"
  local args=("${common[@]}" --sequence "$sequence" --no-dds --fast --every-frame
              --trajectory-csv "$dir/fs/tracks.csv" --detections-csv "$dir/fs/detections.csv")
  if mount -t tmpfs -o "size=${kib}k,mode=0755" vp_faults_full "$dir/fs" 2>/dev/null; then
    how="a ${kib} KiB tmpfs"
    "$app" "${args[@]}" 2>"$log" || status=$?
    cp "$dir/fs/tracks.csv" "$dir/fs/detections.csv" "$dir/" 2>/dev/null || true
    umount "$dir/fs"
  else
    # No right to mount: the file-size limit is a disk that is full at FULL_KIB per file
    # (EFBIG instead of ENOSPC; SIGXFSZ ignored, as a service would).
    how="a ${kib} KiB file-size limit (ulimit -f)"
    (trap '' XFSZ; ulimit -f "$kib"; exec "$app" "${args[@]}") 2>"$log" || status=$?
    cp "$dir/fs/tracks.csv" "$dir/fs/detections.csv" "$dir/"
  fi
  local processed frames_in errors first_line first_file first_frame first_reason
  processed=$(field processed "$log") frames_in=$(field frames_in "$log")
  errors=$(field output_errors "$log")
  first_line=$(grep -a "write failed at frame" "$log" | head -1 || true)
  first_file=$(sed -n 's/^vp_firmware_app: \([^:]*\): write failed.*/\1/p' <<<"$first_line")
  first_frame=$(sed -n 's/.*write failed at frame \([0-9]*\):.*/\1/p' <<<"$first_line")
  first_reason=$(sed -n 's/.*write failed at frame [0-9]*: \([^(]*\) (.*/\1/p' <<<"$first_line" | sed 's/ *$//')
  local per_file
  per_file=$(grep -a "write failed at frame" "$log" |
    sed -n 's/^vp_firmware_app: \([^:]*\): write failed at frame \([0-9]*\).*/\1 at frame \2/p' |
    sed 's|.*/||' | paste -sd ';' - | sed 's/;/, /g')
  local whole=0 problems=""
  for f in "$dir/tracks.csv" "$dir/detections.csv"; do
    problems+=$(check_csv "$f") || whole=1
  done
  local kept_frames
  kept_frames=$(awk -F, '!/^#/ && NR > 1 && $1 ~ /^[0-9]+$/ { f[$1] = 1 } END { print length(f) }' "$dir/detections.csv")
  local after=$(( ${frames_in:-0} - 1 - ${first_frame:-99999} ))
  figures+=("full-disk: outputs on $how: first error ${per_file:-none} (${first_reason:-?}), $processed/$frames_in frames processed, $after of them after the first error, output_errors=$errors, exit $status; files whole: $(rows "$dir/detections.csv") detection rows of $kept_frames frames, $(rows "$dir/tracks.csv") track rows kept")
  echo "faults: ${figures[-1]}"
  check full-disk "$(ok_if "[[ $status -eq 1 ]]")" "exit status $status, expected 1"
  check full-disk "$(ok_if "[[ -n '$first_frame' && -n '$first_file' ]]")" "no log line naming the file and the frame of the write error"
  check full-disk "$(ok_if "[[ ${processed:-0} -eq ${frames_in:--1} && $after -gt 0 ]]")" "the loop did not go on after the error ($processed of $frames_in processed)"
  check full-disk "$(ok_if "[[ ${errors:-0} -gt 0 ]]")" "output_errors is ${errors:-missing}"
  check full-disk "$whole" "a file is not whole rows: $problems"
}

# ---- slow-disk -------------------------------------------------------------------------------
case_slow_disk() {
  local dir="$out/slow-disk" rate=${SLOW_BPS:-8192} frames=100
  rm -rf "$dir"
  mkdir -p "$dir/normal" "$dir/slow"
  local tracer=()
  if command -v strace >/dev/null && strace -f -qq -o /dev/null true 2>/dev/null; then
    tracer=(strace -f -qq -T -y -e trace=write -e signal=none)
    strace --seccomp-bpf -f -o /dev/null true 2>/dev/null && tracer+=(--seccomp-bpf)
  fi
  # traced LOG COMMAND...: runs COMMAND under strace (its write(2) calls and their durations)
  traced() {
    local log=$1
    shift
    if [[ ${#tracer[@]} -gt 0 ]]; then
      "${tracer[@]}" -o "$log" "$@"
    else
      "$@"
    fi
  }
  local args=("${common[@]}" --sequence "$sequence" --no-dds --loop --max-frames "$frames")
  # The same paced run (10 Hz) twice: detections to a file, then into a FIFO read at SLOW_BPS.
  local status_n=0 status_s=0 reader_status=0
  traced "$dir/normal/strace.log" "$app" "${args[@]}" \
    --detections-csv "$dir/normal/detections.csv" 2>"$dir/normal/app.log" || status_n=$?
  mkfifo "$dir/slow/detections.fifo"
  py slow_reader "$dir/slow/detections.fifo" "$dir/slow/detections.csv" "$rate" &
  local reader=$!
  traced "$dir/slow/strace.log" "$app" "${args[@]}" \
    --detections-csv "$dir/slow/detections.fifo" 2>"$dir/slow/app.log" || status_s=$?
  wait "$reader" || reader_status=$?
  local n s wn="" ws=""
  n="$dir/normal/app.log" s="$dir/slow/app.log"
  if [[ ${#tracer[@]} -gt 0 ]]; then
    wn=$(py write_stalls "$dir/normal/strace.log" detections.csv)
    ws=$(py write_stalls "$dir/slow/strace.log" detections.fifo)
  fi
  local in_s proc_s drop_s bad_s wall_n wall_s
  in_s=$(field frames_in "$s") proc_s=$(field processed "$s") drop_s=$(field dropped "$s") bad_s=$(field bad "$s")
  wall_n=$(field wall_s "$n") wall_s=$(field wall_s "$s")
  local rate_n rate_s
  rate_n=$(awk -v p="$(field processed "$n")" -v w="$wall_n" 'BEGIN { printf "%.1f", p / w }')
  rate_s=$(awk -v p="$proc_s" -v w="$wall_s" 'BEGIN { printf "%.1f", p / w }')
  local stall="write(2) not traced (no strace)"
  if [[ -n "$ws" ]]; then
    stall="detections write(2) median/p99/max $(value write_median_ms "$wn")/$(value write_p99_ms "$wn")/$(value write_max_ms "$wn") ms normal vs $(value write_median_ms "$ws")/$(value write_p99_ms "$ws")/$(value write_max_ms "$ws") ms slow (frame of $(value bytes_median "$ws") bytes at $rate B/s = $(awk -v b="$(value bytes_median "$ws")" -v r="$rate" 'BEGIN { printf "%.0f", b / r * 1000 }') ms), $(value write_total_s "$ws") s of ${wall_s} s blocked in write"
  fi
  figures+=("slow-disk: detections CSV into a FIFO read at $rate B/s: the loop waits in write(2): $stall; processed $(field processed "$n")/$(field frames_in "$n") frames at $rate_n/s normal vs $proc_s/$in_s at $rate_s/s slow ($drop_s dropped); e2e median/p99 $(field e2e_median_ms "$n")/$(field e2e_p99_ms "$n") vs $(field e2e_median_ms "$s")/$(field e2e_p99_ms "$s") ms, queue p99 $(field queue_p99_ms "$n") vs $(field queue_p99_ms "$s") ms; rows: $(rows "$dir/slow/detections.csv") read = $(field detections "$s") detections")
  echo "faults: ${figures[-1]}"
  check slow-disk "$(ok_if "[[ $status_n -eq 0 && $status_s -eq 0 && $reader_status -eq 0 ]]")" "exit status $status_n (normal), $status_s (slow), reader $reader_status"
  check slow-disk "$(ok_if "[[ '$(field output_errors "$s")' == 0 ]]")" "output_errors $(field output_errors "$s") on the slow disk"
  check slow-disk "$(ok_if "[[ $((proc_s + drop_s + bad_s)) -eq $in_s ]]")" "frames_in $in_s != processed $proc_s + dropped $drop_s + bad $bad_s"
  local problem
  problem=$(check_csv "$dir/slow/detections.csv") || check slow-disk 1 "$problem"
  check slow-disk "$(ok_if "[[ $(rows "$dir/slow/detections.csv") -eq $(field detections "$s") ]]")" "rows read from the FIFO ($(rows "$dir/slow/detections.csv")) != detections ($(field detections "$s")): rows lost"
}

# ---- subscriber-churn ------------------------------------------------------------------------
case_subscriber_churn() {
  local dir="$out/subscriber-churn" starts=${CHURN:-20}
  rm -rf "$dir"
  mkdir -p "$dir"
  local log="$dir/app.log"
  "$app" --config "$config" --sequence "$sequence" --loop --max-frames 100000 \
    --trajectory-csv "$dir/tracks.csv" 2>"$log" &
  local pid=$!
  local i
  for ((i = 0; i < 1200; ++i)); do
    grep -q 'running: ' "$log" 2>/dev/null && break
    kill -0 "$pid" 2>/dev/null || break
    sleep 0.05
  done
  sleep 1
  local subs=() sigs=(TERM KILL) first_ms=() missing=0 t0 t_first
  for ((i = 1; i <= starts; ++i)); do
    local csv="$dir/sub_$i.csv"
    t0=$(date +%s%N)
    "$sub" --config "$config" --out "$csv" 2>"$dir/sub_$i.log" &
    local spid=$!
    # Until it has states of two frames (its first states and one live frame), at most 10 s.
    t_first=""
    local j
    for ((j = 0; j < 200; ++j)); do
      if [[ -z "$t_first" ]] && grep -q '^state,' "$csv" 2>/dev/null; then
        t_first=$(date +%s%N)
      fi
      if [[ -n "$t_first" ]] && [[ $(awk -F, '$1 == "state" { t[$4] = 1 } END { print length(t) }' "$csv") -ge 2 ]]; then
        break
      fi
      sleep 0.05
    done
    kill -"${sigs[$((i % 2))]}" "$spid" 2>/dev/null || true
    wait "$spid" 2>/dev/null || true
    subs+=("$csv")
    if [[ -n "$t_first" ]]; then
      first_ms+=($(((t_first - t0) / 1000000)))
    else
      missing=$((missing + 1))
    fi
  done
  sleep 1
  local alive=0 status=0
  kill -0 "$pid" 2>/dev/null && alive=1
  kill -TERM "$pid" 2>/dev/null || true
  wait "$pid" || status=$?
  local result churn_status=0
  result=$(py churn "$dir/tracks.csv" "${subs[@]}" 2>"$dir/churn_check.txt") || churn_status=$?
  # Frames processed at every statistics line: must rise from one line to the next.
  local lines rising
  lines=$(grep -a -o "frames in [0-9]* processed [0-9]*" "$log" | awk '{ print $5 }')
  rising=$(awk 'NR > 1 && $1 <= prev { bad++ } { prev = $1; n++ } END { printf "%d %d", n, bad + 0 }' <<<"$lines")
  local first_median
  first_median=$(printf '%s\n' "${first_ms[@]:-}" | sort -n | awk 'NF { v[n++] = $1 } END { print (n ? v[int(n / 2)] : "-") }')
  figures+=("subscriber-churn: $starts vp_rsu_subscriber starts ($((starts - starts / 2)) ended by SIGKILL, $((starts / 2)) by SIGTERM) during one paced run: app processed $(field processed "$log") frames, dropped $(field dropped "$log"), states_published $(field states_published "$log"), publish_errors $(field publish_errors "$log"), processed rising at all ${rising% *} statistics lines (${rising#* } not); publish median/p99 $(field publish_median_ms "$log")/$(field publish_p99_ms "$log") ms; every subscriber got states ($(value states_min "$result") at least, first after median $first_median ms), first states = every live vehicle's newest state in $(value newest_ok "$result") of $starts (+$(value straddled "$result") matched mid-frame), $(value first_tracks_median "$result") vehicles each (median); exit $status")
  echo "faults: ${figures[-1]}"
  check subscriber-churn "$(ok_if "[[ $alive -eq 1 && $status -eq 0 ]]")" "the app was not running to the end or exited $status"
  check subscriber-churn "$(ok_if "[[ '$(field publish_errors "$log")' == 0 ]]")" "publish_errors $(field publish_errors "$log")"
  check subscriber-churn "$(ok_if "[[ ${rising#* } -eq 0 && ${rising% *} -ge 2 ]]")" "frames processed did not rise at every statistics line"
  check subscriber-churn "$(ok_if "[[ $missing -eq 0 ]]")" "$missing subscribers received no state"
  check subscriber-churn "$churn_status" "first states: $(tr '\n' ' ' <"$dir/churn_check.txt")"
}

# ---- camera-loss -----------------------------------------------------------------------------
case_camera_loss() {
  local dir="$out/camera-loss" gap_s=${GAP_S:-8}
  rm -rf "$dir"
  mkdir -p "$dir"
  # (a) Frames missing or unreadable in a recording (a camera delivering damaged buffers).
  local damaged="$dir/damaged"
  copy_sequence "$damaged"
  rm "$damaged/frames"
  mkdir "$damaged/frames"
  cp "$sequence"/frames/* "$damaged/frames/"
  local f5 f10 f15
  f5=$(awk -F, '$1 == 5 { print $3 }' "$damaged/frames.csv")
  f10=$(awk -F, '$1 == 10 { print $3 }' "$damaged/frames.csv")
  f15=$(awk -F, '$1 == 15 { print $3 }' "$damaged/frames.csv")
  rm "$damaged/$f5"
  truncate -s $(($(stat -c %s "$damaged/$f10") / 2)) "$damaged/$f10"
  head -c 4096 /dev/urandom >"$damaged/$f15"
  local log="$dir/damaged.log" status=0
  "$app" "${common[@]}" --sequence "$damaged" --no-dds --fast --every-frame 2>"$log" || status=$?
  local named=0 f
  for f in "$f5" "$f10" "$f15"; do
    grep -a -q "$(basename "$f")" "$log" && named=$((named + 1))
  done
  # (b) The source silent for GAP_S s (a camera that stops delivering, or a reopen backing off),
  # under systemd's watchdog protocol as the unit sets it (WatchdogSec=5s: WATCHDOG=1 due every
  # 2.5 s, killed after 5 s without one).
  local silent="$dir/silent"
  copy_sequence "$silent"
  local shift_ns=$((gap_s * 1000000000))
  for file in frames.csv telemetry.csv; do
    awk -F, -v OFS=, -v t15="$(awk -F, '$1 == 15 { print $2 }' "$sequence/frames.csv")" -v d="$shift_ns" \
      'NR > 1 && $1 + 0 >= t15 + 0 && FILENAME ~ /telemetry/ { $1 = sprintf("%.0f", $1 + d) }
       NR > 1 && FILENAME ~ /frames/ && $2 + 0 >= t15 + 0 { $2 = sprintf("%.0f", $2 + d) } { print }' \
      "$sequence/$file" >"$silent/$file"
  done
  local wd
  wd=$(py watchdog_gaps "$dir/notify.sock" "$dir/silent.log" -- env NOTIFY_SOCKET="$dir/notify.sock" \
    WATCHDOG_USEC=5000000 "$app" "${common[@]}" --sequence "$silent" --no-dds)
  local units="" unit_status=0
  # (c) The emulated V4L2 driver's unplug tests (tests/platform/v4l2, tests/firmware_app).
  local tv4l2="$build/tests/platform/v4l2/test_v4l2" tapp="$build/tests/firmware_app/test_firmware_app"
  if [[ -x "$tv4l2" ]]; then
    "$tv4l2" --gtest_filter='V4l2CameraTest.UnpluggedDeviceIsReleasedAndReopenedWithBackoff' >"$dir/test_v4l2.log" 2>&1 || unit_status=1
    units+=" | test_v4l2 (fake clock): $(grep -a -o 'unplug: .*' "$dir/test_v4l2.log" | head -1)"
  fi
  if [[ -x "$tapp" ]]; then
    "$tapp" --gtest_filter='AppFaults.CameraDisappearsAndComesBackAndProcessingResumes' >"$dir/test_firmware_app.log" 2>&1 || unit_status=1
    units+=" | test_firmware_app (loop clock): $(grep -a -o 'camera unplugged: .*' "$dir/test_firmware_app.log" | head -1)"
  fi
  [[ -n "$units" ]] || units=" | unplug tests not built (test_v4l2, test_firmware_app)"
  figures+=("camera-loss: recording with frame 5 missing, 10 truncated, 15 corrupt: frames_in $(field frames_in "$log") processed $(field processed "$log") bad $(field bad "$log"), $named of 3 files named in the log, exit $status | source silent ${gap_s} s under WATCHDOG_USEC=5 s: $(value kicks "$wd") WATCHDOG=1, longest gap $(value max_gap_s "$wd") s (systemd kills after 5 s), exit $(value exit "$wd")$units")
  echo "faults: ${figures[-1]}"
  check camera-loss "$(ok_if "[[ $status -eq 0 && '$(field bad "$log")' == 3 && '$(field processed "$log")' == 27 ]]")" "damaged recording: exit $status, bad $(field bad "$log"), processed $(field processed "$log") (expected 0, 3, 27)"
  check camera-loss "$(ok_if "[[ $named -eq 3 ]]")" "only $named of the 3 damaged files named in the log"
  check camera-loss "$(ok_if "[[ '$(value exit "$wd")' == 0 && '$(value kicks "$wd")' -ge 1 ]]")" "silent source run: exit $(value exit "$wd"), $(value kicks "$wd") WATCHDOG=1"
  check camera-loss "$unit_status" "an unplug test failed (see $dir/test_*.log)"
  check camera-loss "$(ok_if "awk -v g='$(value max_gap_s "$wd")' 'BEGIN { exit !(g + 0 > 0 && g < 5) }'")" "longest WATCHDOG=1 gap $(value max_gap_s "$wd") s while the source is silent (systemd kills after 5 s)"
}

# ---- telemetry-loss --------------------------------------------------------------------------
case_telemetry_loss() {
  local dir="$out/telemetry-loss"
  rm -rf "$dir"
  mkdir -p "$dir"
  local seq="$dir/sequence"
  copy_sequence "$seq"
  # No telemetry from frame 10's time to frame 17's (0.8 s), and none after frame 24's.
  local t10 t17 t24
  t10=$(awk -F, '$1 == 10 { print $2 }' "$sequence/frames.csv")
  t17=$(awk -F, '$1 == 17 { print $2 }' "$sequence/frames.csv")
  t24=$(awk -F, '$1 == 24 { print $2 }' "$sequence/frames.csv")
  awk -F, -v a="$t10" -v b="$t17" -v c="$t24" \
    'NR == 1 || !(($1 + 0 >= a + 0 && $1 + 0 <= b + 0) || $1 + 0 > c + 0)' \
    "$sequence/telemetry.csv" >"$seq/telemetry.csv"
  local log="$dir/app.log" status=0
  "$app" "${common[@]}" --sequence "$seq" --no-dds --fast --every-frame \
    --detections-csv "$dir/detections.csv" 2>"$log" || status=$?
  local max_age lookahead result check_status=0
  max_age=$(sed -n 's/^  max_age_s: *\([0-9.]*\).*/\1/p' "$config" | head -1)
  lookahead=$(sed -n 's/^  replay_lookahead_s: *\([0-9.]*\).*/\1/p' "$config" | head -1)
  result=$(py telemetry "$seq" "$dir/detections.csv" "$max_age" "$lookahead" 2>"$dir/telemetry_check.txt") || check_status=$?
  local episodes
  episodes=$(grep -a -o "pose [a-z ]* from frame [0-9]*\|pose ok again at frame [0-9]* after [0-9]* frame(s)" "$log" | paste -sd ';' - | sed 's/;/; /g')
  figures+=("telemetry-loss: telemetry.csv without rows for 0.8 s (frames 10-17) and after frame 24: stale_pose $(field stale_pose "$log") (expected $(value expected_stale "$result"): frames $(value stale_frames "$result")), no_pose $(field no_pose "$log"), $(value image_only "$result") detections kept image-only, $(field lifted "$log") of $(field detections "$log") lifted; log: $episodes; exit $status")
  echo "faults: ${figures[-1]}"
  check telemetry-loss "$(ok_if "[[ $status -eq 0 ]]")" "exit status $status"
  check telemetry-loss "$(ok_if "[[ '$(field stale_pose "$log")' == '$(value expected_stale "$result")' && '$(field no_pose "$log")' == '$(value expected_no_pose "$result")' ]]")" "stale_pose $(field stale_pose "$log") / no_pose $(field no_pose "$log"), expected $(value expected_stale "$result") / $(value expected_no_pose "$result")"
  check telemetry-loss "$check_status" "detections file: $(tr '\n' ' ' <"$dir/telemetry_check.txt")"
  check telemetry-loss "$(ok_if "grep -a -q 'pose ok again at frame' '$log' && grep -a -q 'pose stale pose from frame' '$log'")" "no log line for the stale episode and the pose ok again"
}

for c in "${cases[@]}"; do
  echo "faults: --- $c"
  "case_${c//-/_}"
done
echo "faults: ${#figures[@]} case(s) run, ${#failed[@]} check(s) failed; outputs in $out"
for f in "${failed[@]}"; do
  echo "faults: FAILED $f"
done
[[ ${#failed[@]} -eq 0 ]]

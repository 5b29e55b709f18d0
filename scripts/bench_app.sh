#!/usr/bin/env bash
# End-to-end benchmark of vp_firmware_app at 2592 x 2048 on a simulated sequence:
#   scripts/bench_app.sh [SEQUENCE_DIR]     (BUILD=build/release by default; FRAMES=30)
# Runs, with DDS off (the loop alone) and the shipped int8 models:
#   1. every frame processed (--fast --every-frame), pinned to 1 core and to 2 cores (taskset,
#      --threads = cores): frames per second, per-stage and end-to-end latency (median, p99),
#      peak RSS (/usr/bin/time -v);
#   2. a source faster than the loop (--fast, drop-oldest), 2 cores: drops counted, latency
#      bounded.
# BACKENDS="int8 int8-dnnl" (default "auto", the app's default: int8-dnnl on VNNI CPUs with
# oneDNN, else int8; the app's log says which) repeats the runs per inference backend
# (--backend; int8-dnnl needs an x86 build with oneDNN, docs/inference.md), one after the
# other, so their fps sit side by side.
# PIPELINES="off on" (default "off") repeats every run per loop mode (--pipeline; app.pipeline,
# docs/firmware_app.md "Pipelined mode": --threads N then means N cores in total, the detector
# thread's pools get N - 1); RUNS=3 (default 1) repeats each run and prints the median of the
# figures over the runs (fps, per-stage and end-to-end median/p99) after the single runs.
# Without SEQUENCE_DIR, FRAMES frames are rendered with vp_simulate (seed 5) into /tmp.
# FRAME_FORMAT=ppm replays a copy of the sequence whose frames are uncompressed PPM (made once
# beside it, SEQUENCE_DIR.ppm, with /usr/bin/python3 and OpenCV): the replay's capture thread
# then reads the frames instead of decoding 2592 x 2048 JPEGs on the same cores, closer to a
# camera that delivers raw frames (the default, jpg, replays the frames as recorded).
set -euo pipefail
cd "$(dirname "$0")/.."
build="${BUILD:-build/release}"
frames="${FRAMES:-30}"
if [ ! -f "$build/build.ninja" ]; then
  cmake -S . -B "$build" -G Ninja -DCMAKE_BUILD_TYPE=Release >/dev/null
fi
cmake --build "$build" --target vp_firmware_app vp_simulate -j"${JOBS:-2}" >/dev/null
app="$build/firmware_app/vp_firmware_app"
out="$(mktemp -d /tmp/bench_app.XXXXXX)"

sequence="${1:-}"
if [ -z "$sequence" ]; then
  sequence="/tmp/bench_app_sequence_${frames}"
  if [ ! -f "$sequence/frames.csv" ]; then
    rm -rf "$sequence"
    "$build/tools/simulator/vp_simulate" --scene intersection --seed 5 --frames "$frames" \
      --out "$sequence" >/dev/null
  fi
fi
if [ "${FRAME_FORMAT:-jpg}" = ppm ]; then
  raw="${sequence%/}.ppm"
  if [ ! -f "$raw/frames.csv" ]; then
    rm -rf "$raw"
    cp -r "$sequence" "$raw"
    /usr/bin/python3 - "$raw" <<'PY'
import os, sys
import cv2
os.chdir(sys.argv[1])
lines = open("frames.csv").read().splitlines()
out = [lines[0]]
for line in lines[1:]:
    parts = line.split(",")
    image = cv2.imread(parts[-1], cv2.IMREAD_COLOR)
    if image is None:
        sys.exit(f"bench_app.sh: cannot decode {parts[-1]}")
    ppm = os.path.splitext(parts[-1])[0] + ".ppm"
    if not cv2.imwrite(ppm, image):
        sys.exit(f"bench_app.sh: cannot write {ppm}")
    os.remove(parts[-1])
    out.append(",".join(parts[:-1] + [ppm]))
open("frames.csv", "w").write("\n".join(out) + "\n")
PY
  fi
  sequence="$raw"
elif [ "${FRAME_FORMAT:-jpg}" != jpg ]; then
  echo "bench_app.sh: FRAME_FORMAT must be jpg or ppm, got '${FRAME_FORMAT}'" >&2
  exit 2
fi
echo "bench_app: $(nproc) cores, load average $(cut -d' ' -f1-3 /proc/loadavg); sequence $sequence; logs in $out"

# value KEY LOGFILE: the number after KEY= on the summary line
value() { grep -o "$1=[0-9.]*" "$2" | tail -1 | cut -d= -f2; }

# summary NAME: the medians over the runs NAME.1 .. NAME.RUNS (RUNS > 1)
summary() {
  local name=$1
  printf '%-40s %6s fps median of %s runs |' "$name" "$(medianOf fps "$name")" "${RUNS}"
  for stage in preprocess detector crops lift track e2e queue; do
    printf ' %s %s/%s' "$stage" "$(medianOf ${stage}_median_ms "$name")" \
      "$(medianOf ${stage}_p99_ms "$name")"
  done
  printf '\n'
}

# medianOf KEY NAME: the median over the runs NAME.1 .. NAME.RUNS of KEY's value
medianOf() {
  local key=$1 name=$2 r
  for r in $(seq 1 "${RUNS:-1}"); do value "$key" "$out/$name.$r.log"; done |
    sort -g | awk '{ v[NR] = $1 } END { print (NR % 2) ? v[(NR + 1) / 2] : (v[NR / 2] + v[NR / 2 + 1]) / 2 }'
}

run() {  # run NAME CPUS THREADS ARGS...
  local name=$1 cpus=$2 threads=$3
  shift 3
  taskset -c "$cpus" /usr/bin/time -v "$app" --config config/default.yaml --sequence "$sequence" \
    --no-dds --quiet --threads "$threads" "$@" 2>"$out/$name.log" >/dev/null
  local rss
  rss=$(awk -F: '/Maximum resident set size/ { gsub(/ /, "", $2); print $2 }' "$out/$name.log")
  printf '%-32s %6s fps  in %4s processed %4s dropped %4s |' "$name" \
    "$(value fps "$out/$name.log")" "$(value frames_in "$out/$name.log")" \
    "$(value processed "$out/$name.log")" "$(value dropped "$out/$name.log")"
  for stage in preprocess detector decode crops lift track e2e queue; do
    printf ' %s %s/%s' "$stage" "$(value ${stage}_median_ms "$out/$name.log")" \
      "$(value ${stage}_p99_ms "$out/$name.log")"
  done
  printf ' | peak RSS %s MiB\n' "$((rss / 1024))"
}

echo "ms median/p99 per stage; e2e = capture -> published; queue = capture -> processing start"
runs="${RUNS:-1}"
for backend in ${BACKENDS:-auto}; do
  # The modes in turn within each repetition (off on off on ...): a drifting load hits both.
  for r in $(seq 1 "$runs"); do
    for pipeline in ${PIPELINES:-off}; do
      # The pipeline needs a second core: on one core it only adds the hand-off.
      if [ "$pipeline" = off ]; then
        run "every_frame_1_core_$backend.$r" 0 1 --fast --every-frame --backend "$backend"
        # The serial loop on 2 cores with a 1-thread detector: the pipelined runs' detector
        # threads (--threads 2 pipelined = 1 detector thread + the processing thread).
        run "every_frame_2_cores_1_thread_${backend}_pipeline_off.$r" 0-1 1 --fast --every-frame \
          --backend "$backend" --pipeline off
      fi
      run "every_frame_2_cores_${backend}_pipeline_$pipeline.$r" 0-1 2 --fast --every-frame \
        --backend "$backend" --pipeline "$pipeline"
      run "fast_source_2_cores_${backend}_pipeline_$pipeline.$r" 0-1 2 --fast \
        --backend "$backend" --pipeline "$pipeline"
    done
  done
  if [ "$runs" -gt 1 ]; then
    for pipeline in ${PIPELINES:-off}; do
      if [ "$pipeline" = off ]; then
        summary "every_frame_1_core_$backend"
        summary "every_frame_2_cores_1_thread_${backend}_pipeline_off"
      fi
      summary "every_frame_2_cores_${backend}_pipeline_$pipeline"
      summary "fast_source_2_cores_${backend}_pipeline_$pipeline"
    done
  fi
done

#!/usr/bin/env bash
# Inference engine benchmark, side by side in one run:
#   vp engine XnnpackInt8 / XnnpackFp32 / OpenCvFp32   (tests/bench/engine_bench.cpp)
#   torch fp32, torch int8 (onednn), torch int8 (qnnpack) (tools/engine/bench_torch.py)
# on the same MobileNetV2-like 512x512 model, threads 1 and 2, plus the CPU's measured int8
# peak (tools/engine/peak_int8.cpp), printed as one Markdown table.
#
# Usage: scripts/bench_engine.sh
# Environment:
#   REPS=10        Google Benchmark repetitions (the median is reported)
#   MIN_TIME=0.5   seconds per repetition
#   RUNS=20        timed torch runs (median) after 3 warm-up runs
#   MODEL_DIR=/tmp/vp_bench_models   where the bench model is (re)generated
#   OUT=build/release/bench_engine.md  the table is also written here
#   SKIP_TORCH=1   leave out the PyTorch baselines
#   BUILD_DIR=dir  build there (plain Release configure) instead of the 'release' preset
# Timings are only meaningful on an otherwise idle machine (the load average is printed).
set -euo pipefail

root="$(cd "$(dirname "${BASH_SOURCE[0]}")/.." && pwd)"
cd "$root"
PY=/usr/bin/python3  # Debian's Python: torch, onnx, numpy, opencv
REPS="${REPS:-10}"
MIN_TIME="${MIN_TIME:-0.5}"
RUNS="${RUNS:-20}"
MODEL_DIR="${MODEL_DIR:-/tmp/vp_bench_models}"
BUILD="${BUILD_DIR:+$(realpath -m "$BUILD_DIR")}"
BUILD="${BUILD:-$root/build/release}"
OUT="${OUT:-$BUILD/bench_engine.md}"
MODEL="$MODEL_DIR/mobilenetv2_512.onnx"

echo "== 1/5 bench model -> $MODEL" >&2
"$PY" tools/engine/make_test_models.py --bench "$MODEL_DIR" 2> >(grep -v -i -E "warn|_C\._jit" >&2)

if [[ -z "${BUILD_DIR:-}" ]]; then
  echo "== 2/5 build vp_bench_engine (preset release)" >&2
  cmake --preset release >/dev/null
  cmake --build --preset release --target vp_bench_engine
else
  echo "== 2/5 build vp_bench_engine (Release, $BUILD)" >&2
  cmake -S "$root" -B "$BUILD" -G Ninja -DCMAKE_BUILD_TYPE=Release >/dev/null
  cmake --build "$BUILD" --target vp_bench_engine
fi

echo "== 3/5 int8 peak microbenchmark" >&2
g++ -O2 -mavx512f -mavx512bw -mavx512vnni -mavxvnni tools/engine/peak_int8.cpp \
  -o "$BUILD/peak_int8"
peak="$BUILD/peak_int8.txt"
: >"$peak.all"
for _ in 1 2 3; do "$BUILD/peak_int8" >>"$peak.all"; done
# best of three per line
awk '{ if (!($1 in best) || $3 > best[$1]) { best[$1] = $3; line[$1] = $0 } }
     END { for (k in line) print line[k] }' "$peak.all" >"$peak"
cat "$peak" >&2

echo "== 4/5 vp_bench_engine ($REPS repetitions, median)" >&2
"$BUILD/tests/bench/vp_bench_engine" --model="$MODEL" \
  --benchmark_repetitions="$REPS" --benchmark_report_aggregates_only=true \
  --benchmark_min_time="$MIN_TIME" \
  --benchmark_out="$BUILD/bench_engine.json" --benchmark_out_format=json >&2

torch_json="$BUILD/bench_torch.json"
rm -f "$torch_json"
if [[ "${SKIP_TORCH:-0}" != 1 ]]; then
  echo "== 5/5 PyTorch baselines ($RUNS runs, median)" >&2
  "$PY" tools/engine/bench_torch.py --runs "$RUNS" --json "$torch_json" \
    2> >(grep -v -i -E "warn|_C\._jit" >&2) >/dev/null
fi

echo >&2
"$PY" tools/engine/bench_report.py --engine-json "$BUILD/bench_engine.json" \
  --torch-json "$torch_json" --peak "$peak" --model "$MODEL" --out "$OUT"
echo "(written to $OUT)" >&2

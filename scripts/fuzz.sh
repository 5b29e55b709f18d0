#!/usr/bin/env bash
# Fuzzing campaign over every parser of the product (docs/fuzzing.md): builds the preset "fuzz"
# (clang, libFuzzer + ASan + UBSan) and runs each harness of tests/fuzz for SECONDS, one after
# the other, then prints the executions per target and every finding.
#   scripts/fuzz.sh                 # 60 s per target, all targets
#   scripts/fuzz.sh 180             # 3 minutes per target
#   scripts/fuzz.sh 600 dtm_file    # one target
# Findings and the growing corpus live outside the repository, in FUZZ_OUT (default
# /tmp/vp_fuzz): FUZZ_OUT/findings/<target>/ (crash-*, timeout-*, oom-*, leak-*: the input
# that broke it; reproduce with build/fuzz/tests/fuzz/fuzz_<target> FILE), FUZZ_OUT/corpus/<target>/
# (inputs that reached new code, kept between campaigns), FUZZ_OUT/logs/<target>.log.
# A fixed finding goes into tests/fuzz/corpus/<target>/ so that the CTest replay keeps it fixed.
# Exit status: 0 without findings, 1 with findings, 2 on a usage or build problem.
set -euo pipefail
cd "$(dirname "$0")/.."

SECONDS_PER_TARGET="${1:-60}"
shift || true
ALL_TARGETS=(config_yaml sequence_files dtm_file mavlink_stream onnx_model detections_file
             trajectory_file site_file)
TARGETS=("$@")
[ ${#TARGETS[@]} -eq 0 ] && TARGETS=("${ALL_TARGETS[@]}")
OUT="${FUZZ_OUT:-/tmp/vp_fuzz}"
JOBS="${JOBS:-2}"

if ! [[ "$SECONDS_PER_TARGET" =~ ^[0-9]+$ ]]; then
  echo "usage: scripts/fuzz.sh [SECONDS] [TARGET...]  (targets: ${ALL_TARGETS[*]})" >&2
  exit 2
fi
scripts/setup.sh --fuzz  # clang and libFuzzer besides the build dependencies (idempotent)

cmake --preset fuzz > /dev/null
cmake --build --preset fuzz -j "$JOBS"

# Seeds referenced in place rather than copied into tests/fuzz/corpus (too large to copy).
extra_seeds() {
  case "$1" in
    config_yaml) echo config/default.yaml ;;
    onnx_model) echo tests/fixtures/models/classifier.onnx ;;
  esac
}

export ASAN_OPTIONS="${ASAN_OPTIONS:-abort_on_error=1:detect_leaks=1}"
export UBSAN_OPTIONS="${UBSAN_OPTIONS:-print_stacktrace=1:halt_on_error=1}"
summary=()
new_findings=()
for target in "${TARGETS[@]}"; do
  binary="build/fuzz/tests/fuzz/fuzz_${target}"
  if [ ! -x "$binary" ]; then
    echo "fuzz: no target '$target' (targets: ${ALL_TARGETS[*]})" >&2
    exit 2
  fi
  corpus="$OUT/corpus/$target"
  seeds="$OUT/seeds/$target"
  findings="$OUT/findings/$target"
  log="$OUT/logs/$target.log"
  mkdir -p "$corpus" "$seeds" "$findings" "$(dirname "$log")"
  for seed in $(extra_seeds "$target"); do
    cp -f "$seed" "$seeds/"
  done
  before=$(find "$findings" -type f | sort)
  echo "fuzz: $target for ${SECONDS_PER_TARGET} s (log $log)"
  # -fork: a crash or timeout is recorded and the campaign goes on with the other inputs.
  "$binary" -max_total_time="$SECONDS_PER_TARGET" -timeout=10 -rss_limit_mb=2048 \
    -use_value_profile=1 -fork=1 -ignore_crashes=1 \
    -ignore_timeouts=1 -ignore_ooms=1 -artifact_prefix="$findings/" \
    "$corpus" "tests/fuzz/corpus/$target" "$seeds" > "$log" 2>&1 || true
  # Fork mode's status lines start with the executions so far: "#7382: cov: ...".
  execs=$( (grep -Eo '^#[0-9]+' "$log" || true) | tail -1 | tr -d '#')
  added=$(comm -13 <(echo "$before") <(find "$findings" -type f | sort) | sed '/^$/d')
  new=0
  if [ -n "$added" ]; then
    new=$(echo "$added" | wc -l)
    while IFS= read -r file; do new_findings+=("$file"); done <<< "$added"
  fi
  units=$(find "$corpus" -type f | wc -l)
  summary+=("$(printf '%-16s %12s executions %6s corpus files %3s new findings' \
                "$target" "${execs:-?}" "$units" "$new")")
done

echo
echo "fuzz: campaign of ${SECONDS_PER_TARGET} s per target (output in $OUT)"
printf '  %s\n' "${summary[@]}"
if [ ${#new_findings[@]} -gt 0 ]; then
  echo "fuzz: ${#new_findings[@]} new finding(s) (the log of the target shows the report):"
  printf '  %s\n' "${new_findings[@]}"
  exit 1
fi
echo "fuzz: no finding"
